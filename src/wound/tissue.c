/* The tissue at the skin surface, per grid column (seed 001 §5.4: "we map the
 * simulated fields back onto the ... mesh"): the epithelial layer, capillary
 * density and oxygen at the surface, the wound region (plasma, §4.1.8), the
 * eschar and the collagen above the keloid threshold integrated over the
 * column, the scar density maximum, the §5.4 wound depth (surface down to the
 * height where capillaries reach a threshold, interpolated between cells so it
 * does not step with the voxels), and the time since each column's epithelium
 * closed (the age of the new tissue, which no field holds: the tracker learns
 * it by observing the run).
 *
 * Design: the maps are at grid resolution (cheap to update every step); the
 * renderer samples them bilinearly at texel resolution. Columns use the same
 * tissue rule as ss_heal_surface_map (skip air and the boundary layers), so the
 * maps equal heal's surface PNGs where both exist. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/heal_io.h"
#include "skinsim/wound.h"

ss_wound_tissue *ss_wound_tissue_create(const ss_heal_grid *g, const ss_heal_params *p,
                                        const ss_wound_recipe *r, ss_error *err) {
    ss_wound_tissue *t = calloc(1, sizeof *t);
    if (!t) {
        ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        return NULL;
    }
    t->nx = g->nx;
    t->ny = g->ny;
    t->dx_mm = g->dx_mm;
    size_t n = (size_t)g->nx * (size_t)g->ny;
    float **maps[] = {&t->epithelium, &t->capillary, &t->oxygen,   &t->plasma,   &t->scab_mm,
                      &t->scar,       &t->keloid_mm, &t->depth_mm, &t->age_days, &t->elevation_mm};
    int ok = 1;
    for (size_t k = 0; k < sizeof maps / sizeof *maps; k++) ok &= !!(*maps[k] = calloc(n, 4));
    ok &= !!(t->closed_day = malloc(n * sizeof *t->closed_day));
    if (!ok) {
        ss_wound_tissue_free(t);
        ss_error_set(err, SS_ERR_NOMEM, "out of memory (tissue maps)");
        return NULL;
    }
    float healthy[SS_HEAL_NFIELDS];
    ss_heal_params_healthy(p, healthy);
    t->u3_eq = healthy[SS_HEAL_CAPILLARY] > 0 ? healthy[SS_HEAL_CAPILLARY] : 1;
    t->u1_healthy = healthy[SS_HEAL_OXYGEN] > 0 ? healthy[SS_HEAL_OXYGEN] : 1;
    t->rho_max = (float)p->rho_max;
    t->threshold = r->v[SS_WR_CAPILLARY_THRESHOLD];
    t->scab_min = (float)r->v[SS_WR_SCAB_MIN_DENSITY];
    for (size_t i = 0; i < n; i++) t->closed_day[i] = -INFINITY; /* intact until seen open */
    ss_wound_tissue_observe(t, g);
    return t;
}

void ss_wound_tissue_free(ss_wound_tissue *t) {
    if (!t) return;
    free(t->epithelium);
    free(t->capillary);
    free(t->oxygen);
    free(t->plasma);
    free(t->scab_mm);
    free(t->scar);
    free(t->keloid_mm);
    free(t->elevation_mm);
    free(t->depth_mm);
    free(t->age_days);
    free(t->closed_day);
    free(t);
}

static int is_tissue(const ss_heal_grid *g, size_t i, int z) {
    uint8_t c = g->cell[i];
    return !(c == SS_CELL_AIR || (c == SS_CELL_BOUND && (z == 0 || z == g->nz - 1 ||
                                                         (z + 0.5) * g->dx_mm > g->skin_top_mm)));
}

/* §5.4 depth: from the skin surface down to where the capillary density
 * (relative to healthy) first reaches the threshold, scanning down from the
 * top tissue cell; linear between cell centres. */
static float column_depth(const ss_heal_grid *g, const ss_wound_tissue *t, int x, int y, int ztop) {
    const float *u3 = g->field[SS_HEAL_CAPILLARY];
    double thr = t->threshold, dx = g->dx_mm;
    double prev = -1, zc_prev = 0;
    for (int z = ztop; z >= 1; z--) {
        size_t i = ss_heal_idx(g, x, y, z);
        if (!is_tissue(g, i, z)) break;
        double c = u3[i] / t->u3_eq, zc = (z + 0.5) * dx;
        if (c >= thr) {
            if (prev < 0) return 0; /* the top cell is vascular: no depth */
            double f = (thr - prev) / (c - prev);
            double zcross = zc_prev + f * (zc - zc_prev);
            double d = g->skin_top_mm - zcross - 0.5 * dx;
            return d > 0 ? (float)d : 0;
        }
        prev = c;
        zc_prev = zc;
    }
    return (float)(g->skin_top_mm - dx); /* no vascular tissue: the whole column */
}

static void observe(ss_wound_tissue *t, const ss_heal_grid *g, const double *closed);

void ss_wound_tissue_observe(ss_wound_tissue *t, const ss_heal_grid *g) { observe(t, g, NULL); }

void ss_wound_tissue_observe_closure(ss_wound_tissue *t, const ss_heal_grid *g,
                                     const double *closed_day) {
    observe(t, g, closed_day);
}

static void observe(ss_wound_tissue *t, const ss_heal_grid *g, const double *closed) {
    const int nx = g->nx, ny = g->ny, nz = g->nz;
    /* the surface elevation, as heal computes and writes it (its snapshots'
     * surface_elevation_mm), from the same grid: grid rows, then flipped
     * into image orientation */
    memset(t->elevation_mm, 0, (size_t)nx * (size_t)ny * sizeof(float));
    ss_heal_elevation_scan(g, 0, nz, t->elevation_mm);
    for (int y = 0; y < ny / 2; y++) {
        float *a = t->elevation_mm + (size_t)y * nx,
              *b = t->elevation_mm + (size_t)(ny - 1 - y) * nx;
        for (int x = 0; x < nx; x++) {
            float tmp = a[x];
            a[x] = b[x];
            b[x] = tmp;
        }
    }
    const float *e = g->field[SS_HEAL_EPITHELIUM], *u3 = g->field[SS_HEAL_CAPILLARY],
                *u1 = g->field[SS_HEAL_OXYGEN], *pl = g->field[SS_HEAL_PLASMA],
                *s = g->field[SS_HEAL_ESCHAR], *rho = g->field[SS_HEAL_SCAR];
    const double day = g->t_days, dx = g->dx_mm;
    t->day = day;
#pragma omp parallel for schedule(static) if (nx * ny > 16384)
    for (int y = 0; y < ny; y++) {
        for (int x = 0; x < nx; x++) {
            size_t o = (size_t)(ny - 1 - y) * (size_t)nx + (size_t)x;
            int ztop = -1, nlayer = 0;
            float ev = 0, scar = 0;
            double scab = 0, kel = 0;
            for (int z = nz - 1; z >= 0; z--) {
                size_t i = ss_heal_idx(g, x, y, z);
                if (!is_tissue(g, i, z)) continue;
                if (ztop < 0) ztop = z;
                if (nlayer < 2 && (nlayer == 0 || e[i] > ev)) ev = e[i];
                nlayer++;
                /* dense eschar is the crust: a ramp of +-0.2 around scab_min */
                float f = (s[i] - t->scab_min + 0.2f) / 0.4f;
                f = f < 0 ? 0 : f > 1 ? 1 : f;
                scab += f * f * (3 - 2 * f) * s[i] * dx;
                if (rho[i] > scar) scar = rho[i];
                if (rho[i] > t->rho_max) kel += (rho[i] / t->rho_max - 1) * dx;
            }
            if (ztop < 0) { /* a column of air only */
                t->epithelium[o] = 1, t->capillary[o] = 1, t->oxygen[o] = 1;
                t->plasma[o] = t->scab_mm[o] = t->scar[o] = t->keloid_mm[o] = t->depth_mm[o] = 0;
                t->age_days[o] = SS_WOUND_AGE_INTACT;
                continue;
            }
            size_t it = ss_heal_idx(g, x, y, ztop);
            t->epithelium[o] = ev;
            t->capillary[o] = u3[it] / t->u3_eq;
            t->oxygen[o] = u1[it] / t->u1_healthy;
            t->plasma[o] = pl[it];
            t->scab_mm[o] = (float)scab;
            t->scar[o] = scar;
            t->keloid_mm[o] = (float)kel;
            t->depth_mm[o] = column_depth(g, t, x, y, ztop);
            /* closure tracking: open (e < 0.5) sets +inf; the first observation
             * at or above 0.5 after that records the day */
            if (closed) { /* the heal run's own record */
                double c = closed[(size_t)y * (size_t)nx + (size_t)x];
                t->closed_day[o] = c == SS_HEAL_CLOSED_OPEN     ? INFINITY
                                   : c == SS_HEAL_CLOSED_INTACT ? -INFINITY
                                                                : c;
            } else if (ev < 0.5f) {
                t->closed_day[o] = INFINITY;
            } else if (t->closed_day[o] == INFINITY) {
                t->closed_day[o] = day;
            }
            double cd = t->closed_day[o];
            t->age_days[o] = cd == -INFINITY  ? SS_WOUND_AGE_INTACT
                             : cd == INFINITY ? 0.0f
                                              : (float)(day - cd);
        }
    }
}

ss_image *ss_wound_deformation_from_grid(const ss_heal_grid *g, float *const *disp, int size,
                                         ss_error *err) {
    const int nx = g->nx, ny = g->ny;
    /* the surface displacement per column, image orientation (row 0 = grid y ny-1) */
    float *col = malloc((size_t)nx * (size_t)ny * 3 * sizeof *col);
    ss_image *out = col ? ss_image_create(size, size, 3, err) : NULL;
    if (!out) {
        free(col);
        if (!err->code) ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        return NULL;
    }
    for (int y = 0; y < ny; y++)
        for (int x = 0; x < nx; x++) {
            float *c = col + ((size_t)(ny - 1 - y) * (size_t)nx + (size_t)x) * 3;
            c[0] = c[1] = c[2] = 0;
            for (int z = g->nz - 1; z >= 0; z--) {
                size_t i = ss_heal_idx(g, x, y, z);
                if (!is_tissue(g, i, z)) continue;
                for (int k = 0; k < 3; k++) c[k] = disp[k] ? disp[k][i] : 0;
                break;
            }
        }
#pragma omp parallel for schedule(static)
    for (int ty = 0; ty < size; ty++)
        for (int tx = 0; tx < size; tx++) {
            double mx = (tx + 0.5) / size * nx - 0.5, my = (ty + 0.5) / size * ny - 0.5;
            mx = mx < 0 ? 0 : mx > nx - 1 ? nx - 1 : mx;
            my = my < 0 ? 0 : my > ny - 1 ? ny - 1 : my;
            int x0 = (int)mx, y0 = (int)my, x1 = x0 + 1 < nx ? x0 + 1 : x0,
                y1 = y0 + 1 < ny ? y0 + 1 : y0;
            double fx = mx - x0, fy = my - y0;
            for (int k = 0; k < 3; k++) {
                double a = col[((size_t)y0 * nx + x0) * 3 + k],
                       b = col[((size_t)y0 * nx + x1) * 3 + k],
                       c = col[((size_t)y1 * nx + x0) * 3 + k],
                       d = col[((size_t)y1 * nx + x1) * 3 + k];
                out->data[((size_t)ty * size + tx) * 3 + k] =
                    (float)((1 - fy) * ((1 - fx) * a + fx * b) + fy * ((1 - fx) * c + fx * d));
            }
        }
    free(col);
    return out;
}
