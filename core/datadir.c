/* The shipped data files' location (datadir.h). The build tree is laid out
 * as an install is — bin/, lib/, and share/emm/ whose files link to the
 * source tree's data/ (the top CMakeLists.txt) — so one rule serves both:
 * share/emm beside the module's own directory. The module's own path
 * comes from the loader: dladdr1's link map names a shared library by the
 * path it was loaded from, and the main program by an empty name, for
 * which /proc/self/exe is the truth (dladdr's dli_fname would be argv[0],
 * a bare "emm" when the shell found it through PATH). */
#include "datadir.h"

#include <dlfcn.h>
#include <limits.h>
#include <link.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Set by core/CMakeLists.txt; these defaults only serve other builds. */
#ifndef EMM_INSTALL_DATADIR
#define EMM_INSTALL_DATADIR "/usr/local/share"
#endif
/* The data directory relative to the install's bindir and libdir. */
#ifndef EMM_BIN_TO_DATA
#define EMM_BIN_TO_DATA "../share"
#endif
#ifndef EMM_LIB_TO_DATA
#define EMM_LIB_TO_DATA "../share"
#endif

/* The directory of the module this function is linked into, resolved
 * (symbolic links followed); false when the loader cannot say. */
static bool module_dir(char *out, size_t cap)
{
    Dl_info info;
    struct link_map *map = NULL;
    char raw[PATH_MAX], real[PATH_MAX];
    const char *path = NULL;
    if (dladdr1((void *)module_dir, &info, (void **)&map, RTLD_DL_LINKMAP) && map &&
        map->l_name && map->l_name[0] == '/')
        path = map->l_name;
    if (!path) {
        ssize_t n = readlink("/proc/self/exe", raw, sizeof raw - 1);
        if (n <= 0)
            return false;
        raw[n] = '\0';
        path = raw;
    }
    if (!realpath(path, real))
        return false;
    char *slash = strrchr(real, '/');
    if (!slash)
        return false;
    *slash = '\0';
    int w = snprintf(out, cap, "%s", real[0] ? real : "/");
    return w >= 0 && (size_t)w < cap;
}

static void add_tried(char *tried, size_t tcap, const char *path)
{
    if (!tried || tcap == 0)
        return;
    size_t used = strlen(tried);
    snprintf(tried + used, tcap - used, "%s%s", used ? ", " : "", path);
}

bool emm_data_file(const char *name, char *out, size_t cap, char *tried, size_t tcap)
{
    enum { MAX_CAND = 4, CAND_BYTES = PATH_MAX + 256 };
    char dir[PATH_MAX], cand[MAX_CAND][CAND_BYTES];
    size_t n = 0;
    if (tried && tcap)
        tried[0] = '\0';
    if (module_dir(dir, sizeof dir)) {
        snprintf(cand[n++], CAND_BYTES, "%s/%s/emm/%.200s", dir, EMM_BIN_TO_DATA, name);
        if (strcmp(EMM_BIN_TO_DATA, EMM_LIB_TO_DATA) != 0)
            snprintf(cand[n++], CAND_BYTES, "%s/%s/emm/%.200s", dir, EMM_LIB_TO_DATA, name);
    }
    snprintf(cand[n++], CAND_BYTES, "%s/emm/%.200s", EMM_INSTALL_DATADIR, name);
    for (size_t i = 0; i < n; i++) {
        add_tried(tried, tcap, cand[i]);
        bool found = access(cand[i], F_OK) == 0;
        if (found || i + 1 == n) {
            /* The file itself: the build tree's share/emm links to the
             * source tree's data/. */
            char real[PATH_MAX];
            snprintf(out, cap, "%s", found && realpath(cand[i], real) ? real : cand[i]);
            return found;
        }
    }
    return false;
}
