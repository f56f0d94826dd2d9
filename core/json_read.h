/* Internal: a small strict JSON reader (RFC 8259) for the reports that
 * runtime/json.c writes, read back by `emm plot`. It builds a tree.
 *
 * Strict: one value and nothing after it but white space; no comments, no
 * trailing commas, no leading zeros, no NaN or Infinity, no control
 * characters or invalid escapes in strings, no unpaired surrogates; a key
 * repeated in one object is an error (the reports never repeat one, so a
 * repeat means a damaged file). Numbers are read as doubles; strings are
 * decoded to UTF-8 and may not hold "\u0000". Nesting is limited to
 * JR_MAX_DEPTH levels. */
#ifndef EMM_INTERNAL_JSON_READ_H
#define EMM_INTERNAL_JSON_READ_H

#include <stdbool.h>
#include <stddef.h>

#include "emm/common.h"

#define JR_MAX_DEPTH 64

typedef enum jr_type { JR_NULL, JR_BOOL, JR_NUMBER, JR_STRING, JR_ARRAY, JR_OBJECT } jr_type;

typedef struct jr_value jr_value;

/* Parses text[0..len) (need not be NUL-terminated). `name` names the input
 * in messages: "NAME: line L, column C: problem". On success *out owns the
 * tree (jr_free). Errors: EMM_ERR_FORMAT for malformed text, EMM_ERR_NOMEM. */
emm_status jr_parse(const char *text, size_t len, const char *name, jr_value **out,
                    emm_error *err);
/* The largest report jr_parse_file reads: 1 GiB (a whole sweep's report
 * is a few MiB); from a pipe or device, EMM_INFILE_STREAM_MAX. */
#define JR_FILE_MAX ((size_t)1 << 30)

/* Reads and parses the file at path (named by its path in messages);
 * EMM_ERR_IO when it cannot be read or is a directory, EMM_ERR_RANGE when
 * it is larger than JR_FILE_MAX (infile.h). */
emm_status jr_parse_file(const char *path, jr_value **out, emm_error *err);
/* Frees a tree; NULL is allowed. */
void jr_free(jr_value *v);

/* Accessors. Each accepts NULL (a missing value) and then answers as for a
 * value of no type: jr_type_of gives JR_NULL, jr_is false. */
jr_type jr_type_of(const jr_value *v);
bool jr_is(const jr_value *v, jr_type t);
/* Member `key` of an object; NULL when v is no object or has no such key. */
const jr_value *jr_get(const jr_value *v, const char *key);
/* Elements of an array or members of an object; 0 for anything else. */
size_t jr_len(const jr_value *v);
/* Element i (< jr_len) of an array or member i of an object. */
const jr_value *jr_at(const jr_value *v, size_t i);
/* The key of member i (< jr_len) of an object. */
const char *jr_key_at(const jr_value *v, size_t i);
/* A number's value (0 for anything else). */
double jr_number(const jr_value *v);
/* A string's UTF-8 text (NULL for anything else). */
const char *jr_string(const jr_value *v);
/* A boolean's value (false for anything else). */
bool jr_bool(const jr_value *v);

#endif
