/* emm profile TRACE: the distance profile of a trace's first accesses
 * (thesis §5, Eq. 5.1), its pattern class and the strategy the table picks. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "emm/profile.h"
#include "emm/replay.h"
#include "emm/table.h"
#include "emm/trace.h"
#include "json.h"
#include "machine_cli.h"
#include "opts.h"
#include "outfile.h"

static const char *const CMD = "profile";

/* --help's numbers that are no option's default. */
#define EXACT_MAX_TEXT "16384"
_Static_assert(EMM_PROFILE_EXACT_MAX == 16384u, "EXACT_MAX_TEXT is EMM_PROFILE_EXACT_MAX");

static void usage(FILE *out, const opts *o)
{
    char def[4096];
    emm_table_default_path(def, sizeof def);
    fprintf(out,
            "usage: emm profile TRACE [--window N] [--table FILE] [--threshold X]\n"
            "                         [--simulate] [--learn NAME [--pattern CLASS]]\n"
            "                         [--machine FILE] [--set KEY=VALUE]...\n"
            "                         [--dump FILE.csv] [--json FILE]\n"
            "\n"
            "Computes the distance profile D_i = sum over k<i of |p_i - p_k| (thesis Eq. 5.1)\n"
            "of the trace's first N element accesses (vertex or triangle accesses; consecutive\n"
            "accesses to one element count once; positions scaled by the mesh's bounding-box\n"
            "diagonal), reduces it to features, and prints the pattern class, the nearest\n"
            "sample of the strategy table with its distance, and the strategy chosen: the\n"
            "nearest sample's pattern synthesised over the trace's mesh and simulated under\n"
            "every strategy, weighed with the sweep on the window ('checked';\n"
            "docs/profile.md \"The decision\"), or the sample's own strategy when it has no\n"
            "recipe ('table'). A profile farther than the threshold from every sample is\n"
            "novel: then the best of the sweep on the window is chosen ('window').\n"
            "\n");
    opts_help(out, o);
    fprintf(out, "\nThe default table is %s.\n", def);
}

/* Commits an output file; the exit status. */
static int finish_output(emm_outfile *o, const char *what)
{
    emm_error err;
    return emm_outfile_commit(o, what, &err) == EMM_OK ? EMM_EXIT_OK : cli_fail(&err);
}

static int write_dump(const char *path, const double *D, size_t n)
{
    emm_error err;
    emm_outfile o;
    if (emm_outfile_open(&o, path, "the profile", &err) != EMM_OK)
        return cli_fail(&err);
    fprintf(o.f, "i,D\n");
    for (size_t i = 0; i < n; i++)
        fprintf(o.f, "%zu,%.17g\n", i, D[i]);
    return finish_output(&o, "the profile");
}

static int write_json(const char *path, const char *trace, int exact,
                      const emm_window_decision *w, const emm_strategy *answer)
{
    emm_error err;
    emm_outfile o;
    if (emm_outfile_open(&o, path, "the JSON", &err) != EMM_OK)
        return cli_fail(&err);
    const emm_decision *d = &w->table;
    char strat[96], pred[96];
    emm_strategy_format(answer ? answer : &w->strategy, strat, sizeof strat);
    emm_strategy_format(&w->strategy, pred, sizeof pred);
    json_writer jw;
    json_init(&jw, o.f, true);
    json_begin_object(&jw);
    json_key(&jw, "trace");
    json_string(&jw, trace);
    json_key(&jw, "accesses");
    json_u64(&jw, w->accesses);
    json_key(&jw, "method");
    json_string(&jw, exact ? "exact" : "fast");
    json_key(&jw, "pattern");
    json_string(&jw, d->pattern);
    json_key(&jw, "strategy");
    json_string(&jw, strat);
    json_key(&jw, "predicted");
    json_string(&jw, pred);
    json_key(&jw, "nearest");
    json_string(&jw, d->nearest);
    json_key(&jw, "distance");
    json_double(&jw, d->distance);
    json_key(&jw, "novel");
    json_bool(&jw, d->novel);
    json_key(&jw, "how");
    json_string(&jw, emm_decided_name(w->how));
    json_key(&jw, "simulated");
    json_bool(&jw, w->simulated);
    if (w->simulated) {
        json_key(&jw, "candidates");
        json_u64(&jw, w->candidates);
        json_key(&jw, "cycles");
        json_u64(&jw, w->cycles);
    }
    json_key(&jw, "features");
    json_begin_array(&jw);
    for (int k = 0; k < EMM_FEATURES; k++)
        json_double(&jw, w->f[k]);
    json_end_array(&jw);
    json_end_object(&jw);
    json_finish(&jw);
    return finish_output(&o, "the JSON");
}

/* The profile of a window of records, for --dump. */
static emm_status window_profile(const emm_trace_info *info, const emm_trace_record *recs,
                                 size_t n, const char *name, double **D, size_t *nD, int *exact,
                                 size_t *skip, emm_error *err)
{
    emm_profiler *p = NULL;
    *D = NULL;
    *nD = 0;
    emm_status st = emm_profiler_new(info, n ? n : 1, EMM_PROFILE_PLANE, name, &p, err);
    if (st == EMM_OK && (st = emm_profiler_add(p, recs, n, err)) == EMM_OK) {
        size_t np;
        emm_profiler_swept(p, skip);
        const double *xy = emm_profiler_positions(p, &np);
        *D = malloc((np ? np : 1) * sizeof **D);
        if (!*D) {
            err->status = st = EMM_ERR_NOMEM;
            snprintf(err->message, sizeof err->message, "%.300s: out of memory", name);
        } else if ((st = emm_profile_compute(xy, np, emm_profiler_dims(p), *D, exact, NULL,
                                             err)) == EMM_OK)
            *nD = np;
    }
    if (st != EMM_OK) {
        free(*D);
        *D = NULL;
    }
    emm_profiler_free(p);
    return st;
}

/* What the command line asked for. */
struct profile_args {
    machine_cli mc;
    const char *trace, *table, *dump, *json, *learn, *pattern;
    uint64_t window;
    unsigned finalists;
    double threshold;
    int simulate;
};

static int profile(void *p)
{
    struct profile_args *a = p;
    const char *trace = a->trace, *table = a->table, *dump = a->dump, *json = a->json;
    const char *learn = a->learn, *pattern = a->pattern;
    uint64_t window = a->window;
    double threshold = a->threshold;
    int simulate = a->simulate;
    unsigned finalists = a->finalists;
    emm_strategy answer;
    int has_answer = 0;
    emm_table_sample costs; /* the contest's measured costs, for --learn */
    memset(&costs, 0, sizeof costs);
    /* The user table: --table, else $EMM_TABLE; one to learn into may be new. */
    char env[EMM_CONFIG_PATH_MAX];
    const char *user = table;
    if (!user) {
        int erc = cli_env_file(EMM_CONFIG_TABLE, learn != NULL, env);
        if (erc != 0)
            return erc;
        user = env[0] ? env : NULL;
    }
    if (learn) {
        if (!user)
            return cli_usage_error(CMD, "--learn needs the user table to add to: --table FILE "
                                        "or EMM_TABLE");
        if (strlen(learn) >= EMM_TABLE_NAME_MAX || strlen(pattern) >= EMM_TABLE_NAME_MAX)
            return cli_usage_error(CMD, "--learn and --pattern take at most %d characters",
                                   EMM_TABLE_NAME_MAX - 1);
    }

    emm_machine *m = NULL;
    int rc = machine_cli_build(&a->mc, CMD, &m);
    if (rc != 0)
        return rc;
    emm_error err;
    emm_trace_reader *r;
    if (emm_trace_reader_open(trace, &r, &err) != EMM_OK) {
        emm_machine_free(m);
        return cli_fail(&err);
    }
    emm_trace_record *recs = NULL;
    double *D = NULL;
    size_t n = 0, nD = 0, skip = 0;
    int exact = 1;
    rc = EMM_EXIT_FAIL;
    emm_table *t = NULL;
    const emm_trace_info *info = emm_trace_reader_info(r);
    /* The window as the session's on this machine: it reads on until it
     * fills the local store (docs/profile.md "The window"). */
    size_t length = 0; /* the records of the window as asked for: the contest's unit */
    if (emm_profile_trace_window_fill(r, window, emm_machine_get(m, "local.bytes"), trace, &recs,
                                      &n, &length, &err) != EMM_OK ||
        window_profile(info, recs, n, trace, &D, &nD, &exact, &skip, &err) != EMM_OK) {
        rc = cli_fail(&err);
        goto done;
    }
    if (nD < EMM_PROFILE_MIN) {
        cli_error("%s: only %zu element accesses; a profile needs at least %u", trace, nD,
                  EMM_PROFILE_MIN);
        goto done;
    }
    if (dump && write_dump(dump, D, nD) != EMM_EXIT_OK)
        goto done;
    t = emm_table_new();
    if (!t) {
        cli_error("out of memory");
        goto done;
    }
    if (learn && access(user, F_OK) != 0) {
        /* The table to learn into does not exist yet: the default table
         * alone, or none (then the sweep decides). */
        char def[4096];
        if (emm_table_default_path(def, sizeof def) && emm_table_load(t, def, &err) != EMM_OK) {
            rc = cli_fail(&err);
            goto done;
        }
    } else if (emm_table_load_standard(t, user, &err) != EMM_OK) {
        rc = cli_fail(&err);
        goto done;
    }
    emm_window_decision w;
    emm_decide_options dopt = {.threshold = threshold, .simulate = simulate};
    if (emm_decide_window(t, m, info, recs, n, trace, &dopt, &w, &err) != EMM_OK) {
        rc = cli_fail(&err);
        goto done;
    }
    emm_window_decision_release(&w); /* the classes checked are not shown */
    char strat[96];
    emm_strategy_format(&w.strategy, strat, sizeof strat);
    printf("trace:     %s\n", trace);
    if (w.accesses > window)
        /* It read on to fill the local store (docs/profile.md "The window"). */
        printf("window:    %zu element accesses (%s method): read on past the %llu asked for,\n"
               "           to fill the local store (%llu bytes)\n",
               w.accesses, exact ? "exact" : "fast", (unsigned long long)window,
               (unsigned long long)emm_machine_get(m, "local.bytes"));
    else
        printf("window:    %zu element accesses (%s method)\n", w.accesses, exact ? "exact" : "fast");
    if (w.has_table) {
        printf("pattern:   %s\n", w.table.pattern);
        printf("nearest:   %s (distance %.4f)\n", w.table.nearest, w.table.distance);
        printf("novel:     %s (threshold %g)\n", w.table.novel ? "yes" : "no", threshold);
    } else {
        printf("pattern:   unknown (no table yet)\n");
    }
    if (w.simulated)
        printf("simulated: %zu strategies on the window; best %llu cycles\n", w.candidates,
               (unsigned long long)w.cycles);
    else if (w.neighbours) {
        printf("measured:  the %zu nearest runs measured on this machine (within %.3f), their "
               "costs\n           with the window's, %zu strategies\n",
               w.neighbours, w.neighbour_distance, w.candidates);
        if (w.synth_visits)
            printf("           and %s over this mesh (%zu visits) for the %d best\n",
                   strcmp(w.table.synth, "-") != 0 ? w.table.synth : w.table.pattern,
                   w.synth_visits, EMM_DECIDE_SHORTLIST);
        if (w.lead_records)
            printf("           and the leading sweep's %zu records, the run's too\n",
                   w.lead_records);
    } else if (w.how == EMM_DECIDED_CHECKED) {
        printf("checked:   %s over this mesh (%zu visits) and the window, %zu strategies\n",
               w.table.synth, w.synth_visits, w.candidates);
        if (w.lead_records)
            printf("           and the leading sweep's %zu records, the run's too\n",
                   w.lead_records);
    }
    if (!(finalists > 0 && m))
        printf("strategy:  %s\n", strat);
    if (finalists > 0 && m) {
        /* The run's contest over the whole trace, as emm run holds it when
         * it sees the whole run: the same answer on the trace it wrote. */
        emm_contest_result cr;
        if (emm_contest_trace(trace, m, &w.strategy, skip, length > skip ? length - skip : 1,
                              finalists, NULL, &cr, &err) != EMM_OK) {
            rc = cli_fail(&err);
            goto done;
        }
        char best[96], other[96] = "";
        emm_strategy_format(&cr.answer.strategy, best, sizeof best);
        printf("predicted: %s\n", strat);
        if (cr.finalists < cr.entrants)
            printf("contest:   %zu candidates over the whole trace (%llu records), the slower half\n"
                   "           dropped at 2, 4, 8, ... windows of %zu records after the leading\n"
                   "           sweep's %zu, then finalists more than 25%% behind the leader, so\n"
                   "           far and since the last check, stopped: %zu ran to the end,\n"
                   "           %zu were dropped (not measured to the end)\n",
                   cr.entrants, (unsigned long long)cr.accesses,
                   length > skip ? length - skip : 1, skip, cr.finalists,
                   cr.entrants - cr.finalists);
        else
            printf("contest:   %zu candidates over the whole trace (%llu records), every one run\n"
                   "           to the end\n",
                   cr.entrants, (unsigned long long)cr.accesses);
        printf("strategy:  %s\n", best);
        printf("run:       %s %llu cycles\n", best, (unsigned long long)cr.answer.total);
        if (cr.has_runner_up) {
            emm_strategy_format(&cr.runner_up.strategy, other, sizeof other);
            double d = cr.answer.total
                           ? (double)cr.runner_up.total / (double)cr.answer.total - 1
                           : 0;
            printf("runner-up: %s, %llu cycles (%.1f%% slower)%s\n", other,
                   (unsigned long long)cr.runner_up.total, d * 100,
                   emm_decide_is_tie(cr.answer.total, cr.runner_up.total)
                       ? ": a tie, either will do"
                       : "");
        }
        if (cr.has_predicted && cr.answer.total)
            printf("predicted: %s, %llu cycles over the trace, %.2fx the answer\n", strat,
                   (unsigned long long)cr.predicted.total,
                   (double)cr.predicted.total / (double)cr.answer.total);
        answer = cr.answer.strategy;
        has_answer = 1;
        /* What the run measured, for --learn: the answer, the runner-up and
         * the prediction, each one's cycles over the answer's. */
        const emm_result *ran[3] = {&cr.answer, cr.has_runner_up ? &cr.runner_up : NULL,
                                    cr.has_predicted ? &cr.predicted : NULL};
        for (int q = 0; q < 3 && cr.answer.total; q++) {
            bool dup = !ran[q];
            for (uint32_t c = 0; c < costs.ncosts && !dup; c++) {
                char x[96], y[96];
                emm_strategy_format(&costs.cost_strategy[c], x, sizeof x);
                emm_strategy_format(&ran[q]->strategy, y, sizeof y);
                dup = strcmp(x, y) == 0;
            }
            if (dup)
                continue;
            costs.cost_strategy[costs.ncosts] = ran[q]->strategy;
            costs.cost[costs.ncosts++] = (double)ran[q]->total / (double)cr.answer.total;
        }
    } else if (w.has_runner_up && m) {
        /* The choice and the runner-up over the whole trace, as emm run's
         * summary weighs them: within the tie margin, either will do. */
        char other[96];
        emm_strategy_format(&w.runner_up, other, sizeof other);
        emm_strategy two[2] = {w.strategy, w.runner_up};
        emm_result res[2];
        uint64_t acc;
        if (emm_replay(trace, m, two, 2, res, &acc, NULL, NULL, &err) != EMM_OK) {
            rc = cli_fail(&err);
            goto done;
        }
        double d = res[0].total ? (double)res[1].total / (double)res[0].total - 1 : 0;
        printf("runner-up: %s\n", other);
        printf("run:       %s %llu cycles, %s %llu cycles (%.1f%% %s)%s\n", strat,
               (unsigned long long)res[0].total, other, (unsigned long long)res[1].total,
               fabs(d) * 100, d >= 0 ? "slower" : "faster",
               emm_decide_is_tie(res[0].total, res[1].total) ? ": a tie, either will do" : "");
        emm_result_release(&res[0]);
        emm_result_release(&res[1]);
    }
    rc = EMM_EXIT_OK;
    /* What is learnt: the run's answer when the contest held it (the best
     * measured over the whole trace, the table's "table expanded to cover
     * more applications"), else the window's sweep when it ran. */
    if (learn && (has_answer || w.simulated)) {
        emm_table_sample s;
        memset(&s, 0, sizeof s);
        snprintf(s.name, sizeof s.name, "%s", learn);
        snprintf(s.pattern, sizeof s.pattern, "%s", pattern);
        s.strategy = has_answer ? answer : w.strategy;
        memcpy(s.f, w.f, sizeof s.f);
        snprintf(s.machine, sizeof s.machine, "-");
        if (has_answer && costs.ncosts) {
            /* Measured over the whole run on this machine: it decides there
             * (docs/profile.md "The neighbours' costs"). */
            emm_table_machine_id(m, s.machine);
            s.ncosts = costs.ncosts;
            memcpy(s.cost_strategy, costs.cost_strategy, sizeof s.cost_strategy);
            memcpy(s.cost, costs.cost, sizeof s.cost);
        }
        if (emm_table_append(user, &s, &err) != EMM_OK) {
            rc = cli_fail(&err);
            goto done;
        }
        char learnt[96];
        emm_strategy_format(&s.strategy, learnt, sizeof learnt);
        printf("learnt:    %s (%s, %s, %s) added to %s\n", s.name, s.pattern, learnt,
               has_answer ? "the contest's answer over the run" : "the window's sweep", user);
    } else if (learn) {
        printf("learnt:    nothing (--finalists 0 and not novel; --simulate learns the "
               "window's sweep)\n");
    }
    if (json)
        rc = write_json(json, trace, exact, &w, has_answer ? &answer : NULL);
done:
    emm_table_free(t);
    free(recs);
    free(D);
    emm_trace_reader_close(r);
    emm_machine_free(m);
    return rc;
}

/* --finalists: EMM_FINALISTS's row of the configuration table parses it, so
 * that emm profile holds the contest emm run would (a count, or all). */
static bool finalists_option(void *dst, const char *as, const char *value)
{
    emm_config c;
    emm_error err;
    emm_config_init(&c);
    if (emm_config_set(&c, EMM_CONFIG_FINALISTS, value, as, 0, &err) != EMM_OK) {
        cli_bad_value(CMD, &err);
        return false;
    }
    *(unsigned *)dst = c.finalists;
    return true;
}

int emm_cmd_profile(int argc, char **argv)
{
    struct profile_args a = {.pattern = "user", .window = EMM_PROFILE_DEFAULT_WINDOW,
                             .finalists = EMM_CONFIG_DEFAULT_FINALISTS,
                             .threshold = EMM_NOVELTY_THRESHOLD};
    opts_row rows[] = {
        {.name = "--window", .metavar = "N", .kind = OPT_U64, .dst = &a.window,
         .min = EMM_PROFILE_MIN, .show_default = true,
         .help = "element accesses to profile, read on to 1.5 N at most for a mesh larger than "
                 "the machine's local store, until their records fill it (as emm run's window); "
                 "up to " EXACT_MAX_TEXT " use the exact method, longer windows the fast one"},
        {.name = "--table", .metavar = "FILE", .kind = OPT_TEXT, .dst = &a.table,
         .help = "a user table added to the default one (default: $EMM_TABLE)"},
        {.name = "--threshold", .metavar = "X", .kind = OPT_POSITIVE, .dst = &a.threshold,
         .show_default = true, .help = "novelty threshold on the nearest distance"},
        {.name = "--simulate", .kind = OPT_FLAG, .dst = &a.simulate,
         .help = "simulate the sweep on the window even when not novel"},
        {.name = "--finalists", .metavar = "N", .kind = OPT_CALL, .dst = &a.finalists,
         .call = finalists_option,
         .help = "the run's contest, as emm run holds it: every candidate from the trace's "
                 "start, the slower half dropped at 2, 4, 8, ... windows until N remain, then "
                 "finalists more than 25% behind the leader, so far and since the last check, "
                 "stopped; the "
                 "fastest of those that ran to the end is the answer; all: none is dropped; 0: "
                 "the window's prediction stands (default " EMM_CONFIG_DEFAULT_FINALISTS_TEXT ")"},
        {.name = "--learn", .metavar = "NAME", .kind = OPT_TEXT, .dst = &a.learn,
         .help = "append the profile as sample NAME to the user table (--table or $EMM_TABLE, "
                 "created when missing) with the contest's answer over the whole trace, or, "
                 "with --finalists 0, the window sweep's best when the sweep ran"},
        {.name = "--pattern", .metavar = "CLASS", .kind = OPT_TEXT, .dst = &a.pattern,
         .show_default = true, .help = "the pattern class of a learnt sample"},
        MACHINE_CLI_OPTS(&a.mc),
        {.name = "--dump", .metavar = "FILE", .kind = OPT_TEXT, .dst = &a.dump,
         .help = "write the profile as CSV with the columns i,D"},
        {.name = "--json", .metavar = "FILE", .kind = OPT_TEXT, .dst = &a.json,
         .help = "write pattern, strategy, nearest, distance, novel as JSON"},
        {.metavar = "TRACE", .kind = OPT_TEXT, .dst = &a.trace, .required = true},
        OPTS_END,
    };
    opts o = {CMD, rows, usage};
    return opts_run(&o, argc, argv, profile, &a);
}
