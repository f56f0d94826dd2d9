/* emm — common definitions: export macro, status codes, error messages.
 *
 * Every function that can fail on bad data from outside (mesh files, traces,
 * tables, configuration, environment) returns an emm_status and, when the
 * caller passes an emm_error, fills it with one line naming the input and the
 * problem. A programmer's misuse (NULL where the contract forbids it, an id
 * out of range in a query) is an assert, not a status. The library never
 * prints and never exits. */
#ifndef EMM_COMMON_H
#define EMM_COMMON_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define EMM_API __attribute__((visibility("default")))

typedef enum emm_status {
    EMM_OK = 0,
    EMM_ERR_IO,          /* a file is missing, unreadable or unwritable */
    EMM_ERR_FORMAT,      /* a file's content is malformed or truncated */
    EMM_ERR_CORRUPT,     /* a checksum does not match */
    EMM_ERR_MESH,        /* the mesh is not a valid manifold triangle mesh */
    EMM_ERR_INVALID,     /* a value (option, key, strategy string) is not accepted */
    EMM_ERR_RANGE,       /* a value is outside its accepted range */
    EMM_ERR_NOMEM,       /* an allocation failed */
    EMM_ERR_UNSUPPORTED, /* valid, but not something this build can do */
    EMM_STATUS_COUNT
} emm_status;

/* The message buffer of a failed call: "<input>: <problem>", one line,
 * no trailing newline. */
typedef struct emm_error {
    emm_status status;
    char message[512];
} emm_error;

/* Scalar type of a field inside a record. */
typedef enum emm_scalar {
    EMM_F32 = 0,
    EMM_F64,
    EMM_I32,
    EMM_U32,
    EMM_I64,
    EMM_U16
} emm_scalar;

/* The most coordinates a layout, a cell or a point of the interface has.
 * Layouts work in the plane of the mesh's two largest extents today
 * (emm_layout_axes says how many they use); the interface is the same for
 * a layout over all three. */
#define EMM_MAX_DIMS 3

/* What the records of a tagged or traced array hold. */
typedef enum emm_array_kind {
    EMM_ARRAY_VERTICES = 0,  /* records hold a vertex's coordinates */
    EMM_ARRAY_TRIANGLES = 1, /* records hold a triangle's vertex indices */
    EMM_ARRAY_RAW = 2        /* plain memory: element = byte address (din import) */
} emm_array_kind;

/* The bytes the thesis' structs take on a 64-bit host: struct Vertex
 * {unsigned name; double coor[3]; int vfConnec[12];} is 80 bytes and
 * struct Triangle {unsigned name; int vertexIndices[3]; int neighbors[3];}
 * is 28 bytes (thesis §3.1). */
#define EMM_THESIS_VERTEX_BYTES 80u
#define EMM_THESIS_TRIANGLE_BYTES 28u

/* How a library call may use threads. A call that takes a `const
 * emm_threads *` accepts NULL for the defaults (every online CPU, no hook).
 * Helper threads start with every signal blocked, so the program's signals
 * never land on them, and call on_start (when set) before anything else:
 * libemmshim.so marks them there as its own, so their allocations are never
 * taken for the program's. Results never depend on the number of threads. */
typedef struct emm_threads {
    unsigned jobs;               /* threads in all, the caller included; 0: the online CPUs */
    void (*on_start)(void *ctx); /* called first in each helper thread; may be NULL */
    void *ctx;
} emm_threads;

/* A short, static description of a status ("malformed file", ...). */
EMM_API const char *emm_strerror(emm_status status);

/* The library's version as "MAJOR.MINOR.PATCH". */
EMM_API const char *emm_version(void);

#ifdef __cplusplus
}
#endif
#endif
