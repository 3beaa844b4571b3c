/* `skinsim mech stretch`: the uniaxial material test of the tissue models
 * (library: ss_mech_stretch, src/mech/stretch.c). The CLI only parses, runs
 * and prints; bad input exits 2 naming it. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "skinsim/mech.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static void mech_help(FILE *f) {
    fprintf(f, "usage: skinsim mech stretch --stretch L [options]\n\n"
               "Uniaxial test of a cube of the mechanics' own lattice mesh, lateral faces free.\n"
               "Tension: a dead load on the end faces, found so that they end L times the length\n"
               "apart, and six pins against rigid motion only (the block may shear); compression:\n"
               "the low face slides on its plane, the high face is moved to L. Prints the Cauchy\n"
               "stress along the axis (reaction over the current cross-section), the shear\n"
               "(F_a1, F_a2: the axial displacement's gradient across) and the closed-form GOH\n"
               "values of the homogeneous uniaxial state, same parameters (docs/mech.md).\n\n"
               "  --stretch L          stretch along the axis (0.3..3)\n"
               "  --axis x|y|z         the stretched axis (x)\n"
               "  --fibres x|y|z|DEG   one fibre family along an axis, or DEG degrees from x in\n"
               "                       the x-y plane (x)\n"
               "  --param NAME=V       a mechanics parameter (data/heal/mechanics.json), e.g.\n"
               "                       mu=20, k2=5, k1_goh=300, kappa=0.2; repeatable\n"
               "  --params FILE        a parameter file with a \"mechanics\" object\n"
               "  --mech-model M       goh (the hyperelastic solver, default) or springs (the\n"
               "                       seed's mass-spring network; its end faces are clamped)\n"
               "  --size-mm S          cube edge (4)\n"
               "  --tet-size-mm H      lattice edge (the parameters' tet_size_mm, 1)\n"
               "  --increments N       load steps (10)\n"
               "  --threads N          threads; the result is the same for any count\n"
               "  --json               print JSON\n");
}

static int parse_fibre(const char *cmd, const char *s, double f[3]) {
    f[0] = f[1] = f[2] = 0;
    if (!strcmp(s, "x") || !strcmp(s, "y") || !strcmp(s, "z")) {
        f[s[0] - 'x'] = 1;
        return 0;
    }
    double deg;
    ss_error e;
    if (cli_parse_double("--fibres", s, -360, 360, &deg, &e)) {
        ss_error_set(&e, SS_ERR_INPUT, "--fibres: '%s' is not x, y, z or an angle in degrees", s);
        return cli_fail(cmd, &e);
    }
    f[0] = cos(deg * M_PI / 180);
    f[1] = sin(deg * M_PI / 180);
    return 0;
}

static int cmd_mech_stretch(int argc, char **argv) {
    const char *cmd = "mech stretch";
    ss_error e;
    ss_error_clear(&e);
    ss_mech_params p;
    ss_mech_params_default(&p);
    ss_mech_stretch_config c;
    ss_mech_stretch_config_default(&c);
    int json = 0, have_stretch = 0, rc, k1_set = 0;
    const char *params_path = NULL;
    char *sets[64];
    int nsets = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            mech_help(stdout);
            return 0;
        }
        if (!strcmp(a, "--json")) {
            json = 1;
            continue;
        }
        if (strncmp(a, "--", 2)) return cli_usage_error(cmd, "unexpected argument '%s'", a);
        const char *v = cli_option_value(argc, argv, &i, &e);
        if (!v) return cli_fail(cmd, &e);
        if (!strcmp(a, "--stretch")) {
            if (cli_parse_double(a, v, 0.3, 3, &c.stretch, &e)) return cli_fail(cmd, &e);
            have_stretch = 1;
        } else if (!strcmp(a, "--axis")) {
            if (strcmp(v, "x") && strcmp(v, "y") && strcmp(v, "z"))
                return cli_usage_error(cmd, "--axis: '%s' is not x, y or z", v);
            c.axis = v[0] - 'x';
        } else if (!strcmp(a, "--fibres")) {
            if ((rc = parse_fibre(cmd, v, c.fibre))) return rc;
        } else if (!strcmp(a, "--param")) {
            if (nsets == 64) return cli_usage_error(cmd, "--param: at most 64");
            sets[nsets++] = (char *)v;
        } else if (!strcmp(a, "--params")) {
            params_path = v;
        } else if (!strcmp(a, "--mech-model")) {
            if (ss_mech_model_parse(v, &c.model, &e)) return cli_fail(cmd, &e);
        } else if (!strcmp(a, "--size-mm")) {
            if (cli_parse_double(a, v, 0.1, 100, &c.size_mm, &e)) return cli_fail(cmd, &e);
        } else if (!strcmp(a, "--tet-size-mm")) {
            if (cli_parse_double(a, v, 0.05, 100, &c.tet_size_mm, &e)) return cli_fail(cmd, &e);
        } else if (!strcmp(a, "--increments")) {
            long n;
            if (cli_parse_int(a, v, 1, 1000, &n, &e)) return cli_fail(cmd, &e);
            c.increments = (int)n;
        } else if (!strcmp(a, "--threads")) {
            int n;
            if (ss_threads_parse("--threads", v, &n, &e)) return cli_fail(cmd, &e);
            ss_threads_set(n);
        } else {
            return cli_usage_error(cmd, "unknown option '%s'", a);
        }
    }
    if (!have_stretch) return cli_usage_error(cmd, "--stretch L is required");
    if (params_path) {
        char *text = ss_read_file(params_path, NULL, &e);
        if (!text) return cli_fail(cmd, &e);
        ss_status st = ss_mech_params_parse(&p, text, params_path, &e);
        free(text);
        if (st) return cli_fail(cmd, &e);
    }
    for (int k = 0; k < nsets; k++) {
        char name[64];
        const char *eq = strchr(sets[k], '=');
        if (!eq || eq == sets[k] || (size_t)(eq - sets[k]) >= sizeof name)
            return cli_usage_error(cmd, "--param '%s': expected NAME=VALUE", sets[k]);
        memcpy(name, sets[k], (size_t)(eq - sets[k]));
        name[eq - sets[k]] = 0;
        if (!strcmp(name, "k1")) k1_set = 1;
        ss_error pe;
        if (ss_mech_params_set(&p, name, eq + 1, &pe)) {
            ss_error_set(&e, SS_ERR_INPUT, "--param %s: %s", sets[k], pe.msg);
            return cli_fail(cmd, &e);
        }
    }
    if (k1_set && c.model == SS_MECH_MODEL_GOH)
        return cli_usage_error(cmd,
                               "--param k1: k1 is the springs path's rest-length calibration; the "
                               "GOH solver's fibre stiffness is k1_goh");
    ss_mech_stretch_result r;
    if (ss_mech_stretch(&p, &c, &r, &e)) return cli_fail(cmd, &e);
    const char ax = (char)('x' + c.axis);
    double rel = r.analytic_stress_kpa != 0
                     ? (r.stress_kpa - r.analytic_stress_kpa) / fabs(r.analytic_stress_kpa)
                     : 0;
    if (json) {
        printf("{\n  \"model\": \"%s\",\n  \"stretch\": %.17g,\n  \"axis\": \"%c\",\n"
               "  \"fibre\": [%.17g, %.17g, %.17g],\n  \"stress_kpa\": %.17g,\n"
               "  \"analytic_stress_kpa\": %.17g,\n  \"relative_difference\": %.17g,\n"
               "  \"mean_cauchy_kpa\": %.17g,\n  \"lateral_stretch\": [%.17g, %.17g],\n"
               "  \"analytic_lateral_stretch\": [%.17g, %.17g],\n"
               "  \"shear\": [%.17g, %.17g],\n  \"analytic_shear\": [%.17g, %.17g],\n"
               "  \"params\": {\"mu\": %.17g, \"K_bulk\": %.17g, \"k1_goh\": %.17g, \"k2\": %.17g, "
               "\"kappa\": %.17g},\n"
               "  \"nodes\": %d,\n  \"tets\": %d,\n  \"newton\": %d,\n  \"iterations\": %d,\n"
               "  \"converged\": %s\n}\n",
               ss_mech_model_name(c.model), c.stretch, ax, c.fibre[0], c.fibre[1], c.fibre[2],
               r.stress_kpa, r.analytic_stress_kpa, rel, r.mean_sigma_kpa, r.lateral_stretch[0],
               r.lateral_stretch[1], r.analytic_lateral[0], r.analytic_lateral[1], r.shear[0],
               r.shear[1], r.analytic_shear[0], r.analytic_shear[1], p.mu, p.K_bulk, p.k1_goh, p.k2,
               p.kappa, r.nodes, r.tets, r.newton, r.cg, r.converged ? "true" : "false");
    } else {
        printf("%s, stretch %g along %c, fibres (%.3g, %.3g, %.3g), %d tets:\n"
               "  stress %.6g kPa, analytic GOH %.6g kPa (%+.2e), lateral stretch %.5g %.5g "
               "(analytic %.5g %.5g), shear %.5g %.5g (analytic %.5g %.5g)%s\n",
               ss_mech_model_name(c.model), c.stretch, ax, c.fibre[0], c.fibre[1], c.fibre[2],
               r.tets, r.stress_kpa, r.analytic_stress_kpa, rel, r.lateral_stretch[0],
               r.lateral_stretch[1], r.analytic_lateral[0], r.analytic_lateral[1], r.shear[0],
               r.shear[1], r.analytic_shear[0], r.analytic_shear[1],
               r.converged ? "" : " (not converged)");
    }
    return 0;
}

int cmd_mech(int argc, char **argv) {
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
        mech_help(argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    if (!strcmp(argv[1], "stretch")) return cmd_mech_stretch(argc - 1, argv + 1);
    return cli_usage_error("mech", "unknown subcommand '%s' (try: stretch)", argv[1]);
}
