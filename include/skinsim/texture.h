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

/* Eq. 3.6 and 3.7. bias(v,0.5) = v and gain(v,0.5) = v. */
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

/* Fills the single-channel image out with value noise keyed by (seed, stream).
 * Tileable: the base grid wraps, so out tiles seamlessly when its size is a
 * multiple of cell_px * 2^octaves. Bit-identical for any thread count. */
ss_status ss_value_noise(const ss_noise_params *p, uint64_t seed, uint64_t stream,
                         ss_image *out, ss_error *err);
/* Direct transcription of Alg. 3.2 (no stretch, cell_px 1), for tests. */
ss_status ss_value_noise_reference(const ss_noise_params *p, uint64_t seed, uint64_t stream,
                                   ss_image *out, ss_error *err);

/* Per-pixel kernel widths for erosion: random m in [min_w, max_w] made odd by
 * Eq. 3.1 (m + m mod 2 + 1). widths holds width*height ints. */
void ss_erosion_widths(int width, int height, int min_w, int max_w, uint64_t seed,
                       uint64_t stream, int *widths);
/* Alg. 3.1: horizontal N x 1 min filter with per-pixel widths; outside the
 * texture counts as the highest value (ignored). src and dst 1 channel. */
void ss_erode(const ss_image *src, const int *widths, ss_image *dst);
void ss_erode_reference(const ss_image *src, const int *widths, ss_image *dst);

/* Alg. 3.4: gradient of thickness t pixels around the outline, drawn inside
 * (render_inside = 1, where shape is white) or outside. dist: distance from
 * each pixel to the outline (ss_outline_distance). Writes a 0..1 lerp weight
 * per pixel: lerp = dist/t where drawn and dist <= t, else -1 (not drawn), so
 * the caller composes colours as the seed does. */
void ss_gradient_edge(const ss_image *shape, const ss_image *dist, float thickness,
                      int render_inside, ss_image *lerp_out);

/* Height (1 channel, in world units per pixel scaled by strength) to a
 * tangent-space normal map, OpenGL convention (+Y up), RGB in 0..1. Central
 * differences with wrap-around. */
void ss_height_to_normal(const ss_image *height, float strength, ss_image *normal_rgb);

#ifdef __cplusplus
}
#endif
#endif
