/* The adaptive octree layout: the quadtree of thesis §4.1.3 in space (the
 * octree of its reference [32]), for a mesh with depth.
 *
 * As for the quadtree (layout_quadtree.c), triangles are sorted by the
 * Morton code of their centroid in the bounding cube, so that every node's
 * triangles are one contiguous run; a node is split into its 8 octants
 * while it holds more than `cell` triangles. Then the balance rule: leaves
 * that share a face differ by at most EMM_LAYOUT_OCTREE_LEVEL_GAP (1) level
 * (the 2:1 rule of octree meshing), enforced by splitting the shallower
 * leaf of any pair that breaks it until none does; it bounds the leaves a
 * face can touch to 4. The neighbour lists the fetch schemes read hold
 * every leaf that touches by a face, an edge or a corner. Centroids closer
 * than the finest level's cube (EMM_LAYOUT_OCTREE_MAX_DEPTH) stay in one
 * leaf, counted as overfull. */
#include "layout_internal.h"

#include <assert.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"

#define MAXD EMM_LAYOUT_OCTREE_MAX_DEPTH
#define FINEST (1u << MAXD)
#define GAP EMM_LAYOUT_OCTREE_LEVEL_GAP

/* A node: (i[0], i[1], i[2]) is its cube at its own depth. */
typedef struct oc_node {
    uint32_t i[3];
    uint32_t depth;
    int32_t child;  /* the first of 8 consecutive children; -1 for a leaf */
    uint32_t first; /* the node's triangles: [first, first + count) of the Morton order */
    uint32_t count;
    uint32_t cell;  /* leaf: its cell */
    uint64_t path;  /* child indices from the root, 3 bits per level */
} oc_node;

typedef struct octree {
    oc_node *nodes;
    uint32_t nnodes;
    uint32_t *leaf_node; /* ncells: each cell's leaf */
    double olo[3], oside; /* the bounding cube */
    uint32_t overfull;
} octree;

static octree *O(const emm_layout *l)
{
    return l->priv;
}

typedef struct oc_build {
    emm_layout *l;
    octree *o;
    uint64_t *code;
    uint32_t *id;
    uint32_t cap;
    uint32_t *tmp; /* touching leaves of one leaf */
    size_t ntmp, captmp;
    int oom;
} oc_build;

static uint32_t quantise(const octree *t, int axis, double v)
{
    double q = (v - t->olo[axis]) / t->oside * (double)FINEST;
    if (!(q >= 0))
        return 0;
    if (q >= (double)(FINEST - 1))
        return FINEST - 1;
    return (uint32_t)q;
}

/* Bits 0..20 of v to every third bit 0..60. */
static uint64_t spread3(uint32_t v)
{
    uint64_t x = v & 0x1FFFFFu;
    x = (x | x << 32) & 0x1F00000000FFFFull;
    x = (x | x << 16) & 0x1F0000FF0000FFull;
    x = (x | x << 8) & 0x100F00F00F00F00Full;
    x = (x | x << 4) & 0x10C30C30C30C30C3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
}

/* Stable LSD radix sort of (code, id) by code: 4 passes of 16 bits cover
 * the 63-bit codes. */
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
    for (int pass = 0; pass < 4; pass++) {
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

/* Splits leaf i into 8 children; -1 when out of memory. */
static int split(oc_build *b, uint32_t i)
{
    octree *o = b->o;
    if (o->nnodes + 8 > b->cap) {
        uint32_t cap = b->cap * 2;
        oc_node *n = realloc(o->nodes, (size_t)cap * sizeof *n);
        if (!n)
            return -1;
        o->nodes = n;
        b->cap = cap;
    }
    oc_node p = o->nodes[i];
    assert(p.child < 0 && p.depth < MAXD);
    unsigned shift = 3 * (MAXD - 1 - p.depth);
    uint32_t start = p.first, end = p.first + p.count, first = o->nnodes;
    for (uint32_t k = 0; k < 8; k++) {
        /* The first triangle whose digit at this level is above k. */
        uint32_t lo = start, hi = end;
        while (lo < hi) {
            uint32_t mid = lo + (hi - lo) / 2;
            if (((b->code[mid] >> shift) & 7u) <= k)
                lo = mid + 1;
            else
                hi = mid;
        }
        oc_node *c = &o->nodes[first + k];
        *c = (oc_node){.depth = p.depth + 1, .child = -1, .first = start, .count = lo - start,
                       .cell = EMM_LAYOUT_NONE, .path = (p.path << 3) | k};
        for (int a = 0; a < 3; a++)
            c->i[a] = 2 * p.i[a] + ((k >> a) & 1u);
        start = lo;
    }
    o->nodes[i].child = (int32_t)first;
    o->nnodes += 8;
    return 0;
}

static void tmp_push(oc_build *b, uint32_t v)
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

/* The leaves inside node i on its side that faces direction -d: a
 * neighbour at d = -1 along an axis touches with its upper half there. */
static void touching_inside(oc_build *b, uint32_t i, const int *d)
{
    const oc_node *n = &b->o->nodes[i];
    if (n->child < 0) {
        tmp_push(b, i);
        return;
    }
    uint32_t child = (uint32_t)n->child;
    for (uint32_t k = 0; k < 8; k++) {
        int ok = 1;
        for (int a = 0; a < 3; a++) {
            int bit = (int)((k >> a) & 1u);
            ok = ok && !(d[a] == -1 && bit != 1) && !(d[a] == 1 && bit != 0);
        }
        if (ok)
            touching_inside(b, child + k, d);
    }
}

/* The leaves that touch leaf i, into b->tmp (a coarser leaf may appear more
 * than once): by a face only, or by a face, an edge or a corner. */
static void touching(oc_build *b, uint32_t i, int faces_only)
{
    const octree *o = b->o;
    oc_node n = o->nodes[i];
    int64_t side = (int64_t)1 << n.depth;
    b->ntmp = 0;
    /* i's ancestors, anc[e] at depth e: a neighbour's box shares the path
     * from the root down to the deepest node that holds both, so each
     * descent below starts there instead of at the root. */
    uint32_t anc[MAXD + 1];
    anc[0] = 0;
    for (uint32_t e = 0; e < n.depth; e++) {
        unsigned bit = n.depth - 1 - e;
        uint32_t k = 0;
        for (int a = 0; a < 3; a++)
            k |= ((n.i[a] >> bit) & 1u) << a;
        anc[e + 1] = (uint32_t)o->nodes[anc[e]].child + k;
    }
    for (int dz = -1; dz <= 1; dz++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                int d[3] = {dx, dy, dz}, moved = (dx != 0) + (dy != 0) + (dz != 0);
                if (moved == 0 || (faces_only && moved != 1))
                    continue;
                int64_t p[3];
                int inside = 1;
                for (int a = 0; a < 3; a++) {
                    p[a] = (int64_t)n.i[a] + d[a];
                    inside = inside && p[a] >= 0 && p[a] < side;
                }
                if (!inside)
                    continue;
                /* Descend to the node of i's size at p, or the leaf above
                 * it, from the deepest ancestor of i that holds p: the
                 * levels above where the coordinates first differ. */
                uint64_t diff = 0;
                for (int a = 0; a < 3; a++)
                    diff |= (uint64_t)p[a] ^ n.i[a];
                uint32_t low = 64u - (uint32_t)__builtin_clzll(diff);
                uint32_t j = anc[n.depth - low];
                for (uint32_t e = n.depth - low; e < n.depth && o->nodes[j].child >= 0; e++) {
                    unsigned bit = n.depth - 1 - e;
                    uint32_t k = 0;
                    for (int a = 0; a < 3; a++)
                        k |= (uint32_t)((p[a] >> bit) & 1) << a;
                    j = (uint32_t)o->nodes[j].child + k;
                }
                if (o->nodes[j].depth < n.depth)
                    tmp_push(b, j);
                else
                    touching_inside(b, j, d);
            }
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

static int subdivide(oc_build *b)
{
    octree *o = b->o;
    size_t n = 0, cap = 64;
    uint32_t *stack = malloc(cap * sizeof *stack);
    if (!stack)
        return -1;
    stack[n++] = 0;
    while (n > 0) {
        uint32_t i = stack[--n];
        if (o->nodes[i].count <= b->l->opt.cell || o->nodes[i].depth >= MAXD)
            continue;
        if (split(b, i) < 0)
            goto fail;
        if (n + 8 > cap) {
            cap *= 2;
            uint32_t *s = realloc(stack, cap * sizeof *s);
            if (!s)
                goto fail;
            stack = s;
        }
        for (uint32_t k = 0; k < 8; k++)
            stack[n++] = (uint32_t)o->nodes[i].child + k;
    }
    free(stack);
    return 0;
fail:
    free(stack);
    return -1;
}

/* Splits the shallower of any two face-sharing leaves more than GAP levels
 * apart, until none are; a split can only unbalance the split leaf's
 * children and its coarser face neighbours, which go back on the list. */
static int balance(oc_build *b)
{
    octree *o = b->o;
    size_t cap = (size_t)o->nnodes + 64, n = 0;
    uint32_t *work = malloc(cap * sizeof *work);
    if (!work)
        return -1;
    for (uint32_t i = 0; i < o->nnodes; i++)
        if (o->nodes[i].child < 0)
            work[n++] = i;
    while (n > 0) {
        uint32_t i = work[--n];
        if (o->nodes[i].child >= 0)
            continue;
        touching(b, i, 1);
        if (b->oom)
            goto fail;
        uint32_t d = o->nodes[i].depth, deepest = 0;
        for (size_t k = 0; k < b->ntmp; k++)
            if (o->nodes[b->tmp[k]].depth > deepest)
                deepest = o->nodes[b->tmp[k]].depth;
        if (deepest <= d + GAP)
            continue;
        if (split(b, i) < 0)
            goto fail;
        if (n + 8 + b->ntmp > cap) {
            cap = 2 * (n + 8 + b->ntmp);
            uint32_t *w = realloc(work, cap * sizeof *w);
            if (!w)
                goto fail;
            work = w;
        }
        for (size_t k = 0; k < b->ntmp; k++)
            if (o->nodes[b->tmp[k]].depth + GAP < d + 1)
                work[n++] = b->tmp[k];
        for (uint32_t k = 0; k < 8; k++)
            work[n++] = (uint32_t)o->nodes[i].child + k;
    }
    free(work);
    return 0;
fail:
    free(work);
    return -1;
}

/* Cells in depth-first child order: the leaves' Morton order. */
static int number_leaves(oc_build *b)
{
    emm_layout *l = b->l;
    octree *o = b->o;
    uint32_t leaves = 0;
    for (uint32_t i = 0; i < o->nnodes; i++)
        leaves += o->nodes[i].child < 0;
    l->ncells = leaves;
    l->cells = calloc(leaves, sizeof *l->cells);
    o->leaf_node = malloc((size_t)leaves * sizeof *o->leaf_node);
    /* A depth-first stack holds at most 7 pending siblings per level. */
    uint32_t stack[8 * (MAXD + 1)];
    if (!l->cells || !o->leaf_node)
        return -1;
    size_t n = 0;
    uint32_t c = 0;
    stack[n++] = 0;
    while (n > 0) {
        uint32_t i = stack[--n];
        oc_node *node = &o->nodes[i];
        if (node->child >= 0) {
            for (int k = 7; k >= 0; k--)
                stack[n++] = (uint32_t)node->child + (uint32_t)k;
            continue;
        }
        node->cell = c;
        o->leaf_node[c] = i;
        emm_layout_cell *cell = &l->cells[c];
        double size = o->oside / (double)(1u << node->depth);
        for (int a = 0; a < 3; a++) {
            cell->lo[a] = o->olo[a] + node->i[a] * size;
            cell->hi[a] = cell->lo[a] + size;
            cell->coord[a] = -1;
        }
        cell->depth = node->depth;
        cell->path = node->path;
        for (uint32_t k = node->first; k < node->first + node->count; k++)
            l->tri_cell[b->id[k]] = c;
        if (node->count > l->opt.cell)
            o->overfull++;
        c++;
    }
    return 0;
}

/* A side bit when node nb's cube lies wholly beyond that face of na's, in
 * units of the finest level: exact. */
static unsigned node_side(const oc_node *na, const oc_node *nb)
{
    uint32_t sa = MAXD - na->depth, sb = MAXD - nb->depth;
    unsigned s = 0;
    for (int a = 0; a < 3; a++) {
        uint64_t a0 = (uint64_t)na->i[a] << sa, a1 = (uint64_t)(na->i[a] + 1) << sa;
        uint64_t b0 = (uint64_t)nb->i[a] << sb, b1 = (uint64_t)(nb->i[a] + 1) << sb;
        if (b1 <= a0)
            s |= EMM_SIDE_MINUS(a);
        if (b0 >= a1)
            s |= EMM_SIDE_PLUS(a);
    }
    return s;
}

static int neighbors(oc_build *b)
{
    emm_layout *l = b->l;
    octree *o = b->o;
    size_t cap = (size_t)l->ncells * 26 + 16, n = 0;
    l->nb_start = malloc(((size_t)l->ncells + 1) * sizeof *l->nb_start);
    l->nb = malloc(cap * sizeof *l->nb);
    if (!l->nb_start || !l->nb)
        return -1;
    for (uint32_t c = 0; c < l->ncells; c++) {
        l->nb_start[c] = (uint32_t)n;
        /* Leaves without triangles are dropped once the layout is cut
         * (layout.c): no list of their own, in no one's list. */
        if (o->nodes[o->leaf_node[c]].count == 0)
            continue;
        touching(b, o->leaf_node[c], 0);
        if (b->oom)
            return -1;
        size_t kept = 0;
        for (size_t k = 0; k < b->ntmp; k++)
            if (o->nodes[b->tmp[k]].count > 0)
                b->tmp[kept++] = o->nodes[b->tmp[k]].cell;
        b->ntmp = kept;
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
    assert(l->dims == 3); /* a tree of cubes: the ops declare 3 */
    octree *o = calloc(1, sizeof *o);
    if (!o)
        return emm_layout_nomem(err, name);
    l->priv = o;
    oc_build b = {.l = l, .o = o};
    emm_status st = EMM_OK;
    o->oside = 0;
    for (int a = 0; a < 3; a++) {
        double e = l->hi[a] - l->lo[a];
        o->oside = e > o->oside ? e : o->oside;
        o->olo[a] = l->lo[a];
    }
    if (!(o->oside > 0))
        o->oside = 1; /* all centroids in one point: one leaf */
    b.code = malloc(l->nt * sizeof *b.code);
    b.id = malloc(l->nt * sizeof *b.id);
    b.cap = 1024;
    o->nodes = malloc(b.cap * sizeof *o->nodes);
    if (!b.code || !b.id || !o->nodes)
        goto oom;
    for (size_t t = 0; t < l->nt; t++) {
        b.code[t] = spread3(quantise(o, 0, c[0][t])) | spread3(quantise(o, 1, c[1][t])) << 1 |
                    spread3(quantise(o, 2, c[2][t])) << 2;
        b.id[t] = (uint32_t)t;
    }
    if (radix_sort(b.code, b.id, l->nt) < 0)
        goto oom;
    o->nodes[0] = (oc_node){.child = -1, .count = (uint32_t)l->nt, .cell = EMM_LAYOUT_NONE};
    o->nnodes = 1;
    if (subdivide(&b) < 0 || balance(&b) < 0 || number_leaves(&b) < 0 || neighbors(&b) < 0)
        goto oom;
    free(b.code);
    free(b.id);
    free(b.tmp);
    /* The sides from the leaves' cubes, which the nodes hold: faster than
     * move_side's decoding of the paths, which serves after the empty
     * leaves are dropped. */
    l->nb_side = malloc((size_t)l->nb_start[l->ncells] + 1);
    if (!l->nb_side)
        return emm_layout_nomem(err, name);
    for (uint32_t cell = 0; cell < l->ncells; cell++)
        for (uint32_t k = l->nb_start[cell]; k < l->nb_start[cell + 1]; k++)
            l->nb_side[k] = (uint8_t)node_side(&o->nodes[o->leaf_node[cell]],
                                               &o->nodes[o->leaf_node[l->nb[k]]]);
    return EMM_OK;
oom:
    st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory building the octree layout", name);
    free(b.code);
    free(b.id);
    free(b.tmp);
    return st;
}

static uint32_t cell_at(const emm_layout *l, const double *p, uint32_t *levels)
{
    const octree *o = O(l);
    uint32_t q[3], i = 0;
    for (int a = 0; a < 3; a++)
        q[a] = quantise(o, a, p[a]);
    while (o->nodes[i].child >= 0) {
        unsigned bit = MAXD - 1 - o->nodes[i].depth;
        uint32_t k = 0;
        for (int a = 0; a < 3; a++)
            k |= ((q[a] >> bit) & 1u) << a;
        i = (uint32_t)o->nodes[i].child + k;
    }
    if (levels)
        *levels = o->nodes[i].depth;
    return o->nodes[i].cell;
}

/* A leaf's cube in units of the finest level, from its path: exact. */
static void leaf_cube(const emm_layout_cell *cell, uint64_t lo[3], uint64_t hi[3])
{
    uint64_t ix[3] = {0, 0, 0};
    for (uint32_t d = 0; d < cell->depth; d++) {
        uint64_t k = (cell->path >> (3 * (cell->depth - 1 - d))) & 7u;
        for (int a = 0; a < 3; a++)
            ix[a] = 2 * ix[a] + ((k >> a) & 1u);
    }
    uint32_t s = MAXD - cell->depth;
    for (int a = 0; a < 3; a++) {
        lo[a] = ix[a] << s;
        hi[a] = (ix[a] + 1) << s;
    }
}

/* Leaf cubes compared: a side bit when `to` lies wholly beyond that face
 * of `from`. From the cells' paths, as the leaves without triangles are
 * dropped after the build (layout.c). */
static unsigned move_side(const emm_layout *l, uint32_t from, uint32_t to)
{
    uint64_t a0[3], a1[3], b0[3], b1[3];
    leaf_cube(&l->cells[from], a0, a1);
    leaf_cube(&l->cells[to], b0, b1);
    unsigned s = 0;
    for (int a = 0; a < 3; a++) {
        if (b1[a] <= a0[a])
            s |= EMM_SIDE_MINUS(a);
        if (b0[a] >= a1[a])
            s |= EMM_SIDE_PLUS(a);
    }
    return s;
}

/* The look-ups descend the tree: 16 bytes per node in the local store, as
 * for the quadtree (the first child's index, the triangle run). */
static uint64_t lookup_bytes(const emm_layout *l)
{
    return 16 * (uint64_t)O(l)->nnodes;
}

/* The nodes from the root down to cell c's leaf, by the leaf's path. */
static uint32_t path_nodes(const emm_layout *l, uint32_t c, uint32_t *nodes)
{
    const octree *t = O(l);
    const emm_layout_cell *cell = &l->cells[c];
    uint32_t i = 0, n = 0;
    nodes[n++] = 0;
    for (uint32_t d = cell->depth; d > 0; d--) {
        i = (uint32_t)t->nodes[i].child + (uint32_t)((cell->path >> (3 * (d - 1))) & 7u);
        nodes[n++] = i;
    }
    return n;
}

static void stats(const emm_layout *l, emm_layout_stats *out)
{
    out->quadtree_nodes = O(l)->nnodes;
    out->overfull_leaves = O(l)->overfull;
}

static void destroy(emm_layout *l)
{
    octree *o = O(l);
    if (o) {
        free(o->nodes);
        free(o->leaf_node);
        free(o);
    }
}

const struct emm_layout_ops emm_layout_octree_ops = {
    .dims = 3,
    .build = build,
    .compact = 1,
    .move_side = move_side,
    .cell_at = cell_at,
    .lookup_bytes = lookup_bytes,
    .path_nodes = path_nodes,
    .stats = stats,
    .destroy = destroy,
    .bounded = 1,
};
