/* Distances in texture space: point to segment (seed 000 Alg. 3.3), pixel to
 * polygon outline (the inner loop of Alg. 3.4, brute force and fast), and the
 * exact Euclidean distance transform of Felzenszwalb & Huttenlocher (2012).
 *
 * Alg. 3.3 check: with v = l2 - l1 and w = l1 - p, dot(w, v) > 0 means
 * dot(p - l1, l2 - l1) < 0, i.e. p projects before l1, so the distance to l1
 * is right; the mirrored test handles the l2 end; otherwise the distance to
 * the line. The seed's geometry is correct; we only add the degenerate
 * l1 == l2 case (the normalisation in step 12 would divide by zero).
 *
 * Fast outline distance (exact within max_dist, cost independent of the
 * number of edges): every edge is clipped to the image grown by a pad of
 * max_dist + 2 px and rasterised conservatively (every cell it touches is
 * marked and recorded as (16x16 bin, edge) pairs). An exact EDT of the marks
 * gives, per pixel, D = distance to the nearest marked cell centre; since a
 * marked cell holds a point of an edge within h = sqrt(2)/2 of its centre,
 * the true distance d satisfies D - h <= d <= D + h, and the cell holding the
 * true nearest point has its centre within D + 2h of the pixel. So for each
 * 16x16 tile the candidate edges are those recorded in bins within
 * max(D) + sqrt(2) + 1 of the tile; the exact Alg. 3.3 distance to those
 * candidates gives bit for bit the brute-force minimum. Pixels with
 * D - h > max_dist get the lower bound min(D - h, pad), which is > max_dist. */
#include "skinsim/geom.h"

#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

double ss_segment_distance(ss_vec2 l1, ss_vec2 l2, ss_vec2 p) {
    /* 1-5: before l1 */
    double vx = l2.x - l1.x, vy = l2.y - l1.y;
    double wx = l1.x - p.x, wy = l1.y - p.y;
    if (wx * vx + wy * vy > 0 || (vx == 0 && vy == 0)) return sqrt(wx * wx + wy * wy);
    /* 6-10: beyond l2 */
    vx = -vx;
    vy = -vy;
    wx = l2.x - p.x;
    wy = l2.y - p.y;
    if (wx * vx + wy * vy > 0) return sqrt(wx * wx + wy * wy);
    /* 11-14: distance to the line through l1 and l2 */
    double nx = vy, ny = -vx, len = sqrt(nx * nx + ny * ny);
    nx /= len;
    ny /= len;
    return fabs(nx * (p.x - l1.x) + ny * (p.y - l1.y));
}

/* ---- exact EDT --------------------------------------------------------------- */

#define EDT_INF 1e20

/* 1D lower envelope of parabolas (Felzenszwalb & Huttenlocher). f, d: n
 * values; v: n ints; z: n+1 doubles. */
static void dt1d(const double *f, int n, double *d, int *v, double *z) {
    int k = 0;
    v[0] = 0;
    z[0] = -HUGE_VAL;
    z[1] = HUGE_VAL;
    for (int q = 1; q < n; q++) {
        double s;
        for (;;) {
            const int r = v[k];
            s = ((f[q] + (double)q * q) - (f[r] + (double)r * r)) / (2.0 * (q - r));
            if (s <= z[k] && k > 0) {
                k--;
                continue;
            }
            break;
        }
        if (s <= z[k]) { /* k == 0 and the new parabola wins everywhere */
            v[0] = q;
            z[0] = -HUGE_VAL;
            z[1] = HUGE_VAL;
            continue;
        }
        k++;
        v[k] = q;
        z[k] = s;
        z[k + 1] = HUGE_VAL;
    }
    k = 0;
    for (int q = 0; q < n; q++) {
        while (z[k + 1] < q) k++;
        const double dq = q - v[k];
        d[q] = dq * dq + f[v[k]];
    }
}

/* Exact EDT of a W x H byte mask (non-zero = site) into out (W*H floats, in
 * pixels; +INFINITY when there is no site). Column pass as two linear scans of
 * integer distances, row pass with dt1d. Parallel over column blocks / rows;
 * every value is computed the same way for any thread count. */
static ss_status edt_mask(const unsigned char *m, int W, int H, float *out, ss_error *err) {
    int32_t *g = malloc(sizeof *g * (size_t)W * (size_t)H);
    if (!g)
        return ss_error_set(err, SS_ERR_NOMEM, "distance transform: out of memory (%dx%d)", W, H);
    const int32_t NONE = INT32_MAX / 4;
    const int CB = 64; /* columns per block */
    const int nblocks = (W + CB - 1) / CB;
#pragma omp parallel for schedule(dynamic, 1)
    for (int b = 0; b < nblocks; b++) {
        const int x0 = b * CB, x1 = x0 + CB < W ? x0 + CB : W;
        for (int x = x0; x < x1; x++) g[x] = m[x] ? 0 : NONE;
        for (int y = 1; y < H; y++) {
            const size_t r = (size_t)y * W, rp = r - (size_t)W;
            for (int x = x0; x < x1; x++)
                g[r + x] = m[r + x] ? 0 : (g[rp + x] == NONE ? NONE : g[rp + x] + 1);
        }
        for (int y = H - 2; y >= 0; y--) {
            const size_t r = (size_t)y * W, rn = r + (size_t)W;
            for (int x = x0; x < x1; x++)
                if (g[rn + x] != NONE && g[rn + x] + 1 < g[r + x]) g[r + x] = g[rn + x] + 1;
        }
    }
    int fail = 0;
#pragma omp parallel
    {
        double *f = malloc(sizeof *f * (size_t)W), *d = malloc(sizeof *d * (size_t)W);
        double *z = malloc(sizeof *z * (size_t)(W + 1));
        int *v = malloc(sizeof *v * (size_t)W);
        if (!f || !d || !z || !v) {
#pragma omp atomic write
            fail = 1;
        }
#pragma omp for schedule(static)
        for (int y = 0; y < H; y++) {
            if (!f || !d || !z || !v) continue;
            const size_t r = (size_t)y * W;
            for (int x = 0; x < W; x++)
                f[x] = g[r + x] == NONE ? EDT_INF : (double)g[r + x] * (double)g[r + x];
            dt1d(f, W, d, v, z);
            for (int x = 0; x < W; x++)
                out[r + x] = d[x] >= EDT_INF * 0.5 ? INFINITY : (float)sqrt(d[x]);
        }
        free(f);
        free(d);
        free(z);
        free(v);
    }
    free(g);
    if (fail) return ss_error_set(err, SS_ERR_NOMEM, "distance transform: out of memory");
    return SS_OK;
}

ss_status ss_distance_transform(const ss_image *src, ss_image *dist, ss_error *err) {
    if (!src || !dist || !src->data || !dist->data)
        return ss_error_set(err, SS_ERR_INPUT, "distance transform: missing image");
    if (dist->width != src->width || dist->height != src->height || dist->channels != 1)
        return ss_error_set(err, SS_ERR_INPUT,
                            "distance transform: output must be 1 channel %dx%d, got %d channel(s) "
                            "%dx%d",
                            src->width, src->height, dist->channels, dist->width, dist->height);
    const int W = src->width, H = src->height, C = src->channels;
    unsigned char *m = malloc((size_t)W * (size_t)H);
    if (!m) return ss_error_set(err, SS_ERR_NOMEM, "distance transform: out of memory");
    for (size_t i = 0; i < (size_t)W * H; i++) m[i] = src->data[i * (size_t)C] > 0.5f;
    ss_status st = edt_mask(m, W, H, dist->data, err);
    free(m);
    return st;
}

/* ---- outline distance --------------------------------------------------------- */

typedef struct seg {
    ss_vec2 a, b;
} seg;

static ss_status collect_edges(const ss_polygon *polys, int npolys, seg **out, int *nout,
                               ss_error *err) {
    *out = NULL;
    *nout = 0;
    if (npolys < 0 || (npolys > 0 && !polys))
        return ss_error_set(err, SS_ERR_INPUT, "outline distance: bad polygon list (%d)", npolys);
    long total = 0;
    for (int i = 0; i < npolys; i++) {
        if (polys[i].count < 0 || (polys[i].count > 0 && !polys[i].pts))
            return ss_error_set(err, SS_ERR_INPUT, "outline distance: polygon %d is malformed", i);
        for (int j = 0; j < polys[i].count; j++)
            if (!isfinite(polys[i].pts[j].x) || !isfinite(polys[i].pts[j].y))
                return ss_error_set(err, SS_ERR_INPUT,
                                    "outline distance: polygon %d vertex %d is not finite", i, j);
        total += polys[i].count;
    }
    if (total > INT32_MAX / 2)
        return ss_error_set(err, SS_ERR_INPUT, "outline distance: too many edges (%ld)", total);
    seg *e = malloc(sizeof *e * (size_t)(total > 0 ? total : 1));
    if (!e) return ss_error_set(err, SS_ERR_NOMEM, "outline distance: out of memory");
    int k = 0;
    for (int i = 0; i < npolys; i++)
        for (int j = 0; j < polys[i].count; j++) {
            e[k].a = polys[i].pts[j];
            e[k].b = polys[i].pts[(j + 1) % polys[i].count];
            k++;
        }
    *out = e;
    *nout = k;
    return SS_OK;
}

static float min_edge_distance(const seg *e, int n, ss_vec2 p) {
    double best = HUGE_VAL;
    for (int i = 0; i < n; i++) best = fmin(best, ss_segment_distance(e[i].a, e[i].b, p));
    return (float)best;
}

void ss_outline_distance_bruteforce(const ss_polygon *polys, int npolys, ss_image *dist) {
    if (!dist || !dist->data) return;
    seg *e;
    int ne;
    if (collect_edges(polys, npolys, &e, &ne, NULL)) return;
    const int W = dist->width, H = dist->height, C = dist->channels;
#pragma omp parallel for schedule(dynamic, 4)
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const ss_vec2 p = {x + 0.5, y + 0.5};
            dist->data[((size_t)y * W + x) * C] = ne ? min_edge_distance(e, ne, p) : INFINITY;
        }
    free(e);
}

typedef struct pair {
    int32_t bin, edge;
} pair;

typedef struct pairvec {
    pair *v;
    size_t n, cap;
    int fail;
} pairvec;

static void push_pair(pairvec *pv, int32_t bin, int32_t edge) {
    if (pv->fail) return;
    if (pv->n == pv->cap) {
        size_t nc = pv->cap ? pv->cap * 2 : 4096;
        pair *nv = realloc(pv->v, sizeof *nv * nc);
        if (!nv) {
            pv->fail = 1;
            return;
        }
        pv->v = nv;
        pv->cap = nc;
    }
    pv->v[pv->n].bin = bin;
    pv->v[pv->n].edge = edge;
    pv->n++;
}

/* Liang-Barsky clip of a-b to [lo, hi]^2 box; returns 0 when nothing is left. */
static int clip_segment(ss_vec2 *a, ss_vec2 *b, double x0, double y0, double x1, double y1) {
    double t0 = 0, t1 = 1, dx = b->x - a->x, dy = b->y - a->y;
    const double p[4] = {-dx, dx, -dy, dy};
    const double q[4] = {a->x - x0, x1 - a->x, a->y - y0, y1 - a->y};
    for (int i = 0; i < 4; i++) {
        if (p[i] == 0) {
            if (q[i] < 0) return 0;
        } else {
            double t = q[i] / p[i];
            if (p[i] < 0) {
                if (t > t1) return 0;
                if (t > t0) t0 = t;
            } else {
                if (t < t0) return 0;
                if (t < t1) t1 = t;
            }
        }
    }
    ss_vec2 na = {a->x + t0 * dx, a->y + t0 * dy}, nb = {a->x + t1 * dx, a->y + t1 * dy};
    *a = na;
    *b = nb;
    return 1;
}

#define TILE 16

ss_status ss_outline_distance(const ss_polygon *polys, int npolys, double max_dist, ss_image *dist,
                              ss_error *err) {
    if (!dist || !dist->data || dist->channels != 1)
        return ss_error_set(err, SS_ERR_INPUT,
                            "outline distance: output must be a 1-channel image");
    if (!(max_dist >= 0))
        return ss_error_set(err, SS_ERR_INPUT, "outline distance: max_dist must be >= 0, got %g",
                            max_dist);
    seg *e;
    int ne;
    ss_status st = collect_edges(polys, npolys, &e, &ne, err);
    if (st) return st;
    const int W = dist->width, H = dist->height;
    if (ne == 0) {
        for (size_t i = 0; i < (size_t)W * H; i++) dist->data[i] = INFINITY;
        free(e);
        return SS_OK;
    }
    /* Beyond the image diagonal the pad would only grow memory: cap it and fix
     * up any pixel left beyond the cap by brute force (outline far away). */
    const double diag = sqrt((double)W * W + (double)H * H) + 2.0;
    const int capped = max_dist > diag;
    const double md = capped ? diag : max_dist;
    const int pad = (int)ceil(md) + 2;
    const int PW = W + 2 * pad, PH = H + 2 * pad;
    const int BW = (PW + TILE - 1) / TILE, BH = (PH + TILE - 1) / TILE;
    const double h = sqrt(0.5) + 1e-6;

    unsigned char *mark = calloc((size_t)PW * PH, 1);
    float *D = malloc(sizeof *D * (size_t)PW * PH);
    size_t *off = calloc((size_t)BW * BH + 1, sizeof *off);
    pairvec pv = {0};
    int32_t *bin_edges = NULL;
    if (!mark || !D || !off) {
        st = ss_error_set(err, SS_ERR_NOMEM, "outline distance: out of memory (%dx%d)", PW, PH);
        goto done;
    }
    /* Conservative rasterisation of each clipped edge, in padded cell units. */
    for (int i = 0; i < ne; i++) {
        ss_vec2 a = {e[i].a.x + pad, e[i].a.y + pad}, b = {e[i].b.x + pad, e[i].b.y + pad};
        if (!clip_segment(&a, &b, 0, 0, PW, PH)) continue;
        if (a.y > b.y) {
            ss_vec2 t = a;
            a = b;
            b = t;
        }
        int cy0 = (int)floor(a.y - 1e-6), cy1 = (int)floor(b.y + 1e-6);
        if (cy0 < 0) cy0 = 0;
        if (cy1 > PH - 1) cy1 = PH - 1;
        int32_t lastbin = -1;
        for (int cy = cy0; cy <= cy1; cy++) {
            double ylo = fmax(a.y, cy), yhi = fmin(b.y, cy + 1.0), xa, xb;
            if (b.y == a.y) {
                xa = fmin(a.x, b.x);
                xb = fmax(a.x, b.x);
            } else {
                if (ylo > yhi) ylo = yhi = fmin(fmax(ylo, a.y), b.y);
                double t0 = (ylo - a.y) / (b.y - a.y), t1 = (yhi - a.y) / (b.y - a.y);
                double x0 = a.x + t0 * (b.x - a.x), x1 = a.x + t1 * (b.x - a.x);
                xa = fmin(x0, x1);
                xb = fmax(x0, x1);
            }
            int cx0 = (int)floor(xa - 1e-6), cx1 = (int)floor(xb + 1e-6);
            if (cx0 < 0) cx0 = 0;
            if (cx1 > PW - 1) cx1 = PW - 1;
            for (int cx = cx0; cx <= cx1; cx++) {
                mark[(size_t)cy * PW + cx] = 1;
                int32_t bin = (cy / TILE) * BW + cx / TILE;
                if (bin != lastbin) push_pair(&pv, bin, i);
                lastbin = bin;
            }
        }
    }
    if (pv.fail) {
        st = ss_error_set(err, SS_ERR_NOMEM, "outline distance: out of memory");
        goto done;
    }
    st = edt_mask(mark, PW, PH, D, err);
    if (st) goto done;
    /* Bin -> edges (CSR). */
    bin_edges = malloc(sizeof *bin_edges * (pv.n ? pv.n : 1));
    if (!bin_edges) {
        st = ss_error_set(err, SS_ERR_NOMEM, "outline distance: out of memory");
        goto done;
    }
    for (size_t i = 0; i < pv.n; i++) off[pv.v[i].bin + 1]++;
    for (size_t b = 0; b < (size_t)BW * BH; b++) off[b + 1] += off[b];
    {
        size_t *fillp = malloc(sizeof *fillp * ((size_t)BW * BH + 1));
        if (!fillp) {
            st = ss_error_set(err, SS_ERR_NOMEM, "outline distance: out of memory");
            goto done;
        }
        memcpy(fillp, off, sizeof *fillp * ((size_t)BW * BH + 1));
        for (size_t i = 0; i < pv.n; i++) bin_edges[fillp[pv.v[i].bin]++] = pv.v[i].edge;
        free(fillp);
    }
    const int TW = (W + TILE - 1) / TILE, TH = (H + TILE - 1) / TILE;
    int fail = 0;
#pragma omp parallel
    {
        int32_t *stamp = malloc(sizeof *stamp * (size_t)ne);
        seg *cand = malloc(sizeof *cand * (size_t)ne);
        if (!stamp || !cand) {
#pragma omp atomic write
            fail = 1;
        } else {
            for (int i = 0; i < ne; i++) stamp[i] = -1;
        }
#pragma omp for schedule(dynamic, 1)
        for (int t = 0; t < TW * TH; t++) {
            if (!stamp || !cand) continue;
            const int tx0 = (t % TW) * TILE, ty0 = (t / TW) * TILE;
            const int tx1 = tx0 + TILE < W ? tx0 + TILE : W, ty1 = ty0 + TILE < H ? ty0 + TILE : H;
            double Dmax = -1;
            for (int y = ty0; y < ty1; y++)
                for (int x = tx0; x < tx1; x++) {
                    const double Dp = D[(size_t)(y + pad) * PW + (x + pad)];
                    if (Dp - h <= md) Dmax = fmax(Dmax, Dp);
                    dist->data[(size_t)y * W + x] = (float)fmin(Dp - h, (double)pad);
                }
            if (Dmax < 0) continue; /* whole tile beyond max_dist */
            const double R = Dmax + 2 * h + 1.0;
            int bx0 = (int)floor((tx0 + pad + 0.5 - R) / TILE),
                bx1 = (int)floor((tx1 - 1 + pad + 0.5 + R) / TILE);
            int by0 = (int)floor((ty0 + pad + 0.5 - R) / TILE),
                by1 = (int)floor((ty1 - 1 + pad + 0.5 + R) / TILE);
            if (bx0 < 0) bx0 = 0;
            if (by0 < 0) by0 = 0;
            if (bx1 > BW - 1) bx1 = BW - 1;
            if (by1 > BH - 1) by1 = BH - 1;
            int nc = 0;
            for (int by = by0; by <= by1; by++)
                for (int bx = bx0; bx <= bx1; bx++) {
                    const size_t b = (size_t)by * BW + bx;
                    for (size_t k = off[b]; k < off[b + 1]; k++) {
                        const int32_t ei = bin_edges[k];
                        if (stamp[ei] != t) {
                            stamp[ei] = t;
                            cand[nc++] = e[ei];
                        }
                    }
                }
            for (int y = ty0; y < ty1; y++)
                for (int x = tx0; x < tx1; x++) {
                    const double Dp = D[(size_t)(y + pad) * PW + (x + pad)];
                    if (Dp - h > md) continue;
                    const ss_vec2 p = {x + 0.5, y + 0.5};
                    dist->data[(size_t)y * W + x] = min_edge_distance(cand, nc, p);
                }
        }
        free(stamp);
        free(cand);
    }
    if (fail) {
        st = ss_error_set(err, SS_ERR_NOMEM, "outline distance: out of memory");
        goto done;
    }
    if (capped) { /* exact everywhere was asked for: settle the far pixels */
#pragma omp parallel for schedule(dynamic, 4)
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                float *v = &dist->data[(size_t)y * W + x];
                if (*v > md) {
                    const ss_vec2 p = {x + 0.5, y + 0.5};
                    *v = min_edge_distance(e, ne, p);
                }
            }
    }
done:
    free(mark);
    free(D);
    free(off);
    free(pv.v);
    free(bin_edges);
    free(e);
    return st;
}
