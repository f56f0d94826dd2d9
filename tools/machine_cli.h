/* Internal to the emm command: the machine options shared by 'emm machine'
 * and 'emm replay': --machine FILE (or $EMM_MACHINE), then --set KEY=VALUE
 * overrides in order, then one validation. */
#ifndef EMM_TOOLS_MACHINE_CLI_H
#define EMM_TOOLS_MACHINE_CLI_H

#include "emm/sim.h"

#define MACHINE_CLI_MAX_SETS 64

typedef struct machine_cli {
    const char *file;                         /* --machine, NULL when absent */
    const char *sets[MACHINE_CLI_MAX_SETS];   /* --set values in order */
    int nsets;
} machine_cli;

/* When argv[*i] is --machine or --set, consumes it (and its value) and
 * returns 1; returns 0 when it is another argument; -1 after printing a
 * usage error. */
int machine_cli_option(machine_cli *mc, const char *cmd, int argc, char **argv, int *i);

/* Builds and validates the machine. On failure prints the error and returns
 * the exit status (1 for a bad machine file, 2 for a bad --set); else 0. */
int machine_cli_build(const machine_cli *mc, const char *cmd, emm_machine **out);

/* The lines of --help that describe these options. */
#define MACHINE_CLI_HELP                                                                  \
    "  --machine FILE   read the machine from an INI file (default: $EMM_MACHINE when\n"   \
    "                   set, else the built-in STHORM-like defaults; docs/machine.md)\n"   \
    "  --set KEY=VALUE  override one key after the file, e.g. --set dma.issue=300;\n"      \
    "                   may be repeated ('emm machine show' lists the keys)\n"

#endif
