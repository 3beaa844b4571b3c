/* skinsim heal_io: getting wounds into the healing grid and results out of it.
 * Inputs: footprint masks (PNG/EXR), painted stroke CSV files, closed OBJ meshes
 * voxelised by ray parity as in seed 001 §5.1. Outputs: VTK XML ImageData (.vti)
 * snapshots with a ParaView .pvd time collection, top-view surface maps, the
 * normalised wound-area curve of seed 001 Fig. 4 (CSV + cairo plot), and
 * versioned, CRC-checked, atomically written checkpoints for exact resume.
 * All lengths are mm, all times days. See docs/heal-outputs.md. */
#ifndef SKINSIM_HEAL_IO_H
#define SKINSIM_HEAL_IO_H

#include "skinsim/core.h"
#include "skinsim/geom.h"
#include "skinsim/heal.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Painted strokes: ss_stroke_set, ss_stroke_csv_read, ss_stroke_footprint are
 * in skinsim/geom.h (shared with `skinsim abrasion`). */

/* ---- footprints -------------------------------------------------------------
 * A footprint is a 1-channel image, 1 = wound, 0 = intact, covering the grid's
 * x-y extent (image column -> x, image row -> y). */

/* Reads a greyscale/RGB(A) PNG or EXR mask: the first channel (luminance of
 * RGB) is thresholded at 0.5 (linear). An all-zero mask is an input error. */
ss_image *ss_heal_footprint_read(const char *path, ss_error *err);
/* Reads a depth image (PNG: 0..1 scaled by max_depth_mm; EXR: values in mm)
 * into a 1-channel image of depths in mm. Negative or non-finite depths are
 * an input error. */
ss_image *ss_heal_depth_image_read(const char *path, double max_depth_mm, ss_error *err);

/* ---- meshes (OBJ) -----------------------------------------------------------
 * A small OBJ reader: `v x y z [w]`, `f` with `i`, `i/t`, `i//n`, `i/t/n` forms,
 * negative (relative) indices, polygons triangulated as fans; other statements
 * (vt, vn, o, g, s, usemtl, mtllib, l) are ignored. Errors name file and line. */
typedef struct ss_tri_mesh {
    int nverts, ntris;
    double *v; /* 3*nverts, x y z */
    int *tri;  /* 3*ntris vertex indices (0-based) */
    int *line; /* ntris: OBJ line of the face each triangle came from */
} ss_tri_mesh;
ss_status ss_obj_read(const char *path, ss_tri_mesh *out, ss_error *err);
ss_status ss_obj_parse(const char *text, const char *name, ss_tri_mesh *out, ss_error *err);
void ss_tri_mesh_free(ss_tri_mesh *m);
/* Closed = every undirected edge is used by an even, non-zero number of
 * triangles and no triangle is degenerate (repeated vertex). Otherwise
 * SS_ERR_INPUT naming `name` and the OBJ line of an offending face. */
ss_status ss_tri_mesh_check_closed(const ss_tri_mesh *m, const char *name, ss_error *err);

/* Voxelises a closed mesh (coordinates in mm in the grid frame: x, y along the
 * grid, z up, origin at the grid corner) into an nx*ny*nz 0/1 array indexed
 * (z*ny + y)*nx + x: for each column (x, y) a ray along +z through the voxel
 * centre collects crossings with the triangles; a voxel centre is inside when
 * an odd number of crossings lies below it (seed 001 §5.1 ray test). Rays are
 * nudged by a fixed tiny offset to avoid passing exactly through edges.
 * *count receives the number of inside voxels (may be NULL). Returns malloc'd
 * array or NULL with err set. Runs in parallel over columns; deterministic. */
uint8_t *ss_heal_voxelise_mesh(const ss_tri_mesh *m, int nx, int ny, int nz, double dx_mm,
                               size_t *count, ss_error *err);
/* The same for the box of bn[0] x bn[1] x bn[2] voxels at whole-grid index
 * lo of a gdim grid (the MPI driver's boxes; voxels past the grid are 0):
 * every voxel as in the whole-grid mask, *count the inside voxels of the box. */
uint8_t *ss_heal_voxelise_mesh_box(const ss_tri_mesh *m, const int gdim[3], const int lo[3],
                                   const int bn[3], double dx_mm, size_t *count, ss_error *err);

/* ---- VTK output -------------------------------------------------------------
 * VTK XML ImageData, one piece, cell data (one value per voxel), appended raw
 * binary with UInt64 headers, little endian. Arrays: `cell_state` UInt8 (the
 * ss_heal_cell codes), one Float32 array per field named by
 * ss_heal_field_name(), `velocity` Float32 x3 when the grid has velocities.
 * WholeExtent 0 nx 0 ny 0 nz, Origin 0 0 0, Spacing dx dx dx (mm). FieldData
 * TimeValue holds t in days. Written atomically. */
ss_status ss_heal_vti_write(const char *path, const ss_heal_grid *g, ss_error *err);
/* The same with nvec more 3-component cell arrays (names[v], vecs[v][c] of
 * nx*ny*nz floats), e.g. the mechanics' displacement. */
ss_status ss_heal_vti_write_vectors(const char *path, const ss_heal_grid *g, int nvec,
                                    const char *const *names, float *const (*vecs)[3],
                                    ss_error *err);

/* A piece of a parallel image (the MPI driver's per-rank pieces): piece is
 * the box, its cell (0,0,0) at whole-grid index off; Extent off..off+size,
 * WholeExtent 0..whole. Cells and fields only. */
ss_status ss_heal_vti_write_piece(const char *path, const ss_heal_grid *piece, const int off[3],
                                  const int whole[3], ss_error *err);
/* The .pvti that joins npieces such pieces: ext[i] = x0 x1 y0 y1 z0 z1 (point
 * extents), files[i] relative to the .pvti. ParaView opens it as one image. */
ss_status ss_heal_pvti_write(const char *path, const int whole[3], double dx_mm, double t_days,
                             int npieces, const int (*ext)[6], const char *const *files,
                             ss_error *err);
/* Reads a snapshot written by ss_heal_vti_write(_vectors) back into a new grid
 * (cell states, every field, t_days; skin_top_mm and step are left 0: the
 * file does not hold them). displacement: if not NULL, receives a malloc'd
 * array of 3 x nx*ny*nz floats (the x components of every cell, then y, then
 * z) when the file has a `displacement` array, else NULL; closed_day likewise
 * the malloc'd closure days (nx*ny) of a `closed_day` array. A file this writer
 * did not make, a truncated one or a missing array -> SS_ERR_INPUT naming the
 * file. */
ss_heal_grid *ss_heal_vti_read(const char *path, float **displacement, double **closed_day,
                               ss_error *err);

/* ---- closure day per column ----------------------------------------------------
 * The day each (x, y) column's epithelial layer (ss_heal_surface_map's
 * SS_SURFACE_LAYER value) last rose to the open threshold (0.5) from below:
 * the age of the new tissue, which no field holds and a renderer of the
 * surface needs (docs/wound.md). Arrays of nx*ny days in grid order (index
 * y*nx + x); a column that was never seen open is SS_HEAL_CLOSED_INTACT, one
 * that is open now SS_HEAL_CLOSED_OPEN. */
#define SS_HEAL_CLOSED_INTACT (-1.0)
#define SS_HEAL_CLOSED_OPEN (-2.0)
/* Every column intact, then an update (open columns become OPEN). */
void ss_heal_closure_init(const ss_heal_grid *g, double *closed);
/* After a step: open columns become OPEN; an OPEN column now at or above the
 * threshold closed at g->t_days. Columns of air only are left alone. */
void ss_heal_closure_update(const ss_heal_grid *g, double *closed);
/* The same on a box that is one of a stack in z (src/dist; zoff, gz as in
 * ss_heal_stats_acc_add_stack): scan continues the search for the column's
 * two topmost tissue cells over the owned levels (v = -1, found = 0 for the
 * top box; nx*ny each, grid order); the bottom box then applies the result. */
void ss_heal_closure_scan(const ss_heal_grid *g, int zoff, int gz, float *v, float *found);
void ss_heal_closure_apply(const ss_heal_grid *g, const float *v, double *closed);

/* ss_heal_vti_write_vectors plus, if closed_day is not NULL, the closure day
 * per column (nx*ny, as above) as a Float64 FieldData array `closed_day`. */
ss_status ss_heal_vti_write_all(const char *path, const ss_heal_grid *g, int nvec,
                                const char *const *names, float *const (*vecs)[3],
                                const double *closed_day, ss_error *err);

/* ParaView collection: `n` datasets with their times (days) and file names
 * relative to the .pvd. Written atomically. */
ss_status ss_heal_pvd_write(const char *path, int n, const double *t_days, const char *const *files,
                            ss_error *err);

/* ---- surface maps -------------------------------------------------------- */
typedef enum ss_heal_surface_mode {
    SS_SURFACE_TOP = 0,  /* value in the topmost tissue cell of each column */
    SS_SURFACE_MAX = 1,  /* maximum over the tissue cells of each column */
    SS_SURFACE_LAYER = 2 /* maximum over the two topmost tissue cells; for the
                            epithelium (a surface sheet, 0 below the surface
                            cell) the surface coverage that the open-area
                            statistic (ss_heal_stats_compute) thresholds */
} ss_heal_surface_mode;
/* Tissue cells: all but AIR, the BOUND layers z = 0 and z = nz-1, and BOUND
 * cells whose centre is above g->skin_top_mm.
 * nx x ny 1-channel image oriented like a footprint image: image row 0 is
 * grid y = ny-1 (image row r = grid y ny-1-r), column x = grid x. Columns of
 * air only are 0. */
ss_image *ss_heal_surface_map(const ss_heal_grid *g, int field, ss_heal_surface_mode mode,
                              ss_error *err);
/* The map in parts (the MPI driver: boxes stacked in z, zoff and gz as in
 * ss_heal_closure_scan): continues each column's top-down search over g's
 * levels z1-1 down to z0 (v = found = 0 before the top box; nx*ny each, grid
 * order); after the bottom box v holds the map's values, which
 * ss_heal_surface_image turns into the image rows (row 0 = y = ny-1). */
void ss_heal_surface_scan(const ss_heal_grid *g, int field, ss_heal_surface_mode mode, int z0,
                          int z1, int zoff, int gz, float *v, float *found);
void ss_heal_surface_image(const float *v, int nx, int ny, float *out);
/* Colour-mapped picture of a map (viridis, vmin..vmax; nearest-neighbour
 * upscaled so the map is at least ~360 px wide) with a title and a labelled
 * colour bar, written as an 8-bit RGB PNG, atomically. */
ss_status ss_heal_surface_png(const char *path, const ss_image *map, double vmin, double vmax,
                              const char *title, const char *unit, double dx_mm, ss_error *err);

/* ---- wound-area curve (seed 001 Fig. 4) ------------------------------------ */
typedef struct ss_heal_area_row {
    double t_days;
    ss_heal_stats st;
} ss_heal_area_row;
/* Normalised open area: open / initial (0 when the initial area is 0). */
double ss_heal_area_normalised(const ss_heal_stats *st);
/* CSV: header `t_days,open_area_mm2,normalised_area,wound_region_area_mm2,
 * mean_<field>...`, one row per entry. Atomic. */
ss_status ss_heal_area_csv_write(const char *path, const ss_heal_area_row *rows, int n,
                                 ss_error *err);
/* The same with ncols more columns (names[c], vals[i * ncols + c] for row i). */
ss_status ss_heal_area_csv_write_columns(const char *path, const ss_heal_area_row *rows, int n,
                                         int ncols, const char *const *names, const double *vals,
                                         ss_error *err);
/* First time (days, linear interpolation between rows) at which the
 * normalised area drops to <= level; negative when never reached. */
double ss_heal_time_to_closure(const ss_heal_area_row *rows, int n, double level);
/* Cairo line plot of the normalised area vs time (days), labelled axes with
 * ticks, the title, dashed 50% and 95%-closure guides. 8-bit PNG, atomic. */
ss_status ss_heal_area_plot(const char *path, const ss_heal_area_row *rows, int n,
                            const char *title, ss_error *err);
/* The same plot with the contraction's curves (either may be NULL; one value
 * per row, NaN skipped): the deformed initial outline's area / its initial
 * area and the mean myofibroblast fraction under the wound, with a legend. */
ss_status ss_heal_area_plot_contraction(const char *path, const ss_heal_area_row *rows, int n,
                                        const char *title, const double *outline,
                                        const double *myofibroblasts, ss_error *err);

/* ---- checkpoints ------------------------------------------------------------
 * Binary, little endian, version 1:
 *   "SSHEALCK" u32 version u32 header_bytes, then
 *   i32 nx ny nz nfields, f64 dx_mm skin_top_mm t_days, u64 step, i32 scheme,
 *   f64 dt_days, u32 velocity_present, then u32-length-prefixed strings:
 *   scenario, params JSON, aux (caller's run metadata, may be empty), then the
 *   cell array (nx*ny*nz bytes), nfields Float32 arrays, 3 velocity arrays if
 *   present, and a trailing u32 CRC-32 (zlib) over everything before it.
 * Written to a temporary name, fsync'ed and renamed, so a write that is killed
 * leaves the previous checkpoint intact. */
typedef struct ss_heal_checkpoint {
    ss_heal_grid *grid; /* owned */
    char *scenario;     /* owned */
    char *params_json;  /* owned */
    char *aux;          /* owned, "" when none */
    int scheme;
    double dt_days;
} ss_heal_checkpoint;
ss_status ss_heal_checkpoint_write(const char *path, const ss_heal_grid *g, const char *scenario,
                                   const char *params_json, int scheme, double dt_days,
                                   const char *aux, ss_error *err);
/* Verifies magic, version, sizes and CRC before building the grid. A short,
 * corrupt or foreign file is SS_ERR_INPUT naming the path. */
ss_status ss_heal_checkpoint_read(const char *path, ss_heal_checkpoint *out, ss_error *err);
void ss_heal_checkpoint_free(ss_heal_checkpoint *c);
/* Checkpoints of a run directory live in DIR/checkpoints/ as
 * ckpt_<step, 12 digits>.sshc. Loads the newest one that verifies (temporary
 * files from interrupted writes are ignored, corrupt ones skipped; the
 * skipped names go into `note` if not NULL). SS_ERR_INPUT if none loads. */
ss_status ss_heal_checkpoint_load_latest(const char *run_dir, ss_heal_checkpoint *out, char *note,
                                         size_t note_len, ss_error *err);
/* Writes DIR/checkpoints/ckpt_<step>.sshc and then removes all but the
 * newest `keep` (>= 2) checkpoints of that directory and any temporary file
 * an earlier, killed write left there. */
ss_status ss_heal_checkpoint_save(const char *run_dir, const ss_heal_grid *g, const char *scenario,
                                  const char *params_json, int scheme, double dt_days,
                                  const char *aux, int keep, ss_error *err);

#ifdef __cplusplus
}
#endif
#endif
