/* Per-cell DMA bytes of the EMM model (simulator/emm_fetch.c,
 * emm_model_cells): for every layout and fetch scheme, on a region-growing
 * and a curve trace, the cells' bytes add up to the result's dma.bytes,
 * every cell is there with its layout rectangle, a reset clears them, and a
 * model without cells (direct, cache) leaves the result's cells empty. */
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "emm/mesh.h"
#include "emm/replay.h"
#include "emm/sim.h"
#include "emm/synth.h"
#include "emm/trace.h"

static uint64_t sum_cells(const emm_result *r)
{
    uint64_t s = 0;
    for (uint32_t c = 0; c < r->cells.count; c++)
        s += r->cells.cell[c].bytes;
    return s;
}

static void check_trace(const char *path, const emm_machine *m)
{
    static const char *const names[] = {
        "grid+naive@16",          "grid+convolution@32",      "grid+extrapolated@64",
        "tiles+naive@64",         "tiles+convolution@16",     "tiles+extrapolated@128",
        "quadtree+naive@32",      "quadtree+convolution@64",  "quadtree+extrapolated@16",
        "direct",                 "cache",                    "cache@tiles",
    };
    enum { N = sizeof names / sizeof names[0] };
    emm_strategy s[N];
    emm_result res[N];
    emm_error err;
    emm_replay_options opt;

    for (size_t i = 0; i < N; i++)
        REQUIRE(emm_strategy_parse(names[i], &s[i], &err) == EMM_OK);
    memset(&opt, 0, sizeof opt);
    opt.jobs = 2;
    opt.cells = 1;
    REQUIRE(emm_replay_ex(path, m, s, N, &opt, res, NULL, NULL, &err) == EMM_OK);
    for (size_t i = 0; i < N; i++) {
        const emm_result *r = &res[i];
        if (s[i].kind != EMM_STRATEGY_EMM) {
            CHECKF(r->cells.cell == NULL && r->cells.count == 0, "%s has cells", names[i]);
            continue;
        }
        REQUIRE(r->cells.cell != NULL);
        CHECK(r->cells.count > 0);
        CHECKF(r->dma.bytes > 0, "%s moved nothing", names[i]);
        CHECKF(sum_cells(r) == r->dma.bytes, "%s: cells add up to %llu, dma.bytes %llu", names[i],
               (unsigned long long)sum_cells(r), (unsigned long long)r->dma.bytes);
        CHECK(sum_cells(r) == r->emm.demand_bytes + r->emm.prefetch_bytes);
        for (uint32_t c = 0; c < r->cells.count; c++) {
            const emm_cell_dma *cell = &r->cells.cell[c];
            double w = r->cells.hi[0] - r->cells.lo[0];
            CHECK(cell->lo[0] <= cell->hi[0] && cell->lo[1] <= cell->hi[1]);
            /* Tiles at a row's ends reach half a tile past the box. */
            CHECK(cell->lo[0] >= r->cells.lo[0] - w && cell->hi[0] <= r->cells.hi[0] + w);
            CHECK(cell->lo[1] >= r->cells.lo[1] - 1e-9 && cell->hi[1] <= r->cells.hi[1] + 1e-9);
        }
    }
    for (size_t i = 0; i < N; i++)
        emm_result_release(&res[i]);
    for (size_t i = 0; i < N; i++)
        CHECK(res[i].cells.cell == NULL && res[i].cells.count == 0);
}

/* The model API directly: cells without replay, and a reset. */
static void check_reset(const char *path, const emm_machine *m)
{
    emm_trace_reader *rd;
    emm_model *model, *direct;
    emm_strategy s, d;
    emm_result r, rd_res;
    emm_trace_record buf[4096];
    size_t got;
    emm_error err;

    REQUIRE(emm_trace_reader_open(path, &rd, &err) == EMM_OK);
    REQUIRE(emm_strategy_parse("tiles+convolution@32", &s, &err) == EMM_OK);
    REQUIRE(emm_strategy_parse("direct", &d, &err) == EMM_OK);
    REQUIRE(emm_model_new(m, &s, emm_trace_reader_info(rd), &model, &err) == EMM_OK);
    REQUIRE(emm_model_new(m, &d, emm_trace_reader_info(rd), &direct, &err) == EMM_OK);
    REQUIRE(emm_trace_read(rd, buf, 4096, &got, &err) == EMM_OK && got > 0);
    emm_model_run(model, buf, got);
    emm_model_run(direct, buf, got);
    emm_model_result(model, &r);
    REQUIRE(emm_model_cells(model, &r, &err) == EMM_OK);
    CHECK(sum_cells(&r) == r.dma.bytes && r.dma.bytes > 0);
    emm_result_release(&r);
    emm_model_reset(model);
    emm_model_result(model, &r);
    REQUIRE(emm_model_cells(model, &r, &err) == EMM_OK);
    CHECK(r.cells.count > 0 && sum_cells(&r) == 0);
    emm_result_release(&r);
    emm_model_result(direct, &rd_res);
    CHECK(emm_model_cells(direct, &rd_res, &err) == EMM_OK && rd_res.cells.cell == NULL);
    emm_result_release(&rd_res);
    emm_model_free(model);
    emm_model_free(direct);
    emm_trace_reader_close(rd);
}

int main(void)
{
    emm_gen_options g = {3000, 5, EMM_DENSITY_CLUSTERED, EMM_ORDER_INPUT};
    emm_mesh *mesh;
    emm_machine *m;
    emm_error err;
    char region[64], curve[64];
    emm_synth_options so;

    snprintf(region, sizeof region, "/tmp/emm-cellbytes-%ld-r.emmt", (long)getpid());
    snprintf(curve, sizeof curve, "/tmp/emm-cellbytes-%ld-c.emmt", (long)getpid());
    REQUIRE(emm_mesh_generate(&g, &mesh, &err) == EMM_OK);
    REQUIRE(emm_machine_new(&m, &err) == EMM_OK);
    memset(&so, 0, sizeof so);
    so.pattern = EMM_PATTERN_REGION;
    so.seed = 7;
    so.work = 2;
    REQUIRE(emm_synth_trace(mesh, &so, region, NULL, &err) == EMM_OK);
    so.pattern = EMM_PATTERN_CURVE;
    so.length = 40;
    REQUIRE(emm_synth_trace(mesh, &so, curve, NULL, &err) == EMM_OK);
    check_trace(region, m);
    check_trace(curve, m);
    check_reset(curve, m);
    unlink(region);
    unlink(curve);
    emm_machine_free(m);
    emm_mesh_free(mesh);
    return check_done();
}
