/* Mesh welding and local refinement: vertices welded by position (a seam
 * duplicates a position with other UVs or normals), and the triangles near a
 * point split until their edges are short, so per-vertex data (a heal run's
 * fields mapped back onto a body, seed 001 §5.4) can show detail finer than
 * the body's triangles.
 *
 * Design:
 * - Welding joins vertices within SS_WELD_REL of the bounding box's
 *   diagonal (seams computed in float or by trigonometry differ in the last
 *   digits; 1e-9 relative is common): positions binned into cubes of that
 *   size, records (bin, index) sorted with qsort (they carry the key, so the
 *   comparator needs no global state), each vertex compared with the 27
 *   neighbouring bins, a union-find whose root is the lowest index.
 * - Refinement is red-green, one level at a time: a triangle near the point
 *   whose longest edge is too long is split 1-to-4 at its edge midpoints
 *   ("red"); a neighbour that shares one split edge is split 1-to-2
 *   ("green"), one that shares two or three becomes red, repeated until
 *   stable, so the surface stays closed (no T-junction). Edges are matched by
 *   welded ids, so a split edge on a UV seam is split on both sides; each
 *   side gets its own midpoint vertex (its own UV), at the same position.
 * - New points lie on the old triangles (midpoints), normals and UVs are
 *   interpolated (normals renormalised): the shape does not change.
 * - Gave up: green triangles are not undone at the next level (classic
 *   red-green refinement removes them first), so a triangle split 1-to-2
 *   and later 1-to-4 leaves thinner children; the output is for viewing. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/mesh.h"

typedef struct wrec {
    int64_t k[3];
    int i;
} wrec;

static int cmp_wrec(const void *x, const void *y) {
    const wrec *a = x, *b = y;
    for (int d = 0; d < 3; d++)
        if (a->k[d] != b->k[d]) return a->k[d] < b->k[d] ? -1 : 1;
    return a->i - b->i;
}

static int cmp_key(const int64_t *a, const int64_t *b) {
    for (int d = 0; d < 3; d++)
        if (a[d] != b[d]) return a[d] < b[d] ? -1 : 1;
    return 0;
}

static int uf_find(int *up, int a) {
    while (up[a] != a) a = up[a] = up[up[a]];
    return a;
}

ss_status ss_weld_positions(int n, const double *p, int *weld, ss_error *err) {
    if (n <= 0) return SS_OK;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < n; i++)
        for (int d = 0; d < 3; d++) {
            lo[d] = fmin(lo[d], p[3 * (size_t)i + d]);
            hi[d] = fmax(hi[d], p[3 * (size_t)i + d]);
        }
    double diag = 0;
    for (int d = 0; d < 3; d++) diag += (hi[d] - lo[d]) * (hi[d] - lo[d]);
    const double tol = SS_WELD_REL * sqrt(diag);
    wrec *r = malloc((size_t)n * sizeof *r);
    if (!r) return ss_error_set(err, SS_ERR_NOMEM, "mesh weld: out of memory");
    for (int i = 0; i < n; i++) {
        for (int d = 0; d < 3; d++) {
            double q = tol > 0 ? floor((p[3 * (size_t)i + d] - lo[d]) / tol) : 0;
            r[i].k[d] = isfinite(q) ? (int64_t)q : 0;
        }
        r[i].i = i;
        weld[i] = i; /* union-find parents, the root the lowest index */
    }
    qsort(r, (size_t)n, sizeof *r, cmp_wrec);
    for (int s = 0; s < n; s++) {
        const double *a = p + 3 * (size_t)r[s].i;
        for (int dx = -1; dx <= 1; dx++)
            for (int dy = -1; dy <= 1; dy++) {
                int64_t key[3] = {r[s].k[0] + dx, r[s].k[1] + dy, r[s].k[2] - 1};
                int l = 0, u = n; /* first record with key >= (x, y, z - 1) */
                while (l < u) {
                    int mid = l + (u - l) / 2;
                    if (cmp_key(r[mid].k, key) < 0)
                        l = mid + 1;
                    else
                        u = mid;
                }
                for (int t = l; t < n; t++) {
                    if (r[t].k[0] != key[0] || r[t].k[1] != key[1] || r[t].k[2] > key[2] + 2) break;
                    if (t == s) continue;
                    const double *b = p + 3 * (size_t)r[t].i;
                    double d2 = 0;
                    for (int d = 0; d < 3; d++) d2 += (a[d] - b[d]) * (a[d] - b[d]);
                    if (!(d2 <= tol * tol)) continue;
                    int ra = uf_find(weld, r[s].i), rb = uf_find(weld, r[t].i);
                    if (ra < rb)
                        weld[rb] = ra;
                    else if (rb < ra)
                        weld[ra] = rb;
                }
            }
    }
    for (int i = 0; i < n; i++) weld[i] = uf_find(weld, i);
    free(r);
    return SS_OK;
}

ss_status ss_mesh_weld(const ss_mesh *m, int *weld, ss_error *err) {
    int n = m->nvertices;
    double *p = malloc(3 * (size_t)(n > 0 ? n : 1) * sizeof *p);
    if (!p) return ss_error_set(err, SS_ERR_NOMEM, "mesh weld: out of memory");
    for (size_t i = 0; i < 3 * (size_t)n; i++) p[i] = m->positions[i];
    ss_status st = ss_weld_positions(n, p, weld, err);
    free(p);
    return st;
}

/* ---- a small open-addressing map from an edge key to an int ---------------------- */

typedef struct emap {
    uint64_t *key; /* UINT64_MAX = empty */
    int *val;
    size_t cap, n;
} emap;

static int emap_init(emap *h, size_t expect) {
    h->cap = 64;
    while (h->cap < 2 * expect + 16) h->cap *= 2;
    h->n = 0;
    h->key = malloc(h->cap * sizeof *h->key);
    h->val = malloc(h->cap * sizeof *h->val);
    if (!h->key || !h->val) return 0;
    memset(h->key, 0xff, h->cap * sizeof *h->key);
    return 1;
}

static void emap_free(emap *h) {
    free(h->key);
    free(h->val);
}

static uint64_t ekey(uint32_t a, uint32_t b) {
    return a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
}

static size_t emap_slot(const emap *h, uint64_t k) {
    uint64_t x = k * 0x9E3779B97F4A7C15ull;
    size_t s = (size_t)(x >> 17) & (h->cap - 1);
    while (h->key[s] != UINT64_MAX && h->key[s] != k) s = (s + 1) & (h->cap - 1);
    return s;
}

static int emap_get(const emap *h, uint64_t k) {
    size_t s = emap_slot(h, k);
    return h->key[s] == k ? h->val[s] : -1;
}

/* Inserts k -> v unless k is there; returns 0 when memory runs out. */
static int emap_put(emap *h, uint64_t k, int v) {
    if (2 * (h->n + 1) > h->cap) {
        emap g;
        if (!emap_init(&g, h->cap)) {
            emap_free(&g);
            return 0;
        }
        for (size_t s = 0; s < h->cap; s++)
            if (h->key[s] != UINT64_MAX) {
                size_t t = emap_slot(&g, h->key[s]);
                g.key[t] = h->key[s], g.val[t] = h->val[s], g.n++;
            }
        emap_free(h);
        *h = g;
    }
    size_t s = emap_slot(h, k);
    if (h->key[s] != k) h->key[s] = k, h->val[s] = v, h->n++;
    return 1;
}

/* ---- one level of red-green refinement ------------------------------------------- */

static float dist2(const float *a, const float *b) {
    float d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = a[2] - b[2];
    return d0 * d0 + d1 * d1 + d2 * d2;
}

/* Splits m into *out; *nred gets the number of red triangles (0: nothing to
 * do, *out untouched). */
static ss_status refine_level(const ss_mesh *m, const float c[3], float radius, float max_edge,
                              ss_mesh *out, int *nred, ss_error *err) {
    const int nt = m->ntriangles, nv = m->nvertices;
    int *weld = malloc((size_t)nv * sizeof *weld);
    uint8_t *red = calloc((size_t)nt, 1);
    emap split = {0}, mid = {0};
    float *pos = NULL, *nrm = NULL, *uv = NULL;
    uint32_t *idx = NULL;
    ss_status st = SS_OK;
    *nred = 0;
    if (!weld || !red || !emap_init(&split, 1024) || !emap_init(&mid, 1024)) goto nomem;
    if ((st = ss_mesh_weld(m, weld, err))) goto done;
    const float r2 = radius * radius, e2 = max_edge * max_edge;
    for (int t = 0; t < nt; t++) {
        const uint32_t *q = m->indices + 3 * (size_t)t;
        const float *p[3] = {m->positions + 3 * q[0], m->positions + 3 * q[1],
                             m->positions + 3 * q[2]};
        int near = 0, longe = 0;
        for (int k = 0; k < 3; k++) {
            near |= dist2(p[k], c) <= r2;
            longe |= dist2(p[k], p[(k + 1) % 3]) > e2;
        }
        if (near && longe) {
            red[t] = 1;
            for (int k = 0; k < 3; k++)
                if (!emap_put(&split, ekey((uint32_t)weld[q[k]], (uint32_t)weld[q[(k + 1) % 3]]),
                              1))
                    goto nomem;
        }
    }
    /* closure: two or three split edges make a triangle red */
    for (int changed = 1; changed;) {
        changed = 0;
        for (int t = 0; t < nt; t++) {
            if (red[t]) continue;
            const uint32_t *q = m->indices + 3 * (size_t)t;
            int ns = 0;
            for (int k = 0; k < 3; k++)
                ns += emap_get(&split,
                               ekey((uint32_t)weld[q[k]], (uint32_t)weld[q[(k + 1) % 3]])) >= 0;
            if (ns >= 2) {
                red[t] = 1, changed = 1;
                for (int k = 0; k < 3; k++)
                    if (!emap_put(&split,
                                  ekey((uint32_t)weld[q[k]], (uint32_t)weld[q[(k + 1) % 3]]), 1))
                        goto nomem;
            }
        }
    }
    for (int t = 0; t < nt; t++) *nred += red[t];
    if (!*nred) goto done;
    /* new vertices: a midpoint per split edge side (unwelded corner pair) */
    size_t cap_v = (size_t)nv + 3 * (size_t)nt, cap_t = 4 * (size_t)nt;
    pos = malloc(cap_v * 3 * sizeof *pos);
    nrm = malloc(cap_v * 3 * sizeof *nrm);
    uv = m->has_uvs ? malloc(cap_v * 2 * sizeof *uv) : NULL;
    idx = malloc(cap_t * 3 * sizeof *idx);
    if (!pos || !nrm || (m->has_uvs && !uv) || !idx) goto nomem;
    memcpy(pos, m->positions, (size_t)nv * 3 * sizeof *pos);
    memcpy(nrm, m->normals, (size_t)nv * 3 * sizeof *nrm);
    if (uv) memcpy(uv, m->uvs, (size_t)nv * 2 * sizeof *uv);
    int v = nv;
    size_t ot = 0;
    for (int t = 0; t < nt; t++) {
        const uint32_t *q = m->indices + 3 * (size_t)t;
        int mv[3] = {-1, -1, -1}, ns = 0, first = -1;
        for (int k = 0; k < 3; k++) {
            uint32_t a = q[k], b = q[(k + 1) % 3];
            if (emap_get(&split, ekey((uint32_t)weld[a], (uint32_t)weld[b])) < 0) continue;
            ns++;
            if (first < 0) first = k;
            int got = emap_get(&mid, ekey(a, b));
            if (got < 0) {
                got = v++;
                float n3[3], l = 0;
                for (int d = 0; d < 3; d++) {
                    pos[3 * (size_t)got + d] =
                        0.5f * (m->positions[3 * a + d] + m->positions[3 * b + d]);
                    n3[d] = m->normals[3 * a + d] + m->normals[3 * b + d];
                    l += n3[d] * n3[d];
                }
                l = l > 0 ? 1.0f / sqrtf(l) : 0;
                for (int d = 0; d < 3; d++)
                    nrm[3 * (size_t)got + d] = l > 0 ? n3[d] * l : m->normals[3 * a + d];
                if (uv)
                    for (int d = 0; d < 2; d++)
                        uv[2 * (size_t)got + d] = 0.5f * (m->uvs[2 * a + d] + m->uvs[2 * b + d]);
                if (!emap_put(&mid, ekey(a, b), got)) goto nomem;
            }
            mv[k] = got;
        }
        uint32_t *o = idx + 3 * ot;
        if (ns == 0) {
            memcpy(o, q, 3 * sizeof *o);
            ot++;
        } else if (ns == 1) { /* green: corner opposite the split edge to its midpoint */
            uint32_t a = q[first], b = q[(first + 1) % 3], cc = q[(first + 2) % 3],
                     mm = (uint32_t)mv[first];
            uint32_t two[6] = {a, mm, cc, mm, b, cc};
            memcpy(o, two, sizeof two);
            ot += 2;
        } else { /* red (ns == 3 after the closure) */
            uint32_t m01 = (uint32_t)mv[0], m12 = (uint32_t)mv[1], m20 = (uint32_t)mv[2];
            uint32_t four[12] = {q[0], m01, m20, m01, q[1], m12, m20, m12, q[2], m01, m12, m20};
            memcpy(o, four, sizeof four);
            ot += 4;
        }
    }
    st = ss_mesh_from_arrays(pos, nrm, uv, v, idx, (int)ot, "refined mesh", out, err);
    if (!st) out->normals_loaded = m->normals_loaded;
    goto done;
nomem:
    st = ss_error_set(err, SS_ERR_NOMEM, "mesh refinement: out of memory");
done:
    free(weld);
    free(red);
    emap_free(&split);
    emap_free(&mid);
    free(pos);
    free(nrm);
    free(uv);
    free(idx);
    return st;
}

ss_status ss_mesh_refine_near(const ss_mesh *m, const float centre[3], float radius, float max_edge,
                              int max_levels, ss_mesh *out, ss_error *err) {
    memset(out, 0, sizeof *out);
    if (!m || m->nvertices < 3 || m->ntriangles < 1)
        return ss_error_set(err, SS_ERR_INPUT, "mesh refinement: no triangles");
    if (!(radius >= 0 && max_edge > 0 && isfinite(radius) && isfinite(max_edge)) ||
        max_levels < 0 || max_levels > 12)
        return ss_error_set(err, SS_ERR_INPUT,
                            "mesh refinement: radius %g, edge %g, levels %d out of range",
                            (double)radius, (double)max_edge, max_levels);
    ss_mesh cur;
    ss_status st = ss_mesh_from_arrays(m->positions, m->normals, m->has_uvs ? m->uvs : NULL,
                                       m->nvertices, m->indices, m->ntriangles, "mesh", &cur, err);
    if (st) return st;
    cur.normals_loaded = m->normals_loaded;
    for (int level = 0; level < max_levels; level++) {
        ss_mesh next;
        int nred;
        if ((st = refine_level(&cur, centre, radius, max_edge, &next, &nred, err))) break;
        if (!nred) break;
        ss_mesh_free(&cur);
        cur = next;
    }
    if (st) {
        ss_mesh_free(&cur);
        return st;
    }
    *out = cur;
    return SS_OK;
}
