/* The session's output (docs/design.md "The shim and the session", Output): the summary on
 * stderr, the JSON report of docs/report.md with the session's own keys
 * (program, capture, pattern, strategy, decision, window, profile), and the
 * CSV of the window's profile. Files are written whole or not at all
 * (core/outfile.h). */
#include "session_internal.h"

#include <math.h>
#include <string.h>
#include <sys/stat.h>

#include "error.h"
#include "json.h"
#include "outfile.h"
#include "parse.h"
#include "report.h"

static const char *source_name(enum decision_source src)
{
    switch (src) {
    case FROM_CONFIG:
        return "configured";
    case FROM_TABLE:
        return "table";
    case FROM_CHECKED:
        return "checked";
    case FROM_SIMULATION:
        return "simulated";
    default:
        return "none";
    }
}

typedef struct report_ctx {
    const session *s;
    const emm_result *res;    /* every model, in order */
    const emm_error *skipped; /* status != EMM_OK: could not be built */
    size_t n;
} report_ctx;

/* The most profile points the report carries: enough for a plot of the
 * curve (emm plot, thesis Fig. 5.5), little enough for a small report. The
 * first REPORT_PROFILE_HEAD are all kept, for a plot on a log axis. */
#define REPORT_PROFILE_POINTS 2000
#define REPORT_PROFILE_HEAD 500

static void write_features(json_writer *w, const double f[EMM_FEATURES])
{
    json_begin_array(w);
    for (int k = 0; k < EMM_FEATURES; k++)
        json_double(w, f[k]);
    json_end_array(w);
}

/* "profile" (docs/report.md): the window's D_i downsampled to at most
 * REPORT_PROFILE_POINTS points (all of the first REPORT_PROFILE_HEAD, then
 * evenly spaced, the last one always included); m_end, the
 * mean of D_i / i over the last n/32 accesses that features 11-16 divide
 * by (docs/profile.md), so a plot can draw a sample's shape at this
 * window's scale; the features, and the nearest sample's. */
static void write_profile(json_writer *w, const session *s)
{
    const size_t head = REPORT_PROFILE_HEAD, rest = REPORT_PROFILE_POINTS - REPORT_PROFILE_HEAD;
    size_t n = s->nD, step = n > REPORT_PROFILE_POINTS ? (n - head + rest - 1) / rest : 1;
    json_key(w, "profile");
    if (n == 0) {
        json_null(w);
        return;
    }
    json_begin_object(w);
    json_key(w, "accesses");
    json_u64(w, n);
    double sum = 0;
    size_t a = n - n / 32 > 1 ? n - n / 32 : 1, b = n > a ? n : a + 1, cnt = 0;
    for (size_t i = a; i < b && i < n; i++, cnt++)
        sum += s->D[i] / (double)i;
    json_key(w, "m_end");
    if (cnt)
        json_double(w, sum / (double)cnt);
    else
        json_null(w);
    json_key(w, "points");
    json_begin_array(w);
    bool pretty = w->pretty; /* one point a line, not one number */
    for (size_t i = 0; i < n; i += i < head ? 1 : step) {
        size_t k = i >= head && i + step >= n ? n - 1 : i;
        json_begin_array(w);
        w->pretty = false;
        json_u64(w, k);
        json_double(w, s->D[k]);
        json_end_array(w);
        w->pretty = pretty;
    }
    json_end_array(w);
    if (s->has_profile) {
        json_key(w, "features");
        write_features(w, s->features);
        for (size_t i = 0; s->table && i < emm_table_count(s->table); i++) {
            const emm_table_sample *t = emm_table_at(s->table, i);
            if (strcmp(t->name, s->decision.nearest) != 0)
                continue;
            json_key(w, "nearest");
            json_begin_object(w);
            json_key(w, "name");
            json_string(w, t->name);
            json_key(w, "pattern");
            json_string(w, t->pattern);
            json_key(w, "distance");
            json_double(w, s->decision.distance);
            json_key(w, "features");
            write_features(w, t->f);
            json_end_object(w);
            break;
        }
    }
    json_end_object(w);
}

static const emm_result *find_result(const emm_result *res, size_t n, const emm_strategy *want);

/* Whether switching to the phase's best candidate pays: its cycles from the
 * detection on, plus re-laying out the mesh, against the chosen strategy's
 * over the same span. */
static bool phase_pays(const session *s, const program_phase *p)
{
    return p->model != SIZE_MAX && !p->best_is_answer &&
           p->best_span + session_switch_cycles(s) < p->chosen_span;
}

/* "probes" (docs/report.md): the probes taken after the window, and those
 * profiled. */
static void write_probes(json_writer *w, uint64_t taken, uint64_t profiled)
{
    json_key(w, "probes");
    json_begin_object(w);
    json_key(w, "taken");
    json_u64(w, taken);
    json_key(w, "profiled");
    json_u64(w, profiled);
    json_end_object(w);
}

/* "phases" (docs/report.md): the program's phases as the probes found them. */
static void write_phases(json_writer *w, const session *s)
{
    char name[64];
    json_key(w, "phases_probed");
    json_bool(w, s->probed);
    write_probes(w, s->probes_taken, s->probes_profiled);
    json_key(w, "phases");
    json_begin_array(w);
    for (int i = 0; i < s->nphases; i++) {
        const program_phase *p = &s->phases[i];
        json_begin_object(w);
        json_key(w, "start");
        json_u64(w, p->start);
        json_key(w, "end");
        json_u64(w, i + 1 < s->nphases ? s->phases[i + 1].start : s->accesses);
        json_key(w, "pattern");
        json_string(w, p->pattern);
        json_key(w, "nearest");
        json_string(w, p->nearest);
        json_key(w, "distance");
        json_double(w, p->distance);
        json_key(w, "best");
        if (p->has_best) {
            emm_strategy_format(&p->best, name, sizeof name);
            json_string(w, name);
        } else {
            json_null(w);
        }
        if (p->model != SIZE_MAX && !p->best_is_answer) {
            json_key(w, "switch");
            json_begin_object(w);
            json_key(w, "from_access");
            json_u64(w, p->detected);
            json_key(w, "kept_cycles");
            json_u64(w, p->chosen_span);
            json_key(w, "switched_cycles");
            json_u64(w, p->best_span);
            json_key(w, "switch_cost");
            json_u64(w, session_switch_cycles(s));
            json_key(w, "pays");
            json_bool(w, phase_pays(s, p));
            json_end_object(w);
        }
        json_end_object(w);
    }
    json_end_array(w);
}

/* The summary's tie: the choice and the runner-up within the margin over
 * the run (the window's scores when the runner-up was not simulated). */
static bool answer_tie(const session *s, const emm_result *res, const emm_error *skipped,
                       size_t n)
{
    if (s->contest || s->ranked) {
        const emm_result *r = s->runner_model != SIZE_MAX
                                  ? find_result(res, n, &s->mstrat[s->runner_model])
                                  : NULL;
        return n > 0 && r && r != res && emm_decide_is_tie(res[0].total, r->total);
    }
    if (!s->has_chosen || !s->has_wd || !s->wd.has_runner_up || n == 0 ||
        (skipped && skipped[0].status != EMM_OK))
        return false;
    const emm_result *r = find_result(res, n, &s->wd.runner_up);
    size_t k = r ? (size_t)(r - res) : 0;
    if (!r || r == res || (skipped && skipped[k].status != EMM_OK))
        return s->wd.tie != 0;
    return emm_decide_is_tie(res[0].total, r->total) != 0;
}

/* Whether the run's compute counts the capture's work as well as its
 * accesses: compute.per_work set, and a capture that counts work
 * (docs/machine.md "Compute"). */
static bool work_charged(const session *s)
{
    return emm_machine_get(s->machine, "compute.per_work") != 0 &&
           emm_capture_work_unit(s->capture) != NULL;
}

/* "compute" (docs/report.md): how the compute bucket was counted. */
static void write_compute(json_writer *w, const session *s)
{
    const char *unit = emm_capture_work_unit(s->capture);
    json_key(w, "compute");
    json_begin_object(w);
    json_key(w, "counted");
    json_string(w, work_charged(s) ? "per access and work" : "per access");
    json_key(w, "per_access");
    json_u64(w, emm_machine_get(s->machine, "compute.per_access"));
    json_key(w, "per_work");
    json_u64(w, emm_machine_get(s->machine, "compute.per_work"));
    json_key(w, "work_unit");
    if (unit)
        json_string(w, unit);
    else
        json_null(w);
    json_key(w, "work");
    json_u64(w, s->work);
    json_end_object(w);
}

/* How compute was counted: a line of the summary when the capture's work
 * is charged (the figures then depend on the capture), else a verbose
 * line. */
static void print_compute(FILE *out, const session *s)
{
    char num[32], work[32];
    const char *unit = emm_capture_work_unit(s->capture);
    uint64_t pa = emm_machine_get(s->machine, "compute.per_access"),
             pw = emm_machine_get(s->machine, "compute.per_work");
    emm_grouped(s->work, work);
    if (work_charged(s))
        fprintf(out, "emm:   compute: %s cycles: %llu per access and %llu per unit of the %s "
                     "capture's work (%s %s; compute.per_work = %llu): these figures depend on "
                     "the capture (docs/machine.md \"Compute\")\n",
                emm_grouped(pa * s->accesses + pw * s->work, num), (unsigned long long)pa,
                (unsigned long long)pw, emm_capture_name(s->capture), work, unit,
                (unsigned long long)pw);
    else if (unit)
        fprintf(out, "emm: compute: %llu cycle%s per access, whatever the capture; the %s "
                     "capture's work between accesses (%s %s) is not charged "
                     "(compute.per_work = 0)\n",
                (unsigned long long)pa, pa == 1 ? "" : "s", emm_capture_name(s->capture), work,
                unit);
    else
        fprintf(out, "emm: compute: %llu cycle%s per access, whatever the capture\n",
                (unsigned long long)pa, pa == 1 ? "" : "s");
}

static const emm_strategy direct_strategy = {EMM_STRATEGY_DIRECT, EMM_LAYOUT_ORIGINAL,
                                             EMM_FETCH_NONE, 0, 0};

/* "decision.window_check" (docs/report.md): a window-only capture's
 * prediction against every candidate and direct reads over the window. */
static void write_window_check(json_writer *w, const report_ctx *c)
{
    const session *s = c->s;
    json_key(w, "window_check");
    const emm_result *pred = find_result(c->res, c->n, &s->mstrat[0]);
    const emm_result *direct = find_result(c->res, c->n, &direct_strategy);
    if (!s->window_check || !pred || !direct) {
        json_null(w);
        return;
    }
    json_begin_object(w);
    json_key(w, "candidates");
    json_u64(w, contest_entrants(s->window_rank));
    json_key(w, "predicted_cycles");
    json_u64(w, pred->total);
    json_key(w, "direct_cycles");
    json_u64(w, direct->total);
    json_key(w, "kept");
    json_bool(w, !s->ranked);
    json_end_object(w);
}

/* The report's window.ended_by. */
static const char *window_end_name(enum window_end e)
{
    switch (e) {
    case WINDOW_FULL:
        return "full";
    case WINDOW_FINISH:
        return "run_end";
    case WINDOW_FREED:
        return "array_freed";
    case WINDOW_WRITES:
        return "write_cap";
    case WINDOW_RECORDS:
        return "record_cap";
    case WINDOW_CAPTURE:
        return "capture_bound";
    default:
        return "open";
    }
}

static const char *part_name(emm_tag_shape shape)
{
    return shape == EMM_TAG_HALFEDGES ? "halfedges" : shape == EMM_TAG_FACES ? "faces" : "vconn";
}

/* A trace array's records as the program's arrays make them up: its own
 * (positions, or nothing for the triangles of a half-edge mesh) and the
 * connectivity placed with them (docs/report.md "arrays"). */
static void write_parts(json_writer *w, const session *s, uint32_t a)
{
    uint64_t own = s->taccesses ? s->taccesses[a] : 0;
    uint32_t bytes = s->tarrays[a].record_size;
    int n = 0;
    for (int k = 0; k < s->nparts; k++)
        if (s->parts[k].trace == (int32_t)a) {
            own -= s->parts[k].accesses <= own ? s->parts[k].accesses : own;
            n++;
        }
    if (n == 0)
        return;
    json_key(w, "parts");
    json_begin_array(w);
    bool derived = s->he_slot >= 0 && s->tarrays[a].kind == EMM_ARRAY_TRIANGLES;
    if (!derived) {
        uint32_t first = bytes;
        for (int k = 0; k < s->nparts; k++)
            if (s->parts[k].trace == (int32_t)a && s->parts[k].base < first)
                first = s->parts[k].base;
        json_begin_object(w);
        json_key(w, "kind");
        json_string(w, s->tarrays[a].kind == EMM_ARRAY_VERTICES ? "vertices" : "triangles");
        json_key(w, "records");
        json_u64(w, s->tarrays[a].count);
        json_key(w, "record_bytes");
        json_u64(w, first);
        json_key(w, "accesses");
        json_u64(w, own);
        json_end_object(w);
    }
    for (int k = 0; k < s->nparts; k++) {
        const session_part *p = &s->parts[k];
        if (p->trace != (int32_t)a)
            continue;
        json_begin_object(w);
        json_key(w, "kind");
        json_string(w, part_name(p->shape));
        json_key(w, "records");
        json_u64(w, p->count);
        json_key(w, "record_bytes");
        json_u64(w, p->stride);
        json_key(w, "accesses");
        json_u64(w, p->accesses);
        json_end_object(w);
    }
    json_end_array(w);
}

/* The arrays simulated, and those tagged after the decision that were not
 * (docs/report.md "arrays"). */
static void write_arrays(json_writer *w, const session *s)
{
    json_key(w, "arrays");
    json_begin_array(w);
    for (uint32_t a = 0; a < s->ntarrays; a++) {
        json_begin_object(w);
        json_key(w, "kind");
        json_string(w, s->tarrays[a].kind == EMM_ARRAY_VERTICES ? "vertices" : "triangles");
        json_key(w, "records");
        json_u64(w, s->tarrays[a].count);
        json_key(w, "record_bytes");
        json_u64(w, s->tarrays[a].record_size);
        json_key(w, "accesses");
        json_u64(w, s->taccesses ? s->taccesses[a] : 0);
        write_parts(w, s, a);
        json_end_object(w);
    }
    json_end_array(w);
    json_key(w, "late_arrays");
    json_begin_array(w);
    for (int i = 0; i < s->nlate; i++) {
        json_begin_object(w);
        json_key(w, "kind");
        json_string(w, s->late[i].kind == EMM_ARRAY_VERTICES ? "vertices" : "triangles");
        json_key(w, "records");
        json_u64(w, s->late[i].count);
        json_key(w, "origin");
        json_string(w, s->late[i].origin);
        json_end_object(w);
    }
    json_end_array(w);
    json_key(w, "late_arrays_total");
    json_u64(w, s->late_total);
    json_key(w, "missing_kinds");
    json_begin_array(w);
    if (s->missing & 1u << EMM_ARRAY_VERTICES)
        json_string(w, "vertices");
    if (s->missing & 1u << EMM_ARRAY_TRIANGLES)
        json_string(w, "triangles");
    json_end_array(w);
}

static void report_extra(json_writer *w, void *ctx)
{
    const report_ctx *c = ctx;
    const session *s = c->s;
    char name[64];
    json_key(w, "program");
    json_string(w, s->program);
    json_key(w, "capture");
    json_string(w, emm_capture_name(s->capture));
    json_key(w, "ended");
    json_string(w, s->ended[0] ? s->ended : "exit");
    write_compute(w, s);
    json_key(w, "pattern");
    if (s->has_profile)
        json_string(w, s->decision.novel ? "novel" : s->decision.pattern);
    else
        json_null(w);
    json_key(w, "strategy");
    if (s->has_chosen) {
        emm_strategy_format(&s->chosen, name, sizeof name);
        json_string(w, name);
    } else {
        json_null(w);
    }
    json_key(w, "decision");
    json_begin_object(w);
    json_key(w, "source");
    json_string(w, source_name(s->source));
    if (s->has_profile) {
        json_key(w, "nearest");
        json_string(w, s->decision.nearest);
        json_key(w, "nearest_pattern");
        json_string(w, s->decision.pattern);
        json_key(w, "distance");
        json_double(w, s->decision.distance);
        json_key(w, "novel");
        json_bool(w, s->decision.novel != 0);
    } else {
        json_key(w, "nearest");
        json_null(w);
        json_key(w, "nearest_pattern");
        json_null(w);
        json_key(w, "distance");
        json_null(w);
        json_key(w, "novel");
        json_bool(w, false);
    }
    if (s->strategy_note[0]) {
        json_key(w, "note");
        json_string(w, s->strategy_note);
    }
    json_key(w, "candidates");
    json_string(w, emm_machine_get(s->machine, "cache.present")
                       ? "direct, the EMM strategies and the cache"
                       : "direct and the EMM strategies (the cache is a reference)");
    json_key(w, "runner_up");
    if ((s->contest || s->ranked) && s->runner_model != SIZE_MAX) {
        emm_strategy_format(&s->mstrat[s->runner_model], name, sizeof name);
        json_string(w, name);
    } else if (!s->contest && !s->ranked && s->has_wd && s->wd.has_runner_up) {
        emm_strategy_format(&s->wd.runner_up, name, sizeof name);
        json_string(w, name);
        json_key(w, "runner_up_margin");
        json_double(w, s->wd.runner_margin);
    } else {
        json_null(w);
    }
    /* The window's own choice, and the run's contest that confirmed or
     * replaced it (docs/report.md "decision"). */
    json_key(w, "predicted");
    const emm_strategy *overruled = session_overruled(s);
    if (overruled || (s->has_chosen && s->source != FROM_CONFIG)) {
        emm_strategy_format(overruled ? overruled : &s->chosen, name, sizeof name);
        json_string(w, name);
    } else {
        json_null(w);
    }
    json_key(w, "contest");
    if (s->contest) {
        const uint64_t *at;
        const size_t *kept;
        size_t rounds = contest_rounds(s->contest, &at, &kept);
        json_begin_object(w);
        json_key(w, "entrants");
        json_u64(w, contest_entrants(s->contest));
        json_key(w, "finalists");
        if (s->cfg.finalists == EMM_CONFIG_FINALISTS_ALL)
            json_string(w, "all");
        else
            json_u64(w, s->cfg.finalists);
        json_key(w, "margin_percent");
        json_u64(w, CONTEST_MARGIN_PERCENT);
        json_key(w, "lead");
        json_u64(w, contest_lead(s->contest));
        json_key(w, "unit");
        json_u64(w, contest_unit(s->contest));
        json_key(w, "rounds");
        json_begin_array(w);
        for (size_t k = 0; k < rounds; k++) {
            json_begin_object(w);
            json_key(w, "at");
            json_u64(w, at[k]);
            json_key(w, "kept");
            json_u64(w, kept[k]);
            json_end_object(w);
        }
        json_end_array(w);
        json_key(w, "ran_to_end");
        json_u64(w, rounds ? kept[rounds - 1] : contest_entrants(s->contest));
        /* The candidates dropped, by name: their cycles stop where they
         * were dropped, so they are not in results. */
        const size_t *idx;
        const uint64_t *dat, *dcycles;
        size_t nd = contest_dropped(s->contest, &idx, &dat, &dcycles);
        json_key(w, "dropped");
        json_begin_array(w);
        for (size_t k = 0; k < nd; k++) {
            json_begin_object(w);
            json_key(w, "strategy");
            emm_strategy_format(&s->mstrat[idx[k]], name, sizeof name);
            json_string(w, name);
            json_key(w, "at");
            json_u64(w, dat[k]);
            json_key(w, "cycles");
            json_u64(w, dcycles[k]);
            /* halved (the slower half then) or stopped by the margin
             * (more than CONTEST_MARGIN_PERCENT behind the leader, whose
             * cycles then are given, and since the previous check too) */
            uint64_t leader;
            bool stopped = contest_stopped(s->contest, k, &leader);
            json_key(w, "by");
            json_string(w, stopped ? "margin" : "halving");
            if (stopped) {
                json_key(w, "leader_cycles");
                json_u64(w, leader);
            }
            json_end_object(w);
        }
        json_end_array(w);
        json_end_object(w);
    } else {
        json_null(w);
    }
    write_window_check(w, c);
    json_key(w, "classes");
    json_begin_array(w);
    for (size_t k = 0; s->has_wd && k < s->wd.nclasses; k++) {
        json_begin_object(w);
        json_key(w, "pattern");
        json_string(w, s->wd.classes[k].pattern);
        json_key(w, "distance");
        json_double(w, s->wd.classes[k].distance);
        json_key(w, "synth_distance");
        if (s->wd.classes[k].synth_distance >= 0)
            json_double(w, s->wd.classes[k].synth_distance);
        else
            json_null(w);
        json_end_object(w);
    }
    json_end_array(w);
    json_key(w, "tie");
    json_bool(w, answer_tie(s, c->res, c->skipped, c->n));
    json_key(w, "tie_margin");
    json_double(w, EMM_DECIDE_TIE_MARGIN);
    json_key(w, "weak");
    json_bool(w, s->has_profile && s->decision.distance > EMM_WEAK_MATCH);
    json_end_object(w);
    /* What was simulated (docs/report.md "coverage"). */
    json_key(w, "coverage");
    json_begin_object(w);
    json_key(w, "simulated");
    json_string(w, session_window_only(s) ? "window" : "run");
    json_key(w, "accesses");
    json_u64(w, s->accesses);
    json_key(w, "element_accesses");
    json_u64(w, s->elements);
    json_key(w, "share");
    if (session_window_only(s))
        json_null(w);
    else
        json_double(w, 1.0);
    json_key(w, "loader_writes");
    json_u64(w, s->loader_writes);
    json_key(w, "geometry_read");
    json_string(w, s->deferred ? "end" : "decision");
    json_end_object(w);
    /* The traced mesh: its elements and the bytes of its records, against
     * which the DMA bytes say how often cells were fetched again. */
    uint64_t mesh_bytes = session_mesh_bytes(s);
    json_key(w, "mesh");
    json_begin_object(w);
    json_key(w, "vertices");
    json_u64(w, s->info.geometry.nv);
    json_key(w, "triangles");
    json_u64(w, s->vertex_only ? 0 : s->info.geometry.nt);
    json_key(w, "cells_of");
    json_string(w, s->vertex_only ? "vertices" : "triangles");
    json_key(w, "note");
    if (s->pick_note[0])
        json_string(w, s->pick_note);
    else
        json_null(w);
    json_key(w, "bytes");
    json_u64(w, mesh_bytes);
    json_end_object(w);
    json_key(w, "window");
    json_begin_object(w);
    json_key(w, "unit");
    json_string(w, s->cfg.window_accesses ? "accesses" : "iterations");
    json_key(w, "size");
    json_u64(w, s->cfg.window_accesses ? s->cfg.window_accesses : s->cfg.window_iterations);
    json_key(w, "element_accesses");
    json_u64(w, s->nD);
    json_key(w, "reads");
    json_u64(w, s->wreads);
    json_key(w, "writes");
    json_u64(w, s->wwrites);
    json_key(w, "iterations");
    json_u64(w, s->iterations);
    json_key(w, "leading_sweep");
    json_u64(w, s->sweep.elements);
    json_key(w, "complete");
    json_bool(w, s->wend == WINDOW_FULL);
    json_key(w, "ended_by");
    json_string(w, window_end_name(s->wend));
    json_key(w, "sweep_profiled");
    json_bool(w, s->sweep_profiled);
    json_key(w, "read_on");
    json_u64(w, session_read_on(s));
    json_key(w, "store_filled");
    json_bool(w, window_fill_filled(&s->wstore));
    json_key(w, "waited");
    json_u64(w, s->waited);
    json_key(w, "restarts");
    json_u64(w, s->restarts);
    json_key(w, "restart_records");
    json_u64(w, s->restart_records);
    json_end_object(w);
    write_arrays(w, s);
    write_profile(w, s);
    write_phases(w, s);
    session_write_stall_lines(w, s);
}

/* The result of strategy `want` among res[0..n), or NULL. */
static const emm_result *find_result(const emm_result *res, size_t n, const emm_strategy *want)
{
    for (size_t i = 0; i < n; i++)
        if (res[i].strategy.kind == want->kind && res[i].strategy.layout == want->layout &&
            res[i].strategy.fetch == want->fetch && res[i].strategy.cell == want->cell &&
            res[i].strategy.indexed == want->indexed)
            return &res[i];
    return NULL;
}

static const emm_strategy cache_strategy = {EMM_STRATEGY_CACHE, EMM_LAYOUT_ORIGINAL,
                                            EMM_FETCH_NONE, 0, 0};

/* "1.33x faster than" / "1.20x slower than" b, for a against b. */
static const char *versus(uint64_t a, uint64_t b, char *buf, size_t cap)
{
    if (!a || !b)
        snprintf(buf, cap, "n/a against");
    else if (a <= b)
        snprintf(buf, cap, "%.2fx faster than", (double)b / (double)a);
    else
        snprintf(buf, cap, "%.2fx slower than", (double)a / (double)b);
    return buf;
}

static const char *how_predicted(const session *s)
{
    switch (s->source) {
    case FROM_CONFIG:
        return session_source(s, EMM_CONFIG_STRATEGY);
    case FROM_SIMULATION:
        return "the best candidate of the sweep on the window";
    case FROM_CHECKED:
#define NEIGHBOURS "the costs of the runs measured on this machine nearest the window, " \
                   "weighed with the window"
#define LONG " and the pattern's long run over this mesh"
#define LEAD ", and the leading sweep's own cycles"
#define CHECK "the table's pattern simulated over this mesh on this machine"
        if (!(s->has_wd && s->wd.neighbours))
            return s->has_wd && s->wd.lead_records ? CHECK LEAD : CHECK;
        if (s->wd.synth_visits)
            return s->wd.lead_records ? NEIGHBOURS LONG LEAD : NEIGHBOURS LONG;
        return s->wd.lead_records ? NEIGHBOURS LEAD : NEIGHBOURS;
#undef CHECK
#undef LEAD
#undef LONG
#undef NEIGHBOURS
    default:
        return "the nearest sample's strategy";
    }
}

/* How the answer was reached: the window's prediction, the window's check
 * of it, or the contest. The contest measured over the run only the
 * candidates that ran to the end; those it dropped were slower when
 * dropped, not necessarily over the run, so the answer is called the
 * fastest of the former, and the latter are counted as dropped. A
 * window-only capture measured the window alone, and says so. */
static const char *how_decided(const session *s, const emm_result *res, size_t nres, char *buf,
                               size_t cap)
{
    const emm_result *pred = s->window_check ? find_result(res, nres, &s->mstrat[0]) : NULL;
    const emm_result *direct = find_result(res, nres, &direct_strategy);
    if (pred && direct && pred->total && direct->total) {
        char vs[48], pname[64];
        if (!s->ranked) {
            snprintf(buf, cap, "%s; checked over the profiling window only, the part of the run "
                               "seen: %s direct reads there",
                     how_predicted(s), versus(pred->total, direct->total, vs, sizeof vs));
            return buf;
        }
        emm_strategy_format(&pred->strategy, pname, sizeof pname);
        snprintf(buf, cap, "over the profiling window only, the part of the run seen: the fastest "
                           "of %zu candidates there; the window's prediction, %s, took %.2fx the "
                           "cycles of direct reads",
                 contest_entrants(s->window_rank), pname,
                 (double)pred->total / (double)direct->total);
        return buf;
    }
    if (!s->contest || s->answer_model == SIZE_MAX)
        return how_predicted(s);
    const uint64_t *at;
    const size_t *kept;
    size_t rounds = contest_rounds(s->contest, &at, &kept);
    size_t entrants = contest_entrants(s->contest);
    size_t in = rounds ? kept[rounds - 1] : entrants;
    if (in >= entrants) {
        snprintf(buf, cap, "measured over the run: the fastest of %zu candidates, every one run "
                           "to the end", entrants);
        return buf;
    }
    /* "2, 4, 8 and 16": the windows of records at which the halvings came. */
    char when[160] = "";
    uint64_t unit = contest_unit(s->contest), lead = contest_lead(s->contest);
    for (size_t k = 0; k < rounds; k++) {
        size_t used = strlen(when);
        snprintf(when + used, sizeof when - used, "%s%llu",
                 k == 0 ? "" : k + 1 == rounds ? " and " : ", ",
                 (unsigned long long)((at[k] - lead) / unit));
    }
    /* Of those, the ones the margin stopped ("of them 3 more than 25% behind
     * the leader, so far and since the previous check") */
    const size_t *idx;
    const uint64_t *dat, *dcycles;
    size_t nd = contest_dropped(s->contest, &idx, &dat, &dcycles), stopped = 0;
    for (size_t k = 0; k < nd; k++) {
        uint64_t leader;
        stopped += contest_stopped(s->contest, k, &leader);
    }
    char margin[160] = "";
    if (stopped)
        snprintf(margin, sizeof margin,
                 " (%zu of them stopped as more than %u%% behind the leader, so far and since "
                 "the previous check)",
                 stopped, CONTEST_MARGIN_PERCENT);
    snprintf(buf, cap,
             "measured over the run: the fastest of the %zu candidates that ran to the end; the "
             "other %zu of %zu were dropped at %s windows, slower then, and not measured to the "
             "end%s",
             in, entrants - in, entrants, when, margin);
    return buf;
}

/* Why no element read was profiled, for "0 element reads profiled (...)". */
static const char *no_reads_why(const session *s, char *buf, size_t cap)
{
    char num[32];
    if (s->wreads == 0 && s->loader_writes)
        snprintf(buf, cap, "the program wrote its tagged arrays (%s writes, the loader's) but "
                           "was not seen reading them: the window opens at the first read",
                 emm_grouped(s->loader_writes, num));
    else if (s->wreads == 0)
        snprintf(buf, cap, "no read of the tagged arrays was seen");
    else
        snprintf(buf, cap, "the window's %s reads were of arrays outside the traced mesh",
                 emm_grouped(s->wreads, num));
    return buf;
}

/* "the mesh: 50,225 vertices (12-byte records) and 100,000 triangles
 * (12-byte records)": the arrays simulated, by kind. More than two of a
 * kind (a growing vector's buffers, each read in the window) are counted,
 * with the largest: "8 vertex arrays (80-byte records, the largest 5,000)". */
static void print_mesh_arrays(const session *s, FILE *out)
{
    char line[512] = "", num[32];
    const char *part[2];
    char text[2][160];
    int nparts = 0;
    for (int kind = 0; kind < 2; kind++) {
        emm_array_kind k = kind == 0 ? EMM_ARRAY_VERTICES : EMM_ARRAY_TRIANGLES;
        uint32_t n = 0, largest = 0, rec = 0;
        bool same = true;
        for (uint32_t a = 0; a < s->ntarrays; a++) {
            const emm_trace_array *t = &s->tarrays[a];
            if (t->kind != k)
                continue;
            same = same && (n == 0 || t->record_size == rec);
            rec = t->record_size;
            if (n++ == 0 || t->count > s->tarrays[largest].count)
                largest = a;
        }
        if (n == 0)
            continue;
        const char *what = k == EMM_ARRAY_VERTICES ? "vertices" : "triangles";
        if (n <= 2) { /* each, as many arrays are few */
            size_t used = 0;
            text[nparts][0] = '\0';
            for (uint32_t a = 0; a < s->ntarrays; a++) {
                const emm_trace_array *t = &s->tarrays[a];
                if (t->kind == k && used < sizeof text[0])
                    used += (size_t)snprintf(text[nparts] + used, sizeof text[0] - used,
                                             "%s%s %s (%u-byte records)", used ? " and " : "",
                                             emm_grouped(t->count, num), what, t->record_size);
            }
        } else if (same) {
            snprintf(text[nparts], sizeof text[0], "%u %s arrays (%u-byte records, the largest %s)",
                     n, k == EMM_ARRAY_VERTICES ? "vertex" : "triangle", rec,
                     emm_grouped(s->tarrays[largest].count, num));
        } else {
            snprintf(text[nparts], sizeof text[0], "%u %s arrays (the largest %s)", n,
                     k == EMM_ARRAY_VERTICES ? "vertex" : "triangle",
                     emm_grouped(s->tarrays[largest].count, num));
        }
        part[nparts] = text[nparts];
        nparts++;
    }
    if (nparts == 0)
        return;
    snprintf(line, sizeof line, "%s%s%s", part[0], nparts > 1 ? " and " : "",
             nparts > 1 ? part[1] : "");
    fprintf(out, "emm:   simulated arrays: %s\n", line);
    if (s->nparts == 0)
        return;
    /* Half-edge connectivity, placed with the triangles and vertices. */
    size_t used = 0;
    char n1[32], n2[32];
    for (int k = 0; k < s->nparts && used < sizeof line; k++) {
        const session_part *p = &s->parts[k];
        int w = snprintf(line + used, sizeof line - used, "%s%s %s records (%u bytes, %s accesses)",
                         k ? ", " : "", emm_grouped(p->count, n1),
                         p->shape == EMM_TAG_HALFEDGES ? "half-edge"
                         : p->shape == EMM_TAG_FACES   ? "face"
                                                       : "vertex connectivity",
                         p->stride, emm_grouped(p->accesses, n2));
        if (w > 0)
            used += (size_t)w;
    }
    fprintf(out, "emm:   connectivity: %s, each placed in its triangle's (vertex's) record\n",
            line);
    if (s->restarts)
        fprintf(out,
                "emm:   the window started again %u time%s: the half-edge mesh was still being "
                "built (%s records of the loader's left out)\n",
                s->restarts, s->restarts == 1 ? "" : "s", emm_grouped(s->restart_records, n1));
}

/* What the window was: short of its length, waiting for an array, a
 * leading sweep profiled as the traversal; and the arrays of a kind the
 * rules name that came too late. */
static void print_window_lines(const session *s, FILE *out)
{
    char num[32], num2[32], num3[32], bound[160];
    uint64_t size = s->cfg.window_accesses ? s->cfg.window_accesses : s->cfg.window_iterations;
    const char *unit = s->cfg.window_accesses ? "element reads" : "iterations";
    uint64_t got = s->cfg.window_accesses ? (uint64_t)s->nD : s->iterations;
    emm_grouped(got, num);
    emm_grouped(size, num2);
    const char *ended = NULL;
    switch (s->wend) {
    case WINDOW_FINISH:
        ended = "the run ended";
        break;
    case WINDOW_FREED:
        ended = "the last array of a kind was freed";
        break;
    case WINDOW_WRITES:
        snprintf(bound, sizeof bound,
                 "the window reached its bound of %s written records",
                 emm_grouped(SESSION_WINDOW_WRITES, num3));
        ended = bound;
        break;
    case WINDOW_RECORDS:
        ended = "the window reached its bound of records (few elements read many times)";
        break;
    case WINDOW_CAPTURE:
        snprintf(bound, sizeof bound,
                 "the window reached the %s capture's bound of %d window lengths of element "
                 "accesses of either kind",
                 emm_capture_name(s->capture), SESSION_CAPTURE_WINDOWS);
        ended = bound;
        break;
    default:
        break;
    }
    if (s->sweep_profiled)
        /* No read of the window proper: the sweep before it is the run. */
        fprintf(out, "emm:   every one of the %s element reads seen was a leading index-order "
                     "sweep (the program reads its mesh once, in order) and %s before the "
                     "window's %s %s past such a sweep began: the sweep is the traversal, and "
                     "it was profiled\n",
                emm_grouped(s->sweep.elements, num3), ended ? ended : "the window filled", num2,
                unit);
    else if (ended)
        fprintf(out, "emm:   %s after %s of the window's %s %s: the answer rests on them\n", ended,
                num, num2, unit);
    if (session_read_on(s)) {
        emm_grouped(s->wlen, num3);
        if (window_fill_filled(&s->wstore))
            fprintf(out, "emm:   the window read on past its %s %s to %s, until the records it "
                         "read filled the local store (%s bytes)\n",
                    num2, unit, num3, emm_grouped(s->wstore.bytes, bound));
        else
            fprintf(out, "emm:   the window read on past its %s %s to %s (%.3g times its length) "
                         "to fill the local store (%s bytes); its records filled %.0f %% of it\n",
                    num2, unit, num3, EMM_PROFILE_FILL_REACH, emm_grouped(s->wstore.bytes, bound),
                    100.0 * (double)s->wstore.touched / (double)s->wstore.bytes);
    }
    if (s->waited)
        fprintf(out, "emm:   the window filled before an array of every kind the tag rules name "
                     "was tagged, and went on %s more element reads waiting for one\n",
                emm_grouped(s->waited, num));
    static const emm_array_kind kinds[] = {EMM_ARRAY_VERTICES, EMM_ARRAY_TRIANGLES};
    for (int k = 0; k < 2; k++)
        if (s->missing & 1u << kinds[k])
            fprintf(out, "emm:   no %s array was tagged by the decision although a tag rule "
                         "names one: the mesh is simulated without it\n",
                    kinds[k] == EMM_ARRAY_VERTICES ? "vertex" : "triangle");
    for (int i = 0; i < s->nlate; i++) {
        const late_array *l = &s->late[i];
        fprintf(out, "emm:   %s tagged %s %s (%llu-byte records) after the decision: its "
                     "accesses are not simulated (the run's arrays were fixed then)\n",
                l->origin, emm_grouped(l->count, num),
                l->kind == EMM_ARRAY_VERTICES ? "vertices" : "triangles",
                (unsigned long long)l->stride);
    }
    if (s->late_total > (uint64_t)s->nlate)
        fprintf(out, "emm:   and %llu more arrays tagged after the decision, not simulated\n",
                (unsigned long long)(s->late_total - (uint64_t)s->nlate));
}

/* The summary is the answer (docs/report.md "The summary"): the pattern, the
 * chosen strategy in words with its cycles against direct reads, the
 * runner-up, the reference cache, what was simulated, what was skipped,
 * and the next command. */
void session_print_summary(const session *s, FILE *out, const emm_result *res, size_t nres)
{
    char name[64], words[320], num[32], num2[32], vs[48];
    if (s->phase == PHASE_FAILED) {
        /* Most failures already start with the program's name: once is enough. */
        const char *why = s->failure.message;
        size_t len = strlen(s->program);
        if (strncmp(why, s->program, len) == 0 && strncmp(why + len, ": ", 2) == 0)
            why += len + 2;
        fprintf(out, "emm: %s: no simulation: %s\n", s->program, why);
        return;
    }
    if (s->has_profile && s->decision.novel)
        fprintf(out, "emm: %s: pattern novel (nearest %s, a %s sample, at distance %.2f, beyond "
                     "%.2f): the candidates were simulated on the window\n",
                s->program, s->decision.nearest, s->decision.pattern, s->decision.distance,
                EMM_NOVELTY_THRESHOLD);
    else if (s->has_profile && s->decision.distance > EMM_WEAK_MATCH)
        fprintf(out, "emm: %s: pattern %s, a weak match (nearest %s at distance %.2f, beyond "
                     "%.2f): trust the simulated cycles below more than the pattern\n",
                s->program, s->decision.pattern, s->decision.nearest, s->decision.distance,
                EMM_WEAK_MATCH);
    else if (s->has_profile)
        fprintf(out, "emm: %s: pattern %s (nearest %s, distance %.2f)\n", s->program,
                s->decision.pattern, s->decision.nearest, s->decision.distance);
    else if (s->nD == 0) {
        char why[256];
        fprintf(out, "emm: %s: pattern unknown (0 element reads profiled: %s)\n", s->program,
                no_reads_why(s, why, sizeof why));
    } else
        fprintf(out, "emm: %s: pattern unknown (%zu element reads profiled; %s)\n", s->program,
                s->nD,
                !s->table ? "no strategy table"
                : s->has_chosen && s->source == FROM_SIMULATION
                    ? "a pattern needs at least 256: the candidates were simulated over those "
                      "reads instead"
                    : "a profile needs at least 256");
    print_window_lines(s, out);

    const emm_result *chosen = s->has_chosen && nres ? &res[0] : NULL;
    const emm_result *direct = find_result(res, nres, &direct_strategy);
    const emm_result *cache = find_result(res, nres, &cache_strategy);
    const emm_result *runner = NULL;
    if (s->contest || s->ranked)
        runner = s->runner_model != SIZE_MAX ? find_result(res, nres, &s->mstrat[s->runner_model])
                                             : NULL;
    else if (s->has_wd && s->wd.has_runner_up)
        runner = find_result(res, nres, &s->wd.runner_up);
    char how[400];
    if (chosen) {
        emm_strategy_format(&chosen->strategy, name, sizeof name);
        emm_strategy_words(&chosen->strategy, words, sizeof words);
        /* The other of a tie: the simulated runner-up, or the decision's
         * (not simulated with EMM_COMPARE=none). */
        const emm_strategy *tied = NULL;
        if (runner && runner != chosen)
            tied = emm_decide_is_tie(chosen->total, runner->total) ? &runner->strategy : NULL;
        else if (!s->contest && !s->ranked && s->has_wd && s->wd.tie && s->wd.has_runner_up)
            tied = &s->wd.runner_up;
        if (tied) {
            char other[64];
            emm_strategy_format(tied, other, sizeof other);
            fprintf(out, "emm: answer: a tie between %s and %s (within %.0f%%: either will "
                         "do); %s named first (%s)\n",
                    name, other, EMM_DECIDE_TIE_MARGIN * 100, name,
                    how_decided(s, res, nres, how, sizeof how));
        } else {
            fprintf(out, "emm: answer: %s (%s)\n", name,
                    how_decided(s, res, nres, how, sizeof how));
        }
        fprintf(out, "emm:   %s\n", words);
        const char *over = session_window_only(s) ? " over the window" : "";
        if (direct && direct != chosen)
            fprintf(out, "emm:   %s cycles%s, %s direct reads (%s cycles)\n",
                    emm_grouped(chosen->total, num), over,
                    versus(chosen->total, direct->total, vs, sizeof vs),
                    emm_grouped(direct->total, num2));
        else
            fprintf(out, "emm:   %s cycles%s\n", emm_grouped(chosen->total, num), over);
        if (runner && runner != chosen) {
            emm_strategy_format(&runner->strategy, name, sizeof name);
            double d = chosen->total ? (double)runner->total / (double)chosen->total - 1 : 0;
            /* Fault capture simulates the window only. A runner-up faster
             * there than the answer lost on what the choice weighs: the
             * pattern's long run on this mesh (the window is cold). */
            const char *span = session_window_only(s) ? "over the window" : "over the run";
            if (d < 0 && !s->contest && !s->ranked && s->has_wd && s->wd.has_runner_up &&
                s->wd.runner_margin > 0)
                fprintf(out,
                        "emm:   runner-up %s: %s cycles (%.1f%% faster %s, which starts cold; "
                        "%.1f%% slower on the pattern's long run over this mesh, which the choice "
                        "weighs)\n",
                        name, emm_grouped(runner->total, num), fabs(d) * 100, span,
                        s->wd.runner_margin * 100);
            else
                fprintf(out, "emm:   runner-up %s: %s cycles (%.1f%% %s %s)\n", name,
                        emm_grouped(runner->total, num), fabs(d) * 100,
                        d >= 0 ? "slower" : "faster", span);
        }
        /* An indexed answer assumes the program adopts the layout's
         * numbering: what that saves, against the best that keeps the
         * look-up table. */
        if (chosen->strategy.indexed && s->plain_model != SIZE_MAX) {
            emm_strategy_format(&s->mstrat[s->plain_model], name, sizeof name);
            fprintf(out,
                    "emm:   adopt this numbering (emm layout --write) and the look-up cost "
                    "disappears: %s cycles vs %s (%s, with the look-up table)\n",
                    emm_grouped(chosen->total, num), emm_grouped(s->plain_total, num2), name);
        }
        /* What the window alone predicted, against the run's answer. */
        const emm_strategy *overruled = session_overruled(s);
        const emm_result *pred = overruled ? find_result(res, nres, overruled) : NULL;
        if (s->contest && s->answer_model != SIZE_MAX && !overruled)
            fprintf(out, "emm:   the window predicted it too (%s)\n", how_predicted(s));
        else if (pred && pred != chosen && chosen->total) {
            emm_strategy_format(&pred->strategy, name, sizeof name);
            fprintf(out, "emm:   the window predicted %s (%s): %s cycles, %.2fx the answer\n",
                    name, how_predicted(s), emm_grouped(pred->total, num),
                    (double)pred->total / (double)chosen->total);
        }
        session_print_stall_lines(s, out);
    } else if (s->strategy_note[0]) {
        fprintf(out, "emm: no answer: the chosen strategy cannot be simulated: %s\n",
                s->strategy_note);
    } else {
        fprintf(out, "emm: no answer: no strategy chosen; direct reads and the reference only\n");
        if (direct)
            fprintf(out, "emm:   direct reads: %s cycles\n", emm_grouped(direct->total, num));
    }
    if (cache && cache != chosen) {
        uint64_t kib = emm_machine_get(s->machine, "cache.bytes") >> 10;
        unsigned ways = (unsigned)emm_machine_get(s->machine, "cache.assoc");
        bool has = emm_machine_get(s->machine, "cache.present") != 0;
        fprintf(out, "emm:   %s: a %llu KiB %u-way cache%s would take %s cycles",
                has ? "the machine's cache" : "reference", (unsigned long long)kib, ways,
                has ? "" : " (not on this machine)", emm_grouped(cache->total, num));
        if (chosen && chosen->total)
            fprintf(out, " (%.2fx the answer)", (double)cache->total / (double)chosen->total);
        fputc('\n', out);
    }
    char elems[32];
    emm_grouped(s->elements, elems);
    if (s->deferred)
        fprintf(out, "emm:   simulated: the profiling window only, %s accesses, %s element "
                     "accesses: when it closed the arrays held no mesh yet (%s); read again "
                     "at the program's end they did, and the layouts are that mesh's; the "
                     "rest of the run was not captured\n",
                emm_grouped(s->accesses, num), elems, s->deferred_why.message);
    else if (session_window_only(s)) {
        /* What the window cost: under the fault capture tens of
         * microseconds an access, against Valgrind's whole run. */
        char took[160] = "";
        if (s->wseconds > 0 && s->wraw)
            snprintf(took, sizeof took, ": its window took %.2f s from the first access it "
                     "captured to the decision, %.1f us per access, %s captured",
                     s->wseconds, s->wseconds * 1e6 / (double)s->wraw, emm_grouped(s->wraw, num));
        fprintf(out, "emm:   simulated: the profiling window only, %s accesses, %s element "
                     "accesses (the %s capture stops at the decision%s; its share of the run is "
                     "unknown): the answer covers the window; for an answer over the whole run, "
                     "capture all of it: emm run --capture valgrind -- %s ... (emm run starts "
                     "Valgrind, which plain LD_PRELOAD cannot), or a build with "
                     "clang's sanitizer coverage (pkg-config emm-sancov) under --capture "
                     "sancov\n",
                emm_grouped(s->accesses, num), elems, emm_capture_name(s->capture), took,
                s->program);
    } else {
        fprintf(out, "emm:   simulated: the whole run from the frozen mesh on, %s accesses, %s "
                     "element accesses (the %s capture%s)\n",
                emm_grouped(s->accesses, num), elems, emm_capture_name(s->capture),
                s->cfg.capture == EMM_CAPTURE_AUTO && (emm_capture_caps(s->capture) &
                                                       EMM_CAP_VALGRIND)
                    ? ", --capture auto's pick for a binary without coverage hooks or emm "
                      "calls: it covers the whole run, in about the time the fault capture, at "
                      "tens of microseconds an access, takes for the window alone"
                    : "");
    }
    if (s->ended[0])
        fprintf(out, "emm:   the run ended by %s: what was captured up to then is simulated\n",
                s->ended);
    if (work_charged(s))
        print_compute(out, s);
    char remote[256];
    if (s->ntarrays && emm_machine_remote_warning(s->machine, &s->info, remote, sizeof remote))
        fprintf(out, "emm:   %s\n", remote);
    if (s->pick_note[0])
        fprintf(out, "emm:   %s\n", s->pick_note);
    print_mesh_arrays(s, out);
    if (s->vertex_only)
        fprintf(out, "emm:   the mesh: %s vertex positions and no triangle array: the layouts "
                     "cut cells of vertices, which every strategy can run on\n",
                emm_grouped(s->info.geometry.nv, num));
    if (s->nphases > 1) {
        fprintf(out, "emm:   phases: %d —", s->nphases);
        for (int i = 0; i < s->nphases; i++)
            fprintf(out, "%s %s from access %s", i ? "," : "", s->phases[i].pattern,
                    emm_grouped(s->phases[i].start, num));
        fputc('\n', out);
        for (int i = 1; i < s->nphases; i++) {
            const program_phase *p = &s->phases[i];
            if (!p->has_best)
                continue;
            emm_strategy_format(&p->best, name, sizeof name);
            if (p->best_is_answer || p->model == SIZE_MAX) {
                fprintf(out, "emm:   the %s phase's best candidate is the answer too: no switch\n",
                        p->pattern);
                continue;
            }
            uint64_t cost = session_switch_cycles(s), with = p->best_span + cost;
            fprintf(out, "emm:   the %s phase: switching to %s would take %s cycles with %s to "
                         "re-lay out the mesh, against %s for the answer: switching %s\n",
                    p->pattern, name, emm_grouped(with, num), emm_grouped(cost, num2),
                    emm_grouped(p->chosen_span, vs), phase_pays(s, p) ? "pays" : "does not pay");
        }
    }
    if (s->loader_writes)
        fprintf(out, "emm:   before it, %s writes while the mesh was being built (the loader): "
                     "not simulated\n",
                emm_grouped(s->loader_writes, num));
    if (s->skipped) {
        const char *why = "";
        for (size_t i = 0; i < s->nmodels && !why[0]; i++)
            if (s->merr[i].status != EMM_OK && !(i == 0 && s->strategy_note[0]))
                why = s->merr[i].message;
        char clip[EMM_CLIP + 1];
        fprintf(out, "emm:   %zu strategies skipped, e.g. %s (each with its reason in the "
                     "report)\n",
                s->skipped, emm_clip(why, strlen(why), clip));
    }
    if (s->cfg.compare == EMM_COMPARE_ALL && s->cfg.report[0])
        fprintf(out, "emm:   next: emm plot %s   (every candidate's cycles, by bucket)\n",
                s->cfg.report);
    else if (s->cfg.trace[0])
        fprintf(out, "emm:   next: emm replay %s --all --json all.json && emm plot all.json\n",
                s->cfg.trace);
    else
        fprintf(out, "emm:   next: rerun with --trace run.emmt, then emm replay run.emmt --all "
                     "--json all.json && emm plot all.json   (every candidate)\n");
    if (s->cfg.log < 2)
        return;
    for (size_t i = 0; i < nres; i++) {
        emm_strategy_format(&res[i].strategy, name, sizeof name);
        fprintf(out, "emm:   %-22s %15s cycles\n", name, emm_grouped(res[i].total, num));
    }
    for (uint32_t a = 0; a < s->ntarrays; a++)
        fprintf(out, "emm: array %u: %s, %llu records of %u bytes at 0x%llx\n", a,
                emm_trace_kind_name(s->tarrays[a].kind), (unsigned long long)s->tarrays[a].count,
                s->tarrays[a].record_size, (unsigned long long)s->tarrays[a].base);
    fprintf(out, "emm: %llu accesses simulated; window %zu element reads, %llu iterations\n",
            (unsigned long long)s->accesses, s->nD, (unsigned long long)s->iterations);
    if (!work_charged(s))
        print_compute(out, s);
    if (s->dropped)
        fprintf(out, "emm: %llu accesses to tagged arrays outside the traced mesh were ignored\n",
                (unsigned long long)s->dropped);
}

emm_status session_write_csv(const session *s, emm_error *err)
{
    emm_outfile o;
    emm_error e;
    emm_status st = emm_outfile_open(&o, s->cfg.profile_dump, "the profile", &e);
    if (st == EMM_OK) {
        fprintf(o.f, "i,D\n");
        for (size_t i = 0; i < s->nD; i++)
            fprintf(o.f, "%zu,%.17g\n", i, s->D[i]);
        st = emm_outfile_commit(&o, "the profile", &e);
    }
    return st == EMM_OK ? EMM_OK : emm_fail(err, st, "%s: %s", session_source(s, EMM_CONFIG_PROFILE_DUMP), e.message);
}

/* A report with nothing simulated (docs/report.md "Nothing simulated"):
 * the keys of a session's report, with no results, coverage.simulated
 * "nothing" and coverage.reason. s (NULL when no session started) adds what
 * was seen before the session stepped aside. */
struct nothing_ctx {
    const session *s;
    const char *program, *why;
    emm_capture capture;
};

static void nothing_extra(json_writer *w, void *ctx)
{
    const struct nothing_ctx *c = ctx;
    const session *s = c->s;
    json_key(w, "program");
    json_string(w, c->program);
    json_key(w, "capture");
    json_string(w, emm_capture_name(c->capture));
    json_key(w, "ended");
    json_string(w, s && s->ended[0] ? s->ended : "exit");
    json_key(w, "pattern");
    json_null(w);
    json_key(w, "strategy");
    json_null(w);
    json_key(w, "decision");
    json_null(w);
    json_key(w, "coverage");
    json_begin_object(w);
    json_key(w, "simulated");
    json_string(w, "nothing");
    json_key(w, "reason");
    json_string(w, c->why);
    json_key(w, "accesses");
    json_u64(w, 0);
    json_key(w, "element_accesses");
    json_u64(w, 0);
    json_key(w, "share");
    json_null(w);
    json_key(w, "loader_writes");
    json_u64(w, s ? s->loader_writes : 0);
    json_key(w, "window_records");
    json_u64(w, s ? s->wreads + s->wwrites : 0);
    json_end_object(w);
    json_key(w, "mesh");
    json_null(w);
    json_key(w, "window");
    json_null(w);
    json_key(w, "profile");
    json_null(w);
    json_key(w, "phases_probed");
    json_bool(w, false);
    write_probes(w, 0, 0);
    json_key(w, "phases");
    json_begin_array(w);
    json_end_array(w);
}

/* Whether the file at path was modified at or after *since: another
 * process of the run wrote it after this one started. */
static bool written_since(const char *path, const struct timespec *since)
{
    struct stat st;
    if (!since || stat(path, &st) != 0)
        return false;
    return st.st_mtim.tv_sec > since->tv_sec ||
           (st.st_mtim.tv_sec == since->tv_sec && st.st_mtim.tv_nsec >= since->tv_nsec);
}

static emm_status write_nothing(const char *path, const emm_machine *m,
                                const struct nothing_ctx *c, const struct timespec *since,
                                emm_error *err)
{
    if (written_since(path, since))
        return EMM_OK;
    return emm_report_write_extra(path, "", m, 0, NULL, NULL, 0, nothing_extra, (void *)c, err);
}

emm_status session_write_nothing(const session *s, emm_error *err)
{
    struct nothing_ctx c = {s, s->program, s->failure.message, s->capture};
    emm_error e;
    emm_status st = write_nothing(s->cfg.report, s->machine, &c, &s->started, &e);
    if (st != EMM_OK)
        return emm_fail(err, st, "%s: %s", session_source(s, EMM_CONFIG_REPORT), e.message);
    return EMM_OK;
}

emm_status emm_session_report_nothing(const emm_config *cfg, const char *program,
                                      emm_capture capture, const char *why,
                                      const struct timespec *since, emm_error *err)
{
    if (!cfg->report[0])
        return EMM_OK;
    /* The machine in effect: the configured file's, when it can be read
     * (it may be why nothing started), else the built-in one. */
    emm_machine *m = NULL;
    emm_error e;
    emm_status st = emm_machine_new(&m, &e);
    if (st == EMM_OK && cfg->machine[0] && emm_machine_load(m, cfg->machine, &e) != EMM_OK) {
        emm_machine_free(m);
        st = emm_machine_new(&m, &e);
    }
    struct nothing_ctx c = {NULL, program ? program : "program", why, capture};
    if (st == EMM_OK)
        st = write_nothing(cfg->report, m, &c, since, &e);
    emm_machine_free(m);
    const char *as = cfg->source[EMM_CONFIG_REPORT] ? cfg->source[EMM_CONFIG_REPORT]
                                                    : emm_config_row_get(EMM_CONFIG_REPORT)->var;
    return st == EMM_OK ? EMM_OK : emm_fail(err, st, "%s: %s", as, e.message);
}

/* One report per process: when another process of the run (a child the
 * program started, which ended first; the program that started this one)
 * wrote the report's file since this session started, this one goes beside
 * it with the program's pid as a suffix, and the summary says so. */
static const char *report_path(const session *s, char *buf, size_t cap)
{
    if (!written_since(s->cfg.report, &s->started))
        return s->cfg.report;
    snprintf(buf, cap, "%s.%ld", s->cfg.report, s->pid);
    return buf;
}

emm_status session_write_report(const session *s, const emm_result *res,
                                const emm_error *skipped, size_t nres, FILE *summary,
                                emm_error *err)
{
    report_ctx ctx = {s, res, skipped, nres};
    emm_error e;
    char buf[EMM_CONFIG_PATH_MAX + 24];
    const char *path = report_path(s, buf, sizeof buf);
    if (path == buf && summary && s->cfg.log >= 1)
        fprintf(summary, "emm:   report: %s (%s holds another process's of this run)\n",
                path, s->cfg.report);
    emm_status st = emm_report_write_extra(path, s->cfg.trace, s->machine, s->accesses,
                                           res, skipped, nres, report_extra, &ctx, &e);
    if (st != EMM_OK)
        return emm_fail(err, st, "%s: %s", session_source(s, EMM_CONFIG_REPORT), e.message);
    return EMM_OK;
}
