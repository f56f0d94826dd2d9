/* Speed and size of trace files on a traversal-like access stream (not a
 * test: it prints numbers). Usage: trace_bench [RECORDS] [DIR]
 * The stream: a walk over a 20,000-triangle mesh, each step reading a
 * triangle's vertex indices and then its three vertices' coordinates, with
 * ids that move locally, as in curve tracing and region growing. */
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "emm/trace.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts); /* CPU time: the machine may be busy */
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static uint64_t rng = 88172645463325252ull;
static uint64_t rnd(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

static void gen(emm_trace_record *r, size_t n, uint64_t *t)
{
    for (size_t i = 0; i + 4 <= n; i += 4) {
        *t = (*t + 20000 + rnd() % 61 - 30) % 20000;
        r[i] = (emm_trace_record){.element = *t, .array = 1, .offset = 4, .bytes = 12,
                                  .work = (uint32_t)(rnd() % 16)};
        for (int k = 1; k <= 3; k++)
            r[i + k] = (emm_trace_record){.element = (*t / 2 + 10000 + rnd() % 41 - 20) % 10000,
                                          .array = 0, .offset = 8, .bytes = 24,
                                          .work = (uint32_t)(rnd() % 4),
                                          .write = (uint8_t)(rnd() % 16 == 0)};
    }
}

int main(int argc, char **argv)
{
    size_t total = argc > 1 ? (size_t)strtoull(argv[1], NULL, 10) : 20000000;
    const char *dir = argc > 2 ? argv[2] : "/tmp";
    const size_t piece = 1 << 20;
    const emm_trace_array arrays[2] = {{EMM_ARRAY_VERTICES, 80, 10000, 0x10000000},
                                       {EMM_ARRAY_TRIANGLES, 40, 20000, 0x20000000}};
    emm_trace_record *buf = malloc(piece * sizeof *buf);
    char path[512];
    for (int compress = 0; compress <= 1; compress++) {
        snprintf(path, sizeof path, "%s/trace_bench_%ld.emt", dir, (long)getpid());
        emm_error err;
        emm_trace_writer *w;
        if (emm_trace_writer_open(path, arrays, 2, NULL, compress, &w, &err) != EMM_OK) {
            fprintf(stderr, "%s\n", err.message);
            return 1;
        }
        uint64_t t = 0;
        double enc = 0;
        for (size_t done = 0; done < total; done += piece) {
            size_t k = total - done < piece ? total - done : piece;
            gen(buf, k, &t);
            double t0 = now();
            if (emm_trace_write(w, buf, k, &err) != EMM_OK) {
                fprintf(stderr, "%s\n", err.message);
                return 1;
            }
            enc += now() - t0;
        }
        double t0 = now();
        if (emm_trace_writer_close(w, &err) != EMM_OK) {
            fprintf(stderr, "%s\n", err.message);
            return 1;
        }
        enc += now() - t0;
        struct stat st;
        stat(path, &st);
        const size_t caps[2] = {piece, 1000};
        double dec[2] = {1e30, 1e30};
        for (int rep = 0; rep < 6; rep++) {
            int c = rep % 2; /* best of three for each buffer size */
            emm_trace_reader *r;
            if (emm_trace_reader_open(path, &r, &err) != EMM_OK) {
                fprintf(stderr, "%s\n", err.message);
                return 1;
            }
            size_t got, seen = 0;
            uint64_t sum = 0;
            t0 = now();
            while (emm_trace_read(r, buf, caps[c], &got, &err) == EMM_OK && got > 0) {
                seen += got;
                sum += buf[got - 1].element;
            }
            double dt = now() - t0;
            dec[c] = dt < dec[c] ? dt : dec[c];
            emm_trace_reader_close(r);
            if (seen != total) {
                fprintf(stderr, "read %zu of %zu records (%llu)\n", seen, total,
                        (unsigned long long)sum);
                return 1;
            }
        }
        printf("%-12s %zu records, %.2f bytes/record, encode %.1f M records/s, "
               "decode %.1f M records/s (buffer %zu), %.1f M records/s (buffer %zu)\n",
               compress ? "zstd" : "uncompressed", total, (double)st.st_size / (double)total,
               total / enc / 1e6, total / dec[0] / 1e6, caps[0], total / dec[1] / 1e6, caps[1]);
        remove(path);
    }
    free(buf);
    return 0;
}
