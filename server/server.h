/* emm-session's body (server/server.c), for its main and for the fuzz
 * harness of the frames it reads. */
#ifndef EMM_SERVER_H
#define EMM_SERVER_H

#include "emm/common.h"

/* Serves one program's session over the socket `fd` (the other end is a
 * handle made with emm_session_config.server) until the program closes it.
 * Returns when the program has gone; the session's outputs were written at
 * its finish, after which `done` (a descriptor, or -1) is closed: emm run,
 * which started the server, need not wait for it to free its memory and
 * end. A malformed frame ends the service with an error. */
emm_status emm_server_serve(int fd, int done, emm_error *err);

#endif
