/* EMM_TAG's names and messages (core/tag_rules.c): the names a frame
 * answers to (a method of a class template by its own name, issue 14),
 * site= matching, a rule written back as it is spelled, u16 indices, and
 * the line a rule that matched nothing gets; column-major and soup rules,
 * and axis rules (x=, y=, z=: structure of arrays). */
#include <string.h>

#include <stdbool.h>

#include "check.h"
#include "emm/config.h"

static void names(const char *sym, const char *dm, const char *want_name, const char *want_qual)
{
    char n[EMM_TAG_SITE_MAX], q[512];
    emm_tag_site_names(sym, dm, n, sizeof n, q, sizeof q);
    CHECKF(strcmp(n, want_name) == 0, "%s: name '%s', want '%s'", sym, n, want_name);
    CHECKF(strcmp(q, want_qual) == 0, "%s: qualified '%s', want '%s'", sym, q, want_qual);
}

/* Whether two parses made the same rules. */
static bool same_rules(const emm_tag_rules *a, const emm_tag_rules *b)
{
    return a->n == b->n && memcmp(a->rule, b->rule, a->n * sizeof *a->rule) == 0;
}

/* text parses, is written back as `want` (NULL: as text), and that parses
 * to the same rule. */
static void round_trip(const char *text, const char *want, emm_tag_rule *out)
{
    emm_tag_rules rs, again;
    emm_error err;
    char back[256];
    if (emm_tag_rules_parse(text, &rs, &err) != EMM_OK) {
        CHECKF(0, "%s: %s", text, err.message);
        return;
    }
    emm_tag_rule_format(&rs.rule[0], back, sizeof back);
    CHECKF(strcmp(back, want ? want : text) == 0, "%s: written back as %s", text, back);
    REQUIRE(emm_tag_rules_parse(back, &again, &err) == EMM_OK);
    CHECKF(same_rules(&rs, &again), "%s: %s parses to another rule", text, back);
    *out = rs.rule[0];
    emm_tag_rules_free(&rs);
    emm_tag_rules_free(&again);
}

/* text is refused with a message holding `want`. */
static void refused(const char *text, const char *want)
{
    emm_tag_rules rs;
    emm_error err;
    CHECKF(emm_tag_rules_parse(text, &rs, &err) != EMM_OK, "%s: accepted", text);
    CHECKF(strstr(err.message, want) != NULL, "%s: '%s' lacks '%s'", text, err.message, want);
}

/* Issue 14 item 5: column-major blocks (order=columns, n=) and triangle
 * soups (soup:, corners=), parsed, written back, and the blocks they fit. */
static void shapes(void)
{
    emm_tag_rule r = {0};
    /* Eigen's V: the stride defaults to the scalar's size. */
    round_trip("vertices:site=load,order=columns,xyz=0:f64",
               "vertices:site=load,order=columns,stride=8,xyz=0:f64", &r);
    CHECK(r.kind == EMM_ARRAY_VERTICES && r.shape == EMM_TAG_COLUMNS && r.stride == 8 &&
          r.n == 0 && r.min == 4096);
    CHECK(emm_tag_rule_fits(&r, 3 * 8 * 1000));
    CHECK(!emm_tag_rule_fits(&r, 3 * 8 * 1000 + 8)); /* not three equal columns */
    CHECK(!emm_tag_rule_fits(&r, 0));
    /* Eigen's F with its count: only a block of exactly 3 * n entries. */
    round_trip("triangles:order=columns,n=2000,vidx=0:i32",
               "triangles:order=columns,n=2000,stride=4,vidx=0:i32", &r);
    CHECK(r.kind == EMM_ARRAY_TRIANGLES && r.shape == EMM_TAG_COLUMNS && r.n == 2000 &&
          r.min == 24000);
    CHECK(emm_tag_rule_fits(&r, 24000));
    CHECK(!emm_tag_rule_fits(&r, 48000) && !emm_tag_rule_fits(&r, 23988));
    /* Columns of wider entries, the scalar inside each. */
    round_trip("vertices:order=columns,stride=16,xyz=8:f32",
               "vertices:order=columns,stride=16,xyz=8:f32", &r);
    round_trip("vertices:order=records,stride=12,xyz=0:f32", "vertices:stride=12,xyz=0:f32", &r);
    CHECK(r.shape == EMM_TAG_RECORDS);
    /* Binary STL: 50-byte facets, the corners after the normal. */
    round_trip("soup:site=read_stl,stride=50,corners=12:f32", NULL, &r);
    CHECK(r.kind == EMM_ARRAY_TRIANGLES && r.shape == EMM_TAG_SOUP && r.offset == 12 &&
          r.type == EMM_F32);
    CHECK(emm_tag_rule_fits(&r, 50 * 100) && !emm_tag_rule_fits(&r, 50 * 100 + 2));
    round_trip("soup:min=1M,stride=72,corners=0:f64", "soup:min=1048576,stride=72,corners=0:f64", &r);

    refused("vertices:order=rows,stride=12,xyz=0:f32", "order=records|columns");
    refused("vertices:stride=12,n=10,xyz=0:f32", "needs order=columns");
    refused("vertices:order=columns,n=0,xyz=0:f32", "count of records");
    refused("vertices:order=columns,stride=4,xyz=0:f64", "does not fit");
    refused("vertices:order=columns,n=18446744073709551615,xyz=0:f64", "too large");
    refused("soup:stride=50,corners=12:u32", "corners=OFFSET:f32|f64");
    refused("soup:stride=47,corners=12:f32", "nine corner coordinates do not fit");
    refused("soup:stride=50,xyz=12:f32", "soup rules take site, min, nth, stride, corners");
    refused("soup:stride=50,order=columns,corners=12:f32", "unknown key");
    refused("soup:corners=12:f32", "needs stride=");
    refused("triangles:order=columns,corners=0:f32", "unknown key");
    refused("triangles:order=columns", "needs vidx=");
    refused("points:stride=12,xyz=0:f32", "vertices, triangles, soup, halfedges, faces or vconn");

    /* The line for a column-major rule that matched nothing names the
     * blocks that are not its three columns. */
    emm_tag_rules rs;
    emm_error err;
    REQUIRE(emm_tag_rules_parse("vertices:site=load_mesh,order=columns,n=999,xyz=0:f64", &rs,
                                &err) == EMM_OK);
    emm_tag_site_seen seen = {"load_mesh", 2, 242424};
    char line[1024];
    emm_tag_unmatched_message(&rs.rule[0], 0, &seen, 1, line, sizeof line);
    CHECKF(strstr(line, "EMM_TAG rule 1 (vertices:site=load_mesh,order=columns,n=999,stride=8,"
                        "xyz=0:f64) matched no allocation; sites seen, closest first: load_mesh "
                        "(2 blocks, up to 242424 bytes, not 3 columns of n=999 entries of 8 "
                        "bytes (23976 bytes))") == line,
           "%s", line);
    emm_tag_rules_free(&rs);
}

/* Structure of arrays: x=, y=, z= rules, each one block holding one
 * coordinate of every vertex; a set needs x and y of one stride and type. */
/* Issue 30: half-edge connectivity (halfedges:, faces:, vconn:), its links
 * written back and parsed again, the checks on them, and the OpenMesh
 * preset. */
static void halfedges(void)
{
    emm_tag_rule r = {0};
    round_trip("halfedges:site=^ArrayKernel::reserve,stride=16,to=4:i32,next=8,prev=12,face=0",
               NULL, &r);
    CHECK(r.kind == EMM_ARRAY_TRIANGLES && r.shape == EMM_TAG_HALFEDGES && r.offset == 4 &&
          r.type == EMM_I32);
    CHECK(r.link[EMM_TAG_LINK_NEXT] == 8 && r.link[EMM_TAG_LINK_PREV] == 12 &&
          r.link[EMM_TAG_LINK_FACE] == 0 && r.link[EMM_TAG_LINK_OPP] == EMM_TAG_NO_LINK);
    CHECK(strcmp(r.site, "^ArrayKernel::reserve") == 0);
    /* A link may repeat the type; opp= is a field of its own. */
    round_trip("halfedges:stride=20,next=2:u16,to=0:u16,face=4,opp=6",
               "halfedges:stride=20,to=0:u16,next=2,face=4,opp=6", &r);
    CHECK(r.link[EMM_TAG_LINK_OPP] == 6 && r.link[EMM_TAG_LINK_PREV] == EMM_TAG_NO_LINK);
    round_trip("faces:site=load,stride=4,he=0:u32", NULL, &r);
    CHECK(r.kind == EMM_ARRAY_TRIANGLES && r.shape == EMM_TAG_FACES);
    round_trip("vconn:stride=8,he=0:i64", NULL, &r);
    CHECK(r.kind == EMM_ARRAY_VERTICES && r.shape == EMM_TAG_VCONN && r.type == EMM_I64);
    refused("halfedges:stride=16,to=4:i32,face=0", "needs next=OFFSET and face=OFFSET");
    refused("halfedges:stride=16,to=4:i32,next=8", "needs next=OFFSET and face=OFFSET");
    refused("halfedges:stride=16,next=8,face=0", "needs to=OFFSET");
    refused("halfedges:stride=16,to=4:i32,next=8:u32,face=0", "another type than to=");
    refused("halfedges:stride=16,to=4:i32,next=14,face=0", "next= does not fit");
    refused("halfedges:stride=16,to=4:i32,next=8,next=12,face=0", "given twice");
    refused("halfedges:stride=16,to=4:f32,next=8,face=0", "to=OFFSET:i32|u32|u16|i64");
    refused("halfedges:stride=16,to=4:i32,next=x,face=0", "expected next=OFFSET");
    refused("halfedges:stride=16,to=4:i32,next=8,face=0,order=columns", "unknown key");
    refused("faces:stride=4,vidx=0:i32", "faces rules take site, min, nth, stride, he");
    refused("vconn:stride=2,he=0:i32", "does not fit in stride");
    refused("faces:stride=4,he=0:i32,next=0", "unknown key");

    /* The preset: OpenMesh's arrays, each rule an alternative of its kind. */
    emm_tag_rules rs;
    emm_error err;
    REQUIRE(emm_tag_rules_parse("openmesh", &rs, &err) == EMM_OK);
    unsigned shapes_seen = 0;
    for (size_t i = 0; i < rs.n; i++) {
        CHECK(rs.rule[i].alternative);
        shapes_seen |= 1u << rs.rule[i].shape;
    }
    CHECK(shapes_seen == (1u << EMM_TAG_RECORDS | 1u << EMM_TAG_HALFEDGES |
                          1u << EMM_TAG_FACES | 1u << EMM_TAG_VCONN));
    CHECK(emm_tag_preset("openmesh") && !emm_tag_preset("cgal"));
    emm_tag_rules_free(&rs);
}

static void axes(void)
{
    emm_tag_rules rs, again;
    emm_error err;
    char back[3][256], joined[800];
    REQUIRE(emm_tag_rules_parse("vertices:site=load,x=0:f32;vertices:site=load,y=0:f32;"
                                "vertices:site=load,z=0:f32;triangles:stride=12,vidx=0:u32",
                                &rs, &err) == EMM_OK);
    for (uint32_t k = 0; k < 3; k++) {
        const emm_tag_rule *r = &rs.rule[k];
        CHECK(r->kind == EMM_ARRAY_VERTICES && r->shape == EMM_TAG_AXIS && r->axis == k &&
              r->stride == 4 && r->offset == 0 && r->type == EMM_F32 && r->min == 4096);
        emm_tag_rule_format(r, back[k], sizeof back[k]);
    }
    CHECKF(strcmp(back[0], "vertices:site=load,stride=4,x=0:f32") == 0, "%s", back[0]);
    CHECKF(strcmp(back[2], "vertices:site=load,stride=4,z=0:f32") == 0, "%s", back[2]);
    CHECK(emm_tag_rule_fits(&rs.rule[1], 4 * 1000) && !emm_tag_rule_fits(&rs.rule[1], 4002));
    snprintf(joined, sizeof joined, "%s;%s;%s;triangles:stride=12,vidx=0:u32", back[0], back[1],
             back[2]);
    REQUIRE(emm_tag_rules_parse(joined, &again, &err) == EMM_OK);
    CHECK(same_rules(&rs, &again));
    emm_tag_rules_free(&rs);
    emm_tag_rules_free(&again);
    /* An array of structs with only x in it (x at 8 of 16 bytes), doubles;
     * z is optional. */
    REQUIRE(emm_tag_rules_parse("vertices:stride=16,y=8:f64;vertices:stride=16,x=8:f64", &rs,
                                &err) == EMM_OK);
    CHECK(rs.n == 2 && rs.rule[0].axis == 1 && rs.rule[1].axis == 0 &&
          rs.rule[1].offset == 8 && rs.rule[1].stride == 16 && rs.rule[1].type == EMM_F64);
    CHECK(emm_tag_rule_fits(&rs.rule[0], 16 * 300) && !emm_tag_rule_fits(&rs.rule[0], 16 * 300 + 8));
    emm_tag_rules_free(&rs);

    /* A missing axis, or one of another stride or type: one line naming
     * the rule. */
    refused("vertices:x=0:f32;vertices:z=0:f32",
            "rule 1 'vertices:stride=4,x=0:f32' is one coordinate of the vertices, but no rule "
            "gives their y block with stride=4 and f32");
    refused("vertices:x=0:f32;vertices:y=0:f64", "rule 1 'vertices:stride=4,x=0:f32'");
    refused("vertices:stride=8,x=0:f32;vertices:y=0:f32", "their y block with stride=8");
    refused("vertices:y=0:f32", "need an x and a y rule");
    /* One field per rule, and an axis block has no order. */
    refused("vertices:x=0:f32,y=4:f32", "a rule has one of xyz=, x=, y=, z=");
    refused("vertices:stride=12,xyz=0:f32,x=0:f32", "a rule has one of");
    refused("vertices:order=columns,x=0:f32;vertices:y=0:f32", "order= does not apply");
    refused("vertices:x=0:f32,n=10;vertices:y=0:f32", "needs order=columns");
    refused("vertices:x=0:i32;vertices:y=0:f32", "'x=0:i32': expected x=OFFSET:f32|f64");
    refused("vertices:stride=6,x=4:f32;vertices:stride=6,y=0:f32", "coordinate does not fit");
    refused("triangles:x=0:f32", "unknown key");
    refused("soup:stride=36,y=0:f32", "unknown key");
}

int main(void)
{
    /* A method of a class template, as __cxa_demangle spells it: the
     * method's name, not the class's (issue 14: site=add_vertex). */
    names("_ZN8OpenMesh9PropertyTINS_7VectorTIfLi3EEEE7reserveEm",
          "OpenMesh::PropertyT<OpenMesh::VectorT<float, 3> >::reserve(unsigned long)", "reserve",
          "OpenMesh::PropertyT::reserve");
    /* A template function with its return type, a clone suffix. */
    names("_Z4loadIfEvPKc", "void load<float>(char const*) [clone .constprop.0]", "load", "load");
    /* A C symbol, no demangler. */
    names("read_mesh.isra.0", NULL, "read_mesh", "read_mesh");

    /* The shim's own frames are no site, under Valgrind too (its preload). */
    CHECK(emm_tag_site_is_library("shim_rules_match", "/x/lib/libemmshim.so"));
    CHECK(emm_tag_site_is_library("shim_rules_match",
                                  "/x/lib/emm/valgrind/vgpreload_emm-amd64-linux.so"));
    CHECK(!emm_tag_site_is_library("load_mesh", "/x/bin/smooth"));
    CHECK(emm_tag_site_is_library("_ZNSt6vectorIiSaIiEE7reserveEm", "/x/bin/app"));
    CHECK(emm_tag_site_matches("reserve", "reserve", "OpenMesh::PropertyT::reserve"));
    CHECK(emm_tag_site_matches("PropertyT::reserve", "reserve", "OpenMesh::PropertyT::reserve"));
    CHECK(emm_tag_site_matches("OpenMesh::PropertyT::reserve", "reserve",
                               "OpenMesh::PropertyT::reserve"));
    CHECK(!emm_tag_site_matches("PropertyT", "reserve", "OpenMesh::PropertyT::reserve"));
    CHECK(!emm_tag_site_matches("tyT::reserve", "reserve", "OpenMesh::PropertyT::reserve"));

    /* Written back as spelled, and parsed again the same. */
    emm_tag_rules rs, again;
    emm_error err;
    const char *text = "vertices:site=load_mesh,stride=12,xyz=0:f32;"
                       "triangles:site=load_mesh,nth=2,stride=6,vidx=0:u16";
    REQUIRE(emm_tag_rules_parse(text, &rs, &err) == EMM_OK);
    CHECK(rs.rule[1].type == EMM_U16);
    char a[256], b[256], joined[600];
    emm_tag_rule_format(&rs.rule[0], a, sizeof a);
    emm_tag_rule_format(&rs.rule[1], b, sizeof b);
    CHECKF(strcmp(a, "vertices:site=load_mesh,stride=12,xyz=0:f32") == 0, "%s", a);
    CHECKF(strcmp(b, "triangles:site=load_mesh,nth=2,stride=6,vidx=0:u16") == 0, "%s", b);
    snprintf(joined, sizeof joined, "%s;%s", a, b);
    REQUIRE(emm_tag_rules_parse(joined, &again, &err) == EMM_OK);
    CHECK(same_rules(&rs, &again));
    emm_tag_rules_free(&rs);
    CHECK(emm_tag_rules_parse("triangles:stride=6,vidx=0:u8", &rs, &err) != EMM_OK &&
          strstr(err.message, "u16"));

    /* The line for a rule that matched nothing: the site with the most in
     * common with its site= first, a block of partial records said so. */
    emm_tag_site_seen seen[3] = {{"main", 3, 24552}, {"load_obj", 4, 24576},
                                 {"fopen_buffer", 1, 4096}};
    char line[1024];
    emm_tag_unmatched_message(&again.rule[0], 0, seen, 3, line, sizeof line);
    CHECKF(strstr(line, "EMM_TAG rule 1 (vertices:site=load_mesh,stride=12,xyz=0:f32) matched "
                        "no allocation; sites seen, closest first: load_obj (4 blocks, up to "
                        "24576 bytes)") == line,
           "%s", line);
    CHECKF(strstr(line, "inlined") != NULL, "%s", line);
    emm_tag_site_seen odd = {"load_mesh", 2, 100000};
    emm_tag_unmatched_message(&again.rule[0], 0, &odd, 1, line, sizeof line);
    CHECKF(strstr(line, "load_mesh (2 blocks, up to 100000 bytes, not whole records)"), "%s",
           line);
    emm_tag_unmatched_message(&again.rule[0], 0, NULL, 0, line, sizeof line);
    CHECKF(strstr(line, "no allocation of 4096 bytes or more was seen"), "%s", line);
    emm_tag_rules_free(&again);

    shapes();
    axes();
    halfedges();
    return check_done();
}
