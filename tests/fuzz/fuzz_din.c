/* Dinero IV din text (simulator/din.c) into a trace writer whose output is
 * dropped. The first byte picks --bytes (0: the default). */
#include "fuzz.h"
#include "emm/trace.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0)
        return 0;
    static char out[64];
    if (!out[0])
        snprintf(out, sizeof out, "/tmp/emm-fuzz-din-%ld.emmt", (long)getpid());
    uint32_t bytes = data[0] < 200 ? data[0] % 9 : (uint32_t)data[0] * 20;
    FILE *in = fmemopen((void *)(data + 1), size - 1 ? size - 1 : 1, "r");
    if (!in)
        abort();
    if (size == 1)
        fgetc(in); /* fmemopen wants a non-empty buffer: consume it */
    const emm_trace_array raw = { EMM_ARRAY_RAW, 1, 0, 0 };
    emm_trace_writer *w = NULL;
    emm_error err;
    if (emm_trace_writer_open(out, &raw, 1, NULL, 0, &w, &err) != EMM_OK) {
        fprintf(stderr, "fuzz: %s\n", err.message);
        abort();
    }
    emm_din_counts counts;
    emm_status st = emm_din_import(in, "fuzz.din", bytes, w, &counts, &err);
    fuzz_check_error(st, &err);
    emm_trace_writer_abort(w);
    fclose(in);
    return 0;
}
