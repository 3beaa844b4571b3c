/* Reflectance spectra, colour and the sampled BRDF of skin (seed 003 §4.5.2,
 * §4.7.1, §3.1.6): runs the transport per wavelength and turns spectra into
 * CIE 1931 XYZ under D65 and linear sRGB albedo.
 *
 * Colour: the spectrum is interpolated linearly onto the 1 nm grid of the CIE
 * tables over 380..780 nm (held constant beyond its ends), X = sum R S xbar /
 * sum S ybar (S = D65, so a perfect white has Y = 1), then the IEC 61966-2-1
 * XYZ -> linear sRGB matrix, and each channel is divided by the value a
 * perfect white reflector gives, so white maps to exactly (1,1,1). The map is
 * linear in R, so a per-wavelength weight vector (the colour of a unit impulse
 * at each sample wavelength) converts BRDF and radial-profile spectra too.
 * The same seed is used at every wavelength (common random numbers), which
 * makes spectra smooth: neighbouring wavelengths share photon paths. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "optics_internal.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static const double XYZ_TO_SRGB[3][3] = {{3.2404542, -1.5371385, -0.4985314},
                                         {-0.9692660, 1.8760108, 0.0415560},
                                         {0.0556434, -0.2040259, 1.0572252}};

void ss_spectrum_options_default(ss_spectrum_options *o) {
    memset(o, 0, sizeof *o);
    o->wl_min_nm = 380.0;
    o->wl_max_nm = 780.0;
    o->wl_step_nm = 10.0;
    ss_mc_options_default(&o->mc);
    o->mc.photons = 20000;
    o->mc.roughness_sigma = 0.75; /* BioSpec default surface roughness */
}

static double interp_refl(const double *wl, const double *r, int n, double x) {
    if (x <= wl[0]) return r[0];
    if (x >= wl[n - 1]) return r[n - 1];
    int lo = 0, hi = n - 1;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (wl[mid] <= x)
            lo = mid;
        else
            hi = mid;
    }
    double f = (x - wl[lo]) / (wl[hi] - wl[lo]);
    return r[lo] + f * (r[hi] - r[lo]);
}

static void xyz_of(const ss_optics_data *d, const double *wl, const double *r, int n,
                   double xyz[3]) {
    double sx = 0, sy = 0, sz = 0, norm = 0;
    for (int nm = 380; nm <= 780; nm++) {
        double S = ss_spectrum_table_eval(&d->d65, nm);
        double xb = ss_spectrum_table_eval(&d->cie_x, nm);
        double yb = ss_spectrum_table_eval(&d->cie_y, nm);
        double zb = ss_spectrum_table_eval(&d->cie_z, nm);
        double R = r ? interp_refl(wl, r, n, nm) : 1.0;
        sx += R * S * xb;
        sy += R * S * yb;
        sz += R * S * zb;
        norm += S * yb;
    }
    xyz[0] = sx / norm;
    xyz[1] = sy / norm;
    xyz[2] = sz / norm;
}

static void rgb_of_xyz(const double xyz[3], double rgb[3]) {
    for (int c = 0; c < 3; c++)
        rgb[c] =
            XYZ_TO_SRGB[c][0] * xyz[0] + XYZ_TO_SRGB[c][1] * xyz[1] + XYZ_TO_SRGB[c][2] * xyz[2];
}

static ss_status check_spectrum(const double *wl, const double *refl, int n, ss_error *err) {
    if (!wl || !refl || n < 1)
        return ss_error_set(err, SS_ERR_INPUT, "spectrum: need at least one sample (got %d)", n);
    for (int i = 0; i < n; i++) {
        if (!isfinite(wl[i]) || !isfinite(refl[i]))
            return ss_error_set(err, SS_ERR_INPUT, "spectrum: sample %d is not finite", i);
        if (i > 0 && !(wl[i] > wl[i - 1]))
            return ss_error_set(err, SS_ERR_INPUT,
                                "spectrum: wavelengths must increase (sample %d: %g after %g)", i,
                                wl[i], wl[i - 1]);
    }
    return SS_OK;
}

ss_status ss_spectrum_to_srgb_data(const ss_optics_data *d, const double *wl_nm, const double *refl,
                                   int n, double rgb[3], ss_error *err) {
    ss_status st = check_spectrum(wl_nm, refl, n, err);
    if (st) return st;
    double xyz[3], xyzw[3], w[3], v[3];
    xyz_of(d, wl_nm, refl, n, xyz);
    xyz_of(d, NULL, NULL, 0, xyzw);
    rgb_of_xyz(xyz, v);
    rgb_of_xyz(xyzw, w);
    for (int c = 0; c < 3; c++) rgb[c] = v[c] / w[c];
    return SS_OK;
}

ss_status ss_spectrum_to_srgb_linear(const double *wl_nm, const double *refl, int n, double rgb[3],
                                     ss_error *err) {
    ss_status st = check_spectrum(wl_nm, refl, n, err);
    if (st) return st;
    ss_optics_data d;
    st = ss_optics_data_load(&d, err);
    if (st) return st;
    st = ss_spectrum_to_srgb_data(&d, wl_nm, refl, n, rgb, err);
    ss_optics_data_free(&d);
    return st;
}

ss_status ss_spectrum_to_srgb_linear_with(const ss_optics_data *d, const double *wl_nm,
                                          const double *refl, int n, double rgb[3], ss_error *err) {
    if (!d) return ss_error_set(err, SS_ERR_INPUT, "spectra are NULL");
    return ss_spectrum_to_srgb_data(d, wl_nm, refl, n, rgb, err);
}

/* Linear-sRGB weight of each sample wavelength: rgb = sum_k W[k] R_k. */
static ss_status colour_weights(const ss_optics_data *d, const double *wl, int n, double *W,
                                ss_error *err) {
    double *imp = calloc((size_t)n, sizeof *imp);
    if (!imp) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    for (int k = 0; k < n; k++) {
        imp[k] = 1.0;
        ss_status st = ss_spectrum_to_srgb_data(d, wl, imp, n, &W[3 * k], err);
        imp[k] = 0.0;
        if (st) {
            free(imp);
            return st;
        }
    }
    free(imp);
    return SS_OK;
}

static ss_status check_spec_opts(const ss_spectrum_options *o, int *nwl, ss_error *err) {
    if (!o) return ss_error_set(err, SS_ERR_INPUT, "spectrum options are missing");
    if (!(o->wl_min_nm >= 300.0 && o->wl_max_nm <= 800.0 && o->wl_min_nm <= o->wl_max_nm))
        return ss_error_set(err, SS_ERR_INPUT,
                            "wavelength range %g..%g nm must lie within 300..800 nm", o->wl_min_nm,
                            o->wl_max_nm);
    if (!(o->wl_step_nm > 0.0 && o->wl_step_nm <= 400.0))
        return ss_error_set(err, SS_ERR_INPUT, "wavelength step %g nm must be in (0, 400]",
                            o->wl_step_nm);
    double span = (o->wl_max_nm - o->wl_min_nm) / o->wl_step_nm;
    if (span > 10000)
        return ss_error_set(err, SS_ERR_INPUT, "wavelength step %g nm gives too many samples",
                            o->wl_step_nm);
    *nwl = (int)floor(span + 1e-9) + 1;
    return SS_OK;
}

void ss_reflectance_spectrum_free(ss_reflectance_spectrum *s) {
    if (!s) return;
    free(s->wavelength_nm);
    free(s->reflectance);
    free(s->std_error);
    s->wavelength_nm = s->reflectance = s->std_error = NULL;
    s->n = 0;
}

ss_status ss_optics_reflectance_spectrum(const ss_bio_params *bio, const ss_spectrum_options *o,
                                         ss_reflectance_spectrum *out, ss_error *err) {
    if (!out) return ss_error_set(err, SS_ERR_INPUT, "spectrum output is NULL");
    memset(out, 0, sizeof *out);
    int n;
    ss_status st = check_spec_opts(o, &n, err);
    if (st) return st;
    if ((st = ss_bio_params_validate(bio, err))) return st;
    ss_optics_data d;
    if ((st = ss_optics_data_load(&d, err))) return st;
    out->wavelength_nm = calloc((size_t)n, sizeof(double));
    out->reflectance = calloc((size_t)n, sizeof(double));
    out->std_error = calloc((size_t)n, sizeof(double));
    if (!out->wavelength_nm || !out->reflectance || !out->std_error) {
        ss_optics_data_free(&d);
        ss_reflectance_spectrum_free(out);
        return ss_error_set(err, SS_ERR_NOMEM, "out of memory for the spectrum");
    }
    out->n = n;
    ss_mc_options mc = o->mc;
    mc.brdf_n_theta = mc.brdf_n_phi = 0;
    mc.radial_bins = 0;
    mc.radial_max_cm = 0;
    double spec = 0.0;
    for (int k = 0; k < n && !st; k++) {
        double wl = o->wl_min_nm + k * o->wl_step_nm;
        ss_optics_slab slab;
        ss_mc_result r;
        st = ss_optics_skin_slab_data(&d, bio, wl, &slab, err);
        if (!st) st = ss_mc_run(&slab, &mc, &r, err);
        if (st) break;
        out->wavelength_nm[k] = wl;
        out->reflectance[k] = r.diffuse;
        out->std_error[k] = r.diffuse_se;
        spec += r.specular;
        ss_mc_result_free(&r);
        if (o->progress) o->progress(o->progress_user, (double)(k + 1) / n);
    }
    ss_optics_data_free(&d);
    if (st) {
        ss_reflectance_spectrum_free(out);
        return st;
    }
    out->specular = spec / n;
    return SS_OK;
}

void ss_brdf_sampled_free(ss_brdf_sampled *b) {
    if (!b) return;
    free(b->f_rgb);
    b->f_rgb = NULL;
}

/* Checks shared by the BRDF samplers; clears *out, sets *n (wavelengths). */
static ss_status check_brdf_args(const ss_spectrum_options *o, int n_theta_i, int n_theta_r,
                                 int n_phi, ss_brdf_sampled *out, int *n, ss_error *err) {
    if (!out) return ss_error_set(err, SS_ERR_INPUT, "BRDF output is NULL");
    memset(out, 0, sizeof *out);
    ss_status st = check_spec_opts(o, n, err);
    if (st) return st;
    if (n_theta_i < 1 || n_theta_i > 256 || n_theta_r < 1 || n_theta_r > 256 || n_phi < 1 ||
        n_phi > 256)
        return ss_error_set(err, SS_ERR_INPUT,
                            "BRDF bins theta_i %d x theta_r %d x phi %d: each must be 1..256",
                            n_theta_i, n_theta_r, n_phi);
    return SS_OK;
}

/* One incidence row of a sampled BRDF: theta_i at the centre of row ti, the
 * exit directions binned, no radial profile. */
static ss_mc_options brdf_row_options(const ss_mc_options *base, int ti, int n_theta_i,
                                      int n_theta_r, int n_phi) {
    ss_mc_options mc = *base;
    mc.theta_i_rad = (ti + 0.5) * M_PI / (2.0 * n_theta_i);
    mc.brdf_n_theta = n_theta_r;
    mc.brdf_n_phi = n_phi;
    mc.radial_bins = 0;
    mc.radial_max_cm = 0;
    return mc;
}

ss_status ss_optics_brdf_sample(const ss_bio_params *bio, const ss_spectrum_options *o,
                                int n_theta_i, int n_theta_r, int n_phi, ss_brdf_sampled *out,
                                ss_error *err) {
    int n;
    ss_status st = check_brdf_args(o, n_theta_i, n_theta_r, n_phi, out, &n, err);
    if (st) return st;
    if ((st = ss_bio_params_validate(bio, err))) return st;
    ss_optics_data d;
    if ((st = ss_optics_data_load(&d, err))) return st;
    size_t nb = (size_t)n_theta_r * (size_t)n_phi;
    double *wl = calloc((size_t)n, sizeof *wl), *W = calloc((size_t)n * 3, sizeof *W);
    out->f_rgb = calloc((size_t)n_theta_i * nb * 3, sizeof(double));
    if (!wl || !W || !out->f_rgb) {
        free(wl);
        free(W);
        ss_optics_data_free(&d);
        ss_brdf_sampled_free(out);
        return ss_error_set(err, SS_ERR_NOMEM, "out of memory for the BRDF");
    }
    for (int k = 0; k < n; k++) wl[k] = o->wl_min_nm + k * o->wl_step_nm;
    st = colour_weights(&d, wl, n, W, err);
    out->n_theta_i = n_theta_i;
    out->n_theta_r = n_theta_r;
    out->n_phi = n_phi;
    for (int k = 0; k < n && !st; k++) {
        ss_optics_slab slab;
        st = ss_optics_skin_slab_data(&d, bio, wl[k], &slab, err);
        for (int ti = 0; ti < n_theta_i && !st; ti++) {
            ss_mc_options mc = brdf_row_options(&o->mc, ti, n_theta_i, n_theta_r, n_phi);
            ss_mc_result r;
            st = ss_mc_run(&slab, &mc, &r, err);
            if (st) break;
            double *f = out->f_rgb + (size_t)ti * nb * 3;
            for (size_t b = 0; b < nb; b++)
                for (int c = 0; c < 3; c++) f[b * 3 + c] += W[3 * k + c] * r.brdf_exit[b];
            ss_mc_result_free(&r);
            if (o->progress)
                o->progress(o->progress_user, (double)(k * n_theta_i + ti + 1) / (n * n_theta_i));
        }
    }
    free(wl);
    free(W);
    ss_optics_data_free(&d);
    if (st) ss_brdf_sampled_free(out);
    return st;
}

ss_status ss_optics_surface_brdf_sample(const ss_spectrum_options *o, int n_theta_i, int n_theta_r,
                                        int n_phi, ss_brdf_sampled *out, ss_error *err) {
    int n;
    ss_status st = check_brdf_args(o, n_theta_i, n_theta_r, n_phi, out, &n, err);
    if (st) return st;
    /* the skin's own surface: indices of air and stratum corneum from the slab */
    ss_bio_params bio;
    ss_bio_params_default(&bio);
    ss_optics_slab skin, slab;
    if ((st = ss_optics_skin_slab(&bio, 550.0, &skin, err))) return st;
    memset(&slab, 0, sizeof slab);
    slab.nlayers = 1;
    slab.layer[0].n = skin.layer[0].n;
    slab.layer[0].d_cm = skin.layer[0].d_cm;
    slab.n_above = skin.n_above;
    slab.n_below = skin.layer[0].n; /* what enters leaves: only the surface reflects */
    slab.bottom_albedo = -1.0;
    size_t nb = (size_t)n_theta_r * (size_t)n_phi;
    out->f_rgb = calloc((size_t)n_theta_i * nb * 3, sizeof(double));
    if (!out->f_rgb) return ss_error_set(err, SS_ERR_NOMEM, "out of memory for the BRDF");
    out->n_theta_i = n_theta_i;
    out->n_theta_r = n_theta_r;
    out->n_phi = n_phi;
    for (int ti = 0; ti < n_theta_i && !st; ti++) {
        ss_mc_options mc = brdf_row_options(&o->mc, ti, n_theta_i, n_theta_r, n_phi);
        ss_mc_result r;
        if ((st = ss_mc_run(&slab, &mc, &r, err))) break;
        double *f = out->f_rgb + (size_t)ti * nb * 3;
        for (size_t b = 0; b < nb; b++)
            for (int c = 0; c < 3; c++) f[b * 3 + c] = r.brdf_exit[b]; /* grey */
        ss_mc_result_free(&r);
    }
    if (st) ss_brdf_sampled_free(out);
    return st;
}

ss_status ss_optics_radial_profile_rgb(const ss_bio_params *bio, const ss_spectrum_options *o,
                                       int bins, double max_cm, double *rgb, ss_error *err) {
    int n;
    ss_status st = check_spec_opts(o, &n, err);
    if (st) return st;
    if (bins < 1 || bins > 100000 || !(max_cm > 0.0 && max_cm < 100.0) || !rgb)
        return ss_error_set(err, SS_ERR_INPUT,
                            "radial profile: %d bins up to %g cm (need 1..100000 bins, 0 < max "
                            "< 100 cm)",
                            bins, max_cm);
    if ((st = ss_bio_params_validate(bio, err))) return st;
    ss_optics_data d;
    if ((st = ss_optics_data_load(&d, err))) return st;
    double *wl = calloc((size_t)n, sizeof *wl), *W = calloc((size_t)n * 3, sizeof *W);
    if (!wl || !W) {
        free(wl);
        free(W);
        ss_optics_data_free(&d);
        return ss_error_set(err, SS_ERR_NOMEM, "out of memory for the radial profile");
    }
    for (int k = 0; k < n; k++) wl[k] = o->wl_min_nm + k * o->wl_step_nm;
    st = colour_weights(&d, wl, n, W, err);
    for (int i = 0; i < bins * 3; i++) rgb[i] = 0.0;
    for (int k = 0; k < n && !st; k++) {
        ss_optics_slab slab;
        st = ss_optics_skin_slab_data(&d, bio, wl[k], &slab, err);
        if (st) break;
        ss_mc_options mc = o->mc;
        mc.brdf_n_theta = mc.brdf_n_phi = 0;
        mc.radial_bins = bins;
        mc.radial_max_cm = max_cm;
        ss_mc_result r;
        st = ss_mc_run(&slab, &mc, &r, err);
        if (st) break;
        for (int b = 0; b < bins; b++)
            for (int c = 0; c < 3; c++) rgb[b * 3 + c] += W[3 * k + c] * r.radial[b];
        ss_mc_result_free(&r);
        if (o->progress) o->progress(o->progress_user, (double)(k + 1) / n);
    }
    free(wl);
    free(W);
    ss_optics_data_free(&d);
    return st;
}

ss_status ss_optics_albedo_grid(const ss_bio_params *bio, const ss_spectrum_options *o,
                                const double *M, int nmel, const double *B, int nbl, double *rgb,
                                ss_error *err) {
    if (!bio || !o || !M || !B || !rgb || nmel < 1 || nbl < 1)
        return ss_error_set(err, SS_ERR_INPUT, "albedo grid: missing input or empty lists");
    int nwl;
    ss_status st = check_spec_opts(o, &nwl, err);
    if (st) return st;
    size_t ncell = (size_t)nmel * (size_t)nbl;
    double *wl = calloc((size_t)nwl, sizeof *wl);
    double *refl = calloc((size_t)nwl * ncell, sizeof *refl);
    ss_optics_data *data = NULL;
    if (!wl || !refl) {
        free(wl);
        free(refl);
        return ss_error_set(err, SS_ERR_NOMEM, "albedo grid: out of memory");
    }
    st = ss_optics_data_open(&data, err);
    ss_mc_options mo = o->mc;
    mo.brdf_n_theta = mo.brdf_n_phi = mo.radial_bins = 0;
    mo.radial_max_cm = 0.0;
    mo.theta_i_rad = 0.0;
    for (int k = 0; k < nwl && !st; k++) {
        wl[k] = o->wl_min_nm + k * o->wl_step_nm;
        ss_optics_slab geom;
        ss_mc_paths *paths = NULL;
        st = ss_optics_skin_slab_with(data, bio, wl[k], &geom, err);
        if (!st) st = ss_mc_trace_paths(&geom, &mo, &paths, err);
        for (int bi = 0; bi < nbl && !st; bi++)
            for (int mi = 0; mi < nmel && !st; mi++) {
                ss_bio_params b = *bio;
                b.melanin = M[mi];
                b.blood = B[bi];
                ss_optics_slab s;
                st = ss_optics_skin_slab_with(data, &b, wl[k], &s, err);
                if (st) break;
                double mua[SS_OPTICS_MAX_LAYERS];
                for (int l = 0; l < s.nlayers; l++) mua[l] = s.layer[l].mua_per_cm;
                ss_mc_result r;
                st = ss_mc_paths_apply(paths, mua, &r, err);
                if (st) break;
                refl[((size_t)bi * nmel + mi) * nwl + k] = r.diffuse;
                ss_mc_result_free(&r);
            }
        ss_mc_paths_free(paths);
        if (o->progress) o->progress(o->progress_user, (double)(k + 1) / nwl);
    }
    for (size_t q = 0; q < ncell && !st; q++)
        st = ss_spectrum_to_srgb_data(data, wl, refl + q * nwl, nwl, rgb + 3 * q, err);
    ss_optics_data_close(data);
    free(wl);
    free(refl);
    return st;
}
