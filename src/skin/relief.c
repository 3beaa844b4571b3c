/* The skin's microrelief network (docs/skin.md): primary lines, grooves
 * about 20-100 um deep that enclose polygonal plateaus of roughly 0.2-1 mm,
 * with shallower secondary lines inside them, a connected pattern (the
 * "sulci cutis" of dermatology texts). The seed's Bezier wrinkles (§5.3.7)
 * stay as the deep furrows on top of it.
 *
 * Design: the lines are the edges of a Voronoi diagram of jittered lattice
 * points (one per cell of a periodic lattice, so the network tiles and is
 * connected by construction: Voronoi edges form a planar graph without
 * loose ends). The distance to the nearest edge is the distance to the
 * bisector between the nearest point and its rivals, exact for a Voronoi
 * diagram. Where a direction is given (the wrinkle vector field), the metric
 * is stretched along it by `relief_stretch`, so cells are elongated and the
 * long edges - the primary lines - run along the field, as skin lines
 * follow the tension lines of the body. Each edge has its own depth (a
 * symmetric hash of its two cells). The groove profile is (1 - d/w)^2.
 *
 * Antialiasing: a texel is the mean of n x n sub-samples over its square
 * (spacing texel / n <= 12.5 um, n <= 4: 2 x 2 at 2048 on 5 cm, 4 x 4 at
 * 1024 and below), so thin diagonal lines are area-averaged instead of
 * point-sampled (dotted chains), and a patch's mean height per mm converges
 * with --size, junctions included (a 1D filter across the nearest line
 * alone does not: lines overlap at the Voronoi vertices). The points are
 * gathered once per texel; only texels whose centre is within w + the
 * sub-samples' reach of a line are sub-sampled (the rest are plateau, 0).
 * Below 0.75 sub-sample spacing a line is widened and its depth lowered in
 * proportion (the cross-section is kept). The field's direction is the
 * texel centre's for all its sub-samples (it turns over millimetres). Gave
 * up: the network is statistically, not anatomically, oriented (no
 * per-region pattern). */
#include "skin_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* the sub-sampling of a texel (skin_relief_eval) */
enum { RELIEF_SUB_MAX = 4 };
#define RELIEF_SUB_MM 0.0125

void skin_relief_free(skin_relief *r) {
    if (!r) return;
    free(r->p1);
    free(r->p2);
    free(r->dir);
    memset(r, 0, sizeof *r);
}

static float *make_points(int m, uint64_t seed, uint64_t stream) {
    float *p = malloc((size_t)m * m * 3 * sizeof(float));
    if (!p) return NULL;
#pragma omp parallel for schedule(static)
    for (int j = 0; j < m; j++)
        for (int i = 0; i < m; i++) {
            uint32_t r[4];
            ss_rng4(seed, stream, (uint64_t)j * m + i, r);
            float *q = p + ((size_t)j * m + i) * 3;
            q[0] = (i + 0.1f + 0.8f * ((r[0] >> 8) * 0x1p-24f)) / m;
            q[1] = (j + 0.1f + 0.8f * ((r[1] >> 8) * 0x1p-24f)) / m;
            q[2] = (r[2] >> 8) * 0x1p-24f; /* per-point share of its edges' depth */
        }
    return p;
}

ss_status skin_relief_init(skin_relief *r, const ss_skin_settings *s, const ss_image *vf,
                           ss_error *err) {
    memset(r, 0, sizeof *r);
    const ss_skin_dist *d = &s->dist;
    r->world_mm = s->world_size_cm * 10.0;
    r->texel_mm = r->world_mm / s->size;
    r->stretch = d->relief_stretch < 1.0 ? 1.0 : d->relief_stretch;
    if (!(d->relief_depth > 0.0 || d->relief_depth2 > 0.0)) return SS_OK; /* no network */
    long m1 = lround(r->world_mm / d->relief_cell), m2 = lround(r->world_mm / d->relief_cell2);
    if (m1 < 3) m1 = 3;
    if (m2 < 3) m2 = 3;
    if (m1 > 4096 || m2 > 4096)
        return ss_error_set(err, SS_ERR_INPUT,
                            "microrelief: cells of %g / %g mm on %g mm need more than 4096 per "
                            "side",
                            d->relief_cell, d->relief_cell2, r->world_mm);
    r->m1 = (int)m1;
    r->m2 = (int)m2;
    r->p1 = make_points(r->m1, s->seed, 240);
    r->p2 = make_points(r->m2, s->seed, 241);
    long nd = lround(r->world_mm / 0.4);
    r->nd = (int)(nd < 8 ? 8 : nd > 1024 ? 1024 : nd);
    r->dir = malloc((size_t)r->nd * r->nd * 2 * sizeof(float));
    if (r->dir)
#pragma omp parallel for schedule(static)
        for (int j = 0; j < r->nd; j++)
            for (int i = 0; i < r->nd; i++) {
                double tx, ty;
                skin_field_direction(vf, (double)i / r->nd, (double)j / r->nd, &tx, &ty);
                float *q = r->dir + ((size_t)j * r->nd + i) * 2;
                q[0] = (float)(tx * tx - ty * ty); /* cos 2a */
                q[1] = (float)(2.0 * tx * ty);     /* sin 2a */
            }
    if (!r->p1 || !r->p2 || !r->dir) {
        skin_relief_free(r);
        return ss_error_set(err, SS_ERR_NOMEM, "microrelief: out of memory");
    }
    /* sub-samples per texel side: spaced at most RELIEF_SUB_MM (about
     * half the secondary line's half-width), up to RELIEF_SUB_MAX */
    long ns = lround(ceil(r->texel_mm / RELIEF_SUB_MM - 1e-9));
    r->ns = (int)(ns < 1 ? 1 : ns > RELIEF_SUB_MAX ? RELIEF_SUB_MAX : ns);
    /* half-widths: primary lines about 80 um wide, secondary 40 um; a line
     * narrower than 0.75 sub-sample spacing is widened */
    const double wmin = 0.75 * r->texel_mm / r->ns;
    r->w1 = 0.04;
    r->w2 = 0.02;
    r->d1 = d->relief_depth;
    r->d2 = d->relief_depth2;
    r->k1 = r->k2 = 1.0;
    if (r->w1 < wmin) {
        r->k1 = r->w1 / wmin;
        r->d1 *= r->k1;
        r->w1 = wmin;
    }
    if (r->w2 < wmin) {
        r->k2 = r->w2 / wmin;
        r->d2 *= r->k2;
        r->w2 = wmin;
    }
    return SS_OK;
}

/* The points of the m x m periodic set that can matter within a texel:
 * offsets (mm, in the stretched metric) from the texel centre (u, v) to the
 * points of the 5 x 5 lattice cells around it, kept when
 * |p_k| < |p_nearest| + slack. A point can only be nearest to a sub-sample
 * within distance t of the centre when |p_k| < |p_nearest| + 2 t, and only
 * be the other side of an edge nearer than `reach` when
 * |p_k| < |p_nearest| + 2 t + 2 reach (the bisector distance is at least
 * half the difference of the two distances), so slack = 2 (t + reach)
 * keeps every point the texel's sub-samples need and skips most. */
enum { REACH = 2, SIDE = 2 * REACH + 1, NPTS = SIDE * SIDE };
typedef struct cand_set {
    int n;
    double x[NPTS], y[NPTS], d2[NPTS];
    float z[NPTS];
} cand_set;

static inline __attribute__((always_inline)) void
gather_points(const float *p, int m, double world_mm, double u, double v, double tx, double ty,
              double inv_stretch, int iso, double slack, cand_set *cs) {
    const int ci = (int)floor(u * m), cj = (int)floor(v * m);
    double bx[NPTS], by[NPTS], bd2[NPTS];
    float bz[NPTS];
    int col[SIDE];
    double cox[SIDE];
    for (int d = 0; d < SIDE; d++) { /* the periodic wrap, once per column */
        int i = ci + d - REACH;
        double ox = 0;
        if (i < 0) i += m, ox = -1;
        if (i >= m) i -= m, ox = 1;
        col[d] = i;
        cox[d] = ox;
    }
    int nb = 0;
    for (int dj = 0; dj < SIDE; dj++) {
        int j = cj + dj - REACH;
        double oy = 0;
        if (j < 0) j += m, oy = -1;
        if (j >= m) j -= m, oy = 1;
        const float *row = p + (size_t)j * m * 3;
        for (int di = 0; di < SIDE; di++) {
            const float *q = row + (size_t)col[di] * 3;
            double dx = (q[0] + cox[di] - u) * world_mm, dy = (q[1] + oy - v) * world_mm;
            /* into the metric: shrink the component along the direction
             * (iso: the identity, whose products by 1 and 0 are exact) */
            double a = dx, b = dy;
            if (!iso) a = (dx * tx + dy * ty) * inv_stretch, b = -dx * ty + dy * tx;
            bx[nb] = a;
            by[nb] = b;
            bz[nb] = q[2];
            bd2[nb] = a * a + b * b;
            nb++;
        }
    }
    /* the nearest distance: the minimum by a tree (no serial dependence) */
    double mn[SIDE], bd = INFINITY;
    for (int d = 0; d < SIDE; d++) {
        const double *r5 = bd2 + d * SIDE;
        double x = r5[0] < r5[1] ? r5[0] : r5[1], y = r5[2] < r5[3] ? r5[2] : r5[3];
        x = x < y ? x : y;
        mn[d] = x < r5[4] ? x : r5[4];
    }
    for (int d = 0; d < SIDE; d++)
        if (mn[d] < bd) bd = mn[d];
    const double lim = sqrt(bd) + slack, lim2 = lim * lim;
    int n = 0;
    for (int k = 0; k < nb; k++) /* in lattice order: ties resolve as before */
        if (bd2[k] <= lim2) {
            cs->x[n] = bx[k];
            cs->y[n] = by[k];
            cs->d2[n] = bd2[k];
            cs->z[n] = bz[k];
            n++;
        }
    cs->n = n;
}

/* Distance (mm, in the metric) from the point at offset (ox, oy) from the
 * texel centre to the nearest Voronoi edge of the gathered points, and
 * that edge's depth factor; only edges nearer than `reach` are looked for
 * (+INFINITY: none). The distance to the bisector between the nearest point
 * and a rival, exact for a Voronoi diagram; at offset 0 the centre's own
 * distances are used as they are. */
static inline __attribute__((always_inline)) double edge_at(const cand_set *cs, double ox,
                                                            double oy, double reach, float *depth) {
    double d2[NPTS], bd = INFINITY;
    int best = 0;
    for (int k = 0; k < cs->n; k++) {
        double a = cs->x[k] - ox, b = cs->y[k] - oy;
        d2[k] = a * a + b * b;
    }
    for (int k = 0; k < cs->n; k++) /* the first nearest, a strict running minimum */
        if (d2[k] < bd) bd = d2[k], best = k;
    const double lim = sqrt(bd) + 2.0 * reach, lim2 = lim * lim;
    double e = INFINITY;
    float dep = 0.0f;
    for (int k = 0; k < cs->n; k++) {
        if (k == best || d2[k] > lim2) continue;
        double gx = cs->x[k] - cs->x[best], gy = cs->y[k] - cs->y[best];
        double gl = sqrt(gx * gx + gy * gy);
        if (!(gl > 0)) continue;
        /* the bisector: points x with (x - mid) . g = 0; the sample is at 0 */
        double dist = (d2[k] - bd) / (2.0 * gl);
        if (dist < e) {
            e = dist;
            dep = 0.5f + 0.5f * (cs->z[k] + cs->z[best]); /* symmetric in the two cells */
        }
    }
    *depth = dep;
    return e;
}

float skin_relief_eval(const skin_relief *r, double u, double v, float *groove) {
    *groove = 0.0f;
    if (!r->p1) return 0.0f;
    /* the field's axis here: bilinear in the doubled angle, periodic */
    const int nd = r->nd;
    double X = u * nd, Y = v * nd, fx = floor(X), fy = floor(Y);
    int i0 = (int)fx, j0 = (int)fy;
    if (i0 < 0 || i0 >= nd) i0 = (i0 % nd + nd) % nd;
    if (j0 < 0 || j0 >= nd) j0 = (j0 % nd + nd) % nd;
    int i1 = i0 + 1 == nd ? 0 : i0 + 1, j1 = j0 + 1 == nd ? 0 : j0 + 1;
    double sx = X - fx, sy = Y - fy, c2 = 0, s2 = 0;
    const int ii[4] = {i0, i1, i0, i1}, jj[4] = {j0, j0, j1, j1};
    const double ww[4] = {(1 - sx) * (1 - sy), sx * (1 - sy), (1 - sx) * sy, sx * sy};
    for (int k = 0; k < 4; k++) {
        const float *q = r->dir + ((size_t)jj[k] * nd + ii[k]) * 2;
        c2 += ww[k] * q[0];
        s2 += ww[k] * q[1];
    }
    /* half the doubled angle: cos a = sqrt((1 + c) / 2), sin a = sign(s) sqrt((1 - c) / 2) */
    const double len = sqrt(c2 * c2 + s2 * s2), c = len > 0 ? c2 / len : 1.0;
    const double tx = sqrt(fmax(0.0, 0.5 * (1.0 + c))),
                 ty = (s2 < 0 ? -1.0 : 1.0) * sqrt(fmax(0.0, 0.5 * (1.0 - c)));
    /* the texel's footprint: n x n sub-samples on a regular grid, their
     * offsets along the texel's axes in each metric; t bounds their distance
     * from the centre (the metric only shrinks) */
    const int n = r->ns;
    const double h = r->texel_mm / n, t = 0.5 * (n - 1) * h * sqrt(2.0);
    const double is = 1.0 / r->stretch;
    cand_set cp, cs;
    gather_points(r->p1, r->m1, r->world_mm, u, v, tx, ty, is, 0, 2.0 * (t + r->w1), &cp);
    gather_points(r->p2, r->m2, r->world_mm, u, v, 1.0, 0.0, 1.0, 1, 2.0 * (t + r->w2), &cs);
    float dep1, dep2;
    /* a line reaches the footprint only when the centre is within w + t of
     * it (the distance to the edges is 1-Lipschitz): else a plateau, 0 */
    const int near1 = edge_at(&cp, 0.0, 0.0, r->w1 + t, &dep1) < r->w1 + t;
    const int near2 = edge_at(&cs, 0.0, 0.0, r->w2 + t, &dep2) < r->w2 + t;
    if (!near1 && !near2) return 0.0f;
    double hs = 0.0, gs = 0.0;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            const double ox = (i + 0.5 - 0.5 * n) * h, oy = (j + 0.5 - 0.5 * n) * h;
            double g1 = 0.0, g2 = 0.0;
            if (near1) {
                const double e1 =
                    edge_at(&cp, (ox * tx + oy * ty) * is, -ox * ty + oy * tx, r->w1, &dep1);
                if (e1 < r->w1) g1 = (1.0 - e1 / r->w1) * (1.0 - e1 / r->w1);
            }
            if (near2) {
                const double e2 = edge_at(&cs, ox, oy, r->w2, &dep2);
                if (e2 < r->w2) g2 = (1.0 - e2 / r->w2) * (1.0 - e2 / r->w2);
            }
            hs += r->d1 * dep1 * g1 + r->d2 * dep2 * g2;
            /* the groove weight keeps its area when the line is widened,
             * like the depth */
            const double q1 = g1 * r->k1, q2 = 0.5 * g2 * r->k2;
            gs += q1 > q2 ? q1 : q2;
        }
    const double inv = 1.0 / (n * n);
    *groove = (float)(gs * inv);
    return (float)(-hs * inv);
}
