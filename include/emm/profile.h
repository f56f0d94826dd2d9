/* emm — the distance profile (thesis §5, Eq. 5.1; docs/profile.md).
 *
 * For the i-th element access with position p_i,
 *
 *     D_i = Σ_{k<i} ‖p_i − p_k‖                                  (Eq. 5.1)
 *
 * Positions have the dimension their caller chooses: 2, the plane of the
 * two largest extents of the mesh's bounding box (as the layouts see a mesh
 * today), or 3, x, y and z. They are scaled by the bounding box's diagonal
 * over those axes, so profiles of different meshes compare. An element
 * access is an access to a vertex (its coordinates) or a triangle (its
 * centroid); consecutive accesses to one element count once.
 *
 * Two methods compute D: an exact one, O(n²) in SIMD over up to two threads,
 * and a fast one, a tree code over the earlier accesses (a quadtree in the
 * plane, an octree in space) with a stated bound on its relative error,
 * the same in either dimension. emm_profile_compute picks by length.
 *
 * The profile is then reduced to a fixed-size feature vector
 * (emm_profile_features) that the strategy table (emm/table.h) compares. */
#ifndef EMM_PROFILE_H
#define EMM_PROFILE_H

#include "emm/common.h"
#include "emm/config.h"
#include "emm/trace.h"

#ifdef __cplusplus
extern "C" {
#endif

/* emm_profile_compute uses the exact method up to this many accesses (the
 * default window's) and the fast method beyond. It was 65,536; a window
 * that reads on to fill the local store (EMM_PROFILE_FILL_REACH) is 24,576
 * accesses long, where the exact method took 74 ms and the fast one 11 ms
 * (a random walk; largest relative error 1.3e-3), and make predict and
 * decision_quality gave the same answers with either (docs/profile.md
 * "Fast method and its bound"). */
#define EMM_PROFILE_EXACT_MAX 16384u
/* The fast method's default opening angle: a node's aggregate stands for its
 * points when r ≤ θ·d (r: the node's radius about its centroid, d: the
 * distance from the query to that centroid). The stated worst-case bound at
 * 0.45 is 0.105; the errors measured on access-like sequences are far lower
 * (bench/profile_speed: 1.5e-4 on 1,000,000 accesses, in 0.85 s on two
 * cores; tests/profile: at most 6.1e-4), so this is where speed and accuracy
 * meet. docs/profile.md. */
#define EMM_PROFILE_THETA 0.45
/* The default profile window, in element accesses. */
#define EMM_PROFILE_DEFAULT_WINDOW EMM_CONFIG_DEFAULT_WINDOW
/* A window reads on past its length, to at most this many times it, while
 * the distinct records it has read are fewer bytes than the machine's local
 * store (docs/profile.md "The window"): a window that never filled the
 * store cannot show which cells the run evicts and fetches again. On make
 * predict 1.5 and 1.75 took the worst case from 31.60 % to 25.56 %; 1.25
 * left it at 32.11 %, 2 made another case 34.45 % off. */
#define EMM_PROFILE_FILL_REACH 1.5
/* The most element accesses a window of `window` reads when it fills. */
EMM_API uint64_t emm_profile_fill_most(uint64_t window);
/* The shortest profile that has features. */
#define EMM_PROFILE_MIN 256u
/* Positions in the plane of the mesh's two largest extents: what the
 * session, the decision and the tools profile today, since the layouts and
 * the synthetic traversals see a mesh in that plane too. */
#define EMM_PROFILE_PLANE 2u

/* Exact Eq. 5.1. `pos` holds n positions of `dims` coordinates each (2 or
 * 3; anything else is a misuse): x0, y0, x1, y1, ... in the plane, x0, y0,
 * z0, x1, ... in space; D receives n values (D[0] = 0). Double precision
 * throughout: the result differs from a naive double loop only by
 * summation order (relative 1e-12 at most for any n this is meant for).
 * Uses AVX2 when the processor has it, SSE2 otherwise, and up to two
 * threads (`threads` may allow fewer; NULL: two). */
EMM_API void emm_profile_exact(const double *pos, size_t n, uint32_t dims, double *D,
                               const emm_threads *threads);

/* The fast method's bound on the relative error of every D_i for opening
 * angle theta (0 < theta < 1): each term ‖p − q‖ a node's aggregate stands
 * for is replaced by its second-order Taylor expansion about the node's
 * centroid, whose remainder is at most (1/(3√3))·r³/(d−r)² per point, while
 * the term itself is at least d − r; so the relative error of the sum is at
 * most (1/(3√3))·(θ/(1−θ))³, in the plane and in space alike. */
EMM_API double emm_profile_fast_bound(double theta);

/* Fast Eq. 5.1 over n positions of `dims` coordinates (as for
 * emm_profile_exact): an incremental tree over the earlier positions — a
 * quadtree for 2, an octree for 3 — whose nodes keep count, first and
 * second moments and the bounding box of their points; a node far enough
 * (r ≤ θ·d) contributes its multipole sum, a near leaf its points one by
 * one. Relative error at most emm_profile_fast_bound(theta). Two threads,
 * each with its own tree over its half of the queries. Fails with
 * EMM_ERR_RANGE for theta outside (0, 1), and when memory runs out. */
EMM_API emm_status emm_profile_fast(const double *pos, size_t n, uint32_t dims, double theta,
                                    double *D, const emm_threads *threads, emm_error *err);

/* Exact when n ≤ EMM_PROFILE_EXACT_MAX, fast with EMM_PROFILE_THETA beyond.
 * *exact (may be NULL) tells which ran. */
EMM_API emm_status emm_profile_compute(const double *pos, size_t n, uint32_t dims, double *D,
                                       int *exact, const emm_threads *threads, emm_error *err);

/* Reduces a profile of n ≥ EMM_PROFILE_MIN values to EMM_FEATURES numbers
 * (documented in docs/profile.md): the shape of the mean distance
 * m_i = D_i / i on a log scale of i, how fast it grows, how much it jumps,
 * and how its change over a lag of L accesses grows with L (locality across
 * scales, which makes the Z-order and Gray-code orders of thesis Fig. 5.3
 * alike). The values do not depend on the mesh's size or on n for a given
 * shape. Returns EMM_ERR_RANGE (naming `name`) when n is too short. */
#define EMM_FEATURES 19
EMM_API emm_status emm_profile_features(const double *D, size_t n, const char *name,
                                        double f[EMM_FEATURES], emm_error *err);

/* Collects the positions of a trace's element accesses. Build one from the
 * trace's description, feed it records in order, and stop when it is full.
 * `name` names the trace in error messages. */
typedef struct emm_profiler emm_profiler;

/* The most element accesses of a leading index-order sweep that a profile
 * leaves out (docs/profile.md "The leading sweep"): a sweep over every
 * triangle of a 2M-face mesh. The session keeps the sweep's records until
 * the decision (some 32 bytes each), so this bounds that memory. */
#define EMM_PROFILE_SWEEP_MAX 2097152u

/* Positions of `dims` coordinates (2: EMM_PROFILE_PLANE, the plane of the
 * mesh's two largest extents; 3: x, y and z; anything else is a misuse).
 * Fails with EMM_ERR_UNSUPPORTED when no array of the trace has positions
 * (an address-only trace: RAW arrays, or no geometry). window = 0 means
 * EMM_PROFILE_DEFAULT_WINDOW. */
EMM_API emm_status emm_profiler_new(const emm_trace_info *info, uint64_t window, uint32_t dims,
                                    const char *name, emm_profiler **out, emm_error *err);
/* The coordinates of each position (the `dims` it was built with). */
EMM_API uint32_t emm_profiler_dims(const emm_profiler *p);
/* Makes p's window read on past its length, up to
 * emm_profile_fill_most(window) element accesses, until the distinct
 * records it has read (each array's record_size bytes, the leading sweep
 * left out) are `bytes` or more: the local store's bytes, for a window a
 * decision on that machine is to be made on — unless the trace's vertex
 * and triangle records are `bytes` or fewer (the mesh fits the store). 0:
 * the window is exact (the default). Call it before the first
 * emm_profiler_add. */
EMM_API void emm_profiler_fill(emm_profiler *p, uint64_t bytes);
/* Adds records; records of RAW arrays are skipped, and so is a leading
 * index-order sweep (docs/profile.md "The leading sweep": element 0, 1, 2,
 * ... of the arrays before the traversal; at most EMM_PROFILE_SWEEP_MAX
 * element accesses), which does not count towards the window. An element
 * outside the geometry is an error. Records after the window is full are
 * ignored. */
EMM_API emm_status emm_profiler_add(emm_profiler *p, const emm_trace_record *recs, size_t n,
                                    emm_error *err);
/* The element accesses of the leading sweep left out so far; *records
 * (when not NULL) receives how many of the records added belong to it (the
 * window proper starts after them). */
EMM_API uint64_t emm_profiler_swept(const emm_profiler *p, size_t *records);
/* True once `window` element accesses are collected. */
EMM_API int emm_profiler_full(const emm_profiler *p);
/* The positions so far, emm_profiler_dims(p) coordinates each (x0, y0, x1,
 * y1, ... in the plane), owned by p; *n receives their count. */
EMM_API const double *emm_profiler_positions(const emm_profiler *p, size_t *n);
EMM_API void emm_profiler_free(emm_profiler *p);

/* Reads a trace from its first record until `window` element accesses
 * (0: EMM_PROFILE_DEFAULT_WINDOW) or its end and returns their positions,
 * `dims` coordinates each (as for emm_profiler_new), in *pos (malloc'd, the
 * caller frees) and their count in *n. */
EMM_API emm_status emm_profile_trace_positions(emm_trace_reader *r, uint64_t window,
                                               uint32_t dims, const char *name, double **pos,
                                               size_t *n, emm_error *err);

/* Reads a trace from its first record until `window` element accesses
 * (0: EMM_PROFILE_DEFAULT_WINDOW) or its end and returns those records
 * (RAW ones included, as the simulation needs them) in *recs (malloc'd,
 * the caller frees) and their count in *n: the window the session decides
 * on. */
EMM_API emm_status emm_profile_trace_window(emm_trace_reader *r, uint64_t window,
                                            const char *name, emm_trace_record **recs,
                                            size_t *n, emm_error *err);
/* The same window reading on until its distinct records are `fill` bytes
 * (emm_profiler_fill; 0: exact): the window a decision on a machine with a
 * local store of `fill` bytes is made on. *length (may be NULL) receives
 * the records up to where its element accesses reached `window`, before it
 * read on (*n when it did not): the unit the session's contest counts in. */
EMM_API emm_status emm_profile_trace_window_fill(emm_trace_reader *r, uint64_t window,
                                                 uint64_t fill, const char *name,
                                                 emm_trace_record **recs, size_t *n,
                                                 size_t *length, emm_error *err);

#ifdef __cplusplus
}
#endif
#endif
