/* The five abrasion key positions of seed 000 §4.3, with the seed's colours,
 * noise parameters, gradient thicknesses and blending equations (4.5-4.8,
 * Alg. 4.4). The seed blends in display (sRGB) space on GPU textures, so the
 * blending here also works on sRGB-encoded values and the result is decoded
 * to linear light once per pixel. Pixel quantities of the seed (gradient
 * thickness 100, erosion widths, noise periods) refer to a reference_px
 * texture and are scaled with the output size. Where the seed is silent
 * (reflection and height of some phases) the choice is documented in
 * docs/abrasion.md. */
#include "skinsim/abrasion.h"
#include "abrasion_internal.h"
#include "skinsim/texture.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Reflection and height where the seed gives none (docs/abrasion.md). */
static const float SKIN_REFLECTION = 0.25f;     /* healthy skin specular strength */
static const float RAW_WOUND_REFLECTION = 0.5f; /* fresh, wet wound bed */
static const float WOUND_DEPTH = 0.05f;         /* epidermis removed: 0.05 of the height range */
static const float SCRAPE_RELIEF = 0.02f;       /* depth of the scrape lines */
#define DEFAULT_MATURATION_DAYS 20.0 /* the default timeline's maturation span (days 10..30) */

/* Noise streams: one per noise texture, so each phase is reproducible alone. */
enum {
    ST_SCRAPE = 0x100,
    ST_SCABFORM_LOW,
    ST_SCABFORM_SPECKLE,
    ST_SCAB_MASK,
    ST_SCAB_MIDDLE,
    ST_SCAB_RED,
    ST_SCAB_REFLECT,
    ST_ERODE1,
    ST_ERODE2
};

void ss_abrasion_settings_default(ss_abrasion_settings *s) {
    s->size = 2048;
    s->world_size_cm = 10.0;
    s->reference_px = 2048.0;
    s->scab_height_mm = 0.5;
    s->seed = 1;
}

const char *ss_phase_name(ss_phase p) {
    static const char *names[SS_PHASE_COUNT] = {"vasoconstriction", "vasodilation", "scab_forming",
                                                "scab", "maturation"};
    return (unsigned)p < SS_PHASE_COUNT ? names[p] : "unknown";
}

int ss_phase_from_name(const char *name) {
    for (int p = 0; p < SS_PHASE_COUNT; p++)
        if (!strcmp(name, ss_phase_name((ss_phase)p))) return p;
    if (!strcmp(name, "scab-forming")) return SS_PHASE_SCAB_FORMING;
    return -1;
}

ss_status ss_texture_set_create(int size, ss_texture_set *t, ss_error *err) {
    memset(t, 0, sizeof *t);
    /* Renders and frames overwrite every pixel: no need to zero. */
    t->color = ss_image_create_uninit(size, size, 3, err);
    t->reflection = t->color ? ss_image_create_uninit(size, size, 1, err) : NULL;
    t->height = t->reflection ? ss_image_create_uninit(size, size, 1, err) : NULL;
    t->normal = t->height ? ss_image_create_uninit(size, size, 3, err) : NULL;
    if (!t->normal) {
        ss_texture_set_free(t);
        return err->code;
    }
    return SS_OK;
}

void ss_texture_set_free(ss_texture_set *t) {
    if (!t) return;
    ss_image_free(t->color);
    ss_image_free(t->reflection);
    ss_image_free(t->height);
    ss_image_free(t->normal);
    memset(t, 0, sizeof *t);
}

static inline float lum(const float *c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

/* Everything one render needs, resolved for the output size. */
typedef struct ctx {
    const ss_wound_shape *w;
    const ss_base_skin *skin;
    const ss_abrasion_settings *s;
    int n;
    size_t npx;
    float k;                      /* output pixels per reference pixel */
    int bx, by, bw, bh;           /* the wound's box: noise, erosion and normals are only
                                     needed there (outside, every phase is plain skin), so
                                     the cost grows with the wound, not the texture */
    int rx, ry, rw, rh;           /* the box grown by the glow: where any colour differs
                                     from healthy skin */
    const ss_abrasion_palette *P; /* the tissue colours (optics) */
    float px_per_mm;              /* texture pixels per mm on the body */
    float rim_px;                 /* width of the torn-epidermis rim: 0.35 mm */
    float lower_mean, upper_mean; /* mean luminance of the lower and upper skin in the box */
} ctx;

void ss_abrasion_changed_region(const ss_wound_shape *w, const ss_abrasion_settings *s, int *x,
                                int *y, int *width, int *height) {
    int n = s->size;
    int g = (int)ceilf((float)(SS_ABRASION_MAX_GRADIENT_REF_PX * s->size / s->reference_px)) + 2;
    *x = w->box_x - g < 0 ? 0 : w->box_x - g;
    *y = w->box_y - g < 0 ? 0 : w->box_y - g;
    *width = (w->box_x + w->box_w + g > n ? n : w->box_x + w->box_w + g) - *x;
    *height = (w->box_y + w->box_h + g > n ? n : w->box_y + w->box_h + g) - *y;
    if (w->box_w == 0) *width = *height = 0;
}

static void ctx_init(ctx *c, const ss_wound_shape *w, const ss_base_skin *skin,
                     const ss_abrasion_settings *s) {
    c->w = w;
    c->skin = skin;
    c->s = s;
    c->n = s->size;
    c->npx = (size_t)s->size * (size_t)s->size;
    c->k = (float)(s->size / s->reference_px);
    c->P = skin->palette;
    c->px_per_mm = (float)(s->size / (s->world_size_cm * 10.0));
    c->rim_px = fmaxf(1.0f, 0.35f * c->px_per_mm);
    c->bx = w->box_x;
    c->by = w->box_y;
    c->bw = w->box_w;
    c->bh = w->box_h;
    ss_abrasion_changed_region(w, s, &c->rx, &c->ry, &c->rw, &c->rh);
    double acc = 0, acc_up = 0;
    for (int y = c->by; y < c->by + c->bh; y++)
        for (int x = c->bx; x < c->bx + c->bw; x++) {
            size_t i = ((size_t)y * (size_t)c->n + (size_t)x) * 3;
            acc += lum(skin->lower->data + i);
            acc_up += lum(skin->upper->data + i);
        }
    double area = (double)c->bw * c->bh;
    c->lower_mean = c->bw > 0 && acc > 0 ? (float)(acc / area) : 1.0f;
    c->upper_mean = c->bw > 0 && acc_up > 0 ? (float)(acc_up / area) : 1.0f;
}

/* A value-noise texture over the wound's box only (noise is only read inside
 * the wound); index it with box_index. Same values as the whole texture. */
typedef struct noise_spec {
    int octaves;
    float persistence, bias, gain, stretch_y;
    uint64_t stream;
} noise_spec;
static ss_status noise(const ctx *c, const noise_spec *q, ss_image **out, ss_error *err) {
    ss_noise_params p;
    ss_noise_params_default(&p);
    p.octaves = q->octaves;
    p.persistence = q->persistence;
    p.bias = q->bias;
    p.gain = q->gain;
    p.stretch_y = q->stretch_y;
    p.cell_px = c->k;
    *out = ss_image_create_uninit(c->bw > 0 ? c->bw : 1, c->bh > 0 ? c->bh : 1, 1, err);
    if (!*out) return err->code;
    if (c->bw == 0) return SS_OK;
    ss_status st =
        ss_value_noise_rect(&p, c->s->seed, q->stream, c->n, c->n, c->bx, c->by, *out, err);
    if (st) {
        ss_image_free(*out);
        *out = NULL;
    }
    return st;
}

/* Index into a box-sized image (x0, y0 its corner, w its width) of the
 * texture pixel i. */
static inline size_t box_index(const ctx *c, int x0, int y0, int w, size_t i) {
    size_t y = i / (size_t)c->n, x = i - y * (size_t)c->n;
    return (y - (size_t)y0) * (size_t)w + (x - (size_t)x0);
}

/* Thickness of the glow and the scab's inner gradient: 100 reference px. */
static inline float gradient_px(const ctx *c) { return 100.0f * c->k; }

/* Every phase starts from healthy skin: the upper colour, its reflection,
 * flat height and normal; the phases then draw only around the wound. */
static void fill_healthy(const ctx *c, ss_texture_set *out) {
    const size_t n = (size_t)c->n;
#pragma omp parallel for schedule(static)
    for (int y = 0; y < c->n; y++) {
        size_t o = (size_t)y * n;
        memcpy(out->color->data + o * 3, c->skin->upper->data + o * 3, n * 3 * sizeof(float));
        float *r = out->reflection->data + o, *h = out->height->data + o;
        float *nm = out->normal->data + o * 3;
        for (size_t x = 0; x < n; x++) {
            r[x] = SKIN_REFLECTION;
            h[x] = 0.5f;
            nm[3 * x] = 0.5f;
            nm[3 * x + 1] = 0.5f;
            nm[3 * x + 2] = 1.0f;
        }
    }
}

static void normals(const ctx *c, ss_texture_set *out) {
    double pixel_mm = c->s->world_size_cm * 10.0 / c->n;
    /* height 0..1 spans 2 * scab_height_mm (0.5 is the skin surface) */
    float strength = (float)(2.0 * c->s->scab_height_mm / pixel_mm);
    /* Outside the wound the height is flat (0.5), so the normal is (0,0,1);
     * only the box around the wound needs the differences. */
    int x0 = c->rx - 2, y0 = c->ry - 2, w = c->rw + 4, h = c->rh + 4;
    if (c->rw == 0 || x0 < 0 || y0 < 0 || x0 + w > c->n || y0 + h > c->n) {
        ss_height_to_normal(out->height, strength, out->normal);
        return;
    }
    ss_error err; /* the flat normal outside is already there (fill_healthy) */
    ss_image *hs = ss_image_create(w, h, 1, &err), *ns = hs ? ss_image_create(w, h, 3, &err) : NULL;
    if (!ns) { /* no memory for the box: do the whole texture */
        ss_image_free(hs);
        ss_height_to_normal(out->height, strength, out->normal);
        return;
    }
    for (int y = 0; y < h; y++)
        memcpy(ss_image_px(hs, 0, y), ss_image_px(out->height, x0, y0 + y),
               (size_t)w * sizeof(float));
    ss_height_to_normal(hs, strength, ns);
    /* The box's outer ring saw wrapped neighbours; it is flat anyway. */
    for (int y = 1; y < h - 1; y++)
        memcpy(ss_image_px(out->normal, x0 + 1, y0 + y), ss_image_px(ns, 1, y),
               (size_t)(w - 2) * 3 * sizeof(float));
    ss_image_free(hs);
    ss_image_free(ns);
}

/* ---- the tissue look (docs/abrasion.md, "Colours from the optics") ------------ */

/* Streams of the noises the tissue look adds to the seed's. */
enum { ST_JITTER = 0x140, ST_CAPILLARY, ST_PATCH, ST_BLEED };

static inline float clampf(float v, float lo, float hi) { return v < lo ? lo : v > hi ? hi : v; }
static inline float smooth01(float e0, float e1, float v) {
    float t = clampf((v - e0) / (e1 - e0), 0.0f, 1.0f);
    return t * t * (3.0f - 2.0f * t);
}

/* Value noise over the changed region whose coarsest period is period_mm on
 * the body; index it with region_index. */
static ss_status noise_mm(const ctx *c, int octaves, double period_mm, uint64_t stream,
                          ss_image **out, ss_error *err) {
    ss_noise_params p;
    ss_noise_params_default(&p);
    p.octaves = octaves;
    double cell = period_mm * c->px_per_mm / (double)(1 << octaves);
    p.cell_px = (float)(cell < 0.5 ? 0.5 : cell);
    *out = ss_image_create_uninit(c->rw > 0 ? c->rw : 1, c->rh > 0 ? c->rh : 1, 1, err);
    if (!*out) return err->code;
    if (c->rw == 0) return SS_OK;
    ss_status st = ss_value_noise_rect(&p, c->s->seed, stream, c->n, c->n, c->rx, c->ry, *out, err);
    if (st) {
        ss_image_free(*out);
        *out = NULL;
    }
    return st;
}
static inline size_t region_index(const ctx *c, size_t i) {
    return box_index(c, c->rx, c->ry, c->rw, i);
}
/* Index of pixel i into a box-sized image, clamped into the box (pixels just
 * outside the mask, inside the jittered margin, read the nearest box pixel). */
static inline size_t box_index_clamped(const ctx *c, size_t i) {
    int y = (int)(i / (size_t)c->n), x = (int)(i - (size_t)y * (size_t)c->n);
    x = x < c->bx ? c->bx : x >= c->bx + c->bw ? c->bx + c->bw - 1 : x;
    y = y < c->by ? c->by : y >= c->by + c->bh ? c->by + c->bh - 1 : y;
    return (size_t)(y - c->by) * (size_t)c->bw + (size_t)(x - c->bx);
}

/* The noises every phase reads: the margin jitter (~1 mm), the capillary
 * loops of the dermal papillae (~0.35 mm), patches of exudate or fibrin
 * (~2.5 mm) and spots of bleeding (~1.2 mm). */
typedef struct look {
    ss_image *jitter, *cap, *patch, *bleed;
} look;
static void look_free(look *l) {
    ss_image_free(l->jitter);
    ss_image_free(l->cap);
    ss_image_free(l->patch);
    ss_image_free(l->bleed);
}
static ss_status look_create(const ctx *c, look *l, ss_error *err) {
    memset(l, 0, sizeof *l);
    ss_status st = noise_mm(c, 3, 1.2, ST_JITTER, &l->jitter, err);
    if (!st) st = noise_mm(c, 1, 0.3, ST_CAPILLARY, &l->cap, err);
    if (!st) st = noise_mm(c, 4, 2.5, ST_PATCH, &l->patch, err);
    if (!st) st = noise_mm(c, 3, 1.2, ST_BLEED, &l->bleed, err);
    if (st) look_free(l);
    return st;
}

/* A phase's noises: the shared look and count of its own (box-sized, index
 * with box_index_clamped), made together and freed together. */
#define MAX_PHASE_NOISES 4
typedef struct phase_noises {
    look l;
    ss_image *n[MAX_PHASE_NOISES];
    int count;
} phase_noises;
static void phase_noises_free(phase_noises *p) {
    for (int k = 0; k < p->count; k++) ss_image_free(p->n[k]);
    look_free(&p->l);
}
static ss_status phase_noises_create(const ctx *c, const noise_spec *spec, int count,
                                     phase_noises *p, ss_error *err) {
    memset(p, 0, sizeof *p);
    p->count = count;
    ss_status st = SS_OK;
    for (int k = 0; k < count && !st; k++) st = noise(c, &spec[k], &p->n[k], err);
    if (!st) st = look_create(c, &p->l, err);
    if (st) phase_noises_free(p);
    return st;
}

/* Where pixel i sits against the one distance field every mask of a phase is
 * cut from: s (pixels, > 0 inside) jittered by +-0.2 mm so the margin is
 * ragged, and the erythema weight of the glow (1 at the outline, 0 at the
 * glow's width; from the unjittered distance, so it ends inside the changed
 * region). */
typedef struct where {
    float s, glow;
    size_t r; /* region index */
} where;
static inline where locate_px(const ctx *c, const look *l, size_t i) {
    where w;
    w.r = region_index(c, i);
    float d = c->w->dist->data[i], s = c->w->mask->data[i] > 0.5f ? d : -d;
    float x = clampf(-s / gradient_px(c), 0.0f, 1.0f);
    w.glow = (1.0f - x) * (1.0f - x);
    w.s = s + 0.2f * c->px_per_mm * (2.0f * l->jitter->data[w.r] - 1.0f);
    return w;
}

/* The colour outside the outline: the skin, reddened by the erythema of the
 * glow (strength 0..1). */
static inline void glow_color(const ctx *c, size_t i, float glow, float strength, float *rgb) {
    const float *up = c->skin->upper->data + i * 3, *e = c->P->erythema;
    for (int k = 0; k < 3; k++) rgb[k] = up[k] * (1.0f + (e[k] - 1.0f) * glow * strength);
}

/* The lower skin texture's relative brightness: the bed keeps its detail. */
static inline float lower_mod(const ctx *c, size_t i) {
    return clampf(lum(c->skin->lower->data + i * 3) / c->lower_mean, 0.8f, 1.2f);
}
/* The upper skin texture's relative brightness: new epithelium, a colour of
 * its own, keeps the skin's grain. */
static inline float upper_mod(const ctx *c, size_t i) {
    return clampf(lum(c->skin->upper->data + i * 3) / c->upper_mean, 0.8f, 1.2f);
}

/* Writes the pixel: outside the jittered outline the glow, inside the bed,
 * the two joined across the rim (rim_mm of torn epidermis) by one lerp, so
 * the colour runs monotonically from the glow into the bed with no band of
 * another colour between. depth: how far the bed lies below the skin (height
 * units); refl: the bed's reflection. */
static inline void put_px(const ctx *c, size_t i, const where *w, float strength, const float *bed,
                          float refl, float height, ss_texture_set *out) {
    float g[3];
    glow_color(c, i, w->glow, strength, g);
    float t = smooth01(0.0f, c->rim_px, w->s);
    float *o = out->color->data + i * 3;
    for (int k = 0; k < 3; k++) o[k] = clampf(g[k] + (bed[k] - g[k]) * t, 0.0f, 1.0f);
    out->reflection->data[i] = SKIN_REFLECTION + (refl - SKIN_REFLECTION) * t;
    out->height->data[i] = 0.5f + (height - 0.5f) * t;
}

/* Loops over the changed region, pixel index i. */
#define FOR_REGION(c)                                                                              \
    _Pragma("omp parallel for schedule(static)") for (int y_ = (c)->ry; y_ < (c)->ry + (c)->rh;    \
                                                      y_++) for (size_t i =                        \
                                                                     (size_t)y_ * (size_t)(c)->n + \
                                                                     (size_t)(c)->rx,              \
                                                                 e_ = i + (size_t)(c)->rw;         \
                                                                 i < e_; i++)

/* The capillary loops of the exposed papillae: red dots where the fine noise
 * is high (0..1). */
static inline float capillary_dots(const look *l, size_t r) {
    return smooth01(0.66f, 0.85f, l->cap->data[r]);
}

static ss_status render_vasoconstriction(const ctx *c, ss_texture_set *out, ss_error *err) {
    /* §4.3.1: the fresh bed (arterioles constricted, the seed's blanched
     * phase): exposed dermis, deep red from the torn papillary plexus as
     * fresh abrasions look, with punctate bleeding from torn capillary loops
     * (pale pink-white, then salmon pink, did not look like one); wet; no
     * erythema yet. */
    look l;
    ss_status st = look_create(c, &l, err);
    if (st) return st;
    const ss_abrasion_palette *P = c->P;
    FOR_REGION(c) {
        where w = locate_px(c, &l, i);
        if (w.s <= 0.0f) continue; /* healthy skin (fill_healthy) */
        float m = lower_mod(c, i), dots = 0.6f * capillary_dots(&l, w.r), bed[3];
        float bl = 0.4f * smooth01(0.6f, 0.9f, l.bleed->data[w.r]);
        for (int k = 0; k < 3; k++) {
            float v = P->bed_pale[k] * m;
            v += (P->capillary[k] - v) * dots;
            bed[k] = v + (P->blood[k] - v) * bl;
        }
        put_px(c, i, &w, 0.0f, bed, RAW_WOUND_REFLECTION + 0.2f * bl,
               0.5f - WOUND_DEPTH + 0.01f * (l.cap->data[w.r] - 0.5f), out);
    }
    look_free(&l);
    return SS_OK;
}

static ss_status render_vasodilation(const ctx *c, ss_texture_set *out, ss_error *err) {
    /* §4.3.2: the dilated bed: red-pink dermis dotted with capillary loops,
     * bleeding along the scrape lines and in spots, a wet film (shiny), the
     * erythema of the glow around; the seed's scrape lines as reflection and
     * relief. */
    static const noise_spec spec[] = {{5, 0.09f, 0.5f, 0.43f, 64.0f, ST_SCRAPE}};
    phase_noises p;
    ss_status st = phase_noises_create(c, spec, 1, &p, err);
    if (st) return st;
    const look *l = &p.l;
    const ss_image *scrape = p.n[0];
    const ss_abrasion_palette *P = c->P;
    FOR_REGION(c) {
        where w = locate_px(c, l, i);
        if (w.s <= 0.0f) {
            if (w.glow > 0.0f) glow_color(c, i, w.glow, 1.0f, out->color->data + i * 3);
            continue;
        }
        float sc = scrape->data[box_index_clamped(c, i)];
        float m = lower_mod(c, i), dots = capillary_dots(l, w.r), bed[3];
        float bl =
            0.55f * smooth01(0.55f, 0.85f, l->bleed->data[w.r]) + 0.25f * smooth01(0.55f, 0.8f, sc);
        bl = clampf(bl, 0.0f, 0.7f);
        for (int k = 0; k < 3; k++) {
            float v = P->bed[k] * m;
            v += (P->capillary[k] - v) * (0.25f + 0.45f * dots);
            bed[k] = v + (P->blood[k] - v) * bl;
        }
        put_px(c, i, &w, 1.0f, bed, 0.55f + 0.4f * sc,
               0.5f - WOUND_DEPTH + SCRAPE_RELIEF * (sc - 0.5f) + 0.008f * (dots - 0.5f), out);
    }
    phase_noises_free(&p);
    return SS_OK;
}

static ss_status render_scab_forming(const ctx *c, ss_texture_set *out, ss_error *err) {
    /* §4.3.3: the bed glazed with serous exudate that turns to yellow fibrin
     * in patches (the seed's Eq. 4.5 mix, its low noise as the fibrin
     * weight), dark-red speckles of drying blood (its Eq. 4.6 speckles),
     * drying, so less shiny where fibrin has set; the glow fades. */
    static const noise_spec spec[] = {{5, 0.85f, 0.54f, 0.21f, 1.0f, ST_SCABFORM_LOW},
                                      {5, 0.48f, 0.16f, 0.15f, 1.0f, ST_SCABFORM_SPECKLE},
                                      {5, 0.09f, 0.5f, 0.43f, 64.0f, ST_SCRAPE}};
    phase_noises p;
    ss_status st = phase_noises_create(c, spec, 3, &p, err);
    if (st) return st;
    const look *l = &p.l;
    const ss_image *low = p.n[0], *speck = p.n[1], *scrape = p.n[2];
    const ss_abrasion_palette *P = c->P;
    FOR_REGION(c) {
        where w = locate_px(c, l, i);
        if (w.s <= 0.0f) {
            if (w.glow > 0.0f) glow_color(c, i, w.glow, 0.8f, out->color->data + i * 3);
            continue;
        }
        size_t b = box_index_clamped(c, i);
        float m = lower_mod(c, i), dots = capillary_dots(l, w.r), bed[3];
        float fib = 0.45f * smooth01(0.5f, 0.85f, 0.5f * low->data[b] + 0.5f * l->patch->data[w.r]);
        float sp = smooth01(0.25f, 0.6f, speck->data[b]) * 0.8f;
        for (int k = 0; k < 3; k++) {
            float v = P->bed[k] * m;
            v += (P->capillary[k] - v) * (0.2f + 0.4f * dots);
            v += (P->serous[k] - v) * 0.35f;
            v += (P->fibrin[k] - v) * fib;
            float dried = 0.5f * (P->capillary[k] + P->crust_dark[k]);
            bed[k] = v + (dried - v) * sp;
        }
        put_px(c, i, &w, 0.8f, bed, 0.75f * (1.0f - 0.6f * fib) * (0.6f + 0.4f * scrape->data[b]),
               0.5f - WOUND_DEPTH * (0.5f + low->data[b]) - WOUND_DEPTH * sp + 0.02f * fib, out);
    }
    phase_noises_free(&p);
    return SS_OK;
}

static ss_status render_scab(const ctx *c, ss_texture_set *out, ss_error *err) {
    /* §4.3.4: the crust. Its height = mask noise x middle noise, as the seed;
     * colour from a thin serous (amber) to a thick dark dried-blood crust
     * with the height; within 100 reference px of the edge a redder, thinner
     * crust where the red-detail noise is high (the seed's inward red
     * gradient); matte (reflection noise x 0.4); the glow fades. */
    static const noise_spec spec[] = {{7, 1.0f, 0.44f, 0.02f, 1.0f, ST_SCAB_MASK},
                                      {5, 0.54f, 0.3f, 0.69f, 1.0f, ST_SCAB_MIDDLE},
                                      {5, 0.33f, 0.60f, 0.59f, 1.0f, ST_SCAB_RED},
                                      {10, 1.0f, 0.25f, 0.95f, 1.0f, ST_SCAB_REFLECT}};
    phase_noises p;
    ss_status st = phase_noises_create(c, spec, 4, &p, err);
    if (st) return st;
    const look *l = &p.l;
    const ss_image *mask_n = p.n[0], *mid = p.n[1], *redn = p.n[2], *refl = p.n[3];
    const ss_abrasion_palette *P = c->P;
    FOR_REGION(c) {
        where w = locate_px(c, l, i);
        if (w.s <= 0.0f) {
            if (w.glow > 0.0f) glow_color(c, i, w.glow, 0.5f, out->color->data + i * 3);
            continue;
        }
        size_t b = box_index_clamped(c, i);
        float h = mask_n->data[b] * mid->data[b];
        /* the thick parts are the dark crust, the thin ones amber */
        float thick = clampf(0.55f + 1.2f * h, 0.0f, 1.0f), crust[3];
        float edge = 1.0f - smooth01(0.0f, gradient_px(c), w.s);
        float red = edge * redn->data[b] * 0.6f;
        for (int k = 0; k < 3; k++) {
            float v = P->crust_light[k] + (P->crust_dark[k] - P->crust_light[k]) * thick;
            crust[k] = v + (0.5f * (P->capillary[k] + P->crust_dark[k]) - v) * red;
        }
        put_px(c, i, &w, 0.5f, crust, 0.4f * refl->data[b], 0.5f + 0.5f * h, out);
    }
    phase_noises_free(&p);
    return SS_OK;
}

/* Maturation at a position (Alg. 4.4's healed border sweeping inward by up to
 * half the closing distance, its inner border rand(0.4, 0.8) of that further
 * in), on the smoothed distance, so its fronts are rounded and nested:
 *   healed (d <= outer): new epithelium, the optics' own colour of a thin
 *     epidermis over hyperaemic dermis at the ring's melanin (the palette's
 *     epithelium; pink on light skin, pink-brown on dark), giving way to
 *     the skin texture as exp(-age / 120 d) (age the days since that ring
 *     healed),
 *     lightening (1 - exp(-age / 60 d)) and turning into a faint pale scar
 *     after the first month (1 - exp(-(age - 30 d) / 150 d)); its melanin
 *     (a factor of the skin's, drawn through the palette's melanin_ratio)
 *     0.5 at closure, repigmenting over ~10 days, times 1 + the
 *     post-inflammatory hyperpigmentation (rising over the first weeks and
 *     fading over months, as strong as the skin type's clinical rate), less
 *     a quarter as the scar matures;
 *   front (outer < d <= inner): new epithelium at the front, red
 *     granulation tissue behind it;
 *   core: moist granulation tissue with fibrin.
 * Ages: span_days is the maturation phase's length, after_days the time past
 * its end (the scar keeps maturing). */
#define SCAR_RED_DAYS 120.0f   /* fading of the young scar's pink */
#define SCAR_PALE_DELAY 30.0f  /* days before the scar starts to pale */
#define SCAR_PALE_DAYS 150.0f  /* its paling */
#define SCAR_BRIGHT_DAYS 60.0f /* its lightening (dense collagen) */
#define SCAR_WEIGHT 0.6f       /* how far a mature scar goes to the palette's scar */
/* Post-inflammatory hyperpigmentation after healing: ss_abrasion_pih_factor
 * (palette.c), the course `wound` uses too (ss_pih_melanin_factor,
 * src/optics/healing.c: Danielsen et al. 2013's +24 % at 1 month, +15 % at 3,
 * back at 12, as strong as the skin type's PIH rate). */
/* The new epithelium's melanin and the scar's: ss_repigmentation_factor
 * (src/optics/healing.c), the model `wound` uses too (0.5 of the skin's at
 * closure, repigmenting over ~10 days, a quarter less in the mature scar).
 * 0.4 and 28 days drew an orange-tan ring on dark skin (melanin loss as a
 * multiplier of the skin; day 20: L* +10.7, chroma +12). */

/* One of the palette's tables over melanin factors (melanin_ratio,
 * epithelium) at a factor: log-linear between its samples, clamped to
 * 0.25..2.5. */
static void at_melanin(const float table[SS_ABRASION_NMELANIN][3], float factor, float out[3]) {
    double x =
        log10(fmax(factor, 1e-6) / ss_abrasion_melanin_factor(0)) * (SS_ABRASION_NMELANIN - 1);
    x = x < 0 ? 0 : x > SS_ABRASION_NMELANIN - 1 ? SS_ABRASION_NMELANIN - 1 : x;
    int k = (int)x < SS_ABRASION_NMELANIN - 1 ? (int)x : SS_ABRASION_NMELANIN - 2;
    float t = (float)(x - k);
    for (int c = 0; c < 3; c++) out[c] = table[k][c] + (table[k + 1][c] - table[k][c]) * t;
}
static inline int maturation_px(const ctx *c, const look *l, size_t i, double position,
                                double span_days, double after_days, float *rgb, float *refl) {
    const ss_abrasion_palette *P = c->P;
    float d = c->w->smooth->data[i];
    where w = locate_px(c, l, i);
    float s = d + (w.s - (c->w->mask->data[i] > 0.5f ? c->w->dist->data[i]
                                                     : -c->w->dist->data[i])); /* + jitter */
    if (s <= -c->rim_px) return 0;
    int lab = c->w->label[i];
    double closing = c->w->closing_px[lab >= 0 ? lab : 0];
    double ratio = c->w->inner_ratio[lab >= 0 ? lab : 0];
    double max_outer = closing * 0.5, outer = max_outer * position;
    double inner = outer + max_outer * ratio;
    const float *up = c->skin->upper->data + i * 3;
    float healed[3], heal_t = 0, m = lower_mod(c, i);
    /* days since this ring healed */
    double pos_h = s > 0 ? s / max_outer : 0;
    double age = (position - pos_h) * span_days + after_days;
    if (age < 0) age = 0;
    /* the young scar's redness fades over months while its pallor comes in
     * after the first month (two effects, not one lerp: pink to pale through
     * the skin's own colour would hide the scar around day 90) */
    float red = expf(-(float)age / SCAR_RED_DAYS);
    float pale = 1.0f - expf(-fmaxf(0.0f, (float)age - SCAR_PALE_DELAY) / SCAR_PALE_DAYS);
    float bright_t = 1.0f - expf(-(float)age / SCAR_BRIGHT_DAYS);
    float mat = 1.0f - red;
    /* the scar's multiplier split into its brightness (which comes in first)
     * and its chromaticity (the loss of redness, with the pallor), so that on
     * the way from pink to pale the scar is lighter than the skin, never the
     * skin's own colour */
    float sb = lum(P->scar) > 1e-6f ? lum(P->scar) : 1.0f;
    /* PIH follows the inflammation of the whole wound, not each ring's age:
     * the oldest ring's age for every ring (per-ring ages made the oldest,
     * outermost ring darkest: a dark line at the healed margin) */
    float wage = (float)(position * span_days + after_days);
    float pih = (float)ss_abrasion_pih_factor(c->P, wage) - 1.0f;
    /* the epidermis's melanin, as a factor of the skin's: the new epithelium
     * melanin-poor, repigmenting over weeks, darkened by post-inflammatory
     * hyperpigmentation, and the mature scar somewhat hypopigmented; drawn as
     * the optics render that melanin (the palette's epithelium while young,
     * its melanin_ratio on the skin texture as it matures), so a dark skin
     * heals pink-brown, then darker, then faintly lighter (the melanin change
     * as one more multiplier per channel, weighted in sRGB, made a saturated
     * orange patch of a dark skin; the young epithelium as a multiplier of
     * the texture, an orange ring round the red core at day 12) */
    ss_repigmentation repig;
    ss_repigmentation_default(&repig);
    float mel = (float)ss_repigmentation_factor(&repig, age) * (1.0f + pih);
    float mr[3], epi[3], detail = upper_mod(c, i);
    at_melanin(P->melanin_ratio, mel, mr);
    at_melanin(P->epithelium, mel, epi);
    for (int k = 0; k < 3; k++) {
        float young = epi[k] * detail, mature = up[k] * mr[k];
        healed[k] = (mature + (young - mature) * red) *
                    (1.0f + (sb - 1.0f) * SCAR_WEIGHT * bright_t) *
                    (1.0f + (P->scar[k] / sb - 1.0f) * SCAR_WEIGHT * pale);
    }
    float r = 0.32f - 0.05f * mat; /* young epithelium is smooth and shiny */
    if (s > outer) {               /* the front and the open core */
        double t = inner > outer ? (s - outer) / (inner - outer) : 1.0;
        heal_t = smooth01(0.0f, 1.0f, (float)t);
        double span = closing * 0.5 - inner;
        float core = span > 0 ? clampf((float)((s - inner) / span), 0.0f, 1.0f) : 1.0f;
        core = s > inner ? core : 0.0f;
        float dots = capillary_dots(l, w.r);
        float fib = 0.35f * core * smooth01(0.45f, 0.75f, l->patch->data[w.r]);
        for (int k = 0; k < 3; k++) {
            float g = P->granulation[k] * m;
            g += (P->capillary[k] - g) * 0.3f * dots;
            g += (P->fibrin[k] - g) * fib;
            healed[k] += (g - healed[k]) * heal_t;
        }
        r += (0.75f - r) * heal_t;
    }
    /* the scar's edge: soft over the rim */
    float in = smooth01(-c->rim_px, c->rim_px, s);
    for (int k = 0; k < 3; k++) rgb[k] = up[k] + (healed[k] - up[k]) * in;
    *refl = SKIN_REFLECTION + (r - SKIN_REFLECTION) * in;
    return 1;
}

static ss_status maturation_region(const ctx *c, double position, double span_days,
                                   double after_days, ss_image *color, ss_image *reflection,
                                   ss_progress_fn fn, void *user, ss_error *err) {
    look l;
    ss_status st = look_create(c, &l, err);
    if (st) return st;
    /* with a progress callback the region's rows go in bands, polled between
     * them (each pixel is a function of its own position: no value changes) */
    const int band = fn ? (c->rh / 32 > 16 ? c->rh / 32 : 16) : (c->rh > 0 ? c->rh : 1);
    for (int yb = c->ry; yb < c->ry + c->rh; yb += band) {
        const int ye = c->ry + c->rh - yb > band ? yb + band : c->ry + c->rh;
#pragma omp parallel for schedule(static)
        for (int y_ = yb; y_ < ye; y_++)
            for (size_t i = (size_t)y_ * (size_t)c->n + (size_t)c->rx, e_ = i + (size_t)c->rw;
                 i < e_; i++) {
                float rgb[3], r;
                if (!maturation_px(c, &l, i, position, span_days, after_days, rgb, &r)) continue;
                for (int k = 0; k < 3; k++) color->data[i * 3 + k] = clampf(rgb[k], 0.0f, 1.0f);
                if (reflection) reflection->data[i] = r;
            }
        if (fn && fn(user, (double)(ye - c->ry) / c->rh)) {
            look_free(&l);
            return ss_error_set(err, SS_ERR_RUNTIME, "abrasion frame: cancelled");
        }
    }
    look_free(&l);
    return SS_OK;
}

static ss_status render_maturation(const ctx *c, double position, ss_texture_set *out,
                                   ss_error *err) {
    /* The height is flat, a hair below the skin inside (a flat scar). */
    ss_status st = maturation_region(c, position, DEFAULT_MATURATION_DAYS, 0.0, out->color,
                                     out->reflection, NULL, NULL, err);
    FOR_REGION(c) {
        float d = c->w->smooth->data[i];
        out->height->data[i] = 0.5f - 0.01f * smooth01(-c->rim_px, c->rim_px, d);
    }
    return st;
}

static ss_status check_inputs(const ss_wound_shape *w, const ss_base_skin *skin,
                              const ss_abrasion_settings *s, const ss_texture_set *out,
                              ss_error *err) {
    int n = s->size;
    if (w->size != n || skin->upper->width != n || skin->lower->width != n ||
        out->color->width != n)
        return ss_error_set(err, SS_ERR_INPUT,
                            "abrasion render: shape, skin and output sizes differ from %d", n);
    if (!(s->world_size_cm > 0) || !(s->reference_px > 0) || !(s->scab_height_mm > 0))
        return ss_error_set(
            err, SS_ERR_INPUT,
            "abrasion settings: world size, reference size and scab height must be > 0");
    return SS_OK;
}

ss_status ss_abrasion_render_phase(ss_phase phase, double position, const ss_wound_shape *w,
                                   const ss_base_skin *skin, const ss_abrasion_settings *s,
                                   ss_texture_set *out, ss_error *err) {
    ss_status st = check_inputs(w, skin, s, out, err);
    if (st) return st;
    ctx c;
    ctx_init(&c, w, skin, s);
    fill_healthy(&c, out);
    switch (phase) {
    case SS_PHASE_VASOCONSTRICTION:
        st = render_vasoconstriction(&c, out, err);
        break;
    case SS_PHASE_VASODILATION:
        st = render_vasodilation(&c, out, err);
        break;
    case SS_PHASE_SCAB_FORMING:
        st = render_scab_forming(&c, out, err);
        break;
    case SS_PHASE_SCAB:
        st = render_scab(&c, out, err);
        break;
    case SS_PHASE_MATURATION:
        if (!(position >= 0.0 && position <= 1.0))
            return ss_error_set(err, SS_ERR_INPUT, "maturation position %g is outside 0..1",
                                position);
        st = render_maturation(&c, position, out, err);
        break;
    default:
        return ss_error_set(err, SS_ERR_INPUT, "unknown phase %d", (int)phase);
    }
    if (!st) normals(&c, out);
    return st;
}

ss_status ss_abrasion_maturation_at(const ss_wound_shape *w, const ss_base_skin *skin,
                                    const ss_abrasion_settings *s, double position,
                                    double span_days, double after_days, ss_image *color,
                                    ss_image *reflection, ss_error *err) {
    return abrasion_maturation_at_poll(w, skin, s, position, span_days, after_days, color,
                                       reflection, NULL, NULL, err);
}

ss_status abrasion_maturation_at_poll(const ss_wound_shape *w, const ss_base_skin *skin,
                                      const ss_abrasion_settings *s, double position,
                                      double span_days, double after_days, ss_image *color,
                                      ss_image *reflection, ss_progress_fn fn, void *user,
                                      ss_error *err) {
    if (!(position >= 0.0 && position <= 1.0))
        return ss_error_set(err, SS_ERR_INPUT, "maturation position %g is outside 0..1", position);
    if (!(span_days >= 0) || !(after_days >= 0))
        return ss_error_set(err, SS_ERR_INPUT, "maturation: days must be >= 0");
    ctx c;
    ctx_init(&c, w, skin, s);
    return maturation_region(&c, position, span_days, after_days, color, reflection, fn, user, err);
}

ss_status ss_abrasion_maturation_color(const ss_wound_shape *w, const ss_base_skin *skin,
                                       const ss_abrasion_settings *s, double position,
                                       ss_image *color, ss_error *err) {
    return ss_abrasion_maturation_at(w, skin, s, position, DEFAULT_MATURATION_DAYS, 0.0, color,
                                     NULL, err);
}

ss_status ss_reflection_to_metal_rough(const ss_image *reflection, ss_image *mr, ss_error *err) {
    if (reflection->width != mr->width || reflection->height != mr->height ||
        reflection->channels != 1 || mr->channels != 3)
        return ss_error_set(err, SS_ERR_INPUT,
                            "metal-rough: needs a 1-channel reflection and an "
                            "RGB output of the same size");
    size_t n = (size_t)mr->width * (size_t)mr->height;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) {
        float r = reflection->data[i];
        r = r < 0 ? 0 : r > 1 ? 1 : r;
        mr->data[i * 3] = 1.0f;
        mr->data[i * 3 + 1] = 1.0f - 0.8f * r;
        mr->data[i * 3 + 2] = 0.0f;
    }
    return SS_OK;
}
