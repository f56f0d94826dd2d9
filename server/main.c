/* emm-session: the session of a program that runs under Valgrind, run
 * natively beside it (runtime/session_proxy.c starts it). libemmshim.so
 * starts it inside the client with a socket as fd 3; `emm run --capture
 * valgrind` tells Valgrind not to trace it (--trace-children-skip). Not
 * for users: started by hand it says so. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>

#include "server.h"

int main(int argc, char **argv)
{
    int type = 0;
    socklen_t len = sizeof type;
    if (argc != 2 || strcmp(argv[1], "3") != 0 ||
        getsockopt(3, SOL_SOCKET, SO_TYPE, &type, &len) != 0 || type != SOCK_STREAM) {
        fprintf(stderr, "emm-session: the session server of emm run --capture valgrind; "
                        "libemmshim.so starts it, not a user\n");
        return 2;
    }
    emm_error err;
    if (emm_server_serve(3, &err) != EMM_OK) {
        fprintf(stderr, "emm: %s\n", err.message);
        return 1;
    }
    return 0;
}
