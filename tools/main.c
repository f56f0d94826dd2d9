/* emm — the command line (docs/design.md "The command line"). One table of
 * subcommands; each lives in its own cmd_*.c. */
#include <stdio.h>
#include <string.h>

#include "cli.h"

struct command {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *summary;
};

static const struct command commands[] = {
    {"mesh", emm_cmd_mesh, "generate meshes and describe mesh files"},
    {"machine", emm_cmd_machine, "show the simulated machine and DMA costs"},
    {"trace", emm_cmd_trace, "describe, export and import access traces"},
    {"replay", emm_cmd_replay, "simulate a trace under a strategy"},
    {"annotate", emm_cmd_annotate, "a strategy's cycles by source line and function"},
    {"layout", emm_cmd_layout, "build a layout and draw or describe its cells"},
    {"profile", emm_cmd_profile, "distance profile of a trace and the strategy it picks"},
    {"table", emm_cmd_table, "list the strategy table or add a sample to it"},
    {"run", emm_cmd_run, "run a program under the shim: profile, decide, simulate"},
    {"plot", emm_cmd_plot, "draw a report's figures with gnuplot (PNG, SVG)"},
};

static void usage(FILE *out)
{
    fprintf(out,
            "usage: emm COMMAND [ARGS...]\n"
            "\n"
            "emm simulates how a mesh-traversal program would run on a machine with an\n"
            "explicitly managed memory (a DMA-fed local store, no cache), beside direct\n"
            "remote reads and a hardware cache.\n"
            "\n"
            "commands:\n");
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        fprintf(out, "  %-10s %s\n", commands[i].name, commands[i].summary);
    fprintf(out,
            "\n"
            "'emm COMMAND --help' explains each command. 'emm --version' prints the version.\n");
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return EMM_EXIT_USAGE;
    }
    if (cli_is_help(argv[1])) {
        usage(stdout);
        return EMM_EXIT_OK;
    }
    if (strcmp(argv[1], "--version") == 0) {
        printf("emm %s\n", emm_version());
        return EMM_EXIT_OK;
    }
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (strcmp(argv[1], commands[i].name) == 0)
            return commands[i].run(argc - 1, argv + 1);
    cli_error("unknown command '%s'; try 'emm --help'", argv[1]);
    return EMM_EXIT_USAGE;
}
