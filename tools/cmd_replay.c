/* PLACEHOLDER: replaced by the real 'emm replay' implementation. */
#include "cli.h"

int emm_cmd_replay(int argc, char **argv)
{
    (void)argc; (void)argv;
    cli_error("'replay' is not built yet");
    return EMM_EXIT_FAIL;
}
