/* A program with its own SIGSEGV handler (installed with signal() and then
 * sigaction()) that touches a page it protected itself: under
 * EMM_CAPTURE=fault the shim must pass that fault to the program's handler,
 * while its own faults on the tagged array (allocated in load, selected by
 * an EMM_TAG rule) stay the shim's. Prints the same with and without it. */
#include <setjmp.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

static sigjmp_buf back;
static volatile sig_atomic_t caught;

static void on_segv(int sig)
{
    (void)sig;
    caught++;
    siglongjmp(back, 1);
}

static void on_segv_info(int sig, siginfo_t *si, void *uc)
{
    (void)si; (void)uc;
    on_segv(sig);
}

struct vert { uint32_t id; double xyz[3]; };

static __attribute__((noinline)) struct vert *load(size_t n)
{
    struct vert *v = malloc(n * sizeof *v);
    for (size_t i = 0; v && i < n; i++)
        v[i] = (struct vert){(uint32_t)i, {(double)i, 1, 0}};
    return v;
}

static void touch_own_page(char *page)
{
    if (sigsetjmp(back, 1) == 0) {
        page[10] = 1; /* faults: the program's handler jumps back */
        puts("not reached");
    }
}

int main(void)
{
    long ps = sysconf(_SC_PAGESIZE);
    char *page = mmap(NULL, (size_t)ps, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (page == MAP_FAILED)
        return 1;
    struct vert *v = load(4000);
    if (!v)
        return 1;

    signal(SIGSEGV, on_segv);
    double s = 0;
    for (size_t i = 0; i < 4000; i += 7)
        s += v[i].xyz[0];
    touch_own_page(page);

    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_sigaction = on_segv_info;
    sa.sa_flags = SA_SIGINFO;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGSEGV, &sa, NULL);
    for (size_t i = 0; i < 4000; i += 5)
        s += v[i].xyz[1];
    touch_own_page(page);

    struct sigaction now;
    sigaction(SIGSEGV, NULL, &now);
    printf("caught: %d\nsum: %.1f\nhandler kept: %s\n", (int)caught, s,
           now.sa_sigaction == on_segv_info ? "yes" : "no");
    free(v);
    return 0;
}
