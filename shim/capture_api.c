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
#include <elf.h>
#include <link.h>
#include <string.h>

#include "emm/mesh.h"
#include "shim.h"

/* The next definition of `name` (the C library's, or libemm's). */
#define REAL(name)                                        \
    static __typeof__(name) *real_##name;                 \
    if (!real_##name)                                     \
        real_##name = (__typeof__(name) *)dlsym(RTLD_NEXT, #name)

static bool wanted(void);
const struct shim_capture_ops shim_capture_api = {.kind = EMM_CAPTURE_API, .wanted = wanted};

static bool api_active(void)
{
    return shim.ops == &shim_capture_api && shim.enabled && !shim.finished && !shim_busy;
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

/* The records of a mesh are two arrays; their stride is the distance
 * between the first two records. */
static void tag_mesh(const emm_mesh *m)
{
    shim_busy++;
    size_t nv = emm_mesh_vertex_count(m), nt = emm_mesh_triangle_count(m);
    const char *v0 = nv ? (const char *)real_vertex(m, 0) : NULL;
    const char *t0 = nt ? (const char *)real_triangle(m, 0) : NULL;
    size_t vs = nv > 1 ? (size_t)((const char *)real_vertex(m, 1) - v0) : sizeof(emm_vertex);
    size_t ts = nt > 1 ? (size_t)((const char *)real_triangle(m, 1) - t0) : sizeof(emm_triangle);
    shim_busy--;
    if (v0)
        shim_tag_array(EMM_ARRAY_VERTICES, v0, nv * vs, vs, offsetof(emm_vertex, xyz), EMM_F64,
                       -1, NULL, 0);
    if (t0)
        shim_tag_array(EMM_ARRAY_TRIANGLES, t0, nt * ts, ts, offsetof(emm_triangle, v), EMM_I32,
                       -1, NULL, 0);
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
    if (m && shim.ops == &shim_capture_api && shim.enabled && !shim_busy) {
        shim_busy++;
        const void *v0 = emm_mesh_vertex_count(m) ? (const void *)real_vertex(m, 0) : NULL;
        const void *t0 = emm_mesh_triangle_count(m) ? (const void *)real_triangle(m, 0) : NULL;
        shim_busy--;
        if (v0)
            shim_untag_array(v0);
        if (t0)
            shim_untag_array(t0);
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

/* --- what the program imports ------------------------------------------ */

struct import_query {
    const char *name;
    bool found;
};

static uintptr_t dyn_addr(const struct dl_phdr_info *info, ElfW(Addr) v)
{
    /* ld.so relocates the main program's dynamic entries in place on most
     * targets, but not on all. */
    return v < info->dlpi_addr ? info->dlpi_addr + v : v;
}

static int first_object(struct dl_phdr_info *info, size_t size, void *arg)
{
    (void)size;
    struct import_query *q = arg;
    const ElfW(Dyn) *dyn = NULL;
    for (int i = 0; i < info->dlpi_phnum; i++)
        if (info->dlpi_phdr[i].p_type == PT_DYNAMIC)
            dyn = (const ElfW(Dyn) *)(info->dlpi_addr + info->dlpi_phdr[i].p_vaddr);
    if (!dyn)
        return 1;
    const ElfW(Sym) *symtab = NULL;
    const char *strtab = NULL;
    for (; dyn->d_tag != DT_NULL; dyn++) {
        if (dyn->d_tag == DT_SYMTAB)
            symtab = (const ElfW(Sym) *)dyn_addr(info, dyn->d_un.d_ptr);
        else if (dyn->d_tag == DT_STRTAB)
            strtab = (const char *)dyn_addr(info, dyn->d_un.d_ptr);
    }
    /* The symbol table ends where the string table starts, as the linkers
     * lay them out. */
    if (!symtab || !strtab || (const void *)strtab <= (const void *)symtab)
        return 1;
    size_t n = (size_t)((const char *)strtab - (const char *)symtab) / sizeof(ElfW(Sym));
    for (size_t i = 1; i < n; i++)
        if (symtab[i].st_shndx == SHN_UNDEF && strcmp(strtab + symtab[i].st_name, q->name) == 0) {
            q->found = true;
            break;
        }
    return 1; /* only the main program */
}

static bool imports(const char *name)
{
    struct import_query q = {name, false};
    dl_iterate_phdr(first_object, &q);
    return q.found;
}

/* A program written against the mesh interface, that keeps no arrays of its
 * own for the shim to watch. */
static bool wanted(void)
{
    return shim.config.tags.n == 0 && !imports("emm_tag_vertices") &&
           (imports("emm_mesh_vertex") || imports("emm_mesh_triangle"));
}
