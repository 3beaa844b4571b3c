/* glTF 2.0 reader (.gltf JSON and .glb binary), written with cJSON; no glTF
 * library (cgltf is not packaged in Debian, DESIGN.md). It reads what a
 * textured body needs: triangle primitives (mode 4, and strips 5 and fans 6
 * turned into triangles), POSITION, NORMAL and TEXCOORD_0, indices of any
 * unsigned type, byteStride, normalised integer UVs. Buffers come from the
 * GLB BIN chunk, base64 data URIs, or files inside the .gltf's folder (a
 * URI with "..", an absolute path or a symbolic link out of the folder is
 * refused by name: a scene must not read what lies beside it).
 *
 * All primitives of all mesh nodes of the default scene (else every root
 * node, else every mesh) are merged into one ss_mesh with their world
 * transforms applied: positions by the node matrix, normals by its inverse
 * transpose, winding reversed under a mirroring transform. A skinned node
 * keeps its vertices as stored (the bind pose): the spec ignores a skinned
 * node's own transform and the joints in their rest pose cancel the
 * inverse bind matrices. Animation, morph targets and materials are not
 * read.
 *
 * Every offset, stride and count is checked against the buffer it reads, so
 * a broken or hostile file is an input error naming the file and the object
 * (accessor 3, bufferView 1, ...), never a read past the end. Sparse
 * accessors and compression extensions (Draco, meshopt) are refused by
 * name. */
#include "skinsim/mesh.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

ss_status ss_mesh_load_gltf(const char *path, ss_mesh *out, ss_error *err);

#define MAX_NODE_DEPTH 64

typedef struct blob {
    unsigned char *data;
    size_t len;
    int owned;
} blob;

typedef struct gltf_doc {
    const char *path;
    cJSON *json;
    blob *buffers;
    int nbuffers;
    const unsigned char *bin; /* GLB BIN chunk (inside file) */
    size_t bin_len;
    /* merged output */
    float *pos, *nrm, *uv;
    size_t nv, cap_v;
    uint32_t *idx;
    size_t ni, cap_i;
    int all_uv, all_nrm, prims;
} gltf_doc;

/* ---- small helpers ------------------------------------------------------ */

static int get_int(const cJSON *obj, const char *key, long long *out) {
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!it) return 0;
    if (!cJSON_IsNumber(it)) return -1;
    double d = it->valuedouble;
    if (!(d >= 0 && d <= 9.0e15) || d != floor(d)) return -1;
    *out = (long long)d;
    return 1;
}

static int b64_value(int c) {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+' || c == '-') return 62;
    if (c == '/' || c == '_') return 63;
    return -1;
}

static unsigned char *base64_decode(const char *s, size_t *len) {
    size_t n = strlen(s);
    unsigned char *out = malloc(n / 4 * 3 + 3), *o = out;
    if (!out) return NULL;
    unsigned acc = 0;
    int bits = 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] == '=') break;
        int v = b64_value((unsigned char)s[i]);
        if (v < 0) {
            free(out);
            return NULL;
        }
        acc = (acc << 6) | (unsigned)v;
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            *o++ = (unsigned char)(acc >> bits);
            acc &= (1u << bits) - 1;
        }
    }
    *len = (size_t)(o - out);
    return out;
}

/* Percent-decodes a relative URI into a path next to the .gltf. */
static char *sibling_path(const char *gltf_path, const char *uri) {
    const char *slash = strrchr(gltf_path, '/');
    size_t dir = slash ? (size_t)(slash - gltf_path + 1) : 0;
    char *out = malloc(dir + strlen(uri) + 1);
    if (!out) return NULL;
    memcpy(out, gltf_path, dir);
    char *o = out + dir;
    for (const char *p = uri; *p; p++) {
        if (p[0] == '%' && p[1] && p[2]) {
            char hex[3] = {p[1], p[2], 0};
            char *end;
            long v = strtol(hex, &end, 16);
            if (*end == '\0' && v > 0) {
                *o++ = (char)v;
                p += 2;
                continue;
            }
        }
        *o++ = *p;
    }
    *o = '\0';
    return out;
}

static ss_status load_buffers(gltf_doc *d, ss_error *err) {
    const cJSON *bufs = cJSON_GetObjectItemCaseSensitive(d->json, "buffers");
    if (!bufs) return SS_OK;
    if (!cJSON_IsArray(bufs))
        return ss_error_set(err, SS_ERR_INPUT, "%s: 'buffers' is not an array", d->path);
    int n = cJSON_GetArraySize(bufs);
    d->buffers = calloc((size_t)(n ? n : 1), sizeof *d->buffers);
    if (!d->buffers) return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", d->path);
    d->nbuffers = n;
    for (int i = 0; i < n; i++) {
        const cJSON *b = cJSON_GetArrayItem(bufs, i);
        long long blen = 0;
        if (!cJSON_IsObject(b) || get_int(b, "byteLength", &blen) != 1)
            return ss_error_set(err, SS_ERR_INPUT, "%s: buffer %d has no valid byteLength", d->path,
                                i);
        const cJSON *uri = cJSON_GetObjectItemCaseSensitive(b, "uri");
        blob *bl = &d->buffers[i];
        if (!uri) {
            if (i != 0 || !d->bin)
                return ss_error_set(err, SS_ERR_INPUT,
                                    "%s: buffer %d has no uri and there is no GLB BIN chunk",
                                    d->path, i);
            bl->data = (unsigned char *)d->bin;
            bl->len = d->bin_len;
        } else if (!cJSON_IsString(uri)) {
            return ss_error_set(err, SS_ERR_INPUT, "%s: buffer %d: uri is not a string", d->path,
                                i);
        } else if (!strncmp(uri->valuestring, "data:", 5)) {
            const char *comma = strchr(uri->valuestring, ',');
            if (!comma || (comma - uri->valuestring) < 7 || strncmp(comma - 7, ";base64", 7))
                return ss_error_set(err, SS_ERR_INPUT,
                                    "%s: buffer %d: only base64 data URIs are supported", d->path,
                                    i);
            bl->data = base64_decode(comma + 1, &bl->len);
            if (!bl->data)
                return ss_error_set(err, SS_ERR_INPUT, "%s: buffer %d: bad base64 data", d->path,
                                    i);
            bl->owned = 1;
        } else {
            if (strstr(uri->valuestring, "://"))
                return ss_error_set(err, SS_ERR_INPUT,
                                    "%s: buffer %d: remote uri '%s' is not supported", d->path, i,
                                    uri->valuestring);
            /* decoded, then held inside the .gltf's folder: no "..", no
             * absolute path, no symbolic link out of it */
            char *rel = sibling_path("", uri->valuestring), *file = NULL;
            if (!rel) return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", d->path);
            ss_error e2;
            ss_status ps = ss_input_path_inside(d->path, rel, &file, &e2);
            free(rel);
            if (ps) return ss_error_set(err, SS_ERR_INPUT, "buffer %d: %s", i, e2.msg);
            char *data = ss_read_file_max(file, &bl->len, SS_READ_MAX_MESH, &e2);
            free(file);
            if (!data)
                return ss_error_set(err, SS_ERR_INPUT, "%s: buffer %d: %s", d->path, i, e2.msg);
            bl->data = (unsigned char *)data;
            bl->owned = 1;
        }
        if ((unsigned long long)blen > bl->len)
            return ss_error_set(err, SS_ERR_INPUT,
                                "%s: buffer %d: byteLength %lld but only %zu bytes present",
                                d->path, i, blen, bl->len);
        bl->len = (size_t)blen;
    }
    return SS_OK;
}

/* ---- accessors ------------------------------------------------------------ */

static int type_components(const char *t) {
    if (!strcmp(t, "SCALAR")) return 1;
    if (!strcmp(t, "VEC2")) return 2;
    if (!strcmp(t, "VEC3")) return 3;
    if (!strcmp(t, "VEC4")) return 4;
    if (!strcmp(t, "MAT2")) return 4;
    if (!strcmp(t, "MAT3")) return 9;
    if (!strcmp(t, "MAT4")) return 16;
    return 0;
}

static int component_size(long long ct) {
    switch (ct) {
    case 5120:
    case 5121:
        return 1; /* BYTE, UNSIGNED_BYTE */
    case 5122:
    case 5123:
        return 2; /* SHORT, UNSIGNED_SHORT */
    case 5125:
    case 5126:
        return 4; /* UNSIGNED_INT, FLOAT */
    default:
        return 0;
    }
}

static double read_component(const unsigned char *p, long long ct, int normalized) {
    switch (ct) {
    case 5120: {
        signed char v;
        memcpy(&v, p, 1);
        return normalized ? fmax(v / 127.0, -1.0) : v;
    }
    case 5121:
        return normalized ? p[0] / 255.0 : p[0];
    case 5122: {
        int16_t v;
        memcpy(&v, p, 2);
        return normalized ? fmax(v / 32767.0, -1.0) : v;
    }
    case 5123: {
        uint16_t v;
        memcpy(&v, p, 2);
        return normalized ? v / 65535.0 : v;
    }
    case 5125: {
        uint32_t v;
        memcpy(&v, p, 4);
        return v;
    }
    default: {
        float v;
        memcpy(&v, p, 4);
        return v;
    }
    }
}

/* Reads accessor `ai` as *count elements of ncomp doubles (malloc'd). The
 * accessor must have exactly ncomp components; allowed_types is a bit set
 * of component sizes accepted (float always when want_float). */
static ss_status read_accessor(gltf_doc *d, long long ai, int ncomp, const char *what,
                               int allow_int, double **out, size_t *count, ss_error *err) {
    *out = NULL;
    const cJSON *accs = cJSON_GetObjectItemCaseSensitive(d->json, "accessors");
    if (!cJSON_IsArray(accs) || ai < 0 || ai >= cJSON_GetArraySize(accs))
        return ss_error_set(err, SS_ERR_INPUT, "%s: %s refers to missing accessor %lld", d->path,
                            what, ai);
    const cJSON *a = cJSON_GetArrayItem(accs, (int)ai);
    long long ct = 0, cnt = 0, off = 0, bv = -1;
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(a, "type");
    if (!cJSON_IsObject(a) || get_int(a, "componentType", &ct) != 1 ||
        get_int(a, "count", &cnt) != 1 || get_int(a, "byteOffset", &off) < 0 ||
        get_int(a, "bufferView", &bv) < 0 || !cJSON_IsString(type))
        return ss_error_set(err, SS_ERR_INPUT, "%s: accessor %lld is malformed", d->path, ai);
    if (cJSON_GetObjectItemCaseSensitive(a, "sparse"))
        return ss_error_set(err, SS_ERR_INPUT, "%s: accessor %lld is sparse (not supported)",
                            d->path, ai);
    int nc = type_components(type->valuestring), cs = component_size(ct);
    if (nc != ncomp || cs == 0 || (!allow_int && ct != 5126))
        return ss_error_set(
            err, SS_ERR_INPUT, "%s: accessor %lld (%s) has type %s/%lld, expected %d components%s",
            d->path, ai, what, type->valuestring, ct, ncomp, allow_int ? "" : " of FLOAT");
    if (cnt > (1LL << 28))
        return ss_error_set(err, SS_ERR_INPUT, "%s: accessor %lld: count too large", d->path, ai);
    const cJSON *norm = cJSON_GetObjectItemCaseSensitive(a, "normalized");
    int normalized = cJSON_IsTrue(norm);
    double *v = calloc((size_t)(cnt ? cnt : 1) * (size_t)ncomp, sizeof *v);
    if (!v) return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", d->path);
    *count = (size_t)cnt;
    *out = v;
    if (bv < 0) return SS_OK; /* no bufferView: all zeros, as the spec says */
    const cJSON *views = cJSON_GetObjectItemCaseSensitive(d->json, "bufferViews");
    if (!cJSON_IsArray(views) || bv >= cJSON_GetArraySize(views))
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: accessor %lld refers to missing bufferView %lld", d->path, ai, bv);
    const cJSON *view = cJSON_GetArrayItem(views, (int)bv);
    long long buf = -1, voff = 0, vlen = 0, stride = 0;
    if (!cJSON_IsObject(view) || get_int(view, "buffer", &buf) != 1 ||
        get_int(view, "byteLength", &vlen) != 1 || get_int(view, "byteOffset", &voff) < 0 ||
        get_int(view, "byteStride", &stride) < 0)
        return ss_error_set(err, SS_ERR_INPUT, "%s: bufferView %lld is malformed", d->path, bv);
    if (buf >= d->nbuffers)
        return ss_error_set(err, SS_ERR_INPUT, "%s: bufferView %lld refers to missing buffer %lld",
                            d->path, bv, buf);
    const blob *b = &d->buffers[buf];
    if ((unsigned long long)voff + (unsigned long long)vlen > b->len)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: bufferView %lld runs past the end of buffer %lld", d->path, bv,
                            buf);
    long long elem = (long long)nc * cs;
    if (stride == 0) stride = elem;
    if (stride < elem || stride > 252)
        return ss_error_set(err, SS_ERR_INPUT, "%s: bufferView %lld: bad byteStride %lld", d->path,
                            bv, stride);
    if (cnt > 0 && (unsigned long long)off +
                           (unsigned long long)(cnt - 1) * (unsigned long long)stride +
                           (unsigned long long)elem >
                       (unsigned long long)vlen)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: accessor %lld (%s) reads past the end of bufferView %lld", d->path,
                            ai, what, bv);
    const unsigned char *base = b->data + voff + off;
    for (long long i = 0; i < cnt; i++)
        for (int c = 0; c < nc; c++)
            v[i * nc + c] = read_component(base + i * stride + c * cs, ct, normalized);
    return SS_OK;
}

/* ---- merging primitives ---------------------------------------------------- */

static int grow(void **p, size_t *cap, size_t need, size_t elem) {
    if (need <= *cap) return 0;
    size_t c = *cap ? *cap : 1024;
    while (c < need) c *= 2;
    void *q = realloc(*p, c * elem);
    if (!q) return -1;
    *p = q;
    *cap = c;
    return 0;
}

static void mat_mul(const double *a, const double *b, double *out) { /* column-major */
    double r[16];
    for (int c = 0; c < 4; c++)
        for (int rr = 0; rr < 4; rr++) {
            double s = 0;
            for (int k = 0; k < 4; k++) s += a[k * 4 + rr] * b[c * 4 + k];
            r[c * 4 + rr] = s;
        }
    memcpy(out, r, sizeof r);
}

/* Inverse transpose of the upper 3x3 (row-major result n[r*3+c]) and the
 * determinant of the 3x3. */
static double normal_matrix(const double *m, double n[9]) {
    double a = m[0], b = m[4], c = m[8], dd = m[1], e = m[5], f = m[9], g = m[2], h = m[6],
           i = m[10];
    double A = e * i - f * h, B = -(dd * i - f * g), C = dd * h - e * g;
    double det = a * A + b * B + c * C;
    /* cofactor matrix == det * inverse transpose */
    n[0] = A, n[1] = B, n[2] = C;
    n[3] = -(b * i - c * h), n[4] = a * i - c * g, n[5] = -(a * h - b * g);
    n[6] = b * f - c * e, n[7] = -(a * f - c * dd), n[8] = a * e - b * dd;
    return det;
}

static ss_status add_primitive(gltf_doc *d, const cJSON *prim, int mesh_i, int prim_i,
                               const double *mat, ss_error *err) {
    long long mode = 4, pa = -1, na = -1, ta = -1, ia = -1;
    if (get_int(prim, "mode", &mode) < 0)
        return ss_error_set(err, SS_ERR_INPUT, "%s: mesh %d primitive %d: bad mode", d->path,
                            mesh_i, prim_i);
    if (mode != 4 && mode != 5 && mode != 6) return SS_OK; /* points and lines: skipped */
    const cJSON *attrs = cJSON_GetObjectItemCaseSensitive(prim, "attributes");
    if (!cJSON_IsObject(attrs) || get_int(attrs, "POSITION", &pa) != 1)
        return ss_error_set(err, SS_ERR_INPUT, "%s: mesh %d primitive %d has no POSITION", d->path,
                            mesh_i, prim_i);
    if (get_int(attrs, "NORMAL", &na) < 0 || get_int(attrs, "TEXCOORD_0", &ta) < 0 ||
        get_int(prim, "indices", &ia) < 0)
        return ss_error_set(err, SS_ERR_INPUT, "%s: mesh %d primitive %d: bad attribute index",
                            d->path, mesh_i, prim_i);
    const cJSON *ext = cJSON_GetObjectItemCaseSensitive(prim, "extensions");
    if (cJSON_GetObjectItemCaseSensitive(ext, "KHR_draco_mesh_compression"))
        return ss_error_set(err, SS_ERR_INPUT, "%s: mesh %d uses Draco compression (not supported)",
                            d->path, mesh_i);
    double *P = NULL, *N = NULL, *T = NULL, *I = NULL;
    size_t np = 0, nn = 0, nt = 0, ni = 0;
    char what[64];
    snprintf(what, sizeof what, "mesh %d POSITION", mesh_i);
    ss_status st = read_accessor(d, pa, 3, what, 0, &P, &np, err);
    if (!st && na >= 0) {
        snprintf(what, sizeof what, "mesh %d NORMAL", mesh_i);
        st = read_accessor(d, na, 3, what, 0, &N, &nn, err);
        if (!st && nn != np)
            st = ss_error_set(err, SS_ERR_INPUT, "%s: mesh %d: NORMAL count differs from POSITION",
                              d->path, mesh_i);
    }
    if (!st && ta >= 0) {
        snprintf(what, sizeof what, "mesh %d TEXCOORD_0", mesh_i);
        st = read_accessor(d, ta, 2, what, 1, &T, &nt, err);
        if (!st && nt != np)
            st = ss_error_set(err, SS_ERR_INPUT,
                              "%s: mesh %d: TEXCOORD_0 count differs from POSITION", d->path,
                              mesh_i);
    }
    if (!st && ia >= 0) {
        snprintf(what, sizeof what, "mesh %d indices", mesh_i);
        st = read_accessor(d, ia, 1, what, 1, &I, &ni, err);
    }
    /* Corner list of the primitive (vertex indices local to it). */
    size_t ncorner = ia >= 0 ? ni : np;
    uint32_t *tri = NULL;
    size_t ntri = 0;
    if (!st) {
        size_t maxtri = ncorner >= 3 ? (mode == 4 ? ncorner / 3 : ncorner - 2) : 0;
        tri = malloc(sizeof *tri * 3 * (maxtri ? maxtri : 1));
        if (!tri) st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", d->path);
        for (size_t k = 0; !st && k < ncorner; k++) {
            double v = ia >= 0 ? I[k] : (double)k;
            if (ia >= 0 && (v < 0 || v >= (double)np || v != floor(v)))
                st =
                    ss_error_set(err, SS_ERR_INPUT,
                                 "%s: mesh %d primitive %d: index %.0f out of range (%zu vertices)",
                                 d->path, mesh_i, prim_i, v, np);
        }
        for (size_t t = 0; !st && t < maxtri; t++) {
            size_t c[3];
            if (mode == 4)
                c[0] = 3 * t, c[1] = 3 * t + 1, c[2] = 3 * t + 2;
            else if (mode == 5)
                c[0] = t, c[1] = t % 2 ? t + 2 : t + 1, c[2] = t % 2 ? t + 1 : t + 2;
            else
                c[0] = 0, c[1] = t + 1, c[2] = t + 2;
            for (int k = 0; k < 3; k++)
                tri[3 * ntri + k] = (uint32_t)(ia >= 0 ? I[c[k]] : (double)c[k]);
            ntri++;
        }
    }
    if (!st) {
        if (d->nv + np > ((size_t)1 << 28) || d->ni + 3 * ntri > ((size_t)3 << 28))
            st = ss_error_set(err, SS_ERR_INPUT, "%s: too many vertices", d->path);
        else if (grow((void **)&d->pos, &d->cap_v, d->nv + np, sizeof(float) * 3) ||
                 grow((void **)&d->idx, &d->cap_i, d->ni + 3 * ntri, sizeof(uint32_t)))
            st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", d->path);
        else {
            /* nrm and uv share cap_v with pos: reallocate them to the same size. */
            float *nr = realloc(d->nrm, sizeof(float) * 3 * d->cap_v);
            if (nr) d->nrm = nr;
            float *uv = realloc(d->uv, sizeof(float) * 2 * d->cap_v);
            if (uv) d->uv = uv;
            if (!nr || !uv) st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", d->path);
        }
    }
    if (!st) {
        double nm[9];
        double det = normal_matrix(mat, nm);
        for (size_t v = 0; v < np; v++) {
            const double *p = P + 3 * v;
            for (int r = 0; r < 3; r++)
                d->pos[3 * (d->nv + v) + r] =
                    (float)(mat[r] * p[0] + mat[4 + r] * p[1] + mat[8 + r] * p[2] + mat[12 + r]);
            for (int r = 0; r < 3; r++) {
                double nv = 0;
                if (N)
                    nv = nm[3 * r] * N[3 * v] + nm[3 * r + 1] * N[3 * v + 1] +
                         nm[3 * r + 2] * N[3 * v + 2];
                d->nrm[3 * (d->nv + v) + r] = (float)(det < 0 ? -nv : nv);
            }
            d->uv[2 * (d->nv + v)] = T ? (float)T[2 * v] : 0.0f;
            d->uv[2 * (d->nv + v) + 1] = T ? (float)T[2 * v + 1] : 0.0f;
        }
        for (size_t t = 0; t < ntri; t++)
            for (int k = 0; k < 3; k++) {
                int kk = det < 0 ? (k == 0 ? 0 : 3 - k) : k; /* mirrored: reverse winding */
                d->idx[d->ni + 3 * t + k] = (uint32_t)d->nv + tri[3 * t + kk];
            }
        d->nv += np;
        d->ni += 3 * ntri;
        if (!T) d->all_uv = 0;
        if (!N) d->all_nrm = 0;
        d->prims++;
    }
    free(P), free(N), free(T), free(I), free(tri);
    return st;
}

static ss_status add_mesh(gltf_doc *d, long long mi, const double *mat, ss_error *err) {
    const cJSON *meshes = cJSON_GetObjectItemCaseSensitive(d->json, "meshes");
    if (!cJSON_IsArray(meshes) || mi >= cJSON_GetArraySize(meshes))
        return ss_error_set(err, SS_ERR_INPUT, "%s: node refers to missing mesh %lld", d->path, mi);
    const cJSON *mesh = cJSON_GetArrayItem(meshes, (int)mi);
    const cJSON *prims = cJSON_GetObjectItemCaseSensitive(mesh, "primitives");
    if (!cJSON_IsArray(prims))
        return ss_error_set(err, SS_ERR_INPUT, "%s: mesh %lld has no primitives", d->path, mi);
    for (int p = 0; p < cJSON_GetArraySize(prims); p++) {
        const cJSON *prim = cJSON_GetArrayItem(prims, p);
        if (!cJSON_IsObject(prim))
            return ss_error_set(err, SS_ERR_INPUT, "%s: mesh %lld primitive %d is not an object",
                                d->path, mi, p);
        ss_status st = add_primitive(d, prim, (int)mi, p, mat, err);
        if (st) return st;
    }
    return SS_OK;
}

static ss_status read_numbers(const cJSON *arr, double *out, int n) {
    if (!cJSON_IsArray(arr) || cJSON_GetArraySize(arr) != n) return SS_ERR_INPUT;
    for (int i = 0; i < n; i++) {
        const cJSON *it = cJSON_GetArrayItem(arr, i);
        if (!cJSON_IsNumber(it) || !isfinite(it->valuedouble)) return SS_ERR_INPUT;
        out[i] = it->valuedouble;
    }
    return SS_OK;
}

/* The node's local matrix (column-major): matrix, or T * R * S. */
static ss_status node_matrix(gltf_doc *d, const cJSON *node, long long ni, double *m,
                             ss_error *err) {
    static const double id[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    memcpy(m, id, sizeof id);
    const cJSON *mat = cJSON_GetObjectItemCaseSensitive(node, "matrix");
    if (mat) {
        if (read_numbers(mat, m, 16))
            return ss_error_set(err, SS_ERR_INPUT, "%s: node %lld: bad matrix", d->path, ni);
        return SS_OK;
    }
    double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
    const cJSON *jt = cJSON_GetObjectItemCaseSensitive(node, "translation");
    const cJSON *jr = cJSON_GetObjectItemCaseSensitive(node, "rotation");
    const cJSON *js = cJSON_GetObjectItemCaseSensitive(node, "scale");
    if ((jt && read_numbers(jt, t, 3)) || (jr && read_numbers(jr, q, 4)) ||
        (js && read_numbers(js, s, 3)))
        return ss_error_set(err, SS_ERR_INPUT, "%s: node %lld: bad translation/rotation/scale",
                            d->path, ni);
    double qn = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(qn > 0))
        return ss_error_set(err, SS_ERR_INPUT, "%s: node %lld: zero rotation quaternion", d->path,
                            ni);
    double x = q[0] / qn, y = q[1] / qn, z = q[2] / qn, w = q[3] / qn;
    double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),
                   2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                   2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y)};
    for (int c = 0; c < 3; c++)
        for (int rr = 0; rr < 3; rr++) m[c * 4 + rr] = r[c * 3 + rr] * s[c];
    m[12] = t[0], m[13] = t[1], m[14] = t[2];
    return SS_OK;
}

static ss_status visit_node(gltf_doc *d, long long ni, const double *parent, int depth,
                            ss_error *err) {
    const cJSON *nodes = cJSON_GetObjectItemCaseSensitive(d->json, "nodes");
    if (!cJSON_IsArray(nodes) || ni < 0 || ni >= cJSON_GetArraySize(nodes))
        return ss_error_set(err, SS_ERR_INPUT, "%s: reference to missing node %lld", d->path, ni);
    if (depth > MAX_NODE_DEPTH)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: node hierarchy deeper than %d (a cycle?) at node %lld", d->path,
                            MAX_NODE_DEPTH, ni);
    const cJSON *node = cJSON_GetArrayItem(nodes, (int)ni);
    if (!cJSON_IsObject(node))
        return ss_error_set(err, SS_ERR_INPUT, "%s: node %lld is not an object", d->path, ni);
    double local[16], world[16];
    ss_status st = node_matrix(d, node, ni, local, err);
    if (st) return st;
    mat_mul(parent, local, world);
    long long mi = -1, si = -1;
    if (get_int(node, "mesh", &mi) < 0 || get_int(node, "skin", &si) < 0)
        return ss_error_set(err, SS_ERR_INPUT, "%s: node %lld: bad mesh or skin index", d->path,
                            ni);
    if (mi >= 0) {
        static const double id[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        st = add_mesh(d, mi, si >= 0 ? id : world, err);
        if (st) return st;
    }
    const cJSON *children = cJSON_GetObjectItemCaseSensitive(node, "children");
    if (children && !cJSON_IsArray(children))
        return ss_error_set(err, SS_ERR_INPUT, "%s: node %lld: children is not an array", d->path,
                            ni);
    for (int c = 0; children && c < cJSON_GetArraySize(children); c++) {
        const cJSON *ch = cJSON_GetArrayItem(children, c);
        if (!cJSON_IsNumber(ch) || ch->valuedouble != floor(ch->valuedouble))
            return ss_error_set(err, SS_ERR_INPUT, "%s: node %lld: bad child index", d->path, ni);
        st = visit_node(d, (long long)ch->valuedouble, world, depth + 1, err);
        if (st) return st;
    }
    return SS_OK;
}

static ss_status walk_scene(gltf_doc *d, ss_error *err) {
    static const double id[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    const cJSON *scenes = cJSON_GetObjectItemCaseSensitive(d->json, "scenes");
    const cJSON *nodes = cJSON_GetObjectItemCaseSensitive(d->json, "nodes");
    long long si = 0;
    if (get_int(d->json, "scene", &si) < 0)
        return ss_error_set(err, SS_ERR_INPUT, "%s: bad 'scene' index", d->path);
    if (cJSON_IsArray(scenes) && cJSON_GetArraySize(scenes) > 0) {
        if (si >= cJSON_GetArraySize(scenes))
            return ss_error_set(err, SS_ERR_INPUT, "%s: default scene %lld does not exist", d->path,
                                si);
        const cJSON *roots =
            cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(scenes, (int)si), "nodes");
        for (int i = 0; cJSON_IsArray(roots) && i < cJSON_GetArraySize(roots); i++) {
            const cJSON *r = cJSON_GetArrayItem(roots, i);
            if (!cJSON_IsNumber(r) || r->valuedouble != floor(r->valuedouble))
                return ss_error_set(err, SS_ERR_INPUT, "%s: scene %lld: bad node index", d->path,
                                    si);
            ss_status st = visit_node(d, (long long)r->valuedouble, id, 0, err);
            if (st) return st;
        }
        return SS_OK;
    }
    if (cJSON_IsArray(nodes) && cJSON_GetArraySize(nodes) > 0) {
        /* No scene: every node that is nobody's child is a root. */
        int n = cJSON_GetArraySize(nodes);
        char *is_child = calloc((size_t)n, 1);
        if (!is_child) return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", d->path);
        for (int i = 0; i < n; i++) {
            const cJSON *ch =
                cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(nodes, i), "children");
            for (int c = 0; cJSON_IsArray(ch) && c < cJSON_GetArraySize(ch); c++) {
                const cJSON *x = cJSON_GetArrayItem(ch, c);
                if (cJSON_IsNumber(x) && x->valuedouble >= 0 && x->valuedouble < n)
                    is_child[(int)x->valuedouble] = 1;
            }
        }
        ss_status st = SS_OK;
        for (int i = 0; i < n && !st; i++)
            if (!is_child[i]) st = visit_node(d, i, id, 0, err);
        free(is_child);
        return st;
    }
    const cJSON *meshes = cJSON_GetObjectItemCaseSensitive(d->json, "meshes");
    for (int i = 0; cJSON_IsArray(meshes) && i < cJSON_GetArraySize(meshes); i++) {
        ss_status st = add_mesh(d, i, id, err);
        if (st) return st;
    }
    return SS_OK;
}

/* ---- entry ---------------------------------------------------------------- */

static uint32_t le32(const unsigned char *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* Splits a GLB file into its JSON text (copied, NUL-terminated) and BIN chunk. */
static ss_status parse_glb(gltf_doc *d, const unsigned char *f, size_t len, char **json,
                           ss_error *err) {
    if (len < 20 || le32(f) != 0x46546C67u)
        return ss_error_set(err, SS_ERR_INPUT, "%s: not a GLB file (bad magic)", d->path);
    if (le32(f + 4) != 2)
        return ss_error_set(err, SS_ERR_INPUT, "%s: GLB version %u (only 2 is supported)", d->path,
                            (unsigned)le32(f + 4));
    size_t total = le32(f + 8);
    if (total > len)
        return ss_error_set(err, SS_ERR_INPUT, "%s: truncated GLB (%zu of %zu bytes)", d->path, len,
                            total);
    size_t pos = 12;
    *json = NULL;
    while (pos + 8 <= total) {
        size_t clen = le32(f + pos);
        uint32_t ctype = le32(f + pos + 4);
        if (clen > total - pos - 8)
            return ss_error_set(err, SS_ERR_INPUT, "%s: GLB chunk runs past the end", d->path);
        const unsigned char *cdata = f + pos + 8;
        if (ctype == 0x4E4F534Au && !*json) {
            *json = malloc(clen + 1);
            if (!*json) return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", d->path);
            memcpy(*json, cdata, clen);
            (*json)[clen] = '\0';
        } else if (ctype == 0x004E4942u && !d->bin) {
            d->bin = cdata;
            d->bin_len = clen;
        }
        pos += 8 + ((clen + 3) & ~(size_t)3);
    }
    if (!*json) return ss_error_set(err, SS_ERR_INPUT, "%s: GLB has no JSON chunk", d->path);
    return SS_OK;
}

ss_status ss_mesh_load_gltf(const char *path, ss_mesh *out, ss_error *err) {
    memset(out, 0, sizeof *out);
    size_t len;
    char *file = ss_read_file_max(path, &len, SS_READ_MAX_MESH, err);
    if (!file) return err ? err->code : SS_ERR_INPUT;
    gltf_doc d;
    memset(&d, 0, sizeof d);
    d.path = path;
    d.all_uv = d.all_nrm = 1;
    char *json_text = NULL;
    ss_status st = SS_OK;
    if (len >= 4 && !memcmp(file, "glTF", 4)) {
        st = parse_glb(&d, (const unsigned char *)file, len, &json_text, err);
    } else {
        json_text = file; /* .gltf: the file is the JSON */
    }
    if (!st) {
        d.json = cJSON_Parse(json_text);
        if (!d.json || !cJSON_IsObject(d.json))
            st = ss_error_set(err, SS_ERR_INPUT, "%s: not valid glTF JSON", path);
    }
    if (!st) {
        const cJSON *asset = cJSON_GetObjectItemCaseSensitive(d.json, "asset");
        const cJSON *ver = cJSON_GetObjectItemCaseSensitive(asset, "version");
        if (!cJSON_IsString(ver) || strncmp(ver->valuestring, "2.", 2))
            st = ss_error_set(err, SS_ERR_INPUT, "%s: not a glTF 2.0 file (asset.version)", path);
    }
    if (!st) {
        const cJSON *req = cJSON_GetObjectItemCaseSensitive(d.json, "extensionsRequired");
        for (int i = 0; cJSON_IsArray(req) && i < cJSON_GetArraySize(req) && !st; i++) {
            const cJSON *e = cJSON_GetArrayItem(req, i);
            if (cJSON_IsString(e) && strcmp(e->valuestring, "KHR_materials_unlit") &&
                strcmp(e->valuestring, "KHR_texture_transform"))
                st = ss_error_set(err, SS_ERR_INPUT, "%s: requires extension %s (not supported)",
                                  path, e->valuestring);
        }
    }
    if (!st) st = load_buffers(&d, err);
    if (!st) st = walk_scene(&d, err);
    if (!st && d.ni == 0)
        st = ss_error_set(err, SS_ERR_INPUT, "%s: no triangles in the default scene", path);
    if (!st)
        st = ss_mesh_from_arrays(d.pos, d.all_nrm ? d.nrm : NULL, d.all_uv ? d.uv : NULL, (int)d.nv,
                                 d.idx, (int)(d.ni / 3), path, out, err);
    for (int i = 0; i < d.nbuffers; i++)
        if (d.buffers[i].owned) free(d.buffers[i].data);
    free(d.buffers);
    cJSON_Delete(d.json);
    if (json_text != file) free(json_text);
    free(file);
    free(d.pos), free(d.nrm), free(d.uv), free(d.idx);
    return st;
}
