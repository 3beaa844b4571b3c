/* Wound inputs for the healing grid (stroke CSV files are read by geom):
 * footprint and depth images, and closed
 * OBJ meshes voxelised by ray parity (seed 001 §5.1: "we check with a ray
 * intersection test which cells are wound, skin, or empty cells"). Rays run
 * along +z through each voxel column; a voxel centre is inside when an odd
 * number of triangle crossings lies below it. */
#define _POSIX_C_SOURCE 200809L
#include "skinsim/heal_io.h"
#include "skinsim/geom.h"
#include "skinsim/mesh.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#ifndef M_SQRT2
#define M_SQRT2 1.41421356237309504880
#endif

/* ---- footprint and depth images ------------------------------------------------- */

static float first_or_luma(const ss_image *img, int x, int y) {
    const float *p = ss_image_px(img, x, y);
    if (img->channels >= 3) return 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2];
    return p[0];
}

ss_image *ss_heal_footprint_read(const char *path, ss_error *err) {
    ss_image *img = ss_image_read(path, SS_ENC_LINEAR, err);
    if (!img) return NULL;
    ss_image *fp = ss_image_create(img->width, img->height, 1, err);
    if (!fp) {
        ss_image_free(img);
        return NULL;
    }
    size_t on = 0;
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++) {
            float v = first_or_luma(img, x, y);
            int w = v > 0.5f; /* NaN counts as intact */
            fp->data[(size_t)y * (size_t)img->width + (size_t)x] = (float)w;
            on += (size_t)w;
        }
    ss_image_free(img);
    if (!on) {
        ss_error_set(err, SS_ERR_INPUT, "%s: the wound mask is empty (no pixel above 0.5)", path);
        ss_image_free(fp);
        return NULL;
    }
    return fp;
}

ss_image *ss_heal_depth_image_read(const char *path, double max_depth_mm, ss_error *err) {
    size_t l = strlen(path);
    int is_exr = l >= 4 && (!strcmp(path + l - 4, ".exr") || !strcmp(path + l - 4, ".EXR"));
    ss_image *img = ss_image_read(path, SS_ENC_LINEAR, err);
    if (!img) return NULL;
    ss_image *d = ss_image_create(img->width, img->height, 1, err);
    if (!d) {
        ss_image_free(img);
        return NULL;
    }
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++) {
            double v = first_or_luma(img, x, y);
            if (!is_exr) v *= max_depth_mm;
            if (!isfinite(v) || v < 0) {
                ss_error_set(err, SS_ERR_INPUT,
                             "%s: depth at pixel (%d,%d) is %g; depths must be finite and >= 0 "
                             "mm",
                             path, x, y, v);
                ss_image_free(img);
                ss_image_free(d);
                return NULL;
            }
            d->data[(size_t)y * (size_t)img->width + (size_t)x] = (float)v;
        }
    ss_image_free(img);
    return d;
}

/* ---- OBJ ------------------------------------------------------------------------ */

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
    int too_long;
    ss_status st = SS_OK;
#define FAIL(code, ...)                                                                            \
    do {                                                                                           \
        st = ss_error_set(err, code, __VA_ARGS__);                                                 \
        goto fail;                                                                                 \
    } while (0)
    if (!V || !T || !TL || !face) FAIL(SS_ERR_NOMEM, "%s: out of memory", name);
    if (!strncmp(text, "\xEF\xBB\xBF", 3)) text += 3; /* UTF-8 byte order mark */
    for (const char *p = text; (p = ss_text_next_line(p, line, sizeof line, &too_long));) {
        lineno++;
        if (too_long) FAIL(SS_ERR_INPUT, "%s:%d: line too long", name, lineno);
        char *s = ss_text_trim(line);
        char *hash = strchr(s, '#');
        if (hash) *hash = '\0';
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

static const double *cmp_base;
/* (qsort has no context argument; the comparator reads the vertex array through a
 * file-static pointer set just before the call, in one thread.) */
static int cmp_vert(const void *a, const void *b) {
    const double *p = cmp_base + 3 * (size_t) * (const int *)a;
    const double *q = cmp_base + 3 * (size_t) * (const int *)b;
    for (int k = 0; k < 3; k++)
        if (p[k] != q[k]) return p[k] < q[k] ? -1 : 1;
    return 0;
}

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
    int *order = malloc((size_t)nv * sizeof *order), *weld = malloc((size_t)nv * sizeof *weld);
    edge *e = malloc((size_t)nt * 3 * sizeof *e);
    ss_status st = SS_OK;
    if (!order || !weld || !e) {
        st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", name);
        goto done;
    }
    /* Weld vertices with identical coordinates (exporters often split them). */
    for (int i = 0; i < nv; i++) order[i] = i;
    cmp_base = m->v;
    qsort(order, (size_t)nv, sizeof *order, cmp_vert);
    for (int i = 0; i < nv; i++)
        weld[order[i]] =
            (i > 0 && cmp_vert(&order[i - 1], &order[i]) == 0) ? weld[order[i - 1]] : order[i];
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
    free(order);
    free(weld);
    free(e);
    return st;
}

/* ---- voxelisation by ray parity (seed 001 §5.1) -------------------------------------- */

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

uint8_t *ss_heal_voxelise_mesh(const ss_tri_mesh *m, int nx, int ny, int nz, double dx_mm,
                               size_t *count, ss_error *err) {
    const int gdim[3] = {nx, ny, nz}, lo[3] = {0, 0, 0};
    return ss_heal_voxelise_mesh_box(m, gdim, lo, gdim, dx_mm, count, err);
}

uint8_t *ss_heal_voxelise_mesh_box(const ss_tri_mesh *m, const int gdim[3], const int lo[3],
                                   const int bn[3], double dx_mm, size_t *count, ss_error *err) {
    if (count) *count = 0;
    const int nx = gdim[0], ny = gdim[1], nz = gdim[2];
    if (nx < 1 || ny < 1 || nz < 1 || bn[0] < 1 || bn[1] < 1 || bn[2] < 1 || !(dx_mm > 0) ||
        !isfinite(dx_mm)) {
        ss_error_set(err, SS_ERR_INPUT, "voxelise: invalid grid %dx%dx%d, dx %g mm", nx, ny, nz,
                     dx_mm);
        return NULL;
    }
    /* the box's columns and levels inside the grid (whole-grid indices) */
    const int x0 = lo[0] > 0 ? lo[0] : 0, x1 = lo[0] + bn[0] < nx ? lo[0] + bn[0] : nx;
    const int ya = lo[1] > 0 ? lo[1] : 0, yb = lo[1] + bn[1] < ny ? lo[1] + bn[1] : ny;
    const int z0 = lo[2] > 0 ? lo[2] : 0, z1 = lo[2] + bn[2] < nz ? lo[2] + bn[2] : nz;
    size_t n = (size_t)bn[0] * (size_t)bn[1] * (size_t)bn[2];
    uint8_t *vox = calloc(n, 1);
    /* Bin triangles by grid row (y) so each column tests only nearby triangles. */
    int *rowcount = calloc((size_t)ny + 1, sizeof(int));
    if (!vox || !rowcount) {
        free(vox);
        free(rowcount);
        ss_error_set(err, SS_ERR_NOMEM, "voxelise: out of memory");
        return NULL;
    }
    /* A fixed, tiny, irrational nudge keeps rays off exact edges and vertices of
     * meshes built on the grid lattice. */
    const double ox = dx_mm * 1.2345678e-6 * M_SQRT2, oy = dx_mm * 0.9876543e-6 * M_PI;
    int ntri = m->ntris;
#define ROWRANGE(t, lo, hi)                                                                        \
    do {                                                                                           \
        double y0 = INFINITY, y1 = -INFINITY;                                                      \
        for (int k_ = 0; k_ < 3; k_++) {                                                           \
            double yy = m->v[3 * (size_t)m->tri[3 * (t) + k_] + 1];                                \
            if (yy < y0) y0 = yy;                                                                  \
            if (yy > y1) y1 = yy;                                                                  \
        }                                                                                          \
        lo = (int)ceil((y0 - oy) / dx_mm - 0.5);                                                   \
        hi = (int)floor((y1 - oy) / dx_mm - 0.5);                                                  \
        if (lo < ya) lo = ya;                                                                      \
        if (hi > yb - 1) hi = yb - 1;                                                              \
    } while (0)
    for (int t = 0; t < ntri; t++) {
        int lo, hi;
        ROWRANGE(t, lo, hi);
        for (int y = lo; y <= hi; y++) rowcount[y + 1]++;
    }
    for (int y = 0; y < ny; y++) rowcount[y + 1] += rowcount[y];
    size_t total = (size_t)rowcount[ny];
    int *rowtri = malloc((total ? total : 1) * sizeof(int));
    int *fill = calloc((size_t)ny, sizeof(int));
    if (!rowtri || !fill) {
        free(vox);
        free(rowcount);
        free(rowtri);
        free(fill);
        ss_error_set(err, SS_ERR_NOMEM, "voxelise: out of memory");
        return NULL;
    }
    for (int t = 0; t < ntri; t++) {
        int lo, hi;
        ROWRANGE(t, lo, hi);
        for (int y = lo; y <= hi; y++) rowtri[rowcount[y] + fill[y]++] = t;
    }
#undef ROWRANGE
    free(fill);
    size_t inside = 0;
    int oom = 0;
#pragma omp parallel reduction(+ : inside) reduction(| : oom)
    {
        int cap = 64;
        double *hits = malloc((size_t)cap * sizeof *hits);
        if (!hits) oom = 1;
#pragma omp for schedule(dynamic, 1)
        for (int y = ya; y < yb; y++) {
            if (!hits) continue;
            double py = (y + 0.5) * dx_mm + oy;
            for (int x = x0; x < x1; x++) {
                double px = (x + 0.5) * dx_mm + ox;
                int nh = 0;
                for (int r = rowcount[y]; r < rowcount[y + 1]; r++) {
                    int t = rowtri[r];
                    const double *a = m->v + 3 * (size_t)m->tri[3 * t];
                    const double *b = m->v + 3 * (size_t)m->tri[3 * t + 1];
                    const double *c = m->v + 3 * (size_t)m->tri[3 * t + 2];
                    /* 2D barycentric test in the xy projection */
                    double d = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
                    if (d == 0) continue; /* face parallel to the ray */
                    double w1 = ((px - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (py - a[1])) / d;
                    double w2 = ((b[0] - a[0]) * (py - a[1]) - (px - a[0]) * (b[1] - a[1])) / d;
                    double w0 = 1 - w1 - w2;
                    if (w0 < 0 || w1 < 0 || w2 < 0) continue;
                    if (nh == cap) {
                        cap *= 2;
                        double *q = realloc(hits, (size_t)cap * sizeof *hits);
                        if (!q) {
                            oom = 1;
                            break;
                        }
                        hits = q;
                    }
                    hits[nh++] = w0 * a[2] + w1 * b[2] + w2 * c[2];
                }
                if (nh < 2) continue;
                qsort(hits, (size_t)nh, sizeof *hits, cmp_double);
                int h = 0;
                for (int z = z0; z < z1; z++) {
                    double pz = (z + 0.5) * dx_mm;
                    while (h < nh && hits[h] < pz) h++;
                    if (h & 1) {
                        vox[((size_t)(z - lo[2]) * (size_t)bn[1] + (size_t)(y - lo[1])) *
                                (size_t)bn[0] +
                            (size_t)(x - lo[0])] = 1;
                        inside++;
                    }
                }
            }
        }
        free(hits);
    }
    free(rowcount);
    free(rowtri);
    if (oom) {
        free(vox);
        ss_error_set(err, SS_ERR_NOMEM, "voxelise: out of memory");
        return NULL;
    }
    if (count) *count = inside;
    return vox;
}
