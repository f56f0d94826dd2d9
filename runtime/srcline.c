/* Program counters to source lines (srcline.h) with elfutils' libdwfl: each
 * object is reported to libdwfl the first time a pc falls in it, at its
 * recorded load bias; the line comes from the line table, the function
 * from the innermost DWARF scope (an inlined subroutine's name when the
 * code was inlined, as a source reader expects), else the symbol table. */
#include "srcline.h"

#include <dlfcn.h>
#include <elfutils/libdwfl.h>
#include <dwarf.h>
#include <limits.h>
#include <link.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "error.h"
#include "trace_format.h"

struct emm_srcmap {
    Dwfl *dwfl;
    uint32_t n;
    emm_trace_module *mods;
    Dwfl_Module **dwmod; /* per module: reported, or NULL */
    bool *tried;         /* per module: reported or failed */
};

static const Dwfl_Callbacks callbacks = {
    .find_elf = dwfl_build_id_find_elf,
    .find_debuginfo = dwfl_standard_find_debuginfo,
    .section_address = dwfl_offline_section_address,
};

emm_status emm_srcmap_new(const emm_trace_module *m, uint32_t n, emm_srcmap **out,
                          emm_error *err)
{
    *out = NULL;
    emm_srcmap *s = calloc(1, sizeof *s);
    size_t paths = 0;
    for (uint32_t i = 0; i < n; i++)
        paths += strlen(m[i].path ? m[i].path : "") + 1;
    if (s) {
        s->mods = malloc((n ? n : 1) * sizeof *s->mods + paths);
        s->dwmod = calloc(n ? n : 1, sizeof *s->dwmod);
        s->tried = calloc(n ? n : 1, sizeof *s->tried);
    }
    if (!s || !s->mods || !s->dwmod || !s->tried) {
        emm_srcmap_free(s);
        return emm_fail(err, EMM_ERR_NOMEM, "out of memory for the source map");
    }
    char *text = (char *)(s->mods + (n ? n : 1));
    for (uint32_t i = 0; i < n; i++) {
        s->mods[i] = m[i];
        size_t l = strlen(m[i].path ? m[i].path : "");
        memcpy(text, m[i].path ? m[i].path : "", l + 1);
        s->mods[i].path = text;
        text += l + 1;
    }
    s->n = n;
    s->dwfl = dwfl_begin(&callbacks);
    if (!s->dwfl) {
        emm_srcmap_free(s);
        return emm_fail(err, EMM_ERR_UNSUPPORTED, "libdwfl: %s", dwfl_errmsg(-1));
    }
    *out = s;
    return EMM_OK;
}

void emm_srcmap_free(emm_srcmap *s)
{
    if (!s)
        return;
    if (s->dwfl)
        dwfl_end(s->dwfl);
    free(s->mods);
    free(s->dwmod);
    free(s->tried);
    free(s);
}

/* The module holding pc, reported to libdwfl on first use; NULL when none
 * does or its file cannot be read. *index gets the trace module's index
 * (or -1). */
static Dwfl_Module *module_of(emm_srcmap *s, uint64_t pc, int64_t *index)
{
    *index = -1;
    for (uint32_t i = 0; i < s->n; i++) {
        if (pc < s->mods[i].lo || pc >= s->mods[i].hi)
            continue;
        *index = i;
        if (!s->tried[i]) {
            s->tried[i] = true;
            if (s->mods[i].path[0]) {
                dwfl_report_begin_add(s->dwfl);
                s->dwmod[i] = dwfl_report_elf(s->dwfl, s->mods[i].path, s->mods[i].path, -1,
                                              s->mods[i].bias, true);
                dwfl_report_end(s->dwfl, NULL, NULL);
            }
        }
        return s->dwmod[i];
    }
    return NULL;
}

bool emm_srcmap_lookup(emm_srcmap *s, uint64_t pc, emm_srcloc *out)
{
    memset(out, 0, sizeof *out);
    int64_t index;
    Dwfl_Module *mod = module_of(s, pc, &index);
    if (index >= 0)
        out->module = s->mods[index].path;
    if (!mod || pc == 0)
        return false;
    Dwarf_Addr at = pc - 1; /* the call the hook returns to */
    /* The compile unit by its ranges: dwfl_module_addrdie goes through
     * address tables that clang's DWARF 5 leaves out. */
    Dwarf_Addr bias = 0;
    Dwarf_Die *cu = NULL;
    while ((cu = dwfl_module_nextcu(mod, cu, &bias)) && dwarf_haspc(cu, at - bias) != 1)
        ;
    if (cu) {
        /* Innermost scope out: an inlined subroutine is named and its
         * instance's own containing scopes (in its caller) followed, up to
         * the subprogram the code physically lies in. */
        Dwarf_Die *scopes = NULL;
        int ns = dwarf_getscopes(cu, at - bias, &scopes), k = 0;
        while (k < ns && out->nchain < EMM_SRCLOC_CHAIN) {
            int tag = dwarf_tag(&scopes[k]);
            if (tag != DW_TAG_subprogram && tag != DW_TAG_inlined_subroutine) {
                k++;
                continue;
            }
            const char *name = dwarf_diename(&scopes[k]);
            if (name) {
                out->chain_file[out->nchain] = dwarf_decl_file(&scopes[k]);
                out->chain[out->nchain++] = name;
            }
            if (tag == DW_TAG_subprogram)
                break;
            Dwarf_Die *outer = NULL;
            int no = dwarf_getscopes_die(&scopes[k], &outer);
            free(scopes);
            scopes = outer;
            ns = no;
            k = 1; /* outer[0] is the inlined instance itself */
        }
        free(scopes);
        out->function = out->nchain ? out->chain[0] : NULL;
        Dwarf_Line *line = dwarf_getsrc_die(cu, at - bias);
        int lineno = 0;
        if (line && dwarf_lineno(line, &lineno) == 0) {
            out->file = dwarf_linesrc(line, NULL, NULL);
            out->line = lineno;
        }
    }
    if (!out->function && (out->function = dwfl_module_addrname(mod, at)) != NULL) {
        out->chain_file[out->nchain] = NULL;
        out->chain[out->nchain++] = out->function;
    }
    return out->file != NULL && out->line > 0;
}

/* ---- the calling process's modules ------------------------------------------ */

struct collect {
    emm_trace_module *m;
    uint32_t n, cap;
    size_t paths; /* bytes of paths */
    char exe[PATH_MAX];
    bool failed;
};

static int one_object(struct dl_phdr_info *info, size_t size, void *ctx)
{
    (void)size;
    struct collect *c = ctx;
    const char *name = info->dlpi_name;
    bool main_program = !name || !name[0];
    if (main_program)
        name = c->exe;
    if (!name[0] || strncmp(name, "linux-vdso", 10) == 0 || c->n == EMM_TRACE_MAX_MODULES)
        return 0;
    uint64_t lo = UINT64_MAX, hi = 0;
    for (int k = 0; k < info->dlpi_phnum; k++) {
        const ElfW(Phdr) *ph = &info->dlpi_phdr[k];
        if (ph->p_type != PT_LOAD)
            continue;
        uint64_t a = info->dlpi_addr + ph->p_vaddr;
        lo = a < lo ? a : lo;
        hi = a + ph->p_memsz > hi ? a + ph->p_memsz : hi;
    }
    if (lo >= hi)
        return 0;
    if (c->n == c->cap) {
        uint32_t cap = c->cap ? 2 * c->cap : 32;
        emm_trace_module *m = realloc(c->m, cap * sizeof *m);
        if (!m) {
            c->failed = true;
            return 1;
        }
        c->m = m;
        c->cap = cap;
    }
    /* The path is kept in the struct until the one block is made. */
    char *copy = strdup(name);
    if (!copy) {
        c->failed = true;
        return 1;
    }
    c->m[c->n++] = (emm_trace_module){(uint64_t)info->dlpi_addr, lo, hi, copy};
    c->paths += strlen(copy) + 1;
    return 0;
}

emm_status emm_process_modules(emm_trace_module **out, uint32_t *n, emm_error *err)
{
    struct collect c = {0};
    ssize_t len = readlink("/proc/self/exe", c.exe, sizeof c.exe - 1);
    c.exe[len > 0 ? len : 0] = '\0';
    dl_iterate_phdr(one_object, &c);
    emm_trace_module *block = NULL;
    if (!c.failed)
        block = malloc((c.n ? c.n : 1) * sizeof *block + c.paths);
    if (block) {
        char *text = (char *)(block + (c.n ? c.n : 1));
        for (uint32_t i = 0; i < c.n; i++) {
            size_t l = strlen(c.m[i].path) + 1;
            memcpy(text, c.m[i].path, l);
            block[i] = c.m[i];
            block[i].path = text;
            text += l;
        }
    }
    for (uint32_t i = 0; i < c.n; i++)
        free((char *)c.m[i].path);
    free(c.m);
    if (!block)
        return emm_fail(err, EMM_ERR_NOMEM, "out of memory for the program's modules");
    *out = block;
    *n = c.n;
    return EMM_OK;
}
