/* Internal to the emm command: every subcommand's options as rows of one
 * table, as `emm run`'s come from the configuration table (core/config.c).
 * A row names an option, what its value is and where it goes, and its
 * help; one parser walks argv, checks each value by its kind and reports
 * every problem the same way ("emm CMD: MESSAGE" and "Try 'emm CMD
 * --help'.", exit status 2), and the options part of --help is printed from
 * the same rows. */
#ifndef EMM_TOOLS_OPTS_H
#define EMM_TOOLS_OPTS_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

/* What a value may be, and the type `dst` points to. */
typedef enum opt_kind {
    OPT_FLAG,     /* no value: int, set to 1 */
    OPT_TEXT,     /* any non-empty text: const char * (or opts_list with repeat) */
    OPT_U64,      /* a non-negative integer in [min, max]: uint64_t */
    OPT_SIZE,     /* bytes, K/M/G suffixes allowed, in [min, max]: uint64_t */
    OPT_POSITIVE, /* a finite number above 0: double */
    OPT_WORD,     /* one of `words`: int, the word's index */
    OPT_STRATEGY, /* a strategy string, checked by emm_strategy_parse: the text, as
                     for OPT_TEXT */
    OPT_CALL,     /* `call` checks and stores it (with metavar NULL, no value: NULL) */
    OPT_REST,     /* a positional that ends the options: int, the index in argv of
                     this argument, which with all after it is the command's as is
                     (emm run's PROGRAM ARGS...) */
} opt_kind;

/* The values of a repeated option in the order given (--set, --strategy);
 * the strings are argv's, the array opts_run's. */
typedef struct opts_list {
    const char **v;
    size_t n;
} opts_list;

/* One option, or with name NULL one positional argument (in the order of
 * the rows; a repeated positional takes the rest). */
typedef struct opts_row {
    const char *name;         /* "--window"; NULL: positional. Messages name it so. */
    const char *alias;        /* another spelling ("-j"), or NULL */
    const char *metavar;      /* "N"; NULL for a flag */
    opt_kind kind;
    void *dst;                /* holds the default before parsing */
    const char *help;         /* '\n' starts a new line; long lines are wrapped */
    uint64_t min, max;        /* OPT_U64, OPT_SIZE: the bounds (max 0: none) */
    const char *const *words; /* OPT_WORD: NULL-terminated */
    bool required;            /* "missing --mesh FILE" when absent */
    bool repeat;              /* OPT_TEXT, OPT_STRATEGY: dst is an opts_list */
    bool show_default;        /* --help appends "(default V)", V read from dst */
    /* OPT_CALL: takes the value for dst, the option as typed naming it;
     * false after printing why not. */
    bool (*call)(void *dst, const char *as, const char *value);
    unsigned seen;            /* set by opts_parse: how many times it was given */
} opts_row;

/* A command's rows (ended by a row with neither name nor metavar) and its
 * help. */
typedef struct opts {
    const char *cmd; /* "mesh gen": messages start "emm mesh gen: " */
    opts_row *rows;
    /* Prints --help: the usage lines and the prose, with opts_help(out, o)
     * where the options go. */
    void (*usage)(FILE *out, const struct opts *o);
} opts;

#define OPTS_END {0}

/* Parses argv[1..argc) (argv[0] is the command's own name) into the rows'
 * destinations: options anywhere, "--name=value" or "--name value", "--"
 * ending the options. Returns false when the command goes on (*rc is then
 * EMM_EXIT_OK); true when it stops with *rc: EMM_EXIT_OK after -h/--help
 * printed the usage, EMM_EXIT_USAGE after a message naming the problem and
 * the hint. */
bool opts_parse(opts *o, int argc, char **argv, int *rc);

/* The options part of --help: one entry per option row, name and metavar
 * in a column, the help beside it. */
void opts_help(FILE *out, const opts *o);

/* opts_parse, and when the command goes on run(args); then releases what
 * parsing allocated (the repeated options' arrays), so a command whose rows
 * repeat goes through here. Returns the exit status. */
int opts_run(opts *o, int argc, char **argv, int (*run)(void *args), void *args);

/* A subcommand: `emm mesh gen ...` runs gen's run with argv from "gen". */
typedef struct opts_sub {
    const char *name;
    int (*run)(int argc, char **argv);
} opts_sub;

/* Runs the subcommand argv[1] names among subs (ended by {NULL, NULL});
 * -h/--help prints usage; none or another word is a usage error that lists
 * the subcommands. Returns the exit status. */
int opts_subcommand(const char *cmd, const opts_sub *subs, void (*usage)(FILE *out), int argc,
                    char **argv);

#endif
