/* Shared `skinsim optics` options; see optics_opts.h. */
#include "optics_opts.h"

#include <string.h>

#include "cli.h"

int optics_parse_shared(const char *cmd, int argc, char **argv, int *i, ss_bio_params *bio,
                        ss_spectrum_options *spec, uint64_t min_photons, uint64_t max_photons,
                        int *rc) {
    const char *a = argv[*i];
    ss_error e;
    ss_error_clear(&e);
    if (!strcmp(a, "--scalar")) { /* the one-photon-at-a-time loop, for comparison */
        spec->mc.kernel = SS_MC_KERNEL_SCALAR;
        return 1;
    }
    struct {
        const char *name;
        double *dst;
        double lo, hi;
    } dbl[] = {
        {"--melanin", &bio->melanin, 0, 1},
        {"--pheomelanin-ratio", &bio->pheomelanin_ratio, 0, 1},
        {"--blood", &bio->blood, 0, 1},
        {"--oxygenation", &bio->oxygenation, 0, 1},
        {"--sc-thickness-cm", &bio->sc_thickness_cm, 1e-6, 1},
        {"--epidermis-thickness-cm", &bio->epidermis_thickness_cm, 1e-6, 1},
        {"--bilirubin-g-per-l", &bio->bilirubin_g_per_l, 0, 100},
        {"--betacarotene-g-per-l", &bio->betacarotene_g_per_l, 0, 100},
        {"--roughness", &spec->mc.roughness_sigma, 0, 10},
        {"--wl-min", &spec->wl_min_nm, 300, 800},
        {"--wl-max", &spec->wl_max_nm, 300, 800},
        {"--wl-step", &spec->wl_step_nm, 0.1, 400},
    };
    int is_dbl = -1;
    for (size_t k = 0; k < sizeof dbl / sizeof dbl[0]; k++)
        if (!strcmp(a, dbl[k].name)) is_dbl = (int)k;
    int is_u64 = !strcmp(a, "--photons") || !strcmp(a, "--seed");
    if (is_dbl < 0 && !is_u64) return 0;
    if (*i + 1 >= argc) {
        *rc = cli_usage_error(cmd, "%s needs a value", a);
        return -1;
    }
    const char *val = argv[++*i];
    if (is_dbl >= 0) {
        if (cli_parse_double(a, val, dbl[is_dbl].lo, dbl[is_dbl].hi, dbl[is_dbl].dst, &e)) {
            *rc = cli_fail(cmd, &e);
            return -1;
        }
        return 1;
    }
    uint64_t v;
    if (cli_parse_u64(a, val, &v, &e)) {
        *rc = cli_fail(cmd, &e);
        return -1;
    }
    if (!strcmp(a, "--seed")) {
        spec->mc.seed = v;
        return 1;
    }
    if (v < min_photons || v > max_photons) {
        *rc = cli_usage_error(cmd, "--photons: %llu is outside %llu..%llu", (unsigned long long)v,
                              (unsigned long long)min_photons, (unsigned long long)max_photons);
        return -1;
    }
    spec->mc.photons = v;
    return 1;
}
