/* The EMM_* environment: one descriptor table (STYLE.md §8, after mimalloc's
 * options.c). Each row names a variable, what it accepts, its default, its
 * help text and the function that parses it; everything else (validation
 * messages, `emm run --help`, the EMM_LOG=2 dump) reads the rows. */
#include "env.h"

#include <errno.h>
#include <stddef.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "emm/profile.h"
#include "emm/strategy.h"
#include "parse.h"

typedef bool (*env_parser)(const char *v, struct shim_env *e, long pid,
                           shim_env_tag_check tag_check, char *why, size_t cap);

struct env_row {
    const char *name;
    const char *accepts;  /* what a value may be: printed after "expected" */
    const char *def;      /* the default, as text */
    const char *help;
    env_parser parse;
};

static bool parse_tag(const char *v, struct shim_env *e, long pid, shim_env_tag_check check,
                      char *why, size_t cap)
{
    (void)pid;
    if (check && !check(v, why, cap))
        return false;
    e->tag = v;
    return true;
}

static bool parse_capture(const char *v, struct shim_env *e, long pid, shim_env_tag_check check,
                          char *why, size_t cap)
{
    (void)pid; (void)check; (void)why; (void)cap;
    static const char *const names[] = {"auto", "sancov", "fault", "api"};
    for (size_t i = 0; i < sizeof names / sizeof *names; i++)
        if (strcmp(v, names[i]) == 0) {
            e->capture = (enum shim_capture)i;
            return true;
        }
    return false;
}

/* N[K|M|G] accesses, or Nit iterations; N >= 1. */
static bool parse_window(const char *v, struct shim_env *e, long pid, shim_env_tag_check check,
                         char *why, size_t cap)
{
    (void)pid; (void)check; (void)why; (void)cap;
    size_t n = strlen(v);
    uint64_t x;
    if (n > 2 && strcmp(v + n - 2, "it") == 0) {
        char digits[32];
        if (n - 2 >= sizeof digits)
            return false;
        memcpy(digits, v, n - 2);
        digits[n - 2] = '\0';
        if (!emm_parse_u64(digits, &x) || x == 0)
            return false;
        e->window_accesses = 0;
        e->window_iterations = x;
        return true;
    }
    if (!emm_parse_size(v, &x) || x == 0)
        return false;
    e->window_accesses = x;
    e->window_iterations = 0;
    return true;
}

static bool parse_strategy(const char *v, struct shim_env *e, long pid, shim_env_tag_check check,
                           char *why, size_t cap)
{
    (void)pid; (void)check;
    emm_strategy s;
    emm_error err;
    if (emm_strategy_parse(v, &s, &err) != EMM_OK) {
        snprintf(why, cap, "%s", err.message);
        return false;
    }
    e->strategy = v;
    return true;
}

static bool parse_compare(const char *v, struct shim_env *e, long pid, shim_env_tag_check check,
                          char *why, size_t cap)
{
    (void)pid; (void)check; (void)why; (void)cap;
    if (strcmp(v, "baselines") == 0)
        e->compare = EMM_COMPARE_BASELINES;
    else if (strcmp(v, "all") == 0)
        e->compare = EMM_COMPARE_ALL;
    else if (strcmp(v, "none") == 0)
        e->compare = EMM_COMPARE_NONE;
    else
        return false;
    return true;
}

/* An input file: it must exist, be readable and not be a directory. Its
 * content is the session's to check. */
static bool check_input(const char *v, char *why, size_t cap)
{
    struct stat st;
    if (stat(v, &st) != 0) {
        snprintf(why, cap, "%s", strerror(errno));
        return false;
    }
    if (S_ISDIR(st.st_mode)) {
        snprintf(why, cap, "is a directory, expected a file");
        return false;
    }
    if (access(v, R_OK) != 0) {
        snprintf(why, cap, "not readable");
        return false;
    }
    return true;
}

static bool parse_machine(const char *v, struct shim_env *e, long pid, shim_env_tag_check check,
                          char *why, size_t cap)
{
    (void)pid; (void)check;
    if (!check_input(v, why, cap))
        return false;
    e->machine = v;
    return true;
}

static bool parse_table(const char *v, struct shim_env *e, long pid, shim_env_tag_check check,
                        char *why, size_t cap)
{
    (void)pid; (void)check;
    if (!check_input(v, why, cap))
        return false;
    e->table = v;
    return true;
}

/* An output path: %p becomes the pid, %% a percent sign; its directory must
 * exist and be writable now, so a report is not lost at exit. */
static bool output_path(const char *v, long pid, char out[SHIM_PATH_MAX], char *why, size_t cap)
{
    size_t o = 0;
    for (const char *p = v; *p; p++) {
        char piece[32];
        size_t len;
        if (p[0] == '%' && p[1] == 'p') {
            len = (size_t)snprintf(piece, sizeof piece, "%ld", pid);
            p++;
        } else if (p[0] == '%' && p[1] == '%') {
            piece[0] = '%';
            len = 1;
            p++;
        } else {
            piece[0] = *p;
            len = 1;
        }
        if (o + len >= SHIM_PATH_MAX) {
            snprintf(why, cap, "path too long");
            return false;
        }
        memcpy(out + o, piece, len);
        o += len;
    }
    out[o] = '\0';
    if (out[o - 1] == '/') {
        snprintf(why, cap, "expected a file path, not a directory");
        return false;
    }
    struct stat st;
    if (stat(out, &st) == 0 && S_ISDIR(st.st_mode)) {
        snprintf(why, cap, "is a directory, expected a file path");
        return false;
    }
    char dir[SHIM_PATH_MAX];
    const char *slash = strrchr(out, '/');
    if (!slash) {
        strcpy(dir, ".");
    } else if (slash == out) {
        strcpy(dir, "/");
    } else {
        memcpy(dir, out, (size_t)(slash - out));
        dir[slash - out] = '\0';
    }
    if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
        snprintf(why, cap, "directory %s does not exist", dir);
        return false;
    }
    if (access(dir, W_OK | X_OK) != 0) {
        snprintf(why, cap, "directory %s is not writable", dir);
        return false;
    }
    return true;
}

static bool parse_report(const char *v, struct shim_env *e, long pid, shim_env_tag_check check,
                         char *why, size_t cap)
{
    (void)check;
    return output_path(v, pid, e->report, why, cap);
}

static bool parse_dump(const char *v, struct shim_env *e, long pid, shim_env_tag_check check,
                       char *why, size_t cap)
{
    (void)check;
    return output_path(v, pid, e->profile_dump, why, cap);
}

static bool parse_trace(const char *v, struct shim_env *e, long pid, shim_env_tag_check check,
                        char *why, size_t cap)
{
    (void)check;
    return output_path(v, pid, e->trace, why, cap);
}

static bool parse_log(const char *v, struct shim_env *e, long pid, shim_env_tag_check check,
                      char *why, size_t cap)
{
    (void)pid; (void)check; (void)why; (void)cap;
    static const char *const words[] = {"quiet", "summary", "verbose"};
    for (int i = 0; i < 3; i++) {
        char digit[2] = {(char)('0' + i), '\0'};
        if (strcmp(v, digit) == 0 || strcmp(v, words[i]) == 0) {
            e->log = i;
            return true;
        }
    }
    return false;
}

static bool parse_strict(const char *v, struct shim_env *e, long pid, shim_env_tag_check check,
                         char *why, size_t cap)
{
    (void)pid; (void)check; (void)why; (void)cap;
    if (strcmp(v, "0") != 0 && strcmp(v, "1") != 0)
        return false;
    e->strict = v[0] == '1';
    return true;
}

/* The table. EMM_STRICT comes first: it decides what a later bad value does. */
static const struct env_row rows[] = {
    {"EMM_STRICT", "0 or 1", "0",
     "1: a bad EMM_* value or a session that cannot start stops the program (exit 125)\n"
     "instead of letting it run without emm", parse_strict},
    {"EMM_TAG", "rules KIND:key=value,...;... (see below)", "(none)",
     "tag arrays by rule, e.g. vertices:site=read_mesh,stride=80,xyz=8:f64", parse_tag},
    {"EMM_CAPTURE", "auto, sancov, fault or api", "auto",
     "how accesses are seen: sancov (a build with emm_sancov_executable), fault (page\n"
     "protection, profiling window only), api (programs using emm_mesh_*); auto picks", parse_capture},
    {"EMM_PROFILE", "a count of accesses (16384, 16K) or of iterations (5it), at least 1", "16384",
     "the profiling window: element accesses, or emm_iteration() calls with 'it'", parse_window},
    {"EMM_STRATEGY", "a strategy: direct, cache[@LAYOUT] or LAYOUT+FETCH[@CELL]", "(decide)",
     "skip the decision and simulate this strategy, e.g. tiles+convolution@64", parse_strategy},
    {"EMM_COMPARE", "baselines, all or none", "baselines",
     "also simulate direct reads and the cache (baselines), the whole sweep (all) or nothing", parse_compare},
    {"EMM_MACHINE", "a readable machine file", "(built-in)",
     "the machine model's parameters (see emm machine --help)", parse_machine},
    {"EMM_TABLE", "a readable strategy table file", "(shipped table only)",
     "a user table of sample profiles, consulted with the shipped one", parse_table},
    {"EMM_REPORT", "a file path in a writable directory (%p: pid)", "(none)",
     "write the JSON report there at exit", parse_report},
    {"EMM_PROFILE_DUMP", "a file path in a writable directory (%p: pid)", "(none)",
     "write the distance profile as CSV (i,D_i)", parse_dump},
    {"EMM_TRACE", "a file path in a writable directory (%p: pid)", "(none)",
     "write the access trace, for emm replay", parse_trace},
    {"EMM_LOG", "0, 1, 2, quiet, summary or verbose", "1",
     "0: nothing on stderr; 1: the summary at exit; 2: also what the shim does", parse_log},
};

#define NROWS (sizeof rows / sizeof *rows)

const char *shim_capture_name(enum shim_capture c)
{
    switch (c) {
    case SHIM_CAPTURE_AUTO: return "auto";
    case SHIM_CAPTURE_SANCOV: return "sancov";
    case SHIM_CAPTURE_FAULT: return "fault";
    case SHIM_CAPTURE_API: return "api";
    }
    return "?";
}

bool shim_env_parse(struct shim_env *e, const char *(*get)(const char *name), long pid,
                    shim_env_tag_check tag_check, char *msg, size_t cap)
{
    memset(e, 0, sizeof *e);
    e->capture = SHIM_CAPTURE_AUTO;
    e->window_accesses = EMM_PROFILE_DEFAULT_WINDOW;
    e->compare = EMM_COMPARE_BASELINES;
    e->log = 1;
    for (size_t i = 0; i < NROWS; i++) {
        const char *v = get(rows[i].name);
        if (!v)
            continue;
        char why[512] = "";
        if (*v == '\0' || !rows[i].parse(v, e, pid, tag_check, why, sizeof why)) {
            /* Long values are cut so the message stays one readable line. */
            int shown = strlen(v) > 80 ? 77 : 80;
            const char *dots = strlen(v) > 80 ? "..." : "";
            if (why[0])
                snprintf(msg, cap, "%s='%.*s%s': %s", rows[i].name, shown, v, dots, why);
            else
                snprintf(msg, cap, "%s='%.*s%s': expected %s", rows[i].name, shown, v, dots,
                         rows[i].accepts);
            return false;
        }
    }
    return true;
}

void shim_env_help(FILE *out)
{
    fprintf(out, "Environment (read by libemmshim.so; emm run's options set them):\n");
    for (size_t i = 0; i < NROWS; i++) {
        fprintf(out, "  %-17s %s (default: %s)\n", rows[i].name, rows[i].accepts, rows[i].def);
        const char *h = rows[i].help;
        while (*h) {
            const char *nl = strchr(h, '\n');
            size_t len = nl ? (size_t)(nl - h) : strlen(h);
            fprintf(out, "  %-17s   %.*s\n", "", (int)len, h);
            h += len + (nl ? 1 : 0);
        }
    }
    fprintf(out,
            "\nEMM_TAG rules are split by ';', each KIND:key=value,... with KIND vertices or\n"
            "triangles. Selectors: site=FUNCTION (the function that makes the allocation,\n"
            "looking past allocator and C++ standard-library frames such as std::vector's),\n"
            "min=BYTES (K/M/G; default max(stride, 4K)), nth=N (the Nth block the other\n"
            "selectors select, from 1). Record: stride=BYTES (required), xyz=OFFSET:f32|f64\n"
            "(vertices), vidx=OFFSET:i32|u32|i64 (triangles). Count = block size / stride;\n"
            "a block must be a whole number of records. A rule with site= follows the first\n"
            "allocation call in that function it selects (a growing std::vector reallocates\n"
            "from that same call); the function's other allocations go to later rules, so\n"
            "list the rules in the order the program allocates the arrays.\n"
            "A bad value gets one line on stderr and the program runs without emm.\n");
}

void shim_env_dump(const struct shim_env *e, FILE *out)
{
    fprintf(out, "emm:   EMM_TAG=%s\n", e->tag ? e->tag : "");
    fprintf(out, "emm:   EMM_CAPTURE=%s\n", shim_capture_name(e->capture));
    if (e->window_accesses)
        fprintf(out, "emm:   EMM_PROFILE=%llu\n", (unsigned long long)e->window_accesses);
    else
        fprintf(out, "emm:   EMM_PROFILE=%lluit\n", (unsigned long long)e->window_iterations);
    fprintf(out, "emm:   EMM_STRATEGY=%s\n", e->strategy ? e->strategy : "");
    fprintf(out, "emm:   EMM_COMPARE=%s\n",
            e->compare == EMM_COMPARE_ALL ? "all" : e->compare == EMM_COMPARE_NONE ? "none" : "baselines");
    fprintf(out, "emm:   EMM_MACHINE=%s\n", e->machine ? e->machine : "");
    fprintf(out, "emm:   EMM_TABLE=%s\n", e->table ? e->table : "");
    fprintf(out, "emm:   EMM_REPORT=%s\n", e->report);
    fprintf(out, "emm:   EMM_PROFILE_DUMP=%s\n", e->profile_dump);
    fprintf(out, "emm:   EMM_TRACE=%s\n", e->trace);
    fprintf(out, "emm:   EMM_LOG=%d\n", e->log);
    fprintf(out, "emm:   EMM_STRICT=%d\n", e->strict ? 1 : 0);
}
