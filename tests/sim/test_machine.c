/* Machine configuration: defaults, INI files, --set, and bad input — every
 * error names the file, the line, the key and the value. */
#include <string.h>

#include "check.h"
#include "emm/sim.h"

static emm_machine *fresh(void)
{
    emm_machine *m;
    emm_error err;
    REQUIRE(emm_machine_new(&m, &err) == EMM_OK);
    return m;
}

/* Loads `text` as file "m.ini" into a default machine; returns the status
 * and leaves the message in err. */
static emm_status load(const char *text, emm_error *err)
{
    emm_machine *m = fresh();
    emm_status st = emm_machine_load_text(m, "m.ini", text, err);
    emm_machine_free(m);
    return st;
}

static void expect_error(const char *text, emm_status status, const char *part1, const char *part2)
{
    emm_error err;
    emm_status st = load(text, &err);
    CHECKF(st == status, "'%s': status %d, wanted %d", text, (int)st, (int)status);
    CHECKF(st != EMM_OK && strstr(err.message, part1) && (!part2 || strstr(err.message, part2)),
           "'%s' gave '%s', wanted '%s' and '%s'", text, st ? err.message : "ok", part1,
           part2 ? part2 : "");
}

static void defaults(void)
{
    emm_machine *m = fresh();
    emm_error err;
    char buf[32];
    CHECK(emm_machine_validate(m, &err) == EMM_OK);
    CHECK(emm_machine_get(m, "clock.mhz") == 400);
    CHECK(emm_machine_get(m, "word.bytes") == 4);
    CHECK(emm_machine_get(m, "local.bytes") == 256 * 1024);
    CHECK(emm_machine_get(m, "remote.bytes") == 6 * 1024 * 1024);
    CHECK(emm_machine_get(m, "direct.cycles_per_word") == 32);
    CHECK(emm_machine_get(m, "direct.write_cycles") == 1);
    CHECK(emm_machine_get(m, "dma.issue") == 266);
    CHECK(emm_machine_get(m, "dma.cycles_per_8b") == 2);
    CHECK(emm_machine_get(m, "dma.chunk_bytes") == 1024);
    CHECK(emm_machine_get(m, "dma.chunk_cycles") == 208);
    CHECK(emm_machine_get(m, "dma.channels") == 2);
    CHECK(emm_machine_get(m, "cache.bytes") == 256 * 1024);
    CHECK(emm_machine_get(m, "cache.assoc") == 4);
    CHECK(emm_machine_get(m, "cache.line") == 64);
    CHECK(emm_machine_get(m, "cache.fetch") == EMM_CACHE_FETCH_MISS);
    CHECK(emm_machine_get(m, "cache.hit") == 1);
    emm_machine_format(m, "cache.fetch", buf, sizeof buf);
    CHECK(strcmp(buf, "miss") == 0);
    emm_machine_format(m, "local.bytes", buf, sizeof buf);
    CHECK(strcmp(buf, "256K") == 0);
    CHECK(emm_machine_dma_cycles(m, 64) == 282);
    CHECK(emm_machine_dma_cycles(m, 1024) == 522);
    CHECK(emm_machine_dma_cycles(m, 1025) == 732);
    CHECK(emm_machine_dma_cycles(m, 4096) == 1914);
    CHECK(emm_machine_dma_cycles(m, 0) == 0);
    /* Every key has a unit, help and a default that parses back. */
    for (size_t i = 0; i < emm_machine_key_count(); i++) {
        const emm_machine_key *k = emm_machine_key_at(i);
        char v[64];
        CHECK(k->unit && *k->unit && k->help && *k->help);
        emm_machine_format(m, k->name, v, sizeof v);
        CHECKF(strcmp(v, k->fallback) == 0, "%s: %s vs %s", k->name, v, k->fallback);
    }
    emm_machine_free(m);
}

static void files(void)
{
    emm_machine *m = fresh();
    emm_error err;
    const char *text =
        "# a machine\n"
        "; another comment\n"
        "clock.mhz = 800\n"
        "\n"
        "[dma]\n"
        "issue = 300   # programming\n"
        "  channels=4\n"
        "[cache]\n"
        "bytes = 64K\n"
        "fetch = always ; comment\n"
        "dma.chunk_bytes = 2K\n";
    CHECKF(emm_machine_load_text(m, "m.ini", text, &err) == EMM_OK, "%s", err.message);
    CHECK(emm_machine_get(m, "clock.mhz") == 800);
    CHECK(emm_machine_get(m, "dma.issue") == 300);
    CHECK(emm_machine_get(m, "dma.channels") == 4);
    CHECK(emm_machine_get(m, "cache.bytes") == 64 * 1024);
    CHECK(emm_machine_get(m, "cache.fetch") == EMM_CACHE_FETCH_ALWAYS);
    CHECK(emm_machine_get(m, "dma.chunk_bytes") == 2048);
    CHECK(emm_machine_validate(m, &err) == EMM_OK);
    /* --set after the file */
    CHECK(emm_machine_set(m, "dma.issue=100", &err) == EMM_OK);
    CHECK(emm_machine_get(m, "dma.issue") == 100);
    CHECK(emm_machine_set(m, " cache.fetch = demand ", &err) == EMM_OK);
    CHECK(emm_machine_get(m, "cache.fetch") == EMM_CACHE_FETCH_DEMAND);
    CHECK(emm_machine_dma_cycles(m, 64) == 100 + 16);
    emm_machine_free(m);

    /* A missing file names itself. */
    m = fresh();
    CHECK(emm_machine_load(m, "/nonexistent/machine.ini", &err) == EMM_ERR_IO);
    CHECK(strstr(err.message, "/nonexistent/machine.ini") != NULL);
    emm_machine_free(m);
}

static void bad_files(void)
{
    expect_error("[dma]\nisue = 3\n", EMM_ERR_INVALID, "m.ini:2:", "unknown key 'dma.isue'");
    expect_error("dma.issue = 12x\n", EMM_ERR_INVALID, "m.ini:1:", "dma.issue = '12x'");
    expect_error("\n\n[dma]\nissue = -1\n", EMM_ERR_INVALID, "m.ini:4:", "'-1'");
    expect_error("dma.issue = 99999999999999999999999\n", EMM_ERR_INVALID, "m.ini:1:",
                 "dma.issue = '99999999999999999999999'");
    expect_error("cache.bytes = 64G\n", EMM_ERR_RANGE, "m.ini:1:", "cache.bytes = '64G': out of range");
    expect_error("dma.channels = 0\n", EMM_ERR_RANGE, "m.ini:1:", "dma.channels = '0'");
    expect_error("[dma]\nissue 266\n", EMM_ERR_FORMAT, "m.ini:2:", "expected 'key = value', got 'issue 266'");
    expect_error("[dmaa]\nissue = 2\n", EMM_ERR_INVALID, "m.ini:1:", "unknown section '[dmaa]'");
    expect_error("[dma\n", EMM_ERR_FORMAT, "m.ini:1:", "[section]");
    expect_error("[dma]\nissue = 1\n[dma]\nissue = 2\n", EMM_ERR_INVALID, "m.ini:4:",
                 "duplicate key 'dma.issue' (first set on line 2)");
    expect_error("dma.issue =\n", EMM_ERR_FORMAT, "m.ini:1:", "dma.issue");
    expect_error("= 3\n", EMM_ERR_FORMAT, "m.ini:1:", "missing key");
    expect_error("cache.fetch = sometimes\n", EMM_ERR_INVALID, "m.ini:1:", "cache.fetch = 'sometimes'");
    expect_error("nosuchkey = 1\n", EMM_ERR_INVALID, "m.ini:1:", "unknown key 'nosuchkey'");
}

static void bad_sets_and_validation(void)
{
    emm_machine *m = fresh();
    emm_error err;
    CHECK(emm_machine_set(m, "dma.isue=3", &err) == EMM_ERR_INVALID);
    CHECK(strstr(err.message, "unknown key 'dma.isue'") != NULL);
    CHECK(emm_machine_set(m, "dma.issue", &err) == EMM_ERR_INVALID);
    CHECK(strstr(err.message, "KEY=VALUE") != NULL);
    CHECK(emm_machine_set(m, "word.bytes=abc", &err) == EMM_ERR_INVALID);
    CHECK(strstr(err.message, "word.bytes = 'abc'") != NULL);

    CHECK(emm_machine_set(m, "cache.line=48", &err) == EMM_OK);
    CHECK(emm_machine_validate(m, &err) == EMM_ERR_INVALID);
    CHECK(strstr(err.message, "cache.line = 48") != NULL);
    CHECK(emm_machine_set(m, "cache.line=64", &err) == EMM_OK);
    CHECK(emm_machine_set(m, "cache.bytes=1000", &err) == EMM_OK);
    CHECK(emm_machine_validate(m, &err) == EMM_ERR_INVALID);
    CHECK(strstr(err.message, "cache.bytes = 1000") != NULL);
    CHECK(emm_machine_set(m, "cache.bytes=768", &err) == EMM_OK); /* 3 sets */
    CHECK(emm_machine_validate(m, &err) == EMM_ERR_INVALID);
    CHECK(strstr(err.message, "power of two") != NULL);
    CHECK(emm_machine_set(m, "cache.bytes=1K", &err) == EMM_OK);
    CHECK(emm_machine_set(m, "word.bytes=3", &err) == EMM_OK);
    CHECK(emm_machine_validate(m, &err) == EMM_ERR_INVALID);
    CHECK(strstr(err.message, "word.bytes = 3") != NULL);
    emm_machine_free(m);
}

/* docs/machine.md documents every key (the table is the one source). */
static void documented(void)
{
    FILE *f = fopen(EMM_TEST_DATA "/../../docs/machine.md", "r");
    static char text[1 << 16];
    size_t n;
    REQUIRE(f != NULL);
    n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = '\0';
    for (size_t i = 0; i < emm_machine_key_count(); i++) {
        char cell[96];
        const emm_machine_key *k = emm_machine_key_at(i);
        snprintf(cell, sizeof cell, "| `%s` | %s |", k->name, k->fallback);
        CHECKF(strstr(text, cell) != NULL, "docs/machine.md lacks '%s'", cell);
    }
}

int main(void)
{
    documented();
    defaults();
    files();
    bad_files();
    bad_sets_and_validation();
    return check_done();
}
