/* Where the shipped data files (spectra, tables, presets) are.
 *
 * Order: $SKINSIM_DATA when set; else the share/skinsim folder of an
 * installed copy, found relative to the file that holds this code (the
 * shared library, or the program the static library is linked into; the
 * relative paths come from the build: lib/../share/skinsim on most
 * prefixes); else the source tree's data/ folder the build was made from,
 * while it exists; else the configured install folder (a program linked
 * statically and kept elsewhere than the prefix's bin/).
 * Finding the install relative to the code, not from the configured prefix,
 * keeps an installed tree relocatable (copy the prefix elsewhere and it
 * still works) and lets a build folder and an install of it coexist: the
 * build folder has no ../share/skinsim, so it keeps using the source tree.
 *
 * The installed path is looked up once (pthread_once) and then only read:
 * it is a property of the process, not mutable state. A folder counts as
 * the data folder when it holds spectra/d65.csv. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <libgen.h>
#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "skinsim/core.h"

#ifndef SKINSIM_DATA_FROM_LIB
#define SKINSIM_DATA_FROM_LIB "../share/skinsim"
#endif
#ifndef SKINSIM_DATA_FROM_BIN
#define SKINSIM_DATA_FROM_BIN "../share/skinsim"
#endif

static char installed_dir[PATH_MAX];
static pthread_once_t installed_once = PTHREAD_ONCE_INIT;

/* Sets installed_dir to <dir of file>/<rel> when that holds the data. */
static int try_dir(const char *file, const char *rel) {
    char real[PATH_MAX], probe[PATH_MAX + 64];
    if (!file || !*file || !realpath(file, real)) return 0;
    const char *dir = dirname(real);
    char cand[PATH_MAX];
    if ((size_t)snprintf(cand, sizeof cand, "%s/%s", dir, rel) >= sizeof cand) return 0;
    snprintf(probe, sizeof probe, "%s/spectra/d65.csv", cand);
    if (access(probe, R_OK) != 0) return 0;
    char canon[PATH_MAX];
    if (!realpath(cand, canon)) return 0;
    snprintf(installed_dir, sizeof installed_dir, "%s", canon);
    return 1;
}

static void find_installed(void) {
    Dl_info info;
    const char *code_file = NULL;
    /* any object of this library will do; a data address avoids the
     * function-to-object pointer conversion ISO C forbids */
    if (dladdr(&installed_once, &info) && info.dli_fname) code_file = info.dli_fname;
    if (try_dir(code_file, SKINSIM_DATA_FROM_LIB)) return;
    if (try_dir(code_file, SKINSIM_DATA_FROM_BIN)) return;
    /* the static library inside a program: dladdr may name it as argv[0] */
    if (try_dir("/proc/self/exe", SKINSIM_DATA_FROM_BIN)) return;
    installed_dir[0] = '\0';
}

const char *ss_data_dir(void) {
    const char *env = getenv("SKINSIM_DATA");
    if (env && *env) return env;
    pthread_once(&installed_once, find_installed);
    if (installed_dir[0]) return installed_dir;
#ifdef SKINSIM_INSTALL_DATA_DIR
#ifdef SKINSIM_DATA_DIR
    if (access(SKINSIM_DATA_DIR "/spectra/d65.csv", R_OK) == 0) return SKINSIM_DATA_DIR;
#endif
    return SKINSIM_INSTALL_DATA_DIR;
#elif defined(SKINSIM_DATA_DIR)
    return SKINSIM_DATA_DIR;
#else
    return "data";
#endif
}

const char *ss_version(void) {
#ifdef SKINSIM_VERSION
    return SKINSIM_VERSION;
#else
    return "unknown";
#endif
}
