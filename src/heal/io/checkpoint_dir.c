/* The checkpoints of a run directory (DIR/checkpoints/): the newest usable
 * one of either kind, a whole-grid file ckpt_<step>.sshc (checkpoint.c) or a
 * header ckpt_<step>.sshh with its pieces (checkpoint_pieces.c), for
 * `skinsim heal --resume`; saving a whole-grid checkpoint; and the pruning
 * that keeps the newest few of either kind. A checkpoint counts only when it
 * is complete (its file or its header exists: both are renamed into place
 * last) and verifies; a newer damaged one is skipped and named, so a run
 * killed while writing resumes from the one before. */
#define _POSIX_C_SOURCE 200809L
#include "checkpoint_internal.h"

#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

typedef enum ck_kind { CK_NONE = 0, CK_WHOLE, CK_HEAD, CK_PIECE } ck_kind;

/* ckpt_<12 digits>.sshc | .sshh | _p<6 digits>.sshp */
static ck_kind ck_name(const char *s, unsigned long long *step) {
    size_t l = strlen(s);
    if (l < 22 || strncmp(s, "ckpt_", 5) != 0) return CK_NONE;
    unsigned long long v = 0;
    for (int i = 5; i < 17; i++) {
        if (s[i] < '0' || s[i] > '9') return CK_NONE;
        v = v * 10 + (unsigned long long)(s[i] - '0');
    }
    *step = v;
    if (l == 22 && !strcmp(s + 17, CK_EXT)) return CK_WHOLE;
    if (l == 22 && !strcmp(s + 17, CK_HEAD_EXT)) return CK_HEAD;
    if (l != 30 || s[17] != '_' || s[18] != 'p' || strcmp(s + 25, CK_PIECE_EXT)) return CK_NONE;
    for (int i = 19; i < 25; i++)
        if (s[i] < '0' || s[i] > '9') return CK_NONE;
    return CK_PIECE;
}

typedef struct ck_entry {
    unsigned long long step;
    ck_kind kind;
} ck_entry;

/* newest first; a whole-grid file before a header of the same step */
static int cmp_desc(const void *a, const void *b) {
    const ck_entry *x = a, *y = b;
    if (x->step != y->step) return x->step < y->step ? 1 : -1;
    return (int)x->kind - (int)y->kind;
}

/* The complete checkpoints in dir (whole-grid files and headers; with
 * pieces also the piece files), newest first; *n entries, malloc'd. */
static ck_entry *list_ckpts(const char *dir, int pieces, int *n) {
    *n = 0;
    DIR *d = opendir(dir);
    if (!d) return NULL;
    int cap = 16;
    ck_entry *s = malloc((size_t)cap * sizeof *s);
    struct dirent *e;
    while (s && (e = readdir(d))) {
        unsigned long long v;
        ck_kind k = ck_name(e->d_name, &v);
        if (k == CK_NONE || (k == CK_PIECE && !pieces)) continue;
        if (*n == cap) {
            cap *= 2;
            ck_entry *t = realloc(s, (size_t)cap * sizeof *s);
            if (!t) break;
            s = t;
        }
        s[*n].step = v;
        s[(*n)++].kind = k;
    }
    closedir(d);
    if (s) qsort(s, (size_t)*n, sizeof *s, cmp_desc);
    return s;
}

static void whole_path(char *buf, size_t len, const char *dir, unsigned long long step) {
    snprintf(buf, len, "%s/ckpt_%012llu%s", dir, step, CK_EXT);
}

/* Newest first: the first that verifies. load_grid: a piece checkpoint is
 * read whole into *whole (else only its header, pieces checked). */
static ss_status latest(const char *run_dir, int load_grid, int verify_crc,
                        ss_heal_checkpoint *whole, ss_heal_ckpt_header *pieces, char *note,
                        size_t note_len, ss_error *err) {
    char dir[4096], path[4400];
    if (note && note_len) note[0] = '\0';
    memset(whole, 0, sizeof *whole);
    if (pieces) memset(pieces, 0, sizeof *pieces);
    snprintf(dir, sizeof dir, "%s/checkpoints", run_dir);
    int n;
    ck_entry *c = list_ckpts(dir, 0, &n);
    if (!n) {
        free(c);
        return ss_error_set(err, SS_ERR_INPUT, "%s: no checkpoint to resume from (%s/ckpt_*%s)",
                            run_dir, dir, CK_EXT);
    }
    ss_error e1;
    ss_error_clear(&e1);
    for (int i = 0; i < n; i++) {
        ss_error e;
        ss_error_clear(&e);
        ss_status st;
        if (c[i].kind == CK_WHOLE) {
            whole_path(path, sizeof path, dir, c[i].step);
            st = ss_heal_checkpoint_read(path, whole, &e);
        } else if (load_grid) {
            st = ss_heal_checkpoint_read_pieces(run_dir, c[i].step, whole, &e);
        } else {
            ss_heal_ckpt_header_path(path, sizeof path, run_dir, c[i].step);
            st = ss_heal_ckpt_header_read(path, pieces, &e);
            if (!st && (st = ss_heal_ckpt_pieces_check(run_dir, pieces, verify_crc, &e)))
                ss_heal_ckpt_header_free(pieces);
        }
        if (st == SS_OK) {
            free(c);
            return SS_OK;
        }
        if (!e1.code) e1 = e;
        if (note && note_len) {
            size_t l = strlen(note);
            snprintf(note + l, note_len - l, "%sskipped %s", l ? "; " : "", e.msg);
        }
    }
    free(c);
    return ss_error_set(err, SS_ERR_INPUT, "%s: no usable checkpoint (%s)", run_dir, e1.msg);
}

ss_status ss_heal_checkpoint_load_latest(const char *run_dir, ss_heal_checkpoint *out, char *note,
                                         size_t note_len, ss_error *err) {
    return latest(run_dir, 1, 1, out, NULL, note, note_len, err);
}

ss_status ss_heal_checkpoint_open_latest(const char *run_dir, int verify_crc,
                                         ss_heal_checkpoint *whole, ss_heal_ckpt_header *pieces,
                                         char *note, size_t note_len, ss_error *err) {
    return latest(run_dir, 0, verify_crc, whole, pieces, note, note_len, err);
}

void ss_heal__ckpt_prune(const char *dir, int keep, unsigned long long upto) {
    char path[4400];
    if (keep < 2) keep = 2;
    int n;
    ck_entry *c = list_ckpts(dir, 1, &n);
    int kept = 0;
    for (int i = 0; i < n; i++) {
        if (c[i].kind == CK_PIECE) continue;
        if (kept < keep) { /* mark the kept steps by their (complete) entries */
            kept++;
            continue;
        }
        if (c[i].kind == CK_WHOLE)
            whole_path(path, sizeof path, dir, c[i].step);
        else
            snprintf(path, sizeof path, "%s/ckpt_%012llu%s", dir, c[i].step, CK_HEAD_EXT);
        unlink(path); /* a header goes first: its checkpoint is then incomplete */
        c[i].kind = CK_NONE;
    }
    /* pieces whose header is gone (pruned above, or never written by a
     * killed run) up to upto; the kept ones are the remaining headers */
    for (int i = 0; i < n; i++) {
        if (c[i].kind != CK_PIECE || c[i].step > upto) continue;
        int has_head = 0;
        for (int j = 0; j < n && !has_head; j++)
            has_head = c[j].kind == CK_HEAD && c[j].step == c[i].step;
        if (has_head) continue;
        DIR *d = opendir(dir);
        struct dirent *e;
        unsigned long long v;
        while (d && (e = readdir(d)))
            if (ck_name(e->d_name, &v) == CK_PIECE && v == c[i].step) {
                snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
                unlink(path);
            }
        if (d) closedir(d);
        for (int j = i; j < n; j++) /* once per step */
            if (c[j].kind == CK_PIECE && c[j].step == c[i].step) c[j].kind = CK_NONE;
    }
    free(c);
    /* temporary files left by checkpoint writes that were killed (ours are
     * committed): a checkpoint's name, the atomic writer's marker and the id
     * of a process that is gone; nothing else here is touched */
    DIR *d = opendir(dir);
    struct dirent *e;
    while (d && (e = readdir(d))) {
        const char *t = strstr(e->d_name, SS_ATOMIC_TMP);
        unsigned long long v;
        char base[64];
        if (!t || (size_t)(t - e->d_name) >= sizeof base) continue;
        snprintf(base, sizeof base, "%.*s", (int)(t - e->d_name), e->d_name);
        if (ck_name(base, &v) == CK_NONE) continue;
        char *end;
        long pid = strtol(t + strlen(SS_ATOMIC_TMP), &end, 10);
        if (pid <= 0 || *end != '.' || strlen(end + 1) != 6 || kill((pid_t)pid, 0) == 0 ||
            errno != ESRCH)
            continue;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        unlink(path);
    }
    if (d) closedir(d);
}

ss_status ss_heal_checkpoint_save(const char *run_dir, const ss_heal_grid *g, const char *scenario,
                                  const char *params_json, int scheme, double dt_days,
                                  const char *aux, int keep, ss_error *err) {
    char dir[4096], path[4400];
    snprintf(dir, sizeof dir, "%s/checkpoints", run_dir);
    ss_status st = ss_mkdir_p(dir, err);
    if (st) return st;
    whole_path(path, sizeof path, dir, (unsigned long long)g->step);
    st = ss_heal_checkpoint_write(path, g, scenario, params_json, scheme, dt_days, aux, err);
    if (st) return st;
    ss_heal__ckpt_prune(dir, keep, (unsigned long long)g->step);
    return SS_OK;
}
