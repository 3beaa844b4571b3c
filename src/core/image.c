/* Float images: plain structs with create/free, wrap-around sampling, resize,
 * and the sRGB transfer functions used at 8/16-bit file boundaries. */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE
#include "skinsim/core.h"

#include <sys/mman.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Pixel storage. Big images (textures are hundreds of MB per set) are
 * aligned to 2 MB and advised as huge pages: first touch then costs one
 * fault per 2 MB instead of per 4 KB, which dominated rendering a timeline.
 * Zeroing runs in parallel so the page faults are spread over the threads. */
#define HUGE_BYTES ((size_t)8 << 20)
static float *alloc_pixels(size_t n, int zero) {
    size_t bytes = n * sizeof(float);
    if (bytes < HUGE_BYTES) return zero ? calloc(n, sizeof(float)) : malloc(bytes);
    void *p = NULL;
    if (posix_memalign(&p, (size_t)2 << 20, bytes) != 0) return NULL;
#ifdef MADV_HUGEPAGE
    madvise(p, bytes, MADV_HUGEPAGE);
#endif
    if (zero) {
        const size_t chunk = (size_t)1 << 20; /* bytes */
        const long nchunks = (long)((bytes + chunk - 1) / chunk);
#pragma omp parallel for schedule(static)
        for (long c = 0; c < nchunks; c++) {
            size_t off = (size_t)c * chunk, len = bytes - off < chunk ? bytes - off : chunk;
            memset((char *)p + off, 0, len);
        }
    }
    return p;
}

static ss_image *image_new(int width, int height, int channels, int zero, ss_error *err) {
    if (width <= 0 || height <= 0 || width > SS_IMAGE_MAX_SIDE || height > SS_IMAGE_MAX_SIDE) {
        ss_error_set(err, SS_ERR_INPUT, "image size %dx%d is out of range 1..%d", width, height,
                     SS_IMAGE_MAX_SIDE);
        return NULL;
    }
    if (channels < 1 || channels > SS_IMAGE_MAX_CHANNELS) {
        ss_error_set(err, SS_ERR_INPUT, "image channel count %d is out of range 1..%d", channels,
                     SS_IMAGE_MAX_CHANNELS);
        return NULL;
    }
    ss_image *img = malloc(sizeof *img);
    size_t n = (size_t)width * (size_t)height * (size_t)channels;
    float *data = img ? alloc_pixels(n, zero) : NULL;
    if (!data) {
        free(img);
        ss_error_set(err, SS_ERR_NOMEM, "out of memory for a %dx%dx%d image", width, height,
                     channels);
        return NULL;
    }
    img->width = width;
    img->height = height;
    img->channels = channels;
    img->data = data;
    return img;
}

ss_image *ss_image_create(int width, int height, int channels, ss_error *err) {
    return image_new(width, height, channels, 1, err);
}

ss_image *ss_image_create_uninit(int width, int height, int channels, ss_error *err) {
    return image_new(width, height, channels, 0, err);
}

ss_image *ss_image_clone(const ss_image *img, ss_error *err) {
    ss_image *c = ss_image_create_uninit(img->width, img->height, img->channels, err);
    if (c)
        memcpy(c->data, img->data,
               (size_t)img->width * (size_t)img->height * (size_t)img->channels * sizeof(float));
    return c;
}

void ss_image_free(ss_image *img) {
    if (!img) return;
    free(img->data);
    free(img);
}

void ss_image_fill(ss_image *img, const float *value) {
    size_t n = (size_t)img->width * (size_t)img->height;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < img->channels; c++)
            img->data[i * (size_t)img->channels + (size_t)c] = value[c];
}

static int wrap(int i, int n) {
    i %= n;
    return i < 0 ? i + n : i;
}

void ss_image_sample_wrap(const ss_image *img, float u, float v, float *out) {
    float fx = u * (float)img->width - 0.5f, fy = v * (float)img->height - 0.5f;
    float x0f = floorf(fx), y0f = floorf(fy);
    float tx = fx - x0f, ty = fy - y0f;
    int x0 = wrap((int)x0f, img->width), y0 = wrap((int)y0f, img->height);
    int x1 = wrap(x0 + 1, img->width), y1 = wrap(y0 + 1, img->height);
    const float *a = ss_image_px(img, x0, y0), *b = ss_image_px(img, x1, y0);
    const float *c = ss_image_px(img, x0, y1), *d = ss_image_px(img, x1, y1);
    for (int k = 0; k < img->channels; k++) {
        float top = a[k] + (b[k] - a[k]) * tx, bot = c[k] + (d[k] - c[k]) * tx;
        out[k] = top + (bot - top) * ty;
    }
}

/* ss_image_resize of map(img), without making the mapped full-size image:
 * each output texel is the same bilinear sample as ss_image_sample_wrap
 * (the same operations, so the same floats) of the four mapped texels it
 * reads. A 2048^2 map shrunk to 512^2 maps 1 texel in 4 instead of all. */
ss_image *ss_image_resize_mapped(const ss_image *img, int width, int height, int channels,
                                 ss_texel_map map, void *ctx, ss_error *err) {
    if (channels < 1 || channels > 4 || !map) {
        ss_error_set(err, SS_ERR_INPUT, "resize: %d mapped channels (1..4)", channels);
        return NULL;
    }
    ss_image *r = ss_image_create(width, height, channels, err);
    if (!r) return NULL;
    if (width == img->width && height == img->height) {
#pragma omp parallel for schedule(static)
        for (int y = 0; y < height; y++)
            for (int x = 0; x < width; x++) map(ss_image_px(img, x, y), ss_image_px(r, x, y), ctx);
        return r;
    }
#pragma omp parallel for schedule(static)
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) {
            const float u = ((float)x + 0.5f) / (float)width, v = ((float)y + 0.5f) / (float)height;
            float fx = u * (float)img->width - 0.5f, fy = v * (float)img->height - 0.5f;
            float x0f = floorf(fx), y0f = floorf(fy);
            float tx = fx - x0f, ty = fy - y0f;
            int x0 = wrap((int)x0f, img->width), y0 = wrap((int)y0f, img->height);
            int x1 = wrap(x0 + 1, img->width), y1 = wrap(y0 + 1, img->height);
            float a[4], b[4], c[4], d[4], *out = ss_image_px(r, x, y);
            map(ss_image_px(img, x0, y0), a, ctx);
            map(ss_image_px(img, x1, y0), b, ctx);
            map(ss_image_px(img, x0, y1), c, ctx);
            map(ss_image_px(img, x1, y1), d, ctx);
            for (int k = 0; k < channels; k++) {
                float top = a[k] + (b[k] - a[k]) * tx, bot = c[k] + (d[k] - c[k]) * tx;
                out[k] = top + (bot - top) * ty;
            }
        }
    return r;
}

ss_image *ss_image_resize(const ss_image *img, int width, int height, ss_error *err) {
    ss_image *r = ss_image_create(width, height, img->channels, err);
    if (!r) return NULL;
    if (width == img->width && height == img->height) {
        memcpy(r->data, img->data,
               (size_t)width * (size_t)height * (size_t)img->channels * sizeof(float));
        return r;
    }
#pragma omp parallel for schedule(static)
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++)
            ss_image_sample_wrap(img, ((float)x + 0.5f) / (float)width,
                                 ((float)y + 0.5f) / (float)height, ss_image_px(r, x, y));
    return r;
}

float ss_srgb_encode(float l) {
    if (!(l > 0.0f)) return 0.0f;
    if (l >= 1.0f) return 1.0f;
    return l <= 0.0031308f ? 12.92f * l : 1.055f * powf(l, 1.0f / 2.4f) - 0.055f;
}

float ss_srgb_decode(float e) {
    if (!(e > 0.0f)) return 0.0f;
    if (e >= 1.0f) return 1.0f;
    return e <= 0.04045f ? e / 12.92f : powf((e + 0.055f) / 1.055f, 2.4f);
}

#define ENC_LUT 16384
void ss_srgb_encode_array(const float *in, float *out, size_t n) {
    float *lut = malloc((ENC_LUT + 1) * sizeof(float));
    if (!lut) { /* no memory for the table: exact per value */
        for (size_t i = 0; i < n; i++) out[i] = ss_srgb_encode(in[i]);
        return;
    }
    for (int i = 0; i <= ENC_LUT; i++) lut[i] = ss_srgb_encode((float)i / ENC_LUT);
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) {
        float v = in[i];
        if (!(v > 0.0f)) v = 0.0f;
        if (v > 1.0f) v = 1.0f;
        float f = v * ENC_LUT;
        int k = (int)f;
        if (k >= ENC_LUT) k = ENC_LUT - 1;
        out[i] = lut[k] + (lut[k + 1] - lut[k]) * (f - (float)k);
    }
    free(lut);
}
