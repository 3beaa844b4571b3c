/* Tissue -> biology -> textures, per texel (docs/wound.md has every mapping
 * with its reason and source):
 *
 *   cover = ramp(epithelium)            new epidermis over the bed (1 = closed)
 *   reg   = ramp(plasma)                the wound region (§4.1.8): tissue that was destroyed
 *   maturity m(a) = 1 - exp(-a / tau)   a = days since the column closed (observed)
 *   skin  = lerp(base texel, base mean, reg)     destroyed tissue loses its features
 *   melanin   = skin x cover x (reg: repigmentation(age) x PIH(age), shared with abrasion)
 *   epidermis = lerp(floor, skin x (reg: lerp(new_epidermis, 1, m_epidermis)), cover)
 *   blood     = lerp(skin x capillary x (reg: lerp(1, scar_blood, scar x m_scar))
 *                    + young_blood x reg x cover x (1 - m_scar),  min(bed, cap),  open x reg),
 *               bed = lerp(skin, bed_blood, capillary) x loops; the bed's blood above the
 *               table's cap is in its top loop_depth, drawn per wavelength with the clot
 *               and exudate on it (bed_spectrum.c)
 *   oxygenation = lerp(clot_oxygenation, skin, oxygen)
 *   -> ModelMatch (GGX base colour, roughness), then the scar's whitening, the
 *      scab (dried-blood layer, adding formula), roughness of the wet bed, the
 *      scab and the mature scar, and the height: skin relief - depth (§5.4) +
 *      scab + keloid (+ the mechanics' displacement).
 *
 * Design: the tissue maps are at grid resolution and sampled bilinearly; a
 * texel whose four source columns are all healthy (and undeformed) is copied
 * from the base skin's textures (`skinsim skin`'s render maps of the bio map),
 * so the skin away from the wound is the base skin exactly and only the
 * wound's texels cost a table lookup (skin.h's render lookup of the GGX fit).
 * Hair is pigment of the bio map (src/skin/texgen.c: hair melanin through
 * the table, as the skin's), so the same lookup draws it, and where the
 * tissue was destroyed it goes with the skin's other features. The bio
 * map's extra colour (an RGBA over-layer, 0 in every map `skinsim skin`
 * writes now) is still laid over everything except the destroyed tissue: a
 * --skin bio.exr may carry one (an older `skinsim skin` run, a user's
 * paint), and `skinsim skin`'s render maps, copied outside the wound, lay
 * it too, so without it here a painted hair would stop at a seam where the
 * rendered texels begin; at alpha 0 it changes no value. Gave up: sub-texel detail of the fields
 * (the grid is 0.5 mm; bilinear keeps edges soft, as healing edges are). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/geom.h"
#include "skinsim/optics.h"
#include "skinsim/texture.h"
#include "wound_internal.h"

/* Floors of the open bed: no epidermis and no stratum corneum, held at the
 * table's smallest samples (the transport needs layers of non-zero
 * thickness); the melanin floor is the table's too. */
#define EPI_FLOOR_CM 0.004
#define SC_FLOOR_CM 0.001
#define MELANIN_FLOOR 0.0
/* The jitter of the tissue sampling, in grid columns (docs/wound.md). */
#define WARP_COLUMNS 0.7
/* On a mesh's UV layout a texel is the mean of BOX_N x BOX_N samples of the
 * tissue over a square of EDGE_BOX_MM on the skin: a filter of fixed size in
 * mm, so a wound's edge is antialiased and equally wide at 512, 1024 and 2048
 * (a 512 texel of the hand is 0.66 mm). */
#define EDGE_BOX_MM 0.8
#define BOX_N 4
/* Its noise's period (mm), and the texels per period from which it is whole. */
#define WARP_PERIOD_MM 0.6
#define WARP_FULL_PX 6.0
/* The crust's edge: its coverage rises over this many mm from its edge. */
#define EDGE_MM 0.4
/* The open bed's edge: its coverage (the exposed dermis, the clot over it,
 * the bed's blood and wetness, all one mask) rises over this many mm across
 * the contour of the open columns (open_in, a signed distance). */
#define BED_EDGE_MM 0.3
/* A crust is granular (clotted cells, fibrin strands, dried serum at a few
 * tenths of a mm): its thickness varies by +-CRUST_GRAIN at ~0.6 mm, and the
 * edges of its serous patches are as ragged, not soft blobs. */
#define CRUST_GRAIN 0.25
/* Healed skin is patchy: its post-inflammatory hyperpigmentation and its
 * young tissue's redness vary by +-PATCHY (a flat colour over the healed
 * region, days 14-90, read as paint). */
#define PATCHY 0.35
/* The fresh clot of the open bed: at most CLOT_MAX_MM of pooled blood, and
 * POOL_FILM of that between the pools (a film of ooze over the bed). */
#define CLOT_MAX_MM 0.4
/* The bed's capillary loops (dots at ~0.35 mm) hold up to 1 + 5/6 LOOP_CONTRAST
 * times its blood, the tissue between them 1 - LOOP_CONTRAST / 6 (an even bed
 * of loops: at 3, red dots on an orange film of thin blood) */
#define LOOP_CONTRAST 1.5
#define POOL_FILM 0.25
/* A keloid's telangiectasia (module comment of render_texel's keloid part):
 * trunks along the mid-level lines of a value noise of KELOID_TRUNK_MM,
 * branches along those of one of KELOID_BRANCH_MM near the trunks, both
 * with widths in mm; its nodular surface a noise of KELOID_NODULE_MM. */
#define KELOID_TRUNK_MM 3.0
#define KELOID_BRANCH_MM 1.2
#define KELOID_NODULE_MM 4.0
/* where the keloid's swelling starts: its edge for the margin's distance */
#define KELOID_EDGE_FRACTION 0.1
/* blood and oxygenation in the dilated vessels: the table's most blood
 * (ss_mm_axis_default_range: 5 %), oxygenated as in the open bed */
#define VESSEL_BLOOD 0.05
#define VESSEL_OXYGENATION 0.9

struct ss_wound_renderer {
    ss_wound_render_options o;
    ss_image *skin; /* size x size x SS_BIO_NCHANNELS */
    ss_skin_lut *lut;
    float mean[SS_BIO_NCHANNELS];
    ss_layer_table scab, serous, clot;
    ss_image *crust;     /* value noise 0..1 at ~1.5 mm: the crust's thickness is uneven */
    ss_image *mottle;    /* value noise at ~3 mm: where the crust is serous, not bloody */
    ss_image *crack;     /* value noise at ~2.5 mm: its mid-level lines are the cracks */
    ss_image *warp[2];   /* value noise at ~1.2 mm: jitter of where the tissue maps are
                            sampled, so margins are ragged, not stepped with the voxels */
    ss_image *cap;       /* value noise at ~0.35 mm: the bed's capillary loops */
    ss_image *grain;     /* value noise at ~0.6 mm: the crust's granular surface */
    ss_image *vessel[2]; /* value noise at KELOID_TRUNK_MM, KELOID_BRANCH_MM: the keloid's
                            vessels along their mid-level lines */
    ss_image *nodule;    /* value noise at KELOID_NODULE_MM: the keloid's uneven raise */
    double pih;          /* the skin type's rate of post-inflammatory hyperpigmentation */
    double blood_cap;    /* the table's largest blood fraction: blood above it is a layer */
    ss_bed_spectra bed;  /* the open bed's spectra: its blood layers added per wavelength */
    ss_wound_textures base;
    ss_image *columns; /* NULL: the flat block; else tissue-map coordinates per texel */
};

void ss_wound_render_options_default(ss_wound_render_options *o) {
    memset(o, 0, sizeof *o);
    o->size = 1024;
    o->side_mm = 30;
    ss_wound_recipe_default(&o->recipe);
    o->scab_photons = 2000;
    o->seed = 1;
}

ss_status ss_wound_textures_create(int size, ss_wound_textures *t, ss_error *err) {
    memset(t, 0, sizeof *t);
    if (!(t->base_color = ss_image_create(size, size, 3, err)) ||
        !(t->roughness = ss_image_create(size, size, 1, err)) ||
        !(t->height = ss_image_create(size, size, 1, err)) ||
        !(t->normal = ss_image_create(size, size, 3, err))) {
        ss_wound_textures_free(t);
        return err->code ? err->code : SS_ERR_NOMEM;
    }
    return SS_OK;
}

void ss_wound_textures_free(ss_wound_textures *t) {
    ss_image_free(t->base_color);
    ss_image_free(t->roughness);
    ss_image_free(t->height);
    ss_image_free(t->normal);
    memset(t, 0, sizeof *t);
}

/* ---- the table lookup (skinsim/skin.h's render lookup of the GGX fit) ------------- */

typedef struct lookup5 {
    double rgb[3], roughness;
} lookup5;

/* One texel's bio parameters -> base colour and roughness. */
static void bio_to_render(const ss_skin_lut *lut, ss_skin_lut_cache *lc, const float *b,
                          lookup5 *out) {
    float x[6] = {b[SS_BIO_MELANIN],     b[SS_BIO_PHEOMELANIN], b[SS_BIO_BLOOD],
                  b[SS_BIO_OXYGENATION], b[SS_BIO_SC_CM],       b[SS_BIO_EPIDERMIS_CM]};
    float r[5];
    ss_skin_lut_lookup_cached(lut, lc, x, r);
    for (int c = 0; c < 3; c++) out->rgb[c] = r[c] < 0 ? 0 : r[c] > 1 ? 1 : r[c];
    out->roughness = r[4] < 0 ? 0 : r[4] > 1 ? 1 : r[4];
}

/* ---- create ----------------------------------------------------------------------------- */

/* The open bed's blood above the table's cap, as fractions of its capillary
 * loops' layer (bed_spectrum.c): up to whole blood, denser where the colour
 * changes fastest. */
static const double LOOP_BLOOD[] = {0.075, 0.1, 0.15, 0.2, 0.3, 0.45, 0.65, 1.0};
#define NLOOP_BLOOD ((int)(sizeof LOOP_BLOOD / sizeof *LOOP_BLOOD))

/* The open bed's reflectance spectra (bed_spectrum.c): at the table's blood
 * samples (at most SS_BED_MAX_BLOOD - NLOOP_BLOOD of them, evenly picked,
 * both ends kept) and with its loops' blood above the cap; the bed's bio
 * parameters (no melanin: the table's least, the floors of the epidermis
 * and stratum corneum, the bed's oxygenation, the skin's mean pheomelanin
 * ratio), the table's base pigments. */
static ss_status build_bed_spectra(ss_wound_renderer *r, ss_error *err) {
    const ss_mm_table *t = r->o.table;
    int n = t->nsamples[SS_MM_AXIS_BLOOD], most = SS_BED_MAX_BLOOD - NLOOP_BLOOD;
    int m = n < most ? n : most;
    double blood[SS_BED_MAX_BLOOD];
    for (int k = 0; k < m; k++)
        blood[k] =
            t->axis[SS_MM_AXIS_BLOOD][m > 1 ? (int)lround((double)k * (n - 1) / (m - 1)) : 0];
    double cap = blood[m - 1];
    if (!(cap > 0 && cap < 1))
        return ss_error_set(err, SS_ERR_INPUT,
                            "wound renderer: the table's largest blood "
                            "fraction (%g) is not in (0, 1)",
                            cap);
    for (int k = 0; k < NLOOP_BLOOD; k++)
        if (LOOP_BLOOD[k] > blood[m - 1]) blood[m++] = LOOP_BLOOD[k];
    ss_bio_params bed;
    ss_bio_params_default(&bed);
    bed.melanin = t->axis[SS_MM_AXIS_MELANIN][0];
    bed.pheomelanin_ratio = fmin(1, fmax(0, r->mean[SS_BIO_PHEOMELANIN]));
    bed.oxygenation = fmin(1, fmax(0, r->o.recipe.v[SS_WR_BED_OXYGENATION]));
    bed.sc_thickness_cm = SC_FLOOR_CM;
    bed.epidermis_thickness_cm = EPI_FLOOR_CM;
    return ss_bed_spectra_build(&bed, blood, m, cap, r->o.recipe.v[SS_WR_LOOP_DEPTH_MM],
                                r->o.scab_photons, r->o.seed + 4000, &r->bed, err);
}

/* The base skin's textures are `skinsim skin`'s render maps of the bio map. */
static ss_status render_base(ss_wound_renderer *r, ss_error *err) {
    ss_skin_maps m;
    ss_status st = ss_skin_render_maps(r->skin, r->lut, r->o.side_mm / 10.0, 0, &m, err);
    if (st) return st;
    r->base.base_color = m.base_color;
    r->base.roughness = m.roughness;
    r->base.height = m.height_mm;
    r->base.normal = m.normal;
    /* The wound has its own specular, translucency and cavity: drop the skin's. */
    ss_image_free(m.specular);
    ss_image_free(m.translucency);
    ss_image_free(m.cavity);
    return SS_OK;
}

ss_status ss_wound_renderer_create(const ss_wound_render_options *o, ss_wound_renderer **out,
                                   ss_error *err) {
    *out = NULL;
    if (!o->table || !o->skin || o->size < 4 || o->size > 16384 || !(o->side_mm > 0))
        return ss_error_set(err, SS_ERR_INPUT,
                            "wound renderer: need a table, a skin, a size "
                            "of 4..16384 and a side > 0 mm");
    ss_status st = ss_wound_skin_validate(o->skin, "base skin", err);
    if (st) return st;
    ss_wound_renderer *r = calloc(1, sizeof *r);
    if (!r) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    r->o = *o;
    r->skin = (o->skin->width == o->size && o->skin->height == o->size)
                  ? ss_image_clone(o->skin, err)
                  : ss_image_resize(o->skin, o->size, o->size, err);
    if (!r->skin) st = err->code ? err->code : SS_ERR_NOMEM;
    if (!st) {
        size_t n = (size_t)o->size * (size_t)o->size;
        for (int c = 0; c < SS_BIO_NCHANNELS; c++) {
            double acc = 0;
            for (size_t i = 0; i < n; i++) acc += r->skin->data[i * SS_BIO_NCHANNELS + c];
            r->mean[c] = (float)(acc / (double)n);
        }
    }
    ss_blood_layer scab, serous, clot;
    ss_blood_layer_scab(o->recipe.v[SS_WR_SCAB_HB_FACTOR], &scab);
    ss_blood_layer_scab(o->recipe.v[SS_WR_SCAB_SEROUS_HB], &serous);
    scab.bilirubin_g_per_l = serous.bilirubin_g_per_l = o->recipe.v[SS_WR_SCAB_BILIRUBIN];
    ss_blood_layer_clot(o->recipe.v[SS_WR_CLOT_OXYGENATION], &clot);
    if (!st) st = ss_layer_table_build(&scab, o->scab_photons, o->seed, &r->scab, err);
    if (!st) st = ss_layer_table_build(&clot, o->scab_photons, o->seed + 1000, &r->clot, err);
    if (!st) st = ss_layer_table_build(&serous, o->scab_photons, o->seed + 2000, &r->serous, err);
    if (!st && !(r->lut = ss_skin_lut_create(o->table, err))) st = err->code;
    if (!st) /* as a float, the lookup's own axis value */
        r->blood_cap =
            (float)o->table->axis[SS_MM_AXIS_BLOOD][o->table->nsamples[SS_MM_AXIS_BLOOD] - 1];
    if (!st) st = build_bed_spectra(r, err);
    if (!st && !(r->crust = ss_image_create(o->size, o->size, 1, err))) st = err->code;
    if (!st) st = ss_wound__noise(o->size, o->side_mm, 1.5, 2, o->seed, 201, r->crust, err);
    if (!st && !(r->mottle = ss_image_create(o->size, o->size, 1, err))) st = err->code;
    if (!st) st = ss_wound__noise(o->size, o->side_mm, 2.0, 3, o->seed, 202, r->mottle, err);
    if (!st && !(r->crack = ss_image_create(o->size, o->size, 1, err))) st = err->code;
    if (!st) st = ss_wound__noise(o->size, o->side_mm, 2.5, 3, o->seed, 203, r->crack, err);
    if (!st && !(r->cap = ss_image_create(o->size, o->size, 1, err))) st = err->code;
    if (!st) st = ss_wound__noise(o->size, o->side_mm, 0.35, 1, o->seed, 206, r->cap, err);
    if (!st && !(r->grain = ss_image_create(o->size, o->size, 1, err))) st = err->code;
    if (!st) st = ss_wound__noise(o->size, o->side_mm, 0.6, 2, o->seed, 207, r->grain, err);
    const double vessel_mm[2] = {KELOID_TRUNK_MM, KELOID_BRANCH_MM};
    for (int k = 0; k < 2 && !st; k++) {
        if (!(r->vessel[k] = ss_image_create(o->size, o->size, 1, err))) st = err->code;
        if (!st)
            st = ss_wound__noise(o->size, o->side_mm, vessel_mm[k], 2 - k, o->seed,
                                 208 + (uint64_t)k, r->vessel[k], err);
    }
    if (!st && !(r->nodule = ss_image_create(o->size, o->size, 1, err))) st = err->code;
    if (!st)
        st =
            ss_wound__noise(o->size, o->side_mm, KELOID_NODULE_MM, 2, o->seed, 210, r->nodule, err);
    for (int k = 0; k < 2 && !st; k++) {
        if (!(r->warp[k] = ss_image_create(o->size, o->size, 1, err))) st = err->code;
        if (!st)
            st = ss_wound__noise(o->size, o->side_mm, WARP_PERIOD_MM, 2, o->seed, 204 + (uint64_t)k,
                                 r->warp[k], err);
    }
    if (!st) st = render_base(r, err);
    if (!st) { /* the skin type: typology angle of the base skin's mean colour */
        size_t n = (size_t)o->size * (size_t)o->size;
        double m[3] = {0, 0, 0}, lab[3], chroma, hue, ita;
        for (size_t i = 0; i < n; i++)
            for (int c = 0; c < 3; c++) m[c] += r->base.base_color->data[i * 3 + c];
        for (int c = 0; c < 3; c++) m[c] /= (double)n;
        ss_srgb_linear_to_lab(m, lab);
        ss_lab_describe(lab, &chroma, &hue, &ita);
        r->pih = ss_pih_prevalence(ita);
    }
    if (st) {
        ss_wound_renderer_free(r);
        return st;
    }
    *out = r;
    return SS_OK;
}

void ss_wound_renderer_free(ss_wound_renderer *r) {
    if (!r) return;
    ss_image_free(r->skin);
    ss_image_free(r->crust);
    ss_image_free(r->columns);
    ss_image_free(r->mottle);
    ss_image_free(r->crack);
    ss_image_free(r->warp[0]);
    ss_image_free(r->warp[1]);
    ss_image_free(r->cap);
    ss_image_free(r->grain);
    ss_image_free(r->vessel[0]);
    ss_image_free(r->vessel[1]);
    ss_image_free(r->nodule);
    ss_skin_lut_free(r->lut);
    ss_wound_textures_free(&r->base);
    free(r);
}

double ss_wound_renderer_pih_factor(const ss_wound_renderer *r, double days) {
    return ss_pih_melanin_factor(r->pih, days, r->o.recipe.v[SS_WR_PIH_GAIN]);
}

/* The recipe's repigmentation (ss_repigmentation_factor's parameters). */
static ss_repigmentation recipe_repigmentation(const double *v) {
    return (ss_repigmentation){v[SS_WR_NEW_MELANIN], v[SS_WR_PIGMENT_DAYS], v[SS_WR_SCAR_MELANIN]};
}

double ss_wound_renderer_melanin_factor(const ss_wound_renderer *r, double days) {
    ss_repigmentation p = recipe_repigmentation(r->o.recipe.v);
    return ss_healed_melanin_factor(&p, r->pih, r->o.recipe.v[SS_WR_PIH_GAIN], days);
}

const ss_wound_textures *ss_wound_renderer_base(const ss_wound_renderer *r) { return &r->base; }

ss_status ss_wound_renderer_set_columns(ss_wound_renderer *r, const ss_image *columns,
                                        ss_error *err) {
    int n = r->o.size;
    if (columns && (columns->width != n || columns->height != n || columns->channels != 2))
        return ss_error_set(err, SS_ERR_INPUT, "wound renderer: the column map must be %dx%d x 2",
                            n, n);
    ss_image *c = columns ? ss_image_clone(columns, err) : NULL;
    if (columns && !c) return err->code ? err->code : SS_ERR_NOMEM;
    ss_image_free(r->columns);
    r->columns = c;
    return SS_OK;
}

/* ---- render ------------------------------------------------------------------------------ */

static double ramp(double v, double lo, double hi) {
    double f = (v - lo) / (hi - lo);
    f = f < 0 ? 0 : f > 1 ? 1 : f;
    return f * f * (3 - 2 * f); /* smoothstep: no kinks at the ends */
}
static double clamp01(double v) { return v < 0 ? 0 : v > 1 ? 1 : v; }
static double lerp(double a, double b, double t) { return a + (b - a) * t; }

/* The tissue at one texel (bilinear between column centres, clamped at the
 * edges). The age (days since a column closed) is the mean over the wounded
 * columns only: intact columns hold the sentinel SS_WOUND_AGE_INTACT (1e5
 * days), and mixing it in made the margin of a healed region look a
 * century old (a bright rim of mature scar around a 90-day-old one). */
typedef struct texel_tissue {
    double e, cap, oxy, plasma, scab, scar, keloid, depth, age, elev;
    double wounded;   /* weight of the columns that were ever open (0..1) */
    double crust_in;  /* mm from the crust's edge inwards (0 outside the crust) */
    double keloid_in; /* mm from the keloid's edge inwards (0 outside it) */
    double wound_in;  /* mm from the edge of the columns that were ever open inwards */
    double open_in;   /* mm from the edge of the open bed inwards, negative outside it */
} texel_tissue;

/* Per column: mm from the crust's and from the keloid's edge inwards. */
typedef struct edge_maps {
    const float *crust_in, *keloid_in, *wound_in, *open_in;
} edge_maps;

/* On a mesh's UV layout: the same fields through a cubic B-spline (4 x 4
 * columns, weights summing to 1, clamped at the edges). A texel there is
 * 0.3-0.7 mm, close to a column: bilinear sampling of a step between two
 * columns gave a transition narrower than a texel (stepped, aliased edges at
 * 1024). The B-spline is C2, so a wound's edge is a smooth ramp about two
 * columns wide, the same width in mm at every texture size. */
static void sample_tissue_smooth(const ss_wound_tissue *t, const edge_maps *em, double mx,
                                 double my, texel_tissue *s) {
    double fx0 = floor(mx), fy0 = floor(my), fx = mx - fx0, fy = my - fy0;
    double wx[4], wy[4];
    const double *f[2] = {&fx, &fy};
    double *w[2] = {wx, wy};
    for (int a = 0; a < 2; a++) {
        double u = *f[a], v = 1 - u;
        w[a][0] = v * v * v / 6;
        w[a][1] = (3 * u * u * u - 6 * u * u + 4) / 6;
        w[a][2] = (-3 * u * u * u + 3 * u * u + 3 * u + 1) / 6;
        w[a][3] = u * u * u / 6;
    }
    size_t idx[16];
    double wt[16];
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++) {
            double xx = fx0 - 1 + i, yy = fy0 - 1 + j;
            int xi = xx < 0 ? 0 : xx > t->nx - 1 ? t->nx - 1 : (int)xx;
            int yi = yy < 0 ? 0 : yy > t->ny - 1 ? t->ny - 1 : (int)yy;
            idx[j * 4 + i] = (size_t)yi * t->nx + (size_t)xi;
            wt[j * 4 + i] = wx[i] * wy[j];
        }
#define BS(m, out)                                                                                 \
    do {                                                                                           \
        double acc_ = 0;                                                                           \
        for (int q_ = 0; q_ < 16; q_++) acc_ += wt[q_] * (double)(m)[idx[q_]];                     \
        (out) = acc_;                                                                              \
    } while (0)
    BS(t->epithelium, s->e);
    BS(t->capillary, s->cap);
    BS(t->oxygen, s->oxy);
    BS(t->plasma, s->plasma);
    BS(t->scab_mm, s->scab);
    BS(t->scar, s->scar);
    BS(t->keloid_mm, s->keloid);
    BS(t->elevation_mm, s->elev);
    BS(t->depth_mm, s->depth);
    {
        double acc = 0, ws = 0;
        for (int q = 0; q < 16; q++)
            if (t->age_days[idx[q]] < SS_WOUND_AGE_INTACT)
                acc += wt[q] * (double)t->age_days[idx[q]], ws += wt[q];
        s->age = ws > 1e-12 ? acc / ws : (double)SS_WOUND_AGE_INTACT;
        s->wounded = ws;
    }
    BS(em->crust_in, s->crust_in);
    BS(em->keloid_in, s->keloid_in);
    BS(em->wound_in, s->wound_in);
    BS(em->open_in, s->open_in);
#undef BS
}

static void sample_tissue(const ss_wound_tissue *t, const edge_maps *em, double mx, double my,
                          texel_tissue *s) {
    if (mx < 0) mx = 0;
    if (my < 0) my = 0;
    if (mx > t->nx - 1) mx = t->nx - 1;
    if (my > t->ny - 1) my = t->ny - 1;
    int x0 = (int)mx, y0 = (int)my;
    int x1 = x0 + 1 < t->nx ? x0 + 1 : x0, y1 = y0 + 1 < t->ny ? y0 + 1 : y0;
    double fx = mx - x0, fy = my - y0;
    size_t i00 = (size_t)y0 * t->nx + x0, i01 = (size_t)y0 * t->nx + x1,
           i10 = (size_t)y1 * t->nx + x0, i11 = (size_t)y1 * t->nx + x1;
#define BL(m)                                                                                      \
    ((1 - fy) * ((1 - fx) * (double)(m)[i00] + fx * (double)(m)[i01]) +                            \
     fy * ((1 - fx) * (double)(m)[i10] + fx * (double)(m)[i11]))
    s->e = BL(t->epithelium);
    s->cap = BL(t->capillary);
    s->oxy = BL(t->oxygen);
    s->plasma = BL(t->plasma);
    s->scab = BL(t->scab_mm);
    s->scar = BL(t->scar);
    s->keloid = BL(t->keloid_mm);
    s->elev = BL(t->elevation_mm);
    s->depth = BL(t->depth_mm);
    { /* the mean age of the wounded columns only (module comment) */
        const size_t ix[4] = {i00, i01, i10, i11};
        const double wq[4] = {(1 - fy) * (1 - fx), (1 - fy) * fx, fy * (1 - fx), fy * fx};
        double acc = 0, ws = 0;
        for (int q = 0; q < 4; q++)
            if (t->age_days[ix[q]] < SS_WOUND_AGE_INTACT)
                acc += wq[q] * (double)t->age_days[ix[q]], ws += wq[q];
        s->age = ws > 1e-12 ? acc / ws : (double)SS_WOUND_AGE_INTACT;
        s->wounded = ws;
    }
    s->crust_in = BL(em->crust_in);
    s->keloid_in = BL(em->keloid_in);
    s->wound_in = BL(em->wound_in);
    s->open_in = BL(em->open_in);
#undef BL
}

/* 1 when sampled tissue is intact skin (the thresholds of column_healthy). */
static int tissue_intact(const texel_tissue *s) {
    return s->e >= 0.999 && fabs(s->cap - 1) < 1e-3 && fabs(s->oxy - 1) < 1e-3 &&
           s->plasma < 1e-3 && s->scab < 1e-4 && s->scar < 1e-4 && s->keloid <= 0 &&
           s->depth < 1e-4 && s->age >= SS_WOUND_AGE_INTACT;
}

/* 1 when a column is healthy skin: the mapping is the identity there. */
static int column_healthy(const ss_wound_tissue *t, size_t i) {
    return t->epithelium[i] >= 0.999f && fabsf(t->capillary[i] - 1) < 1e-3f &&
           fabsf(t->oxygen[i] - 1) < 1e-3f && t->plasma[i] < 1e-3f && t->scab_mm[i] < 1e-4f &&
           t->scar[i] < 1e-4f && t->keloid_mm[i] <= 0 && t->depth_mm[i] < 1e-4f &&
           t->age_days[i] >= SS_WOUND_AGE_INTACT;
}

typedef struct texel_out {
    double rgb[3], roughness, height_mm;
} texel_out;

/* The crust's, the bed's and the keloid's noises at a texel (0..1); trunk
 * and branch are the keloid's vessels' coverage of the texel (vessel_line). */
typedef struct crust_noise {
    float thick, mottle, crack, cap, grain;
    float trunk, branch, nodule;
} crust_noise;

/* The coverage of a texel by a line of width_mm along the mid-level line of
 * a noise (0..1): the distance to the line is |n - 0.5| / |grad n| in mm
 * (central differences), so the width is in mm, not in noise values nor
 * texels; where a texel is wider than the line, the line is drawn one texel
 * wide at width / texel of the strength (its area kept: the same look at
 * 256, 512 and 1024 texels for the same world size). */
static double vessel_line(const ss_image *noise, int x, int y, double texel_mm, double width_mm) {
    const int w = noise->width, h = noise->height;
    const float *d = noise->data;
    int x0 = x > 0 ? x - 1 : x, x1 = x < w - 1 ? x + 1 : x;
    int y0 = y > 0 ? y - 1 : y, y1 = y < h - 1 ? y + 1 : y;
    double gx = (d[(size_t)y * w + x1] - d[(size_t)y * w + x0]) / ((x1 - x0) * texel_mm);
    double gy = (d[(size_t)y1 * w + x] - d[(size_t)y0 * w + x]) / ((y1 - y0) * texel_mm);
    double g = hypot(gx, gy);
    if (!(g > 1e-9)) return 0;
    double dist = fabs(d[(size_t)y * w + x] - 0.5) / g;
    double half = 0.5 * width_mm, eff = fmax(half, 0.5 * texel_mm);
    double f = 1 - dist / eff;
    return f > 0 ? f * f * (3 - 2 * f) * (half / eff) : 0;
}

/* The keloid at a texel, as tissue (docs/wound.md, row keloid): its look
 * kel from its swelling, and under it a structure from the healing model's
 * own fields. A keloid grows at its edge and matures from within (Bayat,
 * McGrouther & Ferguson 2003, BMJ 326: 88; Ogawa 2017, Int. J. Mol. Sci. 18:
 * 606): its margin active, erythematous (keloid_blood), its centre, where
 * the wound closed longest ago, more fibrous and paler (the blood down to
 * keloid_centre_blood of it, the scar's whitening back) as it matures over
 * keloid_maturation; the tissue it spread over beyond the wound (never open:
 * no age) counts as margin. Over all of it dilated, arborizing telangiectatic
 * vessels (the dermoscopy of keloids: linear and branching vessels on a pink
 * to red background) as blood in lines of physical width; its raise uneven
 * (nodules at ~4 mm), smoother where it matured. */
typedef struct keloid_tissue {
    double kel;     /* how much keloid the texel shows (0..1) */
    double mature;  /* its centre's maturity: fibrous, paler (0..1) */
    double vessels; /* the vessels' coverage (0..1) */
    double blood, oxygenation;
    double raise; /* factor of the raise: the nodules */
} keloid_tissue;

static void keloid_structure(const double *v, const texel_tissue *s, const crust_noise *nz,
                             keloid_tissue *k) {
    k->kel = 1 - exp(-s->keloid / v[SS_WR_KELOID_LOOK_MM]);
    double centre = 1 - exp(-fmin(s->keloid_in, s->wound_in) / v[SS_WR_KELOID_MARGIN_MM]);
    double age = s->age < SS_WOUND_AGE_INTACT ? s->age : 0;
    k->mature = centre * (1 - exp(-age / v[SS_WR_KELOID_MATURE_DAYS]));
    k->vessels = v[SS_WR_KELOID_VESSELS] * k->kel * fmax(nz->trunk, nz->branch);
    k->blood = lerp(v[SS_WR_KELOID_BLOOD] * lerp(1, v[SS_WR_KELOID_CENTRE_BLOOD], k->mature),
                    VESSEL_BLOOD, k->vessels);
    k->oxygenation = lerp(v[SS_WR_KELOID_OXYGENATION], VESSEL_OXYGENATION, k->vessels);
    /* the nodules only lower it: its highest point stays heal's elevation */
    k->raise = 1 - v[SS_WR_KELOID_NODULES] * (1 - 0.5 * k->mature) * nz->nodule;
}

static void render_texel(const ss_wound_renderer *r, ss_skin_lut_cache *lc, const float *skin,
                         const crust_noise *nz, const texel_tissue *s, double day, texel_out *o) {
    const double *v = r->o.recipe.v;
    double reg = ramp(s->plasma, v[SS_WR_REGION_LO], v[SS_WR_REGION_HI]);
    /* the open bed, one mask from one distance field: its coverage bed rises
     * over BED_EDGE_MM across the contour of the open columns (open x region
     * >= 0.5 there), the same width in mm at every texture size; the exposed
     * dermis (no epidermis, no melanin: 1 - cover) and everything laid
     * on the bed (the clot, its blood, wetness: open x reg = bed, the open
     * bed being wound region) follow it. Before, cover came from the
     * epithelium and the clot's coverage from epithelium x region, two ramps
     * of two bilinear fields: where the one had fallen and the other not yet
     * risen, a 1-2 texel rim of pale-pink dermis showed round the clot on
     * dark skin */
    double bed = ramp(s->open_in, -0.5 * BED_EDGE_MM, 0.5 * BED_EDGE_MM);
    /* the dermis is bared under the clot's inner half of the edge only: the
     * table's colour of a half-bared dermis (half the melanin) is lighter
     * than both the skin and the clot, so bared where the clot covered less
     * than half it drew a faint light line (L* +4 on dark skin) */
    double cover = 1 - ramp(s->open_in, 0, 0.5 * BED_EDGE_MM);
    reg = fmax(reg, bed);
    double open = reg > 0 ? bed / reg : 0;
    /* the epidermis that was destroyed and grew back: the region where it was
     * ever open. Where the region spread over skin that never opened (a
     * keloid growing beyond the wound) the epidermis is the skin's own, and
     * its age is no age at all (SS_WOUND_AGE_INTACT): counted as a matured
     * scar it drew a hypopigmented, whitened rim around the keloid */
    double regrown = reg * s->wounded;
    double m_scar = 1 - exp(-s->age / v[SS_WR_SCAR_DAYS]);
    double m_epi = 1 - exp(-s->age / v[SS_WR_EPIDERMIS_DAYS]);
    double scar = ramp(s->scar, 0, v[SS_WR_SCAR_DENSITY_HI]);
    float b[SS_BIO_NCHANNELS] = {0}, k[SS_BIO_NCHANNELS];
    for (int c = 0; c < SS_BIO_NCHANNELS; c++) k[c] = (float)lerp(skin[c], r->mean[c], reg);
    /* keloid tissue: hypervascular, hypoxic, often hyperpigmented, with an
     * active margin, a maturing centre and vessels (keloid_structure) */
    keloid_tissue kt;
    keloid_structure(v, s, nz, &kt);
    const double kel = kt.kel;
    /* post-inflammatory hyperpigmentation: the course shared with abrasion
     * (ss_pih_melanin_factor: rises over two weeks after closure, fades over
     * months), as strong as the skin type's clinical rate */
    double pih = ss_wound_renderer_pih_factor(r, s->age) - 1;
    /* both patchy, not one flat colour: PIH in macules (+-PATCHY at ~1.5 mm),
     * the young tissue's redness in blotches (at ~2 mm) */
    pih *= 1 + PATCHY * (2.0 * nz->thick - 1);
    /* the regrown epidermis's melanin: the repigmentation shared with
     * abrasion (ss_repigmentation_factor: melanin-poor at closure, back within
     * weeks, a little lighter in the mature scar) times the PIH */
    const ss_repigmentation repig = recipe_repigmentation(v);
    double mel = k[SS_BIO_MELANIN] * cover *
                 lerp(1, ss_repigmentation_factor(&repig, s->age) * (1 + pih), regrown) *
                 lerp(1, v[SS_WR_KELOID_MELANIN], kel);
    double epi = lerp(
        EPI_FLOOR_CM,
        k[SS_BIO_EPIDERMIS_CM] * lerp(1, lerp(v[SS_WR_NEW_EPIDERMIS], 1, m_epi), regrown), cover);
    double sc = lerp(SC_FLOOR_CM, k[SS_BIO_SC_CM], cover * lerp(1, m_epi, regrown));
    /* over the keloid's vessels the stretched epidermis is thinnest: they
     * lie in the papillary dermis right under it */
    epi *= 1 - 0.25 * kt.vessels;
    double cap = s->cap < 0 ? 0 : s->cap;
    /* freshly closed tissue: the tissue ss_bio_new_epithelium describes
     * (src/optics/healing.c, as `abrasion` draws it) through the recipe's
     * knobs, whose defaults are its constants: new_epidermis
     * (SS_NEW_EPIDERMIS_FRACTION), its dermis hyperaemic (young_blood,
     * SS_YOUNG_DERMIS_BLOOD, at SS_YOUNG_DERMIS_OXYGENATION), fading as the
     * scar matures */
    double young = reg * cover * (1 - m_scar);
    double tissue_blood =
        lerp(k[SS_BIO_BLOOD] * cap * lerp(1, v[SS_WR_SCAR_BLOOD], reg * scar * m_scar),
             v[SS_WR_YOUNG_BLOOD] * (1 + PATCHY * (2.0 * nz->mottle - 1)), young);
    tissue_blood = lerp(tissue_blood, kt.blood, kel * cover);
    /* the open bed: granulation tissue, as vascular as the healing model's new
     * capillaries (none in the freshly exposed, torn dermis of day 0: the
     * punctate bleeding there is the clot's), its capillary loops (dots at
     * ~0.35 mm) holding more blood */
    double bedtex = v[SS_WR_BED_TEXTURE] * open * reg;
    double dots = ramp(nz->cap, 0.55, 0.85);
    double bed_blood = lerp(k[SS_BIO_BLOOD], v[SS_WR_BED_BLOOD], clamp01(cap)) *
                       (1 + bedtex * LOOP_CONTRAST * (dots - 1.0 / 6));
    /* the bed's blood beyond the table's largest fraction is not clamped
     * away: it sits in the capillary loops of the top loop_depth (granulation
     * tissue's loops reach to ~0.1-0.3 mm under its surface), drawn by the
     * bed's spectra (bed_spectrum.c: the transport of a bed whose top
     * loop_depth holds that blood, under the factor that gives the table's
     * colour at the cap). Laid over the open part (open x reg) as coverage,
     * as the clot: a blood fading with open x reg reddened the rim within a
     * texel (a stepped edge) */
    double loops = bed_blood > r->blood_cap ? fmin(bed_blood, 1) : 0;
    double blood = lerp(tissue_blood, fmin(bed_blood, r->blood_cap), open * reg);
    /* blood under cover follows the tissue's oxygen; blood in the open bed is
     * oxygenated by the air (atmospheric O2 reaches ~0.3 mm deep) */
    double oxy =
        lerp(lerp(v[SS_WR_TISSUE_MIN_OXYGENATION],
                  lerp(k[SS_BIO_OXYGENATION], SS_YOUNG_DERMIS_OXYGENATION, young), clamp01(s->oxy)),
             v[SS_WR_BED_OXYGENATION], open * reg);
    oxy = lerp(oxy, kt.oxygenation, kel * cover);
    b[SS_BIO_MELANIN] = (float)(mel > MELANIN_FLOOR ? mel : MELANIN_FLOOR);
    b[SS_BIO_PHEOMELANIN] = k[SS_BIO_PHEOMELANIN];
    b[SS_BIO_BLOOD] = (float)clamp01(blood);
    b[SS_BIO_OXYGENATION] = (float)clamp01(oxy);
    b[SS_BIO_SC_CM] = (float)sc;
    b[SS_BIO_EPIDERMIS_CM] = (float)epi;
    lookup5 l;
    bio_to_render(r->lut, lc, b, &l);
    /* dense mature collagen scatters more: a lift of the albedo towards a
     * white dermis seen through this texel's own epidermis. Its filter is the
     * table's: the bloodless albedo with this melanin over the one without
     * melanin (the melanin's two passes), so the lift is near white on light
     * skin and a moderate lightening at the skin's own brown on melanin-rich
     * skin (a lift to the skin's hue at full brightness, as before, drew a
     * bright orange scar there). Only where the epidermis regrew: skin the
     * region spread over was never a scar maturing since closure. */
    double white =
        v[SS_WR_SCAR_WHITENING] * regrown * scar * m_scar * cover * (1 - kel * (1 - kt.mature));
    double skin_rgb[3] = {l.rgb[0], l.rgb[1], l.rgb[2]};
    double R[3], T[3], R2[3], T2[3], R3[3], T3[3], mid[3];
    /* the bed per wavelength (bed_spectrum.c): the spectrum standing for the
     * table's colour, its loops' blood, then the clot and the exudate on it
     * (spec: A holds skin_rgb's spectrum) */
    double A[SS_LAYER_NWL], A1[SS_LAYER_NWL], q[3];
    int spec = 0;
    if (loops > 0 && open * reg > 0 && (spec = ss_bed_fit(&r->bed, b[SS_BIO_BLOOD], l.rgb, q))) {
        ss_bed_eval(&r->bed, b[SS_BIO_BLOOD], q, A);
        ss_bed_eval(&r->bed, loops, q, A1);
        for (int w = 0; w < SS_LAYER_NWL; w++) A[w] = lerp(A[w], A1[w], open * reg);
        ss_bed_spectra_to_rgb(&r->bed, A, mid);
        for (int c = 0; c < 3; c++) skin_rgb[c] = l.rgb[c] = mid[c];
    } /* (no factor: the bed's spectra reflect nothing; no blood shows) */
    if (white > 0) {
        spec = 0; /* skin_rgb changes below */
        float bw[SS_BIO_NCHANNELS];
        memcpy(bw, b, sizeof bw);
        bw[SS_BIO_BLOOD] = 0;
        lookup5 with, without;
        bio_to_render(r->lut, lc, bw, &with);
        bw[SS_BIO_MELANIN] = (float)MELANIN_FLOOR;
        bio_to_render(r->lut, lc, bw, &without);
        for (int c = 0; c < 3; c++) {
            double filt = without.rgb[c] > 1e-6 ? clamp01(with.rgb[c] / without.rgb[c]) : 1;
            skin_rgb[c] = clamp01(l.rgb[c] + white * (filt - l.rgb[c]));
        }
    }
    /* the crust: thin at its edge, full from scab_dome inwards; its thickness
     * mottled (+-scab_mottle at ~1.5 mm) */
    double dome = lerp(v[SS_WR_SCAB_EDGE], 1, 1 - exp(-s->crust_in / v[SS_WR_SCAB_DOME_MM]));
    double thick =
        s->scab * v[SS_WR_SCAB_SCALE] * dome *
        (1 + v[SS_WR_SCAB_MOTTLE] * (2.0 * nz->thick - 1) + CRUST_GRAIN * (2.0 * nz->grain - 1));
    if (thick < 0) thick = 0;
    /* drying: a fresh crust is wet, red blood; it darkens to the aged crust
     * (deoxygenated, concentrated) and turns matte over crust_dry_days */
    double dry = 1 - exp(-day / v[SS_WR_CRUST_DRY_DAYS]);
    /* cracks along the mid-level lines of a noise, where the dried crust
     * shrinks: across the crust, the more the nearer its edge; a fissure is a
     * groove in the height and a shadow, not the bed showing through */
    double crack = v[SS_WR_CRACK_WIDTH] > 0
                       ? (1 - ramp(fabs(nz->crack - 0.5), 0, v[SS_WR_CRACK_WIDTH])) *
                             lerp(0.45, 1, exp(-s->crust_in / v[SS_WR_CRACK_REACH_MM])) * dry
                       : 0;
    /* the crust's edge as coverage, not as thickness: the layer's colour
     * saturates within microns of blood, so a thickness that fades across
     * the edge gave a one-texel step (and an orange rim); instead the crust
     * covers a fraction of the texel that rises over EDGE_MM from its edge
     * (crust_in, sampled smoothly), the same width in mm at any size */
    double edge_c = ramp(s->crust_in, 0.02, EDGE_MM);
    double scab_cover = (1 - exp(-thick / 0.05)) * edge_c; /* a 0.05 mm crust hides the bed */
    crack *= scab_cover;
    /* patches of serous (haemoglobin-poor, amber) crust among the bloody one */
    double serous =
        v[SS_WR_SCAB_SEROUS] * ramp(nz->mottle + CRUST_GRAIN * (nz->grain - 0.5), 0.5, 0.8);
    /* and granules of serum through the bloody crust */
    serous = 1 - (1 - serous) * (1 - v[SS_WR_SCAB_SEROUS] * 0.15 * ramp(nz->grain, 0.5, 0.9));
    /* the clot: fresh blood in the open, avascular bed, pooled in patches and
     * at the capillary loops, at most 0.25 mm (a scrape oozes, it does not
     * fill with blood); exudate: serum and fibrin glazing the bed from the
     * first day (yellow patches) */
    double room = s->depth - s->scab > 0 ? s->depth - s->scab : 0;
    double pool = lerp(1, POOL_FILM + (1 - POOL_FILM) * ramp(nz->mottle, 0.3, 0.75) + 0.3 * dots,
                       fmin(1, v[SS_WR_BED_TEXTURE]));
    /* the clot's full thickness, laid over the open part (open x reg) as
     * coverage: a thickness fading with open x reg saturated to blood red
     * within a texel of the wound's edge (a hard, stepped edge) */
    double clot_full = fmin(room, CLOT_MAX_MM) * v[SS_WR_CLOT_SCALE] * pool, a_clot = open * reg;
    double clot = a_clot * clot_full;
    double exudate = bedtex * 0.04 * ramp(nz->thick, 0.45, 0.8) * (1 - exp(-day / 1.0));
    int clotted = clot_full > 0 && a_clot > 0, wet = clotted || exudate > 0;
    if (wet && !spec && (spec = ss_bed_fit(&r->bed, b[SS_BIO_BLOOD], skin_rgb, q)))
        ss_bed_eval(&r->bed, b[SS_BIO_BLOOD], q, A);
    if (wet && spec) {
        if (clotted) {
            ss_layer_add_wl(&r->clot, clot_full, A, A1);
            for (int w = 0; w < SS_LAYER_NWL; w++) A[w] = lerp(A[w], A1[w], a_clot);
        }
        if (exudate > 0) ss_layer_add_wl(&r->serous, exudate, A, A);
        ss_bed_spectra_to_rgb(&r->bed, A, mid);
    } else { /* none, or no spectrum for this colour: in RGB (bare: mid = skin_rgb) */
        ss_layer_table_eval(&r->clot, clot_full, R, T);
        ss_layer_over(R, T, skin_rgb, mid);
        for (int c = 0; c < 3; c++) mid[c] = lerp(skin_rgb[c], mid[c], a_clot);
        ss_layer_table_eval(&r->serous, exudate, R, T);
        ss_layer_over(R, T, mid, mid);
    }
    /* the crust: the fresh one as whole blood of the same haemoglobin per
     * area (hb_factor x the thickness), the aged one the dried-blood layer */
    ss_layer_table_eval(&r->clot, thick * v[SS_WR_SCAB_HB_FACTOR], R3, T3);
    ss_layer_table_eval(&r->scab, thick, R, T);
    ss_layer_table_eval(&r->serous, thick, R2, T2);
    for (int c = 0; c < 3; c++) {
        R[c] = lerp(R[c], R2[c], serous), T[c] = lerp(T[c], T2[c], serous);
        R[c] = lerp(R3[c], R[c], dry), T[c] = lerp(T3[c], T[c], dry);
    }
    ss_layer_over(R, T, mid, o->rgb);
    /* the edge lifts where new epithelium has slid under it (Winter 1962):
     * raised, drier and paler, before it comes off; the cracks' shadow and
     * the lifted edge's pallor are the crust's own, so they apply before its
     * coverage (applied after, they brightened the skin beside a crust into
     * a white halo) */
    double lift = v[SS_WR_CRUST_LIFT_MM] > 0 ? cover * scab_cover * exp(-s->crust_in / 0.8) : 0;
    for (int c = 0; c < 3; c++)
        o->rgb[c] = lerp(mid[c], o->rgb[c] * (1 - 0.65 * crack) * (1 + 0.5 * lift), edge_c);
    /* the bio map's extra colour over everything, gone where the tissue was
     * destroyed (module comment: 0 in new maps, kept for given ones) */
    double ea = k[SS_BIO_EXTRA_A] * (1 - reg);
    for (int c = 0; c < 3; c++)
        o->rgb[c] = clamp01(clamp01(o->rgb[c]) * (1 - ea) + k[SS_BIO_EXTRA_R + c] * ea);
    double rough = l.roughness;
    /* the wet bed: a fluid film, smoother where fresh blood pools */
    rough =
        lerp(rough, v[SS_WR_WET_ROUGHNESS] * (0.75 + 0.5 * nz->mottle) * (1 - 0.3 * dots * bedtex),
             open * reg);
    rough = lerp(rough, v[SS_WR_SCAR_ROUGHNESS], reg * cover * m_epi * scar);
    rough = lerp(rough, v[SS_WR_KELOID_ROUGHNESS], kel * cover);
    rough = lerp(rough, lerp(0.4, v[SS_WR_SCAB_ROUGHNESS], dry) + 0.1 * crack, scab_cover);
    o->roughness = clamp01(rough);
    /* the keloid's raise: the healing model's surface elevation (collagen
     * beyond the dermis it replaced and the keloid's added volume, heal's
     * surface_elevation_mm) where it is raised - where it falls short, the
     * open wound's depth above already draws the defect. Taken as it is, not
     * saturated: the model itself bounds it (docs/heal-model.md [D16]), and
     * the height map's range follows the frame (ss_wound_height_range) */
    double keloid = v[SS_WR_KELOID_SCALE] * fmax(s->elev, 0.0) * kt.raise;
    /* the surface: the skin, down by the wound's depth, filled by the clot and
     * by the crust (which fills the defect and stands above the skin), the
     * bed's relief of capillary loops, the crust's cracks and lifted edge, and
     * the keloid's raise */
    double fill = fmax(scab_cover, 0.0);
    o->height_mm = k[SS_BIO_HEIGHT_MM] - v[SS_WR_DEPTH_SCALE] * s->depth * (1 - fill) + clot +
                   bedtex * 0.02 * (dots - 0.5) + thick * edge_c * (1 - 0.7 * crack) +
                   v[SS_WR_CRUST_LIFT_MM] * lift + keloid;
}

/* The keloid's vessels at texel (x, y): trunks, and branches near them, as
 * the coverage of lines of physical width (vessel_line). Only needed where
 * the keloid's field is non-zero: elsewhere keloid_structure's kel is 0 and
 * the vessels' coverage with it (the same values, two noise gradients
 * fewer per texel). */
static void keloid_vessels(const ss_wound_renderer *r, int x, int y, double texel_mm,
                           double vessel_mm, crust_noise *nz) {
    size_t i = (size_t)y * (size_t)r->o.size + (size_t)x;
    nz->trunk = (float)(vessel_line(r->vessel[0], x, y, texel_mm, vessel_mm) *
                        ramp(r->mottle->data[i], 0.3, 0.6));
    nz->branch = (float)(vessel_line(r->vessel[1], x, y, texel_mm, 0.5 * vessel_mm) *
                         (1 - ramp(fabs(r->vessel[0]->data[i] - 0.5), 0.03, 0.1)));
}

/* Per column: mm from the edge of a map's region inwards (0 outside it; the
 * region: map x scale >= threshold): the distance to the nearest column
 * outside, less half a column so that it is about 0 at the edge. For the
 * crust (scab_mm) and the keloid (keloid_mm). */
static ss_image *edge_depth(const ss_wound_tissue *t, const float *map, double scale,
                            double threshold, ss_error *err) {
    ss_image *no = ss_image_create(t->nx, t->ny, 1, err);
    ss_image *d = no ? ss_image_create(t->nx, t->ny, 1, err) : NULL;
    size_t n = (size_t)t->nx * (size_t)t->ny;
    for (size_t i = 0; d && i < n; i++) no->data[i] = map[i] * scale < threshold ? 1.f : 0.f;
    if (d && ss_distance_transform(no, d, err)) ss_image_free(d), d = NULL;
    for (size_t i = 0; d && i < n; i++) {
        double mm = isfinite(d->data[i]) ? (d->data[i] - 0.5) * t->dx_mm : 1e3;
        d->data[i] = (float)(mm > 0 ? mm : 0);
    }
    ss_image_free(no);
    return d;
}

/* Per column: the signed mm from the edge of a map's region (map >=
 * threshold), positive inside, negative outside, about 0 halfway between
 * the last column in and the first out; +-1e3 where there is no edge. */
static ss_image *signed_edge_depth(const ss_wound_tissue *t, const float *map, double threshold,
                                   ss_error *err) {
    ss_image *in = edge_depth(t, map, 1.0, threshold, err);
    size_t n = (size_t)t->nx * (size_t)t->ny;
    float *flip = in ? calloc(n ? n : 1, sizeof *flip) : NULL;
    for (size_t i = 0; flip && i < n; i++) flip[i] = map[i] >= threshold ? 0.f : 1.f;
    ss_image *out = flip ? edge_depth(t, flip, 1.0, 0.5, err) : NULL;
    if (in && !flip) ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    free(flip);
    for (size_t i = 0; out && i < n; i++)
        in->data[i] = map[i] >= threshold ? in->data[i] : -out->data[i];
    ss_image_free(out);
    if (!out) ss_image_free(in), in = NULL;
    return in;
}

ss_status ss_wound_render(ss_wound_renderer *r, const ss_wound_tissue *t,
                          const ss_image *deformation, ss_wound_textures *out, ss_error *err) {
    return ss_wound_render_poll(r, t, deformation, out, NULL, NULL, err);
}

ss_status ss_wound_render_poll(ss_wound_renderer *r, const ss_wound_tissue *t,
                               const ss_image *deformation, ss_wound_textures *out,
                               ss_progress_fn fn, void *user, ss_error *err) {
    const int n = r->o.size;
    if (!out->base_color || out->base_color->width != n || !out->roughness || !out->height ||
        !out->normal)
        return ss_error_set(err, SS_ERR_INPUT, "wound render: textures must be %dx%d", n, n);
    if (deformation &&
        (deformation->width != n || deformation->height != n || deformation->channels != 3))
        return ss_error_set(err, SS_ERR_INPUT, "wound render: deformation must be %dx%d x 3", n, n);
    if (deformation && r->columns)
        return ss_error_set(err, SS_ERR_INPUT,
                            "wound render: no deformation on a mesh's UV layout (yet)");
    /* per column: healthy (identity mapping) */
    size_t ncol = (size_t)t->nx * (size_t)t->ny;
    uint8_t *healthy = malloc(ncol);
    if (!healthy) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < ncol; i++) healthy[i] = (uint8_t)column_healthy(t, i);
    ss_image *crust_in = edge_depth(t, t->scab_mm, r->o.recipe.v[SS_WR_SCAB_SCALE], 0.01, err);
    ss_image *keloid_in =
        crust_in ? edge_depth(t, t->keloid_mm, 1.0,
                              KELOID_EDGE_FRACTION * r->o.recipe.v[SS_WR_KELOID_LOOK_MM], err)
                 : NULL;
    if (!keloid_in) {
        free(healthy);
        ss_image_free(crust_in);
        return err->code ? err->code : SS_ERR_NOMEM;
    }
    /* the columns that were ever open: their age is not the intact sentinel */
    float *opened = calloc(ncol ? ncol : 1, sizeof *opened);
    for (size_t i = 0; opened && i < ncol; i++)
        opened[i] = t->age_days[i] < SS_WOUND_AGE_INTACT ? 1.f : 0.f;
    ss_image *wound_in = opened ? edge_depth(t, opened, 1.0, 0.5, err) : NULL;
    /* the open bed's columns: open x region (the ramps of the epithelium and
     * the plasma), its edge as one signed distance */
    const double *rv = r->o.recipe.v;
    for (size_t i = 0; wound_in && i < ncol; i++)
        opened[i] =
            (float)((1 - ramp(t->epithelium[i], rv[SS_WR_EPITHELIUM_LO], rv[SS_WR_EPITHELIUM_HI])) *
                    ramp(t->plasma[i], rv[SS_WR_REGION_LO], rv[SS_WR_REGION_HI]));
    ss_image *open_in = wound_in ? signed_edge_depth(t, opened, 0.5, err) : NULL;
    free(opened);
    if (!open_in) {
        free(healthy);
        ss_image_free(crust_in);
        ss_image_free(keloid_in);
        ss_image_free(wound_in);
        return err->code ? err->code : ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    const edge_maps em = {crust_in->data, keloid_in->data, wound_in->data, open_in->data};
    const double texel_mm = r->o.side_mm / n, vessel_mm = r->o.recipe.v[SS_WR_KELOID_VESSEL_MM];
    const double side_x = t->nx * t->dx_mm, side_y = t->ny * t->dx_mm;
    /* the jitter's noise (0.6 mm) needs a few texels per period; where the
     * texels are coarser (a mesh's UV layout at 1024: 0.33 mm) it would
     * jump from texel to texel (a jagged rim with isolated texels), so it
     * fades out: full from WARP_FULL_PX texels per period, none at 2 */
    const double warp_px = WARP_PERIOD_MM * n / r->o.side_mm;
    const double warp_amp = WARP_COLUMNS * clamp01((warp_px - 2.0) / (WARP_FULL_PX - 2.0));
    /* on a mesh: the box's half width in columns, and its reach in whole columns */
    const double box_h = 0.5 * EDGE_BOX_MM / t->dx_mm;
    const int box_r = (int)ceil(box_h);
    /* with a progress callback the rows go in bands, polled between them
     * (each texel is a function of its own position only, so the bands
     * change no value) */
    const int band = fn ? (n / 32 > 64 ? n / 32 : 64) : n;
    int cancelled = 0;
    /* a table-lookup cache per thread (neighbouring texels share cells; the
     * values are the uncached lookup's: a thread without one looks up
     * uncached) */
    const int nthreads = omp_get_max_threads();
    ss_skin_lut_cache **caches = calloc((size_t)nthreads, sizeof *caches);
    for (int k = 0; caches && k < nthreads; k++) caches[k] = ss_skin_lut_cache_create();
    for (int yb = 0; yb < n && !cancelled; yb += band) {
        const int ye = n - yb > band ? yb + band : n;
#pragma omp parallel for schedule(dynamic, 8)
        for (int y = yb; y < ye; y++) {
            ss_skin_lut_cache *lc = caches ? caches[omp_get_thread_num()] : NULL;
            for (int x = 0; x < n; x++) {
                size_t i = (size_t)y * (size_t)n + (size_t)x;
                double u = (x + 0.5) / n, vv = (y + 0.5) / n, dz = 0;
                if (deformation) { /* the material point now sits displaced: sample there */
                    const float *d = deformation->data + i * 3;
                    u += d[0] / side_x;
                    vv -= d[1] / side_y;
                    dz = d[2];
                }
                double mx = u * t->nx - 0.5, my = vv * t->ny - 0.5;
                int off = 0; /* on a mesh: the texel shows no skin of the patch */
                if (r->columns) {
                    const float *cm = r->columns->data + i * 2;
                    off = !(cm[0] == cm[0]);
                    mx = cm[0], my = cm[1];
                }
                /* +-WARP_COLUMNS of a column, so a margin follows no voxel staircase */
                mx += warp_amp * (2.0 * r->warp[0]->data[i] - 1);
                my += warp_amp * (2.0 * r->warp[1]->data[i] - 1);
                if (off) mx = my = 0;
                double cx = mx < 0 ? 0 : mx > t->nx - 1 ? t->nx - 1 : mx;
                double cy = my < 0 ? 0 : my > t->ny - 1 ? t->ny - 1 : my;
                int x0 = (int)cx, y0 = (int)cy;
                int x1 = x0 + 1 < t->nx ? x0 + 1 : x0, y1 = y0 + 1 < t->ny ? y0 + 1 : y0;
                int base = off;
                if (!base && r->columns) { /* the B-spline's 4 x 4 columns, over the box */
                    base = 1;
                    for (int jj = y0 - 1 - box_r; jj <= y0 + 2 + box_r && base; jj++)
                        for (int ii = x0 - 1 - box_r; ii <= x0 + 2 + box_r && base; ii++) {
                            int a = ii < 0 ? 0 : ii > t->nx - 1 ? t->nx - 1 : ii;
                            int b = jj < 0 ? 0 : jj > t->ny - 1 ? t->ny - 1 : jj;
                            base = healthy[(size_t)b * t->nx + a];
                        }
                } else if (!base)
                    base = healthy[(size_t)y0 * t->nx + x0] && healthy[(size_t)y0 * t->nx + x1] &&
                           healthy[(size_t)y1 * t->nx + x0] && healthy[(size_t)y1 * t->nx + x1];
                if (base) {
                    for (int c = 0; c < 3; c++)
                        out->base_color->data[i * 3 + c] = r->base.base_color->data[i * 3 + c];
                    out->roughness->data[i] = r->base.roughness->data[i];
                    out->height->data[i] = r->base.height->data[i] + (float)dz;
                    continue;
                }
                texel_tissue s;
                texel_out o;
                crust_noise nz = {r->crust->data[i],
                                  r->mottle->data[i],
                                  r->crack->data[i],
                                  r->cap->data[i],
                                  r->grain->data[i],
                                  0,
                                  0,
                                  r->nodule->data[i]};
                /* the keloid's vessels only where a sample has keloid (elsewhere
                 * kel is 0 and so is their coverage: the same values) */
                int vessels_done = 0;
                if (r->columns) { /* the mean over a box of EDGE_BOX_MM (module comment) */
                    o = (texel_out){{0, 0, 0}, 0, 0};
                    for (int q = 0; q < BOX_N * BOX_N; q++) {
                        double ox = box_h * ((2 * (q % BOX_N) + 1.0) / BOX_N - 1),
                               oy = box_h * ((2 * (q / BOX_N) + 1.0) / BOX_N - 1);
                        double sx = cx + ox, sy = cy + oy;
                        sx = sx < 0 ? 0 : sx > t->nx - 1 ? t->nx - 1 : sx;
                        sy = sy < 0 ? 0 : sy > t->ny - 1 ? t->ny - 1 : sy;
                        texel_out os;
                        sample_tissue_smooth(t, &em, sx, sy, &s);
                        if (s.keloid > 0 && !vessels_done)
                            keloid_vessels(r, x, y, texel_mm, vessel_mm, &nz), vessels_done = 1;
                        if (tissue_intact(&s)) { /* the base skin itself: no seam at the rim */
                            for (int c = 0; c < 3; c++)
                                os.rgb[c] = r->base.base_color->data[i * 3 + c];
                            os.roughness = r->base.roughness->data[i];
                            os.height_mm = r->base.height->data[i];
                        } else
                            render_texel(r, lc, r->skin->data + i * SS_BIO_NCHANNELS, &nz, &s,
                                         t->day, &os);
                        for (int c = 0; c < 3; c++) o.rgb[c] += os.rgb[c] / (BOX_N * BOX_N);
                        o.roughness += os.roughness / (BOX_N * BOX_N);
                        o.height_mm += os.height_mm / (BOX_N * BOX_N);
                    }
                } else {
                    sample_tissue(t, &em, mx, my, &s);
                    if (s.keloid > 0) keloid_vessels(r, x, y, texel_mm, vessel_mm, &nz);
                    render_texel(r, lc, r->skin->data + i * SS_BIO_NCHANNELS, &nz, &s, t->day, &o);
                }
                for (int c = 0; c < 3; c++) out->base_color->data[i * 3 + c] = (float)o.rgb[c];
                out->roughness->data[i] = (float)o.roughness;
                out->height->data[i] = (float)(o.height_mm + dz);
            }
        }
        if (fn && fn(user, 0.95 * ye / n)) cancelled = 1;
    }
    for (int k = 0; caches && k < nthreads; k++) ss_skin_lut_cache_free(caches[k]);
    free(caches);
    free(healthy);
    ss_image_free(crust_in);
    ss_image_free(keloid_in);
    ss_image_free(wound_in);
    ss_image_free(open_in);
    if (cancelled) return ss_error_set(err, SS_ERR_RUNTIME, "wound render: cancelled");
    /* height in mm -> normal: slope per texel times texels per mm */
    ss_height_to_normal(out->height, (float)(n / r->o.side_mm), out->normal);
    if (fn) fn(user, 1.0); /* done: a stop now changes nothing */
    return SS_OK;
}
