/* paint: strokes painted by rays on the hand stay inside one UV island each
 * (checked against an independent UV-triangle lookup), a gesture that goes
 * around the hand is split at the seams, the brush ring makes a hull that
 * covers every painted centre, undo/clear, the CSV round trip through the
 * reader `skinsim abrasion` uses, and bad input (no UVs, UVs outside 0..1,
 * a file for another mesh). */
#include "testutil.h"
#include "skinsim/paint.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static ss_mesh hand;

static int setup(void **state) {
    (void)state;
    char p[4096];
    snprintf(p, sizeof p, "%s/data/meshes/generic-hand-left.glb", SKINSIM_SOURCE_DIR);
    ss_error err;
    return ss_mesh_load(p, &hand, &err) == SS_OK ? 0 : -1;
}

static int teardown(void **state) {
    (void)state;
    ss_mesh_free(&hand);
    return 0;
}

/* A ray from a circle around the hand's long (y) axis at height y, aimed at
 * the axis: angle a in radians. right/up: the ring plane. */
static void circle_ray(double a, double y, float o[3], float d[3], float right[3], float up[3]) {
    float c[3];
    for (int k = 0; k < 3; k++) c[k] = 0.5f * (hand.bbox_min[k] + hand.bbox_max[k]);
    o[0] = c[0] + 0.4f * (float)cos(a), o[1] = (float)y, o[2] = c[2] + 0.4f * (float)sin(a);
    d[0] = -(float)cos(a), d[1] = 0, d[2] = -(float)sin(a);
    right[0] = -(float)sin(a), right[1] = 0, right[2] = (float)cos(a);
    up[0] = 0, up[1] = 1, up[2] = 0;
}

static void test_paint_islands(void **state) {
    (void)state;
    ss_paint p;
    ss_error err = {0};
    assert_int_equal(ss_paint_create(&hand, 0.004, &p, &err), SS_OK);
    assert_int_equal(p.nislands, 3);
    double y = hand.bbox_min[1] + 0.7 * (hand.bbox_max[1] - hand.bbox_min[1]);
    /* One gesture all around the hand: must cross seams. */
    ss_paint_begin(&p);
    int hits = 0;
    for (int i = 0; i <= 360; i += 2) {
        float o[3], d[3], r[3], u[3];
        circle_ray(i * 3.14159265358979 / 180, y, o, d, r, u);
        hits += ss_paint_add(&p, o, d, r, u, NULL);
    }
    ss_paint_end(&p);
    assert_true(hits > 100);
    int islands_seen[3] = {0, 0, 0}, nstrokes = p.next_stroke;
    assert_true(nstrokes >= 2);
    for (int i = 0; i < p.n; i++) {
        const ss_paint_sample *s = &p.s[i];
        assert_int_equal(s->group, 0);
        islands_seen[s->island] = 1;
        /* Independent check: the triangle holding this UV is in the
         * stroke's island (all samples of a stroke share the island). */
        int t = ss_mesh_locate_uv(&hand, s->uv, NULL);
        assert_true(t >= 0);
        assert_int_equal(p.island[t], s->island);
        for (int j = 0; j < i; j++)
            if (p.s[j].stroke == s->stroke) {
                assert_int_equal(p.s[j].island, s->island);
                break;
            }
        /* The UV reproduces the surface point (Eq. 4.1-4.3 are consistent). */
        float pos[3];
        assert_true(ss_mesh_locate_uv(&hand, s->uv, pos) >= 0);
    }
    assert_true(islands_seen[0] + islands_seen[1] + islands_seen[2] >= 2);
    /* Consecutive strokes of the gesture are in different islands. */
    for (int i = 1; i < p.n; i++)
        if (p.s[i].stroke != p.s[i - 1].stroke)
            assert_int_not_equal(p.s[i].island, p.s[i - 1].island);

    /* Every stroke makes a hull; the footprint covers every sample. */
    ss_stroke_set set;
    int dropped = -1;
    assert_int_equal(ss_paint_to_strokes(&p, &set, &dropped, &err), SS_OK);
    assert_true(set.nstrokes >= 2);
    assert_int_equal(set.nstrokes + dropped, nstrokes);
    const int N = 512;
    ss_image *fp = ss_stroke_footprint(&set, N, N, 0, NULL, &err);
    assert_non_null(fp);
    for (int i = 0; i < set.npoints; i++) {
        int x = (int)(set.u[i] * N), yy = (int)(set.v[i] * N);
        if (x >= N) x = N - 1;
        if (yy >= N) yy = N - 1;
        /* on the hull outline a pixel centre may fall outside: look at the
         * 3x3 neighbourhood */
        int inside = 0;
        for (int dy = -1; dy <= 1; dy++)
            for (int dx = -1; dx <= 1; dx++) {
                int xx = x + dx, yv = yy + dy;
                if (xx >= 0 && xx < N && yv >= 0 && yv < N)
                    inside |= ss_image_px(fp, xx, yv)[0] > 0.5f;
            }
        assert_true(inside);
    }
    ss_image_free(fp);
    ss_stroke_set_free(&set);

    /* A click with the brush ring: one stroke with 9 distinct points. */
    ss_paint_clear(&p);
    assert_int_equal(p.n, 0);
    ss_paint_begin(&p);
    float o[3], d[3], r[3], u[3];
    circle_ray(1.0, y, o, d, r, u);
    ss_ray_hit h;
    assert_int_equal(ss_paint_add(&p, o, d, r, u, &h), 1);
    ss_paint_end(&p);
    assert_true(p.n >= 6);
    /* A second gesture, then undo removes only it. */
    int n1 = p.n;
    ss_paint_begin(&p);
    circle_ray(2.5, y, o, d, r, u);
    ss_paint_add(&p, o, d, r, u, NULL);
    ss_paint_end(&p);
    assert_true(p.n > n1);
    assert_int_equal(ss_paint_undo(&p), 1);
    assert_int_equal(p.n, n1);
    /* A miss adds nothing. */
    ss_paint_begin(&p);
    const float far[3] = {10, 10, 10}, dx[3] = {1, 0, 0};
    assert_int_equal(ss_paint_add(&p, far, dx, r, u, NULL), 0);
    ss_paint_end(&p);
    assert_int_equal(p.n, n1);

    /* CSV round trip through the abrasion reader. */
    char *dir = tu_tmpdir("paint");
    char path[4200];
    snprintf(path, sizeof path, "%s/strokes.csv", dir);
    assert_int_equal(ss_paint_save_csv(&p, path, &dropped, &err), SS_OK);
    ss_stroke_set back;
    assert_int_equal(ss_stroke_csv_read(path, &back, &err), SS_OK);
    assert_int_equal(back.npoints, p.n);
    assert_int_equal(back.nstrokes, 1);
    for (int i = 0; i < back.npoints; i++)
        assert_true(fabs(back.u[i] - p.s[i].uv[0]) < 1e-7 && fabs(back.v[i] - p.s[i].uv[1]) < 1e-7);
    ss_stroke_set_free(&back);
    /* Loading places the points back on the surface. */
    float pos0[3] = {p.s[0].pos[0], p.s[0].pos[1], p.s[0].pos[2]};
    int outside = -1;
    assert_int_equal(ss_paint_load_csv(&p, path, &outside, &err), SS_OK);
    assert_int_equal(outside, 0);
    assert_int_equal(p.n, n1);
    for (int k = 0; k < 3; k++) assert_true(fabsf(p.s[0].pos[k] - pos0[k]) < 1e-4f);
    /* A file for another mesh: UVs outside 0..1 are refused naming the line. */
    FILE *f = fopen(path, "w");
    fputs("u,v\n0.5,0.5\n1.5,0.2\n0.1,0.1\n", f);
    fclose(f);
    assert_int_equal(ss_paint_load_csv(&p, path, &outside, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "strokes.csv"));
    /* UVs inside 0..1 but where the hand has no triangle: loaded, counted. */
    f = fopen(path, "w");
    fputs("u,v\n0.001,0.001\n0.002,0.001\n0.001,0.002\n", f);
    fclose(f);
    assert_int_equal(ss_paint_load_csv(&p, path, &outside, &err), SS_OK);
    assert_int_equal(outside, 3);
    assert_true(isnan(p.s[0].pos[0]));
    /* Nothing painted: saving is an input error and writes nothing. */
    ss_paint_clear(&p);
    remove(path);
    assert_int_equal(ss_paint_save_csv(&p, path, &dropped, &err), SS_ERR_INPUT);
    assert_false(tu_file_exists(path));
    tu_rmtree(dir);
    free(dir);
    ss_paint_free(&p);
}

static void test_paint_no_uvs(void **state) {
    (void)state;
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint32_t idx[3] = {0, 1, 2};
    ss_mesh m;
    ss_error err = {0};
    assert_int_equal(ss_mesh_from_arrays(pos, NULL, NULL, 3, idx, 1, "tri", &m, &err), SS_OK);
    ss_paint p;
    assert_int_equal(ss_paint_create(&m, 0.01, &p, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "UVs"));
    assert_int_equal(ss_paint_create(&hand, -1, &p, &err), SS_ERR_INPUT);
    assert_int_equal(ss_paint_create(&hand, NAN, &p, &err), SS_ERR_INPUT);
    ss_mesh_free(&m);
}

/* A UV cut inside one island: a cylinder (radius 1, height 2) unwrapped
 * around its axis, u = angle / 2 pi, whose top cap joins every column (its
 * centre has one UV), so the u = 0 and u = 1 columns are one island. A short
 * stroke across the cut must become two strokes, each on its own side, and
 * no brush ring may reach across. */
static void test_paint_wrap_inside_island(void **state) {
    (void)state;
    enum { N = 32 };
    float pos[3 * (2 * (N + 1) + 1)], uv[2 * (2 * (N + 1) + 1)];
    uint32_t idx[3 * (2 * N + N)];
    int nv = 0, nt = 0;
    for (int row = 0; row < 2; row++)
        for (int i = 0; i <= N; i++) {
            double a = 2 * 3.14159265358979 * (i % N) / N;
            pos[3 * nv] = (float)cos(a), pos[3 * nv + 1] = (float)(2 * row - 1),
                    pos[3 * nv + 2] = (float)sin(a);
            uv[2 * nv] = (float)i / N, uv[2 * nv + 1] = 0.25f + 0.5f * (float)row;
            nv++;
        }
    int centre = nv;
    pos[3 * nv] = 0, pos[3 * nv + 1] = 1, pos[3 * nv + 2] = 0;
    uv[2 * nv] = 0.5f, uv[2 * nv + 1] = 0.95f;
    nv++;
    for (int i = 0; i < N; i++) {
        uint32_t b0 = (uint32_t)i, b1 = (uint32_t)i + 1, t0 = b0 + N + 1, t1 = b1 + N + 1;
        uint32_t tri[3][3] = {{b0, t0, b1}, {b1, t0, t1}, {t0, (uint32_t)centre, t1}};
        for (int k = 0; k < 3; k++, nt++) memcpy(idx + 3 * nt, tri[k], sizeof tri[k]);
    }
    ss_mesh m;
    ss_error err = {0};
    assert_int_equal(ss_mesh_from_arrays(pos, NULL, uv, nv, idx, nt, "cylinder", &m, &err), SS_OK);
    ss_paint p;
    assert_int_equal(ss_paint_create(&m, 0.05, &p, &err), SS_OK);
    assert_int_equal(p.nislands, 1);
    ss_paint_begin(&p);
    int hits = 0;
    for (int k = -6; k <= 6; k++) { /* 12 degrees either side of the cut at angle 0 */
        double a = k * 2.0 * 3.14159265358979 / 180;
        float o[3] = {3 * (float)cos(a), 0, 3 * (float)sin(a)};
        float d[3] = {-(float)cos(a), 0, -(float)sin(a)};
        float r[3] = {-(float)sin(a), 0, (float)cos(a)}, u[3] = {0, 1, 0};
        hits += ss_paint_add(&p, o, d, r, u, NULL);
    }
    ss_paint_end(&p);
    assert_int_equal(hits, 13);
    assert_true(p.next_stroke >= 2);
    for (int st = 0; st < p.next_stroke; st++) {
        float lo = 2, hi = -1;
        for (int i = 0; i < p.n; i++)
            if (p.s[i].stroke == st) {
                if (p.s[i].uv[0] < lo) lo = p.s[i].uv[0];
                if (p.s[i].uv[0] > hi) hi = p.s[i].uv[0];
            }
        if (hi < lo) continue;
        /* each stroke on one side of the cut: a few degrees wide, not the island */
        assert_true(hi - lo < 0.1f);
    }
    ss_stroke_set set;
    int dropped = 0;
    assert_int_equal(ss_paint_to_strokes(&p, &set, &dropped, &err), SS_OK);
    assert_true(set.nstrokes >= 2);
    ss_stroke_set_free(&set);
    ss_paint_free(&p);
    ss_mesh_free(&m);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_paint_islands),
        cmocka_unit_test(test_paint_no_uvs),
        cmocka_unit_test(test_paint_wrap_inside_island),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
