/* The uniaxial material test of the tissue models (`skinsim mech stretch`,
 * docs/mech.md "Stress-stretch").
 *
 * A cube of the solvers' own lattice mesh (src/mech/tetmesh.c, the mesh the
 * heal runs use) is stretched along one axis: the face at the low end of the
 * axis slides on its plane (held in the axis direction; one corner held in
 * all three and one node against the rotation about the axis), the face at
 * the high end is moved to lambda times the length in load increments, the
 * four lateral faces are free. The stress is the reaction on the moving face
 * over the current cross-section (current volume / current length). The
 * analytic value is the homogeneous state of the same GOH law with only the
 * axial Cauchy stress non-zero: the right stretch tensor U with n.U n =
 * lambda whose other five stress components vanish, solved by Newton on the
 * closed-form Cauchy stress (ss_hyper_goh_cauchy, written from the
 * invariants, not the solver's derivative code). With fibres along or across
 * the axis the ends' sliding condition admits that state, so the solver must
 * reproduce it; fibres at another angle shear the block, which the planar
 * ends restrain (the test then reports the restrained block against the free
 * homogeneous state).
 * The springs model (the seed's mass-spring network, modulus 9 K_bulk as in
 * mech.c) takes the same block with both end faces clamped (its nodes have no
 * sliding condition) and relaxes by its own sub-steps. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/mech.h"

void ss_mech_stretch_config_default(ss_mech_stretch_config *c) {
    memset(c, 0, sizeof *c);
    c->stretch = 1.1;
    c->axis = 0;
    c->fibre[0] = 1;
    c->size_mm = 4.0;
    c->tet_size_mm = 0; /* the params' */
    c->model = SS_MECH_MODEL_GOH;
    c->increments = 10;
}

/* rotation taking n to e_x (Rodrigues), rows of R */
static void frame_to_x(const double n[3], double R[9]) {
    double c = n[0], v[3] = {0, n[2], -n[1]}; /* n x e_x */
    double s2 = v[1] * v[1] + v[2] * v[2];
    static const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    if (s2 < 1e-30) {
        memcpy(R, I, sizeof I);
        if (c < 0) R[0] = R[4] = -1; /* rotation by pi about z */
        return;
    }
    double k = (1 - c) / s2, V[9] = {0, -v[2], v[1], v[2], 0, -v[0], -v[1], v[0], 0};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double VV = 0;
            for (int m = 0; m < 3; m++) VV += V[3 * i + m] * V[3 * m + j];
            R[3 * i + j] = I[3 * i + j] + V[3 * i + j] + k * VV;
        }
}

static void resid(const ss_mech_params *q, double lambda, const double u[5], double res[5],
                  double *s11) {
    double F[9] = {lambda, u[2], u[3], u[2], u[0], u[4], u[3], u[4], u[1]}, sg[9];
    ss_hyper_goh_cauchy(q, F, sg);
    res[0] = sg[4];
    res[1] = sg[8];
    res[2] = sg[1];
    res[3] = sg[2];
    res[4] = sg[5];
    if (s11) *s11 = sg[0];
}

/* 5x5 Gaussian elimination with partial pivoting; 0 when singular */
static int solve5(double A[5][5], double b[5]) {
    for (int c = 0; c < 5; c++) {
        int piv = c;
        for (int r = c + 1; r < 5; r++)
            if (fabs(A[r][c]) > fabs(A[piv][c])) piv = r;
        if (!(fabs(A[piv][c]) > 1e-300)) return 0;
        for (int k = 0; k < 5; k++) {
            double t = A[c][k];
            A[c][k] = A[piv][k];
            A[piv][k] = t;
        }
        double t = b[c];
        b[c] = b[piv];
        b[piv] = t;
        for (int r = c + 1; r < 5; r++) {
            double f = A[r][c] / A[c][c];
            for (int k = c; k < 5; k++) A[r][k] -= f * A[c][k];
            b[r] -= f * b[c];
        }
    }
    for (int c = 4; c >= 0; c--) {
        for (int k = c + 1; k < 5; k++) b[c] -= A[c][k] * b[k];
        b[c] /= A[c][c];
    }
    return 1;
}

ss_status ss_mech_uniaxial_analytic(const ss_mech_params *p, const double n_in[3], double lambda,
                                    double *sigma, double lateral[2], ss_error *err) {
    double nl = sqrt(n_in[0] * n_in[0] + n_in[1] * n_in[1] + n_in[2] * n_in[2]);
    if (!(nl > 0) || !(lambda > 0) || !isfinite(lambda))
        return ss_error_set(err, SS_ERR_INPUT, "uniaxial GOH: bad axis or stretch %g", lambda);
    double n[3] = {n_in[0] / nl, n_in[1] / nl, n_in[2] / nl}, R[9];
    frame_to_x(n, R);
    ss_mech_params q = *p; /* the fibres in the frame where the axis is x */
    for (int f = 0; f < p->nfibres; f++)
        for (int i = 0; i < 3; i++)
            q.fibre[f][i] = R[3 * i] * p->fibre[f][0] + R[3 * i + 1] * p->fibre[f][1] +
                            R[3 * i + 2] * p->fibre[f][2];
    double u[5] = {1 / sqrt(lambda), 1 / sqrt(lambda), 0, 0, 0}, r[5], s11 = 0;
    int ok = 0;
    for (int it = 0; it < 100; it++) {
        resid(&q, lambda, u, r, &s11);
        double rn = 0;
        for (int k = 0; k < 5; k++) rn = fmax(rn, fabs(r[k]));
        if (rn < 1e-10 * (1 + fabs(s11))) {
            ok = 1;
            break;
        }
        double A[5][5];
        for (int k = 0; k < 5; k++) {
            double up[5], rp[5], hh = 1e-7 * (1 + fabs(u[k]));
            memcpy(up, u, sizeof up);
            up[k] += hh;
            resid(&q, lambda, up, rp, NULL);
            for (int m = 0; m < 5; m++) A[m][k] = (rp[m] - r[m]) / hh;
        }
        double dx[5];
        for (int m = 0; m < 5; m++) dx[m] = -r[m];
        if (!solve5(A, dx)) break;
        double sc = 1;
        for (int k = 0; k < 2; k++) /* keep the lateral stretches positive */
            while (u[k] + sc * dx[k] <= 0.05 * u[k]) sc *= 0.5;
        for (int k = 0; k < 5; k++) u[k] += sc * dx[k];
    }
    if (!ok)
        return ss_error_set(err, SS_ERR_INPUT,
                            "uniaxial GOH: no homogeneous state found at stretch %g", lambda);
    *sigma = s11;
    if (lateral) {
        lateral[0] = u[0];
        lateral[1] = u[1];
    }
    return SS_OK;
}

static ss_tetmesh *block(double L, double h, ss_error *err) {
    int nv = (int)ceil(2 * L / h);
    if (nv < 2) nv = 2;
    if (nv > 400) {
        ss_error_set(err, SS_ERR_INPUT, "mech stretch: tet size %g mm too small for a %g mm block",
                     h, L);
        return NULL;
    }
    uint8_t *in = malloc((size_t)nv * nv * nv);
    if (!in) {
        ss_error_set(err, SS_ERR_NOMEM, "mech stretch: out of memory");
        return NULL;
    }
    memset(in, 1, (size_t)nv * nv * nv);
    ss_tetmesh *m = ss_tetmesh_lattice(in, nv, nv, nv, L / nv, h, err);
    free(in);
    return m;
}

static ss_status stretch_springs(const ss_mech_params *p, const ss_mech_stretch_config *c,
                                 const ss_tetmesh *m, double L, ss_mech_stretch_result *res,
                                 ss_error *err) {
    ss_springs *S = ss_springs_create(m, 9.0 * p->K_bulk, err);
    if (!S) return SS_ERR_INPUT;
    const int ax = c->axis, nn = m->nnodes;
    const double eps = 1e-9 * L;
    for (int i = 0; i < nn; i++) {
        double xa = m->x[3 * i + ax];
        if (xa < eps || xa > L - eps) S->fixed[i] = 1;
    }
    ss_springs_update_mass(S);
    int tot = 0, conv = 1;
    for (int k = 1; k <= c->increments; k++) {
        double lam = 1 + (c->stretch - 1) * k / c->increments;
        for (int i = 0; i < nn; i++)
            if (m->x[3 * i + ax] > L - eps) S->x[3 * i + ax] = lam * L;
        S->fvalid = 0;
        memset(S->v, 0, 3 * (size_t)nn * sizeof(double));
        int cv = 0;
        tot += ss_springs_relax(S, p->tol * 1e-2, 200000, &cv);
        conv &= cv;
    }
    double *f = malloc(3 * (size_t)nn * sizeof(double));
    if (!f) {
        ss_springs_free(S);
        return ss_error_set(err, SS_ERR_NOMEM, "mech stretch: out of memory");
    }
    ss_springs_forces(S, f);
    double R = 0, lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < nn; i++) {
        if (m->x[3 * i + ax] > L - eps) R -= f[3 * i + ax]; /* the grip pulls against the springs */
        for (int d = 0; d < 3; d++) {
            lo[d] = fmin(lo[d], S->x[3 * i + d]);
            hi[d] = fmax(hi[d], S->x[3 * i + d]);
        }
    }
    /* cross-section: the mid-plane's lateral extent (the ends are clamped) */
    double mid[2] = {0, 0};
    int e1 = (ax + 1) % 3, e2 = (ax + 2) % 3;
    double mlo[2] = {INFINITY, INFINITY}, mhi[2] = {-INFINITY, -INFINITY};
    for (int i = 0; i < nn; i++) {
        if (fabs(m->x[3 * i + ax] - 0.5 * L) > 0.26 * L) continue;
        int ee[2] = {e1, e2};
        for (int k = 0; k < 2; k++) {
            mlo[k] = fmin(mlo[k], S->x[3 * i + ee[k]]);
            mhi[k] = fmax(mhi[k], S->x[3 * i + ee[k]]);
        }
    }
    for (int k = 0; k < 2; k++) mid[k] = (mhi[k] - mlo[k]) / L;
    res->lateral_stretch[0] = mid[0];
    res->lateral_stretch[1] = mid[1];
    res->stress_kpa = R / (mid[0] * mid[1] * L * L);
    res->mean_sigma_kpa = res->stress_kpa;
    res->newton = 0;
    res->cg = tot;
    res->converged = conv;
    free(f);
    ss_springs_free(S);
    return SS_OK;
}

ss_status ss_mech_stretch(const ss_mech_params *p_in, const ss_mech_stretch_config *c,
                          ss_mech_stretch_result *res, ss_error *err) {
    memset(res, 0, sizeof *res);
    if (!(c->stretch > 0.3 && c->stretch < 3))
        return ss_error_set(err, SS_ERR_INPUT, "mech stretch: --stretch %g outside 0.3..3",
                            c->stretch);
    if (c->axis < 0 || c->axis > 2)
        return ss_error_set(err, SS_ERR_INPUT, "mech stretch: axis must be x, y or z");
    if (!(c->size_mm > 0) || !(c->increments >= 1))
        return ss_error_set(err, SS_ERR_INPUT, "mech stretch: bad block size or increments");
    ss_mech_params p = *p_in;
    double fl =
        sqrt(c->fibre[0] * c->fibre[0] + c->fibre[1] * c->fibre[1] + c->fibre[2] * c->fibre[2]);
    if (!(fl > 0)) return ss_error_set(err, SS_ERR_INPUT, "mech stretch: zero fibre direction");
    memset(p.fibre, 0, sizeof p.fibre);
    for (int d = 0; d < 3; d++) p.fibre[0][d] = c->fibre[d] / fl;
    p.nfibres = 1;
    ss_status st = ss_mech_params_check(&p, err);
    if (st) return st;
    const double L = c->size_mm, h = c->tet_size_mm > 0 ? c->tet_size_mm : p.tet_size_mm;
    double n[3] = {0, 0, 0};
    n[c->axis] = 1;
    if ((st = ss_mech_uniaxial_analytic(&p, n, c->stretch, &res->analytic_stress_kpa,
                                        res->analytic_lateral, err)))
        return st;
    { /* the analytic laterals are in the frame with the axis along x: map back */
        double R[9], lat[2];
        frame_to_x(n, R);
        /* e_y, e_z of that frame in the block's coordinates are R's rows 1, 2 */
        int e1 = (c->axis + 1) % 3, e2 = (c->axis + 2) % 3;
        lat[0] = fabs(R[3 + e1]) > 0.5 ? res->analytic_lateral[0] : res->analytic_lateral[1];
        lat[1] = fabs(R[6 + e2]) > 0.5 ? res->analytic_lateral[1] : res->analytic_lateral[0];
        res->analytic_lateral[0] = lat[0];
        res->analytic_lateral[1] = lat[1];
    }
    ss_tetmesh *m = block(L, h, err);
    if (!m) return SS_ERR_INPUT;
    res->nodes = m->nnodes;
    res->tets = m->ntets;
    if (c->model == SS_MECH_MODEL_SPRINGS) {
        st = stretch_springs(&p, c, m, L, res, err);
        ss_tetmesh_free(m);
        return st;
    }
    ss_hyper *H = ss_hyper_create(m, &p, err);
    if (!H) {
        ss_tetmesh_free(m);
        return SS_ERR_INPUT;
    }
    const int ax = c->axis, nn = m->nnodes, e1 = (ax + 1) % 3, e2 = (ax + 2) % 3;
    const double eps = 1e-9 * L;
    uint8_t *fx = ss_hyper_fixed(H);
    double *x = ss_hyper_x(H);
    int corner = -1, rot = -1;
    for (int i = 0; i < nn; i++) {
        const double *X = m->x + 3 * i;
        if (X[ax] < eps || X[ax] > L - eps) fx[3 * i + ax] = 1;
        if (X[ax] < eps && X[e1] < eps && X[e2] < eps) corner = i;
        if (X[ax] < eps && X[e1] > L - eps && X[e2] < eps) rot = i;
    }
    if (corner < 0 || rot < 0) {
        ss_hyper_free(H);
        ss_tetmesh_free(m);
        return ss_error_set(err, SS_ERR_INPUT, "mech stretch: block corners not found");
    }
    fx[3 * corner + e1] = fx[3 * corner + e2] = 1;
    fx[3 * rot + e2] = 1;
    ss_hyper_report rep = {0, 0, 0, 0, 0};
    int conv = 1;
    for (int k = 1; k <= c->increments && !st; k++) {
        double lam = 1 + (c->stretch - 1) * k / c->increments,
               lp = 1 + (c->stretch - 1) * (k - 1) / c->increments;
        /* the increment's start: the last state stretched affinely along
         * the axis (a good guess, and the moving face at its place) */
        for (int i = 0; i < nn; i++) x[3 * i + ax] *= lam / lp;
        ss_hyper_report r1;
        st = ss_hyper_solve(H, 1e-10, 60, &r1, err);
        rep.newton += r1.newton;
        rep.cg += r1.cg;
        conv &= r1.converged;
    }
    if (!st) {
        double *f = malloc(3 * (size_t)nn * sizeof(double));
        if (!f) {
            st = ss_error_set(err, SS_ERR_NOMEM, "mech stretch: out of memory");
        } else {
            ss_hyper_tet_forces(H, f);
            double Rf = 0, sg[9], V;
            for (int i = 0; i < nn; i++)
                if (m->x[3 * i + ax] > L - eps) Rf -= f[3 * i + ax];
            ss_hyper_mean_cauchy(H, sg, &V);
            double lo[3] = {INFINITY, INFINITY, INFINITY},
                   hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            for (int i = 0; i < nn; i++)
                for (int d = 0; d < 3; d++) {
                    lo[d] = fmin(lo[d], x[3 * i + d]);
                    hi[d] = fmax(hi[d], x[3 * i + d]);
                }
            res->stress_kpa = Rf / (V / (c->stretch * L));
            res->mean_sigma_kpa = sg[4 * ax];
            res->lateral_stretch[0] = (hi[e1] - lo[e1]) / L;
            res->lateral_stretch[1] = (hi[e2] - lo[e2]) / L;
            free(f);
        }
    }
    res->newton = rep.newton;
    res->cg = rep.cg;
    res->converged = conv;
    ss_hyper_free(H);
    ss_tetmesh_free(m);
    return st;
}
