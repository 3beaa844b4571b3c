/* The packet path of the photon transport (src/optics/mc.c, mc_packet.h;
 * issue 28) against the scalar loop: on van de Hulst's slab, the 4-layer skin
 * benchmark input, a thick high-albedo tissue, a mismatched-index slab and the
 * seed's skin model (rough surface, tabulated phase functions, fat reflector)
 * both paths give the same RAT and the same radial and angular arrays within
 * Monte Carlo error (a two-sample chi-square over bins, per-bin variances from
 * independent seeds); the packet path is bit-identical for 1 and 2 threads
 * and in its AVX2 and baseline copies, for tallies and traced paths. */
#include "testutil.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../src/optics/optics_internal.h"
#include "skinsim/optics.h"

static ss_optics_slab slab1(double n, double mua, double mus, double g, double d, double nout) {
    ss_optics_slab s;
    memset(&s, 0, sizeof s);
    s.nlayers = 1;
    s.layer[0] = (ss_optics_layer){n, mua, mus, g, d, 0, {0}};
    s.n_above = 1.0;
    s.n_below = nout;
    s.bottom_albedo = -1.0;
    return s;
}

static ss_optics_slab skin4(void) {
    ss_optics_slab s;
    memset(&s, 0, sizeof s);
    s.nlayers = 4;
    s.layer[0] = (ss_optics_layer){1.55, 0.4605, 373.6, 0.90, 0.001, 0, {0}};
    s.layer[1] = (ss_optics_layer){1.40, 5.479, 373.6, 0.90, 0.01, 0, {0}};
    s.layer[2] = (ss_optics_layer){1.36, 1.643, 169.4, 0.7795, 0.02, 0, {0}};
    s.layer[3] = (ss_optics_layer){1.38, 1.643, 169.4, 0.7795, 0.18, 0, {0}};
    s.n_above = 1.0;
    s.n_below = 1.44;
    s.bottom_albedo = -1.0;
    return s;
}

/* The observables of one run as a flat vector: Rd, Tt, A, the MCML arrays
 * Rd_r, Rd_a, Tt_a, A_z (or, with brdf, the exit-direction BRDF and Rd(r)
 * of ss_mc_run), per photon. */
#define NR 12
#define NA 10
#define NZ 12
#define NOBS (3 + NR + 2 * NA + NZ)
static int observe(const ss_optics_slab *s, ss_mc_options o, int mcml, double *v) {
    ss_error e;
    double n = (double)o.photons;
    if (mcml) {
        ss_mc_tally_spec sp;
        memset(&sp, 0, sizeof sp);
        sp.mcml = 1;
        sp.rad_n = NR;
        sp.rad_dr = 0.01;
        sp.na = NA;
        sp.nz = NZ;
        double d = 0;
        for (int l = 0; l < s->nlayers; l++) d += s->layer[l].d_cm;
        sp.dz = fmin(d, 0.1) / NZ;
        ss_mc_tallies t;
        assert_int_equal(ss_mc_run_tallies(s, &o, &sp, &t, &e), SS_OK);
        int k = 0;
        v[k++] = t.diffuse / n;
        v[k++] = t.transmit / n;
        v[k++] = t.absorbed / n;
        for (int i = 0; i < NR; i++) v[k++] = t.rd_r[i] / n;
        for (int i = 0; i < NA; i++) v[k++] = t.rd_a[i] / n;
        for (int i = 0; i < NA; i++) v[k++] = t.tt_a[i] / n;
        for (int i = 0; i < NZ; i++) v[k++] = t.a_z[i] / n;
        ss_mc_tallies_free(&t);
        return k;
    }
    o.brdf_n_theta = 6;
    o.brdf_n_phi = 4;
    o.radial_bins = NR;
    o.radial_max_cm = 0.12;
    ss_mc_result r;
    assert_int_equal(ss_mc_run(s, &o, &r, &e), SS_OK);
    int k = 0;
    v[k++] = r.diffuse;
    v[k++] = r.transmit;
    v[k++] = r.absorbed;
    for (int i = 0; i < 24; i++) v[k++] = r.brdf_exit[i];
    for (int i = 0; i < NR; i++) v[k++] = r.radial[i];
    ss_mc_result_free(&r);
    return k;
}

/* K independent runs per path (seeds 1..K and 101..100+K); per observable the
 * difference of the path means over the pooled standard error, t with 2K - 2
 * degrees of freedom under equal means; returns the sum of squares over the
 * observables whose pooled error is not zero, *dof their number. */
#define KRUNS 10
static double chi2_paths(const char *name, const ss_optics_slab *s, ss_mc_options o, int mcml,
                         int *dof) {
    static double va[KRUNS][NOBS + 8], vb[KRUNS][NOBS + 8];
    int nobs = 0;
    for (int r = 0; r < KRUNS; r++) {
        o.kernel = SS_MC_KERNEL_AUTO;
        o.seed = 1 + (uint64_t)r;
        nobs = observe(s, o, mcml, va[r]);
        o.kernel = SS_MC_KERNEL_SCALAR;
        o.seed = 101 + (uint64_t)r;
        observe(s, o, mcml, vb[r]);
    }
    double chi2 = 0, worst = 0;
    int n = 0, wi = -1;
    for (int i = 0; i < nobs; i++) {
        double ma = 0, mb = 0, sa = 0, sb = 0;
        for (int r = 0; r < KRUNS; r++) {
            ma += va[r][i];
            mb += vb[r][i];
        }
        ma /= KRUNS;
        mb /= KRUNS;
        for (int r = 0; r < KRUNS; r++) {
            sa += (va[r][i] - ma) * (va[r][i] - ma);
            sb += (vb[r][i] - mb) * (vb[r][i] - mb);
        }
        double var = (sa + sb) / (2 * KRUNS - 2) * (2.0 / KRUNS);
        if (!(var > 1e-30 * (ma * ma + mb * mb)) || var <= 0) continue;
        double z2 = (ma - mb) * (ma - mb) / var;
        chi2 += z2;
        n++;
        if (z2 > worst) worst = z2, wi = i;
    }
    printf("%-34s packet vs scalar: chi2 %.1f over %d observables (worst z %.2f at #%d)\n", name,
           chi2, n, sqrt(worst), wi);
    *dof = n;
    return chi2;
}

/* Under equal means each term is t^2 with 18 degrees of freedom: mean
 * 18/16, standard deviation 1.75; the limit is the mean plus 6 standard
 * deviations of the sum (false alarm far below 1e-6 for Gaussian sums, about
 * 1e-4 allowing for the t tails). */
static void assert_agree(double chi2, int dof) {
    assert_true(dof >= 10);
    double mean = dof * 18.0 / 16.0, sd = 1.75 * sqrt((double)dof);
    assert_true(chi2 < mean + 6.0 * sd);
}

static void test_agree_within_mc_error(void **state) {
    (void)state;
    const uint64_t n = tu_quick() ? 1500 : 4000;
    ss_mc_options o;
    ss_mc_options_default(&o);
    int dof;
    double c;
    ss_optics_slab vdh = slab1(1.0, 10, 90, 0.75, 0.02, 1.0);
    o.photons = n * 4;
    c = chi2_paths("van de Hulst slab (MCML arrays)", &vdh, o, 1, &dof);
    assert_agree(c, dof);
    ss_optics_slab sk = skin4();
    o.photons = n;
    c = chi2_paths("4-layer skin (MCML arrays)", &sk, o, 1, &dof);
    assert_agree(c, dof);
    c = chi2_paths("4-layer skin, 40 deg (BRDF, Rd(r))", &sk,
                   (ss_mc_options){.photons = n, .seed = 1, .theta_i_rad = 0.7}, 0, &dof);
    assert_agree(c, dof);
    ss_optics_slab thick = slab1(1.4, 0.1, 100, 0.9, 1.0, 1.0);
    o.photons = n / 4;
    c = chi2_paths("thick high-albedo tissue", &thick, o, 1, &dof);
    assert_agree(c, dof);
    ss_optics_slab mis = slab1(1.6, 2, 150, 0.8, 0.05, 1.33);
    o.photons = n;
    c = chi2_paths("mismatched-index slab (1 / 1.6 / 1.33)", &mis, o, 1, &dof);
    assert_agree(c, dof);
    ss_bio_params b;
    ss_bio_params_default(&b);
    ss_optics_slab seed;
    ss_error e;
    assert_int_equal(ss_optics_skin_slab(&b, 550, &seed, &e), SS_OK);
    ss_mc_options os = o;
    os.roughness_sigma = 0.75;
    c = chi2_paths("skin model, rough 0.75, fat (BRDF)", &seed, os, 0, &dof);
    assert_agree(c, dof);
    os.radial_distance = SS_RADIAL_PATH;
    c = chi2_paths("skin model, path distance D", &seed, os, 0, &dof);
    assert_agree(c, dof);
}

/* van de Hulst's slab on both paths: Rd and Tt within 3 standard errors. */
static void test_van_de_hulst_both_paths(void **state) {
    (void)state;
    ss_optics_slab v = slab1(1.0, 10, 90, 0.75, 0.02, 1.0);
    for (int k = 0; k < 3; k++) {
        ss_mc_options o;
        ss_mc_options_default(&o);
        o.photons = tu_quick() ? 40000 : 200000;
        o.kernel = k;
        ss_mc_result r;
        ss_error e;
        assert_int_equal(ss_mc_run(&v, &o, &r, &e), SS_OK);
        printf("van de Hulst, kernel %d: Rd %.5f +- %.5f (0.09739), Tt %.5f +- %.5f (0.66096)\n", k,
               r.diffuse, r.diffuse_se, r.transmit, r.transmit_se);
        assert_true(fabs(r.diffuse - 0.09739) < 3 * r.diffuse_se);
        assert_true(fabs(r.transmit - 0.66096) < 3 * r.transmit_se);
        assert_true(fabs(r.specular + r.diffuse + r.transmit + r.absorbed - r.roulette_net - 1.0) <
                    1e-9);
        ss_mc_result_free(&r);
    }
}

static int same_result(const ss_mc_result *a, const ss_mc_result *b) {
    if (a->diffuse != b->diffuse || a->transmit != b->transmit || a->absorbed != b->absorbed ||
        a->specular != b->specular || a->roulette_net != b->roulette_net)
        return 0;
    for (int i = 0; i < a->brdf_n_theta * a->brdf_n_phi; i++)
        if (a->brdf_exit[i] != b->brdf_exit[i]) return 0;
    for (int i = 0; i < a->radial_bins; i++)
        if (a->radial[i] != b->radial[i]) return 0;
    return 1;
}

/* Threads 1 and 2, and the AVX2 copy (AUTO, where the processor has AVX2)
 * against the baseline copy: identical results, for weighted runs with every
 * tally and for the path tracer of the table build. */
static void test_packet_deterministic(void **state) {
    (void)state;
    ss_bio_params b;
    ss_bio_params_default(&b);
    ss_optics_slab seed;
    ss_error e;
    assert_int_equal(ss_optics_skin_slab(&b, 500, &seed, &e), SS_OK);
    ss_optics_slab sk = skin4();
    const ss_optics_slab *slabs[2] = {&sk, &seed};
    for (int si = 0; si < 2; si++) {
        ss_mc_options o;
        ss_mc_options_default(&o);
        o.photons = 9000;
        o.roughness_sigma = si ? 0.75 : 0.0;
        o.brdf_n_theta = 6;
        o.brdf_n_phi = 4;
        o.radial_bins = 10;
        o.radial_max_cm = 0.1;
        ss_mc_result r[3];
        omp_set_num_threads(1);
        assert_int_equal(ss_mc_run(slabs[si], &o, &r[0], &e), SS_OK);
        omp_set_num_threads(2);
        assert_int_equal(ss_mc_run(slabs[si], &o, &r[1], &e), SS_OK);
        o.kernel = SS_MC_KERNEL_PACKET_BASE;
        assert_int_equal(ss_mc_run(slabs[si], &o, &r[2], &e), SS_OK);
        assert_true(same_result(&r[0], &r[1]));
        assert_true(same_result(&r[0], &r[2]));
        for (int k = 0; k < 3; k++) ss_mc_result_free(&r[k]);
        /* traced paths, then reweighted */
        ss_mc_paths *p[2];
        o.kernel = SS_MC_KERNEL_AUTO;
        assert_int_equal(ss_mc_trace_paths(slabs[si], &o, &p[0], &e), SS_OK);
        o.kernel = SS_MC_KERNEL_PACKET_BASE;
        omp_set_num_threads(1);
        assert_int_equal(ss_mc_trace_paths(slabs[si], &o, &p[1], &e), SS_OK);
        double mua[SS_OPTICS_MAX_LAYERS];
        for (int l = 0; l < slabs[si]->nlayers; l++) mua[l] = slabs[si]->layer[l].mua_per_cm;
        assert_int_equal(ss_mc_paths_apply(p[0], mua, &r[0], &e), SS_OK);
        assert_int_equal(ss_mc_paths_apply(p[1], mua, &r[1], &e), SS_OK);
        assert_true(r[0].diffuse == r[1].diffuse && r[0].transmit == r[1].transmit);
        for (int i = 0; i < 24; i++) assert_true(r[0].brdf_exit[i] == r[1].brdf_exit[i]);
        /* the traced paths reproduce the direct weighted run within MC error */
        o.kernel = SS_MC_KERNEL_AUTO;
        assert_int_equal(ss_mc_run(slabs[si], &o, &r[2], &e), SS_OK);
        double se = hypot(r[0].diffuse_se, r[2].diffuse_se);
        printf("paths vs direct (%s): Rd %.5f / %.5f (se %.5f)\n", si ? "skin model" : "skin4",
               r[0].diffuse, r[2].diffuse, se);
        assert_true(fabs(r[0].diffuse - r[2].diffuse) < 4 * se);
        for (int k = 0; k < 3; k++) ss_mc_result_free(&r[k]);
        ss_mc_paths_free(p[0]);
        ss_mc_paths_free(p[1]);
    }
    omp_set_num_threads(2);
}

/* An unknown kernel is an input error naming the option. */
static void test_kernel_option(void **state) {
    (void)state;
    ss_optics_slab v = slab1(1.0, 10, 90, 0.75, 0.02, 1.0);
    ss_mc_options o;
    ss_mc_options_default(&o);
    o.kernel = 7;
    ss_mc_result r;
    ss_error e;
    assert_int_equal(ss_mc_run(&v, &o, &r, &e), SS_ERR_INPUT);
    assert_non_null(strstr(e.msg, "kernel"));
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_agree_within_mc_error),
        cmocka_unit_test(test_van_de_hulst_both_paths),
        cmocka_unit_test(test_packet_deterministic),
        cmocka_unit_test(test_kernel_option),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
