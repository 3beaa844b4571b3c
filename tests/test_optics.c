/* Optics transport: van de Hulst slab, unscattered transmission, energy
 * conservation, a semi-infinite medium against Chandrasekhar's exact
 * H-function result, Fresnel against closed forms, clear-slab multiple
 * reflections, BRDF / radial normalisation, the absorption-free path method
 * against direct runs, determinism across thread counts, parameter checks,
 * and the inner loop's samplers (ziggurat exponential, polynomial azimuth)
 * against their distributions. */
#include "testutil.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../src/optics/optics_internal.h"
#include "skinsim/optics.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static uint64_t nph(uint64_t full) { return tu_quick() ? full / 4 : full; }

static ss_optics_slab one_layer(double n, double mua, double mus, double g, double d) {
    ss_optics_slab s;
    memset(&s, 0, sizeof s);
    s.nlayers = 1;
    s.layer[0] = (ss_optics_layer){n, mua, mus, g, d, 0, {0}};
    s.n_above = s.n_below = 1.0;
    s.bottom_albedo = -1.0;
    return s;
}

static void run_ok(const ss_optics_slab *s, const ss_mc_options *o, ss_mc_result *r) {
    ss_error e;
    ss_error_clear(&e);
    ss_status st = ss_mc_run(s, o, r, &e);
    if (st) fprintf(stderr, "ss_mc_run: %s\n", e.msg);
    assert_int_equal(st, SS_OK);
}

/* van de Hulst (1980) via MCML's validation: n=1, mua=10, mus=90, g=0.75, d=0.02 cm. */
static void test_van_de_hulst(void **state) {
    (void)state;
    ss_optics_slab s = one_layer(1.0, 10, 90, 0.75, 0.02);
    ss_mc_options o;
    ss_mc_options_default(&o);
    o.photons = nph(200000);
    o.seed = 7;
    ss_mc_result r;
    run_ok(&s, &o, &r);
    printf("van de Hulst: Rd %.5f +- %.5f (ref 0.09739), Tt %.5f +- %.5f (ref 0.66096)\n",
           r.diffuse, r.diffuse_se, r.transmit, r.transmit_se);
    assert_true(fabs(r.diffuse - 0.09739) < 3 * r.diffuse_se);
    assert_true(fabs(r.transmit - 0.66096) < 3 * r.transmit_se);
    assert_true(r.diffuse_se > 0 && r.diffuse_se < 0.003);
    assert_true(r.specular == 0.0);
    /* The seed's absorb-or-scatter mode estimates the same quantities. */
    o.stochastic_absorb = 1;
    ss_mc_result q;
    run_ok(&s, &o, &q);
    printf("van de Hulst (stochastic absorb): Rd %.5f +- %.5f, Tt %.5f +- %.5f\n", q.diffuse,
           q.diffuse_se, q.transmit, q.transmit_se);
    assert_true(fabs(q.diffuse - 0.09739) < 3 * q.diffuse_se);
    assert_true(fabs(q.transmit - 0.66096) < 3 * q.transmit_se);
    ss_mc_result_free(&r);
    ss_mc_result_free(&q);
}

/* A purely absorbing slab of optical depth 2: every packet that interacts is
 * absorbed, so T is the unscattered transmission exp(-2). */
static void test_unscattered(void **state) {
    (void)state;
    ss_optics_slab s = one_layer(1.0, 100, 0, 0, 0.02);
    ss_mc_options o;
    ss_mc_options_default(&o);
    o.photons = nph(100000);
    ss_mc_result r;
    run_ok(&s, &o, &r);
    printf("unscattered: T %.5f +- %.5f (exp(-2) = %.5f)\n", r.transmit, r.transmit_se, exp(-2.0));
    assert_true(fabs(r.transmit - exp(-2.0)) < 3 * r.transmit_se);
    assert_true(r.diffuse == 0.0);
    ss_mc_result_free(&r);
}

static void check_energy(const ss_optics_slab *s, ss_mc_options *o) {
    ss_mc_result r;
    run_ok(s, o, &r);
    double sum = r.specular + r.diffuse + r.transmit + r.absorbed - r.roulette_net;
    assert_true(fabs(sum - 1.0) < 1e-9);
    double al = 0;
    for (int l = 0; l < s->nlayers; l++) al += r.absorbed_per_layer[l];
    assert_true(fabs(al - r.absorbed) < 1e-9);
    /* Roulette is unbiased: without the bookkeeping the sum is 1 within noise. */
    assert_true(fabs(sum + r.roulette_net - 1.0) < 0.02);
    ss_mc_result_free(&r);
}

static void test_energy_conservation(void **state) {
    (void)state;
    ss_mc_options o;
    ss_mc_options_default(&o);
    o.photons = nph(40000);
    ss_optics_slab s = one_layer(1.0, 10, 90, 0.75, 0.02);
    check_energy(&s, &o);
    /* mismatched three-layer slab, rough surface, oblique incidence */
    ss_optics_slab m;
    memset(&m, 0, sizeof m);
    m.nlayers = 3;
    m.layer[0] = (ss_optics_layer){1.5, 2, 50, 0.8, 0.01, 0, {0}};
    m.layer[1] = (ss_optics_layer){1.33, 0.5, 100, 0.9, 0.05, 0, {0}};
    m.layer[2] = (ss_optics_layer){1.4, 5, 20, 0.0, 0.1, 0, {0}};
    m.n_above = 1.0;
    m.n_below = 1.2;
    m.bottom_albedo = -1;
    o.roughness_sigma = 0.75;
    o.theta_i_rad = 0.6;
    check_energy(&m, &o);
    o.stochastic_absorb = 1;
    check_energy(&m, &o);
    /* the skin over its fat reflector */
    ss_bio_params b;
    ss_bio_params_default(&b);
    ss_optics_slab sk;
    ss_error e;
    assert_int_equal(ss_optics_skin_slab(&b, 560, &sk, &e), SS_OK);
    o.stochastic_absorb = 0;
    o.photons = nph(10000);
    check_energy(&sk, &o);
}

/* Chandrasekhar (Radiative Transfer, 1960): for a semi-infinite medium with
 * isotropic scattering and single-scattering albedo a, the total diffuse
 * reflectance of a collimated beam at cosine mu0 is 1 - H(mu0) sqrt(1 - a), with
 * 1/H(mu) = sqrt(1-a) + (a/2) int_0^1 mu' H(mu') / (mu + mu') dmu'. */
static double chandrasekhar_rd(double a, double mu0) {
    enum { N = 400 };
    double mu[N], wq[N], H[N];
    /* Gauss-Legendre on [0,1] via Newton on P_N */
    for (int i = 0; i < N; i++) {
        double x = cos(M_PI * (i + 0.75) / (N + 0.5)), dp = 1;
        for (int it = 0; it < 100; it++) {
            double p0 = 1, p1 = x;
            for (int k = 2; k <= N; k++) {
                double p2 = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            dp = N * (x * p1 - p0) / (x * x - 1);
            double dx = p1 / dp;
            x -= dx;
            if (fabs(dx) < 1e-15) break;
        }
        mu[i] = 0.5 * (x + 1);
        wq[i] = 1.0 / ((1 - x * x) * dp * dp); /* = 2/((1-x^2)P'^2) / 2 */
        H[i] = 1;
    }
    double s1a = sqrt(1 - a);
    for (int it = 0; it < 500; it++)
        for (int i = 0; i < N; i++) {
            double sum = 0;
            for (int j = 0; j < N; j++) sum += wq[j] * mu[j] * H[j] / (mu[i] + mu[j]);
            H[i] = 1.0 / (s1a + 0.5 * a * sum);
        }
    double sum = 0;
    for (int j = 0; j < N; j++) sum += wq[j] * mu[j] * H[j] / (mu0 + mu[j]);
    double H0 = 1.0 / (s1a + 0.5 * a * sum);
    return 1.0 - H0 * s1a;
}

static void test_semi_infinite_isotropic(void **state) {
    (void)state;
    double albedo[] = {0.9, 0.5};
    for (int k = 0; k < 2; k++) {
        double a = albedo[k];
        double ref = chandrasekhar_rd(a, 1.0);
        /* The reference itself against Hapke's (2002, Icarus 157:523) closed-form
         * approximation of H, good to about 1 %. */
        double y = sqrt(1 - a), r0 = (1 - y) / (1 + y);
        double Hh = 1.0 / (1 - (1 - y) * (r0 + (1 - 0.5 * r0 - r0) * log(2.0)));
        double refh = 1 - Hh * y;
        printf("semi-infinite a=%.1f: exact H-function Rd = %.5f (Hapke approx %.5f)\n", a, ref,
               refh);
        assert_true(fabs(ref - refh) < 0.01 * ref);
        /* 1000 transport mean free paths deep: semi-infinite for reflectance */
        ss_optics_slab s = one_layer(1.0, 100 * (1 - a), 100 * a, 0.0, 10.0);
        ss_mc_options o;
        ss_mc_options_default(&o);
        o.photons = nph(100000);
        o.seed = 3;
        ss_mc_result r;
        run_ok(&s, &o, &r);
        printf("semi-infinite MC: Rd %.5f +- %.5f\n", r.diffuse, r.diffuse_se);
        assert_true(fabs(r.diffuse - ref) < 3 * r.diffuse_se);
        ss_mc_result_free(&r);
    }
}

/* Fresnel: weighted-mode specular is the exact unpolarised Fresnel reflectance,
 * here against the sine/tangent closed forms. */
static double fresnel_closed(double n1, double n2, double ti) {
    if (ti == 0) return pow((n1 - n2) / (n1 + n2), 2);
    double tt = asin(n1 / n2 * sin(ti));
    double rs = pow(sin(ti - tt) / sin(ti + tt), 2);
    double rp = pow(tan(ti - tt) / tan(ti + tt), 2);
    return 0.5 * (rs + rp);
}

static void test_fresnel(void **state) {
    (void)state;
    ss_mc_options o;
    ss_mc_options_default(&o);
    o.photons = 1000;
    double angles[] = {0.0, 0.3, 0.7854, 1.0472, 1.4};
    double ns[] = {1.33, 1.4, 1.55};
    for (int a = 0; a < 5; a++)
        for (int k = 0; k < 3; k++) {
            ss_optics_slab s = one_layer(ns[k], 1, 10, 0.9, 0.1);
            o.theta_i_rad = angles[a];
            ss_mc_result r;
            run_ok(&s, &o, &r);
            double ref = fresnel_closed(1.0, ns[k], angles[a]);
            assert_true(fabs(r.specular - ref) < 1e-12);
            ss_mc_result_free(&r);
        }
    /* 0.04 for n = 1.5 at normal incidence */
    ss_optics_slab g = one_layer(1.5, 0, 0, 0, 0.1);
    o.theta_i_rad = 0;
    o.photons = nph(200000);
    ss_mc_result r;
    run_ok(&g, &o, &r);
    assert_true(fabs(r.specular - 0.04) < 1e-12);
    /* Clear glass plate: incoherent multiple reflections give total reflection
     * 2R/(1+R) and transmission (1-R)/(1+R). */
    double R = 0.04;
    printf("glass plate: R %.5f (ref %.5f) T %.5f +- %.5f (ref %.5f)\n", r.specular + r.diffuse,
           2 * R / (1 + R), r.transmit, r.transmit_se, (1 - R) / (1 + R));
    assert_true(fabs(r.transmit - (1 - R) / (1 + R)) < 3 * r.transmit_se + 1e-12);
    assert_true(fabs(r.specular + r.diffuse - 2 * R / (1 + R)) < 3 * r.transmit_se + 1e-12);
    ss_mc_result_free(&r);
}

static void test_brdf_and_radial_normalisation(void **state) {
    (void)state;
    ss_optics_slab s = one_layer(1.4, 1, 100, 0.8, 1.0);
    ss_mc_options o;
    ss_mc_options_default(&o);
    o.photons = nph(40000);
    o.theta_i_rad = 0.5;
    o.brdf_n_theta = 9;
    o.brdf_n_phi = 12;
    o.radial_bins = 200;
    o.radial_max_cm = 20.0;
    ss_mc_result r;
    run_ok(&s, &o, &r);
    /* sum f_r cos(theta_c) dOmega over bins = specular + diffuse (to rounding) */
    double tot = 0;
    for (int it = 0; it < 9; it++) {
        double t0 = it * M_PI / 18, t1 = t0 + M_PI / 18;
        double om = (cos(t0) - cos(t1)) * (M_PI / 12) * 2;
        for (int ip = 0; ip < 12; ip++) tot += r.brdf_exit[it * 12 + ip] * om * cos(t0 + M_PI / 36);
    }
    assert_true(fabs(tot - (r.specular + r.diffuse)) < 1e-9);
    /* The smooth-surface specular lands in the mirror bin: theta_r = theta_i, dphi = pi. */
    int it_spec = (int)(0.5 / (M_PI / 18));
    double t0 = it_spec * M_PI / 18;
    double om = (cos(t0) - cos(t0 + M_PI / 18)) * (M_PI / 12) * 2 * cos(t0 + M_PI / 36);
    assert_true(r.brdf_exit[it_spec * 12 + 11] * om >= r.specular);
    /* radial profile integrates to the diffuse reflectance (all within 20 cm) */
    double rad = 0;
    for (int i = 0; i < 200; i++) {
        double r0 = i * 0.1, r1 = r0 + 0.1;
        rad += r.radial[i] * M_PI * (r1 * r1 - r0 * r0);
    }
    assert_true(fabs(rad - r.diffuse) < 1e-3 * r.diffuse);
    /* and is monotonically decreasing away from the source on average */
    assert_true(r.radial[0] > r.radial[5] && r.radial[5] > r.radial[50]);
    ss_mc_result_free(&r);
}

static void test_determinism_threads(void **state) {
    (void)state;
    ss_bio_params b;
    ss_bio_params_default(&b);
    ss_optics_slab s;
    ss_error e;
    assert_int_equal(ss_optics_skin_slab(&b, 550, &s, &e), SS_OK);
    ss_mc_options o;
    ss_mc_options_default(&o);
    o.photons = nph(20000);
    o.roughness_sigma = 0.75;
    o.brdf_n_theta = 6;
    o.brdf_n_phi = 6;
    o.radial_bins = 20;
    o.radial_max_cm = 0.5;
    ss_mc_result a, c;
    omp_set_num_threads(1);
    run_ok(&s, &o, &a);
    omp_set_num_threads(2);
    run_ok(&s, &o, &c);
    assert_memory_equal(&a.diffuse, &c.diffuse, sizeof(double));
    assert_memory_equal(&a.transmit, &c.transmit, sizeof(double));
    assert_memory_equal(&a.absorbed, &c.absorbed, sizeof(double));
    assert_memory_equal(&a.diffuse_se, &c.diffuse_se, sizeof(double));
    assert_memory_equal(a.brdf_exit, c.brdf_exit, 36 * sizeof(double));
    assert_memory_equal(a.radial, c.radial, 20 * sizeof(double));
    assert_memory_equal(a.absorbed_per_layer, c.absorbed_per_layer, 4 * sizeof(double));
    /* a different seed gives a different estimate */
    o.seed = 99;
    ss_mc_result d;
    run_ok(&s, &o, &d);
    assert_true(d.diffuse != a.diffuse);
    ss_mc_result_free(&a);
    ss_mc_result_free(&c);
    ss_mc_result_free(&d);
}

/* Paths traced once without absorption, reweighted with exp(-sum mua L), agree
 * with direct runs at several absorption sets. */
static void test_paths_vs_run(void **state) {
    (void)state;
    ss_bio_params b;
    ss_bio_params_default(&b);
    ss_optics_slab s;
    ss_error e;
    assert_int_equal(ss_optics_skin_slab(&b, 600, &s, &e), SS_OK);
    ss_mc_options o;
    ss_mc_options_default(&o);
    o.photons = nph(20000);
    o.brdf_n_theta = 4;
    o.brdf_n_phi = 4;
    o.radial_bins = 10;
    o.radial_max_cm = 0.5;
    ss_mc_paths *p = NULL;
    assert_int_equal(ss_mc_trace_paths(&s, &o, &p, &e), SS_OK);
    double scale[] = {1.0, 3.0};
    for (int k = 0; k < 2; k++) {
        double mua[4];
        ss_optics_slab t = s;
        for (int l = 0; l < 4; l++) {
            mua[l] = s.layer[l].mua_per_cm * scale[k];
            t.layer[l].mua_per_cm = mua[l];
        }
        ss_mc_result a, r;
        assert_int_equal(ss_mc_paths_apply(p, mua, &a, &e), SS_OK);
        o.seed = 1000 + k;
        run_ok(&t, &o, &r);
        double se = sqrt(a.diffuse_se * a.diffuse_se + r.diffuse_se * r.diffuse_se);
        printf("paths vs run (mua x%g): %.5f vs %.5f (+- %.5f)\n", scale[k], a.diffuse, r.diffuse,
               se);
        assert_true(fabs(a.diffuse - r.diffuse) < 3.5 * se);
        assert_true(a.specular == r.specular);
        double sa = 0;
        for (int i = 0; i < 16; i++) sa += a.brdf_exit[i];
        assert_true(sa > 0);
        ss_mc_result_free(&a);
        ss_mc_result_free(&r);
    }
    double bad[4] = {1, -1, 1, 1};
    ss_mc_result x;
    assert_int_equal(ss_mc_paths_apply(p, bad, &x, &e), SS_ERR_INPUT);
    ss_mc_paths_free(p);
    /* a grey fat reflector (albedo 0.6) is applied per recorded bounce */
    s.bottom_albedo = 0.6;
    o.seed = 5;
    assert_int_equal(ss_mc_trace_paths(&s, &o, &p, &e), SS_OK);
    double mua[4];
    for (int l = 0; l < 4; l++) mua[l] = s.layer[l].mua_per_cm;
    ss_mc_result a, r;
    assert_int_equal(ss_mc_paths_apply(p, mua, &a, &e), SS_OK);
    o.seed = 6;
    run_ok(&s, &o, &r);
    double se = sqrt(a.diffuse_se * a.diffuse_se + r.diffuse_se * r.diffuse_se);
    printf("paths vs run (fat albedo 0.6): %.5f vs %.5f (+- %.5f)\n", a.diffuse, r.diffuse, se);
    assert_true(fabs(a.diffuse - r.diffuse) < 3.5 * se);
    ss_mc_result_free(&a);
    ss_mc_result_free(&r);
    ss_mc_paths_free(p);
}

static void test_bad_parameters(void **state) {
    (void)state;
    ss_bio_params b;
    ss_error e;
    ss_bio_params_default(&b);
    assert_int_equal(ss_bio_params_validate(&b, &e), SS_OK);
    b.melanin = -0.1;
    assert_int_equal(ss_bio_params_validate(&b, &e), SS_ERR_INPUT);
    assert_non_null(strstr(e.msg, "melanin"));
    ss_bio_params_default(&b);
    b.blood = 1.5;
    assert_int_equal(ss_bio_params_validate(&b, &e), SS_ERR_INPUT);
    ss_bio_params_default(&b);
    b.oxygenation = NAN;
    assert_int_equal(ss_bio_params_validate(&b, &e), SS_ERR_INPUT);
    ss_bio_params_default(&b);
    b.epidermis_thickness_cm = 0;
    assert_int_equal(ss_bio_params_validate(&b, &e), SS_ERR_INPUT);
    ss_optics_slab s;
    assert_int_equal(ss_optics_skin_slab(&b, 550, &s, &e), SS_ERR_INPUT);
    ss_bio_params_default(&b);
    assert_int_equal(ss_optics_skin_slab(&b, 1200, &s, &e), SS_ERR_INPUT);
    ss_optics_slab t = one_layer(1.0, 10, 90, 1.0, 0.02);
    ss_mc_options o;
    ss_mc_options_default(&o);
    ss_mc_result r;
    assert_int_equal(ss_mc_run(&t, &o, &r, &e), SS_ERR_INPUT); /* g = 1 */
    t = one_layer(1.0, 10, 90, 0.5, -1);
    assert_int_equal(ss_mc_run(&t, &o, &r, &e), SS_ERR_INPUT);
    t = one_layer(1.0, 10, 90, 0.5, 0.1);
    o.photons = 0;
    assert_int_equal(ss_mc_run(&t, &o, &r, &e), SS_ERR_INPUT);
    o.photons = 10;
    o.theta_i_rad = 2.0;
    assert_int_equal(ss_mc_run(&t, &o, &r, &e), SS_ERR_INPUT);
}

/* Chi-square statistic of n samples over nb equiprobable bins. */
static double chi2_of(const long *cnt, int nb, double n) {
    double e = n / nb, c2 = 0.0;
    for (int k = 0; k < nb; k++) c2 += (cnt[k] - e) * (cnt[k] - e) / e;
    return c2;
}

/* The transport's step lengths come from a ziggurat exponential sampler and
 * its azimuths from a polynomial sine/cosine: both must have exactly the
 * distributions they replace (-ln u; uniform angle on the unit circle). */
static void test_inner_loop_samplers(void **state) {
    (void)state;
    const size_t n = tu_quick() ? 500000 : 2000000;
    double *e = malloc(n * sizeof *e), *c = malloc(n * sizeof *c), *s = malloc(n * sizeof *s);
    assert_non_null(e);
    assert_non_null(c);
    assert_non_null(s);
    ss_mc_test_samplers(12345, n, e, c, s);
    enum { NB = 64 };
    long he[NB] = {0}, ha[NB] = {0};
    double m1 = 0, m2 = 0, cm = 0, sm = 0, maxdev = 0;
    const double tt[6] = {0.25, 1.0, 2.0, 4.0, 7.69711747013104972, 10.0};
    long tail[6] = {0};
    for (size_t i = 0; i < n; i++) {
        assert_true(e[i] > 0.0 && isfinite(e[i]));
        m1 += e[i];
        m2 += e[i] * e[i];
        for (int k = 0; k < 6; k++) tail[k] += e[i] > tt[k];
        int b = (int)((1.0 - exp(-e[i])) * NB); /* CDF: equiprobable bins */
        he[b < NB ? b : NB - 1]++;
        double dev = fabs(c[i] * c[i] + s[i] * s[i] - 1.0);
        if (dev > maxdev) maxdev = dev;
        cm += c[i];
        sm += s[i];
        int a = (int)((atan2(s[i], c[i]) + M_PI) / (2.0 * M_PI) * NB);
        ha[a < NB ? a : NB - 1]++;
    }
    double dn = (double)n;
    /* moments: mean 1 (variance 1), E[X^2] = 2 (variance 20); 5 sigma */
    assert_true(fabs(m1 / dn - 1.0) < 5.0 / sqrt(dn));
    assert_true(fabs(m2 / dn - 2.0) < 5.0 * sqrt(20.0 / dn));
    /* tails P(X > t) = exp(-t), including the ziggurat's base-strip tail r = 7.697 */
    for (int k = 0; k < 6; k++) {
        double p = exp(-tt[k]), sd = sqrt(p * (1 - p) / dn);
        assert_true(fabs(tail[k] / dn - p) < 5.0 * sd + 1.0 / dn);
    }
    /* 64 equiprobable bins, chi-square with 63 degrees of freedom (sd 11.2) */
    assert_true(chi2_of(he, NB, dn) < 63.0 + 6.0 * 11.2);
    assert_true(chi2_of(ha, NB, dn) < 63.0 + 6.0 * 11.2);
    /* unit vectors to rounding, centred (mean cos, sin: sd sqrt(0.5 / n)) */
    assert_true(maxdev < 1e-14);
    assert_true(fabs(cm / dn) < 5.0 * sqrt(0.5 / dn));
    assert_true(fabs(sm / dn) < 5.0 * sqrt(0.5 / dn));
    /* a pure function of the seed */
    double e2[8], c2[8], s2[8];
    ss_mc_test_samplers(12345, 8, e2, c2, s2);
    for (int i = 0; i < 8; i++) {
        assert_true(e2[i] == e[i]);
        assert_true(c2[i] == c[i] && s2[i] == s[i]);
    }
    free(e);
    free(c);
    free(s);
}

/* Seed §4.7.1's subsurface distance D (radial_distance = SS_RADIAL_PATH): the
 * horizontal path length summed over segments is at least the net distance of
 * every packet, and the random streams do not change, so the same packets
 * leave: the diffuse reflectance is identical and the cumulative Rd within
 * every radius is never larger with D than with the net distance; an
 * unknown mode is an input error. */
static void test_radial_path_distance(void **state) {
    (void)state;
    ss_error err;
    ss_optics_slab s = one_layer(1.4, 0.5, 100.0, 0.8, 0.2);
    ss_mc_options o;
    ss_mc_options_default(&o);
    o.photons = nph(40000);
    o.radial_bins = 40;
    o.radial_max_cm = 2.0;
    ss_mc_result net, path;
    assert_int_equal(ss_mc_run(&s, &o, &net, &err), SS_OK);
    o.radial_distance = SS_RADIAL_PATH;
    assert_int_equal(ss_mc_run(&s, &o, &path, &err), SS_OK);
    assert_true(net.diffuse == path.diffuse);
    double cn = 0, cp = 0, mn = 0, mp = 0;
    for (int k = 0; k < o.radial_bins; k++) {
        double r0 = k * 0.05, r1 = r0 + 0.05, area = M_PI * (r1 * r1 - r0 * r0);
        cn += net.radial[k] * area;
        cp += path.radial[k] * area;
        mn += net.radial[k] * area * 0.5 * (r0 + r1);
        mp += path.radial[k] * area * 0.5 * (r0 + r1);
        assert_true(cp <= cn * (1.0 + 1e-12));
    }
    assert_true(mp / cp > 1.2 * (mn / cn)); /* paths meander: D clearly exceeds r */
    ss_mc_result_free(&net);
    ss_mc_result_free(&path);
    o.radial_distance = 7;
    assert_int_equal(ss_mc_run(&s, &o, &net, &err), SS_ERR_INPUT);
}

/* ss_mc_options.cancel: polled by the calling thread only, after each block;
 * a non-zero answer stops the run with an error and an empty result; a
 * callback that never cancels leaves the result bit-identical. */
typedef struct cancel_count {
    int calls, stop_at;
    int off_thread; /* calls from a thread other than the caller's */
} cancel_count;
static int count_cancel(void *user) {
    cancel_count *c = user;
    if (omp_in_parallel() && omp_get_thread_num() != 0) c->off_thread++;
    return ++c->calls >= c->stop_at;
}
static void test_cancel(void **state) {
    (void)state;
    ss_optics_slab s = one_layer(1.4, 1, 100, 0.9, 0.1);
    ss_mc_options o;
    ss_mc_options_default(&o);
    o.photons = 64 * 2048; /* 64 blocks */
    o.seed = 5;
    ss_mc_result plain, polled, stopped;
    run_ok(&s, &o, &plain);
    cancel_count never = {0, 1 << 30, 0};
    o.cancel = count_cancel;
    o.cancel_user = &never;
    run_ok(&s, &o, &polled);
    assert_true(never.calls >= 1);
    assert_int_equal(never.off_thread, 0);
    assert_true(plain.diffuse == polled.diffuse && plain.transmit == polled.transmit &&
                plain.absorbed == polled.absorbed && plain.diffuse_se == polled.diffuse_se);
    cancel_count soon = {0, 2, 0};
    o.cancel_user = &soon;
    ss_error err;
    memset(&stopped, 0, sizeof stopped);
    assert_int_equal(ss_mc_run(&s, &o, &stopped, &err), SS_ERR_RUNTIME);
    assert_non_null(strstr(err.msg, "cancelled"));
    assert_int_equal(soon.calls, 2);
    assert_int_equal(soon.off_thread, 0);
    assert_null(stopped.absorbed_per_layer);
    ss_mc_result_free(&plain);
    ss_mc_result_free(&polled);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_van_de_hulst),
        cmocka_unit_test(test_cancel),
        cmocka_unit_test(test_unscattered),
        cmocka_unit_test(test_energy_conservation),
        cmocka_unit_test(test_semi_infinite_isotropic),
        cmocka_unit_test(test_fresnel),
        cmocka_unit_test(test_brdf_and_radial_normalisation),
        cmocka_unit_test(test_determinism_threads),
        cmocka_unit_test(test_paths_vs_run),
        cmocka_unit_test(test_bad_parameters),
        cmocka_unit_test(test_inner_loop_samplers),
        cmocka_unit_test(test_radial_path_distance),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
