/* Skin optics: colour conversion anchors, and the plausibility of the skin
 * model: melanin lowers blue reflectance, blood deepens the 540-580 nm dip,
 * deoxygenation turns the HbO2 double peak into a single Hb band, light and
 * dark tones land in sensible ranges, red light spreads further than blue
 * (radial profile), the sampled BRDF is normalised, spectra are thread-count
 * independent. */
#include "testutil.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/optics.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static uint64_t nph(uint64_t full) { return tu_quick() ? full / 4 : full; }

static void spectrum(const ss_bio_params *b, double lo, double hi, double step, uint64_t photons,
                     ss_reflectance_spectrum *s) {
    ss_spectrum_options o;
    ss_spectrum_options_default(&o);
    o.wl_min_nm = lo;
    o.wl_max_nm = hi;
    o.wl_step_nm = step;
    o.mc.photons = photons;
    ss_error e;
    ss_error_clear(&e);
    ss_status st = ss_optics_reflectance_spectrum(b, &o, s, &e);
    if (st) fprintf(stderr, "%s\n", e.msg);
    assert_int_equal(st, SS_OK);
}

static double at(const ss_reflectance_spectrum *s, double nm) {
    for (int i = 0; i < s->n; i++)
        if (fabs(s->wavelength_nm[i] - nm) < 1e-6) return s->reflectance[i];
    fail_msg("wavelength %g not sampled", nm);
    return 0;
}

static void test_colour_anchors(void **state) {
    (void)state;
    double wl[41], r[41], rgb[3];
    ss_error e;
    for (int i = 0; i < 41; i++) {
        wl[i] = 380 + 10 * i;
        r[i] = 1.0;
    }
    assert_int_equal(ss_spectrum_to_srgb_linear(wl, r, 41, rgb, &e), SS_OK);
    for (int c = 0; c < 3; c++) assert_true(fabs(rgb[c] - 1.0) < 1e-12);
    for (int i = 0; i < 41; i++) r[i] = 0.18;
    assert_int_equal(ss_spectrum_to_srgb_linear(wl, r, 41, rgb, &e), SS_OK);
    for (int c = 0; c < 3; c++) assert_true(fabs(rgb[c] - 0.18) < 1e-12);
    /* long-pass (red) and short-pass (blue) filters */
    for (int i = 0; i < 41; i++) r[i] = wl[i] >= 600 ? 1.0 : 0.0;
    assert_int_equal(ss_spectrum_to_srgb_linear(wl, r, 41, rgb, &e), SS_OK);
    assert_true(rgb[0] > 0.5 && rgb[1] < 0.2 && rgb[2] < 0.1);
    for (int i = 0; i < 41; i++) r[i] = wl[i] <= 480 ? 1.0 : 0.0;
    assert_int_equal(ss_spectrum_to_srgb_linear(wl, r, 41, rgb, &e), SS_OK);
    assert_true(rgb[2] > 0.5 && rgb[0] < 0.2);
    /* bad input */
    wl[5] = wl[4];
    assert_int_equal(ss_spectrum_to_srgb_linear(wl, r, 41, rgb, &e), SS_ERR_INPUT);
    wl[5] = 430;
    r[3] = NAN;
    assert_int_equal(ss_spectrum_to_srgb_linear(wl, r, 41, rgb, &e), SS_ERR_INPUT);
}

static void test_melanin_lowers_blue(void **state) {
    (void)state;
    ss_bio_params b;
    ss_bio_params_default(&b);
    ss_reflectance_spectrum lo, hi;
    b.melanin = 0.03;
    spectrum(&b, 450, 650, 200, nph(20000), &lo);
    b.melanin = 0.15;
    spectrum(&b, 450, 650, 200, nph(20000), &hi);
    printf("melanin 0.03 -> 0.15: R(450) %.4f -> %.4f, R(650) %.4f -> %.4f\n", at(&lo, 450),
           at(&hi, 450), at(&lo, 650), at(&hi, 650));
    assert_true(at(&hi, 450) < 0.7 * at(&lo, 450));
    /* melanin absorbs more in the blue: blue drops relatively more than red */
    assert_true(at(&hi, 450) / at(&lo, 450) < at(&hi, 650) / at(&lo, 650));
    ss_reflectance_spectrum_free(&lo);
    ss_reflectance_spectrum_free(&hi);
}

static void test_blood_and_oxygenation(void **state) {
    (void)state;
    ss_bio_params b;
    ss_bio_params_default(&b);
    ss_reflectance_spectrum s1, s2, ox, de;
    b.blood = 0.005;
    spectrum(&b, 545, 650, 15, nph(20000), &s1);
    b.blood = 0.03;
    spectrum(&b, 545, 650, 15, nph(20000), &s2);
    double d1 = at(&s1, 560) / at(&s1, 650), d2 = at(&s2, 560) / at(&s2, 650);
    printf("blood 0.005 -> 0.03: R(560)/R(650) %.3f -> %.3f\n", d1, d2);
    assert_true(d2 < 0.8 * d1);
    /* oxygenated blood: two bands (542, 577 nm) with a window at 560 nm;
     * deoxygenated: one band at 555 nm, so 560 nm becomes the minimum */
    b.blood = 0.03;
    b.oxygenation = 1.0;
    spectrum(&b, 545, 575, 15, nph(40000), &ox);
    b.oxygenation = 0.0;
    spectrum(&b, 545, 575, 15, nph(40000), &de);
    double wo = at(&ox, 560) - 0.5 * (at(&ox, 545) + at(&ox, 575));
    double wd = at(&de, 560) - 0.5 * (at(&de, 545) + at(&de, 575));
    printf("560 nm window: oxygenated %+.4f, deoxygenated %+.4f\n", wo, wd);
    assert_true(wo > 0.0);
    assert_true(wd < 0.0);
    ss_reflectance_spectrum_free(&s1);
    ss_reflectance_spectrum_free(&s2);
    ss_reflectance_spectrum_free(&ox);
    ss_reflectance_spectrum_free(&de);
}

static void tone(double melanin, double rgb[3]) {
    ss_bio_params b;
    ss_bio_params_default(&b);
    b.melanin = melanin;
    ss_reflectance_spectrum s;
    spectrum(&b, 380, 780, 20, nph(8000), &s);
    ss_error e;
    assert_int_equal(ss_spectrum_to_srgb_linear(s.wavelength_nm, s.reflectance, s.n, rgb, &e),
                     SS_OK);
    assert_true(s.specular > 0.02 && s.specular < 0.1);
    ss_reflectance_spectrum_free(&s);
}

static void test_skin_tones(void **state) {
    (void)state;
    double l[3], d[3];
    tone(0.015, l);
    tone(0.35, d);
    printf("light skin linear sRGB %.3f %.3f %.3f; dark %.3f %.3f %.3f\n", l[0], l[1], l[2], d[0],
           d[1], d[2]);
    /* light skin: bright, red > green > blue (sRGB-encoded roughly 180-230 red) */
    assert_true(l[0] > 0.35 && l[0] < 0.8);
    assert_true(l[0] > l[1] && l[1] > l[2] && l[2] > 0.1);
    /* dark skin: dark brown, still red > green >= blue */
    assert_true(d[0] > 0.02 && d[0] < 0.15);
    assert_true(d[0] > d[1] && d[1] >= 0.9 * d[2]);
}

static void test_radial_red_spreads_further(void **state) {
    (void)state;
    ss_bio_params b;
    ss_bio_params_default(&b);
    ss_spectrum_options o;
    ss_spectrum_options_default(&o);
    o.wl_step_nm = 40;
    o.mc.photons = nph(10000);
    enum { NB = 40 };
    double rgb[NB * 3];
    ss_error e;
    assert_int_equal(ss_optics_radial_profile_rgb(&b, &o, NB, 1.0, rgb, &e), SS_OK);
    double tot[3] = {0}, far[3] = {0};
    for (int i = 0; i < NB; i++) {
        double r0 = i * 0.025, r1 = r0 + 0.025, area = M_PI * (r1 * r1 - r0 * r0);
        for (int c = 0; c < 3; c++) {
            tot[c] += rgb[i * 3 + c] * area;
            if (r0 >= 0.1) far[c] += rgb[i * 3 + c] * area;
        }
    }
    printf("fraction of albedo beyond 1 mm: r %.3f g %.3f b %.3f\n", far[0] / tot[0],
           far[1] / tot[1], far[2] / tot[2]);
    assert_true(far[0] / tot[0] > far[1] / tot[1]);
    assert_true(far[1] / tot[1] > far[2] / tot[2]);
    assert_true(tot[0] > 0.2 && tot[0] < 1.0);
}

static void test_brdf_sample(void **state) {
    (void)state;
    ss_bio_params b;
    ss_bio_params_default(&b);
    ss_spectrum_options o;
    ss_spectrum_options_default(&o);
    o.wl_step_nm = 100;
    o.mc.photons = nph(8000);
    ss_brdf_sampled br;
    ss_error e;
    assert_int_equal(ss_optics_brdf_sample(&b, &o, 2, 6, 4, &br, &e), SS_OK);
    assert_int_equal(br.n_theta_i, 2);
    for (int ti = 0; ti < 2; ti++) {
        double hem[3] = {0};
        for (int tr = 0; tr < 6; tr++) {
            double t0 = tr * M_PI / 12, t1 = t0 + M_PI / 12;
            double w = (cos(t0) - cos(t1)) * (M_PI / 4) * 2 * cos(t0 + M_PI / 24);
            for (int p = 0; p < 4; p++)
                for (int c = 0; c < 3; c++) {
                    double f = br.f_rgb[((ti * 6 + tr) * 4 + p) * 3 + c];
                    assert_true(f >= -1e-3); /* colour weights can be slightly negative */
                    hem[c] += f * w;
                }
        }
        /* directional albedo incl. specular: skin-like, red highest */
        assert_true(hem[0] > hem[2] && hem[0] < 1.0 && hem[2] > 0.05);
    }
    ss_brdf_sampled_free(&br);
    assert_int_equal(ss_optics_brdf_sample(&b, &o, 0, 6, 4, &br, &e), SS_ERR_INPUT);
}

static void test_spectrum_threads_and_errors(void **state) {
    (void)state;
    ss_bio_params b;
    ss_bio_params_default(&b);
    ss_reflectance_spectrum a, c;
    omp_set_num_threads(1);
    spectrum(&b, 400, 700, 100, nph(8000), &a);
    omp_set_num_threads(2);
    spectrum(&b, 400, 700, 100, nph(8000), &c);
    assert_int_equal(a.n, 4);
    assert_memory_equal(a.reflectance, c.reflectance, 4 * sizeof(double));
    assert_memory_equal(a.std_error, c.std_error, 4 * sizeof(double));
    ss_reflectance_spectrum_free(&a);
    ss_reflectance_spectrum_free(&c);
    ss_spectrum_options o;
    ss_spectrum_options_default(&o);
    ss_error e;
    o.wl_step_nm = 0;
    assert_int_equal(ss_optics_reflectance_spectrum(&b, &o, &a, &e), SS_ERR_INPUT);
    ss_spectrum_options_default(&o);
    o.wl_min_nm = 200;
    assert_int_equal(ss_optics_reflectance_spectrum(&b, &o, &a, &e), SS_ERR_INPUT);
    ss_spectrum_options_default(&o);
    b.pheomelanin_ratio = 2;
    assert_int_equal(ss_optics_reflectance_spectrum(&b, &o, &a, &e), SS_ERR_INPUT);
    assert_non_null(strstr(e.msg, "pheomelanin"));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_colour_anchors),
        cmocka_unit_test(test_melanin_lowers_blue),
        cmocka_unit_test(test_blood_and_oxygenation),
        cmocka_unit_test(test_skin_tones),
        cmocka_unit_test(test_radial_red_spreads_further),
        cmocka_unit_test(test_brdf_sample),
        cmocka_unit_test(test_spectrum_threads_and_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
