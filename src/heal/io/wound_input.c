/* Wound inputs for the healing grid (stroke CSV files and OBJ meshes are read
 * by geom): footprint and depth images, and closed
 * meshes voxelised by ray parity (seed 001 §5.1: "we check with a ray
 * intersection test which cells are wound, skin, or empty cells"). Rays run
 * along +z through each voxel column; a voxel centre is inside when an odd
 * number of triangle crossings lies below it. */
#define _POSIX_C_SOURCE 200809L
#include "skinsim/heal_io.h"
#include "skinsim/geom.h"
#include "skinsim/mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#ifndef M_SQRT2
#define M_SQRT2 1.41421356237309504880
#endif

/* ---- footprint and depth images ------------------------------------------------- */

static float first_or_luma(const ss_image *img, int x, int y) {
    const float *p = ss_image_px(img, x, y);
    if (img->channels >= 3) return 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2];
    return p[0];
}

ss_image *ss_heal_footprint_read(const char *path, ss_error *err) {
    ss_image *img = ss_image_read(path, SS_ENC_LINEAR, err);
    if (!img) return NULL;
    ss_image *fp = ss_image_create(img->width, img->height, 1, err);
    if (!fp) {
        ss_image_free(img);
        return NULL;
    }
    size_t on = 0;
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++) {
            float v = first_or_luma(img, x, y);
            int w = v > 0.5f; /* NaN counts as intact */
            fp->data[(size_t)y * (size_t)img->width + (size_t)x] = (float)w;
            on += (size_t)w;
        }
    ss_image_free(img);
    if (!on) {
        ss_error_set(err, SS_ERR_INPUT, "%s: the wound mask is empty (no pixel above 0.5)", path);
        ss_image_free(fp);
        return NULL;
    }
    return fp;
}

ss_image *ss_heal_depth_image_read(const char *path, double max_depth_mm, ss_error *err) {
    size_t l = strlen(path);
    int is_exr = l >= 4 && (!strcmp(path + l - 4, ".exr") || !strcmp(path + l - 4, ".EXR"));
    ss_image *img = ss_image_read(path, SS_ENC_LINEAR, err);
    if (!img) return NULL;
    ss_image *d = ss_image_create(img->width, img->height, 1, err);
    if (!d) {
        ss_image_free(img);
        return NULL;
    }
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++) {
            double v = first_or_luma(img, x, y);
            if (!is_exr) v *= max_depth_mm;
            if (!isfinite(v) || v < 0) {
                ss_error_set(err, SS_ERR_INPUT,
                             "%s: depth at pixel (%d,%d) is %g; depths must be finite and >= 0 "
                             "mm",
                             path, x, y, v);
                ss_image_free(img);
                ss_image_free(d);
                return NULL;
            }
            d->data[(size_t)y * (size_t)img->width + (size_t)x] = (float)v;
        }
    ss_image_free(img);
    return d;
}

/* ---- voxelisation by ray parity (seed 001 §5.1) -------------------------------------- */

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

uint8_t *ss_heal_voxelise_mesh(const ss_tri_mesh *m, int nx, int ny, int nz, double dx_mm,
                               size_t *count, ss_error *err) {
    const int gdim[3] = {nx, ny, nz}, lo[3] = {0, 0, 0};
    return ss_heal_voxelise_mesh_box(m, gdim, lo, gdim, dx_mm, count, err);
}

uint8_t *ss_heal_voxelise_mesh_box(const ss_tri_mesh *m, const int gdim[3], const int lo[3],
                                   const int bn[3], double dx_mm, size_t *count, ss_error *err) {
    if (count) *count = 0;
    const int nx = gdim[0], ny = gdim[1], nz = gdim[2];
    if (nx < 1 || ny < 1 || nz < 1 || bn[0] < 1 || bn[1] < 1 || bn[2] < 1 || !(dx_mm > 0) ||
        !isfinite(dx_mm)) {
        ss_error_set(err, SS_ERR_INPUT, "voxelise: invalid grid %dx%dx%d, dx %g mm", nx, ny, nz,
                     dx_mm);
        return NULL;
    }
    /* the box's columns and levels inside the grid (whole-grid indices) */
    const int x0 = lo[0] > 0 ? lo[0] : 0, x1 = lo[0] + bn[0] < nx ? lo[0] + bn[0] : nx;
    const int ya = lo[1] > 0 ? lo[1] : 0, yb = lo[1] + bn[1] < ny ? lo[1] + bn[1] : ny;
    const int z0 = lo[2] > 0 ? lo[2] : 0, z1 = lo[2] + bn[2] < nz ? lo[2] + bn[2] : nz;
    size_t n = (size_t)bn[0] * (size_t)bn[1] * (size_t)bn[2];
    uint8_t *vox = calloc(n, 1);
    /* Bin triangles by grid row (y) so each column tests only nearby triangles. */
    int *rowcount = calloc((size_t)ny + 1, sizeof(int));
    if (!vox || !rowcount) {
        free(vox);
        free(rowcount);
        ss_error_set(err, SS_ERR_NOMEM, "voxelise: out of memory");
        return NULL;
    }
    /* A fixed, tiny, irrational nudge keeps rays off exact edges and vertices of
     * meshes built on the grid lattice. */
    const double ox = dx_mm * 1.2345678e-6 * M_SQRT2, oy = dx_mm * 0.9876543e-6 * M_PI;
    int ntri = m->ntris;
#define ROWRANGE(t, lo, hi)                                                                        \
    do {                                                                                           \
        double y0 = INFINITY, y1 = -INFINITY;                                                      \
        for (int k_ = 0; k_ < 3; k_++) {                                                           \
            double yy = m->v[3 * (size_t)m->tri[3 * (t) + k_] + 1];                                \
            if (yy < y0) y0 = yy;                                                                  \
            if (yy > y1) y1 = yy;                                                                  \
        }                                                                                          \
        lo = (int)ceil((y0 - oy) / dx_mm - 0.5);                                                   \
        hi = (int)floor((y1 - oy) / dx_mm - 0.5);                                                  \
        if (lo < ya) lo = ya;                                                                      \
        if (hi > yb - 1) hi = yb - 1;                                                              \
    } while (0)
    for (int t = 0; t < ntri; t++) {
        int lo, hi;
        ROWRANGE(t, lo, hi);
        for (int y = lo; y <= hi; y++) rowcount[y + 1]++;
    }
    for (int y = 0; y < ny; y++) rowcount[y + 1] += rowcount[y];
    size_t total = (size_t)rowcount[ny];
    int *rowtri = malloc((total ? total : 1) * sizeof(int));
    int *fill = calloc((size_t)ny, sizeof(int));
    if (!rowtri || !fill) {
        free(vox);
        free(rowcount);
        free(rowtri);
        free(fill);
        ss_error_set(err, SS_ERR_NOMEM, "voxelise: out of memory");
        return NULL;
    }
    for (int t = 0; t < ntri; t++) {
        int lo, hi;
        ROWRANGE(t, lo, hi);
        for (int y = lo; y <= hi; y++) rowtri[rowcount[y] + fill[y]++] = t;
    }
#undef ROWRANGE
    free(fill);
    size_t inside = 0;
    int oom = 0;
#pragma omp parallel reduction(+ : inside) reduction(| : oom)
    {
        int cap = 64;
        double *hits = malloc((size_t)cap * sizeof *hits);
        if (!hits) oom = 1;
#pragma omp for schedule(dynamic, 1)
        for (int y = ya; y < yb; y++) {
            if (!hits) continue;
            double py = (y + 0.5) * dx_mm + oy;
            for (int x = x0; x < x1; x++) {
                double px = (x + 0.5) * dx_mm + ox;
                int nh = 0;
                for (int r = rowcount[y]; r < rowcount[y + 1]; r++) {
                    int t = rowtri[r];
                    const double *a = m->v + 3 * (size_t)m->tri[3 * t];
                    const double *b = m->v + 3 * (size_t)m->tri[3 * t + 1];
                    const double *c = m->v + 3 * (size_t)m->tri[3 * t + 2];
                    /* 2D barycentric test in the xy projection */
                    double d = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
                    if (d == 0) continue; /* face parallel to the ray */
                    double w1 = ((px - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (py - a[1])) / d;
                    double w2 = ((b[0] - a[0]) * (py - a[1]) - (px - a[0]) * (b[1] - a[1])) / d;
                    double w0 = 1 - w1 - w2;
                    if (w0 < 0 || w1 < 0 || w2 < 0) continue;
                    if (nh == cap) {
                        cap *= 2;
                        double *q = realloc(hits, (size_t)cap * sizeof *hits);
                        if (!q) {
                            oom = 1;
                            break;
                        }
                        hits = q;
                    }
                    hits[nh++] = w0 * a[2] + w1 * b[2] + w2 * c[2];
                }
                if (nh < 2) continue;
                qsort(hits, (size_t)nh, sizeof *hits, cmp_double);
                int h = 0;
                for (int z = z0; z < z1; z++) {
                    double pz = (z + 0.5) * dx_mm;
                    while (h < nh && hits[h] < pz) h++;
                    if (h & 1) {
                        vox[((size_t)(z - lo[2]) * (size_t)bn[1] + (size_t)(y - lo[1])) *
                                (size_t)bn[0] +
                            (size_t)(x - lo[0])] = 1;
                        inside++;
                    }
                }
            }
        }
        free(hits);
    }
    free(rowcount);
    free(rowtri);
    if (oom) {
        free(vox);
        ss_error_set(err, SS_ERR_NOMEM, "voxelise: out of memory");
        return NULL;
    }
    if (count) *count = inside;
    return vox;
}
