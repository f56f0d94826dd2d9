/* The session's decision (docs/design.md "The shim and the session", Session; thesis §5):
 * at the end of the window, "freeze the data" — read the positions and the triangles'
 * vertex indices from the tagged arrays — profile the window (Eq. 5.1), choose the
 * strategy (runtime/table.c, docs/profile.md "The decision"), build the models and replay
 * the window through them. */
#include "session_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "error.h"
#include "parse.h"

static double read_coord(const unsigned char *p, emm_scalar t)
{
    if (t == EMM_F32) {
        float f;
        memcpy(&f, p, sizeof f);
        return f;
    }
    double d;
    memcpy(&d, p, sizeof d);
    return d;
}

static int64_t read_index(const unsigned char *p, emm_scalar t)
{
    if (t == EMM_I32) {
        int32_t v;
        memcpy(&v, p, sizeof v);
        return v;
    }
    if (t == EMM_U32) {
        uint32_t v;
        memcpy(&v, p, sizeof v);
        return v;
    }
    if (t == EMM_U16) {
        uint16_t v;
        memcpy(&v, p, sizeof v);
        return v;
    }
    int64_t v;
    memcpy(&v, p, sizeof v);
    return v;
}

/* Whether array a is a better mesh than array b: live (an array already
 * gone, a growing vector's old buffer, is not the mesh the run goes on
 * with), then read most by the window, then the most records. */
static bool better_mesh(const session_array *a, const session_array *b)
{
    if (a->live != b->live)
        return a->live;
    if (a->refs != b->refs)
        return a->refs > b->refs;
    return a->count > b->count;
}

/* The array of `kind` that is the mesh (better_mesh); other arrays of the
 * kind are per-element data beside it (normals, colours), or gone. When
 * one rule selected several live arrays, the summary says which was taken
 * (s->pick_note): a rule's nth= or min= picks another. */
static int mesh_array(session *s, emm_array_kind kind)
{
    int best = -1, same_rule = 0;
    for (int i = 0; i < s->narrays; i++) {
        const session_array *a = &s->arrays[i];
        if (session_usable(a) && a->kind == kind && !emm_tag_shape_is_connectivity(a->shape) &&
            (best < 0 || better_mesh(a, &s->arrays[best])))
            best = i;
    }
    if (best < 0 || s->arrays[best].rule < 0)
        return best;
    for (int i = 0; i < s->narrays; i++)
        same_rule += s->arrays[i].live && s->arrays[best].live && s->arrays[i].kind == kind &&
                     !emm_tag_shape_is_connectivity(s->arrays[i].shape) &&
                     s->arrays[i].rule == s->arrays[best].rule;
    if (same_rule > 1) {
        char o[512];
        size_t used = strlen(s->pick_note);
        snprintf(s->pick_note + used, sizeof s->pick_note - used,
                 "%s%s selected %d live %s arrays; the mesh is the one at 0x%llx (%llu records, "
                 "%llu window accesses), the others are per-element data (nth= picks another)",
                 used ? "; " : "", session_origin(s, &s->arrays[best], o, sizeof o), same_rule,
                 kind == EMM_ARRAY_VERTICES ? "vertex" : "triangle",
                 (unsigned long long)s->arrays[best].base,
                 (unsigned long long)s->arrays[best].count,
                 (unsigned long long)s->arrays[best].refs);
    }
    return best;
}

/* The records of an array in use: all of them for an emm_tag_* call; for a
 * block a rule selected, whose size is a capacity, those up to the highest
 * element the program accessed (its loader's writes included). */
static uint64_t in_use(const session_array *a)
{
    return a->rule >= 0 && a->top > 0 && a->top < a->count ? a->top : a->count;
}

/* A coordinate a mesh can have: finite, not subnormal, not absurdly large.
 * Integers or pointers read as floating point are subnormal or huge: a
 * wrong stride or offset shows here. */
static bool plausible(double x, emm_scalar t)
{
    double tiny = t == EMM_F32 ? 1.1754943508222875e-38 : 2.2250738585072014e-308;
    return isfinite(x) && (x == 0 || fabs(x) >= tiny) && fabs(x) < 1e30;
}

/* The array's count becomes the records in use: later accesses past them
 * are not the mesh's. A snapshot (an array freed before the decision)
 * holds every record's fields in a row, so it shrinks alike; left at its
 * capacity it was more records than the mesh's vertices, and the trace
 * left the whole array out. */
static void shrink_to(session_array *a, uint64_t count)
{
    if (count < a->count) {
        a->count = count;
        a->end = session_array_end(a);
    }
}

/* Reads the three coordinates of record i into p, coordinate c from array
 * src[c] (one array for all three, or a mesh's axis blocks; NULL: 0, a
 * mesh without a z block): a vertex's (corner < 0), or a soup's corner
 * (0..2). A value that cannot be a coordinate refuses the block it is in,
 * in one line that names the rule or call that tagged it. */
static emm_status read_position(session *s, session_array *const src[3], uint64_t i,
                                int corner, double *p, emm_error *err)
{
    static const char axis[] = "xyz";
    unsigned first = corner < 0 ? 0 : 3 * (unsigned)corner;
    for (unsigned c = 0; c < 3; c++) {
        session_array *a = src[c];
        if (!a) {
            p[c] = 0;
            continue;
        }
        p[c] = read_coord(session_scalar_at(s, a, i, a->axis >= 0 ? 0 : first + c), a->type);
        if (plausible(p[c], a->type))
            continue;
        char origin[512], shape[96], what[64], key[8];
        if (a->plane)
            snprintf(shape, sizeof shape, "3 columns of %llu entries of %llu bytes",
                     (unsigned long long)a->count, (unsigned long long)a->stride);
        else
            snprintf(shape, sizeof shape, "%llu %s of %llu bytes", (unsigned long long)a->count,
                     a->axis >= 0 ? "entries" : "records", (unsigned long long)a->stride);
        if (corner < 0)
            snprintf(what, sizeof what, "vertex %llu", (unsigned long long)i);
        else
            snprintf(what, sizeof what, "triangle %llu's corner %d", (unsigned long long)i,
                     corner + 1);
        if (a->axis >= 0)
            snprintf(key, sizeof key, "%c", axis[c]);
        else
            snprintf(key, sizeof key, "%s", a->shape == EMM_TAG_SOUP ? "corners" : "xyz");
        return emm_fail(err, EMM_ERR_MESH,
                        "%s: %s: the block at 0x%llx (%s) is refused: %s has %c = %g, not a "
                        "coordinate (is stride or %s's offset or type wrong?)",
                        s->program, session_origin(s, a, origin, sizeof origin),
                        (unsigned long long)a->base, shape, what, axis[c], p[c], key);
    }
    return EMM_OK;
}

/* A triangle soup (an EMM_TAG soup: rule): each record is a triangle whose
 * three corners are its own coordinates, as STL facets are. The geometry's
 * vertices are the corners, those at exactly the same position (-0 and 0
 * alike) one vertex: the layouts then see the connectivity an indexed mesh
 * of the same surface has. */
static emm_status read_soup(session *s, session_array *t, emm_error *err)
{
    char to[512];
    session_origin(s, t, to, sizeof to);
    if (!session_readable(s, t))
        return emm_fail(err, EMM_ERR_INVALID,
                        "%s: the tagged arrays' contents never reached the session's process",
                        s->program);
    uint64_t nt = in_use(t);
    if (nt > INT32_MAX / 3)
        return emm_fail(err, EMM_ERR_RANGE, "%s: %s: the soup has %llu triangles (at most %d)",
                        s->program, to, (unsigned long long)nt, INT32_MAX / 3);
    size_t corners = (size_t)(3 * nt), cap = 16;
    while (cap < 2 * corners)
        cap *= 2;
    int32_t *slot = malloc(cap * sizeof *slot);
    s->xyz = malloc(3 * (corners ? corners : 1) * sizeof *s->xyz);
    s->tri = malloc((corners ? corners : 1) * sizeof *s->tri);
    if (!slot || !s->xyz || !s->tri) {
        free(slot);
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the geometry", s->program);
    }
    memset(slot, 0xff, cap * sizeof *slot); /* -1: empty */
    uint64_t nv = 0;
    for (uint64_t i = 0; i < nt; i++)
        for (int k = 0; k < 3; k++) {
            double p[3];
            emm_status st = read_position(s, (session_array *const[3]){t, t, t}, i, k, p, err);
            if (st != EMM_OK) {
                free(slot);
                return st;
            }
            uint64_t h = 14695981039346656037ull;
            for (int c = 0; c < 3; c++) {
                if (p[c] == 0)
                    p[c] = 0; /* -0 is 0 */
                uint64_t bits;
                memcpy(&bits, &p[c], sizeof bits);
                h = (h ^ bits) * 1099511628211ull;
                h ^= h >> 31;
            }
            size_t at = (size_t)h & (cap - 1);
            while (slot[at] >= 0 && memcmp(s->xyz + 3 * (size_t)slot[at], p, sizeof p) != 0)
                at = (at + 1) & (cap - 1);
            if (slot[at] < 0) {
                slot[at] = (int32_t)nv;
                memcpy(s->xyz + 3 * nv, p, sizeof p);
                nv++;
            }
            s->tri[3 * i + (uint64_t)k] = slot[at];
        }
    free(slot);
    shrink_to(t, nt);
    s->soup = true;
    s->info.geometry.nv = nv;
    s->info.geometry.xyz = s->xyz;
    s->info.geometry.nt = nt;
    s->info.geometry.tri = s->tri;
    char a[32], b[32], c[32];
    size_t used = strlen(s->pick_note);
    snprintf(s->pick_note + used, sizeof s->pick_note - used,
             "%sthe mesh is a triangle soup (%s): %s triangles, their %s corners %s vertices "
             "(corners at the same position are one vertex)",
             used ? "; " : "", to, emm_grouped(nt, a), emm_grouped(3 * nt, b), emm_grouped(nv, c));
    return EMM_OK;
}

/* A mesh's vertices in axis blocks (EMM_TAG x=, y=, z=): the x, y and z
 * blocks of the group of `best` into src (z may be NULL: 0). A missing x or
 * y block, or blocks whose counts came to disagree, refuse the mesh in one
 * line naming the rule of each block concerned. */
static emm_status axis_blocks(session *s, session_array *best, session_array *src[3],
                              emm_error *err)
{
    static const char axis[] = "xyz";
    char o[512], o2[512], n1[32], n2[32];
    for (int k = 0; k < 3; k++) {
        src[k] = NULL;
        for (int i = 0; i < s->narrays; i++) {
            session_array *a = &s->arrays[i];
            if (session_usable(a) && a->axis == k && a->lead == best->lead &&
                (!src[k] || better_mesh(a, src[k])))
                src[k] = a;
        }
    }
    for (int k = 0; k < 2; k++) {
        if (src[k])
            continue;
        /* A block of the axis that is in no group of best's count: its
         * count disagrees. */
        session_array *other = NULL;
        for (int i = 0; i < s->narrays; i++)
            if (session_usable(&s->arrays[i]) && s->arrays[i].axis == k &&
                (!other || better_mesh(&s->arrays[i], other)))
                other = &s->arrays[i];
        session_origin(s, best, o, sizeof o);
        if (other)
            return emm_fail(err, EMM_ERR_INVALID,
                            "%s: %s tagged the %c block at 0x%llx, %s entries, but %s tagged "
                            "the %c block at 0x%llx with %s: the counts disagree, and no vertex "
                            "is read from either (the blocks of one mesh hold one entry per "
                            "vertex)",
                            s->program, o, axis[best->axis], (unsigned long long)best->base,
                            emm_grouped(best->count, n1),
                            session_origin(s, other, o2, sizeof o2), axis[k],
                            (unsigned long long)other->base, emm_grouped(other->count, n2));
        return emm_fail(err, EMM_ERR_INVALID,
                        "%s: %s tagged the %c block at 0x%llx, %s entries, but no %c block was "
                        "tagged: the vertices need their x and y (does the %c rule's site=, "
                        "min= or nth= select its block?)",
                        s->program, o, axis[best->axis], (unsigned long long)best->base,
                        emm_grouped(best->count, n1), axis[k], axis[k]);
    }
    for (int k = 1; k < 3; k++)
        if (src[k] && src[k]->count != src[0]->count)
            return emm_fail(err, EMM_ERR_MESH,
                            "%s: the vertices' x block at 0x%llx (%s) has %s entries, its %c "
                            "block at 0x%llx (%s) %s: the counts disagree (a block reallocated "
                            "alone?)",
                            s->program, (unsigned long long)src[0]->base,
                            session_origin(s, src[0], o, sizeof o),
                            emm_grouped(src[0]->count, n1), axis[k],
                            (unsigned long long)src[k]->base,
                            session_origin(s, src[k], o2, sizeof o2),
                            emm_grouped(src[k]->count, n2));
    return EMM_OK;
}

/* The summary's and the report's line on a mesh whose vertices are axis
 * blocks: "the vertices are 3 blocks (x, y, z) of 4,000 f32 each (EMM_TAG
 * rules 1, 2, 3)". */
static void note_axis_blocks(session *s, session_array *const src[3], uint64_t nv)
{
    char num[32], rules[64] = "";
    int n = 0;
    for (int k = 0; k < 3; k++)
        if (src[k]) {
            size_t used = strlen(rules);
            snprintf(rules + used, sizeof rules - used, "%s%d", n ? ", " : "", src[k]->rule + 1);
            n++;
        }
    size_t used = strlen(s->pick_note);
    snprintf(s->pick_note + used, sizeof s->pick_note - used,
             "%sthe vertices are %d blocks (%s) of %s %s each (EMM_TAG rules %s)",
             used ? "; " : "", n, src[2] ? "x, y, z" : "x, y; z is 0", emm_grouped(nv, num),
             src[0]->type == EMM_F32 ? "f32" : "f64", rules);
}

/* Whether every vertex index of triangle array t names a record of vertex
 * array v. */
static bool indices_fit(session *s, session_array *t, const session_array *v)
{
    if (!session_readable(s, t))
        return false;
    for (uint64_t i = 0, nt = in_use(t); i < nt; i++)
        for (unsigned c = 0; c < 3; c++) {
            int64_t x = read_index(session_scalar_at(s, t, i, c), t->type);
            if (x < 0 || (uint64_t)x >= v->count)
                return false;
        }
    return true;
}

/* Several meshes (threads that each load one, a program that keeps two):
 * the best triangle and vertex arrays apart may be of different meshes, or
 * a mesh still being built. With several live arrays of each kind, or when
 * the indices of *gt do not fit *gv, the pair to simulate is the best
 * triangle array (written to its end first, then better_mesh order) with
 * the smallest vertex array its indices fit; the summary says which, and
 * that the others are not simulated. */
static void pair_mesh(session *s, int *gv, int *gt)
{
    if (*gv < 0 || *gt < 0 || s->arrays[*gv].axis >= 0)
        return;
    int nv = 0, nt = 0, bv = -1, bt = -1;
    for (int i = 0; i < s->narrays; i++) {
        const session_array *a = &s->arrays[i];
        bool plain = !emm_tag_shape_is_connectivity(a->shape);
        nv += session_usable(a) && a->live && plain && a->kind == EMM_ARRAY_VERTICES;
        nt += session_usable(a) && a->live && plain && a->kind == EMM_ARRAY_TRIANGLES;
    }
    /* One mesh (beside per-element data of one kind): the arrays apart are
     * it, and read_geometry checks them. */
    if ((nv < 2 || nt < 2) && (!session_readable(s, &s->arrays[*gv]) ||
                               indices_fit(s, &s->arrays[*gt], &s->arrays[*gv])))
        return;
    for (int t = 0; t < s->narrays; t++) {
        session_array *ta = &s->arrays[t];
        if (!session_usable(ta) || ta->kind != EMM_ARRAY_TRIANGLES ||
            ta->shape == EMM_TAG_SOUP || emm_tag_shape_is_connectivity(ta->shape))
            continue;
        /* A block written to its end before one still being filled (its
         * thread was loading when the window closed), then better_mesh. */
        if (bt >= 0) {
            const session_array *b = &s->arrays[bt];
            bool whole = in_use(ta) == ta->count, bwhole = in_use(b) == b->count;
            if (whole != bwhole ? !whole : !better_mesh(ta, b))
                continue;
        }
        /* Of the vertex arrays the indices fit, the tightest: a larger one
         * (another thread's bigger mesh) fits too. */
        int fv = -1;
        for (int v = 0; v < s->narrays; v++) {
            session_array *va = &s->arrays[v];
            const session_array *f = fv >= 0 ? &s->arrays[fv] : NULL;
            if (session_usable(va) && va->kind == EMM_ARRAY_VERTICES && va->axis < 0 &&
                !emm_tag_shape_is_connectivity(va->shape) &&
                session_readable(s, va) &&
                (!f || va->count < f->count || (va->count == f->count && better_mesh(va, f))) &&
                indices_fit(s, ta, va))
                fv = v;
        }
        if (fv >= 0)
            bv = fv, bt = t;
    }
    if (bt < 0 || (bt == *gt && bv == *gv))
        return; /* none fits (read_geometry says why), or the pair apart is it */
    *gv = bv;
    *gt = bt;
    char vo[512], to[512];
    size_t used = strlen(s->pick_note);
    snprintf(s->pick_note + used, sizeof s->pick_note - used,
             "%sthe tagged arrays hold several meshes (%d vertex and %d triangle arrays live): "
             "simulated %s with %s, the smallest vertex array its indices fit; the others "
             "are not simulated",
             used ? "; " : "", nv, nt, session_origin(s, &s->arrays[bt], to, sizeof to),
             session_origin(s, &s->arrays[bv], vo, sizeof vo));
}

/* "Freeze the data": copies the positions and the triangles' vertex indices
 * out of the program's arrays, checking them. Without a triangle array the
 * geometry is the vertices alone (nt = 0: the layouts cut cells of
 * vertices). */
static emm_status read_geometry(session *s, emm_error *err)
{
    int gv = mesh_array(s, EMM_ARRAY_VERTICES), gt = mesh_array(s, EMM_ARRAY_TRIANGLES);
    char vo[512], to[512];
    if (gt >= 0 && s->arrays[gt].shape == EMM_TAG_SOUP)
        return read_soup(s, &s->arrays[gt], err);
    /* A half-edge mesh's triangles are its faces (beside a triangle array:
     * the triangle array is the mesh, the connectivity not simulated). */
    bool halfedges = gt < 0 && session_halfedge_pick(s);
    pair_mesh(s, &gv, &gt);
    if (gv < 0)
        return emm_fail(err, EMM_ERR_INVALID,
                        "%s: no vertex array was tagged (emm_tag_vertices or an EMM_TAG "
                        "'vertices:' rule), so there is no geometry to lay out",
                        s->program);
    s->vertex_slot = gv;
    session_array *v = &s->arrays[gv];
    /* Where each coordinate is read from: the array, or its axis blocks. */
    session_array *src[3] = {v, v, v};
    if (v->axis >= 0) {
        emm_status st = axis_blocks(s, v, src, err);
        if (st != EMM_OK)
            return st;
        v = src[0];
    }
    session_origin(s, v, vo, sizeof vo);
    bool readable = gt < 0 || session_readable(s, &s->arrays[gt]);
    for (int k = 0; k < 3; k++)
        readable = readable && (!src[k] || session_readable(s, src[k]));
    if (!readable)
        return emm_fail(err, EMM_ERR_INVALID,
                        "%s: the tagged arrays' contents never reached the session's process",
                        s->program);
    uint64_t nv = 0, nt = 0;
    for (int k = 0; k < 3; k++)
        if (src[k] && in_use(src[k]) > nv)
            nv = in_use(src[k]);
    int64_t highest = -1;
    if (gt >= 0) {
        session_array *t = &s->arrays[gt];
        session_origin(s, t, to, sizeof to);
        nt = in_use(t);
        s->tri = malloc((nt ? 3 * nt : 1) * sizeof *s->tri);
        if (!s->tri)
            return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the geometry", s->program);
        for (uint64_t i = 0; i < nt; i++) {
            for (unsigned c = 0; c < 3; c++) {
                int64_t x = read_index(session_scalar_at(s, t, i, c), t->type);
                if (x < 0 || (uint64_t)x >= v->count || x > INT32_MAX) {
                    /* Blame the array that changed, when one did. */
                    const char *why = v->moves || t->moves
                                          ? "the arrays were reallocated while the program ran: "
                                            "the indices may be of another state of the mesh"
                                          : "is vidx's offset or type wrong, or the vertex rule's "
                                            "block the wrong one?";
                    return emm_fail(err, EMM_ERR_MESH,
                                    "%s: %s: the block at 0x%llx is refused: triangle %llu has "
                                    "vertex index %lld, outside the %llu records of %s at 0x%llx "
                                    "(%s)",
                                    s->program, to, (unsigned long long)t->base,
                                    (unsigned long long)i, (long long)x,
                                    (unsigned long long)v->count, vo, (unsigned long long)v->base,
                                    why);
                }
                if (x > highest)
                    highest = x;
                s->tri[3 * i + (uint64_t)c] = (int32_t)x;
            }
        }
        shrink_to(t, nt);
        /* The vertices the triangles use are in use, written or not. */
        if (v->rule >= 0 && (uint64_t)(highest + 1) > nv)
            nv = (uint64_t)(highest + 1);
        s->info.geometry.nt = nt;
        s->info.geometry.tri = s->tri;
    } else if (halfedges) {
        emm_status st = session_halfedge_triangles(s, v, &nt, &highest, err);
        if (st != EMM_OK)
            return st;
        if (v->rule >= 0 && (uint64_t)(highest + 1) > nv)
            nv = (uint64_t)(highest + 1);
        s->info.geometry.nt = nt;
        s->info.geometry.tri = s->tri;
    }
    if (nv > INT32_MAX)
        return emm_fail(err, EMM_ERR_RANGE, "%s: the vertex array has %llu records (at most %d)",
                        s->program, (unsigned long long)nv, INT32_MAX);
    s->xyz = malloc(3 * (nv ? nv : 1) * sizeof *s->xyz);
    if (!s->xyz)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the geometry", s->program);
    for (uint64_t i = 0; i < nv; i++) {
        emm_status st = read_position(s, src, i, -1, s->xyz + 3 * i, err);
        if (st != EMM_OK)
            return st;
    }
    for (int k = 0; k < 3; k++)
        if (src[k])
            shrink_to(src[k], nv);
    if (v->axis >= 0)
        note_axis_blocks(s, src, nv);
    s->info.geometry.nv = nv;
    s->info.geometry.xyz = s->xyz;
    if (gt < 0 && !halfedges) {
        /* Vertex positions only (a half-edge mesh, a point set): each vertex
         * is its own degenerate triangle, so the layouts cut cells of
         * vertices and every strategy runs on them. */
        s->vertex_only = true;
        s->tri = malloc(3 * (nv ? nv : 1) * sizeof *s->tri);
        if (!s->tri)
            return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the geometry", s->program);
        for (uint64_t i = 0; i < 3 * nv; i++)
            s->tri[i] = (int32_t)(i / 3);
        s->info.geometry.nt = nv;
        s->info.geometry.tri = s->tri;
    }
    return EMM_OK;
}

/* The coordinates a record of the axis blocks of group `lead` has: up to
 * the highest axis among them (x and y: two). */
static unsigned group_axes(const session *s, int lead)
{
    unsigned n = 1;
    for (int i = 0; i < s->narrays; i++)
        if (session_usable(&s->arrays[i]) && s->arrays[i].lead == lead &&
            s->arrays[i].axis >= (int)n)
            n = (unsigned)s->arrays[i].axis + 1;
    return n;
}

uint64_t session_trace_record_bytes(const session *s, const session_array *a)
{
    return a->axis >= 0 ? group_axes(s, a->lead) * a->stride : session_record_bytes(a);
}

/* Trace arrays for the live slots the geometry covers, in slot order, the
 * axis blocks of one group one trace array (its records their x, y, z
 * entries side by side); the window's records are renumbered and those of
 * other slots dropped. */
static emm_status freeze_arrays(session *s, emm_error *err)
{
    /* The trace array of each group's lead slot, or -1. */
    int32_t *group_trace = malloc(((size_t)s->narrays + 1) * sizeof *group_trace);
    s->tarrays = calloc((size_t)s->narrays + 1, sizeof *s->tarrays);
    if (!s->tarrays || !group_trace) {
        free(group_trace);
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", s->program);
    }
    for (int i = 0; i < s->narrays; i++)
        group_trace[i] = -1;
    for (int i = 0; i < s->narrays; i++) {
        session_array *a = &s->arrays[i];
        /* A soup's vertices are its corners: a vertex array beside it is
         * other data. */
        uint64_t limit = a->kind == EMM_ARRAY_VERTICES ? (s->soup ? 0 : s->info.geometry.nv)
                         : s->vertex_only           ? 0
                                                    : s->info.geometry.nt;
        a->trace_index = -1;
        a->part = -1;
        if (!session_usable(a) || a->count > limit || emm_tag_shape_is_connectivity(a->shape))
            continue;
        if (a->axis >= 0 && group_trace[a->lead] >= 0) {
            a->trace_index = group_trace[a->lead];
            shrink_to(a, s->tarrays[a->trace_index].count); /* a block grown alone */
            continue;
        }
        uint64_t record = session_trace_record_bytes(s, a);
        if (a->axis >= 0)
            group_trace[a->lead] = (int32_t)s->ntarrays;
        a->trace_index = (int32_t)s->ntarrays;
        s->tarrays[s->ntarrays++] = (emm_trace_array){
            .kind = a->kind, .record_size = (uint32_t)record, .count = a->count, .base = a->base};
    }
    free(group_trace);
    s->info.version = 1;
    s->info.narrays = s->ntarrays;
    s->info.arrays = s->tarrays;
    emm_status st = session_halfedge_freeze(s, err);
    if (st != EMM_OK)
        return st;
    size_t m = 0;
    uint64_t work = 0;
    for (size_t k = 0; k < s->wn; k++) {
        if (k == s->wfill)
            s->wunit = m;
        if (k == s->wlength)
            s->wstep = m;
        emm_trace_record r = s->window[k];
        const session_array *sa = &s->arrays[r.array];
        int32_t t = sa->trace_index;
        if (t >= 0 && sa->part >= 0) {
            if (session_part_map(s, sa, &r))
                t = (int32_t)r.array;
            else
                t = -1;
        }
        if (t < 0) {
            work += r.work;
            s->dropped++;
            continue;
        }
        work += r.work;
        r.work = work > UINT32_MAX ? UINT32_MAX : (uint32_t)work;
        work = 0;
        r.array = (uint32_t)t;
        s->window[m++] = r;
    }
    if (s->wfill == 0 || s->wfill >= s->wn)
        s->wunit = m;
    if (s->wlength == 0 || s->wlength >= s->wn)
        s->wstep = m;
    s->wn = m;
    return EMM_OK;
}

/* Eq. 5.1 over the window, its features and the table's nearest sample. */
static emm_status profile_window(session *s, emm_error *err)
{
    emm_profiler *p;
    /* Every read of the window was a leading index-order sweep (a
     * converter reads its mesh once, in order): that sweep is the
     * traversal, profiled whole rather than left out. */
    s->sweep_profiled = s->welements == 0 && s->sweep.elements > 0;
    uint64_t window = s->sweep_profiled ? s->sweep.elements : s->welements;
    /* A window that went on waiting for an array is profiled over its
     * length: the reads after it are the run's. */
    if (s->waited && s->wlen && window > s->wlen)
        window = s->wlen;
    emm_status st = emm_profiler_new(&s->info, window ? window : 1, EMM_PROFILE_PLANE,
                                     s->program, &p, err);
    if (st != EMM_OK)
        return st;
    if (s->sweep_profiled)
        profiler_keep_sweep(p);
    if ((st = emm_profiler_add(p, s->window, s->wn, err)) != EMM_OK) {
        emm_profiler_free(p);
        return st;
    }
    /* The profiler leaves the leading sweep out by the same rule as
     * window_add; its count of the sweep's records is the one that holds
     * for the frozen window. */
    emm_profiler_swept(p, &s->wskip);
    size_t n;
    const double *xy = emm_profiler_positions(p, &n);
    if (n > 0) {
        s->D = malloc(n * sizeof *s->D);
        if (!s->D) {
            emm_profiler_free(p);
            return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the profile", s->program);
        }
        st = emm_profile_compute(xy, n, emm_profiler_dims(p), s->D, NULL, &s->threads, err);
        s->nD = st == EMM_OK ? n : 0;
    }
    emm_profiler_free(p);
    if (st != EMM_OK || s->nD < EMM_PROFILE_MIN || !s->table)
        return st;
    double f[EMM_FEATURES];
    if ((st = emm_profile_features(s->D, s->nD, s->program, f, err)) != EMM_OK)
        return st;
    /* The nearest sample, also when EMM_STRATEGY decides (the report names it). */
    if ((st = emm_table_decide(s->table, f, 0, &s->decision, err)) != EMM_OK)
        return st;
    memcpy(s->features, f, sizeof f);
    s->has_profile = true;
    return EMM_OK;
}

size_t session_window_proper(const session *s)
{
    return s->wunit > 0 && s->wunit <= s->wn ? s->wunit : s->wn;
}

/* The window's records past its leading sweep that the decision sees: up
 * to where its element reads filled it, as emm profile reads them off the
 * trace. The records of the capture's batch that came after join the
 * window (they are simulated in order) but are the run's: a capture with
 * larger batches (valgrind's) would otherwise decide on more. */
static size_t window_decided(const session *s)
{
    size_t end = session_window_proper(s);
    return end > s->wskip ? end - s->wskip : 0;
}

/* The decision (runtime/table.c, docs/profile.md "The decision"): the
 * nearest sample, its pattern simulated over this mesh and weighed with the
 * window, or the sweep on the window when the profile is novel. */
static emm_status choose(session *s, emm_error *err)
{
    emm_window_decision wd;
    /* The leading sweep the profile left out is the run's too. */
    emm_decide_options opt = {.threads = &s->threads, .lead = s->window, .nlead = s->wskip};
    emm_status st = decide_features_shared(s->table, s->machine, &s->info, s->window + s->wskip,
                                           window_decided(s), s->features, s->nD, s->program,
                                           &opt, s->layouts, s->decisions, &wd, err);
    if (st != EMM_OK)
        return st;
    s->chosen = wd.strategy;
    s->has_chosen = true;
    /* The class checked on this mesh is the pattern the report names. */
    if (wd.reclassified)
        s->decision = wd.table;
    s->wd = wd;
    s->has_wd = true;
    s->source = wd.how == EMM_DECIDED_WINDOW    ? FROM_SIMULATION
                : wd.how == EMM_DECIDED_CHECKED ? FROM_CHECKED
                                                : FROM_TABLE;
    return EMM_OK;
}

/* The decision without a profile: the standard sweep simulated over the
 * window's records, the fewest cycles taken. */
static emm_status choose_on_window(session *s, emm_error *err)
{
    emm_window_decision wd;
    emm_decide_options opt = {.threads = &s->threads};
    double f[EMM_FEATURES] = {0};
    emm_status st = decide_features_shared(NULL, s->machine, &s->info, s->window + s->wskip,
                                           window_decided(s), f, s->nD, s->program, &opt,
                                           s->layouts, s->decisions, &wd, err);
    if (st != EMM_OK)
        return st;
    s->chosen = wd.strategy;
    s->has_chosen = true;
    s->wd = wd;
    s->has_wd = true;
    s->source = FROM_SIMULATION;
    return EMM_OK;
}

static bool same_strategy(const emm_strategy *a, const emm_strategy *b)
{
    return a->kind == b->kind && a->layout == b->layout && a->fetch == b->fetch &&
           a->cell == b->cell && a->indexed == b->indexed;
}

/* Whether the run confirms the choice (docs/profile.md "The contest"): the
 * session decided (no configured strategy), finalists are asked for, and
 * the capture sees the run past the window. */
static bool wants_contest(const session *s)
{
    return s->has_chosen && s->source != FROM_CONFIG && s->cfg.finalists > 0 &&
           !session_window_only(s);
}

/* Whether the window's prediction is checked against every candidate over
 * the window, the only span a window-only capture sees: the session
 * decided (a configured strategy is the user's), whatever EMM_FINALISTS
 * says (it sizes the run's contest, which such a capture cannot hold). */
static bool wants_window_check(const session *s)
{
    return s->has_chosen && s->source != FROM_CONFIG && session_window_only(s);
}

/* The models: the chosen strategy first, then the comparison, then the
 * contest's other candidates. A comparison strategy that cannot run on
 * this mesh is skipped; the chosen one failing is reported, and the
 * baselines still run. */
static emm_status build_models(session *s, emm_error *err)
{
    bool racing = wants_contest(s), checking = wants_window_check(s);
    /* A mesh with depth brings the layouts in space into the sweep. */
    const emm_trace_geometry *g = &s->info.geometry;
    int depth = emm_geometry_has_depth(g->xyz, g->nv, g->tri, g->nt);
    size_t sweep = emm_strategy_sweep_for(depth, NULL, 0);
    /* A mesh whose look-up tables are paged brings the indexed variants
     * into the contest: the answer may then be to adopt the layout's
     * numbering. */
    size_t indexed = (racing || checking) &&
                             emm_indexed_joins_contest(
                                 g->nv, g->nt, emm_machine_get(s->machine, "emm.lookup_budget"))
                         ? emm_strategy_sweep_indexed(depth, NULL, 0)
                         : 0;
    size_t cap = 4 + (s->cfg.compare == EMM_COMPARE_ALL || racing || checking ? 2 * sweep : 0) +
                 indexed;
    emm_strategy *all = calloc(cap, sizeof *all), *list = calloc(cap, sizeof *list);
    emm_error *errs = calloc(cap, sizeof *errs);
    size_t *entrants = calloc(cap, sizeof *entrants);
    bool *pinned = calloc(cap, sizeof *pinned);
    size_t n = 0, k = 0, shown = 0, ne = 0;
    emm_status st = EMM_OK;
    if (!all || !list || !errs || !entrants || !pinned) {
        st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", s->program);
        goto out;
    }
    if (s->has_chosen)
        all[n++] = s->chosen;
    /* The runner-up, direct reads and the reference cache come first after
     * the choice in every comparison: the summary's answer is made of them.
     * With a contest the runner-up is the contest's. */
    if (s->cfg.compare != EMM_COMPARE_NONE || !s->has_chosen) {
        if (s->has_wd && s->wd.has_runner_up && !racing)
            all[n++] = s->wd.runner_up;
        all[n++] = (emm_strategy){EMM_STRATEGY_DIRECT, EMM_LAYOUT_ORIGINAL, EMM_FETCH_NONE, 0, 0};
        all[n++] = (emm_strategy){EMM_STRATEGY_CACHE, EMM_LAYOUT_ORIGINAL, EMM_FETCH_NONE, 0, 0};
    }
    if (s->cfg.compare == EMM_COMPARE_ALL)
        n += emm_strategy_sweep_for(depth, all + n, cap - n);
    shown = n;
    if (racing || checking)
        n += emm_strategy_sweep_for(depth, all + n, cap - n);
    if (indexed)
        n += emm_strategy_sweep_indexed(depth, all + n, cap - n);
    for (size_t i = 0; i < n; i++) {
        /* The contest's sweep brings only what the machine offers: a
         * strategy it does not offer (cache@LAYOUT without a cache) is no
         * candidate and, not asked for, no comparison either. */
        if (i >= shown && !emm_machine_offers(s->machine, &all[i]))
            continue;
        size_t j = 0;
        while (j < k && !same_strategy(&all[i], &list[j]))
            j++;
        if (j == k)
            list[k++] = all[i];
        /* Every candidate of the sweep the machine offers enters the
         * contest (or the window's check) once; what the report shows keeps
         * running when dropped. */
        if ((racing || checking) && i >= shown) {
            bool in = false;
            for (size_t e = 0; e < ne; e++)
                in = in || entrants[e] == j;
            if (!in) {
                pinned[ne] = j < shown || contest_pins(&all[i]);
                entrants[ne++] = j;
            }
        }
    }
    if ((st = emm_runner_new_shared(&s->threads, s->layouts, &s->runner, err)) != EMM_OK ||
        (st = emm_runner_add(s->runner, s->machine, list, k, &s->info, errs, err)) != EMM_OK)
        goto out;
    s->nmodels = k;
    s->mstrat = list;
    s->direct_model = SIZE_MAX;
    for (size_t i = 0; i < k; i++)
        if (list[i].kind == EMM_STRATEGY_DIRECT)
            s->direct_model = i;
    s->merr = errs;
    list = NULL;
    errs = NULL;
    size_t built = 0;
    for (size_t i = 0; i < k; i++) {
        if (emm_runner_model(s->runner, i)) {
            built++;
        } else if (i == 0 && s->has_chosen) {
            snprintf(s->strategy_note, sizeof s->strategy_note, "%s", s->merr[i].message);
            s->has_chosen = false;
        } else {
            s->skipped++;
        }
    }
    if (built == 0) {
        st = emm_fail(err, EMM_ERR_UNSUPPORTED, "%s: no strategy can be simulated: %s",
                      s->program, s->strategy_note[0] ? s->strategy_note : "none was asked for");
        goto out;
    }
    /* The contest's unit is the window as asked for: its records past the
     * leading sweep up to where its element reads reached its length,
     * before it read on to fill the local store (the same counts emm
     * profile reads off the trace). */
    if (racing && s->has_chosen) {
        size_t lead = s->wskip < s->wstep ? s->wskip : 0;
        st = contest_new(s->runner, entrants, pinned, ne, lead,
                         s->wstep > lead ? s->wstep - lead : 1, s->cfg.finalists, &s->contest,
                         err);
    }
    /* The window's check ranks the same candidates at the end, none
     * dropped: the contest's ranking over the window alone. */
    if (checking && s->has_chosen && s->direct_model != SIZE_MAX &&
        (st = contest_new(s->runner, entrants, NULL, ne, 0, 1, EMM_CONFIG_FINALISTS_ALL,
                          &s->window_rank, err)) == EMM_OK)
        s->window_check = true;
    /* The run's batches queue for the models, which run beside the program
     * (and beside the capture's process, under valgrind) instead of
     * holding it at every batch. Without memory for that they run as
     * before. */
    if (st == EMM_OK) {
        emm_error e;
        emm_runner_pipeline(s->runner, &e);
    }
out:
    free(all);
    free(list);
    free(errs);
    free(entrants);
    free(pinned);
    return st;
}

static uint64_t model_cycles(const session *s, size_t i)
{
    emm_result r;
    emm_model_result(emm_runner_model(s->runner, i), &r);
    uint64_t total = r.total;
    emm_result_release(&r);
    return total;
}

void session_decide_answer(session *s)
{
    size_t top[2], in = 0;
    s->answer_model = s->runner_model = SIZE_MAX;
    s->ranked = false;
    if (s->contest)
        in = contest_standing(s->contest, top, 2);
    else if (s->window_check && s->has_chosen && emm_runner_model(s->runner, 0) &&
             emm_runner_model(s->runner, s->direct_model) &&
             model_cycles(s, 0) > model_cycles(s, s->direct_model))
        /* The prediction took more than direct reads over the window: an
         * EMM strategy slower than doing nothing there is no answer; the
         * fastest candidate over the window is (direct, or one faster). */
        in = contest_standing(s->window_rank, top, 2);
    if (in >= 1) {
        s->answer_model = top[0];
        s->ranked = true;
    }
    if (in >= 2)
        s->runner_model = top[1];
    if (session_overruled(s))
        s->chosen = s->mstrat[s->answer_model];
    /* An indexed answer: the best ranked strategy that keeps its look-up
     * table, for the summary's "adopt this numbering" line. */
    s->plain_model = SIZE_MAX;
    size_t ans = session_answer_model(s);
    const contest *c = s->contest ? s->contest : s->window_check ? s->window_rank : NULL;
    if (c && ans != SIZE_MAX && ans < s->nmodels && s->mstrat[ans].indexed) {
        size_t *idx = malloc(s->nmodels * sizeof *idx);
        size_t n = idx ? contest_standing(c, idx, s->nmodels) : 0;
        for (size_t k = 0; k < n && k < s->nmodels && s->plain_model == SIZE_MAX; k++)
            if (s->mstrat[idx[k]].kind == EMM_STRATEGY_EMM && !s->mstrat[idx[k]].indexed &&
                emm_runner_model(s->runner, idx[k])) {
                s->plain_model = idx[k];
                s->plain_total = model_cycles(s, idx[k]);
            }
        free(idx);
    }
}

void session_window_clock(session *s, size_t n)
{
    if (s->wraw == 0 && n)
        clock_gettime(CLOCK_MONOTONIC, &s->wclock);
    s->wraw += n;
}

emm_status session_decide_read(session *s, emm_error *err)
{
    emm_status st;
    s->wseconds = -1;
    if (s->wraw) {
        struct timespec now;
        clock_gettime(CLOCK_MONOTONIC, &now);
        s->wseconds = (double)(now.tv_sec - s->wclock.tv_sec) +
                      (double)(now.tv_nsec - s->wclock.tv_nsec) / 1e9;
    }
    s->geometry_failed = false;
    unsigned have = 0;
    for (int i = 0; i < s->narrays; i++)
        if (session_usable(&s->arrays[i]))
            have |= 1u << s->arrays[i].kind;
    s->missing = s->expect & ~have;
    if ((st = read_geometry(s, err)) != EMM_OK) {
        s->geometry_failed = true;
        return st;
    }
    if ((st = freeze_arrays(s, err)) != EMM_OK)
        return st;
    session_outputs_prepare(s);
    return EMM_OK;
}

emm_status session_decide_rest(session *s, emm_error *err)
{
    emm_status st;
    if (!(s->layouts = emm_model_share_new()))
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", s->program);
    emm_model_share_keep(s->layouts);
    if (!(s->decisions = decide_cache_new()))
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", s->program);
    if ((st = profile_window(s, err)) != EMM_OK)
        return st;
    if (s->cfg.has_strategy) {
        s->chosen = s->cfg.strategy;
        s->has_chosen = true;
        s->source = FROM_CONFIG;
    } else if (s->has_profile) {
        if ((st = choose(s, err)) != EMM_OK)
            return st;
    } else if (s->nD > 0 && s->table) {
        /* Fewer element reads than a profile's features need (the run
         * ended first): no pattern, but the reads there were still decide —
         * the candidates simulated over them, the fewest cycles taken (the
         * novel profile's rule). */
        if ((st = choose_on_window(s, err)) != EMM_OK)
            return st;
    }
    if ((st = build_models(s, err)) != EMM_OK)
        return st;
    session_outputs_start(s); /* the trace, the timeline, the stall lines */
    /* The window proper, then the probes watch the run: from the record
     * after the one that filled it, whatever the capture's batches. */
    size_t proper = session_window_proper(s);
    session_simulate(s, s->window, proper);
    session_phases_start(s);
    if (s->wn > proper)
        session_simulate(s, s->window + proper, s->wn - proper);
    return EMM_OK;
}

