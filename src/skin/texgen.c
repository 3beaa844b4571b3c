/* TexGen (seed 003 §4.8.8): the spatial index of the features and the texel
 * evaluation into biological parameter maps (§4.8.5 blend, §5.3 features).
 *
 * Spatial index: the texture is cut into 32 x 32 texel tiles; every feature
 * is listed in each tile its support box overlaps (the seed suggests an
 * R-tree; a uniform tile grid answers "which features touch this texel" in
 * O(1) and suits features of similar size). On the torus (wrap, §4.8.7) a
 * box crossing an edge is also listed, with a -1/+1 texture offset, in the
 * tiles on the other side, so features wrap and the maps tile. Lists are
 * built in feature order, and features are ordered by type = priority, so
 * within a tile the list is already the blend order.
 *
 * Texels: tiles are independent (OpenMP over tiles); inside a tile the
 * baseline skin is written first, then the lips, then each listed feature
 * over the texels of its box in list order, so each texel sees the
 * features in priority order (§4.8.5: everything that adds blood before the
 * follicles take it away). Features colour the skin only through its
 * pigment (add_melanin: above the table's top melanin, a thicker pigmented
 * layer), hair too, so the table renders them at every tone. The
 * baseline noise is a per-texel uniform per parameter (§5.3.1, phi x range
 * width), drawn from the counter-based RNG by texel index, so the result
 * does not depend on tiles or threads.
 *
 * Supports (where a feature is evaluated): cyst and mole 2 r (the sigmoid
 * profile is below 7e-4 there), freckle r / 1.2 (its profile is 0 beyond),
 * follicle r_o, wrinkle the control points' box grown by the width (a cubic
 * lies in the hull of its control points). Inside it, per row, only the x
 * range where the boxes of a 16-segment flattening of the curve (grown by
 * the width and a texel) meet the row gets the golden-section distance. */
#include "skin_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define TILE 32
#define MOLE_BORDER_MAX 1.0 /* mm; the upper bound of moles.border */

const char *ss_bio_channel_name(int c) {
    static const char *const names[SS_BIO_NCHANNELS] = {
        "melanin",     "pheomelanin_ratio", "blood",
        "oxygenation", "sc_thickness_cm",   "epidermis_thickness_cm",
        "height_mm",   "extra.R",           "extra.G",
        "extra.B",     "extra.A",           "surface_roughness"};
    return c >= 0 && c < SS_BIO_NCHANNELS ? names[c] : "unknown";
}

typedef struct entry {
    uint32_t feature;
    int16_t ox, oy; /* texture-unit offset of this copy (torus) */
} entry;

typedef struct tile_index {
    int ntiles;    /* per side */
    size_t *start; /* ntiles^2 + 1 */
    entry *e;
} tile_index;

/* Follicles smaller than a texel are area-sampled: n x n points per texel
 * (n = ceil(2 texel / r_i), at most 8), so an opening of 0.08 mm on 0.2 mm
 * texels darkens its texel by the fraction it covers instead of painting a
 * full-contrast dot or nothing, depending on where it falls (point sampling:
 * texel-sized pepper whose look changed with --size). A follicle whose core
 * is at least a texel wide keeps the single sample at the texel centre. */
static int follicle_subsamples(const ss_skin_feature *f, double mm_per_unit, int size) {
    const double texel_mm = mm_per_unit / size;
    if (f->type != SS_FEAT_FOLLICLE || !(texel_mm > f->r) || !(f->r > 0.0)) return 1;
    const double n = ceil(2.0 * texel_mm / f->r);
    return n > 8.0 ? 8 : (int)n;
}

/* Support box of a feature in texture units. */
static void support_box(const ss_skin_feature *f, double mm_per_unit, int size, double *x0,
                        double *y0, double *x1, double *y1) {
    double R = 0.0;
    switch (f->type) {
    case SS_FEAT_CYST:
        R = 2.0 * f->r;
        break;
    case SS_FEAT_MOLE: /* the border, and 8 % of irregular outline */
        R = 1.1 * f->r + 0.5 * MOLE_BORDER_MAX;
        break;
    case SS_FEAT_FRECKLE:
        R = f->r / 1.2;
        break;
    case SS_FEAT_FOLLICLE: /* area-sampled: the texels a sample can reach */
        R = f->r2 > f->r ? f->r2 : f->r;
        if (follicle_subsamples(f, mm_per_unit, size) > 1) R += mm_per_unit / size;
        break;
    case SS_FEAT_WRINKLE: {
        double w = f->w / mm_per_unit;
        *x0 = *x1 = f->curve.x[0];
        *y0 = *y1 = f->curve.y[0];
        for (int i = 1; i < 4; i++) {
            if (f->curve.x[i] < *x0) *x0 = f->curve.x[i];
            if (f->curve.x[i] > *x1) *x1 = f->curve.x[i];
            if (f->curve.y[i] < *y0) *y0 = f->curve.y[i];
            if (f->curve.y[i] > *y1) *y1 = f->curve.y[i];
        }
        *x0 -= w, *y0 -= w, *x1 += w, *y1 += w;
        return;
    }
    default:
        break;
    }
    R /= mm_per_unit;
    *x0 = f->x - R, *x1 = f->x + R, *y0 = f->y - R, *y1 = f->y + R;
}

/* Calls visit(ti, tj, ox, oy) for every tile the box overlaps. */
#define FOR_TILES(...)                                                                             \
    do {                                                                                           \
        double bx0, by0, bx1, by1;                                                                 \
        support_box(f, mm_per_unit, size, &bx0, &by0, &bx1, &by1);                                 \
        long tx0 = (long)floor(bx0 * size / TILE), tx1 = (long)floor(bx1 * size / TILE);           \
        long ty0 = (long)floor(by0 * size / TILE), ty1 = (long)floor(by1 * size / TILE);           \
        if (tx1 - tx0 >= nt) tx1 = tx0 + nt - 1;                                                   \
        if (ty1 - ty0 >= nt) ty1 = ty0 + nt - 1;                                                   \
        if (!wrap) {                                                                               \
            if (tx0 < 0) tx0 = 0;                                                                  \
            if (ty0 < 0) ty0 = 0;                                                                  \
            if (tx1 >= nt) tx1 = nt - 1;                                                           \
            if (ty1 >= nt) ty1 = nt - 1;                                                           \
        }                                                                                          \
        for (long ty = ty0; ty <= ty1; ty++)                                                       \
            for (long tx = tx0; tx <= tx1; tx++) {                                                 \
                long wx = ((tx % nt) + nt) % nt, wy = ((ty % nt) + nt) % nt;                       \
                int ox = (int)((wx - tx) / nt), oy = (int)((wy - ty) / nt);                        \
                size_t tile = (size_t)wy * (size_t)nt + (size_t)wx;                                \
                __VA_ARGS__;                                                                       \
            }                                                                                      \
    } while (0)

static ss_status index_build(const ss_skin_feature_list *l, const uint32_t *order, int size,
                             double mm_per_unit, int wrap, tile_index *ix, ss_error *err) {
    const long nt = (size + TILE - 1) / TILE;
    ix->ntiles = (int)nt;
    ix->start = calloc((size_t)(nt * nt + 1), sizeof *ix->start);
    ix->e = NULL;
    if (!ix->start) return ss_error_set(err, SS_ERR_NOMEM, "feature index: out of memory");
    for (size_t q = 0; q < l->n; q++) {
        const ss_skin_feature *f = &l->f[order[q]];
        FOR_TILES((void)ox; (void)oy; ix->start[tile + 1]++);
    }
    for (long t = 0; t < nt * nt; t++) ix->start[t + 1] += ix->start[t];
    size_t total = ix->start[nt * nt];
    ix->e = malloc((total ? total : 1) * sizeof *ix->e);
    size_t *fill = malloc((size_t)(nt * nt) * sizeof *fill);
    if (!ix->e || !fill) {
        free(fill);
        return ss_error_set(err, SS_ERR_NOMEM, "feature index: out of memory (%zu entries)", total);
    }
    memcpy(fill, ix->start, (size_t)(nt * nt) * sizeof *fill);
    for (size_t q = 0; q < l->n; q++) {
        const ss_skin_feature *f = &l->f[order[q]];
        FOR_TILES(ix->e[fill[tile]++] = (entry){order[q], (int16_t)ox, (int16_t)oy});
    }
    free(fill);
    return SS_OK;
}

static void index_free(tile_index *ix) {
    free(ix->start);
    free(ix->e);
}

/* Per-wrinkle data for the texel pass: the flattened curve. */
#define FLAT 16
typedef struct wrinkle_flat {
    float x[FLAT + 1], y[FLAT + 1];
} wrinkle_flat;

/* Whether (px, py) lies within r of one of the listed segments of a
 * flattened wrinkle (squared distances, so no square root per texel). */
static int near_segments(const wrinkle_flat *wf, const int *seg, int nseg, float px, float py,
                         float r) {
    for (int k = 0; k < nseg; k++) {
        const int i = seg[k];
        const float ax = wf->x[i], ay = wf->y[i];
        const float dx = wf->x[i + 1] - ax, dy = wf->y[i + 1] - ay;
        const float l2 = dx * dx + dy * dy;
        float t = l2 > 0.0f ? ((px - ax) * dx + (py - ay) * dy) / l2 : 0.0f;
        t = t < 0.0f ? 0.0f : t > 1.0f ? 1.0f : t;
        const float ex = ax + t * dx - px, ey = ay + t * dy - py;
        if (ex * ex + ey * ey <= r * r) return 1;
    }
    return 0;
}

/* What the texel pass shares: the mottling, the relief network, fields. */
typedef struct texel_ctx {
    const ss_skin_settings *s;
    const ss_skin_fields *fields;
    const skin_mottle *mot;
    const skin_relief *rel;
} texel_ctx;

static float field01(const ss_image *img, double u, double v, float dflt) {
    if (!img) return dflt;
    float w;
    ss_image_sample_wrap(img, (float)u, (float)v, &w);
    return w < 0.0f ? 0.0f : w > 1.0f ? 1.0f : w;
}

/* Per-tile scratch: the groove of the relief network and the melanin
 * mottle per texel (moles and freckles read them). */
typedef struct tile_scratch {
    float groove[TILE * TILE], mottle[TILE * TILE];
} tile_scratch;

/* Baseline skin for one tile (§5.3.1 with mottling in mm), the microrelief
 * network, the lips (§5.3.6), a scar and the surface state. */
static void tile_baseline(const texel_ctx *c, int tx0, int ty0, int tw, int th, ss_image *bio,
                          tile_scratch *sc) {
    const ss_skin_settings *s = c->s;
    const ss_skin_dist *d = &s->dist;
    const int size = s->size;
    float mean[6], wid[6];
    for (int a = 0; a < 6; a++) {
        wid[a] = (float)(s->phi * (s->base_hi[a] - s->base_lo[a]));
        mean[a] = (float)s->base_lo[a] + 0.5f * wid[a];
    }
    const ss_image *lips = c->fields->lips, *scar = c->fields->scar;
    for (int y = ty0; y < ty0 + th; y++) {
        for (int x = tx0; x < tx0 + tw; x++) {
            const double u = (x + 0.5) / size, v = (y + 0.5) / size;
            float *p = ss_image_px(bio, x, y);
            float m[MOTTLE_F];
            skin_mottle_eval(c->mot, u, v, m);
            /* melanin and blood: log-normal mottling around the baseline
             * value base_lo (their chromophore maps vary by a factor, not
             * an offset; the seed's band of phi x range on top of the low
             * end added 0.02 melanin to every skin, so very light skin was
             * out of reach); the others within the seed's phi band */
            p[SS_BIO_MELANIN] = (float)s->base_lo[0] * expf((float)d->mottle_melanin * m[0]);
            p[SS_BIO_BLOOD] = (float)s->base_lo[2] * expf((float)d->mottle_blood * m[2]);
            for (int a = 0; a < 6; a++) {
                if (a == SS_BIO_MELANIN || a == SS_BIO_BLOOD) continue;
                float q = mean[a] + 0.29f * wid[a] * m[a];
                float lo = (float)s->base_lo[a];
                p[a] = q < lo ? lo : q > lo + wid[a] ? lo + wid[a] : q;
            }
            p[SS_BIO_HEIGHT_MM] = (float)d->mottle_height * m[MOT_HEIGHT]; /* gentle undulation */
            /* no extra colour: the hair is pigment (follicles) */
            p[7] = p[8] = p[9] = p[10] = 0.0f;
            /* the relief network, oriented by the wrinkle field (read every
             * 8 texels: it turns over millimetres) */
            float g;
            float hr = skin_relief_eval(c->rel, u, v, &g);
            const float S = field01(scar, u, v, 0.0f);
            hr *= 1.0f - 0.85f * S, g *= 1.0f - 0.85f * S; /* scars lose the microrelief */
            p[SS_BIO_HEIGHT_MM] += hr;
            p[SS_BIO_MELANIN] *= 1.0f + 0.12f * g; /* lines read slightly darker */
            const int k = (y - ty0) * TILE + (x - tx0);
            sc->groove[k] = g;
            sc->mottle[k] = m[0];
            /* surface state -> the surface's roughness (docs/skin.md): water
             * in the stratum corneum and a sebum film smooth it */
            float hyd = field01(c->fields->hydration, u, v, (float)d->surface_hydration);
            float seb = field01(c->fields->sebum, u, v, (float)d->surface_sebum) *
                        expf(0.4f * m[MOT_SEBUM]);
            if (seb > 1.0f) seb = 1.0f;
            float sig = (float)d->surface_sigma_dry * (1.0f - 0.4f * hyd) * (1.0f - 0.5f * seb);
            sig += (0.75f - sig) * 0.6f * g; /* the lines' walls are rough */
            if (lips) {
                float w = field01(lips, u, v, 0.0f);
                p[SS_BIO_BLOOD] += ((float)d->lip_blood - p[SS_BIO_BLOOD]) * w;
                p[SS_BIO_PHEOMELANIN] += ((float)d->lip_pheomelanin - p[SS_BIO_PHEOMELANIN]) * w;
                sig += (0.22f - sig) * w; /* the moist vermilion is glossy */
            }
            if (S > 0.0f) { /* scar: paler, pinker, smooth and shiny */
                p[SS_BIO_MELANIN] *= 1.0f - 0.4f * S;
                p[SS_BIO_BLOOD] += (0.02f - p[SS_BIO_BLOOD]) * 0.4f * S;
                sig += (0.25f - sig) * S;
            }
            p[SS_BIO_SURFACE_SIGMA] = sig;
        }
    }
}

/* Adds melanin dm to a texel (a feature's pigment). Above the top of the
 * melanin range (base_hi: the table's axis, 0.43), which the lookup would
 * clamp, the excess goes into the thickness of the pigmented layer: melanin
 * x epidermis thickness, the melanin the light crosses, grows as asked, up
 * to the epidermis range's top. So a mole on dark skin still darkens (as
 * naevi do at every tone) instead of stopping at the table's darkest
 * melanin. Continuous in dm; a texel already above the top (the baseline's
 * mottle) keeps its melanin and scales its thickness. */
static inline void add_melanin(const ss_skin_settings *s, float *p, float dm) {
    const float top = (float)s->base_hi[SS_BIO_MELANIN];
    const float e_top = (float)s->base_hi[SS_BIO_EPIDERMIS_CM];
    const float m0 = p[SS_BIO_MELANIN], mt = m0 + dm;
    float scale = 1.0f;
    if (m0 >= top && m0 > 0.0f)
        scale = mt / m0;
    else if (mt > top && top > 0.0f)
        p[SS_BIO_MELANIN] = top, scale = mt / top;
    else
        p[SS_BIO_MELANIN] = mt > 0.0f ? mt : 0.0f;
    if (scale != 1.0f) {
        const float e0 = p[SS_BIO_EPIDERMIS_CM], lim = e0 > e_top ? e0 : e_top;
        const float e = e0 * (scale > 0.0f ? scale : 0.0f);
        p[SS_BIO_EPIDERMIS_CM] = e < lim ? e : lim;
    }
}

/* One feature over the texels of its box inside the tile. */
static void apply_feature(const ss_skin_settings *s, const ss_skin_feature *f, uint32_t fi,
                          const wrinkle_flat *wf, double ox, double oy, int tx0, int ty0, int tw,
                          int th, double mm_per_unit, ss_image *bio, const tile_scratch *sc) {
    const int size = s->size;
    double bx0, by0, bx1, by1;
    support_box(f, mm_per_unit, size, &bx0, &by0, &bx1, &by1);
    bx0 += ox, bx1 += ox, by0 += oy, by1 += oy;
    int x0 = (int)floor(bx0 * size - 0.5), x1 = (int)ceil(bx1 * size - 0.5);
    int y0 = (int)floor(by0 * size - 0.5), y1 = (int)ceil(by1 * size - 0.5);
    if (x0 < tx0) x0 = tx0;
    if (y0 < ty0) y0 = ty0;
    if (x1 > tx0 + tw - 1) x1 = tx0 + tw - 1;
    if (y1 > ty0 + th - 1) y1 = ty0 + th - 1;
    const double cx = f->x + ox, cy = f->y + oy;
    const ss_skin_dist *d = &s->dist;
    const int nss = follicle_subsamples(f, mm_per_unit, size);
    if (f->type == SS_FEAT_WRINKLE) {
        /* per row, the x range where a flattened segment's box grown by the
         * reach (the width, plus a texel for the flattening) meets the row;
         * only those texels get the golden-section distance */
        const float R = (float)(f->w / mm_per_unit) + 1.0f / (float)size;
        skin_bezier3_prep bq;
        skin_bezier3_prepare(&f->curve, &bq);
        for (int y = y0; y <= y1; y++) {
            const double v = (y + 0.5) / size;
            const float fv = (float)(v - oy);
            float xmin = INFINITY, xmax = -INFINITY;
            int seg[FLAT], nseg = 0;
            for (int i = 0; i < FLAT; i++) {
                float ya = fminf(wf->y[i], wf->y[i + 1]) - R,
                      yb = fmaxf(wf->y[i], wf->y[i + 1]) + R;
                if (fv < ya || fv > yb) continue;
                seg[nseg++] = i;
                xmin = fminf(xmin, fminf(wf->x[i], wf->x[i + 1]) - R);
                xmax = fmaxf(xmax, fmaxf(wf->x[i], wf->x[i + 1]) + R);
            }
            if (!(xmin <= xmax)) continue;
            int xa = (int)floor((xmin + ox) * size - 0.5), xb = (int)ceil((xmax + ox) * size - 0.5);
            if (xa < x0) xa = x0;
            if (xb > x1) xb = x1;
            for (int x = xa; x <= xb; x++) {
                const double u = (x + 0.5) / size;
                /* a texel farther than the reach from every flattened
                 * segment of this row is farther than the width from the
                 * curve (the same bound as the boxes; 1 % slack for float
                 * rounding): skip the golden section */
                if (!near_segments(wf, seg, nseg, (float)(u - ox), fv, R * 1.01f)) continue;
                double t;
                double dist = skin_bezier3_distance_prep(&bq, u - ox, v - oy, 8, 2e-3,
                                                         f->w / mm_per_unit, &t) *
                              mm_per_unit;
                double prof = ss_profile_wrinkle(dist, ss_wrinkle_taper(t, f->w));
                if (prof > 0.0) {
                    float *p = ss_image_px(bio, x, y);
                    p[SS_BIO_HEIGHT_MM] -= (float)(prof * f->h);
                    /* a furrow: slightly darker (as melanin, so it follows
                     * the tone) and rough-walled */
                    add_melanin(s, p, (float)(0.15 * prof) * p[SS_BIO_MELANIN]);
                    p[SS_BIO_SURFACE_SIGMA] +=
                        (0.75f - p[SS_BIO_SURFACE_SIGMA]) * (float)(0.5 * prof);
                }
            }
        }
        return;
    }
    for (int y = y0; y <= y1; y++)
        for (int x = x0; x <= x1; x++) {
            const double u = (x + 0.5) / size, v = (y + 0.5) / size;
            float *p = ss_image_px(bio, x, y);
            const double dist = sqrt((u - cx) * (u - cx) + (v - cy) * (v - cy)) * mm_per_unit;
            switch (f->type) {
            case SS_FEAT_CYST:
                if (dist < 2.0 * f->r)
                    p[SS_BIO_HEIGHT_MM] += (float)(ss_profile_sigmoid(dist, f->r) * f->h);
                break;
            case SS_FEAT_MOLE: {
                /* a naevus: a sharp border (moles.border wide), a slightly
                 * irregular outline, uniform or reticular pigment; melanin
                 * added in proportion to M and grows with the skin's own
                 * melanin (1 + moles.tone_gain melanin), beyond the table's
                 * top as a thicker pigmented layer: the contrast follows
                 * the tone */
                const double a = ss_profile_mole(dist, ss_mole_outline(f->r, atan2(v - cy, u - cx)),
                                                 d->mole_border);
                if (a > 0.0) {
                    const int k = (y - ty0) * TILE + (x - tx0);
                    const double pat = f->p > 0.5 ? 0.45 + 0.55 * sqrt(sc->groove[k]) : 1.0;
                    add_melanin(
                        s, p,
                        (float)(a * pat * f->m * (1.0 + d->mole_tone_gain * p[SS_BIO_MELANIN])));
                    p[SS_BIO_HEIGHT_MM] += (float)(f->h * a * f->m);
                }
                break;
            }
            case SS_FEAT_FRECKLE: {
                double a = ss_profile_freckle(dist, f->r);
                if (a > 0.0) {
                    /* the seed's per-texel U is the melanin mottle here (in
                     * mm, not per texel); contrast follows the tone */
                    const float mt = sc->mottle[(y - ty0) * TILE + (x - tx0)];
                    double U = 0.6 + 0.25 * mt;
                    U = U < 0.1 ? 0.1 : U > 1.0 ? 1.0 : U;
                    add_melanin(
                        s, p,
                        (float)(a * f->m * U * (1.0 + d->freckle_tone_gain * p[SS_BIO_MELANIN])));
                    p[SS_BIO_PHEOMELANIN] += (float)(a * f->p * U);
                }
                break;
            }
            case SS_FEAT_FOLLICLE: {
                /* al: the alpha; pit: its part outside r_i (the opening);
                 * core: the fraction inside r_i (the stub) */
                double al = ss_profile_follicle(dist, f->r, f->r2), pit, core;
                if (nss == 1) {
                    pit = dist > f->r ? al : 0.0;
                    core = dist <= f->r ? 1.0 : 0.0;
                } else {
                    al = pit = core = 0.0;
                    for (int j = 0; j < nss; j++)
                        for (int i = 0; i < nss; i++) {
                            const double su = u + ((i + 0.5) / nss - 0.5) / size,
                                         sv = v + ((j + 0.5) / nss - 0.5) / size;
                            const double ds =
                                sqrt((su - cx) * (su - cx) + (sv - cy) * (sv - cy)) * mm_per_unit;
                            const double a = ss_profile_follicle(ds, f->r, f->r2);
                            al += a;
                            if (ds > f->r)
                                pit += a;
                            else
                                core += 1.0;
                        }
                    const double inv = 1.0 / (nss * nss);
                    al *= inv, pit *= inv, core *= inv;
                }
                if (al > 0.0) {
                    /* the hair: pigment that the table renders, melanin
                     * m_h = hair_melanin + hair_gain x the texel's melanin
                     * (lighter hair on light skin, black on dark), its
                     * pheomelanin a constant amount of it; the texel goes
                     * to the hair's pigment by the alpha (its coverage) */
                    const double m = p[SS_BIO_MELANIN];
                    double mh = d->hair_melanin + d->hair_gain * m;
                    double ph = mh > 0.0 ? d->hair_pheomelanin / mh : 0.0;
                    if (ph > 1.0) ph = 1.0;
                    /* no more than the darkest the table renders (the top
                     * melanin through the thickest epidermis): beyond it the
                     * stub is no darker, only the fade around it would be */
                    const double e = p[SS_BIO_EPIDERMIS_CM];
                    const double mmax =
                        e > 0.0 ? s->base_hi[SS_BIO_MELANIN] * s->base_hi[SS_BIO_EPIDERMIS_CM] / e
                                : mh;
                    if (mh > mmax && mmax > m) mh = mmax;
                    add_melanin(s, p, (float)((mh - m) * al));
                    p[SS_BIO_PHEOMELANIN] += (float)((ph - p[SS_BIO_PHEOMELANIN]) * al);
                    p[SS_BIO_BLOOD] *= (float)(1.0 - d->follicle_blood_drop * al);
                    /* the opening around the hair: a shallow pit, rough */
                    if (pit > 0.0) p[SS_BIO_HEIGHT_MM] -= (float)(0.012 * pit);
                    p[SS_BIO_SURFACE_SIGMA] += (0.8f - p[SS_BIO_SURFACE_SIGMA]) * (float)(0.6 * al);
                    if (core > 0.0 && p[SS_BIO_HEIGHT_MM] < d->follicle_height)
                        p[SS_BIO_HEIGHT_MM] =
                            core >= 1.0
                                ? (float)d->follicle_height
                                : p[SS_BIO_HEIGHT_MM] +
                                      (float)((d->follicle_height - p[SS_BIO_HEIGHT_MM]) * core);
                }
                break;
            }
            default:
                break;
            }
            (void)fi;
        }
}

static ss_image *bio_maps(const ss_skin_settings *s, const ss_skin_fields *fields,
                          const ss_skin_feature_list *l, ss_skin_timing *tm, ss_progress_fn fn,
                          void *user, ss_error *err) {
    ss_status st = ss_skin_settings_validate(s, err);
    if (st) return NULL;
    static const ss_skin_fields none;
    if (!fields) fields = &none;
    for (size_t i = 0; i < l->n; i++) {
        const ss_skin_feature *f = &l->f[i];
        if (f->type < 0 || f->type >= SS_FEAT_NTYPES) {
            ss_error_set(err, SS_ERR_INPUT, "feature %zu: unknown type %d", i, f->type);
            return NULL;
        }
        /* sizes up to 1 m and positions within 10 textures of this one keep
         * every box computation finite */
        int ok = fabs(f->x) <= 10.0 && fabs(f->y) <= 10.0;
        const double len[5] = {f->r, f->r2, f->h, f->w, f->m + f->p};
        for (int k = 0; k < 5; k++) ok &= len[k] >= 0.0 && len[k] <= 1000.0;
        for (int k = 0; k < 4 && f->type == SS_FEAT_WRINKLE; k++)
            ok &= fabs(f->curve.x[k]) <= 10.0 && fabs(f->curve.y[k]) <= 10.0;
        if (!ok) {
            ss_error_set(err, SS_ERR_INPUT,
                         "feature %zu (%s): a size outside 0..1000 mm, a position outside "
                         "-10..10 texture units, or not a number",
                         i, ss_feature_type_name(f->type));
            return NULL;
        }
    }
    if (l->n > 0xffffffffu) {
        ss_error_set(err, SS_ERR_INPUT, "too many features (%zu)", l->n);
        return NULL;
    }
    double t0 = ss_now();
    const double mm_per_unit = s->world_size_cm * 10.0;
    const int size = s->size;
    /* priority order: stable sort of indices by type (merge of per-type runs) */
    uint32_t *order = malloc((l->n ? l->n : 1) * sizeof *order);
    wrinkle_flat *flat = NULL;
    size_t nw = 0;
    for (size_t i = 0; i < l->n; i++) nw += l->f[i].type == SS_FEAT_WRINKLE;
    uint32_t *flat_of = calloc(l->n ? l->n : 1, sizeof *flat_of);
    flat = malloc((nw ? nw : 1) * sizeof *flat);
    ss_image *bio = NULL;
    tile_index ix = {0};
    skin_mottle mot = {0};
    skin_relief rel = {0};
    if (!order || !flat || !flat_of) {
        ss_error_set(err, SS_ERR_NOMEM, "features: out of memory");
        goto done;
    }
    {
        size_t q = 0;
        for (int t = 0; t < SS_FEAT_NTYPES; t++)
            for (size_t i = 0; i < l->n; i++)
                if (l->f[i].type == t) order[q++] = (uint32_t)i;
        size_t w = 0;
        for (size_t i = 0; i < l->n; i++)
            if (l->f[i].type == SS_FEAT_WRINKLE) {
                flat_of[i] = (uint32_t)w;
                for (int k = 0; k <= FLAT; k++) {
                    double x, y;
                    ss_bezier3_eval(&l->f[i].curve, (double)k / FLAT, &x, &y);
                    flat[w].x[k] = (float)x;
                    flat[w].y[k] = (float)y;
                }
                w++;
            }
    }
    if (index_build(l, order, size, mm_per_unit, s->wrap, &ix, err)) goto done;
    if (skin_mottle_init(&mot, s, err)) goto done;
    if (skin_relief_init(&rel, s, fields->wrinkle_vectors, err)) goto done;
    double t1 = ss_now();
    bio = ss_image_create_uninit(size, size, SS_BIO_NCHANNELS, err);
    if (!bio) goto done;
    const int nt = ix.ntiles;
    const texel_ctx ctx = {s, fields, &mot, &rel};
    int nomem = 0, cancelled = 0;
    /* with a progress callback the tiles go in bands of tile rows, polled
     * between them (tiles are independent: the bands change no value) */
    const int band = fn ? (nt / 32 > 1 ? nt / 32 : 1) : nt;
    for (int tb = 0; tb < nt && !nomem && !cancelled; tb += band) {
        const int t0 = tb * nt, t1 = (nt - tb > band ? tb + band : nt) * nt;
#pragma omp parallel
        {
            tile_scratch *sc = malloc(sizeof *sc);
            if (!sc) {
#pragma omp atomic write
                nomem = 1;
            }
#pragma omp for schedule(dynamic, 4)
            for (int t = t0; t < t1; t++) {
                if (!sc) continue;
                const int tx0 = (t % nt) * TILE, ty0 = (t / nt) * TILE;
                const int tw = tx0 + TILE <= size ? TILE : size - tx0;
                const int th = ty0 + TILE <= size ? TILE : size - ty0;
                tile_baseline(&ctx, tx0, ty0, tw, th, bio, sc);
                for (size_t q = ix.start[t]; q < ix.start[t + 1]; q++) {
                    const entry *e = &ix.e[q];
                    const ss_skin_feature *f = &l->f[e->feature];
                    apply_feature(s, f, e->feature,
                                  f->type == SS_FEAT_WRINKLE ? &flat[flat_of[e->feature]] : NULL,
                                  e->ox, e->oy, tx0, ty0, tw, th, mm_per_unit, bio, sc);
                }
                /* clamp fractions and the surface roughness */
                for (int y = ty0; y < ty0 + th; y++)
                    for (int x = tx0; x < tx0 + tw; x++) {
                        float *p = ss_image_px(bio, x, y);
                        for (int a = 0; a < 4; a++)
                            p[a] = p[a] < 0.0f ? 0.0f : p[a] > 1.0f ? 1.0f : p[a];
                        float sg = p[SS_BIO_SURFACE_SIGMA];
                        p[SS_BIO_SURFACE_SIGMA] = sg < 0.05f ? 0.05f : sg > 1.5f ? 1.5f : sg;
                    }
            }
            free(sc);
        }
        if (fn && !nomem && fn(user, (double)t1 / ((double)nt * nt))) cancelled = 1;
    }
    if (nomem || cancelled) {
        if (nomem)
            ss_error_set(err, SS_ERR_NOMEM, "texels: out of memory");
        else
            ss_error_set(err, SS_ERR_RUNTIME, "skin bio maps: cancelled");
        ss_image_free(bio);
        bio = NULL;
        goto done;
    }
    if (tm) {
        tm->index_s = t1 - t0;
        tm->texels_s = ss_now() - t1;
    }
done:
    skin_mottle_free(&mot);
    skin_relief_free(&rel);
    index_free(&ix);
    free(order);
    free(flat);
    free(flat_of);
    return bio;
}

ss_image *ss_skin_bio_maps_timed(const ss_skin_settings *s, const ss_skin_fields *fields,
                                 const ss_skin_feature_list *l, ss_skin_timing *tm, ss_error *err) {
    return bio_maps(s, fields, l, tm, NULL, NULL, err);
}

ss_image *ss_skin_bio_maps_poll(const ss_skin_settings *s, const ss_skin_fields *fields,
                                const ss_skin_feature_list *features, ss_progress_fn fn, void *user,
                                ss_error *err) {
    return bio_maps(s, fields, features, NULL, fn, user, err);
}

ss_image *ss_skin_bio_maps(const ss_skin_settings *s, const ss_skin_fields *fields,
                           const ss_skin_feature_list *features, ss_error *err) {
    return ss_skin_bio_maps_timed(s, fields, features, NULL, err);
}

ss_image *ss_skin_bio_default(int size, double world_size_cm, uint64_t seed, ss_error *err) {
    ss_skin_settings s;
    if (ss_skin_settings_preset(&s, "forearm", size, err)) return NULL;
    s.world_size_cm = world_size_cm;
    s.seed = seed;
    ss_skin_forearm_counts(world_size_cm, s.count);
    ss_skin_feature_list l;
    if (ss_skin_generate(&s, NULL, &l, NULL, 0, err)) return NULL;
    ss_image *bio = ss_skin_bio_maps(&s, NULL, &l, err);
    ss_skin_feature_list_free(&l);
    return bio;
}
