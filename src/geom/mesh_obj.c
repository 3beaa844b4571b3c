/* Wavefront OBJ reader: v, vt, vn and f statements; everything else (groups,
 * materials, smoothing groups, lines, points) is ignored. A face corner is
 * v, v/t, v//n or v/t/n with 1-based or negative (relative) indices;
 * polygons are fanned from their first corner, which is exact for the convex
 * faces OBJ exporters write. Corners become vertices of the indexed mesh
 * through a hash on the (v, t, n) triple, so a seam splits vertices exactly
 * where the file does. UVs are flipped to skinsim's v-down convention. When
 * any corner lacks a texture coordinate the mesh has no UVs (has_uvs = 0);
 * when any lacks a normal, all normals are computed: mixing the two within
 * one mesh would leave seams in the shading.
 *
 * Errors name the file and line: a number that does not parse or is not
 * finite, an index of 0 or out of range, a face with fewer than 3 corners,
 * a line longer than 64 KiB, no faces at all. */
#include "skinsim/mesh.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

ss_status ss_mesh_load_obj(const char *path, ss_mesh *out, ss_error *err);

typedef struct fvec {
    float *v;
    size_t n, cap; /* in floats */
} fvec;

static int fvec_push(fvec *a, const float *x, int k) {
    if (a->n + (size_t)k > a->cap) {
        size_t cap = a->cap ? a->cap * 2 : 1024;
        while (cap < a->n + (size_t)k) cap *= 2;
        float *p = realloc(a->v, sizeof *p * cap);
        if (!p) return -1;
        a->v = p, a->cap = cap;
    }
    memcpy(a->v + a->n, x, sizeof *x * (size_t)k);
    a->n += (size_t)k;
    return 0;
}

typedef struct uvec {
    uint32_t *v;
    size_t n, cap;
} uvec;

static int uvec_push(uvec *a, uint32_t x) {
    if (a->n == a->cap) {
        size_t cap = a->cap ? a->cap * 2 : 1024;
        uint32_t *p = realloc(a->v, sizeof *p * cap);
        if (!p) return -1;
        a->v = p, a->cap = cap;
    }
    a->v[a->n++] = x;
    return 0;
}

/* Open-addressing hash from a (v, t, n) corner to its vertex index. */
typedef struct corner_map {
    int64_t *keys; /* 3 per slot; keys[3*s] == -1 marks an empty slot */
    uint32_t *vals;
    size_t cap, used;
} corner_map;

static uint64_t hash3(const int64_t *k) {
    uint64_t h = 1469598103934665603ull;
    for (int i = 0; i < 3; i++) {
        h ^= (uint64_t)k[i];
        h *= 1099511628211ull;
        h ^= h >> 29;
    }
    return h;
}

static int map_grow(corner_map *m) {
    size_t cap = m->cap ? m->cap * 2 : 4096;
    int64_t *keys = malloc(sizeof *keys * 3 * cap);
    uint32_t *vals = malloc(sizeof *vals * cap);
    if (!keys || !vals) {
        free(keys), free(vals);
        return -1;
    }
    for (size_t s = 0; s < cap; s++) keys[3 * s] = -1;
    for (size_t s = 0; s < m->cap; s++) {
        if (m->keys[3 * s] < 0) continue;
        size_t j = hash3(m->keys + 3 * s) & (cap - 1);
        while (keys[3 * j] >= 0) j = (j + 1) & (cap - 1);
        memcpy(keys + 3 * j, m->keys + 3 * s, sizeof *keys * 3);
        vals[j] = m->vals[s];
    }
    free(m->keys), free(m->vals);
    m->keys = keys, m->vals = vals, m->cap = cap;
    return 0;
}

/* Finds the corner or inserts it with value next; *val gets the index.
 * Returns 1 when inserted, 0 when found, -1 on memory failure. */
static int map_get(corner_map *m, const int64_t *key, uint32_t next, uint32_t *val) {
    if (2 * (m->used + 1) > m->cap && map_grow(m) != 0) return -1;
    size_t j = hash3(key) & (m->cap - 1);
    while (m->keys[3 * j] >= 0) {
        if (!memcmp(m->keys + 3 * j, key, sizeof *key * 3)) {
            *val = m->vals[j];
            return 0;
        }
        j = (j + 1) & (m->cap - 1);
    }
    memcpy(m->keys + 3 * j, key, sizeof *key * 3);
    m->vals[j] = next;
    m->used++;
    *val = next;
    return 1;
}

/* Parses up to max floats from s; returns how many, -1 on a bad token. */
static int parse_floats(char *s, float *out, int max) {
    int n = 0;
    char *save = NULL;
    for (char *tok = strtok_r(s, " \t", &save); tok; tok = strtok_r(NULL, " \t", &save)) {
        double x;
        if (n >= max) break;
        if (ss_text_parse_number(tok, &x) != 0 || fabs(x) > 3.0e38) return -1;
        out[n++] = (float)x;
    }
    return n;
}

/* Resolves a 1-based or negative OBJ index against count; -1 when invalid. */
static int64_t resolve(const char *s, char **end, size_t count) {
    errno = 0;
    long long v = strtoll(s, end, 10);
    if (*end == s || errno) return -1;
    if (v > 0 && (unsigned long long)v <= count) return v - 1;
    if (v < 0 && (unsigned long long)(-v) <= count) return (int64_t)count + v;
    return -1;
}

typedef struct obj_state {
    fvec pos, tex, nrm;    /* as read from the file */
    fvec vpos, vtex, vnrm; /* per unique corner */
    uvec tris;
    corner_map map;
    int all_tex, all_nrm;
} obj_state;

static void obj_state_free(obj_state *s) {
    free(s->pos.v), free(s->tex.v), free(s->nrm.v);
    free(s->vpos.v), free(s->vtex.v), free(s->vnrm.v);
    free(s->tris.v), free(s->map.keys), free(s->map.vals);
}

/* One face line (after "f"): corners into vertices, polygon fanned. */
static ss_status parse_face(obj_state *s, char *line, const char *path, long lineno,
                            ss_error *err) {
    uint32_t first = 0, prev = 0;
    int k = 0;
    char *save = NULL;
    for (char *tok = strtok_r(line, " \t", &save); tok; tok = strtok_r(NULL, " \t", &save), k++) {
        int64_t key[3] = {-1, -1, -1};
        char *end;
        key[0] = resolve(tok, &end, s->pos.n / 3);
        if (key[0] < 0)
            return ss_error_set(err, SS_ERR_INPUT, "%s:%ld: bad or out-of-range vertex index '%s'",
                                path, lineno, tok);
        if (*end == '/') {
            char *p = end + 1;
            if (*p != '/') {
                key[1] = resolve(p, &end, s->tex.n / 2);
                if (key[1] < 0)
                    return ss_error_set(err, SS_ERR_INPUT,
                                        "%s:%ld: bad or out-of-range texture index in '%s'", path,
                                        lineno, tok);
                p = end;
            }
            if (*p == '/') {
                key[2] = resolve(p + 1, &end, s->nrm.n / 3);
                if (key[2] < 0)
                    return ss_error_set(err, SS_ERR_INPUT,
                                        "%s:%ld: bad or out-of-range normal index in '%s'", path,
                                        lineno, tok);
            }
        }
        if (*end != '\0' && *end != '/')
            return ss_error_set(err, SS_ERR_INPUT, "%s:%ld: bad face corner '%s'", path, lineno,
                                tok);
        if (key[1] < 0) s->all_tex = 0;
        if (key[2] < 0) s->all_nrm = 0;
        if (s->vpos.n / 3 >= ((size_t)1 << 28))
            return ss_error_set(err, SS_ERR_INPUT, "%s: too many vertices", path);
        uint32_t idx;
        int r = map_get(&s->map, key, (uint32_t)(s->vpos.n / 3), &idx);
        if (r < 0) return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
        if (r == 1) {
            static const float zero[3] = {0, 0, 0};
            float uv[2] = {0, 0};
            if (key[1] >= 0) {
                uv[0] = s->tex.v[2 * key[1]];
                uv[1] = 1.0f - s->tex.v[2 * key[1] + 1];
            }
            if (fvec_push(&s->vpos, s->pos.v + 3 * key[0], 3) || fvec_push(&s->vtex, uv, 2) ||
                fvec_push(&s->vnrm, key[2] >= 0 ? s->nrm.v + 3 * key[2] : zero, 3))
                return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
        }
        if (k == 0) first = idx;
        if (k >= 2 && s->tris.n / 3 >= ((size_t)1 << 28))
            return ss_error_set(err, SS_ERR_INPUT, "%s: too many triangles", path);
        if (k >= 2 &&
            (uvec_push(&s->tris, first) || uvec_push(&s->tris, prev) || uvec_push(&s->tris, idx)))
            return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
        prev = idx;
    }
    if (k < 3)
        return ss_error_set(err, SS_ERR_INPUT, "%s:%ld: a face needs at least 3 corners", path,
                            lineno);
    return SS_OK;
}

ss_status ss_mesh_load_obj(const char *path, ss_mesh *out, ss_error *err) {
    memset(out, 0, sizeof *out);
    size_t len;
    char *text = ss_read_file_max(path, &len, SS_READ_MAX_MESH, err);
    if (!text) return err ? err->code : SS_ERR_INPUT;
    if (memchr(text, '\0', len)) {
        free(text);
        return ss_error_set(err, SS_ERR_INPUT, "%s: not a text file (OBJ expected)", path);
    }
    obj_state s;
    memset(&s, 0, sizeof s);
    s.all_tex = s.all_nrm = 1;
    enum { LINE_MAX_BYTES = 65536 };
    char *line = malloc(LINE_MAX_BYTES);
    ss_status st = line ? SS_OK : ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
    long lineno = 0;
    const char *p = text;
    while (st == SS_OK) {
        int too_long = 0;
        p = ss_text_next_line(p, line, LINE_MAX_BYTES, &too_long);
        if (!p) break;
        lineno++;
        if (too_long) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s:%ld: line too long", path, lineno);
            break;
        }
        char *l = ss_text_trim(line);
        char *hash = strchr(l, '#');
        if (hash) *hash = '\0';
        float v[3];
        int n;
        if (!strncmp(l, "v ", 2) || !strncmp(l, "v\t", 2)) {
            n = parse_floats(l + 2, v, 3);
            if (n != 3)
                st = ss_error_set(err, SS_ERR_INPUT, "%s:%ld: a vertex needs 3 finite numbers",
                                  path, lineno);
            else if (fvec_push(&s.pos, v, 3))
                st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
        } else if (!strncmp(l, "vt ", 3) || !strncmp(l, "vt\t", 3)) {
            n = parse_floats(l + 3, v, 2);
            if (n < 1)
                st =
                    ss_error_set(err, SS_ERR_INPUT,
                                 "%s:%ld: a texture coordinate needs finite numbers", path, lineno);
            else {
                if (n == 1) v[1] = 0;
                if (fvec_push(&s.tex, v, 2))
                    st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
            }
        } else if (!strncmp(l, "vn ", 3) || !strncmp(l, "vn\t", 3)) {
            n = parse_floats(l + 3, v, 3);
            if (n != 3)
                st = ss_error_set(err, SS_ERR_INPUT, "%s:%ld: a normal needs 3 finite numbers",
                                  path, lineno);
            else if (fvec_push(&s.nrm, v, 3))
                st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
        } else if (!strncmp(l, "f ", 2) || !strncmp(l, "f\t", 2)) {
            st = parse_face(&s, l + 2, path, lineno, err);
        }
    }
    free(line);
    free(text);
    if (st == SS_OK && s.tris.n == 0)
        st = ss_error_set(err, SS_ERR_INPUT, "%s: no faces (not an OBJ mesh?)", path);
    if (st == SS_OK)
        st =
            ss_mesh_from_arrays(s.vpos.v, s.all_nrm ? s.vnrm.v : NULL, s.all_tex ? s.vtex.v : NULL,
                                (int)(s.vpos.n / 3), s.tris.v, (int)(s.tris.n / 3), path, out, err);
    obj_state_free(&s);
    return st;
}
