/* The hyperelastic tissue of the coupled mechanics (--mech-model goh;
 * docs/mech.md "The GOH solver in the heal run"): what mech.c does with the
 * springs in steps 2 and 3 of a frame, done with the GOH tets of hyper.c.
 *
 * Set-up: every tet gets the GOH material; tets whose centroid lies in the
 * initial wound are the clot (fibres off, no resting tension, stiffness
 * rho_ecm/rho_ecm_hat as on the springs path), intact tets carry the in
 * vivo pre-stretch along the fibres as their rest state G = I + (1/lambda_p
 * - 1) a a (Langer lines: intact skin is under tension at its reference
 * shape). The skin beyond the block pulls with the same resting tension: a
 * dead load on the nodes equal to the intact pre-stressed block's internal
 * force at the reference shape, so an unwounded block stays where it is and
 * a wound (soft, tension-free) gapes at once; the set-up solves that first
 * equilibrium (day 0). The foundation (subcutis, far field) and the sutures
 * are the springs path's, with stitch stiffness k_suture_goh.
 * Frame: per node the amplitude of the active tension, n m K_m_goh
 * through a first-order lag of time constant tau_contract_goh (the cells'
 * force and the matrix they pull on build up days after the myofibroblast
 * count: without it the default wound's edges peaked at 0.73 mm/day on days
 * 4-6 and most of the contraction came before day 8); per tet the mean of
 * its nodes' amplitudes and the stiffness scale rho_ecm/rho_ecm_hat; Newton to
 * equilibrium from the last frame with the active law in the solve (the
 * seed's p_cell at the tet's own areal strain, a tension in the skin's
 * plane: ss_hyper_set_active_law; from the previous frame's strain the
 * frames alternated at higher loads, and an isotropic stress mostly thinned
 * the wound);
 * then remodelling, the continuum form of the springs' rest-length lag: in
 * tets under active stress the volume the pull has taken from the elastic
 * state (J_e < 1) is taken into the rest state by the fraction phi = 1 -
 * exp(-dt/tau_remodel), isotropically (G <- J_e^(phi/3) G): the matrix is
 * laid down in the contracted state and locks it, nothing lengthens. Only
 * the volume: taking in every compressed direction of U_e (tried first)
 * also takes in the Poisson thinning that the resting tension causes, so
 * under the far field's dead load the tissue crept without end (a default
 * wound grew by 150 % in 14 days). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mech_internal.h"

static int tet_in_wound(const ss_mech *m, int t) {
    const int32_t *q = m->mesh->tet + 4 * t;
    double c[3] = {0, 0, 0};
    for (int k = 0; k < 4; k++)
        for (int d = 0; d < 3; d++) c[d] += 0.25 * m->mesh->x[3 * q[k] + d];
    int i = (int)floor(c[0] / m->dx), j = (int)floor(c[1] / m->dx), k = (int)floor(c[2] / m->dx);
    if (i < 0 || j < 0 || k < 0 || i >= m->nx || j >= m->ny || k >= m->nz) return 0;
    return m->wound0[((size_t)k * m->ny + j) * m->nx + i];
}

ss_status ss_mech_goh_setup(ss_mech *m, ss_error *err) {
    const ss_mech_params *p = &m->p;
    ss_hyper *H = m->H = ss_hyper_create(m->mesh, p, err);
    if (!H) return err->code ? err->code : SS_ERR_INPUT;
    ss_hyper_set_active_law(H, 1);
    const int nn = m->mesh->nnodes, nt = m->mesh->ntets;
    if (!(m->nact = calloc((size_t)nn, sizeof(double))))
        return ss_error_set(err, SS_ERR_NOMEM, "mechanics: out of memory");
    memcpy(ss_hyper_anchor(H), m->S->anchor, (size_t)nn * sizeof(double));
    for (int sp = m->ntissue; sp < m->S->nsprings; sp++) {
        double k = p->k_suture > 0 ? m->kbase[sp] * p->k_suture_goh / p->k_suture : 0;
        if (ss_hyper_add_spring(H, m->S->e[2 * sp], m->S->e[2 * sp + 1], m->S->rest[sp], k, err) <
            0)
            return err->code;
    }
    /* the intact skin's rest state: shorter along the fibres by 1/lambda_p */
    double G0[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    const double sh = 1.0 / p->prestretch - 1.0;
    for (int f = 0; f < p->nfibres; f++)
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) G0[3 * i + j] += sh * p->fibre[f][i] * p->fibre[f][j];
    double *G = ss_hyper_growth(H);
    for (int t = 0; t < nt; t++) memcpy(G + 9 * (size_t)t, G0, sizeof G0);
    /* the far field's resting tension: the intact block's internal force */
    double *f = malloc(3 * (size_t)nn * sizeof(double));
    if (!f) return ss_error_set(err, SS_ERR_NOMEM, "mechanics: out of memory");
    ss_hyper_tet_forces(H, f);
    double *load = ss_hyper_load(H);
    for (int i = 0; i < 3 * nn; i++) load[i] = -f[i];
    free(f);
    /* the wound: the clot, soft and without tension or oriented collagen */
    G = ss_hyper_growth(H);
    uint8_t *fib = ss_hyper_fibres_on(H);
    double *sc = ss_hyper_scale(H);
    for (int t = 0; t < nt; t++) {
        if (!tet_in_wound(m, t)) continue;
        static const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        memcpy(G + 9 * (size_t)t, I, sizeof I);
        fib[t] = 0;
        sc[t] = p->ecm_floor;
    }
    /* day 0: the cut gapes */
    ss_hyper_report rep;
    ss_status st = ss_hyper_solve(H, p->tol, 50, &rep, err);
    if (st) return st;
    memcpy(m->S->x, ss_hyper_x(H), 3 * (size_t)nn * sizeof(double));
    m->last_substeps = rep.newton;
    m->last_converged = rep.converged;
    return SS_OK;
}

ss_status ss_mech_goh_frame(ss_mech *m, const ss_heal_grid *g, double dt_days, ss_error *err) {
    const ss_mech_params *p = &m->p;
    ss_hyper *H = m->H;
    const int nt = m->mesh->ntets, nn = m->mesh->nnodes;
    const int32_t *tet = m->mesh->tet;
    double *act = ss_hyper_active(H), *sc = ss_hyper_scale(H);
    /* the lagged amplitude, exact for an amplitude constant over the frame
     * (so a frame time does not change the course); the node field written
     * to the .vtu is it times p_cell at the grid's volumetric strain (the
     * solve itself uses each tet's own areal strain) */
    const double lag = p->tau_contract_goh > 0 ? 1.0 - exp(-dt_days / p->tau_contract_goh) : 1.0;
    double *nact = m->nact;
#pragma omp parallel for schedule(static)
    for (int i = 0; i < nn; i++) {
        double nw = m->nmyo[i] > 0 ? m->nmyo[i] : 0.0, a = nw * m->nmf[i] * p->K_m_goh;
        nact[i] = lag < 1 ? nact[i] + lag * (a - nact[i]) : a;
        m->stress[i] = ss_mech_pcell(p, m->nth[i]) * nact[i];
    }
#pragma omp parallel for schedule(static)
    for (int t = 0; t < nt; t++) {
        const int32_t *q = tet + 4 * t;
        double s = 0, e = 0;
        for (int k = 0; k < 4; k++) {
            s += 0.25 * nact[q[k]];
            e += 0.25 * m->necm[q[k]];
        }
        act[t] = s;
        sc[t] = e > p->ecm_floor ? e : p->ecm_floor;
    }
    for (int i = 0; i < m->nsutures; i++)
        for (int sp = m->suture_spring[i]; sp < m->suture_spring[i + 1]; sp++) {
            double k = p->k_suture > 0 ? m->kbase[sp] * p->k_suture_goh / p->k_suture : 0;
            ss_hyper_set_spring(H, sp - m->ntissue, m->S->rest[sp],
                                g->t_days >= m->suture_day[i] ? 0.0 : k);
        }
    memcpy(ss_hyper_x(H), m->S->x, 3 * (size_t)nn * sizeof(double));
    ss_hyper_report rep;
    ss_status st = ss_hyper_solve(H, p->tol, 50, &rep, err);
    if (st) return st;
    memcpy(m->S->x, ss_hyper_x(H), 3 * (size_t)nn * sizeof(double));
    m->last_substeps = rep.newton;
    m->last_converged = rep.converged;
    m->last_increments = 1;
    m->last_inverted = ss_mech_inverted_tets(m);
    /* remodelling: the compressive elastic stretch of pulling tets into G */
    const double phi = p->tau_remodel > 0 ? 1.0 - exp(-dt_days / p->tau_remodel) : 1.0;
    if (!(phi > 0)) return SS_OK;
    const double *x = ss_hyper_x(H);
    const double *X = ss_hyper_X(H);
    double *G = ss_hyper_growth(H);
#pragma omp parallel for schedule(static)
    for (int t = 0; t < nt; t++) {
        if (!(act[t] > 0)) continue;
        const int32_t *q = tet + 4 * t;
        double D[9], Dx[9], Di[9], F[9], Gi[9], Fe[9];
        for (int c = 0; c < 3; c++)
            for (int i = 0; i < 3; i++) {
                D[3 * i + c] = X[3 * q[c + 1] + i] - X[3 * q[0] + i];
                Dx[3 * i + c] = x[3 * q[c + 1] + i] - x[3 * q[0] + i];
            }
        /* F = Dx D^-1, Fe = F G^-1 */
        double *Gt = G + 9 * (size_t)t;
        double dD = D[0] * (D[4] * D[8] - D[5] * D[7]) - D[1] * (D[3] * D[8] - D[5] * D[6]) +
                    D[2] * (D[3] * D[7] - D[4] * D[6]);
        double dG = Gt[0] * (Gt[4] * Gt[8] - Gt[5] * Gt[7]) -
                    Gt[1] * (Gt[3] * Gt[8] - Gt[5] * Gt[6]) +
                    Gt[2] * (Gt[3] * Gt[7] - Gt[4] * Gt[6]);
        if (!(fabs(dD) > 0) || !(fabs(dG) > 0)) continue;
        const double *A[2] = {D, Gt};
        double *B[2] = {Di, Gi};
        double dets[2] = {dD, dG};
        for (int k = 0; k < 2; k++) {
            const double *M = A[k];
            double *R = B[k], d = dets[k];
            R[0] = (M[4] * M[8] - M[5] * M[7]) / d;
            R[1] = (M[2] * M[7] - M[1] * M[8]) / d;
            R[2] = (M[1] * M[5] - M[2] * M[4]) / d;
            R[3] = (M[5] * M[6] - M[3] * M[8]) / d;
            R[4] = (M[0] * M[8] - M[2] * M[6]) / d;
            R[5] = (M[2] * M[3] - M[0] * M[5]) / d;
            R[6] = (M[3] * M[7] - M[4] * M[6]) / d;
            R[7] = (M[1] * M[6] - M[0] * M[7]) / d;
            R[8] = (M[0] * M[4] - M[1] * M[3]) / d;
        }
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                F[3 * i + j] =
                    Dx[3 * i] * Di[j] + Dx[3 * i + 1] * Di[3 + j] + Dx[3 * i + 2] * Di[6 + j];
            }
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                Fe[3 * i + j] =
                    F[3 * i] * Gi[j] + F[3 * i + 1] * Gi[3 + j] + F[3 * i + 2] * Gi[6 + j];
        /* the volume the cells' pull has taken from the elastic state */
        double Je = Fe[0] * (Fe[4] * Fe[8] - Fe[5] * Fe[7]) -
                    Fe[1] * (Fe[3] * Fe[8] - Fe[5] * Fe[6]) +
                    Fe[2] * (Fe[3] * Fe[7] - Fe[4] * Fe[6]);
        if (!(Je < 1) || !(Je > 0)) continue;
        double sh = pow(Je, phi / 3.0), Gn[9];
        for (int k = 0; k < 9; k++) Gn[k] = sh * Gt[k];
        memcpy(Gt, Gn, sizeof Gn);
    }
    return SS_OK;
}
