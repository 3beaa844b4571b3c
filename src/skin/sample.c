/* Probability fields (seed 003 §5.1): drawing feature centres from a
 * greyscale image. Two samplers draw the same distribution, a density that
 * is constant inside each texel and proportional to the texel value raised
 * to `power`:
 *   - the seed's ChoosePoint: uniform (x, y) and rho until rho < T(x, y)
 *     (strictly less, so a black texel can never be chosen; the seed's <=
 *     would accept a black texel when rho is exactly 0), with rho uniform
 *     in [0, max T) rather than [0, 1): the same distribution, without
 *     1 / max T times more tries for a dark field;
 *   - an alias table (Vose 1991) over the texels, then a uniform position
 *     inside the chosen texel: O(1) per point whatever the field, where the
 *     rejection loop needs 1 / mean(T) tries per point.
 * Point k depends only on (seed, stream, k), so any thread count gives the
 * same points; tests compare the two samplers with a chi-square test. */
#include "skinsim/skin.h"

#include <math.h>
#include <stdlib.h>

/* Field value at texel i raised to power, 0 for non-positive values. */
static double texel_weight(const ss_image *f, size_t i, double power) {
    double v = f->data[i * (size_t)f->channels];
    if (!(v > 0.0)) return 0.0;
    if (v > 1.0) v = 1.0;
    return power == 1.0 ? v : pow(v, power);
}

static ss_status check_field(const ss_image *f, double power, double *total, ss_error *err) {
    if (!f || !f->data || f->width <= 0 || f->height <= 0)
        return ss_error_set(err, SS_ERR_INPUT, "probability field: empty image");
    if (!(power > 0.0) || !isfinite(power))
        return ss_error_set(err, SS_ERR_INPUT, "probability field: power %g must be > 0", power);
    size_t n = (size_t)f->width * (size_t)f->height;
    double s = 0.0;
    for (size_t i = 0; i < n; i++) {
        float v = f->data[i * (size_t)f->channels];
        if (!isfinite(v))
            return ss_error_set(err, SS_ERR_INPUT,
                                "probability field: texel (%zu, %zu) is not a finite number",
                                i % (size_t)f->width, i / (size_t)f->width);
        s += texel_weight(f, i, power);
    }
    if (!(s > 0.0))
        return ss_error_set(err, SS_ERR_INPUT, "probability field is all black (no features)");
    *total = s;
    return SS_OK;
}

/* 53-bit uniform from two 32-bit words. */
static double u53(uint32_t a, uint32_t b) {
    return (double)(((uint64_t)a << 21) ^ (uint64_t)(b >> 11)) * 0x1p-53;
}

static ss_status sample_alias(const ss_image *f, double power, double total, uint64_t seed,
                              uint64_t stream, size_t n, double *xy, ss_error *err) {
    size_t N = (size_t)f->width * (size_t)f->height;
    double *prob = malloc(N * sizeof *prob);
    size_t *alias = malloc(N * sizeof *alias), *small = malloc(N * sizeof *small),
           *large = malloc(N * sizeof *large);
    if (!prob || !alias || !small || !large) {
        free(prob), free(alias), free(small), free(large);
        return ss_error_set(err, SS_ERR_NOMEM, "probability field: out of memory (alias table)");
    }
    size_t ns = 0, nl = 0;
    for (size_t i = 0; i < N; i++) {
        prob[i] = texel_weight(f, i, power) * (double)N / total;
        alias[i] = i;
        if (prob[i] < 1.0)
            small[ns++] = i;
        else
            large[nl++] = i;
    }
    while (ns && nl) {
        size_t s = small[--ns], l = large[nl - 1];
        alias[s] = l;
        prob[l] -= 1.0 - prob[s];
        if (prob[l] < 1.0) {
            nl--;
            small[ns++] = l;
        }
    }
    while (nl) prob[large[--nl]] = 1.0;
    /* rounding leftovers among the small ones: keep them only if positive */
    while (ns) {
        size_t s = small[--ns];
        prob[s] = prob[s] > 0.0 ? 1.0 : 0.0;
    }
    free(small), free(large);
    const int W = f->width, H = f->height;
#pragma omp parallel for schedule(static)
    for (size_t k = 0; k < n; k++) {
        uint32_t r[4], q[4];
        ss_rng4(seed, stream, 2 * (uint64_t)k, r);
        ss_rng4(seed, stream, 2 * (uint64_t)k + 1, q);
        double u = u53(r[0], r[1]) * (double)N;
        size_t col = (size_t)u;
        if (col >= N) col = N - 1;
        double acc = u53(r[2], r[3]);
        size_t i = acc < prob[col] ? col : alias[col];
        double jx = u53(q[0], q[1]), jy = u53(q[2], q[3]);
        xy[2 * k] = ((double)(i % (size_t)W) + jx) / W;
        xy[2 * k + 1] = ((double)(i / (size_t)W) + jy) / H;
    }
    free(prob), free(alias);
    return SS_OK;
}

static ss_status sample_rejection(const ss_image *f, double power, uint64_t seed, uint64_t stream,
                                  size_t n, double *xy, ss_error *err) {
    const int W = f->width, H = f->height;
    int failed = 0;
    /* rho uniform in [0, max T) instead of [0, 1): the same distribution
     * (any bound >= max T is), and a dark field does not take 1 / max T
     * times longer */
    double tmax = 0.0;
    for (size_t i = 0; i < (size_t)W * (size_t)H; i++) tmax = fmax(tmax, texel_weight(f, i, power));
#pragma omp parallel for schedule(dynamic, 256)
    for (size_t k = 0; k < n; k++) {
        ss_rng_seq r;
        ss_rng_seq_init(&r, seed, (stream << 40) ^ (uint64_t)k);
        for (long it = 0;; it++) {
            if (it > 100000000L) { /* the field's values are too small to accept */
#pragma omp atomic write
                failed = 1;
                break;
            }
            double x = ss_rng_seq_uniform(&r), y = ss_rng_seq_uniform(&r),
                   rho = ss_rng_seq_uniform(&r);
            int tx = (int)(x * W), ty = (int)(y * H);
            if (tx >= W) tx = W - 1;
            if (ty >= H) ty = H - 1;
            if (rho * tmax < texel_weight(f, (size_t)ty * W + tx, power)) {
                xy[2 * k] = x;
                xy[2 * k + 1] = y;
                break;
            }
        }
    }
    if (failed)
        return ss_error_set(err, SS_ERR_INPUT,
                            "probability field: rejection sampling gave up after 1e8 tries "
                            "(field too dark; use the alias sampler)");
    return SS_OK;
}

ss_status ss_skin_sample_points(const ss_image *field, double power, int sampler, uint64_t seed,
                                uint64_t stream, size_t n, double *xy, ss_error *err) {
    double total = 0.0;
    ss_status st = check_field(field, power, &total, err);
    if (st || n == 0) return st;
    if (sampler == SS_SAMPLER_REJECTION)
        return sample_rejection(field, power, seed, stream, n, xy, err);
    return sample_alias(field, power, total, seed, stream, n, xy, err);
}
