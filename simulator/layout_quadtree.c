/* The adaptive quadtree layout (thesis §4.1.3, after the octree of its
 * reference [32]).
 *
 * The thesis builds a full "raw" quadtree and then merges or subdivides
 * leaves until each holds at most `cell` triangles. Subdividing top-down
 * from the root while a node holds more than `cell` triangles gives the
 * same tree, so that is what is done: triangles are sorted by the Morton
 * code of their centroid, which makes every node's triangles one
 * contiguous run, and a split only searches that run for its children's
 * boundaries. Then the balance rule ("adjacent leaves differ by at most
 * three levels", which bounds what loading a leaf and its neighbours
 * costs) is enforced by splitting the shallower leaf of any pair that
 * breaks it, until none does. Leaves that share an edge or only a corner
 * count as adjacent, because convolution prefetching (§4.2.1) loads the
 * corner cells too. Centroids closer than the finest level's square
 * (EMM_LAYOUT_MAX_DEPTH) cannot be separated: such a leaf stays above
 * `cell` and is counted as overfull. */
#include "layout_internal.h"

#include <assert.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"

#define MAXD EMM_LAYOUT_MAX_DEPTH
#define FINEST (1u << MAXD)

/* A node. (ix, iy) is the node's square at its own depth: it spans
 * [ix, ix + 1) * 2^-depth of the bounding square in each axis. */
typedef struct qt_node {
    uint32_t ix, iy;
    uint32_t depth;
    int32_t child;  /* index of the first of 4 consecutive children; -1 for a leaf */
    uint32_t first; /* the node's triangles: [first, first + count) of the Morton order */
    uint32_t count;
    uint32_t cell;  /* leaf: its cell */
    uint64_t path;  /* child indices from the root, 2 bits per level */
} qt_node;

/* The layout's priv. */
typedef struct quadtree {
    qt_node *nodes;
    uint32_t nnodes;
    uint32_t *leaf_node;  /* ncells: each cell's leaf */
    double qlo[2], qside; /* the bounding square */
    uint32_t overfull;
} quadtree;

static quadtree *Q(const emm_layout *l)
{
    return l->priv;
}

typedef struct qt_build {
    emm_layout *l;
    quadtree *q;
    uint64_t *code;  /* Morton codes, sorted */
    uint32_t *id;    /* the triangle of each code */
    uint32_t cap;    /* nodes allocated */
    uint32_t *tmp;   /* touching leaves of one leaf */
    size_t ntmp, captmp;
    int oom;
} qt_build;

/* A coordinate of the layout's space on the finest level (clamped). */
static uint32_t quantise(const quadtree *t, int axis, double v)
{
    double q = (v - t->qlo[axis]) / t->qside * (double)FINEST;
    if (!(q >= 0))
        return 0;
    if (q >= (double)(FINEST - 1))
        return FINEST - 1;
    return (uint32_t)q;
}

/* Bits 0..23 of v to the even bits 0..46. */
static uint64_t spread(uint32_t v)
{
    uint64_t x = v;
    x = (x | (x << 16)) & 0x0000FFFF0000FFFFull;
    x = (x | (x << 8)) & 0x00FF00FF00FF00FFull;
    x = (x | (x << 4)) & 0x0F0F0F0F0F0F0F0Full;
    x = (x | (x << 2)) & 0x3333333333333333ull;
    x = (x | (x << 1)) & 0x5555555555555555ull;
    return x;
}

/* Stable LSD radix sort of (code, id) by code: 3 passes of 16 bits cover
 * the 48-bit codes. */
static int radix_sort(uint64_t *code, uint32_t *id, size_t n)
{
    uint64_t *c2 = malloc(n * sizeof *c2);
    uint32_t *i2 = malloc(n * sizeof *i2);
    size_t *count = malloc(65536 * sizeof *count);
    if (!c2 || !i2 || !count) {
        free(c2);
        free(i2);
        free(count);
        return -1;
    }
    for (int pass = 0; pass < 3; pass++) {
        int shift = 16 * pass;
        memset(count, 0, 65536 * sizeof *count);
        for (size_t i = 0; i < n; i++)
            count[(code[i] >> shift) & 0xFFFF]++;
        size_t sum = 0;
        for (size_t k = 0; k < 65536; k++) {
            size_t c = count[k];
            count[k] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++) {
            size_t o = count[(code[i] >> shift) & 0xFFFF]++;
            c2[o] = code[i];
            i2[o] = id[i];
        }
        memcpy(code, c2, n * sizeof *code);
        memcpy(id, i2, n * sizeof *id);
    }
    free(c2);
    free(i2);
    free(count);
    return 0;
}

/* Splits leaf i into 4 children; returns -1 when out of memory. */
static int split(qt_build *b, uint32_t i)
{
    quadtree *q = b->q;
    if (q->nnodes + 4 > b->cap) {
        uint32_t cap = b->cap * 2;
        qt_node *n = realloc(q->nodes, (size_t)cap * sizeof *n);
        if (!n)
            return -1;
        q->nodes = n;
        b->cap = cap;
    }
    qt_node p = q->nodes[i];
    assert(p.child < 0 && p.depth < MAXD);
    unsigned shift = 2 * (MAXD - 1 - p.depth);
    uint32_t start = p.first, end = p.first + p.count;
    uint32_t first = q->nnodes;
    for (uint32_t k = 0; k < 4; k++) {
        /* The first triangle whose digit at this level is above k. */
        uint32_t lo = start, hi = end;
        while (lo < hi) {
            uint32_t mid = lo + (hi - lo) / 2;
            if (((b->code[mid] >> shift) & 3u) <= k)
                lo = mid + 1;
            else
                hi = mid;
        }
        q->nodes[first + k] = (qt_node){
            .ix = 2 * p.ix + (k & 1u),
            .iy = 2 * p.iy + (k >> 1),
            .depth = p.depth + 1,
            .child = -1,
            .first = start,
            .count = lo - start,
            .cell = EMM_LAYOUT_NONE,
            .path = (p.path << 2) | k,
        };
        start = lo;
    }
    q->nodes[i].child = (int32_t)first;
    q->nnodes += 4;
    return 0;
}

static void tmp_push(qt_build *b, uint32_t v)
{
    if (b->ntmp == b->captmp) {
        size_t cap = b->captmp ? 2 * b->captmp : 64;
        uint32_t *t = realloc(b->tmp, cap * sizeof *t);
        if (!t) {
            b->oom = 1;
            return;
        }
        b->tmp = t;
        b->captmp = cap;
    }
    b->tmp[b->ntmp++] = v;
}

/* The leaves inside node i that touch the side (dx, dy) of i faces: a
 * neighbour to the left (dx = -1) touches with its right column, and so on. */
static void touching_inside(qt_build *b, uint32_t i, int dx, int dy)
{
    const qt_node *n = &b->q->nodes[i];
    if (n->child < 0) {
        tmp_push(b, i);
        return;
    }
    uint32_t child = (uint32_t)n->child;
    for (uint32_t k = 0; k < 4; k++) {
        int xb = (int)(k & 1u), yb = (int)(k >> 1);
        if ((dx == -1 && xb != 1) || (dx == 1 && xb != 0) || (dy == -1 && yb != 1) ||
            (dy == 1 && yb != 0))
            continue;
        touching_inside(b, child + k, dx, dy);
    }
}

/* The leaves that touch leaf i by an edge or a corner, into b->tmp (a
 * coarser leaf may appear more than once). */
static void touching(qt_build *b, uint32_t i)
{
    const quadtree *q = b->q;
    qt_node n = q->nodes[i];
    int64_t side = (int64_t)1 << n.depth;
    b->ntmp = 0;
    /* i's ancestors, anc[d] at depth d: a neighbour's square shares the
     * path from the root down to the deepest node that holds both, so
     * each descent below starts there instead of at the root. */
    uint32_t anc[MAXD + 1];
    anc[0] = 0;
    for (uint32_t d = 0; d < n.depth; d++) {
        unsigned bit = n.depth - 1 - d;
        uint32_t k = ((n.ix >> bit) & 1u) | (((n.iy >> bit) & 1u) << 1);
        anc[d + 1] = (uint32_t)q->nodes[anc[d]].child + k;
    }
    for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
            if (dx == 0 && dy == 0)
                continue;
            int64_t x = (int64_t)n.ix + dx, y = (int64_t)n.iy + dy;
            if (x < 0 || y < 0 || x >= side || y >= side)
                continue;
            /* Descend to the node of i's size at (x, y), or the leaf above
             * it, from the deepest ancestor of i that holds (x, y): the
             * levels above where the coordinates first differ. */
            uint64_t diff = ((uint64_t)x ^ n.ix) | ((uint64_t)y ^ n.iy);
            uint32_t low = 64u - (uint32_t)__builtin_clzll(diff);
            uint32_t j = anc[n.depth - low];
            for (uint32_t d = n.depth - low; d < n.depth && q->nodes[j].child >= 0; d++) {
                unsigned bit = n.depth - 1 - d;
                uint32_t k = (uint32_t)(((x >> bit) & 1) | (((y >> bit) & 1) << 1));
                j = (uint32_t)q->nodes[j].child + k;
            }
            if (q->nodes[j].depth < n.depth)
                tmp_push(b, j);
            else
                touching_inside(b, j, dx, dy);
        }
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

static int subdivide(qt_build *b)
{
    emm_layout *l = b->l;
    quadtree *q = b->q;
    uint32_t *stack = malloc(64 * sizeof *stack);
    size_t n = 0, cap = 64;
    if (!stack)
        return -1;
    stack[n++] = 0;
    while (n > 0) {
        uint32_t i = stack[--n];
        if (q->nodes[i].count <= l->opt.cell || q->nodes[i].depth >= MAXD)
            continue;
        if (split(b, i) < 0)
            goto fail;
        if (n + 4 > cap) {
            cap *= 2;
            uint32_t *s = realloc(stack, cap * sizeof *s);
            if (!s)
                goto fail;
            stack = s;
        }
        for (uint32_t k = 0; k < 4; k++)
            stack[n++] = (uint32_t)q->nodes[i].child + k;
    }
    free(stack);
    return 0;
fail:
    free(stack);
    return -1;
}

/* Splits the shallower of any two touching leaves more than
 * EMM_LAYOUT_MAX_LEVEL_GAP levels apart, until none are. A split can only
 * unbalance the split leaf's children and its coarser neighbours, so those
 * are what goes back on the work list. */
static int balance(qt_build *b)
{
    quadtree *q = b->q;
    size_t cap = (size_t)q->nnodes + 64, n = 0;
    uint32_t *work = malloc(cap * sizeof *work);
    if (!work)
        return -1;
    for (uint32_t i = 0; i < q->nnodes; i++)
        if (q->nodes[i].child < 0)
            work[n++] = i;
    while (n > 0) {
        uint32_t i = work[--n];
        if (q->nodes[i].child >= 0)
            continue;
        touching(b, i);
        if (b->oom)
            goto fail;
        uint32_t d = q->nodes[i].depth, deepest = 0;
        for (size_t k = 0; k < b->ntmp; k++)
            if (q->nodes[b->tmp[k]].depth > deepest)
                deepest = q->nodes[b->tmp[k]].depth;
        if (deepest <= d + EMM_LAYOUT_MAX_LEVEL_GAP)
            continue;
        if (split(b, i) < 0)
            goto fail;
        if (n + 4 + b->ntmp > cap) {
            cap = 2 * (n + 4 + b->ntmp);
            uint32_t *w = realloc(work, cap * sizeof *w);
            if (!w)
                goto fail;
            work = w;
        }
        for (size_t k = 0; k < b->ntmp; k++)
            if (q->nodes[b->tmp[k]].depth + EMM_LAYOUT_MAX_LEVEL_GAP < d + 1)
                work[n++] = b->tmp[k];
        for (uint32_t k = 0; k < 4; k++)
            work[n++] = (uint32_t)q->nodes[i].child + k;
    }
    free(work);
    return 0;
fail:
    free(work);
    return -1;
}

/* Cells in depth-first child order: the leaves' Morton order. */
static int number_leaves(qt_build *b)
{
    emm_layout *l = b->l;
    quadtree *q = b->q;
    uint32_t leaves = 0;
    for (uint32_t i = 0; i < q->nnodes; i++)
        leaves += q->nodes[i].child < 0;
    l->ncells = leaves;
    l->cells = calloc(leaves, sizeof *l->cells);
    q->leaf_node = malloc((size_t)leaves * sizeof *q->leaf_node);
    /* A depth-first stack holds at most 3 pending siblings per level. */
    uint32_t stack[4 * (MAXD + 1)];
    if (!l->cells || !q->leaf_node)
        return -1;
    size_t n = 0;
    uint32_t c = 0;
    stack[n++] = 0;
    while (n > 0) {
        uint32_t i = stack[--n];
        qt_node *node = &q->nodes[i];
        if (node->child >= 0) {
            for (int k = 3; k >= 0; k--)
                stack[n++] = (uint32_t)node->child + (uint32_t)k;
            continue;
        }
        node->cell = c;
        q->leaf_node[c] = i;
        emm_layout_cell *cell = &l->cells[c];
        double size = q->qside / (double)(1u << node->depth);
        cell->lo[0] = q->qlo[0] + node->ix * size;
        cell->lo[1] = q->qlo[1] + node->iy * size;
        cell->hi[0] = cell->lo[0] + size;
        cell->hi[1] = cell->lo[1] + size;
        cell->coord[0] = cell->coord[1] = -1;
        cell->depth = node->depth;
        cell->path = node->path;
        for (uint32_t k = node->first; k < node->first + node->count; k++)
            l->tri_cell[b->id[k]] = c;
        if (node->count > l->opt.cell)
            q->overfull++;
        c++;
    }
    return 0;
}

static int neighbors(qt_build *b)
{
    emm_layout *l = b->l;
    quadtree *q = b->q;
    size_t cap = (size_t)l->ncells * 8 + 16, n = 0;
    l->nb_start = malloc(((size_t)l->ncells + 1) * sizeof *l->nb_start);
    l->nb = malloc(cap * sizeof *l->nb);
    if (!l->nb_start || !l->nb)
        return -1;
    for (uint32_t c = 0; c < l->ncells; c++) {
        l->nb_start[c] = (uint32_t)n;
        touching(b, q->leaf_node[c]);
        if (b->oom)
            return -1;
        for (size_t k = 0; k < b->ntmp; k++)
            b->tmp[k] = q->nodes[b->tmp[k]].cell;
        if (b->ntmp > 1)
            qsort(b->tmp, b->ntmp, sizeof *b->tmp, cmp_u32);
        if (n + b->ntmp > UINT32_MAX)
            return -1;
        if (n + b->ntmp > cap) {
            cap = 2 * (n + b->ntmp);
            uint32_t *nb = realloc(l->nb, cap * sizeof *nb);
            if (!nb)
                return -1;
            l->nb = nb;
        }
        for (size_t k = 0; k < b->ntmp; k++)
            if (k == 0 || b->tmp[k] != b->tmp[k - 1])
                l->nb[n++] = b->tmp[k];
    }
    l->nb_start[l->ncells] = (uint32_t)n;
    return 0;
}

static emm_status build(emm_layout *l, const double *const *c, const char *name, emm_error *err)
{
    assert(l->dims == 2); /* a tree of squares: the ops declare 2 (an octree would be 3) */
    quadtree *q = calloc(1, sizeof *q);
    if (!q)
        return emm_layout_nomem(err, name);
    l->priv = q;
    qt_build b = {.l = l, .q = q};
    emm_status st = EMM_OK;
    double w = l->hi[0] - l->lo[0], h = l->hi[1] - l->lo[1];
    q->qside = w > h ? w : h;
    if (!(q->qside > 0))
        q->qside = 1; /* all centroids in one point: one leaf */
    q->qlo[0] = l->lo[0];
    q->qlo[1] = l->lo[1];

    b.code = malloc(l->nt * sizeof *b.code);
    b.id = malloc(l->nt * sizeof *b.id);
    b.cap = 1024;
    q->nodes = malloc(b.cap * sizeof *q->nodes);
    if (!b.code || !b.id || !q->nodes)
        goto oom;
    for (size_t t = 0; t < l->nt; t++) {
        b.code[t] = spread(quantise(q, 0, c[0][t])) | spread(quantise(q, 1, c[1][t])) << 1;
        b.id[t] = (uint32_t)t;
    }
    if (radix_sort(b.code, b.id, l->nt) < 0)
        goto oom;
    q->nodes[0] = (qt_node){0, 0, 0, -1, 0, (uint32_t)l->nt, EMM_LAYOUT_NONE, 0};
    q->nnodes = 1;
    if (subdivide(&b) < 0 || balance(&b) < 0 || number_leaves(&b) < 0 || neighbors(&b) < 0)
        goto oom;
    free(b.code);
    free(b.id);
    free(b.tmp);
    return emm_layout_fill_sides(l, name, err);
oom:
    st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory building the quadtree layout", name);
    free(b.code);
    free(b.id);
    free(b.tmp);
    return st;
}

static uint32_t cell_at(const emm_layout *l, const double *p, uint32_t *levels)
{
    const quadtree *q = Q(l);
    uint32_t qx = quantise(q, 0, p[0]), qy = quantise(q, 1, p[1]), i = 0;
    while (q->nodes[i].child >= 0) {
        unsigned bit = MAXD - 1 - q->nodes[i].depth;
        uint32_t k = ((qx >> bit) & 1u) | (((qy >> bit) & 1u) << 1);
        i = (uint32_t)q->nodes[i].child + k;
    }
    if (levels)
        *levels = q->nodes[i].depth;
    return q->nodes[i].cell;
}

/* Leaf squares in units of the finest level, exact: a side bit when `to`
 * lies wholly beyond that edge of `from`. */
static unsigned move_side(const emm_layout *l, uint32_t from, uint32_t to)
{
    const quadtree *q = Q(l);
    const qt_node *na = &q->nodes[q->leaf_node[from]], *nb = &q->nodes[q->leaf_node[to]];
    uint32_t sa = MAXD - na->depth, sb = MAXD - nb->depth;
    uint64_t a0[2] = {(uint64_t)na->ix << sa, (uint64_t)na->iy << sa};
    uint64_t a1[2] = {(uint64_t)(na->ix + 1) << sa, (uint64_t)(na->iy + 1) << sa};
    uint64_t b0[2] = {(uint64_t)nb->ix << sb, (uint64_t)nb->iy << sb};
    uint64_t b1[2] = {(uint64_t)(nb->ix + 1) << sb, (uint64_t)(nb->iy + 1) << sb};
    unsigned s = 0;
    for (int a = 0; a < 2; a++) {
        if (b1[a] <= a0[a])
            s |= EMM_SIDE_MINUS(a);
        if (b0[a] >= a1[a])
            s |= EMM_SIDE_PLUS(a);
    }
    return s;
}

/* The look-ups descend the tree: 16 bytes per node in the local store. */
static uint64_t lookup_bytes(const emm_layout *l)
{
    return 16 * (uint64_t)Q(l)->nnodes;
}

/* The nodes from the root down to cell c's leaf, by the leaf's path. */
static uint32_t path_nodes(const emm_layout *l, uint32_t c, uint32_t *nodes)
{
    const quadtree *t = Q(l);
    const emm_layout_cell *cell = &l->cells[c];
    uint32_t i = 0, n = 0;
    nodes[n++] = 0;
    for (uint32_t d = cell->depth; d > 0; d--) {
        i = (uint32_t)t->nodes[i].child + (uint32_t)((cell->path >> (2 * (d - 1))) & 3u);
        nodes[n++] = i;
    }
    return n;
}

static void stats(const emm_layout *l, emm_layout_stats *out)
{
    out->quadtree_nodes = Q(l)->nnodes;
    out->overfull_leaves = Q(l)->overfull;
}

static void destroy(emm_layout *l)
{
    quadtree *q = Q(l);
    if (q) {
        free(q->nodes);
        free(q->leaf_node);
        free(q);
    }
}

const struct emm_layout_ops emm_layout_quadtree_ops = {
    .dims = 2,
    .build = build,
    .move_side = move_side,
    .cell_at = cell_at,
    .lookup_bytes = lookup_bytes,
    .path_nodes = path_nodes,
    .stats = stats,
    .destroy = destroy,
    .bounded = 1,
};
