/* Abrasion timeline (seed 000 §3.2, §4.2-4.3): timeline arithmetic, stroke
 * parsing, shapes against brute-force geometry, the look a user relies on (a
 * bed of tissue colour with texture, no ring between glow and bed, rounded
 * maturation fronts, a faint scar at a year; on random strokes too), blending,
 * scale invariance and determinism across thread counts. */
#include "testutil.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/abrasion.h"
#include "skinsim/optics.h"
#include "skinsim/texture.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

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
    /* A square of half the side with its corners rounded by SS_STROKE_ROUND
     * of its diagonal: a quarter of the pixels less (4 - pi) r^2, and the
     * closing distance across the rounded corners. */
    double area = 0, r = SS_STROKE_ROUND * 32 * sqrt(2.0);
    for (int i = 0; i < n * n; i++) area += w->mask->data[i];
    assert_float_equal(area, n * n / 4.0 - (4 - M_PI) * r * r, 6);
    assert_true(area < n * n / 4.0 - 20); /* the corners are gone */
    assert_int_equal(w->nwounds, 1);
    assert_float_equal(w->closing_px[0], (32 - 2 * r) * sqrt(2.0) + 2 * r, 0.1);
    assert_true(w->inner_ratio[0] >= 0.4 && w->inner_ratio[0] <= 0.8);
    /* Distances equal the brute force over hull edges (Alg. 3.4's loop)
     * within the range they are exact in (half the closing distance; beyond
     * it, at the image's corners, a lower bound above that) */
    ss_image *bf = ss_image_create(n, n, 1, &err);
    ss_outline_distance_bruteforce(w->polys, w->npolys, bf);
    int exact = 0;
    for (int i = 0; i < n * n; i++)
        if (bf->data[i] <= 0.5 * w->closing_px[0]) {
            assert_float_equal(w->dist->data[i], bf->data[i], 1e-4);
            exact++;
        } else
            assert_true(w->dist->data[i] > 0.5 * w->closing_px[0]);
    assert_true(exact > n * n * 9 / 10);
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

/* Random strokes the look was not tuned on: one wound of 7-12 points around a
 * random centre with random radii (counter-based RNG, so the same each run). */
static ss_stroke_set random_strokes(uint64_t seed) {
    int np = 7 + (int)(6 * ss_rng_uniform(seed, 1, 0));
    ss_stroke_set s = {0};
    s.npoints = np;
    s.nstrokes = 1;
    s.u = calloc((size_t)np, sizeof *s.u);
    s.v = calloc((size_t)np, sizeof *s.v);
    s.stroke = calloc((size_t)np, sizeof *s.stroke);
    s.stroke_ids = calloc(1, sizeof *s.stroke_ids);
    double cx = 0.4 + 0.2 * ss_rng_uniform(seed, 2, 0), cy = 0.4 + 0.2 * ss_rng_uniform(seed, 2, 1);
    for (int i = 0; i < np; i++) {
        double a = 2 * M_PI * (i + 0.6 * ss_rng_uniform(seed, 3, (uint64_t)i)) / np;
        double r = 0.08 + 0.12 * ss_rng_uniform(seed, 4, (uint64_t)i);
        s.u[i] = cx + r * cos(a);
        s.v[i] = cy + r * sin(a);
    }
    return s;
}

static void scene_from(scene *sc, const ss_stroke_set *st, int n, double world_cm) {
    ss_error err;
    assert_int_equal(ss_wound_shape_from_strokes(st, SS_HULL_CONVEX, 5, n, 7, &sc->w, &err), SS_OK);
    assert_int_equal(ss_base_skin_create(NULL, NULL, n, 7, &sc->skin, &err), SS_OK);
    ss_abrasion_settings_default(&sc->s);
    sc->s.size = n;
    sc->s.seed = 7;
    sc->s.world_size_cm = world_cm;
}

/* Trial 0 of a look test: the seed's example scrape; trial k > 0: random
 * strokes (seed base + k) on a 10 cm patch. */
static void scene_trial(scene *sc, int n, int trial, uint64_t seed_base) {
    if (trial == 0) {
        scene_make(sc, n);
        return;
    }
    ss_stroke_set st = random_strokes(seed_base + (uint64_t)trial);
    scene_from(sc, &st, n, 10);
    ss_stroke_set_free(&st);
}

/* Every map of two texture sets of the same size equal, bit for bit. */
static void assert_sets_equal(const ss_texture_set *a, const ss_texture_set *b) {
    size_t n1 = sizeof(float) * (size_t)a->color->width * (size_t)a->color->height;
    assert_int_equal(a->color->width, b->color->width);
    assert_memory_equal(a->color->data, b->color->data, 3 * n1);
    assert_memory_equal(a->reflection->data, b->reflection->data, n1);
    assert_memory_equal(a->height->data, b->height->data, n1);
    assert_memory_equal(a->normal->data, b->normal->data, 3 * n1);
}

static double lum3(const float *c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }
static int enc8(float v) { return (int)lroundf(255.0f * ss_srgb_encode(v)); }

/* The bed is tissue, not paint: on the fresh, bleeding and exuding phases its
 * green and blue stay above a floor (the seed's bed is (0.79, 0, 0) x skin:
 * G = B = 0), it has texture (capillary loops, bleeding, fibrin: a spread of
 * luminance), and it is wetter (more reflective) than the skin. On the
 * example scrape and on random strokes. */
static void test_bed_is_tissue(void **state) {
    (void)state;
    int n = 256;
    for (int trial = 0; trial < 4; trial++) {
        scene sc;
        scene_trial(&sc, n, trial, 100);
        ss_texture_set t;
        ss_error err;
        assert_int_equal(ss_texture_set_create(n, &t, &err), SS_OK);
        const ss_phase ph[3] = {SS_PHASE_VASOCONSTRICTION, SS_PHASE_VASODILATION,
                                SS_PHASE_SCAB_FORMING};
        for (int k = 0; k < 3; k++) {
            assert_int_equal(ss_abrasion_render_phase(ph[k], 0, sc.w, &sc.skin, &sc.s, &t, &err),
                             SS_OK);
            double g = 0, b = 0, l = 0, l2 = 0, refl = 0, cnt = 0;
            for (int i = 0; i < n * n; i++) {
                if (sc.w->mask->data[i] < 0.5f || sc.w->dist->data[i] < 4) continue;
                const float *c = t.color->data + i * 3;
                g += enc8(c[1]), b += enc8(c[2]);
                l += lum3(c), l2 += lum3(c) * lum3(c), refl += t.reflection->data[i], cnt++;
            }
            assert_true(cnt > 100);
            g /= cnt, b /= cnt, l /= cnt, refl /= cnt;
            double sd = sqrt(fmax(0, l2 / cnt - l * l));
            printf("phase %d trial %d: bed mean G %.0f B %.0f, luminance sd/mean %.3f, "
                   "reflection %.2f\n",
                   (int)ph[k], trial, g, b, sd / l, refl);
            assert_true(g > 25 && b > 15);
            assert_true(sd / l > 0.04);
            assert_true(refl > 0.35);
        }
        ss_texture_set_free(&t);
        scene_free(&sc);
    }
}

/* No ring between the glow and the bed (the seed's half-scraped edge was a
 * band of skin colour, 1-6 px, between the red glow and the red bed): along
 * rays through the outline, no texel between the glow 1.5 mm outside and the
 * bed 0.7 mm inside is lighter than both (the colour runs from one to the
 * other). */
static void test_no_ring(void **state) {
    (void)state;
    int n = 512;
    for (int trial = 0; trial < 3; trial++) {
        scene sc;
        scene_trial(&sc, n, trial, 200);
        ss_texture_set t;
        ss_error err;
        assert_int_equal(ss_texture_set_create(n, &t, &err), SS_OK);
        double cx = sc.w->box_x + 0.5 * sc.w->box_w, cy = sc.w->box_y + 0.5 * sc.w->box_h;
        double px_mm = n / (sc.s.world_size_cm * 10);
        for (int ph = SS_PHASE_VASOCONSTRICTION; ph <= SS_PHASE_SCAB; ph++) {
            assert_int_equal(
                ss_abrasion_render_phase((ss_phase)ph, 0, sc.w, &sc.skin, &sc.s, &t, &err), SS_OK);
            double worst = 0;
            for (int r = 0; r < 90; r++) {
                double a = 2 * M_PI * r / 90, dx = cos(a), dy = sin(a);
                /* from the centre outwards to the first pixel outside the mask */
                double rr = 0;
                while (rr < n) {
                    int x = (int)(cx + rr * dx), y = (int)(cy + rr * dy);
                    if (x < 0 || y < 0 || x >= n || y >= n) break;
                    if (sc.w->mask->data[y * n + x] < 0.5f) break;
                    rr += 0.5;
                }
                /* the glow 1.5 mm outside, the bed 0.7-1.2 mm inside (its brightest
                 * texel), and between them no band lighter than both */
                double l_out = -1, l_in = -1;
                for (double q = rr + 1.5 * px_mm; q > rr - 1.2 * px_mm; q -= 0.5) {
                    int x = (int)(cx + q * dx), y = (int)(cy + q * dy);
                    if (x < 0 || y < 0 || x >= n || y >= n) continue;
                    double l = lum3(t.color->data + (size_t)(y * n + x) * 3);
                    if (l_out < 0) l_out = l;
                    if (q < rr - 0.7 * px_mm) l_in = fmax(l_in, l);
                }
                for (double q = rr + 1.5 * px_mm; q > rr - 0.7 * px_mm; q -= 0.5) {
                    int x = (int)(cx + q * dx), y = (int)(cy + q * dy);
                    if (x < 0 || y < 0 || x >= n || y >= n || l_in < 0) continue;
                    double l = lum3(t.color->data + (size_t)(y * n + x) * 3);
                    worst = fmax(worst, l - fmax(l_out, l_in));
                }
            }
            printf("phase %d trial %d: ring (luminance above both glow and bed) %.3f\n", ph, trial,
                   worst);
            /* the seed's ring: #D3A489 between #CA0201 and #9C0000, 0.35 above both */
            assert_true(worst < 0.05);
        }
        ss_texture_set_free(&t);
        scene_free(&sc);
    }
}

/* Maturation's fronts come from the smoothed distance: on a square wound the
 * raw distance has a crease along the diagonals (its second difference across
 * them is ~1 per pixel), the smoothed one none, so there are no straight
 * ridge lines from the corners to the centre. */
static void test_maturation_no_ridges(void **state) {
    (void)state;
    int n = 256;
    ss_error err;
    ss_stroke_set sq = square_strokes(0.25, 0.75);
    ss_wound_shape *w;
    assert_int_equal(ss_wound_shape_from_strokes(&sq, SS_HULL_CONVEX, 5, n, 7, &w, &err), SS_OK);
    double raw = 0, smooth = 0;
    for (int y = 2; y < n - 2; y++)
        for (int x = 2; x < n - 2; x++) {
            int i = y * n + x;
            if (w->mask->data[i] < 0.5f || w->dist->data[i] < 8) continue;
            const float *d = w->dist->data, *s = w->smooth->data;
            double lr = d[i - 1] + d[i + 1] + d[i - n] + d[i + n] - 4 * d[i];
            double ls = s[i - 1] + s[i + 1] + s[i - n] + s[i + n] - 4 * s[i];
            raw = fmax(raw, fabs(lr));
            smooth = fmax(smooth, fabs(ls));
        }
    printf("largest |Laplacian| inside the square: raw distance %.3f, smoothed %.3f\n", raw,
           smooth);
    assert_true(raw > 0.5);
    assert_true(smooth < 0.15);
    ss_wound_shape_free(w);
    ss_stroke_set_free(&sq);
}

/* The maturation story: red granulation early, pink new epithelium, and a
 * faint scar that is still there at a year (the seed returns to plain skin by
 * day 30): mean CIEDE2000 against the skin over the wound 1 < dE < 12 at day
 * 365, redder (a*) at day 12 than at day 365; on random strokes too. */
static void test_scar_at_a_year(void **state) {
    (void)state;
    int n = 128;
    for (int trial = 0; trial < 3; trial++) {
        scene sc;
        scene_trial(&sc, n, trial, 300);
        ss_timeline tl;
        ss_timeline_default(&tl);
        ss_abrasion *a;
        ss_error err;
        assert_int_equal(ss_abrasion_create(&sc.s, &tl, sc.w, &sc.skin, &a, &err), SS_OK);
        ss_texture_set f;
        assert_int_equal(ss_texture_set_create(n, &f, &err), SS_OK);
        const double days[3] = {12, 20, 365};
        double de[3] = {0}, astar[3] = {0};
        for (int k = 0; k < 3; k++) {
            assert_int_equal(ss_abrasion_frame(a, days[k], &f, &err), SS_OK);
            double cnt = 0;
            for (int i = 0; i < n * n; i++) {
                if (sc.w->mask->data[i] < 0.5f || sc.w->dist->data[i] < 3) continue;
                double c1[3], c2[3], l1[3], l2[3];
                for (int c = 0; c < 3; c++)
                    c1[c] = f.color->data[i * 3 + c], c2[c] = sc.skin.upper->data[i * 3 + c];
                ss_srgb_linear_to_lab(c1, l1);
                ss_srgb_linear_to_lab(c2, l2);
                de[k] += ss_ciede2000(l1, l2);
                astar[k] += l1[1] - l2[1];
                cnt++;
            }
            de[k] /= cnt, astar[k] /= cnt;
        }
        printf("trial %d: dE00 to skin day 12 %.2f, day 20 %.2f, day 365 %.2f; a* - skin "
               "%.2f %.2f %.2f\n",
               trial, de[0], de[1], de[2], astar[0], astar[1], astar[2]);
        assert_true(de[2] > 1.0 && de[2] < 12.0);
        assert_true(astar[0] > astar[2] + 3);
        assert_true(de[0] > de[2]);
        ss_texture_set_free(&f);
        ss_abrasion_free(a);
        scene_free(&sc);
    }
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
    assert_int_equal(ss_abrasion_maturation_at(sc.w, &sc.skin, &sc.s, pos, tl.end_day - m0, 0,
                                               ref.color, NULL, &err),
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
        assert_sets_equal(&a->phase[ph], &b->phase[ph]);
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
        const float *u = sc.skin.upper->data + i * 3;
        /* reddened (the erythema of the glow): red over green up by 5 % */
        frac += c[0] * u[1] > 1.05f * c[1] * u[0] && sc.w->mask->data[i] < 0.5f;
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
        assert_sets_equal(&t1, &t2);
        ss_texture_set_free(&t1);
        ss_texture_set_free(&t2);
    }
    scene_free(&sc);
}

/* ss_abrasion_frame_poll in a blend and in maturation: cancelled at the
 * first poll, SS_ERR_RUNTIME "cancelled"; never stopped, the plain frame. */
static void test_frame_cancel(void **state) {
    (void)state;
    scene sc;
    int n = 64;
    scene_make(&sc, n);
    ss_timeline tl;
    ss_timeline_default(&tl);
    ss_abrasion *a;
    ss_error err;
    assert_int_equal(ss_abrasion_create(&sc.s, &tl, sc.w, &sc.skin, &a, &err), SS_OK);
    ss_texture_set f, g;
    assert_int_equal(ss_texture_set_create(n, &f, &err), SS_OK);
    assert_int_equal(ss_texture_set_create(n, &g, &err), SS_OK);
    const double m0 = tl.key[tl.nkeys - 1].day;
    const double days[2] = {0.5 * (tl.key[3].day + tl.key[4].day), m0 + 0.4 * (tl.end_day - m0)};
    for (int k = 0; k < 2; k++) {
        tu_poll stop = {0, 1, 0}, go = {0, 0, 0};
        assert_int_equal(ss_abrasion_frame_poll(a, days[k], &g, tu_poll_count, &stop, &err),
                         SS_ERR_RUNTIME);
        assert_non_null(strstr(err.msg, "cancelled"));
        assert_int_equal(stop.calls, 1);
        assert_int_equal(ss_abrasion_frame(a, days[k], &f, &err), SS_OK);
        assert_int_equal(ss_abrasion_frame_poll(a, days[k], &g, tu_poll_count, &go, &err), SS_OK);
        assert_true(go.calls >= 2 && go.last == 1.0);
        assert_sets_equal(&f, &g);
    }
    ss_texture_set_free(&f);
    ss_texture_set_free(&g);
    ss_abrasion_free(a);
    scene_free(&sc);
}

/* Dark skin (issue 24): the healing patch follows the skin's own melanin.
 * The example scrape on the default skin darkened to a brown skin; at days
 * 20 and 30 the healed ring (inside the outline, away from the still-open
 * core) is within 8 L* of the skin around it and at most 7 units of chroma
 * more saturated (the melanin change as a multiplier per channel drew a
 * light, saturated orange-tan patch). */
static void test_dark_skin_maturation(void **state) {
    (void)state;
    int n = 96;
    scene sc;
    scene_make(&sc, n);
    ss_error err;
    /* the same skin texture at a brown skin's mean colour (linear sRGB) */
    const double dark[3] = {0.11, 0.045, 0.025};
    double mean[3] = {0, 0, 0};
    for (int i = 0; i < n * n; i++)
        for (int c = 0; c < 3; c++) mean[c] += sc.skin.upper->data[i * 3 + c] / (n * n);
    ss_image *up = ss_image_create(n, n, 3, &err);
    assert_non_null(up);
    for (int i = 0; i < n * n; i++)
        for (int c = 0; c < 3; c++)
            up->data[i * 3 + c] = (float)(sc.skin.upper->data[i * 3 + c] * dark[c] / mean[c]);
    ss_base_skin_free(&sc.skin);
    assert_int_equal(ss_base_skin_create(up, NULL, n, 7, &sc.skin, &err), SS_OK);
    ss_image_free(up);
    assert_true(sc.skin.palette->pih_prevalence > 0.4f);
    ss_timeline tl;
    ss_timeline_default(&tl);
    ss_abrasion *a;
    assert_int_equal(ss_abrasion_create(&sc.s, &tl, sc.w, &sc.skin, &a, &err), SS_OK);
    ss_texture_set f;
    assert_int_equal(ss_texture_set_create(n, &f, &err), SS_OK);
    const double days[2] = {20, 30};
    for (int k = 0; k < 2; k++) {
        assert_int_equal(ss_abrasion_frame(a, days[k], &f, &err), SS_OK);
        double cw = 0, cs = 0, lw = 0, ls = 0, nw = 0, ns = 0;
        double dmax = 0;
        for (int i = 0; i < n * n; i++)
            if (sc.w->mask->data[i] > 0.5f) dmax = fmax(dmax, sc.w->dist->data[i]);
        for (int i = 0; i < n * n; i++) {
            double rgb[3], lab[3], chroma, hue, ita;
            for (int c = 0; c < 3; c++) rgb[c] = f.color->data[i * 3 + c];
            ss_srgb_linear_to_lab(rgb, lab);
            ss_lab_describe(lab, &chroma, &hue, &ita);
            int inside = sc.w->mask->data[i] > 0.5f;
            float d = sc.w->dist->data[i];
            if (inside && d >= 2 && d < 0.25 * dmax) /* the healed ring, not the open core */
                cw += chroma, lw += lab[0], nw++;
            else if (!inside && d > 8)
                cs += chroma, ls += lab[0], ns++;
        }
        assert_true(nw > 0 && ns > 0);
        cw /= nw, cs /= ns, lw /= nw, ls /= ns;
        printf("dark skin day %g: healed ring L* %.1f chroma %.1f, skin L* %.1f chroma %.1f\n",
               days[k], lw, cw, ls, cs);
        /* lighter pink-tan, then darker: not the light orange-tan (old: L* +21,
         * chroma +7.4 at day 20) */
        assert_true(fabs(lw - ls) < 8.0);
        assert_true(cw - cs < 7.0);
    }
    ss_texture_set_free(&f);
    ss_abrasion_free(a);
    scene_free(&sc);
}

/* The example scrape (trial 0) or a random one on the default skin, its
 * texture scaled to the mean colour dark (linear sRGB); dark = NULL keeps
 * the light skin. */
static void scene_skin(scene *sc, int n, int trial, const double *dark) {
    scene_trial(sc, n, trial, 300);
    if (!dark) return;
    ss_error err;
    double mean[3] = {0, 0, 0};
    for (int i = 0; i < n * n; i++)
        for (int c = 0; c < 3; c++) mean[c] += sc->skin.upper->data[i * 3 + c] / (n * n);
    ss_image *up = ss_image_create(n, n, 3, &err);
    assert_non_null(up);
    for (int i = 0; i < n * n; i++)
        for (int c = 0; c < 3; c++)
            up->data[i * 3 + c] = (float)(sc->skin.upper->data[i * 3 + c] * dark[c] / mean[c]);
    ss_base_skin_free(&sc->skin);
    assert_int_equal(ss_base_skin_create(up, NULL, n, 7, &sc->skin, &err), SS_OK);
    ss_image_free(up);
}

static const double DARK_SKIN[3] = {0.11, 0.045, 0.025}; /* a brown skin's mean, linear */

/* Mean CIELAB of a frame's colour where sel(mask, dist / dmax) holds. */
typedef int (*px_sel)(int inside, double d, double rel);
static void frame_lab(const ss_abrasion *a, const scene *sc, double day, px_sel sel,
                      double lab[3]) {
    int n = sc->s.size;
    ss_error err;
    ss_texture_set f;
    assert_int_equal(ss_texture_set_create(n, &f, &err), SS_OK);
    assert_int_equal(ss_abrasion_frame(a, day, &f, &err), SS_OK);
    double dmax = 0, cnt = 0;
    for (int i = 0; i < n * n; i++)
        if (sc->w->mask->data[i] > 0.5f) dmax = fmax(dmax, sc->w->dist->data[i]);
    lab[0] = lab[1] = lab[2] = 0;
    for (int i = 0; i < n * n; i++) {
        int inside = sc->w->mask->data[i] > 0.5f;
        double d = sc->w->dist->data[i];
        if (!sel(inside, d, d / dmax)) continue;
        double rgb[3], l[3];
        for (int c = 0; c < 3; c++) rgb[c] = f.color->data[i * 3 + c];
        ss_srgb_linear_to_lab(rgb, l);
        for (int c = 0; c < 3; c++) lab[c] += l[c];
        cnt++;
    }
    assert_true(cnt > 0);
    for (int c = 0; c < 3; c++) lab[c] /= cnt;
    ss_texture_set_free(&f);
}
static int sel_bed(int inside, double d, double rel) {
    (void)rel;
    return inside && d >= 4;
}
static int sel_core(int inside, double d, double rel) {
    (void)d;
    return inside && rel > 0.8;
}
static int sel_skin(int inside, double d, double rel) {
    (void)rel;
    return !inside && d > 8;
}
static double hue_deg(const double lab[3]) { return atan2(lab[2], lab[1]) * 180 / M_PI; }

/* Light and dark skin (CIELAB means over regions): the day-0 bed is exposed,
 * blood-filled dermis, deep red and the same on both (no epidermal melanin;
 * it was a pale pink L* 68.5, a* 19.9, then salmon pink L* 56.8, a* 27.3;
 * now L* 45.4, a* 33.3); at a year the wound is a faint scar, still paler
 * than dark skin around it (L* +2..+10), within dE 10 of light skin. Printed
 * too: the open core's granulation at days 12 and 20 (on dark skin it was
 * orange at day 20, hue 47 against 38; test_dark_skin_new_epithelium). */
static void test_dark_skin_bed_and_scar(void **state) {
    (void)state;
    int n = 128;
    double bed[2][3];
    for (int dk = 0; dk < 2; dk++) {
        scene sc;
        scene_skin(&sc, n, 0, dk ? DARK_SKIN : NULL);
        ss_timeline tl;
        ss_timeline_default(&tl);
        ss_abrasion *a;
        ss_error err;
        assert_int_equal(ss_abrasion_create(&sc.s, &tl, sc.w, &sc.skin, &a, &err), SS_OK);
        const char *name[5] = {"day 0 bed", "day 12 granulation", "day 20 granulation",
                               "day 365 wound", "skin"};
        const double day[5] = {0, 12, 20, 365, 365};
        px_sel sel[5] = {sel_bed, sel_core, sel_core, sel_bed, sel_skin};
        double lab[5][3];
        for (int k = 0; k < 5; k++) {
            frame_lab(a, &sc, day[k], sel[k], lab[k]);
            printf("%s skin %-19s L* %5.1f a* %5.1f b* %5.1f hue %5.1f\n", dk ? "dark " : "light",
                   name[k], lab[k][0], lab[k][1], lab[k][2], hue_deg(lab[k]));
        }
        memcpy(bed[dk], lab[0], sizeof bed[dk]);
        assert_true(lab[0][0] < 50.0);       /* deep, not salmon pink */
        assert_true(lab[0][1] > 30.0);       /* red */
        assert_true(hue_deg(lab[0]) < 32.0); /* not orange or tan */
        double dl = lab[3][0] - lab[4][0];
        double de = sqrt(dl * dl + (lab[3][1] - lab[4][1]) * (lab[3][1] - lab[4][1]) +
                         (lab[3][2] - lab[4][2]) * (lab[3][2] - lab[4][2]));
        if (dk) assert_true(dl > 2.0 && dl < 10.0); /* a faint, paler scar */
        assert_true(de < 10.0);
        ss_abrasion_free(a);
        scene_free(&sc);
    }
    for (int c = 0; c < 3; c++) assert_true(fabs(bed[0][c] - bed[1][c]) < 3.0);
}

static int sel_ring(int inside, double d, double rel) { return inside && d >= 2 && rel < 0.3; }
static double chroma_of(const double lab[3]) { return hypot(lab[1], lab[2]); }

/* New epithelium at the closing front, light and dark skin (the example
 * scrape and one random stroke): on dark skin a pink-brown, not orange. Drawn
 * as the optics' own colour of a thin epidermis at the ring's melanin over
 * hyperaemic dermis; as a multiplier of the dark skin texture it was an
 * orange ring round the pink-red core at day 12 (ring b* 11.5 above the
 * skin's, hue 51 at the skin's own 51.5 and 21 deg above the core's) and an
 * orange-brown patch and core at day 20 (hue 48 and 47-50). Checked on dark
 * skin at days 12 and 20: the ring no more than 7 b* units yellower than the
 * skin and its hue 5 deg below the skin's (redder), the day-20 core's hue too,
 * the day-12 ring's hue within 18 deg of the core's; on light skin the ring
 * pink (hue 10 deg below the skin's) and lighter than the red core. */
static void test_dark_skin_new_epithelium(void **state) {
    (void)state;
    int n = 128;
    for (int trial = 0; trial < 2; trial++) {
        double ring[2][2][3], core[2][2][3], skin[2][3];
        const double day[2] = {12, 20};
        for (int dk = 0; dk < 2; dk++) {
            scene sc;
            scene_skin(&sc, n, trial, dk ? DARK_SKIN : NULL);
            ss_timeline tl;
            ss_timeline_default(&tl);
            ss_abrasion *a;
            ss_error err;
            assert_int_equal(ss_abrasion_create(&sc.s, &tl, sc.w, &sc.skin, &a, &err), SS_OK);
            frame_lab(a, &sc, 20, sel_skin, skin[dk]);
            for (int k = 0; k < 2; k++) {
                frame_lab(a, &sc, day[k], sel_ring, ring[dk][k]);
                frame_lab(a, &sc, day[k], sel_core, core[dk][k]);
                printf("trial %d %s skin day %2g: ring L* %5.1f C* %5.1f b* %5.1f hue %5.1f, core "
                       "L* %5.1f C* %5.1f hue %5.1f, skin L* %5.1f C* %5.1f b* %5.1f hue %5.1f\n",
                       trial, dk ? "dark " : "light", day[k], ring[dk][k][0],
                       chroma_of(ring[dk][k]), ring[dk][k][2], hue_deg(ring[dk][k]), core[dk][k][0],
                       chroma_of(core[dk][k]), hue_deg(core[dk][k]), skin[dk][0],
                       chroma_of(skin[dk]), skin[dk][2], hue_deg(skin[dk]));
            }
            ss_abrasion_free(a);
            scene_free(&sc);
        }
        for (int k = 0; k < 2; k++) {
            /* redder than the dark skin, not yellower: pink-brown, not orange */
            assert_true(ring[1][k][2] - skin[1][2] < 7.0);
            assert_true(hue_deg(ring[1][k]) < hue_deg(skin[1]) - 5.0);
            /* a pink new skin on light skin, lighter than its red core */
            assert_true(hue_deg(ring[0][k]) < hue_deg(skin[0]) - 10.0);
        }
        assert_true(ring[0][0][0] > core[0][0][0] + 5.0);
        assert_true(hue_deg(core[1][1]) < hue_deg(skin[1]) - 5.0);
        /* no orange ring round the red core */
        assert_true(hue_deg(ring[1][0]) - hue_deg(core[1][0]) < 18.0);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_timeline_locate),
        cmocka_unit_test(test_timeline_json),
        cmocka_unit_test(test_strokes_csv),
        cmocka_unit_test(test_shape_from_strokes),
        cmocka_unit_test(test_shape_from_mask),
        cmocka_unit_test(test_bed_is_tissue),
        cmocka_unit_test(test_no_ring),
        cmocka_unit_test(test_maturation_no_ridges),
        cmocka_unit_test(test_scar_at_a_year),
        cmocka_unit_test(test_frames_blend),
        cmocka_unit_test(test_frame_cancel),
        cmocka_unit_test(test_scale_invariance),
        cmocka_unit_test(test_thread_determinism),
        cmocka_unit_test(test_update_equals_create),
        cmocka_unit_test(test_dark_skin_maturation),
        cmocka_unit_test(test_dark_skin_bed_and_scar),
        cmocka_unit_test(test_dark_skin_new_epithelium),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
