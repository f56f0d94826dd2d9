/* The valgrind capture backend (docs/design.md "The shim and the session", Capture
 * backends: valgrind): an unmodified binary's whole run, seen by emm's Valgrind tool
 * (shim/vgtool/emm_tool.c; `emm run --capture valgrind` starts it).
 *
 * The shim keeps tagging inside the client by interposition, as with every
 * backend; this file tells the tool the tagged ranges and takes its records
 * (shim/vgtool/protocol.h is the channel), at the agent's events:
 * - at start-up it registers a buffer of records and the drain function;
 * - the tool appends every access inside a tagged range to the buffer, in
 *   the order the threads ran (Valgrind runs one at a time: exact with
 *   threads), with the instruction's address as its program counter;
 * - the records go to the session whenever the shim flushes (a tag, a free,
 *   an iteration, the finish), and when the buffer fills the tool sends the
 *   running thread to shim_vg_trampoline, at the start of a superblock of
 *   the program's own code, as a signal handler interrupts a program: it
 *   saves every register, drains, and returns where the thread was;
 * - while the session reads the arrays itself (a snapshot before a free,
 *   the decision's geometry) the tool is told no ranges, so those reads are
 *   not the program's.
 * Outside Valgrind, or under another tool, the client requests answer 0 and
 * the backend is unavailable: init says how to start it. */
#include <stddef.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <valgrind/valgrind.h>

#include "shim.h"
#include "vgtool/protocol.h"

/* Records the buffer holds (24 bytes each). */
#define CHANNEL_RECORDS 65536

_Static_assert(sizeof(struct emm_vg_record) == sizeof(emm_raw_access), "record layout");
_Static_assert(offsetof(struct emm_vg_record, bytes_write) ==
                   offsetof(emm_raw_access, bytes_write) &&
               offsetof(struct emm_vg_record, work) == offsetof(emm_raw_access, work) &&
               offsetof(struct emm_vg_record, pc) == offsetof(emm_raw_access, pc),
               "record layout");
_Static_assert(EMM_VG_WRITE == EMM_RAW_WRITE, "write flag");

#define REQUEST(req, a1, a2, a3) \
    VALGRIND_DO_CLIENT_REQUEST_EXPR(0, (req), (a1), (a2), (a3), 0, 0)

static struct emm_vg_channel channel;
static bool connected;

/* Read by the trampoline: whether to save the AVX registers whole. */
unsigned char shim_vg_avx SHIM_HIDDEN;
void shim_vg_drain(void) SHIM_HIDDEN;
void shim_vg_trampoline(void) SHIM_HIDDEN;

/* Entered from the tool's diversion with the return address on the stack
 * and the red zone skipped (protocol.h); a signal handler's discipline:
 * every register the C call may change is saved, the flags too, x87 is
 * reset for the call and the direction flag cleared. */
__asm__(".text\n"
        ".globl shim_vg_trampoline\n"
        ".hidden shim_vg_trampoline\n"
        ".type shim_vg_trampoline,@function\n"
        "shim_vg_trampoline:\n"
        "  pushfq\n"
        "  cld\n"
        "  push %rax\n  push %rcx\n  push %rdx\n  push %rsi\n  push %rdi\n"
        "  push %r8\n  push %r9\n  push %r10\n  push %r11\n"
        "  push %rbp\n"
        "  mov %rsp, %rbp\n"
        "  and $-64, %rsp\n"
        "  sub $1024, %rsp\n"
        "  fxsave64 (%rsp)\n"
        "  cmpb $0, shim_vg_avx(%rip)\n"
        "  je 1f\n"
        "  .irp n,0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15\n"
        "  vmovdqu %ymm\\n, 512+32*\\n(%rsp)\n"
        "  .endr\n"
        "1:\n"
        "  fninit\n"
        "  call shim_vg_drain\n"
        "  cmpb $0, shim_vg_avx(%rip)\n"
        "  je 2f\n"
        "  .irp n,0,1,2,3,4,5,6,7,8,9,10,11,12,13,14,15\n"
        "  vmovdqu 512+32*\\n(%rsp), %ymm\\n\n"
        "  .endr\n"
        "2:\n"
        "  fxrstor64 (%rsp)\n"
        "  mov %rbp, %rsp\n"
        "  pop %rbp\n"
        "  pop %r11\n  pop %r10\n  pop %r9\n  pop %r8\n"
        "  pop %rdi\n  pop %rsi\n  pop %rdx\n  pop %rcx\n  pop %rax\n"
        "  popfq\n"
        "  ret $128\n"
        ".size shim_vg_trampoline, .-shim_vg_trampoline\n");

void shim_vg_drain(void)
{
    /* Inside the shim or the allocator the session cannot be entered (the
     * thread may hold the lock): the records wait for the next time. */
    if (shim_busy || shim_in_alloc || !emm_agent_active(shim.agent)) {
        REQUEST(EMM_VG_LATER, 0, 0, 0);
        return;
    }
    shim_flush_thread();
}

static bool on_emm_tool(void)
{
    return RUNNING_ON_VALGRIND && REQUEST(EMM_VG_HELLO, 0, 0, 0) == EMM_VG_VERSION;
}

static bool init(char *msg, size_t cap)
{
    if (!on_emm_tool()) {
        snprintf(msg, cap,
                 "EMM_CAPTURE=valgrind: %s is not running under emm's Valgrind tool "
                 "(start it with emm run --capture valgrind -- PROGRAM)",
                 program_invocation_short_name);
        return false;
    }
    size_t bytes = CHANNEL_RECORDS * sizeof(struct emm_vg_record);
    void *rec = mmap(NULL, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (rec == MAP_FAILED) {
        snprintf(msg, cap, "EMM_CAPTURE=valgrind: no memory for the record buffer");
        return false;
    }
    shim_vg_avx = __builtin_cpu_supports("avx") ? 1 : 0;
    channel.rec = rec;
    channel.cap = CHANNEL_RECORDS;
    channel.drain = (unsigned long long)(uintptr_t)shim_vg_trampoline;
    if (REQUEST(EMM_VG_CHANNEL, &channel, 0, 0) != 1) {
        munmap(rec, bytes);
        snprintf(msg, cap, "EMM_CAPTURE=valgrind: emm's Valgrind tool refused the record buffer");
        return false;
    }
    connected = true;
    return true;
}

static void tell_ranges(size_t n, const uint64_t *lo, const uint64_t *hi)
{
    REQUEST(EMM_VG_RANGES, lo, hi, n);
}

static void ranges(emm_agent *a)
{
    if (!connected)
        return;
    size_t n = emm_agent_ranges_locked(a, NULL, NULL, 0);
    uint64_t *lo = malloc((n ? n : 1) * sizeof *lo), *hi = malloc((n ? n : 1) * sizeof *hi);
    if (lo && hi) {
        n = emm_agent_ranges_locked(a, lo, hi, n);
        tell_ranges(n, lo, hi);
    }
    free(lo);
    free(hi);
}

/* The session is about to read the arrays itself (a snapshot of the one
 * leaving, the decision's geometry): no ranges until the next ranges. */
static void pause_ranges(void)
{
    if (connected)
        tell_ranges(0, NULL, NULL);
}

static void on_untag(const emm_agent_block *b)
{
    (void)b;
    pause_ranges();
}

static void drain(emm_agent *a)
{
    if (!connected)
        return;
    REQUEST(EMM_VG_BUSY, 1, 0, 0);
    for (size_t n = REQUEST(EMM_VG_TAKE, 0, 0, 0); n > 0; n = REQUEST(EMM_VG_RELEASE, 0, 0, 0))
        emm_agent_feed_locked(a, (const emm_raw_access *)channel.rec, n);
    REQUEST(EMM_VG_BUSY, 0, 0, 0);
}

static void fork_child(void)
{
    if (connected)
        REQUEST(EMM_VG_STOP, 0, 0, 0);
    connected = false;
}

const struct shim_capture_ops shim_capture_valgrind = {
    .wanted = on_emm_tool,
    .init = init,
    .hooks = {.on_untag = on_untag, .ranges = ranges, .before_decide = pause_ranges, .drain = drain},
    .fork_child = fork_child,
};
