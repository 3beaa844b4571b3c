/* `skinsim optics match`: a target skin colour (8-bit sRGB or CIELAB) ->
 * the biological parameters whose rendered colour is closest, with the
 * CIEDE2000 difference (library: ss_mm_match, src/optics/match.c). The CLI
 * only parses, runs and prints; bad input exits 2 naming it. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "skinsim/optics.h"
#include "skinsim/optics_fit.h"

static void match_help(FILE *f) {
    fprintf(f, "usage: skinsim optics match (--srgb R,G,B | --lab L,a,b) [options]\n\n"
               "The biological skin parameters (melanin, pheomelanin ratio, blood, oxygenation,\n"
               "stratum corneum and epidermis thickness) whose colour under D65 is closest to a\n"
               "target colour in CIEDE2000. The colour is the diffuse albedo at normal incidence\n"
               "plus, by default, the light the rough surface reflects (as a colorimeter or a\n"
               "d:8 spectrophotometer with the specular component included measures skin, and\n"
               "as a photo under diffuse light shows it). The ModelMatch table gives the start,\n"
               "photon transport at the thicknesses found refines the four pigment parameters.\n"
               "Among colours that fit, a population prior (measured pheomelanin share,\n"
               "oxygenation, layer thicknesses, blood) picks the plausible biology; prints both\n"
               "stages' Delta-E00, the prior's penalty, and whether another biology far away\n"
               "fits within Delta-E00 +1 (unique: no, with that alternative).\n\n"
               "  --srgb R,G,B      target as 8-bit sRGB (0..255 each, e.g. picked from a photo)\n"
               "  --lab L,a,b       target as CIELAB (D65)\n"
               "  --table FILE      ModelMatch table (data/modelmatch_default.sstab)\n"
               "  --photons N       packets per wavelength in the transport stage (20000)\n"
               "  --seed N          random seed (1)\n"
               "  --threads N       threads (default: $SKINSIM_THREADS or all cores); the\n"
               "                    answer is the same for any count\n"
               "  --table-only      skip the transport stage\n"
               "  --geometry G      sci (default): albedo + surface reflectance (specular\n"
               "                    component included); sce: the albedo alone\n"
               "  --json            print JSON\n"
               "  --quiet           accepted for symmetry (no progress output)\n\n"
               "Example:\n  skinsim optics match --srgb 194,150,130\n");
}

static int parse3(const char *cmd, const char *opt, const char *s, double lo, double hi,
                  double v[3]) {
    ss_error e;
    ss_error_clear(&e);
    double *vals = NULL;
    int n = 0;
    if (cli_parse_double_list(opt, s, lo, hi, &vals, &n, &e)) return cli_fail(cmd, &e);
    if (n != 3) {
        free(vals);
        return cli_usage_error(cmd, "%s needs three comma-separated values (got %d)", opt, n);
    }
    memcpy(v, vals, 3 * sizeof(double));
    free(vals);
    return 0;
}

static void print_bio_json(const ss_bio_params *b) {
    printf("{\"melanin\": %.6f, \"pheomelanin_ratio\": %.6f, \"blood\": %.6f, "
           "\"oxygenation\": %.6f, \"sc_thickness_cm\": %.6f, \"epidermis_thickness_cm\": %.6f}",
           b->melanin, b->pheomelanin_ratio, b->blood, b->oxygenation, b->sc_thickness_cm,
           b->epidermis_thickness_cm);
}

int cmd_optics_match(int argc, char **argv) {
    const char *cmd = "optics match";
    double target[3] = {0, 0, 0}, srgb[3] = {0, 0, 0};
    int have_srgb = 0, have_lab = 0, json = 0, table_only = 0, threads = 0;
    const char *table = NULL;
    char defpath[4096];
    ss_mm_match_options o;
    ss_mm_match_options_default(&o);
    ss_error e;
    ss_error_clear(&e);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            match_help(stdout);
            return 0;
        }
        int val = !strcmp(a, "--srgb") || !strcmp(a, "--lab") || !strcmp(a, "--table") ||
                  !strcmp(a, "--photons") || !strcmp(a, "--seed") || !strcmp(a, "--threads") ||
                  !strcmp(a, "--geometry");
        if (val && i + 1 >= argc) return cli_usage_error(cmd, "%s needs a value", a);
        int rc;
        if (!strcmp(a, "--srgb")) {
            if ((rc = parse3(cmd, "--srgb", argv[++i], 0, 255, srgb))) return rc;
            have_srgb = 1;
        } else if (!strcmp(a, "--lab")) {
            if ((rc = parse3(cmd, "--lab", argv[++i], -200, 200, target))) return rc;
            if (target[0] < 0 || target[0] > 100)
                return cli_usage_error(cmd, "--lab: L* %g is outside 0..100", target[0]);
            have_lab = 1;
        } else if (!strcmp(a, "--table")) {
            table = argv[++i];
        } else if (!strcmp(a, "--photons")) {
            long n;
            if (cli_parse_int("--photons", argv[++i], 100, 4000000, &n, &e))
                return cli_fail(cmd, &e);
            o.spectrum.mc.photons = (uint64_t)n;
        } else if (!strcmp(a, "--seed")) {
            if (cli_parse_u64("--seed", argv[++i], &o.spectrum.mc.seed, &e))
                return cli_fail(cmd, &e);
        } else if (!strcmp(a, "--threads")) {
            int n;
            if (ss_threads_parse("--threads", argv[++i], &n, &e)) return cli_fail(cmd, &e);
            threads = n;
        } else if (!strcmp(a, "--geometry")) {
            const char *g = argv[++i];
            if (!strcmp(g, "sci"))
                o.geometry = SS_MM_GEOMETRY_SCI;
            else if (!strcmp(g, "sce"))
                o.geometry = SS_MM_GEOMETRY_SCE;
            else
                return cli_usage_error(cmd, "--geometry: '%s' is neither sci nor sce", g);
        } else if (!strcmp(a, "--table-only")) {
            table_only = 1;
        } else if (!strcmp(a, "--json")) {
            json = 1;
        } else if (!strcmp(a, "--quiet")) {
            /* nothing to silence */
        } else
            return cli_unknown_option(cmd, a, match_help);
    }
    if (have_srgb == have_lab) return cli_usage_error(cmd, "give exactly one of --srgb or --lab");
    if (ss_threads_check_env(&e)) return cli_fail(cmd, &e);
    ss_threads_set(threads);
    if (have_srgb) {
        double lin[3];
        for (int c = 0; c < 3; c++) lin[c] = ss_srgb_decode((float)(srgb[c] / 255.0));
        ss_srgb_linear_to_lab(lin, target);
    }
    if (!table) {
        snprintf(defpath, sizeof defpath, "%s/modelmatch_default.sstab", ss_data_dir());
        table = defpath;
    }
    ss_mm_table *t = ss_mm_table_read(table, &e);
    if (!t) return cli_fail(cmd, &e);
    o.refine = !table_only;
    ss_mm_match_result r;
    ss_status st = ss_mm_match(t, target, &o, &r, &e);
    ss_mm_table_free(t);
    if (st) return cli_fail(cmd, &e);
    double C, h, ita;
    ss_lab_describe(r.lab, &C, &h, &ita);
    if (json) {
        printf("{\"target_lab\": [%.4f, %.4f, %.4f], \"bio\": ", target[0], target[1], target[2]);
        print_bio_json(&r.bio);
        printf(", \"albedo_rgb\": [%.6f, %.6f, %.6f], \"lab\": [%.4f, %.4f, %.4f], "
               "\"delta_e00\": %.4f, \"refined\": %s, \"geometry\": \"%s\", \"surface\": %.5f, "
               "\"table_bio\": ",
               r.albedo_rgb[0], r.albedo_rgb[1], r.albedo_rgb[2], r.lab[0], r.lab[1], r.lab[2],
               r.delta_e00, r.refined ? "true" : "false",
               o.geometry == SS_MM_GEOMETRY_SCI ? "sci" : "sce", r.surface);
        print_bio_json(&r.table_bio);
        printf(", \"table_lab\": [%.4f, %.4f, %.4f], \"table_delta_e00\": %.4f, "
               "\"prior_penalty\": %.4f, \"unique\": %s, \"alternative\": {\"bio\": ",
               r.table_lab[0], r.table_lab[1], r.table_lab[2], r.table_delta_e00, r.prior_penalty,
               r.unique ? "true" : "false");
        print_bio_json(&r.alt_bio);
        printf(", \"delta_e00_table\": %.4f, \"distance\": %.4f}}\n", r.alt_delta_e00,
               r.alt_distance);
        return 0;
    }
    printf("target             L*a*b* %.2f %.2f %.2f\n", target[0], target[1], target[2]);
    printf("melanin            %.4f\npheomelanin ratio  %.3f\nblood              %.4f\n"
           "oxygenation        %.3f\nstratum corneum    %.5f cm\nepidermis          %.5f cm\n",
           r.bio.melanin, r.bio.pheomelanin_ratio, r.bio.blood, r.bio.oxygenation,
           r.bio.sc_thickness_cm, r.bio.epidermis_thickness_cm);
    printf("rendered           L*a*b* %.2f %.2f %.2f (C* %.1f, h %.1f deg, ITA %.1f deg)\n",
           r.lab[0], r.lab[1], r.lab[2], C, h, ita);
    printf("albedo             %.4f %.4f %.4f (linear sRGB)\n", r.albedo_rgb[0], r.albedo_rgb[1],
           r.albedo_rgb[2]);
    printf("geometry           %s (surface reflectance %.4f added to the albedo)\n",
           o.geometry == SS_MM_GEOMETRY_SCI ? "sci" : "sce", r.surface);
    printf("Delta-E00          %.3f (%s; table stage %.3f)\n", r.delta_e00,
           r.refined ? "transport" : "table", r.table_delta_e00);
    printf("prior penalty      %.3f (Delta-E00 units; the population prior, docs/optics.md)\n",
           r.prior_penalty);
    if (r.unique)
        printf("unique             yes (every fit within Delta-E00 +%.1f lies within %.2f of the "
               "axis ranges)\n",
               SS_MM_MATCH_TOL, SS_MM_MATCH_FAR);
    else
        printf("unique             no: melanin %.4f, pheomelanin ratio %.3f, blood %.4f, "
               "oxygenation %.3f also fits (table Delta-E00 %.3f, distance %.2f)\n",
               r.alt_bio.melanin, r.alt_bio.pheomelanin_ratio, r.alt_bio.blood,
               r.alt_bio.oxygenation, r.alt_delta_e00, r.alt_distance);
    return 0;
}
