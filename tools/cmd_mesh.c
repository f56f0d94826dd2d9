/* emm mesh: generate meshes (docs/design.md "Workloads": the thesis' non-uniform
 * 2D mesh, §6.1) and describe mesh files. */
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "cli.h"
#include "opts.h"
#include "parse.h"
#include "emm/mesh.h"
#include "generate.h"
#include "json.h"

static void usage_mesh(FILE *out)
{
    fprintf(out,
            "usage: emm mesh gen [--surface plane|sphere|torus|terrain] [--faces N] [--seed S]\n"
            "                   [--density clustered|uniform] [--order made|random|hilbert]\n"
            "                   -o FILE\n"
            "       emm mesh info [--json] FILE\n"
            "\n"
            "  gen   make a planar (z = 0) Delaunay triangulation of points in the unit\n"
            "        square, or a sphere, torus or terrain of exactly N faces, and write\n"
            "        it as an OFF or OBJ file; by default the thesis' mesh: %u faces,\n"
            "        planar, clustered (non-uniform) points, seed %u\n"
            "  info  print a mesh file's vertex, face and boundary-edge counts, its\n"
            "        bounding box, mean edge length and the bytes the thesis' structs take\n"
            "\n"
            "'emm mesh gen --help' and 'emm mesh info --help' say more.\n",
            EMM_DEFAULT_FACES, EMM_DEFAULT_SEED);
}

static void usage_gen(FILE *out, const opts *o)
{
    fprintf(out,
            "usage: emm mesh gen [--surface plane|sphere|torus|terrain] [--faces N] [--seed S]\n"
            "                   [--density clustered|uniform] [--order made|random|hilbert]\n"
            "                   -o FILE\n"
            "\n"
            "Writes a planar (z = 0) Delaunay triangulation (libqhull) of points drawn in\n"
            "the unit square, as an ASCII OFF file, or OBJ when FILE ends in .obj. The face\n"
            "count is N exactly (within 1%% at worst). The convex hull is about sqrt(2N)\n"
            "points spread around the square's border, pushed out onto a squircle so that\n"
            "it is strictly convex: as many boundary edges (200 for 20,000 faces), each\n"
            "about as long as the edges inside. The same options give the same file, byte\n"
            "for byte.\n"
            "\n"
            "--surface makes a 3D surface instead, a grid of exactly N faces (any N that\n"
            "the surface allows; another N is refused), vertices jittered from the seed,\n"
            "triangles consistently oriented (normals outward, or up), none degenerate:\n"
            "  sphere   radius 1, closed (every edge in two faces): N even, %u or more.\n"
            "           One spiral strip wound from pole to pole, closed by a fan at\n"
            "           each pole: a UV sphere without a seam, thin triangles at the poles.\n"
            "  torus    radii 1 and 0.4, closed: N even, %u or more. One helical strip\n"
            "           closed on itself, cells about square.\n"
            "  terrain  open, a height field z = f(x, y) over the unit square with hills\n"
            "           from the seed: any N from %u. A grid of quads split along their\n"
            "           shorter diagonal; the last row may be partial.\n"
            "Time and memory grow linearly with N (10 million faces: about 20 s and\n"
            "1.1 GiB). --order made numbers a surface as it is built, hilbert along a\n"
            "3D Hilbert curve (vertices by position, faces by centroid).\n"
            "\n",
            EMM_GEN_MIN_CLOSED_FACES, EMM_GEN_MIN_CLOSED_FACES, EMM_GEN_MIN_FACES);
    opts_help(out, o);
}

static void usage_info(FILE *out, const opts *o)
{
    fprintf(out,
            "usage: emm mesh info [--json] FILE\n"
            "\n"
            "Reads a mesh file (OFF, OBJ, PLY, STL; polygons are fan-triangulated) and prints:\n"
            "  vertices, faces, boundary edges, polygons split, bbox, mean edge length, and\n"
            "  thesis bytes: what the thesis' structs would take (Vertex %u B, Triangle %u B).\n"
            "\n",
            EMM_THESIS_VERTEX_BYTES, EMM_THESIS_TRIANGLE_BYTES);
    opts_help(out, o);
}

/* "input" is the old name of "made". */
static const char *const densities[] = {"clustered", "uniform", NULL};
static const char *const orders[] = {"made", "random", "hilbert", "input", NULL};
/* In emm_surface's order. */
static const char *const surfaces[] = {"plane", "sphere", "torus", "terrain", NULL};

static int gen(const emm_gen_options *opt, emm_surface surface, const char *output)
{
    /* The format the name promises; no OFF text in a file called .obj. */
    const char *dot = strrchr(output, '.');
    int obj = dot && strcasecmp(dot, ".obj") == 0;
    if (!dot || strchr(dot, '/') || (!obj && strcasecmp(dot, ".off") != 0))
        return cli_usage_error("mesh gen", "-o %s: the file must end in .off (OFF) or .obj (OBJ)",
                               output);

    emm_error err;
    emm_mesh *m;
    if (emm_mesh_generate_surface(opt, surface, &m, &err) != EMM_OK)
        return cli_fail(&err);
    emm_status st = obj ? emm_mesh_write_obj(m, output, &err) : emm_mesh_write_off(m, output, &err);
    if (st == EMM_OK)
        printf("wrote %s: %zu vertices, %zu faces\n", output, emm_mesh_vertex_count(m),
               emm_mesh_triangle_count(m));
    emm_mesh_free(m);
    return st == EMM_OK ? EMM_EXIT_OK : cli_fail(&err);
}

static int cmd_gen(int argc, char **argv)
{
    uint64_t faces = EMM_DEFAULT_FACES, seed = EMM_DEFAULT_SEED;
    int density = EMM_DENSITY_CLUSTERED, order = EMM_ORDER_MADE, surface = EMM_SURFACE_PLANE;
    const char *output = NULL;
    opts_row rows[] = {
        {.name = "--surface", .metavar = "S", .kind = OPT_WORD, .dst = &surface, .words = surfaces,
         .help = "plane: the planar Delaunay mesh (default); sphere, torus: closed surfaces, "
                 "an even N of 20 or more; terrain: an open height field, any N of 8 or more"},
        {.name = "--faces", .metavar = "N", .kind = OPT_U64, .dst = &faces,
         .min = EMM_GEN_MIN_FACES, .max = EMM_GEN_MAX_FACES, .show_default = true,
         .help = "triangles to make, 8 or more (exactly N for a --surface)"},
        {.name = "--seed", .metavar = "S", .kind = OPT_U64, .dst = &seed, .show_default = true,
         .help = "seed of the point stream (of the jitter and hills for a --surface)"},
        {.name = "--density", .metavar = "D", .kind = OPT_WORD, .dst = &density, .words = densities,
         .help = "clustered: a few Gaussian clusters over a uniform background, their number, "
                 "places and widths drawn from the seed (default)\n"
                 "uniform: points spread evenly (planar meshes only)"},
        {.name = "--order", .metavar = "O", .kind = OPT_WORD, .dst = &order, .words = orders,
         .help = "made: vertices in the order the points were drawn, faces in qhull's order, "
                 "which is spatially coherent (default; 'input' is the same); random: both in a "
                 "random order from the seed, unorganised like the thesis' original mesh; "
                 "hilbert: both numbered along a Hilbert curve, for locality (3D for a "
                 "--surface)"},
        {.name = "-o", .alias = "--output", .metavar = "FILE", .kind = OPT_TEXT, .dst = &output,
         .required = true,
         .help = "the file to write (required): .off for OFF, .obj for OBJ (another extension "
                 "is refused); written whole or not at all"},
        OPTS_END,
    };
    opts o = {"mesh gen", rows, usage_gen};
    int rc;
    if (opts_parse(&o, argc, argv, &rc))
        return rc;
    if (surface != EMM_SURFACE_PLANE && rows[3].seen)
        return cli_usage_error("mesh gen", "--density applies to planar meshes only, not to "
                                           "--surface %s",
                               surfaces[surface]);
    emm_gen_options opt = {(size_t)faces, seed, (emm_density)density,
                           order == EMM_ORDER_RANDOM || order == EMM_ORDER_HILBERT
                               ? (emm_order)order
                               : EMM_ORDER_MADE};
    return gen(&opt, (emm_surface)surface, output);
}

static int cmd_info(int argc, char **argv)
{
    const char *path = NULL;
    int json = 0;
    opts_row rows[] = {
        {.name = "--json", .kind = OPT_FLAG, .dst = &json,
         .help = "print the same as one JSON object"},
        {.metavar = "FILE", .kind = OPT_TEXT, .dst = &path, .required = true},
        OPTS_END,
    };
    opts o = {"mesh info", rows, usage_info};
    int rc;
    if (opts_parse(&o, argc, argv, &rc))
        return rc;

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
    static const opts_sub subs[] = {{"gen", cmd_gen}, {"info", cmd_info}, {NULL, NULL}};
    return opts_subcommand("mesh", subs, usage_mesh, argc, argv);
}
