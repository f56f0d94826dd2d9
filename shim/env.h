/* Internal: the EMM_* environment of libemmshim.so, one descriptor table
 * (STYLE.md §8). Parsing, validation, `emm run --help` and the verbose dump
 * all read the same rows. Built as its own small static library
 * (emm_shim_env) so the emm command can print the table too. */
#ifndef EMM_SHIM_ENV_H
#define EMM_SHIM_ENV_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "emm/session.h"

enum shim_capture {
    SHIM_CAPTURE_AUTO = 0,
    SHIM_CAPTURE_SANCOV,
    SHIM_CAPTURE_FAULT,
    SHIM_CAPTURE_API
};

#define SHIM_PATH_MAX 4096

/* Every EMM_* variable, parsed. Strings point into the environment, except
 * the output paths, which are copied with %p expanded. */
struct shim_env {
    const char *tag;              /* EMM_TAG, NULL when unset */
    enum shim_capture capture;    /* EMM_CAPTURE */
    uint64_t window_accesses;     /* EMM_PROFILE in accesses (0 when in iterations) */
    uint64_t window_iterations;   /* EMM_PROFILE in iterations */
    const char *strategy;         /* EMM_STRATEGY, NULL: decide */
    emm_compare compare;          /* EMM_COMPARE */
    const char *machine;          /* EMM_MACHINE, NULL: defaults */
    const char *table;            /* EMM_TABLE, NULL: the shipped table only */
    char report[SHIM_PATH_MAX];   /* EMM_REPORT, "" when unset */
    char profile_dump[SHIM_PATH_MAX];
    char trace[SHIM_PATH_MAX];
    int log;                      /* EMM_LOG: 0 quiet, 1 summary, 2 verbose */
    bool strict;                  /* EMM_STRICT */
};

/* Checks EMM_TAG's value (the shim passes its rule parser; NULL accepts any
 * non-empty text). Fills why on failure. */
typedef bool (*shim_env_tag_check)(const char *value, char *why, size_t cap);

/* Reads every EMM_* variable through `get` (getenv, or a test's own), with
 * `pid` for %p. On the first bad value returns false and writes one line,
 * "EMM_X='value': expected ..." (no "emm: " prefix, no newline), into msg;
 * e->strict is set even then (from a valid EMM_STRICT). */
bool shim_env_parse(struct shim_env *e, const char *(*get)(const char *name), long pid,
                    shim_env_tag_check tag_check, char *msg, size_t cap);

/* Prints the table: each variable, what it accepts, its default and what it
 * does (for `emm run --help`, the README and EMM_LOG=2). */
void shim_env_help(FILE *out);

/* Prints the values in force (EMM_LOG=2), one "emm:   EMM_X=value" line each. */
void shim_env_dump(const struct shim_env *e, FILE *out);

/* The exit status of a program stopped by EMM_STRICT=1. */
#define SHIM_STRICT_EXIT 125

const char *shim_capture_name(enum shim_capture c);

#endif
