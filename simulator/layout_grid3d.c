/* A 3D grid: equal boxes over the bounding box in x, y and z, about CELL
 * triangles each on average, numbered x fastest, then y, then z; up to 26
 * neighbours. A dummy that shows a layout in space is this file and one
 * line of EMM_LAYOUT_LIST (docs/architecture.md, "Adding a part"). */
#include "layout_internal.h"

#include <math.h>
#include <stdlib.h>

#include "error.h"

struct grid3d {
    uint32_t n[3];  /* boxes along each axis */
    double size[3]; /* a box's extent along each axis */
};

static const struct grid3d *G(const emm_layout *l)
{
    return l->priv;
}

static uint32_t clamp_index(double v, uint32_t n)
{
    if (!(v >= 0))
        return 0;
    if (v >= (double)n)
        return n - 1;
    return (uint32_t)v;
}

static uint32_t index_of(const struct grid3d *g, const uint32_t k[3])
{
    return (k[2] * g->n[1] + k[1]) * g->n[0] + k[0];
}

static uint32_t cell_at(const emm_layout *l, const double *p, uint32_t *levels)
{
    const struct grid3d *g = G(l);
    uint32_t k[3];
    for (int a = 0; a < 3; a++)
        k[a] = clamp_index((p[a] - l->lo[a]) / g->size[a], g->n[a]);
    if (levels)
        *levels = 0;
    return index_of(g, k);
}

static unsigned move_side(const emm_layout *l, uint32_t from, uint32_t to)
{
    unsigned s = 0;
    for (int a = 0; a < 3; a++) {
        int32_t f = l->cells[from].coord[a], t = l->cells[to].coord[a];
        if (t < f)
            s |= EMM_SIDE_MINUS(a);
        if (t > f)
            s |= EMM_SIDE_PLUS(a);
    }
    return s;
}

static uint32_t per_axis(const emm_layout *l, uint32_t n[EMM_MAX_DIMS])
{
    for (int a = 0; a < 3; a++)
        n[a] = G(l)->n[a];
    return 3;
}

static emm_status build(emm_layout *l, const double *const *c, const char *name, emm_error *err)
{
    struct grid3d *g = calloc(1, sizeof *g);
    if (!g)
        return emm_layout_nomem(err, name);
    l->priv = g;
    /* About ceil(nt / cell) boxes, as near cubes as the box allows: side s
     * with the product of extent / s over the axes that have an extent. */
    uint64_t want = (l->nt + l->opt.cell - 1) / l->opt.cell, total = 1;
    double prod = 1;
    int k = 0;
    for (int a = 0; a < 3; a++)
        if (l->hi[a] - l->lo[a] > 0) {
            prod *= l->hi[a] - l->lo[a];
            k++;
        }
    double s = k ? pow(prod / (double)want, 1.0 / k) : 1;
    for (int a = 0; a < 3; a++) {
        double ext = l->hi[a] - l->lo[a];
        uint64_t n = ext > 0 ? (uint64_t)llround(ext / s) : 1;
        n = n < 1 ? 1 : n > want ? want : n;
        g->n[a] = (uint32_t)n;
        g->size[a] = ext > 0 ? ext / (double)n : 1;
        total *= n;
    }
    if (total * 26 > UINT32_MAX)
        return emm_fail(err, EMM_ERR_RANGE, "%s: %llu cells are too many; use a larger CELL",
                        name, (unsigned long long)total);
    l->ncells = (uint32_t)total;
    l->cells = calloc(total, sizeof *l->cells);
    l->nb_start = malloc((total + 1) * sizeof *l->nb_start);
    l->nb = malloc(total * 26 * sizeof *l->nb);
    if (!l->cells || !l->nb_start || !l->nb)
        return emm_layout_nomem(err, name);
    uint32_t q[3], n = 0;
    for (q[2] = 0; q[2] < g->n[2]; q[2]++)
        for (q[1] = 0; q[1] < g->n[1]; q[1]++)
            for (q[0] = 0; q[0] < g->n[0]; q[0]++) {
                uint32_t ci = index_of(g, q);
                emm_layout_cell *cell = &l->cells[ci];
                for (int a = 0; a < 3; a++) {
                    cell->coord[a] = (int32_t)q[a];
                    cell->lo[a] = l->lo[a] + (double)q[a] * g->size[a];
                    cell->hi[a] = l->lo[a] + (double)(q[a] + 1) * g->size[a];
                }
                /* The 26 around, ascending: z, then y, then x. */
                l->nb_start[ci] = n;
                for (int dz = -1; dz <= 1; dz++)
                    for (int dy = -1; dy <= 1; dy++)
                        for (int dx = -1; dx <= 1; dx++) {
                            int64_t r[3] = {(int64_t)q[0] + dx, (int64_t)q[1] + dy,
                                            (int64_t)q[2] + dz};
                            int inside = !(dx == 0 && dy == 0 && dz == 0);
                            for (int a = 0; a < 3; a++)
                                inside = inside && r[a] >= 0 && r[a] < g->n[a];
                            if (inside) {
                                uint32_t u[3] = {(uint32_t)r[0], (uint32_t)r[1], (uint32_t)r[2]};
                                l->nb[n++] = index_of(g, u);
                            }
                        }
            }
    l->nb_start[l->ncells] = n;
    for (size_t t = 0; t < l->nt; t++) {
        double p[3] = {c[0][t], c[1][t], c[2][t]};
        l->tri_cell[t] = cell_at(l, p, NULL);
    }
    return emm_layout_fill_sides(l, name, err);
}

const struct emm_layout_ops emm_layout_grid3d_ops = {
    .dims = 3,
    .build = build,
    .move_side = move_side,
    .cell_at = cell_at,
    .per_axis = per_axis,
};
