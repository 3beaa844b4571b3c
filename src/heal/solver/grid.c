/* Healing grid (seed 001 §5.1): a regular 3D grid of cubic voxels over a block
 * of skin with a cell state per voxel (air, epidermis, dermis, wound, outer
 * bound shell) and the eight species fields of §4.1 as float32 arrays. Builds
 * the wound mask from a footprint + depth (or a box), initialises states and
 * fields (healthy values, wound values, the two-voxel epithelial layer on top
 * of the skin), and computes the diagnostics behind area.csv.
 * Sub-voxel depth (docs/heal-model.md [D15]): the column ranges are kept in
 * 1/SS_HEAL_WOUND_SUB of a level and the mask byte is the wounded fraction
 * of its voxel (1 = whole, 2..255 = v/256), so a depth that is not a
 * multiple of the voxel cuts its last voxel instead of rounding to whole
 * voxels; whole-voxel depths give the masks and fields they gave before. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "skinsim/heal.h"

static const char *const field_names[SS_HEAL_NFIELDS] = {
    "oxygen", "mdgf", "capillary", "fibroblast", "eschar", "epithelium", "scar", "plasma"};

const char *ss_heal_field_name(int field) {
    return field >= 0 && field < SS_HEAL_NFIELDS ? field_names[field] : NULL;
}

double ss_heal_open_threshold(void) { return 0.5; }

size_t ss_heal_grid_bytes(int nx, int ny, int nz) {
    if (nx <= 0 || ny <= 0 || nz <= 0) return 0;
    size_t n = (size_t)nx * (size_t)ny * (size_t)nz;
    return sizeof(ss_heal_grid) + n * (1 + SS_HEAL_NFIELDS * sizeof(float));
}

ss_heal_grid *ss_heal_grid_create(int nx, int ny, int nz, double dx_mm, ss_error *err) {
    if (nx < 3 || ny < 3 || nz < 3) {
        ss_error_set(err, SS_ERR_INPUT, "heal grid: size %dx%dx%d too small (need >= 3 per axis)",
                     nx, ny, nz);
        return NULL;
    }
    if (!(dx_mm > 0) || !isfinite(dx_mm)) {
        ss_error_set(err, SS_ERR_INPUT, "heal grid: voxel size %g mm must be > 0", dx_mm);
        return NULL;
    }
    double cells = (double)nx * (double)ny * (double)nz;
    if (cells > (double)SS_HEAL_MAX_CELLS) {
        ss_error_set(err, SS_ERR_INPUT,
                     "heal grid: %dx%dx%d = %.3g cells is more than the %zu allowed (about %.1f "
                     "GB with the solver's work memory)",
                     nx, ny, nz, cells, (size_t)SS_HEAL_MAX_CELLS,
                     (double)SS_HEAL_MAX_CELLS * 70.0 / 1e9);
        return NULL;
    }
    /* grid + the explicit solver's second set of fields and masks */
    double need = (double)ss_heal_grid_bytes(nx, ny, nz) + cells * (SS_HEAL_NFIELDS * 4.0 + 9.0);
    double phys = ss_memory_physical_bytes();
    if (phys > 0 && need > phys) {
        ss_error_set(err, SS_ERR_INPUT,
                     "heal grid: %dx%dx%d needs about %.1f GB with the solver's work memory, "
                     "more than the %.1f GB of this machine; use a coarser voxel",
                     nx, ny, nz, need / 1e9, phys / 1e9);
        return NULL;
    }
    ss_heal_grid *g = calloc(1, sizeof *g);
    if (!g) goto nomem;
    g->nx = nx;
    g->ny = ny;
    g->nz = nz;
    g->dx_mm = dx_mm;
    size_t n = (size_t)nx * (size_t)ny * (size_t)nz;
    g->cell = calloc(n, 1);
    if (!g->cell) goto nomem;
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) {
        g->field[f] = calloc(n, sizeof(float));
        if (!g->field[f]) goto nomem;
    }
    return g;
nomem:
    ss_heal_grid_free(g);
    ss_error_set(err, SS_ERR_NOMEM, "heal grid: out of memory for %dx%dx%d (%.1f MB)", nx, ny, nz,
                 (double)ss_heal_grid_bytes(nx, ny, nz) / 1e6);
    return NULL;
}

void ss_heal_grid_free(ss_heal_grid *g) {
    if (!g) return;
    free(g->cell);
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) free(g->field[f]);
    for (int d = 0; d < 3; d++) free(g->velocity[d]);
    free(g->added);
    free(g);
}

ss_status ss_heal_grid_init(ss_heal_grid *g, double skin_top_mm, double epidermis_mm,
                            const uint8_t *wound3d, const ss_heal_params *p, ss_error *err) {
    if (!g) return ss_error_set(err, SS_ERR_INPUT, "heal grid init: no grid or params");
    const int goff[3] = {0, 0, 0}, gdim[3] = {g->nx, g->ny, g->nz};
    return ss_heal_grid_init_box(g, goff, gdim, skin_top_mm, epidermis_mm, wound3d, p, err);
}

ss_status ss_heal_grid_init_box(ss_heal_grid *g, const int goff[3], const int gdim[3],
                                double skin_top_mm, double epidermis_mm, const uint8_t *wound3d,
                                const ss_heal_params *p, ss_error *err) {
    if (!g || !p || !goff || !gdim)
        return ss_error_set(err, SS_ERR_INPUT, "heal grid init: no grid or params");
    const int nx = g->nx, ny = g->ny, nz = g->nz, GX = gdim[0], GY = gdim[1], GZ = gdim[2];
    /* top = number of skin layers of the whole grid (Z < top are skin) */
    int top = (int)floor(skin_top_mm / g->dx_mm + 0.5);
    top = top < 0 ? 0 : (top > GZ ? GZ : top);
    if (!(skin_top_mm > 0) || top < 4 || top > GZ - 2)
        return ss_error_set(err, SS_ERR_INPUT,
                            "heal grid init: skin top %g mm must leave >= 3 tissue voxels above "
                            "the bottom bound and >= 1 air voxel below the top bound (grid "
                            "height %g mm, voxel %g mm)",
                            skin_top_mm, GZ * g->dx_mm, g->dx_mm);
    if (!(epidermis_mm >= 0) || epidermis_mm > skin_top_mm)
        return ss_error_set(err, SS_ERR_INPUT,
                            "heal grid init: epidermis thickness %g mm must be in 0..%g mm",
                            epidermis_mm, skin_top_mm);
    /* the voxels whose depth range reaches into the top epidermis_mm: the
     * surface voxel holds a thinner epidermis as a sub-voxel sheet */
    int nepi = (int)ceil(epidermis_mm / g->dx_mm - 1e-9);
    if (nepi < 1) nepi = 1;
    if (nepi > top - 2) nepi = top - 2;
    g->skin_top_mm = skin_top_mm;
    g->t_days = 0.0;
    g->step = 0;
    float hv[SS_HEAL_NFIELDS];
    ss_heal_params_healthy(p, hv);
    for (int z = 0; z < nz; z++) {
        for (int y = 0; y < ny; y++) {
            for (int x = 0; x < nx; x++) {
                const int X = x + goff[0], Y = y + goff[1], Z = z + goff[2];
                size_t c = ss_heal_idx(g, x, y, z);
                uint8_t s;
                const int outside = X < 0 || Y < 0 || Z < 0 || X >= GX || Y >= GY || Z >= GZ;
                if (outside || X == 0 || Y == 0 || Z == 0 || X == GX - 1 || Y == GY - 1 ||
                    Z == GZ - 1)
                    s = SS_CELL_BOUND;
                else if (Z >= top)
                    s = SS_CELL_AIR;
                else if (wound3d && wound3d[c])
                    s = SS_CELL_WOUND; /* whole or partial */
                else if (Z >= top - nepi)
                    s = SS_CELL_EPIDERMIS;
                else
                    s = SS_CELL_DERMIS;
                g->cell[c] = s;
                float v[SS_HEAL_NFIELDS] = {0};
                if (!outside && (s == SS_CELL_EPIDERMIS || s == SS_CELL_DERMIS ||
                                 (s == SS_CELL_BOUND && Z > 0 && Z < top))) {
                    for (int f = 0; f < SS_HEAL_NFIELDS; f++) v[f] = hv[f];
                    /* the intact epidermis (§5.1's layer on top of the skin, in mm) */
                    if (Z >= top - nepi) v[SS_HEAL_EPITHELIUM] = 1.0f;
                } else if (s == SS_CELL_WOUND && wound3d[c] == 1) {
                    v[SS_HEAL_OXYGEN] = (float)p->u1_wound;
                    v[SS_HEAL_PLASMA] = 1.0f;
                } else if (s == SS_CELL_WOUND) {
                    /* a partial cell: its intact share (1 - f) keeps the healthy
                     * tissue's oxygen, capillaries and fibroblasts, its wounded
                     * share f the clot's oxygen. No epithelium: the wound opened
                     * the surface sheet (an e of 1 - f would count that share of
                     * the wound as covered at t = 0). Plasma (1 + f) / 2: in
                     * omega like every cell the wound cuts (p enters the model
                     * only through omega), and the record of f that the adnexa's
                     * depth reads ([D15]) */
                    const float f = (float)ss_heal_wound_fraction(wound3d[c]);
                    for (int k = 0; k < SS_HEAL_NFIELDS; k++) v[k] = (1.0f - f) * hv[k];
                    v[SS_HEAL_EPITHELIUM] = 0.0f;
                    v[SS_HEAL_OXYGEN] += f * (float)p->u1_wound;
                    v[SS_HEAL_PLASMA] = 0.5f * (1.0f + f);
                }
                for (int f = 0; f < SS_HEAL_NFIELDS; f++) g->field[f][c] = v[f];
            }
        }
    }
    return SS_OK;
}

/* ---- the wound as per-column depth ranges ------------------------------------------- */

double ss_heal_wound_fraction(uint8_t v) { return v == 1 ? 1.0 : (double)v / SS_HEAL_WOUND_SUB; }

/* [top - d, top) in 1/SS_HEAL_WOUND_SUB of a level, clipped to the grid;
 * c stays 0, 0 (no wound) when nothing is left */
static void sub_range(int nz, double dx_mm, double top_mm, double d, int32_t c[2]) {
    const double s = SS_HEAL_WOUND_SUB, full = (double)nz * s;
    double lo = floor((top_mm - d) / dx_mm * s + 0.5), hi = floor(top_mm / dx_mm * s + 0.5);
    lo = lo < 0 ? 0 : lo;
    hi = hi > full ? full : hi;
    if (hi > lo) c[0] = (int32_t)lo, c[1] = (int32_t)hi;
}

int ss_heal_wound_subvoxel(const ss_heal_params *p) {
    return p && p->static_region && !(p->lamkrho > 0);
}

void ss_heal_wound_columns_whole(int32_t *cols, size_t ncol) {
    const int32_t s = SS_HEAL_WOUND_SUB, h = SS_HEAL_WOUND_SUB / 2;
    for (size_t i = 0; i < ncol; i++) {
        int32_t *c = cols + 2 * i;
        if (c[1] <= c[0]) continue;
        /* the levels that are at least half wound (centre inside the range) */
        const int32_t lo = (c[0] + h - 1) / s, hi = (c[1] + h) / s;
        c[0] = hi > lo ? lo * s : 0;
        c[1] = hi > lo ? hi * s : 0;
    }
}

int32_t *ss_heal_wound_columns_footprint(int nx, int ny, int nz, double dx_mm, double skin_top_mm,
                                         const ss_image *footprint, double depth_mm,
                                         const ss_image *depth_mm_img, ss_error *err) {
    if (!footprint || !footprint->data || footprint->width < 1 || footprint->height < 1) {
        ss_error_set(err, SS_ERR_INPUT, "wound footprint: no image");
        return NULL;
    }
    if (!depth_mm_img && (!(depth_mm > 0) || !isfinite(depth_mm))) {
        ss_error_set(err, SS_ERR_INPUT, "wound depth %g mm must be > 0", depth_mm);
        return NULL;
    }
    if (depth_mm_img && (!depth_mm_img->data || depth_mm_img->width < 1)) {
        ss_error_set(err, SS_ERR_INPUT, "wound depth image: empty");
        return NULL;
    }
    if (!(skin_top_mm > 0) || skin_top_mm > nz * dx_mm) {
        ss_error_set(err, SS_ERR_INPUT, "wound footprint: skin top %g mm outside the grid (0..%g)",
                     skin_top_mm, nz * dx_mm);
        return NULL;
    }
    int32_t *cols = calloc(2 * (size_t)nx * (size_t)ny, sizeof *cols);
    if (!cols) {
        ss_error_set(err, SS_ERR_NOMEM, "wound footprint: out of memory");
        return NULL;
    }
    for (int y = 0; y < ny; y++) {
        for (int x = 0; x < nx; x++) {
            /* voxel centre -> image pixel (row 0 at the far +y edge) */
            double u = (x + 0.5) / nx, v = 1.0 - (y + 0.5) / ny;
            int px = (int)(u * footprint->width), py = (int)(v * footprint->height);
            if (px >= footprint->width) px = footprint->width - 1;
            if (py >= footprint->height) py = footprint->height - 1;
            if (ss_image_px(footprint, px, py)[0] <= 0.5f) continue;
            double d = depth_mm;
            if (depth_mm_img) {
                int qx = (int)(u * depth_mm_img->width), qy = (int)(v * depth_mm_img->height);
                if (qx >= depth_mm_img->width) qx = depth_mm_img->width - 1;
                if (qy >= depth_mm_img->height) qy = depth_mm_img->height - 1;
                d = ss_image_px(depth_mm_img, qx, qy)[0];
                if (!(d >= 0) || !isfinite(d)) {
                    free(cols);
                    ss_error_set(err, SS_ERR_INPUT,
                                 "wound depth image: pixel (%d,%d) = %g mm is not a depth >= 0", qx,
                                 qy, d);
                    return NULL;
                }
            }
            sub_range(nz, dx_mm, skin_top_mm, d, cols + 2 * ((size_t)y * (size_t)nx + (size_t)x));
        }
    }
    return cols;
}

int32_t *ss_heal_wound_columns_box(int nx, int ny, int nz, double dx_mm, double skin_top_mm,
                                   double side_x_mm, double side_y_mm, double depth_mm,
                                   ss_error *err) {
    if (!(side_x_mm > 0) || !(side_y_mm > 0) || !(depth_mm > 0)) {
        ss_error_set(err, SS_ERR_INPUT, "wound box: sides %g x %g mm and depth %g mm must be > 0",
                     side_x_mm, side_y_mm, depth_mm);
        return NULL;
    }
    int32_t *cols = calloc(2 * (size_t)nx * (size_t)ny, sizeof *cols);
    if (!cols) {
        ss_error_set(err, SS_ERR_NOMEM, "wound box: out of memory");
        return NULL;
    }
    int32_t r[2] = {0, 0};
    sub_range(nz, dx_mm, skin_top_mm, depth_mm, r);
    const int32_t lo = r[0], hi = r[1];
    double cx = 0.5 * nx * dx_mm, cy = 0.5 * ny * dx_mm;
    for (int y = 0; hi > lo && y < ny; y++) {
        double yc = (y + 0.5) * dx_mm;
        if (fabs(yc - cy) >= 0.5 * side_y_mm) continue;
        for (int x = 0; x < nx; x++) {
            double xc = (x + 0.5) * dx_mm;
            if (fabs(xc - cx) < 0.5 * side_x_mm) {
                cols[2 * ((size_t)y * (size_t)nx + (size_t)x)] = lo;
                cols[2 * ((size_t)y * (size_t)nx + (size_t)x) + 1] = hi;
            }
        }
    }
    return cols;
}

uint8_t *ss_heal_wound_columns_expand(const int32_t *cols, const int gdim[3], const int lo[3],
                                      const int n[3], ss_error *err) {
    uint8_t *m = calloc((size_t)n[0] * (size_t)n[1] * (size_t)n[2], 1);
    if (!m) {
        ss_error_set(err, SS_ERR_NOMEM, "wound mask: out of memory");
        return NULL;
    }
    for (int y = 0; y < n[1]; y++)
        for (int x = 0; x < n[0]; x++) {
            const int X = x + lo[0], Y = y + lo[1];
            if (X < 0 || Y < 0 || X >= gdim[0] || Y >= gdim[1]) continue;
            const int32_t *c = cols + 2 * ((size_t)Y * (size_t)gdim[0] + (size_t)X);
            const int32_t s = SS_HEAL_WOUND_SUB;
            if (c[1] <= c[0]) continue;
            for (int Z = c[0] / s; Z <= (c[1] - 1) / s; Z++) {
                const int z = Z - lo[2];
                if (z < 0 || z >= n[2]) continue;
                /* the level's wounded share in 1/s: whole = 1, a sliver >= 2 */
                const int32_t a = c[0] > Z * s ? c[0] : Z * s,
                              b = c[1] < (Z + 1) * s ? c[1] : (Z + 1) * s;
                const int32_t ov = b - a;
                m[((size_t)z * (size_t)n[1] + (size_t)y) * (size_t)n[0] + (size_t)x] =
                    (uint8_t)(ov >= s  ? 1
                              : ov < 2 ? 2
                                       : ov);
            }
        }
    return m;
}

/* A whole-grid mask from column ranges (NULL in, NULL out: err is set). */
static uint8_t *whole_mask(const ss_heal_grid *g, int32_t *cols, ss_error *err) {
    if (!cols) return NULL;
    const int gdim[3] = {g->nx, g->ny, g->nz}, lo[3] = {0, 0, 0};
    uint8_t *m = ss_heal_wound_columns_expand(cols, gdim, lo, gdim, err);
    free(cols);
    return m;
}

uint8_t *ss_heal_wound_from_footprint(const ss_heal_grid *g, double skin_top_mm,
                                      const ss_image *footprint, double depth_mm,
                                      const ss_image *depth_mm_img, ss_error *err) {
    if (!g) {
        ss_error_set(err, SS_ERR_INPUT, "wound footprint: no image");
        return NULL;
    }
    return whole_mask(g,
                      ss_heal_wound_columns_footprint(g->nx, g->ny, g->nz, g->dx_mm, skin_top_mm,
                                                      footprint, depth_mm, depth_mm_img, err),
                      err);
}

uint8_t *ss_heal_wound_box(const ss_heal_grid *g, double skin_top_mm, double side_x_mm,
                           double side_y_mm, double depth_mm, ss_error *err) {
    if (!g) {
        ss_error_set(err, SS_ERR_INPUT, "wound box: sides %g x %g mm and depth %g mm must be > 0",
                     side_x_mm, side_y_mm, depth_mm);
        return NULL;
    }
    return whole_mask(g,
                      ss_heal_wound_columns_box(g->nx, g->ny, g->nz, g->dx_mm, skin_top_mm,
                                                side_x_mm, side_y_mm, depth_mm, err),
                      err);
}

int ss_heal_in_region(const ss_heal_grid *g, const ss_heal_params *p, size_t idx) {
    uint8_t s = g->cell[idx];
    if (s == SS_CELL_AIR || s == SS_CELL_BOUND) return 0;
    (void)p;
    return g->field[SS_HEAL_PLASMA][idx] > (float)SS_HEAL_P_MIN;
}
