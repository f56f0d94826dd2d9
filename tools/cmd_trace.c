/* PLACEHOLDER: replaced by the real 'emm trace' implementation. */
#include "cli.h"

int emm_cmd_trace(int argc, char **argv)
{
    (void)argc; (void)argv;
    cli_error("'trace' is not built yet");
    return EMM_EXIT_FAIL;
}
