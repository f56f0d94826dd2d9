/* The session's views of the answer's run beyond its totals: the trace
 * with the program counters of the accesses and the program's modules (for
 * emm annotate), the timeline (EMM_TIMELINE), and the source lines the
 * answer's DMA stalls came from, named in the summary and the report.
 *
 * The answer is known only at the end: the run's contest (or, for a
 * window-only capture, the window's) names it among the candidates. So
 * every model that may be the answer reports each DMA stall with the record
 * that waited (emm_model_stalls, as emm annotate's costed run would charge
 * it), summed by program counter per model (annotate.c, as emm annotate
 * does): a hash table of a few thousand counters each, the dropped ones'
 * left as they were. At finish the answer's counters are resolved to source
 * lines with libdw (srcline.c), off every capture path.
 *
 * A timeline is a stream of every event of one model, up to 50 MB; keeping
 * one per candidate until the answer is known is not affordable. The run's
 * records are written to a trace instead (the --trace file, or one of the
 * session's own in TMPDIR, removed at the end), and at finish the answer's
 * model alone runs them again with the timeline watching: the same records
 * through the same model give the same cycles, as emm replay's do. */
#include "session_internal.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "error.h"
#include "annotate.h"
#include "model.h"
#include "srcline.h"

/* A DMA stall of a model (on the thread running it): ctx is its annotation. */
static void on_stall(void *ctx, const emm_trace_record *r, uint64_t cycles)
{
    emm_annotation_add_stall(ctx, r->pc, cycles);
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

/* The trace the timeline replays when none was asked for: a name of its
 * own in TMPDIR (or /tmp), which the trace writer replaces whole. */
static bool private_trace(session *s)
{
    const char *dir = getenv("TMPDIR");
    if (!dir || !dir[0] || strlen(dir) > sizeof s->trace_path - 32)
        dir = "/tmp";
    snprintf(s->trace_path, sizeof s->trace_path, "%s/emm-timeline-XXXXXX", dir);
    int fd = mkstemp(s->trace_path);
    if (fd < 0) {
        emm_fail(&s->trace_error, EMM_ERR_IO, "%s: cannot make a file there", dir);
        s->trace_path[0] = '\0';
        return false;
    }
    close(fd);
    s->trace_private = true;
    return true;
}

void session_outputs_start(session *s)
{
    emm_trace_module *mods = NULL;
    uint32_t nmods = 0;
    bool owned = false;
    bool user = s->cfg.trace[0] != '\0';
    if (user)
        snprintf(s->trace_path, sizeof s->trace_path, "%s", s->cfg.trace);
    if (user || (s->cfg.timeline[0] && s->has_chosen)) {
        /* The private trace needs no program counters: only the timeline
         * reads it. */
        emm_trace_options o = {0, user && has_pcs(s), NULL, 0};
        if (o.pcs && program_modules(s, &mods, &nmods, &owned)) {
            o.modules = mods;
            o.nmodules = nmods;
        }
        if ((!user && !private_trace(s)) ||
            emm_trace_writer_open_ex(s->trace_path, s->tarrays, s->ntarrays, &s->info.geometry,
                                     &o, &s->trace, &s->trace_error) != EMM_OK) {
            s->trace_failed = true;
            s->trace = NULL;
        }
        if (owned)
            free(mods);
    }
    /* The stalls of every model that may be the answer, by pc. */
    if (!has_pcs(s) || !s->has_chosen ||
        !(s->annotations = calloc(s->nmodels ? s->nmodels : 1, sizeof *s->annotations)))
        return;
    for (size_t i = 0; i < s->nmodels; i++) {
        emm_model *m = emm_runner_model(s->runner, i);
        if (!m || s->mstrat[i].kind != EMM_STRATEGY_EMM || !session_may_answer(s, i) ||
            !(s->annotations[i] = emm_annotation_new()))
            continue;
        if (!emm_model_stalls(m, on_stall, s->annotations[i])) {
            emm_annotation_free(s->annotations[i]);
            s->annotations[i] = NULL;
        }
    }
}

void session_window_done(session *s)
{
    s->window_records = s->accesses;
}

void session_stall_lines(session *s)
{
    size_t a = session_answer_model(s);
    if (s->stall_lines_done || !s->annotations || a == SIZE_MAX || !s->annotations[a])
        return;
    s->stall_lines_done = true;
    emm_annotation *ann = s->annotations[a];
    emm_trace_module *mods = NULL;
    uint32_t nmods = 0;
    bool owned = false;
    s->stall_total = emm_annotation_total(ann)->cycles[EMM_BUCKET_DMA_STALL];
    if (!program_modules(s, &mods, &nmods, &owned))
        return;
    const emm_annotate_row *rows;
    if (emm_annotation_resolve(ann, mods, nmods, EMM_BUCKET_DMA_STALL, NULL) == EMM_OK) {
        size_t n = emm_annotation_lines(ann, &rows);
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
    char name[64];
    emm_strategy_format(&s->chosen, name, sizeof name);
    fprintf(out, "emm:   the answer's DMA stalls come from");
    for (size_t i = 0; i < s->nstall_lines; i++)
        fprintf(out, "%s %s:%d %s (%.0f%%)", i ? "," : "", base_name(s->stall_lines[i].file),
                s->stall_lines[i].line, s->stall_lines[i].function,
                100.0 * (double)s->stall_lines[i].cycles / (double)s->stall_total);
    if (s->cfg.trace[0])
        fprintf(out, "   (every line: emm annotate %s --strategy %s)\n", s->cfg.trace, name);
    else
        fprintf(out, "   (every line: rerun with --trace T, then emm annotate T --strategy %s)\n",
                name);
}

void session_write_stall_lines(json_writer *w, const session *s)
{
    if (!has_pcs(s) || !s->stall_lines_done)
        return;
    char name[64];
    emm_strategy_format(&s->chosen, name, sizeof name);
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

emm_status session_trace_close(session *s)
{
    if (s->trace) {
        emm_status st = emm_trace_writer_close(s->trace, &s->trace_error);
        s->trace = NULL;
        if (st != EMM_OK)
            s->trace_failed = true;
    }
    return s->trace_failed ? s->trace_error.status : EMM_OK;
}

/* The answer's model over the trace, its clock read at each of marks[0..n)
 * (records run, ascending) into clock[]. */
static emm_status replay_marked(session *s, emm_model *m, const uint64_t *marks, uint64_t *clock,
                                size_t n, emm_error *err)
{
    enum { BATCH = 65536 };
    emm_trace_reader *r = NULL;
    emm_trace_record *buf = malloc(BATCH * sizeof *buf);
    emm_status st = buf ? emm_trace_reader_open(s->trace_path, &r, err)
                        : emm_fail(err, EMM_ERR_NOMEM, "out of memory");
    uint64_t done = 0;
    size_t k = 0;
    while (st == EMM_OK) {
        size_t got;
        if ((st = emm_trace_read(r, buf, BATCH, &got, err)) != EMM_OK || got == 0)
            break;
        for (size_t off = 0; off < got;) {
            size_t part = got - off;
            if (k < n && marks[k] >= done && marks[k] - done < part)
                part = (size_t)(marks[k] - done);
            emm_model_run(m, buf + off, part);
            off += part;
            done += part;
            for (; k < n && marks[k] <= done; k++)
                clock[k] = emm_model_total(m);
        }
    }
    for (; k < n; k++)
        clock[k] = emm_model_total(m);
    if (r)
        emm_trace_reader_close(r);
    free(buf);
    return st;
}

/* A private trace is removed once the timeline has read it (the shim's
 * session is not freed at the program's exit). */
static void drop_private_trace(session *s)
{
    if (s->trace_private)
        unlink(s->trace_path);
    s->trace_private = false;
}

static emm_status timeline_write(session *s, emm_error *err)
{
    const char *as = session_source(s, EMM_CONFIG_TIMELINE);
    emm_error e;
    if (!s->cfg.timeline[0] || !s->has_chosen)
        return EMM_OK;
    if (s->trace_failed)
        return emm_fail(err, s->trace_error.status, "%s: the run's records, which it is "
                        "simulated from, could not be kept: %s", as, s->trace_error.message);
    emm_trace_reader *r = NULL;
    emm_model *m = NULL;
    emm_timeline *t = NULL;
    emm_status st = emm_trace_reader_open(s->trace_path, &r, &e);
    if (st == EMM_OK)
        st = emm_model_new(s->machine, &s->chosen, emm_trace_reader_info(r), &m, &e);
    if (r)
        emm_trace_reader_close(r);
    if (st == EMM_OK)
        st = emm_timeline_open(s->cfg.timeline, s->machine, &s->chosen, 0, &t, &e);
    /* The window's end, then each later phase's detection. */
    uint64_t marks[SESSION_MAX_PHASES + 1], clock[SESSION_MAX_PHASES + 1];
    size_t n = 0;
    marks[n++] = s->window_records;
    for (int i = 1; i < s->nphases; i++)
        marks[n++] = s->phases[i].detected;
    if (st == EMM_OK) {
        emm_timeline_watch(t, m);
        st = replay_marked(s, m, marks, clock, n, &e);
    }
    if (st != EMM_OK) {
        emm_timeline_abort(t, m);
        emm_model_free(m);
        return emm_fail(err, st, "%s: %s", as, e.message);
    }
    uint64_t total = emm_model_total(m);
    char name[96];
    emm_timeline_phase(t, "the profiling window (replayed at the decision)", 0, clock[0]);
    /* Phases after the window: from their detection to the next one's, or
     * the end. */
    for (int i = 1; i <= s->nphases; i++) {
        uint64_t start = clock[i - 1], end = i < s->nphases ? clock[i] : total;
        if (i == 1)
            snprintf(name, sizeof name, "run after the window: %s", s->phases[0].pattern);
        else
            snprintf(name, sizeof name, "phase %d: %s", i - 1, s->phases[i - 1].pattern);
        emm_timeline_phase(t, name, start, end);
    }
    st = emm_timeline_close(t, m, total, &e);
    emm_model_free(m);
    return st == EMM_OK ? EMM_OK : emm_fail(err, st, "%s: %s", as, e.message);
}

emm_status session_timeline_write(session *s, emm_error *err)
{
    emm_status st = timeline_write(s, err);
    drop_private_trace(s);
    return st;
}

void session_lines_free(session *s)
{
    if (s->trace)
        emm_trace_writer_abort(s->trace);
    s->trace = NULL;
    drop_private_trace(s);
    for (size_t i = 0; s->annotations && i < s->nmodels; i++)
        emm_annotation_free(s->annotations[i]);
    free(s->annotations);
    s->annotations = NULL;
}
