/* Benchmark of `skinsim wound` (issue 12 item 7; DESIGN.md target: healing
 * textures per output day at 2048^2 <= 1 s on 2 cores, the heal dominating):
 * the built-in 2 cm wound (20 x 20 mm, 1 mm deep, scab scenario) in the
 * default 30 x 30 x 4 mm block, output days 0,1,3,7,14,28,90,365 at
 * 2048 x 2048. Prints the one-off renderer set-up (base skin textures, the
 * blood-layer tables), then per day the heal time since the previous day
 * (adaptive steps as `skinsim wound` takes them; the run keeps each column's
 * closure day) and the texture time
 * (sampling the tissue with ss_wound_tissue_observe_closure, then
 * ss_wound_render), as `skinsim wound` does it.
 * PNG writing is not included. CPU seconds (all threads) are printed next to
 * the wall clock: on a loaded machine CPU / threads is what idle cores give.
 * Usage: bench_wound [--size N] [--threads N]
 * Figures only; nothing is asserted. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "skinsim/wound.h"

static double cpu(void) { return (double)clock() / CLOCKS_PER_SEC; }

static const double days[] = {0, 1, 3, 7, 14, 28, 90, 365};

int main(int argc, char **argv) {
    int size = 2048, threads = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--size") && i + 1 < argc)
            size = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
            threads = atoi(argv[++i]);
        else {
            fprintf(stderr, "usage: bench_wound [--size N] [--threads N]\n");
            return 2;
        }
    }
    ss_threads_set(threads);
    ss_error err;
    const int ndays = 8;
    ss_heal_run_config hc;
    ss_heal_run_config_default(&hc);
    hc.scenario = "scab";
    hc.days = days[ndays - 1];
    hc.adapt_tol = SS_HEAL_RUN_DEFAULT_ADAPT_TOL; /* as `skinsim wound` runs it */
    ss_heal_run *run;
    char path[4096];
    snprintf(path, sizeof path, "%s/modelmatch_default.sstab", ss_data_dir());
    ss_mm_table *table = ss_mm_table_read(path, &err);
    if (!table || ss_heal_run_create(&hc, &run, &err)) {
        fprintf(stderr, "bench_wound: %s\n", err.msg);
        return 1;
    }
    const ss_heal_grid *g = ss_heal_run_grid(run);
    double side = g->nx * g->dx_mm, t0 = ss_now(), c0 = cpu();
    ss_image *skin = ss_skin_bio_default(size, side / 10.0, 1, &err); /* forearm skin */
    ss_wound_render_options o;
    ss_wound_render_options_default(&o);
    o.size = size;
    o.side_mm = side;
    o.skin = skin;
    o.table = table;
    ss_wound_renderer *r = NULL;
    ss_wound_recipe rec;
    ss_wound_recipe_default(&rec);
    ss_wound_tissue *t = ss_wound_tissue_create(g, ss_heal_run_params(run), &rec, &err);
    ss_wound_textures tex;
    if (!skin || !t || ss_wound_renderer_create(&o, &r, &err) ||
        ss_wound_textures_create(size, &tex, &err)) {
        fprintf(stderr, "bench_wound: %s\n", err.msg);
        return 1;
    }
    printf("bench_wound: %dx%d texels, %d threads, heal grid %dx%dx%d of %g mm, scab scenario\n",
           size, size, ss_threads_get(), g->nx, g->ny, g->nz, g->dx_mm);
    printf("renderer set-up (base skin textures, blood-layer tables): %.3f s (cpu %.3f s)\n",
           ss_now() - t0, cpu() - c0);
    printf("%8s %10s %10s %12s %12s\n", "day", "heal_s", "heal_cpu", "texture_s", "texture_cpu");
    double heal_sum = 0, tex_sum = 0, tex_cpu = 0;
    for (int k = 0; k < ndays; k++) {
        double a = ss_now(), ca = cpu();
        if (ss_heal_run_advance_to(run, days[k], &err)) {
            fprintf(stderr, "bench_wound: %s\n", err.msg);
            return 1;
        }
        double b = ss_now(), cb = cpu();
        ss_wound_tissue_observe_closure(t, ss_heal_run_grid(run), ss_heal_run_closure(run));
        if (ss_wound_render(r, t, NULL, &tex, &err)) {
            fprintf(stderr, "bench_wound: %s\n", err.msg);
            return 1;
        }
        double c = ss_now(), cc = cpu();
        printf("%8g %10.3f %10.3f %12.3f %12.3f\n", days[k], b - a, cb - ca, c - b, cc - cb);
        heal_sum += b - a;
        tex_sum += c - b;
        tex_cpu += cc - cb;
    }
    printf("total: heal %.3f s, textures %.3f s (%.3f s per day, cpu %.3f s per day; target "
           "<= 1 s on 2 cores)\n",
           heal_sum, tex_sum, tex_sum / ndays, tex_cpu / ndays);
    ss_wound_textures_free(&tex);
    ss_wound_renderer_free(r);
    ss_wound_tissue_free(t);
    ss_image_free(skin);
    ss_heal_run_free(run);
    ss_mm_table_free(table);
    return 0;
}
