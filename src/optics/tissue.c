/* Skin tissue model: biological parameters (seed 003 §5.2) to the optical
 * coefficients of the four layers of §2.1 over a diffusely reflecting fat
 * layer, and the tabulated spectra they need (the CSV files in data/spectra).
 *
 * Every coefficient, its unit and its source (see also docs/optics.md):
 * - Refractive indices (BioSpec, Krishnaswamy & Baranoski 2004): stratum
 *   corneum 1.55, epidermis 1.40, papillary dermis 1.36, reticular dermis 1.38;
 *   air above 1.0.
 * - Thicknesses: SC and epidermis from the parameters (defaults 0.001 cm and
 *   0.01 cm, BioSpec); papillary dermis 0.02 cm, reticular dermis 0.18 cm (BioSpec).
 * - No unspecific "baseline" absorption: the non-pigment absorbers of skin
 *   in the visible are the carotene and bilirubin baselines below; water and
 *   fat absorb < 0.03 /cm below 780 nm (Jacques 2013, Phys. Med. Biol.
 *   58:R37, which models skin as blood + water + fat + melanin + bilirubin +
 *   carotene) and are left out. Jacques' 1998 bloodless-rat-skin baseline is
 *   not used: it made the blood-poor cells too yellow (docs/optics.md).
 * - Melanin (epidermis): mua_eu = eps_eu(lambda) * 80 mg/mL, mua_ph =
 *   eps_ph(lambda) * 12 mg/mL, eps in cm^-1/(mg/mL) (OMLC/Prahl tabulation of
 *   measurements on polymeric eumelanin and pheomelanin, as used by BioSpec;
 *   concentrations in melanosomes from BioSpec). The melanosome absorption is
 *   (1-p) mua_eu + p mua_ph for pheomelanin ratio p; the epidermis is
 *   mua_epi = f_mel mua_melanosome (+ carotene).
 * - Blood (dermis): mua_blood = ln(10) * 150 g/L / 66500 g/mol *
 *   (S eps_HbO2 + (1-S) eps_Hb) + bilirubin (ln 10 * eps_bil * c / 584.66 g/mol),
 *   eps in cm^-1/M decadic (Prahl, OMLC). mua_derm = f_blood mua_blood
 *   (+ carotene) in both dermal layers (the same blood fraction in both).
 * - beta-carotene in every layer at the given concentration: ln 10 * eps * c /
 *   536.87 g/mol added to the layer absorption (Prahl, OMLC).
 * - Scattering, stratum corneum and epidermis: the angular distributions of
 *   light transmitted through excised layers measured by Bruls & van der Leun
 *   1984 (data/spectra/bruls_scattering.csv) as a tabulated phase function
 *   (deflection angle quantiles, interpolated in wavelength, clamped outside
 *   254/302-546 nm), with mus = 1 / thickness: on average one deflection per
 *   normal traversal, the volumetric form of BioSpec's one perturbation per
 *   traversal. These distributions have no backward part.
 * - Scattering, dermis (Jacques 1998): mus' = 2e5 lambda^-1.5 (Mie, collagen
 *   fibres) + 2e12 lambda^-4 (Rayleigh) [1/cm, lambda in nm]; Henyey-
 *   Greenstein with g_dermis = 0.62 + 0.29e-3 lambda; mus = mus' / (1 - g).
 * - Fat below: Lambertian reflector of albedo SS_FAT_ALBEDO (seed §2.1: "the
 *   fatty tissue simply reflects all light back"). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "optics_internal.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define SS_FAT_ALBEDO 1.0
#define N_AIR 1.0
#define N_SC 1.55
#define N_EPI 1.40
#define N_PAP 1.36
#define N_RET 1.38
#define N_FAT 1.44
#define D_PAP_CM 0.02
#define D_RET_CM 0.18
#define C_EUMELANIN_MG_PER_ML 80.0
#define C_PHEOMELANIN_MG_PER_ML 12.0
#define C_HB_G_PER_L 150.0
#define M_HB_G_PER_MOL 66500.0
#define M_BILIRUBIN_G_PER_MOL 584.66
#define M_BETACAROTENE_G_PER_MOL 536.87
#define LN10 2.302585092994046

void ss_bio_params_default(ss_bio_params *p) {
    memset(p, 0, sizeof *p);
    p->melanin = 0.015; /* light skin: 1.3-6.3 % (Jacques 1998) */
    p->pheomelanin_ratio = 0.3;
    p->blood = 0.005; /* dermal average 0.2-1 % (Jacques 1998) */
    p->oxygenation = 0.75;
    p->sc_thickness_cm = 0.001;
    p->epidermis_thickness_cm = 0.01;
    p->bilirubin_g_per_l = 0.003;     /* BioSpec */
    p->betacarotene_g_per_l = 2.1e-4; /* BioSpec (SC and epidermis) */
}

static ss_status check_range(const char *name, double v, double lo, double hi, int lo_open,
                             ss_error *err) {
    if (!isfinite(v) || v < lo || v > hi || (lo_open && v <= lo))
        return ss_error_set(err, SS_ERR_INPUT, "%s: %g is outside %s%g, %g]", name, v,
                            lo_open ? "(" : "[", lo, hi);
    return SS_OK;
}

ss_status ss_bio_params_validate(const ss_bio_params *p, ss_error *err) {
    if (!p) return ss_error_set(err, SS_ERR_INPUT, "biological parameters are missing");
    ss_status st;
    if ((st = check_range("melanin (melanosome volume fraction)", p->melanin, 0, 1, 0, err)) ||
        (st = check_range("pheomelanin ratio", p->pheomelanin_ratio, 0, 1, 0, err)) ||
        (st = check_range("blood (volume fraction)", p->blood, 0, 1, 0, err)) ||
        (st = check_range("oxygenation", p->oxygenation, 0, 1, 0, err)) ||
        (st = check_range("stratum corneum thickness (cm)", p->sc_thickness_cm, 0, 1, 1, err)) ||
        (st = check_range("epidermis thickness (cm)", p->epidermis_thickness_cm, 0, 1, 1, err)) ||
        (st = check_range("bilirubin (g/L)", p->bilirubin_g_per_l, 0, 100, 0, err)) ||
        (st = check_range("beta-carotene (g/L)", p->betacarotene_g_per_l, 0, 100, 0, err)))
        return st;
    return SS_OK;
}

ss_status ss_optics_slab_validate(const ss_optics_slab *s, ss_error *err) {
    if (!s) return ss_error_set(err, SS_ERR_INPUT, "slab is missing");
    if (s->nlayers < 1 || s->nlayers > SS_OPTICS_MAX_LAYERS)
        return ss_error_set(err, SS_ERR_INPUT, "number of layers %d is outside 1..%d", s->nlayers,
                            SS_OPTICS_MAX_LAYERS);
    if (!(s->n_above >= 1.0 && s->n_above < 10.0))
        return ss_error_set(err, SS_ERR_INPUT,
                            "refractive index above the slab %g is outside [1, 10)", s->n_above);
    if (!(s->n_below >= 1.0 && s->n_below < 10.0))
        return ss_error_set(err, SS_ERR_INPUT,
                            "refractive index below the slab %g is outside [1, 10)", s->n_below);
    if (!(isfinite(s->bottom_albedo) && s->bottom_albedo <= 1.0))
        return ss_error_set(err, SS_ERR_INPUT,
                            "bottom albedo %g must be < 0 (transmitting) or in [0, 1]",
                            s->bottom_albedo);
    for (int l = 0; l < s->nlayers; l++) {
        const ss_optics_layer *L = &s->layer[l];
        if (!(L->n >= 1.0 && L->n < 10.0))
            return ss_error_set(err, SS_ERR_INPUT,
                                "layer %d: refractive index %g is outside [1, 10)", l + 1, L->n);
        if (!(L->mua_per_cm >= 0.0 && L->mua_per_cm < 1e7))
            return ss_error_set(err, SS_ERR_INPUT, "layer %d: mua %g /cm must be finite and >= 0",
                                l + 1, L->mua_per_cm);
        if (!(L->mus_per_cm >= 0.0 && L->mus_per_cm < 1e7))
            return ss_error_set(err, SS_ERR_INPUT, "layer %d: mus %g /cm must be finite and >= 0",
                                l + 1, L->mus_per_cm);
        if (!(L->g > -1.0 && L->g < 1.0))
            return ss_error_set(err, SS_ERR_INPUT, "layer %d: anisotropy g %g is outside (-1, 1)",
                                l + 1, L->g);
        if (!(L->d_cm > 0.0 && L->d_cm < 1e6))
            return ss_error_set(err, SS_ERR_INPUT, "layer %d: thickness %g cm must be > 0", l + 1,
                                L->d_cm);
        if (L->phase_n != 0 && (L->phase_n < 2 || L->phase_n > SS_OPTICS_PHASE_MAX))
            return ss_error_set(err, SS_ERR_INPUT,
                                "layer %d: tabulated phase function has %d points (0 or 2..%d)",
                                l + 1, L->phase_n, SS_OPTICS_PHASE_MAX);
        for (int k = 0; k < L->phase_n; k++)
            if (!(L->phase_theta[k] >= 0.0 && L->phase_theta[k] <= 3.14159265358979323846 &&
                  (k == 0 || L->phase_theta[k] >= L->phase_theta[k - 1])))
                return ss_error_set(err, SS_ERR_INPUT,
                                    "layer %d: phase angle %d (%g rad) is not a non-decreasing "
                                    "angle in [0, pi]",
                                    l + 1, k, L->phase_theta[k]);
    }
    return SS_OK;
}

/* ---- spectra tables ---------------------------------------------------------- */
static ss_status load_csv(const char *file, int ncols, ss_spectrum_table *out[], ss_error *err) {
    char path[4096];
    snprintf(path, sizeof path, "%s/spectra/%s", ss_data_dir(), file);
    size_t len;
    char *text = ss_read_file_max(path, &len, SS_READ_MAX_CONFIG, err);
    if (!text) return err ? err->code : SS_ERR_INPUT;
    int cap = 256, n = 0;
    double *nm = malloc(cap * sizeof *nm);
    double *v[16] = {0};
    for (int k = 0; k < ncols; k++) v[k] = malloc(cap * sizeof(double));
    int ok = nm != NULL;
    for (int k = 0; k < ncols; k++) ok = ok && v[k];
    char *save = NULL;
    int lineno = 0;
    for (char *line = strtok_r(text, "\n", &save); line && ok; line = strtok_r(NULL, "\n", &save)) {
        lineno++;
        if (line[0] == '#' || line[0] == '\r' || line[0] == 0) continue;
        if (!((line[0] >= '0' && line[0] <= '9') || line[0] == '.')) continue; /* header */
        if (n == cap) {
            cap *= 2;
            double *t = realloc(nm, cap * sizeof *nm);
            if (!t) {
                ok = 0;
                break;
            }
            nm = t;
            for (int k = 0; k < ncols; k++) {
                t = realloc(v[k], cap * sizeof(double));
                if (!t) {
                    ok = 0;
                    break;
                }
                v[k] = t;
            }
            if (!ok) break;
        }
        char *p = line, *end;
        nm[n] = strtod(p, &end);
        if (end == p) goto bad;
        p = end;
        for (int k = 0; k < ncols; k++) {
            if (*p != ',') goto bad;
            p++;
            v[k][n] = strtod(p, &end);
            if (end == p) goto bad;
            p = end;
        }
        if (n > 0 && !(nm[n] > nm[n - 1])) goto bad;
        n++;
        continue;
    bad:
        free(text);
        free(nm);
        for (int k = 0; k < ncols; k++) free(v[k]);
        return ss_error_set(err, SS_ERR_INPUT, "%s: line %d: malformed or unsorted data", path,
                            lineno);
    }
    free(text);
    if (!ok || n < 2) {
        free(nm);
        for (int k = 0; k < ncols; k++) free(v[k]);
        return ok ? ss_error_set(err, SS_ERR_INPUT, "%s: fewer than 2 data rows", path)
                  : ss_error_set(err, SS_ERR_NOMEM, "out of memory reading %s", path);
    }
    for (int k = 0; k < ncols; k++) {
        out[k]->n = n;
        out[k]->v = v[k];
        if (k == 0)
            out[k]->nm = nm;
        else {
            out[k]->nm = malloc(n * sizeof(double));
            if (out[k]->nm) memcpy(out[k]->nm, nm, n * sizeof(double));
        }
    }
    for (int k = 0; k < ncols; k++)
        if (!out[k]->nm) return ss_error_set(err, SS_ERR_NOMEM, "out of memory reading %s", path);
    return SS_OK;
}

static void table_free(ss_spectrum_table *t) {
    free(t->nm);
    free(t->v);
    t->nm = t->v = NULL;
    t->n = 0;
}

void ss_optics_data_free(ss_optics_data *d) {
    if (!d) return;
    ss_spectrum_table *all[] = {&d->eumelanin, &d->pheomelanin,  &d->hbo2,  &d->hb,
                                &d->bilirubin, &d->betacarotene, &d->cie_x, &d->cie_y,
                                &d->cie_z,     &d->d65};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++) table_free(all[i]);
    for (int k = 0; k < SS_BRULS_COLUMNS; k++) table_free(&d->bruls[k]);
}

ss_status ss_optics_data_load(ss_optics_data *d, ss_error *err) {
    memset(d, 0, sizeof *d);
    ss_status st;
    ss_spectrum_table *eu[] = {&d->eumelanin}, *ph[] = {&d->pheomelanin},
                      *hb[] = {&d->hbo2, &d->hb}, *bi[] = {&d->bilirubin},
                      *bc[] = {&d->betacarotene}, *cie[] = {&d->cie_x, &d->cie_y, &d->cie_z},
                      *d65[] = {&d->d65};
    ss_spectrum_table *br[SS_BRULS_COLUMNS];
    for (int k = 0; k < SS_BRULS_COLUMNS; k++) br[k] = &d->bruls[k];
    if ((st = load_csv("eumelanin.csv", 1, eu, err)) ||
        (st = load_csv("pheomelanin.csv", 1, ph, err)) ||
        (st = load_csv("hemoglobin.csv", 2, hb, err)) ||
        (st = load_csv("bilirubin.csv", 1, bi, err)) ||
        (st = load_csv("betacarotene.csv", 1, bc, err)) ||
        (st = load_csv("cie1931_2deg.csv", 3, cie, err)) ||
        (st = load_csv("d65.csv", 1, d65, err)) ||
        (st = load_csv("bruls_scattering.csv", SS_BRULS_COLUMNS, br, err))) {
        ss_optics_data_free(d);
        return st;
    }
    return SS_OK;
}

double ss_spectrum_table_eval(const ss_spectrum_table *t, double nm) {
    if (nm <= t->nm[0]) return t->v[0];
    if (nm >= t->nm[t->n - 1]) return t->v[t->n - 1];
    int lo = 0, hi = t->n - 1;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (t->nm[mid] <= nm)
            lo = mid;
        else
            hi = mid;
    }
    double f = (nm - t->nm[lo]) / (t->nm[hi] - t->nm[lo]);
    return t->v[lo] + f * (t->v[hi] - t->v[lo]);
}

/* ---- the skin slab ----------------------------------------------------------- */
/* Stratum corneum (epi = 0) or epidermis (epi = 1) deflection-angle phase
 * function from Bruls & van der Leun 1984, mixed with a wide-angle
 * (isotropic) share iso_frac: the Bruls cumulative transmitted share over
 * the exitant angle at the two nearest measured wavelengths, interpolated
 * linearly in wavelength (clamped outside the measured 254/302-546 nm) and
 * normalised, F(theta) = (1 - iso_frac) F_Bruls(theta) + iso_frac (1 - cos
 * theta) / 2 on a 0.25-degree grid, inverted at probabilities k / (n - 1);
 * the exitant angle is used as the deflection angle, as BioSpec does. g gets
 * the mixture's mean cosine. Returns the Bruls part's mean cosine. */
static double bruls_phase(const ss_optics_data *d, int epi, double nm, double iso_frac,
                          ss_optics_layer *L) {
    static const double wl_sc[5] = {254, 302, 365, 436, 546}, wl_epi[4] = {302, 365, 436, 546};
    const double *wl = epi ? wl_epi : wl_sc;
    int nw = epi ? 4 : 5, c0 = epi ? 5 : 0, a = 0, b = 0;
    double f = 0.0;
    if (nm >= wl[nw - 1])
        a = b = nw - 1;
    else if (nm > wl[0]) {
        while (wl[a + 1] < nm) a++;
        b = a + 1;
        f = (nm - wl[a]) / (wl[b] - wl[a]);
    }
    const ss_spectrum_table *ta = &d->bruls[c0 + a], *tb = &d->bruls[c0 + b];
    int n = ta->n < 64 ? ta->n : 64;
    double cdf[64], ang[64];
    for (int i = 0; i < n; i++) {
        ang[i] = ta->nm[i] * (M_PI / 180.0); /* used as measured (BioSpec) */
        cdf[i] = (1.0 - f) * ta->v[i] + f * tb->v[i];
        if (i > 0 && cdf[i] < cdf[i - 1]) cdf[i] = cdf[i - 1];
    }
    double top = cdf[n - 1] > 0.0 ? cdf[n - 1] : 1.0;
    for (int i = 0; i < n; i++) cdf[i] /= top;
    /* mean cosine of the Bruls part (piecewise-uniform angle density) */
    double gb = 0.0;
    for (int j = 0; j + 1 < n; j++) {
        double w = cdf[j + 1] - cdf[j], t0 = ang[j], t1 = ang[j + 1];
        gb += w * (t1 > t0 ? (sin(t1) - sin(t0)) / (t1 - t0) : cos(t0));
    }
    /* the mixture's CDF on a fine grid over [0, pi] */
    enum { NG = 721 };
    double fg[NG], tg[NG];
    int i = 0;
    for (int k = 0; k < NG; k++) {
        double t = M_PI * k / (NG - 1), fb;
        while (i < n - 2 && ang[i + 1] < t) i++;
        if (t >= ang[n - 1])
            fb = 1.0;
        else {
            double span = ang[i + 1] - ang[i];
            double u = span > 0.0 ? (t - ang[i]) / span : 1.0;
            fb = cdf[i] + fmin(1.0, fmax(0.0, u)) * (cdf[i + 1] - cdf[i]);
        }
        tg[k] = t;
        fg[k] = (1.0 - iso_frac) * fb + iso_frac * 0.5 * (1.0 - cos(t));
        if (k > 0 && fg[k] < fg[k - 1]) fg[k] = fg[k - 1];
    }
    fg[NG - 1] = 1.0;
    /* the last angle carrying probability (62.5 degrees without iso part) */
    int last = NG - 1;
    while (last > 0 && fg[last - 1] >= 1.0) last--;
    const int N = SS_OPTICS_PHASE_MAX;
    L->phase_n = N;
    i = 0;
    for (int k = 0; k < N; k++) {
        double p = (double)k / (N - 1);
        while (i < NG - 2 && fg[i + 1] < p) i++;
        double span = fg[i + 1] - fg[i];
        double t = span > 0.0 ? (p - fg[i]) / span : 0.0;
        L->phase_theta[k] = tg[i] + fmin(1.0, fmax(0.0, t)) * (tg[i + 1] - tg[i]);
        if (k > 0 && L->phase_theta[k] < L->phase_theta[k - 1])
            L->phase_theta[k] = L->phase_theta[k - 1];
    }
    L->phase_theta[N - 1] = tg[last];
    L->g = (1.0 - iso_frac) * gb; /* the isotropic part has mean cosine 0 */
    return gb;
}

/* Reduced scattering coefficient of excised human epidermis measured with
 * integrating spheres (Marchesini, Clemente, Pignoli & Brambilla 1992, J.
 * Photochem. Photobiol. B 16:127): 32 /cm at 400 nm falling to 21 /cm at 800
 * nm; linear in between, held outside. */
static double musp_marchesini(double nm) {
    double t = fmin(1.0, fmax(0.0, (nm - 400.0) / 400.0));
    return 32.0 - 11.0 * t;
}

/* SC or epidermis scattering: the Bruls & van der Leun forward distribution
 * with mus_B = 1 / d (one deflection per normal traversal, BioSpec), plus
 * isotropic scattering mus_iso that brings the layer's reduced scattering
 * mus_B (1 - g_B) + mus_iso up to Marchesini's mus' (none if the Bruls part
 * already reaches it). Bruls & van der Leun measured only light transmitted
 * forward; the isotropic share is the wide-angle and backward scattering
 * their set-up could not see. */
static void epidermal_scattering(const ss_optics_data *d, int epi, double nm, ss_optics_layer *L) {
    double mus_b = 1.0 / L->d_cm;
    double gb = bruls_phase(d, epi, nm, 0.0, L);
    double iso = musp_marchesini(nm) - mus_b * (1.0 - gb);
    if (iso > 0.0) {
        L->mus_per_cm = mus_b + iso;
        bruls_phase(d, epi, nm, iso / (mus_b + iso), L);
    } else
        L->mus_per_cm = mus_b;
}

static double musp_jacques(double nm) { return 2e5 * pow(nm, -1.5) + 2e12 * pow(nm, -4.0); }

ss_status ss_optics_skin_slab_data(const ss_optics_data *d, const ss_bio_params *bio, double nm,
                                   ss_optics_slab *out, ss_error *err) {
    ss_status st = ss_bio_params_validate(bio, err);
    if (st) return st;
    if (!(nm >= 300.0 && nm <= 800.0))
        return ss_error_set(err, SS_ERR_INPUT,
                            "wavelength %g nm is outside 300..800 nm (range of the spectra)", nm);
    memset(out, 0, sizeof *out);
    double bc = LN10 * ss_spectrum_table_eval(&d->betacarotene, nm) * bio->betacarotene_g_per_l /
                M_BETACAROTENE_G_PER_MOL;
    double mel = (1.0 - bio->pheomelanin_ratio) * ss_spectrum_table_eval(&d->eumelanin, nm) *
                     C_EUMELANIN_MG_PER_ML +
                 bio->pheomelanin_ratio * ss_spectrum_table_eval(&d->pheomelanin, nm) *
                     C_PHEOMELANIN_MG_PER_ML;
    double so = bio->oxygenation;
    double blood = LN10 * C_HB_G_PER_L / M_HB_G_PER_MOL *
                       (so * ss_spectrum_table_eval(&d->hbo2, nm) +
                        (1.0 - so) * ss_spectrum_table_eval(&d->hb, nm)) +
                   LN10 * ss_spectrum_table_eval(&d->bilirubin, nm) * bio->bilirubin_g_per_l /
                       M_BILIRUBIN_G_PER_MOL;
    double musp = musp_jacques(nm);
    double g_derm = 0.62 + 0.29e-3 * nm;
    if (g_derm > 0.95) g_derm = 0.95;
    out->nlayers = 4;
    out->n_above = N_AIR;
    out->n_below = N_FAT;
    out->bottom_albedo = SS_FAT_ALBEDO;
    ss_optics_layer *L = out->layer;
    /* stratum corneum and epidermis: one Bruls & van der Leun deflection per
     * normal traversal on average (BioSpec perturbs once per traversal) */
    L[0].n = N_SC;
    L[0].mua_per_cm = bc;
    L[0].d_cm = bio->sc_thickness_cm;
    epidermal_scattering(d, 0, nm, &L[0]);
    L[1].n = N_EPI;
    L[1].mua_per_cm = bio->melanin * mel + bc;
    L[1].d_cm = bio->epidermis_thickness_cm;
    epidermal_scattering(d, 1, nm, &L[1]);
    /* papillary and reticular dermis */
    double mua_d = bio->blood * blood + bc;
    L[2].n = N_PAP;
    L[3].n = N_RET;
    L[2].d_cm = D_PAP_CM;
    L[3].d_cm = D_RET_CM;
    for (int k = 2; k < 4; k++) {
        L[k].mua_per_cm = mua_d;
        L[k].g = g_derm;
        L[k].mus_per_cm = musp / (1.0 - g_derm);
    }
    return ss_optics_slab_validate(out, err);
}

ss_status ss_optics_skin_slab(const ss_bio_params *bio, double wavelength_nm, ss_optics_slab *out,
                              ss_error *err) {
    if (!out) return ss_error_set(err, SS_ERR_INPUT, "slab output is NULL");
    ss_status st = ss_bio_params_validate(bio, err);
    if (st) return st;
    ss_optics_data d;
    st = ss_optics_data_load(&d, err);
    if (st) return st;
    st = ss_optics_skin_slab_data(&d, bio, wavelength_nm, out, err);
    ss_optics_data_free(&d);
    return st;
}

ss_status ss_optics_data_open(ss_optics_data **out, ss_error *err) {
    if (!out) return ss_error_set(err, SS_ERR_INPUT, "data output is NULL");
    *out = calloc(1, sizeof **out);
    if (!*out) return ss_error_set(err, SS_ERR_NOMEM, "out of memory for spectra");
    ss_status st = ss_optics_data_load(*out, err);
    if (st) {
        free(*out);
        *out = NULL;
    }
    return st;
}

void ss_optics_data_close(ss_optics_data *d) {
    if (!d) return;
    ss_optics_data_free(d);
    free(d);
}

ss_status ss_optics_skin_slab_with(const ss_optics_data *d, const ss_bio_params *bio,
                                   double wavelength_nm, ss_optics_slab *out, ss_error *err) {
    if (!d || !out) return ss_error_set(err, SS_ERR_INPUT, "spectra or slab output is NULL");
    return ss_optics_skin_slab_data(d, bio, wavelength_nm, out, err);
}
