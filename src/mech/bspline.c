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
    double *w;        /* weight sums */
    double *val[3];   /* accumulated values (up to 3 components) */
    uint8_t *valid;   /* node reached by a particle / sampled */
    float *tmp[3];    /* sub-lattice values for divergence */
    float *stA, *stB; /* separable upsampling stages (weight + 3 components) */
    int *xa;          /* per grid x: the sub-lattice node a0 = x / s at or below it */
    float *xw[2];     /* per grid x: the weights of a0 and a0 + 1 (0: not used) */
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
    t->stA = malloc((size_t)t->mx * t->my * nz * 4 * sizeof(float));
    t->stB = malloc((size_t)t->mx * ny * nz * 4 * sizeof(float));
    if (!t->stA || !t->stB) goto nomem;
    t->xa = malloc((size_t)nx * sizeof(int));
    t->xw[0] = malloc((size_t)nx * sizeof(float));
    t->xw[1] = malloc((size_t)nx * sizeof(float));
    if (!t->xa || !t->xw[0] || !t->xw[1]) goto nomem;
    for (int x = 0; x < nx; x++) { /* the x pass's weights, tabulated once */
        int a0 = x / stride;
        float fx = (float)(x - a0 * stride) / (float)stride;
        t->xa[x] = a0;
        t->xw[0][x] = 1 - fx;
        t->xw[1][x] = a0 + 1 < t->mx ? fx : 0;
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
    free(t->stA);
    free(t->stB);
    free(t->xa);
    free(t->xw[0]);
    free(t->xw[1]);
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

/* The value at one sub-lattice node, or 0 with *ok = 0 when the node has none. */
typedef double (*node_value_fn)(const ss_mech_transfer *t, const void *ctx, int a, int b, int c,
                                int *ok);

/* G2P for every point: the B-spline-weighted mean over the nodes that have a
 * value (the weights renormalised over them). */
static void gather(const ss_mech_transfer *t, node_value_fn value, const void *ctx,
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
                    int ok;
                    double v = value(t, ctx, ax + a, ay + b, az + c, &ok);
                    if (!ok) continue;
                    sw += w;
                    sv += w * v;
                }
            }
        }
        out[p] = sw > 1e-12 ? sv / sw : 0.0;
    }
}

typedef struct grid_src {
    const float *field;
    const uint8_t *mask;
} grid_src;

static double grid_value(const ss_mech_transfer *t, const void *ctx, int a, int b, int c, int *ok) {
    const grid_src *g = ctx;
    long id = node_cell(t, a, b, c, g->mask);
    *ok = id >= 0;
    return id >= 0 ? g->field[id] : 0.0;
}

void ss_mech_g2p(const ss_mech_transfer *t, const float *field, const uint8_t *mask,
                 const double *pts, int np, double *out) {
    grid_src g = {field, mask};
    gather(t, grid_value, &g, pts, np, out);
}

/* Trilinear from sub-lattice arrays vals[q] (with validity) to the grid cells
 * in mask, renormalised over the valid corners: sum w v / sum w with
 * w the trilinear weight of a valid corner. Done separably (z, then y, then
 * x) on (w v, w), which gives the same sums at a fraction of the cost. */
static void upsample_from(const ss_mech_transfer *t, double *const *vals, const uint8_t *valid,
                          int ncomp, const uint8_t *mask, float **out) {
    const int s = t->s, mx = t->mx, my = t->my, nx = t->nx, ny = t->ny, nz = t->nz;
    const int K = 4; /* weight + up to 3 components */
    float *A = t->stA, *B = t->stB;
#pragma omp parallel for schedule(static)
    for (int z = 0; z < nz; z++) {
        int c0 = z / s;
        float fz = (float)(z - c0 * s) / (float)s;
        for (int b = 0; b < my; b++)
            for (int a = 0; a < mx; a++) {
                float *o = A + (((size_t)z * my + b) * mx + a) * K;
                o[0] = o[1] = o[2] = o[3] = 0;
                for (int k = 0; k < 2; k++) {
                    int c = c0 + k;
                    float w = k ? fz : 1 - fz;
                    if (w == 0 || c >= t->mz) continue;
                    size_t n = sub_idx(t, a, b, c);
                    if (!valid[n]) continue;
                    o[0] += w;
                    for (int q = 0; q < ncomp; q++) o[1 + q] += w * (float)vals[q][n];
                }
            }
    }
#pragma omp parallel for schedule(static)
    for (int z = 0; z < nz; z++)
        for (int y = 0; y < ny; y++) {
            int b0 = y / s;
            float fy = (float)(y - b0 * s) / (float)s;
            for (int a = 0; a < mx; a++) {
                float *o = B + (((size_t)z * ny + y) * mx + a) * K;
                o[0] = o[1] = o[2] = o[3] = 0;
                for (int k = 0; k < 2; k++) {
                    int b = b0 + k;
                    float w = k ? fy : 1 - fy;
                    if (w == 0 || b >= my) continue;
                    const float *i = A + (((size_t)z * my + b) * mx + a) * K;
                    for (int q = 0; q < K; q++) o[q] += w * i[q];
                }
            }
        }
#pragma omp parallel for schedule(static)
    for (int z = 0; z < nz; z++)
        for (int y = 0; y < ny; y++) {
            const float *row = B + ((size_t)z * ny + y) * mx * K;
            for (int x = 0; x < nx; x++) {
                size_t id = ((size_t)z * ny + y) * nx + x;
                if (mask && !mask[id]) {
                    for (int q = 0; q < ncomp; q++) out[q][id] = 0;
                    continue;
                }
                /* the weights tabulated at creation (the same floats as
                 * (x - s a0) / s and its complement, so the same sums) */
                const int a0 = t->xa[x];
                float acc[4] = {0, 0, 0, 0};
                for (int k = 0; k < 2; k++) {
                    const float w = t->xw[k][x];
                    if (w == 0) continue;
                    for (int q = 0; q < K; q++) acc[q] += w * row[(size_t)(a0 + k) * K + q];
                }
                for (int q = 0; q < ncomp; q++)
                    out[q][id] = acc[0] > 1e-6f ? acc[1 + q] / acc[0] : 0;
            }
        }
}

static void upsample(const ss_mech_transfer *t, int ncomp, const uint8_t *mask, float **out) {
    upsample_from(t, t->val, t->valid, ncomp, mask, out);
}

void ss_mech_p2g_sub(ss_mech_transfer *t, const double *pts, int np, const double *val,
                     const double *grad, int ncomp) {
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
}

void ss_mech_p2g(ss_mech_transfer *t, const double *pts, int np, const double *val,
                 const double *grad, int ncomp, const uint8_t *mask, float **out) {
    ss_mech_p2g_sub(t, pts, np, val, grad, ncomp);
    upsample(t, ncomp, mask, out);
}

size_t ss_mech_sub_count(const ss_mech_transfer *t) { return (size_t)t->mx * t->my * t->mz; }

void ss_mech_sub_get(const ss_mech_transfer *t, int ncomp, double **vals, uint8_t *valid) {
    size_t m = ss_mech_sub_count(t);
    for (int q = 0; q < ncomp; q++) memcpy(vals[q], t->val[q], m * sizeof(double));
    memcpy(valid, t->valid, m);
}

void ss_mech_sub_upsample(const ss_mech_transfer *t, double *const *vals, const uint8_t *valid,
                          int ncomp, const uint8_t *mask, float **out) {
    upsample_from(t, vals, valid, ncomp, mask, out);
}

/* Central-difference divergence on the sub-lattice of the 3-component
 * sub-lattice field u (validity uv); one-sided next to invalid nodes. */
void ss_mech_sub_divergence(const ss_mech_transfer *t, double *const *u, const uint8_t *uv,
                            double *div) {
    const double h = t->s * t->dx;
    const int dim[3] = {t->mx, t->my, t->mz};
#pragma omp parallel for schedule(static)
    for (int c = 0; c < t->mz; c++)
        for (int b = 0; b < t->my; b++)
            for (int a = 0; a < t->mx; a++) {
                size_t n = sub_idx(t, a, b, c);
                double dv = 0;
                if (uv[n]) {
                    int ijk[3] = {a, b, c};
                    for (int d = 0; d < 3; d++) {
                        int lo[3] = {a, b, c}, hi[3] = {a, b, c};
                        lo[d] = ijk[d] - 1;
                        hi[d] = ijk[d] + 1;
                        size_t nl = lo[d] >= 0 ? sub_idx(t, lo[0], lo[1], lo[2]) : 0;
                        size_t nh = hi[d] < dim[d] ? sub_idx(t, hi[0], hi[1], hi[2]) : 0;
                        int okl = lo[d] >= 0 && uv[nl], okh = hi[d] < dim[d] && uv[nh];
                        double vl = okl ? u[d][nl] : u[d][n], vh = okh ? u[d][nh] : u[d][n];
                        if (okl + okh) dv += (vh - vl) / ((okl + okh) * h);
                    }
                }
                div[n] = dv;
            }
}

typedef struct sub_src {
    const double *sub;
    const uint8_t *valid;
} sub_src;

static double sub_value(const ss_mech_transfer *t, const void *ctx, int a, int b, int c, int *ok) {
    const sub_src *q = ctx;
    size_t n = sub_idx(t, a, b, c);
    *ok = q->valid[n] != 0;
    return *ok ? q->sub[n] : 0.0;
}

void ss_mech_g2p_sub(const ss_mech_transfer *t, const double *sub, const uint8_t *valid,
                     const double *pts, int np, double *out) {
    sub_src q = {sub, valid};
    gather(t, sub_value, &q, pts, np, out);
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
