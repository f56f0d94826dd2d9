/* A mesh program as people write them, with nothing of emm in it: it reads
 * an OBJ or OFF file into arrays of its own that grow with realloc (float
 * positions, uint32_t triangle corners), smooths the mesh with a few
 * Laplacian passes over the triangles, and prints a checksum.
 *
 * It is what `emm run` is for (README "Capture backends"): tagged by
 * EMM_TAG rules, e.g.
 *   vertices:site=load_mesh,stride=12,xyz=0:f32;triangles:site=load_mesh,stride=12,vidx=0:u32
 * and captured whole under --capture valgrind (or built with
 * emm_sancov_executable, as smooth.sancov). Both builds are compiled
 * without vectorisation (sancov needs it off), so they make the same loads
 * and their element-access counts compare.
 *
 * usage: smooth MESH.obj|MESH.off [PASSES]   (default 10 passes) */
#include <ctype.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct mesh {
    float *xyz;    /* 3 per vertex */
    uint32_t *tri; /* 3 per triangle */
    size_t nv, nt, vcap, tcap;
};

/* Room for one more record of `width` scalars: capacity doubles. */
static int grow(void **p, size_t *cap, size_t n, size_t record)
{
    if (n < *cap)
        return 0;
    size_t ncap = *cap ? 2 * *cap : 256;
    void *q = realloc(*p, ncap * record);
    if (!q)
        return -1;
    *p = q;
    *cap = ncap;
    return 0;
}

static int add_vertex(struct mesh *m, float x, float y, float z)
{
    if (grow((void **)&m->xyz, &m->vcap, m->nv, 3 * sizeof *m->xyz) != 0)
        return -1;
    float *p = &m->xyz[3 * m->nv++];
    p[0] = x;
    p[1] = y;
    p[2] = z;
    return 0;
}

static int add_triangle(struct mesh *m, long a, long b, long c)
{
    if (a < 0 || b < 0 || c < 0 || (size_t)a >= m->nv || (size_t)b >= m->nv ||
        (size_t)c >= m->nv)
        return -1;
    if (grow((void **)&m->tri, &m->tcap, m->nt, 3 * sizeof *m->tri) != 0)
        return -1;
    uint32_t *t = &m->tri[3 * m->nt++];
    t[0] = (uint32_t)a;
    t[1] = (uint32_t)b;
    t[2] = (uint32_t)c;
    return 0;
}

/* One OBJ face corner ("7", "7/2", "7//3", "-1"): a 0-based vertex index. */
static int corner(const char **s, size_t nv, long *out)
{
    char *end;
    long i = strtol(*s, &end, 10);
    if (end == *s || i == 0)
        return -1;
    while (*end && !isspace((unsigned char)*end))
        end++;
    *s = end;
    *out = i > 0 ? i - 1 : (long)nv + i;
    return 0;
}

static int load_obj(FILE *f, struct mesh *m)
{
    char line[4096];
    while (fgets(line, sizeof line, f)) {
        if (line[0] == 'v' && line[1] == ' ') {
            float x, y, z;
            if (sscanf(line + 2, "%f %f %f", &x, &y, &z) != 3 || add_vertex(m, x, y, z) != 0)
                return -1;
        } else if (line[0] == 'f' && line[1] == ' ') {
            /* A polygon, as a fan of triangles. */
            const char *s = line + 2;
            long first, prev, cur;
            if (corner(&s, m->nv, &first) != 0 || corner(&s, m->nv, &prev) != 0)
                return -1;
            while (*s && (s += strspn(s, " \t\r\n"), *s)) {
                if (corner(&s, m->nv, &cur) != 0 || add_triangle(m, first, prev, cur) != 0)
                    return -1;
                prev = cur;
            }
        }
    }
    return 0;
}

static int load_off(FILE *f, struct mesh *m)
{
    long nv, nf, ne;
    if (fscanf(f, " OFF %ld %ld %ld", &nv, &nf, &ne) != 3 || nv <= 0 || nf < 0)
        return -1;
    for (long i = 0; i < nv; i++) {
        float x, y, z;
        if (fscanf(f, "%f %f %f", &x, &y, &z) != 3 || add_vertex(m, x, y, z) != 0)
            return -1;
    }
    for (long i = 0; i < nf; i++) {
        long k, first, prev, cur;
        if (fscanf(f, "%ld %ld %ld", &k, &first, &prev) != 3 || k < 3)
            return -1;
        for (long j = 2; j < k; j++) {
            if (fscanf(f, "%ld", &cur) != 1 || add_triangle(m, first, prev, cur) != 0)
                return -1;
            prev = cur;
        }
    }
    return 0;
}

/* The loader the rules name: both arrays grow here (through the helpers,
 * which the compiler may inline into it). Kept out of line so that it is a
 * frame of the allocations' stack at -O2; built with -DLOADER_INLINE it is
 * inlined into main, and site=load_mesh finds nothing (tests/shim). */
#ifdef LOADER_INLINE
static inline __attribute__((always_inline)) int load_mesh(const char *path, struct mesh *m)
#else
static __attribute__((noinline)) int load_mesh(const char *path, struct mesh *m)
#endif
{
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    const char *dot = strrchr(path, '.');
    int rc = dot && strcmp(dot, ".off") == 0 ? load_off(f, m) : load_obj(f, m);
    fclose(f);
    return rc == 0 && m->nv > 0 && m->nt > 0 ? 0 : -1;
}

/* One Laplacian pass: each vertex moves halfway to the mean of its
 * neighbours along the triangles' edges (an edge shared by two triangles
 * counts twice, as the two triangles pull twice). A triangle's corners and
 * their positions are read once into locals: the stores to `sum` could
 * alias the positions, and a compiler would otherwise read them again
 * after each store, each compiler its own way. */
static void smooth_pass(struct mesh *m, float *sum, uint32_t *count)
{
    memset(sum, 0, 3 * m->nv * sizeof *sum);
    memset(count, 0, m->nv * sizeof *count);
    for (size_t t = 0; t < m->nt; t++) {
        const uint32_t *c = &m->tri[3 * t];
        uint32_t v[3] = {c[0], c[1], c[2]};
        float p[3][3];
        for (int k = 0; k < 3; k++) {
            const float *q = &m->xyz[3 * v[k]];
            p[k][0] = q[0];
            p[k][1] = q[1];
            p[k][2] = q[2];
        }
        for (int k = 0; k < 3; k++) {
            int n1 = (k + 1) % 3, n2 = (k + 2) % 3;
            for (int d = 0; d < 3; d++)
                sum[3 * v[k] + d] += p[n1][d] + p[n2][d];
            count[v[k]] += 2;
        }
    }
    for (size_t v = 0; v < m->nv; v++) {
        if (count[v] == 0)
            continue;
        float *p = &m->xyz[3 * v];
        float x = p[0], y = p[1], z = p[2];
        p[0] = 0.5f * x + 0.5f * sum[3 * v] / (float)count[v];
        p[1] = 0.5f * y + 0.5f * sum[3 * v + 1] / (float)count[v];
        p[2] = 0.5f * z + 0.5f * sum[3 * v + 2] / (float)count[v];
    }
}

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 3) {
        fprintf(stderr, "usage: smooth MESH.obj|MESH.off [PASSES]\n");
        return 2;
    }
    long passes = argc == 3 ? strtol(argv[2], NULL, 10) : 10;
    struct mesh m = {0};
    if (load_mesh(argv[1], &m) != 0) {
        fprintf(stderr, "smooth: cannot read a triangle mesh from %s\n", argv[1]);
        return 1;
    }
    float *sum = malloc(3 * m.nv * sizeof *sum);
    uint32_t *count = malloc(m.nv * sizeof *count);
    if (!sum || !count)
        return 1;
    for (long i = 0; i < passes; i++)
        smooth_pass(&m, sum, count);
    double check = 0;
    for (size_t v = 0; v < m.nv; v++)
        check += fabs((double)m.xyz[3 * v]) + 2 * fabs((double)m.xyz[3 * v + 1]) +
                 3 * fabs((double)m.xyz[3 * v + 2]);
    printf("vertices %zu triangles %zu passes %ld checksum %.6f\n", m.nv, m.nt, passes, check);
    free(sum);
    free(count);
    free(m.xyz);
    free(m.tri);
    return 0;
}
