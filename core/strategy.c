/* Strategy strings (docs/design.md "Strategies"; thesis Table 4.1: a strategy is a
 * layout, a fetch scheme and a transfer size). One parser for the
 * environment, the command line, the tables and the reports. */
#include "emm/strategy.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "error.h"
#include "parse.h"

#define NAME_(e, n, w) #n,
#define LNAME_(e, n, d, w) #n,
static const char *const layout_names[EMM_LAYOUT_COUNT] = {"original", EMM_LAYOUT_LIST(LNAME_)};
static const char *const fetch_names[EMM_FETCH_COUNT] = {"none", EMM_FETCH_LIST(NAME_)};
#undef NAME_
#undef LNAME_
#define DIMS_(e, n, d, w) d,
static const uint32_t layout_dims[EMM_LAYOUT_COUNT] = {0, EMM_LAYOUT_LIST(DIMS_)};
#undef DIMS_
#define WORDS_(e, n, w) w,
#define LWORDS_(e, n, d, w) w,
static const char *const layout_words[EMM_LAYOUT_COUNT] = {"the program's own layout",
                                                          EMM_LAYOUT_LIST(LWORDS_)};
static const char *const fetch_words[EMM_FETCH_COUNT] = {"", EMM_FETCH_LIST(WORDS_)};
#undef WORDS_
#undef LWORDS_
/* "grid, tiles, quadtree, ..." */
#define LIST_(e, n, w) ", " #n
#define LLIST_(e, n, d, w) ", " #n
#define LAYOUTS (&(EMM_LAYOUT_LIST(LLIST_))[2])
#define FETCHES (&(EMM_FETCH_LIST(LIST_))[2])

#define ACCEPTED \
    "direct, cache, cache@LAYOUT[@CELL] or LAYOUT+FETCH[@CELL][" EMM_INDEXED_SUFFIX "]"

/* The standard sweep's cell sizes (thesis §6.3: "small cells" win). */
static const uint32_t sweep_cells[] = {4, 8, 16, 32, 64, 128, 256};

const char *emm_layout_name(emm_layout_kind k)
{
    return (unsigned)k < sizeof layout_names / sizeof *layout_names ? layout_names[k] : "?";
}

const char *emm_fetch_name(emm_fetch_kind k)
{
    return (unsigned)k < sizeof fetch_names / sizeof *fetch_names ? fetch_names[k] : "?";
}

/* Matches [s, s+n) against the EMM layouts. */
static int match_layout(const char *s, size_t n, emm_layout_kind *out)
{
    for (int k = EMM_LAYOUT_ORIGINAL + 1; k < EMM_LAYOUT_COUNT; k++)
        if (strlen(layout_names[k]) == n && memcmp(s, layout_names[k], n) == 0) {
            *out = (emm_layout_kind)k;
            return 1;
        }
    return 0;
}

static int match_fetch(const char *s, size_t n, emm_fetch_kind *out)
{
    for (int k = EMM_FETCH_NONE + 1; k < EMM_FETCH_COUNT; k++)
        if (strlen(fetch_names[k]) == n && memcmp(s, fetch_names[k], n) == 0) {
            *out = (emm_fetch_kind)k;
            return 1;
        }
    return 0;
}

static emm_status parse_cell(const char *q, const char *s, uint32_t *cell, emm_error *err)
{
    uint64_t v;
    char c[EMM_CLIP + 1];
    if (!emm_parse_u64(s, &v) || v == 0 || v > EMM_MAX_CELL)
        return emm_fail(err, EMM_ERR_INVALID,
                        "strategy '%s': cell size '%s' is not an integer from 1 to %u "
                        "(triangles per cell)",
                        q, emm_clip(s, strlen(s), c), EMM_MAX_CELL);
    *cell = (uint32_t)v;
    return EMM_OK;
}

/* Messages quote the text and its parts cut to EMM_CLIP characters, so the
 * list of what is accepted always fits. */
emm_status emm_strategy_parse(const char *text, emm_strategy *out, emm_error *err)
{
    emm_strategy s = {EMM_STRATEGY_DIRECT, EMM_LAYOUT_ORIGINAL, EMM_FETCH_NONE, 0, 0};
    char q[EMM_CLIP + 1], part[EMM_CLIP + 1];

    if (!text || !*text)
        return emm_fail(err, EMM_ERR_INVALID, "strategy is empty; accepted: " ACCEPTED);
    emm_clip(text, strlen(text), q);
    /* The indexed variant: an EMM strategy with the suffix, parsed without
     * it. */
    const char *colon = strchr(text, ':');
    if (colon) {
        char body[128];
        size_t bn = (size_t)(colon - text);
        if (strcmp(colon, EMM_INDEXED_SUFFIX) != 0)
            return emm_fail(err, EMM_ERR_INVALID,
                            "strategy '%s': unknown variant '%s'; accepted: " EMM_INDEXED_SUFFIX
                            " after LAYOUT+FETCH[@CELL]",
                            q, emm_clip(colon, strlen(colon), part));
        if (bn >= sizeof body)
            return emm_fail(err, EMM_ERR_INVALID, "strategy '%s' is too long", q);
        memcpy(body, text, bn);
        body[bn] = '\0';
        emm_status st = emm_strategy_parse(body, &s, err);
        if (st != EMM_OK)
            return st;
        if (s.kind != EMM_STRATEGY_EMM)
            return emm_fail(err, EMM_ERR_INVALID,
                            "strategy '%s': " EMM_INDEXED_SUFFIX
                            " applies to an EMM strategy LAYOUT+FETCH[@CELL], whose look-up "
                            "table it replaces",
                            q);
        s.indexed = 1;
        *out = s;
        return EMM_OK;
    }
    if (strcmp(text, "direct") == 0) {
        *out = s;
        return EMM_OK;
    }
    if (strncmp(text, "cache", 5) == 0 && (text[5] == '\0' || text[5] == '@')) {
        s.kind = EMM_STRATEGY_CACHE;
        if (text[5] == '@') {
            /* cache@LAYOUT[@CELL]: the cache on the layout the EMM strategy
             * at that cell uses (thesis §6.3: "Cache(Grid) runs on the grid
             * layout same as in EMM(Grid)"). */
            const char *l = text + 6, *at = strchr(l, '@');
            size_t ln = at ? (size_t)(at - l) : strlen(l);
            if (!match_layout(l, ln, &s.layout))
                return emm_fail(err, EMM_ERR_INVALID,
                                "strategy '%s': unknown layout '%s'; accepted: %s", q,
                                emm_clip(l, ln, part), LAYOUTS);
            s.cell = EMM_DEFAULT_CELL;
            if (at) {
                emm_status st = parse_cell(q, at + 1, &s.cell, err);
                if (st != EMM_OK)
                    return st;
            }
        }
        *out = s;
        return EMM_OK;
    }

    const char *plus = strchr(text, '+');
    if (!plus) {
        size_t n = strcspn(text, "@");
        if (match_layout(text, n, &s.layout))
            return emm_fail(err, EMM_ERR_INVALID,
                            "strategy '%s': layout '%s' needs a fetch scheme, "
                            "e.g. '%s+naive'; fetch schemes: %s",
                            q, emm_layout_name(s.layout), emm_layout_name(s.layout), FETCHES);
        return emm_fail(err, EMM_ERR_INVALID, "strategy '%s' is unknown; accepted: " ACCEPTED,
                        q);
    }
    if (!match_layout(text, (size_t)(plus - text), &s.layout))
        return emm_fail(err, EMM_ERR_INVALID, "strategy '%s': unknown layout '%s'; accepted: %s",
                        q, emm_clip(text, (size_t)(plus - text), part), LAYOUTS);
    const char *f = plus + 1;
    const char *at = strchr(f, '@');
    size_t fn = at ? (size_t)(at - f) : strlen(f);
    if (!match_fetch(f, fn, &s.fetch))
        return emm_fail(err, EMM_ERR_INVALID,
                        "strategy '%s': unknown fetch scheme '%s'; accepted: %s", q,
                        emm_clip(f, fn, part), FETCHES);
    s.kind = EMM_STRATEGY_EMM;
    s.cell = EMM_DEFAULT_CELL;
    if (at) {
        emm_status st = parse_cell(q, at + 1, &s.cell, err);
        if (st != EMM_OK)
            return st;
    }
    *out = s;
    return EMM_OK;
}

size_t emm_strategy_format(const emm_strategy *s, char *buf, size_t cap)
{
    int n;
    switch (s->kind) {
    case EMM_STRATEGY_DIRECT:
        n = snprintf(buf, cap, "direct");
        break;
    case EMM_STRATEGY_CACHE:
        if (s->layout == EMM_LAYOUT_ORIGINAL)
            n = snprintf(buf, cap, "cache");
        else if (s->cell == EMM_DEFAULT_CELL || s->cell == 0)
            n = snprintf(buf, cap, "cache@%s", emm_layout_name(s->layout));
        else
            n = snprintf(buf, cap, "cache@%s@%u", emm_layout_name(s->layout), s->cell);
        break;
    default:
        n = snprintf(buf, cap, "%s+%s@%u%s", emm_layout_name(s->layout), emm_fetch_name(s->fetch),
                     s->cell, s->indexed ? EMM_INDEXED_SUFFIX : "");
        break;
    }
    return n < 0 ? 0 : (size_t)n;
}

size_t emm_strategy_sweep_cells(const uint32_t **cells)
{
    *cells = sweep_cells;
    return sizeof sweep_cells / sizeof *sweep_cells;
}

uint32_t emm_layout_kind_dims(emm_layout_kind k)
{
    return (unsigned)k < EMM_LAYOUT_COUNT ? layout_dims[k] : 0;
}

int emm_geometry_has_depth(const double *xyz, size_t nv, const int32_t *tri, size_t nt)
{
    (void)nv;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < 3 * nt; i++)
        for (int a = 0; a < 3; a++) {
            double v = xyz[3 * (size_t)tri[i] + a];
            lo[a] = v < lo[a] ? v : lo[a];
            hi[a] = v > hi[a] ? v : hi[a];
        }
    double small = INFINITY, big = 0;
    for (int a = 0; a < 3 && nt > 0; a++) {
        double e = hi[a] - lo[a];
        small = e < small ? e : small;
        big = e > big ? e : big;
    }
    return nt > 0 && isfinite(big) && big > 0 && small >= EMM_DEPTH_RATIO * big;
}

size_t emm_strategy_sweep_for(int depth, emm_strategy *out, size_t cap)
{
    size_t n = 0;
#define PUT(...)                                                                               \
    do {                                                                                       \
        if (n < cap)                                                                           \
            out[n] = (emm_strategy){__VA_ARGS__, 0};                                            \
        n++;                                                                                   \
    } while (0)
    /* The layouts in the plane, then (with depth) those in space. */
    for (uint32_t d = 2; d <= (depth ? 3u : 2u); d++)
        for (int l = EMM_LAYOUT_ORIGINAL + 1; l < EMM_LAYOUT_COUNT; l++)
            if (layout_dims[l] == d)
                for (int f = EMM_FETCH_NONE + 1; f < EMM_FETCH_COUNT; f++)
                    for (size_t c = 0; c < sizeof sweep_cells / sizeof *sweep_cells; c++)
                        PUT(EMM_STRATEGY_EMM, (emm_layout_kind)l, (emm_fetch_kind)f,
                            sweep_cells[c]);
    PUT(EMM_STRATEGY_DIRECT, EMM_LAYOUT_ORIGINAL, EMM_FETCH_NONE, 0);
    PUT(EMM_STRATEGY_CACHE, EMM_LAYOUT_ORIGINAL, EMM_FETCH_NONE, 0);
    for (uint32_t d = 2; d <= (depth ? 3u : 2u); d++)
        for (int l = EMM_LAYOUT_ORIGINAL + 1; l < EMM_LAYOUT_COUNT; l++)
            if (layout_dims[l] == d)
                PUT(EMM_STRATEGY_CACHE, (emm_layout_kind)l, EMM_FETCH_NONE, EMM_DEFAULT_CELL);
#undef PUT
    return n;
}

size_t emm_strategy_sweep_indexed(int depth, emm_strategy *out, size_t cap)
{
    size_t all = emm_strategy_sweep_for(depth, NULL, 0), n = 0;
    emm_strategy *s = malloc(all * sizeof *s);
    if (!s)
        return 0;
    emm_strategy_sweep_for(depth, s, all);
    for (size_t i = 0; i < all; i++)
        if (s[i].kind == EMM_STRATEGY_EMM) {
            if (n < cap) {
                out[n] = s[i];
                out[n].indexed = 1;
            }
            n++;
        }
    free(s);
    return n;
}

int emm_indexed_joins_contest(size_t nv, size_t nt, uint64_t lookup_budget)
{
    return 4 * ((uint64_t)nv + (uint64_t)nt) > lookup_budget;
}

size_t emm_strategy_sweep(emm_strategy *out, size_t cap)
{
    return emm_strategy_sweep_for(0, out, cap);
}

size_t emm_strategy_sweep_describe(char *buf, size_t cap)
{
    char cells[128] = "";
    size_t o = 0;
    int planar = 0;
    for (int l = EMM_LAYOUT_ORIGINAL + 1; l < EMM_LAYOUT_COUNT; l++)
        planar += layout_dims[l] == 2;
    for (size_t c = 0; c < sizeof sweep_cells / sizeof *sweep_cells && o < sizeof cells; c++)
        o += (size_t)snprintf(cells + o, sizeof cells - o, "%s%u", c ? ", " : "", sweep_cells[c]);
    int n = snprintf(buf, cap,
                     "%d layouts x %d fetch schemes x cells %s, then direct, cache and cache@ "
                     "each layout: %zu strategies",
                     planar, EMM_FETCH_COUNT - 1, cells, emm_strategy_sweep(NULL, 0));
    return n < 0 ? 0 : (size_t)n;
}

size_t emm_strategy_words(const emm_strategy *s, char *buf, size_t cap)
{
    int n;
    if (s->kind == EMM_STRATEGY_DIRECT)
        n = snprintf(buf, cap, "direct reads of remote memory, word by word");
    else if (s->kind == EMM_STRATEGY_CACHE && s->layout == EMM_LAYOUT_ORIGINAL)
        n = snprintf(buf, cap, "the hardware cache on the program's own layout");
    else if (s->kind == EMM_STRATEGY_CACHE)
        n = snprintf(buf, cap, "the hardware cache on the %s layout of %u triangles per cell",
                     emm_layout_name(s->layout), s->cell);
    else
        n = snprintf(buf, cap, "layout %s (%s), fetch %s (%s), %u triangles per cell%s",
                     emm_layout_name(s->layout), layout_words[s->layout],
                     emm_fetch_name(s->fetch), fetch_words[s->fetch], s->cell,
                     s->indexed ? ", the program numbered as the layout (no look-up table)"
                                : "");
    return n < 0 ? 0 : (size_t)n;
}
