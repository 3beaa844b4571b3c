/* Polygon fill into a mask (seed 000 §4.2.2 Alg. 4.2 and the scanline
 * improvement of §5.1 Fig. 5.1).
 *
 * ss_polygon_fill: per row, the crossings of the row's pixel-centre line with
 * all edges (half-open rule: an edge counts when exactly one end is above the
 * line), sorted, filled pairwise (even-odd), so concave and multi-loop
 * outlines work. A pixel is in when its centre x lies in [x_in, x_out).
 * Rows run in parallel (OpenMP); every row is independent, so the result does
 * not depend on the thread count.
 *
 * ss_polygon_fill_bruteforce: Alg. 4.2 for convex polygons: every pixel of
 * the bounding box is tested against every edge with Eq. 4.4 and set to 1
 * (in) or 0 (out). Two deliberate differences from the printed pseudo-code:
 * isInHull is reset for every pixel (the seed initialises it once, which
 * would blacken everything after the first outside pixel), and the side that
 * counts as "outside" follows the polygon's orientation (sign of its area),
 * so either winding works. Pixels exactly on an edge count as inside. */
#include "skinsim/geom.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>

static void set_px(ss_image *m, int x, int y, float v) {
    float *p = ss_image_px(m, x, y);
    for (int c = 0; c < m->channels; c++) p[c] = v;
}

/* Polygons with NaN/inf vertices are not filled (nothing sensible to do). */
static int finite_poly(const ss_polygon *poly) {
    for (int i = 0; i < poly->count; i++)
        if (!isfinite(poly->pts[i].x) || !isfinite(poly->pts[i].y)) return 0;
    return 1;
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

void ss_polygon_fill(const ss_polygon *poly, ss_image *mask) {
    if (!poly || !mask || poly->count < 3 || !poly->pts || !finite_poly(poly)) return;
    const int n = poly->count, W = mask->width, H = mask->height;
    double ymin = poly->pts[0].y, ymax = ymin;
    for (int i = 1; i < n; i++) {
        ymin = fmin(ymin, poly->pts[i].y);
        ymax = fmax(ymax, poly->pts[i].y);
    }
    /* Rows whose centre y+0.5 can lie inside [ymin, ymax]. */
    const double y0d = fmax(0.0, floor(ymin - 0.5)), y1d = fmin((double)H - 1, ceil(ymax));
    if (y0d > y1d) return;
    const int y0 = (int)y0d, y1 = (int)y1d;
#pragma omp parallel
    {
        double *xs = malloc(sizeof *xs * (size_t)n);
#pragma omp for schedule(dynamic, 16)
        for (int y = y0; y <= y1; y++) {
            if (!xs) continue;
            const double yc = y + 0.5;
            int nx = 0;
            for (int i = 0, j = n - 1; i < n; j = i++) {
                const ss_vec2 a = poly->pts[j], b = poly->pts[i];
                if ((a.y > yc) != (b.y > yc))
                    xs[nx++] = a.x + (yc - a.y) * (b.x - a.x) / (b.y - a.y);
            }
            qsort(xs, (size_t)nx, sizeof *xs, cmp_double);
            for (int k = 0; k + 1 < nx; k += 2) {
                /* pixels with xa <= x + 0.5 < xb */
                double fa = ceil(xs[k] - 0.5), fb = ceil(xs[k + 1] - 0.5);
                if (fb <= 0 || fa >= W) continue;
                int xa = fa < 0 ? 0 : (int)fa, xb = fb > W ? W : (int)fb;
                for (int x = xa; x < xb; x++) set_px(mask, x, y, 1.0f);
            }
        }
        free(xs);
    }
}

void ss_polygon_fill_bruteforce(const ss_polygon *poly, ss_image *mask) {
    if (!poly || !mask || poly->count < 3 || !poly->pts || !finite_poly(poly)) return;
    const int n = poly->count, W = mask->width, H = mask->height;
    double minx = poly->pts[0].x, maxx = minx, miny = poly->pts[0].y, maxy = miny, area2 = 0;
    for (int i = 0; i < n; i++) {
        const ss_vec2 a = poly->pts[i], b = poly->pts[(i + 1) % n];
        minx = fmin(minx, a.x);
        maxx = fmax(maxx, a.x);
        miny = fmin(miny, a.y);
        maxy = fmax(maxy, a.y);
        area2 += a.x * b.y - b.x * a.y;
    }
    const double s = area2 >= 0 ? 1.0 : -1.0;
    /* GetHullBoundingBox: pixels that can have their centre in the box. */
    const double x0d = fmax(0.0, floor(minx)), x1d = fmin((double)W - 1, ceil(maxx));
    const double y0d = fmax(0.0, floor(miny)), y1d = fmin((double)H - 1, ceil(maxy));
    if (x0d > x1d || y0d > y1d) return;
    const int x0 = (int)x0d, x1 = (int)x1d, y0 = (int)y0d, y1 = (int)y1d;
#pragma omp parallel for schedule(static)
    for (int y = y0; y <= y1; y++)
        for (int x = x0; x <= x1; x++) {
            const ss_vec2 p = {x + 0.5, y + 0.5};
            int in = 1;
            for (int i = 0; i < n; i++) {
                const ss_vec2 a = poly->pts[i], b = poly->pts[(i + 1) % n];
                /* IsOnRightSide, Eq. 4.4 (mirrored for the other winding) */
                double det = (b.x - a.x) * (p.y - a.y) - (p.x - a.x) * (b.y - a.y);
                if (s * det < 0) {
                    in = 0;
                    break;
                }
            }
            set_px(mask, x, y, in ? 1.0f : 0.0f);
        }
}
