/* A mesh program that stores its mesh column-major, as libigl does with
 * Eigen's V (#V x 3 doubles) and F (#F x 3 ints): one block holding all the
 * x's, then all the y's, then all the z's, and one holding every triangle's
 * first corner, then the second ones, then the third ones. It knows nothing
 * of emm: it reads an OFF file of triangles, smooths the mesh with a few
 * Laplacian passes over the triangles, and prints a checksum.
 *
 * Tagged by EMM_TAG rules (README "Tagging a program you did not write"):
 *   vertices:site=load_mesh,order=columns,xyz=0:f64;triangles:site=load_mesh,order=columns,vidx=0:i32
 *
 * usage: smooth_columns MESH.off [PASSES]   (default 10 passes) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct mesh {
    double *V; /* column-major: V[v], V[nv + v], V[2 nv + v] are vertex v's x, y, z */
    int *F;    /* column-major: F[t], F[nt + t], F[2 nt + t] are triangle t's corners */
    size_t nv, nt;
};

/* The loader the rules name: both blocks are allocated here, at their
 * final size (the OFF header gives the counts), as Eigen's resize does. */
static __attribute__((noinline)) int load_mesh(const char *path, struct mesh *m)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    long nv, nf, ne;
    int rc = -1;
    if (fscanf(f, " OFF %ld %ld %ld", &nv, &nf, &ne) != 3 || nv <= 0 || nf <= 0)
        goto done;
    m->nv = (size_t)nv;
    m->nt = (size_t)nf;
    m->V = malloc(3 * m->nv * sizeof *m->V);
    m->F = malloc(3 * m->nt * sizeof *m->F);
    if (!m->V || !m->F)
        goto done;
    for (size_t v = 0; v < m->nv; v++)
        if (fscanf(f, "%lf %lf %lf", &m->V[v], &m->V[m->nv + v], &m->V[2 * m->nv + v]) != 3)
            goto done;
    for (size_t t = 0; t < m->nt; t++) {
        int k, c[3];
        if (fscanf(f, "%d %d %d %d", &k, &c[0], &c[1], &c[2]) != 4 || k != 3)
            goto done; /* triangles only */
        for (int j = 0; j < 3; j++) {
            if (c[j] < 0 || (size_t)c[j] >= m->nv)
                goto done;
            m->F[j * m->nt + t] = c[j];
        }
    }
    rc = 0;
done:
    fclose(f);
    return rc;
}

/* One Laplacian pass: each vertex moves halfway to the mean of its
 * neighbours along the triangles' edges (an edge of two triangles counts
 * twice). A triangle's corners and positions are read once into locals. */
static void smooth_pass(struct mesh *m, double *sum, unsigned *count)
{
    size_t nv = m->nv, nt = m->nt;
    memset(sum, 0, 3 * nv * sizeof *sum);
    memset(count, 0, nv * sizeof *count);
    for (size_t t = 0; t < nt; t++) {
        size_t v[3] = {(size_t)m->F[t], (size_t)m->F[nt + t], (size_t)m->F[2 * nt + t]};
        double p[3][3];
        for (int k = 0; k < 3; k++)
            for (int d = 0; d < 3; d++)
                p[k][d] = m->V[d * nv + v[k]];
        for (int k = 0; k < 3; k++) {
            int n1 = (k + 1) % 3, n2 = (k + 2) % 3;
            for (int d = 0; d < 3; d++)
                sum[d * nv + v[k]] += p[n1][d] + p[n2][d];
            count[v[k]] += 2;
        }
    }
    for (size_t v = 0; v < nv; v++) {
        if (count[v] == 0)
            continue;
        for (int d = 0; d < 3; d++) {
            double x = m->V[d * nv + v];
            m->V[d * nv + v] = 0.5 * x + 0.5 * sum[d * nv + v] / (double)count[v];
        }
    }
}

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 3) {
        fprintf(stderr, "usage: smooth_columns MESH.off [PASSES]\n");
        return 2;
    }
    long passes = argc == 3 ? strtol(argv[2], NULL, 10) : 10;
    struct mesh m = {0};
    if (load_mesh(argv[1], &m) != 0) {
        fprintf(stderr, "smooth_columns: cannot read a triangle mesh from %s\n", argv[1]);
        return 1;
    }
    double *sum = malloc(3 * m.nv * sizeof *sum);
    unsigned *count = malloc(m.nv * sizeof *count);
    if (!sum || !count)
        return 1;
    for (long i = 0; i < passes; i++)
        smooth_pass(&m, sum, count);
    double check = 0;
    for (size_t v = 0; v < m.nv; v++)
        check += fabs(m.V[v]) + 2 * fabs(m.V[m.nv + v]) + 3 * fabs(m.V[2 * m.nv + v]);
    printf("vertices %zu triangles %zu passes %ld checksum %.6f\n", m.nv, m.nt, passes, check);
    free(sum);
    free(count);
    free(m.V);
    free(m.F);
    return 0;
}
