/* Writes small traces for the command-line test of emm profile and emm
 * table: `grid OUT` (a 48x48 grid mesh visited row by row, a triangle and
 * its three vertices per visit), `walk OUT` (the same mesh in a random
 * order), `raw OUT` (an address-only trace). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "emm/trace.h"

#define N 48

int main(int argc, char **argv)
{
    if (argc != 3)
        return 2;
    emm_error err;
    emm_trace_writer *w;
    if (strcmp(argv[1], "raw") == 0) {
        emm_trace_array a = {EMM_ARRAY_RAW, 1, 0, 0};
        emm_trace_geometry g = {0, 0, NULL, NULL};
        if (emm_trace_writer_open(argv[2], &a, 1, &g, 0, &w, &err) != EMM_OK)
            goto fail;
        for (uint64_t i = 0; i < 4096; i++) {
            emm_trace_record r = {0x1000 + 8 * i, 0, 0, 8, 1, 0, 0};
            if (emm_trace_write(w, &r, 1, &err) != EMM_OK)
                goto fail;
        }
        return emm_trace_writer_close(w, &err) == EMM_OK ? 0 : (fprintf(stderr, "%s\n", err.message), 1);
    }
    static double xyz[3 * (N + 1) * (N + 1)];
    static int32_t tri[3 * 2 * N * N];
    for (int y = 0; y <= N; y++)
        for (int x = 0; x <= N; x++) {
            double *p = xyz + 3 * (y * (N + 1) + x);
            p[0] = x;
            p[1] = y;
            p[2] = 0;
        }
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++) {
            int32_t v = y * (N + 1) + x, *t = tri + 6 * (y * N + x);
            t[0] = v, t[1] = v + 1, t[2] = v + N + 2;
            t[3] = v, t[4] = v + N + 2, t[5] = v + N + 1;
        }
    emm_trace_array a[2] = {{EMM_ARRAY_VERTICES, 80, (N + 1) * (N + 1), 0x10000000u},
                            {EMM_ARRAY_TRIANGLES, 28, 2 * N * N, 0x20000000u}};
    emm_trace_geometry g = {(N + 1) * (N + 1), 2 * N * N, xyz, tri};
    if (emm_trace_writer_open(argv[2], a, 2, &g, 0, &w, &err) != EMM_OK)
        goto fail;
    uint32_t order[2 * N * N];
    for (uint32_t t = 0; t < 2 * N * N; t++)
        order[t] = t;
    if (strcmp(argv[1], "walk") == 0) {
        uint64_t s = 7;
        for (uint32_t t = 2 * N * N; t > 1; t--) {
            s = s * 6364136223846793005ull + 1442695040888963407ull;
            uint32_t j = (uint32_t)((s >> 33) % t), x = order[t - 1];
            order[t - 1] = order[j];
            order[j] = x;
        }
    }
    for (uint32_t i = 0; i < 2 * N * N; i++) {
        emm_trace_record r[4] = {{order[i], 1, 4, 24, 1, 0, 0}};
        for (int k = 0; k < 3; k++)
            r[1 + k] = (emm_trace_record){(uint64_t)tri[3 * order[i] + k], 0, 8, 24, 1, 0, 0};
        if (emm_trace_write(w, r, 4, &err) != EMM_OK)
            goto fail;
    }
    if (emm_trace_writer_close(w, &err) != EMM_OK)
        goto fail;
    return 0;
fail:
    fprintf(stderr, "make_trace: %s\n", err.message);
    return 1;
}
