/* The uniaxial material test of the tissue models (`skinsim mech stretch`,
 * docs/mech.md "Stress-stretch").
 *
 * A cube of the solvers' own lattice mesh (src/mech/tetmesh.c, the mesh the
 * heal runs use) is stretched along one axis with its lateral faces free.
 * In tension the end faces carry a dead load (a uniform nominal traction T
 * along the axis, lumped on the face nodes by area) and six pins remove the
 * rigid motion only: a corner held, the corner along the axis held across
 * it, the corner along the next axis held in the third. T is found by a
 * secant iteration per load increment so that the end faces' mean
 * positions are lambda times the length apart. So the block is free to
 * shear: with fibres at an angle to the axis it does, and no boundary
 * condition resists it. The analytic value is the homogeneous state of that
 * problem: the first Piola stress T e_a x e_a (traction only on the end
 * faces) needs F e_a = lambda e_a, so F is upper triangular in the frame
 * (axis, next, next-but-one) once the rotation about the axis is fixed as
 * the pins fix it; its five free components (two lateral stretches, three
 * shears) make the other five Cauchy components vanish, solved by Newton
 * on the closed-form Cauchy stress (ss_hyper_goh_cauchy, written from the
 * invariants, not the solver's derivative code). Linear tets represent that
 * state exactly, so the solver must reproduce it at every refinement.
 * Compression keeps the displacement-controlled ends (a dead compressive
 * load on a block held only against rigid motion is unstable): the low
 * face slides on its plane, the high face is moved to lambda; that matches
 * the homogeneous state only while the fibres do not shear the block (along
 * or across the axis, or slack).
 * The springs model (the seed's mass-spring network, modulus 9 K_bulk as in
 * mech.c) takes the same block with both end faces clamped (its nodes have no
 * sliding condition) and relaxes by its own sub-steps. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/mech.h"
#include "mat3.h"

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

/* rows of Q: the unit axis n, t1 (the coordinate axis after n's largest
 * component, made orthogonal to n), t2 = n x t1; for n = e_k that is
 * (e_k, e_k+1, e_k+2), the block's cyclic order */
static void axis_frame(const double n[3], double Q[9]) {
    int k = 0;
    for (int d = 1; d < 3; d++)
        if (fabs(n[d]) > fabs(n[k])) k = d;
    double t[3] = {0, 0, 0};
    t[(k + 1) % 3] = 1;
    double nt = n[(k + 1) % 3], tl = 0;
    for (int d = 0; d < 3; d++) {
        t[d] -= nt * n[d];
        tl += t[d] * t[d];
    }
    tl = sqrt(tl);
    for (int d = 0; d < 3; d++) {
        Q[d] = n[d];
        Q[3 + d] = t[d] / tl;
    }
    Q[6] = n[1] * Q[5] - n[2] * Q[4];
    Q[7] = n[2] * Q[3] - n[0] * Q[5];
    Q[8] = n[0] * Q[4] - n[1] * Q[3];
}

/* F upper triangular, its first row (lambda, u0, u1), then (0, u2, u3),
 * (0, 0, u4); res the five Cauchy components that must vanish */
static void ut_F(double lambda, const double u[5], double F[9]) {
    const double G[9] = {lambda, u[0], u[1], 0, u[2], u[3], 0, 0, u[4]};
    memcpy(F, G, sizeof G);
}

static void resid(const ss_mech_params *q, double lambda, const double u[5], double res[5],
                  double *s11) {
    double F[9], sg[9];
    ut_F(lambda, u, F);
    ss_hyper_goh_cauchy(q, F, sg);
    res[0] = sg[4];
    res[1] = sg[8];
    res[2] = sg[5];
    res[3] = sg[1];
    res[4] = sg[2];
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

/* From F in the frame (axis, t1, t2): the lateral stretches, i.e. the
 * distance of the opposite lateral faces over the reference one (1 / |F^-T
 * t_k|, which a rotation leaves alone), and the shears F_a1, F_a2 (how the
 * axial displacement grows across the block; with F e_a along e_a a
 * rotation about the axis leaves them alone too) */
static void lateral_shear(const double F[9], double lat[2], double shear[2]) {
    double c[9], J = mat3_cofactors(F, c);
    for (int k = 0; k < 2; k++) {
        const double *r = c + 3 * (k + 1);
        lat[k] = fabs(J) / sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        shear[k] = F[1 + k];
    }
}

ss_status ss_mech_uniaxial_analytic(const ss_mech_params *p, const double n_in[3], double lambda,
                                    double *sigma, double lateral[2], double shear[2],
                                    ss_error *err) {
    double nl = sqrt(n_in[0] * n_in[0] + n_in[1] * n_in[1] + n_in[2] * n_in[2]);
    if (!(nl > 0) || !(lambda > 0) || !isfinite(lambda))
        return ss_error_set(err, SS_ERR_INPUT, "uniaxial GOH: bad axis or stretch %g", lambda);
    double n[3] = {n_in[0] / nl, n_in[1] / nl, n_in[2] / nl}, Q[9];
    axis_frame(n, Q);
    ss_mech_params q = *p; /* the fibres in the frame (n, t1, t2) */
    for (int f = 0; f < p->nfibres; f++)
        for (int i = 0; i < 3; i++)
            q.fibre[f][i] = Q[3 * i] * p->fibre[f][0] + Q[3 * i + 1] * p->fibre[f][1] +
                            Q[3 * i + 2] * p->fibre[f][2];
    double u[5] = {0, 0, 1 / sqrt(lambda), 0, 1 / sqrt(lambda)}, r[5], s11 = 0;
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
        for (int k = 2; k < 5; k += 2) /* keep the lateral stretches positive */
            while (u[k] + sc * dx[k] <= 0.05 * u[k]) sc *= 0.5;
        for (int k = 0; k < 5; k++) u[k] += sc * dx[k];
    }
    if (!ok)
        return ss_error_set(err, SS_ERR_INPUT,
                            "uniaxial GOH: no homogeneous state found at stretch %g", lambda);
    *sigma = s11;
    double F[9], lat[2], sh[2];
    ut_F(lambda, u, F);
    lateral_shear(F, lat, sh);
    if (lateral) memcpy(lateral, lat, sizeof lat);
    if (shear) memcpy(shear, sh, sizeof sh);
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

/* The reference-volume mean of the tets' deformation gradients at x (the
 * block's mean F, exact for a homogeneous state), in the frame (ax, e1,
 * e2) of the block's axes. */
static void mean_F(const ss_tetmesh *m, const double *x, int ax, double Fm[9]) {
    const int pm[3] = {ax, (ax + 1) % 3, (ax + 2) % 3};
    double S[9] = {0}, V = 0;
    for (int t = 0; t < m->ntets; t++) {
        const int32_t *v = m->tet + 4 * t;
        double D[9], d[9]; /* columns: reference and current edges from node 0 */
        for (int k = 0; k < 3; k++)
            for (int i = 0; i < 3; i++) {
                D[3 * i + k] = m->x[3 * v[k + 1] + pm[i]] - m->x[3 * v[0] + pm[i]];
                d[3 * i + k] = x[3 * v[k + 1] + pm[i]] - x[3 * v[0] + pm[i]];
            }
        double c[9], det = mat3_cofactors(D, c);
        /* F = d D^-1, D^-1 = c^T / det; weighted by the volume det/6: sum d c^T / 6 */
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                S[3 * i + j] +=
                    d[3 * i] * c[3 * j] + d[3 * i + 1] * c[3 * j + 1] + d[3 * i + 2] * c[3 * j + 2];
        V += det;
    }
    for (int i = 0; i < 9; i++) Fm[i] = S[i] / V;
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
    double R = 0;
    for (int i = 0; i < nn; i++)
        if (m->x[3 * i + ax] > L - eps) R -= f[3 * i + ax]; /* the grip pulls against the springs */
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
    double Fm[9], lat[2];
    mean_F(m, S->x, ax, Fm);
    lateral_shear(Fm, lat, res->shear);
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

/* The end faces' nodal areas (reference, mm^2: a third of each boundary
 * triangle's), negative on the low face; 0 elsewhere. */
static void end_areas(const ss_tetmesh *m, int ax, double L, double *area) {
    static const int fc[4][3] = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
    const double eps = 1e-9 * L;
    memset(area, 0, (size_t)m->nnodes * sizeof(double));
    for (int t = 0; t < m->ntets; t++)
        for (int f = 0; f < 4; f++) {
            const int32_t a = m->tet[4 * t + fc[f][0]], b = m->tet[4 * t + fc[f][1]],
                          c = m->tet[4 * t + fc[f][2]];
            const double *A = m->x + 3 * a, *B = m->x + 3 * b, *C = m->x + 3 * c;
            int lo = A[ax] < eps && B[ax] < eps && C[ax] < eps;
            int hi = A[ax] > L - eps && B[ax] > L - eps && C[ax] > L - eps;
            if (!lo && !hi) continue;
            double u[3], v[3];
            for (int d = 0; d < 3; d++) {
                u[d] = B[d] - A[d];
                v[d] = C[d] - A[d];
            }
            double w[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                           u[0] * v[1] - u[1] * v[0]};
            double s = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) / 6 * (hi ? 1 : -1);
            area[a] += s;
            area[b] += s;
            area[c] += s;
        }
}

/* the distance of the end faces' area-weighted mean positions along the
 * axis over the reference length */
static double end_stretch(const double *x, const double *area, int nn, int ax, double L) {
    double s = 0, a = 0;
    for (int i = 0; i < nn; i++) {
        s += area[i] * x[3 * i + ax];
        a += fabs(area[i]);
    }
    return s / (0.5 * a) / L;
}

/* Tension: dead load on the end faces, six pins; per increment a secant
 * iteration on the traction T (kPa) until the end faces are lambda apart.
 * The first guess of dT/dlambda is the small-strain stiffness with the
 * fibres along the axis (an upper bound: the stretch undershoots, and the
 * stiffening law keeps the secant from overshooting far). */
static ss_status pull_dead_load(ss_hyper *H, const ss_tetmesh *m, const ss_mech_params *p,
                                const ss_mech_stretch_config *c, double L, ss_hyper_report *rep,
                                int *conv, ss_error *err) {
    const int ax = c->axis, nn = m->nnodes, e1 = (ax + 1) % 3, e2 = (ax + 2) % 3;
    const double eps = 1e-9 * L;
    uint8_t *fx = ss_hyper_fixed(H);
    double *x = ss_hyper_x(H), *load = ss_hyper_load(H);
    int corner = -1, along = -1, next = -1;
    for (int i = 0; i < nn; i++) {
        const double *X = m->x + 3 * i;
        int o1 = X[e1] < eps, o2 = X[e2] < eps;
        if (X[ax] < eps && o1 && o2) corner = i;
        if (X[ax] > L - eps && o1 && o2) along = i;
        if (X[ax] < eps && X[e1] > L - eps && o2) next = i;
    }
    if (corner < 0 || along < 0 || next < 0)
        return ss_error_set(err, SS_ERR_INPUT, "mech stretch: block corners not found");
    fx[3 * corner] = fx[3 * corner + 1] = fx[3 * corner + 2] = 1;
    fx[3 * along + e1] = fx[3 * along + e2] = 1;
    fx[3 * next + e2] = 1;
    double *area = malloc((size_t)nn * sizeof(double));
    if (!area) return ss_error_set(err, SS_ERR_NOMEM, "mech stretch: out of memory");
    end_areas(m, ax, L, area);
    const double tol_s = 1e-11 * c->stretch;
    double T0 = 0, s0 = 1, slope = 9 * p->K_bulk * p->mu / (3 * p->K_bulk + p->mu) + 4 * p->k1_goh;
    ss_status st = SS_OK;
    *conv = 1;
    for (int k = 1; k <= c->increments && !st; k++) {
        const double lam = 1 + (c->stretch - 1) * k / c->increments;
        double Ta = T0, sa = s0, T = T0 + slope * (lam - s0), s = s0;
        double Tlo = T0, Thi = INFINITY; /* the bracket: stretch below, above lam */
        /* the increments before the last only lead the way there (never
         * tighter than the last: at stretch 1 their share would be 0, which
         * the rounding of the end stretch never meets) */
        const int last = k == c->increments;
        const double tol_k =
            last ? tol_s : fmax(tol_s, 1e-3 * fabs(c->stretch - 1) / c->increments);
        int found = 0, newton_ok = 0;
        for (int it = 0; it < 60 && !found && !st; it++) {
            for (int i = 0; i < nn; i++) load[3 * i + ax] = T * area[i];
            /* the warm start: the last state stretched affinely to lam */
            double sc = lam / end_stretch(x, area, nn, ax, L);
            for (int i = 0; i < nn; i++) x[3 * i + ax] *= sc;
            ss_hyper_report r1;
            /* the last solve tighter: the reaction's residual is the error left */
            st = ss_hyper_solve(H, last ? 1e-12 : 1e-10, 60, &r1, err);
            rep->newton += r1.newton;
            rep->cg += r1.cg;
            newton_ok = r1.converged;
            s = end_stretch(x, area, nn, ax, L);
            if (fabs(s - lam) <= tol_k) {
                found = 1;
                break;
            }
            if (s < lam)
                Tlo = fmax(Tlo, T);
            else
                Thi = fmin(Thi, T);
            double Tn = s != sa ? T + (lam - s) * (T - Ta) / (s - sa) : NAN;
            if (!(Tn > Tlo && Tn < Thi)) Tn = isfinite(Thi) ? 0.5 * (Tlo + Thi) : 2 * T - Tlo;
            if (fabs(Tn - T) <= 1e-15 * fabs(T)) break; /* the secant can do no better */
            Ta = T;
            sa = s;
            T = Tn;
        }
        *conv &= newton_ok && found;
        if (s != s0) slope = (T - T0) / (s - s0);
        T0 = T;
        s0 = s;
    }
    free(area);
    return st;
}

/* Compression: the low face slides on its plane (one corner held, one node
 * against the rotation about the axis), the high face is moved to lambda in
 * increments. */
static ss_status push_flat_ends(ss_hyper *H, const ss_tetmesh *m, const ss_mech_stretch_config *c,
                                double L, ss_hyper_report *rep, int *conv, ss_error *err) {
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
    if (corner < 0 || rot < 0)
        return ss_error_set(err, SS_ERR_INPUT, "mech stretch: block corners not found");
    fx[3 * corner + e1] = fx[3 * corner + e2] = 1;
    fx[3 * rot + e2] = 1;
    ss_status st = SS_OK;
    *conv = 1;
    for (int k = 1; k <= c->increments && !st; k++) {
        double lam = 1 + (c->stretch - 1) * k / c->increments,
               lp = 1 + (c->stretch - 1) * (k - 1) / c->increments;
        /* the increment's start: the last state stretched affinely along
         * the axis (a good guess, and the moving face at its place) */
        for (int i = 0; i < nn; i++) x[3 * i + ax] *= lam / lp;
        ss_hyper_report r1;
        st = ss_hyper_solve(H, 1e-10, 60, &r1, err);
        rep->newton += r1.newton;
        rep->cg += r1.cg;
        *conv &= r1.converged;
    }
    return st;
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
    n[c->axis] = 1; /* the analytic frame (n, t1, t2) is then the block's (ax, e1, e2) */
    if ((st = ss_mech_uniaxial_analytic(&p, n, c->stretch, &res->analytic_stress_kpa,
                                        res->analytic_lateral, res->analytic_shear, err)))
        return st;
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
    const int ax = c->axis, nn = m->nnodes;
    const double eps = 1e-9 * L;
    ss_hyper_report rep = {0, 0, 0, 0, 0, 0};
    int conv = 1;
    st = c->stretch >= 1 ? pull_dead_load(H, m, &p, c, L, &rep, &conv, err)
                         : push_flat_ends(H, m, c, L, &rep, &conv, err);
    if (!st) {
        double *f = malloc(3 * (size_t)nn * sizeof(double));
        if (!f) {
            st = ss_error_set(err, SS_ERR_NOMEM, "mech stretch: out of memory");
        } else {
            const double *x = ss_hyper_x(H);
            ss_hyper_tet_forces(H, f);
            double Rf = 0, sg[9], V, Fm[9];
            for (int i = 0; i < nn; i++)
                if (m->x[3 * i + ax] > L - eps) Rf -= f[3 * i + ax];
            ss_hyper_mean_cauchy(H, sg, &V);
            mean_F(m, x, ax, Fm);
            /* the current cross-section: volume over the axial length */
            res->stress_kpa = Rf / (V / (Fm[0] * L));
            res->mean_sigma_kpa = sg[4 * ax];
            lateral_shear(Fm, res->lateral_stretch, res->shear);
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
