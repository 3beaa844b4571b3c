/* UV padding (edge dilation) for textures on a mesh: which texels a mesh's
 * UV triangles cover, and texels outside every island, within N texels of
 * one, given the colour of the nearest covered texel - the gutter a
 * texture baker leaves, so bilinear filtering and mipmaps at an island's
 * border read the island's own colour instead of whatever lies beyond.
 *
 * Design: coverage is the texel centre inside a triangle
 * (ss_uv_triangle_raster, the rasteriser the wound's UV columns use too). The nearest covered texel
 * is found exactly, in Euclidean distance, by the two-pass squared distance transform of
 * Felzenszwalb and Huttenlocher ("Distance transforms of sampled
 * functions", Theory of Computing 2012) carrying the argmin along: per
 * column the nearest covered row, then per row the lower envelope of the
 * columns' parabolas. Ties go to the lower column, then the lower row (fixed
 * by the scan order), so the result is the same for any thread count.
 * Covered texels are never written. Gave up: padding across the texture's
 * edge (mesh textures do not wrap) and colour averaging of equidistant
 * texels (a baker's "extend" keeps one source, as here). */
#include "skinsim/mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct coverage_ctx {
    unsigned char *mask;
    int width;
} coverage_ctx;

static void cover_texel(int x, int y, int tri, double b0, double b1, double b2, void *ctx) {
    (void)tri, (void)b0, (void)b1, (void)b2;
    coverage_ctx *c = ctx;
    c->mask[(size_t)y * (size_t)c->width + (size_t)x] = 1;
}

ss_status ss_mesh_uv_coverage(const ss_mesh *m, int width, int height, unsigned char *mask,
                              ss_error *err) {
    if (!m->has_uvs)
        return ss_error_set(err, SS_ERR_INPUT, "the mesh has no texture coordinates (UVs)");
    memset(mask, 0, (size_t)width * (size_t)height);
    coverage_ctx c = {mask, width};
    ss_uv_triangle_raster(m, width, height, cover_texel, &c);
    return SS_OK;
}

ss_status ss_image_pad_islands(ss_image *img, const unsigned char *inside, int n, ss_error *err) {
    if (n <= 0) return SS_OK;
    const int w = img->width, h = img->height, C = img->channels;
    const size_t N = (size_t)w * (size_t)h;
    /* per texel: the nearest covered row in its column (-1: none) */
    int *row = malloc(N * sizeof(int));
    /* per texel: the column of its nearest covered texel (-1: none within n) */
    int *col = malloc(N * sizeof(int));
    if (!row || !col) {
        free(row);
        free(col);
        return ss_error_set(err, SS_ERR_NOMEM, "UV padding: out of memory");
    }
#pragma omp parallel for schedule(static)
    for (int x = 0; x < w; x++) {
        int last = -1;
        for (int y = 0; y < h; y++) { /* downwards: nearest covered at or above */
            if (inside[(size_t)y * w + x]) last = y;
            row[(size_t)y * w + x] = last;
        }
        last = -1;
        for (int y = h - 1; y >= 0; y--) { /* upwards: keep the nearer (ties: the upper) */
            if (inside[(size_t)y * w + x]) last = y;
            int *r = &row[(size_t)y * w + x];
            if (last >= 0 && (*r < 0 || last - y < y - *r)) *r = last;
        }
    }
    const double INF = 1e300;
#pragma omp parallel
    {
        int *v = malloc((size_t)w * sizeof(int));
        double *z = malloc(((size_t)w + 1) * sizeof(double));
        double *f = malloc((size_t)w * sizeof(double));
#pragma omp for schedule(static)
        for (int y = 0; y < h; y++) {
            int *cy = col + (size_t)y * w;
            if (!v || !z || !f) {
                for (int x = 0; x < w; x++) cy[x] = -2; /* out of memory: reported below */
                continue;
            }
            const int *ry = row + (size_t)y * w;
            int k = -1;
            for (int q = 0; q < w; q++) {
                if (ry[q] < 0) continue;
                double dy = ry[q] - y;
                f[q] = dy * dy;
                if (f[q] > (double)n * n) continue; /* its parabola is above n^2 everywhere */
                /* the lower envelope of parabolas (x - q)^2 + f[q] */
                for (;;) {
                    if (k < 0) {
                        v[++k] = q;
                        z[k] = -INF;
                        z[k + 1] = INF;
                        break;
                    }
                    int p = v[k];
                    double s = ((f[q] + (double)q * q) - (f[p] + (double)p * p)) / (2.0 * (q - p));
                    if (s <= z[k]) {
                        k--;
                        continue;
                    }
                    v[++k] = q;
                    z[k] = s;
                    z[k + 1] = INF;
                    break;
                }
            }
            for (int x = 0, j = 0; x < w; x++) {
                if (k < 0) {
                    cy[x] = -1;
                    continue;
                }
                while (z[j + 1] < x) j++;
                int q = v[j];
                double d2 = (double)(x - q) * (x - q) + f[q];
                cy[x] = d2 <= (double)n * n ? q : -1;
            }
        }
        free(v);
        free(z);
        free(f);
    }
    for (size_t i = 0; i < N; i++)
        if (col[i] == -2) {
            free(row);
            free(col);
            return ss_error_set(err, SS_ERR_NOMEM, "UV padding: out of memory");
        }
        /* copy from the sources (always covered texels, which are never written) */
#pragma omp parallel for schedule(static)
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)y * w + x;
            int q = col[i];
            if (inside[i] || q < 0) continue;
            size_t j = (size_t)row[(size_t)y * w + q] * w + (size_t)q;
            memcpy(img->data + i * C, img->data + j * C, (size_t)C * sizeof(float));
        }
    free(row);
    free(col);
    return SS_OK;
}
