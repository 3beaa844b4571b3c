/* Inputs that cannot hang a run or exhaust its memory. Every reader opens
 * its file through ss_input_open: the path is checked with stat(2) first (a
 * device is never opened), then opened with O_NONBLOCK (a named pipe with
 * no writer returns at once instead of blocking forever) and checked again
 * with fstat(2) on what was actually opened, so a file swapped for a pipe in
 * between is caught too. Image readers ask ss_image_check_alloc before they
 * allocate what a header claims: a 68-byte PNG saying 30000 x 30000 is an
 * input error naming the size, not a multi-gigabyte allocation. The memory
 * figure is the smallest of MemAvailable, the address-space limit (ulimit
 * -v) left over and the cgroup v2 limit left over; where none is known it
 * is the physical memory. */
#define _GNU_SOURCE
#include "skinsim/core.h"
#include "core_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

const char *ss__file_kind(mode_t m) {
    if (S_ISDIR(m)) return "a folder";
    if (S_ISCHR(m)) return "a character device";
    if (S_ISBLK(m)) return "a block device";
    if (S_ISFIFO(m)) return "a named pipe";
    if (S_ISSOCK(m)) return "a socket";
    if (S_ISLNK(m)) return "a symbolic link";
    return "not a regular file";
}

int ss_input_open_fd(const char *path, size_t *size, ss_error *err) {
    if (!path || !*path) {
        ss_error_set(err, SS_ERR_INPUT, "an input file name is empty");
        return -1;
    }
    struct stat st;
    if (stat(path, &st) != 0) {
        ss_error_set(err, SS_ERR_INPUT, "%s: cannot open: %s", path, strerror(errno));
        return -1;
    }
    if (!S_ISREG(st.st_mode)) {
        ss_error_set(err, SS_ERR_INPUT, "%s: is %s, not a regular file", path,
                     ss__file_kind(st.st_mode));
        return -1;
    }
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
    if (fd < 0) {
        ss_error_set(err, SS_ERR_INPUT, "%s: cannot open: %s", path, strerror(errno));
        return -1;
    }
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        ss_error_set(err, SS_ERR_INPUT, "%s: is %s, not a regular file", path,
                     ss__file_kind(st.st_mode));
        close(fd);
        return -1;
    }
    int fl = fcntl(fd, F_GETFL);
    if (fl >= 0) fcntl(fd, F_SETFL, fl & ~O_NONBLOCK);
    if (size) *size = (size_t)st.st_size;
    return fd;
}

FILE *ss_input_open(const char *path, size_t *size, ss_error *err) {
    int fd = ss_input_open_fd(path, size, err);
    if (fd < 0) return NULL;
    FILE *f = fdopen(fd, "rb");
    if (!f) {
        ss_error_set(err, SS_ERR_RUNTIME, "%s: %s", path, strerror(errno));
        close(fd);
    }
    return f;
}

/* A reference is decided on its own text first (absolute, or a ".."
 * component: refused whatever exists on disk), then on disk: realpath of
 * the joined name must lie under realpath of the referrer's folder, which
 * catches a symlink inside the folder pointing out of it. A name that does
 * not exist is returned as joined; its reader then fails to open it. */
ss_status ss_input_path_inside(const char *referrer, const char *ref, char **out, ss_error *err) {
    *out = NULL;
    if (!ref || !*ref)
        return ss_error_set(err, SS_ERR_INPUT, "%s: a referenced file name is empty", referrer);
    int dotdot = 0;
    for (const char *p = ref; *p;) {
        size_t l = strcspn(p, "/\\");
        if (l == 2 && p[0] == '.' && p[1] == '.') dotdot = 1;
        p += l;
        if (*p) p++;
    }
    if (ref[0] == '/' || ref[0] == '\\' || dotdot)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: the referenced file '%s' is %s; a file may only reference "
                            "files inside its own folder",
                            referrer, ref,
                            dotdot ? "outside its folder (a '..' component)" : "an absolute path");
    const char *slash = strrchr(referrer, '/');
    size_t dl = slash ? (size_t)(slash - referrer + 1) : 0;
    char *joined = malloc(dl + strlen(ref) + 1);
    if (!joined) return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", referrer);
    memcpy(joined, referrer, dl);
    strcpy(joined + dl, ref);
    char *folder = strndup(dl ? referrer : ".", dl ? dl : 1);
    char *rdir = folder ? realpath(folder, NULL) : NULL;
    char *rfile = realpath(joined, NULL);
    ss_status st = SS_OK;
    if (!rdir)
        st = ss_error_set(err, SS_ERR_INPUT, "%s: cannot resolve its folder: %s", referrer,
                          strerror(errno));
    else if (rfile) {
        size_t n = strlen(rdir);
        int inside = !strncmp(rfile, rdir, n) && (rfile[n] == '/' || (n == 1 && rdir[0] == '/'));
        if (!inside)
            st = ss_error_set(err, SS_ERR_INPUT,
                              "%s: the referenced file '%s' resolves to %s, outside the folder "
                              "%s (a symbolic link?); a file may only reference files inside "
                              "its own folder",
                              referrer, ref, rfile, rdir);
    }
    free(folder);
    free(rdir);
    free(rfile);
    if (st)
        free(joined);
    else
        *out = joined;
    return st;
}

/* A "key: value kB" line of a /proc file, in bytes; -1 if missing. */
static double proc_kb(const char *file, const char *key) {
    FILE *f = fopen(file, "r");
    if (!f) return -1;
    char line[256];
    double v = -1;
    size_t n = strlen(key);
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, key, n) && line[n] == ':') {
            v = strtod(line + n + 1, NULL) * 1024.0;
            break;
        }
    fclose(f);
    return v;
}

/* A single number from a file ("max" = unlimited = -1). */
static double file_number(const char *path) {
    FILE *f = fopen(path, "r");
    if (!f) return -1;
    char buf[64] = {0};
    double v = -1;
    if (fgets(buf, sizeof buf, f) && strncmp(buf, "max", 3)) v = strtod(buf, NULL);
    fclose(f);
    return v;
}

/* The cgroup v2 memory left: memory.max - memory.current of this process's
 * cgroup; -1 when there is no limit or no cgroup v2. */
static double cgroup_left(void) {
    FILE *f = fopen("/proc/self/cgroup", "r");
    if (!f) return -1;
    char line[1024], path[1200];
    double left = -1;
    while (fgets(line, sizeof line, f)) {
        if (strncmp(line, "0::", 3)) continue;
        line[strcspn(line, "\n")] = '\0';
        snprintf(path, sizeof path, "/sys/fs/cgroup%s/memory.max", line + 3);
        double max = file_number(path);
        snprintf(path, sizeof path, "/sys/fs/cgroup%s/memory.current", line + 3);
        double cur = file_number(path);
        if (max > 0) left = max - (cur > 0 ? cur : 0);
        break;
    }
    fclose(f);
    return left;
}

double ss_memory_available_bytes(void) {
    double best = proc_kb("/proc/meminfo", "MemAvailable");
    if (best < 0) best = ss_memory_physical_bytes();
    struct rlimit rl;
    if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) {
        double used = proc_kb("/proc/self/status", "VmSize");
        double left = (double)rl.rlim_cur - (used > 0 ? used : 0);
        /* nothing left is 1 byte, not 0 (which would mean "unknown") */
        if (best <= 0 || left < best) best = left > 1 ? left : 1;
    }
    double cg = cgroup_left();
    if (cg >= 0 && (best <= 0 || cg < best)) best = cg > 1 ? cg : 1;
    return best;
}

ss_status ss_image_check_alloc(const char *name, long width, long height, int channels,
                               ss_error *err) {
    if (width < 1 || height < 1 || channels < 1 || channels > SS_IMAGE_MAX_CHANNELS)
        return ss_error_set(err, SS_ERR_INPUT, "%s: bad image size %ld x %ld x %d", name, width,
                            height, channels);
    if (width > SS_IMAGE_MAX_SIDE || height > SS_IMAGE_MAX_SIDE)
        return ss_error_set(err, SS_ERR_INPUT, "%s: %ld x %ld pixels is above the %d-pixel limit",
                            name, width, height, SS_IMAGE_MAX_SIDE);
    double need = (double)width * (double)height * channels * sizeof(float);
    double avail = ss_memory_available_bytes();
    if (avail > 0 && need > avail)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: a %ld x %ld image with %d channel%s needs %.2f GB, more than the "
                            "%.2f GB of memory available",
                            name, width, height, channels, channels == 1 ? "" : "s", need / 1e9,
                            avail / 1e9);
    return SS_OK;
}
