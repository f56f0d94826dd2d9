/* Internal: a tiny streaming JSON writer for reports. It tracks nesting and
 * commas so callers write keys and values in order; output goes to a FILE.
 * Numbers are unsigned 64-bit integers or finite doubles; strings are
 * escaped, and always valid UTF-8 (json_write_string). Errors are sticky: check json_failed() (or ferror) at the end. */
#ifndef EMM_INTERNAL_JSON_H
#define EMM_INTERNAL_JSON_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#define JSON_MAX_DEPTH 32

typedef struct json_writer {
    FILE *out;
    int depth;
    bool first[JSON_MAX_DEPTH]; /* nothing written yet at this level */
    bool pretty;
    bool pending;               /* a key was written; its value comes next */
    bool failed;                /* nesting too deep */
} json_writer;

void json_init(json_writer *w, FILE *out, bool pretty);
/* Inside an object, json_key comes before each value. */
void json_key(json_writer *w, const char *key);
void json_begin_object(json_writer *w);
void json_end_object(json_writer *w);
void json_begin_array(json_writer *w);
void json_end_array(json_writer *w);
void json_string(json_writer *w, const char *s);
void json_u64(json_writer *w, uint64_t v);
void json_double(json_writer *w, double v);
/* A finite double with `decimals` digits after the point (%.*f): for
 * numbers whose precision is known, written short. */
void json_fixed(json_writer *w, double v, int decimals);
void json_bool(json_writer *w, bool v);
void json_null(json_writer *w);
/* Writes s as one JSON string: quotes, backslashes and control characters
 * escaped; well-formed UTF-8 copied; every byte that is not part of a
 * well-formed UTF-8 sequence written as \ufffd (docs/report.md). */
void json_write_string(FILE *out, const char *s);
/* Ends the document with a newline. */
void json_finish(json_writer *w);
bool json_failed(const json_writer *w);

#endif
