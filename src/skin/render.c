/* From biological parameter maps to render maps (seed 003 §4.8.8 line 16,
 * mmd(FEATURE(...))): every texel's optical parameters go through the
 * ModelMatch table (optics_fit.h, the same table `skinsim optics table
 * --lookup` reads) to the GGX render parameters; the extra colour (an over
 * layer; `skin` writes none, its hair is pigment) is laid over the base
 * colour; height becomes a normal map.
 *
 * The lookup: ss_mm_table_lookup interpolates all 18 fields of an entry in
 * double over 64 corners with a weight product per corner. A texture needs
 * 5 of them at millions of texels, so ss_skin_lut copies the GGX base
 * colour, specular and roughness of every node (read through the public
 * table struct) into 8 floats, and interpolates by successive linear
 * interpolation along the axes (63 8-wide lerps, which vectorise). Colours
 * (base colour, subsurface radius) are stored as logs and interpolated in
 * log space, as ss_mm_table_lookup does (albedo is about exponential in the
 * absorbers), and the blood axis weighs in sqrt(blood), as ss_mm_table_lookup
 * does (docs/modelmatch.md). The result equals ss_mm_table_lookup's to float rounding
 * (tested); a new table file plugs in unchanged.
 *
 * The surface: specular and roughness come from the table's surface curve
 * at the texel's surface roughness sigma (bio channel SS_BIO_SURFACE_SIGMA,
 * set by the surface state in texgen), and the base colour is scaled so the
 * albedo is kept under that lobe (ss_mm_surface_lobe). Furrows and follicle
 * openings occlude the lobe: specular x (1 - 0.5 (1 - cavity)), cavity from
 * the height below its 0.25 mm neighbourhood. */
#include "skinsim/skin.h"
#include "skinsim/texture.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define LUT_F 8 /* log base R, G, B, specular, roughness, log radius R, G, B */
#define LUT_LOG_MIN 1e-9f

struct ss_skin_lut {
    int n[SS_MM_NAXES];
    size_t stride[SS_MM_NAXES];
    float *axis[SS_MM_NAXES];
    size_t corner[64]; /* node offset of each cell corner from the cell's first node */
    float *node;       /* nentries x LUT_F */
    /* surface curve: sigma, specular, roughness, base colour scale per node */
    int nsurf;
    float s_sigma[SS_MM_MAX_SURFACE], s_spec[SS_MM_MAX_SURFACE], s_rough[SS_MM_MAX_SURFACE],
        s_scale[SS_MM_MAX_SURFACE];
};

void ss_skin_lut_free(ss_skin_lut *l) {
    if (!l) return;
    for (int a = 0; a < SS_MM_NAXES; a++) free(l->axis[a]);
    free(l->node);
    free(l);
}

ss_skin_lut *ss_skin_lut_create(const ss_mm_table *t, ss_error *err) {
    if (!t || !t->entries || t->nentries == 0) {
        ss_error_set(err, SS_ERR_INPUT, "ModelMatch table: empty");
        return NULL;
    }
    ss_skin_lut *l = calloc(1, sizeof *l);
    if (!l) goto nomem;
    size_t stride = 1;
    for (int a = SS_MM_NAXES - 1; a >= 0; a--) {
        l->n[a] = t->nsamples[a];
        l->stride[a] = stride;
        stride *= (size_t)t->nsamples[a];
        l->axis[a] = malloc((size_t)t->nsamples[a] * sizeof(float));
        if (!l->axis[a]) goto nomem;
        for (int i = 0; i < t->nsamples[a]; i++) l->axis[a][i] = (float)t->axis[a][i];
    }
    /* corner c: bit (5 - a) set = upper node on axis a (0 when the axis has
     * one sample), so axis 0 is reduced first over contiguous halves */
    for (int c = 0; c < 64; c++) {
        size_t off = 0;
        for (int a = 0; a < SS_MM_NAXES; a++)
            if (((c >> (5 - a)) & 1) && l->n[a] > 1) off += l->stride[a];
        l->corner[c] = off;
    }
    l->node = calloc(t->nentries * LUT_F, sizeof(float));
    if (!l->node) goto nomem;
    for (size_t e = 0; e < t->nentries; e++) {
        ss_mm_entry en;
        ss_mm_entry_unpack(t->entries + e * SS_MM_NFIELDS, &en);
        const ss_render_params *g = &en.fit[SS_RENDER_GGX];
        float *o = l->node + e * LUT_F;
        for (int c = 0; c < 3; c++) {
            o[c] = logf(fmaxf((float)g->base_rgb[c], LUT_LOG_MIN));
            o[5 + c] = logf(fmaxf((float)en.sss_radius_cm[c], LUT_LOG_MIN));
        }
        o[3] = (float)g->specular;
        o[4] = (float)g->roughness;
        for (int c = 0; c < LUT_F; c++)
            if (!isfinite(o[c])) {
                ss_error_set(err, SS_ERR_INPUT, "ModelMatch table: entry %zu is not finite", e);
                ss_skin_lut_free(l);
                return NULL;
            }
    }
    l->nsurf = t->nsurface >= 2 ? t->nsurface : 0;
    for (int k = 0; k < l->nsurf; k++) {
        double sp, ro, sc;
        ss_mm_surface_lobe(t, t->surf_sigma[k], &sp, &ro, &sc);
        l->s_sigma[k] = (float)t->surf_sigma[k];
        l->s_spec[k] = (float)sp;
        l->s_rough[k] = (float)ro;
        l->s_scale[k] = (float)sc;
    }
    return l;
nomem:
    ss_skin_lut_free(l);
    ss_error_set(err, SS_ERR_NOMEM, "ModelMatch lookup: out of memory");
    return NULL;
}

/* Lookup state of one thread: the corners of the last few cells (8 slots,
 * direct-mapped by the cell's first node): the baseline noise moves texels
 * between a handful of neighbouring cells, and gathering 64 corners is the
 * expensive part of a lookup. */
#define LUT_SLOTS 8
typedef struct lut_cache {
    size_t base[LUT_SLOTS];
    float cor[LUT_SLOTS][LUT_F][64];
} lut_cache;

static void lut_cache_init(lut_cache *c) {
    for (int i = 0; i < LUT_SLOTS; i++) c->base[i] = (size_t)-1;
}

/* The lookup with `nslots` cached cells (base[], cor[]; nslots a power of 2). */
static inline void lut_lookup_slots(const ss_skin_lut *l, size_t *cbase, float (*ccor)[LUT_F][64],
                                    int nslots, const float x[6], float out[LUT_F]) {
    size_t base = 0;
    float fr[SS_MM_NAXES];
    for (int a = 0; a < SS_MM_NAXES; a++) {
        const int n = l->n[a];
        const float *v = l->axis[a];
        fr[a] = 0.0f;
        if (n == 1) continue;
        float xa = x[a];
        if (!(xa > v[0])) xa = v[0];
        if (xa > v[n - 1]) xa = v[n - 1];
        int i = 0;
        while (i < n - 2 && xa >= v[i + 1]) i++;
        if (a == SS_MM_AXIS_BLOOD && v[i] >= 0.0f) /* as ss_mm_table_lookup */
            fr[a] = (sqrtf(xa) - sqrtf(v[i])) / (sqrtf(v[i + 1]) - sqrtf(v[i]));
        else
            fr[a] = (xa - v[i]) / (v[i + 1] - v[i]);
        base += (size_t)i * l->stride[a];
    }
    const int slot =
        nslots > 1 ? (int)(((uint64_t)base * 0x9E3779B97F4A7C15ull) >> 61) & (nslots - 1) : 0;
    float(*cor)[64] = ccor[slot];
    if (base != cbase[slot]) {
        cbase[slot] = base;
        for (int k = 0; k < 64; k++) {
            const float *nd = l->node + (base + l->corner[k]) * LUT_F;
            for (int f = 0; f < LUT_F; f++) cor[f][k] = nd[f];
        }
    }
    /* fixed trip counts so that the lerps vectorise */
#define LERP_LEVEL(DST, SRC, HALF, A)                                                              \
    do {                                                                                           \
        const float w1 = fr[A], w0 = 1.0f - w1;                                                    \
        for (int j = 0; j < HALF; j++) DST[j] = SRC[j] * w0 + SRC[j + HALF] * w1;                  \
    } while (0)
    for (int f = 0; f < LUT_F; f++) {
        float b[32];
        LERP_LEVEL(b, cor[f], 32, 0);
        LERP_LEVEL(b, b, 16, 1);
        LERP_LEVEL(b, b, 8, 2);
        LERP_LEVEL(b, b, 4, 3);
        LERP_LEVEL(b, b, 2, 4);
        LERP_LEVEL(b, b, 1, 5);
        out[f] = b[0];
    }
#undef LERP_LEVEL
    for (int c = 0; c < 3; c++) {
        out[c] = expf(out[c]);
        out[5 + c] = expf(out[5 + c]);
    }
}

/* The surface curve at sigma: specular, roughness, base colour scale. */
static inline void lut_surface(const ss_skin_lut *l, float sigma, float *sp, float *ro, float *sc) {
    const int n = l->nsurf;
    const float *v = l->s_sigma;
    float s = sigma;
    if (!(s > v[0])) s = v[0];
    if (s > v[n - 1]) s = v[n - 1];
    int i = 0;
    while (i < n - 2 && s >= v[i + 1]) i++;
    const float f = (s - v[i]) / (v[i + 1] - v[i]);
    *sp = l->s_spec[i] + f * (l->s_spec[i + 1] - l->s_spec[i]);
    *ro = l->s_rough[i] + f * (l->s_rough[i + 1] - l->s_rough[i]);
    *sc = l->s_scale[i] + f * (l->s_scale[i + 1] - l->s_scale[i]);
}

static inline void apply_surface(const ss_skin_lut *l, float sigma, float out[LUT_F]) {
    if (l->nsurf < 2) return;
    float sp, ro, sc;
    lut_surface(l, sigma, &sp, &ro, &sc);
    out[0] *= sc, out[1] *= sc, out[2] *= sc;
    out[3] = sp;
    out[4] = ro;
}

static inline void lut_lookup(const ss_skin_lut *l, lut_cache *c, const float x[6],
                              float out[LUT_F]) {
    lut_lookup_slots(l, c->base, c->cor, LUT_SLOTS, x, out);
}

void ss_skin_lut_lookup(const ss_skin_lut *l, const float x[6], float out[5]) {
    /* one slot on the stack: no allocation per call (callers that look up
     * texel after texel, such as the wound renderer, call this) */
    struct {
        size_t base[1];
        float cor[1][LUT_F][64];
    } one;
    one.base[0] = (size_t)-1;
    float r[LUT_F];
    lut_lookup_slots(l, one.base, one.cor, 1, x, r);
    memcpy(out, r, 5 * sizeof(float));
}

struct ss_skin_lut_cache {
    lut_cache c;
};

ss_skin_lut_cache *ss_skin_lut_cache_create(void) {
    ss_skin_lut_cache *c = malloc(sizeof *c);
    if (c) lut_cache_init(&c->c);
    return c;
}

void ss_skin_lut_cache_free(ss_skin_lut_cache *c) { free(c); }

void ss_skin_lut_lookup_cached(const ss_skin_lut *l, ss_skin_lut_cache *c, const float x[6],
                               float out[5]) {
    if (!c) {
        ss_skin_lut_lookup(l, x, out);
        return;
    }
    float r[LUT_F];
    lut_lookup(l, &c->c, x, r);
    memcpy(out, r, 5 * sizeof(float));
}

void ss_skin_lut_lookup_surface(const ss_skin_lut *l, const float x[6], float sigma, float out[8]) {
    struct {
        size_t base[1];
        float cor[1][LUT_F][64];
    } one;
    one.base[0] = (size_t)-1;
    lut_lookup_slots(l, one.base, one.cor, 1, x, out);
    apply_surface(l, sigma, out);
}

void ss_skin_bio_texel(const ss_image *bio, int x, int y, ss_bio_params *out) {
    ss_bio_params_default(out);
    const float *p = ss_image_px(bio, x, y);
    out->melanin = p[SS_BIO_MELANIN];
    out->pheomelanin_ratio = p[SS_BIO_PHEOMELANIN];
    out->blood = p[SS_BIO_BLOOD];
    out->oxygenation = p[SS_BIO_OXYGENATION];
    out->sc_thickness_cm = p[SS_BIO_SC_CM];
    out->epidermis_thickness_cm = p[SS_BIO_EPIDERMIS_CM];
}

void ss_skin_maps_free(ss_skin_maps *m) {
    if (!m) return;
    ss_image_free(m->base_color);
    ss_image_free(m->roughness);
    ss_image_free(m->specular);
    ss_image_free(m->height_mm);
    ss_image_free(m->normal);
    ss_image_free(m->translucency);
    ss_image_free(m->cavity);
    memset(m, 0, sizeof *m);
}

/* Cavity: how far a texel lies below the mean height of its neighbourhood
 * (a box of +-0.25 mm, wrapped), over CAVITY_DEPTH_MM: 1 on plateaus and
 * ridges, 0 at the bottom of a furrow 0.05 mm deep. Separable running
 * sums, so O(1) per texel whatever the texel size; tmp holds W x H floats. */
#define CAVITY_RADIUS_MM 0.25
#define CAVITY_DEPTH_MM 0.05
static void cavity_map(const ss_image *h, double texel_mm, float *tmp, ss_image *out) {
    const int W = h->width, H = h->height;
    int R = (int)lround(CAVITY_RADIUS_MM / texel_mm);
    if (R < 1) R = 1;
    if (2 * R + 1 > W) R = (W - 1) / 2;
    if (2 * R + 1 > H) R = (H - 1) / 2;
        /* the wraps by compare, not %, and the column pass over blocks of
         * columns a row at a time (each column's sum is updated in the same
         * order as one column at a time, so the values are the same) */
#pragma omp parallel for schedule(static)
    for (int y = 0; y < H; y++) {
        const float *row = h->data + (size_t)y * W;
        double s = 0;
        for (int k = -R; k <= R; k++) s += row[((k % W) + W) % W];
        for (int x = 0; x < W; x++) {
            tmp[(size_t)y * W + x] = (float)(s / (2 * R + 1));
            int xa = x + R + 1, xb = x - R;
            if (xa >= W) xa -= W;
            if (xb < 0) xb += W;
            s += row[xa] - row[xb];
        }
    }
    enum { CB = 64 };
    const int nblk = (W + CB - 1) / CB;
#pragma omp parallel for schedule(static)
    for (int blk = 0; blk < nblk; blk++) {
        const int x0 = blk * CB, nx = W - x0 < CB ? W - x0 : CB;
        double s[CB];
        for (int i = 0; i < nx; i++) s[i] = 0;
        for (int k = -R; k <= R; k++) {
            const float *t = tmp + (size_t)(((k % H) + H) % H) * W + x0;
            for (int i = 0; i < nx; i++) s[i] += t[i];
        }
        for (int y = 0; y < H; y++) {
            int ya = y + R + 1, yb = y - R;
            if (ya >= H) ya -= H;
            if (yb < 0) yb += H;
            const float *hr = h->data + (size_t)y * W + x0, *ta = tmp + (size_t)ya * W + x0,
                        *tb = tmp + (size_t)yb * W + x0;
            float *o = out->data + (size_t)y * W + x0;
            for (int i = 0; i < nx; i++) {
                const double mean = s[i] / (2 * R + 1);
                const double d = (mean - hr[i]) / CAVITY_DEPTH_MM;
                o[i] = (float)(d <= 0 ? 1.0 : d >= 1 ? 0.0 : 1.0 - d);
                s[i] += ta[i] - tb[i];
            }
        }
    }
}

ss_status ss_skin_render_maps(const ss_image *bio, const ss_skin_lut *lut, double world_size_cm,
                              int normal_directx, ss_skin_maps *out, ss_error *err) {
    return ss_skin_render_maps_poll(bio, lut, world_size_cm, normal_directx, out, NULL, NULL, err);
}

ss_status ss_skin_render_maps_poll(const ss_image *bio, const ss_skin_lut *lut,
                                   double world_size_cm, int normal_directx, ss_skin_maps *out,
                                   ss_progress_fn fn, void *user, ss_error *err) {
    memset(out, 0, sizeof *out);
    if (!bio || bio->channels != SS_BIO_NCHANNELS || !lut)
        return ss_error_set(err, SS_ERR_INPUT, "render maps: need a %d-channel bio map",
                            SS_BIO_NCHANNELS);
    if (!(world_size_cm > 0.0))
        return ss_error_set(err, SS_ERR_INPUT, "render maps: world size %g cm", world_size_cm);
    const int W = bio->width, H = bio->height;
    if (!(out->base_color = ss_image_create_uninit(W, H, 3, err)) ||
        !(out->roughness = ss_image_create_uninit(W, H, 1, err)) ||
        !(out->specular = ss_image_create_uninit(W, H, 1, err)) ||
        !(out->height_mm = ss_image_create_uninit(W, H, 1, err)) ||
        !(out->normal = ss_image_create_uninit(W, H, 3, err)) ||
        !(out->translucency = ss_image_create_uninit(W, H, 3, err)) ||
        !(out->cavity = ss_image_create_uninit(W, H, 1, err))) {
        ss_skin_maps_free(out);
        return err->code;
    }
    const size_t n = (size_t)W * (size_t)H;
    double hmin = INFINITY, hmax = -INFINITY;
    /* with a progress callback the texels go in bands of rows, polled
     * between them (a texel's values do not depend on the band, nor the
     * height's minimum and maximum on the order) */
    const size_t band = fn ? (size_t)W * (size_t)(H / 32 > 16 ? H / 32 : 16) : n;
    for (size_t i0 = 0; i0 < n; i0 += band) {
        const size_t i1 = n - i0 > band ? i0 + band : n;
#pragma omp parallel reduction(min : hmin) reduction(max : hmax)
        {
            lut_cache *cache = malloc(sizeof *cache);
            if (cache) lut_cache_init(cache);
#pragma omp for schedule(static)
            for (size_t i = i0; i < i1; i++) {
                const float *p = bio->data + i * SS_BIO_NCHANNELS;
                float r[LUT_F];
                if (cache) {
                    lut_lookup(lut, cache, p, r);
                    apply_surface(lut, p[SS_BIO_SURFACE_SIGMA], r);
                } else
                    ss_skin_lut_lookup_surface(lut, p, p[SS_BIO_SURFACE_SIGMA], r);
                for (int c = 0; c < 3; c++) out->translucency->data[i * 3 + c] = r[5 + c];
                const float a = p[SS_BIO_EXTRA_A];
                for (int c = 0; c < 3; c++) {
                    float b = r[c] < 0.0f ? 0.0f : r[c] > 1.0f ? 1.0f : r[c];
                    out->base_color->data[i * 3 + c] = b * (1.0f - a) + p[SS_BIO_EXTRA_R + c] * a;
                }
                out->specular->data[i] = r[3] < 0.0f ? 0.0f : r[3] > 1.0f ? 1.0f : r[3];
                out->roughness->data[i] = r[4] < 0.0f ? 0.0f : r[4] > 1.0f ? 1.0f : r[4];
                const float h = p[SS_BIO_HEIGHT_MM];
                out->height_mm->data[i] = h;
                if (h < hmin) hmin = h;
                if (h > hmax) hmax = h;
            }
            free(cache);
        }
        if (fn && fn(user, 0.8 * (double)i1 / (double)n)) {
            ss_skin_maps_free(out);
            return ss_error_set(err, SS_ERR_RUNTIME, "skin render maps: cancelled");
        }
    }
    const double texel_mm = world_size_cm * 10.0 / W;
    /* the cavity map's row sums go in the normal map's memory (3 floats a
     * texel, not yet written): fresh pages cost faults (16 MB at 2048^2) */
    cavity_map(out->height_mm, texel_mm, out->normal->data, out->cavity);
    ss_height_to_normal(out->height_mm, (float)(1.0 / texel_mm), out->normal);
    /* furrows and follicle openings shadow the specular lobe */
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++)
        out->specular->data[i] *= 1.0f - 0.5f * (1.0f - out->cavity->data[i]);
    if (normal_directx)
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < n; i++)
            out->normal->data[i * 3 + 1] = 1.0f - out->normal->data[i * 3 + 1];
    out->height_min_mm = hmin;
    out->height_max_mm = hmax;
    if (fn) fn(user, 1.0); /* done: a stop now changes nothing */
    return SS_OK;
}
