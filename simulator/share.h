/* Internal: what the models of one trace share (simulator/runner.c builds
 * every model of a sweep with one share). A layout is the same for every
 * fetch scheme over it, and its build is the expensive part of a model, so
 * it is built once per (kind, cell, record sizes) and kept while a model
 * uses it; the triangles' vertex ids are copied once. Thread-safe: models
 * are built in parallel, and a second model asking for a layout being built
 * waits for the first build. */
#ifndef EMM_SIM_SHARE_H
#define EMM_SIM_SHARE_H

#include "emm/layout.h"
#include "emm/trace.h"

typedef struct emm_model_share emm_model_share;

/* A share with one reference (NULL when memory runs out). */
emm_model_share *emm_model_share_new(void);
void emm_model_share_ref(emm_model_share *sh);
/* Keeps every layout built until the share is freed, instead of freeing
 * one when its last model goes: for a caller that builds models of the
 * same trace several times (the decision's sweeps, then the session's
 * models, then its probes). */
void emm_model_share_keep(emm_model_share *sh);
/* Drops a reference; the last one frees the share. NULL is allowed. */
void emm_model_share_unref(emm_model_share *sh);

/* The layout `opt` describes over the geometry of trace `t` (every call on
 * one share must pass the same geometry), built on first request; `name`
 * names it in errors, which are emm_layout_build's. The caller holds a
 * reference until emm_model_share_release. */
emm_status emm_model_share_layout(emm_model_share *sh, const emm_trace_info *t,
                                  const emm_layout_options *opt, const char *name,
                                  const emm_layout **out, emm_error *err);
void emm_model_share_release(emm_model_share *sh, const emm_layout *l);

/* A CELL for layout l's kind whose cells fit `local` bytes
 * (emm_layout_fit_cell over t's geometry), found once per layout and local
 * store and remembered: the models of one layout and cell size that do not
 * fit, one per fetch scheme, share the search's trial builds. */
emm_status emm_model_share_fit(emm_model_share *sh, const emm_trace_info *t, const emm_layout *l,
                               uint64_t local, uint32_t *suggest, const char *name,
                               emm_error *err);

/* Data derived from layout l alone for the key (a, b) — a model's tables
 * that every model over l would compute alike — built by `build` on the
 * first request, under the share's lock, and kept as long as l is: *out is
 * shared and read-only, freed by `destroy`. Fails only as build does. */
typedef emm_status (*emm_share_build_fn)(const emm_layout *l, uint64_t a, uint64_t b, void **out,
                                         emm_error *err);
emm_status emm_model_share_derived(emm_model_share *sh, const emm_layout *l, uint64_t a,
                                   uint64_t b, emm_share_build_fn build, void (*destroy)(void *),
                                   const void **out, emm_error *err);

/* The triangles' vertex ids, 3 per triangle, copied from t once; NULL
 * (with err) when memory runs out. Lives as long as the share. */
const int32_t *emm_model_share_triangles(emm_model_share *sh, const emm_trace_info *t,
                                         emm_error *err);

#endif
