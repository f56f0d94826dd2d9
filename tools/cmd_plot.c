/* emm plot REPORT: figures of a JSON report (docs/report.md) with gnuplot,
 * after the thesis' figures: the distance profile with the nearest table
 * sample (§5, Fig. 5.5), the cycle breakdowns (§6.3, Figs. 6.1, 6.3–6.6,
 * 6.8, 6.9), the transfer-size sweep (Figs. 6.2, 6.7), and a map of the
 * DMA traffic per layout cell, which the thesis does not have. docs/plot.md
 * describes each figure.
 *
 * The whole report is read and checked before anything is written. Every
 * figure is made in a private directory inside DIR (data files, a gnuplot
 * script, the images); only when every gnuplot run has succeeded are the
 * files renamed into DIR, so a failure leaves DIR as it was. */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include "cli.h"
#include "opts.h"
#include "emm/profile.h"
#include "emm/sim.h"
#include "emm/strategy.h"
#include "error.h"
#include "infile.h"
#include "json_read.h"

static const char *const CMD = "plot";

/* More results than this (EMM_COMPARE=all, emm replay --all) are split into
 * a figure of the EMM layouts and fetch schemes and a comparison figure. */
#define PLOT_MAX_BARS 12
#define PLOT_MAX_FILES 32

static void usage(FILE *out, const opts *o)
{
    fprintf(out,
            "usage: emm plot REPORT [--out DIR] [--format png|svg|both] [--cells STRATEGY]\n"
            "                       [--gnuplot PROGRAM]\n"
            "\n"
            "Draws the figures of a JSON report (emm run --report, EMM_REPORT, emm replay\n"
            "--json) with gnuplot, as PNG and SVG files, beside the data files and gnuplot\n"
            "scripts that made them (run 'gnuplot -e \"fmt=\\\"svg\\\"\" NAME.gp' in DIR to\n"
            "redo one):\n"
            "\n"
            "  profile     the window's distance profile D_i against i (thesis Fig. 5.5) and\n"
            "              the mean distance D_i / i, with the nearest table sample's shape\n"
            "              (features 11-16) overlaid; needs a session's report\n"
            "  breakdown   cycles per strategy, stacked by bucket (Figs. 6.1, 6.4, 6.6); with\n"
            "              more than %d results, the EMM layouts x fetch schemes at the best\n"
            "              EMM strategy's cell size\n"
            "  compare     with more than %d results: direct, cache, cache@LAYOUT, the answer\n"
            "              (a session's) and the best EMM strategy (Figs. 6.3, 6.5, 6.8, 6.9)\n"
            "  transfer    total cycles against triangles per cell for each layout and fetch\n"
            "              scheme (Figs. 6.2, 6.7); needs two cell sizes of one of them\n"
            "  cells       the mesh's bounding box and each layout cell coloured by the bytes\n"
            "              DMA moved for it, for the answer or else the best EMM strategy\n"
            "\n"
            "A figure the report has no data for is skipped with a note; the others are\n"
            "still drawn. Nothing is written unless every figure drawn succeeds.\n"
            "\n",
            PLOT_MAX_BARS, PLOT_MAX_BARS);
    opts_help(out, o);
    fprintf(out,
            "\n"
            "Exit status: 0 figures written, 1 a missing or malformed report, no gnuplot, or\n"
            "a figure that could not be made, 2 bad usage.\n");
}

/* ---- the report ------------------------------------------------------------- */

typedef struct plot_result {
    const char *name;
    emm_strategy s;
    int ran;                          /* 0: the report says why it did not run */
    double total;
    double cycles[EMM_BUCKET_COUNT];
    const jr_value *cells;            /* "cells", or NULL */
} plot_result;

typedef struct plot_report {
    const char *path;
    jr_value *root;
    plot_result *r;
    size_t n, ran;
    const char *program;              /* NULL for a replay report */
    const char *chosen;               /* the session's answer (its "strategy"), or NULL */
    const jr_value *profile;          /* NULL when there is none */
} plot_report;

static emm_status bad(emm_error *err, const char *path, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static emm_status bad(emm_error *err, const char *path, const char *fmt, ...)
{
    char msg[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return emm_fail(err, EMM_ERR_FORMAT, "%s: %s", path, msg);
}

/* An array of exactly n numbers (n == 0: any length >= 1). */
static int numbers(const jr_value *v, size_t n)
{
    if (!jr_is(v, JR_ARRAY) || (n && jr_len(v) != n) || jr_len(v) == 0)
        return 0;
    for (size_t i = 0; i < jr_len(v); i++)
        if (!jr_is(jr_at(v, i), JR_NUMBER))
            return 0;
    return 1;
}

static emm_status check_cells(const plot_report *rep, size_t i, const jr_value *c,
                              emm_error *err)
{
    const jr_value *rects = jr_get(c, "rects");
    /* Boxes of the layout's dims axes: low corner, high corner (4 numbers
     * in the plane, 6 in space). */
    size_t dims = jr_len(jr_get(c, "bbox")) / 2;
    if (!jr_is(c, JR_OBJECT) || !jr_is(jr_get(c, "count"), JR_NUMBER) ||
        !(dims == 2 || dims == 3) || !numbers(jr_get(c, "bbox"), 2 * dims) ||
        !jr_is(rects, JR_ARRAY))
        return bad(err, rep->path, "results[%zu].cells: needs \"count\", \"bbox\" [x0, y0, x1, y1] "
                   "(or [x0, y0, z0, x1, y1, z1]) and \"rects\"", i);
    for (size_t k = 0; k < jr_len(rects); k++) {
        const jr_value *q = jr_at(rects, k);
        int ok = numbers(q, 2 * dims + 1) && jr_number(jr_at(q, 2 * dims)) >= 0;
        for (size_t a = 0; ok && a < dims; a++)
            ok = jr_number(jr_at(q, a)) <= jr_number(jr_at(q, dims + a));
        if (!ok)
            return bad(err, rep->path, "results[%zu].cells.rects[%zu]: not [x0, y0, x1, y1, bytes] "
                       "(or [x0, y0, z0, x1, y1, z1, bytes]) with x0 <= x1, y0 <= y1, z0 <= z1, "
                       "bytes >= 0", i, k);
    }
    return EMM_OK;
}

static emm_status check_profile(const plot_report *rep, const jr_value *p, emm_error *err)
{
    const jr_value *pts = jr_get(p, "points"), *near = jr_get(p, "nearest"), *m = jr_get(p, "m_end");
    if (!jr_is(p, JR_OBJECT) || !jr_is(pts, JR_ARRAY) || !jr_is(jr_get(p, "accesses"), JR_NUMBER))
        return bad(err, rep->path, "profile: needs \"accesses\" and \"points\"");
    if (!jr_is(m, JR_NUMBER) && !jr_is(m, JR_NULL))
        return bad(err, rep->path, "profile.m_end: not a number");
    for (size_t k = 0; k < jr_len(pts); k++)
        if (!numbers(jr_at(pts, k), 2) || jr_number(jr_at(jr_at(pts, k), 0)) < 0)
            return bad(err, rep->path, "profile.points[%zu]: not [i, D_i] with i >= 0", k);
    if (jr_get(p, "features") && !numbers(jr_get(p, "features"), EMM_FEATURES))
        return bad(err, rep->path, "profile.features: not %d numbers", EMM_FEATURES);
    if (near && (!jr_is(jr_get(near, "name"), JR_STRING) ||
                 !jr_is(jr_get(near, "distance"), JR_NUMBER) ||
                 !numbers(jr_get(near, "features"), EMM_FEATURES)))
        return bad(err, rep->path, "profile.nearest: needs \"name\", \"distance\" and %d "
                   "\"features\"", EMM_FEATURES);
    return EMM_OK;
}

/* What a file that is not a report is, from its first bytes, so that the
 * user hears "a trace" rather than a JSON syntax error: EMM_OK (err left as
 * it was) when it may be JSON (it starts with '{' or '['). */
static emm_status sniff_input(const char *path, emm_error *err)
{
    unsigned char head[8] = {0};
    FILE *f = emm_infile_fopen(path, "report", NULL);
    if (!f)
        return EMM_OK; /* the parser says why it cannot be read (a FIFO is not waited for) */
    size_t n = fread(head, 1, sizeof head, f);
    int c = 0;
    rewind(f);
    while ((c = fgetc(f)) != EOF && (c == ' ' || c == '\t' || c == '\n' || c == '\r'))
        ;
    fclose(f);
    if (n == sizeof head && memcmp(head, "EMMTRACE", 8) == 0)
        return bad(err, path, "an emm trace, not a report: simulate it first (emm replay %s "
                   "--all --json REPORT.json), then emm plot REPORT.json", path);
    if (c != '{' && c != '[')
        return bad(err, path, "not a JSON report (emm run --report, emm replay --json make one)");
    return EMM_OK;
}

/* Reads the report and checks every part a figure reads, so that a bad
 * report fails before anything is drawn. */
static emm_status load_report(const char *path, plot_report *rep, emm_error *err)
{
    const jr_value *results, *v;
    emm_status st;
    memset(rep, 0, sizeof *rep);
    rep->path = path;
    /* A file that reads but does not parse may be a trace or text: say
     * which instead of a JSON syntax error. (A file that cannot be read, is
     * a directory or is too large keeps the reader's message.) */
    if ((st = jr_parse_file(path, &rep->root, err)) != EMM_OK) {
        if (st == EMM_ERR_FORMAT)
            sniff_input(path, err);
        return st;
    }
    if (jr_is(rep->root, JR_OBJECT) && jr_get(rep->root, "traceEvents"))
        return bad(err, path, "a timeline, not a report: open it in Perfetto's UI "
                   "(ui.perfetto.dev) or chrome://tracing");
    if (!jr_is(rep->root, JR_OBJECT) || !jr_is(jr_get(rep->root, "emm_report"), JR_NUMBER))
        return bad(err, path, "not an emm report (no \"emm_report\" key)");
    if (jr_number(jr_get(rep->root, "emm_report")) != 1)
        return bad(err, path, "report version %g; this emm reads version 1",
                   jr_number(jr_get(rep->root, "emm_report")));
    results = jr_get(rep->root, "results");
    if (!jr_is(results, JR_ARRAY))
        return bad(err, path, "\"results\" is missing or not an array");
    rep->n = jr_len(results);
    rep->r = calloc(rep->n ? rep->n : 1, sizeof *rep->r);
    if (!rep->r)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
    for (size_t i = 0; i < rep->n; i++) {
        const jr_value *res = jr_at(results, i), *cyc;
        plot_result *r = &rep->r[i];
        double sum = 0;
        emm_error e;
        r->name = jr_string(jr_get(res, "strategy"));
        if (!r->name)
            return bad(err, path, "results[%zu]: no \"strategy\" string", i);
        if (emm_strategy_parse(r->name, &r->s, &e) != EMM_OK)
            return bad(err, path, "results[%zu]: %s", i, e.message);
        if (jr_get(res, "error")) {
            if (!jr_is(jr_get(res, "error"), JR_STRING))
                return bad(err, path, "results[%zu].error: not a string", i);
            continue;
        }
        cyc = jr_get(res, "cycles");
        if (!jr_is(cyc, JR_OBJECT) || !jr_is(jr_get(cyc, "total"), JR_NUMBER))
            return bad(err, path, "results[%zu] (%s): no \"cycles\" with a \"total\"", i, r->name);
        r->total = jr_number(jr_get(cyc, "total"));
        for (int b = 0; b < EMM_BUCKET_COUNT; b++) {
            const char *key = emm_bucket_name((emm_bucket)b);
            v = jr_get(cyc, key);
            if (!jr_is(v, JR_NUMBER) || jr_number(v) < 0)
                return bad(err, path, "results[%zu].cycles: \"%s\" is missing or negative", i, key);
            r->cycles[b] = jr_number(v);
            sum += r->cycles[b];
        }
        if (r->total < 0 || fabs(sum - r->total) > 1e-9 * fmax(1, r->total))
            return bad(err, path, "results[%zu].cycles: the buckets add up to %.0f, not the "
                       "total %.0f", i, sum, r->total);
        if ((r->cells = jr_get(res, "cells")) && (st = check_cells(rep, i, r->cells, err)) != EMM_OK)
            return st;
        r->ran = 1;
        rep->ran++;
    }
    rep->program = jr_string(jr_get(rep->root, "program"));
    rep->chosen = jr_string(jr_get(rep->root, "strategy"));
    v = jr_get(rep->root, "profile");
    if (v && !jr_is(v, JR_NULL)) {
        if ((st = check_profile(rep, v, err)) != EMM_OK)
            return st;
        rep->profile = v;
    }
    return EMM_OK;
}

static void free_report(plot_report *rep)
{
    free(rep->r);
    jr_free(rep->root);
}

static const plot_result *find(const plot_report *rep, const char *name)
{
    emm_strategy s;
    if (!name || emm_strategy_parse(name, &s, NULL) != EMM_OK)
        return NULL;
    for (size_t i = 0; i < rep->n; i++)
        if (rep->r[i].ran && rep->r[i].s.kind == s.kind && rep->r[i].s.layout == s.layout &&
            rep->r[i].s.fetch == s.fetch && rep->r[i].s.cell == s.cell &&
            rep->r[i].s.indexed == s.indexed)
            return &rep->r[i];
    return NULL;
}

static const plot_result *best_emm(const plot_report *rep)
{
    const plot_result *best = NULL;
    for (size_t i = 0; i < rep->n; i++)
        if (rep->r[i].ran && rep->r[i].s.kind == EMM_STRATEGY_EMM &&
            (!best || rep->r[i].total < best->total))
            best = &rep->r[i];
    return best;
}

/* ---- the work directory ----------------------------------------------------- */

typedef struct plot_ctx {
    const char *out;                  /* DIR */
    char *work;                       /* DIR/.emm-plot.XXXXXX */
    const char *gnuplot;
    int png, svg;
    char *files[PLOT_MAX_FILES];      /* names made in work, moved into DIR at the end */
    size_t nfiles;
    const char *title;                /* the program's name or the report's file name */
} plot_ctx;

static char *join(const char *dir, const char *name)
{
    size_t n = strlen(dir) + strlen(name) + 2;
    char *p = malloc(n);
    if (p)
        snprintf(p, n, "%s/%s", dir, name);
    return p;
}

static int add_file(plot_ctx *c, const char *name)
{
    if (c->nfiles == PLOT_MAX_FILES || !(c->files[c->nfiles] = strdup(name)))
        return 0;
    c->nfiles++;
    return 1;
}

/* Opens a file of the work directory for writing and remembers it. */
static FILE *work_open(plot_ctx *c, const char *name, emm_error *err)
{
    char *p = join(c->work, name);
    FILE *f = p ? fopen(p, "w") : NULL;
    if (!f || !add_file(c, name)) {
        emm_fail(err, EMM_ERR_IO, "%s: cannot write %s: %s", c->out, name,
                 f ? "too many files" : strerror(errno));
        if (f)
            fclose(f);
        f = NULL;
    }
    free(p);
    return f;
}

static emm_status work_close(plot_ctx *c, FILE *f, const char *name, emm_error *err)
{
    int bad_write = ferror(f);
    if (fclose(f) != 0 || bad_write)
        return emm_fail(err, EMM_ERR_IO, "%s: cannot write %s: %s", c->out, name,
                        strerror(errno ? errno : EIO));
    return EMM_OK;
}

static void remove_work(plot_ctx *c)
{
    DIR *d;
    struct dirent *e;
    if (!c->work)
        return;
    if ((d = opendir(c->work))) {
        while ((e = readdir(d))) {
            char *p;
            if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
                continue;
            if ((p = join(c->work, e->d_name))) {
                unlink(p);
                free(p);
            }
        }
        closedir(d);
    }
    rmdir(c->work);
}

/* The first line gnuplot wrote on stderr, for the error message. */
static void first_line(const char *path, char *buf, size_t cap)
{
    FILE *f = fopen(path, "r");
    buf[0] = '\0';
    if (!f)
        return;
    while (fgets(buf, (int)cap, f)) {
        buf[strcspn(buf, "\r\n")] = '\0';
        if (buf[strspn(buf, " \t^")] != '\0')
            break;
    }
    fclose(f);
}

/* Runs gnuplot on `script` in the work directory for each format asked
 * for; each run must exit 0 and leave a non-empty image. */
static emm_status run_gnuplot(plot_ctx *c, const char *fig, emm_error *err)
{
    const char *fmts[2] = {c->png ? "png" : NULL, c->svg ? "svg" : NULL};
    char script[64], image[64], setfmt[32];
    snprintf(script, sizeof script, "%s.gp", fig);
    for (int k = 0; k < 2; k++) {
        pid_t pid;
        int status = 0;
        struct stat sb;
        char *img, *errpath;
        if (!fmts[k])
            continue;
        errpath = join(c->work, ".gnuplot.err");
        snprintf(setfmt, sizeof setfmt, "fmt='%s'", fmts[k]);
        snprintf(image, sizeof image, "%s.%s", fig, fmts[k]);
        if (!errpath)
            return emm_fail(err, EMM_ERR_NOMEM, "out of memory");
        fflush(NULL);
        pid = fork();
        if (pid < 0) {
            free(errpath);
            return emm_fail(err, EMM_ERR_IO, "gnuplot: cannot start: %s", strerror(errno));
        }
        if (pid == 0) {
            int fd = open(errpath, O_WRONLY | O_CREAT | O_TRUNC, 0600);
            int null = open("/dev/null", O_RDWR);
            if (fd >= 0)
                dup2(fd, STDERR_FILENO);
            if (null >= 0) {
                dup2(null, STDIN_FILENO);
                dup2(null, STDOUT_FILENO);
            }
            if (chdir(c->work) != 0)
                _exit(126);
            execlp(c->gnuplot, c->gnuplot, "-e", setfmt, script, (char *)NULL);
            _exit(127);
        }
        while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
            ;
        if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
            char line[300];
            first_line(errpath, line, sizeof line);
            free(errpath);
            if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
                return emm_fail(err, EMM_ERR_IO, "%s: cannot run it", c->gnuplot);
            return emm_fail(err, EMM_ERR_IO, "%s: %s failed: %s", c->gnuplot, script,
                            line[0] ? line : WIFSIGNALED(status) ? "killed by a signal"
                                                                 : "no message");
        }
        unlink(errpath);
        free(errpath);
        img = join(c->work, image);
        if (!img)
            return emm_fail(err, EMM_ERR_NOMEM, "out of memory");
        if (stat(img, &sb) != 0 || sb.st_size == 0) {
            free(img);
            return emm_fail(err, EMM_ERR_IO, "%s: %s wrote no %s", c->gnuplot, script, image);
        }
        free(img);
        if (!add_file(c, image))
            return emm_fail(err, EMM_ERR_IO, "%s: too many files", c->out);
    }
    return EMM_OK;
}

/* A double-quoted gnuplot string. */
static void gp_str(FILE *f, const char *s)
{
    fputc('"', f);
    for (; *s; s++) {
        if (*s == '\n')
            fputs("\\n", f);
        if (*s == '"' || *s == '\\')
            fputc('\\', f);
        if ((unsigned char)*s >= 0x20)
            fputc(*s, f);
    }
    fputc('"', f);
}

/* The script's first lines: the terminal for `fmt` ("png" unless set with
 * -e), white background, one font. Text is not "enhanced": strategy names
 * hold '@' and '_', which enhanced text would take for markup. */
static void gp_terminal(FILE *f, const char *fig, int w, int h)
{
    fprintf(f,
            "# emm plot: %s. Redo with: gnuplot -e \"fmt='png'\" %s.gp (or fmt='svg')\n"
            "if (!exists(\"fmt\")) fmt = 'png'\n"
            "if (fmt eq 'svg') {\n"
            "    set terminal svg size %d,%d dynamic noenhanced font 'DejaVu Sans,13' "
            "background rgb 'white'\n"
            "    set output '%s.svg'\n"
            "} else {\n"
            "    set terminal pngcairo size %d,%d noenhanced font 'DejaVu Sans,11' "
            "background rgb 'white'\n"
            "    set output '%s.png'\n"
            "}\n"
            "set encoding utf8\n",
            fig, fig, w, h, fig, w, h, fig);
}

/* ---- the figures -------------------------------------------------------------- */

/* Thesis Fig. 5.5 (i against D_i) above the mean distance m_i = D_i / i on
 * a log axis, where features 11-16 live: ⅛·log2(m at n/64 … n/2 ÷ m_end)
 * (docs/profile.md), so a sample's shape is m(n/2^j) = m_end·2^(8·f). The
 * nearest sample's shape is drawn at this window's length and level; it is
 * what the distance in feature space compares (with the other features). */
static emm_status fig_profile(plot_ctx *c, const plot_report *rep, emm_error *err)
{
    const jr_value *p = rep->profile, *pts = jr_get(p, "points");
    const jr_value *feat = jr_get(p, "features"), *near = jr_get(p, "nearest");
    double n = jr_number(jr_get(p, "accesses")), mend = jr_number(jr_get(p, "m_end"));
    int shapes = jr_is(jr_get(p, "m_end"), JR_NUMBER) && mend > 0 && feat;
    emm_status st;
    FILE *f;

    if (!(f = work_open(c, "profile.dat", err)))
        return err->status;
    fprintf(f, "# i  D_i (bounding-box diagonals)\n");
    for (size_t k = 0; k < jr_len(pts); k++)
        fprintf(f, "%.17g %.17g\n", jr_number(jr_at(jr_at(pts, k), 0)),
                jr_number(jr_at(jr_at(pts, k), 1)));
    if ((st = work_close(c, f, "profile.dat", err)) != EMM_OK)
        return st;
    if (shapes) {
        if (!(f = work_open(c, "profile-shape.dat", err)))
            return err->status;
        fprintf(f, "# i  m_i of this window  m_i of the nearest sample  (features 11-16, "
                   "scaled by m_end = %.17g)\n", mend);
        for (int j = 6; j >= 1; j--) {
            double i = floor(n / (double)(1 << j)), ms = NAN;
            double mw = mend * exp2(8 * jr_number(jr_at(feat, (size_t)(16 - j))));
            if (near)
                ms = mend * exp2(8 * jr_number(jr_at(jr_get(near, "features"), (size_t)(16 - j))));
            fprintf(f, "%.17g %.17g %.17g\n", i, mw, ms);
        }
        fprintf(f, "%.17g %.17g %.17g\n", n - 1, mend, near ? mend : NAN);
        if ((st = work_close(c, f, "profile-shape.dat", err)) != EMM_OK)
            return st;
    }
    if (!(f = work_open(c, "profile.gp", err)))
        return err->status;
    gp_terminal(f, "profile", 1000, 900);
    fprintf(f, "set multiplot layout 2,1 title ");
    {
        char t[300];
        snprintf(t, sizeof t, "Distance profile of %s: %.0f element accesses", c->title, n);
        gp_str(f, t);
    }
    fprintf(f, " font ',14'\n"
               "set datafile missing 'nan'\n"
               "set key top left box opaque\n"
               "set grid\n"
               "set format y '%%g'\n"
               "set xlabel 'element access i'\n"
               "set ylabel 'D_i = sum of |p_i - p_k| over k < i  (bounding-box diagonals)'\n"
               "set title 'D_i against i (thesis Fig. 5.5)'\n");
    fprintf(f, "plot 'profile.dat' using 1:2 with lines lw 2 lc rgb '#1f77b4' title 'this run'");
    if (shapes && near)
        fprintf(f, ", \\\n     'profile-shape.dat' using 1:($1*$3) with points pt 7 ps 1.6 "
                   "lc rgb '#d62728' title 'the nearest sample''s shape, at this window''s scale'");
    fprintf(f, "\nset logscale x 2\n"
               "set xlabel 'element access i (log scale)'\n"
               "set ylabel 'm_i = D_i / i  (bounding-box diagonals)'\n"
               "set title 'Mean distance to the earlier accesses; points: the features 11-16 "
               "(m at n/64 ... n/2, and m_end)'\n"
               "set yrange [0:*]\n"
               "set offsets graph 0, graph 0, graph 0.45, 0\n"
               "set key top left box opaque\n"
               "plot 'profile.dat' using ($1 > 0 ? $1 : NaN):($1 > 0 ? $2/$1 : NaN) with lines lw 2 "
               "lc rgb '#1f77b4' title 'this run'");
    if (shapes) {
        fprintf(f, ", \\\n     'profile-shape.dat' using 1:2 with points pt 6 ps 2 lw 2 "
                   "lc rgb '#1f77b4' title 'this run''s shape features'");
        if (near) {
            char t[300];
            snprintf(t, sizeof t, "nearest sample %s (%s), distance %.3g",
                     jr_string(jr_get(near, "name")),
                     jr_string(jr_get(near, "pattern")) ? jr_string(jr_get(near, "pattern")) : "?",
                     jr_number(jr_get(near, "distance")));
            fprintf(f, ", \\\n     'profile-shape.dat' using 1:3 with linespoints pt 7 ps 1.6 "
                       "lw 1.5 dt 2 lc rgb '#d62728' title ");
            gp_str(f, t);
        }
    }
    fprintf(f, "\nunset multiplot\n");
    if ((st = work_close(c, f, "profile.gp", err)) != EMM_OK)
        return st;
    return run_gnuplot(c, "profile", err);
}

static const char *const BUCKET_TITLE[EMM_BUCKET_COUNT] = {
    "local access", "remote access", "compute", "EMM instructions",
    "DMA issue", "DMA stall", "cache hit", "cache miss stall",
};
/* One colour per bucket in every figure (ColorBrewer Set1, colour-blind
 * tolerable), so that figures compare. */
static const char *const BUCKET_COLOR[EMM_BUCKET_COUNT] = {
    "#4daf4a", "#e41a1c", "#bdbdbd", "#984ea3", "#ff7f00", "#a65628", "#377eb8", "#f781bf",
};

typedef struct bar {
    const plot_result *r;
    char label[96];
} bar;

/* Stacked bars, one per result, bucket by bucket, in millions of cycles,
 * with the total above each bar. Buckets that are zero in every bar are
 * left out of the legend. */
static emm_status fig_bars(plot_ctx *c, const char *fig, const char *title, const bar *bars,
                           size_t n, emm_error *err)
{
    char dat[64], name[64];
    int used[EMM_BUCKET_COUNT] = {0}, first = 1;
    double top = 0;
    emm_status st;
    FILE *f;

    snprintf(dat, sizeof dat, "%s.dat", fig);
    if (!(f = work_open(c, dat, err)))
        return err->status;
    fprintf(f, "# strategy");
    for (int b = 0; b < EMM_BUCKET_COUNT; b++)
        fprintf(f, " %s", emm_bucket_name((emm_bucket)b));
    fprintf(f, " total   (millions of cycles)\n");
    for (size_t i = 0; i < n; i++) {
        fprintf(f, "\"%s\"", bars[i].label);
        for (int b = 0; b < EMM_BUCKET_COUNT; b++) {
            fprintf(f, " %.9g", bars[i].r->cycles[b] / 1e6);
            used[b] |= bars[i].r->cycles[b] > 0;
        }
        fprintf(f, " %.9g\n", bars[i].r->total / 1e6);
        top = fmax(top, bars[i].r->total / 1e6);
    }
    if ((st = work_close(c, f, dat, err)) != EMM_OK)
        return st;
    snprintf(name, sizeof name, "%s.gp", fig);
    if (!(f = work_open(c, name, err)))
        return err->status;
    gp_terminal(f, fig, n > 6 ? 1200 : 1000, 700);
    fprintf(f, "set title ");
    gp_str(f, title);
    fprintf(f, " font ',14'\n"
               "set style data histograms\n"
               "set style histogram rowstacked\n"
               "set style fill solid 0.9 border rgb '#404040'\n"
               "set boxwidth 0.65\n"
               "set key outside right top vertical title 'cycles spent on' box\n"
               "set ylabel 'cycles (×10⁶)'\n"
               "set xlabel 'strategy'\n"
               "set yrange [0:%.9g]\n"
               "set xrange [-0.6:%zu.6]\n"
               "set grid ytics\n"
               "set format y '%%g'\n",
            top * 1.1, n - 1);
    /* Side by side, up to four names fit under their bars; more are turned,
     * and the first one then reaches left of the axis: room for it. */
    if (n > 4)
        fprintf(f, "set xtics nomirror rotate by 30 right\nset lmargin %d\n",
                (int)fmax(10, 0.8 * (double)strlen(bars[0].label)));
    else
        fprintf(f, "set xtics nomirror\n");
    fprintf(f, "plot ");
    for (int b = 0; b < EMM_BUCKET_COUNT; b++) {
        if (!used[b])
            continue;
        fprintf(f, "%s'%s' using %d%s lc rgb '%s' title '%s'", first ? "" : ", \\\n     ", dat,
                b + 2, first ? ":xtic(1)" : "", BUCKET_COLOR[b], BUCKET_TITLE[b]);
        first = 0;
    }
    if (first) /* every bucket zero: still draw the axes and labels */
        fprintf(f, "'%s' using %d:xtic(1) lc rgb '#bdbdbd' title 'no cycles'", dat, 2);
    fprintf(f, ", \\\n     '%s' using 0:%d:(sprintf('%%.3g', $%d)) with labels offset 0,0.8 "
               "notitle\n",
            dat, EMM_BUCKET_COUNT + 2, EMM_BUCKET_COUNT + 2);
    if ((st = work_close(c, f, name, err)) != EMM_OK)
        return st;
    return run_gnuplot(c, fig, err);
}

static void label_bar(bar *b, const plot_result *r, const char *note)
{
    b->r = r;
    snprintf(b->label, sizeof b->label, "%s%s", r->name, note ? note : "");
}

/* Few results: one bar each, in the report's order. Many: the EMM layouts x
 * fetch schemes at the best EMM strategy's cell size (Figs. 6.1, 6.4, 6.6),
 * and a comparison (Figs. 6.3, 6.5, 6.8, 6.9). */
static emm_status fig_breakdown(plot_ctx *c, const plot_report *rep, int *made_compare,
                                emm_error *err)
{
    /* Room for every layout x fetch scheme at one cell (the sweep of a mesh
     * with depth), or for the baselines. */
    enum { NBARS = (EMM_LAYOUT_COUNT - 1) * (EMM_FETCH_COUNT - 1) + 2 };
    bar bars[PLOT_MAX_BARS > NBARS ? PLOT_MAX_BARS : NBARS];
    const plot_result *chosen = find(rep, rep->chosen), *best = best_emm(rep);
    char title[256];
    size_t n = 0;
    emm_status st;

    *made_compare = 0;
    if (rep->ran <= PLOT_MAX_BARS) {
        for (size_t i = 0; i < rep->n; i++)
            if (rep->r[i].ran)
                label_bar(&bars[n++], &rep->r[i], &rep->r[i] == chosen ? " (answer)" : NULL);
        snprintf(title, sizeof title, "%s: cycles per strategy", c->title);
        return fig_bars(c, "breakdown", title, bars, n, err);
    }
    if (best) {
        for (int l = EMM_LAYOUT_ORIGINAL + 1; l < EMM_LAYOUT_COUNT; l++)
            for (int k = EMM_FETCH_NONE + 1; k < EMM_FETCH_COUNT; k++)
                for (size_t i = 0; i < rep->n; i++) {
                    const plot_result *r = &rep->r[i];
                    if (r->ran && r->s.kind == EMM_STRATEGY_EMM && (int)r->s.layout == l &&
                        (int)r->s.fetch == k && r->s.cell == best->s.cell &&
                        r->s.indexed == best->s.indexed)
                        label_bar(&bars[n++], r, r == best ? " (best)" : NULL);
                }
        snprintf(title, sizeof title, "%s: EMM layouts and fetch schemes, %u triangles per cell",
                 c->title, best->s.cell);
        if ((st = fig_bars(c, "breakdown", title, bars, n, err)) != EMM_OK)
            return st;
    }
    n = 0;
    {
        /* direct, cache, then the cache on each layout */
        int chosen_shown = 0;
        for (int i = -1; i < EMM_LAYOUT_COUNT; i++) {
            char base[64];
            if (i < 0)
                snprintf(base, sizeof base, "direct");
            else if (i == EMM_LAYOUT_ORIGINAL)
                snprintf(base, sizeof base, "cache");
            else
                snprintf(base, sizeof base, "cache@%s", emm_layout_name((emm_layout_kind)i));
            const plot_result *r = find(rep, base);
            if (r)
                label_bar(&bars[n++], r, r == chosen ? " (answer)" : NULL);
            chosen_shown |= r && r == chosen;
        }
        if (chosen_shown)
            chosen = NULL; /* drawn in its place among the baselines */
    }
    if (chosen)
        label_bar(&bars[n++], chosen, chosen == best ? " (answer, best EMM)" : " (answer)");
    if (best && best != chosen)
        label_bar(&bars[n++], best, " (best EMM)");
    if (n == 0)
        return EMM_OK;
    snprintf(title, sizeof title, "%s: direct reads, the cache and EMM", c->title);
    *made_compare = 1;
    return fig_bars(c, "compare", title, bars, n, err);
}

/* Total cycles against the cell size, one line per layout + fetch scheme
 * (Figs. 6.2, 6.7), and the plain cache for reference. Returns EMM_OK with
 * *made 0 when no layout + fetch has two cell sizes. */
static emm_status fig_transfer(plot_ctx *c, const plot_report *rep, int *made, emm_error *err)
{
    /* A colour per layout, a point and dash type per fetch scheme (cycled
     * when the sweep has more of them than these). */
    static const char *const lcolor[] = {"#1f77b4", "#ff7f0e", "#2ca02c",
                                         "#d62728", "#9467bd", "#8c564b"};
    static const int ptype[] = {7, 5, 9, 11, 13}, dtype[] = {1, 2, 4, 5, 3};
    enum { NL = EMM_LAYOUT_COUNT - 1, NF = EMM_FETCH_COUNT - 1 };
    const plot_result *cache = find(rep, "cache");
    uint32_t cellmin = UINT32_MAX, cellmax = 0;
    int index = 0, first = 1;
    char titles[NL * NF][64];
    int lk[NL * NF][2];
    emm_status st;
    FILE *f;

    *made = 0;
    for (int l = 0; l < NL; l++)
        for (int k = 0; k < NF; k++) {
            size_t cnt = 0;
            for (size_t i = 0; i < rep->n; i++)
                cnt += rep->r[i].ran && rep->r[i].s.kind == EMM_STRATEGY_EMM &&
                       (int)rep->r[i].s.layout == l + 1 && (int)rep->r[i].s.fetch == k + 1 &&
                       !rep->r[i].s.indexed;
            *made |= cnt >= 2;
        }
    if (!*made)
        return EMM_OK;
    if (!(f = work_open(c, "transfer.dat", err)))
        return err->status;
    fprintf(f, "# triangles per cell, total cycles (millions); one block per layout+fetch\n");
    for (int l = 0; l < NL; l++)
        for (int k = 0; k < NF; k++) {
            emm_layout_kind L = (emm_layout_kind)(l + 1);
            emm_fetch_kind F = (emm_fetch_kind)(k + 1);
            uint32_t last = 0;
            int any = 0;
            for (;;) { /* ascending cell sizes */
                const plot_result *next = NULL;
                for (size_t i = 0; i < rep->n; i++) {
                    const plot_result *r = &rep->r[i];
                    if (r->ran && r->s.kind == EMM_STRATEGY_EMM && r->s.layout == L &&
                        r->s.fetch == F && !r->s.indexed && r->s.cell > last &&
                        (!next || r->s.cell < next->s.cell))
                        next = r;
                }
                if (!next)
                    break;
                if (!any)
                    fprintf(f, "# %s+%s\n", emm_layout_name(L), emm_fetch_name(F));
                fprintf(f, "%u %.9g\n", next->s.cell, next->total / 1e6);
                cellmin = next->s.cell < cellmin ? next->s.cell : cellmin;
                cellmax = next->s.cell > cellmax ? next->s.cell : cellmax;
                last = next->s.cell;
                any = 1;
            }
            if (any) {
                fprintf(f, "\n\n");
                snprintf(titles[index], sizeof titles[index], "%s+%s", emm_layout_name(L),
                         emm_fetch_name(F));
                lk[index][0] = l;
                lk[index][1] = k;
                index++;
            }
        }
    if ((st = work_close(c, f, "transfer.dat", err)) != EMM_OK)
        return st;
    if (!(f = work_open(c, "transfer.gp", err)))
        return err->status;
    gp_terminal(f, "transfer", 1000, 650);
    {
        char t[256];
        snprintf(t, sizeof t, "%s: total cycles against transfer size", c->title);
        fprintf(f, "set title ");
        gp_str(f, t);
    }
    fprintf(f, " font ',14'\n"
               "set logscale x 2\n"
               "set xrange [%g:%g]\n"
               "set xtics (",
            cellmin / 1.25, cellmax * 1.25);
    for (uint32_t x = cellmin; x <= cellmax && x > 0; x *= 2)
        fprintf(f, "%s%u", x == cellmin ? "" : ", ", x);
    fprintf(f, ")\n"
               "set xlabel 'cell size (triangles per cell, log scale)'\n"
               "set ylabel 'total cycles (×10⁶)'\n"
               "set format y '%%g'\n"
               "set yrange [0:*]\n"
               "set grid\n"
               "set key outside right top vertical box\n"
               "plot ");
    for (int i = 0; i < index; i++) {
        fprintf(f, "%s'transfer.dat' index %d using 1:2 with linespoints lw 2 ps 1.3 lc rgb '%s' "
                   "pt %d dt %d title '%s'",
                first ? "" : ", \\\n     ", i, lcolor[lk[i][0] % (int)(sizeof lcolor / sizeof *lcolor)], ptype[lk[i][1] % 5],
                dtype[lk[i][1] % 5],
                titles[i]);
        first = 0;
    }
    if (cache)
        fprintf(f, ", \\\n     %.9g with lines lw 2 dt 3 lc rgb 'black' title 'cache (original "
                   "layout)'",
                cache->total / 1e6);
    fprintf(f, "\n");
    if ((st = work_close(c, f, "transfer.gp", err)) != EMM_OK)
        return st;
    return run_gnuplot(c, "transfer", err);
}

/* The mesh's bounding box and its layout cells, each coloured by the bytes
 * DMA moved for it; cells that moved nothing are not in the report and
 * stay white. */
static emm_status fig_cells(plot_ctx *c, const plot_result *r, const char *why, emm_error *err)
{
    const jr_value *cells = r->cells, *rects = jr_get(cells, "rects"), *bb = jr_get(cells, "bbox");
    /* The first two axes of the layout's space: a layout in space is seen
     * along its third (its boxes are dims low, dims high coordinates). */
    size_t dims = jr_len(bb) / 2;
    double x0 = jr_number(jr_at(bb, 0)), y0 = jr_number(jr_at(bb, 1));
    double x1 = jr_number(jr_at(bb, dims)), y1 = jr_number(jr_at(bb, dims + 1));
    double lo[2] = {x0, y0}, hi[2] = {x1, y1}, total = 0, pad, bmin = INFINITY, bmax = 0;
    double unit;
    int logscale;
    emm_status st;
    FILE *f;

    if (!(f = work_open(c, "cells.dat", err)))
        return err->status;
    fprintf(f, "# x0 y0 x1 y1 bytes  (%s; cells DMA moved nothing for are left out)\n", r->name);
    for (size_t k = 0; k < jr_len(rects); k++) {
        const jr_value *q = jr_at(rects, k);
        double v[5] = {jr_number(jr_at(q, 0)), jr_number(jr_at(q, 1)), jr_number(jr_at(q, dims)),
                       jr_number(jr_at(q, dims + 1)), jr_number(jr_at(q, 2 * dims))};
        fprintf(f, "%.17g %.17g %.17g %.17g %.17g\n", v[0], v[1], v[2], v[3], v[4]);
        lo[0] = fmin(lo[0], v[0]);
        lo[1] = fmin(lo[1], v[1]);
        hi[0] = fmax(hi[0], v[2]);
        hi[1] = fmax(hi[1], v[3]);
        total += v[4];
        bmin = v[4] > 0 ? fmin(bmin, v[4]) : bmin;
        bmax = fmax(bmax, v[4]);
    }
    /* A dense part of a mesh can draw a hundred times the traffic of the
     * rest: then a log colour scale, or the rest is one pale colour. */
    logscale = bmax > 30 * bmin;
    unit = bmax >= 10 * 1048576.0 ? 1048576.0 : 1024.0;
    if ((st = work_close(c, f, "cells.dat", err)) != EMM_OK)
        return st;
    pad = 0.02 * fmax(hi[0] - lo[0], hi[1] - lo[1]);
    if (!(pad > 0))
        pad = 1;
    if (!(f = work_open(c, "cells.gp", err)))
        return err->status;
    gp_terminal(f, "cells", 1000, 850);
    {
        char t[300];
        snprintf(t, sizeof t, "%s: DMA traffic per cell, %s\n(%s); %zu of %.0f cells fetched, "
                 "%.3g MiB moved in all",
                 c->title, r->name, why, jr_len(rects), jr_number(jr_get(cells, "count")),
                 total / 1048576.0);
        fprintf(f, "set title ");
        gp_str(f, t);
    }
    fprintf(f, " font ',14'\n"
               "set size ratio -1\n"
               "set xrange [%.17g:%.17g]\n"
               "set yrange [%.17g:%.17g]\n"
               "set xlabel 'x (mesh units)'\n"
               "set ylabel 'y (mesh units)'\n"
               "set cblabel 'bytes moved by DMA for the cell (%s%s)'\n"
               "%s\n"
               "set palette defined (0 '#ffffcc', 0.25 '#fed976', 0.5 '#fd8d3c', 0.75 '#e31a1c', "
               "1 '#800026')\n"
               "set object 1 rect from %.17g,%.17g to %.17g,%.17g fs empty border lc rgb 'black' "
               "lw 2 front\n"
               "unset key\n"
               "plot 'cells.dat' using (($1+$3)/2):(($2+$4)/2):(($3-$1)/2):(($4-$2)/2):($5/%.0f) "
               "with boxxyerror fs solid 1.0 border lc rgb '#606060' lc palette notitle\n",
            lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad, unit > 1024 ? "MiB" : "KiB",
            logscale ? ", log scale" : "", logscale ? "set logscale cb" : "set cbrange [0:*]", x0,
            y0, x1, y1, unit);
    if ((st = work_close(c, f, "cells.gp", err)) != EMM_OK)
        return st;
    return run_gnuplot(c, "cells", err);
}

/* ---- the command ---------------------------------------------------------- */

/* gnuplot as execlp will find it: a path with a '/', or on $PATH. */
static int have_program(const char *prog)
{
    const char *path = getenv("PATH");
    if (strchr(prog, '/'))
        return access(prog, X_OK) == 0;
    if (!path)
        path = "/usr/bin:/bin";
    while (*path) {
        size_t len = strcspn(path, ":");
        char buf[4096];
        if (len > 0 && len + strlen(prog) + 2 < sizeof buf) {
            snprintf(buf, sizeof buf, "%.*s/%s", (int)len, path, prog);
            if (access(buf, X_OK) == 0)
                return 1;
        }
        path += len + (path[len] == ':');
    }
    return 0;
}

/* Makes the figures into c->work; on success moves them into DIR. */
static emm_status make_figures(plot_ctx *c, const plot_report *rep, const char *cells_name,
                               emm_error *err)
{
    const plot_result *cells_r = NULL;
    const char *why = "the answer";
    int made = 0;
    emm_status st;

    if (!rep->profile)
        printf("emm plot: no profile figure: the report has no profile (only a session's "
               "report, emm run --report, has one)\n");
    else if ((st = fig_profile(c, rep, err)) != EMM_OK)
        return st;
    if (rep->ran == 0)
        printf("emm plot: no breakdown figure: no strategy in the report ran\n");
    else if ((st = fig_breakdown(c, rep, &made, err)) != EMM_OK)
        return st;
    if ((st = fig_transfer(c, rep, &made, err)) != EMM_OK)
        return st;
    if (!made)
        printf("emm plot: no transfer figure: no layout and fetch scheme has results at two "
               "cell sizes (emm replay --all or EMM_COMPARE=all have)\n");
    if (cells_name) {
        cells_r = find(rep, cells_name);
        if (!cells_r || !cells_r->cells)
            return emm_fail(err, EMM_ERR_INVALID, "%s: --cells %s: the report has no cells for "
                            "that strategy", rep->path, cells_name);
        why = "asked for";
    } else {
        cells_r = find(rep, rep->chosen);
        if (!cells_r || !cells_r->cells) {
            const plot_result *b = NULL;
            for (size_t i = 0; i < rep->n; i++)
                if (rep->r[i].cells && (!b || rep->r[i].total < b->total))
                    b = &rep->r[i];
            cells_r = b;
            why = "the fastest EMM strategy in the report";
        }
    }
    if (!cells_r)
        printf("emm plot: no cells figure: no EMM strategy in the report has per-cell DMA "
               "bytes\n");
    else if ((st = fig_cells(c, cells_r, why, err)) != EMM_OK)
        return st;
    return EMM_OK;
}

static emm_status commit(plot_ctx *c, emm_error *err)
{
    for (size_t i = 0; i < c->nfiles; i++) {
        char *from = join(c->work, c->files[i]), *to = join(c->out, c->files[i]);
        int ok = from && to && rename(from, to) == 0;
        int e = errno;
        free(from);
        free(to);
        if (!ok)
            return emm_fail(err, EMM_ERR_IO, "%s: cannot move %s into place: %s", c->out,
                            c->files[i], strerror(e));
    }
    return EMM_OK;
}

static const char *const formats[] = {"png", "svg", "both", NULL};

int emm_cmd_plot(int argc, char **argv)
{
    const char *report = NULL, *out = NULL, *cells = NULL;
    int format = 2;
    plot_ctx c;
    plot_report rep;
    emm_error err;
    char *outbuf = NULL;
    char titlebuf[256];
    int created = 0, rc = EMM_EXIT_OK;
    emm_status st;

    memset(&c, 0, sizeof c);
    c.gnuplot = "gnuplot";
    opts_row rows[] = {
        {.name = "--out", .alias = "-o", .metavar = "DIR", .kind = OPT_TEXT, .dst = &out,
         .help = "where the figures go (default: REPORT without .json, plus -plots); created "
                 "when missing"},
        {.name = "--format", .metavar = "F", .kind = OPT_WORD, .dst = &format, .words = formats,
         .show_default = true, .help = "png, svg or both"},
        {.name = "--cells", .metavar = "STRATEGY", .kind = OPT_STRATEGY, .dst = &cells,
         .help = "the EMM strategy of the cells figure"},
        {.name = "--gnuplot", .metavar = "PROGRAM", .kind = OPT_TEXT, .dst = &c.gnuplot,
         .help = "the gnuplot to run (default: gnuplot, found on PATH)"},
        {.metavar = "REPORT", .kind = OPT_TEXT, .dst = &report, .required = true},
        OPTS_END,
    };
    opts o = {CMD, rows, usage};
    if (opts_parse(&o, argc, argv, &rc))
        return rc;
    c.png = format != 1;
    c.svg = format != 0;

    if ((st = load_report(report, &rep, &err)) != EMM_OK) {
        free_report(&rep);
        return cli_fail(&err);
    }
    if (!have_program(c.gnuplot)) {
        free_report(&rep);
        cli_error("%s: not found%s; install gnuplot (Debian: apt-get install gnuplot-nox)",
                  c.gnuplot, strchr(c.gnuplot, '/') ? "" : " on PATH");
        return EMM_EXIT_FAIL;
    }
    if (!out) {
        size_t len = strlen(report);
        if (len > 5 && strcmp(report + len - 5, ".json") == 0)
            len -= 5;
        outbuf = malloc(len + 7);
        if (!outbuf) {
            free_report(&rep);
            cli_error("out of memory");
            return EMM_EXIT_FAIL;
        }
        snprintf(outbuf, len + 7, "%.*s-plots", (int)len, report);
        out = outbuf;
    }
    c.out = out;
    {
        /* The program's name (a session), else the trace's (a replay). */
        const char *t = rep.program, *trace = jr_string(jr_get(rep.root, "trace"));
        if (!t || !*t)
            t = trace && *trace ? trace : report;
        c.title = strrchr(t, '/') ? strrchr(t, '/') + 1 : t;
        /* A session that simulated its window only says so in every title
         * (docs/report.md "coverage"). */
        const jr_value *cov = jr_get(rep.root, "coverage");
        const char *sim = cov ? jr_string(jr_get(cov, "simulated")) : NULL;
        if (sim && strcmp(sim, "window") == 0) {
            snprintf(titlebuf, sizeof titlebuf, "%s (window only)", c.title);
            c.title = titlebuf;
        }
    }
    if (mkdir(out, 0777) == 0) {
        created = 1;
    } else if (errno != EEXIST) {
        cli_error("%s: cannot create the directory: %s", out, strerror(errno));
        rc = EMM_EXIT_FAIL;
        goto done;
    }
    c.work = join(out, ".emm-plot.XXXXXX");
    if (!c.work || !mkdtemp(c.work)) {
        cli_error("%s: cannot write there: %s", out, c.work ? strerror(errno) : "out of memory");
        free(c.work);
        c.work = NULL;
        rc = EMM_EXIT_FAIL;
        goto done;
    }
    if ((st = make_figures(&c, &rep, cells, &err)) != EMM_OK || (st = commit(&c, &err)) != EMM_OK) {
        rc = cli_fail(&err);
        goto done;
    }
    for (size_t i = 0; i < c.nfiles; i++) {
        const char *dot = strrchr(c.files[i], '.');
        if (dot && (strcmp(dot, ".png") == 0 || strcmp(dot, ".svg") == 0))
            printf("wrote %s/%s\n", out, c.files[i]);
    }
done:
    remove_work(&c);
    if (rc != EMM_EXIT_OK && created)
        rmdir(out); /* only if still empty: a failure leaves nothing behind */
    for (size_t i = 0; i < c.nfiles; i++)
        free(c.files[i]);
    free(c.work);
    free(outbuf);
    free_report(&rep);
    return rc;
}
