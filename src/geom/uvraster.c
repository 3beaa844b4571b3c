/* The UV triangle rasteriser shared by everything that bakes into a mesh's
 * UV layout (seed 001 §5.4's fields mapped back onto the mesh; UV padding):
 * for every triangle, in file order, every texel whose centre lies in it,
 * with its barycentric coordinates.
 *
 * Design: a bounding box per triangle clamped to the texture, and the
 * barycentric test of the texel centre (x + 0.5, y + 0.5) in texel units,
 * with a 1e-9 tolerance so texels on a shared edge belong to both triangles
 * (no cracks between them; the later triangle is called last). Degenerate
 * (|det| < 1e-12 texel^2) and non-finite triangles are skipped. One thread:
 * callers write per texel, and the file order decides overlaps. Gave up:
 * conservative rasterisation (a sliver narrower than a texel may cover no
 * texel centre) and a top-left fill rule (shared edges are visited twice). */
#include "skinsim/mesh.h"

#include <math.h>

void ss_uv_triangle_raster(const ss_mesh *m, int width, int height, ss_uv_texel_fn fn, void *ctx) {
    for (int t = 0; t < m->ntriangles; t++) {
        double U[3][2];
        for (int k = 0; k < 3; k++) {
            uint32_t vi = m->indices[3 * t + k];
            U[k][0] = (double)m->uvs[2 * vi] * width;
            U[k][1] = (double)m->uvs[2 * vi + 1] * height;
        }
        double det =
            (U[1][0] - U[0][0]) * (U[2][1] - U[0][1]) - (U[2][0] - U[0][0]) * (U[1][1] - U[0][1]);
        if (!(fabs(det) >= 1e-12)) continue; /* degenerate, or NaN */
        double fx0 = floor(fmin(U[0][0], fmin(U[1][0], U[2][0]))),
               fx1 = ceil(fmax(U[0][0], fmax(U[1][0], U[2][0]))),
               fy0 = floor(fmin(U[0][1], fmin(U[1][1], U[2][1]))),
               fy1 = ceil(fmax(U[0][1], fmax(U[1][1], U[2][1])));
        if (!isfinite(fx0) || !isfinite(fx1) || !isfinite(fy0) || !isfinite(fy1)) continue;
        int x0 = fx0 < 0 ? 0 : (int)fmin(fx0, width - 1.0),
            y0 = fy0 < 0 ? 0 : (int)fmin(fy0, height - 1.0);
        int x1 = fx1 > width - 1.0 ? width - 1 : (int)fmax(fx1, 0.0),
            y1 = fy1 > height - 1.0 ? height - 1 : (int)fmax(fy1, 0.0);
        for (int y = y0; y <= y1; y++)
            for (int x = x0; x <= x1; x++) {
                double px = x + 0.5, py = y + 0.5;
                double b1 = ((px - U[0][0]) * (U[2][1] - U[0][1]) -
                             (U[2][0] - U[0][0]) * (py - U[0][1])) /
                            det,
                       b2 = ((U[1][0] - U[0][0]) * (py - U[0][1]) -
                             (px - U[0][0]) * (U[1][1] - U[0][1])) /
                            det,
                       b0 = 1 - b1 - b2;
                if (b0 < -1e-9 || b1 < -1e-9 || b2 < -1e-9) continue;
                fn(x, y, t, b0, b1, b2, ctx);
            }
    }
}
