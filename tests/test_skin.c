/* skin (seed 003 §4.8, §5): profiles against the seed's formulas, golden-
 * section distance against dense brute force, exact feature counts, no
 * centre where the field is zero, the two samplers drawing the same
 * distribution (chi-square), feature effects and blend order on single
 * features, seamless wrap, determinism across thread counts, the
 * features.csv round trip, the render lookup against ss_mm_table_lookup,
 * and bad inputs. */
#include "testutil.h"
#include "skinsim/skin.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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
            double mel = lo + sm * 0.2 * (1.0 + 3.0 * lo); /* contrast follows the tone */
            double h = sc * 0.3 + 0.6 * sm * 0.2;
            if (df > 0.15) h -= 0.012 * al; /* the follicle opening's pit */
            if (df <= 0.15 && h < s.dist.follicle_height) h = s.dist.follicle_height;
            double blood = s.dist.lip_blood * (1.0 - s.dist.follicle_blood_drop * al);
            assert_float_equal(p[SS_BIO_MELANIN], mel, 2e-6);
            assert_float_equal(p[SS_BIO_HEIGHT_MM], h, 2e-6);
            assert_float_equal(p[SS_BIO_BLOOD], blood, 2e-6);
            assert_float_equal(p[SS_BIO_PHEOMELANIN], s.dist.lip_pheomelanin, 2e-6);
            assert_float_equal(p[SS_BIO_EXTRA_A], al, 2e-6);
            if (al > 0) assert_float_equal(p[SS_BIO_EXTRA_R], s.dist.hair_rgb[0], 2e-6);
        }
    ss_image_free(bio);
    ss_image_free(lips);
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
    if (px[SS_BIO_EXTRA_A] == 0.0f)
        for (int c = 0; c < 3; c++)
            assert_float_equal(ss_image_px(maps[0].base_color, 5, 7)[c],
                               fmin(1.0, fmax(0.0, me.fit[SS_RENDER_GGX].base_rgb[c])), 2e-5);
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

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_profiles),
        cmocka_unit_test(test_bezier_golden_vs_dense),
        cmocka_unit_test(test_counts_and_zero_field),
        cmocka_unit_test(test_samplers_agree),
        cmocka_unit_test(test_single_features),
        cmocka_unit_test(test_seamless_wrap),
        cmocka_unit_test(test_determinism_and_roundtrip),
        cmocka_unit_test(test_lut_matches_table),
        cmocka_unit_test(test_lut_other_table),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
