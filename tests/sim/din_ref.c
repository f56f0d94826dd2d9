/* Test helper: Dinero IV's view of a din file, computed by the reference
 * model of ref_cache.h (docs/dinero.md):
 *   din_ref --generate N SEED            print a din trace of N references
 *   din_ref FILE [--fetch d|m|a] [--size S] [--assoc A] [--line L]
 *                                        print Dinero's counts for FILE
 *   din_ref FILE --write-trace OUT       write FILE as an emm trace, the
 *                                        way Dinero reads it (address & ~3,
 *                                        4 bytes, ifetches skipped)
 * din (dinfmt.c): one "LABEL ADDRESS" per line, both hex; 0 read, 1 write,
 * 2 instruction fetch (goes to memory when only a data cache is given),
 * 3 misc (a read that never prefetches). */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "emm/trace.h"
#include "ref_cache.h"

struct ref { uint64_t addr; int label; };

static struct ref *read_din(const char *path, size_t *n)
{
    FILE *f = fopen(path, "r");
    struct ref *v = NULL;
    size_t cap = 0;
    unsigned label;
    uint64_t addr;
    char line[256];
    *n = 0;
    if (!f) {
        perror(path);
        exit(2);
    }
    while (fgets(line, sizeof line, f)) {
        if (sscanf(line, "%x %" SCNx64, &label, &addr) != 2) {
            fprintf(stderr, "%s: bad line '%s'\n", path, line);
            exit(2);
        }
        if (*n == cap) {
            cap = cap ? 2 * cap : 1024;
            v = realloc(v, cap * sizeof *v);
            if (!v)
                exit(2);
        }
        v[*n].addr = addr & ~(uint64_t)3; /* dinfmt.c: word-oriented */
        v[*n].label = (int)label;
        (*n)++;
    }
    fclose(f);
    return v;
}

static uint64_t state;
static uint64_t rnd(void)
{
    uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

int main(int argc, char **argv)
{
    if (argc == 4 && strcmp(argv[1], "--generate") == 0) {
        uint64_t n = strtoull(argv[2], NULL, 10), a = 0x1000;
        state = strtoull(argv[3], NULL, 10);
        for (uint64_t i = 0; i < n; i++) {
            uint64_t r = rnd();
            if (r % 10 == 0)
                a = 0x1000 + rnd() % (1u << 20);     /* jump within 1 MiB */
            else if (r % 10 < 8)
                a += 4 * (1 + rnd() % 6);            /* walk */
            else
                a = 0x200000 + (rnd() % 64) * 4096;  /* a hot, conflicting set */
            /* labels 0 and 1, some unaligned addresses, a few ifetches */
            printf("%d %" PRIx64 "\n", r % 97 == 0 ? 2 : (r % 5 == 0 ? 1 : 0),
                   a + (r % 13 == 0 ? 2 : 0));
        }
        return 0;
    }
    if (argc < 2) {
        fprintf(stderr, "usage: see the comment in din_ref.c\n");
        return 2;
    }
    {
        size_t n;
        struct ref *v = read_din(argv[1], &n);
        char fetch = 'm';
        uint64_t size = 256 * 1024, assoc = 4, line = 64;
        const char *out = NULL;
        for (int i = 2; i + 1 < argc; i += 2) {
            if (strcmp(argv[i], "--fetch") == 0) fetch = argv[i + 1][0];
            else if (strcmp(argv[i], "--size") == 0) size = strtoull(argv[i + 1], NULL, 10);
            else if (strcmp(argv[i], "--assoc") == 0) assoc = strtoull(argv[i + 1], NULL, 10);
            else if (strcmp(argv[i], "--line") == 0) line = strtoull(argv[i + 1], NULL, 10);
            else if (strcmp(argv[i], "--write-trace") == 0) out = argv[i + 1];
            else return 2;
        }
        if (out) {
            uint64_t max = 0;
            emm_trace_array arr = {EMM_ARRAY_RAW, 1, 0, 0};
            emm_trace_geometry geo = {0, 0, NULL, NULL};
            emm_trace_writer *w;
            emm_error err;
            for (size_t i = 0; i < n; i++)
                if (v[i].addr + 4 > max)
                    max = v[i].addr + 4;
            arr.count = max;
            if (emm_trace_writer_open(out, &arr, 1, &geo, 0, &w, &err) != EMM_OK) {
                fprintf(stderr, "%s\n", err.message);
                return 1;
            }
            for (size_t i = 0; i < n; i++) {
                emm_trace_record r;
                if (v[i].label == 2)
                    continue;
                memset(&r, 0, sizeof r);
                r.element = v[i].addr;
                r.bytes = 4;
                r.write = v[i].label == 1;
                if (emm_trace_write(w, &r, 1, &err) != EMM_OK) {
                    fprintf(stderr, "%s\n", err.message);
                    return 1;
                }
            }
            if (emm_trace_writer_close(w, &err) != EMM_OK) {
                fprintf(stderr, "%s\n", err.message);
                return 1;
            }
        } else {
            ref_cache r;
            ref_init(&r, size, assoc, line, fetch);
            for (size_t i = 0; i < n; i++) {
                if (v[i].label == 2)
                    continue; /* no instruction cache: ifetches go to memory */
                if (v[i].label == 3) {
                    /* misc: a demand reference that neither prefetches nor writes */
                    int hit = ref_touch(&r, v[i].addr / line);
                    r.demand_fetches++;
                    r.demand_misses += !hit;
                    continue;
                }
                ref_access(&r, v[i].addr, 4, v[i].label == 1);
            }
            printf("demand_fetches %llu\ndemand_misses %llu\nprefetch_fetches %llu\n"
                   "prefetch_misses %llu\n",
                   (unsigned long long)r.demand_fetches, (unsigned long long)r.demand_misses,
                   (unsigned long long)r.prefetch_fetches, (unsigned long long)r.prefetch_misses);
            ref_free(&r);
        }
        free(v);
    }
    return 0;
}
