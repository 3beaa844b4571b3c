/* MCML files: parsing a multi-run .mci (comments, blank lines), errors with
 * line numbers, and the .mco output: RAT against van de Hulst's slab and the
 * MCML normalisations of A_z, Rd_r, Rd_a and of the 2-D arrays A_rz, Rd_ra,
 * Tt_ra (they integrate back to RAT and to the 1-D arrays). */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/optics.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static const char *SAMPLE = "####\n"
                            "# Template of input files for Monte Carlo simulation (mcml).\n"
                            "####\n"
                            "1.0                      # file version\n"
                            "2                        # number of runs\n"
                            "\n"
                            "#### SPECIFY DATA FOR RUN 1\n"
                            "#InParm                  # Input parameters. cm is used.\n"
                            "vdh.mco  A               # output file name, ASCII.\n"
                            "PHOTONS                  # No. of photons\n"
                            "0.001 0.01               # dz, dr [cm]\n"
                            "20 200 30                # No. of dz, dr, da.\n"
                            "\n"
                            "1                        # Number of layers\n"
                            "#n mua mus g d           # One line for each layer\n"
                            "1                        # n for medium above\n"
                            "1.0 10 90 0.75 0.02      # layer 1\n"
                            "1                        # n for medium below\n"
                            "\n"
                            "#### SPECIFY DATA FOR RUN 2\n"
                            "two.mco A\n"
                            "1000\n"
                            "0.01 0.01\n"
                            "40 50 10\n"
                            "2\n"
                            "1\n"
                            "1.37 1 100 0.9 0.1\n"
                            "1.37 1 10 0.0 0.2\n"
                            "1.0\n";

static char *sample(const char *photons) {
    const char *p = strstr(SAMPLE, "PHOTONS");
    size_t pre = (size_t)(p - SAMPLE);
    char *s = malloc(strlen(SAMPLE) + 32);
    memcpy(s, SAMPLE, pre);
    strcpy(s + pre, photons);
    strcat(s, p + 7);
    return s;
}

static void test_parse(void **state) {
    (void)state;
    char *t = sample("5000");
    ss_mci_file f;
    ss_error e;
    assert_int_equal(ss_mci_parse(t, "sample.mci", &f, &e), SS_OK);
    assert_int_equal(f.nruns, 2);
    assert_string_equal(f.runs[0].out_name, "vdh.mco");
    assert_true(f.runs[0].photons == 5000);
    assert_true(f.runs[0].dz_cm == 0.001 && f.runs[0].dr_cm == 0.01);
    assert_int_equal(f.runs[0].nz, 20);
    assert_int_equal(f.runs[0].nr, 200);
    assert_int_equal(f.runs[0].na, 30);
    assert_int_equal(f.runs[0].slab.nlayers, 1);
    assert_true(f.runs[0].slab.layer[0].mus_per_cm == 90);
    assert_true(f.runs[0].slab.bottom_albedo < 0);
    assert_int_equal(f.runs[1].slab.nlayers, 2);
    assert_true(f.runs[1].slab.layer[1].d_cm == 0.2);
    assert_true(f.runs[1].slab.n_above == 1.0 && f.runs[1].slab.n_below == 1.0);
    ss_mci_file_free(&f);
    free(t);
}

static void expect_error(const char *from, const char *to, const char *needle) {
    char *t = sample("5000");
    char *p = strstr(t, from);
    assert_non_null(p);
    char *s = malloc(strlen(t) + strlen(to) + 1);
    memcpy(s, t, (size_t)(p - t));
    strcpy(s + (p - t), to);
    strcat(s, p + strlen(from));
    ss_mci_file f;
    ss_error e;
    ss_error_clear(&e);
    assert_int_equal(ss_mci_parse(s, "bad.mci", &f, &e), SS_ERR_INPUT);
    if (!strstr(e.msg, needle)) fail_msg("message '%s' lacks '%s'", e.msg, needle);
    assert_non_null(strstr(e.msg, "bad.mci: line"));
    assert_null(f.runs);
    free(s);
    free(t);
}

static void test_parse_errors(void **state) {
    (void)state;
    expect_error("1.0                      # file version", "2.0", "version");
    expect_error("1.0 10 90 0.75 0.02", "1.0 -10 90 0.75 0.02", "mua");
    expect_error("1.0 10 90 0.75 0.02", "1.0 10 90 1.5 0.02", "anisotropy");
    expect_error("1.0 10 90 0.75 0.02", "1.0 10 90 0.75", "layer");
    expect_error("1.0 10 90 0.75 0.02", "1.0 10 90 0.75 0", "thickness");
    expect_error("20 200 30", "20 0 30", "grid");
    expect_error("two.mco A", "vdh.mco A", "like run 1");
    expect_error("1.37 1 10 0.0 0.2\n1.0\n", "1.37 1 10 0.0 0.2\n", "end of file");
    expect_error("vdh.mco  A", "vdh.mco B", "ASCII");
}

static double rat(const char *mco, const char *label) {
    const char *p = strstr(mco, label);
    assert_non_null(p);
    while (p > mco && p[-1] != '\n') p--;
    return strtod(p, NULL);
}

static double *array(const char *mco, const char *head, int n) {
    const char *p = strstr(mco, head);
    assert_non_null(p);
    p = strchr(p, '\n') + 1;
    double *v = malloc(sizeof(double) * (size_t)n);
    for (int i = 0; i < n; i++) {
        char *end;
        v[i] = strtod(p, &end);
        assert_true(end != p);
        p = end;
    }
    return v;
}

static void test_simulate_van_de_hulst(void **state) {
    (void)state;
    char *t = sample(tu_quick() ? "25000" : "100000");
    ss_mci_file f;
    ss_error e;
    assert_int_equal(ss_mci_parse(t, "sample.mci", &f, &e), SS_OK);
    char *mco = NULL;
    assert_int_equal(ss_mci_simulate(&f.runs[0], 5, &mco, &e), SS_OK);
    double N = (double)f.runs[0].photons;
    double sp = rat(mco, "#Specular reflectance"), rd = rat(mco, "#Diffuse reflectance");
    double a = rat(mco, "#Absorbed fraction"), tt = rat(mco, "#Transmittance");
    printf("mci van de Hulst: Rsp %.5f Rd %.5f A %.5f Tt %.5f\n", sp, rd, a, tt);
    assert_true(sp == 0.0);
    /* per-photon contributions lie in [0,1], so SE <= sqrt(p(1-p)/N) */
    assert_true(fabs(rd - 0.09739) < 3 * sqrt(0.09739 * (1 - 0.09739) / N));
    assert_true(fabs(tt - 0.66096) < 3 * sqrt(0.66096 * (1 - 0.66096) / N));
    assert_true(fabs(sp + rd + a + tt - 1.0) < 0.01);
    double *al = array(mco, "A_l #", 1);
    assert_true(fabs(al[0] - a) <= 5e-4 * a); /* 4 significant digits, as MCML */
    {                                         /* A_l in MCML's %12.4G, e.g. "      0.2417" */
        const char *l = strchr(strstr(mco, "A_l #"), '\n') + 1;
        char want[32];
        snprintf(want, sizeof want, "%12.4G\n", al[0]);
        assert_true(strncmp(l, want, strlen(want)) == 0);
        assert_true(strchr(want, 'E') == NULL);
    }
    /* A_z [1/cm]: sum dz = A (all absorption within 20 x 0.001 = 0.02 cm) */
    double *az = array(mco, "A_z #", 20), s = 0;
    for (int i = 0; i < 20; i++) s += az[i] * 0.001;
    assert_true(fabs(s - a) < 1e-4);
    /* Rd_r [1/cm^2] over annuli 2 pi (i+0.5) dr^2 gives Rd (overflow in the last bin) */
    double *rr = array(mco, "Rd_r #", 200);
    s = 0;
    for (int i = 0; i < 200; i++) s += rr[i] * 2 * M_PI * (i + 0.5) * 0.01 * 0.01;
    assert_true(fabs(s - rd) < 1e-4);
    /* Rd_a [1/sr] over 2 pi sin(theta) dtheta gives Rd */
    double *ra = array(mco, "Rd_a #", 30), da = M_PI / 60;
    s = 0;
    for (int i = 0; i < 30; i++) s += ra[i] * 2 * M_PI * sin((i + 0.5) * da) * da;
    assert_true(fabs(s - rd) < 1e-4);
    /* Tt_a similarly integrates to Tt (including the unscattered beam) */
    double *ta = array(mco, "Tt_a #", 30);
    s = 0;
    for (int i = 0; i < 30; i++) s += ta[i] * 2 * M_PI * sin((i + 0.5) * da) * da;
    assert_true(fabs(s - tt) < 1e-4);
    /* the 2-D arrays in MCML's layout and units integrate back too:
     * A_rz [1/cm^3] x 2 pi (ir+0.5) dr^2 dz -> A; Rd_ra, Tt_ra [1/(cm^2 sr)] x
     * 4 pi^2 dr^2 sin(da/2) (ir+0.5) sin(2 (ia+0.5) da) -> Rd, Tt; their
     * angle sums give Rd_r (row ir) and their radius sums Rd_a */
    double *arz = array(mco, "A_rz\n", 200 * 20);
    double *rra = array(mco, "Rd_ra\n", 200 * 30), *tra = array(mco, "Tt_ra\n", 200 * 30);
    double sa = 0, sr = 0, st = 0;
    for (int ir = 0; ir < 200; ir++) {
        for (int iz = 0; iz < 20; iz++)
            sa += arz[ir * 20 + iz] * 2 * M_PI * (ir + 0.5) * 0.01 * 0.01 * 0.001;
        double row = 0;
        for (int ia = 0; ia < 30; ia++) {
            double w =
                4 * M_PI * M_PI * 0.01 * 0.01 * sin(da / 2) * (ir + 0.5) * sin(2 * (ia + 0.5) * da);
            sr += rra[ir * 30 + ia] * w;
            st += tra[ir * 30 + ia] * w;
            row += rra[ir * 30 + ia] * w;
        }
        /* row ir summed over angles = Rd_r[ir] x annulus area */
        double ann = rr[ir] * 2 * M_PI * (ir + 0.5) * 0.01 * 0.01;
        assert_true(fabs(row - ann) < 1e-3 * rd + 1e-3 * ann);
    }
    printf("2-D arrays: A %.5f (%.5f) Rd %.5f (%.5f) Tt %.5f (%.5f)\n", sa, a, sr, rd, st, tt);
    assert_true(fabs(sa - a) < 1e-3 * a);
    assert_true(fabs(sr - rd) < 1e-3 * rd);
    assert_true(fabs(st - tt) < 1e-3 * tt);
    free(arz);
    free(rra);
    free(tra);
    free(al);
    free(az);
    free(rr);
    free(ra);
    free(ta);
    free(mco);
    /* run 2: matched-index 1.37 under air gives specular ((1-1.37)/2.37)^2 */
    assert_int_equal(ss_mci_simulate(&f.runs[1], 5, &mco, &e), SS_OK);
    assert_true(fabs(rat(mco, "#Specular reflectance") - pow(0.37 / 2.37, 2)) < 1e-5);
    assert_non_null(strstr(mco, "InParm"));
    assert_non_null(strstr(mco, "two.mco"));
    free(mco);
    ss_mci_file_free(&f);
    free(t);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_parse),
        cmocka_unit_test(test_parse_errors),
        cmocka_unit_test(test_simulate_van_de_hulst),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
