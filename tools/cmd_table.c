/* emm table: list the strategy table's samples, add a trace's profile as a
 * sample (thesis §5: the table grows with new applications). `emm table
 * build`, which generates the shipped default table by simulating the
 * standard sweep, comes with the strategy simulation. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "emm/profile.h"
#include "emm/table.h"
#include "emm/trace.h"

static void usage(FILE *out)
{
    fprintf(out,
            "usage: emm table list [--table FILE]\n"
            "       emm table add PROFILE --name NAME --strategy S [--pattern CLASS]\n"
            "                     [--window N] [--table FILE]\n"
            "\n"
            "The strategy table maps distance-profile samples to strategies. The default\n"
            "table is %s; a user table\n"
            "(--table FILE, or $EMM_TABLE) adds to it.\n"
            "\n"
            "  list   print every sample: name, pattern class, strategy, source file\n"
            "  add    profile the trace PROFILE (its first N element accesses, default %u)\n"
            "         and append it to the user table (created when missing) as NAME with\n"
            "         strategy S (required for now: choosing the best of the standard sweep\n"
            "         needs the strategy simulation) and pattern CLASS (default 'user')\n",
            emm_table_default_path(), EMM_PROFILE_DEFAULT_WINDOW);
}

static int table_list(int argc, char **argv)
{
    const char *cmd = "table list", *table = NULL;
    for (int i = 1; i < argc; i++) {
        if (cli_is_help(argv[i])) {
            usage(stdout);
            return EMM_EXIT_OK;
        } else if (strcmp(argv[i], "--table") == 0) {
            if (!(table = cli_value(cmd, argc, argv, &i)))
                return EMM_EXIT_USAGE;
        } else {
            return cli_usage_error(cmd, "unexpected argument '%s'", argv[i]);
        }
    }
    emm_error err;
    emm_table *t = emm_table_new();
    if (!t) {
        cli_error("out of memory");
        return EMM_EXIT_FAIL;
    }
    if (emm_table_load_standard(t, table, &err) != EMM_OK) {
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

static int table_add(int argc, char **argv)
{
    const char *cmd = "table add", *table = NULL, *trace = NULL, *name = NULL, *strategy = NULL;
    const char *pattern = "user";
    uint64_t window = EMM_PROFILE_DEFAULT_WINDOW;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (cli_is_help(a)) {
            usage(stdout);
            return EMM_EXIT_OK;
        } else if (strcmp(a, "--table") == 0) {
            if (!(table = cli_value(cmd, argc, argv, &i)))
                return EMM_EXIT_USAGE;
        } else if (strcmp(a, "--name") == 0) {
            if (!(name = cli_value(cmd, argc, argv, &i)))
                return EMM_EXIT_USAGE;
        } else if (strcmp(a, "--strategy") == 0) {
            if (!(strategy = cli_value(cmd, argc, argv, &i)))
                return EMM_EXIT_USAGE;
        } else if (strcmp(a, "--pattern") == 0) {
            if (!(pattern = cli_value(cmd, argc, argv, &i)))
                return EMM_EXIT_USAGE;
        } else if (strcmp(a, "--window") == 0) {
            const char *v = cli_value(cmd, argc, argv, &i);
            if (!v || !cli_u64(cmd, a, v, &window))
                return EMM_EXIT_USAGE;
            if (window < EMM_PROFILE_MIN)
                return cli_usage_error(cmd, "--window must be at least %u", EMM_PROFILE_MIN);
        } else if (a[0] == '-' && a[1] != '\0') {
            return cli_usage_error(cmd, "unknown option '%s'", a);
        } else if (!trace) {
            trace = a;
        } else {
            return cli_usage_error(cmd, "one PROFILE trace only ('%s' is extra)", a);
        }
    }
    if (!trace)
        return cli_usage_error(cmd, "a PROFILE trace is required");
    if (!name)
        return cli_usage_error(cmd, "--name is required");
    if (!strategy)
        return cli_usage_error(cmd, "--strategy is required (the sweep that would choose one "
                                    "is not built yet)");
    if (!table) {
        const char *env = getenv("EMM_TABLE");
        if (!env || !*env)
            return cli_usage_error(cmd, "say which user table to add to: --table FILE or "
                                        "EMM_TABLE");
        table = env;
    }

    emm_error err;
    emm_table_sample s;
    memset(&s, 0, sizeof s);
    if (strlen(name) >= sizeof s.name || strlen(pattern) >= sizeof s.pattern)
        return cli_usage_error(cmd, "--name and --pattern take at most %d characters",
                               EMM_TABLE_NAME_MAX - 1);
    snprintf(s.name, sizeof s.name, "%s", name);
    snprintf(s.pattern, sizeof s.pattern, "%s", pattern);
    if (emm_strategy_parse(strategy, &s.strategy, &err) != EMM_OK)
        return cli_usage_error(cmd, "%s", err.message);

    emm_trace_reader *r;
    if (emm_trace_reader_open(trace, &r, &err) != EMM_OK)
        return cli_fail(&err);
    double *xy = NULL, *D = NULL;
    size_t n = 0;
    int rc = EMM_EXIT_FAIL;
    if (emm_profile_trace_positions(r, window, trace, &xy, &n, &err) != EMM_OK) {
        rc = cli_fail(&err);
        goto done;
    }
    if (n < EMM_PROFILE_MIN) {
        cli_error("%s: only %zu element accesses; a profile needs at least %u", trace, n,
                  EMM_PROFILE_MIN);
        goto done;
    }
    D = malloc(n * sizeof *D);
    if (!D) {
        cli_error("%s: out of memory", trace);
        goto done;
    }
    if (emm_profile_compute(xy, n, D, NULL, &err) != EMM_OK ||
        emm_profile_features(D, n, trace, s.f, &err) != EMM_OK ||
        emm_table_append(table, &s, &err) != EMM_OK) {
        rc = cli_fail(&err);
        goto done;
    }
    printf("added %s (%s, %s) to %s\n", s.name, s.pattern, strategy, table);
    rc = EMM_EXIT_OK;
done:
    free(xy);
    free(D);
    emm_trace_reader_close(r);
    return rc;
}

int emm_cmd_table(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return EMM_EXIT_USAGE;
    }
    if (cli_is_help(argv[1])) {
        usage(stdout);
        return EMM_EXIT_OK;
    }
    if (strcmp(argv[1], "list") == 0)
        return table_list(argc - 1, argv + 1);
    if (strcmp(argv[1], "add") == 0)
        return table_add(argc - 1, argv + 1);
    if (strcmp(argv[1], "build") == 0) {
        cli_error("'table build' needs the strategy simulation, which is not built yet");
        return EMM_EXIT_FAIL;
    }
    return cli_usage_error("table", "unknown subcommand '%s' (list, add)", argv[1]);
}
