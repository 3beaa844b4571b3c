/* Contraction mechanics (src/mech): the seed's constitutive laws, the
 * lattice tetrahedralisation and the mesh readers, the spring network's
 * invariants (rest stays at rest, rigid motions are force-free, damped
 * relaxation never gains energy), the B-spline coupling (partition of unity,
 * exact linear transfer both ways), a free block under uniform active
 * pressure shrinking by the strain the constitutive law predicts, and the
 * tet volume barrier (its force is its energy's gradient; a finer mesh under
 * the benchmark's load folds no tet). The coupled
 * healing scenarios are in test_mech_heal.c. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "testutil.h"
#include "skinsim/mech.h"

static ss_tetmesh *box_mesh(int nx, int ny, int nz, double dx, double h) {
    uint8_t *in = malloc((size_t)nx * ny * nz);
    memset(in, 1, (size_t)nx * ny * nz);
    ss_error err;
    ss_tetmesh *m = ss_tetmesh_lattice(in, nx, ny, nz, dx, h, &err);
    free(in);
    assert_non_null(m);
    return m;
}

static void test_pcell(void **state) {
    (void)state;
    ss_mech_params p;
    ss_mech_params_default(&p);
    double ts = p.p_max / p.K_act;
    /* the seed's cases: passive outside [theta1, theta2], p_max + K_pas theta at theta* */
    assert_float_equal(ss_mech_pcell(&p, p.theta1 - 0.1), p.K_pas * (p.theta1 - 0.1), 1e-12);
    assert_float_equal(ss_mech_pcell(&p, p.theta2 + 0.1), p.K_pas * (p.theta2 + 0.1), 1e-12);
    assert_float_equal(ss_mech_pcell(&p, p.theta1), p.K_pas * p.theta1, 1e-12);
    assert_float_equal(ss_mech_pcell(&p, p.theta2), p.K_pas * p.theta2, 1e-12);
    assert_float_equal(ss_mech_pcell(&p, ts), p.p_max + p.K_pas * ts, 1e-9);
    /* continuous and piecewise linear: midpoints are averages */
    for (int i = 0; i < 200; i++) {
        double a = -0.5 + i * 0.005, b = a + 0.001;
        double pa = ss_mech_pcell(&p, a), pb = ss_mech_pcell(&p, b);
        assert_true(fabs(pb - pa) < 0.001 * (p.K_act + p.K_pas) * 2);
    }
    /* explicit formula of the rising branch */
    double th = 0.5 * (p.theta1 + ts);
    double want =
        p.K_act * p.p_max / (p.K_act * p.theta1 - p.p_max) * (p.theta1 - th) + p.K_pas * th;
    assert_float_equal(ss_mech_pcell(&p, th), want, 1e-12);
}

static void test_goh(void **state) {
    (void)state;
    ss_mech_params p;
    ss_mech_params_default(&p);
    double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, pg, pf[2];
    ss_mech_goh_energy(&p, I, &pg, pf);
    assert_float_equal(pg, 0, 1e-15);
    assert_float_equal(pf[0], 0, 1e-15);
    /* uniaxial stretch lambda along the fibre, kappa = 0: E = lambda^2 - 1 */
    p.kappa = 0;
    double l = 1.1, C[9] = {l * l, 0, 0, 0, 1, 0, 0, 0, 1};
    ss_mech_goh_energy(&p, C, &pg, pf);
    double E = l * l - 1;
    assert_float_equal(pf[0], p.k1 / (2 * p.k2) * (exp(p.k2 * E * E) - 1), 1e-12);
    double J = l, I1b = (l * l + 2) * pow(J, -2.0 / 3.0);
    assert_float_equal(pg, 0.5 * p.mu * (I1b - 3) + 0.5 * p.K_bulk * (J - 1) * (J - 1), 1e-12);
    /* across the fibre at kappa = 0 the fibre does not feel it */
    double Cy[9] = {1, 0, 0, 0, l * l, 0, 0, 0, 1};
    ss_mech_goh_energy(&p, Cy, &pg, pf);
    assert_float_equal(pf[0], 0, 1e-15);
    /* isotropic dispersion: the same energy along x and y */
    p.kappa = 1.0 / 3.0;
    double fx[2], fy[2];
    ss_mech_goh_energy(&p, C, &pg, fx);
    ss_mech_goh_energy(&p, Cy, &pg, fy);
    assert_float_equal(fx[0], fy[0], 1e-12);
    /* spring energy: ground only at k1 = 0 gives exactly the linear strain theta/3 */
    p.k1 = 0;
    double ex[3] = {1, 0, 0};
    double sig = 2.0, th = sig / p.K_bulk;
    double psi = ss_mech_spring_energy_density(&p, sig, ex);
    assert_float_equal(psi, 0.5 * p.K_bulk * th * th, 1e-12);
    assert_float_equal(ss_mech_shortening(&p, psi), th / 3, 1e-12);
    /* fibres along x: a spring along x stores more energy than one along y (Fig. 7) */
    ss_mech_params_default(&p);
    p.kappa = 0;
    double ey[3] = {0, 1, 0};
    assert_true(ss_mech_spring_energy_density(&p, sig, ex) >
                1.5 * ss_mech_spring_energy_density(&p, sig, ey));
    /* isotropic dispersion: equal */
    p.kappa = 1.0 / 3.0;
    assert_float_equal(ss_mech_spring_energy_density(&p, sig, ex),
                       ss_mech_spring_energy_density(&p, sig, ey), 1e-12);
}

static void test_params(void **state) {
    (void)state;
    ss_mech_params p;
    ss_error err;
    ss_mech_params_default(&p);
    assert_int_equal(ss_mech_params_check(&p, &err), SS_OK);
    assert_int_equal(ss_mech_params_set_fibres(&p, "0,2,0:1,0,0", &err), SS_OK);
    assert_int_equal(p.nfibres, 2);
    assert_float_equal(p.fibre[0][1], 1.0, 1e-15);
    assert_int_equal(ss_mech_params_set_fibres(&p, "0,0,0", &err), SS_ERR_INPUT);
    assert_int_equal(ss_mech_params_set_fibres(&p, "1,0,0:-2,0,0", &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "parallel"));
    assert_int_equal(ss_mech_params_set_fibres(&p, "1,0", &err), SS_ERR_INPUT);
    assert_int_equal(ss_mech_params_set_fibres(&p, "1,nan,0", &err), SS_ERR_INPUT);
    ss_mech_params_default(&p);
    assert_int_equal(ss_mech_params_parse(&p,
                                          "{\"mechanics\":{\"K_m\":{\"value\":2,\"unit\":\"1\"}}}",
                                          "t.json", &err),
                     SS_OK);
    assert_float_equal(p.K_m, 2, 0);
    assert_int_equal(
        ss_mech_params_parse(&p, "{\"mechanics\":{\"K_act\":{\"value\":2}}}", "t.json", &err),
        SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "unit"));
    assert_int_equal(
        ss_mech_params_parse(&p, "{\"mechanics\":{\"bogus\":{\"value\":2,\"unit\":\"1\"}}}",
                             "t.json", &err),
        SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "bogus"));
    assert_int_equal(
        ss_mech_params_parse(&p, "{\"mechanics\":{\"kappa\":{\"value\":0.5,\"unit\":\"1\"}}}",
                             "t.json", &err),
        SS_ERR_INPUT);
    /* round trip through JSON */
    ss_mech_params_default(&p);
    p.K_m = 3.5;
    ss_mech_params_set_fibres(&p, "1,1,0:0,0,1", &err);
    char *js = ss_mech_params_to_json(&p);
    ss_mech_params q;
    ss_mech_params_default(&q);
    assert_int_equal(ss_mech_params_parse(&q, js, "rt", &err), SS_OK);
    free(js);
    assert_float_equal(q.K_m, 3.5, 0);
    assert_int_equal(q.nfibres, 2);
    assert_float_equal(q.fibre[0][0], sqrt(0.5), 1e-15);
    /* the shipped file parses and equals the built-in defaults */
    char path[4096];
    snprintf(path, sizeof path, "%s/data/heal/mechanics.json", SKINSIM_SOURCE_DIR);
    char *text = ss_read_file(path, NULL, &err);
    assert_non_null(text);
    ss_mech_params_default(&q);
    q.K_m = -1; /* must be overwritten */
    ss_mech_params d;
    ss_mech_params_default(&d);
    q = d;
    q.K_m = 0;
    assert_int_equal(ss_mech_params_parse(&q, text, path, &err), SS_OK);
    free(text);
    assert_memory_equal(&q, &d, sizeof d);
}

static void test_lattice(void **state) {
    (void)state;
    /* a 10 x 8 x 6 mm box of 0.5 mm voxels, 1 mm tets */
    ss_tetmesh *m = box_mesh(20, 16, 12, 0.5, 1.0);
    double vmax, vol = ss_tetmesh_volume(m, &vmax);
    assert_float_equal(vol, 10.0 * 8 * 6, 1e-9);
    assert_int_equal(m->ntets, 6 * 10 * 8 * 6);
    assert_true(vmax <= 1.0 / 6.0 + 1e-12);
    /* conforming: every face is shared by two tets except the boundary's,
     * whose area is the box surface */
    ss_springs *s = ss_springs_create(m, 1.0, NULL);
    assert_non_null(s);
    /* edges: 3 axis-parallel, 3 face diagonals, 1 body diagonal per cube, Euler-counted */
    long nodes = 11L * 9 * 7;
    assert_int_equal(m->nnodes, nodes);
    long ax = 10L * 9 * 7 + 11L * 8 * 7 + 11L * 9 * 6;
    long fd = 10L * 8 * 7 + 10L * 9 * 6 + 11L * 8 * 6, bd = 10L * 8 * 6;
    assert_int_equal(s->nsprings, ax + fd + bd);
    /* volume shares add up to the volume */
    double sv = 0;
    for (int i = 0; i < s->nsprings; i++) sv += s->vol[i];
    assert_float_equal(sv, vol, 1e-9);
    ss_springs_free(s);
    ss_tetmesh_free(m);
    /* bad input */
    ss_error err;
    uint8_t none[27] = {0};
    assert_null(ss_tetmesh_lattice(none, 3, 3, 3, 1.0, 1.0, &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    uint8_t one[27];
    memset(one, 1, 27);
    assert_null(ss_tetmesh_lattice(one, 3, 3, 3, 1.0, -1.0, &err));
    assert_null(ss_tetmesh_lattice(one, 3, 3, 3, 1.0, NAN, &err));
}

static void write_text(const char *path, const char *text) {
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static void test_readers(void **state) {
    (void)state;
    char *dir = tu_tmpdir("mech_readers");
    char a[4096], b[4096];
    ss_error err;
    /* one unit cube as 6 tets in TetGen (1-based, with a marker) and Gmsh form */
    ss_tetmesh *ref = box_mesh(1, 1, 1, 1.0, 1.0);
    snprintf(a, sizeof a, "%s/c.node", dir);
    snprintf(b, sizeof b, "%s/c.ele", dir);
    FILE *f = fopen(a, "w");
    fprintf(f, "# cube\n%d 3 0 1\n", ref->nnodes);
    for (int i = 0; i < ref->nnodes; i++)
        fprintf(f, "%d %g %g %g 0\n", i + 1, ref->x[3 * i], ref->x[3 * i + 1], ref->x[3 * i + 2]);
    fclose(f);
    f = fopen(b, "w");
    fprintf(f, "%d 4 0\n", ref->ntets);
    for (int t = 0; t < ref->ntets; t++) /* reversed orientation: the reader flips it */
        fprintf(f, "%d %d %d %d %d\n", t + 1, ref->tet[4 * t] + 1, ref->tet[4 * t + 1] + 1,
                ref->tet[4 * t + 3] + 1, ref->tet[4 * t + 2] + 1);
    fclose(f);
    ss_tetmesh *m = ss_tetmesh_read(a, &err);
    assert_non_null(m);
    assert_float_equal(ss_tetmesh_volume(m, NULL), 1.0, 1e-12);
    assert_int_equal(m->ntets, 6);
    ss_tetmesh_free(m);
    m = ss_tetmesh_read(b, &err); /* by the .ele name too */
    assert_non_null(m);
    ss_tetmesh_free(m);
    snprintf(a, sizeof a, "%s/c.msh", dir);
    f = fopen(a, "w");
    fprintf(f, "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n%d\n", ref->nnodes);
    for (int i = 0; i < ref->nnodes; i++) /* sparse ids */
        fprintf(f, "%d %g %g %g\n", 10 + 2 * i, ref->x[3 * i], ref->x[3 * i + 1],
                ref->x[3 * i + 2]);
    fprintf(f, "$EndNodes\n$Elements\n%d\n1 15 2 0 1 10\n", ref->ntets + 1);
    for (int t = 0; t < ref->ntets; t++)
        fprintf(f, "%d 4 2 0 1 %d %d %d %d\n", t + 2, 10 + 2 * ref->tet[4 * t],
                10 + 2 * ref->tet[4 * t + 1], 10 + 2 * ref->tet[4 * t + 2],
                10 + 2 * ref->tet[4 * t + 3]);
    fprintf(f, "$EndElements\n");
    fclose(f);
    m = ss_tetmesh_read(a, &err);
    assert_non_null(m);
    assert_float_equal(ss_tetmesh_volume(m, NULL), 1.0, 1e-12);
    ss_tetmesh_free(m);
    /* malformed inputs name the file */
    static const char *bad_msh[] = {
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n",
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 "
        "1\n$EndNodes\n$Elements\n1\n1 4 0 1 2 3 9\n$EndElements\n",
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 2 0 "
        "0\n$EndNodes\n$Elements\n1\n1 4 0 1 2 3 4\n$EndElements\n",
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 x 0\n",
        "garbage",
    };
    for (size_t i = 0; i < sizeof bad_msh / sizeof *bad_msh; i++) {
        write_text(a, bad_msh[i]);
        err.msg[0] = 0;
        assert_null(ss_tetmesh_read(a, &err));
        assert_int_equal(err.code, SS_ERR_INPUT);
        assert_non_null(strstr(err.msg, "c.msh"));
    }
    snprintf(a, sizeof a, "%s/missing.msh", dir);
    assert_null(ss_tetmesh_read(a, &err));
    snprintf(a, sizeof a, "%s/c.obj", dir);
    assert_null(ss_tetmesh_read(a, &err));
    /* tetgen: only where installed */
    snprintf(a, sizeof a, "%s/c.off", dir);
    write_text(a, "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n");
    m = ss_tetmesh_tetgen(a, 0.01, &err);
    if (m) {
        assert_float_equal(ss_tetmesh_volume(m, NULL), 1.0 / 6.0, 1e-9);
        double vmax;
        ss_tetmesh_volume(m, &vmax);
        assert_true(vmax <= 0.01 + 1e-12);
        ss_tetmesh_free(m);
    } else {
        assert_int_equal(err.code, SS_ERR_INPUT);
    }
    ss_tetmesh_free(ref);
    tu_rmtree(dir);
    free(dir);
}

static double max_force(ss_springs *s) {
    double *f = malloc(3 * (size_t)s->nnodes * sizeof(double)), mx = 0;
    ss_springs_forces(s, f);
    for (int i = 0; i < 3 * s->nnodes; i++) mx = fmax(mx, fabs(f[i]));
    free(f);
    return mx;
}

static void test_springs_rest_rigid(void **state) {
    (void)state;
    ss_tetmesh *m = box_mesh(6, 5, 4, 1.0, 1.0);
    ss_springs *s = ss_springs_create(m, 100.0, NULL);
    assert_true(max_force(s) < 1e-12);
    int conv;
    int it = ss_springs_relax(s, 1e-9, 50, &conv);
    assert_true(conv);
    assert_int_equal(it, 2);
    for (int i = 0; i < 3 * s->nnodes; i++) assert_true(s->x[i] == s->X[i]);
    /* rigid motion: rotation about an arbitrary axis plus a translation */
    double ax[3] = {0.3, -0.5, 0.8}, an = sqrt(0.09 + 0.25 + 0.64), th = 0.7;
    for (int d = 0; d < 3; d++) ax[d] /= an;
    double c = cos(th), sn = sin(th), R[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            R[i][j] = (1 - c) * ax[i] * ax[j] + (i == j ? c : 0);
        }
    R[0][1] -= sn * ax[2];
    R[0][2] += sn * ax[1];
    R[1][0] += sn * ax[2];
    R[1][2] -= sn * ax[0];
    R[2][0] -= sn * ax[1];
    R[2][1] += sn * ax[0];
    for (int i = 0; i < s->nnodes; i++) {
        double *x = s->x + 3 * i, y[3];
        for (int r = 0; r < 3; r++)
            y[r] = R[r][0] * x[0] + R[r][1] * x[1] + R[r][2] * x[2] + 5.0 * r - 3;
        memcpy(x, y, sizeof y);
    }
    assert_true(max_force(s) < 1e-9);
    assert_true(ss_springs_energy(s) < 1e-18);
    ss_springs_free(s);
    ss_tetmesh_free(m);
}

static void test_springs_energy_monotone(void **state) {
    (void)state;
    ss_tetmesh *m = box_mesh(8, 6, 4, 1.0, 1.0);
    ss_springs *s = ss_springs_create(m, 100.0, NULL);
    /* random perturbation and random rest lengths; anchor one face */
    for (int i = 0; i < 3 * s->nnodes; i++) s->x[i] += 0.2 * (ss_rng_uniform(7, 1, i) - 0.5);
    for (int i = 0; i < s->nsprings; i++)
        s->rest[i] = s->l0[i] * (0.8 + 0.3 * ss_rng_uniform(7, 2, i));
    for (int i = 0; i < s->nnodes; i++)
        if (s->X[3 * i] == 0) s->anchor[i] = 50.0;
    ss_springs_update_mass(s);
    double e0 = ss_springs_energy(s) + ss_springs_kinetic(s), e = e0;
    int steps = 0;
    for (; steps < 5000; steps++) {
        double d = ss_springs_substep(s);
        double e1 = ss_springs_energy(s) + ss_springs_kinetic(s);
        assert_true(e1 <= e * (1 + 1e-12) + 1e-15);
        e = e1;
        if (d < 1e-8) break;
    }
    assert_true(steps < 5000);
    assert_true(e < 0.5 * e0);
    /* relaxed: the force balance holds */
    double fm = max_force(s);
    assert_true(fm < 1e-5);
    ss_springs_free(s);
    ss_tetmesh_free(m);
}

static void test_bspline(void **state) {
    (void)state;
    /* partition of unity of the seed's kernel, and its linear reproduction */
    for (int k = 0; k < 100; k++) {
        double x = ss_rng_uniform(3, 0, k) * 10;
        double s = 0, s1 = 0;
        for (int i = -3; i < 15; i++) {
            s += ss_mech_bspline(x - i);
            s1 += ss_mech_bspline(x - i) * i;
        }
        assert_float_equal(s, 1.0, 1e-12);
        assert_float_equal(s1, x, 1e-12);
    }
    assert_float_equal(ss_mech_bspline(0), 2.0 / 3.0, 1e-15);
    assert_float_equal(ss_mech_bspline(1), 1.0 / 6.0, 1e-15);
    assert_float_equal(ss_mech_bspline(2), 0, 1e-15);
    assert_float_equal(ss_mech_kernel_width(8000, 1000), 2.0, 1e-12);
    /* grid -> particles -> grid of a linear field, strides 1 and 3 */
    for (int stride = 1; stride <= 3; stride += 2) {
        const int nx = 30, ny = 26, nz = 22;
        const double dx = 0.5;
        size_t n = (size_t)nx * ny * nz;
        float *u = malloc(n * sizeof(float)), *o[3];
        uint8_t *mask = malloc(n);
        for (int c = 0; c < 3; c++) o[c] = malloc(n * sizeof(float));
        const double a[3] = {0.3, -0.2, 0.1}, b0 = 1.5;
        for (int z = 0; z < nz; z++)
            for (int y = 0; y < ny; y++)
                for (int x = 0; x < nx; x++) {
                    size_t i = ((size_t)z * ny + y) * nx + x;
                    double p[3] = {(x + 0.5) * dx, (y + 0.5) * dx, (z + 0.5) * dx};
                    u[i] = (float)(b0 + a[0] * p[0] + a[1] * p[1] + a[2] * p[2]);
                    mask[i] = 1;
                }
        ss_mech_transfer *t = ss_mech_transfer_create(nx, ny, nz, dx, stride, NULL);
        /* particles scattered inside, away from the edges */
        int np = 400;
        double *pts = malloc(3 * (size_t)np * sizeof(double)),
               *val = malloc((size_t)np * sizeof(double));
        double *v3 = malloc(3 * (size_t)np * sizeof(double)),
               *g3 = malloc(9 * (size_t)np * sizeof(double));
        double L[3] = {nx * dx, ny * dx, nz * dx};
        for (int p = 0; p < np; p++)
            for (int d = 0; d < 3; d++)
                pts[3 * p + d] = (0.25 + 0.5 * ss_rng_uniform(5, d, p)) * L[d];
        ss_mech_g2p(t, u, mask, pts, np, val);
        for (int p = 0; p < np; p++) {
            double want = b0 + a[0] * pts[3 * p] + a[1] * pts[3 * p + 1] + a[2] * pts[3 * p + 2];
            assert_float_equal(val[p], want, 2e-5);
            for (int c = 0; c < 3; c++) {
                v3[3 * p + c] = val[p] * (c + 1);
                for (int d = 0; d < 3; d++) g3[9 * p + 3 * c + d] = a[d] * (c + 1);
            }
        }
        ss_mech_p2g(t, pts, np, v3, g3, 3, mask, o);
        int checked = 0;
        for (int z = 0; z < nz; z++)
            for (int y = 0; y < ny; y++)
                for (int x = 0; x < nx; x++) {
                    double p[3] = {(x + 0.5) * dx, (y + 0.5) * dx, (z + 0.5) * dx};
                    int in = 1;
                    for (int d = 0; d < 3; d++) in &= p[d] > 0.4 * L[d] && p[d] < 0.6 * L[d];
                    if (!in) continue;
                    size_t i = ((size_t)z * ny + y) * nx + x;
                    double want = b0 + a[0] * p[0] + a[1] * p[1] + a[2] * p[2];
                    for (int c = 0; c < 3; c++) assert_float_equal(o[c][i], want * (c + 1), 1e-4);
                    checked++;
                }
        assert_true(checked > 50);
        /* divergence of the linear field (a, 2a, 3a components) is a0 + 2 a1 + 3 a2 */
        float *div = malloc(n * sizeof(float));
        ss_mech_divergence(t, o, mask, div);
        size_t mid = ((size_t)(nz / 2) * ny + ny / 2) * nx + nx / 2;
        assert_float_equal(div[mid], a[0] + 2 * a[1] + 3 * a[2], 1e-4);
        free(div);
        ss_mech_transfer_free(t);
        free(pts);
        free(val);
        free(v3);
        free(g3);
        free(u);
        free(mask);
        for (int c = 0; c < 3; c++) free(o[c]);
    }
}

/* A free block (no anchors) of tissue under a uniform myofibroblast density:
 * every spring's rest length shortens by the strain the constitutive law
 * predicts, so the block shrinks by exactly that strain. */
static void test_free_block(void **state) {
    (void)state;
    ss_error err;
    ss_heal_params *hp = ss_heal_params_preset("clean", &err);
    assert_non_null(hp);
    const int nx = 24, ny = 20, nz = 14;
    ss_heal_grid *g = ss_heal_grid_create(nx, ny, nz, 0.5, &err);
    assert_non_null(g);
    assert_int_equal(ss_heal_grid_init(g, 6.0, 0.1, NULL, hp, &err), SS_OK);
    size_t n = (size_t)nx * ny * nz;
    const double nmyo = 0.5;
    /* an open wound region everywhere: plasma above p_min, no epithelium */
    for (size_t i = 0; i < n; i++) {
        g->field[SS_HEAL_FIBROBLAST][i] = (float)nmyo;
        g->field[SS_HEAL_PLASMA][i] = 1.0f;
        g->field[SS_HEAL_EPITHELIUM][i] = 0.0f;
    }
    ss_mech_params p;
    ss_mech_params_default(&p);
    p.anchor = 0;
    p.anchor_side = 0;
    p.kappa = 1.0 / 3.0; /* isotropic: the same strain in every direction */
    p.k1 = 0;            /* ground matrix only: the strain is sigma / (3 K_bulk) */
    p.K_m = 1;
    p.tau_myo = 0;     /* no differentiation kinetics: the open wound's fibroblasts pull at once */
    p.tau_remodel = 0; /* and the rest lengths take their target in the frame */
    p.tol = 1e-9;
    p.max_substeps = 20000;
    p.tet_size_mm = 1.0;
    ss_mech *m = ss_mech_create(g, hp, &p, NULL, NULL, 0, &err);
    assert_non_null(m);
    assert_int_equal(ss_mech_step(m, g, 0.1, &err), SS_OK);
    ss_mech_stats st;
    ss_mech_stats_compute(m, &st);
    assert_true(st.converged);
    /* prediction: sigma = p_cell(0) n K_m; strain = sqrt(2 psi / 9K) */
    double sig = ss_mech_pcell(&p, 0.0) * nmyo * p.K_m;
    double e[3] = {1, 0, 0};
    double eps = ss_mech_shortening(&p, ss_mech_spring_energy_density(&p, sig, e));
    assert_true(eps > 0.01);
    assert_float_equal(eps, sig / (3 * p.K_bulk), 1e-12);
    /* distances are free of the rigid drift a free block may pick up */
    const ss_tetmesh *M = ss_mech_mesh(m);
    const double *x = ss_mech_positions(m);
    for (int k = 0; k < 50; k++) {
        int a = (int)(ss_rng_uniform(9, 0, k) * M->nnodes),
            b = (int)(ss_rng_uniform(9, 1, k) * M->nnodes);
        if (a == b) continue;
        double d0 = 0, d1 = 0;
        for (int d = 0; d < 3; d++) {
            d0 += (M->x[3 * a + d] - M->x[3 * b + d]) * (M->x[3 * a + d] - M->x[3 * b + d]);
            d1 += (x[3 * a + d] - x[3 * b + d]) * (x[3 * a + d] - x[3 * b + d]);
        }
        assert_float_equal(1 - sqrt(d1 / d0), eps, 1e-6);
    }
    /* the grid now carries the contraction: theta = (1 - eps)^3 - 1 near the middle, and
     * the velocity points inwards */
    float *const *u = ss_mech_grid_displacement(m);
    size_t c = ((size_t)5 * ny + ny / 2) * nx + nx / 2;
    (void)u;
    assert_true(g->velocity[0][c - 4] > 0 && g->velocity[0][c + 4] < 0);
    ss_mech_free(m);
    ss_heal_grid_free(g);
    ss_heal_params_free(hp);
}

/* Sutures: the CSV reader's errors, a stitch outside the domain, and a
 * stitch pulling its two points together until its removal day. */
static void test_sutures(void **state) {
    (void)state;
    char *dir = tu_tmpdir("mech_sutures");
    char path[4096];
    ss_error err;
    int n = 0;
    snprintf(path, sizeof path, "%s/s.csv", dir);
    write_text(path, "# stitches\nx1,y1,z1,x2,y2,z2,remove_day\n# a stitch\n4,5,5,8,5,5,2\n");
    ss_mech_suture *s = ss_mech_sutures_read(path, &n, &err);
    assert_non_null(s);
    assert_int_equal(n, 1);
    assert_float_equal(s[0].remove_day, 2, 0);
    static const char *bad[] = {"1,2,3\n", "1,2,3,4,5,x\n", "1,2,3,4,5,6,-1\n", "",
                                "1,2,3,4,5,6,7,8\n"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        write_text(path, bad[i]);
        assert_null(ss_mech_sutures_read(path, &n, &err));
        assert_int_equal(err.code, SS_ERR_INPUT);
        assert_non_null(strstr(err.msg, "s.csv"));
    }
    /* a 12 x 10 x 6 mm block; the stitch joins (4,5,5) and (8,5,5) */
    ss_heal_params *hp = ss_heal_params_preset("clean", &err);
    ss_heal_grid *g = ss_heal_grid_create(24, 20, 14, 0.5, &err);
    assert_int_equal(ss_heal_grid_init(g, 6.0, 0.1, NULL, hp, &err), SS_OK);
    ss_mech_params p;
    ss_mech_params_default(&p);
    p.k_suture = 50; /* a tight stitch in intact skin */
    ss_mech_suture out = {{4, 5, 5}, {40, 5, 5}, INFINITY};
    assert_null(ss_mech_create(g, hp, &p, NULL, &out, 1, &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "outside"));
    ss_mech *m = ss_mech_create(g, hp, &p, NULL, s, 1, &err);
    assert_non_null(m);
    const ss_tetmesh *M = ss_mech_mesh(m);
    int a = -1, b = -1;
    double da = 1e9, db = 1e9;
    for (int i = 0; i < M->nnodes; i++) { /* the stitched nodes: nearest to the points */
        const double *x = M->x + 3 * i;
        double ea = hypot(hypot(x[0] - 4, x[1] - 5), x[2] - 5);
        double eb = hypot(hypot(x[0] - 8, x[1] - 5), x[2] - 5);
        if (ea < da) da = ea, a = i;
        if (eb < db) db = eb, b = i;
    }
    assert_true(a >= 0 && b >= 0);
    double d0 = fabs(M->x[3 * b] - M->x[3 * a]);
    for (int k = 0; k < 10; k++) { /* day 0 .. 1: stitched */
        g->t_days += 0.1;
        assert_int_equal(ss_mech_step(m, g, 0.1, &err), SS_OK);
    }
    const double *x = ss_mech_positions(m);
    double d1 = fabs(x[3 * b] - x[3 * a]);
    assert_true(d1 < 0.8 * d0);
    g->t_days = 3; /* taken out: the skin springs back */
    assert_int_equal(ss_mech_step(m, g, 0.1, &err), SS_OK);
    x = ss_mech_positions(m);
    assert_float_equal(fabs(x[3 * b] - x[3 * a]), d0, 1e-2);
    ss_mech_free(m);
    ss_heal_grid_free(g);
    ss_heal_params_free(hp);
    free(s);
    tu_rmtree(dir);
    free(dir);
}

/* The tet volume barrier: its force is the gradient of its energy (central
 * differences at a squashed configuration where it acts), it is zero above
 * j_min, and a relaxation whose springs pull a tet flat stops short of
 * folding it. */
static void test_barrier(void **state) {
    (void)state;
    ss_error err;
    ss_tetmesh *m = box_mesh(3, 3, 3, 1.0, 1.0);
    ss_springs *s = ss_springs_create(m, 100.0, &err);
    assert_non_null(s);
    assert_int_equal(ss_springs_set_barrier(s, m, 30.0, 0.2, &err), SS_OK);
    assert_int_equal(s->ntets, m->ntets);
    /* squash the block to a tenth of its height: every tet at J = 0.1 < 0.2 */
    for (int i = 0; i < s->nnodes; i++) s->x[3 * i + 2] *= 0.1;
    ss_springs_barrier_update(s);
    double *f = malloc(3 * (size_t)s->nnodes * sizeof(double));
    double *fs = malloc(3 * (size_t)s->nnodes * sizeof(double));
    ss_springs_forces(s, f);
    double jmin = s->jmin;
    s->jmin = 0; /* springs alone */
    ss_springs_forces(s, fs);
    s->jmin = jmin;
    int checked = 0;
    for (int i = 0; i < s->nnodes; i += 3)
        for (int d = 0; d < 3; d++) {
            const double h = 1e-6, x0 = s->x[3 * i + d];
            s->x[3 * i + d] = x0 + h;
            double up = ss_springs_energy(s);
            s->x[3 * i + d] = x0 - h;
            double um = ss_springs_energy(s);
            s->x[3 * i + d] = x0;
            double fd = -(up - um) / (2 * h);
            assert_float_equal(f[3 * i + d], fd, 1e-5 * (1 + fabs(fd)));
            checked += fabs(f[3 * i + d] - fs[3 * i + d]) > 1e-3; /* the barrier pushes */
        }
    assert_true(checked > 0);
    /* unsquashed: no barrier force at all */
    memcpy(s->x, s->X, 3 * (size_t)s->nnodes * sizeof(double));
    ss_springs_barrier_update(s);
    ss_springs_forces(s, f);
    for (int i = 0; i < 3 * s->nnodes; i++) assert_true(fabs(f[i]) < 1e-12);
    /* every vertical spring wants a twentieth of its length, the diagonals
     * and horizontal ones their own: edge springs alone would let tets fold
     * to get there; the barrier keeps every tet above zero volume */
    for (int i = 0; i < s->nsprings; i++) {
        const double *a = s->X + 3 * s->e[2 * i], *b = s->X + 3 * s->e[2 * i + 1];
        if (fabs(a[2] - b[2]) > 0.5 && fabs(a[0] - b[0]) < 1e-9 && fabs(a[1] - b[1]) < 1e-9)
            s->rest[i] = 0.05 * s->l0[i];
    }
    for (int i = 0; i < s->nnodes; i++)
        if (s->X[3 * i + 2] == 0) s->anchor[i] = 100.0;
    ss_springs_update_mass(s);
    int conv;
    ss_springs_relax(s, 1e-7, 20000, &conv);
    for (int t = 0; t < m->ntets; t++) {
        const int32_t *q = m->tet + 4 * t;
        double u[3], v[3], w[3];
        for (int d = 0; d < 3; d++) {
            u[d] = s->x[3 * q[1] + d] - s->x[3 * q[0] + d];
            v[d] = s->x[3 * q[2] + d] - s->x[3 * q[0] + d];
            w[d] = s->x[3 * q[3] + d] - s->x[3 * q[0] + d];
        }
        double V = (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                    u[2] * (v[0] * w[1] - v[1] * w[0])) /
                   6.0;
        assert_true(V > 0);
    }
    free(f);
    free(fs);
    ss_springs_free(s);
    ss_tetmesh_free(m);
}

/* Most folded tets after any frame of the benchmark's load (a 20 x 20 mm
 * wound through a 24 mm block, the wound's fibroblasts ramped to 0.5 in
 * steps of 0.05, kinetics and remodelling lag off, k1 and max_shorten of
 * the benchmark) on a 30 x 23 x 30 mm
 * grid of 0.75 mm cells with lattice edge h; the outline contraction at the
 * end into *contr. */
static int folds_under_load(double h, double jmin, double *contr) {
    ss_error err;
    ss_heal_params *hp = ss_heal_params_preset("clean", &err);
    assert_non_null(hp);
    const int nx = 40, ny = 31, nz = 40;
    const double dx = 0.75, top = 0.8 * nz * dx;
    ss_heal_grid *g = ss_heal_grid_create(nx, ny, nz, dx, &err);
    assert_non_null(g);
    uint8_t *w = ss_heal_wound_box(g, top, 20.0, 20.0, 1.0, &err);
    assert_non_null(w);
    assert_int_equal(ss_heal_grid_init(g, top, 0.1, w, hp, &err), SS_OK);
    free(w);
    ss_mech_params p;
    ss_mech_params_default(&p);
    p.tet_size_mm = h;
    p.tau_myo = 0;
    p.tau_remodel = 0;
    p.k1 = 4000; /* the benchmark's fixed load (bench/bench_mech.c) */
    p.max_shorten = 0.5;
    p.j_min = jmin;
    ss_mech *m = ss_mech_create(g, hp, &p, NULL, NULL, 0, &err);
    assert_non_null(m);
    int folds = 0;
    ss_mech_stats st;
    for (int f = 1; f <= 10; f++) {
        for (size_t i = 0; i < (size_t)nx * ny * nz; i++)
            if (g->cell[i] == SS_CELL_WOUND) g->field[SS_HEAL_FIBROBLAST][i] = 0.05f * f;
        assert_int_equal(ss_mech_step(m, g, 0.05, &err), SS_OK);
        ss_mech_stats_compute(m, &st);
        if (st.inverted_tets > folds) folds = st.inverted_tets;
    }
    *contr = 1 - st.outline_area_mm2 / st.initial_outline_area_mm2;
    ss_mech_free(m);
    ss_heal_grid_free(g);
    ss_heal_params_free(hp);
    return folds;
}

/* The barrier's near pass (only the tets near jmin and those of nodes that
 * moved off their safe distance) against the full pass at every force
 * evaluation: the same positions, bit for bit, after a relaxation in which
 * part of the block is squashed below jmin and the rest moves freely. */
static void test_barrier_near_pass(void **state) {
    (void)state;
    ss_error err;
    ss_tetmesh *m = box_mesh(12, 10, 3, 1.0, 1.0);
    ss_springs *s[2];
    for (int k = 0; k < 2; k++) {
        s[k] = ss_springs_create(m, 100.0, &err);
        assert_non_null(s[k]);
        assert_int_equal(ss_springs_set_barrier(s[k], m, 30.0, 0.2, &err), SS_OK);
        for (int i = 0; i < s[k]->nsprings; i++) {
            const double *a = s[k]->X + 3 * s[k]->e[2 * i], *b = s[k]->X + 3 * s[k]->e[2 * i + 1];
            /* vertical edges of the left third want a twentieth of their length */
            if (fabs(a[2] - b[2]) > 0.5 && fabs(a[0] - b[0]) < 1e-9 && fabs(a[1] - b[1]) < 1e-9 &&
                a[0] < 4.5)
                s[k]->rest[i] = 0.05 * s[k]->l0[i];
        }
        for (int i = 0; i < s[k]->nnodes; i++)
            if (s[k]->X[3 * i + 2] == 0) s[k]->anchor[i] = 100.0;
        ss_springs_update_mass(s[k]);
    }
    s[1]->bar_full_always = 1;
    int conv[2];
    int n0 = ss_springs_relax(s[0], 1e-7, 3000, &conv[0]);
    int n1 = ss_springs_relax(s[1], 1e-7, 3000, &conv[1]);
    assert_int_equal(n0, n1);
    assert_memory_equal(s[0]->x, s[1]->x, 3 * (size_t)s[0]->nnodes * sizeof(double));
    assert_true(s[0]->U == s[1]->U);
    /* the barrier acted, and the near pass did most of the evaluations */
    int below = 0;
    for (int t = 0; t < s[0]->ntets; t++) below += s[0]->tcoef[t] != 0;
    assert_true(below > 0);
    assert_true(s[0]->bar_passes[1] > 2 * s[0]->bar_passes[0]);
    assert_int_equal(s[1]->bar_passes[1], 0);
    for (int k = 0; k < 2; k++) ss_springs_free(s[k]);
    ss_tetmesh_free(m);
}

/* A finer mesh under the same load keeps every tet unfolded, and contracts
 * the wound as the coarse one does (within 3 points of outline area): the
 * mechanics converge with the tet size instead of folding at the wound's
 * corners. Without the volume barrier (j_min = 0) the fine mesh folds
 * (several hundred tets in the first frame), the coarse one does not. */
static void test_fine_mesh_no_folds(void **state) {
    (void)state;
    omp_set_num_threads(1);
    double cc, cf, c0;
    int coarse = folds_under_load(2.2, 0.2, &cc), fine = folds_under_load(1.07, 0.2, &cf);
    print_message("folded tets: coarse (h 2.2 mm) %d, fine (h 1.07 mm) %d; contraction %.1f / "
                  "%.1f %%\n",
                  coarse, fine, 100 * cc, 100 * cf);
    assert_int_equal(coarse, 0);
    assert_int_equal(fine, 0);
    assert_true(cc > 0.2 && cf > 0.2);
    assert_float_equal(cf, cc, 0.03);
    if (!tu_quick()) {
        int bare = folds_under_load(1.07, 0.0, &c0);
        print_message("without the barrier: %d folded tets on the fine mesh\n", bare);
        assert_true(bare > 0);
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pcell),
        cmocka_unit_test(test_goh),
        cmocka_unit_test(test_params),
        cmocka_unit_test(test_lattice),
        cmocka_unit_test(test_readers),
        cmocka_unit_test(test_springs_rest_rigid),
        cmocka_unit_test(test_springs_energy_monotone),
        cmocka_unit_test(test_bspline),
        cmocka_unit_test(test_free_block),
        cmocka_unit_test(test_sutures),
        cmocka_unit_test(test_barrier),
        cmocka_unit_test(test_barrier_near_pass),
        cmocka_unit_test(test_fine_mesh_no_folds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
