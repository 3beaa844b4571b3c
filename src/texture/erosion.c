/* Shape erosion with per-pixel kernel widths (seed 000 §3.3.1, Eq. 3.1,
 * Alg. 3.1): each pixel becomes the minimum of the N x 1 horizontal window
 * centred on it, N = widths[pixel]; pixels outside the texture count as the
 * highest value, i.e. the window is clipped to the row.
 *
 * ss_erode_reference loops over the window literally (O(N) per pixel).
 * ss_erode answers the same range-minimum queries in O(1) from a per-row
 * sparse table (min over [x, x + 2^k)), built only up to the largest power
 * of two the row's widths need; min is exact, so the two agree bit for bit.
 * Rows run in parallel (OpenMP), each independently. Multi-channel images
 * are eroded channel by channel; src and dst must have the same shape (dst
 * is left untouched otherwise). ss_erode may run in place (dst == src). */
#include "skinsim/texture.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

void ss_erosion_widths_rect(int width, int height, int x0, int y0, int w, int h, int min_w,
                            int max_w, uint64_t seed, uint64_t stream, int *widths) {
    if (!widths || width <= 0 || height <= 0 || w <= 0 || h <= 0 || x0 < 0 || y0 < 0 ||
        x0 + w > width || y0 + h > height)
        return;
    if (min_w < 0) min_w = 0;
    if (max_w < min_w) max_w = min_w;
    const uint64_t span = (uint64_t)(max_w - min_w) + 1;
    /* The random numbers go through widths itself (same size as uint32);
     * pixel (x, y) always draws index y * width + x. */
    uint32_t *r = (uint32_t *)(void *)widths;
    for (int y = 0; y < h; y++)
        ss_rng_fill_u32(seed, stream, (uint64_t)(y0 + y) * (uint64_t)width + (uint64_t)x0,
                        r + (size_t)y * w, (size_t)w);
    const size_t n = (size_t)w * h;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) {
        const int m = min_w + (int)(r[i] % span);
        widths[i] = m + (m % 2) + 1; /* Eq. 3.1 */
    }
}

void ss_erosion_widths(int width, int height, int min_w, int max_w, uint64_t seed, uint64_t stream,
                       int *widths) {
    ss_erosion_widths_rect(width, height, 0, 0, width, height, min_w, max_w, seed, stream, widths);
}

static int same_shape(const ss_image *a, const ss_image *b) {
    return a && b && a->data && b->data && a->width == b->width && a->height == b->height &&
           a->channels == b->channels;
}

static inline int half_width(int n) { return n > 1 ? n / 2 : 0; }

/* min without fminf's NaN handling (a library call at -O2); both versions use it. */
static inline float min2(float a, float b) { return b < a ? b : a; }

void ss_erode_reference(const ss_image *src, const int *widths, ss_image *dst) {
    if (!same_shape(src, dst) || !widths) return;
    const int W = src->width, H = src->height, C = src->channels;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            for (int c = 0; c < C; c++) {
                float out = HUGE_VALF; /* highest value possible */
                const int e = half_width(widths[(size_t)y * W + x]);
                for (int k = -e; k <= e; k++) {
                    const int xx = x + k;
                    if (xx < 0 || xx >= W) continue; /* outside: highest value, ignored */
                    const float v = src->data[((size_t)y * W + xx) * C + c];
                    out = min2(out, v);
                }
                dst->data[((size_t)y * W + x) * C + c] = out;
            }
}

void ss_erode(const ss_image *src, const int *widths, ss_image *dst) {
    if (!same_shape(src, dst) || !widths) return;
    const int W = src->width, H = src->height, C = src->channels;
    int levels_max = 1;
    while ((1 << levels_max) <= W) levels_max++;
#pragma omp parallel
    {
        float *tab = malloc(sizeof *tab * (size_t)W * levels_max);
#pragma omp for schedule(static)
        for (int y = 0; y < H; y++) {
            if (!tab) continue;
            const int *wr = widths + (size_t)y * W;
            int maxlen = 1;
            for (int x = 0; x < W; x++) {
                const int len = 2 * half_width(wr[x]) + 1;
                if (len > maxlen) maxlen = len > W ? W : len;
            }
            int levels = 1;
            while ((1 << levels) <= maxlen) levels++;
            for (int c = 0; c < C; c++) {
                for (int x = 0; x < W; x++) tab[x] = src->data[((size_t)y * W + x) * C + c];
                for (int k = 1; k < levels; k++) {
                    const float *a = tab + (size_t)(k - 1) * W;
                    float *t = tab + (size_t)k * W;
                    const int step = 1 << (k - 1), last = W - (1 << k);
                    for (int x = 0; x <= last; x++) t[x] = min2(a[x], a[x + step]);
                }
                for (int x = 0; x < W; x++) {
                    const int e = half_width(wr[x]);
                    const int lo = x - e < 0 ? 0 : x - e, hi = x + e >= W ? W - 1 : x + e;
                    const int len = hi - lo + 1;
                    const int k = 31 - __builtin_clz((unsigned)len);
                    const float *t = tab + (size_t)k * W;
                    dst->data[((size_t)y * W + x) * C + c] = min2(t[lo], t[hi - (1 << k) + 1]);
                }
            }
        }
        free(tab);
    }
}
