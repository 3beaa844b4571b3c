/* skinsim heal: the physically based wound-healing simulation of seed 001
 * (§4.1 biochemistry on the §5.1 grid) from the command line. It parses the
 * options into an ss_heal_run_config, and the run object (src/heal/run/run*.c,
 * skinsim/heal_run.h) does the rest: validates every input before anything is
 * written, builds the wound, steps, and writes the area curve of Fig. 4 (CSV +
 * plot), VTK snapshots with a ParaView time collection, top-view surface maps,
 * checkpoints for exact resume, and summary.json. This file drives the steps
 * with a progress bar and prints the summary. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "heal_opts.h"
#include "skinsim/heal_run.h"
#ifdef SKINSIM_HAVE_MPI
#include "skinsim/dist.h"
#endif

#define CMD "heal"

static void help(FILE *f) {
    fprintf(f, "usage: skinsim heal [options]\n"
               "\n"
               "Simulates the healing of a wound in a block of skin with the biochemical\n"
               "model of Feess et al. (seed 001 §4.1): oxygen, MDGF, capillaries,\n"
               "fibroblasts, eschar, epithelium, scar and plasma on a regular 3D grid.\n"
               "Units: lengths in mm, times in days. x, y run along the skin, z up.\n"
               "\n"
               "Scenario and model\n"
               "  --scenario NAME        clean | scab | keloid (default clean, or the\n"
               "                         \"scenario\" key of --params)\n"
               "  --params FILE.json     parameter overrides (every value with its unit, see\n"
               "                         data/heal/clean.json); applied on top of the scenario\n"
               "  --no-scab              switch off eschar (scab) formation\n"
               "  --static-region        keep the wound region fixed (no keloid growth)\n"
               "\n"
               "Grid (default: a 30 x 30 x 4 mm block, 0.5 mm voxels = 60x60x8, skin\n"
               "surface at 3 mm, 0.1 mm epidermis (a sheet in the surface voxel))\n"
               "  --grid NXxNYxNZ        voxels; alone it keeps 0.5 mm voxels\n"
               "  --size-mm X,Y,Z        block size in mm; alone it keeps 0.5 mm voxels;\n"
               "                         with --grid the voxels must come out cubic\n"
               "  --skin-top-mm H        height of the skin surface (default: NZ-2 voxels,\n"
               "                         3 mm in the default block, one air layer)\n"
               "  --epidermis-mm E       epidermis thickness (default 0.1; thinner than a\n"
               "                         voxel, it is a sheet in the surface voxel)\n"
               "\n"
               "Wound (default: a centred square 20 x 20 mm, or 2/3 of the smaller block\n"
               "side if that is less, 1 mm deep)\n"
               "  --wound-mask PNG       footprint: pixels > 0.5 are wound; the image covers\n"
               "                         the whole block (row 0 at the far y edge)\n"
               "  --stroke CSV           painted outline(s): lines 'u,v[,stroke_id]', u,v in\n"
               "                         0..1 over the block; each stroke's hull is filled\n"
               "  --concave-k K          with --stroke: k-nearest concave hull (K >= 3);\n"
               "                         default 0 = convex hull\n"
               "  --wound-mesh FILE      closed triangle mesh: an OBJ in mm in the grid frame\n"
               "                         (origin at the block corner, z up), voxels whose\n"
               "                         centre is inside (ray parity along z) are wound; with\n"
               "                         --mesh, OBJ/glTF/GLB in the body mesh's units\n"
               "  --wound-depth-mm D     depth below the skin surface (default 1); with a\n"
               "                         PNG depth image, the depth of a white pixel\n"
               "  --wound-depth-image F  per-pixel depth: PNG grey 0..1 x --wound-depth-mm,\n"
               "                         or EXR in mm; alone it is also the footprint\n"
               "                         (depth > 0)\n"
               "\n"
               "Real geometry (seed 001 §5.1, §5.4; docs/mech.md): the grid is a patch of\n"
               "skin around the wound on a closed body mesh\n"
               "  --mesh FILE            closed OBJ/glTF/GLB surface; the skin is the shell\n"
               "                         under it, found by ray tests\n"
               "  --wound-uv CSV         strokes 'u,v[,stroke_id]' in the mesh's UV space,\n"
               "                         cut --wound-depth-mm deep (with --mesh; or the\n"
               "                         --wound-mesh above)\n"
               "  --skin-thickness-mm T  skin shell thickness (default 3)\n"
               "  --voxel-mm H           voxel edge of the patch (default 0.5)\n"
               "  --mesh-units-mm U      one mesh unit in mm (default: glTF 1000; an OBJ by\n"
               "                         its bounding-box diagonal D: D < 3 metres (with a\n"
               "                         note), D >= 60 mm, 3..60 refused as mm or cm)\n"
               "  writes surface/skin_NNNN.vtu (+ skin.pvd): the fields and the deformation\n"
               "  on the undeformed mesh's vertices\n"
               "\n");
    fprintf(f, "Contraction mechanics (seed 001 §4.2-5.3, docs/mech.md)\n"
               "  --mechanics            myofibroblasts contract the wound on a mass-spring\n"
               "                         tet mesh; its velocity convects every field\n"
               "  --no-mechanics         epithelialisation only (the default)\n"
               "  --fibres X,Y,Z[:X,Y,Z] collagen fibre families (default 1,0,0)\n"
               "  --kappa K              fibre dispersion 0 (aligned, default) .. 0.333\n"
               "                         (isotropic)\n"
               "  --tet-size-mm H        lattice tet edge (default 1; max tet volume H^3/6)\n"
               "  --tet-mesh FILE        TetGen .node/.ele or Gmsh 2.2 .msh instead of the\n"
               "                         lattice (mm, in the grid frame)\n"
               "  --sutures CSV          stitches 'x1,y1,z1,x2,y2,z2[,remove_day]' in mm\n"
               "  --mech-model M         springs (the seed's mass-spring network, default) or\n"
               "                         goh (hyperelastic GOH tets with resting skin tension)\n"
               "  mechanical parameters: the \"mechanics\" object of --params (see\n"
               "  data/heal/mechanics.json)\n"
               "\n");
    fprintf(f, "Time\n"
               "  --days T               simulated time (default 10)\n"
               "  --scheme S             explicit | split (default split: implicit diffusion)\n"
               "  --dt DAYS              time step (default: automatic, see the solver's\n"
               "                         stability limit; too large is an error)\n"
               "  --adapt-tol X          split scheme with the automatic step: adaptive steps\n"
               "                         of up to 2 days; a step may change no species by more\n"
               "                         than X in any cell (fields normalised to healthy = 1),\n"
               "                         else it is retried shorter (default 0.01; 0 = fixed\n"
               "                         steps; docs/heal-model.md)\n"
               "  --snapshot-every DAYS  VTK + surface maps interval (default 1; 0 = first\n"
               "                         and last only)\n"
               "  --area-every DAYS      area.csv row interval (default 0.01, at least 1 step)\n"
               "  --checkpoint-every DAYS  write a checkpoint at this interval (default off)\n"
               "  --checkpoint-pieces PXxPYxPZ  write each checkpoint as PX x PY x PZ box\n"
               "                         pieces and a header (as MPI ranks do; default one\n"
               "                         file); --resume reads either kind\n"
               "  --resume DIR           continue the run in DIR from its newest valid\n"
               "                         checkpoint (bit-identical to an uninterrupted run);\n"
               "                         may be combined with --days, --checkpoint-every,\n"
               "                         --checkpoint-pieces, --threads, --quiet, --json\n"
               "\n"
               "Output\n"
               "  --out DIR              output directory (default heal-out)\n"
               "  --force                overwrite a previous run's outputs in DIR\n"
               "  --threads N            OpenMP threads (default $SKINSIM_THREADS or all)\n"
               "  --seed N               recorded in summary.json (the solver is deterministic\n"
               "                         and draws no random numbers)\n"
               "  --quiet                no progress bar or text summary\n"
               "  --json                 print summary.json on stdout\n"
               "\n");
    fprintf(f, "Files written in DIR:\n"
               "  area.csv               t_days, open_area_mm2 (the uncovered area: the sum of\n"
               "                         1 - e over the wound's surface, e the epithelial\n"
               "                         cover), normalised_area (open / initial; the closure\n"
               "                         times are its crossings of 0.5 and 0.05),\n"
               "                         wound_region_area_mm2, mean_<field> over tissue cells,\n"
               "                         open_columns_mm2 (columns with e < 0.5),\n"
               "                         elevation_mean_mm / elevation_max_mm (surface raised\n"
               "                         by scar collagen, sunk by tissue lost)\n"
               "  area.png               normalised open area vs days (seed 001 Fig. 4)\n"
               "  fields/fields_NNNN.vti VTK ImageData: cell_state (UInt8) + 8 Float32 fields\n"
               "                         + surface_elevation_mm (per column) as cell data,\n"
               "                         spacing = voxel size in mm\n"
               "  fields/fields.pvd      ParaView collection, time = days (time slider)\n"
               "  surface/<f>_NNNN.png   top views of epithelium, capillary (surface value),\n"
               "                         eschar, scar (column maximum)\n"
               "  checkpoints/ckpt_*.sshc  with --checkpoint-every (newest 2 kept; with\n"
               "                         --checkpoint-pieces ckpt_*.sshh + ckpt_*_p*.sshp)\n"
               "  with --mechanics: fields/mesh_NNNN.vtu + mesh.pvd (deformed tets:\n"
               "                         displacement, velocity, stress), displacement in the\n"
               "                         .vti, surface/velocity_NNNN.png (Fig. 7 top view),\n"
               "                         area.csv outline_area_mm2, contraction and closure\n"
               "                         shares, summary.json \"mechanics\"\n"
               "  summary.json           scenario, grid, dt, scheme, days, time to 50%% and\n"
               "                         95%% closure, wall time, parameters\n"
               "See docs/heal-outputs.md. Exit codes: 0 ok, 1 runtime failure, 2 bad input\n"
               "(nothing is written then).\n\n"
               "Example:\n"
               "  skinsim heal --scenario scab --stroke data/examples/knee.csv --days 21 --out "
               "knee-heal\n");
}

/* The run's settings plus what only the command line has. */
typedef struct opts {
    ss_heal_run_config c;
    int threads, quiet, json, have_days, have_adapt;
    int nonresume_opts; /* options that a --resume run cannot take */
} opts;

/* ---- argument parsing -------------------------------------------------------------- */

/* --checkpoint-pieces PXxPYxPZ: three counts >= 1 (the run checks them
 * against the grid). */
static ss_status parse_pieces(const char *s, int d[3], ss_error *err) {
    const char *p = s;
    char *end = NULL;
    for (int k = 0; k < 3; k++) {
        long v = strtol(p, &end, 10);
        if (end == p || v < 1 || v > SS_HEAL_CKPT_MAX_PIECES || (k < 2 && *end != 'x') ||
            (k == 2 && *end))
            return ss_error_set(err, SS_ERR_INPUT,
                                "--checkpoint-pieces: '%s' is not PXxPYxPZ with counts of at "
                                "least 1",
                                s);
        d[k] = (int)v;
        p = end + 1;
    }
    return SS_OK;
}

static int parse_args(int argc, char **argv, opts *o, ss_error *err) {
    memset(o, 0, sizeof *o);
    ss_heal_run_config *c = &o->c;
    ss_heal_run_config_default(c);
    c->out_dir = "heal-out";
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) return 1;
        int flag = 1;
        if (heal_parse_problem_flag(a, c)) {
            o->nonresume_opts++;
        } else if (!strcmp(a, "--quiet")) {
            o->quiet = 1;
        } else if (!strcmp(a, "--json")) {
            o->json = 1;
        } else if (!strcmp(a, "--force")) {
            c->force = 1;
        } else {
            flag = 0;
        }
        if (flag) continue;
        const char *v = cli_option_value(argc, argv, &i, err);
        if (!v) return -1;
        ss_status st = SS_OK;
        long l;
        int resume_ok = 0;
        int pr = heal_parse_problem_option(a, v, c, err);
        if (pr < 0) return -1;
        if (pr > 0) {
            o->nonresume_opts++;
            continue;
        }
        if (!strcmp(a, "--days")) {
            st = cli_parse_double(a, v, 1e-9, 1e6, &c->days, err);
            o->have_days = 1;
            resume_ok = 1;
        } else if (!strcmp(a, "--snapshot-every")) {
            st = cli_parse_double(a, v, 0, 1e6, &c->snapshot_every, err);
        } else if (!strcmp(a, "--area-every")) {
            st = cli_parse_double(a, v, 0, 1e6, &c->area_every, err);
        } else if (!strcmp(a, "--checkpoint-every")) {
            st = cli_parse_double(a, v, 0, 1e6, &c->checkpoint_every, err);
            resume_ok = 1;
        } else if (!strcmp(a, "--checkpoint-pieces")) {
            st = parse_pieces(v, c->checkpoint_pieces, err);
            resume_ok = 1;
        } else if (!strcmp(a, "--resume")) {
            c->resume_dir = v;
            resume_ok = 1;
        } else if (!strcmp(a, "--out")) {
            c->out_dir = v;
        } else if (!strcmp(a, "--threads")) {
            st = cli_parse_int(a, v, 1, SS_THREADS_MAX, &l, err);
            o->threads = (int)l;
            resume_ok = 1;
        } else if (!strcmp(a, "--seed")) {
            st = cli_parse_u64(a, v, &c->seed, err);
        } else if (!strcmp(a, "--adapt-tol")) {
            st = cli_parse_double(a, v, 0, 1, &c->adapt_tol, err);
            o->have_adapt = 1;
        } else {
            cli_unknown_option_set(err, "unknown option", a, help);
            return -1;
        }
        if (st) return -1;
        if (!resume_ok) o->nonresume_opts++;
    }
    /* adaptive steps by default where they apply: split scheme, the automatic
     * step, no mechanics (--dt fixes the step; --adapt-tol 0 too) */
    if (!o->have_adapt) heal_default_adapt_tol(c);
    return 0;
}

/* ---- main --------------------------------------------------------------------------- */

static void print_summary(const ss_heal_run *r, const char *out) {
    int n;
    const ss_heal_area_row *rows = ss_heal_run_area(r, &n);
    double t50 = ss_heal_time_to_closure(rows, n, 0.5),
           t95 = ss_heal_time_to_closure(rows, n, 0.05);
    printf("%s: %.3g days simulated, final normalised open area %.4f\n", ss_heal_run_scenario(r),
           ss_heal_run_day(r), n ? ss_heal_area_normalised(&rows[n - 1].st) : NAN);
    char s50[32] = "not reached", s95[32] = "not reached";
    if (t50 >= 0) snprintf(s50, sizeof s50, "%.3f days", t50);
    if (t95 >= 0) snprintf(s95, sizeof s95, "%.3f days", t95);
    printf("time to 50%% closure: %s, to 95%%: %s\n", s50, s95);
    printf("outputs in %s/ (area.csv, area.png, fields/, surface/, summary.json)\n", out);
}

/* Notes on stderr before the run: skipped checkpoints, rounded --days, the set-up. */
static void print_notes(const opts *o, ss_heal_run *r) {
    const char *note = ss_heal_run_note(r);
    if (note[0] && !o->quiet) fprintf(stderr, "skinsim heal: %s\n", note);
    if (o->quiet || o->json) return;
    double days = o->c.days != 0 ? o->c.days : SS_HEAL_RUN_DEFAULT_DAYS;
    double dt = ss_heal_run_dt(r);
    long long nsteps = ss_heal_run_steps_total(r);
    if ((o->have_days || !o->c.resume_dir) &&
        fabs((double)nsteps * dt - days) > 1e-9 * (days > 1 ? days : 1))
        fprintf(stderr, "skinsim heal: note: --days %g rounded to %lld steps of %g days\n", days,
                nsteps, dt);
    if (!o->c.resume_dir) {
        const ss_heal_grid *g = ss_heal_run_grid(r);
        fprintf(stderr,
                "skinsim heal: %s, %dx%dx%d voxels of %g mm, %s scheme, dt %g days, %lld "
                "steps%s\n",
                ss_heal_run_scenario(r), g->nx, g->ny, g->nz, g->dx_mm,
                ss_heal_run_scheme(r) == SS_HEAL_EXPLICIT ? "explicit" : "split", dt, nsteps,
                o->c.adapt_tol > 0 ? " (adaptive: a solver step spans up to 2 days, --adapt-tol)"
                                   : "");
    }
}

/* Ends the run on every MPI rank with rank 0's status (no-op without MPI). */
static void dist_end(void *dist, ss_status st) {
#ifdef SKINSIM_HAVE_MPI
    if (dist) ss_dist_heal_end(dist, st);
#else
    (void)dist;
    (void)st;
#endif
}

/* Rank 0 under MPI: the distributed solver's times (slowest rank). */
static void print_dist_timing(const opts *o, void *dist) {
#ifdef SKINSIM_HAVE_MPI
    if (!dist || o->quiet) return;
    ss_dist_heal_timing t;
    ss_dist_heal_timing_get(dist, &t);
    fprintf(stderr,
            "skinsim heal: MPI %d ranks (%dx%dx%d): %lld steps, compute %.3f s, halo exchange "
            "%.3f s, statistics %.3f s, gathers %.3f s (slowest rank); halo %.0f bytes/step\n",
            t.dims[0] * t.dims[1] * t.dims[2], t.dims[0], t.dims[1], t.dims[2], t.steps,
            t.compute_s, t.halo_s, t.stats_s, t.gather_s, t.halo_bytes_per_step);
    if (t.mech_s > 0 || t.mech_bytes_per_step > 0)
        fprintf(stderr,
                "skinsim heal: mechanics on rank 0: gather + scatter %.3f s in all, %.0f "
                "bytes/step\n",
                t.mech_s, t.mech_bytes_per_step);
    fprintf(stderr, "skinsim heal: peak memory per rank (MB):");
    for (int i = 0; t.rss_mb && i < t.dims[0] * t.dims[1] * t.dims[2]; i++)
        fprintf(stderr, " %.1f", t.rss_mb[i]);
    fprintf(stderr, "\n");
#else
    (void)o;
    (void)dist;
#endif
}

/* Start, steps, finish and the printed summary of a created run; dist is the
 * MPI driver on rank 0 (NULL without MPI). */
static int run_steps(const opts *o, ss_heal_run *r, ss_error *err, void *dist) {
    /* The output folder: locked, checked against the free space, staged or
     * marked unfinished; errors here are still about the input (exit 2). */
    ss_status st = ss_heal_run_start(r, err);
    if (st) {
        dist_end(dist, st);
        return cli_fail(CMD, err);
    }
    /* Everything is validated: from here on, files are written. */
    ss_progress pr;
    ss_progress_begin(&pr, "heal", (double)ss_heal_run_steps_total(r), o->quiet);
    while (!st && !ss_heal_run_done(r)) {
        st = ss_heal_run_step(r, err);
        ss_progress_update(&pr, (double)ss_heal_run_step_index(r));
    }
    ss_progress_end(&pr);
    char *summary = NULL;
    if (!st) st = ss_heal_run_finish(r, &summary, err);
    if (st) {
        if (err->code == SS_ERR_INPUT) err->code = SS_ERR_RUNTIME; /* mid-run: runtime failure */
        dist_end(dist, err->code);
        return cli_fail(CMD, err);
    }
    dist_end(dist, SS_OK);
    print_dist_timing(o, dist);
    if (o->json)
        printf("%s\n", summary);
    else if (!o->quiet)
        print_summary(r, o->c.resume_dir ? o->c.resume_dir : o->c.out_dir);
    free(summary);
    return 0;
}

#ifdef SKINSIM_HAVE_MPI
/* Several MPI ranks: rank 0 creates (validates) the run and drives it, the
 * others step their boxes (src/mpi/heal.c); every rank exits with rank 0's code. */
static int heal_mpi(const opts *o, ss_error *err) {
    ss_heal_run *r = NULL;
    ss_heal_run_config c = o->c;
    c.distributed = 1; /* rank 0 never holds the whole grid (a checkpoint write aside) */
    ss_status cst = ss_dist_rank() == 0 ? ss_heal_run_create(&c, &r, err) : SS_OK;
    ss_dist_heal *d = NULL;
    ss_status st = ss_dist_heal_create(r, cst, &d, err);
    int rc;
    if (st) {
        rc = ss_dist_rank() == 0 ? cli_fail(CMD, err) : ss_status_exit_code(st);
    } else if (ss_dist_rank() != 0) {
        rc = ss_status_exit_code(ss_dist_heal_serve(d, err));
    } else {
        print_notes(o, r);
        rc = run_steps(o, r, err, d);
    }
    ss_dist_heal_free(d);
    ss_heal_run_free(r);
    return rc;
}
#endif

int cmd_heal(int argc, char **argv) {
    ss_error err;
    ss_error_clear(&err);
    opts o;
    int pa = parse_args(argc, argv, &o, &err);
    if (pa == 1) {
        help(stdout);
        return 0;
    }
    if (pa < 0) return cli_usage_error(CMD, "%s", err.msg);
    if (o.c.resume_dir && o.nonresume_opts) {
        ss_error_set(&err, SS_ERR_INPUT,
                     "--resume continues a run with its own settings; only --days, "
                     "--checkpoint-every, --checkpoint-pieces, --threads, --quiet and "
                     "--json may be given");
        return cli_fail(CMD, &err);
    }
    ss_threads_set(o.threads);
#ifdef SKINSIM_HAVE_MPI
    /* one rank under mpirun takes the distributed path too when it can (a
     * fresh run; with mechanics only on the explicit scheme), so its times
     * are reported alike */
    if (ss_dist_size() > 1 ||
        (ss_dist_active() && !o.c.resume_dir && (!o.c.mechanics || o.c.scheme == SS_HEAL_EXPLICIT)))
        return heal_mpi(&o, &err);
#endif

    ss_heal_run *r;
    if (ss_heal_run_create(&o.c, &r, &err)) return cli_fail(CMD, &err);
    print_notes(&o, r);
    int rc = run_steps(&o, r, &err, NULL);
    ss_heal_run_free(r);
    return rc;
}
