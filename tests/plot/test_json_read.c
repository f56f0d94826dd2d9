/* The strict JSON reader (runtime/json_read.c): what it accepts, what it
 * builds, and that every malformed input is one error naming the input,
 * the line and the column. */
#include <string.h>

#include "check.h"
#include "json_read.h"

static jr_value *ok(const char *text)
{
    jr_value *v = NULL;
    emm_error err;
    emm_status st = jr_parse(text, strlen(text), "t.json", &v, &err);
    CHECKF(st == EMM_OK, "rejected %s: %s", text, st == EMM_OK ? "" : err.message);
    return v;
}

/* A malformed text: an error, and its message names the input and `what`. */
static void bad(const char *text, const char *what)
{
    jr_value *v = NULL;
    emm_error err;
    emm_status st = jr_parse(text, strlen(text), "t.json", &v, &err);
    CHECKF(st == EMM_ERR_FORMAT, "accepted %s", text);
    CHECK(v == NULL);
    if (st != EMM_OK) {
        CHECKF(strncmp(err.message, "t.json: line ", 13) == 0, "%s", err.message);
        CHECKF(strstr(err.message, what) != NULL, "'%s' lacks '%s'", err.message, what);
        CHECK(strchr(err.message, '\n') == NULL);
    }
    jr_free(v);
}

int main(void)
{
    jr_value *v = ok("{\"emm_report\": 1, \"results\": [{\"strategy\": \"cache\", \"x\": -1.5e3},"
                     " true, false, null, [], {}], \"s\": \"a\\\"b\\\\c\\n\\u00e9\\ud83d\\ude00\"}");
    REQUIRE(v != NULL);
    CHECK(jr_type_of(v) == JR_OBJECT && jr_len(v) == 3);
    CHECK(jr_number(jr_get(v, "emm_report")) == 1);
    const jr_value *r = jr_get(v, "results");
    CHECK(jr_is(r, JR_ARRAY) && jr_len(r) == 6);
    CHECK(strcmp(jr_string(jr_get(jr_at(r, 0), "strategy")), "cache") == 0);
    CHECK(jr_number(jr_get(jr_at(r, 0), "x")) == -1500);
    CHECK(jr_bool(jr_at(r, 1)) && !jr_bool(jr_at(r, 2)) && jr_is(jr_at(r, 2), JR_BOOL));
    CHECK(jr_is(jr_at(r, 3), JR_NULL) && jr_len(jr_at(r, 4)) == 0 && jr_is(jr_at(r, 5), JR_OBJECT));
    CHECK(strcmp(jr_string(jr_get(v, "s")), "a\"b\\c\n\xc3\xa9\xf0\x9f\x98\x80") == 0);
    CHECK(strcmp(jr_key_at(v, 1), "results") == 0);
    CHECK(jr_get(v, "missing") == NULL && jr_get(r, "x") == NULL && jr_at(r, 6) == NULL);
    CHECK(jr_string(jr_get(v, "emm_report")) == NULL && jr_number(jr_get(v, "s")) == 0);
    jr_free(v);
    jr_free(ok("  0 "));
    jr_free(ok("-0.5e-2"));
    jr_free(ok("\"\""));
    jr_free(ok("[1,\n2 ,\t3]"));
    jr_free(NULL);

    bad("", "unexpected end of input");
    bad("   ", "unexpected end of input");
    bad("{", "expected a string key");
    bad("[1, 2", "unexpected end of input");
    bad("[1, 2,]", "trailing comma in an array");
    bad("{\"a\": 1,}", "trailing comma in an object");
    bad("{\"a\" 1}", "expected ':'");
    bad("{a: 1}", "expected a string key");
    bad("{\"a\": 1, \"a\": 2}", "key repeated");
    bad("[1 2]", "expected ',' or ']'");
    bad("{\"a\": 1 \"b\": 2}", "expected ',' or '}'");
    bad("01", "leading zero");
    bad("1.", "decimal point");
    bad("1e", "exponent");
    bad("-", "invalid number");
    bad("+1", "unexpected character");
    bad("NaN", "unexpected character");
    bad("1e999", "out of range");
    bad("tru", "unexpected word");
    bad("nul", "unexpected word");
    bad("\"abc", "unterminated string");
    bad("\"a\tb\"", "control character");
    bad("\"\\x\"", "invalid escape");
    bad("\"\\u12\"", "four hex digits");
    bad("\"\\ud800\"", "unpaired high surrogate");
    bad("\"\\udc00\"", "unpaired low surrogate");
    bad("\"\\u0000\"", "\\u0000");
    bad("{} {}", "text after the JSON value");
    bad("[1] x", "text after the JSON value");
    bad("// c\n1", "unexpected character");
    bad("\xEF\xBB\xBF{}", "byte order mark");
    {
        char deep[200];
        memset(deep, '[', 100);
        memset(deep + 100, ']', 100);
        deep[199] = '\0'; /* 100 '[' and 99 ']': parsing stops at the depth limit first */
        bad(deep, "nested too deep");
    }
    {
        /* The line and column of the problem. */
        jr_value *x = NULL;
        emm_error err;
        const char *text = "{\n  \"a\": [1,\n        2,,\n  ]\n}";
        CHECK(jr_parse(text, strlen(text), "t.json", &x, &err) == EMM_ERR_FORMAT);
        CHECKF(strstr(err.message, "line 3, column 11") != NULL, "%s", err.message);
    }
    {
        jr_value *x = NULL;
        emm_error err;
        CHECK(jr_parse_file("/nonexistent/r.json", &x, &err) == EMM_ERR_IO);
        CHECK(strstr(err.message, "/nonexistent/r.json: cannot open") == err.message);
    }
    return check_done();
}
