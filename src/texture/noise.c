/* Value noise, bias and gain (seed 000 §3.3.2, Eq. 3.2-3.7, Alg. 3.2).
 *
 * Bias: Eq. 3.6 as printed, v / ((1/b)(1-v) + 1), gives bias(v, 0.5) =
 * v / (3 - 2v), which contradicts the seed's own statement that 0.5 leaves
 * the noise unchanged (and fig. 3.7). The formula it abbreviates is Schlick's
 * rational bias (Graphics Gems IV, 1994), v / ((1/b - 2)(1 - v) + 1), which we
 * use: bias(v, 0.5) = v exactly, b > 0.5 brightens, b < 0.5 darkens.
 * Gain: Eq. 3.7 exactly as printed, on top of that bias. Note that with it a
 * gain g > 0.5 pulls both halves towards 0.5 (less contrast) and g < 0.5
 * pushes them apart; gain(v, g) equals Perlin's/Schlick's gain(v, 1 - g).
 *
 * ss_value_noise_reference is Alg. 3.2 line by line: a base array of the
 * output size filled with ss_rng_fill_f32(seed, stream, 0, ...) (index y*w + x), octaves from
 * `octaves` down to 0 with period 2^oct, sample rows/columns by Eq. 3.2/3.3
 * (x0 wraps with a true modulo so periods larger than the texture also
 * work; for period <= size it is the seed's formula), blend = (p - x1) *
 * frequency, Eq. 3.4 on the four rows then on the column, times the
 * amplitude, summed; then divided by the total amplitude. Eq. 3.4 (a
 * Catmull-Rom-like cubic) overshoots [0, 1] slightly near extreme lattice
 * values, so the normalised value is clamped to [0, 1] before bias and gain
 * (which are only defined there). All arithmetic is float.
 *
 * ss_value_noise computes the same numbers (bit for bit at stretch 1 and
 * cell_px 1, as the tests check) faster and more generally: the base lattice
 * has round(size / cell_px) points per axis and wraps; output pixel p samples
 * lattice coordinate u = p * lattice / (size * stretch), wrapped into the
 * lattice. Per octave the four lattice indices and the blend of every column
 * and every row are precomputed once; the image is processed in bands of 32
 * rows (OpenMP over bands): for each octave the horizontal cubics of only
 * the lattice rows the band needs are computed into a per-thread buffer, then
 * each output row is a vectorisable vertical cubic of four buffered rows.
 * Every pixel is computed by the same float operations in the same order on
 * any thread count, so results are bit-identical across thread counts. */
#include "skinsim/texture.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

float ss_bias(float v, float b) {
    if (!(v > 0.0f)) return v == v ? 0.0f : v;
    if (v >= 1.0f) return 1.0f;
    if (b <= 0.0f) return 0.0f;
    if (b >= 1.0f) return 1.0f;
    return v / ((1.0f / b - 2.0f) * (1.0f - v) + 1.0f);
}

float ss_gain(float v, float g) {
    if (v < 0.5f) return ss_bias(v * 2.0f, g) / 2.0f;
    return ss_bias(v * 2.0f - 1.0f, 1.0f - g) / 2.0f + 0.5f;
}

void ss_noise_params_default(ss_noise_params *p) {
    p->octaves = 5;
    p->persistence = 0.5f;
    p->bias = 0.5f;
    p->gain = 0.5f;
    p->stretch_x = 1.0f;
    p->stretch_y = 1.0f;
    p->cell_px = 1.0f;
}

/* Eq. 3.4. Written once so both versions evaluate it identically. */
static inline float cubic(float v0, float v1, float v2, float v3, float b) {
    const float p = (v3 - v2) - (v0 - v1);
    const float q = (v0 - v1) - p;
    const float r = v2 - v0;
    return p * b * b * b + q * b * b + r * b + v1;
}

/* Alg. 3.2 lines 20-22 on n values, with the clamp. bias = gain = 0.5 is the
 * identity exactly (see ss_bias), so it is skipped then. */
static void finish(float *restrict o, size_t n, float total, float bias, float gain) {
    const int ident = bias == 0.5f && gain == 0.5f;
#pragma omp simd
    for (size_t i = 0; i < n; i++) {
        float v = o[i] / total;
        v = v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v); /* Eq. 3.4 overshoot */
        o[i] = v;
    }
    if (!ident)
        for (size_t i = 0; i < n; i++) o[i] = ss_gain(ss_bias(o[i], bias), gain);
}

#define MAX_OCTAVES 24

static ss_status check_params(const ss_noise_params *p, const ss_image *out, ss_error *err) {
    if (!p) return ss_error_set(err, SS_ERR_INPUT, "value noise: no parameters");
    if (!out || !out->data || out->channels != 1)
        return ss_error_set(err, SS_ERR_INPUT, "value noise: output must be a 1-channel image");
    if (p->octaves < 0 || p->octaves > MAX_OCTAVES)
        return ss_error_set(err, SS_ERR_INPUT, "value noise: octaves must be 0..%d, got %d",
                            MAX_OCTAVES, p->octaves);
    if (!(p->persistence > 0.0f) || !isfinite(p->persistence))
        return ss_error_set(err, SS_ERR_INPUT, "value noise: persistence must be > 0, got %g",
                            (double)p->persistence);
    if (!(p->bias >= 0.0f && p->bias <= 1.0f))
        return ss_error_set(err, SS_ERR_INPUT, "value noise: bias must be in [0, 1], got %g",
                            (double)p->bias);
    if (!(p->gain >= 0.0f && p->gain <= 1.0f))
        return ss_error_set(err, SS_ERR_INPUT, "value noise: gain must be in [0, 1], got %g",
                            (double)p->gain);
    return SS_OK;
}

/* Amplitudes of Alg. 3.2 lines 4-8, in loop order (oct = octaves .. 0). */
static float amplitudes(const ss_noise_params *p, float *amp) {
    float amplitude = 1.0f, total = 0.0f;
    for (int j = 0; j <= p->octaves; j++) {
        amplitude = amplitude * p->persistence;
        total = total + amplitude;
        amp[j] = amplitude;
    }
    return total;
}

/* Eq. 3.2/3.3 with a true modulo for x0. */
static void positions(int x1, int period, int size, int *x) {
    x[1] = x1;
    x[0] = x1 >= period ? x1 - period : (int)((((long)x1 - period) % size + size) % size);
    x[2] = (int)(((long)x1 + period) % size);
    x[3] = (int)(((long)x[2] + period) % size);
}

ss_status ss_value_noise_reference(const ss_noise_params *p, uint64_t seed, uint64_t stream,
                                   ss_image *out, ss_error *err) {
    ss_status st = check_params(p, out, err);
    if (st) return st;
    const int w = out->width, h = out->height;
    float *base = malloc(sizeof *base * (size_t)w * h); /* line 2 */
    if (!base) return ss_error_set(err, SS_ERR_NOMEM, "value noise: out of memory (%dx%d)", w, h);
    ss_rng_fill_f32(seed, stream, 0, base, (size_t)w * h); /* line 3 */
    float *T = out->data;
    memset(T, 0, sizeof *T * (size_t)w * h);
    float amplitude = 1.0f, totalAmplitude = 0.0f; /* lines 4-5 */
    for (int oct = p->octaves; oct >= 0; oct--) {  /* line 6 */
        amplitude = amplitude * p->persistence;
        totalAmplitude = totalAmplitude + amplitude;
        const int period = 1 << oct;
        const float frequency = 1.0f / (float)period;
        for (int py = 0; py < h; py++)
            for (int px = 0; px < w; px++) {
                int ys[4], xs[4];
                positions(py / period * period, period, h, ys);
                const float vertBlend = (float)(py - ys[1]) * frequency;
                positions(px / period * period, period, w, xs);
                const float horBlend = (float)(px - xs[1]) * frequency;
                float row[4];
                for (int k = 0; k < 4; k++) {
                    const float *b = base + (size_t)ys[k] * w;
                    row[k] = cubic(b[xs[0]], b[xs[1]], b[xs[2]], b[xs[3]], horBlend);
                }
                T[(size_t)py * w + px] +=
                    cubic(row[0], row[1], row[2], row[3], vertBlend) * amplitude;
            }
    }
    finish(T, (size_t)w * h, totalAmplitude, p->bias, p->gain); /* lines 20-22 */
    free(base);
    return SS_OK;
}

/* Per-axis sampling table of one octave: 4 lattice indices and a blend per
 * output coordinate. */
static void axis_table(int n, int lattice, double stretch, int period, int *idx, float *blend) {
    const float frequency = 1.0f / (float)period;
    const double den = (double)n * stretch;
    for (int i = 0; i < n; i++) {
        double u = ((double)i * lattice) / den;
        if (u >= lattice) u = fmod(u, (double)lattice);
        const int x1 = (int)(u / period) * period;
        positions(x1, period, lattice, idx + 4 * i);
        blend[i] = (float)(u - x1) * frequency;
    }
}

#define BAND 32

/* o[x] += Eq. 3.4 of four buffered rows, times the amplitude (vectorises). */
static void vertical(float *restrict o, const float *restrict h0, const float *restrict h1,
                     const float *restrict h2, const float *restrict h3, float vb, float a, int W) {
#pragma omp simd
    for (int x = 0; x < W; x++) o[x] += cubic(h0[x], h1[x], h2[x], h3[x], vb) * a;
}

/* One lattice row's horizontal cubics for every output column. */
static void horizontal(float *restrict o, const float *restrict L, const int *restrict ci,
                       const float *restrict hb, int W) {
    for (int x = 0; x < W; x++) {
        const int *c = ci + 4 * x;
        o[x] = cubic(L[c[0]], L[c[1]], L[c[2]], L[c[3]], hb[x]);
    }
}

/* The fast generator over the rectangle (rx, ry, rw, rh) of a W x H texture:
 * out (rw x rh, row-major) gets exactly the values the full texture has
 * there. Only the lattice rows the rectangle samples are drawn. */
static ss_status noise_rect(const ss_noise_params *p, uint64_t seed, uint64_t stream, int W, int H,
                            int rx, int ry, int rw, int rh, float *out, ss_error *err) {
    if (!(p->stretch_x > 0.0f) || !isfinite(p->stretch_x) || !(p->stretch_y > 0.0f) ||
        !isfinite(p->stretch_y))
        return ss_error_set(err, SS_ERR_INPUT, "value noise: stretch must be > 0, got %g x %g",
                            (double)p->stretch_x, (double)p->stretch_y);
    if (!(p->cell_px > 0.0f) || !isfinite(p->cell_px))
        return ss_error_set(err, SS_ERR_INPUT, "value noise: cell_px must be > 0, got %g",
                            (double)p->cell_px);
    if (rx < 0 || ry < 0 || rw < 1 || rh < 1 || rx + rw > W || ry + rh > H)
        return ss_error_set(err, SS_ERR_INPUT, "value noise: rectangle outside the %dx%d texture",
                            W, H);
    const double lwd = fmax(1.0, round(W / (double)p->cell_px));
    const double lhd = fmax(1.0, round(H / (double)p->cell_px));
    if (lwd * lhd > (double)(1 << 26))
        return ss_error_set(err, SS_ERR_INPUT,
                            "value noise: cell_px %g gives a %.0f x %.0f lattice (too large)",
                            (double)p->cell_px, lwd, lhd);
    const int LW = (int)lwd, LH = (int)lhd, no = p->octaves + 1;
    float amp[MAX_OCTAVES + 1];
    const float total = amplitudes(p, amp);
    ss_status st = SS_OK;

    float *lat = malloc(sizeof *lat * (size_t)LW * LH);
    unsigned char *needed = calloc((size_t)LH, 1);
    int *cidx = malloc(sizeof *cidx * 4 * (size_t)W * no),
        *ridx = malloc(sizeof *ridx * 4 * (size_t)H * no);
    float *cb = malloc(sizeof *cb * (size_t)W * no), *rb = malloc(sizeof *rb * (size_t)H * no);
    if (!lat || !needed || !cidx || !ridx || !cb || !rb) {
        st = ss_error_set(err, SS_ERR_NOMEM, "value noise: out of memory (%dx%d)", W, H);
        goto done;
    }
    for (int j = 0; j < no; j++) {
        const int period = 1 << (p->octaves - j);
        axis_table(W, LW, p->stretch_x, period, cidx + 4 * (size_t)W * j, cb + (size_t)W * j);
        axis_table(H, LH, p->stretch_y, period, ridx + 4 * (size_t)H * j, rb + (size_t)H * j);
        for (int y = ry; y < ry + rh; y++)
            for (int k = 0; k < 4; k++) needed[ridx[4 * ((size_t)H * j + y) + k]] = 1;
    }
    /* Alg. 3.2 line 3, for the lattice rows this rectangle reads. */
    for (int r = 0; r < LH; r++)
        if (needed[r])
            ss_rng_fill_f32(seed, stream, (uint64_t)r * LW, lat + (size_t)r * LW, (size_t)LW);
    const int nbands = (rh + BAND - 1) / BAND;
    int fail = 0;
#pragma omp parallel
    {
        float *buf = malloc(sizeof *buf * (size_t)4 * BAND * rw);
        int *slot = malloc(sizeof *slot * (size_t)LH);
        int rows[4 * BAND];
        if (!buf || !slot) {
#pragma omp atomic write
            fail = 1;
        } else {
            for (int i = 0; i < LH; i++) slot[i] = -1;
        }
#pragma omp for schedule(dynamic, 1)
        for (int band = 0; band < nbands; band++) {
            if (!buf || !slot) continue;
            const int y0 = ry + band * BAND, y1 = y0 + BAND < ry + rh ? y0 + BAND : ry + rh;
            float *ob = out + (size_t)(y0 - ry) * rw;
            memset(ob, 0, sizeof(float) * (size_t)rw * (size_t)(y1 - y0));
            for (int j = 0; j < no; j++) {
                const int *ci = cidx + 4 * ((size_t)W * j + rx), *ri = ridx + 4 * (size_t)H * j;
                const float *hb = cb + (size_t)W * j + rx, *vbl = rb + (size_t)H * j;
                int ns = 0;
                /* Horizontal cubics of the lattice rows this band needs. */
                for (int y = y0; y < y1; y++)
                    for (int k = 0; k < 4; k++) {
                        const int r = ri[4 * y + k];
                        if (slot[r] >= 0) continue;
                        slot[r] = ns;
                        rows[ns] = r;
                        horizontal(buf + (size_t)ns * rw, lat + (size_t)r * LW, ci, hb, rw);
                        ns++;
                    }
                /* Vertical cubic, times the amplitude, summed. */
                const float a = amp[j];
                for (int y = y0; y < y1; y++) {
                    const float *h0 = buf + (size_t)slot[ri[4 * y]] * rw;
                    const float *h1 = buf + (size_t)slot[ri[4 * y + 1]] * rw;
                    const float *h2 = buf + (size_t)slot[ri[4 * y + 2]] * rw;
                    const float *h3 = buf + (size_t)slot[ri[4 * y + 3]] * rw;
                    vertical(ob + (size_t)(y - y0) * rw, h0, h1, h2, h3, vbl[y], a, rw);
                }
                for (int s = 0; s < ns; s++) slot[rows[s]] = -1;
            }
            finish(ob, (size_t)(y1 - y0) * rw, total, p->bias, p->gain);
        }
        free(buf);
        free(slot);
    }
    if (fail) st = ss_error_set(err, SS_ERR_NOMEM, "value noise: out of memory");
done:
    free(lat);
    free(needed);
    free(cidx);
    free(ridx);
    free(cb);
    free(rb);
    return st;
}

ss_status ss_value_noise(const ss_noise_params *p, uint64_t seed, uint64_t stream, ss_image *out,
                         ss_error *err) {
    ss_status st = check_params(p, out, err);
    if (st) return st;
    return noise_rect(p, seed, stream, out->width, out->height, 0, 0, out->width, out->height,
                      out->data, err);
}

ss_status ss_value_noise_rect(const ss_noise_params *p, uint64_t seed, uint64_t stream, int width,
                              int height, int x0, int y0, ss_image *out, ss_error *err) {
    ss_status st = check_params(p, out, err);
    if (st) return st;
    return noise_rect(p, seed, stream, width, height, x0, y0, out->width, out->height, out->data,
                      err);
}
