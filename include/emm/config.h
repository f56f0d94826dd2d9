/* emm — the configuration: every EMM_* variable and `emm run` option, one
 * table (after mimalloc's options.c; docs/design.md "The shim and the session").
 *
 * Each row names the environment variable, the `emm run` option, what it
 * accepts, its default and its help, and parses its value into an
 * emm_config that holds *parsed* values (an emm_strategy, not text). The
 * shim reads the environment through it, `emm run` its options, and both
 * print their help and their verbose dump from the same rows. What a row
 * can check from the value alone (a file exists, a directory is writable, a
 * strategy or a tag rule is well formed) it checks; the content of a
 * machine file or a table is checked when a session starts with the
 * config, and every message names the variable or the option the value
 * came from (emm_config.source). */
#ifndef EMM_CONFIG_H
#define EMM_CONFIG_H

#include <stdio.h>

#include "emm/common.h"
#include "emm/strategy.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What a capture backend gives. The layers above the shim ask these
 * (emm_capture_caps), never which backend it is. */
typedef enum emm_capture_cap {
    EMM_CAP_WHOLE_RUN = 1u << 0,     /* it sees the run past the profiling window: the whole run
                                        is simulated (without it, the window only) */
    EMM_CAP_PCS = 1u << 1,           /* each access carries its program counter (source lines,
                                        emm annotate) */
    EMM_CAP_WORK = 1u << 2,          /* each access carries the work done since the previous one
                                        (instructions or instrumented edges) */
    EMM_CAP_THREADS_EXACT = 1u << 3, /* the accesses of several threads come in the order they
                                        ran (without it, approximately) */
    EMM_CAP_VALGRIND = 1u << 4       /* the program runs under emm's Valgrind tool, which emm run
                                        starts; the session then runs natively in a process of
                                        its own (emm-session) */
} emm_capture_cap;

/* The capture backends, one X(NAME, name, capabilities, work, help) each, in
 * the order EMM_CAPTURE=auto tries them; the last is the one it falls back
 * to. `work` names the unit of the records' work field for a backend with
 * EMM_CAP_WORK (NULL without): charged only at compute.per_work cycles a
 * unit (docs/machine.md "Compute"). The enum, the names EMM_CAPTURE
 * accepts, its help and the shim's table of backends (one
 * shim/capture_name.c each) follow this list. */
#define EMM_CAPTURE_LIST(X)                                                                   \
    X(VALGRIND, valgrind,                                                                     \
      EMM_CAP_WHOLE_RUN | EMM_CAP_PCS | EMM_CAP_WORK | EMM_CAP_THREADS_EXACT | EMM_CAP_VALGRIND, \
      "superblocks", "emm's Valgrind tool, the whole run of an unmodified binary; emm run starts it") \
    X(SANCOV, sancov, EMM_CAP_WHOLE_RUN | EMM_CAP_PCS | EMM_CAP_WORK, "edges",                 \
      "a build with emm_sancov_executable")                                                   \
    X(API, api, EMM_CAP_WHOLE_RUN, NULL, "programs using emm_mesh_*")                        \
    X(FAULT, fault, 0, NULL, "page protection, profiling window only")

/* How accesses are captured: EMM_CAPTURE_AUTO (the shim picks), then the
 * list's backends. */
typedef enum emm_capture {
    EMM_CAPTURE_AUTO = 0,
#define EMM_CAPTURE_ENUM_(N, n, caps, work, help) EMM_CAPTURE_##N,
    EMM_CAPTURE_LIST(EMM_CAPTURE_ENUM_)
#undef EMM_CAPTURE_ENUM_
    EMM_CAPTURE_COUNT
} emm_capture;

/* "auto", "sancov", ... ("?" for other values). */
EMM_API const char *emm_capture_name(emm_capture c);
/* The backend's capabilities (emm_capture_cap bits); 0 for auto and for
 * other values. */
EMM_API unsigned emm_capture_caps(emm_capture c);
/* The unit of the backend's records' work field ("edges", "superblocks"),
 * or NULL when it counts none (no EMM_CAP_WORK), for auto and for other
 * values. */
EMM_API const char *emm_capture_work_unit(emm_capture c);

/* What the session simulates beside the chosen strategy. */
typedef enum emm_compare {
    EMM_COMPARE_BASELINES = 0, /* direct reads and the cache */
    EMM_COMPARE_ALL,           /* the whole standard sweep */
    EMM_COMPARE_NONE,          /* the chosen strategy only */
    EMM_COMPARE_COUNT
} emm_compare;

/* "baselines", "all", "none" ("?" for other values). */
EMM_API const char *emm_compare_name(emm_compare c);

/* ---- EMM_TAG rules ------------------------------------------------------- */

#define EMM_TAG_SITE_MAX 128

/* How a rule's block holds its records. */
typedef enum emm_tag_shape {
    EMM_TAG_RECORDS = 0, /* records of `stride` bytes, the three scalars in a row at `offset`
                            (x y z x y z ...) */
    EMM_TAG_COLUMNS,     /* order=columns: three columns of n entries of `stride` bytes, the
                            block's first third the x's (or first corners), then the y's, then
                            the z's (Eigen's column-major V and F); a scalar at `offset` in each
                            entry */
    EMM_TAG_SOUP,        /* soup: triangle records of `stride` bytes holding their three
                            corners inline, nine coordinates in a row at `offset` (STL facets) */
    EMM_TAG_AXIS,        /* x=, y= or z=: one coordinate of every vertex, an entry of `stride`
                            bytes each with its scalar at `offset` (structure of arrays: x at
                            one base, y at another); the session joins a mesh's x, y (and z)
                            blocks of one count, same stride and type, into its vertices */
    EMM_TAG_HALFEDGES,   /* halfedges: half-edge records of `stride` bytes (kind TRIANGLES):
                            the to-vertex index at `offset`, next, prev, face and opposite
                            half-edge indices at link[] (prev and opp may be absent: opp is
                            then h ^ 1, OpenMesh's, CGAL's and PMP's pairing) */
    EMM_TAG_FACES,       /* faces: a face's records (kind TRIANGLES) holding one half-edge of
                            its cycle at `offset` */
    EMM_TAG_VCONN        /* vconn: a vertex's connectivity records (kind VERTICES) holding one
                            outgoing half-edge at `offset` */
} emm_tag_shape;

/* A half-edge record's fields besides its to-vertex: emm_tag_rule.link[]
 * and emm_array_desc.link[], byte offsets in the record, EMM_TAG_NO_LINK
 * for a field the record does not have. */
enum { EMM_TAG_LINK_NEXT = 0, EMM_TAG_LINK_PREV, EMM_TAG_LINK_FACE, EMM_TAG_LINK_OPP, EMM_TAG_LINKS };
#define EMM_TAG_NO_LINK UINT32_MAX

/* Whether a shape is half-edge connectivity (halfedges:, faces:, vconn:). */
static inline int emm_tag_shape_is_connectivity(emm_tag_shape s)
{
    return s == EMM_TAG_HALFEDGES || s == EMM_TAG_FACES || s == EMM_TAG_VCONN;
}

/* One rule: which allocations are a mesh array (site, min, nth) and where
 * the coordinates or vertex indices sit in each record. */
typedef struct emm_tag_rule {
    emm_array_kind kind;          /* VERTICES or TRIANGLES (a soup's records are triangles; a
                                     half-edge rule's and a faces rule's are the triangles'
                                     connectivity, a vconn rule's the vertices') */
    emm_tag_shape shape;
    char site[EMM_TAG_SITE_MAX];  /* a function on the allocation's stack; "" for any */
    uint64_t min;                 /* the smallest block selected, in bytes (>= one record) */
    uint64_t nth;                 /* only the nth block the other selectors select; 0: all */
    uint64_t n;                   /* order=columns: entries per column (the block is then
                                     3 * n * stride bytes); 0: the block's size says */
    uint32_t stride;              /* bytes per record (per column entry for order=columns, per
                                     entry of one coordinate for an axis rule) */
    uint32_t axis;                /* EMM_TAG_AXIS: the coordinate, 0 x, 1 y, 2 z; else 0 */
    uint32_t offset;              /* where the scalars start in a record (an entry) */
    emm_scalar type;              /* f32|f64 for vertices and soups, i32|u32|u16|i64 for
                                     triangles and the half-edge kinds */
    uint32_t link[EMM_TAG_LINKS]; /* EMM_TAG_HALFEDGES: next, prev, face, opp offsets (of
                                     `type`), EMM_TAG_NO_LINK when absent; else all absent */
    uint8_t alternative;          /* a preset's rule (--tag openmesh): one of several ways a
                                     library allocates an array (reserve or growth); it says
                                     nothing at exit for matching nothing when a rule of its
                                     kind and shape tagged */
} emm_tag_rule;

/* The rules, as many as EMM_TAG has: rule[0..n), malloc'ed (NULL when n is
 * 0), owned by whoever parsed them (emm_tag_rules_free). */
typedef struct emm_tag_rules {
    size_t n;
    emm_tag_rule *rule;
} emm_tag_rules;

/* The rules of EMM_TAG's presets ("openmesh"), as EMM_TAG spells them, or
 * NULL for another name. */
EMM_API const char *emm_tag_preset(const char *name);
/* Parses EMM_TAG's grammar: rules split by ';', each KIND:key=value,...
 * (docs in emm_tag_rules_help), or a preset's name (emm_tag_preset). On failure err says what is wrong in one
 * line that quotes at most a bounded part of the text. Axis rules (x=, y=,
 * z=) come in sets: every axis rule needs an x rule and a y rule of its
 * stride and type (z is optional: the layouts work in the plane). */
EMM_API emm_status emm_tag_rules_parse(const char *text, emm_tag_rules *out, emm_error *err);
/* One rule (no ';'), as emm_tag_rules_parse reads each, without the check
 * that an axis rule has its set (--list-sites tries the rules it suggests
 * one by one). */
EMM_API emm_status emm_tag_rule_parse(const char *text, emm_tag_rule *out, emm_error *err);
/* Frees the rules emm_tag_rules_parse made; *rs is then empty. */
EMM_API void emm_tag_rules_free(emm_tag_rules *rs);
/* A rule as EMM_TAG spells it ("vertices:site=read_mesh,stride=24,xyz=0:f64"),
 * into out (cap bytes, NUL included; cut when it does not fit). */
EMM_API void emm_tag_rule_format(const emm_tag_rule *r, char *out, size_t cap);
/* A scalar type as a rule spells it: "f32", "f64", "i32", "u32", "i64",
 * "u16" ("?" for another value). */
EMM_API const char *emm_scalar_name(emm_scalar t);
/* The grammar, as `emm run --help` prints it. */
EMM_API void emm_tag_rules_help(FILE *out);
/* Whether a block of `size` bytes is what rule r describes: a whole number
 * of records, or for order=columns three equal columns of whole entries (of
 * n entries each when the rule gives n=). A block that is not is never
 * tagged; the line at exit for a rule that matched nothing says why
 * (emm_tag_unmatched_message). */
EMM_API int emm_tag_rule_fits(const emm_tag_rule *r, uint64_t size);

/* A function's name as a rule's site= spells it, from its symbol: compiler
 * clone suffixes (.constprop.0, .isra.0, .part.0, .cold) dropped, and a C++
 * name reduced to its unqualified identifier (_ZN4mesh4loadEv -> load).
 * Writes at most cap bytes (NUL included) into out. */
EMM_API void emm_tag_site_name(const char *symbol, char *out, size_t cap);
/* A frame's two names for site= (docs/design.md "The shim and the session", Tagging):
 * `name`, the function's own (a method's name without its class, a template's without its
 * arguments), and `qualified`, with its namespaces and classes
 * ("OpenMesh::PropertyT::resize"; template arguments dropped). `demangled` is the symbol
 * as the C++ runtime demangles it, or NULL (a C symbol, or no demangler): the names then
 * come from the symbol as emm_tag_site_name reads it. */
EMM_API void emm_tag_site_names(const char *symbol, const char *demangled, char *name,
                                size_t ncap, char *qualified, size_t qcap);
/* Whether a rule's site= names a frame: its name, its qualified name, or a
 * tail of that ("PropertyT::resize"). */
EMM_API int emm_tag_site_matches(const char *site, const char *name, const char *qualified);

/* One tagged block, described whole: what the shim resolved of an
 * emm_tag_* call or of the EMM_TAG rule that selected the block. The
 * session (emm_session_tag) needs nothing else to read it: no rule to look
 * up again. */
typedef struct emm_array_desc {
    emm_array_kind kind;  /* VERTICES or TRIANGLES (a soup's records are triangles) */
    emm_tag_shape shape;  /* records, three columns, a soup, or one coordinate's block */
    int axis;             /* EMM_TAG_AXIS: the coordinate, 0 x, 1 y, 2 z; else ignored */
    const void *base;     /* the block's address in the program */
    uint64_t count;       /* records (EMM_TAG_COLUMNS: entries, three columns of count / 3) */
    uint64_t stride;      /* bytes per record (per entry) */
    uint64_t offset;      /* where the scalars start in a record: three coordinates or vertex
                             indices, a soup's nine corner coordinates, an axis block's one */
    emm_scalar type;
    unsigned rule;        /* the EMM_TAG rule that selected the block, from 1: `count` is then
                             the block's capacity, and the records the mesh has are those the
                             program writes or indexes (the highest element accessed, and for
                             vertices the highest index the triangles hold), taken when the
                             geometry is read; blocks of one rule are told apart from others'.
                             0: an emm_tag_* call, `count` records exactly */
    const char *origin;   /* who described it, for messages: "EMM_TAG rule 2 (triangles:...)"
                             (copied); NULL: "the emm_tag_vertices call" or its triangles' */
    uint32_t link[EMM_TAG_LINKS]; /* EMM_TAG_HALFEDGES: the rule's link[] (next, prev, face,
                                     opp offsets); EMM_TAG_NO_LINK otherwise */
} emm_array_desc;

/* The description of a block of `bytes` bytes at `base` that rule r (the
 * index-th of its rules, from 0) selected: count = bytes / stride, and
 * origin "EMM_TAG rule N (TEXT)" written into origin_buf (cap bytes), to
 * which d->origin then points. */
EMM_API void emm_tag_rule_describe(const emm_tag_rule *r, size_t index, const void *base,
                                   uint64_t bytes, emm_array_desc *d, char *origin_buf,
                                   size_t cap);

/* An allocation site the shim saw while looking for a rule's blocks. */
typedef struct emm_tag_site_seen {
    char name[EMM_TAG_SITE_MAX]; /* the innermost frame of the program's own */
    uint64_t count;              /* blocks allocated there */
    uint64_t largest;            /* the largest, in bytes */
} emm_tag_site_seen;

/* The line that says rule `index` (from 0) matched no allocation, naming
 * up to three of the sites seen closest to it: names that share most with
 * its site= first, then blocks that hold a whole number of its records,
 * then the largest blocks; a site whose blocks are not whole records says
 * so (a wrong stride). */
EMM_API void emm_tag_unmatched_message(const emm_tag_rule *r, size_t index,
                                       const emm_tag_site_seen *seen, size_t nseen, char *out,
                                       size_t cap);

/* Whether a frame is not a program's allocation site: one of the C
 * library, the C++ runtime, the loader, emm's own libraries, or a standard
 * library template instantiated in the program (std::vector's growth,
 * operator new). `symbol` (may be NULL) is the frame's raw symbol, `object`
 * (may be NULL) the file of the object that holds it. */
EMM_API int emm_tag_site_is_library(const char *symbol, const char *object);

/* ---- the configuration table --------------------------------------------- */

typedef enum emm_config_key {
    EMM_CONFIG_STRICT = 0, /* first: it decides what a later bad value does */
    EMM_CONFIG_TAG,
    EMM_CONFIG_CAPTURE,
    EMM_CONFIG_PROFILE,
    EMM_CONFIG_STRATEGY,
    EMM_CONFIG_COMPARE,
    EMM_CONFIG_FINALISTS,
    EMM_CONFIG_PHASES,
    EMM_CONFIG_MACHINE,
    EMM_CONFIG_TABLE,
    EMM_CONFIG_REPORT,
    EMM_CONFIG_PROFILE_DUMP,
    EMM_CONFIG_TRACE,
    EMM_CONFIG_TIMELINE,
    EMM_CONFIG_LOG,
    EMM_CONFIG_LIST_SITES,
    EMM_CONFIG_COUNT
} emm_config_key;

#define EMM_CONFIG_PATH_MAX 4096
/* Candidates that run to the end of the run to confirm the window's
 * prediction when EMM_FINALISTS is unset, beside the prediction and direct
 * reads, which always do (docs/profile.md "The contest"). */
#define EMM_CONFIG_DEFAULT_FINALISTS 1
/* The same, as the help texts print it (emm run's and emm profile's). */
#define EMM_CONFIG_TEXT_(x) #x
#define EMM_CONFIG_TEXT(x) EMM_CONFIG_TEXT_(x)
#define EMM_CONFIG_DEFAULT_FINALISTS_TEXT EMM_CONFIG_TEXT(EMM_CONFIG_DEFAULT_FINALISTS)
/* EMM_FINALISTS=all: every candidate runs to the end of the run, none is
 * dropped (the answer is then the fastest of all of them over the run, at
 * the cost of simulating every one: as EMM_COMPARE=all). */
#define EMM_CONFIG_FINALISTS_ALL 0xffffffffu
/* The most events a timeline holds (EMM_TIMELINE, emm replay --timeline):
 * about 50 MB of JSON, what Perfetto's UI and chrome://tracing open. */
#define EMM_TIMELINE_MAX_EVENTS 500000u
#define EMM_TIMELINE_MAX_EVENTS_TEXT "500,000"
/* The profile window when EMM_PROFILE is unset, in element accesses. */
#define EMM_CONFIG_DEFAULT_WINDOW 16384u

/* Every setting, parsed. Paths are "" when unset; output paths have %p
 * (the pid) and %% expanded. A config owns its tag rules: emm_config_free
 * releases them, emm_config_copy copies them. */
typedef struct emm_config {
    int strict;                   /* EMM_STRICT */
    emm_tag_rules tags;           /* EMM_TAG; tags.n == 0 when unset */
    emm_capture capture;          /* EMM_CAPTURE */
    uint64_t window_accesses;     /* EMM_PROFILE in element accesses, 0 when in iterations */
    uint64_t window_iterations;   /* EMM_PROFILE in emm_iteration() calls */
    int has_strategy;             /* EMM_STRATEGY given: no decision */
    emm_strategy strategy;
    emm_compare compare;          /* EMM_COMPARE */
    unsigned finalists;           /* EMM_FINALISTS: 0, the window's prediction stands;
                                     EMM_CONFIG_FINALISTS_ALL, none is dropped */
    int phases;                   /* EMM_PHASES: probe the run for phases after the window */
    char machine[EMM_CONFIG_PATH_MAX];      /* EMM_MACHINE; "": built-in */
    char table[EMM_CONFIG_PATH_MAX];        /* EMM_TABLE; "": the shipped table only */
    char report[EMM_CONFIG_PATH_MAX];       /* EMM_REPORT */
    char profile_dump[EMM_CONFIG_PATH_MAX]; /* EMM_PROFILE_DUMP */
    char trace[EMM_CONFIG_PATH_MAX];        /* EMM_TRACE */
    char timeline[EMM_CONFIG_PATH_MAX];     /* EMM_TIMELINE */
    int log;                      /* EMM_LOG: 0 quiet, 1 summary, 2 verbose */
    int list_sites;               /* EMM_LIST_SITES: list the candidate arrays, simulate nothing */
    /* Where each value came from — the variable or the option that set it
     * (static strings of the table), NULL for a default — so that every
     * message names what the user typed. */
    const char *source[EMM_CONFIG_COUNT];
} emm_config;

#define EMM_CONFIG_SWITCHES 4

/* An `emm run` option that sets a fixed value (--quiet is EMM_LOG=0). */
typedef struct emm_config_switch {
    const char *option; /* "--quiet" */
    const char *value;  /* "0" */
    const char *help;
} emm_config_switch;

/* One row of the table. */
typedef struct emm_config_row {
    const char *var;      /* "EMM_TAG" */
    const char *option;   /* "--tag" (NULL: no option with a value) */
    const char *metavar;  /* "RULES" */
    const char *accepts;  /* what a value may be, printed after "expected" */
    const char *def;      /* the default, as text */
    const char *help;     /* may hold several lines */
    emm_config_switch switches[EMM_CONFIG_SWITCHES]; /* fixed-value options; NULL ends them */
} emm_config_row;

EMM_API const emm_config_row *emm_config_row_get(emm_config_key k);

/* Every row at its default. */
EMM_API void emm_config_init(emm_config *c);
/* Releases what c owns (its tag rules); c is then at its defaults. */
EMM_API void emm_config_free(emm_config *c);
/* *dst becomes a copy of *src that owns its own rules (dst is not freed
 * first). EMM_ERR_NOMEM leaves dst at its defaults. */
EMM_API emm_status emm_config_copy(emm_config *dst, const emm_config *src);

/* Sets row k from `value`, given as `source` (the variable or the option:
 * it names the value in messages and is recorded in c->source[k]; it must
 * outlive c — a row's var or option does). `pid` expands %p. On failure c
 * is unchanged and err reads "SOURCE='value': problem", one line, the
 * value cut (with "...") so the problem always fits. */
EMM_API emm_status emm_config_set(emm_config *c, emm_config_key k, const char *value,
                                  const char *source, long pid, emm_error *err);

/* Reads every row's variable through `get` (getenv, or a test's own; an
 * unset variable is NULL) in table order, skipping the rows whose bit is
 * set in `skip` (1u << key: set by options that override them). Stops at
 * the first bad value; c->strict is set even then when EMM_STRICT was
 * valid. */
EMM_API emm_status emm_config_from_env(emm_config *c, const char *(*get)(const char *name),
                                       long pid, unsigned skip, emm_error *err);

/* The row whose option or switch is `arg` ("--tag", "--quiet"); *fixed gets
 * the switch's value, or NULL for an option that takes one. Returns
 * EMM_CONFIG_COUNT when no row has it. */
EMM_API emm_config_key emm_config_find_option(const char *arg, const char **fixed);

/* The table for --help: `options` nonzero lists the `emm run` options with
 * their variables, zero the variables alone. */
EMM_API void emm_config_help(FILE *out, int options);

/* Row k's value in c as text that emm_config_set turns back into the same
 * value (output paths with their % doubled, so that a second expansion
 * leaves them as they are), into out (cap bytes, NUL included). Returns
 * false when it does not fit, or for EMM_STRATEGY when none is set. */
EMM_API int emm_config_format(const emm_config *c, emm_config_key k, char *out, size_t cap);

/* The values in force, one "emm:   EMM_X=value" line each (EMM_LOG=2). */
EMM_API void emm_config_dump(const emm_config *c, FILE *out);

#ifdef __cplusplus
}
#endif
#endif
