/* The option table of every emm subcommand (opts.h): one parser, one
 * checker per kind of value, one help printer. */
#include "opts.h"

#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "emm/strategy.h"
#include "parse.h"

/* The help column: labels up to LABEL_MAX wide share it, a longer one gets
 * its help on the next line; help lines are at most HELP_WIDTH columns. */
enum { LABEL_MAX = 20, HELP_WIDTH = 80 };

static bool is_end(const opts_row *r)
{
    return !r->name && !r->metavar;
}

/* "8", "64K": a size as a user would type it. */
static const char *size_text(uint64_t v, char buf[32])
{
    static const char suffix[] = "KMG";
    int k = 0;
    while (k < 3 && v >= 1024 && v % 1024 == 0) {
        v /= 1024;
        k++;
    }
    snprintf(buf, 32, k ? "%llu%c" : "%llu", (unsigned long long)v, suffix[k ? k - 1 : 0]);
    return buf;
}

static const char *bound_text(const opts_row *r, uint64_t v, char buf[32])
{
    if (r->kind == OPT_SIZE)
        return size_text(v, buf);
    snprintf(buf, 32, "%llu", (unsigned long long)v);
    return buf;
}

/* "a, b or c" into buf. */
static const char *words_text(const char *const *words, char *buf, size_t cap)
{
    size_t len = 0;
    buf[0] = '\0';
    for (size_t i = 0; words[i] && len < cap; i++) {
        const char *sep = i == 0 ? "" : words[i + 1] ? ", " : " or ";
        len += (size_t)snprintf(buf + len, cap - len, "%s%s", sep, words[i]);
    }
    return buf;
}

/* The usage error for a value of row r given as `as` (the option as typed,
 * or a positional's metavar). */
static bool bad(const opts *o, const char *as, const char *value, const char *what)
{
    cli_usage_error(o->cmd, "%s expects %s, not '%s'", as, what, value);
    return false;
}

static bool out_of_bounds(const opts *o, const opts_row *r, const char *as, const char *value)
{
    char lo[32], hi[32];
    if (!r->max)
        cli_usage_error(o->cmd, "%s must be at least %s, not '%s'", as, bound_text(r, r->min, lo),
                        value);
    else if (!r->min)
        cli_usage_error(o->cmd, "%s must be at most %s, not '%s'", as, bound_text(r, r->max, hi),
                        value);
    else
        cli_usage_error(o->cmd, "%s must be between %s and %s, not '%s'", as,
                        bound_text(r, r->min, lo), bound_text(r, r->max, hi), value);
    return false;
}

static bool append(opts_list *l, const char *v)
{
    const char **grown = realloc(l->v, (l->n + 1) * sizeof *grown);
    if (!grown) {
        cli_error("out of memory");
        return false;
    }
    l->v = grown;
    l->v[l->n++] = v;
    return true;
}

/* Checks `value` by r's kind and stores it; false after the message. */
static bool take(const opts *o, const opts_row *r, const char *as, const char *value)
{
    uint64_t n;
    double x;
    emm_error err;
    char text[512];
    switch (r->kind) {
    case OPT_FLAG:
        break;
    case OPT_U64:
    case OPT_SIZE:
        if (r->kind == OPT_U64 ? !emm_parse_u64(value, &n) : !emm_parse_size(value, &n))
            return bad(o, as, value,
                       r->kind == OPT_U64 ? "a non-negative integer"
                                          : "a size in bytes (K, M, G suffixes allowed)");
        if (n < r->min || (r->max && n > r->max))
            return out_of_bounds(o, r, as, value);
        *(uint64_t *)r->dst = n;
        return true;
    case OPT_POSITIVE:
        if (!emm_parse_double(value, &x) || !(x > 0))
            return bad(o, as, value, "a positive number");
        *(double *)r->dst = x;
        return true;
    case OPT_WORD:
        for (int i = 0; r->words[i]; i++)
            if (strcmp(value, r->words[i]) == 0) {
                *(int *)r->dst = i;
                return true;
            }
        return bad(o, as, value, words_text(r->words, text, sizeof text));
    case OPT_STRATEGY:
        /* Checked here, kept as text like OPT_TEXT. */
        if (emm_strategy_parse(value, &(emm_strategy){0}, &err) != EMM_OK) {
            cli_usage_error(o->cmd, "%s: %s", as, err.message);
            return false;
        }
        /* fall through */
    case OPT_TEXT:
        if (r->repeat)
            return append(r->dst, value);
        *(const char **)r->dst = value;
        return true;
    case OPT_CALL:
        return r->call(r->dst, as, value);
    case OPT_REST:
        break;
    }
    return true;
}

/* Whether `spelling` (may be NULL) is a[0..len). */
static bool spelled(const char *spelling, const char *a, size_t len)
{
    return spelling && strlen(spelling) == len && strncmp(spelling, a, len) == 0;
}

static opts_row *find(const opts *o, const char *a, size_t len)
{
    for (opts_row *r = o->rows; !is_end(r); r++)
        if (spelled(r->name, a, len) || spelled(r->alias, a, len))
            return r;
    return NULL;
}

bool opts_parse(opts *o, int argc, char **argv, int *rc)
{
    opts_row *pos = o->rows, *last = NULL; /* the next positional row, the last one taken */
    bool options = true;
    *rc = EMM_EXIT_USAGE;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (options && strcmp(a, "--") == 0) {
            options = false;
            continue;
        }
        if (options && a[0] == '-' && a[1] != '\0') {
            if (cli_is_help(a)) {
                o->usage(stdout, o);
                *rc = EMM_EXIT_OK;
                return true;
            }
            /* --name=value; a short option's value is the next argument. */
            const char *eq = a[1] == '-' ? strchr(a, '=') : NULL;
            size_t len = eq ? (size_t)(eq - a) : strlen(a);
            opts_row *r = find(o, a, len);
            if (!r) {
                cli_usage_error(o->cmd, "unknown option '%.*s'", (int)len, a);
                return true;
            }
            const char *as = spelled(r->alias, a, len) ? r->alias : r->name; /* as typed */
            if (!r->metavar) {
                if (eq) {
                    cli_usage_error(o->cmd, "%s takes no value", as);
                    return true;
                }
                if (r->kind == OPT_FLAG)
                    *(int *)r->dst = 1;
                else if (!take(o, r, as, NULL))
                    return true;
                r->seen++;
                continue;
            }
            const char *v = eq ? eq + 1 : i + 1 < argc ? argv[++i] : NULL;
            if (!v || !*v) {
                cli_usage_error(o->cmd, "%s needs a value", as);
                return true;
            }
            if (!take(o, r, as, v))
                return true;
            r->seen++;
            continue;
        }
        while (!is_end(pos) && pos->name)
            pos++;
        if (is_end(pos)) {
            if (last)
                cli_usage_error(o->cmd, "unexpected argument '%s': one %s only", a, last->metavar);
            else
                cli_usage_error(o->cmd, "unexpected argument '%s'", a);
            return true;
        }
        pos->seen++;
        if (pos->kind == OPT_REST) {
            *(int *)pos->dst = i;
            break;
        }
        if (!take(o, pos, pos->metavar, a))
            return true;
        last = pos;
        if (!pos->repeat)
            pos++;
    }
    /* What is missing: the positionals first, as the usage lines name them first. */
    for (int pass = 0; pass < 2; pass++)
        for (const opts_row *r = o->rows; !is_end(r); r++) {
            if (!r->required || r->seen || (r->name != NULL) != (pass == 1))
                continue;
            if (!r->name)
                cli_usage_error(o->cmd, "missing %s", r->metavar);
            else if (r->metavar)
                cli_usage_error(o->cmd, "missing %s %s", r->name, r->metavar);
            else /* a flag's name alone says little: what it is follows */
                cli_usage_error(o->cmd, "missing %s: %s", r->name, r->help ? r->help : "");
            return true;
        }
    *rc = EMM_EXIT_OK;
    return false;
}

int opts_run(opts *o, int argc, char **argv, int (*run)(void *args), void *args)
{
    int rc;
    if (!opts_parse(o, argc, argv, &rc))
        rc = run(args);
    for (opts_row *r = o->rows; !is_end(r); r++)
        if (r->repeat) {
            opts_list *l = r->dst;
            free(l->v);
            l->v = NULL;
            l->n = 0;
        }
    return rc;
}

int opts_subcommand(const char *cmd, const opts_sub *subs, void (*usage)(FILE *out), int argc,
                    char **argv)
{
    char list[256];
    size_t len = 0;
    if (argc >= 2 && cli_is_help(argv[1])) {
        usage(stdout);
        return EMM_EXIT_OK;
    }
    for (size_t i = 0; subs[i].name; i++) {
        if (argc >= 2 && strcmp(argv[1], subs[i].name) == 0)
            return subs[i].run(argc - 1, argv + 1);
        if (len < sizeof list) /* "a, b or c" */
            len += (size_t)snprintf(list + len, sizeof list - len, "%s%s",
                                    i == 0 ? "" : subs[i + 1].name ? ", " : " or ", subs[i].name);
    }
    if (argc < 2)
        return cli_usage_error(cmd, "missing subcommand: %s", list);
    return cli_usage_error(cmd, "unknown subcommand '%s': expected %s", argv[1], list);
}

/* ---- --help ---------------------------------------------------------------- */

/* "-o, --output FILE": the short spelling first, as is usual. */
static int label(const opts_row *r, char *buf, size_t cap)
{
    const char *first = r->name, *second = r->alias;
    if (second && second[1] != '-') {
        first = r->alias;
        second = r->name;
    }
    return snprintf(buf, cap, "%s%s%s%s%s", first, second ? ", " : "", second ? second : "",
                    r->metavar ? " " : "", r->metavar ? r->metavar : "");
}

/* The default a row's destination holds, as text; false when there is none
 * to show. */
static bool default_text(const opts_row *r, char buf[64])
{
    char tmp[32];
    switch (r->kind) {
    case OPT_U64:
        snprintf(buf, 64, "%llu", (unsigned long long)*(const uint64_t *)r->dst);
        return true;
    case OPT_SIZE:
        snprintf(buf, 64, "%s", size_text(*(const uint64_t *)r->dst, tmp));
        return true;
    case OPT_POSITIVE:
        snprintf(buf, 64, "%g", *(const double *)r->dst);
        return true;
    case OPT_WORD:
        snprintf(buf, 64, "%s", r->words[*(const int *)r->dst]);
        return true;
    case OPT_TEXT:
    case OPT_STRATEGY:
        if (r->repeat || !*(const char **)r->dst)
            return false;
        snprintf(buf, 64, "%s", *(const char **)r->dst);
        return true;
    case OPT_FLAG:
    case OPT_CALL:
    case OPT_REST:
        break;
    }
    return false;
}

/* How far a wrapped line's continuation is indented: as far as the line
 * itself, or for a list entry ("region    breadth-first growth ...") as far
 * as its text after the word. */
static size_t hang(const char *line, size_t len)
{
    size_t indent = strspn(line, " ");
    size_t word = indent + strcspn(line + indent, " \n");
    size_t gap = strspn(line + word, " ");
    return gap >= 2 && word + gap < len ? word + gap : indent;
}

/* Prints text from column `col`, the first line after `at` columns already
 * used: '\n' breaks a line, and a line longer than HELP_WIDTH is wrapped at
 * spaces. */
static void wrapped(FILE *out, const char *text, int col, int at)
{
    if (!*text)
        fputc('\n', out);
    while (*text) {
        size_t line = strcspn(text, "\n");
        size_t indent = hang(text, line);
        const char *p = text, *end = text + line;
        bool first = true;
        while (p < end) {
            size_t room = HELP_WIDTH - (size_t)col - (first ? 0 : indent);
            size_t n = (size_t)(end - p);
            if (n > room) {
                size_t cut = room;
                while (cut > 0 && p[cut] != ' ')
                    cut--;
                n = cut > 0 ? cut : strcspn(p, " ");
            }
            fprintf(out, "%*s%*s%.*s\n", col - at, "", first ? 0 : (int)indent, "", (int)n, p);
            at = 0;
            first = false;
            p += n;
            while (p < end && *p == ' ')
                p++;
        }
        if (line == 0)
            fputc('\n', out);
        text = *end ? end + 1 : end;
    }
}

void opts_help(FILE *out, const opts *o)
{
    int width = 10;
    char buf[128], def[64];
    for (const opts_row *r = o->rows; !is_end(r); r++) {
        int n = r->name ? label(r, buf, sizeof buf) : 0;
        if (n > width && n <= LABEL_MAX)
            width = n;
    }
    int col = 2 + width + 2;
    for (const opts_row *r = o->rows; !is_end(r); r++) {
        if (!r->name)
            continue;
        int n = label(r, buf, sizeof buf);
        char help[1024];
        snprintf(help, sizeof help, "%s", r->help ? r->help : "");
        if (r->show_default && default_text(r, def))
            snprintf(help + strlen(help), sizeof help - strlen(help), " (default %s)", def);
        fprintf(out, "  %s", buf);
        if (n > width) {
            fputc('\n', out);
            n = -2;
        }
        wrapped(out, help, col, 2 + n);
    }
    fprintf(out, "  %-*s  this text\n", width, "-h, --help");
}
