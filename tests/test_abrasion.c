/* Abrasion timeline (seed 000 §3.2, §4.2-4.3): timeline arithmetic, stroke
 * parsing, shapes against brute-force geometry, the phases' seed colours and
 * Alg. 4.4 against a direct transcription, blending, scale invariance and
 * determinism across thread counts. */
#include "testutil.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/abrasion.h"
#include "skinsim/texture.h"

static char *write_tmp(const char *dir, const char *name, const char *text) {
    static char path[512];
    ss_error err;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    assert_int_equal(ss_write_file_atomic(path, text, strlen(text), &err), SS_OK);
    return path;
}

static void test_timeline_locate(void **state) {
    (void)state;
    ss_timeline t;
    ss_timeline_default(&t);
    ss_error err;
    assert_int_equal(ss_timeline_validate(&t, &err), SS_OK);
    /* At a key: that key. */
    ss_timeline_pos p = ss_timeline_locate(&t, 0.0);
    assert_int_equal(p.key_a, 0);
    assert_true(p.weight == 0.0);
    /* Halfway between two keys: weight 0.5. */
    double mid = 0.5 * (t.key[3].day + t.key[4].day);
    p = ss_timeline_locate(&t, mid);
    assert_int_equal(p.key_a, 3);
    assert_int_equal(p.key_b, 4);
    assert_float_equal(p.weight, 0.5, 1e-12);
    /* Between the two scab keys the phase is held (same phase both sides). */
    p = ss_timeline_locate(&t, 0.5 * (t.key[6].day + t.key[7].day));
    assert_int_equal(t.key[p.key_a].phase, SS_PHASE_SCAB);
    assert_int_equal(t.key[p.key_b].phase, SS_PHASE_SCAB);
    /* Maturation: position 0 at its key, 1 at the end, linear between. */
    double m0 = t.key[t.nkeys - 1].day;
    p = ss_timeline_locate(&t, m0);
    assert_true(p.in_maturation);
    assert_float_equal(p.maturation_pos, 0.0, 1e-12);
    p = ss_timeline_locate(&t, 0.5 * (m0 + t.end_day));
    assert_float_equal(p.maturation_pos, 0.5, 1e-12);
    p = ss_timeline_locate(&t, t.end_day + 100);
    assert_float_equal(p.maturation_pos, 1.0, 1e-12);
    /* The scab -> maturation jump is shorter than an hour. */
    assert_true(m0 - t.key[t.nkeys - 2].day < 1.0 / 24);
}

static void test_timeline_json(void **state) {
    (void)state;
    char *dir = tu_tmpdir("tl");
    ss_error err;
    ss_timeline t;
    const char *good =
        write_tmp(dir, "good.json",
                  "{\"keys\":[{\"phase\":\"vasoconstriction\",\"day\":0},"
                  "{\"phase\":\"scab\",\"day\":2},{\"phase\":\"maturation\",\"day\":4}],"
                  "\"end_day\":9}");
    assert_int_equal(ss_timeline_load_json(good, &t, &err), SS_OK);
    assert_int_equal(t.nkeys, 3);
    assert_int_equal(t.key[1].phase, SS_PHASE_SCAB);
    assert_float_equal(t.end_day, 9.0, 0);
    const char *bads[] = {
        "{\"keys\":[{\"phase\":\"bogus\",\"day\":0},{\"phase\":\"scab\",\"day\":1}]}",
        "{\"keys\":[{\"phase\":\"scab\",\"day\":2},{\"phase\":\"scab\",\"day\":1}]}",
        "{\"keys\":[{\"phase\":\"maturation\",\"day\":1},{\"phase\":\"scab\",\"day\":2}]}",
        "{\"keys\":[{\"phase\":\"scab\",\"day\":\"x\"}]}",
        "{\"end_day\":1}",
        "[1,2",
    };
    for (size_t i = 0; i < sizeof bads / sizeof bads[0]; i++) {
        const char *bad = write_tmp(dir, "bad.json", bads[i]);
        assert_int_equal(ss_timeline_load_json(bad, &t, &err), SS_ERR_INPUT);
        assert_non_null(strstr(err.msg, "bad.json"));
    }
    tu_rmtree(dir);
    free(dir);
}

static void test_strokes_csv(void **state) {
    (void)state;
    char *dir = tu_tmpdir("csv");
    ss_error err;
    ss_stroke_set s;
    const char *ok = write_tmp(dir, "ok.csv",
                               "u,v,stroke\n# comment\n0.1,0.2,0\n0.2,0.2,0\n0.2,0.3,0\n0.3, 0.4 "
                               ",1\r\n0.4,0.4,1\n0.4,0.5,1\n\n0.5,0.6\n0.6,0.6\n0.5,0.6\n");
    assert_int_equal(ss_stroke_csv_read(ok, &s, &err), SS_OK);
    assert_int_equal(s.npoints, 9);
    assert_int_equal(s.nstrokes, 2);
    assert_int_equal(s.stroke[3], 1);
    assert_float_equal(s.v[8], 0.6, 1e-12);
    ss_stroke_set_free(&s);
    const char *bads[] = {"0.1,0.2\n0.3,nan\n", "0.1,0.2\n1.5,0.2\n", "0.1,0.2\n-0.1,0.2\n",
                          "0.1,0.2\nfoo\n",     "0.1,0.2,1.5\n",      "",
                          "# only comments\n"};
    for (size_t i = 0; i < sizeof bads / sizeof bads[0]; i++) {
        const char *bad = write_tmp(dir, "bad.csv", bads[i]);
        assert_int_equal(ss_stroke_csv_read(bad, &s, &err), SS_ERR_INPUT);
        assert_non_null(strstr(err.msg, "bad.csv"));
    }
    assert_int_equal(ss_stroke_csv_read("/nonexistent.csv", &s, &err), SS_ERR_INPUT);
    tu_rmtree(dir);
    free(dir);
}

static ss_stroke_set square_strokes(double a, double b) {
    ss_stroke_set s = {0};
    s.npoints = 4;
    s.u = malloc(4 * sizeof(double));
    s.v = malloc(4 * sizeof(double));
    s.stroke = calloc(4, sizeof(int));
    s.stroke_ids = calloc(1, sizeof(int));
    s.nstrokes = 1;
    const double u[4] = {a, b, b, a}, v[4] = {a, a, b, b};
    memcpy(s.u, u, sizeof u);
    memcpy(s.v, v, sizeof v);
    return s;
}

static void test_shape_from_strokes(void **state) {
    (void)state;
    ss_error err;
    ss_stroke_set s = square_strokes(0.25, 0.75);
    ss_wound_shape *w;
    int n = 64;
    assert_int_equal(ss_wound_shape_from_strokes(&s, SS_HULL_CONVEX, 5, n, 1, &w, &err), SS_OK);
    /* A square of half the side: exactly a quarter of the pixels. */
    double area = 0;
    for (int i = 0; i < n * n; i++) area += w->mask->data[i];
    assert_float_equal(area, n * n / 4.0, 0);
    assert_int_equal(w->nwounds, 1);
    assert_float_equal(w->closing_px[0], 32 * sqrt(2.0), 1e-9);
    assert_true(w->inner_ratio[0] >= 0.4 && w->inner_ratio[0] <= 0.8);
    /* Distances equal the brute force over hull edges (Alg. 3.4's loop). */
    ss_image *bf = ss_image_create(n, n, 1, &err);
    ss_outline_distance_bruteforce(w->polys, w->npolys, bf);
    for (int i = 0; i < n * n; i++) assert_float_equal(w->dist->data[i], bf->data[i], 1e-4);
    ss_image_free(bf);
    ss_wound_shape_free(w);
    /* Two points only: a clear input error. */
    s.npoints = 2;
    assert_int_equal(ss_wound_shape_from_strokes(&s, SS_HULL_CONVEX, 5, n, 1, &w, &err),
                     SS_ERR_INPUT);
    ss_stroke_set_free(&s);
}

static void test_shape_from_mask(void **state) {
    (void)state;
    ss_error err;
    int n = 80;
    ss_image *m = ss_image_create(n, n, 1, &err);
    for (int y = 10; y < 30; y++)
        for (int x = 10; x < 30; x++) ss_image_px(m, x, y)[0] = 1;
    for (int y = 50; y < 70; y++)
        for (int x = 40; x < 75; x++) ss_image_px(m, x, y)[0] = 1;
    ss_wound_shape *w;
    assert_int_equal(ss_wound_shape_from_mask(m, n, 3, &w, &err), SS_OK);
    assert_int_equal(w->nwounds, 2);
    int l0 = w->label[20 * n + 20], l1 = w->label[60 * n + 50];
    assert_int_not_equal(l0, l1);
    assert_float_equal(w->closing_px[l0], 20 * sqrt(2.0), 1e-9);
    assert_float_equal(w->closing_px[l1], sqrt(35.0 * 35 + 20 * 20), 1e-9);
    /* The pixel just inside the edge is half a pixel from the outline. */
    assert_float_equal(w->dist->data[20 * n + 10], 0.5, 1e-6);
    assert_float_equal(w->dist->data[20 * n + 9], 0.5, 1e-6);
    assert_float_equal(w->dist->data[20 * n + 5], 4.5, 1e-6);
    ss_wound_shape_free(w);
    memset(m->data, 0, sizeof(float) * (size_t)(n * n));
    assert_int_equal(ss_wound_shape_from_mask(m, n, 3, &w, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "empty"));
    ss_image_free(m);
}

typedef struct scene {
    ss_wound_shape *w;
    ss_base_skin skin;
    ss_abrasion_settings s;
} scene;

static void scene_make(scene *sc, int n) {
    ss_error err;
    ss_stroke_set st;
    assert_int_equal(ss_abrasion_example_strokes(&st, &err), SS_OK);
    assert_int_equal(ss_wound_shape_from_strokes(&st, SS_HULL_CONVEX, 5, n, 7, &sc->w, &err),
                     SS_OK);
    ss_stroke_set_free(&st);
    assert_int_equal(ss_base_skin_create(NULL, NULL, n, 7, &sc->skin, &err), SS_OK);
    ss_abrasion_settings_default(&sc->s);
    sc->s.size = n;
    sc->s.seed = 7;
}

static void scene_free(scene *sc) {
    ss_wound_shape_free(sc->w);
    ss_base_skin_free(&sc->skin);
}

static void test_vasoconstriction_colours(void **state) {
    (void)state;
    scene sc;
    int n = 128;
    scene_make(&sc, n);
    ss_texture_set t;
    ss_error err;
    assert_int_equal(ss_texture_set_create(n, &t, &err), SS_OK);
    assert_int_equal(
        ss_abrasion_render_phase(SS_PHASE_VASOCONSTRICTION, 0, sc.w, &sc.skin, &sc.s, &t, &err),
        SS_OK);
    for (int i = 0; i < n * n; i++) {
        const ss_image *src = sc.w->mask->data[i] > 0.5f ? sc.skin.lower : sc.skin.upper;
        for (int c = 0; c < 3; c++)
            assert_float_equal(t.color->data[i * 3 + c], src->data[i * 3 + c], 2e-4);
    }
    ss_texture_set_free(&t);
    scene_free(&sc);
}

static void test_vasodilation_glow(void **state) {
    (void)state;
    scene sc;
    int n = 256;
    scene_make(&sc, n);
    ss_texture_set t;
    ss_error err;
    assert_int_equal(ss_texture_set_create(n, &t, &err), SS_OK);
    assert_int_equal(
        ss_abrasion_render_phase(SS_PHASE_VASODILATION, 0, sc.w, &sc.skin, &sc.s, &t, &err), SS_OK);
    float thick = 100.0f * n / 2048.0f;
    float red = ss_srgb_decode(0.79f);
    for (int i = 0; i < n * n; i++) {
        if (sc.w->mask->data[i] > 0.5f) {
            /* Inside the eroded wound: lower skin x (0.79, 0, 0): no green or blue. */
            continue;
        }
        float d = sc.w->dist->data[i];
        float enc_up = ss_srgb_encode(sc.skin.upper->data[i * 3]);
        if (d > thick) {
            assert_float_equal(t.color->data[i * 3], sc.skin.upper->data[i * 3], 2e-4);
        } else {
            /* Alg. 3.4: lerp from the glow red to the skin by d / thickness. */
            float want = ss_srgb_decode(0.79f + (enc_up - 0.79f) * d / thick);
            assert_float_equal(t.color->data[i * 3], want, 2e-4);
            if (d < 0.01f) assert_float_equal(t.color->data[i * 3], red, 2e-4);
        }
    }
    /* The scrape lines: the reflection inside is stretched along y, so it
     * varies much less down a column than along a row. */
    double dv = 0, dh = 0;
    for (int y = 1; y < n; y++)
        for (int x = 1; x < n; x++) {
            int i = y * n + x;
            if (sc.w->mask->data[i] < 0.5f || sc.w->mask->data[i - 1] < 0.5f ||
                sc.w->mask->data[i - n] < 0.5f)
                continue;
            dh += fabs(t.reflection->data[i] - t.reflection->data[i - 1]);
            dv += fabs(t.reflection->data[i] - t.reflection->data[i - n]);
        }
    assert_true(dv < 0.25 * dh);
    ss_texture_set_free(&t);
    scene_free(&sc);
}

/* Alg. 4.4 transcribed per pixel with the brute-force hull distance. */
static void test_maturation_matches_alg44(void **state) {
    (void)state;
    scene sc;
    int n = 96;
    scene_make(&sc, n);
    ss_error err;
    ss_image *bf = ss_image_create(n, n, 1, &err);
    ss_outline_distance_bruteforce(sc.w->polys, sc.w->npolys, bf);
    ss_texture_set t;
    assert_int_equal(ss_texture_set_create(n, &t, &err), SS_OK);
    const double positions[] = {0.0, 0.3, 0.7, 1.0};
    for (int k = 0; k < 4; k++) {
        double pos = positions[k];
        assert_int_equal(
            ss_abrasion_render_phase(SS_PHASE_MATURATION, pos, sc.w, &sc.skin, &sc.s, &t, &err),
            SS_OK);
        double closing = sc.w->closing_px[0], max_outer = closing * 0.5;
        double outer = max_outer * pos, inner = outer + max_outer * sc.w->inner_ratio[0];
        const float red[3] = {0.79f, 0, 0}, white[3] = {0.79f, 0.41f, 0.41f};
        for (int i = 0; i < n * n; i++) {
            float want[3];
            const float *skin = sc.skin.upper_srgb->data + i * 3;
            double d = bf->data[i];
            for (int c = 0; c < 3; c++) {
                if (sc.w->mask->data[i] < 0.5f || d <= outer)
                    want[c] = skin[c];
                else if (d <= inner)
                    want[c] = (float)(skin[c] + (red[c] - skin[c]) * (d - outer) / (inner - outer));
                else {
                    double v = (d - inner) / (closing * 0.5 - inner);
                    v = v < 0 ? 0 : v > 1 ? 1 : v;
                    want[c] = (float)(red[c] + (white[c] - red[c]) * v);
                }
                assert_float_equal(t.color->data[i * 3 + c], ss_srgb_decode(want[c]), 1e-3);
            }
        }
    }
    /* At the end of maturation the wound has closed: skin everywhere. */
    for (int i = 0; i < n * n * 3; i++)
        assert_float_equal(t.color->data[i], sc.skin.upper->data[i], 2e-4);
    ss_texture_set_free(&t);
    ss_image_free(bf);
    scene_free(&sc);
}

static void test_frames_blend(void **state) {
    (void)state;
    scene sc;
    int n = 64;
    scene_make(&sc, n);
    ss_timeline tl;
    ss_timeline_default(&tl);
    ss_abrasion *a;
    ss_error err;
    assert_int_equal(ss_abrasion_create(&sc.s, &tl, sc.w, &sc.skin, &a, &err), SS_OK);
    ss_texture_set f;
    assert_int_equal(ss_texture_set_create(n, &f, &err), SS_OK);
    /* Halfway between vasodilation (key 3) and scab-forming (key 4). */
    double mid = 0.5 * (tl.key[3].day + tl.key[4].day);
    assert_int_equal(ss_abrasion_frame(a, mid, &f, &err), SS_OK);
    const ss_texture_set *A = &a->phase[SS_PHASE_VASODILATION],
                         *B = &a->phase[SS_PHASE_SCAB_FORMING];
    for (int i = 0; i < n * n * 3; i++)
        assert_float_equal(f.color->data[i], 0.5f * (A->color->data[i] + B->color->data[i]), 1e-6);
    for (int i = 0; i < n * n; i++)
        assert_float_equal(f.height->data[i], 0.5f * (A->height->data[i] + B->height->data[i]),
                           1e-6);
    /* Inside a double key the phase holds. */
    assert_int_equal(ss_abrasion_frame(a, 0.5 * (tl.key[6].day + tl.key[7].day), &f, &err), SS_OK);
    assert_memory_equal(f.color->data, a->phase[SS_PHASE_SCAB].color->data,
                        sizeof(float) * (size_t)(n * n * 3));
    /* Normals stay unit length after blending. */
    assert_int_equal(ss_abrasion_frame(a, 0.5 * (tl.key[5].day + tl.key[6].day), &f, &err), SS_OK);
    for (int i = 0; i < n * n; i++) {
        double l = 0;
        for (int c = 0; c < 3; c++) l += pow(2 * f.normal->data[i * 3 + c] - 1, 2);
        assert_float_equal(l, 1.0, 1e-4);
    }
    /* In maturation, the frame re-renders maturation at its position. */
    double m0 = tl.key[tl.nkeys - 1].day, pos = 0.4;
    assert_int_equal(ss_abrasion_frame(a, m0 + pos * (tl.end_day - m0), &f, &err), SS_OK);
    ss_texture_set ref;
    assert_int_equal(ss_texture_set_create(n, &ref, &err), SS_OK);
    assert_int_equal(
        ss_abrasion_render_phase(SS_PHASE_MATURATION, pos, sc.w, &sc.skin, &sc.s, &ref, &err),
        SS_OK);
    for (int i = 0; i < n * n * 3; i++)
        assert_float_equal(f.color->data[i], ref.color->data[i], 1e-6);
    /* A colour-only frame (the slider's) equals the colour of the full one. */
    ss_image *col = ss_image_create(n, n, 3, &err);
    ss_texture_set only = {col, NULL, NULL, NULL};
    for (double day = 0.001; day < 40; day *= 3.7) {
        assert_int_equal(ss_abrasion_frame(a, day, &f, &err), SS_OK);
        assert_int_equal(ss_abrasion_frame(a, day, &only, &err), SS_OK);
        assert_memory_equal(col->data, f.color->data, sizeof(float) * (size_t)(n * n * 3));
    }
    ss_image_free(col);
    assert_int_equal(ss_abrasion_frame(a, NAN, &f, &err), SS_ERR_INPUT);
    assert_int_equal(ss_abrasion_frame(a, -1, &f, &err), SS_ERR_INPUT);
    ss_texture_set_free(&ref);
    ss_texture_set_free(&f);
    ss_abrasion_free(a);
    scene_free(&sc);
}

/* Repainting (new shape into the existing textures) gives the same keys as
 * a fresh timeline for that shape. */
static void test_update_equals_create(void **state) {
    (void)state;
    int n = 64;
    scene sc;
    scene_make(&sc, n);
    ss_error err;
    ss_timeline tl;
    ss_timeline_default(&tl);
    ss_abrasion *a, *b;
    assert_int_equal(ss_abrasion_create(&sc.s, &tl, sc.w, &sc.skin, &a, &err), SS_OK);
    ss_stroke_set sq = square_strokes(0.2, 0.6);
    ss_wound_shape *w2;
    assert_int_equal(ss_wound_shape_from_strokes(&sq, SS_HULL_CONVEX, 5, n, 7, &w2, &err), SS_OK);
    assert_int_equal(ss_abrasion_update(a, w2, &err), SS_OK);
    assert_int_equal(ss_abrasion_create(&sc.s, &tl, w2, &sc.skin, &b, &err), SS_OK);
    for (int ph = 0; ph < SS_PHASE_COUNT; ph++) {
        assert_memory_equal(a->phase[ph].color->data, b->phase[ph].color->data,
                            sizeof(float) * (size_t)(n * n * 3));
        assert_memory_equal(a->phase[ph].normal->data, b->phase[ph].normal->data,
                            sizeof(float) * (size_t)(n * n * 3));
    }
    ss_abrasion_free(a);
    ss_abrasion_free(b);
    ss_wound_shape_free(w2);
    ss_stroke_set_free(&sq);
    scene_free(&sc);
}

/* The same wound at two resolutions: the glow ring and the scab's red edge
 * cover the same fraction of the texture. */
static double red_fraction(int n, ss_phase ph) {
    scene sc;
    scene_make(&sc, n);
    ss_texture_set t;
    ss_error err;
    assert_int_equal(ss_texture_set_create(n, &t, &err), SS_OK);
    assert_int_equal(ss_abrasion_render_phase(ph, 0, sc.w, &sc.skin, &sc.s, &t, &err), SS_OK);
    double frac = 0;
    for (int i = 0; i < n * n; i++) {
        const float *c = t.color->data + i * 3;
        frac += c[0] > 2.5f * c[1] && sc.w->mask->data[i] < 0.5f;
    }
    ss_texture_set_free(&t);
    scene_free(&sc);
    return frac / ((double)n * n);
}

static void test_scale_invariance(void **state) {
    (void)state;
    double a = red_fraction(128, SS_PHASE_VASODILATION),
           b = red_fraction(256, SS_PHASE_VASODILATION);
    assert_true(a > 0.02);
    assert_float_equal(a, b, 0.1 * b);
}

static void test_thread_determinism(void **state) {
    (void)state;
    int n = tu_quick() ? 64 : 128;
    scene sc;
    scene_make(&sc, n);
    ss_error err;
    for (int ph = 0; ph < SS_PHASE_COUNT; ph++) {
        ss_texture_set t1, t2;
        assert_int_equal(ss_texture_set_create(n, &t1, &err), SS_OK);
        assert_int_equal(ss_texture_set_create(n, &t2, &err), SS_OK);
        ss_threads_set(1);
        assert_int_equal(
            ss_abrasion_render_phase((ss_phase)ph, 0.3, sc.w, &sc.skin, &sc.s, &t1, &err), SS_OK);
        ss_threads_set(2);
        assert_int_equal(
            ss_abrasion_render_phase((ss_phase)ph, 0.3, sc.w, &sc.skin, &sc.s, &t2, &err), SS_OK);
        assert_memory_equal(t1.color->data, t2.color->data, sizeof(float) * (size_t)(n * n * 3));
        assert_memory_equal(t1.height->data, t2.height->data, sizeof(float) * (size_t)(n * n));
        assert_memory_equal(t1.reflection->data, t2.reflection->data,
                            sizeof(float) * (size_t)(n * n));
        ss_texture_set_free(&t1);
        ss_texture_set_free(&t2);
    }
    scene_free(&sc);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_timeline_locate),    cmocka_unit_test(test_timeline_json),
        cmocka_unit_test(test_strokes_csv),        cmocka_unit_test(test_shape_from_strokes),
        cmocka_unit_test(test_shape_from_mask),    cmocka_unit_test(test_vasoconstriction_colours),
        cmocka_unit_test(test_vasodilation_glow),  cmocka_unit_test(test_maturation_matches_alg44),
        cmocka_unit_test(test_frames_blend),       cmocka_unit_test(test_scale_invariance),
        cmocka_unit_test(test_thread_determinism), cmocka_unit_test(test_update_equals_create),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
