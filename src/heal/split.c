/* Generic reaction-diffusion-convection core, operator-split part (the faster
 * scheme next to the seed's explicit central differences of §5.1). One step:
 *  1. reaction: per cell, nsub substeps of u <- (u + h prod) / (1 + h loss)
 *     (production explicit, loss implicit: unconditionally non-negative),
 *     then the diffusion multipliers m_k are frozen from the new state;
 *  2. convection: donor-cell, subcycled to the CFL limit (only with a velocity);
 *  3. diffusion: implicit Euler, locally one-dimensional (LOD): for each field
 *     solve (I - dt m D d_xx) then d_yy then d_zz by the Thomas algorithm.
 *     Every line matrix is an M-matrix with unit column sums where m = 1, so
 *     the step is unconditionally stable, keeps u >= 0 and conserves mass of
 *     pure diffusion with no-flux faces. x lines are solved one by one, y and
 *     z lines are swept in bundles along x so memory access stays contiguous.
 * OpenMP over rows/slabs; no reductions, so bit-identical for any thread count. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "heal_internal.h"

static int thread_count(const ss_heal_rd_work *w) {
    int nt = omp_get_max_threads();
    return nt < w->nthreads ? nt : w->nthreads;
}

static void reaction_pass(ss_heal_rd_system *sys, ss_heal_rd_work *w, double dt, int nsub) {
    const int nx = sys->nx, ny = sys->ny, nz = sys->nz, nf = sys->nfields;
    const size_t sy = (size_t)nx, sz = (size_t)nx * (size_t)ny;
    const int n = nx - 2;
    if (nsub < 1) nsub = 1;
    const float h = (float)(dt / nsub);
#pragma omp parallel num_threads(thread_count(w))
    {
        float *scr = w->tscratch[omp_get_thread_num()];
        ss_heal_rd_row row;
        memset(&row, 0, sizeof row);
        float *loc[SS_HEAL_RD_MAXF];
        for (int f = 0; f < nf; f++) {
            row.prod[f] = scr + (size_t)f * (size_t)nx;
            row.loss[f] = scr + (size_t)(nf + f) * (size_t)nx;
            loc[f] = scr + (size_t)(2 * nf + f) * (size_t)nx;
            row.u[f] = loc[f];
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
                for (int f = 0; f < nf; f++) memcpy(loc[f], sys->u[f] + base, (size_t)n * 4);
                if (sys->react) {
                    for (int s = 0; s < nsub; s++) {
                        sys->react(sys->ctx, &row);
                        for (int f = 0; f < nf; f++) {
                            float *restrict u = loc[f];
                            const float *restrict pr = row.prod[f];
                            const float *restrict ls = row.loss[f];
                            const uint8_t *restrict upd = w->upd[f] + base;
                            const float lo = sys->lo[f], hi = sys->hi[f];
                            for (int i = 0; i < n; i++) {
                                float v = (u[i] + h * pr[i]) / (1.0f + h * ls[i]);
                                v = fminf(fmaxf(v, lo), hi);
                                u[i] = upd[i] ? v : u[i];
                            }
                        }
                    }
                    /* multipliers frozen from the post-reaction state */
                    if (sys->nslots > 0) {
                        sys->react(sys->ctx, &row);
                        for (int k = 0; k < sys->nslots; k++)
                            memcpy(w->mslot[k] + base, row.m[k], (size_t)n * 4);
                    }
                    for (int f = 0; f < nf; f++) memcpy(sys->u[f] + base, loc[f], (size_t)n * 4);
                } else {
                    for (int k = 0; k < sys->nslots; k++)
                        for (int i = 0; i < n; i++) w->mslot[k][base + (size_t)i] = 1.0f;
                }
            }
        }
    }
}

/* Coefficient k_i = dt D m_i / h^2 for updated cells, 0 for walls and fixed. */
static inline float coef(const ss_heal_rd_work *w, int f, const float *mk, size_t c, float kD) {
    return w->upd[f][c] ? kD * (mk ? mk[c] : 1.0f) : 0.0f;
}

static void diffuse_x(const ss_heal_rd_system *sys, ss_heal_rd_work *w, int f, float kD,
                      const float *mk) {
    const int nx = sys->nx, ny = sys->ny, nz = sys->nz;
    const size_t sy = (size_t)nx, sz = (size_t)nx * (size_t)ny;
#pragma omp parallel num_threads(thread_count(w))
    {
        float *cp = w->tscratch[omp_get_thread_num()];
        float *dp = cp + nx;
#pragma omp for collapse(2) schedule(static)
        for (int z = 1; z < nz - 1; z++) {
            for (int y = 1; y < ny - 1; y++) {
                const size_t base = (size_t)z * sz + (size_t)y * sy;
                float *restrict u = sys->u[f] + base;
                const uint8_t *restrict nb = w->nb + base;
                /* forward sweep over x = 1 .. nx-2 */
                float cprev = 0.0f, dprev = 0.0f;
                for (int x = 1; x < nx - 1; x++) {
                    const float k = coef(w, f, mk, base + (size_t)x, kD);
                    const float wl = (float)(nb[x] & NB_XM ? 1 : 0);
                    const float wr = (float)(nb[x] & NB_XP ? 1 : 0);
                    const float a = -k * wl, c = -k * wr, b = 1.0f + k * (wl + wr);
                    const float den = b - a * cprev;
                    cprev = c / den;
                    dprev = (u[x] - a * dprev) / den;
                    cp[x] = cprev;
                    dp[x] = dprev;
                }
                float nxt = dp[nx - 2];
                u[nx - 2] = nxt;
                for (int x = nx - 3; x >= 1; x--) {
                    nxt = dp[x] - cp[x] * nxt;
                    u[x] = nxt;
                }
            }
        }
    }
}

/* Lines along direction d (1 = y, 2 = z), swept in bundles of x. */
static void diffuse_yz(const ss_heal_rd_system *sys, ss_heal_rd_work *w, int f, float kD,
                       const float *mk, int d) {
    const int nx = sys->nx, ny = sys->ny, nz = sys->nz;
    const size_t sy = (size_t)nx, sz = (size_t)nx * (size_t)ny;
    const int nline = d == 1 ? ny : nz;   /* cells along the line */
    const int nouter = d == 1 ? nz : ny;  /* bundles */
    const size_t step = d == 1 ? sy : sz; /* stride along the line */
    const size_t ostep = d == 1 ? sz : sy;
    const uint8_t bm = d == 1 ? NB_YM : NB_ZM, bp = d == 1 ? NB_YP : NB_ZP;
    const int n = nx - 2;
#pragma omp parallel num_threads(thread_count(w))
    {
        float *scr = w->tscratch[omp_get_thread_num()];
#pragma omp for schedule(static)
        for (int o = 1; o < nouter - 1; o++) {
            float *restrict cpall = scr;
            float *restrict dpall = scr + (size_t)nline * (size_t)nx;
            float *restrict u0 = sys->u[f] + (size_t)o * ostep;
            for (int j = 1; j < nline - 1; j++) {
                const size_t lb = (size_t)j * step; /* offset of line cell j, x = 0 */
                float *restrict u = u0 + lb;
                const uint8_t *restrict nb = w->nb + (size_t)o * ostep + lb;
                const uint8_t *restrict upd = w->upd[f] + (size_t)o * ostep + lb;
                const float *restrict mrow = mk ? mk + (size_t)o * ostep + lb : NULL;
                float *restrict cp = cpall + (size_t)j * (size_t)nx;
                float *restrict dp = dpall + (size_t)j * (size_t)nx;
                const float *restrict cpp = cpall + (size_t)(j - 1) * (size_t)nx;
                const float *restrict dpp = dpall + (size_t)(j - 1) * (size_t)nx;
                for (int x = 1; x <= n; x++) {
                    const float k = upd[x] ? kD * (mrow ? mrow[x] : 1.0f) : 0.0f;
                    const float wl = (float)(nb[x] & bm ? 1 : 0);
                    const float wr = (float)(nb[x] & bp ? 1 : 0);
                    const float a = -k * wl, c = -k * wr, b = 1.0f + k * (wl + wr);
                    const float cprev = j > 1 ? cpp[x] : 0.0f;
                    const float dprev = j > 1 ? dpp[x] : 0.0f;
                    const float den = b - a * cprev;
                    cp[x] = c / den;
                    dp[x] = (u[x] - a * dprev) / den;
                }
            }
            {
                const int j = nline - 2;
                float *restrict u = u0 + (size_t)j * step;
                const float *restrict dp = dpall + (size_t)j * (size_t)nx;
                for (int x = 1; x <= n; x++) u[x] = dp[x];
            }
            for (int j = nline - 3; j >= 1; j--) {
                float *restrict u = u0 + (size_t)j * step;
                const float *restrict un = u0 + (size_t)(j + 1) * step;
                const float *restrict cp = cpall + (size_t)j * (size_t)nx;
                const float *restrict dp = dpall + (size_t)j * (size_t)nx;
                for (int x = 1; x <= n; x++) u[x] = dp[x] - cp[x] * un[x];
            }
        }
    }
}

void ss_heal_rd_step_split(ss_heal_rd_system *sys, ss_heal_rd_work *w, double dt, int nsub) {
    reaction_pass(sys, w, dt, nsub);
    const int has_vel = sys->velocity[0] || sys->velocity[1] || sys->velocity[2];
    if (has_vel && w->have_buf) {
        double speed = ss_heal_rd_max_speed(sys);
        int nc = (int)ceil(dt * speed / sys->h_mm / 0.9);
        if (nc < 1) nc = 1;
        double h = dt / nc;
        for (int f = 0; f < sys->nfields; f++) {
            for (int s = 0; s < nc; s++) {
                ss_heal_rd__convect(sys, w, f, sys->u[f], w->buf[f], h);
                float *t = sys->u[f];
                sys->u[f] = w->buf[f];
                w->buf[f] = t;
            }
        }
    }
    const double ih2 = 1.0 / (sys->h_mm * sys->h_mm);
    for (int f = 0; f < sys->nfields; f++) {
        if (!(sys->D[f] > 0)) continue;
        const float kD = (float)(dt * sys->D[f] * ih2);
        const float *mk = sys->mslot[f] >= 0 && w->have_mslot ? w->mslot[sys->mslot[f]] : NULL;
        diffuse_x(sys, w, f, kD, mk);
        diffuse_yz(sys, w, f, kD, mk, 1);
        diffuse_yz(sys, w, f, kD, mk, 2);
        const float lo = sys->lo[f], hi = sys->hi[f];
        float *u = sys->u[f];
        const size_t nc = w->ncell;
#pragma omp parallel for schedule(static) num_threads(thread_count(w))
        for (size_t c = 0; c < nc; c++) u[c] = fminf(fmaxf(u[c], lo), hi);
    }
}
