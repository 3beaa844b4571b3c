/* skin (seed 003 §4.8, §5): profiles against the seed's formulas, golden-
 * section distance against dense brute force, exact feature counts, no
 * centre where the field is zero, the two samplers drawing the same
 * distribution (chi-square), feature effects and blend order on single
 * features, seamless wrap, determinism across thread counts, the
 * features.csv round trip, the render lookup against ss_mm_table_lookup,
 * feature contrast through the table at four tones (moles, hair), and bad
 * inputs. */
#include "testutil.h"
#include "skinsim/optics.h"
#include "skinsim/skin.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static double sigm(double x) { return 1.0 / (1.0 + exp(-x)); }

static void test_profiles(void **state) {
    (void)state;
    for (double r = 0.1; r < 3.0; r += 0.7)
        for (double d = 0.0; d < 3.0 * r; d += 0.05 * r) {
            /* §5.3.2 */
            assert_float_equal(ss_profile_sigmoid(d, r), 1.0 - (sigm(d / r * 4.0) - 0.5) * 2.0,
                               1e-12);
            /* §5.3.5 */
            double a = 1.0 - 1.2 * d / r;
            a = a < 0 ? 0 : a > 1 ? 1 : a;
            assert_float_equal(ss_profile_freckle(d, r), a, 1e-12);
        }
    assert_float_equal(ss_profile_sigmoid(0.0, 1.0), 1.0, 1e-12);
    /* follicle alpha: 1 inside r_i, 1 at r_i, ~0.013 at r_o, 0 beyond */
    assert_float_equal(ss_profile_follicle(0.02, 0.04, 0.1), 1.0, 0);
    assert_float_equal(ss_profile_follicle(0.04, 0.04, 0.1), 1.0, 1e-12);
    assert_float_equal(ss_profile_follicle(0.1, 0.04, 0.1), 2.0 * (1.0 - sigm(5.0)), 1e-12);
    assert_float_equal(ss_profile_follicle(0.11, 0.04, 0.1), 0.0, 0);
    /* §5.3.7 taper: 2tw below 1/2, 2(1-t)w above; w at the middle, 0 at the ends */
    assert_float_equal(ss_wrinkle_taper(0.25, 2.0), 1.0, 1e-12);
    assert_float_equal(ss_wrinkle_taper(0.75, 2.0), 1.0, 1e-12);
    assert_float_equal(ss_wrinkle_taper(0.5, 2.0), 2.0, 1e-12);
    assert_float_equal(ss_wrinkle_taper(0.0, 2.0), 0.0, 0);
    assert_float_equal(ss_wrinkle_taper(1.0, 2.0), 0.0, 0);
    /* wrinkle profile: 1 on the line, 0 at the width, in [0,1], decreasing */
    assert_float_equal(ss_profile_wrinkle(0.0, 0.3), 1.0, 0);
    assert_float_equal(ss_profile_wrinkle(0.3, 0.3), 0.0, 0);
    assert_float_equal(ss_profile_wrinkle(0.15, 0.3), 1.0 - pow(0.5, 0.2), 1e-12);
    assert_float_equal(ss_profile_wrinkle(0.1, 0.0), 0.0, 0);
    double prev = 2.0;
    for (double d = 0.0; d <= 0.3; d += 0.01) {
        double p = ss_profile_wrinkle(d, 0.3);
        assert_true(p >= 0.0 && p <= 1.0 && p <= prev);
        prev = p;
    }
}

static void test_bezier_golden_vs_dense(void **state) {
    (void)state;
    int n_curves = tu_quick() ? 20 : 100;
    for (int c = 0; c < n_curves; c++) {
        ss_bezier3 b;
        for (int i = 0; i < 4; i++) {
            b.x[i] = ss_rng_uniform(7, 1, (uint64_t)c * 8 + i);
            b.y[i] = ss_rng_uniform(7, 1, (uint64_t)c * 8 + 4 + i);
        }
        /* the endpoints evaluate exactly */
        double x, y;
        ss_bezier3_eval(&b, 0.0, &x, &y);
        assert_true(x == b.x[0] && y == b.y[0]);
        ss_bezier3_eval(&b, 1.0, &x, &y);
        assert_float_equal(x, b.x[3], 1e-15);
        for (int k = 0; k < 20; k++) {
            double px = ss_rng_uniform(7, 2, (uint64_t)c * 64 + k) * 1.4 - 0.2;
            double py = ss_rng_uniform(7, 3, (uint64_t)c * 64 + k) * 1.4 - 0.2;
            double tg, td;
            double dg = ss_bezier3_distance(&b, px, py, 8, 1e-10, INFINITY, &tg);
            /* with a reach, either the same answer or a proof it is beyond */
            double tr, dr = ss_bezier3_distance(&b, px, py, 8, 1e-10, 0.1, &tr);
            assert_true(dr == dg || (dr == INFINITY && dg > 0.1));
            double dd = ss_bezier3_distance_dense(&b, px, py, 100000, &td);
            /* golden section is at least as close as the dense samples, and
             * no farther than what the dense grid can miss */
            assert_true(dg <= dd + 1e-12);
            assert_true(dd - dg < 1e-6);
            ss_bezier3_eval(&b, tg, &x, &y);
            assert_float_equal(hypot(x - px, y - py), dg, 1e-12);
        }
    }
}

static ss_skin_settings small_settings(int size) {
    ss_skin_settings s;
    ss_error err;
    assert_int_equal(ss_skin_settings_preset(&s, "seed", size, &err), SS_OK);
    s.world_size_cm = 2.0;
    long c[SS_FEAT_NTYPES] = {40, 7, 30, 10, 900};
    memcpy(s.count, c, sizeof c);
    return s;
}

static void test_counts_and_zero_field(void **state) {
    (void)state;
    ss_error err;
    ss_skin_settings s = small_settings(64);
    /* field: black on the left half and at the top-right texel */
    ss_image *f = ss_image_create(16, 8, 1, &err);
    for (int y = 0; y < 8; y++)
        for (int x = 8; x < 16; x++) ss_image_px(f, x, y)[0] = (float)(x - 7) / 8.0f;
    ss_image_px(f, 15, 0)[0] = 0.0f;
    for (int sampler = 0; sampler < 2; sampler++) {
        s.sampler = sampler;
        ss_skin_fields fields;
        memset(&fields, 0, sizeof fields);
        for (int t = 0; t < SS_FEAT_NTYPES; t++) fields.density[t] = f;
        ss_skin_feature_list l;
        char notes[512];
        assert_int_equal(ss_skin_generate(&s, &fields, &l, notes, sizeof notes, &err), SS_OK);
        long cnt[SS_FEAT_NTYPES] = {0};
        for (size_t i = 0; i < l.n; i++) {
            cnt[l.f[i].type]++;
            /* centres (wrinkle starts) never where the field is zero */
            int tx = (int)(l.f[i].x * 16), ty = (int)(l.f[i].y * 8);
            assert_true(tx >= 8 && tx < 16 && ty >= 0 && ty < 8);
            assert_false(tx == 15 && ty == 0);
            if (i) assert_true(l.f[i].type >= l.f[i - 1].type);
        }
        for (int t = 0; t < SS_FEAT_NTYPES; t++) assert_int_equal(cnt[t], s.count[t]);
        ss_skin_feature_list_free(&l);
    }
    /* an all-black field: no features of that type, and a note */
    ss_image *black = ss_image_create(4, 4, 1, &err);
    ss_skin_fields fields;
    memset(&fields, 0, sizeof fields);
    fields.density[SS_FEAT_MOLE] = black;
    ss_skin_feature_list l;
    char notes[512];
    assert_int_equal(ss_skin_generate(&s, &fields, &l, notes, sizeof notes, &err), SS_OK);
    for (size_t i = 0; i < l.n; i++) assert_int_not_equal(l.f[i].type, SS_FEAT_MOLE);
    assert_non_null(strstr(notes, "moles: field is all black"));
    ss_skin_feature_list_free(&l);
    /* NaN in a field is an input error */
    ss_image_px(black, 1, 1)[0] = NAN;
    assert_int_equal(ss_skin_generate(&s, &fields, &l, NULL, 0, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "moles"));
    /* a vector field with only zero vectors */
    ss_image *vz = ss_image_create(4, 4, 3, &err);
    for (int i = 0; i < 16; i++)
        vz->data[3 * i] = vz->data[3 * i + 1] = 0.5f, vz->data[3 * i + 2] = 1;
    memset(&fields, 0, sizeof fields);
    fields.wrinkle_vectors = vz;
    assert_int_equal(ss_skin_generate(&s, &fields, &l, NULL, 0, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "zero"));
    /* negative counts, unknown constants */
    s.count[SS_FEAT_CYST] = -1;
    assert_int_equal(ss_skin_generate(&s, NULL, &l, NULL, 0, &err), SS_ERR_INPUT);
    assert_int_equal(ss_skin_dist_set(&s.dist, "moles.nope", 1.0, &err), SS_ERR_INPUT);
    assert_int_equal(ss_skin_dist_set(&s.dist, "moles.r_sigma", NAN, &err), SS_ERR_INPUT);
    assert_int_equal(ss_skin_dist_set(&s.dist, "moles.r_sigma", 0.5, &err), SS_OK);
    assert_float_equal(ss_skin_dist_get(&s.dist, "moles.r_sigma"), 0.5, 0);
    assert_int_equal(ss_feature_type_from_name("mole"), SS_FEAT_MOLE);
    assert_int_equal(ss_feature_type_from_name("warts"), -1);
    ss_image_free(vz);
    ss_image_free(black);
    ss_image_free(f);
}

/* The two samplers draw the same distribution: a two-sample chi-square on
 * 2 x 2 bins per texel of a gradient field (so the jitter inside texels is
 * tested too), and each against the expected counts. */
static void test_samplers_agree(void **state) {
    (void)state;
    ss_error err;
    const int W = 8, H = 6, B = 2;
    ss_image *f = ss_image_create(W, H, 1, &err);
    double tot = 0.0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            tot += ss_image_px(f, x, y)[0] = (float)(x + 1) * (y + 2) / 64.0f;
    size_t n = tu_quick() ? 60000 : 300000;
    double *a = malloc(2 * n * sizeof *a), *b = malloc(2 * n * sizeof *b);
    assert_int_equal(ss_skin_sample_points(f, 1.0, SS_SAMPLER_ALIAS, 5, 1, n, a, &err), SS_OK);
    assert_int_equal(ss_skin_sample_points(f, 1.0, SS_SAMPLER_REJECTION, 5, 1, n, b, &err), SS_OK);
    int nb = W * B * H * B;
    double *ca = calloc((size_t)nb, sizeof *ca), *cb = calloc((size_t)nb, sizeof *cb);
    for (size_t k = 0; k < n; k++) {
        int ia = (int)(a[2 * k + 1] * H * B) * W * B + (int)(a[2 * k] * W * B);
        int ib = (int)(b[2 * k + 1] * H * B) * W * B + (int)(b[2 * k] * W * B);
        assert_true(ia >= 0 && ia < nb && ib >= 0 && ib < nb);
        ca[ia]++, cb[ib]++;
    }
    double chi2 = 0.0, chia = 0.0, chib = 0.0;
    for (int i = 0; i < nb; i++) {
        int tx = (i % (W * B)) / B, ty = (i / (W * B)) / B;
        double e = (double)n * ss_image_px(f, tx, ty)[0] / tot / (B * B);
        if (ca[i] + cb[i] > 0) chi2 += (ca[i] - cb[i]) * (ca[i] - cb[i]) / (ca[i] + cb[i]);
        chia += (ca[i] - e) * (ca[i] - e) / e;
        chib += (cb[i] - e) * (cb[i] - e) / e;
    }
    double dof = nb - 1, lim = dof + 5.0 * sqrt(2.0 * dof); /* about p = 1e-5 */
    print_message("chi-square (dof %.0f): alias vs rejection %.1f, alias %.1f, rejection %.1f\n",
                  dof, chi2, chia, chib);
    assert_true(chi2 < lim);
    assert_true(chia < lim);
    assert_true(chib < lim);
    /* power: the freckle field raised to i concentrates the points */
    assert_int_equal(ss_skin_sample_points(f, 3.0, SS_SAMPLER_ALIAS, 5, 1, n, a, &err), SS_OK);
    double mx1 = 0, mx3 = 0;
    for (size_t k = 0; k < n; k++) mx1 += b[2 * k], mx3 += a[2 * k];
    assert_true(mx3 / n > mx1 / n + 0.05);
    free(ca), free(cb), free(a), free(b);
    ss_image_free(f);
}

/* One feature of each kind at the centre on a flat baseline (phi = 0): the
 * bio map equals the seed's formula at texel centres; follicles lower the
 * blood that the lips set (blend order, §4.8.5). */
static void test_single_features(void **state) {
    (void)state;
    ss_error err;
    ss_skin_settings s = small_settings(64);
    s.phi = 0.0;
    s.dist.mottle_melanin = s.dist.mottle_blood = s.dist.mottle_height = 0.0;
    s.dist.relief_depth = s.dist.relief_depth2 = 0.0; /* no network */
    s.world_size_cm = 0.64;                           /* 0.1 mm texels */
    const double mm = 6.4;                            /* mm per texture unit */
    ss_skin_feature fs[3];
    memset(fs, 0, sizeof fs);
    fs[0].type = SS_FEAT_MOLE, fs[0].x = 0.25, fs[0].y = 0.25, fs[0].r = 0.5, fs[0].h = 0.6,
    fs[0].m = 0.2;
    fs[1].type = SS_FEAT_CYST, fs[1].x = 0.75, fs[1].y = 0.25, fs[1].r = 0.4, fs[1].h = 0.3;
    fs[2].type = SS_FEAT_FOLLICLE, fs[2].x = 0.5, fs[2].y = 0.75, fs[2].r = 0.15, fs[2].r2 = 0.4;
    ss_skin_feature_list l = {3, fs};
    ss_image *lips = ss_image_create(2, 2, 1, &err);
    for (int i = 0; i < 4; i++) lips->data[i] = 1.0f;
    ss_skin_fields fields;
    memset(&fields, 0, sizeof fields);
    fields.lips = lips;
    ss_image *bio = ss_skin_bio_maps(&s, &fields, &l, &err);
    assert_non_null(bio);
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 64; x++) {
            const float *p = ss_image_px(bio, x, y);
            double u = (x + 0.5) / 64, v = (y + 0.5) / 64;
            double dm = hypot(u - 0.25, v - 0.25) * mm, dc = hypot(u - 0.75, v - 0.25) * mm,
                   df = hypot(u - 0.5, v - 0.75) * mm;
            /* the mole: its outline and sharp border, uniform pigment */
            double sm = ss_profile_mole(dm, ss_mole_outline(0.5, atan2(v - 0.25, u - 0.25)),
                                        s.dist.mole_border);
            double sc = dc < 0.8 ? ss_profile_sigmoid(dc, 0.4) : 0.0;
            double al = ss_profile_follicle(df, 0.15, 0.4);
            const double lo = s.base_lo[SS_BIO_MELANIN];
            double mel = lo + sm * 0.2 * (1.0 + s.dist.mole_tone_gain * lo); /* follows the tone */
            /* the hair: the texel goes to the hair's pigment by the alpha */
            const double mh = s.dist.hair_melanin + s.dist.hair_gain * lo;
            mel += (mh - lo) * al;
            const double pheo = s.dist.lip_pheomelanin +
                                (s.dist.hair_pheomelanin / mh - s.dist.lip_pheomelanin) * al;
            double h = sc * 0.3 + 0.6 * sm * 0.2;
            if (df > 0.15) h -= 0.012 * al; /* the follicle opening's pit */
            if (df <= 0.15 && h < s.dist.follicle_height) h = s.dist.follicle_height;
            double blood = s.dist.lip_blood * (1.0 - s.dist.follicle_blood_drop * al);
            assert_float_equal(p[SS_BIO_MELANIN], mel, 2e-6);
            assert_float_equal(p[SS_BIO_HEIGHT_MM], h, 2e-6);
            assert_float_equal(p[SS_BIO_BLOOD], blood, 2e-6);
            assert_float_equal(p[SS_BIO_PHEOMELANIN], pheo, 2e-6);
            assert_float_equal(p[SS_BIO_EXTRA_A], 0.0, 0); /* hair is pigment, no extra colour */
        }
    ss_image_free(bio);
    ss_image_free(lips);
}

/* A follicle smaller than a texel is area-sampled: on 0.2 mm texels an
 * opening of r_i 0.04 mm darkens by the area it covers, wherever it falls
 * in its texel. Moved by a fraction of a texel, its summed alpha (its
 * coverage, read as the share of the hair's melanin its texels took) stays within 10 % and near the
 * disk integral; its peak texel stays well under full contrast (point sampling: 1 at the texel
 * centre, 0 a quarter texel away). */
static void test_follicle_area_sampled(void **state) {
    (void)state;
    ss_error err;
    ss_skin_settings s = small_settings(32);
    s.phi = 0.0;
    s.dist.mottle_melanin = s.dist.mottle_blood = s.dist.mottle_height = 0.0;
    s.dist.relief_depth = s.dist.relief_depth2 = 0.0;
    s.world_size_cm = 0.64; /* 0.2 mm texels */
    const double texel = 0.2, ri = 0.04, ro = 0.1;
    /* the disk integral of the alpha, by dense sampling, in texels */
    double want = 0.0;
    const int M = 400;
    for (int j = 0; j < M; j++)
        for (int i = 0; i < M; i++) {
            double x = -ro + 2 * ro * (i + 0.5) / M, y = -ro + 2 * ro * (j + 0.5) / M;
            want += ss_profile_follicle(hypot(x, y), ri, ro);
        }
    want *= (2 * ro / M) * (2 * ro / M) / (texel * texel);
    const double offs[4][2] = {{0.5, 0.5}, {0.0, 0.0}, {0.25, 0.7}, {0.9, 0.1}};
    double sums[4];
    for (int k = 0; k < 4; k++) {
        ss_skin_feature f;
        memset(&f, 0, sizeof f);
        f.type = SS_FEAT_FOLLICLE, f.r = ri, f.r2 = ro;
        f.x = (16 + offs[k][0]) / 32.0, f.y = (16 + offs[k][1]) / 32.0;
        ss_skin_feature_list l = {1, &f};
        ss_image *bio = ss_skin_bio_maps(&s, NULL, &l, &err);
        assert_non_null(bio);
        double sum = 0.0, peak = 0.0;
        /* the alpha is the share of the hair's pigment a texel took */
        const double lo = s.base_lo[SS_BIO_MELANIN];
        const double mh = s.dist.hair_melanin + s.dist.hair_gain * lo;
        for (int i = 0; i < 32 * 32; i++) {
            double a = (bio->data[(size_t)i * SS_BIO_NCHANNELS + SS_BIO_MELANIN] - lo) / (mh - lo);
            sum += a;
            peak = fmax(peak, a);
        }
        print_message("follicle at +%.2f,+%.2f texel: coverage %.4f (disk %.4f), peak %.3f\n",
                      offs[k][0], offs[k][1], sum, want, peak);
        assert_true(fabs(sum - want) < 0.15 * want);
        assert_true(peak < 0.6);
        sums[k] = sum;
        ss_image_free(bio);
    }
    for (int k = 1; k < 4; k++) assert_true(fabs(sums[k] - sums[0]) < 0.1 * sums[0]);
}

/* Features crossing the edges wrap: every map's last column continues into
 * its first (and last row into the first) as smoothly as neighbouring
 * columns continue each other. */
static void test_seamless_wrap(void **state) {
    (void)state;
    ss_error err;
    ss_skin_settings s = small_settings(128);
    s.phi = 0.0; /* look at the features only */
    s.count[SS_FEAT_CYST] = 400, s.count[SS_FEAT_FRECKLE] = 200, s.count[SS_FEAT_WRINKLE] = 200;
    s.dist.wrinkle_max_length = 4.0;
    ss_skin_feature_list l;
    assert_int_equal(ss_skin_generate(&s, NULL, &l, NULL, 0, &err), SS_OK);
    ss_image *bio = ss_skin_bio_maps(&s, NULL, &l, &err);
    assert_non_null(bio);
    const int N = 128;
    for (int c = 0; c < SS_BIO_NCHANNELS; c++) {
        if (c == SS_BIO_OXYGENATION || c == SS_BIO_SC_CM || c == SS_BIO_EPIDERMIS_CM) continue;
        if (c >= SS_BIO_EXTRA_R && c <= SS_BIO_EXTRA_A) { /* none: the hair is pigment */
            for (int i = 0; i < N * N; i++)
                assert_true(bio->data[(size_t)i * SS_BIO_NCHANNELS + c] == 0.0f);
            continue;
        }
        double maxc = 0.0, maxr = 0.0, wc = 0.0, wr = 0.0;
        for (int x = 0; x < N; x++) {
            double dc = 0.0, dr = 0.0;
            for (int y = 0; y < N; y++) {
                dc += fabs(ss_image_px(bio, (x + 1) % N, y)[c] - ss_image_px(bio, x, y)[c]);
                dr += fabs(ss_image_px(bio, y, (x + 1) % N)[c] - ss_image_px(bio, y, x)[c]);
            }
            if (x == N - 1)
                wc = dc, wr = dr;
            else {
                if (dc > maxc) maxc = dc;
                if (dr > maxr) maxr = dr;
            }
        }
        assert_true(maxc > 0.0);
        /* 5 % slack: with the microrelief network everywhere, every column
         * pair differs alike and the seam is one draw among 128 of them; a
         * cut feature would exceed the roughest pair by far more */
        if (!(wc <= 1.05 * maxc && wr <= 1.05 * maxr))
            print_error("channel %d: seam %g %g, roughest pair %g %g\n", c, wc, wr, maxc, maxr);
        assert_true(wc <= 1.05 * maxc);
        assert_true(wr <= 1.05 * maxr);
    }
    /* with --no-wrap the same features are cut at the edge: the seam is larger */
    s.wrap = 0;
    ss_image *nw = ss_skin_bio_maps(&s, NULL, &l, &err);
    double seam = 0, seamw = 0;
    for (int y = 0; y < N; y++) {
        seam += fabs(ss_image_px(nw, 0, y)[SS_BIO_HEIGHT_MM] -
                     ss_image_px(nw, N - 1, y)[SS_BIO_HEIGHT_MM]);
        seamw += fabs(ss_image_px(bio, 0, y)[SS_BIO_HEIGHT_MM] -
                      ss_image_px(bio, N - 1, y)[SS_BIO_HEIGHT_MM]);
    }
    assert_true(seam != seamw);
    ss_image_free(nw);
    ss_image_free(bio);
    ss_skin_feature_list_free(&l);
}

static ss_mm_table *load_table(void) {
    ss_error err;
    ss_mm_table *t = ss_mm_table_read(SKINSIM_SOURCE_DIR "/data/modelmatch_default.sstab", &err);
    if (!t) print_error("%s\n", err.msg);
    assert_non_null(t);
    return t;
}

static void test_determinism_and_roundtrip(void **state) {
    (void)state;
    ss_error err;
    ss_skin_settings s = small_settings(tu_quick() ? 96 : 192);
    ss_mm_table *t = load_table();
    ss_skin_lut *lut = ss_skin_lut_create(t, &err);
    assert_non_null(lut);
    ss_image *bio[2];
    ss_skin_maps maps[2];
    ss_skin_feature_list l[2];
    for (int k = 0; k < 2; k++) {
        ss_threads_set(k + 1);
        assert_int_equal(ss_skin_generate(&s, NULL, &l[k], NULL, 0, &err), SS_OK);
        bio[k] = ss_skin_bio_maps(&s, NULL, &l[k], &err);
        assert_non_null(bio[k]);
        assert_int_equal(ss_skin_render_maps(bio[k], lut, s.world_size_cm, 0, &maps[k], &err),
                         SS_OK);
    }
    ss_threads_set(0);
    size_t n = (size_t)s.size * s.size;
    assert_int_equal(l[0].n, l[1].n);
    assert_memory_equal(l[0].f, l[1].f, l[0].n * sizeof *l[0].f);
    assert_memory_equal(bio[0]->data, bio[1]->data, n * SS_BIO_NCHANNELS * sizeof(float));
    assert_memory_equal(maps[0].base_color->data, maps[1].base_color->data, n * 3 * sizeof(float));
    assert_memory_equal(maps[0].normal->data, maps[1].normal->data, n * 3 * sizeof(float));
    /* features.csv round trip: the same list, bit for bit, and the same maps */
    char *dir = tu_tmpdir("skin");
    char path[4096];
    snprintf(path, sizeof path, "%s/features.csv", dir);
    assert_int_equal(ss_skin_features_write_csv(path, &l[0], &err), SS_OK);
    ss_skin_feature_list back;
    assert_int_equal(ss_skin_features_read_csv(path, &back, &err), SS_OK);
    assert_int_equal(back.n, l[0].n);
    for (size_t i = 0; i < back.n; i++) {
        const ss_skin_feature *a = &l[0].f[i], *b = &back.f[i];
        assert_int_equal(a->type, b->type);
        assert_true(a->x == b->x && a->y == b->y && a->r == b->r && a->r2 == b->r2 &&
                    a->h == b->h && a->m == b->m && a->p == b->p && a->w == b->w);
        if (a->type == SS_FEAT_WRINKLE) assert_memory_equal(&a->curve, &b->curve, sizeof a->curve);
    }
    ss_image *bio2 = ss_skin_bio_maps(&s, NULL, &back, &err);
    assert_memory_equal(bio2->data, bio[0]->data, n * SS_BIO_NCHANNELS * sizeof(float));
    /* the bio map survives bio.exr with its channel names */
    const char *names[SS_BIO_NCHANNELS];
    for (int c = 0; c < SS_BIO_NCHANNELS; c++) names[c] = ss_bio_channel_name(c);
    snprintf(path, sizeof path, "%s/bio.exr", dir);
    assert_int_equal(ss_exr_write_channels(path, bio2, names, 0, &err), SS_OK);
    ss_image *rd = ss_exr_read_channels(path, names, SS_BIO_NCHANNELS, &err);
    assert_non_null(rd);
    assert_memory_equal(rd->data, bio2->data, n * SS_BIO_NCHANNELS * sizeof(float));
    ss_image_free(rd);
    ss_skin_feature_list_free(&back);
    /* bad rows name the file and line */
    assert_int_equal(ss_skin_features_parse_csv("type,x,y,r,r2,h,m,p,w,x1,y1,x2,y2,x3,y3\n"
                                                "wart,0.5,0.5,1,0,0,0,0,0,0,0,0,0,0,0\n",
                                                "f.csv", &back, &err),
                     SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "f.csv:2"));
    assert_int_equal(ss_skin_features_parse_csv("type,x,y,r,r2,h,m,p,w,x1,y1,x2,y2,x3,y3\n"
                                                "moles,0.5,nan,1,0,0,0,0,0,0,0,0,0,0,0\n",
                                                "f.csv", &back, &err),
                     SS_ERR_INPUT);
    assert_int_equal(ss_skin_features_parse_csv("x,y\n", "f.csv", &back, &err), SS_ERR_INPUT);
    /* a texel as the optics model's parameters: valid, and the table lookup of
     * them equals the render map */
    ss_bio_params bp;
    ss_skin_bio_texel(bio2, 5, 7, &bp);
    assert_int_equal(ss_bio_params_validate(&bp, &err), SS_OK);
    ss_mm_entry me;
    assert_int_equal(ss_mm_table_lookup_bio(t, &bp, &me, &err), SS_OK);
    const float *px = ss_image_px(bio2, 5, 7);
    double sc; /* the base colour kept under the texel's own lobe */
    ss_mm_surface_lobe(t, px[SS_BIO_SURFACE_SIGMA], NULL, NULL, &sc);
    if (px[SS_BIO_EXTRA_A] == 0.0f)
        for (int c = 0; c < 3; c++)
            assert_float_equal(ss_image_px(maps[0].base_color, 5, 7)[c],
                               fmin(1.0, fmax(0.0, me.fit[SS_RENDER_GGX].base_rgb[c] * sc)), 2e-5);
    ss_image_free(bio2);
    tu_rmtree(dir);
    free(dir);
    for (int k = 0; k < 2; k++) {
        ss_image_free(bio[k]);
        ss_skin_maps_free(&maps[k]);
        ss_skin_feature_list_free(&l[k]);
    }
    ss_skin_lut_free(lut);
    ss_mm_table_free(t);
}

/* The texture lookup equals the table's own multilinear lookup. */
static void test_lut_matches_table(void **state) {
    (void)state;
    ss_error err;
    ss_mm_table *t = load_table();
    ss_skin_lut *lut = ss_skin_lut_create(t, &err);
    for (int k = 0; k < 2000; k++) {
        double x[SS_MM_NAXES];
        float xf[6], out[5];
        for (int a = 0; a < SS_MM_NAXES; a++) {
            double lo, hi;
            ss_mm_axis_default_range(a, &lo, &hi);
            double u = ss_rng_uniform(3, 9, (uint64_t)k * 8 + a) * 1.2 - 0.1; /* some outside */
            xf[a] = (float)(lo + u * (hi - lo));
            x[a] = xf[a];
        }
        double ref[SS_MM_NFIELDS];
        ss_mm_table_lookup(t, x, ref);
        ss_skin_lut_lookup(lut, xf, out);
        for (int c = 0; c < 3; c++) assert_float_equal(out[c], ref[c], 2e-5);
        assert_float_equal(out[3], ref[3], 2e-5);
        assert_float_equal(out[4], ref[4], 2e-5);
    }
    ss_skin_lut_free(lut);
    ss_mm_table_free(t);
}

/* The cached lookup (ss_skin_lut_lookup_cached, the wound renderer's per
 * thread) gives exactly the uncached values, bit for bit: points in a few
 * neighbouring cells (cache hits) and scattered ones (misses and slot
 * collisions), and a NULL cache. */
static void test_lut_cache_exact(void **state) {
    (void)state;
    ss_error err;
    ss_mm_table *t = load_table();
    ss_skin_lut *lut = ss_skin_lut_create(t, &err);
    ss_skin_lut_cache *c = ss_skin_lut_cache_create();
    assert_non_null(c);
    for (int k = 0; k < 4000; k++) {
        float xf[6], a[5], b[5], d[5];
        for (int ax = 0; ax < SS_MM_NAXES; ax++) {
            double lo, hi;
            ss_mm_axis_default_range(ax, &lo, &hi);
            double u = ss_rng_uniform(5, 1, (uint64_t)k * 8 + ax);
            if (k % 2) u = 0.4 + 0.05 * u; /* near one point: repeated cells */
            xf[ax] = (float)(lo + u * (hi - lo));
        }
        ss_skin_lut_lookup(lut, xf, a);
        ss_skin_lut_lookup_cached(lut, c, xf, b);
        ss_skin_lut_lookup_cached(lut, NULL, xf, d);
        assert_memory_equal(a, b, sizeof a);
        assert_memory_equal(a, d, sizeof a);
    }
    ss_skin_lut_cache_free(c);
    ss_skin_lut_free(lut);
    ss_mm_table_free(t);
}

/* Another table shape plugs in: single-sample axes and other sample counts,
 * entries a known function of the node; the lookup equals the table's. */
static void test_lut_other_table(void **state) {
    (void)state;
    ss_error err;
    const int ns[SS_MM_NAXES] = {3, 1, 2, 1, 4, 2};
    double lo[SS_MM_NAXES], hi[SS_MM_NAXES];
    for (int a = 0; a < SS_MM_NAXES; a++) ss_mm_axis_default_range(a, &lo[a], &hi[a]);
    ss_mm_table *t = ss_mm_table_create(ns, lo, hi, &err);
    assert_non_null(t);
    for (size_t e = 0; e < t->nentries; e++)
        for (int f = 0; f < SS_MM_NFIELDS; f++)
            t->entries[e * SS_MM_NFIELDS + f] = sin(0.7 * (double)e + f) * 0.5 + 0.5;
    ss_skin_lut *lut = ss_skin_lut_create(t, &err);
    assert_non_null(lut);
    for (int k = 0; k < 500; k++) {
        double x[SS_MM_NAXES], ref[SS_MM_NFIELDS];
        float xf[6], out[5];
        for (int a = 0; a < SS_MM_NAXES; a++) {
            double u = ss_rng_uniform(4, 2, (uint64_t)k * 8 + a) * 1.2 - 0.1;
            xf[a] = (float)(lo[a] + u * (hi[a] - lo[a]));
            x[a] = xf[a];
        }
        ss_mm_table_lookup(t, x, ref);
        ss_skin_lut_lookup(lut, xf, out);
        for (int f = 0; f < 5; f++) assert_float_equal(out[f], ref[f], 2e-6);
    }
    ss_skin_lut_free(lut);
    ss_mm_table_free(t);
}

/* Mean and sd over cells of cell_mm of one bio channel, and the mean
 * |difference| of horizontally neighbouring texels. */
static void cell_stats(const ss_image *bio, int ch, double world_mm, double cell_mm, double *sd,
                       double *neighbour, double *cells, int *ncell) {
    const int N = bio->width, cw = (int)lround(cell_mm / world_mm * N), nc = N / cw;
    double s1 = 0, s2 = 0, nb = 0;
    for (int cy = 0; cy < nc; cy++)
        for (int cx = 0; cx < nc; cx++) {
            double m = 0;
            for (int y = 0; y < cw; y++)
                for (int x = 0; x < cw; x++) m += ss_image_px(bio, cx * cw + x, cy * cw + y)[ch];
            m /= (double)cw * cw;
            if (cells) cells[cy * nc + cx] = m;
            s1 += m, s2 += m * m;
        }
    const double n = (double)nc * nc, mean = s1 / n;
    *sd = sqrt(fmax(0.0, s2 / n - mean * mean));
    for (int y = 0; y < N; y++)
        for (int x = 0; x + 1 < N; x++)
            nb += fabs(ss_image_px(bio, x + 1, y)[ch] - ss_image_px(bio, x, y)[ch]);
    *neighbour = nb / ((double)N * (N - 1));
    if (ncell) *ncell = nc * nc;
}

/* Colour and height variation is defined in mm: the same world patch at
 * two texture sizes has the same statistics over mm-sized cells (and the
 * same cell means, cell by cell), and no per-texel noise (neighbouring
 * texels at half the texel size differ about half as much). */
static void test_mm_defined_variation(void **state) {
    (void)state;
    ss_error err;
    const int sizes[2] = {192, 384};
    const double world_mm = 24.0;
    ss_image *bio[2];
    for (int k = 0; k < 2; k++) {
        ss_skin_settings s;
        assert_int_equal(ss_skin_settings_preset(&s, "forearm", sizes[k], &err), SS_OK);
        s.world_size_cm = world_mm / 10.0;
        ss_skin_forearm_counts(s.world_size_cm, s.count);
        s.seed = 11;
        ss_skin_feature_list l;
        assert_int_equal(ss_skin_generate(&s, NULL, &l, NULL, 0, &err), SS_OK);
        bio[k] = ss_skin_bio_maps(&s, NULL, &l, &err);
        assert_non_null(bio[k]);
        ss_skin_feature_list_free(&l);
    }
    const int chans[3] = {SS_BIO_MELANIN, SS_BIO_BLOOD, SS_BIO_HEIGHT_MM};
    for (int c = 0; c < 3; c++)
        for (int cell = 0; cell < 2; cell++) {
            const double cmm = cell ? 1.0 : 0.5;
            double sd[2], nb[2];
            static double cells[2][4096];
            int nc = 0;
            for (int k = 0; k < 2; k++)
                cell_stats(bio[k], chans[c], world_mm, cmm, &sd[k], &nb[k], cells[k], &nc);
            print_message("channel %d, %.1f mm cells: sd %.5g / %.5g, neighbour %.3g / %.3g\n",
                          chans[c], cmm, sd[0], sd[1], nb[0], nb[1]);
            assert_true(sd[0] > 0.0);
            assert_true(fabs(sd[1] / sd[0] - 1.0) < 0.1);
            double dif = 0;
            for (int i = 0; i < nc; i++) dif += fabs(cells[1][i] - cells[0][i]);
            print_message("  cell by cell: mean |difference| %.3g sd\n", dif / nc / sd[0]);
            /* the same patch, cell by cell (height: the follicle stubs and
             * Bezier furrows are narrower than a texel and point-sampled) */
            assert_true(dif / nc < (chans[c] == SS_BIO_HEIGHT_MM ? 0.6 : 0.25) * sd[0]);
            /* no per-texel noise: neighbours differ far less than texels
             * spread (white noise: 1.13 x the texel sd) */
            double t1 = 0, t2 = 0;
            const size_t nt = (size_t)sizes[1] * sizes[1];
            for (size_t i = 0; i < nt; i++) {
                double v = bio[1]->data[i * SS_BIO_NCHANNELS + chans[c]];
                t1 += v, t2 += v * v;
            }
            double tsd = sqrt(fmax(0.0, t2 / nt - (t1 / nt) * (t1 / nt)));
            if (chans[c] != SS_BIO_HEIGHT_MM) assert_true(nb[1] < 0.35 * tsd); /* lines are sharp */
        }
    ss_image_free(bio[0]);
    ss_image_free(bio[1]);
}

/* The surface roughness follows the surface state and the anatomy: more
 * hydration and sebum make it smoother, lips and scars smoother still, the
 * microrelief lines and follicle openings rougher; it varies over the patch. */
static void test_surface_state(void **state) {
    (void)state;
    ss_error err;
    const int N = 128;
    ss_skin_settings s;
    assert_int_equal(ss_skin_settings_preset(&s, "forearm", N, &err), SS_OK);
    s.world_size_cm = 1.28; /* 0.1 mm texels */
    ss_skin_forearm_counts(s.world_size_cm, s.count);
    s.count[SS_FEAT_MOLE] = 0;
    ss_image *hyd = ss_image_create(4, 4, 1, &err), *scar = ss_image_create(4, 4, 1, &err),
             *lips = ss_image_create(4, 4, 1, &err);
    for (int y = 0; y < 4; y++)
        for (int x = 0; x < 4; x++) {
            ss_image_px(hyd, x, y)[0] = x < 2 ? 1.0f : 0.0f;   /* left half wet */
            ss_image_px(scar, x, y)[0] = y == 0 ? 1.0f : 0.0f; /* top quarter a scar */
            ss_image_px(lips, x, y)[0] = y == 3 ? 1.0f : 0.0f; /* bottom quarter lips */
        }
    ss_skin_fields f;
    memset(&f, 0, sizeof f);
    f.hydration = hyd;
    ss_skin_feature_list l;
    assert_int_equal(ss_skin_generate(&s, &f, &l, NULL, 0, &err), SS_OK);
    ss_image *b1 = ss_skin_bio_maps(&s, &f, &l, &err);
    f.scar = scar;
    f.lips = lips;
    ss_image *b2 = ss_skin_bio_maps(&s, &f, &l, &err);
    assert_non_null(b1);
    assert_non_null(b2);
    /* rows 40..87 are away from the fields' blends (sampled bilinearly) */
    double wet = 0, dry = 0, line = 0, plateau = 0, sc = 0, lip = 0, mid = 0, h_sc = 0, h_mid = 0;
    int nl = 0, np = 0;
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++) {
            const float *p = ss_image_px(b1, x, y), *q = ss_image_px(b2, x, y);
            const int band = y >= 40 && y < 88;
            if (band && x >= 8 && x < 56) wet += p[SS_BIO_SURFACE_SIGMA];
            if (band && x >= 72 && x < 120) dry += p[SS_BIO_SURFACE_SIGMA];
            if (band && p[SS_BIO_EXTRA_A] == 0.0f) {
                if (p[SS_BIO_HEIGHT_MM] < -0.02f) line += p[SS_BIO_SURFACE_SIGMA], nl++;
                if (p[SS_BIO_HEIGHT_MM] > -0.001f) plateau += p[SS_BIO_SURFACE_SIGMA], np++;
            }
            if (y >= 4 && y < 20) sc += q[SS_BIO_SURFACE_SIGMA], h_sc += fabs(q[SS_BIO_HEIGHT_MM]);
            if (y >= 108 && y < 124) lip += q[SS_BIO_SURFACE_SIGMA];
            if (band) mid += q[SS_BIO_SURFACE_SIGMA], h_mid += fabs(q[SS_BIO_HEIGHT_MM]);
        }
    wet /= 48.0 * 48, dry /= 48.0 * 48, sc /= 16.0 * N, lip /= 16.0 * N, mid /= 48.0 * N;
    h_sc /= 16.0 * N, h_mid /= 48.0 * N;
    assert_true(nl > 50 && np > 50);
    line /= nl, plateau /= np;
    print_message("sigma: wet %.3f dry %.3f, lines %.3f plateaus %.3f, scar %.3f lips %.3f "
                  "skin %.3f; |height| scar %.4f skin %.4f mm\n",
                  wet, dry, line, plateau, sc, lip, mid, h_sc, h_mid);
    assert_true(wet < 0.9 * dry);
    assert_true(line > plateau + 0.05);
    assert_true(sc < 0.8 * mid && lip < 0.8 * mid);
    assert_true(h_sc < 0.5 * h_mid); /* a scar has lost the microrelief */
    /* Weyrich et al. 2006's range of facial specular roughness: plateaus of
     * the default forearm in 0.3..0.5 (sigma = GGX alpha ~ Beckmann m) */
    assert_true(plateau > 0.3 && plateau < 0.5);
    ss_image_free(b1);
    ss_image_free(b2);
    ss_image_free(hyd);
    ss_image_free(scar);
    ss_image_free(lips);
    ss_skin_feature_list_free(&l);
}

/* With a user's vector field wrinkles follow it; wrinkles.cross_deg turns
 * every other one only when cross_with_field is set (the CLI sets it when
 * --param wrinkles.cross_deg is given). */
static void test_wrinkles_follow_field(void **state) {
    (void)state;
    ss_error err;
    ss_skin_settings s;
    assert_int_equal(ss_skin_settings_preset(&s, "forearm", 64, &err), SS_OK);
    s.world_size_cm = 1.0;
    memset(s.count, 0, sizeof s.count);
    s.count[SS_FEAT_WRINKLE] = 40;
    assert_true(s.dist.wrinkle_cross_deg == 60.0);
    ss_image *vf = ss_image_create(2, 2, 3, &err);
    for (int i = 0; i < 4; i++)
        vf->data[i * 3] = 1.0f, vf->data[i * 3 + 1] = 0.5f, vf->data[i * 3 + 2] = 1.0f;
    ss_skin_fields f;
    memset(&f, 0, sizeof f);
    f.wrinkle_vectors = vf;
    for (int with = 0; with < 2; with++) {
        s.dist.wrinkle_cross_with_field = with;
        ss_skin_feature_list l;
        assert_int_equal(ss_skin_generate(&s, &f, &l, NULL, 0, &err), SS_OK);
        for (size_t k = 0; k < l.n; k++) {
            const ss_bezier3 *b = &l.f[k].curve;
            double a = atan2(b->y[3] - b->y[0], b->x[3] - b->x[0]) * 180.0 / M_PI;
            double want = with && (k & 1) ? 60.0 : 0.0;
            assert_true(fabs(a - want) < 1.0);
        }
        ss_skin_feature_list_free(&l);
    }
    ss_image_free(vf);
}

/* Moles have a sharp border (moles.border), and reticular ones a pigment
 * network; their melanin contrast grows with the skin's own melanin. */
static void test_mole_border(void **state) {
    (void)state;
    assert_float_equal(ss_profile_mole(0.9, 1.0, 0.08), 1.0, 0);
    assert_float_equal(ss_profile_mole(1.0, 1.0, 0.08), 0.5, 1e-12);
    assert_float_equal(ss_profile_mole(1.05, 1.0, 0.08), 0.0, 0);
    for (double th = 0; th < 6.3; th += 0.1) {
        double r = ss_mole_outline(2.0, th);
        assert_true(r > 2.0 * 0.91 && r < 2.0 * 1.09);
    }
    ss_error err;
    ss_skin_settings s = small_settings(128);
    s.world_size_cm = 1.28;
    s.phi = 0.0;
    s.dist.mottle_melanin = s.dist.mottle_blood = 0.0;
    ss_skin_feature fs[2];
    memset(fs, 0, sizeof fs);
    fs[0].type = fs[1].type = SS_FEAT_MOLE;
    fs[0].x = 0.25, fs[1].x = 0.75, fs[0].y = fs[1].y = 0.5;
    fs[0].r = fs[1].r = 2.0, fs[0].m = fs[1].m = 0.1;
    fs[1].p = 1.0; /* reticular */
    ss_skin_feature_list l = {2, fs};
    double sdev[2] = {0}, inside_mel[2] = {0};
    for (int dark = 0; dark < 2; dark++) {
        s.base_lo[SS_BIO_MELANIN] = dark ? 0.25 : 0.02;
        ss_image *bio = ss_skin_bio_maps(&s, NULL, &l, &err);
        assert_non_null(bio);
        for (int k = 0; k < 2; k++) {
            double s1 = 0, s2 = 0;
            int n = 0;
            for (int y = 54; y < 74; y++)
                for (int x = 22; x < 42; x++) {
                    double v = ss_image_px(bio, x + 64 * k, y)[SS_BIO_MELANIN];
                    s1 += v, s2 += v * v, n++;
                }
            if (!dark) sdev[k] = sqrt(fmax(0.0, s2 / n - (s1 / n) * (s1 / n)));
            if (k == 0) {
                /* the melanin the light crosses: melanin x epidermis over the
                 * skin's epidermis (above the table's top a mole thickens the
                 * pigmented layer) */
                double col = 0.0;
                for (int y = 54; y < 74; y++)
                    for (int x = 22; x < 42; x++) {
                        const float *p = ss_image_px(bio, x, y);
                        assert_true(p[SS_BIO_MELANIN] <= s.base_hi[SS_BIO_MELANIN] + 1e-6);
                        assert_true(p[SS_BIO_EPIDERMIS_CM] <=
                                    s.base_hi[SS_BIO_EPIDERMIS_CM] + 1e-7);
                        col += p[SS_BIO_MELANIN] * p[SS_BIO_EPIDERMIS_CM];
                    }
                inside_mel[dark] =
                    col / n / s.base_lo[SS_BIO_EPIDERMIS_CM] - s.base_lo[SS_BIO_MELANIN];
            }
        }
        /* 0.3 mm outside the outline: untouched skin */
        double out = ss_image_px(bio, 32 + 23, 64)[SS_BIO_MELANIN];
        assert_true(fabs(out - s.base_lo[SS_BIO_MELANIN]) < 0.15 * s.base_lo[SS_BIO_MELANIN]);
        ss_image_free(bio);
    }
    assert_true(sdev[1] > 3.0 * sdev[0] + 1e-4); /* the network shows inside */
    assert_true(inside_mel[1] > 1.5 * inside_mel[0]);
}

/* With the shipped table (its surface curve) the roughness and specular maps
 * vary over the patch and follow the surface: the lookup with a surface
 * sigma equals ss_mm_surface_lobe, and no subsurface radius is negative. */
static void test_render_surface_maps(void **state) {
    (void)state;
    ss_error err;
    ss_mm_table *t = load_table();
    assert_true(t->nsurface >= 2);
    for (size_t e = 0; e < t->nentries; e++)
        for (int c = 12; c < 15; c++) assert_true(t->entries[e * SS_MM_NFIELDS + c] > 0.0);
    ss_skin_lut *lut = ss_skin_lut_create(t, &err);
    const float x[6] = {0.05f, 0.3f, 0.01f, 0.8f, 0.0015f, 0.009f};
    double prev = 0.0;
    for (double sg = 0.25; sg <= 0.9; sg += 0.05) {
        float out[8];
        double sp, ro, sc, ref[SS_MM_NFIELDS];
        ss_skin_lut_lookup_surface(lut, x, (float)sg, out);
        ss_mm_surface_lobe(t, sg, &sp, &ro, &sc);
        double xd[6];
        for (int a = 0; a < 6; a++) xd[a] = x[a];
        ss_mm_table_lookup(t, xd, ref);
        assert_float_equal(out[3], sp, 1e-5);
        assert_float_equal(out[4], ro, 1e-5);
        for (int c = 0; c < 3; c++) assert_float_equal(out[c], ref[c] * sc, 2e-5 * (1 + ref[c]));
        for (int c = 0; c < 3; c++) assert_float_equal(out[5 + c], ref[12 + c], 2e-5);
        assert_true(ro > prev); /* a rougher surface, a rougher lobe */
        prev = ro;
    }
    ss_skin_settings s;
    assert_int_equal(ss_skin_settings_preset(&s, "forearm", 128, &err), SS_OK);
    s.world_size_cm = 1.28;
    ss_skin_forearm_counts(s.world_size_cm, s.count);
    ss_skin_feature_list l;
    assert_int_equal(ss_skin_generate(&s, NULL, &l, NULL, 0, &err), SS_OK);
    ss_image *bio = ss_skin_bio_maps(&s, NULL, &l, &err);
    ss_skin_maps m;
    assert_int_equal(ss_skin_render_maps(bio, lut, s.world_size_cm, 0, &m, &err), SS_OK);
    const size_t n = 128 * 128;
    double r1 = 0, r2 = 0, s1 = 0, s2 = 0, rl = 0, rp = 0;
    int nl = 0, np = 0;
    for (size_t i = 0; i < n; i++) {
        double r = m.roughness->data[i], q = m.specular->data[i];
        r1 += r, r2 += r * r, s1 += q, s2 += q * q;
        assert_true(m.cavity->data[i] >= 0.0f && m.cavity->data[i] <= 1.0f);
        for (int c = 0; c < 3; c++) assert_true(m.translucency->data[i * 3 + c] > 0.0f);
        /* on a line: cavity < 0.6 (the relief is area-averaged over the
         * 0.1 mm texel, so a line's texels are shallower than its centre:
         * 259 texels below 0.6, 47 below 0.5) */
        if (m.cavity->data[i] < 0.6f) rl += r, nl++;
        if (m.cavity->data[i] == 1.0f) rp += r, np++;
    }
    const double rsd = sqrt(r2 / n - (r1 / n) * (r1 / n)), ssd = sqrt(s2 / n - (s1 / n) * (s1 / n));
    print_message("roughness %.3f sd %.3f (lines %.3f, plateaus %.3f; %d / %d texels), specular "
                  "%.3f sd %.3f\n",
                  r1 / n, rsd, nl ? rl / nl : 0, np ? rp / np : 0, nl, np, s1 / n, ssd);
    assert_true(rsd > 0.02 && ssd > 0.02);
    assert_true(nl > 100 && np > 100 && rl / nl > rp / np + 0.03);
    ss_skin_maps_free(&m);
    ss_image_free(bio);
    ss_skin_feature_list_free(&l);
    ss_skin_lut_free(lut);
    ss_mm_table_free(t);
}

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Both ends of the tone range from the baseline melanin, through the shipped
 * table, for the forearm and the seed (face) presets: very light (ITA > 55,
 * C* >= 14) and dark (ITA < -30, C* <= 24), the medians of the base colour
 * map's L*, a*, b*. */
static void test_tone_ends(void **state) {
    (void)state;
    ss_error err;
    ss_mm_table *t = load_table();
    ss_skin_lut *lut = ss_skin_lut_create(t, &err);
    const double mel[2] = {0.003, 0.43};
    const char *presets[2] = {"forearm", "seed"};
    for (int run = 0; run < 4; run++) {
        const int k = run % 2;
        ss_skin_settings s;
        assert_int_equal(ss_skin_settings_preset(&s, presets[run / 2], 128, &err), SS_OK);
        s.world_size_cm = 1.28;
        ss_skin_forearm_counts(s.world_size_cm, s.count);
        s.base_lo[SS_BIO_MELANIN] = mel[k];
        ss_skin_feature_list l;
        assert_int_equal(ss_skin_generate(&s, NULL, &l, NULL, 0, &err), SS_OK);
        ss_image *bio = ss_skin_bio_maps(&s, NULL, &l, &err);
        ss_skin_maps m;
        assert_int_equal(ss_skin_render_maps(bio, lut, s.world_size_cm, 0, &m, &err), SS_OK);
        const size_t n = 128 * 128;
        double *L[3];
        for (int c = 0; c < 3; c++) L[c] = malloc(n * sizeof(double));
        for (size_t i = 0; i < n; i++) {
            double rgb[3], lab[3];
            for (int c = 0; c < 3; c++) rgb[c] = m.base_color->data[i * 3 + c];
            ss_srgb_linear_to_lab(rgb, lab);
            for (int c = 0; c < 3; c++) L[c][i] = lab[c];
        }
        double med[3], C, ita;
        for (int c = 0; c < 3; c++) {
            qsort(L[c], n, sizeof(double), cmp_double);
            med[c] = L[c][n / 2];
            free(L[c]);
        }
        ss_lab_describe(med, &C, NULL, &ita);
        print_message("%s melanin %.3f: L* %.1f a* %.1f b* %.1f, C* %.1f, ITA %.1f\n",
                      presets[run / 2], mel[k], med[0], med[1], med[2], C, ita);
        if (k == 0)
            assert_true(ita > 55.0 && C >= 14.0);
        else
            assert_true(ita < -30.0 && C <= 24.0);
        ss_skin_maps_free(&m);
        ss_image_free(bio);
        ss_skin_feature_list_free(&l);
    }
    ss_skin_lut_free(lut);
    ss_mm_table_free(t);
}

/* Mean L* of the base colour over texels (x0..x1, y0..y1), or over those
 * whose centre lies between r0 and r1 texels of (cx, cy) when r1 > 0. */
static double mean_lstar(const ss_image *bc, int x0, int y0, int x1, int y1, double cx, double cy,
                         double r0, double r1) {
    double sum = 0.0;
    int n = 0;
    for (int y = y0; y <= y1; y++)
        for (int x = x0; x <= x1; x++) {
            const double d = hypot(x + 0.5 - cx, y + 0.5 - cy);
            if (r1 > 0.0 && (d < r0 || d >= r1)) continue;
            double rgb[3], lab[3];
            for (int c = 0; c < 3; c++) rgb[c] = ss_image_px(bc, x, y)[c];
            ss_srgb_linear_to_lab(rgb, lab);
            sum += lab[0], n++;
        }
    assert_true(n > 0);
    return sum / n;
}

/* Feature contrast follows the tone, through the shipped table: one mole
 * (r 1 mm, M 0.1, uniform pigment) and one follicle on uniform forearm skin
 * at 0.025 mm texels, at melanin 0.01, 0.05, 0.15 and 0.3. The mole is darker
 * than the skin around it at every tone, by at least 8 L* and a third of the
 * skin's L* (with a stop at the table's top melanin it kept 6 L*, a quarter,
 * at 0.3). The hair stub is darker than the skin at every tone, and on light
 * skin (0.01) a light brown, L* > 40 (a fixed dark hair colour: L* 16). */
static void test_feature_contrast_follows_tone(void **state) {
    (void)state;
    ss_error err;
    ss_mm_table *t = load_table();
    ss_skin_lut *lut = ss_skin_lut_create(t, &err);
    assert_non_null(lut);
    const int N = 256;
    ss_skin_settings s;
    assert_int_equal(ss_skin_settings_preset(&s, "forearm", N, &err), SS_OK);
    s.world_size_cm = 0.64; /* 0.025 mm texels: the stub covers its centre texel */
    s.phi = 0.0;
    s.dist.mottle_melanin = s.dist.mottle_blood = s.dist.mottle_height = 0.0;
    s.dist.relief_depth = s.dist.relief_depth2 = 0.0;
    ss_skin_feature fs[2];
    memset(fs, 0, sizeof fs);
    fs[0].type = SS_FEAT_MOLE, fs[0].x = 0.3, fs[0].y = 0.5, fs[0].r = 1.0, fs[0].m = 0.1;
    fs[1].type = SS_FEAT_FOLLICLE, fs[1].x = (192 + 0.5) / N, fs[1].y = (128 + 0.5) / N;
    fs[1].r = s.dist.follicle_r_inner, fs[1].r2 = s.dist.follicle_r_outer;
    ss_skin_feature_list l = {2, fs};
    const double mel[4] = {0.01, 0.05, 0.15, 0.3};
    const double tex_mm = 6.4 / N, mcx = 0.3 * N, mcy = 0.5 * N;
    for (int k = 0; k < 4; k++) {
        s.base_lo[SS_BIO_MELANIN] = mel[k];
        ss_image *bio = ss_skin_bio_maps(&s, NULL, &l, &err);
        assert_non_null(bio);
        ss_skin_maps m;
        assert_int_equal(ss_skin_render_maps(bio, lut, s.world_size_cm, 0, &m, &err), SS_OK);
        /* the mole: its inner half against a ring 0.5-1 mm outside it */
        const double r = 1.0 / tex_mm;
        const double Lm = mean_lstar(m.base_color, 0, 0, N / 2, N - 1, mcx, mcy, 0.0, 0.5 * r);
        const double Ls = mean_lstar(m.base_color, 0, 0, N / 2, N - 1, mcx, mcy, r + 0.5 / tex_mm,
                                     r + 1.0 / tex_mm);
        /* the follicle: its centre texel, and skin 0.2-0.4 mm away */
        const double Lf = mean_lstar(m.base_color, 192, 128, 192, 128, 0, 0, 0, 0);
        const double Lfs =
            mean_lstar(m.base_color, 160, 96, 224, 160, 192.5, 128.5, 0.2 / tex_mm, 0.4 / tex_mm);
        print_message("melanin %.2f: skin L* %.1f, mole %.1f (dL* %.1f), hair stub %.1f (skin "
                      "%.1f)\n",
                      mel[k], Ls, Lm, Lm - Ls, Lf, Lfs);
        assert_true(Lm - Ls <= -8.0);
        assert_true(Lm - Ls <= -Ls / 3.0);
        assert_true(Lf < Lfs - 5.0);
        if (k == 0) assert_true(Lf > 40.0 && Lf < Lfs - 8.0);
        ss_skin_maps_free(&m);
        ss_image_free(bio);
    }
    ss_skin_lut_free(lut);
    ss_mm_table_free(t);
}

/* The _poll calls: cancelled, SS_ERR_RUNTIME "cancelled" and nothing kept
 * (ASan: nothing leaks); never stopped, the plain calls' maps bit for bit. */
static void test_poll_cancel(void **state) {
    (void)state;
    ss_error err;
    ss_skin_settings s = small_settings(128);
    ss_mm_table *t = load_table();
    ss_skin_lut *lut = ss_skin_lut_create(t, &err);
    assert_non_null(lut);
    ss_skin_feature_list l, l2;
    assert_int_equal(ss_skin_generate(&s, NULL, &l, NULL, 0, &err), SS_OK);
    tu_poll stop = {0, 2, 0}, go = {0, 0, 0};
    /* features: stopped at the second type, nothing kept; never stopped,
     * the same list as the plain call */
    assert_int_equal(ss_skin_generate_poll(&s, NULL, &l2, NULL, 0, tu_poll_count, &stop, &err),
                     SS_ERR_RUNTIME);
    assert_non_null(strstr(err.msg, "cancelled"));
    assert_int_equal(stop.calls, 2);
    assert_null(l2.f);
    assert_int_equal(l2.n, 0);
    assert_int_equal(ss_skin_generate_poll(&s, NULL, &l2, NULL, 0, tu_poll_count, &go, &err),
                     SS_OK);
    assert_true(go.calls >= 2 && go.last == 1.0);
    assert_int_equal(l2.n, l.n);
    assert_memory_equal(l2.f, l.f, l.n * sizeof *l.f);
    ss_skin_feature_list_free(&l2);
    stop = (tu_poll){0, 2, 0};
    go = (tu_poll){0, 0, 0};
    assert_null(ss_skin_bio_maps_poll(&s, NULL, &l, tu_poll_count, &stop, &err));
    assert_int_equal(err.code, SS_ERR_RUNTIME);
    assert_non_null(strstr(err.msg, "cancelled"));
    assert_int_equal(stop.calls, 2);
    ss_image *bio = ss_skin_bio_maps(&s, NULL, &l, &err);
    ss_image *bio2 = ss_skin_bio_maps_poll(&s, NULL, &l, tu_poll_count, &go, &err);
    assert_non_null(bio);
    assert_non_null(bio2);
    assert_true(go.calls >= 2 && go.last == 1.0);
    size_t n = (size_t)s.size * s.size;
    assert_memory_equal(bio->data, bio2->data, n * SS_BIO_NCHANNELS * sizeof(float));
    ss_skin_maps m, m2;
    stop = (tu_poll){0, 2, 0};
    assert_int_equal(
        ss_skin_render_maps_poll(bio, lut, s.world_size_cm, 0, &m2, tu_poll_count, &stop, &err),
        SS_ERR_RUNTIME);
    assert_non_null(strstr(err.msg, "cancelled"));
    assert_null(m2.base_color);
    go = (tu_poll){0, 0, 0};
    assert_int_equal(ss_skin_render_maps(bio, lut, s.world_size_cm, 0, &m, &err), SS_OK);
    assert_int_equal(
        ss_skin_render_maps_poll(bio, lut, s.world_size_cm, 0, &m2, tu_poll_count, &go, &err),
        SS_OK);
    assert_true(go.calls >= 2 && go.last == 1.0);
    assert_memory_equal(m.base_color->data, m2.base_color->data, n * 3 * sizeof(float));
    assert_memory_equal(m.specular->data, m2.specular->data, n * sizeof(float));
    assert_memory_equal(m.normal->data, m2.normal->data, n * 3 * sizeof(float));
    assert_true(m.height_min_mm == m2.height_min_mm && m.height_max_mm == m2.height_max_mm);
    ss_skin_maps_free(&m);
    ss_skin_maps_free(&m2);
    ss_image_free(bio);
    ss_image_free(bio2);
    ss_skin_feature_list_free(&l);
    ss_skin_lut_free(lut);
    ss_mm_table_free(t);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_profiles),
        cmocka_unit_test(test_bezier_golden_vs_dense),
        cmocka_unit_test(test_counts_and_zero_field),
        cmocka_unit_test(test_samplers_agree),
        cmocka_unit_test(test_single_features),
        cmocka_unit_test(test_follicle_area_sampled),
        cmocka_unit_test(test_seamless_wrap),
        cmocka_unit_test(test_determinism_and_roundtrip),
        cmocka_unit_test(test_poll_cancel),
        cmocka_unit_test(test_lut_matches_table),
        cmocka_unit_test(test_lut_cache_exact),
        cmocka_unit_test(test_lut_other_table),
        cmocka_unit_test(test_mm_defined_variation),
        cmocka_unit_test(test_surface_state),
        cmocka_unit_test(test_wrinkles_follow_field),
        cmocka_unit_test(test_mole_border),
        cmocka_unit_test(test_render_surface_maps),
        cmocka_unit_test(test_tone_ends),
        cmocka_unit_test(test_feature_contrast_follows_tone),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
