/* broken_halfedges — a half-edge mesh of our own, C, nothing of emm in it:
 * a grid of 40 x 40 cells, two triangles each (--quads: one quad each),
 * kept as OpenMesh keeps its
 * connectivity (a half-edge record {face, to, next, prev} of 16 bytes, a
 * face's one half-edge, the positions as 3 floats). It walks every face's
 * cycle 20 times, summing its corners' coordinates, and prints the sum.
 *
 *   broken_halfedges [--break] [--quads]
 *
 * --break corrupts face 7's cycle (its third half-edge's next skips back
 * to its second): the walk, three steps a face, still ends, but the mesh is
 * no mesh, and emm must refuse it in one line naming the rule and the
 * half-edge (tests/openmesh/CMakeLists.txt). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define W 40

struct halfedge {
    int face, to, next, prev;
};

static struct halfedge *he;
static int *faces;
static float *points;

static int sides = 3;

static __attribute__((noinline)) int build_mesh(int corrupt)
{
    int nv = (W + 1) * (W + 1), nf = sides == 3 ? 2 * W * W : W * W;
    points = malloc((size_t)nv * 3 * sizeof *points);
    he = malloc((size_t)nf * (size_t)sides * sizeof *he);
    faces = malloc((size_t)nf * sizeof *faces);
    if (!points || !he || !faces)
        return -1;
    for (int i = 0; i < nv; i++) {
        points[3 * i] = (float)(i % (W + 1));
        points[3 * i + 1] = (float)(i / (W + 1));
        points[3 * i + 2] = (float)((i * 7) % 5) * 0.25f;
    }
    int f = 0;
    for (int y = 0; y < W; y++)
        for (int x = 0; x < W; x++) {
            int a = y * (W + 1) + x, b = a + 1, c = a + W + 1, d = c + 1;
            int poly[2][4] = {{a, b, d, c}, {a, d, c, c}};
            if (sides == 3) {
                poly[0][2] = d;
                poly[0][1] = b;
            }
            int tri[2][3] = {{a, b, d}, {a, d, c}};
            for (int t = 0; t < (sides == 3 ? 2 : 1); t++, f++) {
                for (int k = 0; k < sides; k++) {
                    struct halfedge *h = &he[sides * f + k];
                    h->face = f;
                    h->to = sides == 3 ? tri[t][(k + 1) % 3] : poly[0][(k + 1) % 4];
                    h->next = sides * f + (k + 1) % sides;
                    h->prev = sides * f + (k + sides - 1) % sides;
                }
                faces[f] = sides * f;
            }
        }
    if (corrupt)
        he[3 * 7 + 2].next = 3 * 7 + 1;
    return nf;
}

int main(int argc, char **argv)
{
    int corrupt = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--break") == 0)
            corrupt = 1;
        else if (strcmp(argv[i], "--quads") == 0)
            sides = 4;
    }
    int nf = build_mesh(corrupt);
    if (nf < 0) {
        fprintf(stderr, "broken_halfedges: out of memory\n");
        return 1;
    }
    double sum = 0;
    for (int round = 0; round < 20; round++)
        for (int f = 0; f < nf; f++) {
            int h = faces[f];
            for (int k = 0; k < sides; k++) {
                const float *p = &points[3 * he[h].to];
                sum += p[0] + 2 * p[1] + 3 * p[2];
                h = he[h].next;
            }
        }
    printf("faces: %d\nsum: %.3f\n", nf, sum);
    free(points);
    free(he);
    free(faces);
    return 0;
}
