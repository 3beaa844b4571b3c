/* The options of `skinsim heal` that describe the healing problem (model,
 * grid, wound, time step), parsed in one place for every command that runs a
 * heal simulation (`skinsim heal`, `skinsim wound`). */
#ifndef SKINSIM_APP_HEAL_OPTS_H
#define SKINSIM_APP_HEAL_OPTS_H

#include "skinsim/heal_run.h"

/* A flag without a value (--no-scab, --static-region, --mechanics,
 * --no-mechanics): 1 when consumed, else 0. */
int heal_parse_problem_flag(const char *opt, ss_heal_run_config *c);
/* An option with a value (--scenario, --params, --grid, --size-mm,
 * --skin-top-mm, --epidermis-mm, --wound-mask, --stroke, --concave-k,
 * --wound-mesh, --wound-depth-mm, --wound-depth-image, --dt, --scheme,
 * --fibres, --kappa, --tet-size-mm, --sutures, --tet-mesh):
 * 1 when consumed, 0 when not one of these, -1 on a bad value (err set). */
int heal_parse_problem_option(const char *opt, const char *val, ss_heal_run_config *c,
                              ss_error *err);

/* Adaptive steps where they apply, as `skinsim heal` defaults to them: the
 * split scheme with the automatic step and no mechanics get
 * SS_HEAL_RUN_DEFAULT_ADAPT_TOL (--dt fixes the step; an explicit --adapt-tol,
 * 0 included, is kept: call this only when it was not given). */
void heal_default_adapt_tol(ss_heal_run_config *c);

#endif
