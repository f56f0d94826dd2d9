/* The EMM_* descriptor table (shim/env.c): defaults, accepted syntaxes, %p,
 * and the one-line message for each bad value. */
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "env.h"

static const char *vars[16][2];
static size_t nvars;

static const char *fake_get(const char *name)
{
    for (size_t i = 0; i < nvars; i++)
        if (strcmp(vars[i][0], name) == 0)
            return vars[i][1];
    return NULL;
}

static void set(const char *name, const char *value)
{
    vars[nvars][0] = name;
    vars[nvars][1] = value;
    nvars++;
}

static bool parse(struct shim_env *e, char *msg)
{
    msg[0] = '\0';
    return shim_env_parse(e, fake_get, 4242, NULL, msg, 600);
}

int main(void)
{
    struct shim_env e;
    char msg[600];

    nvars = 0;
    CHECK(parse(&e, msg));
    CHECK(e.capture == SHIM_CAPTURE_AUTO && e.window_accesses == 16384 && e.window_iterations == 0);
    CHECK(e.compare == EMM_COMPARE_BASELINES && e.log == 1 && !e.strict && !e.strategy);
    CHECK(e.report[0] == '\0' && !e.tag);

    nvars = 0;
    set("EMM_PROFILE", "20K");
    set("EMM_CAPTURE", "fault");
    set("EMM_COMPARE", "all");
    set("EMM_LOG", "verbose");
    set("EMM_STRATEGY", "tiles+convolution@64");
    set("EMM_REPORT", "/tmp/r-%p-%%.json");
    set("EMM_STRICT", "1");
    CHECK(parse(&e, msg));
    CHECK(e.window_accesses == 20480 && e.capture == SHIM_CAPTURE_FAULT);
    CHECK(e.compare == EMM_COMPARE_ALL && e.log == 2 && e.strict);
    CHECK(strcmp(e.report, "/tmp/r-4242-%.json") == 0);
    CHECK(e.strategy && strcmp(e.strategy, "tiles+convolution@64") == 0);

    nvars = 0;
    set("EMM_PROFILE", "5it");
    CHECK(parse(&e, msg));
    CHECK(e.window_accesses == 0 && e.window_iterations == 5);

    static const char *bad[][2] = {
        {"EMM_PROFILE", "abc"}, {"EMM_PROFILE", ""}, {"EMM_PROFILE", "-3"},
        {"EMM_PROFILE", "99999999999999999999999"}, {"EMM_PROFILE", "0it"},
        {"EMM_CAPTURE", "magic"}, {"EMM_COMPARE", "best"}, {"EMM_LOG", "4"},
        {"EMM_STRICT", "yes"}, {"EMM_STRATEGY", "fastest"}, {"EMM_MACHINE", "/nonexistent/m"},
        {"EMM_REPORT", "/nonexistent/d/r.json"}, {"EMM_TRACE", "/tmp"}, {"EMM_TAG", ""},
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        nvars = 0;
        set(bad[i][0], bad[i][1]);
        bool ok = parse(&e, msg);
        CHECKF(!ok, "%s='%s' accepted", bad[i][0], bad[i][1]);
        char head[128];
        snprintf(head, sizeof head, "%s='%s': ", bad[i][0], bad[i][1]);
        CHECKF(strncmp(msg, head, strlen(head)) == 0, "message '%s'", msg);
        CHECKF(strchr(msg, '\n') == NULL, "message '%s' has a newline", msg);
    }
    nvars = 0;
    set("EMM_PROFILE", "abc");
    CHECK(!parse(&e, msg));
    CHECK(strstr(msg, "expected a count of accesses") != NULL);

    /* A bad value still lets a valid EMM_STRICT through, so the shim knows
     * whether to stop. */
    nvars = 0;
    set("EMM_STRICT", "1");
    set("EMM_LOG", "x");
    CHECK(!parse(&e, msg) && e.strict);

    FILE *devnull = fopen("/dev/null", "w");
    if (devnull) {
        shim_env_help(devnull);
        fclose(devnull);
    }
    return check_done();
}
