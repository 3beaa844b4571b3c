/* Healing checkpoints: the whole solver state (grid dims, dx, time, step,
 * scheme, dt, parameters as JSON, cell states, every field and velocity) in a
 * versioned little-endian binary file closed by a zlib CRC-32, written to a
 * temporary name and renamed, so `skinsim heal --resume` continues
 * bit-identically and a killed write never damages the previous checkpoint.
 * Serves the run-control part of seed 001 §5.1 (long simulations). */
#define _POSIX_C_SOURCE 200809L
#include "skinsim/heal_io.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

#define CK_MAGIC "SSHEALCK"
#define CK_VERSION 1u
#define CK_EXT ".sshc"

/* ---- little-endian buffer helpers ------------------------------------------ */

typedef struct wbuf {
    FILE *fp;
    uLong crc;
    int bad;
} wbuf;

static void wraw(wbuf *w, const void *p, size_t n) {
    if (!n) return;
    w->crc = crc32_z(w->crc, (const Bytef *)p, n);
    if (fwrite(p, 1, n, w->fp) != n) w->bad = 1;
}
static void wu32(wbuf *w, uint32_t v) {
    unsigned char b[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16),
                          (unsigned char)(v >> 24)};
    wraw(w, b, 4);
}
static void wu64(wbuf *w, uint64_t v) {
    wu32(w, (uint32_t)v);
    wu32(w, (uint32_t)(v >> 32));
}
static void wf64(wbuf *w, double d) {
    uint64_t v;
    memcpy(&v, &d, 8);
    wu64(w, v);
}
static void wstr(wbuf *w, const char *s) {
    size_t n = s ? strlen(s) : 0;
    wu32(w, (uint32_t)n);
    wraw(w, s, n);
}
/* Float arrays: written as IEEE little-endian words. */
static void wf32s(wbuf *w, const float *a, size_t n) {
    static const uint32_t one = 1;
    if (*(const unsigned char *)&one == 1) {
        wraw(w, a, n * 4);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        uint32_t v;
        memcpy(&v, &a[i], 4);
        wu32(w, v);
    }
}

typedef struct rbuf {
    const unsigned char *p;
    size_t len, pos;
} rbuf;
static int rneed(rbuf *r, size_t n) { return r->len - r->pos >= n; }
static uint32_t ru32(rbuf *r) {
    const unsigned char *b = r->p + r->pos;
    r->pos += 4;
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}
static uint64_t ru64(rbuf *r) {
    uint64_t lo = ru32(r);
    return lo | (uint64_t)ru32(r) << 32;
}
static double rf64(rbuf *r) {
    uint64_t v = ru64(r);
    double d;
    memcpy(&d, &v, 8);
    return d;
}
static char *rstr(rbuf *r) {
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
static void rf32s(rbuf *r, float *a, size_t n) {
    static const uint32_t one = 1;
    if (*(const unsigned char *)&one == 1) {
        memcpy(a, r->p + r->pos, n * 4);
        r->pos += n * 4;
        return;
    }
    for (size_t i = 0; i < n; i++) {
        uint32_t v = ru32(r);
        memcpy(&a[i], &v, 4);
    }
}

/* ---- write ------------------------------------------------------------------ */

ss_status ss_heal_checkpoint_write(const char *path, const ss_heal_grid *g, const char *scenario,
                                   const char *params_json, int scheme, double dt_days,
                                   const char *aux, ss_error *err) {
    if (!g || !g->cell) return ss_error_set(err, SS_ERR_INPUT, "%s: no grid to checkpoint", path);
    for (int f = 0; f < SS_HEAL_NFIELDS; f++)
        if (!g->field[f])
            return ss_error_set(err, SS_ERR_INPUT, "%s: grid field %d missing", path, f);
    int vel = g->velocity[0] && g->velocity[1] && g->velocity[2];
    size_t n = (size_t)g->nx * (size_t)g->ny * (size_t)g->nz;
    ss_atomic_file af;
    ss_status st = ss_atomic_open(&af, path, err);
    if (st) return st;
    wbuf w = {af.fp, crc32_z(0L, Z_NULL, 0), 0};
    wraw(&w, CK_MAGIC, 8);
    wu32(&w, CK_VERSION);
    wu32(&w, 4 * 4 + 3 * 8 + 8 + 4 + 8 + 4); /* fixed header bytes that follow */
    wu32(&w, (uint32_t)g->nx);
    wu32(&w, (uint32_t)g->ny);
    wu32(&w, (uint32_t)g->nz);
    wu32(&w, SS_HEAL_NFIELDS);
    wf64(&w, g->dx_mm);
    wf64(&w, g->skin_top_mm);
    wf64(&w, g->t_days);
    wu64(&w, g->step);
    wu32(&w, (uint32_t)scheme);
    wf64(&w, dt_days);
    wu32(&w, (uint32_t)vel);
    wstr(&w, scenario);
    wstr(&w, params_json);
    wstr(&w, aux);
    wraw(&w, g->cell, n);
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) wf32s(&w, g->field[f], n);
    if (vel)
        for (int c = 0; c < 3; c++) wf32s(&w, g->velocity[c], n);
    uint32_t crc = (uint32_t)w.crc;
    wu32(&w, crc);
    if (w.bad) {
        ss_atomic_abort(&af);
        return ss_error_set(err, SS_ERR_RUNTIME, "%s: write failed: %s", path, strerror(errno));
    }
    return ss_atomic_commit(&af, err);
}

/* ---- read ------------------------------------------------------------------- */

void ss_heal_checkpoint_free(ss_heal_checkpoint *c) {
    if (!c) return;
    ss_heal_grid_free(c->grid);
    free(c->scenario);
    free(c->params_json);
    free(c->aux);
    memset(c, 0, sizeof *c);
}

ss_status ss_heal_checkpoint_read(const char *path, ss_heal_checkpoint *out, ss_error *err) {
    memset(out, 0, sizeof *out);
    size_t len = 0;
    char *data = ss_read_file(path, &len, err);
    if (!data) return err ? err->code : SS_ERR_INPUT;
    rbuf r = {(const unsigned char *)data, len, 0};
    ss_status st = SS_OK;
#define BAD(...)                                                                                   \
    do {                                                                                           \
        st = ss_error_set(err, SS_ERR_INPUT, __VA_ARGS__);                                         \
        goto done;                                                                                 \
    } while (0)
    if (len < 16 || memcmp(data, CK_MAGIC, 8) != 0)
        BAD("%s: not a skinsim healing checkpoint (bad magic)", path);
    r.pos = 8;
    uint32_t version = ru32(&r);
    if (version != CK_VERSION)
        BAD("%s: checkpoint version %u is not supported (this build reads %u)", path, version,
            CK_VERSION);
    uint32_t crc_stored;
    {
        if (len < 20) BAD("%s: truncated checkpoint", path);
        const unsigned char *b = r.p + len - 4;
        crc_stored =
            (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
        uint32_t crc = (uint32_t)crc32_z(crc32_z(0L, Z_NULL, 0), r.p, len - 4);
        if (crc != crc_stored)
            BAD("%s: checkpoint is truncated or corrupt (CRC-32 %08x, expected %08x)", path, crc,
                crc_stored);
    }
    r.len = len - 4;
    uint32_t hdr = ru32(&r);
    if (hdr != 4 * 4 + 3 * 8 + 8 + 4 + 8 + 4 || !rneed(&r, hdr))
        BAD("%s: checkpoint header size %u unexpected", path, hdr);
    int nx = (int)ru32(&r), ny = (int)ru32(&r), nz = (int)ru32(&r);
    uint32_t nf = ru32(&r);
    double dx = rf64(&r), top = rf64(&r), t = rf64(&r);
    uint64_t step = ru64(&r);
    int scheme = (int)ru32(&r);
    double dt = rf64(&r);
    uint32_t vel = ru32(&r);
    if (nf != SS_HEAL_NFIELDS)
        BAD("%s: checkpoint has %u fields, this build has %d", path, nf, SS_HEAL_NFIELDS);
    if (nx <= 0 || ny <= 0 || nz <= 0 || !(dx > 0) || !isfinite(dx) || !isfinite(t) ||
        !isfinite(top) || !(dt > 0) || !isfinite(dt) || vel > 1)
        BAD("%s: checkpoint header values are invalid", path);
    out->scenario = rstr(&r);
    out->params_json = out->scenario ? rstr(&r) : NULL;
    out->aux = out->params_json ? rstr(&r) : NULL;
    if (!out->aux) BAD("%s: truncated checkpoint (strings)", path);
    size_t n = (size_t)nx * (size_t)ny * (size_t)nz;
    size_t need = n * (1 + 4 * (size_t)(SS_HEAL_NFIELDS + (vel ? 3 : 0)));
    if (n / (size_t)nx / (size_t)ny != (size_t)nz || n > SIZE_MAX / 64 || r.len - r.pos != need)
        BAD("%s: checkpoint data size %zu does not match a %dx%dx%d grid (%zu bytes)", path,
            r.len - r.pos, nx, ny, nz, need);
    ss_heal_grid *g = ss_heal_grid_create(nx, ny, nz, dx, err);
    if (!g) {
        st = err ? err->code : SS_ERR_RUNTIME;
        goto done;
    }
    out->grid = g;
    for (int c = 0; vel && c < 3; c++) /* the grid owns (and frees) its velocity arrays */
        if (!g->velocity[c] && !(g->velocity[c] = malloc(n * sizeof(float)))) {
            st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory for velocities", path);
            goto done;
        }
    g->skin_top_mm = top;
    g->t_days = t;
    g->step = step;
    memcpy(g->cell, r.p + r.pos, n);
    r.pos += n;
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) rf32s(&r, g->field[f], n);
    if (vel)
        for (int c = 0; c < 3; c++) rf32s(&r, g->velocity[c], n);
    else
        for (int c = 0; c < 3; c++)
            if (g->velocity[c]) memset(g->velocity[c], 0, n * sizeof(float));
    out->scheme = scheme;
    out->dt_days = dt;
#undef BAD
done:
    free(data);
    if (st) ss_heal_checkpoint_free(out);
    return st;
}

/* ---- run directory ------------------------------------------------------------ */

static int is_ckpt_name(const char *s, unsigned long long *step) {
    size_t l = strlen(s);
    if (l != 5 + 12 + strlen(CK_EXT) || strncmp(s, "ckpt_", 5) != 0 || strcmp(s + 17, CK_EXT))
        return 0;
    unsigned long long v = 0;
    for (int i = 5; i < 17; i++) {
        if (s[i] < '0' || s[i] > '9') return 0;
        v = v * 10 + (unsigned long long)(s[i] - '0');
    }
    *step = v;
    return 1;
}

static int cmp_desc(const void *a, const void *b) {
    unsigned long long x = *(const unsigned long long *)a, y = *(const unsigned long long *)b;
    return x < y ? 1 : x > y ? -1 : 0;
}

/* Steps of the checkpoints in dir, newest first; *n entries, malloc'd. */
static unsigned long long *list_ckpts(const char *dir, int *n) {
    *n = 0;
    DIR *d = opendir(dir);
    if (!d) return NULL;
    int cap = 16;
    unsigned long long *s = malloc((size_t)cap * sizeof *s);
    struct dirent *e;
    while (s && (e = readdir(d))) {
        unsigned long long v;
        if (!is_ckpt_name(e->d_name, &v)) continue;
        if (*n == cap) {
            cap *= 2;
            unsigned long long *t = realloc(s, (size_t)cap * sizeof *s);
            if (!t) break;
            s = t;
        }
        s[(*n)++] = v;
    }
    closedir(d);
    if (s) qsort(s, (size_t)*n, sizeof *s, cmp_desc);
    return s;
}

ss_status ss_heal_checkpoint_load_latest(const char *run_dir, ss_heal_checkpoint *out, char *note,
                                         size_t note_len, ss_error *err) {
    char dir[4096], path[4400];
    if (note && note_len) note[0] = '\0';
    snprintf(dir, sizeof dir, "%s/checkpoints", run_dir);
    int n;
    unsigned long long *steps = list_ckpts(dir, &n);
    if (!n) {
        free(steps);
        return ss_error_set(err, SS_ERR_INPUT, "%s: no checkpoint to resume from (%s/ckpt_*%s)",
                            run_dir, dir, CK_EXT);
    }
    ss_error e1;
    ss_error_clear(&e1);
    for (int i = 0; i < n; i++) {
        snprintf(path, sizeof path, "%s/ckpt_%012llu%s", dir, steps[i], CK_EXT);
        ss_error e;
        ss_error_clear(&e);
        if (ss_heal_checkpoint_read(path, out, &e) == SS_OK) {
            free(steps);
            return SS_OK;
        }
        if (!e1.code) e1 = e;
        if (note && note_len) {
            size_t l = strlen(note);
            snprintf(note + l, note_len - l, "%sskipped %s", l ? "; " : "", e.msg);
        }
    }
    free(steps);
    return ss_error_set(err, SS_ERR_INPUT, "%s: no usable checkpoint (%s)", run_dir, e1.msg);
}

ss_status ss_heal_checkpoint_save(const char *run_dir, const ss_heal_grid *g, const char *scenario,
                                  const char *params_json, int scheme, double dt_days,
                                  const char *aux, int keep, ss_error *err) {
    char dir[4096], path[4400];
    snprintf(dir, sizeof dir, "%s/checkpoints", run_dir);
    ss_status st = ss_mkdir_p(dir, err);
    if (st) return st;
    snprintf(path, sizeof path, "%s/ckpt_%012llu%s", dir, (unsigned long long)g->step, CK_EXT);
    st = ss_heal_checkpoint_write(path, g, scenario, params_json, scheme, dt_days, aux, err);
    if (st) return st;
    if (keep < 2) keep = 2;
    int n;
    unsigned long long *steps = list_ckpts(dir, &n);
    for (int i = keep; i < n; i++) {
        snprintf(path, sizeof path, "%s/ckpt_%012llu%s", dir, steps[i], CK_EXT);
        unlink(path);
    }
    free(steps);
    /* temporary files left by writes that were killed (ours just committed) */
    DIR *d = opendir(dir);
    struct dirent *e;
    while (d && (e = readdir(d))) {
        if (strncmp(e->d_name, "ckpt_", 5) || !strstr(e->d_name, CK_EXT ".tmp.")) continue;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        unlink(path);
    }
    if (d) closedir(d);
    return SS_OK;
}
