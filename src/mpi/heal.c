/* The healing solver of seed 001 §4.1 on MPI (docs/scaling.md). The grid is
 * cut by a Cartesian process grid (MPI_Cart_create over x, y and z).
 * Explicit scheme: MPI_Dims_create splits x and y (z too on request,
 * SKINSIM_MPI_DIMS); every rank steps its box plus a one-cell halo with the
 * library's own kernel in its sub-box form (ss_heal_solver_create_sub): it
 * posts the exchange of the faces of all eight fields with its (up to six)
 * neighbours, computes the interior of its box meanwhile, then waits and
 * computes the boundary ring (ss_heal_step_part). With z split, the column
 * values the epithelium reads (its whole depth) run down each stack of boxes
 * in one process's order (ss_heal_solver_set_columns over an MPI_Cart_sub
 * communicator), as do the column statistics and the closure days. Split
 * scheme: the boxes are y slabs (x lines and z columns whole) and the y sweep
 * runs on x slabs, reached by two MPI_Alltoallv transposes per step, so every
 * Thomas line solve runs whole, as in one process (no halo needed). With a
 * velocity (the mechanics') phase 0 convects on the y slabs
 * (ss_heal_solver_set_convection, split_conv): the subcycle count from the
 * largest speed of any slab (a max-reduction), and before each donor-cell
 * subcycle the one-row y faces of the current fields are exchanged (x lines
 * and z columns are whole on a slab), so every cell reads what one process
 * reads.
 *
 * No rank holds the whole grid. Rank 0 holds the run object
 * (skinsim/heal_run.h) created with config.distributed: it validates every
 * input with the single-process code but allocates no grid; the wound goes
 * to every rank as per-column level ranges (or the mesh, voxelised per box)
 * and every rank builds its own box + halo (ss_heal_grid_init_box), the
 * mesh's checks being made on the reduced counts. Rank 0 drives the others
 * through a command channel (one broadcast per step, area row, sync, surface
 * map, snapshot or checkpoint). Its hooks replace the run's step (all ranks
 * step; an adaptive run's rejected step is undone on all ranks, its largest
 * change is a max-reduction), its statistics (exact fixed-point partial sums
 * reduced with integer additions, ss_heal_stats_acc), its surface maps (a
 * top-down scan down each stack, the bottom boxes' columns gathered: nx*ny
 * floats), its snapshots (every rank writes its box as a .vti piece with the
 * closure days of its columns, straight from the box; rank 0 the .pvti) and
 * its checkpoints (every rank writes its piece, rank 0 the header once all
 * agree; a resume reads each rank's box from the pieces of any split). The
 * kernels compute every cell from the same neighbours in the same arithmetic
 * as one process, so fields, area.csv, the pieces and checkpoints are
 * bit-identical to one process for any rank count and process grid.
 * The contraction mechanics (--mechanics) run on rank 0, unchanged, on a grid
 * of the whole block's size (ss_heal_run_mech_attach): each step the boxes
 * send it the five fields the mechanics read, inside the tissue's bounding
 * box, and it sends every box + halo the velocity they wrote (mech_in /
 * mech_out hooks); snapshots scatter the displacement of the owned cells into
 * the pieces. A run on a skin mesh (--mesh) builds its patch's grid on rank 0
 * once and scatters it; its surface outputs read each column's top tissue
 * cell from the box that owns it (2D). Gave up: the column chain of a z stack
 * is sequential (Pz - 1 hops per step); the mechanics are serial on rank 0
 * (its memory bounds them; docs/scaling.md "Mechanics on MPI"); a
 * whole-grid checkpoint (of a single process) or a skin patch is loaded on
 * rank 0 once. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <mpi.h>
#include <sys/resource.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/dist.h"
#include "skinsim/mech.h"

enum {
    CMD_STEP = 1,
    CMD_UNDO,
    CMD_CLOSURE,
    CMD_STATS,
    CMD_SYNC,
    CMD_PIECES,
    CMD_SURFACE,
    CMD_CKPT,
    CMD_MECH_IN,
    CMD_MECH_OUT,
    CMD_COLUMNS,
    CMD_END
};
enum { FACE_XM, FACE_XP, FACE_YM, FACE_YP, FACE_ZM, FACE_ZP, NFACES };

/* What rank 0 tells every rank about the run before the boxes are sent. */
typedef struct setup {
    int G[3];
    int dims[3];
    int scheme;
    double dx_mm, skin_top_mm, t_days, dt, epidermis_mm;
    unsigned long long step;
    ss_heal_params p;
    int fresh;             /* 1: every rank builds its box from the wound; 0: rank 0 scatters the
                              checkpoint's grid */
    int wound;             /* fresh: WOUND_COLUMNS or WOUND_MESH */
    long long pieces_step; /* resumed from a checkpoint in pieces: its step (every rank
                              reads its box), else -1 */
    int mesh_nv, mesh_nt;
    int mech;  /* --mechanics: they run on rank 0 (mech_setup) */
    int shell; /* --mesh: the surface outputs read the columns' top cells */
} setup;
enum { WOUND_COLUMNS = 1, WOUND_MESH };

struct ss_dist_heal {
    MPI_Comm cart;
    int rank, size, dims[3], coords[3];
    int nbr[NFACES];
    setup su;
    int lo[3], n[3];           /* owned box (whole grid indices) */
    int hz;                    /* 1: z is split (dims[2] > 1), the box has a halo in z too */
    MPI_Comm zcomm;            /* the stack of boxes in z over this box's columns */
    int zabove, zbelow, zroot; /* in zcomm: the boxes above and below, the bottom box */
    float *colbuf;             /* the column scans down the stack */
    double t_col;              /* the column exchange's time (in the kernel's) */
    double t_conv;             /* split: the convection's halo exchanges (in the kernel's) */
    ss_heal_grid *g;           /* box + halo (x, y; z when split) */
    ss_heal_solver *s;
    float *sbuf[NFACES], *rbuf[NFACES];
    int fcount[NFACES]; /* floats per face message */
    /* split scheme: the boxes above are y slabs (dims 1 x P x 1); the y sweep
     * runs on x slabs (gB, sB), reached by two transposes per step */
    int split, nslots;
    ss_heal_grid *gB;
    ss_heal_solver *sB;
    float *tsend, *trecv;
    int *scnt, *sdsp, *rcnt, *rdsp;
    double tbytes;                  /* transpose bytes this rank sends per step */
    ss_heal_run *run;               /* rank 0 */
    const char *pdir;               /* rank 0: the fields folder of the snapshot being written */
    double next_dt;                 /* rank 0: the step being broadcast */
    float *backup[SS_HEAL_NFIELDS]; /* adaptive steps: the fields before the step */
    double saved_t;
    double *closed;       /* closure day per column of the box + halo (heal_io.h) */
    double *closed_root;  /* rank 0: the run's closure days, filled by the sync */
    double *rss_mb;       /* rank 0, after end: every rank's peak resident memory, MB */
    const int32_t *wcols; /* set-up of a fresh run: the wound's column ranges (rank 0: the
                             run's), or */
    ss_tri_mesh mesh;     /* its closed mesh (a copy on every rank) */
    int own_wcols;
    char ckdir[4096]; /* a resume from pieces: the run folder */
    uint64_t saved_step;
    int dirty;   /* rank 0: the run's whole grid is behind the boxes */
    int overlap; /* explicit: the halo exchange runs during the interior kernel */
    double t_compute, t_halo, t_stats, t_gather;
    /* --mechanics: rank 0's grid of what they read (the run owns it), the
     * box they read and write (whole-grid lo x y z, hi x y z), the
     * displacement of the box + halo for the snapshot pieces */
    ss_heal_grid *mg;
    int bb[6];
    float *disp[3];
    double t_mech, mech_bytes;
    int32_t *top; /* --mesh: each column's top tissue level (whole grid, nx*ny) */
    long long steps;
    ss_dist_heal_timing tmax; /* rank 0, after end */
};

/* Block split of n cells over p parts: part i starts at i n / p. */
static int part_lo(int n, int p, int i) { return (int)((long long)n * i / p); }

static void box_of(const ss_dist_heal *d, const int coords[3], int lo[3], int n[3]) {
    for (int a = 0; a < 3; a++) {
        lo[a] = part_lo(d->su.G[a], d->su.dims[a], coords[a]);
        n[a] = part_lo(d->su.G[a], d->su.dims[a], coords[a] + 1) - lo[a];
    }
}

/* ---- the box: scatter from and gather to rank 0's whole grid ---------------------- */

/* The box + halo of a rank with origin lo and size n, cut from the whole grid
 * G (cells outside it are BOUND with zero fields): cells then 8 field planes.
 * hz: the box has a halo in z too (z split; else it spans the grid in z). */
static void pack_box(const ss_heal_grid *G, const int lo[3], const int n[3], int hz, uint8_t *cells,
                     float *fields) {
    const int nxl = n[0] + 2, nyl = n[1] + 2, nzl = n[2] + 2 * hz;
    const size_t nl = (size_t)nxl * nyl * nzl;
    for (int z = 0; z < nzl; z++)
        for (int y = 0; y < nyl; y++)
            for (int x = 0; x < nxl; x++) {
                const int X = lo[0] - 1 + x, Y = lo[1] - 1 + y, Z = lo[2] - hz + z;
                const size_t c = ((size_t)z * nyl + y) * nxl + x;
                if (X < 0 || Y < 0 || Z < 0 || X >= G->nx || Y >= G->ny || Z >= G->nz) {
                    cells[c] = SS_CELL_BOUND;
                    for (int f = 0; f < SS_HEAL_NFIELDS; f++) fields[f * nl + c] = 0.0f;
                    continue;
                }
                const size_t gc = ss_heal_idx(G, X, Y, Z);
                cells[c] = G->cell[gc];
                for (int f = 0; f < SS_HEAL_NFIELDS; f++) fields[f * nl + c] = G->field[f][gc];
            }
}

/* ---- halo exchange -------------------------------------------------------------- */

/* Face planes: x faces are (y, z) planes at x = 1 / nxl-2 (sent) and x = 0 /
 * nxl-1 (received); y faces are (x, z) rows at y = 1 / nyl-2 and 0 / nyl-1;
 * z faces (z split) are (x, y) planes at z = 1 / nzl-2 and 0 / nzl-1. */
static void face_io(ss_heal_grid *g, int face, int recv, float *buf) {
    const int nxl = g->nx, nyl = g->ny, nz = g->nz;
    size_t k = 0;
    if (face == FACE_XM || face == FACE_XP) {
        int x = face == FACE_XM ? (recv ? 0 : 1) : (recv ? nxl - 1 : nxl - 2);
        for (int f = 0; f < SS_HEAL_NFIELDS; f++)
            for (int z = 0; z < nz; z++)
                for (int y = 0; y < nyl; y++) {
                    float *p = g->field[f] + ss_heal_idx(g, x, y, z);
                    if (recv)
                        *p = buf[k++];
                    else
                        buf[k++] = *p;
                }
    } else if (face == FACE_ZM || face == FACE_ZP) {
        const int z = face == FACE_ZM ? (recv ? 0 : 1) : (recv ? nz - 1 : nz - 2);
        const size_t plane = (size_t)nxl * nyl;
        for (int f = 0; f < SS_HEAL_NFIELDS; f++) {
            float *p = g->field[f] + ss_heal_idx(g, 0, 0, z);
            if (recv)
                memcpy(p, buf + k, plane * sizeof(float));
            else
                memcpy(buf + k, p, plane * sizeof(float));
            k += plane;
        }
    } else {
        int y = face == FACE_YM ? (recv ? 0 : 1) : (recv ? nyl - 1 : nyl - 2);
        for (int f = 0; f < SS_HEAL_NFIELDS; f++)
            for (int z = 0; z < nz; z++) {
                float *p = g->field[f] + ss_heal_idx(g, 0, y, z);
                if (recv)
                    memcpy(p, buf + k, (size_t)nxl * sizeof(float));
                else
                    memcpy(buf + k, p, (size_t)nxl * sizeof(float));
                k += (size_t)nxl;
            }
    }
}

/* Posts the exchange of the faces in `mask` (bit 1 << face) of the current
 * fields: receives into rbuf, sends packed copies (the fields may be read
 * meanwhile, never the halo). Returns the request count. */
static int halo_post(ss_dist_heal *d, MPI_Request rq[2 * NFACES], int mask) {
    int nr = 0;
    /* a face's opposite: what the neighbour on the -x side sends us is its +x face */
    static const int opposite[NFACES] = {FACE_XP, FACE_XM, FACE_YP, FACE_YM, FACE_ZP, FACE_ZM};
    for (int f = 0; f < NFACES; f++) {
        if (d->nbr[f] == MPI_PROC_NULL || !(mask & (1 << f))) continue;
        MPI_Irecv(d->rbuf[f], d->fcount[f], MPI_FLOAT, d->nbr[f], opposite[f], d->cart, &rq[nr++]);
    }
    for (int f = 0; f < NFACES; f++) {
        if (d->nbr[f] == MPI_PROC_NULL || !(mask & (1 << f))) continue;
        face_io(d->g, f, 0, d->sbuf[f]);
        MPI_Isend(d->sbuf[f], d->fcount[f], MPI_FLOAT, d->nbr[f], f, d->cart, &rq[nr++]);
    }
    return nr;
}

/* Waits for the exchange and writes the received faces into the halo. */
static void halo_finish(ss_dist_heal *d, MPI_Request rq[2 * NFACES], int nr, int mask) {
    MPI_Waitall(nr, rq, MPI_STATUSES_IGNORE);
    for (int f = 0; f < NFACES; f++)
        if (d->nbr[f] != MPI_PROC_NULL && (mask & (1 << f))) face_io(d->g, f, 1, d->rbuf[f]);
}

/* ---- the split scheme's transposes ---------------------------------------------- */

/* x slab of rank j (the y sweep's decomposition) */
static void xslab(const ss_dist_heal *d, int j, int *lo, int *n) {
    *lo = part_lo(d->su.G[0], d->size, j);
    *n = part_lo(d->su.G[0], d->size, j + 1) - *lo;
}
static void yslab(const ss_dist_heal *d, int j, int *lo, int *n) {
    *lo = part_lo(d->su.G[1], d->size, j);
    *n = part_lo(d->su.G[1], d->size, j + 1) - *lo;
}

/* the quantities moved: fields, then (A -> B only) the frozen multipliers */
static float *quantity(ss_heal_grid *g, ss_heal_solver *s, int q) {
    return q < SS_HEAL_NFIELDS ? g->field[q] : ss_heal_solver_multipliers(s, q - SS_HEAL_NFIELDS);
}

/* The box that side A (y slab: all x, owned y) or side B (x slab: owned x,
 * all y) exchanges with rank j: on A the x range of j's x slab and all local
 * rows, on B all local x and the rows of j's y slab; local coordinates (the
 * halo shifts them by one). */
typedef struct {
    int x0, xn, y0, yn;
} slab_box;

static slab_box side_box(const ss_dist_heal *d, int side_b, int j) {
    slab_box b;
    if (side_b) {
        xslab(d, d->rank, &b.x0, &b.xn);
        yslab(d, j, &b.y0, &b.yn);
        b.x0 = 1;
        b.y0 += 1;
    } else {
        xslab(d, j, &b.x0, &b.xn);
        yslab(d, d->rank, &b.y0, &b.yn);
        b.x0 += 1;
        b.y0 = 1;
    }
    return b;
}

/* Moves nq quantities from one side to the other in one MPI_Alltoallv: each
 * rank packs, per partner, the x rows of the box the partner owns on the
 * other side, and unpacks the partner's rows into its own box. A -> B moves
 * every field and the frozen multipliers (the y sweep needs them); B -> A
 * the fields after the y sweep. */
static void transpose(ss_dist_heal *d, int from_b, int nq) {
    ss_heal_grid *gs = from_b ? d->gB : d->g, *gd = from_b ? d->g : d->gB;
    ss_heal_solver *ss = from_b ? d->sB : d->s, *sd = from_b ? d->s : d->sB;
    const int nz = d->su.G[2];
    size_t k = 0;
    for (int j = 0; j < d->size; j++) {
        slab_box b = side_box(d, from_b, j);
        d->sdsp[j] = (int)k;
        for (int q = 0; q < nq; q++) {
            const float *u = quantity(gs, ss, q);
            for (int z = 0; z < nz; z++)
                for (int y = 0; y < b.yn; y++) {
                    memcpy(d->tsend + k, u + ss_heal_idx(gs, b.x0, b.y0 + y, z),
                           (size_t)b.xn * sizeof(float));
                    k += (size_t)b.xn;
                }
        }
        d->scnt[j] = (int)k - d->sdsp[j];
    }
    k = 0;
    for (int j = 0; j < d->size; j++) {
        slab_box b = side_box(d, !from_b, j);
        d->rdsp[j] = (int)k;
        d->rcnt[j] = nq * nz * b.yn * b.xn;
        k += (size_t)d->rcnt[j];
    }
    MPI_Alltoallv(d->tsend, d->scnt, d->sdsp, MPI_FLOAT, d->trecv, d->rcnt, d->rdsp, MPI_FLOAT,
                  d->cart);
    k = 0;
    for (int j = 0; j < d->size; j++) {
        slab_box b = side_box(d, !from_b, j);
        for (int q = 0; q < nq; q++) {
            float *u = quantity(gd, sd, q);
            for (int z = 0; z < nz; z++)
                for (int y = 0; y < b.yn; y++) {
                    memcpy(u + ss_heal_idx(gd, b.x0, b.y0 + y, z), d->trecv + k,
                           (size_t)b.xn * sizeof(float));
                    k += (size_t)b.xn;
                }
        }
    }
}

/* The split scheme's convection (ss_heal_solver_set_convection) on the y
 * slabs: the subcycles from the largest speed of any slab, and before each
 * donor-cell subcycle the y faces of the current fields (the one-cell halo
 * the donor cell reads across a slab boundary; x lines and z columns are
 * whole on a y slab). */
static void split_conv(void *ctx, int op, float *const *u, double *speed) {
    ss_dist_heal *d = ctx;
    const double t0 = MPI_Wtime();
    if (op == SS_HEAL_CONV_SPEED) {
        double m = *speed;
        MPI_Allreduce(&m, speed, 1, MPI_DOUBLE, MPI_MAX, d->cart);
    } else {
        /* the step swaps the fields with its buffers: the halo goes to the current ones */
        for (int f = 0; f < SS_HEAL_NFIELDS; f++) d->g->field[f] = u[f];
        const int yf = 1 << FACE_YM | 1 << FACE_YP;
        MPI_Request rq[2 * NFACES];
        halo_finish(d, rq, halo_post(d, rq, yf), yf);
    }
    d->t_conv += MPI_Wtime() - t0;
}

/* One split step: x sweep on the y slabs, y sweep on the x slabs, z sweep back
 * on the y slabs (columns and x lines are whole on a y slab, y lines on an x
 * slab: every line is solved whole, as in one process). With the mechanics'
 * velocity, phase 0 convects on the y slabs first (split_conv). */
static ss_status split_step(ss_dist_heal *d, ss_error *err) {
    double t0 = MPI_Wtime(), c0 = d->t_conv;
    ss_status st = ss_heal_step_phase(d->s, d->g, 0, err);
    double t1 = MPI_Wtime(), tc = d->t_conv - c0;
    transpose(d, 0, SS_HEAL_NFIELDS + d->nslots);
    double t2 = MPI_Wtime();
    if (!st) st = ss_heal_step_phase(d->sB, d->gB, 1, err);
    double t3 = MPI_Wtime();
    transpose(d, 1, SS_HEAL_NFIELDS);
    double t4 = MPI_Wtime();
    if (!st) st = ss_heal_step_phase(d->s, d->g, 2, err);
    double t5 = MPI_Wtime();
    d->t_compute += (t1 - t0 - tc) + (t3 - t2) + (t5 - t4);
    d->t_halo += (t2 - t1) + (t4 - t3) + tc;
    d->steps++;
    return st;
}

/* ---- the commands ------------------------------------------------------------- */

/* One explicit step. The halo holds the neighbours' faces of the fields
 * before the step only once the exchange posted at the step's start is
 * complete, so the kernel runs in two parts: the interior (no stencil reaches
 * the halo in flight) while the faces travel, then the boundary ring. The x
 * faces are waited for first: a ring in x would cut every x row (the kernel's
 * unit) into three, whose single end cells cost more than their share; the y
 * and z faces (whole rows of the ring) travel during the interior. (After the
 * step the halo is stale until the next step's exchange: nothing reads it.)
 * SKINSIM_DIST_OVERLAP=0 (benchmarks) waits for every face first. */
static ss_status plain_step(ss_dist_heal *d, ss_error *err) {
    if (d->split) return split_step(d, err);
    ss_status st;
    double t0 = MPI_Wtime();
    if (d->size == 1) {
        st = ss_heal_step(d->s, d->g, err);
        d->t_compute += MPI_Wtime() - t0;
        d->steps++;
        return st;
    }
    const int xf = 1 << FACE_XM | 1 << FACE_XP, yzf = (1 << NFACES) - 1 - xf;
    MPI_Request rqx[2 * NFACES], rq[2 * NFACES];
    const int nrx = halo_post(d, rqx, xf), nr = halo_post(d, rq, yzf);
    halo_finish(d, rqx, nrx, xf);
    if (!d->overlap) halo_finish(d, rq, nr, yzf);
    int ring = 0; /* the faces still in flight (the kernel's bits: 1 << face) */
    for (int f = FACE_YM; f < NFACES && d->overlap; f++)
        if (d->nbr[f] != MPI_PROC_NULL) ring |= 1 << f;
    double t1 = MPI_Wtime(), c0 = d->t_col;
    st = ss_heal_step_part(d->s, d->g, 1, ring, err);
    double t2 = MPI_Wtime(), tc = d->t_col - c0; /* the column exchange inside */
    if (d->overlap) halo_finish(d, rq, nr, yzf);
    double t3 = MPI_Wtime();
    if (!st) st = ss_heal_step_part(d->s, d->g, 2, ring, err);
    double t4 = MPI_Wtime();
    d->t_compute += (t2 - t1 - tc) + (t4 - t3);
    d->t_halo += (t1 - t0) + (t3 - t2) + tc;
    d->steps++;
    return st;
}

/* One step of dt (rank 0 broadcasts it: the adaptive run's multiple of its
 * step); with want_change the fields are kept first and the largest change of
 * any species in any cell is returned (a max: the same for any split). */
static ss_status do_step(ss_dist_heal *d, int want_change, double *change, ss_error *err) {
    double dt = 0;
    if (d->rank == 0) dt = d->next_dt;
    MPI_Bcast(&dt, 1, MPI_DOUBLE, 0, d->cart);
    ss_status st = SS_OK;
    if (ss_heal_solver_dt(d->s) != dt) st = ss_heal_solver_set_dt(d->s, dt, err);
    if (!st && d->sB && ss_heal_solver_dt(d->sB) != dt) st = ss_heal_solver_set_dt(d->sB, dt, err);
    if (st) MPI_Abort(d->cart, 2); /* rank 0 checked the step: cannot differ here */
    const size_t n = (size_t)d->g->nx * d->g->ny * d->g->nz;
    if (want_change) {
        for (int f = 0; f < SS_HEAL_NFIELDS; f++) {
            if (!d->backup[f] && !(d->backup[f] = malloc(n * sizeof(float)))) MPI_Abort(d->cart, 3);
            memcpy(d->backup[f], d->g->field[f], n * sizeof(float));
        }
        d->saved_t = d->g->t_days;
        d->saved_step = d->g->step;
    }
    st = plain_step(d, err);
    if (want_change) {
        double m = 0.0, mall = 0.0;
        for (int f = 0; f < SS_HEAL_NFIELDS; f++) {
            const float *x = d->g->field[f], *y = d->backup[f];
            float mf = 0.0f;
            for (size_t i = 0; i < n; i++) {
                const float c = fabsf(x[i] - y[i]);
                mf = c > mf ? c : mf;
            }
            if (mf > m) m = mf;
        }
        MPI_Allreduce(&m, &mall, 1, MPI_DOUBLE, MPI_MAX, d->cart);
        if (change) *change = mall;
    }
    return st;
}

/* ---- the stack of boxes in z (z split): column values, top down ------------------ */

/* The solver's column exchange (ss_heal_solver_set_columns) over the stack. */
static void zcol(void *ctx, int op, float *buf, size_t n) {
    ss_dist_heal *d = ctx;
    const double t0 = MPI_Wtime();
    switch (op) {
    case SS_HEAL_COL_MAX:
        MPI_Allreduce(MPI_IN_PLACE, buf, (int)n, MPI_FLOAT, MPI_MAX, d->zcomm);
        break;
    case SS_HEAL_COL_FROM_ABOVE:
        if (d->zabove != MPI_PROC_NULL)
            MPI_Recv(buf, (int)n, MPI_FLOAT, d->zabove, 30, d->zcomm, MPI_STATUS_IGNORE);
        break;
    case SS_HEAL_COL_TO_BELOW:
        if (d->zbelow != MPI_PROC_NULL) MPI_Send(buf, (int)n, MPI_FLOAT, d->zbelow, 30, d->zcomm);
        break;
    default: /* SS_HEAL_COL_FROM_BOTTOM */
        MPI_Bcast(buf, (int)n, MPI_FLOAT, d->zroot, d->zcomm);
        break;
    }
    d->t_col += MPI_Wtime() - t0;
}

/* A column scan continued from the box above and handed to the box below:
 * receives n bytes into buf (the top box: zeroes them) or sends them. */
static void zchain(ss_dist_heal *d, void *buf, size_t n, int send) {
    if (!send && d->zabove == MPI_PROC_NULL) memset(buf, 0, n);
    if (!send && d->zabove != MPI_PROC_NULL)
        MPI_Recv(buf, (int)n, MPI_BYTE, d->zabove, 31, d->zcomm, MPI_STATUS_IGNORE);
    if (send && d->zbelow != MPI_PROC_NULL)
        MPI_Send(buf, (int)n, MPI_BYTE, d->zbelow, 31, d->zcomm);
}

/* Closure days: the search for each column's two topmost tissue cells runs
 * down the stack; the bottom box keeps the days of its columns. */
static void do_closure(ss_dist_heal *d) {
    if (!d->hz) {
        ss_heal_closure_update(d->g, d->closed);
        return;
    }
    const size_t nc = (size_t)d->g->nx * d->g->ny;
    float *v = d->colbuf, *found = d->colbuf + nc;
    zchain(d, d->colbuf, 2 * nc * sizeof(float), 0);
    if (d->zabove == MPI_PROC_NULL)
        for (size_t i = 0; i < nc; i++) v[i] = -1.0f;
    ss_heal_closure_scan(d->g, d->lo[2] - 1, d->su.G[2], v, found);
    zchain(d, d->colbuf, 2 * nc * sizeof(float), 1);
    if (d->zbelow == MPI_PROC_NULL) ss_heal_closure_apply(d->g, v, d->closed);
}

static void do_undo(ss_dist_heal *d) {
    const size_t n = (size_t)d->g->nx * d->g->ny * d->g->nz;
    for (int f = 0; f < SS_HEAL_NFIELDS; f++)
        if (d->backup[f]) memcpy(d->g->field[f], d->backup[f], n * sizeof(float));
    d->g->t_days = d->saved_t;
    d->g->step = d->saved_step;
}

static void do_stats(ss_dist_heal *d, ss_heal_stats *st) {
    double t0 = MPI_Wtime();
    ss_heal_stats_acc a;
    ss_heal_stats_acc_init(&a);
    if (d->hz) { /* the column figures run down the stack, the bottom box adds them */
        const size_t n = (size_t)d->n[0] * d->n[1] * sizeof(ss_heal_col_state);
        ss_heal_col_state *cols = (ss_heal_col_state *)d->colbuf;
        zchain(d, cols, n, 0);
        ss_heal_stats_acc_add_stack(&a, d->g, 1, d->g->nx - 1, 1, d->g->ny - 1, d->lo[2] - 1,
                                    d->su.G[2], cols, d->zbelow == MPI_PROC_NULL);
        zchain(d, cols, n, 1);
    } else {
        ss_heal_stats_acc_add(&a, d->g, 1, d->g->nx - 1, 1, d->g->ny - 1);
    }
    /* integer parts: counts and limbs (normalised, so sums cannot overflow) */
    enum { NI = 6 + SS_HEAL_ACC_SUMS * SS_HEAL_ACC_LIMBS };
    int64_t in[NI], out[NI];
    int64_t cnt[6] = {a.n_initial, a.n_region, a.n_open, a.n_wcol, a.n_tissue, a.n_nonfinite};
    memcpy(in, cnt, sizeof cnt);
    memcpy(in + 6, a.sum, sizeof a.sum);
    double mx[2] = {a.scar_max, a.elev_max}, mxall[2] = {0, 0};
    MPI_Reduce(in, out, NI, MPI_INT64_T, MPI_SUM, 0, d->cart);
    MPI_Reduce(mx, mxall, 2, MPI_DOUBLE, MPI_MAX, 0, d->cart);
    if (d->rank == 0) {
        ss_heal_stats_acc t;
        ss_heal_stats_acc_init(&t);
        t.n_initial = out[0];
        t.n_region = out[1];
        t.n_open = out[2];
        t.n_wcol = out[3];
        t.n_tissue = out[4];
        t.n_nonfinite = out[5];
        memcpy(t.sum, out + 6, sizeof t.sum);
        t.scar_max = mxall[0];
        t.elev_max = mxall[1];
        ss_heal_stats_acc_finish(&t, d->su.dx_mm, st);
    }
    d->t_stats += MPI_Wtime() - t0;
}

/* The closure days of a box's own columns (kept by the bottom box of each
 * stack in z) into cb, n[0] x n[1]. */
static void own_closed(const ss_dist_heal *d, double *cb) {
    for (int y = 0; y < d->n[1]; y++)
        memcpy(cb + (size_t)y * d->n[0], d->closed + (size_t)(y + 1) * d->g->nx + 1,
               (size_t)d->n[0] * sizeof(double));
}

/* Rank 0's copy of the closure days (the run's, for its checkpoints): the
 * bottom box of every stack sends those of its columns, 1/nz of the grid. */
static ss_status do_sync(ss_dist_heal *d, ss_error *err) {
    double t0 = MPI_Wtime();
    (void)err;
    if (d->rank != 0) {
        if (d->coords[2] == 0) {
            double *cb = malloc((size_t)d->n[0] * d->n[1] * sizeof(double));
            if (!cb) MPI_Abort(d->cart, 3);
            own_closed(d, cb);
            MPI_Send(cb, d->n[0] * d->n[1], MPI_DOUBLE, 0, 101, d->cart);
            free(cb);
        }
    } else {
        const int GX = d->su.G[0];
        for (int r = 0; r < d->size; r++) {
            int coords[3], lo[3], n[3];
            MPI_Cart_coords(d->cart, r, 3, coords);
            if (coords[2] != 0) continue;
            box_of(d, coords, lo, n);
            double *cb = malloc((size_t)n[0] * n[1] * sizeof(double));
            if (!cb) MPI_Abort(d->cart, 3);
            if (r == 0)
                own_closed(d, cb);
            else
                MPI_Recv(cb, n[0] * n[1], MPI_DOUBLE, r, 101, d->cart, MPI_STATUS_IGNORE);
            for (int y = 0; y < n[1]; y++)
                memcpy(d->closed_root + (size_t)(lo[1] + y) * GX + lo[0], cb + (size_t)y * n[0],
                       (size_t)n[0] * sizeof(double));
            free(cb);
        }
        d->dirty = 0;
    }
    d->t_gather += MPI_Wtime() - t0;
    return SS_OK;
}

/* Rank 0's string (a folder) on every rank, into buf of len bytes. */
static void bcast_string(ss_dist_heal *d, const char *s, char *buf, size_t len) {
    int n = 0;
    if (d->rank == 0) n = (int)strlen(s) + 1;
    MPI_Bcast(&n, 1, MPI_INT, 0, d->cart);
    if (n > (int)len) n = (int)len;
    if (d->rank == 0) memcpy(buf, s, (size_t)n);
    MPI_Bcast(buf, n, MPI_CHAR, 0, d->cart);
    buf[len - 1] = 0;
}

/* Every rank's status agreed (the worst); on rank 0, err then names what
 * went wrong on the first rank that failed (its own message, sent over). */
static ss_status agree_err(ss_dist_heal *d, ss_status st, ss_error *err) {
    int v[2] = {(int)st, st ? d->rank : d->size}, m[2];
    MPI_Allreduce(&v[0], &m[0], 1, MPI_INT, MPI_MAX, d->cart);
    MPI_Allreduce(&v[1], &m[1], 1, MPI_INT, MPI_MIN, d->cart);
    if (!m[0]) return SS_OK;
    if (m[1] != 0 && m[1] < d->size) { /* another rank's message to rank 0 */
        if (d->rank == m[1]) MPI_Send(err, (int)sizeof *err, MPI_BYTE, 0, 104, d->cart);
        if (d->rank == 0)
            MPI_Recv(err, (int)sizeof *err, MPI_BYTE, m[1], 104, d->cart, MPI_STATUS_IGNORE);
    }
    return (ss_status)m[0];
}

/* ---- the contraction mechanics on rank 0 --------------------------------------- */

/* The box [alo, alo + an) cut to bb: its origin lo and size n; the cell count. */
static size_t clip_box(const int alo[3], const int an[3], const int bb[6], int lo[3], int n[3]) {
    size_t c = 1;
    for (int a = 0; a < 3; a++) {
        const int l = alo[a] > bb[a] ? alo[a] : bb[a];
        const int h = alo[a] + an[a] < bb[3 + a] ? alo[a] + an[a] : bb[3 + a];
        lo[a] = l;
        n[a] = h > l ? h - l : 0;
        c *= (size_t)n[a];
    }
    return c;
}

/* Copies the region (whole-grid origin lo, size n) of na float arrays of g
 * (whole-grid index of g's cell (0,0,0): org) to buf (unpack 0) or back. */
static void region_io(const ss_heal_grid *g, const int org[3], float *const *arr, int na,
                      const int lo[3], const int n[3], float *buf, int unpack) {
    size_t k = 0;
    for (int q = 0; q < na; q++)
        for (int z = 0; z < n[2]; z++)
            for (int y = 0; y < n[1]; y++) {
                float *p =
                    arr[q] + ss_heal_idx(g, lo[0] - org[0], lo[1] + y - org[1], lo[2] + z - org[2]);
                if (unpack)
                    memcpy(p, buf + k, (size_t)n[0] * sizeof(float));
                else
                    memcpy(buf + k, p, (size_t)n[0] * sizeof(float));
                k += (size_t)n[0];
            }
}

static void cells_io(const ss_heal_grid *g, const int org[3], const int lo[3], const int n[3],
                     uint8_t *buf, int unpack) {
    size_t k = 0;
    for (int z = 0; z < n[2]; z++)
        for (int y = 0; y < n[1]; y++) {
            uint8_t *p =
                g->cell + ss_heal_idx(g, lo[0] - org[0], lo[1] + y - org[1], lo[2] + z - org[2]);
            if (unpack)
                memcpy(p, buf + k, (size_t)n[0]);
            else
                memcpy(buf + k, p, (size_t)n[0]);
            k += (size_t)n[0];
        }
}

/* The fields the mechanics read (mech.c: at tissue cells only) */
static const int mech_fields[] = {SS_HEAL_SCAR, SS_HEAL_FIBROBLAST, SS_HEAL_EPITHELIUM,
                                  SS_HEAL_PLASMA, SS_HEAL_MDGF};
enum { NMF = (int)(sizeof mech_fields / sizeof mech_fields[0]) };

static void arrays_of(ss_heal_grid *g, int vel, float **a) {
    for (int i = 0; i < (vel ? 3 : NMF); i++)
        a[i] = vel ? g->velocity[i] : g->field[mech_fields[i]];
}

/* Rank 0's mechanics grid gets, inside bb, the owned cells of every box:
 * the fields the mechanics read (vel 0) or the velocity (vel 1), and with
 * cells the cell states. Returns the bytes rank 0 received. */
static double mech_gather(ss_dist_heal *d, int vel, int cells) {
    const double t0 = MPI_Wtime();
    const int na = vel ? 3 : NMF;
    const int org[3] = {d->lo[0] - 1, d->lo[1] - 1, d->lo[2] - d->hz}, zero[3] = {0, 0, 0};
    float *a[NMF];
    double bytes = 0;
    int lo[3], n[3];
    if (d->rank != 0) {
        const size_t c = clip_box(d->lo, d->n, d->bb, lo, n);
        if (c) {
            float *buf = malloc(c * (size_t)na * sizeof(float) + c);
            if (!buf) MPI_Abort(d->cart, 3);
            arrays_of(d->g, vel, a);
            region_io(d->g, org, a, na, lo, n, buf, 0);
            if (cells) cells_io(d->g, org, lo, n, (uint8_t *)(buf + c * (size_t)na), 0);
            MPI_Send(buf, (int)(c * (size_t)na * sizeof(float) + (cells ? c : 0)), MPI_BYTE, 0, 40,
                     d->cart);
            free(buf);
        }
    } else {
        for (int r = 0; r < d->size; r++) {
            int coords[3], blo[3], bn[3];
            MPI_Cart_coords(d->cart, r, 3, coords);
            box_of(d, coords, blo, bn);
            const size_t c = clip_box(blo, bn, d->bb, lo, n);
            if (!c) continue;
            float *buf = malloc(c * (size_t)na * sizeof(float) + c);
            if (!buf) MPI_Abort(d->cart, 3);
            const int len = (int)(c * (size_t)na * sizeof(float) + (cells ? c : 0));
            if (r == 0) {
                arrays_of(d->g, vel, a);
                region_io(d->g, org, a, na, lo, n, buf, 0);
                if (cells) cells_io(d->g, org, lo, n, (uint8_t *)(buf + c * (size_t)na), 0);
            } else {
                MPI_Recv(buf, len, MPI_BYTE, r, 40, d->cart, MPI_STATUS_IGNORE);
                bytes += len;
            }
            arrays_of(d->mg, vel, a);
            region_io(d->mg, zero, a, na, lo, n, buf, 1);
            if (cells) cells_io(d->mg, zero, lo, n, (uint8_t *)(buf + c * (size_t)na), 1);
            free(buf);
        }
    }
    d->t_mech += MPI_Wtime() - t0;
    return bytes;
}

/* Rank 0 hands out 3-vectors of its mechanics grid inside bb: the velocity
 * (into every box + halo: the convection reads the halo) or (own 1) the
 * displacement of the owned cells, into d->disp. Returns the bytes sent. */
static double mech_scatter(ss_dist_heal *d, float *const *src, int own) {
    const double t0 = MPI_Wtime();
    double bytes = 0;
    int lo[3], n[3];
    const int zero[3] = {0, 0, 0};
    for (int r = d->rank == 0 ? d->size - 1 : d->rank; r >= (d->rank == 0 ? 0 : d->rank); r--) {
        int coords[3], blo[3], bn[3];
        MPI_Cart_coords(d->cart, r, 3, coords);
        box_of(d, coords, blo, bn);
        const int hz = d->hz, org[3] = {blo[0] - 1, blo[1] - 1, blo[2] - hz};
        const int alo[3] = {blo[0] - 1, blo[1] - 1, blo[2] - hz},
                  an[3] = {bn[0] + 2, bn[1] + 2, bn[2] + 2 * hz};
        const size_t c = own ? clip_box(blo, bn, d->bb, lo, n) : clip_box(alo, an, d->bb, lo, n);
        if (!c) continue;
        float *buf = malloc(3 * c * sizeof(float));
        if (!buf) MPI_Abort(d->cart, 3);
        float *dst[3] = {own ? d->disp[0] : d->g->velocity[0], own ? d->disp[1] : d->g->velocity[1],
                         own ? d->disp[2] : d->g->velocity[2]};
        if (d->rank == 0) {
            region_io(d->mg, zero, src, 3, lo, n, buf, 0);
            if (r == 0) {
                region_io(d->g, org, dst, 3, lo, n, buf, 1);
            } else {
                MPI_Send(buf, (int)(3 * c), MPI_FLOAT, r, 41, d->cart);
                bytes += 12.0 * (double)c;
            }
        } else {
            MPI_Recv(buf, (int)(3 * c), MPI_FLOAT, 0, 41, d->cart, MPI_STATUS_IGNORE);
            region_io(d->g, org, dst, 3, lo, n, buf, 1);
        }
        free(buf);
    }
    d->t_mech += MPI_Wtime() - t0;
    return bytes;
}

static void do_mech_in(ss_dist_heal *d) { mech_gather(d, 0, 0); }
static void do_mech_out(ss_dist_heal *d) {
    mech_scatter(d, d->rank == 0 ? d->mg->velocity : NULL, 0);
}

/* The mechanics set up on rank 0: every box gets a velocity (zero, or the
 * checkpoint's), rank 0 a grid of the run's size with the cell states of
 * every box (and a resumed run's velocity), on which the run creates them
 * (ss_heal_run_mech_attach); their box (the tissue's bounding box: the
 * mechanics read the fields and write the velocity at tissue cells only) is
 * shared, the first velocity handed out. */
static ss_status mech_setup(ss_dist_heal *d, ss_heal_run *r, ss_error *err) {
    const size_t nl = (size_t)d->g->nx * d->g->ny * d->g->nz;
    for (int c = 0; c < 3; c++)
        if (!d->g->velocity[c] && !(d->g->velocity[c] = calloc(nl, sizeof(float))))
            MPI_Abort(d->cart, 3);
    ss_status st = SS_OK;
    for (int a = 0; a < 3; a++) {
        d->bb[a] = 0;
        d->bb[3 + a] = d->su.G[a];
    }
    if (d->rank == 0) {
        d->mg = ss_heal_grid_create(d->su.G[0], d->su.G[1], d->su.G[2], d->su.dx_mm, err);
        if (!d->mg) MPI_Abort(d->cart, 3);
        d->mg->skin_top_mm = d->su.skin_top_mm;
        for (int c = 0; c < 3; c++)
            if (!(d->mg->velocity[c] =
                      calloc((size_t)d->su.G[0] * d->su.G[1] * d->su.G[2], sizeof(float))))
                MPI_Abort(d->cart, 3);
    }
    mech_gather(d, 0, 1);
    if (!d->su.fresh) { /* the checkpoint's velocity: the boxes' (pieces) or rank 0's grid */
        ss_heal_grid *G = d->rank == 0 ? ss_heal_run_grid(r) : NULL;
        int whole = d->rank == 0 && G->velocity[0] && G->velocity[1] && G->velocity[2];
        MPI_Bcast(&whole, 1, MPI_INT, 0, d->cart);
        if (!whole) mech_gather(d, 1, 0);
        for (int c = 0; whole && d->rank == 0 && c < 3; c++) {
            free(d->mg->velocity[c]);
            d->mg->velocity[c] = G->velocity[c];
            G->velocity[c] = NULL;
        }
    }
    if (d->rank == 0) {
        ss_heal_grid *mg = d->mg;
        st = ss_heal_run_mech_attach(r, mg, err); /* the run owns mg from here */
        if (st) d->mg = NULL;
        /* the tissue's bounding box */
        int lo[3] = {d->su.G[0], d->su.G[1], d->su.G[2]}, hi[3] = {0, 0, 0};
        for (int z = 0; !st && z < d->su.G[2]; z++)
            for (int y = 0; y < d->su.G[1]; y++)
                for (int x = 0; x < d->su.G[0]; x++) {
                    const uint8_t c = d->mg->cell[ss_heal_idx(d->mg, x, y, z)];
                    if (c != SS_CELL_EPIDERMIS && c != SS_CELL_DERMIS && c != SS_CELL_WOUND)
                        continue;
                    const int v[3] = {x, y, z};
                    for (int a = 0; a < 3; a++) {
                        if (v[a] < lo[a]) lo[a] = v[a];
                        if (v[a] + 1 > hi[a]) hi[a] = v[a] + 1;
                    }
                }
        for (int a = 0; a < 3; a++) {
            d->bb[a] = lo[a];
            d->bb[3 + a] = hi[a] > lo[a] ? hi[a] : lo[a];
        }
    }
    if ((st = agree_err(d, st, err))) return st;
    MPI_Bcast(d->bb, 6, MPI_INT, 0, d->cart);
    for (int c = 0; d->rank == 0 && c < 3; c++)
        if (!(d->disp[c] = calloc(nl, sizeof(float)))) MPI_Abort(d->cart, 3);
    for (int c = 0; d->rank != 0 && c < 3; c++)
        if (!(d->disp[c] = calloc(nl, sizeof(float)))) MPI_Abort(d->cart, 3);
    d->t_mech = 0;
    do_mech_out(d);
    /* the bytes of one coupling step (rank 0's box not counted), for the timing */
    if (d->rank == 0) {
        int lo[3], n[3];
        double b = 0;
        for (int q = 1; q < d->size; q++) {
            int coords[3], blo[3], bn[3];
            MPI_Cart_coords(d->cart, q, 3, coords);
            box_of(d, coords, blo, bn);
            b += 4.0 * NMF * (double)clip_box(blo, bn, d->bb, lo, n);
            const int alo[3] = {blo[0] - 1, blo[1] - 1, blo[2] - d->hz},
                      an[3] = {bn[0] + 2, bn[1] + 2, bn[2] + 2 * d->hz};
            b += 12.0 * (double)clip_box(alo, an, d->bb, lo, n);
        }
        d->mech_bytes = b;
    }
    d->t_mech = 0;
    return SS_OK;
}

/* A run on a skin mesh: the fields at each column's top tissue cell (d->top)
 * go to rank 0 (vals: nx*ny x NFIELDS) from the box that owns that cell, in
 * column order: nx*ny x NFIELDS floats at most, never the grid. */
static void do_columns(ss_dist_heal *d, float *vals) {
    const double t0 = MPI_Wtime();
    const int GX = d->su.G[0];
    for (int r = d->rank == 0 ? 0 : d->rank; r < (d->rank == 0 ? d->size : d->rank + 1); r++) {
        int coords[3], lo[3], n[3];
        MPI_Cart_coords(d->cart, r, 3, coords);
        box_of(d, coords, lo, n);
        size_t cnt = 0;
        for (int y = lo[1]; y < lo[1] + n[1]; y++)
            for (int x = lo[0]; x < lo[0] + n[0]; x++) {
                const int k = d->top[(size_t)y * GX + x];
                cnt += k >= lo[2] && k < lo[2] + n[2];
            }
        if (!cnt) continue;
        float *buf = malloc(cnt * SS_HEAL_NFIELDS * sizeof(float));
        if (!buf) MPI_Abort(d->cart, 3);
        if (r == d->rank) /* this rank's own: pack */
            for (size_t y = 0, m = 0; y < (size_t)n[1]; y++)
                for (int x = 0; x < n[0]; x++) {
                    const int k = d->top[(size_t)(lo[1] + (int)y) * GX + lo[0] + x];
                    if (k < lo[2] || k >= lo[2] + n[2]) continue;
                    const size_t i = ss_heal_idx(d->g, x + 1, (int)y + 1, k - lo[2] + d->hz);
                    for (int f = 0; f < SS_HEAL_NFIELDS; f++) buf[m++] = d->g->field[f][i];
                }
        if (d->rank != 0) MPI_Send(buf, (int)(cnt * SS_HEAL_NFIELDS), MPI_FLOAT, 0, 42, d->cart);
        if (d->rank == 0 && r != 0)
            MPI_Recv(buf, (int)(cnt * SS_HEAL_NFIELDS), MPI_FLOAT, r, 42, d->cart,
                     MPI_STATUS_IGNORE);
        if (d->rank == 0) /* unpack in the same column order */
            for (int y = lo[1], m = 0; y < lo[1] + n[1]; y++)
                for (int x = lo[0]; x < lo[0] + n[0]; x++) {
                    const size_t c = (size_t)y * GX + x;
                    const int k = d->top[c];
                    if (k < lo[2] || k >= lo[2] + n[2]) continue;
                    for (int f = 0; f < SS_HEAL_NFIELDS; f++)
                        vals[c * SS_HEAL_NFIELDS + (size_t)f] = buf[m++];
                }
        free(buf);
    }
    d->t_gather += MPI_Wtime() - t0;
}

/* A checkpoint in pieces (skinsim/heal_io.h): every rank writes its box as
 * piece `rank`, the statuses are agreed and the pieces' sizes and CRCs
 * gathered, then rank 0 writes the header naming the whole grid, the process
 * grid and the step (the checkpoint exists from that moment) and prunes the
 * older ones. No rank holds more than its box. */
static ss_status do_checkpoint(ss_dist_heal *d, const ss_heal_grid *hdr, const char *run_dir,
                               const char *scenario, const char *params_json, int scheme,
                               double dt_days, const char *aux, int keep, ss_error *err) {
    double t0 = MPI_Wtime();
    char dir[4096] = "";
    bcast_string(d, run_dir, dir, sizeof dir);
    /* the run's step (an adaptive step counts its multiple of dt) and time */
    struct {
        unsigned long long step;
        double t;
    } at = {0, 0};
    if (d->rank == 0) at.step = hdr->step, at.t = hdr->t_days;
    MPI_Bcast(&at, (int)sizeof at, MPI_BYTE, 0, d->cart);
    d->g->step = at.step;
    d->g->t_days = at.t;
    ss_error e;
    ss_error_clear(&e);
    ss_heal_ckpt_piece info;
    memset(&info, 0, sizeof info);
    const int org[3] = {d->lo[0] - 1, d->lo[1] - 1, d->lo[2] - d->hz};
    ss_status st =
        ss_heal_ckpt_piece_write(dir, d->rank, d->g, org, d->lo, d->n, d->su.G, &info, &e);
    st = agree_err(d, st, &e);
    ss_heal_ckpt_piece *all = d->rank == 0 ? malloc((size_t)d->size * sizeof *all) : NULL;
    if (d->rank == 0 && !all) MPI_Abort(d->cart, 3);
    MPI_Gather(&info, (int)sizeof info, MPI_BYTE, all, (int)sizeof info, MPI_BYTE, 0, d->cart);
    if (d->rank == 0) {
        if (st) {
            *err = e;
        } else {
            ss_heal_ckpt_header h;
            memset(&h, 0, sizeof h);
            memcpy(h.whole, d->su.G, sizeof h.whole);
            h.dx_mm = d->su.dx_mm;
            h.skin_top_mm = hdr->skin_top_mm;
            h.t_days = hdr->t_days;
            h.step = hdr->step;
            h.scheme = scheme;
            h.dt_days = dt_days;
            h.scenario = (char *)scenario; /* not owned here: h is not freed */
            h.params_json = (char *)params_json;
            h.aux = (char *)(aux ? aux : "");
            memcpy(h.dims, d->dims, sizeof h.dims);
            h.velocity =
                d->su.mech |
                (d->g->added ? 2
                             : 0); /* the mechanics' velocity; the keloid's added volume [D16] */
            h.npieces = d->size;
            h.piece = all;
            st = ss_heal_ckpt_header_save(dir, &h, keep, err);
        }
        free(all);
    }
    MPI_Bcast(&st, 1, MPI_INT, 0, d->cart);
    d->t_gather += MPI_Wtime() - t0;
    return st;
}

/* A resume from a checkpoint in pieces: every rank reads its box + halo g
 * (whole-grid origin org; cells past the grid are BOUND, zero fields) from
 * the pieces that overlap it, whatever split wrote them. */
static ss_status read_box(ss_dist_heal *d, const char *dir, unsigned long long step,
                          ss_heal_grid *g, const int org[3], ss_error *err) {
    char path[4400];
    ss_heal_ckpt_header_path(path, sizeof path, dir, step);
    ss_heal_ckpt_header h;
    memset(&h, 0, sizeof h);
    ss_status st = ss_heal_ckpt_header_read(path, &h, err);
    if (!st && (h.whole[0] != d->su.G[0] || h.whole[1] != d->su.G[1] || h.whole[2] != d->su.G[2]))
        st = ss_error_set(err, SS_ERR_INPUT, "%s: the grid differs from rank 0's", path);
    if (!st) {
        const size_t n = (size_t)g->nx * g->ny * g->nz;
        memset(g->cell, SS_CELL_BOUND, n);
        for (int f = 0; f < SS_HEAL_NFIELDS; f++) memset(g->field[f], 0, n * sizeof(float));
        const int bn[3] = {g->nx, g->ny, g->nz};
        st = ss_heal_ckpt_read_box(dir, &h, g, org, org, bn, err);
    }
    ss_heal_ckpt_header_free(&h);
    return st;
}

/* A surface map (ss_heal_surface_map) from the boxes: each stack in z scans
 * its columns top down, box by box (ss_heal_surface_scan), the bottom box
 * sends the values of its own columns to rank 0, which sets the picture's
 * rows: nx*ny floats move, never the grid. */
static ss_image *do_surface(ss_dist_heal *d, int field, ss_heal_surface_mode mode, ss_error *err) {
    double t0 = MPI_Wtime();
    const size_t nc = (size_t)d->g->nx * d->g->ny;
    float *vf = calloc(2 * nc, sizeof(float));
    if (!vf) MPI_Abort(d->cart, 3);
    if (d->hz) {
        zchain(d, vf, 2 * nc * sizeof(float), 0);
        ss_heal_surface_scan(d->g, field, mode, 1, d->g->nz - 1, d->lo[2] - 1, d->su.G[2], vf,
                             vf + nc);
        zchain(d, vf, 2 * nc * sizeof(float), 1);
    } else {
        ss_heal_surface_scan(d->g, field, mode, 0, d->g->nz, 0, d->su.G[2], vf, vf + nc);
    }
    /* the own columns of the bottom boxes */
    float *own = malloc((size_t)d->n[0] * d->n[1] * sizeof(float));
    if (!own) MPI_Abort(d->cart, 3);
    for (int y = 0; y < d->n[1]; y++)
        memcpy(own + (size_t)y * d->n[0], vf + (size_t)(y + 1) * d->g->nx + 1,
               (size_t)d->n[0] * sizeof(float));
    free(vf);
    ss_image *img = NULL;
    if (d->rank != 0) {
        if (d->coords[2] == 0) MPI_Send(own, d->n[0] * d->n[1], MPI_FLOAT, 0, 102, d->cart);
    } else {
        const int GX = d->su.G[0], GY = d->su.G[1];
        float *map = malloc((size_t)GX * GY * sizeof(float));
        if (!map) MPI_Abort(d->cart, 3);
        for (int r = 0; r < d->size; r++) {
            int coords[3], lo[3], n[3];
            MPI_Cart_coords(d->cart, r, 3, coords);
            if (coords[2] != 0) continue;
            box_of(d, coords, lo, n);
            float *b = r == 0 ? own : malloc((size_t)n[0] * n[1] * sizeof(float));
            if (!b) MPI_Abort(d->cart, 3);
            if (r != 0) MPI_Recv(b, n[0] * n[1], MPI_FLOAT, r, 102, d->cart, MPI_STATUS_IGNORE);
            for (int y = 0; y < n[1]; y++)
                memcpy(map + (size_t)(lo[1] + y) * GX + lo[0], b + (size_t)y * n[0],
                       (size_t)n[0] * sizeof(float));
            if (r != 0) free(b);
        }
        if ((img = ss_image_create(GX, GY, 1, err))) ss_heal_surface_image(map, GX, GY, img->data);
        free(map);
    }
    free(own);
    d->t_gather += MPI_Wtime() - t0;
    return img;
}

/* Every rank writes its owned box as fields_dir/fields_NNNN_pRRRR.vti and
 * rank 0 the fields_NNNN.pvti that joins them (ParaView opens it as one
 * image): the per-rank output that needs no gather. */
static ss_status do_pieces(ss_dist_heal *d, int index, ss_error *err) {
    double t0 = MPI_Wtime();
    int len = 0;
    char dir[4096] = "";
    if (d->rank == 0) len = (int)strlen(d->pdir) + 1;
    MPI_Bcast(&len, 1, MPI_INT, 0, d->cart);
    if (len > (int)sizeof dir) len = (int)sizeof dir;
    if (d->rank == 0) memcpy(dir, d->pdir, (size_t)len);
    MPI_Bcast(dir, len, MPI_CHAR, 0, d->cart);
    dir[sizeof dir - 1] = 0;
    char path[4400];
    snprintf(path, sizeof path, "%s/fields_%04d_p%04d.vti", dir, index, d->rank);
    ss_error e;
    ss_error_clear(&e);
    /* the closure days of the box's columns (with z split the bottom box of
     * the stack has them: every box of the stack writes them in its piece) */
    if (d->hz) MPI_Bcast(d->closed, d->g->nx * d->g->ny, MPI_DOUBLE, d->zroot, d->zcomm);
    double *cb = malloc((size_t)d->n[0] * d->n[1] * sizeof(double));
    if (!cb) MPI_Abort(d->cart, 3);
    own_closed(d, cb);
    /* the mechanics' displacement of the owned cells, from rank 0 (the
     * velocity is the box's own) */
    static const char *const vnames[2] = {"velocity", "displacement"};
    if (d->su.mech) {
        float *const *u = NULL;
        if (d->rank == 0 && !(u = ss_mech_grid_displacement(ss_heal_run_mech(d->run))))
            MPI_Abort(d->cart, 3);
        mech_scatter(d, u, 1);
    }
    float *const vec[1][3] = {{d->disp[0], d->disp[1], d->disp[2]}};
    /* the owned box, written straight from the box + halo */
    const int box[6] = {1, 1, d->hz, d->n[0], d->n[1], d->n[2]};
    const int off[3] = {d->lo[0], d->lo[1], d->lo[2]};
    /* the surface elevation: with z split summed down the stack in the
     * single grid's order (top down), then the bottom box's totals to all */
    float *ev = NULL;
    if (d->hz) {
        const size_t nc = (size_t)d->g->nx * d->g->ny;
        if (!(ev = malloc(nc * sizeof *ev))) MPI_Abort(d->cart, 3);
        zchain(d, ev, nc * sizeof *ev, 0);
        ss_heal_elevation_scan(d->g, 1, d->g->nz - 1, ev);
        zchain(d, ev, nc * sizeof *ev, 1);
        MPI_Bcast(ev, (int)nc, MPI_FLOAT, d->zroot, d->zcomm);
    }
    ss_status st = ss_heal_vti_write_box_vectors(path, d->g, box, off, d->su.G, d->su.mech ? 1 : 0,
                                                 vnames + 1, vec, cb, ev, &e);
    free(ev);
    free(cb);
    int v = (int)st, vmax = 0;
    MPI_Allreduce(&v, &vmax, 1, MPI_INT, MPI_MAX, d->cart);
    if (d->rank == 0 && vmax) {
        if (st)
            *err = e;
        else
            ss_error_set(err, SS_ERR_RUNTIME, "%s: a rank could not write its piece", dir);
    } else if (d->rank == 0) {
        int(*ext)[6] = malloc((size_t)d->size * sizeof *ext);
        char **files = malloc((size_t)d->size * sizeof *files);
        char *names = malloc((size_t)d->size * 32);
        if (!ext || !files || !names) {
            vmax = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        } else {
            for (int q = 0; q < d->size; q++) {
                int coords[3], lo[3], n[3];
                MPI_Cart_coords(d->cart, q, 3, coords);
                box_of(d, coords, lo, n);
                const int e6[6] = {lo[0], lo[0] + n[0], lo[1], lo[1] + n[1], lo[2], lo[2] + n[2]};
                memcpy(ext[q], e6, sizeof e6);
                files[q] = names + (size_t)q * 32;
                snprintf(files[q], 32, "fields_%04d_p%04d.vti", index, q);
            }
            snprintf(path, sizeof path, "%s/fields_%04d.pvti", dir, index);
            /* the pieces hold the keloid's added volume when the grids have it [D16] */
            vmax = ss_heal_pvti_write_arrays(path, d->su.G, d->su.dx_mm, d->size,
                                             (const int(*)[6])ext, (const char *const *)files,
                                             d->su.mech ? 2 : 0, vnames, d->g->added != NULL, err);
        }
        free(ext);
        free(files);
        free(names);
    }
    d->t_gather += MPI_Wtime() - t0;
    return (ss_status)vmax;
}

static void send_cmd(ss_dist_heal *d, int cmd, int arg) {
    int m[2] = {cmd, arg};
    MPI_Bcast(m, 2, MPI_INT, 0, d->cart);
}

/* rank 0's hooks on its run */
static ss_status hook_step(void *ctx, ss_heal_grid *G, double dt, double *max_change,
                           ss_error *err) {
    ss_dist_heal *d = ctx;
    send_cmd(d, CMD_STEP, max_change != NULL);
    d->next_dt = dt;
    ss_status st = do_step(d, max_change != NULL, max_change, err);
    G->t_days = d->g->t_days;
    G->step++;
    d->dirty = 1;
    return st;
}

static void hook_closure(void *ctx, ss_heal_grid *G, double *closed_day) {
    ss_dist_heal *d = ctx;
    (void)G;
    d->closed_root = closed_day;
    send_cmd(d, CMD_CLOSURE, 0);
    do_closure(d);
    d->dirty = 1;
}

static void hook_undo(void *ctx, ss_heal_grid *G) {
    ss_dist_heal *d = ctx;
    (void)G;
    send_cmd(d, CMD_UNDO, 0);
    do_undo(d);
}

static void hook_stats(void *ctx, const ss_heal_grid *G, ss_heal_stats *st) {
    ss_dist_heal *d = ctx;
    (void)G;
    send_cmd(d, CMD_STATS, 0);
    do_stats(d, st);
}

static ss_status hook_sync(void *ctx, ss_heal_grid *G, ss_error *err) {
    ss_dist_heal *d = ctx;
    (void)G;
    if (!d->dirty) return SS_OK;
    send_cmd(d, CMD_SYNC, 0);
    return do_sync(d, err);
}

static ss_image *hook_surface(void *ctx, const ss_heal_grid *G, int field,
                              ss_heal_surface_mode mode, ss_error *err) {
    ss_dist_heal *d = ctx;
    (void)G;
    send_cmd(d, CMD_SURFACE, field | (int)mode << 8);
    return do_surface(d, field, mode, err);
}

static ss_status hook_checkpoint(void *ctx, const ss_heal_grid *G, const char *run_dir,
                                 const char *scenario, const char *params_json, int scheme,
                                 double dt_days, const char *aux, int keep, ss_error *err) {
    ss_dist_heal *d = ctx;
    send_cmd(d, CMD_CKPT, 0);
    return do_checkpoint(d, G, run_dir, scenario, params_json, scheme, dt_days, aux, keep, err);
}

static ss_status hook_snapshot(void *ctx, const ss_heal_grid *G, const char *fields_dir, int index,
                               ss_error *err) {
    ss_dist_heal *d = ctx;
    (void)G;
    d->pdir = fields_dir;
    send_cmd(d, CMD_PIECES, index);
    return do_pieces(d, index, err);
}

static void hook_columns(void *ctx, const int32_t *top, float *vals) {
    ss_dist_heal *d = ctx;
    (void)top; /* the same as d->top */
    send_cmd(d, CMD_COLUMNS, 0);
    do_columns(d, vals);
}

static void hook_mech_in(void *ctx, ss_heal_grid *mg) {
    ss_dist_heal *d = ctx;
    (void)mg;
    send_cmd(d, CMD_MECH_IN, 0);
    do_mech_in(d);
}

static void hook_mech_out(void *ctx, const ss_heal_grid *mg) {
    ss_dist_heal *d = ctx;
    (void)mg;
    send_cmd(d, CMD_MECH_OUT, 0);
    do_mech_out(d);
}

/* ---- set-up ----------------------------------------------------------------------- */

/* Rank 0 sends every rank its box + halo of its whole grid (cells and
 * fields) into g: the boxes of the process grid, or (xslabs) the split
 * scheme's x slabs. */
static void scatter(ss_dist_heal *d, ss_heal_run *r, ss_heal_grid *g, int xslabs) {
    const int tag = xslabs ? 12 : 10, hz = xslabs ? 0 : d->hz;
    if (d->rank != 0) {
        const size_t nl = (size_t)g->nx * g->ny * g->nz;
        float *fields = malloc(nl * SS_HEAL_NFIELDS * sizeof(float));
        if (!fields) MPI_Abort(d->cart, 3);
        MPI_Recv(g->cell, (int)nl, MPI_BYTE, 0, tag, d->cart, MPI_STATUS_IGNORE);
        MPI_Recv(fields, (int)(nl * SS_HEAL_NFIELDS), MPI_FLOAT, 0, tag + 1, d->cart,
                 MPI_STATUS_IGNORE);
        for (int f = 0; f < SS_HEAL_NFIELDS; f++)
            memcpy(g->field[f], fields + f * nl, nl * sizeof(float));
        free(fields);
        return;
    }
    const ss_heal_grid *G = ss_heal_run_grid(r);
    for (int q = d->size - 1; q >= 0; q--) {
        int lo[3] = {0, 0, 0}, n[3] = {0, d->su.G[1], d->su.G[2]};
        if (xslabs) {
            xslab(d, q, &lo[0], &n[0]);
        } else {
            int coords[3];
            MPI_Cart_coords(d->cart, q, 3, coords);
            box_of(d, coords, lo, n);
        }
        size_t nq = (size_t)(n[0] + 2) * (n[1] + 2) * (n[2] + 2 * hz);
        uint8_t *cells = q == 0 ? g->cell : malloc(nq);
        float *fields = malloc(nq * SS_HEAL_NFIELDS * sizeof(float));
        if (!cells || !fields) MPI_Abort(d->cart, 3);
        pack_box(G, lo, n, hz, cells, fields);
        if (q == 0) {
            for (int f = 0; f < SS_HEAL_NFIELDS; f++)
                memcpy(g->field[f], fields + f * nq, nq * sizeof(float));
        } else {
            MPI_Send(cells, (int)nq, MPI_BYTE, q, tag, d->cart);
            MPI_Send(fields, (int)(nq * SS_HEAL_NFIELDS), MPI_FLOAT, q, tag + 1, d->cart);
            free(cells);
        }
        free(fields);
    }
}

/* Rank 0 sends every rank the closure days of its box + halo columns (the
 * run's, fresh or from the checkpoint; columns outside the grid: intact). */
static void scatter_closed(ss_dist_heal *d, ss_heal_run *r) {
    const size_t nl = (size_t)d->g->nx * d->g->ny;
    if (d->rank != 0) {
        MPI_Recv(d->closed, (int)nl, MPI_DOUBLE, 0, 14, d->cart, MPI_STATUS_IGNORE);
        return;
    }
    const double *C = ss_heal_run_closure(r);
    const ss_heal_grid *G = ss_heal_run_grid(r);
    for (int q = d->size - 1; q >= 0; q--) {
        int coords[3], lo[3], n[3];
        MPI_Cart_coords(d->cart, q, 3, coords);
        box_of(d, coords, lo, n);
        const int nxl = n[0] + 2, nyl = n[1] + 2;
        double *c = q == 0 ? d->closed : malloc((size_t)nxl * nyl * sizeof(double));
        if (!c) MPI_Abort(d->cart, 3);
        for (int y = 0; y < nyl; y++)
            for (int x = 0; x < nxl; x++) {
                const int X = lo[0] - 1 + x, Y = lo[1] - 1 + y;
                const int in = C && X >= 0 && Y >= 0 && X < G->nx && Y < G->ny;
                c[(size_t)y * nxl + x] = in ? C[(size_t)Y * G->nx + X] : SS_HEAL_CLOSED_INTACT;
            }
        if (q != 0) {
            MPI_Send(c, nxl * nyl, MPI_DOUBLE, q, 14, d->cart);
            free(c);
        }
    }
}

/* A fresh run: the box g whose cell (0,0,0) is the whole grid's goff, built
 * by this rank from the wound (its mask from the column ranges or the mesh
 * voxelised over the box) with ss_heal_grid_init_box: the cells and fields
 * the whole grid has there. cnt (if not NULL): += the wound voxels of the
 * owned cells, and those under the skin surface (the mesh's checks). */
static ss_status build_box(ss_dist_heal *d, ss_heal_grid *g, const int goff[3], size_t cnt[2],
                           ss_error *err) {
    const int bn[3] = {g->nx, g->ny, g->nz};
    size_t all = 0;
    uint8_t *m =
        d->su.wound == WOUND_MESH
            ? ss_heal_voxelise_mesh_box(&d->mesh, d->su.G, goff, bn, d->su.dx_mm, &all, err)
            : ss_heal_wound_columns_expand(d->wcols, d->su.G, goff, bn, err);
    if (!m) return err->code ? err->code : SS_ERR_NOMEM;
    for (int z = d->hz; cnt && z < d->hz + d->n[2]; z++)
        for (int y = 1; y <= d->n[1]; y++)
            for (int x = 1; x <= d->n[0]; x++)
                if (m[ss_heal_idx(g, x, y, z)]) {
                    cnt[0]++;
                    cnt[1] += (z + goff[2] + 0.5) * d->su.dx_mm < d->su.skin_top_mm;
                }
    ss_status st = ss_heal_grid_init_box(g, goff, d->su.G, d->su.skin_top_mm, d->su.epidermis_mm, m,
                                         &d->su.p, err);
    free(m);
    return st;
}

/* Every rank gets the wound of a fresh run from rank 0: the column ranges
 * (2 x nx*ny int32) or the mesh. */
static ss_status share_wound(ss_dist_heal *d, ss_heal_run *r, ss_error *err) {
    ss_status st = SS_OK;
    if (d->su.wound == WOUND_COLUMNS) {
        const size_t nc = 2 * (size_t)d->su.G[0] * d->su.G[1];
        int32_t *c = NULL;
        if (d->rank == 0) {
            d->wcols = ss_heal_run_wound_columns(r);
        } else {
            if (!(c = malloc(nc * sizeof *c))) MPI_Abort(d->cart, 3);
            d->wcols = c;
            d->own_wcols = 1;
        }
        MPI_Bcast((void *)d->wcols, (int)nc, MPI_INT32_T, 0, d->cart);
        return st;
    }
    ss_tri_mesh *m = &d->mesh;
    m->nverts = d->su.mesh_nv;
    m->ntris = d->su.mesh_nt;
    m->v = malloc((size_t)m->nverts * 3 * sizeof *m->v);
    m->tri = malloc((size_t)m->ntris * 3 * sizeof *m->tri);
    if (!m->v || !m->tri) MPI_Abort(d->cart, 3);
    if (d->rank == 0) {
        const ss_tri_mesh *w = ss_heal_run_wound_mesh(r);
        memcpy(m->v, w->v, (size_t)m->nverts * 3 * sizeof *m->v);
        memcpy(m->tri, w->tri, (size_t)m->ntris * 3 * sizeof *m->tri);
    }
    MPI_Bcast(m->v, 3 * m->nverts, MPI_DOUBLE, 0, d->cart);
    MPI_Bcast(m->tri, 3 * m->ntris, MPI_INT, 0, d->cart);
    (void)err;
    return st;
}

/* The split scheme's x slab of every rank (built like the y slabs, or from
 * rank 0's whole grid on a resume) and the transpose buffers. */
static ss_status split_setup(ss_dist_heal *d, ss_heal_run *r, ss_error *err) {
    const int nz = d->su.G[2];
    int xlo, xn;
    xslab(d, d->rank, &xlo, &xn);
    d->nslots = ss_heal_solver_nslots(d->s);
    d->gB = ss_heal_grid_create(xn + 2, d->su.G[1] + 2, nz, d->su.dx_mm, err);
    if (!d->gB) return err->code ? err->code : SS_ERR_NOMEM;
    d->gB->skin_top_mm = d->su.skin_top_mm;
    int goff[3] = {xlo - 1, -1, 0};
    if (d->su.fresh || d->su.pieces_step >= 0) {
        ss_status st = d->su.fresh ? build_box(d, d->gB, goff, NULL, err)
                                   : read_box(d, d->ckdir, (unsigned long long)d->su.pieces_step,
                                              d->gB, goff, err);
        if (st) return st;
    } else {
        scatter(d, r, d->gB, 1);
    }
    d->sB = ss_heal_solver_create_sub(d->gB, goff, d->su.G, &d->su.p, SS_HEAL_SPLIT, d->su.dt, err);
    if (!d->sB) return err->code ? err->code : SS_ERR_RUNTIME;
    /* the largest message set: A's owned rows or B's owned columns, all quantities */
    int ylo, yn;
    yslab(d, d->rank, &ylo, &yn);
    size_t na = (size_t)d->su.G[0] * yn * nz, nbo = (size_t)xn * d->su.G[1] * nz;
    size_t cap = (na > nbo ? na : nbo) * (size_t)(SS_HEAL_NFIELDS + d->nslots);
    d->tsend = malloc(cap * sizeof(float));
    d->trecv = malloc(cap * sizeof(float));
    d->scnt = malloc((size_t)d->size * 4 * sizeof(int));
    if (!d->tsend || !d->trecv || !d->scnt) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    d->sdsp = d->scnt + d->size;
    d->rcnt = d->sdsp + d->size;
    d->rdsp = d->rcnt + d->size;
    /* bytes sent to other ranks per step: both transposes, less what stays here */
    int xo, xno;
    xslab(d, d->rank, &xo, &xno);
    d->tbytes = 4.0 * nz *
                ((double)(d->su.G[0] - xno) * yn * (SS_HEAL_NFIELDS + d->nslots) +
                 (double)xno * (d->su.G[1] - yn) * SS_HEAL_NFIELDS);
    return SS_OK;
}

/* Rank 0: what the distributed solver cannot do, as an input error. */
static ss_status check_root(ss_heal_run *r, int size, int dims[3], ss_error *err) {
    const ss_heal_grid *G = ss_heal_run_grid(r);
    /* the process grid the user asked for: SKINSIM_MPI_DIMS=PXxPYxPZ (0 = any) */
    const char *ask = getenv("SKINSIM_MPI_DIMS");
    int want[3] = {0, 0, 1}; /* default: columns stay whole (z is split only on request) */
    if (ask && *ask) {
        char tail = 0;
        if (sscanf(ask, "%dx%dx%d%c", &want[0], &want[1], &want[2], &tail) != 3 || want[0] < 0 ||
            want[1] < 0 || want[2] < 0)
            return ss_error_set(err, SS_ERR_INPUT,
                                "SKINSIM_MPI_DIMS=%s: expected PXxPYxPZ, e.g. 2x1x2 (0 = let MPI "
                                "choose that axis)",
                                ask);
        if (ss_heal_run_scheme(r) != SS_HEAL_EXPLICIT)
            return ss_error_set(err, SS_ERR_INPUT,
                                "SKINSIM_MPI_DIMS=%s: the split scheme always runs on y and x "
                                "slabs (its line solves need whole lines); unset it or use "
                                "--scheme explicit",
                                ask);
    }
    if (ss_heal_run_scheme(r) != SS_HEAL_EXPLICIT) {
        /* y slabs, and x slabs for the y sweep: every line solve stays whole */
        dims[0] = dims[2] = 1;
        dims[1] = size;
        if (size > G->nx || size > G->ny)
            return ss_error_set(err, SS_ERR_INPUT,
                                "%d MPI ranks are too many for the %dx%dx%d grid with --scheme "
                                "split (slabs in y and in x, one column each at least); use at "
                                "most %d ranks, a larger --grid or --scheme explicit",
                                size, G->nx, G->ny, G->nz, G->nx < G->ny ? G->nx : G->ny);
        return SS_OK;
    }
    memcpy(dims, want, sizeof want);
    long long fixed = 1;
    for (int a = 0; a < 3; a++) fixed *= want[a] ? want[a] : 1;
    if (size % fixed != 0 || MPI_Dims_create(size, 3, dims) != MPI_SUCCESS)
        return ss_error_set(err, SS_ERR_INPUT, "%d MPI ranks do not fit the process grid %s", size,
                            ask && *ask ? ask : "Px x Py x 1");
    if (dims[2] > 1 && G->nz / dims[2] < 3)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%d MPI ranks are too many for the %dx%dx%d grid: the process grid "
                            "%dx%dx%d splits z into boxes of fewer than 3 levels; use at most "
                            "%d boxes in z",
                            size, G->nx, G->ny, G->nz, dims[0], dims[1], dims[2], G->nz / 3);
    if (dims[0] > G->nx || dims[1] > G->ny)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%d MPI ranks are too many for the %dx%dx%d grid: the process grid "
                            "%dx%dx%d would leave a rank without a column; use at most %d "
                            "ranks or a larger --grid",
                            size, G->nx, G->ny, G->nz, dims[0], dims[1], dims[2],
                            G->nx < G->ny ? G->nx : G->ny);
    return SS_OK;
}

static ss_status agree(MPI_Comm comm, ss_status st) {
    int v = (int)st, m = 0;
    MPI_Allreduce(&v, &m, 1, MPI_INT, MPI_MAX, comm);
    return (ss_status)m;
}

ss_status ss_dist_heal_create(ss_heal_run *r, ss_status root_st, ss_dist_heal **out,
                              ss_error *err) {
    *out = NULL;
    int rank, size;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    setup su;
    memset(&su, 0, sizeof su);
    int v = (int)root_st;
    if (rank == 0 && !root_st) {
        v = (int)check_root(r, size, su.dims, err);
    }
    MPI_Bcast(&v, 1, MPI_INT, 0, MPI_COMM_WORLD);
    if (v) {
        if (rank != 0) ss_error_set(err, (ss_status)v, "rank 0 refused the run");
        return (ss_status)v;
    }
    if (rank == 0) {
        const ss_heal_grid *G = ss_heal_run_grid(r);
        su.G[0] = G->nx;
        su.G[1] = G->ny;
        su.G[2] = G->nz;
        su.scheme = (int)ss_heal_run_scheme(r);
        su.dx_mm = G->dx_mm;
        su.skin_top_mm = G->skin_top_mm;
        su.t_days = G->t_days;
        su.step = G->step;
        su.dt = ss_heal_run_dt(r);
        su.p = *ss_heal_run_params(r);
        su.epidermis_mm = ss_heal_run_epidermis_mm(r);
        su.pieces_step = ss_heal_run_resume_pieces(r, NULL);
        su.fresh = G->cell == NULL && su.pieces_step < 0; /* config.distributed */
        su.mech = ss_heal_run_mech_pending(r);
        su.shell = ss_heal_run_shell(r) != NULL;
        const ss_tri_mesh *m = ss_heal_run_wound_mesh(r);
        su.wound = m ? WOUND_MESH : WOUND_COLUMNS;
        if (m) {
            su.mesh_nv = m->nverts;
            su.mesh_nt = m->ntris;
        }
    }
    MPI_Bcast(&su, (int)sizeof su, MPI_BYTE, 0, MPI_COMM_WORLD);

    ss_dist_heal *d = calloc(1, sizeof *d);
    ss_status st = d ? SS_OK : ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    if (agree(MPI_COMM_WORLD, st)) {
        free(d);
        return SS_ERR_NOMEM;
    }
    d->su = su;
    d->size = size;
    d->run = rank == 0 ? r : NULL;
    int periods[3] = {0, 0, 0};
    memcpy(d->dims, su.dims, sizeof d->dims);
    MPI_Cart_create(MPI_COMM_WORLD, 3, d->dims, periods, 0, &d->cart);
    MPI_Comm_rank(d->cart, &d->rank);
    MPI_Cart_coords(d->cart, d->rank, 3, d->coords);
    MPI_Cart_shift(d->cart, 0, 1, &d->nbr[FACE_XM], &d->nbr[FACE_XP]);
    MPI_Cart_shift(d->cart, 1, 1, &d->nbr[FACE_YM], &d->nbr[FACE_YP]);
    MPI_Cart_shift(d->cart, 2, 1, &d->nbr[FACE_ZM], &d->nbr[FACE_ZP]);
    box_of(d, d->coords, d->lo, d->n);
    /* the stack of boxes in z over this box's columns */
    const int remain[3] = {0, 0, 1};
    MPI_Cart_sub(d->cart, remain, &d->zcomm);
    MPI_Cart_shift(d->zcomm, 0, 1, &d->zbelow, &d->zabove);
    const int zero = 0;
    MPI_Cart_rank(d->zcomm, &zero, &d->zroot);
    d->hz = d->dims[2] > 1;

    /* the box + halo grid and its solver */
    const int nxl = d->n[0] + 2, nyl = d->n[1] + 2, nz = d->n[2] + 2 * d->hz;
    d->g = ss_heal_grid_create(nxl, nyl, nz, su.dx_mm, err);
    if (d->g) {
        d->g->skin_top_mm = su.skin_top_mm;
        d->g->t_days = su.t_days;
        d->g->step = su.step;
    }
    d->fcount[FACE_XM] = d->fcount[FACE_XP] = SS_HEAL_NFIELDS * nyl * nz;
    d->fcount[FACE_YM] = d->fcount[FACE_YP] = SS_HEAL_NFIELDS * nxl * nz;
    d->fcount[FACE_ZM] = d->fcount[FACE_ZP] = SS_HEAL_NFIELDS * nxl * nyl;
    /* the column scans down the stack: 2 floats or one ss_heal_col_state per column */
    const size_t colsz = sizeof(ss_heal_col_state) > 2 * sizeof(float) ? sizeof(ss_heal_col_state)
                                                                       : 2 * sizeof(float);
    if (d->hz && !(d->colbuf = malloc((size_t)nxl * nyl * colsz)))
        st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    for (int f = 0; f < NFACES && d->g; f++) {
        d->sbuf[f] = malloc((size_t)d->fcount[f] * sizeof(float));
        d->rbuf[f] = malloc((size_t)d->fcount[f] * sizeof(float));
        if (!d->sbuf[f] || !d->rbuf[f]) st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    if (!d->g) st = err->code ? err->code : SS_ERR_NOMEM;
    if ((st = agree(d->cart, st))) {
        if (rank != 0) ss_error_set(err, st, "a rank could not allocate its box");
        ss_dist_heal_free(d);
        return st;
    }

    /* every rank its box + halo: built from the wound (fresh), or cut from
     * the checkpoint's grid on rank 0 */
    int goff[3] = {d->lo[0] - 1, d->lo[1] - 1, d->lo[2] - d->hz};
    if (su.fresh) {
        size_t cnt[2] = {0, 0};
        unsigned long long c2[2], sum[2] = {0, 0};
        st = share_wound(d, r, err);
        if (!st) st = build_box(d, d->g, goff, cnt, err);
        c2[0] = cnt[0];
        c2[1] = cnt[1];
        MPI_Reduce(c2, sum, 2, MPI_UNSIGNED_LONG_LONG, MPI_SUM, 0, d->cart);
        if (rank == 0 && !st && su.wound == WOUND_MESH)
            st = ss_heal_run_wound_counted(r, (size_t)sum[0], (size_t)sum[1], err);
        if ((st = agree_err(d, st, err))) {
            ss_dist_heal_free(d);
            return st;
        }
    } else if (su.pieces_step >= 0) {
        const char *ckdir = NULL;
        if (rank == 0) ss_heal_run_resume_pieces(r, &ckdir);
        bcast_string(d, ckdir, d->ckdir, sizeof d->ckdir);
        st = read_box(d, d->ckdir, (unsigned long long)su.pieces_step, d->g, goff, err);
        if ((st = agree_err(d, st, err))) {
            ss_dist_heal_free(d);
            return st;
        }
    } else {
        scatter(d, r, d->g, 0);
    }
    if (!(d->closed = malloc((size_t)nxl * nyl * sizeof(double)))) MPI_Abort(d->cart, 3);
    if (su.fresh) { /* ss_heal_closure_init, down each stack */
        for (size_t k = 0; k < (size_t)nxl * nyl; k++) d->closed[k] = SS_HEAL_CLOSED_INTACT;
        do_closure(d);
    } else {
        scatter_closed(d, r);
    }
    /* a skin mesh: the columns' top levels on every rank (2D) */
    if (su.shell) {
        const size_t nc = (size_t)su.G[0] * su.G[1];
        if (!(d->top = malloc(nc * sizeof *d->top))) MPI_Abort(d->cart, 3);
        if (rank == 0) memcpy(d->top, ss_heal_run_shell_tops(r), nc * sizeof *d->top);
        MPI_Bcast(d->top, (int)nc, MPI_INT32_T, 0, d->cart);
    }
    /* the mechanics on rank 0 (before the solver: the boxes' velocity) */
    if (su.mech && (st = mech_setup(d, r, err))) {
        ss_dist_heal_free(d);
        return st;
    }
    d->s =
        ss_heal_solver_create_sub(d->g, goff, su.G, &su.p, (ss_heal_scheme)su.scheme, su.dt, err);
    st = d->s ? SS_OK : (err->code ? err->code : SS_ERR_RUNTIME);
    if (agree(d->cart, st) == SS_OK && d->hz) ss_heal_solver_set_columns(d->s, zcol, d);
    if ((st = agree(d->cart, st))) {
        if (d->rank != 0) ss_error_set(err, st, "a rank could not set up its solver");
        ss_dist_heal_free(d);
        return st;
    }
    d->split = su.scheme == SS_HEAL_SPLIT && size > 1; /* one rank: the plain step */
    const char *ov = getenv("SKINSIM_DIST_OVERLAP");
    d->overlap = !(ov && strcmp(ov, "0") == 0);
    if (d->split) st = split_setup(d, r, err);
    if (d->split) ss_heal_solver_set_convection(d->s, split_conv, d);
    if ((st = agree(d->cart, st))) {
        if (d->rank != 0) ss_error_set(err, st, "a rank could not set up its x slab");
        ss_dist_heal_free(d);
        return st;
    }
    if (d->rank == 0) {
        /* from here on rank 0 holds no whole grid */
        if (!su.fresh && su.pieces_step < 0) ss_heal_run_release_grid(r);
        d->closed_root = (double *)ss_heal_run_closure(r);
        d->dirty = su.fresh; /* the ranks' day-0 closure days are not here yet */
        ss_heal_run_hooks h = {.ctx = d,
                               .step = hook_step,
                               .undo = hook_undo,
                               .stats = hook_stats,
                               .sync = hook_sync,
                               .closure = hook_closure,
                               .snapshot = hook_snapshot,
                               .surface_map = hook_surface,
                               .mech_in = su.mech ? hook_mech_in : NULL,
                               .mech_out = su.mech ? hook_mech_out : NULL,
                               .columns = su.shell ? hook_columns : NULL};
        ss_heal_run_set_checkpoint_hook(r, hook_checkpoint, d);
        /* (a fresh run's day-0 area row: the first command the others serve) */
        if ((st = ss_heal_run_set_hooks(r, &h, err))) {
            ss_dist_heal_end(d, st);
            ss_dist_heal_free(d);
            return st;
        }
    }
    *out = d;
    return SS_OK;
}

static void reduce_timing(ss_dist_heal *d) {
    double t[6] = {d->t_compute, d->t_halo, d->t_stats, d->t_gather, 0, d->t_mech}, m[6];
    size_t fb = 0;
    for (int f = 0; f < NFACES; f++)
        if (d->nbr[f] != MPI_PROC_NULL) fb += (size_t)d->fcount[f] * sizeof(float);
    t[4] = d->split ? d->tbytes : (double)fb;
    MPI_Reduce(t, m, 6, MPI_DOUBLE, MPI_MAX, 0, d->cart);
    struct rusage ru;
    double rss = getrusage(RUSAGE_SELF, &ru) == 0 ? (double)ru.ru_maxrss / 1024.0 : 0.0;
    if (d->rank == 0 && !d->rss_mb && !(d->rss_mb = malloc((size_t)d->size * sizeof(double))))
        MPI_Abort(d->cart, 3);
    MPI_Gather(&rss, 1, MPI_DOUBLE, d->rss_mb, 1, MPI_DOUBLE, 0, d->cart);
    if (d->rank == 0) {
        d->tmax.compute_s = m[0];
        d->tmax.halo_s = m[1];
        d->tmax.stats_s = m[2];
        d->tmax.gather_s = m[3];
        d->tmax.halo_bytes_per_step = m[4];
        d->tmax.mech_s = d->t_mech; /* rank 0's: it waits for every gather */
        d->tmax.mech_bytes_per_step = d->mech_bytes;
        (void)m[5];
        memcpy(d->tmax.dims, d->dims, sizeof d->dims);
        d->tmax.steps = d->steps;
        d->tmax.rss_mb = d->rss_mb;
    }
}

ss_status ss_dist_heal_serve(ss_dist_heal *d, ss_error *err) {
    for (;;) {
        int m[2];
        MPI_Bcast(m, 2, MPI_INT, 0, d->cart);
        switch (m[0]) {
        case CMD_STEP:
            do_step(d, m[1], NULL, err);
            break;
        case CMD_UNDO:
            do_undo(d);
            break;
        case CMD_CLOSURE:
            do_closure(d);
            break;
        case CMD_STATS: {
            ss_heal_stats st;
            do_stats(d, &st);
            break;
        }
        case CMD_SYNC:
            do_sync(d, err);
            break;
        case CMD_SURFACE:
            do_surface(d, m[1] & 0xff, (ss_heal_surface_mode)(m[1] >> 8), err);
            break;
        case CMD_CKPT:
            do_checkpoint(d, NULL, NULL, NULL, NULL, 0, 0, NULL, 0, err);
            break;
        case CMD_PIECES:
            do_pieces(d, m[1], err);
            break;
        case CMD_MECH_IN:
            do_mech_in(d);
            break;
        case CMD_MECH_OUT:
            do_mech_out(d);
            break;
        case CMD_COLUMNS:
            do_columns(d, NULL);
            break;
        default: /* CMD_END */
            reduce_timing(d);
            if (m[1]) return ss_error_set(err, (ss_status)m[1], "rank 0 stopped the run");
            return SS_OK;
        }
    }
}

void ss_dist_heal_end(ss_dist_heal *d, ss_status st) {
    if (!d || d->rank != 0) return;
    send_cmd(d, CMD_END, (int)st);
    reduce_timing(d);
    ss_heal_run_set_hooks(d->run, NULL, NULL);
    ss_heal_run_set_checkpoint_hook(d->run, NULL, NULL);
}

void ss_dist_heal_timing_get(const ss_dist_heal *d, ss_dist_heal_timing *t) { *t = d->tmax; }

void ss_dist_heal_free(ss_dist_heal *d) {
    if (!d) return;
    for (int f = 0; f < NFACES; f++) {
        free(d->sbuf[f]);
        free(d->rbuf[f]);
    }
    ss_heal_solver_free(d->s);
    ss_heal_grid_free(d->g);
    ss_heal_solver_free(d->sB);
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) free(d->backup[f]);
    for (int c = 0; c < 3; c++) free(d->disp[c]);
    free(d->top);
    free(d->closed);
    ss_heal_grid_free(d->gB);
    free(d->tsend);
    free(d->trecv);
    free(d->scnt);
    free(d->colbuf);
    free(d->rss_mb);
    if (d->own_wcols) free((void *)d->wcols);
    ss_tri_mesh_free(&d->mesh);
    if (d->zcomm != MPI_COMM_NULL && d->zcomm) MPI_Comm_free(&d->zcomm);
    if (d->cart != MPI_COMM_NULL && d->cart) MPI_Comm_free(&d->cart);
    free(d);
}
