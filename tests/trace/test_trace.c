/* Trace files: round trips, streaming, and damaged files (truncated at every
 * byte, flipped bits, wrong magic, a future version, bad geometry, elements
 * out of range). Files are written into the test's working directory. */
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "emm/trace.h"
#include "trace_format.h"

static uint64_t rng_state = 0x243F6A8885A308D3ull;

static uint64_t rnd(void)
{
    uint64_t x = rng_state;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    return rng_state = x;
}

static char path_buf[4][256];

static const char *tpath(int slot, const char *name)
{
    snprintf(path_buf[slot], sizeof path_buf[slot], "trace_test_%ld_%s.emt", (long)getpid(), name);
    return path_buf[slot];
}

/* Three arrays covering the field ranges: vertices, triangles with a large
 * record, raw memory with elements over the whole 64-bit range. */
static const emm_trace_array test_arrays[3] = {
    {EMM_ARRAY_VERTICES, 80, 1000, 0x7f0000001000ull},
    {EMM_ARRAY_TRIANGLES, 4000000000u, 1900, 0x1000},
    {EMM_ARRAY_RAW, 1, 0, 0},
};

static double geo_xyz[3 * 5];
static int32_t geo_tri[3 * 3] = {0, 1, 2, 1, 3, 2, 2, 3, 4};

static emm_trace_geometry test_geometry(void)
{
    for (int i = 0; i < 15; i++)
        geo_xyz[i] = i * 0.25 - 1.0 / 3.0;
    emm_trace_geometry g = {5, 3, geo_xyz, geo_tri};
    return g;
}

/* Records with mostly local steps, some jumps, and extreme values. */
static void gen_records(emm_trace_record *r, size_t n)
{
    uint64_t cur[3] = {0, 0, 0};
    for (size_t i = 0; i < n; i++) {
        uint32_t a = (uint32_t)(rnd() % 3);
        uint64_t x = rnd();
        emm_trace_record *o = &r[i];
        memset(o, 0, sizeof *o);
        o->array = a;
        if (a == 2) {
            cur[2] = (x & 7) == 0 ? rnd() : cur[2] + (x % 64) - 32; /* any 64-bit address */
            o->element = cur[2];
            o->offset = 0;
        } else {
            uint64_t count = test_arrays[a].count;
            if ((x & 15) == 0)
                cur[a] = rnd() % count;
            else
                cur[a] = (cur[a] + count + (x >> 8) % 21 - 10) % count;
            o->element = cur[a];
            o->offset = (uint32_t)(rnd() % test_arrays[a].record_size);
        }
        uint64_t y = rnd();
        /* Now and then the widest access the array takes (trace.h). */
        uint32_t widest = a == 2 || test_arrays[a].record_size > EMM_TRACE_MAX_ACCESS_BYTES
                              ? EMM_TRACE_MAX_ACCESS_BYTES
                              : test_arrays[a].record_size;
        o->bytes = (y & 255) == 0 ? widest : (uint32_t)(1u << (y % 4));
        if (o->element + (o->bytes - 1) < o->element) /* would run past 2^64 */
            o->element -= o->bytes;
        o->work = (y & 1023) == 1 ? UINT32_MAX : (uint32_t)((y >> 16) % 40);
        o->write = (uint8_t)((y >> 40) % 4 == 0);
    }
}

static bool same_record(const emm_trace_record *a, const emm_trace_record *b)
{
    return a->element == b->element && a->array == b->array && a->offset == b->offset &&
           a->bytes == b->bytes && a->work == b->work && a->write == b->write;
}

static emm_status write_trace(const char *path, const emm_trace_record *r, size_t n, int compress,
                              const emm_trace_geometry *g, emm_error *err)
{
    emm_trace_writer *w = NULL;
    emm_status s = emm_trace_writer_open(path, test_arrays, 3, g, compress, &w, err);
    if (s != EMM_OK)
        return s;
    /* In uneven pieces, to cross block boundaries inside a call. */
    size_t done = 0;
    while (done < n && s == EMM_OK) {
        size_t k = 1 + rnd() % 70000;
        if (k > n - done)
            k = n - done;
        s = emm_trace_write(w, r + done, k, err);
        done += k;
    }
    if (s != EMM_OK) {
        emm_trace_writer_abort(w);
        return s;
    }
    return emm_trace_writer_close(w, err);
}

/* Reads the whole trace with a buffer of `cap` records and compares. */
static bool read_and_compare(const char *path, const emm_trace_record *want, size_t n, size_t cap)
{
    emm_error err;
    emm_trace_reader *r = NULL;
    if (emm_trace_reader_open(path, &r, &err) != EMM_OK) {
        fprintf(stderr, "open: %s\n", err.message);
        return false;
    }
    emm_trace_record *buf = malloc(cap * sizeof *buf);
    size_t total = 0, got;
    bool ok = true;
    for (;;) {
        if (emm_trace_read(r, buf, cap, &got, &err) != EMM_OK) {
            fprintf(stderr, "read: %s\n", err.message);
            ok = false;
            break;
        }
        if (got == 0)
            break;
        for (size_t i = 0; i < got && ok; i++)
            if (total + i >= n || !same_record(&buf[i], &want[total + i])) {
                fprintf(stderr, "record %zu differs\n", total + i);
                ok = false;
            }
        total += got;
        if (!ok)
            break;
    }
    free(buf);
    emm_trace_reader_close(r);
    return ok && total == n;
}

static void test_round_trip(void)
{
    const size_t sizes[] = {0, 1, 1000, 65536, 3 * 65536 + 17};
    const size_t caps[] = {1, 7, 4096, 65536, 300000};
    emm_trace_geometry g = test_geometry();
    size_t maxn = 3 * 65536 + 17;
    emm_trace_record *recs = malloc(maxn * sizeof *recs);
    gen_records(recs, maxn);
    for (int compress = 0; compress <= 1; compress++) {
        for (size_t si = 0; si < sizeof sizes / sizeof sizes[0]; si++) {
            size_t n = sizes[si];
            const char *path = tpath(0, "roundtrip");
            emm_error err;
            emm_status s = write_trace(path, recs, n, compress, &g, &err);
            CHECKF(s == EMM_OK, "%s", err.message);
            /* The info. */
            emm_trace_reader *r = NULL;
            REQUIRE(emm_trace_reader_open(path, &r, &err) == EMM_OK);
            const emm_trace_info *info = emm_trace_reader_info(r);
            CHECK(info->version == EMM_TRACE_VERSION);
            CHECK(info->compressed == compress);
            CHECK(info->accesses == n);
            uint64_t writes = 0;
            for (size_t i = 0; i < n; i++)
                writes += recs[i].write;
            CHECK(info->writes == writes);
            CHECK(info->blocks == (n + 65535) / 65536);
            CHECK(info->narrays == 3);
            for (int a = 0; a < 3; a++)
                CHECK(info->arrays[a].kind == test_arrays[a].kind &&
                      info->arrays[a].record_size == test_arrays[a].record_size &&
                      info->arrays[a].count == test_arrays[a].count &&
                      info->arrays[a].base == test_arrays[a].base);
            CHECK(info->geometry.nv == 5 && info->geometry.nt == 3);
            CHECK(memcmp(info->geometry.xyz, geo_xyz, sizeof geo_xyz) == 0);
            CHECK(memcmp(info->geometry.tri, geo_tri, sizeof geo_tri) == 0);
            emm_trace_reader_close(r);
            for (size_t ci = 0; ci < sizeof caps / sizeof caps[0]; ci++) {
                if (caps[ci] == 1 && n > 70000)
                    continue; /* slow and covered by cap 7 */
                CHECKF(read_and_compare(path, recs, n, caps[ci]), "n %zu cap %zu compress %d", n,
                       caps[ci], compress);
            }
            remove(path);
        }
    }
    free(recs);
}

static void test_no_geometry_no_arrays(void)
{
    emm_trace_writer *w = NULL;
    emm_error err;
    const char *path = tpath(0, "bare");
    REQUIRE(emm_trace_writer_open(path, NULL, 0, NULL, 0, &w, &err) == EMM_OK);
    REQUIRE(emm_trace_writer_close(w, &err) == EMM_OK);
    emm_trace_reader *r = NULL;
    REQUIRE(emm_trace_reader_open(path, &r, &err) == EMM_OK);
    const emm_trace_info *info = emm_trace_reader_info(r);
    CHECK(info->narrays == 0 && info->accesses == 0 && info->geometry.nv == 0);
    emm_trace_record rec;
    size_t got = 99;
    CHECK(emm_trace_read(r, &rec, 1, &got, &err) == EMM_OK && got == 0);
    emm_trace_reader_close(r);
    remove(path);
}

static void test_rewind(void)
{
    size_t n = 150000;
    emm_trace_record *recs = malloc(n * sizeof *recs), *buf = malloc(n * sizeof *buf);
    gen_records(recs, n);
    emm_trace_geometry g = test_geometry();
    emm_error err;
    const char *path = tpath(0, "rewind");
    REQUIRE(write_trace(path, recs, n, 1, &g, &err) == EMM_OK);
    emm_trace_reader *r = NULL;
    REQUIRE(emm_trace_reader_open(path, &r, &err) == EMM_OK);
    size_t got = 0;
    REQUIRE(emm_trace_read(r, buf, 70001, &got, &err) == EMM_OK && got == 70001);
    for (int pass = 0; pass < 2; pass++) {
        REQUIRE(emm_trace_rewind(r, &err) == EMM_OK);
        size_t total = 0;
        while (emm_trace_read(r, buf + total, 33333 < n - total ? 33333 : n - total + 1, &got,
                              &err) == EMM_OK && got > 0)
            total += got;
        CHECK(total == n);
        bool same = true;
        for (size_t i = 0; i < n && same; i++)
            same = same_record(&buf[i], &recs[i]);
        CHECK(same);
    }
    emm_trace_reader_close(r);
    remove(path);
    free(recs);
    free(buf);
}

static long rss_kib(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    long size = 0, res = 0;
    if (!f)
        return -1;
    if (fscanf(f, "%ld %ld", &size, &res) != 2)
        res = -1;
    fclose(f);
    return res < 0 ? -1 : res * (sysconf(_SC_PAGESIZE) / 1024);
}

/* Memory does not grow with the trace: write and read 4M records through a
 * small buffer and compare the resident size after the first block with
 * the one at the end. */
static void test_streaming_memory(void)
{
    const size_t n = 4000000, piece = 1000;
    emm_trace_record *buf = malloc(piece * sizeof *buf);
    emm_error err;
    const char *path = tpath(0, "stream");
    emm_trace_writer *w = NULL;
    REQUIRE(emm_trace_writer_open(path, test_arrays, 3, NULL, 0, &w, &err) == EMM_OK);
    long rss_w0 = 0;
    for (size_t done = 0; done < n; done += piece) {
        gen_records(buf, piece);
        REQUIRE(emm_trace_write(w, buf, piece, &err) == EMM_OK);
        if (done == 200 * piece)
            rss_w0 = rss_kib();
    }
    long rss_w1 = rss_kib();
    REQUIRE(emm_trace_writer_close(w, &err) == EMM_OK);
    emm_trace_reader *r = NULL;
    REQUIRE(emm_trace_reader_open(path, &r, &err) == EMM_OK);
    size_t got, total = 0;
    long rss_r0 = 0;
    while (emm_trace_read(r, buf, piece, &got, &err) == EMM_OK && got > 0) {
        total += got;
        if (total == 200 * piece)
            rss_r0 = rss_kib();
    }
    long rss_r1 = rss_kib();
    CHECK(total == n);
    CHECKF(rss_w1 - rss_w0 < 2048, "writer grew from %ld to %ld KiB", rss_w0, rss_w1);
    CHECKF(rss_r1 - rss_r0 < 2048, "reader grew from %ld to %ld KiB", rss_r0, rss_r1);
    emm_trace_reader_close(r);
    remove(path);
    free(buf);
}

/* Opens and reads a whole file; returns the first failure's status (EMM_OK
 * if the file reads cleanly) with its message in err. */
static emm_status read_all(const char *path, emm_error *err)
{
    emm_trace_reader *r = NULL;
    emm_status s = emm_trace_reader_open(path, &r, err);
    if (s != EMM_OK)
        return s;
    emm_trace_record buf[500];
    size_t got;
    while ((s = emm_trace_read(r, buf, 500, &got, err)) == EMM_OK && got > 0) {
    }
    emm_trace_reader_close(r);
    return s;
}

static unsigned char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    REQUIRE(f);
    fseek(f, 0, SEEK_END);
    *len = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc(*len + 1);
    REQUIRE(fread(b, 1, *len, f) == *len);
    fclose(f);
    return b;
}

/* A new file each time: on ext4 a file emptied by fopen's truncation and
 * written again is sent to the disk at close (auto_da_alloc), and this test
 * writes thousands. */
static void spit(const char *path, const unsigned char *b, size_t len)
{
    remove(path);
    FILE *f = fopen(path, "wb");
    REQUIRE(f);
    REQUIRE(fwrite(b, 1, len, f) == len);
    fclose(f);
}

/* The file at path cut to its first len bytes. The cuts of a file are made
 * longest first from one copy, each shortening the one before, so the
 * bytes are written once and not once per cut (the multi-block file's cuts
 * alone would be 1.6 GB of writes). */
static void cut_to(const char *path, size_t len)
{
    REQUIRE(truncate(path, (off_t)len) == 0);
}

/* The error message names the file and a byte offset. */
static bool names_offset(const char *path, const emm_error *err)
{
    size_t pl = strlen(path);
    return strncmp(err->message, path, pl) == 0 && strncmp(err->message + pl, ": byte ", 7) == 0;
}

static void make_small(const char *path, int compress, size_t n)
{
    emm_trace_record *recs = malloc(n * sizeof *recs);
    gen_records(recs, n);
    emm_trace_geometry g = test_geometry();
    emm_error err;
    REQUIRE(write_trace(path, recs, n, compress, &g, &err) == EMM_OK);
    free(recs);
}

static void test_truncation(void)
{
    for (int compress = 0; compress <= 1; compress++) {
        const char *src = tpath(0, "small"), *dst = tpath(1, "cut");
        make_small(src, compress, 300);
        size_t len;
        unsigned char *b = slurp(src, &len);
        emm_error err;
        CHECK(read_all(src, &err) == EMM_OK);
        int bad = 0;
        spit(dst, b, len);
        for (size_t cut = len; cut-- > 0;) {
            cut_to(dst, cut);
            emm_status s = read_all(dst, &err);
            if (s != EMM_ERR_FORMAT || !names_offset(dst, &err)) {
                if (bad++ < 5)
                    fprintf(stderr, "cut at %zu: status %d: %s\n", cut, (int)s, err.message);
            }
        }
        CHECKF(bad == 0, "%d truncations not reported as FORMAT with an offset", bad);
        /* A message as the brief shows it. */
        spit(dst, b, len - 5);
        read_all(dst, &err);
        CHECKF(strstr(err.message, "truncated in block 0 payload") != NULL, "%s", err.message);
        free(b);
        remove(src);
        remove(dst);
    }
    /* A multi-block file, cut around every block boundary. */
    const char *src = tpath(0, "multi"), *dst = tpath(1, "cut");
    make_small(src, 0, 3 * 65536 + 5);
    size_t len;
    unsigned char *b = slurp(src, &len);
    int bad = 0, tried = 0;
    size_t ncuts = 0, *cuts = malloc((len / 4099 + 1) * sizeof *cuts);
    REQUIRE(cuts);
    for (size_t cut = 1; cut < len; cut += 4099 + rnd() % 64)
        cuts[ncuts++] = cut;
    spit(dst, b, len);
    while (ncuts > 0) {
        cut_to(dst, cuts[--ncuts]);
        emm_error err;
        emm_status s = read_all(dst, &err);
        tried++;
        if (s != EMM_ERR_FORMAT || !names_offset(dst, &err))
            bad++;
    }
    CHECKF(bad == 0, "%d of %d cuts in a multi-block file not reported", bad, tried);
    free(cuts);
    free(b);
    remove(src);
    remove(dst);
}

static void test_bit_flips(void)
{
    for (int compress = 0; compress <= 1; compress++) {
        const char *src = tpath(0, "flip_src"), *dst = tpath(1, "flip");
        make_small(src, compress, 400);
        size_t len;
        unsigned char *b = slurp(src, &len);
        int bad = 0;
        /* Every byte, one bit each (a different bit per byte). */
        for (size_t i = 0; i < len; i++) {
            b[i] ^= (unsigned char)(1u << (i % 8));
            spit(dst, b, len);
            b[i] ^= (unsigned char)(1u << (i % 8));
            emm_error err;
            emm_status s = read_all(dst, &err);
            bool version = i >= EMM_TH_VERSION && i < EMM_TH_VERSION + 4;
            bool ok = (s == EMM_ERR_FORMAT || s == EMM_ERR_CORRUPT ||
                       (version && s == EMM_ERR_UNSUPPORTED)) &&
                      names_offset(dst, &err);
            if (!ok && bad++ < 5)
                fprintf(stderr, "flip at %zu: status %d: %s\n", i, (int)s, err.message);
        }
        CHECKF(bad == 0, "%d of %zu flipped bytes not detected", bad, len);
        /* Random damage: a few random bytes overwritten. */
        bad = 0;
        for (int t = 0; t < 300; t++) {
            unsigned char *c = malloc(len);
            memcpy(c, b, len);
            int k = 1 + (int)(rnd() % 4);
            for (int j = 0; j < k; j++) {
                size_t at = rnd() % len;
                c[at] = (unsigned char)(c[at] ^ (1 + rnd() % 255));
            }
            spit(dst, c, len);
            free(c);
            emm_error err;
            emm_status s = read_all(dst, &err);
            if (s != EMM_ERR_FORMAT && s != EMM_ERR_CORRUPT && s != EMM_ERR_UNSUPPORTED)
                bad++;
        }
        CHECKF(bad == 0, "%d random damages not detected", bad);
        /* Trailing garbage. */
        unsigned char *c = malloc(len + 3);
        memcpy(c, b, len);
        memcpy(c + len, "xyz", 3);
        spit(dst, c, len + 3);
        emm_error err;
        CHECK(read_all(dst, &err) == EMM_ERR_FORMAT);
        CHECKF(strstr(err.message, "unexpected bytes after the last block") != NULL, "%s",
               err.message);
        free(c);
        free(b);
        remove(src);
        remove(dst);
    }
}

static void test_bad_magic_and_missing(void)
{
    const char *p = tpath(0, "magic");
    spit(p, (const unsigned char *)"this is not a trace file at all, just some text\n", 49);
    emm_error err;
    emm_trace_reader *r = NULL;
    CHECK(emm_trace_reader_open(p, &r, &err) == EMM_ERR_FORMAT && r == NULL);
    CHECKF(strstr(err.message, "byte 0: not an emm trace") != NULL, "%s", err.message);
    spit(p, (const unsigned char *)"", 0);
    CHECK(emm_trace_reader_open(p, &r, &err) == EMM_ERR_FORMAT);
    remove(p);
    CHECK(emm_trace_reader_open(p, &r, &err) == EMM_ERR_IO);
    CHECK(strstr(err.message, p) == err.message);
}

/* Rewrites a region's checksum after changing it, so that only the
 * semantic check can catch the change. */
static void rehash(unsigned char *b, size_t start, size_t len)
{
    emm_put_le64(b + start + len, emm_trace_hash(b + start, len, 0));
}

static void test_future_version(void)
{
    const char *src = tpath(0, "ver_src"), *dst = tpath(1, "ver");
    make_small(src, 0, 10);
    size_t len;
    unsigned char *b = slurp(src, &len);
    emm_put_le32(b + EMM_TH_VERSION, 7);
    rehash(b, 0, EMM_TH_CHECKSUM);
    spit(dst, b, len);
    emm_error err;
    CHECK(read_all(dst, &err) == EMM_ERR_UNSUPPORTED);
    CHECKF(strstr(err.message, "unsupported trace version 7 (this emm reads up to 2)") != NULL,
           "%s", err.message);
    free(b);
    remove(src);
    remove(dst);
}

static void test_bad_geometry(void)
{
    /* The writer refuses it. */
    emm_trace_geometry g = test_geometry();
    int32_t tri[9];
    memcpy(tri, geo_tri, sizeof tri);
    tri[4] = 5; /* == nv */
    g.tri = tri;
    emm_trace_writer *w = NULL;
    emm_error err;
    const char *src = tpath(0, "geo_src"), *dst = tpath(1, "geo");
    CHECK(emm_trace_writer_open(src, test_arrays, 3, &g, 0, &w, &err) == EMM_ERR_INVALID);
    CHECK(w == NULL && access(src, F_OK) != 0);
    double xyz[15];
    memcpy(xyz, geo_xyz, sizeof xyz);
    xyz[7] = 0.0 / 0.0;
    g.tri = geo_tri;
    g.xyz = xyz;
    CHECK(emm_trace_writer_open(src, test_arrays, 3, &g, 0, &w, &err) == EMM_ERR_INVALID);
    /* The reader refuses a file that has it, even with a right checksum. */
    make_small(src, 0, 10);
    size_t len;
    unsigned char *b = slurp(src, &len);
    size_t geo = EMM_TRACE_HEADER_SIZE + 3 * EMM_TRACE_ARRAY_SIZE + 8;
    size_t glen = 5 * 24 + 3 * 12;
    emm_put_le32(b + geo + 5 * 24 + 4 * 4, 5);
    rehash(b, geo, glen);
    spit(dst, b, len);
    CHECK(read_all(dst, &err) == EMM_ERR_FORMAT);
    CHECKF(strstr(err.message, "triangle 1 has vertex index 5 (5 vertices)") != NULL, "%s",
           err.message);
    CHECK(names_offset(dst, &err));
    emm_put_le32(b + geo + 5 * 24 + 4 * 4, (uint32_t)-1);
    rehash(b, geo, glen);
    spit(dst, b, len);
    CHECK(read_all(dst, &err) == EMM_ERR_FORMAT);
    free(b);
    remove(src);
    remove(dst);
}

static void test_element_out_of_range(void)
{
    const char *src = tpath(0, "elem_src"), *dst = tpath(1, "elem");
    emm_trace_record recs[3] = {
        {.element = 10, .array = 0, .offset = 0, .bytes = 8},
        {.element = 999, .array = 0, .offset = 8, .bytes = 8},
        {.element = 5, .array = 1, .offset = 4, .bytes = 4, .write = 1},
    };
    emm_error err;
    emm_trace_geometry g = test_geometry();
    REQUIRE(write_trace(src, recs, 3, 0, &g, &err) == EMM_OK);
    size_t len;
    unsigned char *b = slurp(src, &len);
    size_t table = EMM_TRACE_HEADER_SIZE;
    emm_put_le64(b + table + 8, 500); /* array 0: 500 records */
    rehash(b, table, 3 * EMM_TRACE_ARRAY_SIZE);
    spit(dst, b, len);
    CHECK(read_all(dst, &err) == EMM_ERR_FORMAT);
    CHECKF(strstr(err.message, "record 1: element 999 out of range (array 0 has 500 records)") !=
               NULL,
           "%s", err.message);
    CHECK(names_offset(dst, &err));
    /* A kind that does not exist. */
    free(b);
    b = slurp(src, &len);
    emm_put_le32(b + table + EMM_TRACE_ARRAY_SIZE, 9);
    rehash(b, table, 3 * EMM_TRACE_ARRAY_SIZE);
    spit(dst, b, len);
    CHECK(read_all(dst, &err) == EMM_ERR_FORMAT);
    CHECKF(strstr(err.message, "array 1 has unknown kind 9") != NULL, "%s", err.message);
    /* Record size 0. */
    free(b);
    b = slurp(src, &len);
    emm_put_le32(b + table + 4, 0);
    rehash(b, table, 3 * EMM_TRACE_ARRAY_SIZE);
    spit(dst, b, len);
    CHECK(read_all(dst, &err) == EMM_ERR_FORMAT);
    free(b);
    remove(src);
    remove(dst);
}

/* Damage inside a block's payload with both checksums recomputed: the
 * decoder's own checks must catch it. */
static void test_bad_block_content(void)
{
    const char *src = tpath(0, "blk_src"), *dst = tpath(1, "blk");
    emm_trace_record recs[40];
    for (int i = 0; i < 40; i++)
        recs[i] = (emm_trace_record){.element = (uint64_t)(i * 7 % 1000), .array = (uint32_t)(i % 2),
                                     .offset = (uint32_t)(i % 4), .bytes = 4 + (uint32_t)(i % 3),
                                     .work = (uint32_t)i, .write = (uint8_t)(i % 2)};
    emm_error err;
    emm_trace_geometry g = test_geometry();
    REQUIRE(write_trace(src, recs, 40, 0, &g, &err) == EMM_OK);
    size_t len;
    unsigned char *orig = slurp(src, &len);
    /* Header, array table, geometry, an empty module table. */
    const size_t blk = EMM_TRACE_HEADER_SIZE + 3 * EMM_TRACE_ARRAY_SIZE + 8 + 5 * 24 + 3 * 12 + 8 +
                       EMM_TRACE_MODULES_HEADER + 8;
    const size_t pay = blk + EMM_TRACE_BLOCK_HEADER_SIZE;
    const size_t plen = len - pay;
    REQUIRE(emm_le32(orig + blk) == EMM_TRACE_BLOCK_MAGIC && emm_le32(orig + blk + 12) == plen);
    struct {
        size_t at;      /* byte inside the payload */
        int size;       /* 1, 8 */
        uint64_t value;
        const char *want;
    } cases[] = {
        {8 + 8 * EMM_COL_BYTES, 8, 0, "access of 0 bytes"},
        {8 + 8 * EMM_COL_BYTES, 8, 5000, "bytes (array"},
        {8 + 8 * EMM_COL_WRITE, 8, 2, "write flag 2"},
        {8 + 8 * EMM_COL_ARRAY, 8, 5, "array 5 out of range (3 arrays)"},
        {8 + 8 * EMM_COL_WORK, 8, UINT32_MAX, "work 4294967"},
        {8 + 8 * EMM_COL_OFFSET, 8, 79, "outside the 80-byte record of array 0"},
        {8 + 8 * EMM_COL_DELTA, 8, 990, "element"},
        {EMM_COL_WORK, 1, 60, "column 4 has width 60"},
        {EMM_COL_WORK, 1, 7, "column sizes add up"},
        {6, 1, 1, "column sizes add up"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        unsigned char *b = malloc(len);
        memcpy(b, orig, len);
        if (cases[k].size == 8)
            emm_put_le64(b + pay + cases[k].at, cases[k].value);
        else
            b[pay + cases[k].at] = (unsigned char)cases[k].value;
        emm_put_le64(b + blk + EMM_TB_PAYLOAD_SUM, emm_trace_hash(b + pay, plen, 0));
        emm_put_le64(b + blk + EMM_TB_HEADER_SUM, emm_trace_hash(b + blk, EMM_TB_HEADER_SUM, 0));
        spit(dst, b, len);
        emm_status s = read_all(dst, &err);
        CHECKF(s == EMM_ERR_FORMAT && strstr(err.message, cases[k].want) && names_offset(dst, &err),
               "case %zu: status %d: %s", k, (int)s, err.message);
        free(b);
    }
    /* A record count in the block header that disagrees with the file's. */
    unsigned char *b = malloc(len);
    memcpy(b, orig, len);
    emm_put_le32(b + blk + EMM_TB_RECORDS, 41);
    emm_put_le64(b + blk + EMM_TB_HEADER_SUM, emm_trace_hash(b + blk, EMM_TB_HEADER_SUM, 0));
    spit(dst, b, len);
    CHECK(read_all(dst, &err) == EMM_ERR_FORMAT);
    emm_put_le32(b + blk + EMM_TB_RECORDS, 39);
    emm_put_le64(b + blk + EMM_TB_HEADER_SUM, emm_trace_hash(b + blk, EMM_TB_HEADER_SUM, 0));
    spit(dst, b, len);
    CHECK(read_all(dst, &err) == EMM_ERR_FORMAT);
    free(b);
    free(orig);
    remove(src);
    remove(dst);
}

static void test_writer_rejects(void)
{
    const char *p = tpath(0, "reject");
    const emm_trace_record bad[] = {
        {.element = 1, .array = 3, .bytes = 1},                /* no such array */
        {.element = 1000, .array = 0, .bytes = 1},             /* element == count */
        {.element = 1, .array = 0, .offset = 80, .bytes = 1},  /* offset outside the record */
        {.element = 1, .array = 0, .bytes = 0},                /* zero bytes */
        {.element = 1, .array = 0, .bytes = 4, .write = 2},    /* write flag */
        {.element = 0, .array = 2, .offset = 1, .bytes = 4},   /* raw: offset must be 0 */
        {.element = 1, .array = 0, .bytes = 81},               /* wider than the record */
        {.element = 0, .array = 2, .bytes = EMM_TRACE_MAX_ACCESS_BYTES + 1}, /* raw: too wide */
        {.element = UINT64_MAX - 2, .array = 2, .bytes = 4},  /* raw: past 2^64 */
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        emm_trace_writer *w = NULL;
        emm_error err;
        REQUIRE(emm_trace_writer_open(p, test_arrays, 3, NULL, 0, &w, &err) == EMM_OK);
        emm_trace_record good = {.element = 999, .array = 0, .offset = 79, .bytes = 1};
        CHECK(emm_trace_write(w, &good, 1, &err) == EMM_OK);
        CHECKF(emm_trace_write(w, &bad[i], 1, &err) == EMM_ERR_RANGE, "case %zu", i);
        CHECK(strstr(err.message, "record 1:") != NULL);
        emm_trace_writer_abort(w);
        CHECK(access(p, F_OK) != 0);
    }
    /* Invalid arrays. */
    emm_trace_array arr = {EMM_ARRAY_VERTICES, 0, 10, 0};
    emm_trace_writer *w = NULL;
    emm_error err;
    CHECK(emm_trace_writer_open(p, &arr, 1, NULL, 0, &w, &err) == EMM_ERR_INVALID);
    arr.record_size = 16;
    arr.base = UINT64_MAX - 100;
    CHECK(emm_trace_writer_open(p, &arr, 1, NULL, 0, &w, &err) == EMM_ERR_INVALID);
    arr = (emm_trace_array){EMM_ARRAY_RAW, 4, 0, 0};
    CHECK(emm_trace_writer_open(p, &arr, 1, NULL, 0, &w, &err) == EMM_ERR_INVALID);
    /* An unwritable place. */
    CHECK(emm_trace_writer_open("/nonexistent-dir/x.emt", test_arrays, 3, NULL, 0, &w, &err) ==
          EMM_ERR_IO);
    /* The temporary file is not left behind, nor does a half-written trace
     * appear before close. */
    REQUIRE(emm_trace_writer_open(p, test_arrays, 3, NULL, 0, &w, &err) == EMM_OK);
    CHECK(access(p, F_OK) != 0);
    REQUIRE(emm_trace_writer_close(w, &err) == EMM_OK);
    CHECK(access(p, F_OK) == 0);
    remove(p);
}

static void test_hash(void)
{
    unsigned char buf[77];
    for (size_t i = 0; i < sizeof buf; i++)
        buf[i] = (unsigned char)rnd();
    uint64_t h = emm_trace_hash(buf, sizeof buf, 0);
    int missed = 0;
    for (size_t i = 0; i < sizeof buf; i++)
        for (int bit = 0; bit < 8; bit++) {
            buf[i] ^= (unsigned char)(1u << bit);
            missed += emm_trace_hash(buf, sizeof buf, 0) == h;
            buf[i] ^= (unsigned char)(1u << bit);
        }
    CHECK(missed == 0);
    CHECK(emm_trace_hash(buf, 76, 0) != emm_trace_hash(buf, 77, 0));
    CHECK(emm_trace_hash(buf, 0, 0) != emm_trace_hash(buf, 0, 1));
}

/* Version 2's pc column and module table: written, read back, compressed
 * or not; the modules as given. */
static void test_pcs_and_modules(void)
{
    const char *path = tpath(0, "pc");
    enum { N = 70000 };
    emm_trace_record *recs = malloc(N * sizeof *recs);
    REQUIRE(recs);
    for (size_t i = 0; i < N; i++) {
        recs[i] = (emm_trace_record){.element = i % 1000, .array = (uint32_t)(i % 2),
                                     .offset = 4, .bytes = 4, .work = 1,
                                     .pc = i % 5 == 0 ? 0 : 0x555500001000u + 16 * (i % 37)};
    }
    const emm_trace_module mods[2] = {{0x555500000000u, 0x555500000000u, 0x555500100000u,
                                       "/usr/bin/prog"},
                                      {0x7f0000000000u, 0x7f0000001000u, 0x7f0000009000u, ""}};
    emm_trace_geometry g = test_geometry();
    for (int compress = 0; compress <= 1; compress++) {
        emm_trace_options o = {compress, 1, mods, 2};
        emm_trace_writer *w = NULL;
        emm_error err;
        REQUIRE(emm_trace_writer_open_ex(path, test_arrays, 3, &g, &o, &w, &err) == EMM_OK);
        REQUIRE(emm_trace_write(w, recs, N, &err) == EMM_OK);
        REQUIRE(emm_trace_writer_close(w, &err) == EMM_OK);
        emm_trace_reader *r = NULL;
        REQUIRE(emm_trace_reader_open(path, &r, &err) == EMM_OK);
        const emm_trace_info *info = emm_trace_reader_info(r);
        CHECK(info->has_pc && info->nmodules == 2);
        CHECK(info->modules[0].bias == mods[0].bias && info->modules[0].lo == mods[0].lo &&
              info->modules[0].hi == mods[0].hi &&
              strcmp(info->modules[0].path, "/usr/bin/prog") == 0);
        CHECK(info->modules[1].lo == mods[1].lo && strcmp(info->modules[1].path, "") == 0);
        emm_trace_record *buf = malloc(N * sizeof *buf);
        size_t got = 0, k;
        while (emm_trace_read(r, buf + got, N - got, &k, &err) == EMM_OK && k > 0)
            got += k;
        CHECK(got == N);
        size_t bad = 0;
        for (size_t i = 0; i < got; i++)
            bad += !same_record(&buf[i], &recs[i]) || buf[i].pc != recs[i].pc;
        CHECKF(bad == 0, "%zu records differ", bad);
        free(buf);
        emm_trace_reader_close(r);
    }
    free(recs);
    remove(path);
}

/* A version 1 file (no module table, six columns) is still read; its
 * records have pc 0. Made from a version 2 file without pcs: the version
 * set to 1 and the empty module table cut out. */
static void test_version_1(void)
{
    const char *src = tpath(0, "v1_src"), *dst = tpath(1, "v1");
    make_small(src, 0, 10);
    size_t len;
    unsigned char *b = slurp(src, &len);
    const size_t mods = EMM_TRACE_HEADER_SIZE + 3 * EMM_TRACE_ARRAY_SIZE + 8 + 5 * 24 + 3 * 12 + 8;
    const size_t cut = EMM_TRACE_MODULES_HEADER + 8;
    REQUIRE(emm_le32(b + mods) == 0 && len > mods + cut);
    memmove(b + mods, b + mods + cut, len - mods - cut);
    emm_put_le32(b + EMM_TH_VERSION, 1);
    rehash(b, 0, EMM_TH_CHECKSUM);
    spit(dst, b, len - cut);
    emm_error err;
    emm_trace_reader *r = NULL;
    REQUIRE(emm_trace_reader_open(dst, &r, &err) == EMM_OK);
    const emm_trace_info *info = emm_trace_reader_info(r);
    CHECK(info->version == 1 && !info->has_pc && info->nmodules == 0);
    emm_trace_record buf[16];
    size_t got = 0;
    CHECK(emm_trace_read(r, buf, 16, &got, &err) == EMM_OK && got == 10);
    for (size_t i = 0; i < got; i++)
        CHECK(buf[i].pc == 0);
    emm_trace_reader_close(r);
    /* The pc flag is version 2's: in a version 1 header it is unknown. */
    emm_put_le32(b + EMM_TH_FLAGS, 2);
    rehash(b, 0, EMM_TH_CHECKSUM);
    spit(dst, b, len - cut);
    CHECK(read_all(dst, &err) == EMM_ERR_FORMAT && strstr(err.message, "unknown flags"));
    free(b);
    remove(src);
    remove(dst);
}

int main(void)
{
    test_hash();
    test_round_trip();
    test_no_geometry_no_arrays();
    test_rewind();
    test_streaming_memory();
    test_truncation();
    test_bit_flips();
    test_bad_magic_and_missing();
    test_future_version();
    test_bad_geometry();
    test_element_out_of_range();
    test_bad_block_content();
    test_writer_rejects();
    test_pcs_and_modules();
    test_version_1();
    return check_done();
}
