/* A program that loads a mesh of its own (load_grid, a 40 x 40 grid),
 * walks it, then starts another program that does the same (argv[1], with
 * its arguments; fork and exec, LD_PRELOAD carried along) and walks its
 * mesh again once the child is done. Under emm each process keeps its own
 * report: neither writes over the other's.
 *   test_shim_parent PROGRAM [ARGS...] */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include "grid.h"


int main(int argc, char **argv)
{
    if (argc < 2)
        return 2;
    struct vert *v;
    struct tri *t;
    size_t nt;
    if (load_grid(40, &v, &t, &nt) != 0)
        return 1;
    double sum = walk_grid(v, t, nt);
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
    sum += walk_grid(v, t, nt);
    printf("parent: sum %.1f, child %d\n", sum, WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    free(v);
    free(t);
    return 0;
}
