/* Machine resources: the thread count for OpenMP loops (--threads N, else
 * $SKINSIM_THREADS, else all cores; both 1..SS_THREADS_MAX, checked by one
 * parser) and the physical memory. */
#define _DEFAULT_SOURCE /* sysconf(_SC_PHYS_PAGES) */
#include "skinsim/core.h"

#include <errno.h>
#include <omp.h>
#include <stdlib.h>
#include <unistd.h>

ss_status ss_threads_parse(const char *what, const char *s, int *n, ss_error *err) {
    char *end;
    errno = 0;
    long v = s ? strtol(s, &end, 10) : 0;
    if (!s || !*s || end == s || *end != '\0' || errno == ERANGE)
        return ss_error_set(err, SS_ERR_INPUT, "%s: '%s' is not a whole number of threads", what,
                            s ? s : "(missing)");
    if (v < 1 || v > SS_THREADS_MAX)
        return ss_error_set(err, SS_ERR_INPUT, "%s: %s threads is out of range [1, %d]", what, s,
                            SS_THREADS_MAX);
    *n = (int)v;
    return SS_OK;
}

ss_status ss_threads_check_env(ss_error *err) {
    const char *env = getenv("SKINSIM_THREADS");
    int n;
    if (!env || !*env) return SS_OK;
    return ss_threads_parse("SKINSIM_THREADS", env, &n, err);
}

int ss_threads_set(int n) {
    if (n <= 0) {
        /* an invalid $SKINSIM_THREADS is refused by the CLI before this;
         * a library caller falls back to all cores */
        const char *env = getenv("SKINSIM_THREADS");
        int v = 0;
        n = env && *env && !ss_threads_parse("SKINSIM_THREADS", env, &v, NULL)
                ? v
                : omp_get_num_procs();
    }
    if (n > SS_THREADS_MAX) n = SS_THREADS_MAX;
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
