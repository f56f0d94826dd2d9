/* emm run: runs a program under libemmshim.so (DESIGN.md "The shim").
 *
 * It only prepares the environment: the shim found beside this executable
 * goes first in LD_PRELOAD, each option becomes its EMM_* variable, and the
 * program replaces this process (exec), so its exit status — or the signal
 * that ended it — is the status the caller sees, unchanged. */
#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "env.h"
#include "emm/strategy.h"
#include "parse.h"

#define SHIM_NAME "libemmshim.so"

static void usage(FILE *out)
{
    fprintf(out,
            "usage: emm run [OPTIONS] -- PROGRAM [ARGS...]\n"
            "\n"
            "Runs PROGRAM with libemmshim.so preloaded: its mesh arrays are tagged as they\n"
            "are allocated (emm_tag_* calls or EMM_TAG rules), the first accesses are\n"
            "profiled, a strategy is chosen from the strategy table, and the whole run is\n"
            "simulated under that strategy and the baselines (direct reads, the cache).\n"
            "A summary goes to stderr at exit; PROGRAM's output and exit status are its own.\n"
            "\n"
            "  --strategy S     use strategy S instead of deciding (EMM_STRATEGY)\n"
            "  --profile N      profiling window: N element accesses (16384, 16K) or\n"
            "                   Nit iterations marked by emm_iteration() (EMM_PROFILE)\n"
            "  --compare C      baselines (default), all (the whole sweep) or none (EMM_COMPARE)\n"
            "  --capture C      auto (default), sancov, fault or api (EMM_CAPTURE)\n"
            "  --tag RULES      tag rules, e.g. 'vertices:site=read_mesh,stride=80,xyz=8:f64'\n"
            "                   (EMM_TAG)\n"
            "  --report FILE    JSON report, docs/report.md (EMM_REPORT)\n"
            "  --dump FILE      the window's distance profile as CSV i,D (EMM_PROFILE_DUMP)\n"
            "  --trace FILE     the access trace, for emm replay (EMM_TRACE)\n"
            "  --machine FILE   machine file (EMM_MACHINE)\n"
            "  --table FILE     a strategy table added to the shipped one (EMM_TABLE)\n"
            "  --quiet          no summary (EMM_LOG=0)\n"
            "  --verbose        more detail (EMM_LOG=2)\n"
            "  --strict         a bad EMM_* value stops the program instead of the shim\n"
            "                   stepping aside (EMM_STRICT=1)\n"
            "\n"
            "%%p in a FILE becomes the process id. EMM_* variables already in the\n"
            "environment apply unless an option sets them. The shim is looked for beside\n"
            "this executable: <bindir>/../lib/" SHIM_NAME " (build tree and install), and\n"
            "<bindir>/../lib64 and <bindir>/../lib/<multiarch>/ when installed there.\n"
            "\n");
    shim_env_help(out);
}

/* out = a + b + c; false when it does not fit. */
static bool join(char *out, size_t cap, const char *a, const char *b, const char *c)
{
    int n = snprintf(out, cap, "%s%s%s", a, b, c);
    return n >= 0 && (size_t)n < cap;
}

/* Where the shim may be, in order, relative to this executable. Returns
 * the first that exists, or NULL with the paths tried in `tried`. */
static char *find_shim(char *tried, size_t cap)
{
    char exe[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    size_t used = 0;
    tried[0] = '\0';
    if (n <= 0) {
        snprintf(tried, cap, "(cannot read /proc/self/exe: %s)", strerror(errno));
        return NULL;
    }
    exe[n] = '\0';
    char *slash = strrchr(exe, '/');
    if (!slash)
        return NULL;
    *slash = '\0'; /* exe is now the bin directory */

    enum { MAX_CAND = 16 };
    char cand[MAX_CAND][PATH_MAX];
    size_t nc = 0;
    char libdir[PATH_MAX];
    if (join(cand[nc], PATH_MAX, exe, "/../lib/", SHIM_NAME))
        nc++;
    if (join(cand[nc], PATH_MAX, exe, "/../lib64/", SHIM_NAME))
        nc++;
    DIR *d = join(libdir, sizeof libdir, exe, "/../lib", "") ? opendir(libdir) : NULL;
    if (d) {
        /* A multiarch install: lib/x86_64-linux-gnu/ and the like. */
        struct dirent *e;
        char sub[PATH_MAX];
        while ((e = readdir(d)) && nc < MAX_CAND)
            if (e->d_name[0] != '.' && strchr(e->d_name, '-') &&
                join(sub, sizeof sub, libdir, "/", e->d_name) &&
                join(cand[nc], PATH_MAX, sub, "/", SHIM_NAME))
                nc++;
        closedir(d);
    }
    for (size_t i = 0; i < nc; i++) {
        char real[PATH_MAX];
        if (access(cand[i], R_OK) == 0 && realpath(cand[i], real))
            return strdup(real);
        int w = snprintf(tried + used, cap - used, "%s%s", used ? ", " : "", cand[i]);
        if (w > 0 && (size_t)w < cap - used)
            used += (size_t)w;
    }
    return NULL;
}

static bool valid_window(const char *v)
{
    uint64_t x;
    size_t n = strlen(v);
    if (n > 2 && strcmp(v + n - 2, "it") == 0) {
        char buf[64];
        if (n - 2 >= sizeof buf)
            return false;
        memcpy(buf, v, n - 2);
        buf[n - 2] = '\0';
        return emm_parse_u64(buf, &x) && x > 0;
    }
    return emm_parse_size(v, &x) && x > 0;
}

static bool one_of(const char *v, const char *const *words)
{
    for (; *words; words++)
        if (strcmp(v, *words) == 0)
            return true;
    return false;
}

struct setting {
    const char *opt;
    const char *var;
};

static const struct setting settings[] = {
    {"--strategy", "EMM_STRATEGY"}, {"--profile", "EMM_PROFILE"},
    {"--compare", "EMM_COMPARE"},   {"--capture", "EMM_CAPTURE"},
    {"--tag", "EMM_TAG"},           {"--report", "EMM_REPORT"},
    {"--dump", "EMM_PROFILE_DUMP"}, {"--trace", "EMM_TRACE"},
    {"--machine", "EMM_MACHINE"},   {"--table", "EMM_TABLE"},
};

int emm_cmd_run(int argc, char **argv)
{
    static const char *const compares[] = {"baselines", "all", "none", NULL};
    static const char *const captures[] = {"auto", "sancov", "fault", "api", NULL};
    const char *values[sizeof settings / sizeof settings[0]] = {0};
    const char *log = NULL, *strict = NULL;
    int i;

    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "--") == 0) {
            i++;
            break;
        }
        if (cli_is_help(a)) {
            usage(stdout);
            return EMM_EXIT_OK;
        }
        if (strcmp(a, "--quiet") == 0 || strcmp(a, "-q") == 0) {
            log = "0";
            continue;
        }
        if (strcmp(a, "--verbose") == 0 || strcmp(a, "-v") == 0) {
            log = "2";
            continue;
        }
        if (strcmp(a, "--strict") == 0) {
            strict = "1";
            continue;
        }
        if (a[0] != '-')
            break; /* the program, without "--" */
        size_t k = 0;
        while (k < sizeof settings / sizeof settings[0] && strcmp(a, settings[k].opt) != 0)
            k++;
        if (k == sizeof settings / sizeof settings[0])
            return cli_usage_error("run", "unknown option '%s'", a);
        const char *v = cli_value("run", argc, argv, &i);
        if (!v)
            return EMM_EXIT_USAGE;
        if (!*v)
            return cli_usage_error("run", "%s: empty value", a);
        values[k] = v;
    }
    if (i >= argc)
        return cli_usage_error("run", "missing PROGRAM (emm run [OPTIONS] -- PROGRAM [ARGS...])");

    /* Mistakes the shim would only report from inside the program are
     * usage errors here. */
    for (size_t k = 0; k < sizeof settings / sizeof settings[0]; k++) {
        const char *v = values[k];
        emm_strategy s;
        emm_error err;
        if (!v)
            continue;
        if (strcmp(settings[k].opt, "--strategy") == 0 && emm_strategy_parse(v, &s, &err) != EMM_OK)
            return cli_usage_error("run", "--strategy: %s", err.message);
        if (strcmp(settings[k].opt, "--profile") == 0 && !valid_window(v))
            return cli_usage_error("run",
                                   "--profile '%s': expected a count of accesses (16384, 16K) or "
                                   "of iterations (5it), at least 1",
                                   v);
        if (strcmp(settings[k].opt, "--compare") == 0 && !one_of(v, compares))
            return cli_usage_error("run", "--compare '%s': expected baselines, all or none", v);
        if (strcmp(settings[k].opt, "--capture") == 0 && !one_of(v, captures))
            return cli_usage_error("run", "--capture '%s': expected auto, sancov, fault or api",
                                   v);
    }

    char tried[4096];
    char *shim = find_shim(tried, sizeof tried);
    if (!shim) {
        cli_error("run: cannot find %s; tried %s", SHIM_NAME, tried);
        return EMM_EXIT_FAIL;
    }
    const char *old = getenv("LD_PRELOAD");
    size_t len = strlen(shim) + (old ? strlen(old) + 1 : 0) + 1;
    char *preload = malloc(len);
    if (!preload) {
        cli_error("run: out of memory");
        free(shim);
        return EMM_EXIT_FAIL;
    }
    if (old && *old)
        snprintf(preload, len, "%s:%s", shim, old);
    else
        snprintf(preload, len, "%s", shim);
    free(shim);
    int bad = setenv("LD_PRELOAD", preload, 1);
    free(preload);
    for (size_t k = 0; k < sizeof settings / sizeof settings[0]; k++)
        if (values[k])
            bad |= setenv(settings[k].var, values[k], 1);
    if (log)
        bad |= setenv("EMM_LOG", log, 1);
    if (strict)
        bad |= setenv("EMM_STRICT", strict, 1);
    if (bad) {
        cli_error("run: cannot set the environment: %s", strerror(errno));
        return EMM_EXIT_FAIL;
    }
    fflush(NULL);
    execvp(argv[i], argv + i);
    /* As a shell does: 127 when the program is not found, 126 when it
     * cannot run. */
    int e = errno;
    cli_error("run: cannot run '%s': %s", argv[i], strerror(e));
    return e == ENOENT ? 127 : 126;
}
