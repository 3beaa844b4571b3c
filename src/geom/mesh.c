/* Triangle meshes: the common part of the OBJ and glTF readers (mesh_obj.c,
 * mesh_gltf.c). Both readers end in ss_mesh_from_arrays, which is where every
 * mesh is checked once: indices in range, values finite, at least one
 * triangle; it computes area-weighted vertex normals where the file had
 * none and the bounding box.
 *
 * UV islands (seed 000 §4.2: a painted stroke must not be joined across a
 * seam) are the connected components of triangles that share a UV point
 * with exactly the same coordinates. Exact float equality is right here: a
 * seam in a real file duplicates the vertex with different UVs, while the
 * corners inside an island share one stored UV. Union-find over the
 * vertices sorted by UV, O(n log n). */
#include "skinsim/mesh.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

ss_status ss_mesh_load_obj(const char *path, ss_mesh *out, ss_error *err);
ss_status ss_mesh_load_gltf(const char *path, ss_mesh *out, ss_error *err);

void ss_mesh_free(ss_mesh *m) {
    if (!m) return;
    free(m->positions);
    free(m->normals);
    free(m->uvs);
    free(m->indices);
    memset(m, 0, sizeof *m);
}

static int ends_with(const char *s, const char *ext) {
    size_t n = strlen(s), k = strlen(ext);
    if (n < k) return 0;
    for (size_t i = 0; i < k; i++)
        if (tolower((unsigned char)s[n - k + i]) != ext[i]) return 0;
    return 1;
}

ss_status ss_mesh_load(const char *path, ss_mesh *out, ss_error *err) {
    memset(out, 0, sizeof *out);
    if (!path || !*path) return ss_error_set(err, SS_ERR_INPUT, "mesh: empty path");
    if (ends_with(path, ".obj")) return ss_mesh_load_obj(path, out, err);
    if (ends_with(path, ".gltf") || ends_with(path, ".glb"))
        return ss_mesh_load_gltf(path, out, err);
    return ss_error_set(err, SS_ERR_INPUT, "%s: unknown mesh format (expected .obj, .gltf or .glb)",
                        path);
}

static void compute_normals(ss_mesh *m) {
    memset(m->normals, 0, sizeof(float) * 3 * (size_t)m->nvertices);
    for (int t = 0; t < m->ntriangles; t++) {
        const uint32_t *ix = m->indices + 3 * (size_t)t;
        const float *a = m->positions + 3 * (size_t)ix[0];
        const float *b = m->positions + 3 * (size_t)ix[1];
        const float *c = m->positions + 3 * (size_t)ix[2];
        double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        /* The cross product's length is twice the area: area weighting. */
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]};
        for (int k = 0; k < 3; k++)
            for (int d = 0; d < 3; d++) m->normals[3 * (size_t)ix[k] + d] += (float)n[d];
    }
}

static void normalise_normals(ss_mesh *m) {
    for (int i = 0; i < m->nvertices; i++) {
        float *n = m->normals + 3 * (size_t)i;
        double len = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
        if (len > 0 && isfinite(len)) {
            for (int d = 0; d < 3; d++) n[d] = (float)(n[d] / len);
        } else {
            n[0] = 0, n[1] = 0, n[2] = 1; /* isolated or degenerate vertex */
        }
    }
}

ss_status ss_mesh_from_arrays(const float *positions, const float *normals, const float *uvs,
                              int nvertices, const uint32_t *indices, int ntriangles,
                              const char *name, ss_mesh *out, ss_error *err) {
    memset(out, 0, sizeof *out);
    if (!name) name = "mesh";
    if (nvertices <= 0 || ntriangles <= 0 || !positions || !indices)
        return ss_error_set(err, SS_ERR_INPUT, "%s: no triangles", name);
    if ((size_t)nvertices > ((size_t)1 << 28) || (size_t)ntriangles > ((size_t)1 << 28))
        return ss_error_set(err, SS_ERR_INPUT, "%s: too many vertices or triangles", name);
    for (size_t i = 0; i < 3 * (size_t)nvertices; i++)
        if (!isfinite(positions[i]))
            return ss_error_set(err, SS_ERR_INPUT, "%s: vertex %zu has a non-finite position", name,
                                i / 3);
    if (uvs)
        for (size_t i = 0; i < 2 * (size_t)nvertices; i++)
            if (!isfinite(uvs[i]))
                return ss_error_set(err, SS_ERR_INPUT,
                                    "%s: vertex %zu has a non-finite texture coordinate", name,
                                    i / 2);
    for (size_t i = 0; i < 3 * (size_t)ntriangles; i++)
        if (indices[i] >= (uint32_t)nvertices)
            return ss_error_set(err, SS_ERR_INPUT,
                                "%s: triangle %zu uses vertex %u but there are %d vertices", name,
                                i / 3, (unsigned)indices[i], nvertices);
    size_t nv = (size_t)nvertices, nt = (size_t)ntriangles;
    out->positions = malloc(sizeof(float) * 3 * nv);
    out->normals = malloc(sizeof(float) * 3 * nv);
    out->uvs = uvs ? malloc(sizeof(float) * 2 * nv) : NULL;
    out->indices = malloc(sizeof(uint32_t) * 3 * nt);
    if (!out->positions || !out->normals || (uvs && !out->uvs) || !out->indices) {
        ss_mesh_free(out);
        return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory for %d vertices", name,
                            nvertices);
    }
    out->nvertices = nvertices;
    out->ntriangles = ntriangles;
    memcpy(out->positions, positions, sizeof(float) * 3 * nv);
    memcpy(out->indices, indices, sizeof(uint32_t) * 3 * nt);
    if (uvs) memcpy(out->uvs, uvs, sizeof(float) * 2 * nv);
    out->has_uvs = uvs != NULL;
    int normals_ok = normals != NULL;
    if (normals)
        for (size_t i = 0; i < 3 * nv && normals_ok; i++) normals_ok = isfinite(normals[i]);
    if (normals_ok) {
        memcpy(out->normals, normals, sizeof(float) * 3 * nv);
        out->normals_loaded = 1;
    } else {
        compute_normals(out);
    }
    normalise_normals(out);
    for (int d = 0; d < 3; d++) out->bbox_min[d] = INFINITY, out->bbox_max[d] = -INFINITY;
    for (size_t i = 0; i < nv; i++)
        for (int d = 0; d < 3; d++) {
            float p = out->positions[3 * i + d];
            if (p < out->bbox_min[d]) out->bbox_min[d] = p;
            if (p > out->bbox_max[d]) out->bbox_max[d] = p;
        }
    return SS_OK;
}

/* ---- UV islands ---------------------------------------------------------- */

/* Vertex indices sorted by (u, v, index): bottom-up merge sort (reentrant,
 * unlike qsort with a global context). */
static int sort_by_uv(const float *uv, uint32_t *order, size_t nv) {
    uint32_t *tmp = malloc(sizeof *tmp * (nv ? nv : 1));
    if (!tmp) return -1;
    for (size_t i = 0; i < nv; i++) order[i] = (uint32_t)i;
    for (size_t w = 1; w < nv; w *= 2) {
        for (size_t lo = 0; lo < nv; lo += 2 * w) {
            size_t mid = lo + w < nv ? lo + w : nv, hi = lo + 2 * w < nv ? lo + 2 * w : nv;
            size_t i = lo, j = mid, k = lo;
            while (i < mid && j < hi) {
                const float *a = uv + 2 * (size_t)order[i], *b = uv + 2 * (size_t)order[j];
                int le = a[0] < b[0] ||
                         (a[0] == b[0] && (a[1] < b[1] || (a[1] == b[1] && order[i] < order[j])));
                tmp[k++] = le ? order[i++] : order[j++];
            }
            while (i < mid) tmp[k++] = order[i++];
            while (j < hi) tmp[k++] = order[j++];
        }
        memcpy(order, tmp, sizeof *order * nv);
    }
    free(tmp);
    return 0;
}

static uint32_t uf_find(uint32_t *parent, uint32_t x) {
    while (parent[x] != x) {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    return x;
}

static void uf_union(uint32_t *parent, uint32_t a, uint32_t b) {
    a = uf_find(parent, a);
    b = uf_find(parent, b);
    if (a != b) {
        if (a < b)
            parent[b] = a;
        else
            parent[a] = b;
    }
}

int ss_mesh_uv_islands(const ss_mesh *m, int *island) {
    if (!m || !m->has_uvs || !m->uvs || !island) return -1;
    size_t nv = (size_t)m->nvertices, nt = (size_t)m->ntriangles;
    uint32_t *order = malloc(sizeof *order * nv);
    uint32_t *canon = malloc(sizeof *canon * nv);
    uint32_t *parent = malloc(sizeof *parent * nv);
    int *label = malloc(sizeof *label * nv);
    if (!order || !canon || !parent || !label) {
        free(order), free(canon), free(parent), free(label);
        return -1;
    }
    /* canon[v]: the first vertex in UV order with exactly v's UV. */
    if (sort_by_uv(m->uvs, order, nv) != 0) {
        free(order), free(canon), free(parent), free(label);
        return -1;
    }
    for (size_t i = 0; i < nv; i++) {
        size_t v = order[i];
        if (i > 0) {
            size_t p = order[i - 1];
            if (m->uvs[2 * v] == m->uvs[2 * p] && m->uvs[2 * v + 1] == m->uvs[2 * p + 1]) {
                canon[v] = canon[p];
                continue;
            }
        }
        canon[v] = (uint32_t)v;
    }
    for (size_t i = 0; i < nv; i++) parent[i] = (uint32_t)i;
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *ix = m->indices + 3 * t;
        uf_union(parent, canon[ix[0]], canon[ix[1]]);
        uf_union(parent, canon[ix[0]], canon[ix[2]]);
    }
    for (size_t i = 0; i < nv; i++) label[i] = -1;
    int n = 0;
    for (size_t t = 0; t < nt; t++) {
        uint32_t r = uf_find(parent, canon[m->indices[3 * t]]);
        if (label[r] < 0) label[r] = n++;
        island[t] = label[r];
    }
    free(order), free(canon), free(parent), free(label);
    return n;
}
