/* Setting up a heal run (seed 001 §5.1) from its config, one job per function:
 * the parameters (preset, overrides, switches), the grid geometry (voxel
 * counts, voxel size, skin surface), the memory check, the wound inputs (mask,
 * strokes, in-memory footprint, depth image or closed mesh, all read and
 * checked before the grid exists), the wound volume and its check, and the
 * solver with the step intervals. A resume instead loads the newest valid
 * checkpoint and the run's metadata stored in it.
 *
 * Nothing here writes a file: every input is validated before the run's
 * outputs begin. Messages name settings by their `skinsim heal` options, since
 * that is where most users meet them. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "run_internal.h"

/* ---- config checks a library caller could get wrong (the CLI checks first) ---- */

static ss_status check_config(const ss_heal_run_config *c, ss_error *err) {
    int have_grid = c->grid[0] || c->grid[1] || c->grid[2];
    for (int k = 0; have_grid && k < 3; k++)
        if (c->grid[k] < 3 || c->grid[k] > 100000)
            return ss_error_set(err, SS_ERR_INPUT,
                                "--grid %dx%dx%d: each count must be between 3 and 100000",
                                c->grid[0], c->grid[1], c->grid[2]);
    int have_size = c->size_mm[0] != 0 || c->size_mm[1] != 0 || c->size_mm[2] != 0;
    for (int k = 0; have_size && k < 3; k++)
        if (!(c->size_mm[k] >= 1e-6 && c->size_mm[k] <= 1e6))
            return ss_error_set(err, SS_ERR_INPUT, "--size-mm %g,%g,%g: need 1e-6..1e6 mm each",
                                c->size_mm[0], c->size_mm[1], c->size_mm[2]);
    static const char *const names[] = {"--skin-top-mm", "--epidermis-mm", "--wound-depth-mm",
                                        "--days",        "--dt",           "--snapshot-every",
                                        "--area-every"};
    const double v[] = {c->skin_top_mm, c->epidermis_mm,   c->wound_depth_mm, c->days,
                        c->dt_days,     c->snapshot_every, c->area_every};
    for (int k = 0; k < 7; k++)
        if (!(v[k] >= 0 && v[k] <= 1e6))
            return ss_error_set(err, SS_ERR_INPUT, "%s %g: need a finite value >= 0", names[k],
                                v[k]);
    if (!(c->checkpoint_every <= 1e6)) /* negative = default */
        return ss_error_set(err, SS_ERR_INPUT, "--checkpoint-every %g: need a finite value",
                            c->checkpoint_every);
    if (c->scheme != SS_HEAL_EXPLICIT && c->scheme != SS_HEAL_SPLIT)
        return ss_error_set(err, SS_ERR_INPUT, "--scheme: %d is not explicit or split",
                            (int)c->scheme);
    if (c->concave_k < 0 || (c->concave_k > 0 && c->concave_k < 3))
        return ss_error_set(err, SS_ERR_INPUT, "--concave-k: use 0 (convex) or >= 3");
    if (!(c->adapt_tol >= 0 && c->adapt_tol <= 1))
        return ss_error_set(err, SS_ERR_INPUT, "--adapt-tol %g: need a value in [0, 1]",
                            c->adapt_tol);
    if (c->adapt_tol > 0 && (c->scheme != SS_HEAL_SPLIT || c->mechanics))
        return ss_error_set(err, SS_ERR_INPUT,
                            "--adapt-tol %g: adaptive steps need the split scheme without "
                            "--mechanics (use --adapt-tol 0)",
                            c->adapt_tol);
    return SS_OK;
}

/* ---- parameters ---------------------------------------------------------------- */

static ss_status setup_params(ss_heal_run *r, ss_error *err) {
    const ss_heal_run_config *c = &r->c;
    /* with a params file and no scenario, the file's "scenario" key decides */
    r->p = c->params_path ? ss_heal_params_load(c->params_path, c->scenario, err)
                          : ss_heal_params_preset(c->scenario ? c->scenario : "clean", err);
    if (!r->p) return err->code ? err->code : SS_ERR_INPUT;
    ss_status st =
        ss_heal_params_set_switches(r->p, c->no_scab ? 0 : -1, c->static_region ? 1 : -1);
    if (st) return ss_error_set(err, st, "cannot apply --no-scab/--static-region");
    snprintf(r->scenario, sizeof r->scenario, "%s", r->p->scenario);
    return SS_OK;
}

/* ---- grid geometry --------------------------------------------------------------- */

typedef struct geometry {
    int n[3];
    double dx, top; /* voxel edge, skin surface height (mm) */
    double X, Y, Z; /* block size (mm) */
    double depth;   /* wound depth (mm) */
} geometry;

static ss_status voxel_counts(const ss_heal_run_config *c, int n[3], double *dx, ss_error *err) {
    int have_grid = c->grid[0] || c->grid[1] || c->grid[2];
    int have_size = c->size_mm[0] != 0 || c->size_mm[1] != 0 || c->size_mm[2] != 0;
    const double *s = c->size_mm;
    *dx = SS_HEAL_DEFAULT_DX_MM;
    if (have_grid && have_size) {
        *dx = s[0] / c->grid[0];
        for (int k = 1; k < 3; k++)
            if (fabs(s[k] / c->grid[k] - *dx) > 1e-6 * *dx)
                return ss_error_set(err, SS_ERR_INPUT,
                                    "--size-mm %g,%g,%g with --grid %dx%dx%d gives non-cubic "
                                    "voxels (%g, %g, %g mm); voxels must be cubic",
                                    s[0], s[1], s[2], c->grid[0], c->grid[1], c->grid[2],
                                    s[0] / c->grid[0], s[1] / c->grid[1], s[2] / c->grid[2]);
        memcpy(n, c->grid, 3 * sizeof *n);
    } else if (have_grid) {
        memcpy(n, c->grid, 3 * sizeof *n);
    } else {
        double sz[3] = {SS_HEAL_DEFAULT_BLOCK_X_MM, SS_HEAL_DEFAULT_BLOCK_Y_MM,
                        SS_HEAL_DEFAULT_BLOCK_Z_MM};
        if (have_size) memcpy(sz, s, sizeof sz);
        for (int k = 0; k < 3; k++) {
            double cnt = ceil(sz[k] / *dx - 1e-9);
            if (cnt < 3 || cnt > 100000)
                return ss_error_set(err, SS_ERR_INPUT,
                                    "--size-mm: %g mm gives %g voxels of %g mm (need 3..100000)",
                                    sz[k], cnt, *dx);
            n[k] = (int)cnt;
        }
    }
    return SS_OK;
}

static ss_status check_memory(const int n[3], ss_error *err) {
    size_t cells = (size_t)n[0] * (size_t)n[1] * (size_t)n[2];
    if (cells > SS_HEAL_MAX_CELLS)
        return ss_error_set(err, SS_ERR_INPUT, "--grid %dx%dx%d: %zu cells exceed the limit %zu",
                            n[0], n[1], n[2], cells, (size_t)SS_HEAL_MAX_CELLS);
    /* grid + wound mask + solver scratch (about two more grids for the split scheme) */
    double need = 3.0 * (double)ss_heal_grid_bytes(n[0], n[1], n[2]) + (double)cells;
    double avail = ss_memory_physical_bytes();
    if (avail > 0 && need > 0.8 * avail)
        return ss_error_set(err, SS_ERR_INPUT,
                            "--grid %dx%dx%d needs about %.1f GB, more than this machine's "
                            "memory (%.1f GB)",
                            n[0], n[1], n[2], need / 1e9, avail / 1e9);
    return SS_OK;
}

static ss_status setup_geometry(const ss_heal_run_config *c, geometry *gm, ss_error *err) {
    ss_status st = voxel_counts(c, gm->n, &gm->dx, err);
    if (!st) st = check_memory(gm->n, err);
    if (st) return st;
    gm->X = gm->n[0] * gm->dx;
    gm->Y = gm->n[1] * gm->dx;
    gm->Z = gm->n[2] * gm->dx;
    /* Default skin surface: one air layer under the top boundary voxel, which
     * is the highest surface ss_heal_grid_init accepts ((nz-2) voxels). */
    gm->top = c->skin_top_mm != 0 ? c->skin_top_mm : (gm->n[2] - 2) * gm->dx;
    if (!(gm->top > 0) || gm->top >= gm->Z)
        return ss_error_set(err, SS_ERR_INPUT,
                            "skin surface at %g mm is outside the block (0..%g mm); use "
                            "--skin-top-mm or --size-mm",
                            gm->top, gm->Z);
    gm->depth = c->wound_depth_mm != 0 ? c->wound_depth_mm : SS_HEAL_DEFAULT_DEPTH_MM;
    return SS_OK;
}

/* ---- wound inputs: read and check everything before the grid exists ------------ */

typedef struct wound_inputs {
    ss_image *fp;   /* footprint, NULL = mesh or built-in square */
    ss_image *dimg; /* depth image in mm, NULL = uniform depth */
    ss_tri_mesh mesh;
} wound_inputs;

static void wound_inputs_free(wound_inputs *w) {
    ss_image_free(w->fp);
    ss_image_free(w->dimg);
    ss_tri_mesh_free(&w->mesh);
}

static ss_status check_wound_options(const ss_heal_run_config *c, const geometry *gm,
                                     ss_error *err) {
    int nsrc = !!c->wound_mask + !!c->wound_stroke + !!c->wound_mesh + !!c->wound_footprint;
    if (nsrc > 1)
        return ss_error_set(err, SS_ERR_INPUT,
                            "give only one of --wound-mask, --stroke, --wound-mesh");
    if (c->wound_mesh && (c->wound_depth_image || c->wound_depth_mm != 0))
        return ss_error_set(err, SS_ERR_INPUT,
                            "--wound-mesh defines the wound volume; it cannot be combined with "
                            "--wound-depth-mm or --wound-depth-image");
    if (c->concave_k && !c->wound_stroke)
        return ss_error_set(err, SS_ERR_INPUT, "--concave-k only applies to --stroke");
    if (!c->wound_depth_image && gm->depth >= gm->top - gm->dx)
        return ss_error_set(err, SS_ERR_INPUT,
                            "--wound-depth-mm %g reaches the bottom of the tissue (skin surface "
                            "at %g mm, %g mm voxels)",
                            gm->depth, gm->top, gm->dx);
    if (c->wound_footprint && (c->wound_footprint->channels != 1 || c->wound_footprint->width < 1 ||
                               c->wound_footprint->height < 1))
        return ss_error_set(err, SS_ERR_INPUT, "wound footprint: need a 1-channel image");
    return SS_OK;
}

/* The footprint from a mask, strokes, an in-memory image, or the mesh. */
static ss_status read_wound_shape(ss_heal_run *r, const geometry *gm, wound_inputs *w,
                                  ss_error *err) {
    const ss_heal_run_config *c = &r->c;
    ss_status st;
    if (c->wound_mask) {
        w->fp = ss_heal_footprint_read(c->wound_mask, err);
        if (!w->fp) return err->code;
        cJSON_AddStringToObject(r->wound, "mask", c->wound_mask);
    } else if (c->wound_footprint) {
        w->fp = ss_image_clone(c->wound_footprint, err);
        if (!w->fp) return err->code;
        cJSON_AddStringToObject(r->wound, "footprint", "image");
    } else if (c->wound_stroke) {
        ss_stroke_set ss;
        if ((st = ss_stroke_csv_read(c->wound_stroke, &ss, err))) return st;
        w->fp = ss_stroke_footprint(&ss, 4 * gm->n[0], 4 * gm->n[1], c->concave_k, c->wound_stroke,
                                    err);
        cJSON_AddStringToObject(r->wound, "stroke", c->wound_stroke);
        cJSON_AddNumberToObject(r->wound, "strokes", ss.nstrokes);
        cJSON_AddStringToObject(r->wound, "hull", c->concave_k ? "concave" : "convex");
        ss_stroke_set_free(&ss);
        if (!w->fp) return err->code;
    } else if (c->wound_mesh) {
        if ((st = ss_obj_read(c->wound_mesh, &w->mesh, err))) return st;
        if ((st = ss_tri_mesh_check_closed(&w->mesh, c->wound_mesh, err))) return st;
        cJSON_AddStringToObject(r->wound, "mesh", c->wound_mesh);
        cJSON_AddNumberToObject(r->wound, "triangles", w->mesh.ntris);
    }
    return SS_OK;
}

/* The depth image; alone, its non-zero pixels are also the footprint. */
static ss_status read_wound_depth(ss_heal_run *r, const geometry *gm, wound_inputs *w,
                                  ss_error *err) {
    const char *path = r->c.wound_depth_image;
    if (!path) return SS_OK;
    w->dimg = ss_heal_depth_image_read(path, gm->depth, err);
    if (!w->dimg) return err->code;
    float dmax = 0;
    size_t np = (size_t)w->dimg->width * (size_t)w->dimg->height;
    for (size_t i = 0; i < np; i++)
        if (w->dimg->data[i] > dmax) dmax = w->dimg->data[i];
    if (dmax >= gm->top - gm->dx)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: depth %g mm reaches the bottom of the tissue (skin surface "
                            "at %g mm)",
                            path, dmax, gm->top);
    if (!w->fp) {
        w->fp = ss_image_create(w->dimg->width, w->dimg->height, 1, err);
        if (!w->fp) return err->code;
        size_t on = 0;
        for (size_t i = 0; i < np; i++) on += (w->fp->data[i] = w->dimg->data[i] > 0 ? 1.f : 0.f);
        if (!on) return ss_error_set(err, SS_ERR_INPUT, "%s: depth image is zero everywhere", path);
    }
    cJSON_AddStringToObject(r->wound, "depth_image", path);
    return SS_OK;
}

/* ---- the wound volume --------------------------------------------------------------- */

static const char *wound_source_name(const ss_heal_run_config *c) {
    return c->wound_mesh        ? c->wound_mesh
           : c->wound_mask      ? c->wound_mask
           : c->wound_stroke    ? c->wound_stroke
           : c->wound_footprint ? "wound footprint"
                                : "--wound-depth-mm";
}

static ss_status wound_uncovered(const ss_heal_run_config *c, const geometry *gm, int whole,
                                 ss_error *err) {
    char hint[160];
    if (c->wound_mesh)
        snprintf(hint, sizeof hint, "; mesh coordinates are mm from the block corner, z up");
    else if (whole)
        snprintf(hint, sizeof hint,
                 "; make it larger or deeper (the keloid and --mechanics round the depth to "
                 "whole %g mm voxels)",
                 gm->dx);
    else
        snprintf(hint, sizeof hint, "; make it larger or deeper");
    return ss_error_set(err, SS_ERR_INPUT,
                        "%s: the wound covers no voxel under the skin surface (%g mm) of the "
                        "%gx%gx%g mm block with %g mm voxels%s",
                        wound_source_name(c), gm->top, gm->X, gm->Y, gm->Z, gm->dx, hint);
}

static ss_status mesh_outside(const ss_heal_run_config *c, const geometry *gm, ss_error *err) {
    return ss_error_set(err, SS_ERR_INPUT,
                        "%s: no voxel centre of the %gx%gx%g mm block lies inside the mesh "
                        "(coordinates are mm from the block corner, z up)",
                        c->wound_mesh, gm->X, gm->Y, gm->Z);
}

/* The keloid, an evolving region and the mechanics keep whole-voxel depths
 * (docs/heal-model.md [D15]): the mechanics' wound springs read the WOUND
 * state, not a partial cell's intact share, and its velocity carries the
 * plasma that records the fraction. */
static int whole_voxels(const ss_heal_run *r) {
    return r->c.mechanics || !ss_heal_wound_subvoxel(r->p);
}

/* The wound of a footprint or the built-in square as column ranges
 * (rounded to whole levels where whole_voxels); NULL with err set. */
static int32_t *wound_columns(ss_heal_run *r, const geometry *gm, const wound_inputs *w,
                              ss_error *err) {
    int32_t *cols;
    if (w->fp) {
        cols = ss_heal_wound_columns_footprint(gm->n[0], gm->n[1], gm->n[2], gm->dx, gm->top, w->fp,
                                               gm->depth, w->dimg, err);
    } else {
        double side = SS_HEAL_DEFAULT_WOUND_MM, lim = (gm->X < gm->Y ? gm->X : gm->Y) * 2.0 / 3.0;
        if (side > lim) side = lim;
        cols = ss_heal_wound_columns_box(gm->n[0], gm->n[1], gm->n[2], gm->dx, gm->top, side, side,
                                         gm->depth, err);
        cJSON_AddStringToObject(r->wound, "builtin", "centred square");
        cJSON_AddNumberToObject(r->wound, "side_mm", side);
    }
    if (cols && whole_voxels(r)) ss_heal_wound_columns_whole(cols, (size_t)gm->n[0] * gm->n[1]);
    return cols;
}

/* The nx*ny*nz wound mask (0 intact, 1 wound voxel, 2..255 partial) on r->g;
 * NULL with err set. */
static uint8_t *wound_volume(ss_heal_run *r, const geometry *gm, const wound_inputs *w,
                             ss_error *err) {
    const ss_heal_run_config *c = &r->c;
    uint8_t *w3 = NULL;
    if (c->wound_mesh) {
        size_t cnt = 0;
        w3 = ss_heal_voxelise_mesh(&w->mesh, gm->n[0], gm->n[1], gm->n[2], gm->dx, &cnt, err);
        if (w3 && cnt == 0) {
            mesh_outside(c, gm, err);
            free(w3);
            return NULL;
        }
        if (w3) cJSON_AddNumberToObject(r->wound, "voxels", (double)cnt);
    } else {
        int32_t *cols = wound_columns(r, gm, w, err);
        const int lo[3] = {0, 0, 0};
        if (cols) w3 = ss_heal_wound_columns_expand(cols, gm->n, lo, gm->n, err);
        free(cols);
    }
    if (!w3) return NULL;
    /* the wound must reach at least one voxel under the skin surface */
    size_t below = 0, plane = (size_t)gm->n[0] * (size_t)gm->n[1];
    for (size_t i = 0; i < plane * (size_t)gm->n[2]; i++)
        below += w3[i] && ((double)(i / plane) + 0.5) * gm->dx < gm->top;
    if (!below) {
        wound_uncovered(c, gm, whole_voxels(r), err);
        free(w3);
        return NULL;
    }
    return w3;
}

/* ---- solver and step intervals ------------------------------------------------------ */

static long long every_steps(double days, double dt) {
    if (!(days > 0)) return 0;
    long long k = llround(days / dt);
    return k < 1 ? 1 : k;
}

static ss_status setup_solver(ss_heal_run *r, ss_error *err) {
    const ss_heal_run_config *c = &r->c;
    if (c->distributed) { /* the MPI driver's ranks step the boxes */
        double dt = c->dt_days;
        ss_status st = ss_heal_solver_check(r->g, r->p, r->scheme, &dt, err);
        if (st) return st;
        r->dt = dt;
    } else {
        r->s = ss_heal_solver_create(r->g, r->p, r->scheme, c->dt_days, err);
        if (!r->s) return err->code ? err->code : SS_ERR_INPUT;
        r->dt = ss_heal_solver_dt(r->s);
    }
    r->snap_every = every_steps(c->snapshot_every, r->dt);
    r->area_every = llround(c->area_every / r->dt);
    if (r->area_every < 1) r->area_every = 1;
    r->ckpt_every = every_steps(c->checkpoint_every, r->dt);
    r->adapt_tol = c->adapt_tol;
    ss_heal_run__adapt_init(r);
    r->params_json = ss_heal_params_to_json(r->p);
    if (!r->params_json) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    return SS_OK;
}

/* ---- distributed set-up (the MPI driver): no whole grid ------------------------------ */

static geometry geometry_of(const ss_heal_grid *g) {
    geometry gm = {
        {g->nx, g->ny, g->nz}, g->dx_mm, g->skin_top_mm, g->nx * g->dx_mm, g->ny * g->dx_mm,
        g->nz * g->dx_mm,      0};
    return gm;
}

/* The grid's sizes without its arrays, the checks of ss_heal_grid_init, and
 * the wound for the boxes: per-column level ranges (1/nz of the mask), or the
 * mesh, which every rank voxelises over its own box (its checks follow in
 * ss_heal_run_wound_counted). */
static ss_status setup_distributed(ss_heal_run *r, const geometry *gm, wound_inputs *w,
                                   ss_error *err) {
    const ss_heal_run_config *c = &r->c;
    if (!(r->g = calloc(1, sizeof *r->g))) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    r->g->nx = gm->n[0];
    r->g->ny = gm->n[1];
    r->g->nz = gm->n[2];
    r->g->dx_mm = gm->dx;
    ss_heal_grid probe = *r->g; /* an empty box: only the checks run */
    probe.nx = probe.ny = probe.nz = 0;
    const int zero[3] = {0, 0, 0};
    ss_status st =
        ss_heal_grid_init_box(&probe, zero, gm->n, gm->top, c->epidermis_mm, NULL, r->p, err);
    if (st) return st;
    r->g->skin_top_mm = gm->top;
    r->epidermis_mm = c->epidermis_mm;
    if (c->wound_mesh) {
        r->wmesh = w->mesh;
        memset(&w->mesh, 0, sizeof w->mesh);
        return SS_OK;
    }
    r->wcols = wound_columns(r, gm, w, err);
    if (!r->wcols) return err->code ? err->code : SS_ERR_RUNTIME;
    /* every level of a range lies under the skin surface */
    for (size_t k = 0; k < (size_t)gm->n[0] * (size_t)gm->n[1]; k++)
        if (r->wcols[2 * k + 1] > r->wcols[2 * k]) return SS_OK;
    return wound_uncovered(c, gm, whole_voxels(r), err);
}

ss_status ss_heal_run_wound_counted(ss_heal_run *r, size_t inside, size_t below, ss_error *err) {
    if (!r->c.wound_mesh) return SS_OK;
    const geometry gm = geometry_of(r->g);
    if (inside == 0) return mesh_outside(&r->c, &gm, err);
    cJSON_AddNumberToObject(r->wound, "voxels", (double)inside);
    return below ? SS_OK : wound_uncovered(&r->c, &gm, 0, err);
}

ss_status ss_heal_run__setup_fresh(ss_heal_run *r, ss_error *err) {
    const ss_heal_run_config *c = &r->c;
    ss_status st = check_config(c, err);
    if (!st) st = setup_params(r, err);
    if (!st && ss_heal_run__shell_wanted(c)) { /* a patch of skin on a mesh */
        r->days = c->days != 0 ? c->days : SS_HEAL_RUN_DEFAULT_DAYS;
        r->scheme = c->scheme;
        /* every option that needs no grid before the mesh work (minutes on
         * a large mesh): mechanics, checkpoint pieces, steps, the output */
        st = ss_heal_run__mech_check_options(r, err);
        const int *d = c->checkpoint_pieces;
        if (!st && (d[0] || d[1] || d[2]) &&
            (d[0] < 1 || d[1] < 1 || d[2] < 1 ||
             (long long)d[0] * d[1] * d[2] > SS_HEAL_CKPT_MAX_PIECES))
            st = ss_error_set(err, SS_ERR_INPUT,
                              "--checkpoint-pieces %dx%dx%d: need at least 1 per axis and at most "
                              "%d in all",
                              d[0], d[1], d[2], SS_HEAL_CKPT_MAX_PIECES);
        if (!st && c->dt_days > 0 && llround(r->days / c->dt_days) < 1)
            st = ss_error_set(err, SS_ERR_INPUT, "--days %g is shorter than one step (dt %g)",
                              r->days, c->dt_days);
        if (!st) st = ss_heal_run__outputs_precheck(r, err);
        if (!st) st = ss_heal_run__shell_setup_fresh(r, err);
        if (!st) st = ss_heal_run__mech_setup_fresh(r, err);
        if (!st) st = setup_solver(r, err);
        return st;
    }
    geometry gm;
    if (!st) st = setup_geometry(c, &gm, err);
    if (!st) st = check_wound_options(c, &gm, err);
    /* the output folder is checked now, not at the first step: a library
     * caller learns of a bad out_dir from create, before any work */
    if (!st && !c->distributed) st = ss_heal_run__outputs_precheck(r, err);
    if (st) return st;
    r->days = c->days != 0 ? c->days : SS_HEAL_RUN_DEFAULT_DAYS;
    r->scheme = c->scheme;
    wound_inputs w = {0};
    r->wound = cJSON_CreateObject();
    if (!r->wound) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    st = read_wound_shape(r, &gm, &w, err);
    if (!st) st = read_wound_depth(r, &gm, &w, err);
    if (!st && !c->wound_mesh) cJSON_AddNumberToObject(r->wound, "depth_mm", gm.depth);
    uint8_t *w3 = NULL;
    if (!st && c->distributed) {
        st = setup_distributed(r, &gm, &w, err);
        wound_inputs_free(&w);
        if (!st) st = ss_heal_run__mech_setup_fresh(r, err); /* its option checks */
        if (!st) st = setup_solver(r, err);
        return st;
    }
    if (!st) {
        r->g = ss_heal_grid_create(gm.n[0], gm.n[1], gm.n[2], gm.dx, err);
        if (!r->g) st = err->code ? err->code : SS_ERR_NOMEM;
    }
    if (!st && !(w3 = wound_volume(r, &gm, &w, err))) st = err->code ? err->code : SS_ERR_RUNTIME;
    wound_inputs_free(&w);
    if (!st) st = ss_heal_grid_init(r->g, gm.top, c->epidermis_mm, w3, r->p, err);
    free(w3);
    if (!st) st = ss_heal_run__mech_setup_fresh(r, err); /* before the solver: velocity */
    if (!st) st = setup_solver(r, err);
    return st;
}

/* A distributed resume: the newest checkpoint, a checkpoint in pieces
 * without its grid (checked: every piece there, its size, header and CRC;
 * the ranks read their boxes from it, ss_heal_run_resume_pieces), a
 * whole-grid one loaded as before (the driver hands it out, then drops it). */
static ss_status open_distributed(ss_heal_run *r, const char *dir, ss_heal_checkpoint *ck,
                                  ss_error *err) {
    ss_heal_ckpt_header h;
    memset(&h, 0, sizeof h);
    memset(ck, 0, sizeof *ck);
    ss_status st = ss_heal_checkpoint_open_latest(dir, 1, ck, &h, r->note, sizeof r->note, err);
    if (st || h.npieces == 0) return st;
    if (!(ck->grid = calloc(1, sizeof *ck->grid))) {
        ss_heal_ckpt_header_free(&h);
        return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    ck->grid->nx = h.whole[0];
    ck->grid->ny = h.whole[1];
    ck->grid->nz = h.whole[2];
    ck->grid->dx_mm = h.dx_mm;
    ck->grid->skin_top_mm = h.skin_top_mm;
    ck->grid->t_days = h.t_days;
    ck->grid->step = h.step;
    ck->scenario = h.scenario;
    ck->params_json = h.params_json;
    ck->aux = h.aux;
    h.scenario = h.params_json = h.aux = NULL;
    ck->scheme = h.scheme;
    ck->dt_days = h.dt_days;
    r->pieces_step = (long long)h.step;
    ss_heal_ckpt_header_free(&h);
    return SS_OK;
}

ss_status ss_heal_run__setup_resume(ss_heal_run *r, ss_error *err) {
    const ss_heal_run_config *c = &r->c;
    const char *dir = c->resume_dir;
    if (!(c->days >= 0 && c->days <= 1e6) || !(c->checkpoint_every <= 1e6))
        return ss_error_set(err, SS_ERR_INPUT, "--days and --checkpoint-every must be finite");
    ss_heal_checkpoint ck;
    ss_status st = c->distributed
                       ? open_distributed(r, dir, &ck, err)
                       : ss_heal_checkpoint_load_latest(dir, &ck, r->note, sizeof r->note, err);
    if (st) return st;
    /* a checkpoint of another run (copied in) is refused before anything is touched */
    if ((st = ss_heal_run__check_identity(r, dir, &ck, err))) {
        ss_heal_checkpoint_free(&ck);
        return st;
    }
    r->g = ck.grid;
    ck.grid = NULL;
    snprintf(r->scenario, sizeof r->scenario, "%s", ck.scenario);
    r->params_json = ck.params_json;
    ck.params_json = NULL;
    r->dt = ck.dt_days;
    r->scheme = (ss_heal_scheme)ck.scheme;
    st = ss_heal_run__aux_restore(r, ck.aux, dir, err);
    ss_heal_checkpoint_free(&ck);
    if (st) return st;
    if (c->days != 0) r->days = c->days;
    r->p = ss_heal_params_parse(r->params_json, "checkpoint parameters", r->scenario, err);
    if (!r->p) return err->code ? err->code : SS_ERR_INPUT;
    st = ss_heal_run__mech_setup_resume(r, dir, err);
    if (!st) st = ss_heal_run__shell_setup_resume(r, err);
    if (st) return st;
    double dt = r->dt;
    if (c->distributed) { /* the MPI driver's ranks step the boxes */
        if ((st = ss_heal_solver_check(r->g, r->p, r->scheme, &dt, err))) return st;
    } else {
        r->s = ss_heal_solver_create(r->g, r->p, r->scheme, r->dt, err);
        if (!r->s) return err->code ? err->code : SS_ERR_INPUT;
        dt = ss_heal_solver_dt(r->s);
    }
    if (dt != r->dt)
        return ss_error_set(err, SS_ERR_INPUT, "%s: solver refused the checkpoint's dt %.17g", dir,
                            r->dt);
    if (c->checkpoint_every >= 0) r->ckpt_every = every_steps(c->checkpoint_every, r->dt);
    long long mult = r->mult; /* from the checkpoint */
    ss_heal_run__adapt_init(r);
    if (mult >= 1 && mult <= r->mult_max) r->mult = mult;
    r->resumed_from = (long long)r->g->step;
    return SS_OK;
}
