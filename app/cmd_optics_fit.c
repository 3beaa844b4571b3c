/* skinsim optics fit / optics table: ModelMatch from the command line (seed
 * 003 §4.6-4.7, §4.8.6, §6.1). `fit` fits the render BRDFs (glTF GGX +
 * Lambert, Ashikhmin-Shirley) to the sampled skin BRDF of one parameter set
 * and prints the parameters and residuals; `table` builds the ModelMatch
 * table over the six optical biological parameters, or with --lookup reads
 * one and prints the interpolated render parameters. Reached through the
 * `skinsim optics` dispatcher (app/cmd_optics.c). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "optics_opts.h"
#include "skinsim/optics_fit.h"
#ifdef SKINSIM_HAVE_MPI
#include "skinsim/dist.h"
#endif

typedef struct fit_cli {
    ss_bio_params bio;
    ss_mm_build_options build; /* spectrum, bins, fit options */
    int threads, json, quiet, fast;
    double max_theta_deg;
    long samples;
    const char *out, *lookup;
    /* explicit sample values of an axis (--axis NAME=v1,v2,...): NULL = uniform */
    double *axis_values[SS_MM_NAXES];
    int axis_count[SS_MM_NAXES];
} fit_cli;

static const char *BIO_HELP =
    "Biological parameters (seed 003 §5.2; defaults: a light skin):\n"
    "  --melanin F              epidermal melanosome volume fraction 0..1 (0.015)\n"
    "  --pheomelanin-ratio F    pheomelanin share of melanin 0..1 (0.3)\n"
    "  --blood F                dermal blood volume fraction 0..1 (0.005)\n"
    "  --oxygenation F          HbO2 / total haemoglobin 0..1 (0.75)\n"
    "  --sc-thickness-cm X      stratum corneum thickness, cm (0.001)\n"
    "  --epidermis-thickness-cm X  epidermis thickness, cm (0.01)\n"
    "  --bilirubin-g-per-l X    bilirubin in blood, g/L (0.003)\n"
    "  --betacarotene-g-per-l X beta-carotene in tissue, g/L (0.00021)\n";

static const char *MC_HELP =
    "Transport and fit:\n"
    "  --photons N              photon packets per wavelength and incidence bin (%llu)\n"
    "  --seed S                 random seed (1); same seed, same result for any thread count\n"
    "  --roughness S            Trowbridge-Reitz surface roughness sigma (0.75)\n"
    "  --scalar                 trace one photon at a time instead of 4 in SIMD lanes\n"
    "  --wl-min NM --wl-max NM --wl-step NM   wavelengths, nm (%g, %g, %g)\n"
    "  --theta-i N --theta-r N --phi N        BRDF bins (8, 8, 8): theta uniform over\n"
    "                           [0, 90) deg, dphi over [0, 180] deg, mirror at 180\n"
    "  --weighting W            distance weights: solid-angle (seed §3.1.6, default),\n"
    "                           uniform (dtheta_i dtheta_r dphi, §4.6 literally) or\n"
    "                           projected (solid angle x cos theta_i cos theta_r)\n"
    "  --max-theta-deg D        leave out bins whose theta_i or theta_r centre is above\n"
    "                           D degrees (90: all bins, as the seed)\n"
    "  --base B                 albedo (default): base colour from the skin's diffuse\n"
    "                           albedo, lobe fitted to the surface reflection; free:\n"
    "                           base colour and lobe fitted together (seed §4.6)\n"
    "  --threads N              worker threads (default $SKINSIM_THREADS or all cores)\n"
    "  --json                   machine-readable output on stdout\n"
    "  --quiet                  no progress bar\n";

static void init_cli(fit_cli *c) {
    memset(c, 0, sizeof *c);
    ss_bio_params_default(&c->bio);
    ss_mm_build_options_default(&c->build);
    c->samples = 3;
    c->max_theta_deg = 90.0;
}

static int need(const char *cmd, int argc, int i, const char *opt) {
    if (i + 1 >= argc) return cli_usage_error(cmd, "%s needs a value", opt);
    return 0;
}

/* 1 consumed, 0 not ours, -1 error (rc set). */
static int parse_shared(const char *cmd, int argc, char **argv, int *i, fit_cli *c, int *rc) {
    ss_spectrum_options *sp = &c->build.spectrum;
    int r = optics_parse_shared(cmd, argc, argv, i, &c->bio, sp, 100, 4000000, rc);
    if (r) return r;
    const char *a = argv[*i];
    ss_error e;
    ss_error_clear(&e);
    if (!strcmp(a, "--max-theta-deg")) {
        if ((*rc = need(cmd, argc, *i, a))) return -1;
        if (cli_parse_double(a, argv[++*i], 1, 90, &c->max_theta_deg, &e)) {
            *rc = cli_fail(cmd, &e);
            return -1;
        }
        return 1;
    }
    struct {
        const char *name;
        int *dst;
        long lo, hi;
    } ints[] = {
        {"--theta-i", &c->build.n_theta_i, 1, 64},
        {"--theta-r", &c->build.n_theta_r, 1, 64},
        {"--phi", &c->build.n_phi, 1, 64},
        {"--threads", &c->threads, 1, SS_THREADS_MAX},
    };
    for (size_t k = 0; k < sizeof ints / sizeof ints[0]; k++) {
        if (strcmp(a, ints[k].name)) continue;
        long v;
        if ((*rc = need(cmd, argc, *i, a))) return -1;
        if (cli_parse_int(a, argv[++*i], ints[k].lo, ints[k].hi, &v, &e)) {
            *rc = cli_fail(cmd, &e);
            return -1;
        }
        *ints[k].dst = (int)v;
        return 1;
    }
    if (!strcmp(a, "--weighting")) {
        if ((*rc = need(cmd, argc, *i, a))) return -1;
        const char *w = argv[++*i];
        int k;
        for (k = 0; k <= SS_FIT_PROJECTED; k++)
            if (!strcmp(w, ss_fit_weighting_name(k))) break;
        if (k > SS_FIT_PROJECTED) {
            *rc = cli_usage_error(cmd, "--weighting: '%s' is not solid-angle, uniform or projected",
                                  w);
            return -1;
        }
        c->build.fit.weighting = k;
        return 1;
    }
    if (!strcmp(a, "--base")) {
        if ((*rc = need(cmd, argc, *i, a))) return -1;
        const char *b = argv[++*i];
        if (!strcmp(b, "albedo"))
            c->build.fit.base_mode = SS_FIT_BASE_ALBEDO;
        else if (!strcmp(b, "free"))
            c->build.fit.base_mode = SS_FIT_BASE_FREE;
        else {
            *rc = cli_usage_error(cmd, "--base: '%s' is neither albedo nor free", b);
            return -1;
        }
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
    return 0;
}

static int finish_shared(const char *cmd, fit_cli *c) {
    ss_error e;
    ss_error_clear(&e);
    if (ss_bio_params_validate(&c->bio, &e)) return cli_fail(cmd, &e);
    const ss_spectrum_options *sp = &c->build.spectrum;
    if (sp->wl_min_nm > sp->wl_max_nm)
        return cli_usage_error(cmd, "--wl-min %g is above --wl-max %g", sp->wl_min_nm,
                               sp->wl_max_nm);
    if ((sp->wl_max_nm - sp->wl_min_nm) / sp->wl_step_nm > 1000)
        return cli_usage_error(cmd, "--wl-step %g gives more than 1001 wavelengths",
                               sp->wl_step_nm);
    double first =
        45.0 / (c->build.n_theta_i < c->build.n_theta_r ? c->build.n_theta_i : c->build.n_theta_r);
    if (c->max_theta_deg < 45.0 / c->build.n_theta_i ||
        c->max_theta_deg < 45.0 / c->build.n_theta_r)
        return cli_usage_error(cmd, "--max-theta-deg %g leaves no bin (first bin centre %g deg)",
                               c->max_theta_deg, first);
    ss_threads_set(c->threads);
    c->build.quiet = c->quiet;
    c->build.fit.max_theta_rad = c->max_theta_deg * 3.14159265358979323846 / 180.0;
    return 0;
}

/* A JSON string literal (quotes, backslashes and control characters escaped). */
static void json_str(const char *s) {
    putchar('"');
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '"' || *p == '\\')
            printf("\\%c", *p);
        else if (*p < 0x20)
            printf("\\u%04x", *p);
        else
            putchar(*p);
    }
    putchar('"');
}

static void progress_cb(void *user, double fraction) {
    ss_progress_update((ss_progress *)user, fraction);
}

static void print_entry(const ss_mm_entry *en, const double *rms, int json) {
    if (json) {
        printf("\"models\": {");
        for (int m = 0; m < SS_RENDER_NMODELS; m++) {
            const ss_render_params *p = &en->fit[m];
            printf("%s\"%s\": {\"base_color_linear\": [%.6f, %.6f, %.6f], \"specular\": %.6f, "
                   "\"f0\": %.6f, \"roughness\": %.6f, \"residual_rel\": %.6f",
                   m ? ", " : "", ss_render_model_name((ss_render_model)m), p->base_rgb[0],
                   p->base_rgb[1], p->base_rgb[2], p->specular,
                   p->specular * SS_RENDER_F0_PER_SPECULAR, p->roughness, en->residual_rel[m]);
            if (rms) printf(", \"residual_rms_per_sr\": %.6g", rms[m]);
            printf("}");
        }
        printf("}, \"subsurface_radius_cm\": [%.6f, %.6f, %.6f], \"albedo_linear\": [%.6f, %.6f, "
               "%.6f]",
               en->sss_radius_cm[0], en->sss_radius_cm[1], en->sss_radius_cm[2], en->albedo_rgb[0],
               en->albedo_rgb[1], en->albedo_rgb[2]);
        return;
    }
    for (int m = 0; m < SS_RENDER_NMODELS; m++) {
        const ss_render_params *p = &en->fit[m];
        printf("%-18s base colour (linear) %.4f %.4f %.4f  specular %.4f (F0 %.4f)  roughness "
               "%.4f  residual %.4f (relative)",
               ss_render_model_name((ss_render_model)m), p->base_rgb[0], p->base_rgb[1],
               p->base_rgb[2], p->specular, p->specular * SS_RENDER_F0_PER_SPECULAR, p->roughness,
               en->residual_rel[m]);
        if (rms) printf(", %.4g 1/sr rms", rms[m]);
        printf("\n");
    }
    printf("subsurface radius  %.5f %.5f %.5f cm (mean radius of the diffuse profile, R G B)\n",
           en->sss_radius_cm[0], en->sss_radius_cm[1], en->sss_radius_cm[2]);
    printf("diffuse albedo     %.4f %.4f %.4f (linear sRGB, normal incidence)\n", en->albedo_rgb[0],
           en->albedo_rgb[1], en->albedo_rgb[2]);
}

/* ---- fit ---------------------------------------------------------------------- */

static void fit_help(FILE *f, const fit_cli *c) {
    fprintf(f,
            "usage: skinsim optics fit [options]\n\n"
            "Samples the skin BRDF of the given biological parameters by Monte Carlo (one run\n"
            "per wavelength and incidence bin, specular surface reflection included) and fits\n"
            "the render BRDFs to it by least squares (seed 003 §4.6-4.7):\n"
            "  ggx                glTF metallic-roughness (metallic 0): GGX + Lambert\n"
            "  ashikhmin-shirley  Ashikhmin-Shirley 2000 (the seed's §6.1 model)\n"
            "Printed per model: base colour (linear sRGB), specular strength (F0 = 0.08 x\n"
            "specular), perceptual roughness and the fit residual (relative: sqrt(distance /\n"
            "sum w f^2); and rms in 1/sr). Also the subsurface radius per channel (mean\n"
            "radius of the radial diffuse reflectance profile, cm) and the diffuse albedo.\n\n"
            "  --fast                   trace photon paths once per wavelength and incidence\n"
            "                           bin without absorption and reweight (the table's\n"
            "                           method) instead of direct simulation\n\n%s",
            BIO_HELP);
    fprintf(f, MC_HELP, (unsigned long long)c->build.spectrum.mc.photons,
            c->build.spectrum.wl_min_nm, c->build.spectrum.wl_max_nm, c->build.spectrum.wl_step_nm);
    fprintf(f, "\nExample:\n  skinsim optics fit --melanin 0.05 --fast --json\n");
}

/* The help texts with their defaults, for "did you mean" (cli_suggest). */
static void fit_help_options(FILE *f) {
    fit_cli c;
    init_cli(&c);
    c.build.spectrum.mc.photons = 20000;
    fit_help(f, &c);
}

int cmd_optics_fit(int argc, char **argv) {
    const char *cmd = "optics fit";
    fit_cli c;
    init_cli(&c);
    c.build.spectrum.mc.photons = 20000;
    int rc = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            fit_help(stdout, &c);
            return 0;
        }
        int k = parse_shared(cmd, argc, argv, &i, &c, &rc);
        if (k < 0) return rc;
        if (k == 1) continue;
        if (!strcmp(argv[i], "--fast"))
            c.fast = 1;
        else
            return cli_unknown_option(cmd, argv[i], fit_help_options);
    }
    if ((rc = finish_shared(cmd, &c))) return rc;
    ss_error e;
    ss_error_clear(&e);
    ss_brdf_sampled s;
    ss_mm_entry en;
    memset(&en, 0, sizeof en);
    double t0 = ss_now();
    if (c.fast) {
        if (ss_mm_sample_fast(&c.bio, &c.build, &s, en.sss_radius_cm, en.albedo_rgb, &e))
            return cli_fail(cmd, &e);
    } else {
        ss_progress prog;
        ss_progress_begin(&prog, "sampled BRDF", 1.0, c.quiet);
        ss_spectrum_options sp = c.build.spectrum;
        sp.progress = progress_cb;
        sp.progress_user = &prog;
        ss_status bst = ss_optics_brdf_sample(&c.bio, &sp, c.build.n_theta_i, c.build.n_theta_r,
                                              c.build.n_phi, &s, &e);
        ss_progress_end(&prog);
        if (bst) return cli_fail(cmd, &e);
        /* radial profile (normal incidence) for the subsurface radius and albedo */
        int bins = 200;
        double max_cm = 1.0, *rad = calloc((size_t)bins * 3, sizeof(double));
        if (!rad) {
            ss_brdf_sampled_free(&s);
            ss_error_set(&e, SS_ERR_NOMEM, "out of memory");
            return cli_fail(cmd, &e);
        }
        ss_status st =
            ss_optics_radial_profile_rgb(&c.bio, &c.build.spectrum, bins, max_cm, rad, &e);
        if (!st) {
            ss_mm_sss_radius(rad, bins, max_cm, en.sss_radius_cm);
            ss_mm_radial_albedo(rad, bins, max_cm, en.albedo_rgb);
        }
        free(rad);
        if (st) {
            ss_brdf_sampled_free(&s);
            return cli_fail(cmd, &e);
        }
    }
    double rms[SS_RENDER_NMODELS];
    ss_fit_options fo = c.build.fit;
    ss_brdf_sampled surf = {0, 0, 0, NULL};
    if (fo.base_mode == SS_FIT_BASE_ALBEDO) {
        for (int ch = 0; ch < 3; ch++) fo.albedo_rgb[ch] = fmin(1.0, fmax(0.0, en.albedo_rgb[ch]));
        if (ss_optics_surface_brdf_sample(&c.build.spectrum, c.build.n_theta_i, c.build.n_theta_r,
                                          c.build.n_phi, &surf, &e)) {
            ss_brdf_sampled_free(&s);
            return cli_fail(cmd, &e);
        }
    }
    for (int m = 0; m < SS_RENDER_NMODELS; m++) {
        ss_fit_result r;
        /* the GGX lobe models the surface reflection; the Ashikhmin-Shirley
         * lobe cannot (its best fit to it is no lobe), so it keeps the whole BRDF */
        fo.surface = (m == SS_RENDER_GGX && surf.f_rgb) ? &surf : NULL;
        if (ss_render_fit((ss_render_model)m, &s, &fo, &r, &e)) {
            ss_brdf_sampled_free(&s);
            ss_brdf_sampled_free(&surf);
            return cli_fail(cmd, &e);
        }
        en.fit[m] = r.params;
        en.residual_rel[m] = r.residual_rel;
        rms[m] = r.residual_rms;
    }
    ss_brdf_sampled_free(&s);
    ss_brdf_sampled_free(&surf);
    double secs = ss_now() - t0;
    if (c.json) {
        printf("{\"method\": \"%s\", \"photons\": %llu, \"weighting\": \"%s\", \"seconds\": %.3f, ",
               c.fast ? "fast" : "direct", (unsigned long long)c.build.spectrum.mc.photons,
               ss_fit_weighting_name(c.build.fit.weighting), secs);
        print_entry(&en, rms, 1);
        printf("}\n");
    } else {
        printf("# ModelMatch fit (%s transport, %llu photons per wavelength and incidence bin, "
               "%s weights, %.1f s)\n",
               c.fast ? "fast" : "direct", (unsigned long long)c.build.spectrum.mc.photons,
               ss_fit_weighting_name(c.build.fit.weighting), secs);
        print_entry(&en, rms, 0);
    }
    return 0;
}

/* ---- table -------------------------------------------------------------------- */

static void table_help(FILE *f, const fit_cli *c) {
    fprintf(f, "usage: skinsim optics table --out FILE.sstab [--samples N] [options]\n"
               "       skinsim optics table --lookup FILE.sstab [--melanin F ...] [--json]\n\n"
               "Builds the ModelMatch table (seed 003 §4.8.6): a hypercube over melanin,\n"
               "pheomelanin ratio, blood, oxygenation, stratum corneum and epidermis thickness\n"
               "with N samples per axis over the default ranges\n");
    for (int a = 0; a < SS_MM_NAXES; a++) {
        double lo, hi;
        ss_mm_axis_default_range(a, &lo, &hi);
        fprintf(f, "  %-12s %g .. %g%s\n", ss_mm_axis_name(a), lo, hi,
                a >= SS_MM_AXIS_SC ? " cm" : "");
    }
    fprintf(f,
            "each entry the fitted render parameters of both models, the subsurface radius\n"
            "and the albedo. Photon paths are traced once per thickness pair, wavelength and\n"
            "incidence bin without absorption and reweighted for every absorption set.\n"
            "File format: docs/modelmatch.md. With --lookup, prints the render parameters\n"
            "interpolated multilinearly at the given biological parameters (clamped to the\n"
            "table's range).\n\n"
            "  --out FILE               table to write (atomically)\n"
            "  --samples N              samples per axis, 1..9 (3)\n"
            "  --axis NAME=V1,V2,...    explicit, increasing sample values for one axis\n"
            "                           (melanin, pheomelanin, blood, oxygenation, sc,\n"
            "                           epidermis; fractions 0..1, thicknesses in cm);\n"
            "                           repeatable, e.g. a denser melanin axis\n"
            "  --lookup FILE            read a table and interpolate instead of building\n"
            "  --surface-sigma S        with --lookup: the surface's Trowbridge-Reitz\n"
            "                           roughness (0..2); the GGX lobe and base colour\n"
            "                           follow the table's surface curve (default: the\n"
            "                           sigma the entries were built with)\n"
            "When building, bilirubin and beta-carotene are the fixed non-axis values and\n"
            "the six axis parameters below are not used; with --lookup they are the point.\n\n%s",
            BIO_HELP);
    fprintf(f, MC_HELP, (unsigned long long)c->build.spectrum.mc.photons,
            c->build.spectrum.wl_min_nm, c->build.spectrum.wl_max_nm, c->build.spectrum.wl_step_nm);
    fprintf(f, "\nExample (render parameters for one skin from the shipped table):\n"
               "  skinsim optics table --lookup data/modelmatch_default.sstab --melanin 0.05 "
               "--blood 0.01\n");
}

/* --axis NAME=V1,V2,...: explicit sample values for one table axis. */
static int parse_axis(const char *cmd, const char *arg, fit_cli *c) {
    const char *eq = strchr(arg, '=');
    int a = -1;
    for (int k = 0; eq && k < SS_MM_NAXES; k++)
        if ((size_t)(eq - arg) == strlen(ss_mm_axis_name(k)) &&
            !strncmp(arg, ss_mm_axis_name(k), (size_t)(eq - arg)))
            a = k;
    if (a < 0)
        return cli_usage_error(cmd,
                               "--axis: '%s' is not NAME=V1,V2,... with NAME one of melanin, "
                               "pheomelanin, blood, oxygenation, sc, epidermis",
                               arg);
    ss_error e;
    double *v;
    int n;
    int thickness = a == SS_MM_AXIS_SC || a == SS_MM_AXIS_EPIDERMIS;
    if (cli_parse_double_list("--axis", eq + 1, thickness ? 1e-6 : 0.0, 1.0, &v, &n, &e))
        return cli_fail(cmd, &e);
    for (int k = 1; k < n; k++)
        if (!(v[k] > v[k - 1])) {
            free(v);
            return cli_usage_error(cmd, "--axis %s: values must increase", ss_mm_axis_name(a));
        }
    if (n > 16) {
        free(v);
        return cli_usage_error(cmd, "--axis %s: at most 16 values", ss_mm_axis_name(a));
    }
    free(c->axis_values[a]);
    c->axis_values[a] = v;
    c->axis_count[a] = n;
    return 0;
}

static void table_help_options(FILE *f) {
    fit_cli c;
    init_cli(&c);
    table_help(f, &c);
}

int cmd_optics_table(int argc, char **argv) {
    const char *cmd = "optics table";
    fit_cli c;
    init_cli(&c);
    int rc = 0;
    ss_error e;
    ss_error_clear(&e);
    double surface_sigma = -1.0; /* --lookup: the surface's sigma (default: the table's) */
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            table_help(stdout, &c);
            return 0;
        }
        int k = parse_shared(cmd, argc, argv, &i, &c, &rc);
        if (k < 0) return rc;
        if (k == 1) continue;
        if (!strcmp(argv[i], "--out") || !strcmp(argv[i], "--lookup")) {
            if ((rc = need(cmd, argc, i, argv[i]))) return rc;
            if (!strcmp(argv[i], "--out"))
                c.out = argv[i + 1];
            else
                c.lookup = argv[i + 1];
            i++;
        } else if (!strcmp(argv[i], "--axis")) {
            if ((rc = need(cmd, argc, i, argv[i]))) return rc;
            if ((rc = parse_axis(cmd, argv[++i], &c))) return rc;
        } else if (!strcmp(argv[i], "--samples")) {
            if ((rc = need(cmd, argc, i, argv[i]))) return rc;
            if (cli_parse_int("--samples", argv[++i], 1, 9, &c.samples, &e))
                return cli_fail(cmd, &e);
        } else if (!strcmp(argv[i], "--surface-sigma")) {
            if ((rc = need(cmd, argc, i, argv[i]))) return rc;
            if (cli_parse_double("--surface-sigma", argv[++i], 0.0, 2.0, &surface_sigma, &e))
                return cli_fail(cmd, &e);
        } else
            return cli_unknown_option(cmd, argv[i], table_help_options);
    }
    if (c.out && c.lookup) return cli_usage_error(cmd, "--out and --lookup exclude each other");
    if (!c.out && !c.lookup) return cli_usage_error(cmd, "--out FILE or --lookup FILE is required");
    if ((rc = finish_shared(cmd, &c))) return rc;
    if (c.lookup) {
        ss_mm_table *t = ss_mm_table_read(c.lookup, &e);
        if (!t) return cli_fail(cmd, &e);
        ss_mm_entry en;
        ss_status st = ss_mm_table_lookup_bio(t, &c.bio, &en, &e);
        if (st) {
            ss_mm_table_free(t);
            return cli_fail(cmd, &e);
        }
        /* the GGX lobe of the surface's state (the table's surface curve),
         * and the base colour that keeps the albedo under it */
        const double sig = surface_sigma >= 0.0 ? surface_sigma : t->surface_sigma;
        double scale = 1.0;
        if (t->nsurface >= 2) {
            ss_mm_surface_lobe(t, sig, &en.fit[SS_RENDER_GGX].specular,
                               &en.fit[SS_RENDER_GGX].roughness, &scale);
            for (int k = 0; k < 3; k++) en.fit[SS_RENDER_GGX].base_rgb[k] *= scale;
        }
        if (c.json) {
            printf("{\"table\": ");
            json_str(c.lookup);
            printf(", \"entries\": %zu, \"photons\": %llu, \"surface_sigma\": %.6g, "
                   "\"table_surface_sigma\": %.6g, \"surface_curve\": %s, ",
                   t->nentries, (unsigned long long)t->photons, sig, t->surface_sigma,
                   t->nsurface >= 2 ? "true" : "false");
            print_entry(&en, NULL, 1);
            printf("}\n");
        } else {
            printf("# ModelMatch lookup in %s (%zu entries, %llu photons per trace)\n", c.lookup,
                   t->nentries, (unsigned long long)t->photons);
            if (t->nsurface >= 2)
                printf("# surface sigma %g (entries traced at %g): GGX lobe from the surface "
                       "curve, base colour x %.4f\n",
                       sig, t->surface_sigma, scale);
            else
                printf("# version 1 table: no surface curve, the entries' own lobe\n");
            print_entry(&en, NULL, 0);
        }
        ss_mm_table_free(t);
        return 0;
    }
    /* Under MPI (several ranks) every rank builds with rank 0 (src/mpi/table.c):
     * each calls table_build exactly once, rank 0 with its verdict on the output. */
    int dist = 0, rank0 = 1;
#ifdef SKINSIM_HAVE_MPI
    dist = ss_dist_size() > 1;
    rank0 = ss_dist_rank() == 0;
#define TABLE_BUILD(t, root_st)                                                                    \
    (dist        ? ss_dist_mm_table_build((t), &c.build, (root_st), &e)                            \
     : (root_st) ? (root_st)                                                                       \
                 : ss_mm_table_build((t), &c.build, &e))
#else
#define TABLE_BUILD(t, root_st) ((root_st) ? (root_st) : ss_mm_table_build((t), &c.build, &e))
#endif
    /* the table file: checked now, staged, swapped in whole when built (rank 0) */
    ss_outputs *outs = rank0 ? ss_outputs_create("optics", &e) : NULL;
    ss_status st = outs || !rank0 ? SS_OK : SS_ERR_NOMEM;
    double bytes = 8.0 * SS_MM_NFIELDS;
    for (int a = 0; a < SS_MM_NAXES; a++)
        bytes *= c.axis_values[a] ? c.axis_count[a] : (int)c.samples;
    if (!st && rank0) st = ss_outputs_add(outs, "--out", c.out, SS_OUTPUT_FILE, bytes + 4096, &e);
    if (!st && rank0) st = ss_outputs_begin(outs, &e);
    if (st) {
        if (dist) TABLE_BUILD(NULL, st);
        ss_outputs_free(outs);
        for (int a = 0; a < SS_MM_NAXES; a++) free(c.axis_values[a]);
        return cli_fail(cmd, &e);
    }
    int ns[SS_MM_NAXES];
    double lo[SS_MM_NAXES], hi[SS_MM_NAXES];
    for (int a = 0; a < SS_MM_NAXES; a++) {
        ns[a] = c.axis_values[a] ? c.axis_count[a] : (int)c.samples;
        ss_mm_axis_default_range(a, &lo[a], &hi[a]);
    }
    ss_mm_table *t = ss_mm_table_create(ns, lo, hi, &e);
    for (int a = 0; t && a < SS_MM_NAXES; a++)
        if (c.axis_values[a])
            for (int k = 0; k < ns[a]; k++) t->axis[a][k] = c.axis_values[a][k];
    for (int a = 0; a < SS_MM_NAXES; a++) free(c.axis_values[a]);
    if (!t) {
        if (dist) TABLE_BUILD(NULL, rank0 ? e.code : SS_OK);
        ss_outputs_free(outs);
        return cli_fail(cmd, &e);
    }
    c.build.base = c.bio; /* bilirubin, beta-carotene (the non-axis parameters) */
    double t0 = ss_now();
    st = TABLE_BUILD(t, SS_OK);
    double secs = ss_now() - t0;
    if (!rank0) { /* the others only built */
        ss_mm_table_free(t);
        return ss_status_exit_code(st);
    }
    /* the surface curve (cheap; the MPI build fills the entries only) */
    if (!st && t->nsurface == 0)
        st = ss_mm_table_build_surface(t, &c.build, SS_MM_SURFACE_N, SS_MM_SURFACE_LO,
                                       SS_MM_SURFACE_HI, &e);
    if (!st) st = ss_mm_table_write(ss_outputs_path(outs, 0), t, &e);
    st = ss_outputs_finish(outs, st, &e);
    ss_outputs_free(outs);
    if (st) {
        ss_mm_table_free(t);
        return cli_fail(cmd, &e);
    }
    if (c.json) {
        printf("{\"out\": ");
        json_str(c.out);
        printf(", \"samples\": %ld, \"entries\": %zu, \"photons\": %llu, \"seconds\": %.2f}\n",
               c.samples, t->nentries, (unsigned long long)t->photons, secs);
    } else if (!c.quiet)
        fprintf(stderr, "skinsim optics table: wrote %s (%zu entries, %.1f s)\n", c.out,
                t->nentries, secs);
    ss_mm_table_free(t);
    return 0;
}
