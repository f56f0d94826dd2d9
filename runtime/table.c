/* The strategy table and the nearest-neighbour decision (thesis §5, Table
 * 5.1: a space of distance-profile samples mapped to EMM strategies; a new
 * profile takes the strategy of its nearest sample, and one far from every
 * sample is novel). The file format is described in include/emm/table.h and
 * docs/profile.md. */
#include "emm/table.h"

#include <assert.h>
#include <ctype.h>
#include <stdbool.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "datadir.h"
#include "error.h"
#include "infile.h"
#include "outfile.h"
#include "parse.h"
#include "model.h"
#include "runner.h"
#include "share.h"
#include "synth_internal.h"
#include "table_internal.h"

struct emm_table {
    emm_table_sample *s;
    char **source; /* per sample, "" or a strdup'd path */
    size_t n, cap;
    int version;   /* of the last file loaded */
};

emm_table *emm_table_new(void)
{
    return calloc(1, sizeof(emm_table));
}

void emm_table_free(emm_table *t)
{
    if (!t)
        return;
    for (size_t i = 0; i < t->n; i++)
        free(t->source[i]);
    free(t->source);
    free(t->s);
    free(t);
}

size_t emm_table_count(const emm_table *t)
{
    return t->n;
}

const emm_table_sample *emm_table_at(const emm_table *t, size_t i)
{
    return i < t->n ? &t->s[i] : NULL;
}

const char *emm_table_source(const emm_table *t, size_t i)
{
    return i < t->n ? t->source[i] : "";
}

static bool name_ok(const char *s)
{
    if (!*s || strlen(s) >= EMM_TABLE_NAME_MAX)
        return false;
    for (; *s; s++)
        if (!isalnum((unsigned char)*s) && !strchr("-_.@+", *s))
            return false;
    return true;
}

/* "-", or a fingerprint: 16 lowercase hex digits (emm_table_machine_id). */
static bool machine_ok(const char *s)
{
    if (!*s || strcmp(s, "-") == 0)
        return true;
    if (strlen(s) != 16)
        return false;
    for (; *s; s++)
        if (!isdigit((unsigned char)*s) && !(*s >= 'a' && *s <= 'f'))
            return false;
    return true;
}

void emm_table_machine_id(const emm_machine *m, char out[17])
{
    uint64_t h = 0xcbf29ce484222325ull; /* FNV-1a over "key=value\n" of every key */
    char buf[256];
    for (size_t i = 0; i < emm_machine_key_count(); i++) {
        const emm_machine_key *k = emm_machine_key_at(i);
        int w = snprintf(buf, sizeof buf, "%s=", k->name);
        if (w < 0 || (size_t)w >= sizeof buf)
            continue;
        emm_machine_format(m, k->name, buf + w, sizeof buf - (size_t)w);
        for (const char *p = buf; *p; p++)
            h = (h ^ (unsigned char)*p) * 0x100000001b3ull;
        h = (h ^ '\n') * 0x100000001b3ull;
    }
    snprintf(out, 17, "%016llx", (unsigned long long)h);
}

static ptrdiff_t find(const emm_table *t, const char *name)
{
    for (size_t i = 0; i < t->n; i++)
        if (strcmp(t->s[i].name, name) == 0)
            return (ptrdiff_t)i;
    return -1;
}

static emm_status push(emm_table *t, const emm_table_sample *s, const char *source,
                       emm_error *err)
{
    if (t->n == t->cap) {
        size_t cap = t->cap ? 2 * t->cap : 32;
        emm_table_sample *ns = realloc(t->s, cap * sizeof *ns);
        if (!ns)
            return emm_fail(err, EMM_ERR_NOMEM, "strategy table: out of memory");
        t->s = ns;
        char **nsrc = realloc(t->source, cap * sizeof *nsrc);
        if (!nsrc)
            return emm_fail(err, EMM_ERR_NOMEM, "strategy table: out of memory");
        t->source = nsrc;
        t->cap = cap;
    }
    char *src = strdup(source ? source : "");
    if (!src)
        return emm_fail(err, EMM_ERR_NOMEM, "strategy table: out of memory");
    t->s[t->n] = *s;
    t->source[t->n] = src;
    t->n++;
    return EMM_OK;
}

emm_status emm_table_add(emm_table *t, const emm_table_sample *s, emm_error *err)
{
    if (!name_ok(s->name))
        return emm_fail(err, EMM_ERR_INVALID,
                        "sample name '%s': use 1 to %d letters, digits and - _ . @ +", s->name,
                        EMM_TABLE_NAME_MAX - 1);
    if (!name_ok(s->pattern))
        return emm_fail(err, EMM_ERR_INVALID,
                        "pattern class '%s': use 1 to %d letters, digits and - _ . @ +",
                        s->pattern, EMM_TABLE_NAME_MAX - 1);
    for (int k = 0; k < EMM_FEATURES; k++)
        if (!isfinite(s->f[k]))
            return emm_fail(err, EMM_ERR_INVALID, "sample '%s': feature %d is not finite",
                            s->name, k + 1);
    if (!machine_ok(s->machine))
        return emm_fail(err, EMM_ERR_INVALID, "sample '%s': machine '%s' is not '-' or a "
                        "fingerprint", s->name, s->machine);
    if (s->ncosts > EMM_TABLE_COSTS)
        return emm_fail(err, EMM_ERR_INVALID, "sample '%s': more than %d costs", s->name,
                        EMM_TABLE_COSTS);
    for (uint32_t c = 0; c < s->ncosts; c++)
        if (!(s->cost[c] >= 1) || !isfinite(s->cost[c]))
            return emm_fail(err, EMM_ERR_INVALID, "sample '%s': cost %u is not a ratio of at "
                            "least 1", s->name, c + 1);
    emm_synth_options so;
    if (s->synth[0] && strcmp(s->synth, "-") != 0) {
        if (!name_ok(s->synth))
            return emm_fail(err, EMM_ERR_INVALID, "synth recipe '%s': bad characters", s->synth);
        emm_status st = emm_synth_recipe_parse(s->synth, &so, err);
        if (st != EMM_OK)
            return st;
    }
    if (find(t, s->name) >= 0)
        return emm_fail(err, EMM_ERR_INVALID, "sample '%s' is already in the table", s->name);
    return push(t, s, "", err);
}

/* Splits a line into whitespace-separated fields after dropping a comment;
 * returns the count (at most cap; one more means "too many"). */
static int split(char *line, char **field, int cap)
{
    char *hash = strchr(line, '#');
    if (hash)
        *hash = '\0';
    int n = 0;
    for (char *p = line; *p;) {
        while (*p && isspace((unsigned char)*p))
            p++;
        if (!*p)
            break;
        if (n == cap)
            return cap + 1;
        field[n++] = p;
        while (*p && !isspace((unsigned char)*p))
            p++;
        if (*p)
            *p++ = '\0';
    }
    return n;
}

#define EMM_TABLE_COSTS_TEXT "24"
_Static_assert(EMM_TABLE_COSTS == 24, "EMM_TABLE_COSTS_TEXT is EMM_TABLE_COSTS");

/* A table of a few thousand samples is a few hundred KiB. */
#define EMM_TABLE_FILE_MAX ((size_t)64 << 20)

emm_status emm_table_load(emm_table *t, const char *path, emm_error *err)
{
    char *text;
    size_t len;
    emm_status st = emm_infile_read(path, "strategy table", EMM_TABLE_FILE_MAX, &text, &len, err);
    if (st != EMM_OK)
        return st;
    size_t first = t->n;
    const char *end = text + len;
    char *next = text;
    long lineno = 0;
    bool header = false;
    enum { MAXF = EMM_FEATURES + 5 + EMM_TABLE_COSTS };
    int version = EMM_TABLE_VERSION, fixed = 5; /* fields before the features */
    char *field[MAXF];
    while (st == EMM_OK && next < end) {
        char *line = next;
        char *nl = memchr(line, '\n', (size_t)(end - line));
        size_t n = nl ? (size_t)(nl - line) : (size_t)(end - line);
        line[n] = '\0'; /* the newline, or the NUL after the text */
        next = line + n + 1;
        lineno++;
        if (strlen(line) != n) {
            st = emm_fail(err, EMM_ERR_FORMAT, "%s:%ld: malformed line (NUL byte)", path, lineno);
            break;
        }
        int nf = split(line, field, MAXF);
        if (nf == 0)
            continue;
        if (!header) {
            uint64_t ver, nfeat;
            if (nf != 3 || strcmp(field[0], "emm-table") != 0 ||
                strncmp(field[2], "features=", 9) != 0) {
                st = emm_fail(err, EMM_ERR_FORMAT,
                              "%s:%ld: expected the header 'emm-table %d features=%d'", path,
                              lineno, EMM_TABLE_VERSION, EMM_FEATURES);
            } else if (!emm_parse_u64(field[1], &ver) || ver < 2 || ver > EMM_TABLE_VERSION) {
                st = emm_fail(err, EMM_ERR_FORMAT,
                              "%s:%ld: table version '%s' is not supported (this build reads "
                              "versions 2 to %d)",
                              path, lineno, field[1], EMM_TABLE_VERSION);
            } else if (!emm_parse_u64(field[2] + 9, &nfeat) || nfeat != EMM_FEATURES) {
                st = emm_fail(err, EMM_ERR_FORMAT,
                              "%s:%ld: the table has '%s' but this build computes %d features",
                              path, lineno, field[2] + 9, EMM_FEATURES);
            }
            if (st == EMM_OK) {
                version = t->version = (int)ver;
                fixed = version >= 4 ? 5 : version >= 3 ? 4 : 3;
            }
            header = true;
            continue;
        }
        int most = EMM_FEATURES + fixed + (fixed == 5 ? EMM_TABLE_COSTS : 0);
        if (nf < EMM_FEATURES + fixed || nf > most) {
            st = emm_fail(err, EMM_ERR_FORMAT,
                          "%s:%ld: expected name, pattern, %s%sstrategy and %d features%s, found "
                          "%s%d fields",
                          path, lineno, fixed >= 4 ? "synth, " : "",
                          fixed == 5 ? "machine, " : "", EMM_FEATURES,
                          fixed == 5 ? " (then at most " EMM_TABLE_COSTS_TEXT " costs)" : "",
                          nf > most ? "more than " : "", nf > most ? most : nf);
            break;
        }
        emm_table_sample s;
        memset(&s, 0, sizeof s);
        if (!name_ok(field[0])) {
            st = emm_fail(err, EMM_ERR_FORMAT,
                          "%s:%ld: bad sample name '%s' (1 to %d letters, digits, - _ . @ +)",
                          path, lineno, field[0], EMM_TABLE_NAME_MAX - 1);
            break;
        }
        if (!name_ok(field[1])) {
            st = emm_fail(err, EMM_ERR_FORMAT,
                          "%s:%ld: bad pattern class '%s' (1 to %d letters, digits, - _ . @ +)",
                          path, lineno, field[1], EMM_TABLE_NAME_MAX - 1);
            break;
        }
        snprintf(s.name, sizeof s.name, "%s", field[0]);
        snprintf(s.pattern, sizeof s.pattern, "%s", field[1]);
        snprintf(s.synth, sizeof s.synth, "%s", fixed >= 4 ? field[2] : "-");
        snprintf(s.machine, sizeof s.machine, "%s", fixed == 5 ? field[3] : "-");
        if (!machine_ok(s.machine)) {
            st = emm_fail(err, EMM_ERR_FORMAT,
                          "%s:%ld: machine '%s' is not '-' or 16 hex digits (a fingerprint)",
                          path, lineno, s.machine);
            break;
        }
        emm_error serr;
        emm_synth_options so;
        if (strcmp(s.synth, "-") != 0 &&
            (!name_ok(s.synth) || emm_synth_recipe_parse(s.synth, &so, &serr) != EMM_OK)) {
            st = emm_fail(err, EMM_ERR_FORMAT, "%s:%ld: synth '%s': %s", path, lineno, s.synth,
                          name_ok(s.synth) ? serr.message : "bad characters");
            break;
        }
        if (emm_strategy_parse(field[fixed - 1], &s.strategy, &serr) != EMM_OK) {
            st = emm_fail(err, EMM_ERR_FORMAT, "%s:%ld: %s", path, lineno, serr.message);
            break;
        }
        for (int k = 0; k < EMM_FEATURES && st == EMM_OK; k++)
            if (!emm_parse_double(field[fixed + k], &s.f[k]))
                st = emm_fail(err, EMM_ERR_FORMAT, "%s:%ld: feature %d: '%s' is not a number",
                              path, lineno, k + 1, field[fixed + k]);
        for (int k = EMM_FEATURES + fixed; k < nf && st == EMM_OK; k++) {
            char *eq = strrchr(field[k], '=');
            uint32_t c = s.ncosts;
            if (eq)
                *eq = '\0';
            if (!eq || emm_strategy_parse(field[k], &s.cost_strategy[c], &serr) != EMM_OK ||
                !emm_parse_double(eq + 1, &s.cost[c]) || !(s.cost[c] >= 1) ||
                !isfinite(s.cost[c]))
                st = emm_fail(err, EMM_ERR_FORMAT,
                              "%s:%ld: cost %d: '%s%s%s' is not STRATEGY=RATIO (a ratio of at "
                              "least 1)",
                              path, lineno, c + 1, field[k], eq ? "=" : "", eq ? eq + 1 : "");
            s.ncosts++;
        }
        if (st != EMM_OK)
            break;
        ptrdiff_t dup = find(t, s.name);
        if (dup >= 0) {
            const char *where = t->source[dup];
            st = emm_fail(err, EMM_ERR_FORMAT, "%s:%ld: sample '%s' is already defined%s%s",
                          path, lineno, s.name, where[0] ? " in " : "", where);
            break;
        }
        char src[600];
        snprintf(src, sizeof src, "%s:%ld", path, lineno);
        st = push(t, &s, src, err);
    }
    if (st == EMM_OK && !header)
        st = emm_fail(err, EMM_ERR_FORMAT, "%s: empty file: no 'emm-table %d features=%d' header",
                      path, EMM_TABLE_VERSION, EMM_FEATURES);
    free(text);
    if (st != EMM_OK) {
        for (size_t i = first; i < t->n; i++)
            free(t->source[i]);
        t->n = first;
    }
    return st;
}

static void write_sample(FILE *fp, const emm_table_sample *s)
{
    char strat[96];
    emm_strategy_format(&s->strategy, strat, sizeof strat);
    fprintf(fp, "%-24s %-9s %-13s %-16s %-24s", s->name, s->pattern,
            s->synth[0] ? s->synth : "-", s->machine[0] ? s->machine : "-", strat);
    for (int k = 0; k < EMM_FEATURES; k++)
        fprintf(fp, " %.9g", s->f[k]);
    for (uint32_t c = 0; c < s->ncosts && c < EMM_TABLE_COSTS; c++) {
        emm_strategy_format(&s->cost_strategy[c], strat, sizeof strat);
        fprintf(fp, " %s=%.6g", strat, s->cost[c]);
    }
    fputc('\n', fp);
}

static void write_header(FILE *fp, const char *comment)
{
    fprintf(fp, "# emm strategy table: distance-profile samples and their strategies.\n"
                "# See docs/profile.md for the format and the meaning of the features.\n"
                "emm-table %d features=%d\n",
            EMM_TABLE_VERSION, EMM_FEATURES);
    if (comment) {
        const char *p = comment;
        while (*p) {
            const char *nl = strchr(p, '\n');
            size_t len = nl ? (size_t)(nl - p) : strlen(p);
            fprintf(fp, "# %.*s\n", (int)len, p);
            p += len + (nl ? 1 : 0);
        }
    }
    fprintf(fp, "# name                   pattern   synth         machine          strategy"
                "                 features 1..%d, then costs (STRATEGY=RATIO)\n",
            EMM_FEATURES);
}

/* Writes the whole table to a temporary file beside path, renamed into place. */
static emm_status write_whole(const emm_table *t, const char *path, const char *comment,
                              const emm_table_sample *extra, emm_error *err)
{
    emm_outfile o;
    emm_status st = emm_outfile_open(&o, path, "the table", err);
    if (st != EMM_OK)
        return st;
    write_header(o.f, comment);
    for (size_t i = 0; i < t->n; i++)
        write_sample(o.f, &t->s[i]);
    if (extra)
        write_sample(o.f, extra);
    return emm_outfile_commit(&o, "the table", err);
}

emm_status emm_table_write(const emm_table *t, const char *path, const char *comment,
                           emm_error *err)
{
    return write_whole(t, path, comment, NULL, err);
}

/* Copies the file as it is (comments and all) and adds one sample line,
 * through a temporary file renamed into place. */
static emm_status append_line(const char *path, const emm_table_sample *s, emm_error *err)
{
    FILE *in = emm_infile_fopen(path, "strategy table", err);
    if (!in)
        return err ? err->status : EMM_ERR_IO;
    emm_outfile o;
    emm_status st = emm_outfile_open(&o, path, "the table", err);
    if (st != EMM_OK) {
        fclose(in);
        return st;
    }
    char buf[8192];
    size_t got;
    int tail = '\n';
    while ((got = fread(buf, 1, sizeof buf, in)) > 0) {
        fwrite(buf, 1, got, o.f);
        tail = buf[got - 1];
    }
    if (tail != '\n')
        fputc('\n', o.f);
    write_sample(o.f, s);
    if (ferror(in)) {
        st = emm_fail(err, EMM_ERR_IO, "%s: cannot rewrite: cannot read it", path);
        emm_outfile_abort(&o);
    } else {
        st = emm_outfile_commit(&o, "the table", err);
    }
    fclose(in);
    return st;
}

emm_status emm_table_append(const char *path, const emm_table_sample *s, emm_error *err)
{
    emm_table *t = emm_table_new();
    if (!t)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
    emm_status st = EMM_OK;
    bool exists = access(path, F_OK) == 0;
    if (exists)
        st = emm_table_load(t, path, err);
    if (st == EMM_OK) {
        /* Checks the name and the values as the parser would. */
        emm_table *probe = emm_table_new();
        st = probe ? emm_table_add(probe, s, err) : emm_fail(err, EMM_ERR_NOMEM, "out of memory");
        emm_table_free(probe);
    }
    if (st == EMM_OK && find(t, s->name) >= 0)
        st = emm_fail(err, EMM_ERR_INVALID, "%s: sample '%s' is already in this table", path,
                      s->name);
    /* An older version's file is rewritten whole in this version. */
    if (st == EMM_OK)
        st = exists && t->version == EMM_TABLE_VERSION ? append_line(path, s, err)
                                                         : write_whole(t, path, NULL, s, err);
    emm_table_free(t);
    return st;
}

int emm_table_default_path(char *out, size_t cap)
{
    return emm_data_file("table.txt", out, cap, NULL, 0);
}

emm_status emm_table_load_standard(emm_table *t, const char *user, emm_error *err)
{
    char def[4096], tried[2048];
    emm_status st;
    if (emm_data_file("table.txt", def, sizeof def, tried, sizeof tried)) {
        st = emm_table_load(t, def, err);
        if (st != EMM_OK)
            return st;
    }
    if (user) {
        st = emm_table_load(t, user, err);
        if (st != EMM_OK)
            return st;
    }
    if (t->n == 0) {
        if (user)
            return emm_fail(err, EMM_ERR_IO,
                            "no strategy table with samples: the shipped table is not at %s, "
                            "and %s has none",
                            tried, user);
        return emm_fail(err, EMM_ERR_IO,
                        "no strategy table found: the shipped table (share/emm/table.txt of "
                        "an install, data/table.txt of a source tree, where `make table` makes "
                        "it) is not at %s, and no user table was given (--table FILE or "
                        "EMM_TABLE; `emm table add` makes one)",
                        tried);
    }
    return EMM_OK;
}

double emm_feature_distance(const double a[EMM_FEATURES], const double b[EMM_FEATURES])
{
    double d = 0;
    for (int k = 0; k < EMM_FEATURES; k++) {
        double e = a[k] - b[k];
        d += e * e;
    }
    return sqrt(d);
}

emm_status emm_table_decide(const emm_table *t, const double f[EMM_FEATURES], double threshold,
                            emm_decision *out, emm_error *err)
{
    if (t->n == 0)
        return emm_fail(err, EMM_ERR_INVALID, "strategy table: no samples to compare with");
    if (threshold <= 0)
        threshold = EMM_NOVELTY_THRESHOLD;
    size_t best = 0;
    double bd = INFINITY;
    for (size_t i = 0; i < t->n; i++) {
        double d = emm_feature_distance(f, t->s[i].f);
        if (d < bd) {
            bd = d;
            best = i;
        }
    }
    memset(out, 0, sizeof *out);
    snprintf(out->pattern, sizeof out->pattern, "%s", t->s[best].pattern);
    snprintf(out->nearest, sizeof out->nearest, "%s", t->s[best].name);
    snprintf(out->synth, sizeof out->synth, "%s", t->s[best].synth[0] ? t->s[best].synth : "-");
    out->strategy = t->s[best].strategy;
    out->distance = bd;
    out->novel = out->distance > threshold;
    return EMM_OK;
}

/* ---- simulating the candidates ------------------------------------------- */

emm_status emm_sweep_records(const emm_machine *m, const emm_trace_info *info,
                             const emm_trace_record *recs, size_t n, const emm_threads *threads,
                             emm_sweep **out, emm_error *err)
{
    return sweep_records_shared(m, info, recs, n, threads, NULL, false, out, err);
}

/* A bounded sweep's pieces: its records in about this many, none shorter
 * than SWEEP_PIECE_MIN (a shorter run is swept whole). */
#define SWEEP_PIECES 16
#define SWEEP_PIECE_MIN 4096
/* A strategy stops once its cycles exceed the second fewest of the whole
 * run by more than one part in this many (table_internal.h). */
#define SWEEP_MARGIN 1000

/* The runner's models by their sweep index: the two fewest cycles so far
 * among the offered strategies (*a, *b: SIZE_MAX when fewer ran). */
static void two_fewest(emm_runner *run, const size_t *model_of, size_t count, size_t *a,
                       size_t *b)
{
    uint64_t ta = UINT64_MAX, tb = UINT64_MAX;
    *a = *b = SIZE_MAX;
    for (size_t i = 0; i < count; i++) {
        emm_model *model = model_of[i] == SIZE_MAX ? NULL : emm_runner_model(run, model_of[i]);
        if (!model)
            continue;
        uint64_t t = emm_model_total(model);
        if (t < ta) {
            *b = *a, tb = ta;
            *a = i, ta = t;
        } else if (t < tb) {
            *b = i, tb = t;
        }
    }
}

/* recs through the sweep's models (every strategy offered), bounded: all
 * run the first piece; the two fewest cycles then, and the reference cache,
 * run to the end; every other strategy runs until its cycles pass the
 * larger of those two's by more than 1/SWEEP_MARGIN, and is marked in
 * partial (its result a lower bound). */
static emm_status run_bounded(emm_runner *run, const emm_strategy *s, const size_t *model_of,
                              size_t count, const emm_trace_record *recs, size_t n,
                              uint8_t *partial, emm_error *err)
{
    size_t piece = n / SWEEP_PIECES < SWEEP_PIECE_MIN ? SWEEP_PIECE_MIN : n / SWEEP_PIECES;
    size_t *lead = calloc(count, sizeof *lead), *rest = calloc(count, sizeof *rest);
    size_t *rest_of = calloc(count, sizeof *rest_of), *ran = calloc(count, sizeof *ran);
    size_t nlead = 0, nrest = 0, a, b;
    if (!lead || !rest || !rest_of || !ran) {
        free(lead), free(rest), free(rest_of), free(ran);
        return emm_fail(err, EMM_ERR_NOMEM, "strategy sweep: out of memory");
    }
    emm_runner_run(run, recs, piece);
    two_fewest(run, model_of, count, &a, &b);
    for (size_t i = 0; i < count; i++) {
        if (model_of[i] == SIZE_MAX || !emm_runner_model(run, model_of[i]))
            continue;
        bool reference = s[i].kind == EMM_STRATEGY_CACHE && s[i].layout == EMM_LAYOUT_ORIGINAL;
        if (i == a || i == b || reference)
            lead[nlead++] = model_of[i];
        else
            rest_of[nrest] = i, rest[nrest++] = model_of[i];
    }
    emm_runner_run_bounded(run, lead, nlead, recs + piece, n - piece, piece, UINT64_MAX, ran);
    uint64_t bound = 0;
    for (size_t i = 0; i < count; i++)
        if (i == a || i == b) {
            uint64_t t = emm_model_total(emm_runner_model(run, model_of[i]));
            bound = t > bound ? t : bound;
        }
    bound += bound / SWEEP_MARGIN;
    emm_runner_run_bounded(run, rest, nrest, recs + piece, n - piece, piece, bound, ran);
    for (size_t j = 0; j < nrest; j++)
        partial[rest_of[j]] = ran[j] < n - piece;
    free(lead), free(rest), free(rest_of), free(ran);
    return EMM_OK;
}

/* The sweep; partial NULL: every strategy over every record; else a
 * bounded sweep of the offered strategies (run_bounded), *partial set to
 * its flags. only (NULL: all): the sweep's strategies to simulate, a flag
 * each; the others stay ran = 0. */
static emm_status sweep_run(const emm_machine *m, const emm_trace_info *info,
                            const emm_trace_record *recs, size_t n, const emm_threads *threads,
                            emm_model_share *share, bool offered_only, const uint8_t *only,
                            uint8_t **partial, emm_sweep **out, emm_error *err)
{
    *out = NULL;
    /* A mesh with depth brings the layouts in space into the sweep. */
    int depth = emm_geometry_has_depth(info->geometry.xyz, info->geometry.nv, info->geometry.tri,
                                       info->geometry.nt);
    size_t count = emm_strategy_sweep_for(depth, NULL, 0);
    emm_sweep *sw = calloc(1, sizeof *sw);
    emm_strategy *s = calloc(count, sizeof *s), *ran = calloc(count, sizeof *ran);
    emm_error *skipped = calloc(count, sizeof *skipped);
    size_t *model_of = calloc(count, sizeof *model_of), nrun = 0;
    uint8_t *flags = partial ? calloc(count, 1) : NULL;
    emm_runner *run = NULL;
    emm_status st = EMM_OK;
    if (sw) {
        sw->result = calloc(count, sizeof *sw->result);
        sw->ran = calloc(count, sizeof *sw->ran);
    }
    if (!sw || !s || !ran || !skipped || !model_of || !sw->result || !sw->ran ||
        (partial && !flags)) {
        st = emm_fail(err, EMM_ERR_NOMEM, "strategy sweep: out of memory");
        goto out;
    }
    emm_strategy_sweep_for(depth, s, count);
    sw->count = count;
    /* Strategies the machine does not offer are not simulated when only the
     * offered ones are asked for (they stay ran = 0). */
    for (size_t i = 0; i < count; i++) {
        model_of[i] = SIZE_MAX;
        if ((!offered_only || emm_machine_offers(m, &s[i])) && (!only || only[i])) {
            model_of[i] = nrun;
            ran[nrun++] = s[i];
        }
    }
    if ((st = emm_runner_new_shared(threads, share, &run, err)) != EMM_OK ||
        (st = emm_runner_add(run, m, ran, nrun, info, skipped, err)) != EMM_OK)
        goto out;
    if (flags && n >= 2 * SWEEP_PIECE_MIN)
        st = run_bounded(run, s, model_of, count, recs, n, flags, err);
    else
        emm_runner_run(run, recs, n);
    if (st != EMM_OK)
        goto out;
    uint64_t best = UINT64_MAX;
    for (size_t i = 0; i < count; i++) {
        emm_model *model = model_of[i] == SIZE_MAX ? NULL : emm_runner_model(run, model_of[i]);
        sw->result[i].strategy = s[i];
        if (s[i].kind == EMM_STRATEGY_CACHE && s[i].layout == EMM_LAYOUT_ORIGINAL)
            sw->cache = i;
        if (!model)
            continue;
        emm_model_result(model, &sw->result[i]);
        sw->ran[i] = 1;
        sw->simulated++;
        if (emm_machine_offers(m, &s[i]) && sw->result[i].total < best) {
            best = sw->result[i].total;
            sw->best = i;
        }
    }
    if (sw->simulated == 0)
        st = emm_fail(err, EMM_ERR_UNSUPPORTED,
                      "strategy sweep: no strategy of the sweep can be simulated on this trace");
out:
    emm_runner_free(run);
    free(s);
    free(ran);
    free(model_of);
    free(skipped);
    if (st == EMM_OK) {
        *out = sw;
        if (partial)
            *partial = flags;
    } else {
        emm_sweep_free(sw);
        free(flags);
    }
    return st;
}

emm_status sweep_records_shared(const emm_machine *m, const emm_trace_info *info,
                                const emm_trace_record *recs, size_t n,
                                const emm_threads *threads, emm_model_share *share,
                                bool offered_only, emm_sweep **out, emm_error *err)
{
    return sweep_run(m, info, recs, n, threads, share, offered_only, NULL, NULL, out, err);
}

emm_status sweep_records_bounded(const emm_machine *m, const emm_trace_info *info,
                                 const emm_trace_record *recs, size_t n,
                                 const emm_threads *threads, emm_model_share *share,
                                 emm_sweep **out, uint8_t **partial, emm_error *err)
{
    *partial = NULL;
    return sweep_run(m, info, recs, n, threads, share, true, NULL, partial, out, err);
}

void emm_sweep_free(emm_sweep *sw)
{
    if (!sw)
        return;
    free(sw->result);
    free(sw->ran);
    free(sw);
}

/* ---- the decision ---------------------------------------------------------- */

int emm_decide_is_tie(uint64_t a, uint64_t b)
{
    uint64_t lo = a < b ? a : b, hi = a < b ? b : a;
    return lo > 0 && (double)(hi - lo) <= EMM_DECIDE_TIE_MARGIN * (double)lo;
}

const char *emm_decided_name(emm_decided_how how)
{
    switch (how) {
    case EMM_DECIDED_TABLE:
        return "table";
    case EMM_DECIDED_CHECKED:
        return "checked";
    case EMM_DECIDED_WINDOW:
        return "window";
    default:
        return "none";
    }
}

/* The first array of a kind in the trace, or -1. */
static int array_of(const emm_trace_info *info, emm_array_kind kind)
{
    for (uint32_t i = 0; i < info->narrays; i++)
        if (info->arrays[i].kind == kind)
            return (int)i;
    return -1;
}

/* Where a synthetic visit lands in the program's own arrays: the thesis'
 * fields when the records are as large as the thesis' structs, else the
 * front of each record. */
static bool program_arrays(const emm_trace_info *info, struct synth_arrays *a)
{
    int tri = array_of(info, EMM_ARRAY_TRIANGLES), vert = array_of(info, EMM_ARRAY_VERTICES);
    if (tri < 0 || vert < 0)
        return false;
    uint32_t trs = info->arrays[tri].record_size, vrs = info->arrays[vert].record_size;
    a->tri = (uint32_t)tri;
    a->tri_offset = trs >= 28 ? 4 : 0;
    a->tri_bytes = trs >= 28 ? 24 : (trs < 12 ? trs : 12);
    a->vert = (uint32_t)vert;
    a->vert_offset = vrs >= 32 ? 8 : 0;
    a->vert_bytes = vrs >= 32 ? 24 : (vrs < 24 ? vrs : 24);
    return a->tri_bytes > 0 && a->vert_bytes > 0;
}

static void set_runner_up(emm_window_decision *out, const emm_result *r, double margin)
{
    out->has_runner_up = r != NULL;
    if (!r)
        return;
    out->runner_up = r->strategy;
    out->runner_cycles = r->total;
    out->runner_margin = margin;
    out->tie = margin <= EMM_DECIDE_TIE_MARGIN;
}

/* The features of the profile of recs[0..n) (trace `info`): a window of
 * `window` element accesses less a leading index-order sweep, as the
 * session profiles its own. *np gets the element accesses profiled and
 * *skip (may be NULL) the records of the leading sweep. EMM_ERR_RANGE when
 * fewer than EMM_PROFILE_MIN element accesses were found. */
static emm_status records_features(const emm_trace_info *info, const emm_trace_record *recs,
                                   size_t n, uint64_t window, const char *name,
                                   const emm_threads *threads, double f[EMM_FEATURES],
                                   size_t *np, size_t *skip, emm_error *err)
{
    emm_profiler *p;
    emm_status st = emm_profiler_new(info, window ? window : 1, EMM_PROFILE_PLANE, name, &p, err);
    if (st != EMM_OK)
        return st;
    if ((st = emm_profiler_add(p, recs, n, err)) != EMM_OK) {
        emm_profiler_free(p);
        return st;
    }
    const double *xy = emm_profiler_positions(p, np);
    size_t swept;
    emm_profiler_swept(p, &swept);
    if (skip)
        *skip = swept;
    if (*np < EMM_PROFILE_MIN) {
        emm_profiler_free(p);
        return emm_fail(err, EMM_ERR_RANGE,
                        "%s: only %zu element accesses; a profile needs at least %u", name, *np,
                        EMM_PROFILE_MIN);
    }
    double *D = malloc(*np * sizeof *D);
    if (!D) {
        emm_profiler_free(p);
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the profile", name);
    }
    st = emm_profile_compute(xy, *np, emm_profiler_dims(p), D, NULL, threads, err);
    emm_profiler_free(p);
    if (st == EMM_OK)
        st = emm_profile_features(D, *np, name, f, err);
    free(D);
    return st;
}

/* The options of the canonical traversal of recipe over this mesh: a
 * region grows from where the program's did (its first triangle).
 * EMM_ERR_INVALID for a recipe that names no traversal. */
static emm_status synth_options(const emm_mesh *mesh, const struct synth_arrays *arrays,
                                const char *recipe, const emm_trace_record *recs, size_t n,
                                uint64_t visits, emm_synth_options *so, emm_error *err)
{
    *so = (emm_synth_options){.seed = EMM_DECIDE_SYNTH_SEED};
    if (emm_synth_recipe_parse(recipe, so, err) != EMM_OK)
        return EMM_ERR_INVALID;
    for (size_t i = 0; i < n && !so->has_start; i++)
        if (recs[i].array == arrays->tri && recs[i].element < emm_mesh_triangle_count(mesh)) {
            so->has_start = 1;
            so->start = (uint32_t)recs[i].element;
        }
    /* At most the whole traversal: a triangle a visit, or one a corner for
     * a growth over vertices' one-rings. */
    uint64_t whole = (so->rings ? 3 : 1) * (uint64_t)emm_mesh_triangle_count(mesh);
    so->visits = visits < whole ? visits : whole;
    return EMM_OK;
}

/* ---- what a session's decisions share --------------------------------------- */

/* A canonical traversal's profile or sweep depends on the traversal (its
 * options), the mesh, the arrays and, for a sweep, the machine — not on
 * the window, once its start is known — so a session's decisions (the
 * window's, then each phase's) compute each once. */
enum cached_kind { CACHED_FEATURES, CACHED_SWEEP, CACHED_SOME };

typedef struct cached {
    enum cached_kind kind;
    emm_synth_options so;    /* start cleared where the pattern has none (synth_order) */
    uint64_t window;         /* features: the profile's window */
    const emm_machine *m;    /* sweep: the machine */
    struct synth_arrays arrays;
    emm_status st;           /* never EMM_ERR_NOMEM: that is not kept */
    emm_error e;             /* why, when st != EMM_OK */
    double g[EMM_FEATURES];  /* features */
    emm_sweep *sw;           /* sweep, when st == EMM_OK */
    uint8_t *partial;        /* its bounded results (sweep_records_bounded), or NULL */
} cached;

struct decide_cache {
    const emm_trace_info *info; /* the trace the entries are of (the first asked about) */
    emm_mesh *mesh;             /* its geometry as a mesh, or NULL (not built yet) */
    emm_status mesh_st;         /* EMM_OK until building it failed */
    cached *e;
    size_t n, cap;
};

decide_cache *decide_cache_new(void)
{
    return calloc(1, sizeof(decide_cache));
}

void decide_cache_free(decide_cache *c)
{
    if (!c)
        return;
    for (size_t i = 0; i < c->n; i++) {
        emm_sweep_free(c->e[i].sw);
        free(c->e[i].partial);
    }
    free(c->e);
    emm_mesh_free(c->mesh);
    free(c);
}

/* The cache for decisions over `info`, or NULL (none, or one of another
 * trace: then nothing is shared). */
static decide_cache *cache_for(decide_cache *c, const emm_trace_info *info)
{
    if (c && !c->info)
        c->info = info;
    return c && c->info == info ? c : NULL;
}

static bool same_options(const emm_synth_options *a, const emm_synth_options *b)
{
    return a->pattern == b->pattern && a->seed == b->seed && a->visits == b->visits &&
           a->length == b->length && a->corner_seed == b->corner_seed && a->rings == b->rings &&
           a->work == b->work &&
           a->has_start == b->has_start && a->start == b->start;
}

static bool same_arrays(const struct synth_arrays *a, const struct synth_arrays *b)
{
    return a->tri == b->tri && a->tri_offset == b->tri_offset && a->tri_bytes == b->tri_bytes &&
           a->vert == b->vert && a->vert_offset == b->vert_offset && a->vert_bytes == b->vert_bytes;
}

/* The entry of this kind and key, or NULL. */
static cached *cache_find(decide_cache *c, enum cached_kind kind, const emm_synth_options *so,
                          uint64_t window, const emm_machine *m, const struct synth_arrays *arrays)
{
    emm_synth_options key = *so;
    if (key.pattern != EMM_PATTERN_REGION)
        key.has_start = 0, key.start = 0;
    for (size_t i = 0; c && i < c->n; i++) {
        cached *x = &c->e[i];
        if (x->kind == kind && same_options(&x->so, &key) && x->window == window && x->m == m &&
            same_arrays(&x->arrays, arrays))
            return x;
    }
    return NULL;
}

/* A new entry (its result to be filled in), or NULL when there is no cache
 * or no memory for one (the result is then not kept: only slower). */
static cached *cache_add(decide_cache *c, enum cached_kind kind, const emm_synth_options *so,
                         uint64_t window, const emm_machine *m, const struct synth_arrays *arrays)
{
    if (!c)
        return NULL;
    if (c->n == c->cap) {
        size_t cap = c->cap ? 2 * c->cap : 8;
        cached *e = realloc(c->e, cap * sizeof *e);
        if (!e)
            return NULL;
        c->e = e;
        c->cap = cap;
    }
    cached *x = &c->e[c->n++];
    memset(x, 0, sizeof *x);
    x->kind = kind;
    x->so = *so;
    if (x->so.pattern != EMM_PATTERN_REGION)
        x->so.has_start = 0, x->so.start = 0;
    x->window = window;
    x->m = m;
    x->arrays = *arrays;
    return x;
}

/* The features of the traversal `so` over the mesh, profiled with a window
 * of `window` element accesses (records_features). */
static emm_status synth_features(decide_cache *c, const emm_mesh *mesh,
                                 const emm_trace_info *info, const struct synth_arrays *arrays,
                                 const emm_synth_options *so, uint64_t window, const char *name,
                                 const emm_threads *threads, double g[EMM_FEATURES],
                                 emm_error *err)
{
    cached *x = cache_find(c, CACHED_FEATURES, so, window, NULL, arrays);
    if (x) {
        memcpy(g, x->g, sizeof x->g);
        if (x->st != EMM_OK && err)
            *err = x->e;
        return x->st;
    }
    emm_trace_record *syn = NULL;
    size_t ns = 0, np;
    emm_status st = emm_synth_records(mesh, so, arrays, name, &syn, &ns, err);
    if (st == EMM_OK)
        st = records_features(info, syn, ns, window, name, threads, g, &np, NULL, err);
    free(syn);
    if (st != EMM_ERR_NOMEM && (x = cache_add(c, CACHED_FEATURES, so, window, NULL, arrays))) {
        x->st = st;
        if (st == EMM_OK)
            memcpy(x->g, g, sizeof x->g);
        else if (err)
            x->e = *err;
    }
    return st;
}

/* The sweep of the traversal `so` over the mesh on machine m, bounded
 * (sweep_records_bounded; exact: every strategy in full): *S and *partial
 * (NULL: all exact), owned by the cache when there is one (*owned false),
 * or *S NULL with *e saying why it could not be swept. An exact sweep
 * replaces a bounded one in the cache. Returns the synthesis's errors. */
static emm_status synth_sweep(decide_cache *c, const emm_machine *m, const emm_trace_info *info,
                              const emm_mesh *mesh, const struct synth_arrays *arrays,
                              const emm_synth_options *so, const char *name,
                              const emm_threads *threads, emm_model_share *share, bool exact,
                              emm_sweep **S, uint8_t **partial, bool *owned, emm_error *e,
                              emm_error *err)
{
    *S = NULL;
    *partial = NULL;
    *owned = false;
    cached *x = cache_find(c, CACHED_SWEEP, so, 0, m, arrays);
    if (x && !(exact && x->partial)) {
        if (x->st == EMM_OK) {
            *S = x->sw;
            *partial = x->partial;
        } else {
            *e = x->e;
        }
        return EMM_OK;
    }
    emm_trace_record *syn = NULL;
    size_t ns = 0;
    emm_status st = emm_synth_records(mesh, so, arrays, name, &syn, &ns, err);
    if (st != EMM_OK)
        return st;
    emm_status sst = exact ? sweep_records_shared(m, info, syn, ns, threads, share, true, S, e)
                           : sweep_records_bounded(m, info, syn, ns, threads, share, S, partial, e);
    free(syn);
    if (sst != EMM_ERR_NOMEM && (x || (x = cache_add(c, CACHED_SWEEP, so, 0, m, arrays)))) {
        emm_sweep_free(x->sw);
        free(x->partial);
        x->st = sst;
        x->sw = *S;
        x->partial = *partial;
        if (sst != EMM_OK)
            x->e = *e;
        return EMM_OK;
    }
    *owned = *S != NULL;
    return EMM_OK;
}

/* The trace's geometry as a mesh: *mesh, owned by the cache when there is
 * one (*owned false); NULL when it is not a mesh. */
static void program_mesh(decide_cache *c, const emm_trace_info *info, const char *name,
                         emm_mesh **mesh, bool *owned)
{
    *owned = false;
    if (c && (c->mesh || c->mesh_st != EMM_OK)) {
        *mesh = c->mesh;
        return;
    }
    *mesh = NULL;
    emm_error e;
    emm_status st = emm_mesh_from_arrays(info->geometry.xyz, info->geometry.nv, info->geometry.tri,
                                         info->geometry.nt, name, mesh, &e);
    if (st != EMM_OK)
        *mesh = NULL;
    if (c && st != EMM_ERR_NOMEM) {
        c->mesh = *mesh;
        c->mesh_st = st;
    } else {
        *owned = *mesh != NULL;
    }
}

/* The recipe a sample is checked by: its own, or its class's canonical
 * traversal for a sample from a program (its label was made on another
 * machine and mesh). */
static const char *sample_recipe(const emm_table_sample *t)
{
    return t->synth[0] && strcmp(t->synth, "-") != 0 ? t->synth : t->pattern;
}

/* The decision's class becomes sample b's (its nearest sample of that
 * class): the check runs its traversal. */
static void reclassify(emm_window_decision *out, const emm_table_sample *b,
                       const double f[EMM_FEATURES])
{
    snprintf(out->table.pattern, sizeof out->table.pattern, "%s", b->pattern);
    snprintf(out->table.nearest, sizeof out->table.nearest, "%s", b->name);
    snprintf(out->table.synth, sizeof out->table.synth, "%s", b->synth[0] ? b->synth : "-");
    out->table.strategy = b->strategy;
    out->table.distance = emm_feature_distance(f, b->f);
    out->strategy = b->strategy;
    out->reclassified = 1;
}

/* The feature distance from the window (features f, `accesses` element
 * accesses) to the traversal of `recipe` made on this mesh for as many
 * element accesses (shared through the cache): *d when EMM_OK; another
 * status when the traversal cannot be made (*e says why: EMM_ERR_NOMEM is
 * out of memory). */
static emm_status made_distance(decide_cache *cache, const emm_mesh *mesh,
                                const emm_trace_info *info, const struct synth_arrays *arrays,
                                const char *recipe, const emm_trace_record *recs, size_t n,
                                const double f[EMM_FEATURES], size_t accesses, const char *name,
                                const emm_threads *threads, double *d, emm_error *e)
{
    emm_synth_options so;
    double g[EMM_FEATURES];
    emm_status st = synth_options(mesh, arrays, recipe, recs, n, accesses, &so, e);
    if (st == EMM_OK)
        st = synth_features(cache, mesh, info, arrays, &so, accesses, name, threads, g, e);
    if (st == EMM_OK)
        *d = emm_feature_distance(f, g);
    return st;
}

/* The nearest sample of each class (pattern) among the samples within
 * `within` of f — only those without costs when `canonical`, none of class
 * `skip` (may be NULL) — into cand, in the table's order of the classes'
 * first such sample. Returns how many. */
static size_t class_nearest(const emm_table *t, const double f[EMM_FEATURES], double within,
                            bool canonical, const char *skip, size_t *cand)
{
    size_t nc = 0;
    for (size_t i = 0; i < t->n; i++) {
        const emm_table_sample *x = &t->s[i];
        double d = emm_feature_distance(f, x->f);
        if (d > within || (canonical && x->ncosts > 0) || (skip && strcmp(x->pattern, skip) == 0))
            continue;
        size_t k = 0;
        while (k < nc && strcmp(t->s[cand[k]].pattern, x->pattern) != 0)
            k++;
        if (k == nc)
            cand[nc++] = i;
        else if (d < emm_feature_distance(f, t->s[cand[k]].f))
            cand[k] = i;
    }
    return nc;
}

/* The pattern's class checked on this mesh (docs/profile.md "The
 * decision"): a window may lie near samples of several classes (a scan
 * line is a long straight curve at some scales), and the samples were made
 * on other meshes. Each class whose nearest sample lies within
 * EMM_DECIDE_CLASS_MARGIN of the nearest distance is synthesised over this
 * mesh for as many element accesses as the window, and profiled; the class
 * whose traversal profiles nearest the window's own is taken, with its
 * nearest sample. */
static emm_status pick_class(const emm_table *t, const emm_trace_info *info, const emm_mesh *mesh,
                             const struct synth_arrays *arrays, const emm_trace_record *recs,
                             size_t n, const double f[EMM_FEATURES], size_t accesses,
                             const char *name, const emm_threads *threads, decide_cache *cache,
                             emm_window_decision *out, emm_error *err)
{
    /* The nearest sample of every class that has one within the margin,
     * however many: the classes are sized here, not capped
     * (docs/profile.md "The decision" has what checking them all changed). */
    size_t *cand = malloc((t->n ? t->n : 1) * sizeof *cand);
    if (!cand)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the class check", name);
    size_t nc = class_nearest(t, f, out->table.distance * EMM_DECIDE_CLASS_MARGIN, false, NULL,
                              cand);
    emm_status st = EMM_OK;
    size_t best = SIZE_MAX;
    double bd = INFINITY, mine = INFINITY;
    if (nc < 2)
        goto done;
    if (!(out->classes = malloc(nc * sizeof *out->classes))) {
        st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the class check", name);
        goto done;
    }
    for (size_t k = 0; k < nc; k++) {
        const emm_table_sample *smp = &t->s[cand[k]];
        double d = -1;
        emm_error e;
        emm_status sst = made_distance(cache, mesh, info, arrays, sample_recipe(smp), recs, n, f,
                                       accesses, name, threads, &d, &e);
        if (sst == EMM_ERR_NOMEM) {
            st = emm_fail(err, sst, "%s", e.message);
            goto done;
        }
        emm_decide_class *c = &out->classes[out->nclasses++];
        c->distance = emm_feature_distance(f, smp->f);
        c->synth_distance = sst == EMM_OK ? d : -1;
        snprintf(c->pattern, sizeof c->pattern, "%s", smp->pattern);
        if (sst == EMM_OK && strcmp(smp->pattern, out->table.pattern) == 0)
            mine = d;
        if (sst == EMM_OK && d < bd) {
            bd = d;
            best = cand[k];
        }
    }
    /* Another class only when its traversal is clearly nearer the window
     * than the nearest sample's class's own on this mesh. */
    if (best != SIZE_MAX && !(bd < EMM_DECIDE_CLASS_SWITCH * mine))
        best = SIZE_MAX;
    if (best != SIZE_MAX && strcmp(t->s[best].pattern, out->table.pattern) != 0)
        reclassify(out, &t->s[best], f);
done:
    free(cand);
    return st;
}

/* The traversal the nearest sample's pattern is made by (its recipe, or
 * the pattern's name), which the pattern check runs. */
static const char *check_recipe(const emm_window_decision *out)
{
    return strcmp(out->table.synth, "-") != 0 ? out->table.synth : out->table.pattern;
}

/* Whether the check has a traversal to run: the recipe parses. */
static bool names_traversal(const emm_window_decision *out)
{
    emm_synth_options so = {0};
    emm_error e;
    return emm_synth_recipe_parse(check_recipe(out), &so, &e) == EMM_OK;
}

/* The feature distance from the window to the check's traversal made on
 * this mesh for as many element accesses (what pick_class measures, and
 * shares through the cache): *d, left alone when the traversal cannot be
 * made. Errors are out of memory only. */
static emm_status check_distance_of(const emm_mesh *mesh, const emm_trace_info *info,
                                    const struct synth_arrays *arrays,
                                    const emm_trace_record *recs, size_t n,
                                    const double f[EMM_FEATURES], size_t accesses,
                                    const char *name, const emm_threads *threads,
                                    decide_cache *cache, const emm_window_decision *out,
                                    double *d, emm_error *err)
{
    emm_error e;
    emm_status st = made_distance(cache, mesh, info, arrays, check_recipe(out), recs, n, f,
                                  accesses, name, threads, d, &e);
    return st == EMM_ERR_NOMEM ? emm_fail(err, st, "%s", e.message) : EMM_OK;
}

/* The window lies near a canonical sample, but the checked class's
 * traversal made on this mesh does not (decide): another canonical class
 * (its nearest sample within EMM_DECIDE_NEAR_CLASS_REACH times the nearest
 * canonical sample's distance) whose traversal, made on this mesh, lies
 * within EMM_DECIDE_CANONICAL_NEAR of the window is the window's pattern
 * after all, and the check runs it (the nearest such; its nearest sample
 * becomes the decision's). *d gets its distance, left alone when none is
 * that near. Errors are out of memory only. */
static emm_status near_class(const emm_table *t, const emm_mesh *mesh, const emm_trace_info *info,
                             const struct synth_arrays *arrays, const emm_trace_record *recs,
                             size_t n, const double f[EMM_FEATURES], size_t accesses,
                             const char *name, const emm_threads *threads, decide_cache *cache,
                             emm_window_decision *out, double *d, emm_error *err)
{
    /* The nearest canonical sample (no costs, a recipe) of each other class. */
    size_t *cand = malloc((t->n ? t->n : 1) * sizeof *cand);
    if (!cand)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the class check", name);
    double nearest = INFINITY;
    for (size_t i = 0; i < t->n; i++)
        if (t->s[i].ncosts == 0 && emm_feature_distance(f, t->s[i].f) < nearest)
            nearest = emm_feature_distance(f, t->s[i].f);
    size_t nc = class_nearest(t, f, EMM_DECIDE_NEAR_CLASS_REACH * nearest, true,
                              out->table.pattern, cand);
    size_t best = SIZE_MAX;
    double bd = EMM_DECIDE_CANONICAL_NEAR;
    emm_status st = EMM_OK;
    for (size_t k = 0; k < nc && st == EMM_OK; k++) {
        double dk;
        emm_error e;
        emm_status sst = made_distance(cache, mesh, info, arrays, sample_recipe(&t->s[cand[k]]),
                                       recs, n, f, accesses, name, threads, &dk, &e);
        if (sst == EMM_ERR_NOMEM)
            st = emm_fail(err, sst, "%s", e.message);
        else if (sst == EMM_OK && dk <= bd) {
            bd = dk;
            best = cand[k];
        }
    }
    if (st == EMM_OK && best != SIZE_MAX) {
        reclassify(out, &t->s[best], f);
        *d = bd;
    }
    free(cand);
    return st;
}

/* The leading sweep lead[0..nlead), which the run pays too: its cycles
 * under each of the window's count strategies into cyc (its first
 * EMM_DECIDE_LEAD_SAMPLE records swept cold, scaled to its length;
 * INFINITY where a strategy could not run it), and into *rest the rest of
 * the run, priced at the window's best cycles wb scaled from the window's
 * `accesses` to EMM_DECIDE_REST_PER_TRIANGLE element accesses a triangle.
 * Returns 1 when priced, 0 when the sweep could not be made, -1 out of
 * memory (err set). */
static int lead_cycles(const emm_machine *m, const emm_trace_info *info,
                       const emm_trace_record *lead, size_t nlead, size_t accesses,
                       const emm_threads *threads, emm_model_share *share, size_t count,
                       double wb, double *cyc, double *rest, emm_error *err)
{
    emm_sweep *L = NULL;
    emm_error e;
    size_t nl = nlead < EMM_DECIDE_LEAD_SAMPLE ? nlead : EMM_DECIDE_LEAD_SAMPLE;
    if (sweep_records_shared(m, info, lead, nl, threads, share, true, &L, &e) != EMM_OK) {
        if (e.status != EMM_ERR_NOMEM)
            return 0;
        emm_fail(err, e.status, "%s", e.message);
        return -1;
    }
    int priced = L->count == count;
    if (priced) {
        *rest = wb * EMM_DECIDE_REST_PER_TRIANGLE * (double)info->geometry.nt / (double)accesses;
        for (size_t i = 0; i < count; i++)
            cyc[i] = L->ran[i] ? (double)L->result[i].total * ((double)nlead / (double)nl)
                               : INFINITY;
    }
    emm_sweep_free(L);
    return priced;
}

/* The neighbours' scores val[0..count), least vmin, become cycles with
 * the leading sweep (lead_cycles): each strategy's sweep cycles plus its
 * score over vmin times the rest of the run. A strategy the sweep could
 * not simulate is no candidate. *priced: nlead when it was priced, 0 when
 * the sweep could not be made (the scores stand). Errors are out of
 * memory only. */
static emm_status price_lead(const emm_machine *m, const emm_trace_info *info,
                             const emm_trace_record *lead, size_t nlead, size_t accesses,
                             const emm_threads *threads, emm_model_share *share, size_t count,
                             double wb, double vmin, double *val, size_t *priced,
                             emm_error *err)
{
    *priced = 0;
    double *cyc = malloc((count ? count : 1) * sizeof *cyc), rest = 0;
    if (!cyc)
        return emm_fail(err, EMM_ERR_NOMEM, "out of memory");
    int r = lead_cycles(m, info, lead, nlead, accesses, threads, share, count, wb, cyc, &rest,
                        err);
    if (r > 0) {
        for (size_t i = 0; i < count; i++)
            val[i] = isfinite(val[i]) ? cyc[i] + val[i] / vmin * rest : INFINITY;
        *priced = nlead;
    }
    free(cyc);
    return r < 0 ? EMM_ERR_NOMEM : EMM_OK;
}

/* The pattern check's score of strategy i: S/S_best, W breaking ties; with
 * a leading sweep (lp not NULL), the sweep's own cycles under i plus that
 * score times the rest of the run (lead_price). */
static double checked_score(const emm_sweep *S, const emm_sweep *W, size_t i,
                            const struct lead_price *lp)
{
    double v = (double)S->result[i].total / (double)S->result[S->best].total +
               1e-6 * ((double)W->result[i].total / (double)W->result[W->best].total);
    return lp ? lp->cycles[i] + v * lp->rest : v;
}

/* The pattern check's ranking (check_pattern): the candidates (ran in both
 * sweeps, offered), and the least and second least checked_score. */
struct ranking {
    size_t pick, second, both;
    double score, score2;
};

static void rank_checked(const emm_machine *m, const emm_sweep *S, const emm_sweep *W,
                         const struct lead_price *lp, struct ranking *r)
{
    r->pick = r->second = SIZE_MAX;
    r->both = 0;
    r->score = r->score2 = INFINITY;
    for (size_t i = 0; i < S->count; i++) {
        if (!S->ran[i] || !W->ran[i] || !emm_machine_offers(m, &S->result[i].strategy))
            continue;
        r->both++;
        double v = checked_score(S, W, i, lp);
        if (v < r->score) {
            r->score2 = r->score;
            r->second = r->pick;
            r->score = v;
            r->pick = i;
        } else if (v < r->score2) {
            r->score2 = v;
            r->second = i;
        }
    }
}

int check_bounds_hold(const emm_machine *m, const emm_sweep *S, const uint8_t *partial,
                      const emm_sweep *W, const struct lead_price *lp, size_t pick, size_t second,
                      double score2)
{
    if (!partial)
        return 1;
    if ((pick != SIZE_MAX && partial[pick]) || (second != SIZE_MAX && partial[second]) ||
        partial[S->best] || partial[S->cache])
        return 0;
    for (size_t i = 0; i < S->count; i++) {
        if (!partial[i] || !S->ran[i] || !W->ran[i] ||
            !emm_machine_offers(m, &S->result[i].strategy))
            continue;
        /* S_i is a lower bound: so is the score made of it. */
        double v = checked_score(S, W, i, lp);
        if (!(v > score2))
            return 0;
    }
    return 1;
}

/* The long run of the traversal `recipe` over the mesh (synth_sweep's) for
 * the sweep's strategies flagged in want (count flags) only: *S has their
 * results (ran set; another strategy may have run too). The cache keeps
 * what was simulated, and a later decision over the same trace (a phase's)
 * simulates only what it lacks. *S is the cache's, or the caller's to free
 * when *owned; NULL when the traversal cannot be made here (the records
 * name no start for it) or nothing could be simulated. *visits_out gets
 * its length, EMM_DECIDE_LONG_VISITS or the mesh's triangles. Errors are
 * out of memory only. */
static emm_status long_run_some(decide_cache *c, const emm_machine *m, const emm_trace_info *info,
                                const emm_mesh *mesh, const struct synth_arrays *arrays,
                                const char *recipe, const emm_trace_record *recs, size_t n,
                                const uint8_t *want, size_t count, const char *name,
                                const emm_threads *threads, emm_model_share *share,
                                emm_sweep **S, bool *owned, uint64_t *visits_out, emm_error *err)
{
    *S = NULL;
    *owned = false;
    emm_synth_options so;
    emm_error e;
    emm_status st = synth_options(mesh, arrays, recipe, recs, n, EMM_DECIDE_LONG_VISITS, &so, &e);
    if (st == EMM_ERR_INVALID)
        return EMM_OK;
    if (st != EMM_OK)
        return emm_fail(err, st, "%s", e.message);
    *visits_out = so.visits;
    cached *x = cache_find(c, CACHED_SOME, &so, 0, m, arrays);
    bool kept = x && x->sw && x->sw->count == count; /* what an earlier decision simulated */
    uint8_t *lack = calloc(count ? count : 1, 1);
    if (!lack)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", name);
    size_t nlack = 0;
    for (size_t i = 0; i < count; i++)
        if (want[i] && !(kept && x->sw->ran[i]))
            lack[i] = 1, nlack++;
    if (nlack == 0) {
        free(lack);
        *S = kept ? x->sw : NULL;
        return EMM_OK;
    }
    emm_trace_record *syn = NULL;
    size_t ns = 0;
    emm_sweep *got = NULL;
    st = emm_synth_records(mesh, &so, arrays, name, &syn, &ns, err);
    if (st == EMM_OK) {
        emm_status sst = sweep_run(m, info, syn, ns, threads, share, true, lack, NULL, &got, &e);
        if (sst == EMM_ERR_NOMEM)
            st = emm_fail(err, sst, "%s", e.message);
    }
    free(syn);
    free(lack);
    if (st != EMM_OK || !got || got->count != count) {
        emm_sweep_free(got);
        return st;
    }
    if (kept) {
        for (size_t i = 0; i < count; i++)
            if (got->ran[i]) {
                x->sw->result[i] = got->result[i];
                x->sw->ran[i] = 1;
            }
        emm_sweep_free(got);
        *S = x->sw;
    } else if (x || (x = cache_add(c, CACHED_SOME, &so, 0, m, arrays))) {
        emm_sweep_free(x->sw);
        x->st = EMM_OK;
        x->sw = got;
        *S = got;
    } else {
        *S = got;
        *owned = true;
    }
    return EMM_OK;
}

/* The table's pattern, checked on this mesh and this window (docs/profile.md
 * "The decision"): the nearest sample's canonical traversal (its recipe,
 * or its class's for a sample from a program) is synthesised over the
 * program's own mesh and arrays and swept (S: the long run the pattern
 * predicts on this mesh and machine), the window is swept too (W: what the
 * program did, cold, in its first accesses), and the strategy with the
 * least S/S_best is taken, W breaking ties (measured: weighing W in,
 * as (S/S_best)·(W/W_best), doubled the regret on traces not in the table:
 * a window is too short to see cells reused) — unless, on a machine with a
 * cache, the long run says it loses to the cache and it is not at least
 * 1/EMM_DECIDE_CACHE_MARGIN times better than the cache over both. When
 * the window follows a leading sweep (lead[0..nlead)), the run pays it too:
 * the score becomes cycles (checked_score with lead_cycles' price).
 * S is swept bounded (sweep_records_bounded); when a strategy it stopped
 * early could have ranked first or second, S is swept again in full, so
 * the outcome is the full sweep's.
 * Returns EMM_OK leaving *out alone when the recipe names no traversal;
 * errors are out of memory only. */
static emm_status check_pattern(const emm_machine *m, const emm_trace_info *info,
                                const emm_mesh *mesh, const struct synth_arrays *arrays,
                                const emm_trace_record *recs, size_t n, size_t accesses,
                                const emm_trace_record *lead, size_t nlead, const char *name,
                                const emm_threads *threads, emm_model_share *share,
                                decide_cache *cache, uint64_t visits, emm_window_decision *out,
                                emm_error *err)
{
    const char *recipe = check_recipe(out);
    if (visits == 0 || visits > EMM_DECIDE_SYNTH_VISITS)
        visits = EMM_DECIDE_SYNTH_VISITS;
    emm_synth_options so;
    emm_status st = synth_options(mesh, arrays, recipe, recs, n, visits, &so, err);
    if (st == EMM_ERR_INVALID)
        return EMM_OK;
    visits = so.visits;
    emm_sweep *S = NULL, *W = NULL;
    uint8_t *partial = NULL;
    bool own_S = false;
    emm_error e;
    struct ranking r;
    /* The leading sweep, when the window follows one, is the run's too. */
    double *lcyc = NULL;
    struct lead_price lp = {0}, *lpp = NULL;
    size_t priced = 0;
    for (int exact = 0; exact < 2; exact++) {
        if (own_S) {
            emm_sweep_free(S);
            free(partial);
        }
        st = synth_sweep(cache, m, info, mesh, arrays, &so, name, threads, share, exact, &S,
                         &partial, &own_S, &e, err);
        if (st == EMM_ERR_INVALID) {
            st = EMM_OK;
            goto done;
        }
        if (st != EMM_OK)
            goto done;
        if (!S || (!W && sweep_records_shared(m, info, recs, n, threads, share, true, &W, &e) !=
                             EMM_OK)) {
            st = e.status == EMM_ERR_NOMEM ? emm_fail(err, e.status, "%s", e.message) : EMM_OK;
            goto done;
        }
        if (lead && nlead > 0 && accesses > 0 && !lcyc) {
            if (!(lcyc = malloc(W->count * sizeof *lcyc))) {
                st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", name);
                goto done;
            }
            int pr = lead_cycles(m, info, lead, nlead, accesses, threads, share, W->count,
                                 (double)W->result[W->best].total, lcyc, &lp.rest, err);
            if (pr < 0) {
                st = EMM_ERR_NOMEM;
                goto done;
            }
            if (pr > 0) {
                lp.cycles = lcyc;
                lpp = &lp;
                priced = nlead;
            }
        }
        rank_checked(m, S, W, lpp, &r);
        if (check_bounds_hold(m, S, partial, W, lpp, r.pick, r.second, r.score2))
            break;
    }
    size_t pick = r.pick, second = r.second;
    double score = r.score, score2 = r.score2, sb = (double)S->result[S->best].total,
           wb = (double)W->result[W->best].total;
    size_t both = r.both;
    size_t c = S->cache;
    if (pick != SIZE_MAX && S->ran[c] && W->ran[c] && pick != c &&
        emm_machine_offers(m, &S->result[c].strategy) &&
        S->result[pick].total > S->result[c].total) {
        double vs_cache = (double)S->result[pick].total / (double)S->result[c].total *
                          ((double)W->result[pick].total / (double)W->result[c].total);
        if (vs_cache > EMM_DECIDE_CACHE_MARGIN) {
            second = pick;
            score2 = score;
            pick = c;
            score = lpp ? checked_score(S, W, c, lpp)
                        : (double)S->result[c].total / sb * ((double)W->result[c].total / wb);
        }
    }
    if (pick != SIZE_MAX) {
        out->how = EMM_DECIDED_CHECKED;
        out->strategy = W->result[pick].strategy;
        out->cycles = W->result[pick].total;
        out->candidates = both;
        out->synth_visits = (size_t)visits;
        out->lead_records = priced;
        set_runner_up(out, second == SIZE_MAX ? NULL : &W->result[second], score2 / score - 1);
    }
done:
    if (own_S) {
        emm_sweep_free(S);
        free(partial);
    }
    free(lcyc);
    emm_sweep_free(W);
    return st;
}

/* The neighbours' costs (docs/profile.md "The neighbours' costs"): the
 * EMM_DECIDE_NEIGHBOURS samples nearest the window's features among those
 * measured on this machine (their machine column is its fingerprint) that
 * list their run's costs. Each strategy's score is the geometric mean of
 * its cost in each neighbour's run (a strategy a neighbour does not list
 * counts as EMM_DECIDE_UNLISTED times its last listed one: it was slower
 * than all of them), times (W/W_best)^EMM_DECIDE_WINDOW_WEIGHT, W the window's cold
 * cycles, the worse of W/W_best on the machine and on a machine with the
 * local store shifted right by EMM_DECIDE_WINDOW_STORE_SHIFT (a cold window
 * fills less of the store than the run): the neighbours say what the run
 * rewards, the window what this program's accesses cost. A strategy no neighbour lists is no candidate.
 * When the window follows a leading sweep (lead[0..nlead)), the run pays it
 * too: price_lead turns the scores into cycles with it.
 * Leaves *out alone when no sample qualifies; errors are out of memory
 * only. */
static bool same_strategy(const emm_strategy *a, const emm_strategy *b)
{
    return a->kind == b->kind && a->layout == b->layout && a->fetch == b->fetch &&
           a->cell == b->cell && a->indexed == b->indexed;
}

static int by_distance(const void *a, const void *b)
{
    const struct {
        double d;
        size_t i;
    } *x = a, *y = b;
    return x->d < y->d ? -1 : x->d > y->d ? 1 : (x->i > y->i) - (x->i < y->i);
}

/* Two samples of one run: their names equal but for the window, "-wN". */
static bool same_run(const char *a, const char *b)
{
    const char *wa = strstr(a, "-w"), *wb = strstr(b, "-w");
    while (wa && strstr(wa + 2, "-w"))
        wa = strstr(wa + 2, "-w");
    while (wb && strstr(wb + 2, "-w"))
        wb = strstr(wb + 2, "-w");
    if (!wa || !wb || wa - a != wb - b || strncmp(a, b, (size_t)(wa - a)) != 0)
        return strcmp(a, b) == 0;
    wa += 2 + strspn(wa + 2, "0123456789");
    wb += 2 + strspn(wb + 2, "0123456789");
    return strcmp(wa, wb) == 0;
}

/* Whether a layout in space is among the strategies (a mesh with depth). */
static bool any_in_space(const emm_strategy *s, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (s[i].layout != EMM_LAYOUT_ORIGINAL && emm_layout_kind_dims(s[i].layout) == 3)
            return true;
    return false;
}

/* The neighbours: the samples nearest f among the runs measured on this
 * machine, at most EMM_DECIDE_NEIGHBOURS (their indices in near, their
 * distances in dist, nearest first; one sample a run), and only when the
 * nearest run is within EMM_DECIDE_NEIGHBOUR_GATE times the nearest sample
 * without costs (a canonical pattern's), whose distance goes to *canonical.
 * Returns how many; SIZE_MAX without memory. */
static size_t pick_neighbours(const emm_table *t, const emm_machine *m,
                              const emm_trace_info *info, const double f[EMM_FEATURES],
                              size_t near[EMM_DECIDE_NEIGHBOURS],
                              double dist[EMM_DECIDE_NEIGHBOURS], double *canonical_out)
{
    char id[17];
    emm_table_machine_id(m, id);
    size_t k = 0;
    /* A run over a mesh with depth tried the layouts in space, and its
     * fastest include some: such samples serve such meshes, the others the
     * planar ones (their costs rank different candidates). */
    bool depth = info->geometry.nt > 0 &&
                 emm_geometry_has_depth(info->geometry.xyz, (size_t)info->geometry.nv,
                                        info->geometry.tri, (size_t)info->geometry.nt);
    struct cand {
        double d;
        size_t i;
    } *c = malloc((t->n ? t->n : 1) * sizeof *c);
    if (!c)
        return SIZE_MAX;
    size_t nc = 0;
    double canonical = INFINITY; /* the nearest sample without costs */
    for (size_t i = 0; i < t->n; i++) {
        const emm_table_sample *x = &t->s[i];
        double d = emm_feature_distance(f, x->f);
        if (x->ncosts == 0) {
            if (d < canonical)
                canonical = d;
            continue;
        }
        if (strcmp(x->machine, id) == 0 && any_in_space(x->cost_strategy, x->ncosts) == depth)
            c[nc++] = (struct cand){d, i};
    }
    qsort(c, nc, sizeof *c, by_distance);
    for (size_t j = 0; j < nc && k < EMM_DECIDE_NEIGHBOURS; j++) {
        if (k == 0 && !(c[j].d <= EMM_DECIDE_NEIGHBOUR_GATE * canonical))
            break;
        bool seen = false;
        for (size_t q = 0; q < k && !seen; q++)
            seen = same_run(t->s[near[q]].name, t->s[c[j].i].name);
        if (seen)
            continue;
        near[k] = c[j].i;
        dist[k++] = c[j].d;
    }
    free(c);
    *canonical_out = canonical;
    return k;
}

/* Flags in want[0..count) the EMM_DECIDE_SHORTLIST least finite scores of
 * val, ties to the sweep's order. */
static void shortlist(const double *val, size_t count, uint8_t *want)
{
    for (size_t picked = 0; picked < EMM_DECIDE_SHORTLIST; picked++) {
        size_t best = SIZE_MAX;
        for (size_t i = 0; i < count; i++)
            if (!want[i] && isfinite(val[i]) && (best == SIZE_MAX || val[i] < val[best]))
                best = i;
        if (best == SIZE_MAX)
            break;
        want[best] = 1;
    }
}

/* The shortlisted scores (want, count flags of the sweep; val, infinite
 * for the others) times the long run of the checked pattern over this
 * mesh over its best among them, to the power EMM_DECIDE_LONG_WEIGHT; a
 * shortlisted strategy the long run could not simulate is no candidate any
 * more. Left as they were when the pattern cannot be made here. *vmin gets
 * the least score, *weighed the long run's triangle visits (0: it did not
 * weigh). Errors are out of memory only. */
static emm_status weigh_long_run(decide_cache *cache, const emm_machine *m,
                                 const emm_trace_info *info, const emm_mesh *mesh,
                                 const struct synth_arrays *arrays, const char *recipe,
                                 const emm_trace_record *recs, size_t n, const uint8_t *want,
                                 size_t count, const char *name, const emm_threads *threads,
                                 emm_model_share *share, double *val, double *vmin,
                                 size_t *weighed, emm_error *err)
{
    *weighed = 0;
    emm_sweep *S = NULL;
    bool owned = false;
    uint64_t visits = 0;
    emm_status st = long_run_some(cache, m, info, mesh, arrays, recipe, recs, n, want, count, name,
                                  threads, share, &S, &owned, &visits, err);
    double sb = INFINITY;
    for (size_t i = 0; S && i < count; i++)
        if (want[i] && S->ran[i] && (double)S->result[i].total < sb)
            sb = (double)S->result[i].total;
    if (st == EMM_OK && sb > 0 && isfinite(sb)) {
        *weighed = (size_t)visits;
        *vmin = INFINITY;
        for (size_t i = 0; i < count; i++) {
            if (want[i] && S->ran[i])
                val[i] *= pow((double)S->result[i].total / sb, EMM_DECIDE_LONG_WEIGHT);
            else
                val[i] = INFINITY;
            if (val[i] < *vmin)
                *vmin = val[i];
        }
    }
    if (owned)
        emm_sweep_free(S);
    return st;
}

static emm_status neighbour_costs(const emm_table *t, const emm_machine *m,
                                  const emm_trace_info *info, const emm_mesh *mesh,
                                  const struct synth_arrays *arrays, const emm_trace_record *recs,
                                  size_t n, size_t accesses, const emm_trace_record *lead,
                                  size_t nlead, const size_t near[EMM_DECIDE_NEIGHBOURS],
                                  const double dist[EMM_DECIDE_NEIGHBOURS], size_t k,
                                  const char *name, const emm_threads *threads,
                                  emm_model_share *share, decide_cache *cache,
                                  emm_window_decision *out, emm_error *err)
{
    if (k == 0)
        return EMM_OK;
    /* The window's sweep. */
    emm_sweep *own = NULL;
    emm_error e;
    if (sweep_records_shared(m, info, recs, n, threads, share, true, &own, &e) != EMM_OK)
        return e.status == EMM_ERR_NOMEM ? emm_fail(err, e.status, "%s", e.message) : EMM_OK;
    const emm_sweep *W = own;
    double wb = INFINITY;
    for (size_t i = 0; i < W->count; i++)
        if (W->ran[i] && emm_machine_offers(m, &W->result[i].strategy) &&
            (double)W->result[i].total < wb)
            wb = (double)W->result[i].total;
    size_t scored = 0, nled = 0;
    double *val = malloc((W->count ? W->count : 1) * sizeof *val), vmin = INFINITY;
    double *nbm = malloc((W->count ? W->count : 1) * sizeof *nbm);
    uint8_t *want = calloc(W->count ? W->count : 1, 1);
    emm_sweep *small = NULL;
    emm_status st = EMM_OK;
    if (!val || !nbm || !want) {
        st = emm_fail(err, EMM_ERR_NOMEM, "out of memory for the neighbours' costs");
        goto done;
    }
    /* Each strategy's score on the whole store: the neighbours' costs times
     * the window's. */
    for (size_t i = 0; i < W->count; i++)
        val[i] = INFINITY;
    for (size_t i = 0; i < W->count && wb > 0 && isfinite(wb); i++) {
        const emm_strategy *s = &W->result[i].strategy;
        if (!W->ran[i] || !emm_machine_offers(m, s))
            continue;
        double logsum = 0;
        size_t listed = 0;
        for (size_t j = 0; j < k; j++) {
            const emm_table_sample *nb = &t->s[near[j]];
            double cost = EMM_DECIDE_UNLISTED * nb->cost[nb->ncosts - 1];
            for (uint32_t q = 0; q < nb->ncosts; q++)
                if (same_strategy(&nb->cost_strategy[q], s)) {
                    cost = nb->cost[q];
                    listed++;
                    break;
                }
            logsum += log(cost);
        }
        if (listed == 0)
            continue;
        scored++;
        nbm[i] = exp(logsum / (double)k);
        val[i] = nbm[i] * pow((double)W->result[i].total / wb, EMM_DECIDE_WINDOW_WEIGHT);
    }
    /* The shortlist, again on a smaller local store
     * (EMM_DECIDE_WINDOW_STORE_SHIFT), as full as the run will keep it: its
     * window's cost is the worse of the two ratios, each to its best among
     * the shortlist; the rest are no candidates. Without that store (one
     * too small to halve), the window's own sweep stands. */
    shortlist(val, W->count, want);
    emm_machine *ms = NULL;
    char bytes[32];
    snprintf(bytes, sizeof bytes, "%llu",
             (unsigned long long)(emm_machine_get(m, "local.bytes") >>
                                  EMM_DECIDE_WINDOW_STORE_SHIFT));
    if (scored > 0 && emm_machine_clone(m, &ms, &e) == EMM_OK &&
        emm_machine_set_key(ms, "local.bytes", bytes, "decision", &e) == EMM_OK &&
        emm_machine_validate(ms, &e) == EMM_OK &&
        sweep_run(ms, info, recs, n, threads, share, true, want, NULL, &small, &e) != EMM_OK &&
        e.status == EMM_ERR_NOMEM) {
        emm_machine_free(ms);
        st = emm_fail(err, e.status, "%s", e.message);
        goto done;
    }
    emm_machine_free(ms);
    const emm_sweep *Ws = small && small->count == W->count ? small : W;
    double wsb = INFINITY;
    for (size_t i = 0; i < W->count; i++)
        if (want[i] && Ws->ran[i])
            wsb = fmin(wsb, (double)Ws->result[i].total);
    for (size_t i = 0; i < W->count; i++) {
        if (!want[i] || !Ws->ran[i] || !(wsb > 0 && isfinite(wsb))) {
            val[i] = INFINITY;
            want[i] = 0;
            continue;
        }
        double wr = fmax((double)W->result[i].total / wb, (double)Ws->result[i].total / wsb);
        val[i] = nbm[i] * pow(wr, EMM_DECIDE_WINDOW_WEIGHT);
        vmin = fmin(vmin, val[i]);
    }
    size_t long_visits = 0;
    if (isfinite(vmin) &&
        (st = weigh_long_run(cache, m, info, mesh, arrays, check_recipe(out), recs, n, want,
                             W->count, name, threads, share, val, &vmin, &long_visits, err)) !=
            EMM_OK)
        goto done;
    if (lead && nlead > 0 && isfinite(vmin) && accesses > 0 &&
        (st = price_lead(m, info, lead, nlead, accesses, threads, share, W->count, wb, vmin,
                         val, &nled, err)) != EMM_OK)
        goto done;
    size_t pick = SIZE_MAX, second = SIZE_MAX;
    double score = INFINITY, score2 = INFINITY;
    for (size_t i = 0; i < W->count; i++) {
        if (val[i] < score) {
            score2 = score;
            second = pick;
            score = val[i];
            pick = i;
        } else if (val[i] < score2) {
            score2 = val[i];
            second = i;
        }
    }
    if (pick != SIZE_MAX) {
        out->strategy = W->result[pick].strategy;
        out->cycles = W->result[pick].total;
        out->candidates = scored;
        out->neighbours = k;
        out->neighbour_distance = dist[k - 1];
        out->lead_records = nled;
        out->synth_visits = long_visits;
        set_runner_up(out, second == SIZE_MAX ? NULL : &W->result[second], score2 / score - 1);
    }
done:
    free(val);
    free(nbm);
    free(want);
    emm_sweep_free(small);
    emm_sweep_free(own);
    return st;
}

emm_status emm_decide_features(const emm_table *t, const emm_machine *m,
                               const emm_trace_info *info, const emm_trace_record *recs, size_t n,
                               const double f[EMM_FEATURES], size_t accesses, const char *name,
                               const emm_decide_options *opt, emm_window_decision *out,
                               emm_error *err)
{
    emm_model_share *share = emm_model_share_new();
    if (!share)
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", name);
    emm_model_share_keep(share); /* the sweeps build each layout once */
    emm_status st = decide_features_shared(t, m, info, recs, n, f, accesses, name, opt, share,
                                           NULL, out, err);
    emm_model_share_unref(share);
    return st;
}

void emm_window_decision_release(emm_window_decision *d)
{
    free(d->classes);
    d->classes = NULL;
    d->nclasses = 0;
}

/* decide_features_shared, but for what a failure leaves in *out. */
static emm_status decide(const emm_table *t, const emm_machine *m, const emm_trace_info *info,
                         const emm_trace_record *recs, size_t n, const double f[EMM_FEATURES],
                         size_t accesses, const char *name, const emm_decide_options *opt,
                         emm_model_share *share, decide_cache *cache, emm_window_decision *out,
                         emm_error *err)
{
    cache = cache_for(cache, info);
    memset(out, 0, sizeof *out);
    memcpy(out->f, f, sizeof out->f);
    out->accesses = accesses;
    emm_status st;
    if (t && t->n > 0) {
        if ((st = emm_table_decide(t, out->f, opt ? opt->threshold : 0, &out->table, err)) !=
            EMM_OK)
            return st;
        out->has_table = 1;
        out->strategy = out->table.strategy;
        out->how = EMM_DECIDED_TABLE;
    }
    const emm_threads *threads = opt ? opt->threads : NULL;
    if (!(opt && opt->simulate) && out->has_table && !out->table.novel) {
        if (!m)
            return EMM_OK;
        struct synth_arrays arrays;
        emm_mesh *mesh = NULL;
        bool own_mesh = false;
        st = EMM_OK;
        if (info->geometry.nt > 0 && program_arrays(info, &arrays))
            program_mesh(cache, info, name, &mesh, &own_mesh);
        size_t near[EMM_DECIDE_NEIGHBOURS], k = 0;
        double dist[EMM_DECIDE_NEIGHBOURS];
        if (mesh) {
            st = pick_class(t, info, mesh, &arrays, recs, n, f, accesses, name, threads, cache,
                            out, err);
            /* Runs measured on this machine near the window, when the table
             * has some, decide among the candidates once the pattern names
             * a traversal to check (a sample of the user's own class,
             * without a recipe, stands as in the thesis): the check's long
             * run, most of a decision's cost, would not count, and is made
             * only when they decide nothing. */
            double canonical = INFINITY, check_distance = INFINITY;
            if (st == EMM_OK && names_traversal(out) &&
                (k = pick_neighbours(t, m, info, f, near, dist, &canonical)) == SIZE_MAX)
                st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", name);
            /* A window is a canonical pattern's (the check predicts those
             * traversals nearly exactly) when the checked pattern, made on
             * this mesh, lies within EMM_DECIDE_CANONICAL_NEAR of it,
             * however far the table's samples of it (made on other meshes
             * and windows) lie — or, when a sample lies that near, when
             * another class's traversal made here does (near_class). A
             * window no pattern resembles here is another program's. */
            if (st == EMM_OK && k > 0) {
                st = check_distance_of(mesh, info, &arrays, recs, n, f, accesses, name, threads,
                                       cache, out, &check_distance, err);
                if (st == EMM_OK && !(check_distance <= EMM_DECIDE_CANONICAL_NEAR) &&
                    canonical <= EMM_DECIDE_CANONICAL_NEAR)
                    st = near_class(t, mesh, info, &arrays, recs, n, f, accesses, name, threads,
                                    cache, out, &check_distance, err);
                if (check_distance <= EMM_DECIDE_CANONICAL_NEAR)
                    k = 0;
            }
            if (st == EMM_OK && k > 0) {
                st = neighbour_costs(t, m, info, mesh, &arrays, recs, n, accesses,
                                     opt ? opt->lead : NULL, opt ? opt->nlead : 0, near, dist, k,
                                     name, threads, share, cache, out, err);
                if (out->neighbours)
                    out->how = EMM_DECIDED_CHECKED;
            }
            if (st == EMM_OK && !out->neighbours)
                st = check_pattern(m, info, mesh, &arrays, recs, n, accesses,
                                   opt ? opt->lead : NULL, opt ? opt->nlead : 0, name, threads,
                                   share, cache,
                                   opt ? opt->synth_visits : 0, out, err);
        }
        if (own_mesh)
            emm_mesh_free(mesh);
        /* A sample's strategy the machine does not have (a cache label on a
         * machine without one) is no answer: the window decides. */
        if (st != EMM_OK || out->how == EMM_DECIDED_CHECKED ||
            emm_machine_offers(m, &out->strategy))
            return st;
    }
    emm_sweep *sw = NULL;
    st = sweep_records_shared(m, info, recs, n, threads, share, false, &sw, err);
    if (st == EMM_OK) {
        out->simulated = 1;
        out->how = EMM_DECIDED_WINDOW;
        out->strategy = sw->result[sw->best].strategy;
        out->cycles = sw->result[sw->best].total;
        out->candidates = sw->simulated;
        size_t second = SIZE_MAX;
        for (size_t i = 0; i < sw->count; i++)
            if (i != sw->best && sw->ran[i] && emm_machine_offers(m, &sw->result[i].strategy) &&
                (second == SIZE_MAX || sw->result[i].total < sw->result[second].total))
                second = i;
        if (second != SIZE_MAX)
            set_runner_up(out, &sw->result[second],
                          (double)sw->result[second].total / (double)(out->cycles ? out->cycles : 1) -
                              1);
    }
    emm_sweep_free(sw);
    return st;
}

emm_status decide_features_shared(const emm_table *t, const emm_machine *m,
                                  const emm_trace_info *info, const emm_trace_record *recs,
                                  size_t n, const double f[EMM_FEATURES], size_t accesses,
                                  const char *name, const emm_decide_options *opt,
                                  emm_model_share *share, decide_cache *cache,
                                  emm_window_decision *out, emm_error *err)
{
    emm_status st = decide(t, m, info, recs, n, f, accesses, name, opt, share, cache, out, err);
    if (st != EMM_OK)
        emm_window_decision_release(out);
    return st;
}

emm_status emm_decide_window(const emm_table *t, const emm_machine *m, const emm_trace_info *info,
                             const emm_trace_record *recs, size_t n, const char *name,
                             const emm_decide_options *opt, emm_window_decision *out,
                             emm_error *err)
{
    memset(out, 0, sizeof *out);
    double f[EMM_FEATURES];
    size_t np, skip;
    emm_status st = records_features(info, recs, n, n ? n : 1, name, opt ? opt->threads : NULL, f,
                                     &np, &skip, err);
    if (st != EMM_OK)
        return st;
    /* The window proper starts after the leading sweep, as the session's does. */
    emm_decide_options o = opt ? *opt : (emm_decide_options){0};
    o.lead = recs;
    o.nlead = skip;
    return emm_decide_features(t, m, info, recs + skip, n - skip, f, np, name, &o, out, err);
}
