/* Bad mesh input, one case per CTest entry: each must come back as an error
 * status, a NULL mesh, and one line that starts with the file's name and
 * says what is wrong. ASan (the sanitizer CI build) checks nothing leaks or
 * overruns on the way. */
#include "check.h"
#include "fixtures.h"

#include "emm/mesh.h"

#include <string.h>

typedef struct bad_case {
    const char *name;
    const char *file;    /* in tests/data/mesh, or generated in the build tree when gen != 0 */
    int gen;
    emm_status status;
    const char *problem; /* must appear in the message */
} bad_case;

enum { GEN_NONE, GEN_PLY_CUT, GEN_PLY_NAN, GEN_STL_CUT, GEN_OFF_CUT };

static const bad_case cases[] = {
    { "missing", "no_such_file.off", 0, EMM_ERR_IO, "No such file or directory" },
    { "empty", "empty.off", 0, EMM_ERR_FORMAT, "empty file" },
    { "no_faces", "no_faces.off", 0, EMM_ERR_MESH, "no faces" },
    { "truncated_off", "truncated_faces.off", 0, EMM_ERR_FORMAT, "truncated: header declares 2 faces, file has 1" },
    { "truncated_off_vertices", "truncated_vertices.off", 0, EMM_ERR_FORMAT,
      "truncated: header declares 4 vertices, file has 3" },
    { "truncated_off_face_line", "truncated_face_line.off", 0, EMM_ERR_FORMAT,
      "line 8: face 1: expected 3 vertex indices, found 2" },
    { "truncated_ply_binary", "truncated.ply", GEN_PLY_CUT, EMM_ERR_FORMAT, "truncated" },
    { "truncated_off_binary", "truncated_binary.off", GEN_OFF_CUT, EMM_ERR_FORMAT,
      "truncated: the data ends before the 4 vertices and 2 faces the header declares" },
    { "truncated_stl_binary", "truncated.stl", GEN_STL_CUT, EMM_ERR_FORMAT,
      "truncated: header declares 2 facets, file has 1" },
    { "out_of_range", "out_of_range.off", 0, EMM_ERR_MESH,
      "line 8: face 1 refers to vertex 9, but the file has 4 vertices" },
    { "negative_index", "negative_index.off", 0, EMM_ERR_MESH,
      "face 1 refers to vertex -1, but the file has 4 vertices" },
    { "out_of_range_obj", "out_of_range.obj", 0, EMM_ERR_MESH,
      "line 6: face 2 refers to vertex 9, but the file has 4 vertices" },
    { "nan", "nan.off", 0, EMM_ERR_MESH, "vertex 2 has a non-finite coordinate (nan)" },
    { "inf", "inf.off", 0, EMM_ERR_MESH, "vertex 3 has a non-finite coordinate (inf)" },
    { "nan_obj", "nan.obj", 0, EMM_ERR_MESH, "vertex 3 has a non-finite coordinate (nan)" },
    { "nan_ply_binary", "nan.ply", GEN_PLY_NAN, EMM_ERR_MESH, "vertex 1 has a non-finite coordinate (nan)" },
    { "non_manifold", "non_manifold.off", 0, EMM_ERR_MESH, "edge (0, 1) is shared by 3 faces (non-manifold)" },
    { "degenerate", "degenerate.off", 0, EMM_ERR_MESH, "line 8: face 1 repeats vertex 2 (degenerate face)" },
    { "degenerate_obj", "degenerate.obj", 0, EMM_ERR_MESH, "line 6: face 2 repeats vertex 3 (degenerate face)" },
    { "two_corners", "two_corners.off", 0, EMM_ERR_MESH, "face 1 has 2 corners; a face needs at least 3" },
    { "unknown_extension", "triangle.xyz", 0, EMM_ERR_UNSUPPORTED, "unknown mesh file extension" },
    { "garbage_off", "garbage.off", 0, EMM_ERR_FORMAT, "not an OFF file" },
    { "garbage_ply", "garbage.ply", 0, EMM_ERR_FORMAT, "not a readable PLY file" },
    { "garbage_stl", "garbage.stl", 0, EMM_ERR_FORMAT, "not an STL file" },
};

static int run(const bad_case *c, const char *gen_dir)
{
    char path[4096];
    if (c->gen)
        snprintf(path, sizeof path, "%s/%s", gen_dir, c->file);
    else
        snprintf(path, sizeof path, "%s/mesh/%s", EMM_TEST_DATA, c->file);
    if (c->gen == GEN_PLY_CUT)
        write_binary_ply(path, 7, -1);
    else if (c->gen == GEN_PLY_NAN)
        write_binary_ply(path, 0, 1);
    else if (c->gen == GEN_OFF_CUT)
        write_binary_off(path, 8);
    else if (c->gen == GEN_STL_CUT)
        write_binary_stl(path, 50);

    emm_mesh *m = (emm_mesh *)1;
    emm_error err;
    emm_status st = emm_mesh_open(path, &m, &err);
    printf("%s: status %d (%s): %s\n", c->name, (int)st, emm_strerror(st), err.message);
    CHECKF(st == c->status, "status %d, want %d", (int)st, (int)c->status);
    CHECK(err.status == st);
    CHECK(m == NULL);
    CHECKF(strncmp(err.message, path, strlen(path)) == 0 && strncmp(err.message + strlen(path), ": ", 2) == 0,
           "message does not start with \"%s: \"", path);
    CHECKF(strstr(err.message, c->problem) != NULL, "message lacks \"%s\"", c->problem);
    CHECK(strchr(err.message, '\n') == NULL);
    emm_mesh_free(m);
    return check_done();
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: %s CASE GENERATED_DIR\n", argv[0]);
        return 2;
    }
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        if (strcmp(cases[i].name, argv[1]) == 0)
            return run(&cases[i], argv[2]);
    fprintf(stderr, "unknown case %s\n", argv[1]);
    return 2;
}
