/* The clinical course of a centred square wound (seed 001 §6 scenarios):
 * runs the §4.1 model with the split scheme and reduces the run to the
 * figures docs/heal-model.md calibrates against: days to 50 % and 95 %
 * closure, scab formation and detachment, scar volume peak and remodelling
 * half-life, epithelium below the surface, keloid extent beyond the original
 * margin. One function so the tests, bench_heal_course and the convergence
 * and sensitivity tables (bench/heal_tables.sh) measure the same thing.
 * Samples every step; the closure times interpolate linearly between steps. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/heal.h"

typedef struct sample {
    double t, area, eschar, vol, exc;
} sample;

static int tissue(uint8_t c) { return c != SS_CELL_AIR && c != SS_CELL_BOUND; }

static double deep_fraction(const ss_heal_grid *g) {
    long deep = 0, hit = 0;
    const float *e = g->field[SS_HEAL_EPITHELIUM];
    for (int z = 1; z < g->nz - 1; z++) {
        double depth = g->skin_top_mm - (z + 0.5) * g->dx_mm;
        if (depth <= 0.5) continue;
        for (int y = 1; y < g->ny - 1; y++)
            for (int x = 1; x < g->nx - 1; x++) {
                size_t i = ss_heal_idx(g, x, y, z);
                if (!tissue(g->cell[i])) continue;
                deep++;
                hit += e[i] > 0.5f;
            }
    }
    return deep ? (double)hit / (double)deep : 0.0;
}

/* The scar collagen above the mature scar's (the part remodelling resorbs,
 * docs/heal-model.md [D10]): the integral of (rho - rho_mature)+, mm^3. */
static double scar_excess(const ss_heal_grid *g, double rho_mature) {
    const float *rho = g->field[SS_HEAL_SCAR];
    const float rm = (float)rho_mature;
    const size_t n = (size_t)g->nx * (size_t)g->ny * (size_t)g->nz;
    double sum = 0;
    for (size_t i = 0; i < n; i++)
        if (tissue(g->cell[i]) && rho[i] > rm) sum += (double)(rho[i] - rm);
    return sum * g->dx_mm * g->dx_mm * g->dx_mm;
}

static float colmax_scar(const ss_heal_grid *g, int x, int y) {
    float m = 0;
    for (int z = 1; z < g->nz - 1; z++) {
        size_t i = ss_heal_idx(g, x, y, z);
        if (tissue(g->cell[i]) && g->field[SS_HEAL_SCAR][i] > m) m = g->field[SS_HEAL_SCAR][i];
    }
    return m;
}

/* Mean advance of scar > thr beyond the margin along the four mid-edge lines. */
static double keloid_beyond(const ss_heal_grid *g, double wound_mm, double thr, double *area) {
    const int cx = g->nx / 2, cy = g->ny / 2;
    const double half = 0.5 * wound_mm, c0x = 0.5 * g->nx * g->dx_mm, c0y = 0.5 * g->ny * g->dx_mm;
    double sum = 0;
    for (int d = 0; d < 4; d++) {
        double adv = 0;
        int dx = d == 0 ? 1 : d == 1 ? -1 : 0, dy = d == 2 ? 1 : d == 3 ? -1 : 0;
        for (int k = 0;; k++) {
            int x = cx + dx * k, y = cy + dy * k;
            if (x < 1 || y < 1 || x > g->nx - 2 || y > g->ny - 2) break;
            double r = dx ? fabs((x + 0.5) * g->dx_mm - c0x) : fabs((y + 0.5) * g->dx_mm - c0y);
            if (colmax_scar(g, x, y) <= thr) {
                if (r > half) break;
                continue;
            }
            double outer = r + 0.5 * g->dx_mm - half;
            if (outer > adv) adv = outer;
        }
        sum += adv;
    }
    if (area) {
        double a = 0;
        for (int y = 1; y < g->ny - 1; y++)
            for (int x = 1; x < g->nx - 1; x++)
                if (colmax_scar(g, x, y) > thr) a += g->dx_mm * g->dx_mm;
        *area = a;
    }
    return 0.25 * sum;
}

static double cross(const sample *s, int n, double level, int from) {
    for (int i = from; i < n; i++)
        if (s[i].area <= level) {
            if (i == 0) return s[0].t;
            double f = s[i - 1].area != s[i].area
                           ? (s[i - 1].area - level) / (s[i - 1].area - s[i].area)
                           : 1.0;
            return s[i - 1].t + f * (s[i].t - s[i - 1].t);
        }
    return -1.0;
}

ss_status ss_heal_course_run(const ss_heal_params *p, const ss_heal_course_opts *o,
                             ss_heal_course *c, ss_error *err) {
    memset(c, 0, sizeof *c);
    c->t50 = c->t95 = c->scab_day = c->scab_gone_day = -1;
    if (!p || !o || !(o->dx_mm > 0) || !(o->block_mm > o->wound_mm) || !(o->wound_mm > 0) ||
        !(o->days > 0))
        return ss_error_set(err, SS_ERR_INPUT, "heal course: bad options");
    const double dx = o->dx_mm, top = 3.0;
    int n = (int)lround(o->block_mm / dx), nz = (int)lround(4.0 / dx);
    ss_heal_grid *g = ss_heal_grid_create(n, n, nz, dx, err);
    if (!g) return err->code;
    /* the keloid keeps whole-voxel depths (docs/heal-model.md [D15]) */
    int32_t *cols =
        ss_heal_wound_columns_box(n, n, nz, dx, top, o->wound_mm, o->wound_mm, o->depth_mm, err);
    if (cols && !ss_heal_wound_subvoxel(p)) ss_heal_wound_columns_whole(cols, (size_t)n * n);
    const int gdim[3] = {n, n, nz}, lo[3] = {0, 0, 0};
    uint8_t *w = cols ? ss_heal_wound_columns_expand(cols, gdim, lo, gdim, err) : NULL;
    free(cols);
    ss_status st =
        w ? ss_heal_grid_init(g, top, SS_HEAL_DEFAULT_EPIDERMIS_MM, w, p, err) : err->code;
    free(w);
    const double dt0 = o->dt_days > 0 ? o->dt_days : SS_HEAL_SPLIT_DEFAULT_DT_DAYS;
    ss_heal_solver *s = st ? NULL : ss_heal_solver_create(g, p, SS_HEAL_SPLIT, dt0, err);
    if (!s) {
        ss_heal_grid_free(g);
        return st ? st : err->code;
    }
    long cap = (long)ceil(o->days / dt0) + 16;
    sample *sm = malloc((size_t)cap * sizeof *sm);
    if (!sm) {
        ss_heal_solver_free(s);
        ss_heal_grid_free(g);
        return ss_error_set(err, SS_ERR_NOMEM, "heal course: out of memory");
    }
    double t0 = ss_now();
    ss_heal_stats stt;
    ss_heal_stats_compute(g, &stt);
    /* the crust's share of its layer, also on voxels coarser than it [D14] */
    const double cshare = ss_heal_crust_voxel_share(p, dx);
    stt.eschar_wound_mean /= cshare;
    const double a0 = stt.initial_area_mm2;
    int ns = 0;
    sm[ns++] = (sample){0, 1, stt.eschar_wound_mean, stt.scar_volume_mm3, 0};
    int late = 0, deep_done = o->deep_check_day < 0, kday_done[2] = {0, 0};
    while (g->t_days < o->days - 1e-9 && !st) {
        double dt = ss_heal_solver_dt(s);
        if (g->t_days + dt > o->days + 1e-9)
            st = ss_heal_solver_set_dt(s, o->days - g->t_days, err);
        if (!st) st = ss_heal_step(s, g, err);
        if (st) break;
        c->steps++;
        if (!deep_done && g->t_days >= o->deep_check_day - 1e-9) {
            c->deep_e_fraction = deep_fraction(g);
            deep_done = 1;
        }
        ss_heal_stats_compute(g, &stt);
        stt.eschar_wound_mean /= cshare;
        if (ns == cap) break;
        sample *q = &sm[ns++];
        *q = (sample){g->t_days, a0 > 0 ? stt.open_area_mm2 / a0 : 0, stt.eschar_wound_mean,
                      stt.scar_volume_mm3, scar_excess(g, p->rho_mature)};
        if (c->scab_day < 0 && q->eschar > 0.5) c->scab_day = q->t;
        if (stt.scar_volume_mm3 > c->scar_peak_mm3) {
            c->scar_peak_mm3 = stt.scar_volume_mm3;
            c->scar_peak_day = g->t_days;
        }
        if (stt.scar_max > c->scar_max_peak) c->scar_max_peak = stt.scar_max;
        if (stt.elevation_max_mm > c->elev_max_mm) {
            c->elev_max_mm = stt.elevation_max_mm;
            c->elev_max_day = g->t_days;
        }
        if (o->keloid_thr > 0) {
            const double kb = keloid_beyond(g, o->wound_mm, o->keloid_thr, NULL);
            if (kb > c->keloid_beyond_max) c->keloid_beyond_max = kb;
            for (int k = 0; k < 2; k++)
                if (o->keloid_day[k] > 0 && !kday_done[k] && g->t_days >= o->keloid_day[k] - 1e-9) {
                    c->keloid_beyond_day[k] = kb;
                    kday_done[k] = 1;
                }
        }
        if (c->t95 < 0) {
            c->t95 = cross(sm, ns, 0.05, 0);
            if (c->t95 >= 0 && o->keloid_thr > 0)
                c->keloid_beyond_t95 = keloid_beyond(g, o->wound_mm, o->keloid_thr, NULL);
        }
        if (c->t95 >= 0 && c->scab_gone_day < 0 && q->eschar < 0.05) c->scab_gone_day = q->t;
        /* the slow phase: closed, no scab, past the fast transients */
        if (!late && o->late_dt_days > dt0 && c->t95 >= 0 && q->eschar < 0.05 &&
            g->t_days > c->t95 + 5.0) {
            st = ss_heal_solver_set_dt(s, o->late_dt_days, err);
            late = 1;
        } else if (!late && g->t_days + dt0 <= o->days + 1e-9 && ss_heal_solver_dt(s) != dt0) {
            st = ss_heal_solver_set_dt(s, dt0, err);
        }
    }
    if (!st) {
        size_t ncell = (size_t)g->nx * (size_t)g->ny * (size_t)g->nz;
        c->bounds_ok = 1;
        for (int f = 0; f < SS_HEAL_NFIELDS; f++) {
            const float hi = f == SS_HEAL_ESCHAR || f == SS_HEAL_EPITHELIUM || f == SS_HEAL_PLASMA
                                 ? 1.0f
                                 : INFINITY;
            for (size_t i = 0; i < ncell; i++)
                if (!(g->field[f][i] >= 0.0f && g->field[f][i] <= hi)) c->bounds_ok = 0;
        }
        c->t50 = cross(sm, ns, 0.5, 0);
        c->scar_end_mm3 = stt.scar_volume_mm3;
        c->scar_max_end = stt.scar_max;
        c->elev_end_max_mm = stt.elevation_max_mm;
        c->elev_end_mean_mm = stt.elevation_mean_mm;
        for (int z = 1; z < g->nz - 1; z++) { /* below the keloid's layer */
            if (top - (z + 1) * dx < p->keloid_mm - 1e-9) continue;
            for (int y = 1; y < g->ny - 1; y++)
                for (int x = 1; x < g->nx - 1; x++) {
                    const size_t i = ss_heal_idx(g, x, y, z);
                    const float r = g->field[SS_HEAL_SCAR][i];
                    if (tissue(g->cell[i]) && r > c->scar_deep_max) c->scar_deep_max = r;
                }
        }
        c->region_area_mm2 = stt.wound_region_area_mm2;
        /* remodelling: decay of the scar collagen above the mature scar's over the
         * last quarter, after the peak (the mature part stays, [D10]) */
        double ta = 0.75 * o->days;
        if (ta < c->scar_peak_day) ta = c->scar_peak_day;
        int ia = 0;
        while (ia < ns - 1 && sm[ia].t < ta) ia++;
        const sample *A = &sm[ia], *B = &sm[ns - 1];
        if (B->t - A->t > 1.0 && A->exc > 0 && B->exc > 0) {
            double rate = log(A->exc / B->exc) / (B->t - A->t);
            c->half_life_days = rate > 0 ? log(2.0) / rate : -1;
        }
        if (o->keloid_thr > 0)
            c->keloid_beyond_mm = keloid_beyond(g, o->wound_mm, o->keloid_thr, &c->keloid_area_mm2);
    }
    c->wall_s = ss_now() - t0;
    free(sm);
    ss_heal_solver_free(s);
    ss_heal_grid_free(g);
    return st;
}
