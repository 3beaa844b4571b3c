/* The healing-problem options shared by `skinsim heal` and `skinsim wound`
 * (see heal_opts.h): each fills one field of ss_heal_run_config, checking the
 * value's range and naming the option on error. */
#define _POSIX_C_SOURCE 200809L
#include "heal_opts.h"

#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "skinsim/mech.h"

static ss_status parse_grid(const char *s, int g[3], ss_error *err) {
    long v[3];
    char *end;
    const char *p = s;
    for (int k = 0; k < 3; k++) {
        v[k] = strtol(p, &end, 10);
        if (end == p || v[k] < 3 || v[k] > 100000) goto bad;
        if (k < 2) {
            if (*end != 'x' && *end != 'X') goto bad;
            p = end + 1;
        }
    }
    if (*end) goto bad;
    for (int k = 0; k < 3; k++) g[k] = (int)v[k];
    return SS_OK;
bad:
    return ss_error_set(err, SS_ERR_INPUT,
                        "--grid: '%s' is not NXxNYxNZ with each count between 3 and 100000", s);
}

int heal_parse_problem_flag(const char *a, ss_heal_run_config *c) {
    if (!strcmp(a, "--mechanics"))
        c->mechanics = 1;
    else if (!strcmp(a, "--no-mechanics"))
        c->mechanics = 0;
    else if (!strcmp(a, "--no-scab"))
        c->no_scab = 1;
    else if (!strcmp(a, "--static-region"))
        c->static_region = 1;
    else
        return 0;
    return 1;
}

int heal_parse_problem_option(const char *a, const char *v, ss_heal_run_config *c, ss_error *err) {
    ss_status st = SS_OK;
    long l;
    if (!strcmp(a, "--scenario")) {
        c->scenario = v;
    } else if (!strcmp(a, "--params")) {
        c->params_path = v;
    } else if (!strcmp(a, "--grid")) {
        st = parse_grid(v, c->grid, err);
    } else if (!strcmp(a, "--size-mm")) {
        double *d;
        int n;
        st = cli_parse_double_list(a, v, 1e-6, 1e6, &d, &n, err);
        if (!st && n != 3) st = ss_error_set(err, SS_ERR_INPUT, "--size-mm: need X,Y,Z");
        if (!st)
            for (int k = 0; k < 3; k++) c->size_mm[k] = d[k];
        if (!st) free(d);
    } else if (!strcmp(a, "--skin-top-mm")) {
        st = cli_parse_double(a, v, 1e-6, 1e6, &c->skin_top_mm, err);
    } else if (!strcmp(a, "--epidermis-mm")) {
        st = cli_parse_double(a, v, 0, 1e6, &c->epidermis_mm, err);
    } else if (!strcmp(a, "--wound-mask")) {
        c->wound_mask = v;
    } else if (!strcmp(a, "--stroke")) {
        c->wound_stroke = v;
    } else if (!strcmp(a, "--concave-k")) {
        st = cli_parse_int(a, v, 0, 10000, &l, err);
        c->concave_k = (int)l;
        if (!st && l > 0 && l < 3)
            st = ss_error_set(err, SS_ERR_INPUT, "--concave-k: use 0 (convex) or >= 3");
    } else if (!strcmp(a, "--wound-mesh")) {
        c->wound_mesh = v;
    } else if (!strcmp(a, "--wound-depth-mm")) {
        st = cli_parse_double(a, v, 1e-6, 1e6, &c->wound_depth_mm, err);
    } else if (!strcmp(a, "--wound-depth-image")) {
        c->wound_depth_image = v;
    } else if (!strcmp(a, "--fibres")) {
        c->fibres = v;
    } else if (!strcmp(a, "--kappa")) {
        st = cli_parse_double(a, v, 0, 1.0 / 3.0 + 1e-9, &c->kappa, err);
    } else if (!strcmp(a, "--tet-size-mm")) {
        st = cli_parse_double(a, v, 1e-6, 1e3, &c->tet_size_mm, err);
    } else if (!strcmp(a, "--sutures")) {
        c->sutures = v;
    } else if (!strcmp(a, "--mech-model")) {
        int mm;
        st = ss_mech_model_parse(v, &mm, err);
        if (st) ss_error_set(err, SS_ERR_INPUT, "--mech-model: '%s' is not 'springs' or 'goh'", v);
        c->mech_model = v;
    } else if (!strcmp(a, "--tet-mesh")) {
        c->tet_mesh = v;
    } else if (!strcmp(a, "--mesh")) {
        c->skin_mesh = v;
    } else if (!strcmp(a, "--wound-uv")) {
        c->wound_uv = v;
    } else if (!strcmp(a, "--skin-thickness-mm")) {
        st = cli_parse_double(a, v, 1e-6, 100, &c->skin_thickness_mm, err);
    } else if (!strcmp(a, "--voxel-mm")) {
        st = cli_parse_double(a, v, 0.05, 10, &c->voxel_mm, err);
    } else if (!strcmp(a, "--mesh-units-mm")) {
        st = cli_parse_double(a, v, 1e-9, 1e9, &c->mesh_units_mm, err);
    } else if (!strcmp(a, "--dt")) {
        st = cli_parse_double(a, v, 1e-12, 1e3, &c->dt_days, err);
    } else if (!strcmp(a, "--scheme")) {
        if (!strcmp(v, "explicit"))
            c->scheme = SS_HEAL_EXPLICIT;
        else if (!strcmp(v, "split"))
            c->scheme = SS_HEAL_SPLIT;
        else
            st = ss_error_set(err, SS_ERR_INPUT, "--scheme: '%s' is not 'explicit' or 'split'", v);
    } else {
        return 0;
    }
    return st ? -1 : 1;
}

void heal_default_adapt_tol(ss_heal_run_config *c) {
    if (c->scheme == SS_HEAL_SPLIT && c->dt_days == 0 && !c->mechanics)
        c->adapt_tol = SS_HEAL_RUN_DEFAULT_ADAPT_TOL;
}
