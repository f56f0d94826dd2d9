/* A mesh program as a newcomer writes one, with nothing of emm in it (issue
 * 25): it reads an OBJ file into two arrays that grow with realloc (float
 * x y z per vertex, uint32_t corners per triangle), finds each triangle's
 * neighbours across its edges, floods the mesh breadth-first from its first
 * triangle, then locates points by walking from triangle to triangle
 * towards each (a visibility walk), and prints what it found.
 *
 * Tagged by EMM_TAG rules (README "Tagging a program you did not write"):
 *   vertices:site=read_obj,stride=12,xyz=0:f32;triangles:site=read_obj,stride=12,vidx=0:u32
 * and captured by --capture valgrind (this build) or --capture sancov (its
 * build flood_walk.sancov): tests/shim/compute.sh checks that both, and the
 * sancov build under valgrind, give the same answer and cycles
 * (docs/machine.md "Compute"). Its functions are not static, as in a
 * program of several files: gcc inlines a static function called once, and
 * the rules' site= names read_obj's frame.
 *
 * The walk works in the plane z = 0 of `emm mesh gen`'s meshes.
 *
 * usage: flood_walk MESH.obj [POINTS]   (default 2000 points) */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

float *verts;        /* x y z of vertex i at verts[3*i] */
uint32_t *tris;      /* corners of triangle t at tris[3*t] */
size_t nverts, ntris;

int read_obj(const char *path);
int *neighbours(void);
void corners(uint32_t t, double x[3], double y[3]);
double orient(double ax, double ay, double bx, double by, double px, double py);

/* Reads the "v" and "f" lines of an OBJ file (triangles only; "f 1/2/3"
 * keeps the vertex index). Returns 0 when it read a mesh. */
int read_obj(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    size_t vcap = 0, tcap = 0;
    char line[1024];
    while (fgets(line, sizeof line, f)) {
        if (line[0] == 'v' && line[1] == ' ') {
            if (nverts == vcap) {
                vcap = vcap ? vcap * 2 : 1024;
                verts = realloc(verts, vcap * 3 * sizeof(float));
                if (!verts)
                    break;
            }
            char *s = line + 2;
            for (int k = 0; k < 3; k++)
                verts[3 * nverts + k] = strtof(s, &s);
            nverts++;
        } else if (line[0] == 'f' && line[1] == ' ') {
            if (ntris == tcap) {
                tcap = tcap ? tcap * 2 : 1024;
                tris = realloc(tris, tcap * 3 * sizeof(uint32_t));
                if (!tris)
                    break;
            }
            char *s = line + 2;
            for (int k = 0; k < 3; k++) {
                long i = strtol(s, &s, 10);
                if (i < 1 || (size_t)i > nverts) {
                    fclose(f);
                    return -1;
                }
                tris[3 * ntris + k] = (uint32_t)(i - 1);
                while (*s && *s != ' ' && *s != '\t')
                    s++;
            }
            ntris++;
        }
    }
    fclose(f);
    return verts && tris && nverts > 0 && ntris > 0 ? 0 : -1;
}

/* nb[3*t+k]: the triangle across the edge from corner k to corner k+1 of
 * triangle t, or -1 on the boundary. Each vertex keeps the list of its
 * triangles, and an edge's other triangle is the one of its first corner's
 * list that also has its second corner. */
int *neighbours(void)
{
    size_t *first = calloc(nverts + 1, sizeof *first);
    uint32_t *list = malloc(3 * ntris * sizeof *list);
    size_t *fill = malloc(nverts * sizeof *fill);
    int *nb = malloc(3 * ntris * sizeof *nb);
    if (!first || !list || !fill || !nb)
        return NULL;
    for (size_t t = 0; t < ntris; t++)
        for (int k = 0; k < 3; k++)
            first[tris[3 * t + k] + 1]++;
    for (size_t v = 0; v < nverts; v++)
        first[v + 1] += first[v];
    memcpy(fill, first, nverts * sizeof *fill);
    for (size_t t = 0; t < ntris; t++)
        for (int k = 0; k < 3; k++)
            list[fill[tris[3 * t + k]]++] = (uint32_t)t;
    for (size_t t = 0; t < ntris; t++) {
        uint32_t c[3] = {tris[3 * t], tris[3 * t + 1], tris[3 * t + 2]};
        for (int k = 0; k < 3; k++) {
            uint32_t a = c[k], b = c[(k + 1) % 3];
            int across = -1;
            for (size_t j = first[a]; j < first[a + 1] && across < 0; j++) {
                uint32_t u = list[j];
                if (u == t)
                    continue;
                uint32_t d0 = tris[3 * u], d1 = tris[3 * u + 1], d2 = tris[3 * u + 2];
                if (d0 == b || d1 == b || d2 == b)
                    across = (int)u;
            }
            nb[3 * t + k] = across;
        }
    }
    free(first);
    free(list);
    free(fill);
    return nb;
}

/* The x and y of triangle t's three corners: each index and each coordinate
 * is read once, into locals, before any of them is used, so that builds by
 * different compilers (gcc's plain one, clang's for sancov) make the same
 * loads of the mesh, as the captures compare (tests/shim/compute.sh). */
void corners(uint32_t t, double x[3], double y[3])
{
    uint32_t c[3] = {tris[3 * t], tris[3 * t + 1], tris[3 * t + 2]};
    for (int k = 0; k < 3; k++) {
        x[k] = verts[3 * c[k]];
        y[k] = verts[3 * c[k] + 1];
    }
}

/* Twice the signed area of (a, b, p): positive when p is left of a->b. */
double orient(double ax, double ay, double bx, double by, double px, double py)
{
    return (bx - ax) * (py - ay) - (by - ay) * (px - ax);
}

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 3) {
        fprintf(stderr, "usage: flood_walk MESH.obj [POINTS]\n");
        return 2;
    }
    long npoints = argc == 3 ? atol(argv[2]) : 2000;
    if (read_obj(argv[1]) != 0) {
        fprintf(stderr, "flood_walk: cannot read a triangle mesh from %s\n", argv[1]);
        return 1;
    }
    int *nb = neighbours();
    if (!nb)
        return 1;

    /* Breadth-first flood from triangle 0: each triangle's depth, and the
     * area the fill covers. */
    int *depth = malloc(ntris * sizeof *depth);
    uint32_t *queue = malloc(ntris * sizeof *queue);
    if (!depth || !queue)
        return 1;
    for (size_t t = 0; t < ntris; t++)
        depth[t] = -1;
    size_t head = 0, tail = 0;
    queue[tail++] = 0;
    depth[0] = 0;
    double area = 0;
    int deepest = 0;
    while (head < tail) {
        uint32_t t = queue[head++];
        double cx[3], cy[3];
        corners(t, cx, cy);
        area += 0.5 * orient(cx[0], cy[0], cx[1], cy[1], cx[2], cy[2]);
        if (depth[t] > deepest)
            deepest = depth[t];
        for (int k = 0; k < 3; k++) {
            int u = nb[3 * t + k];
            if (u >= 0 && depth[u] < 0) {
                depth[u] = depth[t] + 1;
                queue[tail++] = (uint32_t)u;
            }
        }
    }

    /* The bounding box, for the points. */
    float lo[2] = {verts[0], verts[1]}, hi[2] = {verts[0], verts[1]};
    for (size_t v = 1; v < nverts; v++) {
        for (int d = 0; d < 2; d++) {
            if (verts[3 * v + d] < lo[d])
                lo[d] = verts[3 * v + d];
            if (verts[3 * v + d] > hi[d])
                hi[d] = verts[3 * v + d];
        }
    }

    /* The visibility walk: from the triangle the last point was found in,
     * cross any edge the point lies beyond, until no edge is (the point is
     * inside) or the edge is the boundary (the point is outside). */
    unsigned long seed = 12345;
    uint32_t t = 0;
    long inside = 0, steps = 0;
    unsigned long found = 0;
    for (long i = 0; i < npoints; i++) {
        seed = seed * 6364136223846793005ul + 1442695040888963407ul;
        double x = lo[0] + (hi[0] - lo[0]) * (double)(seed >> 11) / 9007199254740992.0;
        seed = seed * 6364136223846793005ul + 1442695040888963407ul;
        double y = lo[1] + (hi[1] - lo[1]) * (double)(seed >> 11) / 9007199254740992.0;
        for (;;) {
            double cx[3], cy[3];
            corners(t, cx, cy);
            int k;
            for (k = 0; k < 3; k++)
                if (orient(cx[k], cy[k], cx[(k + 1) % 3], cy[(k + 1) % 3], x, y) < 0)
                    break;
            if (k == 3) {
                inside++;
                found += t;
                break;
            }
            if (nb[3 * t + k] < 0)
                break;
            t = (uint32_t)nb[3 * t + k];
            steps++;
        }
    }

    printf("vertices %zu triangles %zu\n", nverts, ntris);
    printf("flood: %zu triangles reached, depth %d, area %.6f\n", tail, deepest, area);
    printf("walk: %ld points, %ld inside, %ld steps, triangle sum %lu\n", npoints, inside, steps,
           found);
    free(nb);
    free(depth);
    free(queue);
    free(verts);
    free(tris);
    return 0;
}
