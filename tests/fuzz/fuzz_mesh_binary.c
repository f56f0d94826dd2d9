/* PLY (ascii and binary), STL (ascii and binary) and binary OFF
 * (runtime/mesh_ply.c, mesh_stl.c, mesh_text.c), then the mesh checks and
 * build. The first byte picks the format; for binary OFF the harness adds
 * the "OFF BINARY" line itself so the fuzzer starts in the data. */
#include "fuzz.h"
#include "mesh_internal.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0)
        return 0;
    static const char prefix[] = "OFF BINARY\n";
    int kind = data[0] % 3;
    const char *name = kind == 0 ? "fuzz.ply" : kind == 1 ? "fuzz.stl" : "fuzz.off";
    size_t pre = kind == 2 ? sizeof prefix - 1 : 0;
    char *buf = malloc(size - 1 + pre + 1);
    if (!buf)
        abort();
    memcpy(buf, prefix, pre);
    memcpy(buf + pre, data + 1, size - 1);
    emm_mesh *m = NULL;
    emm_error err;
    emm_status st = emm_mesh_parse(name, buf, size - 1 + pre, &m, &err);
    fuzz_check_error(st, &err);
    emm_mesh_free(m);
    free(buf);
    return 0;
}
