/* Layers of rows of equal boxes in space: the machinery the 3D grid
 * (layout_grid3d.c) and the 3D interleaving tiles (layout_tiles3d.c)
 * share, the rows of layout_rows.c carried up one axis. Cells are numbered
 * layer by layer (axis 2), row by row (axis 1), then along the row (axis 0),
 * from the low corner.
 *
 * Without `shift` the boxes form a plain 3D grid: up to 26 neighbours.
 * With it, each layer is a plane of interleaving tiles (odd rows shifted by
 * half a box along axis 0), and every odd layer is moved by half a row
 * along axis 1 and a quarter box along axis 0. Then no row boundary, and no
 * end of a box in a row, of one layer lies on one of the next layer's: a
 * box touches 2 boxes in its row, 2 in each neighbouring row of its layer
 * (6, as in the plane) and 2 x 2 in each neighbouring layer, 14 in all
 * (docs/layouts.md, "Layouts in space"). Odd rows and odd layers hold one
 * more box along axis 0 and odd layers one more row, so the shifted boxes
 * still cover the bounding box.
 *
 * The number of boxes: a mesh with depth is mostly a surface, which meets
 * few of the boxes that fill its bounding box; so the boxes are sized so
 * that those holding triangles hold CELL on average (the grid in the plane,
 * whose boxes a planar mesh fills, averages CELL over all of them). */
#include "layout_internal.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>

#include "error.h"

/* Most boxes tried. Only the boxes that hold triangles become cells; the
 * others cost a bit each while the layout is cut (128 MiB at the most). */
#define MAX_BOXES (1u << 30)

/* Boxes are numbered layer by layer, row by row ("raw" numbers, of every
 * box); the cells are the boxes that hold triangles, in that order. */
struct boxes {
    uint32_t n[3];   /* boxes along each axis of an even row of an even layer */
    double w[3];     /* a box's extent along each axis */
    int shift;
    uint32_t layer_cells[2]; /* boxes in an even, an odd layer */
    uint32_t *occ;   /* ncells: each cell's box, ascending */
};

static const struct boxes *B(const emm_layout *l)
{
    return l->priv;
}

static uint32_t clamp_index(double v, uint32_t n)
{
    if (!(v >= 0)) /* also NaN */
        return 0;
    if (v >= (double)n)
        return n - 1;
    return (uint32_t)v;
}

static uint32_t rows_in(const struct boxes *b, uint32_t k)
{
    return b->n[1] + (b->shift ? (k & 1u) : 0u);
}

static uint32_t row_len(const struct boxes *b, uint32_t j, uint32_t k)
{
    return b->n[0] + (b->shift ? ((j | k) & 1u) : 0u);
}

/* A box's low corner along axes 0 and 1, in quarter boxes relative to its
 * index: odd rows half a box back, odd layers a quarter more and half a
 * row back. */
static int64_t off4x(const struct boxes *b, uint32_t j, uint32_t k)
{
    return b->shift ? -(int64_t)(2 * (j & 1u) + (k & 1u)) : 0;
}

static int64_t off4y(const struct boxes *b, uint32_t k)
{
    return b->shift ? -(int64_t)(2 * (k & 1u)) : 0;
}

static uint32_t row_start(const struct boxes *b, uint32_t j, uint32_t k)
{
    if (!b->shift)
        return j * b->n[0];
    return (k & 1u) ? j * (b->n[0] + 1) : j * b->n[0] + j / 2;
}

static uint32_t layer_start(const struct boxes *b, uint32_t k)
{
    return (k / 2) * (b->layer_cells[0] + b->layer_cells[1]) + (k & 1u) * b->layer_cells[0];
}

static uint64_t count_cells(struct boxes *b)
{
    uint64_t n0 = b->n[0], n1 = b->n[1], n2 = b->n[2];
    if (!b->shift) {
        b->layer_cells[0] = b->layer_cells[1] = (uint32_t)(n0 * n1);
        return n0 * n1 * n2;
    }
    uint64_t even = n0 * n1 + n1 / 2, odd = (n0 + 1) * (n1 + 1);
    b->layer_cells[0] = (uint32_t)even;
    b->layer_cells[1] = (uint32_t)odd;
    return (n2 / 2) * (even + odd) + (n2 & 1u) * even;
}

static uint32_t box_at(const emm_layout *l, const struct boxes *b, const double *p)
{
    uint32_t k = clamp_index((p[2] - l->lo[2]) / b->w[2], b->n[2]);
    uint32_t j = clamp_index((p[1] - l->lo[1]) / b->w[1] - (double)off4y(b, k) / 4, rows_in(b, k));
    uint32_t i =
        clamp_index((p[0] - l->lo[0]) / b->w[0] - (double)off4x(b, j, k) / 4, row_len(b, j, k));
    return layer_start(b, k) + row_start(b, j, k) + i;
}

uint32_t emm_boxes_cell_at(const emm_layout *l, const double *p, uint32_t *levels)
{
    if (levels)
        *levels = 0;
    const struct boxes *b = B(l);
    uint32_t box = box_at(l, b, p), lo = 0, hi = l->ncells;
    while (lo < hi) { /* the cell of that box, if it holds triangles */
        uint32_t mid = lo + (hi - lo) / 2;
        if (b->occ[mid] < box)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < l->ncells && b->occ[lo] == box ? lo : EMM_LAYOUT_NONE;
}

/* A bit per box: set for those that hold triangles, and the cells before
 * each 64 boxes, which number the cells. */
typedef struct held {
    uint64_t *bits;
    uint32_t *before;
} held;

static int is_held(const held *h, uint32_t box)
{
    return (int)((h->bits[box >> 6] >> (box & 63)) & 1u);
}

static uint32_t cell_of_box(const held *h, uint32_t box)
{
    uint64_t below = h->bits[box >> 6] & ((UINT64_C(1) << (box & 63)) - 1);
    return h->before[box >> 6] + (uint32_t)__builtin_popcountll(below);
}

/* The box at raw number `box`: its layer, row and place. */
static void box_coord(const struct boxes *b, uint32_t box, int32_t co[3])
{
    uint32_t pair = b->layer_cells[0] + b->layer_cells[1];
    uint32_t k = 2 * (box / pair), r = box % pair;
    if (r >= b->layer_cells[0]) {
        k++;
        r -= b->layer_cells[0];
    }
    uint32_t n0 = b->n[0], i, j;
    if (!b->shift) {
        j = r / n0;
        i = r % n0;
    } else if (k & 1u) { /* every row of an odd layer holds n0 + 1 */
        j = r / (n0 + 1);
        i = r % (n0 + 1);
    } else { /* rows of n0 and n0 + 1 in turn */
        uint32_t two = 2 * n0 + 1, rr = r % two;
        j = 2 * (r / two) + (rr >= n0);
        i = rr >= n0 ? rr - n0 : rr;
    }
    co[0] = (int32_t)i;
    co[1] = (int32_t)j;
    co[2] = (int32_t)k;
}

/* About `want` boxes, as n[0] x n[1] x n[2] following the bounding box's
 * proportions so boxes come out cube-ish; a flat extent gets one layer of
 * unit boxes along it. */
static void size_boxes(const emm_layout *l, struct boxes *b, double want)
{
    double e[3], prod = 1;
    int live = 0;
    for (int a = 0; a < 3; a++) {
        e[a] = l->hi[a] - l->lo[a];
        if (e[a] > 0) {
            prod *= e[a];
            live++;
        }
    }
    double s = live ? pow(want / prod, 1.0 / live) : 0;
    for (int a = 0; a < 3; a++) {
        /* At most `want` boxes along an axis: a very thin extent beside a
         * long one must not multiply the boxes along the long one. */
        double v = e[a] > 0 ? e[a] * s : 1;
        v = v > want ? want : v;
        b->n[a] = v < 1 ? 1 : v > (double)MAX_BOXES ? MAX_BOXES : (uint32_t)llround(v);
        if (b->n[a] < 1)
            b->n[a] = 1;
        b->w[a] = e[a] > 0 ? e[a] / (double)b->n[a] : 1;
    }
}

/* Boxes that hold a centroid, for the sizing. */
static int64_t occupied(const emm_layout *l, struct boxes *b, const double *const *c)
{
    uint64_t *mark = calloc(count_cells(b) / 64 + 1, sizeof *mark);
    if (!mark)
        return -1;
    int64_t n = 0;
    for (size_t t = 0; t < l->nt; t++) {
        double p[3] = {c[0][t], c[1][t], c[2][t]};
        uint32_t x = box_at(l, b, p);
        uint64_t bit = UINT64_C(1) << (x & 63);
        n += !(mark[x >> 6] & bit);
        mark[x >> 6] |= bit;
    }
    free(mark);
    return n;
}

/* The fewest boxes (of those tried) of which at least ceil(nt / cell) hold
 * triangles, or as many as MAX_BOXES allows. */
static int choose_boxes(const emm_layout *l, struct boxes *b, const double *const *c)
{
    double target = ceil((double)l->nt / l->opt.cell);
    size_boxes(l, b, target);
    if (target <= 1 || count_cells(b) > MAX_BOXES)
        return 0;
    double lo = target, hi = target;
    int64_t occ = occupied(l, b, c);
    /* Grow until enough boxes hold triangles. */
    while (occ >= 0 && (double)occ < target) {
        lo = hi;
        hi *= 2;
        size_boxes(l, b, hi);
        if (count_cells(b) > MAX_BOXES) {
            hi = lo;
            break;
        }
        occ = occupied(l, b, c);
    }
    /* Then narrow down between too few and enough. */
    for (int round = 0; round < 12 && occ >= 0 && hi > lo * 1.02; round++) {
        double mid = sqrt(lo * hi);
        size_boxes(l, b, mid);
        if ((occ = occupied(l, b, c)) >= 0 && (double)occ >= target)
            hi = mid;
        else
            lo = mid;
    }
    size_boxes(l, b, hi);
    return occ < 0 ? -1 : 0;
}

/* The box of cell (i, j, k) in quarter boxes along every axis: exact. */
static void box4(const struct boxes *b, const int32_t *coord, int64_t lo[3])
{
    uint32_t i = (uint32_t)coord[0], j = (uint32_t)coord[1], k = (uint32_t)coord[2];
    lo[0] = 4 * (int64_t)i + off4x(b, j, k);
    lo[1] = 4 * (int64_t)j + off4y(b, k);
    lo[2] = 4 * (int64_t)k;
}

/* Box centres compared along each axis, exactly. */
unsigned emm_boxes_move_side(const emm_layout *l, uint32_t from, uint32_t to)
{
    int64_t f[3], t[3];
    box4(B(l), l->cells[from].coord, f);
    box4(B(l), l->cells[to].coord, t);
    unsigned s = 0;
    for (int a = 0; a < 3; a++) {
        if (t[a] < f[a])
            s |= EMM_SIDE_MINUS(a);
        if (t[a] > f[a])
            s |= EMM_SIDE_PLUS(a);
    }
    return s;
}

uint32_t emm_boxes_per_axis(const emm_layout *l, uint32_t n[EMM_MAX_DIMS])
{
    for (int a = 0; a < 3; a++)
        n[a] = B(l)->n[a];
    return l->dims;
}

/* The cells that touch each cell by a face, an edge or a corner: those of
 * the layers, rows and places around its box whose closed boxes meet its
 * own and hold triangles. Ascending: boxes come in raw order, and cells
 * number the held boxes in that order. */
static emm_status neighbors(emm_layout *l, const held *h, const char *name, emm_error *err)
{
    const struct boxes *b = B(l);
    size_t cap = (size_t)l->ncells * (b->shift ? 14u : 26u) + 1;
    if (cap > UINT32_MAX) /* neighbour lists are 32-bit indexed */
        return emm_fail(err, EMM_ERR_RANGE, "%s: %u cells are too many; use a larger CELL", name,
                        l->ncells);
    l->nb_start = malloc(((size_t)l->ncells + 1) * sizeof *l->nb_start);
    l->nb = malloc(cap * sizeof *l->nb);
    if (!l->nb_start || !l->nb)
        return emm_layout_nomem(err, name);
    uint32_t n = 0;
    for (uint32_t c = 0; c < l->ncells; c++) {
        l->nb_start[c] = n;
        const int32_t *co = l->cells[c].coord;
        int64_t me[3];
        box4(b, co, me);
        for (int64_t k = co[2] - 1; k <= co[2] + 1; k++) {
            if (k < 0 || k >= b->n[2])
                continue;
            for (int64_t j = co[1] - 2; j <= co[1] + 2; j++) {
                if (j < 0 || j >= rows_in(b, (uint32_t)k))
                    continue;
                for (int64_t i = co[0] - 2; i <= co[0] + 2; i++) {
                    if (i < 0 || i >= row_len(b, (uint32_t)j, (uint32_t)k))
                        continue;
                    int32_t oc[3] = {(int32_t)i, (int32_t)j, (int32_t)k};
                    int64_t other[3];
                    box4(b, oc, other);
                    int touch = 1, same = 1;
                    for (int a = 0; a < 3; a++) {
                        touch = touch && other[a] <= me[a] + 4 && me[a] <= other[a] + 4;
                        same = same && other[a] == me[a];
                    }
                    uint32_t o = layer_start(b, (uint32_t)k) +
                                 row_start(b, (uint32_t)j, (uint32_t)k) + (uint32_t)i;
                    if (touch && !same && is_held(h, o)) {
                        assert(n < cap);
                        l->nb[n++] = cell_of_box(h, o);
                    }
                }
            }
        }
    }
    l->nb_start[l->ncells] = n;
    return emm_layout_fill_sides(l, name, err);
}

/* The cells: the boxes that hold triangles (h), in raw order, their
 * geometry, and each triangle's cell (l->tri_cell holds its box before). */
static emm_status cut_cells(emm_layout *l, struct boxes *b, uint64_t nboxes, held *h,
                            const char *name, emm_error *err)
{
    size_t words = (size_t)(nboxes / 64 + 1);
    uint32_t n = 0;
    for (size_t w = 0; w < words; w++) {
        h->before[w] = n;
        n += (uint32_t)__builtin_popcountll(h->bits[w]);
    }
    l->ncells = n;
    l->nraw = (uint32_t)nboxes;
    l->cells = calloc((size_t)n + 1, sizeof *l->cells);
    b->occ = malloc(((size_t)n + 1) * sizeof *b->occ);
    if (!l->cells || !b->occ)
        return emm_layout_nomem(err, name);
    uint32_t c = 0;
    for (size_t w = 0; w < words; w++)
        for (uint64_t bits = h->bits[w]; bits; bits &= bits - 1)
            b->occ[c++] = (uint32_t)(w * 64 + (size_t)__builtin_ctzll(bits));
    for (c = 0; c < n; c++) {
        emm_layout_cell *cell = &l->cells[c];
        box_coord(b, b->occ[c], cell->coord);
        int64_t q[3];
        box4(b, cell->coord, q);
        for (int a = 0; a < 3; a++) {
            cell->lo[a] = l->lo[a] + (double)q[a] / 4 * b->w[a];
            cell->hi[a] = l->lo[a] + (double)(q[a] + 4) / 4 * b->w[a];
        }
    }
    for (size_t t = 0; t < l->nt; t++)
        l->tri_cell[t] = cell_of_box(h, l->tri_cell[t]);
    return EMM_OK;
}

emm_status emm_boxes_build(emm_layout *l, const double *const *c, int shift, const char *name,
                           emm_error *err)
{
    assert(l->dims == 3); /* boxes in space: the kind's ops declare 3 */
    struct boxes *b = calloc(1, sizeof *b);
    if (!b)
        return emm_layout_nomem(err, name);
    l->priv = b;
    b->shift = shift;
    if (choose_boxes(l, b, c) < 0)
        return emm_layout_nomem(err, name);
    uint64_t nboxes = count_cells(b);
    size_t words = (size_t)(nboxes / 64 + 1);
    held h = {calloc(words, sizeof *h.bits), malloc(words * sizeof *h.before)};
    if (!h.bits || !h.before) {
        free(h.bits);
        free(h.before);
        return emm_layout_nomem(err, name);
    }
    for (size_t t = 0; t < l->nt; t++) {
        double p[3] = {c[0][t], c[1][t], c[2][t]};
        uint32_t box = box_at(l, b, p);
        l->tri_cell[t] = box;
        h.bits[box >> 6] |= UINT64_C(1) << (box & 63);
    }
    emm_status st = cut_cells(l, b, nboxes, &h, name, err);
    if (st == EMM_OK)
        st = neighbors(l, &h, name, err);
    free(h.bits);
    free(h.before);
    return st;
}

void emm_boxes_destroy(emm_layout *l)
{
    struct boxes *b = l->priv;
    if (b)
        free(b->occ);
    free(b);
}
