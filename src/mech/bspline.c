/* Grid <-> particle coupling (seed 001 §5.3): the cubic B-spline kernel, as a
 * tensor product in 3D, with a width tied to the ratio of grid cells to spring
 * nodes, w = (N_c / N_m)^(1/3).
 *
 * The seed writes phi(w x) with the cases in |x| < 1, < 2; read literally a
 * width w > 1 would shrink the support below one cell when the grid is finer
 * than the mechanics, leaving cells that no particle reaches. We read w as the
 * particle spacing in cells: the kernel spans two particle spacings. To keep
 * the cost independent of w (the seed's 160x124x159 grid with 34185 tets
 * has w ~ 7: 30^3 cells per particle), the kernel runs on the sub-lattice of
 * every s-th cell, s = round(w): there the weights are the standard cubic
 * B-spline, a partition of unity that reproduces linear fields exactly.
 * Particle-to-grid values carry the particle's gradient (APIC-style
 * v_p + G_p (x_I - x_p)) so a linear field survives the round trip exactly,
 * and reach the cells between sub-lattice nodes by trilinear interpolation,
 * also exact for linear fields. With s = 1 this is the seed's transfer
 * itself. What it gives up: features finer than s cells are not seen by the
 * mechanics, which cannot resolve them anyway. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/mech.h"

struct ss_mech_transfer {
    int nx, ny, nz, s;
    int mx, my, mz; /* sub-lattice nodes; node m sits at cell s*m (may be past the grid) */
    double dx;
    double *w;      /* weight sums */
    double *val[3]; /* accumulated values (up to 3 components) */
    uint8_t *valid; /* node reached by a particle / sampled */
    float *tmp[3];  /* sub-lattice values for divergence */
};

double ss_mech_bspline(double x) {
    double a = fabs(x);
    if (a < 1.0) return 0.5 * a * a * a - a * a + 2.0 / 3.0;
    if (a < 2.0) {
        double b = 2.0 - a;
        return b * b * b / 6.0; /* = -a^3/6 + a^2 - 2a + 4/3, the seed's second case */
    }
    return 0.0;
}

double ss_mech_kernel_width(size_t active_cells, size_t particles) {
    if (!particles) return 1.0;
    double w = cbrt((double)active_cells / (double)particles);
    return w < 1.0 ? 1.0 : w;
}

ss_mech_transfer *ss_mech_transfer_create(int nx, int ny, int nz, double dx_mm, int stride,
                                          ss_error *err) {
    if (nx < 1 || ny < 1 || nz < 1 || stride < 1 || !(dx_mm > 0)) {
        ss_error_set(err, SS_ERR_INPUT, "transfer: bad grid %dx%dx%d or stride %d", nx, ny, nz,
                     stride);
        return NULL;
    }
    ss_mech_transfer *t = calloc(1, sizeof *t);
    if (!t) goto nomem;
    t->nx = nx;
    t->ny = ny;
    t->nz = nz;
    t->s = stride;
    t->dx = dx_mm;
    t->mx = (nx - 1 + stride - 1) / stride + 1;
    t->my = (ny - 1 + stride - 1) / stride + 1;
    t->mz = (nz - 1 + stride - 1) / stride + 1;
    size_t m = (size_t)t->mx * t->my * t->mz;
    t->w = malloc(m * sizeof(double));
    t->valid = malloc(m);
    if (!t->w || !t->valid) goto nomem;
    for (int c = 0; c < 3; c++) {
        t->val[c] = malloc(m * sizeof(double));
        t->tmp[c] = malloc(m * sizeof(float));
        if (!t->val[c] || !t->tmp[c]) goto nomem;
    }
    return t;
nomem:
    ss_mech_transfer_free(t);
    ss_error_set(err, SS_ERR_NOMEM, "transfer: out of memory");
    return NULL;
}

void ss_mech_transfer_free(ss_mech_transfer *t) {
    if (!t) return;
    free(t->w);
    free(t->valid);
    for (int c = 0; c < 3; c++) {
        free(t->val[c]);
        free(t->tmp[c]);
    }
    free(t);
}

int ss_mech_transfer_stride(const ss_mech_transfer *t) { return t->s; }

/* 1D weights of point coordinate x (mm) on axis with m nodes: first node index
 * and 4 weights (out-of-range nodes get weight 0). */
static int weights1(const ss_mech_transfer *t, double x, int m, double w[4]) {
    double r = (x / t->dx - 0.5) / t->s; /* in sub-lattice units */
    int i0 = (int)floor(r) - 1;
    for (int k = 0; k < 4; k++) {
        int i = i0 + k;
        w[k] = (i >= 0 && i < m) ? ss_mech_bspline(r - i) : 0.0;
    }
    return i0;
}

static inline size_t sub_idx(const ss_mech_transfer *t, int a, int b, int c) {
    return ((size_t)c * t->my + b) * t->mx + a;
}

/* Grid cell of sub-lattice node (a,b,c), -1 if past the grid or masked. */
static long node_cell(const ss_mech_transfer *t, int a, int b, int c, const uint8_t *mask) {
    int x = a * t->s, y = b * t->s, z = c * t->s;
    if (x >= t->nx || y >= t->ny || z >= t->nz) return -1;
    size_t id = ((size_t)z * t->ny + y) * t->nx + x;
    if (mask && !mask[id]) return -1;
    return (long)id;
}

void ss_mech_g2p(const ss_mech_transfer *t, const float *field, const uint8_t *mask,
                 const double *pts, int np, double *out) {
#pragma omp parallel for schedule(static)
    for (int p = 0; p < np; p++) {
        double wx[4], wy[4], wz[4];
        int ax = weights1(t, pts[3 * p], t->mx, wx);
        int ay = weights1(t, pts[3 * p + 1], t->my, wy);
        int az = weights1(t, pts[3 * p + 2], t->mz, wz);
        double sw = 0, sv = 0;
        for (int c = 0; c < 4; c++) {
            if (wz[c] == 0) continue;
            for (int b = 0; b < 4; b++) {
                if (wy[b] == 0) continue;
                for (int a = 0; a < 4; a++) {
                    double w = wx[a] * wy[b] * wz[c];
                    if (w == 0) continue;
                    long id = node_cell(t, ax + a, ay + b, az + c, mask);
                    if (id < 0) continue;
                    sw += w;
                    sv += w * field[id];
                }
            }
        }
        out[p] = sw > 1e-12 ? sv / sw : 0.0;
    }
}

/* Trilinear from sub-lattice arrays (with validity) to the grid cells in mask. */
static void upsample(const ss_mech_transfer *t, int ncomp, const uint8_t *mask, float **out) {
    const int s = t->s;
#pragma omp parallel for schedule(static)
    for (int z = 0; z < t->nz; z++) {
        int c0 = z / s;
        double fz = (double)(z - c0 * s) / s;
        for (int y = 0; y < t->ny; y++) {
            int b0 = y / s;
            double fy = (double)(y - b0 * s) / s;
            for (int x = 0; x < t->nx; x++) {
                size_t id = ((size_t)z * t->ny + y) * t->nx + x;
                if (mask && !mask[id]) {
                    for (int c = 0; c < ncomp; c++) out[c][id] = 0;
                    continue;
                }
                int a0 = x / s;
                double fx = (double)(x - a0 * s) / s;
                double sw = 0, sv[3] = {0, 0, 0};
                for (int k = 0; k < 8; k++) {
                    int a = a0 + (k & 1), b = b0 + ((k >> 1) & 1), c = c0 + (k >> 2);
                    double w =
                        ((k & 1) ? fx : 1 - fx) * ((k & 2) ? fy : 1 - fy) * ((k & 4) ? fz : 1 - fz);
                    if (w == 0 || a >= t->mx || b >= t->my || c >= t->mz) continue;
                    size_t n = sub_idx(t, a, b, c);
                    if (!t->valid[n]) continue;
                    sw += w;
                    for (int q = 0; q < ncomp; q++) sv[q] += w * t->val[q][n];
                }
                for (int q = 0; q < ncomp; q++) out[q][id] = sw > 1e-12 ? (float)(sv[q] / sw) : 0;
            }
        }
    }
}

void ss_mech_p2g(ss_mech_transfer *t, const double *pts, int np, const double *val,
                 const double *grad, int ncomp, const uint8_t *mask, float **out) {
    size_t m = (size_t)t->mx * t->my * t->mz;
    memset(t->w, 0, m * sizeof(double));
    for (int c = 0; c < ncomp; c++) memset(t->val[c], 0, m * sizeof(double));
    /* serial scatter in particle order: cheap (64 nodes per particle) and the
     * sums are the same on any thread count */
    for (int p = 0; p < np; p++) {
        double wx[4], wy[4], wz[4];
        const double *xp = pts + 3 * (size_t)p;
        int ax = weights1(t, xp[0], t->mx, wx);
        int ay = weights1(t, xp[1], t->my, wy);
        int az = weights1(t, xp[2], t->mz, wz);
        for (int c = 0; c < 4; c++) {
            if (wz[c] == 0) continue;
            double zc = ((az + c) * t->s + 0.5) * t->dx - xp[2];
            for (int b = 0; b < 4; b++) {
                if (wy[b] == 0) continue;
                double yc = ((ay + b) * t->s + 0.5) * t->dx - xp[1];
                for (int a = 0; a < 4; a++) {
                    double w = wx[a] * wy[b] * wz[c];
                    if (w == 0) continue;
                    double xc = ((ax + a) * t->s + 0.5) * t->dx - xp[0];
                    size_t n = sub_idx(t, ax + a, ay + b, az + c);
                    t->w[n] += w;
                    for (int q = 0; q < ncomp; q++) {
                        double v = val[(size_t)p * ncomp + q];
                        if (grad) {
                            const double *g = grad + ((size_t)p * ncomp + q) * 3;
                            v += g[0] * xc + g[1] * yc + g[2] * zc;
                        }
                        t->val[q][n] += w * v;
                    }
                }
            }
        }
    }
    for (size_t n = 0; n < m; n++) {
        t->valid[n] = t->w[n] > 1e-6;
        for (int q = 0; q < ncomp; q++) t->val[q][n] = t->valid[n] ? t->val[q][n] / t->w[n] : 0;
    }
    upsample(t, ncomp, mask, out);
}

void ss_mech_divergence(ss_mech_transfer *t, float *const u[3], const uint8_t *mask, float *out) {
    const double h = t->s * t->dx;
    size_t m = (size_t)t->mx * t->my * t->mz;
    for (size_t n = 0; n < m; n++) t->valid[n] = 0;
    for (int c = 0; c < t->mz; c++)
        for (int b = 0; b < t->my; b++)
            for (int a = 0; a < t->mx; a++) {
                long id = node_cell(t, a, b, c, mask);
                size_t n = sub_idx(t, a, b, c);
                if (id < 0) continue;
                t->valid[n] = 1;
                for (int d = 0; d < 3; d++) t->tmp[d][n] = u[d][id];
            }
    for (int c = 0; c < t->mz; c++)
        for (int b = 0; b < t->my; b++)
            for (int a = 0; a < t->mx; a++) {
                size_t n = sub_idx(t, a, b, c);
                if (!t->valid[n]) {
                    t->val[0][n] = 0;
                    continue;
                }
                int ijk[3] = {a, b, c}, dim[3] = {t->mx, t->my, t->mz};
                double div = 0;
                for (int d = 0; d < 3; d++) {
                    int lo[3] = {a, b, c}, hi[3] = {a, b, c};
                    lo[d] = ijk[d] - 1;
                    hi[d] = ijk[d] + 1;
                    int okl = lo[d] >= 0 && t->valid[sub_idx(t, lo[0], lo[1], lo[2])];
                    int okh = hi[d] < dim[d] && t->valid[sub_idx(t, hi[0], hi[1], hi[2])];
                    double vl = okl ? t->tmp[d][sub_idx(t, lo[0], lo[1], lo[2])] : t->tmp[d][n];
                    double vh = okh ? t->tmp[d][sub_idx(t, hi[0], hi[1], hi[2])] : t->tmp[d][n];
                    int span = okl + okh;
                    if (span) div += (vh - vl) / (span * h);
                }
                t->val[0][n] = div;
            }
    float *o[1] = {out};
    upsample(t, 1, mask, o);
}
