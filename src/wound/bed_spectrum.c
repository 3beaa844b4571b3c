/* The open bed's colour per wavelength: its blood beyond the ModelMatch
 * table's cap and the blood and serum lying on it (docs/wound.md, "The open
 * bed's colour").
 *
 * The table's blood stops at 5 %; granulation tissue holds far more, in the
 * capillary loops of its top ~0.1-0.3 mm. Drawn as a film of whole blood,
 * (bed - cap) x loop_depth thick, over the table's colour and added in RGB
 * (ss_layer_over), the bed was orange (day 7, clean: h_ab 43 degrees, b* 42
 * against a* 45): the channel averages of the film's transmittance hold
 * haemoglobin's Soret and Q bands, so blue and green were dimmed as if the
 * bed's light came from there. Added per wavelength the film gives h 38 (it
 * still kills the blue below 450 nm). Here the loops' blood is where it
 * is: in the scattering tissue of the bed, by the transport; blood in
 * scattering tissue absorbs as the square root of mu_a / mu_s' rather than
 * exponentially in it, so the bed between the Soret band and the Q bands
 * (460-520 nm, where oxygenated blood absorbs least below 590 nm) keeps
 * some of its blue: crimson (h 24-28 at 10-50 % blood), the lips' and a
 * haemangioma's red, not orange.
 *
 * One blood axis: at or below the cap a sample is the bed with that blood
 * in its whole dermis (the table's own samples there); above it, the bed at
 * the cap whose top loop_depth of dermis holds the sample's blood (the same
 * haemoglobin per area as the film: (blood - cap) x loop_depth). Its
 * spectra S_b are the optics model's transport (ss_optics_skin_slab_with,
 * the loops as an extra layer cut from the top of the dermis), linear
 * between samples.
 *
 * The table keeps colours, not spectra, so a texel's colour rgb at blood b
 * stands for S_b(wl) q(wl), q = c0 + c1 x + c2 x^2 with x = (wl - 550) / 150
 * the smooth factor whose c solves sum_w W[w] S_b q = rgb (W: the CIE 1931
 * observer under D65 to linear sRGB per bin, ss_spectrum_to_srgb_linear_with
 * of each bin's impulse). q stands for what the texel has that the bare bed
 * has not (its epidermis, melanin, the GGX fit's scale of the albedo):
 * smooth absorbers, as melanin is; the haemoglobin bands stay where the
 * transport put them. The loops then change S_b to S_bed under the same q,
 * so with no loops (or at zero thickness of a layer) the colour is rgb.
 *
 * Layers on the bed (the fresh clot, the exudate) are films on its surface:
 * their R and T per wavelength are the layer table's (Monte Carlo at 16
 * wavelengths, before it converts them), linear in thickness between its
 * samples; then R + T^2 A / (1 - R A) per wavelength, summed with W. A texel
 * costs ~16 x 25 flops and a 3 x 3 solve, no transport.
 *
 * Gave up: q is fitted to three numbers, so pigments with bands of their
 * own (bilirubin of a bruise, methaemoglobin) are not in it, and a texel
 * whose colour is far from the bed's (the skin at the partly open rim) gets
 * a smooth correction of the bed's spectrum, not its own. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <string.h>

#include "skinsim/wound.h"
#include "wound_internal.h"

#define WL_MIN 400.0
#define WL_STEP 20.0

/* The slab of the bed at one sample and wavelength: above the cap, the top
 * loop_mm of its dermis (layers 2..) cut off into layers of the sample's
 * blood. */
static ss_status bed_slab(const ss_optics_data *d, const ss_bio_params *bed, double blood,
                          double cap, double loop_mm, double wl, ss_optics_slab *slab,
                          ss_error *err) {
    ss_bio_params b = *bed;
    b.blood = blood <= cap ? blood : cap;
    ss_status st = ss_optics_skin_slab_with(d, &b, wl, slab, err);
    if (st || blood <= cap || !(loop_mm > 0)) return st;
    /* the dermis' absorption per unit blood fraction, from one at blood 1 */
    ss_optics_slab one;
    b.blood = 1;
    if ((st = ss_optics_skin_slab_with(d, &b, wl, &one, err))) return st;
    ss_optics_slab out = *slab;
    out.nlayers = 2;
    double left = loop_mm * 0.1; /* cm */
    for (int l = 2; l < slab->nlayers; l++) {
        ss_optics_layer L = slab->layer[l];
        double per_blood = (one.layer[l].mua_per_cm - L.mua_per_cm) / (1 - cap);
        if (left > 0 && out.nlayers < SS_OPTICS_MAX_LAYERS - 1) {
            ss_optics_layer top = L;
            top.d_cm = left < L.d_cm ? left : L.d_cm;
            top.mua_per_cm = L.mua_per_cm + (blood - cap) * per_blood;
            out.layer[out.nlayers++] = top;
            left -= top.d_cm;
            L.d_cm -= top.d_cm;
        }
        if (L.d_cm > 1e-9) out.layer[out.nlayers++] = L;
    }
    *slab = out;
    return ss_optics_slab_validate(slab, err);
}

ss_status ss_bed_spectra_build(const ss_bio_params *bed, const double *blood, int nblood,
                               double cap, double loop_depth_mm, uint64_t photons, uint64_t seed,
                               ss_bed_spectra *out, ss_error *err) {
    memset(out, 0, sizeof *out);
    if (nblood < 1 || nblood > SS_BED_MAX_BLOOD || photons < 100 || !(cap > 0 && cap < 1) ||
        !(loop_depth_mm >= 0 && loop_depth_mm <= 10))
        return ss_error_set(err, SS_ERR_INPUT,
                            "bed spectra: need 1..%d blood fractions, a cap in (0, 1), a loop "
                            "depth of 0..10 mm and >= 100 photons",
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
    out->cap = cap;
    out->loop_depth_mm = loop_depth_mm;
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
        ss_optics_slab slab;
        sts[jb] =
            bed_slab(d, bed, blood[k], cap, loop_depth_mm, out->wavelength_nm[w], &slab, &errs[jb]);
        if (sts[jb]) continue;
        sts[jb] = ss_wound__mc_one(&slab, photons, seed + (uint64_t)jb, &out->reflect[k][w], NULL,
                                   &errs[jb]);
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

static double det3(double m[3][3]) {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

int ss_bed_fit(const ss_bed_spectra *s, double blood, const double rgb[3], double q[3]) {
    double f;
    int k = blood_sample(s, blood, &f), k1 = s->nblood > 1 ? k + 1 : k;
    double m[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            m[i][j] = s->moment[k][i][j] + f * (s->moment[k1][i][j] - s->moment[k][i][j]);
    /* m q = rgb by Cramer's rule */
    double det = det3(m);
    double scale = fabs(m[0][0] * m[1][1] * m[2][2]) + fabs(m[0][1] * m[1][2] * m[2][0]) +
                   fabs(m[0][2] * m[1][0] * m[2][1]);
    if (!(fabs(det) > 1e-9 * scale) || !isfinite(det)) return 0;
    for (int j = 0; j < 3; j++) {
        double a[3][3];
        memcpy(a, m, sizeof a);
        for (int i = 0; i < 3; i++) a[i][j] = rgb[i];
        q[j] = det3(a) / det;
    }
    return 1;
}

void ss_bed_eval(const ss_bed_spectra *s, double blood, const double q[3],
                 double out[SS_LAYER_NWL]) {
    double f;
    int k = blood_sample(s, blood, &f), k1 = s->nblood > 1 ? k + 1 : k;
    for (int w = 0; w < SS_LAYER_NWL; w++) {
        double x = s->x[w];
        double sw = s->reflect[k][w] + f * (s->reflect[k1][w] - s->reflect[k][w]);
        out[w] = sw * (q[0] + x * (q[1] + x * q[2]));
    }
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
    double A[SS_LAYER_NWL], q[3];
    if (!ss_bed_fit(s, blood, rgb, q)) {
        double R[3], T[3];
        ss_layer_table_eval(t, thickness_mm, R, T);
        ss_layer_over(R, T, rgb, out);
        return;
    }
    ss_bed_eval(s, blood, q, A);
    ss_layer_add_wl(t, thickness_mm, A, A);
    ss_bed_spectra_to_rgb(s, A, out);
}
