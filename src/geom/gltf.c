/* glTF 2.0 output (written with cJSON, no glTF library): a textured square
 * that shows a texture set in any glTF viewer or Blender. The geometry (4
 * vertices with normal, tangent and UV; 2 triangles) is embedded as a base64
 * buffer; the textures are referenced by relative URI, so the .gltf sits next
 * to its PNGs. glTF units are metres, +Y up; the square lies in the XY plane
 * facing +Z, with UV (0,0) at the top-left like the images. */
#include "skinsim/geom.h"

#include <cjson/cJSON.h>
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

ss_status ss_gltf_write_textured_square(const char *path, double side_m, const char *name,
                                        const char *base_color_uri,
                                        const char *metallic_roughness_uri, const char *normal_uri,
                                        ss_error *err) {
    if (!(side_m > 0)) return ss_error_set(err, SS_ERR_INPUT, "%s: square side must be > 0", path);
    const float h = (float)(side_m / 2);
    /* Vertex layout: 4 positions, 4 normals, 4 tangents, 4 UVs, 6 indices. */
    struct {
        float pos[4][3], nrm[4][3], tan[4][4], uv[4][2];
        unsigned short idx[6];
        unsigned short pad;
    } buf = {{{-h, h, 0}, {h, h, 0}, {h, -h, 0}, {-h, -h, 0}},
             {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}},
             {{1, 0, 0, 1}, {1, 0, 0, 1}, {1, 0, 0, 1}, {1, 0, 0, 1}},
             {{0, 0}, {1, 0}, {1, 1}, {0, 1}},
             {0, 3, 2, 0, 2, 1},
             0};
    char *b64 = base64((const unsigned char *)&buf, sizeof buf);
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
    cJSON_AddNumberToObject(b, "byteLength", (double)sizeof buf);
    cJSON_AddStringToObject(b, "uri", uri);
    cJSON_AddItemToArray(buffers, b);
    free(uri);
    cJSON *views = cJSON_AddArrayToObject(root, "bufferViews");
    add_view(views, 0, 48, 34962);   /* positions */
    add_view(views, 48, 48, 34962);  /* normals */
    add_view(views, 96, 64, 34962);  /* tangents */
    add_view(views, 160, 32, 34962); /* uvs */
    add_view(views, 192, 12, 34963); /* indices */
    cJSON *acc = cJSON_AddArrayToObject(root, "accessors");
    const double pmin[3] = {-h, -h, 0}, pmax[3] = {h, h, 0};
    add_accessor(acc, 0, 5126, 4, "VEC3", pmin, pmax, 3);
    add_accessor(acc, 1, 5126, 4, "VEC3", NULL, NULL, 3);
    add_accessor(acc, 2, 5126, 4, "VEC4", NULL, NULL, 4);
    add_accessor(acc, 3, 5126, 4, "VEC2", NULL, NULL, 2);
    add_accessor(acc, 4, 5123, 6, "SCALAR", NULL, NULL, 1);

    cJSON *meshes = cJSON_AddArrayToObject(root, "meshes");
    cJSON *mesh = cJSON_CreateObject();
    cJSON *prims = cJSON_AddArrayToObject(mesh, "primitives");
    cJSON *prim = cJSON_CreateObject();
    cJSON *attrs = cJSON_AddObjectToObject(prim, "attributes");
    cJSON_AddNumberToObject(attrs, "POSITION", 0);
    cJSON_AddNumberToObject(attrs, "NORMAL", 1);
    cJSON_AddNumberToObject(attrs, "TANGENT", 2);
    cJSON_AddNumberToObject(attrs, "TEXCOORD_0", 3);
    cJSON_AddNumberToObject(prim, "indices", 4);
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
