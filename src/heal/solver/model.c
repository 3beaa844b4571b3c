/* The §4.1 healing model of seed 001 as a reaction function for the generic
 * reaction-diffusion core, and the solver that steps an ss_heal_grid with the
 * explicit or the split scheme. Each equation is written in the core's
 * production/loss form R = prod - loss * u (same terms as §4.1, only sorted by
 * sign), with diffusion multipliers (1 - s) for u1, u2, u3, n (slot 0) and
 * (1 - s) Q(u3_bed) for e (slot 1). Cell classes: AIR and BOUND are walls (no
 * flux), the intact EPIDERMIS holds e at its healthy value 1 (Dirichlet),
 * DERMIS and WOUND evolve. omega = [p > SS_HEAL_P_MIN].
 * The epithelium is a sheet on the tissue surface, not a volume species: e
 * (its coverage, 0..1) evolves only in the topmost tissue cell of each
 * column and diffuses along x and y only; it reads the wound bed's capillary
 * density as the mean u3 over the top bed_mm (physical depth, not voxels).
 * Its effects below the surface ((1 - e) in eschar and scar production, the
 * eschar dissolution lames e s) use the column's surface coverage. The
 * eschar is a crust confined to the top scab_mm of the exposed wound (its
 * source acts there, it diffuses along x and y only); with the scab switch
 * the (1 - s) of u1..n weights the cell faces (a full crust insulates the
 * bed instead of draining it), and a dry factor from the column's crust
 * thickness slows capillary and fibroblast growth in the wound below. The
 * bed the sheet reads is the granulation tissue (omega) under the crust. A
 * voxel the crust layer's floor cuts (voxels coarser than scab_mm) holds a
 * sub-voxel crust over tissue that grows at the full rate; that tissue has
 * its own volume and a face to the dermis below from its own centre (the
 * core's vfrac). These
 * column inputs are gathered before each reaction pass (prepare hook), so
 * rows stay independent and results bit-identical for any thread count.
 * The keloid's invasion signal a(t) (keloid_tau, keloid_floor) depends on the grid's day
 * only and is set before each step, so resumes and rank counts agree.
 * docs/heal-model.md §2 lists where and why this departs from §4.1 as printed. */
/* The hot loops are written branch-free for SIMD. At -O2 GCC vectorises
 * their compares/selects only with loop if-conversion and without treating
 * FP exception flags as observable (-fno-trapping-math: values are unchanged,
 * unlike -ffast-math there is no reassociation or finite-math assumption). */
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("tree-loop-if-convert", "tree-loop-vectorize", "no-trapping-math")
#endif
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "heal_internal.h"

ss_heal_rd_work *ss_heal_rd__work_create_ex(const ss_heal_rd_system *sys, int need_buf,
                                            int need_mslot, ss_error *err);

typedef struct model_ctx {
    float lam11, lam31, lam12, lam22, beta2, lam33, lam32, inv_u3eq, rn, inv_K, lamnn;
    float Rs, lames, lamge, lamee, gamma1, lamnrho, lamrhop, lamkrho, lampp, inv_rhomax, rhomax;
    float kscab, kang, bed_mm, h, rho_closed, inv_rhosat, inv_scabmm;
    float kact;         /* keloid invasion signal a(t) for the current step (keloid_signal) */
    float rmat;         /* rho_mature: remodelling resorbs only the excess above it [D10] */
    float kadn, adn_mm; /* adnexal outgrowth rate and the depth that destroys it [D11] */
    float kel_h;        /* keloid_mm / voxel: the keloid's depth in voxel levels [D12] */
    float kgain;        /* keloid_gain: refused deposition kept as added volume [D16] */
    int scab, static_region;
    const uint8_t *cell;
    /* the frozen plasma of a static region without a velocity: a partial
     * wound cell's wounded fraction f, which the adnexa's depth reads [D15]
     * (NULL: every WOUND cell counts whole) */
    const float *pfrac;
    int nx, ny, nz;
    /* per column (y * nx + x): surface cell z (-1: none), gathered surface
     * epithelium and wound-bed capillary density */
    int *ztop;
    float *ecol, *bed, *ds;   /* ds: the column's eschar thickness (mm) */
    float *wsum, *bedo, *wso; /* prepare's scratch */
    float *cu, *cs, *co, *ch; /* the bed walk's carry: the level above (bed_level) */
    float *kfix;              /* De/h^2 x the surface cell's faces to intact epidermis [D8] */
    float De;
    const uint8_t *ztop_of; /* the cell array ztop was computed from */
    float scab_h;           /* scab_mm / voxel: the scab layer in voxel levels */
    float crust;            /* s above which a voxel is crust, closed to u1..n [D9] (inf: none) */
    int *zt_min, *zt_max;   /* per y: range of ztop over the row's columns */
    int kdeep;              /* levels below the surface where no surface/scab term acts */
    /* per cell: the tissue volume fraction 1 - wsc of a WOUND cell the crust
     * layer's floor cuts (0 < wsc < 1), 1 elsewhere [D14]; NULL when no level
     * can be cut (scab_mm a whole number of voxels, or no crust) */
    float *vfrac;
    float vmin; /* its smallest value (0: none is cut, vfrac stays NULL) */
    /* a box of a stack in z (src/mpi): ztop, zt_min, zt_max are whole-grid
     * levels, zoff the whole-grid level of this box's z = 0, col the exchange
     * with the boxes above and below (NULL: the columns are whole here) */
    int zoff;
    ss_heal_column_fn col;
    void *col_ctx;
} model_ctx;

struct ss_heal_solver {
    ss_heal_params p;
    ss_heal_scheme scheme;
    double dt;
    int nsub;
    int nx, ny, nz;
    model_ctx ctx;
    ss_heal_rd_system sys;
    ss_heal_rd_work *w;
};

static inline float pos(float v) { return v > 0.0f ? v : 0.0f; }

/* The seed's epithelial window Q(u3) (§4.1.6), rising to 1 at gamma1, and
 * held at 1 above it. The seed's falling branch (1 - u3)/(1 - gamma1) reaches
 * zero at the healthy density u3 = 1: a bed compacted by wound contraction
 * passes it (the mechanics' convection concentrates the capillaries), and the
 * epithelium stopped for good short of closure; held at one half above
 * (1 + gamma1)/2, as before issue 25, it still stalled large wounds, whose
 * centre the front reaches only once the bed has matured (t95 grew 0.70
 * day/mm of radius from 1 to 2 cm, 1.17 from 2 to 4 cm). The margin of a
 * wound advances at a rate independent of its size (Cukjati et al. 2001,
 * Med Biol Eng Comput 39:263, 300 wounds: the advance of the margin towards
 * the centre per day, unlike the area healed per day), and the new
 * epidermis migrates over a fully vascularised bed as over healthy
 * granulation tissue: 0.63 and 0.61 day/mm now (docs/heal-model.md [D3]). */
static inline float qwin(float u3, float g1, float ig1) { return u3 < g1 ? pos(u3 * ig1) : 1.0f; }

/* The share of a level kf below the column's surface (0 = the surface
 * level) that lies inside the top scab_h levels, the crust layer: 1 within
 * it, 0 below it and above the surface, between on the level its floor
 * cuts. Arithmetic only, so react_row's loop stays vectorised. */
static inline float crust_share(float scab_h, float kf) {
    return (float)(kf >= 0.0f) * clampf(scab_h - kf, 0.0f, 1.0f);
}

/* One row of the reaction. `deep` (a constant at each call, so the compiler
 * emits two loops): no cell of the row is a surface cell or inside the scab
 * layer, so the sheet and eschar-source terms are zero there and are not
 * computed (the values written are the same as the full loop's). `kel`
 * (likewise): the keloid deposition is on (lamkrho > 0); without it the term
 * is skipped (it would add exactly 0). */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline void
react_row(const model_ctx *m, const ss_heal_rd_row *row, const int deep, const int kel) {
    const int n = row->n;
    const size_t col0 = (size_t)row->y * (size_t)m->nx + (size_t)row->x0;
    const int *restrict ZT = m->ztop + col0;
    const float *restrict EC = m->ecol + col0, *restrict BED = m->bed + col0;
    const float *restrict DS = m->ds + col0, *restrict KF = m->kfix + col0;
    const float
        *restrict U1 = row->u[SS_HEAL_OXYGEN],
                  *restrict U2 = row->u[SS_HEAL_MDGF], *restrict U3 = row->u[SS_HEAL_CAPILLARY],
                  *restrict N = row->u[SS_HEAL_FIBROBLAST], *restrict S = row->u[SS_HEAL_ESCHAR],
                  *restrict E = row->u[SS_HEAL_EPITHELIUM], *restrict RHO = row->u[SS_HEAL_SCAR],
                  *restrict P = row->u[SS_HEAL_PLASMA];
    float *const *pr = row->prod, *const *ls = row->loss;
    _Static_assert(SS_HEAL_OXYGEN == 0 && SS_HEAL_PLASMA == 7, "field order");
    const float Rs = m->scab ? m->Rs : 0.0f;
    const float pmin = (float)SS_HEAL_P_MIN;
    const float g1 = m->gamma1, ig1 = 1.0f / m->gamma1;
    const float ppos = pos(m->lampp), pneg = pos(-m->lampp);
    const float dyn = m->static_region ? 0.0f : 1.0f;
    const float ibeta = 1.0f / m->beta2;
    const int z = row->z + m->zoff;
    const float scab_h = m->scab_h, kscab = m->kscab, rclosed = m->rho_closed, crust = m->crust;
    const float lamnrho = m->lamnrho, lamge = m->lamge, lamee = m->lamee;
    const float lames = m->lames, irsat = m->inv_rhosat;
    /* keloid factor G = a + (1 - a) clamp(rho/rho_max - 1, 0, 1), times lamkrho */
    const float lka = m->lamkrho * m->kact, lkb = m->lamkrho * (1.0f - m->kact);
    const float irmax = m->inv_rhomax;
    const float rmat = m->rmat, lrm = m->lamrhop * m->rmat, kel_h = m->kel_h;
    const float kang = m->kang * m->inv_scabmm;
    float *restrict m0 = row->m[0], *restrict m1 = row->m[1];
    float *restrict p1 = pr[0], *restrict p2 = pr[1], *restrict p3 = pr[2], *restrict p4 = pr[3];
    float *restrict p5 = pr[4], *restrict p6 = pr[5], *restrict p7 = pr[6], *restrict p8 = pr[7];
    float *restrict l1 = ls[0], *restrict l2 = ls[1], *restrict l3 = ls[2], *restrict l4 = ls[3];
    float *restrict l5 = ls[4], *restrict l6 = ls[5], *restrict l7 = ls[6], *restrict l8 = ls[7];
#pragma omp simd
    for (int i = 0; i < n; i++) {
        const float u1 = U1[i], u2 = U2[i], u3 = U3[i], nn = N[i], s = S[i], e = E[i];
        const float rho = RHO[i], p = P[i];
        const float om = (float)(p > pmin);
        const float open3 = pos(1.0f - u3);
        /* depth level below the surface cell (0 = surface, < 0: no surface) and
         * the fraction of the level inside the top scab_mm (arithmetic, no
         * table lookup, so the loop stays vectorised) */
        const float kf = deep ? 1.0f : (float)(ZT[i] - z);
        const float surf = deep ? 0.0f : (float)(kf == 0.0f);
        const float wsc = deep ? 0.0f : crust_share(scab_h, kf);
        /* a voxel the crust layer's floor cuts (0 < wsc < 1, voxels coarser
         * than scab_mm or not a divisor of it) holds a sub-voxel crust on top
         * of tissue [D14]: its tissue species are those of the tissue part,
         * which grows at the full rate (the tissue under a crust does on a
         * fine grid: s = 0 there), and the crust's own fraction of the layer
         * part is s / wsc (1 when the crust is complete) */
        const float part = deep ? 0.0f : (float)(wsc > 0.0f && wsc < 1.0f);
        const float ns = part > 0.0f ? 1.0f : pos(1.0f - s);
        const float sl = part > 0.0f ? clampf(s / (wsc > 0.0f ? wsc : 1.0f), 0.0f, 1.0f) : s;
        const float ecl = EC[i], necl = pos(1.0f - ecl);
        /* 4.1.1 oxygen: (1-s)(D1 lap u1 + lam31 u3) - lam11 u1 */
        p1[i] = ns * m->lam31 * u3;
        l1[i] = m->lam11;
        /* 4.1.2 MDGF: (1-s)(D2 lap u2 + lam12 P(u1)) - lam22 u2 */
        const float Pu1 = pos(1.0f - u1 * ibeta);
        p2[i] = ns * m->lam12 * Pu1;
        l2[i] = m->lam22;
        /* 4.1.3 capillaries: (1-s)(D3 lap u3 + (lam33 + lam32 u2) u3 (1 - u3/u3eq)),
         * growth in the wound region slowed by the crust over the column:
         * (1 - kang min(1, eschar thickness / scab_mm)) */
        const float dry = pos(1.0f - om * clampf(kang * DS[i], 0.0f, m->kang));
        const float g3 = ns * dry * (m->lam33 + m->lam32 * u2) * u3;
        p3[i] = g3;
        l3[i] = g3 * m->inv_u3eq;
        /* 4.1.4 fibroblasts: (1-s)(Dn lap n + rn u1 n (1 - n/K)) - lamnn n */
        const float gn = ns * dry * m->rn * u1 * nn;
        p4[i] = gn;
        l4[i] = gn * m->inv_K + m->lamnn;
        /* 4.1.5 eschar: Ds lap s + (1-s)(1-u3)(1-e) R(omega) - lames e s; R acts in
         * the top scab_mm of the wound region, e is the column's surface sheet */
        const float X = deep ? 0.0f : open3 * necl * Rs * om * (float)(wsc > 0.0f);
        p5[i] = X * wsc;
        l5[i] = deep ? lames * ecl : X + lames * ecl;
        /* 4.1.6 epithelium, on the surface only:
         * (1 - kscab s) Q(u3_bed)(De lap_xy e + lamge e) - lamee e; the
         * intact epidermis holds e = 1 at the margin, the face of its cell,
         * half a voxel nearer than its centre: KF (1 - e) adds the other
         * half of such a face's conductance [D8] */
        const float me = deep ? 0.0f : surf * pos(1.0f - kscab * sl) * qwin(BED[i], g1, ig1);
        p6[i] = deep ? 0.0f : me * (lamge * e + KF[i]);
        l6[i] = deep ? 0.0f : surf * lamee + me * KF[i];
        /* 4.1.7 scar, restricted to omega:
         * (1-s) n ((1-u3)(1-e) lamnrho + lamkrho G (1 - rho/rho_sat)+)
         * - lamrhop rho; G = a + (1 - a) clamp(rho/rho_max - 1, 0, 1): tissue
         * not yet keloid needs the invasion signal a(t) [D6] */
        const float imm = pos(1.0f - rclosed * u3); /* (1 - u3) at rho_open = 0 */
        /* remodelling resorbs the excess above the mature scar's collagen:
         * - lamrhop (rho - rho_mature)+ [D10], as production lamrhop rho_mature
         * and loss lamrhop where rho > rho_mature (rho never falls below it) */
        const float over = (float)(rho > rmat);
        /* the keloid lies in the dermis above keloid_mm: the fraction of the
         * voxel inside it (levels below the column's surface cell) */
        const float kin = kel ? clampf(kel_h - (float)(ZT[i] - z), 0.0f, 1.0f) : 0.0f;
        const float kdep = kel ? (lka + lkb * clampf(rho * irmax - 1.0f, 0.0f, 1.0f)) *
                                     pos(1.0f - rho * irsat) * kin
                               : 0.0f;
        p7[i] = om * ns * nn * (imm * necl * lamnrho + kdep) + lrm * over;
        l7[i] = m->lamrhop * over;
        /* 4.1.8 plasma: Dp lap p + lampp p + C(rho)(1-p) */
        const float C = pos(rho - m->rhomax) * m->inv_rhomax;
        p8[i] = dyn * (C + ppos * p);
        l8[i] = dyn * (C + pneg);
        m0[i] = part > 0.0f ? 1.0f : face_m(s, crust);
        m1[i] = me;
        (void)e;
    }
}

static void heal_react(void *vctx, const ss_heal_rd_row *row) {
    const model_ctx *m = vctx;
    const int z = row->z + m->zoff, y = row->y;
    /* deep row: every column's surface is above z by at least one level and
     * the scab layer (levels below the surface with wsc > 0: kf < scab_h), or
     * below z (no surface in the column at this height) */
    const int deep = z > m->zt_max[y] || m->zt_min[y] - z >= m->kdeep;
    if (m->lamkrho > 0.0f) {
        if (deep)
            react_row(m, row, 1, 1);
        else
            react_row(m, row, 0, 1);
    } else if (deep) {
        react_row(m, row, 1, 0);
    } else {
        react_row(m, row, 0, 0);
    }
}

static int is_tissue(uint8_t c) { return c != SS_CELL_AIR && c != SS_CELL_BOUND; }

/* The plasma is a record of the wound's fraction only while it is frozen
 * (static region) and not carried by a velocity (the mechanics). */
static void surface_inputs(model_ctx *c, const ss_heal_grid *g) {
    const int vel = g->velocity[0] || g->velocity[1] || g->velocity[2];
    c->pfrac = c->static_region && !vel ? g->field[SS_HEAL_PLASMA] : NULL;
}

/* The tissue volume fraction of every cell, halo included (the explicit
 * scheme reads it at the neighbours): 1 - wsc in a WOUND cell the crust
 * layer's floor cuts, wsc = crust_share as in react_row, from the column's
 * topmost tissue level (over a z stack: the maximum, exact as floats). The
 * column scan reuses the prepare scratch wsum, which prepare rewrites. */
static void tissue_fraction(model_ctx *c) {
    const int nx = c->nx, ny = c->ny, nz = c->nz;
    const size_t ncol = (size_t)nx * ny;
    float *zt = c->wsum;
    for (size_t i = 0; i < ncol; i++) {
        zt[i] = -1.0f;
        for (int z = nz - 2; z >= 1; z--)
            if (is_tissue(c->cell[(size_t)z * ncol + i])) {
                zt[i] = (float)(z + c->zoff);
                break;
            }
    }
    if (c->col) c->col(c->col_ctx, SS_HEAL_COL_MAX, zt, ncol);
    for (int z = 0; z < nz; z++)
        for (size_t i = 0; i < ncol; i++) {
            const size_t k = (size_t)z * ncol + i;
            float v = 1.0f;
            if (c->cell[k] == SS_CELL_WOUND && zt[i] >= 0.0f) {
                const float kf = zt[i] - (float)(z + c->zoff);
                const float wsc = crust_share(c->scab_h, kf);
                if (wsc > 0.0f && wsc < 1.0f) v = 1.0f - wsc;
            }
            c->vfrac[k] = v;
        }
}

/* Surface cell of every column: the topmost tissue cell inside the bounds. */
static void find_surface(model_ctx *c) {
    const int nx = c->nx, ny = c->ny, nz = c->nz;
    for (int y = 0; y < ny; y++)
        for (int x = 0; x < nx; x++) {
            int zt = -1;
            if (x > 0 && y > 0 && x < nx - 1 && y < ny - 1)
                for (int z = nz - 2; z >= 1; z--)
                    if (is_tissue(c->cell[((size_t)z * ny + y) * nx + x])) {
                        zt = z + c->zoff;
                        break;
                    }
            c->ztop[(size_t)y * nx + x] = zt;
        }
    if (c->col) { /* the topmost over the z stack (levels are exact as floats) */
        const size_t ncol = (size_t)nx * ny;
        for (size_t i = 0; i < ncol; i++) c->ds[i] = (float)c->ztop[i];
        c->col(c->col_ctx, SS_HEAL_COL_MAX, c->ds, ncol);
        for (size_t i = 0; i < ncol; i++) c->ztop[i] = (int)c->ds[i];
    }
    for (int y = 0; y < ny; y++) {
        int lo = 1 << 30, hi = -1; /* (whole-grid levels in a stack) */
        for (int x = 1; x < nx - 1; x++) {
            const int zt = c->ztop[(size_t)y * nx + x];
            if (zt < 0) continue;
            lo = zt < lo ? zt : lo;
            hi = zt > hi ? zt : hi;
        }
        c->zt_min[y] = lo;
        c->zt_max[y] = hi;
    }
    if (c->vfrac) tissue_fraction(c);
    /* the margin [D8]: lateral faces of a surface cell with intact epidermis
     * (the Dirichlet e = 1 of the sheet) at the same level */
    const float kf = c->De / (c->h * c->h);
    const size_t ncol = (size_t)nx * ny;
    /* adnexal remnants [D11]: the column's wound depth from the lowest WOUND
     * level (whole-grid, the maximum of its negative over a z stack); kept in
     * ds, which prepare recomputes before it is read. A partial lowest cell
     * [D15] is wound only in its top f: the floor lies 1 - f above its bottom
     * (f = 1 in a whole cell: the same float as before) */
    if (c->kadn > 0.0f) {
        for (size_t i = 0; i < ncol; i++) {
            float lo = -1e30f;
            for (int z = 1; z <= nz - 2; z++)
                if (c->cell[(size_t)z * ncol + i] == SS_CELL_WOUND) {
                    /* p = (1 + f) / 2 in a partial cell, 1 in a whole one */
                    const float f =
                        c->pfrac ? clampf(2.0f * c->pfrac[(size_t)z * ncol + i] - 1.0f, 0.0f, 1.0f)
                                 : 1.0f;
                    lo = -(float)(z + c->zoff) - (1.0f - f);
                    break;
                }
            c->ds[i] = lo;
        }
        if (c->col) c->col(c->col_ctx, SS_HEAL_COL_MAX, c->ds, ncol);
    }
    for (int y = 0; y < ny; y++)
        for (int x = 0; x < nx; x++) {
            const size_t i = (size_t)y * nx + x;
            const int zl = c->ztop[i] - c->zoff;
            c->kfix[i] = 0.0f;
            if (c->ztop[i] < 0 || zl < 1 || zl > nz - 2 || x < 1 || y < 1 || x > nx - 2 ||
                y > ny - 2)
                continue;
            const uint8_t *cz = c->cell + (size_t)zl * ny * nx;
            if (cz[i] == SS_CELL_EPIDERMIS) continue;
            const int nb = (cz[i - 1] == SS_CELL_EPIDERMIS) + (cz[i + 1] == SS_CELL_EPIDERMIS) +
                           (cz[i - nx] == SS_CELL_EPIDERMIS) + (cz[i + nx] == SS_CELL_EPIDERMIS);
            c->kfix[i] = kf * (float)nb;
            /* the surviving adnexa pull the sheet towards 1 like the margin
             * does, an areal source kadn (1 - depth / adnexa_mm)+ (1 - e) */
            if (c->kadn > 0.0f && cz[i] == SS_CELL_WOUND && c->ds[i] > -1e29f) {
                const float depth = (float)(c->ztop[i] + c->ds[i] + 1.0f) * c->h;
                c->kfix[i] += c->kadn * clampf(1.0f - depth / c->adn_mm, 0.0f, 1.0f);
            }
        }
    c->ztop_of = c->cell;
}

/* The bed reads u3 through its piecewise-linear interpolant in depth, not
 * the voxel means (docs/heal-model.md [D8]): u3 is one continuous field (the
 * capillary network of the dermis grows on into the clot), so between two
 * voxel centres it is taken linear, the value at their face being the mean
 * of the two, weighted by the face's conductance min(1 - s) of [D6] (under a
 * full crust the face insulates: constant towards it); at a wall (air, the
 * bound, no level) it is constant. A voxel in the window contributes the
 * integral of the interpolant over its part of the window. As h -> 0 this is
 * the mean of the field; at h = 0.5 mm it keeps the capillaries at the wound
 * floor, half a voxel below the bed voxel's centre, that the voxel mean
 * misses (the granulation layer under the default crust is one voxel).
 * One segment [d0, d1] of depth (values v0, v1 at its ends, linear) of a
 * voxel whose granulation flag is om: its part in the window [a, b]. */
static inline void bed_seg(float d0, float d1, float v0, float v1, float om, float a, float b,
                           float *bed, float *ws, float *bo, float *wo) {
    const float lo = d0 > a ? d0 : a, hi = d1 < b ? d1 : b;
    if (!(hi > lo)) return;
    const float v = v0 + (v1 - v0) * (0.5f * (lo + hi) - d0) / (d1 - d0);
    *bed += (hi - lo) * v;
    *ws += hi - lo;
    if (om > 0.0f) { /* om < 1: a partial wound cell's share [D15] (1 x: exact) */
        *bo += om * (hi - lo) * v;
        *wo += om * (hi - lo);
    }
}

/* One level z of the bed sum of a row of columns, walking down: voxel
 * k = zt - z below the surface. The carry (cu, cs, co, ch: u3, s, omega flag
 * and presence of voxel k - 1, the level above) is handed from level to level
 * (and from box to box in a z stack). Level z adds the lower half of voxel
 * k - 1 and the upper half of voxel k, each clipped to the bed window
 * [ds, ds + bed_mm]; bo, wo sum the granulation tissue (omega: plasma Pr above
 * SS_HEAL_P_MIN) of the window alone. Cr: the level's cell classes. */
static inline void bed_level(const int *zt, const float *ds, const float *Ur, const float *Sr,
                             const float *Pr, const uint8_t *Cr, float *bed, float *ws, float *bo,
                             float *wo, float *cu, float *cs, float *co, float *ch, int nx, int z,
                             float h, float bedmm, int frac) {
    const float pmin = (float)SS_HEAL_P_MIN;
    for (int x = 0; x < nx; x++) {
        const int k = zt[x] - z;
        if (k < 0) continue;
        const float a = ds[x], b = ds[x] + bedmm;
        const int tis = Cr[x] != SS_CELL_AIR && Cr[x] != SS_CELL_BOUND;
        /* omega's weight: a partial wound cell (frozen p = (1 + f) / 2) is
         * granulation tissue in its wounded share f only [D15] */
        const float u = Ur[x], sk = Sr[x],
                    om = frac ? clampf(2.0f * Pr[x] - 1.0f, 0.0f, 1.0f) : (float)(Pr[x] > pmin);
        const float top = k * h, mid = top + 0.5f * h;
        float fk = u; /* the interpolant at voxel k's top face, seen from k */
        if (ch[x] > 0.0f) {
            const float mk = clampf(1.0f - sk, 0.0f, 1.0f), mp = clampf(1.0f - cs[x], 0.0f, 1.0f);
            const float mf = tis ? (mk < mp ? mk : mp) : 0.0f, f = 0.5f * (cu[x] + u);
            const float fp = cu[x] + mf * (f - cu[x]); /* seen from k - 1 */
            bed_seg(top - 0.5f * h, top, cu[x], fp, co[x], a, b, &bed[x], &ws[x], &bo[x], &wo[x]);
            fk = u + mf * (f - u);
        }
        ch[x] = (float)tis;
        if (!tis) continue;
        bed_seg(top, mid, fk, u, om, a, b, &bed[x], &ws[x], &bo[x], &wo[x]);
        cu[x] = u;
        cs[x] = sk;
        co[x] = om;
    }
}

/* The end of a column's walk: the lower half of its last voxel, constant
 * (the bound below, or no more window). */
static inline void bed_flush(const int *zt, const float *ds, float *bed, float *ws, float *bo,
                             float *wo, const float *cu, const float *co, const float *ch, int nx,
                             int zlast, float h, float bedmm) {
    for (int x = 0; x < nx; x++) {
        const int k = zt[x] - zlast;
        if (k < 0 || !(ch[x] > 0.0f)) continue;
        const float bot = (k + 1) * h;
        bed_seg(bot - 0.5f * h, bot, cu[x], cu[x], co[x], ds[x], ds[x] + bedmm, &bed[x], &ws[x],
                &bo[x], &wo[x]);
    }
}

/* The lowest level a row's bed sums must visit: below the row's LOWEST
 * surface, the deepest window [ds, ds + bed_mm] of the row (one level of
 * slack for rounding), so it reaches every column's own window. A bound from
 * the row's highest surface cut the window of a column lying 3+ levels lower
 * (an uneven surface, a curved shell) and made the bed depend on which columns
 * share the row (issue #8). Levels below a column's window add nothing to it
 * (bed_level), so the sums do not depend on the bound as long as it reaches
 * every window (flat rows: the same levels as before). */
static inline int bed_low(const int *zt, const float *ds, int nx, float h, float bedmm) {
    int zmin = 1 << 30;
    float dmax = 0.0f;
    for (int x = 0; x < nx; x++) {
        if (zt[x] < 0) continue;
        if (zt[x] < zmin) zmin = zt[x];
        if (ds[x] > dmax) dmax = ds[x];
    }
    return zmin - (int)ceilf((dmax + bedmm) / h) - 1;
}

/* The bed mean of a column: the granulation tissue where the window holds
 * some, else all the viable tissue in it, else u3 at the bottom (u3_1). */
static inline float bed_mean(float bed, float ws, float bo, float wo, float u3_1) {
    if (wo > 0) return bo / wo;
    return ws > 0 ? bed / ws : u3_1;
}

static void heal_prepare_z(model_ctx *c, float *const *u);

/* prepare hook: the surface epithelium and the bed's mean capillary density
 * of every column, from the current fields. Walks each y slab z-row by z-row
 * (contiguous in x) rather than column by column, so large grids stream
 * through memory; per column the sums still run in z order (deterministic). */

static void heal_prepare(void *vctx, float *const *u) {
    model_ctx *c = vctx;
    if (c->col) {
        heal_prepare_z(c, u);
        return;
    }
    const int nx = c->nx, ny = c->ny;
    const size_t sz = (size_t)nx * (size_t)ny;
    const float *E = u[SS_HEAL_EPITHELIUM], *U3 = u[SS_HEAL_CAPILLARY], *S = u[SS_HEAL_ESCHAR];
    const float *P = u[SS_HEAL_PLASMA];
    const float h = c->h, bedmm = c->bed_mm;
    const int scab = c->scab;
#pragma omp parallel for schedule(static) if (sz * (size_t)c->nz >= RD_PAR_MIN_CELLS)
    for (int y = 0; y < ny; y++) {
        const size_t r0 = (size_t)y * (size_t)nx;
        const int *zt = c->ztop + r0;
        float *ec = c->ecol + r0, *bed = c->bed + r0, *ds = c->ds + r0, *ws = c->wsum + r0;
        float *bo = c->bedo + r0, *wo = c->wso + r0;
        float *cu = c->cu + r0, *cs = c->cs + r0, *co = c->co + r0, *ch = c->ch + r0;
        int zhi = -1;
        for (int x = 0; x < nx; x++) {
            ec[x] = zt[x] >= 0 ? E[(size_t)zt[x] * sz + r0 + x] : 0.0f;
            ds[x] = bed[x] = ws[x] = bo[x] = wo[x] = 0.0f;
            cu[x] = cs[x] = co[x] = ch[x] = 0.0f;
            if (zt[x] > zhi) zhi = zt[x];
        }
        if (zhi < 1) continue;
        /* the eschar thickness over each column: the depth integral of s (0
         * without the scab switch, which is the only eschar source) */
        if (scab)
            for (int z = zhi; z >= 1; z--) {
                const float *Sr = S + (size_t)z * sz + r0;
                for (int x = 0; x < nx; x++)
                    if (zt[x] >= z) ds[x] += Sr[x] * h;
            }
        /* the bed: the top bed_mm of viable tissue below the eschar; of it, the
         * granulation tissue (omega) where the column has some, so the mean
         * does not mix in the intact dermis under a shallow wound. The levels
         * walked reach the deepest column's window (bed_low) */
        int zlo = bed_low(zt, ds, nx, h, bedmm);
        if (zlo < 1) zlo = 1;
        for (int z = zhi; z >= zlo; z--) {
            const size_t o = (size_t)z * sz + r0;
            bed_level(zt, ds, U3 + o, S + o, P + o, c->cell + o, bed, ws, bo, wo, cu, cs, co, ch,
                      nx, z, h, bedmm, c->pfrac != NULL);
        }
        bed_flush(zt, ds, bed, ws, bo, wo, cu, co, ch, nx, zlo, h, bedmm);
        for (int x = 0; x < nx; x++) {
            if (zt[x] < 0) continue;
            bed[x] = bed_mean(bed[x], ws[x], bo[x], wo[x], U3[sz + r0 + x]); /* z = 1 */
        }
    }
}

/* heal_prepare on a box of a stack in z (src/mpi): the same sums in the same
 * order (top down, each level's terms as above), each continued from the box
 * above and handed to the box below; the bottom box finishes the bed mean and
 * sends the column values to the whole stack; the surface epithelium comes
 * from the box that holds the surface cell. Owned levels: z = 1 .. nz - 2. */
static void heal_prepare_z(model_ctx *c, float *const *u) {
    const int nx = c->nx, ny = c->ny, nz = c->nz, zoff = c->zoff;
    const size_t sz = (size_t)nx * (size_t)ny;
    const float *E = u[SS_HEAL_EPITHELIUM], *U3 = u[SS_HEAL_CAPILLARY], *S = u[SS_HEAL_ESCHAR];
    const float *P = u[SS_HEAL_PLASMA];
    const float h = c->h, bedmm = c->bed_mm;
    const int own_hi = zoff + nz - 2, own_lo = zoff + 1; /* whole-grid levels */
    const int par = sz * (size_t)nz >= RD_PAR_MIN_CELLS;
#pragma omp parallel for schedule(static) if (par)
    for (size_t i = 0; i < sz; i++) {
        const int zt = c->ztop[i];
        c->ecol[i] = zt >= own_lo && zt <= own_hi ? E[(size_t)(zt - zoff) * sz + i] : -INFINITY;
        c->ds[i] = c->bed[i] = c->wsum[i] = c->bedo[i] = c->wso[i] = 0.0f;
        c->cu[i] = c->cs[i] = c->co[i] = c->ch[i] = 0.0f;
    }
    c->col(c->col_ctx, SS_HEAL_COL_MAX, c->ecol, sz);
    for (size_t i = 0; i < sz; i++)
        if (c->ztop[i] < 0) c->ecol[i] = 0.0f;
    if (c->scab) { /* the eschar thickness over each column */
        c->col(c->col_ctx, SS_HEAL_COL_FROM_ABOVE, c->ds, sz);
#pragma omp parallel for schedule(static) if (par)
        for (int y = 0; y < ny; y++) {
            const size_t r0 = (size_t)y * (size_t)nx;
            const int *zt = c->ztop + r0;
            float *ds = c->ds + r0;
            int zhi = -1;
            for (int x = 0; x < nx; x++)
                if (zt[x] > zhi) zhi = zt[x];
            for (int z = zhi < own_hi ? zhi : own_hi; z >= own_lo && z >= 1; z--) {
                const float *Sr = S + (size_t)(z - zoff) * sz + r0;
                for (int x = 0; x < nx; x++)
                    if (zt[x] >= z) ds[x] += Sr[x] * h;
            }
        }
        c->col(c->col_ctx, SS_HEAL_COL_TO_BELOW, c->ds, sz);
        c->col(c->col_ctx, SS_HEAL_COL_FROM_BOTTOM, c->ds, sz);
    }
    c->col(c->col_ctx, SS_HEAL_COL_FROM_ABOVE, c->bed, sz);
    c->col(c->col_ctx, SS_HEAL_COL_FROM_ABOVE, c->wsum, sz);
    c->col(c->col_ctx, SS_HEAL_COL_FROM_ABOVE, c->bedo, sz);
    c->col(c->col_ctx, SS_HEAL_COL_FROM_ABOVE, c->wso, sz);
    float *carry[4] = {c->cu, c->cs, c->co, c->ch};
    for (int k = 0; k < 4; k++) c->col(c->col_ctx, SS_HEAL_COL_FROM_ABOVE, carry[k], sz);
#pragma omp parallel for schedule(static) if (par)
    for (int y = 0; y < ny; y++) {
        const size_t r0 = (size_t)y * (size_t)nx;
        const int *zt = c->ztop + r0;
        float *bed = c->bed + r0, *ds = c->ds + r0, *ws = c->wsum + r0;
        float *bo = c->bedo + r0, *wo = c->wso + r0;
        float *cu = c->cu + r0, *cs = c->cs + r0, *co = c->co + r0, *ch = c->ch + r0;
        int zhi = -1;
        for (int x = 0; x < nx; x++)
            if (zt[x] > zhi) zhi = zt[x];
        if (zhi < 1) continue;
        int zlo = bed_low(zt, ds, nx, h, bedmm);
        if (zlo < 1) zlo = 1;
        const int zend = zlo; /* the whole column's last level (bed_flush) */
        if (zlo < own_lo) zlo = own_lo;
        for (int z = zhi < own_hi ? zhi : own_hi; z >= zlo; z--) {
            const size_t o = (size_t)(z - zoff) * sz + r0;
            bed_level(zt, ds, U3 + o, S + o, P + o, c->cell + o, bed, ws, bo, wo, cu, cs, co, ch,
                      nx, z, h, bedmm, c->pfrac != NULL);
        }
        if (own_lo > 0) continue; /* the bottom box (global level 1 inside) finishes */
        bed_flush(zt, ds, bed, ws, bo, wo, cu, co, ch, nx, zend, h, bedmm);
        for (int x = 0; x < nx; x++) {
            if (zt[x] < 0) continue;
            bed[x] = bed_mean(bed[x], ws[x], bo[x], wo[x], U3[(size_t)(1 - zoff) * sz + r0 + x]);
        }
    }
    c->col(c->col_ctx, SS_HEAL_COL_TO_BELOW, c->bed, sz);
    c->col(c->col_ctx, SS_HEAL_COL_TO_BELOW, c->wsum, sz);
    c->col(c->col_ctx, SS_HEAL_COL_TO_BELOW, c->bedo, sz);
    c->col(c->col_ctx, SS_HEAL_COL_TO_BELOW, c->wso, sz);
    for (int k = 0; k < 4; k++) c->col(c->col_ctx, SS_HEAL_COL_TO_BELOW, carry[k], sz);
    c->col(c->col_ctx, SS_HEAL_COL_FROM_BOTTOM, c->bed, sz);
}

static void ctx_init(model_ctx *c, const ss_heal_params *p, const ss_heal_grid *g) {
    memset(c, 0, sizeof *c);
    c->lam11 = (float)p->lam11;
    c->lam31 = (float)p->lam31;
    c->lam12 = (float)p->lam12;
    c->lam22 = (float)p->lam22;
    c->beta2 = (float)p->u1_beta2;
    c->lam33 = (float)p->lam33;
    c->lam32 = (float)p->lam32;
    c->inv_u3eq = (float)(1.0 / p->u3_eq);
    c->rn = (float)p->rn;
    c->inv_K = (float)(1.0 / p->K);
    c->lamnn = (float)p->lamnn;
    c->Rs = (float)p->Rs;
    c->lames = (float)p->lames;
    c->lamge = (float)p->lamge;
    c->lamee = (float)p->lamee;
    c->gamma1 = (float)p->gamma1;
    c->lamnrho = (float)p->lamnrho;
    c->lamrhop = (float)p->lamrhop;
    c->lamkrho = (float)p->lamkrho;
    c->lampp = (float)p->lampp;
    c->rhomax = (float)p->rho_max;
    c->inv_rhomax = (float)(1.0 / p->rho_max);
    c->scab = p->scab;
    c->static_region = p->static_region;
    c->cell = g->cell;
    surface_inputs(c, g);
    c->nx = g->nx;
    c->ny = g->ny;
    c->nz = g->nz;
    c->kscab = (float)p->kscab;
    c->kang = p->scab ? (float)p->kang : 0.0f;
    c->inv_scabmm = p->scab_mm > 0 ? (float)(1.0 / p->scab_mm) : 0.0f;
    c->inv_rhosat = (float)(1.0 / p->rho_sat);
    c->kact = 1.0f;
    c->rmat = (float)p->rho_mature;
    c->kadn = (float)p->kadn;
    c->adn_mm = p->adnexa_mm > 0 ? (float)p->adnexa_mm : 1.0f;
    c->kel_h = (float)(p->keloid_mm / g->dx_mm);
    c->kgain = (float)p->keloid_gain;
    c->rho_closed = (float)(1.0 - p->rho_open);
    c->bed_mm = (float)p->bed_mm;
    c->h = (float)g->dx_mm;
    c->De = (float)p->De;
    c->scab_h = (float)(p->scab_mm / g->dx_mm);
    c->crust = p->scab ? (float)SS_HEAL_CRUST_CLOSED : INFINITY;
    /* a level the crust layer's floor cuts exists when scab_mm is not a whole
     * number of voxels (and a crust forms) [D14]: its tissue fraction */
    const double frac = (double)c->scab_h - floor((double)c->scab_h);
    c->vmin = p->scab && p->Rs != 0.0 && frac > 0.0 ? (float)(1.0 - frac) : 0.0f;
    /* wsc = 0 once kf >= scab_h; without the scab switch R = 0 everywhere */
    c->kdeep = 1;
    if (p->scab && p->Rs != 0.0) {
        const double k = ceil((double)c->scab_h);
        c->kdeep = k > 1.0 ? (k < 1e6 ? (int)k : 1000000) : 1;
    }
}

/* Bound on the reaction rates (growth + loss, 1/day) for the explicit limit. */
static double rate_bound(const ss_heal_params *p) {
    double u2max = p->lam22 > 0 ? p->lam12 / p->lam22 : p->lam12;
    double u1max = p->lam31 * p->u3_eq / p->lam11;
    if (u1max < 1.0) u1max = 1.0;
    double r[8] = {p->lam11,
                   p->lam22,
                   2.0 * (p->lam33 + p->lam32 * u2max),
                   2.0 * p->rn * u1max + p->lamnn,
                   p->scab ? p->Rs + p->lames : p->lames,
                   p->lamge + p->lamee + p->kadn,
                   p->lamrhop,
                   p->static_region ? 0.0 : fabs(p->lampp)};
    double m = 0.0;
    for (int i = 0; i < 8; i++)
        if (r[i] > m) m = r[i];
    return m;
}

static void sys_init(ss_heal_rd_system *s, model_ctx *c, const ss_heal_grid *g,
                     const ss_heal_params *p) {
    memset(s, 0, sizeof *s);
    s->nx = g->nx;
    s->ny = g->ny;
    s->nz = g->nz;
    s->h_mm = g->dx_mm;
    s->nfields = SS_HEAL_NFIELDS;
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) {
        s->u[f] = g->field[f];
        s->lo[f] = 0.0f;
        s->hi[f] = INFINITY;
        s->mslot[f] = -1;
    }
    s->cls = g->cell;
    s->wall[SS_CELL_AIR] = 1;
    s->wall[SS_CELL_BOUND] = 1;
    for (int k = SS_CELL_BOUND + 1; k < SS_HEAL_RD_MAXCLASS; k++) s->wall[k] = 1;
    s->fixed[SS_HEAL_EPITHELIUM][SS_CELL_EPIDERMIS] = 1;
    s->lateral[SS_HEAL_EPITHELIUM] = 1; /* a surface sheet */
    s->lateral[SS_HEAL_ESCHAR] = 1;     /* a crust confined to its layer */
    s->D[SS_HEAL_OXYGEN] = p->D1;
    s->D[SS_HEAL_MDGF] = p->D2;
    s->D[SS_HEAL_CAPILLARY] = p->D3;
    s->D[SS_HEAL_FIBROBLAST] = p->Dn;
    s->D[SS_HEAL_ESCHAR] = p->Ds;
    s->D[SS_HEAL_EPITHELIUM] = p->De;
    s->D[SS_HEAL_SCAR] = 0.0;
    s->D[SS_HEAL_PLASMA] = p->static_region ? 0.0 : p->Dp;
    s->mslot[SS_HEAL_OXYGEN] = s->mslot[SS_HEAL_MDGF] = 0;
    s->mslot[SS_HEAL_CAPILLARY] = s->mslot[SS_HEAL_FIBROBLAST] = 0;
    s->mslot[SS_HEAL_EPITHELIUM] = 1;
    s->nslots = 2;
    /* the crust insulates the tissue below it instead of draining it: u1..n
     * diffuse through faces of conductance min(1 - s) (without the scab
     * switch s = 0 and the two forms are the same) */
    if (p->scab) {
        s->mface[0] = SS_HEAL_ESCHAR + 1;
        s->mface_closed = (float)SS_HEAL_CRUST_CLOSED; /* [D9] */
    }
    s->hi[SS_HEAL_ESCHAR] = s->hi[SS_HEAL_EPITHELIUM] = s->hi[SS_HEAL_PLASMA] = 1.0f;
    /* the packing limit holds for every deposition (the ordinary one is not
     * saturated: a large or long-open wound could pack it past rho_sat, issue
     * 25: 3.33 in a 4 cm circle); below rho_sat nothing changes */
    s->hi[SS_HEAL_SCAR] = (float)p->rho_sat;
    for (int d = 0; d < 3; d++) s->velocity[d] = g->velocity[d];
    s->react = heal_react;
    s->prepare = c->ztop ? heal_prepare : NULL;
    s->ctx = c;
    s->mmax = 1.0;
    /* sub-voxel tissue [D14]: a cell's face sum grows to at most 4 lateral
     * faces of 1 and two z faces of 2 / (vmin (1 + vmin)) each */
    s->vfrac = c->vfrac;
    if (c->vmin > 0.0f) s->mmax = (4.0 + 4.0 / ((double)c->vmin * (1.0 + c->vmin))) / 6.0;
    s->rate_max = rate_bound(p);
}

static ss_status check_params(const ss_heal_params *p, ss_error *err) {
    if (!(p->lam11 > 0) || !(p->u3_eq > 0) || !(p->K > 0) || !(p->rho_max > 0) ||
        !(p->u1_beta2 > 0) || !(p->gamma1 > 0 && p->gamma1 < 1) || !(p->bed_mm > 0) ||
        !(p->scab_mm >= 0) || !(p->rho_sat > 0) || !(p->rho_mature >= 0) || !(p->kadn >= 0) ||
        !(p->adnexa_mm > 0) || !(p->keloid_mm > 0))
        return ss_error_set(err, SS_ERR_INPUT,
                            "heal params: lam11, u3_eq, K, rho_max, u1_beta2, bed_mm, rho_sat must "
                            "be > 0, "
                            "scab_mm >= 0 and gamma1 in (0, 1); rho_mature, kadn >= 0, "
                            "adnexa_mm > 0");
    return SS_OK;
}

double ss_heal_stable_dt(const ss_heal_grid *g, const ss_heal_params *p, ss_heal_scheme s) {
    if (!g || !p) return 0.0;
    if (s == SS_HEAL_SPLIT) return SS_HEAL_SPLIT_MAX_DT_DAYS;
    model_ctx c;
    ss_heal_rd_system sys;
    ctx_init(&c, p, g);
    sys_init(&sys, &c, g, p);
    return ss_heal_rd_explicit_dt(&sys);
}

static ss_heal_solver *solver_create(const ss_heal_grid *g, const int *goff, const int *gdim,
                                     const ss_heal_params *p, ss_heal_scheme scheme, double dt,
                                     ss_error *err);

ss_status ss_heal_solver_check(const ss_heal_grid *g, const ss_heal_params *p,
                               ss_heal_scheme scheme, double *dt_days, ss_error *err) {
    if (!g || !p || !dt_days)
        return ss_error_set(err, SS_ERR_INPUT, "heal solver: no grid or parameters");
    if (scheme != SS_HEAL_EXPLICIT && scheme != SS_HEAL_SPLIT)
        return ss_error_set(err, SS_ERR_INPUT, "heal solver: unknown scheme %d", (int)scheme);
    ss_status st = check_params(p, err);
    if (st) return st;
    double dt = *dt_days;
    if (!(dt >= 0) || !isfinite(dt))
        return ss_error_set(err, SS_ERR_INPUT, "heal solver: time step %g days must be >= 0", dt);
    double limit = ss_heal_stable_dt(g, p, scheme);
    if (dt == 0) dt = scheme == SS_HEAL_EXPLICIT ? 0.9 * limit : SS_HEAL_SPLIT_DEFAULT_DT_DAYS;
    if (dt > limit * (1.0 + 1e-12)) {
        if (scheme == SS_HEAL_EXPLICIT)
            return ss_error_set(err, SS_ERR_INPUT,
                                "heal solver: time step %g days exceeds the explicit stability "
                                "limit %g days (voxel %g mm; limit = 1 / (6 D_max / h^2 + max "
                                "reaction rate + |v|/h)); use --dt <= %g or the split scheme",
                                dt, limit, g->dx_mm, limit);
        return ss_error_set(err, SS_ERR_INPUT,
                            "heal solver: time step %g days exceeds the split scheme's accuracy "
                            "limit %g days",
                            dt, limit);
    }
    *dt_days = dt;
    return SS_OK;
}

ss_heal_solver *ss_heal_solver_create(const ss_heal_grid *g, const ss_heal_params *p,
                                      ss_heal_scheme scheme, double dt, ss_error *err) {
    return solver_create(g, NULL, NULL, p, scheme, dt, err);
}

ss_heal_solver *ss_heal_solver_create_sub(const ss_heal_grid *g, const int goff[3],
                                          const int gdim[3], const ss_heal_params *p,
                                          ss_heal_scheme scheme, double dt, ss_error *err) {
    if (!g || !goff || !gdim || gdim[0] < g->nx - 2 || gdim[1] < g->ny - 2 || gdim[2] < g->nz - 2 ||
        (scheme != SS_HEAL_EXPLICIT && (goff[2] != 0 || gdim[2] != g->nz))) {
        ss_error_set(err, SS_ERR_INPUT,
                     "heal solver: a sub-box must lie inside the grid (and span it in z with the "
                     "split scheme, whose z line solves need whole columns)");
        return NULL;
    }
    return solver_create(g, goff, gdim, p, scheme, dt, err);
}

static ss_heal_solver *solver_create(const ss_heal_grid *g, const int *goff, const int *gdim,
                                     const ss_heal_params *p, ss_heal_scheme scheme, double dt,
                                     ss_error *err) {
    if (ss_heal_solver_check(g, p, scheme, &dt, err)) return NULL;
    ss_heal_solver *s = calloc(1, sizeof *s);
    if (!s) {
        ss_error_set(err, SS_ERR_NOMEM, "heal solver: out of memory");
        return NULL;
    }
    s->p = *p;
    s->scheme = scheme;
    s->dt = dt;
    s->nx = g->nx;
    s->ny = g->ny;
    s->nz = g->nz;
    ctx_init(&s->ctx, &s->p, g);
    const size_t ncol = (size_t)g->nx * (size_t)g->ny;
    s->ctx.ztop = malloc(ncol * sizeof(int));
    s->ctx.ecol = calloc(ncol, sizeof(float));
    s->ctx.bed = calloc(ncol, sizeof(float));
    s->ctx.ds = calloc(ncol, sizeof(float));
    s->ctx.wsum = calloc(ncol, sizeof(float));
    s->ctx.bedo = calloc(ncol, sizeof(float));
    s->ctx.wso = calloc(ncol, sizeof(float));
    s->ctx.cu = calloc(ncol, sizeof(float));
    s->ctx.cs = calloc(ncol, sizeof(float));
    s->ctx.co = calloc(ncol, sizeof(float));
    s->ctx.ch = calloc(ncol, sizeof(float));
    s->ctx.kfix = calloc(ncol, sizeof(float));
    s->ctx.zt_min = malloc((size_t)g->ny * sizeof(int));
    s->ctx.zt_max = malloc((size_t)g->ny * sizeof(int));
    if (!s->ctx.ztop || !s->ctx.ecol || !s->ctx.bed || !s->ctx.ds || !s->ctx.wsum || !s->ctx.bedo ||
        !s->ctx.wso || !s->ctx.cu || !s->ctx.cs || !s->ctx.co || !s->ctx.ch || !s->ctx.kfix ||
        !s->ctx.zt_min || !s->ctx.zt_max) {
        ss_heal_solver_free(s);
        ss_error_set(err, SS_ERR_NOMEM, "heal solver: out of memory");
        return NULL;
    }
    if (goff) s->ctx.zoff = goff[2];
    if (s->ctx.vmin > 0.0f) {
        s->ctx.vfrac = malloc((size_t)g->nx * g->ny * g->nz * sizeof(float));
        if (!s->ctx.vfrac) {
            ss_heal_solver_free(s);
            ss_error_set(err, SS_ERR_NOMEM, "heal solver: out of memory");
            return NULL;
        }
    }
    find_surface(&s->ctx);
    sys_init(&s->sys, &s->ctx, g, &s->p);
    for (int d = 0; goff && d < 3; d++) {
        s->sys.goff[d] = goff[d];
        s->sys.gdim[d] = gdim[d];
    }
    double r = s->sys.rate_max;
    /* reaction substeps of at most 0.1 / rate_max (both halves together) */
    s->nsub = (int)ceil(dt * r / 0.1);
    if (s->nsub < 1) s->nsub = 1;
    int has_vel = g->velocity[0] || g->velocity[1] || g->velocity[2];
    s->w = ss_heal_rd__work_create_ex(&s->sys, scheme == SS_HEAL_EXPLICIT || has_vel,
                                      scheme == SS_HEAL_SPLIT, err);
    if (!s->w) {
        ss_heal_solver_free(s);
        return NULL;
    }
    return s;
}

void ss_heal_solver_set_columns(ss_heal_solver *s, ss_heal_column_fn fn, void *ctx) {
    if (!s) return;
    s->ctx.col = fn;
    s->ctx.col_ctx = ctx;
    find_surface(&s->ctx); /* the surface over the whole stack */
}

void ss_heal_solver_set_convection(ss_heal_solver *s, ss_heal_conv_fn fn, void *ctx) {
    if (!s) return;
    s->sys.conv = fn;
    s->sys.conv_ctx = ctx;
}

double ss_heal_solver_dt(const ss_heal_solver *s) { return s ? s->dt : 0.0; }

ss_status ss_heal_solver_set_dt(ss_heal_solver *s, double dt, ss_error *err) {
    if (!s) return ss_error_set(err, SS_ERR_INPUT, "heal solver: none");
    double limit = s->scheme == SS_HEAL_SPLIT ? SS_HEAL_SPLIT_LATE_MAX_DT_DAYS
                                              : ss_heal_rd_explicit_dt(&s->sys);
    if (!(dt > 0) || !isfinite(dt) || dt > limit * (1.0 + 1e-12))
        return ss_error_set(err, SS_ERR_INPUT, "heal solver: time step %g days not in (0, %g]", dt,
                            limit);
    s->dt = dt;
    s->nsub = (int)ceil(dt * s->sys.rate_max / 0.1);
    if (s->nsub < 1) s->nsub = 1;
    return SS_OK;
}

void ss_heal_solver_free(ss_heal_solver *s) {
    if (!s) return;
    ss_heal_rd_work_free(s->w);
    free(s->ctx.ztop);
    free(s->ctx.ecol);
    free(s->ctx.bed);
    free(s->ctx.ds);
    free(s->ctx.wsum);
    free(s->ctx.bedo);
    free(s->ctx.wso);
    free(s->ctx.cu);
    free(s->ctx.cs);
    free(s->ctx.co);
    free(s->ctx.ch);
    free(s->ctx.kfix);
    free(s->ctx.zt_min);
    free(s->ctx.zt_max);
    free(s->ctx.vfrac);
    free(s);
}

/* The keloid's invasion signal over a step from day t of length dt, at the
 * step's midpoint: a = floor + (1 - floor) exp(-t_mid / keloid_tau), 1
 * without decay. A function
 * of the grid's day only, so resumed runs and any rank count see the same. */
static float keloid_signal(const ss_heal_params *p, double t, double dt) {
    if (!(p->keloid_tau > 0)) return 1.0f;
    const double f = p->keloid_floor;
    return (float)(f + (1.0 - f) * exp(-(t + 0.5 * dt) / p->keloid_tau));
}

/* Points the solver at a grid's cells, fields and velocity before a step
 * (the surface found again only when the cell array changed). */
static void bind_grid(ss_heal_solver *s, ss_heal_grid *g) {
    s->ctx.cell = g->cell;
    surface_inputs(&s->ctx, g);
    s->sys.cls = g->cell;
    if (s->ctx.ztop_of != g->cell) find_surface(&s->ctx);
    s->ctx.kact = keloid_signal(&s->p, g->t_days, s->dt);
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) s->sys.u[f] = g->field[f];
    for (int d = 0; d < 3; d++) s->sys.velocity[d] = g->velocity[d];
}

/* The keloid's added tissue volume [D16]: the packing limit keeps rho at
 * rho_sat, so the part of the keloid deposition that its (1 - rho/rho_sat)
 * factor refuses, lamkrho G min(1, rho/rho_sat) in the cells it reaches (the
 * same omega, (1 - s), n, G and depth share kin as react_row's kdep), is not
 * lost: keloid_gain of it stays as tissue added to the cell's column
 * (g->added, rho units; the elevation adds it). Explicit over the step from
 * the fields at its end, cell by cell, so any box or rank count and a resumed
 * run (the checkpoint holds g->added) give the same values. */
static void keloid_volume(ss_heal_solver *s, ss_heal_grid *g) {
    const model_ctx *m = &s->ctx;
    if (!g->added || !(m->lamkrho > 0.0f) || !(m->kgain > 0.0f)) return;
    const int nx = g->nx, ny = g->ny, nz = g->nz;
    const float *N = g->field[SS_HEAL_FIBROBLAST], *S = g->field[SS_HEAL_ESCHAR];
    const float *RHO = g->field[SS_HEAL_SCAR], *P = g->field[SS_HEAL_PLASMA];
    const float pmin = (float)SS_HEAL_P_MIN, dtg = (float)s->dt * m->kgain;
    const float lka = m->lamkrho * m->kact, lkb = m->lamkrho * (1.0f - m->kact);
#pragma omp parallel for schedule(static)
    for (int z = 0; z < nz; z++)
        for (int y = 0; y < ny; y++)
            for (int x = 0; x < nx; x++) {
                const size_t i = ss_heal_idx(g, x, y, z);
                const int zt = m->ztop[(size_t)y * (size_t)nx + (size_t)x];
                const int Z = z + m->zoff;
                if (!is_tissue(g->cell[i]) || zt < Z || !(P[i] > pmin)) continue;
                const float kin = clampf(m->kel_h - (float)(zt - Z), 0.0f, 1.0f);
                const float rho = RHO[i];
                const float G = lka + lkb * clampf(rho * m->inv_rhomax - 1.0f, 0.0f, 1.0f);
                const float refused = clampf(rho * m->inv_rhosat, 0.0f, 1.0f);
                g->added[i] += dtg * pos(1.0f - S[i]) * N[i] * G * refused * kin;
            }
}

/* Allocates the keloid's added volume on a keloid grid that has none yet. */
static ss_status keloid_alloc(const ss_heal_solver *s, ss_heal_grid *g, ss_error *err) {
    if (g->added || !(s->ctx.lamkrho > 0.0f) || !(s->ctx.kgain > 0.0f)) return SS_OK;
    g->added = calloc((size_t)g->nx * (size_t)g->ny * (size_t)g->nz, sizeof *g->added);
    return g->added ? SS_OK : ss_error_set(err, SS_ERR_NOMEM, "heal step: out of memory");
}

ss_status ss_heal_step_phase(ss_heal_solver *s, ss_heal_grid *g, int phase, ss_error *err) {
    const int has_vel = g && (g->velocity[0] || g->velocity[1] || g->velocity[2]);
    if (!s || !g || s->scheme != SS_HEAL_SPLIT || phase < 0 || phase > 2 ||
        (has_vel && !s->w->have_buf))
        return ss_error_set(err, SS_ERR_INPUT,
                            "heal step phase: the split scheme, phase 0..2, a velocity only on "
                            "a solver created with it");
    if (g->nx != s->nx || g->ny != s->ny || g->nz != s->nz)
        return ss_error_set(err, SS_ERR_INPUT, "heal step phase: grid does not match the solver");
    if (phase == 2 && keloid_alloc(s, g, err)) return err ? err->code : SS_ERR_NOMEM;
    bind_grid(s, g);
    ss_heal_rd__step_split_phase(&s->sys, s->w, s->dt, s->nsub, phase);
    /* the convection swaps the fields with the work buffers */
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) g->field[f] = s->sys.u[f];
    if (phase == 2) {
        keloid_volume(s, g);
        g->t_days += s->dt;
        g->step++;
    }
    return SS_OK;
}

float *ss_heal_solver_multipliers(ss_heal_solver *s, int slot) {
    if (!s || !s->w || !s->w->have_mslot || slot < 0 || slot >= s->sys.nslots) return NULL;
    return s->w->mslot[slot];
}

int ss_heal_solver_nslots(const ss_heal_solver *s) { return s ? s->sys.nslots : 0; }

/* What every step does first: check the grid, point the system at its
 * fields and velocity, re-check the explicit limit under a velocity. */
static ss_status step_begin(ss_heal_solver *s, ss_heal_grid *g, ss_error *err) {
    if (!s || !g) return ss_error_set(err, SS_ERR_INPUT, "heal step: no solver or grid");
    if (g->nx != s->nx || g->ny != s->ny || g->nz != s->nz)
        return ss_error_set(err, SS_ERR_INPUT,
                            "heal step: grid %dx%dx%d does not match the solver's %dx%dx%d", g->nx,
                            g->ny, g->nz, s->nx, s->ny, s->nz);
    ss_status sa = keloid_alloc(s, g, err);
    if (sa) return sa;
    bind_grid(s, g);
    const int has_vel = g->velocity[0] || g->velocity[1] || g->velocity[2];
    if (has_vel) {
        double speed = ss_heal_rd_max_speed(&s->sys);
        if (s->scheme == SS_HEAL_EXPLICIT) {
            double lim = ss_heal_rd_explicit_dt(&s->sys);
            if (s->dt > lim * (1.0 + 1e-12))
                return ss_error_set(err, SS_ERR_INPUT,
                                    "heal step: velocity up to %g mm/day lowers the explicit "
                                    "limit to %g days < dt %g days",
                                    speed, lim, s->dt);
        } else if (!s->w->have_buf && speed > 0) {
            return ss_error_set(err, SS_ERR_INPUT,
                                "heal step: a velocity field was attached after the split "
                                "solver was created; create the solver with the velocity set");
        }
    }
    return SS_OK;
}

static void step_end(ss_heal_solver *s, ss_heal_grid *g) {
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) g->field[f] = s->sys.u[f];
    keloid_volume(s, g);
    g->t_days += s->dt;
    g->step++;
}

ss_status ss_heal_step(ss_heal_solver *s, ss_heal_grid *g, ss_error *err) {
    ss_status st = step_begin(s, g, err);
    if (st) return st;
    if (s->scheme == SS_HEAL_EXPLICIT)
        ss_heal_rd_step_explicit(&s->sys, s->w, s->dt);
    else
        ss_heal_rd_step_split(&s->sys, s->w, s->dt, s->nsub);
    step_end(s, g);
    return SS_OK;
}

ss_status ss_heal_step_part(ss_heal_solver *s, ss_heal_grid *g, int part, int ring, ss_error *err) {
    if (!s || s->scheme != SS_HEAL_EXPLICIT || (part != 1 && part != 2))
        return ss_error_set(err, SS_ERR_INPUT, "heal step part: the explicit scheme, part 1 or 2");
    if (part == 1) {
        ss_status st = step_begin(s, g, err);
        if (st) return st;
        ss_heal_rd__step_explicit_part(&s->sys, s->w, s->dt, RD_PART_INTERIOR, ring);
        return SS_OK;
    }
    if (!g || g->nx != s->nx || g->ny != s->ny || g->nz != s->nz)
        return ss_error_set(err, SS_ERR_INPUT, "heal step part: grid does not match the solver");
    ss_heal_rd__step_explicit_part(&s->sys, s->w, s->dt, RD_PART_RING, ring);
    step_end(s, g);
    return SS_OK;
}
