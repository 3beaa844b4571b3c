/* A heal run on a real body (seed 001 §5.1, §5.4; the geometry is
 * src/shell/shell.c, skinsim/shell.h): the skin mesh and the wound (UV strokes
 * or a closed wound mesh) are read and checked, the healing grid is the
 * shell's patch around the wound, and every snapshot maps the fields and the
 * mechanics' displacement back onto the undeformed mesh, refined around the
 * wound to about the voxel size (ss_mesh_refine_near)
 * (surface/skin_NNNN.vtu with a surface/skin.pvd time series for ParaView,
 * and surface/skin_NNNN.glb for glTF viewers and Blender: the fields as
 * vertex attributes, the displacement as a morph target, a wound-state
 * vertex colour).
 *
 * Design: the patch is rebuilt from the same files on resume (its
 * construction is deterministic), so a checkpoint stores only the paths and
 * options; a resume checks the rebuilt patch against the checkpointed grid.
 * Gave up: a resume after the mesh file changed is refused rather than
 * remapped. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "run_internal.h"
#include "skinsim/shell.h"

int ss_heal_run__shell_wanted(const ss_heal_run_config *c) {
    return c->skin_mesh || c->wound_uv || c->skin_thickness_mm != 0 || c->voxel_mm != 0 ||
           c->mesh_units_mm != 0;
}

static void opts_from(const ss_heal_run *r, ss_shell_opts *o) {
    ss_shell_opts_default(o);
    o->voxel_mm = r->shell_opts[0];
    o->thickness_mm = r->shell_opts[1];
    o->epidermis_mm = r->shell_opts[2];
    o->depth_mm = r->shell_opts[3];
    o->margin_mm = r->shell_opts[4];
    o->units_mm = r->shell_opts[5];
    o->concave_k = r->shell_concave;
}

/* Mesh, wound and patch from r->skin_path, r->wound_path and r->shell_opts. */
static ss_status build(ss_heal_run *r, ss_error *err) {
    ss_status st = ss_mesh_load(r->skin_path, &r->skin, err);
    if (st) return st;
    if ((st = ss_shell_check_closed(&r->skin, r->skin_path, err))) return st;
    ss_shell_opts o;
    opts_from(r, &o);
    /* an OBJ's unit from its size (skinsim/shell.h); the metre reading is a note */
    char note[512];
    if ((st = ss_shell_units_resolve(&r->skin, r->skin_path, o.units_mm, &o.units_mm, note,
                                     sizeof note, err)))
        return st;
    if (note[0]) {
        size_t n = strlen(r->note);
        snprintf(r->note + n, sizeof r->note - n, "%s%s", n ? "\n" : "", note);
    }
    if (r->wound_is_uv) {
        r->shell = ss_shell_patch_from_uv(&r->skin, r->skin_path, r->wound_path, &o, err);
    } else {
        ss_mesh w;
        if ((st = ss_mesh_load(r->wound_path, &w, err))) return st;
        st = ss_shell_check_closed(&w, r->wound_path, err);
        if (!st)
            r->shell = ss_shell_patch_from_mesh(&r->skin, r->skin_path, &w, r->wound_path, &o, err);
        ss_mesh_free(&w);
        if (st) return st;
    }
    if (!r->shell) return err->code ? err->code : SS_ERR_INPUT;
    /* the mesh the fields are mapped onto: the skin's triangles near the
     * wound split down to about the voxel (a hand's are 5 mm, a wound a few
     * voxels), so the vertex data shows the wound and not a few vertices */
    const ss_shell_patch *p = r->shell;
    float c[3];
    for (int d = 0; d < 3; d++) c[d] = (float)(p->wound_centre_mm[d] / p->units_mm);
    if ((st = ss_mesh_refine_near(&r->skin, c,
                                  (float)((1.5 * p->wound_radius_mm + 2 * p->dx_mm) / p->units_mm),
                                  (float)(1.5 * p->dx_mm / p->units_mm), 6, &r->surf, err)))
        return st;
    r->vfields = malloc((size_t)r->surf.nvertices * SS_SHELL_VERTEX_STRIDE * sizeof(float));
    if (!r->vfields) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    return SS_OK;
}

static ss_status shell_tops(ss_heal_run *r, ss_error *err);

ss_status ss_heal_run__shell_setup_fresh(ss_heal_run *r, ss_error *err) {
    const ss_heal_run_config *c = &r->c;
    if (!c->skin_mesh)
        return ss_error_set(err, SS_ERR_INPUT,
                            "--wound-uv, --skin-thickness-mm, --voxel-mm and --mesh-units-mm need "
                            "--mesh");
    if (!!c->wound_uv + !!c->wound_mesh != 1)
        return ss_error_set(err, SS_ERR_INPUT,
                            "--mesh needs the wound as --wound-uv CSV or --wound-mesh FILE (one)");
    if (c->wound_mask || c->wound_stroke || c->wound_footprint || c->wound_depth_image ||
        c->grid[0] || c->grid[1] || c->grid[2] || c->size_mm[0] != 0 || c->size_mm[1] != 0 ||
        c->size_mm[2] != 0 || c->skin_top_mm != 0)
        return ss_error_set(err, SS_ERR_INPUT,
                            "--mesh sets the grid and the skin: --grid, --size-mm, --skin-top-mm, "
                            "--wound-mask, --stroke and --wound-depth-image do not apply");
    if (c->wound_mesh && c->wound_depth_mm != 0)
        return ss_error_set(
            err, SS_ERR_INPUT,
            "--wound-mesh defines the wound volume; --wound-depth-mm does not apply");
    if (c->concave_k && !c->wound_uv)
        return ss_error_set(err, SS_ERR_INPUT, "--concave-k only applies to --wound-uv");
    ss_shell_opts o;
    ss_shell_opts_default(&o);
    double v[6] = {c->voxel_mm != 0 ? c->voxel_mm : o.voxel_mm,
                   c->skin_thickness_mm != 0 ? c->skin_thickness_mm : o.thickness_mm,
                   c->epidermis_mm != 0 ? c->epidermis_mm : o.epidermis_mm,
                   c->wound_depth_mm != 0 ? c->wound_depth_mm : o.depth_mm,
                   0,
                   c->mesh_units_mm};
    memcpy(r->shell_opts, v, sizeof v);
    r->shell_concave = c->concave_k;
    r->wound_is_uv = c->wound_uv != NULL;
    r->skin_path = strdup(c->skin_mesh);
    r->wound_path = strdup(c->wound_uv ? c->wound_uv : c->wound_mesh);
    if (!r->skin_path || !r->wound_path) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    ss_status st = build(r, err);
    if (st) return st;
    const ss_shell_patch *p = r->shell;
    r->g = ss_heal_grid_create(p->nx, p->ny, p->nz, p->dx_mm, err);
    if (!r->g) return err->code ? err->code : SS_ERR_NOMEM;
    if ((st = ss_shell_patch_grid_init(p, r->g, r->p, err))) return st;
    /* distributed: rank 0 builds the patch's grid once, hands the ranks their
     * boxes and drops it; the column tops stay for the surface outputs */
    if (c->distributed && (st = shell_tops(r, err))) return st;
    r->wound = cJSON_CreateObject();
    if (!r->wound) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    cJSON_AddStringToObject(r->wound, "skin_mesh", r->skin_path);
    cJSON_AddStringToObject(r->wound, r->wound_is_uv ? "wound_uv" : "wound_mesh", r->wound_path);
    if (r->wound_is_uv) cJSON_AddNumberToObject(r->wound, "depth_mm", v[3]);
    cJSON_AddNumberToObject(r->wound, "voxels", p->wound_cells);
    cJSON_AddNumberToObject(r->wound, "radius_mm", p->wound_radius_mm);
    return SS_OK;
}

ss_status ss_heal_run__shell_setup_resume(ss_heal_run *r, ss_error *err) {
    cJSON *a = r->shell_aux;
    if (!a) return SS_OK;
    const cJSON *sk = cJSON_GetObjectItem(a, "skin_mesh"), *wo = cJSON_GetObjectItem(a, "wound"),
                *uv = cJSON_GetObjectItem(a, "wound_is_uv"), *op = cJSON_GetObjectItem(a, "opts"),
                *ck = cJSON_GetObjectItem(a, "concave_k");
    if (!cJSON_IsString(sk) || !cJSON_IsString(wo) || !cJSON_IsNumber(uv) || !cJSON_IsArray(op) ||
        cJSON_GetArraySize(op) != 6 || !cJSON_IsNumber(ck))
        return ss_error_set(err, SS_ERR_INPUT, "checkpoint: the skin-mesh metadata is incomplete");
    for (int k = 0; k < 6; k++) r->shell_opts[k] = cJSON_GetArrayItem(op, k)->valuedouble;
    r->shell_concave = ck->valueint;
    r->wound_is_uv = uv->valueint;
    r->skin_path = strdup(sk->valuestring);
    r->wound_path = strdup(wo->valuestring);
    cJSON_Delete(r->shell_aux);
    r->shell_aux = NULL;
    if (!r->skin_path || !r->wound_path) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    ss_status st = build(r, err);
    if (st) return st;
    if (r->shell->nx != r->g->nx || r->shell->ny != r->g->ny || r->shell->nz != r->g->nz)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: the skin patch no longer matches the checkpoint's grid (did the "
                            "mesh or the wound file change?)",
                            r->skin_path);
    return r->c.distributed ? shell_tops(r, err) : SS_OK;
}

void ss_heal_run__shell_aux(const ss_heal_run *r, cJSON *aux) {
    if (!r->shell) return;
    cJSON *a = cJSON_AddObjectToObject(aux, "shell");
    cJSON_AddStringToObject(a, "skin_mesh", r->skin_path);
    cJSON_AddStringToObject(a, "wound", r->wound_path);
    cJSON_AddNumberToObject(a, "wound_is_uv", r->wound_is_uv);
    cJSON_AddItemToObject(a, "opts", cJSON_CreateDoubleArray(r->shell_opts, 6));
    cJSON_AddNumberToObject(a, "concave_k", r->shell_concave);
}

/* A distributed run: the column tops from the patch's cells (rank 0's whole
 * grid while it has one, or a grid of the patch built for the purpose). */
static ss_status shell_tops(ss_heal_run *r, ss_error *err) {
    const ss_shell_patch *p = r->shell;
    if (!(r->shell_top = malloc((size_t)p->nx * p->ny * sizeof(int32_t))))
        return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    if (r->g->cell) {
        ss_shell_column_tops(p, r->g->cell, r->shell_top);
        return SS_OK;
    }
    ss_heal_grid *g = ss_heal_grid_create(p->nx, p->ny, p->nz, p->dx_mm, err);
    if (!g) return err->code ? err->code : SS_ERR_NOMEM;
    ss_status st = ss_shell_patch_grid_init(p, g, r->p, err);
    if (!st) ss_shell_column_tops(p, g->cell, r->shell_top);
    ss_heal_grid_free(g);
    return st;
}

const int32_t *ss_heal_run_shell_tops(const ss_heal_run *r) { return r->shell_top; }

ss_status ss_heal_run__shell_snapshot(ss_heal_run *r, int idx, ss_error *err) {
    if (!r->shell) return SS_OK;
    float *const *u = r->mech ? ss_mech_grid_displacement(r->mech) : NULL;
    if (r->mech && !u) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    if (r->g->cell) {
        ss_shell_vertex_fields(r->shell, &r->surf, r->g, r->p, u, r->vfields);
    } else { /* distributed: the values at the columns' tops from the ranks */
        const ss_shell_patch *p = r->shell;
        const size_t ncol = (size_t)p->nx * p->ny;
        float *tv = calloc(ncol * SS_HEAL_NFIELDS, sizeof(float));
        float *td = u ? calloc(3 * ncol, sizeof(float)) : NULL;
        if (!tv || (u && !td) || !r->hooks.columns || !r->shell_top) {
            free(tv);
            free(td);
            return ss_error_set(err, SS_ERR_NOMEM, "out of memory (surface columns)");
        }
        r->hooks.columns(r->hooks.ctx, r->shell_top, tv);
        for (size_t c = 0; td && c < ncol; c++)
            if (r->shell_top[c] >= 0)
                for (int d = 0; d < 3; d++)
                    td[3 * c + (size_t)d] = u[d][(size_t)r->shell_top[c] * ncol + c];
        ss_shell_vertex_fields_top(p, &r->surf, r->p, r->shell_top, tv, td, r->vfields);
        free(tv);
        free(td);
    }
    char path[4400];
    snprintf(path, sizeof path, "%s/surface/skin_%04d.vtu", r->out_dir, idx);
    ss_status st =
        ss_shell_surface_vtu_write(r->shell, &r->surf, r->vfields, path, r->g->t_days, err);
    if (st) return st;
    snprintf(path, sizeof path, "%s/surface/skin_%04d.glb", r->out_dir, idx);
    if ((st = ss_shell_surface_glb_write(r->shell, &r->surf, r->vfields, path, r->g->t_days, err)))
        return st;
    return ss_heal_run__series_pvd(r, "surface", "skin", err);
}

void ss_heal_run__shell_summary(const ss_heal_run *r, cJSON *j) {
    if (!r->shell) return;
    const ss_shell_patch *p = r->shell;
    cJSON *s = cJSON_AddObjectToObject(j, "skin_mesh");
    cJSON_AddStringToObject(s, "mesh", r->skin_path);
    cJSON_AddNumberToObject(s, "vertices", r->skin.nvertices);
    cJSON_AddNumberToObject(s, "triangles", r->skin.ntriangles);
    cJSON_AddNumberToObject(s, "surface_vertices", r->surf.nvertices);
    cJSON_AddNumberToObject(s, "surface_triangles", r->surf.ntriangles);
    cJSON_AddNumberToObject(s, "units_mm", p->units_mm);
    cJSON_AddNumberToObject(s, "thickness_mm", r->shell_opts[1]);
    cJSON_AddItemToObject(s, "patch_origin_mm", cJSON_CreateDoubleArray(p->origin_mm, 3));
    cJSON_AddItemToObject(s, "patch_x_axis", cJSON_CreateDoubleArray(p->axis[0], 3));
    cJSON_AddItemToObject(s, "patch_y_axis", cJSON_CreateDoubleArray(p->axis[1], 3));
    cJSON_AddItemToObject(s, "patch_normal", cJSON_CreateDoubleArray(p->axis[2], 3));
    cJSON_AddItemToObject(s, "wound_centre_mm", cJSON_CreateDoubleArray(p->wound_centre_mm, 3));
    cJSON_AddNumberToObject(s, "wound_radius_mm", p->wound_radius_mm);
}

void ss_heal_run__shell_free(ss_heal_run *r) {
    ss_shell_patch_free(r->shell);
    ss_mesh_free(&r->skin);
    ss_mesh_free(&r->surf);
    free(r->skin_path);
    free(r->wound_path);
    free(r->vfields);
    free(r->shell_top);
    cJSON_Delete(r->shell_aux);
}

const struct ss_shell_patch *ss_heal_run_shell(const ss_heal_run *r) { return r->shell; }
const struct ss_mesh *ss_heal_run_skin_mesh(const ss_heal_run *r) {
    return r->shell ? &r->skin : NULL;
}
