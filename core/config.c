/* The configuration table (include/emm/config.h; after
 * mimalloc's options.c). Each row names a variable, its `emm run` option,
 * what it accepts, its default, its help and the function that parses it;
 * everything else — the environment, the options, validation messages,
 * `emm run --help`, the EMM_LOG=2 dump — reads the rows. */
#include "emm/config.h"

#include <errno.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "error.h"
#include "parse.h"

/* Parses v into c; false with `why` filled (or left empty for "expected
 * <accepts>"). */
typedef bool (*row_parser)(emm_config *c, const char *v, long pid, char *why, size_t cap);

static const char *const capture_names[EMM_CAPTURE_COUNT] = {
    "auto",
#define CAPTURE_NAME(N, n, caps, work, help) #n,
    EMM_CAPTURE_LIST(CAPTURE_NAME)
#undef CAPTURE_NAME
};
static const unsigned capture_caps[EMM_CAPTURE_COUNT] = {
    0,
#define CAPTURE_CAPS(N, n, caps, work, help) caps,
    EMM_CAPTURE_LIST(CAPTURE_CAPS)
#undef CAPTURE_CAPS
};
static const char *const capture_work_units[EMM_CAPTURE_COUNT] = {
    NULL,
#define CAPTURE_WORK(N, n, caps, work, help) work,
    EMM_CAPTURE_LIST(CAPTURE_WORK)
#undef CAPTURE_WORK
};
static const char *const compare_names[EMM_COMPARE_COUNT] = {"baselines", "all", "none"};
static const char *const log_words[] = {"quiet", "summary", "verbose"};

const char *emm_capture_name(emm_capture c)
{
    return (unsigned)c < EMM_CAPTURE_COUNT ? capture_names[c] : "?";
}

unsigned emm_capture_caps(emm_capture c)
{
    return (unsigned)c < EMM_CAPTURE_COUNT ? capture_caps[c] : 0;
}

const char *emm_capture_work_unit(emm_capture c)
{
    return (emm_capture_caps(c) & EMM_CAP_WORK) ? capture_work_units[c] : NULL;
}

const char *emm_compare_name(emm_compare c)
{
    return (unsigned)c < EMM_COMPARE_COUNT ? compare_names[c] : "?";
}

/* The index of v in words[0..n), or -1. */
static int word(const char *v, const char *const *words, int n)
{
    for (int i = 0; i < n; i++)
        if (strcmp(v, words[i]) == 0)
            return i;
    return -1;
}

/* "0" or "1" into *flag. */
static bool parse_01(const char *v, int *flag)
{
    if (strcmp(v, "0") != 0 && strcmp(v, "1") != 0)
        return false;
    *flag = v[0] == '1';
    return true;
}

static bool parse_strict(emm_config *c, const char *v, long pid, char *why, size_t cap)
{
    (void)pid; (void)why; (void)cap;
    return parse_01(v, &c->strict);
}

static bool parse_phases(emm_config *c, const char *v, long pid, char *why, size_t cap)
{
    (void)pid; (void)why; (void)cap;
    return parse_01(v, &c->phases);
}

static bool parse_list_sites(emm_config *c, const char *v, long pid, char *why, size_t cap)
{
    (void)pid; (void)why; (void)cap;
    return parse_01(v, &c->list_sites);
}

/* The rules replace c's (emm_config_set frees the old ones once the value
 * is taken). */
static bool parse_tag(emm_config *c, const char *v, long pid, char *why, size_t cap)
{
    (void)pid;
    emm_error e;
    if (emm_tag_rules_parse(v, &c->tags, &e) != EMM_OK) {
        snprintf(why, cap, "%s", e.message);
        return false;
    }
    return true;
}

static bool parse_capture(emm_config *c, const char *v, long pid, char *why, size_t cap)
{
    (void)pid; (void)why; (void)cap;
    int k = word(v, capture_names, EMM_CAPTURE_COUNT);
    if (k < 0)
        return false;
    c->capture = (emm_capture)k;
    return true;
}

/* N[K|M|G] accesses, or Nit iterations; N >= 1. */
static bool parse_window(emm_config *c, const char *v, long pid, char *why, size_t cap)
{
    (void)pid; (void)why; (void)cap;
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
        c->window_accesses = 0;
        c->window_iterations = x;
        return true;
    }
    if (!emm_parse_size(v, &x) || x == 0)
        return false;
    c->window_accesses = x;
    c->window_iterations = 0;
    return true;
}

static bool parse_strategy(emm_config *c, const char *v, long pid, char *why, size_t cap)
{
    (void)pid;
    emm_error e;
    if (emm_strategy_parse(v, &c->strategy, &e) != EMM_OK) {
        snprintf(why, cap, "%s", e.message);
        return false;
    }
    c->has_strategy = 1;
    return true;
}

static bool parse_compare(emm_config *c, const char *v, long pid, char *why, size_t cap)
{
    (void)pid; (void)why; (void)cap;
    int k = word(v, compare_names, EMM_COMPARE_COUNT);
    if (k < 0)
        return false;
    c->compare = (emm_compare)k;
    return true;
}

static bool parse_finalists(emm_config *c, const char *v, long pid, char *why, size_t cap)
{
    (void)pid; (void)why; (void)cap;
    uint64_t x;
    if (strcmp(v, "all") == 0) {
        c->finalists = EMM_CONFIG_FINALISTS_ALL;
        return true;
    }
    if (!emm_parse_u64(v, &x) || x > 64)
        return false;
    c->finalists = (unsigned)x;
    return true;
}

/* An input file: it must exist, be readable and not be a directory. Its
 * content is the session's to check. */
static bool input_path(const char *v, char out[EMM_CONFIG_PATH_MAX], char *why, size_t cap)
{
    struct stat st;
    if (strlen(v) >= EMM_CONFIG_PATH_MAX) {
        snprintf(why, cap, "path too long");
        return false;
    }
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
    strcpy(out, v);
    return true;
}

static bool parse_machine(emm_config *c, const char *v, long pid, char *why, size_t cap)
{
    (void)pid;
    return input_path(v, c->machine, why, cap);
}

static bool parse_table(emm_config *c, const char *v, long pid, char *why, size_t cap)
{
    (void)pid;
    return input_path(v, c->table, why, cap);
}

/* An output path: %p becomes the pid, %% a percent sign; its directory must
 * exist and be writable now, so a report is not lost at exit. */
static bool output_path(const char *v, long pid, char out[EMM_CONFIG_PATH_MAX], char *why,
                        size_t cap)
{
    char path[EMM_CONFIG_PATH_MAX];
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
        if (o + len >= sizeof path) {
            snprintf(why, cap, "path too long");
            return false;
        }
        memcpy(path + o, piece, len);
        o += len;
    }
    path[o] = '\0';
    if (path[o - 1] == '/') {
        snprintf(why, cap, "expected a file path, not a directory");
        return false;
    }
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
        snprintf(why, cap, "is a directory, expected a file path");
        return false;
    }
    char dir[EMM_CONFIG_PATH_MAX];
    const char *slash = strrchr(path, '/');
    if (!slash) {
        strcpy(dir, ".");
    } else if (slash == path) {
        strcpy(dir, "/");
    } else {
        memcpy(dir, path, (size_t)(slash - path));
        dir[slash - path] = '\0';
    }
    if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
        snprintf(why, cap, "directory %s does not exist", dir);
        return false;
    }
    if (access(dir, W_OK | X_OK) != 0) {
        snprintf(why, cap, "directory %s is not writable", dir);
        return false;
    }
    strcpy(out, path);
    return true;
}

static bool parse_report(emm_config *c, const char *v, long pid, char *why, size_t cap)
{
    return output_path(v, pid, c->report, why, cap);
}

static bool parse_dump(emm_config *c, const char *v, long pid, char *why, size_t cap)
{
    return output_path(v, pid, c->profile_dump, why, cap);
}

static bool parse_trace(emm_config *c, const char *v, long pid, char *why, size_t cap)
{
    return output_path(v, pid, c->trace, why, cap);
}

static bool parse_timeline(emm_config *c, const char *v, long pid, char *why, size_t cap)
{
    return output_path(v, pid, c->timeline, why, cap);
}

static bool parse_log(emm_config *c, const char *v, long pid, char *why, size_t cap)
{
    (void)pid; (void)why; (void)cap;
    for (int i = 0; i < 3; i++) {
        char digit[2] = {(char)('0' + i), '\0'};
        if (strcmp(v, digit) == 0 || strcmp(v, log_words[i]) == 0) {
            c->log = i;
            return true;
        }
    }
    return false;
}

struct row {
    emm_config_row pub;
    row_parser parse;
};

/* EMM_CAPTURE's accepted words and help, from the list of backends. */
#define CAPTURE_ACCEPTS(N, n, caps, work, help) ", " #n
#define CAPTURE_HELP(N, n, caps, work, help) "  " #n ": " help "\n"

/* The table, in emm_config_key order. */
static const struct row rows[EMM_CONFIG_COUNT] = {
    [EMM_CONFIG_STRICT] = {{"EMM_STRICT", NULL, NULL, "0 or 1", "0",
        "1: a bad EMM_* value or a session that cannot start stops the program (exit 125)\n"
        "instead of letting it run without emm",
        {{"--strict", "1", "a bad value stops the program instead of the shim stepping aside"}}},
        parse_strict},
    [EMM_CONFIG_TAG] = {{"EMM_TAG", "--tag", "RULES",
        "rules KIND:key=value,...;... (see below), or openmesh (the preset for OpenMesh's arrays)",
        "(none)", "tag arrays by rule, e.g. vertices:site=read_mesh,stride=80,xyz=8:f64", {{0}}},
        parse_tag},
    [EMM_CONFIG_CAPTURE] = {{"EMM_CAPTURE", "--capture", "C",
        "auto" EMM_CAPTURE_LIST(CAPTURE_ACCEPTS), "auto",
        "how accesses are seen:\n" EMM_CAPTURE_LIST(CAPTURE_HELP)
        "auto: the first of these that suits the program (emm run picks valgrind for a binary\n"
        "without coverage hooks or emm calls when Valgrind and the tool are there)", {{0}}},
        parse_capture},
    [EMM_CONFIG_PROFILE] = {{"EMM_PROFILE", "--profile", "N",
        "a count of accesses (16384, 16K) or of iterations (5it), at least 1", "16384",
        "the profiling window: element reads from the program's first read of the mesh (writes "
        "neither open nor fill it; for a mesh larger than the local store it reads on, to 1.5 N "
        "at most, until its records fill the store), or emm_iteration() calls with 'it'", {{0}}},
        parse_window},
    [EMM_CONFIG_STRATEGY] = {{"EMM_STRATEGY", "--strategy", "S",
        "a strategy: direct, cache[@LAYOUT] or LAYOUT+FETCH[@CELL]", "(decide)",
        "skip the decision and simulate this strategy, e.g. tiles+convolution@64", {{0}}},
        parse_strategy},
    [EMM_CONFIG_COMPARE] = {{"EMM_COMPARE", "--compare", "C", "baselines, all or none", "baselines",
        "also simulate direct reads and the cache (baselines), the whole sweep (all) or nothing",
        {{0}}}, parse_compare},
    [EMM_CONFIG_FINALISTS] = {{"EMM_FINALISTS", "--finalists", "N",
        "a count from 0 to 64, or all", EMM_CONFIG_DEFAULT_FINALISTS_TEXT,
        "when the whole run is captured, every candidate runs from the window on and the\n"
        "slower half is dropped at 2, 4, 8, ... windows until N remain, then a finalist more\n"
        "than 25% behind the leader, so far and since the last check, is stopped; the fastest\n"
        "of those that ran to the end (the finalists, the prediction and direct reads) is the\n"
        "answer (all: none is dropped, every candidate is simulated over the whole run; 0: the\n"
        "window's prediction stands, as in the thesis)",
        {{0}}}, parse_finalists},
    [EMM_CONFIG_PHASES] = {{"EMM_PHASES", NULL, NULL, "0 or 1", "1",
        "1: when the whole run is captured, probe it after the window for the program's\n"
        "phases (a window's profile every 8 windows, beside the run) and say whether switching\n"
        "strategy between them pays; 0: the window's pattern stands for the whole run, as in\n"
        "the thesis (on a program made of mesh accesses, a fifth of the capture's time)",
        {{"--no-phases", "0", "do not probe the run for phases after the window"}}},
        parse_phases},
    [EMM_CONFIG_MACHINE] = {{"EMM_MACHINE", "--machine", "FILE", "a readable machine file",
        "(built-in)", "the machine model's parameters (see emm machine --help)", {{0}}},
        parse_machine},
    [EMM_CONFIG_TABLE] = {{"EMM_TABLE", "--table", "FILE", "a readable strategy table file",
        "(shipped table only)", "a user table of sample profiles, consulted with the shipped one",
        {{0}}}, parse_table},
    [EMM_CONFIG_REPORT] = {{"EMM_REPORT", "--report", "FILE",
        "a file path in a writable directory (%p: pid)", "(none)",
        "write the JSON report there at exit (docs/report.md), also when nothing was\n"
        "simulated: then with the reason; when another process of the run wrote it\n"
        "first, to FILE.PID beside it", {{0}}}, parse_report},
    [EMM_CONFIG_PROFILE_DUMP] = {{"EMM_PROFILE_DUMP", "--dump", "FILE",
        "a file path in a writable directory (%p: pid)", "(none)",
        "write the window's distance profile as CSV (i,D_i)", {{0}}}, parse_dump},
    [EMM_CONFIG_TRACE] = {{"EMM_TRACE", "--trace", "FILE",
        "a file path in a writable directory (%p: pid)", "(none)",
        "write the access trace, for emm replay", {{0}}}, parse_trace},
    [EMM_CONFIG_TIMELINE] = {{"EMM_TIMELINE", "--timeline", "FILE",
        "a file path in a writable directory (%p: pid)", "(none)",
        "write the answer's simulated run as a Chrome/Perfetto trace-event JSON: a track\n"
        "per DMA channel, the core's stalls, cell entries, the window and phases; at most\n"
        EMM_TIMELINE_MAX_EVENTS_TEXT " events (the file says when the cap was hit); the answer\n"
        "is known at the end, so its run is simulated again then over the run's trace\n"
        "(EMM_TRACE's, or one of its own in TMPDIR, removed after)",
        {{0}}}, parse_timeline},
    [EMM_CONFIG_LOG] = {{"EMM_LOG", "--log", "LEVEL", "0, 1, 2, quiet, summary or verbose", "1",
        "0: nothing on stderr; 1: the summary at exit; 2: also what the shim does",
        {{"--quiet", "0", "no summary"}, {"-q", "0", "the same as --quiet"},
         {"--verbose", "2", "more detail"}, {"-v", "2", "the same as --verbose"}}},
        parse_log},
    [EMM_CONFIG_LIST_SITES] = {{"EMM_LIST_SITES", NULL, NULL, "0 or 1", "0",
        "1: run the program once and list, at exit, its candidate arrays (blocks of 64 KiB\n"
        "or more, by call site, with the whole stack and what their records look like),\n"
        "each with a suggested EMM_TAG rule; nothing is tagged or simulated",
        {{"--list-sites", "1", "list the program's candidate arrays and a rule for each"}}},
        parse_list_sites},
};

const emm_config_row *emm_config_row_get(emm_config_key k)
{
    return (unsigned)k < EMM_CONFIG_COUNT ? &rows[k].pub : NULL;
}

void emm_config_init(emm_config *c)
{
    memset(c, 0, sizeof *c);
    c->capture = EMM_CAPTURE_AUTO;
    c->window_accesses = EMM_CONFIG_DEFAULT_WINDOW;
    c->compare = EMM_COMPARE_BASELINES;
    c->finalists = EMM_CONFIG_DEFAULT_FINALISTS;
    c->phases = 1;
    c->log = 1;
}

void emm_config_free(emm_config *c)
{
    emm_tag_rules_free(&c->tags);
    emm_config_init(c);
}

emm_status emm_config_copy(emm_config *dst, const emm_config *src)
{
    *dst = *src;
    if (src->tags.n == 0)
        return EMM_OK;
    dst->tags.rule = malloc(src->tags.n * sizeof *dst->tags.rule);
    if (!dst->tags.rule) {
        emm_config_init(dst);
        return EMM_ERR_NOMEM;
    }
    memcpy(dst->tags.rule, src->tags.rule, src->tags.n * sizeof *dst->tags.rule);
    return EMM_OK;
}

emm_status emm_config_set(emm_config *c, emm_config_key k, const char *value, const char *source,
                          long pid, emm_error *err)
{
    char why[400] = "", q[EMM_CLIP + 1];
    if ((unsigned)k >= EMM_CONFIG_COUNT)
        return emm_fail(err, EMM_ERR_INVALID, "%s: not a setting", source ? source : "?");
    const struct row *r = &rows[k];
    if (!source)
        source = r->pub.var;
    /* Parsed into a copy: a bad value leaves c as it was. The copy is large
     * (five paths), so it lives on the heap when it can. */
    emm_config *t = malloc(sizeof *t);
    emm_config local;
    bool heap = t != NULL;
    if (!heap)
        t = &local;
    *t = *c;
    bool ok = *value != '\0' && r->parse(t, value, pid, why, sizeof why);
    /* A row that made new rules: the old ones go with the value taken, the
     * new ones with the value refused. */
    if (t->tags.rule != c->tags.rule)
        free(ok ? c->tags.rule : t->tags.rule);
    if (ok) {
        t->source[k] = source;
        *c = *t;
    }
    if (heap)
        free(t);
    if (ok)
        return EMM_OK;
    emm_clip(value, strlen(value), q);
    emm_printable(why); /* it may quote a path made from the value */
    if (why[0])
        return emm_fail(err, EMM_ERR_INVALID, "%s='%s': %s", source, q, why);
    return emm_fail(err, EMM_ERR_INVALID, "%s='%s': expected %s", source, q, r->pub.accepts);
}

emm_status emm_config_from_env(emm_config *c, const char *(*get)(const char *name), long pid,
                               unsigned skip, emm_error *err)
{
    for (int k = 0; k < EMM_CONFIG_COUNT; k++) {
        if (skip & (1u << k))
            continue;
        const char *v = get(rows[k].pub.var);
        if (!v)
            continue;
        emm_status st = emm_config_set(c, (emm_config_key)k, v, rows[k].pub.var, pid, err);
        if (st != EMM_OK)
            return st;
    }
    return EMM_OK;
}

emm_config_key emm_config_find_option(const char *arg, const char **fixed)
{
    for (int k = 0; k < EMM_CONFIG_COUNT; k++) {
        const emm_config_row *r = &rows[k].pub;
        if (r->option && strcmp(arg, r->option) == 0) {
            *fixed = NULL;
            return (emm_config_key)k;
        }
        for (int i = 0; i < EMM_CONFIG_SWITCHES && r->switches[i].option; i++)
            if (strcmp(arg, r->switches[i].option) == 0) {
                *fixed = r->switches[i].value;
                return (emm_config_key)k;
            }
    }
    *fixed = NULL;
    return EMM_CONFIG_COUNT;
}

/* The help's lines under a row, indented. */
static void help_lines(FILE *out, const char *h, int indent)
{
    while (*h) {
        const char *nl = strchr(h, '\n');
        size_t len = nl ? (size_t)(nl - h) : strlen(h);
        fprintf(out, "%*s%.*s\n", indent, "", (int)len, h);
        h += len + (nl ? 1 : 0);
    }
}

void emm_config_help(FILE *out, int options)
{
    if (options) {
        for (int k = 0; k < EMM_CONFIG_COUNT; k++) {
            const emm_config_row *r = &rows[k].pub;
            char head[64];
            if (r->option) {
                snprintf(head, sizeof head, "%s %s", r->option, r->metavar);
                fprintf(out, "  %-18s %s (%s; default %s)\n", head, r->accepts, r->var, r->def);
                help_lines(out, r->help, 21);
            }
            for (int i = 0; i < EMM_CONFIG_SWITCHES && r->switches[i].option; i++)
                fprintf(out, "  %-18s %s (%s=%s)\n", r->switches[i].option, r->switches[i].help,
                        r->var, r->switches[i].value);
        }
        fprintf(out, "\n");
        emm_tag_rules_help(out);
        return;
    }
    fprintf(out, "Environment (read by libemmshim.so; emm run's options set them):\n");
    for (int k = 0; k < EMM_CONFIG_COUNT; k++) {
        const emm_config_row *r = &rows[k].pub;
        fprintf(out, "  %-17s %s (default: %s)\n", r->var, r->accepts, r->def);
        help_lines(out, r->help, 21);
    }
    fprintf(out, "\n");
    emm_tag_rules_help(out);
    fprintf(out, "A bad value gets one line on stderr and the program runs without emm.\n");
}

/* path with every % doubled. */
static bool format_output(const char *path, char *out, size_t cap)
{
    size_t o = 0;
    for (const char *p = path; *p; p++) {
        if (o + (*p == '%' ? 2 : 1) >= cap)
            return false;
        if (*p == '%')
            out[o++] = '%';
        out[o++] = *p;
    }
    out[o] = '\0';
    return cap > 0;
}

int emm_config_format(const emm_config *c, emm_config_key k, char *out, size_t cap)
{
    int n = -1;
    switch (k) {
    case EMM_CONFIG_STRICT: n = snprintf(out, cap, "%d", c->strict ? 1 : 0); break;
    case EMM_CONFIG_TAG: {
        size_t o = 0;
        if (cap)
            out[0] = '\0';
        for (size_t i = 0; i < c->tags.n; i++) {
            char r[512];
            emm_tag_rule_format(&c->tags.rule[i], r, sizeof r);
            int w = snprintf(out + o, cap - o, "%s%s", i ? ";" : "", r);
            if (w < 0 || (size_t)w >= cap - o)
                return false;
            o += (size_t)w;
        }
        return c->tags.n > 0;
    }
    case EMM_CONFIG_CAPTURE: n = snprintf(out, cap, "%s", emm_capture_name(c->capture)); break;
    case EMM_CONFIG_PROFILE:
        n = c->window_accesses
                ? snprintf(out, cap, "%llu", (unsigned long long)c->window_accesses)
                : snprintf(out, cap, "%lluit", (unsigned long long)c->window_iterations);
        break;
    case EMM_CONFIG_STRATEGY:
        if (!c->has_strategy || cap < 96)
            return false;
        emm_strategy_format(&c->strategy, out, cap);
        return true;
    case EMM_CONFIG_COMPARE: n = snprintf(out, cap, "%s", emm_compare_name(c->compare)); break;
    case EMM_CONFIG_FINALISTS:
        n = c->finalists == EMM_CONFIG_FINALISTS_ALL ? snprintf(out, cap, "all")
                                                     : snprintf(out, cap, "%u", c->finalists);
        break;
    case EMM_CONFIG_PHASES: n = snprintf(out, cap, "%d", c->phases ? 1 : 0); break;
    case EMM_CONFIG_MACHINE: n = snprintf(out, cap, "%s", c->machine); break;
    case EMM_CONFIG_TABLE: n = snprintf(out, cap, "%s", c->table); break;
    case EMM_CONFIG_REPORT: return format_output(c->report, out, cap);
    case EMM_CONFIG_PROFILE_DUMP: return format_output(c->profile_dump, out, cap);
    case EMM_CONFIG_TRACE: return format_output(c->trace, out, cap);
    case EMM_CONFIG_TIMELINE: return format_output(c->timeline, out, cap);
    case EMM_CONFIG_LOG: n = snprintf(out, cap, "%d", c->log); break;
    case EMM_CONFIG_LIST_SITES: n = snprintf(out, cap, "%d", c->list_sites ? 1 : 0); break;
    default: return false;
    }
    return n >= 0 && (size_t)n < cap;
}

void emm_config_dump(const emm_config *c, FILE *out)
{
    char s[96] = "";
    fprintf(out, "emm:   EMM_STRICT=%d\n", c->strict ? 1 : 0);
    fprintf(out, "emm:   EMM_TAG=%zu rule%s\n", c->tags.n, c->tags.n == 1 ? "" : "s");
    for (size_t i = 0; i < c->tags.n; i++) {
        const emm_tag_rule *r = &c->tags.rule[i];
        fprintf(out, "emm:     rule %zu: %s site=%s min=%llu nth=%llu stride=%u offset=%u%s\n",
                i + 1,
                r->shape == EMM_TAG_HALFEDGES ? "halfedges"
                : r->shape == EMM_TAG_FACES   ? "faces"
                : r->shape == EMM_TAG_VCONN   ? "vconn"
                : r->kind == EMM_ARRAY_VERTICES ? "vertices"
                                                : "triangles",
                r->site[0] ? r->site : "(any)", (unsigned long long)r->min,
                (unsigned long long)r->nth, r->stride, r->offset,
                r->shape != EMM_TAG_AXIS ? "" : r->axis == 0 ? " (the x block)"
                                              : r->axis == 1 ? " (the y block)"
                                                             : " (the z block)");
    }
    fprintf(out, "emm:   EMM_CAPTURE=%s\n", emm_capture_name(c->capture));
    if (c->window_accesses)
        fprintf(out, "emm:   EMM_PROFILE=%llu\n", (unsigned long long)c->window_accesses);
    else
        fprintf(out, "emm:   EMM_PROFILE=%lluit\n", (unsigned long long)c->window_iterations);
    if (c->has_strategy)
        emm_strategy_format(&c->strategy, s, sizeof s);
    fprintf(out, "emm:   EMM_STRATEGY=%s\n", s);
    fprintf(out, "emm:   EMM_COMPARE=%s\n", emm_compare_name(c->compare));
    if (c->finalists == EMM_CONFIG_FINALISTS_ALL)
        fprintf(out, "emm:   EMM_FINALISTS=all\n");
    else
        fprintf(out, "emm:   EMM_FINALISTS=%u\n", c->finalists);
    fprintf(out, "emm:   EMM_PHASES=%d\n", c->phases);
    fprintf(out, "emm:   EMM_MACHINE=%s\n", c->machine);
    fprintf(out, "emm:   EMM_TABLE=%s\n", c->table);
    fprintf(out, "emm:   EMM_REPORT=%s\n", c->report);
    fprintf(out, "emm:   EMM_PROFILE_DUMP=%s\n", c->profile_dump);
    fprintf(out, "emm:   EMM_TRACE=%s\n", c->trace);
    fprintf(out, "emm:   EMM_TIMELINE=%s\n", c->timeline);
    fprintf(out, "emm:   EMM_LOG=%d\n", c->log);
    fprintf(out, "emm:   EMM_LIST_SITES=%d\n", c->list_sites);
}
