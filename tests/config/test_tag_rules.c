/* EMM_TAG's names and messages (core/tag_rules.c): the names a frame
 * answers to (a method of a class template by its own name, issue 14),
 * site= matching, a rule written back as it is spelled, u16 indices, and
 * the line a rule that matched nothing gets. */
#include <string.h>

#include "check.h"
#include "emm/config.h"

static void names(const char *sym, const char *dm, const char *want_name, const char *want_qual)
{
    char n[EMM_TAG_SITE_MAX], q[512];
    emm_tag_site_names(sym, dm, n, sizeof n, q, sizeof q);
    CHECKF(strcmp(n, want_name) == 0, "%s: name '%s', want '%s'", sym, n, want_name);
    CHECKF(strcmp(q, want_qual) == 0, "%s: qualified '%s', want '%s'", sym, q, want_qual);
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
    CHECK(memcmp(&rs, &again, sizeof rs) == 0);
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
    return check_done();
}
