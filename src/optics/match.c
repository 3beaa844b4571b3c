/* Colour -> biology (`skinsim optics match`): the biological parameters whose
 * rendered skin colour is closest, in CIEDE2000, to a target colour.
 *
 * Design:
 * 1. Table stage: the ModelMatch table's albedo (diffuse reflectance at normal
 *    incidence, linear sRGB) is interpolated over a grid of all six axes
 *    (every node and the midpoints between nodes); the best cell starts a
 *    bounded Nelder-Mead search on the interpolated table.
 * 2. Transport stage: at the thicknesses found, photon paths are traced once
 *    per wavelength without absorption (ss_mc_trace_paths) and Nelder-Mead
 *    varies melanin, pheomelanin ratio, blood and oxygenation with the albedo
 *    recomputed exactly by reweighting (ss_mc_paths_apply) - the same
 *    transport the table was built with, without its interpolation error.
 * 3. Geometry: with SCI (default) the compared colour is the albedo plus the
 *    rough surface's reflectance at normal incidence, a spectrally flat
 *    constant (n of the stratum corneum does not vary with wavelength in the
 *    model) estimated once from surface walks alone; SCE compares the albedo.
 *    Measured skin colours (colorimeters, d:8 spectrophotometers in SCI mode,
 *    photos) include the light the surface scatters; the albedo does not.
 * 4. The objective is Delta-E00 plus prior_weight x a population prior
 *    (prior_nlog below: measured pheomelanin share, oxygenation, layer
 *    thicknesses and blood; none on melanin), so that among near-equal
 *    colours the biology people have wins: at the default weight 0.05 a
 *    parameter 3 sd from its mean costs 0.22 Delta-E00, 5 sd 0.63.
 * 5. Uniqueness: every grid point of stage 1 keeps its colour difference
 *    (without the prior); the grid point within SS_MM_MATCH_TOL of the
 *    answer's Delta-E00 that lies farthest from the answer (pigment axes in
 *    units of their range) is reported, and the answer is not unique when
 *    that distance exceeds SS_MM_MATCH_FAR.
 * Deterministic: fixed grids, fixed seed, fixed iteration counts. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "optics_internal.h"
#include "skinsim/optics_fit.h"

void ss_mm_match_options_default(ss_mm_match_options *o) {
    memset(o, 0, sizeof *o);
    ss_spectrum_options_default(&o->spectrum);
    o->spectrum.wl_min_nm = 400;
    o->spectrum.wl_max_nm = 700;
    o->spectrum.wl_step_nm = 20;
    o->spectrum.mc.photons = 20000;
    o->refine = 1;
    o->prior_weight = SS_MM_PRIOR_WEIGHT;
}

typedef struct match_ctx {
    const ss_mm_table *t;
    double target[3];
    double surface; /* added to every channel before comparing (SCI) */
    double lo[SS_MM_NAXES], hi[SS_MM_NAXES], def[SS_MM_NAXES];
    double prior;
    /* transport stage */
    int nwl;
    double *wl;
    ss_mc_paths **paths;
    const ss_optics_data *data;
    ss_bio_params base;
    double *refl;
    ss_status st;
    ss_error *err;
} match_ctx;

static double clampd(double v, double lo, double hi) { return v < lo ? lo : v > hi ? hi : v; }

/* The population prior, as -log density (a sum of z^2 / 2), times
 * prior_weight (Delta-E00 per unit): colour alone leaves a valley of
 * near-equal fits (more pheomelanin trades against more eumelanin and
 * blood), and the prior picks the biology people have. Means and spreads
 * (docs/optics.md): pheomelanin share 0.26 (Del Bino et al. 2015, about
 * 26 % pheomelanin in the epidermis of every skin type, light to dark), sd
 * 0.1; oxygenation 0.75 sd 0.1 (dermal blood between arterial and venous);
 * stratum corneum and epidermis thickness log-normal around the model's
 * 10 um and 100 um (Sandby-Moller et al. 2003: the epidermis of most body
 * sites 50-110 um) with 40 % and 30 % spread; blood log-normal around 0.5 %
 * (Jacques 1998: dermal average 0.2-1 %) with a factor e spread. Melanin
 * has none: the tone is the colour's to decide. */
#define PRIOR_PHEO_MEAN 0.26
#define PRIOR_PHEO_SD 0.10
#define PRIOR_OXY_MEAN 0.75
#define PRIOR_OXY_SD 0.10
#define PRIOR_SC_LOGSD 0.4
#define PRIOR_EPI_LOGSD 0.3
#define PRIOR_BLOOD_MEAN 0.005
#define PRIOR_BLOOD_LOGSD 1.0
static double prior_nlog(const match_ctx *c, const double x[SS_MM_NAXES]) {
    double z[5];
    z[0] = (x[SS_MM_AXIS_PHEOMELANIN] - PRIOR_PHEO_MEAN) / PRIOR_PHEO_SD;
    z[1] = (x[SS_MM_AXIS_OXYGENATION] - PRIOR_OXY_MEAN) / PRIOR_OXY_SD;
    z[2] = log(fmax(x[SS_MM_AXIS_SC], 1e-6) / c->def[SS_MM_AXIS_SC]) / PRIOR_SC_LOGSD;
    z[3] =
        log(fmax(x[SS_MM_AXIS_EPIDERMIS], 1e-6) / c->def[SS_MM_AXIS_EPIDERMIS]) / PRIOR_EPI_LOGSD;
    z[4] = log(fmax(x[SS_MM_AXIS_BLOOD], 1e-6) / PRIOR_BLOOD_MEAN) / PRIOR_BLOOD_LOGSD;
    double p = 0.0;
    for (int k = 0; k < 5; k++) p += 0.5 * z[k] * z[k];
    return p;
}

static double prior_pen(const match_ctx *c, const double x[SS_MM_NAXES]) {
    return c->prior * prior_nlog(c, x);
}

static double de_of_rgb(const match_ctx *c, const double rgb[3]) {
    double lab[3], v[3] = {rgb[0] + c->surface, rgb[1] + c->surface, rgb[2] + c->surface};
    ss_srgb_linear_to_lab(v, lab);
    return ss_ciede2000(lab, c->target);
}

static double table_obj(match_ctx *c, const double x[SS_MM_NAXES]) {
    double v[SS_MM_NFIELDS];
    ss_mm_table_lookup(c->t, x, v);
    return de_of_rgb(c, v + 15) + prior_pen(c, x);
}

/* Albedo by the traced paths for the four absorption parameters x (melanin,
 * pheomelanin, blood, oxygenation). */
static int transport_rgb(match_ctx *c, const double x[4], double rgb[3]) {
    ss_bio_params b = c->base;
    b.melanin = x[0];
    b.pheomelanin_ratio = x[1];
    b.blood = x[2];
    b.oxygenation = x[3];
    for (int k = 0; k < c->nwl; k++) {
        ss_optics_slab s;
        ss_mc_result r;
        if ((c->st = ss_optics_skin_slab_with(c->data, &b, c->wl[k], &s, c->err))) return -1;
        double mua[SS_OPTICS_MAX_LAYERS];
        for (int l = 0; l < s.nlayers; l++) mua[l] = s.layer[l].mua_per_cm;
        if ((c->st = ss_mc_paths_apply(c->paths[k], mua, &r, c->err))) return -1;
        c->refl[k] = r.diffuse;
        ss_mc_result_free(&r);
    }
    if ((c->st = ss_spectrum_to_srgb_linear_with(c->data, c->wl, c->refl, c->nwl, rgb, c->err)))
        return -1;
    return 0;
}

static const int TR_AX[4] = {SS_MM_AXIS_MELANIN, SS_MM_AXIS_PHEOMELANIN, SS_MM_AXIS_BLOOD,
                             SS_MM_AXIS_OXYGENATION};

static double transport_obj(match_ctx *c, const double x4[4]) {
    double rgb[3];
    if (c->st || transport_rgb(c, x4, rgb)) return HUGE_VAL;
    double x[SS_MM_NAXES] = {0};
    for (int k = 0; k < 4; k++) x[TR_AX[k]] = x4[k];
    x[SS_MM_AXIS_SC] = c->base.sc_thickness_cm;
    x[SS_MM_AXIS_EPIDERMIS] = c->base.epidermis_thickness_cm;
    return de_of_rgb(c, rgb) + prior_pen(c, x);
}

/* Bounded Nelder-Mead on n <= 6 variables scaled to [0,1] boxes; f(x) gets
 * the unscaled point. mode 0: table objective (6 axes), 1: transport (4). */
static double nelder_mead(match_ctx *c, int mode, int n, const double *lo, const double *hi,
                          double *x, int iters, double step) {
    double P[7][6], F[7], u[6];
    for (int i = 0; i <= n; i++) {
        for (int k = 0; k < n; k++) {
            double s = hi[k] > lo[k] ? (x[k] - lo[k]) / (hi[k] - lo[k]) : 0.0;
            P[i][k] = s + (i == k + 1 ? (s + step <= 1.0 ? step : -step) : 0.0);
        }
    }
#define EVAL(pt, out)                                                                              \
    do {                                                                                           \
        for (int k_ = 0; k_ < n; k_++)                                                             \
            u[k_] = lo[k_] + clampd((pt)[k_], 0, 1) * (hi[k_] - lo[k_]);                           \
        (out) = mode ? transport_obj(c, u) : table_obj(c, u);                                      \
    } while (0)
    for (int i = 0; i <= n; i++) EVAL(P[i], F[i]);
    for (int it = 0; it < iters; it++) {
        /* order */
        for (int i = 1; i <= n; i++)
            for (int j = i; j > 0 && F[j] < F[j - 1]; j--) {
                double tf = F[j];
                F[j] = F[j - 1];
                F[j - 1] = tf;
                for (int k = 0; k < n; k++) {
                    double tp = P[j][k];
                    P[j][k] = P[j - 1][k];
                    P[j - 1][k] = tp;
                }
            }
        if (F[n] - F[0] < 1e-7) break;
        double cen[6] = {0}, xr[6], xe[6], fr, fe;
        for (int i = 0; i < n; i++)
            for (int k = 0; k < n; k++) cen[k] += P[i][k] / n;
        for (int k = 0; k < n; k++) xr[k] = clampd(cen[k] + (cen[k] - P[n][k]), 0, 1);
        EVAL(xr, fr);
        if (fr < F[0]) {
            for (int k = 0; k < n; k++) xe[k] = clampd(cen[k] + 2.0 * (cen[k] - P[n][k]), 0, 1);
            EVAL(xe, fe);
            if (fe < fr) {
                memcpy(P[n], xe, sizeof xe);
                F[n] = fe;
            } else {
                memcpy(P[n], xr, sizeof xr);
                F[n] = fr;
            }
        } else if (fr < F[n - 1]) {
            memcpy(P[n], xr, sizeof xr);
            F[n] = fr;
        } else {
            for (int k = 0; k < n; k++) xe[k] = cen[k] + 0.5 * (P[n][k] - cen[k]);
            EVAL(xe, fe);
            if (fe < F[n]) {
                memcpy(P[n], xe, sizeof xe);
                F[n] = fe;
            } else {
                for (int i = 1; i <= n; i++) {
                    for (int k = 0; k < n; k++) P[i][k] = P[0][k] + 0.5 * (P[i][k] - P[0][k]);
                    EVAL(P[i], F[i]);
                }
            }
        }
        if (c->st) break;
    }
    int b = 0;
    for (int i = 1; i <= n; i++)
        if (F[i] < F[b]) b = i;
    for (int k = 0; k < n; k++) x[k] = lo[k] + clampd(P[b][k], 0, 1) * (hi[k] - lo[k]);
#undef EVAL
    return F[b];
}

/* Reflectance of the rough air/skin surface at normal incidence: the share of
 * Smith microsurface walks (the transport's own surface, mc.c) from air into
 * the stratum corneum that end reflected; Fresnel's ((n-1)/(n+1))^2 when
 * smooth. Deterministic (fixed seed and count). */
static double surface_reflectance(double sigma, uint64_t seed) {
    const double n_sc = 1.55; /* stratum corneum (tissue.c) */
    if (!(sigma > 0.0)) return ((n_sc - 1.0) / (n_sc + 1.0)) * ((n_sc - 1.0) / (n_sc + 1.0));
    const int nw = 200000;
    long refl = 0;
    for (int k = 0; k < nw; k++) {
        double w[3] = {0.0, 0.0, -1.0};
        int order;
        refl += !ss_ms_walk(sigma, 1.0, n_sc, w, seed, (uint64_t)k, &order);
    }
    return (double)refl / nw;
}

static void bio_from_x(const ss_bio_params *base, const double x[SS_MM_NAXES], ss_bio_params *b) {
    *b = *base;
    b->melanin = x[SS_MM_AXIS_MELANIN];
    b->pheomelanin_ratio = x[SS_MM_AXIS_PHEOMELANIN];
    b->blood = x[SS_MM_AXIS_BLOOD];
    b->oxygenation = x[SS_MM_AXIS_OXYGENATION];
    b->sc_thickness_cm = x[SS_MM_AXIS_SC];
    b->epidermis_thickness_cm = x[SS_MM_AXIS_EPIDERMIS];
}

/* The answer's prior penalty, and the farthest near-equal fit on the grid. */
/* Point q of the search grid: the table's nodes and the midpoints between
 * them on every axis (ng[a] = 2 x nodes - 1), the last axis fastest. */
static void search_point(const ss_mm_table *t, const int ng[SS_MM_NAXES], size_t q,
                         double x[SS_MM_NAXES]) {
    for (int a = SS_MM_NAXES - 1; a >= 0; a--) {
        int g = (int)(q % (size_t)ng[a]);
        q /= (size_t)ng[a];
        int i0 = g / 2;
        x[a] = (g % 2 == 0) ? t->axis[a][i0] : 0.5 * (t->axis[a][i0] + t->axis[a][i0 + 1]);
    }
}

static void finish(const match_ctx *c, const ss_mm_table *t, const int ng[SS_MM_NAXES],
                   size_t total, const float *gde, ss_mm_match_result *out) {
    double ax[SS_MM_NAXES] = {out->bio.melanin,         out->bio.pheomelanin_ratio,
                              out->bio.blood,           out->bio.oxygenation,
                              out->bio.sc_thickness_cm, out->bio.epidermis_thickness_cm};
    out->prior_penalty = prior_pen(c, ax);
    out->unique = 1;
    out->alt_distance = 0.0;
    out->alt_delta_e00 = out->delta_e00;
    out->alt_bio = out->bio;
    const double lim = out->delta_e00 + SS_MM_MATCH_TOL;
    double far = -1.0, fx[SS_MM_NAXES] = {0}, fde = 0.0;
    for (size_t q = 0; q < total; q++) {
        if (!(gde[q] <= lim)) continue;
        double x[SS_MM_NAXES];
        search_point(t, ng, q, x);
        double d2 = 0.0;
        for (int k = 0; k < 4; k++) {
            int a = TR_AX[k];
            double rg = c->hi[a] - c->lo[a];
            if (rg > 0) d2 += ((x[a] - ax[a]) / rg) * ((x[a] - ax[a]) / rg);
        }
        if (d2 > far) {
            far = d2;
            memcpy(fx, x, sizeof fx);
            fde = gde[q];
        }
    }
    if (far < 0) return;
    out->alt_distance = sqrt(far);
    out->alt_delta_e00 = fde;
    bio_from_x(&out->bio, fx, &out->alt_bio);
    out->unique = out->alt_distance <= SS_MM_MATCH_FAR;
}

ss_status ss_mm_match(const ss_mm_table *t, const double target_lab[3],
                      const ss_mm_match_options *o, ss_mm_match_result *out, ss_error *err) {
    if (!t || !target_lab || !o || !out)
        return ss_error_set(err, SS_ERR_INPUT, "match: table, target, options or output missing");
    memset(out, 0, sizeof *out);
    if (!(isfinite(target_lab[0]) && isfinite(target_lab[1]) && isfinite(target_lab[2]) &&
          target_lab[0] >= 0.0 && target_lab[0] <= 100.0 && fabs(target_lab[1]) <= 200.0 &&
          fabs(target_lab[2]) <= 200.0))
        return ss_error_set(err, SS_ERR_INPUT,
                            "target colour: L*a*b* (%g, %g, %g) is outside L* 0..100, |a*|, |b*| "
                            "<= 200",
                            target_lab[0], target_lab[1], target_lab[2]);
    match_ctx c;
    memset(&c, 0, sizeof c);
    c.t = t;
    c.err = err;
    c.prior = o->prior_weight >= 0.0 ? o->prior_weight : 0.0;
    if (o->geometry != SS_MM_GEOMETRY_SCI && o->geometry != SS_MM_GEOMETRY_SCE)
        return ss_error_set(err, SS_ERR_INPUT, "match: geometry %d is neither SCI (0) nor SCE (1)",
                            o->geometry);
    if (!(o->spectrum.mc.roughness_sigma >= 0.0 && o->spectrum.mc.roughness_sigma <= 10.0))
        return ss_error_set(err, SS_ERR_INPUT, "match: roughness %g is outside [0, 10]",
                            o->spectrum.mc.roughness_sigma);
    c.surface = o->geometry == SS_MM_GEOMETRY_SCI
                    ? surface_reflectance(o->spectrum.mc.roughness_sigma, o->spectrum.mc.seed)
                    : 0.0;
    out->surface = c.surface;
    memcpy(c.target, target_lab, sizeof c.target);
    ss_bio_params def;
    ss_bio_params_default(&def);
    double defx[SS_MM_NAXES] = {def.melanin,     def.pheomelanin_ratio, def.blood,
                                def.oxygenation, def.sc_thickness_cm,   def.epidermis_thickness_cm};
    for (int a = 0; a < SS_MM_NAXES; a++) {
        c.lo[a] = t->axis[a][0];
        c.hi[a] = t->axis[a][t->nsamples[a] - 1];
        c.def[a] = clampd(defx[a], c.lo[a], c.hi[a]);
    }
    /* 1. grid over nodes and midpoints of every axis */
    int ng[SS_MM_NAXES];
    size_t total = 1;
    for (int a = 0; a < SS_MM_NAXES; a++) {
        ng[a] = 2 * t->nsamples[a] - 1;
        total *= (size_t)ng[a];
    }
    double best = HUGE_VAL, bx[SS_MM_NAXES] = {0};
    float *gde = malloc(total * sizeof(float)); /* each grid point's Delta-E00 */
    if (!gde) return ss_error_set(err, SS_ERR_NOMEM, "match: out of memory");
    for (size_t q = 0; q < total; q++) {
        double x[SS_MM_NAXES];
        search_point(t, ng, q, x);
        double v0[SS_MM_NFIELDS];
        ss_mm_table_lookup(t, x, v0);
        double de = de_of_rgb(&c, v0 + 15), f = de + prior_pen(&c, x);
        gde[q] = (float)de;
        if (f < best) {
            best = f;
            memcpy(bx, x, sizeof bx);
        }
    }
    nelder_mead(&c, 0, SS_MM_NAXES, c.lo, c.hi, bx, 400, 0.05);
    double v[SS_MM_NFIELDS];
    ss_mm_table_lookup(t, bx, v);
    bio_from_x(o->base_set ? &o->base : &def, bx, &out->table_bio);
    memcpy(out->table_albedo_rgb, v + 15, sizeof out->table_albedo_rgb);
    double sv[3];
    for (int k = 0; k < 3; k++) sv[k] = out->table_albedo_rgb[k] + c.surface;
    ss_srgb_linear_to_lab(sv, out->table_lab);
    out->table_delta_e00 = ss_ciede2000(out->table_lab, target_lab);
    out->bio = out->table_bio;
    memcpy(out->albedo_rgb, out->table_albedo_rgb, sizeof out->albedo_rgb);
    memcpy(out->lab, out->table_lab, sizeof out->lab);
    out->delta_e00 = out->table_delta_e00;
    out->refined = 0;
    if (!o->refine) {
        finish(&c, t, ng, total, gde, out);
        free(gde);
        return SS_OK;
    }

    /* 2. transport refinement at the thicknesses found */
    ss_status st = SS_OK;
    ss_optics_data *data = NULL;
    int nwl = (int)floor((o->spectrum.wl_max_nm - o->spectrum.wl_min_nm) / o->spectrum.wl_step_nm +
                         1e-9) +
              1;
    if (!(o->spectrum.wl_step_nm > 0.0) || nwl < 2 || nwl > 1000) {
        st = ss_error_set(err, SS_ERR_INPUT, "match: wavelength range %g..%g step %g",
                          o->spectrum.wl_min_nm, o->spectrum.wl_max_nm, o->spectrum.wl_step_nm);
        goto done;
    }
    c.nwl = nwl;
    c.wl = calloc((size_t)nwl, sizeof(double));
    c.refl = calloc((size_t)nwl, sizeof(double));
    c.paths = calloc((size_t)nwl, sizeof(ss_mc_paths *));
    if (!c.wl || !c.refl || !c.paths) {
        st = ss_error_set(err, SS_ERR_NOMEM, "match: out of memory");
        goto done;
    }
    if ((st = ss_optics_data_open(&data, err))) goto done;
    c.data = data;
    c.base = out->table_bio;
    for (int k = 0; k < nwl && !st; k++) {
        c.wl[k] = o->spectrum.wl_min_nm + k * o->spectrum.wl_step_nm;
        ss_optics_slab geo;
        ss_mc_options mo = o->spectrum.mc;
        mo.theta_i_rad = 0.0;
        mo.brdf_n_theta = mo.brdf_n_phi = 0;
        mo.radial_bins = 0;
        mo.radial_max_cm = 0;
        if (!(st = ss_optics_skin_slab_with(data, &c.base, c.wl[k], &geo, err)))
            st = ss_mc_trace_paths(&geo, &mo, &c.paths[k], err);
    }
    if (st) goto done;
    double lo4[4], hi4[4], x4[4];
    for (int k = 0; k < 4; k++) {
        lo4[k] = c.lo[TR_AX[k]];
        hi4[k] = c.hi[TR_AX[k]];
        x4[k] = bx[TR_AX[k]];
    }
    nelder_mead(&c, 1, 4, lo4, hi4, x4, 150, 0.03);
    if (c.st) {
        st = c.st;
        goto done;
    }
    ss_bio_params b = c.base;
    b.melanin = x4[0];
    b.pheomelanin_ratio = x4[1];
    b.blood = x4[2];
    b.oxygenation = x4[3];
    double rgb[3];
    if (transport_rgb(&c, x4, rgb)) {
        st = c.st;
        goto done;
    }
    out->bio = b;
    memcpy(out->albedo_rgb, rgb, sizeof rgb);
    for (int k = 0; k < 3; k++) sv[k] = rgb[k] + c.surface;
    ss_srgb_linear_to_lab(sv, out->lab);
    out->delta_e00 = ss_ciede2000(out->lab, target_lab);
    out->refined = 1;
    finish(&c, t, ng, total, gde, out);
done:
    free(gde);
    if (c.paths)
        for (int k = 0; k < nwl; k++) ss_mc_paths_free(c.paths[k]);
    free(c.paths);
    free(c.wl);
    free(c.refl);
    ss_optics_data_close(data);
    return st;
}
