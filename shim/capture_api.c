/* The api capture backend (docs/design.md "The mesh", the thesis' interface of
 * §5): a program that reads its mesh only through emm_mesh_vertex,
 * emm_mesh_triangle, emm_vertex_triangles, emm_triangle_vertices and
 * emm_triangle_neighbors is traced without tags. The shim interposes those
 * functions: every call is an access to the mesh's own vertex or triangle
 * record, and the mesh's two record arrays are tagged when it is opened
 * (emm_mesh_open, emm_mesh_generate, emm_mesh_from_arrays) and untagged when
 * it is freed. Calls made while the shim or the session runs are forwarded
 * untouched. */
#include <dlfcn.h>
#include <string.h>

#include "emm/mesh.h"
#include "shim.h"

/* The next definition of `name` (the C library's, or libemm's). */
#define REAL(name)                                        \
    static __typeof__(name) *real_##name;                 \
    if (!real_##name)                                     \
        real_##name = (__typeof__(name) *)dlsym(RTLD_NEXT, #name)

static bool wanted(void);
const struct shim_capture_ops shim_capture_api = {.wanted = wanted};

static bool api_active(void)
{
    return shim.ops == &shim_capture_api && emm_agent_active(shim.agent) && !shim_busy;
}

static const emm_vertex *real_vertex(const emm_mesh *m, uint32_t id)
{
    REAL(emm_mesh_vertex);
    return real_emm_mesh_vertex(m, id);
}

static const emm_triangle *real_triangle(const emm_mesh *m, uint32_t id)
{
    REAL(emm_mesh_triangle);
    return real_emm_mesh_triangle(m, id);
}

static void tag_mesh(const emm_mesh *m)
{
    shim_busy++;
    shim_flush_thread();
    emm_agent_tag_mesh(shim.agent, m);
    shim_leave();
}

emm_status emm_mesh_open(const char *path, emm_mesh **out, emm_error *err)
{
    REAL(emm_mesh_open);
    bool active = api_active();
    emm_status st = real_emm_mesh_open(path, out, err);
    if (st == EMM_OK && active)
        tag_mesh(*out);
    return st;
}

emm_status emm_mesh_from_arrays(const double *xyz, size_t nv, const int32_t *tri, size_t nt,
                                const char *name, emm_mesh **out, emm_error *err)
{
    REAL(emm_mesh_from_arrays);
    bool active = api_active();
    emm_status st = real_emm_mesh_from_arrays(xyz, nv, tri, nt, name, out, err);
    if (st == EMM_OK && active)
        tag_mesh(*out);
    return st;
}

emm_status emm_mesh_generate(const emm_gen_options *opt, emm_mesh **out, emm_error *err)
{
    REAL(emm_mesh_generate);
    bool active = api_active();
    emm_status st = real_emm_mesh_generate(opt, out, err);
    if (st == EMM_OK && active)
        tag_mesh(*out);
    return st;
}

void emm_mesh_free(emm_mesh *m)
{
    REAL(emm_mesh_free);
    if (m && api_active()) {
        shim_busy++;
        shim_flush_thread();
        emm_agent_untag_mesh(shim.agent, m);
        shim_leave();
    }
    real_emm_mesh_free(m);
}

const emm_vertex *emm_mesh_vertex(const emm_mesh *m, uint32_t id)
{
    const emm_vertex *v = real_vertex(m, id);
    if (api_active())
        shim_record((uintptr_t)v, sizeof *v, false);
    return v;
}

const emm_triangle *emm_mesh_triangle(const emm_mesh *m, uint32_t id)
{
    const emm_triangle *t = real_triangle(m, id);
    if (api_active())
        shim_record((uintptr_t)t, sizeof *t, false);
    return t;
}

size_t emm_vertex_triangles(const emm_mesh *m, uint32_t v, const int32_t **tris)
{
    REAL(emm_vertex_triangles);
    if (api_active())
        shim_record((uintptr_t)real_vertex(m, v), sizeof(emm_vertex), false);
    return real_emm_vertex_triangles(m, v, tris);
}

void emm_triangle_vertices(const emm_mesh *m, uint32_t t, int32_t out[3])
{
    REAL(emm_triangle_vertices);
    if (api_active())
        shim_record((uintptr_t)real_triangle(m, t) + offsetof(emm_triangle, v), 12, false);
    real_emm_triangle_vertices(m, t, out);
}

void emm_triangle_neighbors(const emm_mesh *m, uint32_t t, int32_t out[3])
{
    REAL(emm_triangle_neighbors);
    if (api_active())
        shim_record((uintptr_t)real_triangle(m, t) + offsetof(emm_triangle, n), 12, false);
    real_emm_triangle_neighbors(m, t, out);
}

/* A program written against the mesh interface, that keeps no arrays of its
 * own for the shim to watch. */
static bool wanted(void)
{
    return shim.config.tags.n == 0 && !emm_program_imports("emm_tag_vertices") &&
           (emm_program_imports("emm_mesh_vertex") || emm_program_imports("emm_mesh_triangle"));
}
