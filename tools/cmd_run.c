/* emm run: runs a program under libemmshim.so (docs/design.md "The shim and the session").
 *
 * It prepares the environment — the shim found beside this executable goes
 * first in LD_PRELOAD, each option becomes its EMM_* variable — starts the
 * program and waits for it, and ends as the program did: its exit status,
 * or the signal that ended it raised again, is the status the caller sees.
 * It waits so that a program the shim never loaded into (statically linked,
 * set-user-ID: the loader preloads nothing) is not silently left
 * unanalysed: the shim answers on a pipe when it loads (emm/agent.h,
 * EMM_AGENT_READY_VAR), and without an answer emm run says so in one line.
 * While it waits, SIGINT and SIGQUIT (which the terminal sends the program
 * too) are ignored, and SIGTERM, SIGHUP, SIGUSR1 and SIGUSR2 are passed on
 * to the program.
 *
 * Under --capture valgrind (and for --capture auto, a binary that neither
 * links emm's coverage hooks nor calls emm, when Valgrind and emm's tool are
 * there) the program runs under `valgrind --tool=emm` instead, with
 * VALGRIND_LIB pointing at the tool's directory beside the shim
 * (lib/emm/valgrind/); Valgrind preloads the shim into the program as the
 * tool's own preload (shim/vgtool/CMakeLists.txt), so the launcher itself
 * never loads it. Valgrind exits with the program's status. */
#include <dirent.h>
#include <elf.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "infile.h"
#include "opts.h"
#include "emm/agent.h"
#include "emm/config.h"
#include "emm/session.h"
#include "session_transport.h"

#define SHIM_NAME "libemmshim.so"
#define HOOKS_NAME "libemmhooks.so"
#define VGTOOL_NAME "emm/valgrind/emm-amd64-linux"

static void usage(FILE *out, const opts *o)
{
    (void)o; /* the options are the configuration table's rows */
    fprintf(out,
            "usage: emm run [OPTIONS] -- PROGRAM [ARGS...]\n"
            "\n"
            "Runs PROGRAM with libemmshim.so preloaded: its mesh arrays are tagged as they\n"
            "are allocated (emm_tag_* calls or EMM_TAG rules), the first accesses are\n"
            "profiled, a strategy is chosen from the strategy table, and the whole run is\n"
            "simulated under that strategy and the baselines (direct reads, the cache).\n"
            "A summary goes to stderr at exit; PROGRAM's output and exit status are its own.\n"
            "emm run waits for PROGRAM and ends as it did. When the shim could not load into\n"
            "it (a statically linked or set-user-ID program), it runs untouched and emm run\n"
            "says so in one line (so does a program the loader could not start). Programs\n"
            "PROGRAM starts get the shim too; one that tags nothing says nothing (--verbose:\n"
            "one line), and symbolizers are not entered. This emm's library directory\n"
            "goes first in LD_LIBRARY_PATH: a program built against an emm (emm-sancov.pc,\n"
            "emm_sancov_executable) finds its libraries there even after the install moved.\n"
            "\n"
            "Options (each sets its EMM_* variable; %%p in a FILE becomes the process id):\n");
    emm_config_help(out, 1);
    fprintf(out,
            "\n"
            "EMM_* variables already in the environment apply unless an option sets them.\n"
            "A bad option or variable is refused (exit status 2) before PROGRAM starts.\n"
            "The shim is looked for beside this executable: <bindir>/../lib/" SHIM_NAME
            " (build\n"
            "tree and install), and <bindir>/../lib64 and <bindir>/../lib/<multiarch>/.\n"
            "\n"
            "--capture valgrind runs PROGRAM under `valgrind --tool=emm` (the whole run of an\n"
            "unmodified binary, threads exact), with VALGRIND_LIB set to the tool's directory,\n"
            "<libdir>/emm/valgrind/. The session (profile, decision, simulation) runs\n"
            "natively beside the program in a process of its own, emm-session from that\n"
            "directory, which Valgrind does not trace (in the program, slower, when it is\n"
            "missing; --verbose says which). Its summary goes to the program's stderr. --capture\n"
            "auto does the same for a binary that neither links emm's coverage hooks\n"
            "(emm_sancov_executable) nor calls emm, when valgrind is on PATH and the tool\n"
            "was built (the fault capture, the alternative there, pays tens of microseconds\n"
            "a window access and sees the window only; --verbose says which auto took and\n"
            "why, and the summary names auto's pick); otherwise it preloads the shim, which\n"
            "picks sancov, api or fault.\n"
            "\n"
            "--list-sites runs PROGRAM once and lists, at exit, its candidate arrays: blocks\n"
            "of 64 KiB or more by call path, with the whole stack, what their records look\n"
            "like (from the program's accesses under --capture valgrind or sancov, else a\n"
            "guess from the bytes) and an EMM_TAG rule each, checked by replaying the run's\n"
            "allocations through the rule matcher: it selects that block used as printed (or\n"
            "the line says none does). A frame no symbol names is MODULE+0xOFFSET. A rule\n"
            "that matches nothing says so at exit with the sites seen closest to it, or which\n"
            "rule took its blocks; --verbose names each tagged block's site.\n");
}

/* out = a + b + c; false when it does not fit. */
static bool join(char *out, size_t cap, const char *a, const char *b, const char *c)
{
    int n = snprintf(out, cap, "%s%s%s", a, b, c);
    return n >= 0 && (size_t)n < cap;
}

/* Where a file of emm's lib directory (the shim, the Valgrind tool) may
 * be, in order, relative to this executable. Returns the first that exists,
 * or NULL with the paths tried in `tried`. */
static char *find_beside(const char *name, char *tried, size_t cap)
{
    char exe[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", exe, sizeof exe - 1);
    size_t used = 0;
    tried[0] = '\0';
    if (n <= 0) {
        snprintf(tried, cap, "(cannot read /proc/self/exe: %s)", strerror(errno));
        return NULL;
    }
    exe[n] = '\0';
    char *slash = strrchr(exe, '/');
    if (!slash)
        return NULL;
    *slash = '\0'; /* exe is now the bin directory */

    enum { MAX_CAND = 16 };
    char cand[MAX_CAND][PATH_MAX];
    size_t nc = 0;
    char libdir[PATH_MAX];
    if (join(cand[nc], PATH_MAX, exe, "/../lib/", name))
        nc++;
    if (join(cand[nc], PATH_MAX, exe, "/../lib64/", name))
        nc++;
    DIR *d = join(libdir, sizeof libdir, exe, "/../lib", "") ? opendir(libdir) : NULL;
    if (d) {
        /* A multiarch install: lib/x86_64-linux-gnu/ and the like. */
        struct dirent *e;
        char sub[PATH_MAX];
        while ((e = readdir(d)) && nc < MAX_CAND)
            if (e->d_name[0] != '.' && strchr(e->d_name, '-') &&
                join(sub, sizeof sub, libdir, "/", e->d_name) &&
                join(cand[nc], PATH_MAX, sub, "/", name))
                nc++;
        closedir(d);
    }
    for (size_t i = 0; i < nc; i++) {
        char real[PATH_MAX];
        if (access(cand[i], R_OK) == 0 && realpath(cand[i], real))
            return strdup(real);
        int w = snprintf(tried + used, cap - used, "%s%s", used ? ", " : "", cand[i]);
        if (w > 0 && (size_t)w < cap - used)
            used += (size_t)w;
    }
    return NULL;
}

/* The executable `name` resolves to, as execvp would find it, into out. */
static bool find_program(const char *name, char *out, size_t cap)
{
    if (strchr(name, '/')) {
        int n = snprintf(out, cap, "%s", name);
        return n >= 0 && (size_t)n < cap && access(out, X_OK) == 0;
    }
    const char *path = getenv("PATH");
    if (!path)
        path = "/usr/local/bin:/usr/bin:/bin";
    while (*path) {
        const char *colon = strchr(path, ':');
        size_t len = colon ? (size_t)(colon - path) : strlen(path);
        int n = snprintf(out, cap, "%.*s/%s", (int)len, len ? path : ".", name);
        if (n >= 0 && (size_t)n < cap && access(out, X_OK) == 0)
            return true;
        path += len + (colon ? 1 : 0);
    }
    return false;
}

/* Reads `len` bytes at `off` of f. */
static bool read_at(FILE *f, long off, void *buf, size_t len)
{
    return fseek(f, off, SEEK_SET) == 0 && fread(buf, 1, len, f) == len;
}

/* The file offset of virtual address v in a 64-bit ELF's loaded segments. */
static bool elf_offset(const Elf64_Phdr *ph, size_t nph, uint64_t v, uint64_t *off)
{
    for (size_t i = 0; i < nph; i++)
        if (ph[i].p_type == PT_LOAD && v >= ph[i].p_vaddr && v - ph[i].p_vaddr < ph[i].p_filesz) {
            *off = ph[i].p_offset + (v - ph[i].p_vaddr);
            return true;
        }
    return false;
}

/* What emm run reads of the program's file. */
struct program_file {
    bool elf;       /* a 64-bit ELF that could be read */
    bool loader;    /* it names a dynamic loader (PT_INTERP): LD_PRELOAD applies */
    bool setid;     /* set-user-ID or set-group-ID: the loader ignores LD_PRELOAD paths */
    bool links_emm; /* it needs libemmhooks.so (a sancov build) or libemm.so (emm_tag_*
                       calls, the mesh interface): it captures its own accesses */
};

/* The program at `path`; anything unreadable is an unmodified program. */
static void read_program(const char *path, struct program_file *pf)
{
    memset(pf, 0, sizeof *pf);
    struct stat st;
    pf->setid = stat(path, &st) == 0 && (st.st_mode & (S_ISUID | S_ISGID));
    FILE *f = emm_infile_fopen(path, "program", NULL);
    if (!f)
        return;
    bool found = false;
    Elf64_Ehdr eh;
    Elf64_Phdr ph[64];
    if (!read_at(f, 0, &eh, sizeof eh) || memcmp(eh.e_ident, ELFMAG, SELFMAG) != 0 ||
        eh.e_ident[EI_CLASS] != ELFCLASS64 || eh.e_phentsize != sizeof(Elf64_Phdr) ||
        eh.e_phnum == 0 || eh.e_phnum > 64 ||
        !read_at(f, (long)eh.e_phoff, ph, eh.e_phnum * sizeof *ph))
        goto out;
    pf->elf = true;
    for (size_t i = 0; i < eh.e_phnum; i++)
        pf->loader |= ph[i].p_type == PT_INTERP;
    for (size_t i = 0; i < eh.e_phnum && !found; i++) {
        if (ph[i].p_type != PT_DYNAMIC)
            continue;
        size_t nd = ph[i].p_filesz / sizeof(Elf64_Dyn);
        Elf64_Dyn *dyn = nd && nd < 4096 ? malloc(nd * sizeof *dyn) : NULL;
        uint64_t strtab = 0, stroff;
        if (!dyn || !read_at(f, (long)ph[i].p_offset, dyn, nd * sizeof *dyn)) {
            free(dyn);
            goto out;
        }
        for (size_t k = 0; k < nd && dyn[k].d_tag != DT_NULL; k++)
            if (dyn[k].d_tag == DT_STRTAB)
                strtab = dyn[k].d_un.d_ptr;
        for (size_t k = 0; k < nd && dyn[k].d_tag != DT_NULL && !found; k++) {
            char name[64];
            if (dyn[k].d_tag != DT_NEEDED ||
                !elf_offset(ph, eh.e_phnum, strtab + dyn[k].d_un.d_val, &stroff) ||
                fseek(f, (long)stroff, SEEK_SET) != 0 || !fgets(name, sizeof name, f))
                continue;
            found = strncmp(name, "libemmhooks.so", 14) == 0 || strncmp(name, "libemm.so", 9) == 0;
        }
        free(dyn);
    }
out:
    fclose(f);
    pf->links_emm = found;
}

/* How the program will run under Valgrind: the tool's directory and the
 * launcher, or NULL with why not in `why`. */
static char *valgrind_setup(char *launcher, size_t lcap, char *why, size_t wcap)
{
    char tried[4096];
    char *tool = find_beside(VGTOOL_NAME, tried, sizeof tried);
    if (!tool) {
        snprintf(why, wcap, "emm's Valgrind tool is not beside this emm (it is built where "
                 "Valgrind's tool headers and libraries, Debian package valgrind, are "
                 "installed); tried %s", tried);
        return NULL;
    }
    if (!find_program("valgrind", launcher, lcap)) {
        free(tool);
        snprintf(why, wcap, "valgrind is not on PATH (Debian package valgrind)");
        return NULL;
    }
    *strrchr(tool, '/') = '\0';
    return tool;
}

static const char *get_env(const char *name)
{
    return getenv(name);
}

/* Puts `value` first in the colon-separated list of variable `name`;
 * returns setenv's result (-1 with errno on failure). */
static int prepend_env(const char *name, const char *value)
{
    const char *old = getenv(name);
    size_t len = strlen(value) + (old ? strlen(old) + 1 : 0) + 1;
    char *list = malloc(len);
    if (!list) {
        errno = ENOMEM;
        return -1;
    }
    if (old && *old)
        snprintf(list, len, "%s:%s", value, old);
    else
        snprintf(list, len, "%s", value);
    int rc = setenv(name, list, 1);
    free(list);
    return rc;
}

/* ---- starting the program and waiting for it ------------------------------- */

/* The program, while emm run waits for it. */
static volatile sig_atomic_t program_pid;

static void pass_on(int sig)
{
    if (program_pid > 0)
        kill((pid_t)program_pid, sig);
}

/* The signals a supervisor may send emm run meaning the program. */
static const int passed_on[] = {SIGTERM, SIGHUP, SIGUSR1, SIGUSR2};
/* The terminal's, which the program (in the same process group) gets
 * anyway: emm run ignores them, as system() and time(1) do. */
static const int ignored[] = {SIGINT, SIGQUIT};

static void set_handler(int sig, void (*fn)(int))
{
    struct sigaction act;
    memset(&act, 0, sizeof act);
    act.sa_handler = fn;
    act.sa_flags = SA_RESTART;
    sigemptyset(&act.sa_mask);
    sigaction(sig, &act, NULL);
}

/* Ends this process as the program ended: its exit status, or the signal
 * that ended it raised again (without a second core dump). */
static int end_as(int status)
{
    if (WIFEXITED(status))
        return WEXITSTATUS(status);
    if (!WIFSIGNALED(status))
        return EMM_EXIT_FAIL;
    int sig = WTERMSIG(status);
    struct rlimit none = {0, 0};
    setrlimit(RLIMIT_CORE, &none);
    fflush(NULL);
    signal(sig, SIG_DFL);
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, sig);
    sigprocmask(SIG_UNBLOCK, &set, NULL);
    raise(sig);
    return 128 + sig; /* a signal that does not end a process by default */
}

/* Why the shim did not load into the program, which ended with `status`. */
static const char *why_not_loaded(const struct program_file *pf, int status)
{
    if (pf->elf && !pf->loader)
        return "it is statically linked, and only the dynamic loader preloads the shim "
               "(link it dynamically)";
    if (pf->setid)
        return "it is set-user-ID or set-group-ID, and the loader preloads nothing from a "
               "path into such a program (run a copy without the bit)";
    /* The loader's own status when a library is missing: it said why. */
    if (pf->loader && WIFEXITED(status) && WEXITSTATUS(status) == 127)
        return "the dynamic loader could not start it (exit status 127: a library it needs "
               "was not found, its message is above)";
    return "the loader did not preload libemmshim.so into it";
}

/* The valgrind capture's emm-session as emm run started it (start_session):
 * the program's end of its socket (0: none), the read end of the pipe it
 * closes once its outputs are written (-1: none), its pid. */
struct started_session {
    int sock, done;
    pid_t pid;
};

/* Whether process `name` (a number) is a child of this process named
 * emm-session that has not ended. */
static bool is_session_child(const char *name)
{
    char path[64], line[256], comm[64] = "", state = 0;
    long ppid = 0;
    snprintf(path, sizeof path, "/proc/%.20s/stat", name);
    FILE *f = fopen(path, "r");
    if (!f)
        return false;
    bool yes = fgets(line, sizeof line, f) &&
               sscanf(line, "%*d (%63[^)]) %c %ld", comm, &state, &ppid) == 3 &&
               ppid == (long)getpid() && state != 'Z' && strcmp(comm, "emm-session") == 0;
    fclose(f);
    return yes;
}

/* A child of this process named emm-session that has not ended, other than
 * `skip`, or 0: from the kernel's list of this (single-threaded) process's
 * children, or, where it has none, from every process in /proc. */
static pid_t session_child(pid_t skip)
{
    char path[64], pid[24];
    snprintf(path, sizeof path, "/proc/self/task/%ld/children", (long)getpid());
    FILE *f = fopen(path, "r");
    if (f) {
        pid_t found = 0;
        while (!found && fscanf(f, "%23s", pid) == 1)
            if (atol(pid) != (long)skip && is_session_child(pid))
                found = (pid_t)atol(pid);
        fclose(f);
        return found;
    }
    pid_t found = 0;
    DIR *d = opendir("/proc");
    struct dirent *e;
    while (d && !found && (e = readdir(d)) != NULL)
        if (e->d_name[0] >= '1' && e->d_name[0] <= '9' && atol(e->d_name) != (long)skip &&
            is_session_child(e->d_name))
            found = (pid_t)atol(e->d_name);
    if (d)
        closedir(d);
    return found;
}

/* Waits at most ms milliseconds for process pid (a child) to end, without
 * reaping it: on a descriptor of the process where the kernel has them
 * (Linux 5.3), else in steps of a millisecond. */
static void wait_end(pid_t pid, long ms)
{
#ifdef SYS_pidfd_open
    int fd = (int)syscall(SYS_pidfd_open, pid, 0);
    if (fd >= 0) {
        struct pollfd p = {.fd = fd, .events = POLLIN};
        while (poll(&p, 1, (int)ms) < 0 && errno == EINTR) {
        }
        close(fd);
        return;
    }
#endif
    siginfo_t si;
    struct timespec step = {0, 1000 * 1000};
    for (long t = 0; t < ms; t++) {
        si.si_pid = 0;
        if (waitid(P_PID, (id_t)pid, &si, WEXITED | WNOHANG | WNOWAIT) != 0 || si.si_pid)
            return;
        nanosleep(&step, NULL);
    }
}

/* Whether every writer of pipe `fd` closed it within ms milliseconds. */
static bool wait_closed(int fd, int ms)
{
    struct pollfd p = {.fd = fd, .events = POLLIN};
    char byte;
    for (;;) {
        int r = poll(&p, 1, ms);
        if (r < 0 && errno == EINTR)
            continue;
        if (r <= 0)
            return false;
        if (read(fd, &byte, 1) <= 0)
            return true;
    }
}

/* The valgrind capture's session processes (emm-session) that outlive the
 * program — it closed their socket with its other descriptors, or died,
 * before finishing with them, or they are still ending — write its report
 * when they see the connection end. emm run is the subreaper of the
 * program's processes, so they are its children now: it waits for them, at
 * most 60 s in all, so that the report is there and the summary printed
 * when it returns; each is waited for until it ends, not polled (a session
 * that ends a few milliseconds after the program, freeing its memory, once
 * cost a 50 ms sleep). The one emm run started says when its outputs are
 * written (started->done): it is not waited for past that, nor while it
 * frees its memory and ends (10 to 25 ms after a 100,000-face run). Any
 * other orphan that has ended is reaped on the way; one that runs on is
 * left. */
static void wait_sessions(const struct started_session *started)
{
    struct timespec start, now;
    clock_gettime(CLOCK_MONOTONIC, &start);
    pid_t skip = 0;
    if (started && started->done >= 0 && wait_closed(started->done, 60000))
        skip = started->pid;
    for (;;) {
        while (waitpid(-1, NULL, WNOHANG) > 0) {
        }
        pid_t s = session_child(skip);
        if (!s)
            return;
        clock_gettime(CLOCK_MONOTONIC, &now);
        long left = 60000 - ((now.tv_sec - start.tv_sec) * 1000 +
                             (now.tv_nsec - start.tv_nsec) / 1000000);
        if (left <= 0)
            return;
        wait_end(s, left);
    }
}

/* Starts emm-session at `path` for the valgrind capture's program, while
 * Valgrind starts: in the program, under Valgrind, its two forks and the
 * session's own start came before the program's first instruction (about
 * 60 ms). Its child, with the pipe it closes once its outputs are written
 * (session_server_start). sock 0 when it could not start: the shim then
 * starts one itself. A program that never takes the socket over
 * (EMM_AGENT_SESSION_VAR) closes it by ending, and the session ends
 * without a word. */
static struct started_session start_session(const char *path)
{
    struct started_session r = {0, -1, 0};
    emm_error err;
    if (access(path, X_OK) == 0) /* r is left as it is when the start fails */
        session_server_start(path, false, &r.sock, &r.done, &r.pid, &err);
    return r;
}

/* Starts `file` with `av` (through PATH when `search`), waits for it and
 * returns the status to end with. With `say`, when the shim did not answer
 * from the program (emm/agent.h, EMM_AGENT_READY_VAR), one line names it
 * as `shown` and says why. */
static int run_program(const char *file, char **av, bool search, const char *shown,
                       const struct program_file *pf, bool say,
                       const struct started_session *started)
{
    int session = started ? started->sock : 0;
    int ready[2], failed[2];
    if (pipe2(ready, O_CLOEXEC) != 0)
        goto no_pipe;
    if (pipe2(failed, O_CLOEXEC) != 0) {
        close(ready[0]);
        close(ready[1]);
        goto no_pipe;
    }
    fflush(NULL);
    prctl(PR_SET_CHILD_SUBREAPER, 1);
    pid_t pid = fork();
    if (pid == 0) {
        /* The write end stays open in the program for the shim; the other
         * pipe closes at exec, or carries exec's error. */
        char v[64], sv[64];
        snprintf(v, sizeof v, "%d:%ld", ready[1], (long)getpid());
        snprintf(sv, sizeof sv, "%d:%ld", session, (long)getpid());
        if (session && (fcntl(session, F_SETFD, 0) != 0 ||
                        setenv(EMM_AGENT_SESSION_VAR, sv, 1) != 0))
            close(session); /* the shim starts a session itself */
        if (fcntl(ready[1], F_SETFD, 0) == 0 && setenv(EMM_AGENT_READY_VAR, v, 1) == 0) {
            if (search)
                execvp(file, av);
            else
                execv(file, av);
        }
        int e = errno;
        ssize_t w = write(failed[1], &e, sizeof e);
        (void)w;
        _exit(e == ENOENT ? 127 : 126);
    }
    int e = errno;
    close(ready[1]);
    close(failed[1]);
    if (session)
        close(session);
    if (pid < 0) {
        close(ready[0]);
        close(failed[0]);
        cli_error("run: cannot start '%s': %s", file, strerror(e));
        return EMM_EXIT_FAIL;
    }
    program_pid = pid;
    for (size_t k = 0; k < sizeof passed_on / sizeof *passed_on; k++)
        set_handler(passed_on[k], pass_on);
    for (size_t k = 0; k < sizeof ignored / sizeof *ignored; k++)
        set_handler(ignored[k], SIG_IGN);
    ssize_t got;
    e = 0;
    while ((got = read(failed[0], &e, sizeof e)) < 0 && errno == EINTR) {
    }
    close(failed[0]);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    program_pid = 0;
    wait_sessions(started);
    if (started && started->done >= 0)
        close(started->done);
    char byte;
    bool answered = fcntl(ready[0], F_SETFL, O_NONBLOCK) == 0 && read(ready[0], &byte, 1) == 1;
    close(ready[0]);
    if (got == (ssize_t)sizeof e) {
        /* As a shell does: 127 when the program is not found, 126 when it
         * cannot run. */
        cli_error("run: cannot run '%s': %s", file, strerror(e));
        return e == ENOENT ? 127 : 126;
    }
    if (!answered && say)
        cli_error("run: %s ran without emm, nothing captured: %s", shown,
                  why_not_loaded(pf, status));
    return end_as(status);
no_pipe:
    cli_error("run: cannot make a pipe: %s", strerror(errno));
    return EMM_EXIT_FAIL;
}

/* The options as they are parsed, each by its row of the configuration
 * table. */
struct run_options {
    emm_config cfg;
    const char *values[EMM_CONFIG_COUNT]; /* as given, for the environment */
    unsigned given;                       /* 1u << key for each one given */
};

/* Sets the row whose option or switch `as` is; a bad value stops here,
 * naming the option, before the program starts. */
static bool run_option(void *dst, const char *as, const char *value)
{
    struct run_options *ro = dst;
    const char *fixed;
    emm_error err;
    emm_config_key k = emm_config_find_option(as, &fixed);
    if (fixed)
        value = fixed;
    if (emm_config_set(&ro->cfg, k, value, as, (long)getpid(), &err) != EMM_OK) {
        cli_bad_value("run", &err);
        return false;
    }
    ro->values[k] = value;
    ro->given |= 1u << k;
    return true;
}

int emm_cmd_run(int argc, char **argv)
{
    struct run_options ro = {0};
    opts_row rows[EMM_CONFIG_COUNT * (1 + EMM_CONFIG_SWITCHES) + 2];
    size_t n = 0;
    emm_error err;
    int i = argc, rc;

    /* A row for each option and each switch of the configuration table,
     * then PROGRAM, which ends the options. */
    emm_config_init(&ro.cfg);
    for (int k = 0; k < EMM_CONFIG_COUNT; k++) {
        const emm_config_row *r = emm_config_row_get((emm_config_key)k);
        if (r->option)
            rows[n++] = (opts_row){.name = r->option, .metavar = r->metavar, .kind = OPT_CALL,
                                   .dst = &ro, .call = run_option};
        for (int w = 0; w < EMM_CONFIG_SWITCHES && r->switches[w].option; w++)
            rows[n++] = (opts_row){.name = r->switches[w].option, .kind = OPT_CALL, .dst = &ro,
                                   .call = run_option};
    }
    rows[n++] = (opts_row){.metavar = "PROGRAM", .kind = OPT_REST, .dst = &i, .required = true};
    rows[n] = (opts_row)OPTS_END;
    opts o = {"run", rows, usage};
    if (opts_parse(&o, argc, argv, &rc))
        return rc;
    emm_config cfg = ro.cfg;
    const char **values = ro.values;
    /* The variables the options leave alone, as the shim will read them;
     * then what only a session can check (a machine file's keys, a table's
     * samples), as the shim will start it. */
    if (emm_config_from_env(&cfg, get_env, (long)getpid(), ro.given, &err) != EMM_OK)
        return cli_bad_value("run", &err);
    emm_session_config sc = {&cfg, cfg.capture, argv[i], 0, {1, NULL, NULL}, NULL, NULL, 0, 0, 0};
    emm_session *probe;
    if (emm_session_new(&sc, &probe, &err) != EMM_OK)
        return cli_bad_value("run", &err);
    emm_session_free(probe);

    /* Valgrind when asked, or for an unmodified binary under auto. */
    char launcher[PATH_MAX], program[PATH_MAX], why[8192];
    char *vgdir = NULL;
    struct program_file pf = {0};
    bool found = find_program(argv[i], program, sizeof program);
    if (found)
        read_program(program, &pf);
    if (emm_capture_caps(cfg.capture) & EMM_CAP_VALGRIND) {
        if (!(vgdir = valgrind_setup(launcher, sizeof launcher, why, sizeof why))) {
            cli_error("run: --capture valgrind is unavailable: %s", why);
            return EMM_EXIT_FAIL;
        }
    } else if (cfg.capture == EMM_CAPTURE_AUTO && found && !pf.links_emm) {
        /* Valgrind before the fault capture: it covers the whole run in
         * about the time the fault capture takes for the window alone
         * (bench/fault_overhead.sh); and --list-sites reads records from
         * the program's accesses, which the fault capture does not see. */
        vgdir = valgrind_setup(launcher, sizeof launcher, why, sizeof why);
        if (cfg.log >= 2)
            cli_error("run: --capture auto: %s for %s, which neither links emm's coverage hooks "
                     "nor calls emm: %s", vgdir ? "valgrind" : "fault", argv[i],
                     vgdir ? "emm's Valgrind tool captures the whole run, in about the time the "
                             "fault capture, at tens of microseconds an access, takes for the "
                             "profiling window alone (README, Capture backends)"
                           : why);
    } else if (cfg.capture == EMM_CAPTURE_AUTO && !cfg.list_sites && found && cfg.log >= 2) {
        cli_error("run: --capture auto: %s links emm (coverage hooks or emm calls): the shim "
                 "captures its accesses itself (sancov or api)", argv[i]);
    }

    int bad = 0;
    bool under_valgrind = vgdir != NULL;
    char server[PATH_MAX + 32] = "";
    if (vgdir) {
        /* The shim finds emm-session beside its preload, the tool's. */
        if (!cfg.list_sites)
            snprintf(server, sizeof server, "%s/emm-session", vgdir);
        bad |= setenv("VALGRIND_LIB", vgdir, 1);
        /* Under auto the shim picks the valgrind capture itself (it runs
         * under emm's tool), and the summary says it was auto's pick. */
        if (cfg.capture != EMM_CAPTURE_AUTO)
            values[EMM_CONFIG_CAPTURE] = emm_capture_name(cfg.capture);
        free(vgdir);
    } else {
        char tried[4096];
        char *shim = find_beside(SHIM_NAME, tried, sizeof tried);
        if (!shim) {
            cli_error("run: cannot find %s; tried %s", SHIM_NAME, tried);
            return EMM_EXIT_FAIL;
        }
        bad |= prepend_env("LD_PRELOAD", shim);
        free(shim);
    }
    /* This emm's libdir goes first in LD_LIBRARY_PATH: a program built
     * against an emm (libemmhooks.so, libemm.so) finds the libraries of
     * the emm that runs it, whatever run path its build recorded — an
     * install moved since, or another one (docs/design.md "Processes"). */
    char tried[4096], *hooks = find_beside(HOOKS_NAME, tried, sizeof tried);
    if (hooks) {
        *strrchr(hooks, '/') = '\0';
        bad |= prepend_env("LD_LIBRARY_PATH", hooks);
        free(hooks);
    }
    for (int k = 0; k < EMM_CONFIG_COUNT; k++)
        if (values[k])
            bad |= setenv(emm_config_row_get((emm_config_key)k)->var, values[k], 1);
    /* The program is the root of its tree, even when emm run itself runs
     * under a shim (emm/agent.h). */
    bad |= unsetenv(EMM_AGENT_ROOT_VAR);
    if (bad) {
        cli_error("run: cannot set the environment: %s", strerror(errno));
        return EMM_EXIT_FAIL;
    }
    bool say = cfg.log >= 1 && found;
    if (!under_valgrind)
        return run_program(argv[i], argv + i, true, argv[i], &pf, say, NULL);
    /* valgrind --tool=emm -q --trace-children=yes PROGRAM ARGS...: exec'd
     * programs are captured too, as LD_PRELOAD carries the shim for the
     * other backends; not the session's own process, which runs natively
     * beside the program (server/, runtime/session_proxy.c), nor the
     * helpers the shim never enters (symbolizers). */
    static const char *const pre[] = {"valgrind", "--tool=emm", "-q", "--trace-children=yes"};
    char skip[512] = "--trace-children-skip=*/emm-session";
#define SKIP_HELPER(n) strncat(skip, ",*/" n "*", sizeof skip - strlen(skip) - 1);
    EMM_AGENT_HELPERS(SKIP_HELPER)
#undef SKIP_HELPER
    size_t np = sizeof pre / sizeof *pre, na = (size_t)(argc - i);
    char **vargv = calloc(np + 1 + na + 1, sizeof *vargv);
    if (!vargv) {
        cli_error("run: out of memory");
        return EMM_EXIT_FAIL;
    }
    for (size_t k = 0; k < np; k++)
        vargv[k] = (char *)pre[k];
    vargv[np] = skip;
    for (size_t k = 0; k < na; k++)
        vargv[np + 1 + k] = argv[i + (int)k];
    /* Started last, with the environment the program gets. */
    struct started_session started = {0, -1, 0};
    if (server[0])
        started = start_session(server);
    rc = run_program(launcher, vargv, false, argv[i], &pf, say, &started);
    free(vargv);
    return rc;
}
