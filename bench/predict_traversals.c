/* Traversal programs for the prediction benchmark (bench/predict.sh): more
 * shapes of mesh traversal than the example workloads, each one a program as
 * far as the benchmark's leave-one-program-out goes. They read the mesh into
 * the workloads' thesis records (examples/workload.c, tagged for the shim)
 * and touch the mesh only through them; what they print is a checksum, so
 * the native and the shimmed run can be compared.
 *
 *   walk        64 walks of 400 steps across edges, each step to the
 *               neighbour that keeps the walk's heading best (a straight
 *               walk that bends with the mesh), from random triangles
 *   flood       breadth-first flood fill over triangle adjacency from
 *               triangle 0, reading each triangle and its corners
 *   seeds       8 breadth-first fills from random seeds, one step of each
 *               in turn (round robin), each up to an eighth of the mesh
 *   scan-index  every triangle and its corners in index order, twice
 *   scan-rows   the triangles sorted into 64 rows of centroid y, each row
 *               by x (a raster scan)
 *   scan-hilbert the triangles in the Hilbert order of their centroids
 *   smooth      3 Laplacian passes over the vertices, each vertex reading
 *               its one-ring's triangles and their corners
 *
 * usage: predict_traversals MODE MESH   (any mesh the workloads read) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "workload.h"

#define PROG "predict_traversals"

static uint64_t rng = 0x9e3779b97f4a7c15ull;
static uint64_t next_random(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

static uint64_t hash;

/* Reads triangle t and its three corners, as a visit does. */
static void visit(const struct Mesh *m, int32_t t, double c[3])
{
    const struct Triangle *tr = &m->triangles[t];
    c[0] = c[1] = c[2] = 0;
    for (int i = 0; i < 3; i++) {
        const struct Vertex *v = &m->vertices[tr->vertexIndices[i]];
        for (int k = 0; k < 3; k++)
            c[k] += v->coor[k] / 3;
    }
    /* Into the checksum, so that no read is dead code. */
    hash = fnv1a64(hash, &t, sizeof t);
    hash = fnv1a64(hash, c, 3 * sizeof *c);
}

static void *xcalloc(size_t n, size_t size)
{
    void *p = calloc(n ? n : 1, size);
    if (!p) {
        fprintf(stderr, PROG ": out of memory\n");
        exit(1);
    }
    return p;
}

static void walk(const struct Mesh *m)
{
    double c[3], d[3];
    for (int w = 0; w < 64; w++) {
        int32_t t = (int32_t)(next_random() % m->triNr);
        double a = (double)(next_random() % 6283) / 1000;
        double dir[3] = {cos(a), sin(a), 0};
        visit(m, t, c);
        for (int s = 0; s < 400; s++) {
            int32_t best = -1;
            double bestdot = -2;
            for (int i = 0; i < 3; i++) {
                int32_t n = m->triangles[t].neighbors[i];
                if (n < 0)
                    continue;
                visit(m, n, d);
                double e[3] = {d[0] - c[0], d[1] - c[1], d[2] - c[2]};
                double len = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
                double dot = len > 0 ? (e[0] * dir[0] + e[1] * dir[1] + e[2] * dir[2]) / len : -1;
                if (dot > bestdot)
                    bestdot = dot, best = n;
            }
            if (best < 0)
                break;
            visit(m, best, d);
            double e[3] = {d[0] - c[0], d[1] - c[1], d[2] - c[2]};
            double len = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
            if (len > 0) /* the heading follows the surface */
                for (int k = 0; k < 3; k++)
                    dir[k] = 0.8 * dir[k] + 0.2 * e[k] / len;
            memcpy(c, d, sizeof c);
            t = best;
        }
    }
}

/* Breadth-first fills from `nseeds` seeds, one step of each in turn. */
static void flood(const struct Mesh *m, int nseeds)
{
    size_t nt = m->triNr;
    unsigned char *seen = xcalloc(nt, 1);
    int32_t *queue = xcalloc(nt, sizeof *queue);
    size_t head[8], tail[8], cap = nt / (size_t)nseeds + 1;
    if (nseeds > 1)
        queue = realloc(queue, (size_t)nseeds * cap * sizeof *queue);
    if (!queue) {
        fprintf(stderr, PROG ": out of memory\n");
        exit(1);
    }
    for (int s = 0; s < nseeds; s++) {
        int32_t t = nseeds == 1 ? 0 : (int32_t)(next_random() % nt);
        head[s] = tail[s] = (size_t)s * (nseeds == 1 ? 0 : cap);
        if (!seen[t]) {
            seen[t] = 1;
            queue[tail[s]++] = t;
        }
    }
    size_t limit = nseeds == 1 ? nt : cap;
    double c[3];
    for (int busy = 1; busy;) {
        busy = 0;
        for (int s = 0; s < nseeds; s++) {
            if (head[s] == tail[s])
                continue;
            busy = 1;
            int32_t t = queue[head[s]++];
            visit(m, t, c);
            for (int i = 0; i < 3; i++) {
                int32_t n = m->triangles[t].neighbors[i];
                if (n >= 0 && !seen[n] && tail[s] - (size_t)s * (nseeds == 1 ? 0 : cap) < limit) {
                    seen[n] = 1;
                    queue[tail[s]++] = n;
                }
            }
        }
    }
    free(seen);
    free(queue);
}

static uint32_t hilbert_d(uint32_t n, uint32_t x, uint32_t y)
{
    uint32_t d = 0;
    for (uint32_t s = n / 2; s > 0; s /= 2) {
        uint32_t rx = (x & s) > 0, ry = (y & s) > 0;
        d += s * s * ((3 * rx) ^ ry);
        if (ry == 0) {
            if (rx == 1) {
                x = s - 1 - x;
                y = s - 1 - y;
            }
            uint32_t tmp = x;
            x = y;
            y = tmp;
        }
    }
    return d;
}

struct keyed {
    double key;
    int32_t t;
};

static int by_key(const void *a, const void *b)
{
    const struct keyed *x = a, *y = b;
    return x->key < y->key ? -1 : x->key > y->key ? 1 : (x->t > y->t) - (x->t < y->t);
}

/* The triangles in an order of their centroids: 'r' rows, 'h' Hilbert. The
 * keys come from a copy of the positions read in index order (a leading
 * sweep over the vertices, then one over the triangles' corners, which the
 * profile leaves out), then the scan reads the mesh in the keys' order. */
static void scan_sorted(const struct Mesh *m, char how)
{
    size_t nt = m->triNr, nv = m->verNr;
    struct keyed *k = xcalloc(nt, sizeof *k);
    double *p = xcalloc(3 * nv, sizeof *p), c[3];
    for (size_t v = 0; v < nv; v++)
        for (int a = 0; a < 3; a++)
            p[3 * v + a] = m->vertices[v].coor[a];
    int ax = 0, ay = 1; /* the two largest extents */
    double w0 = m->hi[0] - m->lo[0], w1 = m->hi[1] - m->lo[1], w2 = m->hi[2] - m->lo[2];
    if (w2 > w0 && w0 <= w1)
        ax = 2;
    else if (w2 > w1 && w1 < w0)
        ay = 2;
    double sx = (m->hi[ax] - m->lo[ax]) > 0 ? m->hi[ax] - m->lo[ax] : 1;
    double sy = (m->hi[ay] - m->lo[ay]) > 0 ? m->hi[ay] - m->lo[ay] : 1;
    for (size_t t = 0; t < nt; t++) {
        double x = 0, y = 0;
        for (int i = 0; i < 3; i++) {
            int32_t v = m->triangles[t].vertexIndices[i];
            x += (p[3 * v + ax] - m->lo[ax]) / sx / 3;
            y += (p[3 * v + ay] - m->lo[ay]) / sy / 3;
        }
        if (how == 'r') {
            double row = floor(y * 64);
            k[t].key = (row > 63 ? 63 : row) * 2 + x;
        } else {
            uint32_t n = 1024, ix = (uint32_t)(x * (n - 1)), iy = (uint32_t)(y * (n - 1));
            k[t].key = hilbert_d(n, ix, iy);
        }
        k[t].t = (int32_t)t;
    }
    qsort(k, nt, sizeof *k, by_key);
    for (size_t i = 0; i < nt; i++)
        visit(m, k[i].t, c);
    free(p);
    free(k);
}

static void smooth(const struct Mesh *m)
{
    int32_t fan[64];
    double *out = xcalloc(3 * m->verNr, sizeof *out);
    for (int pass = 0; pass < 3; pass++) {
        for (size_t v = 0; v < m->verNr; v++) {
            bool open;
            size_t n = vertex_fan(m, (int32_t)v, fan, 64, &open);
            if (n > 64)
                n = 64;
            double s[3] = {0, 0, 0}, c[3];
            for (size_t i = 0; i < n; i++) {
                visit(m, fan[i], c);
                for (int k = 0; k < 3; k++)
                    s[k] += c[k];
            }
            for (int k = 0; k < 3; k++)
                out[3 * v + k] = n ? s[k] / (double)n : m->vertices[v].coor[k];
        }
        for (size_t v = 0; v < 3 * m->verNr; v++)
            hash = fnv1a64(hash, &out[v], sizeof out[v]);
    }
    free(out);
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: " PROG " walk|flood|seeds|scan-index|scan-rows|scan-hilbert|"
                        "smooth MESH\n");
        return 2;
    }
    const char *mode = argv[1];
    struct Mesh m;
    if (!read_mesh(PROG, argv[2], &m))
        return 1;
    hash = FNV1A64_INIT;
    double c[3];
    if (strcmp(mode, "walk") == 0)
        walk(&m);
    else if (strcmp(mode, "flood") == 0)
        flood(&m, 1);
    else if (strcmp(mode, "seeds") == 0)
        flood(&m, 8);
    else if (strcmp(mode, "scan-index") == 0)
        for (int pass = 0; pass < 2; pass++)
            for (size_t t = 0; t < m.triNr; t++)
                visit(&m, (int32_t)t, c);
    else if (strcmp(mode, "scan-rows") == 0)
        scan_sorted(&m, 'r');
    else if (strcmp(mode, "scan-hilbert") == 0)
        scan_sorted(&m, 'h');
    else if (strcmp(mode, "smooth") == 0)
        smooth(&m);
    else {
        fprintf(stderr, PROG ": unknown mode '%s'\n", mode);
        free_mesh(&m);
        return 2;
    }
    printf("%s: %zu triangles, checksum 0x%016llx\n", mode, m.triNr, (unsigned long long)hash);
    free_mesh(&m);
    return 0;
}
