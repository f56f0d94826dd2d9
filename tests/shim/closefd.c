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

#include "grid.h"

int main(int argc, char **argv)
{
    if (argc != 2 && (argc != 3 || strcmp(argv[2], "all") != 0))
        return 2;
    struct vert *v;
    struct tri *t;
    size_t nt;
    if (load_grid(48, &v, &t, &nt) != 0)
        return 1;
    double sum = 0;
    for (int pass = 0; pass < 2; pass++)
        sum += walk_grid(v, t, nt);
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
