/* Internal to src/heal's checkpoints: the little-endian writer (with a
 * running zlib CRC-32) and reader that the whole-grid format (checkpoint.c)
 * and the format in pieces (checkpoint_pieces.c) share, and the run
 * directory's pruning, which keeps the newest checkpoints of either kind.
 * Not installed; other modules use skinsim/heal_io.h. */
#ifndef SKINSIM_CHECKPOINT_INTERNAL_H
#define SKINSIM_CHECKPOINT_INTERNAL_H

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "skinsim/heal_io.h"

#define CK_EXT ".sshc"       /* a whole-grid checkpoint */
#define CK_HEAD_EXT ".sshh"  /* the header of a checkpoint in pieces */
#define CK_PIECE_EXT ".sshp" /* one of its pieces */

static inline int ck_little_endian(void) {
    static const uint32_t one = 1;
    return *(const unsigned char *)&one == 1;
}

/* ---- writing: every byte goes through the CRC ---------------------------- */

typedef struct wbuf {
    FILE *fp;
    uLong crc;
    int bad;
} wbuf;

static inline void wraw(wbuf *w, const void *p, size_t n) {
    if (!n) return;
    w->crc = crc32_z(w->crc, (const Bytef *)p, n);
    if (fwrite(p, 1, n, w->fp) != n) w->bad = 1;
}
static inline void wu32(wbuf *w, uint32_t v) {
    unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16),
                          (unsigned char)(v >> 24)};
    wraw(w, b, 4);
}
static inline void wu64(wbuf *w, uint64_t v) {
    wu32(w, (uint32_t)v);
    wu32(w, (uint32_t)(v >> 32));
}
static inline void wf64(wbuf *w, double d) {
    uint64_t v;
    memcpy(&v, &d, 8);
    wu64(w, v);
}
static inline void wstr(wbuf *w, const char *s) {
    size_t n = s ? strlen(s) : 0;
    wu32(w, (uint32_t)n);
    wraw(w, s, n);
}
/* Float arrays: written as IEEE little-endian words. */
static inline void wf32s(wbuf *w, const float *a, size_t n) {
    if (ck_little_endian()) {
        wraw(w, a, n * 4);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        uint32_t v;
        memcpy(&v, &a[i], 4);
        wu32(w, v);
    }
}

/* ---- reading from memory ---------------------------------------------------- */

typedef struct rbuf {
    const unsigned char *p;
    size_t len, pos;
} rbuf;
static inline int rneed(rbuf *r, size_t n) { return r->len - r->pos >= n; }
static inline uint32_t ck_get_u32(const unsigned char *b) {
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}
static inline uint32_t ru32(rbuf *r) {
    uint32_t v = ck_get_u32(r->p + r->pos);
    r->pos += 4;
    return v;
}
static inline uint64_t ru64(rbuf *r) {
    uint64_t lo = ru32(r);
    return lo | (uint64_t)ru32(r) << 32;
}
static inline double rf64(rbuf *r) {
    uint64_t v = ru64(r);
    double d;
    memcpy(&d, &v, 8);
    return d;
}
static inline char *rstr(rbuf *r) {
    if (!rneed(r, 4)) return NULL;
    uint32_t n = ru32(r);
    if (!rneed(r, n)) return NULL;
    char *s = malloc((size_t)n + 1);
    if (!s) return NULL;
    memcpy(s, r->p + r->pos, n);
    s[n] = '\0';
    r->pos += n;
    return s;
}
/* n little-endian Float32 words at src into dst. */
static inline void ck_get_f32s(float *dst, const unsigned char *src, size_t n) {
    if (ck_little_endian()) {
        memcpy(dst, src, n * 4);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        uint32_t v = ck_get_u32(src + 4 * i);
        memcpy(&dst[i], &v, 4);
    }
}
static inline void rf32s(rbuf *r, float *a, size_t n) {
    ck_get_f32s(a, r->p + r->pos, n);
    r->pos += n * 4;
}

/* Ends a file written through w: appends the CRC-32 (into *crc if not
 * NULL) and swaps the file in, or drops it after a write error. */
static inline ss_status ck_finish(wbuf *w, ss_atomic_file *af, const char *path, uint32_t *crc,
                                  ss_error *err) {
    uint32_t c = (uint32_t)w->crc;
    wu32(w, c);
    if (crc) *crc = c;
    if (w->bad) {
        int e = errno;
        ss_atomic_abort(af);
        return ss_error_set(err, SS_ERR_RUNTIME, "%s: write failed: %s", path, strerror(e));
    }
    return ss_atomic_commit(af, err);
}

/* ---- shared by the readers (checkpoint.c) ---------------------------------------- */

/* Reads a checkpoint file whole (*data, *len; caller frees) after checking
 * its 8-byte magic, the version word, then its closing CRC-32 (over all but
 * its last 4 bytes, the file at least crc_len long): SS_ERR_INPUT naming the
 * path as not `what` (bad magic), of another version of `kind`, or a
 * truncated or corrupt `kind`. */
ss_status ss_heal__ck_load(const char *path, const char *magic, uint32_t version, size_t min_len,
                           size_t crc_len, const char *what, const char *kind, char **data,
                           size_t *len, ss_error *err);

/* ---- the run directory (checkpoint_dir.c) ----------------------------------------- */

/* In dir (DIR/checkpoints): keeps the newest `keep` complete checkpoints of
 * either kind (whole-grid files and piece headers) and removes the older
 * ones with their pieces, pieces of no kept checkpoint up to step `upto`, and
 * the temporary files of killed writes. */
void ss_heal__ckpt_prune(const char *dir, int keep, unsigned long long upto);

#endif
