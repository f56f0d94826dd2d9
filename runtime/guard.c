/* Page protection for the fault capture (emm/guard.h).
 *
 * Regions live in chunks that are never moved or freed while the guard
 * lives, appended to a list: a signal handler walks them with atomic loads
 * and no lock, and a region it found stays valid however many blocks are
 * tagged meanwhile. A region's fields change under the guard's lock, with
 * the order that keeps a racing handler right: a region's pages open
 * before it leaves, so a thread that faults on them meanwhile still finds
 * it; a page opened for good is noted (`lifted`) so that a handler that
 * ran late retries the access instead of taking the fault for the
 * program's own. */
#include "emm/guard.h"

#include <errno.h>
#include <pthread.h>
#include <sched.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/uio.h>
#include <unistd.h>

#define CHUNK_REGIONS 64
/* Ranges opened for good lately, kept for late handlers. */
#define LIFTED 16
/* The executable slots the steps run in (emm_guard_step): one per thread
 * that faults, never given back; threads beyond them use the trap flag. */
#define SLOT_BYTES 32
#define SLOT_MAP (64 * 1024)
/* Pages of a block's own mapping made VMAs of their own, for all blocks at
 * once (a share of the kernel's default limit of 65,530 mappings a process). */
#define SPLIT_BUDGET 32768

struct emm_guard_region {
    uintptr_t plo, phi; /* protected pages; plo == phi: none */
    uintptr_t lo, hi;   /* the array's bytes */
    uintptr_t base;     /* the block's key; 0: a free slot */
    int io;             /* system calls that have the pages open: changed under the lock,
                           read atomically by handlers */
    size_t split;       /* pages made VMAs of their own (split_pages) */
};

struct chunk {
    struct chunk *next; /* atomic */
    struct emm_guard_region r[CHUNK_REGIONS];
};

struct emm_guard {
    pthread_mutex_t lock;
    struct chunk *head; /* atomic */
    int watching;       /* atomic */
    struct {
        uintptr_t lo, hi;
    } lifted[LIFTED];
    unsigned nlifted;   /* atomic: lifted ranges ever recorded */
    int building;       /* atomic: no read has faulted yet */
    uintptr_t kept[EMM_GUARD_BUILD_PAGES]; /* atomic: pages kept open while building, 0 free */
    unsigned nkept;     /* atomic: pages ever kept */
    unsigned char *slots; /* SLOT_MAP bytes, read, write and execute; NULL: refused */
    unsigned nslots;    /* atomic: slots claimed */
    size_t split;       /* pages split (split_pages), under the lock */
    size_t page;
    int peek;           /* process_vm_readv reads this process (last_word) */
    unsigned protecting; /* atomic: handlers that may protect a page (emm_guard_step_done) */
    emm_sigaction_fn real;             /* the C library's sigaction */
    struct sigaction saved_segv, saved_trap; /* the program's handlers */
};

emm_guard *emm_guard_new(void)
{
    emm_guard *g = calloc(1, sizeof *g);
    if (!g)
        return NULL;
    pthread_mutex_init(&g->lock, NULL);
    g->page = (size_t)sysconf(_SC_PAGESIZE);
    g->watching = 1;
    g->building = 1;
    /* A seccomp filter may refuse process_vm_readv: then kept pages are
     * read in place, as before. */
    uint64_t probe = 1, got = 0;
    struct iovec to = {&got, sizeof got}, from = {&probe, sizeof probe};
    g->peek = process_vm_readv(getpid(), &to, 1, &from, 1, 0) == (ssize_t)sizeof got && got == 1;
#if defined(__x86_64__)
    void *m = mmap(NULL, SLOT_MAP, PROT_READ | PROT_WRITE | PROT_EXEC,
                   MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    g->slots = m == MAP_FAILED ? NULL : m;
#endif
    return g;
}

#define FOR_REGIONS(g, c, r)                                                                  \
    for (struct chunk *c = __atomic_load_n(&(g)->head, __ATOMIC_ACQUIRE); c;                   \
         c = __atomic_load_n(&c->next, __ATOMIC_ACQUIRE))                                       \
        for (struct emm_guard_region *r = c->r; r < c->r + CHUNK_REGIONS; r++)

int emm_guard_watching(const emm_guard *g)
{
    return __atomic_load_n(&g->watching, __ATOMIC_RELAXED);
}

/* The region of the block at base, or with base 0 a free one (a new chunk
 * when none is free; NULL without memory). With the lock held. */
static struct emm_guard_region *slot(emm_guard *g, uintptr_t base)
{
    FOR_REGIONS(g, c, r)
        if (r->base == base)
            return r;
    if (base)
        return NULL;
    struct chunk *n = calloc(1, sizeof *n);
    if (!n)
        return NULL;
    /* Appended last: a handler walking the list sees it whole or not. */
    struct chunk **at = &g->head;
    while (*at)
        at = &(*at)->next;
    __atomic_store_n(at, n, __ATOMIC_RELEASE);
    return &n->r[0];
}

/* Opens r's pages and takes it out; with the lock held. */
static void open_region(emm_guard *g, struct emm_guard_region *r)
{
    uintptr_t plo = r->plo, phi = r->phi;
    /* The pages open before the region leaves: another thread that faults
     * on them meanwhile must still find its region (a fault on a page no
     * region claims is the program's own). */
    if (plo < phi) {
        mprotect((void *)plo, phi - plo, PROT_READ | PROT_WRITE);
        unsigned k = __atomic_load_n(&g->nlifted, __ATOMIC_RELAXED) % LIFTED;
        __atomic_store_n(&g->lifted[k].lo, 0, __ATOMIC_RELAXED);
        __atomic_store_n(&g->lifted[k].hi, phi, __ATOMIC_RELAXED);
        __atomic_store_n(&g->lifted[k].lo, plo, __ATOMIC_RELEASE);
        __atomic_add_fetch(&g->nlifted, 1, __ATOMIC_RELEASE);
    }
    __atomic_store_n(&r->phi, 0, __ATOMIC_RELEASE);
    __atomic_store_n(&r->plo, 0, __ATOMIC_RELAXED);
    __atomic_store_n(&r->io, 0, __ATOMIC_RELAXED);
    g->split -= r->split;
    r->split = 0;
}

/* Makes each page of [lo, hi) a VMA of its own: every other page gets a
 * flag its neighbours lack (no transparent huge pages; on a block's own
 * mapping, else no core dump), so the kernel never merges them. Protecting one
 * page inside a large VMA splits it in three and opening it merges them
 * back, which made up about half of an mprotect's cost; on pages split
 * beforehand an mprotect changes one VMA. With the lock held; as many pages
 * as SPLIT_BUDGET leaves (the rest of the blocks stay whole: slower, as
 * exact). */
static size_t split_pages(emm_guard *g, uintptr_t lo, uintptr_t hi, bool own)
{
    size_t n = (hi - lo) / g->page;
    if (n < 2 || g->split + n > SPLIT_BUDGET)
        return 0;
    static const int advice[] = {MADV_NOHUGEPAGE, MADV_DONTDUMP};
    for (size_t k = 0; k < (own ? 2u : 1u); k++) {
        uintptr_t p = lo;
        while (p < hi && madvise((void *)p, g->page, advice[k]) == 0)
            p += 2 * g->page;
        if (p >= hi) {
            g->split += n;
            return n;
        }
        if (p > lo) /* the mapping limit: what was split stays so */
            return 0;
    }
    return 0;
}

void emm_guard_protect(emm_guard *g, uintptr_t base, size_t bytes, void *map, size_t map_len)
{
    pthread_mutex_lock(&g->lock);
    struct emm_guard_region *r = slot(g, base);
    if (r)
        open_region(g, r);
    else
        r = slot(g, 0);
    if (!r || !emm_guard_watching(g)) {
        if (r)
            r->base = 0;
        pthread_mutex_unlock(&g->lock);
        return;
    }
    uintptr_t plo, phi;
    if (map) {
        plo = (uintptr_t)map;
        phi = plo + map_len;
    } else {
        plo = (base + g->page - 1) & ~(uintptr_t)(g->page - 1);
        phi = (base + bytes) & ~(uintptr_t)(g->page - 1);
    }
    r->base = base;
    if (plo < phi) {
        __atomic_store_n(&r->lo, base, __ATOMIC_RELAXED);
        __atomic_store_n(&r->hi, base + bytes, __ATOMIC_RELAXED);
        __atomic_store_n(&r->plo, plo, __ATOMIC_RELAXED);
        __atomic_store_n(&r->phi, phi, __ATOMIC_RELEASE);
        r->split = split_pages(g, plo, phi, map != NULL);
        mprotect((void *)plo, phi - plo, PROT_NONE);
    }
    pthread_mutex_unlock(&g->lock);
}

/* Waits until no handler may still protect a page: one that checked
 * before the caller's change (the watching flag cleared, a region gone) and
 * has yet to protect its page or open it again. After that, no page the
 * caller opens is protected behind its back — which a thread of the shim's
 * own, that reads the program's arrays with SIGSEGV blocked (the decision),
 * would not survive. Not from a handler. */
static void quiesce(emm_guard *g)
{
    __atomic_thread_fence(__ATOMIC_SEQ_CST);
    while (__atomic_load_n(&g->protecting, __ATOMIC_SEQ_CST) != 0)
        sched_yield();
}

void emm_guard_unprotect(emm_guard *g, uintptr_t base)
{
    pthread_mutex_lock(&g->lock);
    struct emm_guard_region *r = base ? slot(g, base) : NULL;
    if (r) {
        open_region(g, r);
        r->base = 0;
        /* A handler that checked the region before it left may have
         * protected a page of it since: it opens it again (its check
         * after), and is waited for. */
        quiesce(g);
    }
    pthread_mutex_unlock(&g->lock);
}

void emm_guard_lift(emm_guard *g)
{
    pthread_mutex_lock(&g->lock);
    /* Before the pages open: a handler that protects a page again after
     * this store sees it and opens the page (emm_guard_step_done), and one
     * that checked before it is waited for. */
    __atomic_store_n(&g->watching, 0, __ATOMIC_SEQ_CST);
    quiesce(g);
    FOR_REGIONS(g, c, r)
        if (r->base) {
            open_region(g, r);
            r->base = 0;
        }
    pthread_mutex_unlock(&g->lock);
}

void emm_guard_free(emm_guard *g)
{
    if (!g)
        return;
    emm_guard_lift(g);
    for (struct chunk *c = g->head, *next; c; c = next) {
        next = c->next;
        free(c);
    }
    if (g->slots)
        munmap(g->slots, SLOT_MAP);
    pthread_mutex_destroy(&g->lock);
    free(g);
}

emm_guard_region *emm_guard_find(emm_guard *g, uintptr_t a, int *in_array)
{
    FOR_REGIONS(g, c, r) {
        uintptr_t plo = __atomic_load_n(&r->plo, __ATOMIC_RELAXED);
        uintptr_t phi = __atomic_load_n(&r->phi, __ATOMIC_ACQUIRE);
        if (a >= plo && a < phi) {
            *in_array = a >= __atomic_load_n(&r->lo, __ATOMIC_RELAXED) &&
                        a < __atomic_load_n(&r->hi, __ATOMIC_RELAXED);
            return r;
        }
    }
    return NULL;
}

int emm_guard_retry(const emm_guard *g, uintptr_t a, uintptr_t *retried)
{
    if (retried[0] == a) {
        if (retried[1]++ >= EMM_GUARD_RETRIES)
            return 0;
        sched_yield(); /* to the thread that is opening the page */
    } else {
        retried[1] = 0;
    }
    for (unsigned k = 0; k < LIFTED; k++) {
        uintptr_t lo = __atomic_load_n(&g->lifted[k].lo, __ATOMIC_ACQUIRE);
        if (lo && a >= lo && a < __atomic_load_n(&g->lifted[k].hi, __ATOMIC_RELAXED)) {
            retried[0] = a;
            return 1;
        }
    }
    return 0;
}

void emm_guard_step_done(emm_guard *g, emm_guard_region *r, uintptr_t page)
{
    /* Counted from before its check to after its last mprotect, so that
     * emm_guard_lift and emm_guard_unprotect can wait for it (quiesce). */
    __atomic_add_fetch(&g->protecting, 1, __ATOMIC_SEQ_CST);
    if (__atomic_load_n(&g->watching, __ATOMIC_SEQ_CST) &&
        __atomic_load_n(&r->io, __ATOMIC_RELAXED) == 0) {
        int in;
        mprotect((void *)page, g->page, PROT_NONE);
        /* The window closed meanwhile (emm_guard_lift) or the region left:
         * its pages stay open. */
        if (!__atomic_load_n(&g->watching, __ATOMIC_SEQ_CST) || emm_guard_find(g, page, &in) != r)
            mprotect((void *)page, g->page, PROT_READ | PROT_WRITE);
    }
    __atomic_sub_fetch(&g->protecting, 1, __ATOMIC_SEQ_CST);
}

/* --- stepping in a slot ------------------------------------------------- */

/* One-byte opcodes (x86-64) the guard runs in a slot: 1 + the bytes of
 * their immediate (Z: 2 or 4 by the operand size), 0 for the others;
 * groups are narrowed by their ModRM reg field below. */
#define Z 9
static const unsigned char map0[256] = {
    [0x00] = 1, 1, 1, 1, [0x08] = 1, 1, 1, 1, [0x10] = 1, 1, 1, 1, [0x18] = 1, 1, 1, 1,
    [0x20] = 1, 1, 1, 1, [0x28] = 1, 1, 1, 1, [0x30] = 1, 1, 1, 1, [0x38] = 1, 1, 1, 1,
    [0x63] = 1, [0x69] = 1 + Z, [0x6b] = 2,
    [0x80] = 2, [0x81] = 1 + Z, [0x83] = 2, [0x84] = 1, 1, 1, 1, 1, 1, 1, 1,
    [0xc0] = 2, 2, [0xc6] = 2, 1 + Z, [0xd0] = 1, 1, 1, 1,
    [0xd8] = 1, 1, 1, 1, 1, 1, 1, 1, [0xf6] = 2, 1 + Z, [0xfe] = 1, 1,
};

/* Two-byte opcodes (0F xx), as map0. */
static unsigned map1(unsigned op, unsigned reg)
{
    /* System, branch, push and pop, bswap, fences and the undefined ones out. */
    if (op <= 0x0c || op == 0x0e || op == 0x0f || (op >= 0x20 && op <= 0x27) ||
        (op >= 0x30 && op <= 0x3f) || (op >= 0x77 && op <= 0x7b) || (op >= 0x80 && op <= 0x8f) ||
        (op >= 0xa0 && op <= 0xa2) || (op >= 0xa6 && op <= 0xaa) || op == 0xae || op == 0xb9 ||
        (op == 0xc7 && reg != 1) || (op >= 0xc8 && op <= 0xcf) || op == 0xff)
        return 0;
    return (op >= 0x70 && op <= 0x73) || op == 0xa4 || op == 0xac || op == 0xba || op == 0xc2 ||
                   (op >= 0xc4 && op <= 0xc6)
               ? 2
               : 1;
}

size_t emm_guard_insn_len(const unsigned char *p)
{
#if defined(__x86_64__)
    size_t i = 0;
    int o16 = 0, legacy = 0, rexw = 0;
    for (;; i++) {
        unsigned b = p[i];
        if (b == 0x66)
            o16 = 1;
        else if (!(b == 0x67 || b == 0xf0 || b == 0xf2 || b == 0xf3 || b == 0x2e ||
                   b == 0x36 || b == 0x3e || b == 0x26 || b == 0x64 || b == 0x65))
            break;
        legacy = 1;
        if (i == 14)
            return 0;
    }
    int rex = (p[i] & 0xf0) == 0x40;
    if (rex)
        rexw = (p[i++] & 8) != 0;
    unsigned op = p[i++], kind, reg;
    if (op == 0xc4 || op == 0xc5) { /* VEX: maps 1 (0F), 2 (0F 38), 3 (0F 3A) */
        if (rex || legacy)
            return 0;
        unsigned map = 1;
        if (op == 0xc4)
            map = p[i++] & 0x1f;
        i++;
        if (map < 1 || map > 3)
            return 0;
        op = p[i++];
        if (map == 1 && (op == 0x77 || op == 0xae))
            return 0;
        kind = map == 3 || (map == 1 && ((op >= 0x70 && op <= 0x73) || op == 0xc2 ||
                                          (op >= 0xc4 && op <= 0xc6))) ? 2 : 1;
        reg = (p[i] >> 3) & 7;
    } else if (op == 0x0f) {
        op = p[i++];
        if (op == 0x38 || op == 0x3a) {
            kind = op == 0x3a ? 2 : 1;
            i++;
        } else {
            kind = map1(op, (p[i] >> 3) & 7);
        }
        reg = (p[i] >> 3) & 7;
    } else {
        kind = map0[op];
        if (!kind)
            return 0;
        reg = (p[i] >> 3) & 7;
        /* mov imm only of C6/C7; test, not, neg, mul, imul of F6/F7 (no
         * divide: its fault would name the slot); inc and dec of FE/FF. */
        if (((op == 0xc6 || op == 0xc7) && reg != 0) || ((op == 0xf6 || op == 0xf7) && reg >= 6) ||
            ((op == 0xfe || op == 0xff) && reg >= 2))
            return 0;
        if ((op == 0xf6 || op == 0xf7) && reg >= 2)
            kind = 1;
    }
    if (!kind)
        return 0;
    unsigned imm = kind == 1 + Z ? (o16 && !rexw ? 2 : 4) : kind - 1;
    unsigned m = p[i++], mod = m >> 6, rm = m & 7, disp = mod == 1 ? 1 : mod == 2 ? 4 : 0;
    if (mod == 3)
        return 0; /* a register operand: no access */
    if (rm == 4) {
        if (mod == 0 && (p[i] & 7) == 5)
            disp = 4;
        i++;
    } else if (mod == 0 && rm == 5) {
        return 0; /* RIP-relative: the copy would address elsewhere */
    }
    i += disp + imm;
    return i <= 15 ? i : 0;
#else
    (void)p;
    return 0;
#endif
}
#undef Z

/* The calling thread's slot, claimed at its first step; NULL when none is
 * left. */
static unsigned char *claim_slot(emm_guard *g, emm_guard_step *s)
{
    if (!s->slot && g->slots) {
        unsigned k = __atomic_fetch_add(&g->nslots, 1, __ATOMIC_RELAXED);
        if (k < SLOT_MAP / SLOT_BYTES)
            s->slot = g->slots + (size_t)k * SLOT_BYTES;
    }
    return s->slot;
}

int emm_guard_step_begin(emm_guard *g, emm_guard_step *s, emm_guard_region *r, uintptr_t page,
                         uintptr_t *pc)
{
    mprotect((void *)page, g->page, PROT_READ | PROT_WRITE);
    if (s->n < 4) {
        s->page[s->n] = page;
        s->r[s->n++] = r;
    }
    /* In the copy: its second page. Elsewhere while a copy runs: a signal
     * handler of the program's interrupted it, and the slot is taken. */
    if (s->end)
        return *pc >= (uintptr_t)s->slot && *pc < s->end ? 0 : 1;
    const unsigned char *code = (const unsigned char *)*pc;
    size_t len = emm_guard_insn_len(code);
    unsigned char *slot = len ? claim_slot(g, s) : NULL;
    if (!slot)
        return 1;
    memcpy(slot, code, len);
    slot[len] = 0xcc; /* int3 */
    s->resume = *pc + len;
    s->end = (uintptr_t)slot + len + 1;
    *pc = (uintptr_t)slot;
    return 0;
}

static void step_close(emm_guard *g, emm_guard_step *s)
{
    for (int i = 0; i < s->n; i++)
        emm_guard_step_done(g, s->r[i], s->page[i]);
    s->n = 0;
}

int emm_guard_step_end(emm_guard *g, emm_guard_step *s, uintptr_t *pc, int trap)
{
    if (s->end && *pc == s->end) {
        *pc = s->resume;
        s->end = 0;
    } else if (!trap || s->n == 0) {
        return 0;
    }
    /* (A trap-flag step inside a copy's closes the copy's pages too: the
     * copy faults on them again when it resumes.) */
    step_close(g, s);
    return 1;
}

void emm_guard_step_abandon(emm_guard *g, emm_guard_step *s, uintptr_t *pc)
{
    if (s->end && *pc >= (uintptr_t)s->slot && *pc < s->end)
        *pc = s->resume - (s->end - 1 - (uintptr_t)s->slot);
    s->end = 0;
    step_close(g, s);
}

/* The last of the n words at a that is not 0, or 0 (none, or the page
 * was protected meanwhile). Read with process_vm_readv, which fails with
 * EFAULT on a protected page instead of faulting: another thread may
 * protect a kept page at any moment — it kept the same page and closed it,
 * or faulted on it before it opened and stepped — and a fault here, inside
 * the SIGSEGV handler, where SIGSEGV is blocked, would kill the program.
 * From the end, 64 words at a time (a handler's stack is the program's).
 * Without process_vm_readv (g->peek 0) the words are read in place. */
static uintptr_t last_word(const emm_guard *g, uintptr_t a, size_t n)
{
    if (!g->peek) {
        for (size_t i = n; i-- > 0;)
            if (*(const volatile uint64_t *)(a + i * 8) != 0)
                return a + i * 8;
        return 0;
    }
    int saved = errno; /* the interrupted program's */
    pid_t pid = getpid();
    uint64_t buf[64];
    uintptr_t last = 0;
    while (n > 0 && !last) {
        size_t k = n < 64 ? n : 64;
        n -= k;
        struct iovec to = {buf, k * 8}, from = {(void *)(a + n * 8), k * 8};
        if (process_vm_readv(pid, &to, 1, &from, 1, 0) != (ssize_t)(k * 8))
            break;
        for (size_t i = k; i-- > 0 && !last;)
            if (buf[i] != 0)
                last = a + (n + i) * 8;
    }
    errno = saved;
    return last;
}

/* Protects a page kept open while building again, unless its region left
 * (emm_guard_step_done's checks), after telling `note` the last word of the
 * array on it that is not 0. The caller took the page out of g->kept: each
 * entry closes once. */
static void close_kept(emm_guard *g, uintptr_t page, void (*note)(uintptr_t addr))
{
    int in;
    emm_guard_region *r = page ? emm_guard_find(g, page, &in) : NULL;
    if (!r)
        return;
    uintptr_t lo = __atomic_load_n(&r->lo, __ATOMIC_RELAXED);
    uintptr_t hi = __atomic_load_n(&r->hi, __ATOMIC_RELAXED);
    uintptr_t a = page > lo ? page + ((lo - page) & 7) : lo, end = page + g->page;
    if (end > hi)
        end = hi;
    uintptr_t last = a + 8 <= end ? last_word(g, a, (end - a) / 8) : 0;
    if (last)
        note(last);
    emm_guard_step_done(g, r, page);
}

int emm_guard_build_open(emm_guard *g, emm_guard_region *r, uintptr_t page, int write,
                         void (*note)(uintptr_t addr))
{
    if (!__atomic_load_n(&g->building, __ATOMIC_SEQ_CST))
        return 0;
    if (!write) {
        if (__atomic_exchange_n(&g->building, 0, __ATOMIC_SEQ_CST))
            for (unsigned k = 0; k < EMM_GUARD_BUILD_PAGES; k++)
                close_kept(g, __atomic_exchange_n(&g->kept[k], 0, __ATOMIC_SEQ_CST), note);
        return 0;
    }
    /* The array's last page single-steps: where an array of the size of
     * its records ends, what was written there is seen write by write. */
    if (page + g->page >= __atomic_load_n(&r->hi, __ATOMIC_RELAXED))
        return 0;
    mprotect((void *)page, g->page, PROT_READ | PROT_WRITE);
    unsigned k = __atomic_fetch_add(&g->nkept, 1, __ATOMIC_RELAXED) % EMM_GUARD_BUILD_PAGES;
    close_kept(g, __atomic_exchange_n(&g->kept[k], page, __ATOMIC_SEQ_CST), note);
    /* The build ended while this page opened: the sweep may have missed
     * it. Taken back only while still in its entry — else whoever took it
     * (the sweep, or a thread that came round to the entry) closes it. */
    uintptr_t mine = page;
    if (!__atomic_load_n(&g->building, __ATOMIC_SEQ_CST) &&
        __atomic_compare_exchange_n(&g->kept[k], &mine, 0, false, __ATOMIC_SEQ_CST,
                                    __ATOMIC_SEQ_CST))
        close_kept(g, page, note);
    return 1;
}

int emm_guard_install(emm_guard *g, emm_sigaction_fn real,
                      void (*on_segv)(int, siginfo_t *, void *),
                      void (*on_trap)(int, siginfo_t *, void *))
{
    g->real = real;
    if (real(SIGSEGV, NULL, &g->saved_segv) != 0 || real(SIGTRAP, NULL, &g->saved_trap) != 0)
        return 0;
    struct sigaction act;
    memset(&act, 0, sizeof act);
    sigemptyset(&act.sa_mask);
    act.sa_flags = SA_SIGINFO;
    act.sa_sigaction = on_segv;
    if (real(SIGSEGV, &act, NULL) != 0)
        return 0;
    act.sa_sigaction = on_trap;
    return real(SIGTRAP, &act, NULL) == 0;
}

int emm_guard_sigaction(emm_guard *g, int sig, const struct sigaction *act, struct sigaction *old)
{
    struct sigaction *pa = sig == SIGSEGV ? &g->saved_segv : &g->saved_trap;
    if (old)
        *old = *pa;
    if (act)
        *pa = *act;
    return 0;
}

emm_signal_handler emm_guard_signal(emm_guard *g, int sig, emm_signal_handler handler)
{
    struct sigaction act, old;
    memset(&act, 0, sizeof act);
    act.sa_handler = handler;
    sigemptyset(&act.sa_mask);
    act.sa_flags = SA_RESTART;
    emm_guard_sigaction(g, sig, &act, &old);
    return (old.sa_flags & SA_SIGINFO) ? (emm_signal_handler)(void (*)(void))old.sa_sigaction
                                       : old.sa_handler;
}

void emm_guard_chain(emm_guard *g, int sig, siginfo_t *si, void *uctx)
{
    struct sigaction *pa = sig == SIGSEGV ? &g->saved_segv : &g->saved_trap;
    if (pa->sa_flags & SA_SIGINFO) {
        void (*h)(int, siginfo_t *, void *) = pa->sa_sigaction;
        if (pa->sa_flags & SA_RESETHAND)
            pa->sa_handler = SIG_DFL, pa->sa_flags &= ~SA_SIGINFO;
        h(sig, si, uctx);
        return;
    }
    void (*h)(int) = pa->sa_handler;
    if (h == SIG_IGN && sig == SIGTRAP)
        return;
    if (h == SIG_DFL || h == SIG_IGN) {
        struct sigaction dfl;
        memset(&dfl, 0, sizeof dfl);
        dfl.sa_handler = SIG_DFL;
        g->real(sig, &dfl, NULL);
        if (sig == SIGTRAP || si->si_code <= 0)
            raise(sig);
        return;
    }
    if (pa->sa_flags & SA_RESETHAND)
        pa->sa_handler = SIG_DFL;
    h(sig);
}

/* The regions a system call has open. */
struct io_token {
    size_t n;
    struct emm_guard_region *r[];
};

void *emm_guard_io_begin(emm_guard *g, const void *p, size_t n)
{
    if (!emm_guard_watching(g) || n == 0)
        return NULL;
    uintptr_t a = (uintptr_t)p, b = a + n;
    size_t hits = 0;
    FOR_REGIONS(g, c, r)
        hits += __atomic_load_n(&r->phi, __ATOMIC_RELAXED) > a &&
                __atomic_load_n(&r->plo, __ATOMIC_RELAXED) < b;
    if (hits == 0)
        return NULL;
    pthread_mutex_lock(&g->lock);
    hits = 0;
    FOR_REGIONS(g, c, r)
        hits += r->plo < r->phi && r->phi > a && r->plo < b;
    struct io_token *t = hits ? malloc(sizeof *t + hits * sizeof *t->r) : NULL;
    if (t) {
        t->n = 0;
        FOR_REGIONS(g, c, r)
            if (r->plo < r->phi && r->phi > a && r->plo < b && t->n < hits) {
                if (__atomic_fetch_add(&r->io, 1, __ATOMIC_RELAXED) == 0)
                    mprotect((void *)r->plo, r->phi - r->plo, PROT_READ | PROT_WRITE);
                t->r[t->n++] = r;
            }
    }
    pthread_mutex_unlock(&g->lock);
    return t;
}

void emm_guard_io_end(emm_guard *g, void *token)
{
    struct io_token *t = token;
    if (!t)
        return;
    pthread_mutex_lock(&g->lock);
    for (size_t i = 0; i < t->n; i++) {
        struct emm_guard_region *r = t->r[i];
        if (r->io > 0 && __atomic_sub_fetch(&r->io, 1, __ATOMIC_RELAXED) == 0 &&
            r->plo < r->phi && emm_guard_watching(g))
            mprotect((void *)r->plo, r->phi - r->plo, PROT_NONE);
    }
    pthread_mutex_unlock(&g->lock);
    free(t);
}
