/* The strategy table file (runtime/table.c), then a nearest-sample query. */
#include "fuzz.h"
#include "emm/table.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    emm_table *t = emm_table_new();
    if (!t)
        abort();
    emm_error err;
    emm_status st = emm_table_load(t, fuzz_file(data, size), &err);
    fuzz_check_error(st, &err);
    emm_table_free(t);
    return 0;
}
