/* A program nobody tagged: it reads an OFF mesh file into arrays of its own
 * (doubles for the vertices, ints for the triangles), then smooths each
 * vertex towards the centroids of its triangles a few times (a Laplacian
 * pass over the triangles), and prints a checksum. Under fault capture
 * with EMM_TAG rules, the loader's writes come first: the window must open
 * at the traversal's first read (thesis §5, "freeze the data").
 * usage: test_shim_loader MESH.off */
#include <stdio.h>
#include <stdlib.h>

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

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: test_shim_loader MESH.off\n");
        return 2;
    }
    double *xyz;
    int *tri;
    long nv, nt;
    if (read_mesh(argv[1], &xyz, &tri, &nv, &nt) != 0) {
        fprintf(stderr, "test_shim_loader: %s: not a triangle OFF file\n", argv[1]);
        return 1;
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
