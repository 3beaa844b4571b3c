/* Generic reaction-diffusion-convection core, operator-split part (the faster
 * scheme next to the seed's explicit central differences of §5.1). One step:
 * Strang splitting R(dt/2) T(dt) R(dt/2):
 *  R: reaction, per cell, substeps of u <- (u + h prod) / (1 + h loss)
 *     (production explicit, loss implicit: unconditionally non-negative); the
 *     diffusion multipliers m_k are frozen from the state of the last substep
 *     of the first half;
 *  T: convection (donor-cell, subcycled to the CFL limit; only with a
 *     velocity), then diffusion: implicit Euler, locally one-dimensional
 *     (LOD): for each field
 *     solve (I - dt m D d_xx) then d_yy then d_zz by the Thomas algorithm.
 *     Every line matrix is an M-matrix with unit column sums where m = 1, so
 *     the step is unconditionally stable, keeps u >= 0 and conserves mass of
 *     pure diffusion with no-flux faces (with a tissue volume fraction
 *     vfrac, [D14], the rows are divided by v: the sum of v u is conserved,
 *     still an M-matrix). Lines are solved in bundles (all x
 *     lines of a z slab, all y lines of a z slab, all z lines of a y slab) so
 *     independent lines fill the SIMD lanes and memory access stays local.
 * OpenMP over rows/slabs; no reductions, so bit-identical for any thread count. */
/* The hot loops are written branch-free for SIMD. At -O2 GCC vectorises
 * their compares/selects only with loop if-conversion and without treating
 * FP exception flags as observable (-fno-trapping-math: values are unchanged,
 * unlike -ffast-math there is no reassociation or finite-math assumption). */
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("tree-loop-if-convert", "tree-loop-vectorize", "no-trapping-math",            \
                     "fp-contract=off")
#endif
/* The reaction update and the line solves are built twice, for AVX2 and for
 * the baseline, and the loader picks one per machine (issue 25: 8 lanes
 * instead of 4). The AVX2 target has no FMA and contraction is off, so both
 * copies do the same IEEE single-precision operations in the same order:
 * every result is bit-identical whichever copy runs. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define RD_HOT __attribute__((target_clones("avx2", "default"), noinline))
#else
#define RD_HOT
#endif
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "heal_internal.h"

static int thread_count(const ss_heal_rd_work *w) {
    int nt = omp_get_max_threads();
    return nt < w->nthreads ? nt : w->nthreads;
}

/* One substep of one field on one row: u <- clamp((u + h prod) / (1 + h loss))
 * where the field is updated. */
RD_HOT static void react_update(float *restrict u, const float *restrict pr,
                                const float *restrict ls, const uint8_t *restrict upd, int n,
                                float h, float lo, float hi) {
#pragma omp simd
    for (int i = 0; i < n; i++) {
        float v = (u[i] + h * pr[i]) / (1.0f + h * ls[i]);
        v = clampf(v, lo, hi);
        u[i] = upd[i] ? v : u[i];
    }
}

static void reaction_pass(ss_heal_rd_system *sys, ss_heal_rd_work *w, double dt, int nsub) {
    const int nx = sys->nx, ny = sys->ny, nz = sys->nz, nf = sys->nfields;
    const size_t sy = (size_t)nx, sz = (size_t)nx * (size_t)ny;
    const int n = nx - 2;
    if (nsub < 1) nsub = 1;
    const float h = (float)(dt / nsub);
    if (sys->react && sys->prepare) sys->prepare(sys->ctx, sys->u);
#pragma omp parallel num_threads(thread_count(w)) if (w->ncell >= RD_PAR_MIN_CELLS)
    {
        float *scr = w->tscratch[omp_get_thread_num()];
        ss_heal_rd_row row;
        memset(&row, 0, sizeof row);
        /* the row is updated in place: the reaction reads only its own row
         * and the column values of the prepare hook (copying each row to the
         * scratch and back cost 4 % of a step, issue 25) */
        float *loc[SS_HEAL_RD_MAXF];
        for (int f = 0; f < nf; f++) {
            row.prod[f] = scr + (size_t)f * (size_t)nx;
            row.loss[f] = scr + (size_t)(nf + f) * (size_t)nx;
        }
        for (int k = 0; k < sys->nslots; k++) row.m[k] = scr + (size_t)(3 * nf + k) * (size_t)nx;
#pragma omp for collapse(2) schedule(static)
        for (int z = 1; z < nz - 1; z++) {
            for (int y = 1; y < ny - 1; y++) {
                const size_t base = (size_t)z * sz + (size_t)y * sy + 1;
                row.n = n;
                row.x0 = 1;
                row.y = y;
                row.z = z;
                row.cls = sys->cls ? sys->cls + base : NULL;
                for (int f = 0; f < nf; f++) row.u[f] = loc[f] = sys->u[f] + base;
                if (sys->react) {
                    for (int s = 0; s < nsub; s++) {
                        sys->react(sys->ctx, &row);
                        /* multipliers frozen from the state at the last substep */
                        if (s == nsub - 1)
                            for (int k = 0; k < sys->nslots; k++)
                                memcpy(w->mslot[k] + base, row.m[k], (size_t)n * 4);
                        for (int f = 0; f < nf; f++)
                            react_update(loc[f], row.prod[f], row.loss[f], w->upd[f] + base, n, h,
                                         sys->lo[f], sys->hi[f]);
                    }
                } else {
                    for (int k = 0; k < sys->nslots; k++)
                        for (int i = 0; i < n; i++) w->mslot[k][base + (size_t)i] = 1.0f;
                }
            }
        }
    }
}

/* Skipping lines that are exactly zero (issue 25: in much of the block a
 * field such as the epithelium or the eschar is 0 bit for bit). If every
 * unknown u of a line is +0 (bits zero) and every coefficient is finite, the
 * Thomas sweep writes +0 back: forward, dp = (u - a dpp) r with u = +0,
 * dpp = +0 and a <= 0 gives +0 - (-0 or +0) = +0, times r > 0 (the pivot
 * b - a cpp >= 1 of this M-matrix, finite) is +0; backward u = dp - cp un
 * = +0 - (+-0) = +0; the clamp then returns clampf(+0, lo, hi), which is +0
 * when zero_kept says so. Finite coefficients: the multiplier m is in
 * [0, RD_MLIM / kD] (a NaN or huge m fails the test and the line is solved as
 * before). So the skip changes no bit. */
#define RD_MLIM 1e18f

static int zero_kept(float lo, float hi) {
    const float z = clampf(0.0f, lo, hi);
    uint32_t b;
    memcpy(&b, &z, sizeof b);
    return b == 0u;
}

/* 1 when the n floats at p are all +0 */
static int bits_zero(const float *p, size_t n) {
    uint32_t acc = 0;
    for (size_t i = 0; i < n; i++) {
        uint32_t b;
        memcpy(&b, p + i, sizeof b);
        acc |= b;
    }
    return acc == 0u;
}

/* 1 when the n multipliers at p are in [0, lim] */
static int m_tame(const float *p, size_t n, float lim) {
    int ok = 1;
    for (size_t i = 0; i < n; i++) ok &= p[i] >= 0.0f && p[i] <= lim;
    return ok;
}

static float m_limit(float kD) { return RD_MLIM / (kD > 1.0f ? kD : 1.0f); }

/* Lines are swept in bundles of at most BUNDLE lines side by side, so the
 * Thomas coefficients of a bundle (2 x line length x BUNDLE floats) stay in
 * the L2 cache; the lines are independent, so the chunking does not change
 * any result. */
#define BUNDLE 64

/* Bundle of lines along direction d (1 = y, 2 = z) at outer index o, for
 * x in [x0, x0 + cw): the recurrence runs along the line, x is the SIMD
 * dimension. Clamps to [lo, hi] on the way back when clampit. */
RD_HOT static void bundle_yz(const ss_heal_rd_system *sys, const ss_heal_rd_work *w, int f,
                             float kD, const float *mk, int face, int d, int o, int x0, int cw,
                             float *scr, int clampit) {
    const size_t sy = (size_t)sys->nx, sz = (size_t)sys->nx * (size_t)sys->ny;
    const int nline = d == 1 ? sys->ny : sys->nz;
    const size_t step = d == 1 ? sy : sz;
    const size_t ob = (size_t)o * (d == 1 ? sz : sy) + (size_t)x0;
    const uint8_t bm = d == 1 ? NB_YM : NB_ZM, bp = d == 1 ? NB_YP : NB_ZP;
    const size_t ldc = (size_t)cw;
    /* scratch: cp, dp (nline rows of cw each; row 0 zero), and a fixed row of
     * ones for fields without multiplier */
    float *restrict cpall = scr;
    float *restrict dpall = scr + (size_t)nline * ldc;
    const float *restrict ones = scr + w->ones_off + x0;
    float *restrict u0 = sys->u[f] + ob;
    if (!clampit || zero_kept(sys->lo[f], sys->hi[f])) {
        int zero = 1;
        for (int j = 1; zero && j < nline - 1; j++) zero = bits_zero(u0 + (size_t)j * step, ldc);
        for (int j = 0; zero && mk && j < nline; j++)
            zero = m_tame(mk + ob + (size_t)j * step, ldc, m_limit(kD));
        if (zero) return; /* exactly zero in, exactly zero out (above) */
    }
    for (int x = 0; x < cw; x++) cpall[x] = dpall[x] = 0.0f; /* "line -1": no coupling */
    for (int j = 1; j < nline - 1; j++) {
        const size_t lb = (size_t)j * step;
        float *restrict u = u0 + lb;
        const uint8_t *restrict nb = w->nb + ob + lb;
        const uint8_t *restrict upd = w->upd[f] + ob + lb;
        const float *restrict mrow = mk ? mk + ob + lb : ones;
        float *restrict cp = cpall + (size_t)j * ldc;
        float *restrict dp = dpall + (size_t)j * ldc;
        const float *restrict cpp = cp - ldc;
        const float *restrict dpp = dp - ldc;
        if (face && sys->vfrac) {
            /* with sub-voxel tissue [D14]: lateral faces x min(v), the face
             * below a cell x 2 / (1 + v) of the upper cell, the row / v */
            const float *restrict mlo = mrow - step, *restrict mhi = mrow + step;
            const float *restrict v = sys->vfrac + ob + lb;
            const float *restrict vlo = v - step, *restrict vhi = v + step;
#pragma omp simd
            for (int x = 0; x < cw; x++) {
                const float k = kD / v[x] * (float)(upd[x] != 0);
                const float ml = mrow[x] < mlo[x] ? mrow[x] : mlo[x];
                const float mr = mrow[x] < mhi[x] ? mrow[x] : mhi[x];
                const float gl = d == 1 ? (v[x] < vlo[x] ? v[x] : vlo[x]) : 2.0f / (1.0f + v[x]);
                const float gr = d == 1 ? (v[x] < vhi[x] ? v[x] : vhi[x]) : 2.0f / (1.0f + vhi[x]);
                const float wl = (float)((nb[x] & bm) != 0) * ml * gl;
                const float wr = (float)((nb[x] & bp) != 0) * mr * gr;
                const float a = -k * wl, c = -k * wr, b = 1.0f + k * (wl + wr);
                const float r = 1.0f / (b - a * cpp[x]);
                cp[x] = c * r;
                dp[x] = (u[x] - a * dpp[x]) * r;
            }
            continue;
        }
        if (face) {
            /* conservative: face conductance min(m) of the two cells */
            const float *restrict mlo = mrow - step, *restrict mhi = mrow + step;
#pragma omp simd
            for (int x = 0; x < cw; x++) {
                const float k = kD * (float)(upd[x] != 0);
                const float ml = mrow[x] < mlo[x] ? mrow[x] : mlo[x];
                const float mr = mrow[x] < mhi[x] ? mrow[x] : mhi[x];
                const float wl = (float)((nb[x] & bm) != 0) * ml;
                const float wr = (float)((nb[x] & bp) != 0) * mr;
                const float a = -k * wl, c = -k * wr, b = 1.0f + k * (wl + wr);
                const float r = 1.0f / (b - a * cpp[x]);
                cp[x] = c * r;
                dp[x] = (u[x] - a * dpp[x]) * r;
            }
            continue;
        }
#pragma omp simd
        for (int x = 0; x < cw; x++) {
            const float k = kD * mrow[x] * (float)(upd[x] != 0);
            const float wl = (float)((nb[x] & bm) != 0);
            const float wr = (float)((nb[x] & bp) != 0);
            const float a = -k * wl, c = -k * wr, b = 1.0f + k * (wl + wr);
            const float r = 1.0f / (b - a * cpp[x]);
            cp[x] = c * r;
            dp[x] = (u[x] - a * dpp[x]) * r;
        }
    }
    const float lo = sys->lo[f], hi = sys->hi[f];
    {
        const int j = nline - 2;
        float *restrict u = u0 + (size_t)j * step;
        const float *restrict dp = dpall + (size_t)j * ldc;
        for (int x = 0; x < cw; x++) u[x] = clampit ? clampf(dp[x], lo, hi) : dp[x];
    }
    for (int j = nline - 3; j >= 1; j--) {
        float *restrict u = u0 + (size_t)j * step;
        const float *restrict un = u0 + (size_t)(j + 1) * step;
        const float *restrict cp = cpall + (size_t)j * ldc;
        float *restrict dp = dpall + (size_t)j * ldc;
        const float *restrict dn = dp + ldc;
        if (clampit) {
            /* recurrence on the unclamped values (kept in dp), clamped output */
            for (int x = 0; x < cw; x++) {
                const float v = dp[x] - cp[x] * dn[x];
                dp[x] = v;
                u[x] = clampf(v, lo, hi);
            }
        } else {
            for (int x = 0; x < cw; x++) u[x] = dp[x] - cp[x] * un[x];
        }
    }
}

/* The x lines y in [y0, y0 + ch) of slab z at once: the recurrence runs along
 * x while the independent lines form the SIMD dimension, so the Thomas sweep
 * is not bound by the latency of its division chain. Scratch layout [x][y]. */
RD_HOT static void bundle_x(const ss_heal_rd_system *sys, const ss_heal_rd_work *w, int f, float kD,
                            const float *mk, int face, int z, int y0, int ch, float *scr) {
    const int nx = sys->nx;
    const size_t sy = (size_t)nx;
    const size_t bz = (size_t)z * (size_t)nx * (size_t)sys->ny + (size_t)y0 * sy;
    const size_t ldc = (size_t)ch;
    float *restrict cpall = scr;
    float *restrict dpall = scr + (size_t)nx * ldc;
    float *restrict u = sys->u[f] + bz;
    const uint8_t *restrict nb = w->nb + bz;
    const uint8_t *restrict upd = w->upd[f] + bz;
    const float *restrict m = mk ? mk + bz : NULL;
    const float *restrict vf = sys->vfrac ? sys->vfrac + bz : NULL;
    {
        int zero = 1;
        for (int y = 0; zero && y < ch; y++)
            zero = bits_zero(u + (size_t)y * sy + 1, (size_t)nx - 2);
        for (int y = 0; zero && m && y < ch; y++)
            zero = m_tame(m + (size_t)y * sy, (size_t)nx, m_limit(kD));
        if (zero) return; /* exactly zero in, exactly zero out (bits_zero above) */
    }
    for (int y = 0; y < ch; y++) cpall[y] = dpall[y] = 0.0f; /* x = 0: no coupling */
    for (int x = 1; x < nx - 1; x++) {
        float *restrict cp = cpall + (size_t)x * ldc;
        float *restrict dp = dpall + (size_t)x * ldc;
        const float *restrict cpp = cp - ldc;
        const float *restrict dpp = dp - ldc;
#define BX_BODY(MVAL)                                                                              \
    {                                                                                              \
        const size_t c = (size_t)y * sy + (size_t)x;                                               \
        const float k = kD * (MVAL) * (float)(upd[c] != 0);                                        \
        const float wl = (float)((nb[c] & NB_XM) != 0);                                            \
        const float wr = (float)((nb[c] & NB_XP) != 0);                                            \
        const float a = -k * wl, cc = -k * wr, b = 1.0f + k * (wl + wr);                           \
        const float r = 1.0f / (b - a * cpp[y]);                                                   \
        cp[y] = cc * r;                                                                            \
        dp[y] = (u[c] - a * dpp[y]) * r;                                                           \
    }
        if (m && face && vf) {
            /* with sub-voxel tissue [D14]: faces x min(v), the row / v */
#pragma omp simd
            for (int y = 0; y < ch; y++) {
                const size_t c = (size_t)y * sy + (size_t)x;
                const float k = kD / vf[c] * (float)(upd[c] != 0);
                const float ml = m[c] < m[c - 1] ? m[c] : m[c - 1];
                const float mr = m[c] < m[c + 1] ? m[c] : m[c + 1];
                const float gl = vf[c] < vf[c - 1] ? vf[c] : vf[c - 1];
                const float gr = vf[c] < vf[c + 1] ? vf[c] : vf[c + 1];
                const float wl = (float)((nb[c] & NB_XM) != 0) * ml * gl;
                const float wr = (float)((nb[c] & NB_XP) != 0) * mr * gr;
                const float a = -k * wl, cc = -k * wr, b = 1.0f + k * (wl + wr);
                const float r = 1.0f / (b - a * cpp[y]);
                cp[y] = cc * r;
                dp[y] = (u[c] - a * dpp[y]) * r;
            }
        } else if (m && face) {
            /* conservative: face conductance min(m) of the two cells */
#pragma omp simd
            for (int y = 0; y < ch; y++) {
                const size_t c = (size_t)y * sy + (size_t)x;
                const float k = kD * (float)(upd[c] != 0);
                const float ml = m[c] < m[c - 1] ? m[c] : m[c - 1];
                const float mr = m[c] < m[c + 1] ? m[c] : m[c + 1];
                const float wl = (float)((nb[c] & NB_XM) != 0) * ml;
                const float wr = (float)((nb[c] & NB_XP) != 0) * mr;
                const float a = -k * wl, cc = -k * wr, b = 1.0f + k * (wl + wr);
                const float r = 1.0f / (b - a * cpp[y]);
                cp[y] = cc * r;
                dp[y] = (u[c] - a * dpp[y]) * r;
            }
        } else if (m) {
#pragma omp simd
            for (int y = 0; y < ch; y++) BX_BODY(m[(size_t)y * sy + (size_t)x])
        } else {
#pragma omp simd
            for (int y = 0; y < ch; y++) BX_BODY(1.0f)
        }
#undef BX_BODY
    }
    {
        const int x = nx - 2;
        const float *restrict dp = dpall + (size_t)x * ldc;
        for (int y = 0; y < ch; y++) u[(size_t)y * sy + (size_t)x] = dp[y];
    }
    for (int x = nx - 3; x >= 1; x--) {
        const float *restrict cp = cpall + (size_t)x * ldc;
        const float *restrict dp = dpall + (size_t)x * ldc;
#pragma omp simd
        for (int y = 0; y < ch; y++) {
            const size_t c = (size_t)y * sy + (size_t)x;
            u[c] = dp[y] - cp[y] * u[c + 1];
        }
    }
}

/* Implicit-Euler LOD diffusion of every field with D > 0: one parallel
 * region, three work-shared sweeps (x bundles per z, y bundles per z, z bundles per
 * y), fields looped inside, the admissible-range clamp fused into the last
 * (the y sweep for lateral fields, which skip z). */
static void diffuse_all(ss_heal_rd_system *sys, ss_heal_rd_work *w, double dt, int dirs) {
    const int nx = sys->nx, ny = sys->ny, nz = sys->nz, nf = sys->nfields;
    const double ih2 = 1.0 / (sys->h_mm * sys->h_mm);
    float kD[SS_HEAL_RD_MAXF];
    const float *mk[SS_HEAL_RD_MAXF];
    int act[SS_HEAL_RD_MAXF], face[SS_HEAL_RD_MAXF], na = 0;
    for (int f = 0; f < nf; f++) {
        if (!(sys->D[f] > 0)) continue;
        act[na++] = f;
        kD[f] = (float)(dt * sys->D[f] * ih2);
        mk[f] = sys->mslot[f] >= 0 && w->have_mslot ? w->mslot[sys->mslot[f]] : NULL;
        face[f] = mk[f] && sys->mface[sys->mslot[f]] != 0;
    }
    if (!na) return;
#pragma omp parallel num_threads(thread_count(w)) if (w->ncell >= RD_PAR_MIN_CELLS)
    {
        float *scr = w->tscratch[omp_get_thread_num()];
        /* dirs: bit 0 x, bit 1 y, bit 2 z (the MPI driver runs them apart) */
#pragma omp for collapse(2) schedule(static)
        for (int z = 1; z < nz - 1; z++)
            for (int y0 = 1; y0 < ny - 1; y0 += BUNDLE) {
                if (!(dirs & 1)) continue;
                const int ch = ny - 1 - y0 < BUNDLE ? ny - 1 - y0 : BUNDLE;
                for (int a = 0; a < na; a++)
                    bundle_x(sys, w, act[a], kD[act[a]], mk[act[a]], face[act[a]], z, y0, ch, scr);
            }
#pragma omp for collapse(2) schedule(static)
        for (int z = 1; z < nz - 1; z++)
            for (int x0 = 1; x0 < nx - 1; x0 += BUNDLE) {
                if (!(dirs & 2)) continue;
                const int cw = nx - 1 - x0 < BUNDLE ? nx - 1 - x0 : BUNDLE;
                for (int a = 0; a < na; a++)
                    bundle_yz(sys, w, act[a], kD[act[a]], mk[act[a]], face[act[a]], 1, z, x0, cw,
                              scr, sys->lateral[act[a]]);
            }
#pragma omp for collapse(2) schedule(static)
        for (int y = 1; y < ny - 1; y++)
            for (int x0 = 1; x0 < nx - 1; x0 += BUNDLE) {
                if (!(dirs & 4)) continue;
                const int cw = nx - 1 - x0 < BUNDLE ? nx - 1 - x0 : BUNDLE;
                for (int a = 0; a < na; a++)
                    if (!sys->lateral[act[a]])
                        bundle_yz(sys, w, act[a], kD[act[a]], mk[act[a]], face[act[a]], 2, y, x0,
                                  cw, scr, 1);
            }
    }
}

void ss_heal_rd__step_split_phase(ss_heal_rd_system *sys, ss_heal_rd_work *w, double dt, int nsub,
                                  int phase) {
    /* Strang: half reaction, transport, half reaction */
    const int nhalf = (nsub + 1) / 2;
    if (phase == 0) {
        reaction_pass(sys, w, 0.5 * dt, nhalf);
        const int has_vel = sys->velocity[0] || sys->velocity[1] || sys->velocity[2];
        if (has_vel && w->have_buf) {
            double speed = ss_heal_rd_max_speed(sys);
            if (sys->conv) sys->conv(sys->conv_ctx, SS_HEAL_CONV_SPEED, sys->u, &speed);
            int nc = (int)ceil(dt * speed / sys->h_mm / 0.9);
            if (nc < 1) nc = 1;
            double h = dt / nc;
            /* the fields convect independently (the velocity is fixed over the
             * step): subcycle by subcycle, each box's halo refreshed first */
            for (int s = 0; s < nc; s++) {
                if (sys->conv) sys->conv(sys->conv_ctx, SS_HEAL_CONV_HALO, sys->u, NULL);
                for (int f = 0; f < sys->nfields; f++) {
                    ss_heal_rd__convect(sys, w, f, sys->u[f], w->buf[f], h);
                    float *t = sys->u[f];
                    sys->u[f] = w->buf[f];
                    w->buf[f] = t;
                }
            }
        }
        diffuse_all(sys, w, dt, 1);
    } else if (phase == 1) {
        diffuse_all(sys, w, dt, 2);
    } else {
        diffuse_all(sys, w, dt, 4);
        reaction_pass(sys, w, 0.5 * dt, nhalf);
    }
}

void ss_heal_rd_step_split(ss_heal_rd_system *sys, ss_heal_rd_work *w, double dt, int nsub) {
    for (int phase = 0; phase < 3; phase++) ss_heal_rd__step_split_phase(sys, w, dt, nsub, phase);
}
