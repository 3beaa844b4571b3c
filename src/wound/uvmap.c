/* Textures in a mesh's UV space (seed 001 §5.4: "we map the simulated fields
 * back onto the ... mesh"): for a heal run on a real body (skinsim/shell.h),
 * every texel of the mesh's UV layout is traced to the point of the
 * undeformed skin surface it shows (the UV triangle holding the texel centre,
 * barycentric in 3D), that point is put into the healing patch's frame, and
 * the texel samples the tissue column under it. Texels whose point lies
 * outside the patch (or in its outer two columns, the boundary layer), or on another sheet of skin
 * than the column's surface (the far side of a finger: the point is more than SHEET_MM above or
 * below the column's surface), and texels in no UV triangle, are intact skin.
 *
 * Design: a per-texel map from texel to tissue-map coordinates, made once
 * per run by rasterising the UV triangles (one thread, triangles in file
 * order, so the later triangle wins where UV islands overlap); the renderer
 * then samples the tissue there instead of at its texel's place in a flat
 * block. The texture's world scale is the mesh's mean mm per UV unit
 * (sqrt of 3D area over UV area), which sizes the base skin's features and
 * the normal map's slopes. Gave up: per-texel scale and tangent frames (a
 * UV layout stretched unevenly gets features of uneven size). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdlib.h>

#include "skinsim/mesh.h"
#include "skinsim/shell.h"
#include "skinsim/wound.h"

/* A point counts as the column's surface within this distance (mm). */
#define SHEET_MM 2.0

static double tri_area3(const double a[3], const double b[3], const double c[3]) {
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double x = u[1] * v[2] - u[2] * v[1], y = u[2] * v[0] - u[0] * v[2],
           z = u[0] * v[1] - u[1] * v[0];
    return 0.5 * sqrt(x * x + y * y + z * z);
}

ss_image *ss_wound_uv_columns(const ss_shell_patch *p, const ss_mesh *m, int size,
                              double *mm_per_uv, ss_error *err) {
    if (!m->has_uvs) {
        ss_error_set(err, SS_ERR_INPUT, "the skin mesh has no texture coordinates (UVs)");
        return NULL;
    }
    ss_image *out = ss_image_create(size, size, 2, err);
    if (!out) return NULL;
    for (size_t i = 0; i < (size_t)size * (size_t)size * 2; i++) out->data[i] = NAN;
    double area3 = 0, areauv = 0, u = p->units_mm;
    for (int t = 0; t < m->ntriangles; t++) {
        double P[3][3], U[3][2];
        for (int k = 0; k < 3; k++) {
            uint32_t vi = m->indices[3 * t + k];
            for (int c = 0; c < 3; c++) P[k][c] = m->positions[3 * vi + c] * u;
            U[k][0] = m->uvs[2 * vi] * size, U[k][1] = m->uvs[2 * vi + 1] * size;
        }
        double det =
            (U[1][0] - U[0][0]) * (U[2][1] - U[0][1]) - (U[2][0] - U[0][0]) * (U[1][1] - U[0][1]);
        area3 += tri_area3(P[0], P[1], P[2]);
        areauv += fabs(det) * 0.5 / ((double)size * size);
        if (fabs(det) < 1e-12) continue;
        int x0 = (int)floor(fmin(U[0][0], fmin(U[1][0], U[2][0]))),
            x1 = (int)ceil(fmax(U[0][0], fmax(U[1][0], U[2][0]))),
            y0 = (int)floor(fmin(U[0][1], fmin(U[1][1], U[2][1]))),
            y1 = (int)ceil(fmax(U[0][1], fmax(U[1][1], U[2][1])));
        if (x0 < 0) x0 = 0;
        if (y0 < 0) y0 = 0;
        if (x1 > size - 1) x1 = size - 1;
        if (y1 > size - 1) y1 = size - 1;
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
                /* the skin point in the patch frame */
                double loc[3];
                for (int a = 0; a < 3; a++) {
                    double acc = 0;
                    for (int c = 0; c < 3; c++)
                        acc += (b0 * P[0][c] + b1 * P[1][c] + b2 * P[2][c] - p->origin_mm[c]) *
                               p->axis[a][c];
                    loc[a] = acc / p->dx_mm;
                }
                double ci = loc[0] - 0.5, cj = loc[1] - 0.5;
                float *o = out->data + ((size_t)y * (size_t)size + (size_t)x) * 2;
                int ii = (int)lround(ci), jj = (int)lround(cj);
                /* the patch's outer columns are its boundary layer, not skin */
                if (ci < 1.5 || cj < 1.5 || ci > p->nx - 2.5 || cj > p->ny - 2.5) {
                    o[0] = o[1] = NAN;
                    continue;
                }
                float sz = p->surf_z[(size_t)jj * (size_t)p->nx + (size_t)ii];
                if (!isfinite(sz) || fabs(loc[2] * p->dx_mm - sz) > SHEET_MM) {
                    o[0] = o[1] = NAN;
                    continue;
                }
                o[0] = (float)ci;                 /* tissue maps: x = grid i */
                o[1] = (float)((p->ny - 1) - cj); /* row 0 = grid y ny-1 */
            }
    }
    *mm_per_uv = areauv > 0 ? sqrt(area3 / areauv) : 100.0;
    return out;
}
