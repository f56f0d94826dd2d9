/* The machine's configuration: one descriptor table that the
 * INI reader, --set, validation, `emm machine show` and docs/machine.md all
 * follow. Defaults are docs/machine.md's table (thesis §3.2 and §6.1). */
#include "machine.h"

#include <assert.h>
#include <errno.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "infile.h"
#include "parse.h"

enum key_type { KEY_COUNT, KEY_SIZE, KEY_FETCH, KEY_GRANULARITY };

struct key_desc {
    emm_machine_key pub;
    enum key_type type;
    size_t offset;
    uint64_t fallback;
    uint64_t min, max;
};

/* A machine file is a few dozen keys; anything past 1 MiB is not one. */
#define EMM_MACHINE_FILE_MAX ((size_t)1 << 20)

#define P(field) offsetof(emm_machine_params, field)
#define K(x) ((uint64_t)(x) << 10)
#define M(x) ((uint64_t)(x) << 20)
#define G(x) ((uint64_t)(x) << 30)

/* Upper bounds keep every product in the models far from 64-bit overflow
 * (a trace of 2^40 accesses at a million cycles each still fits). */
static const struct key_desc keys[] = {
    {{"clock.mhz", "MHz", "core clock, only to print seconds (thesis 6.1)", "400"},
     KEY_COUNT, P(clock_mhz), 400, 1, 1000000},
    {{"word.bytes", "bytes", "the core's word; direct reads move one word at a time; a layout triangle's 3 vertex pointers are words", "4"},
     KEY_COUNT, P(word_bytes), 4, 1, 64},
    {{"local.bytes", "bytes", "local store size (thesis 6.1)", "256K"},
     KEY_SIZE, P(local_bytes), K(256), 1, G(64)},
    {{"local.cycles", "cycles", "one local store access; also the local access of a cache miss (thesis 3.2)", "1"},
     KEY_COUNT, P(local_cycles), 1, 0, 1000000},
    {{"remote.bytes", "bytes", "remote store size; a mesh larger than it is simulated, with a warning naming both (thesis 6.1)", "6M"},
     KEY_SIZE, P(remote_bytes), M(6), 1, G(1024)},
    {{"direct.cycles_per_word", "cycles", "one word read directly from remote memory", "32"},
     KEY_COUNT, P(direct_cycles_per_word), 32, 0, 1000000},
    {{"direct.write_cycles", "cycles", "one word written to remote memory (buffered, thesis 3.2)", "1"},
     KEY_COUNT, P(direct_write_cycles), 1, 0, 1000000},
    {{"direct.granularity", "unit", "field: a direct read moves the words the program loads; record: an element's first load copies its whole record, later loads of it are local (an STL-style getVertex(id), thesis 6)", "field"},
     KEY_GRANULARITY, P(direct_granularity), EMM_DIRECT_FIELD, 0, 1},
    {{"dma.program", "cycles", "the core's part of starting a DMA: the runtime's call and the controller's registers (thesis 3.2: dma.program + dma.latency = the 266 of initial programming; the split is fitted, docs/calibration.md)", "125"},
     KEY_COUNT, P(dma_program), 125, 0, 1000000},
    {{"dma.latency", "cycles", "the controller's part: cycles on the channel before the data moves, while the core goes on", "141"},
     KEY_COUNT, P(dma_latency), 141, 0, 1000000},
    {{"dma.cycles_per_8b", "cycles", "transfer time per 8 bytes (thesis 3.2)", "2"},
     KEY_COUNT, P(dma_cycles_per_8b), 2, 0, 1000000},
    {{"dma.chunk_bytes", "bytes", "the engine is reprogrammed after each chunk (thesis 3.2)", "1K"},
     KEY_SIZE, P(dma_chunk_bytes), K(1), 1, G(1)},
    {{"dma.chunk_cycles", "cycles", "reprogramming cost of each further chunk (thesis 3.2)", "208"},
     KEY_COUNT, P(dma_chunk_cycles), 208, 0, 1000000},
    {{"dma.channels", "channels", "transfers in flight at once (thesis 3.2)", "2"},
     KEY_COUNT, P(dma_channels), 2, 1, EMM_DMA_MAX_CHANNELS},
    {{"cache.present", "0|1", "0 (STHORM): the target has no cache; the cache below is simulated as a reference only, never chosen; 1: the target has it, and the cache strategies are candidates of the decision", "0"},
     KEY_COUNT, P(cache_present), 0, 0, 1},
    {{"cache.bytes", "bytes", "hardware cache size, of the target or of the reference (thesis 3.2)", "256K"},
     KEY_SIZE, P(cache_bytes), K(256), 4, G(1)},
    {{"cache.assoc", "ways", "cache associativity (thesis 3.2)", "4"},
     KEY_COUNT, P(cache_assoc), 4, 1, 256},
    {{"cache.line", "bytes", "cache line (Dinero block) size (thesis 3.2)", "64"},
     KEY_SIZE, P(cache_line), 64, 4, M(1)},
    {{"cache.fetch", "policy", "demand | miss | always: Dinero IV's -dfetch d, m, a (thesis 3.2: miss)", "miss"},
     KEY_FETCH, P(cache_fetch), EMM_CACHE_FETCH_MISS, 0, 2},
    {{"cache.hit", "cycles", "one cache hit (thesis 3.2)", "1"},
     KEY_COUNT, P(cache_hit), 1, 0, 1000000},
    {{"compute.per_access", "cycles", "the program's compute charged for each access, the same under every capture (docs/machine.md \"Compute\")", "1"},
     KEY_COUNT, P(compute_per_access), 1, 0, 1000000},
    {{"compute.per_work", "cycles", "compute per unit of a record's work field, whose unit is the capture's own (sancov: edges; valgrind: superblocks); 0: not charged", "0"},
     KEY_COUNT, P(compute_per_work), 0, 0, 1000000},
    {{"emm.lookup", "cycles", "EMM runtime: find a requested element through the id table (fitted, docs/calibration.md)", "12"},
     KEY_COUNT, P(emm_lookup), 12, 0, 1000000},
    {{"emm.residency", "cycles", "EMM runtime: check whether a cell is resident", "2"},
     KEY_COUNT, P(emm_residency), 2, 0, 1000000},
    {{"emm.quadtree_level", "cycles", "EMM runtime: descend one quadtree level", "6"},
     KEY_COUNT, P(emm_quadtree_level), 6, 0, 1000000},
    {{"emm.predict", "cycles", "EMM runtime: one prediction of the cells to prefetch", "10"},
     KEY_COUNT, P(emm_predict), 10, 0, 1000000},
    {{"emm.dma_issue_instr", "cycles", "EMM runtime: bookkeeping around one DMA request", "20"},
     KEY_COUNT, P(emm_dma_issue_instr), 20, 0, 1000000},
    {{"emm.fifo", "moves", "extrapolated fetching: moves between cells kept to predict the next (thesis 4.2.2)", "4"},
     KEY_COUNT, P(emm_fifo), 4, 1, 64},
    {{"emm.prefetch_filter", "0|1", "1: do not prefetch a cell whose last prefetch was evicted unused until the program enters it (docs/fetch.md); 0: the thesis' plain schemes", "1"},
     KEY_COUNT, P(emm_prefetch_filter), 1, 0, 1},
    {{"emm.lookup_budget", "bytes", "local store the look-up tables may hold; larger tables live in remote memory and come in by pages (thesis 4.1.1)", "128K"},
     KEY_SIZE, P(emm_lookup_budget), K(128), 0, G(64)},
    {{"emm.lookup_page", "bytes", "one page of paged look-up tables, moved by one DMA", "1K"},
     KEY_SIZE, P(emm_lookup_page), K(1), 64, M(1)},
};

#define NKEYS (sizeof keys / sizeof keys[0])

static const char *const fetch_names[] = {"demand", "miss", "always"};
static const char *const granularity_names[] = {"field", "record"};

/* The words of a text key. */
static const char *const *words_of(const struct key_desc *k, size_t *n)
{
    if (k->type == KEY_FETCH) {
        *n = sizeof fetch_names / sizeof *fetch_names;
        return fetch_names;
    }
    *n = sizeof granularity_names / sizeof *granularity_names;
    return granularity_names;
}

/* dma.issue, the one number of the model before the core's part and the
 * controller's were told apart: setting it sets dma.program to the value
 * and dma.latency to 0 (the core pays all, as then); reading it gives their
 * sum. */
#define ISSUE_ALIAS "dma.issue"

static uint64_t *field(emm_machine *m, const struct key_desc *k)
{
    return (uint64_t *)((char *)&m->p + k->offset);
}

static uint64_t field_get(const emm_machine *m, const struct key_desc *k)
{
    return *(const uint64_t *)((const char *)&m->p + k->offset);
}

static const struct key_desc *find_key(const char *name)
{
    for (size_t i = 0; i < NKEYS; i++)
        if (strcmp(keys[i].pub.name, name) == 0)
            return &keys[i];
    return NULL;
}

static void set_defaults(emm_machine *m)
{
    for (size_t i = 0; i < NKEYS; i++)
        *field(m, &keys[i]) = keys[i].fallback;
}

emm_status emm_machine_new(emm_machine **out, emm_error *err)
{
    emm_machine *m = calloc(1, sizeof *m);
    if (!m)
        return emm_fail(err, EMM_ERR_NOMEM, "machine: out of memory");
    set_defaults(m);
    *out = m;
    return EMM_OK;
}

void emm_machine_free(emm_machine *m)
{
    free(m);
}

emm_status emm_machine_clone(const emm_machine *m, emm_machine **out, emm_error *err)
{
    emm_machine *c = malloc(sizeof *c);
    if (!c)
        return emm_fail(err, EMM_ERR_NOMEM, "machine: out of memory");
    *c = *m;
    *out = c;
    return EMM_OK;
}

size_t emm_machine_key_count(void)
{
    return NKEYS;
}

const emm_machine_key *emm_machine_key_at(size_t i)
{
    assert(i < NKEYS);
    return &keys[i].pub;
}

int emm_machine_key_is_text(const char *key)
{
    const struct key_desc *k = find_key(key);
    return k && (k->type == KEY_FETCH || k->type == KEY_GRANULARITY);
}

uint64_t emm_machine_get(const emm_machine *m, const char *key)
{
    if (strcmp(key, ISSUE_ALIAS) == 0)
        return m->p.dma_program + m->p.dma_latency;
    const struct key_desc *k = find_key(key);
    assert(k);
    return field_get(m, k);
}

/* Sizes print with the largest exact suffix so `show` output reads like a
 * machine file a person wrote. */
static size_t format_value(const struct key_desc *k, uint64_t v, char *buf, size_t cap)
{
    int n;
    size_t nw;
    if (k->type == KEY_FETCH || k->type == KEY_GRANULARITY)
        n = snprintf(buf, cap, "%s", words_of(k, &nw)[v]);
    else if (k->type == KEY_SIZE && v != 0 && v % G(1) == 0)
        n = snprintf(buf, cap, "%lluG", (unsigned long long)(v >> 30));
    else if (k->type == KEY_SIZE && v != 0 && v % M(1) == 0)
        n = snprintf(buf, cap, "%lluM", (unsigned long long)(v >> 20));
    else if (k->type == KEY_SIZE && v != 0 && v % K(1) == 0)
        n = snprintf(buf, cap, "%lluK", (unsigned long long)(v >> 10));
    else
        n = snprintf(buf, cap, "%llu", (unsigned long long)v);
    return n < 0 ? 0 : (size_t)n;
}

size_t emm_machine_format(const emm_machine *m, const char *key, char *buf, size_t cap)
{
    const struct key_desc *k = find_key(key);
    if (!k) {
        if (cap)
            buf[0] = '\0';
        return 0;
    }
    return format_value(k, field_get(m, k), buf, cap);
}

emm_status emm_machine_set_key(emm_machine *m, const char *key, const char *value,
                               const char *where, emm_error *err)
{
    const struct key_desc *k = find_key(key);
    uint64_t v = 0;
    if (strcmp(key, ISSUE_ALIAS) == 0) {
        emm_status st = emm_machine_set_key(m, "dma.program", value, where, err);
        if (st == EMM_OK)
            m->p.dma_latency = 0;
        else if (err) /* name the key as written */
            emm_fail(err, st, "%s: %s = '%s': expected a non-negative integer up to 1000000",
                     where, key, value);
        return st;
    }
    if (!k)
        return emm_fail(err, EMM_ERR_INVALID, "%s: unknown key '%s' (see 'emm machine show')",
                        where, key);
    if (k->type == KEY_FETCH || k->type == KEY_GRANULARITY) {
        size_t i, nw;
        const char *const *w = words_of(k, &nw);
        for (i = 0; i < nw; i++)
            if (strcmp(value, w[i]) == 0)
                break;
        if (i == nw)
            return emm_fail(err, EMM_ERR_INVALID, "%s: %s = '%s': expected %s", where, key, value,
                            k->type == KEY_FETCH ? "demand, miss or always" : "field or record");
        v = i;
    } else {
        bool ok = k->type == KEY_SIZE ? emm_parse_size(value, &v) : emm_parse_u64(value, &v);
        if (!ok)
            return emm_fail(err, EMM_ERR_INVALID, "%s: %s = '%s': expected %s", where, key, value,
                            k->type == KEY_SIZE ? "a size in bytes (e.g. 256K, 6M)"
                                                : "a non-negative integer");
    }
    if (v < k->min || v > k->max) {
        char lo[32], hi[32];
        format_value(k, k->min, lo, sizeof lo);
        format_value(k, k->max, hi, sizeof hi);
        return emm_fail(err, EMM_ERR_RANGE, "%s: %s = '%s': out of range [%s, %s]", where, key,
                        value, lo, hi);
    }
    *field(m, k) = v;
    return EMM_OK;
}

static char *trim(char *s)
{
    char *e;
    while (*s == ' ' || *s == '\t' || *s == '\r')
        s++;
    e = s + strlen(s);
    while (e > s && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\r' || e[-1] == '\n'))
        *--e = '\0';
    return s;
}

emm_status emm_machine_set(emm_machine *m, const char *assignment, emm_error *err)
{
    char buf[256];
    char *eq, *key, *value;
    if (strlen(assignment) >= sizeof buf)
        return emm_fail(err, EMM_ERR_INVALID, "--set %.40s...: too long", assignment);
    strcpy(buf, assignment);
    eq = strchr(buf, '=');
    if (!eq)
        return emm_fail(err, EMM_ERR_INVALID, "--set %s: expected KEY=VALUE", assignment);
    *eq = '\0';
    key = trim(buf);
    value = trim(eq + 1);
    {
        char where[300];
        snprintf(where, sizeof where, "--set %s", assignment);
        return emm_machine_set_key(m, key, value, where, err);
    }
}

static bool section_known(const char *section)
{
    size_t len = strlen(section);
    for (size_t i = 0; i < NKEYS; i++)
        if (strncmp(keys[i].pub.name, section, len) == 0 && keys[i].pub.name[len] == '.')
            return true;
    return false;
}

emm_status emm_machine_load_text(emm_machine *m, const char *name, const char *text,
                                 emm_error *err)
{
    unsigned first_line[NKEYS] = {0};
    char section[64] = "";
    unsigned lineno = 0;
    const char *p = text;

    while (*p) {
        char line[1024], where[600], full[200];
        const char *nl = strchr(p, '\n');
        size_t len = nl ? (size_t)(nl - p) : strlen(p);
        char *s, *c, *eq, *key, *value;
        const struct key_desc *k;
        emm_status st;

        lineno++;
        snprintf(where, sizeof where, "%s:%u", name, lineno);
        if (len >= sizeof line)
            return emm_fail(err, EMM_ERR_FORMAT, "%s: line too long", where);
        memcpy(line, p, len);
        line[len] = '\0';
        p = nl ? nl + 1 : p + len;

        if ((c = strpbrk(line, "#;")) != NULL)
            *c = '\0';
        s = trim(line);
        if (*s == '\0')
            continue;
        if (*s == '[') {
            char *close = strchr(s, ']');
            if (!close || *trim(close + 1) != '\0')
                return emm_fail(err, EMM_ERR_FORMAT, "%s: expected '[section]', got '%s'", where, s);
            *close = '\0';
            s = trim(s + 1);
            if (!section_known(s))
                return emm_fail(err, EMM_ERR_INVALID, "%s: unknown section '[%s]'", where, s);
            snprintf(section, sizeof section, "%s", s);
            continue;
        }
        eq = strchr(s, '=');
        if (!eq)
            return emm_fail(err, EMM_ERR_FORMAT, "%s: expected 'key = value', got '%s'", where, s);
        *eq = '\0';
        key = trim(s);
        value = trim(eq + 1);
        if (*key == '\0')
            return emm_fail(err, EMM_ERR_FORMAT, "%s: missing key before '= %s'", where, value);
        if (section[0] && !strchr(key, '.'))
            snprintf(full, sizeof full, "%s.%s", section, key);
        else
            snprintf(full, sizeof full, "%s", key);
        if (strcmp(full, ISSUE_ALIAS) == 0)
            k = find_key("dma.program"); /* duplicates count against dma.program */
        else
            k = find_key(full);
        if (!k)
            return emm_fail(err, EMM_ERR_INVALID, "%s: unknown key '%s'", where, full);
        if (first_line[k - keys])
            return emm_fail(err, EMM_ERR_INVALID, "%s: duplicate key '%s' (first set on line %u)",
                            where, full, first_line[k - keys]);
        if (*value == '\0')
            return emm_fail(err, EMM_ERR_FORMAT, "%s: %s: missing value", where, full);
        st = emm_machine_set_key(m, full, value, where, err);
        if (st != EMM_OK)
            return st;
        first_line[k - keys] = lineno;
    }
    return EMM_OK;
}

emm_status emm_machine_load(emm_machine *m, const char *path, emm_error *err)
{
    char *text;
    size_t len;
    emm_status st = emm_infile_read(path, "machine file", EMM_MACHINE_FILE_MAX, &text, &len, err);
    if (st != EMM_OK)
        return st;
    if (strlen(text) != len) {
        free(text);
        return emm_fail(err, EMM_ERR_FORMAT, "%s: not a text file (NUL byte)", path);
    }
    st = emm_machine_load_text(m, path, text, err);
    free(text);
    return st;
}

static bool pow2(uint64_t v)
{
    return v && (v & (v - 1)) == 0;
}

emm_status emm_machine_validate(const emm_machine *m, emm_error *err)
{
    const emm_machine_params *p = &m->p;
    if (!pow2(p->word_bytes))
        return emm_fail(err, EMM_ERR_INVALID, "machine: word.bytes = %llu: must be a power of two",
                        (unsigned long long)p->word_bytes);
    if (!pow2(p->cache_line))
        return emm_fail(err, EMM_ERR_INVALID, "machine: cache.line = %llu: must be a power of two",
                        (unsigned long long)p->cache_line);
    if (p->cache_bytes % (p->cache_line * p->cache_assoc) != 0)
        return emm_fail(err, EMM_ERR_INVALID,
                        "machine: cache.bytes = %llu: must be a multiple of cache.line x cache.assoc = %llu",
                        (unsigned long long)p->cache_bytes,
                        (unsigned long long)(p->cache_line * p->cache_assoc));
    if (!pow2(p->cache_bytes / (p->cache_line * p->cache_assoc)))
        return emm_fail(err, EMM_ERR_INVALID,
                        "machine: cache.bytes = %llu: cache.bytes / (cache.line x cache.assoc) = %llu sets, must be a power of two",
                        (unsigned long long)p->cache_bytes,
                        (unsigned long long)(p->cache_bytes / (p->cache_line * p->cache_assoc)));
    return EMM_OK;
}

int emm_machine_remote_warning(const emm_machine *m, const emm_trace_info *trace, char *msg,
                               size_t cap)
{
    uint64_t bytes = 0;
    msg[0] = '\0';
    for (uint32_t i = 0; i < trace->narrays; i++)
        if (trace->arrays[i].kind != EMM_ARRAY_RAW)
            bytes += trace->arrays[i].count * trace->arrays[i].record_size;
    if (bytes <= m->p.remote_bytes)
        return 0;
    char have[32], want[32], key[32];
    emm_machine_format(m, "remote.bytes", key, sizeof key);
    snprintf(msg, cap,
             "the mesh's arrays take %s bytes, more than the machine's remote store of %s "
             "(remote.bytes = %s): simulated as if they fitted",
             emm_grouped(bytes, have), emm_grouped(m->p.remote_bytes, want), key);
    return 1;
}

uint64_t emm_machine_dma_cycles(const emm_machine *m, uint64_t bytes)
{
    if (bytes == 0)
        return 0;
    return emm_dma_sync_cycles(&m->p, bytes);
}

int emm_machine_offers(const emm_machine *m, const emm_strategy *s)
{
    return s->kind != EMM_STRATEGY_CACHE || m->p.cache_present != 0;
}
