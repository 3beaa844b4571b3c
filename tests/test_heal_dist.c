/* The library side of the MPI healing solver (docs/scaling.md), without MPI:
 * the exact statistics give the same figures however the columns are split
 * and merged (and are exact where a float sum is not); the sub-box solver
 * (ss_heal_solver_create_sub) steps a box with a one-cell halo to the same
 * bits as the whole grid, and the split step in phases and the explicit step
 * in parts equal ss_heal_step; every rank's set-up of its own box
 * (ss_heal_grid_init_box from the wound's column ranges or a mesh voxelised
 * over the box) gives the whole grid's cells and fields there, and the
 * surface maps scanned in parts equal ss_heal_surface_map. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"
#include "skinsim/heal.h"
#include "skinsim/heal_io.h"

/* scab scenario: a 6 mm wound in a block of nx x ny x nz 0.5 mm voxels */
static ss_heal_grid *problem(const ss_heal_params *p, int nx, int ny, int nz) {
    ss_error err;
    ss_heal_grid *g = ss_heal_grid_create(nx, ny, nz, 0.5, &err);
    assert_non_null(g);
    double top = (nz - 2) * 0.5;
    uint8_t *w = ss_heal_wound_box(g, top, 6.0, 4.0, 1.0, &err);
    assert_non_null(w);
    assert_int_equal(ss_heal_grid_init(g, top, 0.1, w, p, &err), SS_OK);
    free(w);
    return g;
}

static void run(ss_heal_grid *g, const ss_heal_params *p, ss_heal_scheme sc, int steps) {
    ss_error err;
    ss_heal_solver *s = ss_heal_solver_create(g, p, sc, 0, &err);
    assert_non_null(s);
    for (int i = 0; i < steps; i++) assert_int_equal(ss_heal_step(s, g, &err), SS_OK);
    ss_heal_solver_free(s);
}

static void test_stats_parts(void **state) {
    (void)state;
    ss_error err;
    ss_heal_params *p = ss_heal_params_preset("scab", &err);
    ss_heal_grid *g = problem(p, 23, 17, 9);
    run(g, p, SS_HEAL_SPLIT, 6);
    ss_heal_stats whole;
    ss_heal_stats_compute(g, &whole);
    /* 3 x 2 blocks of columns with ragged edges, merged in reverse order */
    const int xs[4] = {0, 7, 8, 23}, ys[3] = {0, 11, 17};
    ss_heal_stats_acc part[6], all;
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 3; i++) {
            ss_heal_stats_acc_init(&part[j * 3 + i]);
            ss_heal_stats_acc_add(&part[j * 3 + i], g, xs[i], xs[i + 1], ys[j], ys[j + 1]);
        }
    ss_heal_stats_acc_init(&all);
    for (int k = 5; k >= 0; k--) ss_heal_stats_acc_merge(&all, &part[k]);
    ss_heal_stats merged;
    ss_heal_stats_acc_finish(&all, g->dx_mm, &merged);
    assert_memory_equal(&whole, &merged, sizeof whole);
    assert_true(whole.initial_area_mm2 > 0 && whole.field_mean[SS_HEAL_OXYGEN] > 0);
    ss_heal_grid_free(g);
    ss_heal_params_free(p);

    /* exact where a float sum is not: 1e30 + 1 - 1e30 over 8 tissue cells */
    g = ss_heal_grid_create(4, 4, 4, 1.0, &err);
    assert_non_null(g);
    for (int z = 1; z < 3; z++)
        for (int y = 1; y < 3; y++)
            for (int x = 1; x < 3; x++) g->cell[ss_heal_idx(g, x, y, z)] = SS_CELL_DERMIS;
    g->field[SS_HEAL_MDGF][ss_heal_idx(g, 1, 1, 1)] = 1e30f;
    g->field[SS_HEAL_MDGF][ss_heal_idx(g, 2, 1, 1)] = 1.0f;
    g->field[SS_HEAL_MDGF][ss_heal_idx(g, 1, 2, 1)] = -1e30f;
    g->field[SS_HEAL_MDGF][ss_heal_idx(g, 2, 2, 2)] = 1e-40f; /* subnormal */
    ss_heal_stats st;
    ss_heal_stats_compute(g, &st);
    assert_true(st.field_mean[SS_HEAL_MDGF] == (1.0 + (double)1e-40f) / 8.0);
    g->field[SS_HEAL_MDGF][ss_heal_idx(g, 2, 1, 1)] = NAN;
    ss_heal_stats_compute(g, &st);
    assert_true(isnan(st.field_mean[SS_HEAL_MDGF]));
    ss_heal_grid_free(g);
}

/* Box [x0, x0 + bx) x [y0, y0 + by) of G with a one-cell halo (outside G:
 * BOUND, zero), every field and the cells. */
static void cut(const ss_heal_grid *G, ss_heal_grid *b, int x0, int y0) {
    for (int z = 0; z < b->nz; z++)
        for (int y = 0; y < b->ny; y++)
            for (int x = 0; x < b->nx; x++) {
                int X = x0 - 1 + x, Y = y0 - 1 + y;
                size_t c = ss_heal_idx(b, x, y, z);
                int in = X >= 0 && Y >= 0 && X < G->nx && Y < G->ny;
                b->cell[c] = in ? G->cell[ss_heal_idx(G, X, Y, z)] : SS_CELL_BOUND;
                for (int f = 0; f < SS_HEAL_NFIELDS; f++)
                    b->field[f][c] = in ? G->field[f][ss_heal_idx(G, X, Y, z)] : 0.0f;
            }
}

/* The same with a halo in z too: levels [z0 - 1, z0 - 1 + b->nz) of G. */
static void cut3(const ss_heal_grid *G, ss_heal_grid *b, int z0) {
    for (int z = 0; z < b->nz; z++)
        for (int y = 0; y < b->ny; y++)
            for (int x = 0; x < b->nx; x++) {
                int X = x - 1, Y = y - 1, Z = z0 - 1 + z;
                size_t c = ss_heal_idx(b, x, y, z);
                int in = X >= 0 && Y >= 0 && Z >= 0 && X < G->nx && Y < G->ny && Z < G->nz;
                b->cell[c] = in ? G->cell[ss_heal_idx(G, X, Y, Z)] : SS_CELL_BOUND;
                for (int f = 0; f < SS_HEAL_NFIELDS; f++)
                    b->field[f][c] = in ? G->field[f][ss_heal_idx(G, X, Y, Z)] : 0.0f;
            }
    b->skin_top_mm = G->skin_top_mm;
    b->t_days = G->t_days;
}

/* A stack of two boxes in z (the MPI driver's z split): the statistics and the
 * closure days scanned down the stack, top box first, equal the whole grid's. */
static void test_stack_columns(void **state) {
    (void)state;
    ss_error err;
    ss_heal_params *p = ss_heal_params_preset("scab", &err);
    ss_heal_grid *G = problem(p, 23, 17, 9);
    run(G, p, SS_HEAL_EXPLICIT, 40);
    /* levels 0..4 (bottom) and 5..8 (top), each with a one-level halo */
    ss_heal_grid *bot = ss_heal_grid_create(25, 19, 7, 0.5, &err);
    ss_heal_grid *top = ss_heal_grid_create(25, 19, 6, 0.5, &err);
    assert_non_null(bot);
    assert_non_null(top);
    cut3(G, bot, 0);
    cut3(G, top, 5);
    ss_heal_col_state cols[23 * 17];
    memset(cols, 0, sizeof cols);
    ss_heal_stats_acc a;
    ss_heal_stats_acc_init(&a);
    ss_heal_stats_acc_add_stack(&a, top, 1, 24, 1, 18, 4, 9, cols, 0);
    ss_heal_stats_acc_add_stack(&a, bot, 1, 24, 1, 18, -1, 9, cols, 1);
    ss_heal_stats whole, stacked;
    ss_heal_stats_compute(G, &whole);
    ss_heal_stats_acc_finish(&a, G->dx_mm, &stacked);
    assert_memory_equal(&whole, &stacked, sizeof whole);
    assert_true(whole.initial_area_mm2 > 0 && whole.eschar_wound_mean > 0);

    double closedG[23 * 17], closedB[25 * 19];
    float v[25 * 19], found[25 * 19];
    ss_heal_closure_init(G, closedG);
    ss_heal_closure_update(G, closedG);
    for (int i = 0; i < 25 * 19; i++) {
        closedB[i] = SS_HEAL_CLOSED_INTACT;
        v[i] = -1.0f;
        found[i] = 0.0f;
    }
    ss_heal_closure_scan(top, 4, 9, v, found);
    ss_heal_closure_scan(bot, -1, 9, v, found);
    ss_heal_closure_apply(bot, v, closedB);
    ss_heal_closure_apply(bot, v, closedB); /* twice, as init + update */
    int open = 0;
    for (int y = 0; y < 17; y++)
        for (int x = 0; x < 23; x++) {
            assert_true(closedG[y * 23 + x] == closedB[(y + 1) * 25 + x + 1]);
            open += closedG[y * 23 + x] == SS_HEAL_CLOSED_OPEN;
        }
    assert_true(open > 0);
    ss_heal_grid_free(bot);
    ss_heal_grid_free(top);
    ss_heal_grid_free(G);
    ss_heal_params_free(p);
}

static void test_subbox_explicit(void **state) {
    (void)state;
    ss_error err;
    ss_heal_params *p = ss_heal_params_preset("scab", &err);
    ss_heal_grid *G = problem(p, 23, 17, 9);
    ss_heal_solver *S = ss_heal_solver_create(G, p, SS_HEAL_EXPLICIT, 0, &err);
    assert_non_null(S);
    const double dt = ss_heal_solver_dt(S);
    /* 2 x 2 boxes, uneven: x 0..10 | 11..22, y 0..7 | 8..16 */
    const int xs[3] = {0, 11, 23}, ys[3] = {0, 8, 17}, gdim[3] = {23, 17, 9};
    ss_heal_grid *b[4];
    ss_heal_solver *s[4];
    for (int k = 0; k < 4; k++) {
        int i = k % 2, j = k / 2;
        b[k] = ss_heal_grid_create(xs[i + 1] - xs[i] + 2, ys[j + 1] - ys[j] + 2, 9, 0.5, &err);
        assert_non_null(b[k]);
        cut(G, b[k], xs[i], ys[j]);
        const int goff[3] = {xs[i] - 1, ys[j] - 1, 0};
        s[k] = ss_heal_solver_create_sub(b[k], goff, gdim, p, SS_HEAL_EXPLICIT, dt, &err);
        assert_non_null(s[k]);
    }
    /* the split scheme's boxes span z (whole z line solves); a box larger than the grid */
    const int zoff[3] = {0, 0, 1}, small[3] = {5, 17, 9};
    assert_null(ss_heal_solver_create_sub(b[0], zoff, gdim, p, SS_HEAL_SPLIT, 0, &err));
    assert_null(ss_heal_solver_create_sub(b[0], zoff, small, p, SS_HEAL_EXPLICIT, dt, &err));
    int steps = tu_quick() ? 5 : 30;
    for (int n = 0; n < steps; n++) {
        assert_int_equal(ss_heal_step(S, G, &err), SS_OK);
        for (int k = 0; k < 4; k++) {
            int i = k % 2, j = k / 2;
            assert_int_equal(ss_heal_step(s[k], b[k], &err), SS_OK);
            /* every owned cell equals the whole grid's, bit for bit */
            for (int z = 0; z < 9; z++)
                for (int y = ys[j]; y < ys[j + 1]; y++)
                    for (int f = 0; f < SS_HEAL_NFIELDS; f++)
                        assert_memory_equal(b[k]->field[f] + ss_heal_idx(b[k], 1, y - ys[j] + 1, z),
                                            G->field[f] + ss_heal_idx(G, xs[i], y, z),
                                            (size_t)(xs[i + 1] - xs[i]) * sizeof(float));
            assert_true(b[k]->t_days == G->t_days);
            cut(G, b[k], xs[i], ys[j]); /* the halo exchange */
        }
    }
    for (int k = 0; k < 4; k++) {
        ss_heal_solver_free(s[k]);
        ss_heal_grid_free(b[k]);
    }
    ss_heal_solver_free(S);
    ss_heal_grid_free(G);
    ss_heal_params_free(p);
}

/* An uneven surface split in x (issue #8): one column raised 4 levels in one
 * box, a wound column whose capillary density rises with depth in the other.
 * Each column's bed window is its own, so the boxes step to the whole grid's
 * bits (a bound from the row's highest surface cut the wound column's window
 * in the whole grid but not in its box). */
static void test_subbox_uneven(void **state) {
    (void)state;
    ss_error err;
    ss_heal_params *p = ss_heal_params_preset("clean", &err);
    assert_non_null(p);
    const int nx = 14, ny = 5, nz = 20, zs = 7, xr = 10, gdim[3] = {14, 5, 20};
    ss_heal_grid *G = ss_heal_grid_create(nx, ny, nz, 0.25, &err);
    assert_non_null(G);
    assert_int_equal(ss_heal_grid_init(G, 2.0, 0.1, NULL, p, &err), SS_OK);
    for (int y = 1; y < ny - 1; y++) {
        for (int k = 1; k <= 4; k++) {
            G->cell[ss_heal_idx(G, xr, y, zs + k)] = G->cell[ss_heal_idx(G, xr, y, zs)];
            for (int f = 0; f < SS_HEAL_NFIELDS; f++)
                G->field[f][ss_heal_idx(G, xr, y, zs + k)] = G->field[f][ss_heal_idx(G, xr, y, zs)];
        }
        for (int z = 1; z <= zs; z++) {
            const size_t i = ss_heal_idx(G, 3, y, z);
            G->cell[i] = SS_CELL_WOUND;
            G->field[SS_HEAL_CAPILLARY][i] = zs - z < 2 ? 0.2f : 0.6f;
            G->field[SS_HEAL_PLASMA][i] = 1.0f;
        }
        G->field[SS_HEAL_EPITHELIUM][ss_heal_idx(G, 3, y, zs)] = 0.5f;
    }
    ss_heal_solver *S = ss_heal_solver_create(G, p, SS_HEAL_EXPLICIT, 0, &err);
    assert_non_null(S);
    const double dt = ss_heal_solver_dt(S);
    const int xs[3] = {0, 7, 14};
    ss_heal_grid *b[2];
    ss_heal_solver *s[2];
    for (int i = 0; i < 2; i++) {
        b[i] = ss_heal_grid_create(xs[i + 1] - xs[i] + 2, ny + 2, nz, 0.25, &err);
        assert_non_null(b[i]);
        cut(G, b[i], xs[i], 0);
        const int goff[3] = {xs[i] - 1, -1, 0};
        s[i] = ss_heal_solver_create_sub(b[i], goff, gdim, p, SS_HEAL_EXPLICIT, dt, &err);
        assert_non_null(s[i]);
    }
    for (int n = 0; n < 3; n++) {
        assert_int_equal(ss_heal_step(S, G, &err), SS_OK);
        for (int i = 0; i < 2; i++) {
            assert_int_equal(ss_heal_step(s[i], b[i], &err), SS_OK);
            for (int z = 0; z < nz; z++)
                for (int y = 0; y < ny; y++)
                    for (int f = 0; f < SS_HEAL_NFIELDS; f++)
                        assert_memory_equal(b[i]->field[f] + ss_heal_idx(b[i], 1, y + 1, z),
                                            G->field[f] + ss_heal_idx(G, xs[i], y, z),
                                            (size_t)(xs[i + 1] - xs[i]) * sizeof(float));
            cut(G, b[i], xs[i], 0);
        }
    }
    for (int i = 0; i < 2; i++) {
        ss_heal_solver_free(s[i]);
        ss_heal_grid_free(b[i]);
    }
    ss_heal_solver_free(S);
    ss_heal_grid_free(G);
    ss_heal_params_free(p);
}

static void test_split_phases(void **state) {
    (void)state;
    ss_error err;
    ss_heal_params *p = ss_heal_params_preset("scab", &err);
    ss_heal_grid *a = problem(p, 20, 16, 9), *b = problem(p, 20, 16, 9);
    ss_heal_solver *sa = ss_heal_solver_create(a, p, SS_HEAL_SPLIT, 0, &err);
    ss_heal_solver *sb = ss_heal_solver_create(b, p, SS_HEAL_SPLIT, 0, &err);
    assert_non_null(sa);
    assert_non_null(sb);
    assert_int_equal(ss_heal_solver_nslots(sb), 2);
    assert_non_null(ss_heal_solver_multipliers(sb, 1));
    assert_null(ss_heal_solver_multipliers(sb, 2));
    for (int n = 0; n < 8; n++) {
        assert_int_equal(ss_heal_step(sa, a, &err), SS_OK);
        for (int ph = 0; ph < 3; ph++) assert_int_equal(ss_heal_step_phase(sb, b, ph, &err), SS_OK);
    }
    size_t nc = (size_t)a->nx * a->ny * a->nz;
    for (int f = 0; f < SS_HEAL_NFIELDS; f++)
        assert_memory_equal(a->field[f], b->field[f], nc * sizeof(float));
    assert_true(a->t_days == b->t_days && a->step == b->step);
    assert_int_equal(ss_heal_step_phase(sb, b, 3, &err), SS_ERR_INPUT);
    ss_heal_solver *se = ss_heal_solver_create(a, p, SS_HEAL_EXPLICIT, 0, &err);
    assert_int_equal(ss_heal_step_phase(se, a, 0, &err), SS_ERR_INPUT);
    ss_heal_solver_free(se);
    ss_heal_solver_free(sa);
    ss_heal_solver_free(sb);
    ss_heal_grid_free(a);
    ss_heal_grid_free(b);
    ss_heal_params_free(p);
}

/* The explicit step in two parts (the MPI driver's overlap of the halo
 * exchange): part 1 never reads the outer shell (it holds garbage meanwhile,
 * as a halo in flight), and parts 1 + 2 give ss_heal_step's bits. */
static void shell_set(ss_heal_grid *g, float *save, int restore, int ring) {
    size_t k = 0;
    for (int f = 0; f < SS_HEAL_NFIELDS; f++)
        for (int z = 0; z < g->nz; z++)
            for (int y = 0; y < g->ny; y++)
                for (int x = 0; x < g->nx; x++) {
                    /* the shell planes of the faces in `ring` (-x, +x, -y, +y, -z, +z) */
                    const int on = (x == 0 && (ring & 1)) || (x == g->nx - 1 && (ring & 2)) ||
                                   (y == 0 && (ring & 4)) || (y == g->ny - 1 && (ring & 8)) ||
                                   (z == 0 && (ring & 16)) || (z == g->nz - 1 && (ring & 32));
                    if (!on) continue;
                    float *v = g->field[f] + ss_heal_idx(g, x, y, z);
                    if (restore) {
                        *v = save[k++];
                    } else {
                        save[k++] = *v;
                        *v = 1e30f;
                    }
                }
}

static void test_explicit_parts(void **state) {
    (void)state;
    ss_error err;
    ss_heal_params *p = ss_heal_params_preset("scab", &err);
    ss_heal_grid *a = problem(p, 21, 16, 9), *b = problem(p, 21, 16, 9);
    ss_heal_solver *sa = ss_heal_solver_create(a, p, SS_HEAL_EXPLICIT, 0, &err);
    ss_heal_solver *sb = ss_heal_solver_create(b, p, SS_HEAL_EXPLICIT, 0, &err);
    assert_non_null(sa);
    assert_non_null(sb);
    float *save = malloc((size_t)SS_HEAL_NFIELDS * 2 * (21 * 16 + 21 * 9 + 16 * 9) * sizeof(float));
    assert_non_null(save);
    for (int n = 0; n < 30; n++) {
        /* every face in flight, then only some (+x, -y, +z) */
        const int ring = n < 15 ? 63 : 2 | 4 | 32;
        assert_int_equal(ss_heal_step(sa, a, &err), SS_OK);
        shell_set(b, save, 0, ring);
        assert_int_equal(ss_heal_step_part(sb, b, 1, ring, &err), SS_OK);
        shell_set(b, save, 1, ring);
        assert_int_equal(ss_heal_step_part(sb, b, 2, ring, &err), SS_OK);
        shell_set(b, save, 1, ring); /* part 1 copied the garbage shell: the next halo */
    }
    size_t nc = (size_t)a->nx * a->ny * a->nz;
    for (int f = 0; f < SS_HEAL_NFIELDS; f++)
        assert_memory_equal(a->field[f], b->field[f], nc * sizeof(float));
    assert_true(a->t_days == b->t_days && a->step == b->step && a->step == 30);
    assert_int_equal(ss_heal_step_part(sb, b, 0, 63, &err), SS_ERR_INPUT);
    ss_heal_solver *ss = ss_heal_solver_create(a, p, SS_HEAL_SPLIT, 0, &err);
    assert_int_equal(ss_heal_step_part(ss, a, 1, 63, &err), SS_ERR_INPUT);
    ss_heal_solver_free(ss);
    free(save);
    ss_heal_solver_free(sa);
    ss_heal_solver_free(sb);
    ss_heal_grid_free(a);
    ss_heal_grid_free(b);
    ss_heal_params_free(p);
}

/* a closed box mesh from (x0, y0, z0) to (x1, y1, z1), mm */
static void cube(ss_tri_mesh *m, const double a[3], const double b[3]) {
    static const int T[36] = {0, 3, 2, 0, 2, 1, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                              1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
    memset(m, 0, sizeof *m);
    m->nverts = 8;
    m->ntris = 12;
    m->v = malloc(24 * sizeof *m->v);
    m->tri = malloc(36 * sizeof *m->tri);
    assert_non_null(m->v);
    assert_non_null(m->tri);
    for (int k = 0; k < 8; k++) {
        m->v[3 * k] = (k == 1 || k == 2 || k == 5 || k == 6) ? b[0] : a[0];
        m->v[3 * k + 1] = (k == 2 || k == 3 || k == 6 || k == 7) ? b[1] : a[1];
        m->v[3 * k + 2] = k >= 4 ? b[2] : a[2];
    }
    memcpy(m->tri, T, sizeof T);
}

/* The box at lo (whole-grid cell of the box's (0,0,0); may be -1 or reach
 * past the grid: a halo) of size n, built from mask m (n cells), equals G's
 * cells and fields inside the grid and is BOUND with zero fields outside. */
static void check_box(const ss_heal_grid *G, const ss_heal_params *p, const int lo[3],
                      const int n[3], const uint8_t *m, double top) {
    ss_error err;
    ss_heal_grid *b = ss_heal_grid_create(n[0], n[1], n[2], G->dx_mm, &err);
    assert_non_null(b);
    const int gd[3] = {G->nx, G->ny, G->nz};
    assert_int_equal(ss_heal_grid_init_box(b, lo, gd, top, 0.1, m, p, &err), SS_OK);
    for (int z = 0; z < n[2]; z++)
        for (int y = 0; y < n[1]; y++)
            for (int x = 0; x < n[0]; x++) {
                const int X = x + lo[0], Y = y + lo[1], Z = z + lo[2];
                const size_t c = ss_heal_idx(b, x, y, z);
                if (X < 0 || Y < 0 || Z < 0 || X >= G->nx || Y >= G->ny || Z >= G->nz) {
                    assert_int_equal(b->cell[c], SS_CELL_BOUND);
                    for (int f = 0; f < SS_HEAL_NFIELDS; f++) assert_true(b->field[f][c] == 0.0f);
                    continue;
                }
                const size_t C = ss_heal_idx(G, X, Y, Z);
                assert_int_equal(b->cell[c], G->cell[C]);
                for (int f = 0; f < SS_HEAL_NFIELDS; f++)
                    assert_memory_equal(&b->field[f][c], &G->field[f][C], sizeof(float));
            }
    ss_heal_grid_free(b);
}

static void test_box_setup(void **state) {
    (void)state;
    ss_error err;
    ss_heal_params *p = ss_heal_params_preset("scab", &err);
    const int gd[3] = {23, 17, 9};
    const double top = 3.5;
    /* boxes with halos, past the grid's edges too, and one of the whole grid */
    const int boxes[][6] = {{-1, -1, 0, 13, 10, 9},
                            {10, 7, -1, 15, 12, 7},
                            {5, -1, 3, 3, 19, 7},
                            {21, 15, 7, 3, 3, 3},
                            {-1, -1, -1, 25, 19, 11}};
    /* the built-in square: column ranges expanded per box */
    ss_heal_grid *G = ss_heal_grid_create(gd[0], gd[1], gd[2], 0.5, &err);
    uint8_t *w = ss_heal_wound_box(G, top, 6.0, 4.0, 1.0, &err);
    assert_non_null(w);
    assert_int_equal(ss_heal_grid_init(G, top, 0.1, w, p, &err), SS_OK);
    int32_t *cols = ss_heal_wound_columns_box(gd[0], gd[1], gd[2], 0.5, top, 6.0, 4.0, 1.0, &err);
    assert_non_null(cols);
    for (size_t b = 0; b < sizeof boxes / sizeof *boxes; b++) {
        uint8_t *m = ss_heal_wound_columns_expand(cols, gd, boxes[b], boxes[b] + 3, &err);
        assert_non_null(m);
        check_box(G, p, boxes[b], boxes[b] + 3, m, top);
        free(m);
    }
    free(cols);
    free(w);
    /* a mesh voxelised per box: the same voxels, the counts add up */
    ss_tri_mesh mesh;
    const double a[3] = {2.2, 1.9, 1.6}, bb[3] = {8.1, 6.3, 3.4};
    cube(&mesh, a, bb);
    size_t all = 0;
    w = ss_heal_voxelise_mesh(&mesh, gd[0], gd[1], gd[2], 0.5, &all, &err);
    assert_non_null(w);
    assert_true(all > 0);
    assert_int_equal(ss_heal_grid_init(G, top, 0.1, w, p, &err), SS_OK);
    size_t parts = 0;
    for (int zb = 0; zb < 2; zb++) /* 4 boxes that tile the grid: their counts add up */
        for (int xb = 0; xb < 2; xb++) {
            const int lo[3] = {xb ? 9 : 0, 0, zb ? 4 : 0},
                      n[3] = {xb ? gd[0] - 9 : 9, gd[1], zb ? gd[2] - 4 : 4};
            size_t c = 0;
            uint8_t *m = ss_heal_voxelise_mesh_box(&mesh, gd, lo, n, 0.5, &c, &err);
            assert_non_null(m);
            parts += c;
            free(m);
        }
    assert_int_equal(parts, all);
    for (size_t b = 0; b < sizeof boxes / sizeof *boxes; b++) {
        size_t c;
        uint8_t *m = ss_heal_voxelise_mesh_box(&mesh, gd, boxes[b], boxes[b] + 3, 0.5, &c, &err);
        assert_non_null(m);
        check_box(G, p, boxes[b], boxes[b] + 3, m, top);
        free(m);
    }
    free(w);
    ss_tri_mesh_free(&mesh);
    /* an empty box runs only the checks: a skin surface too high is refused */
    ss_heal_grid probe = *G;
    probe.nx = probe.ny = probe.nz = 0;
    const int zero[3] = {0, 0, 0};
    assert_int_equal(ss_heal_grid_init_box(&probe, zero, gd, 4.4, 0.1, NULL, p, &err),
                     SS_ERR_INPUT);
    assert_int_equal(ss_heal_grid_init_box(&probe, zero, gd, top, 0.1, NULL, p, &err), SS_OK);
    ss_heal_grid_free(G);
    ss_heal_params_free(p);
}

static void test_surface_parts(void **state) {
    (void)state;
    ss_error err;
    ss_heal_params *p = ss_heal_params_preset("scab", &err);
    ss_heal_grid *g = problem(p, 23, 17, 9);
    run(g, p, SS_HEAL_EXPLICIT, 40);
    const size_t nc = (size_t)g->nx * g->ny;
    float *vf = malloc(2 * nc * sizeof *vf), *img = malloc(nc * sizeof *img);
    assert_non_null(vf);
    assert_non_null(img);
    for (int f = 0; f < SS_HEAL_NFIELDS; f++)
        for (int mode = SS_SURFACE_TOP; mode <= SS_SURFACE_LAYER; mode++) {
            ss_image *whole = ss_heal_surface_map(g, f, (ss_heal_surface_mode)mode, &err);
            assert_non_null(whole);
            /* three slices of levels, top down, as a stack of boxes scans them */
            memset(vf, 0, 2 * nc * sizeof *vf);
            const int cut[4] = {9, 7, 3, 0};
            for (int k = 0; k < 3; k++)
                ss_heal_surface_scan(g, f, (ss_heal_surface_mode)mode, cut[k + 1], cut[k], 0, g->nz,
                                     vf, vf + nc);
            ss_heal_surface_image(vf, g->nx, g->ny, img);
            assert_memory_equal(img, whole->data, nc * sizeof *img);
            ss_image_free(whole);
        }
    free(vf);
    free(img);
    ss_heal_grid_free(g);
    ss_heal_params_free(p);
}

/* A box written straight from a grid with a halo is the file of a grid of
 * just those cells (the MPI driver's snapshot pieces). */
static void test_vti_box(void **state) {
    (void)state;
    ss_error err;
    ss_heal_params *p = ss_heal_params_preset("scab", &err);
    ss_heal_grid *g = problem(p, 23, 17, 9);
    run(g, p, SS_HEAL_EXPLICIT, 5);
    const int box[6] = {4, 3, 1, 11, 9, 6}, off[3] = {3, 2, 0}, whole[3] = {30, 20, 9};
    ss_heal_grid *c = ss_heal_grid_create(box[3], box[4], box[5], g->dx_mm, &err);
    assert_non_null(c);
    c->t_days = g->t_days;
    double cd[11 * 9];
    for (int z = 0; z < box[5]; z++)
        for (int y = 0; y < box[4]; y++)
            for (int x = 0; x < box[3]; x++) {
                const size_t i = ss_heal_idx(c, x, y, z),
                             j = ss_heal_idx(g, box[0] + x, box[1] + y, box[2] + z);
                c->cell[i] = g->cell[j];
                for (int f = 0; f < SS_HEAL_NFIELDS; f++) c->field[f][i] = g->field[f][j];
                cd[y * box[3] + x] = x - 0.25 * y;
            }
    char *dir = tu_tmpdir("vtibox"), a[512], b[512];
    snprintf(a, sizeof a, "%s/box.vti", dir);
    snprintf(b, sizeof b, "%s/copy.vti", dir);
    assert_int_equal(ss_heal_vti_write_box(a, g, box, off, whole, cd, &err), SS_OK);
    assert_int_equal(ss_heal_vti_write_piece_all(b, c, off, whole, 0, NULL, NULL, cd, &err), SS_OK);
    size_t na = 0, nb = 0;
    char *ta = ss_read_file(a, &na, &err), *tb = ss_read_file(b, &nb, &err);
    assert_non_null(ta);
    assert_non_null(tb);
    assert_int_equal(na, nb);
    assert_memory_equal(ta, tb, na);
    const int outside[6] = {20, 3, 1, 4, 9, 6};
    assert_int_equal(ss_heal_vti_write_box(a, g, outside, off, whole, NULL, &err), SS_ERR_INPUT);
    free(ta);
    free(tb);
    free(dir);
    ss_heal_grid_free(c);
    ss_heal_grid_free(g);
    ss_heal_params_free(p);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stats_parts),   cmocka_unit_test(test_subbox_explicit),
        cmocka_unit_test(test_split_phases),  cmocka_unit_test(test_explicit_parts),
        cmocka_unit_test(test_stack_columns), cmocka_unit_test(test_subbox_uneven),
        cmocka_unit_test(test_box_setup),     cmocka_unit_test(test_surface_parts),
        cmocka_unit_test(test_vti_box),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
