/* EMM_TAG's grammar (docs/design.md "The shim and the session", Tagging): which
 * allocations are mesh arrays and where the coordinates or vertex indices sit in each
 * record.
 *
 *   vertices:site=read_mesh,stride=80,xyz=8:f64;triangles:site=read_mesh,stride=28,vidx=4:i32
 *
 * Parsed here, below the shim, so `emm run` refuses a bad rule before the
 * program starts and the shim keeps only the matching (call stacks, ranks).
 * Messages quote at most EMM_CLIP characters of the text, so the explanation
 * always fits the one line. */
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "emm/config.h"
#include "error.h"
#include "parse.h"

/* Without min=, a rule looks at blocks of at least this many bytes (and at
 * least one record): the shim's fast path skips the unwinding for the small
 * blocks that make up most allocations. */
#define DEFAULT_MIN 4096u
static bool parse_field(const char *v, size_t len, bool coordinates, uint32_t *offset,
                        emm_scalar *type)
{
    char buf[64];
    if (len >= sizeof buf)
        return false;
    memcpy(buf, v, len);
    buf[len] = '\0';
    char *colon = strchr(buf, ':');
    if (!colon)
        return false;
    *colon = '\0';
    uint64_t off;
    if (!emm_parse_u64(buf, &off) || off > UINT32_MAX)
        return false;
    const char *t = colon + 1;
    if (coordinates && strcmp(t, "f32") == 0)
        *type = EMM_F32;
    else if (coordinates && strcmp(t, "f64") == 0)
        *type = EMM_F64;
    else if (!coordinates && strcmp(t, "i32") == 0)
        *type = EMM_I32;
    else if (!coordinates && strcmp(t, "u32") == 0)
        *type = EMM_U32;
    else if (!coordinates && strcmp(t, "i64") == 0)
        *type = EMM_I64;
    else if (!coordinates && strcmp(t, "u16") == 0)
        *type = EMM_U16;
    else
        return false;
    *offset = (uint32_t)off;
    return true;
}

static size_t scalar_size(emm_scalar t)
{
    return t == EMM_F64 || t == EMM_I64 ? 8 : t == EMM_U16 ? 2 : 4;
}

static bool is_key(const char *p, size_t kl, const char *key)
{
    return kl == strlen(key) && memcmp(p, key, kl) == 0;
}

/* The bytes a block must be a whole number of: a record, three column
 * entries, or with n= the whole block. */
static uint64_t rule_unit(const emm_tag_rule *r)
{
    if (r->shape != EMM_TAG_COLUMNS)
        return r->stride;
    return 3 * (uint64_t)r->stride * (r->n ? r->n : 1);
}

static uint64_t default_min(const emm_tag_rule *r)
{
    uint64_t u = rule_unit(r);
    return u > DEFAULT_MIN ? u : DEFAULT_MIN;
}

int emm_tag_rule_fits(const emm_tag_rule *r, uint64_t size)
{
    uint64_t u = rule_unit(r);
    return size > 0 && (r->shape == EMM_TAG_COLUMNS && r->n ? size == u : size % u == 0);
}

/* The scalars a record (an entry) holds from its offset: three in a row,
 * one of a column or of an axis block, a soup's nine. */
static unsigned rule_scalars(const emm_tag_rule *r)
{
    return r->shape == EMM_TAG_SOUP ? 9
           : r->shape == EMM_TAG_COLUMNS || r->shape == EMM_TAG_AXIS ||
                   emm_tag_shape_is_connectivity(r->shape)
               ? 1
               : 3;
}

/* A half-edge record's link keys, in emm_tag_rule.link[]'s order. */
static const char *const link_keys[EMM_TAG_LINKS] = {"next", "prev", "face", "opp"};

static int link_key(const char *p, size_t kl)
{
    for (int i = 0; i < EMM_TAG_LINKS; i++)
        if (is_key(p, kl, link_keys[i]))
            return i;
    return -1;
}

/* A link's value: OFFSET, or OFFSET:TYPE of the rule's type (given by to=,
 * before or after). */
static bool parse_link(const char *v, size_t len, uint32_t *offset, emm_scalar *type)
{
    const char *colon = memchr(v, ':', len);
    char buf[32];
    size_t n = colon ? (size_t)(colon - v) : len;
    uint64_t off;
    if (n == 0 || n >= sizeof buf)
        return false;
    memcpy(buf, v, n);
    buf[n] = '\0';
    if (!emm_parse_u64(buf, &off) || off >= UINT32_MAX)
        return false;
    *type = (emm_scalar)-1;
    if (colon) {
        uint32_t ignored;
        char field[48];
        int w = snprintf(field, sizeof field, "0%.*s", (int)(len - n), colon);
        if (w < 0 || (size_t)w >= sizeof field || !parse_field(field, strlen(field), false, &ignored, type))
            return false;
    }
    *offset = (uint32_t)off;
    return true;
}

/* The key of an axis rule: x=, y= or z=; -1 for another key. */
static int axis_key(const char *p, size_t kl)
{
    return kl != 1 ? -1 : *p == 'x' ? 0 : *p == 'y' ? 1 : *p == 'z' ? 2 : -1;
}

/* A site= naming a function by MODULE+0xOFFSET (what --list-sites prints
 * for a frame no symbol names) in the frames' spelling: lower-case hex, no
 * leading zeros. False when the text after "+0x" is not hex; true, and the
 * site untouched, for a function name. */
static bool module_offset_site(char *site)
{
    char *plus = strstr(site, "+0x");
    if (!plus)
        plus = strstr(site, "+0X");
    if (!plus)
        return true;
    char *hex = plus + 3;
    if (!*hex)
        return false;
    for (char *c = hex; *c; c++) {
        if (!((*c >= '0' && *c <= '9') || (*c >= 'a' && *c <= 'f') || (*c >= 'A' && *c <= 'F')))
            return false;
        if (*c >= 'A' && *c <= 'F')
            *c = (char)(*c - 'A' + 'a');
    }
    plus[2] = 'x';
    char *first = hex;
    while (first[0] == '0' && first[1])
        first++;
    memmove(hex, first, strlen(first) + 1);
    return plus != site;
}

/* One rule, text[0..len). */
static emm_status parse_rule(const char *text, size_t len, emm_tag_rule *r, emm_error *err)
{
    char q[EMM_CLIP + 1];
    memset(r, 0, sizeof *r);
    for (int i = 0; i < EMM_TAG_LINKS; i++)
        r->link[i] = EMM_TAG_NO_LINK;
    const char *colon = memchr(text, ':', len);
    if (!colon)
        return emm_fail(err, EMM_ERR_INVALID,
                        "rule '%s' has no KIND: (vertices:, triangles:, soup:, halfedges:, "
                        "faces: or vconn:)",
                        emm_clip(text, len, q));
    size_t klen = (size_t)(colon - text);
    if (is_key(text, klen, "vertices")) {
        r->kind = EMM_ARRAY_VERTICES;
    } else if (is_key(text, klen, "triangles")) {
        r->kind = EMM_ARRAY_TRIANGLES;
    } else if (is_key(text, klen, "soup")) {
        r->kind = EMM_ARRAY_TRIANGLES;
        r->shape = EMM_TAG_SOUP;
    } else if (is_key(text, klen, "halfedges")) {
        r->kind = EMM_ARRAY_TRIANGLES;
        r->shape = EMM_TAG_HALFEDGES;
    } else if (is_key(text, klen, "faces")) {
        r->kind = EMM_ARRAY_TRIANGLES;
        r->shape = EMM_TAG_FACES;
    } else if (is_key(text, klen, "vconn")) {
        r->kind = EMM_ARRAY_VERTICES;
        r->shape = EMM_TAG_VCONN;
    } else {
        return emm_fail(err, EMM_ERR_INVALID,
                        "unknown kind '%s' (expected vertices, triangles, soup, halfedges, "
                        "faces or vconn)",
                        emm_clip(text, klen, q));
    }
    bool conn = emm_tag_shape_is_connectivity(r->shape), he = r->shape == EMM_TAG_HALFEDGES;
    bool vertices = r->kind == EMM_ARRAY_VERTICES && !conn, soup = r->shape == EMM_TAG_SOUP;
    const char *field = soup ? "corners" : vertices ? "xyz" : he ? "to" : conn ? "he" : "vidx";
    const char *field_help = soup       ? "corners=OFFSET:f32|f64"
                             : vertices ? "xyz=OFFSET:f32|f64"
                             : he       ? "to=OFFSET:i32|u32|u16|i64"
                             : conn     ? "he=OFFSET:i32|u32|u16|i64"
                                        : "vidx=OFFSET:i32|u32|u16|i64";
    const char *kind_name = soup ? "soup" : vertices ? "vertices" : he ? "halfedges"
                            : r->shape == EMM_TAG_FACES ? "faces" : conn ? "vconn" : "triangles";
    emm_scalar link_type[EMM_TAG_LINKS];
    bool have_min = false, have_field = false, have_order = false;
    const char *p = colon + 1, *end = text + len;
    while (p < end) {
        const char *comma = memchr(p, ',', (size_t)(end - p));
        const char *e = comma ? comma : end;
        const char *eq = memchr(p, '=', (size_t)(e - p));
        size_t plen = (size_t)(e - p);
        if (!eq || eq == p)
            return emm_fail(err, EMM_ERR_INVALID, "'%s' is not key=value", emm_clip(p, plen, q));
        size_t kl = (size_t)(eq - p), vl = (size_t)(e - eq - 1);
        const char *v = eq + 1;
        char num[32] = "";
        uint64_t x = 0;
        bool numeric = is_key(p, kl, "min") || is_key(p, kl, "nth") ||
                       is_key(p, kl, "stride") || (is_key(p, kl, "n") && !soup && !conn);
        if (numeric) {
            if (vl == 0 || vl >= sizeof num)
                return emm_fail(err, EMM_ERR_INVALID, "'%s' needs a number", emm_clip(p, plen, q));
            memcpy(num, v, vl);
            num[vl] = '\0';
        }
        if (is_key(p, kl, "site")) {
            if (vl == 0 || vl >= EMM_TAG_SITE_MAX)
                return emm_fail(err, EMM_ERR_INVALID,
                                "'%s' needs a function name of 1 to %d characters",
                                emm_clip(p, plen, q), EMM_TAG_SITE_MAX - 1);
            memcpy(r->site, v, vl);
            r->site[vl] = '\0';
            if (!module_offset_site(r->site))
                return emm_fail(err, EMM_ERR_INVALID,
                                "'%s': expected MODULE+0xHEX (a function in a stripped object, "
                                "as --list-sites names it)",
                                emm_clip(p, plen, q));
        } else if (is_key(p, kl, "min")) {
            if (!emm_parse_size(num, &x))
                return emm_fail(err, EMM_ERR_INVALID,
                                "'%s' is not a size in bytes (K/M/G allowed)", emm_clip(p, plen, q));
            r->min = x;
            have_min = true;
        } else if (is_key(p, kl, "nth")) {
            if (!emm_parse_u64(num, &x) || x == 0)
                return emm_fail(err, EMM_ERR_INVALID, "'%s' is not a rank from 1",
                                emm_clip(p, plen, q));
            r->nth = x;
        } else if (is_key(p, kl, "stride")) {
            if (!emm_parse_size(num, &x) || x == 0 || x > UINT32_MAX)
                return emm_fail(err, EMM_ERR_INVALID, "'%s' is not a record size in bytes",
                                emm_clip(p, plen, q));
            r->stride = (uint32_t)x;
        } else if (he && link_key(p, kl) >= 0) {
            int k = link_key(p, kl);
            if (r->link[k] != EMM_TAG_NO_LINK)
                return emm_fail(err, EMM_ERR_INVALID, "'%s': %s= is given twice",
                                emm_clip(p, plen, q), link_keys[k]);
            if (!parse_link(v, vl, &r->link[k], &link_type[k]))
                return emm_fail(err, EMM_ERR_INVALID,
                                "'%s': expected %s=OFFSET or %s=OFFSET:i32|u32|u16|i64",
                                emm_clip(p, plen, q), link_keys[k], link_keys[k]);
        } else if (is_key(p, kl, "order") && !soup && !conn) {
            have_order = true;
            if (vl == 7 && memcmp(v, "records", 7) == 0)
                r->shape = EMM_TAG_RECORDS;
            else if (vl == 7 && memcmp(v, "columns", 7) == 0)
                r->shape = EMM_TAG_COLUMNS;
            else
                return emm_fail(err, EMM_ERR_INVALID, "'%s': expected order=records|columns",
                                emm_clip(p, plen, q));
        } else if (is_key(p, kl, "n") && !soup && !conn) {
            if (!emm_parse_u64(num, &x) || x == 0)
                return emm_fail(err, EMM_ERR_INVALID, "'%s' is not a count of records from 1",
                                emm_clip(p, plen, q));
            r->n = x;
        } else if (is_key(p, kl, field) || (vertices && axis_key(p, kl) >= 0)) {
            /* One field per rule: a record's three coordinates, or one
             * coordinate of every vertex (an axis block). */
            if (have_field)
                return emm_fail(err, EMM_ERR_INVALID,
                                "'%s': a rule has one of xyz=, x=, y=, z= (a block holding one "
                                "coordinate gets a rule of its own)",
                                emm_clip(p, plen, q));
            if (!parse_field(v, vl, vertices || soup, &r->offset, &r->type))
                return emm_fail(err, EMM_ERR_INVALID, "'%s': expected %.*s%s",
                                emm_clip(p, plen, q), (int)kl, p,
                                field_help + strlen(field));
            if (axis_key(p, kl) >= 0) {
                r->axis = (uint32_t)axis_key(p, kl);
                r->shape = EMM_TAG_AXIS;
            }
            have_field = true;
        } else {
            return emm_fail(err, EMM_ERR_INVALID, "unknown key in '%s' (%s rules take %s)",
                            emm_clip(p, plen, q), kind_name,
                            soup       ? "site, min, nth, stride, corners"
                            : vertices ? "site, min, nth, stride, order, n, xyz or x|y|z"
                            : he       ? "site, min, nth, stride, to, next, prev, face, opp"
                            : conn     ? "site, min, nth, stride, he"
                                       : "site, min, nth, stride, order, n, vidx");
        }
        p = comma ? comma + 1 : end;
    }
    if (!have_field)
        return emm_fail(err, EMM_ERR_INVALID, "rule '%s' needs %s", emm_clip(text, len, q),
                        field_help);
    if (he && (r->link[EMM_TAG_LINK_NEXT] == EMM_TAG_NO_LINK ||
               r->link[EMM_TAG_LINK_FACE] == EMM_TAG_NO_LINK))
        return emm_fail(err, EMM_ERR_INVALID,
                        "rule '%s' needs next=OFFSET and face=OFFSET (prev= and opp= are "
                        "optional: the opposite of half-edge h is then h ^ 1)",
                        emm_clip(text, len, q));
    for (int k = 0; he && k < EMM_TAG_LINKS; k++) {
        if (r->link[k] == EMM_TAG_NO_LINK)
            continue;
        if (link_type[k] != (emm_scalar)-1 && link_type[k] != r->type)
            return emm_fail(err, EMM_ERR_INVALID,
                            "rule '%s': %s= has another type than to= (a record's indices "
                            "are of one type)",
                            emm_clip(text, len, q), link_keys[k]);
        if (r->stride && (uint64_t)r->link[k] + scalar_size(r->type) > r->stride)
            return emm_fail(err, EMM_ERR_INVALID, "rule '%s': %s= does not fit in stride bytes",
                            emm_clip(text, len, q), link_keys[k]);
    }
    bool columns = r->shape == EMM_TAG_COLUMNS, axis = r->shape == EMM_TAG_AXIS;
    if (axis && have_order)
        return emm_fail(err, EMM_ERR_INVALID,
                        "rule '%s': an axis block (x=, y=, z=) holds one coordinate of every "
                        "vertex: order= does not apply",
                        emm_clip(text, len, q));
    if (r->n && !columns)
        return emm_fail(err, EMM_ERR_INVALID,
                        "rule '%s': n= counts the entries of a column: it needs order=columns",
                        emm_clip(text, len, q));
    /* A column's or an axis block's entries are its scalars, unless
     * stride= says otherwise. */
    if (r->stride == 0 && (columns || axis))
        r->stride = (uint32_t)scalar_size(r->type);
    if (r->stride == 0)
        return emm_fail(err, EMM_ERR_INVALID, "rule '%s' needs stride=BYTES", emm_clip(text, len, q));
    if ((uint64_t)r->offset + rule_scalars(r) * scalar_size(r->type) > r->stride)
        return emm_fail(err, EMM_ERR_INVALID,
                        soup      ? "rule '%s': the nine corner coordinates do not fit in stride bytes"
                        : columns ? "rule '%s': a column's scalar does not fit in stride bytes"
                        : axis    ? "rule '%s': the coordinate does not fit in stride bytes"
                        : conn    ? "rule '%s': the half-edge index does not fit in stride bytes"
                                  : "rule '%s': the three fields do not fit in stride bytes",
                        emm_clip(text, len, q));
    if (r->n > UINT64_MAX / 3 / r->stride)
        return emm_fail(err, EMM_ERR_INVALID, "rule '%s': n= is too large", emm_clip(text, len, q));
    if (!have_min)
        r->min = default_min(r);
    if (r->min < rule_unit(r))
        r->min = rule_unit(r);
    return EMM_OK;
}

/* Axis rules come in sets: each needs an x rule and a y rule of its
 * stride and type (itself counts), which the session joins with it into
 * one mesh's vertices; z is optional. */
static emm_status check_axes(const emm_tag_rules *rs, emm_error *err)
{
    for (size_t i = 0; i < rs->n; i++) {
        const emm_tag_rule *r = &rs->rule[i];
        if (r->shape != EMM_TAG_AXIS)
            continue;
        for (uint32_t need = 0; need < 2; need++) {
            bool found = false;
            for (size_t j = 0; j < rs->n && !found; j++)
                found = rs->rule[j].shape == EMM_TAG_AXIS && rs->rule[j].axis == need &&
                        rs->rule[j].stride == r->stride && rs->rule[j].type == r->type;
            if (found)
                continue;
            char text[256], q[EMM_CLIP + 1];
            emm_tag_rule_format(r, text, sizeof text);
            return emm_fail(err, EMM_ERR_INVALID,
                            "rule %zu '%s' is one coordinate of the vertices, but no rule gives "
                            "their %c block with stride=%u and %s (a mesh's vertices need an x "
                            "and a y rule; z is optional)",
                            i + 1, emm_clip(text, strlen(text), q), "xy"[need], r->stride,
                            r->type == EMM_F32 ? "f32" : "f64");
        }
    }
    return EMM_OK;
}

void emm_tag_rules_free(emm_tag_rules *rs)
{
    free(rs->rule);
    rs->rule = NULL;
    rs->n = 0;
}

emm_status emm_tag_rule_parse(const char *text, emm_tag_rule *out, emm_error *err)
{
    return parse_rule(text, strlen(text), out, err);
}

/* OpenMesh's ArrayKernel (OpenMesh 8 and 9, the default TriMesh/PolyMesh
 * traits: Vec3f points, half-edges with prev): the points property
 * (12 bytes), vertices_ (one outgoing half-edge), edges_ (two 16-byte
 * half-edges {face, to, next, prev}, so the block is the half-edge array
 * with h ^ 1 the opposite) and faces_ (one half-edge). A reader that knows
 * the counts (OFF, PLY, STL) reserves them in ArrayKernel::reserve, in that
 * order (vertices_, edges_, faces_, then the properties); one that does not
 * (OBJ) grows them, the points and vertices_ under the importer's
 * add_vertex (points first past 4 KiB), the edges under new_edge, the faces
 * under add_face (after the edges it makes); a program that builds or
 * refines a mesh (a subdivider) grows them under PolyMeshT::new_vertex
 * (the points are its first vertex property), new_edge and new_face. Each
 * site= but that of the growing points is the innermost
 * frame (^): the properties that grow beside them (under new_edge, under
 * ArrayKernel::reserve) are other blocks. */
static const char openmesh_preset[] =
    "vertices:site=^PropertyT::reserve,stride=12,xyz=0:f32;"
    "vconn:site=^ArrayKernel::reserve,stride=4,he=0:i32;"
    "halfedges:site=^ArrayKernel::reserve,stride=16,to=4:i32,next=8,prev=12,face=0;"
    "faces:site=^ArrayKernel::reserve,stride=4,he=0:i32;"
    "vertices:site=^ImporterT::add_vertex,stride=12,xyz=0:f32;"
    "vconn:site=^ImporterT::add_vertex,stride=4,he=0:i32;"
    "halfedges:site=^ArrayKernel::new_edge,stride=16,to=4:i32,next=8,prev=12,face=0;"
    "faces:site=^PolyConnectivity::add_face,stride=4,he=0:i32;"
    "vertices:site=PolyMeshT::new_vertex,stride=12,xyz=0:f32;"
    "vconn:site=^PolyMeshT::new_vertex,stride=4,he=0:i32;"
    "faces:site=^ArrayKernel::new_face,stride=4,he=0:i32";

const char *emm_tag_preset(const char *name)
{
    return strcmp(name, "openmesh") == 0 ? openmesh_preset : NULL;
}

emm_status emm_tag_rules_parse(const char *text, emm_tag_rules *out, emm_error *err)
{
    const char *preset = emm_tag_preset(text);
    if (preset) {
        emm_status st = emm_tag_rules_parse(preset, out, err);
        for (size_t i = 0; st == EMM_OK && i < out->n; i++)
            out->rule[i].alternative = 1;
        return st;
    }
    emm_tag_rules rs = {0, NULL};
    size_t cap = 0;
    emm_status st = EMM_OK;
    const char *p = text;
    while (*p && st == EMM_OK) {
        const char *semi = strchr(p, ';');
        size_t len = semi ? (size_t)(semi - p) : strlen(p);
        if (len > 0) {
            /* A rule is at least a few bytes of text: the rules take a
             * small multiple of the text's size. */
            if (rs.n == cap) {
                size_t ncap = cap ? 2 * cap : 4;
                emm_tag_rule *r = realloc(rs.rule, ncap * sizeof *r);
                if (!r) {
                    st = emm_fail(err, EMM_ERR_NOMEM, "out of memory for %zu rules", ncap);
                    break;
                }
                rs.rule = r;
                cap = ncap;
            }
            st = parse_rule(p, len, &rs.rule[rs.n], err);
            if (st == EMM_OK)
                rs.n++;
        }
        p += len + (semi ? 1 : 0);
    }
    if (st == EMM_OK && rs.n == 0)
        st = emm_fail(err, EMM_ERR_INVALID,
                      "expected rules KIND:key=value,... split by ';' (see emm run --help)");
    if (st == EMM_OK)
        st = check_axes(&rs, err);
    if (st != EMM_OK) {
        emm_tag_rules_free(&rs);
        return st;
    }
    *out = rs;
    return EMM_OK;
}

const char *emm_scalar_name(emm_scalar t)
{
    switch (t) {
    case EMM_F32: return "f32";
    case EMM_F64: return "f64";
    case EMM_I32: return "i32";
    case EMM_U32: return "u32";
    case EMM_I64: return "i64";
    case EMM_U16: return "u16";
    default: return "?";
    }
}

void emm_tag_rule_describe(const emm_tag_rule *r, size_t index, const void *base,
                           uint64_t bytes, emm_array_desc *d, char *origin_buf, size_t cap)
{
    char text[512];
    emm_tag_rule_format(r, text, sizeof text);
    snprintf(origin_buf, cap, "EMM_TAG rule %zu (%s)", index + 1, text);
    *d = (emm_array_desc){.kind = r->kind,
                          .shape = r->shape,
                          .axis = r->shape == EMM_TAG_AXIS ? (int)r->axis : -1,
                          .base = base,
                          .count = r->stride ? bytes / r->stride : 0,
                          .stride = r->stride,
                          .offset = r->offset,
                          .type = r->type,
                          .rule = (unsigned)(index + 1),
                          .origin = origin_buf};
    memcpy(d->link, r->link, sizeof d->link);
}

/* A connectivity rule as EMM_TAG spells it. */
static void format_connectivity(const emm_tag_rule *r, const char *selectors, char *out,
                                size_t cap)
{
    bool he = r->shape == EMM_TAG_HALFEDGES;
    char links[96] = "";
    size_t used = 0;
    for (int k = 0; he && k < EMM_TAG_LINKS; k++)
        if (r->link[k] != EMM_TAG_NO_LINK && used < sizeof links) {
            int w = snprintf(links + used, sizeof links - used, ",%s=%u", link_keys[k],
                             r->link[k]);
            if (w > 0)
                used += (size_t)w;
        }
    snprintf(out, cap, "%s:%sstride=%u,%s=%u:%s%s",
             he ? "halfedges" : r->shape == EMM_TAG_FACES ? "faces" : "vconn", selectors,
             r->stride, he ? "to" : "he", r->offset, emm_scalar_name(r->type), links);
}

void emm_tag_rule_format(const emm_tag_rule *r, char *out, size_t cap)
{
    bool vertices = r->kind == EMM_ARRAY_VERTICES, soup = r->shape == EMM_TAG_SOUP;
    char site[EMM_TAG_SITE_MAX + 8] = "", nth[32] = "", min[32] = "", order[48] = "";
    if (r->site[0])
        snprintf(site, sizeof site, "site=%s,", r->site);
    if (r->nth)
        snprintf(nth, sizeof nth, "nth=%llu,", (unsigned long long)r->nth);
    if (r->min != default_min(r))
        snprintf(min, sizeof min, "min=%llu,", (unsigned long long)r->min);
    if (r->shape == EMM_TAG_COLUMNS && r->n)
        snprintf(order, sizeof order, "order=columns,n=%llu,", (unsigned long long)r->n);
    else if (r->shape == EMM_TAG_COLUMNS)
        snprintf(order, sizeof order, "order=columns,");
    if (emm_tag_shape_is_connectivity(r->shape)) {
        char sel[EMM_TAG_SITE_MAX + 80];
        snprintf(sel, sizeof sel, "%s%s%s", site, min, nth);
        format_connectivity(r, sel, out, cap);
        return;
    }
    static const char *const axes[] = {"x", "y", "z"};
    snprintf(out, cap, "%s:%s%s%s%sstride=%u,%s=%u:%s",
             soup ? "soup" : vertices ? "vertices" : "triangles", site, min, nth, order,
             r->stride,
             soup                          ? "corners"
             : r->shape == EMM_TAG_AXIS    ? axes[r->axis < 3 ? r->axis : 0]
             : vertices                    ? "xyz"
                                           : "vidx",
             r->offset, emm_scalar_name(r->type));
}

void emm_tag_rules_help(FILE *out)
{
    fprintf(out,
            "EMM_TAG rules are split by ';', each KIND:key=value,... with KIND vertices,\n"
            "triangles, soup, halfedges, faces or vconn. Selectors: site=FUNCTION (a\n"
            "function on the allocation's stack, looking past allocator and C++\n"
            "standard-library frames such as std::vector's; site=^FUNCTION: the innermost\n"
            "of the program's frames only; a function no symbol names, in a stripped\n"
            "binary, is MODULE+0xOFFSET, as --list-sites prints it: the object's file name\n"
            "and the function's offset from its load base), min=BYTES (K/M/G; default max(one record, 4K)), nth=N (the Nth\n"
            "block the other selectors select, from 1). Record: stride=BYTES (required;\n"
            "optional with order=columns or an axis key), xyz=OFFSET:f32|f64 (vertices),\n"
            "vidx=OFFSET:i32|u32|u16|i64 (triangles). Count = block size / stride; a block\n"
            "must be a whole number of records; no rule selects a block the C library\n"
            "allocates for itself (a FILE's buffer). A rule with site= follows the first\n"
            "allocation call in that function it selects (a growing std::vector\n"
            "reallocates from that same call); the function's other allocations go to\n"
            "later rules, so list the rules in the order the program allocates the arrays.\n"
            "Column-major (libigl/Eigen V and F): order=columns (default order=records)\n"
            "says the block holds n x's, then n y's, then n z's (for triangles n first\n"
            "corners, then n second, then n third), each entry stride bytes (default: the\n"
            "scalar's size) with its scalar at OFFSET; an access to any column is that\n"
            "element's. n=N (optional) says how many: a block that is not 3*N*stride bytes\n"
            "is not tagged. E.g. vertices:site=load,order=columns,xyz=0:f64;\n"
            "triangles:site=load,order=columns,vidx=0:i32.\n"
            "Structure of arrays (x at one base, y at another): a vertices rule with\n"
            "x=OFFSET:f32|f64, y=... or z=... instead of xyz= selects a block holding that\n"
            "coordinate of every vertex, each entry stride bytes (default: the scalar's\n"
            "size). One rule per block, e.g. vertices:site=load,x=0:f32;\n"
            "vertices:site=load,y=0:f32;vertices:site=load,z=0:f32 (the site's blocks in\n"
            "the order it allocates them); x and y are required, z optional (0 without\n"
            "it). Blocks of one count, stride and type are one mesh's vertices: element i\n"
            "of any of them is vertex i.\n"
            "Triangle soup (STL facets): soup:stride=BYTES,corners=OFFSET:f32|f64, each\n"
            "record a triangle whose three corners are nine coordinates in a row at OFFSET\n"
            "(binary STL: soup:stride=50,corners=12:f32); corners at exactly the same\n"
            "position are one vertex. An access anywhere in a record is its triangle's.\n"
            "Half-edge meshes (OpenMesh, CGAL Surface_mesh, PMP): halfedges:stride=BYTES,\n"
            "to=OFFSET:i32|u32|u16|i64,next=OFFSET,face=OFFSET[,prev=OFFSET][,opp=OFFSET],\n"
            "each record a half-edge (without opp= the opposite of h is h ^ 1, a face of -1\n"
            "a boundary); faces:stride=BYTES,he=OFFSET:TYPE, a face's half-edge; vconn:\n"
            "stride=BYTES,he=OFFSET:TYPE, a vertex's half-edge. A face's corners\n"
            "are the to-vertices of its half-edge cycle, which must close (a polygon is\n"
            "a fan of triangles); each face and its cycle's half-edges are placed in its\n"
            "triangles' cells, a vertex's vconn record with its position. --tag openmesh\n"
            "(EMM_TAG=openmesh) is the set for OpenMesh's ArrayKernel.\n");
}

/* ---- call sites ------------------------------------------------------------ */

/* Reads one <length><identifier> of the Itanium mangling at *p. */
static bool mangled_id(const char **p, const char **id, size_t *len)
{
    size_t n = 0;
    if (**p < '0' || **p > '9')
        return false;
    while (**p >= '0' && **p <= '9')
        n = n * 10 + (size_t)(*(*p)++ - '0');
    if (n == 0 || strnlen(*p, n) < n)
        return false;
    *id = *p;
    *len = n;
    *p += n;
    return true;
}

void emm_tag_site_name(const char *symbol, char *out, size_t cap)
{
    char buf[1024];
    snprintf(buf, sizeof buf, "%s", symbol);
    char *dot = strchr(buf, '.');
    if (dot && dot != buf)
        *dot = '\0';
    const char *p = buf, *id = NULL;
    size_t len = 0;
    if (p[0] == '_' && p[1] == 'Z') {
        p += 2;
        if (*p == 'L')
            p++;
        if (*p == 'N') {
            p++;
            while (*p == 'K' || *p == 'V' || *p == 'r')
                p++;
            if (p[0] == 'S' && p[1] == 't')
                p += 2;
            const char *cid;
            size_t clen;
            while (mangled_id(&p, &cid, &clen)) {
                id = cid;
                len = clen;
            }
        } else {
            mangled_id(&p, &id, &len);
        }
    }
    if (cap == 0)
        return;
    if (id && len < cap) {
        memcpy(out, id, len);
        out[len] = '\0';
    } else {
        /* Too long for any site= (EMM_TAG_SITE_MAX): cut, it will match nothing. */
        size_t n = strnlen(buf, cap - 1);
        memcpy(out, buf, n);
        out[n] = '\0';
    }
}

int emm_tag_site_is_library(const char *symbol, const char *object)
{
    static const char *const prefixes[] = {"_ZNSt", "_ZNKSt", "_ZSt", "_Znw", "_Zna",
                                           "_ZN9__gnu_cxx", "_ZNK9__gnu_cxx", "__libc_"};
    /* The shim is vgpreload_emm-amd64-linux.so when Valgrind preloads it. */
    static const char *const libs[] = {"libc.so", "libstdc++.so", "libgcc_s.so", "ld-linux",
                                       "libemmshim.so", "libunwind.so", "vgpreload_"};
    if (symbol)
        for (size_t i = 0; i < sizeof prefixes / sizeof *prefixes; i++)
            if (strncmp(symbol, prefixes[i], strlen(prefixes[i])) == 0)
                return 1;
    if (!object)
        return 0;
    const char *base = strrchr(object, '/');
    base = base ? base + 1 : object;
    for (size_t i = 0; i < sizeof libs / sizeof *libs; i++)
        if (strncmp(base, libs[i], strlen(libs[i])) == 0)
            return 1;
    return 0;
}

/* ---- site names from demangled symbols, and the unmatched rules --------- */

void emm_tag_site_names(const char *symbol, const char *demangled, char *name, size_t ncap,
                        char *qualified, size_t qcap)
{
    if (ncap == 0 || qcap == 0)
        return;
    if (!demangled) {
        emm_tag_site_name(symbol, name, ncap);
        snprintf(qualified, qcap, "%s", name);
        return;
    }
    /* The function's part: up to its parameter list, the last '(' at the top
     * level, after the return type a template function's name carries. */
    char buf[1024];
    snprintf(buf, sizeof buf, "%s", demangled);
    char *clone = strstr(buf, " [clone");
    if (clone)
        *clone = '\0';
    int depth = 0;
    size_t len = strlen(buf), start = 0, paren = len;
    for (size_t i = 0; i < len; i++) {
        char c = buf[i];
        if (c == '<')
            depth++;
        else if (c == '>' && depth > 0)
            depth--;
        else if (c == '(' && depth == 0) {
            paren = i;
            break;
        } else if (c == ' ' && depth == 0)
            start = i + 1;
    }
    /* Template arguments dropped. */
    char q[1024];
    size_t n = 0;
    depth = 0;
    for (size_t i = start; i < paren && n + 1 < sizeof q; i++) {
        char c = buf[i];
        if (c == '<')
            depth++;
        else if (c == '>' && depth > 0)
            depth--;
        else if (depth == 0)
            q[n++] = c;
    }
    q[n] = '\0';
    snprintf(qualified, qcap, "%s", q);
    const char *last = q, *sep;
    while ((sep = strstr(last, "::")))
        last = sep + 2;
    snprintf(name, ncap, "%s", last);
}

int emm_tag_site_matches(const char *site, const char *name, const char *qualified)
{
    if (strcmp(site, name) == 0 || strcmp(site, qualified) == 0)
        return 1;
    size_t ls = strlen(site), lq = strlen(qualified);
    return ls + 2 <= lq && strcmp(qualified + lq - ls, site) == 0 &&
           memcmp(qualified + lq - ls - 2, "::", 2) == 0;
}

/* The longest common substring of a and b, in characters (short names). */
static size_t common(const char *a, const char *b)
{
    size_t best = 0, la = strlen(a), lb = strlen(b);
    for (size_t i = 0; i < la; i++)
        for (size_t j = 0; j < lb; j++) {
            size_t k = 0;
            while (i + k < la && j + k < lb && a[i + k] == b[j + k])
                k++;
            if (k > best)
                best = k;
        }
    return best;
}

/* What is wrong with a block of `size` bytes for rule r, as ", not whole
 * records", or "" when it fits. */
static const char *misfit(const emm_tag_rule *r, uint64_t size, char *buf, size_t cap)
{
    if (emm_tag_rule_fits(r, size))
        return "";
    if (r->shape != EMM_TAG_COLUMNS)
        return ", not whole records";
    if (r->n)
        snprintf(buf, cap, ", not 3 columns of n=%llu entries of %u bytes (%llu bytes)",
                 (unsigned long long)r->n, r->stride, (unsigned long long)rule_unit(r));
    else
        snprintf(buf, cap, ", not 3 columns of whole %u-byte entries", r->stride);
    return buf;
}

void emm_tag_unmatched_message(const emm_tag_rule *r, size_t index,
                               const emm_tag_site_seen *seen, size_t nseen, char *out,
                               size_t cap)
{
    char text[256];
    emm_tag_rule_format(r, text, sizeof text);
    int w = snprintf(out, cap, "EMM_TAG rule %zu (%s) matched no allocation", index + 1, text);
    if (w < 0 || (size_t)w >= cap)
        return;
    size_t used = (size_t)w;
    if (nseen == 0) {
        snprintf(out + used, cap - used,
                 r->site[0] ? "; no allocation of %llu bytes or more was seen (min=)"
                            : "; no block of %llu bytes or more was allocated",
                 (unsigned long long)r->min);
        return;
    }
    bool taken[64] = {false};
    char why[96];
    for (int k = 0; k < 3 && (size_t)k < nseen; k++) {
        size_t best = SIZE_MAX;
        long best_score = -1;
        for (size_t i = 0; i < nseen && i < 64; i++) {
            if (taken[i])
                continue;
            bool whole = emm_tag_rule_fits(r, seen[i].largest);
            long name = (long)(r->site[0] ? common(r->site, seen[i].name) : 0);
            long score = (name < 255 ? name : 255) * (1L << 40) + (whole ? 1L << 32 : 0) +
                         (long)(seen[i].largest >> 8 < (1u << 31) ? seen[i].largest >> 8
                                                                 : (1u << 31));
            if (score > best_score) {
                best_score = score;
                best = i;
            }
        }
        if (best == SIZE_MAX)
            break;
        taken[best] = true;
        w = snprintf(out + used, cap - used, "%s%s (%llu block%s, up to %llu bytes%s)",
                     k == 0 ? "; sites seen, closest first: " : ", ", seen[best].name,
                     (unsigned long long)seen[best].count, seen[best].count == 1 ? "" : "s",
                     (unsigned long long)seen[best].largest,
                     misfit(r, seen[best].largest, why, sizeof why));
        if (w < 0 || (size_t)w >= cap - used)
            return;
        used += (size_t)w;
    }
    if (r->site[0])
        snprintf(out + used, cap - used,
                 " (a function the compiler inlined is no frame of the stack: name its caller)");
}
