/* The distance profiler (thesis §5, Eq. 5.1, Figs 5.4–5.5): exact and fast
 * computation of D_i = Σ_{k<i} ‖p_i − p_k‖, the positions of a trace's
 * element accesses, and the feature vector the strategy table compares.
 * docs/profile.md explains the choices. */
#include "emm/profile.h"

#include <assert.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <emmintrin.h>
#include <immintrin.h>

#include "error.h"
#include "geom.h"
#include "lead_sweep.h"
#include "pool.h"
#include "window_fill.h"

/* ---- exact ------------------------------------------------------------ */

/* Positions come in as `dims` coordinates a point (2 or 3); the exact method
 * splits them into one array per axis, c[a][k], so the kernels load whole
 * vectors of one axis. */

/* Row i of Eq. 5.1 is Σ_{k<i} ‖p_k − p_i‖, summed in a fixed order: the
 * terms go round L lanes (two accumulators of L/2 lanes each: the square
 * root is the bottleneck, so independent chains keep the unit busy) over
 * whole blocks of L, the lanes are added pairwise, then the tail's terms
 * one by one. A row's accumulators after block b are the same for every
 * row of the same point that reaches b, so the rows of a point that recurs
 * (a vertex read again by each of its triangles) are one computation: each
 * occurrence carries the previous one's accumulators on from its block
 * boundary and adds only its own tail. The results are bit for bit those
 * of computing every row from scratch, for a fraction of the square roots.
 * A third axis adds its squared difference after the first two, so a
 * profile in the plane is what it was before positions had a dimension. */
typedef struct row_kernel {
    size_t lanes; /* L: the block length, and the accumulators' lanes */
    /* Adds the blocks [k0, k1) (multiples of L) to the accumulators acc[L]. */
    void (*blocks)(const double *const *c, uint32_t dims, size_t k0, size_t k1, const double *p,
                   double *acc);
    /* The row's sum: the accumulators reduced, then the terms [k0, n). */
    double (*finish)(const double *const *c, uint32_t dims, size_t k0, size_t n, const double *p,
                     const double *acc);
} row_kernel;

/* ‖p_k − p‖, one term of a row's tail. */
static inline double term(const double *const *c, uint32_t dims, size_t k, const double *p)
{
    double dx = c[0][k] - p[0], dy = c[1][k] - p[1], s = dx * dx + dy * dy;
    if (dims > 2) {
        double dz = c[2][k] - p[2];
        s += dz * dz;
    }
    return sqrt(s);
}

/* SSE2: the squared distances of points k, k + 1 from P. */
static inline __m128d sq_sse2(const double *const *c, uint32_t dims, size_t k, const __m128d *P)
{
    __m128d dx = _mm_sub_pd(_mm_loadu_pd(c[0] + k), P[0]);
    __m128d dy = _mm_sub_pd(_mm_loadu_pd(c[1] + k), P[1]);
    __m128d s = _mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy));
    if (dims > 2) {
        __m128d dz = _mm_sub_pd(_mm_loadu_pd(c[2] + k), P[2]);
        s = _mm_add_pd(s, _mm_mul_pd(dz, dz));
    }
    return s;
}

/* SSE2: two accumulators of two lanes (baseline x86-64). */
static void blocks_sse2(const double *const *c, uint32_t dims, size_t k0, size_t k1,
                        const double *p, double *acc)
{
    __m128d a0 = _mm_loadu_pd(acc), a1 = _mm_loadu_pd(acc + 2);
    __m128d P[3] = {_mm_set1_pd(p[0]), _mm_set1_pd(p[1]), _mm_set1_pd(dims > 2 ? p[2] : 0)};
    for (size_t k = k0; k < k1; k += 4) {
        a0 = _mm_add_pd(a0, _mm_sqrt_pd(sq_sse2(c, dims, k, P)));
        a1 = _mm_add_pd(a1, _mm_sqrt_pd(sq_sse2(c, dims, k + 2, P)));
    }
    _mm_storeu_pd(acc, a0);
    _mm_storeu_pd(acc + 2, a1);
}

static double finish_sse2(const double *const *c, uint32_t dims, size_t k0, size_t n,
                          const double *p, const double *acc)
{
    double lanes[2];
    _mm_storeu_pd(lanes, _mm_add_pd(_mm_loadu_pd(acc), _mm_loadu_pd(acc + 2)));
    double s = lanes[0] + lanes[1];
    for (size_t k = k0; k < n; k++)
        s += term(c, dims, k, p);
    return s;
}

/* The same with two accumulators of four lanes, for processors that have
 * AVX2 (the build targets baseline x86-64, so this is chosen at run time). */
__attribute__((target("avx2"))) static inline __m256d sq_avx2(const double *const *c,
                                                              uint32_t dims, size_t k,
                                                              const __m256d *P)
{
    __m256d dx = _mm256_sub_pd(_mm256_loadu_pd(c[0] + k), P[0]);
    __m256d dy = _mm256_sub_pd(_mm256_loadu_pd(c[1] + k), P[1]);
    __m256d s = _mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy));
    if (dims > 2) {
        __m256d dz = _mm256_sub_pd(_mm256_loadu_pd(c[2] + k), P[2]);
        s = _mm256_add_pd(s, _mm256_mul_pd(dz, dz));
    }
    return s;
}

__attribute__((target("avx2"))) static void blocks_avx2(const double *const *c, uint32_t dims,
                                                         size_t k0, size_t k1, const double *p,
                                                         double *acc)
{
    __m256d a0 = _mm256_loadu_pd(acc), a1 = _mm256_loadu_pd(acc + 4);
    __m256d P[3] = {_mm256_set1_pd(p[0]), _mm256_set1_pd(p[1]),
                    _mm256_set1_pd(dims > 2 ? p[2] : 0)};
    for (size_t k = k0; k < k1; k += 8) {
        a0 = _mm256_add_pd(a0, _mm256_sqrt_pd(sq_avx2(c, dims, k, P)));
        a1 = _mm256_add_pd(a1, _mm256_sqrt_pd(sq_avx2(c, dims, k + 4, P)));
    }
    _mm256_storeu_pd(acc, a0);
    _mm256_storeu_pd(acc + 4, a1);
}

__attribute__((target("avx2"))) static double finish_avx2(const double *const *c, uint32_t dims,
                                                           size_t k0, size_t n, const double *p,
                                                           const double *acc)
{
    double lanes[4];
    _mm256_storeu_pd(lanes, _mm256_add_pd(_mm256_loadu_pd(acc), _mm256_loadu_pd(acc + 4)));
    double s = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
    for (size_t k = k0; k < n; k++)
        s += term(c, dims, k, p);
    return s;
}

static const row_kernel kernel_sse2 = {4, blocks_sse2, finish_sse2};
static const row_kernel kernel_avx2 = {8, blocks_avx2, finish_avx2};

static const row_kernel *pick_kernel(void)
{
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") ? &kernel_avx2 : &kernel_sse2;
}

/* The rows of one point: i, next[i], next[next[i]], ... (ascending). */
static void point_rows(const row_kernel *kr, const double *const *c, uint32_t dims,
                       const int32_t *next, size_t i, double *D)
{
    double acc[8] = {0};
    double p[EMM_MAX_DIMS] = {0};
    for (uint32_t a = 0; a < dims; a++)
        p[a] = c[a][i];
    size_t done = 0; /* blocks added so far, in terms */
    for (int64_t r = (int64_t)i; r >= 0; r = next[r]) {
        size_t row = (size_t)r, whole = row - row % kr->lanes;
        if (whole > done) {
            kr->blocks(c, dims, done, whole, p, acc);
            done = whole;
        }
        D[row] = kr->finish(c, dims, done, row, p, acc);
    }
}

/* Points per item of the pool's work: the items go from the last points
 * (the longest rows) to the first, so the threads finish together. */
#define EXACT_ITEM 16u

struct exact_job {
    const row_kernel *kr;
    const double *c[EMM_MAX_DIMS];
    uint32_t dims;
    const int32_t *next;
    const int32_t *heads; /* the first row of each distinct point, ascending */
    size_t nheads;
    double *D;
};

static void exact_run(void *ctx, size_t k)
{
    const struct exact_job *j = ctx;
    size_t items = (j->nheads + EXACT_ITEM - 1) / EXACT_ITEM;
    size_t item = items - 1 - k, lo = item * EXACT_ITEM;
    size_t hi = lo + EXACT_ITEM < j->nheads ? lo + EXACT_ITEM : j->nheads;
    for (size_t h = hi; h-- > lo;)
        point_rows(j->kr, j->c, j->dims, j->next, (size_t)j->heads[h], j->D);
}

/* Too short to be worth a thread. */
#define EXACT_THREAD_MIN 2048u

static uint64_t point_hash(const double *const *c, uint32_t dims, size_t i)
{
    uint64_t a, b;
    memcpy(&a, &c[0][i], sizeof a);
    memcpy(&b, &c[1][i], sizeof b);
    uint64_t h = a * 0x9E3779B97F4A7C15u ^ (b + 0x632BE59BD9B4E019u + (a << 6) + (a >> 2));
    if (dims > 2) {
        uint64_t z;
        memcpy(&z, &c[2][i], sizeof z);
        h ^= z * 0xC2B2AE3D27D4EB4Fu;
    }
    h ^= h >> 31;
    h *= 0xD6E8FEB86659FD93u;
    return h ^ (h >> 32);
}

/* Links each row to the next row of the same point (bitwise the same
 * coordinates) in next[], -1 after the last, and lists each point's first
 * row in heads[]; returns the number of points. `slot` has cap entries (a
 * power of two above n). */
static size_t group_points(const double *const *c, uint32_t dims, size_t n, int32_t *next,
                           int32_t *heads, int32_t *slot, int32_t *last, size_t cap)
{
    size_t nheads = 0;
    for (size_t s = 0; s < cap; s++)
        slot[s] = -1;
    for (size_t i = 0; i < n; i++) {
        next[i] = -1;
        size_t s = (size_t)point_hash(c, dims, i) & (cap - 1);
        for (;;) {
            int32_t h = slot[s];
            if (h < 0) {
                slot[s] = (int32_t)nheads;
                heads[nheads] = (int32_t)i;
                last[nheads++] = (int32_t)i;
                break;
            }
            size_t f = (size_t)heads[h];
            bool same = true;
            for (uint32_t a = 0; a < dims && same; a++)
                same = memcmp(&c[a][f], &c[a][i], sizeof c[a][i]) == 0;
            if (same) {
                next[last[h]] = (int32_t)i;
                last[h] = (int32_t)i;
                break;
            }
            s = (s + 1) & (cap - 1);
        }
    }
    return nheads;
}

void emm_profile_exact(const double *pos, size_t n, uint32_t dims, double *D,
                       const emm_threads *threads)
{
    assert(dims == 2 || dims == 3);
    if (n == 0)
        return;
    size_t cap = 16;
    while (cap < 2 * n)
        cap *= 2;
    double *split = n <= INT32_MAX ? malloc(dims * n * sizeof *split) : NULL;
    int32_t *ints = split ? malloc((3 * n + cap) * sizeof *ints) : NULL;
    if (!ints) {
        free(split);
        /* No room for the split copy: the scalar loop on the caller's array. */
        for (size_t i = 0; i < n; i++) {
            double s = 0;
            for (size_t k = 0; k < i; k++) {
                const double *a = pos + dims * k, *b = pos + dims * i;
                double dx = a[0] - b[0], dy = a[1] - b[1], s2 = dx * dx + dy * dy;
                if (dims > 2)
                    s2 += (a[2] - b[2]) * (a[2] - b[2]);
                s += sqrt(s2);
            }
            D[i] = s;
        }
        return;
    }
    struct exact_job job = {.kr = pick_kernel(), .dims = dims, .D = D};
    for (uint32_t a = 0; a < dims; a++) {
        double *ca = split + a * n;
        for (size_t i = 0; i < n; i++)
            ca[i] = pos[dims * i + a];
        job.c[a] = ca;
    }
    int32_t *next = ints, *heads = ints + n, *last = ints + 2 * n, *slot = ints + 3 * n;
    job.next = next;
    job.heads = heads;
    job.nheads = group_points(job.c, dims, n, next, heads, slot, last, cap);
    size_t items = (job.nheads + EXACT_ITEM - 1) / EXACT_ITEM;
    emm_pool *pool = n >= EXACT_THREAD_MIN ? emm_pool_new(threads, 2) : NULL;
    emm_pool_for(pool, items, exact_run, &job);
    emm_pool_free(pool);
    free(ints);
    free(split);
}

/* ---- fast ------------------------------------------------------------- */

/* The tree over the earlier positions: each node splits its cube in two
 * along every axis, so 2^dims children — a quadtree in the plane, an octree
 * in space. Nothing in the bound depends on the dimension (docs/profile.md
 * "Fast method and its bound"): the third derivative of ‖x‖ along a line
 * lives in the plane of that line and the origin, and the expansion's
 * terms are written for any number of axes. The walks are inlined with the
 * dimension a constant (fast_walk). */
#define ALWAYS_INLINE inline __attribute__((always_inline))

/* A node of the tree: count, centroid and central second moments of its
 * points (Welford's update keeps the central forms accurate), their
 * bounding box, and the node's own cube. The second moments are the upper
 * triangle by columns, xx, xy, yy, xz, yz, zz: moment (a, b), a <= b, at
 * MOMENT(a, b); a tree in the plane uses the first three. */
struct tnode {
    double c[EMM_MAX_DIMS];            /* centroid of the points */
    double r2;                         /* squared radius about the centroid (box corners) */
    double m[EMM_MAX_DIMS * (EMM_MAX_DIMS + 1) / 2]; /* central second moments */
    double lo[EMM_MAX_DIMS], hi[EMM_MAX_DIMS];       /* bounding box of the points */
    double b[EMM_MAX_DIMS], half;      /* box centre and half side */
    uint32_t count;
    int32_t child;                     /* first of 2^dims children, or -1 for a leaf */
    int32_t head;                      /* leaf: first point (index into the list), -1 if none */
    uint32_t depth;
};

#define MOMENT(a, b) ((b) * ((b) + 1) / 2 + (a))

/* A leaf splits when it holds more points than this (unless at MAX_DEPTH,
 * where only duplicates and near-duplicates end up). */
#define LEAF_MAX 24u
#define MAX_DEPTH 40u

struct tree {
    struct tnode *node;
    size_t nnodes, cap;
    const double *pos;   /* dims coordinates a point */
    uint32_t dims, nchild;
    int32_t *next; /* per point: the next point in the same leaf */
    double theta2;
    /* traversal stack */
    int32_t *stack;
    size_t stack_cap;
};

static void tnode_init(struct tnode *q, uint32_t dims, const double *b, double half,
                       uint32_t depth)
{
    memset(q, 0, sizeof *q);
    for (uint32_t a = 0; a < dims; a++) {
        q->b[a] = b[a];
        q->lo[a] = INFINITY;
        q->hi[a] = -INFINITY;
    }
    q->half = half;
    q->child = -1;
    q->head = -1;
    q->depth = depth;
}

/* Adds a point to a node's aggregates: Welford's update keeps the central
 * moments accurate, and the query reads them without further arithmetic.
 * In the plane the operations are, in order, those of the 2D tree this
 * replaced, so its profiles are unchanged to the bit. */
static ALWAYS_INLINE void tnode_account(struct tnode *q, uint32_t dims, const double *p)
{
    q->count++;
    double d[EMM_MAX_DIMS];
    for (uint32_t a = 0; a < dims; a++)
        d[a] = p[a] - q->c[a];
    double inv = 1.0 / q->count;
    for (uint32_t a = 0; a < dims; a++)
        q->c[a] += d[a] * inv;
    for (uint32_t b = 0; b < dims; b++)
        for (uint32_t a = 0; a <= b; a++)
            q->m[MOMENT(a, b)] += d[a] * (p[b] - q->c[b]);
    double r2 = 0;
    for (uint32_t a = 0; a < dims; a++) {
        if (p[a] < q->lo[a])
            q->lo[a] = p[a];
        if (p[a] > q->hi[a])
            q->hi[a] = p[a];
        double r = fmax(q->c[a] - q->lo[a], q->hi[a] - q->c[a]);
        r2 = a == 0 ? r * r : r2 + r * r;
    }
    q->r2 = r2;
}

/* The child of q whose box holds p: bit a set for the upper half along a. */
static ALWAYS_INLINE uint32_t child_of(const struct tnode *q, uint32_t dims, const double *p)
{
    uint32_t k = 0;
    for (uint32_t a = 0; a < dims; a++)
        k |= (uint32_t)(p[a] >= q->b[a]) << a;
    return k;
}

static bool tree_split(struct tree *t, int32_t ni)
{
    if (t->nnodes + t->nchild > t->cap) {
        size_t cap = t->cap * 2;
        struct tnode *nn = realloc(t->node, cap * sizeof *nn);
        if (!nn)
            return false;
        t->node = nn;
        t->cap = cap;
    }
    struct tnode *q = &t->node[ni];
    int32_t first = (int32_t)t->nnodes;
    double h = q->half * 0.5;
    for (uint32_t k = 0; k < t->nchild; k++) {
        double b[EMM_MAX_DIMS];
        for (uint32_t a = 0; a < t->dims; a++)
            b[a] = q->b[a] + (((k >> a) & 1u) ? h : -h);
        tnode_init(&t->node[first + (int32_t)k], t->dims, b, h, q->depth + 1);
    }
    t->nnodes += t->nchild;
    for (int32_t k = q->head; k >= 0;) {
        int32_t nk = t->next[k];
        const double *p = t->pos + (size_t)t->dims * (size_t)k;
        struct tnode *c = &t->node[first + (int32_t)child_of(q, t->dims, p)];
        tnode_account(c, t->dims, p);
        t->next[k] = c->head;
        c->head = k;
        k = nk;
    }
    q->child = first;
    q->head = -1;
    return true;
}

static ALWAYS_INLINE bool tree_insert(struct tree *t, uint32_t dims, int32_t k)
{
    const double *p = t->pos + (size_t)dims * (size_t)k;
    int32_t ni = 0;
    for (;;) {
        struct tnode *q = &t->node[ni];
        tnode_account(q, dims, p);
        if (q->child >= 0) {
            ni = q->child + (int32_t)child_of(q, dims, p);
            continue;
        }
        t->next[k] = q->head;
        q->head = k;
        if (q->count > LEAF_MAX && q->depth < MAX_DEPTH)
            return tree_split(t, ni);
        return true;
    }
}

/* Σ over the tree's points of ‖p − q‖, within the relative bound. */
static ALWAYS_INLINE double tree_query(const struct tree *t, uint32_t dims, const double *p)
{
    double sum = 0;
    size_t top = 0;
    t->stack[top++] = 0;
    while (top) {
        const struct tnode *q = &t->node[t->stack[--top]];
        if (q->count == 0)
            continue;
        double dx = p[0] - q->c[0], dy = p[1] - q->c[1], dz = dims > 2 ? p[2] - q->c[2] : 0;
        double d2 = dx * dx + dy * dy;
        if (dims > 2)
            d2 += dz * dz;
        if (q->r2 <= t->theta2 * d2 && d2 > 0) {
            /* Multipole: n·d + (tr M − uᵀMu) / (2d), M the central second moments. */
            double d = sqrt(d2);
            const double *m = q->m;
            double quad = dx * dx * m[MOMENT(0, 0)] + 2 * dx * dy * m[MOMENT(0, 1)] +
                          dy * dy * m[MOMENT(1, 1)];
            double tr = m[MOMENT(0, 0)] + m[MOMENT(1, 1)];
            if (dims > 2) {
                quad += 2 * dx * dz * m[MOMENT(0, 2)] + 2 * dy * dz * m[MOMENT(1, 2)] +
                        dz * dz * m[MOMENT(2, 2)];
                tr += m[MOMENT(2, 2)];
            }
            quad /= d2;
            sum += q->count * d + (tr - quad) / (2 * d);
        } else if (q->child < 0) {
            for (int32_t k = q->head; k >= 0; k = t->next[k]) {
                const double *r = t->pos + (size_t)dims * (size_t)k;
                double ex = r[0] - p[0], ey = r[1] - p[1], e2 = ex * ex + ey * ey;
                if (dims > 2)
                    e2 += (r[2] - p[2]) * (r[2] - p[2]);
                sum += sqrt(e2);
            }
        } else {
            for (uint32_t c = 0; c < 1u << dims; c++)
                t->stack[top++] = q->child + (int32_t)c;
        }
    }
    return sum;
}

struct fast_job {
    const double *pos;
    uint32_t dims;
    size_t n, lo, hi; /* answers queries lo..hi-1; inserts 0..hi-1 */
    double theta;
    double *D;
    double b[EMM_MAX_DIMS], half;
    bool ok;
};

/* Inserts the points 0..lo-1, then answers and inserts lo..hi-1; false
 * when memory runs out. Inlined with dims a constant (fast_walk2,
 * fast_walk3), so that each dimension's loops are unrolled: a tree over a
 * run-time dimension made the plane's profile 10 % slower. */
static ALWAYS_INLINE bool fast_walk(struct tree *t, const struct fast_job *j, uint32_t dims)
{
    size_t i = 0;
    for (; i < j->lo; i++)
        if (!tree_insert(t, dims, (int32_t)i))
            return false;
    for (; i < j->hi; i++) {
        j->D[i] = tree_query(t, dims, j->pos + (size_t)dims * i);
        if (!tree_insert(t, dims, (int32_t)i))
            return false;
    }
    return true;
}

static bool fast_walk2(struct tree *t, const struct fast_job *j)
{
    return fast_walk(t, j, 2);
}

static bool fast_walk3(struct tree *t, const struct fast_job *j)
{
    return fast_walk(t, j, 3);
}

static void fast_run(void *ctx, size_t k)
{
    struct fast_job *j = (struct fast_job *)ctx + k;
    struct tree t = {0};
    j->ok = false;
    t.dims = j->dims;
    t.nchild = 1u << j->dims;
    t.cap = 1024;
    t.node = malloc(t.cap * sizeof *t.node);
    t.next = malloc(j->hi * sizeof *t.next);
    /* A depth-first walk keeps at most nchild - 1 siblings pending per level. */
    t.stack_cap = t.nchild * MAX_DEPTH + 8;
    t.stack = malloc(t.stack_cap * sizeof *t.stack);
    t.pos = j->pos;
    t.theta2 = j->theta * j->theta;
    if (t.node && t.next && t.stack) {
        tnode_init(&t.node[0], t.dims, j->b, j->half, 0);
        t.nnodes = 1;
        j->ok = t.dims == 2 ? fast_walk2(&t, j) : fast_walk3(&t, j);
    }
    free(t.node);
    free(t.next);
    free(t.stack);
}

double emm_profile_fast_bound(double theta)
{
    if (!(theta > 0 && theta < 1))
        return INFINITY;
    double q = theta / (1 - theta);
    return q * q * q / (3 * sqrt(3.0));
}

emm_status emm_profile_fast(const double *pos, size_t n, uint32_t dims, double theta, double *D,
                            const emm_threads *threads, emm_error *err)
{
    assert(dims == 2 || dims == 3);
    if (!(theta > 0 && theta < 1))
        return emm_fail(err, EMM_ERR_RANGE, "opening angle %g: must be between 0 and 1", theta);
    if (n > (size_t)INT32_MAX)
        return emm_fail(err, EMM_ERR_RANGE, "%zu accesses: the fast profile takes at most %d",
                        n, INT32_MAX);
    if (n == 0)
        return EMM_OK;
    double lo[EMM_MAX_DIMS], hi[EMM_MAX_DIMS], half = 0;
    for (uint32_t a = 0; a < dims; a++) {
        lo[a] = INFINITY;
        hi[a] = -INFINITY;
    }
    for (size_t i = 0; i < n; i++)
        for (uint32_t a = 0; a < dims; a++) {
            lo[a] = fmin(lo[a], pos[dims * i + a]);
            hi[a] = fmax(hi[a], pos[dims * i + a]);
        }
    for (uint32_t a = 0; a < dims; a++)
        half = a == 0 ? hi[a] - lo[a] : fmax(half, hi[a] - lo[a]);
    half *= 0.5;
    half = half > 0 ? half * (1 + 1e-9) : 1.0;
    /* Answering queries costs far more than inserting, so the second thread,
     * which first inserts the first part, takes a little less than half.
     * One thread does it all in one go (no part inserted twice). Either way
     * query i meets the tree of points 0..i-1 built in that order, so the
     * profile does not depend on the split. */
    size_t mid = n < 4096 || emm_threads_jobs(threads) < 2 ? n : n / 2 + n / 50;
    struct fast_job jobs[2] = {
        {.pos = pos, .dims = dims, .n = n, .lo = 0, .hi = mid, .theta = theta, .D = D,
         .half = half},
        {.pos = pos, .dims = dims, .n = n, .lo = mid, .hi = n, .theta = theta, .D = D,
         .half = half},
    };
    for (uint32_t a = 0; a < dims; a++)
        jobs[0].b[a] = jobs[1].b[a] = 0.5 * (lo[a] + hi[a]);
    emm_pool *pool = mid < n ? emm_pool_new(threads, 2) : NULL;
    emm_pool_for(pool, mid < n ? 2 : 1, fast_run, jobs);
    emm_pool_free(pool);
    if (!jobs[0].ok || (mid < n && !jobs[1].ok))
        return emm_fail(err, EMM_ERR_NOMEM, "%zu accesses: out of memory for the profile's tree", n);
    return EMM_OK;
}

emm_status emm_profile_compute(const double *pos, size_t n, uint32_t dims, double *D, int *exact,
                               const emm_threads *threads, emm_error *err)
{
    if (n <= EMM_PROFILE_EXACT_MAX) {
        emm_profile_exact(pos, n, dims, D, threads);
        if (exact)
            *exact = 1;
        return EMM_OK;
    }
    if (exact)
        *exact = 0;
    return emm_profile_fast(pos, n, dims, EMM_PROFILE_THETA, D, threads, err);
}

/* ---- positions of element accesses -------------------------------------- */

struct emm_profiler {
    const emm_trace_info *info;
    char name[256];
    uint64_t window;
    uint32_t dims;               /* coordinates a position: 2 or 3 */
    int axes[EMM_MAX_DIMS];      /* the axes kept, ascending */
    double lo[EMM_MAX_DIMS], scale; /* position = (coordinate − lo) · scale */
    double *pos;                 /* dims coordinates a position */
    size_t n, cap;
    uint32_t last_array;
    uint64_t last_element;
    bool any;
    lead_sweep sweep;
    size_t records;       /* records added and read */
    size_t sweep_records; /* of them, the leading sweep's */
    double first[EMM_MAX_DIMS]; /* the sweep's first position, given back if it stays alone */
    size_t first_record;
    uint32_t first_array;        /* and its element */
    uint64_t first_element;
    window_fill fill;            /* reading on until the window fills the store */
};

emm_status emm_profiler_new(const emm_trace_info *info, uint64_t window, uint32_t dims,
                            const char *name, emm_profiler **out, emm_error *err)
{
    const emm_trace_geometry *g = &info->geometry;
    assert(dims == 2 || dims == 3);
    *out = NULL;
    bool positional = false;
    for (uint32_t a = 0; a < info->narrays; a++) {
        if (info->arrays[a].kind == EMM_ARRAY_VERTICES && g->nv > 0)
            positional = true;
        if (info->arrays[a].kind == EMM_ARRAY_TRIANGLES && g->nt > 0 && g->nv > 0)
            positional = true;
    }
    if (!positional)
        return emm_fail(err, EMM_ERR_UNSUPPORTED,
                        "%s: an address-only trace (no vertex or triangle array with geometry) "
                        "has no positions to profile",
                        name);
    emm_profiler *p = calloc(1, sizeof *p);
    if (!p)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", name);
    p->info = info;
    snprintf(p->name, sizeof p->name, "%s", name);
    p->window = window ? window : EMM_PROFILE_DEFAULT_WINDOW;
    p->dims = dims;

    /* In the plane, that of the two largest extents, as the synthetic
     * patterns and the layouts see the mesh; in space, x, y and z. Scaled by
     * the bounding box's diagonal over the axes kept. */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint64_t v = 0; v < g->nv; v++)
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], g->xyz[3 * v + a]);
            hi[a] = fmax(hi[a], g->xyz[3 * v + a]);
        }
    emm_axes_largest(lo, hi, dims, p->axes);
    double diag = 0;
    for (uint32_t k = 0; k < dims; k++) {
        p->lo[k] = lo[p->axes[k]];
        diag = k == 0 ? hi[p->axes[k]] - lo[p->axes[k]]
                      : hypot(diag, hi[p->axes[k]] - lo[p->axes[k]]);
    }
    p->scale = diag > 0 && isfinite(diag) ? 1.0 / diag : 1.0;
    *out = p;
    return EMM_OK;
}

uint32_t emm_profiler_dims(const emm_profiler *p)
{
    return p->dims;
}

void emm_profiler_fill(emm_profiler *p, uint64_t bytes)
{
    window_fill_start(&p->fill, bytes);
    uint64_t mesh = 0;
    for (uint32_t a = 0; a < p->info->narrays; a++)
        if (p->info->arrays[a].kind != EMM_ARRAY_RAW)
            mesh += p->info->arrays[a].count * p->info->arrays[a].record_size;
    window_fill_size(&p->fill, mesh);
}

static bool profiler_full(const emm_profiler *p)
{
    return window_fill_done(&p->fill, p->window, p->n);
}

static bool profiler_push(emm_profiler *p, const double *x, uint32_t array, uint64_t element)
{
    if (p->n == p->cap) {
        size_t cap = p->cap ? 2 * p->cap : 4096;
        uint64_t most = p->fill.bytes ? emm_profile_fill_most(p->window) : p->window;
        if (cap > most)
            cap = (size_t)most;
        double *npos = realloc(p->pos, p->dims * cap * sizeof *npos);
        if (!npos)
            return false;
        p->pos = npos;
        p->cap = cap;
    }
    for (uint32_t k = 0; k < p->dims; k++)
        p->pos[p->dims * p->n + k] = (x[k] - p->lo[k]) * p->scale;
    p->n++;
    window_fill_add(&p->fill, array, element, p->info->arrays[array].record_size);
    return true;
}

void profiler_keep_sweep(emm_profiler *p)
{
    p->sweep.over = true;
}

uint64_t emm_profiler_swept(const emm_profiler *p, size_t *records)
{
    if (records)
        *records = p->n ? p->sweep_records : p->records;
    return p->sweep.elements;
}

emm_status emm_profiler_add(emm_profiler *p, const emm_trace_record *recs, size_t n,
                            emm_error *err)
{
    const emm_trace_geometry *g = &p->info->geometry;
    for (size_t r = 0; r < n && !profiler_full(p); r++, p->records++) {
        const emm_trace_record *rec = &recs[r];
        if (rec->array >= p->info->narrays)
            return emm_fail(err, EMM_ERR_FORMAT, "%s: a record names array %u of %u", p->name,
                            rec->array, p->info->narrays);
        emm_array_kind kind = p->info->arrays[rec->array].kind;
        /* The profile is of reads: the mesh is frozen once loaded (thesis
         * §5), and a loader's writes are not the traversal. */
        if (kind == EMM_ARRAY_RAW || rec->write)
            continue;
        if (p->any && rec->array == p->last_array && rec->element == p->last_element)
            continue;
        p->any = true;
        p->last_array = rec->array;
        p->last_element = rec->element;
        double x[EMM_MAX_DIMS] = {0};
        if (kind == EMM_ARRAY_VERTICES) {
            if (rec->element >= g->nv)
                return emm_fail(err, EMM_ERR_FORMAT,
                                "%s: access to vertex %llu, but the geometry has %llu vertices",
                                p->name, (unsigned long long)rec->element,
                                (unsigned long long)g->nv);
            for (uint32_t k = 0; k < p->dims; k++)
                x[k] = g->xyz[3 * rec->element + (uint64_t)p->axes[k]];
        } else {
            if (rec->element >= g->nt)
                return emm_fail(err, EMM_ERR_FORMAT,
                                "%s: access to triangle %llu, but the geometry has %llu triangles",
                                p->name, (unsigned long long)rec->element,
                                (unsigned long long)g->nt);
            for (int c = 0; c < 3; c++) {
                int32_t v = g->tri[3 * rec->element + c];
                if (v < 0 || (uint64_t)v >= g->nv)
                    return emm_fail(err, EMM_ERR_FORMAT,
                                    "%s: triangle %llu has vertex %d, outside the geometry",
                                    p->name, (unsigned long long)rec->element, v);
                for (uint32_t k = 0; k < p->dims; k++)
                    x[k] += g->xyz[3 * (uint64_t)v + (uint64_t)p->axes[k]];
            }
            for (uint32_t k = 0; k < p->dims; k++)
                x[k] /= 3;
        }
        int enter = lead_sweep_step(&p->sweep, rec->array, rec->element);
        if (enter == 0) {
            if (p->sweep.elements == 1) {
                memcpy(p->first, x, sizeof p->first);
                p->first_record = p->records;
                p->first_array = rec->array;
                p->first_element = rec->element;
            }
            continue;
        }
        if (p->n == 0)
            p->sweep_records = enter == 2 ? p->first_record : p->records;
        if (enter == 2 && !profiler_push(p, p->first, p->first_array, p->first_element))
            return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the profile window",
                            p->name);
        if (profiler_full(p))
            break;
        if (!profiler_push(p, x, rec->array, rec->element))
            return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the profile window",
                            p->name);
    }
    return EMM_OK;
}

int emm_profiler_full(const emm_profiler *p)
{
    return profiler_full(p);
}

const double *emm_profiler_positions(const emm_profiler *p, size_t *n)
{
    *n = p->n;
    return p->pos;
}

void emm_profiler_free(emm_profiler *p)
{
    if (p) {
        window_fill_free(&p->fill);
        free(p->pos);
        free(p);
    }
}

emm_status emm_profile_trace_positions(emm_trace_reader *r, uint64_t window, uint32_t dims,
                                       const char *name, double **pos, size_t *n, emm_error *err)
{
    emm_profiler *p;
    *pos = NULL;
    *n = 0;
    emm_status st = emm_trace_rewind(r, err);
    if (st == EMM_OK)
        st = emm_profiler_new(emm_trace_reader_info(r), window, dims, name, &p, err);
    if (st != EMM_OK)
        return st;
    enum { CHUNK = 4096 };
    emm_trace_record *buf = malloc(CHUNK * sizeof *buf);
    if (!buf) {
        emm_profiler_free(p);
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", name);
    }
    size_t got;
    while (st == EMM_OK && !emm_profiler_full(p)) {
        st = emm_trace_read(r, buf, CHUNK, &got, err);
        if (st != EMM_OK || got == 0)
            break;
        st = emm_profiler_add(p, buf, got, err);
    }
    free(buf);
    if (st == EMM_OK) {
        *pos = p->pos;
        *n = p->n;
        p->pos = NULL;
    }
    emm_profiler_free(p);
    return st;
}

emm_status emm_profile_trace_window(emm_trace_reader *r, uint64_t window, const char *name,
                                    emm_trace_record **recs, size_t *n, emm_error *err)
{
    return emm_profile_trace_window_fill(r, window, 0, name, recs, n, NULL, err);
}

emm_status emm_profile_trace_window_fill(emm_trace_reader *r, uint64_t window, uint64_t fill,
                                         const char *name, emm_trace_record **recs, size_t *n,
                                         size_t *length, emm_error *err)
{
    size_t reached = 0;
    emm_profiler *p;
    *recs = NULL;
    *n = 0;
    emm_status st = emm_trace_rewind(r, err);
    /* The profiler only counts the window's element accesses here, which
     * its positions' dimension does not change. */
    if (st == EMM_OK)
        st = emm_profiler_new(emm_trace_reader_info(r), window, EMM_PROFILE_PLANE, name, &p, err);
    if (st != EMM_OK)
        return st;
    emm_profiler_fill(p, fill);
    enum { CHUNK = 4096 };
    emm_trace_record *buf = NULL;
    size_t len = 0, cap = 0, got;
    while (st == EMM_OK && !emm_profiler_full(p)) {
        if (cap - len < CHUNK) {
            size_t ncap = cap ? 2 * cap : 4 * CHUNK;
            emm_trace_record *nb = realloc(buf, ncap * sizeof *nb);
            if (!nb) {
                st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the window", name);
                break;
            }
            buf = nb;
            cap = ncap;
        }
        /* One record at a time once close, so the window ends exactly where
         * the profiler fills. */
        size_t want = CHUNK;
        size_t have;
        emm_profiler_positions(p, &have);
        if (have + CHUNK > p->window)
            want = 1;
        st = emm_trace_read(r, buf + len, want, &got, err);
        if (st != EMM_OK || got == 0)
            break;
        st = emm_profiler_add(p, buf + len, got, err);
        len += got;
        emm_profiler_positions(p, &have);
        if (!reached && have >= p->window)
            reached = len;
    }
    emm_profiler_free(p);
    if (st != EMM_OK) {
        free(buf);
        return st;
    }
    *recs = buf;
    *n = len;
    if (length)
        *length = reached ? reached : len;
    return EMM_OK;
}

/* ---- features ----------------------------------------------------------- */

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Sorts v[0..n) ascending. The profile's values are non-negative: their
 * bit patterns sort as unsigned integers, so a radix sort gives the same
 * order as qsort, several times faster; short runs are sorted by insertion
 * (the running median's nine values), anything else by qsort. */
static void sort_doubles(double *v, size_t n)
{
    if (n <= 16) {
        for (size_t i = 1; i < n; i++) {
            double x = v[i];
            size_t j = i;
            for (; j > 0 && v[j - 1] > x; j--)
                v[j] = v[j - 1];
            v[j] = x;
        }
        return;
    }
    bool plain = true;
    for (size_t i = 0; i < n && plain; i++)
        plain = v[i] >= 0 && !signbit(v[i]);
    uint64_t *a = plain ? malloc(2 * n * sizeof *a) : NULL;
    if (!a) {
        qsort(v, n, sizeof *v, cmp_double);
        return;
    }
    uint64_t *b = a + n;
    memcpy(a, v, n * sizeof *a);
    for (int shift = 0; shift < 64; shift += 8) {
        size_t count[257] = {0};
        for (size_t i = 0; i < n; i++)
            count[((a[i] >> shift) & 0xff) + 1]++;
        if (count[((a[0] >> shift) & 0xff) + 1] == n)
            continue; /* every key has this byte: the pass would not move anything */
        for (int d = 0; d < 256; d++)
            count[d + 1] += count[d];
        for (size_t i = 0; i < n; i++)
            b[count[(a[i] >> shift) & 0xff]++] = a[i];
        uint64_t *t = a;
        a = b;
        b = t;
    }
    memcpy(v, a, n * sizeof *v);
    free(a < b ? a : b);
}

/* v[k] of v[lo..hi) once sorted — the same value sort_doubles would put
 * there — with [lo, k) not above it and (k, hi) not below (reorders v).
 * Quickselect on non-negative values (the profile's: comparing them is
 * comparing their bits, as the sort does), which runs in time linear in
 * hi - lo; anything else, or a range that keeps splitting badly, is
 * sorted. */
static double select_kth(double *v, size_t lo, size_t hi, size_t k)
{
    for (size_t i = lo; i < hi && hi - lo > 16; i++)
        if (!(v[i] >= 0) || signbit(v[i])) {
            sort_doubles(v + lo, hi - lo);
            return v[k];
        }
    for (unsigned rounds = 0; hi - lo > 16; rounds++) {
        if (rounds > 64) {
            sort_doubles(v + lo, hi - lo);
            return v[k];
        }
        /* The median of the first, middle and last as the pivot. */
        double a = v[lo], b = v[lo + (hi - lo) / 2], c = v[hi - 1];
        double p = a < b ? (b < c ? b : (a < c ? c : a)) : (a < c ? a : (b < c ? c : b));
        size_t i = lo, j = hi - 1;
        for (;;) { /* Hoare's partition: [lo, i) <= p, (j, hi) >= p */
            while (v[i] < p)
                i++;
            while (v[j] > p)
                j--;
            if (i >= j)
                break;
            double t = v[i];
            v[i++] = v[j];
            v[j--] = t;
        }
        if (k <= j)
            hi = j + 1;
        else
            lo = j + 1;
    }
    sort_doubles(v + lo, hi - lo);
    return v[k];
}

/* The q-quantile of v[0..n) (reorders v). */
static double quantile(double *v, size_t n, double q)
{
    if (n == 0)
        return 0;
    size_t k = (size_t)(q * (double)(n - 1) + 0.5);
    return select_kth(v, 0, n, k < n ? k : n - 1);
}

/* Mean of m_i = D_i / i over [a, b). */
static double mean_m(const double *D, size_t a, size_t b)
{
    double s = 0;
    if (a < 1)
        a = 1;
    if (b <= a)
        b = a + 1;
    for (size_t i = a; i < b; i++)
        s += D[i] / (double)i;
    return s / (double)(b - a);
}

/* Least-squares line through (x, y); returns the slope and the RMS residual. */
static void fit_line(const double *x, const double *y, size_t n, double *slope, double *rms)
{
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (size_t i = 0; i < n; i++) {
        sx += x[i];
        sy += y[i];
        sxx += x[i] * x[i];
        sxy += x[i] * y[i];
    }
    double den = (double)n * sxx - sx * sx;
    double b = den > 0 ? ((double)n * sxy - sx * sy) / den : 0;
    double a = (sy - b * sx) / (double)n;
    double r = 0;
    for (size_t i = 0; i < n; i++) {
        double e = y[i] - (a + b * x[i]);
        r += e * e;
    }
    *slope = b;
    *rms = n ? sqrt(r / (double)n) : 0;
}

/* Segment medians of log m over [a, b): nseg segments, their centres in lx. */
static size_t segment_medians(const double *D, size_t a, size_t b, size_t nseg, double *tmp,
                              double *lx, double *ly)
{
    size_t len = (b - a) / nseg, k = 0;
    if (len < 1)
        return 0;
    for (size_t s = 0; s < nseg; s++) {
        size_t lo = a + s * len, c = 0;
        for (size_t i = lo; i < lo + len; i++)
            if (i > 0 && D[i] > 0)
                tmp[c++] = D[i] / (double)i;
        if (c == 0)
            continue;
        lx[k] = log((double)lo + 0.5 * (double)len);
        ly[k] = log(quantile(tmp, c, 0.5));
        k++;
    }
    return k;
}

#define NSEG 64
#define NZ 512

static double periodicity(const double *D, size_t a, size_t n, double *tmp)
{
    double lx[NZ], z[NZ], slope, rms;
    size_t nz = segment_medians(D, a, n, n - a < NZ ? n - a : NZ, tmp, lx, z);
    if (nz < 16)
        return 0;
    (void)slope;
    (void)rms;
    /* Differences remove any slow trend, whatever its shape. */
    for (size_t i = 0; i + 1 < nz; i++)
        z[i] = z[i + 1] - z[i];
    nz--;
    double mean = 0, var = 0;
    for (size_t i = 0; i < nz; i++)
        mean += z[i];
    mean /= (double)nz;
    for (size_t i = 0; i < nz; i++) {
        z[i] -= mean;
        var += z[i] * z[i];
    }
    if (!(var > 0))
        return 0;
    double best = 0;
    bool crossed = false;
    for (size_t lag = 1; lag <= nz / 2; lag++) {
        double s = 0;
        for (size_t i = 0; i + lag < nz; i++)
            s += z[i] * z[i + lag];
        double rho = s / var * (double)nz / (double)(nz - lag);
        if (rho < 0)
            crossed = true;
        else if (crossed && rho > best)
            best = rho;
    }
    return fmin(best, 1.0);
}

emm_status emm_profile_features(const double *D, size_t n, const char *name,
                                double f[EMM_FEATURES], emm_error *err)
{
    if (n < EMM_PROFILE_MIN)
        return emm_fail(err, EMM_ERR_RANGE,
                        "%s: a profile of %zu accesses is too short for features (at least %u)",
                        name, n, EMM_PROFILE_MIN);
    double *tmp = malloc(n * sizeof *tmp);
    double *sm = malloc(n * sizeof *sm);
    if (!tmp || !sm) {
        free(tmp);
        free(sm);
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for features", name);
    }
    int k = 0;
    size_t a = n / 8;

    /* Jitter: relative change of m over 4 accesses (about one triangle visit
     * with its vertices). Large for random access, small for local walks. */
    size_t c = 0;
    for (size_t i = a; i + 4 < n; i++) {
        double m0 = D[i] / (double)i, m1 = D[i + 4] / (double)(i + 4);
        if (m0 > 0)
            tmp[c++] = fabs(m1 - m0) / m0;
    }
    double med = quantile(tmp, c, 0.5), p90 = 0;
    if (c) {
        /* The median leaves the larger half above it: the 90th is there. */
        size_t k50 = (size_t)(0.5 * (double)(c - 1) + 0.5), k90 = (size_t)(0.9 * (double)(c - 1));
        p90 = k90 > k50 ? select_kth(tmp, k50 + 1, c, k90)
              : k90 < k50 ? select_kth(tmp, 0, k50, k90)
                          : med;
    }
    f[k++] = 0.5 * log10(fmax(med, 1e-5));
    f[k++] = 0.5 * log10(fmax(p90, 1e-5));

    /* Trend and oscillation of the segment medians, on a log-log scale. */
    double lx[NSEG], ly[NSEG], slope, rms;
    size_t ns = segment_medians(D, a, n, NSEG, tmp, lx, ly);
    fit_line(lx, ly, ns, &slope, &rms);
    f[k++] = slope;
    f[k++] = 2 * rms;
    size_t ns2 = segment_medians(D, n / 64 > 0 ? n / 64 : 1, a, NSEG / 2, tmp, lx, ly);
    double slope2, rms2;
    fit_line(lx, ly, ns2, &slope2, &rms2);
    f[k++] = slope2;
    f[k++] = 2 * rms2;

    /* Jumps against glides: m smoothed by a running median of 9, then the share
     * of its total variation that happens in steps of more than 5%. Curves
     * start anew with a jump; scan lines and growing regions glide. */
    for (size_t i = 0; i < n; i++) {
        size_t lo = i >= 4 ? i - 4 : 0, hi = i + 5 < n ? i + 5 : n, w = 0;
        double win[9];
        for (size_t j = lo; j < hi; j++)
            win[w++] = j ? D[j] / (double)j : 0;
        sm[i] = quantile(win, w, 0.5);
    }
    double tv = 0, jv = 0;
    size_t steps = 0, big = 0;
    for (size_t i = a; i + 4 < n; i += 4) {
        double d = fabs(sm[i + 4] - sm[i]);
        tv += d;
        steps++;
        if (d > 0.05 * sm[i]) {
            jv += d;
            big++;
        }
    }
    f[k++] = tv > 0 ? jv / tv : 0;
    f[k++] = steps ? sqrt((double)big / (double)steps) : 0;

    /* Level: the end value, in bounding-box diagonals. */
    double end = mean_m(D, n - n / 32, n);
    f[k++] = 0.5 * log10(fmax(end, 1e-6));

    /* Periodicity: scan lines repeat one row after another, walks of curves
     * vary in length. The highest autocorrelation of the detrended log m
     * (in NZ segment medians) past its first zero crossing. */
    f[k++] = periodicity(D, a, n, tmp);

    /* Shape: log2 of m at n/64 ... n/2 against its end value. */
    for (int j = 6; j >= 1; j--) {
        size_t cc = n >> j, w = cc / 16 + 1;
        double mj = mean_m(D, cc > w ? cc - w : 1, cc + w);
        f[k++] = 0.125 * log2(fmax(mj, 1e-12) / fmax(end, 1e-12));
    }
    /* Locality across scales (thesis Fig. 5.3): how the typical change of m
     * over a lag of L accesses grows with L, as an exponent between lags 4,
     * 16, 64 and 256. m_i follows the mean-distance function of the earlier
     * accesses at p_i, which changes slowly, so |m_{i+L} − m_i| tracks how
     * far the traversal moves in L accesses. Hierarchical space-filling
     * orders (Z-order, Gray code, Hilbert: grouped by four at every level)
     * stay within a block of about √L cells: exponent ½ at every lag,
     * whatever the order within a group. Scan lines and curves sweep rows and
     * lines (exponent ≈ 1 below a row's length); random access does not
     * move in a measurable way (≈ 0); region growing depends on its
     * frontier. A lag too long for the window repeats the previous exponent. */
    static const size_t lag[] = {4, 16, 64, 256};
    double prev = 0, alpha = 0.5;
    for (int l = 0; l < 4; l++) {
        size_t cc = 0;
        if (n - a > lag[l] + 64)
            for (size_t i = a; i + lag[l] < n; i++) {
                double m0 = D[i] / (double)i, m1 = D[i + lag[l]] / (double)(i + lag[l]);
                if (m0 > 0)
                    tmp[cc++] = fabs(m1 - m0) / m0;
            }
        double s = cc ? fmax(quantile(tmp, cc, 0.5), 1e-12) : 0;
        if (l > 0) {
            if (s > 0 && prev > 0)
                alpha = log(s / prev) / log((double)lag[l] / (double)lag[l - 1]);
            f[k++] = alpha;
        }
        prev = s;
    }
    free(tmp);
    free(sm);
    return EMM_OK;
}
