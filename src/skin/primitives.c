/* Primitives and profile functions of seed 003 §4.8.1-4.8.3 and §5.3: the
 * cubic Bezier curve with point-to-curve distance by golden-section search,
 * and the profiles that turn a distance into a feature's weight.
 *
 * Golden section finds a minimum of a unimodal function; the squared
 * distance from a point to a cubic can have several local minima over
 * [0, 1], so the search first samples the curve at `coarse` + 1 points and
 * runs golden section in the bracket around every local minimum of the
 * samples, keeping the best (the seed's search, made safe for curved
 * wrinkles). Tests compare it with dense brute-force
 * sampling.
 *
 * Profiles: the printed wrinkle profile and follicle fade are garbled or
 * negative in the seed's text; the readings used are documented in
 * docs/skin.md and next to each function. */
#include "skin_internal.h"
#include "skinsim/skin.h"

#include <math.h>

void ss_bezier3_eval(const ss_bezier3 *b, double t, double *x, double *y) {
    double u = 1.0 - t, b0 = u * u * u, b1 = 3.0 * u * u * t, b2 = 3.0 * u * t * t, b3 = t * t * t;
    *x = b0 * b->x[0] + b1 * b->x[1] + b2 * b->x[2] + b3 * b->x[3];
    *y = b0 * b->y[0] + b1 * b->y[1] + b2 * b->y[2] + b3 * b->y[3];
}

static double dist2_at(const ss_bezier3 *b, double t, double px, double py) {
    double x, y;
    ss_bezier3_eval(b, t, &x, &y);
    return (x - px) * (x - px) + (y - py) * (y - py);
}

/* The curve in power form, x(t) = ((a t + b) t + c) t + d, relative to the
 * query point: what the search evaluates (Horner, 6 multiply-adds a point). */
typedef struct poly3 {
    double ax, bx, cx, dx, ay, by, cy, dy;
} poly3;

void skin_bezier3_prepare(const ss_bezier3 *b, skin_bezier3_prep *q) {
    q->ax = -b->x[0] + 3.0 * b->x[1] - 3.0 * b->x[2] + b->x[3];
    q->bx = 3.0 * b->x[0] - 6.0 * b->x[1] + 3.0 * b->x[2];
    q->cx = -3.0 * b->x[0] + 3.0 * b->x[1];
    q->x0 = b->x[0];
    q->ay = -b->y[0] + 3.0 * b->y[1] - 3.0 * b->y[2] + b->y[3];
    q->by = 3.0 * b->y[0] - 6.0 * b->y[1] + 3.0 * b->y[2];
    q->cy = -3.0 * b->y[0] + 3.0 * b->y[1];
    q->y0 = b->y[0];
    /* |B'| <= 3 max |P_k+1 - P_k| (the hodograph's hull) */
    q->sp = 0.0;
    for (int k = 0; k < 3; k++) {
        double l = hypot(b->x[k + 1] - b->x[k], b->y[k + 1] - b->y[k]);
        if (l > q->sp) q->sp = l;
    }
}

static inline double pdist2(const poly3 *p, double t) {
    double x = ((p->ax * t + p->bx) * t + p->cx) * t + p->dx;
    double y = ((p->ay * t + p->by) * t + p->cy) * t + p->dy;
    return x * x + y * y;
}

double ss_bezier3_distance_dense(const ss_bezier3 *b, double px, double py, int n, double *t_out) {
    if (n < 1) n = 1;
    double best = INFINITY, bt = 0.0;
    for (int i = 0; i <= n; i++) {
        double t = (double)i / n, d = dist2_at(b, t, px, py);
        if (d < best) best = d, bt = t;
    }
    if (t_out) *t_out = bt;
    return sqrt(best);
}

/* Golden section for the minimum of the squared distance over [lo, hi]. */
static double golden(const poly3 *p, double lo, double hi, double tol, double *t_out) {
    const double g = 0.6180339887498949; /* (sqrt 5 - 1) / 2 */
    double c = hi - g * (hi - lo), d = lo + g * (hi - lo);
    double fc = pdist2(p, c), fd = pdist2(p, d);
    while (hi - lo > tol) {
        if (fc < fd) {
            hi = d, d = c, fd = fc;
            c = hi - g * (hi - lo);
            fc = pdist2(p, c);
        } else {
            lo = c, c = d, fc = fd;
            d = lo + g * (hi - lo);
            fd = pdist2(p, d);
        }
    }
    *t_out = 0.5 * (lo + hi);
    return pdist2(p, *t_out);
}

double skin_bezier3_distance_prep(const skin_bezier3_prep *q, double px, double py, int coarse,
                                  double tol, double reach, double *t_out) {
    if (coarse < 2) coarse = 2;
    if (coarse > 64) coarse = 64;
    if (!(tol > 0.0)) tol = 1e-6;
    const poly3 p = {q->ax, q->bx, q->cx, q->x0 - px, q->ay, q->by, q->cy, q->y0 - py};
    double f[65], fmin = INFINITY;
    for (int i = 0; i <= coarse; i++) {
        f[i] = pdist2(&p, (double)i / coarse);
        if (f[i] < fmin) fmin = f[i];
    }
    if (reach < INFINITY) {
        /* between two samples the curve is within 1.5 max |dP| / coarse of
         * one of them */
        double lb = sqrt(fmin) - 1.5 * q->sp / coarse;
        if (lb > reach) {
            if (t_out) *t_out = 0.0;
            return INFINITY;
        }
    }
    /* every local minimum of the samples brackets a minimum of the curve's
     * distance (a cubic has at most three); refine each, keep the best */
    double best = INFINITY, bt = 0.0;
    for (int i = 0; i <= coarse; i++) {
        if ((i > 0 && f[i - 1] < f[i]) || (i < coarse && f[i + 1] < f[i])) continue;
        if (f[i] < best) best = f[i], bt = (double)i / coarse; /* endpoints can be the minimum */
        double t, v = golden(&p, (double)(i > 0 ? i - 1 : 0) / coarse,
                             (double)(i < coarse ? i + 1 : coarse) / coarse, tol, &t);
        if (v < best) best = v, bt = t;
    }
    if (t_out) *t_out = bt;
    return sqrt(best);
}

double ss_bezier3_distance(const ss_bezier3 *b, double px, double py, int coarse, double tol,
                           double reach, double *t_out) {
    skin_bezier3_prep q;
    skin_bezier3_prepare(b, &q);
    return skin_bezier3_distance_prep(&q, px, py, coarse, tol, reach, t_out);
}

static double sigmoid(double x) { return 1.0 / (1.0 + exp(-x)); }

/* §5.3.2: þsig = 1 - (sigmoid(4 d / r) - 1/2) * 2: 1 at the centre, 0.036 at d = r. */
double ss_profile_sigmoid(double d, double r) {
    if (!(r > 0.0)) return 0.0;
    return 1.0 - (sigmoid(d / r * 4.0) - 0.5) * 2.0;
}

/* §5.3.5: a = 1 - 1.2 d / r restricted to [0, 1]. */
double ss_profile_freckle(double d, double r) {
    if (!(r > 0.0)) return 0.0;
    double a = 1.0 - 1.2 * d / r;
    return a < 0.0 ? 0.0 : a > 1.0 ? 1.0 : a;
}

/* §5.3.4: alpha 1 inside r_i; between r_i and r_o the seed's sigmoid fade
 * with its factor 5, 2 (1 - sigmoid(5 (d - r_i) / (r_o - r_i))): 1 at r_i,
 * 0.013 at r_o; 0 beyond r_o. (The printed (sigmoid(5 d / r) - 1) / 2 is
 * negative everywhere and cannot be an alpha.) */
double ss_profile_follicle(double d, double r_inner, double r_outer) {
    if (d <= r_inner) return 1.0;
    if (!(d <= r_outer) || !(r_outer > r_inner)) return 0.0;
    return 2.0 * (1.0 - sigmoid(5.0 * (d - r_inner) / (r_outer - r_inner)));
}

/* §5.3.7: T(t, w) = 2 (1 - t) w for t > 1/2, 2 t w for t < 1/2 (w at the middle). */
double ss_wrinkle_taper(double t, double w) { return t > 0.5 ? 2.0 * (1.0 - t) * w : 2.0 * t * w; }

/* §5.3.7: the printed profile (three fractions d/t and an exponent 0.2, cut
 * apart by the text extraction) read as 1 - (d / T)^0.2 restricted to
 * [0, 1]: 1 on the centre line, 0 at the width T, a sharp crease with wide
 * shoulders. T <= 0 (the tapered ends) gives 0. */
double ss_profile_wrinkle(double d, double thickness) {
    if (!(thickness > 0.0)) return 0.0;
    double u = d / thickness;
    if (u >= 1.0) return 0.0;
    if (u <= 0.0) return 1.0;
    return 1.0 - pow(u, 0.2);
}

double ss_mole_outline(double r, double theta) {
    const double ph = 6.283185307179586 * r;
    return r * (1.0 + 0.05 * sin(2.0 * theta + ph) + 0.03 * sin(3.0 * theta + 2.0 * ph));
}

double ss_profile_mole(double d, double r_out, double border) {
    const double b = border > 1e-6 ? border : 1e-6;
    double a = (r_out + 0.5 * b - d) / b;
    return a <= 0.0 ? 0.0 : a >= 1.0 ? 1.0 : a * a * (3.0 - 2.0 * a);
}
