/* The strategy grammar of docs/design.md "Strategies": every accepted form parses
 * to the right fields and formats back to itself; every bad form is refused
 * with a message naming the bad part. */
#include <string.h>

#include "check.h"
#include "emm/strategy.h"

static void round_trip(const char *text, emm_strategy_kind kind, emm_layout_kind layout,
                       emm_fetch_kind fetch, uint32_t cell, const char *canonical)
{
    emm_strategy s;
    emm_error err;
    char buf[64];
    CHECKF(emm_strategy_parse(text, &s, &err) == EMM_OK, "%s", text);
    CHECKF(s.kind == kind && s.layout == layout && s.fetch == fetch && s.cell == cell, "%s", text);
    emm_strategy_format(&s, buf, sizeof buf);
    CHECKF(strcmp(buf, canonical) == 0, "%s formats as %s", text, buf);
}

static void refused(const char *text, const char *must_mention)
{
    emm_strategy s;
    emm_error err = {0};
    CHECKF(emm_strategy_parse(text, &s, &err) == EMM_ERR_INVALID, "'%s' accepted", text);
    CHECKF(strstr(err.message, must_mention) != NULL, "'%s': message '%s' lacks '%s'", text,
           err.message, must_mention);
}

int main(void)
{
    round_trip("direct", EMM_STRATEGY_DIRECT, EMM_LAYOUT_ORIGINAL, EMM_FETCH_NONE, 0, "direct");
    round_trip("cache", EMM_STRATEGY_CACHE, EMM_LAYOUT_ORIGINAL, EMM_FETCH_NONE, 0, "cache");
    round_trip("cache@tiles", EMM_STRATEGY_CACHE, EMM_LAYOUT_TILES, EMM_FETCH_NONE, 64,
               "cache@tiles");
    round_trip("tiles+convolution@64", EMM_STRATEGY_EMM, EMM_LAYOUT_TILES,
               EMM_FETCH_CONVOLUTION, 64, "tiles+convolution@64");
    round_trip("grid+naive@16", EMM_STRATEGY_EMM, EMM_LAYOUT_GRID, EMM_FETCH_NAIVE, 16,
               "grid+naive@16");
    round_trip("octree+naive@64", EMM_STRATEGY_EMM, EMM_LAYOUT_OCTREE, EMM_FETCH_NAIVE, 64,
               "octree+naive@64");
    round_trip("grid3d+convolution@32", EMM_STRATEGY_EMM, EMM_LAYOUT_GRID3D,
               EMM_FETCH_CONVOLUTION, 32, "grid3d+convolution@32");
    round_trip("tiles3d+extrapolated@16", EMM_STRATEGY_EMM, EMM_LAYOUT_TILES3D,
               EMM_FETCH_EXTRAPOLATED, 16, "tiles3d+extrapolated@16");
    round_trip("cache@octree", EMM_STRATEGY_CACHE, EMM_LAYOUT_OCTREE, EMM_FETCH_NONE, 64,
               "cache@octree");
    /* The cache on the layout of an EMM strategy at another cell; @64 is
     * the default and is not written. */
    round_trip("cache@grid@4", EMM_STRATEGY_CACHE, EMM_LAYOUT_GRID, EMM_FETCH_NONE, 4,
               "cache@grid@4");
    round_trip("cache@tiles@64", EMM_STRATEGY_CACHE, EMM_LAYOUT_TILES, EMM_FETCH_NONE, 64,
               "cache@tiles");
    refused("octree3d+naive", "accepted: grid, tiles, quadtree, grid3d, tiles3d, octree");
    round_trip("quadtree+extrapolated", EMM_STRATEGY_EMM, EMM_LAYOUT_QUADTREE,
               EMM_FETCH_EXTRAPOLATED, EMM_DEFAULT_CELL, "quadtree+extrapolated@64");

    /* The indexed variant of an EMM strategy, with or without its cell. */
    round_trip("tiles+extrapolated@32:indexed", EMM_STRATEGY_EMM, EMM_LAYOUT_TILES,
               EMM_FETCH_EXTRAPOLATED, 32, "tiles+extrapolated@32:indexed");
    round_trip("octree+naive:indexed", EMM_STRATEGY_EMM, EMM_LAYOUT_OCTREE, EMM_FETCH_NAIVE,
               EMM_DEFAULT_CELL, "octree+naive@64:indexed");
    {
        emm_strategy x, y;
        CHECK(emm_strategy_parse("grid+naive@16:indexed", &x, NULL) == EMM_OK && x.indexed == 1);
        CHECK(emm_strategy_parse("grid+naive@16", &y, NULL) == EMM_OK && y.indexed == 0);
    }
    refused("grid+naive@16:sorted", "':sorted'");
    refused("grid+naive@16:indexed:indexed", "unknown variant");
    refused("direct:indexed", "applies to an EMM strategy");
    refused("cache@tiles:indexed", "applies to an EMM strategy");
    refused("grid+magic:indexed", "'magic'");
    {
        /* One indexed variant per EMM strategy of the sweep, in its order. */
        emm_strategy all[512], ix[512];
        size_t n = emm_strategy_sweep_for(1, all, 512), k = emm_strategy_sweep_indexed(1, ix, 512);
        size_t j = 0;
        for (size_t i = 0; i < n; i++)
            if (all[i].kind == EMM_STRATEGY_EMM) {
                CHECK(j < k && ix[j].indexed == 1 && ix[j].layout == all[i].layout &&
                      ix[j].fetch == all[i].fetch && ix[j].cell == all[i].cell);
                j++;
            } else {
                CHECK(all[i].indexed == 0);
            }
        CHECKF(j == k && k > 0, "%zu indexed of %zu EMM strategies", k, j);
    }

    refused("", "empty");
    refused("cahce", "cahce");
    refused("cache@hex", "'hex'");
    refused("cache@hex@4", "'hex'");
    refused("cache@grid@0", "'0'");
    refused("grid", "needs a fetch scheme");
    refused("grid+magic@16", "'magic'");
    refused("hexes+naive", "'hexes'");
    refused("grid+naive@0", "'0'");
    refused("grid+naive@-4", "'-4'");
    refused("grid+naive@99999999999999999999", "99999999999999999999");
    refused("grid+naive@16x", "'16x'");
    refused("grid+naive@", "''");

    /* The standard sweep: every layout in the plane x every fetch scheme x 7
     * cells (4 to 256) EMM strategies, direct, cache, cache@ each of those
     * layouts — counted from the lists, so a new layout or scheme changes no
     * test. */
    size_t L = 0, L3 = 0;
    for (int k = EMM_LAYOUT_ORIGINAL + 1; k < EMM_LAYOUT_COUNT; k++) {
        L += emm_layout_kind_dims((emm_layout_kind)k) == 2;
        L3 += emm_layout_kind_dims((emm_layout_kind)k) == 3;
    }
    CHECK(L == 3 && L3 == 3 && L + L3 == EMM_LAYOUT_COUNT - 1);
    CHECK(emm_layout_kind_dims(EMM_LAYOUT_OCTREE) == 3 && emm_layout_kind_dims(EMM_LAYOUT_TILES) == 2);
    const size_t F = EMM_FETCH_COUNT - 1; /* less none */
    const size_t want = L * F * 7 + 1 + 1 + L;
    const uint32_t *cells;
    CHECK(emm_strategy_sweep_cells(&cells) == 7 && cells[0] == 4 && cells[1] == 8 &&
          cells[6] == 256);
    CHECK(emm_strategy_sweep(NULL, 0) == want);
    emm_strategy *sweep = calloc(want + 1, sizeof *sweep);
    REQUIRE(sweep);
    size_t n = emm_strategy_sweep(sweep, want + 1);
    CHECK(n == want);
    size_t emm = 0, cache = 0, direct = 0;
    for (size_t i = 0; i < n; i++) {
        emm += sweep[i].kind == EMM_STRATEGY_EMM;
        cache += sweep[i].kind == EMM_STRATEGY_CACHE;
        direct += sweep[i].kind == EMM_STRATEGY_DIRECT;
        for (size_t j = 0; j < i; j++)
            CHECK(memcmp(&sweep[i], &sweep[j], sizeof sweep[i]) != 0);
    }
    /* For a mesh with depth: the same, then the layouts in space after
     * those in the plane, both among the EMM strategies and the cache@. */
    size_t want3 = (L + L3) * F * 7 + 1 + 1 + L + L3;
    emm_strategy *deep = calloc(want3, sizeof *deep), *flat = calloc(want, sizeof *flat);
    REQUIRE(deep && flat);
    CHECK(emm_strategy_sweep_for(0, flat, want) == want);
    CHECK(memcmp(flat, sweep, want * sizeof *flat) == 0);
    CHECK(emm_strategy_sweep_for(1, deep, want3) == want3);
    CHECK(memcmp(deep, sweep, L * F * 7 * sizeof *deep) == 0);
    size_t in_space = 0;
    for (size_t i = 0; i < want3; i++)
        in_space += emm_layout_kind_dims(deep[i].layout) == 3;
    CHECK(in_space == L3 * F * 7 + L3);
    CHECK(emm_layout_kind_dims(deep[L * F * 7].layout) == 3);
    CHECK(emm_layout_kind_dims(deep[want3 - 1].layout) == 3 &&
          deep[want3 - 1].kind == EMM_STRATEGY_CACHE);
    free(deep);
    free(flat);
    free(sweep);
    CHECK(emm == L * F * 7 && cache == L + 1 && direct == 1);
    char text[256], expect[128];
    emm_strategy_sweep_describe(text, sizeof text);
    snprintf(expect, sizeof expect, "%zu layouts x %zu fetch schemes x cells 4, 8, 16, 32, 64, 128, 256", L, F);
    CHECKF(strstr(text, expect), "%s", text);
    snprintf(expect, sizeof expect, "%zu strategies", want);
    CHECKF(strstr(text, expect), "%s", text);
    return check_done();
}
