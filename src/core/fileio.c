/* Files: atomic writes (temporary name + fsync + rename, so a failed or killed
 * run never leaves a half-written output), whole-file reads, mkdir -p. */
#define _XOPEN_SOURCE 700
#include "skinsim/core.h"

#include <errno.h>
#include <ftw.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

ss_status ss_atomic_open(ss_atomic_file *af, const char *path, ss_error *err) {
    af->fp = NULL;
    if (strlen(path) >= sizeof af->path)
        return ss_error_set(err, SS_ERR_INPUT, "%s: path too long", path);
    snprintf(af->path, sizeof af->path, "%s", path);
    snprintf(af->tmp, sizeof af->tmp, "%s" SS_ATOMIC_TMP "%ld.XXXXXX", path, (long)getpid());
    int fd = mkstemp(af->tmp);
    if (fd < 0)
        return ss_error_set(err, SS_ERR_INPUT, "%s: cannot create file: %s", path, strerror(errno));
    fchmod(fd, 0644);
    af->fp = fdopen(fd, "wb");
    if (!af->fp) {
        close(fd);
        unlink(af->tmp);
        return ss_error_set(err, SS_ERR_RUNTIME, "%s: %s", path, strerror(errno));
    }
    return SS_OK;
}

ss_status ss_atomic_commit(ss_atomic_file *af, ss_error *err) {
    if (!af->fp) return ss_error_set(err, SS_ERR_RUNTIME, "%s: file not open", af->path);
    int bad = ferror(af->fp) || fflush(af->fp) != 0 || fsync(fileno(af->fp)) != 0;
    int e = errno;
    if (fclose(af->fp) != 0) bad = 1;
    af->fp = NULL;
    if (bad) {
        unlink(af->tmp);
        return ss_error_set(err, SS_ERR_RUNTIME, "%s: write failed: %s", af->path, strerror(e));
    }
    if (rename(af->tmp, af->path) != 0) {
        e = errno;
        unlink(af->tmp);
        return ss_error_set(err, SS_ERR_RUNTIME, "%s: cannot rename into place: %s", af->path,
                            strerror(e));
    }
    return SS_OK;
}

void ss_atomic_abort(ss_atomic_file *af) {
    if (af->fp) fclose(af->fp);
    af->fp = NULL;
    unlink(af->tmp);
}

ss_status ss_write_file_atomic(const char *path, const void *data, size_t len, ss_error *err) {
    ss_atomic_file af;
    ss_status st = ss_atomic_open(&af, path, err);
    if (st) return st;
    if (len && fwrite(data, 1, len, af.fp) != len) {
        int e = errno;
        ss_atomic_abort(&af);
        return ss_error_set(err, SS_ERR_RUNTIME, "%s: write failed: %s", path, strerror(e));
    }
    return ss_atomic_commit(&af, err);
}

char *ss_read_file(const char *path, size_t *len, ss_error *err) {
    return ss_read_file_max(path, len, SS_READ_MAX_ANY, err);
}

/* The size comes from fstat on the opened file, so a 2 GB sparse file is
 * refused before a byte is read or allocated. */
char *ss_read_file_max(const char *path, size_t *len, size_t max_bytes, ss_error *err) {
    size_t n = 0;
    FILE *f = ss_input_open(path, &n, err); /* regular files only, never blocks */
    if (!f) return NULL;
    double avail = ss_memory_available_bytes();
    if (n > max_bytes || (avail > 0 && (double)n + 1.0 > avail)) {
        fclose(f);
        if (n > max_bytes)
            ss_error_set(err, SS_ERR_INPUT,
                         "%s: %zu bytes is above the %zu MB limit for this kind of file", path, n,
                         max_bytes / SS_MB);
        else
            ss_error_set(err, SS_ERR_INPUT,
                         "%s: %zu bytes is more than the %.0f MB of memory available", path, n,
                         avail / 1e6);
        return NULL;
    }
    char *buf = malloc(n + 1);
    if (!buf) {
        fclose(f);
        ss_error_set(err, SS_ERR_INPUT, "%s: %zu bytes do not fit in memory", path, n);
        return NULL;
    }
    size_t got = fread(buf, 1, n, f);
    fclose(f);
    if (got != n) {
        free(buf);
        ss_error_set(err, SS_ERR_INPUT, "%s: short read", path);
        return NULL;
    }
    buf[n] = '\0';
    if (len) *len = n;
    return buf;
}

ss_status ss_mkdir_p(const char *path, ss_error *err) {
    char buf[4096];
    if (!path || !*path) return ss_error_set(err, SS_ERR_INPUT, "empty directory name");
    if (strlen(path) >= sizeof buf)
        return ss_error_set(err, SS_ERR_INPUT, "%s: path too long", path);
    snprintf(buf, sizeof buf, "%s", path);
    for (char *p = buf + 1;; p++) {
        char c = *p;
        if (c == '/' || c == '\0') {
            *p = '\0';
            struct stat st;
            if (stat(buf, &st) != 0) {
                if (mkdir(buf, 0755) != 0 && errno != EEXIST)
                    return ss_error_set(err, SS_ERR_INPUT, "%s: cannot create directory %s: %s",
                                        path, buf, strerror(errno));
            } else if (!S_ISDIR(st.st_mode)) {
                return ss_error_set(err, SS_ERR_INPUT, "%s: %s exists and is not a directory", path,
                                    buf);
            }
            *p = c;
            if (c == '\0') break;
        }
    }
    return SS_OK;
}

ss_status ss_check_writable_dir(const char *dir, ss_error *err) {
    struct stat st;
    if (stat(dir, &st) == 0) {
        if (!S_ISDIR(st.st_mode))
            return ss_error_set(err, SS_ERR_INPUT, "%s: exists and is not a directory", dir);
        if (access(dir, W_OK | X_OK) != 0)
            return ss_error_set(err, SS_ERR_INPUT, "%s: directory is not writable", dir);
        return SS_OK;
    }
    /* Find the nearest existing ancestor and check we could create inside it. */
    char buf[4096];
    snprintf(buf, sizeof buf, "%s", dir);
    for (;;) {
        char *slash = strrchr(buf, '/');
        if (!slash) {
            snprintf(buf, sizeof buf, ".");
            break;
        }
        if (slash == buf) {
            buf[1] = '\0';
            break;
        }
        *slash = '\0';
        if (stat(buf, &st) == 0) break;
    }
    if (stat(buf, &st) != 0 || !S_ISDIR(st.st_mode))
        return ss_error_set(err, SS_ERR_INPUT, "%s: cannot be created (%s is not a directory)", dir,
                            buf);
    if (access(buf, W_OK | X_OK) != 0)
        return ss_error_set(err, SS_ERR_INPUT, "%s: cannot be created (%s is not writable)", dir,
                            buf);
    return SS_OK;
}

static int unlink_cb(const char *path, const struct stat *sb, int flag, struct FTW *ftw) {
    (void)sb;
    (void)flag;
    (void)ftw;
    return remove(path);
}

void ss_remove_tree(const char *path) {
    if (path && *path) nftw(path, unlink_cb, 16, FTW_DEPTH | FTW_PHYS);
}
