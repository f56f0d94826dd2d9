/* A timeline with a small cap (emm_timeline_open's max_events): a model
 * that makes more events than the cap writes exactly the cap, and the
 * file's metadata says the cap was hit (timeline.py --capped checks the
 * JSON). Records: a walk over a grid mesh that changes cells often. */
#include <stdio.h>
#include <stdlib.h>

#include "check.h"
#include "emm/replay.h"
#include "emm/sim.h"

#define N 24 /* squares per side */

int main(int argc, char **argv)
{
    REQUIRE(argc == 2);
    static double xyz[3 * (N + 1) * (N + 1)];
    static int32_t tri[6 * N * N];
    for (int y = 0; y <= N; y++)
        for (int x = 0; x <= N; x++) {
            double *p = xyz + 3 * (y * (N + 1) + x);
            p[0] = x, p[1] = y, p[2] = 0;
        }
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++) {
            int32_t v = y * (N + 1) + x, *t = tri + 6 * (y * N + x);
            t[0] = v, t[1] = v + 1, t[2] = v + N + 2;
            t[3] = v, t[4] = v + N + 2, t[5] = v + N + 1;
        }
    emm_trace_array arrays[2] = {{EMM_ARRAY_VERTICES, 80, (N + 1) * (N + 1), 0x10000000u},
                                 {EMM_ARRAY_TRIANGLES, 28, 2 * N * N, 0x20000000u}};
    emm_trace_info info = {0};
    info.narrays = 2;
    info.arrays = arrays;
    info.geometry = (emm_trace_geometry){(N + 1) * (N + 1), 2 * N * N, xyz, tri};
    emm_error err;
    emm_machine *m;
    emm_strategy s;
    emm_model *model;
    emm_timeline *t;
    REQUIRE(emm_machine_new(&m, &err) == EMM_OK);
    REQUIRE(emm_machine_set(m, "local.bytes=16K", &err) == EMM_OK);
    REQUIRE(emm_strategy_parse("grid+naive@4", &s, &err) == EMM_OK);
    REQUIRE(emm_model_new(m, &s, &info, &model, &err) == EMM_OK);
    REQUIRE(emm_timeline_open(argv[1], m, &s, 40, &t, &err) == EMM_OK);
    CHECK(emm_timeline_watch(t, model) == 1);
    /* Triangles far apart, again and again: a cell change and a fetch each. */
    emm_trace_record r = {0};
    r.array = 1;
    r.bytes = 4;
    for (int i = 0; i < 2000; i++) {
        r.element = (uint64_t)(i * 97) % (2 * N * N);
        emm_model_run(model, &r, 1);
    }
    emm_result res;
    emm_model_result(model, &res);
    CHECK(res.dma.transfers > 40);
    emm_timeline_phase(t, "the whole walk", 0, res.total);
    CHECK(emm_timeline_close(t, model, res.total, &err) == EMM_OK);
    emm_model_free(model);
    emm_machine_free(m);
    return check_done();
}
