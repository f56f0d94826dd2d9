/* PLACEHOLDER: replaced by the real 'emm layout' implementation. */
#include "cli.h"

int emm_cmd_layout(int argc, char **argv)
{
    (void)argc; (void)argv;
    cli_error("'layout' is not built yet");
    return EMM_EXIT_FAIL;
}
