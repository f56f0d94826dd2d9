/* emm trace: describe a trace, export it to Dinero IV's din text format,
 * import din text as an address-only trace (docs/trace-format.md;
 * docs/trace-format.md says how multi-byte accesses and labels map), and
 * synthesise traces of canonical traversals (include/emm/synth.h). */
#include <errno.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "machine_cli.h"
#include "opts.h"
#include "emm/mesh.h"
#include "emm/synth.h"
#include "emm/trace.h"
#include "outfile.h"

#define READ_BATCH 65536

static const char trace_usage_text[] =
    "usage: emm trace info TRACE [--verify]\n"
    "       emm trace export --din TRACE [-o FILE] [--machine FILE] [--set KEY=VALUE]...\n"
    "       emm trace import --din FILE -o TRACE [--bytes N] [--compress]\n"
    "       emm trace synth --mesh FILE --pattern P -o TRACE [--seed S] [--visits N]\n"
    "                       [--length L] [--corner] [--ring] [--work W] [--compress]\n"
    "\n"
    "Describe, export, import and synthesise access traces (the files EMM_TRACE\n"
    "writes).\n"
    "'emm trace SUBCOMMAND --help' explains each subcommand.\n";

static void info_usage(FILE *out, const opts *o)
{
    fputs("usage: emm trace info TRACE [--verify]\n"
          "\n"
          "Prints the trace's version, compression, arrays (kind, record size, count,\n"
          "base address), geometry, accesses (reads and writes) and bytes on disk per\n"
          "access.\n"
          "\n",
          out);
    opts_help(out, o);
}

static void export_usage(FILE *out, const opts *o)
{
    fputs("usage: emm trace export --din TRACE [-o FILE] [--machine FILE] [--set KEY=VALUE]...\n"
          "\n"
          "Writes the trace in Dinero IV's din format, 'LABEL ADDRESS' per line, label 0\n"
          "for a read and 1 for a write, the address in hex. din has no size, and\n"
          "Dinero IV reads every line as the 4-byte word holding its address, so an\n"
          "access becomes one line per cache line it touches (the machine's cache.line,\n"
          "64 by default): its first byte, then the start of each further line. Dinero IV\n"
          "run with that block size (-l1-dbsize) counts the demand fetches, misses and\n"
          "prefetches emm's cache counts on the trace (docs/dinero.md). Addresses are\n"
          "those the models use: the arrays placed as docs/machine.md \"Addresses\"\n"
          "says, the same every run; raw memory (an imported din trace) keeps its own.\n"
          "\n",
          out);
    opts_help(out, o);
}

static void import_usage(FILE *out, const opts *o)
{
    fputs("usage: emm trace import --din FILE -o TRACE [--bytes N] [--compress]\n"
          "\n"
          "Reads Dinero IV din text ('-' for stdin) and writes an address-only trace:\n"
          "one raw-memory array, no geometry, so only the 'direct' and 'cache'\n"
          "strategies apply to it. Label 0 is a read, 1 a write; 2 (instruction\n"
          "fetch) is skipped, as emm models data accesses; other labels are errors.\n"
          "Text after the address is ignored, as Dinero IV does.\n"
          "\n",
          out);
    opts_help(out, o);
}

/* ------------------------------------------------------------------------ */

static int trace_info(int argc, char **argv)
{
    const char *path = NULL;
    int verify = 0;
    opts_row rows[] = {
        {.name = "--verify", .kind = OPT_FLAG, .dst = &verify,
         .help = "also read every block, checking checksums and records, and print "
                 "'verify: ok' or exit 1 with the first problem"},
        {.metavar = "TRACE", .kind = OPT_TEXT, .dst = &path, .required = true},
        OPTS_END,
    };
    opts o = {"trace info", rows, info_usage};
    int rc;
    if (opts_parse(&o, argc, argv, &rc))
        return rc;

    emm_error err;
    emm_trace_reader *r = NULL;
    if (emm_trace_reader_open(path, &r, &err) != EMM_OK)
        return cli_fail(&err);
    const emm_trace_info *info = emm_trace_reader_info(r);
    struct stat st;
    uint64_t size = stat(path, &st) == 0 ? (uint64_t)st.st_size : 0;
    printf("trace:       %s\n", path);
    printf("version:     %u\n", info->version);
    printf("compressed:  %s\n", info->compressed ? "yes (zstd)" : "no");
    printf("arrays:      %u\n", info->narrays);
    for (uint32_t i = 0; i < info->narrays; i++) {
        const emm_trace_array *a = &info->arrays[i];
        if (a->kind == EMM_ARRAY_RAW && a->count == 0)
            printf("  %u: %-9s  record %u B  count unbounded  base 0x%" PRIx64 "\n", i,
                   emm_trace_kind_name(a->kind), a->record_size, a->base);
        else
            printf("  %u: %-9s  record %u B  count %" PRIu64 "  base 0x%" PRIx64 "\n", i,
                   emm_trace_kind_name(a->kind), a->record_size, a->count, a->base);
    }
    if (info->geometry.nv == 0 && info->geometry.nt == 0)
        printf("geometry:    none (address-only: only 'direct' and 'cache' apply)\n");
    else
        printf("geometry:    %" PRIu64 " vertices, %" PRIu64 " triangles\n", info->geometry.nv,
               info->geometry.nt);
    printf("accesses:    %" PRIu64 " (%" PRIu64 " reads, %" PRIu64 " writes)\n", info->accesses,
           info->accesses - info->writes, info->writes);
    printf("blocks:      %" PRIu64 "\n", info->blocks);
    if (info->has_pc) {
        printf("pcs:         yes (emm annotate resolves them), %u modules\n", info->nmodules);
        for (uint32_t i = 0; i < info->nmodules; i++)
            printf("  0x%" PRIx64 "-0x%" PRIx64 "  %s\n", info->modules[i].lo, info->modules[i].hi,
                   info->modules[i].path);
    } else {
        printf("pcs:         no\n");
    }
    if (info->accesses > 0)
        printf("file:        %" PRIu64 " bytes, %.2f bytes per access\n", size,
               (double)size / (double)info->accesses);
    else
        printf("file:        %" PRIu64 " bytes\n", size);
    rc = EMM_EXIT_OK;
    if (verify) {
        emm_trace_record *buf = malloc(READ_BATCH * sizeof *buf);
        if (!buf) {
            emm_trace_reader_close(r);
            cli_error("%s: out of memory", path);
            return EMM_EXIT_FAIL;
        }
        size_t got;
        emm_status s;
        while ((s = emm_trace_read(r, buf, READ_BATCH, &got, &err)) == EMM_OK && got > 0) {
        }
        free(buf);
        fflush(stdout);
        if (s != EMM_OK)
            rc = cli_fail(&err);
        else
            printf("verify:      ok\n");
    }
    emm_trace_reader_close(r);
    return rc;
}

/* ------------------------------------------------------------------------ */

/* "L HEX\n" into p; returns the end. */
static char *put_din_line(char *p, int label, uint64_t addr)
{
    static const char hex[] = "0123456789abcdef";
    char tmp[16];
    int n = 0;
    do {
        tmp[n++] = hex[addr & 15];
        addr >>= 4;
    } while (addr);
    *p++ = (char)('0' + label);
    *p++ = ' ';
    while (n)
        *p++ = tmp[--n];
    *p++ = '\n';
    return p;
}

/* Standard output, or an output file written whole or not at all. */
struct out_file {
    FILE *f;
    emm_outfile file; /* file.path NULL: stdout */
};

static int out_open(struct out_file *o, const char *path)
{
    emm_error err;
    o->file = (emm_outfile){0};
    if (!path) {
        o->f = stdout;
        return 0;
    }
    if (emm_outfile_open(&o->file, path, "the export", &err) != EMM_OK) {
        cli_fail(&err);
        return -1;
    }
    o->f = o->file.f;
    return 0;
}

static int out_close(struct out_file *o, int ok)
{
    emm_error err;
    if (!o->file.path) {
        if (fflush(stdout) != 0 && ok) {
            cli_error("stdout: cannot write: %s", strerror(errno));
            return -1;
        }
        return ok ? 0 : -1;
    }
    if (!ok) {
        emm_outfile_abort(&o->file);
        return -1;
    }
    if (emm_outfile_commit(&o->file, "the export", &err) != EMM_OK) {
        cli_fail(&err);
        return -1;
    }
    return 0;
}

/* Room for the din lines of one record: the lines its bytes span at most,
 * each "L " and 16 hex digits and a newline. */
static size_t din_record_room(uint64_t line)
{
    return (EMM_TRACE_MAX_ACCESS_BYTES / line + 2) * 20;
}

static int trace_export(int argc, char **argv)
{
    const char *path = NULL, *out = NULL;
    int din = 0;
    machine_cli mc = {0};
    opts_row rows[] = {
        {.name = "--din", .kind = OPT_FLAG, .dst = &din, .required = true,
         .help = "the output format (the only one)"},
        {.name = "-o", .alias = "--output", .metavar = "FILE", .kind = OPT_TEXT, .dst = &out,
         .help = "write to FILE (whole or not at all) instead of stdout"},
        MACHINE_CLI_OPTS(&mc),
        {.metavar = "TRACE", .kind = OPT_TEXT, .dst = &path, .required = true},
        OPTS_END,
    };
    opts o = {"trace export", rows, export_usage};
    int rc;
    if (opts_parse(&o, argc, argv, &rc))
        return rc;
    emm_machine *m;
    rc = machine_cli_build(&mc, "trace export", &m);
    free(mc.sets.v); /* opts_parse's list of --set values (opts_run frees it for others) */
    if (rc != 0)
        return rc;
    const uint64_t line = emm_machine_get(m, "cache.line");
    emm_machine_free(m);

    emm_error err;
    emm_trace_reader *r = NULL;
    if (emm_trace_reader_open(path, &r, &err) != EMM_OK)
        return cli_fail(&err);
    const emm_trace_info *info = emm_trace_reader_info(r);
    const size_t room = din_record_room(line), cap = (size_t)READ_BATCH * 20 + room;
    emm_trace_record *buf = malloc(READ_BATCH * sizeof *buf);
    uint64_t *base = malloc((info->narrays ? info->narrays : 1) * sizeof *base);
    char *text = malloc(cap);
    struct out_file dest;
    if (!buf || !text || !base) {
        cli_error("%s: out of memory", path);
        free(buf);
        free(text);
        free(base);
        emm_trace_reader_close(r);
        return EMM_EXIT_FAIL;
    }
    int placed = emm_trace_place(info, base, &err) == EMM_OK;
    if (!placed)
        cli_fail(&err);
    if (!placed || out_open(&dest, out) != 0) {
        free(buf);
        free(text);
        free(base);
        emm_trace_reader_close(r);
        return EMM_EXIT_FAIL;
    }
    int ok = 1;
    size_t got;
    emm_status s = EMM_OK;
    char *p = text;
    while (ok && (s = emm_trace_read(r, buf, READ_BATCH, &got, &err)) == EMM_OK && got > 0) {
        for (size_t i = 0; i < got && ok; i++) {
            const emm_trace_array *a = &info->arrays[buf[i].array];
            /* The reader checked that the address fits 64 bits (raw arrays:
             * element is the address, base is added modulo 2^64); an access
             * running past the top ends at the last address, as in the
             * models. */
            uint64_t addr = base[buf[i].array] + buf[i].element * a->record_size + buf[i].offset;
            uint64_t last = buf[i].bytes - 1 > UINT64_MAX - addr ? UINT64_MAX
                                                                 : addr + (buf[i].bytes - 1);
            p = put_din_line(p, buf[i].write, addr);
            for (uint64_t l = addr / line + 1; l <= last / line; l++)
                p = put_din_line(p, buf[i].write, l * line);
            if ((size_t)(p - text) > cap - room) {
                if (fwrite(text, 1, (size_t)(p - text), dest.f) != (size_t)(p - text)) {
                    cli_error("%s: cannot write: %s", out ? out : "stdout", strerror(errno));
                    ok = 0;
                }
                p = text;
            }
        }
    }
    if (ok && p > text && fwrite(text, 1, (size_t)(p - text), dest.f) != (size_t)(p - text)) {
        cli_error("%s: cannot write: %s", out ? out : "stdout", strerror(errno));
        ok = 0;
    }
    if (ok && s != EMM_OK) {
        cli_fail(&err);
        ok = 0;
    }
    free(buf);
    free(text);
    free(base);
    emm_trace_reader_close(r);
    return out_close(&dest, ok) == 0 ? EMM_EXIT_OK : EMM_EXIT_FAIL;
}

/* ------------------------------------------------------------------------ */

static int trace_import(int argc, char **argv)
{
    const char *in = NULL, *out = NULL;
    int din = 0, compress = 0;
    uint64_t fixed_bytes = 0;
    opts_row rows[] = {
        {.name = "--din", .kind = OPT_FLAG, .dst = &din, .required = true,
         .help = "the input format (the only one)"},
        {.name = "-o", .alias = "--output", .metavar = "TRACE", .kind = OPT_TEXT, .dst = &out,
         .required = true,
         .help = "the trace to write (required)"},
        {.name = "--bytes", .metavar = "N", .kind = OPT_U64, .dst = &fixed_bytes, .min = 1,
         .max = EMM_TRACE_MAX_ACCESS_BYTES,
         .help = "bytes per access, 1 to 4096 (default: to the end of the aligned 4-byte word "
                 "holding the address, the word Dinero IV would access)"},
        {.name = "--compress", .kind = OPT_FLAG, .dst = &compress,
         .help = "zstd-compress the trace's blocks"},
        {.metavar = "FILE", .kind = OPT_TEXT, .dst = &in, .required = true},
        OPTS_END,
    };
    opts o = {"trace import", rows, import_usage};
    int rc;
    if (opts_parse(&o, argc, argv, &rc))
        return rc;

    const char *in_name = strcmp(in, "-") == 0 ? "stdin" : in;
    FILE *f = strcmp(in, "-") == 0 ? stdin : fopen(in, "r");
    struct stat sb;
    if (!f) {
        cli_error("%s: cannot open: %s", in, strerror(errno));
        return EMM_EXIT_FAIL;
    }
    if (fstat(fileno(f), &sb) == 0 && S_ISDIR(sb.st_mode)) {
        cli_error("%s: is a directory, not a din file", in_name);
        if (f != stdin)
            fclose(f);
        return EMM_EXIT_FAIL;
    }
    /* Raw memory: element = address, one byte per record, no known end. */
    const emm_trace_array raw = {EMM_ARRAY_RAW, 1, 0, 0};
    emm_error err;
    emm_trace_writer *w = NULL;
    if (emm_trace_writer_open(out, &raw, 1, NULL, compress, &w, &err) != EMM_OK) {
        if (f != stdin)
            fclose(f);
        return cli_fail(&err);
    }
    emm_din_counts counts;
    emm_status st = emm_din_import(f, in_name, (uint32_t)fixed_bytes, w, &counts, &err);
    if (f != stdin)
        fclose(f);
    if (st != EMM_OK) {
        emm_trace_writer_abort(w);
        return cli_fail(&err);
    }
    if (emm_trace_writer_close(w, &err) != EMM_OK)
        return cli_fail(&err);
    printf("%s: %" PRIu64 " accesses", out, counts.accesses);
    if (counts.skipped)
        printf(" (%" PRIu64 " instruction fetches skipped)", counts.skipped);
    printf("\n");
    return EMM_EXIT_OK;
}

/* ------------------------------------------------------------------------ */

static void synth_usage(FILE *out, const opts *o)
{
    fputs("usage: emm trace synth --mesh FILE --pattern P -o TRACE [--seed S] [--visits N]\n"
          "                       [--length L] [--corner] [--ring] [--work W] [--compress]\n"
          "\n"
          "Writes the trace of a canonical traversal over a mesh (thesis §5, Table 5.1):\n"
          "each triangle visit reads the triangle's record (vertex indices and\n"
          "neighbours, 24 bytes) and then its three vertices' coordinates (24 bytes\n"
          "each), so a trace has 4 records per visit, over the thesis' record layout\n"
          "(80-byte vertices, 28-byte triangles) and the mesh's geometry. The same\n"
          "options give the same file, byte for byte. A mesh is seen in the plane of\n"
          "its bounding box's two largest extents; one with depth (a surface in space,\n"
          "no extent zero) has its zorder, gray and hilbert orders taken in 3D, and\n"
          "its curves walk each triangle's plane, for at most the box's diagonal.\n"
          "\n",
          out);
    opts_help(out, o);
}

static int trace_synth(int argc, char **argv)
{
    const char *cmd = "trace synth";
    const char *mesh_path = NULL, *out = NULL;
    const char *patterns[EMM_PATTERN_COUNT + 1];
    emm_synth_options opt;
    uint64_t work = 0;
    int pattern = 0;
    emm_error err;

    memset(&opt, 0, sizeof opt);
    opt.seed = 1;
    for (int k = 0; k < EMM_PATTERN_COUNT; k++)
        patterns[k] = emm_pattern_name((emm_pattern)k);
    patterns[EMM_PATTERN_COUNT] = NULL;
    opts_row rows[] = {
        {.name = "--mesh", .metavar = "FILE", .kind = OPT_TEXT, .dst = &mesh_path,
         .required = true, .help = "the mesh (OFF, OBJ, PLY, STL)"},
        {.name = "--pattern", .metavar = "P", .kind = OPT_WORD, .dst = &pattern, .words = patterns,
         .required = true,
         .help = "region    breadth-first growth over edge neighbours from a seed\n"
                 "curve     straight walks across triangles from random starts\n"
                 "scanline  rows of triangles by centroid, left to right\n"
                 "zorder    triangles in Z-order (Morton) of their centroids\n"
                 "gray      triangles in Gray-code order of their centroids\n"
                 "hilbert   triangles in Hilbert order of their centroids\n"
                 "random    triangles in a uniformly random order\n"
                 "spiral    triangles by angle then radius around the centre"},
        {.name = "-o", .alias = "--output", .metavar = "TRACE", .kind = OPT_TEXT, .dst = &out,
         .required = true, .help = "the trace to write (required), whole or not at all"},
        {.name = "--seed", .metavar = "S", .kind = OPT_U64, .dst = &opt.seed, .show_default = true,
         .help = "seed of region's start, curves' starts and directions and random's order"},
        {.name = "--visits", .metavar = "N", .kind = OPT_U64, .dst = &opt.visits, .min = 1,
         .help = "stop after N triangle visits (default: every triangle once; curve: as many "
                 "visits as triangles; region --ring: 3 a triangle). Only curve and region --ring "
                 "visit a triangle more than once, so the other patterns stop at the triangle "
                 "count"},
        {.name = "--length", .metavar = "L", .kind = OPT_U64, .dst = &opt.length,
         .help = "curve: triangles per walk before a new walk starts (default 0: walk to the "
                 "boundary)"},
        {.name = "--corner", .kind = OPT_FLAG, .dst = &opt.corner_seed,
         .help = "region: start at the corner triangle (lowest x + y centroid) instead of one "
                 "drawn from the seed"},
        {.name = "--ring", .kind = OPT_FLAG, .dst = &opt.rings,
         .help = "region: grow over vertices, each vertex visiting the triangles of its one-ring "
                 "(a triangle once a corner: 3 visits a triangle; recipe region@ring), as a "
                 "program that conquers vertices does"},
        {.name = "--work", .metavar = "W", .kind = OPT_U64, .dst = &work, .max = UINT32_MAX,
         .show_default = true, .help = "work recorded before each access, charged at compute.per_work cycles a unit "
                 "(by default 0: not charged; docs/machine.md \"Compute\")"},
        {.name = "--compress", .kind = OPT_FLAG, .dst = &opt.compress,
         .help = "zstd-compress the trace's blocks"},
        OPTS_END,
    };
    opts o = {cmd, rows, synth_usage};
    int rc;
    if (opts_parse(&o, argc, argv, &rc))
        return rc;
    opt.work = (uint32_t)work;
    opt.pattern = (emm_pattern)pattern;

    emm_mesh *mesh = NULL;
    uint64_t records = 0;
    if (emm_mesh_open(mesh_path, &mesh, &err) != EMM_OK)
        return cli_fail(&err);
    emm_status st = emm_synth_trace(mesh, &opt, out, &records, &err);
    emm_mesh_free(mesh);
    if (st != EMM_OK)
        return cli_fail(&err);
    printf("wrote %s: %" PRIu64 " records (pattern %s)\n", out, records,
           emm_pattern_name(opt.pattern));
    return EMM_EXIT_OK;
}

static void trace_usage(FILE *out)
{
    fputs(trace_usage_text, out);
}

int emm_cmd_trace(int argc, char **argv)
{
    static const opts_sub subs[] = {{"info", trace_info},     {"export", trace_export},
                                    {"import", trace_import}, {"synth", trace_synth},
                                    {NULL, NULL}};
    return opts_subcommand("trace", subs, trace_usage, argc, argv);
}
