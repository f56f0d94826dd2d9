/* emm-session: the session of a program that runs under Valgrind, run
 * natively beside it. `emm run --capture valgrind` starts it with a socket
 * as fd 3 and the write end of a pipe as fd 4 (`emm-session 3 4`), which it
 * closes once its outputs are written; libemmshim.so starts it inside the
 * client with the socket alone (runtime/session_proxy.c), and emm run tells
 * Valgrind not to trace it (--trace-children-skip). Not for users: started
 * by hand it says so. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>

#include "server.h"

int main(int argc, char **argv)
{
    int type = 0;
    socklen_t len = sizeof type;
    struct stat st;
    int done = argc == 3 && strcmp(argv[2], "4") == 0 && fstat(4, &st) == 0 && S_ISFIFO(st.st_mode)
                   ? 4
                   : -1;
    if (argc < 2 || argc > 3 || (argc == 3 && done < 0) || strcmp(argv[1], "3") != 0 ||
        getsockopt(3, SOL_SOCKET, SO_TYPE, &type, &len) != 0 || type != SOCK_STREAM) {
        fprintf(stderr, "emm-session: the session server of emm run --capture valgrind; "
                        "libemmshim.so starts it, not a user\n");
        return 2;
    }
    emm_error err;
    if (emm_server_serve(3, done, &err) != EMM_OK) {
        fprintf(stderr, "emm: %s\n", err.message);
        return 1;
    }
    return 0;
}
