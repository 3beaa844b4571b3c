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

#endif
