/* The coupled mechanics object, shared by src/mech/mech.c (set-up, frames,
 * state) and src/mech/output.c (VTU, top view). Not a public header. */
#ifndef SKINSIM_MECH_INTERNAL_H
#define SKINSIM_MECH_INTERNAL_H

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
    uint8_t *mask;                      /* tissue cells */
    uint8_t *wound0;                    /* initial wound cells */
    float *ecm;                         /* rho_ecm / rho_ecm_hat per cell (scratch) */
    float *myo;    /* myofibroblast density per cell (scratch) */
    float *theta;                       /* grid volumetric strain */
    float *u[3];                        /* grid displacement, mm */
    double *kbase;                      /* undamaged spring stiffness */
    double *nmyo, *nth, *necm, *stress; /* per node */
    double *vel;                        /* 3n, mm/day */
    double *xprev, *grad, *disp;
    int32_t *tri; /* top surface triangles (3 per) */
    uint8_t *tri_wound;
    int ntri;
    int nsutures;
    int *suture_spring;
    double *suture_day;
    double outline0;
    int last_substeps, last_converged;
    double last_vmax;
    long frames;
};

#endif
