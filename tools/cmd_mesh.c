/* PLACEHOLDER: replaced by the real 'emm mesh' implementation. */
#include "cli.h"

int emm_cmd_mesh(int argc, char **argv)
{
    (void)argc; (void)argv;
    cli_error("'mesh' is not built yet");
    return EMM_EXIT_FAIL;
}
