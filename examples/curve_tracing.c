/* curve_tracing — the curve-tracing workload of thesis §4.3.1 (Program 4.1).
 *
 * Curves are integrated through a tension vector field over a planar mesh
 * (the thesis uses the wrinkle curves of [24]: gamma'(u) = v(gamma(u))):
 *
 * - The field (workload.c, field_at): the gradient of a smooth potential,
 *   a linear ramp plus three Gaussian bumps, over the mesh's bounding box
 *   mapped to the unit square. The ramp is steeper than all bumps together,
 *   so the field has no zeros and, being a gradient, no closed orbits: every
 *   curve ends at the boundary. `--field uniform` replaces it with the
 *   constant (1, 0), whose curves are straight lines (the tests use it).
 *   The field is evaluated at the vertices once; inside a triangle it is
 *   interpolated with barycentric coordinates, as in the thesis.
 * - Seeds: `--curves N` (default 300) vertices, seed i being vertex
 *   floor(i * nv / N); each is traced in the +v direction from the triangle
 *   around the seed whose corner contains v.
 * - Euler steps of length lambda = half the mean edge length along v/|v|.
 *   Each step walks the segment through the mesh: where it leaves the current
 *   triangle (the first edge its barycentric coordinates cross, never the
 *   one it came in by), the walk moves to the neighbour across that edge
 *   (`neighbors`), until the segment's end lies in the current triangle. A
 *   boundary edge ends the curve at the crossing point.
 * - `--short` (default): every triangle a curve visits is marked with the
 *   curve's number; a curve stops where it enters a triangle an earlier curve
 *   marked. `--long`: curves run until the boundary.
 * - Thresholds, in both modes: a curve stops where |v| < 1e-9 (never, for
 *   the two fields here), after 4 * (bounding-box diagonal) / lambda steps,
 *   or when one step crosses more than 10,000 edges (numerical trouble only).
 *
 * On a surface in space (a mesh whose z are not all equal) the same walk
 * goes over the surface (trace_curve3): the field is a spatial potential's
 * gradient (field_at3) projected onto each triangle's plane, a step goes
 * straight in that plane and is unfolded about each edge it crosses into
 * the next triangle's plane, the step limit uses the 3D box's diagonal, and
 * a curve also ends where the field turns against its last step: it passed
 * a zero of the field, which a closed surface always has. Flat meshes take
 * the planar code above, so their outputs are what they were.
 *
 * Output: the number of curves of positive length and their total length
 * (in mesh units), "curves: N\nlength: X.XXXXXX\n". */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "workload.h"

#define PROG "curve_tracing"
#define DEFAULT_CURVES 300
#define FIELD_MIN 1e-9
#define MAX_CROSSINGS 10000

static void usage(FILE *out)
{
    fprintf(out,
            "usage: " PROG " [--short|--long] [--curves N] [--field tension|uniform] [--times] [MESH]\n"
            "\n"
            "Traces curves through a tension field over a triangle mesh (thesis section\n"
            "4.3.1) and prints their number and total length. MESH is an OFF, OBJ, PLY\n"
            "or STL file; without it the default mesh (20,000 clustered faces, seed 1)\n"
            "is generated in memory. On a mesh that is not flat (a sphere, a terrain)\n"
            "the curves follow the surface and also end where the field vanishes.\n"
            "\n"
            "  --short          stop a curve where it meets an earlier one (default)\n"
            "  --long           trace every curve to the boundary (or a sink)\n"
            "  --curves N       number of seed vertices (default %d)\n"
            "  --field F        tension (default) or uniform (the constant field (1, 0))\n"
            "  --times          print load and traversal seconds on stderr\n",
            DEFAULT_CURVES);
}


static double cross2(double ax, double ay, double bx, double by)
{
    return ax * by - ay * bx;
}

/* Barycentric coordinates of (x, y) in triangle t: b[j] belongs to corner j.
 * Each is its own ratio of areas (not 1 minus the others), so a point on an
 * edge gets an exact zero. */
static void barycentric(const struct Mesh *m, int32_t t, double x, double y, double b[3])
{
    const struct Triangle *T = &m->triangles[t];
    const double *A = m->vertices[T->vertexIndices[0]].coor;
    const double *B = m->vertices[T->vertexIndices[1]].coor;
    const double *C = m->vertices[T->vertexIndices[2]].coor;
    double area = cross2(B[0] - A[0], B[1] - A[1], C[0] - A[0], C[1] - A[1]);
    b[0] = cross2(B[0] - x, B[1] - y, C[0] - x, C[1] - y) / area;
    b[1] = cross2(C[0] - x, C[1] - y, A[0] - x, A[1] - y) / area;
    b[2] = cross2(A[0] - x, A[1] - y, B[0] - x, B[1] - y) / area;
}

/* The triangle around vertex s whose corner at s contains direction d, or -1
 * (a boundary vertex whose field points out of the mesh). */
static int32_t start_triangle(const struct Mesh *m, int32_t s, const double d[2],
                              int32_t **fan, size_t *cap)
{
    bool open;
    size_t n = vertex_fan(m, s, *fan, *cap, &open);
    if (n > *cap) {
        int32_t *grown = realloc(*fan, n * sizeof **fan);
        if (!grown) {
            fprintf(stderr, PROG ": out of memory\n");
            exit(1);
        }
        *fan = grown;
        *cap = n;
        n = vertex_fan(m, s, *fan, *cap, &open);
    }
    const double *S = m->vertices[s].coor;
    for (size_t i = 0; i < n; i++) {
        const struct Triangle *T = &m->triangles[(*fan)[i]];
        int k = tri_corner(T, s);
        const double *A = m->vertices[T->vertexIndices[(k + 1) % 3]].coor;
        const double *B = m->vertices[T->vertexIndices[(k + 2) % 3]].coor;
        double e1x = A[0] - S[0], e1y = A[1] - S[1], e2x = B[0] - S[0], e2y = B[1] - S[1];
        double o = cross2(e1x, e1y, e2x, e2y);
        if (cross2(e1x, e1y, d[0], d[1]) * o >= 0 && cross2(d[0], d[1], e2x, e2y) * o >= 0)
            return (*fan)[i];
    }
    return -1;
}

/* The edge index of triangle t that joins a and b. */
static int shared_edge(const struct Triangle *T, int32_t a, int32_t b)
{
    for (int i = 0; i < 3; i++) {
        int32_t x = T->vertexIndices[i], y = T->vertexIndices[(i + 1) % 3];
        if ((x == a && y == b) || (x == b && y == a))
            return i;
    }
    return -1;
}

struct tracer {
    const struct Mesh *m;
    const double *vf;   /* the field at each vertex: 2 per vertex, 3 when not flat */
    int32_t *mark;      /* --short: the curve that visited each triangle, -1 */
    bool short_mode;
    double lambda;
    size_t max_steps;
    int32_t *fan;
    size_t fan_cap;
};

/* ---- Surfaces in space (a mesh that is not flat). The same walk, each
 * triangle in its own plane: the field is the spatial one (field_at3),
 * interpolated at a point with barycentric coordinates and projected onto
 * the triangle's plane; a step goes straight in that plane; where it leaves
 * through an edge, the rest of the step is unfolded about the edge into the
 * neighbour's plane (the direction keeps its angle with the edge) and goes
 * on from the crossing point. */

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double a[3], const double b[3], double o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

static void sub3(const double a[3], const double b[3], double o[3])
{
    for (int i = 0; i < 3; i++)
        o[i] = a[i] - b[i];
}

/* Triangle t's normal (not normalised) and its corners. */
static void tri_frame(const struct Mesh *m, int32_t t, const double *c[3], double n[3])
{
    const struct Triangle *T = &m->triangles[t];
    for (int j = 0; j < 3; j++)
        c[j] = m->vertices[T->vertexIndices[j]].coor;
    double e1[3], e2[3];
    sub3(c[1], c[0], e1);
    sub3(c[2], c[0], e2);
    cross3(e1, e2, n);
}

/* Barycentric coordinates of x's projection onto t's plane: each the
 * signed area of its sub-triangle over the whole, as in 2D. */
static void barycentric3(const struct Mesh *m, int32_t t, const double x[3], double b[3])
{
    const double *c[3];
    double n[3];
    tri_frame(m, t, c, n);
    double nn = dot3(n, n);
    for (int j = 0; j < 3; j++) {
        double u[3], w[3], k[3];
        sub3(c[(j + 1) % 3], x, u);
        sub3(c[(j + 2) % 3], x, w);
        cross3(u, w, k);
        b[j] = dot3(k, n) / nn;
    }
}

/* d without its component along n. */
static void project3(double d[3], const double n[3])
{
    double nn = dot3(n, n), k = nn > 0 ? dot3(d, n) / nn : 0;
    for (int i = 0; i < 3; i++)
        d[i] -= k * n[i];
}

/* The field at barycentric b of t, in t's plane. */
static void field_in3(const struct tracer *tr, int32_t t, const double b[3], double d[3])
{
    const double *c[3];
    double n[3];
    tri_frame(tr->m, t, c, n);
    const struct Triangle *T = &tr->m->triangles[t];
    d[0] = d[1] = d[2] = 0;
    for (int j = 0; j < 3; j++)
        for (int i = 0; i < 3; i++)
            d[i] += b[j] * tr->vf[3 * T->vertexIndices[j] + i];
    project3(d, n);
}

/* The triangle around vertex s whose corner at s contains d projected onto
 * its plane. Where the surface is curved the corners' angles add up to less
 * (or more) than a full turn, so d may fall in none of them: then the
 * triangle it misses by the least angle (the walk leaves it at once if need
 * be). -1 only for a vertex with no triangle. */
static int32_t start_triangle3(const struct Mesh *m, int32_t s, const double d[3],
                               int32_t **fan, size_t *cap)
{
    bool open;
    size_t n = vertex_fan(m, s, *fan, *cap, &open);
    if (n > *cap) {
        int32_t *grown = realloc(*fan, n * sizeof **fan);
        if (!grown) {
            fprintf(stderr, PROG ": out of memory\n");
            exit(1);
        }
        *fan = grown;
        *cap = n;
        n = vertex_fan(m, s, *fan, *cap, &open);
    }
    const double *S = m->vertices[s].coor;
    int32_t best = -1;
    double best_score = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        const struct Triangle *T = &m->triangles[(*fan)[i]];
        int k = tri_corner(T, s);
        double e1[3], e2[3], nrm[3], dp[3] = {d[0], d[1], d[2]}, x1[3], x2[3];
        sub3(m->vertices[T->vertexIndices[(k + 1) % 3]].coor, S, e1);
        sub3(m->vertices[T->vertexIndices[(k + 2) % 3]].coor, S, e2);
        cross3(e1, e2, nrm);
        project3(dp, nrm);
        cross3(e1, dp, x1);
        cross3(dp, e2, x2);
        double in1 = dot3(x1, nrm), in2 = dot3(x2, nrm);
        if (in1 >= 0 && in2 >= 0)
            return (*fan)[i];
        /* The sine of the angle by which d misses the corner's nearer side. */
        double scale = sqrt(dot3(nrm, nrm) * dot3(dp, dp));
        double score = scale > 0 ? fmin(in1 / (scale * sqrt(dot3(e1, e1))),
                                        in2 / (scale * sqrt(dot3(e2, e2))))
                                 : -INFINITY;
        if (best < 0 || score > best_score) {
            best = (*fan)[i];
            best_score = score;
        }
    }
    return best;
}

/* Turns unit direction dir, leaving a triangle across edge (A, B), into the
 * plane of the neighbour whose third corner is C: the same component along
 * the edge, the rest pointing into the neighbour. */
static void unfold(const double A[3], const double B[3], const double C[3], double dir[3])
{
    double e[3], w[3], mm[3];
    sub3(B, A, e);
    double len = sqrt(dot3(e, e));
    for (int i = 0; i < 3; i++)
        e[i] /= len;
    double along = dot3(dir, e);
    for (int i = 0; i < 3; i++)
        w[i] = dir[i] - along * e[i];
    double across = sqrt(dot3(w, w));
    sub3(C, A, mm);
    double k = dot3(mm, e);
    for (int i = 0; i < 3; i++)
        mm[i] -= k * e[i];
    double ml = sqrt(dot3(mm, mm));
    for (int i = 0; i < 3; i++)
        dir[i] = along * e[i] + (ml > 0 ? across * mm[i] / ml : 0);
}

/* Traces curve c from seed vertex s over a surface in space; returns its
 * length. Besides the planar rules, a curve stops where the field turns
 * against the step just taken: it went past a zero of the field (the
 * surface's sinks, where curves would otherwise swing to and fro until the
 * step limit). */
static double trace_curve3(struct tracer *tr, int32_t c, int32_t s)
{
    const struct Mesh *m = tr->m;
    double d[3] = {tr->vf[3 * s], tr->vf[3 * s + 1], tr->vf[3 * s + 2]};
    int32_t t = start_triangle3(m, s, d, &tr->fan, &tr->fan_cap);
    if (t < 0)
        return 0;
    const double *corner[3];
    double n[3];
    tri_frame(m, t, corner, n);
    project3(d, n);
    if (sqrt(dot3(d, d)) < FIELD_MIN)
        return 0;
    if (tr->short_mode) {
        if (tr->mark[t] >= 0 && tr->mark[t] != c)
            return 0;
        tr->mark[t] = c;
    }
    double p[3];
    memcpy(p, m->vertices[s].coor, sizeof p);
    double length = 0;
    for (size_t step = 0; step < tr->max_steps; step++) {
        double norm = sqrt(dot3(d, d)), dir[3], q[3], rest = tr->lambda;
        for (int i = 0; i < 3; i++) {
            dir[i] = d[i] / norm;
            q[i] = p[i] + rest * dir[i];
        }
        int entry = -1;
        double bq[3];
        for (int crossings = 0;; crossings++) {
            if (crossings > MAX_CROSSINGS)
                return length;
            double bp[3];
            barycentric3(m, t, q, bq);
            barycentric3(m, t, p, bp);
            int exit_edge = -1;
            double s_exit = 2;
            for (int j = 0; j < 3; j++) {
                int e = (j + 1) % 3; /* the edge opposite corner j */
                if (e == entry || !(bq[j] < 0))
                    continue;
                double sj = bp[j] / (bp[j] - bq[j]);
                if (sj < s_exit) {
                    s_exit = sj;
                    exit_edge = e;
                }
            }
            if (exit_edge < 0)
                break; /* q lies in t */
            if (s_exit < 0)
                s_exit = 0;
            double done = tr->lambda - rest + s_exit * rest;
            const struct Triangle *T = &m->triangles[t];
            int32_t next = T->neighbors[exit_edge];
            if (next < 0)
                return length + done;
            if (tr->short_mode) {
                if (tr->mark[next] >= 0 && tr->mark[next] != c)
                    return length + done;
                tr->mark[next] = c;
            }
            int32_t a = T->vertexIndices[exit_edge], b = T->vertexIndices[(exit_edge + 1) % 3];
            entry = shared_edge(&m->triangles[next], a, b);
            const double *far = m->vertices[m->triangles[next].vertexIndices[(entry + 2) % 3]].coor;
            unfold(m->vertices[a].coor, m->vertices[b].coor, far, dir);
            for (int i = 0; i < 3; i++)
                p[i] += s_exit * (q[i] - p[i]);
            rest -= s_exit * rest;
            for (int i = 0; i < 3; i++)
                q[i] = p[i] + rest * dir[i];
            t = next;
        }
        length += tr->lambda;
        memcpy(p, q, sizeof p);
        field_in3(tr, t, bq, d);
        if (sqrt(dot3(d, d)) < FIELD_MIN || dot3(d, dir) < 0)
            break;
    }
    return length;
}

/* Traces curve c from seed vertex s; returns its length. */
static double trace_curve(struct tracer *tr, int32_t c, int32_t s)
{
    const struct Mesh *m = tr->m;
    double d[2] = {tr->vf[2 * s], tr->vf[2 * s + 1]};
    if (hypot(d[0], d[1]) < FIELD_MIN)
        return 0;
    int32_t t = start_triangle(m, s, d, &tr->fan, &tr->fan_cap);
    if (t < 0)
        return 0;
    if (tr->short_mode) {
        if (tr->mark[t] >= 0 && tr->mark[t] != c)
            return 0;
        tr->mark[t] = c;
    }
    double px = m->vertices[s].coor[0], py = m->vertices[s].coor[1];
    double length = 0;
    for (size_t step = 0; step < tr->max_steps; step++) {
        double norm = hypot(d[0], d[1]);
        double qx = px + tr->lambda * (d[0] / norm), qy = py + tr->lambda * (d[1] / norm);
        int entry = -1;
        double bq[3];
        for (int crossings = 0;; crossings++) {
            if (crossings > MAX_CROSSINGS)
                return length;
            double bp[3];
            barycentric(m, t, qx, qy, bq);
            barycentric(m, t, px, py, bp);
            int exit_edge = -1;
            double s_exit = 2;
            for (int j = 0; j < 3; j++) {
                int e = (j + 1) % 3; /* the edge opposite corner j */
                if (e == entry || !(bq[j] < 0))
                    continue;
                double sj = bp[j] / (bp[j] - bq[j]);
                if (sj < s_exit) {
                    s_exit = sj;
                    exit_edge = e;
                }
            }
            if (exit_edge < 0)
                break; /* q lies in t */
            if (s_exit < 0)
                s_exit = 0;
            const struct Triangle *T = &m->triangles[t];
            int32_t next = T->neighbors[exit_edge];
            if (next < 0)
                return length + s_exit * tr->lambda;
            if (tr->short_mode) {
                if (tr->mark[next] >= 0 && tr->mark[next] != c)
                    return length + s_exit * tr->lambda;
                tr->mark[next] = c;
            }
            int32_t a = T->vertexIndices[exit_edge], b = T->vertexIndices[(exit_edge + 1) % 3];
            entry = shared_edge(&m->triangles[next], a, b);
            t = next;
        }
        length += tr->lambda;
        px = qx;
        py = qy;
        const struct Triangle *T = &m->triangles[t];
        d[0] = d[1] = 0;
        for (int j = 0; j < 3; j++) {
            d[0] += bq[j] * tr->vf[2 * T->vertexIndices[j]];
            d[1] += bq[j] * tr->vf[2 * T->vertexIndices[j] + 1];
        }
        if (hypot(d[0], d[1]) < FIELD_MIN)
            break;
    }
    return length;
}

int main(int argc, char **argv)
{
    struct workload_args args = {NULL, false};
    bool short_mode = true;
    unsigned long long ncurves = DEFAULT_CURVES;
    enum field_kind kind = FIELD_TENSION;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(a, "--short") == 0) {
            short_mode = true;
        } else if (strcmp(a, "--long") == 0) {
            short_mode = false;
        } else if (strcmp(a, "--curves") == 0 || strcmp(a, "--field") == 0) {
            if (i + 1 >= argc)
                return workload_usage_error(PROG, "option needs a value", a);
            const char *val = argv[++i];
            if (strcmp(a, "--field") == 0) {
                if (!field_parse(val, &kind))
                    return workload_usage_error(PROG, "--field accepts tension or uniform, not", val);
            } else {
                char *end;
                if (val[0] < '0' || val[0] > '9')
                    return workload_usage_error(PROG, "--curves needs a positive integer, not", val);
                ncurves = strtoull(val, &end, 10);
                if (*end || ncurves == 0 || ncurves > INT32_MAX)
                    return workload_usage_error(PROG, "--curves needs a positive integer, not", val);
            }
        } else {
            int rc = workload_common_arg(&args, PROG, a);
            if (rc)
                return rc;
        }
    }

    double t0 = workload_now();
    struct Mesh mesh;
    if (!read_mesh(PROG, args.mesh, &mesh))
        return 1;
    double t1 = workload_now();

    size_t nv = mesh.verNr, nt = mesh.triNr;
    struct field f;
    field_init(&f, kind, &mesh);
    int dims = mesh.flat ? 2 : 3;
    double *vf = malloc((size_t)dims * (nv ? nv : 1) * sizeof *vf);
    int32_t *mark = malloc((nt ? nt : 1) * sizeof *mark);
    struct tracer tr = {&mesh, vf, mark, short_mode, mesh.mean_edge / 2, 0, NULL, 0};
    tr.fan_cap = 64;
    tr.fan = malloc(tr.fan_cap * sizeof *tr.fan);
    if (!vf || !mark || !tr.fan) {
        fprintf(stderr, PROG ": out of memory\n");
        return 1;
    }
    for (size_t v = 0; v < nv; v++) {
        if (mesh.flat)
            field_at(&f, mesh.vertices[v].coor[0], mesh.vertices[v].coor[1], &vf[2 * v]);
        else
            field_at3(&f, mesh.vertices[v].coor, &vf[3 * v]);
    }
    for (size_t t = 0; t < nt; t++)
        mark[t] = -1;
    double diag = hypot(mesh.hi[0] - mesh.lo[0], mesh.hi[1] - mesh.lo[1]);
    if (!mesh.flat)
        diag = hypot(diag, mesh.hi[2] - mesh.lo[2]);
    tr.max_steps = tr.lambda > 0 ? (size_t)ceil(4 * diag / tr.lambda) : 0;

    if (ncurves > nv)
        ncurves = nv;
    size_t drawn = 0;
    double total = 0;
    for (size_t i = 0; i < ncurves; i++) {
        int32_t seed = (int32_t)(i * nv / ncurves);
        double len = mesh.flat ? trace_curve(&tr, (int32_t)i, seed)
                               : trace_curve3(&tr, (int32_t)i, seed);
        if (len > 0) {
            drawn++;
            total += len;
        }
    }
    double t2 = workload_now();

    printf("curves: %zu\nlength: %.6f\n", drawn, total);
    workload_report_times(&args, t0, t1, t2);
    free(tr.fan);
    free(mark);
    free(vf);
    free_mesh(&mesh);
    return 0;
}
