/* Internal to src/heal (solver side): the work memory of the generic
 * reaction-diffusion core shared by explicit.c and split.c, and the model
 * hooks model.c gives the solver. Not installed; other modules use heal.h. */
#ifndef SKINSIM_HEAL_INTERNAL_H
#define SKINSIM_HEAL_INTERNAL_H

#include "skinsim/heal.h"

/* Grids with fewer cells run on one thread: for them the OpenMP barriers cost
 * more than the work (and much more on an oversubscribed machine). Results do
 * not depend on it (every cell is computed independently either way). */
#define RD_PAR_MIN_CELLS ((size_t)32768)

/* Neighbour bits of nb[]: bit k set when the face towards neighbour k
 * conducts (both cells are not walls). Order -x, +x, -y, +y, -z, +z. */
enum { NB_XM = 1, NB_XP = 2, NB_YM = 4, NB_YP = 8, NB_ZM = 16, NB_ZP = 32 };

struct ss_heal_rd_work {
    int nx, ny, nz, nfields, nslots;
    size_t ncell;
    uint8_t *nb;                   /* per cell neighbour bits */
    uint8_t *upd[SS_HEAL_RD_MAXF]; /* per field: 1 = cell is updated (not wall/fixed) */
    uint8_t *upd_common;           /* 1 = not a wall; upd[f] of every field without fixed classes */
    float *buf[SS_HEAL_RD_MAXF];   /* explicit: next values; split: convection scratch */
    float *mslot[SS_HEAL_RD_MAXSLOT]; /* split: frozen diffusion multipliers */
    int nthreads;                     /* per-thread scratch count */
    float **tscratch;                 /* per thread row/line scratch */
    size_t tscratch_len;              /* floats per thread */
    size_t ones_off;                  /* offset of a row of nx ones in each thread scratch */
    int have_buf, have_mslot;
};

/* The explicit step in parts (the MPI driver, src/mpi, overlaps its halo
 * exchange with the interior): ALL = ss_heal_rd_step_explicit; INTERIOR =
 * the prepare hook and every cell whose stencil does not reach the faces of
 * the box's outer shell named in `ring` (NB_* bits: the halo still in
 * flight), no buffer swap; RING = the remaining cells, then the swap.
 * INTERIOR then RING computes every cell as ALL does, in the same
 * arithmetic: the same values. */
enum { RD_PART_ALL = 0, RD_PART_INTERIOR = 1, RD_PART_RING = 2 };
void ss_heal_rd__step_explicit_part(ss_heal_rd_system *sys, ss_heal_rd_work *w, double dt, int part,
                                    int ring);

/* Shared helpers (explicit.c) */
void ss_heal_rd__build_masks(const ss_heal_rd_system *sys, ss_heal_rd_work *w);
/* Donor-cell convection of field f from src into dst over dt (dst may not
 * alias src). */
void ss_heal_rd__convect(const ss_heal_rd_system *sys, const ss_heal_rd_work *w, int f,
                         const float *src, float *dst, double dt);

/* Split step in phases (split.c): 0 = first reaction half, convection, x
 * sweep; 1 = y sweep; 2 = z sweep, second reaction half. */
void ss_heal_rd__step_split_phase(ss_heal_rd_system *sys, ss_heal_rd_work *w, double dt, int nsub,
                                  int phase);

/* ---- I/O shared between files ---- */
/* A box of whole-grid cells: lo[3], n[3]. */
typedef struct ss_heal_box {
    int lo[3], n[3];
} ss_heal_box;
/* NULL when the nbox boxes tile the whole grid exactly (each inside it, no
 * two overlapping, their volumes adding up to it), else why not with *bad the
 * offending box (-1: a gap). Boxes are read from base with a stride of
 * `stride` bytes (each element begins with an ss_heal_box). Quadratic in
 * nbox. (checkpoint_pieces.c) */
const char *ss_heal__boxes_tile(const int whole[3], int nbox, const void *base, size_t stride,
                                int *bad);
/* A .vti piece of a parallel image (vti.c): the grid of its Piece Extent
 * (allocated at least 3 wide, nx ny nz set to the piece's), whole from its
 * WholeExtent and off from its Piece Extent; otherwise as ss_heal_vti_read. */
ss_heal_grid *ss_heal__vti_read_piece(const char *path, int whole[3], int off[3],
                                      float **displacement, double **closed_day, ss_error *err);

/* clamp without the libm call fminf/fmaxf need without -ffast-math */
static inline float clampf(float v, float lo, float hi) {
    v = v > lo ? v : lo;
    return v < hi ? v : hi;
}

/* A face slot's multiplier of a cell from its field value u: 1 - u in
 * [0, 1], 0 above `closed` (ss_heal_rd_system.mface_closed; inf: never). The
 * explicit scheme and the model's reaction (for the split scheme) share it. */
static inline float face_m(float u, float closed) {
    return u > closed ? 0.0f : clampf(1.0f - u, 0.0f, 1.0f);
}

#endif
