/* The prediction benchmark (make predict; bench/predict.sh makes the corpus):
 * for each case — a program's trace, a machine — the window's prediction
 * (what `--finalists 0` answers: the thesis' method, no contest) against the
 * whole run's best candidate of `emm replay --all` (the cache strategies left
 * out: the default machine has no cache), leave-one-program-out: the
 * strategy table's samples of the case's own program (named prog-PROGRAM-...)
 * are dropped before the case is decided, so a program never predicts
 * itself. Also the regret of the nearest sample's own label (the thesis'
 * Table 5.1 lookup) on the same filtered table.
 *
 * usage: predict CASES [--window N] [--table FILE] [--dump FILE]
 * CASES has one case a line: PROGRAM NAME TRACE MACHINE ALL
 *   PROGRAM  the program, as the table's samples name it (prog-PROGRAM-...)
 *   NAME     the case's name in the listing
 *   TRACE    its trace (emm run --trace)
 *   MACHINE  a machine file, or - for the default machine
 *   ALL      `emm replay TRACE --all` 's listing on that machine
 * Prints one line a case, then mean, median and worst regret. --dump FILE
 * writes a JSON line a case for studying predictors offline: the window's
 * features, its cold sweep (after the leading sweep, as the decision's)
 * on the machine and on its local store shifted right by 1 to 4 bits
 * (window_1 ... window_4), the leading sweep's own cold sweep (lead, when
 * the window follows one), the whole run's listing, the window's revisits
 * and the bytes of the distinct elements it touches, and the mesh's bytes
 * against the local store. A benchmark, not a test. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "emm/mesh.h"
#include "emm/profile.h"
#include "emm/replay.h"
#include "emm/sim.h"
#include "emm/table.h"
#include "emm/trace.h"

#define MAX_CASES 1024
#define MAX_STRATS 512

static void die(const char *what, const char *msg)
{
    fprintf(stderr, "predict: %s: %s\n", what, msg);
    exit(1);
}

struct listing {
    size_t n;
    char name[MAX_STRATS][96];
    unsigned long long total[MAX_STRATS];
};

/* `emm replay --all`'s table: "RANK STRATEGY TOTAL ..." lines. */
static void read_listing(const char *path, struct listing *l)
{
    FILE *f = fopen(path, "r");
    if (!f)
        die(path, "cannot open");
    char line[1024];
    l->n = 0;
    while (fgets(line, sizeof line, f) && l->n < MAX_STRATS) {
        unsigned rank;
        char s[96];
        unsigned long long total;
        if (sscanf(line, "%u %95s %llu", &rank, s, &total) == 3) {
            snprintf(l->name[l->n], sizeof l->name[l->n], "%s", s);
            l->total[l->n++] = total;
        }
    }
    fclose(f);
    if (l->n == 0)
        die(path, "no strategy lines (not an emm replay --all listing)");
}

static int is_cache(const char *s)
{
    return strncmp(s, "cache", 5) == 0;
}

/* The strategy's cycles in the listing; 0 when absent. */
static unsigned long long cycles_of(const struct listing *l, const char *s)
{
    for (size_t i = 0; i < l->n; i++)
        if (strcmp(l->name[i], s) == 0)
            return l->total[i];
    return 0;
}

/* A sweep's cycles as the members of a JSON object: "strategy": cycles. */
static void dump_sweep(FILE *f, const emm_sweep *w)
{
    int first = 1;
    for (size_t i = 0; i < w->count; i++) {
        if (!w->ran[i])
            continue;
        char sname[96];
        emm_strategy_format(&w->result[i].strategy, sname, sizeof sname);
        fprintf(f, "%s\"%s\": %llu", first ? "" : ", ", sname,
                (unsigned long long)w->result[i].total);
        first = 0;
    }
}

/* A JSON line for the case: what a predictor could look at, and the truth. */
static void dump_case(FILE *f, const char *prog, const char *name, const char *mname,
                      const emm_machine *m, const emm_trace_info *info,
                      const emm_trace_record *recs, size_t n, const emm_window_decision *d,
                      const char *pred, const char *label, const struct listing *l)
{
    emm_error err;
    emm_sweep *w = NULL;
    fprintf(f, "{\"program\": \"%s\", \"case\": \"%s\", \"machine\": \"%s\", "
               "\"predicted\": \"%s\", \"label\": \"%s\", \"nearest\": \"%s\", "
               "\"distance\": %.6f, \"features\": [",
            prog, name, mname, pred, label, d->has_table ? d->table.nearest : "-",
            d->has_table ? d->table.distance : 0.0);
    for (int k = 0; k < EMM_FEATURES; k++)
        fprintf(f, "%s%.9g", k ? ", " : "", d->f[k]);
    /* Revisits: element accesses (consecutive repeats once), distinct
     * elements, and the median distance in accesses back to the last visit. */
    uint64_t total = 0;
    for (uint32_t a = 0; a < info->narrays; a++)
        total += info->arrays[a].count;
    uint32_t *last = calloc(total ? total : 1, sizeof *last);
    uint64_t *base = calloc(info->narrays ? info->narrays : 1, sizeof *base);
    size_t *gaps = malloc((n ? n : 1) * sizeof *gaps), ngaps = 0, acc = 0, distinct = 0;
    uint64_t dbytes = 0;
    for (uint32_t a = 1; a < info->narrays; a++)
        base[a] = base[a - 1] + info->arrays[a - 1].count;
    uint64_t prev = UINT64_MAX;
    for (size_t i = 0; last && base && gaps && i < n; i++) {
        if (recs[i].write || recs[i].array >= info->narrays ||
            recs[i].element >= info->arrays[recs[i].array].count)
            continue;
        uint64_t e = base[recs[i].array] + recs[i].element;
        if (e == prev)
            continue;
        prev = e;
        acc++;
        if (last[e])
            gaps[ngaps++] = acc - last[e];
        else {
            distinct++;
            dbytes += info->arrays[recs[i].array].record_size;
        }
        last[e] = (uint32_t)acc;
    }
    size_t med = 0;
    if (ngaps) {
        size_t *g = gaps;
        /* a histogram of powers of two, then the median's bucket */
        size_t hist[64] = {0};
        for (size_t i = 0; i < ngaps; i++) {
            int b = 0;
            while ((g[i] >> b) > 1)
                b++;
            hist[b]++;
        }
        size_t c = 0;
        for (int b = 0; b < 64; b++) {
            c += hist[b];
            if (2 * c >= ngaps) {
                med = (size_t)1 << b;
                break;
            }
        }
    }
    uint64_t bytes = 0;
    for (uint32_t a = 0; a < info->narrays; a++)
        bytes += info->arrays[a].count * info->arrays[a].record_size;
    fprintf(f, "], \"window_accesses\": %zu, \"distinct\": %zu, \"revisits\": %zu, "
               "\"median_gap\": %zu, \"mesh_bytes\": %llu, \"nt\": %llu, \"nv\": %llu, "
               "\"local_bytes\": %llu, \"run_records\": %llu, \"distinct_bytes\": %llu",
            acc, distinct, ngaps, med, (unsigned long long)bytes,
            (unsigned long long)info->geometry.nt, (unsigned long long)info->geometry.nv,
            (unsigned long long)emm_machine_get(m, "local.bytes"),
            (unsigned long long)info->accesses, (unsigned long long)dbytes);
    free(last);
    free(base);
    free(gaps);
    /* The window's sweep as the decision's: after the leading index-order
     * sweep, which the profile leaves out (docs/profile.md). */
    size_t skip = 0;
    emm_profiler *p;
    if (emm_profiler_new(info, n ? n : 1, EMM_PROFILE_PLANE, name, &p, &err) == EMM_OK) {
        if (emm_profiler_add(p, recs, n, &err) == EMM_OK)
            emm_profiler_swept(p, &skip);
        emm_profiler_free(p);
    }
    fprintf(f, ", \"skip\": %zu, \"window\": {", skip);
    if (emm_sweep_records(m, info, recs + skip, n - skip, NULL, &w, &err) == EMM_OK) {
        dump_sweep(f, w);
        emm_sweep_free(w);
    }
    fprintf(f, "}");
    /* The leading sweep alone, cold: part of the run the decision leaves out. */
    if (skip > 0 && emm_sweep_records(m, info, recs, skip, NULL, &w, &err) == EMM_OK) {
        fprintf(f, ", \"lead\": {");
        dump_sweep(f, w);
        fprintf(f, "}");
        emm_sweep_free(w);
    }
    /* The same window on smaller local stores (a quarter, a sixteenth...):
     * a cold window leaves most of the store empty where the run fills it. */
    uint64_t lb = emm_machine_get(m, "local.bytes");
    for (int sh = 1; sh <= 4; sh++) {
        emm_machine *ms;
        char a[64];
        snprintf(a, sizeof a, "local.bytes=%llu", (unsigned long long)(lb >> sh));
        if (emm_machine_clone(m, &ms, &err) != EMM_OK)
            continue;
        if (emm_machine_set(ms, a, &err) == EMM_OK && emm_machine_validate(ms, &err) == EMM_OK &&
            emm_sweep_records(ms, info, recs + skip, n - skip, NULL, &w, &err) == EMM_OK) {
            fprintf(f, ", \"window_%d\": {", sh);
            dump_sweep(f, w);
            fprintf(f, "}");
            emm_sweep_free(w);
        }
        emm_machine_free(ms);
    }
    fprintf(f, ", \"run\": {");
    for (size_t i = 0; i < l->n; i++)
        fprintf(f, "%s\"%s\": %llu", i ? ", " : "", l->name[i], l->total[i]);
    fprintf(f, "}}\n");
    fflush(f);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void summary(const char *what, double *r, size_t n)
{
    if (n == 0) {
        printf("%-34s no cases\n", what);
        return;
    }
    double sum = 0;
    for (size_t i = 0; i < n; i++)
        sum += r[i];
    qsort(r, n, sizeof *r, cmp_double);
    double med = n % 2 ? r[n / 2] : (r[n / 2 - 1] + r[n / 2]) / 2;
    printf("%-34s mean %7.2f%%  median %7.2f%%  worst %7.2f%%  (%zu cases)\n", what,
           100 * sum / (double)n, 100 * med, 100 * r[n - 1], n);
}

int main(int argc, char **argv)
{
    const char *cases = NULL, *user = NULL, *dump = NULL;
    uint64_t window = 16384;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--window") == 0 && i + 1 < argc)
            window = strtoull(argv[++i], NULL, 10);
        else if (strcmp(argv[i], "--table") == 0 && i + 1 < argc)
            user = argv[++i];
        else if (strcmp(argv[i], "--dump") == 0 && i + 1 < argc)
            dump = argv[++i];
        else if (!cases && argv[i][0] != '-')
            cases = argv[i];
        else {
            fprintf(stderr, "usage: predict CASES [--window N] [--table FILE] [--dump FILE]\n");
            return 2;
        }
    }
    if (!cases) {
        fprintf(stderr, "usage: predict CASES [--window N] [--table FILE] [--dump FILE]\n");
        return 2;
    }
    emm_error err;
    emm_table *full = emm_table_new();
    if (!full || emm_table_load_standard(full, user, &err) != EMM_OK)
        die("table", err.message);
    FILE *cf = fopen(cases, "r");
    if (!cf)
        die(cases, "cannot open");
    FILE *df = dump ? fopen(dump, "w") : NULL;
    if (dump && !df)
        die(dump, "cannot write");
    static double reg[MAX_CASES], lab[MAX_CASES];
    size_t nreg = 0, nlab = 0, skipped = 0;
    printf("%-36s %-8s %-8s %-24s %-24s %8s %-24s %8s %6s %s\n", "case", "machine", "how",
           "predicted", "best (no cache)", "regret", "nearest's label", "regret", "dist",
           "nearest");
    char line[4096];
    while (fgets(line, sizeof line, cf)) {
        char prog[256], name[256], trace[1024], mfile[1024], all[1024];
        if (line[0] == '#' || sscanf(line, "%255s %255s %1023s %1023s %1023s", prog, name, trace,
                                     mfile, all) != 5)
            continue;
        /* The table without the program's own samples. */
        char own[300];
        snprintf(own, sizeof own, "prog-%s-", prog);
        emm_table *t = emm_table_new();
        if (!t)
            die("table", "out of memory");
        for (size_t i = 0; i < emm_table_count(full); i++) {
            const emm_table_sample *s = emm_table_at(full, i);
            if (strncmp(s->name, own, strlen(own)) != 0 && emm_table_add(t, s, &err) != EMM_OK)
                die("table", err.message);
        }
        emm_machine *m;
        if (emm_machine_new(&m, &err) != EMM_OK)
            die("machine", err.message);
        const char *mname = "default";
        if (strcmp(mfile, "-") != 0) {
            if (emm_machine_load(m, mfile, &err) != EMM_OK)
                die(mfile, err.message);
            mname = strrchr(mfile, '/') ? strrchr(mfile, '/') + 1 : mfile;
        }
        struct listing l;
        read_listing(all, &l);
        emm_trace_reader *r;
        emm_trace_record *recs = NULL;
        size_t n = 0;
        if (emm_trace_reader_open(trace, &r, &err) != EMM_OK ||
            emm_profile_trace_window_fill(r, window, emm_machine_get(m, "local.bytes"), trace,
                                          &recs, &n, NULL, &err) != EMM_OK)
            die(trace, err.message);
        emm_window_decision d;
        emm_decide_options dopt = {0};
        if (emm_decide_window(t, m, emm_trace_reader_info(r), recs, n, trace, &dopt, &d, &err) !=
            EMM_OK)
            die(trace, err.message);
        emm_window_decision_release(&d);
        unsigned long long best = 0;
        const char *bestname = "?";
        for (size_t i = 0; i < l.n; i++)
            if (!is_cache(l.name[i]) && (best == 0 || l.total[i] < best))
                best = l.total[i], bestname = l.name[i];
        char pred[96], label[96] = "-";
        emm_strategy_format(&d.strategy, pred, sizeof pred);
        if (d.has_table)
            emm_strategy_format(&d.table.strategy, label, sizeof label);
        if (df)
            dump_case(df, prog, name, mname, m, emm_trace_reader_info(r), recs, n, &d, pred,
                      label, &l);
        free(recs);
        emm_trace_reader_close(r);
        unsigned long long pc = cycles_of(&l, pred), lc = d.has_table ? cycles_of(&l, label) : 0;
        char rp[32] = "n/a", rl[32] = "n/a";
        if (pc && best && nreg < MAX_CASES) {
            reg[nreg] = (double)pc / (double)best - 1;
            snprintf(rp, sizeof rp, "%7.2f%%", 100 * reg[nreg++]);
        } else {
            skipped++;
        }
        if (lc && best && nlab < MAX_CASES) {
            lab[nlab] = (double)lc / (double)best - 1;
            snprintf(rl, sizeof rl, "%7.2f%%", 100 * lab[nlab++]);
        }
        printf("%-36s %-8.8s %-8s %-24s %-24s %8s %-24s %8s %6.3f %s\n", name, mname,
               d.neighbours ? "costs" : emm_decided_name(d.how), pred, bestname, rp, label, rl,
               d.has_table ? d.table.distance : 0.0, d.has_table ? d.table.nearest : "-");
        fflush(stdout);
        emm_machine_free(m);
        emm_table_free(t);
    }
    fclose(cf);
    if (df)
        fclose(df);
    printf("\nleave-one-program-out, against the best non-cache strategy of the whole run:\n");
    summary("the window's prediction", reg, nreg);
    summary("the nearest sample's label", lab, nlab);
    if (skipped)
        printf("(%zu cases without a regret: the prediction is not in the listing)\n", skipped);
    emm_table_free(full);
    return 0;
}
