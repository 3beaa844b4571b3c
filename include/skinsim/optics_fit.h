/* skinsim optics ModelMatch: render BRDF models (Ashikhmin-Shirley, glTF GGX +
 * Lambert), least-squares fitting of a render BRDF to a sampled skin BRDF
 * (seed 003 §4.6-4.7, distance weighted by bin solid angle §3.1.6), and the
 * precomputed ModelMatch table over the optical biological parameters with
 * multilinear lookup and a versioned binary file (seed 003 §4.8.6, §5.2, §6.1).
 *
 * Angles: theta measured from the surface normal in radians, dphi = |phi_r -
 * phi_i| in [0, pi]. BRDF values in 1/sr. Colours are linear sRGB. */
#ifndef SKINSIM_OPTICS_FIT_H
#define SKINSIM_OPTICS_FIT_H

#include "skinsim/core.h"
#include "skinsim/optics.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- render BRDF models -------------------------------------------------- */

/* GGX: the glTF 2.0 metallic-roughness model with metallic = 0: GGX
 * specular D*V*F (height-correlated Smith V, Schlick F(h.k)) plus Lambert
 * c/pi. glTF weights the Lambert term by 1 - F(h.k), which is not energy
 * bounded at grazing incidence (directional albedo up to 1.54 for a white
 * base, roughness 0.15, 85 degrees); skinsim weights it by the reciprocal
 * Fresnel transmission (1 - F(cos_i)) (1 - F(cos_r)) instead, which keeps
 * the albedo <= 1 (docs/modelmatch.md). */
typedef enum ss_render_model {
    SS_RENDER_GGX = 0, /* glTF metallic-roughness, metallic = 0: Lambert + GGX */
    SS_RENDER_AS = 1   /* Ashikhmin-Shirley 2000, isotropic */
} ss_render_model;
#define SS_RENDER_NMODELS 2
const char *ss_render_model_name(ss_render_model m); /* "ggx" / "ashikhmin-shirley" */

/* Parameters shared by both models:
 *   base_rgb  diffuse colour, linear RGB in [0,1] (GGX: c_diff; AS: R_d)
 *   specular  specular strength in [0,1]; normal-incidence Fresnel
 *             F0 = 0.08 * specular (0.5 -> 0.04, the glTF dielectric default)
 *   roughness perceptual roughness in [0,1]; GGX alpha = roughness^2,
 *             AS exponent n = 2/alpha^2 - 2 (the Beckmann-equivalent lobe). */
typedef struct ss_render_params {
    double base_rgb[3];
    double specular;
    double roughness;
} ss_render_params;
#define SS_RENDER_F0_PER_SPECULAR 0.08
#define SS_RENDER_ROUGHNESS_MIN 0.05 /* fits stay in [MIN, 1] */

/* The models are linear in the base colour: f_c = base_c * diffuse + specular.
 * Writes both terms (1/sr) for one direction pair. */
void ss_render_brdf_terms(ss_render_model m, double specular, double roughness, double theta_i,
                          double theta_r, double dphi, double *diffuse, double *spec);
/* The direction-dependent quantities of one (theta_i, theta_r, dphi) triple,
 * precomputed so that a fitter can evaluate many parameter sets cheaply. */
typedef struct ss_render_geom {
    double cos_i, cos_r; /* cosines to the normal (> 0 for valid pairs) */
    double cos_h;        /* n . h, h the half vector */
    double log_cos_h;    /* log(n . h) */
    double cos_hk;       /* h . k_i = h . k_r */
    double schlick5;     /* (1 - h.k)^5 */
    double schlick5_i;   /* (1 - cos_i)^5 */
    double schlick5_r;   /* (1 - cos_r)^5 */
    double as_diffuse;   /* 28/(23 pi) (1-(1-cos_i/2)^5)(1-(1-cos_r/2)^5) */
    int valid;           /* 0 when either direction is at or below the horizon */
} ss_render_geom;
void ss_render_geom_init(double theta_i, double theta_r, double dphi, ss_render_geom *g);
/* Directional albedo E(cos_theta) of the GGX model's specular lobe (Schlick F,
 * height-correlated Smith), from the table the GGX diffuse coupling uses;
 * roughness is clamped to [SS_RENDER_ROUGHNESS_MIN, 1]. */
double ss_render_ggx_spec_albedo(double specular, double roughness, double cos_theta);
void ss_render_terms_geom(ss_render_model m, double specular, double roughness,
                          const ss_render_geom *g, double *diffuse, double *spec);

/* f_r (1/sr) per channel. */
void ss_render_brdf_eval(ss_render_model m, const ss_render_params *p, double theta_i,
                         double theta_r, double dphi, double f_rgb[3]);

/* Sampled BRDF of a render model in the ss_brdf_sampled layout: theta_i at
 * bin centres (k+0.5)*pi/(2n), each exit bin (theta_r, dphi) estimated the
 * way the photon tally of ss_mc_run does it: integral of f cos(theta_r) dw
 * over the bin divided by (solid angle * cos(theta_r at the bin centre)),
 * by a midpoint rule with subsamples x subsamples points.
 * out->f_rgb is malloc'd (free with ss_brdf_sampled_free or free()). */
ss_status ss_render_brdf_sample(ss_render_model m, const ss_render_params *p, int n_theta_i,
                                int n_theta_r, int n_phi, int subsamples, ss_brdf_sampled *out,
                                ss_error *err);

/* Directional albedo: integral of f cos(theta_r) over the hemisphere for one
 * channel value of base colour, by midpoint quadrature with n x n points. */
double ss_render_albedo(ss_render_model m, const ss_render_params *p, double theta_i, int channel,
                        int n);

/* ---- fitting (seed 003 §4.6-4.7) ----------------------------------------- */

/* Weight of each (theta_i, theta_r, dphi) bin in the squared distance.
 *   SS_FIT_SOLID_ANGLE: dtheta_i x solid angle of the exit bin (§3.1.6)
 *   SS_FIT_UNIFORM:     dtheta_i dtheta_r dphi, the seed's §4.6 integral read
 *                       literally (uniform in the angles)
 *   SS_FIT_PROJECTED:   solid angle x cos(theta_i) cos(theta_r): irradiance
 *                       times projected solid angle, which de-emphasises the
 *                       grazing bins (see docs/modelmatch.md) */
typedef enum ss_fit_weighting {
    SS_FIT_SOLID_ANGLE = 0,
    SS_FIT_UNIFORM = 1,
    SS_FIT_PROJECTED = 2
} ss_fit_weighting;
const char *ss_fit_weighting_name(int w); /* "solid-angle", "uniform", "projected" */

typedef struct ss_fit_options {
    int subsamples;       /* per exit bin and axis for the model's bin average (default 3) */
    int max_iter;         /* Nelder-Mead iterations (default 300) */
    double tol;           /* relative distance tolerance (default 1e-10) */
    int weighting;        /* an ss_fit_weighting (default SS_FIT_SOLID_ANGLE) */
    double max_theta_rad; /* bins whose theta_i or theta_r centre lies above this get
                             weight 0 (default pi/2: all bins) */
    int base_mode;        /* an ss_fit_base_mode (default SS_FIT_BASE_FREE) */
    double albedo_rgb[3]; /* SS_FIT_BASE_ALBEDO: the skin's diffuse albedo at normal incidence */
    const struct ss_brdf_sampled *surface; /* SS_FIT_BASE_ALBEDO, optional: the surface-reflected
                                              part of the BRDF alone (same bins); the lobe is
                                              fitted to it */
} ss_fit_options;
/* How the base colour is found. FREE: in closed form with the lobe, minimising
 * the seed's distance over the whole BRDF. ALBEDO: the base colour whose
 * diffuse term reflects albedo_rgb at normal incidence (the render model then
 * has the skin's albedo), and only the lobe (specular, roughness) is fitted:
 * to `surface` when given, else to the whole BRDF. */
enum { SS_FIT_BASE_FREE = 0, SS_FIT_BASE_ALBEDO = 1 };
void ss_fit_options_default(ss_fit_options *o);

typedef struct ss_fit_result {
    ss_render_model model;
    ss_render_params params;
    double distance;     /* weighted squared distance sum w (f_model - f_data)^2, 1/sr^2 */
    double residual_rms; /* sqrt(distance / sum w) / channels, 1/sr */
    double residual_rel; /* sqrt(distance / sum w f_data^2): relative residual */
    int evaluations;
} ss_fit_result;

/* Least-squares fit of render model m to the sampled BRDF data. The distance
 * is the seed's discretised integral over (theta_i, theta_r, dphi) with each
 * term weighted by the solid angle of its exit bin (sin theta_r dtheta_r
 * dphi, §3.1.6) and the width of the incidence bin, summed over R, G, B.
 * The base colour enters linearly and is solved in closed form for each
 * (specular, roughness); those two are found by a coarse grid and
 * Nelder-Mead (variable projection). */
ss_status ss_render_fit(ss_render_model m, const ss_brdf_sampled *data, const ss_fit_options *o,
                        ss_fit_result *out, ss_error *err);

/* ---- ModelMatch table (seed 003 §4.8.6) ----------------------------------- */

/* Table axes: the optical biological parameters of seed 003 §5.2. */
enum {
    SS_MM_AXIS_MELANIN = 0,     /* melanosome volume fraction in the epidermis */
    SS_MM_AXIS_PHEOMELANIN = 1, /* pheomelanin ratio 0..1 */
    SS_MM_AXIS_BLOOD = 2,       /* blood volume fraction in the dermis */
    SS_MM_AXIS_OXYGENATION = 3, /* oxygen saturation 0..1 */
    SS_MM_AXIS_SC = 4,          /* stratum corneum thickness, cm */
    SS_MM_AXIS_EPIDERMIS = 5,   /* epidermis thickness, cm */
    SS_MM_NAXES = 6
};
const char *ss_mm_axis_name(int axis); /* "melanin", "pheomelanin", ... */
/* Default axis ranges (lo, hi) used by `skinsim optics table`. */
void ss_mm_axis_default_range(int axis, double *lo, double *hi);

/* One table entry: the fitted render parameters. */
typedef struct ss_mm_entry {
    ss_render_params fit[SS_RENDER_NMODELS]; /* indexed by ss_render_model */
    double residual_rel[SS_RENDER_NMODELS];  /* relative fit residual */
    double sss_radius_cm[3];                 /* subsurface mean radius per RGB channel */
    double albedo_rgb[3]; /* diffuse reflectance (linear RGB), normal incidence */
} ss_mm_entry;
#define SS_MM_NFIELDS 18 /* doubles per entry in the file, see docs/modelmatch.md */
void ss_mm_entry_pack(const ss_mm_entry *e, double v[SS_MM_NFIELDS]);
void ss_mm_entry_unpack(const double v[SS_MM_NFIELDS], ss_mm_entry *e);

#define SS_MM_MAX_SURFACE 32
typedef struct ss_mm_table {
    int nsamples[SS_MM_NAXES];
    double *axis[SS_MM_NAXES]; /* strictly increasing sample values per axis */
    size_t nentries;           /* product of nsamples */
    double *entries;           /* nentries * SS_MM_NFIELDS; axis 0 slowest, axis 5 fastest */
    /* how it was made */
    uint64_t photons, seed;
    int n_theta_i, n_theta_r, n_phi;
    double wl_min_nm, wl_max_nm, wl_step_nm;
    /* The surface (version 2): the Trowbridge-Reitz roughness sigma the
     * entries were traced with, and the GGX lobe fitted to the surface-
     * reflected BRDF alone at nsurface roughnesses (separable: the lobe
     * depends on the surface only, docs/modelmatch.md). nsurface 0 (a
     * version 1 file): no curve, the entries' own lobe is used. */
    double surface_sigma;
    int nsurface;
    double surf_sigma[SS_MM_MAX_SURFACE]; /* strictly increasing */
    double surf_specular[SS_MM_MAX_SURFACE], surf_roughness[SS_MM_MAX_SURFACE];
} ss_mm_table;

/* Uniform axes: nsamples[a] values from lo[a] to hi[a] (one sample: lo). */
ss_mm_table *ss_mm_table_create(const int nsamples[SS_MM_NAXES], const double lo[SS_MM_NAXES],
                                const double hi[SS_MM_NAXES], ss_error *err);
void ss_mm_table_free(ss_mm_table *t);
size_t ss_mm_table_index(const ss_mm_table *t, const int idx[SS_MM_NAXES]);

/* Multilinear interpolation over the 2^6 surrounding nodes; coordinates
 * outside an axis are clamped to its range. Exact at the nodes. The colour
 * fields (base colours, subsurface radius, albedo) are interpolated in log
 * space (multilinearly in log, where all 64 corners are positive): albedo
 * falls about exponentially with the absorbers, so log is where it is
 * smooth (docs/modelmatch.md gives the errors against the transport). */
void ss_mm_table_lookup(const ss_mm_table *t, const double x[SS_MM_NAXES],
                        double out[SS_MM_NFIELDS]);
/* The same for n points at once (maps): x[i * SS_MM_NAXES + a] ->
 * out[i * SS_MM_NFIELDS + f], in parallel; each point's values are those of
 * ss_mm_table_lookup, bit for bit, at any thread count. */
void ss_mm_table_lookup_many(const ss_mm_table *t, const double *x, size_t n, double *out);
/* Same, with the coordinates taken from bio (validated first). */
ss_status ss_mm_table_lookup_bio(const ss_mm_table *t, const ss_bio_params *bio, ss_mm_entry *out,
                                 ss_error *err);

/* The GGX lobe (specular strength, perceptual roughness) of a surface of
 * Trowbridge-Reitz roughness sigma, interpolated linearly over the table's
 * surface curve (clamped to its ends), and diffuse_scale = (1 - E(0) at the
 * entries' sigma) / (1 - E(0) at sigma): the factor that turns an entry's
 * base colour into the one that keeps the albedo under this lobe (E the
 * lobe's directional albedo, ss_render_ggx_spec_albedo; interpolated between the curve's nodes like
 * the lobe). Without a curve (version 1): entry 0's lobe, scale 1. Any pointer may be NULL. */
void ss_mm_surface_lobe(const ss_mm_table *t, double sigma, double *specular, double *roughness,
                        double *diffuse_scale);
/* Binary file (format in docs/modelmatch.md): magic "SSMMTAB\n", version,
 * axes, entry layout, little-endian doubles, the surface curve (version 2),
 * CRC-32. Written atomically (version 2). Version 1 and 2 files are read;
 * a truncated, corrupt or other-version file is SS_ERR_INPUT. */
#define SS_MM_FILE_VERSION 2
ss_status ss_mm_table_write(const char *path, const ss_mm_table *t, ss_error *err);
ss_mm_table *ss_mm_table_read(const char *path, ss_error *err);
ss_mm_table *ss_mm_table_from_memory(const unsigned char *buf, size_t len, const char *name,
                                     ss_error *err);

/* ---- building the table ------------------------------------------------- */

typedef struct ss_mm_build_options {
    ss_spectrum_options spectrum; /* wavelengths; mc.photons per (geometry, wavelength, theta_i) */
    int n_theta_i, n_theta_r, n_phi;
    ss_fit_options fit;
    ss_bio_params base; /* values of the parameters that are not axes */
    int quiet;          /* no progress bar */
} ss_mm_build_options;
void ss_mm_build_options_default(ss_mm_build_options *o);

/* Sampled BRDF of one parameter set in the same way as the table builder:
 * per geometry and incidence angle the photon paths are traced once without
 * absorption (ss_mc_trace_paths) and each absorption set is applied by exact
 * reweighting (ss_mc_paths_apply). Also returns the radial profile based
 * subsurface radius per channel and the normal-incidence diffuse albedo. */
ss_status ss_mm_sample_fast(const ss_bio_params *bio, const ss_mm_build_options *o,
                            ss_brdf_sampled *out, double sss_radius_cm[3], double albedo_rgb[3],
                            ss_error *err);

/* From a radial diffuse reflectance profile per RGB channel (bins of width
 * max_cm/bins from r = 0, rgb[bin*3+c] per cm^2, as ss_optics_radial_profile_rgb
 * returns it): the subsurface radius, the reflectance-weighted mean distance
 * from the point of entry per channel (cm, seed §4.7.1), and the albedo
 * (integral over the disc of radius max_cm). */
void ss_mm_sss_radius(const double *radial_rgb, int bins, double max_cm, double out_cm[3]);
void ss_mm_radial_albedo(const double *radial_rgb, int bins, double max_cm, double out[3]);

/* Fits the surface curve of t (nsurface sigmas spread over sigma_lo..hi,
 * 2..SS_MM_MAX_SURFACE) with o's bins, photons and seed; t->surface_sigma =
 * o->spectrum.mc.roughness_sigma. ss_mm_table_build calls it. */
ss_status ss_mm_table_build_surface(ss_mm_table *t, const ss_mm_build_options *o, int nsurface,
                                    double sigma_lo, double sigma_hi, ss_error *err);
/* Default surface curve: SS_MM_SURFACE_N sigmas over LO .. HI (below about
 * 0.25 the 8 x 8 x 8 default bins are coarser than the lobe: the fitted
 * roughness stops falling there). */
#define SS_MM_SURFACE_N 9
#define SS_MM_SURFACE_LO 0.15
#define SS_MM_SURFACE_HI 0.95
/* Fills every entry of t (axes set by ss_mm_table_create), and the surface
 * curve (the defaults above). */
ss_status ss_mm_table_build(ss_mm_table *t, const ss_mm_build_options *o, ss_error *err);
/* The same in parts (the MPI driver shares them out, src/mpi): a geometry is
 * one pair of layer thicknesses (axes 4 and 5, gi = isc * nsamples[5] + iep),
 * whose photon paths are traced once for all its absorption sets (axes 0-3,
 * entry a of the geometry at axis indices a = ((i0 n1 + i1) n2 + i2) n3 + i3).
 * Building every geometry, in any order or process, gives the bytes of
 * ss_mm_table_build. build_check validates the options and axes only. */
int ss_mm_table_ngeometries(const ss_mm_table *t);
/* Records how the table is made (photons, seed, angles, wavelengths) in t. */
void ss_mm_table_record_options(ss_mm_table *t, const ss_mm_build_options *o);
ss_status ss_mm_table_build_geometry(ss_mm_table *t, const ss_mm_build_options *o, int gi,
                                     ss_error *err);
ss_status ss_mm_table_build_check(const ss_mm_table *t, const ss_mm_build_options *o,
                                  ss_error *err);

/* ---- colour -> biology (src/optics/match.c, `skinsim optics match`) ---------- */
typedef struct ss_mm_match_options {
    ss_spectrum_options spectrum; /* transport stage: wavelengths, mc.photons, mc.seed,
                                     mc.roughness_sigma (defaults: 400..700 step 20, 20000) */
    int refine;                   /* 1 (default): refine the table's answer by transport */
    double prior_weight;          /* Delta-E00 per unit of the population prior's
                                     -log density (SS_MM_PRIOR_WEIGHT; 0: none;
                                     docs/optics.md) */
    int base_set;                 /* 1: take the non-axis parameters from base */
    ss_bio_params base;
    int geometry; /* colour compared with the target: SS_MM_GEOMETRY_SCI (default) or _SCE */
} ss_mm_match_options;
/* Measurement geometry of the target colour. SCI (CIE d:8, specular component
 * included - skin colorimeters and spectrophotometers, a photo under diffuse
 * light): the albedo plus the rough surface's reflectance at normal incidence
 * (by reciprocity the light a diffusely lit surface reflects towards the
 * viewer). SCE: the albedo alone (surface reflection excluded entirely). */
#define SS_MM_GEOMETRY_SCI 0
#define SS_MM_GEOMETRY_SCE 1
void ss_mm_match_options_default(ss_mm_match_options *o);
typedef struct ss_mm_match_result {
    ss_bio_params bio;       /* the answer (transport-refined if refined) */
    double albedo_rgb[3];    /* its albedo (linear sRGB, normal incidence, no specular) */
    double lab[3];           /* and CIELAB */
    double delta_e00;        /* CIEDE2000 to the target */
    int refined;             /* 1 if the transport stage ran */
    ss_bio_params table_bio; /* the table stage's answer, its interpolated albedo, Lab, dE00 */
    double table_albedo_rgb[3], table_lab[3], table_delta_e00;
    double surface; /* surface reflectance added to the albedo before comparing (SCI; 0 for SCE);
                       lab and table_lab are of albedo + surface */
    double prior_penalty;  /* prior_weight x the prior's -log density at bio (Delta-E00 units) */
    int unique;            /* 0: a fit within SS_MM_MATCH_TOL lies farther than SS_MM_MATCH_FAR */
    ss_bio_params alt_bio; /* the farthest grid point within the tolerance (table colour) */
    double alt_delta_e00;  /* its Delta-E00 by the table, without the prior */
    double alt_distance;   /* its distance from bio: pigment axes in units of their range */
} ss_mm_match_result;
#define SS_MM_PRIOR_WEIGHT 0.05
#define SS_MM_MATCH_TOL 1.0  /* Delta-E00: about one just-noticeable difference */
#define SS_MM_MATCH_FAR 0.25 /* a quarter of the axis ranges */
/* The biological parameters (within the table's axis ranges) whose colour
 * (albedo, plus the surface reflectance for SCI) is closest in CIEDE2000 to
 * target_lab (D65 CIELAB): table search, then
 * transport refinement (design in match.c). Deterministic. */
ss_status ss_mm_match(const ss_mm_table *t, const double target_lab[3],
                      const ss_mm_match_options *o, ss_mm_match_result *out, ss_error *err);

#ifdef __cplusplus
}
#endif
#endif
