/* Skin on a closed surface (seed 001 §5.1, §5.4; src/shell/shell.c) on a
 * 40 mm cube whose faces each have their own UV island (a 3 x 2 atlas):
 * - closedness: the cube passes; without a triangle it is open; two
 *   overlapping cubes are closed but intersect themselves;
 * - a UV-stroke wound on the top face: the patch's normal is +z, the surface
 *   sits where the cube's top is, the cut is depth_mm deep and has the area
 *   of the stroke hull, the skin is thickness_mm thick; strokes outside the
 *   islands or across two of them are input errors naming the CSV;
 * - a wound mesh cuts the voxels inside it; one away from the skin misses it;
 * - mapping back (§5.4): vertices over the wound read the wound's fields, the
 *   others healthy values, and a uniform displacement comes back rotated;
 * - on a cylinder (a finger): a wound over 60 degrees of arc is cut whole, one
 *   over 150 degrees wraps too far and is refused (SS_SHELL_MAX_WRAP_DEG),
 *   one over 110 degrees with its points crowded on one side is held by the
 *   minimax normal;
 * - the mesh refined around the wound for the mapping back stays closed and
 *   keeps its shape. */
#include <math.h>
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "skinsim/paint.h"
#include "skinsim/shell.h"

/* A cube [0,s]^3 shifted by off, 24 vertices, one UV cell per face. */
static void cube(double s, double off, ss_mesh *m) {
    static const int F[6][4][3] = {
        {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}, /* top z = s */
        {{0, 1, 0}, {1, 1, 0}, {1, 0, 0}, {0, 0, 0}}, /* bottom */
        {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}, /* y = 0 */
        {{1, 1, 0}, {0, 1, 0}, {0, 1, 1}, {1, 1, 1}}, /* y = s */
        {{0, 1, 0}, {0, 0, 0}, {0, 0, 1}, {0, 1, 1}}, /* x = 0 */
        {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}}, /* x = s */
    };
    float pos[72], uv[48];
    uint32_t idx[36];
    for (int f = 0; f < 6; f++) {
        double u0 = (f % 3) / 3.0 + 0.01, v0 = (f / 3) / 2.0 + 0.01, du = 1 / 3.0 - 0.02,
               dv = 0.5 - 0.02;
        static const double cu[4] = {0, 1, 1, 0}, cv[4] = {1, 1, 0, 0};
        for (int k = 0; k < 4; k++) {
            for (int d = 0; d < 3; d++) pos[3 * (4 * f + k) + d] = (float)(F[f][k][d] * s + off);
            uv[2 * (4 * f + k)] = (float)(u0 + cu[k] * du);
            uv[2 * (4 * f + k) + 1] = (float)(v0 + cv[k] * dv);
        }
        uint32_t b = 4 * f, q[6] = {b, b + 1, b + 2, b, b + 2, b + 3};
        memcpy(idx + 6 * f, q, sizeof q);
    }
    ss_error err;
    assert_int_equal(ss_mesh_from_arrays(pos, NULL, uv, 24, idx, 12, "cube", m, &err), SS_OK);
}

static void test_closed(void **state) {
    (void)state;
    ss_mesh m, open, two;
    ss_error err;
    cube(40, 0, &m);
    assert_int_equal(ss_shell_check_closed(&m, "cube", &err), SS_OK);
    assert_int_equal(
        ss_mesh_from_arrays(m.positions, NULL, NULL, 24, m.indices, 11, "open", &open, &err),
        SS_OK);
    assert_int_equal(ss_shell_check_closed(&open, "open.obj", &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "open.obj"));
    assert_non_null(strstr(err.msg, "not a closed surface"));
    /* two cubes, the second shifted into the first */
    ss_mesh b;
    cube(40, 10, &b);
    float pos[144];
    uint32_t idx[72];
    memcpy(pos, m.positions, 72 * sizeof(float));
    memcpy(pos + 72, b.positions, 72 * sizeof(float));
    for (int i = 0; i < 36; i++) idx[i] = m.indices[i], idx[36 + i] = b.indices[i] + 24;
    assert_int_equal(ss_mesh_from_arrays(pos, NULL, NULL, 48, idx, 24, "two", &two, &err), SS_OK);
    assert_int_equal(ss_shell_check_closed(&two, "two.obj", &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "intersects itself"));
    ss_mesh_free(&m);
    ss_mesh_free(&open);
    ss_mesh_free(&two);
    ss_mesh_free(&b);
}

static void write_text(const char *path, const char *t) {
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(t, f);
    fclose(f);
}

static void test_uv_patch(void **state) {
    (void)state;
    ss_error err;
    ss_mesh m;
    cube(40, 0, &m);
    char *dir = tu_tmpdir("shell"), csv[4096];
    snprintf(csv, sizeof csv, "%s/s.csv", dir);
    /* top face island: u in 0.01..0.323, v in 0.01..0.49 (v = 0.49 at y = 0);
     * a square of 0.1 x 0.2 UV = 0.1/0.313*40 x 0.2/0.48*40 mm */
    write_text(csv, "u,v\n0.1,0.1\n0.2,0.1\n0.2,0.3\n0.1,0.3\n");
    ss_shell_opts o;
    ss_shell_opts_default(&o);
    o.units_mm = 1;
    ss_shell_patch *p = ss_shell_patch_from_uv(&m, "cube.obj", csv, &o, &err);
    assert_non_null(p);
    assert_float_equal(p->axis[2][2], 1.0, 1e-9);
    /* the surface: z = 40 mm */
    double top = p->origin_mm[2] + p->skin_top_mm;
    assert_float_equal(top, 40.0, 1e-6);
    double w = 0.1 / (1 / 3.0 - 0.02) * 40, h = 0.2 / (0.5 - 0.02) * 40;
    int cols = 0, tissue_max = 0;
    for (int j = 0; j < p->ny; j++)
        for (int i = 0; i < p->nx; i++) {
            int wc = 0, t = 0;
            for (int k = 0; k < p->nz; k++) {
                uint8_t c = p->cell[((size_t)k * p->ny + j) * p->nx + i];
                wc += c == SS_CELL_WOUND;
                t += c == SS_CELL_WOUND || c == SS_CELL_EPIDERMIS || c == SS_CELL_DERMIS;
            }
            if (wc) {
                assert_int_equal(wc, (int)lround(o.depth_mm / o.voxel_mm));
                cols++;
            }
            if (t > tissue_max) tissue_max = t;
        }
    assert_int_equal(tissue_max, (int)lround(o.thickness_mm / o.voxel_mm));
    double area = cols * o.voxel_mm * o.voxel_mm;
    assert_true(fabs(area - w * h) < 0.1 * w * h);
    /* grid and mapping back */
    ss_heal_params *hp = ss_heal_params_preset("clean", &err);
    ss_heal_grid *g = ss_heal_grid_create(p->nx, p->ny, p->nz, p->dx_mm, &err);
    assert_int_equal(ss_shell_patch_grid_init(p, g, hp, &err), SS_OK);
    size_t n = (size_t)p->nx * p->ny * p->nz;
    float *u[3];
    for (int d = 0; d < 3; d++) {
        u[d] = malloc(n * sizeof(float));
        for (size_t i = 0; i < n; i++) u[d][i] = d == 0 ? 0.5f : 0.0f;
    }
    float *vf = malloc((size_t)m.nvertices * SS_SHELL_VERTEX_STRIDE * sizeof(float));
    ss_shell_vertex_fields(p, &m, g, hp, u, vf);
    /* the bottom face is outside the patch: healthy, no displacement */
    for (int v = 0; v < m.nvertices; v++) {
        if (m.positions[3 * v + 2] != 0) continue;
        assert_float_equal(vf[v * SS_SHELL_VERTEX_STRIDE + SS_HEAL_EPITHELIUM], 1.0, 1e-6);
        assert_float_equal(vf[v * SS_SHELL_VERTEX_STRIDE + SS_HEAL_NFIELDS], 0.0, 0);
    }
    /* a vertex on the wound: a one-vertex mesh at the top face centre of the cut */
    ss_mesh one;
    float c[9] = {(float)(0.15 / (1 / 3.0 - 0.02) * 40 - 0.01 * 40 / (1 / 3.0 - 0.02)),
                  0,
                  40,
                  0,
                  0,
                  40,
                  0,
                  0,
                  40};
    double vc = 0.2, yy = (0.49 - vc) / 0.48 * 40; /* v -> y on the top face */
    c[0] = (float)((0.15 - 0.01) / (1 / 3.0 - 0.02) * 40);
    c[1] = (float)yy;
    c[3] = 1, c[6] = 2; /* a second, third vertex far away on the top */
    c[4] = 1, c[7] = 1;
    uint32_t t3[3] = {0, 1, 2};
    assert_int_equal(ss_mesh_from_arrays(c, NULL, NULL, 3, t3, 1, "one", &one, &err), SS_OK);
    float vf1[3 * SS_SHELL_VERTEX_STRIDE];
    ss_shell_vertex_fields(p, &one, g, hp, u, vf1);
    assert_float_equal(vf1[SS_HEAL_EPITHELIUM], 0.0, 1e-6);
    assert_float_equal(vf1[SS_HEAL_PLASMA], 1.0, 1e-6);
    for (int d = 0; d < 3; d++) /* 0.5 mm along the patch's x axis, in the mesh frame */
        assert_float_equal(vf1[SS_HEAL_NFIELDS + d], 0.5 * p->axis[0][d], 1e-6);
    ss_mesh_free(&one);
    free(vf);
    for (int d = 0; d < 3; d++) free(u[d]);
    ss_heal_grid_free(g);
    ss_heal_params_free(hp);
    ss_shell_patch_free(p);
    /* bad strokes */
    write_text(csv, "u,v\n0.333,0.2\n0.334,0.3\n0.333,0.4\n"); /* between two islands */
    assert_null(ss_shell_patch_from_uv(&m, "cube.obj", csv, &o, &err));
    assert_non_null(strstr(err.msg, "outside the UV islands"));
    assert_non_null(strstr(err.msg, "s.csv"));
    write_text(csv, "u,v\n0.1,0.1\n0.2,0.1\n0.5,0.3\n");
    assert_null(ss_shell_patch_from_uv(&m, "cube.obj", csv, &o, &err));
    assert_non_null(strstr(err.msg, "two UV islands"));
    ss_mesh_free(&m);
    tu_rmtree(dir);
    free(dir);
}

static void test_wound_mesh(void **state) {
    (void)state;
    ss_error err;
    ss_mesh m, w, far;
    cube(40, 0, &m);
    cube(4, 18, &w); /* 18..22 in x, y, z */
    /* a 6 mm box straddling the top face */
    float pos[72];
    memcpy(pos, w.positions, sizeof pos);
    for (int i = 0; i < 24; i++) pos[3 * i + 2] += 20.5f; /* z 38.5..42.5 */
    ss_mesh_free(&w);
    uint32_t idx[36];
    ss_mesh tmp;
    cube(4, 18, &tmp);
    memcpy(idx, tmp.indices, sizeof idx);
    ss_mesh_free(&tmp);
    assert_int_equal(ss_mesh_from_arrays(pos, NULL, NULL, 24, idx, 12, "w", &w, &err), SS_OK);
    ss_shell_opts o;
    ss_shell_opts_default(&o);
    o.units_mm = 1;
    ss_shell_patch *p = ss_shell_patch_from_mesh(&m, "cube.obj", &w, "w.obj", &o, &err);
    assert_non_null(p);
    assert_float_equal(p->axis[2][2], 1.0, 1e-9);
    /* 4 x 4 mm footprint, 1.5 mm deep (38.5..40) */
    assert_int_equal(p->wound_cells, 8 * 8 * 3);
    ss_shell_patch_free(p);
    cube(2, 100, &far);
    assert_null(ss_shell_patch_from_mesh(&m, "cube.obj", &far, "far.obj", &o, &err));
    assert_non_null(strstr(err.msg, "misses the skin"));
    ss_mesh_free(&far);
    ss_mesh_free(&w);
    ss_mesh_free(&m);
}

/* A closed cylinder along x (0..len mm, radius r), n segments around: the
 * side is one UV island (u = 0.05 + 0.9 phi / 2 pi, v = 0.45 x / len), the
 * caps two more (v > 0.5). phi = 90 degrees faces +z. */
static void cylinder(double r, double len, int n, ss_mesh *m) {
    const int M = 12, nside = (n + 1) * (M + 1), nv = nside + 2 * (n + 1);
    float *pos = malloc((size_t)nv * 3 * sizeof(float)),
          *uv = malloc((size_t)nv * 2 * sizeof(float));
    uint32_t *idx = malloc((size_t)(2 * n * M + 2 * n) * 3 * sizeof(uint32_t));
    int t = 0;
    for (int j = 0; j <= M; j++)
        for (int k = 0; k <= n; k++) {
            double phi = k == n ? 0 : 2 * M_PI * k / n; /* the seam welds exactly */
            int v = j * (n + 1) + k;
            pos[3 * v] = (float)(len * j / M), pos[3 * v + 1] = (float)(r * cos(phi)),
                    pos[3 * v + 2] = (float)(r * sin(phi));
            uv[2 * v] = (float)(0.05 + 0.9 * k / n), uv[2 * v + 1] = (float)(0.45 * j / M);
        }
    for (int j = 0; j < M; j++)
        for (int k = 0; k < n; k++) {
            uint32_t a = (uint32_t)(j * (n + 1) + k), b = a + 1, c = a + (uint32_t)(n + 1),
                     d = c + 1;
            uint32_t q[6] = {a, b, d, a, d, c};
            memcpy(idx + 3 * t, q, sizeof q);
            t += 2;
        }
    /* caps: a centre and a ring each, at x = 0 (facing -x) and x = len */
    for (int e = 0; e < 2; e++) {
        int base = nside + e * (n + 1);
        double x = e ? len : 0;
        pos[3 * base] = (float)x, pos[3 * base + 1] = 0, pos[3 * base + 2] = 0;
        uv[2 * base] = (float)(0.25 + 0.5 * e), uv[2 * base + 1] = 0.75f;
        for (int k = 0; k < n; k++) {
            double phi = 2 * M_PI * k / n;
            int v = base + 1 + k;
            pos[3 * v] = (float)x, pos[3 * v + 1] = (float)(r * cos(phi)),
                    pos[3 * v + 2] = (float)(r * sin(phi));
            uv[2 * v] = (float)(0.25 + 0.5 * e + 0.2 * cos(phi)),
                   uv[2 * v + 1] = (float)(0.75 + 0.2 * sin(phi));
        }
        for (int k = 0; k < n; k++) {
            uint32_t c = (uint32_t)base, a = c + 1 + (uint32_t)k,
                     b = c + 1 + (uint32_t)((k + 1) % n);
            uint32_t q[3] = {c, e ? a : b, e ? b : a};
            memcpy(idx + 3 * t, q, sizeof q);
            t++;
        }
    }
    /* the caps' rings weld to the side's ends by position */
    ss_error err;
    assert_int_equal(ss_mesh_from_arrays(pos, NULL, uv, nv, idx, t, "cyl", m, &err), SS_OK);
    free(pos), free(uv), free(idx);
}

/* A wound on a finger-like cylinder: 60 degrees of arc heals whole (no
 * column cut off); 150 degrees of arc wraps too far and is refused, naming
 * the CSV and the limit. */
/* columns of the patch holding any wound voxel: the wound's projected area in voxels */
static int wound_columns(const ss_shell_patch *p) {
    const size_t plane = (size_t)p->nx * p->ny;
    int cols = 0;
    for (size_t q = 0; q < plane; q++) {
        int wc = 0;
        for (int k = 0; k < p->nz; k++) wc |= p->cell[(size_t)k * plane + q] == SS_CELL_WOUND;
        cols += wc;
    }
    return cols;
}

static void test_wrap(void **state) {
    (void)state;
    ss_error err;
    ss_mesh m;
    cylinder(8, 60, 72, &m);
    assert_int_equal(ss_shell_check_closed(&m, "cyl.obj", &err), SS_OK);
    char *dir = tu_tmpdir("shell"), csv[4096], text[512];
    snprintf(csv, sizeof csv, "%s/arc.csv", dir);
    ss_shell_opts o;
    ss_shell_opts_default(&o);
    o.units_mm = 1;
    const double half_deg[2] = {30, 75};
    for (int c = 0; c < 2; c++) {
        double u0 = 0.05 + 0.9 * (90 - half_deg[c]) / 360,
               u1 = 0.05 + 0.9 * (90 + half_deg[c]) / 360;
        double v0 = 0.45 * 25 / 60, v1 = 0.45 * 35 / 60; /* x 25..35 mm */
        snprintf(text, sizeof text, "u,v\n%.6f,%.6f\n%.6f,%.6f\n%.6f,%.6f\n%.6f,%.6f\n", u0, v0, u1,
                 v0, u1, v1, u0, v1);
        write_text(csv, text);
        ss_shell_patch *p = ss_shell_patch_from_uv(&m, "cyl.obj", csv, &o, &err);
        if (c == 0) {
            assert_non_null(p);
            assert_float_equal(p->axis[2][2], 1.0, 1e-3);
            /* every wound column: the projected arc, 10 mm x 2 r sin 30 deg */
            double area = wound_columns(p) * o.voxel_mm * o.voxel_mm,
                   want = 10 * 2 * 8 * sin(M_PI / 6);
            assert_true(fabs(area - want) < 0.15 * want);
            ss_shell_patch_free(p);
        } else {
            assert_null(p);
            assert_int_equal(err.code, SS_ERR_INPUT);
            assert_non_null(strstr(err.msg, "arc.csv"));
            assert_non_null(strstr(err.msg, "wraps around"));
            assert_non_null(strstr(err.msg, "60 degrees"));
        }
    }
    /* 30..140 degrees of arc (half-span 55) with the stroke's points crowded
     * on the 140 degree edge: their mean normal leans there (the 30 degree
     * edge is 96 degrees off it); the patch takes the normal that minimises
     * the largest angle instead (85 degrees) and holds the whole arc */
    {
        double u0 = 0.05 + 0.9 * 30 / 360.0, u1 = 0.05 + 0.9 * 140 / 360.0;
        double v0 = 0.45 * 25 / 60, v1 = 0.45 * 35 / 60;
        int len = snprintf(text, sizeof text, "u,v\n%.6f,%.6f\n%.6f,%.6f\n", u0, v0, u0, v1);
        for (int k = 0; k <= 10; k++)
            len += snprintf(text + len, sizeof text - (size_t)len, "%.6f,%.6f\n", u1,
                            v0 + (v1 - v0) * k / 10);
        write_text(csv, text);
        ss_shell_patch *p = ss_shell_patch_from_uv(&m, "cyl.obj", csv, &o, &err);
        assert_non_null(p);
        double phi = atan2(p->axis[2][2], p->axis[2][1]) * 180 / M_PI;
        assert_true(fabs(phi - 85) < 3);
        double area = wound_columns(p) * o.voxel_mm * o.voxel_mm,
               want = 10 * 2 * 8 * sin(55 * M_PI / 180);
        assert_true(fabs(area - want) < 0.15 * want);
        ss_shell_patch_free(p);
    }
    ss_mesh_free(&m);
    tu_rmtree(dir);
    free(dir);
}

static double mesh_area(const ss_mesh *m) {
    double a = 0;
    for (int t = 0; t < m->ntriangles; t++) {
        const float *p0 = m->positions + 3 * m->indices[3 * t],
                    *p1 = m->positions + 3 * m->indices[3 * t + 1],
                    *p2 = m->positions + 3 * m->indices[3 * t + 2];
        double u[3], w[3];
        for (int d = 0; d < 3; d++) u[d] = p1[d] - p0[d], w[d] = p2[d] - p0[d];
        double c0 = u[1] * w[2] - u[2] * w[1], c1 = u[2] * w[0] - u[0] * w[2],
               c2 = u[0] * w[1] - u[1] * w[0];
        a += 0.5 * sqrt(c0 * c0 + c1 * c1 + c2 * c2);
    }
    return a;
}

/* The mesh the fields are mapped onto (ss_mesh_refine_near): refined around
 * a point on the cylinder it stays closed (no T-junction, seams included),
 * keeps its area and its old vertices, has short edges near the point, and
 * every new vertex sits where its UV lies on the original mesh. */
static void test_refine(void **state) {
    (void)state;
    ss_error err;
    ss_mesh m, r;
    cylinder(8, 60, 24, &m);               /* 2.1 mm around, 5 mm along */
    const float c[3] = {30, 7.52f, 2.74f}; /* 20 degrees from the UV seam at +y */
    assert_int_equal(ss_mesh_refine_near(&m, c, 6, 0.8f, 6, &r, &err), SS_OK);
    assert_true(r.ntriangles > 4 * m.ntriangles / 3);
    assert_int_equal(ss_shell_check_closed(&r, "refined", &err), SS_OK);
    assert_float_equal(mesh_area(&r), mesh_area(&m), 1e-4 * mesh_area(&m));
    assert_memory_equal(r.positions, m.positions, (size_t)m.nvertices * 3 * sizeof(float));
    for (int t = 0; t < r.ntriangles; t++)
        for (int k = 0; k < 3; k++) {
            const float *a = r.positions + 3 * r.indices[3 * t + k],
                        *b = r.positions + 3 * r.indices[3 * t + (k + 1) % 3];
            float da = 0, e = 0;
            for (int d = 0; d < 3; d++)
                da += (a[d] - c[d]) * (a[d] - c[d]), e += (a[d] - b[d]) * (a[d] - b[d]);
            if (da < 3 * 3) assert_true(sqrtf(e) <= 0.8f);
        }
    for (int v = m.nvertices; v < r.nvertices; v++) {
        float p[3];
        assert_true(ss_mesh_locate_uv(&m, r.uvs + 2 * v, p) >= 0);
        for (int d = 0; d < 3; d++) assert_float_equal(p[d], r.positions[3 * v + d], 1e-3);
        float l = 0;
        for (int d = 0; d < 3; d++) l += r.normals[3 * v + d] * r.normals[3 * v + d];
        assert_float_equal(l, 1.0, 1e-5);
    }
    /* a seam: a unit square of two triangles whose shared diagonal has its
     * vertices duplicated (other UVs); refining near (0,0) splits the first
     * triangle, and the second must split the diagonal too: every edge used
     * by only one triangle lies on the square's border */
    const float sp[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0},
                su[12] = {0, 0, 0.4f, 0, 0, 0.4f, 0.6f, 0, 1, 0, 0.6f, 0.4f};
    const uint32_t si[6] = {0, 1, 2, 3, 4, 5};
    ss_mesh sq, sr;
    assert_int_equal(ss_mesh_from_arrays(sp, NULL, su, 6, si, 2, "square", &sq, &err), SS_OK);
    const float corner[3] = {0, 0, 0};
    assert_int_equal(ss_mesh_refine_near(&sq, corner, 0.3f, 0.9f, 1, &sr, &err), SS_OK);
    assert_int_equal(sr.ntriangles, 4 + 2);
    for (int t = 0; t < sr.ntriangles; t++)
        for (int k = 0; k < 3; k++) {
            const float *a = sr.positions + 3 * sr.indices[3 * t + k],
                        *b = sr.positions + 3 * sr.indices[3 * t + (k + 1) % 3];
            int uses = 0;
            for (int t2 = 0; t2 < sr.ntriangles; t2++)
                for (int k2 = 0; k2 < 3; k2++) {
                    const float *c2 = sr.positions + 3 * sr.indices[3 * t2 + k2],
                                *d2 = sr.positions + 3 * sr.indices[3 * t2 + (k2 + 1) % 3];
                    uses += (!memcmp(a, c2, 12) && !memcmp(b, d2, 12)) ||
                            (!memcmp(a, d2, 12) && !memcmp(b, c2, 12));
                }
            int border = (a[0] == b[0] && (a[0] == 0 || a[0] == 1)) ||
                         (a[1] == b[1] && (a[1] == 0 || a[1] == 1));
            assert_int_equal(uses, border ? 1 : 2);
        }
    ss_mesh_free(&sq);
    ss_mesh_free(&sr);
    /* nothing near: the same mesh */
    ss_mesh same;
    const float far[3] = {500, 0, 0};
    assert_int_equal(ss_mesh_refine_near(&m, far, 1, 0.8f, 6, &same, &err), SS_OK);
    assert_int_equal(same.ntriangles, m.ntriangles);
    ss_mesh_free(&same);
    ss_mesh_free(&r);
    ss_mesh_free(&m);
}

/* OBJ units from the bounding-box diagonal (docs/mesh.md "Units"): a
 * forearm-sized block in metres, cm and mm; glTF and an explicit unit win. */
static void test_units(void **state) {
    (void)state;
    ss_error err;
    ss_mesh m;
    char note[512];
    double u = 0;
    cube(0.2, 0, &m); /* diagonal 0.35: metres, with a note naming the file */
    assert_int_equal(ss_shell_units_resolve(&m, "arm.obj", 0, &u, note, sizeof note, &err), SS_OK);
    assert_true(u == 1000);
    assert_non_null(strstr(note, "arm.obj: read in metres"));
    ss_mesh_free(&m);
    cube(20, 0, &m); /* diagonal 35: mm or cm, refused naming the flag */
    assert_int_equal(ss_shell_units_resolve(&m, "arm.obj", 0, &u, note, sizeof note, &err),
                     SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "arm.obj"));
    assert_non_null(strstr(err.msg, "--mesh-units-mm"));
    ss_shell_opts o;
    ss_shell_opts_default(&o);
    assert_null(ss_shell_patch_from_mesh(&m, "arm.obj", &m, "w.obj", &o, &err));
    assert_non_null(strstr(err.msg, "--mesh-units-mm"));
    assert_int_equal(ss_shell_units_resolve(&m, "arm.obj", 10, &u, note, sizeof note, &err), SS_OK);
    assert_true(u == 10 && note[0] == 0);
    assert_int_equal(ss_shell_units_resolve(&m, "arm.GLB", 0, &u, NULL, 0, &err), SS_OK);
    assert_true(u == 1000);
    ss_mesh_free(&m);
    cube(200, 0, &m); /* diagonal 346: mm, no note */
    assert_int_equal(ss_shell_units_resolve(&m, "arm.obj", 0, &u, note, sizeof note, &err), SS_OK);
    assert_true(u == 1 && note[0] == 0);
    ss_mesh_free(&m);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_closed),     cmocka_unit_test(test_uv_patch),
        cmocka_unit_test(test_wound_mesh), cmocka_unit_test(test_wrap),
        cmocka_unit_test(test_refine),     cmocka_unit_test(test_units),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
