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
    free(s->face_tri);
    s->face_tri = NULL;
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

/* The most sides a face may have: a longer cycle is taken for a broken one. */
#define MAX_SIDES 64

/* Walks face f's cycle from half-edge h0 into cyc (its length into *n):
 * half-edges of face f, each in no other face's cycle, to-vertices in
 * range, prev the inverse of next when there is prev, back to h0 in at
 * least 3 and at most MAX_SIDES steps. Marks them as face f's (he_owner). */
static emm_status walk_face(session *s, session_array *H, uint64_t nh, uint64_t f, int64_t h0,
                            const session_array *v, int64_t *cyc, int *n, emm_error *err)
{
    int64_t h = h0;
    bool prev = (H->hhas & 1u << F_PREV) != 0;
    int c = 0;
    char path[160];
    for (;;) {
        int64_t face = index_at(s, H, (uint64_t)h, F_FACE);
        if (face != (int64_t)f)
            REFUSE(H, "half-edge %lld of face %llu's cycle belongs to face %lld", (long long)h,
                   (unsigned long long)f, (long long)face);
        int64_t to = index_at(s, H, (uint64_t)h, F_TO);
        if (to < 0 || (uint64_t)to >= v->count || to > INT32_MAX)
            REFUSE(H, "half-edge %lld points to vertex %lld, outside the %llu vertex records",
                   (long long)h, (long long)to, (unsigned long long)v->count);
        if (s->he_owner[h] != UINT32_MAX) {
            size_t at = 0;
            for (int k = 0; k < c && at < sizeof path; k++)
                at += (size_t)snprintf(path + at, sizeof path - at, "%lld -> ",
                                       (long long)cyc[k]);
            if (s->he_owner[h] == (uint32_t)f)
                REFUSE(H, "half-edge %lld's cycle does not close: it comes back to half-edge "
                          "%lld, not to %lld (%s%lld)",
                       (long long)h0, (long long)h, (long long)h0, path, (long long)h);
            REFUSE(H, "half-edge %lld is in the cycles of faces %u and %llu", (long long)h,
                   s->he_owner[h], (unsigned long long)f);
        }
        if (c == MAX_SIDES)
            REFUSE(H, "half-edge %lld's cycle does not close in %d steps", (long long)h0,
                   MAX_SIDES);
        s->he_owner[h] = (uint32_t)f;
        cyc[c++] = h;
        int64_t next = index_at(s, H, (uint64_t)h, F_NEXT);
        if (next < 0 || (uint64_t)next >= nh)
            REFUSE(H, "half-edge %lld's next is %lld, outside the %llu half-edges in use",
                   (long long)h, (long long)next, (unsigned long long)nh);
        if (prev && index_at(s, H, (uint64_t)next, F_PREV) != h)
            REFUSE(H, "half-edge %lld's prev is %lld, not %lld whose next it is", (long long)next,
                   (long long)index_at(s, H, (uint64_t)next, F_PREV), (long long)h);
        if (next == h0)
            break;
        h = next;
    }
    if (c < 3)
        REFUSE(H, "face %llu's cycle has %d half-edge%s (a face has 3 or more)",
               (unsigned long long)f, c, c == 1 ? "" : "s");
    *n = c;
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
    if (nf > nh / 3)
        REFUSE(F ? F : H, "%llu faces for %llu half-edges (a face has 3 or more)",
               (unsigned long long)nf, (unsigned long long)nh);
    session_halfedge_free(s);
    s->he_owner = malloc((nh ? nh : 1) * sizeof *s->he_owner);
    s->he_pos = calloc(nh ? nh : 1, 1);
    s->face_tri = malloc((nf ? nf : 1) * sizeof *s->face_tri);
    uint32_t *start = malloc((nf ? nf : 1) * sizeof *start);
    if (!s->he_owner || !s->he_pos || !s->face_tri || !start) {
        free(start);
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the geometry", s->program);
    }
    memset(s->he_owner, 0xff, (nh ? nh : 1) * sizeof *s->he_owner);
    /* Each face's first half-edge: its record's, or the first that names it. */
    memset(start, 0xff, (nf ? nf : 1) * sizeof *start);
    for (uint64_t f = 0; F && f < nf; f++) {
        int64_t h0 = index_at(s, F, f, 0);
        if (h0 < 0 || (uint64_t)h0 >= nh) {
            free(start);
            REFUSE(F, "face %llu's half-edge is %lld, outside the %llu half-edges in use",
                   (unsigned long long)f, (long long)h0, (unsigned long long)nh);
        }
        start[f] = (uint32_t)h0;
    }
    for (uint64_t h = 0; !F && h < nh; h++) {
        int64_t f = index_at(s, H, h, F_FACE);
        if (f >= 0 && start[f] == UINT32_MAX)
            start[f] = (uint32_t)h;
    }
    /* The cycles, checked; a face of n sides is n - 2 triangles, a fan
     * from its first corner. */
    int64_t cyc[MAX_SIDES];
    uint64_t nt = 0;
    emm_status st = EMM_OK;
    for (uint64_t f = 0; f < nf && st == EMM_OK; f++) {
        int n = 0;
        if (start[f] == UINT32_MAX) {
            free(start);
            REFUSE(H, "no half-edge names face %llu (of %llu)", (unsigned long long)f,
                   (unsigned long long)nf);
        }
        st = walk_face(s, H, nh, f, start[f], v, cyc, &n, err);
        s->face_tri[f] = (uint32_t)nt;
        nt += (uint64_t)n - 2;
    }
    if (st == EMM_OK && nt > INT32_MAX / 3)
        st = emm_fail(err, EMM_ERR_RANGE, "%s: %llu triangles (at most %d)", s->program,
                      (unsigned long long)nt, INT32_MAX / 3);
    s->tri = st == EMM_OK ? malloc((nt ? 3 * nt : 1) * sizeof *s->tri) : NULL;
    if (st == EMM_OK && !s->tri)
        st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the geometry", s->program);
    for (uint64_t f = 0; f < nf && st == EMM_OK; f++) {
        /* Walked once already: the half-edges are the face's. */
        int64_t h = start[f];
        int n = 0;
        do {
            cyc[n++] = h;
            h = index_at(s, H, (uint64_t)h, F_NEXT);
        } while (h != (int64_t)start[f] && n < MAX_SIDES);
        uint32_t t0 = s->face_tri[f];
        for (int i = 0; i < n; i++) {
            s->he_owner[cyc[i]] = t0 + (uint32_t)(i < 3 ? 0 : i - 2);
            s->he_pos[cyc[i]] = (uint8_t)(i < 3 ? i : 2);
        }
        int32_t c0 = (int32_t)index_at(s, H, (uint64_t)cyc[0], F_TO);
        for (int k = 0; k + 2 < n; k++) {
            int32_t *t = s->tri + 3 * (t0 + (uint32_t)k);
            t[0] = c0;
            t[1] = (int32_t)index_at(s, H, (uint64_t)cyc[k + 1], F_TO);
            t[2] = (int32_t)index_at(s, H, (uint64_t)cyc[k + 2], F_TO);
        }
    }
    free(start);
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
    for (uint64_t i = 0; i < 3 * nt; i++)
        if (s->tri[i] > *highest)
            *highest = s->tri[i];
    *nt_out = nt;
    s->nfaces = nf;
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
             "%sthe triangles are the %s faces of the half-edge mesh of %s (%s half-edges)%s",
             at ? "; " : "", emm_grouped(nf, a), session_origin(s, H, o, sizeof o),
             emm_grouped(nh, b),
             nt > nf ? ", its polygons cut into fans of triangles, each face's record and "
                       "first three half-edges with its first triangle"
                     : "");
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
    if (F) {
        session_part *fp = add_part(s, F, t, 0, s->nfaces);
        fp->remap = s->face_tri;
    }
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
