/* Internal to the emm command: the machine options of every command that
 * simulates ('emm machine', 'emm replay', 'emm annotate', 'emm profile',
 * 'emm table add' and 'build'): --machine FILE (or $EMM_MACHINE), then
 * --set KEY=VALUE overrides in order, then one validation. */
#ifndef EMM_TOOLS_MACHINE_CLI_H
#define EMM_TOOLS_MACHINE_CLI_H

#include "emm/config.h"
#include "emm/sim.h"
#include "opts.h"

typedef struct machine_cli {
    const char *file; /* --machine; after machine_cli_build, $EMM_MACHINE's when absent */
    opts_list sets;   /* --set values in order */
    char env[EMM_CONFIG_PATH_MAX];
} machine_cli;

/* The two option rows, for a command's table. */
#define MACHINE_CLI_OPTS(mc)                                                                      \
    {.name = "--machine", .metavar = "FILE", .kind = OPT_TEXT, .dst = &(mc)->file,              \
     .help = "read the machine from an INI file (default: $EMM_MACHINE when set, else the "     \
             "built-in STHORM-like defaults; docs/machine.md)"},                                \
    {.name = "--set", .metavar = "KEY=VALUE", .kind = OPT_TEXT, .repeat = true,                 \
     .dst = &(mc)->sets,                                                                        \
     .help = "override one key after the file, e.g. --set dma.issue=300; may be repeated "      \
             "('emm machine show' lists the keys)"}

/* Builds and validates the machine. On failure prints the error and returns
 * the exit status (1 for a bad machine file or $EMM_MACHINE, 2 for a bad
 * --set); else 0. */
int machine_cli_build(machine_cli *mc, const char *cmd, emm_machine **out);

#endif
