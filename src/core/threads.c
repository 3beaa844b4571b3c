/* Thread count for OpenMP loops: --threads N, else $SKINSIM_THREADS, else all cores. */
#include "skinsim/core.h"

#include <omp.h>
#include <stdlib.h>

int ss_threads_set(int n) {
    if (n <= 0) {
        const char *env = getenv("SKINSIM_THREADS");
        long v = env ? strtol(env, NULL, 10) : 0;
        n = v > 0 && v <= 4096 ? (int)v : omp_get_num_procs();
    }
    omp_set_num_threads(n);
    return n;
}

int ss_threads_get(void) { return omp_get_max_threads(); }
