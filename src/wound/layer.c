/* Blood layers of the optics model over the skin: the scab (dried blood) and
 * the clot of a fresh wound (whole blood).
 *
 * Scab absorption: haemoglobin at hb_factor times the concentration of whole blood
 * (150 g/L, the optics model's blood; docs/optics.md), fully deoxygenated, as
 * a documented stand-in for the methaemoglobin and hemichrome that dried
 * blood turns into within days (Bremmer et al. 2011, "Age estimation of blood
 * stains by hemoglobin derivative determination using reflectance
 * spectroscopy", Forensic Sci. Int. 206: 166-171): the optics data ship the
 * oxy- and deoxy-haemoglobin spectra of Prahl (OMLC) only, and deoxy-Hb has the
 * broad 555 nm band in the same place as the oxidised forms' absorption rise
 * towards the blue; methaemoglobin's extra 630 nm band (which would brown the
 * crust) is missing. Drying concentrates haemoglobin about threefold over
 * whole blood (the default hb_factor 3; blood is ~80 % water, a scab also holds
 * fibrin and serum). The whole-blood absorption is taken from the optics
 * model's public slab (a dermis of blood fraction 1), so the spectrum and its
 * source stay in one place.
 * Scab scattering: mus = 1500 /cm, g = 0.9 (mus' = 150 /cm): a crust is a
 * porous, cracked matrix of fibrin, cell debris and air that scatters far more
 * than whole blood; a stand-in chosen so that a thick crust reflects ~5 % in
 * the red and < 1 % in the green, the dark red-brown of aged blood stains
 * (reflectance spectra in Bremmer et al. 2011); refractive index 1.45 (dried
 * protein).
 * Clot: whole blood (hb_factor 1) at a given oxygenation (the fresh clot's,
 * and the open bed's for the blood of its capillary loops) with the
 * reduced scattering of whole blood, mus' = 30 /cm (mus 2000-2800 /cm with g
 * 0.98-0.99 in the red, Roggan et al. 1999, J. Biomed. Opt. 4: 36-46), here
 * as mus = 300 /cm with g = 0.9 (the similarity relation: the same mus',
 * seven times fewer scattering events to trace), n 1.40.
 *
 * Transport per texel would cost seconds per day; instead the layer's diffuse
 * reflectance R (over a black background, specular excluded like the table's
 * albedos) and its diffuse transmittance T into the skin (n = 1.4 below) are
 * tabulated over SS_LAYER_NTHICK thicknesses by Monte Carlo at 400..700 nm and
 * converted to linear sRGB; a texel then adds the layer to its skin albedo A
 * with the adding formula R + T^2 A / (1 - R A) (Kubelka 1954; it treats the
 * layer as symmetric). In RGB that is an approximation (the docs state it),
 * kept for the crust; the table keeps R and T per wavelength too, and the
 * open bed's blood (its capillary loops, the fresh clot) is added per
 * wavelength (bed_spectrum.c), where a thin layer of blood is not orange. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/wound.h"
#include "wound_internal.h"

static const double THICK_MM[SS_LAYER_NTHICK] = {0,   0.005, 0.01, 0.02, 0.05,
                                                 0.1, 0.2,   0.4,  0.8,  1.6};
#define SKIN_N 1.4
#define WL_MIN 400.0
#define WL_STEP 20.0
#define NWL SS_LAYER_NWL

void ss_blood_layer_scab(double hb_factor, ss_blood_layer *l) {
    *l = (ss_blood_layer){hb_factor, 0.0, 1500.0, 0.9, 1.45, 0.0};
}

void ss_blood_layer_clot(double oxygenation, ss_blood_layer *l) {
    *l = (ss_blood_layer){1.0, oxygenation, 300.0, 0.9, 1.40, 0.0};
}

/* Whole-blood absorption (1/cm) at an oxygenation and wavelength wl. */
static ss_status blood_mua(const ss_optics_data *d, double oxygenation, double bilirubin, double wl,
                           double *mua, ss_error *err) {
    ss_bio_params bio;
    ss_bio_params_default(&bio);
    bio.blood = 1;
    bio.oxygenation = oxygenation;
    bio.bilirubin_g_per_l = bilirubin;
    bio.betacarotene_g_per_l = 0;
    ss_optics_slab slab;
    ss_status st = ss_optics_skin_slab_with(d, &bio, wl, &slab, err);
    if (!st) *mua = slab.layer[2].mua_per_cm; /* papillary dermis = whole blood here */
    return st;
}

ss_status ss_wound__mc_one(const ss_optics_slab *slab, uint64_t photons, uint64_t seed,
                           double *diffuse, double *transmit, ss_error *err) {
    ss_mc_options o;
    ss_mc_options_default(&o);
    o.photons = photons;
    o.seed = seed;
    ss_mc_result res;
    memset(&res, 0, sizeof res);
    ss_status st = ss_mc_run(slab, &o, &res, err);
    *diffuse = res.diffuse;
    if (transmit) *transmit = res.transmit;
    ss_mc_result_free(&res);
    return st;
}

ss_status ss_layer_table_build(const ss_blood_layer *l, uint64_t photons, uint64_t seed,
                               ss_layer_table *out, ss_error *err) {
    if (!(l->hb_factor >= 0) || !(l->bilirubin_g_per_l >= 0 && l->bilirubin_g_per_l <= 100) ||
        !(l->oxygenation >= 0 && l->oxygenation <= 1) || !(l->mus_per_cm >= 0) ||
        !(fabs(l->g) < 1) || !(l->n >= 1) || photons < 100)
        return ss_error_set(
            err, SS_ERR_INPUT,
            "blood layer: need hb_factor >= 0, bilirubin 0..100 g/L, oxygenation 0..1, mus >= 0, "
            "|g| < 1, n >= 1 and >= 100 photons");
    memset(out, 0, sizeof *out);
    memcpy(out->thickness_mm, THICK_MM, sizeof THICK_MM);
    ss_optics_data *d = NULL;
    ss_status st = ss_optics_data_open(&d, err);
    if (st) return st;
    double wl[NWL], mua[NWL];
    for (int w = 0; w < NWL && !st; w++) {
        wl[w] = WL_MIN + WL_STEP * w;
        /* haemoglobin at hb_factor times whole blood's, plus the bilirubin term
         * (the optics model's blood with and without it) at the layer's own
         * concentration */
        double base = 0, with = 0;
        st = blood_mua(d, l->oxygenation, 0, wl[w], &base, err);
        if (!st && l->bilirubin_g_per_l > 0)
            st = blood_mua(d, l->oxygenation, l->bilirubin_g_per_l, wl[w], &with, err);
        mua[w] = base * l->hb_factor + (l->bilirubin_g_per_l > 0 ? with - base : 0);
    }
    /* the bare skin: R = 0, T = 1 */
    for (int c = 0; c < 3; c++) out->transmit[0][c] = 1;
    for (int w = 0; w < NWL; w++) out->transmit_wl[0][w] = 1;
    /* one Monte Carlo run per (thickness, wavelength), in parallel: each run
     * is smaller than one block of the transport, so it runs on one thread */
    double R[SS_LAYER_NTHICK][NWL], T[SS_LAYER_NTHICK][NWL];
    ss_status sts[SS_LAYER_NTHICK * NWL] = {0};
    ss_error errs[SS_LAYER_NTHICK * NWL];
    int njob = (SS_LAYER_NTHICK - 1) * NWL;
#pragma omp parallel for schedule(dynamic, 1) if (!st)
    for (int jb = 0; jb < njob; jb++) {
        int k = 1 + jb / NWL, w = jb % NWL;
        ss_optics_slab slab = {0};
        slab.nlayers = 1;
        slab.layer[0] = (ss_optics_layer){.n = l->n,
                                          .mua_per_cm = mua[w],
                                          .mus_per_cm = l->mus_per_cm,
                                          .g = l->g,
                                          .d_cm = THICK_MM[k] * 0.1};
        slab.n_above = 1.0;
        slab.n_below = SKIN_N;
        slab.bottom_albedo = -1;
        sts[jb] =
            ss_wound__mc_one(&slab, photons, seed + (uint64_t)jb, &R[k][w], &T[k][w], &errs[jb]);
    }
    for (int jb = 0; jb < njob && !st; jb++)
        if (sts[jb]) {
            *err = errs[jb];
            st = sts[jb];
        }
    for (int k = 1; k < SS_LAYER_NTHICK && !st; k++) {
        memcpy(out->reflect_wl[k], R[k], sizeof R[k]);
        memcpy(out->transmit_wl[k], T[k], sizeof T[k]);
        st = ss_spectrum_to_srgb_linear_with(d, wl, R[k], NWL, out->reflect[k], err);
        if (!st) st = ss_spectrum_to_srgb_linear_with(d, wl, T[k], NWL, out->transmit[k], err);
        for (int c = 0; c < 3 && !st; c++) { /* colour matrices can dip below 0 */
            if (out->reflect[k][c] < 0) out->reflect[k][c] = 0;
            if (out->transmit[k][c] < 0) out->transmit[k][c] = 0;
        }
    }
    ss_optics_data_close(d);
    return st;
}

/* The sample at or below the thickness and the fraction towards the next. */
static int thickness_sample(const ss_layer_table *t, double thickness_mm, double *f) {
    int k = 0;
    if (!(thickness_mm > 0)) thickness_mm = 0;
    while (k < SS_LAYER_NTHICK - 2 && thickness_mm > t->thickness_mm[k + 1]) k++;
    double a = t->thickness_mm[k], b = t->thickness_mm[k + 1];
    *f = (thickness_mm - a) / (b - a);
    if (*f > 1) *f = 1;
    return k;
}

void ss_layer_table_eval_wl(const ss_layer_table *t, double thickness_mm,
                            double reflect[SS_LAYER_NWL], double transmit[SS_LAYER_NWL]) {
    double f;
    int k = thickness_sample(t, thickness_mm, &f);
    for (int w = 0; w < SS_LAYER_NWL; w++) {
        reflect[w] = t->reflect_wl[k][w] + f * (t->reflect_wl[k + 1][w] - t->reflect_wl[k][w]);
        transmit[w] = t->transmit_wl[k][w] + f * (t->transmit_wl[k + 1][w] - t->transmit_wl[k][w]);
    }
}

void ss_layer_table_eval(const ss_layer_table *t, double thickness_mm, double reflect[3],
                         double transmit[3]) {
    double f;
    int k = thickness_sample(t, thickness_mm, &f);
    for (int c = 0; c < 3; c++) {
        reflect[c] = t->reflect[k][c] + f * (t->reflect[k + 1][c] - t->reflect[k][c]);
        transmit[c] = t->transmit[k][c] + f * (t->transmit[k + 1][c] - t->transmit[k][c]);
    }
}

void ss_layer_over(const double reflect[3], const double transmit[3], const double skin[3],
                   double out[3]) {
    for (int c = 0; c < 3; c++) {
        double den = 1 - reflect[c] * skin[c];
        out[c] = reflect[c] + transmit[c] * transmit[c] * skin[c] / (den > 1e-6 ? den : 1e-6);
    }
}
