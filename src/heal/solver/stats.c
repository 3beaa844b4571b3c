/* Diagnostics of a healing grid (seed 001 Fig. 4's open area, the wound
 * region, field means, scar volume) in parts that merge exactly: counts are
 * integers and sums of float values are kept as fixed-point integers
 * (limbs of 32 bits covering every float from the smallest subnormal up, with
 * room for 2^40 terms), so a sum does not depend on the order of its terms.
 * The MPI driver (src/mpi) adds its sub-box on each rank and reduces the
 * limbs with integer sums: the figures are bit-identical to a single-process
 * run on any number of ranks. The conversion to double is deterministic (a
 * Horner pass over the limbs, a few units in the last place of the exact sum). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/heal.h"

/* bit 0 of limb 0 weighs 2^-LIMB_BIAS; the smallest float term is 2^-172 x 2^23 */
#define LIMB_BIAS 176
#define LIMB_MASK ((int64_t)0xffffffff)
/* normalise before a limb could overflow (each term adds < 2^32 to a limb) */
#define ADDS_MAX ((int64_t)1 << 30)

static int is_tissue(uint8_t c) { return c != SS_CELL_AIR && c != SS_CELL_BOUND; }

/* The uncovered fraction 1 - e of a surface cell, in [0, 1] (e is the covered
 * fraction of the column's bed: a sub-voxel measure of the open area, smooth
 * as the front crosses a column, where the threshold flips whole columns). */
static float uncovered(float e) { return e >= 1.0f ? 0.0f : e <= 0.0f ? 1.0f : 1.0f - e; }

void ss_heal_stats_acc_init(ss_heal_stats_acc *a) {
    memset(a, 0, sizeof *a);
    a->elev_max = -INFINITY;
}

static float elev_k(const ss_heal_grid *g) { return (float)(SS_HEAL_COLLAGEN_VOLUME * g->dx_mm); }

void ss_heal_elevation_scan(const ss_heal_grid *g, int z0, int z1, float *elev) {
    const float k = elev_k(g), *rho = g->field[SS_HEAL_SCAR], *ad = g->added;
    const size_t ncol = (size_t)g->nx * (size_t)g->ny;
    if (z0 < 0) z0 = 0;
    if (z1 > g->nz) z1 = g->nz;
    for (int z = z1 - 1; z >= z0; z--) {
        const uint8_t *c = g->cell + (size_t)z * ncol;
        const float *r = rho + (size_t)z * ncol;
        const size_t zo = (size_t)z * ncol;
        for (size_t i = 0; i < ncol; i++)
            if (is_tissue(c[i]))
                elev[i] += ss_heal_elevation_term(r[i] + (ad ? ad[zo + i] : 0.0f), c[i], k);
    }
}

static void limbs_normalise(int64_t *l) {
    for (int i = 0; i < SS_HEAL_ACC_LIMBS - 1; i++) {
        int64_t lo = l[i] & LIMB_MASK; /* two's complement: the low 32 bits, >= 0 */
        int64_t carry = (l[i] - lo) / ((int64_t)1 << 32);
        l[i] = lo;
        l[i + 1] += carry;
    }
}

void ss_heal_stats_acc_normalise(ss_heal_stats_acc *a) {
    for (int k = 0; k < SS_HEAL_ACC_SUMS; k++) limbs_normalise(a->sum[k]);
    a->adds = 0;
}

/* Adds the float v exactly; a non-finite value is counted instead. The
 * mantissa and exponent come from the bits (|v| = M 2^(E - 150) for a normal
 * float, M = mant | 2^23, E its biased exponent; mant 2^-149 for a
 * subnormal): the same value, so the same normalised limbs, as frexpf, at a
 * fraction of the cost (the statistics of every area row, issue 25). */
static void limbs_add(ss_heal_stats_acc *a, int k, float v) {
    uint32_t b;
    memcpy(&b, &v, sizeof b);
    const uint32_t ex = (b >> 23) & 0xffu, mant = b & 0x7fffffu;
    if (ex == 0xffu) {
        a->n_nonfinite++;
        return;
    }
    if (ex == 0 && mant == 0) return;
    const int64_t M = ex ? (int64_t)(mant | 0x800000u) : (int64_t)mant;
    const int pos = (ex ? (int)ex : 1) - 150 + LIMB_BIAS; /* >= 27 */
    uint64_t t = (uint64_t)M << (pos % 32);               /* < 2^56 */
    int64_t lo = (int64_t)(t & 0xffffffffu), hi = (int64_t)(t >> 32);
    int64_t *l = a->sum[k] + pos / 32;
    if (!(b >> 31)) {
        l[0] += lo;
        l[1] += hi;
    } else {
        l[0] -= lo;
        l[1] -= hi;
    }
    if (++a->adds >= ADDS_MAX) ss_heal_stats_acc_normalise(a);
}

static double limbs_value(const int64_t *src) {
    int64_t l[SS_HEAL_ACC_LIMBS];
    memcpy(l, src, sizeof l);
    limbs_normalise(l);
    double d = 0.0;
    for (int i = SS_HEAL_ACC_LIMBS - 1; i >= 0; i--) d = d * 4294967296.0 + (double)l[i];
    return ldexp(d, -LIMB_BIAS);
}

/* The tissue cells of column (x, y) at levels [z0, z1): count, field sums, scar maximum. */
static void add_cells(ss_heal_stats_acc *a, const ss_heal_grid *g, int x, int y, int z0, int z1) {
    const float *rho = g->field[SS_HEAL_SCAR];
    for (int z = z0; z < z1; z++) {
        size_t c = ss_heal_idx(g, x, y, z);
        if (!is_tissue(g->cell[c])) continue;
        a->n_tissue++;
        for (int f = 0; f < SS_HEAL_NFIELDS; f++) limbs_add(a, f, g->field[f][c]);
        if (rho[c] > a->scar_max) a->scar_max = rho[c];
    }
}

/* A column's figures from its surface cell: wound column (initial: a WOUND
 * voxel at the surface at t = 0) with the eschar maximum below it, in omega
 * (region), and for either the open test and the uncovered fraction of e. */
static void add_column(ss_heal_stats_acc *a, int initial, int region, float smax, float e,
                       float elev) {
    if (elev > a->elev_max) a->elev_max = elev;
    if (initial) {
        a->n_initial++;
        limbs_add(a, SS_HEAL_ACC_ESCHAR, smax);
        limbs_add(a, SS_HEAL_ACC_ELEV, elev);
        a->n_wcol++;
    }
    if (region) a->n_region++;
    if (initial || region) {
        a->n_open += e < (float)ss_heal_open_threshold();
        limbs_add(a, SS_HEAL_ACC_DEFICIT, uncovered(e));
    }
}

/* Exact sums of many floats in exponent buckets: bucket[E] adds the signed
 * 24-bit mantissas of the terms with biased exponent E (E = 0: subnormals,
 * weighed as E = 1), at most 2^30 terms between folds (< 2^54 per bucket).
 * Folding a bucket into the limbs adds the same integer the terms would have
 * added one by one, so the normalised limbs, and every figure, are the same
 * as with limbs_add; a term costs a load, a mask and an add (the per-row
 * statistics of issue 25: about 3x cheaper than limbs_add on the fields). */
typedef struct {
    int64_t b[SS_HEAL_NFIELDS][256];
    int64_t nonfinite, adds;
} bucket_sums;

static void limbs_add_u64(int64_t *l, int pos, uint64_t x, int neg) {
    /* x 2^(pos - LIMB_BIAS) into the limbs: x split in 32-bit halves, each
     * shifted by pos % 32 (< 2^64) into the limbs it spans */
    const int sh = pos % 32;
    const uint64_t part[2] = {x & 0xffffffffu, x >> 32};
    for (int h = 0; h < 2; h++) {
        const uint64_t t = part[h] << sh;
        int64_t *q = l + pos / 32 + h;
        const int64_t lo = (int64_t)(t & 0xffffffffu), hi = (int64_t)(t >> 32);
        if (neg) {
            q[0] -= lo;
            q[1] -= hi;
        } else {
            q[0] += lo;
            q[1] += hi;
        }
    }
}

static void buckets_fold(ss_heal_stats_acc *a, bucket_sums *bs) {
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) {
        for (int ex = 0; ex < 255; ex++) {
            const int64_t v = bs->b[f][ex];
            if (!v) continue;
            const int pos = (ex ? ex : 1) - 150 + LIMB_BIAS;
            limbs_add_u64(a->sum[f], pos, v < 0 ? (uint64_t)0 - (uint64_t)v : (uint64_t)v, v < 0);
            bs->b[f][ex] = 0;
        }
        limbs_normalise(a->sum[f]);
    }
    a->n_nonfinite += bs->nonfinite;
    bs->nonfinite = 0;
    bs->adds = 0;
}

static inline void bucket_add(bucket_sums *bs, int f, float v) {
    uint32_t b;
    memcpy(&b, &v, sizeof b);
    const uint32_t ex = (b >> 23) & 0xffu, mant = b & 0x7fffffu;
    const int64_t M = (int64_t)(ex ? mant | 0x800000u : mant), neg = -(int64_t)(b >> 31);
    bs->nonfinite += ex == 0xffu; /* counted, and its bucket 255 never folded */
    bs->b[f][ex] += (M ^ neg) - neg;
}

/* The tissue cells of columns [x0, x1) x [y0, y1), plane by plane in memory
 * order (the sums are exact, so the order is free; a column-by-column walk
 * strided through every plane), and each column's elevation, top down in
 * float into elev (row-major over the range) as ss_heal_elevation_scan. */
static void add_planes(ss_heal_stats_acc *a, const ss_heal_grid *g, int x0, int x1, int y0, int y1,
                       float *elev, bucket_sums *bs) {
    const float k = elev_k(g), *rho = g->field[SS_HEAL_SCAR], *ad = g->added;
    const int w = x1 - x0;
    memset(bs, 0, sizeof *bs);
    for (int z = g->nz - 1; z >= 0; z--)
        for (int y = y0; y < y1; y++) {
            const size_t r = ss_heal_idx(g, 0, y, z);
            float *ev = elev + (size_t)(y - y0) * (size_t)w;
            if (bs->adds > ADDS_MAX - g->nx) buckets_fold(a, bs);
            for (int x = x0; x < x1; x++) {
                const size_t c = r + (size_t)x;
                if (!is_tissue(g->cell[c])) continue;
                a->n_tissue++;
                bs->adds++;
                for (int f = 0; f < SS_HEAL_NFIELDS; f++) bucket_add(bs, f, g->field[f][c]);
                if (rho[c] > a->scar_max) a->scar_max = rho[c];
                ev[x - x0] += ss_heal_elevation_term(rho[c] + (ad ? ad[c] : 0.0f), g->cell[c], k);
            }
        }
    buckets_fold(a, bs);
}

void ss_heal_stats_acc_add(ss_heal_stats_acc *a, const ss_heal_grid *g, int x0, int x1, int y0,
                           int y1) {
    const float *e = g->field[SS_HEAL_EPITHELIUM], *p = g->field[SS_HEAL_PLASMA];
    const float *s = g->field[SS_HEAL_ESCHAR];
    if (x0 < 0) x0 = 0;
    if (y0 < 0) y0 = 0;
    if (x1 > g->nx) x1 = g->nx;
    if (y1 > g->ny) y1 = g->ny;
    if (x1 <= x0 || y1 <= y0) return;
    float *elev = calloc((size_t)(x1 - x0) * (size_t)(y1 - y0), sizeof *elev);
    bucket_sums *bs = malloc(sizeof *bs);
    if (!elev || !bs) { /* no memory: a NaN figure rather than a wrong one */
        a->n_nonfinite++;
        free(elev);
        free(bs);
        return;
    }
    add_planes(a, g, x0, x1, y0, y1, elev, bs);
    free(bs);
    for (int y = y0; y < y1; y++) {
        for (int x = x0; x < x1; x++) {
            /* columns: the epithelium is a sheet on the tissue surface, so a
             * column of the wound (a WOUND voxel at the surface at t = 0, or in
             * omega now) is open while the epithelial coverage of its surface
             * cell is below the threshold (add_column). The outermost shell is
             * BOUND: no surface. */
            int ztop = -1;
            for (int z = g->nz - 2; z >= 1; z--)
                if (is_tissue(g->cell[ss_heal_idx(g, x, y, z)])) {
                    ztop = z;
                    break;
                }
            if (ztop >= 0) {
                size_t c0 = ss_heal_idx(g, x, y, ztop);
                const int initial = g->cell[c0] == SS_CELL_WOUND;
                float smax = 0;
                for (int z = ztop; initial && z >= 1; z--) {
                    size_t c = ss_heal_idx(g, x, y, z);
                    if (!is_tissue(g->cell[c])) break;
                    if (s[c] > smax) smax = s[c];
                }
                add_column(a, initial, p[c0] > (float)SS_HEAL_P_MIN, smax, e[c0],
                           elev[(size_t)(y - y0) * (size_t)(x1 - x0) + (size_t)(x - x0)]);
            }
        }
    }
    free(elev);
    ss_heal_stats_acc_normalise(a);
}

void ss_heal_stats_acc_add_stack(ss_heal_stats_acc *a, const ss_heal_grid *g, int x0, int x1,
                                 int y0, int y1, int zoff, int gz, ss_heal_col_state *cols,
                                 int bottom) {
    const float *e = g->field[SS_HEAL_EPITHELIUM], *p = g->field[SS_HEAL_PLASMA];
    const float *s = g->field[SS_HEAL_ESCHAR];
    for (int y = y0; y < y1; y++) {
        for (int x = x0; x < x1; x++) {
            /* the column scan of ss_heal_stats_acc_add, continued level by level */
            ss_heal_col_state *cs = cols + (size_t)(y - y0) * (size_t)(x1 - x0) + (x - x0);
            for (int z = g->nz - 2; z >= 1 && cs->phase < 2; z--) {
                const int Z = z + zoff;
                if (Z < 1 || Z > gz - 2) continue;
                const size_t c = ss_heal_idx(g, x, y, z);
                if (cs->phase == 0) {
                    if (!is_tissue(g->cell[c])) continue;
                    cs->phase = 1;
                    cs->initial = g->cell[c] == SS_CELL_WOUND;
                    cs->region = p[c] > (float)SS_HEAL_P_MIN;
                    cs->esurf = e[c];
                } else if (!is_tissue(g->cell[c])) {
                    cs->phase = 2;
                    break;
                }
                if (s[c] > cs->smax) cs->smax = s[c];
            }
            /* the elevation: every tissue cell of the owned levels, top down */
            const float k = elev_k(g), *rho = g->field[SS_HEAL_SCAR], *ad = g->added;
            for (int z = g->nz - 2; z >= 1; z--) {
                const int Z = z + zoff;
                const size_t c = ss_heal_idx(g, x, y, z);
                if (Z >= 1 && Z <= gz - 2 && is_tissue(g->cell[c]))
                    cs->elev += ss_heal_elevation_term(rho[c] + (ad ? ad[c] : 0.0f), g->cell[c], k);
            }
            if (bottom && cs->phase)
                add_column(a, cs->initial, cs->region, cs->smax, cs->esurf, cs->elev);
            add_cells(a, g, x, y, 1, g->nz - 1);
        }
    }
    ss_heal_stats_acc_normalise(a);
}

void ss_heal_stats_acc_merge(ss_heal_stats_acc *a, const ss_heal_stats_acc *b) {
    a->n_initial += b->n_initial;
    a->n_region += b->n_region;
    a->n_open += b->n_open;
    a->n_wcol += b->n_wcol;
    a->n_tissue += b->n_tissue;
    a->n_nonfinite += b->n_nonfinite;
    for (int k = 0; k < SS_HEAL_ACC_SUMS; k++)
        for (int i = 0; i < SS_HEAL_ACC_LIMBS; i++) a->sum[k][i] += b->sum[k][i];
    if (b->scar_max > a->scar_max) a->scar_max = b->scar_max;
    if (b->elev_max > a->elev_max) a->elev_max = b->elev_max;
    ss_heal_stats_acc_normalise(a);
}

void ss_heal_stats_acc_finish(const ss_heal_stats_acc *a, double dx_mm, ss_heal_stats *st) {
    memset(st, 0, sizeof *st);
    const double area = dx_mm * dx_mm;
    st->initial_area_mm2 = (double)a->n_initial * area;
    st->wound_region_area_mm2 = (double)a->n_region * area;
    st->open_columns_mm2 = (double)a->n_open * area;
    st->open_area_mm2 = limbs_value(a->sum[SS_HEAL_ACC_DEFICIT]) * area;
    const double esum = limbs_value(a->sum[SS_HEAL_ACC_ESCHAR]);
    st->eschar_wound_mean = a->n_wcol ? esum / (double)a->n_wcol : 0.0;
    for (int f = 0; f < SS_HEAL_NFIELDS; f++)
        st->field_mean[f] = a->n_tissue ? limbs_value(a->sum[f]) / (double)a->n_tissue : 0.0;
    st->scar_volume_mm3 = limbs_value(a->sum[SS_HEAL_SCAR]) * area * dx_mm;
    st->scar_max = a->scar_max;
    st->elevation_mean_mm =
        a->n_initial ? limbs_value(a->sum[SS_HEAL_ACC_ELEV]) / (double)a->n_initial : 0.0;
    st->elevation_max_mm = isfinite(a->elev_max) ? a->elev_max : 0.0;
    if (a->n_nonfinite) { /* a blown-up field shows as NaN, never as a plausible figure */
        for (int f = 0; f < SS_HEAL_NFIELDS; f++) st->field_mean[f] = NAN;
        st->scar_volume_mm3 = st->eschar_wound_mean = st->open_area_mm2 = NAN;
        st->elevation_mean_mm = st->elevation_max_mm = NAN;
    }
}

/* Rows of y per slab of the threaded sum, and the cells below which it stays
 * on one thread. */
#define STATS_SLAB_ROWS 8
#define STATS_PAR_MIN_CELLS ((size_t)1 << 15)

/* The whole grid as y slabs on the OpenMP threads, merged in slab order:
 * every part is an exact integer sum, a count or a max (the MPI driver's
 * merge), so the figures are bit-identical to one slab on one thread. */
void ss_heal_stats_compute(const ss_heal_grid *g, ss_heal_stats *st) {
    const int nslab = (g->ny + STATS_SLAB_ROWS - 1) / STATS_SLAB_ROWS;
    const size_t ncell = (size_t)g->nx * (size_t)g->ny * (size_t)g->nz;
    ss_heal_stats_acc a;
    ss_heal_stats_acc_init(&a);
    ss_heal_stats_acc *part = nslab > 1 ? malloc((size_t)nslab * sizeof *part) : NULL;
    if (!part) { /* one slab, or no memory for the parts: the serial sum */
        ss_heal_stats_acc_add(&a, g, 0, g->nx, 0, g->ny);
        ss_heal_stats_acc_finish(&a, g->dx_mm, st);
        return;
    }
#pragma omp parallel for schedule(dynamic, 1) if (ncell >= STATS_PAR_MIN_CELLS)
    for (int i = 0; i < nslab; i++) {
        ss_heal_stats_acc_init(&part[i]);
        ss_heal_stats_acc_add(&part[i], g, 0, g->nx, i * STATS_SLAB_ROWS,
                              (i + 1) * STATS_SLAB_ROWS);
    }
    for (int i = 0; i < nslab; i++) ss_heal_stats_acc_merge(&a, &part[i]);
    free(part);
    ss_heal_stats_acc_finish(&a, g->dx_mm, st);
}
