/* Benchmark of the healing biochemistry step (seed 001 Table 1: 0.128, 0.684
 * and 5.356 s per frame on one thread for 80x62x79, 160x124x159, 320x248x319).
 * For each grid, scheme (explicit, split) and thread count (1, 2) it prints
 * seconds per step, species-cell updates per second (8 species x interior
 * cells / time per step) and the peak resident memory.
 * Usage: bench_heal [--skip-large] [--steps N] [--threads "1 2"]
 * Figures only; nothing is asserted. The clean-regeneration preset and a
 * 20 x 20 mm wound, 1 mm deep, as in the seed's Table 1 example. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

#include "skinsim/heal.h"

static double peak_rss_mb(void) {
    FILE *f = fopen("/proc/self/status", "r");
    if (!f) return -1;
    char line[256];
    double mb = -1;
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, "VmHWM:", 6)) mb = atof(line + 6) / 1024.0;
    fclose(f);
    return mb;
}

int main(int argc, char **argv) {
    int skip_large = 0, steps_override = 0;
    int threads[2] = {1, 2}, nthr = 2;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--skip-large"))
            skip_large = 1;
        else if (!strcmp(argv[i], "--steps") && i + 1 < argc)
            steps_override = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc) {
            nthr = sscanf(argv[++i], "%d %d", &threads[0], &threads[1]);
            if (nthr < 1) nthr = 1;
        } else {
            fprintf(stderr, "usage: bench_heal [--skip-large] [--steps N] [--threads \"1 2\"]\n");
            return 2;
        }
    }
    static const int dims[3][3] = {{80, 62, 79}, {160, 124, 159}, {320, 248, 319}};
    static const double table1[3] = {0.128, 0.684, 5.356};
    ss_error err;
    ss_heal_params *p = ss_heal_params_preset("clean", &err);
    printf("# heal step benchmark (clean preset). Seed Table 1: s/frame on 1 thread, Xeon E5 "
           "3.5 GHz. Target >= 3e8 species-cell updates/s on 2 cores.\n");
    printf("# s/day = wall seconds per simulated day (explicit at 0.9 x its stability limit, "
           "split at its default step); peakMB is the process peak so far.\n");
    printf("%-14s %-8s %3s %10s %12s %14s %10s %10s %10s\n", "grid", "scheme", "thr", "dt_days",
           "s/step", "upd/s", "s/day", "peakMB", "seed_s");
    for (int gi = 0; gi < 3; gi++) {
        if (gi == 2 && skip_large) continue;
        const int nx = dims[gi][0], ny = dims[gi][1], nz = dims[gi][2];
        const double dx = 30.0 / nx; /* 30 mm block, as for the 2 x 2 cm wound */
        const double top = 0.8 * nz * dx;
        for (int sc = 0; sc < 2; sc++) {
            for (int ti = 0; ti < nthr; ti++) {
                omp_set_num_threads(threads[ti]);
                ss_heal_grid *g = ss_heal_grid_create(nx, ny, nz, dx, &err);
                if (!g) {
                    fprintf(stderr, "%s\n", err.msg);
                    return 1;
                }
                uint8_t *w = ss_heal_wound_box(g, top, 20.0, 20.0, 1.0, &err);
                if (!w || ss_heal_grid_init(g, top, 0.1, w, p, &err) != SS_OK) {
                    fprintf(stderr, "%s\n", err.msg);
                    return 1;
                }
                free(w);
                ss_heal_scheme s = sc ? SS_HEAL_SPLIT : SS_HEAL_EXPLICIT;
                ss_heal_solver *sol = ss_heal_solver_create(g, p, s, 0, &err);
                if (!sol) {
                    fprintf(stderr, "%s\n", err.msg);
                    return 1;
                }
                int steps = steps_override > 0 ? steps_override : gi == 0 ? 20 : gi == 1 ? 6 : 2;
                if (ss_heal_step(sol, g, &err) != SS_OK) return 1; /* warm-up */
                double t0 = ss_now();
                for (int k = 0; k < steps; k++)
                    if (ss_heal_step(sol, g, &err) != SS_OK) return 1;
                double sps = (ss_now() - t0) / steps;
                double cells = (double)(nx - 2) * (ny - 2) * (nz - 2);
                char gname[32];
                snprintf(gname, sizeof gname, "%dx%dx%d", nx, ny, nz);
                printf("%-14s %-8s %3d %10.3g %12.4f %14.3g %10.2f %10.0f %10.3f\n", gname,
                       sc ? "split" : "explicit", threads[ti], ss_heal_solver_dt(sol), sps,
                       SS_HEAL_NFIELDS * cells / sps, sps / ss_heal_solver_dt(sol), peak_rss_mb(),
                       table1[gi]);
                fflush(stdout);
                ss_heal_solver_free(sol);
                ss_heal_grid_free(g);
            }
        }
    }
    ss_heal_params_free(p);
    return 0;
}
