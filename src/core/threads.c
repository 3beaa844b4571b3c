/* Machine resources: the thread count for OpenMP loops (--threads N, else
 * $SKINSIM_THREADS, else all cores) and the physical memory. */
#define _DEFAULT_SOURCE /* sysconf(_SC_PHYS_PAGES) */
#include "skinsim/core.h"

#include <omp.h>
#include <stdlib.h>
#include <unistd.h>

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

double ss_memory_physical_bytes(void) {
#ifdef _SC_PHYS_PAGES
    long pages = sysconf(_SC_PHYS_PAGES), psz = sysconf(_SC_PAGESIZE);
    if (pages > 0 && psz > 0) return (double)pages * (double)psz;
#endif
    return 0.0;
}
