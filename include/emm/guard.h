/* emm — page protection for the fault capture (docs/design.md "The shim
 * and the session", Capture backends: fault).
 *
 * The fault backend (shim/capture_fault.c) sees an unmodified program's
 * accesses to its tagged arrays by protecting their pages and
 * single-stepping each access its SIGSEGV handler catches. The guard holds
 * what that needs beside the signal plumbing: the protected regions (as
 * many as there are tagged blocks), which pages a fault belongs to, the
 * pages opened for good when the window closed, and the windows a system
 * call on protected memory opens, and how an access's step runs
 * (emm_guard_step). Each protected range's pages are kept VMAs of their
 * own (every other page flagged MADV_NOHUGEPAGE, up to 32,768 pages in
 * all), so that opening and closing one page never splits and merges the
 * mapping around it. The calls marked signal-safe only read atomics and
 * make system calls (mprotect, process_vm_readv): a handler may make them. */
#ifndef EMM_GUARD_H
#define EMM_GUARD_H

#include <signal.h>
#include <stddef.h>
#include <stdint.h>

#include "emm/common.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct emm_guard emm_guard;

/* A guard that watches (protects what it is given); NULL without memory. */
EMM_API emm_guard *emm_guard_new(void);
/* Opens every page and frees the guard. NULL is allowed. */
EMM_API void emm_guard_free(emm_guard *g);

/* While it watches, protects the block at base: its own mapping [map,
 * map + map_len) whole, or without one the pages wholly inside [base,
 * base + bytes) (an array tagged after its allocation shares its first and
 * last pages with other data, which the C library may touch). A block
 * already protected is opened first. */
EMM_API void emm_guard_protect(emm_guard *g, uintptr_t base, size_t bytes, void *map,
                               size_t map_len);
/* Opens the block at base and forgets it. */
EMM_API void emm_guard_unprotect(emm_guard *g, uintptr_t base);
/* Stops watching: every page opens for good. */
EMM_API void emm_guard_lift(emm_guard *g);
/* Whether it still watches. Signal-safe. */
EMM_API int emm_guard_watching(const emm_guard *g);

/* A fault at addr on a protected page: the region it belongs to, and in
 * *in_array whether addr is inside the array's bytes (else a byte of its
 * pages beside it). NULL when no region claims the page. Regions stay where
 * they are for the guard's life, so a handler may hold one. Signal-safe. */
typedef struct emm_guard_region emm_guard_region;
EMM_API emm_guard_region *emm_guard_find(emm_guard *g, uintptr_t addr, int *in_array);
/* A fault no region claims, on pages opened lately: the handler ran after
 * the window closed or the block left, and the access is to be retried.
 * retried[0] is the thread's last retried address, retried[1] how many
 * times in a row (both updated): the same access faults again when another
 * thread, preempted, has yet to open the page it protected for a moment
 * (emm_guard_step_done), so it yields and retries, EMM_GUARD_RETRIES times
 * at most before the fault is taken for the program's own. Signal-safe. */
#define EMM_GUARD_RETRIES 1000
EMM_API int emm_guard_retry(const emm_guard *g, uintptr_t addr, uintptr_t *retried);
/* After the single step of an access on `page` of region r: protects the
 * page again unless the guard stopped watching, the region left, or a
 * system call has it open. Signal-safe. */
EMM_API void emm_guard_step_done(emm_guard *g, emm_guard_region *r, uintptr_t page);

/* One access's step, the calling thread's (the fault handler keeps one per
 * thread): the pages its fault opened, and where it runs. Single-stepping
 * with the trap flag costs a debug exception, the dearest part of a fault
 * capture's access in a virtual machine; so the guard copies the faulting
 * instruction, when it is a plain load or store through a memory operand
 * (x86-64: no branch, not RIP-relative, no string instruction), into an
 * executable slot of the thread's followed by int3, and the access runs
 * there: the SIGTRAP of the int3 ends the step and the thread resumes after
 * the instruction. Other instructions, and every one where executable
 * memory is refused, single-step with the trap flag. Zeroed: no step. */
typedef struct emm_guard_step {
    uintptr_t page[4];
    emm_guard_region *r[4];
    int n;
    unsigned char *slot;     /* the thread's slot; NULL until its first step */
    uintptr_t resume, end;   /* the instruction's end, and its copy's int3 + 1; 0: none */
} emm_guard_step;
/* A fault in region r on `page` of an access at *pc: opens the page for the
 * step (s holds it) and either points *pc at the copy of the instruction
 * (returns 0) or asks for the trap flag (returns 1). A fault inside the
 * copy (an access that spans two protected pages) opens its page and the
 * copy goes on (0). Signal-safe. */
EMM_API int emm_guard_step_begin(emm_guard *g, emm_guard_step *s, emm_guard_region *r,
                                 uintptr_t page, uintptr_t *pc);
/* A SIGTRAP at *pc (trap: the trap flag was set): when it ends s's step,
 * protects its pages again (emm_guard_step_done), moves *pc past the
 * original instruction when it ran in the copy, and returns 1; 0 when the
 * signal is not the step's. Signal-safe. */
EMM_API int emm_guard_step_end(emm_guard *g, emm_guard_step *s, uintptr_t *pc, int trap);
/* A fault that is not the guard's while s steps: the step is given up (its
 * pages protected again, *pc back at the original instruction when it was
 * in the copy), so the program's handler sees its own code. Signal-safe. */
EMM_API void emm_guard_step_abandon(emm_guard *g, emm_guard_step *s, uintptr_t *pc);
/* The length of the instruction at pc when the guard may run it in a slot
 * (see emm_guard_step), else 0. Reads no byte past the instruction. */
EMM_API size_t emm_guard_insn_len(const unsigned char *pc);

/* While the mesh is being built — no read of a tagged array has faulted
 * yet — a write fault does not single-step: its page opens and stays open
 * for the next writes, with the EMM_GUARD_BUILD_PAGES pages opened last
 * (the oldest is protected again as another opens), so a loader that fills
 * its arrays faults once a page instead of once a write (the array's last
 * page excepted: there each write single-steps). The first read
 * fault ends the build for good: the pages still open are protected again
 * and every access single-steps from then on. The writes to an open page
 * after the one that opened it are not seen one by one: when the page
 * closes, `note` is given the last word of the array on it that is not 0
 * (the end of what was written there, on pages of its own that start as
 * zeros), so the records in use stay known — up to trailing zeros on a
 * block larger than what was written, a capacity. That read never faults
 * (process_vm_readv where the kernel allows it): another thread may protect
 * the page meanwhile; each page kept closes once. Returns 1 when it opened
 * the page of region r (no single step), 0 once the build is over.
 * Signal-safe. */
#define EMM_GUARD_BUILD_PAGES 8
EMM_API int emm_guard_build_open(emm_guard *g, emm_guard_region *r, uintptr_t page, int write,
                                 void (*note)(uintptr_t addr));

/* The signals: the C library's sigaction (`real`; the shim interposes
 * sigaction), on_segv and on_trap installed for SIGSEGV and SIGTRAP
 * (SA_SIGINFO), the program's own handlers of them kept. False when they
 * cannot be installed. */
typedef int (*emm_sigaction_fn)(int sig, const struct sigaction *act, struct sigaction *old);
EMM_API int emm_guard_install(emm_guard *g, emm_sigaction_fn real,
                              void (*on_segv)(int, siginfo_t *, void *),
                              void (*on_trap)(int, siginfo_t *, void *));
/* The program's sigaction for SIGSEGV or SIGTRAP once installed: its
 * handler is kept for emm_guard_chain, ours stays in place. */
EMM_API int emm_guard_sigaction(emm_guard *g, int sig, const struct sigaction *act,
                                struct sigaction *old);
/* signal() for SIGSEGV or SIGTRAP once installed, as emm_guard_sigaction
 * with SA_RESTART: the program's previous handler. */
typedef void (*emm_signal_handler)(int);
EMM_API emm_signal_handler emm_guard_signal(emm_guard *g, int sig, emm_signal_handler handler);
/* A SIGSEGV or SIGTRAP that is not the guard's: the program's handler, or
 * the default action (a real fault re-runs and faults again without us; a
 * sent or trap-made signal is raised again). From the handler. */
EMM_API void emm_guard_chain(emm_guard *g, int sig, siginfo_t *si, void *uctx);

/* Opens the protected pages [p, p + n) touches for a system call (read,
 * write, fread, ...), which would fail with EFAULT on them; returns a
 * token for emm_guard_io_end, NULL when nothing was opened. */
EMM_API void *emm_guard_io_begin(emm_guard *g, const void *p, size_t n);
EMM_API void emm_guard_io_end(emm_guard *g, void *token);

#ifdef __cplusplus
}
#endif
#endif
