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

#endif
