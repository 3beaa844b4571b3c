/* skinsim view: the interactive painter and viewer lives in its own program,
 * skinsim-view (GTK 4 + OpenGL), so the skinsim command and the library do
 * not depend on GTK. This runs it from the folder of this executable (the
 * build folder or the install prefix's bin), passing the arguments on. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"

int cmd_view(int argc, char **argv) {
    char self[4096], path[4200];
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n <= 0) n = 0;
    self[n] = '\0';
    char *slash = strrchr(self, '/');
    if (slash) *slash = '\0';
    snprintf(path, sizeof path, "%s/skinsim-view", slash ? self : ".");
    char **args = calloc((size_t)argc + 2, sizeof *args);
    if (!args) return 1;
    args[0] = path;
    for (int i = 1; i < argc; i++) args[i] = argv[i];
    /* skinsim-view would otherwise run itself again to set this (see its
     * main): OpenMP threads that sleep at barriers instead of spinning */
    if (!getenv("OMP_WAIT_POLICY")) setenv("OMP_WAIT_POLICY", "passive", 1);
    /* and huge pages for malloc's large blocks (see skinsim-view's main) */
    const char *t = getenv("GLIBC_TUNABLES");
    if (!t || !strstr(t, "glibc.malloc.hugetlb")) {
        char buf[1024];
        snprintf(buf, sizeof buf, "%s%sglibc.malloc.hugetlb=1", t ? t : "", t && *t ? ":" : "");
        if (strlen(buf) < sizeof buf - 1) setenv("GLIBC_TUNABLES", buf, 1);
    }
    execv(path, args);
    int e = errno;
    free(args);
    if (e == ENOENT) {
        fprintf(stderr,
                "skinsim view: %s is missing: skinsim was built without the viewer (it "
                "needs GTK 4 and libepoxy: apt-get install libgtk-4-dev libepoxy-dev, "
                "then rebuild)\n",
                path);
        return 1;
    }
    fprintf(stderr, "skinsim view: cannot run %s: %s\n", path, strerror(e));
    return 1;
}
