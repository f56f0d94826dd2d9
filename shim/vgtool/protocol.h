/* The channel between libemmshim.so (shim/capture_valgrind.c, inside the
 * client) and emm's Valgrind tool (shim/vgtool/emm_tool.c, the static
 * binary Valgrind runs the client on). Shared by both; it needs only
 * <stdint.h>-sized types, since the tool is built without a C library.
 *
 * Client requests (valgrind.h's VALGRIND_DO_CLIENT_REQUEST_EXPR, a no-op
 * answering 0 outside Valgrind or under another tool):
 *   HELLO      -> EMM_VG_VERSION when emm's tool runs the client
 *   CHANNEL(c) the tool appends records to c->rec[0..c->cap) and diverts a
 *              thread to c->drain when the buffer is full
 *   RANGES(lo, hi, n)  the tagged ranges [lo[i], hi[i]); n == 0 pauses
 *              recording (the shim reading the arrays itself)
 *   TAKE       -> how many records c->rec holds (the shim feeds them to the
 *              session, then RELEASEs)
 *   RELEASE    -> the buffer is free again: the tool moves records that did
 *              not fit into it and answers how many it holds now
 *   LATER      the drain function was reached where it cannot drain (the
 *              thread is inside the shim or the allocator): not now
 *   STOP       a forked child: record nothing more
 *   BUSY(1)/BUSY(0)  around the shim's feeding of the session: the work the
 *              C library does meanwhile (the session's malloc, memcpy,
 *              qsort, the socket's send) is not the program's, so the
 *              record count of work goes back to what it was at BUSY(1)
 * Records are emm_raw_access (emm/session.h), laid out identically as
 * emm_vg_record below (capture_valgrind.c checks the layout). */
#ifndef EMM_VGTOOL_PROTOCOL_H
#define EMM_VGTOOL_PROTOCOL_H

#define EMM_VG_VERSION 2
/* Valgrind's tool request base for the two letters 'E', 'M'. */
#define EMM_VG_BASE (((unsigned)'E' & 0xff) << 24 | ((unsigned)'M' & 0xff) << 16)

enum emm_vg_request {
    EMM_VG_HELLO = EMM_VG_BASE,
    EMM_VG_CHANNEL,
    EMM_VG_RANGES,
    EMM_VG_TAKE,
    EMM_VG_RELEASE,
    EMM_VG_LATER,
    EMM_VG_STOP,
    EMM_VG_BUSY
};

/* The write flag in bytes_write, as EMM_RAW_WRITE. */
#define EMM_VG_WRITE 0x80000000u

struct emm_vg_record {
    unsigned long long addr;
    unsigned int bytes_write;
    unsigned int work; /* superblocks of the program's code run since the last record */
    unsigned long long pc;
};

/* In the client's memory, registered once with CHANNEL. */
struct emm_vg_channel {
    struct emm_vg_record *rec;
    unsigned long long cap;
    /* The client function a thread is sent to when the buffer is full, as
     * a signal handler interrupts a program: the tool makes the thread call
     * it at the start of a superblock of the program's own code (never
     * inside the C library, the loader or emm), 128 bytes below the stack
     * pointer (the red zone), with the return address pushed; it saves
     * every register and returns with `ret $128`. */
    unsigned long long drain;
};

#endif
