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

static void add_view(cJSON *views, int offset, int length, int target) {
    cJSON *v = cJSON_CreateObject();
    cJSON_AddNumberToObject(v, "buffer", 0);
    cJSON_AddNumberToObject(v, "byteOffset", offset);
    cJSON_AddNumberToObject(v, "byteLength", length);
    cJSON_AddNumberToObject(v, "target", target);
    cJSON_AddItemToArray(views, v);
}

static void add_accessor(cJSON *acc, int view, int component, int count, const char *type,
                         const double *min, const double *max, int ncomp) {
    cJSON *a = cJSON_CreateObject();
    cJSON_AddNumberToObject(a, "bufferView", view);
    cJSON_AddNumberToObject(a, "componentType", component);
    cJSON_AddNumberToObject(a, "count", count);
    cJSON_AddStringToObject(a, "type", type);
    if (min) cJSON_AddItemToObject(a, "min", num_array(min, ncomp));
    if (max) cJSON_AddItemToObject(a, "max", num_array(max, ncomp));
    cJSON_AddItemToArray(acc, a);
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

/* One textured triangle mesh as a glTF 2.0 file: the arrays packed into one
 * base64 buffer (positions, normals, optional tangents, UVs, 32-bit indices),
 * a metallic-roughness material with the given texture URIs. */
static ss_status write_textured(const char *path, const char *name, const float *pos,
                                const float *nrm, const float *tan, const float *uv, int nv,
                                const uint32_t *idx, int nt, const char *base_color_uri,
                                const char *metallic_roughness_uri, const char *normal_uri,
                                ss_error *err) {
    const size_t o_pos = 0, o_nrm = o_pos + (size_t)nv * 12, o_tan = o_nrm + (size_t)nv * 12,
                 o_uv = o_tan + (tan ? (size_t)nv * 16 : 0), o_idx = o_uv + (size_t)nv * 8,
                 total = o_idx + (size_t)nt * 12;
    unsigned char *buf = malloc(total);
    if (!buf) return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
    memcpy(buf + o_pos, pos, (size_t)nv * 12);
    memcpy(buf + o_nrm, nrm, (size_t)nv * 12);
    if (tan) memcpy(buf + o_tan, tan, (size_t)nv * 16);
    memcpy(buf + o_uv, uv, (size_t)nv * 8);
    memcpy(buf + o_idx, idx, (size_t)nt * 12);
    double pmin[3] = {INFINITY, INFINITY, INFINITY}, pmax[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < nv; i++)
        for (int c = 0; c < 3; c++) {
            if (pos[3 * i + c] < pmin[c]) pmin[c] = pos[3 * i + c];
            if (pos[3 * i + c] > pmax[c]) pmax[c] = pos[3 * i + c];
        }
    char *b64 = base64(buf, total);
    free(buf);
    if (!b64) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    size_t urilen = strlen(b64) + 64;
    char *uri = malloc(urilen);
    if (!uri) {
        free(b64);
        return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    snprintf(uri, urilen, "data:application/octet-stream;base64,%s", b64);
    free(b64);

    cJSON *root = cJSON_CreateObject();
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
    cJSON_AddStringToObject(node, "name", name ? name : "skin");
    cJSON_AddNumberToObject(node, "mesh", 0);
    cJSON_AddItemToArray(nodes, node);

    cJSON *buffers = cJSON_AddArrayToObject(root, "buffers");
    cJSON *b = cJSON_CreateObject();
    cJSON_AddNumberToObject(b, "byteLength", (double)total);
    cJSON_AddStringToObject(b, "uri", uri);
    cJSON_AddItemToArray(buffers, b);
    free(uri);
    cJSON *views = cJSON_AddArrayToObject(root, "bufferViews");
    cJSON *acc = cJSON_AddArrayToObject(root, "accessors");
    int view = 0;
    add_view(views, (int)o_pos, nv * 12, 34962);
    add_accessor(acc, view++, 5126, nv, "VEC3", pmin, pmax, 3);
    add_view(views, (int)o_nrm, nv * 12, 34962);
    add_accessor(acc, view++, 5126, nv, "VEC3", NULL, NULL, 3);
    int tan_acc = -1;
    if (tan) {
        add_view(views, (int)o_tan, nv * 16, 34962);
        tan_acc = view;
        add_accessor(acc, view++, 5126, nv, "VEC4", NULL, NULL, 4);
    }
    add_view(views, (int)o_uv, nv * 8, 34962);
    int uv_acc = view;
    add_accessor(acc, view++, 5126, nv, "VEC2", NULL, NULL, 2);
    add_view(views, (int)o_idx, nt * 12, 34963);
    int idx_acc = view;
    add_accessor(acc, view++, 5125, nt * 3, "SCALAR", NULL, NULL, 1);

    cJSON *meshes = cJSON_AddArrayToObject(root, "meshes");
    cJSON *mesh = cJSON_CreateObject();
    cJSON *prims = cJSON_AddArrayToObject(mesh, "primitives");
    cJSON *prim = cJSON_CreateObject();
    cJSON *attrs = cJSON_AddObjectToObject(prim, "attributes");
    cJSON_AddNumberToObject(attrs, "POSITION", 0);
    cJSON_AddNumberToObject(attrs, "NORMAL", 1);
    if (tan_acc >= 0) cJSON_AddNumberToObject(attrs, "TANGENT", tan_acc);
    cJSON_AddNumberToObject(attrs, "TEXCOORD_0", uv_acc);
    cJSON_AddNumberToObject(prim, "indices", idx_acc);
    cJSON_AddNumberToObject(prim, "material", 0);
    cJSON_AddItemToArray(prims, prim);
    cJSON_AddItemToArray(meshes, mesh);

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
    cJSON_Delete(root);
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
