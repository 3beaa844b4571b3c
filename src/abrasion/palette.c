/* The abrasion's tissue colours from the optics model (docs/abrasion.md,
 * "Colours from the optics"): instead of the seed's hand-set display colours
 * (its bed is lower skin x (0.79, 0, 0), pure red), every colour the phases
 * draw is the albedo of a layered tissue built from the optics model's
 * absorption and scattering coefficients (ss_optics_skin_slab_with: melanin,
 * haemoglobin, bilirubin, the dermis's scattering), computed once per base
 * skin:
 *
 *   exposed dermis     the papillary and reticular dermis without epidermis, at
 *                      a pale (vasoconstricted), a dilated and a capillary-loop
 *                      blood fraction, and as red granulation tissue;
 *   films over it      fresh whole blood, serous exudate (plasma: water with its
 *                      bilirubin), fibrin (a scattering protein gel holding
 *                      serum pigment) and dried crust (haemoglobin concentrated
 *                      by drying, deoxygenated, with serum bilirubin);
 *   skin multipliers   erythema (dilated dermal blood), mature scar
 *                      (hypovascular, more scattering collagen) and the skin
 *                      at nine melanin factors 0.25..2.5 (the healing phases'
 *                      hypo- and hyperpigmentation, interpolated in log
 *                      factor), each as the ratio of its albedo to the healthy
 *                      skin's, so the upper skin texture keeps its own detail
 *                      under them;
 *   new epithelium     a colour of its own at the same nine melanin factors:
 *                      a thin epidermis over young, hyperaemic dermis. Not a
 *                      multiplier: on a dark skin the ratio of a melanin-poor
 *                      epidermis to the skin (red and green gain most) times
 *                      the texture's own saturated brown drew orange.
 *
 * The skin's melanin is estimated from the upper texture's mean luminance
 * (bisection on the model's melanin fraction), so a dark skin given with
 * --upper gets dark-skin erythema, scar and pigmentation.
 *
 * Transport: two-flux Kubelka-Munk per layer (K = 2 mua, S = 0.75 mus(1-g)),
 * layers stacked with the adding formulas, the fat below as a Lambertian
 * reflector, and the Saunderson correction for the rough air-tissue boundary
 * (4 % external, 60 % internal diffuse reflection for n ~ 1.4), at 400..700 nm
 * every 10 nm, then CIE 1931 under D65 to linear sRGB. Gave up: the Monte
 * Carlo transport of src/optics (a palette would cost seconds instead of
 * microseconds, and the phases must render five keys in well under a
 * second); Kubelka-Munk is within a few per cent of it for the thick,
 * scattering layers here, and the skin multipliers are ratios, so its bias
 * largely cancels. */
#include <math.h>
#include <string.h>

#include "skinsim/abrasion.h"
#include "skinsim/optics.h"

#define NWL 31
#define WL0 400.0
#define WLSTEP 10.0
#define FAT_ALBEDO 1.0 /* the optics model's fat reflector (src/optics/tissue.c) */
#define RS 0.04        /* external specular reflection, n = 1.4 (excluded: an albedo) */
#define RI 0.6         /* internal diffuse reflection at n = 1.4 (Saunderson) */

typedef struct rt {
    double R, T;
} rt;

static rt km_layer(double mua, double musp, double d_cm) {
    double K = 2.0 * mua, S = 0.75 * musp;
    if (d_cm <= 0) return (rt){0, 1};
    if (S < 1e-9) return (rt){0, exp(-K * d_cm)};
    double a = 1.0 + K / S, b = sqrt(a * a - 1.0), x = b * S * d_cm;
    if (b < 1e-6) { /* no absorption: the conservative limit */
        double sd = S * d_cm;
        return (rt){sd / (1 + sd), 1 / (1 + sd)};
    }
    if (x > 30) { /* thick: the layer's own reflectance, nothing through */
        return (rt){a - b, 0};
    }
    double sh = sinh(x), ch = cosh(x), den = a * sh + b * ch;
    return (rt){sh / den, b / den};
}

/* Layer `top` over a stack below with reflectance Rb (seen from above) and
 * transmittance Tb: the adding formulas. */
static rt km_over(rt top, rt below) {
    double den = 1.0 - top.R * below.R;
    return (rt){top.R + top.T * top.T * below.R / den, top.T * below.T / den};
}

static double observed(double R) { return (1 - RS) * (1 - RI) * R / (1 - RI * R); }

/* What a palette colour is made of. */
typedef struct recipe {
    ss_bio_params bio;
    int epidermis;         /* 0: the epidermis is gone (abraded) */
    double dermis_scatter; /* multiple of the dermis's scattering (scar collagen) */
    /* a film over the surface: none if film_mm <= 0 */
    double film_mm, film_hb, film_oxy, film_bili, film_musp, film_water_mua;
} recipe;

static ss_status albedo(const ss_optics_data *d, const recipe *r, double rgb[3], ss_error *err) {
    double wl[NWL], refl[NWL];
    for (int w = 0; w < NWL; w++) {
        wl[w] = WL0 + WLSTEP * w;
        ss_optics_slab s;
        ss_status st = ss_optics_skin_slab_with(d, &r->bio, wl[w], &s, err);
        if (st) return st;
        rt stack = {FAT_ALBEDO, 0};
        for (int l = s.nlayers - 1; l >= (r->epidermis ? 0 : 2); l--) {
            const ss_optics_layer *L = &s.layer[l];
            double musp = L->mus_per_cm * (1 - L->g) * (l >= 2 ? r->dermis_scatter : 1.0);
            stack = km_over(km_layer(L->mua_per_cm, musp, L->d_cm), stack);
        }
        if (r->film_mm > 0) {
            /* whole-blood absorption at the film's oxygenation: the optics
             * model's dermis at blood fraction 1 (as src/wound/layer.c) */
            ss_bio_params b = r->bio;
            b.blood = 1;
            b.oxygenation = r->film_oxy;
            b.bilirubin_g_per_l = 0;
            ss_optics_slab bs, bb;
            st = ss_optics_skin_slab_with(d, &b, wl[w], &bs, err);
            b.bilirubin_g_per_l = r->film_bili;
            if (!st) st = ss_optics_skin_slab_with(d, &b, wl[w], &bb, err);
            if (st) return st;
            double hb = bs.layer[2].mua_per_cm, bili = bb.layer[2].mua_per_cm - hb;
            double mua = r->film_hb * hb + bili + r->film_water_mua;
            stack = km_over(km_layer(mua, r->film_musp, r->film_mm * 0.1), stack);
        }
        refl[w] = observed(stack.R);
    }
    return ss_spectrum_to_srgb_linear_with(d, wl, refl, NWL, rgb, err);
}

static double luminance(const double rgb[3]) {
    return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
}

static void to_f(const double *a, float *out) {
    for (int c = 0; c < 3; c++) out[c] = (float)(a[c] < 0 ? 0 : a[c] > 1 ? 1 : a[c]);
}

double ss_abrasion_melanin_factor(int k) {
    return 0.25 * pow(10.0, (double)k / (SS_ABRASION_NMELANIN - 1));
}

ss_status ss_abrasion_palette_compute(const ss_image *upper, ss_abrasion_palette *P,
                                      ss_error *err) {
    memset(P, 0, sizeof *P);
    ss_optics_data *d = NULL;
    ss_status st = ss_optics_data_open(&d, err);
    if (st) return st;
    /* the skin's mean colour and melanin */
    size_t n = (size_t)upper->width * (size_t)upper->height;
    double mean[3] = {0, 0, 0};
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) mean[c] += upper->data[i * 3 + c];
    for (int c = 0; c < 3; c++) mean[c] /= (double)(n ? n : 1);
    double target = luminance(mean), lo = 0.001, hi = 0.6, rgb[3];
    recipe skin = {.epidermis = 1, .dermis_scatter = 1};
    ss_bio_params_default(&skin.bio);
    for (int it = 0; it < 30 && !st; it++) { /* albedo falls with melanin */
        skin.bio.melanin = 0.5 * (lo + hi);
        st = albedo(d, &skin, rgb, err);
        if (luminance(rgb) > target)
            lo = skin.bio.melanin;
        else
            hi = skin.bio.melanin;
    }
    skin.bio.melanin = 0.5 * (lo + hi);
    P->melanin = (float)skin.bio.melanin;
    double lab[3], chroma, hue, ita;
    ss_srgb_linear_to_lab(mean, lab);
    ss_lab_describe(lab, &chroma, &hue, &ita);
    P->ita_deg = (float)ita;
    P->pih_prevalence = (float)ss_pih_prevalence(ita);
    double ref[3];
    if (!st) st = albedo(d, &skin, ref, err);

    /* exposed dermis: no epidermis, the dermal blood as named */
    recipe der = {.bio = skin.bio, .epidermis = 0, .dermis_scatter = 1};
    double out[3];
#define DERMIS(field, blood_, oxy_)                                                                \
    do {                                                                                           \
        der.bio.blood = (blood_);                                                                  \
        der.bio.oxygenation = (oxy_);                                                              \
        if (!st) st = albedo(d, &der, out, err);                                                   \
        to_f(out, P->field);                                                                       \
    } while (0)
    /* the fresh bed: the arterioles constrict, yet the torn papillary plexus
     * and the blood spilled into the exposed dermis make a fresh abrasion deep
     * red with punctate bleeding, as clinical photographs show it (0.01 drew
     * pale pink, 0.035 salmon pink: L* 57, C* 30) */
    DERMIS(bed_pale, 0.10, 0.85);
    DERMIS(bed, 0.10, 0.9);          /* dilated papillary plexus (0.05 was paler than day 0) */
    DERMIS(capillary, 0.30, 0.95);   /* a capillary loop / petechia */
    DERMIS(granulation, 0.20, 0.95); /* young vascular tissue, beefy red */
#undef DERMIS
    /* films over the dilated bed */
    der.bio.blood = 0.05;
    der.bio.oxygenation = 0.9;
#define FILM(field, mm, hb, oxy, bili, musp)                                                       \
    do {                                                                                           \
        recipe f = der;                                                                            \
        f.film_mm = (mm), f.film_hb = (hb), f.film_oxy = (oxy), f.film_bili = (bili);              \
        f.film_musp = (musp);                                                                      \
        if (!st) st = albedo(d, &f, out, err);                                                     \
        to_f(out, P->field);                                                                       \
    } while (0)
    /* fresh blood: whole blood, oxygenated by the air, mus' 30 /cm (Roggan et al.
     * 1999) */
    FILM(blood, 0.1, 1.0, 0.95, 0, 30.0);
    /* serous exudate: plasma, clear (mus' 2 /cm), with some red cells and its
     * bilirubin (~0.01 g/L in serum, concentrated as it thickens) */
    FILM(serous, 0.2, 0.02, 0.9, 0.05, 2.0);
    /* fibrin: a white protein gel (mus' 60 /cm, a stand-in) holding serum
     * pigment and a few red cells */
    FILM(fibrin, 0.3, 0.01, 0.8, 0.3, 60.0);
    /* dried crust: haemoglobin concentrated 3x by drying, deoxygenated (a stand-in
     * for its methaemoglobin), serum bilirubin 1.5 g/L, porous (mus' 150 /cm):
     * src/wound/layer.c's scab; thick and dark, or thin and serous */
    FILM(crust_dark, 0.4, 3.0, 0.0, 1.5, 150.0);
    FILM(crust_light, 0.12, 0.6, 0.0, 1.5, 150.0);
#undef FILM
    /* skin multipliers: albedo / healthy albedo */
#define RATIO(field)                                                                               \
    do {                                                                                           \
        if (!st) st = albedo(d, &m, out, err);                                                     \
        for (int c = 0; c < 3; c++) P->field[c] = (float)(ref[c] > 1e-6 ? out[c] / ref[c] : 1.0);  \
    } while (0)
    recipe m = skin;
    m.bio.blood = 0.06; /* erythema: dermal blood x12 */
    m.bio.oxygenation = 0.85;
    RATIO(erythema);
    m = skin; /* mature scar: hypovascular, dense collagen (its melanin: melanin_ratio) */
    m.bio.blood = 0.003;
    m.dermis_scatter = 1.3;
    RATIO(scar);
    for (int k = 0; k < SS_ABRASION_NMELANIN; k++) {
        m = skin;
        m.bio.melanin *= ss_abrasion_melanin_factor(k);
        RATIO(melanin_ratio[k]);
    }
#undef RATIO
    /* new epithelium as a colour of its own, at each melanin factor: the
     * tissue of ss_bio_new_epithelium (src/optics/healing.c, shared with
     * `wound`): a thin epidermis (0.6 of the skin's) at the skin's melanin
     * times the factor, over young, hyperaemic dermis (blood 4 %, 8x the
     * healthy skin's, short of the erythema's 6 %). As a multiplier of a dark skin texture (its
     * ratio to the model's skin) a melanin-poor epidermis drew saturated
     * orange (L* 44, C* 45, hue 51 on a brown skin) where the optics give
     * pink-brown (L* 39, C* 28, hue 44) */
    for (int k = 0; k < SS_ABRASION_NMELANIN; k++) {
        m = skin;
        ss_bio_new_epithelium(&skin.bio, ss_abrasion_melanin_factor(k), &m.bio);
        if (!st) st = albedo(d, &m, out, err);
        to_f(out, P->epithelium[k]);
    }
    ss_optics_data_close(d);
    return st;
}

double ss_abrasion_pih_factor(const ss_abrasion_palette *p, double days) {
    return ss_pih_melanin_factor(p->pih_prevalence, days, SS_PIH_GAIN);
}

double ss_abrasion_melanin_factor_at(const ss_abrasion_palette *p, double days) {
    ss_repigmentation repig;
    ss_repigmentation_default(&repig);
    return ss_healed_melanin_factor(&repig, p->pih_prevalence, SS_PIH_GAIN, days);
}
