/* PLACEHOLDER: replaced by the real 'emm machine' implementation. */
#include "cli.h"

int emm_cmd_machine(int argc, char **argv)
{
    (void)argc; (void)argv;
    cli_error("'machine' is not built yet");
    return EMM_EXIT_FAIL;
}
