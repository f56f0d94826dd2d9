/* The frames between a session's proxy and emm-session
 * (runtime/session_wire.c): the start carries every setting that was set,
 * as its row's text, so the server's configuration equals the program's
 * (an output path with a % in it included); a description crosses whole;
 * the program's objects come back as they went; a truncated or foreign
 * payload is refused. */
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "session_wire.h"

static void start(void)
{
    emm_config c, back;
    emm_error err;
    emm_config_init(&c);
    /* "%%" is one percent sign, %p the program's pid (7). */
    REQUIRE(emm_config_set(&c, EMM_CONFIG_REPORT, "r-%%-%p.json", "--report", 7, &err) == EMM_OK);
    REQUIRE(emm_config_set(&c, EMM_CONFIG_PROFILE, "5it", "EMM_PROFILE", 7, &err) == EMM_OK);
    REQUIRE(emm_config_set(&c, EMM_CONFIG_STRATEGY, "tiles+convolution@32", NULL, 7, &err) ==
            EMM_OK);
    REQUIRE(emm_config_set(&c, EMM_CONFIG_COMPARE, "all", NULL, 7, &err) == EMM_OK);
    REQUIRE(emm_config_set(&c, EMM_CONFIG_FINALISTS, "9", NULL, 7, &err) == EMM_OK);
    REQUIRE(emm_config_set(&c, EMM_CONFIG_PHASES, "0", NULL, 7, &err) == EMM_OK);
    REQUIRE(emm_config_set(&c, EMM_CONFIG_LOG, "verbose", NULL, 7, &err) == EMM_OK);
    REQUIRE(emm_config_set(&c, EMM_CONFIG_TAG, "vertices:stride=24,xyz=0:f64", NULL, 7, &err) ==
            EMM_OK);
    CHECK(strcmp(c.report, "r-%-7.json") == 0);
    emm_session_config sc = {&c, EMM_CAPTURE_VALGRIND, "prog", 1, {0, NULL, NULL}, NULL, NULL, 0,
                             1u << EMM_ARRAY_TRIANGLES, 0};
    unsigned char *b;
    size_t n;
    REQUIRE(wire_start_encode(&sc, 7, &b, &n));
    char *strings;
    emm_capture cap;
    int only;
    unsigned expect;
    const char *program;
    long pid = 0;
    CHECKF(wire_start_decode(b, n, &back, &strings, &cap, &only, &expect, &program, &pid,
                             &err) == EMM_OK,
           "%s", err.message);
    CHECK(cap == EMM_CAPTURE_VALGRIND && only == 1 && expect == 1u << EMM_ARRAY_TRIANGLES &&
          strcmp(program, "prog") == 0 && pid == 7);
    CHECKF(strcmp(back.report, c.report) == 0, "%s", back.report);
    CHECK(back.window_accesses == 0 && back.window_iterations == 5);
    CHECK(back.has_strategy && memcmp(&back.strategy, &c.strategy, sizeof c.strategy) == 0);
    CHECK(back.compare == EMM_COMPARE_ALL && back.finalists == 9 && back.phases == 0 &&
          back.log == 2);
    CHECK(back.tags.n == 0); /* descriptions come whole: the rules stay */
    CHECK(back.source[EMM_CONFIG_REPORT] && strcmp(back.source[EMM_CONFIG_REPORT], "--report") == 0);
    CHECK(back.source[EMM_CONFIG_MACHINE] == NULL);
    emm_config_free(&back);
    free(strings);
    /* Every shorter payload is refused, never read past. */
    for (size_t k = 0; k < n; k++) {
        emm_status st = wire_start_decode(b, k, &back, &strings, &cap, &only, &expect,
                                          &program, &pid, &err);
        CHECKF(st != EMM_OK || k == n, "a start cut at %zu of %zu accepted", k, n);
        emm_config_free(&back);
        free(strings);
    }
    /* Another build's start. */
    b[0] ^= 0x40;
    CHECK(wire_start_decode(b, n, &back, &strings, &cap, &only, &expect, &program, &pid,
                            &err) == EMM_ERR_FORMAT &&
          strstr(err.message, "different builds"));
    emm_config_free(&back);
    free(strings);
    free(b);
    emm_config_free(&c);
}

static void tag(void)
{
    static double v[30];
    emm_array_desc d = {EMM_ARRAY_VERTICES, EMM_TAG_AXIS, 2, v, 10, 24, 8, EMM_F64, 3,
                        "EMM_TAG rule 3 (vertices:stride=24,z=8:f64)",
                        {EMM_TAG_NO_LINK, EMM_TAG_NO_LINK, EMM_TAG_NO_LINK, EMM_TAG_NO_LINK}},
                   e;
    unsigned char *b;
    size_t n;
    REQUIRE(wire_tag_encode(&d, &b, &n));
    REQUIRE(wire_tag_decode(b, n, &e));
    CHECK(e.kind == d.kind && e.shape == d.shape && e.axis == 2 && e.base == d.base &&
          e.count == 10 && e.stride == 24 && e.offset == 8 && e.type == EMM_F64 && e.rule == 3);
    CHECK(e.origin && strcmp(e.origin, d.origin) == 0);
    for (size_t k = 0; k < n; k++)
        CHECKF(!wire_tag_decode(b, k, &e), "a tag cut at %zu accepted", k);
    free(b);
    d.origin = NULL;
    d.axis = -1;
    REQUIRE(wire_tag_encode(&d, &b, &n));
    REQUIRE(wire_tag_decode(b, n, &e));
    CHECK(e.origin == NULL && e.axis == -1);
    free(b);
    /* A half-edge block's links travel with it. */
    d.kind = EMM_ARRAY_TRIANGLES;
    d.shape = EMM_TAG_HALFEDGES;
    d.type = EMM_I32;
    d.offset = 4;
    d.link[EMM_TAG_LINK_NEXT] = 8;
    d.link[EMM_TAG_LINK_PREV] = 12;
    d.link[EMM_TAG_LINK_FACE] = 0;
    REQUIRE(wire_tag_encode(&d, &b, &n));
    REQUIRE(wire_tag_decode(b, n, &e));
    CHECK(e.shape == EMM_TAG_HALFEDGES && memcmp(e.link, d.link, sizeof e.link) == 0);
    free(b);
}

static void modules(void)
{
    emm_trace_module m[2] = {{0x1000, 0x400000, 0x500000, "/usr/bin/prog"},
                             {0x7f0000, 0x7f0000, 0x7f8000, "/lib/libc.so.6"}},
                     *back;
    unsigned char *b;
    size_t n;
    uint32_t nb;
    REQUIRE(wire_modules_encode(m, 2, &b, &n));
    REQUIRE(wire_modules_decode(b, n, &back, &nb));
    CHECK(nb == 2);
    for (uint32_t i = 0; i < nb && i < 2; i++)
        CHECK(back[i].bias == m[i].bias && back[i].lo == m[i].lo && back[i].hi == m[i].hi &&
              strcmp(back[i].path, m[i].path) == 0);
    free(back);
    CHECK(!wire_modules_decode(b, n - 1, &back, &nb)); /* a path without its end */
    free(b);
    REQUIRE(wire_modules_encode(NULL, 0, &b, &n));
    CHECK(n == 0 && !wire_modules_decode(b, n, &back, &nb));
    free(b);
}

int main(void)
{
    start();
    tag();
    modules();
    return check_done();
}
