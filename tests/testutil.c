/* Test helpers; see testutil.h. */
#define _POSIX_C_SOURCE 200809L
#include "testutil.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include "skinsim/heal.h"

char *tu_tmpdir(const char *tag) {
    char tmpl[256];
    snprintf(tmpl, sizeof tmpl, "/tmp/skinsim-%s-XXXXXX", tag);
    char *d = mkdtemp(tmpl);
    return d ? strdup(d) : NULL;
}

void tu_rmtree(const char *path) {
    if (!path || strncmp(path, "/tmp/", 5) != 0) return;
    char cmd[4200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", path);
    if (system(cmd) != 0) fprintf(stderr, "warning: could not remove %s\n", path);
}

int tu_run_cli(const char *args, const char *out, const char *errp) {
    char cmd[8192];
    snprintf(cmd, sizeof cmd, "'%s' %s >%s 2>%s", SKINSIM_CLI, args, out ? out : "/dev/null",
             errp ? errp : "/dev/null");
    int rc = system(cmd);
    if (rc == -1 || !WIFEXITED(rc)) return -1;
    return WEXITSTATUS(rc);
}

int tu_file_exists(const char *path) {
    struct stat st;
    return stat(path, &st) == 0 && st.st_size > 0;
}

int tu_count_entries(const char *dir) {
    DIR *d = opendir(dir);
    if (!d) return 0;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) n++;
    closedir(d);
    return n;
}

int tu_quick(void) {
    const char *q = getenv("SKINSIM_TEST_QUICK");
    return q && *q && strcmp(q, "0");
}

char *tu_join(const char *dir, const char *name) {
    size_t n = strlen(dir) + strlen(name) + 2;
    char *p = malloc(n);
    assert_non_null(p);
    snprintf(p, n, "%s/%s", dir, name);
    return p;
}

ss_heal_grid *tu_heal_grid_noisy(int nx, int ny, int nz, double dx_mm, uint64_t seed, int vel) {
    ss_error err;
    ss_heal_grid *g = ss_heal_grid_create(nx, ny, nz, dx_mm, &err);
    assert_non_null(g);
    size_t n = (size_t)nx * ny * nz;
    for (size_t i = 0; i < n; i++) g->cell[i] = (uint8_t)(ss_rng_u32(seed, 7, i) % 5);
    for (int f = 0; f < SS_HEAL_NFIELDS; f++)
        for (size_t i = 0; i < n; i++)
            g->field[f][i] = (float)ss_rng_uniform(seed, 20 + (uint64_t)f, i) * 3.0f - 1.0f;
    for (int c = 0; vel && c < 3; c++) { /* mm/day, as the mechanics set them */
        g->velocity[c] = malloc(n * sizeof(float));
        assert_non_null(g->velocity[c]);
        for (size_t i = 0; i < n; i++)
            g->velocity[c][i] = (float)ss_rng_uniform(seed, 40 + (uint64_t)c, i) - 0.5f;
    }
    g->skin_top_mm = 1.65;
    g->t_days = 3.3333333333333335;
    g->step = 987654321ULL;
    return g;
}

void tu_assert_heal_grids_equal(const ss_heal_grid *a, const ss_heal_grid *b) {
    assert_int_equal(a->nx, b->nx);
    assert_int_equal(a->ny, b->ny);
    assert_int_equal(a->nz, b->nz);
    assert_true(a->dx_mm == b->dx_mm && a->skin_top_mm == b->skin_top_mm);
    assert_true(a->t_days == b->t_days && a->step == b->step);
    size_t n = (size_t)a->nx * a->ny * a->nz;
    assert_memory_equal(a->cell, b->cell, n);
    for (int f = 0; f < SS_HEAL_NFIELDS; f++)
        assert_memory_equal(a->field[f], b->field[f], n * sizeof(float));
    for (int c = 0; c < 3; c++) {
        assert_true(!a->velocity[c] == !b->velocity[c]);
        if (a->velocity[c]) assert_memory_equal(a->velocity[c], b->velocity[c], n * sizeof(float));
    }
    assert_true(!a->added == !b->added);
    if (a->added) assert_memory_equal(a->added, b->added, n * sizeof(float));
}

int tu_poll_count(void *user, double fraction) {
    tu_poll *p = user;
    assert_true(fraction >= p->last && fraction <= 1.0);
    p->last = fraction;
    return ++p->calls == p->stop_at;
}
