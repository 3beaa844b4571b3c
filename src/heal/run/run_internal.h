/* Internal to src/heal (run side): the state of an ss_heal_run shared by
 * run.c (object, stepping, accessors), run_setup.c (fresh set-up and resume)
 * and run_output.c (snapshots, checkpoints and their metadata, tables). Not
 * installed; other modules use skinsim/heal_run.h. */
#ifndef SKINSIM_HEAL_RUN_INTERNAL_H
#define SKINSIM_HEAL_RUN_INTERNAL_H

#include <cjson/cJSON.h>

#include "skinsim/heal_run.h"
#include "skinsim/mech.h"
#include "skinsim/mesh.h"

struct ss_heal_run {
    ss_heal_run_config c; /* copy; string fields point at the caller's strings */
    char *out_dir;        /* where files go: out_dir (resume_dir on resume) until the outputs
                             begin, then the folder they stage or write in place; NULL = in memory */
    ss_outputs *outs;     /* the output folder's discipline (src/core/output.c) */
    int failed;           /* an output step failed: the run is stopped */
    char scenario[32];
    ss_heal_params *p;
    ss_heal_grid *g;
    ss_heal_solver *s;
    char *params_json;
    ss_heal_scheme scheme;
    double dt, days; /* days: the requested end (recorded in checkpoints) */
    long long nsteps, snap_every, area_every, ckpt_every;
    ss_heal_area_row *rows;
    int nrows, caprows;
    double *snap_t;
    char **snap_file;
    int nsnap, capsnap;
    double t0, wall_prev; /* wall clock at create; wall time of the runs before a resume */
    long long resumed_from;
    char run_id[33]; /* made when the run starts (run.json, every checkpoint); "" = none */
    int started;     /* output directory prepared (and day-0 snapshot written) */
    char note[2048];
    cJSON *wound; /* description for summary.json */
    /* contraction mechanics (run_mech.c); mech NULL when off */
    ss_mech *mech;
    ss_heal_grid *mg; /* distributed: the grid the mechanics read and write (rank 0) */
    int mech_pending; /* distributed: the mechanics wait for ss_heal_run_mech_attach */
    ss_mech_params mp;
    ss_mech_suture *sutures;
    int nsutures;
    double *outline; /* per area row: the deformed initial outline's area, mm^2 */
    double *myof;    /* per area row: mean myofibroblast fraction under the wound */
    int capoutline;
    int closed; /* 95 % closure reached; close_* hold the state then */
    double close_day;
    ss_mech_stats close_st;
    cJSON *mech_aux;    /* the checkpoint's "mechanics" object while resuming */
    double *closed_day; /* closure day per column (ss_heal_closure_update), nx*ny */
    /* adaptive steps (run.c): a step is mult x dt; adapt_tol 0 = fixed */
    double adapt_tol;
    long long mult, mult_max, retried, taken;
    float *backup[SS_HEAL_NFIELDS]; /* the fields before the step (change bound, retry) */
    /* real geometry (run_shell.c); shell NULL on the flat block */
    struct ss_shell_patch *shell;
    ss_mesh skin;
    ss_mesh surf; /* skin refined around the wound: the mesh the snapshots map onto */
    char *skin_path, *wound_path; /* owned copies (a resume re-reads them) */
    int wound_is_uv;
    double shell_opts[6]; /* voxel, thickness, epidermis, depth, margin, units */
    int shell_concave;
    float *vfields;          /* per surf vertex, SS_SHELL_VERTEX_STRIDE floats */
    cJSON *shell_aux;        /* the checkpoint's "shell" object while resuming */
    int32_t *shell_top;      /* distributed: each column's top tissue level (or -1) */
    ss_heal_run_hooks hooks; /* an external solver (src/mpi); members NULL = none */
    /* distributed (c.distributed): g has sizes, time and step but no arrays
     * (cell NULL) once the boxes are out; the wound the boxes are built from */
    double epidermis_mm;
    int32_t *wcols;        /* per-column level ranges (ss_heal_wound_columns_*), or */
    ss_tri_mesh wmesh;     /* the closed wound mesh (ntris 0 = none) */
    long long pieces_step; /* resumed from a checkpoint in pieces, not loaded: its step;
                              else -1 */
    ss_heal_run_checkpoint_fn
        ckpt_fn; /* a checkpoint writer instead of the run's own; NULL = none */
    void *ckpt_ctx;
    int (*progress)(void *user, double day); /* ss_heal_run_set_progress; NULL = none */
    void *progress_user;
};
/* Brings r->g's fields up to date when an external solver steps it. */
ss_status ss_heal_run__sync(ss_heal_run *r, ss_error *err);

/* run.c */
ss_status ss_heal_run__add_row(ss_heal_run *r, ss_error *err);
/* mult = 1 and mult_max from dt (adaptive steps; adapt_tol already set). */
void ss_heal_run__adapt_init(ss_heal_run *r);
ss_status ss_heal_run__add_snap(ss_heal_run *r, double t, const char *file, ss_error *err);

/* run_setup.c: fill r from r->c (no file is written) */
ss_status ss_heal_run__setup_fresh(ss_heal_run *r, ss_error *err);
ss_status ss_heal_run__setup_resume(ss_heal_run *r, ss_error *err);

/* run_output.c */
/* Writes a snapshot now (the outputs must have begun). */
ss_status ss_heal_run__snapshot(ss_heal_run *r, ss_error *err);
/* out_dir/dir/stem.pvd: the time series of stem_0000.vtu .. stem_NNNN.vtu, one
 * file per snapshot so far (r->snap_t) plus the one being written now. */
ss_status ss_heal_run__series_pvd(const ss_heal_run *r, const char *dir, const char *stem,
                                  ss_error *err);
/* Checkpoint metadata: intervals, seed, wall time, wound, area rows, snapshots. */
char *ss_heal_run__aux_json(const ss_heal_run *r, double wall);
ss_status ss_heal_run__aux_restore(ss_heal_run *r, const char *aux, const char *dir, ss_error *err);
/* Checks the output folder before any work (a previous run needs force; a
 * path the core refuses) and registers the inputs and the disk estimate. */
ss_status ss_heal_run__outputs_open(ss_heal_run *r, ss_error *err);
ss_status ss_heal_run__outputs_precheck(ss_heal_run *r, ss_error *err);
/* Begins the outputs (lock, leftovers, disk, staging), points out_dir at
 * where files go, makes fields/ and surface/, writes run.json (fresh runs). */
ss_status ss_heal_run__prepare_out_dir(ss_heal_run *r, ss_error *err);
/* run.json: the run's identity (run id, scenario, grid, parameter hash). */
ss_status ss_heal_run__write_identity(const ss_heal_run *r, ss_error *err);
/* A new run's id (random, 32 hex digits) into r->run_id. */
void ss_heal_run__new_run_id(ss_heal_run *r);
/* Every checkpoint in dir must belong to the run dir/run.json names (its run
 * id, and the grid, scenario and parameters of its identity), `newest` too:
 * SS_ERR_INPUT naming a foreign one, or a missing or older identity. On
 * success the run id goes into r->run_id. Reads only. */
ss_status ss_heal_run__check_identity(ss_heal_run *r, const char *dir,
                                      const ss_heal_checkpoint *newest, ss_error *err);
/* area.csv, area.png, summary.json; the summary as cJSON in *summary. */
ss_status ss_heal_run__write_tables(ss_heal_run *r, double wall, cJSON **summary, ss_error *err);
cJSON *ss_heal_run__summary(const ss_heal_run *r, double wall);

/* run_mech.c: the contraction mechanics inside a run */
ss_status ss_heal_run__mech_setup_fresh(ss_heal_run *r, ss_error *err);
/* The mechanics options that need no grid, checked before long work. */
ss_status ss_heal_run__mech_check_options(ss_heal_run *r, ss_error *err);
ss_status ss_heal_run__mech_setup_resume(ss_heal_run *r, const char *dir, ss_error *err);
ss_status ss_heal_run__mech_row(ss_heal_run *r, ss_error *err); /* after a row was added */
ss_status ss_heal_run__mech_snapshot(ss_heal_run *r, int idx, ss_error *err);
void ss_heal_run__mech_aux(const ss_heal_run *r, cJSON *aux); /* into checkpoint metadata */
void ss_heal_run__mech_summary(const ss_heal_run *r, cJSON *summary);
/* Extra area.csv columns: *names (static) and values n x ncols (malloc'd); 0 when off. */
int ss_heal_run__mech_columns(const ss_heal_run *r, const char *const **names, double **vals);
void ss_heal_run__mech_free(ss_heal_run *r);

/* run_shell.c: a run on a skin mesh (skinsim/shell.h) */
int ss_heal_run__shell_wanted(const ss_heal_run_config *c);
/* Loads and checks the mesh and the wound, builds r->g on the patch. */
ss_status ss_heal_run__shell_setup_fresh(ss_heal_run *r, ss_error *err);
ss_status ss_heal_run__shell_setup_resume(ss_heal_run *r, ss_error *err);
ss_status ss_heal_run__shell_snapshot(ss_heal_run *r, int idx, ss_error *err);
void ss_heal_run__shell_aux(const ss_heal_run *r, cJSON *aux);
void ss_heal_run__shell_summary(const ss_heal_run *r, cJSON *summary);
void ss_heal_run__shell_free(ss_heal_run *r);

#endif
