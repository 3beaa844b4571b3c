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
 * a line longer than 64 KiB, no faces at all.
 *
 * The one OBJ reader of skinsim: it also reads the healing grid's wound
 * meshes (ss_obj_parse into an ss_tri_mesh, a stricter dialect, described
 * above its code) and checks them closed. Both dialects share the line
 * scanner; they keep their own rules because a render mesh must load
 * whatever an exporter wrote while a wound mesh is refused at a typo. */
#include "skinsim/mesh.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

ss_status ss_mesh_load_obj(const char *path, ss_mesh *out, ss_error *err);

/* The line scanner both dialects read with: the next line, its number and
 * whether it overflowed the buffer; the line trimmed and cut at '#'. */
typedef struct obj_lines {
    const char *p; /* the rest of the text */
    char *buf;
    size_t cap;
    long lineno;
    int too_long;
} obj_lines;

static char *obj_next_line(obj_lines *L) {
    L->p = ss_text_next_line(L->p, L->buf, L->cap, &L->too_long);
    if (!L->p) return NULL;
    L->lineno++;
    if (L->too_long) return L->buf;
    char *s = ss_text_trim(L->buf);
    char *hash = strchr(s, '#');
    if (hash) *hash = '\0';
    return s;
}

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
    obj_lines L = {text, line, LINE_MAX_BYTES, 0, 0};
    while (st == SS_OK) {
        char *l = obj_next_line(&L);
        if (!l) break;
        const long lineno = L.lineno;
        if (L.too_long) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s:%ld: line too long", path, lineno);
            break;
        }
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

/* ---- the wound-mesh dialect (ss_tri_mesh) -------------------------------------------
 * Positions in double precision (a wound mesh is voxelised at 0.5 mm in a
 * block of a few cm: float would do, but the voxel parity test of
 * ss_heal_voxelise_mesh was validated on doubles), each triangle remembers its
 * OBJ line for the closedness errors, faces may name vertices defined after
 * them (checked at the end), and any statement outside v/f and the ignored
 * list is an error: a wound mesh is a hand-written or exported closed
 * surface, and a typo in it should not pass silently. */

void ss_tri_mesh_free(ss_tri_mesh *m) {
    if (!m) return;
    free(m->v);
    free(m->tri);
    free(m->line);
    memset(m, 0, sizeof *m);
}

ss_status ss_obj_parse(const char *text, const char *name, ss_tri_mesh *out, ss_error *err) {
    memset(out, 0, sizeof *out);
    int vcap = 1024, tcap = 1024, nv = 0, nt = 0, lineno = 0;
    double *V = malloc((size_t)vcap * 3 * sizeof *V);
    int *T = malloc((size_t)tcap * 3 * sizeof *T), *TL = malloc((size_t)tcap * sizeof *TL);
    int fcap = 64, *face = malloc((size_t)fcap * sizeof *face);
    char line[8192];
    obj_lines L = {text, line, sizeof line, 0, 0};
    ss_status st = SS_OK;
#define FAIL(code, ...)                                                                            \
    do {                                                                                           \
        st = ss_error_set(err, code, __VA_ARGS__);                                                 \
        goto fail;                                                                                 \
    } while (0)
    if (!V || !T || !TL || !face) FAIL(SS_ERR_NOMEM, "%s: out of memory", name);
    if (!strncmp(L.p, "\xEF\xBB\xBF", 3)) L.p += 3; /* UTF-8 byte order mark */
    for (char *s; (s = obj_next_line(&L));) {
        lineno = (int)L.lineno;
        if (L.too_long) FAIL(SS_ERR_INPUT, "%s:%d: line too long", name, lineno);
        if (!*s) continue;
        char *save = NULL, *kw = strtok_r(s, " \t", &save);
        if (!strcmp(kw, "v")) {
            double c[3];
            for (int k = 0; k < 3; k++) {
                char *tok = strtok_r(NULL, " \t", &save);
                if (!tok) FAIL(SS_ERR_INPUT, "%s:%d: vertex needs 3 coordinates", name, lineno);
                int r = ss_text_parse_number(tok, &c[k]);
                if (r)
                    FAIL(SS_ERR_INPUT, "%s:%d: vertex coordinate '%s' is %s", name, lineno, tok,
                         r == 2 ? "not finite" : "not a number");
            }
            if (nv == vcap) {
                vcap *= 2;
                double *q = realloc(V, (size_t)vcap * 3 * sizeof *V);
                if (!q) FAIL(SS_ERR_NOMEM, "%s: out of memory", name);
                V = q;
            }
            memcpy(V + 3 * (size_t)nv, c, sizeof c);
            nv++;
        } else if (!strcmp(kw, "f")) {
            int nfv = 0;
            for (char *tok; (tok = strtok_r(NULL, " \t", &save));) {
                char *end;
                errno = 0;
                long idx = strtol(tok, &end, 10);
                if (end == tok || (*end && *end != '/') || errno == ERANGE)
                    FAIL(SS_ERR_INPUT, "%s:%d: bad face vertex '%s'", name, lineno, tok);
                if (*end == '/') { /* i/t, i//n, i/t/n: check the rest is numeric */
                    for (char *q = end; *q; q++)
                        if (!(*q == '/' || *q == '-' || isdigit((unsigned char)*q)))
                            FAIL(SS_ERR_INPUT, "%s:%d: bad face vertex '%s'", name, lineno, tok);
                }
                if (idx < 0) idx = nv + idx + 1; /* relative: -1 is the last vertex */
                if (idx < 1 || idx > INT32_MAX)
                    FAIL(SS_ERR_INPUT,
                         "%s:%d: face vertex '%s' does not refer to a vertex defined "
                         "before it",
                         name, lineno, tok);
                if (nfv == fcap) {
                    fcap *= 2;
                    int *q = realloc(face, (size_t)fcap * sizeof *face);
                    if (!q) FAIL(SS_ERR_NOMEM, "%s: out of memory", name);
                    face = q;
                }
                face[nfv++] = (int)(idx - 1);
            }
            if (nfv < 3)
                FAIL(SS_ERR_INPUT, "%s:%d: face has %d vertices, needs at least 3", name, lineno,
                     nfv);
            for (int k = 1; k + 1 < nfv; k++) {
                if (nt == tcap) {
                    tcap *= 2;
                    int *q = realloc(T, (size_t)tcap * 3 * sizeof *T);
                    if (!q) FAIL(SS_ERR_NOMEM, "%s: out of memory", name);
                    T = q;
                    q = realloc(TL, (size_t)tcap * sizeof *TL);
                    if (!q) FAIL(SS_ERR_NOMEM, "%s: out of memory", name);
                    TL = q;
                }
                T[3 * nt] = face[0];
                T[3 * nt + 1] = face[k];
                T[3 * nt + 2] = face[k + 1];
                TL[nt] = lineno;
                nt++;
            }
        } else if (!strcmp(kw, "vt") || !strcmp(kw, "vn") || !strcmp(kw, "vp") ||
                   !strcmp(kw, "o") || !strcmp(kw, "g") || !strcmp(kw, "s") ||
                   !strcmp(kw, "usemtl") || !strcmp(kw, "mtllib") || !strcmp(kw, "l") ||
                   !strcmp(kw, "p")) {
            continue;
        } else {
            FAIL(SS_ERR_INPUT, "%s:%d: unknown OBJ statement '%s'", name, lineno, kw);
        }
    }
    for (int i = 0; i < nt; i++)
        for (int k = 0; k < 3; k++)
            if (T[3 * i + k] >= nv)
                FAIL(SS_ERR_INPUT, "%s:%d: face refers to vertex %d but the file has %d", name,
                     TL[i], T[3 * i + k] + 1, nv);
    if (nt == 0) FAIL(SS_ERR_INPUT, "%s: no faces", name);
#undef FAIL
    free(face);
    out->nverts = nv;
    out->ntris = nt;
    out->v = V;
    out->tri = T;
    out->line = TL;
    return SS_OK;
fail:
    free(V);
    free(T);
    free(TL);
    free(face);
    return st;
}

ss_status ss_obj_read(const char *path, ss_tri_mesh *out, ss_error *err) {
    memset(out, 0, sizeof *out);
    char *text = ss_read_file_max(path, NULL, SS_READ_MAX_MESH, err);
    if (!text) return err ? err->code : SS_ERR_INPUT;
    ss_status st = ss_obj_parse(text, path, out, err);
    free(text);
    return st;
}

/* ---- closedness --------------------------------------------------------------------- */

typedef struct edge {
    int a, b, tri;
} edge;
static int cmp_edge(const void *x, const void *y) {
    const edge *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return 0;
}

ss_status ss_tri_mesh_check_closed(const ss_tri_mesh *m, const char *name, ss_error *err) {
    int nv = m->nverts, nt = m->ntris;
    int *weld = malloc((size_t)nv * sizeof *weld);
    edge *e = malloc((size_t)nt * 3 * sizeof *e);
    ss_status st = SS_OK;
    if (!weld || !e) {
        st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", name);
        goto done;
    }
    /* Weld vertices at the same position within the mesh size's tolerance
     * (exporters often split them, and round the copies differently). */
    if ((st = ss_weld_positions(nv, m->v, weld, err))) goto done;
    for (int t = 0; t < nt; t++) {
        int a = weld[m->tri[3 * t]], b = weld[m->tri[3 * t + 1]], c = weld[m->tri[3 * t + 2]];
        if (a == b || b == c || a == c) {
            st = ss_error_set(err, SS_ERR_INPUT,
                              "%s:%d: degenerate face (a vertex is repeated); the wound mesh "
                              "must be a closed surface",
                              name, m->line[t]);
            goto done;
        }
        int v3[3] = {a, b, c};
        for (int k = 0; k < 3; k++) {
            int p = v3[k], q = v3[(k + 1) % 3];
            e[3 * t + k] = (edge){p < q ? p : q, p < q ? q : p, t};
        }
    }
    qsort(e, (size_t)nt * 3, sizeof *e, cmp_edge);
    for (size_t i = 0; i < (size_t)nt * 3;) {
        size_t j = i;
        while (j < (size_t)nt * 3 && e[j].a == e[i].a && e[j].b == e[i].b) j++;
        if ((j - i) % 2) {
            st = ss_error_set(err, SS_ERR_INPUT,
                              "%s:%d: the mesh is not closed: the edge between vertices %d and "
                              "%d belongs to %zu face%s (needs an even number, normally 2)",
                              name, m->line[e[i].tri], e[i].a + 1, e[i].b + 1, j - i,
                              j - i == 1 ? "" : "s");
            goto done;
        }
        i = j;
    }
    /* self-intersection, as ss_shell_check_closed does for --mesh: every
     * unique edge as a segment through a BVH of the faces; a face it
     * crosses that does not share one of its vertices is a crossing */
    float *pos = malloc(3 * ((size_t)nv + 1) * sizeof *pos);
    uint32_t *idx = malloc(3 * ((size_t)nt + 1) * sizeof *idx);
    ss_mesh fm = {.nvertices = nv, .ntriangles = nt, .positions = pos, .indices = idx};
    ss_bvh *bvh = NULL;
    if (pos && idx) {
        for (int d = 0; d < 3; d++) fm.bbox_min[d] = INFINITY, fm.bbox_max[d] = -INFINITY;
        for (size_t i = 0; i < 3 * (size_t)nv; i++) {
            pos[i] = (float)m->v[i];
            fm.bbox_min[i % 3] = fminf(fm.bbox_min[i % 3], pos[i]);
            fm.bbox_max[i % 3] = fmaxf(fm.bbox_max[i % 3], pos[i]);
        }
        for (size_t i = 0; i < 3 * (size_t)nt; i++) idx[i] = (uint32_t)m->tri[i];
        bvh = ss_bvh_build(&fm, err);
    } else
        ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", name);
    if (!bvh) st = err && err->code ? err->code : SS_ERR_NOMEM;
    for (size_t i = 0; bvh && !st && i < (size_t)nt * 3; i++) {
        if (i && e[i].a == e[i - 1].a && e[i].b == e[i - 1].b) continue;
        const float *pa = pos + 3 * e[i].a, *pb = pos + 3 * e[i].b;
        float dir[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
        float t0 = 1e-4f;
        for (int tries = 0; tries < 32; tries++) {
            ss_ray_hit h;
            if (!ss_bvh_raycast(bvh, pa, dir, t0, 1.0f - 1e-4f, &h)) break;
            int touches = 0;
            for (int k = 0; k < 3; k++) {
                int w = weld[m->tri[3 * (size_t)h.triangle + k]];
                touches |= w == e[i].a || w == e[i].b;
            }
            if (!touches) {
                st = ss_error_set(err, SS_ERR_INPUT,
                                  "%s:%d: the mesh intersects itself: an edge of this face crosses "
                                  "the face of line %d; the wound mesh must be a closed surface "
                                  "that does not cross itself",
                                  name, m->line[e[i].tri], m->line[h.triangle]);
                break;
            }
            t0 = h.t + 1e-5f;
        }
    }
    ss_bvh_free(bvh);
    free(pos);
    free(idx);
done:
    free(weld);
    free(e);
    return st;
}
