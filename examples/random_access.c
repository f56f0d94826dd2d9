/* random_access — the random-access workload of thesis §4.3.3: the sorting
 * step of curve tracing, where the vertices' tension vectors are sorted by
 * magnitude.
 *
 * The vertex ids are sorted with qsort by the magnitude of the tension field
 * (workload.c, field_at; the same field curve_tracing uses) at each vertex,
 * ties broken by id. The comparator evaluates the field from the two vertex
 * records' coordinates every time, so the sort reads the vertex array in the
 * data-dependent, scattered order the thesis calls random access.
 *
 * Output: "vertices: N\nchecksum: 0x...\n", the checksum being FNV-1a 64 of
 * the sorted order as `--print-order` prints it: one decimal id per line,
 * each line ending in '\n'. */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "workload.h"

#define PROG "random_access"

static void usage(FILE *out)
{
    fputs("usage: " PROG " [--field tension|uniform] [--print-order] [--times] [MESH]\n"
          "\n"
          "Sorts the vertices of a triangle mesh by the magnitude of the tension vector\n"
          "at each (thesis section 4.3.3) and prints their number and a checksum of the\n"
          "sorted order. MESH is an OFF, OBJ, PLY or STL file; without it the default\n"
          "mesh (20,000 clustered faces, seed 1) is generated in memory.\n"
          "\n"
          "  --field F        tension (default) or uniform (the constant field (1, 0))\n"
          "  --print-order    also print the sorted vertex ids, one per line, first\n"
          "  --times          print load and traversal seconds on stderr\n",
          out);
}


/* qsort's comparator has no context argument; this program sorts once. */
static const struct Mesh *sort_mesh;
static const struct field *sort_field;

static double magnitude2(int32_t v)
{
    const double *c = sort_mesh->vertices[v].coor;
    double t[2];
    field_at(sort_field, c[0], c[1], t);
    return t[0] * t[0] + t[1] * t[1];
}

static int by_tension(const void *pa, const void *pb)
{
    int32_t a = *(const int32_t *)pa, b = *(const int32_t *)pb;
    double ma = magnitude2(a), mb = magnitude2(b);
    if (ma != mb)
        return ma < mb ? -1 : 1;
    return (a > b) - (a < b);
}

int main(int argc, char **argv)
{
    struct workload_args args = {NULL, false};
    bool print = false;
    enum field_kind kind = FIELD_TENSION;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(a, "--print-order") == 0) {
            print = true;
        } else if (strcmp(a, "--field") == 0) {
            if (i + 1 >= argc)
                return workload_usage_error(PROG, "option needs a value", a);
            if (!field_parse(argv[++i], &kind))
                return workload_usage_error(PROG, "--field accepts tension or uniform, not", argv[i]);
        } else {
            int rc = workload_common_arg(&args, PROG, a);
            if (rc)
                return rc;
        }
    }

    double t0 = workload_now();
    struct Mesh mesh;
    if (!read_mesh(PROG, args.mesh, &mesh))
        return 1;
    double t1 = workload_now();

    struct field f;
    field_init(&f, kind, &mesh);
    size_t nv = mesh.verNr;
    int32_t *order = malloc((nv ? nv : 1) * sizeof *order);
    if (!order) {
        fprintf(stderr, PROG ": out of memory\n");
        return 1;
    }
    for (size_t v = 0; v < nv; v++)
        order[v] = (int32_t)v;
    sort_mesh = &mesh;
    sort_field = &f;
    qsort(order, nv, sizeof *order, by_tension);

    uint64_t h = FNV1A64_INIT;
    char line[16];
    for (size_t i = 0; i < nv; i++) {
        snprintf(line, sizeof line, "%" PRId32, order[i]);
        h = fnv1a64_line(h, line);
        if (print)
            puts(line);
    }
    double t2 = workload_now();

    printf("vertices: %zu\nchecksum: 0x%016" PRIx64 "\n", nv, h);
    workload_report_times(&args, t0, t1, t2);
    free(order);
    free_mesh(&mesh);
    return 0;
}
