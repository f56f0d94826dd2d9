/* The configuration table (core/config.c): defaults, accepted syntaxes, %p,
 * the one-line message for each bad value naming where it came from, long
 * values cut before the explanation, and the options of `emm run`. */
#include <stdbool.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "emm/config.h"

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

static bool parse(emm_config *e, char *msg)
{
    emm_error err;
    emm_config_free(e); /* the rules of the previous parse, if any */
    msg[0] = '\0';
    if (emm_config_from_env(e, fake_get, 4242, 0, &err) == EMM_OK)
        return true;
    strcpy(msg, err.message);
    return false;
}

/* EMM_TAG takes as many rules as it is given, and a copy of a config owns
 * rules of its own. */
static void many_rules(void)
{
    char text[40 * 48] = "";
    for (int i = 0; i < 40; i++)
        snprintf(text + strlen(text), sizeof text - strlen(text),
                 "%svertices:nth=%d,stride=24,xyz=0:f64", i ? ";" : "", i + 1);
    emm_config c, d;
    emm_error err;
    emm_config_init(&c);
    CHECKF(emm_config_set(&c, EMM_CONFIG_TAG, text, NULL, 1, &err) == EMM_OK, "%s", err.message);
    CHECK(c.tags.n == 40 && c.tags.rule[39].nth == 40);
    REQUIRE(emm_config_copy(&d, &c) == EMM_OK);
    CHECK(d.tags.n == 40 && d.tags.rule != c.tags.rule && d.tags.rule[39].nth == 40);
    /* A second value replaces the rules; a bad one leaves them. */
    CHECK(emm_config_set(&c, EMM_CONFIG_TAG, "triangles:stride=12,vidx=0:i32", NULL, 1, &err) ==
          EMM_OK);
    CHECK(c.tags.n == 1 && c.tags.rule[0].kind == EMM_ARRAY_TRIANGLES);
    CHECK(emm_config_set(&c, EMM_CONFIG_TAG, "garbage", NULL, 1, &err) != EMM_OK);
    CHECK(c.tags.n == 1 && c.tags.rule[0].kind == EMM_ARRAY_TRIANGLES);
    emm_config_free(&c);
    CHECK(c.tags.n == 0 && c.tags.rule == NULL);
    CHECK(d.tags.rule[0].nth == 1);
    emm_config_free(&d);
}

/* Each backend that counts work between accesses names its unit, which the
 * report's compute says (docs/machine.md "Compute"); one that counts none
 * names none. */
static void work_units(void)
{
    CHECK(emm_capture_work_unit(EMM_CAPTURE_AUTO) == NULL);
    CHECK(emm_capture_work_unit(EMM_CAPTURE_COUNT) == NULL);
    for (int c = EMM_CAPTURE_AUTO + 1; c < EMM_CAPTURE_COUNT; c++) {
        const char *unit = emm_capture_work_unit((emm_capture)c);
        bool counts = (emm_capture_caps((emm_capture)c) & EMM_CAP_WORK) != 0;
        CHECKF(counts == (unit != NULL && unit[0] != '\0'), "%s: work %s, unit %s",
               emm_capture_name((emm_capture)c), counts ? "counted" : "not counted",
               unit ? unit : "(none)");
    }
    CHECK(strcmp(emm_capture_work_unit(EMM_CAPTURE_SANCOV), "edges") == 0);
    CHECK(strcmp(emm_capture_work_unit(EMM_CAPTURE_VALGRIND), "superblocks") == 0);
    CHECK(emm_capture_work_unit(EMM_CAPTURE_FAULT) == NULL);
}

int main(void)
{
    emm_config e;
    char msg[600];
    emm_config_init(&e);
    many_rules();
    work_units();

    nvars = 0;
    CHECK(parse(&e, msg));
    CHECK(e.capture == EMM_CAPTURE_AUTO && e.window_accesses == 16384 && e.window_iterations == 0);
    CHECK(e.compare == EMM_COMPARE_BASELINES && e.log == 1 && !e.strict && !e.has_strategy);
    CHECK(e.report[0] == '\0' && e.tags.n == 0);
    for (int k = 0; k < EMM_CONFIG_COUNT; k++)
        CHECK(e.source[k] == NULL);

    nvars = 0;
    set("EMM_PROFILE", "20K");
    set("EMM_CAPTURE", "fault");
    set("EMM_COMPARE", "all");
    set("EMM_LOG", "verbose");
    set("EMM_STRATEGY", "tiles+convolution@64");
    set("EMM_REPORT", "/tmp/r-%p-%%.json");
    set("EMM_STRICT", "1");
    CHECK(parse(&e, msg));
    CHECK(e.window_accesses == 20480 && e.capture == EMM_CAPTURE_FAULT);
    CHECK(e.compare == EMM_COMPARE_ALL && e.log == 2 && e.strict);
    CHECK(strcmp(e.report, "/tmp/r-4242-%.json") == 0);
    CHECK(e.has_strategy && e.strategy.kind == EMM_STRATEGY_EMM &&
          e.strategy.layout == EMM_LAYOUT_TILES && e.strategy.fetch == EMM_FETCH_CONVOLUTION &&
          e.strategy.cell == 64);
    CHECK(e.source[EMM_CONFIG_PROFILE] && strcmp(e.source[EMM_CONFIG_PROFILE], "EMM_PROFILE") == 0);

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

    /* Long values are cut before the explanation, which always fits. */
    char longrule[1200];
    memset(longrule, 'x', sizeof longrule - 1);
    longrule[sizeof longrule - 1] = '\0';
    memcpy(longrule, "vertices:stride=80,xyz=8:f64,", 29);
    nvars = 0;
    set("EMM_TAG", longrule);
    CHECK(!parse(&e, msg));
    CHECKF(strstr(msg, "EMM_TAG='vertices:stride=80,xyz=8:f64,") == msg && strstr(msg, "...'"),
           "%s", msg);
    CHECKF(strstr(msg, "is not key=value") != NULL, "the explanation is lost: %s", msg);
    CHECKF(strlen(msg) < 300, "%zu characters: %s", strlen(msg), msg);
    char longstrat[1200];
    memset(longstrat, 'g', sizeof longstrat - 1);
    longstrat[sizeof longstrat - 1] = '\0';
    nvars = 0;
    set("EMM_STRATEGY", longstrat);
    CHECK(!parse(&e, msg));
    CHECKF(strstr(msg, "accepted: direct, cache") != NULL, "the explanation is lost: %s", msg);

    /* emm run's options: the same rows, named as typed. */
    const char *fixed;
    CHECK(emm_config_find_option("--tag", &fixed) == EMM_CONFIG_TAG && fixed == NULL);
    CHECK(emm_config_find_option("--quiet", &fixed) == EMM_CONFIG_LOG && strcmp(fixed, "0") == 0);
    CHECK(emm_config_find_option("--strict", &fixed) == EMM_CONFIG_STRICT &&
          strcmp(fixed, "1") == 0);
    CHECK(emm_config_find_option("--nonsense", &fixed) == EMM_CONFIG_COUNT);
    emm_error err;
    emm_config_free(&e);
    CHECK(emm_config_set(&e, EMM_CONFIG_REPORT, "nodir/x.json", "--report", 1, &err) ==
          EMM_ERR_INVALID);
    CHECKF(strcmp(err.message, "--report='nodir/x.json': directory nodir does not exist") == 0,
           "%s", err.message);
    CHECK(e.report[0] == '\0' && e.source[EMM_CONFIG_REPORT] == NULL);
    CHECK(emm_config_set(&e, EMM_CONFIG_TAG, "garbage", "--tag", 1, &err) == EMM_ERR_INVALID);
    CHECKF(strncmp(err.message, "--tag='garbage': ", 17) == 0, "%s", err.message);
    CHECK(emm_config_set(&e, EMM_CONFIG_COMPARE, "all", "--compare", 1, &err) == EMM_OK);
    CHECK(e.compare == EMM_COMPARE_ALL && strcmp(e.source[EMM_CONFIG_COMPARE], "--compare") == 0);
    /* --finalists all: none dropped; written back as typed (the server's
     * start frame carries it so). */
    char text[16];
    CHECK(emm_config_set(&e, EMM_CONFIG_FINALISTS, "all", "--finalists", 1, &err) == EMM_OK);
    CHECK(e.finalists == EMM_CONFIG_FINALISTS_ALL);
    CHECK(emm_config_format(&e, EMM_CONFIG_FINALISTS, text, sizeof text) &&
          strcmp(text, "all") == 0);
    CHECK(emm_config_set(&e, EMM_CONFIG_FINALISTS, "65", "--finalists", 1, &err) ==
          EMM_ERR_INVALID);
    CHECKF(strcmp(err.message, "--finalists='65': expected a count from 0 to 64, or all") == 0,
           "%s", err.message);
    CHECK(emm_config_set(&e, EMM_CONFIG_FINALISTS, "8", "--finalists", 1, &err) == EMM_OK);
    CHECK(e.finalists == 8);

    FILE *devnull = fopen("/dev/null", "w");
    if (devnull) {
        emm_config_help(devnull, 0);
        emm_config_help(devnull, 1);
        emm_config_dump(&e, devnull);
        fclose(devnull);
    }
    emm_config_free(&e);
    return check_done();
}
