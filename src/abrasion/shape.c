/* Wound shape at one texture size (seed 000 §4.2): hull per stroke (convex,
 * Alg. 4.1, or concave k-NN) with its corners rounded (ss_stroke_outlines), filled by scanlines,
 * the distance of every pixel to the outline (what Alg. 3.4 and 4.4 loop over every hull edge for),
 * and per wound the closing distance of Alg. 4.3 and the rand(0.4, 0.8) of Eq. 4.8. Mask input:
 * each connected component is one wound and its outline is the mask boundary. */
#include "skinsim/abrasion.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void ss_wound_shape_free(ss_wound_shape *w) {
    if (!w) return;
    ss_image_free(w->mask);
    ss_image_free(w->dist);
    ss_image_free(w->smooth);
    free(w->label);
    free(w->closing_px);
    free(w->inner_ratio);
    for (int i = 0; i < w->npolys; i++) ss_polygon_free(&w->polys[i]);
    free(w->polys);
    free(w);
}

static ss_wound_shape *shape_alloc(int size, int nwounds, ss_error *err) {
    ss_wound_shape *w = calloc(1, sizeof *w);
    if (!w) return ss_error_set(err, SS_ERR_NOMEM, "out of memory"), NULL;
    w->size = size;
    w->nwounds = nwounds;
    w->mask = ss_image_create(size, size, 1, err);
    w->dist = w->mask ? ss_image_create(size, size, 1, err) : NULL;
    w->label = malloc((size_t)size * (size_t)size * sizeof(int));
    w->closing_px = calloc((size_t)(nwounds > 0 ? nwounds : 1), sizeof(double));
    w->inner_ratio = calloc((size_t)(nwounds > 0 ? nwounds : 1), sizeof(double));
    if (!w->dist || !w->label || !w->closing_px || !w->inner_ratio) {
        if (w->dist)
            ss_error_set(err, SS_ERR_NOMEM, "out of memory for a %dx%d wound shape", size, size);
        ss_wound_shape_free(w);
        return NULL;
    }
    return w;
}

static void find_box(ss_wound_shape *w) {
    int n = w->size, x0 = n, y0 = n, x1 = -1, y1 = -1;
    for (int y = 0; y < n; y++) {
        const float *row = w->mask->data + (size_t)y * (size_t)n;
        for (int x = 0; x < n; x++)
            if (row[x] > 0.5f) {
                if (x < x0) x0 = x;
                if (x > x1) x1 = x;
                if (y < y0) y0 = y;
                y1 = y;
            }
    }
    w->box_x = x1 >= 0 ? x0 : 0;
    w->box_y = y1 >= 0 ? y0 : 0;
    w->box_w = x1 >= 0 ? x1 - x0 + 1 : 0;
    w->box_h = y1 >= 0 ? y1 - y0 + 1 : 0;
}

/* One pass of a running-sum box filter of radius r along rows (dir 0) or
 * columns (dir 1) of the w x h block at (x0, y0) of src into dst, clamped at
 * the block's edges. */
static void box_pass(const float *src, float *dst, int n, int x0, int y0, int w, int h, int r,
                     int dir) {
    int lines = dir ? w : h, len = dir ? h : w;
#pragma omp parallel for schedule(static)
    for (int l = 0; l < lines; l++) {
        size_t step = dir ? (size_t)n : 1;
        size_t base = dir ? (size_t)y0 * (size_t)n + (size_t)(x0 + l)
                          : (size_t)(y0 + l) * (size_t)n + (size_t)x0;
        double acc = 0;
        for (int k = -r; k <= r; k++) {
            int q = k < 0 ? 0 : k >= len ? len - 1 : k;
            acc += src[base + (size_t)q * step];
        }
        for (int k = 0; k < len; k++) {
            dst[base + (size_t)k * step] = (float)(acc / (2 * r + 1));
            int out = k - r < 0 ? 0 : k - r, in = k + r + 1 >= len ? len - 1 : k + r + 1;
            acc += src[base + (size_t)in * step] - src[base + (size_t)out * step];
        }
    }
}

/* The smoothed signed distance (ss_wound_shape.smooth): three box passes each
 * way (close to a Gaussian) of a tenth of the largest closing distance, over
 * the box grown by the glow, so the fronts of maturation are rounded. */
static ss_status smooth_distance(ss_wound_shape *w, ss_error *err) {
    int n = w->size;
    w->smooth = ss_image_create(n, n, 1, err);
    ss_image *tmp = w->smooth ? ss_image_create(n, n, 1, err) : NULL;
    if (!tmp) return err->code;
    double cl = 1;
    for (int i = 0; i < w->nwounds; i++) cl = fmax(cl, w->closing_px[i]);
    int r = (int)lround(0.1 * cl / sqrt(3.0)); /* three passes: sd ~ r */
    int g = (int)ceil(SS_ABRASION_MAX_GRADIENT_REF_PX * n / 2048.0) + 2;
    int x0 = w->box_x - g < 0 ? 0 : w->box_x - g, y0 = w->box_y - g < 0 ? 0 : w->box_y - g;
    int x1 = w->box_x + w->box_w + g > n ? n : w->box_x + w->box_w + g;
    int y1 = w->box_y + w->box_h + g > n ? n : w->box_y + w->box_h + g;
    if (w->box_w == 0) x1 = x0, y1 = y0;
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            size_t i = (size_t)y * (size_t)n + (size_t)x;
            float d = w->dist->data[i];
            w->smooth->data[i] = w->mask->data[i] > 0.5f ? d : -d;
        }
    if (r >= 1 && x1 > x0 && y1 > y0)
        for (int pass = 0; pass < 3; pass++) {
            box_pass(w->smooth->data, tmp->data, n, x0, y0, x1 - x0, y1 - y0, r, 0);
            box_pass(tmp->data, w->smooth->data, n, x0, y0, x1 - x0, y1 - y0, r, 1);
        }
    ss_image_free(tmp);
    return SS_OK;
}

/* Eq. 4.8's rand(0.4, 0.8), one draw per wound from the run's seed. */
static void draw_inner_ratios(ss_wound_shape *w, uint64_t seed) {
    for (int i = 0; i < w->nwounds; i++)
        w->inner_ratio[i] = 0.4 + 0.4 * ss_rng_uniform(seed, 0xA8A5, (uint64_t)i);
}

ss_status ss_wound_shape_from_strokes(const ss_stroke_set *s, ss_hull_kind kind, int concave_k,
                                      int size, uint64_t seed, ss_wound_shape **out,
                                      ss_error *err) {
    *out = NULL;
    if (size < 1 || size > 16384)
        return ss_error_set(err, SS_ERR_INPUT, "texture size %d is out of range 1..16384", size);
    if (s->nstrokes < 1) return ss_error_set(err, SS_ERR_INPUT, "no strokes");
    int nids = s->nstrokes;
    ss_wound_shape *w = shape_alloc(size, nids, err);
    if (!w) return err->code;
    /* No name: the caller knows the file and prefixes it. */
    /* the hulls with rounded corners (src/geom/round.c): a four-point stroke
     * is a rounded quadrilateral, not a diamond */
    ss_status st = ss_stroke_outlines(s, size, size, kind == SS_HULL_CONCAVE ? concave_k : 0,
                                      SS_STROKE_ROUND, NULL, &w->polys, err);
    if (st) {
        ss_wound_shape_free(w);
        return st;
    }
    w->npolys = nids;
    for (int k = 0; k < nids; k++) w->closing_px[k] = ss_closing_distance(&w->polys[k]);
    /* Fill each hull; the label of a pixel is the first hull containing it. */
    size_t npx = (size_t)size * (size_t)size;
    for (size_t i = 0; i < npx; i++) w->label[i] = -1;
    ss_image *tmp = ss_image_create(size, size, 1, err);
    if (!tmp) {
        ss_wound_shape_free(w);
        return err->code;
    }
    for (int k = nids - 1; k >= 0; k--) {
        memset(tmp->data, 0, npx * sizeof(float));
        ss_polygon_fill(&w->polys[k], tmp);
        for (size_t i = 0; i < npx; i++)
            if (tmp->data[i] > 0.5f) {
                w->mask->data[i] = 1.0f;
                w->label[i] = k;
            }
    }
    ss_image_free(tmp);
    /* Exact distances are needed up to the widest gradient: the glow (100
     * reference px, see phases.c) outside, half the closing distance inside. */
    double maxd = SS_ABRASION_MAX_GRADIENT_REF_PX * size / 2048.0;
    for (int k = 0; k < nids; k++) maxd = fmax(maxd, 0.5 * w->closing_px[k]);
    st = ss_outline_distance(w->polys, w->npolys, maxd + 2.0, w->dist, err);
    if (st) {
        ss_wound_shape_free(w);
        return st;
    }
    int any = 0;
    for (size_t i = 0; i < npx && !any; i++) any = w->mask->data[i] > 0.5f;
    if (!any) {
        ss_wound_shape_free(w);
        return ss_error_set(err, SS_ERR_INPUT,
                            "the strokes cover no pixel at %dx%d: paint a larger shape", size,
                            size);
    }
    draw_inner_ratios(w, seed);
    find_box(w);
    if ((st = smooth_distance(w, err))) {
        ss_wound_shape_free(w);
        return st;
    }
    *out = w;
    return SS_OK;
}

/* 4-connected component labelling with an explicit stack. */
static int label_components(const ss_image *mask, int *label, ss_error *err) {
    int n = mask->width, ncomp = 0;
    size_t npx = (size_t)n * (size_t)n;
    for (size_t i = 0; i < npx; i++) label[i] = -1;
    size_t *stack = malloc(npx * sizeof(size_t));
    if (!stack) return ss_error_set(err, SS_ERR_NOMEM, "out of memory"), -1;
    for (size_t start = 0; start < npx; start++) {
        if (mask->data[start] <= 0.5f || label[start] >= 0) continue;
        size_t top = 0;
        stack[top++] = start;
        label[start] = ncomp;
        while (top) {
            size_t i = stack[--top];
            int x = (int)(i % (size_t)n), y = (int)(i / (size_t)n);
            const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
            for (int d = 0; d < 4; d++) {
                int xx = x + dx[d], yy = y + dy[d];
                if (xx < 0 || yy < 0 || xx >= n || yy >= n) continue;
                size_t j = (size_t)yy * (size_t)n + (size_t)xx;
                if (mask->data[j] > 0.5f && label[j] < 0) {
                    label[j] = ncomp;
                    stack[top++] = j;
                }
            }
        }
        ncomp++;
    }
    free(stack);
    return ncomp;
}

ss_status ss_wound_shape_from_mask(const ss_image *mask_in, int size, uint64_t seed,
                                   ss_wound_shape **out, ss_error *err) {
    *out = NULL;
    if (size < 1 || size > 16384)
        return ss_error_set(err, SS_ERR_INPUT, "texture size %d is out of range 1..16384", size);
    ss_image *m = ss_image_resize(mask_in, size, size, err);
    if (!m) return err->code;
    ss_wound_shape *w = shape_alloc(size, 0, err);
    if (!w) {
        ss_image_free(m);
        return err->code;
    }
    size_t npx = (size_t)size * (size_t)size;
    /* Wound = mean of the channels (grey, RGB or with alpha as coverage). */
    int ch = m->channels;
    for (size_t i = 0; i < npx; i++) {
        float v = 0;
        int cc = ch == 2 || ch == 4 ? ch - 1 : ch;
        for (int c = 0; c < cc; c++) v += m->data[i * (size_t)ch + (size_t)c];
        v /= (float)cc;
        if (ch == 2 || ch == 4) v *= m->data[i * (size_t)ch + (size_t)(ch - 1)];
        w->mask->data[i] = v > 0.5f ? 1.0f : 0.0f;
    }
    ss_image_free(m);
    int ncomp = label_components(w->mask, w->label, err);
    if (ncomp < 0) {
        ss_wound_shape_free(w);
        return err->code;
    }
    if (ncomp == 0) {
        ss_wound_shape_free(w);
        return ss_error_set(err, SS_ERR_INPUT,
                            "the wound mask is empty (no pixel above 50%% grey)");
    }
    free(w->closing_px);
    free(w->inner_ratio);
    w->nwounds = ncomp;
    w->closing_px = calloc((size_t)ncomp, sizeof(double));
    w->inner_ratio = calloc((size_t)ncomp, sizeof(double));
    /* Closing distance per component: Alg. 4.3 on the convex hull of its
     * boundary pixel corners (the farthest pair lies on the hull). */
    int *cnt = calloc((size_t)ncomp, sizeof(int));
    ss_vec2 **pts = calloc((size_t)ncomp, sizeof(ss_vec2 *));
    ss_status st = (w->closing_px && w->inner_ratio && cnt && pts)
                       ? SS_OK
                       : ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    for (int pass = 0; pass < 2 && !st; pass++) {
        if (pass == 1)
            for (int c = 0; c < ncomp && !st; c++) {
                pts[c] = malloc((size_t)cnt[c] * 4 * sizeof(ss_vec2));
                if (!pts[c]) st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
                cnt[c] = 0;
            }
        for (int y = 0; y < size && !st; y++)
            for (int x = 0; x < size; x++) {
                int l = w->label[(size_t)y * (size_t)size + (size_t)x];
                if (l < 0) continue;
                int edge = x == 0 || y == 0 || x == size - 1 || y == size - 1 ||
                           w->label[(size_t)y * (size_t)size + (size_t)x - 1] != l ||
                           w->label[(size_t)y * (size_t)size + (size_t)x + 1] != l ||
                           w->label[(size_t)(y - 1) * (size_t)size + (size_t)x] != l ||
                           w->label[(size_t)(y + 1) * (size_t)size + (size_t)x] != l;
                if (!edge) continue;
                if (pass == 1) {
                    ss_vec2 *p = pts[l] + cnt[l];
                    p[0] = (ss_vec2){x, y};
                    p[1] = (ss_vec2){x + 1, y};
                    p[2] = (ss_vec2){x, y + 1};
                    p[3] = (ss_vec2){x + 1, y + 1};
                }
                cnt[l] += pass == 1 ? 4 : 1;
            }
    }
    for (int c = 0; c < ncomp && !st; c++) {
        ss_polygon hull = {0, NULL};
        ss_error e2;
        if (ss_convex_hull(pts[c], cnt[c], &hull, &e2) == SS_OK) {
            w->closing_px[c] = ss_closing_distance(&hull);
            ss_polygon_free(&hull);
        } else {
            w->closing_px[c] = 1.0;
        }
    }
    for (int c = 0; pts && c < ncomp; c++) free(pts[c]);
    free(pts);
    free(cnt);
    if (st) {
        ss_wound_shape_free(w);
        return st;
    }
    /* Distance to the outline: the boundary lies half a pixel from the
     * centres of the pixels on either side of it. */
    ss_image *inv = ss_image_create(size, size, 1, err);
    ss_image *din = inv ? ss_image_create(size, size, 1, err) : NULL;
    if (!din) {
        ss_image_free(inv);
        ss_wound_shape_free(w);
        return err->code;
    }
    for (size_t i = 0; i < npx; i++) inv->data[i] = 1.0f - w->mask->data[i];
    st = ss_distance_transform(w->mask, w->dist, err);
    if (!st) st = ss_distance_transform(inv, din, err);
    for (size_t i = 0; i < npx && !st; i++) {
        float d = w->mask->data[i] > 0.5f ? din->data[i] : w->dist->data[i];
        if (!isfinite(d)) d = 1e9f; /* no boundary at all on this side */
        w->dist->data[i] = d > 0.5f ? d - 0.5f : 0.0f;
    }
    ss_image_free(inv);
    ss_image_free(din);
    if (st) {
        ss_wound_shape_free(w);
        return st;
    }
    draw_inner_ratios(w, seed);
    find_box(w);
    if ((st = smooth_distance(w, err))) {
        ss_wound_shape_free(w);
        return st;
    }
    *out = w;
    return SS_OK;
}
