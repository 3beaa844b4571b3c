/* Gradient edges around a shape (seed 000 §3.3.3, Alg. 3.4) and height to
 * normal map conversion.
 *
 * ss_gradient_edge follows Alg. 3.4 with the colour lerp left to the caller:
 * pixels on the wrong side of the shape (shape value <= 0.5 counts as
 * black) or farther than the thickness get -1, the others dist / thickness
 * in [0, 1]. The distance comes from ss_outline_distance (Alg. 3.3 per edge)
 * so this loop is O(pixels). thickness <= 0 draws nothing.
 *
 * ss_height_to_normal: central differences with wrap-around, in the OpenGL
 * (+Y up) tangent convention. Image rows grow downwards, so with
 * gx = (h[x+1] - h[x-1]) / 2 and gy = (h[y+1] - h[y-1]) / 2 (image rows),
 * n = normalize(-s*gx, +s*gy, 1): a height rising to the right tilts the
 * normal to -X (red < 0.5), a height rising towards row 0 (up in the
 * picture) tilts it to -Y (green < 0.5). RGB = n * 0.5 + 0.5. */
#include "skinsim/texture.h"

#include <math.h>
#include <omp.h>

void ss_gradient_edge(const ss_image *shape, const ss_image *dist, float thickness,
                      int render_inside, ss_image *lerp_out) {
    if (!shape || !dist || !lerp_out || !shape->data || !dist->data || !lerp_out->data) return;
    const int W = lerp_out->width, H = lerp_out->height;
    if (shape->width != W || shape->height != H || dist->width != W || dist->height != H) return;
    const int Cs = shape->channels, Cd = dist->channels, Co = lerp_out->channels;
#pragma omp parallel for schedule(static)
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const size_t i = (size_t)y * W + x;
            const float v = ss_gradient_weight(shape->data[i * Cs] > 0.5f, dist->data[i * Cd],
                                               thickness, render_inside);
            for (int c = 0; c < Co; c++) lerp_out->data[i * Co + c] = v;
        }
}

void ss_height_to_normal(const ss_image *height, float strength, ss_image *normal_rgb) {
    if (!height || !normal_rgb || !height->data || !normal_rgb->data) return;
    const int W = height->width, H = height->height, C = height->channels,
              Co = normal_rgb->channels;
    if (normal_rgb->width != W || normal_rgb->height != H || Co < 3) return;
#pragma omp parallel for schedule(static)
    for (int y = 0; y < H; y++) {
        const int yu = (y + H - 1) % H, yd = (y + 1) % H;
        for (int x = 0; x < W; x++) {
            const int xl = (x + W - 1) % W, xr = (x + 1) % W;
            const float gx =
                (height->data[((size_t)y * W + xr) * C] - height->data[((size_t)y * W + xl) * C]) *
                0.5f;
            const float gy =
                (height->data[((size_t)yd * W + x) * C] - height->data[((size_t)yu * W + x) * C]) *
                0.5f;
            float nx = -strength * gx, ny = strength * gy, nz = 1.0f;
            const float len = sqrtf(nx * nx + ny * ny + nz * nz);
            float *o = normal_rgb->data + ((size_t)y * W + x) * Co;
            o[0] = nx / len * 0.5f + 0.5f;
            o[1] = ny / len * 0.5f + 0.5f;
            o[2] = nz / len * 0.5f + 0.5f;
            if (Co > 3) o[3] = 1.0f;
        }
    }
}
