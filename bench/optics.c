/* Photon-transport throughput (seed 003 §4.4; DESIGN.md performance table):
 * photons/s on one and two threads for (a) the four-layer skin input of
 * docs/optics.md as an MCML-style slab (smooth surface, transmitting bottom),
 * (b) the same skin as the seed models it (rough surface sigma 0.75, white fat
 * reflector), (c) the van de Hulst slab. Anchor: MCML runs about 55,000
 * photons/s/core on such a skin input on these machines; target >= 2x.
 * Figures only, never asserted. Usage: bench_optics [photons] */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "skinsim/optics.h"

/* Wall-clock photons/s; *cpu_rate gets photons per CPU-second (process CPU
 * time over all threads), which is less sensitive to a shared machine. */
static double rate(const ss_optics_slab *s, const ss_mc_options *o, int threads, double *rd,
                   double *cpu_rate) {
    omp_set_num_threads(threads);
    ss_mc_result r;
    ss_error e;
    clock_t c0 = clock();
    double t = ss_now();
    if (ss_mc_run(s, o, &r, &e)) {
        fprintf(stderr, "bench_optics: %s\n", e.msg);
        exit(1);
    }
    t = ss_now() - t;
    *cpu_rate = (double)o->photons / ((double)(clock() - c0) / CLOCKS_PER_SEC);
    *rd = r.diffuse;
    ss_mc_result_free(&r);
    return (double)o->photons / t;
}

static void row(const char *name, const ss_optics_slab *s, const ss_mc_options *o) {
    double rd1, rd2, c1, c2;
    double r1 = rate(s, o, 1, &rd1, &c1), r2 = rate(s, o, 2, &rd2, &c2);
    printf("%-44s %12.0f %12.0f %6.2fx %14.0f %14.0f  (Rd %.4f, identical %s)\n", name, r1, r2,
           r2 / r1, c1, c2, rd1, rd1 == rd2 ? "yes" : "NO");
}

int main(int argc, char **argv) {
    uint64_t n = argc > 1 ? strtoull(argv[1], NULL, 10) : 400000;
    /* (a) the MCML-style skin input: docs/optics.md, 550 nm, default light skin */
    ss_optics_slab skin;
    memset(&skin, 0, sizeof skin);
    skin.nlayers = 4;
    skin.layer[0] = (ss_optics_layer){1.55, 0.4605, 373.6, 0.90, 0.001, 0, {0}};
    skin.layer[1] = (ss_optics_layer){1.40, 5.479, 373.6, 0.90, 0.01, 0, {0}};
    skin.layer[2] = (ss_optics_layer){1.36, 1.643, 169.4, 0.7795, 0.02, 0, {0}};
    skin.layer[3] = (ss_optics_layer){1.38, 1.643, 169.4, 0.7795, 0.18, 0, {0}};
    skin.n_above = 1.0;
    skin.n_below = 1.44;
    skin.bottom_albedo = -1.0;
    ss_mc_options o;
    ss_mc_options_default(&o);
    o.photons = n;
    printf("photons per run: %llu (machine shared: figures are noisy)\n", (unsigned long long)n);
    printf("%-44s %12s %12s %7s %14s %14s\n", "input", "1 thread/s", "2 threads/s", "scale",
           "1t per CPU-s", "2t per CPU-s");
    row("4-layer skin, MCML-style (smooth, transmit)", &skin, &o);
    /* (b) the seed's model at 550 nm */
    ss_bio_params b;
    ss_bio_params_default(&b);
    ss_optics_slab seedskin;
    ss_error e;
    if (ss_optics_skin_slab(&b, 550, &seedskin, &e)) {
        fprintf(stderr, "bench_optics: %s\n", e.msg);
        return 1;
    }
    ss_mc_options os = o;
    os.roughness_sigma = 0.75;
    row("skin model, rough 0.75, white fat, 550 nm", &seedskin, &os);
    /* (c) van de Hulst */
    ss_optics_slab v;
    memset(&v, 0, sizeof v);
    v.nlayers = 1;
    v.layer[0] = (ss_optics_layer){1.0, 10, 90, 0.75, 0.02, 0, {0}};
    v.n_above = v.n_below = 1.0;
    v.bottom_albedo = -1;
    ss_mc_options ov = o;
    ov.photons = n * 10;
    row("van de Hulst slab", &v, &ov);
    printf("anchor: MCML ~55,000 photons/s/core on a 4-layer skin input; target >= 110,000\n");
    return 0;
}
