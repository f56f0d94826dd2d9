/* A program that loads a mesh of its own (load_grid, a 40 x 40 grid),
 * walks it, then starts another program that does the same (argv[1], with
 * its arguments; fork and exec, LD_PRELOAD carried along) and walks its
 * mesh again once the child is done. Under emm each process keeps its own
 * report: neither writes over the other's.
 *   test_shim_parent PROGRAM [ARGS...] */
#include <sys/wait.h>
#include <unistd.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

struct vert { uint32_t id; double xyz[3]; };
struct tri { uint32_t id; int32_t v[3]; };

#define N 40


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

static double walk(const struct vert *v, const struct tri *t, size_t nt)
{
    double sum = 0;
    for (size_t i = 0; i < nt; i++)
        for (int c = 0; c < 3; c++)
            sum += v[t[i].v[c]].xyz[0] + 2 * v[t[i].v[c]].xyz[1];
    return sum;
}

int main(int argc, char **argv)
{
    if (argc < 2)
        return 2;
    struct vert *v;
    struct tri *t;
    size_t nt;
    if (load_grid(&v, &t, &nt) != 0)
        return 1;
    double sum = walk(v, t, nt);
    fflush(stdout);
    pid_t pid = fork();
    if (pid < 0)
        return 1;
    if (pid == 0) {
        execv(argv[1], argv + 1);
        _exit(127);
    }
    int status;
    if (waitpid(pid, &status, 0) != pid)
        return 1;
    sum += walk(v, t, nt);
    printf("parent: sum %.1f, child %d\n", sum, WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    free(v);
    free(t);
    return 0;
}
