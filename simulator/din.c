/* Dinero IV's din text into an address-only trace (docs/trace-format.md
 * "din"): one "LABEL ADDRESS" line per reference, both hex. Lines are read
 * into a fixed buffer, so an input without newlines (/dev/zero, a binary
 * file, an endless pipe) ends in an error after EMM_DIN_LINE_MAX bytes
 * instead of growing a line without bound. */
#include "emm/trace.h"

#include "error.h"

#include <errno.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DIN_BATCH 4096

static int hexval(int c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

static bool is_blank(int c)
{
    return c == ' ' || c == '\t' || c == '\r';
}

/* A hex number with an optional 0x; the position after it, or NULL (with
 * *why set) when there is none or it overflows 64 bits. */
static const char *parse_hex(const char *p, uint64_t *out, const char **why)
{
    if (p[0] == '0' && (p[1] == 'x' || p[1] == 'X') && hexval(p[2]) >= 0)
        p += 2;
    if (hexval(*p) < 0) {
        *why = "expected a hex number";
        return NULL;
    }
    uint64_t v = 0;
    for (int d; (d = hexval(*p)) >= 0; p++) {
        if (v >> 60) {
            *why = "number does not fit in 64 bits";
            return NULL;
        }
        v = v << 4 | (uint64_t)d;
    }
    *out = v;
    return p;
}

/* The next line into buf (without its newline, NUL-terminated): 1, 0 at
 * the end of the input, -1 for a line too long, -2 for a NUL byte. */
static int read_line(FILE *in, char *buf, size_t *len)
{
    size_t n = 0;
    int c;
    while ((c = getc_unlocked(in)) != EOF && c != '\n') {
        if (c == '\0')
            return -2;
        if (n == EMM_DIN_LINE_MAX)
            return -1;
        buf[n++] = (char)c;
    }
    buf[n] = '\0';
    *len = n;
    return c == EOF && n == 0 ? 0 : 1;
}

/* One line into *rec; 1 for a record, 0 for a line that carries none, or
 * an error. */
static emm_status parse_line(const char *line, const char *where, uint32_t fixed, emm_trace_record *rec,
                             bool *skip, emm_error *err)
{
    const char *p = line, *why = NULL;
    uint64_t label, addr;
    *skip = true;
    while (is_blank(*p))
        p++;
    if (*p == '\0')
        return EMM_OK; /* blank lines carry nothing */
    if (!(p = parse_hex(p, &label, &why)))
        return emm_fail(err, EMM_ERR_FORMAT, "%s: label: %s", where, why);
    if (!is_blank(*p))
        return emm_fail(err, EMM_ERR_FORMAT, "%s: %s", where,
                        *p == '\0' ? "no address after the label" : "the label is not a hex number");
    while (is_blank(*p))
        p++;
    if (!(p = parse_hex(p, &addr, &why)))
        return emm_fail(err, EMM_ERR_FORMAT, "%s: address: %s", where, why);
    if (!is_blank(*p) && *p != '\0')
        return emm_fail(err, EMM_ERR_FORMAT, "%s: the address is not a hex number", where);
    if (label == 2)
        return EMM_OK; /* an instruction fetch */
    if (label > 1)
        return emm_fail(err, EMM_ERR_FORMAT,
                        "%s: label %llu is not supported (0 read, 1 write, 2 instruction fetch)", where,
                        (unsigned long long)label);
    uint32_t bytes = fixed ? fixed : (uint32_t)(4 - (addr & 3));
    if (addr > UINT64_MAX - (bytes - 1))
        return emm_fail(err, EMM_ERR_RANGE,
                        "%s: an access of %u bytes at 0x%llx runs past the end of the 64-bit address space",
                        where, bytes, (unsigned long long)addr);
    *rec = (emm_trace_record){ .element = addr, .bytes = bytes, .write = (uint8_t)label };
    *skip = false;
    return EMM_OK;
}

emm_status emm_din_import(FILE *in, const char *name, uint32_t bytes, emm_trace_writer *w,
                          emm_din_counts *counts, emm_error *err)
{
    if (bytes > EMM_TRACE_MAX_ACCESS_BYTES)
        return emm_fail(err, EMM_ERR_INVALID, "%s: %u bytes per access (at most %u)", name, bytes,
                        EMM_TRACE_MAX_ACCESS_BYTES);
    *counts = (emm_din_counts){ 0 };
    char *line = malloc(EMM_DIN_LINE_MAX + 1);
    emm_trace_record *buf = malloc(DIN_BATCH * sizeof *buf);
    emm_status st = line && buf ? EMM_OK : emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", name);
    size_t nbuf = 0, len;
    int got;
    while (st == EMM_OK && (got = read_line(in, line, &len)) != 0) {
        char where[600];
        counts->lines++;
        snprintf(where, sizeof where, "%s:%llu", name, (unsigned long long)counts->lines);
        if (got == -1) {
            st = emm_fail(err, EMM_ERR_FORMAT, "%s: line too long (more than %d bytes)", where,
                          EMM_DIN_LINE_MAX);
            break;
        }
        if (got == -2) {
            st = emm_fail(err, EMM_ERR_FORMAT, "%s: NUL byte in the line (not din text)", where);
            break;
        }
        bool skip;
        if ((st = parse_line(line, where, bytes, &buf[nbuf], &skip, err)) != EMM_OK)
            break;
        if (skip) {
            counts->skipped += line[strspn(line, " \t\r")] != '\0';
            continue;
        }
        counts->accesses++;
        if (++nbuf == DIN_BATCH) {
            st = emm_trace_write(w, buf, nbuf, err);
            nbuf = 0;
        }
    }
    if (st == EMM_OK && ferror(in))
        st = emm_fail(err, EMM_ERR_IO, "%s: cannot read: %s", name, strerror(errno));
    if (st == EMM_OK && nbuf > 0)
        st = emm_trace_write(w, buf, nbuf, err);
    free(line);
    free(buf);
    return st;
}
