/* skinsim heal_io: getting wounds into the healing grid and results out of it.
 * Inputs: footprint masks (PNG/EXR), closed meshes (read by geom: strokes and
 * OBJ) voxelised by ray parity as in seed 001 §5.1. Outputs: VTK XML ImageData (.vti)
 * snapshots with a ParaView .pvd time collection, top-view surface maps, the
 * normalised wound-area curve of seed 001 Fig. 4 (CSV + cairo plot), and
 * versioned, CRC-checked, atomically written checkpoints for exact resume.
 * All lengths are mm, all times days. See docs/heal-outputs.md. */
#ifndef SKINSIM_HEAL_IO_H
#define SKINSIM_HEAL_IO_H

#include "skinsim/core.h"
#include "skinsim/geom.h"
#include "skinsim/heal.h"
#include "skinsim/mesh.h"

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

/* ---- meshes ------------------------------------------------------------------
 * Wound meshes are read by geom's OBJ reader (ss_obj_read, ss_tri_mesh in
 * skinsim/mesh.h). */

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
 * ss_heal_field_name(), `velocity` Float32 x3 when the grid has velocities,
 * then `surface_elevation_mm` Float32 (the column's ss_heal_elevation_scan,
 * the same in every cell of a column: a height map for `wound`). WholeExtent 0 nx 0 ny 0 nz, Origin
 * 0 0 0, Spacing dx dx dx (mm). FieldData TimeValue holds t in days. Written atomically. */
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
 * extents), files[i] relative to the .pvti. ParaView opens it as one image
 * (its time is the one fields.pvd gives it). */
ss_status ss_heal_pvti_write(const char *path, const int whole[3], double dx_mm, int npieces,
                             const int (*ext)[6], const char *const *files, ss_error *err);
/* The same with nvec Float32 3-vector cell arrays (names[i]) in every piece. */
ss_status ss_heal_pvti_write_vectors(const char *path, const int whole[3], double dx_mm,
                                     int npieces, const int (*ext)[6], const char *const *files,
                                     int nvec, const char *const *names, ss_error *err);
/* The same, listing also the keloid's added volume (the Float32 cell array
 * keloid_added that the pieces of a grid with g->added hold, docs/heal-model.md
 * [D16]) when added is not 0. */
ss_status ss_heal_pvti_write_arrays(const char *path, const int whole[3], double dx_mm, int npieces,
                                    const int (*ext)[6], const char *const *files, int nvec,
                                    const char *const *names, int added, ss_error *err);
/* The same with nvec 3-component cell arrays (as ss_heal_vti_write_vectors,
 * each of piece->nx*ny*nz floats) and, if closed_day is not NULL, the closure
 * days of the piece's own columns (piece->nx * piece->ny, index y*nx + x of
 * the piece) as a Float64 FieldData array `closed_day`. A snapshot made only
 * of pieces feeds ss_heal_pvti_read (and so `skinsim wound --heal`) only if
 * its pieces carry closed_day: every column of the whole grid must be in at
 * least one piece that has it (e.g. every piece, or the z = 0 box of each
 * stack). */
ss_status ss_heal_vti_write_piece_all(const char *path, const ss_heal_grid *piece, const int off[3],
                                      const int whole[3], int nvec, const char *const *names,
                                      float *const (*vecs)[3], const double *closed_day,
                                      ss_error *err);
/* The piece of the box of g at box[0..2] (g's indices) of box[3] x box[4] x
 * box[5] cells, written straight from g (no copy; e.g. a rank's owned cells
 * inside its halo): the file ss_heal_vti_write_piece_all writes for a grid of
 * just those cells, cells and fields, closed_day of the box's columns. */
ss_status ss_heal_vti_write_box(const char *path, const ss_heal_grid *g, const int box[6],
                                const int off[3], const int whole[3], const double *closed_day,
                                ss_error *err);
/* The same with the grid's velocity (when g has one) and nvec 3-vectors over
 * g (names[i], vecs[i][0..2]) on the box, e.g. a rank's piece of a run with
 * the contraction mechanics (velocity, displacement); elevation: the surface
 * elevation of g's columns (nx*ny, the whole column's, e.g. summed over a z
 * stack of boxes), NULL = over the box's own levels. */
ss_status ss_heal_vti_write_box_vectors(const char *path, const ss_heal_grid *g, const int box[6],
                                        const int off[3], const int whole[3], int nvec,
                                        const char *const *names, float *const (*vecs)[3],
                                        const double *closed_day, const float *elevation,
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

/* Reads a parallel image written by ss_heal_pvti_write and its .vti pieces
 * (ss_heal_vti_write_piece / _piece_all; Source paths relative to the .pvti)
 * into one whole grid: the same grid, displacement and closed_day as
 * ss_heal_vti_read gives for the gathered snapshot of the same state.
 * displacement is set only when every piece has a `displacement` array;
 * closed_day when the pieces that carry one cover every column (pieces that
 * share a column must agree on it). Checked before the grid is returned: the
 * .pvti's XML (PImageData, WholeExtent, Spacing, one Piece per Source), each
 * piece (the vti reader's checks, its WholeExtent, Spacing and TimeValue equal
 * to the .pvti's and the other pieces'), and that the pieces tile the whole
 * extent exactly (no gap, no overlap). Failures -> NULL, SS_ERR_INPUT naming
 * the file at fault (the .pvti or the piece). */
ss_heal_grid *ss_heal_pvti_read(const char *path, float **displacement, double **closed_day,
                                ss_error *err);
/* The cheap part of those checks, without reading the pieces' data: the
 * .pvti's XML, the tiling, and that every piece file is there and not empty. */
ss_status ss_heal_pvti_check(const char *path, ss_error *err);

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
/* The same on a box that is one of a stack in z (src/mpi; zoff, gz as in
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
 * mean_<field>...,open_columns_mm2`, one row per entry (open_area_mm2 the
 * uncovered area, open_columns_mm2 the columns under the threshold: see
 * ss_heal_stats). Atomic. */
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
 * ckpt_<step, 12 digits>.sshc, or in pieces (ckpt_<step>.sshh and its
 * ckpt_<step>_p<i>.sshp, below: read as one box). Loads the newest one of
 * either kind that verifies (temporary
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

/* ---- checkpoints in pieces (docs/heal-outputs.md "Checkpoints in pieces") -----
 * A checkpoint of a grid cut into boxes (the MPI driver's ranks, or
 * ss_heal_checkpoint_save_pieces in one process), so no process ever holds
 * the whole grid to write or read it. In DIR/checkpoints/:
 *   ckpt_<step, 12 digits>_p<piece, 6 digits>.sshp   one box of every array
 *   ckpt_<step, 12 digits>.sshh                      the header, written last
 * A piece (little endian, version 1): "SSHEALPC" u32 version, i32 whole nx ny
 * nz, nfields, lo[3], n[3] (the box in whole-grid cell indices), u64 step,
 * f64 t_days, u32 velocity_present, then the box's cell array (n0*n1*n2
 * bytes, index (z*n1 + y)*n0 + x), nfields Float32 arrays, 3 velocity arrays
 * if present, and a trailing u32 CRC-32 over everything before it.
 * The header ("SSHEALPH", version 1): everything a whole-grid checkpoint's
 * header holds (nx ny nz nfields, dx skin_top t_days, step, scheme, dt,
 * velocity_present, scenario, params JSON, aux), the process grid dims[3],
 * npieces and per piece lo[3], n[3], u64 file bytes, u32 CRC; then its own
 * CRC-32. Each file is written to a temporary name and renamed; the header is
 * written by one writer after every piece is in place, so a checkpoint is
 * complete exactly when its header exists. Pieces may come from any split:
 * any set of boxes that tiles the grid exactly.
 *
 * On MPI (src/mpi), writing: every rank ss_heal_ckpt_piece_write(dir, rank,
 * its box + halo grid, org, its lo and n, whole, &info); the statuses are
 * reduced and the infos gathered (plain bytes) to rank 0, which fills the
 * header (whole grid, dx, skin top, t, step, scheme, dt, scenario, params
 * JSON, aux, dims, pieces) and calls ss_heal_ckpt_header_save. Resuming (any
 * rank count): rank 0 ss_heal_checkpoint_open_latest (a whole-grid checkpoint
 * comes back loaded, as before); for a piece one it broadcasts the step, every
 * rank ss_heal_ckpt_header_read(ss_heal_ckpt_header_path(dir, step)) and
 * ss_heal_ckpt_read_box of its box + halo, and the statuses are reduced before
 * anything is written. Single process: ss_heal_checkpoint_load_latest reads
 * both kinds; `skinsim heal --checkpoint-pieces PXxPYxPZ` writes pieces. */
#define SS_HEAL_CKPT_MAX_PIECES 16384
typedef struct ss_heal_ckpt_piece {
    int lo[3], n[3]; /* the box, whole-grid cell indices */
    uint64_t bytes;  /* the piece file's size */
    uint32_t crc;    /* its CRC-32 (the file's last four bytes) */
} ss_heal_ckpt_piece;
typedef struct ss_heal_ckpt_header {
    int whole[3]; /* nx ny nz */
    double dx_mm, skin_top_mm, t_days;
    uint64_t step;
    int scheme;
    double dt_days;
    int velocity;              /* 1: the pieces hold the three velocity arrays */
    char *scenario;            /* owned */
    char *params_json;         /* owned */
    char *aux;                 /* owned, "" when none */
    int dims[3];               /* the writers' process grid; its product is npieces */
    int npieces;               /* 1..SS_HEAL_CKPT_MAX_PIECES */
    ss_heal_ckpt_piece *piece; /* owned, npieces; piece i is file _p<i> */
} ss_heal_ckpt_header;
void ss_heal_ckpt_header_free(ss_heal_ckpt_header *h); /* frees the members, zeroes h */

/* DIR/checkpoints/ckpt_<step>.sshh and ..._p<index>.sshp into buf. */
void ss_heal_ckpt_header_path(char *buf, size_t len, const char *run_dir, uint64_t step);
void ss_heal_ckpt_piece_path(char *buf, size_t len, const char *run_dir, uint64_t step, int index);

/* Box `c` (coords) of a dims process grid over whole: the block split of the
 * MPI driver, lo = whole * c / dims (integer division), so sizes differ by
 * at most one. */
void ss_heal_ckpt_split(const int whole[3], const int dims[3], const int coords[3], int lo[3],
                        int n[3]);

/* Writes piece `index` of the checkpoint of step g->step: the box lo..lo+n
 * (whole-grid indices, inside whole) of every array of g, a grid whose cell
 * (0,0,0) is whole-grid cell org (a box with its halo: org = lo - 1; the whole
 * grid: org = 0). The box must lie inside g. Creates DIR/checkpoints if
 * needed; atomic. *info receives the box, bytes and CRC for the header (the
 * MPI driver gathers them to the header's writer). Needs no other process. */
ss_status ss_heal_ckpt_piece_write(const char *run_dir, int index, const ss_heal_grid *g,
                                   const int org[3], const int lo[3], const int n[3],
                                   const int whole[3], ss_heal_ckpt_piece *info, ss_error *err);
/* Writes the header (after every piece of h->step is written) and then, like
 * ss_heal_checkpoint_save, keeps only the newest `keep` (>= 2) checkpoints of
 * either kind in DIR/checkpoints, removing older headers, whole-grid files,
 * pieces of no kept checkpoint (up to h->step) and temporaries of killed
 * writes. Refuses (SS_ERR_INPUT) a header whose pieces do not tile the grid. */
ss_status ss_heal_ckpt_header_save(const char *run_dir, const ss_heal_ckpt_header *h, int keep,
                                   ss_error *err);
/* Reads and verifies a header file: magic, version, its CRC, values, and that
 * its pieces tile the whole grid exactly. SS_ERR_INPUT naming the path. */
ss_status ss_heal_ckpt_header_read(const char *path, ss_heal_ckpt_header *out, ss_error *err);
/* Every piece of h is there, has the header's size and its own header agrees
 * with h (whole dims, nfields, box, step, t_days, velocity); with verify_crc
 * each is also read whole (streamed, constant memory) and its CRC checked
 * against the file's and the header's. SS_ERR_INPUT naming the piece file.
 * The MPI driver's rank 0 runs this before a distributed resume. */
ss_status ss_heal_ckpt_pieces_check(const char *run_dir, const ss_heal_ckpt_header *h,
                                    int verify_crc, ss_error *err);
/* Reads the box lo..lo+n (whole-grid indices; clipped to the whole grid, e.g.
 * a box with its halo) of every array into g, whose cell (0,0,0) is the
 * whole-grid cell org (g's cells outside the clipped box are left as they
 * are). Only the pieces overlapping the box are opened; each is checked
 * (its header against h, its size, its CRC over every byte, streamed) as it
 * is read, so on an error g's box holds garbage: SS_ERR_INPUT naming the
 * piece file. Sets g->t_days, step and skin_top_mm from h; with h->velocity,
 * g's missing velocity arrays are allocated (g's size), without it g's
 * velocity arrays (if any) get zeros in the box. */
ss_status ss_heal_ckpt_read_box(const char *run_dir, const ss_heal_ckpt_header *h, ss_heal_grid *g,
                                const int org[3], const int lo[3], const int n[3], ss_error *err);

/* One process: g (the whole grid) as a checkpoint of dims[0] x dims[1] x
 * dims[2] pieces (ss_heal_ckpt_split) and its header, then pruned to the
 * newest keep as ss_heal_ckpt_header_save does. */
ss_status ss_heal_checkpoint_save_pieces(const char *run_dir, const ss_heal_grid *g,
                                         const char *scenario, const char *params_json, int scheme,
                                         double dt_days, const char *aux, const int dims[3],
                                         int keep, ss_error *err);
/* The piece checkpoint of `step` in run_dir read whole (the box = the grid)
 * into *out (header, pieces check, then every piece), as
 * ss_heal_checkpoint_read gives for a whole-grid checkpoint of that state. */
ss_status ss_heal_checkpoint_read_pieces(const char *run_dir, uint64_t step,
                                         ss_heal_checkpoint *out, ss_error *err);
/* The newest usable checkpoint of run_dir of either kind, without reading a
 * piece checkpoint's grid: a whole-grid one is read into *whole (whole->grid
 * set, pieces->npieces 0); for a piece one *pieces gets its header after
 * ss_heal_ckpt_pieces_check(verify_crc) passed (whole->grid NULL). Newer
 * checkpoints that fail are skipped (named in note); SS_ERR_INPUT if none is
 * usable. A resume on any number of ranks: each reads its box with
 * ss_heal_ckpt_read_box. ss_heal_checkpoint_load_latest is this plus, for a
 * piece checkpoint, the whole grid read as one box. */
ss_status ss_heal_checkpoint_open_latest(const char *run_dir, int verify_crc,
                                         ss_heal_checkpoint *whole, ss_heal_ckpt_header *pieces,
                                         char *note, size_t note_len, ss_error *err);

#ifdef __cplusplus
}
#endif
#endif
