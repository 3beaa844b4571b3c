/* The clinical course of one healing scenario on a square wound (figures of
 * docs/heal-model.md §6: closure times, scab, scar, remodelling, keloid),
 * for calibration and for the convergence and sensitivity tables that
 * bench/heal_tables.sh builds from it. Prints one JSON object.
 * Usage: bench_heal_course [--scenario S] [--dx MM] [--block MM] [--wound MM]
 *        [--depth MM] [--days D] [--dt D] [--late-dt D] [--deep-day D]
 *        [--keloid-thr R] [--keloid-days A,B] [--set KEY=VALUE]... [--scale
 * KEY=FACTOR]... bench_heal_course [--scenario S] --get KEY   (prints the preset value) Figures
 * only; nothing is asserted. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/heal.h"

static int set_param(ss_heal_params *p, const char *kv, int scale) {
    char key[64];
    const char *eq = strchr(kv, '=');
    if (!eq || eq - kv >= (long)sizeof key) return -1;
    memcpy(key, kv, (size_t)(eq - kv));
    key[eq - kv] = 0;
    ss_error err;
    double cur = 0, v = atof(eq + 1);
    if (ss_heal_param_get(p, key, &cur, &err) ||
        ss_heal_param_set(p, key, scale ? cur * v : v, &err)) {
        fprintf(stderr, "%s\n", err.msg);
        return -1;
    }
    return 0;
}

int main(int argc, char **argv) {
    const char *scen = "clean";
    ss_heal_course_opts o = {30.0, 20.0, 1.0, 0.5, 30.0, 0.05, 0.0, 21.0, 0.0, {0, 0}};
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], "--scenario") && i + 1 < argc) scen = argv[++i];
    ss_error err;
    ss_heal_params *p = ss_heal_params_preset(scen, &err);
    if (!p) {
        fprintf(stderr, "%s\n", err.msg);
        return 2;
    }
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--scenario")) {
            i++;
        } else if (v && !strcmp(a, "--dx")) {
            o.dx_mm = atof(v), i++;
        } else if (v && !strcmp(a, "--block")) {
            o.block_mm = atof(v), i++;
        } else if (v && !strcmp(a, "--wound")) {
            o.wound_mm = atof(v), i++;
        } else if (v && !strcmp(a, "--depth")) {
            o.depth_mm = atof(v), i++;
        } else if (v && !strcmp(a, "--days")) {
            o.days = atof(v), i++;
        } else if (v && !strcmp(a, "--dt")) {
            o.dt_days = atof(v), i++;
        } else if (v && !strcmp(a, "--late-dt")) {
            o.late_dt_days = atof(v), i++;
        } else if (v && !strcmp(a, "--deep-day")) {
            o.deep_check_day = atof(v), i++;
        } else if (v && !strcmp(a, "--keloid-thr")) {
            o.keloid_thr = atof(v), i++;
        } else if (v && !strcmp(a, "--keloid-days")) {
            if (sscanf(v, "%lf,%lf", &o.keloid_day[0], &o.keloid_day[1]) != 2) {
                fprintf(stderr, "bench_heal_course: --keloid-days wants A,B (days)\n");
                return 2;
            }
            i++;
        } else if (v && !strcmp(a, "--get")) {
            double val;
            if (ss_heal_param_get(p, v, &val, &err)) {
                fprintf(stderr, "%s\n", err.msg);
                return 2;
            }
            printf("%g\n", val);
            ss_heal_params_free(p);
            return 0;
        } else if (v && (!strcmp(a, "--set") || !strcmp(a, "--scale"))) {
            if (set_param(p, v, !strcmp(a, "--scale"))) {
                fprintf(stderr, "bench_heal_course: bad %s %s\n", a, v);
                return 2;
            }
            i++;
        } else {
            fprintf(stderr, "bench_heal_course: unknown option %s (see the file's comment)\n", a);
            return 2;
        }
    }
    ss_heal_course c;
    if (ss_heal_course_run(p, &o, &c, &err)) {
        fprintf(stderr, "%s\n", err.msg);
        return 1;
    }
    printf(
        "{\"scenario\": \"%s\", \"dx_mm\": %g, \"block_mm\": %g, \"wound_mm\": %g, \"days\": %g, "
        "\"t50\": %.3f, \"t95\": %.3f, \"scab_day\": %.3f, \"scab_gone_day\": %.3f, "
        "\"scar_peak_mm3\": %.4f, \"scar_peak_day\": %.2f, \"scar_end_mm3\": %.4f, "
        "\"scar_max_peak\": %.4f, \"half_life_days\": %.1f, \"deep_e_fraction\": %.4f, "
        "\"keloid_beyond_mm\": %.3f, \"keloid_beyond_t95\": %.3f, \"keloid_area_mm2\": %.1f, "
        "\"region_area_mm2\": %.1f, \"keloid_beyond_days\": [%.3f, %.3f], "
        "\"keloid_beyond_max\": %.3f, \"scar_max_end\": %.4f, \"elev_max_mm\": %.4f, "
        "\"elev_max_day\": %.2f, \"elev_end_max_mm\": %.4f, \"elev_end_mean_mm\": %.4f, "
        "\"scar_deep_max\": %.4f, \"steps\": %ld, \"wall_s\": %.2f}\n",
        scen, o.dx_mm, o.block_mm, o.wound_mm, o.days, c.t50, c.t95, c.scab_day, c.scab_gone_day,
        c.scar_peak_mm3, c.scar_peak_day, c.scar_end_mm3, c.scar_max_peak, c.half_life_days,
        c.deep_e_fraction, c.keloid_beyond_mm, c.keloid_beyond_t95, c.keloid_area_mm2,
        c.region_area_mm2, c.keloid_beyond_day[0], c.keloid_beyond_day[1], c.keloid_beyond_max,
        c.scar_max_end, c.elev_max_mm, c.elev_max_day, c.elev_end_max_mm, c.elev_end_mean_mm,
        c.scar_deep_max, c.steps, c.wall_s);
    ss_heal_params_free(p);
    return 0;
}
