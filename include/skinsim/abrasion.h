/* skinsim abrasion: the abrasion-healing texture timeline of seed 000 (§3.2,
 * §4.2-4.3). A wound shape (hulls of painted UV strokes, or a mask) drives five
 * key positions (vasoconstriction, vasodilation, scab-forming, scab,
 * maturation) that each render a texture set; any time t on the timeline is the
 * linear blend of the two keys around it, except maturation, which is
 * re-rendered at its position (§4.3.5). */
#ifndef SKINSIM_ABRASION_H
#define SKINSIM_ABRASION_H

#include "skinsim/core.h"
#include "skinsim/geom.h"
#include "skinsim/optics.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- strokes ------------------------------------------------------------ */

/* Painted strokes are geom's ss_stroke_set (CSV: ss_stroke_csv_read). The
 * built-in example: a roundish scrape in the middle of the texture. */
ss_status ss_abrasion_example_strokes(ss_stroke_set *out, ss_error *err);

/* ---- wound shape -------------------------------------------------------- */

/* The widest gradient of the phases (seed §4.3: thickness 100) in pixels of
 * the reference texture; distances beyond it only need to be "far". */
#define SS_ABRASION_MAX_GRADIENT_REF_PX 100.0

typedef enum ss_hull_kind { SS_HULL_CONVEX = 0, SS_HULL_CONCAVE = 1 } ss_hull_kind;

/* Everything the key positions need to know about the wound(s) at one texture
 * size: the binary shape, the distance of each pixel to the wound outline, and
 * per wound its closing distance (Alg. 4.3) and maturation border ratio. */
typedef struct ss_wound_shape {
    int size;       /* square texture side in pixels */
    ss_image *mask; /* 1 inside a wound, 0 outside */
    ss_image *dist; /* pixels from the pixel centre to the nearest outline;
                       exact up to the widest gradient, larger beyond */
    int *label;     /* size*size: index of the nearest wound */
    int nwounds;
    double *closing_px;             /* per wound: closing distance in pixels */
    double *inner_ratio;            /* per wound: rand(0.4, 0.8) of Eq. 4.8 */
    int box_x, box_y, box_w, box_h; /* bounding box of the mask (box_w = 0: empty) */
    int npolys;                     /* hulls (0 for mask input) */
    ss_polygon *polys;
    /* signed distance to the outline in pixels (> 0 inside), smoothed by a
       blur of a tenth of the wound's size: its level sets are the nested,
       rounded fronts of maturation (no ridges along the medial axis, no X
       on a square); exact in the changed region only, 0 elsewhere */
    ss_image *smooth;
} ss_wound_shape;

/* One hull per stroke id (each needs >= 3 distinct, non-collinear points),
 * filled and measured at the given size. */
ss_status ss_wound_shape_from_strokes(const ss_stroke_set *s, ss_hull_kind kind, int concave_k,
                                      int size, uint64_t seed, ss_wound_shape **out, ss_error *err);
/* A mask image (any size, > 0.5 = wound; resampled to size). Each connected
 * component is a wound; an empty mask is an input error. */
ss_status ss_wound_shape_from_mask(const ss_image *mask, int size, uint64_t seed,
                                   ss_wound_shape **out, ss_error *err);
void ss_wound_shape_free(ss_wound_shape *w);

/* ---- base skin ---------------------------------------------------------- */

/* The seed's "upper" (healthy) and "lower" (dermis) skin colour textures,
 * linear RGB, size x size. Inputs may be given (any size, resampled; grey is
 * replicated to RGB, alpha dropped); the
 * rest are generated procedurally from seed (see docs/abrasion.md). */
/* The tissue colours the phases draw, from the optics model (linear sRGB
 * albedos; src/abrasion/palette.c, docs/abrasion.md): the exposed dermis
 * (blanched, dilated, a capillary loop, granulation tissue), films over the
 * dilated bed (fresh blood, serous exudate, fibrin, dark and light dried
 * crust), multipliers of the healthy skin (erythema, mature scar) and new
 * epithelium at melanin factors. melanin: the skin's melanin fraction
 * estimated from the upper texture; ita_deg its typology angle;
 * pih_prevalence the clinical rate of post-inflammatory hyperpigmentation at
 * that skin type (ss_pih_prevalence, skinsim/optics.h). */
#define SS_ABRASION_NMELANIN 9
typedef struct ss_abrasion_palette {
    float bed_pale[3], bed[3], capillary[3], granulation[3];
    float blood[3], serous[3], fibrin[3], crust_dark[3], crust_light[3];
    float erythema[3], scar[3];
    /* the skin with its epidermal melanin times ss_abrasion_melanin_factor(k),
     * as a ratio to the healthy skin: hypo- and hyperpigmentation as the
     * optics render a melanin change (scar holds the skin's own melanin; the
     * healing phases multiply in one of these) */
    float melanin_ratio[SS_ABRASION_NMELANIN][3];
    /* new epithelium, a colour of its own (not a multiplier): a thin
     * epidermis with the skin's melanin times ss_abrasion_melanin_factor(k)
     * over young, hyperaemic dermis */
    float epithelium[SS_ABRASION_NMELANIN][3];
    float melanin, ita_deg, pih_prevalence;
} ss_abrasion_palette;
/* The melanin factor of melanin_ratio[k]: 0.25 to 2.5, evenly in log. */
double ss_abrasion_melanin_factor(int k);
/* Computes the palette for a skin whose healthy colour is `upper` (linear
 * RGB); reads the optics model's spectra (data/spectra). */
ss_status ss_abrasion_palette_compute(const ss_image *upper, ss_abrasion_palette *p, ss_error *err);
/* The healed skin's melanin factor from post-inflammatory hyperpigmentation
 * `days` after closure: ss_pih_melanin_factor at the palette's PIH rate and
 * SS_PIH_GAIN (the course `wound` uses too, skinsim/optics.h). */
double ss_abrasion_pih_factor(const ss_abrasion_palette *p, double days);
/* The healed skin's whole melanin factor `days` after closure (a ring that
 * healed as long ago as the wound): ss_healed_melanin_factor with the
 * default repigmentation, the palette's PIH rate and SS_PIH_GAIN, the curve
 * `wound` takes too (ss_wound_renderer_melanin_factor). */
double ss_abrasion_melanin_factor_at(const ss_abrasion_palette *p, double days);

typedef struct ss_base_skin {
    ss_image *upper, *lower; /* linear RGB */
    ss_image *upper_srgb,
        *lower_srgb;              /* the same, sRGB-encoded: the seed blends in display space */
    ss_abrasion_palette *palette; /* the tissue colours for this skin (owned) */
} ss_base_skin;
ss_status ss_base_skin_create(const ss_image *upper_in, const ss_image *lower_in, int size,
                              uint64_t seed, ss_base_skin *out, ss_error *err);
void ss_base_skin_free(ss_base_skin *b);

/* ---- key positions ------------------------------------------------------ */

typedef enum ss_phase {
    SS_PHASE_VASOCONSTRICTION = 0,
    SS_PHASE_VASODILATION,
    SS_PHASE_SCAB_FORMING,
    SS_PHASE_SCAB,
    SS_PHASE_MATURATION,
    SS_PHASE_COUNT
} ss_phase;
const char *ss_phase_name(ss_phase p);    /* "vasoconstriction", ... "maturation" */
int ss_phase_from_name(const char *name); /* -1 if unknown */

/* A key position's texture set. color: linear RGB; reflection: 1 channel
 * specular strength 0..1; height: 1 channel, 0.5 = skin surface, 1 = the
 * thickest scab (world units in ss_abrasion_settings); normal: RGB tangent
 * space, OpenGL (+Y up), derived from height. */
typedef struct ss_texture_set {
    ss_image *color, *reflection, *height, *normal;
} ss_texture_set;
ss_status ss_texture_set_create(int size, ss_texture_set *t, ss_error *err);
void ss_texture_set_free(ss_texture_set *t);

/* Scale of the textures in the world: the seed's thicknesses and noise
 * periods are pixels of a reference_px texture; other sizes are scaled so
 * the output looks the same at 512 and at 4096 pixels. */
typedef struct ss_abrasion_settings {
    int size;              /* output side in pixels */
    double world_size_cm;  /* side of the texture in the world */
    double reference_px;   /* texture size the seed's pixel values refer to (2048) */
    double scab_height_mm; /* height = 1 in the height map */
    uint64_t seed;
} ss_abrasion_settings;
void ss_abrasion_settings_default(ss_abrasion_settings *s);

/* Renders one key position. For maturation, position in 0..1 is the
 * maturation interpolation value of §4.3.5 (ignored by other phases). */
ss_status ss_abrasion_render_phase(ss_phase phase, double position, const ss_wound_shape *w,
                                   const ss_base_skin *skin, const ss_abrasion_settings *s,
                                   ss_texture_set *out, ss_error *err);

/* The rectangle outside which every phase is plain healthy skin: the wound's
 * box grown by the widest gradient. Frames blend only inside it. */
void ss_abrasion_changed_region(const ss_wound_shape *w, const ss_abrasion_settings *s, int *x,
                                int *y, int *width, int *height);

/* Only the colour of maturation at a position (reflection, height and normal
 * of maturation do not change with position): what a timeline frame in the
 * maturation phase re-renders. Writes the pixels of the wound's bounding box
 * only: outside it maturation is plain skin at every position, so color must
 * already hold a maturation colour (e.g. the key's) there. */
ss_status ss_abrasion_maturation_color(const ss_wound_shape *w, const ss_base_skin *skin,
                                       const ss_abrasion_settings *s, double position,
                                       ss_image *color, ss_error *err);
/* The same with the ages of the healed rings in days: span_days is the
 * maturation phase's length (position 0..1 over it), after_days the time past
 * its end (the scar keeps maturing: new epithelium turns into a faint scar,
 * hyperpigmentation fades); reflection (may be NULL) gets the healed skin's
 * and the granulation's shine. Writes the changed region only. */
ss_status ss_abrasion_maturation_at(const ss_wound_shape *w, const ss_base_skin *skin,
                                    const ss_abrasion_settings *s, double position,
                                    double span_days, double after_days, ss_image *color,
                                    ss_image *reflection, ss_error *err);

/* For renderers without a specular map (glTF's metallic-roughness): an RGB
 * image with roughness = 1 - 0.8 x reflection in G and metallic 0 in B (R is
 * unused, 1), so shinier parts of the reflection map are smoother. */
ss_status ss_reflection_to_metal_rough(const ss_image *reflection, ss_image *metal_rough,
                                       ss_error *err);

/* ---- timeline ----------------------------------------------------------- */

#define SS_TIMELINE_MAX_KEYS 32
typedef struct ss_timeline_key {
    ss_phase phase;
    double day;
} ss_timeline_key;
/* Keys in increasing day order; maturation runs from its key to end_day. */
typedef struct ss_timeline {
    int nkeys;
    ss_timeline_key key[SS_TIMELINE_MAX_KEYS];
    double end_day;
} ss_timeline;
/* The default mapping of phases to days (seed §2.1; docs/abrasion.md). */
void ss_timeline_default(ss_timeline *t);
/* Overrides from JSON: {"keys":[{"phase":"scab","day":3},...],"end_day":30}.
 * Checks phases are known, days finite, increasing, maturation last. */
ss_status ss_timeline_load_json(const char *path, ss_timeline *t, ss_error *err);
ss_status ss_timeline_validate(const ss_timeline *t, ss_error *err);

/* Where time t falls: the two keys to blend and the weight of the second,
 * or, in maturation, the maturation position. */
typedef struct ss_timeline_pos {
    int key_a, key_b;  /* indices into t->key */
    double weight;     /* 0 = key_a, 1 = key_b */
    int in_maturation; /* 1: re-render maturation at maturation_pos */
    double maturation_pos;
} ss_timeline_pos;
ss_timeline_pos ss_timeline_locate(const ss_timeline *t, double day);

/* The key textures: one set per phase present (rendered once; maturation at
 * position 0). */
typedef struct ss_abrasion {
    ss_abrasion_settings settings;
    ss_timeline timeline;
    const ss_wound_shape *shape;
    const ss_base_skin *skin;
    ss_texture_set phase[SS_PHASE_COUNT];
    int rendered[SS_PHASE_COUNT];
} ss_abrasion;
ss_status ss_abrasion_create(const ss_abrasion_settings *s, const ss_timeline *t,
                             const ss_wound_shape *w, const ss_base_skin *skin, ss_abrasion **out,
                             ss_error *err);
void ss_abrasion_free(ss_abrasion *a);
/* Re-renders every key for a new wound shape (same size) into the existing
 * textures: what an interactive tool does each time the user repaints, with
 * no new memory. */
ss_status ss_abrasion_update(ss_abrasion *a, const ss_wound_shape *w, ss_error *err);
/* The texture set at time day (days since injury), into out (created by the
 * caller with ss_texture_set_create at settings.size). Maps the caller set to
 * NULL (all but color) are skipped: a time slider needs only the colour. */
ss_status ss_abrasion_frame(const ss_abrasion *a, double day, ss_texture_set *out, ss_error *err);
/* ss_abrasion_frame with a progress and cancel callback (core.h
 * ss_progress_fn), polled between maps and, in maturation, between bands of
 * the re-rendered rows; cancelled: out is partly written, SS_ERR_RUNTIME. */
ss_status ss_abrasion_frame_poll(const ss_abrasion *a, double day, ss_texture_set *out,
                                 ss_progress_fn fn, void *user, ss_error *err);

#ifdef __cplusplus
}
#endif
#endif
