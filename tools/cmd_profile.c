/* emm profile TRACE: the distance profile of a trace's first accesses
 * (thesis §5, Eq. 5.1), its pattern class and the strategy the table picks. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "emm/profile.h"
#include "emm/table.h"
#include "emm/trace.h"
#include "json.h"

static const char *const CMD = "profile";

static void usage(FILE *out)
{
    fprintf(out,
            "usage: emm profile TRACE [--window N] [--table FILE] [--threshold X]\n"
            "                         [--dump FILE.csv] [--json FILE]\n"
            "\n"
            "Computes the distance profile D_i = sum over k<i of |p_i - p_k| (thesis Eq. 5.1)\n"
            "of the trace's first N element accesses (vertex or triangle accesses; consecutive\n"
            "accesses to one element count once; positions scaled by the mesh's bounding-box\n"
            "diagonal), reduces it to features, and prints the pattern class, the nearest\n"
            "sample of the strategy table with its distance, and the strategy chosen.\n"
            "\n"
            "  --window N      element accesses to profile (default %u); up to %u use\n"
            "                  the exact method, longer windows the fast one\n"
            "  --table FILE    a user table added to the default one (default: $EMM_TABLE)\n"
            "  --threshold X   novelty threshold on the nearest distance (default %g)\n"
            "  --dump FILE     write the profile as CSV with the columns i,D\n"
            "  --json FILE     write pattern, strategy, nearest, distance, novel as JSON\n"
            "\n"
            "The default table is %s.\n",
            EMM_PROFILE_DEFAULT_WINDOW, EMM_PROFILE_EXACT_MAX, EMM_NOVELTY_THRESHOLD,
            emm_table_default_path());
}

/* Opens a temporary file beside path; *tmp receives its name (malloc'd). */
static FILE *open_temp(const char *path, char **tmp)
{
    size_t len = strlen(path) + 32;
    *tmp = malloc(len);
    if (!*tmp)
        return NULL;
    snprintf(*tmp, len, "%s.tmp.%ld", path, (long)getpid());
    FILE *fp = fopen(*tmp, "w");
    if (!fp) {
        free(*tmp);
        *tmp = NULL;
    }
    return fp;
}

static int finish_temp(FILE *fp, char *tmp, const char *path)
{
    int bad = ferror(fp) != 0;
    bad |= fclose(fp) != 0;
    if (bad || rename(tmp, path) != 0) {
        cli_error("%s: cannot write: %s", path, strerror(errno));
        remove(tmp);
        free(tmp);
        return EMM_EXIT_FAIL;
    }
    free(tmp);
    return EMM_EXIT_OK;
}

static int write_dump(const char *path, const double *D, size_t n)
{
    char *tmp;
    FILE *fp = open_temp(path, &tmp);
    if (!fp) {
        cli_error("%s: cannot write: %s", path, strerror(errno));
        return EMM_EXIT_FAIL;
    }
    fprintf(fp, "i,D\n");
    for (size_t i = 0; i < n; i++)
        fprintf(fp, "%zu,%.17g\n", i, D[i]);
    return finish_temp(fp, tmp, path);
}

static int write_json(const char *path, const char *trace, size_t n, int exact,
                      const emm_decision *d, const double *f)
{
    char *tmp;
    FILE *fp = open_temp(path, &tmp);
    if (!fp) {
        cli_error("%s: cannot write: %s", path, strerror(errno));
        return EMM_EXIT_FAIL;
    }
    char strat[96];
    emm_strategy_format(&d->strategy, strat, sizeof strat);
    json_writer w;
    json_init(&w, fp, true);
    json_begin_object(&w);
    json_key(&w, "trace");
    json_string(&w, trace);
    json_key(&w, "accesses");
    json_u64(&w, n);
    json_key(&w, "method");
    json_string(&w, exact ? "exact" : "fast");
    json_key(&w, "pattern");
    json_string(&w, d->pattern);
    json_key(&w, "strategy");
    json_string(&w, strat);
    json_key(&w, "nearest");
    json_string(&w, d->nearest);
    json_key(&w, "distance");
    json_double(&w, d->distance);
    json_key(&w, "novel");
    json_bool(&w, d->novel);
    json_key(&w, "features");
    json_begin_array(&w);
    for (int k = 0; k < EMM_FEATURES; k++)
        json_double(&w, f[k]);
    json_end_array(&w);
    json_end_object(&w);
    json_finish(&w);
    return finish_temp(fp, tmp, path);
}

int emm_cmd_profile(int argc, char **argv)
{
    const char *trace = NULL, *table = NULL, *dump = NULL, *json = NULL;
    uint64_t window = EMM_PROFILE_DEFAULT_WINDOW;
    double threshold = EMM_NOVELTY_THRESHOLD;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (cli_is_help(a)) {
            usage(stdout);
            return EMM_EXIT_OK;
        } else if (strcmp(a, "--window") == 0) {
            const char *v = cli_value(CMD, argc, argv, &i);
            if (!v || !cli_u64(CMD, a, v, &window))
                return EMM_EXIT_USAGE;
            if (window < EMM_PROFILE_MIN)
                return cli_usage_error(CMD, "--window must be at least %u", EMM_PROFILE_MIN);
        } else if (strcmp(a, "--table") == 0) {
            if (!(table = cli_value(CMD, argc, argv, &i)))
                return EMM_EXIT_USAGE;
        } else if (strcmp(a, "--threshold") == 0) {
            const char *v = cli_value(CMD, argc, argv, &i);
            char *end;
            if (!v)
                return EMM_EXIT_USAGE;
            threshold = strtod(v, &end);
            if (*v == '\0' || *end != '\0' || !(threshold > 0))
                return cli_usage_error(CMD, "--threshold expects a positive number, not '%s'", v);
        } else if (strcmp(a, "--dump") == 0) {
            if (!(dump = cli_value(CMD, argc, argv, &i)))
                return EMM_EXIT_USAGE;
        } else if (strcmp(a, "--json") == 0) {
            if (!(json = cli_value(CMD, argc, argv, &i)))
                return EMM_EXIT_USAGE;
        } else if (a[0] == '-' && a[1] != '\0') {
            return cli_usage_error(CMD, "unknown option '%s'", a);
        } else if (!trace) {
            trace = a;
        } else {
            return cli_usage_error(CMD, "one trace only ('%s' is extra)", a);
        }
    }
    if (!trace)
        return cli_usage_error(CMD, "a TRACE file is required");

    emm_error err;
    emm_trace_reader *r;
    if (emm_trace_reader_open(trace, &r, &err) != EMM_OK)
        return cli_fail(&err);
    double *xy = NULL, *D = NULL;
    size_t n = 0;
    int rc = EMM_EXIT_FAIL, exact = 1;
    emm_table *t = NULL;
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
    if (emm_profile_compute(xy, n, D, &exact, &err) != EMM_OK) {
        rc = cli_fail(&err);
        goto done;
    }
    if (dump && write_dump(dump, D, n) != EMM_EXIT_OK)
        goto done;
    double f[EMM_FEATURES];
    if (emm_profile_features(D, n, trace, f, &err) != EMM_OK) {
        rc = cli_fail(&err);
        goto done;
    }
    t = emm_table_new();
    if (!t) {
        cli_error("out of memory");
        goto done;
    }
    if (emm_table_load_standard(t, table, &err) != EMM_OK) {
        rc = cli_fail(&err);
        goto done;
    }
    emm_decision d;
    if (emm_table_decide(t, f, threshold, &d, &err) != EMM_OK) {
        rc = cli_fail(&err);
        goto done;
    }
    char strat[96];
    emm_strategy_format(&d.strategy, strat, sizeof strat);
    printf("trace:     %s\n", trace);
    printf("window:    %zu element accesses (%s method)\n", n, exact ? "exact" : "fast");
    printf("pattern:   %s\n", d.pattern);
    printf("nearest:   %s (distance %.4f)\n", d.nearest, d.distance);
    printf("novel:     %s (threshold %g)\n", d.novel ? "yes" : "no", threshold);
    printf("strategy:  %s\n", strat);
    rc = EMM_EXIT_OK;
    if (json)
        rc = write_json(json, trace, n, exact, &d, f);
done:
    emm_table_free(t);
    free(xy);
    free(D);
    emm_trace_reader_close(r);
    return rc;
}
