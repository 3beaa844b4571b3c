/* skinsim texture: the key-position techniques of seed 000 §3.3: shape erosion
 * with per-pixel odd kernel widths (Eq. 3.1, Alg. 3.1), value noise with
 * wrap-around bicubic octaves, bias and gain (Eq. 3.2-3.7, Alg. 3.2), gradient
 * edges around a hull (Alg. 3.4), and height-to-normal conversion. */
#ifndef SKINSIM_TEXTURE_H
#define SKINSIM_TEXTURE_H

#include "skinsim/core.h"
#include "skinsim/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Eq. 3.6 and 3.7. bias(v,0.5) = v and gain(v,0.5) = v.
 * Eq. 3.6 as printed (v / ((1/b)(1-v) + 1)) is not the identity at b = 0.5;
 * we use the Schlick rational bias it abbreviates, v / ((1/b - 2)(1-v) + 1)
 * (b > 0.5 brightens). ss_gain is Eq. 3.7 as printed on that bias: note
 * that g > 0.5 then pulls values towards 0.5 (less contrast), i.e. it is
 * Schlick's/Perlin's gain(v, 1 - g). Inputs outside [0,1] clamp to 0 / 1. */
float ss_bias(float v, float b);
float ss_gain(float v, float g);

/* Value noise parameters (Alg. 3.2). octaves: the loop runs oct = octaves
 * down to 0, so octaves+1 octaves with period 2^oct pixels of the base grid.
 * stretch_x/stretch_y scale the pattern along an axis (seed §4.3.2 uses a
 * 6400% y-scale: stretch_y = 64). cell_px: size in output pixels of one base
 * noise cell (1 = the seed's "base noise has the size of the output"); larger
 * values keep the look the same at higher resolutions. */
typedef struct ss_noise_params {
    int octaves;
    float persistence, bias, gain;
    float stretch_x, stretch_y;
    float cell_px;
} ss_noise_params;
void ss_noise_params_default(ss_noise_params *p); /* 5, 0.5, 0.5, 0.5, 1, 1, 1 */
/* Valid: octaves 0..24, persistence > 0, bias and gain in [0, 1], stretch and
 * cell_px > 0 (else SS_ERR_INPUT). The normalised sum is clamped to [0, 1]
 * before bias and gain (Eq. 3.4's cubic can overshoot slightly). */

/* Fills the single-channel image out with value noise keyed by (seed, stream).
 * Tileable: the base grid wraps, so out tiles seamlessly when its size is a
 * multiple of cell_px * 2^octaves. Bit-identical for any thread count.
 * The lattice has round(size / cell_px) points per axis (value k drawn with
 * ss_rng_uniform(seed, stream, ly * lattice_w + lx)); pixel p samples
 * lattice coordinate p * lattice / (size * stretch), wrapped. So doubling
 * the image size and cell_px reproduces the same pattern (pixel 2p equals
 * pixel p of the smaller image), and with stretch 1, cell_px 1 the result
 * equals ss_value_noise_reference bit for bit. */
ss_status ss_value_noise(const ss_noise_params *p, uint64_t seed, uint64_t stream, ss_image *out,
                         ss_error *err);
/* The rectangle of a width x height noise texture whose top-left pixel is
 * (x0, y0) and whose size is out's: exactly the values ss_value_noise gives
 * there, at a cost proportional to the rectangle (a wound needs noise only
 * where it is). */
ss_status ss_value_noise_rect(const ss_noise_params *p, uint64_t seed, uint64_t stream, int width,
                              int height, int x0, int y0, ss_image *out, ss_error *err);
/* Direct transcription of Alg. 3.2 (no stretch, cell_px 1), for tests.
 * p->stretch_* and p->cell_px are ignored. O(octaves * 32) per pixel. */
ss_status ss_value_noise_reference(const ss_noise_params *p, uint64_t seed, uint64_t stream,
                                   ss_image *out, ss_error *err);

/* Per-pixel kernel widths for erosion: random m in [min_w, max_w] made odd by
 * Eq. 3.1 (m + m mod 2 + 1). widths holds width*height ints. m for pixel i
 * comes from ss_rng_u32(seed, stream, i); min_w < 0 counts as 0, max_w <
 * min_w as min_w. */
void ss_erosion_widths(int width, int height, int min_w, int max_w, uint64_t seed, uint64_t stream,
                       int *widths);
/* The widths of the w x h rectangle at (x0, y0) of a width x height
 * texture: the same values ss_erosion_widths gives there (widths holds w*h). */
void ss_erosion_widths_rect(int width, int height, int x0, int y0, int w, int h, int min_w,
                            int max_w, uint64_t seed, uint64_t stream, int *widths);
/* Alg. 3.1: horizontal N x 1 min filter with per-pixel widths; outside the
 * texture counts as the highest value (ignored). src and dst 1 channel.
 * (More channels are eroded independently; src and dst must have the same
 * shape or nothing is written.) The window of width N is x - N/2 .. x + N/2.
 * ss_erode is O(1) per pixel (sparse table) and may run in place; the
 * reference is the literal O(N) loop and must not. Both agree bit for bit. */
void ss_erode(const ss_image *src, const int *widths, ss_image *dst);
void ss_erode_reference(const ss_image *src, const int *widths, ss_image *dst);

/* Alg. 3.4: gradient of thickness t pixels around the outline, drawn inside
 * (render_inside = 1, where shape is white) or outside. dist: distance from
 * each pixel to the outline (ss_outline_distance). Writes a 0..1 lerp weight
 * per pixel: lerp = dist/t where drawn and dist <= t, else -1 (not drawn), so
 * the caller composes colours as the seed does. */
void ss_gradient_edge(const ss_image *shape, const ss_image *dist, float thickness,
                      int render_inside, ss_image *lerp_out);
/* The same weight for one pixel (in_shape: the shape is white there), for
 * renderers that draw the gradient while they compose colours. */
static inline float ss_gradient_weight(int in_shape, float dist, float thickness,
                                       int render_inside) {
    if ((render_inside ? !in_shape : in_shape) || !(thickness > 0.0f) || !(dist <= thickness))
        return -1.0f;
    return dist / thickness;
}
/* (thickness <= 0 draws nothing: all -1. Shape value > 0.5 is white.) */

/* Height (1 channel, in world units per pixel scaled by strength) to a
 * tangent-space normal map, OpenGL convention (+Y up), RGB in 0..1. Central
 * differences with wrap-around. n = normalize(-s dh/dx, +s dh/drow, 1) with
 * rows growing downwards: height rising to the right gives red < 0.5, rising
 * towards row 0 gives green < 0.5. normal_rgb: 3 channels (or 4, alpha 1). */
void ss_height_to_normal(const ss_image *height, float strength, ss_image *normal_rgb);

#ifdef __cplusplus
}
#endif
#endif
