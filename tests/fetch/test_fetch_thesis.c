/* The behaviours thesis §4.1–4.2 and §6.3 predict, on the thesis' mesh
 * (20,000 clustered faces, emm_mesh_generate's defaults) with synthetic
 * traces. `ratio`: convolution over interleaving tiles issues about 25%
 * fewer prefetch DMAs per cell change than over the grid (6 neighbours
 * instead of 8). `region`: on region growing, convolution fetching beats
 * naive fetching. `curve`: on long curves, extrapolated fetching beats
 * naive fetching. Each prints what it measured. */
#include "fetch_util.h"

static const unsigned cells[] = {16, 32, 64};
#define NCELLS 3

/* Prefetch DMAs issued per cell change. */
static double per_change(const emm_result *r)
{
    return (double)r->emm.prefetches / (double)r->emm.cell_changes;
}

/* The thesis' count is of its plain scheme "whenever the EMM optimization
 * requires prefetching all surrounding cells" (§4.1.2): random visits leave
 * most neighbours of a cell not resident, and emm's prefetch filter is off
 * (emm.prefetch_filter=0) so every missing neighbour is fetched. With the
 * filter on, most of those prefetches are skipped on random visits, for
 * both layouts alike; that is checked too. */
static void ratio(const emm_mesh *mesh, emm_machine *mc)
{
    emm_synth_options so = {.pattern = EMM_PATTERN_RANDOM, .seed = 1};
    loaded_trace t;
    emm_error err;
    synth_load(mesh, &so, "fetch_thesis_ratio.emmt", &t);
    for (int i = 0; i < NCELLS; i++) {
        char g[64], ti[64];
        emm_result rg, rt, fg, ft;
        snprintf(g, sizeof g, "grid+convolution@%u", cells[i]);
        snprintf(ti, sizeof ti, "tiles+convolution@%u", cells[i]);
        REQUIRE(emm_machine_set(mc, "emm.prefetch_filter=0", &err) == EMM_OK);
        simulate_ok(mc, g, &t, &rg);
        simulate_ok(mc, ti, &t, &rt);
        REQUIRE(emm_machine_set(mc, "emm.prefetch_filter=1", &err) == EMM_OK);
        simulate_ok(mc, g, &t, &fg);
        simulate_ok(mc, ti, &t, &ft);
        double q = per_change(&rt) / per_change(&rg);
        printf("random @%u: prefetch DMAs per cell change, thesis scheme: grid %.3f, tiles %.3f, "
               "ratio %.3f; with the filter: grid %.3f, tiles %.3f\n",
               cells[i], per_change(&rg), per_change(&rt), q, per_change(&fg), per_change(&ft));
        CHECKF(q >= 0.6 && q <= 0.9, "@%u: ratio %.3f", cells[i], q);
        CHECK(rg.emm.filtered_prefetches == 0 && rt.emm.filtered_prefetches == 0);
        CHECK(ft.emm.filtered_prefetches > 0 && fg.emm.filtered_prefetches > 0);
        CHECK(per_change(&fg) < per_change(&rg) && per_change(&ft) < per_change(&rt));
    }
    free_trace(&t);
}

/* The best of `fetch` over the layouts (the first nl of grid, tiles,
 * quadtree) and cells, and the same for naive. */
static void compare(const emm_machine *mc, const loaded_trace *t, const char *fetch,
                    const char *what, int nl)
{
    static const char *const layouts[] = {"grid", "tiles", "quadtree"};
    uint64_t best_f = UINT64_MAX, best_n = UINT64_MAX;
    char bf[64] = "", bn[64] = "";
    for (int l = 0; l < nl; l++)
        for (int i = 0; i < NCELLS; i++) {
            char f[64], n[64];
            emm_result rf, rn;
            snprintf(f, sizeof f, "%s+%s@%u", layouts[l], fetch, cells[i]);
            snprintf(n, sizeof n, "%s+naive@%u", layouts[l], cells[i]);
            simulate_ok(mc, f, t, &rf);
            simulate_ok(mc, n, t, &rn);
            printf("%s: %-26s %12llu   %-20s %12llu  (%.3f)\n", what, f,
                   (unsigned long long)rf.total, n, (unsigned long long)rn.total,
                   (double)rf.total / (double)rn.total);
            if (rf.total < best_f)
                best_f = rf.total, snprintf(bf, sizeof bf, "%s", f);
            if (rn.total < best_n)
                best_n = rn.total, snprintf(bn, sizeof bn, "%s", n);
        }
    printf("%s: best %s %llu, best naive %s %llu\n", what, bf, (unsigned long long)best_f, bn,
           (unsigned long long)best_n);
    CHECKF(best_f < best_n, "%s: best %s %llu >= best naive %s %llu", what, bf,
           (unsigned long long)best_f, bn, (unsigned long long)best_n);
}

/* Breadth-first growth from a seed over the whole mesh, on the thesis'
 * machine, over grid and tiles (the layouts the thesis pairs with region
 * growing: "we don't consider Quadtree in this case", §4.3.2): convolution
 * beats naive, also where the local store holds only part of the growing
 * ring, because the prefetch filter stops re-prefetching cells whose
 * prefetch was wasted (docs/fetch.md, "Prefetch filter"). Again with a
 * 1 MiB local store, where the ring fits. */
static void region(const emm_mesh *mesh, emm_machine *mc)
{
    emm_synth_options so = {.pattern = EMM_PATTERN_REGION, .seed = 1, .work = 10};
    emm_error err;
    loaded_trace t;
    synth_load(mesh, &so, "fetch_thesis_region.emmt", &t);
    compare(mc, &t, "convolution", "region 256K", 2);
    REQUIRE(emm_machine_set(mc, "local.bytes=1M", &err) == EMM_OK);
    compare(mc, &t, "convolution", "region 1M", 2);
    free_trace(&t);
}

/* Straight walks to the boundary from random starts (thesis §6.3, long
 * curves), 100,000 triangle visits. */
static void curve(const emm_mesh *mesh, const emm_machine *mc)
{
    emm_synth_options so = {.pattern = EMM_PATTERN_CURVE, .seed = 1, .visits = 100000,
                            .length = 0, .work = 10};
    loaded_trace t;
    synth_load(mesh, &so, "fetch_thesis_curve.emmt", &t);
    compare(mc, &t, "extrapolated", "curve", 3);
    free_trace(&t);
}

int main(int argc, char **argv)
{
    emm_machine *mc;
    emm_error err;
    emm_mesh *mesh;
    if (argc != 2)
        return 2;
    mesh = thesis_mesh(EMM_DEFAULT_FACES);
    REQUIRE(emm_machine_new(&mc, &err) == EMM_OK);
    /* The synthetic traces' work is the program's compute between accesses,
     * 10 cycles a record, which prefetching overlaps: charged, as the
     * default machine does not (docs/machine.md "Compute"). */
    REQUIRE(emm_machine_set(mc, "compute.per_work=1", &err) == EMM_OK);
    if (strcmp(argv[1], "ratio") == 0)
        ratio(mesh, mc);
    else if (strcmp(argv[1], "region") == 0)
        region(mesh, mc);
    else if (strcmp(argv[1], "curve") == 0)
        curve(mesh, mc);
    else
        return 2;
    emm_machine_free(mc);
    emm_mesh_free(mesh);
    return check_done();
}
