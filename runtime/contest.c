/* The contest of runtime/contest.h: successive halving over the run, and
 * the margin that stops a challenger which cannot catch up. */
#include "contest.h"

#include <stdlib.h>
#include <string.h>

#include "emm/replay.h"
#include "error.h"

struct contest {
    emm_runner *runner;
    size_t *in;       /* runner indices still in, in entry order */
    size_t nin, entrants;
    size_t *pinned;   /* runner indices that keep running when dropped */
    size_t npinned;
    size_t *retired;  /* runner indices retired, in the order they were */
    uint64_t *retired_at, *retired_cycles; /* the records run then, and its cycles */
    uint64_t *retired_leader; /* a margin stop: the leader's cycles then; else 0 */
    bool *retired_margin;     /* whether it was stopped by the margin (else halved) */
    size_t nretired;
    uint64_t *prev;   /* by runner index: the cycles at the previous check */
    size_t nprev;
    size_t checks;    /* the checks made */
    size_t finalists;
    uint64_t lead, unit, done, next, step;
    uint64_t at[CONTEST_MAX_ROUNDS];
    size_t kept[CONTEST_MAX_ROUNDS];
    size_t rounds;
    size_t *order;    /* scratch for the ranking */
    uint64_t *total;  /* scratch: each contender's cycles so far */
    emm_strategy *strategy; /* scratch: and its strategy */
};

emm_status contest_new(emm_runner *r, const size_t *models, const bool *pinned, size_t n,
                       uint64_t lead, uint64_t unit, size_t finalists, contest **out,
                       emm_error *err)
{
    *out = NULL;
    contest *c = calloc(1, sizeof *c);
    if (c) {
        c->in = calloc(n ? n : 1, sizeof *c->in);
        c->pinned = calloc(n ? n : 1, sizeof *c->pinned);
        c->retired = calloc(n ? n : 1, sizeof *c->retired);
        c->retired_at = calloc(n ? n : 1, sizeof *c->retired_at);
        c->retired_cycles = calloc(n ? n : 1, sizeof *c->retired_cycles);
        c->retired_leader = calloc(n ? n : 1, sizeof *c->retired_leader);
        c->retired_margin = calloc(n ? n : 1, sizeof *c->retired_margin);
        size_t top = 0;
        for (size_t j = 0; j < n; j++)
            top = models[j] + 1 > top ? models[j] + 1 : top;
        c->nprev = top;
        c->prev = calloc(top ? top : 1, sizeof *c->prev);
        c->order = calloc(n ? n : 1, sizeof *c->order);
        c->total = calloc(n ? n : 1, sizeof *c->total);
        c->strategy = calloc(n ? n : 1, sizeof *c->strategy);
    }
    if (!c || !c->in || !c->pinned || !c->retired || !c->retired_at || !c->retired_cycles ||
        !c->retired_leader || !c->retired_margin || !c->prev || !c->order || !c->total ||
        !c->strategy) {
        contest_free(c);
        return emm_fail(err, EMM_ERR_NOMEM, "out of memory for the contest of %zu candidates", n);
    }
    c->runner = r;
    for (size_t j = 0; j < n; j++) {
        if (!emm_runner_model(r, models[j]))
            continue;
        c->in[c->nin++] = models[j];
        if (pinned && pinned[j])
            c->pinned[c->npinned++] = models[j];
    }
    c->entrants = c->nin;
    c->finalists = finalists ? finalists : 1;
    c->lead = lead;
    c->unit = unit ? unit : 1;
    c->step = 2 * c->unit;
    c->next = c->lead + c->step;
    *out = c;
    return EMM_OK;
}

static bool member(const size_t *set, size_t n, size_t x)
{
    for (size_t k = 0; k < n; k++)
        if (set[k] == x)
            return true;
    return false;
}

/* Whether contender a ranks behind contender b: more cycles, or as many and
 * a later strategy in a fixed order (kind, layout, fetch, cell), so that
 * the ranking does not depend on the order the models entered in. */
static bool behind(const contest *c, size_t a, size_t b)
{
    if (c->total[a] != c->total[b])
        return c->total[a] > c->total[b];
    const emm_strategy *x = &c->strategy[a], *y = &c->strategy[b];
    if (x->kind != y->kind)
        return x->kind > y->kind;
    if (x->layout != y->layout)
        return x->layout > y->layout;
    if (x->fetch != y->fetch)
        return x->fetch > y->fetch;
    return x->cell > y->cell;
}

/* The contenders' order, fastest first. */
static size_t rank(const contest *c, size_t *order)
{
    for (size_t k = 0; k < c->nin; k++) {
        emm_result res;
        emm_model_result(emm_runner_model(c->runner, c->in[k]), &res);
        c->total[k] = res.total;
        c->strategy[k] = res.strategy;
        emm_result_release(&res);
        order[k] = k;
    }
    /* insertion sort: a few dozen contenders */
    for (size_t i = 1; i < c->nin; i++) {
        size_t x = order[i], j = i;
        while (j > 0 && behind(c, order[j - 1], x)) {
            order[j] = order[j - 1];
            j--;
        }
        order[j] = x;
    }
    return c->nin;
}

bool contest_pins(const emm_strategy *s)
{
    return s->kind == EMM_STRATEGY_DIRECT ||
           (s->kind == EMM_STRATEGY_CACHE && s->layout == EMM_LAYOUT_ORIGINAL);
}

/* The contenders still in that keep running when dropped (pinned). */
static size_t pinned_in(const contest *c)
{
    size_t n = 0;
    for (size_t k = 0; k < c->nin; k++)
        n += member(c->pinned, c->npinned, c->in[k]);
    return n;
}

/* Retires contender k of those in (its cycles in c->total[k]; leader: the
 * leader's cycles when the margin stopped it, else 0). The caller
 * compacts c->in. */
static void retire(contest *c, size_t k, bool margin, uint64_t leader)
{
    size_t i = c->in[k];
    emm_runner_retire(c->runner, i);
    c->retired[c->nretired] = i;
    c->retired_at[c->nretired] = c->done;
    c->retired_cycles[c->nretired] = c->total[k];
    c->retired_margin[c->nretired] = margin;
    c->retired_leader[c->nretired++] = leader;
}

/* Drops the slower half of the contenders still in (keeping at least
 * `finalists`), retiring them; a pinned contender (one the report shows,
 * simulated to the end anyway) stays in whatever its rank, so that the
 * answer is the fastest of every strategy simulated over the whole run. */
static void halve(contest *c)
{
    size_t keep = (c->nin + 1) / 2;
    if (keep < c->finalists)
        keep = c->finalists;
    if (keep >= c->nin)
        return;
    rank(c, c->order);
    bool *stay = calloc(c->nin, sizeof *stay);
    if (!stay) /* no memory to drop anyone: all stay in, which is only slower */
        return;
    for (size_t k = 0; k < keep; k++)
        stay[c->order[k]] = true;
    size_t m = 0;
    for (size_t k = 0; k < c->nin; k++) {
        if (stay[k] || member(c->pinned, c->npinned, c->in[k]))
            c->in[m++] = c->in[k];
        else
            retire(c, k, false, 0);
    }
    c->nin = m;
    free(stay);
}

/* Whether x exceeds ref by more than CONTEST_MARGIN_PERCENT of ref. */
static bool beyond_margin(uint64_t x, uint64_t ref)
{
    return x > ref && x - ref > ref / 100 * CONTEST_MARGIN_PERCENT +
                                    ref % 100 * CONTEST_MARGIN_PERCENT / 100;
}

/* The margin (contest.h, CONTEST_MARGIN_PERCENT): once halving is over (the
 * contenders not pinned are the finalists), from the second check on, a
 * finalist that is not pinned is stopped when its cycles so far exceed the
 * leader's by more than the margin and so did its cycles since the
 * previous check: behind by more than the margin, and still losing ground
 * at that rate. The leader (the fastest so far) is never stopped, so the
 * fastest contender still runs. */
static void margin_stop(contest *c)
{
    if (c->checks == 0 || c->nin < 2 || c->nin - pinned_in(c) > c->finalists)
        return;
    rank(c, c->order);
    size_t lead_k = c->order[0];
    uint64_t lead = c->total[lead_k];
    size_t li = c->in[lead_k];
    uint64_t lead_span = lead - (li < c->nprev ? c->prev[li] : 0);
    size_t m = 0;
    for (size_t k = 0; k < c->nin; k++) {
        size_t i = c->in[k];
        uint64_t span = c->total[k] - (i < c->nprev ? c->prev[i] : 0);
        bool stop = k != lead_k && !member(c->pinned, c->npinned, i) &&
                    beyond_margin(c->total[k], lead) && beyond_margin(span, lead_span);
        if (stop) {
            retire(c, k, true, lead);
        } else {
            c->in[m] = i;
            c->total[m] = c->total[k];
            c->strategy[m] = c->strategy[k];
            m++;
        }
    }
    c->nin = m;
}

/* Each contender's cycles now, for the next check's "since the previous
 * check". */
static void note_totals(contest *c)
{
    for (size_t k = 0; k < c->nin; k++) {
        emm_result res;
        emm_model_result(emm_runner_model(c->runner, c->in[k]), &res);
        if (c->in[k] < c->nprev)
            c->prev[c->in[k]] = res.total;
        emm_result_release(&res);
    }
}

void contest_run(contest *c, const emm_trace_record *recs, size_t n)
{
    while (n > 0) {
        uint64_t room = c->next - c->done;
        size_t part = room < n ? (size_t)room : n;
        emm_runner_run(c->runner, recs, part);
        c->done += part;
        recs += part;
        n -= part;
        if (c->done == c->next) {
            size_t before = c->nin;
            if (c->nin - pinned_in(c) > c->finalists)
                halve(c);
            /* A contest that drops none (finalists at least the entrants:
             * --finalists all) stops none by the margin either. */
            if (c->finalists < c->entrants) {
                margin_stop(c);
                note_totals(c);
            }
            c->checks++;
            if (c->nin < before && c->rounds < CONTEST_MAX_ROUNDS) {
                c->at[c->rounds] = c->done;
                c->kept[c->rounds] = c->nin;
                c->rounds++;
            }
            c->step = c->step > UINT64_MAX / 4 ? UINT64_MAX / 2 : 2 * c->step;
            c->next = c->lead + c->step;
        }
    }
}

size_t contest_standing(const contest *c, size_t *idx, size_t cap)
{
    rank(c, c->order);
    for (size_t k = 0; k < c->nin && k < cap; k++)
        idx[k] = c->in[c->order[k]];
    return c->nin;
}

size_t contest_entrants(const contest *c)
{
    return c->entrants;
}

uint64_t contest_unit(const contest *c)
{
    return c->unit;
}

uint64_t contest_lead(const contest *c)
{
    return c->lead;
}

size_t contest_rounds(const contest *c, const uint64_t **at, const size_t **kept)
{
    *at = c->at;
    *kept = c->kept;
    return c->rounds;
}

bool contest_retired(const contest *c, size_t i)
{
    return member(c->retired, c->nretired, i);
}

size_t contest_dropped(const contest *c, const size_t **idx, const uint64_t **at,
                       const uint64_t **cycles)
{
    *idx = c->retired;
    *at = c->retired_at;
    *cycles = c->retired_cycles;
    return c->nretired;
}

bool contest_stopped(const contest *c, size_t k, uint64_t *leader)
{
    *leader = k < c->nretired ? c->retired_leader[k] : 0;
    return k < c->nretired && c->retired_margin[k];
}

void contest_free(contest *c)
{
    if (!c)
        return;
    free(c->retired_leader);
    free(c->retired_margin);
    free(c->prev);
    free(c->in);
    free(c->pinned);
    free(c->retired);
    free(c->retired_at);
    free(c->retired_cycles);
    free(c->order);
    free(c->total);
    free(c->strategy);
    free(c);
}

/* ---- over a trace file (emm/replay.h) ------------------------------------- */

emm_status emm_contest_trace(const char *path, const emm_machine *m, const emm_strategy *predicted,
                             uint64_t lead, uint64_t unit, unsigned finalists,
                             const emm_threads *threads, emm_contest_result *out, emm_error *err)
{
    memset(out, 0, sizeof *out);
    emm_trace_reader *r = NULL;
    emm_runner *run = NULL;
    contest *c = NULL;
    emm_trace_record *buf = NULL;
    size_t count = 0, n = 0;
    emm_strategy *list = NULL, *sweep = NULL;
    emm_error *errs = NULL;
    size_t *idx = NULL;
    bool *pinned = NULL;
    emm_status st;
    if ((st = emm_trace_reader_open(path, &r, err)) != EMM_OK)
        goto out;
    /* A mesh with depth brings the layouts in space into the sweep. */
    const emm_trace_geometry *g = &emm_trace_reader_info(r)->geometry;
    int depth = emm_geometry_has_depth(g->xyz, g->nv, g->tri, g->nt);
    size_t plain = emm_strategy_sweep_for(depth, NULL, 0);
    /* As the run's contest: the indexed variants join on a mesh whose
     * look-up tables are paged. */
    count = plain + (emm_indexed_joins_contest(g->nv, g->nt,
                                               emm_machine_get(m, "emm.lookup_budget"))
                         ? emm_strategy_sweep_indexed(depth, NULL, 0)
                         : 0);
    list = calloc(count + 1, sizeof *list);
    errs = calloc(count + 1, sizeof *errs);
    idx = calloc(count + 1, sizeof *idx);
    pinned = calloc(count + 1, sizeof *pinned);
    sweep = calloc(count, sizeof *sweep);
    if (!list || !errs || !idx || !pinned || !sweep) {
        st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the contest", path);
        goto out;
    }
    /* The prediction first (kept running to the end, to set against the
     * answer), then every other candidate of the sweep the machine offers. */
    list[n++] = *predicted;
    emm_strategy_sweep_for(depth, sweep, plain);
    if (count > plain)
        emm_strategy_sweep_indexed(depth, sweep + plain, count - plain);
    for (size_t i = 0; i < count; i++)
        if (emm_machine_offers(m, &sweep[i]) && memcmp(&sweep[i], predicted, sizeof *predicted))
            list[n++] = sweep[i];
    for (size_t i = 0; i < n; i++) {
        idx[i] = i;
        pinned[i] = i == 0 || contest_pins(&list[i]);
    }
    if ((st = emm_runner_new(threads, &run, err)) != EMM_OK ||
        (st = emm_runner_add(run, m, list, n, emm_trace_reader_info(r), errs, err)) != EMM_OK ||
        (st = contest_new(run, idx, pinned, n, lead, unit, finalists, &c, err)) != EMM_OK)
        goto out;
    enum { BATCH = 65536 };
    if (!(buf = malloc(BATCH * sizeof *buf))) {
        st = emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory for the contest", path);
        goto out;
    }
    for (;;) {
        size_t got;
        if ((st = emm_trace_read(r, buf, BATCH, &got, err)) != EMM_OK)
            goto out;
        if (got == 0)
            break;
        contest_run(c, buf, got);
        out->accesses += got;
    }
    size_t top[2];
    size_t in = contest_standing(c, top, 2);
    if (in == 0) {
        st = emm_fail(err, EMM_ERR_UNSUPPORTED, "%s: no candidate can be simulated on this trace",
                      path);
        goto out;
    }
    emm_model_result(emm_runner_model(run, top[0]), &out->answer);
    if (in >= 2) {
        emm_model_result(emm_runner_model(run, top[1]), &out->runner_up);
        out->has_runner_up = 1;
    }
    if (emm_runner_model(run, 0)) {
        emm_model_result(emm_runner_model(run, 0), &out->predicted);
        out->has_predicted = 1;
    }
    const uint64_t *at;
    const size_t *kept;
    size_t rounds = contest_rounds(c, &at, &kept);
    out->entrants = contest_entrants(c);
    out->finalists = rounds ? kept[rounds - 1] : out->entrants;
    out->rounds = rounds;
out:
    free(buf);
    contest_free(c);
    emm_runner_free(run);
    if (r)
        emm_trace_reader_close(r);
    free(list);
    free(errs);
    free(idx);
    free(pinned);
    free(sweep);
    return st;
}
