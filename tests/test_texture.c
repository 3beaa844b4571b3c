/* texture: bias/gain identities and hand-computed values (Eq. 3.6 in
 * Schlick's form, Eq. 3.7), value noise fast == Alg. 3.2 reference bit for
 * bit, range/mean, tileability (wrap of the lattice and seamless edges),
 * resolution independence with cell_px, stretch, determinism across thread
 * counts, bad parameters; erosion widths odd and in range (Eq. 3.1), fast
 * erosion == Alg. 3.1 reference on random masks; gradient edge (Alg. 3.4)
 * values; height-to-normal orientation on ramps. */
#include "testutil.h"
#include "skinsim/texture.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

static void test_bias_gain(void **state) {
    (void)state;
    for (int i = 0; i <= 100; i++) {
        float v = (float)i / 100.0f;
        assert_true(ss_bias(v, 0.5f) == v);
        assert_true(ss_gain(v, 0.5f) == v);
    }
    /* bias(0.25, 0.8) = 0.25 / ((1/0.8 - 2) * 0.75 + 1) = 0.25 / 0.4375 = 4/7 */
    assert_float_equal(ss_bias(0.25f, 0.8f), 4.0 / 7.0, 1e-6);
    /* bias(0.5, b) = b for Schlick's bias */
    assert_float_equal(ss_bias(0.5f, 0.3f), 0.3, 1e-6);
    /* gain(0.25, 0.8) = bias(0.5, 0.8)/2 = 0.4; gain(0.75, 0.8) = bias(0.5, 0.2)/2 + 0.5 = 0.6 */
    assert_float_equal(ss_gain(0.25f, 0.8f), 0.4, 1e-6);
    assert_float_equal(ss_gain(0.75f, 0.8f), 0.6, 1e-6);
    /* Ends are fixed, monotone in v. */
    for (float b = 0.05f; b < 1.0f; b += 0.1f) {
        assert_true(ss_bias(0.0f, b) == 0.0f && ss_bias(1.0f, b) == 1.0f);
        assert_true(ss_gain(0.0f, b) == 0.0f && ss_gain(1.0f, b) == 1.0f);
        float prev = -1;
        for (int i = 0; i <= 50; i++) {
            float g = ss_gain(ss_bias((float)i / 50.0f, b), 1.0f - b);
            assert_true(g >= prev);
            prev = g;
        }
    }
}

static void test_noise_matches_reference(void **state) {
    (void)state;
    ss_error err;
    const int sizes[][2] = {{37, 23}, {64, 48}, {50, 71}, {96, 96}};
    for (int s = 0; s < 4; s++) {
        int W = sizes[s][0], H = sizes[s][1];
        ss_noise_params p;
        ss_noise_params_default(&p);
        p.octaves = 2 + s * 2; /* 2, 4, 6 (periods beyond the size), 8 */
        p.persistence = 0.4f + 0.2f * (float)s;
        p.bias = s % 2 ? 0.3f : 0.5f;
        p.gain = s == 2 ? 0.8f : 0.5f;
        ss_image *a = ss_image_create(W, H, 1, &err), *b = ss_image_create(W, H, 1, &err);
        assert_int_equal(ss_value_noise_reference(&p, 7 + (uint64_t)s, 3, a, &err), SS_OK);
        assert_int_equal(ss_value_noise(&p, 7 + (uint64_t)s, 3, b, &err), SS_OK);
        for (int i = 0; i < W * H; i++)
            if (a->data[i] != b->data[i])
                fail_msg("size %dx%d pixel %d: reference %.9g fast %.9g", W, H, i, a->data[i],
                         b->data[i]);
        ss_image_free(a);
        ss_image_free(b);
    }
}

static void test_noise_properties(void **state) {
    (void)state;
    ss_error err;
    const int N = tu_quick() ? 128 : 256;
    ss_noise_params p;
    ss_noise_params_default(&p);
    ss_image *a = ss_image_create(N, N, 1, &err), *b = ss_image_create(N, N, 1, &err);
    /* Range, and mean with bias = gain = 0.5 over 16 keys at 256^2 (one
     * image's mean has a spread of about 0.027 because the coarse octave has
     * few lattice points; the mean of 16 about 0.007). */
    ss_image *m = ss_image_create(256, 256, 1, &err);
    double mean = 0;
    for (uint64_t s = 0; s < 16; s++) {
        assert_int_equal(ss_value_noise(&p, s, 0, m, &err), SS_OK);
        for (int i = 0; i < 256 * 256; i++) {
            assert_true(m->data[i] >= 0.0f && m->data[i] <= 1.0f);
            mean += m->data[i];
        }
    }
    mean /= 16.0 * 256 * 256;
    assert_true(fabs(mean - 0.5) < 0.025);
    ss_image_free(m);
    assert_int_equal(ss_value_noise(&p, 1, 0, a, &err), SS_OK);
    /* Different seeds/streams differ; same key repeats. */
    assert_int_equal(ss_value_noise(&p, 1, 1, b, &err), SS_OK);
    assert_memory_not_equal(a->data, b->data, sizeof(float) * N * N);
    /* 1 vs 2 threads bit-identical (stretch and cell_px too). */
    p.stretch_y = 4.0f;
    p.cell_px = 3.0f;
    omp_set_num_threads(1);
    assert_int_equal(ss_value_noise(&p, 5, 2, a, &err), SS_OK);
    omp_set_num_threads(2);
    assert_int_equal(ss_value_noise(&p, 5, 2, b, &err), SS_OK);
    assert_memory_equal(a->data, b->data, sizeof(float) * N * N);
    ss_image_free(a);
    ss_image_free(b);

    /* Bad parameters are refused with a message. */
    ss_image *o = ss_image_create(8, 8, 1, &err), *o3 = ss_image_create(8, 8, 3, &err);
    ss_noise_params_default(&p);
    p.persistence = 0;
    assert_int_equal(ss_value_noise(&p, 1, 0, o, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "persistence"));
    ss_noise_params_default(&p);
    p.bias = 1.5f;
    assert_int_equal(ss_value_noise_reference(&p, 1, 0, o, &err), SS_ERR_INPUT);
    ss_noise_params_default(&p);
    p.stretch_y = 0;
    assert_int_equal(ss_value_noise(&p, 1, 0, o, &err), SS_ERR_INPUT);
    ss_noise_params_default(&p);
    p.cell_px = NAN;
    assert_int_equal(ss_value_noise(&p, 1, 0, o, &err), SS_ERR_INPUT);
    ss_noise_params_default(&p);
    p.octaves = -1;
    assert_int_equal(ss_value_noise(&p, 1, 0, o, &err), SS_ERR_INPUT);
    ss_noise_params_default(&p);
    assert_int_equal(ss_value_noise(&p, 1, 0, o3, &err), SS_ERR_INPUT);
    ss_image_free(o);
    ss_image_free(o3);
}

static float maxdiff_cols(const ss_image *img, int c0, int c1) {
    float m = 0;
    for (int y = 0; y < img->height; y++)
        m = fmaxf(m, fabsf(*ss_image_px(img, c0, y) - *ss_image_px(img, c1, y)));
    return m;
}

static float maxdiff_rows(const ss_image *img, int r0, int r1) {
    float m = 0;
    for (int x = 0; x < img->width; x++)
        m = fmaxf(m, fabsf(*ss_image_px(img, x, r0) - *ss_image_px(img, x, r1)));
    return m;
}

static void test_noise_tiling(void **state) {
    (void)state;
    ss_error err;
    ss_noise_params p;
    ss_noise_params_default(&p);
    /* The lattice wraps: with stretch 0.5 a 64 px image shows the 64-point
     * lattice twice, so column x and x + 32 (row y, y + 32) coincide. */
    p.stretch_x = p.stretch_y = 0.5f;
    ss_image *a = ss_image_create(64, 64, 1, &err);
    assert_int_equal(ss_value_noise(&p, 11, 0, a, &err), SS_OK);
    for (int y = 0; y < 32; y++)
        for (int x = 0; x < 32; x++) {
            float v = *ss_image_px(a, x, y);
            assert_true(v == *ss_image_px(a, x + 32, y));
            assert_true(v == *ss_image_px(a, x, y + 32));
        }
    ss_image_free(a);
    /* Seamless: when the size is a multiple of cell_px * 2^octaves the jump
     * across the wrap (last column -> first column) is no larger than the
     * largest jump between neighbouring columns inside the image. Fine
     * octaves are weighted down so neighbour jumps are small. */
    ss_noise_params_default(&p);
    p.persistence = 0.3f;
    p.octaves = 4;
    for (int cell = 1; cell <= 4; cell *= 4) {
        int N = 96 * cell;
        p.cell_px = (float)cell;
        ss_image *t = ss_image_create(N, N, 1, &err);
        assert_int_equal(ss_value_noise(&p, 4, 1, t, &err), SS_OK);
        float inner_c = 0, inner_r = 0;
        for (int i = 0; i + 1 < N; i++) {
            inner_c = fmaxf(inner_c, maxdiff_cols(t, i, i + 1));
            inner_r = fmaxf(inner_r, maxdiff_rows(t, i, i + 1));
        }
        assert_true(maxdiff_cols(t, N - 1, 0) <= inner_c);
        assert_true(maxdiff_rows(t, N - 1, 0) <= inner_r);
        ss_image_free(t);
    }
    /* Resolution independence: a 2x larger image with 2x cell_px samples the
     * same lattice, so every other pixel repeats the small image exactly. */
    ss_noise_params_default(&p);
    p.cell_px = 2.0f;
    ss_image *s = ss_image_create(40, 30, 1, &err);
    assert_int_equal(ss_value_noise(&p, 8, 8, s, &err), SS_OK);
    p.cell_px = 4.0f;
    ss_image *l = ss_image_create(80, 60, 1, &err);
    assert_int_equal(ss_value_noise(&p, 8, 8, l, &err), SS_OK);
    for (int y = 0; y < 30; y++)
        for (int x = 0; x < 40; x++)
            assert_true(*ss_image_px(s, x, y) == *ss_image_px(l, 2 * x, 2 * y));
    ss_image_free(s);
    ss_image_free(l);
    /* Stretch: stretch_y = 64 makes vertical neighbours far more alike. */
    ss_noise_params_default(&p);
    p.stretch_y = 64.0f;
    ss_image *st = ss_image_create(128, 128, 1, &err);
    assert_int_equal(ss_value_noise(&p, 2, 2, st, &err), SS_OK);
    double dx = 0, dy = 0;
    for (int y = 0; y + 1 < 128; y++)
        for (int x = 0; x + 1 < 128; x++) {
            dx += fabsf(*ss_image_px(st, x + 1, y) - *ss_image_px(st, x, y));
            dy += fabsf(*ss_image_px(st, x, y + 1) - *ss_image_px(st, x, y));
        }
    assert_true(dy * 10 < dx);
    ss_image_free(st);
}

/* A rectangle of the noise equals the same pixels of the whole texture, for
 * stretched and scaled lattices and rectangles touching the borders. */
static void test_noise_rect_equals_crop(void **state) {
    (void)state;
    ss_error err;
    const int W = 150, H = 97;
    ss_image *full = ss_image_create(W, H, 1, &err);
    const int rects[][4] = {{0, 0, W, H}, {10, 20, 33, 41}, {117, 60, 33, 37}, {0, 96, 1, 1}};
    for (int pset = 0; pset < 3; pset++) {
        ss_noise_params p;
        ss_noise_params_default(&p);
        p.octaves = 4 + pset;
        p.bias = 0.3f;
        p.gain = 0.6f;
        if (pset == 1) p.stretch_y = 64.0f;
        if (pset == 2) p.cell_px = 0.7f;
        assert_int_equal(ss_value_noise(&p, 5, 9, full, &err), SS_OK);
        for (int r = 0; r < 4; r++) {
            ss_image *sub = ss_image_create(rects[r][2], rects[r][3], 1, &err);
            assert_int_equal(
                ss_value_noise_rect(&p, 5, 9, W, H, rects[r][0], rects[r][1], sub, &err), SS_OK);
            for (int y = 0; y < sub->height; y++)
                for (int x = 0; x < sub->width; x++)
                    assert_true(ss_image_px(sub, x, y)[0] ==
                                ss_image_px(full, rects[r][0] + x, rects[r][1] + y)[0]);
            ss_image_free(sub);
        }
    }
    ss_image *sub = ss_image_create(10, 10, 1, &err);
    ss_noise_params p;
    ss_noise_params_default(&p);
    assert_int_equal(ss_value_noise_rect(&p, 5, 9, W, H, 145, 0, sub, &err), SS_ERR_INPUT);
    ss_image_free(sub);
    ss_image_free(full);
}

/* Widths of a rectangle are the same numbers as the whole texture's there. */
static void test_erosion_widths_rect(void **state) {
    (void)state;
    const int W = 70, H = 40, x0 = 13, y0 = 7, w = 30, h = 21;
    int *full = malloc(sizeof(int) * W * H), *sub = malloc(sizeof(int) * w * h);
    ss_erosion_widths(W, H, 3, 10, 4, 8, full);
    ss_erosion_widths_rect(W, H, x0, y0, w, h, 3, 10, 4, 8, sub);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) assert_int_equal(sub[y * w + x], full[(y0 + y) * W + x0 + x]);
    free(full);
    free(sub);
}

static void test_erosion(void **state) {
    (void)state;
    ss_error err;
    /* Eq. 3.1: widths odd, in [min_w + 1, max_w + 2], every value hit. */
    const int W = 97, H = 61;
    int *w = malloc(sizeof *w * W * H);
    ss_erosion_widths(W, H, 1, 6, 42, 0, w);
    int hit[16] = {0};
    for (int i = 0; i < W * H; i++) {
        assert_true(w[i] % 2 == 1 && w[i] >= 3 && w[i] <= 7);
        hit[w[i]]++;
    }
    assert_true(hit[3] > 0 && hit[5] > 0 && hit[7] > 0);
    int *w2 = malloc(sizeof *w2 * W * H);
    ss_erosion_widths(W, H, 1, 6, 42, 0, w2);
    assert_memory_equal(w, w2, sizeof *w * W * H);
    /* Fast == reference on random masks and random greys, wide kernels too. */
    for (uint64_t seed = 1; seed <= 6; seed++) {
        int maxw = seed < 4 ? 8 : 150;
        ss_erosion_widths(W, H, 0, maxw, seed, 1, w);
        ss_image *src = ss_image_create(W, H, 1, &err), *a = ss_image_create(W, H, 1, &err),
                 *b = ss_image_create(W, H, 1, &err);
        for (int i = 0; i < W * H; i++) {
            double u = ss_rng_uniform(seed, 2, (uint64_t)i);
            src->data[i] = seed % 2 ? (u < 0.9 ? 1.0f : 0.0f) : (float)u;
        }
        ss_erode_reference(src, w, a);
        ss_erode(src, w, b);
        assert_memory_equal(a->data, b->data, sizeof(float) * W * H);
        ss_erode(src, w, src); /* in place */
        assert_memory_equal(a->data, src->data, sizeof(float) * W * H);
        ss_image_free(src);
        ss_image_free(a);
        ss_image_free(b);
    }
    /* Alg. 3.1 by hand: one black pixel in a white row, width 5 everywhere
     * erodes x-2..x+2; at the border the window is clipped. */
    ss_image *r = ss_image_create(9, 1, 1, &err), *o = ss_image_create(9, 1, 1, &err);
    for (int x = 0; x < 9; x++) r->data[x] = x == 0 || x == 6 ? 0.0f : 1.0f;
    int five[9] = {5, 5, 5, 5, 5, 5, 5, 5, 5};
    ss_erode(r, five, o);
    const float want[9] = {0, 0, 0, 1, 0, 0, 0, 0, 0};
    assert_memory_equal(o->data, want, sizeof want);
    ss_image_free(r);
    ss_image_free(o);
    free(w);
    free(w2);
}

static void test_gradient_edge(void **state) {
    (void)state;
    ss_error err;
    /* A square shape; distance from its outline. */
    const int N = 40;
    ss_image *shape = ss_image_create(N, N, 1, &err), *dist = ss_image_create(N, N, 1, &err),
             *lin = ss_image_create(N, N, 1, &err), *lout = ss_image_create(N, N, 1, &err);
    ss_vec2 q[] = {{10, 10}, {30, 10}, {30, 30}, {10, 30}};
    ss_polygon sq = {4, q};
    ss_polygon_fill(&sq, shape);
    assert_int_equal(ss_outline_distance(&sq, 1, 10.0, dist, &err), SS_OK);
    ss_gradient_edge(shape, dist, 4.0f, 1, lin);
    ss_gradient_edge(shape, dist, 4.0f, 0, lout);
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++) {
            const int in = x >= 10 && x < 30 && y >= 10 && y < 30;
            const float d = *ss_image_px(dist, x, y);
            const float vi = *ss_image_px(lin, x, y), vo = *ss_image_px(lout, x, y);
            if (in && d <= 4.0f)
                assert_float_equal(vi, d / 4.0f, 1e-7);
            else
                assert_true(vi == -1.0f);
            if (!in && d <= 4.0f)
                assert_float_equal(vo, d / 4.0f, 1e-7);
            else
                assert_true(vo == -1.0f);
        }
    /* pixel (10,20): centre 0.5 inside the left edge -> 0.125 */
    assert_float_equal(*ss_image_px(lin, 10, 20), 0.125, 1e-7);
    assert_float_equal(*ss_image_px(lout, 8, 20), 1.5 / 4.0, 1e-7);
    ss_image_free(shape);
    ss_image_free(dist);
    ss_image_free(lin);
    ss_image_free(lout);
}

static void test_height_to_normal(void **state) {
    (void)state;
    ss_error err;
    const int W = 16, H = 12;
    ss_image *h = ss_image_create(W, H, 1, &err), *n = ss_image_create(W, H, 3, &err);
    /* Height rising to the right: normal tilts to -X. */
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) *ss_image_px(h, x, y) = 0.1f * (float)x;
    ss_height_to_normal(h, 1.0f, n);
    float *c = ss_image_px(n, 5, 5);
    assert_true(c[0] < 0.5f);
    assert_float_equal(c[1], 0.5, 1e-6);
    /* slope 0.1: n = (-0.1, 0, 1)/|.| */
    assert_float_equal(c[0], -0.1 / sqrt(1.01) * 0.5 + 0.5, 1e-6);
    assert_float_equal(c[2], 1.0 / sqrt(1.01) * 0.5 + 0.5, 1e-6);
    /* Height rising upwards in the picture (towards row 0): green < 0.5. */
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) *ss_image_px(h, x, y) = 0.2f * (float)(H - y);
    ss_height_to_normal(h, 2.0f, n);
    c = ss_image_px(n, 7, 6);
    assert_true(c[1] < 0.5f);
    assert_float_equal(c[0], 0.5, 1e-6);
    assert_float_equal(c[1], -0.4 / sqrt(1.16) * 0.5 + 0.5, 1e-6);
    /* Flat: straight up. Unit length everywhere. */
    for (int i = 0; i < W * H; i++) h->data[i] = 0.3f;
    ss_height_to_normal(h, 5.0f, n);
    for (int i = 0; i < W * H; i++) {
        assert_float_equal(n->data[3 * i], 0.5, 1e-7);
        assert_float_equal(n->data[3 * i + 1], 0.5, 1e-7);
        assert_float_equal(n->data[3 * i + 2], 1.0, 1e-7);
    }
    ss_image_free(h);
    ss_image_free(n);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bias_gain),
        cmocka_unit_test(test_noise_matches_reference),
        cmocka_unit_test(test_noise_properties),
        cmocka_unit_test(test_noise_tiling),
        cmocka_unit_test(test_erosion),
        cmocka_unit_test(test_gradient_edge),
        cmocka_unit_test(test_height_to_normal),
        cmocka_unit_test(test_noise_rect_equals_crop),
        cmocka_unit_test(test_erosion_widths_rect),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
