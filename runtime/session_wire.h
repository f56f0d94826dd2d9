/* Internal: the frames between a session's proxy (session_proxy.c, inside
 * the program) and emm-session, the process that serves it (server/), both
 * of one build (docs/architecture.md "The session").
 *
 * A frame is a fixed header and `len` bytes. Before the decision every call
 * waits for the server's REPLY; while it waits, the client answers the
 * server's READs (the program's bytes) and MODULES (its loaded objects).
 * After the decision accesses and iterations go without waiting. Neither
 * side trusts the other's lengths: a frame claims at most WIRE_FRAME_MAX
 * bytes, and a reader takes memory as the bytes arrive. */
#ifndef EMM_RUNTIME_SESSION_WIRE_H
#define EMM_RUNTIME_SESSION_WIRE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "emm/session.h"

#define WIRE_VERSION 4
/* The largest frame either side accepts: a mesh array's bytes. */
#define WIRE_FRAME_MAX ((uint64_t)1 << 40)

enum wire_op {
    WIRE_NEW = 1,
    WIRE_TAG,
    WIRE_MOVE,
    WIRE_UNTAG,
    WIRE_RANGES,
    WIRE_ACCESS,
    WIRE_ITERATION,
    WIRE_DECIDE,
    WIRE_FINISH,
    WIRE_BYTES, /* the answer to a READ or MODULES */
    /* server to client */
    WIRE_REPLY,
    WIRE_READ,
    WIRE_MODULES
};

struct wire_frame {
    uint32_t op;
    uint32_t wait;  /* client to server: the client waits for a REPLY */
    int64_t value;  /* a REPLY's answer; a READ's address */
    int32_t status; /* a REPLY's emm_status */
    uint32_t pad;
    uint64_t len;   /* bytes that follow */
};

/* Sends f and then a[0..alen) and b[0..blen) (either may be empty); false
 * when the other end is gone. Never raises SIGPIPE. */
bool wire_send(int fd, const struct wire_frame *f, const void *a, size_t alen, const void *b,
               size_t blen);
/* Reads exactly len bytes; false at the end of the stream or an error. */
bool wire_recv(int fd, void *buf, size_t len);
/* Reads f->len bytes into a malloc'ed buffer grown as they arrive (*data;
 * NULL for none). False at the end of the stream, or without memory. */
bool wire_recv_data(int fd, const struct wire_frame *f, unsigned char **data);

/* The start: what emm_session_new was given, the configuration as the
 * values that were set (each row's text and the name it came from; the tag
 * rules stay: descriptions come whole), the program's name and its pid. */
bool wire_start_encode(const emm_session_config *sc, long pid, unsigned char **out, size_t *len);
/* Decodes a start into *cfg (emm_config_init'ed first) and the rest. The
 * sources of cfg point into *strings, malloc'ed, which the caller frees
 * after the session is done with cfg; *program points into data. */
emm_status wire_start_decode(const unsigned char *data, size_t len, emm_config *cfg,
                             char **strings, emm_capture *capture, int *table_only,
                             unsigned *expect, const char **program, long *pid, emm_error *err);

/* A TAG's payload: the description, its origin as a string. */
bool wire_tag_encode(const emm_array_desc *d, unsigned char **out, size_t *len);
/* The description back; d->origin points into data. */
bool wire_tag_decode(const unsigned char *data, size_t len, emm_array_desc *d);

/* MODULES' answer: each module's bias, lo, hi and path. */
bool wire_modules_encode(const emm_trace_module *m, uint32_t n, unsigned char **out, size_t *len);
/* The modules back, malloc'ed in one block with their paths; false when
 * the bytes hold none or are malformed. */
bool wire_modules_decode(const unsigned char *data, size_t len, emm_trace_module **out,
                         uint32_t *n);

#endif
