/* skinsim skin: procedural skin textures from biological features (seed 003
 * §4.8, §5). Features (cysts, moles, freckles, wrinkles, follicles; lips as a
 * field) are scattered by greyscale probability fields (§5.1), stored in a
 * spatial index, and evaluated per texel in priority order into biological
 * parameter maps (§4.8.5, §4.8.8, §5.2-5.3); the ModelMatch table (optics_fit.h)
 * turns those into render maps.
 *
 * Units: every feature length (radius, width, height, depth) is in mm; feature
 * positions are texture units 0..1 (x to the right, y down, as image rows);
 * the texture's side is world_size_cm on the body. Optical thicknesses are in
 * cm as in optics.h. The seed gives its sizes in the units of its face model;
 * skinsim reads them as mm (docs/skin.md). */
#ifndef SKINSIM_SKIN_H
#define SKINSIM_SKIN_H

#include <stdint.h>

#include "skinsim/core.h"
#include "skinsim/optics_fit.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- primitives (seed §4.8.1-4.8.3) --------------------------------------- */

typedef struct ss_bezier3 {
    double x[4], y[4]; /* control points */
} ss_bezier3;
void ss_bezier3_eval(const ss_bezier3 *b, double t, double *x, double *y);
/* Distance from (px, py) to the curve by golden-section search over t
 * (§4.8.1): the curve is first sampled at `coarse` + 1 evenly spaced t
 * (2..64); golden section refines t to |dt| < tol around every local
 * minimum of the samples; the best wins. Returns the distance; *t_out the
 * parameter. reach: when the samples prove every point of the curve
 * farther than reach, returns +INFINITY without refining (INFINITY: always
 * refine). */
double ss_bezier3_distance(const ss_bezier3 *b, double px, double py, int coarse, double tol,
                           double reach, double *t_out);
/* Reference: the minimum over n + 1 evenly spaced samples (for tests). */
double ss_bezier3_distance_dense(const ss_bezier3 *b, double px, double py, int n, double *t_out);

/* Profile functions (§4.8.2-4.8.3, §5.3). d and the radii in the same unit. */
double ss_profile_sigmoid(double d, double r); /* §5.3.2: 1 - (sigmoid(4d/r) - 1/2) * 2 */
double ss_profile_freckle(double d, double r); /* §5.3.5: clamp(1 - 1.2 d / r, 0, 1) */
double ss_profile_follicle(double d, double r_inner, double r_outer); /* alpha, §5.3.4 */
double ss_wrinkle_taper(double t, double w);                          /* §5.3.7 T(t, w) */
double ss_profile_wrinkle(double d, double thickness);                /* §5.3.7, in [0, 1] */
/* Moles (ours, docs/skin.md): the outline's radius at angle theta (radians)
 * about the centre, r (1 + 0.05 sin(2 theta + 2 pi r) + 0.03 sin(3 theta +
 * 4 pi r)), and the border profile: 1 inside r_out - border/2, 0 beyond
 * r_out + border/2, a smoothstep across the border. */
double ss_mole_outline(double r, double theta);
double ss_profile_mole(double d, double r_out, double border);

/* ---- features ----------------------------------------------------------- */

/* Types in blend (priority) order (§4.8.5): what adds height or pigment
 * first; follicles last, because they lower the blood that lips added. */
typedef enum ss_feature_type {
    SS_FEAT_CYST = 0,
    SS_FEAT_MOLE = 1,
    SS_FEAT_FRECKLE = 2,
    SS_FEAT_WRINKLE = 3,
    SS_FEAT_FOLLICLE = 4,
    SS_FEAT_NTYPES = 5
} ss_feature_type;
const char *ss_feature_type_name(int type);      /* "cysts", "moles", ... (plural, as in --count) */
int ss_feature_type_from_name(const char *name); /* -1 if unknown; singular accepted too */

/* One generated feature. Which fields mean what per type:
 *   cyst     x,y centre; r radius; h maximum height
 *   mole     x,y centre; r radius; h height scale; m maximum melanin ratio;
 *            p 1 for reticular pigment, 0 for uniform
 *   freckle  x,y centre; r radius; m maximum melanin M; p maximum pheomelanin H
 *   wrinkle  curve control points (texture units; x,y = first); w maximum
 *            width; h depth
 *   follicle x,y centre; r inner radius r_i; r2 outer radius r_o
 * Lengths in mm. Unused fields are 0. */
typedef struct ss_skin_feature {
    int type;
    double x, y;
    double r, r2, h, m, p, w;
    ss_bezier3 curve; /* wrinkles only */
} ss_skin_feature;

typedef struct ss_skin_feature_list {
    size_t n;
    ss_skin_feature *f; /* sorted by type, then generation order */
} ss_skin_feature_list;
void ss_skin_feature_list_free(ss_skin_feature_list *l);

/* ---- distributions and settings (§5.3) ------------------------------------ */

/* The constants of the seed's distributions and profiles, all lengths in mm.
 * Defaults are the seed's where it gives a value (docs/skin.md lists which
 * are ours). Each has a name "type.key" for `--param`. */
typedef struct ss_skin_dist {
    double cyst_r_sigma, cyst_r_offset, cyst_h_max;             /* r=|s N+o|, h=hmax U */
    double mole_r_sigma, mole_h_scale, mole_h_offset;           /* r=|s N|, h=a U+b */
    double mole_m_min, mole_m_range;                            /* M = min + range U */
    double follicle_r_inner, follicle_r_outer, follicle_height; /* stub height mm */
    double follicle_blood_drop;                                 /* blood *= 1 - drop*alpha */
    /* hair pigment (docs/skin.md): melanin m_h = hair_melanin + hair_gain x
     * the skin's melanin, of which hair_pheomelanin is pheomelanin (constant,
     * as measured in hair: Ito & Wakamatsu 2011); rendered by the table */
    double hair_melanin, hair_gain, hair_pheomelanin;
    double freckle_r_mean, freckle_r_sigma, freckle_m_max, freckle_h_scale, freckle_power;
    double lip_blood, lip_pheomelanin;
    double wrinkle_max_length, wrinkle_width, wrinkle_depth, wrinkle_cross_deg;
    double wrinkle_cross_with_field; /* 1: cross_deg also with a user's vector field */
    /* ours (docs/skin.md): moles r = r_min + |s N|, a border of this width,
     * reticular pigment in this share of moles */
    double mole_r_min, mole_border, mole_reticular;
    /* the pigment a mole or freckle adds: x (1 + tone_gain x the skin's
     * melanin), so its contrast follows the tone (docs/skin.md) */
    double mole_tone_gain, freckle_tone_gain;
    /* baseline mottling in mm (Tsumura et al. 2003 chromophore maps):
     * relative amplitude of melanin and blood, finest and coarsest
     * wavelength of the fBm octaves */
    double mottle_melanin, mottle_blood, mottle_min_mm, mottle_max_mm, mottle_height;
    /* microrelief network: primary cell size and line depth, secondary cell
     * size and depth (mm), stretch along the wrinkle field (>= 1) */
    double relief_cell, relief_depth, relief_cell2, relief_depth2, relief_stretch;
    /* surface state (0..1) and the surface roughness it gives: sigma =
     * sigma_dry (1 - a_h hydration) (1 - a_s sebum), then features */
    double surface_hydration, surface_sebum, surface_sigma_dry;
} ss_skin_dist;
void ss_skin_dist_default(ss_skin_dist *d);
/* Sets one constant by name ("moles.r_sigma"); SS_ERR_INPUT for an unknown
 * name or a value out of its range. */
ss_status ss_skin_dist_set(ss_skin_dist *d, const char *name, double value, ss_error *err);
/* Names of all constants, NULL-terminated, and the value of one. */
const char *const *ss_skin_dist_names(void);
double ss_skin_dist_get(const ss_skin_dist *d, const char *name);

/* The biological parameters per texel (§5.2): channels of a bio map. */
enum {
    SS_BIO_MELANIN = 0,      /* melanocyte (melanosome) volume fraction */
    SS_BIO_PHEOMELANIN = 1,  /* pheomelanin ratio */
    SS_BIO_BLOOD = 2,        /* dermal blood volume fraction */
    SS_BIO_OXYGENATION = 3,  /* HbO2 / Hb */
    SS_BIO_SC_CM = 4,        /* stratum corneum thickness, cm */
    SS_BIO_EPIDERMIS_CM = 5, /* epidermis thickness, cm */
    SS_BIO_HEIGHT_MM = 6,    /* displacement from the mean skin surface, mm */
    SS_BIO_EXTRA_R = 7,      /* extra colour RGBA (linear), over the skin colour
                              * (ss_skin_bio_maps writes 0: hair is pigment) */
    SS_BIO_EXTRA_G = 8,
    SS_BIO_EXTRA_B = 9,
    SS_BIO_EXTRA_A = 10,
    SS_BIO_SURFACE_SIGMA = 11, /* Trowbridge-Reitz roughness of the surface (its state) */
    SS_BIO_NCHANNELS = 12
};
/* The optics model's parameters (optics.h) of one texel of a bio map:
 * melanin, pheomelanin ratio, blood, oxygenation and the two thicknesses
 * from the map, bilirubin and beta-carotene from ss_bio_params_default. */
void ss_skin_bio_texel(const ss_image *bio, int x, int y, ss_bio_params *out);
/* Channel names as written to bio.exr: "melanin", "pheomelanin_ratio",
 * "blood", "oxygenation", "sc_thickness_cm", "epidermis_thickness_cm",
 * "height_mm", "extra.R", "extra.G", "extra.B", "extra.A",
 * "surface_roughness". */
const char *ss_bio_channel_name(int channel);

/* Probability fields (§5.1): greyscale images whose value 0..1 is the
 * probability density of a feature centre (any size: mapped over the whole
 * texture), the lip field (blend weight of the lips), and the wrinkle vector
 * field (RGB: R, G direction with 0.5 = 0, B length as a fraction of
 * wrinkle_max_length). NULL = the built-in default (uniform; no lips; the
 * built-in wrinkle field). Images are not owned. */
typedef struct ss_skin_fields {
    const ss_image *density[SS_FEAT_NTYPES]; /* 1 channel; [SS_FEAT_WRINKLE]: start points */
    const ss_image *lips;                    /* 1 channel */
    const ss_image *wrinkle_vectors;         /* 3 channels */
    /* surface state, 1 channel 0..1 each (NULL: the settings' constants):
     * stratum corneum hydration, sebum, and a scar mask */
    const ss_image *hydration, *sebum, *scar;
} ss_skin_fields;

typedef enum ss_skin_sampler {
    SS_SAMPLER_ALIAS = 0,    /* alias table over texels + uniform jitter (default) */
    SS_SAMPLER_REJECTION = 1 /* the seed's ChoosePoint loop */
} ss_skin_sampler;

typedef struct ss_skin_settings {
    int size;             /* texels per side (square texture) */
    double world_size_cm; /* side of the texture on the body */
    uint64_t seed;
    int wrap;    /* 1: torus (features wrap, maps tile); 0: edges clip */
    int sampler; /* ss_skin_sampler */
    long count[SS_FEAT_NTYPES];
    ss_skin_dist dist;
    /* Baseline skin (§5.3.1): every optical parameter at lo plus noise of
     * phi x (hi - lo); indexed SS_BIO_MELANIN..SS_BIO_EPIDERMIS_CM. */
    double base_lo[6], base_hi[6];
    double phi;
} ss_skin_settings;
/* Presets: "forearm" (default: counts per cm^2 of a forearm, world 5 cm) and
 * "seed" (the seed's counts 5000 cysts, 700 moles, 170000 follicles, 3000
 * freckles, 1000 wrinkles, on a 20 cm face-sized texture). */
ss_status ss_skin_settings_preset(ss_skin_settings *s, const char *preset, int size, ss_error *err);
/* Counts from densities for the forearm preset at this world size. */
void ss_skin_forearm_counts(double world_size_cm, long count[SS_FEAT_NTYPES]);
ss_status ss_skin_settings_validate(const ss_skin_settings *s, ss_error *err);

/* ---- sampling (§5.1) ------------------------------------------------------ */

/* Draws n points (texture units) from a greyscale field raised to `power`:
 * SS_SAMPLER_ALIAS or the seed's rejection loop. Point k is a function of
 * (seed, stream, k) only. A field with no positive texel is an input error
 * (the caller reports "no features"). xy: 2n doubles. */
ss_status ss_skin_sample_points(const ss_image *field, double power, int sampler, uint64_t seed,
                                uint64_t stream, size_t n, double *xy, ss_error *err);

/* ---- generation and texels (§4.8.8 TexGen) -------------------------------- */

/* Generates every feature from the settings and fields (lines 3-7 of TexGen).
 * `notes` (may be NULL, 512 bytes) receives e.g. "moles: field is all black,
 * no features". */
ss_status ss_skin_generate(const ss_skin_settings *s, const ss_skin_fields *fields,
                           ss_skin_feature_list *out, char *notes, size_t notes_len, ss_error *err);
/* ss_skin_generate with a progress and cancel callback (core.h
 * ss_progress_fn), polled before each feature type; cancelled:
 * SS_ERR_RUNTIME "skin features: cancelled" and `out` left empty. */
ss_status ss_skin_generate_poll(const ss_skin_settings *s, const ss_skin_fields *fields,
                                ss_skin_feature_list *out, char *notes, size_t notes_len,
                                ss_progress_fn fn, void *user, ss_error *err);

/* The biological parameter maps of a feature list: a new SS_BIO_NCHANNELS
 * image of s->size^2 (lines 8-15 of TexGen, without the table). This is the
 * call a caller that wants only bio maps makes. */
ss_image *ss_skin_bio_maps(const ss_skin_settings *s, const ss_skin_fields *fields,
                           const ss_skin_feature_list *features, ss_error *err);
/* Everything in one call: preset "forearm" at this size, world size and
 * seed, default fields; returns the bio map (features are not kept). */
ss_image *ss_skin_bio_default(int size, double world_size_cm, uint64_t seed, ss_error *err);
/* ss_skin_bio_maps with a progress and cancel callback (core.h
 * ss_progress_fn), polled between bands of texel rows; cancelled: NULL,
 * SS_ERR_RUNTIME, nothing allocated is kept. */
ss_image *ss_skin_bio_maps_poll(const ss_skin_settings *s, const ss_skin_fields *fields,
                                const ss_skin_feature_list *features, ss_progress_fn fn, void *user,
                                ss_error *err);

/* ---- render maps (the table lookup, mmd in TexGen line 16) ----------------- */

/* A render lookup built once from a ModelMatch table: the GGX fit (base
 * colour, specular, roughness) at every node, as floats. */
typedef struct ss_skin_lut ss_skin_lut;
ss_skin_lut *ss_skin_lut_create(const ss_mm_table *t, ss_error *err);
void ss_skin_lut_free(ss_skin_lut *l);
/* Multilinear lookup of one texel: x in table axis order (melanin,
 * pheomelanin, blood, oxygenation, sc cm, epidermis cm); out: base R, G, B,
 * specular, roughness. Equals ss_mm_table_lookup's GGX fields to float
 * rounding (colours interpolated in log space, as there). */
void ss_skin_lut_lookup(const ss_skin_lut *l, const float x[6], float out[5]);
/* The same with the surface's Trowbridge-Reitz roughness sigma: specular and
 * roughness from the table's surface curve, the base colour scaled to keep
 * the albedo (ss_mm_surface_lobe); out[5..7] the subsurface radius (cm). */
void ss_skin_lut_lookup_surface(const ss_skin_lut *l, const float x[6], float sigma, float out[8]);
/* A lookup cache for one thread: the corners of the last few table cells
 * (gathering them is most of a lookup). Lookups through it give exactly
 * ss_skin_lut_lookup's values, faster where neighbouring texels fall in the
 * same cells. NULL from create when out of memory; a NULL cache in the
 * lookup is ss_skin_lut_lookup. */
typedef struct ss_skin_lut_cache ss_skin_lut_cache;
ss_skin_lut_cache *ss_skin_lut_cache_create(void);
void ss_skin_lut_cache_free(ss_skin_lut_cache *c);
void ss_skin_lut_lookup_cached(const ss_skin_lut *l, ss_skin_lut_cache *c, const float x[6],
                               float out[5]);

typedef struct ss_skin_maps {
    ss_image *base_color;           /* linear RGB (extra colour composited) */
    ss_image *roughness, *specular; /* 1 channel, 0..1 (GGX, optics_fit.h) */
    ss_image *translucency;         /* RGB subsurface radius, cm (the table's) */
    ss_image *cavity;               /* 1 channel, 1 = open surface, 0 = deep in a furrow */
    ss_image *height_mm;            /* 1 channel, mm */
    ss_image *normal;               /* RGB, tangent space, OpenGL (+Y) unless directx */
    double height_min_mm, height_max_mm;
} ss_skin_maps;
/* normal_directx: flip green. */
ss_status ss_skin_render_maps(const ss_image *bio, const ss_skin_lut *lut, double world_size_cm,
                              int normal_directx, ss_skin_maps *out, ss_error *err);
void ss_skin_maps_free(ss_skin_maps *m);
/* ss_skin_render_maps with a progress and cancel callback (core.h
 * ss_progress_fn), polled between bands of texel rows; cancelled:
 * SS_ERR_RUNTIME with *out freed and zeroed. */
ss_status ss_skin_render_maps_poll(const ss_image *bio, const ss_skin_lut *lut,
                                   double world_size_cm, int normal_directx, ss_skin_maps *out,
                                   ss_progress_fn fn, void *user, ss_error *err);

/* ---- features.csv --------------------------------------------------------- */

/* Header "type,x,y,r,r2,h,m,p,w,x1,y1,x2,y2,x3,y3"; numbers with 17
 * significant digits, so a list read back is bit-identical. */
ss_status ss_skin_features_write_csv(const char *path, const ss_skin_feature_list *l,
                                     ss_error *err);
ss_status ss_skin_features_read_csv(const char *path, ss_skin_feature_list *out, ss_error *err);
ss_status ss_skin_features_parse_csv(const char *text, const char *name, ss_skin_feature_list *out,
                                     ss_error *err);

/* ---- timings ------------------------------------------------------------- */
typedef struct ss_skin_timing {
    double generate_s, index_s, texels_s, lookup_s;
} ss_skin_timing;
/* ss_skin_bio_maps with the index and texel times reported. */
ss_image *ss_skin_bio_maps_timed(const ss_skin_settings *s, const ss_skin_fields *fields,
                                 const ss_skin_feature_list *features, ss_skin_timing *t,
                                 ss_error *err);

#ifdef __cplusplus
}
#endif
#endif
