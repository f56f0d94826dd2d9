/* The session's views of the chosen strategy's run beyond its totals: the
 * trace with the program counters of the accesses and the program's
 * modules (for emm annotate), the timeline (EMM_TIMELINE), and the source
 * lines its DMA stalls came from, named in the summary and the report.
 *
 * The chosen model reports each DMA stall with the record that waited
 * (emm_model_stalls, as emm annotate's costed run would charge it), summed
 * by program counter (annotate.c, as emm annotate does); at finish the counters are
 * resolved to source lines with libdw (srcline.c), off every capture path. */
#include "session_internal.h"

#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "annotate.h"
#include "model.h"
#include "srcline.h"

/* A DMA stall of the chosen model (on the thread running it). */
static void on_stall(void *ctx, const emm_trace_record *r, uint64_t cycles)
{
    session *s = ctx;
    emm_annotation_add_stall(s->annotation, r->pc, cycles);
}

/* The capture records program counters: sancov's hooks' return addresses,
 * the valgrind tool's instruction addresses. */
static bool has_pcs(const session *s)
{
    return (emm_capture_caps(s->capture) & EMM_CAP_PCS) != 0;
}

/* A program in another process: asks for its objects again; those it
 * reported last stay when it cannot answer now (it no longer waits). */
static void refresh_modules(session *s)
{
    emm_trace_module *m = NULL;
    uint32_t n = 0;
    if (s->memory->modules && s->memory->modules(s->memory->ctx, &m, &n)) {
        free(s->modules);
        s->modules = m;
        s->nmodules = n;
    }
}

/* The program's loaded objects: this process's, or those a program in
 * another process reported (s->modules, borrowed: *owned is false). */
static bool program_modules(session *s, emm_trace_module **mods, uint32_t *n, bool *owned)
{
    *owned = !s->memory;
    if (s->memory) {
        refresh_modules(s);
        *mods = s->modules;
        *n = s->nmodules;
        return s->modules != NULL;
    }
    return emm_process_modules(mods, n, NULL) == EMM_OK;
}

void session_outputs_prepare(session *s)
{
    if (s->cfg.trace[0] && has_pcs(s) && s->memory)
        refresh_modules(s);
}

void session_outputs_start(session *s)
{
    emm_trace_module *mods = NULL;
    uint32_t nmods = 0;
    bool owned = false;
    if (s->cfg.trace[0]) {
        emm_trace_options o = {0, has_pcs(s), NULL, 0};
        if (has_pcs(s) && program_modules(s, &mods, &nmods, &owned)) {
            o.modules = mods;
            o.nmodules = nmods;
        }
        if (emm_trace_writer_open_ex(s->cfg.trace, s->tarrays, s->ntarrays, &s->info.geometry, &o,
                                     &s->trace, &s->trace_error) != EMM_OK) {
            s->trace_failed = true;
            s->trace = NULL;
        }
        if (owned)
            free(mods);
    }
    emm_model *chosen = s->has_chosen ? emm_runner_model(s->runner, 0) : NULL;
    if (s->cfg.timeline[0] && chosen) {
        if (emm_timeline_open(s->cfg.timeline, s->machine, &s->chosen, 0, &s->timeline,
                              &s->timeline_error) != EMM_OK) {
            s->timeline_failed = true;
            s->timeline = NULL;
        } else {
            emm_timeline_watch(s->timeline, chosen);
        }
    }
    if (has_pcs(s) && chosen && s->chosen.kind == EMM_STRATEGY_EMM &&
        (s->annotation = emm_annotation_new()) != NULL && !emm_model_stalls(chosen, on_stall, s)) {
        emm_annotation_free(s->annotation);
        s->annotation = NULL;
    }
}

void session_window_done(session *s)
{
    emm_model *chosen = s->has_chosen ? emm_runner_model(s->runner, 0) : NULL;
    if (!chosen)
        return;
    emm_result r;
    emm_model_result(chosen, &r);
    s->window_cycles = r.total;
}

void session_stall_lines(session *s)
{
    if (s->stall_lines_done || !s->annotation)
        return;
    s->stall_lines_done = true;
    emm_trace_module *mods = NULL;
    uint32_t nmods = 0;
    bool owned = false;
    s->stall_total = emm_annotation_total(s->annotation)->cycles[EMM_BUCKET_DMA_STALL];
    if (!program_modules(s, &mods, &nmods, &owned))
        return;
    const emm_annotate_row *rows;
    if (emm_annotation_resolve(s->annotation, mods, nmods, EMM_BUCKET_DMA_STALL, NULL) == EMM_OK) {
        size_t n = emm_annotation_lines(s->annotation, &rows);
        for (size_t i = 0; i < n && s->nstall_lines < SESSION_STALL_LINES; i++) {
            if (!rows[i].file || !rows[i].cycles[EMM_BUCKET_DMA_STALL])
                continue;
            struct stall_line *l = &s->stall_lines[s->nstall_lines++];
            snprintf(l->file, sizeof l->file, "%s", rows[i].file);
            snprintf(l->function, sizeof l->function, "%s",
                     rows[i].function ? rows[i].function : "?");
            l->line = rows[i].line;
            l->cycles = rows[i].cycles[EMM_BUCKET_DMA_STALL];
        }
    }
    if (owned)
        free(mods);
}

/* A path's last component: the summary names lines as a compiler would. */
static const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

void session_print_stall_lines(const session *s, FILE *out)
{
    if (!s->nstall_lines || !s->stall_total)
        return;
    /* The stalls were counted on the window's choice (model 0); when the
     * run's contest answered otherwise they are not the answer's: say how
     * to see the answer's instead of naming another strategy's lines. */
    if (session_overruled(s)) {
        if (s->chosen.kind != EMM_STRATEGY_EMM)
            return; /* direct reads (a cache) move no cell: no DMA stalls */
        char name[64];
        emm_strategy_format(&s->chosen, name, sizeof name);
        fprintf(out, "emm:   the answer's DMA stalls by source line: emm annotate %s --strategy %s\n",
                s->cfg.trace[0] ? s->cfg.trace : "TRACE (rerun with --trace TRACE)", name);
        return;
    }
    fprintf(out, "emm:   the answer's DMA stalls come from");
    for (size_t i = 0; i < s->nstall_lines; i++)
        fprintf(out, "%s %s:%d %s (%.0f%%)", i ? "," : "", base_name(s->stall_lines[i].file),
                s->stall_lines[i].line, s->stall_lines[i].function,
                100.0 * (double)s->stall_lines[i].cycles / (double)s->stall_total);
    fprintf(out, "   (emm annotate TRACE for every line)\n");
}

void session_write_stall_lines(json_writer *w, const session *s)
{
    if (!has_pcs(s) || !s->stall_lines_done)
        return;
    char name[64];
    const emm_strategy *pred = session_overruled(s);
    emm_strategy_format(pred ? pred : &s->chosen, name, sizeof name);
    json_key(w, "stall_lines_strategy");
    json_string(w, name);
    json_key(w, "stall_lines");
    json_begin_array(w);
    for (size_t i = 0; i < s->nstall_lines; i++) {
        json_begin_object(w);
        json_key(w, "file");
        json_string(w, s->stall_lines[i].file);
        json_key(w, "line");
        json_u64(w, (uint64_t)s->stall_lines[i].line);
        json_key(w, "function");
        json_string(w, s->stall_lines[i].function);
        json_key(w, "dma_stall");
        json_u64(w, s->stall_lines[i].cycles);
        json_end_object(w);
    }
    json_end_array(w);
}

emm_status session_timeline_close(session *s, emm_error *err)
{
    if (s->timeline_failed)
        return emm_fail(err, s->timeline_error.status, "%s: %s",
                        session_source(s, EMM_CONFIG_TIMELINE), s->timeline_error.message);
    if (!s->timeline)
        return EMM_OK;
    emm_model *chosen = emm_runner_model(s->runner, 0);
    emm_result r;
    emm_model_result(chosen, &r);
    char name[96];
    emm_timeline_phase(s->timeline, "the profiling window (replayed at the decision)", 0,
                       s->window_cycles);
    /* Phases after the window: from their detection (the chosen model's
     * clock then) to the next one's, or the end. */
    uint64_t start = s->window_cycles;
    for (int i = 1; i <= s->nphases; i++) {
        uint64_t end = i < s->nphases ? s->phases[i].chosen_at : r.total;
        if (i == 1)
            snprintf(name, sizeof name, "run after the window: %s", s->phases[0].pattern);
        else
            snprintf(name, sizeof name, "phase %d: %s", i - 1, s->phases[i - 1].pattern);
        emm_timeline_phase(s->timeline, name, start, end);
        start = end;
    }
    emm_status st = emm_timeline_close(s->timeline, chosen, r.total, err);
    s->timeline = NULL;
    return st;
}

void session_lines_free(session *s)
{
    if (s->timeline)
        emm_timeline_abort(s->timeline, emm_runner_model(s->runner, 0));
    s->timeline = NULL;
    emm_annotation_free(s->annotation);
    s->annotation = NULL;
}
