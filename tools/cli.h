/* Internal to the emm command: the subcommands and small shared helpers. */
#ifndef EMM_TOOLS_CLI_H
#define EMM_TOOLS_CLI_H

#include <stdbool.h>
#include <stdio.h>

#include "emm/common.h"
#include "emm/config.h"

/* Each subcommand gets argv starting at its own name (argv[0] == "mesh") and
 * returns the process exit status: 0 success, 1 failure on bad data, 2 bad
 * usage. */
int emm_cmd_mesh(int argc, char **argv);
int emm_cmd_machine(int argc, char **argv);
int emm_cmd_trace(int argc, char **argv);
int emm_cmd_replay(int argc, char **argv);
int emm_cmd_layout(int argc, char **argv);
int emm_cmd_profile(int argc, char **argv);
int emm_cmd_table(int argc, char **argv);
int emm_cmd_run(int argc, char **argv);
int emm_cmd_plot(int argc, char **argv);
int emm_cmd_annotate(int argc, char **argv);

/* Exit statuses. */
enum { EMM_EXIT_OK = 0, EMM_EXIT_FAIL = 1, EMM_EXIT_USAGE = 2 };

/* Prints "emm: <message>" on stderr, one line. */
void cli_error(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
/* Prints "emm: <err->message>" and returns EMM_EXIT_FAIL. */
int cli_fail(const emm_error *err);
/* Prints "emm <cmd>: <message>\nTry 'emm <cmd> --help'." and returns EMM_EXIT_USAGE. */
int cli_usage_error(const char *cmd, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* A bad value whose message says all (it names the option and what it
 * accepts): "emm CMD: MESSAGE", one line; returns EMM_EXIT_USAGE. */
int cli_bad_value(const char *cmd, const emm_error *err);
/* True when `arg` is -h or --help. */
bool cli_is_help(const char *arg);

/* The file the variable of configuration row k names (EMM_MACHINE,
 * EMM_TABLE), read and checked by that row alone, as the shim reads it:
 * into path (EMM_CONFIG_PATH_MAX bytes), "" when the variable is unset or
 * empty. With may_be_new, a file that does not exist yet is taken too (a
 * table to add to, made when missing). Returns 0, or after printing
 * "emm: EMM_X='value': problem" EMM_EXIT_FAIL. */
int cli_env_file(emm_config_key k, bool may_be_new, char path[EMM_CONFIG_PATH_MAX]);

#endif
