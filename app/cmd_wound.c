/* skinsim wound: a healing wound as textures, day by day (the seeds joined:
 * the heal simulation of seed 001, the optics and ModelMatch table of seed
 * 003, the texture-timeline outputs of seed 000). Parses the options into an
 * ss_wound_make_config and prints; src/wound does the work. */
#define _POSIX_C_SOURCE 200809L
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "cli.h"
#include "heal_opts.h"
#include "skinsim/wound.h"

#define CMD "wound"

static void help(FILE *f) {
    fprintf(f,
            "usage: skinsim wound [options]\n"
            "\n"
            "Simulates the healing of a wound (as `skinsim heal`) and turns the tissue at\n"
            "the skin surface into skin textures on every requested day: epithelium,\n"
            "capillaries, oxygen, eschar (scab), scar and the wound region become\n"
            "biological parameters (melanin, blood, oxygenation, layer thicknesses), the\n"
            "ModelMatch table turns them into base colour and roughness, a dried-blood\n"
            "layer colours the scab, and the wound depth (seed 001 §5.4), scab and keloid\n"
            "give the height. See docs/wound.md.\n"
            "\n"
            "Healing problem: the options of `skinsim heal` (see skinsim heal --help):\n"
            "  --scenario clean|scab|keloid, --params FILE.json, --no-scab, --static-region,\n"
            "  --grid NXxNYxNZ, --size-mm X,Y,Z (square in x, y: the texture covers the\n"
            "  block), --stroke CSV, --concave-k K, --wound-mask PNG, --wound-mesh OBJ,\n"
            "  --wound-depth-mm D, --wound-depth-image F, --skin-top-mm, --epidermis-mm,\n"
            "  --dt DAYS, --scheme explicit|split, --adapt-tol X\n"
            "  --mesh M --wound-uv CSV  on a body (as skinsim heal): the textures cover the\n"
            "                         mesh's UV layout and each day's glTF is the mesh\n"
            "  --heal DIR             instead: render a finished `skinsim heal --out DIR` run\n"
            "                         (no heal options then; every day must be one of its\n"
            "                         snapshot days, see its --snapshot-every)\n"
            "\n"
            "Textures\n"
            "  --days LIST            output days, increasing (default 0,1,3,7,14,28,90,365);\n"
            "                         the simulation runs to the last\n"
            "  --size N               texture side in pixels (default 1024, 16..16384); the\n"
            "                         texture covers the heal block (default 30 x 30 mm)\n"
            "  --skin FILE.exr|FOLDER base skin as bio-parameter maps (channels: melanin,\n"
            "                         pheomelanin, blood, oxygenation, sc_cm, epidermis_cm,\n"
            "                         height_mm), or a `skinsim skin` folder (its bio.exr);\n"
            "                         default: a built-in light skin with mottling\n"
            "  --recipe FILE.json     mapping overrides {\"recipe\": {\"bed_blood\": {\"value\":\n"
            "                         0.04, \"unit\": \"1\"}, ...}} (keys and units in\n"
            "                         docs/wound.md)\n"
            "  --table FILE.sstab     ModelMatch table (default data/modelmatch_default.sstab)\n"
            "  --exr                  also write every map as half-float EXR (height in mm)\n"
            "  --no-compare           skip compare_abrasion.png\n"
            "  --mechanics            couple the contraction mechanics (seed 001 §4.2-5.3, as\n"
            "                         skinsim heal --mechanics) and draw its displacement\n"
            "\n"
            "Output\n"
            "  --out DIR              output directory (default wound-out)\n"
            "  --threads N            OpenMP threads (default $SKINSIM_THREADS or all)\n"
            "  --seed N               base skin noise and Monte Carlo seed (default 1)\n"
            "  --quiet                no progress bar or text summary\n"
            "  --json                 print the summary (timeline.json) on stdout\n"
            "\n"
            "Files written in DIR:\n"
            "  frames/t<day>_base_color.png   sRGB 8-bit\n"
            "  frames/t<day>_roughness.png    GGX perceptual roughness, 8-bit linear\n"
            "  frames/t<day>_height.png       16-bit, 0.5 = skin surface, 0..1 spans\n"
            "                                 -2..+2 mm (recipe height_range)\n"
            "  frames/t<day>_normal.png       tangent space, OpenGL (+Y up)\n"
            "  frames/t<day>.gltf             the day on a square of the block's size\n"
            "  contact_sheet.png              base colour per day\n"
            "  compare_abrasion.png           the same wound through `skinsim abrasion`\n"
            "  timeline.json                  frames and files in the abrasion timeline\n"
            "                                 format, recipe, timings\n"
            "Exit codes: 0 ok, 1 runtime failure, 2 bad input (nothing is written then).\n\n"
            "Example:\n"
            "  skinsim wound --scenario scab --days 0,3,7,14 --size 256 --out wound-out\n");
}

typedef struct opts {
    ss_wound_make_config c;
    double *days;
    int threads, json;
} opts;

static int parse_args(int argc, char **argv, opts *o, ss_error *err) {
    memset(o, 0, sizeof *o);
    ss_wound_make_config *c = &o->c;
    ss_wound_make_config_default(c);
    c->out_dir = "wound-out";
    const char *days = "0,1,3,7,14,28,90,365";
    int have_adapt = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) return 1;
        if (heal_parse_problem_flag(a, &c->heal)) continue;
        if (!strcmp(a, "--quiet")) {
            c->quiet = 1;
            continue;
        }
        if (!strcmp(a, "--json")) {
            o->json = 1;
            continue;
        }
        if (!strcmp(a, "--exr")) {
            c->exr = 1;
            continue;
        }
        if (!strcmp(a, "--no-compare")) {
            c->compare = 0;
            continue;
        }
        const char *v = cli_option_value(argc, argv, &i, err);
        if (!v) return -1;
        int pr = heal_parse_problem_option(a, v, &c->heal, err);
        if (pr < 0) return -1;
        if (pr > 0) continue;
        ss_status st = SS_OK;
        long l;
        if (!strcmp(a, "--days")) {
            days = v;
        } else if (!strcmp(a, "--heal")) {
            c->heal_dir = v;
        } else if (!strcmp(a, "--adapt-tol")) {
            st = cli_parse_double(a, v, 0, 1, &c->heal.adapt_tol, err);
            have_adapt = 1;
        } else if (!strcmp(a, "--size")) {
            st = cli_parse_int(a, v, 16, 16384, &l, err);
            c->size = (int)l;
        } else if (!strcmp(a, "--skin")) {
            c->skin_path = v;
        } else if (!strcmp(a, "--recipe")) {
            c->recipe_path = v;
        } else if (!strcmp(a, "--table")) {
            c->table_path = v;
        } else if (!strcmp(a, "--out")) {
            c->out_dir = v;
        } else if (!strcmp(a, "--threads")) {
            st = cli_parse_int(a, v, 0, SS_THREADS_MAX, &l, err);
            o->threads = (int)l;
        } else if (!strcmp(a, "--seed")) {
            st = cli_parse_u64(a, v, &c->seed, err);
        } else {
            cli_unknown_option_set(err, "unknown option", a, help);
            return -1;
        }
        if (st) return -1;
    }
    if (cli_parse_double_list("--days", days, 0, 1e4, &o->days, &c->ndays, err)) return -1;
    /* adaptive steps as skinsim heal's (a --heal DIR run was made already) */
    if (!have_adapt && !c->heal_dir) heal_default_adapt_tol(&c->heal);
    c->days = o->days;
    return 0;
}

int cmd_wound(int argc, char **argv) {
    ss_error err;
    ss_error_clear(&err);
    opts o;
    int pa = parse_args(argc, argv, &o, &err);
    if (pa == 1) {
        help(stdout);
        free(o.days);
        return 0;
    }
    if (pa < 0) {
        free(o.days);
        return cli_usage_error(CMD, "%s", err.msg);
    }
    ss_threads_set(o.threads);
    char *summary = NULL;
    ss_status st = ss_wound_make(&o.c, &summary, &err);
    free(o.days);
    if (st) return cli_fail(CMD, &err);
    cJSON *sum = summary ? cJSON_Parse(summary) : NULL;
    const cJSON *warn, *ws = sum ? cJSON_GetObjectItemCaseSensitive(sum, "warnings") : NULL;
    cJSON_ArrayForEach(warn, ws) if (cJSON_IsString(warn))
        fprintf(stderr, "skinsim %s: warning: %s\n", CMD, warn->valuestring);
    cJSON_Delete(sum);
    if (o.json)
        printf("%s\n", summary);
    else if (!o.c.quiet)
        fprintf(
            stderr,
            "wrote %s (contact sheet: %s/contact_sheet.png, compare: %s/compare_abrasion.png)\n",
            o.c.out_dir, o.c.out_dir, o.c.out_dir);
    free(summary);
    return 0;
}
