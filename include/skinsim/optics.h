/* skinsim optics: the precalculation phase of seed 003 (§2.1, §3.1.3-3.1.6,
 * §4.1-4.7, §5.2). Biological parameters -> per-layer optical coefficients of a
 * four-layer skin over a diffusely reflecting fat layer -> Monte Carlo photon
 * transport (MCML-style packets, Fresnel at index steps, Trowbridge-Reitz rough
 * surface) -> reflectance spectra, sampled BRDF, radial profile, colour.
 *
 * Units: lengths in cm, coefficients in 1/cm (as MCML), wavelengths in nm,
 * angles in radians, BRDF values in 1/sr.
 *
 * Bin conventions (BRDF): theta bins are uniform in theta over [0, pi/2), bin
 * k has centre (k+0.5)*pi/(2n). dphi = |phi_r - phi_i| folded into [0, pi],
 * bins uniform in dphi. f_r = (weight escaping into the bin) / (incident weight
 * * solid angle of the bin * cos(theta_r at the bin centre)) (seed §3.1.6,
 * §4.5.2); the solid angle of a bin is (cos th0 - cos th1) * dphi_width * 2
 * (both mirror halves phi and -phi fold into one dphi bin).
 * Directions: omega_i (towards the light) and omega_r (towards the viewer) both
 * point away from the surface; the incident packet travels in the x-z plane,
 * so the mirror direction has dphi = pi and retro-reflection dphi = 0.
 * The specular surface reflection IS included in brdf_exit / f_rgb (it is part
 * of the BRDF). Colour albedos and reflectance spectra EXCLUDE it; it is
 * reported separately as `specular`. */
#ifndef SKINSIM_OPTICS_H
#define SKINSIM_OPTICS_H

#include <stdint.h>

#include "skinsim/core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- biological parameters (seed 003 §5.2) -------------------------------- */
typedef struct ss_bio_params {
    double melanin;           /* epidermal melanosome volume fraction 0..1 */
    double pheomelanin_ratio; /* pheomelanin / total melanin 0..1 */
    double blood;             /* dermal blood volume fraction 0..1 */
    double oxygenation;       /* HbO2 / total Hb 0..1 */
    double sc_thickness_cm, epidermis_thickness_cm;
    double bilirubin_g_per_l, betacarotene_g_per_l;
} ss_bio_params;
void ss_bio_params_default(ss_bio_params *p); /* a light skin */
/* Rejects NaN/inf, negative values, fractions > 1 and thicknesses <= 0. */
ss_status ss_bio_params_validate(const ss_bio_params *p, ss_error *err);

/* ---- layered slab ----------------------------------------------------------- */
#define SS_OPTICS_MAX_LAYERS 16
#define SS_OPTICS_PHASE_MAX 65
typedef struct ss_optics_layer {
    double n, mua_per_cm, mus_per_cm, g, d_cm;
    /* Optional tabulated phase function (phase_n = 0: Henyey-Greenstein with
     * g). phase_theta[k] is the polar deflection angle (rad, non-decreasing in
     * [0, pi]) at cumulative probability k / (phase_n - 1), azimuth uniform;
     * g should then hold its mean cosine (informational). Used for the stratum
     * corneum and epidermis (Bruls & van der Leun 1984, docs/optics.md). */
    int phase_n;
    double phase_theta[SS_OPTICS_PHASE_MAX];
} ss_optics_layer;
typedef struct ss_optics_slab {
    int nlayers;
    ss_optics_layer layer[SS_OPTICS_MAX_LAYERS];
    double n_above, n_below;
    double bottom_albedo; /* <0: transmit into n_below (MCML); >=0: Lambertian reflector below
                             the last layer (subcutaneous fat) */
} ss_optics_slab;
/* Validates a slab (layer count, n >= 1, coefficients >= 0, |g| < 1, d > 0). */
ss_status ss_optics_slab_validate(const ss_optics_slab *slab, ss_error *err);
/* The four-layer skin of §2.1 at one wavelength (380..780 nm... any wavelength the
 * spectra cover). Layers: stratum corneum, epidermis, papillary dermis, reticular
 * dermis; bottom_albedo = fat reflectance. */
ss_status ss_optics_skin_slab(const ss_bio_params *bio, double wavelength_nm, ss_optics_slab *out,
                              ss_error *err);
/* The same with the spectra loaded once (ss_optics_skin_slab reads the CSV
 * files of data/spectra on every call): for loops over many parameter sets. */
typedef struct ss_optics_data ss_optics_data; /* opaque: tabulated spectra */
ss_status ss_optics_data_open(ss_optics_data **out, ss_error *err);
void ss_optics_data_close(ss_optics_data *d);
ss_status ss_optics_skin_slab_with(const ss_optics_data *d, const ss_bio_params *bio,
                                   double wavelength_nm, ss_optics_slab *out, ss_error *err);

/* ---- Monte Carlo transport (seed §4.1-4.7) ------------------------------------ */
typedef struct ss_mc_options {
    uint64_t photons, seed;
    double theta_i_rad;           /* incidence angle */
    double roughness_sigma;       /* Trowbridge-Reitz surface roughness; 0 = smooth */
    int stochastic_absorb;        /* seed §4.4 absorb-or-scatter instead of weights */
    int brdf_n_theta, brdf_n_phi; /* if > 0, fill result.brdf_exit (theta_r x dphi bins) */
    int radial_bins;
    double radial_max_cm; /* if > 0, fill result.radial (Rd(r)) */
    int radial_distance;  /* SS_RADIAL_NET (default) or SS_RADIAL_PATH */
    int kernel;           /* SS_MC_KERNEL_AUTO (default), _SCALAR, _PACKET_BASE */
    /* optional (NULL, the default: never cancelled): polled from the calling
     * thread only, every 4,096 photons (scalar path) or 65,536 photons
     * (packet path, about 0.1 s) it traces; a
     * non-zero return stops the run, which then returns SS_ERR_RUNTIME
     * ("cancelled") with nothing in its result. Every call built on ss_mc_run
     * (spectra, BRDFs, tables) copies these options, so one callback cancels
     * them all. Results of runs that are not cancelled do not depend on it. */
    int (*cancel)(void *user);
    void *cancel_user;
} ss_mc_options;
/* Which transport loop runs: AUTO, the packet path (4 photons in SIMD lanes;
 * its AVX2 copy where the processor has AVX2, else the baseline x86-64 copy,
 * with identical results); SCALAR, one photon at a time (the earlier loop,
 * kept for comparison; `--scalar` on the command line); PACKET_BASE, the
 * packet path's baseline copy even where AVX2 exists (for tests). The two
 * paths differ in their samplers, so their results differ bitwise but agree
 * within Monte Carlo error; each is bit-identical for any thread count.
 * Stochastic mode always runs the scalar loop. */
#define SS_MC_KERNEL_AUTO 0
#define SS_MC_KERNEL_SCALAR 1
#define SS_MC_KERNEL_PACKET_BASE 2
/* The distance Rd(r) is binned by: NET, the distance from the entry point to
 * the exit point (the diffusion profile renderers use); PATH, seed 003
 * §4.7.1's D, the length of the path's horizontal projection summed over
 * every segment (D >= net distance for every packet). MCML runs use NET. */
#define SS_RADIAL_NET 0
#define SS_RADIAL_PATH 1
void ss_mc_options_default(ss_mc_options *o);
typedef struct ss_mc_result {
    double specular, diffuse, transmit, absorbed; /* fractions of incident */
    double diffuse_se, transmit_se;               /* standard errors */
    double *brdf_exit; /* [theta_r][dphi] f_r in 1/sr (solid-angle + cos normalised), or NULL */
    double *radial;    /* Rd(r) per cm^2 per bin, or NULL */
    double *absorbed_per_layer; /* nlayers */
    /* Russian roulette changes weight only in expectation: net weight it added
     * (survivor boosts minus killed packets), as a fraction of incident, so that
     * specular + diffuse + transmit + absorbed - roulette_net == 1 to rounding. */
    double roulette_net;
    int nlayers, brdf_n_theta, brdf_n_phi, radial_bins; /* sizes of the arrays above */
    double radial_dr_cm;
} ss_mc_result;
ss_status ss_mc_run(const ss_optics_slab *slab, const ss_mc_options *opt, ss_mc_result *res,
                    ss_error *err);
void ss_mc_result_free(ss_mc_result *res);

/* Fast path for tables (issue item 8): trace packets once per geometry (layer
 * thicknesses, n, mus, g fixed) with absorption switched off, recording per
 * escaping packet its exit bin and path length in each layer; any absorption set
 * can then be applied exactly by reweighting with exp(-sum mua_l * L_l). */
typedef struct ss_mc_paths ss_mc_paths; /* opaque */
ss_status ss_mc_trace_paths(const ss_optics_slab *geometry, const ss_mc_options *opt,
                            ss_mc_paths **out, ss_error *err);
/* mua_per_cm: one per layer; fills specular, diffuse, diffuse_se (and brdf_exit
 * if it was recorded, and radial if recorded), transmit (packets leaving through
 * the bottom boundary only). absorbed and absorbed_per_layer are NaN: the path
 * method does not compute them. Memory: one 76-byte record per traced photon at
 * most; traces of more than 4,000,000 photons are refused. Fat bounces are
 * recorded, so bottom_albedo < 1 is applied exactly as albedo^bounces. */
ss_status ss_mc_paths_apply(const ss_mc_paths *p, const double *mua_per_cm, ss_mc_result *res,
                            ss_error *err);
void ss_mc_paths_free(ss_mc_paths *p);

/* ---- MCML input files (.mci) and output (.mco) ------------------------------------ */
/* One run of an MCML input file (Wang, Jacques & Zheng 1995, MCML 1.2 format):
 * output file name and type (A = ASCII), photon count, grid (dz, dr in cm,
 * number of z, r and angle bins) and the layers (slab->bottom_albedo = -1). */
typedef struct ss_mci_run {
    char out_name[1024];
    char out_type;
    uint64_t photons;
    double dz_cm, dr_cm;
    int nz, nr, na;
    ss_optics_slab slab;
    int kernel; /* SS_MC_KERNEL_*: not in the file (the parser sets AUTO) */
} ss_mci_run;
typedef struct ss_mci_file {
    int nruns;
    ss_mci_run *runs;
} ss_mci_file;
/* Parses the text of a .mci file; `name` is used in error messages. '#' starts
 * a comment; blank lines are skipped. Every value is range-checked; a run line
 * needs both name and type; a grid's 2-D arrays (nr * (nz + 2 na) values) are
 * at most SS_MCI_MAX_GRID_VALUES and must fit in the memory available. */
#define SS_MCI_MAX_GRID_VALUES 10000000
ss_status ss_mci_parse(const char *text, const char *name, ss_mci_file *out, ss_error *err);
void ss_mci_file_free(ss_mci_file *f);
/* Runs one MCML run and returns the MCML-style output text (malloc'd): InParm,
 * RAT (specular, diffuse, absorbed, transmittance), A_l, A_z, Rd_r, Rd_a, Tt_r,
 * Tt_a with MCML's units and normalisations (overflow collected in the last bin
 * as MCML does). */
ss_status ss_mci_simulate(const ss_mci_run *run, uint64_t seed, char **mco_text, ss_error *err);

/* ---- spectra and colour ---------------------------------------------------------- */
typedef struct ss_spectrum_options {
    double wl_min_nm, wl_max_nm, wl_step_nm;
    ss_mc_options mc;
    /* optional: called after each Monte Carlo run with the fraction done (0..1]
     * from the calling thread; NULL (the default) for none */
    void (*progress)(void *user, double fraction_done);
    void *progress_user;
} ss_spectrum_options;
void ss_spectrum_options_default(ss_spectrum_options *o); /* 380..780 step 10 */
typedef struct ss_reflectance_spectrum {
    int n;
    double *wavelength_nm, *reflectance, *std_error;
    double specular;
} ss_reflectance_spectrum;
ss_status ss_optics_reflectance_spectrum(const ss_bio_params *bio, const ss_spectrum_options *o,
                                         ss_reflectance_spectrum *out, ss_error *err);
void ss_reflectance_spectrum_free(ss_reflectance_spectrum *s);
/* spectrum -> CIE 1931 XYZ under D65 -> linear sRGB (albedo; white reflector -> (1,1,1)) */
ss_status ss_spectrum_to_srgb_linear(const double *wl_nm, const double *refl, int n, double rgb[3],
                                     ss_error *err);
/* The same with preloaded spectra (see ss_optics_data_open). */
ss_status ss_spectrum_to_srgb_linear_with(const ss_optics_data *d, const double *wl_nm,
                                          const double *refl, int n, double rgb[3], ss_error *err);
/* Sampled BRDF of a skin (per linear-sRGB channel): bins theta_i x theta_r x dphi, f_r in 1/sr. */
typedef struct ss_brdf_sampled {
    int n_theta_i, n_theta_r, n_phi;
    double *f_rgb; /* [(ti*n_theta_r + tr)*n_phi + p]*3 + c */
} ss_brdf_sampled;
ss_status ss_optics_brdf_sample(const ss_bio_params *bio, const ss_spectrum_options *o,
                                int n_theta_i, int n_theta_r, int n_phi, ss_brdf_sampled *out,
                                ss_error *err);
void ss_brdf_sampled_free(ss_brdf_sampled *b);
/* The surface-reflected part of the skin BRDF alone (air over the stratum
 * corneum's index, rough as o->mc.roughness_sigma; nothing returns from
 * below), the same bins as ss_optics_brdf_sample; grey (equal channels: the
 * indices do not depend on wavelength). o->mc.photons per incidence bin. */
ss_status ss_optics_surface_brdf_sample(const ss_spectrum_options *o, int n_theta_i, int n_theta_r,
                                        int n_phi, ss_brdf_sampled *out, ss_error *err);
/* Radial diffuse reflectance profile Rd(r) per linear-sRGB channel (seed
 * §4.7.1): the spectral Rd(r, lambda) of each radial bin is converted with the
 * CIE observer and D65 like an albedo. Bins of width max_cm/bins from r = 0;
 * rgb[bin*3 + c] in 1/cm^2 (integrates over the plane to the channel albedo
 * minus what falls beyond max_cm); far-out bins can be slightly negative, as a
 * colour-matrix row can be. o->mc.radial_* are ignored. */
ss_status ss_optics_radial_profile_rgb(const ss_bio_params *bio, const ss_spectrum_options *o,
                                       int bins, double max_cm, double *rgb, ss_error *err);

/* Albedo grid over melanin x blood (the swatch): linear-sRGB diffuse albedo at
 * normal incidence (specular excluded) of every (melanin[m], blood[b]) cell,
 * other parameters from bio; rgb[(b * nmel + m) * 3 + c]. Photon paths are
 * traced once per wavelength without absorption and reweighted per cell
 * (exact for the fixed layer geometry). o->progress is called per wavelength. */
ss_status ss_optics_albedo_grid(const ss_bio_params *bio, const ss_spectrum_options *o,
                                const double *melanin, int nmel, const double *blood, int nbl,
                                double *rgb, ss_error *err);

/* ---- healing skin as tissue (src/optics/healing.c) -------------------------------- */
/* New epithelium, shared by `abrasion` and `wound`: a thin epidermis over
 * young, hyperaemic dermis. */
#define SS_NEW_EPIDERMIS_FRACTION 0.6 /* its thickness, of the skin's epidermis */
#define SS_YOUNG_DERMIS_BLOOD 0.04    /* blood volume fraction of the dermis below it */
#define SS_YOUNG_DERMIS_OXYGENATION 0.9
/* out = skin with its melanin times melanin_factor, the epidermis thinned and
 * the dermal blood of the young tissue (out may be skin). */
void ss_bio_new_epithelium(const ss_bio_params *skin, double melanin_factor, ss_bio_params *out);
/* Fraction of patients with post-inflammatory hyperpigmentation after an
 * inflammatory skin injury, by the skin's individual typology angle (ITA,
 * degrees; Chardon et al. 1991 classes), from the rates of Taylor et al. 2002
 * and Davis & Callender 2010: 0.03 for very light skin, 0.65 for dark skin. */
double ss_pih_prevalence(double ita_deg);
/* Its time course: the healed skin's pigmentation above the adjacent skin's
 * (a fraction) `days` after closure, through Danielsen et al. 2013's donor
 * sites (+0.24 at 30 d, +0.15 at 90 d, ~0 at 365 d; 0 at and before 0 d). */
double ss_pih_course(double days);
/* The healed skin's melanin factor from PIH, for both wound paths:
 * 1 + gain x prevalence x ss_pih_course(days). SS_PIH_GAIN is the default
 * gain (ours): a light skin (rate 0.08-0.13) gets +12-18 % at a month, near
 * Danielsen's +24 % in Danish patients, a dark one (0.65) 1.94x at a month,
 * 1.59x at 3 months, 1.04x at a year (12.5, Danielsen's exactly at rate
 * 0.08, gave a dark skin 2.95x: a healed ring 9.6 L* below the skin). */
#define SS_PIH_GAIN 6.0
double ss_pih_melanin_factor(double prevalence, double days, double gain);
/* The healed epidermis's melanin apart from PIH, for both wound paths: a
 * factor of the skin's melanin `days` after closure. The new epithelium
 * starts melanin-poor (new_melanin of the skin's) and repigments from the
 * margin and the follicles over repig_days; from SS_SCAR_PALE_DELAY_DAYS
 * on, the maturing scar loses some of it, towards scar_melanin over
 * SS_SCAR_PALE_DAYS:
 *   [n + (1 - n)(1 - exp(-t / repig))] x [1 - (1 - s)(1 - exp(-max(0, t - delay) / pale))].
 * The defaults (SS_REPIG_*) are `abrasion`'s and `wound`'s recipe's. */
typedef struct ss_repigmentation {
    double new_melanin;  /* of the skin's, at closure */
    double repig_days;   /* time constant of repigmentation */
    double scar_melanin; /* of the skin's, in the mature scar (< 1 hypopigmented) */
} ss_repigmentation;
#define SS_REPIG_NEW_MELANIN 0.5
#define SS_REPIG_DAYS 10.0
#define SS_REPIG_SCAR_MELANIN 0.75
#define SS_SCAR_PALE_DELAY_DAYS 30.0
#define SS_SCAR_PALE_DAYS 150.0
void ss_repigmentation_default(ss_repigmentation *p);
double ss_repigmentation_factor(const ss_repigmentation *p, double days);
/* The healed skin's whole melanin factor on one day: repigmentation times
 * the PIH factor at the skin's rate (the skin's melanin enters through that
 * rate, from its typology angle), the one curve of both paths:
 * ss_repigmentation_factor(p, days) x ss_pih_melanin_factor(prevalence, days, gain).
 * Dark skin (rate 0.65, default gain): 1.89x at 30 d, 1.45x at 90 d, 0.81x at
 * 365 d; light (0.125): 1.15x, 1.02x, 0.78x of a melanin that is small. */
double ss_healed_melanin_factor(const ss_repigmentation *p, double prevalence, double gain,
                                double days);

/* ---- CIELAB and CIEDE2000 (src/optics/colour.c) ---------------------------------- */
/* Linear sRGB (white-normalised albedo, as above) <-> CIELAB, D65 white. */
void ss_srgb_linear_to_lab(const double rgb[3], double lab[3]);
void ss_lab_to_srgb_linear(const double lab[3], double rgb[3]);
/* Chroma C*ab, hue angle h_ab in degrees [0, 360) and individual typology
 * angle ITA = atan((L* - 50) / b*) in degrees; any output may be NULL. */
void ss_lab_describe(const double lab[3], double *chroma, double *hue_deg, double *ita_deg);
/* CIEDE2000 colour difference (kL = kC = kH = 1; Sharma, Wu & Dalal 2005). */
double ss_ciede2000(const double lab1[3], const double lab2[3]);

#ifdef __cplusplus
}
#endif
#endif
