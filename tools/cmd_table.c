/* emm table: list the strategy table's samples, add a trace's profile as a
 * sample (thesis §5: the table grows with new applications), and build the
 * shipped default table from canonical patterns over generated meshes, each
 * sample's strategy chosen by simulating the standard sweep. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "synth_internal.h"
#include "emm/mesh.h"
#include "emm/profile.h"
#include "emm/synth.h"
#include "emm/table.h"
#include "emm/trace.h"
#include "machine_cli.h"
#include "opts.h"

static void usage_head(FILE *out)
{
    char def[4096];
    emm_table_default_path(def, sizeof def);
    fprintf(out,
            "usage: emm table list [--table FILE]\n"
            "       emm table add PROFILE --name NAME [--strategy S] [--pattern CLASS]\n"
            "                     [--window N] [--table FILE] [--machine FILE] [--set K=V]...\n"
            "       emm table build [-o FILE] [--quick] [--program TRACE:CLASS:RECIPE]...\n"
            "                       [--program-machine FILE]... [--machine FILE] [--set K=V]...\n"
            "\n"
            "The strategy table maps distance-profile samples to strategies. The default\n"
            "table is %s; a user table\n"
            "(--table FILE, or $EMM_TABLE) adds to it.\n"
            "\n"
            "  list   print every sample: name, pattern class, strategy, source file\n"
            "  add    profile the trace PROFILE (its first N element accesses, default %u)\n"
            "         and append it to the user table (created when missing) as NAME with\n"
            "         strategy S, or without --strategy the best of the standard sweep\n"
            "         simulated on that window; pattern CLASS (default 'user')\n"
            "  build  generate the default table: canonical patterns (random, region from a\n"
            "         random and from a corner seed and over vertices' one-rings, short and\n"
            "         long curves, scan lines, Z-order, Gray code, Hilbert, spiral) over\n"
            "         generated meshes, profiled at windows of 4096, 16384 and 65536 element\n"
            "         accesses, each sample's strategy the best of the standard sweep\n"
            "         simulated on the whole traversal (the run a decision on the window is\n"
            "         for). Deterministic. -o FILE (default: the default table above);\n"
            "         --quick: two meshes and two windows, for tests. --program\n"
            "         TRACE:CLASS:RECIPE adds samples of a program's trace (EMM_TRACE / emm\n"
            "         run --trace), named prog-<file name>-wN, of pattern CLASS and synthetic\n"
            "         recipe RECIPE (a pattern of emm trace synth, region@corner,\n"
            "         region@ring, curve@N, or -), labelled as the canonical ones\n"
            "         (scripts/table.sh makes the shipped table so, from the example\n"
            "         workloads' traces on meshes the tests do not use); a program's sample\n"
            "         also carries the machine's fingerprint and its run's costs (the fastest\n"
            "         strategies' cycles over the best's), which decide on that machine;\n"
            "         --program-machine FILE measures the programs again on another machine\n",
            def, EMM_PROFILE_DEFAULT_WINDOW);
}

static void usage_all(FILE *out)
{
    usage_head(out);
    fprintf(out, "\n'emm table SUBCOMMAND --help' lists each subcommand's options.\n");
}

static void usage(FILE *out, const opts *o)
{
    usage_head(out);
    fprintf(out, "\noptions of emm %s:\n", o->cmd);
    opts_help(out, o);
}

/* The user table: --table, else $EMM_TABLE (read by the configuration
 * table), else ""; a table to add to may not exist yet. */
static int user_table(const char *table, bool to_add, char path[EMM_CONFIG_PATH_MAX])
{
    if (!table)
        return cli_env_file(EMM_CONFIG_TABLE, to_add, path);
    if (strlen(table) >= EMM_CONFIG_PATH_MAX)
        return cli_usage_error("table", "--table: path too long");
    strcpy(path, table);
    return 0;
}

static int table_list(int argc, char **argv)
{
    const char *table = NULL;
    char user[EMM_CONFIG_PATH_MAX];
    opts_row rows[] = {
        {.name = "--table", .metavar = "FILE", .kind = OPT_TEXT, .dst = &table,
         .help = "the user table (default: $EMM_TABLE)"},
        OPTS_END,
    };
    opts o = {"table list", rows, usage};
    int rc;
    if (opts_parse(&o, argc, argv, &rc) || (rc = user_table(table, false, user)) != 0)
        return rc;
    emm_error err;
    emm_table *t = emm_table_new();
    if (!t) {
        cli_error("out of memory");
        return EMM_EXIT_FAIL;
    }
    if (emm_table_load_standard(t, user[0] ? user : NULL, &err) != EMM_OK) {
        emm_table_free(t);
        return cli_fail(&err);
    }
    printf("%-24s %-9s %-24s %s\n", "name", "pattern", "strategy", "source");
    for (size_t i = 0; i < emm_table_count(t); i++) {
        const emm_table_sample *s = emm_table_at(t, i);
        char strat[96];
        emm_strategy_format(&s->strategy, strat, sizeof strat);
        printf("%-24s %-9s %-24s %s\n", s->name, s->pattern, strat, emm_table_source(t, i));
    }
    printf("%zu samples\n", emm_table_count(t));
    emm_table_free(t);
    return EMM_EXIT_OK;
}

/* The features of a trace's first `window` element accesses; *n receives
 * how many there were. */
static emm_status window_features(emm_trace_reader *r, uint64_t window, const char *name,
                                  double f[EMM_FEATURES], size_t *n, emm_error *err)
{
    double *xy = NULL, *D = NULL;
    emm_status st = emm_profile_trace_positions(r, window, EMM_PROFILE_PLANE, name, &xy, n, err);
    if (st == EMM_OK && *n < EMM_PROFILE_MIN) {
        err->status = st = EMM_ERR_RANGE;
        snprintf(err->message, sizeof err->message,
                 "%.300s: only %zu element accesses; a profile needs at least %u", name, *n,
                 EMM_PROFILE_MIN);
    }
    if (st == EMM_OK && !(D = malloc(*n * sizeof *D))) {
        err->status = st = EMM_ERR_NOMEM;
        snprintf(err->message, sizeof err->message, "%.300s: out of memory", name);
    }
    if (st == EMM_OK)
        st = emm_profile_compute(xy, *n, EMM_PROFILE_PLANE, D, NULL, NULL, err);
    if (st == EMM_OK)
        st = emm_profile_features(D, *n, name, f, err);
    free(xy);
    free(D);
    return st;
}

/* table add without --strategy: the best of the sweep on the window. */
static int table_add_swept(const char *trace, const char *table, uint64_t window,
                           machine_cli *mc, emm_table_sample *s)
{
    emm_machine *m = NULL;
    int rc = machine_cli_build(mc, "table add", &m);
    if (rc != 0)
        return rc;
    emm_error err;
    emm_trace_reader *r;
    if (emm_trace_reader_open(trace, &r, &err) != EMM_OK) {
        emm_machine_free(m);
        return cli_fail(&err);
    }
    emm_trace_record *recs = NULL;
    size_t n = 0;
    emm_window_decision w;
    emm_decide_options dopt = {.simulate = 1};
    rc = EMM_EXIT_OK;
    if (emm_profile_trace_window(r, window, trace, &recs, &n, &err) != EMM_OK ||
        emm_decide_window(NULL, m, emm_trace_reader_info(r), recs, n, trace, &dopt, &w, &err) !=
            EMM_OK) {
        rc = cli_fail(&err);
    } else {
        emm_window_decision_release(&w); /* the classes checked are not used */
        s->strategy = w.strategy;
        memcpy(s->f, w.f, sizeof s->f);
        if (emm_table_append(table, s, &err) != EMM_OK) {
            rc = cli_fail(&err);
        } else {
            char strat[96];
            emm_strategy_format(&s->strategy, strat, sizeof strat);
            printf("added %s (%s, %s: the best of %zu strategies, %llu cycles on the window) "
                   "to %s\n",
                   s->name, s->pattern, strat, w.candidates, (unsigned long long)w.cycles, table);
        }
    }
    free(recs);
    emm_trace_reader_close(r);
    emm_machine_free(m);
    return rc;
}

/* table add's command line. */
struct add_args {
    machine_cli mc;
    const char *table, *trace, *name, *strategy, *pattern;
    uint64_t window;
};

static int table_add_run(void *p)
{
    struct add_args *a = p;
    const char *cmd = "table add", *trace = a->trace, *name = a->name;
    const char *strategy = a->strategy, *pattern = a->pattern;
    uint64_t window = a->window;
    char table[EMM_CONFIG_PATH_MAX];
    int rc = user_table(a->table, true, table);
    if (rc != 0)
        return rc;
    if (!table[0])
        return cli_usage_error(cmd, "say which user table to add to: --table FILE or "
                                    "EMM_TABLE");

    emm_error err;
    emm_table_sample s;
    memset(&s, 0, sizeof s);
    if (strlen(name) >= sizeof s.name || strlen(pattern) >= sizeof s.pattern)
        return cli_usage_error(cmd, "--name and --pattern take at most %d characters",
                               EMM_TABLE_NAME_MAX - 1);
    snprintf(s.name, sizeof s.name, "%s", name);
    snprintf(s.pattern, sizeof s.pattern, "%s", pattern);
    if (!strategy)
        return table_add_swept(trace, table, window, &a->mc, &s);
    emm_strategy_parse(strategy, &s.strategy, NULL); /* checked by opts_parse */

    emm_trace_reader *r;
    if (emm_trace_reader_open(trace, &r, &err) != EMM_OK)
        return cli_fail(&err);
    size_t n = 0;
    if (window_features(r, window, trace, s.f, &n, &err) != EMM_OK ||
        emm_table_append(table, &s, &err) != EMM_OK)
        rc = cli_fail(&err);
    else
        printf("added %s (%s, %s) to %s\n", s.name, s.pattern, strategy, table);
    emm_trace_reader_close(r);
    return rc;
}

static int table_add(int argc, char **argv)
{
    struct add_args a = {.pattern = "user", .window = EMM_PROFILE_DEFAULT_WINDOW};
    opts_row rows[] = {
        {.name = "--name", .metavar = "NAME", .kind = OPT_TEXT, .dst = &a.name, .required = true,
         .help = "the sample's name (required)"},
        {.name = "--strategy", .metavar = "S", .kind = OPT_STRATEGY, .dst = &a.strategy,
         .help = "the sample's strategy (default: the best of the standard sweep simulated on "
                 "the window)"},
        {.name = "--pattern", .metavar = "CLASS", .kind = OPT_TEXT, .dst = &a.pattern,
         .show_default = true, .help = "the sample's pattern class"},
        {.name = "--window", .metavar = "N", .kind = OPT_U64, .dst = &a.window,
         .min = EMM_PROFILE_MIN, .show_default = true, .help = "element accesses to profile"},
        {.name = "--table", .metavar = "FILE", .kind = OPT_TEXT, .dst = &a.table,
         .help = "the user table to add to, created when missing (default: $EMM_TABLE)"},
        MACHINE_CLI_OPTS(&a.mc),
        {.metavar = "PROFILE", .kind = OPT_TEXT, .dst = &a.trace, .required = true},
        OPTS_END,
    };
    opts o = {"table add", rows, usage};
    return opts_run(&o, argc, argv, table_add_run, &a);
}

/* ---- emm table build ----------------------------------------------------- */

/* The canonical patterns (thesis Table 5.1 and Figs. 5.2–5.3), each a
 * synthetic recipe (the table's synth column): "@corner" grows the region
 * from the corner, "@24" makes curves of 24 triangles. */
static const struct {
    const char *name, *cls, *recipe;
} build_patterns[] = {
    {"random", "random", "random"},
    {"region", "region", "region"},
    {"region-corner", "region", "region@corner"},
    {"region-ring", "region", "region@ring"},
    {"curve", "curve", "curve"},
    {"curve-short", "curve", "curve@24"},
    {"scanline", "scanline", "scanline"},
    {"zorder", "zorder", "zorder"},
    {"gray", "gray", "gray"},
    {"hilbert", "hilbert", "hilbert"},
    {"spiral", "spiral", "spiral"},
};

static const struct {
    size_t faces;
    emm_density density;
    uint64_t seed;
} build_meshes[] = {
    {6000, EMM_DENSITY_UNIFORM, 11},
    {12000, EMM_DENSITY_CLUSTERED, 12},
    {24000, EMM_DENSITY_UNIFORM, 13},
    {20000, EMM_DENSITY_CLUSTERED, 14},
};

static const uint64_t build_windows[] = {4096, 16384, 65536};

/* Adds the samples of one trace to t: its features at each window of
 * build_windows (the first nwin; a window past the end of the trace is
 * dropped), named PREFIX-wN, of class `cls` and recipe `recipe`, each with
 * the strategy that serves the whole traversal best — the run a decision
 * made on the window is for. */
/* A program's sample (recipe "-") carries the machine it was measured on
 * and its run's costs: the fastest EMM_TABLE_COSTS strategies the machine
 * offers, each one's cycles over the fastest's (docs/profile.md "The
 * neighbours' costs"). */
static void set_costs(emm_table_sample *smp, const emm_machine *m, const emm_sweep *sw)
{
    emm_table_machine_id(m, smp->machine);
    uint64_t best = 0;
    for (uint32_t c = 0; c < EMM_TABLE_COSTS; c++) {
        size_t pick = SIZE_MAX;
        for (size_t i = 0; i < sw->count; i++) {
            if (!sw->ran[i] || !emm_machine_offers(m, &sw->result[i].strategy))
                continue;
            bool taken = false;
            for (uint32_t q = 0; q < c && !taken; q++) {
                char a[96], b[96];
                emm_strategy_format(&smp->cost_strategy[q], a, sizeof a);
                emm_strategy_format(&sw->result[i].strategy, b, sizeof b);
                taken = strcmp(a, b) == 0;
            }
            if (!taken && (pick == SIZE_MAX || sw->result[i].total < sw->result[pick].total))
                pick = i;
        }
        if (pick == SIZE_MAX || (c == 0 && sw->result[pick].total == 0))
            break;
        if (c == 0)
            best = sw->result[pick].total;
        smp->cost_strategy[c] = sw->result[pick].strategy;
        smp->cost[c] = (double)sw->result[pick].total / (double)best;
        smp->ncosts = c + 1;
    }
}

static int add_trace_samples(emm_table *t, const emm_machine *m, const char *trace,
                             const char *prefix, const char *suffix, const char *cls,
                             const char *recipe, size_t nwin)
{
    emm_error err;
    emm_trace_reader *r;
    if (emm_trace_reader_open(trace, &r, &err) != EMM_OK)
        return cli_fail(&err);
    int rc = EMM_EXIT_OK;
    emm_trace_record *all = NULL;
    size_t nall = 0;
    emm_sweep *sw = NULL;
    if (emm_profile_trace_window(r, UINT64_MAX, trace, &all, &nall, &err) != EMM_OK ||
        emm_sweep_records(m, emm_trace_reader_info(r), all, nall, NULL, &sw, &err) != EMM_OK) {
        rc = cli_fail(&err);
    }
    free(all);
    size_t covered = 0;
    for (size_t w = 0; w < nwin && rc == EMM_EXIT_OK; w++) {
        emm_table_sample smp;
        memset(&smp, 0, sizeof smp);
        size_t np = 0;
        if (window_features(r, build_windows[w], trace, smp.f, &np, &err) != EMM_OK) {
            rc = cli_fail(&err);
            break;
        }
        if (np <= covered)
            break;
        covered = np;
        snprintf(smp.name, sizeof smp.name, "%s-w%zu%s", prefix, np, suffix);
        snprintf(smp.pattern, sizeof smp.pattern, "%s", cls);
        snprintf(smp.synth, sizeof smp.synth, "%s", recipe);
        snprintf(smp.machine, sizeof smp.machine, "-");
        smp.strategy = sw->result[sw->best].strategy;
        if (strcmp(recipe, "-") == 0)
            set_costs(&smp, m, sw);
        if (emm_table_add(t, &smp, &err) != EMM_OK) {
            rc = cli_fail(&err);
            break;
        }
        char strat[96];
        emm_strategy_format(&smp.strategy, strat, sizeof strat);
        printf("%-28s %-9s %-24s %llu cycles (best of %zu; cache %llu)\n", smp.name, smp.pattern,
               strat, (unsigned long long)sw->result[sw->best].total, sw->simulated,
               (unsigned long long)sw->result[sw->cache].total);
        fflush(stdout);
    }
    emm_sweep_free(sw);
    emm_trace_reader_close(r);
    return rc;
}

/* --program TRACE:CLASS:RECIPE — a real program's trace (EMM_TRACE). */
struct program_trace {
    char path[512], cls[EMM_TABLE_NAME_MAX], recipe[EMM_TABLE_NAME_MAX], prefix[EMM_TABLE_NAME_MAX];
};

static int parse_program(const char *cmd, const char *v, struct program_trace *p)
{
    const char *c2 = strrchr(v, ':');
    const char *c1 = NULL;
    for (const char *q = v; c2 && q < c2; q++)
        if (*q == ':')
            c1 = q;
    if (!c1 || c1 == v || c2 == c1 + 1 || !c2[1])
        return cli_usage_error(cmd, "--program takes TRACE:CLASS:RECIPE, not '%s'", v);
    size_t lp = (size_t)(c1 - v), lc = (size_t)(c2 - c1 - 1);
    if (lp >= sizeof p->path || lc >= sizeof p->cls || strlen(c2 + 1) >= sizeof p->recipe)
        return cli_usage_error(cmd, "--program '%s': too long", v);
    memcpy(p->path, v, lp);
    p->path[lp] = '\0';
    memcpy(p->cls, c1 + 1, lc);
    p->cls[lc] = '\0';
    snprintf(p->recipe, sizeof p->recipe, "%s", c2 + 1);
    emm_synth_options so;
    emm_error err;
    if (strcmp(p->recipe, "-") != 0 && emm_synth_recipe_parse(p->recipe, &so, &err) != EMM_OK)
        return cli_usage_error(cmd, "--program '%s': %s", v, err.message);
    /* The sample names: "prog-" and the trace's file name without its extension. */
    const char *base = strrchr(p->path, '/');
    base = base ? base + 1 : p->path;
    size_t lb = strcspn(base, ".");
    if (lb > 40)
        lb = 40;
    snprintf(p->prefix, sizeof p->prefix, "prog-%.*s", (int)lb, base);
    return EMM_EXIT_OK;
}

/* table build's command line. */
struct build_args {
    machine_cli mc;
    const char *out;
    int quick;
    opts_list programs; /* --program values */
    opts_list also;     /* --program-machine values */
};

static int table_build_with(struct build_args *a, struct program_trace *progs)
{
    const char *cmd = "table build", *out = a->out;
    int quick = a->quick;
    size_t nprog = a->programs.n;
    for (size_t k = 0; k < nprog; k++) {
        int prc = parse_program(cmd, a->programs.v[k], &progs[k]);
        if (prc != EMM_EXIT_OK)
            return prc;
    }
    char def[4096];
    if (!out) {
        emm_table_default_path(def, sizeof def);
        out = def;
    }
    emm_machine *m = NULL;
    int rc = machine_cli_build(&a->mc, cmd, &m);
    if (rc != 0)
        return rc;

    const char *tmpdir = getenv("TMPDIR");
    char dir[512];
    snprintf(dir, sizeof dir, "%s/emm-table-XXXXXX", tmpdir && *tmpdir ? tmpdir : "/tmp");
    emm_table *t = emm_table_new();
    if (!t || !mkdtemp(dir)) {
        cli_error("%s: cannot make a scratch directory: %s", dir, strerror(errno));
        emm_table_free(t);
        emm_machine_free(m);
        return EMM_EXIT_FAIL;
    }
    char trace[600];
    snprintf(trace, sizeof trace, "%s/pattern.emmt", dir);
    size_t nmesh = quick ? 2 : sizeof build_meshes / sizeof build_meshes[0];
    size_t nwin = quick ? 2 : sizeof build_windows / sizeof build_windows[0];
    emm_error err;
    rc = EMM_EXIT_OK;
    for (size_t g = 0; g < nmesh && rc == EMM_EXIT_OK; g++) {
        emm_gen_options go = {build_meshes[g].faces, build_meshes[g].seed,
                              build_meshes[g].density, EMM_ORDER_INPUT};
        emm_mesh *mesh;
        if (emm_mesh_generate(&go, &mesh, &err) != EMM_OK) {
            rc = cli_fail(&err);
            break;
        }
        for (size_t p = 0; p < sizeof build_patterns / sizeof build_patterns[0]; p++) {
            emm_synth_options so = {.seed = 100 + build_meshes[g].seed};
            if (emm_synth_recipe_parse(build_patterns[p].recipe, &so, &err) != EMM_OK ||
                emm_synth_trace(mesh, &so, trace, NULL, &err) != EMM_OK) {
                rc = cli_fail(&err);
                break;
            }
            char prefix[EMM_TABLE_NAME_MAX];
            snprintf(prefix, sizeof prefix, "%s-%zuk%c", build_patterns[p].name,
                     build_meshes[g].faces / 1000,
                     build_meshes[g].density == EMM_DENSITY_UNIFORM ? 'u' : 'c');
            rc = add_trace_samples(t, m, trace, prefix, "", build_patterns[p].cls,
                                   build_patterns[p].recipe, nwin);
            remove(trace);
            if (rc != EMM_EXIT_OK)
                break;
        }
        emm_mesh_free(mesh);
    }
    rmdir(dir);
    for (size_t k = 0; k < nprog && rc == EMM_EXIT_OK; k++)
        rc = add_trace_samples(t, m, progs[k].path, progs[k].prefix, "", progs[k].cls,
                               progs[k].recipe, nwin);
    /* The programs again on each --program-machine, named ...@FILE-BASE. */
    for (size_t x = 0; x < a->also.n && rc == EMM_EXIT_OK; x++) {
        const char *path = a->also.v[x];
        emm_machine *m2 = NULL;
        if (emm_machine_new(&m2, &err) != EMM_OK || emm_machine_load(m2, path, &err) != EMM_OK) {
            emm_machine_free(m2);
            rc = cli_fail(&err);
            break;
        }
        const char *base = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
        char suffix[24];
        snprintf(suffix, sizeof suffix, "@%.*s", (int)strcspn(base, "."), base);
        for (size_t k = 0; k < nprog && rc == EMM_EXIT_OK; k++)
            rc = add_trace_samples(t, m2, progs[k].path, progs[k].prefix, suffix, progs[k].cls,
                                   progs[k].recipe, nwin);
        emm_machine_free(m2);
    }
    if (rc == EMM_EXIT_OK) {
        char comment[1024];
        int len = snprintf(comment, sizeof comment,
                           "Generated by `emm table build%s%s%s%s`; do not edit by hand, rebuild.\n"
                           "Samples: canonical patterns (emm trace synth, seed 100 + the mesh's)\n"
                           "over planar Delaunay meshes (emm mesh gen):",
                           quick ? " --quick" : "", a->mc.file ? " --machine " : "",
                           a->mc.file ? a->mc.file : "", nprog ? " --program ..." : "");
        for (size_t g = 0; g < nmesh && len > 0 && (size_t)len < sizeof comment; g++)
            len += snprintf(comment + len, sizeof comment - (size_t)len, " %zu %s faces seed %llu%s",
                            build_meshes[g].faces,
                            build_meshes[g].density == EMM_DENSITY_UNIFORM ? "uniform"
                                                                            : "clustered",
                            (unsigned long long)build_meshes[g].seed, g + 1 < nmesh ? "," : ";");
        if (len > 0 && (size_t)len < sizeof comment && nprog)
            len += snprintf(comment + len, sizeof comment - (size_t)len,
                            "\nand %zu traces of programs (the prog-* samples; scripts/table.sh),"
                            "\nwith their runs' costs on this machine%s%s;",
                            nprog, a->also.n ? " and on " : "",
                            a->also.n ? "each --program-machine (the @ samples)" : "");
        if (len > 0 && (size_t)len < sizeof comment)
            snprintf(comment + len, sizeof comment - (size_t)len,
                     "\nwindows of %s element accesses; each strategy is the fewest cycles of\n"
                     "the standard sweep simulated on the whole traversal (%s machine%s).",
                     quick ? "4096 and 16384" : "4096, 16384 and 65536",
                     a->mc.file || a->mc.sets.n ? "a configured" : "the default",
                     a->mc.sets.n ? " with --set overrides" : "");
        if (emm_table_write(t, out, comment, &err) != EMM_OK)
            rc = cli_fail(&err);
        else
            printf("wrote %s: %zu samples\n", out, emm_table_count(t));
    }
    emm_table_free(t);
    emm_machine_free(m);
    return rc;
}

/* table build with an array for the --program traces. */
static int table_build_run(void *p)
{
    struct build_args *a = p;
    struct program_trace *progs = calloc(a->programs.n ? a->programs.n : 1, sizeof *progs);
    int rc;
    if (progs) {
        rc = table_build_with(a, progs);
    } else {
        cli_error("out of memory");
        rc = EMM_EXIT_FAIL;
    }
    free(progs);
    return rc;
}

static int table_build(int argc, char **argv)
{
    struct build_args a = {0};
    opts_row rows[] = {
        {.name = "-o", .alias = "--output", .metavar = "FILE", .kind = OPT_TEXT, .dst = &a.out,
         .help = "the table to write (default: the default table)"},
        {.name = "--quick", .kind = OPT_FLAG, .dst = &a.quick,
         .help = "two meshes and two windows, for tests"},
        {.name = "--program", .metavar = "TRACE:CLASS:RECIPE", .kind = OPT_TEXT, .repeat = true,
         .dst = &a.programs,
         .help = "add the samples of a program's trace, of pattern CLASS and synthetic recipe "
                 "RECIPE; may be repeated"},
        {.name = "--program-machine", .metavar = "FILE", .kind = OPT_TEXT, .repeat = true,
         .dst = &a.also,
         .help = "also measure the --program traces' runs on the machine of FILE, as samples "
                 "named ...@FILE's base name; may be repeated"},
        MACHINE_CLI_OPTS(&a.mc),
        OPTS_END,
    };
    opts o = {"table build", rows, usage};
    return opts_run(&o, argc, argv, table_build_run, &a);
}

int emm_cmd_table(int argc, char **argv)
{
    static const opts_sub subs[] = {{"list", table_list}, {"add", table_add},
                                    {"build", table_build}, {NULL, NULL}};
    return opts_subcommand("table", subs, usage_all, argc, argv);
}
