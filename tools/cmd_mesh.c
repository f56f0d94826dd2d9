/* emm mesh: generate meshes (docs/design.md "Workloads": the thesis' non-uniform
 * 2D mesh, §6.1) and describe mesh files. */
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "cli.h"
#include "parse.h"
#include "emm/mesh.h"
#include "generate.h"
#include "json.h"

static void usage_mesh(FILE *out)
{
    fprintf(out,
            "usage: emm mesh gen [--faces N] [--seed S] [--density clustered|uniform]\n"
            "                   [--order made|random|hilbert] -o FILE\n"
            "       emm mesh info [--json] FILE\n"
            "\n"
            "  gen   make a planar (z = 0) Delaunay triangulation of points in the unit\n"
            "        square and write it as an OFF file; by default the thesis' mesh:\n"
            "        %u faces, clustered (non-uniform) points, seed %u\n"
            "  info  print a mesh file's vertex, face and boundary-edge counts, its\n"
            "        bounding box, mean edge length and the bytes the thesis' structs take\n"
            "\n"
            "'emm mesh gen --help' and 'emm mesh info --help' say more.\n",
            EMM_DEFAULT_FACES, EMM_DEFAULT_SEED);
}

static void usage_gen(FILE *out)
{
    fprintf(out,
            "usage: emm mesh gen [--faces N] [--seed S] [--density clustered|uniform]\n"
            "                   [--order made|random|hilbert] -o FILE\n"
            "\n"
            "Writes a planar (z = 0) Delaunay triangulation (libqhull) of points drawn in\n"
            "the unit square, as an ASCII OFF file, or OBJ when FILE ends in .obj. The face\n"
            "count is N exactly (within 1%% at worst). The convex hull is about sqrt(2N)\n"
            "points spread around the square's border, pushed out onto a squircle so that\n"
            "it is strictly convex: as many boundary edges (200 for 20,000 faces), each\n"
            "about as long as the edges inside. The same options give the same file, byte\n"
            "for byte.\n"
            "\n"
            "  --faces N        triangles to make, 8 or more (default %u)\n"
            "  --seed S         seed of the point stream, a non-negative integer (default %u)\n"
            "  --density D      clustered: a few Gaussian clusters over a uniform background,\n"
            "                   their number, places and widths drawn from the seed (default)\n"
            "                   uniform: points spread evenly\n"
            "  --order O        made: vertices in the order the points were drawn, faces in\n"
            "                   qhull's order, which is spatially coherent (default; 'input'\n"
            "                   is the same); random: both in a random order from the seed,\n"
            "                   unorganised like the thesis' original mesh; hilbert: both\n"
            "                   numbered along a Hilbert curve, for locality\n"
            "  -o, --output F   the file to write (required): .off for OFF, .obj for OBJ\n"
            "                   (another extension is refused); written whole or not at all\n",
            EMM_DEFAULT_FACES, EMM_DEFAULT_SEED);
}

static void usage_info(FILE *out)
{
    fprintf(out,
            "usage: emm mesh info [--json] FILE\n"
            "\n"
            "Reads a mesh file (OFF, OBJ, PLY, STL; polygons are fan-triangulated) and prints:\n"
            "  vertices, faces, boundary edges, polygons split, bbox, mean edge length, and\n"
            "  thesis bytes: what the thesis' structs would take (Vertex %u B, Triangle %u B).\n"
            "\n"
            "  --json   print the same as one JSON object\n",
            EMM_THESIS_VERTEX_BYTES, EMM_THESIS_TRIANGLE_BYTES);
}

static int cmd_gen(int argc, char **argv)
{
    const char *cmd = "mesh gen";
    emm_gen_options opt = {EMM_DEFAULT_FACES, EMM_DEFAULT_SEED, EMM_DENSITY_CLUSTERED, EMM_ORDER_INPUT};
    const char *output = NULL;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v;
        uint64_t n;
        if (cli_is_help(a)) {
            usage_gen(stdout);
            return EMM_EXIT_OK;
        } else if (strcmp(a, "--faces") == 0) {
            if (!(v = cli_value(cmd, argc, argv, &i)) || !cli_u64(cmd, a, v, &n))
                return EMM_EXIT_USAGE;
            if (n < EMM_GEN_MIN_FACES || n > EMM_GEN_MAX_FACES)
                return cli_usage_error(cmd, "--faces must be between %u and %u, not '%s'",
                                       EMM_GEN_MIN_FACES, EMM_GEN_MAX_FACES, v);
            opt.faces = (size_t)n;
        } else if (strcmp(a, "--seed") == 0) {
            if (!(v = cli_value(cmd, argc, argv, &i)) || !cli_u64(cmd, a, v, &n))
                return EMM_EXIT_USAGE;
            opt.seed = n;
        } else if (strcmp(a, "--density") == 0) {
            if (!(v = cli_value(cmd, argc, argv, &i)))
                return EMM_EXIT_USAGE;
            if (strcmp(v, "clustered") == 0)
                opt.density = EMM_DENSITY_CLUSTERED;
            else if (strcmp(v, "uniform") == 0)
                opt.density = EMM_DENSITY_UNIFORM;
            else
                return cli_usage_error(cmd, "--density expects clustered or uniform, not '%s'", v);
        } else if (strcmp(a, "--order") == 0) {
            if (!(v = cli_value(cmd, argc, argv, &i)))
                return EMM_EXIT_USAGE;
            if (strcmp(v, "made") == 0 || strcmp(v, "input") == 0)
                opt.order = EMM_ORDER_MADE;
            else if (strcmp(v, "random") == 0)
                opt.order = EMM_ORDER_RANDOM;
            else if (strcmp(v, "hilbert") == 0)
                opt.order = EMM_ORDER_HILBERT;
            else
                return cli_usage_error(cmd, "--order expects made, random or hilbert, not '%s'", v);
        } else if (strcmp(a, "-o") == 0 || strcmp(a, "--output") == 0) {
            if (!(v = cli_value(cmd, argc, argv, &i)))
                return EMM_EXIT_USAGE;
            if (!*v)
                return cli_usage_error(cmd, "%s needs a file name", a);
            output = v;
        } else if (a[0] == '-') {
            return cli_usage_error(cmd, "unknown option '%s'", a);
        } else {
            return cli_usage_error(cmd, "unexpected argument '%s'", a);
        }
    }
    if (!output)
        return cli_usage_error(cmd, "-o FILE is required");
    /* The format the name promises; no OFF text in a file called .obj. */
    const char *dot = strrchr(output, '.');
    int obj = dot && strcasecmp(dot, ".obj") == 0;
    if (!dot || strchr(dot, '/') || (!obj && strcasecmp(dot, ".off") != 0))
        return cli_usage_error(cmd, "-o %s: the file must end in .off (OFF) or .obj (OBJ)",
                               output);

    emm_error err;
    emm_mesh *m;
    if (emm_mesh_generate(&opt, &m, &err) != EMM_OK)
        return cli_fail(&err);
    emm_status st = obj ? emm_mesh_write_obj(m, output, &err) : emm_mesh_write_off(m, output, &err);
    if (st == EMM_OK)
        printf("wrote %s: %zu vertices, %zu faces\n", output, emm_mesh_vertex_count(m),
               emm_mesh_triangle_count(m));
    emm_mesh_free(m);
    return st == EMM_OK ? EMM_EXIT_OK : cli_fail(&err);
}

static int cmd_info(int argc, char **argv)
{
    const char *cmd = "mesh info";
    const char *path = NULL;
    int json = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (cli_is_help(a)) {
            usage_info(stdout);
            return EMM_EXIT_OK;
        } else if (strcmp(a, "--json") == 0) {
            json = 1;
        } else if (a[0] == '-' && a[1] != '\0') {
            return cli_usage_error(cmd, "unknown option '%s'", a);
        } else if (path) {
            return cli_usage_error(cmd, "one FILE only, not '%s' too", a);
        } else {
            path = a;
        }
    }
    if (!path)
        return cli_usage_error(cmd, "FILE is required");

    emm_error err;
    emm_mesh *m;
    if (emm_mesh_open(path, &m, &err) != EMM_OK)
        return cli_fail(&err);
    size_t nv = emm_mesh_vertex_count(m), nt = emm_mesh_triangle_count(m);
    double lo[3], hi[3];
    emm_mesh_bbox(m, lo, hi);
    unsigned long long bytes = (unsigned long long)nv * EMM_THESIS_VERTEX_BYTES +
                               (unsigned long long)nt * EMM_THESIS_TRIANGLE_BYTES;
    if (json) {
        printf("{\"file\": ");
        json_write_string(stdout, path);
        printf(", \"vertices\": %zu, \"faces\": %zu, \"boundary_edges\": %zu, "
               "\"polygons_split\": %zu, \"bbox\": [[%.17g, %.17g, %.17g], [%.17g, %.17g, %.17g]], "
               "\"mean_edge_length\": %.17g, \"thesis_vertex_bytes\": %u, "
               "\"thesis_triangle_bytes\": %u, \"thesis_bytes\": %llu}\n",
               nv, nt, emm_mesh_boundary_edges(m), emm_mesh_polygons_split(m), lo[0], lo[1],
               lo[2], hi[0], hi[1], hi[2], emm_mesh_mean_edge_length(m),
               EMM_THESIS_VERTEX_BYTES, EMM_THESIS_TRIANGLE_BYTES, bytes);
    } else {
        char buf[32];
        printf("file: %s\n", path);
        printf("vertices: %zu\n", nv);
        printf("faces: %zu\n", nt);
        printf("boundary edges: %zu\n", emm_mesh_boundary_edges(m));
        printf("polygons split: %zu\n", emm_mesh_polygons_split(m));
        printf("bbox: [%g, %g, %g] - [%g, %g, %g]\n", lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
        printf("mean edge length: %.6g\n", emm_mesh_mean_edge_length(m));
        printf("thesis bytes: %s (Vertex %u B, Triangle %u B; %.2f MB)\n", emm_grouped(bytes, buf),
               EMM_THESIS_VERTEX_BYTES, EMM_THESIS_TRIANGLE_BYTES, (double)bytes / 1e6);
    }
    emm_mesh_free(m);
    return EMM_EXIT_OK;
}

int emm_cmd_mesh(int argc, char **argv)
{
    if (argc < 2)
        return cli_usage_error("mesh", "a subcommand is needed: gen or info");
    if (cli_is_help(argv[1])) {
        usage_mesh(stdout);
        return EMM_EXIT_OK;
    }
    if (strcmp(argv[1], "gen") == 0)
        return cmd_gen(argc - 1, argv + 1);
    if (strcmp(argv[1], "info") == 0)
        return cmd_info(argc - 1, argv + 1);
    return cli_usage_error("mesh", "unknown subcommand '%s' (gen or info)", argv[1]);
}
