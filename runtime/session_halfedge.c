/* Half-edge meshes (EMM_TAG halfedges:, faces:, vconn:): the triangles a
 * half-edge structure describes, read from its cycles at the decision, and
 * the parts of the trace's records its arrays become.
 *
 * OpenMesh, CGAL's Surface_mesh and PMP keep a mesh as index arrays: a
 * half-edge holds its to-vertex, next (and prev) half-edge and face, its
 * opposite is h ^ 1; a face holds one half-edge of its cycle; a vertex one
 * outgoing half-edge. A face's corners are the to-vertices of its cycle.
 * The layouts place triangles and vertices in cells; a face's record and
 * its cycle's half-edges travel with its triangle (the derived triangle's
 * trace record is the face's record followed by its three half-edges), a
 * vertex's connectivity record with its position. The program's accesses
 * are renumbered accordingly (session_part_map), and each array's count
 * is kept for the report. */
#include "session_internal.h"

#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "parse.h"

enum { F_TO = 0, F_NEXT, F_PREV, F_FACE, F_OPP };

static int64_t index_at(session *s, session_array *a, uint64_t i, unsigned field)
{
    const unsigned char *p = session_scalar_at(s, a, i, field);
    switch (a->type) {
    case EMM_I32: {
        int32_t v;
        memcpy(&v, p, sizeof v);
        return v;
    }
    case EMM_U32: {
        uint32_t v;
        memcpy(&v, p, sizeof v);
        return v == UINT32_MAX ? -1 : (int64_t)v; /* an unsigned "none" */
    }
    case EMM_U16: {
        uint16_t v;
        memcpy(&v, p, sizeof v);
        return v == UINT16_MAX ? -1 : (int64_t)v;
    }
    default: {
        int64_t v;
        memcpy(&v, p, sizeof v);
        return v;
    }
    }
}

/* As session_decide.c's in_use: a rule's block is a capacity, the records
 * in use those up to the highest the program accessed. */
static uint64_t used(const session_array *a)
{
    return a->rule >= 0 && a->top > 0 && a->top < a->count ? a->top : a->count;
}

static bool better(const session_array *a, const session_array *b)
{
    if (a->live != b->live)
        return a->live;
    if (a->refs != b->refs)
        return a->refs > b->refs;
    return a->count > b->count;
}

static int best_of(session *s, emm_tag_shape shape)
{
    int best = -1;
    for (int i = 0; i < s->narrays; i++) {
        const session_array *a = &s->arrays[i];
        if (session_usable(a) && a->shape == shape &&
            (best < 0 || better(a, &s->arrays[best])))
            best = i;
    }
    return best;
}

bool session_halfedge_pick(session *s)
{
    s->he_slot = best_of(s, EMM_TAG_HALFEDGES);
    s->face_slot = s->he_slot >= 0 ? best_of(s, EMM_TAG_FACES) : -1;
    s->vconn_slot = s->he_slot >= 0 ? best_of(s, EMM_TAG_VCONN) : -1;
    return s->he_slot >= 0;
}

void session_halfedge_free(session *s)
{
    free(s->he_owner);
    free(s->he_pos);
    free(s->taccesses);
    s->he_owner = NULL;
    s->he_pos = NULL;
    s->taccesses = NULL;
    s->nparts = 0;
}

/* The one line a bad half-edge mesh is refused with: the program, the rule
 * (or call) of the array concerned, the problem. */
#define REFUSE(a, ...)                                                                     \
    do {                                                                                   \
        char o_[512], m_[400];                                                             \
        snprintf(m_, sizeof m_, __VA_ARGS__);                                              \
        return emm_fail(err, EMM_ERR_MESH, "%s: %s: the half-edge mesh is refused: %s",    \
                        s->program, session_origin(s, (a), o_, sizeof o_), m_);            \
    } while (0)

/* Walks face f's cycle from half-edge h0: three half-edges, each of face
 * f, closing back on h0; their to-vertices are triangle f's corners. */
static emm_status walk_face(session *s, session_array *H, uint64_t nh, uint64_t f, int64_t h0,
                            const session_array *v, int32_t *tri, emm_error *err)
{
    int64_t h = h0, path[4] = {h0, -1, -1, -1};
    bool prev = (H->hhas & 1u << F_PREV) != 0;
    for (int c = 0; c < 3; c++) {
        int64_t face = index_at(s, H, (uint64_t)h, F_FACE);
        if (face != (int64_t)f)
            REFUSE(H, "half-edge %lld of face %llu's cycle belongs to face %lld", (long long)h,
                   (unsigned long long)f, (long long)face);
        int64_t to = index_at(s, H, (uint64_t)h, F_TO);
        if (to < 0 || (uint64_t)to >= v->count || to > INT32_MAX)
            REFUSE(H, "half-edge %lld points to vertex %lld, outside the %llu vertex records",
                   (long long)h, (long long)to, (unsigned long long)v->count);
        if (s->he_owner[h] != UINT32_MAX && s->he_owner[h] != (uint32_t)f)
            REFUSE(H, "half-edge %lld is in the cycles of faces %u and %llu", (long long)h,
                   s->he_owner[h], (unsigned long long)f);
        s->he_owner[h] = (uint32_t)f;
        s->he_pos[h] = (uint8_t)c;
        tri[c] = (int32_t)to;
        int64_t next = index_at(s, H, (uint64_t)h, F_NEXT);
        if (next < 0 || (uint64_t)next >= nh)
            REFUSE(H, "half-edge %lld's next is %lld, outside the %llu half-edges in use",
                   (long long)h, (long long)next, (unsigned long long)nh);
        if (prev && index_at(s, H, (uint64_t)next, F_PREV) != h)
            REFUSE(H, "half-edge %lld's prev is %lld, not %lld whose next it is", (long long)next,
                   (long long)index_at(s, H, (uint64_t)next, F_PREV), (long long)h);
        path[c + 1] = next;
        h = next;
    }
    if (h != h0)
        REFUSE(H,
               "half-edge %lld's cycle does not close in 3 steps (%lld -> %lld -> %lld -> %lld): "
               "a broken cycle, or a face of more sides: only triangle faces are simulated",
               (long long)h0, (long long)path[0], (long long)path[1], (long long)path[2],
               (long long)path[3]);
    return EMM_OK;
}

emm_status session_halfedge_triangles(session *s, session_array *v, uint64_t *nt_out,
                                      int64_t *highest, emm_error *err)
{
    session_array *H = &s->arrays[s->he_slot];
    session_array *F = s->face_slot >= 0 ? &s->arrays[s->face_slot] : NULL;
    session_array *C = s->vconn_slot >= 0 ? &s->arrays[s->vconn_slot] : NULL;
    if (!session_readable(s, H) || (F && !session_readable(s, F)) ||
        (C && !session_readable(s, C)))
        return emm_fail(err, EMM_ERR_INVALID,
                        "%s: the tagged arrays' contents never reached the session's process",
                        s->program);
    uint64_t nh = used(H);
    if (nh > INT32_MAX)
        REFUSE(H, "%llu half-edges (at most %d)", (unsigned long long)nh, INT32_MAX);
    uint64_t nf = 0;
    if (F) {
        nf = used(F);
    } else {
        for (uint64_t h = 0; h < nh; h++) {
            int64_t f = index_at(s, H, h, F_FACE);
            if (f >= 0 && (uint64_t)f >= nf)
                nf = (uint64_t)f + 1;
        }
    }
    if (nf > INT32_MAX / 3 || nf > nh)
        REFUSE(F ? F : H, "%llu faces for %llu half-edges", (unsigned long long)nf,
               (unsigned long long)nh);
    session_halfedge_free(s);
    s->he_owner = malloc((nh ? nh : 1) * sizeof *s->he_owner);
    s->he_pos = calloc(nh ? nh : 1, 1);
    s->tri = malloc((nf ? 3 * nf : 1) * sizeof *s->tri);
    if (!s->he_owner || !s->he_pos || !s->tri)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the geometry", s->program);
    memset(s->he_owner, 0xff, (nh ? nh : 1) * sizeof *s->he_owner);
    emm_status st = EMM_OK;
    if (F) {
        for (uint64_t f = 0; f < nf && st == EMM_OK; f++) {
            int64_t h0 = index_at(s, F, f, 0);
            if (h0 < 0 || (uint64_t)h0 >= nh)
                REFUSE(F, "face %llu's half-edge is %lld, outside the %llu half-edges in use",
                       (unsigned long long)f, (long long)h0, (unsigned long long)nh);
            st = walk_face(s, H, nh, f, h0, v, s->tri + 3 * f, err);
        }
    } else {
        for (uint64_t h = 0; h < nh && st == EMM_OK; h++) {
            int64_t f = index_at(s, H, h, F_FACE);
            if (f >= 0 && s->he_owner[h] == UINT32_MAX)
                st = walk_face(s, H, nh, (uint64_t)f, (int64_t)h, v, s->tri + 3 * f, err);
        }
    }
    if (st != EMM_OK)
        return st;
    /* Every half-edge that names a face is in its cycle; a boundary
     * half-edge (face -1) travels with its opposite. */
    bool opp = (H->hhas & 1u << F_OPP) != 0;
    for (uint64_t h = 0; h < nh; h++) {
        int64_t f = index_at(s, H, h, F_FACE);
        if (f < -1 || (f >= 0 && (uint64_t)f >= nf))
            REFUSE(H, "half-edge %llu names face %lld, outside the %llu faces",
                   (unsigned long long)h, (long long)f, (unsigned long long)nf);
        if (f >= 0 && s->he_owner[h] == UINT32_MAX)
            REFUSE(H, "half-edge %llu names face %lld, whose cycle does not pass through it",
                   (unsigned long long)h, (long long)f);
    }
    for (uint64_t h = 0; h < nh; h++) {
        if (s->he_owner[h] != UINT32_MAX)
            continue;
        int64_t o = opp ? index_at(s, H, h, F_OPP) : (int64_t)(h ^ 1);
        if (o < 0 || (uint64_t)o >= nh)
            continue;
        if (opp && index_at(s, H, (uint64_t)o, F_OPP) != (int64_t)h)
            REFUSE(H, "half-edge %llu's opposite is %lld, whose opposite is %lld",
                   (unsigned long long)h, (long long)o,
                   (long long)index_at(s, H, (uint64_t)o, F_OPP));
        if (index_at(s, H, (uint64_t)o, F_FACE) >= 0) {
            s->he_owner[h] = s->he_owner[o];
            s->he_pos[h] = s->he_pos[o];
        }
    }
    if (C)
        for (uint64_t i = 0, n = used(C); i < n; i++) {
            int64_t h = index_at(s, C, i, 0);
            if (h < -1 || (h >= 0 && (uint64_t)h >= nh))
                REFUSE(C, "vertex %llu's half-edge is %lld, outside the %llu half-edges in use",
                       (unsigned long long)i, (long long)h, (unsigned long long)nh);
        }
    for (uint64_t i = 0; i < 3 * nf; i++)
        if (s->tri[i] > *highest)
            *highest = s->tri[i];
    *nt_out = nf;
    /* The records past those in use are not the mesh's. */
    if (H->count > nh) {
        H->count = nh;
        H->end = session_array_end(H);
    }
    if (F && F->count > nf) {
        F->count = nf;
        F->end = session_array_end(F);
    }
    char a[32], b[32], o[512];
    size_t at = strlen(s->pick_note);
    snprintf(s->pick_note + at, sizeof s->pick_note - at,
             "%sthe triangles are the %s faces of the half-edge mesh of %s (%s half-edges)",
             at ? "; " : "", emm_grouped(nf, a), session_origin(s, H, o, sizeof o),
             emm_grouped(nh, b));
    return EMM_OK;
}

static session_part *add_part(session *s, session_array *a, int32_t trace, uint32_t base,
                              uint64_t count)
{
    session_part *p = &s->parts[s->nparts];
    *p = (session_part){.shape = a->shape, .trace = trace, .base = base,
                        .stride = (uint32_t)a->stride, .count = count};
    a->trace_index = trace;
    a->part = s->nparts++;
    if (a->count > count) {
        a->count = count;
        a->end = session_array_end(a);
    }
    return p;
}

emm_status session_halfedge_freeze(session *s, emm_error *err)
{
    s->taccesses = calloc((size_t)s->ntarrays + 2, sizeof *s->taccesses);
    if (!s->taccesses)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", s->program);
    for (int i = 0; i < s->narrays; i++)
        if (emm_tag_shape_is_connectivity(s->arrays[i].shape)) {
            s->arrays[i].trace_index = -1; /* another mesh's, or an old buffer: not simulated */
            s->arrays[i].part = -1;
        }
    if (s->he_slot < 0 || s->soup)
        return EMM_OK;
    session_array *H = &s->arrays[s->he_slot];
    session_array *F = s->face_slot >= 0 ? &s->arrays[s->face_slot] : NULL;
    session_array *C = s->vconn_slot >= 0 ? &s->arrays[s->vconn_slot] : NULL;
    uint64_t nt = s->info.geometry.nt;
    uint64_t face_bytes = F ? F->stride : 0, record = face_bytes + 3 * H->stride;
    if (record > UINT32_MAX / 2)
        return emm_fail(err, EMM_ERR_RANGE, "%s: half-edge records of %llu bytes are too large",
                        s->program, (unsigned long long)H->stride);
    int32_t t = (int32_t)s->ntarrays++;
    s->tarrays[t] = (emm_trace_array){.kind = EMM_ARRAY_TRIANGLES,
                                      .record_size = (uint32_t)record,
                                      .count = nt,
                                      .base = F ? F->base : H->base};
    s->nparts = 0;
    if (F)
        add_part(s, F, t, 0, nt);
    session_part *hp = add_part(s, H, t, (uint32_t)face_bytes, H->count);
    hp->remap = s->he_owner;
    hp->pos = s->he_pos;
    /* The mesh's positions are the first vertex array of the trace, which
     * the layouts take for the mesh's (a growing vector's old buffers,
     * read in the window, are arrays of their own: read directly). */
    int32_t vt = s->vertex_slot >= 0 ? s->arrays[s->vertex_slot].trace_index : -1;
    for (int32_t k = 0; vt > 0 && k < vt; k++) {
        if (s->tarrays[k].kind != EMM_ARRAY_VERTICES)
            continue;
        emm_trace_array keep = s->tarrays[k];
        s->tarrays[k] = s->tarrays[vt];
        s->tarrays[vt] = keep;
        for (int i = 0; i < s->narrays; i++)
            if (s->arrays[i].trace_index == k)
                s->arrays[i].trace_index = vt;
            else if (s->arrays[i].trace_index == vt)
                s->arrays[i].trace_index = k;
        vt = k;
        break;
    }
    /* The vertices' records grow by their connectivity record. */
    if (C && vt >= 0 && s->arrays[s->vertex_slot].axis < 0) {
        emm_trace_array *va = &s->tarrays[vt];
        uint64_t n = used(C) < va->count ? used(C) : va->count;
        add_part(s, C, vt, va->record_size, n);
        va->record_size += (uint32_t)C->stride;
    }
    s->info.narrays = s->ntarrays;
    return EMM_OK;
}
