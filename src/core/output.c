/* The output discipline (DESIGN.md, docs/reliability.md): one place that
 * every command goes through for every file or folder it writes.
 *
 * - Checked before any work. A path is resolved at once (symlinks followed,
 *   ".." after a missing folder taken lexically) and refused, with the
 *   option and path in the message, when it is empty, too long, a broken
 *   link, a device, pipe or socket, a folder where a file is wanted, a
 *   folder that is not this command's finished output, the same place as
 *   another output, or an input (or a folder holding one).
 * - One run per output. A lock file NAME.skinsim-lock next to the target is
 *   held with flock(2): the kernel drops it when the run dies, so a lock
 *   left by kill -9 is never stale, and a second run is refused with the
 *   holder's pid. After taking it the inode is compared with the path's, so
 *   a lock unlinked by a finishing run is not mistaken for the live one.
 * - Staged next to the target (NAME.skinsim-staging.PID.XXXXXX, same file
 *   system, so the swap is a rename; a .skinsim-staging marker inside).
 *   What killed runs left there (staging, a backup, an atomic write's
 *   NAME.skinsim-tmp.PID.XXXXXX, a lock) is removed by the next run that
 *   holds the lock, but only what it can prove is skinsim's: the exact name
 *   with the id of a process that is gone and, for a folder, a skinsim
 *   marker inside (or nothing); a lock file only when its text is a skinsim
 *   lock's. A user's look-alike is never renamed, truncated or removed (a
 *   foreign file at the lock's name is refused). A backup whose target is
 *   missing is first put back. Free space is checked against the estimates.
 * - Swapped in whole. renameat2(RENAME_EXCHANGE) swaps new and old in one
 *   step, leaving the old at the staging name until every output of the
 *   run is in; if one swap fails, those done are swapped back. Where the
 *   file system lacks RENAME_EXCHANGE the old output is renamed to a backup
 *   first (the window between the two renames is what the backup recovery
 *   above covers). Folders carry a completion marker, written last.
 * What it gives up: several outputs of one run are each whole, but a kill
 * between two swaps can leave one new and one old; and an existing folder
 * without this command's marker is refused rather than replaced. */
#define _GNU_SOURCE /* renameat2, RENAME_EXCHANGE */
#include "skinsim/core.h"
#include "core_internal.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#ifndef PATH_MAX
#define PATH_MAX 4096
#endif
#ifndef NAME_MAX
#define NAME_MAX 255
#endif

/* Room kept in a path for what goes under and next to a target. */
#define STAGING_SUFFIX 48 /* ".skinsim-staging.PID.XXXXXX" and ".skinsim-tmp.PID.XXXXXX" */
#define SS_LOCK_PREFIX "skinsim-lock "
#define DIR_CONTENT_ROOM 256

typedef enum swap_state { SWAP_NONE, SWAP_EXCHANGED, SWAP_FRESH, SWAP_BACKUP } swap_state;

typedef struct out_entry {
    char *label, *user; /* as given, for messages */
    char *real;         /* resolved absolute target */
    char *parent, *base;
    ss_output_kind kind;
    double bytes;
    int lock_fd;
    char *lock_path;
    char *staging; /* staging folder */
    char *write;   /* staging, or staging/base */
    char **made;   /* parent folders begin created (outermost first) */
    int nmade;
    swap_state swapped;
    char *old; /* where the old output sits after the swap (to remove) */
} out_entry;

typedef struct in_entry {
    char *user, *real;
    dev_t dev;
    ino_t ino;
    int dir; /* an input folder (wound --heal DIR): no output may lie inside it */
} in_entry;

struct ss_outputs {
    char owner[64];
    out_entry *out;
    int nout;
    in_entry *in;
    int nin;
    int begun, finished;
};

/* ---- small helpers ------------------------------------------------------- */

/* A path short enough for a message: long ones keep their start and end. */
static const char *shown(const char *p, char buf[200]) {
    size_t n = p ? strlen(p) : 0;
    if (!p) return "(null)";
    if (n < 180) return p;
    snprintf(buf, 200, "%.80s...%s (%zu characters)", p, p + n - 80, n);
    return buf;
}

static char *join(const char *a, const char *b) {
    size_t na = strlen(a), nb = strlen(b);
    char *s = malloc(na + nb + 2);
    if (!s) return NULL;
    memcpy(s, a, na);
    size_t k = na;
    if (!(na == 1 && a[0] == '/')) s[k++] = '/';
    memcpy(s + k, b, nb + 1);
    return s;
}

static char *dirname_of(const char *p) {
    const char *sl = strrchr(p, '/');
    if (!sl) return strdup(".");
    if (sl == p) return strdup("/");
    return strndup(p, (size_t)(sl - p));
}

static int path_within(const char *inner, const char *outer) {
    size_t n = strlen(outer);
    if (strncmp(inner, outer, n) != 0) return 0;
    return inner[n] == '/' || inner[n] == '\0' || (n == 1 && outer[0] == '/');
}

/* Absolute, physically resolved form of p, which need not exist: the
 * longest existing prefix through realpath(3), the rest lexically (a
 * missing folder cannot be a symlink). A broken symlink, a file used as a
 * folder, a loop or a component over NAME_MAX is an error (errno-like
 * reason in *why). */
static char *resolve(const char *p, const char **why) {
    char *r = realpath(p, NULL);
    if (r) return r;
    int e = errno;
    struct stat st;
    if (e != ENOENT) {
        *why = e == ENOTDIR        ? "a part of it is a file, not a folder"
               : e == ELOOP        ? "too many levels of symbolic links"
               : e == EACCES       ? "permission denied on a folder in it"
               : e == ENAMETOOLONG ? "a name in it is too long"
                                   : strerror(e);
        return NULL;
    }
    if (lstat(p, &st) == 0 && S_ISLNK(st.st_mode)) {
        *why = "it is a broken symbolic link (its target does not exist)";
        return NULL;
    }
    /* p itself is missing: resolve its folder, then append the last name. */
    size_t n = strlen(p);
    while (n > 1 && p[n - 1] == '/') n--;
    char *q = strndup(p, n);
    if (!q) return NULL;
    char *sl = strrchr(q, '/');
    const char *base;
    char *dir;
    if (!sl) {
        dir = strdup(".");
        base = q;
    } else {
        *sl = '\0';
        dir = strdup(sl == q ? "/" : q);
        base = sl + 1;
    }
    char *out = NULL;
    if (dir && strlen(base) > NAME_MAX) {
        *why = "a name in it is longer than 255 bytes";
    } else if (dir) {
        char *rd = resolve(dir, why);
        if (rd) {
            if (!strcmp(base, ".") || !*base) {
                out = rd;
                rd = NULL;
            } else if (!strcmp(base, "..")) {
                out = dirname_of(rd);
            } else {
                out = join(rd, base);
            }
            free(rd);
        }
    }
    free(dir);
    free(q);
    return out;
}

static int dir_is_empty(const char *path) {
    DIR *d = opendir(path);
    if (!d) return 0;
    struct dirent *e;
    int empty = 1;
    while ((e = readdir(d)))
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
            empty = 0;
            break;
        }
    closedir(d);
    return empty;
}

/* 1 when no process has this id (the run that named a leftover is gone). */
static int process_gone(long pid) {
    return pid > 0 && pid <= INT_MAX && kill((pid_t)pid, 0) != 0 && errno == ESRCH;
}

/* ---- markers ---------------------------------------------------------------- */

/* Reads dir/name (a regular file, not followed through a link) into buf, at
 * most n - 1 bytes, NUL-terminated; -1 when it is not there or not readable. */
static ssize_t marker_read(const char *dir, const char *name, char *buf, size_t n) {
    char *m = join(dir, name);
    if (!m) return -1;
    int fd = open(m, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOFOLLOW);
    free(m);
    if (fd < 0) return -1;
    memset(buf, 0, n);
    struct stat st;
    ssize_t r = fstat(fd, &st) == 0 && S_ISREG(st.st_mode) ? read(fd, buf, n - 1) : -1;
    close(fd);
    return r;
}

/* 1 when dir/name is a regular file reading "skinsim <owner>\n". */
static int marker_says(const char *dir, const char *name, const char *owner) {
    char buf[128];
    if (marker_read(dir, name, buf, sizeof buf) < 0) return 0;
    if (!owner) return 1;
    char want[100];
    snprintf(want, sizeof want, "skinsim %s\n", owner);
    return strcmp(buf, want) == 0;
}

/* The command a finished folder's marker names ("abrasion"), into buf; 0 when
 * the folder has no readable marker of the form "skinsim <command>\n". */
static int marker_owner(const char *dir, char *buf, size_t n) {
    char text[128];
    ssize_t r = marker_read(dir, SS_OUTPUT_MARKER, text, sizeof text);
    size_t len = r > 0 ? strlen(text) : 0;
    if (len < 10 || strncmp(text, "skinsim ", 8) || text[len - 1] != '\n') return 0;
    text[len - 1] = '\0';
    for (const char *c = text + 8; *c; c++)
        if (!((*c >= 'a' && *c <= 'z') || *c == '-' || *c == '_')) return 0;
    if (strlen(text + 8) >= n) return 0;
    memcpy(buf, text + 8, strlen(text + 8) + 1);
    return 1;
}

int ss_output_dir_is_complete(const char *dir, const char *owner) {
    return marker_says(dir, SS_OUTPUT_MARKER, owner);
}

int ss_output_dir_is_unfinished(const char *dir, const char *owner) {
    return marker_says(dir, SS_OUTPUT_UNFINISHED, owner);
}

static ss_status put_marker(const char *dir, const char *name, const char *owner, ss_error *err) {
    char *m = join(dir, name);
    if (!m) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    char text[100];
    snprintf(text, sizeof text, "skinsim %s\n", owner ? owner : "");
    ss_status st = ss_write_file_atomic(m, text, strlen(text), err);
    free(m);
    return st;
}

static ss_status drop_marker(const char *dir, const char *name, ss_error *err) {
    char *m = join(dir, name);
    if (!m) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    int bad = unlink(m) != 0 && errno != ENOENT;
    int e = errno;
    free(m);
    if (bad)
        return ss_error_set(err, SS_ERR_RUNTIME, "%s: cannot remove its marker %s: %s", dir, name,
                            strerror(e));
    return SS_OK;
}

/* Complete: the unfinished marker goes once the complete one is in. */
ss_status ss_output_dir_mark_complete(const char *dir, const char *owner, ss_error *err) {
    ss_status st = put_marker(dir, SS_OUTPUT_MARKER, owner, err);
    return st ? st : drop_marker(dir, SS_OUTPUT_UNFINISHED, err);
}

ss_status ss_output_dir_mark_incomplete(const char *dir, ss_error *err) {
    return drop_marker(dir, SS_OUTPUT_MARKER, err);
}

/* Unfinished: that marker first, then the complete one goes. */
static ss_status mark_unfinished(const char *dir, const char *owner, ss_error *err) {
    ss_status st = put_marker(dir, SS_OUTPUT_UNFINISHED, owner, err);
    return st ? st : drop_marker(dir, SS_OUTPUT_MARKER, err);
}

/* ---- the set ---------------------------------------------------------------- */

ss_outputs *ss_outputs_create(const char *owner, ss_error *err) {
    ss_outputs *o = calloc(1, sizeof *o);
    if (!o) {
        ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        return NULL;
    }
    snprintf(o->owner, sizeof o->owner, "%s", owner ? owner : "skinsim");
    return o;
}

int ss_outputs_count(const ss_outputs *o) { return o ? o->nout : 0; }

const char *ss_outputs_path(const ss_outputs *o, int i) {
    return o && i >= 0 && i < o->nout && o->out[i].write ? o->out[i].write : NULL;
}

const char *ss_outputs_target(const ss_outputs *o, int i) {
    return o && i >= 0 && i < o->nout ? o->out[i].real : NULL;
}

/* The label-and-path prefix of every message about output e. */
#define OUTMSG(e, fmt, ...)                                                                        \
    ss_error_set(err, SS_ERR_INPUT, "%s%s%s: " fmt, (e)->label ? (e)->label : "",                  \
                 (e)->label ? " " : "", shown((e)->user, sb), __VA_ARGS__)

static int clash_with_input(const ss_outputs *o, const out_entry *e, const in_entry *in) {
    (void)o;
    if (!in->real) return 0;
    if (!strcmp(in->real, e->real)) return 1;
    struct stat st;
    if (in->ino && stat(e->real, &st) == 0 && st.st_dev == in->dev && st.st_ino == in->ino)
        return 1;
    return (e->kind != SS_OUTPUT_FILE && path_within(in->real, e->real)) ||
           (in->dir && path_within(e->real, in->real));
}

static const char *clash_words(const out_entry *e, const in_entry *in) {
    return in->dir && path_within(e->real, in->real) && strcmp(e->real, in->real)
               ? "it lies inside the input folder"
               : "it would overwrite the input";
}

ss_status ss_outputs_input(ss_outputs *o, const char *path, ss_error *err) {
    if (!o || !path || !*path) return SS_OK;
    struct stat st;
    if (stat(path, &st) != 0) return SS_OK; /* the reader reports it */
    const char *why = NULL;
    char *real = resolve(path, &why);
    if (!real) return SS_OK;
    in_entry *grown = realloc(o->in, (size_t)(o->nin + 1) * sizeof *grown);
    char *user = strdup(path);
    if (!grown || !user) {
        free(real);
        free(user);
        if (grown) o->in = grown;
        return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    o->in = grown;
    in_entry *in = &o->in[o->nin++];
    in->user = user;
    in->real = real;
    in->dev = st.st_dev;
    in->ino = st.st_ino;
    in->dir = S_ISDIR(st.st_mode);
    char sb[200], sb2[200];
    for (int i = 0; i < o->nout; i++)
        if (clash_with_input(o, &o->out[i], in))
            return ss_error_set(err, SS_ERR_INPUT, "%s%s%s: %s %s",
                                o->out[i].label ? o->out[i].label : "", o->out[i].label ? " " : "",
                                shown(o->out[i].user, sb), clash_words(&o->out[i], in),
                                shown(path, sb2));
    return SS_OK;
}

static void free_entry(out_entry *e) {
    free(e->label);
    free(e->user);
    free(e->real);
    free(e->parent);
    free(e->base);
    free(e->lock_path);
    free(e->staging);
    free(e->write);
    free(e->old);
    for (int k = 0; k < e->nmade; k++) free(e->made[k]);
    free(e->made);
}

/* A refused output leaves the set as it was. */
static void pop_entry(ss_outputs *o) { free_entry(&o->out[--o->nout]); }

/* The checks of an existing or missing target that need no lock. */
/* 1 when a folder can be made in dir (made and removed at once), else 0
 * with the reason in *why. */
static int probe_dir(const char *dir, int *why) {
    char p[PATH_MAX];
    if (snprintf(p, sizeof p, "%s/.skinsim-probe.XXXXXX", dir) >= (int)sizeof p) {
        *why = ENAMETOOLONG;
        return 0;
    }
    if (!mkdtemp(p)) {
        *why = errno;
        return 0;
    }
    rmdir(p);
    return 1;
}

static ss_status check_target(const ss_outputs *o, out_entry *e, ss_error *err) {
    char sb[200];
    struct stat st;
    if (lstat(e->real, &st) == 0) {
        if (e->kind == SS_OUTPUT_FILE) {
            if (S_ISDIR(st.st_mode)) return OUTMSG(e, "%s", "is a folder; give a file name");
            if (!S_ISREG(st.st_mode))
                return OUTMSG(e,
                              "is %s; skinsim writes regular files and never replaces anything "
                              "else",
                              ss__file_kind(st.st_mode));
        } else {
            if (!S_ISDIR(st.st_mode))
                return OUTMSG(e, "exists and is %s, not a folder",
                              S_ISREG(st.st_mode) ? "a file" : ss__file_kind(st.st_mode));
            if (!strcmp(e->real, "/"))
                return OUTMSG(e, "%s", "is the root folder; give a folder of its own");
            int ours = ss_output_dir_is_complete(e->real, o->owner) ||
                       ss_output_dir_is_unfinished(e->real, o->owner) || dir_is_empty(e->real);
            char other[64];
            if (!ours && marker_owner(e->real, other, sizeof other))
                return OUTMSG(e,
                              "is a finished 'skinsim %s' output folder, not a 'skinsim %s' one, "
                              "so it is not replaced; choose another folder",
                              other, o->owner);
            if (!ours)
                return OUTMSG(e,
                              "exists and is not a finished 'skinsim %s' output folder (no %s "
                              "marker from a completed run), so it is not replaced; remove it "
                              "or choose another folder",
                              o->owner, SS_OUTPUT_MARKER);
        }
        if (access(e->parent, W_OK | X_OK) != 0)
            return OUTMSG(e, "its folder %s is not writable", e->parent);
        return SS_OK;
    }
    /* Missing: the nearest existing folder above must be writable. */
    int errno_probe = 0;
    char *d = strdup(e->parent);
    if (!d) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    while (stat(d, &st) != 0 && strcmp(d, "/")) {
        char *up = dirname_of(d);
        free(d);
        if (!(d = up)) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    ss_status s = SS_OK;
    if (!S_ISDIR(st.st_mode))
        s = OUTMSG(e, "%s is not a folder", d);
    else if (access(d, W_OK | X_OK) != 0)
        s = OUTMSG(e, "cannot be created: the folder %s is not writable", d);
    else if (!probe_dir(d, &errno_probe))
        /* access() says yes to root everywhere; /proc, /sys and read-only
         * mounts refuse new entries all the same: try one */
        s = OUTMSG(e, "cannot be created in %s: %s", d, strerror(errno_probe));
    free(d);
    return s;
}

ss_status ss_outputs_add(ss_outputs *o, const char *label, const char *path, ss_output_kind kind,
                         double bytes, ss_error *err) {
    char sb[200], sb2[200];
    if (!o) return ss_error_set(err, SS_ERR_INPUT, "no output set");
    const char *lab = label ? label : "output";
    if (o->begun) return ss_error_set(err, SS_ERR_RUNTIME, "%s: added after begin", lab);
    if (!path || !*path)
        return ss_error_set(err, SS_ERR_INPUT, "%s: the path is empty; give a %s name", lab,
                            kind != SS_OUTPUT_FILE ? "folder" : "file");
    size_t n = strlen(path);
    if (n >= PATH_MAX)
        return ss_error_set(err, SS_ERR_INPUT, "%s %s: path too long (at most %d characters)", lab,
                            shown(path, sb), PATH_MAX - 1);
    if (kind == SS_OUTPUT_FILE && path[n - 1] == '/')
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s %s: ends in '/', which names a folder; give a "
                            "file name",
                            lab, shown(path, sb));
    const char *why = "out of memory";
    char *real = resolve(path, &why);
    if (!real) return ss_error_set(err, SS_ERR_INPUT, "%s %s: %s", lab, shown(path, sb), why);
    out_entry *grown = realloc(o->out, (size_t)(o->nout + 1) * sizeof *grown);
    if (!grown) {
        free(real);
        return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    o->out = grown;
    out_entry *e = &o->out[o->nout];
    memset(e, 0, sizeof *e);
    e->lock_fd = -1;
    e->kind = kind;
    e->bytes = bytes > 0 ? bytes : 0;
    e->real = real;
    e->user = strdup(path);
    e->label = label ? strdup(label) : NULL;
    e->parent = dirname_of(real);
    const char *sl = strrchr(real, '/');
    e->base = strdup(sl ? sl + 1 : real);
    o->nout++;
    if (!e->user || (label && !e->label) || !e->parent || !e->base) {
        pop_entry(o);
        return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    ss_status s = SS_OK;
    size_t room = kind != SS_OUTPUT_FILE ? DIR_CONTENT_ROOM : 0;
    if (strlen(real) + STAGING_SUFFIX + room >= PATH_MAX)
        s = OUTMSG(e, "path too long (%zu characters resolved; at most %zu)", strlen(real),
                   (size_t)PATH_MAX - STAGING_SUFFIX - room - 1);
    else if (strlen(e->base) + STAGING_SUFFIX > NAME_MAX)
        s = OUTMSG(e, "the name %s is too long (at most %d bytes here)", shown(e->base, sb2),
                   NAME_MAX - STAGING_SUFFIX);
    long holder = s ? 0 : ss_output_lock_holder(real);
    if (holder)
        s = holder > 0 ? OUTMSG(e,
                                "another skinsim run (process %ld) is writing it; wait for it to "
                                "finish or choose another output",
                                holder)
                       : OUTMSG(e, "%s",
                                "another skinsim run is writing it; wait for it to finish or "
                                "choose another output");
    if (!s) s = check_target(o, e, err);
    for (int i = 0; i < o->nout - 1 && !s; i++) {
        out_entry *p = &o->out[i];
        if (!strcmp(p->real, e->real))
            s = OUTMSG(e, "names the same place as %s %s", p->label ? p->label : "output",
                       shown(p->user, sb2));
        else if ((p->kind != SS_OUTPUT_FILE && path_within(e->real, p->real)) ||
                 (e->kind != SS_OUTPUT_FILE && path_within(p->real, e->real)))
            s = OUTMSG(e, "overlaps %s %s (a folder output is replaced whole)",
                       p->label ? p->label : "output", shown(p->user, sb2));
    }
    for (int i = 0; i < o->nin && !s; i++)
        if (clash_with_input(o, e, &o->in[i]))
            s = OUTMSG(e, "%s %s", clash_words(e, &o->in[i]), shown(o->in[i].user, sb2));
    if (s) pop_entry(o);
    return s;
}

/* ---- begin ------------------------------------------------------------------- */

/* mkdir -p of e->parent, remembering what was created. */
static ss_status make_parents(out_entry *e, ss_error *err) {
    struct stat st;
    if (stat(e->parent, &st) == 0) return SS_OK;
    char *todo[PATH_MAX / 2];
    int nt = 0;
    char *d = strdup(e->parent);
    while (d && stat(d, &st) != 0 && strcmp(d, "/") && nt < (int)(sizeof todo / sizeof *todo)) {
        todo[nt++] = d;
        d = dirname_of(d);
    }
    free(d);
    e->made = calloc((size_t)nt + 1, sizeof *e->made);
    ss_status s = e->made ? SS_OK : ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    for (int k = nt - 1; k >= 0; k--) {
        if (!s) {
            if (mkdir(todo[k], 0755) == 0) {
                e->made[e->nmade++] = todo[k];
                continue;
            }
            if (errno != EEXIST)
                s = ss_error_set(err, SS_ERR_INPUT, "%s: cannot create the folder %s: %s", e->user,
                                 todo[k], strerror(errno));
        }
        free(todo[k]);
    }
    return s;
}

static void remove_made(out_entry *e) {
    for (int k = e->nmade - 1; k >= 0; k--) {
        rmdir(e->made[k]);
        free(e->made[k]);
    }
    free(e->made);
    e->made = NULL;
    e->nmade = 0;
}

static void release_lock(out_entry *e) {
    struct stat a, b;
    if (e->lock_fd >= 0) {
        /* ours only (the inode we hold), while held: a waiter re-checks the inode */
        if (fstat(e->lock_fd, &a) == 0 && lstat(e->lock_path, &b) == 0 && a.st_ino == b.st_ino &&
            a.st_dev == b.st_dev)
            unlink(e->lock_path);
        close(e->lock_fd);
        e->lock_fd = -1;
    }
}

/* The pid a lock file's text names: "skinsim-lock PID\n" (written since the
 * leftovers are proven), or "PID\n" of earlier versions; 0 for anything else
 * (a file of the user's that merely has the name). */
static long lock_text_pid(const char *buf, int *legacy) {
    const char *p = buf;
    *legacy = strncmp(p, SS_LOCK_PREFIX, strlen(SS_LOCK_PREFIX)) != 0;
    if (!*legacy) p += strlen(SS_LOCK_PREFIX);
    char *end;
    errno = 0;
    long pid = strtol(p, &end, 10);
    if (end == p || *p < '0' || *p > '9' || errno || strcmp(end, "\n") || pid <= 0) return 0;
    return pid;
}

/* A new lock file, created with its text and locked before anyone can see
 * it (O_TMPFILE linked in), so a kill never leaves one that is not provably
 * ours. -1 with errno EEXIST when another run made one first. */
static int create_lock(const out_entry *e) {
    char text[48];
    int len = snprintf(text, sizeof text, SS_LOCK_PREFIX "%ld\n", (long)getpid());
#ifdef O_TMPFILE
    int fd = open(e->parent, O_TMPFILE | O_RDWR | O_CLOEXEC, 0644);
    if (fd >= 0) {
        char proc[64];
        snprintf(proc, sizeof proc, "/proc/self/fd/%d", fd);
        if (pwrite(fd, text, (size_t)len, 0) == len && flock(fd, LOCK_EX | LOCK_NB) == 0 &&
            linkat(AT_FDCWD, proc, AT_FDCWD, e->lock_path, AT_SYMLINK_FOLLOW) == 0)
            return fd;
        int er = errno;
        close(fd);
        if (er == EEXIST) {
            errno = er;
            return -1;
        }
    } /* no O_TMPFILE or no /proc here: create, lock, then write (a kill in
         between leaves an empty file, which is refused, not removed) */
#endif
    int f2 = open(e->lock_path, O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0644);
    if (f2 < 0) return -1;
    if (flock(f2, LOCK_EX | LOCK_NB) != 0 || pwrite(f2, text, (size_t)len, 0) != len) {
        close(f2);
        errno = EEXIST; /* someone opened it first: look again */
        return -1;
    }
    return f2;
}

static ss_status take_lock(out_entry *e, ss_error *err) {
    char sb[200];
    size_t n = strlen(e->real) + 16;
    e->lock_path = malloc(n);
    if (!e->lock_path) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    snprintf(e->lock_path, n, "%s.skinsim-lock", e->real);
    for (int attempt = 0; attempt < 20; attempt++) {
        int fd = open(e->lock_path, O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
        if (fd < 0 && errno == ENOENT) {
            if ((fd = create_lock(e)) >= 0) {
                e->lock_fd = fd;
                return SS_OK;
            }
            if (errno == EEXIST) continue;
        }
        if (fd < 0)
            return ss_error_set(err, SS_ERR_INPUT, "%s: cannot create its lock file %s: %s",
                                shown(e->user, sb), e->lock_path,
                                errno == ELOOP ? "it is a symbolic link" : strerror(errno));
        struct stat a, b;
        if (fstat(fd, &a) != 0 || !S_ISREG(a.st_mode)) {
            close(fd);
            return ss_error_set(err, SS_ERR_INPUT, "%s: its lock file %s is not a regular file",
                                shown(e->user, sb), e->lock_path);
        }
        char buf[64] = {0};
        ssize_t got = a.st_size < (off_t)sizeof buf ? pread(fd, buf, sizeof buf - 1, 0) : -1;
        int legacy = 0;
        long pid = got > 0 ? lock_text_pid(buf, &legacy) : 0;
        if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
            close(fd);
            if (pid > 0)
                return ss_error_set(err, SS_ERR_INPUT,
                                    "%s: another skinsim run (process %ld) is writing it; wait "
                                    "for it to finish or choose another output",
                                    shown(e->user, sb), pid);
            return ss_error_set(err, SS_ERR_INPUT,
                                "%s: another skinsim run is writing it; wait for it to finish "
                                "or choose another output",
                                shown(e->user, sb));
        }
        if (stat(e->lock_path, &b) != 0 || a.st_ino != b.st_ino || a.st_dev != b.st_dev) {
            close(fd); /* the holder removed it as we opened it: try again */
            continue;
        }
        /* unlocked: the lock of a killed run when its text is a skinsim lock's
         * (an earlier version's "PID" only when that process is gone); it is
         * removed and made anew. Anything else is the user's and is kept. */
        if (pid > 0 && (!legacy || process_gone(pid))) {
            unlink(e->lock_path);
            close(fd);
            continue;
        }
        close(fd);
        if (a.st_size == 0 && attempt < 19) { /* being created by the fallback: look again */
            usleep(10000);
            continue;
        }
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: %s exists and is not a skinsim lock file, so it is left as it "
                            "is; move it away or choose another output",
                            shown(e->user, sb), e->lock_path);
    }
    return ss_error_set(err, SS_ERR_INPUT, "%s: its lock file %s keeps changing",
                        shown(e->user, sb), e->lock_path);
}

long ss_output_lock_holder(const char *path) {
    const char *why = NULL;
    char *real = path && *path ? resolve(path, &why) : NULL;
    if (!real) return 0;
    size_t n = strlen(real) + 16;
    char *lp = malloc(n);
    if (lp) snprintf(lp, n, "%s.skinsim-lock", real);
    free(real);
    int fd = lp ? open(lp, O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK) : -1;
    free(lp);
    if (fd < 0) return 0;
    long pid = 0;
    if (flock(fd, LOCK_SH | LOCK_NB) == 0) {
        flock(fd, LOCK_UN);
    } else {
        char buf[64] = {0};
        ssize_t got = pread(fd, buf, sizeof buf - 1, 0);
        int legacy;
        pid = got > 0 ? lock_text_pid(buf, &legacy) : 0;
        if (pid <= 0) pid = -1;
    }
    close(fd);
    return pid;
}

/* A name of ours next to base: BASE + mid + PID + "." + 6 letters or digits
 * (mkdtemp/mkstemp); the pid in *pid. */
static int our_name(const char *name, const char *base, const char *mid, long *pid) {
    size_t nb = strlen(base), nm = strlen(mid);
    if (strncmp(name, base, nb) || strncmp(name + nb, mid, nm)) return 0;
    const char *p = name + nb + nm, *q = p;
    long v = 0;
    while (*q >= '0' && *q <= '9' && q - p < 10) v = v * 10 + (*q++ - '0');
    if (q == p || *p == '0' || *q != '.' || strlen(q + 1) != 6 || v <= 0) return 0;
    for (const char *c = q + 1; *c; c++)
        if (!((*c >= '0' && *c <= '9') || (*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z')))
            return 0;
    *pid = v;
    return 1;
}

/* 1 when dir/name is a regular file whose text a skinsim marker has. */
static int skinsim_marker(const char *dir, const char *name) {
    char *m = join(dir, name);
    if (!m) return 0;
    int fd = open(m, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOFOLLOW);
    free(m);
    if (fd < 0) return 0;
    char buf[128] = {0};
    struct stat st;
    ssize_t n = fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size < (off_t)sizeof buf
                    ? read(fd, buf, sizeof buf - 1)
                    : -1;
    close(fd);
    return n > 8 && !strncmp(buf, "skinsim ", 8) && buf[n - 1] == '\n';
}

/* A folder a skinsim run made: its staging marker, a completion marker (an
 * output swapped out, or one finished but not yet swapped in), or empty. */
static int our_folder(const char *path) {
    struct stat st;
    if (lstat(path, &st) != 0 || !S_ISDIR(st.st_mode)) return 0;
    return skinsim_marker(path, SS_OUTPUT_STAGING) || skinsim_marker(path, SS_OUTPUT_MARKER) ||
           dir_is_empty(path);
}

/* What killed runs left next to e's target; called with the lock held, so
 * no live run owns any of it. Only what is provably a skinsim run's goes:
 * the name carries the marker and the id of a process that is gone, and a
 * folder holds a skinsim marker (or nothing); a file or folder of the
 * user's that merely looks alike (res.skinsim-staging.mine, s.csv.tmp.1) is
 * never touched. */
static void clean_stale(out_entry *e) {
    DIR *d = opendir(e->parent);
    if (!d) return;
    struct dirent *de;
    char **names = NULL;
    int nn = 0;
    while ((de = readdir(d))) {
        const char *nm = de->d_name;
        long pid;
        if ((our_name(nm, e->base, ".skinsim-staging.", &pid) ||
             our_name(nm, e->base, ".skinsim-backup.", &pid) ||
             our_name(nm, e->base, SS_ATOMIC_TMP, &pid)) &&
            process_gone(pid)) {
            char **g = realloc(names, (size_t)(nn + 1) * sizeof *g);
            if (!g) break;
            names = g;
            if ((names[nn] = strdup(nm))) nn++;
        }
    }
    closedir(d);
    struct stat st;
    const size_t nb = strlen(e->base);
    for (int i = 0; i < nn; i++) {
        char *p = join(e->parent, names[i]);
        const char *mid = names[i] + nb;
        if (p && lstat(p, &st) == 0) {
            int backup = !strncmp(mid, ".skinsim-backup.", 16);
            int tmp = !strncmp(mid, SS_ATOMIC_TMP, strlen(SS_ATOMIC_TMP));
            if (tmp || (backup && e->kind == SS_OUTPUT_FILE)) {
                /* a file: an atomic write's temporary, or a file output's old
                 * version (put back when a swap was killed half way) */
                if (S_ISREG(st.st_mode) &&
                    !(backup && lstat(e->real, &st) != 0 && rename(p, e->real) == 0))
                    unlink(p);
            } else if (our_folder(p)) {
                /* a swap killed between its two renames: the old one goes back */
                if (!(backup && lstat(e->real, &st) != 0 && rename(p, e->real) == 0))
                    ss_remove_tree(p);
            }
        }
        free(p);
        free(names[i]);
    }
    free(names);
}

static ss_status make_staging(const ss_outputs *o, out_entry *e, ss_error *err) {
    char sb[200];
    if (e->kind == SS_OUTPUT_DIR_IN_PLACE) { /* the folder itself, marked unfinished */
        if (mkdir(e->real, 0755) != 0 && errno != EEXIST)
            return ss_error_set(err, SS_ERR_INPUT, "%s: cannot create the folder: %s",
                                shown(e->user, sb), strerror(errno));
        e->write = strdup(e->real);
        if (!e->write) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        return mark_unfinished(e->real, o->owner, err);
    }
    size_t n = strlen(e->real) + STAGING_SUFFIX;
    char *t = malloc(n);
    if (!t) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    snprintf(t, n, "%s.skinsim-staging.%ld.XXXXXX", e->real, (long)getpid());
    if (!mkdtemp(t)) {
        int er = errno;
        free(t);
        return ss_error_set(err, er == ENOSPC || er == EDQUOT ? SS_ERR_INPUT : SS_ERR_RUNTIME,
                            "%s: cannot create a staging folder next to it: %s", shown(e->user, sb),
                            strerror(er));
    }
    chmod(t, 0755);
    e->staging = t;
    e->write = e->kind == SS_OUTPUT_DIR ? strdup(t) : join(t, e->base);
    if (!e->write) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    /* what proves to a later run that this folder is a skinsim run's */
    char text[64];
    snprintf(text, sizeof text, "staging %ld", (long)getpid());
    return put_marker(t, SS_OUTPUT_STAGING, text, err);
}

static const char *human_bytes(double v, char buf[32]) {
    if (v >= 1e12)
        snprintf(buf, 32, "%.1f TB", v / 1e12);
    else if (v >= 1e9)
        snprintf(buf, 32, "%.1f GB", v / 1e9);
    else
        snprintf(buf, 32, "%.1f MB", v / 1e6);
    return buf;
}

/* Free space against the estimates, summed per file system. */
static ss_status check_space(ss_outputs *o, ss_error *err) {
    char sb[200];
    for (int i = 0; i < o->nout; i++) {
        struct statvfs vi;
        if (o->out[i].bytes <= 0 || statvfs(o->out[i].parent, &vi) != 0) continue;
        double need = 0;
        int first = 1;
        for (int j = 0; j < o->nout; j++) {
            struct statvfs vj;
            if (statvfs(o->out[j].parent, &vj) != 0 || vj.f_fsid != vi.f_fsid) continue;
            if (j < i && o->out[j].bytes > 0) first = 0;
            need += o->out[j].bytes;
        }
        if (!first) continue;
        double avail = (double)vi.f_bavail * (double)vi.f_frsize;
        if (need > avail) {
            out_entry *e = &o->out[i];
            char a[32], b[32];
            return ss_error_set(err, SS_ERR_INPUT,
                                "%s%s%s: needs about %s of disk, but only %s are free in %s; "
                                "free some space or write less",
                                e->label ? e->label : "", e->label ? " " : "", shown(e->user, sb),
                                human_bytes(need, a), human_bytes(avail, b), e->parent);
        }
    }
    return SS_OK;
}

static void rollback(ss_outputs *o) {
    for (int i = 0; i < o->nout; i++) {
        out_entry *e = &o->out[i];
        if (e->kind == SS_OUTPUT_DIR_IN_PLACE && e->write) {
            /* left as it is, marked unfinished, for a resume */
            for (int k = 0; k < e->nmade; k++) free(e->made[k]);
            e->nmade = 0;
        }
        if (e->staging) ss_remove_tree(e->staging);
        free(e->staging);
        free(e->write);
        e->staging = e->write = NULL;
        release_lock(e); /* first: the lock file sits in a folder begin may remove */
        remove_made(e);
    }
}

ss_status ss_outputs_begin(ss_outputs *o, ss_error *err) {
    if (!o || o->begun) return ss_error_set(err, SS_ERR_RUNTIME, "outputs: begin called twice");
    o->begun = 1;
    ss_status s = SS_OK;
    for (int i = 0; i < o->nout && !s; i++) {
        out_entry *e = &o->out[i];
        s = make_parents(e, err);
        if (!s) s = take_lock(e, err);
        if (!s) clean_stale(e);
        if (!s) s = check_target(o, e, err); /* again, now that it is ours */
    }
    if (!s) s = check_space(o, err);
    for (int i = 0; i < o->nout && !s; i++) s = make_staging(o, &o->out[i], err);
    if (s) {
        rollback(o);
        o->finished = 1;
    }
    return s;
}

/* ---- finish ------------------------------------------------------------------ */

static int exchange(const char *a, const char *b) {
#ifdef RENAME_EXCHANGE
    return renameat2(AT_FDCWD, a, AT_FDCWD, b, RENAME_EXCHANGE);
#else
    (void)a;
    (void)b;
    errno = EINVAL;
    return -1;
#endif
}

static int rename_noreplace(const char *a, const char *b) {
#ifdef RENAME_NOREPLACE
    if (renameat2(AT_FDCWD, a, AT_FDCWD, b, RENAME_NOREPLACE) == 0) return 0;
    if (errno != EINVAL && errno != ENOSYS) return -1;
#endif
    struct stat st;
    if (lstat(b, &st) == 0) {
        errno = EEXIST;
        return -1;
    }
    return rename(a, b);
}

static void sync_dir(const char *dir) {
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd >= 0) {
        fsync(fd);
        close(fd);
    }
}

/* Swaps output e in; on success e->swapped says how and e->old where the
 * old output now is (NULL if there was none). */
static int swap_in(out_entry *e) {
    struct stat st;
    if (lstat(e->real, &st) != 0) {
        if (rename_noreplace(e->write, e->real) != 0) return -1;
        e->swapped = SWAP_FRESH;
        return 0;
    }
    if (exchange(e->write, e->real) == 0) {
        e->swapped = SWAP_EXCHANGED;
        e->old = strdup(e->write); /* the old output, at the staging name */
        return 0;
    }
    if (errno != EINVAL && errno != ENOSYS && errno != EOPNOTSUPP) return -1;
    /* No RENAME_EXCHANGE here: old -> backup, new -> target. */
    size_t n = strlen(e->real) + STAGING_SUFFIX;
    char *b = malloc(n);
    if (!b) return -1;
    snprintf(b, n, "%s.skinsim-backup.%ld.XXXXXX", e->real, (long)getpid());
    int bfd = -1; /* a file's backup is a file (rename over an empty one), a folder's a folder */
    if (e->kind == SS_OUTPUT_FILE ? (bfd = mkstemp(b)) < 0 : !mkdtemp(b)) {
        free(b);
        return -1;
    }
    if (bfd >= 0) close(bfd);
    if (rename(e->real, b) != 0) {
        int er = errno;
        if (e->kind == SS_OUTPUT_FILE)
            unlink(b);
        else
            rmdir(b);
        free(b);
        errno = er;
        return -1;
    }
    if (rename(e->write, e->real) != 0) {
        int er = errno;
        rename(b, e->real);
        free(b);
        errno = er;
        return -1;
    }
    e->swapped = SWAP_BACKUP;
    e->old = b;
    return 0;
}

static void swap_back(out_entry *e) {
    if (e->swapped == SWAP_EXCHANGED)
        exchange(e->write, e->real);
    else if (e->swapped == SWAP_FRESH)
        rename(e->real, e->write);
    else if (e->swapped == SWAP_BACKUP && rename(e->real, e->write) == 0)
        rename(e->old, e->real);
    e->swapped = SWAP_NONE;
    free(e->old);
    e->old = NULL;
}

/* Messages of failed writes name the staging path: show the target. */
static void unstage_message(ss_outputs *o, ss_error *err) {
    if (!err) return;
    for (int i = 0; i < o->nout; i++) {
        const char *from = o->out[i].write, *to = o->out[i].user;
        if (!from || !to) continue;
        char buf[sizeof err->msg];
        size_t nf = strlen(from), k = 0;
        const char *p = err->msg;
        for (const char *q; (q = strstr(p, from)) && k < sizeof buf;) {
            k += (size_t)snprintf(buf + k, sizeof buf - k, "%.*s%s", (int)(q - p), p, to);
            p = q + nf;
        }
        if (p == err->msg || k >= sizeof buf) continue;
        snprintf(buf + k, sizeof buf - k, "%s", p);
        memcpy(err->msg, buf, sizeof buf);
    }
}

ss_status ss_outputs_finish(ss_outputs *o, ss_status status, ss_error *err) {
    if (!o) return status;
    if (!o->begun || o->finished) return status;
    o->finished = 1;
    char sb[200];
    if (status) {
        unstage_message(o, err);
        rollback(o);
        return status;
    }
    ss_status s = SS_OK;
    for (int i = 0; i < o->nout && !s; i++) {
        out_entry *e = &o->out[i];
        struct stat st;
        /* what sits at the target now must still be replaceable: something
         * put there during the run (a folder, a pipe) is never swapped out */
        if ((s = check_target(o, e, err))) {
            s = SS_ERR_RUNTIME;
            if (err) err->code = s;
        } else if (e->kind == SS_OUTPUT_FILE && (lstat(e->write, &st) != 0 || !S_ISREG(st.st_mode)))
            s = ss_error_set(err, SS_ERR_RUNTIME, "%s: the run did not write it",
                             shown(e->user, sb));
        else if (e->kind == SS_OUTPUT_DIR &&
                 !(s = ss_output_dir_mark_complete(e->write, o->owner, err)))
            s = drop_marker(e->write, SS_OUTPUT_STAGING, err); /* complete proves it now */
    }
    int done = 0;
    for (; done < o->nout && !s; done++) {
        out_entry *e = &o->out[done];
        if (e->kind == SS_OUTPUT_DIR_IN_PLACE) continue; /* marked complete below */
        if (swap_in(e) != 0) {
            s = ss_error_set(err, SS_ERR_RUNTIME,
                             "%s: cannot move the new output into place: %s; the previous "
                             "one is unchanged",
                             shown(e->user, sb), strerror(errno));
            break;
        }
    }
    if (s)
        for (int i = done - 1; i >= 0; i--) swap_back(&o->out[i]);
    for (int i = 0; i < o->nout && !s; i++)
        if (o->out[i].kind == SS_OUTPUT_DIR_IN_PLACE)
            s = ss_output_dir_mark_complete(o->out[i].write, o->owner, err);
    for (int i = 0; i < o->nout; i++) {
        out_entry *e = &o->out[i];
        if (!s) {
            sync_dir(e->parent);
            if (e->old && e->swapped == SWAP_BACKUP) ss_remove_tree(e->old);
        }
        free(e->old);
        e->old = NULL;
        if (e->staging) ss_remove_tree(e->staging); /* the old one, or nothing */
        free(e->staging);
        free(e->write);
        e->staging = e->write = NULL;
        release_lock(e);
        if (s) {
            remove_made(e);
        } else {
            for (int k = 0; k < e->nmade; k++) free(e->made[k]);
            free(e->made);
            e->made = NULL;
            e->nmade = 0;
        }
    }
    return s;
}

void ss_outputs_free(ss_outputs *o) {
    if (!o) return;
    if (o->begun && !o->finished) rollback(o);
    for (int i = 0; i < o->nout; i++) free_entry(&o->out[i]);
    for (int i = 0; i < o->nin; i++) {
        free(o->in[i].user);
        free(o->in[i].real);
    }
    free(o->out);
    free(o->in);
    free(o);
}

/* ---- paths named by input files ----------------------------------------- */

ss_status ss_path_under(const char *base_dir, const char *name, int allow_outside, char **out,
                        ss_error *err) {
    char sb[200], sb2[200];
    *out = NULL;
    if (!name || !*name) return ss_error_set(err, SS_ERR_INPUT, "an output name is empty");
    const char *why = "out of memory";
    char *base = resolve(base_dir && *base_dir ? base_dir : ".", &why);
    if (!base) return ss_error_set(err, SS_ERR_INPUT, "%s: %s", shown(base_dir, sb), why);
    char *joined = name[0] == '/' ? strdup(name) : join(base, name);
    char *real = joined ? resolve(joined, &why) : NULL;
    ss_status s = SS_OK;
    if (!real)
        s = ss_error_set(err, SS_ERR_INPUT, "output %s: %s", shown(name, sb), why);
    else if (!allow_outside && (name[0] == '/' || !path_within(real, base) || !strcmp(real, base)))
        s = ss_error_set(err, SS_ERR_INPUT,
                         "output %s leaves the folder %s (it resolves to %s); outputs named in "
                         "a file stay in that file's folder unless --allow-outside-paths is "
                         "given",
                         shown(name, sb), base, shown(real, sb2));
    if (!s) {
        *out = strdup(joined); /* the name as written, on the folder's path */
        if (!*out) s = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    free(base);
    free(joined);
    free(real);
    return s;
}
