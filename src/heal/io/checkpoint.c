/* Healing checkpoints: the whole solver state (grid dims, dx, time, step,
 * scheme, dt, parameters as JSON, cell states, every field and velocity) in a
 * versioned little-endian binary file closed by a zlib CRC-32, written to a
 * temporary name and renamed, so `skinsim heal --resume` continues
 * bit-identically and a killed write never damages the previous checkpoint.
 * Serves the run-control part of seed 001 §5.1 (long simulations). The same
 * state cut into per-box pieces is checkpoint_pieces.c; the run directory's
 * checkpoints of both kinds (newest, pruning) are checkpoint_dir.c. */
#define _POSIX_C_SOURCE 200809L
#include "checkpoint_internal.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define CK_MAGIC "SSHEALCK"
#define CK_VERSION 1u

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
    /* bit 1 of the velocity word: the keloid's added volume follows [D16] */
    const uint32_t flags = (uint32_t)vel | (g->added ? 2u : 0u);
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
    wu32(&w, flags);
    wstr(&w, scenario);
    wstr(&w, params_json);
    wstr(&w, aux);
    wraw(&w, g->cell, n);
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) wf32s(&w, g->field[f], n);
    if (vel)
        for (int c = 0; c < 3; c++) wf32s(&w, g->velocity[c], n);
    if (g->added) wf32s(&w, g->added, n);
    return ck_finish(&w, &af, path, NULL, err);
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

ss_status ss_heal__ck_load(const char *path, const char *magic, uint32_t version, size_t min_len,
                           size_t crc_len, const char *what, const char *kind, char **data,
                           size_t *len, ss_error *err) {
    *data = ss_read_file(path, len, err);
    if (!*data) return err ? err->code : SS_ERR_INPUT;
    const unsigned char *b = (const unsigned char *)*data;
    ss_status st = SS_OK;
    if (*len < min_len || memcmp(b, magic, 8) != 0)
        st = ss_error_set(err, SS_ERR_INPUT, "%s: not %s (bad magic)", path, what);
    else if (ck_get_u32(b + 8) != version)
        st = ss_error_set(err, SS_ERR_INPUT,
                          "%s: %s version %u is not supported (this build reads %u)", path, kind,
                          ck_get_u32(b + 8), version);
    else if (*len < crc_len)
        st = ss_error_set(err, SS_ERR_INPUT, "%s: truncated %s", path, kind);
    if (!st) {
        uint32_t stored = ck_get_u32(b + *len - 4);
        uint32_t crc = (uint32_t)crc32_z(crc32_z(0L, Z_NULL, 0), b, *len - 4);
        if (crc != stored)
            st = ss_error_set(err, SS_ERR_INPUT,
                              "%s: %s is truncated or corrupt (CRC-32 %08x, expected %08x)", path,
                              kind, crc, stored);
    }
    if (st) {
        free(*data);
        *data = NULL;
    }
    return st;
}

ss_status ss_heal_checkpoint_read(const char *path, ss_heal_checkpoint *out, ss_error *err) {
    memset(out, 0, sizeof *out);
    size_t len = 0;
    char *data;
    ss_status st = ss_heal__ck_load(path, CK_MAGIC, CK_VERSION, 16, 20,
                                    "a skinsim healing checkpoint", "checkpoint", &data, &len, err);
    if (st) return st;
    rbuf r = {(const unsigned char *)data, len, 12};
#define BAD(...)                                                                                   \
    do {                                                                                           \
        st = ss_error_set(err, SS_ERR_INPUT, __VA_ARGS__);                                         \
        goto done;                                                                                 \
    } while (0)
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
    uint32_t flags = ru32(&r), vel = flags & 1u, added = (flags >> 1) & 1u;
    if (nf != SS_HEAL_NFIELDS)
        BAD("%s: checkpoint has %u fields, this build has %d", path, nf, SS_HEAL_NFIELDS);
    if (nx <= 0 || ny <= 0 || nz <= 0 || !(dx > 0) || !isfinite(dx) || !isfinite(t) ||
        !isfinite(top) || !(dt > 0) || !isfinite(dt) || flags > 3)
        BAD("%s: checkpoint header values are invalid", path);
    out->scenario = rstr(&r);
    out->params_json = out->scenario ? rstr(&r) : NULL;
    out->aux = out->params_json ? rstr(&r) : NULL;
    if (!out->aux) BAD("%s: truncated checkpoint (strings)", path);
    size_t n = (size_t)nx * (size_t)ny * (size_t)nz;
    size_t need = n * (1 + 4 * (size_t)(SS_HEAL_NFIELDS + (vel ? 3 : 0) + added));
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
    if (added && !(g->added = malloc(n * sizeof(float)))) {
        st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory for the added volume", path);
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
    if (added) rf32s(&r, g->added, n);
    out->scheme = scheme;
    out->dt_days = dt;
#undef BAD
done:
    free(data);
    if (st) ss_heal_checkpoint_free(out);
    return st;
}
