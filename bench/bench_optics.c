/* Photon-transport throughput (seed 003 §4.4; DESIGN.md performance table):
 * photons/s on one and two threads for (a) the four-layer skin input of
 * docs/optics.md as an MCML-style slab (smooth surface, transmitting bottom),
 * (b) the same skin as the seed models it (rough surface sigma 0.75, white fat
 * reflector), (c) the van de Hulst slab, on the packet path (the default) and
 * per CPU-second on the scalar loop (`--scalar`) beside it. Target: >= 3x
 * MCML per core, measured side by side (below). Figures only, never asserted.
 * Usage: bench_optics [photons]
 *
 * Side-by-side mode: bench_optics --mcml PATH/TO/mcml [--repeat N] FILE.mci...
 * runs a user-built MCML binary (none is shipped; build one from the public
 * MCML 1.2 sources) and skinsim's MCML runner (one thread) on both of its paths
 * back to back on the same .mci inputs, N rounds alternating MCML, packet,
 * scalar, and prints the CPU seconds of each (MCML: the child's user + system
 * time from wait4; skinsim: this process's CPU time around parse + simulate),
 * the best-of-N ratios MCML / packet and MCML / scalar, the range of the
 * per-round ratios MCML / packet, and the diffuse reflectance of each. The
 * packet path is also run on two threads to show that its output is
 * identical. MCML writes its .mco in a temporary directory that is removed
 * afterwards. */
#define _DEFAULT_SOURCE
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "skinsim/optics.h"

static double cpu_now(void) {
    struct rusage u;
    getrusage(RUSAGE_SELF, &u);
    return (double)u.ru_utime.tv_sec + 1e-6 * (double)u.ru_utime.tv_usec +
           (double)u.ru_stime.tv_sec + 1e-6 * (double)u.ru_stime.tv_usec;
}

/* Runs MCML on mci_path inside dir; returns its CPU seconds or -1. */
static double run_mcml(const char *mcml, const char *dir, const char *mci_name) {
    fflush(stdout);
    fflush(stderr);
    pid_t pid = fork();
    if (pid < 0) return -1;
    if (pid == 0) {
        if (chdir(dir) != 0) _exit(127);
        if (!freopen("/dev/null", "w", stdout)) _exit(127);
        execl(mcml, mcml, mci_name, (char *)NULL);
        _exit(127);
    }
    int status;
    struct rusage u;
    if (wait4(pid, &status, 0, &u) < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) return -1;
    return (double)u.ru_utime.tv_sec + 1e-6 * (double)u.ru_utime.tv_usec +
           (double)u.ru_stime.tv_sec + 1e-6 * (double)u.ru_stime.tv_usec;
}

/* skinsim on every run of the file with `threads` threads; returns CPU
 * seconds and the first run's .mco text in *mco (malloc'd). */
static double run_skinsim(const char *text, const char *name, int threads, int kernel, char **mco) {
    omp_set_num_threads(threads);
    ss_error e;
    ss_mci_file f;
    double c0 = cpu_now();
    if (ss_mci_parse(text, name, &f, &e)) {
        fprintf(stderr, "bench_optics: %s\n", e.msg);
        exit(2);
    }
    *mco = NULL;
    for (int r = 0; r < f.nruns; r++) {
        char *t = NULL;
        f.runs[r].kernel = kernel;
        if (ss_mci_simulate(&f.runs[r], 1, &t, &e)) {
            fprintf(stderr, "bench_optics: %s\n", e.msg);
            exit(1);
        }
        if (r == 0)
            *mco = t;
        else
            free(t);
    }
    ss_mci_file_free(&f);
    return cpu_now() - c0;
}

/* The four RAT numbers after the "RAT" line of an .mco text. */
static void rat_of(const char *mco, double v[4]) {
    v[0] = v[1] = v[2] = v[3] = -1;
    const char *p = mco ? strstr(mco, "\nRAT") : NULL;
    if (!p) return;
    p = strchr(p + 1, '\n');
    for (int k = 0; k < 4 && p; k++) {
        v[k] = strtod(p + 1, NULL);
        p = strchr(p + 1, '\n');
    }
}

static int compare_mcml(int argc, char **argv) {
    const char *mcml = argv[2];
    int repeat = 3, first = 3;
    if (argc > 4 && !strcmp(argv[3], "--repeat")) {
        repeat = atoi(argv[4]);
        first = 5;
        if (repeat < 1 || repeat > 100) {
            fprintf(stderr, "bench_optics: --repeat %s: need 1..100\n", argv[4]);
            return 2;
        }
    }
    if (access(mcml, X_OK) != 0) {
        fprintf(stderr, "bench_optics: MCML binary '%s' is not executable\n", mcml);
        return 2;
    }
    if (first >= argc) {
        fprintf(stderr, "usage: bench_optics --mcml PATH [--repeat N] FILE.mci...\n");
        return 2;
    }
    double la[3] = {0, 0, 0};
    if (getloadavg(la, 3) < 0) la[0] = -1;
    printf("side by side, one thread each, best of %d alternating rounds (load average %.2f)\n"
           "packet = skinsim's default path (4 photons in SIMD lanes), scalar = --scalar\n",
           repeat, la[0]);
    printf("%-24s %9s %8s %8s %8s %8s %15s %8s  %s\n", "input", "photons", "MCML s", "packet s",
           "scalar s", "MCML/pk", "pair MCML/pk", "MCML/sc",
           "Rd MCML / packet / scalar; 2 threads");
    for (int fi = first; fi < argc; fi++) {
        size_t len;
        ss_error e;
        char *text = ss_read_file(argv[fi], &len, &e);
        if (!text) {
            fprintf(stderr, "bench_optics: %s\n", e.msg);
            return 2;
        }
        ss_mci_file f;
        if (ss_mci_parse(text, argv[fi], &f, &e)) {
            fprintf(stderr, "bench_optics: %s\n", e.msg);
            free(text);
            return 2;
        }
        unsigned long long photons = 0;
        for (int r = 0; r < f.nruns; r++) photons += f.runs[r].photons;
        ss_mci_file_free(&f);
        char dir[] = "/tmp/skinsim_bench_XXXXXX";
        if (!mkdtemp(dir)) {
            perror("bench_optics: mkdtemp");
            free(text);
            return 1;
        }
        char path[4200];
        snprintf(path, sizeof path, "%s/in.mci", dir);
        FILE *fo = fopen(path, "w");
        if (!fo || fwrite(text, 1, len, fo) != len) {
            if (fo) fclose(fo);
            fprintf(stderr, "bench_optics: cannot write %s\n", path);
            free(text);
            return 1;
        }
        fclose(fo);
        double best_m = 1e300, best_s = 1e300, best_c = 1e300, rmin = 1e300, rmax = 0;
        char *mco1 = NULL, *mcoc = NULL;
        for (int k = 0; k < repeat; k++) {
            double m = run_mcml(mcml, dir, "in.mci");
            if (m < 0) {
                fprintf(stderr, "bench_optics: MCML failed on %s\n", argv[fi]);
                free(text);
                return 1;
            }
            char *mco = NULL;
            double s = run_skinsim(text, argv[fi], 1, SS_MC_KERNEL_AUTO, &mco);
            if (k == 0)
                mco1 = mco;
            else
                free(mco);
            double sc = run_skinsim(text, argv[fi], 1, SS_MC_KERNEL_SCALAR, &mco);
            if (k == 0)
                mcoc = mco;
            else
                free(mco);
            if (m < best_m) best_m = m;
            if (s < best_s) best_s = s;
            if (sc < best_c) best_c = sc;
            if (m / s < rmin) rmin = m / s;
            if (m / s > rmax) rmax = m / s;
        }
        char *mco2 = NULL;
        run_skinsim(text, argv[fi], 2, SS_MC_KERNEL_AUTO, &mco2);
        /* MCML's output: the first run's file named in the .mci, in dir */
        double rm[4] = {-1, -1, -1, -1}, rs[4], rc[4];
        rat_of(mco1, rs);
        rat_of(mcoc, rc);
        if (ss_mci_parse(text, argv[fi], &f, &e) == SS_OK) {
            char op[6000];
            snprintf(op, sizeof op, "%s/%s", dir, f.runs[0].out_name);
            size_t ml;
            char *mt = ss_read_file(op, &ml, &e);
            if (mt) {
                char *nl = malloc(ml + 2);
                if (nl) {
                    nl[0] = '\n';
                    memcpy(nl + 1, mt, ml + 1);
                    rat_of(nl, rm);
                    free(nl);
                }
                free(mt);
            }
            for (int r = 0; r < f.nruns; r++) {
                snprintf(op, sizeof op, "%s/%s", dir, f.runs[r].out_name);
                unlink(op);
            }
            ss_mci_file_free(&f);
        }
        unlink(path);
        rmdir(dir);
        /* the .mco texts differ only in the timing line: compare from InParm on */
        const char *a1 = mco1 ? strstr(mco1, "\nInParm") : NULL;
        const char *a2 = mco2 ? strstr(mco2, "\nInParm") : NULL;
        int same = a1 && a2 && !strcmp(a1, a2);
        const char *base = strrchr(argv[fi], '/');
        printf("%-24s %9llu %8.2f %8.2f %8.2f %7.2fx %6.2f-%5.2fx %7.2fx  %.5f / %.5f / %.5f; %s\n",
               base ? base + 1 : argv[fi], photons, best_m, best_s, best_c, best_m / best_s, rmin,
               rmax, best_m / best_c, rm[1], rs[1], rc[1], same ? "identical" : "DIFFERENT");
        free(mco1);
        free(mcoc);
        free(mco2);
        free(text);
    }
    return 0;
}

/* Wall-clock photons/s; *cpu_rate gets photons per CPU-second (process CPU
 * time over all threads), which is less sensitive to a shared machine. */
static double rate(const ss_optics_slab *s, const ss_mc_options *o, int threads, double *rd,
                   double *cpu_rate) {
    /* (o->kernel selects the packet path or the scalar loop) */
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
    ss_mc_options sc = *o;
    sc.kernel = SS_MC_KERNEL_SCALAR;
    double rd1, rd2, c1, c2, rds, cs;
    double r1 = rate(s, o, 1, &rd1, &c1), r2 = rate(s, o, 2, &rd2, &c2);
    rate(s, &sc, 1, &rds, &cs);
    printf("%-44s %12.0f %12.0f %6.2fx %12.0f %12.0f %12.0f %6.2fx  (Rd %.4f / %.4f, 1 = 2 "
           "threads: %s)\n",
           name, r1, r2, r2 / r1, c1, c2, cs, c1 / cs, rd1, rds, rd1 == rd2 ? "yes" : "NO");
}

int main(int argc, char **argv) {
    if (argc > 1 && !strcmp(argv[1], "--mcml")) {
        if (argc < 3) {
            fprintf(stderr, "usage: bench_optics --mcml PATH [--repeat N] FILE.mci...\n");
            return 2;
        }
        return compare_mcml(argc, argv);
    }
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
    printf("%-44s %12s %12s %7s %12s %12s %12s %7s\n", "input (packet path unless said)",
           "1 thread/s", "2 threads/s", "scale", "1t /CPU-s", "2t /CPU-s", "scalar /CPU-s",
           "pk/sc");
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
    printf("MCML: measure side by side (bench_optics --mcml PATH bench/mci/*.mci); target >= 3x\n");
    return 0;
}
