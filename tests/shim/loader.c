/* A program nobody tagged: it reads an OFF mesh file into arrays of its own
 * (doubles for the vertices, ints for the triangles), then smooths each
 * vertex towards the centroids of its triangles a few times (a Laplacian
 * pass over the triangles), and prints a checksum. Under fault capture
 * with EMM_TAG rules, the loader's writes come first: the window must open
 * at the traversal's first read (thesis §5, "freeze the data").
 * With --phases it makes two different passes instead: a scan line (the
 * triangles by rows of their centroids) and then a breadth-first region
 * growth from triangle 0 — two phases of one run.
 * usage: test_shim_loader MESH.off [--phases] */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Reads the OFF file into arrays of its own: the positions first, then the
 * triangles (EMM_TAG rules select them by this function's name). */
static __attribute__((noinline)) int read_mesh(const char *path, double **xyz_out,
                                               int **tri_out, long *nv_out, long *nt_out)
{
    FILE *f = fopen(path, "r");
    long nv, nt, ne;
    if (!f || fscanf(f, "OFF %ld %ld %ld", &nv, &nt, &ne) != 3 || nv <= 0 || nt <= 0)
        return -1;
    double *xyz = malloc((size_t)nv * 3 * sizeof *xyz);
    int *tri = malloc((size_t)nt * 3 * sizeof *tri);
    if (!xyz || !tri)
        return -1;
    for (long i = 0; i < 3 * nv; i++)
        if (fscanf(f, "%lf", &xyz[i]) != 1)
            return -1;
    for (long t = 0; t < nt; t++) {
        int k;
        if (fscanf(f, "%d %d %d %d", &k, &tri[3 * t], &tri[3 * t + 1], &tri[3 * t + 2]) != 4 ||
            k != 3)
            return -1;
    }
    fclose(f);
    *xyz_out = xyz;
    *tri_out = tri;
    *nv_out = nv;
    *nt_out = nt;
    return 0;
}

static const double *cent; /* for the scan line's order */
static double rows;         /* rows of the scan line, about an edge high */

static int by_row(const void *a, const void *b)
{
    const double *p = &cent[2 * *(const long *)a], *q = &cent[2 * *(const long *)b];
    long rp = (long)(p[1] * rows), rq = (long)(q[1] * rows);
    if (rp != rq)
        return rp < rq ? -1 : 1;
    return p[0] < q[0] ? -1 : p[0] > q[0];
}

static int cmp_long(const void *a, const void *b)
{
    long x = *(const long *)a, y = *(const long *)b;
    return x < y ? -1 : x > y;
}

/* One visit: the triangle's vertex indices and its vertices' positions. */
static double visit(const double *xyz, const int *tri, long t)
{
    const int *v = &tri[3 * t];
    return xyz[3 * v[0]] + xyz[3 * v[1] + 1] + xyz[3 * v[2]];
}

/* A scan line, then a region grown breadth-first from triangle 0 over the
 * shared edges (its adjacency in memory of its own, not the mesh's). */
static int two_phases(const double *xyz, const int *tri, long nv, long nt)
{
    /* The preparation (centroids, adjacency) works on copies: memcpy is not
     * instrumented, so the two traversals are all the run shows. */
    double *pxyz = malloc((size_t)nv * 3 * sizeof *pxyz);
    int *ptri = malloc((size_t)nt * 3 * sizeof *ptri);
    if (!pxyz || !ptri)
        return 1;
    memcpy(pxyz, xyz, (size_t)nv * 3 * sizeof *pxyz);
    memcpy(ptri, tri, (size_t)nt * 3 * sizeof *ptri);
    double *c = malloc((size_t)nt * 2 * sizeof *c);
    long *order = malloc((size_t)nt * sizeof *order), *queue = malloc((size_t)nt * sizeof *queue);
    long *adj = malloc((size_t)nt * 3 * sizeof *adj), *edge = malloc((size_t)nt * 3 * sizeof *edge);
    char *seen = calloc((size_t)nt, 1);
    if (!c || !order || !queue || !adj || !edge || !seen)
        return 1;
    for (long t = 0; t < nt; t++) {
        order[t] = t;
        c[2 * t] = c[2 * t + 1] = 0;
        for (int k = 0; k < 3; k++) {
            c[2 * t] += pxyz[3 * ptri[3 * t + k]] / 3;
            c[2 * t + 1] += pxyz[3 * ptri[3 * t + k] + 1] / 3;
        }
    }
    cent = c;
    rows = sqrt((double)nt) / 2;
    qsort(order, (size_t)nt, sizeof *order, by_row);
    double scan = 0;
    for (long i = 0; i < nt; i++)
        scan += visit(xyz, tri, order[i]);
    /* Adjacency by sorting the edges (smaller vertex * nv + larger). */
    for (long e = 0; e < 3 * nt; e++) {
        long a = ptri[e], b = ptri[e - e % 3 + (e % 3 + 1) % 3];
        edge[e] = (a < b ? a * nv + b : b * nv + a) * 3 * nt + e;
        adj[e] = -1;
    }
    long *keys = edge;
    qsort(keys, (size_t)(3 * nt), sizeof *keys, cmp_long);
    for (long i = 0; i + 1 < 3 * nt; i++)
        if (keys[i] / (3 * nt) == keys[i + 1] / (3 * nt)) {
            long e = keys[i] % (3 * nt), f = keys[i + 1] % (3 * nt);
            adj[e] = f / 3;
            adj[f] = e / 3;
        }
    double grown = 0;
    long head = 0, tail = 0, reached = 0;
    queue[tail++] = 0;
    seen[0] = 1;
    while (head < tail) {
        long t = queue[head++];
        grown += visit(xyz, tri, t);
        reached++;
        for (int k = 0; k < 3; k++) {
            long u = adj[3 * t + k];
            if (u >= 0 && !seen[u]) {
                seen[u] = 1;
                queue[tail++] = u;
            }
        }
    }
    printf("scan line %.9f region %ld triangles %.9f\n", scan, reached, grown);
    free(pxyz);
    free(ptri);
    free(c);
    free(order);
    free(queue);
    free(adj);
    free(edge);
    free(seen);
    return 0;
}

int main(int argc, char **argv)
{
    int phases = argc == 3 && strcmp(argv[2], "--phases") == 0;
    if (argc != 2 && !phases) {
        fprintf(stderr, "usage: test_shim_loader MESH.off [--phases]\n");
        return 2;
    }
    double *xyz;
    int *tri;
    long nv, nt;
    if (read_mesh(argv[1], &xyz, &tri, &nv, &nt) != 0) {
        fprintf(stderr, "test_shim_loader: %s: not a triangle OFF file\n", argv[1]);
        return 1;
    }
    if (phases) {
        int rc = two_phases(xyz, tri, nv, nt);
        free(xyz);
        free(tri);
        return rc;
    }
    double *acc = calloc((size_t)nv * 4, sizeof *acc);
    if (!acc)
        return 1;
    for (int pass = 0; pass < 3; pass++) {
        for (long i = 0; i < 4 * nv; i++)
            acc[i] = 0;
        for (long t = 0; t < nt; t++) {
            const int *v = &tri[3 * t];
            double cx = 0, cy = 0;
            for (int c = 0; c < 3; c++) {
                cx += xyz[3 * v[c]];
                cy += xyz[3 * v[c] + 1];
            }
            for (int c = 0; c < 3; c++) {
                acc[4 * v[c]] += cx / 3;
                acc[4 * v[c] + 1] += cy / 3;
                acc[4 * v[c] + 3] += 1;
            }
        }
        for (long i = 0; i < nv; i++)
            if (acc[4 * i + 3] > 0) {
                xyz[3 * i] = 0.5 * xyz[3 * i] + 0.5 * acc[4 * i] / acc[4 * i + 3];
                xyz[3 * i + 1] = 0.5 * xyz[3 * i + 1] + 0.5 * acc[4 * i + 1] / acc[4 * i + 3];
            }
    }
    double sum = 0;
    for (long i = 0; i < nv; i++)
        sum += xyz[3 * i] * (double)(i % 7 + 1) + xyz[3 * i + 1];
    printf("vertices %ld triangles %ld checksum %.9f\n", nv, nt, sum);
    free(xyz);
    free(acc);
    free(tri);
    return 0;
}
