/* Shared by the fetch tests: synthetic traces loaded into memory, and one
 * strategy simulated over them. */
#ifndef EMM_TESTS_FETCH_UTIL_H
#define EMM_TESTS_FETCH_UTIL_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "emm/mesh.h"
#include "emm/sim.h"
#include "emm/synth.h"
#include "emm/trace.h"

/* A trace held in memory; the reader stays open because the info points
 * into it. */
typedef struct loaded_trace {
    emm_trace_reader *reader;
    const emm_trace_info *info;
    emm_trace_record *recs;
    size_t n;
} loaded_trace;

static inline void load_trace(const char *path, loaded_trace *t)
{
    emm_error err;
    size_t cap = 1 << 16, got;
    REQUIRE(emm_trace_reader_open(path, &t->reader, &err) == EMM_OK);
    t->info = emm_trace_reader_info(t->reader);
    t->n = 0;
    t->recs = malloc(cap * sizeof *t->recs);
    REQUIRE(t->recs);
    for (;;) {
        if (t->n == cap) {
            cap *= 2;
            t->recs = realloc(t->recs, cap * sizeof *t->recs);
            REQUIRE(t->recs);
        }
        REQUIRE(emm_trace_read(t->reader, t->recs + t->n, cap - t->n, &got, &err) == EMM_OK);
        if (got == 0)
            break;
        t->n += got;
    }
}

static inline void free_trace(loaded_trace *t)
{
    emm_trace_reader_close(t->reader);
    free(t->recs);
}

/* Writes the synthetic trace of `so` over m to `path` and loads it. */
static inline void synth_load(const emm_mesh *m, const emm_synth_options *so, const char *path,
                              loaded_trace *t)
{
    emm_error err;
    if (emm_synth_trace(m, so, path, NULL, &err) != EMM_OK) {
        fprintf(stderr, "%s\n", err.message);
        exit(1);
    }
    load_trace(path, t);
    remove(path);
}

static inline emm_mesh *thesis_mesh(size_t faces)
{
    emm_gen_options o = {faces, EMM_DEFAULT_SEED, EMM_DENSITY_CLUSTERED, EMM_ORDER_INPUT};
    emm_mesh *m;
    emm_error err;
    if (emm_mesh_generate(&o, &m, &err) != EMM_OK) {
        fprintf(stderr, "%s\n", err.message);
        exit(1);
    }
    return m;
}

/* Simulates strategy `name` over t on machine mc; returns its status. */
static inline emm_status simulate(const emm_machine *mc, const char *name, const loaded_trace *t,
                                  emm_result *r, emm_error *err)
{
    emm_strategy s;
    emm_model *model;
    emm_status st;
    REQUIRE(emm_strategy_parse(name, &s, err) == EMM_OK);
    if ((st = emm_model_new(mc, &s, t->info, &model, err)) != EMM_OK)
        return st;
    emm_model_run(model, t->recs, t->n);
    emm_model_result(model, r);
    emm_model_free(model);
    return EMM_OK;
}

static inline void simulate_ok(const emm_machine *mc, const char *name, const loaded_trace *t,
                               emm_result *r)
{
    emm_error err;
    if (simulate(mc, name, t, r, &err) != EMM_OK) {
        fprintf(stderr, "%s: %s\n", name, err.message);
        exit(1);
    }
}

#endif
