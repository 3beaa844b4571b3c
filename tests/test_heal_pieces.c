/* Tests for the healing grid in pieces (skinsim/heal_io.h): checkpoints
 * written as per-box pieces under one split read back bit-identically under
 * every other split, with halos clipped at the grid, as the whole grid and
 * equal to the whole-grid checkpoint of the same state; only the pieces a
 * box overlaps are opened; a missing, truncated, flipped, foreign-step or
 * foreign-grid piece and a damaged or non-tiling header are refused naming
 * the file; the newest complete checkpoint of either kind is found and a
 * damaged one skipped; pruning keeps two. And the .pvti reader: pieces joined
 * equal the gathered .vti, with its errors. */
#define _POSIX_C_SOURCE 200809L
#include "testutil.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>

#include "skinsim/heal.h"
#include "skinsim/heal_io.h"

static const int SPLITS[][3] = {{1, 1, 1}, {2, 1, 1}, {2, 2, 1}, {1, 1, 3}, {3, 2, 2}};
#define NSPLITS ((int)(sizeof SPLITS / sizeof SPLITS[0]))
static const char *PJ = "{\"scenario\": \"scab\"}";

/* Box + one-cell halo of every box of split `rd` read from the checkpoint
 * (written under any split) into a grid of its own: the cells inside the
 * whole grid equal g's, the halo outside it keeps its sentinel. */
static void check_boxes(const char *dir, const ss_heal_ckpt_header *h, const ss_heal_grid *g,
                        const int rd[3]) {
    const int whole[3] = {g->nx, g->ny, g->nz};
    ss_error err;
    for (int z = 0; z < rd[2]; z++)
        for (int y = 0; y < rd[1]; y++)
            for (int x = 0; x < rd[0]; x++) {
                const int c[3] = {x, y, z};
                int lo[3], n[3], org[3], hn[3];
                ss_heal_ckpt_split(whole, rd, c, lo, n);
                for (int a = 0; a < 3; a++) org[a] = lo[a] - 1, hn[a] = n[a] + 2;
                ss_heal_grid *b = ss_heal_grid_create(hn[0] < 3 ? 3 : hn[0], hn[1] < 3 ? 3 : hn[1],
                                                      hn[2] < 3 ? 3 : hn[2], g->dx_mm, &err);
                assert_non_null(b);
                size_t nb = (size_t)b->nx * b->ny * b->nz;
                memset(b->cell, 0xEE, nb);
                for (size_t i = 0; i < nb; i++) b->field[0][i] = -77.0f;
                assert_int_equal(ss_heal_ckpt_read_box(dir, h, b, org, org, hn, &err), SS_OK);
                assert_true(b->step == g->step && b->t_days == g->t_days);
                for (int k = 0; k < hn[2]; k++)
                    for (int j = 0; j < hn[1]; j++)
                        for (int i = 0; i < hn[0]; i++) {
                            const int X = org[0] + i, Y = org[1] + j, Z = org[2] + k;
                            size_t bi = ss_heal_idx(b, i, j, k);
                            if (X < 0 || Y < 0 || Z < 0 || X >= g->nx || Y >= g->ny || Z >= g->nz) {
                                assert_int_equal(b->cell[bi], 0xEE);
                                assert_true(b->field[0][bi] == -77.0f);
                                continue;
                            }
                            size_t gi = ss_heal_idx(g, X, Y, Z);
                            assert_int_equal(b->cell[bi], g->cell[gi]);
                            for (int f = 0; f < SS_HEAL_NFIELDS; f++)
                                assert_memory_equal(&b->field[f][bi], &g->field[f][gi], 4);
                            for (int v = 0; g->velocity[0] && v < 3; v++)
                                assert_memory_equal(&b->velocity[v][bi], &g->velocity[v][gi], 4);
                        }
                ss_heal_grid_free(b);
            }
}

static void test_pieces_any_split(void **state) {
    (void)state;
    ss_error err;
    for (int vel = 0; vel < 2; vel++) {
        ss_heal_grid *g = tu_heal_grid_noisy(13, 11, 7, 0.3, 5 + (uint64_t)vel, vel);
        /* the whole-grid checkpoint of the same state, the reference */
        char *wdir = tu_tmpdir("pieces-whole");
        assert_int_equal(ss_heal_checkpoint_save(wdir, g, "scab", PJ, SS_HEAL_EXPLICIT, 0.002,
                                                 "{\"a\":1}", 2, &err),
                         SS_OK);
        ss_heal_checkpoint ref;
        assert_int_equal(ss_heal_checkpoint_load_latest(wdir, &ref, NULL, 0, &err), SS_OK);
        for (int w = 0; w < NSPLITS; w++) {
            char *dir = tu_tmpdir("pieces");
            assert_int_equal(ss_heal_checkpoint_save_pieces(dir, g, "scab", PJ, SS_HEAL_EXPLICIT,
                                                            0.002, "{\"a\":1}", SPLITS[w], 2, &err),
                             SS_OK);
            /* the whole grid, through the newest-checkpoint lookup */
            ss_heal_checkpoint ck;
            char note[256];
            assert_int_equal(ss_heal_checkpoint_load_latest(dir, &ck, note, sizeof note, &err),
                             SS_OK);
            assert_string_equal(note, "");
            tu_assert_heal_grids_equal(g, ck.grid);
            tu_assert_heal_grids_equal(ref.grid, ck.grid);
            assert_string_equal(ck.scenario, "scab");
            assert_string_equal(ck.params_json, PJ);
            assert_string_equal(ck.aux, "{\"a\":1}");
            assert_int_equal(ck.scheme, SS_HEAL_EXPLICIT);
            assert_true(ck.dt_days == 0.002);
            ss_heal_checkpoint_free(&ck);
            /* every box (+ halo) of every other split */
            ss_heal_ckpt_header h;
            ss_heal_checkpoint none;
            assert_int_equal(ss_heal_checkpoint_open_latest(dir, 1, &none, &h, NULL, 0, &err),
                             SS_OK);
            assert_null(none.grid);
            assert_int_equal(h.npieces, SPLITS[w][0] * SPLITS[w][1] * SPLITS[w][2]);
            assert_int_equal(h.velocity, vel);
            for (int r = 0; r < NSPLITS; r++) check_boxes(dir, &h, g, SPLITS[r]);
            ss_heal_ckpt_header_free(&h);
            tu_rmtree(dir);
            free(dir);
        }
        ss_heal_checkpoint_free(&ref);
        tu_rmtree(wdir);
        free(wdir);
        ss_heal_grid_free(g);
    }
}

/* Rewrites a file with its bytes changed by fn. */
static void rewrite(const char *path, size_t keep, size_t flip) {
    size_t len;
    ss_error err;
    char *b = ss_read_file(path, &len, &err);
    assert_non_null(b);
    if (flip < len) b[flip] ^= 0x04;
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fwrite(b, 1, keep < len ? keep : len, f);
    fclose(f);
    free(b);
}

static void copy_file(const char *from, const char *to) {
    size_t len;
    ss_error err;
    char *b = ss_read_file(from, &len, &err);
    assert_non_null(b);
    assert_int_equal(ss_write_file_atomic(to, b, len, &err), SS_OK);
    free(b);
}

/* Loading fails with SS_ERR_INPUT naming `file` and saying `what`. */
static void expect_refused(const char *dir, uint64_t step, const char *file, const char *what) {
    ss_heal_checkpoint ck;
    ss_error err;
    ss_error_clear(&err);
    assert_int_equal(ss_heal_checkpoint_read_pieces(dir, step, &ck, &err), SS_ERR_INPUT);
    assert_null(ck.grid);
    if (!strstr(err.msg, file) || !strstr(err.msg, what))
        fail_msg("error \"%s\" should name %s and say \"%s\"", err.msg, file, what);
}

static void test_pieces_corruption(void **state) {
    (void)state;
    ss_error err;
    ss_heal_grid *g = tu_heal_grid_noisy(12, 10, 6, 0.3, 9, 0);
    const int d2[3] = {2, 1, 1}, d1[3] = {1, 1, 1};
    char *dir = tu_tmpdir("pieces-bad");
    assert_int_equal(
        ss_heal_checkpoint_save_pieces(dir, g, "scab", PJ, SS_HEAL_SPLIT, 0.05, "", d2, 2, &err),
        SS_OK);
    const uint64_t s = g->step;
    char p0[4400], p1[4400], hp[4400], save[4500];
    ss_heal_ckpt_piece_path(p0, sizeof p0, dir, s, 0);
    ss_heal_ckpt_piece_path(p1, sizeof p1, dir, s, 1);
    ss_heal_ckpt_header_path(hp, sizeof hp, dir, s);
    snprintf(save, sizeof save, "%s.good", p1);
    copy_file(p1, save);
    ss_heal_checkpoint ck;
    assert_int_equal(ss_heal_checkpoint_read_pieces(dir, s, &ck, &err), SS_OK);
    ss_heal_checkpoint_free(&ck);

    /* a missing piece */
    assert_int_equal(unlink(p1), 0);
    expect_refused(dir, s, p1, "missing");
    /* only the pieces a box overlaps are opened: the x < 6 half reads */
    ss_heal_ckpt_header h;
    assert_int_equal(ss_heal_ckpt_header_read(hp, &h, &err), SS_OK);
    {
        ss_heal_grid *b = ss_heal_grid_create(6, 10, 6, g->dx_mm, &err);
        const int org[3] = {0, 0, 0}, n[3] = {6, 10, 6}, n7[3] = {7, 10, 6};
        assert_int_equal(ss_heal_ckpt_read_box(dir, &h, b, org, org, n, &err), SS_OK);
        assert_memory_equal(b->field[3], g->field[3], 6 * sizeof(float));
        ss_heal_grid *b7 = ss_heal_grid_create(7, 10, 6, g->dx_mm, &err);
        assert_int_equal(ss_heal_ckpt_read_box(dir, &h, b7, org, org, n7, &err), SS_ERR_INPUT);
        assert_non_null(strstr(err.msg, p1));
        ss_heal_grid_free(b);
        ss_heal_grid_free(b7);
    }
    /* truncated */
    copy_file(save, p1);
    rewrite(p1, 200, (size_t)-1);
    expect_refused(dir, s, p1, "bytes");
    /* one flipped byte in the data */
    copy_file(save, p1);
    rewrite(p1, (size_t)-1, 500);
    expect_refused(dir, s, p1, "corrupt");
    /* the quick check (sizes and piece headers) does not see it, the CRC pass does */
    assert_int_equal(ss_heal_ckpt_pieces_check(dir, &h, 0, &err), SS_OK);
    assert_int_equal(ss_heal_ckpt_pieces_check(dir, &h, 1, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, p1));
    ss_heal_ckpt_header_free(&h);

    /* a piece of another step (same box) in its place */
    copy_file(save, p1);
    g->step = s + 5;
    assert_int_equal(
        ss_heal_checkpoint_save_pieces(dir, g, "scab", PJ, SS_HEAL_SPLIT, 0.05, "", d2, 2, &err),
        SS_OK);
    char q1[4400];
    ss_heal_ckpt_piece_path(q1, sizeof q1, dir, s + 5, 1);
    copy_file(q1, p1);
    char other[64];
    snprintf(other, sizeof other, "step %llu", (unsigned long long)(s + 5));
    expect_refused(dir, s, p1, other);
    copy_file(save, p1);
    /* a piece of another grid (same box size: the 6x10x6 grid as one piece) */
    ss_heal_grid *g6 = tu_heal_grid_noisy(6, 10, 6, 0.3, 2, 0);
    char *dir6 = tu_tmpdir("pieces-6");
    assert_int_equal(
        ss_heal_checkpoint_save_pieces(dir6, g6, "scab", PJ, SS_HEAL_SPLIT, 0.05, "", d1, 2, &err),
        SS_OK);
    char r0[4400];
    ss_heal_ckpt_piece_path(r0, sizeof r0, dir6, g6->step, 0);
    copy_file(r0, p1);
    expect_refused(dir, s, p1, "6x10x6 grid");
    copy_file(save, p1);
    assert_int_equal(ss_heal_checkpoint_read_pieces(dir, s, &ck, &err), SS_OK);
    ss_heal_checkpoint_free(&ck);

    /* the header: a flipped byte, then pieces that do not tile (CRC made good) */
    char hsave[4500];
    snprintf(hsave, sizeof hsave, "%s.good", hp);
    copy_file(hp, hsave);
    rewrite(hp, (size_t)-1, 30);
    expect_refused(dir, s, hp, "corrupt");
    {
        size_t len;
        unsigned char *b = (unsigned char *)ss_read_file(hsave, &len, &err);
        assert_non_null(b);
        /* piece 1's lo x (the last two pieces' records end the file) */
        size_t rec = len - 4 - 36;
        b[rec] = 5; /* x = 5: overlaps piece 0 */
        uint32_t crc = (uint32_t)crc32(crc32(0L, Z_NULL, 0), b, (uInt)(len - 4));
        for (int k = 0; k < 4; k++) b[len - 4 + (size_t)k] = (unsigned char)(crc >> (8 * k));
        assert_int_equal(ss_write_file_atomic(hp, b, len, &err), SS_OK);
        expect_refused(dir, s, hp, "do not tile");
        free(b);
    }
    /* and one that tiles but is refused when written */
    {
        ss_heal_ckpt_header bad = {0};
        ss_heal_ckpt_piece pc[2] = {{{0, 0, 0}, {7, 10, 6}, 0, 0}, {{6, 0, 0}, {6, 10, 6}, 0, 0}};
        bad.whole[0] = 12, bad.whole[1] = 10, bad.whole[2] = 6;
        bad.dims[0] = 2, bad.dims[1] = bad.dims[2] = 1;
        bad.dx_mm = 0.3, bad.dt_days = 0.05, bad.npieces = 2, bad.piece = pc;
        bad.scenario = "scab", bad.params_json = "{}", bad.aux = "";
        assert_int_equal(ss_heal_ckpt_header_save(dir, &bad, 2, &err), SS_ERR_INPUT);
        assert_non_null(strstr(err.msg, "overlaps"));
    }

    /* the newest complete checkpoint of either kind; a damaged one skipped */
    copy_file(hsave, hp);
    char *ldir = tu_tmpdir("pieces-latest");
    g->step = 100;
    assert_int_equal(ss_heal_checkpoint_save(ldir, g, "scab", PJ, SS_HEAL_SPLIT, 0.05, "", 2, &err),
                     SS_OK);
    g->step = 200;
    g->field[2][7] = 9.5f;
    assert_int_equal(
        ss_heal_checkpoint_save_pieces(ldir, g, "scab", PJ, SS_HEAL_SPLIT, 0.05, "", d2, 2, &err),
        SS_OK);
    /* pieces without a header (a killed write) are not a checkpoint */
    g->step = 300;
    char lp[4400];
    const int org[3] = {0, 0, 0}, lo[3] = {0, 0, 0}, nn[3] = {12, 10, 6};
    assert_int_equal(ss_heal_ckpt_piece_write(ldir, 0, g, org, lo, nn, nn, NULL, &err), SS_OK);
    char note[1024];
    assert_int_equal(ss_heal_checkpoint_load_latest(ldir, &ck, note, sizeof note, &err), SS_OK);
    assert_true(ck.grid->step == 200 && ck.grid->field[2][7] == 9.5f);
    ss_heal_checkpoint_free(&ck);
    ss_heal_ckpt_piece_path(lp, sizeof lp, ldir, 200, 1);
    rewrite(lp, (size_t)-1, 300);
    assert_int_equal(ss_heal_checkpoint_load_latest(ldir, &ck, note, sizeof note, &err), SS_OK);
    assert_true(ck.grid->step == 100);
    assert_non_null(strstr(note, lp));
    ss_heal_checkpoint_free(&ck);
    /* pruning keeps two of either kind: two more piece checkpoints leave
     * headers 400 and 500 and their four pieces; nothing of 100 and 200, nor
     * the headerless step-300 piece (older than the newest checkpoint) */
    for (uint64_t st = 400; st <= 500; st += 100) {
        g->step = st;
        assert_int_equal(ss_heal_checkpoint_save_pieces(ldir, g, "scab", PJ, SS_HEAL_SPLIT, 0.05,
                                                        "", d2, 2, &err),
                         SS_OK);
    }
    char *cdir = tu_join(ldir, "checkpoints");
    assert_int_equal(tu_count_entries(cdir), 2 + 4);
    assert_int_not_equal(access(lp, F_OK), 0);
    free(cdir);

    tu_rmtree(ldir);
    free(ldir);
    tu_rmtree(dir6);
    free(dir6);
    ss_heal_grid_free(g6);
    tu_rmtree(dir);
    free(dir);
    ss_heal_grid_free(g);
}

/* ---- .pvti --------------------------------------------------------------------- */

/* Writes g as the pieces of split d (with displacement and closure days
 * unless bare) and their .pvti in dir; the names are fields_0003*. */
static void write_pvti_n(const char *dir, int index, const ss_heal_grid *g, const int d[3],
                         const float *disp, const double *closed, int bare) {
    const int whole[3] = {g->nx, g->ny, g->nz};
    int np = d[0] * d[1] * d[2], i = 0;
    int(*ext)[6] = malloc((size_t)np * sizeof *ext);
    char **files = malloc((size_t)np * sizeof *files);
    ss_error err;
    for (int z = 0; z < d[2]; z++)
        for (int y = 0; y < d[1]; y++)
            for (int x = 0; x < d[0]; x++, i++) {
                const int c[3] = {x, y, z};
                int lo[3], n[3];
                ss_heal_ckpt_split(whole, d, c, lo, n);
                ss_heal_grid *p = ss_heal_grid_create(n[0] < 3 ? 3 : n[0], n[1] < 3 ? 3 : n[1],
                                                      n[2] < 3 ? 3 : n[2], g->dx_mm, &err);
                assert_non_null(p);
                p->nx = n[0], p->ny = n[1], p->nz = n[2];
                p->t_days = g->t_days;
                size_t pn = (size_t)n[0] * n[1] * n[2];
                if (g->added) assert_non_null(p->added = calloc(pn, sizeof *p->added));
                float *pd = malloc(3 * pn * sizeof *pd);
                double *pc = malloc((size_t)n[0] * n[1] * sizeof *pc);
                for (int k = 0; k < n[2]; k++)
                    for (int j = 0; j < n[1]; j++)
                        for (int q = 0; q < n[0]; q++) {
                            size_t s = ss_heal_idx(g, lo[0] + q, lo[1] + j, lo[2] + k),
                                   t = ss_heal_idx(p, q, j, k);
                            p->cell[t] = g->cell[s];
                            for (int f = 0; f < SS_HEAL_NFIELDS; f++)
                                p->field[f][t] = g->field[f][s];
                            if (g->added) p->added[t] = g->added[s];
                            for (int v = 0; disp && v < 3; v++)
                                pd[(size_t)v * pn + t] =
                                    disp[(size_t)v * g->nx * g->ny * g->nz + s];
                            if (!k)
                                pc[(size_t)j * n[0] + q] =
                                    closed[(size_t)(lo[1] + j) * g->nx + lo[0] + q];
                        }
                float *const vec[1][3] = {{pd, pd + pn, pd + 2 * pn}};
                const char *name = "displacement";
                files[i] = malloc(64);
                snprintf(files[i], 64, "fields_%04d_p%04d.vti", index, i);
                char *path = tu_join(dir, files[i]);
                if (bare)
                    assert_int_equal(ss_heal_vti_write_piece(path, p, lo, whole, &err), SS_OK);
                else
                    assert_int_equal(ss_heal_vti_write_piece_all(path, p, lo, whole, disp ? 1 : 0,
                                                                 &name, vec, pc, &err),
                                     SS_OK);
                const int e6[6] = {lo[0], lo[0] + n[0], lo[1], lo[1] + n[1], lo[2], lo[2] + n[2]};
                memcpy(ext[i], e6, sizeof e6);
                free(path);
                free(pd);
                free(pc);
                ss_heal_grid_free(p);
            }
    char pvname[64];
    snprintf(pvname, sizeof pvname, "fields_%04d.pvti", index);
    char *pv = tu_join(dir, pvname);
    assert_int_equal(ss_heal_pvti_write_arrays(pv, whole, g->dx_mm, np, (const int(*)[6])ext,
                                               (const char *const *)files, 0, NULL,
                                               g->added != NULL, &err),
                     SS_OK);
    for (i = 0; i < np; i++) free(files[i]);
    free(files);
    free(ext);
    free(pv);
}

static void write_pvti(const char *dir, const ss_heal_grid *g, const int d[3], const float *disp,
                       const double *closed, int bare) {
    write_pvti_n(dir, 3, g, d, disp, closed, bare);
}

static void test_pvti_roundtrip(void **state) {
    (void)state;
    ss_error err;
    ss_heal_grid *g = tu_heal_grid_noisy(11, 9, 6, 0.3, 21, 0);
    size_t n = (size_t)g->nx * g->ny * g->nz, ncol = (size_t)g->nx * g->ny;
    float *disp = malloc(3 * n * sizeof *disp);
    double *closed = malloc(ncol * sizeof *closed);
    for (size_t i = 0; i < 3 * n; i++) disp[i] = (float)ss_rng_uniform(77, 1, i);
    for (size_t i = 0; i < ncol; i++) closed[i] = i % 3 ? -1.0 : 0.25 * (double)i;
    char *dir = tu_tmpdir("pvti");
    char *gathered = tu_join(dir, "fields_0003.vti");
    const char *name = "displacement";
    float *const vec[1][3] = {{disp, disp + n, disp + 2 * n}};
    assert_int_equal(ss_heal_vti_write_all(gathered, g, 1, &name, vec, closed, &err), SS_OK);
    float *rd = NULL;
    double *rc = NULL;
    ss_heal_grid *ref = ss_heal_vti_read(gathered, &rd, &rc, &err);
    assert_non_null(ref);
    const int splits[][3] = {{1, 1, 1}, {2, 1, 1}, {3, 2, 1}, {1, 2, 2}, {5, 4, 2}};
    for (int s = 0; s < 5; s++) {
        char *sub = tu_tmpdir("pvti-split");
        write_pvti(sub, g, splits[s], disp, closed, 0);
        char *pv = tu_join(sub, "fields_0003.pvti");
        float *pd = NULL;
        double *pc = NULL;
        ss_heal_grid *h = ss_heal_pvti_read(pv, &pd, &pc, &err);
        if (!h) fail_msg("%s", err.msg);
        tu_assert_heal_grids_equal(ref, h);
        assert_non_null(pd);
        assert_non_null(pc);
        assert_memory_equal(pd, rd, 3 * n * sizeof *pd);
        assert_memory_equal(pc, rc, ncol * sizeof *pc);
        free(pd);
        free(pc);
        ss_heal_grid_free(h);
        free(pv);
        tu_rmtree(sub);
        free(sub);
    }
    /* a keloid grid's added volume [D16]: the pieces hold it, the .pvti lists
     * it, the joined grid has it as the gathered snapshot does */
    {
        ss_heal_grid *k = tu_heal_grid_noisy(11, 9, 6, 0.3, 21, 0);
        assert_non_null(k->added = malloc(n * sizeof *k->added));
        for (size_t i = 0; i < n; i++) k->added[i] = (float)ss_rng_uniform(78, 1, i);
        char *sub = tu_tmpdir("pvti-added");
        char *kg = tu_join(sub, "whole.vti");
        assert_int_equal(ss_heal_vti_write_all(kg, k, 0, NULL, NULL, closed, &err), SS_OK);
        ss_heal_grid *kref = ss_heal_vti_read(kg, NULL, NULL, &err);
        assert_non_null(kref);
        assert_non_null(kref->added);
        assert_memory_equal(kref->added, k->added, n * sizeof *k->added);
        write_pvti(sub, k, splits[2], NULL, closed, 0);
        char *kpv = tu_join(sub, "fields_0003.pvti");
        size_t klen;
        char *kt = ss_read_file(kpv, &klen, &err);
        assert_non_null(kt);
        assert_non_null(strstr(kt, "Name=\"keloid_added\""));
        free(kt);
        ss_heal_grid *kh = ss_heal_pvti_read(kpv, NULL, NULL, &err);
        if (!kh) fail_msg("%s", err.msg);
        tu_assert_heal_grids_equal(kref, kh);
        ss_heal_grid_free(kh);
        ss_heal_grid_free(kref);
        ss_heal_grid_free(k);
        free(kpv);
        free(kg);
        tu_rmtree(sub);
        free(sub);
    }
    /* pieces without displacement or closure days: the fields only */
    write_pvti(dir, g, splits[2], disp, closed, 1);
    char *pv = tu_join(dir, "fields_0003.pvti");
    float *pd = (float *)1;
    double *pc = (double *)1;
    ss_heal_grid *h = ss_heal_pvti_read(pv, &pd, &pc, &err);
    assert_non_null(h);
    assert_null(pd);
    assert_null(pc);
    tu_assert_heal_grids_equal(ref, h);
    ss_heal_grid_free(h);
    /* the gathered reader refuses a piece, the pvti reader the gathered .vti */
    char *p1 = tu_join(dir, "fields_0003_p0001.vti");
    assert_null(ss_heal_vti_read(p1, NULL, NULL, &err));
    assert_non_null(strstr(err.msg, "Piece Extent"));
    assert_null(ss_heal_pvti_read(gathered, NULL, NULL, &err));
    assert_non_null(strstr(err.msg, gathered));

    /* errors name the file at fault */
    size_t len;
    char *text = ss_read_file(pv, &len, &err);
    assert_non_null(text);
    char *save = tu_join(dir, "save.vti");
    copy_file(p1, save);
    assert_int_equal(unlink(p1), 0); /* missing piece */
    assert_null(ss_heal_pvti_read(pv, NULL, NULL, &err));
    assert_non_null(strstr(err.msg, p1));
    copy_file(save, p1);
    rewrite(p1, 300, (size_t)-1); /* truncated piece */
    assert_null(ss_heal_pvti_read(pv, NULL, NULL, &err));
    assert_non_null(strstr(err.msg, p1));
    copy_file(save, p1);
    /* overlapping extents: piece 1's Extent starts one cell early */
    char *bad = strdup(text), *e1 = strstr(strstr(bad, "<Piece") + 1, "<Piece Extent=\"");
    assert_non_null(e1);
    e1[15] = (char)(e1[15] - 1);
    assert_int_equal(ss_write_file_atomic(pv, bad, len, &err), SS_OK);
    assert_null(ss_heal_pvti_read(pv, NULL, NULL, &err));
    if (!strstr(err.msg, "do not tile") || !strstr(err.msg, pv)) fail_msg("%s", err.msg);
    /* a piece dropped from the list: a gap */
    free(bad);
    bad = strdup(text);
    char *pc1 = strstr(strstr(bad, "<Piece") + 1, "<Piece");
    char *end1 = strchr(pc1, '\n');
    memmove(pc1, end1 + 1, strlen(end1 + 1) + 1);
    assert_int_equal(ss_write_file_atomic(pv, bad, strlen(bad), &err), SS_OK);
    assert_null(ss_heal_pvti_read(pv, NULL, NULL, &err));
    assert_non_null(strstr(err.msg, "uncovered"));
    /* malformed XML: cut in the middle */
    assert_int_equal(ss_write_file_atomic(pv, text, len / 2, &err), SS_OK);
    assert_null(ss_heal_pvti_read(pv, NULL, NULL, &err));
    if (!strstr(err.msg, "malformed") || !strstr(err.msg, pv)) fail_msg("%s", err.msg);
    assert_int_equal(ss_write_file_atomic(pv, "<VTKFile type=\"ImageData\">", 26, &err), SS_OK);
    assert_null(ss_heal_pvti_read(pv, NULL, NULL, &err));
    assert_non_null(strstr(err.msg, "PImageData"));
    free(bad);
    free(text);
    free(save);
    free(p1);
    free(pv);
    free(gathered);
    free(rd);
    free(rc);
    ss_heal_grid_free(ref);
    free(disp);
    free(closed);
    ss_heal_grid_free(g);
    tu_rmtree(dir);
    free(dir);
}

/* Every file of folder a equals the one of the same name in b. */
static void assert_same_files(const char *a, const char *b) {
    DIR *d = opendir(a);
    assert_non_null(d);
    struct dirent *e;
    int n = 0;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        char *fa = tu_join(a, e->d_name), *fb = tu_join(b, e->d_name);
        size_t la, lb;
        ss_error err;
        char *ca = ss_read_file(fa, &la, &err), *cb = ss_read_file(fb, &lb, &err);
        if (!ca || !cb || la != lb || memcmp(ca, cb, la)) fail_msg("%s differs from %s", fb, fa);
        free(ca);
        free(cb);
        free(fa);
        free(fb);
        n++;
    }
    closedir(d);
    assert_true(n > 0);
}

/* `skinsim wound --heal` on a run folder whose snapshots are .pvti + pieces
 * only (as a run on MPI ranks leaves them, here made from the gathered ones
 * with the pieces' writer) renders the same bytes as on the gathered .vti. */
static void test_wound_heal_from_pvti(void **state) {
    (void)state;
    char *dir = tu_tmpdir("wound-pvti");
    char cmd[8192];
    snprintf(cmd, sizeof cmd,
             "heal --scenario scab --grid 20x20x8 --days 2 --snapshot-every 1 --adapt-tol 0 "
             "--threads 1 --quiet --out '%s/h'",
             dir);
    assert_int_equal(tu_run_cli(cmd, NULL, NULL), 0);
    snprintf(cmd, sizeof cmd, "cp -r '%s/h' '%s/p'", dir, dir);
    assert_int_equal(system(cmd), 0);
    const int split[3] = {2, 2, 1};
    for (int i = 0; i < 3; i++) {
        char name[64];
        snprintf(name, sizeof name, "p/fields/fields_%04d.vti", i);
        char *vti = tu_join(dir, name), *fdir = tu_join(dir, "p/fields");
        float *disp = NULL;
        double *closed = NULL;
        ss_error err;
        ss_heal_grid *g = ss_heal_vti_read(vti, &disp, &closed, &err);
        assert_non_null(g);
        assert_non_null(closed);
        write_pvti_n(fdir, i, g, split, disp, closed, 0);
        assert_int_equal(unlink(vti), 0);
        ss_heal_grid_free(g);
        free(disp);
        free(closed);
        free(vti);
        free(fdir);
    }
    const char *wopt = "--days 0,1,2 --size 32 --threads 1 --quiet";
    snprintf(cmd, sizeof cmd, "wound --heal '%s/h' %s --out '%s/wa'", dir, wopt, dir);
    assert_int_equal(tu_run_cli(cmd, NULL, NULL), 0);
    snprintf(cmd, sizeof cmd, "wound --heal '%s/p' %s --out '%s/wb'", dir, wopt, dir);
    assert_int_equal(tu_run_cli(cmd, NULL, NULL), 0);
    char *fa = tu_join(dir, "wa/frames"), *fb = tu_join(dir, "wb/frames");
    assert_same_files(fa, fb);
    free(fa);
    free(fb);
    /* a piece missing: exit 2 naming it, nothing written */
    char *piece = tu_join(dir, "p/fields/fields_0001_p0002.vti");
    assert_int_equal(unlink(piece), 0);
    char *errf = tu_join(dir, "err.txt");
    snprintf(cmd, sizeof cmd, "wound --heal '%s/p' %s --out '%s/wc'", dir, wopt, dir);
    assert_int_equal(tu_run_cli(cmd, NULL, errf), 2);
    ss_error err;
    char *msg = ss_read_file(errf, NULL, &err);
    assert_non_null(msg);
    if (!strstr(msg, "fields_0001_p0002.vti")) fail_msg("error does not name the piece: %s", msg);
    char *wc = tu_join(dir, "wc");
    assert_int_not_equal(access(wc, F_OK), 0);
    free(wc);
    free(msg);
    free(errf);
    free(piece);
    tu_rmtree(dir);
    free(dir);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pieces_any_split),
        cmocka_unit_test(test_pieces_corruption),
        cmocka_unit_test(test_pvti_roundtrip),
        cmocka_unit_test(test_wound_heal_from_pvti),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
