/* Tests for the heal run object (skinsim/heal_run.h): an in-memory run equals
 * the solver stepped by hand on the same grid (the run adds bookkeeping, never
 * changes the state); a run stopped after a checkpoint and resumed through the
 * config ends bit-identical to an uninterrupted one, with the same area curve;
 * an in-memory footprint gives the same wound as the same mask from a file;
 * bad configs are input errors that write nothing; stepping outside the run
 * is refused; a distributed run (the MPI driver's rank 0) makes no grid but
 * the same geometry, step and wound, and cannot step without the driver. */
#define _POSIX_C_SOURCE 200809L
#include "testutil.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "skinsim/heal_run.h"

static void small_config(ss_heal_run_config *c) {
    ss_heal_run_config_default(c);
    c->grid[0] = 20;
    c->grid[1] = 16;
    c->grid[2] = 8;
    c->scenario = "scab";
    c->days = 1;
}

static void assert_fields_equal(const ss_heal_grid *a, const ss_heal_grid *b) {
    size_t n = (size_t)a->nx * a->ny * a->nz;
    assert_int_equal(a->nx, b->nx);
    assert_int_equal(a->step, b->step);
    assert_memory_equal(a->cell, b->cell, n);
    for (int f = 0; f < SS_HEAL_NFIELDS; f++)
        assert_memory_equal(a->field[f], b->field[f], n * sizeof(float));
}

/* Resumes the run in dir (from its newest checkpoint) up to `days`. */
static ss_heal_run *resume_run(const char *dir, double days) {
    ss_error err;
    ss_heal_run_config rc;
    ss_heal_run_config_default(&rc);
    rc.resume_dir = dir;
    rc.days = days;
    ss_heal_run *r = NULL;
    assert_int_equal(ss_heal_run_create(&rc, &r, &err), SS_OK);
    return r;
}

/* The run's state after advance_to equals the solver stepped by hand. */
static void test_run_matches_solver(void **state) {
    (void)state;
    ss_error err;
    ss_heal_run_config c;
    small_config(&c);
    ss_heal_run *r;
    assert_int_equal(ss_heal_run_create(&c, &r, &err), SS_OK);
    assert_int_equal(ss_heal_run_step_index(r), 0);
    assert_int_equal(ss_heal_run_steps_total(r), 20); /* 1 day of 0.05 */
    assert_int_equal(ss_heal_run_advance_to(r, 0.5, &err), SS_OK);
    assert_int_equal(ss_heal_run_step_index(r), 10);
    assert_true(ss_heal_run_day(r) > 0.49 && ss_heal_run_day(r) < 0.51);

    /* by hand: the same default problem */
    ss_heal_params *p = ss_heal_params_preset("scab", &err);
    ss_heal_grid *g = ss_heal_grid_create(20, 16, 8, 0.5, &err);
    assert_non_null(g);
    double side = 16 * 0.5 * 2.0 / 3.0; /* 2/3 of the smaller side */
    uint8_t *w3 = ss_heal_wound_box(g, 3.0, side, side, 1.0, &err);
    assert_non_null(w3);
    assert_int_equal(ss_heal_grid_init(g, 3.0, 0.1, w3, p, &err), SS_OK);
    free(w3);
    ss_heal_solver *s = ss_heal_solver_create(g, p, SS_HEAL_SPLIT, 0, &err);
    for (int k = 0; k < 10; k++) assert_int_equal(ss_heal_step(s, g, &err), SS_OK);
    assert_fields_equal(ss_heal_run_grid(r), g);

    /* the area curve: day 0 plus every step (0.01 days rounds to one step) */
    int n;
    const ss_heal_area_row *rows = ss_heal_run_area(r, &n);
    assert_int_equal(n, 11);
    assert_true(rows[0].t_days == 0);
    assert_true(rows[0].st.initial_area_mm2 > 0);

    /* outside the run */
    assert_int_equal(ss_heal_run_advance_to(r, 0.2, &err), SS_ERR_INPUT);
    assert_int_equal(ss_heal_run_advance_to(r, 1.5, &err), SS_ERR_INPUT);
    assert_int_equal(ss_heal_run_write_snapshot(r, &err), SS_ERR_INPUT); /* no out_dir */
    assert_int_equal(ss_heal_run_advance_to(r, 1.0, &err), SS_OK);
    assert_true(ss_heal_run_done(r));
    assert_int_equal(ss_heal_run_step(r, &err), SS_ERR_INPUT);
    char *summary = NULL;
    assert_int_equal(ss_heal_run_finish(r, &summary, &err), SS_OK);
    assert_non_null(strstr(summary, "\"scenario\":\t\"scab\""));
    free(summary);

    ss_heal_solver_free(s);
    ss_heal_grid_free(g);
    ss_heal_params_free(p);
    ss_heal_run_free(r);
}

/* Checkpoint at day 0.5, stop, resume through the config: same end state and
 * the same area curve as one uninterrupted run in memory. */
static void test_run_resume(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("heal-run");
    char out[1024];
    snprintf(out, sizeof out, "%s/run", dir);
    ss_heal_run_config c;
    small_config(&c);
    c.out_dir = out;
    c.checkpoint_every = 0.25;
    c.days = 0.5;
    ss_heal_run *r;
    assert_int_equal(ss_heal_run_create(&c, &r, &err), SS_OK);
    struct stat sb;
    assert_int_not_equal(stat(out, &sb), 0); /* create writes nothing */
    while (!ss_heal_run_done(r)) assert_int_equal(ss_heal_run_step(r, &err), SS_OK);
    assert_int_equal(ss_heal_run_snapshot_count(r), 2); /* day 0 and the end */
    ss_heal_run_free(r);                                /* killed before finish */

    r = resume_run(out, 1);
    assert_int_equal(ss_heal_run_resumed_from(r), 10);
    assert_string_equal(ss_heal_run_scenario(r), "scab");
    while (!ss_heal_run_done(r)) assert_int_equal(ss_heal_run_step(r, &err), SS_OK);
    assert_int_equal(ss_heal_run_finish(r, NULL, &err), SS_OK);
    char path[1100];
    snprintf(path, sizeof path, "%s/summary.json", out);
    assert_true(tu_file_exists(path));

    ss_heal_run_config mc;
    small_config(&mc);
    ss_heal_run *m;
    assert_int_equal(ss_heal_run_create(&mc, &m, &err), SS_OK);
    assert_int_equal(ss_heal_run_advance_to(m, 1, &err), SS_OK);
    assert_fields_equal(ss_heal_run_grid(r), ss_heal_run_grid(m));
    int na, nb;
    const ss_heal_area_row *a = ss_heal_run_area(r, &na), *b = ss_heal_run_area(m, &nb);
    assert_int_equal(na, nb);
    /* rows up to the checkpoint come back through its JSON metadata (cJSON
     * prints doubles to about 1e-15 relative); rows after it are exact */
    for (int i = 0; i < na; i++) {
        const double *x = &a[i].t_days, *y = &b[i].t_days;
        for (size_t k = 0; k < sizeof *a / sizeof(double); k++)
            if (i <= 10)
                assert_true(fabs(x[k] - y[k]) <= 1e-14 * fabs(y[k]));
            else
                assert_true(x[k] == y[k]);
    }
    ss_heal_run_free(m);
    ss_heal_run_free(r);
    tu_rmtree(dir);
    free(dir);
}

static void run_to_end(ss_heal_run *r) {
    ss_error err;
    while (!ss_heal_run_done(r)) assert_int_equal(ss_heal_run_step(r, &err), SS_OK);
}

/* Adaptive steps (adapt_tol): far fewer solver steps over the slow phase,
 * the fast phase (closure) as with fixed steps, the end state close to the
 * fixed-step one; bit-identical across a checkpoint resume and for 1 and 2
 * threads; advance_to lands on the requested day. */
static void test_run_adaptive(void **state) {
    (void)state;
    ss_error err;
    ss_heal_run_config c;
    small_config(&c);
    c.scenario = "clean";
    const int quick = tu_quick(); /* sanitizer runs: shorter runs, the same checks */
    c.days = quick ? 30 : 40;
    ss_heal_run *f, *a;
    assert_int_equal(ss_heal_run_create(&c, &f, &err), SS_OK);
    c.adapt_tol = 0.01;
    assert_int_equal(ss_heal_run_create(&c, &a, &err), SS_OK);
    run_to_end(f);
    run_to_end(a);
    int nf, na;
    const ss_heal_area_row *rf = ss_heal_run_area(f, &nf), *ra = ss_heal_run_area(a, &na);
    /* an area row after every step: the solver steps taken */
    print_message("adaptive: %d steps vs %d fixed, %lld retried, final m %lld\n", na - 1, nf - 1,
                  ss_heal_run_steps_retried(a), ss_heal_run_step_multiple(a));
    assert_true(na - 1 < 0.4 * (nf - 1));
    assert_true(ss_heal_run_step_multiple(a) > 4);
    double t95f = ss_heal_time_to_closure(rf, nf, 0.05),
           t95a = ss_heal_time_to_closure(ra, na, 0.05);
    assert_true(t95f > 0 && fabs(t95a - t95f) < 1e-9);
    const ss_heal_grid *gf = ss_heal_run_grid(f), *ga = ss_heal_run_grid(a);
    assert_int_equal(gf->step, ga->step);
    assert_true(fabs(ga->t_days - c.days) < 1e-9);
    const size_t n = (size_t)gf->nx * gf->ny * gf->nz;
    for (int k = 0; k < SS_HEAL_NFIELDS; k++) {
        double dmax = 0;
        for (size_t i = 0; i < n; i++) {
            double d = fabs((double)gf->field[k][i] - ga->field[k][i]);
            if (d > dmax) dmax = d;
        }
        print_message("  %s: largest difference to fixed steps %.2e\n", ss_heal_field_name(k),
                      dmax);
        assert_true(dmax < 0.01);
    }
    double vf = rf[nf - 1].st.scar_volume_mm3, va = ra[na - 1].st.scar_volume_mm3;
    assert_true(fabs(va - vf) <= 0.005 * vf);
    ss_heal_run_free(f);
    ss_heal_run_free(a);

    /* advance_to lands on a requested day inside a long step */
    assert_int_equal(ss_heal_run_create(&c, &a, &err), SS_OK);
    assert_int_equal(ss_heal_run_advance_to(a, 23.35, &err), SS_OK);
    assert_int_equal(ss_heal_run_step_index(a), 467);
    ss_heal_run_free(a);

    /* resume from a checkpoint of an adaptive run: bit-identical */
    char *dir = tu_tmpdir("heal-adapt");
    char out[1024], ref[1024];
    snprintf(out, sizeof out, "%s/run", dir);
    snprintf(ref, sizeof ref, "%s/ref", dir);
    c.snapshot_every = 0;
    c.checkpoint_every = 7;
    c.days = quick ? 14 : 21;
    c.out_dir = out;
    assert_int_equal(ss_heal_run_create(&c, &a, &err), SS_OK);
    run_to_end(a);
    long long m21 = ss_heal_run_step_multiple(a);
    ss_heal_run_free(a); /* killed before finish */
    a = resume_run(out, quick ? 24 : 40);
    assert_int_equal(ss_heal_run_step_multiple(a), m21);
    run_to_end(a);
    c.days = quick ? 24 : 40;
    c.out_dir = ref;
    assert_int_equal(ss_heal_run_create(&c, &f, &err), SS_OK);
    run_to_end(f);
    assert_fields_equal(ss_heal_run_grid(a), ss_heal_run_grid(f));
    assert_true(ss_heal_run_grid(a)->t_days == ss_heal_run_grid(f)->t_days);
    ss_heal_run_free(a);
    ss_heal_run_free(f);
    tu_rmtree(dir);
    free(dir);

    /* 1 and 2 threads on a grid large enough to run in parallel */
    ss_heal_run_config tc;
    ss_heal_run_config_default(&tc);
    tc.grid[0] = tc.grid[1] = 36; /* 33696 cells: just above the parallel threshold */
    tc.grid[2] = 26;
    tc.days = quick ? 4 : 16;
    tc.adapt_tol = 0.01;
    ss_heal_run *t1, *t2;
    ss_threads_set(1);
    assert_int_equal(ss_heal_run_create(&tc, &t1, &err), SS_OK);
    run_to_end(t1);
    ss_threads_set(2);
    assert_int_equal(ss_heal_run_create(&tc, &t2, &err), SS_OK);
    run_to_end(t2);
    if (!quick) assert_true(ss_heal_run_step_multiple(t1) > 1);
    assert_fields_equal(ss_heal_run_grid(t1), ss_heal_run_grid(t2));
    ss_heal_run_free(t1);
    ss_heal_run_free(t2);
}

/* A footprint image in memory equals the same mask read from a PNG. */
static void test_run_footprint(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("heal-run-fp");
    ss_image *fp = ss_image_create(40, 32, 1, &err);
    assert_non_null(fp);
    for (int y = 8; y < 20; y++)
        for (int x = 10; x < 31; x++) fp->data[y * 40 + x] = 1;
    char png[1024];
    snprintf(png, sizeof png, "%s/mask.png", dir);
    assert_int_equal(ss_png_write(png, fp, 8, SS_ENC_LINEAR, &err), SS_OK);

    ss_heal_run_config c;
    small_config(&c);
    c.wound_footprint = fp;
    ss_heal_run *a, *b;
    assert_int_equal(ss_heal_run_create(&c, &a, &err), SS_OK);
    c.wound_footprint = NULL;
    c.wound_mask = png;
    assert_int_equal(ss_heal_run_create(&c, &b, &err), SS_OK);
    assert_fields_equal(ss_heal_run_grid(a), ss_heal_run_grid(b));
    int n;
    /* 2x2 pixels per voxel: 10 x 6 columns of 0.25 mm^2 */
    assert_true(ss_heal_run_area(a, &n)[0].st.initial_area_mm2 == 15);
    ss_heal_run_free(a);
    ss_heal_run_free(b);
    /* two sources at once */
    c.wound_footprint = fp;
    assert_int_equal(ss_heal_run_create(&c, &a, &err), SS_ERR_INPUT);
    assert_null(a);
    ss_image_free(fp);
    tu_rmtree(dir);
    free(dir);
}

/* Bad configs: input errors naming the setting, nothing written. */
static void test_run_bad_config(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("heal-run-bad");
    char out[1024];
    snprintf(out, sizeof out, "%s/out", dir);
    static const char *const expect[] = {"--size-mm",         "--grid",     "--days",
                                         "--wound-depth-mm",  "--scenario", "--concave-k",
                                         "--checkpoint-every"};
    for (int k = 0; k < 7; k++) {
        ss_heal_run_config c;
        small_config(&c);
        c.out_dir = out;
        switch (k) {
        case 0:
            c.grid[0] = c.grid[1] = c.grid[2] = 0;
            c.size_mm[0] = -1, c.size_mm[1] = 2, c.size_mm[2] = 3;
            break;
        case 1:
            c.grid[2] = 2;
            break;
        case 2:
            c.days = -1;
            break;
        case 3:
            c.wound_depth_mm = 9;
            break;
        case 4:
            c.scenario = "bogus";
            break;
        case 5:
            c.concave_k = 2;
            break;
        default:
            c.checkpoint_every = NAN;
            break;
        }
        ss_heal_run *r = (ss_heal_run *)&c;
        ss_error_clear(&err);
        assert_int_equal(ss_heal_run_create(&c, &r, &err), SS_ERR_INPUT);
        assert_null(r);
        if (k != 4) assert_non_null(strstr(err.msg, expect[k]));
        struct stat sb;
        assert_int_not_equal(stat(out, &sb), 0);
    }
    ss_heal_run_config c;
    ss_heal_run_config_default(&c);
    snprintf(out, sizeof out, "%s/none", dir);
    c.resume_dir = out;
    ss_heal_run *r;
    assert_int_equal(ss_heal_run_create(&c, &r, &err), SS_ERR_INPUT);
    tu_rmtree(dir);
    free(dir);
}

static void test_run_distributed(void **state) {
    (void)state;
    ss_error err;
    ss_heal_run_config c;
    small_config(&c);
    c.scheme = SS_HEAL_EXPLICIT;
    ss_heal_run *whole = NULL, *r = NULL;
    assert_int_equal(ss_heal_run_create(&c, &whole, &err), SS_OK);
    c.distributed = 1;
    assert_int_equal(ss_heal_run_create(&c, &r, &err), SS_OK);
    const ss_heal_grid *g = ss_heal_run_grid(r), *G = ss_heal_run_grid(whole);
    assert_null(g->cell);
    assert_null(g->field[0]);
    assert_int_equal(g->nx, G->nx);
    assert_int_equal(g->nz, G->nz);
    assert_true(g->skin_top_mm == G->skin_top_mm);
    assert_true(ss_heal_run_dt(r) == ss_heal_run_dt(whole));
    assert_true(ss_heal_run_epidermis_mm(r) == c.epidermis_mm);
    /* the wound's column ranges expand to the whole run's wound cells */
    const int32_t *cols = ss_heal_run_wound_columns(r);
    assert_non_null(cols);
    assert_null(ss_heal_run_wound_mesh(r));
    for (int y = 0; y < G->ny; y++)
        for (int x = 1; x < G->nx - 1; x++)
            for (int z = 1; z < G->nz - 1; z++) {
                const size_t k = (size_t)y * G->nx + x;
                const int S = SS_HEAL_WOUND_SUB; /* ranges in 1/S of a level */
                const int in = (z + 1) * S > cols[2 * k] && z * S < cols[2 * k + 1];
                if (y > 0 && y < G->ny - 1)
                    assert_int_equal(in, G->cell[ss_heal_idx(G, x, y, z)] == SS_CELL_WOUND);
            }
    /* no area row, no step, no checkpoint without the driver's hooks */
    int n = -1;
    ss_heal_run_area(r, &n);
    assert_int_equal(n, 0);
    assert_int_equal(ss_heal_run_step(r, &err), SS_ERR_INPUT);
    ss_heal_run_hooks h = {0};
    assert_int_equal(ss_heal_run_set_hooks(r, &h, &err), SS_ERR_INPUT);
    ss_heal_run_free(r);
    ss_heal_run_free(whole);
    /* the mechanics wait for a grid of what they read (the MPI driver's, on
     * rank 0): hooks without mech_in / mech_out and a grid of another size
     * are refused by name */
    c.mechanics = 1;
    assert_int_equal(ss_heal_run_create(&c, &r, &err), SS_OK);
    assert_true(ss_heal_run_mech_pending(r));
    assert_null(ss_heal_run_mech(r));
    assert_int_equal(ss_heal_run_set_hooks(r, &h, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "--mechanics"));
    ss_heal_grid *small = ss_heal_grid_create(3, 3, 3, 0.5, &err);
    assert_non_null(small);
    assert_int_equal(ss_heal_run_mech_attach(r, small, &err), SS_ERR_INPUT); /* frees small */
    assert_true(ss_heal_run_mech_pending(r));
    ss_heal_run_free(r);
}

/* ss_heal_run_set_progress: called after every step with the run's day; a
 * non-zero answer stops advance_to after that step, and advancing to the
 * same day again ends where an uninterrupted run ends, bit for bit. */
typedef struct day_poll {
    int calls;
    double last, stop_day;
} day_poll;
static int poll_day(void *user, double day) {
    day_poll *p = user;
    assert_true(day > p->last);
    p->last = day;
    p->calls++;
    return day >= p->stop_day - 1e-9;
}
static void test_run_cancel(void **state) {
    (void)state;
    ss_error err;
    ss_heal_run_config c;
    small_config(&c);
    ss_heal_run *a, *b;
    assert_int_equal(ss_heal_run_create(&c, &a, &err), SS_OK);
    assert_int_equal(ss_heal_run_create(&c, &b, &err), SS_OK);
    assert_int_equal(ss_heal_run_advance_to(a, 1.0, &err), SS_OK);
    day_poll p = {0, -1.0, 0.3};
    ss_heal_run_set_progress(b, poll_day, &p);
    assert_int_equal(ss_heal_run_advance_to(b, 1.0, &err), SS_ERR_RUNTIME);
    assert_non_null(strstr(err.msg, "cancelled"));
    assert_int_equal(p.calls, 6); /* 0.05 .. 0.30 */
    assert_true(fabs(ss_heal_run_day(b) - 0.3) < 1e-9);
    ss_heal_run_set_progress(b, NULL, NULL);
    assert_int_equal(ss_heal_run_advance_to(b, 1.0, &err), SS_OK);
    assert_fields_equal(ss_heal_run_grid(a), ss_heal_run_grid(b));
    ss_heal_run_free(a);
    ss_heal_run_free(b);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_run_matches_solver), cmocka_unit_test(test_run_resume),
        cmocka_unit_test(test_run_adaptive),       cmocka_unit_test(test_run_footprint),
        cmocka_unit_test(test_run_bad_config),     cmocka_unit_test(test_run_distributed),
        cmocka_unit_test(test_run_cancel),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
