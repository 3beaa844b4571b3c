/* Skin on a closed surface mesh (seed 001 §5.1, §5.4): the healing grid of a
 * wound on a real body, and the fields mapped back onto the mesh.
 *
 * Design:
 * - The grid is a local patch, not the whole body: a box of voxels around the
 *   wound with its z axis along the area-weighted mean normal of the wound's
 *   surface, x and y in the tangent plane, sized to the wound plus a margin
 *   of intact skin. A body at 0.5 mm voxels would need 10^8 cells for a hand;
 *   the patch needs 10^5.
 * - Voxels are classified by ray tests (§5.1): one ray per column from above
 *   along -z gives the surface (first crossing, an entry) and the far side of
 *   the body (second crossing); voxels between them within thickness_mm of
 *   the surface are skin (the top one epidermis), deeper ones inside the body
 *   are the inner bound (intact tissue held at healthy values), the rest air.
 *   Columns whose surface lies farther than the patch's half-width from the
 *   wound's height (a neighbouring finger, the palm under the back of the
 *   hand) count as air.
 * - The wound: UV strokes are hulled in UV space (geom's stroke hulls with
 *   rounded corners, ss_stroke_outlines, as `skinsim abrasion` does) and a column is wounded when
 * the UV of its surface hit lies in a hull; its voxels within depth_mm of the surface are cut out.
 * A wound mesh is voxelised by ray parity along the column.
 * - Mapping back (§5.4): a vertex takes the fields of its column's surface
 *   cell and the displacement there, rotated into the mesh frame.
 * - A wound that wraps around the body (a finger) is refused: its surface
 *   normals, at the stroke points and at the mesh vertices inside it, may
 *   turn at most SS_SHELL_MAX_WRAP_DEG from the patch's normal. Beyond that
 *   the columns meet the skin at a grazing angle (the shell, measured along
 *   the column, thins to thickness x cos) and past 90 degrees miss it.
 *   For UV strokes the patch's normal is the mean of the stroke points'
 *   normals; when that fails, the minimax normal (Badoiu-Clarkson) is tried.
 * - Closedness welds vertices by position (seams duplicate them) and asks
 *   every edge to have exactly two triangles; self-intersection casts every
 *   edge as a ray segment through the BVH: an edge that pierces a triangle
 *   not sharing its vertices means two triangles cross.
 * - Units (ss_shell_units_resolve): glTF is metres by its specification; an
 *   OBJ carries no unit, so its size decides. Body parts span 80 mm (a
 *   finger) to 1.8 m (a body) across their bounding-box diagonal, so a
 *   diagonal under SS_SHELL_OBJ_METRE_DIAG (3) can only be metres (in mm it
 *   could not hold the 3 mm skin), one of SS_SHELL_OBJ_MM_DIAG (60) or more
 *   is mm (in cm it would be 0.6 m..), and between them mm (a fingertip or a
 *   test block) and cm (a finger to a leg) are both plausible: refused,
 *   asking for --mesh-units-mm. Gave up: guessing from the wound (a wound
 *   mesh is in the skin's units, a UV stroke has no size of its own, so
 *   neither tells mm from cm). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/geom.h"
#include "skinsim/paint.h"
#include "skinsim/shell.h"

void ss_shell_opts_default(ss_shell_opts *o) {
    memset(o, 0, sizeof *o);
    o->voxel_mm = SS_HEAL_DEFAULT_DX_MM;
    o->thickness_mm = 3.0;
    o->epidermis_mm = SS_HEAL_DEFAULT_EPIDERMIS_MM;
    o->depth_mm = SS_HEAL_DEFAULT_DEPTH_MM;
}

static int ends_with(const char *s, const char *suf) {
    size_t a = strlen(s), b = strlen(suf);
    if (a < b) return 0;
    for (size_t i = 0; i < b; i++) {
        char c = s[a - b + i];
        if (c >= 'A' && c <= 'Z') c = (char)(c - 'A' + 'a');
        if (c != suf[i]) return 0;
    }
    return 1;
}

double ss_shell_units_for(const char *path, double units_mm) {
    if (units_mm > 0) return units_mm;
    return path && (ends_with(path, ".glb") || ends_with(path, ".gltf")) ? 1000.0 : 1.0;
}

ss_status ss_shell_units_resolve(const ss_mesh *skin, const char *path, double units_mm,
                                 double *out, char *note, size_t note_size, ss_error *err) {
    if (note && note_size) note[0] = 0;
    if (units_mm > 0 || (path && (ends_with(path, ".glb") || ends_with(path, ".gltf")))) {
        *out = ss_shell_units_for(path, units_mm);
        return SS_OK;
    }
    double d2 = 0;
    for (int d = 0; d < 3; d++) {
        double e = (double)skin->bbox_max[d] - skin->bbox_min[d];
        d2 += e * e;
    }
    double diag = sqrt(d2);
    if (diag < SS_SHELL_OBJ_METRE_DIAG) {
        *out = 1000.0;
        if (note && note_size)
            snprintf(note, note_size,
                     "note: %s: read in metres (its bounding-box diagonal is %g units: under %g, "
                     "too small for mm); --mesh-units-mm sets the unit",
                     path ? path : "mesh", diag, SS_SHELL_OBJ_METRE_DIAG);
        return SS_OK;
    }
    if (diag < SS_SHELL_OBJ_MM_DIAG)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: an OBJ has no unit and its size does not tell one: its "
                            "bounding-box diagonal is %g units, %g..%g mm (a fingertip or a test "
                            "block) or cm (a finger to a leg); give the unit with --mesh-units-mm "
                            "(1 for mm, 10 for cm, 1000 for metres)",
                            path ? path : "mesh", diag, SS_SHELL_OBJ_METRE_DIAG,
                            SS_SHELL_OBJ_MM_DIAG);
    *out = 1.0;
    return SS_OK;
}

/* ---- closedness and self-intersection ------------------------------------------- */

typedef struct sedge {
    int a, b, t;
} sedge;
static int cmp_sedge(const void *x, const void *y) {
    const sedge *p = x, *q = y;
    if (p->a != q->a) return p->a < q->a ? -1 : 1;
    if (p->b != q->b) return p->b < q->b ? -1 : 1;
    return p->t - q->t;
}

ss_status ss_shell_check_closed(const ss_mesh *m, const char *name, ss_error *err) {
    if (!m || m->ntriangles < 4)
        return ss_error_set(err, SS_ERR_INPUT, "%s: too few triangles for a closed surface", name);
    int *weld = malloc((size_t)m->nvertices * sizeof *weld);
    sedge *e = malloc(3 * (size_t)m->ntriangles * sizeof *e);
    ss_bvh *bvh = NULL;
    ss_status st = SS_OK;
    if (!weld || !e) {
        st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", name);
        goto done;
    }
    if ((st = ss_mesh_weld(m, weld, err))) goto done;
    for (int t = 0; t < m->ntriangles; t++) {
        int v[3];
        for (int k = 0; k < 3; k++) v[k] = weld[m->indices[3 * t + k]];
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) {
            st = ss_error_set(err, SS_ERR_INPUT,
                              "%s: triangle %d is degenerate (a vertex repeated); the skin must be "
                              "a closed surface",
                              name, t + 1);
            goto done;
        }
        for (int k = 0; k < 3; k++) {
            int a = v[k], b = v[(k + 1) % 3];
            e[3 * t + k] = (sedge){a < b ? a : b, a < b ? b : a, t};
        }
    }
    size_t ne = 3 * (size_t)m->ntriangles;
    qsort(e, ne, sizeof *e, cmp_sedge);
    for (size_t i = 0; i < ne;) {
        size_t j = i;
        while (j < ne && e[j].a == e[i].a && e[j].b == e[i].b) j++;
        if (j - i != 2) {
            st = ss_error_set(err, SS_ERR_INPUT,
                              "%s: not a closed surface: the edge of triangle %d between vertices "
                              "%d and %d belongs to %zu triangle%s (a closed surface has 2)",
                              name, e[i].t + 1, e[i].a + 1, e[i].b + 1, j - i,
                              j - i == 1 ? "" : "s");
            goto done;
        }
        i = j;
    }
    /* self-intersection: every unique edge as a segment through the BVH */
    if (!(bvh = ss_bvh_build(m, err))) {
        st = err->code ? err->code : SS_ERR_NOMEM;
        goto done;
    }
    for (size_t i = 0; i < ne && !st; i += 2) {
        const float *pa = m->positions + 3 * e[i].a, *pb = m->positions + 3 * e[i].b;
        float dir[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
        float t0 = 1e-4f;
        for (int tries = 0; tries < 32; tries++) {
            ss_ray_hit h;
            if (!ss_bvh_raycast(bvh, pa, dir, t0, 1.0f - 1e-4f, &h)) break;
            const uint32_t *q = m->indices + 3 * h.triangle;
            int touches = 0;
            for (int k = 0; k < 3; k++) {
                int w = weld[q[k]];
                touches |= w == e[i].a || w == e[i].b;
            }
            if (!touches) {
                st = ss_error_set(err, SS_ERR_INPUT,
                                  "%s: the surface intersects itself: the edge of triangle %d "
                                  "crosses triangle %d",
                                  name, e[i].t + 1, h.triangle + 1);
                break;
            }
            t0 = h.t + 1e-5f;
        }
    }
done:
    ss_bvh_free(bvh);
    free(weld);
    free(e);
    return st;
}

/* ---- the patch ---------------------------------------------------------------------- */

void ss_shell_patch_free(ss_shell_patch *p) {
    if (!p) return;
    free(p->cell);
    free(p->surf_z);
    free(p);
}

static void normalise(double v[3]) {
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (l > 0)
        for (int d = 0; d < 3; d++) v[d] /= l;
}

static void tri_normal(const ss_mesh *m, int t, double n[3]) {
    const uint32_t *q = m->indices + 3 * t;
    const float *a = m->positions + 3 * q[0], *b = m->positions + 3 * q[1],
                *c = m->positions + 3 * q[2];
    double u[3], w[3];
    for (int d = 0; d < 3; d++) {
        u[d] = (double)b[d] - a[d];
        w[d] = (double)c[d] - a[d];
    }
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
}

/* What decides the wound: per column from the surface hit's UV (a UV
 * footprint), or per voxel by parity against a wound mesh. */
typedef struct wound_src {
    const ss_image *fp; /* UV footprint, > 0.5 = wound */
    double depth_mm;
    const ss_mesh *wmesh; /* in skin units */
    ss_bvh *wbvh;
} wound_src;

/* The frame, the columns' ray tests and the cells. c: wound centre (mm), n:
 * normal, rw: wound radius (mm). */
static ss_shell_patch *build_patch(const ss_mesh *skin, const char *name, const double c[3],
                                   const double n_in[3], double rw, const ss_shell_opts *o,
                                   double units, const wound_src *ws, ss_error *err) {
    const double dx = o->voxel_mm;
    double n[3] = {n_in[0], n_in[1], n_in[2]};
    normalise(n);
    /* tangent axes: the world axis least aligned with n, made orthogonal */
    int ax = 0;
    for (int d = 1; d < 3; d++)
        if (fabs(n[d]) < fabs(n[ax])) ax = d;
    double e1[3] = {0, 0, 0}, e2[3];
    e1[ax] = 1;
    double dot = e1[0] * n[0] + e1[1] * n[1] + e1[2] * n[2];
    for (int d = 0; d < 3; d++) e1[d] -= dot * n[d];
    normalise(e1);
    e2[0] = n[1] * e1[2] - n[2] * e1[1];
    e2[1] = n[2] * e1[0] - n[0] * e1[2];
    e2[2] = n[0] * e1[1] - n[1] * e1[0];
    double margin = o->margin_mm > 0 ? o->margin_mm : fmax(rw, 5.0);
    double half = rw + margin;
    int nh = (int)ceil(half / dx);
    int nx = 2 * nh + 2, ny = nx;
    if ((double)nx * nx > 4e6) {
        ss_error_set(err, SS_ERR_INPUT,
                     "%s: the wound patch needs %d x %d columns of %g mm; use a coarser voxel",
                     name, nx, ny, dx);
        return NULL;
    }
    const double zr = half; /* surface heights kept: within +-zr of the wound centre */
    ss_bvh *bvh = ss_bvh_build(skin, err);
    if (!bvh) return NULL;
    size_t ncol = (size_t)nx * ny;
    float *hz = malloc(ncol * sizeof(float)), *span = malloc(ncol * sizeof(float));
    uint8_t *wcol = calloc(ncol, 1);
    ss_shell_patch *p = calloc(1, sizeof *p);
    if (!hz || !span || !wcol || !p) {
        ss_bvh_free(bvh);
        free(hz);
        free(span);
        free(wcol);
        free(p);
        ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", name);
        return NULL;
    }
    double zlo = INFINITY, zhi = -INFINITY;
    const double top = zr + o->thickness_mm + 2 * dx;
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            size_t col = (size_t)j * nx + i;
            double a = (i + 0.5 - nx / 2.0) * dx, b = (j + 0.5 - ny / 2.0) * dx;
            float org[3], dir[3];
            for (int d = 0; d < 3; d++) {
                org[d] = (float)((c[d] + a * e1[d] + b * e2[d] + top * n[d]) / units);
                dir[d] = (float)-n[d];
            }
            hz[col] = NAN;
            ss_ray_hit h1, h2;
            if (!ss_bvh_raycast(bvh, org, dir, 0.0f, (float)(3 * top / units), &h1)) continue;
            double z = top - h1.t * units; /* height above the centre along n */
            if (fabs(z) > zr) continue;
            double s = 1e9;
            if (ss_bvh_raycast(bvh, org, dir, h1.t + 1e-6f, (float)(1e9), &h2))
                s = (h2.t - h1.t) * units;
            hz[col] = (float)z;
            span[col] = (float)s;
            if (ws->fp) {
                int px = (int)(h1.uv[0] * ws->fp->width), py = (int)(h1.uv[1] * ws->fp->height);
                if (px >= 0 && py >= 0 && px < ws->fp->width && py < ws->fp->height)
                    wcol[col] = ws->fp->data[(size_t)py * ws->fp->width + px] > 0.5f;
            }
            double lo = z - fmin(s, o->thickness_mm);
            if (lo < zlo) zlo = lo;
            if (z > zhi) zhi = z;
        }
    if (!(zhi > zlo)) {
        ss_error_set(err, SS_ERR_INPUT, "%s: no skin surface under the wound", name);
        goto fail;
    }
    /* z: one bound layer, the tissue, one air layer, one bound layer */
    int nz = (int)ceil((zhi - zlo) / dx) + 4;
    double z0 = zlo - dx; /* height of the grid's bottom face above the centre */
    p->nx = nx;
    p->ny = ny;
    p->nz = nz;
    p->dx_mm = dx;
    p->units_mm = units;
    for (int d = 0; d < 3; d++) {
        p->axis[0][d] = e1[d];
        p->axis[1][d] = e2[d];
        p->axis[2][d] = n[d];
        p->origin_mm[d] = c[d] - (nx / 2.0) * dx * e1[d] - (ny / 2.0) * dx * e2[d] + z0 * n[d];
        p->wound_centre_mm[d] = c[d];
    }
    p->wound_radius_mm = rw;
    p->skin_top_mm = zhi - z0;
    size_t nc = ncol * (size_t)nz;
    p->cell = calloc(nc, 1);
    p->surf_z = malloc(ncol * sizeof(float));
    if (!p->cell || !p->surf_z) {
        ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory for %d x %d x %d voxels", name, nx, ny,
                     nz);
        goto fail;
    }
    const double epi = fmax(o->epidermis_mm, 1e-9);
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            size_t col = (size_t)j * nx + i;
            p->surf_z[col] = isnan(hz[col]) ? NAN : (float)(hz[col] - z0);
            /* wound-mesh crossings along +n through this column */
            double cross[64];
            int ncross = 0;
            if (ws->wbvh) {
                double a = (i + 0.5) * dx, b = (j + 0.5) * dx;
                float org[3], dir[3];
                for (int d = 0; d < 3; d++) {
                    org[d] = (float)((p->origin_mm[d] + a * e1[d] + b * e2[d] - dx * n[d]) / units);
                    dir[d] = (float)n[d];
                }
                float t0 = 0;
                ss_ray_hit h;
                while (ncross < 64 &&
                       ss_bvh_raycast(ws->wbvh, org, dir, t0, (float)((nz + 2) * dx / units), &h)) {
                    cross[ncross++] = h.t * units - dx;
                    t0 = h.t + 1e-6f;
                }
            }
            for (int k = 0; k < nz; k++) {
                size_t idx = ((size_t)k * ny + j) * nx + i;
                double zc = (k + 0.5) * dx; /* above the grid bottom */
                uint8_t s = SS_CELL_AIR;
                if (!isnan(hz[col])) {
                    double h = hz[col] - z0, depth = h - zc;
                    if (depth >= 0 && depth <= span[col]) {
                        if (depth > o->thickness_mm)
                            s = SS_CELL_BOUND;
                        else {
                            int wound = 0;
                            if (ws->fp) wound = wcol[col] && depth <= ws->depth_mm;
                            if (ws->wbvh) {
                                int below = 0;
                                for (int q = 0; q < ncross; q++) below += cross[q] < zc;
                                wound = below & 1;
                            }
                            int ktop = (int)floor(h / dx - 0.5); /* the surface voxel */
                            s = wound                       ? SS_CELL_WOUND
                                : k == ktop || depth <= epi ? SS_CELL_EPIDERMIS
                                                            : SS_CELL_DERMIS;
                        }
                    }
                }
                if (i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1)
                    s = s == SS_CELL_AIR ? SS_CELL_AIR : SS_CELL_BOUND;
                if (s == SS_CELL_WOUND) p->wound_cells++;
                p->cell[idx] = s;
            }
        }
    /* the outermost shell is a wall everywhere */
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < ny; j++)
            for (int i = 0; i < nx; i++)
                if (i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1)
                    p->cell[((size_t)k * ny + j) * nx + i] = SS_CELL_BOUND;
    ss_bvh_free(bvh);
    free(hz);
    free(span);
    free(wcol);
    return p;
fail:
    ss_bvh_free(bvh);
    free(hz);
    free(span);
    free(wcol);
    ss_shell_patch_free(p);
    return NULL;
}

static ss_status check_opts(const ss_shell_opts *o, ss_error *err) {
    if (!(o->voxel_mm >= 0.05 && o->voxel_mm <= 10))
        return ss_error_set(err, SS_ERR_INPUT, "--voxel-mm %g: need 0.05..10 mm", o->voxel_mm);
    if (!(o->thickness_mm >= 3 * o->voxel_mm && o->thickness_mm <= 100))
        return ss_error_set(err, SS_ERR_INPUT,
                            "--skin-thickness-mm %g: need at least 3 voxels (%g mm) and <= 100",
                            o->thickness_mm, 3 * o->voxel_mm);
    if (!(o->depth_mm > 0 && o->depth_mm <= o->thickness_mm))
        return ss_error_set(err, SS_ERR_INPUT,
                            "--wound-depth-mm %g: need > 0 and at most the skin thickness %g mm",
                            o->depth_mm, o->thickness_mm);
    if (!(o->margin_mm >= 0 && o->margin_mm <= 1000) || !(o->units_mm >= 0 && o->units_mm < 1e9))
        return ss_error_set(err, SS_ERR_INPUT, "shell options: margin or units out of range");
    return SS_OK;
}

/* ---- how far a wound wraps around the body ------------------------------------------ */

/* The smooth (vertex-interpolated) normal of triangle t at uv. */
static void smooth_normal_at_uv(const ss_mesh *m, int t, const float uv[2], double nrm[3]) {
    const uint32_t *q = m->indices + 3 * t;
    const float *a = m->uvs + 2 * q[0], *b = m->uvs + 2 * q[1], *c = m->uvs + 2 * q[2];
    double d = (double)(b[0] - a[0]) * (c[1] - a[1]) - (double)(c[0] - a[0]) * (b[1] - a[1]);
    double w1 = 1.0 / 3, w2 = 1.0 / 3;
    if (fabs(d) > 1e-30) {
        w1 = ((double)(uv[0] - a[0]) * (c[1] - a[1]) - (double)(c[0] - a[0]) * (uv[1] - a[1])) / d;
        w2 = ((double)(b[0] - a[0]) * (uv[1] - a[1]) - (double)(uv[0] - a[0]) * (b[1] - a[1])) / d;
    }
    double w[3] = {1 - w1 - w2, w1, w2};
    for (int k = 0; k < 3; k++) nrm[k] = 0;
    for (int v = 0; v < 3; v++)
        for (int k = 0; k < 3; k++) nrm[k] += w[v] * m->normals[3 * q[v] + k];
    normalise(nrm);
}

/* Angle in degrees between unit n and nrm (normalised here). */
static double angle_deg(const double n[3], double nrm[3]) {
    normalise(nrm);
    double c = n[0] * nrm[0] + n[1] * nrm[1] + n[2] * nrm[2];
    return acos(c > 1 ? 1 : c < -1 ? -1 : c) * 57.295779513082321; /* radians to degrees */
}

/* The largest angle (degrees) between unit n and the unit normals nrm[0..ns),
 * and in *at the index where it is. */
static double max_angle(double (*nrm)[3], int ns, const double n[3], int *at) {
    double worst = 0;
    *at = 0;
    for (int i = 0; i < ns; i++) {
        double v[3] = {nrm[i][0], nrm[i][1], nrm[i][2]}, a = angle_deg(n, v);
        if (a > worst) worst = a, *at = i;
    }
    return worst;
}

/* The direction whose largest angle to the normals is smallest (the axis of
 * the narrowest cone holding them), by Badoiu and Clarkson's iteration for
 * the smallest enclosing ball: step towards the farthest normal by 1/(k+1),
 * renormalise. Deterministic; from n0. */
static void minimax_normal(double (*nrm)[3], int ns, const double n0[3], double m[3]) {
    memcpy(m, n0, 3 * sizeof *m);
    for (int k = 1; k <= 400 && ns > 0; k++) {
        int w;
        max_angle(nrm, ns, m, &w);
        for (int d = 0; d < 3; d++) m[d] += (nrm[w][d] - m[d]) / (k + 1);
        normalise(m);
    }
}

/* The stroke points' largest distance from c across n (the wound radius). */
static double projected_radius(double (*pos)[3], int np, const double c[3], const double n[3]) {
    double rw = 0;
    for (int i = 0; i < np; i++) {
        double v[3], h = 0, r2 = 0;
        for (int d = 0; d < 3; d++) v[d] = pos[i][d] - c[d];
        for (int d = 0; d < 3; d++) h += v[d] * n[d];
        for (int d = 0; d < 3; d++) r2 += (v[d] - h * n[d]) * (v[d] - h * n[d]);
        if (sqrt(r2) > rw) rw = sqrt(r2);
    }
    return rw;
}

static ss_status wrap_error(ss_error *err, const char *wound, const char *skin, double deg,
                            const double at_mm[3]) {
    return ss_error_set(err, SS_ERR_INPUT,
                        "%s: the wound wraps around the surface of %s: its surface turns %.0f "
                        "degrees away from the skin patch's normal (at %.1f, %.1f, %.1f mm), more "
                        "than the %d degrees one skin patch can hold (its voxel columns follow one "
                        "direction, so the wound's steep sides would be cut off); split it into "
                        "wounds that each face one way and run them separately",
                        wound, skin, deg, at_mm[0], at_mm[1], at_mm[2], SS_SHELL_MAX_WRAP_DEG);
}

ss_shell_patch *ss_shell_patch_from_uv(const ss_mesh *skin, const char *skin_name, const char *csv,
                                       const ss_shell_opts *o, ss_error *err) {
    if (check_opts(o, err)) return NULL;
    if (!skin->has_uvs) {
        ss_error_set(err, SS_ERR_INPUT, "%s: the mesh has no UVs for --wound-uv", skin_name);
        return NULL;
    }
    ss_stroke_set s;
    if (ss_stroke_csv_read(csv, &s, err)) return NULL;
    double units;
    if (ss_shell_units_resolve(skin, skin_name, o->units_mm, &units, NULL, 0, err)) return NULL;
    int *island = malloc((size_t)skin->ntriangles * sizeof(int));
    int *pisl = malloc((size_t)s.nstrokes * sizeof(int));
    double(*pos)[3] = malloc((size_t)s.npoints * sizeof *pos);
    double(*nrm)[3] = NULL, (*npos)[3] = NULL; /* surface normals over the wound, and where */
    ss_image *fp = NULL;
    ss_shell_patch *p = NULL;
    if (!island || !pisl || !pos) {
        ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", csv);
        goto done;
    }
    ss_mesh_uv_islands(skin, island);
    for (int k = 0; k < s.nstrokes; k++) pisl[k] = -1;
    double c[3] = {0, 0, 0}, n[3] = {0, 0, 0};
    for (int i = 0; i < s.npoints; i++) {
        float uv[2] = {(float)s.u[i], (float)s.v[i]}, ps[3];
        int t = ss_mesh_locate_uv(skin, uv, ps);
        if (t < 0) {
            ss_error_set(err, SS_ERR_INPUT,
                         "%s: point %d (u %g, v %g) lies outside the UV islands of %s", csv, i + 1,
                         s.u[i], s.v[i], skin_name);
            goto done;
        }
        int k = 0;
        while (s.stroke_ids[k] != s.stroke[i]) k++;
        if (pisl[k] >= 0 && pisl[k] != island[t]) {
            ss_error_set(err, SS_ERR_INPUT,
                         "%s: stroke %d spans two UV islands of %s (point %d, u %g, v %g); a "
                         "hull across a seam would cut the wrong skin: split the stroke",
                         csv, s.stroke[i], skin_name, i + 1, s.u[i], s.v[i]);
            goto done;
        }
        pisl[k] = island[t];
        double tn[3];
        tri_normal(skin, t, tn);
        for (int d = 0; d < 3; d++) {
            pos[i][d] = ps[d] * units;
            c[d] += pos[i][d] / s.npoints;
            n[d] += tn[d];
        }
    }
    normalise(n);
    double rw = projected_radius(pos, s.npoints, c, n);
    /* the hulls with rounded corners, as `skinsim abrasion` draws them */
    if (!(fp =
              ss_stroke_footprint_rounded(&s, 2048, 2048, o->concave_k, SS_STROKE_ROUND, csv, err)))
        goto done;
    /* how far the wound wraps: the smooth surface normal at every stroke
     * point and at every mesh vertex inside a hull (vertices far from the
     * strokes are skipped: a layout that mirrors UVs puts another part of
     * the body under the same hulls) */
    if (!(nrm = malloc(((size_t)s.npoints + (size_t)skin->nvertices) * sizeof *nrm)) ||
        !(npos = malloc(((size_t)s.npoints + (size_t)skin->nvertices) * sizeof *npos))) {
        ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", csv);
        goto done;
    }
    int ns = 0;
    for (int i = 0; i < s.npoints; i++) {
        float uv[2] = {(float)s.u[i], (float)s.v[i]}, ps[3];
        int t = ss_mesh_locate_uv(skin, uv, ps);
        if (t < 0) continue; /* cannot happen: every point was located above */
        smooth_normal_at_uv(skin, t, uv, nrm[ns]);
        memcpy(npos[ns++], pos[i], sizeof npos[0]);
    }
    const double near2 = (2 * rw + 5) * (2 * rw + 5);
    for (int v = 0; v < skin->nvertices; v++) {
        int px = (int)(skin->uvs[2 * v] * fp->width), py = (int)(skin->uvs[2 * v + 1] * fp->height);
        if (px < 0 || py < 0 || px >= fp->width || py >= fp->height ||
            !(fp->data[(size_t)py * fp->width + px] > 0.5f))
            continue;
        double dd = 0;
        for (int d = 0; d < 3; d++) {
            npos[ns][d] = skin->positions[3 * v + d] * units;
            nrm[ns][d] = skin->normals[3 * v + d];
            dd += (npos[ns][d] - c[d]) * (npos[ns][d] - c[d]);
        }
        if (dd <= near2) normalise(nrm[ns++]);
    }
    int wi;
    double worst = max_angle(nrm, ns, n, &wi);
    if (worst > SS_SHELL_MAX_WRAP_DEG) {
        /* the mean of the stroke points' normals leans to where the points
         * are dense: the normal that minimises the largest angle may hold
         * the wound (then the patch takes it) */
        double m[3];
        minimax_normal(nrm, ns, n, m);
        int wj;
        double w2 = max_angle(nrm, ns, m, &wj);
        if (w2 < worst) {
            worst = w2, wi = wj;
            memcpy(n, m, sizeof m);
            rw = projected_radius(pos, s.npoints, c, n);
        }
    }
    if (worst > SS_SHELL_MAX_WRAP_DEG) {
        wrap_error(err, csv, skin_name, worst, npos[wi]);
        goto done;
    }
    wound_src ws = {fp, o->depth_mm, NULL, NULL};
    p = build_patch(skin, skin_name, c, n, rw + o->voxel_mm, o, units, &ws, err);
    if (p && p->wound_cells == 0) {
        ss_error_set(err, SS_ERR_INPUT,
                     "%s: the strokes cut no skin voxel of %s (wound too small "
                     "for %g mm voxels?)",
                     csv, skin_name, o->voxel_mm);
        ss_shell_patch_free(p);
        p = NULL;
    }
done:
    ss_image_free(fp);
    free(island);
    free(pisl);
    free(pos);
    free(nrm);
    free(npos);
    ss_stroke_set_free(&s);
    return p;
}

ss_shell_patch *ss_shell_patch_from_mesh(const ss_mesh *skin, const char *skin_name,
                                         const ss_mesh *wound, const char *wound_name,
                                         const ss_shell_opts *o, ss_error *err) {
    if (check_opts(o, err)) return NULL;
    double units;
    if (ss_shell_units_resolve(skin, skin_name, o->units_mm, &units, NULL, 0, err)) return NULL;
    double lo[3], hi[3], c[3], n[3] = {0, 0, 0};
    for (int d = 0; d < 3; d++) {
        lo[d] = wound->bbox_min[d] * units - o->voxel_mm;
        hi[d] = wound->bbox_max[d] * units + o->voxel_mm;
        c[d] = 0.5 * (lo[d] + hi[d]);
    }
    /* the skin facing the wound: the nearest surface hit of 26 rays from the
     * wound's centre (axes, face and space diagonals), its triangle's normal */
    double rw = 0;
    for (int d = 0; d < 3; d++) rw = fmax(rw, 0.5 * (hi[d] - lo[d]));
    ss_bvh *sb = ss_bvh_build(skin, err);
    if (!sb) return NULL;
    double best = INFINITY;
    for (int a = -1; a <= 1; a++)
        for (int b = -1; b <= 1; b++)
            for (int e = -1; e <= 1; e++) {
                if (!a && !b && !e) continue;
                double l = sqrt((double)(a * a + b * b + e * e));
                float org[3], dir[3] = {(float)(a / l), (float)(b / l), (float)(e / l)};
                for (int d = 0; d < 3; d++) org[d] = (float)(c[d] / units);
                ss_ray_hit h;
                if (ss_bvh_raycast(sb, org, dir, 0.0f, 1e30f, &h) && h.t * units < best) {
                    best = h.t * units;
                    tri_normal(skin, h.triangle, n);
                }
            }
    ss_bvh_free(sb);
    if (!(best <= rw + o->thickness_mm) || !(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > 0)) {
        ss_error_set(err, SS_ERR_INPUT, "%s: the wound mesh misses the skin of %s", wound_name,
                     skin_name);
        return NULL;
    }

    wound_src ws = {NULL, 0, wound, ss_bvh_build(wound, err)};
    if (!ws.wbvh) return NULL;
    /* how far the wound wraps: the normal of every skin vertex inside the
     * wound mesh (ray parity) against the skin's normal facing the wound */
    normalise(n);
    for (int v = 0; v < skin->nvertices; v++) {
        const float *q = skin->positions + 3 * v;
        int inside = 1;
        for (int d = 0; d < 3; d++)
            inside &= q[d] >= wound->bbox_min[d] && q[d] <= wound->bbox_max[d];
        if (!inside) continue;
        const float dir[3] = {0.5773503f, 0.5773503f, 0.5773503f};
        int crossings = 0;
        float t0 = 0;
        ss_ray_hit h;
        while (crossings < 1000 && ss_bvh_raycast(ws.wbvh, q, dir, t0, 1e30f, &h)) {
            crossings++;
            t0 = h.t + 1e-6f;
        }
        if (!(crossings & 1)) continue;
        double sn[3] = {skin->normals[3 * v], skin->normals[3 * v + 1], skin->normals[3 * v + 2]};
        double a = angle_deg(n, sn);
        if (a > SS_SHELL_MAX_WRAP_DEG) {
            double at[3] = {q[0] * units, q[1] * units, q[2] * units};
            wrap_error(err, wound_name, skin_name, a, at);
            ss_bvh_free(ws.wbvh);
            return NULL;
        }
    }
    ss_shell_patch *p = build_patch(skin, skin_name, c, n, rw, o, units, &ws, err);
    ss_bvh_free(ws.wbvh);
    if (p && p->wound_cells == 0) {
        ss_error_set(err, SS_ERR_INPUT, "%s: the wound mesh misses the skin of %s", wound_name,
                     skin_name);
        ss_shell_patch_free(p);
        return NULL;
    }
    return p;
}

ss_status ss_shell_patch_grid_init(const ss_shell_patch *p, ss_heal_grid *g,
                                   const ss_heal_params *hp, ss_error *err) {
    if (!p || !g || !hp || g->nx != p->nx || g->ny != p->ny || g->nz != p->nz)
        return ss_error_set(err, SS_ERR_INPUT, "shell grid: the grid does not match the patch");
    float hv[SS_HEAL_NFIELDS];
    ss_heal_params_healthy(hp, hv);
    g->skin_top_mm = p->skin_top_mm;
    g->t_days = 0;
    g->step = 0;
    size_t n = (size_t)p->nx * p->ny * p->nz;
    for (size_t i = 0; i < n; i++) {
        uint8_t s = p->cell[i];
        g->cell[i] = s;
        float v[SS_HEAL_NFIELDS] = {0};
        if (s == SS_CELL_EPIDERMIS || s == SS_CELL_DERMIS || s == SS_CELL_BOUND) {
            if (s != SS_CELL_BOUND || !isnan(p->surf_z[i % ((size_t)p->nx * p->ny)]))
                for (int f = 0; f < SS_HEAL_NFIELDS; f++) v[f] = hv[f];
            v[SS_HEAL_EPITHELIUM] = s == SS_CELL_EPIDERMIS ? 1.0f : 0.0f;
        } else if (s == SS_CELL_WOUND) {
            v[SS_HEAL_OXYGEN] = (float)hp->u1_wound;
            v[SS_HEAL_PLASMA] = 1.0f;
        }
        for (int f = 0; f < SS_HEAL_NFIELDS; f++) g->field[f][i] = v[f];
    }
    return SS_OK;
}

/* ---- mapping back (§5.4) -------------------------------------------------------------- */

/* The top tissue cell of column (i, j): its level (1 .. nz-2), or -1. */
static int column_top(const ss_shell_patch *p, const uint8_t *cell, int i, int j) {
    for (int k = p->nz - 2; k >= 1; k--) {
        uint8_t c = cell[((size_t)k * p->ny + j) * p->nx + i];
        if (c == SS_CELL_EPIDERMIS || c == SS_CELL_DERMIS || c == SS_CELL_WOUND) return k;
    }
    return -1;
}

void ss_shell_column_tops(const ss_shell_patch *p, const uint8_t *cell, int32_t *top) {
    for (int j = 0; j < p->ny; j++)
        for (int i = 0; i < p->nx; i++) top[(size_t)j * p->nx + i] = column_top(p, cell, i, j);
}

/* The vertex fields from the grid g (and disp over it), or from the values
 * at the columns' top cells (top, tv: ncol x NFIELDS, td: ncol x 3). */
static void vertex_fields(const ss_shell_patch *p, const ss_mesh *skin, const ss_heal_grid *g,
                          const ss_heal_params *hp, float *const *disp, const int32_t *tops,
                          const float *tv, const float *td, float *out) {
    float hv[SS_HEAL_NFIELDS];
    ss_heal_params_healthy(hp, hv);
    hv[SS_HEAL_EPITHELIUM] = 1.0f;
    const int nx = p->nx, ny = p->ny;
#pragma omp parallel for schedule(static)
    for (int v = 0; v < skin->nvertices; v++) {
        float *o = out + (size_t)v * SS_SHELL_VERTEX_STRIDE;
        for (int f = 0; f < SS_HEAL_NFIELDS; f++) o[f] = hv[f];
        o[SS_HEAL_NFIELDS] = o[SS_HEAL_NFIELDS + 1] = o[SS_HEAL_NFIELDS + 2] = 0;
        double q[3] = {0, 0, 0};
        for (int a = 0; a < 3; a++)
            for (int d = 0; d < 3; d++)
                q[a] +=
                    (skin->positions[3 * v + d] * p->units_mm - p->origin_mm[d]) * p->axis[a][d];
        int i = (int)floor(q[0] / p->dx_mm), j = (int)floor(q[1] / p->dx_mm);
        if (i < 1 || j < 1 || i >= nx - 1 || j >= ny - 1) continue;
        size_t col = (size_t)j * nx + i;
        if (isnan(p->surf_z[col]) || fabs(q[2] - p->surf_z[col]) > 2 * p->dx_mm) continue;
        int top = g ? column_top(p, g->cell, i, j) : tops[col];
        if (top < 0) continue;
        size_t idx = ((size_t)top * ny + j) * nx + i;
        float u[3] = {0, 0, 0};
        for (int f = 0; f < SS_HEAL_NFIELDS; f++)
            o[f] = g ? g->field[f][idx] : tv[col * SS_HEAL_NFIELDS + (size_t)f];
        if (g && disp)
            for (int d = 0; d < 3; d++) u[d] = disp[d][idx];
        if (!g && td)
            for (int d = 0; d < 3; d++) u[d] = td[3 * col + (size_t)d];
        if (disp || td)
            for (int d = 0; d < 3; d++)
                o[SS_HEAL_NFIELDS + d] =
                    (float)((u[0] * p->axis[0][d] + u[1] * p->axis[1][d] + u[2] * p->axis[2][d]));
    }
}

void ss_shell_vertex_fields(const ss_shell_patch *p, const ss_mesh *skin, const ss_heal_grid *g,
                            const ss_heal_params *hp, float *const *disp, float *out) {
    vertex_fields(p, skin, g, hp, disp, NULL, NULL, NULL, out);
}

void ss_shell_vertex_fields_top(const ss_shell_patch *p, const ss_mesh *skin,
                                const ss_heal_params *hp, const int32_t *top, const float *tv,
                                const float *td, float *out) {
    vertex_fields(p, skin, NULL, hp, NULL, top, tv, td, out);
}

ss_status ss_shell_surface_vtu_write(const ss_shell_patch *p, const ss_mesh *skin, const float *vf,
                                     const char *path, double t_days, ss_error *err) {
    ss_atomic_file af;
    ss_status st = ss_atomic_open(&af, path, err);
    if (st) return st;
    FILE *f = af.fp;
    const int nv = skin->nvertices, nt = skin->ntriangles;
    const int S = SS_SHELL_VERTEX_STRIDE;
    fprintf(f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
               "byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n");
    fprintf(f,
            "<FieldData><DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" "
            "format=\"ascii\">%.17g</DataArray></FieldData>\n",
            t_days);
    fprintf(f, "<Piece NumberOfPoints=\"%d\" NumberOfCells=\"%d\">\n", nv, nt);
    fprintf(f, "<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for (int v = 0; v < nv; v++)
        fprintf(f, "%.7g %.7g %.7g\n",
                skin->positions[3 * v] * p->units_mm + vf[S * v + SS_HEAL_NFIELDS],
                skin->positions[3 * v + 1] * p->units_mm + vf[S * v + SS_HEAL_NFIELDS + 1],
                skin->positions[3 * v + 2] * p->units_mm + vf[S * v + SS_HEAL_NFIELDS + 2]);
    fprintf(f, "</DataArray></Points>\n<Cells>\n<DataArray type=\"Int32\" Name=\"connectivity\" "
               "format=\"ascii\">\n");
    for (int t = 0; t < nt; t++)
        fprintf(f, "%u %u %u\n", skin->indices[3 * t], skin->indices[3 * t + 1],
                skin->indices[3 * t + 2]);
    fprintf(f, "</DataArray>\n<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n");
    for (int t = 0; t < nt; t++) fprintf(f, "%d\n", 3 * (t + 1));
    fprintf(f, "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for (int t = 0; t < nt; t++) fprintf(f, "5\n");
    fprintf(
        f, "</DataArray>\n</Cells>\n<PointData Scalars=\"epithelium\" Vectors=\"displacement\">\n");
    fprintf(f, "<DataArray type=\"Float32\" Name=\"displacement\" NumberOfComponents=\"3\" "
               "format=\"ascii\">\n");
    for (int v = 0; v < nv; v++)
        fprintf(f, "%.7g %.7g %.7g\n", vf[S * v + SS_HEAL_NFIELDS], vf[S * v + SS_HEAL_NFIELDS + 1],
                vf[S * v + SS_HEAL_NFIELDS + 2]);
    fprintf(f, "</DataArray>\n");
    for (int k = 0; k < SS_HEAL_NFIELDS; k++) {
        fprintf(f, "<DataArray type=\"Float32\" Name=\"%s\" format=\"ascii\">\n",
                ss_heal_field_name(k));
        for (int v = 0; v < nv; v++) fprintf(f, "%.6g\n", vf[S * v + k]);
        fprintf(f, "</DataArray>\n");
    }
    fprintf(f, "<DataArray type=\"UInt8\" Name=\"open_wound\" format=\"ascii\">\n");
    for (int v = 0; v < nv; v++)
        fprintf(f, "%d\n",
                vf[S * v + SS_HEAL_PLASMA] > SS_HEAL_P_MIN &&
                    vf[S * v + SS_HEAL_EPITHELIUM] < ss_heal_open_threshold());
    fprintf(f, "</DataArray>\n</PointData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    if (ferror(f)) {
        ss_atomic_abort(&af);
        return ss_error_set(err, SS_ERR_RUNTIME, "%s: write failed", path);
    }
    return ss_atomic_commit(&af, err);
}

void ss_shell_wound_colour(const float *f, float rgb[3]) {
    static const float skin[3] = {0.70f, 0.42f, 0.32f}, raw[3] = {0.45f, 0.03f, 0.03f},
                       pink[3] = {0.85f, 0.38f, 0.40f}, crust[3] = {0.10f, 0.03f, 0.015f};
    float e = f[SS_HEAL_EPITHELIUM], s = f[SS_HEAL_ESCHAR], rho = f[SS_HEAL_SCAR];
    e = e > 0 ? (e < 1 ? e : 1) : 0;
    s = s > 0 ? (s < 1 ? s : 1) : 0;
    /* how much of this vertex is wound tissue: the clot's plasma, then the
     * scar's collagen that replaces it */
    float w = f[SS_HEAL_PLASMA] > SS_HEAL_P_MIN ? 1.0f : (rho > 0 ? (rho < 1 ? rho : 1) : 0);
    for (int c = 0; c < 3; c++) {
        float bed = raw[c] + (pink[c] - raw[c]) * e;
        float v = skin[c] + (bed - skin[c]) * w;
        rgb[c] = v + (crust[c] - v) * s;
    }
}

ss_status ss_shell_surface_glb_write(const ss_shell_patch *p, const ss_mesh *skin, const float *vf,
                                     const char *path, double t_days, ss_error *err) {
    enum { NA = SS_HEAL_NFIELDS + 1 };
    const int nv = skin->nvertices, S = SS_SHELL_VERTEX_STRIDE;
    float *a = malloc((size_t)nv * NA * sizeof *a), *col = malloc((size_t)nv * 3 * sizeof *col),
          *dl = malloc((size_t)nv * 3 * sizeof *dl);
    if (!a || !col || !dl) {
        free(a), free(col), free(dl);
        return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
    }
    char names[NA][32];
    ss_gltf_vertex_attr at[NA];
    for (int k = 0; k < NA; k++) {
        const char *n = k < SS_HEAL_NFIELDS ? ss_heal_field_name(k) : "open_wound";
        names[k][0] = '_';
        int i = 0;
        for (; n[i] && i < 30; i++)
            names[k][i + 1] = (char)(n[i] >= 'a' && n[i] <= 'z' ? n[i] - 32 : n[i]);
        names[k][i + 1] = '\0';
        at[k] = (ss_gltf_vertex_attr){names[k], a + (size_t)k * nv, 1};
    }
    const double thr = ss_heal_open_threshold();
    for (int v = 0; v < nv; v++) {
        const float *f = vf + (size_t)S * v;
        for (int k = 0; k < SS_HEAL_NFIELDS; k++) a[(size_t)k * nv + v] = f[k];
        a[(size_t)SS_HEAL_NFIELDS * nv + v] =
            f[SS_HEAL_PLASMA] > SS_HEAL_P_MIN && f[SS_HEAL_EPITHELIUM] < thr ? 1.0f : 0.0f;
        ss_shell_wound_colour(f, col + 3 * (size_t)v);
        for (int d = 0; d < 3; d++) /* mm -> mesh units */
            dl[3 * (size_t)v + d] = (float)(f[SS_HEAL_NFIELDS + d] / p->units_mm);
    }
    char extras[512];
    int len = snprintf(extras, sizeof extras, "{\"t_days\":%.17g,\"units\":\"m\",\"attributes\":[",
                       t_days);
    for (int k = 0; k < NA; k++)
        len +=
            snprintf(extras + len, sizeof extras - (size_t)len, "%s\"%s\"", k ? "," : "", names[k]);
    snprintf(extras + len, sizeof extras - (size_t)len,
             "],\"morph_target\":\"displacement\",\"color\":\"wound state\"}");
    ss_gltf_vertex_data d = {.scale_m = p->units_mm / 1000.0,
                             .name = "skin",
                             .color = col,
                             .attrs = at,
                             .nattrs = NA,
                             .morph_delta = dl,
                             .morph_name = "displacement",
                             .morph_weight = 1.0,
                             .extras_json = extras};
    ss_status st = ss_gltf_write_mesh_glb(path, skin, &d, err);
    free(a), free(col), free(dl);
    return st;
}
