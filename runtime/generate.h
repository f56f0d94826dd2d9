/* Internal: the generator's stages, exposed so tests can check each one
 * without going through emm_mesh_from_arrays. */
#ifndef EMM_INTERNAL_GENERATE_H
#define EMM_INTERNAL_GENERATE_H

#include <stdbool.h>

#include "emm/mesh.h"

/* The generator's deterministic random stream (xoshiro256**, seeded through
 * splitmix64 so that nearby seeds give unrelated streams). */
typedef struct emm_rng {
    uint64_t s[4];
} emm_rng;

void emm_rng_seed(emm_rng *r, uint64_t seed);
uint64_t emm_rng_next(emm_rng *r);
/* Uniform in [0, 1), 53 bits. */
double emm_rng_uniform(emm_rng *r);

/* A 2D Delaunay triangulation of `n` points (`xy` holds 2*n coordinates),
 * computed with libqhull_r. On success *tri (3 * *nt vertex indices, owned by
 * the caller, free with free()) lists every triangle counter-clockwise;
 * zero-area triangles are left out and counted in *degenerate (may be NULL).
 * Points that are not a vertex of any triangle (exact duplicates) are simply
 * not referenced. Fails with EMM_ERR_INVALID when qhull rejects the input
 * (fewer than 3 points, all collinear) and EMM_ERR_NOMEM when memory runs
 * out; the message carries qhull's own first line. */
emm_status emm_delaunay_2d(const double *xy, size_t n, int32_t **tri, size_t *nt,
                           size_t *degenerate, emm_error *err);

/* The generator's output before it becomes an emm_mesh: `xyz` holds 3*nv
 * coordinates (z = 0), `tri` 3*nt counter-clockwise vertex indices; every
 * vertex is used by some triangle. `hull` is the number of convex-hull
 * vertices the point set was built with, `attempts` how many triangulations
 * it took to reach the face count. */
typedef struct emm_gen_arrays {
    double *xyz;
    size_t nv;
    int32_t *tri;
    size_t nt;
    size_t hull;
    unsigned attempts;
} emm_gen_arrays;

/* The hull's point count for a mesh of `faces` triangles: about
 * sqrt(2 * faces), at least 4, of the same parity as faces. */
size_t emm_gen_hull_points(size_t faces);

/* Builds the point set for `opt` and triangulates it (see
 * emm_mesh_generate). On success `out` owns two buffers; release them with
 * emm_gen_arrays_free. */
emm_status emm_gen_arrays_build(const emm_gen_options *opt, emm_gen_arrays *out, emm_error *err);
void emm_gen_arrays_free(emm_gen_arrays *a);

/* The `random` order's key of element i under `seed` (splitmix64), and the
 * sort record both orders use: by key, ties keeping the lower index first. */
uint64_t emm_gen_random_key(uint64_t seed, uint64_t i);
typedef struct emm_gen_keyed {
    uint64_t key;
    uint32_t index;
} emm_gen_keyed;
int emm_gen_keyed_cmp(const void *a, const void *b);

/* The position of the point x (each of its three coordinates `bits` bits,
 * 1 to 21) along a 3D Hilbert curve of that order; x is overwritten. The
 * generator's 3D `hilbert` order and the 3D synthetic patterns use it. */
uint64_t emm_hilbert3(uint32_t x[3], int bits);

/* The 3D surfaces (sphere, torus, terrain; runtime/generate_surface.c):
 * `out` as emm_gen_arrays_build fills it, with hull 0 and attempts 1
 * (EMM_SURFACE_PLANE is emm_gen_arrays_build itself). Fails with EMM_ERR_RANGE naming the surface when
 * `faces` is not a count it can make (odd or below the minimum for the
 * closed ones). */
emm_status emm_gen_surface_build(const emm_gen_options *opt, emm_surface surface,
                                 emm_gen_arrays *out, emm_error *err);

/* Largest face count the generator accepts (indices are int32_t and qhull
 * counts points in an int). */
#define EMM_GEN_MAX_FACES 200000000u
/* Smallest: the fixed hull plus a few interior points. */
#define EMM_GEN_MIN_FACES 8u
/* Smallest sphere or torus: each strip needs a few turns of at least four
 * vertices around. */
#define EMM_GEN_MIN_CLOSED_FACES 20u

#endif
