/* Top-view maps of the healing grid: per (x, y) column, the value of a field in
 * the topmost tissue cell (what one sees at the skin surface), its maximum
 * over the two topmost (the epithelial layer) or over the column's tissue cells; air, the
 * top/bottom boundary layers and side boundary cells above the skin surface are skipped. These are
 * the 2D views the seed maps onto the undeformed mesh for shading (seed 001 §5.4); rendered to PNG
 * by plot.c. */
#include <stdlib.h>
#include <string.h>

#include "skinsim/heal_io.h"

void ss_heal_surface_scan(const ss_heal_grid *g, int field, ss_heal_surface_mode mode, int z0,
                          int z1, int zoff, int gz, float *v, float *found) {
    const int nx = g->nx, ny = g->ny;
    const float *a = g->field[field];
    const int stop = mode == SS_SURFACE_TOP ? 1 : mode == SS_SURFACE_LAYER ? 2 : 0;
#pragma omp parallel for schedule(static)
    for (int y = 0; y < ny; y++) {
        for (int x = 0; x < nx; x++) {
            const size_t k = (size_t)y * (size_t)nx + (size_t)x;
            for (int z = z1 - 1; z >= z0 && !(stop && found[k] >= stop); z--) {
                const size_t i = ss_heal_idx(g, x, y, z);
                const int Z = z + zoff;
                /* skip air and boundary cells that are not tissue: the top and
                 * bottom layers and side boundary cells above the skin surface */
                if (g->cell[i] == SS_CELL_AIR ||
                    (g->cell[i] == SS_CELL_BOUND &&
                     (Z == 0 || Z == gz - 1 || (Z + 0.5) * g->dx_mm > g->skin_top_mm)))
                    continue;
                if (!found[k] || a[i] > v[k]) v[k] = a[i];
                found[k]++;
            }
        }
    }
}

ss_image *ss_heal_surface_map(const ss_heal_grid *g, int field, ss_heal_surface_mode mode,
                              ss_error *err) {
    if (!g || field < 0 || field >= SS_HEAL_NFIELDS || !g->field[field]) {
        ss_error_set(err, SS_ERR_INPUT, "surface map: invalid field %d", field);
        return NULL;
    }
    const int nx = g->nx, ny = g->ny;
    const size_t nc = (size_t)nx * (size_t)ny;
    ss_image *img = ss_image_create(nx, ny, 1, err);
    float *vf = calloc(2 * nc, sizeof *vf);
    if (!img || !vf) {
        ss_image_free(img);
        free(vf);
        if (img) ss_error_set(err, SS_ERR_NOMEM, "surface map: out of memory");
        return NULL;
    }
    ss_heal_surface_scan(g, field, mode, 0, g->nz, 0, g->nz, vf, vf + nc);
    ss_heal_surface_image(vf, nx, ny, img->data);
    free(vf);
    return img;
}

void ss_heal_surface_image(const float *v, int nx, int ny, float *out) {
    for (int y = 0; y < ny; y++)
        memcpy(out + (size_t)(ny - 1 - y) * (size_t)nx, v + (size_t)y * (size_t)nx,
               (size_t)nx * sizeof *out);
}

/* ---- closure day per column ---------------------------------------------------------- */

/* The epithelial layer of column (x, y): the larger value of its two topmost
 * tissue cells (the SS_SURFACE_LAYER rule above); -1 for a column of air. */
static float column_layer(const ss_heal_grid *g, int x, int y) {
    const float *e = g->field[SS_HEAL_EPITHELIUM];
    float v = -1;
    int found = 0;
    for (int z = g->nz - 1; z >= 0 && found < 2; z--) {
        size_t i = ss_heal_idx(g, x, y, z);
        if (g->cell[i] == SS_CELL_AIR ||
            (g->cell[i] == SS_CELL_BOUND &&
             (z == 0 || z == g->nz - 1 || (z + 0.5) * g->dx_mm > g->skin_top_mm)))
            continue;
        if (!found || e[i] > v) v = e[i];
        found++;
    }
    return v;
}

void ss_heal_closure_update(const ss_heal_grid *g, double *closed) {
    const float thr = (float)ss_heal_open_threshold();
#pragma omp parallel for schedule(static) if (g->nx * g->ny > 16384)
    for (int y = 0; y < g->ny; y++)
        for (int x = 0; x < g->nx; x++) {
            float v = column_layer(g, x, y);
            double *c = &closed[(size_t)y * (size_t)g->nx + (size_t)x];
            if (v < 0) continue; /* air only: stays as it is */
            if (v < thr)
                *c = SS_HEAL_CLOSED_OPEN;
            else if (*c == SS_HEAL_CLOSED_OPEN)
                *c = g->t_days;
        }
}

void ss_heal_closure_scan(const ss_heal_grid *g, int zoff, int gz, float *v, float *found) {
    const float *e = g->field[SS_HEAL_EPITHELIUM];
    for (int y = 0; y < g->ny; y++)
        for (int x = 0; x < g->nx; x++) {
            const size_t k = (size_t)y * (size_t)g->nx + (size_t)x;
            for (int z = g->nz - 2; z >= 1 && found[k] < 2; z--) {
                const size_t i = ss_heal_idx(g, x, y, z);
                const int Z = z + zoff;
                if (g->cell[i] == SS_CELL_AIR ||
                    (g->cell[i] == SS_CELL_BOUND &&
                     (Z == 0 || Z == gz - 1 || (Z + 0.5) * g->dx_mm > g->skin_top_mm)))
                    continue;
                if (!found[k] || e[i] > v[k]) v[k] = e[i];
                found[k]++;
            }
        }
}

void ss_heal_closure_apply(const ss_heal_grid *g, const float *v, double *closed) {
    const float thr = (float)ss_heal_open_threshold();
    for (size_t k = 0; k < (size_t)g->nx * (size_t)g->ny; k++) {
        if (v[k] < 0) continue; /* air only: stays as it is */
        if (v[k] < thr)
            closed[k] = SS_HEAL_CLOSED_OPEN;
        else if (closed[k] == SS_HEAL_CLOSED_OPEN)
            closed[k] = g->t_days;
    }
}

void ss_heal_closure_init(const ss_heal_grid *g, double *closed) {
    for (size_t i = 0; i < (size_t)g->nx * (size_t)g->ny; i++) closed[i] = SS_HEAL_CLOSED_INTACT;
    ss_heal_closure_update(g, closed);
}
