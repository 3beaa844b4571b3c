/* Tests for heal_io: VTI files parse back with the right extents, sizes and
 * data; checkpoints round-trip exactly, reject truncation/corruption and a
 * resumed run is bit-identical to an uninterrupted one; OBJ parsing and
 * ray-parity voxelisation (cube exact, sphere vs a brute-force winding-number
 * classification and vs the analytic volume); footprint masks; stroke CSV
 * parsing and its errors; surface maps; closure times and plots. */
#define _POSIX_C_SOURCE 200809L
#include "testutil.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "skinsim/heal.h"
#include "skinsim/heal_io.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static void write_text(const char *path, const char *text) {
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

/* ---- VTI ------------------------------------------------------------------------ */

/* Minimal XML well-formedness check of the header part: tags balance. */
static int xml_balanced(const char *s, const char *end) {
    const char *stack[64];
    size_t len[64];
    int depth = 0;
    for (const char *p = s; p < end; p++) {
        if (*p != '<') continue;
        if (p[1] == '?') {
            p = strstr(p, "?>");
            if (!p) return 0;
            continue;
        }
        const char *q = strchr(p, '>');
        if (!q || q > end) return 0;
        if (p[1] == '/') {
            const char *nm = p + 2;
            size_t l = strcspn(nm, " >");
            if (depth == 0 || len[depth - 1] != l || strncmp(stack[depth - 1], nm, l)) return 0;
            depth--;
        } else if (q[-1] != '/') {
            if (depth == 64) return 0;
            stack[depth] = p + 1;
            len[depth] = strcspn(p + 1, " >/");
            depth++;
        }
        p = q;
    }
    return depth;
}

static uint64_t get_u64le(const unsigned char *b) {
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--) v = v << 8 | b[i];
    return v;
}

static void test_vti_roundtrip(void **state) {
    (void)state;
    char *dir = tu_tmpdir("vti");
    char *path = tu_join(dir, "g.vti");
    int nx = 7, ny = 5, nz = 4;
    ss_heal_grid *g = tu_heal_grid_noisy(nx, ny, nz, 0.25, 3, 1);
    ss_error err;
    assert_int_equal(ss_heal_vti_write(path, g, &err), SS_OK);
    size_t len;
    char *data = ss_read_file(path, &len, &err);
    assert_non_null(data);
    char *app = strstr(data, "<AppendedData encoding=\"raw\">");
    assert_non_null(app);
    /* the header up to the appended section is balanced with only VTKFile open */
    assert_int_equal(xml_balanced(data, app), 1);
    char want[256];
    snprintf(want, sizeof want, "WholeExtent=\"0 %d 0 %d 0 %d\"", nx, ny, nz);
    assert_non_null(strstr(data, want));
    snprintf(want, sizeof want, "<Piece Extent=\"0 %d 0 %d 0 %d\">", nx, ny, nz);
    assert_non_null(strstr(data, want));
    assert_non_null(strstr(data, "Spacing=\"0.25 0.25 0.25\""));
    assert_non_null(strstr(data, "Origin=\"0 0 0\""));
    assert_non_null(strstr(data, "header_type=\"UInt64\""));
    const unsigned char *base = (const unsigned char *)strchr(app, '_') + 1;
    size_t n = (size_t)nx * ny * nz;
    /* cell_state */
    char *da = strstr(data, "Name=\"cell_state\"");
    assert_non_null(da);
    assert_non_null(strstr(data, "type=\"UInt8\" Name=\"cell_state\""));
    unsigned long long off;
    assert_int_equal(sscanf(strstr(da, "offset=\"") + 8, "%llu", &off), 1);
    assert_int_equal(get_u64le(base + off), n);
    assert_memory_equal(base + off + 8, g->cell, n);
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) {
        char key[128];
        snprintf(key, sizeof key, "type=\"Float32\" Name=\"%s\"", ss_heal_field_name(f));
        char *d = strstr(data, key);
        assert_non_null(d);
        assert_int_equal(sscanf(strstr(d, "offset=\"") + 8, "%llu", &off), 1);
        assert_int_equal(get_u64le(base + off), 4 * n);
        assert_true((const char *)base + off + 8 + 4 * n <= data + len);
        float *back = malloc(4 * n);
        memcpy(back, base + off + 8, 4 * n); /* little-endian host assumed by the test */
        assert_memory_equal(back, g->field[f], 4 * n);
        free(back);
    }
    /* velocity: 3 interleaved components per cell */
    char *dv = strstr(data, "Name=\"velocity\" NumberOfComponents=\"3\"");
    assert_non_null(dv);
    assert_int_equal(sscanf(strstr(dv, "offset=\"") + 8, "%llu", &off), 1);
    assert_int_equal(get_u64le(base + off), 12 * n);
    for (size_t i = 0; i < n; i += 17)
        for (int c = 0; c < 3; c++) {
            float v;
            memcpy(&v, base + off + 8 + 12 * i + 4 * (size_t)c, 4);
            assert_true(v == g->velocity[c][i]);
        }
    /* total appended size: every block accounted for, then the closing tags */
    size_t blocks = 8 + n + SS_HEAL_NFIELDS * (8 + 4 * n);
    int vel = g->velocity[0] != NULL;
    if (vel) blocks += 8 + 12 * n;
    blocks += 8 + 4 * n; /* surface_elevation_mm */
    const char *tail = (const char *)base + blocks;
    assert_true(tail < data + len);
    assert_int_equal(strncmp(tail, "\n  </AppendedData>\n</VTKFile>\n", 30), 0);
    assert_int_equal((size_t)(tail + 30 - data), len);
    /* the time is recorded */
    assert_non_null(strstr(data, "Name=\"TimeValue\""));
    free(data);

    /* read back (ss_heal_vti_read): every field and cell state exactly, the
     * time, a displacement array de-interleaved into x, y, z blocks */
    {
        float *disp = (float *)1;
        ss_heal_grid *h = ss_heal_vti_read(path, &disp, NULL, &err);
        assert_non_null(h);
        assert_null(disp);
        assert_int_equal(h->nx, nx);
        assert_int_equal(h->nz, nz);
        assert_true(h->dx_mm == g->dx_mm && h->t_days == g->t_days);
        assert_memory_equal(h->cell, g->cell, n);
        for (int f = 0; f < SS_HEAL_NFIELDS; f++)
            assert_memory_equal(h->field[f], g->field[f], 4 * n);
        ss_heal_grid_free(h);
        char *pv = tu_join(dir, "v.vti");
        const char *name = "displacement";
        float *const vec[1][3] = {{g->field[0], g->field[1], g->field[2]}};
        double *closed = malloc(sizeof *closed * (size_t)nx * ny), *cback = NULL;
        ss_heal_closure_init(g, closed);
        closed[3] = 2.75;
        assert_int_equal(ss_heal_vti_write_all(pv, g, 1, &name, vec, closed, &err), SS_OK);
        h = ss_heal_vti_read(pv, &disp, &cback, &err);
        assert_non_null(h);
        assert_non_null(disp);
        assert_non_null(cback);
        for (int c = 0; c < 3; c++) assert_memory_equal(disp + (size_t)c * n, g->field[c], 4 * n);
        assert_memory_equal(cback, closed, sizeof *closed * (size_t)nx * ny);
        free(disp);
        free(closed);
        free(cback);
        ss_heal_grid_free(h);
        /* truncated: an input error naming the file, no crash */
        size_t vlen;
        char *vd = ss_read_file(pv, &vlen, &err);
        assert_non_null(vd);
        for (size_t cut = 100; cut < vlen; cut += vlen / 7) {
            FILE *fp = fopen(pv, "wb");
            fwrite(vd, 1, cut, fp);
            fclose(fp);
            ss_error_clear(&err);
            assert_null(ss_heal_vti_read(pv, &disp, NULL, &err));
            assert_int_equal(err.code, SS_ERR_INPUT);
            assert_non_null(strstr(err.msg, "v.vti"));
        }
        free(vd);
        free(pv);
    }

    /* pvd collection */
    char *pvd = tu_join(dir, "f.pvd");
    double t[2] = {0, 2.5};
    const char *files[2] = {"a.vti", "b&c.vti"};
    assert_int_equal(ss_heal_pvd_write(pvd, 2, t, files, &err), SS_OK);
    data = ss_read_file(pvd, NULL, &err);
    assert_non_null(data);
    assert_non_null(
        strstr(data, "<DataSet timestep=\"2.5\" group=\"\" part=\"0\" file=\"b&amp;c.vti\"/>"));
    assert_int_equal(xml_balanced(data, data + strlen(data)), 0);
    free(data);
    free(pvd);
    ss_heal_grid_free(g);
    free(path);
    tu_rmtree(dir);
    free(dir);
}

/* ---- checkpoints ------------------------------------------------------------------- */

static void test_checkpoint_roundtrip_and_corruption(void **state) {
    (void)state;
    char *dir = tu_tmpdir("ckpt");
    ss_error err;
    ss_heal_grid *g = tu_heal_grid_noisy(9, 6, 5, 0.25, 11, 1);
    const char *pj = "{\"scenario\": \"clean\"}";
    assert_int_equal(
        ss_heal_checkpoint_save(dir, g, "keloid", pj, SS_HEAL_SPLIT, 0.0125, "{\"x\":1}", 2, &err),
        SS_OK);
    ss_heal_checkpoint ck;
    char note[1024];
    assert_int_equal(ss_heal_checkpoint_load_latest(dir, &ck, note, sizeof note, &err), SS_OK);
    assert_string_equal(note, "");
    tu_assert_heal_grids_equal(g, ck.grid);
    assert_string_equal(ck.scenario, "keloid");
    assert_string_equal(ck.params_json, pj);
    assert_string_equal(ck.aux, "{\"x\":1}");
    assert_int_equal(ck.scheme, SS_HEAL_SPLIT);
    assert_true(ck.dt_days == 0.0125);
    ss_heal_checkpoint_free(&ck);

    /* a second, newer checkpoint; then damage it: loading falls back to the older */
    uint64_t old_step = g->step;
    g->step = old_step + 10;
    g->field[SS_HEAL_SCAR][3] = 42.0f;
    assert_int_equal(
        ss_heal_checkpoint_save(dir, g, "keloid", pj, SS_HEAL_SPLIT, 0.0125, "", 2, &err), SS_OK);
    char name[128];
    snprintf(name, sizeof name, "checkpoints/ckpt_%012llu.sshc", (unsigned long long)g->step);
    char *newest = tu_join(dir, name);
    size_t len;
    char *bytes = ss_read_file(newest, &len, &err);
    assert_non_null(bytes);
    /* reading the intact newest one gives the new state */
    assert_int_equal(ss_heal_checkpoint_read(newest, &ck, &err), SS_OK);
    assert_true(ck.grid->field[SS_HEAL_SCAR][3] == 42.0f);
    ss_heal_checkpoint_free(&ck);
    /* a write interrupted after the temporary file: a leftover .tmp is ignored */
    pid_t dead = fork(); /* the id of a process that is gone: a killed writer's */
    if (dead == 0) _exit(0);
    assert_true(dead > 0);
    waitpid(dead, NULL, 0);
    char tname[128];
    snprintf(tname, sizeof tname, "checkpoints/ckpt_999999999999.sshc" SS_ATOMIC_TMP "%ld.abc123",
             (long)dead);
    char *tmp = tu_join(dir, tname);
    FILE *f = fopen(tmp, "wb");
    fwrite(bytes, 1, len / 2, f);
    fclose(f);
    assert_int_equal(ss_heal_checkpoint_load_latest(dir, &ck, note, sizeof note, &err), SS_OK);
    assert_true(ck.grid->step == g->step);
    ss_heal_checkpoint_free(&ck);
    /* truncate the newest: rejected on its own, skipped by load_latest */
    f = fopen(newest, "wb");
    fwrite(bytes, 1, len - 100, f);
    fclose(f);
    assert_int_equal(ss_heal_checkpoint_read(newest, &ck, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, newest));
    assert_null(ck.grid);
    assert_int_equal(ss_heal_checkpoint_load_latest(dir, &ck, note, sizeof note, &err), SS_OK);
    assert_true(ck.grid->step == old_step);
    assert_true(ck.grid->field[SS_HEAL_SCAR][3] != 42.0f);
    assert_non_null(strstr(note, "skipped"));
    ss_heal_checkpoint_free(&ck);
    /* one flipped bit in the data: CRC mismatch */
    bytes[len / 2] ^= 0x10;
    f = fopen(newest, "wb");
    fwrite(bytes, 1, len, f);
    fclose(f);
    assert_int_equal(ss_heal_checkpoint_read(newest, &ck, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "CRC"));
    /* a foreign file */
    write_text(newest, "hello, this is not a checkpoint at all");
    assert_int_equal(ss_heal_checkpoint_read(newest, &ck, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "magic"));
    /* keep = 2: a third save removes the oldest, and the stale temporary file */
    g->step = old_step + 20;
    assert_int_equal(
        ss_heal_checkpoint_save(dir, g, "keloid", pj, SS_HEAL_SPLIT, 0.0125, "", 2, &err), SS_OK);
    char *cdir = tu_join(dir, "checkpoints");
    assert_int_equal(tu_count_entries(cdir), 2);
    assert_int_not_equal(access(tmp, F_OK), 0);
    free(cdir);
    /* nothing at all */
    char *empty = tu_tmpdir("ckpt-empty");
    assert_int_equal(ss_heal_checkpoint_load_latest(empty, &ck, NULL, 0, &err), SS_ERR_INPUT);
    tu_rmtree(empty);
    free(empty);
    free(bytes);
    free(tmp);
    free(newest);
    ss_heal_grid_free(g);
    tu_rmtree(dir);
    free(dir);
}

/* Run n steps from a fresh default-like setup. */
static ss_heal_grid *fresh_run(const char *scen, int nx, int ny, int nz, ss_heal_params **pp,
                               ss_heal_scheme sch, double dt) {
    ss_error err;
    ss_heal_params *p = ss_heal_params_preset(scen, &err);
    assert_non_null(p);
    ss_heal_grid *g = ss_heal_grid_create(nx, ny, nz, 0.5, &err);
    assert_non_null(g);
    double top = (nz - 2) * 0.5;
    uint8_t *w = ss_heal_wound_box(g, top, nx * 0.5 * 0.6, ny * 0.5 * 0.5, 1.0, &err);
    assert_non_null(w);
    assert_int_equal(ss_heal_grid_init(g, top, 0.1, w, p, &err), SS_OK);
    free(w);
    (void)sch;
    (void)dt;
    *pp = p;
    return g;
}

static void test_resume_bit_identical(void **state) {
    (void)state;
    int nx = tu_quick() ? 12 : 20, ny = tu_quick() ? 10 : 16, nz = 8;
    int nsteps = tu_quick() ? 8 : 20, ksplit = nsteps / 2 + 1;
    /* the keloid also carries its added volume above the packing limit
     * (g->added, docs/heal-model.md [D16]): the checkpoint holds it */
    for (int run = 0; run < 4; run++) {
        const int sch = run & 1;
        const char *scen = run < 2 ? "scab" : "keloid";
        ss_error err;
        ss_heal_params *p;
        ss_heal_grid *a = fresh_run(scen, nx, ny, nz, &p, (ss_heal_scheme)sch, 0);
        ss_heal_solver *s = ss_heal_solver_create(a, p, (ss_heal_scheme)sch, 0, &err);
        assert_non_null(s);
        double dt = ss_heal_solver_dt(s);
        for (int k = 0; k < nsteps; k++) assert_int_equal(ss_heal_step(s, a, &err), SS_OK);
        ss_heal_solver_free(s);
        assert_true(!a->added == (run < 2));
        double added = 0;
        for (size_t i = 0; a->added && i < (size_t)nx * ny * nz; i++) added += a->added[i];
        assert_true(run < 2 || added > 0);

        /* interrupted run: ksplit steps, checkpoint, throw everything away, resume */
        ss_heal_params *p2;
        ss_heal_grid *b = fresh_run(scen, nx, ny, nz, &p2, (ss_heal_scheme)sch, 0);
        s = ss_heal_solver_create(b, p2, (ss_heal_scheme)sch, dt, &err);
        assert_non_null(s);
        for (int k = 0; k < ksplit; k++) assert_int_equal(ss_heal_step(s, b, &err), SS_OK);
        char *dir = tu_tmpdir("resume");
        char *pj = ss_heal_params_to_json(p2);
        assert_int_equal(ss_heal_checkpoint_save(dir, b, p2->scenario, pj, sch, dt, "", 2, &err),
                         SS_OK);
        free(pj);
        ss_heal_solver_free(s);
        ss_heal_grid_free(b);
        ss_heal_params_free(p2);

        ss_heal_checkpoint ck;
        assert_int_equal(ss_heal_checkpoint_load_latest(dir, &ck, NULL, 0, &err), SS_OK);
        ss_heal_params *p3 = ss_heal_params_parse(ck.params_json, "checkpoint", ck.scenario, &err);
        assert_non_null(p3);
        s = ss_heal_solver_create(ck.grid, p3, (ss_heal_scheme)ck.scheme, ck.dt_days, &err);
        assert_non_null(s);
        assert_true(ss_heal_solver_dt(s) == dt);
        for (int k = ksplit; k < nsteps; k++)
            assert_int_equal(ss_heal_step(s, ck.grid, &err), SS_OK);
        tu_assert_heal_grids_equal(a, ck.grid);
        ss_heal_solver_free(s);
        ss_heal_params_free(p3);
        ss_heal_checkpoint_free(&ck);
        ss_heal_grid_free(a);
        ss_heal_params_free(p);
        tu_rmtree(dir);
        free(dir);
    }
}

/* ---- OBJ + voxelisation --------------------------------------------------------------- */

static const char *CUBE_OBJ_FMT =
    "# a cube with quads, texture/normal index forms and negative indices\n"
    "o cube\n"
    "v %g %g %g\nv %g %g %g\nv %g %g %g\nv %g %g %g\n"
    "v %g %g %g\nv %g %g %g\nv %g %g %g\nv %g %g %g\n"
    "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n"
    "f 1/1/1 4/2/1 3/3/1 2/1/1\n" /* bottom z=lo */
    "f 5//1 6//1 7//1 8//1\n"     /* top z=hi */
    "f -8 -7 -3 -4\n"             /* y=lo: 1 2 6 5 */
    "f 2/1 3/2 7/3 6/1\n"         /* x=hi */
    "f 3 4 8 7\n"                 /* y=hi */
    "f 4 1 5 8\n";                /* x=lo */

static void cube_obj(char *buf, size_t n, double lo[3], double hi[3]) {
    snprintf(buf, n, CUBE_OBJ_FMT, lo[0], lo[1], lo[2], hi[0], lo[1], lo[2], hi[0], hi[1], lo[2],
             lo[0], hi[1], lo[2], lo[0], lo[1], hi[2], hi[0], lo[1], hi[2], hi[0], hi[1], hi[2],
             lo[0], hi[1], hi[2]);
}

static size_t centres_in_box(int n, double dx, const double lo[3], const double hi[3]) {
    size_t c[3];
    for (int k = 0; k < 3; k++) {
        c[k] = 0;
        for (int i = 0; i < n; i++) {
            double x = (i + 0.5) * dx;
            c[k] += x > lo[k] && x < hi[k];
        }
    }
    return c[0] * c[1] * c[2];
}

/* A 10 mm cube whose every triangle has its own copies of its corners (a
 * seam everywhere), each copy moved off the corner by up to eps: copies 1e-9
 * of the size apart (an exporter's rounding) weld and the cube is closed;
 * 1e-3 apart are distinct vertices and it is open. */
static void test_obj_weld_tolerance(void **state) {
    (void)state;
    static const int q[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
    const double eps[2] = {1e-9, 1e-3};
    for (int c = 0; c < 2; c++) {
        char obj[8192];
        size_t o = 0;
        int nv = 0;
        for (int f = 0; f < 6; f++)
            for (int h = 0; h < 2; h++) {
                int tri[3] = {q[f][0], q[f][1 + h], q[f][2 + h]};
                for (int k = 0; k < 3; k++, nv++) {
                    double p[3];
                    for (int d = 0; d < 3; d++)
                        p[d] = 3.0 + 10.0 * ((tri[k] >> d) & 1) +
                               10.0 * eps[c] * (((nv * 7 + d * 3) % 5) - 2) / 2.0;
                    o += (size_t)snprintf(obj + o, sizeof obj - o, "v %.17g %.17g %.17g\n", p[0],
                                          p[1], p[2]);
                }
                o += (size_t)snprintf(obj + o, sizeof obj - o, "f %d %d %d\n", nv - 2, nv - 1, nv);
            }
        ss_tri_mesh m;
        ss_error err;
        assert_int_equal(ss_obj_parse(obj, "seams.obj", &m, &err), SS_OK);
        assert_int_equal(m.nverts, 36);
        ss_status st = ss_tri_mesh_check_closed(&m, "seams.obj", &err);
        if (c == 0) {
            if (st) fail_msg("%s", err.msg);
        } else {
            assert_int_equal(st, SS_ERR_INPUT);
            assert_non_null(strstr(err.msg, "seams.obj"));
        }
        ss_tri_mesh_free(&m);
    }
}

static void test_obj_cube(void **state) {
    (void)state;
    char obj[4096];
    ss_error err;
    ss_tri_mesh m;
    double cases[3][2][3] = {{{2.3, 1.1, 0.7}, {7.7, 6.45, 5.2}},
                             {{1.0, 1.0, 1.0}, {6.0, 6.0, 6.0}},        /* on voxel faces */
                             {{0.75, 2.25, 1.25}, {8.25, 3.75, 4.75}}}; /* on centres */
    for (int c = 0; c < 3; c++) {
        cube_obj(obj, sizeof obj, cases[c][0], cases[c][1]);
        assert_int_equal(ss_obj_parse(obj, "cube.obj", &m, &err), SS_OK);
        assert_int_equal(m.nverts, 8);
        assert_int_equal(m.ntris, 12);
        assert_int_equal(ss_tri_mesh_check_closed(&m, "cube.obj", &err), SS_OK);
        size_t count;
        uint8_t *v = ss_heal_voxelise_mesh(&m, 20, 20, 20, 0.5, &count, &err);
        assert_non_null(v);
        size_t want = centres_in_box(20, 0.5, cases[c][0], cases[c][1]);
        if (c < 2) {
            assert_int_equal(count, want);
        } else {
            /* centres exactly on the faces: the nudged ray decides; within one layer */
            size_t outer =
                centres_in_box(20, 0.5, (double[]){0.7, 2.2, 1.2}, (double[]){8.3, 3.8, 4.8});
            assert_true(count >= want && count <= outer);
        }
        size_t s = 0;
        for (size_t i = 0; i < 8000; i++) s += v[i];
        assert_int_equal(s, count);
        free(v);
        ss_tri_mesh_free(&m);
    }
    /* an open cube (one face removed): error names the file and a line */
    cube_obj(obj, sizeof obj, cases[0][0], cases[0][1]);
    char *last = strstr(obj, "f 4 1 5 8");
    *last = '\0';
    assert_int_equal(ss_obj_parse(obj, "open.obj", &m, &err), SS_OK);
    assert_int_equal(ss_tri_mesh_check_closed(&m, "open.obj", &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "open.obj:"));
    assert_non_null(strstr(err.msg, "not closed"));
    ss_tri_mesh_free(&m);
    /* malformed files */
    const char *bad[][2] = {{"v 1 2\n", "open.obj:1"},
                            {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "open.obj:4"},
                            {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "open.obj:4"},
                            {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", "open.obj:4"},
                            {"v 0 0 nan\n", "not finite"},
                            {"v 0 0 0\nbogus 1\n", "open.obj:2"},
                            {"v 0 0 0\nf 1 x 2\n", "open.obj:2"},
                            {"# only a comment\n", "no faces"}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        assert_int_equal(ss_obj_parse(bad[i][0], "open.obj", &m, &err), SS_ERR_INPUT);
        assert_non_null(strstr(err.msg, bad[i][1]));
    }
    /* missing file */
    assert_int_equal(ss_obj_read("/nonexistent/x.obj", &m, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "/nonexistent/x.obj"));
}

/* UV sphere as OBJ text (poles + rings, quads and triangles). */
static char *sphere_obj(double cx, double cy, double cz, double r, int nu, int nv) {
    size_t cap = (size_t)(nu * nv) * 160 + 1024, len = 0;
    char *s = malloc(cap);
    len += (size_t)snprintf(s + len, cap - len, "v %.17g %.17g %.17g\n", cx, cy, cz + r);
    for (int j = 1; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            double th = M_PI * j / nv, ph = 2 * M_PI * i / nu;
            len += (size_t)snprintf(s + len, cap - len, "v %.17g %.17g %.17g\n",
                                    cx + r * sin(th) * cos(ph), cy + r * sin(th) * sin(ph),
                                    cz + r * cos(th));
        }
    len += (size_t)snprintf(s + len, cap - len, "v %.17g %.17g %.17g\n", cx, cy, cz - r);
    int south = 2 + (nv - 1) * nu;
#define RING(j, i) (2 + ((j)-1) * nu + ((i) % nu))
    for (int i = 0; i < nu; i++)
        len += (size_t)snprintf(s + len, cap - len, "f 1 %d %d\n", RING(1, i), RING(1, i + 1));
    for (int j = 1; j < nv - 1; j++)
        for (int i = 0; i < nu; i++)
            len += (size_t)snprintf(s + len, cap - len, "f %d %d %d %d\n", RING(j, i),
                                    RING(j + 1, i), RING(j + 1, i + 1), RING(j, i + 1));
    for (int i = 0; i < nu; i++)
        len += (size_t)snprintf(s + len, cap - len, "f %d %d %d\n", south, RING(nv - 1, i + 1),
                                RING(nv - 1, i));
#undef RING
    return s;
}

/* Winding number of the closed mesh around p (solid angles, Van Oosterom &
 * Strackee): 1 inside, 0 outside. Brute force over all triangles. */
static double winding(const ss_tri_mesh *m, const double p[3]) {
    double w = 0;
    for (int t = 0; t < m->ntris; t++) {
        double a[3], b[3], c[3];
        for (int k = 0; k < 3; k++) {
            a[k] = m->v[3 * m->tri[3 * t] + k] - p[k];
            b[k] = m->v[3 * m->tri[3 * t + 1] + k] - p[k];
            c[k] = m->v[3 * m->tri[3 * t + 2] + k] - p[k];
        }
        double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        double lc = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        double det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                     a[2] * (b[0] * c[1] - b[1] * c[0]);
        double ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        double bc = b[0] * c[0] + b[1] * c[1] + b[2] * c[2];
        double ca = c[0] * a[0] + c[1] * a[1] + c[2] * a[2];
        w += 2 * atan2(det, la * lb * lc + ab * lc + bc * la + ca * lb);
    }
    return w / (4 * M_PI);
}

static void test_obj_sphere(void **state) {
    (void)state;
    int n = tu_quick() ? 24 : 40;
    double dx = 10.0 / n, r = 3.7;
    char *obj = sphere_obj(5.02, 4.97, 5.01, r, 48, 24);
    ss_tri_mesh m;
    ss_error err;
    assert_int_equal(ss_obj_parse(obj, "sphere.obj", &m, &err), SS_OK);
    free(obj);
    assert_int_equal(ss_tri_mesh_check_closed(&m, "sphere.obj", &err), SS_OK);
    size_t count;
    omp_set_num_threads(1);
    uint8_t *v1 = ss_heal_voxelise_mesh(&m, n, n, n, dx, &count, &err);
    omp_set_num_threads(2);
    size_t count2;
    uint8_t *v2 = ss_heal_voxelise_mesh(&m, n, n, n, dx, &count2, &err);
    assert_non_null(v1);
    assert_non_null(v2);
    assert_int_equal(count, count2);
    assert_memory_equal(v1, v2, (size_t)n * n * n);
    /* brute force: every voxel centre classified by its winding number */
    size_t mismatch = 0, inside_bf = 0;
    for (int z = 0; z < n; z++)
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                double p[3] = {(x + 0.5) * dx, (y + 0.5) * dx, (z + 0.5) * dx};
                int in = winding(&m, p) > 0.5;
                inside_bf += (size_t)in;
                mismatch += (size_t)(in != v1[((size_t)z * n + y) * n + x]);
            }
    assert_int_equal(mismatch, 0);
    assert_int_equal(inside_bf, count);
    /* volume: the polyhedron's volume within the discretisation error of the
     * voxel count (surface voxels: area / dx^2 of them, each +-1/2 voxel) */
    double vol_poly = 0;
    for (int t = 0; t < m.ntris; t++) {
        const double *a = m.v + 3 * m.tri[3 * t], *b = m.v + 3 * m.tri[3 * t + 1],
                     *c = m.v + 3 * m.tri[3 * t + 2];
        vol_poly += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                     a[2] * (b[0] * c[1] - b[1] * c[0])) /
                    6;
    }
    vol_poly = fabs(vol_poly);
    double vol_vox = (double)count * dx * dx * dx, sphere = 4.0 / 3.0 * M_PI * r * r * r;
    assert_true(vol_poly < sphere && vol_poly > 0.97 * sphere);
    double tol = 0.5 * 4 * M_PI * r * r * dx;
    assert_true(fabs(vol_vox - vol_poly) < tol);
    free(v1);
    free(v2);
    ss_tri_mesh_free(&m);
}

/* ---- footprints and strokes ---------------------------------------------------------- */

static void test_footprint_mask(void **state) {
    (void)state;
    char *dir = tu_tmpdir("mask");
    char *path = tu_join(dir, "mask.png");
    ss_error err;
    ss_image *img = ss_image_create(40, 30, 1, &err);
    size_t want = 0;
    for (int y = 0; y < 30; y++)
        for (int x = 0; x < 40; x++) {
            int in = (x - 20) * (x - 20) + (y - 12) * (y - 12) < 81;
            /* anti-aliased edge values straddle the 0.5 threshold */
            ss_image_px(img, x, y)[0] = in ? 0.8f : 0.3f;
            want += (size_t)in;
        }
    assert_int_equal(ss_png_write(path, img, 8, SS_ENC_LINEAR, &err), SS_OK);
    ss_image *fp = ss_heal_footprint_read(path, &err);
    assert_non_null(fp);
    assert_int_equal(fp->width, 40);
    assert_int_equal(fp->height, 30);
    assert_int_equal(fp->channels, 1);
    size_t got = 0;
    for (int y = 0; y < 30; y++)
        for (int x = 0; x < 40; x++) {
            float v = ss_image_px(fp, x, y)[0];
            assert_true(v == 0.0f || v == 1.0f);
            assert_true((v == 1.0f) == ((x - 20) * (x - 20) + (y - 12) * (y - 12) < 81));
            got += v == 1.0f;
        }
    assert_int_equal(got, want);
    ss_image_free(fp);
    /* an empty mask and a missing file are input errors naming the file */
    for (int i = 0; i < 40 * 30; i++) img->data[i] = 0.2f;
    assert_int_equal(ss_png_write(path, img, 8, SS_ENC_LINEAR, &err), SS_OK);
    assert_null(ss_heal_footprint_read(path, &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "empty"));
    assert_null(ss_heal_footprint_read("/nonexistent/m.png", &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    /* depth image: PNG scaled by the maximum depth */
    for (int i = 0; i < 40 * 30; i++) img->data[i] = (i % 40) / 39.0f;
    assert_int_equal(ss_png_write(path, img, 16, SS_ENC_LINEAR, &err), SS_OK);
    ss_image *d = ss_heal_depth_image_read(path, 2.0, &err);
    assert_non_null(d);
    assert_float_equal(ss_image_px(d, 39, 5)[0], 2.0, 1e-4);
    assert_float_equal(ss_image_px(d, 13, 5)[0], 2.0 * 13 / 39.0, 1e-4);
    ss_image_free(d);
    /* depth image: EXR values are mm, unscaled; a negative depth is refused */
    char *exr = tu_join(dir, "depth.exr");
    for (int i = 0; i < 40 * 30; i++) img->data[i] = 0.1f * (float)(i % 40);
    assert_int_equal(ss_exr_write(exr, img, 0, &err), SS_OK);
    d = ss_heal_depth_image_read(exr, 2.0, &err);
    assert_non_null(d);
    assert_float_equal(ss_image_px(d, 39, 7)[0], 3.9, 1e-5);
    ss_image_free(d);
    img->data[77] = -0.5f;
    assert_int_equal(ss_exr_write(exr, img, 0, &err), SS_OK);
    assert_null(ss_heal_depth_image_read(exr, 2.0, &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "depth.exr"));
    free(exr);
    ss_image_free(img);
    free(path);
    tu_rmtree(dir);
    free(dir);
}

static void test_stroke_csv(void **state) {
    (void)state;
    ss_stroke_set s;
    ss_error err;
    const char *good = "u,v,stroke_id\n"
                       "# a comment\n"
                       "0.25, 0.25, 0\n0.75,0.25,0\n0.75,0.75,0\n0.25,0.75,0\r\n"
                       "\n"
                       "0.1,0.1,7\n0.2,0.1,7\n0.15,0.2,7\n";
    assert_int_equal(ss_stroke_csv_parse(good, "s.csv", &s, &err), SS_OK);
    assert_int_equal(s.npoints, 7);
    assert_int_equal(s.nstrokes, 2);
    assert_int_equal(s.stroke_ids[0], 0);
    assert_int_equal(s.stroke_ids[1], 7);
    assert_float_equal(s.u[1], 0.75, 0);
    assert_int_equal(s.stroke[6], 7);
    /* footprint: the square's hull fills 50% x 50% of the image, plus the triangle */
    ss_image *fp = ss_stroke_footprint(&s, 100, 100, 0, "s.csv", &err);
    assert_non_null(fp);
    double sq = 0, tri = 0;
    for (int y = 0; y < 100; y++)
        for (int x = 0; x < 100; x++) {
            float v = ss_image_px(fp, x, y)[0];
            if (x >= 25 && x < 75 && y >= 25 && y < 75) sq += v;
            if (x < 25 && y < 25) tri += v;
        }
    assert_int_equal((int)sq, 2500);
    assert_true(fabs(tri - 50.0) <= 12); /* triangle area 10 x 10 / 2 pixels */
    ss_image_free(fp);
    ss_stroke_set_free(&s);
    /* a UTF-8 byte order mark (spreadsheet export) does not hide the first point */
    assert_int_equal(ss_stroke_csv_parse("\xEF\xBB\xBF"
                                         "0.5,0.5\n1,0\n0,1\n",
                                         "b.csv", &s, &err),
                     SS_OK);
    assert_int_equal(s.npoints, 3);
    ss_stroke_set_free(&s);
    /* no header, no ids: one stroke */
    assert_int_equal(ss_stroke_csv_parse("0,0\n1,0\n0,1\n", "t.csv", &s, &err), SS_OK);
    assert_int_equal(s.nstrokes, 1);
    ss_stroke_set_free(&s);
    const char *bad[][2] = {
        {"0.1,0.1\n0.2,nan\n0.3,0.3\n", "t.csv:2"},    /* NaN */
        {"0.1,0.1\n0.2,0.2\n0.3,inf\n", "not finite"}, /* inf */
        {"0.1,0.1\n1.5,0.2\n0.3,0.3\n", "outside [0,1]"},
        {"0.1,0.1\n-0.01,0.2\n0.3,0.3\n", "t.csv:2"},
        {"0.1,0.1\n0.2,0.2\n", "at least 3"},
        {"0.1,0.1,0\n0.2,0.2,0\n0.3,0.3,0\n0.5,0.5,1\n0.6,0.5,1\n", "stroke 1 has 2"},
        {"0.1,0.1\n0.2\n0.3,0.3\n", "t.csv:2"},
        {"0.1,0.1\n0.2,0.2,0,9\n0.3,0.3\n", "t.csv:2"},
        {"0.1,0.1,-1\n0.2,0.2,-1\n0.3,0.3,-1\n", "stroke id"},
        {"0.1,0.1\nx,y\n0.3,0.3\n", "t.csv:2"}, /* a header only as the first line */
        {"u,v\n# nothing\n", "no stroke points"},
        {"", "no stroke points"}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        ss_error_clear(&err);
        assert_int_equal(ss_stroke_csv_parse(bad[i][0], "t.csv", &s, &err), SS_ERR_INPUT);
        if (!strstr(err.msg, bad[i][1])) fail_msg("case %zu: '%s'", i, err.msg);
        assert_null(s.u);
    }
    assert_int_equal(ss_stroke_csv_read("/nonexistent/s.csv", &s, &err), SS_ERR_INPUT);
    /* collinear stroke: the hull fails with the stroke named */
    assert_int_equal(ss_stroke_csv_parse("0.1,0.1,3\n0.2,0.2,3\n0.3,0.3,3\n", "c.csv", &s, &err),
                     SS_OK);
    assert_null(ss_stroke_footprint(&s, 50, 50, 0, "c.csv", &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "stroke 3"));
    ss_stroke_set_free(&s);
}

/* ---- surface maps, area table and plots -------------------------------------------------- */

/* Surface elevation [D12]: collagen beyond the dermis a wound cell lost, or
 * any collagen added to intact dermis, raises the column by
 * SS_HEAL_COLLAGEN_VOLUME x its volume; a wound cell short of it sinks. Known
 * values on a hand-set grid: the statistics (mean over the wound's columns,
 * largest column) and the VTI array surface_elevation_mm, the column's value
 * in every cell of it. */
static void test_surface_elevation(void **state) {
    (void)state;
    ss_error err;
    ss_heal_params *p = ss_heal_params_preset("clean", &err);
    ss_heal_grid *g = ss_heal_grid_create(8, 8, 8, 0.5, &err);
    assert_non_null(g);
    uint8_t *w = ss_heal_wound_box(g, 3.0, 2.0, 2.0, 1.0, &err);
    assert_non_null(w);
    assert_int_equal(ss_heal_grid_init(g, 3.0, 0.1, w, p, &err), SS_OK);
    free(w);
    /* rho = 0.5 in the wound (short of the dermis' 1), 3 in intact column (1, 1) */
    const size_t n = (size_t)g->nx * g->ny * g->nz;
    for (size_t i = 0; i < n; i++)
        g->field[SS_HEAL_SCAR][i] = g->cell[i] == SS_CELL_WOUND ? 0.5f : 0.0f;
    int keloid_cells = 0;
    for (int z = 0; z < g->nz; z++) {
        size_t i = ss_heal_idx(g, 1, 1, z);
        if (g->cell[i] != SS_CELL_AIR && g->cell[i] != SS_CELL_BOUND) {
            g->field[SS_HEAL_SCAR][i] = 3.0f;
            keloid_cells++;
        }
    }
    assert_int_equal(keloid_cells, 5); /* levels 1..5 below the 3 mm surface */
    const double k = SS_HEAL_COLLAGEN_VOLUME * 0.5;
    const double sunk = 2 * k * (0.5 - 1.0), raised = keloid_cells * k * 3.0; /* 1 mm wound */
    ss_heal_stats st;
    ss_heal_stats_compute(g, &st);
    print_message("elevation: wound mean %.4f (expect %.4f), max %.4f (expect %.4f)\n",
                  st.elevation_mean_mm, sunk, st.elevation_max_mm, raised);
    assert_true(fabs(st.elevation_mean_mm - sunk) < 1e-6);
    assert_true(fabs(st.elevation_max_mm - raised) < 1e-6);
    /* the snapshot's array */
    char *dir = tu_tmpdir("elev");
    char *path = tu_join(dir, "g.vti");
    assert_int_equal(ss_heal_vti_write(path, g, &err), SS_OK);
    size_t len;
    char *data = ss_read_file(path, &len, &err);
    assert_non_null(data);
    char *app = strstr(data, "<AppendedData encoding=\"raw\">");
    char *da = strstr(data, "type=\"Float32\" Name=\"surface_elevation_mm\"");
    assert_non_null(app);
    assert_non_null(da);
    unsigned long long off;
    assert_int_equal(sscanf(strstr(da, "offset=\"") + 8, "%llu", &off), 1);
    const unsigned char *base = (const unsigned char *)strchr(app, '_') + 1;
    assert_int_equal(get_u64le(base + off), 4 * n);
    for (int z = 0; z < g->nz; z++)
        for (int y = 0; y < g->ny; y++)
            for (int x = 0; x < g->nx; x++) {
                float v;
                memcpy(&v, base + off + 8 + 4 * ss_heal_idx(g, x, y, z), 4);
                const int wound = g->cell[ss_heal_idx(g, x, y, 4)] == SS_CELL_WOUND;
                const double want = x == 1 && y == 1 ? raised : wound ? sunk : 0.0;
                assert_true(fabs(v - want) < 1e-6);
            }
    /* the reader takes the file back (the extra array is not a field) */
    ss_heal_grid *b = ss_heal_vti_read(path, NULL, NULL, &err);
    assert_non_null(b);
    assert_memory_equal(b->field[SS_HEAL_SCAR], g->field[SS_HEAL_SCAR], n * sizeof(float));
    assert_null(b->added); /* no keloid_added array without g->added */
    assert_null(strstr(data, "keloid_added"));
    ss_heal_grid_free(b);
    free(data);
    /* a keloid grid's added volume [D16] (0.5 rho units in each tissue cell of
     * column (1, 1)): the snapshot holds it, the reader restores it, and the
     * elevation of the grid read back is the run's (wound --heal draws it) */
    assert_non_null(g->added = calloc(n, sizeof *g->added));
    for (int z = 0; z < g->nz; z++) {
        size_t i = ss_heal_idx(g, 1, 1, z);
        if (g->cell[i] != SS_CELL_AIR && g->cell[i] != SS_CELL_BOUND) g->added[i] = 0.5f;
    }
    assert_int_equal(ss_heal_vti_write(path, g, &err), SS_OK);
    assert_non_null(b = ss_heal_vti_read(path, NULL, NULL, &err));
    assert_non_null(b->added);
    assert_memory_equal(b->added, g->added, n * sizeof(float));
    float *e0 = calloc((size_t)g->nx * g->ny, sizeof *e0),
          *e1 = calloc((size_t)g->nx * g->ny, sizeof *e1);
    assert_non_null(e0);
    assert_non_null(e1);
    ss_heal_elevation_scan(g, 0, g->nz, e0);
    ss_heal_elevation_scan(b, 0, b->nz, e1);
    assert_memory_equal(e0, e1, (size_t)g->nx * g->ny * sizeof *e0);
    const double raised_added = keloid_cells * k * 3.5;
    print_message("elevation with the added volume: %.4f (expect %.4f)\n", e1[1 * g->nx + 1],
                  raised_added);
    assert_true(fabs(e1[1 * g->nx + 1] - raised_added) < 1e-6);
    free(e0);
    free(e1);
    ss_heal_grid_free(b);
    tu_rmtree(dir);
    free(path);
    free(dir);
    ss_heal_grid_free(g);
    ss_heal_params_free(p);
}

static void test_surface_and_area(void **state) {
    (void)state;
    ss_error err;
    ss_heal_grid *g = ss_heal_grid_create(4, 3, 5, 0.5, &err);
    assert_non_null(g);
    g->skin_top_mm = 2.5;
    size_t n = 4 * 3 * 5;
    for (size_t i = 0; i < n; i++) {
        int z = (int)(i / 12), y = (int)(i / 4 % 3), x = (int)(i % 4);
        g->cell[i] = z >= 3 + (x == 0) ? SS_CELL_AIR : SS_CELL_DERMIS; /* column x=0 higher */
        g->field[SS_HEAL_SCAR][i] = (float)(10 * z + y + 0.1 * x);
        if (x == 3 && y == 2) g->cell[i] = SS_CELL_AIR; /* an all-air column */
    }
    /* a top boundary voxel is not tissue: ignored by both maps */
    g->cell[(4 * 3 + 1) * 4 + 1] = SS_CELL_BOUND;
    g->field[SS_HEAL_SCAR][(4 * 3 + 1) * 4 + 1] = 5000;
    ss_image *top = ss_heal_surface_map(g, SS_HEAL_SCAR, SS_SURFACE_TOP, &err);
    ss_image *mx = ss_heal_surface_map(g, SS_HEAL_SCAR, SS_SURFACE_MAX, &err);
    assert_non_null(top);
    assert_non_null(mx);
    for (int y = 0; y < 3; y++)
        for (int x = 0; x < 4; x++) {
            float want = (x == 3 && y == 2) ? 0.0f : (float)(10 * (2 + (x == 0)) + y + 0.1 * x);
            /* image row 0 is the far y edge */
            assert_float_equal(ss_image_px(top, x, 2 - y)[0], want, 1e-5);
            assert_float_equal(ss_image_px(mx, x, 2 - y)[0], want, 1e-5);
        }
    g->field[SS_HEAL_SCAR][1] = 1000; /* buried maximum at z=0, x=1, y=0 */
    ss_image_free(mx);
    mx = ss_heal_surface_map(g, SS_HEAL_SCAR, SS_SURFACE_MAX, &err);
    assert_float_equal(ss_image_px(mx, 1, 2)[0], 1000, 0);
    ss_image_free(top);
    top = ss_heal_surface_map(g, SS_HEAL_SCAR, SS_SURFACE_TOP, &err);
    assert_float_equal(ss_image_px(top, 1, 2)[0], 20.1, 1e-5);
    assert_null(ss_heal_surface_map(g, SS_HEAL_NFIELDS, SS_SURFACE_TOP, &err));

    char *dir = tu_tmpdir("area");
    char *png = tu_join(dir, "s.png");
    assert_int_equal(ss_heal_surface_png(png, mx, 0, 30, "scar", "(density)", 0.5, &err), SS_OK);
    ss_image *back = ss_png_read(png, SS_ENC_LINEAR, &err);
    assert_non_null(back);
    assert_true(back->width >= 360 && back->channels >= 3);
    ss_image_free(back);

    /* area rows: open area falls linearly 1 -> 0 over 10 days */
    ss_heal_area_row rows[11];
    memset(rows, 0, sizeof rows);
    for (int i = 0; i <= 10; i++) {
        rows[i].t_days = i;
        rows[i].st.initial_area_mm2 = 400;
        rows[i].st.open_area_mm2 = 400 * (1 - i / 10.0);
        rows[i].st.wound_region_area_mm2 = 400;
    }
    assert_float_equal(ss_heal_time_to_closure(rows, 11, 0.5), 5.0, 1e-12);
    assert_float_equal(ss_heal_time_to_closure(rows, 11, 0.05), 9.5, 1e-12);
    assert_true(ss_heal_time_to_closure(rows, 5, 0.05) < 0);
    char *csv = tu_join(dir, "area.csv");
    assert_int_equal(ss_heal_area_csv_write(csv, rows, 11, &err), SS_OK);
    char *text = ss_read_file(csv, NULL, &err);
    assert_non_null(text);
    assert_int_equal(
        strncmp(text, "t_days,open_area_mm2,normalised_area,wound_region_area_mm2,mean_", 64), 0);
    int lines = 0;
    for (char *p = text; *p; p++) lines += *p == '\n';
    assert_int_equal(lines, 12);
    assert_non_null(strstr(text, "\n5,200,0.5,400,"));
    free(text);
    assert_int_equal(ss_heal_area_plot(png, rows, 11, "test", &err), SS_OK);
    back = ss_png_read(png, SS_ENC_LINEAR, &err);
    assert_non_null(back);
    assert_int_equal(back->width, 900);
    ss_image_free(back);
    /* zero initial area: normalised 0, not NaN */
    ss_heal_stats z;
    memset(&z, 0, sizeof z);
    assert_float_equal(ss_heal_area_normalised(&z), 0.0, 0);
    free(csv);
    free(png);
    tu_rmtree(dir);
    free(dir);
    ss_image_free(top);
    ss_image_free(mx);
    ss_heal_grid_free(g);
}

/* ---- CLI: mask + depth image ------------------------------------------------------- */

static void test_cli_mask_and_depth_image(void **state) {
    (void)state;
    char *dir = tu_tmpdir("cli");
    char *mask = tu_join(dir, "mask.png"), *depth = tu_join(dir, "depth.png"),
         *out = tu_join(dir, "out");
    ss_error err;
    ss_image *m = ss_image_create(40, 32, 1, &err), *d = ss_image_create(40, 32, 1, &err);
    for (int y = 0; y < 32; y++)
        for (int x = 0; x < 40; x++) {
            ss_image_px(m, x, y)[0] = (x >= 10 && x < 30 && y >= 8 && y < 24) ? 1.0f : 0.0f;
            ss_image_px(d, x, y)[0] = x < 20 ? 0.25f : 1.0f; /* x 2 mm: 0.5 mm | 2 mm deep */
        }
    assert_int_equal(ss_png_write(mask, m, 8, SS_ENC_LINEAR, &err), SS_OK);
    assert_int_equal(ss_png_write(depth, d, 16, SS_ENC_LINEAR, &err), SS_OK);
    ss_image_free(m);
    ss_image_free(d);
    char args[4096], *sum = tu_join(dir, "stdout.json");
    snprintf(args, sizeof args,
             "heal --grid 20x16x8 --days 0.1 --wound-mask '%s' --wound-depth-image '%s' "
             "--wound-depth-mm 2 --out '%s' --json",
             mask, depth, out);
    assert_int_equal(tu_run_cli(args, sum, NULL), 0);
    char *text = ss_read_file(sum, NULL, &err);
    assert_non_null(text);
    /* 10 x 8 wound columns of 0.25 mm^2 */
    assert_non_null(strstr(text, "\"initial_area_mm2\":\t20,"));
    free(text);
    /* wound voxels: 40 columns 1 layer deep (0.5 mm) + 40 columns 4 layers (2 mm) */
    char *vti = tu_join(out, "fields/fields_0000.vti");
    size_t len;
    char *data = ss_read_file(vti, &len, &err);
    assert_non_null(data);
    unsigned long long off;
    char *da = strstr(data, "Name=\"cell_state\"");
    assert_non_null(da);
    assert_int_equal(sscanf(strstr(da, "offset=\"") + 8, "%llu", &off), 1);
    const unsigned char *base =
        (const unsigned char *)strchr(strstr(data, "<AppendedData"), '_') + 1 + off;
    size_t n = get_u64le(base), wound = 0;
    assert_int_equal(n, 20 * 16 * 8);
    for (size_t i = 0; i < n; i++) wound += base[8 + i] == SS_CELL_WOUND;
    assert_int_equal(wound, 200);
    free(data);
    /* the same mask with a depth reaching the bottom is refused, nothing written */
    char *out2 = tu_join(dir, "out2");
    snprintf(args, sizeof args,
             "heal --grid 20x16x8 --days 0.1 --wound-mask '%s' --wound-depth-image '%s' "
             "--wound-depth-mm 3.5 --out '%s'",
             mask, depth, out2);
    assert_int_equal(tu_run_cli(args, NULL, NULL), 2);
    assert_int_not_equal(access(out2, F_OK), 0); /* no directory created */
    free(out2);
    free(vti);
    free(sum);
    free(mask);
    free(depth);
    free(out);
    tu_rmtree(dir);
    free(dir);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_vti_roundtrip),
        cmocka_unit_test(test_checkpoint_roundtrip_and_corruption),
        cmocka_unit_test(test_resume_bit_identical),
        cmocka_unit_test(test_obj_cube),
        cmocka_unit_test(test_obj_weld_tolerance),
        cmocka_unit_test(test_obj_sphere),
        cmocka_unit_test(test_footprint_mask),
        cmocka_unit_test(test_stroke_csv),
        cmocka_unit_test(test_surface_elevation),
        cmocka_unit_test(test_surface_and_area),
        cmocka_unit_test(test_cli_mask_and_depth_image),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
