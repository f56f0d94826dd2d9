/* The pattern check's bounded sweep (runtime/table.c,
 * sweep_records_bounded) against the full one over the same records: the
 * fewest and second fewest cycles, the cache and every strategy not stopped
 * come out exactly as in full; a stopped one is a lower bound of its full
 * result and ends above the bound; some do stop (or the bound saves
 * nothing); and check_bounds_hold refuses a ranking a stopped strategy
 * could have changed. On synthetic traversals over a generated mesh, on
 * the default machine (no cache) and on one with a cache. */
#include <math.h>
#include <stdint.h>

#include "../fetch/fetch_util.h"
#include "emm/table.h"
#include "table_internal.h"

/* The sweep's two fewest cycles among offered strategies. */
static void two_least(const emm_machine *mc, const emm_sweep *s, size_t *a, size_t *b)
{
    *a = *b = SIZE_MAX;
    for (size_t i = 0; i < s->count; i++) {
        if (!s->ran[i] || !emm_machine_offers(mc, &s->result[i].strategy))
            continue;
        if (*a == SIZE_MAX || s->result[i].total < s->result[*a].total)
            *b = *a, *a = i;
        else if (*b == SIZE_MAX || s->result[i].total < s->result[*b].total)
            *b = i;
    }
}

static size_t one(const emm_machine *mc, const emm_mesh *mesh, emm_pattern pattern,
                  const char *what)
{
    emm_synth_options so = {.pattern = pattern, .seed = 3};
    loaded_trace t;
    emm_error err;
    char path[64];
    snprintf(path, sizeof path, "bounded_sweep_%d.emmt", (int)pattern);
    synth_load(mesh, &so, path, &t);
    emm_sweep *full = NULL, *b = NULL;
    uint8_t *partial = NULL;
    REQUIRE(sweep_records_shared(mc, t.info, t.recs, t.n, NULL, NULL, true, &full, &err) == EMM_OK);
    REQUIRE(sweep_records_bounded(mc, t.info, t.recs, t.n, NULL, NULL, &b, &partial, &err) ==
            EMM_OK);
    REQUIRE(partial != NULL);
    CHECK(b->count == full->count && b->simulated == full->simulated);
    CHECKF(b->best == full->best, "%s: best %zu, full %zu", what, b->best, full->best);
    size_t fa, fb, ba, bb;
    two_least(mc, full, &fa, &fb);
    two_least(mc, b, &ba, &bb);
    REQUIRE(fb != SIZE_MAX);
    CHECKF(fa == ba && fb == bb, "%s: the two fewest %zu %zu, full %zu %zu", what, ba, bb, fa, fb);
    uint64_t bound = full->result[fb].total + full->result[fb].total / 1000;
    size_t stopped = 0;
    for (size_t i = 0; i < full->count; i++) {
        CHECK(b->ran[i] == full->ran[i]);
        if (!full->ran[i])
            continue;
        uint64_t x = b->result[i].total, y = full->result[i].total;
        if (partial[i]) {
            stopped++;
            CHECKF(x <= y && y > bound, "%s: stopped strategy %zu: %llu of %llu, bound %llu", what,
                   i, (unsigned long long)x, (unsigned long long)y, (unsigned long long)bound);
            CHECK(i != full->best && i != fa && i != fb && i != full->cache);
        } else {
            CHECKF(x == y, "%s: strategy %zu: %llu, full %llu", what, i, (unsigned long long)x,
                   (unsigned long long)y);
        }
    }
    /* A ranking with the full sweep as W: it stands on the bounded S; it
     * does not when its pick or second was stopped, or when a stopped
     * strategy's lower bound scores below score2 (a W that makes the
     * second's score a whole S_best larger). */
    double sb = (double)b->result[b->best].total;
    CHECK(check_bounds_hold(mc, b, partial, full, NULL, ba, bb,
                            (double)b->result[bb].total / sb + 1e-6 * ((double)full->result[bb].total /
                                                                       (double)full->result[full->best].total)));
    CHECK(check_bounds_hold(mc, b, NULL, full, NULL, ba, bb, 0));
    if (stopped) {
        size_t s = 0;
        while (!partial[s])
            s++;
        CHECK(!check_bounds_hold(mc, b, partial, full, NULL, s, bb, INFINITY));
        CHECK(!check_bounds_hold(mc, b, partial, full, NULL, ba, s, INFINITY));
        CHECK(!check_bounds_hold(mc, b, partial, full, NULL, ba, bb, INFINITY));
    }
    printf("%s: %zu records, %zu strategies, %zu stopped early; fewest %llu, second %llu\n", what,
           t.n, b->simulated, stopped, (unsigned long long)full->result[fa].total,
           (unsigned long long)full->result[fb].total);
    emm_sweep_free(full);
    emm_sweep_free(b);
    free(partial);
    free_trace(&t);
    return stopped;
}

int main(void)
{
    emm_mesh *mesh = thesis_mesh(4000);
    emm_machine *plain, *cached;
    emm_error err;
    REQUIRE(emm_machine_new(&plain, &err) == EMM_OK);
    REQUIRE(emm_machine_new(&cached, &err) == EMM_OK);
    REQUIRE(emm_machine_set(cached, "cache.present=1", &err) == EMM_OK);
    size_t stopped = 0;
    stopped += one(plain, mesh, EMM_PATTERN_CURVE, "curve");
    stopped += one(plain, mesh, EMM_PATTERN_REGION, "region");
    stopped += one(plain, mesh, EMM_PATTERN_SCANLINE, "scanline");
    stopped += one(cached, mesh, EMM_PATTERN_RANDOM, "random, with a cache");
    CHECKF(stopped > 0, "no strategy stopped early: the bound saves nothing");
    emm_machine_free(plain);
    emm_machine_free(cached);
    emm_mesh_free(mesh);
    return check_done();
}
