/* Hyperelastic tet solver for the skin (GOH; docs/mech.md, "The GOH solver").
 *
 * What: the tissue as a continuum of linear (4-node) tets, each with the
 * Gasser-Ogden-Holzapfel 2006 energy (isochoric neo-Hookean ground substance
 * mu, a volumetric penalty K_bulk (J - 1)^2 / 2, one or two dispersed fibre
 * families k1_goh, k2, kappa) of the elastic part F_e = F G^-1 of its
 * deformation gradient. G is the tet's rest state from the biology (the
 * multiplicative split F = F_e G of growth and remodelling, Rodriguez, Hoger
 * and McCulloch 1994): the contraction the myofibroblasts lock in, and the
 * in vivo pre-stretch of intact skin. The myofibroblasts' pull is either a
 * constant isotropic Cauchy stress s I (energy s J per volume of the rest
 * state) or, with ss_hyper_set_active_law (the heal run), the seed's cell
 * law s p_cell(theta_a) as a tension in the skin's plane at the tet's areal
 * strain theta_a = J_a - 1 of the total deformation, J_a = |F e_x x F e_y|
 * (energy s V0 int p_cell, forces and tangent in the solve). Nodes carry an elastic
 * foundation (subcutis, far field), dead loads and springs (sutures).
 *
 * Why this way: the seed's mass-spring network is linear, isotropic and has
 * a Poisson ratio near zero whatever the parameters; the continuum gives the
 * material it claims (the uniaxial test of `skinsim mech stretch` matches
 * the closed-form GOH stress). Linear tets with G folded into the shape
 * gradients (F_e = sum_a x_a (x) beta_a G^-1, so growth costs nothing per
 * evaluation). Quasi-static Newton: the analytic tangent per tet (12 x 12 from
 * the 9 x 9 d^2W/dF^2), assembled into a 3x3-block CSR matrix by a gather in
 * a fixed order (each block sums its tets' contributions in tet order, so
 * the result is bit-identical for any thread count; no atomics), solved by
 * conjugate gradients with a two-level preconditioner (block-Jacobi plus a
 * coarse correction on the rigid modes of aggregates of nodes: the thick
 * block on its soft foundation has slow bending modes block-Jacobi alone
 * took hundreds of iterations for), stopped at the forcing tolerance or at
 * negative curvature (the active term and the fibres' switch make the
 * tangent indefinite away from the minimum; then the CG iterate so far is
 * still a descent direction, truncated Newton), and a backtracking (Armijo)
 * line search on the total energy, which is infinite for a folded tet, so no
 * accepted step folds one. The tangent and its preconditioner are kept from
 * iteration to iteration and frame to frame while the steps they give still
 * cut the gradient five-fold (a frame's load changes the tangent little);
 * the assembly was over half of a frame. ss_hyper_set_fast(h, 0) gives the
 * plain solver (block-Jacobi, fresh tangent each iteration), which the tests
 * compare with. Within the Newton tolerance but not the same bytes
 * (ss_hyper_set_tolerant, on by default; off is the solver before them): the
 * CG's matrix products read a float copy of the tangent (half the bytes of
 * the bandwidth-bound product; the residual and gradient stay in double),
 * the per-tet tangents are stored as floats (half the assembly's traffic),
 * a solve that starts where the last one ended starts from there moved by
 * the last one's change of positions if that folds no tet (a smooth load's
 * frames move alike, so Newton starts closer), and a Newton step under the tolerance
 * ends the solve without the line search's evaluation when it folds no tet.
 *
 * What it gave up: linear tets lock somewhat in near-incompressible bending
 * (the default K_bulk/mu = 2.1 is far from it); no sparse direct solver (no
 * packaged MIT/BSD one that is small), so ill-conditioned problems (stiff
 * fibres on a soft foundation) take many CG iterations; the stored per-tet
 * tangents cost 1.2 kB per tet. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/mech.h"
#include "mat3.h"

enum { SUMBLK = 4096 }; /* the fixed blocks of the dot products (fsum, cg) */

typedef struct mat {
    double mu, K, k1, k2, kappa;
    double K_pas, K_act, p_max, theta1, theta2; /* the cell pressure law */
    double a[2][3];
    int nf;
} mat;

struct ss_hyper {
    mat M;
    int nn, nt, ns, scap;
    double *X, *x, *xt;
    int32_t *tet;
    double *beta0, *V0; /* reference shape gradients (12 per tet), volume */
    double *beta, *Vg;  /* with G folded in: beta0 G^-1, V0 det G */
    double *G, *act, *scale;
    uint8_t *fib, *gdirty;
    double *anchor, *load;
    uint8_t *fixed;
    int32_t *se;
    double *srest, *sk;
    /* block CSR */
    int pattern_ok;
    int32_t *rowptr, *col, *diag;
    int nblk;
    double *val;
    int32_t *tblk;           /* per (tet * 16 + la * 4 + lb): its block */
    int32_t *nstart, *nlist; /* per node: (tet * 4 + la) in tet order */
    double *Kt, *gt, *et;    /* Kt: 144 per tet; tolerant: as floats (its first half) */
    double *Minv;
    double *g, *d, *r, *z, *p, *q;
    double *gtry;   /* the gradient at the line search's full step */
    double *cgpart; /* the CG's dot-product partials, 3 x ceil(3 nn / SUMBLK) */
    double mean_edge;
    /* two-level preconditioner: aggregates of nodes (spatial bins), their
     * rigid modes as the coarse space, the coarse matrix's Cholesky factor */
    int fast, nagg, nc, coarse_ok, tangent_ok, act_law;
    int32_t *agg, *astart, *alist;
    double *acen, *arho, ascale; /* arho: node offsets from the centroid / bin side */
    double *Ac, *Lc, *wc;        /* Ac: P^T A P, after the factoring L's transpose */
    int32_t *lband;              /* per coarse row: L's first and L^T's last nonzero */
    /* within the solver's tolerance (ss_hyper_set_tolerant): the matrix in
     * single precision for the CG's products, and the previous solve's
     * displacement as a predictor step */
    int tolerant, pred_ok;
    float *val32;         /* val rounded to float, for matvec */
    double *xend, *dprev; /* the last solve's end (then this one's start), its change */
};

/* ---- material ---------------------------------------------------------------- */

static void mat_from(mat *M, const ss_mech_params *p) {
    M->mu = p->mu;
    M->K = p->K_bulk;
    M->k1 = p->k1_goh;
    M->k2 = p->k2;
    M->kappa = p->kappa;
    M->nf = p->nfibres;
    memcpy(M->a, p->fibre, sizeof M->a);
    M->K_pas = p->K_pas;
    M->K_act = p->K_act;
    M->p_max = p->p_max;
    M->theta1 = p->theta1;
    M->theta2 = p->theta2;
}

/* The seed's cell pressure p_cell(th) (as ss_mech_pcell: K_pas th outside
 * [theta1, theta2], the active branch falling linearly from p_max at th* =
 * p_max/K_act to 0 at theta1 and theta2), its slope *dp and its integral
 * from 0 to th, *pint (continuous and piecewise linear, so the integral is
 * piecewise quadratic and C1). */
static double act_int(const mat *M, double u) { /* int_theta1^u of the active branch */
    const double ts = M->p_max / M->K_act, t1 = M->theta1, t2 = M->theta2;
    const double c1 = M->K_act * M->p_max / (M->K_act * t1 - M->p_max);
    const double c2 = M->K_act * M->p_max / (M->K_act * t2 - M->p_max);
    double v1 = u < t1 ? t1 : u > ts ? ts : u;
    double r = -0.5 * c1 * (v1 - t1) * (v1 - t1);
    if (u > ts) {
        double v2 = u > t2 ? t2 : u;
        r += 0.5 * c2 * ((t2 - ts) * (t2 - ts) - (t2 - v2) * (t2 - v2));
    }
    return r;
}

static double pcell_law(const mat *M, double th, double *dp, double *pint) {
    const double ts = M->p_max / M->K_act, t1 = M->theta1, t2 = M->theta2;
    double p = M->K_pas * th, d = M->K_pas;
    if (!(th < t1 || th > t2)) {
        if (th <= ts) {
            double c1 = M->K_act * M->p_max / (M->K_act * t1 - M->p_max);
            p += c1 * (t1 - th);
            d -= c1;
        } else {
            double c2 = M->K_act * M->p_max / (M->K_act * t2 - M->p_max);
            p += c2 * (t2 - th);
            d -= c2;
        }
    }
    *dp = d;
    *pint = 0.5 * M->K_pas * th * th + act_int(M, th) - act_int(M, 0.0);
    return p;
}

/* The in-plane active law (ss_hyper_set_active_law): energy per reference
 * volume W = s Pi(J_a - 1), Pi' = p_cell, of the total deformation F
 * (against the reference mesh, not F_e: the cells' strain since wounding,
 * the seed's theta), J_a = |F e_x x F e_y| the area stretch of the skin's
 * plane (Nanson: |cof(F) e_z|). Its Cauchy stress is s p_cell (J_a/J)
 * (I - n n), n the current normal of that plane: a tension in the plane of
 * the skin only. P (9) and H (81, or NULL) are d W/dF, d2W/dF2; F's third
 * column does not enter. */
static void skew(const double *v, double S[9]) {
    S[0] = 0, S[1] = -v[2], S[2] = v[1];
    S[3] = v[2], S[4] = 0, S[5] = -v[0];
    S[6] = -v[1], S[7] = v[0], S[8] = 0;
}

/* c = F e_x x F e_y, the skin's plane after F; returns J_a = |c| */
static double plane_normal(const double *F, double c[3]) {
    const double a[3] = {F[0], F[3], F[6]}, b[3] = {F[1], F[4], F[7]};
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
    return sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
}

static double planar_active(const mat *M, double s, const double *F, double *P, double *H) {
    const double a[3] = {F[0], F[3], F[6]}, b[3] = {F[1], F[4], F[7]};
    double c[3];
    const double Ja = plane_normal(F, c);
    if (!(Ja > 0)) return INFINITY;
    const double u[3] = {c[0] / Ja, c[1] / Ja, c[2] / Ja};
    double dp, pint, pc = pcell_law(M, Ja - 1.0, &dp, &pint);
    /* dJa/da = b x u, dJa/db = u x a */
    double ga[3] = {b[1] * u[2] - b[2] * u[1], b[2] * u[0] - b[0] * u[2],
                    b[0] * u[1] - b[1] * u[0]};
    double gb[3] = {u[1] * a[2] - u[2] * a[1], u[2] * a[0] - u[0] * a[2],
                    u[0] * a[1] - u[1] * a[0]};
    for (int i = 0; i < 9; i++) P[i] = 0;
    for (int i = 0; i < 3; i++) {
        P[3 * i] = s * pc * ga[i];
        P[3 * i + 1] = s * pc * gb[i];
    }
    if (H) {
        /* d2Ja: [aa] = [b](I-uu)(-[b])/Ja, [ab] = -[u] + [b](I-uu)[a]/Ja,
         * [bb] = -[a](I-uu)[a]/Ja (with [v] the cross-product matrix) */
        double A[9], B[9], U[9], Q[9];
        skew(a, A);
        skew(b, B);
        skew(u, U);
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) Q[3 * i + j] = ((i == j) - u[i] * u[j]) / Ja;
        double haa[9], hab[9], hbb[9];
        double QB[9], QA[9];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                QB[3 * i + j] = QA[3 * i + j] = 0;
                for (int k = 0; k < 3; k++) {
                    QB[3 * i + j] += Q[3 * i + k] * B[3 * k + j];
                    QA[3 * i + j] += Q[3 * i + k] * A[3 * k + j];
                }
            }
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double x1 = 0, x2 = 0, x3 = 0;
                for (int k = 0; k < 3; k++) {
                    x1 -= B[3 * i + k] * QB[3 * k + j];
                    x2 += B[3 * i + k] * QA[3 * k + j];
                    x3 -= A[3 * i + k] * QA[3 * k + j];
                }
                haa[3 * i + j] = x1;
                hab[3 * i + j] = x2 - U[3 * i + j];
                hbb[3 * i + j] = x3;
            }
        for (int k = 0; k < 81; k++) H[k] = 0;
        const double w2 = s * dp, w1 = s * pc;
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++) {
                /* F index (i, 0) = a_i, (i, 1) = b_i */
                int ia = 3 * i, ib = 3 * i + 1, ka = 3 * k, kb = 3 * k + 1;
                H[ia * 9 + ka] = w2 * ga[i] * ga[k] + w1 * haa[3 * i + k];
                H[ia * 9 + kb] = w2 * ga[i] * gb[k] + w1 * hab[3 * i + k];
                H[ib * 9 + ka] = w2 * gb[i] * ga[k] + w1 * hab[3 * k + i];
                H[ib * 9 + kb] = w2 * gb[i] * gb[k] + w1 * hbb[3 * i + k];
            }
    }
    return s * pint;
}

static double det3(const double *F) {
    return F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) +
           F[2] * (F[3] * F[7] - F[4] * F[6]);
}

/* cofactor matrix (J F^-T) */
static void cof3(const double *F, double *C) { (void)mat3_cofactors(F, C); }

/* W(F) of the GOH law (fibres when fib), P = dW/dF and H = d2W/dF2 (81,
 * H[(3i+j)*9 + 3k+l]); P, H may be NULL. s adds the active energy s J. */
static double goh(const mat *M, const double *F, int fib, double s, double *P, double *H) {
    const double J = det3(F);
    if (!(J > 0)) return INFINITY;
    double cf[9];
    cof3(F, cf); /* dJ/dF */
    double I1 = 0;
    for (int i = 0; i < 9; i++) I1 += F[i] * F[i];
    const double cJ = cbrt(J), J23 = 1.0 / (cJ * cJ), J53 = J23 / J, J83 = J53 / J;
    double W = 0.5 * M->mu * (J23 * I1 - 3.0) + 0.5 * M->K * (J - 1) * (J - 1) + s * J;
    const double f1 = 0.5 * M->mu * J23;
    const double fJ = -M->mu / 3.0 * J53 * I1 + M->K * (J - 1) + s;
    const double f1J = -M->mu / 3.0 * J53;
    const double fJJ = 5.0 * M->mu / 9.0 * J83 * I1 + M->K;
    double gE[2] = {0, 0}, gEE[2] = {0, 0}, dE[2][9];
    int on[2] = {0, 0};
    if (fib && M->k1 > 0)
        for (int f = 0; f < M->nf; f++) {
            const double *a = M->a[f];
            double Fa[3];
            for (int i = 0; i < 3; i++)
                Fa[i] = F[3 * i] * a[0] + F[3 * i + 1] * a[1] + F[3 * i + 2] * a[2];
            double I4 = Fa[0] * Fa[0] + Fa[1] * Fa[1] + Fa[2] * Fa[2];
            double E = M->kappa * I1 + (1 - 3 * M->kappa) * I4 - 1.0;
            if (!(E > 0)) continue;
            on[f] = 1;
            double ex = exp(M->k2 * E * E);
            W += M->k2 > 1e-12 ? M->k1 / (2 * M->k2) * expm1(M->k2 * E * E) : 0.5 * M->k1 * E * E;
            gE[f] = M->k1 * E * ex;
            gEE[f] = M->k1 * ex * (1 + 2 * M->k2 * E * E);
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++)
                    dE[f][3 * i + j] =
                        2 * M->kappa * F[3 * i + j] + 2 * (1 - 3 * M->kappa) * Fa[i] * a[j];
        }
    if (P) {
        for (int i = 0; i < 9; i++) P[i] = 2 * f1 * F[i] + fJ * cf[i];
        for (int f = 0; f < 2; f++)
            if (on[f])
                for (int i = 0; i < 9; i++) P[i] += gE[f] * dE[f][i];
    }
    if (H) {
        double Fi[9]; /* F^-1 = cof^T / J */
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) Fi[3 * i + j] = cf[3 * j + i] / J;
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                for (int k = 0; k < 3; k++)
                    for (int l = 0; l < 3; l++) {
                        int a = 3 * i + j, b = 3 * k + l;
                        /* d2J/dF_ij dF_kl = J (Fi_ji Fi_lk - Fi_jk Fi_li) */
                        double hJ =
                            J * (Fi[3 * j + i] * Fi[3 * l + k] - Fi[3 * j + k] * Fi[3 * l + i]);
                        double h = fJ * hJ + f1J * (2 * F[a] * cf[b] + cf[a] * 2 * F[b]) +
                                   fJJ * cf[a] * cf[b];
                        if (i == k && j == l) h += 2 * f1;
                        for (int f = 0; f < 2; f++) {
                            if (!on[f]) continue;
                            h += gEE[f] * dE[f][a] * dE[f][b];
                            if (i == k)
                                h += gE[f] * (2 * M->kappa * (j == l) +
                                              2 * (1 - 3 * M->kappa) * M->a[f][j] * M->a[f][l]);
                        }
                        H[a * 9 + b] = h;
                    }
    }
    return W;
}

double ss_hyper_goh_energy(const ss_mech_params *p, const double F[9], double P[9]) {
    mat M;
    mat_from(&M, p);
    return goh(&M, F, 1, 0.0, P, NULL);
}

void ss_hyper_goh_cauchy(const ss_mech_params *p, const double F[9], double sg[9]) {
    const double J = det3(F);
    double b[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            b[3 * i + j] =
                F[3 * i] * F[3 * j] + F[3 * i + 1] * F[3 * j + 1] + F[3 * i + 2] * F[3 * j + 2];
    const double I1 = b[0] + b[4] + b[8];
    for (int i = 0; i < 9; i++) sg[i] = p->mu * pow(J, -5.0 / 3.0) * b[i];
    for (int i = 0; i < 3; i++)
        sg[4 * i] += -p->mu * pow(J, -5.0 / 3.0) * I1 / 3.0 + p->K_bulk * (J - 1);
    for (int f = 0; f < p->nfibres; f++) {
        const double *a = p->fibre[f];
        double Fa[3];
        for (int i = 0; i < 3; i++)
            Fa[i] = F[3 * i] * a[0] + F[3 * i + 1] * a[1] + F[3 * i + 2] * a[2];
        double E = p->kappa * I1 +
                   (1 - 3 * p->kappa) * (Fa[0] * Fa[0] + Fa[1] * Fa[1] + Fa[2] * Fa[2]) - 1;
        if (!(E > 0) || !(p->k1_goh > 0)) continue;
        double dpsi = p->k1_goh * E * exp(p->k2 * E * E); /* dPsi/dE */
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                sg[3 * i + j] +=
                    2.0 / J * dpsi * (p->kappa * b[3 * i + j] + (1 - 3 * p->kappa) * Fa[i] * Fa[j]);
    }
}

/* ---- set-up -------------------------------------------------------------------- */

void ss_hyper_free(ss_hyper *h) {
    if (!h) return;
    void *ptrs[] = {
        h->X,     h->x,      h->xt,    h->tet,    h->beta0,  h->V0,   h->beta,   h->Vg,    h->G,
        h->act,   h->scale,  h->fib,   h->gdirty, h->anchor, h->load, h->fixed,  h->se,    h->srest,
        h->sk,    h->rowptr, h->col,   h->diag,   h->val,    h->tblk, h->nstart, h->nlist, h->Kt,
        h->gt,    h->et,     h->Minv,  h->g,      h->d,      h->r,    h->z,      h->p,     h->q,
        h->agg,   h->astart, h->alist, h->acen,   h->arho,   h->Ac,   h->Lc,     h->wc,    h->gtry,
        h->lband, h->cgpart, h->val32, h->xend,   h->dprev};
    for (size_t i = 0; i < sizeof ptrs / sizeof ptrs[0]; i++) free(ptrs[i]);
    free(h);
}

/* 3x3 inverse; returns the determinant */
static double inv3(const double *A, double *B) {
    double c[9];
    cof3(A, c);
    double d = det3(A);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) B[3 * i + j] = c[3 * j + i] / d;
    return d;
}

ss_hyper *ss_hyper_create(const ss_tetmesh *m, const ss_mech_params *p, ss_error *err) {
    if (!m || m->nnodes < 4 || m->ntets < 1) {
        ss_error_set(err, SS_ERR_INPUT, "hyperelastic solver: empty mesh");
        return NULL;
    }
    ss_hyper *h = calloc(1, sizeof *h);
    if (!h) goto nomem;
    mat_from(&h->M, p);
    const int nn = h->nn = m->nnodes, nt = h->nt = m->ntets;
    const size_t n3 = 3 * (size_t)nn;
    h->X = malloc(n3 * sizeof(double));
    h->x = malloc(n3 * sizeof(double));
    h->xt = malloc(n3 * sizeof(double));
    h->tet = malloc(4 * (size_t)nt * sizeof(int32_t));
    h->beta0 = malloc(12 * (size_t)nt * sizeof(double));
    h->beta = malloc(12 * (size_t)nt * sizeof(double));
    h->V0 = malloc((size_t)nt * sizeof(double));
    h->Vg = malloc((size_t)nt * sizeof(double));
    h->G = malloc(9 * (size_t)nt * sizeof(double));
    h->act = calloc((size_t)nt, sizeof(double));
    h->scale = malloc((size_t)nt * sizeof(double));
    h->fib = malloc((size_t)nt);
    h->gdirty = malloc((size_t)nt);
    h->anchor = calloc((size_t)nn, sizeof(double));
    h->load = calloc(n3, sizeof(double));
    h->fixed = calloc(n3, 1);
    h->gt = malloc(12 * (size_t)nt * sizeof(double));
    h->et = malloc((size_t)nt * sizeof(double));
    h->Minv = malloc(9 * (size_t)nn * sizeof(double));
    h->g = malloc(n3 * sizeof(double));
    h->gtry = malloc(n3 * sizeof(double));
    h->d = malloc(n3 * sizeof(double));
    h->r = malloc(n3 * sizeof(double));
    h->z = malloc(n3 * sizeof(double));
    h->p = malloc(n3 * sizeof(double));
    h->q = malloc(n3 * sizeof(double));
    h->cgpart = malloc(3 * ((n3 + SUMBLK - 1) / SUMBLK) * sizeof(double));
    h->xend = malloc(n3 * sizeof(double));
    h->dprev = malloc(n3 * sizeof(double));
    if (!h->X || !h->x || !h->xt || !h->tet || !h->beta0 || !h->beta || !h->V0 || !h->Vg || !h->G ||
        !h->act || !h->scale || !h->fib || !h->gdirty || !h->anchor || !h->load || !h->fixed ||
        !h->gt || !h->et || !h->Minv || !h->g || !h->gtry || !h->d || !h->r || !h->z || !h->p ||
        !h->q || !h->cgpart || !h->xend || !h->dprev)
        goto nomem;
    memcpy(h->X, m->x, n3 * sizeof(double));
    memcpy(h->x, m->x, n3 * sizeof(double));
    memcpy(h->tet, m->tet, 4 * (size_t)nt * sizeof(int32_t));
    double esum = 0;
    for (int t = 0; t < nt; t++) {
        const int32_t *q = h->tet + 4 * t;
        double D[9], B[9];
        for (int c = 0; c < 3; c++)
            for (int i = 0; i < 3; i++) D[3 * i + c] = h->X[3 * q[c + 1] + i] - h->X[3 * q[0] + i];
        double det = inv3(D, B);
        if (!(det > 0)) {
            ss_error_set(err, SS_ERR_INPUT, "hyperelastic solver: tet %d is degenerate or inverted",
                         t + 1);
            goto fail;
        }
        h->V0[t] = det / 6.0;
        double *be = h->beta0 + 12 * (size_t)t;
        for (int j = 0; j < 3; j++) {
            be[j] = -(B[j] + B[3 + j] + B[6 + j]);
            for (int c = 0; c < 3; c++) be[3 * (c + 1) + j] = B[3 * c + j];
        }
        for (int k = 1; k < 4; k++)
            esum += sqrt(D[k - 1] * D[k - 1] + D[k + 2] * D[k + 2] + D[k + 5] * D[k + 5]);
        static const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        memcpy(h->G + 9 * (size_t)t, I, sizeof I);
        h->scale[t] = 1.0;
        h->fib[t] = 1;
        h->gdirty[t] = 1;
    }
    h->mean_edge = esum / (3.0 * nt);
    h->fast = 1;
    h->tolerant = 1;
    return h;
nomem:
    ss_error_set(err, SS_ERR_NOMEM, "hyperelastic solver: out of memory");
fail:
    ss_hyper_free(h);
    return NULL;
}

void ss_hyper_set_fast(ss_hyper *h, int on) { h->fast = on != 0; }
void ss_hyper_set_tolerant(ss_hyper *h, int on) {
    h->tolerant = on != 0;
    h->tangent_ok = 0; /* val32 is filled by the assembly */
    h->pred_ok = 0;
}
void ss_hyper_set_active_law(ss_hyper *h, int on) {
    h->act_law = on != 0;
    h->tangent_ok = 0;
}

int ss_hyper_nodes(const ss_hyper *h) { return h->nn; }
int ss_hyper_tets(const ss_hyper *h) { return h->nt; }
double *ss_hyper_x(ss_hyper *h) { return h->x; }
const double *ss_hyper_X(const ss_hyper *h) { return h->X; }
double *ss_hyper_growth(ss_hyper *h) {
    memset(h->gdirty, 1, (size_t)h->nt); /* the caller may change any G */
    return h->G;
}
double *ss_hyper_active(ss_hyper *h) { return h->act; }
double *ss_hyper_scale(ss_hyper *h) { return h->scale; }
uint8_t *ss_hyper_fibres_on(ss_hyper *h) { return h->fib; }
double *ss_hyper_anchor(ss_hyper *h) { return h->anchor; }
double *ss_hyper_load(ss_hyper *h) { return h->load; }
uint8_t *ss_hyper_fixed(ss_hyper *h) { return h->fixed; }

int ss_hyper_add_spring(ss_hyper *h, int a, int b, double rest, double k, ss_error *err) {
    if (a < 0 || b < 0 || a >= h->nn || b >= h->nn || a == b) {
        ss_error_set(err, SS_ERR_INPUT, "hyperelastic solver: spring %d-%d: bad nodes", a, b);
        return -1;
    }
    if (h->ns == h->scap) {
        int cap = h->scap ? 2 * h->scap : 16;
        int32_t *se = realloc(h->se, 2 * (size_t)cap * sizeof(int32_t));
        if (se) h->se = se;
        double *sr = realloc(h->srest, (size_t)cap * sizeof(double));
        if (sr) h->srest = sr;
        double *sk = realloc(h->sk, (size_t)cap * sizeof(double));
        if (sk) h->sk = sk;
        if (!se || !sr || !sk) {
            ss_error_set(err, SS_ERR_NOMEM, "hyperelastic solver: out of memory");
            return -1;
        }
        h->scap = cap;
    }
    h->se[2 * h->ns] = a;
    h->se[2 * h->ns + 1] = b;
    h->srest[h->ns] = rest;
    h->sk[h->ns] = k;
    h->pattern_ok = 0;
    return h->ns++;
}

void ss_hyper_set_spring(ss_hyper *h, int i, double rest, double k) {
    if (i < 0 || i >= h->ns) return;
    if (h->sk[i] != k || h->srest[i] != rest) /* a stitch cut: fresh tangent, no predictor */
        h->tangent_ok = h->pred_ok = 0;
    h->srest[i] = rest;
    h->sk[i] = k;
}

static int cmp_i32(const void *a, const void *b) {
    int32_t x = *(const int32_t *)a, y = *(const int32_t *)b;
    return x < y ? -1 : x > y;
}

static int find_blk(const ss_hyper *h, int a, int b) {
    int lo = h->rowptr[a], hi = h->rowptr[a + 1] - 1;
    while (lo <= hi) {
        int mid = (lo + hi) / 2;
        if (h->col[mid] == b) return mid;
        if (h->col[mid] < b)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    return -1;
}

/* The block pattern (tets and springs), the tet -> block gather lists and
 * the node -> tet lists. */
static ss_status build_aggregates(ss_hyper *h);
static ss_status build_pattern(ss_hyper *h) {
    const int nn = h->nn, nt = h->nt;
    free(h->rowptr);
    free(h->col);
    free(h->diag);
    free(h->val);
    free(h->tblk);
    free(h->nstart);
    free(h->nlist);
    free(h->Kt);
    free(h->val32);
    h->rowptr = h->col = h->diag = h->tblk = h->nstart = h->nlist = NULL;
    h->val = h->Kt = NULL;
    h->val32 = NULL;
    /* node -> (tet, local) */
    h->nstart = calloc((size_t)nn + 1, sizeof(int32_t));
    h->nlist = malloc(4 * (size_t)nt * sizeof(int32_t));
    if (!h->nstart || !h->nlist) return SS_ERR_NOMEM;
    for (int t = 0; t < 4 * nt; t++) h->nstart[h->tet[t] + 1]++;
    for (int i = 0; i < nn; i++) h->nstart[i + 1] += h->nstart[i];
    int32_t *fill = malloc((size_t)nn * sizeof(int32_t));
    if (!fill) return SS_ERR_NOMEM;
    memcpy(fill, h->nstart, (size_t)nn * sizeof(int32_t));
    for (int t = 0; t < 4 * nt; t++) h->nlist[fill[h->tet[t]]++] = t;
    /* neighbours per node: candidate list, sorted, unique */
    int32_t *cnt = calloc((size_t)nn + 1, sizeof(int32_t));
    if (!cnt) {
        free(fill);
        return SS_ERR_NOMEM;
    }
    for (int i = 0; i < nn; i++) cnt[i + 1] = 4 * (h->nstart[i + 1] - h->nstart[i]) + 1;
    for (int s = 0; s < h->ns; s++) {
        cnt[h->se[2 * s] + 1]++;
        cnt[h->se[2 * s + 1] + 1]++;
    }
    for (int i = 0; i < nn; i++) cnt[i + 1] += cnt[i];
    int32_t *cand = malloc((size_t)cnt[nn] * sizeof(int32_t));
    if (!cand) {
        free(fill);
        free(cnt);
        return SS_ERR_NOMEM;
    }
    memcpy(fill, cnt, (size_t)nn * sizeof(int32_t));
    for (int i = 0; i < nn; i++) {
        cand[fill[i]++] = i;
        for (int k = h->nstart[i]; k < h->nstart[i + 1]; k++) {
            const int32_t *q = h->tet + 4 * (h->nlist[k] / 4);
            for (int l = 0; l < 4; l++) cand[fill[i]++] = q[l];
        }
    }
    for (int s = 0; s < h->ns; s++) {
        int a = h->se[2 * s], b = h->se[2 * s + 1];
        cand[fill[a]++] = b;
        cand[fill[b]++] = a;
    }
    h->rowptr = calloc((size_t)nn + 1, sizeof(int32_t));
    if (!h->rowptr) {
        free(fill);
        free(cnt);
        free(cand);
        return SS_ERR_NOMEM;
    }
    int total = 0;
    for (int i = 0; i < nn; i++) {
        int32_t *c = cand + cnt[i];
        int k = cnt[i + 1] - cnt[i], u = 0;
        qsort(c, (size_t)k, sizeof *c, cmp_i32);
        for (int j = 0; j < k; j++)
            if (j == 0 || c[j] != c[j - 1]) c[u++] = c[j];
        h->rowptr[i + 1] = h->rowptr[i] + u;
        total += u;
    }
    h->nblk = total;
    h->col = malloc((size_t)total * sizeof(int32_t));
    h->diag = malloc((size_t)nn * sizeof(int32_t));
    h->val = malloc(9 * (size_t)total * sizeof(double));
    h->tblk = malloc(16 * (size_t)nt * sizeof(int32_t));
    h->Kt = malloc(144 * (size_t)nt * sizeof(double));
    h->val32 = malloc(9 * (size_t)total * sizeof(float));
    if (!h->col || !h->diag || !h->val || !h->tblk || !h->Kt || !h->val32) {
        free(fill);
        free(cnt);
        free(cand);
        return SS_ERR_NOMEM;
    }
    for (int i = 0; i < nn; i++) {
        int u = h->rowptr[i + 1] - h->rowptr[i];
        memcpy(h->col + h->rowptr[i], cand + cnt[i], (size_t)u * sizeof(int32_t));
    }
    free(cand);
    free(cnt);
    free(fill);
    for (int i = 0; i < nn; i++) h->diag[i] = find_blk(h, i, i);
    /* each tet's 16 blocks (the assembly walks a node's tets in tet order,
     * so each block sums its tets' contributions in tet order) */
    for (int t = 0; t < nt; t++)
        for (int a = 0; a < 4; a++)
            for (int b = 0; b < 4; b++)
                h->tblk[16 * (size_t)t + 4 * a + b] =
                    find_blk(h, h->tet[4 * t + a], h->tet[4 * t + b]);
    if (build_aggregates(h) != SS_OK) return SS_ERR_NOMEM;
    h->tangent_ok = 0;
    h->pattern_ok = 1;
    return SS_OK;
}

/* The coarse space of the two-level preconditioner: the nodes binned into
 * cubes of AGG_EDGES mean edges over the reference bounding box (occupied
 * bins only, numbered in bin order; nodes in node order), each aggregate's
 * coarse dofs its three translations and three small rotations about its
 * centroid (the slow modes block-Jacobi leaves alone: the block moving and
 * bending on its soft foundation). */
enum { AGG_EDGES = 4 };
static ss_status build_aggregates(ss_hyper *h) {
    const int nn = h->nn;
    free(h->agg);
    free(h->astart);
    free(h->alist);
    free(h->acen);
    free(h->arho);
    free(h->Ac);
    free(h->lband);
    free(h->Lc);
    free(h->wc);
    h->agg = h->astart = h->alist = NULL;
    h->acen = h->arho = h->Ac = h->Lc = h->wc = NULL;
    h->lband = NULL;
    h->nagg = h->nc = h->coarse_ok = 0;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < nn; i++)
        for (int d = 0; d < 3; d++) {
            lo[d] = fmin(lo[d], h->X[3 * i + d]);
            hi[d] = fmax(hi[d], h->X[3 * i + d]);
        }
    const double side = AGG_EDGES * h->mean_edge;
    int nb[3];
    for (int d = 0; d < 3; d++) {
        double c = floor((hi[d] - lo[d]) / side) + 1;
        nb[d] = c > 64 ? 64 : (int)c; /* at most 64^3 bins */
    }
    const size_t nbins = (size_t)nb[0] * nb[1] * nb[2];
    int32_t *bin = malloc((size_t)nn * sizeof(int32_t));
    int32_t *idx = malloc(nbins * sizeof(int32_t));
    h->agg = malloc((size_t)nn * sizeof(int32_t));
    h->alist = malloc((size_t)nn * sizeof(int32_t));
    if (!bin || !idx || !h->agg || !h->alist) {
        free(bin);
        free(idx);
        return SS_ERR_NOMEM;
    }
    for (size_t b = 0; b < nbins; b++) idx[b] = -1;
    for (int i = 0; i < nn; i++) {
        size_t b = 0;
        for (int d = 2; d >= 0; d--) {
            int c = (int)((h->X[3 * i + d] - lo[d]) / (hi[d] - lo[d] + 1e-300) * nb[d]);
            if (c < 0) c = 0;
            if (c >= nb[d]) c = nb[d] - 1;
            b = b * nb[d] + (size_t)c;
        }
        bin[i] = (int32_t)b;
        idx[b] = 0;
    }
    int na = 0;
    for (size_t b = 0; b < nbins; b++)
        if (idx[b] == 0) idx[b] = na++;
    h->nagg = na;
    h->nc = 6 * na;
    h->astart = calloc((size_t)na + 1, sizeof(int32_t));
    h->acen = calloc(3 * (size_t)na, sizeof(double));
    h->arho = malloc(3 * (size_t)nn * sizeof(double));
    h->Ac = malloc((size_t)h->nc * h->nc * sizeof(double));
    h->lband = malloc(2 * (size_t)h->nc * sizeof(int32_t));
    h->Lc = malloc((size_t)h->nc * h->nc * sizeof(double));
    h->wc = malloc(2 * (size_t)h->nc * sizeof(double));
    if (!h->astart || !h->acen || !h->arho || !h->Ac || !h->Lc || !h->wc || !h->lband) {
        free(bin);
        free(idx);
        return SS_ERR_NOMEM;
    }
    for (int i = 0; i < nn; i++) {
        int a = h->agg[i] = idx[bin[i]];
        h->astart[a + 1]++;
        for (int d = 0; d < 3; d++) h->acen[3 * a + d] += h->X[3 * i + d];
    }
    for (int a = 0; a < na; a++) {
        for (int d = 0; d < 3; d++) h->acen[3 * a + d] /= h->astart[a + 1];
        h->astart[a + 1] += h->astart[a];
    }
    memcpy(bin, h->astart, (size_t)na * sizeof(int32_t)); /* fill pointers */
    for (int i = 0; i < nn; i++) h->alist[bin[h->agg[i]]++] = i;
    h->ascale = 1.0 / side;
    for (int i = 0; i < nn; i++)
        for (int d = 0; d < 3; d++)
            h->arho[3 * i + d] = (h->X[3 * i + d] - h->acen[3 * h->agg[i] + d]) * h->ascale;
    free(bin);
    free(idx);
    return SS_OK;
}

/* P_i (3 x 6) of node i: translations, rotations (e_k x r, r in bins); fixed
 * dofs' rows zero */
static void prolong_block(const ss_hyper *h, int i, double *P) {
    const double *r = h->arho + 3 * (size_t)i;
    const double v[18] = {1,     0, 0,    0, r[2], -r[1], 0,    1,     0,
                          -r[2], 0, r[0], 0, 0,    1,     r[1], -r[0], 0};
    memcpy(P, v, sizeof v);
    for (int d = 0; d < 3; d++)
        if (h->fixed[3 * i + d])
            for (int c = 0; c < 6; c++) P[6 * d + c] = 0;
}

/* A_c = P^T A P (each aggregate's rows by one thread, in node and block
 * order), then its Cholesky factor; a pivot below 1e-10 of its diagonal
 * (a rotation of a flat or tiny aggregate, a fully fixed one) or negative
 * (an indefinite tangent) drops that coarse dof. */
static void coarse_build(ss_hyper *h) {
    const int nc = h->nc;
    double *A = h->Ac;
#pragma omp parallel for schedule(dynamic, 1)
    for (int I = 0; I < h->nagg; I++) {
        double *row = A + (size_t)6 * I * nc;
        memset(row, 0, 6 * (size_t)nc * sizeof(double));
        for (int s = h->astart[I]; s < h->astart[I + 1]; s++) {
            const int i = h->alist[s];
            double Pi[18];
            prolong_block(h, i, Pi);
            for (int k = h->rowptr[i]; k < h->rowptr[i + 1]; k++) {
                const int j = h->col[k], J = h->agg[j];
                const double *B = h->val + 9 * (size_t)k;
                double Pj[18], T[18];
                prolong_block(h, j, Pj);
                for (int r = 0; r < 3; r++)
                    for (int c = 0; c < 6; c++)
                        T[6 * r + c] =
                            B[3 * r] * Pj[c] + B[3 * r + 1] * Pj[6 + c] + B[3 * r + 2] * Pj[12 + c];
                for (int r = 0; r < 6; r++)
                    for (int c = 0; c < 6; c++)
                        row[(size_t)r * nc + 6 * J + c] +=
                            Pi[r] * T[c] + Pi[6 + r] * T[6 + c] + Pi[12 + r] * T[12 + c];
            }
        }
    }
    double *L = h->Lc;
    memcpy(L, A, (size_t)nc * nc * sizeof(double));
    for (int j = 0; j < nc; j++) {
        double *Lj = L + (size_t)j * nc;
        double dj = Lj[j];
        for (int k = 0; k < j; k++) dj -= Lj[k] * Lj[k];
        if (!(dj > 1e-10 * fabs(A[(size_t)j * nc + j]))) {
            for (int k = 0; k <= j; k++) Lj[k] = 0; /* dropped */
            for (int i = j + 1; i < nc; i++) L[(size_t)i * nc + j] = 0;
            continue;
        }
        const double ljj = sqrt(dj);
        Lj[j] = ljj;
#pragma omp parallel for schedule(static) if (nc - j > 256)
        for (int i = j + 1; i < nc; i++) {
            double *Li = L + (size_t)i * nc;
            double s = Li[j];
            for (int k = 0; k < j; k++) s -= Li[k] * Lj[k];
            Li[j] = s / ljj;
        }
    }
    /* for the solves: L^T (over A, no longer needed) so the backward pass
     * reads rows too, and each row's band (the entries outside it are exact
     * zeros: the factor fills only within the matrix's envelope) */
    int32_t *first = h->lband, *last = h->lband + nc;
    for (int i = 0; i < nc; i++) {
        const double *Li = L + (size_t)i * nc;
        int f = 0;
        while (f < i && Li[f] == 0) f++;
        first[i] = f;
        for (int k = 0; k < nc; k++) A[(size_t)k * nc + i] = Li[k];
    }
    for (int i = 0; i < nc; i++) {
        const double *Ti = A + (size_t)i * nc;
        int l = nc - 1;
        while (l > i && Ti[l] == 0) l--;
        last[i] = l;
    }
    h->coarse_ok = 1;
}

/* z += P A_c^-1 P^T r; P^T r per node is (r, rho x r), P (t, th) is t +
 * th x rho (fixed dofs masked). In three parts so that the CG's single
 * parallel region can call them (their loops are orphaned omp for: called
 * outside a parallel region they run on one thread): the restriction to
 * h->wc, the coarse solves on it (one thread), the prolongation of one dof. */
static void coarse_restrict(const ss_hyper *h, const double *r) {
    double *w = h->wc;
#pragma omp for schedule(static)
    for (int I = 0; I < h->nagg; I++) {
        double s[6] = {0, 0, 0, 0, 0, 0};
        for (int t = h->astart[I]; t < h->astart[I + 1]; t++) {
            const int i = h->alist[t];
            const double *p = h->arho + 3 * (size_t)i;
            double v[3];
            for (int d = 0; d < 3; d++) v[d] = h->fixed[3 * i + d] ? 0 : r[3 * i + d];
            s[0] += v[0];
            s[1] += v[1];
            s[2] += v[2];
            s[3] += p[1] * v[2] - p[2] * v[1];
            s[4] += p[2] * v[0] - p[0] * v[2];
            s[5] += p[0] * v[1] - p[1] * v[0];
        }
        memcpy(w + 6 * I, s, sizeof s);
    }
}

static void coarse_solve(const ss_hyper *h) {
    const int nc = h->nc;
    double *w = h->wc, *y = h->wc + nc;
    const double *L = h->Lc, *Lt = h->Ac;
    const int32_t *first = h->lband, *last = h->lband + nc;
    for (int i = 0; i < nc; i++) { /* L y = w */
        const double *Li = L + (size_t)i * nc;
        if (!(Li[i] > 0)) {
            y[i] = 0;
            continue;
        }
        double s = w[i];
        for (int k = first[i]; k < i; k++) s -= Li[k] * y[k];
        y[i] = s / Li[i];
    }
    for (int i = nc - 1; i >= 0; i--) { /* L^T w = y */
        const double *Ti = Lt + (size_t)i * nc;
        const double lii = Ti[i];
        if (!(lii > 0)) {
            w[i] = 0;
            continue;
        }
        double s = y[i];
        for (int k = i + 1; k <= last[i]; k++) s -= Ti[k] * w[k];
        w[i] = s / lii;
    }
}

/* the coarse correction of dof d of node i (not fixed) */
static double coarse_dof(const ss_hyper *h, int i, int d) {
    const double *c = h->wc + 6 * h->agg[i], *p = h->arho + 3 * (size_t)i;
    switch (d) {
    case 0:
        return c[0] + c[4] * p[2] - c[5] * p[1];
    case 1:
        return c[1] + c[5] * p[0] - c[3] * p[2];
    default:
        return c[2] + c[3] * p[1] - c[4] * p[0];
    }
}

static void coarse_apply(const ss_hyper *h, const double *r, double *z) {
#pragma omp parallel
    {
        coarse_restrict(h, r);
#pragma omp single
        coarse_solve(h);
#pragma omp for schedule(static)
        for (int i = 0; i < h->nn; i++)
            for (int d = 0; d < 3; d++)
                if (!h->fixed[3 * i + d]) z[3 * i + d] += coarse_dof(h, i, d);
    }
}

/* ---- evaluation ---------------------------------------------------------------- */

static void update_growth(ss_hyper *h) {
#pragma omp parallel for schedule(static)
    for (int t = 0; t < h->nt; t++) {
        if (!h->gdirty[t]) continue;
        double Gi[9];
        double dg = inv3(h->G + 9 * (size_t)t, Gi);
        const double *b0 = h->beta0 + 12 * (size_t)t;
        double *b = h->beta + 12 * (size_t)t;
        for (int a = 0; a < 4; a++)
            for (int j = 0; j < 3; j++)
                b[3 * a + j] =
                    b0[3 * a] * Gi[j] + b0[3 * a + 1] * Gi[3 + j] + b0[3 * a + 2] * Gi[6 + j];
        h->Vg[t] = h->V0[t] * dg;
        h->gdirty[t] = 0;
    }
}

/* sum_a x_a (x) b_a over the tet's four nodes q: a deformation gradient
 * from the shape gradients b (12) */
static void nodes_F(const int32_t *q, const double *b, const double *x, double F[9]) {
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            F[3 * i + j] = x[3 * q[0] + i] * b[j] + x[3 * q[1] + i] * b[3 + j] +
                           x[3 * q[2] + i] * b[6 + j] + x[3 * q[3] + i] * b[9 + j];
}

/* F_e of tet t at positions x (the grown tet's shape gradients) */
static void tet_F(const ss_hyper *h, int t, const double *x, double *F) {
    nodes_F(h->tet + 4 * t, h->beta + 12 * (size_t)t, x, F);
}

/* adds w P and w H mapped with the shape gradients b (12) to the tet's
 * gradient g (12) and tangent K (144, or NULL) */
static void map_tet(const double *b, double w, const double *P, const double *H, double *g,
                    double *K) {
    for (int a = 0; a < 4; a++)
        for (int i = 0; i < 3; i++)
            g[3 * a + i] += w * (P[3 * i] * b[3 * a] + P[3 * i + 1] * b[3 * a + 1] +
                                 P[3 * i + 2] * b[3 * a + 2]);
    if (!K) return;
    double Mx[12][9]; /* Mx[(a,i)][(k,l)] = sum_j b_aj H(ij,kl) */
    for (int a = 0; a < 4; a++)
        for (int i = 0; i < 3; i++)
            for (int kl = 0; kl < 9; kl++)
                Mx[3 * a + i][kl] = b[3 * a] * H[(3 * i) * 9 + kl] +
                                    b[3 * a + 1] * H[(3 * i + 1) * 9 + kl] +
                                    b[3 * a + 2] * H[(3 * i + 2) * 9 + kl];
    for (int r = 0; r < 12; r++)
        for (int bb = 0; bb < 4; bb++)
            for (int k = 0; k < 3; k++)
                K[r * 12 + 3 * bb + k] +=
                    w * (Mx[r][3 * k] * b[3 * bb] + Mx[r][3 * k + 1] * b[3 * bb + 1] +
                         Mx[r][3 * k + 2] * b[3 * bb + 2]);
}

/* the total deformation gradient of tet t at x, against the reference mesh
 * (the in-plane active law's F, not F_e) */
static void tet_F_total(const ss_hyper *h, int t, const double *x, double F[9]) {
    nodes_F(h->tet + 4 * t, h->beta0 + 12 * (size_t)t, x, F);
}

/* mode 0: energies; 1: + gradients; 2: + tangents */
static void eval_tets(ss_hyper *h, const double *x, int mode) {
    update_growth(h);
#pragma omp parallel for schedule(static)
    for (int t = 0; t < h->nt; t++) {
        double F[9], P[9], H[81];
        tet_F(h, t, x, F);
        const double c = h->scale[t], V = h->Vg[t], s = h->act[t];
        const int law = h->act_law && s != 0;
        /* c W(F_e) + s J_e: the active energy is not scaled by the stiffness */
        double W =
            goh(&h->M, F, h->fib[t], law ? 0.0 : s / c, mode ? P : NULL, mode == 2 ? H : NULL);
        double Wa = 0, Pa[9], Ha[81], Ft[9];
        if (law && isfinite(W)) { /* the in-plane law on the total F */
            tet_F_total(h, t, x, Ft);
            Wa = planar_active(&h->M, s, Ft, Pa, mode == 2 ? Ha : NULL);
        }
        h->et[t] = V * c * W + h->V0[t] * Wa;
        if (!mode) continue;
        double *g = h->gt + 12 * (size_t)t;
        double Kl[144], *K = mode != 2 ? NULL : h->tolerant ? Kl : h->Kt + 144 * (size_t)t;
        for (int k = 0; k < 12; k++) g[k] = 0;
        if (K) memset(K, 0, 144 * sizeof(double));
        if (isfinite(h->et[t])) {
            map_tet(h->beta + 12 * (size_t)t, V * c, P, H, g, K);
            if (law) map_tet(h->beta0 + 12 * (size_t)t, h->V0[t], Pa, Ha, g, K);
        }
        if (K == Kl) { /* the tolerant tangent is kept in single precision */
            float *Kf = (float *)h->Kt + 144 * (size_t)t;
            for (int k = 0; k < 144; k++) Kf[k] = (float)Kl[k];
        }
    }
}

/* fixed-order sums: partial sums per block of SUMBLK in parallel, then a
 * serial sum of the partials (the same for any thread count) */
static double fsum(const double *a, const double *b, size_t n) {
    size_t nb = (n + SUMBLK - 1) / SUMBLK;
    double stack[256], *part = nb <= 256 ? stack : malloc(nb * sizeof(double));
    if (!part) part = stack, nb = 0; /* out of memory: the serial sum below */
    if (nb == 0) {
        double s = 0;
        for (size_t i = 0; i < n; i++) s += b ? a[i] * b[i] : a[i];
        return s;
    }
#pragma omp parallel for schedule(static)
    for (size_t k = 0; k < nb; k++) {
        size_t lo = k * SUMBLK, hi = lo + SUMBLK < n ? lo + SUMBLK : n;
        double s = 0;
        for (size_t i = lo; i < hi; i++) s += b ? a[i] * b[i] : a[i];
        part[k] = s;
    }
    double s = 0;
    for (size_t k = 0; k < nb; k++) s += part[k];
    if (part != stack) free(part);
    return s;
}

static double spring_energy(const ss_hyper *h, const double *x, double *g) {
    double E = 0;
    for (int s = 0; s < h->ns; s++) { /* serial: few springs, fixed order */
        if (!(h->sk[s] > 0)) continue;
        int a = h->se[2 * s], b = h->se[2 * s + 1];
        double d[3], l2 = 0;
        for (int k = 0; k < 3; k++) {
            d[k] = x[3 * b + k] - x[3 * a + k];
            l2 += d[k] * d[k];
        }
        double l = sqrt(l2), e = l - h->srest[s];
        E += 0.5 * h->sk[s] * e * e;
        if (g && l > 0)
            for (int k = 0; k < 3; k++) {
                double f = h->sk[s] * e * d[k] / l;
                g[3 * b + k] += f;
                g[3 * a + k] -= f;
            }
    }
    return E;
}

/* total energy at x; with g: its gradient (fixed dofs zeroed) */
static double total(ss_hyper *h, const double *x, double *g) {
    eval_tets(h, x, g ? 1 : 0);
    const int nn = h->nn;
    double Et = fsum(h->et, NULL, (size_t)h->nt);
    if (!isfinite(Et)) return INFINITY;
    if (g) {
#pragma omp parallel for schedule(static)
        for (int i = 0; i < nn; i++) {
            double s[3] = {0, 0, 0};
            for (int k = h->nstart[i]; k < h->nstart[i + 1]; k++) {
                int c = h->nlist[k]; /* tet * 4 + local */
                const double *gt = h->gt + 12 * (size_t)(c / 4) + 3 * (c % 4);
                s[0] += gt[0];
                s[1] += gt[1];
                s[2] += gt[2];
            }
            for (int d = 0; d < 3; d++)
                g[3 * i + d] =
                    s[d] + h->anchor[i] * (x[3 * i + d] - h->X[3 * i + d]) - h->load[3 * i + d];
        }
    }
    /* foundation and loads: per-node terms, summed in fixed blocks */
    double *tmp = h->r; /* scratch (not in use during an evaluation) */
#pragma omp parallel for schedule(static)
    for (int i = 0; i < nn; i++) {
        double e = 0;
        for (int d = 0; d < 3; d++) {
            double u = x[3 * i + d] - h->X[3 * i + d];
            e += 0.5 * h->anchor[i] * u * u - h->load[3 * i + d] * u;
        }
        tmp[i] = e;
    }
    double E = Et + fsum(tmp, NULL, (size_t)nn) + spring_energy(h, x, g);
    if (g)
        for (size_t i = 0; i < 3 * (size_t)nn; i++)
            if (h->fixed[i]) g[i] = 0;
    return E;
}

double ss_hyper_energy(ss_hyper *h) {
    if (!h->pattern_ok && build_pattern(h) != SS_OK) return NAN;
    return total(h, h->x, NULL);
}

void ss_hyper_tet_forces(ss_hyper *h, double *f) {
    if (!h->pattern_ok && build_pattern(h) != SS_OK) return;
    eval_tets(h, h->x, 1);
    for (int i = 0; i < h->nn; i++) {
        double s[3] = {0, 0, 0};
        for (int k = h->nstart[i]; k < h->nstart[i + 1]; k++) {
            int c = h->nlist[k];
            const double *gt = h->gt + 12 * (size_t)(c / 4) + 3 * (c % 4);
            for (int d = 0; d < 3; d++) s[d] += gt[d];
        }
        for (int d = 0; d < 3; d++) f[3 * i + d] = -s[d];
    }
}

/* the tangent: tets gathered per row of blocks, then foundation and springs */
static void assemble(ss_hyper *h, const double *x) {
    eval_tets(h, x, 2);
    /* row by row: a node's tets in tet order, each adding its three rows of
     * K to the row's blocks (the same sums in the same order as a gather per
     * block, but K is read a row at a time) */
#pragma omp parallel for schedule(static)
    for (int i = 0; i < h->nn; i++) {
        memset(h->val + 9 * (size_t)h->rowptr[i], 0,
               9 * (size_t)(h->rowptr[i + 1] - h->rowptr[i]) * sizeof(double));
        if (h->tolerant) { /* the float tangents, the same order */
            for (int c = h->nstart[i]; c < h->nstart[i + 1]; c++) {
                const int t = h->nlist[c] / 4, la = h->nlist[c] % 4;
                const float *K = (const float *)h->Kt + 144 * (size_t)t + 36 * la;
                const int32_t *bk = h->tblk + 16 * (size_t)t + 4 * la;
                for (int lb = 0; lb < 4; lb++) {
                    double *v = h->val + 9 * (size_t)bk[lb];
                    for (int r = 0; r < 3; r++)
                        for (int j = 0; j < 3; j++) v[3 * r + j] += K[12 * r + 3 * lb + j];
                }
            }
            continue;
        }
        for (int c = h->nstart[i]; c < h->nstart[i + 1]; c++) {
            const int t = h->nlist[c] / 4, la = h->nlist[c] % 4;
            const double *K = h->Kt + 144 * (size_t)t + 36 * la;
            const int32_t *bk = h->tblk + 16 * (size_t)t + 4 * la;
            for (int lb = 0; lb < 4; lb++) {
                double *v = h->val + 9 * (size_t)bk[lb];
                for (int r = 0; r < 3; r++)
                    for (int j = 0; j < 3; j++) v[3 * r + j] += K[12 * r + 3 * lb + j];
            }
        }
    }
    for (int i = 0; i < h->nn; i++)
        for (int d = 0; d < 3; d++) h->val[9 * (size_t)h->diag[i] + 4 * d] += h->anchor[i];
    for (int s = 0; s < h->ns; s++) {
        if (!(h->sk[s] > 0)) continue;
        int a = h->se[2 * s], b = h->se[2 * s + 1];
        double d[3], l2 = 0;
        for (int k = 0; k < 3; k++) {
            d[k] = x[3 * b + k] - x[3 * a + k];
            l2 += d[k] * d[k];
        }
        double l = sqrt(l2);
        if (!(l > 0)) continue;
        double w = 1 - h->srest[s] / l, B[9];
        if (w < 0) w = 0; /* a compressed spring: keep the tangent positive */
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                B[3 * i + j] = h->sk[s] * ((i == j) * w + (1 - w) * d[i] * d[j] / l2);
        int ab = find_blk(h, a, b), ba = find_blk(h, b, a);
        for (int k = 0; k < 9; k++) {
            h->val[9 * (size_t)h->diag[a] + k] += B[k];
            h->val[9 * (size_t)h->diag[b] + k] += B[k];
            h->val[9 * (size_t)ab + k] -= B[k];
            h->val[9 * (size_t)ba + k] -= B[k];
        }
    }
    /* block-Jacobi preconditioner; fixed dofs -> identity rows; the float
     * copy of the matrix for the products */
#pragma omp parallel for schedule(static)
    for (int i = 0; i < h->nn; i++) {
        if (h->tolerant)
            for (size_t k = 9 * (size_t)h->rowptr[i]; k < 9 * (size_t)h->rowptr[i + 1]; k++)
                h->val32[k] = (float)h->val[k];
        double A[9];
        memcpy(A, h->val + 9 * (size_t)h->diag[i], sizeof A);
        for (int d = 0; d < 3; d++)
            if (h->fixed[3 * i + d])
                for (int e = 0; e < 3; e++) {
                    A[3 * d + e] = A[3 * e + d] = 0;
                    A[4 * d] = 1;
                }
        double *Mi = h->Minv + 9 * (size_t)i;
        double det = det3(A);
        int spd = A[0] > 0 && A[0] * A[4] - A[1] * A[3] > 0 && det > 0;
        if (spd)
            inv3(A, Mi);
        else {
            double m = fmax(fabs(A[0]), fmax(fabs(A[4]), fabs(A[8])));
            memset(Mi, 0, 9 * sizeof(double));
            for (int d = 0; d < 3; d++) Mi[4 * d] = m > 0 ? 1 / m : 1;
        }
    }
    h->coarse_ok = 0;
    if (h->fast && h->nagg > 1) coarse_build(h);
}

/* out = A v (fixed dofs 0); an orphaned omp for (the CG's region) */
static void matvec(const ss_hyper *h, const double *v, double *out) {
    if (h->tolerant) { /* the float matrix: half the bytes, sums in double */
#pragma omp for schedule(static)
        for (int i = 0; i < h->nn; i++) {
            double s[3] = {0, 0, 0};
            for (int k = h->rowptr[i]; k < h->rowptr[i + 1]; k++) {
                const float *B = h->val32 + 9 * (size_t)k;
                const double *w = v + 3 * (size_t)h->col[k];
                s[0] += (double)B[0] * w[0] + (double)B[1] * w[1] + (double)B[2] * w[2];
                s[1] += (double)B[3] * w[0] + (double)B[4] * w[1] + (double)B[5] * w[2];
                s[2] += (double)B[6] * w[0] + (double)B[7] * w[1] + (double)B[8] * w[2];
            }
            for (int d = 0; d < 3; d++) out[3 * i + d] = h->fixed[3 * i + d] ? 0 : s[d];
        }
        return;
    }
#pragma omp for schedule(static)
    for (int i = 0; i < h->nn; i++) {
        double s[3] = {0, 0, 0};
        for (int k = h->rowptr[i]; k < h->rowptr[i + 1]; k++) {
            const double *B = h->val + 9 * (size_t)k, *w = v + 3 * (size_t)h->col[k];
            s[0] += B[0] * w[0] + B[1] * w[1] + B[2] * w[2];
            s[1] += B[3] * w[0] + B[4] * w[1] + B[5] * w[2];
            s[2] += B[6] * w[0] + B[7] * w[1] + B[8] * w[2];
        }
        for (int d = 0; d < 3; d++) out[3 * i + d] = h->fixed[3 * i + d] ? 0 : s[d];
    }
}

static void precond(const ss_hyper *h, const double *r, double *z) {
#pragma omp parallel for schedule(static)
    for (int i = 0; i < h->nn; i++) {
        const double *M = h->Minv + 9 * (size_t)i, *v = r + 3 * (size_t)i;
        for (int d = 0; d < 3; d++)
            z[3 * i + d] = h->fixed[3 * i + d]
                               ? 0
                               : M[3 * d] * v[0] + M[3 * d + 1] * v[1] + M[3 * d + 2] * v[2];
    }
    if (h->coarse_ok) coarse_apply(h, r, z);
}

/* The block-Jacobi part of z = M r at dof k (fixed: 0) */
static double jacobi_dof(const ss_hyper *h, const double *r, size_t k) {
    const size_t i = k / 3, d = k % 3;
    const double *M = h->Minv + 9 * i, *v = r + 3 * i;
    return h->fixed[k] ? 0 : M[3 * d] * v[0] + M[3 * d + 1] * v[1] + M[3 * d + 2] * v[2];
}

/* truncated preconditioned CG on K d = -g; returns iterations. The
 * iterations run in one parallel region (a region costs several barriers'
 * time): the vector updates fused with the dot products' fixed blocks of
 * SUMBLK (each block summed in index order, the blocks' partials summed in
 * block order by every thread alike, as fsum does: the same bytes for any
 * thread count), every thread taking the same decisions from the same sums. */
static int cg(ss_hyper *h, double eta, int maxit) {
    const size_t n = 3 * (size_t)h->nn;
    double *d = h->d, *r = h->r, *z = h->z, *p = h->p, *q = h->q;
    for (size_t i = 0; i < n; i++) {
        d[i] = 0;
        r[i] = -h->g[i];
    }
    precond(h, r, z);
    memcpy(p, z, n * sizeof(double));
    const double rz0 = fsum(r, z, n), r0 = sqrt(fsum(r, r, n));
    if (!(r0 > 0)) return 0;
    const size_t nb = (n + SUMBLK - 1) / SUMBLK;
    double *ppq = h->cgpart, *prr = ppq + nb, *prz = prr + nb;
    const int coarse = h->coarse_ok;
    int iters = 0;
#pragma omp parallel
    {
        double rz = rz0;
        int it;
        for (it = 0; it < maxit; it++) {
            matvec(h, p, q);
#pragma omp for schedule(static)
            for (size_t k = 0; k < nb; k++) {
                const size_t hi = (k + 1) * SUMBLK < n ? (k + 1) * SUMBLK : n;
                double s = 0;
                for (size_t i = k * SUMBLK; i < hi; i++) s += p[i] * q[i];
                ppq[k] = s;
            }
            double pq = 0;
            for (size_t k = 0; k < nb; k++) pq += ppq[k];
            if (!(pq > 0)) {
                if (it == 0) { /* a preconditioned gradient step */
#pragma omp for schedule(static)
                    for (size_t i = 0; i < n; i++) d[i] = z[i];
                }
                break;
            }
            const double a = rz / pq;
#pragma omp for schedule(static)
            for (size_t k = 0; k < nb; k++) {
                const size_t hi = (k + 1) * SUMBLK < n ? (k + 1) * SUMBLK : n;
                double s = 0;
                for (size_t i = k * SUMBLK; i < hi; i++) {
                    d[i] += a * p[i];
                    r[i] -= a * q[i];
                    s += r[i] * r[i];
                }
                prr[k] = s;
            }
            double rr = 0;
            for (size_t k = 0; k < nb; k++) rr += prr[k];
            if (sqrt(rr) <= eta * r0) {
                it++;
                break;
            }
            /* z = M r (block-Jacobi plus the coarse correction), with r.z */
            if (coarse) {
                coarse_restrict(h, r);
#pragma omp single
                coarse_solve(h);
            }
#pragma omp for schedule(static)
            for (size_t k = 0; k < nb; k++) {
                const size_t hi = (k + 1) * SUMBLK < n ? (k + 1) * SUMBLK : n;
                double s = 0;
                for (size_t i = k * SUMBLK; i < hi; i++) {
                    z[i] = jacobi_dof(h, r, i);
                    if (coarse && !h->fixed[i]) z[i] += coarse_dof(h, (int)(i / 3), (int)(i % 3));
                    s += r[i] * z[i];
                }
                prz[k] = s;
            }
            double rz1 = 0;
            for (size_t k = 0; k < nb; k++) rz1 += prz[k];
            const double b = rz1 / rz;
            rz = rz1;
#pragma omp for schedule(static)
            for (size_t i = 0; i < n; i++) p[i] = z[i] + b * p[i];
        }
#pragma omp master
        iters = it;
    }
    return iters;
}

/* the largest node move of the step d */
static double max_move(const ss_hyper *h, const double *d) {
    double mx = 0;
    for (int i = 0; i < h->nn; i++) {
        const double *v = d + 3 * (size_t)i, s2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        if (s2 > mx) mx = s2;
    }
    return sqrt(mx);
}

/* 1 if x + d folds a tet (J_e <= 0, or a zero area in the skin's plane for
 * the in-plane active law): where the energy is infinite */
static int folds(ss_hyper *h, const double *d) {
    const size_t n = 3 * (size_t)h->nn;
    int bad = 0;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) h->xt[i] = h->x[i] + d[i];
    update_growth(h);
#pragma omp parallel for schedule(static) reduction(| : bad)
    for (int t = 0; t < h->nt; t++) {
        double F[9];
        tet_F(h, t, h->xt, F);
        if (!(det3(F) > 0)) bad |= 1;
        if (h->act_law && h->act[t] != 0) {
            double Ft[9], c[3];
            tet_F_total(h, t, h->xt, Ft);
            if (!(plane_normal(Ft, c) > 0)) bad |= 1;
        }
    }
    return bad;
}

ss_status ss_hyper_solve(ss_hyper *h, double tol, int max_newton, ss_hyper_report *rep,
                         ss_error *err) {
    ss_hyper_report rr = {0, 0, 0, 0, 0, 0};
    if (!h->pattern_ok && build_pattern(h) != SS_OK)
        return ss_error_set(err, SS_ERR_NOMEM, "hyperelastic solver: out of memory");
    const size_t n = 3 * (size_t)h->nn;
    /* tolerant: if the positions are where the last solve left them (a new
     * frame of a smooth load), the solve starts from them moved by the last
     * solve's change of positions, if that folds no tet (a smooth load's
     * frames move alike; the evaluation there replaces the one at the old
     * positions, its gradient serves Newton and the tangent is kept). Newton
     * then starts closer, needs fewer iterations and converges to the same
     * tolerance (its line search decreases the energy from there). */
    const int pred_ok = h->tolerant && h->pred_ok && !memcmp(h->x, h->xend, n * sizeof(double));
    if (h->tolerant) memcpy(h->xend, h->x, n * sizeof(double)); /* this solve's start */
    double E = INFINITY;
    if (pred_ok) {
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < n; i++) h->xt[i] = h->x[i] + h->dprev[i];
        E = total(h, h->xt, h->g);
        if (isfinite(E)) {
            memcpy(h->x, h->xt, n * sizeof(double));
            rr.predicted = 1;
        }
    }
    if (!rr.predicted) E = total(h, h->x, h->g);
    if (!isfinite(E)) /* a folded start: nothing to minimise from */
        return ss_error_set(err, SS_ERR_INPUT, "hyperelastic solver: the start has a folded tet");
    double g0 = sqrt(fsum(h->g, h->g, n));
    /* fast: the tangent (and its preconditioner) of an earlier iteration,
     * even of the previous solve, is kept while the steps it gives cut the
     * gradient at least REUSE_RATIO-fold with a full step (a modified
     * Newton: the load of a frame changes the tangent little); a poor step,
     * a failed line search or no descent with an old tangent assembles it
     * afresh at the current positions. */
    const double REUSE_RATIO = 0.2;
    int fresh = 0; /* the matrix is the tangent at the current x */
    if (!h->fast) h->tangent_ok = 0;
    for (int it = 0; it < max_newton; it++) {
        double gn = sqrt(fsum(h->g, h->g, n));
        if (!(gn > 0)) {
            rr.converged = 1;
            break;
        }
        if (!h->tangent_ok) {
            assemble(h, h->x);
            h->tangent_ok = h->fast;
            fresh = 1;
        }
        double eta = g0 > 0 ? sqrt(gn / g0) : 0.1;
        if (eta > 0.1) eta = 0.1;
        if (eta < 1e-6) eta = 1e-6;
        int maxcg = (int)(n < 2000 ? 2000 : n);
        rr.cg += cg(h, eta, maxcg);
        rr.newton++;
        double slope = fsum(h->g, h->d, n);
        if (!(slope < 0) && !fresh) { /* an old tangent: assemble and retry */
            h->tangent_ok = 0;
            continue;
        }
        if (!(slope < 0)) { /* not a descent direction: the gradient itself */
            precond(h, h->g, h->d);
            for (size_t i = 0; i < n; i++) h->d[i] = -h->d[i];
            slope = fsum(h->g, h->d, n);
            if (!(slope < 0)) break;
        }
        /* tolerant: a full step already under the tolerance ends the solve
         * without the line search's evaluation if it folds no tet (the
         * Armijo test would at most shorten a step that is below the
         * tolerance anyway); the gradient kept is the one before it */
        const double move = h->tolerant ? max_move(h, h->d) : INFINITY;
        if (move < tol * h->mean_edge && !folds(h, h->d)) {
#pragma omp parallel for schedule(static)
            for (size_t i = 0; i < n; i++) h->x[i] += h->d[i];
            rr.max_step_mm = move;
            rr.converged = 1;
            break;
        }
        /* the full step (alpha 1, nearly always taken) is evaluated with its
         * gradient, which then serves the next iteration as is: total() at
         * the accepted point gives the same bytes (its energy does not
         * depend on whether the gradient is asked for) */
        double alpha = 1, En = INFINITY;
        for (int ls = 0; ls < 40; ls++) {
#pragma omp parallel for schedule(static)
            for (size_t i = 0; i < n; i++) h->xt[i] = h->x[i] + alpha * h->d[i];
            En = total(h, h->xt, ls == 0 ? h->gtry : NULL);
            if (isfinite(En) && En <= E + 1e-4 * alpha * slope) break;
            alpha *= 0.5;
        }
        if (!(isfinite(En) && En <= E + 1e-4 * alpha * slope)) {
            if (!fresh) {
                h->tangent_ok = 0;
                continue;
            }
            /* no decrease within rounding: we sit at the minimum */
            rr.converged = 1;
            break;
        }
        double mx = 0;
        for (int i = 0; i < h->nn; i++) {
            double s2 = 0;
            for (int dd = 0; dd < 3; dd++)
                s2 += alpha * alpha * h->d[3 * i + dd] * h->d[3 * i + dd];
            if (s2 > mx) mx = s2;
        }
        rr.max_step_mm = sqrt(mx);
        memcpy(h->x, h->xt, n * sizeof(double));
        if (alpha == 1) { /* the gradient of the accepted point is h->gtry */
            double *gs = h->g;
            h->g = h->gtry;
            h->gtry = gs;
            E = En;
        } else
            E = total(h, h->x, h->g);
        fresh = 0;
        if (rr.max_step_mm < tol * h->mean_edge) {
            rr.converged = 1;
            break;
        }
        if (alpha < 1 || !(sqrt(fsum(h->g, h->g, n)) <= REUSE_RATIO * gn)) h->tangent_ok = 0;
    }
    if (h->tolerant) { /* the predictor of the next solve */
        for (size_t i = 0; i < n; i++) {
            h->dprev[i] = h->fixed[i] ? 0 : h->x[i] - h->xend[i];
            h->xend[i] = h->x[i];
        }
        h->pred_ok = 1;
    }
    double gm = 0;
    for (size_t i = 0; i < n; i++) gm = fmax(gm, fabs(h->g[i]));
    rr.residual = gm;
    if (rep) *rep = rr;
    return SS_OK;
}

void ss_hyper_mean_cauchy(ss_hyper *h, double sigma[9], double *volume) {
    update_growth(h);
    double S[9] = {0}, V = 0;
    for (int t = 0; t < h->nt; t++) { /* serial, fixed order */
        double F[9], P[9];
        tet_F(h, t, h->x, F);
        double c = h->scale[t], s = h->act[t];
        const int law = h->act_law && s != 0;
        if (!isfinite(goh(&h->M, F, h->fib[t], law ? 0.0 : s / c, P, NULL))) continue;
        double J = det3(F), v = h->Vg[t] * J;
        if (law) { /* the in-plane active stress: V0 Pa Ft^T */
            const int32_t *q = h->tet + 4 * t;
            const double *b0 = h->beta0 + 12 * (size_t)t;
            double Ft[9], Pa[9];
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++)
                    Ft[3 * i + j] = h->x[3 * q[0] + i] * b0[j] + h->x[3 * q[1] + i] * b0[3 + j] +
                                    h->x[3 * q[2] + i] * b0[6 + j] + h->x[3 * q[3] + i] * b0[9 + j];
            if (!isfinite(planar_active(&h->M, s, Ft, Pa, NULL))) continue;
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++)
                    S[3 * i + j] +=
                        h->V0[t] * (Pa[3 * i] * Ft[3 * j] + Pa[3 * i + 1] * Ft[3 * j + 1] +
                                    Pa[3 * i + 2] * Ft[3 * j + 2]);
        }
        /* sigma = c P F^T / J (the active part included) */
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                S[3 * i + j] += v * c *
                                (P[3 * i] * F[3 * j] + P[3 * i + 1] * F[3 * j + 1] +
                                 P[3 * i + 2] * F[3 * j + 2]) /
                                J;
        V += v;
    }
    for (int k = 0; k < 9; k++) sigma[k] = V > 0 ? S[k] / V : 0;
    if (volume) *volume = V;
}
