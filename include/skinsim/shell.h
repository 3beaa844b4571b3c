/* skinsim shell: skin on a real body (seed 001 §5.1, §5.4). A closed surface
 * mesh (OBJ, glTF/GLB) is the outside of the body; the skin is the shell of a
 * stated thickness under it. Around a wound given as UV strokes with a depth
 * (the stroke CSV of `skinsim abrasion`, in the mesh's UV space) or as a closed
 * wound mesh, a local healing grid (a "patch") is laid with its z axis along
 * the mean surface normal of the wound, and every voxel is classified by ray
 * tests against the mesh (air, epidermis, dermis, wound, inner bound), as the
 * seed's §5.1 does. After a run, fields and the deformation are mapped back
 * onto the undeformed mesh's vertices (§5.4) and written as a VTK surface.
 *
 *   ss_mesh skin;  ss_mesh_load("hand.glb", &skin, &err);
 *   ss_shell_opts o;  ss_shell_opts_default(&o);
 *   ss_shell_patch *p = ss_shell_patch_from_uv(&skin, "hand.glb", "cut.csv", &o, &err);
 *   ss_heal_grid *g = ss_heal_grid_create(p->nx, p->ny, p->nz, p->dx_mm, &err);
 *   ss_shell_patch_grid_init(p, g, params, &err);     // cells + initial fields
 *   ... heal steps ...
 *   ss_shell_vertex_fields(p, &skin, g, disp, out);   // §5.4
 *
 * Units: the mesh's own (glTF: metres) scaled by units_mm to mm; the grid in
 * mm. The patch is local: the seed voxelises the whole body, which a healing
 * grid of 0.5 mm voxels cannot hold for a hand; the wound and a margin of
 * intact skin around it are what heals. Gave up: wounds wider than the
 * surface is flat: the patch's columns run along one normal, so a wound whose
 * surface turns more than SS_SHELL_MAX_WRAP_DEG from its mean normal (one
 * wrapping around a finger) is refused with SS_ERR_INPUT rather than cut off
 * at its steep sides. */
#ifndef SKINSIM_SHELL_H
#define SKINSIM_SHELL_H

#include <stdint.h>

#include "skinsim/core.h"
#include "skinsim/heal.h"
#include "skinsim/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The most a wound's surface normal may turn from the patch's normal. */
#define SS_SHELL_MAX_WRAP_DEG 60

typedef struct ss_shell_opts {
    double voxel_mm;     /* grid voxel edge (default 0.5) */
    double thickness_mm; /* skin shell under the surface (default 3, epidermis + dermis) */
    double epidermis_mm; /* epidermis (default SS_HEAL_DEFAULT_EPIDERMIS_MM) */
    double depth_mm;     /* depth of a UV-stroke wound (default SS_HEAL_DEFAULT_DEPTH_MM) */
    double margin_mm;    /* intact skin around the wound (0 = the wound's radius, >= 5 mm) */
    double units_mm;     /* one mesh unit in mm; 0 = glTF 1000, OBJ by its size (below) */
    int concave_k;       /* stroke hulls: 0 convex, >= 3 k-nearest concave */
} ss_shell_opts;
void ss_shell_opts_default(ss_shell_opts *o);
/* units_mm for a mesh file name (0 in opts): glTF is in metres, OBJ taken as mm. */
double ss_shell_units_for(const char *path, double units_mm);

/* OBJ skin meshes whose bounding-box diagonal (in file units) is below this
 * are read in metres, at or above SS_SHELL_OBJ_MM_DIAG in mm; between the two
 * mm and cm are both plausible and the unit must be given. */
#define SS_SHELL_OBJ_METRE_DIAG 3.0
#define SS_SHELL_OBJ_MM_DIAG 60.0
/* One unit of `skin` (read from `path`) in mm: units_mm when > 0, glTF 1000,
 * an OBJ by its size (above; the metre reading writes a note into `note`,
 * which may be NULL; an ambiguous size is SS_ERR_INPUT naming `path` and
 * --mesh-units-mm). */
ss_status ss_shell_units_resolve(const ss_mesh *skin, const char *path, double units_mm,
                                 double *out, char *note, size_t note_size, ss_error *err);

/* A closed surface: every edge (vertices welded by position) is shared by
 * exactly two triangles, no triangle is degenerate, and no edge pierces a
 * triangle it does not touch (self-intersection). Otherwise SS_ERR_INPUT
 * naming `name` and the offending triangle. */
ss_status ss_shell_check_closed(const ss_mesh *m, const char *name, ss_error *err);

typedef struct ss_shell_patch {
    int nx, ny, nz;
    double dx_mm;
    /* cell (i,j,k) centre, in mesh mm (mesh units x units_mm):
     * origin + (i+0.5) dx axis[0] + (j+0.5) dx axis[1] + (k+0.5) dx axis[2] */
    double origin_mm[3], axis[3][3];
    double units_mm;
    uint8_t *cell;      /* ss_heal_cell per voxel, index (k*ny + j)*nx + i */
    float *surf_z;      /* per column: surface height above the grid's bottom (mm), NaN = none */
    int wound_cells;    /* voxels cut out */
    double skin_top_mm; /* highest surface point above the grid's bottom */
    double wound_centre_mm[3], wound_radius_mm;
} ss_shell_patch;

/* A patch around UV strokes (u,v[,stroke] CSV, read with ss_stroke_csv_read):
 * each stroke's hull is cut to o->depth_mm under the surface. A point in no
 * UV triangle, a stroke spanning two UV islands, or a wound whose surface
 * normals (at the stroke points and the mesh vertices inside the hulls) turn
 * more than SS_SHELL_MAX_WRAP_DEG from their mean and from the direction that
 * minimises the largest angle -> SS_ERR_INPUT naming the
 * CSV, the point and the mesh. The mesh must be closed (ss_shell_check_closed
 * is the caller's job, done once per mesh). */
ss_shell_patch *ss_shell_patch_from_uv(const ss_mesh *skin, const char *skin_name,
                                       const char *strokes_csv, const ss_shell_opts *o,
                                       ss_error *err);
/* A patch around a closed wound mesh (same units as the skin mesh): the
 * tissue voxels inside it are cut out. A wound mesh that cuts no skin voxel
 * -> SS_ERR_INPUT "misses the skin"; one holding a skin vertex whose normal
 * turns more than SS_SHELL_MAX_WRAP_DEG from the skin's normal facing the
 * wound -> SS_ERR_INPUT "wraps around". */
ss_shell_patch *ss_shell_patch_from_mesh(const ss_mesh *skin, const char *skin_name,
                                         const ss_mesh *wound, const char *wound_name,
                                         const ss_shell_opts *o, ss_error *err);
void ss_shell_patch_free(ss_shell_patch *p);

/* Cell states and initial fields of g (created with the patch's nx, ny, nz,
 * dx): as ss_heal_grid_init does for a block (healthy tissue, clot in the
 * wound, epithelium in the intact epidermis), on the patch's cells. */
ss_status ss_shell_patch_grid_init(const ss_shell_patch *p, ss_heal_grid *g,
                                   const ss_heal_params *hp, ss_error *err);

/* §5.4: per mesh vertex, the surface fields of its grid column (the column's
 * top tissue cell; vertices outside the patch get the healthy values) and
 * the displacement there (disp: the grid's 3 displacement arrays in the
 * patch frame, mm, or NULL), rotated into the mesh frame, in mesh units.
 * out: nvertices * (SS_HEAL_NFIELDS + 3) floats, fields first. */
#define SS_SHELL_VERTEX_STRIDE (SS_HEAL_NFIELDS + 3)
void ss_shell_vertex_fields(const ss_shell_patch *p, const ss_mesh *skin, const ss_heal_grid *g,
                            const ss_heal_params *hp, float *const *disp, float *out);
/* The same without the grid (a run on MPI ranks): top[ncol] the level of
 * each column's top tissue cell or -1 (ss_shell_column_tops), tv the fields
 * there (ncol x SS_HEAL_NFIELDS), td the displacement there (ncol x 3, or
 * NULL); ncol = p->nx * p->ny. */
void ss_shell_vertex_fields_top(const ss_shell_patch *p, const ss_mesh *skin,
                                const ss_heal_params *hp, const int32_t *top, const float *tv,
                                const float *td, float *out);
/* The level of every column's top tissue cell (or -1) of a patch grid's cells. */
void ss_shell_column_tops(const ss_shell_patch *p, const uint8_t *cell, int32_t *top);
/* The mesh as a VTK XML UnstructuredGrid of triangles, points moved by the
 * displacement (mm), point data displacement (mm), every heal field and the
 * open-wound flag (epithelium < 0.5 on the wound region). Atomic. */
ss_status ss_shell_surface_vtu_write(const ss_shell_patch *p, const ss_mesh *skin,
                                     const float *vertex_fields, const char *path, double t_days,
                                     ss_error *err);

/* The same snapshot as a binary glTF (.glb, ss_gltf_write_mesh_glb): the
 * undeformed mesh in metres, the eight heal fields and the open-wound flag as
 * float vertex attributes _OXYGEN, _MDGF, _CAPILLARY, _FIBROBLAST, _ESCHAR,
 * _EPITHELIUM, _SCAR, _PLASMA, _OPEN_WOUND, the displacement as a morph
 * target "displacement" shown at weight 1 (slide it to 0 for the undeformed
 * mesh), and COLOR_0 from ss_shell_wound_colour. The node's extras hold
 * t_days and the field names. Atomic. */
ss_status ss_shell_surface_glb_write(const ss_shell_patch *p, const ss_mesh *skin,
                                     const float *vertex_fields, const char *path, double t_days,
                                     ss_error *err);
/* The wound state at a glance, linear RGB: intact skin a light skin tone;
 * wound tissue (plasma above SS_HEAL_P_MIN, or scar collagen) raw red while
 * open, turning pink as the epithelium covers it; dark brown where eschar
 * (crust) lies, in proportion to it. f: one vertex's SS_HEAL_NFIELDS values. */
void ss_shell_wound_colour(const float *f, float rgb[3]);

#ifdef __cplusplus
}
#endif
#endif
