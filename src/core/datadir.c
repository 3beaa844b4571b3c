/* Where the shipped data files (spectra, tables, presets) are.
 *
 * Order: $SKINSIM_DATA when set; else the share/skinsim folder of an
 * installed copy, found relative to the file that holds this code (the
 * shared library, or the program the static library is linked into; the
 * relative paths come from the build: lib/../share/skinsim on most
 * prefixes); else relative to a folder holding libskinsim.{a,so} on the
 * program's library search path (its RUNPATH, which `pkg-config --libs
 * --static skinsim` sets to the installed lib folder, LD_LIBRARY_PATH, the
 * system folders), so a program linked statically against an installed
 * prefix finds that prefix's data wherever the program is kept; else the
 * source tree's data/ folder, but only for code running from the build
 * folder it was built in (never silently for an installed copy); else the
 * configured install folder, whose absence then gives an error naming it.
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
static int in_build_tree; /* the code runs from the folder it was built in */
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

/* 1 when dir holds the static or shared library; its path in probe. */
static int holds_library(const char *dir, char *probe, size_t probesize) {
    static const char *const names[] = {"libskinsim.a", "libskinsim.so"};
    for (size_t i = 0; i < sizeof names / sizeof *names; i++) {
        if ((size_t)snprintf(probe, probesize, "%s/%s", dir, names[i]) >= probesize) continue;
        if (access(probe, R_OK) == 0) return 1;
    }
    return 0;
}

/* The program's library search path (RUNPATH/RPATH, LD_LIBRARY_PATH, the
 * system folders, as the dynamic linker would search them). */
static int try_search_path(void) {
    void *self = dlopen(NULL, RTLD_LAZY | RTLD_NOLOAD);
    if (!self) return 0;
    Dl_serinfo size;
    int found = 0;
    if (dlinfo(self, RTLD_DI_SERINFOSIZE, &size) == 0 && size.dls_size >= sizeof(Dl_serinfo)) {
        Dl_serinfo *info = malloc(size.dls_size);
        if (info) {
            *info = size;
            if (dlinfo(self, RTLD_DI_SERINFO, info) == 0) {
                for (unsigned i = 0; i < info->dls_cnt && !found; i++) {
                    const char *dir = info->dls_serpath[i].dls_name;
                    char file[PATH_MAX + 32];
                    if (!dir || !*dir || !holds_library(dir, file, sizeof file)) continue;
                    found = try_dir(file, SKINSIM_DATA_FROM_LIB);
                }
            }
            free(info);
        }
    }
    dlclose(self);
    return found;
}

/* 1 when file is inside the build folder this code was compiled in. */
static int inside_build(const char *file) {
#ifdef SKINSIM_BUILD_DIR
    char real[PATH_MAX], build[PATH_MAX];
    if (!file || !*file || !realpath(file, real) || !realpath(SKINSIM_BUILD_DIR, build)) return 0;
    size_t n = strlen(build);
    return strncmp(real, build, n) == 0 && real[n] == '/';
#else
    (void)file;
    return 0;
#endif
}

static void find_installed(void) {
    Dl_info info;
    const char *code_file = NULL;
    /* any object of this library will do; a data address avoids the
     * function-to-object pointer conversion ISO C forbids */
    if (dladdr(&installed_once, &info) && info.dli_fname) code_file = info.dli_fname;
    in_build_tree = inside_build(code_file) || inside_build("/proc/self/exe");
    installed_dir[0] = '\0';
    if (try_dir(code_file, SKINSIM_DATA_FROM_LIB)) return;
    if (try_dir(code_file, SKINSIM_DATA_FROM_BIN)) return;
    /* the static library inside a program: dladdr may name it as argv[0] */
    if (try_dir("/proc/self/exe", SKINSIM_DATA_FROM_BIN)) return;
    if (in_build_tree) return; /* a build folder uses its source tree */
    if (try_search_path()) return;
    installed_dir[0] = '\0';
}

const char *ss_data_dir(void) {
    const char *env = getenv("SKINSIM_DATA");
    if (env && *env) return env;
    pthread_once(&installed_once, find_installed);
    if (installed_dir[0]) return installed_dir;
#ifdef SKINSIM_DATA_DIR
    if (in_build_tree) return SKINSIM_DATA_DIR;
#endif
#ifdef SKINSIM_INSTALL_DATA_DIR
    return SKINSIM_INSTALL_DATA_DIR;
#elif defined(SKINSIM_DATA_DIR)
    return SKINSIM_DATA_DIR;
#else
    return "data";
#endif
}

ss_status ss_data_path(const char *name, char *out, size_t outsize, ss_error *err) {
    if (!name || !*name || name[0] == '/' || strstr(name, ".."))
        return ss_error_set(err, SS_ERR_INPUT,
                            "data file name '%s': want a path relative to the data folder",
                            name ? name : "(null)");
    if (!out || outsize == 0)
        return ss_error_set(err, SS_ERR_INPUT, "data file '%s': no room for the path", name);
    const char *dir = ss_data_dir();
    int n = snprintf(out, outsize, "%s/%s", dir, name);
    if (n < 0 || (size_t)n >= outsize) {
        out[0] = '\0';
        return ss_error_set(err, SS_ERR_INPUT, "data file '%s/%s': path longer than %zu bytes", dir,
                            name, outsize - 1);
    }
    if (access(out, R_OK) != 0)
        return ss_error_set(err, SS_ERR_INPUT,
                            "data file %s cannot be read (data folder %s; set SKINSIM_DATA to the "
                            "share/skinsim folder of an install)",
                            out, dir);
    return SS_OK;
}

const char *ss_version(void) {
#ifdef SKINSIM_VERSION
    return SKINSIM_VERSION;
#else
    return "unknown";
#endif
}
