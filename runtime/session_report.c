/* The session's output (DESIGN.md "The shim", Output): the summary on
 * stderr, the JSON report of docs/report.md with the session's own keys
 * (program, capture, pattern, strategy, decision, window, profile), and the
 * CSV of the window's profile. Files are written whole or not at all
 * (core/outfile.h). */
#include "session_internal.h"

#include <string.h>

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
    const emm_session *s;
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
static void write_profile(json_writer *w, const emm_session *s)
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

static void report_extra(json_writer *w, void *ctx)
{
    const emm_session *s = ((const report_ctx *)ctx)->s;
    char name[64];
    json_key(w, "program");
    json_string(w, s->program);
    json_key(w, "capture");
    json_string(w, emm_capture_name(s->capture));
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
    json_end_object(w);
    /* The traced mesh: its elements and the bytes of its records, against
     * which the DMA bytes say how often cells were fetched again. */
    uint64_t mesh_bytes = 0;
    for (uint32_t a = 0; a < s->ntarrays; a++)
        if (s->tarrays[a].kind != EMM_ARRAY_RAW)
            mesh_bytes += s->tarrays[a].count * s->tarrays[a].record_size;
    json_key(w, "mesh");
    json_begin_object(w);
    json_key(w, "vertices");
    json_u64(w, s->info.geometry.nv);
    json_key(w, "triangles");
    json_u64(w, s->info.geometry.nt);
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
    json_key(w, "iterations");
    json_u64(w, s->iterations);
    json_key(w, "leading_sweep");
    json_u64(w, s->sweep.elements);
    json_end_object(w);
    write_profile(w, s);
}

static void print_line(FILE *out, const emm_result *r, const emm_result *ref)
{
    char name[64], num[32];
    emm_strategy_format(&r->strategy, name, sizeof name);
    fprintf(out, "emm:   %-22s %15s cycles", name, emm_grouped(r->total, num));
    if (ref && r != ref && r->total && ref->total) {
        if (r->total >= ref->total)
            fprintf(out, "  (%.2fx slower)", (double)r->total / (double)ref->total);
        else
            fprintf(out, "  (%.2fx faster)", (double)ref->total / (double)r->total);
    }
    fputc('\n', out);
}

void session_print_summary(const emm_session *s, FILE *out, const emm_result *res, size_t nres)
{
    char name[64];
    if (s->phase == PHASE_FAILED) {
        fprintf(out, "emm: %s: no simulation: %s\n", s->program, s->failure.message);
        return;
    }
    if (s->has_profile && s->decision.novel)
        fprintf(out, "emm: %s: pattern novel (nearest %s, a %s sample, at distance %.2f)\n",
                s->program, s->decision.nearest, s->decision.pattern, s->decision.distance);
    else if (s->has_profile)
        fprintf(out, "emm: %s: pattern %s (nearest %s, distance %.2f)\n", s->program,
                s->decision.pattern, s->decision.nearest, s->decision.distance);
    else
        fprintf(out, "emm: %s: pattern unknown (%zu element accesses profiled; %s)\n", s->program,
                s->nD, s->table ? "a profile needs at least 256" : "no strategy table");
    if (s->has_chosen) {
        emm_strategy_format(&s->chosen, name, sizeof name);
        const char *why = s->source == FROM_CONFIG       ? session_source(s, EMM_CONFIG_STRATEGY)
                          : s->source == FROM_SIMULATION ? "best of the sweep on the window"
                          : s->source == FROM_CHECKED
                              ? "the table's pattern simulated over this mesh, with the window"
                              : "from the table";
        fprintf(out, "emm: strategy %s (%s)\n", name, why);
    } else if (s->strategy_note[0]) {
        fprintf(out, "emm: strategy not simulated: %s\n", s->strategy_note);
    } else {
        fprintf(out, "emm: no strategy chosen; baselines only\n");
    }
    const emm_result *ref = s->has_chosen ? &res[0] : NULL;
    size_t shown = 0;
    if (s->cfg.compare != EMM_COMPARE_ALL) {
        for (size_t i = 0; i < nres; i++)
            print_line(out, &res[i], ref);
        shown = nres;
    } else {
        /* The whole sweep is in the report; here the chosen strategy, the
         * baselines and the best of the rest. */
        size_t best = 0;
        for (size_t i = 0; i < nres; i++)
            if (res[i].total < res[best].total)
                best = i;
        for (size_t i = 0; i < nres; i++) {
            bool baseline = res[i].strategy.kind == EMM_STRATEGY_DIRECT ||
                            (res[i].strategy.kind == EMM_STRATEGY_CACHE &&
                             res[i].strategy.layout == EMM_LAYOUT_ORIGINAL);
            if ((i == 0 && s->has_chosen) || baseline || i == best) {
                print_line(out, &res[i], ref);
                shown++;
            }
        }
        if (shown < nres)
            fprintf(out, "emm:   (%zu more in the report; the fastest is listed)\n",
                    nres - shown);
    }
    if (s->cfg.log < 2)
        return;
    for (uint32_t a = 0; a < s->ntarrays; a++)
        fprintf(out, "emm: array %u: %s, %llu records of %u bytes at 0x%llx\n", a,
                emm_trace_kind_name(s->tarrays[a].kind), (unsigned long long)s->tarrays[a].count,
                s->tarrays[a].record_size, (unsigned long long)s->tarrays[a].base);
    fprintf(out, "emm: %llu accesses simulated; window %zu element accesses, %llu iterations\n",
            (unsigned long long)s->accesses, s->nD, (unsigned long long)s->iterations);
    if (s->skipped)
        fprintf(out, "emm: %zu strategies of the comparison cannot run on this mesh\n", s->skipped);
    if (s->dropped)
        fprintf(out, "emm: %llu accesses to tagged arrays outside the traced mesh were ignored\n",
                (unsigned long long)s->dropped);
}

emm_status session_write_csv(const emm_session *s, emm_error *err)
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

emm_status session_write_report(const emm_session *s, const emm_result *res, size_t nres,
                                emm_error *err)
{
    report_ctx ctx = {s};
    emm_error e;
    emm_status st = emm_report_write_extra(s->cfg.report, s->cfg.trace, s->machine, s->accesses,
                                           res, nres, report_extra, &ctx, &e);
    if (st != EMM_OK)
        return emm_fail(err, st, "%s: %s", session_source(s, EMM_CONFIG_REPORT), e.message);
    return EMM_OK;
}
