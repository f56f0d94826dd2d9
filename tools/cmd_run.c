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
#include "emm/config.h"
#include "emm/session.h"

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
            "Options (each sets its EMM_* variable; %%p in a FILE becomes the process id):\n");
    emm_config_help(out, 1);
    fprintf(out,
            "\n"
            "EMM_* variables already in the environment apply unless an option sets them.\n"
            "A bad option or variable is refused (exit status 2) before PROGRAM starts.\n"
            "The shim is looked for beside this executable: <bindir>/../lib/" SHIM_NAME
            " (build\n"
            "tree and install), and <bindir>/../lib64 and <bindir>/../lib/<multiarch>/.\n");
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

static const char *get_env(const char *name)
{
    return getenv(name);
}

int emm_cmd_run(int argc, char **argv)
{
    emm_config cfg;
    const char *values[EMM_CONFIG_COUNT] = {0};
    unsigned given = 0;
    emm_error err;
    int i;

    /* The options, each parsed by its row of the configuration table: a bad
     * one stops here, naming the option, before the program starts. */
    emm_config_init(&cfg);
    for (i = 1; i < argc; i++) {
        const char *a = argv[i], *fixed;
        if (strcmp(a, "--") == 0) {
            i++;
            break;
        }
        if (cli_is_help(a)) {
            usage(stdout);
            return EMM_EXIT_OK;
        }
        if (a[0] != '-')
            break; /* the program, without "--" */
        emm_config_key k = emm_config_find_option(a, &fixed);
        if (k == EMM_CONFIG_COUNT)
            return cli_usage_error("run", "unknown option '%s'", a);
        const char *v = fixed ? fixed : cli_value("run", argc, argv, &i);
        if (!v)
            return EMM_EXIT_USAGE;
        if (emm_config_set(&cfg, k, v, a, (long)getpid(), &err) != EMM_OK)
            return cli_bad_value("run", &err);
        values[k] = v;
        given |= 1u << k;
    }
    if (i >= argc)
        return cli_usage_error("run", "missing PROGRAM (emm run [OPTIONS] -- PROGRAM [ARGS...])");
    /* The variables the options leave alone, as the shim will read them;
     * then what only a session can check (a machine file's keys, a table's
     * samples), as the shim will start it. */
    if (emm_config_from_env(&cfg, get_env, (long)getpid(), given, &err) != EMM_OK)
        return cli_bad_value("run", &err);
    emm_session_config sc = {&cfg, cfg.capture, argv[i], 0, {1, NULL, NULL}};
    emm_session *probe;
    if (emm_session_new(&sc, &probe, &err) != EMM_OK)
        return cli_bad_value("run", &err);
    emm_session_free(probe);
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
    for (int k = 0; k < EMM_CONFIG_COUNT; k++)
        if (values[k])
            bad |= setenv(emm_config_row_get((emm_config_key)k)->var, values[k], 1);
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
