/* skinsim dist: the MPI side of skinsim (built only when CMake finds MPI;
 * SKINSIM_HAVE_MPI is then defined for code linking skinsim_dist). Not
 * installed and not API: skinsim_dist is linked into the skinsim program
 * only (run it under mpirun), not into libskinsim. The
 * healing solver on a Cartesian decomposition of the grid (seed 001 §4.1 on
 * §5.1's grid, explicit and split schemes) and the ModelMatch table (seed 003 §4.8.6)
 * with entries shared out dynamically; both bit-identical to one process.
 * docs/scaling.md describes the decomposition, the protocol and the figures.
 *
 *   ss_dist_init(&argc, &argv);            // MPI_Init only under mpirun
 *   if (ss_dist_size() > 1) ...             // rank 0 drives, the others serve
 *   ss_dist_finalize();
 */
#ifndef SKINSIM_DIST_H
#define SKINSIM_DIST_H

#include "skinsim/core.h"
#include "skinsim/heal_run.h"
#include "skinsim/optics_fit.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Initialises MPI (threads funnelled to the main one) when the process was
 * started by mpirun (OMPI_COMM_WORLD_SIZE, PMIX_RANK or PMI_SIZE in the
 * environment) or SKINSIM_MPI=1; otherwise nothing, and the process is rank 0
 * of 1. Returns 0, or -1 if MPI_Init failed. */
int ss_dist_init(int *argc, char ***argv);
/* MPI_Finalize when ss_dist_init initialised MPI. */
void ss_dist_finalize(void);
int ss_dist_rank(void);   /* 0 without MPI */
int ss_dist_size(void);   /* 1 without MPI */
int ss_dist_active(void); /* 1 when ss_dist_init initialised MPI (under mpirun) */

/* ---- healing on MPI ---- */
typedef struct ss_dist_heal ss_dist_heal;
/* Collective. Rank 0 passes its run, created with config.distributed (every
 * input validated, no whole grid made; a resume may have loaded a whole-grid
 * checkpoint, which is handed out and then dropped), or NULL with root_st the
 * status of its create; the other ranks pass NULL and SS_OK. Rank 0 checks
 * what the distributed solver needs (no mechanics, no skin mesh, at least one
 * column per rank in x and y), decomposes the grid, every rank builds its box
 * with a one-cell halo (from the wound, or from the checkpoint's pieces), and
 * rank 0 hooks the run (ss_heal_run_set_hooks, ss_heal_run_set_checkpoint_hook)
 * so its steps, area rows, surface maps, snapshot pieces and checkpoint
 * pieces run on all ranks. Every rank returns the same status; messages on
 * rank 0 name the input (another rank's set-up error is sent to rank 0). */
ss_status ss_dist_heal_create(ss_heal_run *r, ss_status root_st, ss_dist_heal **out, ss_error *err);
/* Ranks other than 0: carry out rank 0's commands until it ends the run;
 * returns rank 0's final status. */
ss_status ss_dist_heal_serve(ss_dist_heal *d, ss_error *err);
/* Rank 0: ends the run on every rank with status st (after finish, or after
 * a failure). Collective with ss_dist_heal_serve. */
void ss_dist_heal_end(ss_dist_heal *d, ss_status st);
/* Seconds (largest over the ranks, after end): kernel compute, halo
 * exchange, statistics reductions, gathers to rank 0; and the process grid. */
typedef struct ss_dist_heal_timing {
    double compute_s, halo_s, stats_s, gather_s, halo_bytes_per_step;
    int dims[3];
    long long steps;
    const double *rss_mb; /* peak resident memory of every rank (getrusage ru_maxrss), MB,
                             dims[0]*dims[1]*dims[2] values; owned by the driver */
    /* --mechanics (on rank 0): the gather of the fields they read and the
     * scatter of their velocity, seconds in all (rank 0) and bytes moved per
     * coupling step (rank 0's own box not counted) */
    double mech_s, mech_bytes_per_step;
} ss_dist_heal_timing;
void ss_dist_heal_timing_get(const ss_dist_heal *d, ss_dist_heal_timing *t);
void ss_dist_heal_free(ss_dist_heal *d);

/* ---- the ModelMatch table on MPI ---- */
/* Collective. Every rank passes its table (same axes: from the same command
 * line) and options; rank 0 passes root_st, the status of its own checks
 * (the output file), the others SS_OK. Rank 0 hands out geometries to the
 * other ranks as they finish (ss_mm_table_build_geometry) and collects their
 * entries: on rank 0, t then has the bytes of ss_mm_table_build for the same
 * seed. One rank: ss_mm_table_build. Every rank returns rank 0's status. */
ss_status ss_dist_mm_table_build(ss_mm_table *t, const ss_mm_build_options *o, ss_status root_st,
                                 ss_error *err);

#ifdef __cplusplus
}
#endif
#endif
