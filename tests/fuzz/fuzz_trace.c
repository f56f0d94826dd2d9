/* The trace reader (simulator/trace.c) and the models behind it. Built
 * twice: fuzz_trace takes the bytes as they are, so the fuzzer mostly
 * meets the checksums; fuzz_trace_fixed (FUZZ_FIX_CHECKSUMS) first writes
 * the magic and every checksum the bytes' own counts call for, so the
 * fuzzer reaches the block decoder and, with records that pass, the models.
 *
 * The records that read back run through direct, the cache and one EMM
 * strategy (tiles+convolution@16), at most FUZZ_RECORDS of them: the work
 * per record is what must stay bounded (trace.h bounds each record's
 * bytes), not the number of records a small file can declare. */
#include "fuzz.h"
#include "emm/sim.h"
#include "emm/strategy.h"
#include "emm/trace.h"
#include "trace_format.h"

#define FUZZ_RECORDS 100000

#ifdef FUZZ_FIX_CHECKSUMS
static void put_sum(uint8_t *d, size_t size, size_t at, size_t from, size_t n)
{
    if (at + 8 <= size && from + n <= size)
        emm_put_le64(d + at, emm_trace_hash(d + from, n, 0));
}

static void fix_checksums(uint8_t *d, size_t size)
{
    if (size < EMM_TRACE_HEADER_SIZE)
        return;
    memcpy(d, EMM_TRACE_MAGIC, 8);
    put_sum(d, size, EMM_TH_CHECKSUM, 0, EMM_TH_CHECKSUM);
    uint64_t narrays = emm_le32(d + EMM_TH_NARRAYS);
    uint64_t nv = emm_le64(d + EMM_TH_NV), nt = emm_le64(d + EMM_TH_NT);
    size_t pos = EMM_TRACE_HEADER_SIZE;
    if (narrays > size / EMM_TRACE_ARRAY_SIZE)
        return;
    size_t tlen = (size_t)narrays * EMM_TRACE_ARRAY_SIZE;
    put_sum(d, size, pos + tlen, pos, tlen);
    pos += tlen + 8;
    if (nv > size / 24 || nt > size / 12)
        return;
    size_t glen = (size_t)(nv * 24 + nt * 12);
    put_sum(d, size, pos + glen, pos, glen);
    pos += glen + 8;
    while (pos + EMM_TRACE_BLOCK_HEADER_SIZE <= size) {
        emm_put_le32(d + pos + EMM_TB_MAGIC, EMM_TRACE_BLOCK_MAGIC);
        size_t stored = emm_le32(d + pos + EMM_TB_STORED);
        size_t payload = pos + EMM_TRACE_BLOCK_HEADER_SIZE;
        if (stored > size - payload)
            stored = size - payload;
        put_sum(d, size, pos + EMM_TB_PAYLOAD_SUM, payload, stored);
        put_sum(d, size, pos + EMM_TB_HEADER_SUM, pos, EMM_TB_HEADER_SUM);
        pos = payload + stored;
    }
}
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static emm_machine *machine;
    static emm_strategy strategies[3];
    static emm_trace_record *buf;
    emm_error err;
    if (!machine) {
        const char *names[3] = { "direct", "cache", "tiles+convolution@16" };
        if (emm_machine_new(&machine, &err) != EMM_OK || !(buf = malloc(4096 * sizeof *buf)))
            abort();
        for (int i = 0; i < 3; i++)
            if (emm_strategy_parse(names[i], &strategies[i], &err) != EMM_OK)
                abort();
    }
#ifdef FUZZ_FIX_CHECKSUMS
    uint8_t *copy = malloc(size ? size : 1);
    if (!copy)
        abort();
    memcpy(copy, data, size);
    fix_checksums(copy, size);
    const char *path = fuzz_file(copy, size);
    free(copy);
#else
    const char *path = fuzz_file(data, size);
#endif
    emm_trace_reader *r = NULL;
    emm_status st = emm_trace_reader_open(path, &r, &err);
    fuzz_check_error(st, &err);
    if (st != EMM_OK)
        return 0;
    const emm_trace_info *info = emm_trace_reader_info(r);
    emm_model *models[3] = { NULL, NULL, NULL };
    for (int i = 0; i < 3; i++) {
        st = emm_model_new(machine, &strategies[i], info, &models[i], &err);
        fuzz_check_error(st, &err);
    }
    size_t n, total = 0;
    while (total < FUZZ_RECORDS && (st = emm_trace_read(r, buf, 4096, &n, &err)) == EMM_OK && n > 0) {
        for (int i = 0; i < 3; i++)
            if (models[i])
                emm_model_run(models[i], buf, n);
        total += n;
    }
    fuzz_check_error(st, &err);
    for (int i = 0; i < 3; i++) {
        if (!models[i])
            continue;
        emm_result res;
        emm_model_result(models[i], &res);
        emm_model_free(models[i]);
    }
    emm_trace_reader_close(r);
    return 0;
}
