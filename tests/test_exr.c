/* EXR I/O: float (exact) and half round trips for 1-4 channels, channel names
 * and types on disk, files written independently here with OpenEXRCore
 * (offset data window, UINT/HALF/FLOAT, extra channels, tiled), and bad
 * input: missing, not EXR, truncated, corrupt, unwritable destination, and a
 * write that fails half-way (file size limit) leaving the old file intact. */
#define _POSIX_C_SOURCE 200809L
#include "testutil.h"

#include <signal.h>
#include <sys/resource.h>

#include <OpenEXR/openexr.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void quiet(exr_const_context_t c, exr_result_t code, const char *msg) {
    (void)c;
    (void)code;
    (void)msg;
}

/* A value pattern with zeros, small, unit, HDR and negative values. */
static float pattern(int i) {
    static const float v[] = {0.0f, 1.0f, 1e-3f, 100.0f, 0.25f, -2.5f, 30000.0f, 0.123456f, 7.0f};
    return v[i % 9] * (1.0f + (float)(i % 13) / 64.0f);
}

static void roundtrip(int channels, int use_half) {
    ss_error err;
    char *dir = tu_tmpdir("exr");
    char path[512];
    snprintf(path, sizeof path, "%s/t.exr", dir);
    int w = 37, h = 23; /* non-square, not a multiple of the 16-line ZIP chunk */
    ss_image *img = ss_image_create(w, h, channels, &err);
    assert_non_null(img);
    for (int i = 0; i < w * h * channels; i++) img->data[i] = pattern(i);
    if (!use_half) { /* float keeps what half cannot */
        img->data[0] = 1e-30f;
        img->data[1 % (w * h * channels)] = 3e30f;
    }
    assert_int_equal(ss_exr_write(path, img, use_half, &err), SS_OK);
    assert_int_equal(tu_count_entries(dir), 1); /* no temporary file left */
    ss_image *back = ss_exr_read(path, &err);
    assert_non_null(back);
    assert_int_equal(back->width, w);
    assert_int_equal(back->height, h);
    assert_int_equal(back->channels, channels);
    for (int i = 0; i < w * h * channels; i++) {
        float a = img->data[i], b = back->data[i];
        if (use_half) {
            assert_true(fabsf(b - a) <= 1e-3f * fabsf(a));
        } else {
            assert_true(memcmp(&a, &b, sizeof a) == 0);
        }
    }
    /* On disk: ZIP scanline, the requested pixel type, channels named as documented. */
    static const char *want[5] = {"", "Y", "AY", "BGR", "ABGR"}; /* sorted as EXR stores */
    exr_context_t ctx;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet;
    assert_int_equal(exr_start_read(&ctx, path, &init), EXR_ERR_SUCCESS);
    exr_compression_t comp;
    exr_storage_t stor;
    const exr_attr_chlist_t *cl;
    assert_int_equal(exr_get_compression(ctx, 0, &comp), EXR_ERR_SUCCESS);
    assert_int_equal(comp, EXR_COMPRESSION_ZIP);
    assert_int_equal(exr_get_storage(ctx, 0, &stor), EXR_ERR_SUCCESS);
    assert_int_equal(stor, EXR_STORAGE_SCANLINE);
    assert_int_equal(exr_get_channels(ctx, 0, &cl), EXR_ERR_SUCCESS);
    assert_int_equal(cl->num_channels, channels);
    for (int c = 0; c < channels; c++) {
        assert_int_equal(cl->entries[c].name.length, 1);
        assert_int_equal(cl->entries[c].name.str[0], want[channels][c]);
        assert_int_equal(cl->entries[c].pixel_type, use_half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT);
    }
    exr_finish(&ctx);
    ss_image_free(img);
    ss_image_free(back);
    tu_rmtree(dir);
    free(dir);
}

static void test_roundtrips(void **state) {
    (void)state;
    for (int c = 1; c <= 4; c++) {
        roundtrip(c, 0);
        roundtrip(c, 1);
    }
}

/* Test-side writer, independent of ss_exr_write: planar buffers, any pixel
 * type and compression, data window at (x0,y0), scanline or 16x16 tiles.
 * Channel k holds tval(k, x, y) (integers, exact in HALF, FLOAT and UINT). */
static int tval(int k, int x, int y) { return (k + 1) * 100 + x + 2 * y; }

static void write_independent(const char *path, int tiled, int x0, int y0, int w, int h,
                              const char *const *names, int nch, exr_pixel_type_t type,
                              exr_compression_t comp) {
    exr_context_t ctx;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet;
    assert_int_equal(exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init), 0);
    int part;
    assert_int_equal(
        exr_add_part(ctx, "p", tiled ? EXR_STORAGE_TILED : EXR_STORAGE_SCANLINE, &part), 0);
    exr_attr_box2i_t dw = {{{{x0, y0}}}, {{{x0 + w - 1, y0 + h - 1}}}};
    exr_attr_v2f_t swc = {{{0.0f, 0.0f}}};
    assert_int_equal(exr_initialize_required_attr(ctx, part, &dw, &dw, 1.0f, &swc, 1.0f,
                                                  EXR_LINEORDER_INCREASING_Y, comp),
                     0);
    for (int k = 0; k < nch; k++)
        assert_int_equal(exr_add_channel(ctx, part, names[k], type, EXR_PERCEPTUALLY_LINEAR, 1, 1),
                         0);
    if (tiled)
        assert_int_equal(
            exr_set_tile_descriptor(ctx, part, 16, 16, EXR_TILE_ONE_LEVEL, EXR_TILE_ROUND_DOWN), 0);
    assert_int_equal(exr_write_header(ctx), 0);

    uint32_t *buf = malloc(sizeof *buf * (size_t)(w * h * nch));
    assert_non_null(buf);
    for (int k = 0; k < nch; k++)
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                uint32_t *p = buf + ((size_t)k * h + y) * w + x;
                float f = (float)tval(k, x, y);
                if (type == EXR_PIXEL_UINT)
                    *p = (uint32_t)tval(k, x, y);
                else
                    memcpy(p, &f, 4);
            }
    int spc = 16, ntx = tiled ? (w + 15) / 16 : 1, nty = tiled ? (h + 15) / 16 : 0;
    if (!tiled) assert_int_equal(exr_get_scanlines_per_chunk(ctx, part, &spc), 0);
    int nchunks = tiled ? ntx * nty : (h + spc - 1) / spc;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    for (int i = 0; i < nchunks; i++) {
        exr_chunk_info_t ci;
        int px, py; /* pixel offset of the chunk in the buffer */
        if (tiled) {
            assert_int_equal(exr_write_tile_chunk_info(ctx, part, i % ntx, i / ntx, 0, 0, &ci), 0);
            px = (i % ntx) * 16, py = (i / ntx) * 16;
        } else {
            assert_int_equal(exr_write_scanline_chunk_info(ctx, part, y0 + i * spc, &ci), 0);
            px = 0, py = i * spc;
        }
        assert_int_equal(i ? exr_encoding_update(ctx, part, &ci, &enc)
                           : exr_encoding_initialize(ctx, part, &ci, &enc),
                         0);
        for (int c = 0; c < enc.channel_count; c++) {
            int k = 0;
            while (strcmp(enc.channels[c].channel_name, names[k])) k++;
            enc.channels[c].encode_from_ptr =
                (const uint8_t *)(buf + ((size_t)k * h + py) * w + px);
            enc.channels[c].user_pixel_stride = 4;
            enc.channels[c].user_line_stride = 4 * w;
            enc.channels[c].user_bytes_per_element = 4;
            enc.channels[c].user_data_type =
                type == EXR_PIXEL_UINT ? EXR_PIXEL_UINT : EXR_PIXEL_FLOAT;
        }
        if (!i) assert_int_equal(exr_encoding_choose_default_routines(ctx, part, &enc), 0);
        assert_int_equal(exr_encoding_run(ctx, part, &enc), 0);
    }
    exr_encoding_destroy(ctx, &enc);
    assert_int_equal(exr_finish(&ctx), 0);
    free(buf);
}

/* Checks that out channel c of img holds file channel k's pattern. */
static void check_channel(const ss_image *img, int c, int k) {
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++)
            assert_float_equal(ss_image_px(img, x, y)[c], (float)tval(k, x, y), 0.0);
}

static void test_read_independent_files(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("exrind");
    char path[512];
    snprintf(path, sizeof path, "%s/f.exr", dir);
    /* Declared out of alphabetical order, with extra channels that must be
     * ignored; data window offset (also negative). Every pixel type. */
    static const char *const rgbaz[] = {"Z", "G", "diffuse.R", "B", "A", "R"};
    exr_pixel_type_t types[] = {EXR_PIXEL_HALF, EXR_PIXEL_FLOAT, EXR_PIXEL_UINT};
    exr_compression_t comps[] = {EXR_COMPRESSION_ZIP, EXR_COMPRESSION_PIZ, EXR_COMPRESSION_NONE};
    for (int t = 0; t < 3; t++) {
        write_independent(path, 0, 5 - 10 * t, 7, 29, 41, rgbaz, 6, types[t], comps[t]);
        ss_image *img = ss_exr_read(path, &err);
        assert_non_null(img);
        assert_int_equal(img->width, 29);
        assert_int_equal(img->height, 41);
        assert_int_equal(img->channels, 4);
        check_channel(img, 0, 5); /* R */
        check_channel(img, 1, 1); /* G */
        check_channel(img, 2, 3); /* B */
        check_channel(img, 3, 4); /* A */
        ss_image_free(img);
    }
    /* R,G,B without alpha; Y with alpha; Y alone (extra channels ignored). */
    static const char *const rgb[] = {"B", "R", "G", "depth"};
    write_independent(path, 0, 0, -3, 18, 17, rgb, 4, EXR_PIXEL_HALF, EXR_COMPRESSION_ZIP);
    ss_image *img = ss_exr_read(path, &err);
    assert_non_null(img);
    assert_int_equal(img->channels, 3);
    check_channel(img, 0, 1);
    check_channel(img, 1, 2);
    check_channel(img, 2, 0);
    ss_image_free(img);
    static const char *const ya[] = {"Y", "A", "Z"};
    write_independent(path, 0, 0, 0, 16, 33, ya, 3, EXR_PIXEL_FLOAT, EXR_COMPRESSION_RLE);
    img = ss_exr_read(path, &err);
    assert_non_null(img);
    assert_int_equal(img->channels, 2);
    check_channel(img, 0, 0);
    check_channel(img, 1, 1);
    ss_image_free(img);
    write_independent(path, 0, 0, 0, 16, 33, ya + 2, 1, EXR_PIXEL_FLOAT, EXR_COMPRESSION_ZIP);
    /* Z only: nothing to read */
    assert_null(ss_exr_read(path, &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, path));
    static const char *const yzw[] = {"Y", "Z", "W"};
    write_independent(path, 0, 0, 0, 3, 2, yzw, 3, EXR_PIXEL_HALF, EXR_COMPRESSION_ZIPS);
    img = ss_exr_read(path, &err);
    assert_non_null(img);
    assert_int_equal(img->channels, 1);
    check_channel(img, 0, 0);
    ss_image_free(img);
    write_independent(path, 0, 2, 2, 13, 5, yzw, 1, EXR_PIXEL_FLOAT, EXR_COMPRESSION_NONE);
    img = ss_exr_read(path, &err);
    assert_non_null(img);
    assert_int_equal(img->channels, 1);
    check_channel(img, 0, 0);
    ss_image_free(img);
    /* Tiled: a clear refusal. */
    write_independent(path, 1, 0, 0, 40, 20, rgb, 3, EXR_PIXEL_HALF, EXR_COMPRESSION_ZIP);
    assert_null(ss_exr_read(path, &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, path));
    assert_non_null(strstr(err.msg, "tiled EXR not supported"));
    tu_rmtree(dir);
    free(dir);
}

static void expect_bad(const char *path, const void *bytes, size_t len) {
    ss_error err;
    assert_int_equal(ss_write_file_atomic(path, bytes, len, &err), SS_OK);
    ss_error_clear(&err);
    assert_null(ss_exr_read(path, &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, path));
}

static uint64_t le64(const unsigned char *p) {
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--) v = (v << 8) | p[i];
    return v;
}

static void test_bad_input(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("exrbad");
    char good[512], bad[512];
    snprintf(good, sizeof good, "%s/good.exr", dir);
    snprintf(bad, sizeof bad, "%s/bad.exr", dir);

    assert_null(ss_exr_read("/nonexistent/x.exr", &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "/nonexistent/x.exr"));
    assert_null(ss_exr_read(dir, &err)); /* a directory */
    assert_int_equal(err.code, SS_ERR_INPUT);
    expect_bad(bad, "hello, not an EXR file at all", 29);
    expect_bad(bad, "", 0);

    /* A good file (smooth, so ZIP really compresses), then cut and corrupted copies. */
    int w = 37, h = 40, nchunks = (h + 15) / 16;
    ss_image *img = ss_image_create(w, h, 1, &err);
    for (int i = 0; i < w * h; i++) img->data[i] = (float)(i % w) * 0.5f;
    assert_int_equal(ss_exr_write(good, img, 0, &err), SS_OK);
    size_t len;
    unsigned char *bytes = (unsigned char *)ss_read_file(good, &len, &err);
    assert_non_null(bytes);
    expect_bad(bad, bytes, 12);      /* header cut */
    expect_bad(bad, bytes, len / 2); /* chunks missing */
    expect_bad(bad, bytes, len - 1); /* last byte missing */

    /* Locate the offset table: its first entry points just past itself. */
    size_t table = 0;
    for (size_t p = 8; p + 8 * (size_t)nchunks <= len && !table; p++)
        if (le64(bytes + p) == p + 8 * (uint64_t)nchunks) table = p;
    assert_true(table > 0);
    unsigned char *copy = malloc(len);
    memcpy(copy, bytes, len);
    memset(copy + table, 0xff, 8 * (size_t)nchunks); /* offsets past the end */
    expect_bad(bad, copy, len);
    /* Chunk payload garbled: y (4 bytes), size (4 bytes), then zlib data. */
    memcpy(copy, bytes, len);
    size_t chunk = (size_t)le64(bytes + table);
    uint32_t packed = (uint32_t)copy[chunk + 4] | (uint32_t)copy[chunk + 5] << 8 |
                      (uint32_t)copy[chunk + 6] << 16 | (uint32_t)copy[chunk + 7] << 24;
    assert_true(packed < (uint32_t)(w * 16 * 4)); /* really compressed */
    memset(copy + chunk + 8, 0x5a, packed);
    expect_bad(bad, copy, len);
    free(copy);
    free(bytes);

    /* Unwritable destinations: error naming the path, nothing created. */
    assert_int_not_equal(ss_exr_write("/nonexistent-dir/x.exr", img, 1, &err), SS_OK);
    assert_non_null(strstr(err.msg, "/nonexistent-dir/x.exr"));
    snprintf(bad, sizeof bad, "%s/good.exr/x.exr", dir); /* a file in the way */
    assert_int_not_equal(ss_exr_write(bad, img, 1, &err), SS_OK);
    assert_int_equal(err.code, SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, bad));
    /* An unsupported image: refused before anything is written. */
    snprintf(bad, sizeof bad, "%s/five.exr", dir);
    ss_image five = {.width = 2, .height = 2, .channels = 5, .data = img->data};
    assert_int_equal(ss_exr_write(bad, &five, 0, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, bad));
    assert_int_equal(tu_count_entries(dir), 2); /* good.exr and bad.exr only */
    ss_image_free(img);
    tu_rmtree(dir);
    free(dir);
}

static void test_write_failure_leaves_old_file(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("exrfail");
    char path[512];
    snprintf(path, sizeof path, "%s/out.exr", dir);
    assert_int_equal(ss_write_file_atomic(path, "old", 3, &err), SS_OK);
    /* Random floats do not compress: about 1 MB, far over a 64 kB file size limit. */
    ss_image *img = ss_image_create(256, 256, 4, &err);
    for (int i = 0; i < 256 * 256 * 4; i++) img->data[i] = (float)ss_rng_uniform(7, 0, (uint64_t)i);
    struct rlimit old, lim;
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &old), 0);
    lim = old;
    lim.rlim_cur = 64 * 1024;
    void (*prev)(int) = signal(SIGXFSZ, SIG_IGN); /* over-limit writes fail with EFBIG */
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &lim), 0);
    ss_status st = ss_exr_write(path, img, 0, &err);
    assert_int_equal(setrlimit(RLIMIT_FSIZE, &old), 0);
    signal(SIGXFSZ, prev);
    assert_int_not_equal(st, SS_OK);
    assert_non_null(strstr(err.msg, path));
    assert_int_equal(tu_count_entries(dir), 1); /* no temporary file */
    size_t len;
    char *bytes = ss_read_file(path, &len, &err);
    assert_non_null(bytes);
    assert_int_equal(len, 3);
    assert_memory_equal(bytes, "old", 3);
    free(bytes);
    /* Without the limit the same write succeeds and replaces the old file. */
    assert_int_equal(ss_exr_write(path, img, 0, &err), SS_OK);
    ss_image *back = ss_exr_read(path, &err);
    assert_non_null(back);
    assert_memory_equal(back->data, img->data, sizeof(float) * 256 * 256 * 4);
    ss_image_free(back);
    ss_image_free(img);
    tu_rmtree(dir);
    free(dir);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_roundtrips),
        cmocka_unit_test(test_read_independent_files),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_write_failure_leaves_old_file),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
