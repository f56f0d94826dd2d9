/* A mesh program that keeps its vertices as a structure of arrays: all the
 * x's in one block, the y's in another, the z's in a third (as particle and
 * solver codes do), and its triangles as records of three corners. It knows
 * nothing of emm: it reads an OFF file of triangles, smooths the mesh with
 * a few Laplacian passes over the triangles, and prints a checksum.
 *
 * Tagged by EMM_TAG rules (README "Tagging a program you did not write"),
 * one per block, in the order mesh_alloc allocates them:
 *   vertices:site=mesh_alloc,x=0:f32;vertices:site=mesh_alloc,y=0:f32;
 *   vertices:site=mesh_alloc,z=0:f32;triangles:site=mesh_alloc,stride=12,vidx=0:u32
 * (site=mesh_alloc names the arrays' allocations; site=main would do too:
 * the C library's 4 KiB buffer for the file, allocated under the inlined
 * loader and a whole number of 4-byte entries, is never selected.)
 *
 * usage: smooth_soa MESH.off [PASSES]   (default 10 passes) */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct mesh {
    float *x, *y, *z; /* vertex v is (x[v], y[v], z[v]) */
    uint32_t *tri;    /* 3 per triangle */
    size_t nv, nt;
};

/* The function the rules name: the blocks, at their final size. */
static __attribute__((noinline)) int mesh_alloc(struct mesh *m, size_t nv, size_t nt)
{
    m->nv = nv;
    m->nt = nt;
    m->x = malloc(nv * sizeof *m->x);
    m->y = malloc(nv * sizeof *m->y);
    m->z = malloc(nv * sizeof *m->z);
    m->tri = malloc(3 * nt * sizeof *m->tri);
    return m->x && m->y && m->z && m->tri ? 0 : -1;
}

/* The loader: the OFF header gives the counts. */
static int load_mesh(const char *path, struct mesh *m)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    long nv, nf, ne;
    int rc = -1;
    if (fscanf(f, " OFF %ld %ld %ld", &nv, &nf, &ne) != 3 || nv <= 0 || nf <= 0 ||
        mesh_alloc(m, (size_t)nv, (size_t)nf) != 0)
        goto done;
    for (size_t v = 0; v < m->nv; v++)
        if (fscanf(f, "%f %f %f", &m->x[v], &m->y[v], &m->z[v]) != 3)
            goto done;
    for (size_t t = 0; t < m->nt; t++) {
        long k, c[3];
        if (fscanf(f, "%ld %ld %ld %ld", &k, &c[0], &c[1], &c[2]) != 4 || k != 3)
            goto done; /* triangles only */
        for (int j = 0; j < 3; j++) {
            if (c[j] < 0 || (size_t)c[j] >= m->nv)
                goto done;
            m->tri[3 * t + (size_t)j] = (uint32_t)c[j];
        }
    }
    rc = 0;
done:
    fclose(f);
    return rc;
}

/* One Laplacian pass: each vertex moves halfway to the mean of its
 * neighbours along the triangles' edges (an edge of two triangles counts
 * twice). */
static void smooth_pass(struct mesh *m, float *sum, unsigned *count)
{
    size_t nv = m->nv;
    float *axis[3] = {m->x, m->y, m->z};
    memset(sum, 0, 3 * nv * sizeof *sum);
    memset(count, 0, nv * sizeof *count);
    for (size_t t = 0; t < m->nt; t++) {
        const uint32_t *v = &m->tri[3 * t];
        for (int k = 0; k < 3; k++) {
            uint32_t a = v[(k + 1) % 3], b = v[(k + 2) % 3];
            for (int d = 0; d < 3; d++)
                sum[d * nv + v[k]] += axis[d][a] + axis[d][b];
            count[v[k]] += 2;
        }
    }
    for (size_t i = 0; i < nv; i++)
        if (count[i])
            for (int d = 0; d < 3; d++)
                axis[d][i] = 0.5f * axis[d][i] + 0.5f * sum[d * nv + i] / (float)count[i];
}

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 3) {
        fprintf(stderr, "usage: smooth_soa MESH.off [PASSES]\n");
        return 2;
    }
    long passes = argc == 3 ? strtol(argv[2], NULL, 10) : 10;
    struct mesh m = {0};
    if (load_mesh(argv[1], &m) != 0) {
        fprintf(stderr, "smooth_soa: cannot read a triangle mesh from %s\n", argv[1]);
        return 1;
    }
    float *sum = malloc(3 * m.nv * sizeof *sum);
    unsigned *count = malloc(m.nv * sizeof *count);
    if (!sum || !count)
        return 1;
    for (long i = 0; i < passes; i++)
        smooth_pass(&m, sum, count);
    double check = 0;
    for (size_t v = 0; v < m.nv; v++)
        check += fabs(m.x[v]) + 2 * fabs(m.y[v]) + 3 * fabs(m.z[v]);
    printf("vertices %zu triangles %zu passes %ld checksum %.6f\n", m.nv, m.nt, passes, check);
    free(sum);
    free(count);
    free(m.x);
    free(m.y);
    free(m.z);
    free(m.tri);
    return 0;
}
