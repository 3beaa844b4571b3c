/* Helpers shared by the tests: temporary directories, running the CLI, quick mode. */
#ifndef SKINSIM_TESTUTIL_H
#define SKINSIM_TESTUTIL_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "skinsim/core.h"

/* Creates a fresh temporary directory; returns a static-lifetime path (malloc'd). */
char *tu_tmpdir(const char *tag);
/* Removes a directory tree (rm -rf). */
void tu_rmtree(const char *path);
/* Runs the built skinsim CLI with a shell-quoted argument string; returns its
 * exit code. stdout/stderr go to files under /tmp unless out/errpath are given. */
int tu_run_cli(const char *args, const char *stdout_path, const char *stderr_path);
/* 1 when file exists and is non-empty. */
int tu_file_exists(const char *path);
/* Number of entries in a directory (0 if it does not exist). */
int tu_count_entries(const char *dir);
/* 1 under SKINSIM_TEST_QUICK (sanitizer runs): tests use smaller problems. */
int tu_quick(void);
/* dir/name (malloc'd). */
char *tu_join(const char *dir, const char *name);

/* A healing grid of voxel dx_mm with every array filled from the
 * counter-based generator (seed): cell states 0-4, fields in [-1, 2), with
 * vel the three velocity arrays too; odd skin top, time and step, so that a
 * writer/reader pair that drops a bit shows. */
struct ss_heal_grid *tu_heal_grid_noisy(int nx, int ny, int nz, double dx_mm, uint64_t seed,
                                        int vel);
/* Asserts that two healing grids hold the same state, bit for bit. */
void tu_assert_heal_grids_equal(const struct ss_heal_grid *a, const struct ss_heal_grid *b);

/* A progress callback (ss_progress_fn) that counts its calls, asserts the
 * fraction rises and stays in [0, 1], and asks the call to stop at call
 * number stop_at (0: never). */
typedef struct tu_poll {
    int calls, stop_at;
    double last;
} tu_poll;
int tu_poll_count(void *user, double fraction);

#endif
