/* Rounded wound outlines: every corner of a polygon replaced by a circular
 * fillet, and the stroke hulls of seed 000 §4.2.1 with their corners rounded.
 *
 * Why: the seed's convex hull (Alg. 4.1) of a four-point stroke is a
 * quadrilateral, and its gradient edges (Alg. 3.4) blur the colour across
 * the outline but keep the corners: a painted square became a sharp-edged
 * diamond on the hand. A scrape has rounded ends; a stroke is where the user
 * brushed, not a cut with corners.
 *
 * Design: at a vertex where the outline turns by phi, the fillet is the
 * circle of radius r tangent to both edges; its tangent points lie
 * t = r tan(|phi| / 2) from the vertex. t is clamped to half of each
 * adjacent edge so neighbouring fillets never overlap (r shrinks with it: a
 * thin streak gets round tips of its own width). The arc is sampled so its
 * chords stray at most ROUND_TOL pixels from the circle (sagitta), so the
 * outline's exact distance (ss_outline_distance) stays smooth at any size.
 * Reflex corners of a concave hull get an inward fillet by the same formula
 * (the turn's sign puts the centre on the right side). Orientation and the
 * starting vertex are kept. The radius of a stroke's fillets is a fraction
 * of its hull's closing distance (Alg. 4.3), so the shape is the same at
 * every texture size. Gave up: the stroke's corner points lie outside the
 * rounded outline (by at most (sqrt 2 - 1) r on a right angle). */
#include "skinsim/geom.h"

#include <math.h>
#include <stdlib.h>

/* Largest distance (pixels) between a fillet's chords and its circle. */
#define ROUND_TOL 0.05
/* At most this many chords per fillet. */
#define ROUND_MAX_STEPS 256

static int fillet_steps(double phi, double r) {
    if (!(r > ROUND_TOL)) return 1;
    double a = 2.0 * acos(1.0 - ROUND_TOL / r); /* the largest angle a chord may span */
    int m = (int)ceil(fabs(phi) / a);
    return m < 1 ? 1 : m > ROUND_MAX_STEPS ? ROUND_MAX_STEPS : m;
}

ss_status ss_polygon_round(const ss_polygon *in, double radius, ss_polygon *out, ss_error *err) {
    out->count = 0;
    out->pts = NULL;
    if (!(radius >= 0) || !isfinite(radius))
        return ss_error_set(err, SS_ERR_INPUT, "corner radius %g must be finite and >= 0", radius);
    if (!in || in->count < 3)
        return ss_error_set(err, SS_ERR_INPUT, "a polygon to round needs at least 3 vertices");
    const int n = in->count;
    /* first pass: the number of output vertices */
    size_t total = 0;
    for (int pass = 0; pass < 2; pass++) {
        size_t k = 0;
        for (int i = 0; i < n; i++) {
            ss_vec2 a = in->pts[(i + n - 1) % n], p = in->pts[i], b = in->pts[(i + 1) % n];
            double ax = p.x - a.x, ay = p.y - a.y, bx = b.x - p.x, by = b.y - p.y;
            double la = hypot(ax, ay), lb = hypot(bx, by);
            double phi = la > 0 && lb > 0 ? atan2(ax * by - ay * bx, ax * bx + ay * by) : 0;
            double tn = tan(0.5 * fabs(phi));
            double t = radius * tn, tmax = 0.5 * fmin(la, lb);
            if (t > tmax) t = tmax;
            if (!(t > 1e-9) || !(fabs(phi) > 1e-9) || !(fabs(phi) < 3.14159)) {
                if (pass) out->pts[k] = p; /* straight, degenerate or a hairpin: keep */
                k++;
                continue;
            }
            double r = t / tn;
            int m = fillet_steps(phi, r);
            if (pass) {
                double dx = ax / la, dy = ay / la, s = phi > 0 ? 1 : -1;
                ss_vec2 st = {p.x - t * dx, p.y - t * dy};
                ss_vec2 c = {st.x - s * r * dy, st.y + s * r * dx};
                double th0 = atan2(st.y - c.y, st.x - c.x);
                for (int j = 0; j <= m; j++) {
                    double th = th0 + phi * j / m;
                    out->pts[k + (size_t)j] = (ss_vec2){c.x + r * cos(th), c.y + r * sin(th)};
                }
                /* the tangent points exactly, so straight edges stay straight */
                out->pts[k] = st;
                out->pts[k + (size_t)m] = (ss_vec2){p.x + t * bx / lb, p.y + t * by / lb};
            }
            k += (size_t)m + 1;
        }
        if (!pass) {
            total = k;
            if (total > 100000000)
                return ss_error_set(err, SS_ERR_INPUT, "rounded polygon too large");
            out->pts = malloc(total * sizeof *out->pts);
            if (!out->pts) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        }
    }
    out->count = (int)total;
    return SS_OK;
}

ss_status ss_stroke_outlines(const ss_stroke_set *s, double width, double height, int concave_k,
                             double round, const char *name, ss_polygon **out, ss_error *err) {
    if (!(round >= 0 && round <= 0.5))
        return ss_error_set(err, SS_ERR_INPUT, "%s%scorner rounding %g is outside [0, 0.5]",
                            name ? name : "", name ? ": " : "", round);
    ss_status st = ss_stroke_hulls(s, width, height, concave_k, name, out, err);
    if (st || round == 0) return st;
    for (int k = 0; k < s->nstrokes && !st; k++) {
        ss_polygon r;
        st = ss_polygon_round(&(*out)[k], round * ss_closing_distance(&(*out)[k]), &r, err);
        if (!st) {
            ss_polygon_free(&(*out)[k]);
            (*out)[k] = r;
        }
    }
    if (st) {
        for (int k = 0; k < s->nstrokes; k++) ss_polygon_free(&(*out)[k]);
        free(*out);
        *out = NULL;
    }
    return st;
}

ss_image *ss_stroke_footprint_rounded(const ss_stroke_set *s, int width, int height, int concave_k,
                                      double round, const char *name, ss_error *err) {
    ss_polygon *polys;
    if (ss_stroke_outlines(s, width, height, concave_k, round, name, &polys, err)) return NULL;
    ss_image *img = ss_image_create(width, height, 1, err);
    for (int k = 0; k < s->nstrokes; k++) {
        if (img) ss_polygon_fill(&polys[k], img);
        ss_polygon_free(&polys[k]);
    }
    free(polys);
    return img;
}
