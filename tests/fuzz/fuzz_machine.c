/* The machine file (simulator/machine.c: INI keys), then validation. */
#include "fuzz.h"
#include "emm/sim.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    emm_machine *m = NULL;
    emm_error err;
    if (emm_machine_new(&m, &err) != EMM_OK)
        abort();
    emm_status st = emm_machine_load(m, fuzz_file(data, size), &err);
    fuzz_check_error(st, &err);
    if (st == EMM_OK)
        fuzz_check_error(emm_machine_validate(m, &err), &err);
    emm_machine_free(m);
    return 0;
}
