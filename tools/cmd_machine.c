/* emm machine: show the simulated machine (docs/machine.md,
 * thesis §3.2) and the cost of one DMA transfer. */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "machine_cli.h"

int machine_cli_build(machine_cli *mc, const char *cmd, emm_machine **out)
{
    emm_machine *m = NULL;
    emm_error err;
    int rc;
    if (!mc->file) {
        if ((rc = cli_env_file(EMM_CONFIG_MACHINE, false, mc->env)) != 0)
            return rc;
        if (mc->env[0])
            mc->file = mc->env;
    }
    if (emm_machine_new(&m, &err) != EMM_OK)
        return cli_fail(&err);
    if (mc->file && emm_machine_load(m, mc->file, &err) != EMM_OK) {
        emm_machine_free(m);
        return cli_fail(&err);
    }
    for (size_t i = 0; i < mc->sets.n; i++) {
        if (emm_machine_set(m, mc->sets.v[i], &err) != EMM_OK) {
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

static void usage_head(FILE *out)
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
            "\n");
}

static void usage(FILE *out, const opts *o)
{
    usage_head(out);
    opts_help(out, o);
}

/* emm machine --help: the options both subcommands take. */
static void usage_all(FILE *out)
{
    machine_cli mc = {0};
    opts_row rows[] = {MACHINE_CLI_OPTS(&mc), OPTS_END};
    opts o = {"machine", rows, usage};
    usage(out, &o);
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

/* What the command line asked for. */
struct machine_args {
    const char *cmd; /* "machine show" or "machine dma" */
    machine_cli mc;
    uint64_t bytes;  /* dma's BYTES */
};

static int show_dma(void *p)
{
    struct machine_args *a = p;
    machine_cli *mc = &a->mc;
    emm_machine *m = NULL;
    int rc = machine_cli_build(mc, a->cmd, &m);
    if (rc != 0)
        return rc;
    if (strcmp(a->cmd, "machine dma") == 0) {
        printf("%llu\n", (unsigned long long)emm_machine_dma_cycles(m, a->bytes));
    } else {
        char source[512];
        snprintf(source, sizeof source, "defaults%s%s%s", mc->file ? ", then " : "",
                 mc->file ? mc->file : "", mc->sets.n ? ", then --set" : "");
        show(m, source);
    }
    emm_machine_free(m);
    return EMM_EXIT_OK;
}

/* show, or dma with its BYTES. */
static int machine_sub(int argc, char **argv, bool dma)
{
    struct machine_args a = {.cmd = dma ? "machine dma" : "machine show"};
    opts_row rows[] = {
        MACHINE_CLI_OPTS(&a.mc),
        {.metavar = "BYTES", .kind = OPT_SIZE, .dst = &a.bytes, .max = 1ull << 40,
         .required = true},
        OPTS_END,
    };
    if (!dma)
        rows[2] = (opts_row)OPTS_END;
    opts o = {a.cmd, rows, usage};
    return opts_run(&o, argc, argv, show_dma, &a);
}

static int machine_show(int argc, char **argv)
{
    return machine_sub(argc, argv, false);
}

static int machine_dma(int argc, char **argv)
{
    return machine_sub(argc, argv, true);
}

int emm_cmd_machine(int argc, char **argv)
{
    static const opts_sub subs[] = {{"show", machine_show}, {"dma", machine_dma}, {NULL, NULL}};
    return opts_subcommand("machine", subs, usage_all, argc, argv);
}
