/* skinsim optics: the precalculation phase of seed 003 (§4.1-4.7) from the
 * command line: reflectance spectra and colour, the sampled BRDF, MCML input
 * files, and a labelled swatch of skin colours over melanin x blood. The same
 * biological-parameter options work in every subcommand. `fit` and `table`
 * are in app/cmd_optics_fit.c. */
#define _POSIX_C_SOURCE 200809L
#include <cairo.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "optics_opts.h"
#include "skinsim/optics.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* fontconfig (loaded by cairo for text): freed at exit when present so leak
 * checkers stay quiet; weak, so no direct link dependency. */
void FcFini(void) __attribute__((weak));

typedef struct common_opts {
    ss_bio_params bio;
    ss_spectrum_options spec;
    int threads, json, quiet;
    const char *out;
} common_opts;

static const char COMMON_HELP[] =
    "Biological parameters (seed 003 §5.2; defaults: a light skin):\n"
    "  --melanin F              epidermal melanosome volume fraction 0..1 (0.015;\n"
    "                           light skin 0.01-0.06, dark 0.2-0.45)\n"
    "  --pheomelanin-ratio F    pheomelanin share of melanin 0..1 (0.3)\n"
    "  --blood F                dermal blood volume fraction 0..1 (0.005)\n"
    "  --oxygenation F          HbO2 / total haemoglobin 0..1 (0.75)\n"
    "  --sc-thickness-cm X      stratum corneum thickness, cm (0.001)\n"
    "  --epidermis-thickness-cm X  epidermis thickness, cm (0.01)\n"
    "  --bilirubin-g-per-l X    bilirubin in blood, g/L (0.003)\n"
    "  --betacarotene-g-per-l X beta-carotene in tissue, g/L (0.00021)\n"
    "Monte Carlo:\n"
    "  --photons N              photon packets per %s (%llu)\n"
    "  --seed S                 random seed; the same seed gives identical output\n"
    "                           for any thread count (1)\n"
    "  --threads N              worker threads (default $SKINSIM_THREADS or all cores)\n"
    "  --roughness S            Trowbridge-Reitz surface roughness sigma, 0 = smooth\n"
    "                           (0.75, BioSpec)\n"
    "  --stochastic             absorb-or-scatter packets (seed §4.4) instead of weights\n"
    "  --scalar                 trace one photon at a time instead of 4 in SIMD lanes\n"
    "                           (for comparison; agrees within Monte Carlo error)\n"
    "  --wl-min NM --wl-max NM --wl-step NM   wavelengths, nm (380, 780, %g)\n"
    "  --quiet                  no progress output\n";

/* The options every transport subcommand shares, with this subcommand's own
 * defaults (one default per option: what is printed is what runs). */
static void common_help(FILE *f, const char *photons_per, const ss_spectrum_options *defaults) {
    fprintf(f, COMMON_HELP, photons_per, (unsigned long long)defaults->mc.photons,
            defaults->wl_step_nm);
}

/* Returns 1 if argv[*i] was a common option (consumed), 0 if not, -1 on error. */
static int parse_common(const char *cmd, int argc, char **argv, int *i, common_opts *c, int *rc) {
    int r = optics_parse_shared(cmd, argc, argv, i, &c->bio, &c->spec, 1, 1000000000000ull, rc);
    if (r) return r;
    const char *a = argv[*i];
    ss_error e;
    ss_error_clear(&e);
    if (!strcmp(a, "--threads")) {
        long v;
        if (*i + 1 >= argc) {
            *rc = cli_usage_error(cmd, "%s needs a value", a);
            return -1;
        }
        if (cli_parse_int(a, argv[++*i], 1, SS_THREADS_MAX, &v, &e)) {
            *rc = cli_fail(cmd, &e);
            return -1;
        }
        c->threads = (int)v;
        return 1;
    }
    if (!strcmp(a, "--stochastic")) {
        c->spec.mc.stochastic_absorb = 1;
        return 1;
    }
    if (!strcmp(a, "--json")) {
        c->json = 1;
        return 1;
    }
    if (!strcmp(a, "--quiet")) {
        c->quiet = 1;
        return 1;
    }
    if (!strcmp(a, "--out")) {
        if (*i + 1 >= argc) {
            *rc = cli_usage_error(cmd, "%s needs a file name", a);
            return -1;
        }
        c->out = argv[++*i];
        return 1;
    }
    return 0;
}

static void progress_cb(void *user, double fraction) {
    ss_progress_update((ss_progress *)user, fraction);
}

static void common_init(common_opts *c) {
    memset(c, 0, sizeof *c);
    ss_bio_params_default(&c->bio);
    ss_spectrum_options_default(&c->spec);
}

static int common_finish(const char *cmd, common_opts *c) {
    ss_error e;
    ss_error_clear(&e);
    if (ss_bio_params_validate(&c->bio, &e)) return cli_fail(cmd, &e);
    if (c->spec.wl_min_nm > c->spec.wl_max_nm)
        return cli_usage_error(cmd, "--wl-min %g is above --wl-max %g", c->spec.wl_min_nm,
                               c->spec.wl_max_nm);
    ss_threads_set(c->threads);
    return 0;
}

/* ---- spectrum ------------------------------------------------------------------ */
static void spectrum_help(FILE *f) {
    fprintf(f, "usage: skinsim optics spectrum [options]\n\n"
               "Monte Carlo diffuse reflectance spectrum of the four-layer skin model (stratum\n"
               "corneum, epidermis, papillary and reticular dermis over white fat) at normal\n"
               "incidence, and its colour: CIE 1931 XYZ under D65 -> linear sRGB albedo.\n"
               "Prints a table (wavelength_nm reflectance std_error), or with --json:\n"
               "  {\"srgb_linear\": [r,g,b], \"wavelength_nm\": [...], \"reflectance\": [...],\n"
               "   \"specular\": s, \"std_error\": e}\n"
               "(std_error: the largest standard error over the wavelengths; reflectance\n"
               "excludes the specular surface reflection, which is reported separately).\n\n"
               "  --out FILE.csv           also write wavelength_nm,reflectance,std_error\n"
               "  --json                   machine-readable summary on stdout\n"
               "  --radial-out FILE.csv    also write the radial subsurface profile Rd(r) per\n"
               "                           linear-sRGB channel (seed §4.7.1), columns\n"
               "                           r_min_cm,r_max_cm,rd_r,rd_g,rd_b in 1/cm^2 (a separate\n"
               "                           Monte Carlo run with the same options)\n"
               "  --radial-bins N          radial bins (50)\n"
               "  --radial-max-cm X        radial extent, cm (0.5)\n"
               "  --radial-distance D      net (default): entry-to-exit distance; path: the\n"
               "                           seed's D, the horizontal path length summed over\n"
               "                           every segment (seed §4.7.1)\n\n");
    ss_spectrum_options d;
    ss_spectrum_options_default(&d);
    common_help(f, "wavelength", &d);
    fprintf(f, "\nExample:\n"
               "  skinsim optics spectrum --melanin 0.08 --blood 0.02 --oxygenation 0.7 --json\n");
}

/* The radial profile Rd(r) per channel as CSV at path. */
static ss_status write_radial(const common_opts *c, int rbins, double rmax, const char *path,
                              ss_error *e) {
    double *prof = calloc((size_t)rbins * 3, sizeof *prof);
    size_t cap = 64 + (size_t)rbins * 96, len = 0;
    char *buf = malloc(cap);
    ss_status st = prof && buf ? SS_OK : ss_error_set(e, SS_ERR_NOMEM, "out of memory");
    if (!st) st = ss_optics_radial_profile_rgb(&c->bio, &c->spec, rbins, rmax, prof, e);
    if (!st) {
        len += (size_t)snprintf(buf, cap, "r_min_cm,r_max_cm,rd_r,rd_g,rd_b\n");
        double dr = rmax / rbins;
        for (int b = 0; b < rbins; b++)
            len += (size_t)snprintf(buf + len, cap - len, "%.6g,%.6g,%.6g,%.6g,%.6g\n", b * dr,
                                    (b + 1) * dr, prof[3 * b], prof[3 * b + 1], prof[3 * b + 2]);
        st = ss_write_file_atomic(path, buf, len, e);
    }
    free(prof);
    free(buf);
    return st;
}

static ss_status write_spectrum_csv(const ss_reflectance_spectrum *s, const char *path,
                                    ss_error *e) {
    size_t cap = 64 + (size_t)s->n * 64, len = 0;
    char *buf = malloc(cap);
    if (!buf) return ss_error_set(e, SS_ERR_NOMEM, "out of memory");
    len += (size_t)snprintf(buf + len, cap - len, "wavelength_nm,reflectance,std_error\n");
    for (int i = 0; i < s->n; i++)
        len += (size_t)snprintf(buf + len, cap - len, "%g,%.6f,%.6f\n", s->wavelength_nm[i],
                                s->reflectance[i], s->std_error[i]);
    ss_status st = ss_write_file_atomic(path, buf, len, e);
    free(buf);
    return st;
}

static int optics_spectrum(int argc, char **argv) {
    const char *cmd = "optics spectrum";
    common_opts c;
    common_init(&c);
    int rc = 0;
    const char *radial_out = NULL;
    long rbins = 50;
    double rmax = 0.5;
    int rdist = SS_RADIAL_NET;
    ss_error e;
    ss_error_clear(&e);
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            spectrum_help(stdout);
            return 0;
        }
        int k = parse_common(cmd, argc, argv, &i, &c, &rc);
        if (k < 0) return rc;
        if (k == 1) continue;
        if (!strcmp(argv[i], "--radial-out") || !strcmp(argv[i], "--radial-bins") ||
            !strcmp(argv[i], "--radial-max-cm") || !strcmp(argv[i], "--radial-distance")) {
            if (i + 1 >= argc) return cli_usage_error(cmd, "%s needs a value", argv[i]);
            if (!strcmp(argv[i], "--radial-out"))
                radial_out = argv[i + 1];
            else if (!strcmp(argv[i], "--radial-distance")) {
                if (!strcmp(argv[i + 1], "net"))
                    rdist = SS_RADIAL_NET;
                else if (!strcmp(argv[i + 1], "path"))
                    rdist = SS_RADIAL_PATH;
                else
                    return cli_usage_error(cmd, "--radial-distance: '%s' is neither net nor path",
                                           argv[i + 1]);
            } else if (!strcmp(argv[i], "--radial-bins")) {
                if (cli_parse_int(argv[i], argv[i + 1], 1, 10000, &rbins, &e))
                    return cli_fail(cmd, &e);
            } else if (cli_parse_double(argv[i], argv[i + 1], 1e-4, 50, &rmax, &e))
                return cli_fail(cmd, &e);
            i++;
            continue;
        }
        return cli_unknown_option(cmd, argv[i], spectrum_help);
    }
    if ((rc = common_finish(cmd, &c))) return rc;
    c.spec.mc.radial_distance = rdist;
    /* Outputs checked before the Monte Carlo runs, written staged, swapped
     * in together at the end (src/core/output.c). */
    ss_outputs *outs = ss_outputs_create("optics", &e);
    int i_out = -1, i_rad = -1;
    ss_status st = outs ? SS_OK : SS_ERR_NOMEM;
    if (!st && c.out) {
        i_out = ss_outputs_count(outs);
        st = ss_outputs_add(outs, "--out", c.out, SS_OUTPUT_FILE, 64.0 * 1024, &e);
    }
    if (!st && radial_out) {
        i_rad = ss_outputs_count(outs);
        st = ss_outputs_add(outs, "--radial-out", radial_out, SS_OUTPUT_FILE, 64.0 * rbins + 4096,
                            &e);
    }
    if (!st) st = ss_outputs_begin(outs, &e);
    ss_reflectance_spectrum s = {0};
    double rgb[3] = {0};
    if (!st && radial_out)
        st = write_radial(&c, (int)rbins, rmax, ss_outputs_path(outs, i_rad), &e);
    if (!st) {
        ss_progress pr;
        ss_progress_begin(&pr, "spectrum", 1.0, c.quiet || c.json);
        c.spec.progress = progress_cb;
        c.spec.progress_user = &pr;
        st = ss_optics_reflectance_spectrum(&c.bio, &c.spec, &s, &e);
        ss_progress_end(&pr);
    }
    if (!st) st = ss_spectrum_to_srgb_linear(s.wavelength_nm, s.reflectance, s.n, rgb, &e);
    if (!st && c.out) st = write_spectrum_csv(&s, ss_outputs_path(outs, i_out), &e);
    st = ss_outputs_finish(outs, st, &e);
    ss_outputs_free(outs);
    if (st) {
        ss_reflectance_spectrum_free(&s);
        return cli_fail(cmd, &e);
    }
    double se_max = 0;
    for (int i = 0; i < s.n; i++) se_max = fmax(se_max, s.std_error[i]);
    if (c.json) {
        printf("{\"srgb_linear\": [%.6f, %.6f, %.6f], \"wavelength_nm\": [", rgb[0], rgb[1],
               rgb[2]);
        for (int i = 0; i < s.n; i++) printf("%s%g", i ? ", " : "", s.wavelength_nm[i]);
        printf("], \"reflectance\": [");
        for (int i = 0; i < s.n; i++) printf("%s%.6f", i ? ", " : "", s.reflectance[i]);
        printf("], \"specular\": %.6f, \"std_error\": %.6f}\n", s.specular, se_max);
    } else {
        printf("# wavelength_nm reflectance std_error\n");
        for (int i = 0; i < s.n; i++)
            printf("%g %.5f %.5f\n", s.wavelength_nm[i], s.reflectance[i], s.std_error[i]);
        printf("# specular %.5f\n# linear sRGB albedo %.4f %.4f %.4f (8-bit sRGB %d %d %d)\n",
               s.specular, rgb[0], rgb[1], rgb[2],
               (int)lround(255 * ss_srgb_encode((float)fmin(1, fmax(0, rgb[0])))),
               (int)lround(255 * ss_srgb_encode((float)fmin(1, fmax(0, rgb[1])))),
               (int)lround(255 * ss_srgb_encode((float)fmin(1, fmax(0, rgb[2])))));
    }
    ss_reflectance_spectrum_free(&s);
    return 0;
}

/* ---- brdf ------------------------------------------------------------------------- */
static void brdf_help(FILE *f) {
    fprintf(f, "usage: skinsim optics brdf --out FILE.csv [options]\n\n"
               "Sampled BRDF of skin per linear-sRGB channel (seed 003 §4.5.2), one Monte Carlo\n"
               "run per incidence bin and wavelength. Bins: theta uniform over [0, 90) degrees\n"
               "(centres (k+0.5)*90/n), dphi = |phi_r - phi_i| folded into [0, 180] degrees with\n"
               "the mirror direction at 180. f_r = escaping weight / (solid angle * cos theta_r),\n"
               "in 1/sr; the specular surface reflection is included.\n"
               "CSV columns: theta_i_deg,theta_r_deg,dphi_deg,f_r,f_g,f_b (bin centres).\n\n"
               "  --out FILE.csv           output file (required)\n"
               "  --theta-i N              incidence bins (8)\n"
               "  --theta-r N              exit zenith bins (16)\n"
               "  --phi N                  azimuth-difference bins (16)\n\n");
    ss_spectrum_options d;
    ss_spectrum_options_default(&d);
    common_help(f, "incidence bin and wavelength", &d);
    fprintf(f, "\nExample:\n"
               "  skinsim optics brdf --out brdf.csv --melanin 0.03 --theta-i 4 --photons 5000\n");
}

static int optics_brdf(int argc, char **argv) {
    const char *cmd = "optics brdf";
    common_opts c;
    common_init(&c);
    int rc = 0;
    long nti = 8, ntr = 16, nph = 16;
    ss_error e;
    ss_error_clear(&e);
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            brdf_help(stdout);
            return 0;
        }
        int k = parse_common(cmd, argc, argv, &i, &c, &rc);
        if (k < 0) return rc;
        if (k == 1) continue;
        long *dst = !strcmp(argv[i], "--theta-i")   ? &nti
                    : !strcmp(argv[i], "--theta-r") ? &ntr
                    : !strcmp(argv[i], "--phi")     ? &nph
                                                    : NULL;
        if (!dst) return cli_unknown_option(cmd, argv[i], brdf_help);
        if (i + 1 >= argc) return cli_usage_error(cmd, "%s needs a value", argv[i]);
        if (cli_parse_int(argv[i], argv[i + 1], 1, 256, dst, &e)) return cli_fail(cmd, &e);
        i++;
    }
    if (!c.out) return cli_usage_error(cmd, "--out FILE.csv is required");
    if ((rc = common_finish(cmd, &c))) return rc;
    size_t nrow = (size_t)nti * ntr * nph, cap = 64 + nrow * 96, len = 0;
    ss_outputs *outs = ss_outputs_create("optics", &e);
    ss_status st = outs ? SS_OK : SS_ERR_NOMEM;
    if (!st) st = ss_outputs_add(outs, "--out", c.out, SS_OUTPUT_FILE, (double)cap, &e);
    if (!st) st = ss_outputs_begin(outs, &e);
    ss_brdf_sampled b = {0};
    char *buf = NULL;
    if (!st) {
        ss_progress pr;
        ss_progress_begin(&pr, "brdf", 1.0, c.quiet || c.json);
        c.spec.progress = progress_cb;
        c.spec.progress_user = &pr;
        st = ss_optics_brdf_sample(&c.bio, &c.spec, (int)nti, (int)ntr, (int)nph, &b, &e);
        ss_progress_end(&pr);
    }
    if (!st && !(buf = malloc(cap))) st = ss_error_set(&e, SS_ERR_NOMEM, "out of memory");
    if (!st) {
        len += (size_t)snprintf(buf, cap, "theta_i_deg,theta_r_deg,dphi_deg,f_r,f_g,f_b\n");
        for (long ti = 0; ti < nti; ti++)
            for (long tr = 0; tr < ntr; tr++)
                for (long p = 0; p < nph; p++) {
                    const double *f = &b.f_rgb[((ti * ntr + tr) * nph + p) * 3];
                    len += (size_t)snprintf(buf + len, cap - len, "%.4f,%.4f,%.4f,%.6g,%.6g,%.6g\n",
                                            (ti + 0.5) * 90.0 / nti, (tr + 0.5) * 90.0 / ntr,
                                            (p + 0.5) * 180.0 / nph, f[0], f[1], f[2]);
                }
        st = ss_write_file_atomic(ss_outputs_path(outs, 0), buf, len, &e);
    }
    free(buf);
    ss_brdf_sampled_free(&b);
    st = ss_outputs_finish(outs, st, &e);
    ss_outputs_free(outs);
    if (st) return cli_fail(cmd, &e);
    if (c.json) printf("{\"out\": \"%s\", \"bins\": [%ld, %ld, %ld]}\n", c.out, nti, ntr, nph);
    return 0;
}

/* ---- mci -------------------------------------------------------------------------- */
static void mci_help(FILE *f) {
    fprintf(f, "usage: skinsim optics mci FILE.mci [--seed S] [--threads N] [--json]\n"
               "                                  [--allow-outside-paths] [--scalar]\n\n"
               "Runs an MCML input file unchanged (MCML 1.2 format: version, number of runs;\n"
               "per run: output name and type A, photon count, dz dr [cm], nz nr na, number of\n"
               "layers, n above, one 'n mua mus g d' line per layer [1/cm, cm], n below).\n"
               "Each run writes the MCML-style output file its input names: RAT (specular,\n"
               "diffuse reflectance, absorbed fraction, transmittance), A_l, A_z, Rd_r, Rd_a,\n"
               "Tt_r, Tt_a. Output names are taken relative to the folder of FILE.mci (not the\n"
               "current folder) and may not leave it (absolute names, '..', symlinks out)\n"
               "unless --allow-outside-paths is given; an output may not be the .mci itself.\n"
               "The whole file and every output are checked before anything is run; the\n"
               "outputs appear together at the end, each whole.\n"
               "  --seed S      random seed (1)\n  --threads N   worker threads\n"
               "  --json        print a summary of each run on stdout\n"
               "  --allow-outside-paths   let the .mci name outputs anywhere\n"
               "  --scalar      trace one photon at a time instead of 4 in SIMD lanes (for\n"
               "                comparison; agrees within Monte Carlo error)\n\n"
               "Example (the .mco lands next to the .mci):\n"
               "  cp data/examples/sample.mci . && skinsim optics mci sample.mci\n");
}

static int optics_mci(int argc, char **argv) {
    const char *cmd = "optics mci";
    const char *file = NULL;
    uint64_t seed = 1;
    long threads = 0;
    int json = 0, outside = 0, scalar = 0;
    ss_error e;
    ss_error_clear(&e);
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            mci_help(stdout);
            return 0;
        } else if (!strcmp(argv[i], "--seed") && i + 1 < argc) {
            if (cli_parse_u64("--seed", argv[++i], &seed, &e)) return cli_fail(cmd, &e);
        } else if (!strcmp(argv[i], "--threads") && i + 1 < argc) {
            if (cli_parse_int("--threads", argv[++i], 1, SS_THREADS_MAX, &threads, &e))
                return cli_fail(cmd, &e);
        } else if (!strcmp(argv[i], "--json"))
            json = 1;
        else if (!strcmp(argv[i], "--allow-outside-paths"))
            outside = 1;
        else if (!strcmp(argv[i], "--scalar"))
            scalar = 1;
        else if (!strcmp(argv[i], "--quiet"))
            ;
        else if (argv[i][0] == '-')
            return cli_unknown_option(cmd, argv[i], mci_help);
        else if (!file)
            file = argv[i];
        else
            return cli_usage_error(cmd, "more than one input file ('%s')", argv[i]);
    }
    if (!file) return cli_usage_error(cmd, "an input FILE.mci is required");
    ss_threads_set((int)threads);
    size_t len;
    char *text = ss_read_file_max(file, &len, SS_READ_MAX_CONFIG, &e);
    if (!text) return cli_fail(cmd, &e);
    ss_mci_file mf;
    ss_status st = ss_mci_parse(text, file, &mf, &e);
    free(text);
    if (st) return cli_fail(cmd, &e);
    /* Every run's output: inside the .mci's folder, not the .mci itself, not
     * two runs to one file, not a device; all checked before the first run. */
    char *folder = strdup(file);
    char *sl = folder ? strrchr(folder, '/') : NULL;
    if (sl) sl[sl == folder ? 1 : 0] = '\0';
    ss_outputs *outs = ss_outputs_create("optics", &e);
    char **paths = calloc((size_t)mf.nruns, sizeof *paths);
    double(*rat)[4] = calloc((size_t)mf.nruns, sizeof *rat);
    st = folder && outs && paths && rat ? SS_OK : ss_error_set(&e, SS_ERR_NOMEM, "out of memory");
    if (!st) st = ss_outputs_input(outs, file, &e);
    for (int r = 0; r < mf.nruns && !st; r++) {
        ss_mci_run *run = &mf.runs[r];
        char label[64];
        snprintf(label, sizeof label, "%s run %d:", file, r + 1);
        st = ss_path_under(sl ? folder : ".", run->out_name, outside, &paths[r], &e);
        if (st) {
            ss_error e2 = e;
            ss_error_set(&e, st, "%s run %d: %s", file, r + 1, e2.msg);
        }
        double bytes = 8192.0 + 40.0 * (run->nz + 2.0 * run->nr + 2.0 * run->na + 8) +
                       13.0 * run->nr * (run->nz + 2.0 * run->na); /* the 2-D arrays */
        if (!st) st = ss_outputs_add(outs, label, paths[r], SS_OUTPUT_FILE, bytes, &e);
    }
    if (!st) st = ss_outputs_begin(outs, &e);
    for (int r = 0; r < mf.nruns && !st; r++) {
        char *mco = NULL;
        if (scalar) mf.runs[r].kernel = SS_MC_KERNEL_SCALAR;
        st = ss_mci_simulate(&mf.runs[r], seed, &mco, &e);
        if (!st) st = ss_write_file_atomic(ss_outputs_path(outs, r), mco, strlen(mco), &e);
        /* RAT lines follow "RAT #" in the text */
        const char *p = mco ? strstr(mco, "RAT #") : NULL;
        if (p) {
            p = strchr(p, '\n');
            for (int k = 0; k < 4 && p; k++) {
                rat[r][k] = strtod(p + 1, NULL);
                p = strchr(p + 1, '\n');
            }
        }
        free(mco);
    }
    st = ss_outputs_finish(outs, st, &e);
    int rc = st ? cli_fail(cmd, &e) : 0;
    if (json && !rc) {
        printf("[");
        for (int r = 0; r < mf.nruns; r++)
            printf("%s{\"out\": \"%s\", \"specular\": %g, \"diffuse\": %g, \"absorbed\": "
                   "%g, \"transmittance\": %g}",
                   r ? ", " : "", paths[r], rat[r][0], rat[r][1], rat[r][2], rat[r][3]);
        printf("]\n");
    } else if (!rc)
        for (int r = 0; r < mf.nruns; r++)
            fprintf(stderr, "skinsim optics mci: wrote %s\n", paths[r]);
    ss_outputs_free(outs);
    for (int r = 0; paths && r < mf.nruns; r++) free(paths[r]);
    free(paths);
    free(rat);
    free(folder);
    ss_mci_file_free(&mf);
    return rc;
}

/* ---- swatch -------------------------------------------------------------------------- */
/* The swatch traces one photon set per wavelength for every cell: fewer
 * photons and wavelengths than a single spectrum by default. */
static void swatch_defaults(ss_spectrum_options *d) {
    ss_spectrum_options_default(d);
    d->wl_step_nm = 20;
    d->mc.photons = 10000;
}

static void swatch_help(FILE *f) {
    fprintf(f, "usage: skinsim optics swatch --out FILE.png [options]\n\n"
               "A labelled grid of skin colours: melanin (columns) x blood (rows), each cell\n"
               "the linear-sRGB albedo of the Monte Carlo reflectance spectrum (D65, CIE 1931),\n"
               "written as an 8-bit sRGB PNG. Photon paths are traced once per wavelength without\n"
               "absorption and reweighted for every cell (exact for fixed layer geometry).\n\n"
               "  --out FILE.png           output image (required)\n"
               "  --melanin-list A,B,...   column values (0.01,0.03,0.06,0.12,0.2,0.3,0.43)\n"
               "  --blood-list A,B,...     row values (0.002,0.005,0.01,0.02,0.04)\n"
               "  --cell PX                cell size in pixels (96)\n"
               "  --json                   print the colours as JSON\n"
               "  (--melanin and --blood are replaced by the lists)\n\n");
    ss_spectrum_options d;
    swatch_defaults(&d);
    common_help(f, "wavelength", &d);
    fprintf(f, "\nExample:\n"
               "  skinsim optics swatch --out swatch.png\n");
}

static void srgb8(const double lin[3], double out[3]) {
    for (int k = 0; k < 3; k++) out[k] = ss_srgb_encode((float)fmin(1.0, fmax(0.0, lin[k])));
}

static void swatch_progress(void *user, double f) {
    ss_progress *p = user;
    ss_progress_update(p, f * p->total);
}

static int optics_swatch(int argc, char **argv) {
    const char *cmd = "optics swatch";
    common_opts c;
    common_init(&c);
    swatch_defaults(&c.spec);
    int rc = 0;
    double mel_def[] = {0.01, 0.03, 0.06, 0.12, 0.2, 0.3, 0.43};
    double bl_def[] = {0.002, 0.005, 0.01, 0.02, 0.04};
    double *mel = NULL, *bl = NULL;
    int nmel = 0, nbl = 0;
    long cell = 96;
    ss_outputs *outs = NULL;
    ss_error e;
    ss_error_clear(&e);
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            swatch_help(stdout);
            free(mel);
            free(bl);
            return 0;
        }
        int k = parse_common(cmd, argc, argv, &i, &c, &rc);
        if (k < 0) goto out;
        if (k == 1) continue;
        if (i + 1 >= argc && (!strcmp(argv[i], "--melanin-list") ||
                              !strcmp(argv[i], "--blood-list") || !strcmp(argv[i], "--cell"))) {
            rc = cli_usage_error(cmd, "%s needs a value", argv[i]);
            goto out;
        }
        if (!strcmp(argv[i], "--melanin-list")) {
            free(mel);
            mel = NULL;
            if (cli_parse_double_list("--melanin-list", argv[++i], 0, 1, &mel, &nmel, &e) ||
                nmel < 1 || nmel > 32) {
                if (!e.msg[0]) ss_error_set(&e, SS_ERR_INPUT, "--melanin-list: 1..32 values");
                rc = cli_fail(cmd, &e);
                goto out;
            }
        } else if (!strcmp(argv[i], "--blood-list")) {
            free(bl);
            bl = NULL;
            if (cli_parse_double_list("--blood-list", argv[++i], 0, 1, &bl, &nbl, &e) || nbl < 1 ||
                nbl > 32) {
                if (!e.msg[0]) ss_error_set(&e, SS_ERR_INPUT, "--blood-list: 1..32 values");
                rc = cli_fail(cmd, &e);
                goto out;
            }
        } else if (!strcmp(argv[i], "--cell")) {
            if (cli_parse_int("--cell", argv[++i], 24, 512, &cell, &e)) {
                rc = cli_fail(cmd, &e);
                goto out;
            }
        } else {
            rc = cli_unknown_option(cmd, argv[i], swatch_help);
            goto out;
        }
    }
    if (!c.out) {
        rc = cli_usage_error(cmd, "--out FILE.png is required");
        goto out;
    }
    if ((rc = common_finish(cmd, &c))) goto out;
    outs = ss_outputs_create("optics", &e);
    if (!outs || ss_outputs_add(outs, "--out", c.out, SS_OUTPUT_FILE, 3.0 * 1024 * 1024, &e) ||
        ss_outputs_begin(outs, &e)) {
        rc = cli_fail(cmd, &e);
        goto out;
    }
    const double *M = mel ? mel : mel_def, *B = bl ? bl : bl_def;
    if (!mel) nmel = (int)(sizeof mel_def / sizeof mel_def[0]);
    if (!bl) nbl = (int)(sizeof bl_def / sizeof bl_def[0]);
    /* albedo of every cell via the absorption-free path method */
    int nwl = (int)floor((c.spec.wl_max_nm - c.spec.wl_min_nm) / c.spec.wl_step_nm + 1e-9) + 1;
    double *rgb = calloc((size_t)nmel * nbl * 3, sizeof *rgb);
    if (!rgb) {
        ss_error_set(&e, SS_ERR_NOMEM, "out of memory");
        rc = cli_fail(cmd, &e);
        goto out;
    }
    ss_progress pr;
    ss_progress_begin(&pr, "swatch", nwl, c.quiet);
    ss_spectrum_options so = c.spec;
    so.progress = swatch_progress;
    so.progress_user = &pr;
    ss_status st = ss_optics_albedo_grid(&c.bio, &so, M, nmel, B, nbl, rgb, &e);
    ss_progress_end(&pr);
    if (st) {
        free(rgb);
        rc = cli_fail(cmd, &e);
        goto out;
    }
    /* draw: left label column, top label row, title */
    int lw = 110, th = 64, W = lw + nmel * (int)cell + 10, H = th + nbl * (int)cell + 40;
    cairo_surface_t *sf = cairo_image_surface_create(CAIRO_FORMAT_RGB24, W, H);
    cairo_t *cr = cairo_create(sf);
    cairo_set_source_rgb(cr, 0.15, 0.15, 0.16);
    cairo_paint(cr);
    cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_source_rgb(cr, 0.92, 0.92, 0.92);
    cairo_set_font_size(cr, 14);
    cairo_move_to(cr, 10, 20);
    cairo_show_text(cr, "skin albedo (Monte Carlo, D65, sRGB): melanosome fraction ->, blood v");
    cairo_set_font_size(cr, 12);
    for (int mi = 0; mi < nmel; mi++) {
        char t[32];
        snprintf(t, sizeof t, "mel %.1f%%", 100 * M[mi]);
        cairo_move_to(cr, lw + mi * cell + 6, th - 10);
        cairo_show_text(cr, t);
    }
    for (int bi = 0; bi < nbl; bi++) {
        char t[32];
        snprintf(t, sizeof t, "blood %.1f%%", 100 * B[bi]);
        cairo_move_to(cr, 8, th + bi * cell + cell / 2 + 4);
        cairo_show_text(cr, t);
    }
    for (int bi = 0; bi < nbl; bi++)
        for (int mi = 0; mi < nmel; mi++) {
            double s[3];
            srgb8(&rgb[3 * (bi * nmel + mi)], s);
            cairo_set_source_rgb(cr, s[0], s[1], s[2]);
            cairo_rectangle(cr, lw + mi * cell + 2, th + bi * cell + 2, cell - 4, cell - 4);
            cairo_fill(cr);
        }
    char foot[160];
    snprintf(foot, sizeof foot,
             "pheomelanin %.2f  oxygenation %.2f  epidermis %.3g cm  %llu photons/wl",
             c.bio.pheomelanin_ratio, c.bio.oxygenation, c.bio.epidermis_thickness_cm,
             (unsigned long long)c.spec.mc.photons);
    cairo_set_source_rgb(cr, 0.8, 0.8, 0.8);
    cairo_set_font_size(cr, 11);
    cairo_move_to(cr, 10, H - 14);
    cairo_show_text(cr, foot);
    cairo_destroy(cr);
    cairo_surface_flush(sf);
    /* release cairo's and fontconfig's font caches (keeps leak checkers quiet) */
    cairo_debug_reset_static_data();
    if (FcFini) FcFini();
    ss_image *img = ss_image_create(W, H, 3, &e);
    if (img) {
        const unsigned char *d = cairo_image_surface_get_data(sf);
        int stride = cairo_image_surface_get_stride(sf);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                uint32_t px = *(const uint32_t *)(d + (size_t)y * stride + 4 * (size_t)x);
                float *o = ss_image_px(img, x, y);
                o[0] = ss_srgb_decode(((px >> 16) & 255) / 255.0f);
                o[1] = ss_srgb_decode(((px >> 8) & 255) / 255.0f);
                o[2] = ss_srgb_decode((px & 255) / 255.0f);
            }
    }
    cairo_surface_destroy(sf);
    st = img ? ss_png_write(ss_outputs_path(outs, 0), img, 8, SS_ENC_SRGB, &e) : SS_ERR_NOMEM;
    ss_image_free(img);
    st = ss_outputs_finish(outs, st, &e);
    if (st) {
        free(rgb);
        rc = cli_fail(cmd, &e);
        goto out;
    }
    if (c.json) {
        printf("{\"out\": \"%s\", \"melanin\": [", c.out);
        for (int mi = 0; mi < nmel; mi++) printf("%s%g", mi ? ", " : "", M[mi]);
        printf("], \"blood\": [");
        for (int bi = 0; bi < nbl; bi++) printf("%s%g", bi ? ", " : "", B[bi]);
        printf("], \"srgb_linear\": [");
        for (int q = 0; q < nmel * nbl; q++)
            printf("%s[%.5f, %.5f, %.5f]", q ? ", " : "", rgb[3 * q], rgb[3 * q + 1],
                   rgb[3 * q + 2]);
        /* CIELAB (D65), chroma, hue angle and individual typology angle per cell */
        printf("], \"lab\": [");
        for (int q = 0; q < nmel * nbl; q++) {
            double lab[3], C, h, ita;
            ss_srgb_linear_to_lab(rgb + 3 * q, lab);
            ss_lab_describe(lab, &C, &h, &ita);
            printf("%s{\"L\": %.2f, \"a\": %.2f, \"b\": %.2f, \"C\": %.2f, \"h\": %.2f, "
                   "\"ITA\": %.2f}",
                   q ? ", " : "", lab[0], lab[1], lab[2], C, h, ita);
        }
        printf("]}\n");
    }
    free(rgb);
out:
    ss_outputs_free(outs); /* rolls back whatever was not finished */
    free(mel);
    free(bl);
    return rc;
}

/* ---- dispatcher --------------------------------------------------------------------- */
static void optics_help(FILE *f) {
    fprintf(f, "usage: skinsim optics <subcommand> [options]   (each has --help)\n\n"
               "Light transport in a four-layer skin model (seed 003): biological parameters\n"
               "-> optical coefficients -> Monte Carlo photon packets -> spectra, BRDF, colour.\n\n"
               "subcommands:\n"
               "  spectrum   reflectance spectrum and linear sRGB albedo (--json)\n"
               "  brdf       sampled BRDF per colour channel to a CSV file\n"
               "  mci        run an MCML .mci input file, write its .mco outputs\n"
               "  swatch     PNG grid of skin colours over melanin x blood\n");
    fprintf(f, "  fit        fit a render BRDF to the sampled skin BRDF\n");
    fprintf(f, "  table      precomputed ModelMatch table\n");
    fprintf(f, "  match      biological parameters for a target skin colour (sRGB or L*a*b*)\n");
    fprintf(f, "\nExample:\n  skinsim optics swatch --out swatch.png\n");
}

int cmd_optics(int argc, char **argv) {
    if (argc < 2) {
        optics_help(stderr);
        return 2;
    }
    const char *sub = argv[1];
    if (!strcmp(sub, "--help") || !strcmp(sub, "-h") || !strcmp(sub, "help")) {
        optics_help(stdout);
        return 0;
    }
    if (!strcmp(sub, "spectrum")) return optics_spectrum(argc - 1, argv + 1);
    if (!strcmp(sub, "brdf")) return optics_brdf(argc - 1, argv + 1);
    if (!strcmp(sub, "mci")) return optics_mci(argc - 1, argv + 1);
    if (!strcmp(sub, "swatch")) return optics_swatch(argc - 1, argv + 1);
    if (!strcmp(sub, "fit")) return cmd_optics_fit(argc - 1, argv + 1);
    if (!strcmp(sub, "table")) return cmd_optics_table(argc - 1, argv + 1);
    if (!strcmp(sub, "match")) return cmd_optics_match(argc - 1, argv + 1);
    fprintf(stderr, "skinsim optics: unknown subcommand '%s'\n\n", sub);
    optics_help(stderr);
    return 2;
}
