/* Rows of equal boxes (thesis §4.1.1 grid, §4.1.2 interleaving tiles): the
 * machinery both share. Cells are numbered row-major from the bottom-left.
 * With `shift`, every odd row starts half a cell left of the box and holds
 * one more cell, so a tile touches 2 tiles in its row, 2 above and 2 below;
 * without, a cell has up to 8 neighbours. docs/layouts.md. */
#include "layout_internal.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>

#include "error.h"

struct rows {
    uint32_t cols, rows;
    double cw, ch; /* a cell's width and height */
    int shift;
};

static const struct rows *R(const emm_layout *l)
{
    return l->priv;
}

/* About ceil(nt / cell) cells, as cols × rows matching the bounding box's
 * aspect ratio so cells come out square-ish. */
static void choose_dims(const emm_layout *l, struct rows *r)
{
    uint64_t want = (l->nt + l->opt.cell - 1) / l->opt.cell;
    double w = l->hi[0] - l->lo[0], h = l->hi[1] - l->lo[1];
    uint64_t cols, rows;
    if (want <= 1 || (w <= 0 && h <= 0)) {
        cols = rows = 1;
    } else if (h <= 0) {
        cols = want;
        rows = 1;
    } else if (w <= 0) {
        cols = 1;
        rows = want;
    } else {
        double c = sqrt((double)want * w / h);
        cols = c < 1 ? 1 : c >= (double)want ? want : (uint64_t)llround(c);
        if (cols < 1)
            cols = 1;
        rows = (want + cols - 1) / cols;
    }
    r->cols = (uint32_t)cols;
    r->rows = (uint32_t)rows;
    /* A flat extent gets unit-size cells: every point falls in cell 0 of
     * that axis, and nothing divides by zero. */
    r->cw = w > 0 ? w / (double)cols : 1;
    r->ch = h > 0 ? h / (double)rows : 1;
}

static uint32_t clamp_index(double v, uint32_t n)
{
    if (!(v >= 0)) /* also NaN */
        return 0;
    if (v >= (double)n)
        return n - 1;
    return (uint32_t)v;
}

/* First cell of row k and the cells in it. */
static uint32_t row_start(const struct rows *r, uint32_t k)
{
    return r->shift ? k * r->cols + k / 2 : k * r->cols;
}

static uint32_t row_len(const struct rows *r, uint32_t k)
{
    return r->cols + (r->shift ? (k & 1u) : 0u);
}

uint32_t emm_rows_cell_at(const emm_layout *l, const double *p, uint32_t *levels)
{
    const struct rows *r = R(l);
    if (levels)
        *levels = 0;
    uint32_t k = clamp_index((p[1] - l->lo[1]) / r->ch, r->rows);
    /* Odd rows of tiles start half a tile left of the box. */
    double x = (p[0] - l->lo[0]) / r->cw + ((r->shift && (k & 1u)) ? 0.5 : 0.0);
    return row_start(r, k) + clamp_index(x, row_len(r, k));
}

/* Doubled cell centres, exact in integers: tiles of odd rows sit half a
 * tile left of the even rows' tiles with the same column. The cell's row
 * and column (its coord) follow from its number, cells being row-major:
 * with `shift`, each pair of rows holds 2 cols + 1 cells. (Computed, not
 * read: the cells are large, and the one just entered is not in the cache
 * of a model that keeps its own state of it.) */
static void centre2(const emm_layout *l, uint32_t c, int64_t *x2, int64_t *y2)
{
    const struct rows *r = R(l);
    uint32_t row, col;
    if (r->shift) {
        uint32_t pair = c / (2 * r->cols + 1), rest = c % (2 * r->cols + 1);
        row = 2 * pair + (rest >= r->cols);
        col = rest >= r->cols ? rest - r->cols : rest;
    } else {
        row = c / r->cols;
        col = c % r->cols;
    }
    assert((int32_t)row == l->cells[c].coord[1] && (int32_t)col == l->cells[c].coord[0]);
    int64_t shift = (r->shift && (row & 1)) ? 0 : 1;
    *x2 = 2 * (int64_t)col + shift;
    *y2 = 2 * (int64_t)row + 1;
}

unsigned emm_rows_move_side(const emm_layout *l, uint32_t from, uint32_t to)
{
    int64_t f[2], t[2];
    unsigned s = 0;
    centre2(l, from, &f[0], &f[1]);
    centre2(l, to, &t[0], &t[1]);
    for (int a = 0; a < 2; a++) {
        if (t[a] < f[a])
            s |= EMM_SIDE_MINUS(a);
        if (t[a] > f[a])
            s |= EMM_SIDE_PLUS(a);
    }
    return s;
}

uint32_t emm_rows_per_axis(const emm_layout *l, uint32_t n[EMM_MAX_DIMS])
{
    n[0] = R(l)->cols;
    n[1] = R(l)->rows;
    return l->dims;
}

/* Grid: the 8 surrounding cells; tiles: 2 in the row, and the 2 tiles of
 * each adjacent row that overlap this one horizontally. */
static emm_status neighbors(emm_layout *l, const char *name, emm_error *err)
{
    const struct rows *r = R(l);
    size_t cap = (size_t)l->ncells * 8u;
    l->nb_start = malloc(((size_t)l->ncells + 1) * sizeof *l->nb_start);
    l->nb = malloc(cap * sizeof *l->nb);
    if (!l->nb_start || !l->nb)
        return emm_layout_nomem(err, name);
    uint32_t n = 0;
    for (uint32_t c = 0; c < l->ncells; c++) {
        l->nb_start[c] = n;
        uint32_t row = (uint32_t)l->cells[c].coord[1], k = (uint32_t)l->cells[c].coord[0];
        for (int dr = -1; dr <= 1; dr++) {
            int64_t rr = (int64_t)row + dr;
            if (rr < 0 || rr >= r->rows)
                continue;
            int64_t lo, hi; /* columns of row rr that touch cell c */
            if (!r->shift || dr == 0) {
                lo = (int64_t)k - 1;
                hi = (int64_t)k + 1;
            } else if (row & 1u) { /* odd row: tile k spans [k-1/2, k+1/2) */
                lo = (int64_t)k - 1;
                hi = (int64_t)k;
            } else { /* even row: tile k spans [k, k+1), odd neighbours k, k+1 */
                lo = (int64_t)k;
                hi = (int64_t)k + 1;
            }
            uint32_t len = row_len(r, (uint32_t)rr), first = row_start(r, (uint32_t)rr);
            for (int64_t kk = lo; kk <= hi; kk++)
                if (kk >= 0 && kk < len && !(dr == 0 && kk == k))
                    l->nb[n++] = first + (uint32_t)kk;
        }
    }
    l->nb_start[l->ncells] = n;
    return emm_layout_fill_sides(l, name, err);
}

emm_status emm_rows_build(emm_layout *l, const double *const *c, int shift, const char *name,
                          emm_error *err)
{
    assert(l->dims == 2); /* rows in the plane: the kind's ops declare 2 */
    struct rows *r = calloc(1, sizeof *r);
    if (!r)
        return emm_layout_nomem(err, name);
    l->priv = r;
    r->shift = shift;
    choose_dims(l, r);
    uint64_t ncells = (uint64_t)r->cols * r->rows + (shift ? r->rows / 2 : 0);
    if (ncells * 8 > UINT32_MAX) /* neighbour lists are 32-bit indexed */
        return emm_fail(err, EMM_ERR_RANGE, "%s: %llu cells are too many; use a larger CELL",
                        name, (unsigned long long)ncells);
    l->ncells = (uint32_t)ncells;
    l->cells = calloc(ncells, sizeof *l->cells);
    if (!l->cells)
        return emm_layout_nomem(err, name);
    for (uint32_t k = 0; k < r->rows; k++) {
        double off = (shift && (k & 1u)) ? -0.5 : 0.0;
        for (uint32_t i = 0; i < row_len(r, k); i++) {
            emm_layout_cell *cell = &l->cells[row_start(r, k) + i];
            cell->coord[0] = (int32_t)i;
            cell->coord[1] = (int32_t)k;
            cell->lo[0] = l->lo[0] + ((double)i + off) * r->cw;
            cell->hi[0] = l->lo[0] + ((double)i + 1 + off) * r->cw;
            cell->lo[1] = l->lo[1] + (double)k * r->ch;
            cell->hi[1] = l->lo[1] + (double)(k + 1) * r->ch;
        }
    }
    for (size_t t = 0; t < l->nt; t++) {
        double p[2] = {c[0][t], c[1][t]};
        l->tri_cell[t] = emm_rows_cell_at(l, p, NULL);
    }
    return neighbors(l, name, err);
}
