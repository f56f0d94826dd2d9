/* Internal: strict parsing of numbers and sizes from text (command-line
 * arguments, machine files, tables, environment variables). Every function
 * rejects empty strings, trailing garbage, signs where none belong and
 * overflow, and returns false without touching *out on failure. */
#ifndef EMM_INTERNAL_PARSE_H
#define EMM_INTERNAL_PARSE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* A non-negative decimal integer. */
bool emm_parse_u64(const char *s, uint64_t *out);
/* A non-negative decimal integer with an optional K, M or G suffix (powers
 * of 1024; a trailing "i" or "B" is accepted: 64K, 64KiB, 1M). */
bool emm_parse_size(const char *s, uint64_t *out);
/* A finite floating-point number. */
bool emm_parse_double(const char *s, double *out);

/* Writes v with thousands grouped ("301,200") into buf and returns buf:
 * counts in messages and tables read better that way. */
const char *emm_grouped(uint64_t v, char buf[32]);

/* Quotes text[0..len) in messages: cut to EMM_CLIP characters with "..." so
 * the explanation after it always fits one line, control characters (a
 * newline) shown as '?'. Returns buf. */
#define EMM_CLIP 60
const char *emm_clip(const char *text, size_t len, char buf[EMM_CLIP + 1]);
/* Replaces control characters in s with '?', in place. */
void emm_printable(char *s);

#endif
