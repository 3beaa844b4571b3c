/* The coupled mechanics object, shared by src/mech/mech.c (set-up, frames,
 * state) and src/mech/output.c (VTU, top view). Not a public header. */
#ifndef SKINSIM_MECH_INTERNAL_H
#define SKINSIM_MECH_INTERNAL_H

#include <math.h>

#include "skinsim/mech.h"

struct ss_mech {
    ss_mech_params p;
    int nx, ny, nz;
    double dx;
    double n_healthy;    /* fibroblast level of intact skin */
    ss_tetmesh *mesh;    /* reference mesh */
    ss_springs *S;       /* springs; S->x are the current positions */
    ss_mech_transfer *T; /* grid <-> particle */
    double kernel_width;
    uint8_t *mask;           /* tissue cells */
    uint8_t *wound0;         /* initial wound cells */
    uint8_t *side;           /* per node: on a side face (far-field boundary) */
    uint8_t *foot;           /* per column: the initial wound's footprint */
    float *ecm;              /* rho_ecm / rho_ecm_hat per cell (scratch) */
    float *myo;              /* wound fibroblast density per cell (scratch) */
    float *gf, *cov;         /* growth factor and epithelial cover per cell (scratch) */
    float *rhoc;             /* the wound matrix's collagen per cell (scratch) */
    double *usub[3], *thsub; /* sub-lattice displacement and volumetric strain */
    uint8_t *usub_valid;
    float *u[3];                        /* grid displacement, mm (filled on demand) */
    double *kbase;                      /* undamaged spring stiffness */
    double *rest_old, *k_old;           /* the last frame's rest lengths and stiffness */
    int last_inverted, last_increments; /* folded tets after the frame, load increments */
    double *nmyo, *nth, *necm, *stress; /* per node */
    double *nmf, *nproto;               /* per node: myofibroblast, proto fractions */
    double *ngf, *ncov, *nrho;          /* per node: growth factor, cover, wound collagen */
    double *nact;                       /* per node (goh): n m K_m_goh after its lag */
    double *vel;                        /* 3n, mm/day */
    double *xprev, *grad, *disp;
    int32_t *tri; /* top surface triangles (3 per) */
    uint8_t *tri_wound;
    int ntri;
    int nsutures;
    int ntissue;        /* springs before the first stitch spring */
    int *suture_spring; /* first spring of stitch i; its springs run to suture_spring[i+1] */
    double *suture_day;
    double outline0;
    int last_substeps, last_converged;
    double last_vmax;
    long frames;
    ss_hyper *H; /* the hyperelastic tissue (model goh; NULL for springs) */
};

/* The GOH path (mech_goh.c): set-up after the springs, sutures and
 * transfer exist (solves the day-0 gape), and steps 2-3 of a frame. */
ss_status ss_mech_goh_setup(ss_mech *m, ss_error *err);
ss_status ss_mech_goh_frame(ss_mech *m, const ss_heal_grid *g, double dt_days, ss_error *err);

/* Sub-lattice level of the transfer (bspline.c): P2G without the upsampling,
 * copies of the sub-lattice values, upsampling of stored values, divergence
 * and G2P on the sub-lattice. */
void ss_mech_p2g_sub(ss_mech_transfer *t, const double *pts, int np, const double *val,
                     const double *grad, int ncomp);
size_t ss_mech_sub_count(const ss_mech_transfer *t);
void ss_mech_sub_get(const ss_mech_transfer *t, int ncomp, double **vals, uint8_t *valid);
void ss_mech_sub_upsample(const ss_mech_transfer *t, double *const *vals, const uint8_t *valid,
                          int ncomp, const uint8_t *mask, float **out);
void ss_mech_sub_divergence(const ss_mech_transfer *t, double *const *u, const uint8_t *uv,
                            double *div);
void ss_mech_g2p_sub(const ss_mech_transfer *t, const double *sub, const uint8_t *valid,
                     const double *pts, int np, double *out);

/* 1 when the point (x, y) in mm lies over a column of the initial wound's
 * footprint, 0 elsewhere and outside the grid */
static inline int ss_mech_in_foot(const ss_mech *m, double x, double y) {
    int ix = (int)floor(x / m->dx), iy = (int)floor(y / m->dx);
    return ix >= 0 && iy >= 0 && ix < m->nx && iy < m->ny && m->foot[(size_t)iy * m->nx + ix];
}

#endif
