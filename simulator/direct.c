/* Direct remote access (thesis §3.2, docs/machine.md): every
 * access moves the words it spans one at a time; a read costs
 * direct.cycles_per_word per word, a write direct.write_cycles per word
 * (writes to main memory are buffered, thesis §3.2).
 *
 * direct.granularity says what one read of a mesh element moves: `field`,
 * the words the program loads; `record`, the whole record on the element's
 * first load (an STL-style `Vertex getVertex(id)` returns a copy, thesis
 * §6), after which further loads of the same record are local accesses
 * (local.cycles), until the program loads another element. Writes move
 * their own words either way, and plain-memory (raw) arrays always move
 * what is loaded. */
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "model.h"

typedef struct direct_model {
    struct emm_model base;
    emm_addr_map map;
    uint32_t word_shift;
    uint64_t read_cycles, write_cycles, local_cycles;
    uint64_t compute_per_access, compute_per_work;
    bool record;              /* direct.granularity = record */
    uint64_t *record_words;   /* per array: words of a whole record; 0: move fields */
    bool any;                 /* the previous read's element (record mode) */
    uint32_t last_array;
    uint64_t last_element;
    uint64_t accesses, words_read, words_written, work, local;
} direct_model;

/* Record mode: the element's first read copies its record; later reads of
 * it are local. */
static void direct_run_records(direct_model *m, const emm_trace_record *recs, size_t n)
{
    const uint32_t ws = m->word_shift;
    for (size_t i = 0; i < n; i++) {
        const emm_trace_record *r = &recs[i];
        uint64_t rec = m->record_words[r->array];
        m->work += r->work;
        if (r->write || rec == 0) {
            uint64_t a = emm_addr_of(&m->map, r);
            uint64_t words = (emm_last_byte(a, r->bytes) >> ws) - (a >> ws) + 1;
            if (r->write)
                m->words_written += words;
            else
                m->words_read += words;
            continue;
        }
        if (m->any && r->array == m->last_array && r->element == m->last_element) {
            m->local++;
            continue;
        }
        m->any = true;
        m->last_array = r->array;
        m->last_element = r->element;
        m->words_read += rec;
    }
    m->accesses += n;
}

static void direct_run(emm_model *model, const emm_trace_record *recs, size_t n)
{
    direct_model *m = (direct_model *)model;
    if (m->record) {
        direct_run_records(m, recs, n);
        return;
    }
    const emm_addr_map *map = &m->map;
    const uint32_t ws = m->word_shift;
    uint64_t rd = 0, wr = 0, work = 0;
    for (size_t i = 0; i < n; i++) {
        const emm_trace_record *r = &recs[i];
        uint64_t a = emm_addr_of(map, r);
        uint64_t words = (emm_last_byte(a, r->bytes) >> ws) - (a >> ws) + 1;
        if (r->write)
            wr += words;
        else
            rd += words;
        work += r->work;
    }
    m->accesses += n;
    m->words_read += rd;
    m->words_written += wr;
    m->work += work;
}

static void direct_reset(emm_model *model)
{
    direct_model *m = (direct_model *)model;
    m->accesses = m->words_read = m->words_written = m->work = m->local = 0;
    m->any = false;
}

static void direct_result(const emm_model *model, emm_result *out)
{
    const direct_model *m = (const direct_model *)model;
    memset(out->cycles, 0, sizeof out->cycles);
    out->accesses = m->accesses;
    out->cycles[EMM_BUCKET_COMPUTE] = m->accesses * m->compute_per_access + m->work * m->compute_per_work;
    out->cycles[EMM_BUCKET_REMOTE_ACCESS] = m->words_read * m->read_cycles + m->words_written * m->write_cycles;
    out->cycles[EMM_BUCKET_LOCAL_ACCESS] = m->local * m->local_cycles;
    out->total = 0;
    for (int i = 0; i < EMM_BUCKET_COUNT; i++)
        out->total += out->cycles[i];
    out->has_direct = 1;
    out->direct.words_read = m->words_read;
    out->direct.words_written = m->words_written;
}

static void direct_destroy(emm_model *model)
{
    direct_model *m = (direct_model *)model;
    emm_addr_map_free(&m->map);
    free(m->record_words);
    free(m);
}

static const struct emm_model_ops direct_ops = {direct_run, direct_reset, direct_result,
                                                direct_destroy, NULL, NULL, NULL};

emm_status emm_direct_model_new(const emm_machine_params *p, const emm_trace_info *trace,
                                emm_model **out, emm_error *err)
{
    direct_model *m = calloc(1, sizeof *m);
    emm_status st;
    if (!m)
        return emm_fail(err, EMM_ERR_NOMEM, "direct model: out of memory");
    m->base.ops = &direct_ops;
    if ((st = emm_addr_map_init(&m->map, trace, err)) != EMM_OK) {
        free(m);
        return st;
    }
    while ((1ull << m->word_shift) < p->word_bytes)
        m->word_shift++;
    m->read_cycles = p->direct_cycles_per_word;
    m->write_cycles = p->direct_write_cycles;
    m->local_cycles = p->local_cycles;
    m->record = p->direct_granularity == EMM_DIRECT_RECORD;
    uint32_t na = trace ? trace->narrays : 0;
    m->record_words = calloc(na ? na : 1, sizeof *m->record_words);
    if (!m->record_words) {
        direct_destroy(&m->base);
        return emm_fail(err, EMM_ERR_NOMEM, "direct model: out of memory");
    }
    for (uint32_t a = 0; a < na; a++)
        if (trace->arrays[a].kind != EMM_ARRAY_RAW)
            m->record_words[a] = (trace->arrays[a].record_size + p->word_bytes - 1) / p->word_bytes;
    m->compute_per_access = p->compute_per_access;
    m->compute_per_work = p->compute_per_work;
    *out = &m->base;
    return EMM_OK;
}
