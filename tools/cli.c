/* Small helpers shared by the emm subcommands. */
#include "cli.h"

#include <stdarg.h>
#include <string.h>

#include "parse.h"

void cli_error(const char *fmt, ...)
{
    va_list ap;
    fputs("emm: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

int cli_fail(const emm_error *err)
{
    cli_error("%s", err->message[0] ? err->message : emm_strerror(err->status));
    return EMM_EXIT_FAIL;
}

int cli_usage_error(const char *cmd, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "emm %s: ", cmd);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\nTry 'emm %s --help'.\n", cmd);
    return EMM_EXIT_USAGE;
}

int cli_bad_value(const char *cmd, const emm_error *err)
{
    fprintf(stderr, "emm %s: %s\n", cmd, err->message);
    return EMM_EXIT_USAGE;
}

bool cli_is_help(const char *arg)
{
    return strcmp(arg, "-h") == 0 || strcmp(arg, "--help") == 0;
}

bool cli_u64(const char *cmd, const char *opt, const char *value, uint64_t *out)
{
    if (emm_parse_u64(value, out))
        return true;
    cli_usage_error(cmd, "%s expects a non-negative integer, not '%s'", opt, value);
    return false;
}

bool cli_size(const char *cmd, const char *opt, const char *value, uint64_t *out)
{
    if (emm_parse_size(value, out))
        return true;
    cli_usage_error(cmd, "%s expects a size in bytes (K, M, G suffixes allowed), not '%s'",
                    opt, value);
    return false;
}

const char *cli_value(const char *cmd, int argc, char **argv, int *i)
{
    if (*i + 1 >= argc) {
        cli_usage_error(cmd, "%s needs a value", argv[*i]);
        return NULL;
    }
    return argv[++*i];
}
