/* What the models of one trace share (share.h): layouts built once and kept
 * while used, the triangles' vertex ids copied once. */
#include "share.h"

#include <pthread.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "layout_internal.h"

enum { BUILDING, READY, FAILED };

struct entry {
    emm_layout_options opt; /* the key: kind, cell, record sizes */
    emm_layout *layout;
    int state;
    unsigned refs;
    emm_error failure;
};

/* A CELL that fits a local store, found for a layout once
 * (emm_model_share_fit). */
struct fit {
    emm_layout_options opt; /* the layout's key */
    uint64_t local;
    uint32_t suggest;
};

/* Data derived from a layout (emm_model_share_derived). */
struct derived {
    const emm_layout *layout;
    uint64_t a, b;
    void *data;
    void (*destroy)(void *);
};

struct emm_model_share {
    int refs; /* atomic */
    struct derived *d;
    size_t nd, capd;
    struct fit *fits;
    size_t nfits, capfits;
    pthread_mutex_t mu;
    pthread_cond_t built;
    struct entry *e;
    size_t n, cap;
    int32_t *tri;
    bool tri_done;
    /* The geometry every layout starts from, found on the first build. */
    emm_layout_geometry geometry;
    bool geometry_done;
    bool keep; /* layouts stay built until the share goes */
};

emm_model_share *emm_model_share_new(void)
{
    emm_model_share *sh = calloc(1, sizeof *sh);
    if (!sh)
        return NULL;
    sh->refs = 1;
    pthread_mutex_init(&sh->mu, NULL);
    pthread_cond_init(&sh->built, NULL);
    return sh;
}

void emm_model_share_keep(emm_model_share *sh)
{
    pthread_mutex_lock(&sh->mu);
    sh->keep = true;
    pthread_mutex_unlock(&sh->mu);
}

void emm_model_share_ref(emm_model_share *sh)
{
    __atomic_add_fetch(&sh->refs, 1, __ATOMIC_RELAXED);
}

void emm_model_share_unref(emm_model_share *sh)
{
    if (!sh || __atomic_sub_fetch(&sh->refs, 1, __ATOMIC_ACQ_REL) != 0)
        return;
    for (size_t i = 0; i < sh->nd; i++)
        sh->d[i].destroy(sh->d[i].data);
    free(sh->d);
    for (size_t i = 0; i < sh->n; i++)
        emm_layout_free(sh->e[i].layout);
    free(sh->e);
    free(sh->fits);
    free(sh->tri);
    emm_layout_geometry_free(&sh->geometry);
    pthread_cond_destroy(&sh->built);
    pthread_mutex_destroy(&sh->mu);
    free(sh);
}

/* The triangles' vertex ids, copied from t once (under sh->mu); NULL when
 * memory runs out. */
static const int32_t *triangles(emm_model_share *sh, const emm_trace_info *t)
{
    const emm_trace_geometry *g = &t->geometry;
    if (!sh->tri_done) {
        sh->tri = malloc((g->nt ? 3 * (size_t)g->nt : 1) * sizeof *sh->tri);
        if (sh->tri && g->nt)
            memcpy(sh->tri, g->tri, 3 * (size_t)g->nt * sizeof *sh->tri);
        sh->tri_done = sh->tri != NULL;
    }
    return sh->tri;
}

/* The share's geometry, found once (under sh->mu), over its own copy of
 * the triangles, which lives as long as the share. */
static emm_status geometry(emm_model_share *sh, const emm_trace_info *t, const char *name,
                           const emm_layout_geometry **out, emm_error *err)
{
    const emm_trace_geometry *g = &t->geometry;
    if (!sh->geometry_done) {
        const int32_t *tri = g->nt ? triangles(sh, t) : g->tri;
        if (!tri)
            return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", name);
        emm_status st = emm_layout_geometry_init(&sh->geometry, g->xyz, (size_t)g->nv, tri,
                                                 (size_t)g->nt, name, err);
        if (st != EMM_OK)
            return st;
        sh->geometry_done = true;
    }
    *out = &sh->geometry;
    return EMM_OK;
}

static bool same_key(const emm_layout_options *a, const emm_layout_options *b)
{
    return a->kind == b->kind && a->cell == b->cell && a->vertex_bytes == b->vertex_bytes &&
           a->triangle_bytes == b->triangle_bytes && a->local_store == b->local_store &&
           a->vertex_cells == b->vertex_cells && a->pointer_bytes == b->pointer_bytes;
}

emm_status emm_model_share_layout(emm_model_share *sh, const emm_trace_info *t,
                                  const emm_layout_options *opt, const char *name,
                                  const emm_layout **out, emm_error *err)
{
    pthread_mutex_lock(&sh->mu);
    const emm_layout_geometry *g = NULL;
    emm_status gst = emm_layout_check_cell(opt, name, err);
    if (gst == EMM_OK)
        gst = geometry(sh, t, name, &g, err);
    if (gst != EMM_OK) {
        pthread_mutex_unlock(&sh->mu);
        return gst;
    }
    size_t i = 0;
    while (i < sh->n && !same_key(&sh->e[i].opt, opt))
        i++;
    if (i < sh->n) {
        struct entry *e = &sh->e[i];
        while (e = &sh->e[i], e->state == BUILDING)
            pthread_cond_wait(&sh->built, &sh->mu);
        if (e->state == FAILED) {
            if (err)
                *err = e->failure;
            emm_status st = e->failure.status;
            pthread_mutex_unlock(&sh->mu);
            return st;
        }
        if (e->layout) {
            e->refs++;
            *out = e->layout;
            pthread_mutex_unlock(&sh->mu);
            return EMM_OK;
        }
        /* Built once and freed since: build again in this entry. */
        e->state = BUILDING;
    } else {
        if (sh->n == sh->cap) {
            size_t cap = sh->cap ? 2 * sh->cap : 16;
            struct entry *ne = realloc(sh->e, cap * sizeof *ne);
            if (!ne) {
                pthread_mutex_unlock(&sh->mu);
                return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", name);
            }
            sh->e = ne;
            sh->cap = cap;
        }
        memset(&sh->e[sh->n], 0, sizeof sh->e[sh->n]);
        sh->e[sh->n].opt = *opt;
        sh->e[sh->n].state = BUILDING;
        i = sh->n++;
    }
    pthread_mutex_unlock(&sh->mu);

    /* Built outside the lock: other layouts build meanwhile. */
    emm_layout *l = NULL;
    emm_error e;
    emm_status st = emm_layout_build_from(g, opt, name, &l, &e);

    pthread_mutex_lock(&sh->mu);
    struct entry *en = &sh->e[i]; /* the array may have moved */
    if (st == EMM_OK) {
        en->layout = l;
        en->refs = 1;
        en->state = READY;
        *out = l;
    } else {
        en->failure = e;
        en->state = FAILED;
        if (err)
            *err = e;
    }
    pthread_cond_broadcast(&sh->built);
    pthread_mutex_unlock(&sh->mu);
    return st;
}

/* Frees what was derived from layout l (under sh->mu). */
static void drop_derived(emm_model_share *sh, const emm_layout *l)
{
    size_t m = 0;
    for (size_t i = 0; i < sh->nd; i++) {
        if (sh->d[i].layout == l)
            sh->d[i].destroy(sh->d[i].data);
        else
            sh->d[m++] = sh->d[i];
    }
    sh->nd = m;
}

void emm_model_share_release(emm_model_share *sh, const emm_layout *l)
{
    emm_layout *gone = NULL;
    pthread_mutex_lock(&sh->mu);
    for (size_t i = 0; i < sh->n; i++)
        if (sh->e[i].layout == l && --sh->e[i].refs == 0 && !sh->keep) {
            gone = sh->e[i].layout;
            sh->e[i].layout = NULL;
            sh->e[i].state = READY;
            drop_derived(sh, gone);
        }
    pthread_mutex_unlock(&sh->mu);
    emm_layout_free(gone);
}

emm_status emm_model_share_derived(emm_model_share *sh, const emm_layout *l, uint64_t a,
                                   uint64_t b, emm_share_build_fn build, void (*destroy)(void *),
                                   const void **out, emm_error *err)
{
    pthread_mutex_lock(&sh->mu);
    for (size_t i = 0; i < sh->nd; i++)
        if (sh->d[i].layout == l && sh->d[i].a == a && sh->d[i].b == b &&
            sh->d[i].destroy == destroy) {
            *out = sh->d[i].data;
            pthread_mutex_unlock(&sh->mu);
            return EMM_OK;
        }
    void *data = NULL;
    emm_status st = EMM_OK;
    if (sh->nd == sh->capd) {
        size_t cap = sh->capd ? 2 * sh->capd : 16;
        struct derived *nd = realloc(sh->d, cap * sizeof *nd);
        if (!nd)
            st = emm_fail(err, EMM_ERR_NOMEM, "out of memory for a layout's tables");
        else
            sh->d = nd, sh->capd = cap;
    }
    if (st == EMM_OK && (st = build(l, a, b, &data, err)) == EMM_OK) {
        sh->d[sh->nd++] = (struct derived){l, a, b, data, destroy};
        *out = data;
    }
    pthread_mutex_unlock(&sh->mu);
    return st;
}

const int32_t *emm_model_share_triangles(emm_model_share *sh, const emm_trace_info *t,
                                         emm_error *err)
{
    pthread_mutex_lock(&sh->mu);
    const int32_t *tri = triangles(sh, t);
    pthread_mutex_unlock(&sh->mu);
    if (!tri)
        emm_fail(err, EMM_ERR_NOMEM, "out of memory for the triangles' vertex ids");
    return tri;
}

emm_status emm_model_share_fit(emm_model_share *sh, const emm_trace_info *t, const emm_layout *l,
                               uint64_t local, uint32_t *suggest, const char *name,
                               emm_error *err)
{
    const emm_layout_options *opt = emm_layout_get_options(l);
    pthread_mutex_lock(&sh->mu);
    for (size_t i = 0; i < sh->nfits; i++)
        if (sh->fits[i].local == local && same_key(&sh->fits[i].opt, opt)) {
            *suggest = sh->fits[i].suggest;
            pthread_mutex_unlock(&sh->mu);
            return EMM_OK;
        }
    const emm_layout_geometry *g = NULL;
    emm_status st = geometry(sh, t, name, &g, err);
    pthread_mutex_unlock(&sh->mu);
    if (st != EMM_OK)
        return st;
    /* Found outside the lock: two models may both search, and agree. */
    st = emm_layout_fit_cell(g, l, local, suggest, name, err);
    if (st != EMM_OK)
        return st;
    pthread_mutex_lock(&sh->mu);
    if (sh->nfits == sh->capfits) {
        size_t cap = sh->capfits ? 2 * sh->capfits : 8;
        struct fit *nf = realloc(sh->fits, cap * sizeof *nf);
        if (nf) {
            sh->fits = nf;
            sh->capfits = cap;
        }
    }
    if (sh->nfits < sh->capfits) /* else not remembered: found again next time */
        sh->fits[sh->nfits++] = (struct fit){*opt, local, *suggest};
    pthread_mutex_unlock(&sh->mu);
    return EMM_OK;
}
