/* emm machine: show the simulated machine (docs/machine.md,
 * thesis §3.2) and the cost of one DMA transfer. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "machine_cli.h"

int machine_cli_option(machine_cli *mc, const char *cmd, int argc, char **argv, int *i)
{
    const char *v;
    if (strcmp(argv[*i], "--machine") == 0) {
        if (!(v = cli_value(cmd, argc, argv, i)))
            return -1;
        mc->file = v;
        return 1;
    }
    if (strcmp(argv[*i], "--set") == 0) {
        if (!(v = cli_value(cmd, argc, argv, i)))
            return -1;
        if (mc->nsets == MACHINE_CLI_MAX_SETS) {
            cli_usage_error(cmd, "at most %d --set options", MACHINE_CLI_MAX_SETS);
            return -1;
        }
        mc->sets[mc->nsets++] = v;
        return 1;
    }
    return 0;
}

int machine_cli_build(const machine_cli *mc, const char *cmd, emm_machine **out)
{
    emm_machine *m = NULL;
    emm_error err;
    const char *file = mc->file;
    if (!file) {
        const char *env = getenv("EMM_MACHINE");
        if (env && *env)
            file = env;
    }
    if (emm_machine_new(&m, &err) != EMM_OK)
        return cli_fail(&err);
    if (file && emm_machine_load(m, file, &err) != EMM_OK) {
        emm_machine_free(m);
        return cli_fail(&err);
    }
    for (int i = 0; i < mc->nsets; i++) {
        if (emm_machine_set(m, mc->sets[i], &err) != EMM_OK) {
            emm_machine_free(m);
            return cli_usage_error(cmd, "%s", err.message);
        }
    }
    if (emm_machine_validate(m, &err) != EMM_OK) {
        emm_machine_free(m);
        return cli_fail(&err);
    }
    *out = m;
    return 0;
}

static void usage(FILE *out)
{
    fprintf(out,
            "usage: emm machine show [--machine FILE] [--set KEY=VALUE]...\n"
            "       emm machine dma BYTES [--machine FILE] [--set KEY=VALUE]...\n"
            "\n"
            "  show   print every parameter of the simulated machine in effect, as a\n"
            "         machine file (INI) that --machine reads back\n"
            "  dma    print the cycles of one synchronous DMA of BYTES bytes:\n"
            "         dma.issue + dma.cycles_per_8b*ceil(BYTES/8)\n"
            "                   + dma.chunk_cycles*(ceil(BYTES/dma.chunk_bytes) - 1)\n"
            "\n"
            MACHINE_CLI_HELP);
}

static void show(const emm_machine *m, const char *source)
{
    char section[64] = "";
    printf("# emm machine: %s\n", source);
    for (size_t i = 0; i < emm_machine_key_count(); i++) {
        const emm_machine_key *k = emm_machine_key_at(i);
        const char *dot = strchr(k->name, '.');
        size_t slen = (size_t)(dot - k->name);
        char value[64], line[160];
        if (strlen(section) != slen || strncmp(section, k->name, slen) != 0) {
            snprintf(section, sizeof section, "%.*s", (int)slen, k->name);
            printf("\n[%s]\n", section);
        }
        emm_machine_format(m, k->name, value, sizeof value);
        snprintf(line, sizeof line, "%s = %s", dot + 1, value);
        printf("%-28s # %s: %s (default %s)\n", line, k->unit, k->help, k->fallback);
    }
}

int emm_cmd_machine(int argc, char **argv)
{
    machine_cli mc = {0};
    const char *sub = NULL, *bytes_arg = NULL;
    emm_machine *m = NULL;
    int rc;

    for (int i = 1; i < argc; i++) {
        int r;
        if (cli_is_help(argv[i])) {
            usage(stdout);
            return EMM_EXIT_OK;
        }
        r = machine_cli_option(&mc, "machine", argc, argv, &i);
        if (r < 0)
            return EMM_EXIT_USAGE;
        if (r > 0)
            continue;
        if (argv[i][0] == '-' && argv[i][1] != '\0')
            return cli_usage_error("machine", "unknown option '%s'", argv[i]);
        if (!sub)
            sub = argv[i];
        else if (strcmp(sub, "dma") == 0 && !bytes_arg)
            bytes_arg = argv[i];
        else
            return cli_usage_error("machine", "unexpected argument '%s'", argv[i]);
    }
    if (!sub)
        return cli_usage_error("machine", "missing subcommand: show or dma");
    if (strcmp(sub, "show") != 0 && strcmp(sub, "dma") != 0)
        return cli_usage_error("machine", "unknown subcommand '%s': expected show or dma", sub);
    if (strcmp(sub, "dma") == 0) {
        uint64_t bytes;
        if (!bytes_arg)
            return cli_usage_error("machine dma", "missing BYTES");
        if (!cli_size("machine dma", "BYTES", bytes_arg, &bytes))
            return EMM_EXIT_USAGE;
        if (bytes > (1ull << 40))
            return cli_usage_error("machine dma", "BYTES = %s: at most 1T", bytes_arg);
        if ((rc = machine_cli_build(&mc, "machine", &m)) != 0)
            return rc;
        printf("%llu\n", (unsigned long long)emm_machine_dma_cycles(m, bytes));
    } else {
        const char *file = mc.file ? mc.file : getenv("EMM_MACHINE");
        char source[512];
        if ((rc = machine_cli_build(&mc, "machine", &m)) != 0)
            return rc;
        snprintf(source, sizeof source, "defaults%s%s%s", file && *file ? ", then " : "",
                 file && *file ? file : "", mc.nsets ? ", then --set" : "");
        show(m, source);
    }
    emm_machine_free(m);
    return EMM_EXIT_OK;
}
