/* A blood layer over a table colour, added per wavelength (docs/wound.md,
 * "The bed's colour").
 *
 * The open bed is drawn as the ModelMatch table's colour (whose blood stops
 * at the table's 5 %) under layers of whole blood: the blood of its capillary
 * loops beyond that cap, and the fresh clot. Added in RGB (ss_layer_over) a
 * thin layer of oxygenated blood turned the bed orange: the channel averages
 * of its transmittance include haemoglobin's Soret and Q bands, where the
 * bed below reflects little anyway, so the blue and green of the bed were
 * dimmed as if they came from those bands (day 7, clean: h_ab 44 degrees,
 * b* 42 against a* 45). Per wavelength the light the bed returns is
 * attenuated where it is.
 *
 * The table keeps colours, not spectra, so a texel's colour rgb at blood
 * fraction b stands for a spectrum S_b(wl) q(wl): S_b the transport's
 * diffuse reflectance of the open bed (no epidermis, no melanin, the
 * table's base pigments) at b, linear between the table's blood samples
 * (where the table itself samples its blood), and q(wl) = c0 + c1 x + c2 x^2
 * with x = (wl - 550) / 150 the smooth factor whose c solves sum_w
 * W[w] S_b q = rgb (W: the CIE 1931 observer under D65 to linear sRGB per
 * bin, ss_spectrum_to_srgb_linear_with of each bin's impulse). The factor
 * stands for what the texel has that the bare bed has not (its epidermis,
 * melanin, the GGX fit's scale of the albedo): smooth absorbers, as melanin
 * is; the bed's haemoglobin bands stay where the transport put them. At zero
 * thickness the layer gives back rgb exactly.
 *
 * The layer's R and T per wavelength are the layer table's (Monte Carlo at
 * 16 wavelengths, before it converts them), linear in thickness between its
 * samples; then R + T^2 A / (1 - R A) per wavelength, summed with W. A texel
 * costs ~16 x 25 flops and a 3 x 3 solve, no transport.
 *
 * Gave up: the factor is fitted to three numbers, so pigments with bands of
 * their own (bilirubin of a bruise, methaemoglobin) are not in it; a texel
 * whose colour is far from the bed's (skin beside the wound, at the partly
 * open rim) gets a smooth correction of the bed's spectrum, not its own. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <string.h>

#include "skinsim/wound.h"

#define WL_MIN 400.0
#define WL_STEP 20.0

ss_status ss_bed_spectra_build(const ss_bio_params *bed, const double *blood, int nblood,
                               uint64_t photons, uint64_t seed, ss_bed_spectra *out,
                               ss_error *err) {
    memset(out, 0, sizeof *out);
    if (nblood < 1 || nblood > SS_BED_MAX_BLOOD || photons < 100)
        return ss_error_set(err, SS_ERR_INPUT,
                            "bed spectra: need 1..%d blood fractions and >= 100 photons",
                            SS_BED_MAX_BLOOD);
    for (int k = 0; k < nblood; k++)
        if (!(blood[k] >= 0 && blood[k] <= 1) || (k > 0 && !(blood[k] > blood[k - 1])))
            return ss_error_set(err, SS_ERR_INPUT,
                                "bed spectra: blood fraction %d (%g) is not in 0..1 and above "
                                "the one before",
                                k, blood[k]);
    ss_status st = ss_bio_params_validate(bed, err);
    if (st) return st;
    ss_optics_data *d = NULL;
    if ((st = ss_optics_data_open(&d, err))) return st;
    out->nblood = nblood;
    memcpy(out->blood, blood, (size_t)nblood * sizeof *blood);
    for (int w = 0; w < SS_LAYER_NWL; w++) {
        out->wavelength_nm[w] = WL_MIN + WL_STEP * w;
        out->x[w] = (out->wavelength_nm[w] - 550.0) / 150.0;
    }
    /* linear sRGB of each bin: the conversion is linear in the spectrum */
    double imp[SS_LAYER_NWL] = {0};
    for (int w = 0; w < SS_LAYER_NWL && !st; w++) {
        imp[w] = 1;
        st = ss_spectrum_to_srgb_linear_with(d, out->wavelength_nm, imp, SS_LAYER_NWL,
                                             out->weight[w], err);
        imp[w] = 0;
    }
    /* one Monte Carlo run per (blood, wavelength), in parallel */
    int njob = nblood * SS_LAYER_NWL;
    ss_status sts[SS_BED_MAX_BLOOD * SS_LAYER_NWL] = {0};
    ss_error errs[SS_BED_MAX_BLOOD * SS_LAYER_NWL];
#pragma omp parallel for schedule(dynamic, 1) if (!st)
    for (int jb = 0; jb < njob; jb++) {
        int k = jb / SS_LAYER_NWL, w = jb % SS_LAYER_NWL;
        ss_bio_params b = *bed;
        b.blood = blood[k];
        ss_optics_slab slab;
        sts[jb] = ss_optics_skin_slab_with(d, &b, out->wavelength_nm[w], &slab, &errs[jb]);
        if (sts[jb]) continue;
        ss_mc_options o;
        ss_mc_options_default(&o);
        o.photons = photons;
        o.seed = seed + (uint64_t)jb;
        ss_mc_result res;
        memset(&res, 0, sizeof res);
        sts[jb] = ss_mc_run(&slab, &o, &res, &errs[jb]);
        out->reflect[k][w] = res.diffuse;
        ss_mc_result_free(&res);
    }
    for (int jb = 0; jb < njob && !st; jb++)
        if (sts[jb]) {
            *err = errs[jb];
            st = sts[jb];
        }
    ss_optics_data_close(d);
    if (st) return st;
    for (int k = 0; k < nblood; k++)
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double m = 0;
                for (int w = 0; w < SS_LAYER_NWL; w++)
                    m += out->weight[w][i] * out->reflect[k][w] * pow(out->x[w], j);
                out->moment[k][i][j] = m;
            }
    return SS_OK;
}

/* The blood sample at or below b and the fraction towards the next. */
static int blood_sample(const ss_bed_spectra *s, double b, double *f) {
    int k = 0;
    *f = 0;
    if (s->nblood < 2 || !(b > s->blood[0])) return 0;
    while (k < s->nblood - 2 && b > s->blood[k + 1]) k++;
    *f = (b - s->blood[k]) / (s->blood[k + 1] - s->blood[k]);
    if (*f > 1) *f = 1;
    return k;
}

int ss_bed_spectrum(const ss_bed_spectra *s, double blood, const double rgb[3],
                    double out[SS_LAYER_NWL]) {
    double f;
    int k = blood_sample(s, blood, &f), k1 = s->nblood > 1 ? k + 1 : k;
    double m[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            m[i][j] = s->moment[k][i][j] + f * (s->moment[k1][i][j] - s->moment[k][i][j]);
    /* m c = rgb by Cramer's rule */
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                 m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    double scale = fabs(m[0][0] * m[1][1] * m[2][2]) + fabs(m[0][1] * m[1][2] * m[2][0]) +
                   fabs(m[0][2] * m[1][0] * m[2][1]);
    if (!(fabs(det) > 1e-9 * scale) || !isfinite(det)) return 0;
    double c[3];
    for (int j = 0; j < 3; j++) {
        double a[3][3];
        memcpy(a, m, sizeof a);
        for (int i = 0; i < 3; i++) a[i][j] = rgb[i];
        c[j] = (a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
                a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])) /
               det;
    }
    for (int w = 0; w < SS_LAYER_NWL; w++) {
        double x = s->x[w];
        double sw = s->reflect[k][w] + f * (s->reflect[k1][w] - s->reflect[k][w]);
        out[w] = sw * (c[0] + x * (c[1] + x * c[2]));
    }
    return 1;
}

void ss_layer_add_wl(const ss_layer_table *t, double thickness_mm, const double in[SS_LAYER_NWL],
                     double out[SS_LAYER_NWL]) {
    double R[SS_LAYER_NWL], T[SS_LAYER_NWL];
    ss_layer_table_eval_wl(t, thickness_mm, R, T);
    for (int w = 0; w < SS_LAYER_NWL; w++) {
        double den = 1 - R[w] * in[w];
        out[w] = R[w] + T[w] * T[w] * in[w] / (den > 1e-6 ? den : 1e-6);
    }
}

void ss_bed_spectra_to_rgb(const ss_bed_spectra *s, const double spectrum[SS_LAYER_NWL],
                           double rgb[3]) {
    rgb[0] = rgb[1] = rgb[2] = 0;
    for (int w = 0; w < SS_LAYER_NWL; w++)
        for (int c = 0; c < 3; c++) rgb[c] += s->weight[w][c] * spectrum[w];
}

void ss_layer_over_spectral(const ss_layer_table *t, double thickness_mm, const ss_bed_spectra *s,
                            double blood, const double rgb[3], double out[3]) {
    double A[SS_LAYER_NWL];
    if (!ss_bed_spectrum(s, blood, rgb, A)) {
        double R[3], T[3];
        ss_layer_table_eval(t, thickness_mm, R, T);
        ss_layer_over(R, T, rgb, out);
        return;
    }
    ss_layer_add_wl(t, thickness_mm, A, A);
    ss_bed_spectra_to_rgb(s, A, out);
}
