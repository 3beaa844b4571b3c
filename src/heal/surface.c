/* Top-view maps of the healing grid: per (x, y) column, the value of a field in
 * the topmost tissue cell (what one sees at the skin surface), its maximum
 * over the two topmost (the epithelial layer) or over the column's tissue cells; air, the
 * top/bottom boundary layers and side boundary cells above the skin surface are skipped. These are
 * the 2D views the seed maps onto the undeformed mesh for shading (seed 001 §5.4); rendered to PNG
 * by plot.c. */
#include "skinsim/heal_io.h"

ss_image *ss_heal_surface_map(const ss_heal_grid *g, int field, ss_heal_surface_mode mode,
                              ss_error *err) {
    if (!g || field < 0 || field >= SS_HEAL_NFIELDS || !g->field[field]) {
        ss_error_set(err, SS_ERR_INPUT, "surface map: invalid field %d", field);
        return NULL;
    }
    ss_image *img = ss_image_create(g->nx, g->ny, 1, err);
    if (!img) return NULL;
    const int nx = g->nx, ny = g->ny, nz = g->nz;
    const float *a = g->field[field];
#pragma omp parallel for schedule(static)
    for (int y = 0; y < ny; y++) {
        for (int x = 0; x < nx; x++) {
            float v = 0;
            int found = 0;
            for (int z = nz - 1; z >= 0; z--) {
                size_t i = ((size_t)z * (size_t)ny + (size_t)y) * (size_t)nx + (size_t)x;
                /* skip air and boundary cells that are not tissue: the top and
                 * bottom layers and side boundary cells above the skin surface */
                if (g->cell[i] == SS_CELL_AIR ||
                    (g->cell[i] == SS_CELL_BOUND &&
                     (z == 0 || z == nz - 1 || (z + 0.5) * g->dx_mm > g->skin_top_mm)))
                    continue;
                if (mode == SS_SURFACE_TOP) {
                    v = a[i];
                    break;
                }
                if (!found || a[i] > v) v = a[i];
                found++;
                if (mode == SS_SURFACE_LAYER && found == 2) break;
            }
            img->data[(size_t)(ny - 1 - y) * (size_t)nx + (size_t)x] = v;
        }
    }
    return img;
}
