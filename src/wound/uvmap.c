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
 * per run by rasterising the UV triangles (ss_uv_triangle_raster: one thread, triangles in file
 * order, so the later triangle wins where UV islands overlap); the renderer
 * then samples the tissue there instead of at its texel's place in a flat
 * block; texels just outside an island take their neighbour's columns (a
 * 2-texel gutter), so filtering at island edges does not show base-skin
 * seams through the wound. The texture's world scale is the mesh's mean mm per UV unit
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

/* A triangle's corners: positions in mm, UVs in texels. */
static void tri_corners(const ss_mesh *m, int t, double units_mm, int size, double P[3][3],
                        double U[3][2]) {
    for (int k = 0; k < 3; k++) {
        uint32_t vi = m->indices[3 * t + k];
        for (int c = 0; c < 3; c++) P[k][c] = m->positions[3 * vi + c] * units_mm;
        U[k][0] = (double)m->uvs[2 * vi] * size, U[k][1] = (double)m->uvs[2 * vi + 1] * size;
    }
}

typedef struct column_ctx {
    const ss_shell_patch *p;
    const ss_mesh *m;
    ss_image *out;
    unsigned char *hit;
    int size;
} column_ctx;

/* One texel of a UV triangle (ss_uv_triangle_raster): the skin point it
 * shows, in the patch frame, and the tissue column under it. */
static void column_texel(int x, int y, int tri, double b0, double b1, double b2, void *ctx) {
    const column_ctx *cc = ctx;
    const ss_shell_patch *p = cc->p;
    double P[3][3], U[3][2];
    tri_corners(cc->m, tri, p->units_mm, cc->size, P, U);
    double loc[3];
    for (int a = 0; a < 3; a++) {
        double acc = 0;
        for (int c = 0; c < 3; c++)
            acc += (b0 * P[0][c] + b1 * P[1][c] + b2 * P[2][c] - p->origin_mm[c]) * p->axis[a][c];
        loc[a] = acc / p->dx_mm;
    }
    double ci = loc[0] - 0.5, cj = loc[1] - 0.5;
    size_t i = (size_t)y * (size_t)cc->size + (size_t)x;
    float *o = cc->out->data + i * 2;
    cc->hit[i] = 1;
    int ii = (int)lround(ci), jj = (int)lround(cj);
    /* the patch's outer columns are its boundary layer, not skin */
    if (ci < 1.5 || cj < 1.5 || ci > p->nx - 2.5 || cj > p->ny - 2.5) {
        o[0] = o[1] = NAN;
        return;
    }
    float sz = p->surf_z[(size_t)jj * (size_t)p->nx + (size_t)ii];
    if (!isfinite(sz) || fabs(loc[2] * p->dx_mm - sz) > SHEET_MM) {
        o[0] = o[1] = NAN;
        return;
    }
    o[0] = (float)ci;                 /* tissue maps: x = grid i */
    o[1] = (float)((p->ny - 1) - cj); /* row 0 = grid y ny-1 */
}

/* Texels of no UV triangle next to the edge of an island take the columns of
 * a covered neighbour, PAD_TEXELS deep (the gutter a texture baker leaves):
 * texture filtering and mipmaps at the island's edge then read the wound,
 * not a 1-texel seam of base skin (the hard tabs along a wound's rim where it
 * crosses an island edge). The first covered neighbour in a fixed order
 * wins, so the result does not depend on the thread count. */
#define PAD_TEXELS 2
static void pad_islands(ss_image *out, unsigned char *hit, int size) {
    static const int dx[8] = {1, -1, 0, 0, 1, -1, 1, -1}, dy[8] = {0, 0, 1, -1, 1, 1, -1, -1};
    for (int pass = 1; pass <= PAD_TEXELS; pass++)
        for (int y = 0; y < size; y++)
            for (int x = 0; x < size; x++) {
                size_t i = (size_t)y * (size_t)size + (size_t)x;
                if (hit[i]) continue;
                for (int k = 0; k < 8; k++) {
                    int xx = x + dx[k], yy = y + dy[k];
                    if (xx < 0 || yy < 0 || xx >= size || yy >= size) continue;
                    size_t j = (size_t)yy * (size_t)size + (size_t)xx;
                    if (!hit[j] || hit[j] > pass) continue; /* filled in this pass */
                    out->data[i * 2] = out->data[j * 2];
                    out->data[i * 2 + 1] = out->data[j * 2 + 1];
                    hit[i] = (unsigned char)(pass + 1);
                    break;
                }
            }
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
    /* texels whose centre lies in some UV triangle (whether or not on the patch) */
    unsigned char *hit = calloc((size_t)size * (size_t)size, 1);
    if (!hit) {
        ss_image_free(out);
        ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        return NULL;
    }
    double area3 = 0, areauv = 0;
    for (int t = 0; t < m->ntriangles; t++) {
        double P[3][3], U[3][2];
        tri_corners(m, t, p->units_mm, size, P, U);
        double det =
            (U[1][0] - U[0][0]) * (U[2][1] - U[0][1]) - (U[2][0] - U[0][0]) * (U[1][1] - U[0][1]);
        area3 += tri_area3(P[0], P[1], P[2]);
        areauv += fabs(det) * 0.5 / ((double)size * size);
    }
    column_ctx cc = {p, m, out, hit, size};
    ss_uv_triangle_raster(m, size, size, column_texel, &cc);
    pad_islands(out, hit, size);
    free(hit);
    *mm_per_uv = areauv > 0 ? sqrt(area3 / areauv) : 100.0;
    return out;
}
