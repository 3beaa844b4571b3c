/* Healing checkpoints in pieces: the state of checkpoint.c (cell states,
 * every field and velocity, and the run's metadata) cut into boxes, one file
 * per box plus a header that names the whole grid, the process grid and
 * every piece's box, size and CRC-32 (formats in skinsim/heal_io.h). It lets
 * the MPI driver write and read checkpoints without any process holding the
 * whole grid, and resume on any number of ranks: a box is read from the
 * pieces that overlap it, whatever split wrote them.
 *
 * Design: a piece is streamed row by row (x rows of its box), through the
 * CRC, so writing needs no copy of the box and reading a small box out of a
 * large piece costs one pass over that piece in constant memory. Everything
 * is checked before a value is trusted: the header's own CRC and that its
 * boxes tile the grid exactly (volumes add up, no two overlap), each piece's
 * own header against the checkpoint's (grid, box, step, time, arrays), its
 * size, and its CRC against the file's and the header's. Reading streams the
 * values into the caller's grid before the CRC at the end of the piece is
 * known: on an error the box holds garbage and the caller drops it. The
 * header is written last, by one writer, to a temporary name and renamed:
 * a checkpoint exists exactly when its header does. Gave up: pieces are not
 * compressed, and the tiling check is quadratic in the piece count (0.1 s at
 * the SS_HEAL_CKPT_MAX_PIECES limit). */
#define _POSIX_C_SOURCE 200809L
#include "checkpoint_internal.h"
#include "../solver/heal_internal.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define PC_MAGIC "SSHEALPC"
#define PH_MAGIC "SSHEALPH"
#define PC_VERSION 1u
#define PC_HEAD_BYTES (8 + 4 + 12 + 4 + 12 + 12 + 8 + 8 + 4)
#define PH_FIXED_BYTES (8 + 4 + 16 + 24 + 8 + 4 + 8 + 4 + 12 + 4)
#define PH_PIECE_BYTES (24 + 8 + 4)

void ss_heal_ckpt_header_path(char *buf, size_t len, const char *run_dir, uint64_t step) {
    snprintf(buf, len, "%s/checkpoints/ckpt_%012llu%s", run_dir, (unsigned long long)step,
             CK_HEAD_EXT);
}

void ss_heal_ckpt_piece_path(char *buf, size_t len, const char *run_dir, uint64_t step, int index) {
    snprintf(buf, len, "%s/checkpoints/ckpt_%012llu_p%06d%s", run_dir, (unsigned long long)step,
             index, CK_PIECE_EXT);
}

void ss_heal_ckpt_header_free(ss_heal_ckpt_header *h) {
    if (!h) return;
    free(h->scenario);
    free(h->params_json);
    free(h->aux);
    free(h->piece);
    memset(h, 0, sizeof *h);
}

void ss_heal_ckpt_split(const int whole[3], const int dims[3], const int coords[3], int lo[3],
                        int n[3]) {
    for (int a = 0; a < 3; a++) {
        lo[a] = (int)((long long)whole[a] * coords[a] / dims[a]);
        n[a] = (int)((long long)whole[a] * (coords[a] + 1) / dims[a]) - lo[a];
    }
}

static size_t box_cells(const int n[3]) { return (size_t)n[0] * (size_t)n[1] * (size_t)n[2]; }

/* The flags word after t_days: bit 0 the three velocity arrays, bit 1 the
 * keloid's added volume (docs/heal-model.md [D16]) follow the fields. */
static int array_count(int vel) { return SS_HEAL_NFIELDS + 3 * (vel & 1) + ((vel >> 1) & 1); }

static int grid_flags(const ss_heal_grid *g) {
    return (g->velocity[0] && g->velocity[1] && g->velocity[2]) | (g->added ? 2 : 0);
}

static uint64_t piece_bytes(const int n[3], int vel) {
    return PC_HEAD_BYTES + (uint64_t)box_cells(n) * (1 + 4 * (uint64_t)array_count(vel)) + 4;
}

/* The arrays of a grid in file order: cells, fields, velocities. */
static int grid_arrays(const ss_heal_grid *g, int vel, void **a) {
    int k = 0;
    a[k++] = g->cell;
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) a[k++] = g->field[f];
    for (int c = 0; (vel & 1) && c < 3; c++) a[k++] = g->velocity[c];
    if (vel & 2) a[k++] = g->added;
    return k;
}

/* ---- tiling -------------------------------------------------------------------- */

const char *ss_heal__boxes_tile(const int whole[3], int nbox, const void *base, size_t stride,
                                int *bad) {
    const unsigned char *b = base;
#define BOX(i) ((const ss_heal_box *)(const void *)(b + (size_t)(i)*stride))
    uint64_t vol = 0;
    for (int i = 0; i < nbox; i++) {
        *bad = i;
        const ss_heal_box *p = BOX(i);
        for (int a = 0; a < 3; a++)
            if (p->n[a] < 1 || p->lo[a] < 0 || p->lo[a] > whole[a] - p->n[a])
                return "lies outside the grid";
        vol += box_cells(p->n);
    }
    for (int i = 0; i < nbox; i++)
        for (int j = i + 1; j < nbox; j++) {
            const ss_heal_box *p = BOX(i), *q = BOX(j);
            int sep = 0;
            for (int a = 0; a < 3 && !sep; a++)
                sep = p->lo[a] + p->n[a] <= q->lo[a] || q->lo[a] + q->n[a] <= p->lo[a];
            if (!sep) {
                *bad = j;
                return "overlaps another piece";
            }
        }
#undef BOX
    *bad = -1;
    if (vol != (uint64_t)box_cells(whole)) return "pieces leave part of the grid uncovered";
    return NULL;
}

/* ---- writing ------------------------------------------------------------------- */

ss_status ss_heal_ckpt_piece_write(const char *run_dir, int index, const ss_heal_grid *g,
                                   const int org[3], const int lo[3], const int n[3],
                                   const int whole[3], ss_heal_ckpt_piece *info, ss_error *err) {
    char dir[4096], path[4400];
    ss_heal_ckpt_piece_path(path, sizeof path, run_dir, g ? g->step : 0, index);
    if (!g || !g->cell) return ss_error_set(err, SS_ERR_INPUT, "%s: no grid to checkpoint", path);
    const int gn[3] = {g->nx, g->ny, g->nz};
    if (index < 0 || index >= SS_HEAL_CKPT_MAX_PIECES)
        return ss_error_set(err, SS_ERR_INPUT, "%s: piece index %d out of range", path, index);
    for (int a = 0; a < 3; a++)
        if (n[a] < 1 || lo[a] < 0 || lo[a] > whole[a] - n[a] || lo[a] < org[a] ||
            lo[a] - org[a] > gn[a] - n[a])
            return ss_error_set(err, SS_ERR_INPUT,
                                "%s: box %d..%d on axis %d is not inside the %d cells of the grid "
                                "or the %d held from %d",
                                path, lo[a], lo[a] + n[a], a, whole[a], gn[a], org[a]);
    for (int f = 0; f < SS_HEAL_NFIELDS; f++)
        if (!g->field[f])
            return ss_error_set(err, SS_ERR_INPUT, "%s: grid field %d missing", path, f);
    int vel = grid_flags(g);
    snprintf(dir, sizeof dir, "%s/checkpoints", run_dir);
    ss_status st = ss_mkdir_p(dir, err);
    if (st) return st;
    ss_atomic_file af;
    if ((st = ss_atomic_open(&af, path, err))) return st;
    wbuf w = {af.fp, crc32_z(0L, Z_NULL, 0), 0};
    wraw(&w, PC_MAGIC, 8);
    wu32(&w, PC_VERSION);
    for (int a = 0; a < 3; a++) wu32(&w, (uint32_t)whole[a]);
    wu32(&w, SS_HEAL_NFIELDS);
    for (int a = 0; a < 3; a++) wu32(&w, (uint32_t)lo[a]);
    for (int a = 0; a < 3; a++) wu32(&w, (uint32_t)n[a]);
    wu64(&w, g->step);
    wf64(&w, g->t_days);
    wu32(&w, (uint32_t)vel);
    void *arr[SS_HEAL_NFIELDS + 5];
    int na = grid_arrays(g, vel, arr);
    /* a z plane of the box at a time (its x rows gathered), so the CRC and
     * stdio see large blocks */
    const size_t row = (size_t)n[0], plane = row * (size_t)n[1];
    float *buf = malloc(plane * sizeof *buf);
    if (!buf) {
        ss_atomic_abort(&af);
        return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
    }
    for (int k = 0; k < na; k++)
        for (int z = 0; z < n[2]; z++) {
            for (int y = 0; y < n[1]; y++) {
                size_t i = ss_heal_idx(g, lo[0] - org[0], lo[1] - org[1] + y, lo[2] - org[2] + z);
                if (k == 0)
                    memcpy((unsigned char *)buf + (size_t)y * row, g->cell + i, row);
                else
                    memcpy(buf + (size_t)y * row, (const float *)arr[k] + i, row * sizeof *buf);
            }
            if (k == 0)
                wraw(&w, buf, plane);
            else
                wf32s(&w, buf, plane);
        }
    free(buf);
    uint32_t crc;
    if ((st = ck_finish(&w, &af, path, &crc, err))) return st;
    if (info) {
        memcpy(info->lo, lo, sizeof info->lo);
        memcpy(info->n, n, sizeof info->n);
        info->bytes = piece_bytes(n, vel);
        info->crc = crc;
    }
    return SS_OK;
}

static const char *header_values_error(const ss_heal_ckpt_header *h) {
    for (int a = 0; a < 3; a++)
        if (h->whole[a] < 1 || h->dims[a] < 1) return "grid or process grid dimensions invalid";
    if ((double)h->whole[0] * h->whole[1] * h->whole[2] > (double)SS_HEAL_MAX_CELLS)
        return "grid larger than any heal grid";
    if (!(h->dx_mm > 0) || !isfinite(h->dx_mm) || !isfinite(h->t_days) ||
        !isfinite(h->skin_top_mm) || !(h->dt_days > 0) || !isfinite(h->dt_days) ||
        (h->velocity < 0 || h->velocity > 3))
        return "header values are invalid";
    if (h->npieces < 1 || h->npieces > SS_HEAL_CKPT_MAX_PIECES || !h->piece ||
        (long long)h->dims[0] * h->dims[1] * h->dims[2] != h->npieces)
        return "piece count does not match the process grid";
    return NULL;
}

static ss_status tiling_check(const char *path, const ss_heal_ckpt_header *h, ss_error *err) {
    int bad;
    const char *why = ss_heal__boxes_tile(h->whole, h->npieces, h->piece, sizeof *h->piece, &bad);
    if (!why) return SS_OK;
    if (bad < 0)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: the %d pieces do not tile the %dx%dx%d grid (%s)", path,
                            h->npieces, h->whole[0], h->whole[1], h->whole[2], why);
    const ss_heal_ckpt_piece *p = &h->piece[bad];
    return ss_error_set(err, SS_ERR_INPUT,
                        "%s: the pieces do not tile the %dx%dx%d grid: piece %d (box %d,%d,%d size "
                        "%dx%dx%d) %s",
                        path, h->whole[0], h->whole[1], h->whole[2], bad, p->lo[0], p->lo[1],
                        p->lo[2], p->n[0], p->n[1], p->n[2], why);
}

ss_status ss_heal_ckpt_header_save(const char *run_dir, const ss_heal_ckpt_header *h, int keep,
                                   ss_error *err) {
    char dir[4096], path[4400];
    ss_heal_ckpt_header_path(path, sizeof path, run_dir, h->step);
    const char *why = header_values_error(h);
    if (why) return ss_error_set(err, SS_ERR_INPUT, "%s: %s", path, why);
    ss_status st = tiling_check(path, h, err);
    if (st) return st;
    snprintf(dir, sizeof dir, "%s/checkpoints", run_dir);
    if ((st = ss_mkdir_p(dir, err))) return st;
    ss_atomic_file af;
    if ((st = ss_atomic_open(&af, path, err))) return st;
    wbuf w = {af.fp, crc32_z(0L, Z_NULL, 0), 0};
    wraw(&w, PH_MAGIC, 8);
    wu32(&w, PC_VERSION);
    for (int a = 0; a < 3; a++) wu32(&w, (uint32_t)h->whole[a]);
    wu32(&w, SS_HEAL_NFIELDS);
    wf64(&w, h->dx_mm);
    wf64(&w, h->skin_top_mm);
    wf64(&w, h->t_days);
    wu64(&w, h->step);
    wu32(&w, (uint32_t)h->scheme);
    wf64(&w, h->dt_days);
    wu32(&w, (uint32_t)h->velocity);
    for (int a = 0; a < 3; a++) wu32(&w, (uint32_t)h->dims[a]);
    wu32(&w, (uint32_t)h->npieces);
    wstr(&w, h->scenario);
    wstr(&w, h->params_json);
    wstr(&w, h->aux);
    for (int i = 0; i < h->npieces; i++) {
        const ss_heal_ckpt_piece *p = &h->piece[i];
        for (int a = 0; a < 3; a++) wu32(&w, (uint32_t)p->lo[a]);
        for (int a = 0; a < 3; a++) wu32(&w, (uint32_t)p->n[a]);
        wu64(&w, p->bytes);
        wu32(&w, p->crc);
    }
    if ((st = ck_finish(&w, &af, path, NULL, err))) return st;
    ss_heal__ckpt_prune(dir, keep, (unsigned long long)h->step);
    return SS_OK;
}

ss_status ss_heal_checkpoint_save_pieces(const char *run_dir, const ss_heal_grid *g,
                                         const char *scenario, const char *params_json, int scheme,
                                         double dt_days, const char *aux, const int dims[3],
                                         int keep, ss_error *err) {
    if (!g || !g->cell)
        return ss_error_set(err, SS_ERR_INPUT, "%s: no grid to checkpoint", run_dir);
    const int whole[3] = {g->nx, g->ny, g->nz}, org[3] = {0, 0, 0};
    for (int a = 0; a < 3; a++)
        if (dims[a] < 1 || dims[a] > whole[a])
            return ss_error_set(err, SS_ERR_INPUT,
                                "checkpoint pieces %dx%dx%d: need 1 to %d, %d and %d pieces per "
                                "axis for the %dx%dx%d grid",
                                dims[0], dims[1], dims[2], whole[0], whole[1], whole[2], whole[0],
                                whole[1], whole[2]);
    long long np = (long long)dims[0] * dims[1] * dims[2];
    if (np > SS_HEAL_CKPT_MAX_PIECES)
        return ss_error_set(err, SS_ERR_INPUT, "checkpoint pieces %dx%dx%d: more than %d pieces",
                            dims[0], dims[1], dims[2], SS_HEAL_CKPT_MAX_PIECES);
    ss_heal_ckpt_header h = {0};
    h.piece = calloc((size_t)np, sizeof *h.piece);
    if (!h.piece) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    ss_status st = SS_OK;
    int i = 0;
    for (int z = 0; !st && z < dims[2]; z++)
        for (int y = 0; !st && y < dims[1]; y++)
            for (int x = 0; !st && x < dims[0]; x++, i++) {
                const int c[3] = {x, y, z};
                int lo[3], n[3];
                ss_heal_ckpt_split(whole, dims, c, lo, n);
                st = ss_heal_ckpt_piece_write(run_dir, i, g, org, lo, n, whole, &h.piece[i], err);
            }
    if (!st) {
        memcpy(h.whole, whole, sizeof h.whole);
        memcpy(h.dims, dims, sizeof h.dims);
        h.dx_mm = g->dx_mm, h.skin_top_mm = g->skin_top_mm, h.t_days = g->t_days;
        h.step = g->step, h.scheme = scheme, h.dt_days = dt_days;
        h.velocity = grid_flags(g);
        h.scenario = (char *)scenario, h.params_json = (char *)params_json;
        h.aux = (char *)(aux ? aux : "");
        h.npieces = (int)np;
        st = ss_heal_ckpt_header_save(run_dir, &h, keep, err);
    }
    free(h.piece);
    return st;
}

/* ---- reading ------------------------------------------------------------------- */

ss_status ss_heal_ckpt_header_read(const char *path, ss_heal_ckpt_header *out, ss_error *err) {
    memset(out, 0, sizeof *out);
    size_t len = 0;
    char *data;
    ss_status st = ss_heal__ck_load(path, PH_MAGIC, PC_VERSION, 12, PH_FIXED_BYTES + 12 + 4,
                                    "the header of a skinsim checkpoint in pieces",
                                    "checkpoint header", &data, &len, err);
    if (st) return st;
    rbuf r = {(const unsigned char *)data, len, 12};
#define BAD(...)                                                                                   \
    do {                                                                                           \
        st = ss_error_set(err, SS_ERR_INPUT, __VA_ARGS__);                                         \
        goto done;                                                                                 \
    } while (0)
    r.len = len - 4;
    for (int a = 0; a < 3; a++) out->whole[a] = (int)ru32(&r);
    uint32_t nf = ru32(&r);
    if (nf != SS_HEAL_NFIELDS)
        BAD("%s: checkpoint has %u fields, this build has %d", path, nf, SS_HEAL_NFIELDS);
    out->dx_mm = rf64(&r), out->skin_top_mm = rf64(&r), out->t_days = rf64(&r);
    out->step = ru64(&r);
    out->scheme = (int)ru32(&r);
    out->dt_days = rf64(&r);
    out->velocity = (int)ru32(&r);
    for (int a = 0; a < 3; a++) out->dims[a] = (int)ru32(&r);
    uint32_t np = ru32(&r);
    out->npieces = np > SS_HEAL_CKPT_MAX_PIECES ? -1 : (int)np;
    out->scenario = rstr(&r);
    out->params_json = out->scenario ? rstr(&r) : NULL;
    out->aux = out->params_json ? rstr(&r) : NULL;
    if (!out->aux) BAD("%s: truncated checkpoint header (strings)", path);
    if (out->npieces < 1) BAD("%s: checkpoint header piece count %u invalid", path, np);
    if (r.len - r.pos != (size_t)out->npieces * PH_PIECE_BYTES)
        BAD("%s: checkpoint header piece list malformed (%zu bytes for %d pieces)", path,
            r.len - r.pos, out->npieces);
    if (!(out->piece = calloc((size_t)out->npieces, sizeof *out->piece)))
        BAD("%s: out of memory", path);
    const char *why = header_values_error(out);
    if (why) BAD("%s: %s", path, why);
    for (int i = 0; i < out->npieces; i++) {
        ss_heal_ckpt_piece *p = &out->piece[i];
        for (int a = 0; a < 3; a++) p->lo[a] = (int)ru32(&r);
        for (int a = 0; a < 3; a++) p->n[a] = (int)ru32(&r);
        p->bytes = ru64(&r);
        p->crc = ru32(&r);
    }
    if ((st = tiling_check(path, out, err))) goto done;
    for (int i = 0; i < out->npieces; i++)
        if (out->piece[i].bytes != piece_bytes(out->piece[i].n, out->velocity))
            BAD("%s: piece %d's size %llu does not match its box", path, i,
                (unsigned long long)out->piece[i].bytes);
#undef BAD
done:
    free(data);
    if (st) ss_heal_ckpt_header_free(out);
    return st;
}

/* One piece, checked against piece i of h: its header, its size and, when
 * full, its CRC over every byte; with g, the part of the piece inside the
 * clipped box clo..chi (whole-grid indices) is copied into g (origin org). */
static ss_status piece_stream(const char *run_dir, const ss_heal_ckpt_header *h, int i, int full,
                              ss_heal_grid *g, const int org[3], const int clo[3], const int chi[3],
                              ss_error *err) {
    char path[4400];
    ss_heal_ckpt_piece_path(path, sizeof path, run_dir, h->step, i);
    const ss_heal_ckpt_piece *p = &h->piece[i];
    struct stat sb = {0};
    if (lstat(path, &sb) != 0 && errno == ENOENT)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: piece %d of %d of the checkpoint of step %llu is missing (%s)",
                            path, i, h->npieces, (unsigned long long)h->step, strerror(errno));
    /* regular files only, never blocking (a named pipe is refused at once) */
    FILE *f = ss_input_open(path, NULL, err);
    if (!f) return err && err->code ? err->code : SS_ERR_INPUT;
    setvbuf(f, NULL, _IOFBF, (size_t)1 << 20); /* rows are small: read in large blocks */
    ss_status st = SS_OK;
    unsigned char *row = NULL;
#define BAD(...)                                                                                   \
    do {                                                                                           \
        st = ss_error_set(err, SS_ERR_INPUT, __VA_ARGS__);                                         \
        goto done;                                                                                 \
    } while (0)
    if (fstat(fileno(f), &sb) || (uint64_t)sb.st_size != p->bytes)
        BAD("%s: piece is %lld bytes, the checkpoint header says %llu (truncated or foreign)", path,
            (long long)sb.st_size, (unsigned long long)p->bytes);
    unsigned char hb[PC_HEAD_BYTES];
    if (fread(hb, 1, sizeof hb, f) != sizeof hb) BAD("%s: truncated checkpoint piece", path);
    if (memcmp(hb, PC_MAGIC, 8)) BAD("%s: not a skinsim checkpoint piece (bad magic)", path);
    rbuf r = {hb, sizeof hb, 8};
    uint32_t version = ru32(&r);
    if (version != PC_VERSION)
        BAD("%s: checkpoint piece version %u is not supported (this build reads %u)", path, version,
            PC_VERSION);
    int wh[3], lo[3], n[3];
    for (int a = 0; a < 3; a++) wh[a] = (int)ru32(&r);
    uint32_t nf = ru32(&r);
    for (int a = 0; a < 3; a++) lo[a] = (int)ru32(&r);
    for (int a = 0; a < 3; a++) n[a] = (int)ru32(&r);
    uint64_t step = ru64(&r);
    double t = rf64(&r);
    uint32_t vel = ru32(&r);
    if (memcmp(wh, h->whole, sizeof wh) || nf != SS_HEAL_NFIELDS)
        BAD("%s: piece of a %dx%dx%d grid with %u fields, the checkpoint header says %dx%dx%d with "
            "%d",
            path, wh[0], wh[1], wh[2], nf, h->whole[0], h->whole[1], h->whole[2], SS_HEAL_NFIELDS);
    if (memcmp(lo, p->lo, sizeof lo) || memcmp(n, p->n, sizeof n))
        BAD("%s: piece holds box %d,%d,%d size %dx%dx%d, the checkpoint header says %d,%d,%d size "
            "%dx%dx%d",
            path, lo[0], lo[1], lo[2], n[0], n[1], n[2], p->lo[0], p->lo[1], p->lo[2], p->n[0],
            p->n[1], p->n[2]);
    if (step != h->step || memcmp(&t, &h->t_days, sizeof t))
        BAD("%s: piece of step %llu (day %.17g), the checkpoint header says step %llu (day %.17g)",
            path, (unsigned long long)step, t, (unsigned long long)h->step, h->t_days);
    if (vel != (uint32_t)h->velocity)
        BAD("%s: piece %s velocities, the checkpoint header says it %s", path,
            vel ? "has" : "lacks", h->velocity ? "has them" : "does not");
    if (!full && !g) { /* the quick check: the stored CRC is the header's */
        unsigned char cb[4];
        if (fseek(f, -4, SEEK_END) || fread(cb, 1, 4, f) != 4)
            BAD("%s: truncated checkpoint piece", path);
        if (ck_get_u32(cb) != p->crc)
            BAD("%s: piece CRC-32 %08x, the checkpoint header says %08x", path, ck_get_u32(cb),
                p->crc);
        goto done;
    }
    uLong crc = crc32_z(crc32_z(0L, Z_NULL, 0), hb, sizeof hb);
    int inside = g != NULL;
    int olo[3], ohi[3]; /* the part of this piece inside the box, whole-grid indices */
    for (int a = 0; a < 3 && inside; a++) {
        olo[a] = lo[a] > clo[a] ? lo[a] : clo[a];
        ohi[a] = lo[a] + n[a] < chi[a] ? lo[a] + n[a] : chi[a];
        inside = olo[a] < ohi[a];
    }
    void *arr[SS_HEAL_NFIELDS + 5];
    int na = g ? grid_arrays(g, (int)vel, arr) : 1 + array_count((int)vel);
    if (!(row = malloc((size_t)n[0] * 4))) BAD("%s: out of memory", path);
    for (int k = 0; k < na; k++) {
        size_t es = k == 0 ? 1 : 4, rb = (size_t)n[0] * es;
        for (int z = 0; z < n[2]; z++)
            for (int y = 0; y < n[1]; y++) {
                if (fread(row, 1, rb, f) != rb) BAD("%s: truncated checkpoint piece", path);
                crc = crc32_z(crc, row, rb);
                const int Z = lo[2] + z, Y = lo[1] + y;
                if (!inside || Z < olo[2] || Z >= ohi[2] || Y < olo[1] || Y >= ohi[1]) continue;
                size_t d = ss_heal_idx(g, olo[0] - org[0], Y - org[1], Z - org[2]);
                size_t m = (size_t)(ohi[0] - olo[0]), s = (size_t)(olo[0] - lo[0]);
                if (k == 0)
                    memcpy(g->cell + d, row + s, m);
                else
                    ck_get_f32s((float *)arr[k] + d, row + 4 * s, m);
            }
    }
    unsigned char cb[4];
    if (fread(cb, 1, 4, f) != 4) BAD("%s: truncated checkpoint piece", path);
    if ((uint32_t)crc != ck_get_u32(cb) || ck_get_u32(cb) != p->crc)
        BAD("%s: checkpoint piece is corrupt (CRC-32 %08x, the piece says %08x, its header %08x)",
            path, (uint32_t)crc, ck_get_u32(cb), p->crc);
#undef BAD
done:
    free(row);
    fclose(f);
    return st;
}

ss_status ss_heal_ckpt_pieces_check(const char *run_dir, const ss_heal_ckpt_header *h,
                                    int verify_crc, ss_error *err) {
    for (int i = 0; i < h->npieces; i++) {
        ss_status st = piece_stream(run_dir, h, i, verify_crc, NULL, NULL, NULL, NULL, err);
        if (st) return st;
    }
    return SS_OK;
}

ss_status ss_heal_ckpt_read_box(const char *run_dir, const ss_heal_ckpt_header *h, ss_heal_grid *g,
                                const int org[3], const int lo[3], const int n[3], ss_error *err) {
    char path[4400];
    ss_heal_ckpt_header_path(path, sizeof path, run_dir, h->step);
    if (!g || !g->cell) return ss_error_set(err, SS_ERR_INPUT, "%s: no grid to read into", path);
    const int gn[3] = {g->nx, g->ny, g->nz};
    int clo[3], chi[3];
    for (int a = 0; a < 3; a++) {
        clo[a] = lo[a] > 0 ? lo[a] : 0;
        chi[a] = lo[a] + n[a] < h->whole[a] ? lo[a] + n[a] : h->whole[a];
        if (clo[a] >= chi[a] || clo[a] < org[a] || chi[a] - org[a] > gn[a])
            return ss_error_set(err, SS_ERR_INPUT,
                                "%s: box %d..%d on axis %d is empty in the %d cells of the "
                                "checkpoint's grid or not inside the %d held from %d",
                                path, lo[a], lo[a] + n[a], a, h->whole[a], gn[a], org[a]);
    }
    size_t ng = (size_t)gn[0] * gn[1] * gn[2];
    if ((h->velocity & 2) && !g->added && !(g->added = calloc(ng, sizeof(float))))
        return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory for the added volume", path);
    for (int c = 0; (h->velocity & 1) && c < 3; c++)
        if (!g->velocity[c] && !(g->velocity[c] = calloc(ng, sizeof(float))))
            return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory for velocities", path);
    for (int c = 0; !(h->velocity & 1) && c < 3; c++)
        for (int z = clo[2]; g->velocity[c] && z < chi[2]; z++)
            for (int y = clo[1]; y < chi[1]; y++)
                memset(g->velocity[c] + ss_heal_idx(g, clo[0] - org[0], y - org[1], z - org[2]), 0,
                       (size_t)(chi[0] - clo[0]) * sizeof(float));
    for (int i = 0; i < h->npieces; i++) {
        const ss_heal_ckpt_piece *p = &h->piece[i];
        int hit = 1;
        for (int a = 0; a < 3 && hit; a++) hit = p->lo[a] < chi[a] && clo[a] < p->lo[a] + p->n[a];
        if (!hit) continue;
        ss_status st = piece_stream(run_dir, h, i, 1, g, org, clo, chi, err);
        if (st) return st;
    }
    g->t_days = h->t_days;
    g->step = h->step;
    g->skin_top_mm = h->skin_top_mm;
    return SS_OK;
}

ss_status ss_heal_checkpoint_read_pieces(const char *run_dir, uint64_t step,
                                         ss_heal_checkpoint *out, ss_error *err) {
    memset(out, 0, sizeof *out);
    char path[4400];
    ss_heal_ckpt_header_path(path, sizeof path, run_dir, step);
    ss_heal_ckpt_header h;
    ss_status st = ss_heal_ckpt_header_read(path, &h, err);
    if (st) return st;
    if (h.step != step) {
        st = ss_error_set(err, SS_ERR_INPUT, "%s: header of step %llu under the name of step %llu",
                          path, (unsigned long long)h.step, (unsigned long long)step);
        ss_heal_ckpt_header_free(&h);
        return st;
    }
    /* every piece present and agreeing before the grid is allocated */
    if (!(st = ss_heal_ckpt_pieces_check(run_dir, &h, 0, err))) {
        const int org[3] = {0, 0, 0};
        out->grid = ss_heal_grid_create(h.whole[0], h.whole[1], h.whole[2], h.dx_mm, err);
        if (!out->grid) st = err && err->code ? err->code : SS_ERR_RUNTIME;
        if (!st) st = ss_heal_ckpt_read_box(run_dir, &h, out->grid, org, org, h.whole, err);
    }
    if (!st) {
        out->scenario = h.scenario, out->params_json = h.params_json, out->aux = h.aux;
        h.scenario = h.params_json = h.aux = NULL;
        out->scheme = h.scheme;
        out->dt_days = h.dt_days;
    }
    ss_heal_ckpt_header_free(&h);
    if (st) ss_heal_checkpoint_free(out);
    return st;
}
