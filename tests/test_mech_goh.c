/* The hyperelastic GOH tissue (src/mech/hyper.c, stretch.c, mech_goh.c):
 * the solver's forces are its energy's gradient and its energy is objective;
 * the closed-form Cauchy stress agrees with the derivative of the energy; the
 * uniaxial stretch of a block of the solver's own mesh gives the analytic GOH
 * stress at every refinement and under a permutation of the axes, with
 * fibres at 30 degrees too (the block shears as the analytic state does); mu, k2 and
 * the fibre direction change it; and in a heal set-up the resting tension
 * makes a slit across the fibres gape more than one along them, and stitches
 * hold it; the fast solver ends where the plain one does; the heal run's
 * in-plane active law has its closed-form stress, consistent forces and a
 * tangent Newton converges with; its checkpoint state carries the
 * contraction lag and refuses a state written without it. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "testutil.h"
#include "skinsim/mech.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static ss_tetmesh *box_mesh(int n, double dx, double h) {
    uint8_t *in = malloc((size_t)n * n * n);
    memset(in, 1, (size_t)n * n * n);
    ss_error err;
    ss_tetmesh *m = ss_tetmesh_lattice(in, n, n, n, dx, h, &err);
    free(in);
    assert_non_null(m);
    return m;
}

/* a deterministic pseudo-random number in [-1, 1] */
static double rnd(unsigned *s) {
    *s = *s * 1103515245u + 12345u;
    return ((*s >> 8) & 0xffff) / 32767.5 - 1.0;
}

static void test_closed_form_cauchy(void **state) {
    (void)state;
    ss_mech_params p;
    ss_mech_params_default(&p);
    p.kappa = 0.1;
    p.k2 = 3;
    p.nfibres = 2;
    p.fibre[1][0] = 0;
    p.fibre[1][1] = 0.6;
    p.fibre[1][2] = 0.8;
    unsigned s = 7;
    for (int k = 0; k < 20; k++) {
        double F[9];
        for (int i = 0; i < 9; i++) F[i] = (i % 4 == 0) + 0.15 * rnd(&s);
        double P[9], sg[9],
            J = F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) +
                F[2] * (F[3] * F[7] - F[4] * F[6]);
        ss_hyper_goh_energy(&p, F, P);
        ss_hyper_goh_cauchy(&p, F, sg);
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double c = (P[3 * i] * F[3 * j] + P[3 * i + 1] * F[3 * j + 1] +
                            P[3 * i + 2] * F[3 * j + 2]) /
                           J;
                assert_float_equal(c, sg[3 * i + j], 1e-9 * (1 + fabs(c)));
            }
        /* P is the derivative of W (central differences) */
        for (int i = 0; i < 9; i++) {
            double Fp[9], Fm[9], h = 1e-6;
            memcpy(Fp, F, sizeof Fp);
            memcpy(Fm, F, sizeof Fm);
            Fp[i] += h;
            Fm[i] -= h;
            double d =
                (ss_hyper_goh_energy(&p, Fp, NULL) - ss_hyper_goh_energy(&p, Fm, NULL)) / (2 * h);
            assert_float_equal(d, P[i], 1e-5 * (1 + fabs(P[i])));
        }
    }
}

/* The tets' forces of H against central differences of its energy (every
 * stride-th coordinate), then objectivity: with the nodes rotated by R the
 * energy is unchanged and the forces rotate with them. Leaves x rotated. */
static void check_forces_objective(ss_hyper *H, int nn, int stride, const double *R) {
    double *x = ss_hyper_x(H);
    double *f = malloc(3 * (size_t)nn * sizeof(double)),
           *f1 = malloc(3 * (size_t)nn * sizeof(double));
    assert_non_null(f);
    assert_non_null(f1);
    ss_hyper_tet_forces(H, f);
    for (int k = 0; k < 3 * nn; k += stride) {
        double x0 = x[k], h = 1e-6;
        x[k] = x0 + h;
        double ep = ss_hyper_energy(H);
        x[k] = x0 - h;
        double em = ss_hyper_energy(H);
        x[k] = x0;
        assert_float_equal(-(ep - em) / (2 * h), f[k], 1e-5 * (1 + fabs(f[k])));
    }
    double E0 = ss_hyper_energy(H);
    for (int i = 0; i < nn; i++) {
        double y[3];
        for (int d = 0; d < 3; d++)
            y[d] = R[3 * d] * x[3 * i] + R[3 * d + 1] * x[3 * i + 1] + R[3 * d + 2] * x[3 * i + 2];
        memcpy(x + 3 * i, y, sizeof y);
    }
    assert_float_equal(ss_hyper_energy(H), E0, 1e-10 * fabs(E0));
    ss_hyper_tet_forces(H, f1);
    for (int i = 0; i < nn; i++)
        for (int d = 0; d < 3; d++) {
            double rf =
                R[3 * d] * f[3 * i] + R[3 * d + 1] * f[3 * i + 1] + R[3 * d + 2] * f[3 * i + 2];
            assert_float_equal(f1[3 * i + d], rf, 1e-9 * (1 + fabs(rf)));
        }
    free(f);
    free(f1);
}

/* forces = -dE/dx by central differences; a rigid rotation keeps the
 * energy and rotates the forces; growth, active stress and fibres on */
static void test_forces_objective(void **state) {
    (void)state;
    ss_mech_params p;
    ss_mech_params_default(&p);
    p.kappa = 0.05;
    p.fibre[0][0] = 0.8;
    p.fibre[0][1] = 0.6;
    ss_tetmesh *m = box_mesh(4, 0.5, 1.0);
    ss_error err;
    ss_hyper *H = ss_hyper_create(m, &p, &err);
    assert_non_null(H);
    const int nn = ss_hyper_nodes(H), nt = ss_hyper_tets(H);
    double *G = ss_hyper_growth(H), *act = ss_hyper_active(H);
    unsigned s = 3;
    for (int t = 0; t < nt; t++) {
        for (int i = 0; i < 9; i++) G[9 * t + i] = (i % 4 == 0) + 0.05 * rnd(&s);
        act[t] = 2.0 * (1 + rnd(&s));
    }
    double *x = ss_hyper_x(H);
    for (int i = 0; i < 3 * nn; i++) x[i] = m->x[i] * (1 + (i % 3 == 0) * 0.12) + 0.03 * rnd(&s);
    /* rotate everything by 40 degrees about (1, 2, 2)/3 */
    double a = 40 * M_PI / 180, u[3] = {1 / 3.0, 2 / 3.0, 2 / 3.0}, R[9];
    double c = cos(a), sn = sin(a);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double e = 0;
            if ((i + 1) % 3 == j) e = -u[3 - i - j];
            if ((j + 1) % 3 == i) e = u[3 - i - j];
            R[3 * i + j] = c * (i == j) + (1 - c) * u[i] * u[j] + sn * e;
        }
    check_forces_objective(H, nn, 7, R);
    ss_hyper_free(H);
    ss_tetmesh_free(m);
}

static ss_mech_stretch_result stretch(const ss_mech_params *p, double lam, int axis,
                                      const double fib[3], double h) {
    ss_mech_stretch_config c;
    ss_mech_stretch_config_default(&c);
    c.stretch = lam;
    c.axis = axis;
    memcpy(c.fibre, fib, sizeof c.fibre);
    c.tet_size_mm = h;
    c.increments = 5;
    ss_mech_stretch_result r;
    ss_error err;
    assert_int_equal(ss_mech_stretch(p, &c, &r, &err), SS_OK);
    assert_true(r.converged);
    return r;
}

static void test_stretch_analytic(void **state) {
    (void)state;
    ss_mech_params p;
    ss_mech_params_default(&p);
    const double fx[3] = {1, 0, 0}, fy[3] = {0, 1, 0}, fz[3] = {0, 0, 1};
    /* refinement: 48, 384, 1296 tets */
    const double hs[3] = {2.0, 1.0, 2.0 / 3.0};
    for (int k = 0; k < (tu_quick() ? 2 : 3); k++) {
        ss_mech_stretch_result r = stretch(&p, 1.1, 0, fx, hs[k]);
        print_message("h %.3f mm, %d tets: %.9f kPa, analytic %.9f kPa\n", hs[k], r.tets,
                      r.stress_kpa, r.analytic_stress_kpa);
        assert_float_equal(r.stress_kpa, r.analytic_stress_kpa, 1e-6 * r.analytic_stress_kpa);
        assert_float_equal(r.lateral_stretch[0], r.analytic_lateral[0], 1e-6);
    }
    /* the closed form (incompressible limit check of the analytic solver):
     * with K_bulk large the lateral stretches are 1/sqrt(lambda) for fibres
     * along the axis and the stress is mu (l^2 - 1/l) + 2 l^2 psi'(E) */
    {
        ss_mech_params q = p;
        q.K_bulk = 1e6;
        double n[3] = {1, 0, 0}, sg, lat[2], l = 1.1;
        assert_int_equal(ss_mech_uniaxial_analytic(&q, n, l, &sg, lat, NULL, NULL), SS_OK);
        double E = l * l - 1,
               ex = q.mu * (l * l - 1 / l) + 2 * l * l * q.k1_goh * E * exp(q.k2 * E * E);
        assert_float_equal(sg, ex, 1e-3 * ex);
        assert_float_equal(lat[0], 1 / sqrt(l), 1e-5);
    }
    ss_mech_stretch_result along = stretch(&p, 1.1, 0, fx, 1.0);
    /* objectivity: the same test along y and z with the fibres turned with it */
    ss_mech_stretch_result ry = stretch(&p, 1.1, 1, fy, 1.0), rz = stretch(&p, 1.1, 2, fz, 1.0);
    assert_float_equal(ry.stress_kpa, along.stress_kpa, 1e-8 * along.stress_kpa);
    assert_float_equal(rz.stress_kpa, along.stress_kpa, 1e-8 * along.stress_kpa);
    /* across the fibres: the fibres are compressed and bear nothing */
    ss_mech_stretch_result across = stretch(&p, 1.1, 0, fy, 1.0);
    assert_float_equal(across.stress_kpa, across.analytic_stress_kpa,
                       1e-6 * across.analytic_stress_kpa);
    assert_true(along.stress_kpa > 5 * across.stress_kpa);
    /* mu and k2 matter */
    ss_mech_params q = p;
    q.mu = 30;
    ss_mech_stretch_result rmu = stretch(&q, 1.1, 0, fy, 1.0);
    assert_true(rmu.stress_kpa > 1.5 * across.stress_kpa);
    assert_float_equal(rmu.stress_kpa, rmu.analytic_stress_kpa, 1e-6 * rmu.analytic_stress_kpa);
    q = p;
    q.k2 = 10;
    ss_mech_stretch_result rk2 = stretch(&q, 1.1, 0, fx, 1.0);
    assert_true(rk2.stress_kpa > 1.2 * along.stress_kpa);
    assert_float_equal(rk2.stress_kpa, rk2.analytic_stress_kpa, 1e-6 * rk2.analytic_stress_kpa);
    /* compression too */
    ss_mech_stretch_result rc = stretch(&p, 0.9, 0, fx, 1.0);
    assert_true(rc.stress_kpa < 0);
    assert_float_equal(rc.stress_kpa, rc.analytic_stress_kpa, 1e-6 * fabs(rc.analytic_stress_kpa));
    /* the same answer on 1 and 2 threads, bit for bit */
    omp_set_num_threads(1);
    ss_mech_stretch_result r1 = stretch(&p, 1.1, 0, fx, 1.0);
    omp_set_num_threads(2);
    ss_mech_stretch_result r2 = stretch(&p, 1.1, 0, fx, 1.0);
    assert_memory_equal(&r1.stress_kpa, &r2.stress_kpa, sizeof(double));
}

/* fibres at 30 degrees to the axis: the dead-loaded block shears, and its
 * homogeneous state (F e_x = lambda e_x, lateral faces traction-free) is
 * what the analytic value solves, so the stress and the shear equal it at
 * every refinement; turned with the axis (y, fibres in y-z) the same */
static void test_stretch_oblique(void **state) {
    (void)state;
    ss_mech_params p;
    ss_mech_params_default(&p);
    const double f30[3] = {cos(M_PI / 6), sin(M_PI / 6), 0};
    const double hs[3] = {2.0, 1.0, 0.5};
    ss_mech_stretch_result r1 = {0};
    for (int k = 0; k < (tu_quick() ? 2 : 3); k++) {
        ss_mech_stretch_result r = stretch(&p, 1.2, 0, f30, hs[k]);
        print_message("30 deg, h %.2f mm: %.9f kPa, analytic %.9f; shear %.6f, analytic %.6f\n",
                      hs[k], r.stress_kpa, r.analytic_stress_kpa, r.shear[0], r.analytic_shear[0]);
        assert_float_equal(r.stress_kpa, r.analytic_stress_kpa, 1e-7 * r.analytic_stress_kpa);
        assert_float_equal(r.shear[0], r.analytic_shear[0], 1e-7);
        assert_float_equal(r.shear[1], 0, 1e-7);
        for (int d = 0; d < 2; d++)
            assert_float_equal(r.lateral_stretch[d], r.analytic_lateral[d], 1e-7);
        if (k == 1) r1 = r;
    }
    assert_true(r1.shear[0] < -0.2); /* the fibres turn towards the axis */
    /* softer than with the fibres along the axis, stiffer than across */
    const double fx[3] = {1, 0, 0}, fy[3] = {0, 1, 0};
    assert_true(r1.stress_kpa < stretch(&p, 1.2, 0, fx, 2.0).stress_kpa);
    assert_true(r1.stress_kpa > stretch(&p, 1.2, 0, fy, 2.0).stress_kpa);
    const double f30y[3] = {0, cos(M_PI / 6), sin(M_PI / 6)};
    ss_mech_stretch_result ry = stretch(&p, 1.2, 1, f30y, 1.0);
    assert_float_equal(ry.stress_kpa, r1.stress_kpa, 1e-8 * r1.stress_kpa);
    assert_float_equal(ry.shear[0], r1.shear[0], 1e-7);
}

/* The clean preset on a 20 x 20 x 4 mm block (0.5 mm voxels, skin top at
 * 3 mm) with a sx x sy mm wound 1 mm deep; *hp gets the parameters. */
static ss_heal_grid *slit_grid(double sx, double sy, ss_heal_params **hp) {
    ss_error err;
    *hp = ss_heal_params_preset("clean", &err);
    assert_non_null(*hp);
    ss_heal_grid *g = ss_heal_grid_create(40, 40, 8, 0.5, &err);
    assert_non_null(g);
    uint8_t *w = ss_heal_wound_box(g, 3.0, sx, sy, 1.0, &err);
    assert_non_null(w);
    assert_int_equal(ss_heal_grid_init(g, 3.0, 0.1, w, *hp, &err), SS_OK);
    free(w);
    return g;
}

/* a 20 x 20 x 4 mm block (0.5 mm voxels, skin top at 3 mm), a slit 2 mm x
 * 12 mm, 1 mm deep, along y (across the x fibres) or along x; returns the
 * outline area after the day-0 gape over the cut area */
static double gape(int along_x, const ss_mech_suture *sut, int nsut) {
    ss_error err;
    ss_heal_params *hp;
    ss_heal_grid *g = slit_grid(along_x ? 12.0 : 2.0, along_x ? 2.0 : 12.0, &hp);
    ss_mech_params p;
    ss_mech_params_default(&p);
    p.model = SS_MECH_MODEL_GOH;
    ss_mech *m = ss_mech_create(g, hp, &p, NULL, sut, nsut, &err);
    if (!m) fail_msg("%s", err.msg);
    ss_mech_stats st;
    ss_mech_stats_compute(m, &st);
    assert_int_equal(st.inverted_tets, 0);
    double r = st.outline_area_mm2 / st.initial_outline_area_mm2;
    ss_mech_free(m);
    ss_heal_grid_free(g);
    ss_heal_params_free(hp);
    return r;
}

/* The goh state carries the lagged active tension: it reads back whole, and
 * a goh state without it (written before tau_contract_goh) is refused with a
 * message that names the lag, not taken for another mesh. */
static void test_state_lag(void **state) {
    (void)state;
    ss_error err;
    ss_heal_params *hp;
    ss_heal_grid *g = slit_grid(2.0, 12.0, &hp);
    ss_mech_params p;
    ss_mech_params_default(&p);
    ss_mech *sp = ss_mech_create(g, hp, &p, NULL, NULL, 0, &err);
    if (!sp) fail_msg("%s", err.msg);
    p.model = SS_MECH_MODEL_GOH;
    ss_mech *m = ss_mech_create(g, hp, &p, NULL, NULL, 0, &err);
    if (!m) fail_msg("%s", err.msg);
    const ss_tetmesh *mesh = ss_mech_mesh(m);
    const size_t n = ss_mech_state_size(m), nn = (size_t)mesh->nnodes;
    /* springs state + G per tet + the lag per node */
    assert_int_equal(n, ss_mech_state_size(sp) + (9 * (size_t)mesh->ntets + nn) * sizeof(double));
    char *a = malloc(n), *b = malloc(n);
    assert_non_null(a);
    assert_non_null(b);
    ss_mech_state_get(m, a);
    assert_int_equal(ss_mech_state_set(m, a, n, &err), SS_OK);
    ss_mech_state_get(m, b);
    assert_memory_equal(a, b, n);
    assert_int_equal(ss_mech_state_set(m, a, n - nn * sizeof(double), &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "tau_contract_goh"));
    assert_int_equal(ss_mech_state_set(m, a, n - 1, &err), SS_ERR_INPUT);
    assert_null(strstr(err.msg, "tau_contract_goh"));
    free(a);
    free(b);
    ss_mech_free(m);
    ss_mech_free(sp);
    ss_heal_grid_free(g);
    ss_heal_params_free(hp);
}

static void test_resting_tension_gape(void **state) {
    (void)state;
    double across = gape(0, NULL, 0), along = gape(1, NULL, 0);
    ss_mech_suture sut[4];
    for (int i = 0; i < 4; i++) {
        double y = 6.5 + 2.3 * i;
        sut[i] = (ss_mech_suture){{8.0, y, 2.0}, {12.0, y, 2.0}, INFINITY};
    }
    double stitched = gape(0, sut, 4);
    print_message("outline / cut: across the fibres %.3f, along %.3f, across and stitched %.3f\n",
                  across, along, stitched);
    assert_true(across > 1.2);
    assert_true(across - 1 > 2 * (along - 1));
    assert_true(stitched - 1 < 0.5 * (across - 1));
}

/* A 4 x 4 x 2 mm block on a foundation, pre-stretched along fibres at 30
 * degrees and held by the dead load of its resting tension, pulled by an
 * active stress that grows over four solves (frames) in a patch at the top:
 * the fast solver (two-level preconditioner, tangent kept across iterations
 * and frames) ends every frame where the plain one (block-Jacobi, a fresh
 * tangent every iteration) does, and on 1 and 2 threads bit for bit. */
static ss_hyper *pulled_block(int fast, ss_tetmesh **mo) {
    enum { NX = 8, NZ = 4 };
    uint8_t in[NX * NX * NZ];
    memset(in, 1, sizeof in);
    ss_error err;
    ss_tetmesh *m = ss_tetmesh_lattice(in, NX, NX, NZ, 0.5, 0.5, &err);
    assert_non_null(m);
    ss_mech_params p;
    ss_mech_params_default(&p);
    p.fibre[0][0] = cos(M_PI / 6);
    p.fibre[0][1] = sin(M_PI / 6);
    p.fibre[0][2] = 0;
    ss_hyper *H = ss_hyper_create(m, &p, &err);
    assert_non_null(H);
    ss_hyper_set_fast(H, fast);
    const int nn = ss_hyper_nodes(H), nt = ss_hyper_tets(H);
    double *G = ss_hyper_growth(H), *anchor = ss_hyper_anchor(H);
    for (int t = 0; t < nt; t++)
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                G[9 * t + 3 * i + j] = (i == j) + (1 / 1.1 - 1) * p.fibre[0][i] * p.fibre[0][j];
    for (int i = 0; i < nn; i++) anchor[i] = m->x[3 * i + 2] < 1e-9 ? 2.0 : 0.02;
    double *f = malloc(3 * (size_t)nn * sizeof(double)), *load = ss_hyper_load(H);
    assert_non_null(f);
    ss_hyper_tet_forces(H, f);
    for (int i = 0; i < 3 * nn; i++) load[i] = -f[i];
    free(f);
    *mo = m;
    return H;
}

static void pull(ss_hyper *H, const ss_tetmesh *m, int frame) {
    double *act = ss_hyper_active(H);
    for (int t = 0; t < m->ntets; t++) {
        double c[3] = {0, 0, 0};
        for (int k = 0; k < 4; k++)
            for (int d = 0; d < 3; d++) c[d] += 0.25 * m->x[3 * m->tet[4 * t + k] + d];
        double r2 = (c[0] - 2) * (c[0] - 2) + (c[1] - 2) * (c[1] - 2);
        act[t] = r2 < 1.0 && c[2] > 1.0 ? 4.0 * frame : 0;
    }
}

static void test_fast_equals_plain(void **state) {
    (void)state;
    ss_tetmesh *mf, *mr;
    ss_hyper *Hf = pulled_block(1, &mf), *Hr = pulled_block(0, &mr);
    const int n3 = 3 * ss_hyper_nodes(Hf);
    ss_error err;
    int cg_fast = 0, cg_plain = 0;
    for (int fr = 1; fr <= 4; fr++) {
        ss_hyper_report rf, rr;
        pull(Hf, mf, fr);
        pull(Hr, mr, fr);
        omp_set_num_threads(2);
        assert_int_equal(ss_hyper_solve(Hf, 1e-8, 60, &rf, &err), SS_OK);
        assert_int_equal(ss_hyper_solve(Hr, 1e-8, 60, &rr, &err), SS_OK);
        assert_true(rf.converged && rr.converged);
        cg_fast += rf.cg;
        cg_plain += rr.cg;
        const double *xf = ss_hyper_x(Hf), *xr = ss_hyper_x(Hr), *X = ss_hyper_X(Hf);
        double du = 0, umax = 0;
        for (int i = 0; i < n3; i++) {
            du = fmax(du, fabs(xf[i] - xr[i]));
            umax = fmax(umax, fabs(xr[i] - X[i]));
        }
        print_message("frame %d: max |u| %.4g mm, fast - plain %.3g mm; CG %d vs %d\n", fr, umax,
                      du, rf.cg, rr.cg);
        assert_true(umax > 0.01);
        assert_true(du < 1e-5 * umax);
    }
    assert_true(cg_fast < cg_plain);
    ss_hyper_free(Hf);
    ss_hyper_free(Hr);
    ss_tetmesh_free(mf);
    ss_tetmesh_free(mr);
    /* thread counts: the fast path's four frames on 1 and on 2 threads */
    double *xs[2];
    for (int k = 0; k < 2; k++) {
        omp_set_num_threads(k + 1);
        ss_tetmesh *m;
        ss_hyper *H = pulled_block(1, &m);
        for (int fr = 1; fr <= 4; fr++) {
            pull(H, m, fr);
            assert_int_equal(ss_hyper_solve(H, 1e-8, 60, NULL, &err), SS_OK);
        }
        xs[k] = malloc((size_t)n3 * sizeof(double));
        assert_non_null(xs[k]);
        memcpy(xs[k], ss_hyper_x(H), (size_t)n3 * sizeof(double));
        ss_hyper_free(H);
        ss_tetmesh_free(m);
    }
    assert_memory_equal(xs[0], xs[1], (size_t)n3 * sizeof(double));
    free(xs[0]);
    free(xs[1]);
    omp_set_num_threads(2);
}

/* the in-plane active law (ss_hyper_set_active_law, the heal run's): a
 * homogeneous deformation gives the closed-form Cauchy stress s p_cell(J_a
 * - 1) (J_a / J) (I - n n), n the current normal of the skin's plane (no
 * stress through the thickness); the forces are the energy's gradient and
 * objective; Newton with the law's tangent converges in a few iterations
 * and the fast solver ends where the plain one does */
static void test_active_law(void **state) {
    (void)state;
    ss_mech_params p;
    ss_mech_params_default(&p);
    p.mu = 0;
    p.K_bulk = 1e-9;
    p.k1_goh = 0;
    ss_tetmesh *m = box_mesh(3, 0.5, 1.0);
    ss_error err;
    ss_hyper *H = ss_hyper_create(m, &p, &err);
    assert_non_null(H);
    ss_hyper_set_active_law(H, 1);
    const int nn = ss_hyper_nodes(H), nt = ss_hyper_tets(H);
    double *act = ss_hyper_active(H), *x = ss_hyper_x(H);
    for (int t = 0; t < nt; t++) act[t] = 10.0;
    const double Fs[3][9] = {{1, 0, 0, 0, 1, 0, 0, 0, 1},
                             {1.1, 0.05, 0, 0, 1.2, 0, 0.02, 0, 0.9},
                             {0.8, 0, 0.1, 0.03, 0.85, 0, 0, 0.05, 1.3}};
    for (int k = 0; k < 3; k++) {
        const double *F = Fs[k];
        for (int i = 0; i < nn; i++)
            for (int d = 0; d < 3; d++)
                x[3 * i + d] = F[3 * d] * m->x[3 * i] + F[3 * d + 1] * m->x[3 * i + 1] +
                               F[3 * d + 2] * m->x[3 * i + 2];
        double a[3] = {F[0], F[3], F[6]}, b[3] = {F[1], F[4], F[7]};
        double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                       a[0] * b[1] - a[1] * b[0]};
        double Ja = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        double J = F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) +
                   F[2] * (F[3] * F[7] - F[4] * F[6]);
        double pc = ss_mech_pcell(&p, Ja - 1.0), sg[9];
        ss_hyper_mean_cauchy(H, sg, NULL);
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double e = 10.0 * pc * Ja / J * ((i == j) - c[i] * c[j] / (Ja * Ja));
                assert_float_equal(sg[3 * i + j], e, 1e-6 * (1 + fabs(e)));
            }
        if (k == 0) assert_float_equal(sg[0], 10.0 * ss_mech_pcell(&p, 0.0), 1e-9);
    }
    ss_hyper_free(H);
    /* forces, objectivity: growth, fibres, a varying amplitude, the law on */
    ss_mech_params_default(&p);
    p.fibre[0][0] = 0.8;
    p.fibre[0][1] = 0.6;
    H = ss_hyper_create(m, &p, &err);
    assert_non_null(H);
    ss_hyper_set_active_law(H, 1);
    double *G = ss_hyper_growth(H);
    act = ss_hyper_active(H);
    x = ss_hyper_x(H);
    unsigned s = 5;
    for (int t = 0; t < nt; t++) {
        for (int i = 0; i < 9; i++) G[9 * t + i] = (i % 4 == 0) + 0.05 * rnd(&s);
        act[t] = 20.0 * (1 + rnd(&s));
    }
    for (int i = 0; i < 3 * nn; i++) x[i] = m->x[i] * (1 - (i % 3 == 1) * 0.15) + 0.03 * rnd(&s);
    /* a rotation (orthonormal rows, det 1) */
    const double R[9] = {0.36, -0.48, 0.8, 0.8, 0.6, 0, -0.48, 0.64, 0.6};
    check_forces_objective(H, nn, 5, R);
    ss_hyper_free(H);
    ss_tetmesh_free(m);
    /* Newton: a pre-stretched block pulled in-plane in its centre, plain
     * (fresh tangent every iteration) and fast */
    ss_tetmesh *mf, *mr;
    ss_hyper *Hf = pulled_block(1, &mf), *Hr = pulled_block(0, &mr);
    ss_hyper_set_active_law(Hf, 1);
    ss_hyper_set_active_law(Hr, 1);
    const int n3 = 3 * ss_hyper_nodes(Hf);
    for (int fr = 1; fr <= 3; fr++) {
        ss_hyper_report rf, rr;
        pull(Hf, mf, 5 * fr);
        pull(Hr, mr, 5 * fr);
        assert_int_equal(ss_hyper_solve(Hf, 1e-8, 60, &rf, &err), SS_OK);
        assert_int_equal(ss_hyper_solve(Hr, 1e-8, 60, &rr, &err), SS_OK);
        assert_true(rf.converged && rr.converged);
        assert_true(rr.newton <= 12);
        const double *xf = ss_hyper_x(Hf), *xr = ss_hyper_x(Hr), *X = ss_hyper_X(Hf);
        double du = 0, umax = 0;
        for (int i = 0; i < n3; i++) {
            du = fmax(du, fabs(xf[i] - xr[i]));
            umax = fmax(umax, fabs(xr[i] - X[i]));
        }
        print_message("law frame %d: max |u| %.4g mm, fast - plain %.3g mm; Newton %d / %d\n", fr,
                      umax, du, rf.newton, rr.newton);
        assert_true(umax > 0.01);
        assert_true(du < 1e-5 * umax);
    }
    ss_hyper_free(Hf);
    ss_hyper_free(Hr);
    ss_tetmesh_free(mf);
    ss_tetmesh_free(mr);
}

/* ss_hyper_set_tolerant (the default; docs/mech.md, stop 38): the float
 * matrix of the CG's products, the predictor step from the last solve and
 * the end without an evaluation at a step under the tolerance change the bytes but not the result
 * beyond the Newton tolerance. The pulled block with the heal run's in-plane active law over six
 * frames whose pull grows and whose rest state takes in part of the contraction between frames (as
 * the heal frame's remodelling does), at the heal run's tolerance (1e-4 of the mean edge) and a
 * tight one (1e-6; below 1e-7 the exact path's line search reaches the rounding of the energy): the
 * displacement of the tolerant solver differs from the solver without those changes by less than
 * the tolerance times the displacement (2-norms), the predictor is taken from the second frame on,
 * and the tolerant path is bit-identical on 1 and 2 threads. */
static void grow_in(ss_hyper *H, const ss_tetmesh *m) {
    double *G = ss_hyper_growth(H);
    const double *act = ss_hyper_active(H);
    for (int t = 0; t < m->ntets; t++)
        if (act[t] > 0)
            for (int k = 0; k < 9; k++) G[9 * t + k] *= 0.995;
}

static double *tolerant_run(int tolerant, double tol, int *npred, double *unorm, int *n3o) {
    ss_tetmesh *m;
    ss_hyper *H = pulled_block(1, &m);
    ss_hyper_set_active_law(H, 1);
    ss_hyper_set_tolerant(H, tolerant);
    const int n3 = 3 * ss_hyper_nodes(H);
    ss_error err;
    *npred = 0;
    for (int fr = 1; fr <= 6; fr++) {
        ss_hyper_report r;
        pull(H, m, 3 * fr);
        assert_int_equal(ss_hyper_solve(H, tol, 60, &r, &err), SS_OK);
        assert_true(r.converged);
        *npred += r.predicted;
        grow_in(H, m);
    }
    double *x = malloc((size_t)n3 * sizeof(double)), u2 = 0;
    assert_non_null(x);
    memcpy(x, ss_hyper_x(H), (size_t)n3 * sizeof(double));
    for (int i = 0; i < n3; i++) u2 += (x[i] - ss_hyper_X(H)[i]) * (x[i] - ss_hyper_X(H)[i]);
    *unorm = sqrt(u2);
    *n3o = n3;
    ss_hyper_free(H);
    ss_tetmesh_free(m);
    return x;
}

static void test_tolerant_within_tolerance(void **state) {
    (void)state;
    const double tols[2] = {1e-4, 1e-6};
    for (int k = 0; k < 2; k++) {
        omp_set_num_threads(2);
        int pt, pe, p1, n3;
        double ut, ue, u1, d2 = 0;
        double *xt = tolerant_run(1, tols[k], &pt, &ut, &n3);
        double *xe = tolerant_run(0, tols[k], &pe, &ue, &n3);
        for (int i = 0; i < n3; i++) d2 += (xt[i] - xe[i]) * (xt[i] - xe[i]);
        print_message("tol %g: |u| %.4g mm, tolerant - exact %.3g mm (%.3g of |u|); predictor "
                      "taken %d times (exact path %d)\n",
                      tols[k], ue, sqrt(d2), sqrt(d2) / ue, pt, pe);
        assert_true(ue > 0.01);
        assert_true(sqrt(d2) < tols[k] * ue);
        assert_true(pt >= 3); /* of the five frames after the first */
        assert_int_equal(pe, 0);
        omp_set_num_threads(1);
        double *x1 = tolerant_run(1, tols[k], &p1, &u1, &n3);
        assert_memory_equal(x1, xt, (size_t)n3 * sizeof(double));
        free(x1);
        free(xt);
        free(xe);
    }
    omp_set_num_threads(2);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_closed_form_cauchy),
        cmocka_unit_test(test_forces_objective),
        cmocka_unit_test(test_stretch_analytic),
        cmocka_unit_test(test_stretch_oblique),
        cmocka_unit_test(test_resting_tension_gape),
        cmocka_unit_test(test_fast_equals_plain),
        cmocka_unit_test(test_active_law),
        cmocka_unit_test(test_state_lag),
        cmocka_unit_test(test_tolerant_within_tolerance),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
