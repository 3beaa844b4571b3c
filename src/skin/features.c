/* Features and their distributions (seed 003 §4.8.4-4.8.5, §5.3): the
 * constants of every distribution with names for the command line, the two
 * presets, and generation (TexGen lines 3-7, §4.8.8).
 *
 * Every draw is a counter-based random number keyed by (seed, stream, index):
 * centres use stream 1 + type (through ss_skin_sample_points), parameters
 * stream 16 + type with 8 draws per feature, so a feature's parameters do not
 * depend on the sampler, the thread count or the other types' counts.
 * Wrinkles (§5.3.7) start at a point drawn from their start field (uniform by
 * default, as the seed) and step 3 times along the vector field by a third of
 * the length read at the start: the 4 points are the cubic Bezier's control
 * points. A start where the field has no direction or no length is redrawn
 * (index n + k, n + 2k, ...), so counts are exact; a field with no usable
 * vector anywhere is an input error. */
#include "skin_internal.h"

#include <math.h>
#include <stddef.h>
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#include <stdlib.h>
#include <string.h>

static const char *const TYPE_NAMES[SS_FEAT_NTYPES] = {"cysts", "moles", "freckles", "wrinkles",
                                                       "follicles"};
static const char *const TYPE_SINGULAR[SS_FEAT_NTYPES] = {"cyst", "mole", "freckle", "wrinkle",
                                                          "follicle"};

const char *ss_feature_type_name(int type) {
    return type >= 0 && type < SS_FEAT_NTYPES ? TYPE_NAMES[type] : "unknown";
}

int ss_feature_type_from_name(const char *name) {
    for (int t = 0; t < SS_FEAT_NTYPES; t++)
        if (!strcmp(name, TYPE_NAMES[t]) || !strcmp(name, TYPE_SINGULAR[t])) return t;
    return -1;
}

void ss_skin_feature_list_free(ss_skin_feature_list *l) {
    if (!l) return;
    free(l->f);
    l->f = NULL;
    l->n = 0;
}

/* ---- distribution constants --------------------------------------------- */

typedef struct dist_field {
    const char *name;
    size_t offset;
    double lo, hi;
} dist_field;
#define DF(n, m, lo, hi)                                                                           \
    { n, offsetof(ss_skin_dist, m), lo, hi }
static const dist_field DIST_FIELDS[] = {
    DF("cysts.r_sigma", cyst_r_sigma, 0, 100),
    DF("cysts.r_offset", cyst_r_offset, 0, 100),
    DF("cysts.h_max", cyst_h_max, 0, 100),
    DF("moles.r_sigma", mole_r_sigma, 0, 100),
    DF("moles.h_scale", mole_h_scale, 0, 100),
    DF("moles.h_offset", mole_h_offset, 0, 100),
    DF("moles.m_min", mole_m_min, 0, 1),
    DF("moles.m_range", mole_m_range, 0, 1),
    DF("follicles.r_inner", follicle_r_inner, 0, 100),
    DF("follicles.r_outer", follicle_r_outer, 0, 100),
    DF("follicles.height", follicle_height, 0, 100),
    DF("follicles.blood_drop", follicle_blood_drop, 0, 1),
    DF("follicles.hair_melanin", hair_melanin, 0, 2),
    DF("follicles.hair_gain", hair_gain, 0, 100),
    DF("follicles.hair_pheomelanin", hair_pheomelanin, 0, 2),
    DF("freckles.r_mean", freckle_r_mean, 0, 100),
    DF("freckles.r_sigma", freckle_r_sigma, 0, 100),
    DF("freckles.m_max", freckle_m_max, 0, 1),
    DF("freckles.h_scale", freckle_h_scale, 0, 1),
    DF("freckles.power", freckle_power, 1e-3, 100),
    DF("lips.blood", lip_blood, 0, 1),
    DF("lips.pheomelanin", lip_pheomelanin, 0, 1),
    DF("wrinkles.max_length", wrinkle_max_length, 0, 1000),
    DF("wrinkles.width", wrinkle_width, 0, 100),
    DF("wrinkles.depth", wrinkle_depth, 0, 100),
    DF("wrinkles.cross_deg", wrinkle_cross_deg, -180, 180),
    DF("wrinkles.cross_with_field", wrinkle_cross_with_field, 0, 1),
    DF("moles.r_min", mole_r_min, 0, 100),
    DF("moles.border", mole_border, 0, 1),
    DF("moles.reticular", mole_reticular, 0, 1),
    DF("moles.tone_gain", mole_tone_gain, 0, 100),
    DF("freckles.tone_gain", freckle_tone_gain, 0, 100),
    DF("mottle.melanin", mottle_melanin, 0, 2),
    DF("mottle.blood", mottle_blood, 0, 2),
    DF("mottle.min_mm", mottle_min_mm, 0.01, 1000),
    DF("mottle.max_mm", mottle_max_mm, 0.01, 1000),
    DF("mottle.height", mottle_height, 0, 10),
    DF("relief.cell", relief_cell, 0.02, 100),
    DF("relief.depth", relief_depth, 0, 10),
    DF("relief.cell2", relief_cell2, 0.02, 100),
    DF("relief.depth2", relief_depth2, 0, 10),
    DF("relief.stretch", relief_stretch, 1, 4),
    DF("surface.hydration", surface_hydration, 0, 1),
    DF("surface.sebum", surface_sebum, 0, 1),
    DF("surface.sigma_dry", surface_sigma_dry, 0.05, 1.5),
};
#define NDIST ((int)(sizeof DIST_FIELDS / sizeof DIST_FIELDS[0]))

const char *const *ss_skin_dist_names(void) {
    static const char *names[NDIST + 1];
    for (int i = 0; i < NDIST; i++) names[i] = DIST_FIELDS[i].name;
    names[NDIST] = NULL;
    return names;
}

void ss_skin_dist_default(ss_skin_dist *d) {
    memset(d, 0, sizeof *d);
    d->cyst_r_sigma = 0.2; /* §5.3.2 r = |0.2 N(0,1) + 0.01|, h = U / 2 */
    d->cyst_r_offset = 0.01;
    d->cyst_h_max = 0.5;
    d->mole_r_sigma = 0.04; /* §5.3.3 r = |0.04 N(0,1)|, h = 0.7 U + 0.3 */
    d->mole_h_scale = 0.7;
    d->mole_h_offset = 0.3;
    d->mole_m_min = 0.1; /* M: not given by the seed */
    d->mole_m_range = 0.2;
    d->follicle_r_inner = 0.04; /* §5.3.4 r_i = 0.04, r_o = 0.1 */
    d->follicle_r_outer = 0.1;
    d->follicle_height = 0.02;    /* "its maximum": ours */
    d->follicle_blood_drop = 0.5; /* §4.8.5 example: ours */
    /* hair: melanin 0.04 + 4 x the skin's (ours: blond to light brown on
     * light skin, black from melanin ~0.1), pheomelanin a constant 0.02 of
     * it (Ito & Wakamatsu 2011: eumelanin falls from black to blond hair,
     * pheomelanin stays at a trace) */
    d->hair_melanin = 0.04;
    d->hair_gain = 4.0;
    d->hair_pheomelanin = 0.02;
    d->freckle_r_mean = 0.8; /* §5.3.5 r ~ N(0.8, 0.4), M = 0.12 U, H = 0.015 (M + U) */
    d->freckle_r_sigma = 0.4;
    d->freckle_m_max = 0.12;
    d->freckle_h_scale = 0.015;
    d->freckle_power = 1.0;
    d->lip_blood = 0.045; /* §5.3.6 B and H: ours */
    d->lip_pheomelanin = 0.3;
    d->wrinkle_max_length = 8.0; /* §5.3.7: lengths from the field; scale ours */
    d->wrinkle_width = 0.3;
    d->wrinkle_depth = 0.08;
    d->wrinkle_cross_deg = 0.0;
    d->wrinkle_cross_with_field = 0.0;
    d->mole_r_min = 0.0;
    d->mole_border = 0.08; /* naevi are mostly sharp-edged: a 0.08 mm border */
    d->mole_reticular = 0.4;
    d->mole_tone_gain = 10.0; /* pigment x (1 + 10 melanin): ours, docs/skin.md */
    d->freckle_tone_gain = 10.0;
    d->mottle_melanin = 0.12; /* relative sd of melanin and blood (ours, docs/skin.md) */
    d->mottle_blood = 0.25;
    d->mottle_min_mm = 0.1;
    d->mottle_max_mm = 25.6;
    d->mottle_height = 0.004; /* sd of the gentle undulation, mm */
    d->relief_cell = 0.5;     /* polygons 0.2-1 mm, primary lines 20-100 um deep */
    d->relief_depth = 0.05;
    d->relief_cell2 = 0.15;
    d->relief_depth2 = 0.012;
    d->relief_stretch = 1.6;
    d->surface_hydration = 0.5; /* forearm: moderately hydrated, little sebum */
    d->surface_sebum = 0.15;
    d->surface_sigma_dry = 0.55;
}

static const dist_field *dist_find(const char *name) {
    for (int i = 0; i < NDIST; i++)
        if (!strcmp(name, DIST_FIELDS[i].name)) return &DIST_FIELDS[i];
    return NULL;
}

ss_status ss_skin_dist_set(ss_skin_dist *d, const char *name, double value, ss_error *err) {
    const dist_field *f = dist_find(name);
    if (!f)
        return ss_error_set(err, SS_ERR_INPUT,
                            "--param: unknown constant '%s' (see skinsim skin --list-params)",
                            name);
    if (!(value >= f->lo && value <= f->hi))
        return ss_error_set(err, SS_ERR_INPUT, "--param %s: %g is outside [%g, %g]", name, value,
                            f->lo, f->hi);
    *(double *)((char *)d + f->offset) = value;
    return SS_OK;
}

double ss_skin_dist_get(const ss_skin_dist *d, const char *name) {
    const dist_field *f = dist_find(name);
    return f ? *(const double *)((const char *)d + f->offset) : NAN;
}

/* ---- presets ------------------------------------------------------------ */

/* Forearm densities per cm^2: follicles 18 (Otberg et al. 2004, J Invest
 * Dermatol 122:14, forearm), the rest chosen for a plausible patch. */
void ss_skin_forearm_counts(double world_size_cm, long count[SS_FEAT_NTYPES]) {
    static const double per_cm2[SS_FEAT_NTYPES] = {6.0, 0.12, 3.0, 320.0, 18.0};
    double area = world_size_cm * world_size_cm;
    for (int t = 0; t < SS_FEAT_NTYPES; t++) count[t] = lround(per_cm2[t] * area);
}

ss_status ss_skin_settings_preset(ss_skin_settings *s, const char *preset, int size,
                                  ss_error *err) {
    memset(s, 0, sizeof *s);
    s->size = size;
    s->seed = 1;
    s->wrap = 1;
    s->sampler = SS_SAMPLER_ALIAS;
    s->phi = 0.1; /* §5.3.1 */
    ss_skin_dist_default(&s->dist);
    /* plausible ranges: the table's axes (docs/modelmatch.md), except
     * oxygenation, 0.75..0.95 for dermal blood (the table's 0.5 is venous) */
    for (int a = 0; a < 6; a++) ss_mm_axis_default_range(a, &s->base_lo[a], &s->base_hi[a]);
    s->base_lo[SS_BIO_OXYGENATION] = 0.75;
    s->base_hi[SS_BIO_OXYGENATION] = 0.95;
    /* melanin and blood are baseline values with relative mottling (not the
     * seed's low end plus a band): a light skin by default */
    s->base_lo[SS_BIO_MELANIN] = 0.02;
    s->base_lo[SS_BIO_BLOOD] = 0.007;
    if (!strcmp(preset, "seed")) {
        s->world_size_cm = 20.0;
        /* a face: stratum corneum ~12 um and a 60 um viable epidermis, thinner
         * than the forearm's (values ours, between the ranges' thin end and the
         * forearm). At the ranges' thinnest ends (10 and 40 um) melanin 0.43
         * came out a saturated rust (C* 29.5, issue 23's limit 24); at these
         * C* 22 (docs/skin.md, tone range) */
        s->base_lo[SS_BIO_SC_CM] = 0.0012;
        s->base_lo[SS_BIO_EPIDERMIS_CM] = 0.006;
        const long c[SS_FEAT_NTYPES] = {5000, 700, 3000, 1000, 170000};
        memcpy(s->count, c, sizeof c);
        return SS_OK;
    }
    if (!strcmp(preset, "forearm")) {
        s->world_size_cm = 5.0;
        ss_skin_forearm_counts(s->world_size_cm, s->count);
        /* a forearm: larger moles and flatter cysts than the seed's face,
         * fine crossing furrows (docs/skin.md) */
        s->dist.mole_r_sigma = 0.7; /* r = 1 + |0.7 N| mm: diameters 2-6 mm */
        s->dist.mole_r_min = 1.0;
        s->dist.mole_h_scale = 0.3;
        s->dist.mole_h_offset = 0.1;
        s->dist.cyst_h_max = 0.04;
        s->dist.cyst_r_sigma = 0.25;
        s->dist.freckle_m_max = 0.06;
        s->dist.wrinkle_max_length = 1.2;
        s->dist.wrinkle_width = 0.1;
        s->dist.wrinkle_depth = 0.025;
        s->dist.wrinkle_cross_deg = 60.0;
        s->base_lo[SS_BIO_MELANIN] = 0.02;
        s->dist.mole_m_min = 0.05; /* with the tone factor 1 + 10 melanin */
        s->dist.mole_m_range = 0.12;
        s->base_lo[SS_BIO_BLOOD] = 0.007;
        /* a forearm's stratum corneum (~13-15 um) and viable epidermis (~85-90
         * um), not the ranges' thinnest ends: a 40 um epidermis let melanin 0.43
         * through as a saturated rust (docs/skin.md, tone range) */
        s->base_lo[SS_BIO_SC_CM] = 0.0012;
        s->base_lo[SS_BIO_EPIDERMIS_CM] = 0.0082;
        return SS_OK;
    }
    return ss_error_set(err, SS_ERR_INPUT, "--preset: unknown preset '%s' (forearm or seed)",
                        preset);
}

ss_status ss_skin_settings_validate(const ss_skin_settings *s, ss_error *err) {
    if (s->size < 8 || s->size > 32768)
        return ss_error_set(err, SS_ERR_INPUT, "--size %d: must be 8..32768", s->size);
    if (!(s->world_size_cm > 0.0) || !isfinite(s->world_size_cm))
        return ss_error_set(err, SS_ERR_INPUT, "--world-size-cm %g: must be > 0", s->world_size_cm);
    for (int t = 0; t < SS_FEAT_NTYPES; t++)
        if (s->count[t] < 0 || s->count[t] > 100000000L)
            return ss_error_set(err, SS_ERR_INPUT, "--count %s=%ld: must be 0..100000000",
                                ss_feature_type_name(t), s->count[t]);
    if (!(s->phi >= 0.0 && s->phi <= 1.0))
        return ss_error_set(err, SS_ERR_INPUT, "phi %g: must be 0..1", s->phi);
    for (int a = 0; a < 6; a++)
        if (!isfinite(s->base_lo[a]) || !isfinite(s->base_hi[a]) || s->base_lo[a] < 0.0 ||
            s->base_hi[a] < s->base_lo[a])
            return ss_error_set(err, SS_ERR_INPUT, "baseline %s: range %g..%g is not valid",
                                ss_bio_channel_name(a), s->base_lo[a], s->base_hi[a]);
    for (int i = 0; i < NDIST; i++) {
        double v = *(const double *)((const char *)&s->dist + DIST_FIELDS[i].offset);
        if (!(v >= DIST_FIELDS[i].lo && v <= DIST_FIELDS[i].hi))
            return ss_error_set(err, SS_ERR_INPUT, "%s = %g is outside [%g, %g]",
                                DIST_FIELDS[i].name, v, DIST_FIELDS[i].lo, DIST_FIELDS[i].hi);
    }
    if (s->dist.follicle_r_outer < s->dist.follicle_r_inner)
        return ss_error_set(err, SS_ERR_INPUT, "follicles.r_outer %g < follicles.r_inner %g",
                            s->dist.follicle_r_outer, s->dist.follicle_r_inner);
    return SS_OK;
}

/* ---- generation ---------------------------------------------------------- */

#define PARAM_STREAM(t) (16u + (uint64_t)(t))
#define DRAWS 8

static double draw_u(uint64_t seed, int type, size_t k, int j) {
    return ss_rng_uniform(seed, PARAM_STREAM(type), (uint64_t)k * DRAWS + (uint64_t)j);
}
/* Standard normal by Box-Muller from draws j and j+1. */
static double draw_n(uint64_t seed, int type, size_t k, int j) {
    double u1 = draw_u(seed, type, k, j), u2 = draw_u(seed, type, k, j + 1);
    return sqrt(-2.0 * log(1.0 - u1)) * cos(2.0 * M_PI * u2);
}

/* The built-in wrinkle field: directions turning slowly around 20 degrees,
 * full length; periodic in x and y so it tiles. */
static void default_vector(double x, double y, double *vx, double *vy, double *len) {
    double a = (20.0 + 12.0 * sin(2.0 * M_PI * (x + 0.3 * sin(2.0 * M_PI * y))) +
                8.0 * sin(4.0 * M_PI * y)) *
               M_PI / 180.0;
    *vx = cos(a);
    *vy = sin(a);
    *len = 1.0;
}

static void field_vector(const ss_image *v, double x, double y, double *vx, double *vy,
                         double *len) {
    if (!v) {
        default_vector(x, y, vx, vy, len);
        return;
    }
    float s[4];
    x -= floor(x);
    y -= floor(y);
    ss_image_sample_wrap(v, (float)x, (float)y, s);
    *vx = 2.0 * s[0] - 1.0;
    *vy = 2.0 * s[1] - 1.0;
    *len = s[2] < 0.0f ? 0.0 : s[2] > 1.0f ? 1.0 : s[2];
}

/* A direction shorter than this counts as zero: 8-bit PNGs cannot store 0.5
 * exactly (128/255 gives 0.0039), so "no direction" is anything within about
 * one 8-bit step of (0.5, 0.5). */
#define MIN_DIR 0.01

int skin_field_direction(const ss_image *vf, double x, double y, double *vx, double *vy) {
    double len;
    field_vector(vf, x, y, vx, vy, &len);
    double n = hypot(*vx, *vy);
    if (!(n > MIN_DIR)) {
        *vx = 1.0, *vy = 0.0;
        return 0;
    }
    *vx /= n, *vy /= n;
    return 1;
}

static int has_vector(const ss_image *v) {
    if (!v) return 1;
    size_t n = (size_t)v->width * v->height;
    for (size_t i = 0; i < n; i++) {
        const float *p = v->data + i * (size_t)v->channels;
        if (fabsf(2.0f * p[0] - 1.0f) + fabsf(2.0f * p[1] - 1.0f) > 1e-3f && p[2] > 1e-3f) return 1;
    }
    return 0;
}

/* Builds the curve of wrinkle k from start (x0, y0); 0 if the field has no
 * direction or length there. */
static int make_wrinkle(const ss_skin_settings *s, const ss_image *vf, size_t k, double x0,
                        double y0, ss_skin_feature *f) {
    const double mm_per_unit = s->world_size_cm * 10.0;
    double vx, vy, len;
    field_vector(vf, x0, y0, &vx, &vy, &len);
    double norm = hypot(vx, vy);
    if (!(norm > MIN_DIR) || !(len > 1e-3)) return 0;
    double step = len * s->dist.wrinkle_max_length / 3.0 / mm_per_unit;
    /* with a user's vector field, wrinkles follow it unless the crossing is
     * asked for (wrinkles.cross_with_field, which --param wrinkles.cross_deg
     * sets on the command line) */
    const int cross = !vf || s->dist.wrinkle_cross_with_field != 0.0;
    double rot = (k & 1) && cross ? s->dist.wrinkle_cross_deg * M_PI / 180.0 : 0.0;
    double cr = cos(rot), sr = sin(rot);
    double x = x0, y = y0, px = vx / norm, py = vy / norm;
    f->curve.x[0] = x;
    f->curve.y[0] = y;
    for (int i = 1; i < 4; i++) {
        double dx = px * cr - py * sr, dy = px * sr + py * cr;
        x += step * dx;
        y += step * dy;
        f->curve.x[i] = x;
        f->curve.y[i] = y;
        double ux, uy, ul;
        field_vector(vf, x, y, &ux, &uy, &ul);
        double un = hypot(ux, uy);
        if (un > MIN_DIR) {
            /* keep the sense of travel (a direction field has no sign) */
            if (ux * px + uy * py < 0.0) ux = -ux, uy = -uy;
            px = ux / un, py = uy / un;
        }
    }
    f->x = x0;
    f->y = y0;
    f->w = s->dist.wrinkle_width * (0.5 + 0.5 * draw_u(s->seed, SS_FEAT_WRINKLE, k, 0));
    f->h = s->dist.wrinkle_depth * (0.5 + 0.5 * draw_u(s->seed, SS_FEAT_WRINKLE, k, 1));
    return 1;
}

/* Parameters of point feature k of type t (§5.3). */
static void point_params(const ss_skin_settings *s, int t, size_t k, ss_skin_feature *f) {
    const ss_skin_dist *d = &s->dist;
    uint64_t sd = s->seed;
    switch (t) {
    case SS_FEAT_CYST:
        f->r = fabs(d->cyst_r_sigma * draw_n(sd, t, k, 0) + d->cyst_r_offset);
        f->h = d->cyst_h_max * draw_u(sd, t, k, 2);
        break;
    case SS_FEAT_MOLE:
        f->r = d->mole_r_min + fabs(d->mole_r_sigma * draw_n(sd, t, k, 0));
        /* p: 1 for a reticular pigment network, 0 for uniform pigment */
        f->p = draw_u(sd, t, k, 4) < d->mole_reticular ? 1.0 : 0.0;
        f->h = d->mole_h_scale * draw_u(sd, t, k, 2) + d->mole_h_offset;
        f->m = d->mole_m_min + d->mole_m_range * draw_u(sd, t, k, 3);
        break;
    case SS_FEAT_FRECKLE: {
        f->r = fabs(d->freckle_r_mean + d->freckle_r_sigma * draw_n(sd, t, k, 0));
        f->m = d->freckle_m_max * draw_u(sd, t, k, 2);
        f->p = d->freckle_h_scale * (f->m + draw_u(sd, t, k, 3));
        break;
    }
    case SS_FEAT_FOLLICLE:
        f->r = d->follicle_r_inner;
        f->r2 = d->follicle_r_outer;
        break;
    default:
        break;
    }
}

static void note_add(char *notes, size_t len, const char *msg) {
    if (!notes || !len) return;
    size_t used = strlen(notes);
    if (used + strlen(msg) + 3 < len) {
        if (used) strcat(notes, "; ");
        strcat(notes, msg);
    }
}

ss_status ss_skin_generate(const ss_skin_settings *s, const ss_skin_fields *fields,
                           ss_skin_feature_list *out, char *notes, size_t notes_len,
                           ss_error *err) {
    return ss_skin_generate_poll(s, fields, out, notes, notes_len, NULL, NULL, err);
}

/* Polled between feature types and at the end (each type is one sampling
 * pass and one parameter pass, at most a few tenths of a second). */
ss_status ss_skin_generate_poll(const ss_skin_settings *s, const ss_skin_fields *fields,
                                ss_skin_feature_list *out, char *notes, size_t notes_len,
                                ss_progress_fn fn, void *user, ss_error *err) {
    memset(out, 0, sizeof *out);
    if (notes && notes_len) notes[0] = '\0';
    ss_status st = ss_skin_settings_validate(s, err);
    if (st) return st;
    static const ss_skin_fields none;
    if (!fields) fields = &none;
    size_t total = 0;
    for (int t = 0; t < SS_FEAT_NTYPES; t++) total += (size_t)s->count[t];
    out->f = calloc(total ? total : 1, sizeof *out->f);
    if (!out->f) return ss_error_set(err, SS_ERR_NOMEM, "features: out of memory (%zu)", total);
    ss_image *uniform = ss_image_create(1, 1, 1, err);
    if (!uniform) {
        free(out->f);
        out->f = NULL;
        return err->code;
    }
    uniform->data[0] = 1.0f;
    const ss_image *vf = fields->wrinkle_vectors;
    if (vf && vf->channels < 3) {
        st = ss_error_set(err, SS_ERR_INPUT, "wrinkle vector field: needs RGB, has %d channel%s",
                          vf->channels, vf->channels == 1 ? "" : "s");
    }
    size_t at = 0;
    for (int t = 0; t < SS_FEAT_NTYPES && !st; t++) {
        if (fn && t > 0 && fn(user, (double)t / SS_FEAT_NTYPES)) {
            st = ss_error_set(err, SS_ERR_RUNTIME, "skin features: cancelled");
            break;
        }
        size_t n = (size_t)s->count[t];
        if (n == 0) continue;
        const ss_image *field = fields->density[t] ? fields->density[t] : uniform;
        double power = t == SS_FEAT_FRECKLE ? s->dist.freckle_power : 1.0;
        if (t == SS_FEAT_WRINKLE && !has_vector(vf)) {
            st = ss_error_set(err, SS_ERR_INPUT,
                              "wrinkle vector field: every vector is zero (R = G = 0.5 or B = "
                              "0); no wrinkle can be drawn");
            break;
        }
        size_t ndraw = n;
        double *xy = malloc(2 * ndraw * sizeof *xy);
        if (!xy) {
            st = ss_error_set(err, SS_ERR_NOMEM, "features: out of memory");
            break;
        }
        ss_error e2;
        st = ss_skin_sample_points(field, power, s->sampler, s->seed, 1 + (uint64_t)t, ndraw, xy,
                                   &e2);
        if (st) {
            free(xy);
            if (st == SS_ERR_INPUT && fields->density[t] && strstr(e2.msg, "all black")) {
                /* an all-black field: no features of this type, and it is said */
                char msg[160];
                snprintf(msg, sizeof msg, "%s: field is all black, no features",
                         ss_feature_type_name(t));
                note_add(notes, notes_len, msg);
                st = SS_OK;
                continue;
            }
            ss_error_set(err, st, "%s field: %s", ss_feature_type_name(t), e2.msg);
            break;
        }
        if (t != SS_FEAT_WRINKLE) {
#pragma omp parallel for schedule(static)
            for (size_t k = 0; k < n; k++) {
                ss_skin_feature *f = &out->f[at + k];
                f->type = t;
                f->x = xy[2 * k];
                f->y = xy[2 * k + 1];
                point_params(s, t, k, f);
            }
            at += n;
        } else {
            /* a start without a usable vector is redrawn from stream pass
             * 64 + j (j = 1, 2, ...) at the same index k: order stays by k */
            char *done = calloc(n, 1);
            if (!done) st = ss_error_set(err, SS_ERR_NOMEM, "features: out of memory");
            size_t left = n;
            for (int pass = 0; pass < 64 && left && !st; pass++) {
                if (pass > 0) {
                    st = ss_skin_sample_points(field, power, s->sampler, s->seed,
                                               64 + (uint64_t)pass, n, xy, err);
                    if (st) break;
                }
                for (size_t k = 0; k < n; k++) {
                    if (done[k]) continue;
                    ss_skin_feature *f = &out->f[at + k];
                    memset(f, 0, sizeof *f);
                    f->type = t;
                    if (make_wrinkle(s, vf, k, xy[2 * k], xy[2 * k + 1], f)) done[k] = 1, left--;
                }
            }
            if (!st && left)
                st = ss_error_set(err, SS_ERR_INPUT,
                                  "wrinkle vector field: %zu of %zu wrinkles found only zero "
                                  "vectors at 64 start points each",
                                  left, n);
            free(done);
            at += n;
        }
        free(xy);
    }
    ss_image_free(uniform);
    if (!st && fn && fn(user, 1.0))
        st = ss_error_set(err, SS_ERR_RUNTIME, "skin features: cancelled");
    if (st) {
        ss_skin_feature_list_free(out);
        return st;
    }
    out->n = at;
    return SS_OK;
}
