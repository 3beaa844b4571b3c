/* Core: RNG determinism and statistics, PNG round trips (8/16 bit, sRGB and
 * linear), bad-file errors, atomic writes, sRGB transfer, number parsing,
 * progress lines for a parent process. */
#define _POSIX_C_SOURCE 200809L /* setenv, pipe */
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static void test_rng_deterministic_and_uniform(void **state) {
    (void)state;
    /* Same key and counter give the same value; different streams differ. */
    assert_int_equal(ss_rng_u32(42, 1, 7), ss_rng_u32(42, 1, 7));
    assert_int_not_equal(ss_rng_u32(42, 1, 7), ss_rng_u32(42, 2, 7));
    assert_int_not_equal(ss_rng_u32(42, 1, 7), ss_rng_u32(43, 1, 7));
    /* Mean and variance of U(0,1) over 1e5 draws: 0.5 and 1/12. */
    double s = 0, s2 = 0;
    int n = 100000;
    for (int i = 0; i < n; i++) {
        double u = ss_rng_uniform(1, 0, (uint64_t)i);
        assert_true(u >= 0.0 && u < 1.0);
        s += u;
        s2 += u * u;
    }
    double mean = s / n, var = s2 / n - mean * mean;
    assert_true(fabs(mean - 0.5) < 4 * sqrt(1.0 / 12 / n));
    assert_true(fabs(var - 1.0 / 12) < 0.002);
    /* The sequential view is a pure function of position. */
    ss_rng_seq a, b;
    ss_rng_seq_init(&a, 9, 3);
    ss_rng_seq_init(&b, 9, 3);
    for (int i = 0; i < 10; i++) assert_int_equal(ss_rng_seq_u32(&a), ss_rng_seq_u32(&b));
}

static void test_rng_known_answer(void **state) {
    (void)state;
    /* Philox4x32-10 known-answer test (Random123 kat_vectors): zero key and
     * counter give 6627e8d5 e169c58d bc57ac4c 9b00dbd8. */
    uint32_t o[4];
    ss_rng4(0, 0, 0, o);
    assert_int_equal(o[0], 0x6627e8d5u);
    assert_int_equal(o[1], 0xe169c58du);
    assert_int_equal(o[2], 0xbc57ac4cu);
    assert_int_equal(o[3], 0x9b00dbd8u);
}

static void test_srgb(void **state) {
    (void)state;
    for (int i = 0; i <= 100; i++) {
        float v = (float)i / 100.0f;
        assert_float_equal(ss_srgb_decode(ss_srgb_encode(v)), v, 1e-5);
    }
    assert_float_equal(ss_srgb_encode(0.5f), 0.735357f, 1e-5);
}

static void roundtrip(int bits, ss_encoding enc, int channels) {
    ss_error err;
    char *dir = tu_tmpdir("png");
    char path[512];
    snprintf(path, sizeof path, "%s/t.png", dir);
    ss_image *img = ss_image_create(37, 23, channels, &err);
    assert_non_null(img);
    for (int i = 0; i < 37 * 23 * channels; i++) img->data[i] = (float)((i * 7919) % 1000) / 999.0f;
    assert_int_equal(ss_png_write(path, img, bits, enc, &err), SS_OK);
    ss_image *back = ss_png_read(path, enc, &err);
    assert_non_null(back);
    assert_int_equal(back->width, 37);
    assert_int_equal(back->height, 23);
    assert_int_equal(back->channels, channels);
    /* Quantisation error: half a step in the encoded domain, times the
     * largest slope of the sRGB decode curve (about 2.4 near 1). */
    double step = bits == 8 ? 0.5 / 255 : 0.5 / 65535;
    double tol = (enc == SS_ENC_SRGB ? 2.5 : 1.0) * step + 1e-6;
    for (int i = 0; i < 37 * 23 * channels; i++)
        assert_true(fabs(back->data[i] - img->data[i]) <= tol);
    /* No temporary file left behind. */
    assert_int_equal(tu_count_entries(dir), 1);
    ss_image_free(img);
    ss_image_free(back);
    tu_rmtree(dir);
    free(dir);
}

static void test_png_roundtrips(void **state) {
    (void)state;
    for (int c = 1; c <= 4; c++) {
        roundtrip(8, SS_ENC_LINEAR, c);
        roundtrip(16, SS_ENC_LINEAR, c);
        roundtrip(8, SS_ENC_SRGB, c);
        roundtrip(16, SS_ENC_SRGB, c);
    }
}

static void test_png_bad_files(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("pngbad");
    char path[512];
    assert_null(ss_png_read("/nonexistent/x.png", SS_ENC_LINEAR, &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "/nonexistent/x.png"));
    snprintf(path, sizeof path, "%s/text.png", dir);
    assert_int_equal(ss_write_file_atomic(path, "hello", 5, &err), SS_OK);
    assert_null(ss_png_read(path, SS_ENC_LINEAR, &err));
    assert_non_null(strstr(err.msg, "not a PNG"));
    /* A truncated PNG: a good file cut in half. */
    ss_image *img = ss_image_create(64, 64, 3, &err);
    snprintf(path, sizeof path, "%s/good.png", dir);
    assert_int_equal(ss_png_write(path, img, 8, SS_ENC_SRGB, &err), SS_OK);
    size_t len;
    char *bytes = ss_read_file(path, &len, &err);
    snprintf(path, sizeof path, "%s/cut.png", dir);
    assert_int_equal(ss_write_file_atomic(path, bytes, len / 2, &err), SS_OK);
    assert_null(ss_png_read(path, SS_ENC_LINEAR, &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    free(bytes);
    ss_image_free(img);
    /* Unwritable destination: error names the path, nothing written. */
    img = ss_image_create(4, 4, 1, &err);
    assert_int_not_equal(ss_png_write("/nonexistent-dir/x.png", img, 8, SS_ENC_LINEAR, &err),
                         SS_OK);
    assert_non_null(strstr(err.msg, "/nonexistent-dir/x.png"));
    ss_image_free(img);
    tu_rmtree(dir);
    free(dir);
}

static void test_image_create_limits(void **state) {
    (void)state;
    ss_error err;
    assert_null(ss_image_create(0, 10, 3, &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    assert_null(ss_image_create(10, -1, 3, &err));
    assert_null(ss_image_create(10, 10, SS_IMAGE_MAX_CHANNELS + 1, &err));
    ss_image *many = ss_image_create(10, 10, 11, &err); /* parameter maps (skin's bio map) */
    assert_non_null(many);
    ss_image_free(many);
}

static void test_mkdir_and_writable(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("mk");
    char p[512];
    snprintf(p, sizeof p, "%s/a/b/c", dir);
    assert_int_equal(ss_check_writable_dir(p, &err), SS_OK);
    assert_int_equal(ss_mkdir_p(p, &err), SS_OK);
    assert_int_equal(ss_mkdir_p(p, &err), SS_OK);
    snprintf(p, sizeof p, "%s/file", dir);
    assert_int_equal(ss_write_file_atomic(p, "x", 1, &err), SS_OK);
    snprintf(p, sizeof p, "%s/file/sub", dir);
    assert_int_equal(ss_mkdir_p(p, &err), SS_ERR_INPUT);
    assert_int_equal(ss_check_writable_dir(p, &err), SS_ERR_INPUT);
    tu_rmtree(dir);
    free(dir);
}

static void test_cli_basics(void **state) {
    (void)state;
    assert_int_equal(tu_run_cli("--help", NULL, NULL), 0);
    assert_int_equal(tu_run_cli("--version", NULL, NULL), 0);
    assert_int_equal(tu_run_cli("", NULL, NULL), 2);
    assert_int_equal(tu_run_cli("no-such-command", NULL, NULL), 2);
}

/* SKINSIM_PROGRESS_FD: the progress reaches a parent as lines on its pipe,
 * quiet or not, begin (0) to end (1); unset, nothing is written. */
static void test_progress_lines(void **state) {
    (void)state;
    int fd[2];
    assert_int_equal(pipe(fd), 0);
    char num[16];
    snprintf(num, sizeof num, "%d", fd[1]);
    setenv("SKINSIM_PROGRESS_FD", num, 1);
    ss_progress p;
    ss_progress_begin(&p, "job", 4, 1);
    ss_progress_update(&p, 2); /* the first update is drawn */
    ss_progress_end(&p);
    unsetenv("SKINSIM_PROGRESS_FD");
    ss_progress_begin(&p, "off", 1, 1);
    ss_progress_end(&p);
    close(fd[1]);
    char buf[256] = "";
    ssize_t n = read(fd[0], buf, sizeof buf - 1);
    close(fd[0]);
    assert_true(n > 0);
    buf[n] = '\0';
    assert_string_equal(buf, "skinsim-progress job 0.0000\nskinsim-progress job "
                             "0.5000\nskinsim-progress job 1.0000\n");
    setenv("SKINSIM_PROGRESS_FD", "2", 1); /* never stderr or below */
    ss_progress_begin(&p, "x", 1, 1);
    assert_int_equal(p.enabled, 0);
    setenv("SKINSIM_PROGRESS_FD", "7x", 1);
    ss_progress_begin(&p, "x", 1, 1);
    assert_int_equal(p.enabled, 0);
    unsetenv("SKINSIM_PROGRESS_FD");
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rng_deterministic_and_uniform),
        cmocka_unit_test(test_rng_known_answer),
        cmocka_unit_test(test_srgb),
        cmocka_unit_test(test_png_roundtrips),
        cmocka_unit_test(test_png_bad_files),
        cmocka_unit_test(test_image_create_limits),
        cmocka_unit_test(test_mkdir_and_writable),
        cmocka_unit_test(test_cli_basics),
        cmocka_unit_test(test_progress_lines),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
