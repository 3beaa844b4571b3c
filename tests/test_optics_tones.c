/* The whole range of skin tones (issue 9): a melanin sweep at blood 0.2-2 %,
 * oxygenation 0.75 and the other defaults, under D65, must give hue angles
 * h_ab in 25..70 degrees and b* >= 8 in every cell; the lightest melanin
 * reaches ITA > 55 degrees (very light, Chardon et al. 1991) with C* >= 16;
 * the darkest has ITA < -30 degrees (dark) at every blood level; L* falls
 * with melanin. Colours from ss_optics_albedo_grid (the swatch's transport);
 * the table these give is in docs/validation.md. */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "skinsim/optics.h"

static void test_melanin_sweep(void **state) {
    (void)state;
    const double mel[] = {0.01, 0.03, 0.06, 0.12, 0.2, 0.3, 0.43};
    const double bl[] = {0.002, 0.005, 0.01, 0.02};
    const int nm = 7, nb = 4;
    ss_bio_params b;
    ss_bio_params_default(&b);
    b.oxygenation = 0.75;
    ss_spectrum_options o;
    ss_spectrum_options_default(&o);
    o.wl_step_nm = 20;
    o.mc.photons = tu_quick() ? 4000 : 10000;
    double rgb[7 * 4 * 3];
    ss_error e;
    ss_error_clear(&e);
    ss_status st = ss_optics_albedo_grid(&b, &o, mel, nm, bl, nb, rgb, &e);
    if (st) fprintf(stderr, "%s\n", e.msg);
    assert_int_equal(st, SS_OK);
    int lightest_ok = 0;
    printf("blood   melanin    L*     a*     b*     C*    h_ab    ITA\n");
    for (int j = 0; j < nb; j++) {
        double prevL = 1e9;
        for (int i = 0; i < nm; i++) {
            double lab[3], C, h, ita;
            ss_srgb_linear_to_lab(rgb + 3 * (j * nm + i), lab);
            ss_lab_describe(lab, &C, &h, &ita);
            printf("%.3f   %.2f    %5.1f  %5.1f  %5.1f  %5.1f  %5.1f  %6.1f\n", bl[j], mel[i],
                   lab[0], lab[1], lab[2], C, h, ita);
            assert_true(h >= 25.0 && h <= 70.0);
            assert_true(lab[2] >= 8.0);
            assert_true(lab[0] < prevL);
            prevL = lab[0];
            if (i == 0 && ita > 55.0 && C >= 16.0) lightest_ok = 1;
            if (i == nm - 1) assert_true(ita < -30.0);
        }
    }
    assert_true(lightest_ok);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_melanin_sweep),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
