/* Small helpers shared by the emm subcommands. */
#include "cli.h"

#include <assert.h>
#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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

/* The text the configuration table last read through env_get: a table to
 * add to may name a file not made yet, which its row (a file to read)
 * refuses. */
static const char *env_text;

static const char *env_get(const char *name)
{
    const char *v = getenv(name);
    /* Empty is unset, as these commands have always taken it. */
    env_text = v && *v ? v : NULL;
    return env_text;
}

int cli_env_file(emm_config_key k, bool may_be_new, char path[EMM_CONFIG_PATH_MAX])
{
    assert(k == EMM_CONFIG_MACHINE || k == EMM_CONFIG_TABLE);
    emm_config c;
    emm_error err;
    path[0] = '\0';
    emm_config_init(&c);
    env_text = NULL;
    if (emm_config_from_env(&c, env_get, (long)getpid(), ~(1u << k), &err) == EMM_OK)
        strcpy(path, k == EMM_CONFIG_MACHINE ? c.machine : c.table);
    else if (may_be_new && access(env_text, F_OK) != 0 && errno == ENOENT &&
             strlen(env_text) < EMM_CONFIG_PATH_MAX)
        strcpy(path, env_text);
    else
        return cli_fail(&err);
    return 0;
}
