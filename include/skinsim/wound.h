/* skinsim wound: the three seeds joined. Healing fields of a heal run (seed 001
 * §4.1, sampled at the skin surface as §5.4 does) become biological parameters
 * per texel (seed 003 §5.2), which the ModelMatch table (seed 003 §4.8.6) turns
 * into render textures, over a base skin given as bio-parameter maps; a
 * dried-blood layer of the optics model colours the scab. Outputs follow the
 * texture-timeline format of seed 000 (`skinsim abrasion`).
 *
 *   heal run (or a saved run's snapshot) --(ss_wound_tissue_observe_closure, on the
 *   days to render, with the run's closure days)--> tissue maps (grid resolution)
 *   tissue maps + base bio maps --(ss_wound_render)--> base colour, roughness,
 *                                                      height, normal (texture size)
 *
 * Every mapping, its reason and its source are in docs/wound.md; its numbers
 * are a recipe (JSON, with units) that a user can ramp and multiply (§5.4's
 * artistic control). Units: mm and days for tissue, cm for optics (as MCML). */
#ifndef SKINSIM_WOUND_H
#define SKINSIM_WOUND_H

#include "skinsim/core.h"
#include "skinsim/heal.h"
#include "skinsim/heal_run.h"
#include "skinsim/optics.h"
#include "skinsim/optics_fit.h"
#include "skinsim/skin.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- recipe: the numbers of the tissue -> biology mapping ------------------------ */

enum {
    SS_WR_CAPILLARY_THRESHOLD,    /* 1: capillary density (of healthy) that defines the wound
                                     bed's depth (§5.4) */
    SS_WR_EPITHELIUM_LO,          /* 1: epithelium level where cover starts (ramp) */
    SS_WR_EPITHELIUM_HI,          /* 1: epithelium level of full cover */
    SS_WR_REGION_LO,              /* 1: plasma level where the wound region starts (ramp) */
    SS_WR_REGION_HI,              /* 1: plasma level of the full wound region */
    SS_WR_BED_BLOOD,              /* 1: blood volume fraction of the open wound bed's
                                     granulation tissue at the healthy capillary density */
    SS_WR_TISSUE_MIN_OXYGENATION, /* 1: blood oxygenation in tissue without oxygen */
    SS_WR_YOUNG_BLOOD,            /* 1: dermal blood fraction of freshly closed tissue */
    SS_WR_SCAR_DAYS,              /* day: time constant of scar maturation after closure */
    SS_WR_EPIDERMIS_DAYS,         /* day: time constant of epidermal maturation */
    SS_WR_PIGMENT_DAYS,           /* day: time constant of repigmentation
                                     (ss_repigmentation_factor, shared with abrasion) */
    SS_WR_NEW_MELANIN,            /* 1: melanin of new epithelium at closure, of the skin's */
    SS_WR_SCAR_MELANIN,           /* 1: melanin of the mature scar, reached after the first
                                     month over SS_SCAR_PALE_DAYS (< 1 hypo-, > 1 hyper-) */
    SS_WR_NEW_EPIDERMIS,          /* 1: thickness of new epidermis, fraction of the skin's */
    SS_WR_SCAR_DENSITY_HI,        /* 1: scar (collagen) density of the full scar look */
    SS_WR_SCAR_BLOOD,             /* 1: blood of the mature dense scar, fraction of the skin's */
    SS_WR_SCAR_WHITENING,         /* 1: albedo lift of the mature dense scar towards white */
    SS_WR_SCAB_SCALE,             /* 1: scab thickness per mm of eschar column (density x mm) */
    SS_WR_SCAB_HB_FACTOR,         /* 1: haemoglobin of the scab, multiple of whole blood's */
    SS_WR_SCAB_MIN_DENSITY,       /* 1: eschar density around which a cell becomes crust */
    SS_WR_CLOT_SCALE,             /* 1: clot thickness per mm of open, avascular wound depth */
    SS_WR_BED_OXYGENATION,        /* 1: blood oxygenation of the open bed (air-exposed) */
    SS_WR_WET_ROUGHNESS,          /* 1: roughness of the moist open bed */
    SS_WR_SCAB_ROUGHNESS,         /* 1: roughness of the dry scab */
    SS_WR_SCAR_ROUGHNESS,         /* 1: roughness of the mature scar (shiny) */
    SS_WR_DEPTH_SCALE,            /* 1: multiplier of the displacement depth */
    SS_WR_KELOID_SCALE,           /* 1: raise per mm of the healing model's surface elevation
                                     (not saturated: the model bounds it) */
    SS_WR_HEIGHT_RANGE_MM,        /* mm: height map 0..1 spans -range..+range */
    /* the crust's structure (docs/wound.md: mottled, thicker in the middle, cracked at
     * the edges) */
    SS_WR_SCAB_MOTTLE,    /* 1: relative thickness variation of the crust (value noise) */
    SS_WR_SCAB_SEROUS,    /* 1: largest share of serous (haemoglobin-poor) crust in the
                             mottling */
    SS_WR_SCAB_SEROUS_HB, /* 1: haemoglobin of serous crust, multiple of whole blood's */
    SS_WR_SCAB_DOME_MM,   /* mm: distance from the crust's edge to its full thickness */
    SS_WR_SCAB_EDGE,      /* 1: crust thickness at its edge, fraction of the full */
    SS_WR_CRACK_WIDTH,    /* 1: width of the crack lines (noise units, 0 = none) */
    SS_WR_CRACK_REACH_MM, /* mm: how far from the crust's edge it cracks */
    /* the keloid's look: raised, shiny, red to purple-brown */
    SS_WR_KELOID_LOOK_MM,     /* mm: keloid swelling at which its look is 63 % there */
    SS_WR_KELOID_BLOOD,       /* 1: blood volume fraction of keloid tissue */
    SS_WR_KELOID_OXYGENATION, /* 1: blood oxygenation in keloid tissue */
    SS_WR_KELOID_MELANIN,     /* 1: melanin of keloid epidermis, multiple of the skin's */
    SS_WR_KELOID_ROUGHNESS,   /* 1: roughness of the keloid's stretched surface (shiny) */
    SS_WR_SCAB_BILIRUBIN,     /* g/L: serum pigment (bilirubin, carotenoids) of the dried crust */
    /* after healing: post-inflammatory pigmentation by skin type, the crust's ageing */
    SS_WR_PIH_GAIN,         /* 1: gain of post-inflammatory hyperpigmentation: melanin x
                               ss_pih_melanin_factor(rate, age, gain), the course shared
                               with abrasion (default SS_PIH_GAIN, as abrasion's) */
    SS_WR_CRUST_DRY_DAYS,   /* day: time constant of the crust's drying and darkening */
    SS_WR_CRUST_LIFT_MM,    /* mm: how far the crust's edge lifts over new epithelium */
    SS_WR_BED_TEXTURE,      /* 1: strength of the bed's capillary-loop and exudate texture */
    SS_WR_LOOP_DEPTH_MM,    /* mm: depth of the capillary loops that hold blood above the
                               table's largest blood fraction (a thin whole-blood layer) */
    SS_WR_CLOT_OXYGENATION, /* 1: oxygenation of the fresh clot (oozed capillary blood) */
    /* the keloid's structure: active margin, fibrous centre, vessels, nodules */
    SS_WR_KELOID_MARGIN_MM,    /* mm: width of its active, erythematous margin */
    SS_WR_KELOID_CENTRE_BLOOD, /* 1: blood of its matured centre, of keloid_blood */
    SS_WR_KELOID_MATURE_DAYS,  /* day: time constant of its centre's maturation */
    SS_WR_KELOID_VESSELS,      /* 1: strength of its telangiectatic vessels */
    SS_WR_KELOID_VESSEL_MM,    /* mm: width of a vessel trunk (branches half) */
    SS_WR_KELOID_NODULES,      /* 1: unevenness of its raise (fraction, at ~4 mm) */
    SS_WR_NKEYS
};

typedef struct ss_wound_recipe {
    double v[SS_WR_NKEYS];
} ss_wound_recipe;
void ss_wound_recipe_default(ss_wound_recipe *r);
/* Key name ("capillary_threshold", ...) and unit ("1", "day", "mm") of a key. */
const char *ss_wound_recipe_key(int key);
const char *ss_wound_recipe_unit(int key);
/* Defaults overridden by a JSON file {"recipe": {"bed_blood": {"value": 0.04,
 * "unit": "1"}, ...}}. Malformed JSON, an unknown key, a missing or wrong unit,
 * a value outside the key's range -> SS_ERR_INPUT naming the file and key. */
ss_status ss_wound_recipe_load(const char *path, ss_wound_recipe *r, ss_error *err);
ss_status ss_wound_recipe_parse(const char *json, const char *name, ss_wound_recipe *r,
                                ss_error *err);
/* malloc'd JSON text in the load format. */
char *ss_wound_recipe_to_json(const ss_wound_recipe *r);

/* ---- tissue at the skin surface (grid resolution) --------------------------------
 * Maps of nx x ny columns, image orientation like ss_heal_surface_map (row 0 =
 * grid y = ny-1). Values relative to healthy where the field has a healthy
 * level (epithelium, capillary, oxygen: 1 = healthy). */
typedef struct ss_wound_tissue {
    int nx, ny;
    double dx_mm, day;
    float *epithelium;  /* epithelial layer (max of the two topmost tissue cells) */
    float *capillary;   /* topmost tissue cell, / u3_eq */
    float *oxygen;      /* topmost tissue cell, / healthy u1 */
    float *plasma;      /* topmost tissue cell: the wound region (§4.1.8) */
    float *scab_mm;     /* eschar integrated over the column, density x mm */
    float *scar;        /* scar (collagen) density, column maximum */
    float *keloid_mm;   /* swelling: sum of (rho / rho_max - 1) dx over cells above rho_max, mm */
    float *depth_mm;    /* §5.4: skin surface down to the capillary threshold */
    float *age_days;    /* time since the column's epithelium closed (0 = open;
                           intact skin: SS_WOUND_AGE_INTACT) */
    double *closed_day; /* internal: day of closure (+inf open, -inf intact) */
    float u3_eq, u1_healthy, rho_max, scab_min;
    double threshold;    /* capillary threshold used for depth_mm */
    float *elevation_mm; /* the healing model's surface elevation (ss_heal_elevation_scan, the
                            surface_elevation_mm of heal's snapshots): the keloid's raise */
} ss_wound_tissue;
#define SS_WOUND_AGE_INTACT 1e5f

ss_wound_tissue *ss_wound_tissue_create(const ss_heal_grid *g, const ss_heal_params *p,
                                        const ss_wound_recipe *r, ss_error *err);
/* Samples the grid's current state into the maps and updates each column's
 * closure day (first time its epithelium reaches 0.5; reset if it reopens).
 * Call it after every step for exact closure days (it costs a pass over the
 * grid's columns), or at least at every day to be rendered. */
void ss_wound_tissue_observe(ss_wound_tissue *t, const ss_heal_grid *g);
/* The same, with each column's closure day taken from closed_day (nx*ny in
 * grid order, skinsim/heal_io.h's encoding: ss_heal_run_closure, or a saved
 * snapshot's) instead of tracked, so observing the render days alone is
 * exact. */
void ss_wound_tissue_observe_closure(ss_wound_tissue *t, const ss_heal_grid *g,
                                     const double *closed_day);
void ss_wound_tissue_free(ss_wound_tissue *t);

/* ---- base skin: bio-parameter maps -------------------------------------------------
 * The skin a wound is drawn on is a bio map of skinsim/skin.h: SS_BIO_NCHANNELS
 * float channels per texel (melanin, pheomelanin ratio, blood, oxygenation,
 * stratum corneum cm, epidermis cm, height mm, extra colour RGBA), as
 * ss_skin_bio_default makes it or `skinsim skin` writes it to bio.exr. */
/* Checks a bio map: channel count, finite values, fractions and the extra
 * colour in 0..1, thicknesses > 0 (SS_ERR_INPUT naming `name` and the texel). */
ss_status ss_wound_skin_validate(const ss_image *bio, const char *name, ss_error *err);
/* The default base skin: ss_skin_bio_default (forearm preset) over a square
 * of side_mm, size x size texels. */
ss_image *ss_wound_default_skin(int size, double side_mm, uint64_t seed, ss_error *err);
/* Reads DIR/bio.exr (or the .exr file itself) by channel name. */
ss_image *ss_wound_skin_read(const char *path, ss_error *err);

/* ---- blood layers over the skin: the scab (dried blood) and the clot ------------------ */
/* A layer of blood (haemoglobin at hb_factor times whole blood's 150 g/L, at an
 * oxygenation) with its scattering, on top of the skin. */
typedef struct ss_blood_layer {
    double hb_factor, oxygenation;
    double mus_per_cm, g, n;
    double bilirubin_g_per_l; /* yellow serum pigment in the layer (docs/wound.md), g/L */
} ss_blood_layer;
/* The scab (dried blood, docs/wound.md) and fresh clotted blood. */
void ss_blood_layer_scab(double hb_factor, ss_blood_layer *l);
void ss_blood_layer_clot(double oxygenation, ss_blood_layer *l);
/* Diffuse reflectance (over a black background) and transmittance of the layer
 * per linear-sRGB channel, tabulated over thickness by Monte Carlo transport
 * of the optics model at 400..700 nm. */
#define SS_LAYER_NTHICK 10
/* the transport's wavelengths: SS_LAYER_NWL bins, 400..700 nm every 20 nm */
#define SS_LAYER_NWL 16
typedef struct ss_layer_table {
    double thickness_mm[SS_LAYER_NTHICK];
    double reflect[SS_LAYER_NTHICK][3], transmit[SS_LAYER_NTHICK][3];
    /* the same per wavelength, before the conversion to RGB */
    double reflect_wl[SS_LAYER_NTHICK][SS_LAYER_NWL], transmit_wl[SS_LAYER_NTHICK][SS_LAYER_NWL];
} ss_layer_table;
ss_status ss_layer_table_build(const ss_blood_layer *l, uint64_t photons, uint64_t seed,
                               ss_layer_table *out, ss_error *err);
/* R and T at a thickness (linear between samples, constant beyond the last). */
void ss_layer_table_eval(const ss_layer_table *t, double thickness_mm, double reflect[3],
                         double transmit[3]);
/* The same per wavelength (SS_LAYER_NWL bins). */
void ss_layer_table_eval_wl(const ss_layer_table *t, double thickness_mm,
                            double reflect[SS_LAYER_NWL], double transmit[SS_LAYER_NWL]);
/* Albedo of the layer over a skin of albedo `skin` (adding: R + T^2 A / (1 - R A)). */
void ss_layer_over(const double reflect[3], const double transmit[3], const double skin[3],
                   double out[3]);

/* ---- the open bed's spectra: its blood and layers per wavelength (bed_spectrum.c) ---- */
/* Reflectance spectra of the open bed (no epidermis, no melanin: the bio
 * parameters `bed`, its blood set per sample) by the optics model's
 * transport, along one blood axis: a sample at or below `cap` (the
 * ModelMatch table's largest blood fraction) is the bed with that blood in
 * its whole dermis; one above it is the bed at `cap` whose top loop_depth_mm
 * of dermis (its capillary loops) holds that blood fraction. A table colour
 * at a blood fraction stands for the spectrum there times a smooth factor q
 * (quadratic in wavelength) that gives it exactly that colour. */
#define SS_BED_MAX_BLOOD 16
typedef struct ss_bed_spectra {
    int nblood;
    double blood[SS_BED_MAX_BLOOD]; /* strictly increasing */
    double cap, loop_depth_mm;
    double reflect[SS_BED_MAX_BLOOD][SS_LAYER_NWL];      /* the transport's diffuse reflectance */
    double moment[SS_BED_MAX_BLOOD][3][3];               /* sum_w weight[w][i] reflect x^j */
    double wavelength_nm[SS_LAYER_NWL], x[SS_LAYER_NWL]; /* x = (wl - 550) / 150 */
    double weight[SS_LAYER_NWL][3]; /* linear sRGB of each bin: rgb = sum_w weight[w] S[w] */
} ss_bed_spectra;
/* Runs the transport at each of the nblood blood fractions (1..SS_BED_MAX_BLOOD,
 * strictly increasing, in 0..1), `photons` packets per wavelength. */
ss_status ss_bed_spectra_build(const ss_bio_params *bed, const double *blood, int nblood,
                               double cap, double loop_depth_mm, uint64_t photons, uint64_t seed,
                               ss_bed_spectra *out, ss_error *err);
/* The factor q of the colour rgb (linear sRGB) at a blood fraction (clamped
 * to the samples; between them the spectra are linear). Returns 1, or 0 when
 * there is none (the spectra's moments are singular: a bed reflecting nothing). */
int ss_bed_fit(const ss_bed_spectra *s, double blood, const double rgb[3], double q[3]);
/* The spectrum at a blood fraction times the factor q. */
void ss_bed_eval(const ss_bed_spectra *s, double blood, const double q[3],
                 double out[SS_LAYER_NWL]);
/* The layer of the table t, thickness_mm thick, over the spectrum `in`, by
 * the adding formula per wavelength (out may be in). */
void ss_layer_add_wl(const ss_layer_table *t, double thickness_mm, const double in[SS_LAYER_NWL],
                     double out[SS_LAYER_NWL]);
/* A spectrum's linear sRGB (CIE 1931 observer, D65; white -> (1, 1, 1)). */
void ss_bed_spectra_to_rgb(const ss_bed_spectra *s, const double spectrum[SS_LAYER_NWL],
                           double rgb[3]);
/* The layer of the table t, thickness_mm thick, over the spectrum standing
 * for rgb at a blood fraction (ss_bed_fit), by the adding formula per
 * wavelength, in linear sRGB; at thickness 0 it is rgb. Falls back to
 * ss_layer_over in RGB where ss_bed_fit has no factor. */
void ss_layer_over_spectral(const ss_layer_table *t, double thickness_mm, const ss_bed_spectra *s,
                            double blood, const double rgb[3], double out[3]);

/* ---- the renderer --------------------------------------------------------------------- */

typedef struct ss_wound_render_options {
    int size;             /* texture side in texels; the texture covers the heal block */
    double side_mm;       /* the texture's side in the world (the block's x size, default 30) */
    const ss_image *skin; /* base bio maps (SS_BIO_NCHANNELS, resampled to size) */
    const ss_mm_table *table;
    ss_wound_recipe recipe;
    uint64_t scab_photons; /* Monte Carlo packets per wavelength and thickness (default 2000) */
    uint64_t seed;
} ss_wound_render_options;
void ss_wound_render_options_default(ss_wound_render_options *o);

/* One day's textures: base_color linear RGB, roughness (GGX perceptual, 1
 * channel), height in mm (1 channel, 0 = skin surface), normal RGB (tangent
 * space, OpenGL +Y up, from the height). */
typedef struct ss_wound_textures {
    ss_image *base_color, *roughness, *height, *normal;
} ss_wound_textures;
ss_status ss_wound_textures_create(int size, ss_wound_textures *t, ss_error *err);
void ss_wound_textures_free(ss_wound_textures *t);

typedef struct ss_wound_renderer ss_wound_renderer;
/* Resamples and validates the base skin, renders its textures once (texels
 * that the wound leaves alone are copied from them), builds the scab table. */
ss_status ss_wound_renderer_create(const ss_wound_render_options *o, ss_wound_renderer **out,
                                   ss_error *err);
void ss_wound_renderer_free(ss_wound_renderer *r);
/* The base skin's own textures (what the skin looks like without a wound). */
const ss_wound_textures *ss_wound_renderer_base(const ss_wound_renderer *r);
/* The healed skin's melanin factor from post-inflammatory hyperpigmentation
 * `days` after closure (before its patchiness): ss_pih_melanin_factor at the
 * base skin's PIH rate and the recipe's pih_gain; abrasion's
 * ss_abrasion_pih_factor gives the same on the same skin. */
double ss_wound_renderer_pih_factor(const ss_wound_renderer *r, double days);
/* The healed skin's whole melanin factor `days` after closure (before its
 * patchiness): ss_healed_melanin_factor with the recipe's new_melanin,
 * repigmentation, scar_melanin and pih_gain at the base skin's PIH rate;
 * abrasion's ss_abrasion_melanin_factor_at gives the same on the same skin
 * with the default recipe. */
double ss_wound_renderer_melanin_factor(const ss_wound_renderer *r, double days);
/* Textures of the tissue t over the base skin (the texture covers the heal
 * block). deformation: NULL, or the mechanics' per-texel displacement of the
 * material point (3 channels, mm: x, y along the texture (x right, y up), z
 * up), which moves where the fields are sampled and adds to the height
 * (ss_wound_deformation_from_grid makes it from the mechanics' grid arrays). */
ss_status ss_wound_render(ss_wound_renderer *r, const ss_wound_tissue *t,
                          const ss_image *deformation, ss_wound_textures *out, ss_error *err);
/* ss_wound_render with a progress and cancel callback (core.h
 * ss_progress_fn), polled between bands of texture rows; cancelled: out is
 * partly written, SS_ERR_RUNTIME. */
ss_status ss_wound_render_poll(ss_wound_renderer *r, const ss_wound_tissue *t,
                               const ss_image *deformation, ss_wound_textures *out,
                               ss_progress_fn fn, void *user, ss_error *err);

/* ---- textures in a mesh's UV space (a heal run on a real body) -------------------- */
struct ss_shell_patch;
struct ss_mesh;
/* Per texel of a size x size texture over the mesh's UV layout (u right, v
 * down): the tissue-map coordinates (x, y in columns, the ss_wound_tissue
 * orientation) of the patch column under the skin point the texel shows, or
 * NaN where the texel shows no point of the patch's skin (no UV triangle,
 * outside the patch, or another sheet of skin). *mm_per_uv: the mesh's mean
 * scale (sqrt of 3D area / UV area), the texture's world size. A mesh without
 * UVs -> SS_ERR_INPUT. (src/wound/uvmap.c) */
ss_image *ss_wound_uv_columns(const struct ss_shell_patch *p, const struct ss_mesh *m, int size,
                              double *mm_per_uv, ss_error *err);
/* Makes the renderer sample the tissue at `columns` (size x size x 2, as
 * ss_wound_uv_columns gives; copied) instead of over a flat block; NaN texels
 * are the base skin. NULL returns to the flat block. A deformation is not
 * drawn on such a map (ss_wound_render refuses one). */
ss_status ss_wound_renderer_set_columns(ss_wound_renderer *r, const ss_image *columns,
                                        ss_error *err);

/* The per-texel deformation (size x size x 3, mm) from a displacement field on
 * the heal grid (3 arrays of nx*ny*nz, mm, e.g. ss_mech_grid_displacement):
 * each column's topmost tissue cell, bilinear between column centres. */
ss_image *ss_wound_deformation_from_grid(const ss_heal_grid *g, float *const *disp, int size,
                                         ss_error *err);

/* ---- the whole job: `skinsim wound` --------------------------------------------------- */

typedef struct ss_wound_make_config {
    ss_heal_run_config heal; /* the healing problem (out_dir, resume_dir and days are ignored:
                                the run is in memory and ends at the last day) */
    const char *heal_dir;    /* a finished `skinsim heal` run folder to render instead of
                                simulating (heal must then be the defaults); the days must
                                be its snapshot days (docs/wound.md) */
    const double *days;      /* output days, increasing, whole steps of the heal run */
    int ndays;
    int size;                /* texture side (default 1024) */
    const char *skin_path;   /* base skin: `skinsim skin`'s output folder or its bio.exr;
                                NULL = ss_skin_bio_default (forearm skin) */
    const char *table_path;  /* NULL = data/modelmatch_default.sstab */
    const char *recipe_path; /* NULL = defaults */
    const char *out_dir;
    int exr;       /* also write every map as half-float EXR (height in mm) */
    int compare;   /* write compare_abrasion.png (default 1) */
    int mechanics; /* 1: the heal run's coupled contraction mechanics, drawn as displacement */
    int quiet;     /* no progress bar */
    uint64_t seed;
} ss_wound_make_config;
void ss_wound_make_config_default(ss_wound_make_config *c);
/* Validates every input (nothing is written on bad input: SS_ERR_INPUT), then
 * writes out_dir: frames/t<day>_{base_color,roughness,height,normal}.png,
 * t<day>_metal_rough.png and t<day>.gltf per day, contact_sheet.png,
 * compare_abrasion.png, timeline.json (the summary, also returned as
 * malloc'd JSON text when summary_json is not NULL). */
/* The range a wound height map is encoded over (the frames' height PNGs):
 * its minimum and maximum in mm, widened to at least -range_mm..+range_mm;
 * SS_ERR_RUNTIME if a texel is not finite. */
ss_status ss_wound_height_range(const ss_image *height_mm, double range_mm, double *lo, double *hi);
ss_status ss_wound_make(const ss_wound_make_config *c, char **summary_json, ss_error *err);

/* ---- colour checks ------------------------------------------------------------------ */
/* Linear sRGB -> CIELAB (D65 white) and the CIEDE2000 difference (Sharma, Wu
 * & Dalal 2005). */
void ss_linear_srgb_to_lab(const double rgb[3], double lab[3]);
double ss_delta_e2000(const double lab1[3], const double lab2[3]);

#ifdef __cplusplus
}
#endif
#endif
