/* ASCII OFF and OBJ (runtime/mesh_text.c) and the mesh checks and build
 * behind them (runtime/mesh.c): the first byte picks the format. */
#include "fuzz.h"
#include "mesh_internal.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0)
        return 0;
    const char *name = data[0] & 1 ? "fuzz.obj" : "fuzz.off";
    emm_mesh *m = NULL;
    emm_error err;
    emm_status st = emm_mesh_parse(name, (const char *)data + 1, size - 1, &m, &err);
    fuzz_check_error(st, &err);
    emm_mesh_free(m);
    return 0;
}
