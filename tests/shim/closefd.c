/* A program that closes its standard descriptors and then opens three data
 * files, which get descriptors 0, 1 and 2 — the third is where stderr was.
 * It walks its mesh (allocated in load_grid, for an EMM_TAG rule) first,
 * then writes a checksum into each file, and a line of its own to "stderr"
 * (the third file). Under emm the files must be the native run's byte for
 * byte: emm's lines go to the stderr the program started with, never into
 * a file the program opened. With "all" it first closes every descriptor
 * from 3 up, as a daemon does (under valgrind capture the socket to
 * emm-session goes with them).
 *   test_shim_closefd DIR [all] */
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

struct vert { uint32_t id; double xyz[3]; };
struct tri { uint32_t id; int32_t v[3]; };

#define N 48

static __attribute__((noinline)) int load_grid(struct vert **vs, struct tri **ts, size_t *nt)
{
    struct vert *v = malloc(sizeof *v * N * N);
    struct tri *t = malloc(sizeof *t * 2 * (N - 1) * (N - 1));
    if (!v || !t)
        return -1;
    for (int i = 0; i < N * N; i++)
        v[i] = (struct vert){(uint32_t)i, {i % N, i / N, 0}};
    size_t k = 0;
    for (int y = 0; y + 1 < N; y++)
        for (int x = 0; x + 1 < N; x++) {
            int a = y * N + x;
            t[k] = (struct tri){(uint32_t)k, {a, a + 1, a + N}};
            k++;
            t[k] = (struct tri){(uint32_t)k, {a + 1, a + N + 1, a + N}};
            k++;
        }
    *vs = v;
    *ts = t;
    *nt = k;
    return 0;
}

int main(int argc, char **argv)
{
    if (argc != 2 && (argc != 3 || strcmp(argv[2], "all") != 0))
        return 2;
    struct vert *v;
    struct tri *t;
    size_t nt;
    if (load_grid(&v, &t, &nt) != 0)
        return 1;
    double sum = 0;
    for (int pass = 0; pass < 2; pass++)
        for (size_t i = 0; i < nt; i++)
            for (int c = 0; c < 3; c++)
                sum += v[t[i].v[c]].xyz[0] + 2 * v[t[i].v[c]].xyz[1];
    for (int fd = argc == 3 ? 1023 : 2; fd >= 0; fd--)
        close(fd);
    char path[4096];
    for (int i = 0; i < 3; i++) {
        snprintf(path, sizeof path, "%s/%c.dat", argv[1], 'a' + i);
        if (open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644) != i)
            return 3;
    }
    for (int fd = 0; fd < 3; fd++)
        dprintf(fd, "file %d: %zu triangles, sum %.1f\n", fd, nt, sum);
    fprintf(stderr, "the program's own stderr line\n");
    free(v);
    free(t);
    return 0;
}
