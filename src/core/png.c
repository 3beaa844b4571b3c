/* PNG read/write with libpng: writes 8 or 16 bits, 1-4 channels; reads any
 * PNG (1, 2, 4, 8, 16 bits, grey, palette, with alpha or tRNS); sRGB
 * encoding of colour channels only at this boundary (images in memory are
 * linear). Reading is bounded before libpng allocates: every chunk must fit
 * in the file, ancillary chunks are capped, and the pixels the header
 * claims must fit in memory and in what the compressed data can hold. */
#include "skinsim/core.h"

#include <errno.h>
#include <png.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h> /* Z_RLE */

/* libpng's default handler prints to stderr; errors reach the caller as an
 * ss_error instead, so only longjmp here. */
static void png_error_quiet(png_structp png, png_const_charp msg) {
    (void)msg;
    png_longjmp(png, 1);
}
static void png_warning_quiet(png_structp png, png_const_charp msg) {
    (void)png;
    (void)msg;
}

static float encode(float v, int c, int channels, ss_encoding enc) {
    int is_alpha = (channels == 2 && c == 1) || (channels == 4 && c == 3);
    if (!(v > 0.0f)) v = 0.0f; /* also maps NaN to 0 */
    if (v > 1.0f) v = 1.0f;
    return (enc == SS_ENC_SRGB && !is_alpha) ? ss_srgb_encode(v) : v;
}

static unsigned char to8(float v, int c, int channels, ss_encoding enc) {
    return (unsigned char)(encode(v, c, channels, enc) * 255.0f + 0.5f);
}

/* 8-bit sRGB without a powf per sample: th[k] (k = 1..255) is the smallest
 * float whose code is k, found by bisection over the float bit patterns with
 * to8 itself, so the lookup (count of thresholds <= v) gives exactly to8's
 * code. 255 x 31 calls per file; the bytes are the same as before. */
static void srgb8_thresholds(float th[256]) {
    th[0] = 0.0f;
    for (int k = 1; k < 256; k++) {
        uint32_t lo = 0, hi = 0x3f800000u; /* 0.0f .. 1.0f (code 255) */
        while (hi - lo > 1) {
            uint32_t mid = lo + (hi - lo) / 2;
            float f;
            memcpy(&f, &mid, sizeof f);
            if (to8(f, 0, 3, SS_ENC_SRGB) >= k)
                hi = mid;
            else
                lo = mid;
        }
        memcpy(&th[k], &hi, sizeof th[k]);
    }
}

static unsigned char srgb8_lookup(const float th[256], float v) {
    if (!(v > 0.0f)) return 0; /* NaN too */
    int k = 0;
    for (int step = 128; step; step >>= 1)
        if (k + step < 256 && th[k + step] <= v) k += step;
    return (unsigned char)k;
}

ss_status ss_png_write(const char *path, const ss_image *img, int bits, ss_encoding enc,
                       ss_error *err) {
    if (bits != 8 && bits != 16)
        return ss_error_set(err, SS_ERR_INPUT, "%s: PNG bit depth must be 8 or 16, not %d", path,
                            bits);
    static const int types[5] = {0, PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA,
                                 PNG_COLOR_TYPE_RGB, PNG_COLOR_TYPE_RGBA};
    int ch = img->channels;
    if (ch < 1 || ch > 4)
        return ss_error_set(err, SS_ERR_INPUT, "%s: PNG holds 1..4 channels, not %d", path, ch);
    size_t rowbytes = (size_t)img->width * (size_t)ch * (size_t)(bits / 8);
    unsigned char *row = malloc(rowbytes);
    if (!row) return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
    ss_atomic_file af;
    ss_status st = ss_atomic_open(&af, path, err);
    if (st) {
        free(row);
        return st;
    }
    png_structp png =
        png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, png_error_quiet, png_warning_quiet);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!info || setjmp(png_jmpbuf(png))) {
        int e = errno, wrote_badly = af.fp && ferror(af.fp);
        png_destroy_write_struct(&png, &info);
        ss_atomic_abort(&af);
        free(row);
        if (wrote_badly) /* a full disk, a quota, an I/O error */
            return ss_error_set(err, SS_ERR_RUNTIME, "%s: cannot write: %s", path,
                                e ? strerror(e) : "write error");
        return ss_error_set(err, SS_ERR_RUNTIME, "%s: PNG encoding failed", path);
    }
    png_init_io(png, af.fp);
    /* Speed: run-length deflate (Z_RLE: on these noisy maps 5-10 % smaller
     * than level 1 and 1.3-2.7x faster; a flat image still shrinks to
     * almost nothing), and two cheap row filters instead of libpng's trial
     * of all five on every row. */
    png_set_compression_level(png, 1);
    png_set_compression_strategy(png, Z_RLE);
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB | PNG_FILTER_UP);
    png_set_IHDR(png, info, (png_uint_32)img->width, (png_uint_32)img->height, bits, types[ch],
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (enc == SS_ENC_SRGB)
        png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    else
        png_set_gAMA(png, info, 1.0);
    png_write_info(png, info);
    float th[256];
    int lut8 = bits == 8 && enc == SS_ENC_SRGB;
    if (lut8) srgb8_thresholds(th);
    int alpha_at = (ch == 2 || ch == 4) ? ch - 1 : -1;
    for (int y = 0; y < img->height; y++) {
        const float *src = ss_image_px(img, 0, y);
        for (int i = 0, c = 0; i < img->width * ch; i++, c = c + 1 == ch ? 0 : c + 1) {
            if (lut8 && c != alpha_at) {
                row[i] = srgb8_lookup(th, src[i]);
            } else if (bits == 8) {
                row[i] = to8(src[i], c, ch, enc);
            } else {
                float v = encode(src[i], c, ch, enc);
                unsigned q = (unsigned)(v * 65535.0f + 0.5f);
                row[2 * i] = (unsigned char)(q >> 8);
                row[2 * i + 1] = (unsigned char)(q & 0xff);
            }
        }
        png_write_row(png, row);
    }
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    free(row);
    return ss_atomic_commit(&af, err);
}

/* Every chunk's length checked against what the file holds, before libpng
 * sees the file (libpng allocates an ancillary chunk's stated length before
 * it finds the file too short: a 44-byte PNG claiming a 2 GB tEXt took 2 GB).
 * A chunk must fit in the bytes after it (its data and CRC) and an
 * ancillary one is at most SS_PNG_MAX_ANCILLARY_BYTES. Seeks only: a few
 * microseconds per chunk. f is left just after the signature. */
static ss_status png_scan_chunks(FILE *f, const char *path, size_t fsize, ss_error *err) {
    size_t pos = 8;
    for (;;) {
        unsigned char h[8];
        if (fseek(f, (long)pos, SEEK_SET) != 0 || fread(h, 1, 8, f) != 8)
            return ss_error_set(err, SS_ERR_INPUT,
                                "%s: corrupt or truncated PNG (it ends at byte %zu, before IEND)",
                                path, pos);
        unsigned long len = ((unsigned long)h[0] << 24) | ((unsigned long)h[1] << 16) |
                            ((unsigned long)h[2] << 8) | (unsigned long)h[3];
        char type[5];
        for (int k = 0; k < 4; k++) {
            unsigned char c = h[4 + k];
            type[k] = (char)((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') ? c : '?');
        }
        type[4] = '\0';
        size_t left = fsize - pos - 8; /* data and CRC must fit in this */
        if (left < 4 || len > left - 4)
            return ss_error_set(err, SS_ERR_INPUT,
                                "%s: corrupt or truncated PNG (chunk %s at byte %zu claims %lu "
                                "bytes, the file holds %zu more)",
                                path, type, pos, len, left < 4 ? 0 : left - 4);
        if ((h[4] & 0x20) && len > SS_PNG_MAX_ANCILLARY_BYTES)
            return ss_error_set(err, SS_ERR_INPUT,
                                "%s: ancillary chunk %s at byte %zu is %lu bytes, above the %d MB "
                                "limit for ancillary chunks",
                                path, type, pos, len, (int)(SS_PNG_MAX_ANCILLARY_BYTES >> 20));
        if (!memcmp(h + 4, "IEND", 4)) break;
        pos += 12 + (size_t)len;
    }
    if (fseek(f, 8, SEEK_SET) != 0)
        return ss_error_set(err, SS_ERR_INPUT, "%s: cannot seek: %s", path, strerror(errno));
    return SS_OK;
}

ss_image *ss_png_read(const char *path, ss_encoding enc, ss_error *err) {
    size_t fsize = 0;
    FILE *f = ss_input_open(path, &fsize, err); /* regular files only, never blocks */
    if (!f) return NULL;
    unsigned char sig[8];
    if (fread(sig, 1, 8, f) != 8 || png_sig_cmp(sig, 0, 8) != 0) {
        fclose(f);
        ss_error_set(err, SS_ERR_INPUT, "%s: not a PNG file", path);
        return NULL;
    }
    if (png_scan_chunks(f, path, fsize, err)) {
        fclose(f);
        return NULL;
    }
    png_structp png =
        png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, png_error_quiet, png_warning_quiet);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    ss_image *volatile img = NULL;
    unsigned char *volatile row = NULL;
    if (!info || setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, NULL);
        fclose(f);
        ss_image_free(img);
        free(row);
        ss_error_set(err, SS_ERR_INPUT, "%s: corrupt or truncated PNG", path);
        return NULL;
    }
    png_init_io(png, f);
    png_set_sig_bytes(png, 8);
    png_set_user_limits(png, SS_IMAGE_MAX_SIDE, SS_IMAGE_MAX_SIDE);
    png_set_chunk_malloc_max(png, SS_PNG_MAX_ANCILLARY_BYTES); /* also decompressed zTXt, iCCP */
    png_read_info(png, info);
    /* the rows as stored (1, 2, 4 bits a sample, palette indices), before
     * the expansion below: what the compressed data must hold */
    double stored_rowbytes = (double)png_get_rowbytes(png, info);
    png_set_expand(png);  /* palette -> RGB(A), 1/2/4-bit grey -> 8 bits, tRNS -> alpha */
    png_set_packing(png); /* (for any depth below 8 the expansion leaves) */
    png_read_update_info(png, info);
    int w = (int)png_get_image_width(png, info), h = (int)png_get_image_height(png, info);
    int ch = png_get_channels(png, info), bits = png_get_bit_depth(png, info);
    /* Before allocating what the header claims: the pixels must fit in
     * memory, and the file must be able to hold them (deflate expands at
     * most about 1032:1, so a tiny file cannot be a huge image). */
    ss_error e2;
    double raw = (double)h * (stored_rowbytes + 1.0);
    ss_status cs = ss_image_check_alloc(path, w, h, ch, &e2);
    if (!cs && raw > 1100.0 * (double)fsize + 65536.0)
        cs = ss_error_set(&e2, SS_ERR_INPUT,
                          "%s: header claims %d x %d pixels (%.0f MB), more than a %zu-byte PNG "
                          "can hold: truncated or forged",
                          path, w, h, raw / 1e6, fsize);
    img = cs ? NULL : ss_image_create(w, h, ch, &e2);
    if (!img) {
        png_destroy_read_struct(&png, &info, NULL);
        fclose(f);
        if (cs)
            *err = e2;
        else
            ss_error_set(err, SS_ERR_INPUT, "%s: %s", path, e2.msg);
        return NULL;
    }
    row = malloc(png_get_rowbytes(png, info));
    if (!row) png_error(png, "out of memory");
    for (int y = 0; y < h; y++) {
        png_read_row(png, row, NULL);
        float *dst = ss_image_px(img, 0, y);
        for (int i = 0; i < w * ch; i++) {
            float v = bits == 16 ? (float)((row[2 * i] << 8) | row[2 * i + 1]) / 65535.0f
                                 : (float)row[i] / 255.0f;
            int is_alpha = (ch == 2 && i % ch == 1) || (ch == 4 && i % ch == 3);
            dst[i] = (enc == SS_ENC_SRGB && !is_alpha) ? ss_srgb_decode(v) : v;
        }
    }
    png_destroy_read_struct(&png, &info, NULL);
    fclose(f);
    free(row);
    return img;
}

ss_image *ss_image_read(const char *path, ss_encoding enc, ss_error *err) {
    const char *dot = strrchr(path, '.');
    if (dot && (strcmp(dot, ".exr") == 0 || strcmp(dot, ".EXR") == 0))
        return ss_exr_read(path, err);
    return ss_png_read(path, enc, err);
}
