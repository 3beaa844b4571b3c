/* skinsim heal_run: one healing simulation as an object (seed 001 §4.1 on the
 * §5.1 grid): set-up of a fresh run (parameters, grid geometry, wound from a
 * mask, strokes, depth image or closed mesh) or resume from a checkpoint,
 * stepping with the bookkeeping a run needs (the area curve of Fig. 4, VTK and
 * surface-map snapshots, checkpoints), and the closing tables (area.csv,
 * area.png, summary.json). `skinsim heal`, `skinsim wound`, the viewer and the
 * MPI driver all run through it; the CLI only parses options and prints.
 *
 *   ss_heal_run_config c;
 *   ss_heal_run_config_default(&c);
 *   c.scenario = "scab"; c.days = 28; c.out_dir = NULL;  // in memory
 *   ss_heal_run *r;
 *   if (ss_heal_run_create(&c, &r, &err)) ...;           // nothing written yet
 *   ss_heal_run_advance_to(r, 3.0, &err);                 // fields at day 3
 *   const ss_heal_grid *g = ss_heal_run_grid(r);
 *   ...
 *   ss_heal_run_free(r);
 *
 * Error messages name the setting by its `skinsim heal` option (a config field
 * `wound_depth_mm` is `--wound-depth-mm`). Outputs are described in
 * docs/heal-outputs.md. Units: mm and days. */
#ifndef SKINSIM_HEAL_RUN_H
#define SKINSIM_HEAL_RUN_H

#include <stdint.h>

#include "skinsim/core.h"
#include "skinsim/heal.h"
#include "skinsim/heal_io.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Simulated time when config.days is 0 on a fresh run. */
#define SS_HEAL_RUN_DEFAULT_DAYS 10.0
/* adapt_tol of `skinsim heal` with the split scheme and the automatic step. */
#define SS_HEAL_RUN_DEFAULT_ADAPT_TOL 0.01

typedef struct ss_heal_run_config {
    /* ---- model (fresh runs) ---- */
    const char *scenario; /* "clean" | "scab" | "keloid"; NULL = the params file's
                             "scenario" key, else "clean" */
    const char
        *params_path;  /* JSON parameter overrides (data/heal/params.json form); NULL = none */
    int no_scab;       /* 1: switch off eschar formation */
    int static_region; /* 1: keep the wound region fixed (no keloid growth) */

    /* ---- grid (fresh runs) ---- */
    int grid[3];         /* voxels; all 0 = from size_mm with 0.5 mm voxels */
    double size_mm[3];   /* block size; all 0 = 30 x 30 x 4 mm (or grid x 0.5 mm) */
    double skin_top_mm;  /* skin surface height; 0 = nz-2 voxels (one air layer) */
    double epidermis_mm; /* default SS_HEAL_DEFAULT_EPIDERMIS_MM (a sub-voxel sheet in the
                            surface voxel when thinner than a voxel) */

    /* ---- wound (fresh runs): at most one of mask, stroke, mesh, footprint;
     * none = a centred square of 20 mm (at most 2/3 of the smaller side) ---- */
    const char *wound_mask;          /* PNG/EXR footprint over the block */
    const char *wound_stroke;        /* painted strokes CSV (u,v[,id]) over the block */
    int concave_k;                   /* with wound_stroke: k-nearest concave hull, 0 = convex */
    const char *wound_mesh;          /* closed OBJ in mm in the grid frame */
    const ss_image *wound_footprint; /* in-memory footprint (1 channel, > 0.5 = wound, row 0 at
                                       the far y edge); not owned, used during create only */
    double wound_depth_mm;           /* 0 = SS_HEAL_DEFAULT_DEPTH_MM */
    const char *wound_depth_image;   /* per-pixel depth (PNG x depth, EXR in mm) */

    /* ---- time ---- */
    double days;             /* end of the run; 0 = SS_HEAL_RUN_DEFAULT_DAYS, or the
                                checkpoint's end on resume */
    ss_heal_scheme scheme;   /* default SS_HEAL_SPLIT */
    double dt_days;          /* 0 = automatic */
    double snapshot_every;   /* days between snapshots; 0 = first and last only (default 1) */
    double area_every;       /* days between area rows (default 0.01, at least one step) */
    double checkpoint_every; /* days between checkpoints; 0 = none; < 0 = default (none, or
                                the checkpoint's interval on resume) */

    /* ---- files ---- */
    const char *out_dir;      /* run directory; NULL = in memory, no file written */
    int force;                /* 1: replace a previous run's outputs in out_dir */
    const char *resume_dir;   /* continue the run in this directory from its newest valid
                                 checkpoint (bit-identical to an uninterrupted run); the model,
                                 grid, wound and intervals then come from the checkpoint: only
                                 days and checkpoint_every are taken from this config */
    uint64_t seed;            /* recorded in summary.json (the solver draws no random numbers) */
    int checkpoint_pieces[3]; /* all > 0: checkpoints as px x py x pz pieces and a header
                                 (ss_heal_checkpoint_save_pieces); 0 = one whole-grid file */

    /* ---- contraction mechanics (seed 001 §4.2-5.3, docs/mech.md; fresh runs) ---- */
    int mechanics;        /* 1: mass-spring contraction drives the convection (default 0) */
    const char *fibres;   /* "X,Y,Z[:X,Y,Z]" fibre families; NULL = params file or default */
    double kappa;         /* fibre dispersion 0..1/3; < 0 = params file or default */
    double tet_size_mm;   /* lattice tet edge; 0 = params file or default */
    const char *sutures;  /* stitches CSV "x1,y1,z1,x2,y2,z2[,remove_day]" (mm); NULL = none */
    const char *tet_mesh; /* TetGen .node/.ele or Gmsh .msh instead of the lattice; NULL */

    /* "springs" or "goh" (ss_mech_params.model); NULL = params file or default */
    const char *mech_model;

    /* ---- adaptive steps (split scheme without mechanics; fresh runs) ---- */
    double adapt_tol; /* 0 = fixed steps of dt (default). > 0: a step is m x dt (m = 1..
                         SS_HEAL_SPLIT_LATE_MAX_DT_DAYS / dt), m doubled while no species
                         changes by more than adapt_tol / 2 in any cell in a step, and a
                         step that changes one by more than adapt_tol is retried with half
                         the m (docs/heal-model.md §4); `skinsim heal` uses 0.01 */
    /* ---- real geometry (seed 001 §5.1, §5.4; skinsim/shell.h; fresh runs) ---- */
    const char *skin_mesh;    /* closed OBJ/glTF/GLB body surface; the grid is a patch of its
                                 skin around the wound (then wound_uv or wound_mesh, in the
                                 mesh's units, gives the wound); NULL = the flat block */
    const char *wound_uv;     /* with skin_mesh: strokes CSV (u,v[,stroke]) in the mesh's UV
                                 space, cut wound_depth_mm deep */
    double skin_thickness_mm; /* with skin_mesh: skin shell under the surface; 0 = 3 mm */
    double voxel_mm;          /* with skin_mesh: voxel edge; 0 = 0.5 mm */
    double mesh_units_mm;     /* with skin_mesh: one mesh unit in mm; 0 = glTF 1000, OBJ 1 */

    /* ---- distributed (rank 0 of the MPI driver, src/mpi; docs/scaling.md) ---- */
    int distributed; /* 1: every input is checked as usual, but no whole grid is made: a
                        fresh run's grid (ss_heal_run_grid) has its sizes, voxel, skin
                        surface, time and step and no cell or field arrays, and the wound
                        is kept for the boxes (ss_heal_run_wound_columns / _mesh); a
                        resumed one loads the checkpoint's grid, which the driver hands out
                        and then drops (ss_heal_run_release_grid). No solver is made (only
                        its step checks). With mechanics they wait for the driver's grid
                        (ss_heal_run_mech_attach); with skin_mesh rank 0 builds the
                        patch's grid once, as for a resume, and keeps its column tops
                        (ss_heal_run_shell_tops). The driver's hooks then do everything
                        that needs the fields. */
} ss_heal_run_config;

/* The defaults listed above (every other field 0 / NULL). */
void ss_heal_run_config_default(ss_heal_run_config *c);

typedef struct ss_heal_run ss_heal_run;

/* Validates every input (including that out_dir is writable and holds no
 * previous run unless force), builds the grid and the solver, or loads the
 * newest valid checkpoint of resume_dir. Writes no file. Bad input ->
 * SS_ERR_INPUT naming it. A fresh run has its day-0 area row. */
ss_status ss_heal_run_create(const ss_heal_run_config *c, ss_heal_run **out, ss_error *err);
void ss_heal_run_free(ss_heal_run *r);

/* With out_dir: begins the outputs now (src/core/output.c): takes the
 * folder's lock (another run writing it -> SS_ERR_INPUT naming its process),
 * removes what killed runs left next to it, checks the estimated disk use
 * against the free space (SS_ERR_INPUT with both figures), stages the folder
 * (--force over a previous run) or marks it unfinished (a new or resumed
 * one), writes run.json and the day-0 snapshot of a fresh run. The first step
 * does this if it was not called; calling it first lets a caller tell these
 * input errors from failures during the run. */
ss_status ss_heal_run_start(ss_heal_run *r, ss_error *err);
/* One solver step and its bookkeeping: an area row every area_every (and at
 * the end), with out_dir a snapshot every snapshot_every (and at the end) and a
 * checkpoint every checkpoint_every (newest two kept). With adapt_tol the step
 * may span several steps of dt (step indices count steps of dt); it never
 * jumps over a snapshot, a checkpoint or the end, and area rows come at least
 * every area_every and after every step. The first call that
 * writes files first removes a previous run's outputs (force) and writes the
 * day-0 snapshot of a fresh run. Stepping past the end -> SS_ERR_INPUT. */
ss_status ss_heal_run_step(ss_heal_run *r, ss_error *err);
/* Steps until the run reaches `day` (rounded to whole steps), at most to the
 * end; a day before the current time or after the end -> SS_ERR_INPUT. */
ss_status ss_heal_run_advance_to(ss_heal_run *r, double day, ss_error *err);
/* Optional: fn(user, day) is called from the calling thread after every solver
 * step of ss_heal_run_advance_to with the run's new day; a non-zero return
 * stops advance_to after that step with SS_ERR_RUNTIME ("cancelled"). The run
 * stays valid at that step, and advancing to the same day again goes on as
 * if it had not stopped. fn NULL removes it. */
void ss_heal_run_set_progress(ss_heal_run *r, int (*fn)(void *user, double day), void *user);
/* With out_dir: writes the outputs still due (the day-0 snapshot of a run
 * that never stepped), then area.csv, area.png and summary.json. Returns in
 * *summary_json (if not NULL) the summary as malloc'd JSON text without the
 * file's trailing newline. Without out_dir only the summary text is made. */
ss_status ss_heal_run_finish(ss_heal_run *r, char **summary_json, ss_error *err);

/* Writes a snapshot of the current state now (fields/fields_NNNN.vti, the
 * updated fields.pvd, surface/<field>_NNNN.png); needs out_dir. */
ss_status ss_heal_run_write_snapshot(ss_heal_run *r, ss_error *err);
/* Writes a checkpoint of the current state now (checkpoints/ckpt_<step>.sshc,
 * newest two kept) from which ss_heal_run_create resumes; needs out_dir. */
ss_status ss_heal_run_write_checkpoint(ss_heal_run *r, ss_error *err);

/* ---- an external solver (the MPI driver, src/mpi) ---- */
/* With hooks set, the run calls step instead of ss_heal_step (g's fields may
 * then be stale; an adaptive run's rejected step is taken back with undo), stats instead of
 * ss_heal_stats_compute for every area row, sync before anything reads g's
 * fields (snapshots, checkpoints) so it can bring them up to date, and
 * snapshot after each snapshot's .vti. NULL
 * members keep the run's own behaviour. With the contraction mechanics only
 * on a distributed run, with mech_in and mech_out. */
typedef struct ss_heal_run_hooks {
    void *ctx;
    /* one step of dt_days (the run's step or, adaptive, a multiple of it):
     * advances g->t_days by dt_days and g->step by one; with max_change not
     * NULL keeps a copy of the fields first and returns the largest change of
     * any species in any cell (the adaptive control) */
    ss_status (*step)(void *ctx, ss_heal_grid *g, double dt_days, double *max_change,
                      ss_error *err);
    /* puts the fields back as they were before the last step (t_days and
     * step are the run's to restore) */
    void (*undo)(void *ctx, ss_heal_grid *g);
    void (*stats)(void *ctx, const ss_heal_grid *g, ss_heal_stats *st);
    ss_status (*sync)(void *ctx, ss_heal_grid *g, ss_error *err);
    /* instead of ss_heal_closure_update after each accepted step: keeps the
     * closure day per column (skinsim/heal_io.h), current in closed_day
     * after sync */
    void (*closure)(void *ctx, ss_heal_grid *g, double *closed_day);
    /* after snapshot `index` was written into the folder fields_dir (more
     * files for it, e.g. per-rank pieces) */
    ss_status (*snapshot)(void *ctx, const ss_heal_grid *g, const char *fields_dir, int index,
                          ss_error *err);
    /* instead of ss_heal_surface_map for the snapshot's surface pictures */
    ss_image *(*surface_map)(void *ctx, const ss_heal_grid *g, int field, ss_heal_surface_mode mode,
                             ss_error *err);
    /* the contraction mechanics on a run without its whole grid (the MPI
     * driver): before each mechanics step, fill the mechanics grid mg
     * (ss_heal_run_mech_attach) with the fields the mechanics reads; after it
     * (velocity capped), hand mg's velocity to the solver */
    void (*mech_in)(void *ctx, ss_heal_grid *mg);
    void (*mech_out)(void *ctx, const ss_heal_grid *mg);
    /* a run on a skin mesh (--mesh) without its whole grid: the fields at
     * each column's top tissue cell (top: ss_heal_run_shell_tops) into vals,
     * nx*ny x SS_HEAL_NFIELDS (columns without one: untouched) */
    void (*columns)(void *ctx, const int32_t *top, float *vals);
} ss_heal_run_hooks;
/* Sets (h) or clears (NULL) the hooks; SS_ERR_INPUT when the run has the
 * contraction mechanics but no grid of their own (ss_heal_run_mech_attach) or
 * h lacks mech_in / mech_out (naming --mechanics). A run without its whole grid
 * (config.distributed) needs every hook and a checkpoint hook
 * (ss_heal_run_set_checkpoint_hook, set first); its snapshots are then the pieces
 * and .pvti the snapshot hook writes (fields.pvd lists fields_NNNN.pvti), and
 * a fresh one's day-0 area row is added here, through the stats hook. */
ss_status ss_heal_run_set_hooks(ss_heal_run *r, const ss_heal_run_hooks *h, ss_error *err);
/* A checkpoint writer instead of the run's own (ss_heal_checkpoint_save or,
 * with checkpoint_pieces, ss_heal_checkpoint_save_pieces), called after the
 * sync hook with the run's metadata: writes the checkpoint of g's state and
 * keeps the newest `keep`, e.g. as per-rank pieces (skinsim/heal_io.h,
 * "checkpoints in pieces"). fn NULL = the run's own again. */
typedef ss_status (*ss_heal_run_checkpoint_fn)(void *ctx, const ss_heal_grid *g,
                                               const char *run_dir, const char *scenario,
                                               const char *params_json, int scheme, double dt_days,
                                               const char *aux, int keep, ss_error *err);
void ss_heal_run_set_checkpoint_hook(ss_heal_run *r, ss_heal_run_checkpoint_fn fn, void *ctx);

/* ---- distributed set-up (config.distributed; src/mpi) ---- */
/* The fresh run's wound for the boxes: per-column level ranges (2 x nx*ny,
 * ss_heal_wound_columns_footprint) of a mask, strokes, footprint, depth image
 * or the built-in square, or (NULL columns) the closed wound mesh, which the
 * boxes voxelise (ss_heal_voxelise_mesh_box). Both NULL on a resumed run. */
const int32_t *ss_heal_run_wound_columns(const ss_heal_run *r);
const ss_tri_mesh *ss_heal_run_wound_mesh(const ss_heal_run *r);
double ss_heal_run_epidermis_mm(const ss_heal_run *r); /* for ss_heal_grid_init_box */
/* With a wound mesh: the checks the single-process set-up makes on the
 * voxelised mesh, from the totals over the boxes (inside voxels, and those
 * under the skin surface); SS_ERR_INPUT naming the mesh. */
ss_status ss_heal_run_wound_counted(ss_heal_run *r, size_t inside, size_t below, ss_error *err);
/* A distributed resume from a checkpoint in pieces (skinsim/heal_io.h): its
 * step, and in *dir the run folder, whose pieces every rank reads its box
 * from (ss_heal_ckpt_read_box); the grid was not loaded (no arrays). -1 when
 * the run is fresh or its checkpoint was a whole-grid file (then loaded). */
long long ss_heal_run_resume_pieces(const ss_heal_run *r, const char **dir);
/* Frees the grid's cell and field arrays (and the solver): from here on the
 * run holds no whole grid (a resumed distributed run, once its boxes are out). */
void ss_heal_run_release_grid(ss_heal_run *r);

/* ---- state ---- */
/* The grid holds all the state (fields, cells, t_days, step). A caller may
 * change fields or velocities between steps (the mechanics does). */
ss_heal_grid *ss_heal_run_grid(ss_heal_run *r);
const ss_heal_params *ss_heal_run_params(const ss_heal_run *r);
const char *ss_heal_run_scenario(const ss_heal_run *r);
ss_heal_scheme ss_heal_run_scheme(const ss_heal_run *r);
double ss_heal_run_day(const ss_heal_run *r); /* current time, days */
double ss_heal_run_dt(const ss_heal_run *r);  /* step, days (the base step with adapt_tol) */
/* Adaptive steps: current multiple m of dt, and the steps retried so far. */
long long ss_heal_run_step_multiple(const ss_heal_run *r);
long long ss_heal_run_steps_retried(const ss_heal_run *r);
double ss_heal_run_end_day(const ss_heal_run *r); /* steps_total x dt */
long long ss_heal_run_step_index(const ss_heal_run *r);
long long ss_heal_run_steps_total(const ss_heal_run *r);
int ss_heal_run_done(const ss_heal_run *r); /* 1 when the end is reached */
/* The area curve so far (one row per area_every, day 0 first). */
const ss_heal_area_row *ss_heal_run_area(const ss_heal_run *r, int *n);
int ss_heal_run_snapshot_count(const ss_heal_run *r);
/* Step the run was resumed from, -1 for a fresh run. */
long long ss_heal_run_resumed_from(const ss_heal_run *r);
/* Checkpoints skipped as damaged while resuming ("" if none). */
const char *ss_heal_run_note(const ss_heal_run *r);
/* The closure day of every column so far (skinsim/heal_io.h's
 * ss_heal_closure_update, updated every step; nx*ny, grid order). Saved in
 * the snapshots and checkpoints. */
const double *ss_heal_run_closure(const ss_heal_run *r);
/* On a real body (skin_mesh): the patch the grid is laid on and the skin
 * mesh (skinsim/shell.h, skinsim/mesh.h); NULL on the flat block. */
struct ss_shell_patch;
struct ss_mesh;
const struct ss_shell_patch *ss_heal_run_shell(const ss_heal_run *r);
const struct ss_mesh *ss_heal_run_skin_mesh(const ss_heal_run *r);
/* The contraction mechanics of the run (skinsim/mech.h), NULL when off. */
struct ss_mech *ss_heal_run_mech(ss_heal_run *r);
/* A distributed run (config.distributed) with the contraction mechanics
 * creates them only once a grid holds the cells and fields they read: 1 while
 * they wait for ss_heal_run_mech_attach. */
int ss_heal_run_mech_pending(const ss_heal_run *r);
/* A distributed run on a skin mesh: the level of each column's top tissue
 * cell (nx*ny, -1 = none; the surface the mesh's vertices show), else NULL. */
const int32_t *ss_heal_run_shell_tops(const ss_heal_run *r);
/* Creates the pending mechanics (fresh, or restored from the checkpoint's
 * metadata) on mg, a grid of the run's size with its cell states and the
 * fields SCAR, FIBROBLAST, EPITHELIUM, PLASMA and MDGF (and, resumed, the
 * checkpoint's velocity); the run owns mg from here (also on error) and steps
 * the mechanics on it, through the mech_in / mech_out hooks. */
ss_status ss_heal_run_mech_attach(ss_heal_run *r, ss_heal_grid *mg, ss_error *err);

/* ---- a finished run folder, read back (`skinsim wound --heal DIR`) ----------------
 * What `skinsim heal --out DIR` wrote: run.json (its "format" is
 * SS_HEAL_RUN_FORMAT; a folder of another format is refused, since what the
 * files hold and mean may differ), summary.json (scenario, grid, parameters,
 * step), fields/fields.pvd and the snapshots fields/fields_NNNN.vti it lists
 * (or, where one is not there, fields_NNNN.pvti and its pieces, as a run on
 * MPI ranks may leave them; a .pvti fields.pvd lists is read as one).
 * Read-only: nothing in DIR is changed. */
#define SS_HEAL_RUN_FORMAT 1
typedef struct ss_heal_saved_run ss_heal_saved_run;
/* Checks DIR: a run being written or stopped before its end
 * (.skinsim-unfinished, or no completion marker), a folder of another format
 * or another command, missing or malformed run.json, summary.json or
 * fields.pvd -> SS_ERR_INPUT naming DIR and what is wrong. Reads no snapshot. */
ss_status ss_heal_saved_run_open(const char *dir, ss_heal_saved_run **out, ss_error *err);
void ss_heal_saved_run_free(ss_heal_saved_run *s);
const char *ss_heal_saved_run_scenario(const ss_heal_saved_run *s);
const ss_heal_params *ss_heal_saved_run_params(const ss_heal_saved_run *s);
double ss_heal_saved_run_dt(const ss_heal_saved_run *s);      /* step, days */
double ss_heal_saved_run_end_day(const ss_heal_saved_run *s); /* the last snapshot's day */
int ss_heal_saved_run_snapshot_count(const ss_heal_saved_run *s);
double ss_heal_saved_run_snapshot_day(const ss_heal_saved_run *s, int i);
/* The snapshot whose day is `day` (within a thousandth of a step), -1 if none. */
int ss_heal_saved_run_find(const ss_heal_saved_run *s, double day);
/* Reads snapshot i (0-based, in time order) as a new grid with the run's
 * skin_top_mm; displacement and closed_day as ss_heal_vti_read (NULL when
 * the run had no mechanics; the closure days are in every snapshot of this
 * format). A damaged snapshot, or one whose grid or day disagrees with
 * summary.json and fields.pvd -> SS_ERR_INPUT naming the file. */
ss_heal_grid *ss_heal_saved_run_load(const ss_heal_saved_run *s, int i, float **displacement,
                                     double **closed_day, ss_error *err);
/* Snapshot i is whole: its files are there (the .vti, or the .pvti, its
 * tiling and every piece) and it reads as ss_heal_saved_run_load reads it
 * (header, extent, grid, day, size), then is dropped. SS_ERR_INPUT naming the
 * file. A caller checks the snapshots it will need before any work. */
ss_status ss_heal_saved_run_check(const ss_heal_saved_run *s, int i, ss_error *err);

#ifdef __cplusplus
}
#endif
#endif
