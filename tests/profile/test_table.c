/* The strategy table: strict parsing with FILE:LINE errors, writing and
 * appending whole files, loading the default and the user's table, and the
 * nearest-neighbour decision with its novelty threshold. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "emm/table.h"

static void write_file(const char *path, const char *text)
{
    FILE *fp = fopen(path, "w");
    REQUIRE(fp);
    fputs(text, fp);
    fclose(fp);
}

/* A sample line with all features equal to v. */
static char *line(const char *name, const char *pattern, const char *strategy, const char *v,
                  int nfeat)
{
    static char buf[4096];
    int n = snprintf(buf, sizeof buf, "%s %s - - %s", name, pattern, strategy);
    for (int k = 0; k < nfeat; k++)
        n += snprintf(buf + n, sizeof buf - (size_t)n, " %s", v);
    snprintf(buf + n, sizeof buf - (size_t)n, "\n");
    return buf;
}

static char header[64];

/* Loads text as a table; returns the status, err filled. */
static emm_status load_text(const char *text, emm_error *err, size_t *count)
{
    write_file("table_test.txt", text);
    emm_table *t = emm_table_new();
    REQUIRE(t);
    emm_status st = emm_table_load(t, "table_test.txt", err);
    if (count)
        *count = emm_table_count(t);
    emm_table_free(t);
    return st;
}

static void expect_error(const char *text, const char *needle)
{
    emm_error err;
    size_t n;
    emm_status st = load_text(text, &err, &n);
    CHECKF(st != EMM_OK, "accepted a table that should fail with '%s'", needle);
    CHECKF(strstr(err.message, needle) != NULL, "message '%s' lacks '%s'", err.message, needle);
    CHECK(n == 0);
}

static void test_parse(void)
{
    char text[16384];
    emm_error err;
    size_t n;
    /* A good table: comments, blank lines, trailing comments. */
    snprintf(text, sizeof text, "# a comment\n\n%s# columns\n", header);
    strcat(text, line("a-1", "random", "cache", "0.5", EMM_FEATURES));
    strcat(text, "   \n");
    char *l = line("b_2", "region", "tiles+convolution@64", "-1e-3", EMM_FEATURES);
    l[strlen(l) - 1] = '\0';
    strcat(text, l);
    strcat(text, "  # trailing comment\n");
    CHECK(load_text(text, &err, &n) == EMM_OK);
    CHECK(n == 2);

    /* Errors name the file and the line. */
    /* Version 1 had 16 features; its tables are refused, not misread. */
    expect_error("emm-table 1 features=16\n", "table_test.txt:1: table version '1'");
    expect_error("emm-table 5 features=19\n", "table_test.txt:1: table version '5'");
    snprintf(text, sizeof text, "emm-table %d features=%d\n", EMM_TABLE_VERSION, EMM_FEATURES + 1);
    expect_error(text, "table_test.txt:1: the table has");
    expect_error("emm-tables 1\n", "table_test.txt:1: expected the header");
    expect_error("# only comments\n", "table_test.txt: empty file");
    snprintf(text, sizeof text, "%s%s", header, line("x", "random", "cache", "1", EMM_FEATURES - 1));
    expect_error(text, "table_test.txt:2: expected name, pattern, synth, machine, strategy");
    /* One field more than the features is a cost, and it is no STRATEGY=RATIO. */
    snprintf(text, sizeof text, "%s%s", header, line("x", "random", "cache", "1", EMM_FEATURES + 1));
    expect_error(text, "table_test.txt:2: cost 1: '1' is not STRATEGY=RATIO");
    snprintf(text, sizeof text, "%s\n%s", header, line("x", "random", "tiles+warp", "1", EMM_FEATURES));
    expect_error(text, "table_test.txt:3: ");
    snprintf(text, sizeof text, "%s%s", header, line("x", "random", "cache", "1.5x", EMM_FEATURES));
    expect_error(text, "table_test.txt:2: feature 1: '1.5x' is not a number");
    snprintf(text, sizeof text, "%s%s", header, line("x", "random", "cache", "nan", EMM_FEATURES));
    expect_error(text, "table_test.txt:2: feature 1: 'nan' is not a number");
    snprintf(text, sizeof text, "%s%s", header, line("x/y", "random", "cache", "1", EMM_FEATURES));
    expect_error(text, "table_test.txt:2: bad sample name 'x/y'");
    snprintf(text, sizeof text, "%s%s", header, line("dup", "random", "cache", "1", EMM_FEATURES));
    strcat(text, line("dup", "region", "cache", "2", EMM_FEATURES));
    expect_error(text, "table_test.txt:3: sample 'dup' is already defined in table_test.txt:2");

    /* The synth column: a recipe emm trace synth knows, or '-'. */
    snprintf(text, sizeof text, "%s%s", header, line("r", "region", "cache", "1", EMM_FEATURES));
    char *dash = strstr(text, " - ");
    REQUIRE(dash);
    char good[16384];
    snprintf(good, sizeof good, "%.*s region@corner %s", (int)(dash - text), text, dash + 3);
    CHECK(load_text(good, &err, &n) == EMM_OK && n == 1);
    snprintf(good, sizeof good, "%.*s curve@24 %s", (int)(dash - text), text, dash + 3);
    CHECK(load_text(good, &err, &n) == EMM_OK && n == 1);
    snprintf(good, sizeof good, "%.*s region@ring %s", (int)(dash - text), text, dash + 3);
    CHECK(load_text(good, &err, &n) == EMM_OK && n == 1);
    snprintf(good, sizeof good, "%.*s spiral@corner %s", (int)(dash - text), text, dash + 3);
    expect_error(good, "table_test.txt:2: synth 'spiral@corner'");
    snprintf(good, sizeof good, "%.*s curve@ring %s", (int)(dash - text), text, dash + 3);
    expect_error(good, "table_test.txt:2: synth 'curve@ring'");
    snprintf(good, sizeof good, "%.*s warp %s", (int)(dash - text), text, dash + 3);
    expect_error(good, "table_test.txt:2: synth 'warp': pattern 'warp' is unknown");
    /* The machine column: '-' or a fingerprint of 16 hex digits; then the
     * run's costs, STRATEGY=RATIO (at least 1), at most EMM_TABLE_COSTS. */
    snprintf(good, sizeof good, "%.*s - 0123456789abcdef %s", (int)(dash - text), text,
             dash + 5);
    good[strlen(good) - 1] = '\0';
    char costs[16384];
    snprintf(costs, sizeof costs, "%s tiles+naive@16=1 direct=2.5\n", good);
    emm_table *ct = emm_table_new();
    write_file("table_test.txt", costs);
    REQUIRE(emm_table_load(ct, "table_test.txt", &err) == EMM_OK);
    const emm_table_sample *cs = emm_table_at(ct, 0);
    CHECK(strcmp(cs->machine, "0123456789abcdef") == 0 && cs->ncosts == 2 &&
          cs->cost[1] == 2.5 && cs->cost_strategy[1].kind == EMM_STRATEGY_DIRECT);
    /* Written back and read again, the same. */
    remove("table_costs.txt");
    REQUIRE(emm_table_write(ct, "table_costs.txt", NULL, &err) == EMM_OK);
    emm_table *ct2 = emm_table_new();
    REQUIRE(emm_table_load(ct2, "table_costs.txt", &err) == EMM_OK);
    CHECK(emm_table_at(ct2, 0)->ncosts == 2 && emm_table_at(ct2, 0)->cost[1] == 2.5 &&
          strcmp(emm_table_at(ct2, 0)->machine, "0123456789abcdef") == 0);
    emm_table_free(ct2);
    emm_table_free(ct);
    snprintf(costs, sizeof costs, "%s direct=0.5\n", good);
    expect_error(costs, "table_test.txt:2: cost 1: 'direct=0.5' is not STRATEGY=RATIO");
    snprintf(costs, sizeof costs, "%s warp=1\n", good);
    expect_error(costs, "table_test.txt:2: cost 1: 'warp=1'");
    snprintf(costs, sizeof costs, "%s", good);
    for (int c = 0; c <= EMM_TABLE_COSTS; c++)
        strcat(costs, " direct=1");
    strcat(costs, "\n");
    expect_error(costs, "(then at most 24 costs), found more than");
    snprintf(good, sizeof good, "%.*s - 0123456789ABCDEF %s", (int)(dash - text), text, dash + 5);
    expect_error(good, "table_test.txt:2: machine '0123456789ABCDEF' is not '-' or 16 hex digits");
    /* Version 3 tables (no machine column) are still read. */
    snprintf(good, sizeof good, "emm-table 3 features=%d\nold3 random - cache", EMM_FEATURES);
    for (int k = 0; k < EMM_FEATURES; k++)
        strcat(good, " 0.5");
    strcat(good, "\n");
    CHECK(load_text(good, &err, &n) == EMM_OK && n == 1);
    /* Version 2 tables (no synth column) are still read. */
    snprintf(good, sizeof good, "emm-table 2 features=%d\nold random cache", EMM_FEATURES);
    for (int k = 0; k < EMM_FEATURES; k++)
        strcat(good, " 0.5");
    strcat(good, "\n");
    CHECK(load_text(good, &err, &n) == EMM_OK && n == 1);

    CHECK(load_text("", &err, &n) != EMM_OK);
    emm_table *t = emm_table_new();
    CHECK(emm_table_load(t, "no/such/table.txt", &err) == EMM_ERR_IO);
    CHECK(strstr(err.message, "no/such/table.txt: cannot open") != NULL);
    emm_table_free(t);
}

static emm_table_sample sample(const char *name, const char *pattern, const char *strategy,
                               double v)
{
    emm_table_sample s;
    emm_error err;
    memset(&s, 0, sizeof s);
    snprintf(s.name, sizeof s.name, "%s", name);
    snprintf(s.pattern, sizeof s.pattern, "%s", pattern);
    REQUIRE(emm_strategy_parse(strategy, &s.strategy, &err) == EMM_OK);
    for (int k = 0; k < EMM_FEATURES; k++)
        s.f[k] = v;
    return s;
}

static void test_write_append_decide(void)
{
    emm_error err;
    emm_table *t = emm_table_new();
    emm_table_sample a = sample("rand", "random", "cache", 0.0);
    emm_table_sample b = sample("grow", "region", "tiles+convolution@64", 1.0);
    REQUIRE(emm_table_add(t, &a, &err) == EMM_OK);
    REQUIRE(emm_table_add(t, &b, &err) == EMM_OK);
    CHECK(emm_table_add(t, &a, &err) == EMM_ERR_INVALID);
    emm_table_sample bad = sample("bad name", "random", "cache", 0.0);
    CHECK(emm_table_add(t, &bad, &err) == EMM_ERR_INVALID);
    emm_table_sample badsynth = sample("badsynth", "random", "cache", 0.0);
    snprintf(badsynth.synth, sizeof badsynth.synth, "curve@x");
    CHECK(emm_table_add(t, &badsynth, &err) == EMM_ERR_INVALID);

    /* Decide: nearest by Euclidean distance; novel beyond the threshold. */
    double f[EMM_FEATURES];
    for (int k = 0; k < EMM_FEATURES; k++)
        f[k] = 0.75;
    emm_decision d;
    REQUIRE(emm_table_decide(t, f, 0, &d, &err) == EMM_OK);
    CHECK(strcmp(d.nearest, "grow") == 0 && strcmp(d.pattern, "region") == 0);
    CHECK(d.strategy.layout == EMM_LAYOUT_TILES && d.strategy.fetch == EMM_FETCH_CONVOLUTION);
    CHECK(fabs(d.distance - 0.25 * sqrt(EMM_FEATURES)) < 1e-12);
    CHECK(fabs(emm_feature_distance(a.f, b.f) - sqrt(EMM_FEATURES)) < 1e-12);
    double g[EMM_FEATURES] = {0};
    g[0] = 0.1;
    CHECK(fabs(emm_feature_distance(a.f, g) - 0.1) < 1e-12);
    CHECK(d.novel == (d.distance > EMM_NOVELTY_THRESHOLD));
    REQUIRE(emm_table_decide(t, f, 0.1, &d, &err) == EMM_OK);
    CHECK(d.novel);
    REQUIRE(emm_table_decide(t, f, 10, &d, &err) == EMM_OK);
    CHECK(!d.novel);
    emm_table *empty = emm_table_new();
    CHECK(emm_table_decide(empty, f, 0, &d, &err) == EMM_ERR_INVALID);
    emm_table_free(empty);

    /* Write, read back, append. */
    remove("table_out.txt");
    REQUIRE(emm_table_write(t, "table_out.txt", "made by test_table\nsecond line", &err) == EMM_OK);
    emm_table *r = emm_table_new();
    REQUIRE(emm_table_load(r, "table_out.txt", &err) == EMM_OK);
    CHECK(emm_table_count(r) == 2);
    CHECK(strcmp(emm_table_at(r, 1)->name, "grow") == 0);
    CHECK(strcmp(emm_table_source(r, 1), "table_out.txt:8") == 0);
    emm_table_free(r);
    emm_table_sample c = sample("user-1", "curve", "grid+naive@16", 0.5);
    REQUIRE(emm_table_append("table_out.txt", &c, &err) == EMM_OK);
    CHECK(emm_table_append("table_out.txt", &c, &err) == EMM_ERR_INVALID);
    CHECK(strstr(err.message, "already in this table") != NULL);
    remove("table_new.txt");
    REQUIRE(emm_table_append("table_new.txt", &c, &err) == EMM_OK);
    r = emm_table_new();
    REQUIRE(emm_table_load(r, "table_out.txt", &err) == EMM_OK);
    CHECK(emm_table_count(r) == 3);
    CHECK(strcmp(emm_table_source(r, 2), "table_out.txt:9") == 0);
    /* Loading the same names twice is an error naming the first place. */
    CHECK(emm_table_load(r, "table_new.txt", &err) == EMM_ERR_FORMAT);
    CHECK(strstr(err.message, "already defined in table_out.txt") != NULL);
    CHECK(emm_table_count(r) == 3);
    emm_table_free(r);

    /* The standard loading: the shipped table and the user's, by name. */
    r = emm_table_new();
    emm_status st = emm_table_load_standard(r, "table_new.txt", &err);
    CHECK(st == EMM_OK);
    size_t with_user = emm_table_count(r);
    CHECK(with_user >= 1);
    emm_table_free(r);
    r = emm_table_new();
    CHECK(emm_table_load_standard(r, "missing_table.txt", &err) == EMM_ERR_IO);
    CHECK(strstr(err.message, "missing_table.txt") != NULL);
    emm_table_free(r);
    /* The library reads no environment: EMM_TABLE is the configuration
     * table's to read, and a NULL user table is none. */
    r = emm_table_new();
    setenv("EMM_TABLE", "table_new.txt", 1);
    st = emm_table_load_standard(r, NULL, &err);
    CHECK(st != EMM_OK || emm_table_count(r) < with_user);
    emm_table_free(r);
    unsetenv("EMM_TABLE");
    char def[4096];
    /* Run from the build tree: the source tree's table. */
    CHECK(emm_table_default_path(def, sizeof def));
    CHECK(strstr(def, "/data/table.txt") != NULL);
    emm_table_free(t);
}

int main(void)
{
    snprintf(header, sizeof header, "emm-table %d features=%d\n", EMM_TABLE_VERSION, EMM_FEATURES);
    test_parse();
    test_write_append_decide();
    return check_done();
}
