/* Baseline mottling defined in millimetres (docs/skin.md): multi-scale
 * fractal (fBm) value noise whose octaves have physical wavelengths, from
 * the finest skin pigment and capillary structure (0.1-0.2 mm) to patches of
 * centimetres, as the melanin and haemoglobin chromophore maps of Tsumura
 * et al. 2003 ("Image-based skin color and texture analysis/synthesis by
 * extracting hemoglobin and melanin information in the skin", SIGGRAPH)
 * show. It replaces the seed's per-texel uniform noise (§5.3.1), whose size
 * changed with the texture's resolution.
 *
 * Design: every octave is a periodic lattice (the texture is a torus) with
 * round(world / wavelength) points per side, its values drawn once from the
 * counter-based generator keyed by (seed, stream 200 + octave, point), all
 * eight fields (six optical parameters, height, sebum) interleaved per point,
 * so a texel costs per octave one set of quintic weights and 4 contiguous
 * loads of 8 floats. The same world position gives the same value at any
 * --size: octaves finer than 2 texels would alias and are dropped (faded out
 * over 2-4 texels); the normalisation counts all octaves, so what remains
 * keeps its amplitude and the statistics over mm-sized cells agree between
 * sizes (tested). What it gave up: value noise has a little more lattice
 * structure than gradient noise; at 8 fields the cost matters more. */
#include "skin_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Per field: the spectral exponent of its octave amplitudes (amplitude of
 * an octave of wavelength L proportional to L^beta): melanin has much of its
 * variation at the small scales (pigment spots), blood at the large ones
 * (erythema, vascular patches); the thicknesses and sebum vary slowly. */
static const float BETA[MOTTLE_F] = {0.35f, 0.7f, 0.6f, 0.9f, 0.8f, 0.8f, 0.5f, 0.6f};
/* 1 / sd of quintic-interpolated value noise with uniform [-1, 1] lattice
 * values (measured over 10^6 positions: 0.466) */
#define VALUE_NOISE_INV_SD 2.146f

void skin_mottle_free(skin_mottle *m) {
    if (!m) return;
    for (int k = 0; k < MOTTLE_OCT; k++) free(m->lat[k]);
    memset(m, 0, sizeof *m);
}

ss_status skin_mottle_init(skin_mottle *m, const ss_skin_settings *s, ss_error *err) {
    memset(m, 0, sizeof *m);
    const double world = s->world_size_cm * 10.0, texel = world / s->size;
    double lmax = s->dist.mottle_max_mm, lmin = s->dist.mottle_min_mm;
    if (lmax > world) lmax = world;
    if (lmin > lmax) lmin = lmax;
    double norm[MOTTLE_F] = {0};
    int k = 0;
    for (double L = lmax; L >= lmin * 0.999 && k < MOTTLE_OCT; L *= 0.5, k++) {
        for (int f = 0; f < MOTTLE_F; f++) {
            double a = pow(L, BETA[f]);
            norm[f] += a * a;
            double fade = (L / texel - 2.0) / 2.0;
            fade = fade < 0 ? 0 : fade > 1 ? 1 : fade;
            m->w[k][f] = (float)(a * fade);
        }
        long n = lround(world / L);
        m->n[k] = (int)(n < 1 ? 1 : n);
    }
    m->noct = k;
    for (int o = 0; o < m->noct; o++) {
        for (int f = 0; f < MOTTLE_F; f++)
            m->w[o][f] *= (float)(VALUE_NOISE_INV_SD / sqrt(norm[f] > 0 ? norm[f] : 1.0));
        int used = 0;
        for (int f = 0; f < MOTTLE_F; f++) used |= m->w[o][f] != 0.0f;
        if (!used) continue; /* dropped: too fine for this size */
        const size_t np = (size_t)m->n[o] * (size_t)m->n[o];
        m->lat[o] = malloc(np * MOTTLE_F * sizeof(float));
        if (!m->lat[o]) {
            skin_mottle_free(m);
            return ss_error_set(err, SS_ERR_NOMEM, "baseline mottling: out of memory");
        }
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < np * MOTTLE_F / 4; i++) {
            uint32_t r[4];
            ss_rng4(s->seed, 200 + (uint64_t)o, i, r);
            for (int j = 0; j < 4; j++) m->lat[o][i * 4 + j] = (float)(r[j] >> 8) * 0x1p-23f - 1.0f;
        }
    }
    return SS_OK;
}

static inline float quintic(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }

void skin_mottle_eval(const skin_mottle *m, double u, double v, float out[MOTTLE_F]) {
    /* a local accumulator and restrict pointers: the field loop has no
     * aliasing to check, so the compiler runs the 8 fields as one vector
     * (same operations per field, same bits as the scalar loop) */
    float acc[MOTTLE_F] = {0};
    for (int o = 0; o < m->noct; o++) {
        if (!m->lat[o]) continue;
        const int n = m->n[o];
        double X = u * n, Y = v * n;
        double fx0 = floor(X), fy0 = floor(Y);
        /* texel centres give 0 <= X, Y < n: no division (two per octave
         * were a third of the cost); any other position wraps */
        int ix = (int)fx0, iy = (int)fy0;
        if (ix < 0 || ix >= n) ix = ((ix % n) + n) % n;
        if (iy < 0 || iy >= n) iy = ((iy % n) + n) % n;
        const int ix1 = ix + 1 == n ? 0 : ix + 1, iy1 = iy + 1 == n ? 0 : iy + 1;
        const float sx = quintic((float)(X - fx0)), sy = quintic((float)(Y - fy0));
        const float *restrict a = m->lat[o] + ((size_t)iy * n + ix) * MOTTLE_F;
        const float *restrict b = m->lat[o] + ((size_t)iy * n + ix1) * MOTTLE_F;
        const float *restrict c = m->lat[o] + ((size_t)iy1 * n + ix) * MOTTLE_F;
        const float *restrict d = m->lat[o] + ((size_t)iy1 * n + ix1) * MOTTLE_F;
        const float *restrict w = m->w[o];
        for (int f = 0; f < MOTTLE_F; f++) {
            float top = a[f] + sx * (b[f] - a[f]), bot = c[f] + sx * (d[f] - c[f]);
            acc[f] += w[f] * (top + sy * (bot - top));
        }
    }
    for (int f = 0; f < MOTTLE_F; f++) out[f] = acc[f];
}
