/* The heal run object (seed 001 §4.1 stepped on the §5.1 grid): create from a
 * config (fresh, or resumed from a checkpoint), step with the run's
 * bookkeeping, finish with the closing tables, free. Set-up lives in
 * run_setup.c, everything that writes files in run_output.c.
 *
 * Design: all simulation state lives in the grid (fields, cells, t_days,
 * step), so a checkpoint of the grid plus the run's metadata (intervals, area
 * rows, snapshot list) resumes bit-identically. Outputs are tied to step
 * indices, never to wall time or float day comparisons: a snapshot is due at
 * k % snap_every == 0 and at the last step, so a resumed run writes exactly
 * the files an uninterrupted one would. No file is written by create; the
 * first step (or finish) prepares the directory, which keeps "validate every
 * input, then write" in one place for every caller. Gave up: a run cannot be
 * extended past its end after create (make a new run with --resume and a
 * later day instead), which keeps "the last step" well defined. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "run_internal.h"

void ss_heal_run_config_default(ss_heal_run_config *c) {
    memset(c, 0, sizeof *c);
    c->epidermis_mm = SS_HEAL_DEFAULT_EPIDERMIS_MM;
    c->scheme = SS_HEAL_SPLIT;
    c->snapshot_every = 1;
    c->area_every = 0.01;
    c->checkpoint_every = -1;
    c->kappa = -1;
}

void ss_heal_run_free(ss_heal_run *r) {
    if (!r) return;
    ss_heal_solver_free(r->s);
    ss_heal_grid_free(r->g);
    free(r->closed_day);
    ss_heal_params_free(r->p);
    free(r->params_json);
    free(r->rows);
    free(r->snap_t);
    for (int i = 0; i < r->nsnap; i++) free(r->snap_file[i]);
    free(r->snap_file);
    free(r->out_dir);
    ss_outputs_free(r->outs); /* rolls back outputs not finished */
    cJSON_Delete(r->wound);
    ss_heal_run__mech_free(r);
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) free(r->backup[f]);
    ss_heal_run__shell_free(r);
    free(r->wcols);
    ss_tri_mesh_free(&r->wmesh);
    free(r);
}

ss_status ss_heal_run__add_row(ss_heal_run *r, ss_error *err) {
    if (r->nrows == r->caprows) {
        int cap = r->caprows ? 2 * r->caprows : 256;
        ss_heal_area_row *q = realloc(r->rows, (size_t)cap * sizeof *q);
        if (!q) return ss_error_set(err, SS_ERR_NOMEM, "out of memory (area rows)");
        r->rows = q;
        r->caprows = cap;
    }
    ss_heal_area_row *row = &r->rows[r->nrows++];
    row->t_days = r->g->t_days;
    if (r->hooks.stats)
        r->hooks.stats(r->hooks.ctx, r->g, &row->st);
    else if (r->g->cell)
        ss_heal_stats_compute(r->g, &row->st);
    else /* distributed, rows restored from a checkpoint: filled in by the caller */
        memset(&row->st, 0, sizeof row->st);
    /* the crust's share of its layer, also on voxels coarser than the layer */
    row->st.eschar_wound_mean /= ss_heal_crust_voxel_share(r->p, r->g->dx_mm);
    return ss_heal_run__mech_row(r, err);
}

ss_status ss_heal_run__add_snap(ss_heal_run *r, double t, const char *file, ss_error *err) {
    if (r->nsnap == r->capsnap) {
        int cap = r->capsnap ? 2 * r->capsnap : 32;
        double *qt = realloc(r->snap_t, (size_t)cap * sizeof *qt);
        if (qt) r->snap_t = qt;
        char **qf = realloc(r->snap_file, (size_t)cap * sizeof *qf);
        if (qf) r->snap_file = qf;
        if (!qt || !qf) return ss_error_set(err, SS_ERR_NOMEM, "out of memory (snapshots)");
        r->capsnap = cap;
    }
    r->snap_file[r->nsnap] = strdup(file);
    if (!r->snap_file[r->nsnap]) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    r->snap_t[r->nsnap++] = t;
    return SS_OK;
}

/* The number of steps to the requested end, checked against the grid's time. */
static ss_status set_end(ss_heal_run *r, ss_error *err) {
    r->nsteps = llround(r->days / r->dt);
    if (r->nsteps < 1)
        return ss_error_set(err, SS_ERR_INPUT, "--days %g is shorter than one step (dt %g)",
                            r->days, r->dt);
    if (r->nsteps > 2000000000LL)
        return ss_error_set(err, SS_ERR_INPUT, "--days %g needs %lld steps of %g days", r->days,
                            r->nsteps, r->dt);
    if ((long long)r->g->step > r->nsteps)
        return ss_error_set(err, SS_ERR_INPUT, "--days %g is before the checkpoint's time %g days",
                            r->days, r->g->t_days);
    return SS_OK;
}

/* --checkpoint-pieces: 1 to the grid's cells per axis, at most
 * SS_HEAL_CKPT_MAX_PIECES pieces in all; none (all 0) is the whole-grid file. */
static ss_status check_ckpt_pieces(const ss_heal_run *r, ss_error *err) {
    const int *d = r->c.checkpoint_pieces, n[3] = {r->g->nx, r->g->ny, r->g->nz};
    if (!d[0] && !d[1] && !d[2]) return SS_OK;
    for (int a = 0; a < 3; a++)
        if (d[a] < 1 || d[a] > n[a])
            return ss_error_set(err, SS_ERR_INPUT,
                                "--checkpoint-pieces %dx%dx%d: need 1 to %d, %d and %d pieces per "
                                "axis for the %dx%dx%d grid",
                                d[0], d[1], d[2], n[0], n[1], n[2], n[0], n[1], n[2]);
    if ((long long)d[0] * d[1] * d[2] > SS_HEAL_CKPT_MAX_PIECES)
        return ss_error_set(err, SS_ERR_INPUT, "--checkpoint-pieces %dx%dx%d: more than %d pieces",
                            d[0], d[1], d[2], SS_HEAL_CKPT_MAX_PIECES);
    return SS_OK;
}

ss_status ss_heal_run_create(const ss_heal_run_config *c, ss_heal_run **out, ss_error *err) {
    *out = NULL;
    if (!c) return ss_error_set(err, SS_ERR_INPUT, "heal run: no config");
    ss_heal_run *r = calloc(1, sizeof *r);
    if (!r) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    r->c = *c;
    r->resumed_from = -1;
    r->pieces_step = -1;
    const char *dir = c->resume_dir ? c->resume_dir : c->out_dir;
    ss_status st = SS_OK;
    if (dir && !(r->out_dir = strdup(dir))) st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    if (!c->resume_dir) ss_heal_run__new_run_id(r);
    if (!st)
        st = c->resume_dir ? ss_heal_run__setup_resume(r, err) : ss_heal_run__setup_fresh(r, err);
    if (!st) st = set_end(r, err);
    if (!st) st = check_ckpt_pieces(r, err);
    if (!st && !r->closed_day) { /* fresh, or a checkpoint from before the closure days */
        const size_t ncol = (size_t)r->g->nx * (size_t)r->g->ny;
        if (!(r->closed_day = malloc(ncol * sizeof *r->closed_day)))
            st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        else if (r->g->cell)
            ss_heal_closure_init(r->g, r->closed_day);
        else /* distributed: the ranks keep them, the sync hook brings them here */
            for (size_t k = 0; k < ncol; k++) r->closed_day[k] = SS_HEAL_CLOSED_INTACT;
    }
    if (!st && r->out_dir) st = ss_heal_run__outputs_open(r, err);
    /* day 0 (distributed: when the hooks are set, ss_heal_run_set_hooks) */
    if (!st && !c->resume_dir && !c->distributed) st = ss_heal_run__add_row(r, err);
    if (st) {
        ss_heal_run_free(r);
        return st;
    }
    r->t0 = ss_now();
    *out = r;
    return SS_OK;
}

/* A failed output step stops the run: its outputs are rolled back (a staged
 * folder removed, an in-place one left unfinished for a resume) and the
 * message names the folder the user gave. */
static ss_status fail_outputs(ss_heal_run *r, ss_status st, ss_error *err) {
    if (st && r->outs && !r->failed) {
        r->failed = 1;
        st = ss_outputs_finish(r->outs, st, err);
    }
    return st;
}

/* Prepares the output directory and writes the day-0 snapshot of a fresh run. */
static ss_status start_output(ss_heal_run *r, ss_error *err) {
    if (r->failed)
        return ss_error_set(err, SS_ERR_RUNTIME, "heal run: stopped by an earlier error");
    if (r->started || !r->out_dir) return SS_OK;
    ss_status st = ss_heal_run__prepare_out_dir(r, err);
    if (!st && r->resumed_from < 0) st = ss_heal_run__snapshot(r, err);
    if (!st) r->started = 1;
    return fail_outputs(r, st, err);
}

ss_status ss_heal_run_start(ss_heal_run *r, ss_error *err) { return start_output(r, err); }

ss_status ss_heal_run_write_snapshot(ss_heal_run *r, ss_error *err) {
    if (!r->out_dir) return ss_error_set(err, SS_ERR_INPUT, "heal run: no output directory");
    int fresh_start = !r->started && r->resumed_from < 0; /* start writes the day-0 one */
    ss_status st = start_output(r, err);
    if (!st && !fresh_start) st = fail_outputs(r, ss_heal_run__snapshot(r, err), err);
    return st;
}

ss_status ss_heal_run_write_checkpoint(ss_heal_run *r, ss_error *err) {
    if (!r->out_dir) return ss_error_set(err, SS_ERR_INPUT, "heal run: no output directory");
    ss_status st0 = start_output(r, err);
    if (st0) return st0;
    if (!r->g->cell && !r->ckpt_fn)
        return ss_error_set(err, SS_ERR_INPUT,
                            "heal run: a distributed run (config.distributed) writes "
                            "checkpoints only through the MPI driver's hook");
    if ((st0 = ss_heal_run__sync(r, err))) return st0;
    char *aux = ss_heal_run__aux_json(r, r->wall_prev + ss_now() - r->t0);
    if (!aux) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    const int *pc = r->c.checkpoint_pieces;
    ss_status st =
        r->ckpt_fn ? r->ckpt_fn(r->ckpt_ctx, r->g, r->out_dir, r->scenario, r->params_json,
                                (int)r->scheme, r->dt, aux, 2, err)
        : pc[0] > 0 && pc[1] > 0 && pc[2] > 0
            ? ss_heal_checkpoint_save_pieces(r->out_dir, r->g, r->scenario, r->params_json,
                                             (int)r->scheme, r->dt, aux, pc, 2, err)
            : ss_heal_checkpoint_save(r->out_dir, r->g, r->scenario, r->params_json, (int)r->scheme,
                                      r->dt, aux, 2, err);
    free(aux);
    return st;
}

/* The explicit scheme's step cannot follow every spike of the mechanics'
 * velocity (the springs snapping into a new configuration): the grid velocity
 * is capped at what the step admits, 95 % of the CFL budget that diffusion and
 * reaction leave (docs/mech.md). The split scheme sub-cycles its convection
 * and needs no cap. */
static void cap_velocity(ss_heal_run *r, ss_heal_grid *g) {
    if (r->scheme != SS_HEAL_EXPLICIT || ss_heal_stable_dt(g, r->p, SS_HEAL_EXPLICIT) >= r->dt)
        return;
    float *v[3] = {g->velocity[0], g->velocity[1], g->velocity[2]};
    g->velocity[0] = g->velocity[1] = g->velocity[2] = NULL;
    double lim0 = ss_heal_stable_dt(g, r->p, SS_HEAL_EXPLICIT);
    for (int d = 0; d < 3; d++) g->velocity[d] = v[d];
    const size_t n = (size_t)g->nx * g->ny * g->nz;
    double room = 0.95 * g->dx_mm * (1.0 / r->dt - 1.0 / lim0), vmax = 0;
    for (size_t i = 0; i < n; i++) {
        double s = fabs(v[0][i]) + fabs(v[1][i]) + fabs(v[2][i]);
        if (s > vmax) vmax = s;
    }
    if (!(vmax > room)) return;
    float f = room > 0 ? (float)(room / vmax) : 0.0f;
    for (int d = 0; d < 3; d++)
        for (size_t i = 0; i < n; i++) v[d][i] *= f;
}

/* ---- adaptive steps -----------------------------------------------------------------
 * Error control (docs/heal-model.md §4): a step of m x dt is accepted when no
 * species changes by more than adapt_tol in any cell (the fields are
 * normalised, healthy = 1); otherwise it is undone and retried with m / 2.
 * m doubles after a full-length step whose largest change stayed below
 * adapt_tol / 2, up to mult_max (SS_HEAL_SPLIT_LATE_MAX_DT_DAYS). m = 1 (the
 * fixed step) is always accepted, so the fast phases run exactly as with
 * fixed steps as long as they change the fields by more than adapt_tol / 2 per
 * step. The largest change is a max over cells (order-independent), m lives
 * in the checkpoint: results stay bit-identical for any thread count and
 * across a resume. */

static long long min_ll(long long a, long long b) { return a < b ? a : b; }

void ss_heal_run__adapt_init(ss_heal_run *r) {
    r->mult = 1;
    r->mult_max = 1;
    if (r->adapt_tol > 0 && r->scheme == SS_HEAL_SPLIT && !r->mech && !r->mech_pending &&
        r->dt > 0) {
        r->mult_max = (long long)floor(SS_HEAL_SPLIT_LATE_MAX_DT_DAYS / r->dt * (1.0 + 1e-12));
        if (r->mult_max < 1) r->mult_max = 1;
    }
}

/* The largest multiple from base step k that lands on every snapshot and
 * checkpoint due and does not pass `limit`. */
static long long landing(const ss_heal_run *r, long long k, long long limit) {
    long long m = limit - k;
    if (r->out_dir && r->snap_every) m = min_ll(m, r->snap_every - k % r->snap_every);
    if (r->out_dir && r->ckpt_every) m = min_ll(m, r->ckpt_every - k % r->ckpt_every);
    return m < 1 ? 1 : m;
}

/* The adaptive step's copy and its change measure, each one parallel region
 * over every field (max and copies are exact, so the split does not change
 * any value or result). */
#define FIELDS_CHUNK ((size_t)1 << 16)

static void fields_copy(float *const *dst, float *const *src, size_t n) {
    const long long nch = (long long)((n + FIELDS_CHUNK - 1) / FIELDS_CHUNK);
#pragma omp parallel for collapse(2) schedule(static) if (n >= 32768)
    for (int f = 0; f < SS_HEAL_NFIELDS; f++)
        for (long long ch = 0; ch < nch; ch++) {
            const size_t i0 = (size_t)ch * FIELDS_CHUNK;
            const size_t len = n - i0 < FIELDS_CHUNK ? n - i0 : FIELDS_CHUNK;
            memcpy(dst[f] + i0, src[f] + i0, len * sizeof(float));
        }
}

static double max_change(float *const *a, float *const *b, size_t n) {
    float m = 0.0f;
#pragma omp parallel if (n >= 32768)
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) {
        const float *x = a[f], *y = b[f];
#pragma omp for simd reduction(max : m) schedule(static)
        for (size_t i = 0; i < n; i++) {
            const float d = fabsf(x[i] - y[i]);
            m = d > m ? d : m;
        }
    }
    return m;
}

/* One accepted step of the solver towards base step `limit`: m x dt with
 * the control above, or one step of dt without adapt_tol (or when the work
 * copy could not be allocated). */
static ss_status solver_step(ss_heal_run *r, long long limit, ss_error *err) {
    ss_heal_grid *g = r->g;
    const size_t n = (size_t)g->nx * (size_t)g->ny * (size_t)g->nz;
    const int ext = r->hooks.step != NULL; /* an external solver keeps its own copy */
    if (r->adapt_tol > 0 && !r->backup[0] && !ext)
        for (int f = 0; f < SS_HEAL_NFIELDS; f++)
            if (!(r->backup[f] = malloc(n * sizeof(float))))
                return ss_error_set(err, SS_ERR_NOMEM, "out of memory (adaptive step copy)");
    if (!(r->adapt_tol > 0))
        return ext ? r->hooks.step(r->hooks.ctx, g, r->dt, NULL, err) : ss_heal_step(r->s, g, err);
    for (;;) {
        const long long k = (long long)g->step;
        const long long m = min_ll(r->mult, landing(r, k, limit));
        const double t = g->t_days;
        const uint64_t step = g->step;
        ss_status st = SS_OK;
        double d = 0.0;
        if (ext) {
            if ((st = r->hooks.step(r->hooks.ctx, g, (double)m * r->dt, &d, err))) return st;
        } else {
            if (ss_heal_solver_dt(r->s) != (double)m * r->dt)
                st = ss_heal_solver_set_dt(r->s, (double)m * r->dt, err);
            if (st) return st;
            fields_copy(r->backup, g->field, n);
            if ((st = ss_heal_step(r->s, g, err))) return st;
            d = max_change(g->field, r->backup, n);
        }
        if (m > 1 && d > r->adapt_tol) { /* undo, retry shorter */
            if (ext)
                r->hooks.undo(r->hooks.ctx, g);
            else
                fields_copy(g->field, r->backup, n);
            g->t_days = t;
            g->step = step;
            r->mult = m / 2 > 1 ? m / 2 : 1;
            r->retried++;
            continue;
        }
        g->step = step + (uint64_t)m; /* step indices count steps of dt */
        r->taken++;
        if (m == r->mult && d < 0.5 * r->adapt_tol) r->mult = min_ll(2 * r->mult, r->mult_max);
        return SS_OK;
    }
}

static ss_status run_step(ss_heal_run *r, long long limit, ss_error *err) {
    if (!r->g->cell && !r->hooks.step)
        return ss_error_set(err, SS_ERR_INPUT,
                            "heal run: a distributed run (config.distributed) steps only "
                            "through the MPI driver's hooks");
    if (ss_heal_run_done(r))
        return ss_error_set(err, SS_ERR_INPUT, "heal run: already at its end (day %g)",
                            ss_heal_run_end_day(r));
    ss_status st = start_output(r, err);
    const long long k0 = (long long)r->g->step;
    if (!st) st = solver_step(r, limit, err);
    if (!st && r->mech) {
        /* distributed: the mechanics step on rank 0's grid of what they read
         * (the hooks gather it and hand the velocity back) */
        ss_heal_grid *mg = r->mg ? r->mg : r->g;
        if (r->mg) {
            mg->t_days = r->g->t_days;
            mg->step = r->g->step;
            r->hooks.mech_in(r->hooks.ctx, mg);
        }
        if (!(st = ss_mech_step(r->mech, mg, r->dt, err))) {
            cap_velocity(r, mg);
            if (r->mg) r->hooks.mech_out(r->hooks.ctx, mg);
        }
    }
    if (st) return st;
    if (r->hooks.closure)
        r->hooks.closure(r->hooks.ctx, r->g, r->closed_day);
    else
        ss_heal_closure_update(r->g, r->closed_day);
    long long k = (long long)r->g->step;
    int last = k == r->nsteps;
    if (k / r->area_every != k0 / r->area_every || last) st = ss_heal_run__add_row(r, err);
    if (!st && r->out_dir && ((r->snap_every && k % r->snap_every == 0) || last))
        st = ss_heal_run__snapshot(r, err);
    if (!st && r->out_dir && r->ckpt_every && (k % r->ckpt_every == 0 || last))
        st = ss_heal_run_write_checkpoint(r, err);
    return fail_outputs(r, st, err);
}

ss_status ss_heal_run_step(ss_heal_run *r, ss_error *err) { return run_step(r, r->nsteps, err); }

ss_status ss_heal_run_advance_to(ss_heal_run *r, double day, ss_error *err) {
    if (!(day >= 0) || !isfinite(day))
        return ss_error_set(err, SS_ERR_INPUT, "heal run: day %g is not a time >= 0", day);
    long long k = llround(day / r->dt);
    if (k < (long long)r->g->step)
        return ss_error_set(err, SS_ERR_INPUT, "heal run: day %g is before the run's day %g", day,
                            r->g->t_days);
    if (k > r->nsteps)
        return ss_error_set(err, SS_ERR_INPUT, "heal run: day %g is after the run's end (day %g)",
                            day, ss_heal_run_end_day(r));
    ss_status st = SS_OK;
    while (!st && (long long)r->g->step < k) {
        st = run_step(r, k, err);
        /* the caller's poll, between whole steps: a stop leaves a valid run */
        if (!st && r->progress && r->progress(r->progress_user, r->g->t_days))
            st = ss_error_set(err, SS_ERR_RUNTIME, "heal run: cancelled by the caller at day %g",
                              r->g->t_days);
    }
    return st;
}

void ss_heal_run_set_progress(ss_heal_run *r, int (*fn)(void *user, double day), void *user) {
    r->progress = fn;
    r->progress_user = user;
}

ss_status ss_heal_run_finish(ss_heal_run *r, char **summary_json, ss_error *err) {
    if (summary_json) *summary_json = NULL;
    double wall = r->wall_prev + ss_now() - r->t0;
    cJSON *summary = NULL;
    ss_status st = start_output(r, err);
    if (st) return st;
    if (r->out_dir) {
        st = ss_heal_run__write_tables(r, wall, &summary, err);
        /* everything is written: the folder is complete (or swapped in whole) */
        if (!st) st = ss_outputs_finish(r->outs, st, err);
        st = fail_outputs(r, st, err);
    } else {
        summary = ss_heal_run__summary(r, wall);
        if (!summary) st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    if (!st && summary_json) {
        *summary_json = cJSON_Print(summary);
        if (!*summary_json) st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    cJSON_Delete(summary);
    return st;
}

void ss_heal_run_set_checkpoint_hook(ss_heal_run *r, ss_heal_run_checkpoint_fn fn, void *ctx) {
    r->ckpt_fn = fn;
    r->ckpt_ctx = fn ? ctx : NULL;
}

ss_status ss_heal_run_set_hooks(ss_heal_run *r, const ss_heal_run_hooks *h, ss_error *err) {
    if (h && h->step && !h->undo)
        return ss_error_set(err, SS_ERR_INPUT, "heal run: an external step needs an undo hook");
    if (h && (r->mech || r->mech_pending) && (!r->mg || !h->mech_in || !h->mech_out))
        return ss_error_set(err, SS_ERR_INPUT,
                            "--mechanics: an external (distributed) solver needs the mechanics "
                            "attached to a grid of their own (ss_heal_run_mech_attach) and the "
                            "mech_in and mech_out hooks");
    if (h && !r->g->cell &&
        (!h->step || !h->stats || !h->sync || !h->closure || !h->snapshot || !h->surface_map ||
         !r->ckpt_fn))
        return ss_error_set(err, SS_ERR_INPUT,
                            "heal run: a distributed run (no whole grid) needs every hook");
    if (h)
        r->hooks = *h;
    else
        memset(&r->hooks, 0, sizeof r->hooks);
    /* a distributed fresh run's day-0 area row comes from the ranks' boxes */
    if (h && !r->g->cell && r->resumed_from < 0 && r->nrows == 0)
        return ss_heal_run__add_row(r, err);
    return SS_OK;
}

const int32_t *ss_heal_run_wound_columns(const ss_heal_run *r) { return r->wcols; }
const ss_tri_mesh *ss_heal_run_wound_mesh(const ss_heal_run *r) {
    return r->wmesh.ntris ? &r->wmesh : NULL;
}
double ss_heal_run_epidermis_mm(const ss_heal_run *r) { return r->epidermis_mm; }
long long ss_heal_run_resume_pieces(const ss_heal_run *r, const char **dir) {
    if (dir) *dir = r->pieces_step >= 0 ? r->c.resume_dir : NULL;
    return r->pieces_step;
}

void ss_heal_run_release_grid(ss_heal_run *r) {
    if (!r || !r->g) return;
    ss_heal_solver_free(r->s);
    r->s = NULL;
    free(r->g->cell);
    r->g->cell = NULL;
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) {
        free(r->g->field[f]);
        r->g->field[f] = NULL;
        free(r->backup[f]);
        r->backup[f] = NULL;
    }
}

ss_status ss_heal_run__sync(ss_heal_run *r, ss_error *err) {
    return r->hooks.sync ? r->hooks.sync(r->hooks.ctx, r->g, err) : SS_OK;
}

/* ---- accessors ------------------------------------------------------------------ */

ss_heal_grid *ss_heal_run_grid(ss_heal_run *r) { return r->g; }
const ss_heal_params *ss_heal_run_params(const ss_heal_run *r) { return r->p; }
const char *ss_heal_run_scenario(const ss_heal_run *r) { return r->scenario; }
ss_heal_scheme ss_heal_run_scheme(const ss_heal_run *r) { return r->scheme; }
double ss_heal_run_day(const ss_heal_run *r) { return r->g->t_days; }
double ss_heal_run_dt(const ss_heal_run *r) { return r->dt; }
double ss_heal_run_end_day(const ss_heal_run *r) { return (double)r->nsteps * r->dt; }
long long ss_heal_run_step_index(const ss_heal_run *r) { return (long long)r->g->step; }
long long ss_heal_run_step_multiple(const ss_heal_run *r) { return r->mult; }
long long ss_heal_run_steps_retried(const ss_heal_run *r) { return r->retried; }
long long ss_heal_run_steps_total(const ss_heal_run *r) { return r->nsteps; }
int ss_heal_run_done(const ss_heal_run *r) { return (long long)r->g->step >= r->nsteps; }
const ss_heal_area_row *ss_heal_run_area(const ss_heal_run *r, int *n) {
    if (n) *n = r->nrows;
    return r->rows;
}
int ss_heal_run_snapshot_count(const ss_heal_run *r) { return r->nsnap; }
long long ss_heal_run_resumed_from(const ss_heal_run *r) { return r->resumed_from; }
const char *ss_heal_run_note(const ss_heal_run *r) { return r->note; }
struct ss_mech *ss_heal_run_mech(ss_heal_run *r) {
    return r->mech;
}

const double *ss_heal_run_closure(const ss_heal_run *r) { return r->closed_day; }
