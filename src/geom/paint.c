/* Painting strokes on a mesh (seed 000 §4.2.1): rays become UV samples.
 *
 * Each ray is cast into the mesh's BVH; the hit's barycentrics interpolate
 * the corner UVs (Eq. 4.1-4.3, done in ss_bvh_raycast). Where the seed
 * records only the centre of the brush, a ring of `ring` extra rays at the
 * brush radius records its footprint, so a click makes a disc and a drag a
 * band, and the hull (Alg. 4.1) covers what the user saw being painted.
 * Ring rays run parallel to the centre ray; a ring hit counts only when it
 * lands in the centre's UV island and within 3 radii of the centre hit
 * (not on a finger behind the one being painted).
 *
 * Seams: a stroke keeps one island. When the centre hit moves to another
 * island the stroke ends and a new id starts there, in the same group (one
 * press-drag-release), so undo removes the whole gesture but each island
 * gets its own hull. The seed's hand had one UV island per visible side;
 * skinsim's hand has three (DESIGN.md) and a wound across the palm/back
 * seam would otherwise get a hull spanning the empty UV space between them.
 *
 * Cuts inside an island: an island can also wrap (a UV sphere's u = 0/1
 * meridian when the poles join its columns, a cylinder closed by a cap), so
 * a short stroke across the cut would jump from u = 0.99 to u = 0.01 and its
 * hull cover the whole island. Every step is therefore checked against the
 * previous hit's triangle: its affine surface-to-UV map predicts where the
 * new point should land in UV; a landing further from the prediction than
 * twice the predicted step plus 0.02 (a smooth chart is close to linear over
 * a brush step; a cut is off by the island's width) starts a new stroke, as
 * an island change does. Ring samples are checked the same way against the
 * centre hit, so a brush on the cut keeps only its own side. Gave up: a cut
 * narrower than 0.02 in UV is not seen. */
#include "skinsim/paint.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

ss_status ss_paint_create(const ss_mesh *m, double brush_radius, ss_paint *p, ss_error *err) {
    memset(p, 0, sizeof *p);
    if (!m || !m->has_uvs)
        return ss_error_set(err, SS_ERR_INPUT,
                            "the mesh has no texture coordinates (UVs): nothing can be painted");
    if (!(brush_radius > 0) || !isfinite(brush_radius))
        return ss_error_set(err, SS_ERR_INPUT, "brush radius %g must be > 0", brush_radius);
    p->mesh = m;
    p->brush_radius = brush_radius;
    p->ring = 8;
    p->cur_group = p->cur_stroke = -1;
    p->island = malloc(sizeof *p->island * (size_t)m->ntriangles);
    if (!p->island) return ss_error_set(err, SS_ERR_NOMEM, "paint: out of memory");
    p->nislands = ss_mesh_uv_islands(m, p->island);
    if (p->nislands < 0) {
        ss_paint_free(p);
        return ss_error_set(err, SS_ERR_NOMEM, "paint: out of memory");
    }
    p->bvh = ss_bvh_build(m, err);
    if (!p->bvh) {
        ss_status st = err ? err->code : SS_ERR_NOMEM;
        ss_paint_free(p);
        return st;
    }
    return SS_OK;
}

void ss_paint_free(ss_paint *p) {
    if (!p) return;
    ss_bvh_free(p->bvh);
    free(p->island);
    free(p->s);
    memset(p, 0, sizeof *p);
}

static int push(ss_paint *p, const float uv[2], const float pos[3], int island) {
    if (p->n == p->cap) {
        int cap = p->cap ? 2 * p->cap : 1024;
        ss_paint_sample *s = realloc(p->s, sizeof *s * (size_t)cap);
        if (!s) return -1;
        p->s = s;
        p->cap = cap;
    }
    ss_paint_sample *s = &p->s[p->n++];
    s->uv[0] = uv[0], s->uv[1] = uv[1];
    for (int d = 0; d < 3; d++) s->pos[d] = pos ? pos[d] : NAN;
    s->stroke = p->cur_stroke;
    s->group = p->cur_group;
    s->island = island;
    return 0;
}

/* The UV that triangle t's own affine map gives the surface point q (its
 * projection onto t's plane, extrapolated outside t); 0 for a degenerate t. */
static int predict_uv(const ss_mesh *m, int t, const float q[3], float out[2]) {
    const uint32_t *ix = m->indices + 3 * (size_t)t;
    const float *a = m->positions + 3 * (size_t)ix[0], *b = m->positions + 3 * (size_t)ix[1],
                *c = m->positions + 3 * (size_t)ix[2];
    double v0[3], v1[3], v2[3], d00 = 0, d01 = 0, d11 = 0, d20 = 0, d21 = 0;
    for (int k = 0; k < 3; k++) {
        v0[k] = (double)b[k] - a[k], v1[k] = (double)c[k] - a[k], v2[k] = (double)q[k] - a[k];
        d00 += v0[k] * v0[k], d01 += v0[k] * v1[k], d11 += v1[k] * v1[k];
        d20 += v2[k] * v0[k], d21 += v2[k] * v1[k];
    }
    double den = d00 * d11 - d01 * d01;
    if (!(den > 1e-30 * (d00 * d11))) return 0;
    double wb = (d11 * d20 - d01 * d21) / den, wc = (d00 * d21 - d01 * d20) / den;
    double wa = 1.0 - wb - wc;
    const float *ua = m->uvs + 2 * (size_t)ix[0], *ub = m->uvs + 2 * (size_t)ix[1],
                *uc = m->uvs + 2 * (size_t)ix[2];
    for (int k = 0; k < 2; k++) out[k] = (float)(wa * ua[k] + wb * ub[k] + wc * uc[k]);
    return 1;
}

/* 1 when going from uv0 (on triangle t0) to the surface point q1 with UV
 * uv1 crosses no UV cut (see the top of this file). */
static int uv_continuous(const ss_mesh *m, int t0, const float uv0[2], const float q1[3],
                         const float uv1[2]) {
    float pr[2];
    if (!predict_uv(m, t0, q1, pr)) return 1; /* cannot tell: keep it */
    double step = hypot((double)pr[0] - uv0[0], (double)pr[1] - uv0[1]);
    double off = hypot((double)uv1[0] - pr[0], (double)uv1[1] - pr[1]);
    return off <= 2.0 * step + 0.02;
}

void ss_paint_begin(ss_paint *p) {
    p->cur_group = p->next_group++;
    p->cur_stroke = -1;
    p->cur_island = -1;
}

void ss_paint_end(ss_paint *p) { p->cur_group = p->cur_stroke = -1; }

int ss_paint_add(ss_paint *p, const float origin[3], const float dir[3], const float right[3],
                 const float up[3], ss_ray_hit *hit_out) {
    ss_ray_hit hit;
    int ok = ss_bvh_raycast(p->bvh, origin, dir, 0.0f, INFINITY, &hit);
    if (hit_out) *hit_out = hit;
    if (!ok || p->cur_group < 0) return ok;
    int isl = p->island[hit.triangle];
    float c[3];
    for (int d = 0; d < 3; d++) c[d] = origin[d] + hit.t * dir[d];
    if (p->cur_stroke < 0 || isl != p->cur_island ||
        !uv_continuous(p->mesh, p->cur_tri, p->cur_uv, c, hit.uv)) {
        p->cur_stroke = p->next_stroke++;
        p->cur_island = isl;
    }
    p->cur_tri = hit.triangle;
    for (int d = 0; d < 3; d++) p->cur_pos[d] = c[d];
    p->cur_uv[0] = hit.uv[0], p->cur_uv[1] = hit.uv[1];
    if (push(p, hit.uv, c, isl)) return ok;
    double r = p->brush_radius;
    for (int k = 0; k < p->ring; k++) {
        double a = 6.283185307179586 * k / p->ring;
        float o[3];
        for (int d = 0; d < 3; d++)
            o[d] = origin[d] + (float)(r * (cos(a) * right[d] + sin(a) * up[d]));
        ss_ray_hit h;
        if (!ss_bvh_raycast(p->bvh, o, dir, 0.0f, INFINITY, &h)) continue;
        if (p->island[h.triangle] != isl) continue;
        float q[3];
        double dist2 = 0;
        for (int d = 0; d < 3; d++) {
            q[d] = o[d] + h.t * dir[d];
            dist2 += (double)(q[d] - c[d]) * (q[d] - c[d]);
        }
        if (dist2 > 9 * r * r) continue;
        if (!uv_continuous(p->mesh, hit.triangle, hit.uv, q, h.uv)) continue;
        if (push(p, h.uv, q, isl)) break;
    }
    return ok;
}

int ss_paint_undo(ss_paint *p) {
    if (p->n == 0) return 0;
    int g = p->s[p->n - 1].group;
    while (p->n > 0 && p->s[p->n - 1].group == g) p->n--;
    return 1;
}

void ss_paint_clear(ss_paint *p) {
    p->n = 0;
    p->cur_group = p->cur_stroke = -1;
}

static int distinct_points(const ss_paint *p, int stroke, int limit) {
    /* Up to `limit` distinct UVs (enough to know whether a hull is possible). */
    float seen[8][2];
    int k = 0;
    for (int i = 0; i < p->n && k < limit && k < 8; i++) {
        if (p->s[i].stroke != stroke) continue;
        int dup = 0;
        for (int j = 0; j < k && !dup; j++)
            dup = seen[j][0] == p->s[i].uv[0] && seen[j][1] == p->s[i].uv[1];
        if (!dup) seen[k][0] = p->s[i].uv[0], seen[k][1] = p->s[i].uv[1], k++;
    }
    return k;
}

ss_status ss_paint_to_strokes(const ss_paint *p, ss_stroke_set *out, int *dropped, ss_error *err) {
    memset(out, 0, sizeof *out);
    int drop = 0;
    /* Stroke ids in order of first appearance, kept or not. */
    int maxid = -1;
    for (int i = 0; i < p->n; i++)
        if (p->s[i].stroke > maxid) maxid = p->s[i].stroke;
    int *newid = malloc(sizeof *newid * (size_t)(maxid + 2));
    if (!newid) return ss_error_set(err, SS_ERR_NOMEM, "paint: out of memory");
    for (int i = 0; i <= maxid; i++) newid[i] = -2; /* -2 unseen, -1 dropped */
    int k = 0, npts = 0;
    for (int i = 0; i < p->n; i++) {
        int s = p->s[i].stroke;
        if (s < 0) continue;
        if (newid[s] == -2) {
            if (distinct_points(p, s, 3) >= 3)
                newid[s] = k++;
            else
                newid[s] = -1, drop++;
        }
        if (newid[s] >= 0) npts++;
    }
    if (dropped) *dropped = drop;
    if (k == 0) {
        free(newid);
        return ss_error_set(err, SS_ERR_INPUT, "no strokes painted (a stroke needs 3 points)");
    }
    out->u = malloc(sizeof *out->u * (size_t)npts);
    out->v = malloc(sizeof *out->v * (size_t)npts);
    out->stroke = malloc(sizeof *out->stroke * (size_t)npts);
    out->stroke_ids = malloc(sizeof *out->stroke_ids * (size_t)k);
    if (!out->u || !out->v || !out->stroke || !out->stroke_ids) {
        free(newid);
        ss_stroke_set_free(out);
        return ss_error_set(err, SS_ERR_NOMEM, "paint: out of memory");
    }
    int j = 0;
    for (int i = 0; i < p->n; i++) {
        int s = p->s[i].stroke;
        if (s < 0 || newid[s] < 0) continue;
        /* Clamp: barycentric rounding can put an edge UV a hair outside 0..1. */
        double u = p->s[i].uv[0], v = p->s[i].uv[1];
        out->u[j] = u < 0 ? 0 : u > 1 ? 1 : u;
        out->v[j] = v < 0 ? 0 : v > 1 ? 1 : v;
        out->stroke[j] = newid[s];
        j++;
    }
    out->npoints = npts;
    out->nstrokes = k;
    for (int i = 0; i < k; i++) out->stroke_ids[i] = i;
    free(newid);
    return SS_OK;
}

ss_status ss_paint_save_csv(const ss_paint *p, const char *path, int *dropped, ss_error *err) {
    ss_stroke_set s;
    ss_status st = ss_paint_to_strokes(p, &s, dropped, err);
    if (st) return st;
    size_t cap = 32 + (size_t)s.npoints * 48;
    char *buf = malloc(cap);
    if (!buf) {
        ss_stroke_set_free(&s);
        return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
    }
    size_t len = (size_t)snprintf(buf, cap, "u,v,stroke\n");
    for (int i = 0; i < s.npoints; i++)
        len +=
            (size_t)snprintf(buf + len, cap - len, "%.9g,%.9g,%d\n", s.u[i], s.v[i], s.stroke[i]);
    st = ss_write_file_atomic(path, buf, len, err);
    free(buf);
    ss_stroke_set_free(&s);
    return st;
}

int ss_mesh_locate_uv(const ss_mesh *m, const float uv[2], float pos[3]) {
    if (!m->has_uvs) return -1;
    double px = uv[0], py = uv[1];
    for (int t = 0; t < m->ntriangles; t++) {
        const uint32_t *ix = m->indices + 3 * (size_t)t;
        const float *a = m->uvs + 2 * (size_t)ix[0], *b = m->uvs + 2 * (size_t)ix[1],
                    *c = m->uvs + 2 * (size_t)ix[2];
        double d = (double)(b[0] - a[0]) * (c[1] - a[1]) - (double)(c[0] - a[0]) * (b[1] - a[1]);
        if (d == 0) continue;
        double l1 = ((px - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (py - a[1])) / d;
        double l2 = ((b[0] - a[0]) * (py - a[1]) - (px - a[0]) * (b[1] - a[1])) / d;
        double l0 = 1 - l1 - l2;
        const double eps = -1e-7;
        if (l0 < eps || l1 < eps || l2 < eps) continue;
        if (pos)
            for (int k = 0; k < 3; k++)
                pos[k] = (float)(l0 * m->positions[3 * (size_t)ix[0] + k] +
                                 l1 * m->positions[3 * (size_t)ix[1] + k] +
                                 l2 * m->positions[3 * (size_t)ix[2] + k]);
        return t;
    }
    return -1;
}

ss_status ss_paint_load_csv(ss_paint *p, const char *path, int *outside, ss_error *err) {
    ss_stroke_set s;
    ss_status st = ss_stroke_csv_read(path, &s, err);
    if (st) return st;
    int out = 0;
    ss_paint_clear(p);
    int base_stroke = p->next_stroke;
    for (int i = 0; i < s.npoints && !st; i++) {
        float uv[2] = {(float)s.u[i], (float)s.v[i]}, pos[3];
        int t = ss_mesh_locate_uv(p->mesh, uv, pos);
        if (t < 0) out++;
        /* Each file stroke is one group (undo removes it) and one stroke. */
        p->cur_group = base_stroke + s.stroke[i];
        p->cur_stroke = base_stroke + s.stroke[i];
        if (push(p, uv, t >= 0 ? pos : NULL, t >= 0 ? p->island[t] : -1))
            st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
    }
    int maxid = 0;
    for (int i = 0; i < s.npoints; i++)
        if (s.stroke[i] > maxid) maxid = s.stroke[i];
    p->next_stroke = base_stroke + maxid + 1;
    if (p->next_group < p->next_stroke) p->next_group = p->next_stroke;
    p->cur_group = p->cur_stroke = -1;
    ss_stroke_set_free(&s);
    if (outside) *outside = out;
    return st;
}
