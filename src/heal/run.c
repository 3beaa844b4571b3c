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
    else
        ss_heal_stats_compute(r->g, &row->st);
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

ss_status ss_heal_run_create(const ss_heal_run_config *c, ss_heal_run **out, ss_error *err) {
    *out = NULL;
    if (!c) return ss_error_set(err, SS_ERR_INPUT, "heal run: no config");
    ss_heal_run *r = calloc(1, sizeof *r);
    if (!r) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    r->c = *c;
    r->resumed_from = -1;
    const char *dir = c->resume_dir ? c->resume_dir : c->out_dir;
    ss_status st = SS_OK;
    if (dir && !(r->out_dir = strdup(dir))) st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    if (!st)
        st = c->resume_dir ? ss_heal_run__setup_resume(r, err) : ss_heal_run__setup_fresh(r, err);
    if (!st) st = set_end(r, err);
    if (!st && r->out_dir) st = ss_heal_run__outputs_open(r, err);
    if (!st && !c->resume_dir) st = ss_heal_run__add_row(r, err); /* day 0 */
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
    if ((st0 = ss_heal_run__sync(r, err))) return st0;
    char *aux = ss_heal_run__aux_json(r, r->wall_prev + ss_now() - r->t0);
    if (!aux) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    ss_status st = ss_heal_checkpoint_save(r->out_dir, r->g, r->scenario, r->params_json,
                                           (int)r->scheme, r->dt, aux, 2, err);
    free(aux);
    return st;
}

/* The explicit scheme's step cannot follow every spike of the mechanics'
 * velocity (the springs snapping into a new configuration): the grid velocity
 * is capped at what the step admits, 95 % of the CFL budget that diffusion and
 * reaction leave (docs/mech.md). The split scheme sub-cycles its convection
 * and needs no cap. */
static void cap_velocity(ss_heal_run *r) {
    ss_heal_grid *g = r->g;
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

ss_status ss_heal_run_step(ss_heal_run *r, ss_error *err) {
    if (ss_heal_run_done(r))
        return ss_error_set(err, SS_ERR_INPUT, "heal run: already at its end (day %g)",
                            ss_heal_run_end_day(r));
    ss_status st = start_output(r, err);
    if (!st)
        st = r->hooks.step ? r->hooks.step(r->hooks.ctx, r->g, err) : ss_heal_step(r->s, r->g, err);
    if (!st && r->mech && !(st = ss_mech_step(r->mech, r->g, r->dt, err))) cap_velocity(r);
    if (st) return st;
    long long k = (long long)r->g->step;
    int last = k == r->nsteps;
    if (k % r->area_every == 0 || last) st = ss_heal_run__add_row(r, err);
    if (!st && r->out_dir && ((r->snap_every && k % r->snap_every == 0) || last))
        st = ss_heal_run__snapshot(r, err);
    if (!st && r->out_dir && r->ckpt_every && (k % r->ckpt_every == 0 || last))
        st = ss_heal_run_write_checkpoint(r, err);
    return fail_outputs(r, st, err);
}

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
    while (!st && (long long)r->g->step < k) st = ss_heal_run_step(r, err);
    return st;
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

ss_status ss_heal_run_set_hooks(ss_heal_run *r, const ss_heal_run_hooks *h, ss_error *err) {
    if (h && r->mech)
        return ss_error_set(err, SS_ERR_INPUT,
                            "--mechanics: the contraction mechanics needs the whole grid in one "
                            "process; it cannot run with an external (distributed) solver");
    if (h)
        r->hooks = *h;
    else
        memset(&r->hooks, 0, sizeof r->hooks);
    return SS_OK;
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
