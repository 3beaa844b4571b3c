/* Generic reaction-diffusion-convection core, explicit part (seed 001 §5.1:
 * "central differences" on the regular grid). Work memory and masks, the
 * stability limit, donor-cell convection, and the forward-Euler step: per
 * x-row the pluggable reaction function fills production/loss/multiplier rows
 * in thread-local scratch, then one fused pass per field applies the 7-point
 * Laplacian (no-flux faces masked by precomputed neighbour bits), reaction and
 * convection, clamps to the admissible range and writes the next buffer.
 * OpenMP over (z, y) rows; every cell is computed independently, so results
 * are bit-identical for any thread count. */
/* The hot loops are written branch-free for SIMD. At -O2 GCC vectorises
 * their compares/selects only with loop if-conversion and without treating
 * FP exception flags as observable (-fno-trapping-math: values are unchanged,
 * unlike -ffast-math there is no reassociation or finite-math assumption). */
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("tree-loop-if-convert", "tree-loop-vectorize", "no-trapping-math")
#endif
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "heal_internal.h"

static uint8_t cls_of(const ss_heal_rd_system *sys, size_t c) { return sys->cls ? sys->cls[c] : 0; }

void ss_heal_rd__build_masks(const ss_heal_rd_system *sys, ss_heal_rd_work *w) {
    const int nx = sys->nx, ny = sys->ny, nz = sys->nz;
    const size_t sy = (size_t)nx, sz = (size_t)nx * (size_t)ny;
    const int par = (size_t)nx * (size_t)ny * (size_t)nz >= RD_PAR_MIN_CELLS;
    /* a sub-box (src/mpi): walls and neighbour bits by whole-grid index */
    const int ox = sys->goff[0], oy = sys->goff[1], oz = sys->goff[2];
    const int gx = sys->gdim[0] ? sys->gdim[0] : nx, gy = sys->gdim[1] ? sys->gdim[1] : ny;
    const int gz = sys->gdim[2] ? sys->gdim[2] : nz;
#pragma omp parallel for schedule(static) if (par)
    for (int z = 0; z < nz; z++) {
        for (int y = 0; y < ny; y++) {
            for (int x = 0; x < nx; x++) {
                size_t c = (size_t)z * sz + (size_t)y * sy + (size_t)x;
                uint8_t k = cls_of(sys, c) & (SS_HEAL_RD_MAXCLASS - 1);
                const int X = x + ox, Y = y + oy, Z = z + oz;
                int wall = sys->wall[k] || x == 0 || y == 0 || z == 0 || x == nx - 1 ||
                           y == ny - 1 || z == nz - 1 || X <= 0 || Y <= 0 || Z <= 0 ||
                           X >= gx - 1 || Y >= gy - 1 || Z >= gz - 1;
                uint8_t b = 0;
                if (!wall) {
#define NBW(off) (sys->wall[cls_of(sys, (off)) & (SS_HEAL_RD_MAXCLASS - 1)])
                    if (X > 1 && !NBW(c - 1)) b |= NB_XM;
                    if (X < gx - 2 && !NBW(c + 1)) b |= NB_XP;
                    if (Y > 1 && !NBW(c - sy)) b |= NB_YM;
                    if (Y < gy - 2 && !NBW(c + sy)) b |= NB_YP;
                    if (Z > 1 && !NBW(c - sz)) b |= NB_ZM;
                    if (Z < gz - 2 && !NBW(c + sz)) b |= NB_ZP;
#undef NBW
                }
                w->nb[c] = b;
                w->upd_common[c] = (uint8_t)!wall;
                for (int f = 0; f < sys->nfields; f++)
                    if (w->upd[f] != w->upd_common)
                        w->upd[f][c] = (uint8_t)(!wall && !sys->fixed[f][k]);
            }
        }
    }
}

static ss_heal_rd_work *work_create(const ss_heal_rd_system *sys, int need_buf, int need_mslot,
                                    ss_error *err) {
    if (!sys || sys->nx < 3 || sys->ny < 3 || sys->nz < 3 || sys->nfields < 1 ||
        sys->nfields > SS_HEAL_RD_MAXF || sys->nslots < 0 || sys->nslots > SS_HEAL_RD_MAXSLOT ||
        !(sys->h_mm > 0)) {
        ss_error_set(err, SS_ERR_INPUT,
                     "heal solver: bad system (grid needs >= 3 cells per axis, 1..%d fields, "
                     "0..%d multiplier slots, h > 0)",
                     SS_HEAL_RD_MAXF, SS_HEAL_RD_MAXSLOT);
        return NULL;
    }
    for (int f = 0; f < sys->nfields; f++) {
        if (!sys->u[f] || !(sys->D[f] >= 0) || sys->mslot[f] >= sys->nslots) {
            ss_error_set(err, SS_ERR_INPUT,
                         "heal solver: field %d has no data, D < 0 or a bad "
                         "multiplier slot",
                         f);
            return NULL;
        }
    }
    for (int k = 0; k < sys->nslots; k++)
        if (sys->mface[k] > sys->nfields) {
            ss_error_set(err, SS_ERR_INPUT,
                         "heal solver: multiplier slot %d names face field %d of %d", k,
                         sys->mface[k] - 1, sys->nfields);
            return NULL;
        }
    ss_heal_rd_work *w = calloc(1, sizeof *w);
    if (!w) goto nomem;
    w->nx = sys->nx;
    w->ny = sys->ny;
    w->nz = sys->nz;
    w->nfields = sys->nfields;
    w->nslots = sys->nslots;
    w->ncell = (size_t)sys->nx * (size_t)sys->ny * (size_t)sys->nz;
    w->nb = malloc(w->ncell);
    w->upd_common = malloc(w->ncell);
    if (!w->nb || !w->upd_common) goto nomem;
    for (int f = 0; f < sys->nfields; f++) {
        /* fields without a fixed class share one update mask (not a wall),
         * so the step reads one byte per cell for them instead of one each */
        int any_fixed = 0;
        for (int k = 0; k < SS_HEAL_RD_MAXCLASS; k++) any_fixed |= sys->fixed[f][k] != 0;
        w->upd[f] = any_fixed ? malloc(w->ncell) : w->upd_common;
        if (!w->upd[f]) goto nomem;
        if (need_buf) {
            w->buf[f] = malloc(w->ncell * sizeof(float));
            if (!w->buf[f]) goto nomem;
            memcpy(w->buf[f], sys->u[f], w->ncell * sizeof(float));
        }
    }
    w->have_buf = need_buf;
    if (need_mslot) {
        for (int k = 0; k < sys->nslots; k++) {
            w->mslot[k] = malloc(w->ncell * sizeof(float));
            if (!w->mslot[k]) goto nomem;
            for (size_t c = 0; c < w->ncell; c++) w->mslot[k][c] = 1.0f;
        }
        w->have_mslot = 1;
    }
    w->nthreads = omp_get_max_threads();
    if (w->nthreads < 1) w->nthreads = 1;
    size_t nx = (size_t)sys->nx, big = (size_t)(sys->ny > sys->nz ? sys->ny : sys->nz);
    /* split: prod, loss, local u, multipliers; explicit: prod, loss,
     * multipliers, ones, six face weights */
    size_t a = (size_t)(4 * sys->nfields + sys->nslots + 14) * nx;
    size_t b = 2 * big * nx + 4 * nx;
    w->ones_off = a > b ? a : b;
    w->tscratch_len = w->ones_off + nx + 64;
    w->tscratch = calloc((size_t)w->nthreads, sizeof(float *));
    if (!w->tscratch) goto nomem;
    for (int t = 0; t < w->nthreads; t++) {
        w->tscratch[t] = calloc(w->tscratch_len, sizeof(float));
        if (!w->tscratch[t]) goto nomem;
        for (size_t i = 0; i < nx; i++) w->tscratch[t][w->ones_off + i] = 1.0f;
    }
    ss_heal_rd__build_masks(sys, w);
    return w;
nomem:
    ss_heal_rd_work_free(w);
    ss_error_set(err, SS_ERR_NOMEM, "heal solver: out of memory for a %dx%dx%d grid work area",
                 sys->nx, sys->ny, sys->nz);
    return NULL;
}

ss_heal_rd_work *ss_heal_rd__work_create_ex(const ss_heal_rd_system *sys, int need_buf,
                                            int need_mslot, ss_error *err) {
    return work_create(sys, need_buf, need_mslot, err);
}

ss_heal_rd_work *ss_heal_rd_work_create(const ss_heal_rd_system *sys, ss_error *err) {
    return work_create(sys, 1, 1, err);
}

void ss_heal_rd_work_free(ss_heal_rd_work *w) {
    if (!w) return;
    free(w->nb);
    for (int f = 0; f < SS_HEAL_RD_MAXF; f++) {
        if (w->upd[f] != w->upd_common) free(w->upd[f]);
        free(w->buf[f]);
    }
    free(w->upd_common);
    for (int k = 0; k < SS_HEAL_RD_MAXSLOT; k++) free(w->mslot[k]);
    if (w->tscratch)
        for (int t = 0; t < w->nthreads; t++) free(w->tscratch[t]);
    free(w->tscratch);
    free(w);
}

double ss_heal_rd_max_speed(const ss_heal_rd_system *sys) {
    if (!sys->velocity[0] && !sys->velocity[1] && !sys->velocity[2]) return 0.0;
    size_t n = (size_t)sys->nx * (size_t)sys->ny * (size_t)sys->nz;
    double vmax = 0.0;
    for (size_t c = 0; c < n; c++) {
        double s = 0.0;
        for (int d = 0; d < 3; d++)
            if (sys->velocity[d]) s += fabs((double)sys->velocity[d][c]);
        if (s > vmax) vmax = s;
    }
    return vmax;
}

double ss_heal_rd_explicit_dt(const ss_heal_rd_system *sys) {
    double h2 = sys->h_mm * sys->h_mm, dmax = 0.0;
    for (int f = 0; f < sys->nfields; f++)
        if (sys->D[f] > dmax) dmax = sys->D[f];
    double mmax = sys->mmax > 0 ? sys->mmax : 1.0;
    /* forward Euler keeps u >= 0 when dt (6 D m / h^2 + loss + |v|/h) <= 1 */
    double rate = 6.0 * dmax * mmax / h2 + (sys->rate_max > 0 ? sys->rate_max : 0.0) +
                  ss_heal_rd_max_speed(sys) / sys->h_mm;
    return rate > 0 ? 1.0 / rate : INFINITY;
}

/* Donor-cell divergence of the flux u v at cell c (faces masked by nb). */
static inline double donor_div(const ss_heal_rd_system *sys, const float *u, size_t c, uint8_t nbm,
                               size_t sy, size_t sz) {
    const size_t off[3] = {1, sy, sz};
    double div = 0.0;
    for (int d = 0; d < 3; d++) {
        const float *v = sys->velocity[d];
        if (!v) continue;
        if (nbm & (NB_XP << (2 * d))) {
            double vf = 0.5 * ((double)v[c] + (double)v[c + off[d]]);
            div += vf > 0 ? vf * u[c] : vf * u[c + off[d]];
        }
        if (nbm & (NB_XM << (2 * d))) {
            double vf = 0.5 * ((double)v[c] + (double)v[c - off[d]]);
            div -= vf > 0 ? vf * u[c - off[d]] : vf * u[c];
        }
    }
    return div / sys->h_mm;
}

void ss_heal_rd__convect(const ss_heal_rd_system *sys, const ss_heal_rd_work *w, int f,
                         const float *src, float *dst, double dt) {
    const int nx = sys->nx, ny = sys->ny, nz = sys->nz;
    const size_t sy = (size_t)nx, sz = (size_t)nx * (size_t)ny;
    const uint8_t *upd = w->upd[f];
#pragma omp parallel for collapse(2) schedule(static) if (w->ncell >= RD_PAR_MIN_CELLS)
    for (int z = 0; z < nz; z++)
        for (int y = 0; y < ny; y++) {
            size_t base = (size_t)z * sz + (size_t)y * sy;
            for (int x = 0; x < nx; x++) {
                size_t c = base + (size_t)x;
                float v = src[c];
                if (upd[c]) {
                    v = (float)((double)src[c] - dt * donor_div(sys, src, c, w->nb[c], sy, sz));
                    v = clampf(v, sys->lo[f], sys->hi[f]);
                }
                dst[c] = v;
            }
        }
}

static int thread_count(const ss_heal_rd_work *w) {
    int nt = omp_get_max_threads();
    return nt < w->nthreads ? nt : w->nthreads;
}

void ss_heal_rd_step_explicit(ss_heal_rd_system *sys, ss_heal_rd_work *w, double dt) {
    ss_heal_rd__step_explicit_part(sys, w, dt, RD_PART_ALL, 0);
}

/* The x segments of row (y, z) that `part` computes: the whole row (ALL, or
 * a ring row of RING), the row less its ring ends (INTERIOR, a row off the
 * ring), the ring end cells (RING, a row off the ring) or none. The ring is
 * the layer of cells next to the faces in `ring` (NB_* bits): ring rows are
 * those at y or z = 1 or n - 2 next to such a face. */
static int row_segments(int part, int ring, int nx, int ny, int nz, int y, int z, int seg[2][2]) {
    const int ring_row = (y == 1 && (ring & NB_YM)) || (y == ny - 2 && (ring & NB_YP)) ||
                         (z == 1 && (ring & NB_ZM)) || (z == nz - 2 && (ring & NB_ZP));
    const int xa = ring & NB_XM ? 2 : 1, xb = ring & NB_XP ? nx - 3 : nx - 2;
    if (part == RD_PART_ALL || (part == RD_PART_RING && ring_row)) {
        seg[0][0] = 1;
        seg[0][1] = nx - 2;
        return 1;
    }
    if (part == RD_PART_INTERIOR) {
        if (ring_row || xb < xa) return 0;
        seg[0][0] = xa;
        seg[0][1] = xb;
        return 1;
    }
    int ns = 0;
    if (xa == 2 || xb < xa) { /* (a box 1 wide: its one cell) */
        seg[ns][0] = seg[ns][1] = 1;
        ns++;
    }
    if (xb == nx - 3 && nx - 2 > 1) {
        seg[ns][0] = seg[ns][1] = nx - 2;
        ns++;
    }
    return ns;
}

void ss_heal_rd__step_explicit_part(ss_heal_rd_system *sys, ss_heal_rd_work *w, double dt, int part,
                                    int ring) {
    const int nx = sys->nx, ny = sys->ny, nz = sys->nz, nf = sys->nfields;
    const size_t sy = (size_t)nx, sz = (size_t)nx * (size_t)ny;
    const float dtf = (float)dt;
    const double ih2 = 1.0 / (sys->h_mm * sys->h_mm);
    const int has_vel = sys->velocity[0] || sys->velocity[1] || sys->velocity[2];
    const int first = part != RD_PART_RING; /* ALL or INTERIOR: prepare, copy the shell */
    if (first && sys->react && sys->prepare) sys->prepare(sys->ctx, sys->u);
#pragma omp parallel num_threads(thread_count(w)) if (w->ncell >= RD_PAR_MIN_CELLS)
    {
        float *scr = w->tscratch[omp_get_thread_num()];
        ss_heal_rd_row row;
        memset(&row, 0, sizeof row);
        for (int f = 0; f < nf; f++) {
            row.prod[f] = scr + (size_t)f * (size_t)nx;
            row.loss[f] = scr + (size_t)(nf + f) * (size_t)nx;
        }
        for (int k = 0; k < sys->nslots; k++) row.m[k] = scr + (size_t)(2 * nf + k) * (size_t)nx;
        float *ones = scr + (size_t)(2 * nf + sys->nslots) * (size_t)nx;
        for (int i = 0; i < nx; i++) ones[i] = 1.0f;
        /* face weights of the row (1 = the face conducts), shared by the fields */
        float *restrict wxm = ones + nx, *restrict wxp = wxm + nx, *restrict wym = wxp + nx;
        float *restrict wyp = wym + nx, *restrict wzm = wyp + nx, *restrict wzp = wzm + nx;
        /* face conductances of the face-multiplier slot (mface): the face
         * weight times min(m) of the two cells, m = clamp(1 - u_ff, 0, 1) */
        float *restrict cxm = wzp + nx, *restrict cxp = cxm + nx, *restrict cym = cxp + nx;
        float *restrict cyp = cym + nx, *restrict czm = cyp + nx, *restrict czp = czm + nx;
        int fslot = -1, ff = -1;
        for (int k = 0; k < sys->nslots && fslot < 0; k++)
            if (sys->mface[k]) {
                fslot = k;
                ff = sys->mface[k] - 1;
            }
#pragma omp for collapse(2) schedule(static)
        for (int z = 0; z < nz; z++) {
            /* each row twice: its first and its second x segment */
            for (int ys = 0; ys < 2 * ny; ys++) {
                const int y = ys >> 1, sg = ys & 1;
                const size_t base = (size_t)z * sz + (size_t)y * sy;
                if (z == 0 || y == 0 || z == nz - 1 || y == ny - 1) {
                    if (first && !sg)
                        for (int f = 0; f < nf; f++)
                            memcpy(w->buf[f] + base, sys->u[f] + base, (size_t)nx * sizeof(float));
                    continue;
                }
                if (first && !sg)
                    for (int f = 0; f < nf; f++) {
                        w->buf[f][base] = sys->u[f][base];
                        w->buf[f][base + (size_t)nx - 1] = sys->u[f][base + (size_t)nx - 1];
                    }
                int seg[2][2];
                const int nseg = row_segments(part, ring, nx, ny, nz, y, z, seg);
                if (sg >= nseg) continue;
                const int xa = seg[sg][0], n = seg[sg][1] - xa + 1;
                row.n = n;
                row.x0 = xa;
                row.y = y;
                row.z = z;
                row.cls = sys->cls ? sys->cls + base + xa : NULL;
                for (int f = 0; f < nf; f++) row.u[f] = sys->u[f] + base + xa;
                if (sys->react) {
                    sys->react(sys->ctx, &row);
                } else {
                    for (int f = 0; f < nf; f++) {
                        memset(row.prod[f], 0, (size_t)n * sizeof(float));
                        memset(row.loss[f], 0, (size_t)n * sizeof(float));
                    }
                    for (int k = 0; k < sys->nslots; k++)
                        for (int i = 0; i < n; i++) row.m[k][i] = 1.0f;
                }
                const uint8_t *restrict nbr = w->nb + base;
#pragma omp simd
                for (int x = xa; x < xa + n; x++) {
                    const uint8_t b = nbr[x];
                    wxm[x] = (float)(b & 1);
                    wxp[x] = (float)((b >> 1) & 1);
                    wym[x] = (float)((b >> 2) & 1);
                    wyp[x] = (float)((b >> 3) & 1);
                    wzm[x] = (float)((b >> 4) & 1);
                    wzp[x] = (float)((b >> 5) & 1);
                }
                if (fslot >= 0) {
                    const float *restrict q = sys->u[ff] + base;
                    const float qc = sys->mface_closed > 0.0f ? sys->mface_closed : INFINITY;
#pragma omp simd
                    for (int x = xa; x < xa + n; x++) {
                        const float mc = face_m(q[x], qc);
                        const float ml = face_m(q[x - 1], qc);
                        const float mr = face_m(q[x + 1], qc);
                        const float ms = face_m(q[x - (long)sy], qc);
                        const float mn = face_m(q[x + sy], qc);
                        const float md = face_m(q[x - (long)sz], qc);
                        const float mu = face_m(q[x + sz], qc);
                        cxm[x] = wxm[x] * (mc < ml ? mc : ml);
                        cxp[x] = wxp[x] * (mc < mr ? mc : mr);
                        cym[x] = wym[x] * (mc < ms ? mc : ms);
                        cyp[x] = wyp[x] * (mc < mn ? mc : mn);
                        czm[x] = wzm[x] * (mc < md ? mc : md);
                        czp[x] = wzp[x] * (mc < mu ? mc : mu);
                    }
                    if (sys->vfrac) {
                        /* sub-voxel tissue [D14]: a cell with v < 1 holds its
                         * crust apart (its own m is 1, as the split scheme's
                         * reaction writes); lateral faces x min(v), the face
                         * below a cell x 2 / (1 + v) of the upper cell, all
                         * divided by the cell's own v */
                        const float *restrict v = sys->vfrac + base;
                        for (int x = xa; x < xa + n; x++) {
                            const long o[6] = {-1, 1, -(long)sy, (long)sy, -(long)sz, (long)sz};
                            float *const cf[6] = {cxm, cxp, cym, cyp, czm, czp};
                            const float *const wf[6] = {wxm, wxp, wym, wyp, wzm, wzp};
                            const float vc = v[x], iv = 1.0f / vc;
                            const float mc = vc < 1.0f ? 1.0f : face_m(q[x], qc);
                            for (int k = 0; k < 6; k++) {
                                const float vn = v[x + o[k]];
                                const float mn = vn < 1.0f ? 1.0f : face_m(q[x + o[k]], qc);
                                const float g = k < 4    ? (vc < vn ? vc : vn)
                                                : k == 4 ? 2.0f / (1.0f + vc)
                                                         : 2.0f / (1.0f + vn);
                                cf[k][x] = wf[k][x] * (mc < mn ? mc : mn) * g * iv;
                            }
                        }
                    }
                }
                for (int f = 0; f < nf; f++) {
                    const float *restrict u = sys->u[f] + base;
                    float *restrict un = w->buf[f] + base;
                    const uint8_t *restrict upd = w->upd[f] + base;
                    const float *restrict pr = row.prod[f];
                    const float *restrict ls = row.loss[f];
                    const int fc = fslot >= 0 && sys->mslot[f] == fslot;
                    const float *restrict mk =
                        sys->mslot[f] >= 0 && !fc ? row.m[sys->mslot[f]] : ones;
                    const float *restrict Wxm = fc ? cxm : wxm, *restrict Wxp = fc ? cxp : wxp;
                    const float *restrict Wym = fc ? cym : wym, *restrict Wyp = fc ? cyp : wyp;
                    const float *restrict Wzm = fc ? czm : wzm, *restrict Wzp = fc ? czp : wzp;
                    const float Dh = (float)(sys->D[f] * ih2);
                    const float lo = sys->lo[f], hi = sys->hi[f];
                    /* The three variants give the same values as the full
                     * stencil: a face term that is 0 * (finite) only adds a
                     * signed zero, which the clamp at lo = 0 removes. */
                    if (!(Dh > 0.0f)) {
                        /* no diffusion (scar, a static region) */
#pragma omp simd
                        for (int x = xa; x < xa + n; x++) {
                            const float uc = u[x];
                            float v = uc + dtf * (pr[x - xa] - ls[x - xa] * uc);
                            v = v > lo ? v : lo;
                            v = v < hi ? v : hi;
                            un[x] = upd[x] ? v : uc;
                        }
                    } else if (sys->lateral[f]) {
                        /* lateral fields: the z faces do not conduct */
#pragma omp simd
                        for (int x = xa; x < xa + n; x++) {
                            const float uc = u[x];
                            const float lap = Wxm[x] * (u[x - 1] - uc) + Wxp[x] * (u[x + 1] - uc) +
                                              Wym[x] * (u[x - (long)sy] - uc) +
                                              Wyp[x] * (u[x + sy] - uc);
                            float v =
                                uc + dtf * (mk[x - xa] * Dh * lap + pr[x - xa] - ls[x - xa] * uc);
                            v = v > lo ? v : lo;
                            v = v < hi ? v : hi;
                            un[x] = upd[x] ? v : uc;
                        }
                    } else {
#pragma omp simd
                        for (int x = xa; x < xa + n; x++) {
                            const float uc = u[x];
                            const float lap =
                                Wxm[x] * (u[x - 1] - uc) + Wxp[x] * (u[x + 1] - uc) +
                                Wym[x] * (u[x - (long)sy] - uc) + Wyp[x] * (u[x + sy] - uc) +
                                Wzm[x] * (u[x - (long)sz] - uc) + Wzp[x] * (u[x + sz] - uc);
                            float v =
                                uc + dtf * (mk[x - xa] * Dh * lap + pr[x - xa] - ls[x - xa] * uc);
                            v = v > lo ? v : lo;
                            v = v < hi ? v : hi;
                            un[x] = upd[x] ? v : uc;
                        }
                    }
                    if (has_vel) {
                        for (int x = xa; x < xa + n; x++) {
                            if (!upd[x]) continue;
                            size_t c = base + (size_t)x;
                            float v =
                                un[x] - (float)(dt * donor_div(sys, sys->u[f], c, nbr[x], sy, sz));
                            un[x] = clampf(v, lo, hi);
                        }
                    }
                }
            }
        }
    }
    if (part == RD_PART_INTERIOR) return; /* the ring follows: then the exchange */
    for (int f = 0; f < nf; f++) {
        float *t = sys->u[f];
        sys->u[f] = w->buf[f];
        w->buf[f] = t;
    }
}
