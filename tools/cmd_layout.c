/* emm layout: build a strategy's layout (thesis §4.1) over a mesh file and
 * draw its cells over the mesh as an SVG (the pictures of thesis Figs. 4.2,
 * 4.5 and 4.6), print its cell statistics, or write the mesh renumbered in
 * the layout's order (the numbering the ":indexed" strategies assume). */
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "opts.h"
#include "emm/layout.h"
#include "emm/mesh.h"
#include "emm/sim.h"
#include "emm/strategy.h"
#include "outfile.h"
#include "parse.h"

static void usage(FILE *out, const opts *o)
{
    fprintf(out,
            "usage: emm layout MESH --strategy S [--svg FILE] [--stats] [--local BYTES]\n"
            "                  [--vertex-bytes N] [--triangle-bytes N] [--pointer-bytes N]\n"
            "                  [--write OUT [--perm FILE]]\n"
            "\n"
            "Builds the layout of strategy S (grid, tiles or quadtree in the plane, thesis\n"
            "4.1; grid3d, tiles3d or octree in space) over a mesh file and draws or\n"
            "describes its cells. Each cell holds the triangles whose centroids fall in\n"
            "it and a copy of each of their vertices.\n"
            "\n");
    opts_help(out, o);
    fprintf(out,
            "\n"
            "The default record sizes are the thesis' structs (Vertex %u B, Triangle %u B).\n"
            "In a cell a triangle's record is followed by 3 pointers to its vertices'\n"
            "copies in the cell (thesis 4.1.1): a slot of %u B on the default machine.\n"
            "A layout in the plane lays a 3D mesh out over the two axes along which its\n"
            "bounding box is largest; one in space over x, y and z. The SVG of a layout\n"
            "in space is a projection onto its first two axes (the third is seen\n"
            "end-on): triangles coloured by cell, the cells' boxes outlined, so boxes one\n"
            "behind the other overlap. docs/layouts.md explains the layouts.\n"
            "\n"
            "--write renumbers the mesh in the layout's order: the triangles cell by cell,\n"
            "each cell's in ascending original id; each used vertex in the first cell\n"
            "that uses it, in the order of first use there; unused vertices last, in\n"
            "their original order. A program that reads the written mesh finds each\n"
            "cell's triangles and vertices contiguous, so an element's cell follows from\n"
            "its id through a table with an entry per cell: what the S:indexed strategies\n"
            "simulate (docs/layouts.md, \"The indexed variant\"). --perm writes the\n"
            "permutation as text: a line 'vertices N', then N lines 'NEW OLD' in\n"
            "ascending NEW, then 'triangles M' and M such lines (ids from 0; OLD is the\n"
            "id in MESH, counting a polygon's fan triangles in order).\n",
            EMM_THESIS_VERTEX_BYTES, EMM_THESIS_TRIANGLE_BYTES,
            EMM_THESIS_TRIANGLE_BYTES + 3 * EMM_LAYOUT_POINTER_BYTES);
}

static void print_stats(const emm_layout *l, const char *path, const emm_strategy *s)
{
    emm_layout_stats st;
    emm_layout_get_stats(l, &st);
    char a[32], b[32], c[32];
    printf("mesh            %s: %s triangles, %s vertices\n", path,
           emm_grouped(emm_layout_triangle_count(l), a), emm_grouped(emm_layout_vertex_count(l), b));
    printf("layout          %s, CELL %u", emm_layout_name(s->layout), s->cell);
    uint32_t n[EMM_MAX_DIMS];
    emm_layout_cells_per_axis(l, n);
    if (s->layout == EMM_LAYOUT_GRID)
        printf(" (%u columns x %u rows)", n[0], n[1]);
    else if (s->layout == EMM_LAYOUT_TILES)
        printf(" (%u rows of %u and %u tiles)", n[1], n[0], n[0] + 1);
    else if (s->layout == EMM_LAYOUT_GRID3D)
        printf(" (%u x %u x %u boxes)", n[0], n[1], n[2]);
    else if (s->layout == EMM_LAYOUT_TILES3D)
        printf(" (%u layers of %u and %u rows of %u and %u boxes)", n[2], n[1], n[1] + 1, n[0],
               n[0] + 1);
    int axes[EMM_MAX_DIMS];
    uint32_t dims = emm_layout_axes(l, axes, NULL, NULL);
    printf(", over ");
    for (uint32_t k = 0; k < dims; k++)
        printf("%s%c", k == 0 ? "" : k + 1 < dims ? ", " : " and ", "xyz"[axes[k]]);
    printf("\n");
    if (st.dropped_cells)
        printf("cells           %s (%s %s without triangles dropped)\n", emm_grouped(st.cells, a),
               emm_grouped(st.dropped_cells, b), s->layout == EMM_LAYOUT_OCTREE ? "octants" : "boxes");
    else
        printf("cells           %s (%s without triangles)\n", emm_grouped(st.cells, a),
               emm_grouped(st.empty_cells, b));
    printf("triangles/cell  min %s, median %s, max %s\n", emm_grouped(st.tri_min, a),
           emm_grouped(st.tri_median, b), emm_grouped(st.tri_max, c));
    printf("bytes/cell      min %s, median %s, max %s\n", emm_grouped(st.bytes_min, a),
           emm_grouped(st.bytes_median, b), emm_grouped(st.bytes_max, c));
    const emm_layout_options *o = emm_layout_get_options(l);
    if (o->vertex_cells)
        printf("triangle slot   0 bytes (cells of vertices)\n");
    else
        printf("triangle slot   %u bytes (%u of record, 3 pointers of %u to its vertices' copies)\n",
               st.triangle_slot_bytes, o->triangle_bytes, o->pointer_bytes);
    printf("vertex copies   %s (%s duplicated, %s vertices unused)\n",
           emm_grouped(st.vertex_copies, a), emm_grouped(st.duplicated_vertices, b),
           emm_grouped(st.unused_vertices, c));
    printf("image bytes     %s\n", emm_grouped(st.image_bytes, a));
    printf("lookup bytes    %s\n", emm_grouped(st.lookup_bytes, a));
    if (s->layout == EMM_LAYOUT_QUADTREE || s->layout == EMM_LAYOUT_OCTREE) {
        int oct = s->layout == EMM_LAYOUT_OCTREE;
        printf("%-16smin %u, max %u\n", oct ? "octree depth" : "quadtree depth", st.depth_min,
               st.depth_max);
        printf("%-16s%s (%s leaves over CELL at the deepest level)\n",
               oct ? "octree nodes" : "quadtree nodes",
               emm_grouped(st.quadtree_nodes, a), emm_grouped(st.overfull_leaves, b));
    }
}

/* Pastel colours, light enough that the thin triangle edges stay visible. */
static const char *const palette[] = {
    "#8dd3c7", "#ffffb3", "#bebada", "#fb8072", "#80b1d3", "#fdb462",
    "#b3de69", "#fccde5", "#d9d9d9", "#bc80bd", "#ccebc5", "#ffed6f",
};
#define NPALETTE (sizeof palette / sizeof palette[0])

/* Greedy colouring in cell order: each cell takes the first colour none of
 * its already-coloured neighbours has, or the least used among them. */
static unsigned char *colour_cells(const emm_layout *l)
{
    uint32_t n = emm_layout_cell_count(l);
    unsigned char *col = malloc(n ? n : 1);
    if (!col)
        return NULL;
    for (uint32_t c = 0; c < n; c++) {
        unsigned used[NPALETTE] = {0};
        const uint32_t *nb;
        uint32_t k = emm_layout_neighbors(l, c, &nb, NULL);
        for (uint32_t i = 0; i < k; i++)
            if (nb[i] < c)
                used[col[nb[i]]]++;
        unsigned best = 0;
        for (unsigned p = 1; p < NPALETTE; p++)
            if (used[p] < used[best])
                best = p;
        col[c] = (unsigned char)best;
    }
    return col;
}

typedef struct view {
    double lo[2], scale, margin, top, height;
} view;

static double px(const view *v, double x)
{
    return v->margin + (x - v->lo[0]) * v->scale;
}

static double py(const view *v, double y)
{
    return v->top + v->height - (y - v->lo[1]) * v->scale; /* y up */
}

static void write_svg_body(FILE *f, const emm_layout *l, const double *xyz, const int32_t *tri,
                           const char *path, const emm_strategy *s, const unsigned char *col)
{
    uint32_t n = emm_layout_cell_count(l);
    int axes[EMM_MAX_DIMS];
    double lo[EMM_MAX_DIMS], hi[EMM_MAX_DIMS];
    /* The drawing is of the first two axes of the layout's space: a layout
     * in space is seen along its third. */
    emm_layout_axes(l, axes, lo, hi);
    /* The view covers every cell (tiles at a row's end and the quadtree's
     * square reach past the mesh's box). */
    for (uint32_t c = 0; c < n; c++) {
        const emm_layout_cell *cell = emm_layout_cell_get(l, c);
        for (int k = 0; k < 2; k++) {
            if (cell->lo[k] < lo[k])
                lo[k] = cell->lo[k];
            if (cell->hi[k] > hi[k])
                hi[k] = cell->hi[k];
        }
    }
    double w = hi[0] - lo[0], h = hi[1] - lo[1], big = w > h ? w : h;
    if (!(big > 0))
        big = 1;
    view v = {{lo[0], lo[1]}, 1000.0 / big, 20, 50, h * (1000.0 / big)};
    double width = w * v.scale + 2 * v.margin, height = v.top + v.height + v.margin;
    char a[32], b[32];
    fprintf(f,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
            "viewBox=\"0 0 %.2f %.2f\">\n"
            "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
            width, height, width, height);
    fprintf(f,
            "<text x=\"%.1f\" y=\"30\" font-family=\"sans-serif\" font-size=\"18\">"
            "%s layout, CELL %u: %s cells, %s triangles (",
            v.margin, emm_layout_name(s->layout), s->cell, emm_grouped(n, a),
            emm_grouped(emm_layout_triangle_count(l), b));
    for (const char *p = path; *p; p++) /* the file name, escaped */
        switch (*p) {
        case '<': fputs("&lt;", f); break;
        case '>': fputs("&gt;", f); break;
        case '&': fputs("&amp;", f); break;
        default: fputc(*p, f);
        }
    fputs(")</text>\n", f);

    /* Each cell's triangles, filled in the cell's colour, edges thin. */
    fputs("<g stroke=\"#404040\" stroke-width=\"0.3\" stroke-linejoin=\"round\">\n", f);
    for (uint32_t c = 0; c < n; c++) {
        const uint32_t *tris;
        uint32_t nt = emm_layout_cell_triangles(l, c, &tris);
        if (nt == 0)
            continue;
        fprintf(f, "<path fill=\"%s\" d=\"", palette[col[c]]);
        for (uint32_t i = 0; i < nt; i++) {
            const int32_t *t = tri + 3 * (size_t)tris[i];
            for (int k = 0; k < 3; k++) {
                const double *p = xyz + 3 * (size_t)t[k];
                fprintf(f, "%c%.2f %.2f", k == 0 ? 'M' : 'L', px(&v, p[axes[0]]),
                        py(&v, p[axes[1]]));
            }
            fputc('Z', f);
        }
        fputs("\"/>\n", f);
    }
    fputs("</g>\n", f);

    /* Cell boundaries, bold. */
    fputs("<g fill=\"none\" stroke=\"black\" stroke-width=\"1.6\">\n", f);
    for (uint32_t c = 0; c < n; c++) {
        const emm_layout_cell *cell = emm_layout_cell_get(l, c);
        fprintf(f, "<rect x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\"/>\n",
                px(&v, cell->lo[0]), py(&v, cell->hi[1]), (cell->hi[0] - cell->lo[0]) * v.scale,
                (cell->hi[1] - cell->lo[1]) * v.scale);
    }
    fputs("</g>\n</svg>\n", f);
}

/* Writes the SVG to a temporary file beside `out` and renames it into place. */
static int write_svg(const char *out, const emm_layout *l, const double *xyz, const int32_t *tri,
                     const char *path, const emm_strategy *s)
{
    emm_error err;
    unsigned char *col = colour_cells(l);
    if (!col) {
        cli_error("%s: out of memory", out);
        return EMM_EXIT_FAIL;
    }
    emm_outfile o;
    emm_status st = emm_outfile_open(&o, out, "the SVG", &err);
    if (st == EMM_OK) {
        write_svg_body(o.f, l, xyz, tri, path, s, col);
        st = emm_outfile_commit(&o, "the SVG", &err);
    }
    free(col);
    if (st != EMM_OK)
        return cli_fail(&err);
    char name[64];
    emm_strategy_format(s, name, sizeof name);
    printf("wrote %s: %s's %u cells over %zu triangles\n", out, name, emm_layout_cell_count(l),
           emm_layout_triangle_count(l));
    return EMM_EXIT_OK;
}

/* ---- --write: the mesh in the layout's order ------------------------------------------- */

/* The permutations: new_of_v[old] and old_of_t[new] / old_of_v[new]. */
typedef struct renumbering {
    uint32_t *old_of_v, *new_of_v, *old_of_t;
    size_t nv, nt;
} renumbering;

static void renumbering_free(renumbering *r)
{
    free(r->old_of_v);
    free(r->new_of_v);
    free(r->old_of_t);
}

static int renumber(const emm_layout *l, size_t nv, size_t nt, renumbering *r)
{
    r->nv = nv;
    r->nt = nt;
    r->old_of_v = malloc((nv ? nv : 1) * sizeof *r->old_of_v);
    r->new_of_v = malloc((nv ? nv : 1) * sizeof *r->new_of_v);
    r->old_of_t = malloc((nt ? nt : 1) * sizeof *r->old_of_t);
    if (!r->old_of_v || !r->new_of_v || !r->old_of_t)
        return -1;
    for (size_t v = 0; v < nv; v++)
        r->new_of_v[v] = UINT32_MAX;
    size_t kv = 0, kt = 0;
    for (uint32_t c = 0; c < emm_layout_cell_count(l); c++) {
        const uint32_t *tris, *verts;
        uint32_t n = emm_layout_cell_triangles(l, c, &tris);
        for (uint32_t i = 0; i < n; i++)
            r->old_of_t[kt++] = tris[i];
        n = emm_layout_cell_vertices(l, c, &verts);
        for (uint32_t i = 0; i < n; i++)
            if (r->new_of_v[verts[i]] == UINT32_MAX) { /* its home: the first cell */
                r->new_of_v[verts[i]] = (uint32_t)kv;
                r->old_of_v[kv++] = verts[i];
            }
    }
    for (size_t v = 0; v < nv; v++)
        if (r->new_of_v[v] == UINT32_MAX) {
            r->new_of_v[v] = (uint32_t)kv;
            r->old_of_v[kv++] = (uint32_t)v;
        }
    return kv == nv && kt == nt ? 0 : -1;
}

static int write_perm(const char *path, const renumbering *r)
{
    emm_error err;
    emm_outfile o;
    if (emm_outfile_open(&o, path, "the permutation", &err) != EMM_OK)
        return cli_fail(&err);
    fprintf(o.f, "vertices %zu\n", r->nv);
    for (size_t i = 0; i < r->nv; i++)
        fprintf(o.f, "%zu %u\n", i, r->old_of_v[i]);
    fprintf(o.f, "triangles %zu\n", r->nt);
    for (size_t i = 0; i < r->nt; i++)
        fprintf(o.f, "%zu %u\n", i, r->old_of_t[i]);
    if (emm_outfile_commit(&o, "the permutation", &err) != EMM_OK)
        return cli_fail(&err);
    return EMM_EXIT_OK;
}

/* Whether `path` ends in .obj (1), .off (0) or neither (-1). */
static int mesh_format(const char *path)
{
    const char *dot = strrchr(path, '.');
    if (!dot || strchr(dot, '/'))
        return -1;
    return strcasecmp(dot, ".obj") == 0 ? 1 : strcasecmp(dot, ".off") == 0 ? 0 : -1;
}

static int write_renumbered(const char *out, const char *perm, const emm_layout *l,
                            const double *xyz, size_t nv, const int32_t *tri, size_t nt,
                            const emm_strategy *s)
{
    emm_error err;
    renumbering r = {0};
    double *nxyz = malloc((nv ? nv : 1) * 3 * sizeof *nxyz);
    int32_t *ntri = malloc((nt ? nt : 1) * 3 * sizeof *ntri);
    int rc = EMM_EXIT_OK;
    emm_mesh *m = NULL;
    if (!nxyz || !ntri || renumber(l, nv, nt, &r) != 0) {
        cli_error("%s: out of memory for the renumbered mesh", out);
        rc = EMM_EXIT_FAIL;
        goto out;
    }
    for (size_t i = 0; i < nv; i++)
        memcpy(nxyz + 3 * i, xyz + 3 * (size_t)r.old_of_v[i], 3 * sizeof *nxyz);
    for (size_t i = 0; i < nt; i++)
        for (int k = 0; k < 3; k++)
            ntri[3 * i + k] = (int32_t)r.new_of_v[tri[3 * (size_t)r.old_of_t[i] + k]];
    emm_status st = emm_mesh_from_arrays(nxyz, nv, ntri, nt, out, &m, &err);
    if (st == EMM_OK)
        st = mesh_format(out) == 1 ? emm_mesh_write_obj(m, out, &err)
                                   : emm_mesh_write_off(m, out, &err);
    if (st != EMM_OK) {
        rc = cli_fail(&err);
        goto out;
    }
    if (perm && (rc = write_perm(perm, &r)) != EMM_EXIT_OK)
        goto out;
    char name[64];
    emm_strategy_format(s, name, sizeof name);
    printf("wrote %s: %zu vertices and %zu triangles in the order of %s's %u cells\n", out, nv,
           nt, name, emm_layout_cell_count(l));
    if (perm)
        printf("wrote %s: the permutation, 'NEW OLD' per line (vertices, then triangles)\n",
               perm);
out:
    emm_mesh_free(m);
    renumbering_free(&r);
    free(nxyz);
    free(ntri);
    return rc;
}

/* --help's default CELL. */
#define DEFAULT_CELL_TEXT "64"
_Static_assert(EMM_DEFAULT_CELL == 64u, "DEFAULT_CELL_TEXT is EMM_DEFAULT_CELL");

/* --local's and --pointer-bytes' value when not given: the machine's local
 * store and word. */
#define LOCAL_UNSET UINT64_MAX

static int layout(const char *mesh_path, const char *strategy, const char *svg, int stats,
                  uint64_t local, uint64_t vbytes, uint64_t tbytes, uint64_t pbytes,
                  const char *write, const char *perm)
{
    const char *cmd = "layout";
    emm_strategy s;
    emm_error err;
    emm_strategy_parse(strategy, &s, NULL); /* checked by opts_parse */
    if (s.layout == EMM_LAYOUT_ORIGINAL)
        return cli_usage_error(cmd,
                               "strategy '%s' keeps the original layout; give "
                               "LAYOUT+FETCH[@CELL] or cache@LAYOUT",
                               strategy);
    if (perm && !write)
        return cli_usage_error(cmd, "--perm %s goes with --write", perm);
    if (write && mesh_format(write) < 0)
        return cli_usage_error(cmd, "--write %s: the file must end in .off (OFF) or .obj (OBJ)",
                               write);
    if (!svg && !write)
        stats = 1;
    /* Only an EMM strategy moves whole cells into the local store. A
     * triangle's pointers to its vertices' copies are the machine's words. */
    if ((local == LOCAL_UNSET && s.kind == EMM_STRATEGY_EMM) || pbytes == LOCAL_UNSET) {
        emm_machine *m;
        if (emm_machine_new(&m, &err) != EMM_OK)
            return cli_fail(&err);
        if (local == LOCAL_UNSET)
            local = emm_machine_get(m, "local.bytes");
        if (pbytes == LOCAL_UNSET)
            pbytes = emm_machine_get(m, "word.bytes");
        emm_machine_free(m);
    }
    if (s.kind != EMM_STRATEGY_EMM)
        local = 0;

    emm_mesh *mesh;
    if (emm_mesh_open(mesh_path, &mesh, &err) != EMM_OK)
        return cli_fail(&err);
    const double *xyz = emm_mesh_positions(mesh);
    const int32_t *tri = emm_mesh_indices(mesh);
    emm_layout_options opt = {
        .kind = s.layout,
        .cell = s.cell,
        .vertex_bytes = (uint32_t)vbytes,
        .triangle_bytes = (uint32_t)tbytes,
        .pointer_bytes = (uint32_t)pbytes,
        .local_store = local,
        .fetch = s.fetch,
    };
    emm_layout *l;
    if (emm_layout_build(xyz, emm_mesh_vertex_count(mesh), tri, emm_mesh_triangle_count(mesh),
                         &opt, mesh_path, &l, &err) != EMM_OK) {
        emm_mesh_free(mesh);
        return cli_fail(&err);
    }
    int rc = EMM_EXIT_OK;
    if (svg)
        rc = write_svg(svg, l, xyz, tri, mesh_path, &s);
    if (rc == EMM_EXIT_OK && write)
        rc = write_renumbered(write, perm, l, xyz, emm_mesh_vertex_count(mesh), tri,
                              emm_mesh_triangle_count(mesh), &s);
    if (rc == EMM_EXIT_OK && stats)
        print_stats(l, mesh_path, &s);
    emm_layout_free(l);
    emm_mesh_free(mesh);
    return rc;
}

int emm_cmd_layout(int argc, char **argv)
{
    const char *mesh_path = NULL, *strategy = NULL, *svg = NULL, *write = NULL, *perm = NULL;
    int stats = 0;
    uint64_t local = LOCAL_UNSET, vbytes = EMM_THESIS_VERTEX_BYTES;
    uint64_t tbytes = EMM_THESIS_TRIANGLE_BYTES, pbytes = LOCAL_UNSET;
    opts_row rows[] = {
        {.name = "--strategy", .alias = "-s", .metavar = "S", .kind = OPT_STRATEGY,
         .dst = &strategy, .required = true,
         .help = "LAYOUT+FETCH[@CELL][:indexed] or cache@LAYOUT, e.g. tiles+convolution@64; "
                 "CELL is triangles per cell (default " DEFAULT_CELL_TEXT ")"},
        {.name = "--svg", .metavar = "FILE", .kind = OPT_TEXT, .dst = &svg,
         .help = "draw the mesh, each cell's triangles in its own colour and the cell "
                 "boundaries in bold (y up; a layout in space projected along its third "
                 "axis); written whole or not at all"},
        {.name = "--stats", .kind = OPT_FLAG, .dst = &stats,
         .help = "print cells, triangles and bytes per cell (min, median, max), duplicated "
                 "vertices, look-up bytes, quadtree or octree depths; the default when --svg is "
                 "not given"},
        {.name = "--write", .metavar = "OUT", .kind = OPT_TEXT, .dst = &write,
         .help = "write the mesh renumbered in the layout's cell order, OFF or OBJ by OUT's "
                 "extension (.off, .obj), whole or not at all; see below"},
        {.name = "--perm", .metavar = "FILE", .kind = OPT_TEXT, .dst = &perm,
         .help = "with --write: also write the permutation, 'NEW OLD' per line, vertices then "
                 "triangles (see below)"},
        {.name = "--local", .metavar = "BYTES", .kind = OPT_SIZE, .dst = &local,
         .help = "local store size (K, M, G allowed): a cell larger than it is an error for an "
                 "EMM strategy (default: the machine's, 256K; 0 = no check)"},
        {.name = "--vertex-bytes", .metavar = "N", .kind = OPT_U64, .dst = &vbytes, .min = 1,
         .max = 65536, .show_default = true,
         .help = "bytes of a vertex record"},
        {.name = "--triangle-bytes", .metavar = "N", .kind = OPT_U64, .dst = &tbytes, .min = 1,
         .max = 65536, .show_default = true, .help = "bytes of a triangle record"},
        {.name = "--pointer-bytes", .metavar = "N", .kind = OPT_U64, .dst = &pbytes, .min = 1,
         .max = 64,
         .help = "bytes of each of the 3 pointers a cell's triangle keeps to its vertices' "
                 "copies (thesis §4.1.1), which follow its record in the cell (default: the "
                 "machine's word.bytes, 4)"},
        {.metavar = "MESH", .kind = OPT_TEXT, .dst = &mesh_path, .required = true},
        OPTS_END,
    };
    opts o = {"layout", rows, usage};
    int rc;
    if (opts_parse(&o, argc, argv, &rc))
        return rc;
    return layout(mesh_path, strategy, svg, stats, local, vbytes, tbytes, pbytes, write, perm);
}
