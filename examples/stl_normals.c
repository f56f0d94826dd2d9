/* A mesh program that keeps its mesh as a triangle soup, as STL tools do
 * (admesh's facet array): it reads a binary STL file into one block of
 * 50-byte facets (a normal, three corners of three floats, a 2-byte
 * attribute), recomputes every facet's normal from its corners and writes
 * it back, and prints the facets, the distinct corner positions (the
 * vertices an indexed mesh of the same surface has), the area and a
 * checksum of the normals. It knows nothing of emm.
 *
 * Tagged by an EMM_TAG rule (README "Tagging a program you did not write"):
 *   soup:site=load_stl,stride=50,corners=12:f32
 *
 * usage: stl_normals MESH.stl [PASSES]   (default 3 passes) */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FACET 50 /* bytes of a binary STL facet */

/* Reads a binary STL file's facets into *facets (n records of FACET bytes,
 * as they are on disk); 0 on success. */
static __attribute__((noinline)) int load_stl(const char *path, unsigned char **facets,
                                              size_t *n)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return -1;
    unsigned char header[84];
    int rc = -1;
    if (fread(header, 1, sizeof header, f) != sizeof header)
        goto done;
    uint32_t count = (uint32_t)header[80] | (uint32_t)header[81] << 8 |
                     (uint32_t)header[82] << 16 | (uint32_t)header[83] << 24;
    if (count == 0)
        goto done;
    *facets = malloc((size_t)count * FACET);
    if (!*facets || fread(*facets, FACET, count, f) != count)
        goto done;
    *n = count;
    rc = 0;
done:
    fclose(f);
    return rc;
}

static void get3(const unsigned char *p, float *v)
{
    memcpy(v, p, 3 * sizeof *v);
}

/* Recomputes each facet's unit normal from its corners (right-hand rule)
 * and stores it in the facet; returns the total area. */
static double fix_normals(unsigned char *facets, size_t n)
{
    double area = 0;
    for (size_t i = 0; i < n; i++) {
        unsigned char *f = facets + i * FACET;
        float a[3], b[3], c[3];
        get3(f + 12, a);
        get3(f + 24, b);
        get3(f + 36, c);
        double u[3], w[3], nrm[3];
        for (int d = 0; d < 3; d++) {
            u[d] = (double)b[d] - a[d];
            w[d] = (double)c[d] - a[d];
        }
        nrm[0] = u[1] * w[2] - u[2] * w[1];
        nrm[1] = u[2] * w[0] - u[0] * w[2];
        nrm[2] = u[0] * w[1] - u[1] * w[0];
        double len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        area += 0.5 * len;
        float out[3] = {0, 0, 0};
        if (len > 0)
            for (int d = 0; d < 3; d++)
                out[d] = (float)(nrm[d] / len);
        memcpy(f, out, sizeof out);
    }
    return area;
}

static int cmp_corner(const void *x, const void *y)
{
    const float *a = x, *b = y;
    for (int d = 0; d < 3; d++)
        if (a[d] != b[d])
            return a[d] < b[d] ? -1 : 1;
    return 0;
}

/* The distinct corner positions (-0 and 0 alike). */
static size_t count_vertices(const unsigned char *facets, size_t n)
{
    float *c = malloc(9 * n * sizeof *c);
    if (!c)
        return 0;
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) {
            get3(facets + i * FACET + 12 + 12 * (size_t)k, c + 9 * i + 3 * (size_t)k);
            for (int d = 0; d < 3; d++)
                if (c[9 * i + 3 * (size_t)k + (size_t)d] == 0)
                    c[9 * i + 3 * (size_t)k + (size_t)d] = 0;
        }
    qsort(c, 3 * n, 3 * sizeof *c, cmp_corner);
    size_t distinct = 0;
    for (size_t i = 0; i < 3 * n; i++)
        distinct += i == 0 || cmp_corner(c + 3 * (i - 1), c + 3 * i) != 0;
    free(c);
    return distinct;
}

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 3) {
        fprintf(stderr, "usage: stl_normals MESH.stl [PASSES]\n");
        return 2;
    }
    long passes = argc == 3 ? strtol(argv[2], NULL, 10) : 3;
    unsigned char *facets = NULL;
    size_t n = 0;
    if (load_stl(argv[1], &facets, &n) != 0) {
        fprintf(stderr, "stl_normals: cannot read a binary STL file from %s\n", argv[1]);
        free(facets);
        return 1;
    }
    double area = 0;
    for (long i = 0; i < passes; i++)
        area = fix_normals(facets, n);
    double check = 0;
    for (size_t i = 0; i < n; i++) {
        float nrm[3];
        get3(facets + i * FACET, nrm);
        check += fabs((double)nrm[0]) + 2 * fabs((double)nrm[1]) + 3 * fabs((double)nrm[2]);
    }
    printf("facets %zu vertices %zu area %.6f checksum %.6f\n", n, count_vertices(facets, n),
           area, check);
    free(facets);
    return 0;
}
