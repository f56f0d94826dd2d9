/* The shim's agent (runtime/agent.c) and the fault capture's page guard
 * (runtime/guard.c) driven directly, as libemmshim.so drives them, so that
 * the sanitizer build (which cannot preload the shim) runs them too: rules
 * select blocks, tags have no fixed capacity, realloc keeps an array, the
 * hooks see each event, the hot path's filter follows the ranges, and the
 * session answers at finish; the guard claims only its pages, grows past a
 * chunk of regions and opens pages for a system call. */
#include <setjmp.h>
#include <signal.h>
#include <stdint.h>
#include <string.h>
#include <sys/mman.h>
#include <ucontext.h>
#include <unistd.h>

#include "check.h"
#include "emm/agent.h"
#include "emm/guard.h"

/* What the hooks saw. */
static int tags_seen, untags_seen, ranges_seen;

static void on_tag(const emm_agent_block *b)
{
    (void)b;
    tags_seen++;
}

static void on_untag(const emm_agent_block *b)
{
    (void)b;
    untags_seen++;
}

static void on_ranges(emm_agent *a)
{
    (void)a;
    ranges_seen++;
}

static emm_agent *new_agent(const char *rules, const char *report)
{
    emm_config cfg;
    emm_error err;
    emm_config_init(&cfg);
    if (rules)
        REQUIRE(emm_config_set(&cfg, EMM_CONFIG_TAG, rules, NULL, 1, &err) == EMM_OK);
    REQUIRE(emm_config_set(&cfg, EMM_CONFIG_LOG, "0", NULL, 1, &err) == EMM_OK);
    REQUIRE(emm_config_set(&cfg, EMM_CONFIG_STRATEGY, "direct", NULL, 1, &err) == EMM_OK);
    if (report)
        REQUIRE(emm_config_set(&cfg, EMM_CONFIG_REPORT, report, NULL, 1, &err) == EMM_OK);
    static const emm_agent_hooks hooks = {NULL, on_tag, on_untag, on_ranges, NULL, NULL};
    emm_agent_config ac = {&cfg, EMM_CAPTURE_API, &hooks, "test_agent", {1, NULL, NULL}, NULL};
    emm_agent *a;
    REQUIRE(emm_agent_new(&ac, &a, &err) == EMM_OK);
    emm_config_free(&cfg); /* the agent keeps its own copy */
    return a;
}

/* A rule selects the block whose records fit it, the next rule another's;
 * realloc moves the array; free untags it. */
static void rules_and_moves(void)
{
    emm_agent *a = new_agent("vertices:min=8192,stride=24,xyz=0:f64;"
                             "triangles:min=8192,stride=12,vidx=0:i32",
                             NULL);
    CHECK(emm_agent_min_block(a) == 8192);
    CHECK(emm_agent_active(a));
    CHECK(emm_agent_select(a, 4096, NULL) == -1); /* below every rule's min */
    size_t vbytes = 24 * 1000, tbytes = 12 * 1001; /* 12,012: not whole vertex records */
    int rv = emm_agent_select(a, vbytes, NULL), rt = emm_agent_select(a, tbytes, NULL);
    CHECK(rv == 0 && rt == 1);
    double *v = malloc(vbytes);
    int32_t *t = malloc(tbytes);
    REQUIRE(v && t);
    for (int i = 0; i < 3000; i++)
        v[i] = i;
    for (int i = 0; i < 3003; i++)
        t[i] = i % 1000;
    tags_seen = untags_seen = 0;
    emm_agent_allocated(a, rv, v, vbytes, NULL, 0, NULL);
    emm_agent_allocated(a, rt, t, tbytes, NULL, 0, NULL);
    CHECK(tags_seen == 2 && ranges_seen >= 2);
    CHECK(emm_agent_maybe_tagged(a, v) && emm_agent_maybe_tagged(a, t));
    const emm_agent_filter *f = emm_agent_filter_of(a);
    CHECK(f->n == 2);
    /* A read of vertex 5 and triangle 7 go through the filter's ranges. */
    emm_raw_access r[2] = {{(uintptr_t)&v[15], 8, 0, 0}, {(uintptr_t)&t[21], 12, 0, 0}};
    emm_agent_feed(a, r, 2);
    emm_agent_iteration(a);
    /* A vertex array grown by realloc stays the array. */
    int handled = 0;
    double *w = emm_agent_on_realloc(a, v, 2 * vbytes, &handled);
    CHECK(handled && w != NULL);
    CHECK(untags_seen == 1 && tags_seen == 3);
    if (w) {
        CHECK(w[2999] == 2999);
        v = w;
    }
    CHECK(emm_agent_maybe_tagged(a, v));
    CHECK(f->n == 2);
    /* An untagged pointer is not the agent's to free. */
    double *other = malloc(64);
    REQUIRE(other);
    CHECK(!emm_agent_on_free(a, other) || !"an untagged block");
    free(other);
    CHECK(emm_agent_on_free(a, t));
    CHECK(untags_seen == 2 && f->n == 1);
    CHECK(emm_agent_on_free(a, v));
    CHECK(f->n == 0);
    emm_agent_finish(a);
    CHECK(!emm_agent_active(a));
    emm_agent_free(a);
}

/* More arrays than any fixed table held (the shim kept 64, the session
 * 16): every one tagged and watched; the session answers at finish. */
static void many_arrays(void)
{
    char report[] = "agent-report.json";
    remove(report);
    emm_agent *a = new_agent(NULL, report);
    enum { N = 100, RECORDS = 64 };
    double *block[N];
    for (int i = 0; i < N; i++) {
        REQUIRE((block[i] = calloc(RECORDS, 24)) != NULL);
        for (int k = 0; k < RECORDS; k++)
            block[i][3 * k] = k;
        emm_agent_tag_call(a, EMM_ARRAY_VERTICES, block[i], RECORDS, 24, 0, EMM_F64);
    }
    const emm_agent_filter *f = emm_agent_filter_of(a);
    CHECKF(f->n == N, "%zu ranges", f->n);
    int maybe = 0;
    for (int i = 0; i < N; i++)
        maybe += emm_agent_maybe_tagged(a, block[i]);
    CHECK(maybe == N);
    /* The last block's range is the last array's. */
    int found = 0;
    for (size_t i = 0; i < f->n; i++)
        found += f->lo[i] == (uintptr_t)block[N - 1] && f->len[i] == RECORDS * 24;
    CHECK(found == 1);
    emm_agent_untag(a, block[0]);
    CHECK(f->n == N - 1);
    emm_agent_finish(a);
    emm_agent_finish(a); /* once */
    CHECK(access(report, F_OK) == 0);
    emm_agent_free(a);
    for (int i = 0; i < N; i++)
        free(block[i]);
}

static sigjmp_buf fault_jump;

static void on_fault(int sig)
{
    (void)sig;
    siglongjmp(fault_jump, 1);
}

/* Whether reading p faults. */
static int faults(const volatile char *p)
{
    if (sigsetjmp(fault_jump, 1))
        return 1;
    (void)*p;
    return 0;
}

/* The guard: its regions, the pages beside an array, more regions than a
 * chunk, a system call's window, the lift. */
static void guard(void)
{
    size_t ps = (size_t)sysconf(_SC_PAGESIZE);
    struct sigaction act, old;
    memset(&act, 0, sizeof act);
    act.sa_handler = on_fault;
    sigaction(SIGSEGV, &act, &old);
    emm_guard *g = emm_guard_new();
    REQUIRE(g);
    CHECK(emm_guard_watching(g));
    enum { N = 70 }; /* more than a chunk of regions */
    char *map[N];
    for (int i = 0; i < N; i++) {
        map[i] = mmap(NULL, 2 * ps, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        REQUIRE(map[i] != MAP_FAILED);
        /* The array is the mapping's first 100 bytes; its pages are its own. */
        emm_guard_protect(g, (uintptr_t)map[i], 100, map[i], 2 * ps);
    }
    int in = -1;
    for (int i = 0; i < N; i++) {
        emm_guard_region *r = emm_guard_find(g, (uintptr_t)map[i] + 50, &in);
        CHECK(r != NULL && in == 1);
        CHECK(emm_guard_find(g, (uintptr_t)map[i] + ps + 8, &in) == r && in == 0);
    }
    CHECK(faults(map[N - 1]));
    /* A system call's window opens the pages, then closes them. */
    void *tok = emm_guard_io_begin(g, map[3] + 10, 20);
    CHECK(tok != NULL && !faults(map[3] + 10));
    emm_guard_io_end(g, tok);
    CHECK(faults(map[3] + 10));
    CHECK(emm_guard_io_begin(g, &in, sizeof in) == NULL); /* no protected page */
    /* An unprotected block: no region claims it, and a late handler is
     * told to retry; the same access faulting again is retried (another
     * thread has yet to open the page it protected for a moment), up to
     * EMM_GUARD_RETRIES times in a row, then taken for the program's own. */
    emm_guard_unprotect(g, (uintptr_t)map[5]);
    CHECK(emm_guard_find(g, (uintptr_t)map[5], &in) == NULL && !faults(map[5]));
    uintptr_t retried[2] = {0, 0};
    CHECK(emm_guard_retry(g, (uintptr_t)map[5], retried) == 1);
    int again = 0;
    while (emm_guard_retry(g, (uintptr_t)map[5], retried) == 1 && again <= EMM_GUARD_RETRIES)
        again++;
    CHECK(again == EMM_GUARD_RETRIES);
    /* Another address starts the count afresh. */
    CHECK(emm_guard_retry(g, (uintptr_t)map[5] + 64, retried) == 1);
    CHECK(emm_guard_retry(g, (uintptr_t)map[5] + 64, retried) == 1);
    /* A block without pages of its own: only the pages wholly inside. */
    emm_guard_protect(g, (uintptr_t)map[5] + 8, 2 * ps - 8, NULL, 0);
    CHECK(emm_guard_find(g, (uintptr_t)map[5] + 8, &in) == NULL);
    CHECK(emm_guard_find(g, (uintptr_t)map[5] + ps, &in) != NULL && in == 1);
    CHECK(!faults(map[5] + 8) && faults(map[5] + ps));
    emm_guard_lift(g);
    CHECK(!emm_guard_watching(g));
    for (int i = 0; i < N; i++)
        CHECK(!faults(map[i]) && emm_guard_find(g, (uintptr_t)map[i], &in) == NULL);
    emm_guard_protect(g, (uintptr_t)map[0], 100, map[0], 2 * ps); /* no longer watching */
    CHECK(!faults(map[0]));
    emm_guard_free(g);
    for (int i = 0; i < N; i++)
        munmap(map[i], 2 * ps);
    sigaction(SIGSEGV, &old, NULL);
}

/* The instructions the guard runs in a slot, and those it leaves to the
 * trap flag. */
static void insn_lengths(void)
{
    static const struct {
        unsigned char code[16];
        size_t len;
    } cases[] = {
        {{0x8b, 0x04, 0x24}, 3},                                     /* mov eax, [rsp] */
        {{0x48, 0x8b, 0x44, 0x24, 0x08}, 5},                         /* mov rax, [rsp+8] */
        {{0xf2, 0x0f, 0x10, 0x04, 0xc7}, 5},                         /* movsd xmm0, [rdi+rax*8] */
        {{0xc7, 0x44, 0x24, 0x08, 1, 0, 0, 0}, 8},                   /* mov dword [rsp+8], 1 */
        {{0x66, 0xc7, 0x07, 1, 0}, 5},                               /* mov word [rdi], 1 */
        {{0x48, 0xc7, 0x07, 1, 0, 0, 0}, 7},                         /* mov qword [rdi], 1 */
        {{0xc5, 0xfa, 0x10, 0x04, 0x87}, 5},                         /* vmovss xmm0, [rdi+rax*4] */
        {{0xc4, 0xe3, 0x79, 0x16, 0x07, 1}, 6},                      /* vpextrd [rdi], xmm0, 1 */
        {{0x80, 0x3c, 0x07, 0}, 4},                                  /* cmp byte [rdi+rax], 0 */
        {{0xf3, 0x0f, 0x6f, 0x04, 0x05, 0, 0, 0, 0}, 9},             /* movdqu xmm0, [rax*1+0] */
        {{0xf0, 0x48, 0x0f, 0xc1, 0x87, 0, 1, 0, 0}, 9},             /* lock xadd [rdi+256], rax */
        {{0x8b, 0x05, 0, 0, 0, 0}, 0},                               /* mov eax, [rip+0] */
        {{0xff, 0x20}, 0},                                           /* jmp [rax] */
        {{0xff, 0x30}, 0},                                           /* push [rax] */
        {{0x48, 0x8d, 0x04, 0x07}, 0},                               /* lea rax, [rdi+rax] */
        {{0x89, 0xc0}, 0},                                           /* mov eax, eax */
        {{0xf7, 0x37}, 0},                                           /* div dword [rdi] */
        {{0xa4}, 0},                                                 /* movsb */
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
#if defined(__x86_64__)
        CHECK(emm_guard_insn_len(cases[i].code) == cases[i].len);
#else
        CHECK(emm_guard_insn_len(cases[i].code) == 0);
#endif
    }
}

/* The fault capture's step, as the shim's handlers take it: every access
 * to the protected pages faults once and runs (in a slot or under the trap
 * flag), and the program reads what is there. */
static emm_guard *step_guard;
static emm_guard_step step_state;
static volatile size_t step_faults;

static void step_segv(int sig, siginfo_t *si, void *uctx)
{
    (void)sig;
    ucontext_t *uc = uctx;
    int in;
    uintptr_t a = (uintptr_t)si->si_addr, page = a & ~(uintptr_t)(sysconf(_SC_PAGESIZE) - 1);
    emm_guard_region *r = emm_guard_find(step_guard, a, &in);
    if (!r)
        abort();
    step_faults++;
    if (emm_guard_step_begin(step_guard, &step_state, r, page,
                             (uintptr_t *)&uc->uc_mcontext.gregs[REG_RIP]))
        uc->uc_mcontext.gregs[REG_EFL] |= 0x100;
}

static void step_trap(int sig, siginfo_t *si, void *uctx)
{
    (void)sig;
    (void)si;
    ucontext_t *uc = uctx;
    if (!emm_guard_step_end(step_guard, &step_state, (uintptr_t *)&uc->uc_mcontext.gregs[REG_RIP],
                            (uc->uc_mcontext.gregs[REG_EFL] & 0x100) != 0))
        abort();
    uc->uc_mcontext.gregs[REG_EFL] &= ~(greg_t)0x100;
}

static void guard_steps(void)
{
#if defined(__x86_64__)
    size_t ps = (size_t)sysconf(_SC_PAGESIZE);
    struct sigaction act, old_segv, old_trap;
    memset(&act, 0, sizeof act);
    act.sa_flags = SA_SIGINFO;
    act.sa_sigaction = step_segv;
    sigaction(SIGSEGV, &act, &old_segv);
    act.sa_sigaction = step_trap;
    sigaction(SIGTRAP, &act, &old_trap);
    REQUIRE((step_guard = emm_guard_new()));
    enum { PAGES = 8 };
    double *d = mmap(NULL, PAGES * ps, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    REQUIRE(d != MAP_FAILED);
    size_t n = PAGES * ps / sizeof *d;
    double want = 0;
    for (size_t i = 0; i < n; i++)
        want += d[i] = (double)(i % 97);
    emm_guard_protect(step_guard, (uintptr_t)d, PAGES * ps, d, PAGES * ps);
    /* Reads, one fault each: the values are the array's. */
    volatile double *v = d;
    double sum = 0;
    for (size_t i = 0; i < n; i += 37)
        sum += v[i];
    size_t reads = (n + 36) / 37;
    CHECK(step_faults == reads);
    CHECK(step_state.slot != NULL); /* they ran in the thread's slot */
    /* A write, and a read across two protected pages (two faults, one
     * instruction). */
    v[5] = 1.5;
    uint64_t across;
    __asm__ volatile("movq (%1), %0" : "=r"(across) : "r"((char *)d + ps - 4) : "memory");
    CHECK(step_faults == reads + 3);
    emm_guard_lift(step_guard);
    double check = 0;
    for (size_t i = 0; i < n; i += 37)
        check += d[i];
    CHECK(sum == check && d[5] == 1.5);
    uint64_t expect;
    memcpy(&expect, (char *)d + ps - 4, sizeof expect);
    CHECK(across == expect);
    CHECK(want > 0);
    emm_guard_free(step_guard);
    munmap(d, PAGES * ps);
    sigaction(SIGSEGV, &old_segv, NULL);
    sigaction(SIGTRAP, &old_trap, NULL);
#endif
}

int main(void)
{
    rules_and_moves();
    many_arrays();
    guard();
    insn_lengths();
    guard_steps();
    return check_done();
}
