/* glTF 2.0 output (written with cJSON, no glTF library): a textured square
 * that shows a texture set in any glTF viewer or Blender. The geometry (4
 * vertices with normal, tangent and UV; 2 triangles) is embedded as a base64
 * buffer; the textures are referenced by relative URI, so the .gltf sits next
 * to its PNGs. glTF units are metres, +Y up; the square lies in the XY plane
 * facing +Z, with UV (0,0) at the top-left like the images. */
#include "skinsim/geom.h"
#include "skinsim/mesh.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static char *base64(const unsigned char *in, size_t n) {
    static const char tbl[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char *out = malloc(4 * ((n + 2) / 3) + 1), *o = out;
    if (!out) return NULL;
    for (size_t i = 0; i < n; i += 3) {
        unsigned v = (unsigned)in[i] << 16;
        if (i + 1 < n) v |= (unsigned)in[i + 1] << 8;
        if (i + 2 < n) v |= in[i + 2];
        *o++ = tbl[(v >> 18) & 63];
        *o++ = tbl[(v >> 12) & 63];
        *o++ = i + 1 < n ? tbl[(v >> 6) & 63] : '=';
        *o++ = i + 2 < n ? tbl[v & 63] : '=';
    }
    *o = '\0';
    return out;
}

static cJSON *num_array(const double *v, int n) {
    cJSON *a = cJSON_CreateArray();
    for (int i = 0; i < n; i++) cJSON_AddItemToArray(a, cJSON_CreateNumber(v[i]));
    return a;
}

/* ---- one binary buffer, its views and accessors ---------------------------- */

/* The arrays of a glTF file go into one buffer, each with its own bufferView
 * (tightly packed, so no byteStride) and accessor; both writers below build
 * their buffer this way and differ only in how it is stored (a base64 data
 * URI in a .gltf, the BIN chunk of a .glb). */
typedef struct gbuf {
    unsigned char *data;
    size_t len, cap;
    cJSON *root, *views, *accs;
    int failed; /* out of memory on the way */
} gbuf;

static void gb_init(gbuf *b, const char *node_name) {
    memset(b, 0, sizeof *b);
    cJSON *root = b->root = cJSON_CreateObject();
    cJSON *asset = cJSON_AddObjectToObject(root, "asset");
    cJSON_AddStringToObject(asset, "version", "2.0");
    cJSON_AddStringToObject(asset, "generator", "skinsim");
    cJSON_AddNumberToObject(root, "scene", 0);
    cJSON *scenes = cJSON_AddArrayToObject(root, "scenes");
    cJSON *scene = cJSON_CreateObject();
    cJSON_AddItemToObject(scene, "nodes", num_array((const double[]){0}, 1));
    cJSON_AddItemToArray(scenes, scene);
    cJSON *nodes = cJSON_AddArrayToObject(root, "nodes");
    cJSON *node = cJSON_CreateObject();
    cJSON_AddStringToObject(node, "name", node_name);
    cJSON_AddNumberToObject(node, "mesh", 0);
    cJSON_AddItemToArray(nodes, node);
    b->views = cJSON_AddArrayToObject(root, "bufferViews");
    b->accs = cJSON_AddArrayToObject(root, "accessors");
    if (!b->accs) b->failed = 1;
}

static void gb_free(gbuf *b) {
    free(b->data);
    cJSON_Delete(b->root);
}

/* Appends count elements of ncomp components (5126 float or 5125 uint32,
 * both 4 bytes, so every view stays 4-byte aligned) as a view of the given
 * target and an accessor with min/max when minmax (float data only; the spec
 * asks for them on POSITION, morph targets included). Returns the accessor's
 * index, -1 when out of memory. */
static int gb_add(gbuf *b, const void *src, int count, int ncomp, int component, int target,
                  int minmax) {
    static const char *const types[] = {"", "SCALAR", "VEC2", "VEC3", "VEC4"};
    size_t bytes = (size_t)count * ncomp * 4;
    if (b->failed) return -1;
    if (b->len + bytes > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->len + bytes) cap *= 2;
        unsigned char *d = realloc(b->data, cap);
        if (!d) {
            b->failed = 1;
            return -1;
        }
        b->data = d, b->cap = cap;
    }
    memcpy(b->data + b->len, src, bytes);
    cJSON *v = cJSON_CreateObject();
    cJSON_AddNumberToObject(v, "buffer", 0);
    cJSON_AddNumberToObject(v, "byteOffset", (double)b->len);
    cJSON_AddNumberToObject(v, "byteLength", (double)bytes);
    if (target) cJSON_AddNumberToObject(v, "target", target);
    cJSON_AddItemToArray(b->views, v);
    b->len += bytes;
    cJSON *a = cJSON_CreateObject();
    cJSON_AddNumberToObject(a, "bufferView", cJSON_GetArraySize(b->views) - 1);
    cJSON_AddNumberToObject(a, "componentType", component);
    cJSON_AddNumberToObject(a, "count", count);
    cJSON_AddStringToObject(a, "type", types[ncomp]);
    if (minmax && component == 5126) {
        /* min/max of the float32 values as stored, so a validator's check
         * against the data holds exactly */
        double lo[4] = {INFINITY, INFINITY, INFINITY, INFINITY},
               hi[4] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY};
        const float *f = src;
        for (int i = 0; i < count; i++)
            for (int c = 0; c < ncomp; c++) {
                double x = f[(size_t)i * ncomp + c];
                if (x < lo[c]) lo[c] = x;
                if (x > hi[c]) hi[c] = x;
            }
        cJSON_AddItemToObject(a, "min", num_array(lo, ncomp));
        cJSON_AddItemToObject(a, "max", num_array(hi, ncomp));
    }
    cJSON_AddItemToArray(b->accs, a);
    return cJSON_GetArraySize(b->accs) - 1;
}

static void add_texture(cJSON *images, cJSON *textures, const char *uri) {
    cJSON *img = cJSON_CreateObject();
    cJSON_AddStringToObject(img, "uri", uri);
    cJSON_AddItemToArray(images, img);
    cJSON *t = cJSON_CreateObject();
    cJSON_AddNumberToObject(t, "sampler", 0);
    cJSON_AddNumberToObject(t, "source", cJSON_GetArraySize(images) - 1);
    cJSON_AddItemToArray(textures, t);
}

static cJSON *texture_ref(int index) {
    cJSON *r = cJSON_CreateObject();
    cJSON_AddNumberToObject(r, "index", index);
    return r;
}

/* meshes[0] with one triangle primitive: POSITION, NORMAL, the indices and
 * material 0; returns the primitive's attributes object for the rest. */
static cJSON *gb_mesh(gbuf *b, const char *name, int a_pos, int a_nrm, int a_idx,
                      cJSON **mesh_out) {
    cJSON *meshes = cJSON_AddArrayToObject(b->root, "meshes");
    cJSON *mesh = cJSON_CreateObject();
    if (name) cJSON_AddStringToObject(mesh, "name", name);
    cJSON *prims = cJSON_AddArrayToObject(mesh, "primitives");
    cJSON *prim = cJSON_CreateObject();
    cJSON *attrs = cJSON_AddObjectToObject(prim, "attributes");
    cJSON_AddNumberToObject(attrs, "POSITION", a_pos);
    cJSON_AddNumberToObject(attrs, "NORMAL", a_nrm);
    cJSON_AddNumberToObject(prim, "indices", a_idx);
    cJSON_AddNumberToObject(prim, "material", 0);
    cJSON_AddItemToArray(prims, prim);
    cJSON_AddItemToArray(meshes, mesh);
    if (mesh_out) *mesh_out = mesh;
    return attrs;
}

/* One textured triangle mesh as a glTF 2.0 file: the arrays packed into one
 * base64 buffer (positions, normals, optional tangents, UVs, 32-bit indices),
 * a metallic-roughness material with the given texture URIs. */
static ss_status write_textured(const char *path, const char *name, const float *pos,
                                const float *nrm, const float *tan, const float *uv, int nv,
                                const uint32_t *idx, int nt, const char *base_color_uri,
                                const char *metallic_roughness_uri, const char *normal_uri,
                                ss_error *err) {
    gbuf b;
    gb_init(&b, name ? name : "skin");
    int a_pos = gb_add(&b, pos, nv, 3, 5126, 34962, 1);
    int a_nrm = gb_add(&b, nrm, nv, 3, 5126, 34962, 0);
    int a_tan = tan ? gb_add(&b, tan, nv, 4, 5126, 34962, 0) : -1;
    int a_uv = gb_add(&b, uv, nv, 2, 5126, 34962, 0);
    int a_idx = gb_add(&b, idx, nt * 3, 1, 5125, 34963, 0);
    char *b64 = b.failed ? NULL : base64(b.data, b.len);
    char *uri = b64 ? malloc(strlen(b64) + 64) : NULL;
    if (!uri) {
        free(b64);
        gb_free(&b);
        return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
    }
    snprintf(uri, strlen(b64) + 64, "data:application/octet-stream;base64,%s", b64);
    free(b64);
    cJSON *root = b.root;
    cJSON *buffers = cJSON_AddArrayToObject(root, "buffers");
    cJSON *bo = cJSON_CreateObject();
    cJSON_AddNumberToObject(bo, "byteLength", (double)b.len);
    cJSON_AddStringToObject(bo, "uri", uri);
    cJSON_AddItemToArray(buffers, bo);
    free(uri);

    cJSON *attrs = gb_mesh(&b, NULL, a_pos, a_nrm, a_idx, NULL);
    if (a_tan >= 0) cJSON_AddNumberToObject(attrs, "TANGENT", a_tan);
    cJSON_AddNumberToObject(attrs, "TEXCOORD_0", a_uv);

    cJSON *samplers = cJSON_AddArrayToObject(root, "samplers");
    cJSON *smp = cJSON_CreateObject();
    cJSON_AddNumberToObject(smp, "magFilter", 9729);
    cJSON_AddNumberToObject(smp, "minFilter", 9987);
    cJSON_AddItemToArray(samplers, smp);
    cJSON *images = cJSON_AddArrayToObject(root, "images");
    cJSON *textures = cJSON_AddArrayToObject(root, "textures");
    cJSON *materials = cJSON_AddArrayToObject(root, "materials");
    cJSON *mat = cJSON_CreateObject();
    cJSON_AddStringToObject(mat, "name", name ? name : "skin");
    cJSON *pbr = cJSON_AddObjectToObject(mat, "pbrMetallicRoughness");
    cJSON_AddNumberToObject(pbr, "metallicFactor", 0.0);
    cJSON_AddNumberToObject(pbr, "roughnessFactor", 1.0);
    int ntex = 0;
    if (base_color_uri) {
        add_texture(images, textures, base_color_uri);
        cJSON_AddItemToObject(pbr, "baseColorTexture", texture_ref(ntex++));
    }
    if (metallic_roughness_uri) {
        add_texture(images, textures, metallic_roughness_uri);
        cJSON_AddItemToObject(pbr, "metallicRoughnessTexture", texture_ref(ntex++));
    }
    if (normal_uri) {
        add_texture(images, textures, normal_uri);
        cJSON_AddItemToObject(mat, "normalTexture", texture_ref(ntex++));
    }
    cJSON_AddItemToArray(materials, mat);
    char *text = cJSON_Print(root);
    gb_free(&b);
    if (!text) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    ss_status st = ss_write_file_atomic(path, text, strlen(text), err);
    free(text);
    return st;
}

ss_status ss_gltf_write_textured_square(const char *path, double side_m, const char *name,
                                        const char *base_color_uri,
                                        const char *metallic_roughness_uri, const char *normal_uri,
                                        ss_error *err) {
    if (!(side_m > 0)) return ss_error_set(err, SS_ERR_INPUT, "%s: square side must be > 0", path);
    const float h = (float)(side_m / 2);
    const float pos[4][3] = {{-h, h, 0}, {h, h, 0}, {h, -h, 0}, {-h, -h, 0}};
    const float nrm[4][3] = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    const float tan[4][4] = {{1, 0, 0, 1}, {1, 0, 0, 1}, {1, 0, 0, 1}, {1, 0, 0, 1}};
    const float uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    const uint32_t idx[6] = {0, 3, 2, 0, 2, 1};
    return write_textured(path, name, &pos[0][0], &nrm[0][0], &tan[0][0], &uv[0][0], 4, idx, 2,
                          base_color_uri, metallic_roughness_uri, normal_uri, err);
}

ss_status ss_gltf_write_textured_mesh(const char *path, const struct ss_mesh *m, const char *name,
                                      const char *base_color_uri,
                                      const char *metallic_roughness_uri, const char *normal_uri,
                                      ss_error *err) {
    if (!m || !m->has_uvs || !m->uvs || m->nvertices < 3 || m->ntriangles < 1)
        return ss_error_set(err, SS_ERR_INPUT, "%s: the mesh needs triangles with UVs", path);
    /* tangents from the UVs (Lengyel's per-triangle accumulation, then
     * Gram-Schmidt against the normal; w the handedness): glTF wants them
     * with a normal map, and v grows downwards in skinsim's and glTF's UVs */
    const int nv = m->nvertices;
    float *tan = calloc((size_t)nv * 4, sizeof *tan), *bit = calloc((size_t)nv * 3, sizeof *bit);
    if (!tan || !bit) {
        free(tan), free(bit);
        return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
    }
    for (int t = 0; t < m->ntriangles; t++) {
        const uint32_t *ix = m->indices + 3 * t;
        const float *p0 = m->positions + 3 * ix[0], *p1 = m->positions + 3 * ix[1],
                    *p2 = m->positions + 3 * ix[2];
        const float *w0 = m->uvs + 2 * ix[0], *w1 = m->uvs + 2 * ix[1], *w2 = m->uvs + 2 * ix[2];
        float e1[3], e2[3], du1 = w1[0] - w0[0], dv1 = w1[1] - w0[1], du2 = w2[0] - w0[0],
                            dv2 = w2[1] - w0[1];
        for (int c = 0; c < 3; c++) e1[c] = p1[c] - p0[c], e2[c] = p2[c] - p0[c];
        float det = du1 * dv2 - du2 * dv1;
        if (!(fabsf(det) > 1e-20f)) continue;
        float r = 1.0f / det;
        for (int k = 0; k < 3; k++)
            for (int c = 0; c < 3; c++) {
                tan[4 * ix[k] + c] += (e1[c] * dv2 - e2[c] * dv1) * r;
                bit[3 * ix[k] + c] += (e2[c] * du1 - e1[c] * du2) * r;
            }
    }
    for (int i = 0; i < nv; i++) {
        const float *n = m->normals + 3 * i;
        float *tv = tan + 4 * i, d = tv[0] * n[0] + tv[1] * n[1] + tv[2] * n[2];
        for (int c = 0; c < 3; c++) tv[c] -= n[c] * d;
        float len = sqrtf(tv[0] * tv[0] + tv[1] * tv[1] + tv[2] * tv[2]);
        if (!(len > 1e-12f)) { /* no UV gradient here: any unit vector normal to n */
            float a[3] = {fabsf(n[0]) < 0.9f ? 1.0f : 0.0f, fabsf(n[0]) < 0.9f ? 0.0f : 1.0f, 0};
            d = a[0] * n[0] + a[1] * n[1];
            for (int c = 0; c < 3; c++) tv[c] = a[c] - n[c] * d;
            len = sqrtf(tv[0] * tv[0] + tv[1] * tv[1] + tv[2] * tv[2]);
        }
        for (int c = 0; c < 3; c++) tv[c] /= len;
        const float *b = bit + 3 * i;
        float cx = n[1] * tv[2] - n[2] * tv[1], cy = n[2] * tv[0] - n[0] * tv[2],
              cz = n[0] * tv[1] - n[1] * tv[0];
        tv[3] = cx * b[0] + cy * b[1] + cz * b[2] < 0.0f ? -1.0f : 1.0f;
    }
    free(bit);
    ss_status st =
        write_textured(path, name, m->positions, m->normals, tan, m->uvs, nv, m->indices,
                       m->ntriangles, base_color_uri, metallic_roughness_uri, normal_uri, err);
    free(tan);
    return st;
}

/* ---- binary glTF with per-vertex data ----------------------------------------- */

static void put_u32(unsigned char *p, uint32_t v) {
    p[0] = (unsigned char)v, p[1] = (unsigned char)(v >> 8), p[2] = (unsigned char)(v >> 16),
    p[3] = (unsigned char)(v >> 24);
}

ss_status ss_gltf_write_mesh_glb(const char *path, const struct ss_mesh *m,
                                 const ss_gltf_vertex_data *d, ss_error *err) {
    if (!m || m->nvertices < 3 || m->ntriangles < 1 || !m->positions || !m->normals || !m->indices)
        return ss_error_set(err, SS_ERR_INPUT, "%s: the mesh has no triangles", path);
    if (!d || !(d->scale_m > 0 && isfinite(d->scale_m)))
        return ss_error_set(err, SS_ERR_INPUT, "%s: the mesh scale must be > 0", path);
    if (!(d->morph_weight >= 0 && d->morph_weight <= 1))
        return ss_error_set(err, SS_ERR_INPUT, "%s: morph weight %g is not in 0..1", path,
                            d->morph_weight);
    for (int k = 0; k < d->nattrs; k++) {
        const ss_gltf_vertex_attr *a = d->attrs + k;
        if (!a->name || a->name[0] != '_' || !a->data || a->ncomp < 1 || a->ncomp > 4)
            return ss_error_set(err, SS_ERR_INPUT,
                                "%s: vertex attribute %s: a name starting with '_' (glTF's "
                                "application-specific semantics), data and 1-4 components",
                                path, a->name ? a->name : "(unnamed)");
    }
    const int nv = m->nvertices;
    const float s = (float)d->scale_m;
    float *tmp = malloc((size_t)nv * 3 * sizeof *tmp);
    if (!tmp) return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
    const char *name = d->name ? d->name : "skin";
    gbuf b;
    gb_init(&b, name);
    for (int i = 0; i < 3 * nv; i++) tmp[i] = m->positions[i] * s;
    int a_pos = gb_add(&b, tmp, nv, 3, 5126, 34962, 1);
    int a_nrm = gb_add(&b, m->normals, nv, 3, 5126, 34962, 0);
    int a_uv = m->has_uvs && m->uvs ? gb_add(&b, m->uvs, nv, 2, 5126, 34962, 0) : -1;
    int a_col = -1, a_morph = -1;
    if (d->color) {
        for (int i = 0; i < 3 * nv; i++) {
            float c = d->color[i];
            tmp[i] = c > 0 ? (c < 1 ? c : 1) : 0; /* NaN -> 0: COLOR_0 must lie in 0..1 */
        }
        a_col = gb_add(&b, tmp, nv, 3, 5126, 34962, 0);
    }
    int a_idx = gb_add(&b, m->indices, 3 * m->ntriangles, 1, 5125, 34963, 0);
    int *a_attr = calloc((size_t)d->nattrs + 1, sizeof *a_attr);
    if (!a_attr) b.failed = 1;
    for (int k = 0; a_attr && k < d->nattrs; k++)
        a_attr[k] = gb_add(&b, d->attrs[k].data, nv, d->attrs[k].ncomp, 5126, 34962, 0);
    if (d->morph_delta) {
        for (int i = 0; i < 3 * nv; i++) tmp[i] = d->morph_delta[i] * s;
        a_morph = gb_add(&b, tmp, nv, 3, 5126, 34962, 1);
    }
    free(tmp);
    cJSON *root = b.root;
    if (d->extras_json) {
        cJSON *ex = cJSON_Parse(d->extras_json);
        if (!cJSON_IsObject(ex)) {
            cJSON_Delete(ex);
            free(a_attr);
            gb_free(&b);
            return ss_error_set(err, SS_ERR_INPUT, "%s: extras are not a JSON object", path);
        }
        cJSON_AddItemToObject(cJSON_GetArrayItem(cJSON_GetObjectItem(root, "nodes"), 0), "extras",
                              ex);
    }
    cJSON *buffers = cJSON_AddArrayToObject(root, "buffers");
    cJSON *bo = cJSON_CreateObject();
    cJSON_AddNumberToObject(bo, "byteLength", (double)b.len);
    cJSON_AddItemToArray(buffers, bo);
    cJSON *mesh;
    cJSON *attrs = gb_mesh(&b, name, a_pos, a_nrm, a_idx, &mesh);
    cJSON *prim = cJSON_GetArrayItem(cJSON_GetObjectItem(mesh, "primitives"), 0);
    if (a_uv >= 0) cJSON_AddNumberToObject(attrs, "TEXCOORD_0", a_uv);
    if (a_col >= 0) cJSON_AddNumberToObject(attrs, "COLOR_0", a_col);
    for (int k = 0; a_attr && k < d->nattrs; k++)
        cJSON_AddNumberToObject(attrs, d->attrs[k].name, a_attr[k]);
    free(a_attr);
    cJSON_AddNumberToObject(prim, "mode", 4);
    if (a_morph >= 0) {
        cJSON *targets = cJSON_AddArrayToObject(prim, "targets");
        cJSON *t = cJSON_CreateObject();
        cJSON_AddNumberToObject(t, "POSITION", a_morph);
        cJSON_AddItemToArray(targets, t);
        cJSON_AddItemToObject(mesh, "weights", num_array((const double[]){d->morph_weight}, 1));
        cJSON *ex = cJSON_AddObjectToObject(mesh, "extras");
        cJSON *names = cJSON_AddArrayToObject(ex, "targetNames");
        cJSON_AddItemToArray(names,
                             cJSON_CreateString(d->morph_name ? d->morph_name : "displacement"));
    }
    /* white, rough, not metallic: the viewer shows COLOR_0 as it is */
    cJSON *materials = cJSON_AddArrayToObject(root, "materials");
    cJSON *mat = cJSON_CreateObject();
    cJSON_AddStringToObject(mat, "name", name);
    cJSON *pbr = cJSON_AddObjectToObject(mat, "pbrMetallicRoughness");
    cJSON_AddItemToObject(pbr, "baseColorFactor", num_array((const double[]){1, 1, 1, 1}, 4));
    cJSON_AddNumberToObject(pbr, "metallicFactor", 0.0);
    cJSON_AddNumberToObject(pbr, "roughnessFactor", 0.8);
    cJSON_AddItemToArray(materials, mat);

    char *json = b.failed ? NULL : cJSON_PrintUnformatted(root);
    if (!json) {
        gb_free(&b);
        return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
    }
    /* GLB: 12-byte header, the JSON chunk padded with spaces and the BIN
     * chunk padded with zeros to 4 bytes (glTF 2.0 §4.4) */
    size_t jl = strlen(json), jp = (jl + 3) & ~(size_t)3, bp = (b.len + 3) & ~(size_t)3;
    size_t total = 12 + 8 + jp + 8 + bp;
    unsigned char *out = total <= UINT32_MAX ? calloc(total, 1) : NULL;
    ss_status st;
    if (!out) {
        st = ss_error_set(err, total > UINT32_MAX ? SS_ERR_INPUT : SS_ERR_NOMEM,
                          "%s: %zu bytes do not fit a .glb", path, total);
    } else {
        put_u32(out, 0x46546C67u); /* "glTF" */
        put_u32(out + 4, 2);
        put_u32(out + 8, (uint32_t)total);
        put_u32(out + 12, (uint32_t)jp);
        put_u32(out + 16, 0x4E4F534Au); /* "JSON" */
        memcpy(out + 20, json, jl);
        memset(out + 20 + jl, ' ', jp - jl);
        put_u32(out + 20 + jp, (uint32_t)bp);
        put_u32(out + 24 + jp, 0x004E4942u); /* "BIN\0" */
        memcpy(out + 28 + jp, b.data, b.len);
        st = ss_write_file_atomic(path, out, total, err);
    }
    free(out);
    free(json);
    gb_free(&b);
    return st;
}
