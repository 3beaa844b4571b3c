/* geom: convex hull invariants (contains all points, convex, clockwise on the
 * image, duplicates/collinear dropped, bad input refused), concave hull
 * (contains all points, simple, area <= convex and < on an L shape), fill
 * (exact rectangle count, scanline == Alg. 4.2 on convex hulls, == per-pixel
 * even-odd test on concave ones), closing distance of a square, Alg. 3.3
 * known values, exact EDT == brute force, fast outline distance == brute
 * force within max_dist for convex, concave and several polygons, and 1 vs 2
 * threads bit-identical. */
#include "testutil.h"
#include "skinsim/geom.h"
#include "skinsim/mesh.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static double det3(ss_vec2 a, ss_vec2 b, ss_vec2 c) {
    return (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
}

static double area2(const ss_polygon *p) {
    double s = 0;
    for (int i = 0; i < p->count; i++) {
        ss_vec2 a = p->pts[i], b = p->pts[(i + 1) % p->count];
        s += a.x * b.y - b.x * a.y;
    }
    return s;
}

static int point_in_poly_evenodd(const ss_polygon *p, ss_vec2 q) {
    int in = 0;
    for (int i = 0, j = p->count - 1; i < p->count; j = i++) {
        ss_vec2 a = p->pts[j], b = p->pts[i];
        if ((a.y > q.y) != (b.y > q.y)) {
            double x = a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if (q.x < x) in = !in;
        }
    }
    return in;
}

static int inside_or_on(const ss_polygon *p, ss_vec2 q) {
    for (int i = 0; i < p->count; i++)
        if (ss_segment_distance(p->pts[i], p->pts[(i + 1) % p->count], q) < 1e-7) return 1;
    return point_in_poly_evenodd(p, q);
}

static int proper_cross(ss_vec2 a, ss_vec2 b, ss_vec2 c, ss_vec2 d) {
    double d1 = det3(c, d, a), d2 = det3(c, d, b), d3 = det3(a, b, c), d4 = det3(a, b, d);
    return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

static int is_simple(const ss_polygon *p) {
    int n = p->count;
    for (int i = 0; i < n; i++)
        for (int j = i + 2; j < n; j++) {
            if (i == 0 && j == n - 1) continue;
            if (proper_cross(p->pts[i], p->pts[(i + 1) % n], p->pts[j], p->pts[(j + 1) % n]))
                return 0;
        }
    return 1;
}

/* n random points in a disc-ish blob of radius r around (cx, cy). */
static ss_vec2 *random_points(int n, uint64_t seed, double cx, double cy, double r) {
    ss_vec2 *p = malloc(sizeof *p * (size_t)n);
    for (int i = 0; i < n; i++) {
        double a = 6.283185307 * ss_rng_uniform(seed, 1, (uint64_t)i);
        double rr = r * sqrt(ss_rng_uniform(seed, 2, (uint64_t)i));
        p[i].x = cx + rr * cos(a);
        p[i].y = cy + 0.7 * rr * sin(a);
    }
    return p;
}

/* Points filling an L: a W x T horizontal bar and a T x W vertical bar. */
static ss_vec2 *l_points(int *n, double x0, double y0, double step) {
    ss_vec2 *p = malloc(sizeof *p * 400);
    int k = 0;
    for (int i = 0; i <= 10; i++)
        for (int j = 0; j <= 10; j++)
            if (i <= 3 || j >= 7) { /* vertical bar on the left, horizontal bar at the bottom */
                p[k].x = x0 + i * step;
                p[k].y = y0 + j * step;
                k++;
            }
    *n = k;
    return p;
}

static void test_convex_hull(void **state) {
    (void)state;
    ss_error err;
    for (uint64_t seed = 1; seed <= 6; seed++) {
        int n = 20 + (int)seed * 37;
        ss_vec2 *p = random_points(n, seed, 50, 40, 30);
        ss_polygon h;
        assert_int_equal(ss_convex_hull(p, n, &h, &err), SS_OK);
        assert_true(h.count >= 3);
        assert_true(area2(&h) > 0); /* clockwise on a y-down image */
        for (int i = 0; i < h.count; i++) {
            /* strictly convex turns (Eq. 4.4 det > 0) */
            assert_true(det3(h.pts[i], h.pts[(i + 1) % h.count], h.pts[(i + 2) % h.count]) > 0);
            int found = 0;
            for (int j = 0; j < n; j++) found |= p[j].x == h.pts[i].x && p[j].y == h.pts[i].y;
            assert_true(found);
        }
        for (int j = 0; j < n; j++)
            for (int i = 0; i < h.count; i++)
                assert_true(det3(h.pts[i], h.pts[(i + 1) % h.count], p[j]) >= -1e-9);
        ss_polygon_free(&h);
        assert_null(h.pts);
        free(p);
    }
    /* Square with duplicates and points on its edges: 4 corners. */
    ss_vec2 sq[] = {{0, 0}, {4, 0}, {4, 4}, {0, 4}, {2, 0}, {4, 2}, {0, 0}, {2, 2}, {4, 4}, {0, 1}};
    ss_polygon h;
    assert_int_equal(ss_convex_hull(sq, 10, &h, &err), SS_OK);
    assert_int_equal(h.count, 4);
    assert_float_equal(area2(&h), 32.0, 1e-12);
    ss_polygon_free(&h);
    /* Bad input: too few distinct points, collinear, NULL. */
    ss_vec2 two[] = {{1, 1}, {2, 2}, {1, 1}};
    assert_int_equal(ss_convex_hull(two, 3, &h, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "3 distinct"));
    ss_vec2 line[] = {{0, 0}, {1, 1}, {2, 2}, {5, 5}};
    assert_int_equal(ss_convex_hull(line, 4, &h, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "collinear"));
    assert_int_equal(ss_convex_hull(NULL, 4, &h, &err), SS_ERR_INPUT);
    ss_vec2 nan[] = {{0, 0}, {1, 0}, {NAN, 1}};
    assert_int_equal(ss_convex_hull(nan, 3, &h, &err), SS_ERR_INPUT);
    assert_int_equal(ss_concave_hull(line, 4, 3, &h, &err), SS_ERR_INPUT);
    assert_int_equal(ss_concave_hull(two, 3, 3, &h, &err), SS_ERR_INPUT);
}

static void check_concave(const ss_vec2 *p, int n, int k, double *acave, double *avex) {
    ss_error err;
    ss_polygon cv, cx;
    assert_int_equal(ss_concave_hull(p, n, k, &cv, &err), SS_OK);
    assert_int_equal(ss_convex_hull(p, n, &cx, &err), SS_OK);
    assert_true(cv.count >= 3);
    assert_true(area2(&cv) > 0);
    assert_true(is_simple(&cv));
    for (int j = 0; j < n; j++) assert_true(inside_or_on(&cv, p[j]));
    *acave = area2(&cv) / 2;
    *avex = area2(&cx) / 2;
    assert_true(*acave <= *avex + 1e-9);
    ss_polygon_free(&cv);
    ss_polygon_free(&cx);
}

static void test_concave_hull(void **state) {
    (void)state;
    int n;
    double a, b;
    ss_vec2 *L = l_points(&n, 10, 5, 3.0);
    check_concave(L, n, 3, &a, &b);
    /* The L's hull must cut the notch: the convex hull covers 100% of the
     * 30x30 box minus a triangle, the L itself is 9*30 + 9*21 ... */
    assert_true(a < 0.8 * b);
    free(L);
    for (uint64_t seed = 1; seed <= 5; seed++) {
        int m = 30 + (int)seed * 25;
        ss_vec2 *p = random_points(m, 100 + seed, 0, 0, 20);
        check_concave(p, m, 3 + (int)seed % 3, &a, &b);
        free(p);
    }
    /* A triangle is its own hull. */
    ss_vec2 tri[] = {{0, 0}, {5, 1}, {2, 7}};
    check_concave(tri, 3, 3, &a, &b);
    assert_float_equal(a, b, 1e-12);
}

static void test_fill(void **state) {
    (void)state;
    ss_error err;
    ss_image *m = ss_image_create(41, 29, 1, &err);
    ss_vec2 r[] = {{2, 3}, {12, 3}, {12, 10}, {2, 10}};
    ss_polygon rect = {4, r};
    ss_polygon_fill(&rect, m);
    int cnt = 0;
    for (int y = 0; y < m->height; y++)
        for (int x = 0; x < m->width; x++) {
            int in = x >= 2 && x < 12 && y >= 3 && y < 10;
            assert_int_equal(*ss_image_px(m, x, y) > 0.5f, in);
            cnt += in;
        }
    assert_int_equal(cnt, 70);
    ss_image *mb = ss_image_create(41, 29, 1, &err);
    ss_polygon_fill_bruteforce(&rect, mb);
    assert_memory_equal(m->data, mb->data, sizeof(float) * 41 * 29);
    ss_image_free(m);
    ss_image_free(mb);

    /* Random convex hulls (partly outside the image): scanline == Alg. 4.2. */
    for (uint64_t seed = 1; seed <= 8; seed++) {
        int W = 53 + (int)seed * 7, H = 47 + (int)seed * 3, n = 40;
        ss_vec2 *p = random_points(n, 300 + seed, W * 0.5 + (seed % 3) * 15.0, H * 0.5, W * 0.45);
        ss_polygon h;
        assert_int_equal(ss_convex_hull(p, n, &h, &err), SS_OK);
        ss_image *a = ss_image_create(W, H, 1, &err), *b = ss_image_create(W, H, 1, &err);
        ss_polygon_fill(&h, a);
        ss_polygon_fill_bruteforce(&h, b);
        assert_memory_equal(a->data, b->data, sizeof(float) * (size_t)W * H);
        /* Reversed winding gives the same brute-force fill. */
        for (int i = 0; i < h.count / 2; i++) {
            ss_vec2 t = h.pts[i];
            h.pts[i] = h.pts[h.count - 1 - i];
            h.pts[h.count - 1 - i] = t;
        }
        ss_image *c = ss_image_create(W, H, 1, &err);
        ss_polygon_fill_bruteforce(&h, c);
        assert_memory_equal(a->data, c->data, sizeof(float) * (size_t)W * H);
        ss_image_free(a);
        ss_image_free(b);
        ss_image_free(c);
        ss_polygon_free(&h);
        free(p);
    }
    /* Far away, huge or NaN polygons fill nothing (and do not crash). */
    {
        ss_vec2 far[] = {{1e300, 1e300}, {2e300, 1e300}, {1e300, 3e300}};
        ss_vec2 bad[] = {{1, 1}, {NAN, 5}, {9, 9}};
        ss_polygon fp = {3, far}, bp = {3, bad};
        ss_image *z = ss_image_create(17, 13, 1, &err);
        ss_polygon_fill(&fp, z);
        ss_polygon_fill_bruteforce(&fp, z);
        ss_polygon_fill(&bp, z);
        ss_polygon_fill_bruteforce(&bp, z);
        for (int i = 0; i < 17 * 13; i++) assert_true(z->data[i] == 0.0f);
        ss_image_free(z);
    }
    /* Concave: scanline == per-pixel even-odd point-in-polygon. */
    for (uint64_t seed = 1; seed <= 4; seed++) {
        int W = 61, H = 59, n = 60;
        ss_vec2 *p = random_points(n, 400 + seed, 30.3, 29.7, 28);
        ss_polygon h;
        assert_int_equal(ss_concave_hull(p, n, 3, &h, &err), SS_OK);
        ss_image *a = ss_image_create(W, H, 1, &err);
        ss_polygon_fill(&h, a);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                ss_vec2 q = {x + 0.5, y + 0.5};
                assert_int_equal(*ss_image_px(a, x, y) > 0.5f, point_in_poly_evenodd(&h, q));
            }
        ss_image_free(a);
        ss_polygon_free(&h);
        free(p);
    }
}

static void test_closing_and_segment(void **state) {
    (void)state;
    for (double s = 1; s < 100; s *= 3.7) {
        ss_vec2 q[] = {{5, 5}, {5 + s, 5}, {5 + s, 5 + s}, {5, 5 + s}};
        ss_polygon sq = {4, q};
        assert_float_equal(ss_closing_distance(&sq), s * sqrt(2.0), 1e-12 * s);
    }
    ss_vec2 a = {0, 0}, b = {10, 0};
    assert_float_equal(ss_segment_distance(a, b, (ss_vec2){5, 3}), 3.0, 1e-15);   /* inside */
    assert_float_equal(ss_segment_distance(a, b, (ss_vec2){-3, 4}), 5.0, 1e-15);  /* before a */
    assert_float_equal(ss_segment_distance(a, b, (ss_vec2){13, -4}), 5.0, 1e-15); /* beyond b */
    assert_float_equal(ss_segment_distance(a, a, (ss_vec2){3, 4}), 5.0, 1e-15);   /* degenerate */
    assert_float_equal(ss_segment_distance((ss_vec2){1, 1}, (ss_vec2){4, 5}, (ss_vec2){5, -2}), 5.0,
                       1e-12); /* perpendicular foot at the start: distance to (1,1) */
}

static void edt_bruteforce(const ss_image *src, ss_image *out) {
    for (int y = 0; y < src->height; y++)
        for (int x = 0; x < src->width; x++) {
            double best = HUGE_VAL;
            for (int v = 0; v < src->height; v++)
                for (int u = 0; u < src->width; u++)
                    if (*ss_image_px(src, u, v) > 0.5f)
                        best = fmin(best, (double)(u - x) * (u - x) + (double)(v - y) * (v - y));
            *ss_image_px(out, x, y) = best == HUGE_VAL ? INFINITY : (float)sqrt(best);
        }
}

static void test_edt(void **state) {
    (void)state;
    ss_error err;
    for (uint64_t seed = 1; seed <= 5; seed++) {
        int W = 37 + (int)seed * 5, H = 29 + (int)seed * 7;
        double dens = seed == 1 ? 0.002 : 0.02 * (double)seed;
        ss_image *s = ss_image_create(W, H, 1, &err), *a = ss_image_create(W, H, 1, &err),
                 *b = ss_image_create(W, H, 1, &err), *c = ss_image_create(W, H, 1, &err);
        for (int i = 0; i < W * H; i++) s->data[i] = ss_rng_uniform(seed, 9, (uint64_t)i) < dens;
        s->data[W * H / 2] = 1.0f;
        omp_set_num_threads(1);
        assert_int_equal(ss_distance_transform(s, a, &err), SS_OK);
        omp_set_num_threads(2);
        assert_int_equal(ss_distance_transform(s, c, &err), SS_OK);
        edt_bruteforce(s, b);
        assert_memory_equal(a->data, b->data, sizeof(float) * (size_t)W * H);
        assert_memory_equal(a->data, c->data, sizeof(float) * (size_t)W * H);
        ss_image_free(s);
        ss_image_free(a);
        ss_image_free(b);
        ss_image_free(c);
    }
    /* No site: +inf everywhere; bad sizes refused. */
    ss_image *s = ss_image_create(9, 7, 1, &err), *a = ss_image_create(9, 7, 1, &err);
    assert_int_equal(ss_distance_transform(s, a, &err), SS_OK);
    for (int i = 0; i < 63; i++) assert_true(isinf(a->data[i]));
    ss_image *bad = ss_image_create(8, 7, 1, &err);
    assert_int_equal(ss_distance_transform(s, bad, &err), SS_ERR_INPUT);
    ss_image_free(s);
    ss_image_free(a);
    ss_image_free(bad);
}

static void compare_outline(const ss_polygon *polys, int np, int W, int H, double max_dist) {
    ss_error err;
    ss_image *a = ss_image_create(W, H, 1, &err), *b = ss_image_create(W, H, 1, &err),
             *c = ss_image_create(W, H, 1, &err);
    ss_outline_distance_bruteforce(polys, np, a);
    omp_set_num_threads(1);
    assert_int_equal(ss_outline_distance(polys, np, max_dist, b, &err), SS_OK);
    omp_set_num_threads(2);
    assert_int_equal(ss_outline_distance(polys, np, max_dist, c, &err), SS_OK);
    assert_memory_equal(b->data, c->data, sizeof(float) * (size_t)W * H);
    int within = 0;
    for (int i = 0; i < W * H; i++) {
        if (a->data[i] <= max_dist) {
            within++;
            if (a->data[i] != b->data[i])
                fail_msg("pixel %d: brute %.9g fast %.9g (max_dist %g)", i, a->data[i], b->data[i],
                         max_dist);
        } else {
            assert_true(b->data[i] > max_dist);
            assert_true(b->data[i] <= a->data[i]); /* a lower bound */
        }
    }
    assert_true(within > 0);
    ss_image_free(a);
    ss_image_free(b);
    ss_image_free(c);
}

static void test_outline_distance(void **state) {
    (void)state;
    ss_error err;
    const int q = tu_quick();
    const int W = q ? 67 : 131, H = q ? 53 : 97;
    for (uint64_t seed = 1; seed <= (q ? 2u : 4u); seed++) {
        int n = 50;
        ss_vec2 *p1 = random_points(n, 500 + seed, W * 0.35, H * 0.45, W * 0.3);
        ss_vec2 *p2 = random_points(n, 600 + seed, W * 0.8, H * 0.7, W * 0.25); /* spills out */
        ss_polygon polys[3];
        assert_int_equal(ss_convex_hull(p1, n, &polys[0], &err), SS_OK);
        assert_int_equal(ss_concave_hull(p2, n, 3, &polys[1], &err), SS_OK);
        int nl;
        ss_vec2 *L = l_points(&nl, W * 0.1 + (double)seed, H * 0.2, W * 0.05);
        assert_int_equal(ss_concave_hull(L, nl, 4, &polys[2], &err), SS_OK);
        compare_outline(&polys[0], 1, W, H, 6.0);        /* convex */
        compare_outline(&polys[1], 1, W, H, 15.5);       /* concave, partly outside */
        compare_outline(polys, 3, W, H, 3.0 + seed * 7); /* several */
        compare_outline(&polys[2], 1, W, H, INFINITY);   /* exact everywhere */
        for (int i = 0; i < 3; i++) ss_polygon_free(&polys[i]);
        free(p1);
        free(p2);
        free(L);
    }
    /* A huge triangle whose edges cross the image: exact within max_dist. */
    ss_vec2 big[] = {{-1e9, 20.3}, {1e9, 30.7}, {40.2, 1e9}};
    ss_polygon bigp = {3, big};
    compare_outline(&bigp, 1, 61, 47, 12.0);
    /* An outline entirely far outside: still exact with max_dist = inf. */
    ss_vec2 far[] = {{-500, -500}, {-400, -500}, {-450, -420}};
    ss_polygon fp = {3, far};
    compare_outline(&fp, 1, 31, 23, INFINITY);
    ss_image *d = ss_image_create(10, 10, 1, &err);
    assert_int_equal(ss_outline_distance(&fp, 1, -1.0, d, &err), SS_ERR_INPUT);
    assert_int_equal(ss_outline_distance(&fp, 1, NAN, d, &err), SS_ERR_INPUT);
    ss_image_free(d);
}

/* Three points that are collinear up to rounding: the turn tests disagree
 * between the two chains; must be an input error, not a buffer overrun. */
static void test_hull_nearly_collinear(void **state) {
    (void)state;
    const ss_vec2 pts[3] = {{3.2, 6.4}, {9.6, 12.8}, {0, 3.2}};
    ss_polygon h;
    ss_error err;
    ss_status st = ss_convex_hull(pts, 3, &h, &err);
    if (st == SS_OK) {
        assert_true(h.count >= 3);
        ss_polygon_free(&h);
    } else {
        assert_int_equal(st, SS_ERR_INPUT);
    }
}

/* Rounded corners (src/geom/round.c): a 100 px square with r = 20 keeps its
 * orientation, loses exactly (4 - pi) r^2 of area (the chords stray < 0.05 px
 * from the circles), every vertex is on an edge or r from a corner's centre;
 * fillets are clamped on a thin triangle (it stays inside the triangle);
 * radius 0 copies; a negative radius is an input error. */
static double shoelace(const ss_polygon *p) {
    double a = 0;
    for (int i = 0; i < p->count; i++) {
        ss_vec2 u = p->pts[i], v = p->pts[(i + 1) % p->count];
        a += u.x * v.y - v.x * u.y;
    }
    return 0.5 * a;
}

static void test_polygon_round(void **state) {
    (void)state;
    ss_error err;
    ss_vec2 sq[4] = {{0, 0}, {100, 0}, {100, 100}, {0, 100}};
    ss_polygon h, r;
    assert_int_equal(ss_convex_hull(sq, 4, &h, &err), SS_OK);
    assert_int_equal(ss_polygon_round(&h, 20, &r, &err), SS_OK);
    assert_true(r.count > 4 * 8);
    assert_true(shoelace(&r) > 0);
    assert_float_equal(shoelace(&r), 10000 - (4 - M_PI) * 400, 0.05 * 4 * 2 * M_PI * 20 / 4);
    for (int i = 0; i < r.count; i++) {
        ss_vec2 p = r.pts[i];
        double cx = p.x < 20 ? 20 : p.x > 80 ? 80 : p.x, cy = p.y < 20 ? 20 : p.y > 80 ? 80 : p.y;
        double d = hypot(p.x - cx, p.y - cy); /* from the inner square grown by r */
        assert_float_equal(d, 20, 1e-9);
        /* chords: the midpoint of each stays within 0.05 px of the circle */
        ss_vec2 q = r.pts[(i + 1) % r.count], m = {(p.x + q.x) / 2, (p.y + q.y) / 2};
        double mx = m.x < 20 ? 20 : m.x > 80 ? 80 : m.x, my = m.y < 20 ? 20 : m.y > 80 ? 80 : m.y;
        assert_true(hypot(m.x - mx, m.y - my) > 20 - 0.05 - 1e-9);
    }
    ss_polygon_free(&r);
    assert_int_equal(ss_polygon_round(&h, 0, &r, &err), SS_OK);
    assert_int_equal(r.count, h.count);
    for (int i = 0; i < h.count; i++) assert_memory_equal(&r.pts[i], &h.pts[i], sizeof(ss_vec2));
    ss_polygon_free(&r);
    assert_int_equal(ss_polygon_round(&h, -1, &r, &err), SS_ERR_INPUT);
    assert_int_equal(ss_polygon_round(&h, NAN, &r, &err), SS_ERR_INPUT);
    ss_polygon_free(&h);
    /* a thin streak: the tips are rounded with their own width, inside it */
    ss_vec2 th[3] = {{0, 0}, {100, 0}, {50, 4}};
    assert_int_equal(ss_convex_hull(th, 3, &h, &err), SS_OK);
    assert_int_equal(ss_polygon_round(&h, 50, &r, &err), SS_OK);
    double a0 = shoelace(&h), a1 = shoelace(&r);
    assert_true(a1 > 0.5 * a0 && a1 < a0);
    for (int i = 0; i < r.count; i++) {
        ss_vec2 p = r.pts[i];
        assert_true(p.y >= -1e-9 && p.y <= 4 * (1 - fabs(p.x - 50) / 50) + 1e-6);
    }
    ss_polygon_free(&r);
    ss_polygon_free(&h);
}

/* A rounded stroke has the same shape at every texture size: its footprint
 * covers the same fraction at 256 and 1024 (within the outline's pixels),
 * and less than the sharp hull does. */
static void test_stroke_round_sizes(void **state) {
    (void)state;
    ss_error err;
    ss_stroke_set s;
    assert_int_equal(ss_stroke_csv_parse("0.2,0.3\n0.7,0.2\n0.8,0.7\n0.3,0.8\n", "q.csv", &s, &err),
                     SS_OK);
    double frac[2], sharp = 0;
    const int sizes[2] = {256, 1024};
    for (int k = 0; k < 2; k++) {
        int n = sizes[k];
        ss_image *f = ss_stroke_footprint_rounded(&s, n, n, 0, SS_STROKE_ROUND, "q.csv", &err);
        assert_non_null(f);
        double a = 0;
        for (int i = 0; i < n * n; i++) a += f->data[i];
        frac[k] = a / ((double)n * n);
        ss_image_free(f);
    }
    ss_image *f = ss_stroke_footprint(&s, 1024, 1024, 0, "q.csv", &err);
    for (int i = 0; i < 1024 * 1024; i++) sharp += f->data[i];
    sharp /= 1024.0 * 1024.0;
    ss_image_free(f);
    assert_float_equal(frac[0], frac[1], 0.004);
    assert_true(frac[1] < sharp - 0.005);
    assert_null(ss_stroke_footprint_rounded(&s, 64, 64, 0, 0.7, "q.csv", &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    ss_stroke_set_free(&s);
}

/* The UV triangle rasteriser: two triangles making the UV square
 * [0.25, 0.75]^2 of a 16 x 16 texture visit exactly the 8 x 8 texels whose
 * centres lie in it, those on the shared diagonal twice, and their
 * barycentrics give back the texel centre; a degenerate triangle is skipped. */
typedef struct raster_log {
    int visits[16 * 16];
    double worst;
    const ss_mesh *m;
} raster_log;

static void raster_visit(int x, int y, int tri, double b0, double b1, double b2, void *ctx) {
    raster_log *l = ctx;
    l->visits[y * 16 + x]++;
    const uint32_t *ix = l->m->indices + 3 * tri;
    double u = b0 * l->m->uvs[2 * ix[0]] + b1 * l->m->uvs[2 * ix[1]] + b2 * l->m->uvs[2 * ix[2]];
    double v = b0 * l->m->uvs[2 * ix[0] + 1] + b1 * l->m->uvs[2 * ix[1] + 1] +
               b2 * l->m->uvs[2 * ix[2] + 1];
    l->worst = fmax(l->worst, fmax(fabs(u * 16 - (x + 0.5)), fabs(v * 16 - (y + 0.5))));
}

static void test_uv_raster(void **state) {
    (void)state;
    float pos[15] = {0},
          uv[10] = {0.25f, 0.25f, 0.75f, 0.25f, 0.75f, 0.75f, 0.25f, 0.75f, 0.5f, 0.5f};
    uint32_t idx[9] = {0, 1, 2, 0, 2, 3, 0, 2, 4}; /* the last one is degenerate in UV */
    ss_mesh m = {0};
    m.nvertices = 5, m.ntriangles = 3, m.positions = pos, m.uvs = uv, m.indices = idx;
    m.has_uvs = 1;
    raster_log l = {{0}, 0, &m};
    ss_uv_triangle_raster(&m, 16, 16, raster_visit, &l);
    for (int y = 0; y < 16; y++)
        for (int x = 0; x < 16; x++) {
            int in = x >= 4 && x < 12 && y >= 4 && y < 12;
            int expect = in ? (x == y ? 2 : 1) : 0;
            assert_int_equal(l.visits[y * 16 + x], expect);
        }
    assert_true(l.worst < 1e-6);
    unsigned char mask[16 * 16];
    ss_error err;
    assert_int_equal(ss_mesh_uv_coverage(&m, 16, 16, mask, &err), SS_OK);
    for (int i = 0; i < 16 * 16; i++) assert_int_equal(mask[i], l.visits[i] > 0);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hull_nearly_collinear), cmocka_unit_test(test_convex_hull),
        cmocka_unit_test(test_concave_hull),          cmocka_unit_test(test_fill),
        cmocka_unit_test(test_closing_and_segment),   cmocka_unit_test(test_edt),
        cmocka_unit_test(test_outline_distance),      cmocka_unit_test(test_polygon_round),
        cmocka_unit_test(test_stroke_round_sizes),    cmocka_unit_test(test_uv_raster),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
