/* Hulls of point sets (seed 000 §4.2.1 Alg. 4.1 with Eq. 4.4, and the
 * k-nearest-neighbour concave hull of Moreira & Santos 2007 named in seed 000
 * §5.1), plus the closing distance of a hull (Alg. 4.3).
 *
 * Orientation: all hulls come out with positive shoelace area in raw pixel
 * coordinates (x right, y down), which is clockwise as seen on the image. At
 * every vertex Eq. 4.4's determinant is > 0, so a pixel is inside exactly when
 * it is not on Eq. 4.4's "right side" (det < 0) of any edge, which is the test
 * of Alg. 4.2. (The seed's Alg. 4.1 keeps det < 0 turns, i.e. clockwise in a
 * y-up frame; run in a y-down image frame the same list is clockwise on
 * screen only when its order is reversed, so we emit that order.)
 *
 * Design: monotone chain over points sorted by (x, y) with exact duplicates
 * removed; collinear points are dropped (det == 0 is "not a turn"). The
 * concave hull walks from the lowest-y point choosing, among the k nearest
 * unused points, the largest right-hand turn whose new edge does not cross the
 * hull so far; on failure or when a point ends up outside, k grows (by 1 for
 * the first ten tries, then by 25%) and the walk restarts; at k = n-1 it falls
 * back to the convex hull. Cost O(n^2) per attempt (brute-force k-nearest). */
#include "skinsim/geom.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SS_TWO_PI 6.283185307179586476925286766559

void ss_polygon_free(ss_polygon *poly) {
    if (!poly) return;
    free(poly->pts);
    poly->pts = NULL;
    poly->count = 0;
}

/* Eq. 4.4: determinant of (p2 - p1, p3 - p1). */
static double det3(ss_vec2 p1, ss_vec2 p2, ss_vec2 p3) {
    return (p2.x - p1.x) * (p3.y - p1.y) - (p3.x - p1.x) * (p2.y - p1.y);
}

static int cmp_xy(const void *a, const void *b) {
    const ss_vec2 *p = a, *q = b;
    if (p->x < q->x) return -1;
    if (p->x > q->x) return 1;
    if (p->y < q->y) return -1;
    if (p->y > q->y) return 1;
    return 0;
}

/* Copies, sorts by (x,y) and removes exact duplicates; rejects NaN/inf. */
static ss_status unique_sorted(const ss_vec2 *pts, int n, ss_vec2 **out, int *m, ss_error *err) {
    if (!pts || n < 0) return ss_error_set(err, SS_ERR_INPUT, "hull: no points given");
    for (int i = 0; i < n; i++)
        if (!isfinite(pts[i].x) || !isfinite(pts[i].y))
            return ss_error_set(err, SS_ERR_INPUT, "hull: point %d is not finite", i);
    ss_vec2 *p = malloc(sizeof *p * (size_t)(n > 0 ? n : 1));
    if (!p) return ss_error_set(err, SS_ERR_NOMEM, "hull: out of memory for %d points", n);
    if (n > 0) memcpy(p, pts, sizeof *p * (size_t)n);
    qsort(p, (size_t)n, sizeof *p, cmp_xy);
    int k = 0;
    for (int i = 0; i < n; i++)
        if (k == 0 || cmp_xy(&p[k - 1], &p[i]) != 0) p[k++] = p[i];
    *out = p;
    *m = k;
    return SS_OK;
}

static double signed_area2(const ss_vec2 *p, int n) {
    double s = 0;
    for (int i = 0; i < n; i++) {
        const ss_vec2 a = p[i], b = p[(i + 1) % n];
        s += a.x * b.y - b.x * a.y;
    }
    return s;
}

static void reverse(ss_vec2 *p, int n) {
    for (int i = 0, j = n - 1; i < j; i++, j--) {
        ss_vec2 t = p[i];
        p[i] = p[j];
        p[j] = t;
    }
}

/* Monotone chain on sorted unique points p[0..m). Writes the hull to h (room
 * for m+1) and returns its vertex count. Keeps only det > 0 turns (the mirror
 * of Alg. 4.1's det < 0, see the file comment). */
static int chain(const ss_vec2 *p, int m, ss_vec2 *h) {
    int k = 0;
    for (int i = 0; i < m; i++) { /* first chain, left to right */
        while (k >= 2 && det3(h[k - 2], h[k - 1], p[i]) <= 0) k--;
        h[k++] = p[i];
    }
    for (int i = m - 2, t = k + 1; i >= 0; i--) { /* second chain, right to left */
        while (k >= t && det3(h[k - 2], h[k - 1], p[i]) <= 0) k--;
        h[k++] = p[i];
    }
    return k - 1; /* the last point repeats the first */
}

ss_status ss_convex_hull(const ss_vec2 *pts, int n, ss_polygon *out, ss_error *err) {
    if (!out) return ss_error_set(err, SS_ERR_INPUT, "convex hull: no output polygon");
    out->count = 0;
    out->pts = NULL;
    ss_vec2 *p;
    int m;
    ss_status st = unique_sorted(pts, n, &p, &m, err);
    if (st) return st;
    if (m < 3) {
        free(p);
        return ss_error_set(err, SS_ERR_INPUT,
                            "convex hull: need at least 3 distinct points, got %d (of %d)", m, n);
    }
    ss_vec2 *h = malloc(sizeof *h * (size_t)(m + 1));
    if (!h) {
        free(p);
        return ss_error_set(err, SS_ERR_NOMEM, "convex hull: out of memory");
    }
    int k = chain(p, m, h);
    free(p);
    if (k < 3) {
        free(h);
        return ss_error_set(err, SS_ERR_INPUT,
                            "convex hull: the %d distinct points are collinear (no area)", m);
    }
    out->pts = h;
    out->count = k;
    return SS_OK;
}

/* ---- concave hull (Moreira & Santos 2007) ---------------------------------- */

/* Closed segments a-b and c-d share a point. */
static int seg_intersect(ss_vec2 a, ss_vec2 b, ss_vec2 c, ss_vec2 d) {
    double d1 = det3(c, d, a), d2 = det3(c, d, b), d3 = det3(a, b, c), d4 = det3(a, b, d);
    if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0)))
        return 1;
#define ON_SEG(p, q, r)                                                                            \
    (fmin((p).x, (q).x) <= (r).x && (r).x <= fmax((p).x, (q).x) && fmin((p).y, (q).y) <= (r).y &&  \
     (r).y <= fmax((p).y, (q).y))
    if (d1 == 0 && ON_SEG(c, d, a)) return 1;
    if (d2 == 0 && ON_SEG(c, d, b)) return 1;
    if (d3 == 0 && ON_SEG(a, b, c)) return 1;
    if (d4 == 0 && ON_SEG(a, b, d)) return 1;
#undef ON_SEG
    return 0;
}

/* Inside (even-odd) or within tol of the boundary. */
static int inside_or_on(const ss_vec2 *h, int n, ss_vec2 p, double tol) {
    int in = 0;
    for (int i = 0, j = n - 1; i < n; j = i++) {
        ss_vec2 a = h[j], b = h[i];
        if (ss_segment_distance(a, b, p) <= tol) return 1;
        if ((a.y > p.y) != (b.y > p.y)) {
            double x = a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if (p.x < x) in = !in;
        }
    }
    return in;
}

typedef struct cand {
    int idx;
    double key;
} cand;

static int cmp_cand_asc(const void *a, const void *b) {
    double x = ((const cand *)a)->key, y = ((const cand *)b)->key;
    if (x < y) return -1;
    if (x > y) return 1;
    return ((const cand *)a)->idx - ((const cand *)b)->idx;
}

static int cmp_cand_desc(const void *a, const void *b) { return cmp_cand_asc(b, a); }

/* One attempt with a fixed k. p: m unique points; first: index of the start.
 * On success fills hull (indices) and returns its length, else 0. */
static int concave_attempt(const ss_vec2 *p, int m, int first, int k, double tol, int *hull,
                           unsigned char *used, cand *cs) {
    memset(used, 0, (size_t)m);
    int len = 0;
    hull[len++] = first;
    used[first] = 1;
    ss_vec2 back = {-1.0, 0.0}; /* as if arriving along the bottom from the west */
    for (;;) {
        const int cur = hull[len - 1];
        const ss_vec2 c = p[cur];
        /* k nearest among unused points, plus the start once the hull can close
         * (kept sorted by (distance, index) with insertion: O(n k)). */
        int nc = 0;
        for (int i = 0; i < m; i++) {
            if (used[i] && !(i == first && len >= 3)) continue;
            if (i == cur) continue;
            double dx = p[i].x - c.x, dy = p[i].y - c.y;
            const cand ci = {i, dx * dx + dy * dy};
            if (nc == k && cmp_cand_asc(&ci, &cs[k - 1]) >= 0) continue;
            int j = nc < k ? nc++ : k - 1;
            while (j > 0 && cmp_cand_asc(&ci, &cs[j - 1]) < 0) {
                cs[j] = cs[j - 1];
                j--;
            }
            cs[j] = ci;
        }
        if (nc == 0) return 0;
        /* Sort by right-hand (clockwise) turn from the back direction, largest first. */
        for (int i = 0; i < nc; i++) {
            double dx = p[cs[i].idx].x - c.x, dy = p[cs[i].idx].y - c.y;
            double ccw = atan2(back.x * dy - back.y * dx, back.x * dx + back.y * dy);
            double cw = -ccw;
            if (cw < 0) cw += SS_TWO_PI;
            cs[i].key = cw;
        }
        qsort(cs, (size_t)nc, sizeof *cs, cmp_cand_desc);
        int chosen = -1;
        for (int i = 0; i < nc && chosen < 0; i++) {
            const int q = cs[i].idx;
            const ss_vec2 pq = p[q];
            double dx = pq.x - c.x, dy = pq.y - c.y;
            /* Folding straight back onto the previous edge is never a valid edge. */
            if (back.x * dy - back.y * dx == 0 && back.x * dx + back.y * dy > 0) continue;
            if (q == first && len >= 2) {
                ss_vec2 e = {p[hull[1]].x - pq.x, p[hull[1]].y - pq.y};
                ss_vec2 f = {c.x - pq.x, c.y - pq.y};
                if (e.x * f.y - e.y * f.x == 0 && e.x * f.x + e.y * f.y > 0) continue;
            }
            int bad = 0;
            /* Edges hull[j]-hull[j+1]; the last one (ending at cur) shares cur,
             * the first one shares the start when closing. */
            for (int j = 0; j + 1 < len - 1 && !bad; j++) {
                if (q == first && j == 0) continue;
                if (seg_intersect(c, pq, p[hull[j]], p[hull[j + 1]])) bad = 1;
            }
            if (!bad) chosen = q;
        }
        if (chosen < 0) return 0;
        if (chosen == first) break;
        hull[len++] = chosen;
        used[chosen] = 1;
        back.x = c.x - p[chosen].x;
        back.y = c.y - p[chosen].y;
        if (len > m) return 0;
    }
    if (len < 3) return 0;
    /* Every point must be inside the polygon or on its boundary. */
    ss_vec2 *hp = malloc(sizeof *hp * (size_t)len);
    if (!hp) return 0;
    for (int i = 0; i < len; i++) hp[i] = p[hull[i]];
    int ok = fabs(signed_area2(hp, len)) > 0;
    for (int i = 0; i < m && ok; i++)
        if (!used[i] && !inside_or_on(hp, len, p[i], tol)) ok = 0;
    free(hp);
    return ok ? len : 0;
}

ss_status ss_concave_hull(const ss_vec2 *pts, int n, int k, ss_polygon *out, ss_error *err) {
    if (!out) return ss_error_set(err, SS_ERR_INPUT, "concave hull: no output polygon");
    out->count = 0;
    out->pts = NULL;
    ss_vec2 *p;
    int m;
    ss_status st = unique_sorted(pts, n, &p, &m, err);
    if (st) return st;
    int noncollinear = 0;
    for (int i = 2; i < m && !noncollinear; i++)
        if (det3(p[0], p[1], p[i]) != 0) noncollinear = 1;
    if (m < 3 || !noncollinear) {
        free(p);
        if (m < 3)
            return ss_error_set(err, SS_ERR_INPUT,
                                "concave hull: need at least 3 distinct points, got %d (of %d)", m,
                                n);
        return ss_error_set(err, SS_ERR_INPUT,
                            "concave hull: the %d distinct points are collinear (no area)", m);
    }
    double scale = 0;
    int first = 0;
    for (int i = 0; i < m; i++) {
        scale = fmax(scale, fmax(fabs(p[i].x), fabs(p[i].y)));
        if (p[i].y < p[first].y || (p[i].y == p[first].y && p[i].x < p[first].x)) first = i;
    }
    const double tol = 1e-9 * (1.0 + scale);
    int *hull = malloc(sizeof *hull * (size_t)(m + 1));
    unsigned char *used = malloc((size_t)m);
    cand *cs = malloc(sizeof *cs * (size_t)m);
    if (!hull || !used || !cs) {
        free(p);
        free(hull);
        free(used);
        free(cs);
        return ss_error_set(err, SS_ERR_NOMEM, "concave hull: out of memory");
    }
    int kk = k < 3 ? 3 : k, len = 0, tries = 0;
    while (kk < m) {
        len = concave_attempt(p, m, first, kk, tol, hull, used, cs);
        if (len) break;
        tries++;
        kk = tries < 10 ? kk + 1 : kk + (kk + 3) / 4;
    }
    free(used);
    free(cs);
    if (!len) { /* k reached n-1: the convex hull (which contains every point) */
        free(hull);
        free(p);
        return ss_convex_hull(pts, n, out, err);
    }
    ss_vec2 *h = malloc(sizeof *h * (size_t)len);
    if (!h) {
        free(hull);
        free(p);
        return ss_error_set(err, SS_ERR_NOMEM, "concave hull: out of memory");
    }
    for (int i = 0; i < len; i++) h[i] = p[hull[i]];
    free(hull);
    free(p);
    if (signed_area2(h, len) < 0) reverse(h, len);
    out->pts = h;
    out->count = len;
    return SS_OK;
}

/* Alg. 4.3: the largest distance between two vertices of the hull (the
 * seed's "vector from edge e to edge f" read as between their start points,
 * which visits every vertex pair). */
double ss_closing_distance(const ss_polygon *poly) {
    if (!poly || poly->count <= 0) return 0.0;
    double best = 0.0;
    for (int i = 0; i < poly->count; i++)
        for (int j = i + 1; j < poly->count; j++) {
            double dx = poly->pts[j].x - poly->pts[i].x, dy = poly->pts[j].y - poly->pts[i].y;
            best = fmax(best, sqrt(dx * dx + dy * dy));
        }
    return best;
}
