/* Benchmark: building the ModelMatch table (seed 003 §4.8.6, §6.1) at 3
 * samples per axis over the six optical biological parameters (729 entries)
 * with the default build options of `skinsim optics table`, against the
 * seed's 22 hours on two notebooks (target <= 5 minutes on 2 cores). Also
 * times one direct sampled BRDF + fit for comparison with the per-entry cost
 * of the fast path. Prints figures only.
 *
 * usage: bench_optics_table [samples_per_axis (3)] [photons (default build)] */
#include <stdio.h>
#include <stdlib.h>

#include "skinsim/optics_fit.h"

int main(int argc, char **argv) {
    int samples = argc > 1 ? atoi(argv[1]) : 3;
    if (samples < 1 || samples > 9) samples = 3;
    ss_error err;
    ss_mm_build_options o;
    ss_mm_build_options_default(&o);
    if (argc > 2) o.spectrum.mc.photons = strtoull(argv[2], NULL, 10);
    int threads = ss_threads_set(0);
    int ns[SS_MM_NAXES];
    double lo[SS_MM_NAXES], hi[SS_MM_NAXES];
    for (int a = 0; a < SS_MM_NAXES; a++) {
        ns[a] = samples;
        ss_mm_axis_default_range(a, &lo[a], &hi[a]);
    }
    ss_mm_table *t = ss_mm_table_create(ns, lo, hi, &err);
    if (!t) {
        fprintf(stderr, "%s\n", err.msg);
        return 1;
    }
    int nwl =
        (int)((o.spectrum.wl_max_nm - o.spectrum.wl_min_nm) / o.spectrum.wl_step_nm + 1e-9) + 1;
    printf("ModelMatch table: %d samples per axis, %zu entries, %d threads\n", samples, t->nentries,
           threads);
    printf("  %llu photons per trace, %d wavelengths (%g..%g nm), BRDF bins %d x %d x %d\n",
           (unsigned long long)o.spectrum.mc.photons, nwl, o.spectrum.wl_min_nm,
           o.spectrum.wl_max_nm, o.n_theta_i, o.n_theta_r, o.n_phi);
    double t0 = ss_now();
    if (ss_mm_table_build(t, &o, &err)) {
        fprintf(stderr, "%s\n", err.msg);
        return 1;
    }
    double secs = ss_now() - t0;
    printf("  build time %.1f s (%.3f s per entry); seed: 22 h for 3^8 on two notebooks; "
           "target <= 300 s on 2 cores\n",
           secs, secs / (double)t->nentries);

    /* lookup throughput (multilinear over 2^6 nodes, 18 fields) */
    int nl = 1000000;
    double acc = 0, out[SS_MM_NFIELDS];
    t0 = ss_now();
    for (int i = 0; i < nl; i++) {
        double x[SS_MM_NAXES];
        for (int a = 0; a < SS_MM_NAXES; a++)
            x[a] = lo[a] + (hi[a] - lo[a]) * ss_rng_uniform(7, (uint64_t)a, (uint64_t)i);
        ss_mm_table_lookup(t, x, out);
        acc += out[0];
    }
    secs = ss_now() - t0;
    printf("  lookup: %.2f million per second on one thread (checksum %.3f)\n", nl / secs / 1e6,
           acc / nl);
    ss_mm_table_free(t);

    /* one entry by direct simulation (ss_optics_brdf_sample) and the two fits */
    ss_bio_params b;
    ss_bio_params_default(&b);
    ss_brdf_sampled s;
    t0 = ss_now();
    if (ss_optics_brdf_sample(&b, &o.spectrum, o.n_theta_i, o.n_theta_r, o.n_phi, &s, &err)) {
        fprintf(stderr, "%s\n", err.msg);
        return 1;
    }
    double t1 = ss_now();
    ss_fit_result r;
    for (int m = 0; m < SS_RENDER_NMODELS; m++)
        ss_render_fit((ss_render_model)m, &s, &o.fit, &r, &err);
    double t2 = ss_now();
    ss_brdf_sampled_free(&s);
    printf("  one entry by direct simulation: %.2f s transport + %.3f s fits (x %d entries = "
           "%.0f s)\n",
           t1 - t0, t2 - t1, samples * samples * samples * samples * samples * samples,
           (t2 - t0) * samples * samples * samples * samples * samples * samples);
    printf("  (machine shared with other jobs: figures are noisy)\n");
    return 0;
}
