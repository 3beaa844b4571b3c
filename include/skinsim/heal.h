/* skinsim heal: the biochemical wound-healing model of seed 001 (Feess et al.)
 * §4.1 (eight reaction-diffusion-convection species) on the regular 3D grid of
 * §5.1, with an explicit central-difference scheme and an operator-split scheme
 * (implicit LOD diffusion by Thomas line solves + reaction substeps). Both run
 * through one generic reaction-diffusion core (ss_heal_rd_*) with a pluggable
 * reaction function; the Fisher-KPP validation uses the same core.
 * Units: lengths in mm, time in days, species normalised (healthy = 1 where it
 * exists). See docs/heal-model.md. */
#ifndef SKINSIM_HEAL_H
#define SKINSIM_HEAL_H

#include <stddef.h>
#include <stdint.h>

#include "skinsim/core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- cell states and fields ---------------------------------------------- */

typedef enum ss_heal_cell {
    SS_CELL_AIR = 0,
    SS_CELL_EPIDERMIS = 1,
    SS_CELL_DERMIS = 2,
    SS_CELL_WOUND = 3,
    SS_CELL_BOUND = 4
} ss_heal_cell;

enum {
    SS_HEAL_OXYGEN,     /* u1 */
    SS_HEAL_MDGF,       /* u2 */
    SS_HEAL_CAPILLARY,  /* u3 */
    SS_HEAL_FIBROBLAST, /* n */
    SS_HEAL_ESCHAR,     /* s */
    SS_HEAL_EPITHELIUM, /* e */
    SS_HEAL_SCAR,       /* rho */
    SS_HEAL_PLASMA,     /* p, omega = [p > SS_HEAL_P_MIN] */
    SS_HEAL_NFIELDS
};

/* "oxygen", "mdgf", "capillary", "fibroblast", "eschar", "epithelium", "scar",
 * "plasma"; NULL for an out-of-range index. */
const char *ss_heal_field_name(int field);

/* ---- parameters (§4.1; values, units and sources in data/heal/params.json) -- */

typedef struct ss_heal_params {
    char scenario[32]; /* "clean" | "scab" | "keloid" */
    /* scenario switches */
    int scab;          /* 1: eschar source R(omega) on the exposed wound surface */
    int static_region; /* 1: omega = initial wound (plasma not evolved) */
    /* oxygen u1 */
    double D1;    /* mm^2/day */
    double lam11; /* 1/day, oxygen consumption */
    double lam31; /* 1/day, oxygen supply by capillaries (per unit u3) */
    /* MDGF u2 */
    double D2;       /* mm^2/day */
    double lam12;    /* 1/day, MDGF production by hypoxia, times P(u1) */
    double lam22;    /* 1/day, MDGF decay */
    double u1_beta2; /* 1, oxygen level below which MDGF is produced */
    /* capillaries u3 */
    double D3;    /* mm^2/day */
    double lam33; /* 1/day, intrinsic capillary growth */
    double lam32; /* 1/day per unit u2, MDGF-driven angiogenesis */
    double u3_eq; /* 1, maximal capillary density */
    /* fibroblasts n */
    double Dn;    /* mm^2/day */
    double rn;    /* 1/day per unit u1, maximal proliferation rate */
    double K;     /* 1, carrying capacity */
    double lamnn; /* 1/day, fibroblast death/differentiation */
    /* eschar s */
    double Ds;    /* mm^2/day */
    double Rs;    /* 1/day, magnitude of the interface source R(omega) */
    double lames; /* 1/day per unit e, keratinocyte dissolution of the eschar */
    /* epithelium e */
    double De;     /* mm^2/day */
    double lamge;  /* 1/day, epithelial growth on granulation tissue */
    double lamee;  /* 1/day, epithelial loss */
    double gamma1; /* 1, capillary density of maximal Q(u3) */
    /* scar rho */
    double lamnrho;  /* 1/day per unit n, collagen deposition by fibroblasts */
    double lamrhop;  /* 1/day, scar remodelling (fading) */
    double lamkrho;  /* 1/day per unit n, keloid (autocrine) deposition in omega, 0 = none */
    double rho_open; /* 1, share of the deposition that goes on in vascularised tissue while
                        the wound is open: (1-u3) becomes 1 - (1 - rho_open) u3 */
    /* plasma p / wound region */
    double Dp;       /* mm^2/day */
    double lampp;    /* 1/day, signed: negative = plasma resorption */
    double rho_max;  /* 1, collagen level above which C(rho) pushes the region */
    double u1_wound; /* 1, initial oxygen in the wound (clot) */
    /* physical layers (docs/heal-model.md §2): thicknesses in mm, never voxel counts */
    double bed_mm;  /* mm, depth of the wound bed whose mean u3 the epithelium reads */
    double scab_mm; /* mm, thickness of the exposed layer that dries into eschar */
    double kscab;   /* 1, fraction by which a full eschar slows the epithelial sheet under it */
    double kang;    /* 1, fraction by which a full crust over a column slows capillary growth
                       in the wound bed below it (dry wounds revascularise more slowly) */
    double rho_sat; /* 1, packing limit of collagen (x normal dermis): keloid deposition
                       saturates as (1 - rho/rho_sat) */
    /* keloid invasion (docs/heal-model.md §2 [D6]) */
    double keloid_tau;   /* day, e-folding time of the invasion signal a(t) = exp(-t/keloid_tau):
                            keloid deposition in tissue not yet keloid (rho < rho_max) is scaled
                            by a(t); 0 = no decay (a = 1) */
    double keloid_floor; /* 1, share of the invasion signal that persists (the chronic
                            inflammation of the keloid's leading edge): a(t) = floor +
                            (1 - floor) exp(-t/keloid_tau), so the front slows after the
                            injury's acute phase and then keeps invading; 0 = it stops */
    /* scar maturation (docs/heal-model.md §2 [D10]) */
    double rho_mature; /* 1, collagen of a mature scar (x normal dermis): remodelling resorbs
                          only the excess above it, so the scar stays */
    /* adnexal re-epithelialisation (docs/heal-model.md §2 [D11]) */
    double kadn;        /* 1/day, outgrowth of epithelium from surviving follicle and gland
                           remnants below a partial-thickness wound; 0 = edge only */
    double adnexa_mm;   /* mm, wound depth at which no adnexal remnant survives; the share that
                           survives falls linearly from 1 at the surface to 0 at this depth */
    double keloid_mm;   /* mm, depth below the skin surface to which the keloid deposition
                           (lamkrho) reaches (the reticular dermis); deeper dermis stays */
    double keloid_gain; /* 1, share of the keloid deposition that the packing limit refuses
                           (the complement of its (1 - rho/rho_sat) factor) that stays as added
                           tissue volume, raising the column's surface (docs/heal-model.md
                           [D16]); 0 = none (the elevation stops when the dermis saturates) */
} ss_heal_params;

/* omega = [p > SS_HEAL_P_MIN] (plasma is normalised to 1 in the fresh clot). */
#define SS_HEAL_P_MIN 0.5
/* A voxel whose eschar s exceeds this is crust: closed to oxygen, MDGF,
 * capillaries and fibroblasts (no tissue grows into a scab; docs/heal-model.md
 * [D9]). At or below it the faces conduct min(1 - s) ([D6]). */
#define SS_HEAL_CRUST_CLOSED 0.5
/* Healthy far-field values implied by the parameters (steady state of §4.1
 * in intact tissue): u3 = u3_eq, u1 = lam31 u3_eq / lam11, u2 = 0,
 * n = K (1 - lamnn / (rn u1)) (0 if negative), s = rho = p = 0. */
void ss_heal_params_healthy(const ss_heal_params *p, float healthy[SS_HEAL_NFIELDS]);

/* Built-in preset; unknown scenario -> SS_ERR_INPUT listing "clean", "scab",
 * "keloid". The presets are compiled in and equal data/heal/<scenario>.json. */
ss_heal_params *ss_heal_params_preset(const char *scenario, ss_error *err);
/* Preset for `scenario` (NULL = the file's "scenario" key, else "clean"), then
 * overrides from a JSON file of the form {"scenario": "...", "params": {"D1":
 * {"value": 1.0, "unit": "mm^2/day", "source": "..."}, ...}, "switches":
 * {"scab": 0, "static_region": 1}}. Malformed JSON, an unknown key, a missing or
 * wrong unit, or a negative/non-finite value -> SS_ERR_INPUT naming the key. */
ss_heal_params *ss_heal_params_load(const char *json_path, const char *scenario, ss_error *err);
/* Same, from a JSON text (what_name names the source in messages). */
ss_heal_params *ss_heal_params_parse(const char *json_text, const char *what_name,
                                     const char *scenario, ss_error *err);
ss_status ss_heal_params_set_switches(ss_heal_params *p, int scab /* -1 keep */,
                                      int static_region /* -1 keep */);
void ss_heal_params_free(ss_heal_params *p);
ss_heal_params *ss_heal_params_clone(const ss_heal_params *p, ss_error *err);
/* malloc'd JSON text in the load format (value + unit for every parameter). */
char *ss_heal_params_to_json(const ss_heal_params *p);
/* Unit string of a parameter key ("D1" -> "mm^2/day"); NULL if unknown. */
const char *ss_heal_param_unit(const char *key);
/* Parameter keys in file order: the i-th key, NULL past the last. */
const char *ss_heal_param_key(int i);
/* Value of a key (SS_ERR_INPUT if unknown), and setting it with the checks of
 * the JSON loader (unknown key or bad value -> SS_ERR_INPUT naming the key). */
ss_status ss_heal_param_get(const ss_heal_params *p, const char *key, double *v, ss_error *err);
ss_status ss_heal_param_set(ss_heal_params *p, const char *key, double v, ss_error *err);

/* ---- grid (§5.1) ------------------------------------------------------------ */

typedef struct ss_heal_grid {
    int nx, ny, nz;     /* x,y along the skin surface, z up (z = nz-1 is the top) */
    double dx_mm;       /* cubic voxels, edge in mm */
    double skin_top_mm; /* height of the skin surface above z=0 */
    uint8_t *cell;      /* nx*ny*nz, index (z*ny + y)*nx + x */
    float *field[SS_HEAL_NFIELDS];
    float *velocity[3]; /* NULL = zero (mm/day); the mechanics fills these later */
    double t_days;
    uint64_t step;
    /* keloid only (docs/heal-model.md [D16]): per cell, the collagen (rho units) the packing
     * limit refused that stayed as added tissue volume; the surface elevation adds
     * SS_HEAL_COLLAGEN_VOLUME x dx x it. NULL = none (every other scenario). The grid owns it. */
    float *added;
} ss_heal_grid;

/* Largest grid accepted (cells); larger, or more than the machine's physical
 * memory with the solver's work memory -> SS_ERR_INPUT. */
#define SS_HEAL_MAX_CELLS ((size_t)1 << 31)
ss_heal_grid *ss_heal_grid_create(int nx, int ny, int nz, double dx_mm, ss_error *err);
void ss_heal_grid_free(ss_heal_grid *g);
size_t ss_heal_grid_bytes(int nx, int ny, int nz);
static inline size_t ss_heal_idx(const ss_heal_grid *g, int x, int y, int z) {
    return ((size_t)z * (size_t)g->ny + (size_t)y) * (size_t)g->nx + (size_t)x;
}
/* wound3d: nx*ny*nz bytes, 0 = intact, 1 = wound voxel (tissue removed, filled
 * by clot), 2..255 = a partial wound voxel whose wounded fraction is
 * v / SS_HEAL_WOUND_SUB (the last voxel of a depth that is not a multiple of
 * the voxel, docs/heal-model.md [D15]); it is a WOUND cell whose intact share
 * (1 - f) starts with the healthy oxygen, capillaries and fibroblasts and its
 * wounded share f with the clot's oxygen (epithelium 0, plasma (1 + f) / 2:
 * in omega, and the record of f in a static region).
 * Sets cell states (BOUND on the outermost voxel shell, AIR above skin_top_mm,
 * EPIDERMIS in the voxels reaching into the top epidermis_mm of the skin (at
 * least the surface voxel, which then holds a thinner epidermis as a sheet),
 * DERMIS below, WOUND where wound3d says) and initial fields: healthy values in
 * intact tissue, wound values in the wound (u1 = u1_wound, u2 = u3 = n = 0,
 * plasma 1), the epithelium = 1 in the intact epidermis, 0 elsewhere (§5.1's
 * layer on top of the skin, in mm). wound3d NULL = no wound. */
ss_status ss_heal_grid_init(ss_heal_grid *g, double skin_top_mm, double epidermis_mm,
                            const uint8_t *wound3d, const ss_heal_params *p, ss_error *err);
/* The same on a box of a larger grid (the MPI driver's boxes, docs/scaling.md):
 * g's cell (x, y, z) is the whole grid's (x + goff[0], y + goff[1], z +
 * goff[2]) of a gdim[0] x gdim[1] x gdim[2] grid, wound3d is g's own box of
 * the whole-grid mask (NULL = no wound). Every cell gets exactly the state
 * and fields ss_heal_grid_init gives it in the whole grid; cells outside the
 * whole grid (a halo past its edge) are BOUND with zero fields. */
ss_status ss_heal_grid_init_box(ss_heal_grid *g, const int goff[3], const int gdim[3],
                                double skin_top_mm, double epidermis_mm, const uint8_t *wound3d,
                                const ss_heal_params *p, ss_error *err);
/* Sub-voxel wound depth: mask bytes 2..255 are fractions v / SS_HEAL_WOUND_SUB
 * of a voxel; column ranges are in 1/SS_HEAL_WOUND_SUB of a level. */
#define SS_HEAL_WOUND_SUB 256
/* The wounded fraction of a wound3d byte: 0, 1 for 1, v / SS_HEAL_WOUND_SUB. */
double ss_heal_wound_fraction(uint8_t v);
/* The wound of a footprint or the built-in box as per-column ranges: 2 x
 * nx*ny int32 (column y*nx + x: the start and end of the wound in depth, the
 * depth range [skin_top - depth, skin_top) in 1/SS_HEAL_WOUND_SUB of a level;
 * equal = no wound), 1/nz of the 3D mask, so the MPI driver can hand it to
 * every rank. Arguments and errors as ss_heal_wound_from_footprint and
 * ss_heal_wound_box below (which expand these over the whole grid). */
int32_t *ss_heal_wound_columns_footprint(int nx, int ny, int nz, double dx_mm, double skin_top_mm,
                                         const ss_image *footprint, double depth_mm,
                                         const ss_image *depth_mm_img, ss_error *err);
int32_t *ss_heal_wound_columns_box(int nx, int ny, int nz, double dx_mm, double skin_top_mm,
                                   double side_x_mm, double side_y_mm, double depth_mm,
                                   ss_error *err);
/* Rounds ncol column ranges to whole levels: the levels at least half inside
 * (whose centre lies in the range), the wound before [D15]; the keloid and
 * the mechanics use it (docs/heal-model.md [D15]). */
void ss_heal_wound_columns_whole(int32_t *cols, size_t ncol);
/* 1 when the wound under params p may have partial cells: a static region
 * (its frozen plasma keeps each cell's wounded fraction, which the adnexa's
 * depth reads) and no keloid; 0 = round with ss_heal_wound_columns_whole. */
int ss_heal_wound_subvoxel(const ss_heal_params *p);
/* The n[0] x n[1] x n[2] mask of the box at whole-grid index lo (may reach
 * past the grid by a halo: 0 there) from column ranges of a gdim grid; a
 * level the range cuts gets its wounded fraction (2..255, see wound3d). */
uint8_t *ss_heal_wound_columns_expand(const int32_t *cols, const int gdim[3], const int lo[3],
                                      const int n[3], ss_error *err);
/* A footprint (1-channel image, value > 0.5 = wound, mapped onto x,y over the
 * whole grid, image row 0 at y = ny-1) cut to depth_mm (or the per-pixel depth
 * of depth_mm_img, 1 channel in mm, if non-NULL) below the surface; returns the
 * malloc'd wound3d mask (the voxel the wound's floor cuts is partial). */
uint8_t *ss_heal_wound_from_footprint(const ss_heal_grid *g, double skin_top_mm,
                                      const ss_image *footprint, double depth_mm,
                                      const ss_image *depth_mm_img, ss_error *err);
/* The built-in default wound: a centred square of side_mm, depth_mm deep. */
uint8_t *ss_heal_wound_box(const ss_heal_grid *g, double skin_top_mm, double side_x_mm,
                           double side_y_mm, double depth_mm, ss_error *err);

/* Default problem (docs/heal-model.md): a 30 x 30 x 4 mm block of 0.5 mm voxels
 * (60 x 60 x 8), skin surface at 3 mm (one air layer under the top bound),
 * 0.1 mm epidermis (a sheet in the surface voxel), a 20 x 20 mm wound 1 mm deep.
 * The calibration holds at 0.25 mm too (docs/heal-model.md). */
#define SS_HEAL_DEFAULT_BLOCK_X_MM 30.0
#define SS_HEAL_DEFAULT_BLOCK_Y_MM 30.0
#define SS_HEAL_DEFAULT_BLOCK_Z_MM 4.0
#define SS_HEAL_DEFAULT_SKIN_TOP_MM 3.0
#define SS_HEAL_DEFAULT_EPIDERMIS_MM 0.1
#define SS_HEAL_DEFAULT_WOUND_MM 20.0
#define SS_HEAL_DEFAULT_DEPTH_MM 1.0
#define SS_HEAL_DEFAULT_DX_MM 0.5

/* ---- time integration -------------------------------------------------------- */

typedef enum ss_heal_scheme { SS_HEAL_EXPLICIT, SS_HEAL_SPLIT } ss_heal_scheme;

/* Largest admissible step in days. EXPLICIT: the diffusion (h^2 / (6 D_max)),
 * reaction-positivity and convection (CFL) limits; SPLIT: the accuracy cap
 * SS_HEAL_SPLIT_MAX_DT_DAYS (stable for any step; convection is sub-cycled). */
#define SS_HEAL_SPLIT_MAX_DT_DAYS 0.1
double ss_heal_stable_dt(const ss_heal_grid *g, const ss_heal_params *p, ss_heal_scheme s);

typedef struct ss_heal_solver ss_heal_solver;
/* dt_days 0 = automatic (EXPLICIT: 0.9 x limit; SPLIT: SS_HEAL_SPLIT_DEFAULT_DT_DAYS);
 * too large -> SS_ERR_INPUT naming the limit. */
#define SS_HEAL_SPLIT_DEFAULT_DT_DAYS 0.05
ss_heal_solver *ss_heal_solver_create(const ss_heal_grid *g, const ss_heal_params *p,
                                      ss_heal_scheme s, double dt_days, ss_error *err);
/* The checks of ss_heal_solver_create without the solver: *dt_days (0 =
 * automatic) becomes the step it would take. Reads only g's sizes, voxel and
 * velocity, so a grid without cell and field arrays will do (the MPI
 * driver's rank 0, which never holds the whole grid). */
ss_status ss_heal_solver_check(const ss_heal_grid *g, const ss_heal_params *p, ss_heal_scheme s,
                               double *dt_days, ss_error *err);
/* The same on a sub-box of a larger grid (src/mpi): g holds the box and a
 * one-cell halo around it, goff is the whole-grid index of g's cell (0,0,0),
 * gdim the whole grid's dimensions (see ss_heal_rd_system.goff). With the
 * split scheme the box spans the whole grid in z; an explicit box that does
 * not (one of a stack in z) needs ss_heal_solver_set_columns. */
ss_heal_solver *ss_heal_solver_create_sub(const ss_heal_grid *g, const int goff[3],
                                          const int gdim[3], const ss_heal_params *p,
                                          ss_heal_scheme s, double dt_days, ss_error *err);
/* The column values the model gathers before each reaction pass (the surface
 * cell, the surface epithelium, the eschar thickness and the bed's capillary
 * mean: each column's epithelium reads its whole depth) on a box that is one
 * of a stack in z: the solver calls fn with every box of the stack at once
 * (collectively, in the same order) on per-column float arrays of the box +
 * halo (n = nx * ny): SS_HEAL_COL_MAX: the element-wise maximum over the
 * stack, in place; FROM_ABOVE: replace buf with what the box above sent by
 * TO_BELOW (the top box: leave it); TO_BELOW: send buf to the box below (the
 * bottom box: nothing); FROM_BOTTOM: replace buf with the bottom box's. The
 * running sums are thus continued box by box, top down, in the order of one
 * process: the values are bit-identical. Calling it finds the surface cells
 * over the stack (collective). */
enum { SS_HEAL_COL_MAX, SS_HEAL_COL_FROM_ABOVE, SS_HEAL_COL_TO_BELOW, SS_HEAL_COL_FROM_BOTTOM };
typedef void (*ss_heal_column_fn)(void *ctx, int op, float *buf, size_t n);
void ss_heal_solver_set_columns(ss_heal_solver *s, ss_heal_column_fn fn, void *ctx);
/* The split step's convection on a box that is one of several (the MPI
 * driver, src/mpi), called collectively on every box: SS_HEAL_CONV_SPEED:
 * *speed (this box's ss_heal_rd_max_speed) becomes the largest over all
 * boxes, so every box takes the same subcycles; SS_HEAL_CONV_HALO: before
 * each donor-cell subcycle, refresh the halo of the current fields u (the
 * neighbours' values of their owned cells). */
enum { SS_HEAL_CONV_SPEED, SS_HEAL_CONV_HALO };
typedef void (*ss_heal_conv_fn)(void *ctx, int op, float *const *u, double *speed);
/* The convection sync of a split box that is one of several (see
 * ss_heal_conv_fn): phase 0 calls fn for the global largest speed and before
 * every donor-cell subcycle, so the boxes convect as one process does. */
void ss_heal_solver_set_convection(ss_heal_solver *s, ss_heal_conv_fn fn, void *ctx);
double ss_heal_solver_dt(const ss_heal_solver *s);
/* Changes the step (adaptive stepping). EXPLICIT: up to the stability limit;
 * SPLIT: up to SS_HEAL_SPLIT_LATE_MAX_DT_DAYS, for the slow phases once the
 * fast ones are over (the caller owns the accuracy: docs/heal-model.md §4). */
#define SS_HEAL_SPLIT_LATE_MAX_DT_DAYS 2.0
ss_status ss_heal_solver_set_dt(ss_heal_solver *s, double dt_days, ss_error *err);
/* Advances g->t_days by dt, g->step++. All state lives in g (fields, cell,
 * t_days, step); the solver holds only params, dt and scratch memory. */
ss_status ss_heal_step(ss_heal_solver *s, ss_heal_grid *g, ss_error *err);
void ss_heal_solver_free(ss_heal_solver *s);
/* The split step in three phases (the MPI driver, src/mpi, runs the y sweep
 * on another decomposition): 0 = first reaction half, the convection (with a
 * velocity) and the x sweep, 1 = the y sweep, 2 = the z sweep and the second
 * reaction half, then t_days += dt and step++. Phases 0, 1, 2 in turn are
 * ss_heal_step exactly. SS_ERR_INPUT for the explicit scheme or a velocity the
 * solver was not created with (phases 1 and 2 do not read it). */
ss_status ss_heal_step_phase(ss_heal_solver *s, ss_heal_grid *g, int phase, ss_error *err);
/* The explicit step in two parts (the MPI driver, src/mpi, exchanges its
 * halo meanwhile): part 1 computes every cell whose stencil does not reach
 * the faces of the grid's outer shell named in `ring` (bits 1, 2, 4, 8, 16,
 * 32: -x, +x, -y, +y, -z, +z), part 2 the rest (the cells next to those
 * faces) and then t_days += dt and step++. Between them those faces' fields
 * may be rewritten (the halo received); parts 1 and 2 in turn, with the same
 * ring, are ss_heal_step exactly. SS_ERR_INPUT for the split scheme. */
ss_status ss_heal_step_part(ss_heal_solver *s, ss_heal_grid *g, int part, int ring, ss_error *err);
/* The split scheme's frozen diffusion multipliers of slot k (one float per
 * cell of the solver's grid; set by phase 0, read by phases 1 and 2); NULL
 * for the explicit scheme or a slot out of range. */
float *ss_heal_solver_multipliers(ss_heal_solver *s, int slot);
int ss_heal_solver_nslots(const ss_heal_solver *s);

/* ---- diagnostics ---------------------------------------------------------------- */

typedef struct ss_heal_stats {
    double open_area_mm2;               /* the uncovered area: the sum over the wound's
                                           columns (initial or in omega) of 1 - e of the
                                           surface cell (e the covered fraction), x dx^2 */
    double wound_region_area_mm2;       /* columns whose surface cell is in omega */
    double initial_area_mm2;            /* columns that had a WOUND cell at the surface */
    double field_mean[SS_HEAL_NFIELDS]; /* over tissue cells (not AIR/BOUND) */
    double eschar_wound_mean;           /* mean over the initial wound columns of the
                                           column maximum of s (the scab, 0..1) */
    double scar_volume_mm3;             /* integral of rho over the tissue (mm^3 of
                                           normal-dermis-equivalent scar collagen) */
    double scar_max;                    /* largest rho of any tissue cell */
    double open_columns_mm2;            /* those columns whose e < threshold (whole
                                           columns: the closure-day map's test) */
    double elevation_mean_mm;           /* surface elevation (ss_heal_elevation_scan),
                                           mean over the initial wound columns */
    double elevation_max_mm;            /* its largest value over all columns */
} ss_heal_stats;
/* Epithelium level below which a column counts as open: 0.5. */
double ss_heal_open_threshold(void);
void ss_heal_stats_compute(const ss_heal_grid *g, ss_heal_stats *st);
/* The largest eschar a voxel of edge dx_mm at the surface can hold: the share
 * of it inside the crust layer, min(1, scab_mm / dx_mm) (1 with the scab
 * switch off). On voxels coarser than scab_mm the crust is a sub-voxel layer
 * (docs/heal-model.md [D14]); the callers divide eschar_wound_mean by it, so
 * the figure is the crust's share of its layer on every voxel size. */
double ss_heal_crust_voxel_share(const ss_heal_params *p, double dx_mm);
/* The same in parts (the MPI driver's reductions): sums of float values are
 * kept exactly (fixed-point limbs), so the result does not depend on how the
 * columns are split or in which order the parts are merged. */
#define SS_HEAL_ACC_LIMBS 12
#define SS_HEAL_ACC_ESCHAR SS_HEAL_NFIELDS        /* sum[]: the eschar column maxima */
#define SS_HEAL_ACC_DEFICIT (SS_HEAL_NFIELDS + 1) /* sum[]: 1 - e of the open-test columns */
#define SS_HEAL_ACC_ELEV (SS_HEAL_NFIELDS + 2)    /* sum[]: elevations of the wound columns */
#define SS_HEAL_ACC_SUMS (SS_HEAL_NFIELDS + 3)
typedef struct ss_heal_stats_acc {
    int64_t n_initial, n_region, n_open, n_wcol, n_tissue, n_nonfinite;
    int64_t sum[SS_HEAL_ACC_SUMS][SS_HEAL_ACC_LIMBS]; /* fields, the eschar column
                                                         maxima, the uncovered fractions */
    int64_t adds;    /* additions since the limbs were last normalised */
    double scar_max; /* largest rho */
    double elev_max; /* largest column elevation (-inf: no column yet) */
} ss_heal_stats_acc;
void ss_heal_stats_acc_init(ss_heal_stats_acc *a);
/* Adds the columns x0 <= x < x1, y0 <= y < y1 of g (grid indices, all z). */
void ss_heal_stats_acc_add(ss_heal_stats_acc *a, const ss_heal_grid *g, int x0, int x1, int y0,
                           int y1);
/* a += b (limb by limb; both normalised after). */
void ss_heal_stats_acc_merge(ss_heal_stats_acc *a, const ss_heal_stats_acc *b);
/* The same on a box that is one of a stack in z (src/mpi): g is the box
 * with a one-cell halo, zoff the whole-grid level of its z = 0, gz the whole
 * grid's depth. Adds the tissue cells of the owned levels (z = 1 .. nz - 2)
 * of columns [x0, x1) x [y0, y1); the column figures (surface cell, eschar
 * maximum below it) continue the scan of the box above in cols (one per
 * column of the range, row-major, zeroed for the top box) and are added by
 * the bottom box (bottom = 1). Over the stack: ss_heal_stats_acc_add's sums. */
typedef struct ss_heal_col_state {
    float smax, esurf;              /* eschar maximum; e of the surface cell */
    uint8_t phase, initial, region; /* phase 0 above the surface, 1 in the tissue run, 2 past it */
    float elev;                     /* the column's elevation so far (ss_heal_elevation_scan) */
} ss_heal_col_state;
void ss_heal_stats_acc_add_stack(ss_heal_stats_acc *a, const ss_heal_grid *g, int x0, int x1,
                                 int y0, int y1, int zoff, int gz, ss_heal_col_state *cols,
                                 int bottom);
/* Brings every limb into [0, 2^32) (the top one keeps the sign): done by add
 * and merge; integer sums of normalised parts stay exact. */
void ss_heal_stats_acc_normalise(ss_heal_stats_acc *a);
void ss_heal_stats_acc_finish(const ss_heal_stats_acc *a, double dx_mm, ss_heal_stats *st);
/* Surface elevation (mm) where collagen exceeds the dermis it replaced, or
 * falls short of it (docs/heal-model.md §2 [D12]): each tissue cell adds
 * SS_HEAL_COLLAGEN_VOLUME x dx x (rho - ref), ref = 1 in a WOUND cell (its
 * dermis was removed, the scar has to replace its collagen) and 0 elsewhere
 * (a keloid's collagen in intact dermis comes on top of it). Collagen is ~0.3
 * of the dermis' volume (70-80 % of a dry weight that is ~1/3 of the wet
 * weight); scar tissue around excess collagen is taken to hold it at that
 * fraction. ss_heal_elevation_scan adds, for every column of g (elev: nx*ny,
 * index y*nx + x, continued from its values), the tissue cells of levels
 * z1 - 1 down to z0, top down in float (a z stack of boxes continues the
 * sums box by box in the same order: bit-identical to one grid). */
#define SS_HEAL_COLLAGEN_VOLUME 0.3
static inline float ss_heal_elevation_term(float rho, uint8_t cell, float k) {
    return k * (rho - (cell == SS_CELL_WOUND ? 1.0f : 0.0f));
}
void ss_heal_elevation_scan(const ss_heal_grid *g, int z0, int z1, float *elev);
/* omega for one cell (1 = wound region) under params p. */
int ss_heal_in_region(const ss_heal_grid *g, const ss_heal_params *p, size_t idx);

/* ---- clinical course of a square wound ---------------------------------------------
 * The figures docs/heal-model.md calibrates against, measured on a centred
 * square wound in a block (skin surface at 3 mm, one air layer, block 4 mm
 * high), split scheme. Used by the tests, bench_heal_course and the
 * convergence and sensitivity tables (bench/heal_tables.sh). */
typedef struct ss_heal_course_opts {
    double block_mm;       /* block side (x = y) */
    double wound_mm;       /* wound side */
    double depth_mm;       /* wound depth */
    double dx_mm;          /* voxel */
    double days;           /* simulated time */
    double dt_days;        /* split step; 0 = SS_HEAL_SPLIT_DEFAULT_DT_DAYS */
    double late_dt_days;   /* > dt: step used once the wound is closed and the scab
                              gone (the slow remodelling phase); 0 = dt throughout */
    double deep_check_day; /* day of the deep-epithelium check; < 0 = none */
    double keloid_thr;     /* scar level of the keloid extent; 0 = none */
    double keloid_day[2];  /* days of two more keloid-extent readings (0 = none) */
} ss_heal_course_opts;
typedef struct ss_heal_course {
    double t50, t95;      /* days to 50 % / 95 % closure (-1 = not reached) */
    double scab_day;      /* first day the wound's mean eschar exceeds 0.5 */
    double scab_gone_day; /* first day after t95 it is below 0.05 (-1 = not) */
    double scar_peak_mm3; /* peak scar volume (integral of rho) and its day */
    double scar_peak_day;
    double scar_end_mm3;      /* at the end */
    double scar_max_peak;     /* peak of the largest rho */
    double half_life_days;    /* remodelling: ln 2 over the decay rate of the scar collagen
                                 above rho_mature (the part remodelling resorbs) over
                                 the last quarter of the run (after the peak; -1 = not
                                 decaying, 0 = no peak yet) */
    double deep_e_fraction;   /* tissue voxels deeper than 0.5 mm below the skin surface
                                 with e > 0.5, fraction, at deep_check_day */
    double keloid_beyond_mm;  /* mean advance beyond the original margin of the scar above
                                 keloid_thr (column maximum), along the four mid-edge
                                 lines, at the end */
    double keloid_beyond_t95; /* the same at t95 (growth after closure) */
    double keloid_area_mm2;   /* columns whose scar exceeds keloid_thr, at the end */
    double region_area_mm2;   /* wound region (omega) at the surface, at the end */
    int bounds_ok;            /* final fields non-negative, finite; s, e, p <= 1 */
    long steps;
    double wall_s;
    double keloid_beyond_day[2]; /* keloid extent at opts.keloid_day[k] (first step at or after) */
    double keloid_beyond_max;    /* its largest value over the run (regression if > the end) */
    double scar_max_end;         /* largest rho at the end (regression if below the peak) */
    double elev_max_mm;          /* largest surface elevation over the run and its day */
    double elev_max_day;
    double elev_end_max_mm; /* largest and wound-mean surface elevation at the end */
    double elev_end_mean_mm;
    double scar_deep_max; /* largest rho at the end of tissue wholly below keloid_mm (its
                             voxel's top deeper than keloid_mm below the surface) */
} ss_heal_course;
ss_status ss_heal_course_run(const ss_heal_params *p, const ss_heal_course_opts *o,
                             ss_heal_course *c, ss_error *err);

/* ---- generic reaction-diffusion-convection core ---------------------------------
 * u_f,t + div(u_f v) = m_f(u) D_f lap u_f + R_f(u) on a regular grid of cubic
 * cells of edge h. Every cell has a class (< SS_HEAL_RD_MAXCLASS); a class is a
 * wall (no flux, never updated, shared by all fields) or active; per field an
 * active class may be fixed (Dirichlet: value kept, still a neighbour). The
 * outermost voxel shell must be walls. The healing model is one user of it
 * (classes = ss_heal_cell), the Fisher-KPP tests another. */

#define SS_HEAL_RD_MAXF 8
#define SS_HEAL_RD_MAXCLASS 8
#define SS_HEAL_RD_MAXSLOT 4

/* One x-run of cells handed to the reaction function. The reaction of field
 * f is written in production/loss form R_f = prod_f - loss_f * u_f with
 * prod_f >= 0, loss_f >= 0 (this keeps both schemes non-negative). For i < n
 * it must write prod[f][i], loss[f][i] (per day) for every field and m[k][i]
 * (>= 0, the diffusion multiplier) for every slot k < nslots. u[f][i] are the
 * current values; cls[i] the classes. */
typedef struct ss_heal_rd_row {
    int n, x0, y, z;
    const uint8_t *cls;
    const float *u[SS_HEAL_RD_MAXF];
    float *prod[SS_HEAL_RD_MAXF];
    float *loss[SS_HEAL_RD_MAXF];
    float *m[SS_HEAL_RD_MAXSLOT];
} ss_heal_rd_row;
typedef void (*ss_heal_reaction_fn)(void *ctx, const ss_heal_rd_row *row);
/* Called with the current fields before every evaluation pass of the
 * reaction function (explicit: once per step; split: before each half
 * reaction pass), so a model can gather non-local inputs (column values,
 * depth averages) into its context; the reaction must then read only those
 * and the row it is given. NULL = nothing to gather. */
typedef void (*ss_heal_prepare_fn)(void *ctx, float *const *u);

typedef struct ss_heal_rd_system {
    int nx, ny, nz;
    double h_mm;
    int nfields;
    float *u[SS_HEAL_RD_MAXF];                           /* nx*ny*nz each */
    const uint8_t *cls;                                  /* class per cell; NULL = all class 0 */
    uint8_t wall[SS_HEAL_RD_MAXCLASS];                   /* 1 = wall */
    uint8_t fixed[SS_HEAL_RD_MAXF][SS_HEAL_RD_MAXCLASS]; /* 1 = Dirichlet */
    double D[SS_HEAL_RD_MAXF];                           /* mm^2/day; 0 = no diffusion */
    int mslot[SS_HEAL_RD_MAXF];                          /* multiplier slot, -1 = 1 */
    int nslots;
    float lo[SS_HEAL_RD_MAXF], hi[SS_HEAL_RD_MAXF]; /* admissible range (clamp) */
    const float *velocity[3];                       /* NULL = zero; mm/day */
    ss_heal_reaction_fn react;                      /* NULL = no reaction */
    ss_heal_prepare_fn prepare;                     /* NULL = none */
    void *ctx;
    uint8_t lateral[SS_HEAL_RD_MAXF]; /* 1 = field diffuses along x and y only */
    double mmax;                      /* bound on every multiplier m (for the stability limit) */
    double rate_max;                  /* bound on every loss_f (1/day), explicit positivity limit */
    /* A sub-box of a larger grid (the MPI driver, src/mpi): gdim are the whole
     * grid's dimensions and goff the whole-grid index of this grid's cell
     * (0,0,0); all 0 = this grid is the whole problem. The outermost shell of
     * the whole grid is the wall shell; this grid's own outermost shell is a
     * halo (read as neighbours, never updated). */
    int goff[3], gdim[3];
    /* 0: the multiplier of slot k scales the cell's Laplacian, m_i D lap u
     * (the seed's form). f + 1: slot k's fields diffuse through faces of
     * conductance min(m_i, m_j) of the two cells (conservative: a layer with
     * m = 0 insulates instead of acting as a zero-valued sink); the reaction
     * must then write m = clamp(1 - u_f, 0, 1) into the slot, which the
     * explicit scheme recomputes from field f at the neighbours. */
    uint8_t mface[SS_HEAL_RD_MAXSLOT];
    /* > 0: a cell whose u_f of a face slot exceeds it has m = 0 (its faces
     * closed: a voxel that is mostly crust, [D9]); the reaction must write
     * the same into the slot. 0: m = clamp(1 - u_f, 0, 1) everywhere. */
    float mface_closed;
    /* The tissue volume fraction of each cell for the fields of a face slot
     * (a voxel that holds a sub-voxel crust over tissue, [D14]); NULL = 1
     * everywhere (the same arithmetic as before, bit for bit). Such a cell's
     * values are per tissue volume and its tissue lies in the bottom v of the
     * voxel, over a whole cell: its lateral faces conduct min(v_i, v_j) (the
     * tissue's share of the face), the face below it 2 / (1 + v) (the
     * distance from its tissue's centre, v dx/2 + dx/2, instead of dx), and
     * its update is divided by v (conserved: the sum of v u). */
    const float *vfrac;
    /* a sub-box's convection sync (split scheme); NULL = this grid is the whole problem */
    ss_heal_conv_fn conv;
    void *conv_ctx;
} ss_heal_rd_system;

typedef struct ss_heal_rd_work ss_heal_rd_work;
ss_heal_rd_work *ss_heal_rd_work_create(const ss_heal_rd_system *sys, ss_error *err);
void ss_heal_rd_work_free(ss_heal_rd_work *w);
/* Explicit limit in days: 1 / (6 D_max mmax / h^2 + rate_max + max|v| / h). */
double ss_heal_rd_explicit_dt(const ss_heal_rd_system *sys);
/* Largest |vx|+|vy|+|vz| over the grid (0 without velocity), mm/day. */
double ss_heal_rd_max_speed(const ss_heal_rd_system *sys);
/* One forward-Euler step: central-difference diffusion, donor-cell convection
 * (conservative), reaction; clamp to [lo, hi]. The new values are written to
 * the work buffers, which are then exchanged with sys->u (both malloc'd by
 * their creators; after the step sys->u[f] points at the new values). */
void ss_heal_rd_step_explicit(ss_heal_rd_system *sys, ss_heal_rd_work *w, double dt);
/* One split step, in place: reaction (nsub substeps per cell of the
 * positivity-preserving u <- (u + h prod) / (1 + h loss), clamped),
 * convection (CFL-subcycled donor cell), then implicit-Euler LOD diffusion
 * along x, y, z by Thomas line solves with multipliers frozen at the
 * last reaction substep. Unconditionally stable and positivity preserving in diffusion. */
void ss_heal_rd_step_split(ss_heal_rd_system *sys, ss_heal_rd_work *w, double dt, int nsub);

#ifdef __cplusplus
}
#endif
#endif
