/* Strict number parsing shared by the command line, machine files, tables
 * and the shim's environment (sizes accept K/M/G and are checked
 * for overflow). */
#include "parse.h"

#include <ctype.h>
#include <stdio.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static bool parse_digits(const char *s, const char **end, uint64_t *out)
{
    uint64_t v = 0;
    const char *p = s;
    if (!isdigit((unsigned char)*p))
        return false;
    for (; isdigit((unsigned char)*p); p++) {
        uint64_t d = (uint64_t)(*p - '0');
        if (v > (UINT64_MAX - d) / 10)
            return false;
        v = v * 10 + d;
    }
    *end = p;
    *out = v;
    return true;
}

bool emm_parse_u64(const char *s, uint64_t *out)
{
    const char *end;
    uint64_t v;
    if (!s || !parse_digits(s, &end, &v) || *end != '\0')
        return false;
    *out = v;
    return true;
}

bool emm_parse_size(const char *s, uint64_t *out)
{
    const char *end;
    uint64_t v, mul = 1;
    if (!s || !parse_digits(s, &end, &v))
        return false;
    switch (*end) {
    case 'k': case 'K': mul = 1ull << 10; end++; break;
    case 'm': case 'M': mul = 1ull << 20; end++; break;
    case 'g': case 'G': mul = 1ull << 30; end++; break;
    default: break;
    }
    if (mul != 1 && *end == 'i')
        end++;
    if (*end == 'B')
        end++;
    if (*end != '\0')
        return false;
    if (v > UINT64_MAX / mul)
        return false;
    *out = v * mul;
    return true;
}

bool emm_parse_double(const char *s, double *out)
{
    char *end;
    double v;
    if (!s || *s == '\0' || isspace((unsigned char)*s))
        return false;
    errno = 0;
    v = strtod(s, &end);
    if (*end != '\0' || errno == ERANGE || !isfinite(v))
        return false;
    *out = v;
    return true;
}

const char *emm_grouped(uint64_t v, char buf[32])
{
    char tmp[32];
    int n = snprintf(tmp, sizeof tmp, "%llu", (unsigned long long)v);
    int o = 0;
    for (int i = 0; i < n; i++) {
        if (i > 0 && (n - i) % 3 == 0)
            buf[o++] = ',';
        buf[o++] = tmp[i];
    }
    buf[o] = '\0';
    return buf;
}

const char *emm_clip(const char *text, size_t len, char buf[EMM_CLIP + 1])
{
    if (len > EMM_CLIP) {
        memcpy(buf, text, EMM_CLIP - 3);
        memcpy(buf + EMM_CLIP - 3, "...", 4);
    } else {
        memcpy(buf, text, len);
        buf[len] = '\0';
    }
    emm_printable(buf);
    return buf;
}

void emm_printable(char *s)
{
    /* A newline or another control character in a value would split the
     * one-line message, or hide part of it on a terminal. */
    for (; *s; s++)
        if ((unsigned char)*s < 0x20 || *s == 0x7f)
            *s = '?';
}
