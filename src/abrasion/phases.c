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
#include "skinsim/texture.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Seed colours (display values). */
static const float GLOW_RED[3] = {0.79f, 0.0f, 0.0f};      /* §4.3.2 */
static const float EDGE_GREY = 0.95f;                      /* §4.3.2 */
static const float SPECKLE_RED[3] = {0.88f, 0.20f, 0.22f}; /* §4.3.3 */
static const float SCAB_RED[3] = {0.5f, 0.04f, 0.03f};     /* §4.3.4 */
static const float SCAB_LIGHT[3] = {0.78f, 0.48f, 0.27f};  /* §4.3.4 */
static const float SCAB_DARK[3] = {0.39f, 0.12f, 0.11f};   /* §4.3.4 */
static const float WOUND_WHITE[3] = {0.79f, 0.41f, 0.41f}; /* §4.3.5 */

/* Reflection and height where the seed gives none (docs/abrasion.md). */
static const float SKIN_REFLECTION = 0.25f;     /* healthy skin specular strength */
static const float RAW_WOUND_REFLECTION = 0.5f; /* fresh, wet wound bed */
static const float WOUND_DEPTH = 0.05f;         /* epidermis removed: 0.05 of the height range */
static const float SCRAPE_RELIEF = 0.02f;       /* depth of the scrape lines */

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

/* sRGB decode through a table (built per render, a few microseconds): the
 * renderer decodes every output pixel and powf would dominate. */
#define LUT_N 4096
typedef struct decode_lut {
    float v[LUT_N + 1];
} decode_lut;
static void lut_init(decode_lut *l) {
    for (int i = 0; i <= LUT_N; i++) l->v[i] = ss_srgb_decode((float)i / LUT_N);
}
static inline float decode(const decode_lut *l, float e) {
    if (!(e > 0.0f)) return 0.0f;
    if (e >= 1.0f) return 1.0f;
    float f = e * LUT_N;
    int i = (int)f;
    float t = f - (float)i;
    return l->v[i] + (l->v[i + 1] - l->v[i]) * t;
}
static inline void lerp3(const float *a, const float *b, float t, float *out) {
    for (int k = 0; k < 3; k++) out[k] = a[k] + (b[k] - a[k]) * t;
}

/* Everything one render needs, resolved for the output size. */
typedef struct ctx {
    const ss_wound_shape *w;
    const ss_base_skin *skin;
    const ss_abrasion_settings *s;
    int n;
    size_t npx;
    float k;            /* output pixels per reference pixel */
    int bx, by, bw, bh; /* the wound's box: noise, erosion and normals are only
                           needed there (outside, every phase is plain skin), so
                           the cost grows with the wound, not the texture */
    int rx, ry, rw, rh; /* the box grown by the glow: where any colour differs
                           from healthy skin */
    decode_lut lut;
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
    lut_init(&c->lut);
    c->bx = w->box_x;
    c->by = w->box_y;
    c->bw = w->box_w;
    c->bh = w->box_h;
    ss_abrasion_changed_region(w, s, &c->rx, &c->ry, &c->rw, &c->rh);
}

static inline void put_color(const ctx *c, float *dst, const float rgb[3]) {
    for (int k = 0; k < 3; k++) dst[k] = decode(&c->lut, rgb[k]);
}

/* A value-noise texture over the wound's box only (noise is only read inside
 * the wound); index it with box_index. Same values as the whole texture. */
static ss_status noise(const ctx *c, int octaves, float persistence, float bias, float gain,
                       float stretch_y, uint64_t stream, ss_image **out, ss_error *err) {
    ss_noise_params p;
    ss_noise_params_default(&p);
    p.octaves = octaves;
    p.persistence = persistence;
    p.bias = bias;
    p.gain = gain;
    p.stretch_y = stretch_y;
    p.cell_px = c->k;
    *out = ss_image_create_uninit(c->bw > 0 ? c->bw : 1, c->bh > 0 ? c->bh : 1, 1, err);
    if (!*out) return err->code;
    if (c->bw == 0) return SS_OK;
    ss_status st = ss_value_noise_rect(&p, c->s->seed, stream, c->n, c->n, c->bx, c->by, *out, err);
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

/* Outside the wound the glow fades from red to the upper skin (Alg. 3.4);
 * where it is not drawn the pixel keeps the healthy skin fill_healthy wrote. */
static inline void outside_glow(const ctx *c, size_t i, ss_texture_set *out) {
    float t = ss_gradient_weight(0, c->w->dist->data[i], gradient_px(c), 0);
    if (t < 0.0f) return;
    float rgb[3];
    lerp3(GLOW_RED, c->skin->upper_srgb->data + i * 3, t, rgb);
    put_color(c, out->color->data + i * 3, rgb);
}

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
    int x0 = c->bx - 2, y0 = c->by - 2, w = c->bw + 4, h = c->bh + 4;
    if (c->bw == 0 || x0 < 0 || y0 < 0 || x0 + w > c->n || y0 + h > c->n) {
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

static ss_status render_vasoconstriction(const ctx *c, ss_texture_set *out, ss_error *err) {
    (void)err;
    /* §4.3.1: lower skin inside the shape, upper skin outside. */
#pragma omp parallel for schedule(static)
    for (int y = c->ry; y < c->ry + c->rh; y++)
        for (size_t i = (size_t)y * (size_t)c->n + (size_t)c->rx, e = i + (size_t)c->rw; i < e;
             i++) {
            if (c->w->mask->data[i] <= 0.5f) continue;
            put_color(c, out->color->data + i * 3, c->skin->lower_srgb->data + i * 3);
            out->reflection->data[i] = RAW_WOUND_REFLECTION;
            out->height->data[i] = 0.5f - WOUND_DEPTH;
        }
    return SS_OK;
}

static ss_status render_vasodilation(const ctx *c, ss_texture_set *out, ss_error *err) {
    ss_image *scrape = NULL, *e1 = NULL, *e2 = NULL;
    /* Scrape lines: 5 octaves, persistence 0.09, bias 0.5, gain 0.43, y x64. */
    ss_status st = noise(c, 5, 0.09f, 0.5f, 0.43f, 64.0f, ST_SCRAPE, &scrape, err);
    /* The half-scraped edge: erode twice (widths 3-5, then 3-10), in a box
     * around the wound padded wider than the kernels so the result equals
     * eroding the whole texture. */
    int lo = (int)fmaxf(1.0f, roundf(3 * c->k)), hi1 = (int)fmaxf((float)lo, roundf(5 * c->k)),
        hi2 = (int)fmaxf((float)lo, roundf(10 * c->k)), pad = hi2 / 2 + 3;
    int ex0 = c->bx - pad < 0 ? 0 : c->bx - pad;
    int ex1 = c->bx + c->bw + pad > c->n ? c->n : c->bx + c->bw + pad, ew = ex1 - ex0;
    int *widths = NULL;
    if (!st && c->bw > 0) {
        widths = malloc((size_t)ew * (size_t)c->bh * sizeof(int));
        e1 = ss_image_create_uninit(ew, c->bh, 1, err);
        e2 = e1 ? ss_image_create_uninit(ew, c->bh, 1, err) : NULL;
        if (!e2 || !widths) {
            st = widths ? err->code : ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        } else {
            for (int y = 0; y < c->bh; y++)
                memcpy(ss_image_px(e2, 0, y), ss_image_px(c->w->mask, ex0, c->by + y),
                       (size_t)ew * sizeof(float));
            ss_erosion_widths_rect(c->n, c->n, ex0, c->by, ew, c->bh, lo, hi1, c->s->seed,
                                   ST_ERODE1, widths);
            ss_erode(e2, widths, e1);
            ss_erosion_widths_rect(c->n, c->n, ex0, c->by, ew, c->bh, lo, hi2, c->s->seed,
                                   ST_ERODE2, widths);
            ss_erode(e1, widths, e2);
        }
    }
    if (!st) {
#pragma omp parallel for schedule(static)
        for (int y = c->ry; y < c->ry + c->rh; y++)
            for (size_t i = (size_t)y * (size_t)c->n + (size_t)c->rx, e = i + (size_t)c->rw; i < e;
                 i++) {
                if (c->w->mask->data[i] <= 0.5f) {
                    outside_glow(c, i, out);
                    continue;
                }
                float rgb[3];
                float sc = scrape->data[box_index(c, c->bx, c->by, c->bw, i)];
                int bed = e2->data[box_index(c, ex0, c->by, ew, i)] > 0.5f;
                if (bed) {
                    /* Inside: lower skin multiplied by the red (§4.3.2). */
                    const float *lo_s = c->skin->lower_srgb->data + i * 3;
                    for (int k = 0; k < 3; k++) rgb[k] = lo_s[k] * GLOW_RED[k];
                } else {
                    /* The edge of half scraped-off skin. */
                    const float *up = c->skin->upper_srgb->data + i * 3;
                    for (int k = 0; k < 3; k++) rgb[k] = up[k] * EDGE_GREY;
                }
                out->reflection->data[i] = sc;
                out->height->data[i] = bed ? 0.5f - WOUND_DEPTH + SCRAPE_RELIEF * (sc - 0.5f)
                                           : 0.5f - 0.5f * WOUND_DEPTH;
                put_color(c, out->color->data + i * 3, rgb);
            }
    }
    ss_image_free(scrape);
    ss_image_free(e1);
    ss_image_free(e2);
    free(widths);
    return st;
}

static ss_status render_scab_forming(const ctx *c, ss_texture_set *out, ss_error *err) {
    ss_image *low = NULL, *speck = NULL, *scrape = NULL;
    /* Bottom layer: 5 octaves, 0.85 persistence, 0.54 bias, 0.21 gain. */
    ss_status st = noise(c, 5, 0.85f, 0.54f, 0.21f, 1.0f, ST_SCABFORM_LOW, &low, err);
    /* Speckles: 5 octaves, 0.48 persistence, 0.16 bias, 0.15 gain. */
    if (!st) st = noise(c, 5, 0.48f, 0.16f, 0.15f, 1.0f, ST_SCABFORM_SPECKLE, &speck, err);
    /* The scrape lines stay visible in the reflection while the bed dries. */
    if (!st) st = noise(c, 5, 0.09f, 0.5f, 0.43f, 64.0f, ST_SCRAPE, &scrape, err);
    if (!st) {
#pragma omp parallel for schedule(static)
        for (int y = c->ry; y < c->ry + c->rh; y++)
            for (size_t i = (size_t)y * (size_t)c->n + (size_t)c->rx, e = i + (size_t)c->rw; i < e;
                 i++) {
                if (c->w->mask->data[i] <= 0.5f) {
                    outside_glow(c, i, out);
                    continue;
                }
                size_t b = box_index(c, c->bx, c->by, c->bw, i);
                const float *lo_s = c->skin->lower_srgb->data + i * 3;
                const float *up = c->skin->upper_srgb->data + i * 3;
                float ln = low->data[b], lower_wound[3], sp[3], rgb[3];
                /* Eq. 4.5 */
                for (int k = 0; k < 3; k++) lower_wound[k] = lo_s[k] * ln + up[k] * (1.0f - ln);
                /* Eq. 4.6: speckle colour = noise x (0.88, 0.20, 0.22), weighted by its red. */
                for (int k = 0; k < 3; k++) sp[k] = speck->data[b] * SPECKLE_RED[k];
                for (int k = 0; k < 3; k++)
                    rgb[k] = sp[k] * sp[0] + lower_wound[k] * (1.0f - sp[0]);
                out->reflection->data[i] = 0.7f * scrape->data[b];
                /* The redder parts are carved deeper (§4.3.3). */
                out->height->data[i] = 0.5f - WOUND_DEPTH * (0.5f + ln) - WOUND_DEPTH * sp[0];
                put_color(c, out->color->data + i * 3, rgb);
            }
    }
    ss_image_free(low);
    ss_image_free(speck);
    ss_image_free(scrape);
    return st;
}

static ss_status render_scab(const ctx *c, ss_texture_set *out, ss_error *err) {
    ss_image *mask_n = NULL, *mid = NULL, *redn = NULL, *refl = NULL;
    /* Height = mask noise (7, 1.0, 0.44, 0.02) x middle noise (5, 0.54, 0.3, 0.69). */
    ss_status st = noise(c, 7, 1.0f, 0.44f, 0.02f, 1.0f, ST_SCAB_MASK, &mask_n, err);
    if (!st) st = noise(c, 5, 0.54f, 0.3f, 0.69f, 1.0f, ST_SCAB_MIDDLE, &mid, err);
    /* Red details mask: 5 octaves, 0.33 persistence, 0.60 bias, 0.59 gain. */
    if (!st) st = noise(c, 5, 0.33f, 0.60f, 0.59f, 1.0f, ST_SCAB_RED, &redn, err);
    /* Reflection: 10 octaves, 1.0 persistence, 0.25 bias, 0.95 gain. */
    if (!st) st = noise(c, 10, 1.0f, 0.25f, 0.95f, 1.0f, ST_SCAB_REFLECT, &refl, err);
    if (!st) {
#pragma omp parallel for schedule(static)
        for (int y = c->ry; y < c->ry + c->rh; y++)
            for (size_t i = (size_t)y * (size_t)c->n + (size_t)c->rx, e = i + (size_t)c->rw; i < e;
                 i++) {
                if (c->w->mask->data[i] <= 0.5f) {
                    outside_glow(c, i, out);
                    continue;
                }
                size_t b = box_index(c, c->bx, c->by, c->bw, i);
                float h = mask_n->data[b] * mid->data[b];
                float in_col[3], grad[3] = {0, 0, 0}, rgb[3];
                /* Higher crust is the lighter, yellowish colour (docs/abrasion.md). */
                lerp3(SCAB_DARK, SCAB_LIGHT, h, in_col);
                /* Inward gradient, thickness 100, from (0.5, 0.04, 0.03) to
                 * black, masked by the red-detail noise. */
                float t = ss_gradient_weight(1, c->w->dist->data[i], gradient_px(c), 1);
                if (t >= 0.0f) {
                    static const float black[3] = {0, 0, 0};
                    lerp3(SCAB_RED, black, t, grad);
                    for (int k = 0; k < 3; k++) grad[k] *= redn->data[b];
                }
                /* Eq. 4.7 */
                for (int k = 0; k < 3; k++) rgb[k] = in_col[k] + grad[k] * (1.0f - in_col[k]);
                out->reflection->data[i] = refl->data[b];
                out->height->data[i] = 0.5f + 0.5f * h;
                put_color(c, out->color->data + i * 3, rgb);
            }
    }
    ss_image_free(mask_n);
    ss_image_free(mid);
    ss_image_free(redn);
    ss_image_free(refl);
    return st;
}

/* Alg. 4.4 for one pixel (display-space colour); returns 0 for pixels
 * outside the wound, which stay healthy skin. */
static inline int maturation_color(const ctx *c, size_t i, double position, float *rgb) {
    const float *skin = c->skin->upper_srgb->data + i * 3;
    int l = c->w->label[i];
    if (c->w->mask->data[i] <= 0.5f || l < 0) return 0;
    double closing = c->w->closing_px[l];
    double max_outer = closing * 0.5; /* Eq. 4.8 */
    double outer = max_outer * position;
    double inner = outer + max_outer * c->w->inner_ratio[l];
    double d = c->w->dist->data[i];
    if (d <= outer) {
        memcpy(rgb, skin, 3 * sizeof(float));
    } else if (d <= inner) {
        float t = (float)((d - outer) / (inner - outer));
        lerp3(skin, GLOW_RED, t, rgb);
    } else {
        double span = closing * 0.5 - inner;
        float t = span > 0 ? (float)((d - inner) / span) : 1.0f;
        lerp3(GLOW_RED, WOUND_WHITE, t < 0 ? 0 : t > 1 ? 1 : t, rgb);
    }
    return 1;
}

static ss_status render_maturation(const ctx *c, double position, ss_texture_set *out,
                                   ss_error *err) {
    (void)err;
    /* Reflection, height and normal stay those of healthy skin. */
#pragma omp parallel for schedule(static)
    for (int y = c->by; y < c->by + c->bh; y++)
        for (size_t i = (size_t)y * (size_t)c->n + (size_t)c->bx, e = i + (size_t)c->bw; i < e;
             i++) {
            float rgb[3];
            if (maturation_color(c, i, position, rgb)) put_color(c, out->color->data + i * 3, rgb);
        }
    return SS_OK;
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

ss_status ss_abrasion_maturation_color(const ss_wound_shape *w, const ss_base_skin *skin,
                                       const ss_abrasion_settings *s, double position,
                                       ss_image *color, ss_error *err) {
    if (!(position >= 0.0 && position <= 1.0))
        return ss_error_set(err, SS_ERR_INPUT, "maturation position %g is outside 0..1", position);
    ctx c;
    ctx_init(&c, w, skin, s);
#pragma omp parallel for schedule(static)
    for (int y = c.by; y < c.by + c.bh; y++)
        for (int x = c.bx; x < c.bx + c.bw; x++) {
            size_t i = (size_t)y * (size_t)c.n + (size_t)x;
            float rgb[3];
            if (maturation_color(&c, i, position, rgb)) put_color(&c, color->data + i * 3, rgb);
        }
    return SS_OK;
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
