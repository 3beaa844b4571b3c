/* skinsim abrasion: renders the abrasion-healing timeline of seed 000 for a
 * painted shape (strokes or mask) and writes key textures, frames at the
 * requested days, timeline.json and a labelled contact sheet. All inputs are
 * read and checked before anything is written; the output folder goes
 * through the core output discipline (checked before work, staged next to
 * its target, swapped in whole; a previous run's folder is replaced whole or
 * not at all). */
#define _POSIX_C_SOURCE 200809L
#include <cjson/cJSON.h>
#include <getopt.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "skinsim/abrasion.h"

static const char *CMD = "abrasion";

static void help(FILE *f) {
    fprintf(
        f,
        "usage: skinsim abrasion [options]\n\n"
        "Renders the abrasion-healing timeline (seed 000): five key positions\n"
        "(vasoconstriction, vasodilation, scab_forming, scab, maturation) from a wound\n"
        "shape, and the blended texture set at each requested time.\n\n"
        "Wound shape (default: a built-in example scrape):\n"
        "  --stroke FILE.csv     painted points 'u,v[,stroke_id]' per line, u,v in 0..1,\n"
        "                        v = 0 at the top of the texture; one hull per stroke id\n"
        "  --mask FILE.png       white = wound (PNG or EXR, any size); each connected\n"
        "                        region is one wound\n"
        "  --hull convex|concave hull of each stroke (default convex, as the seed)\n"
        "  --concave-k K         neighbours for the concave hull (default 5, >= 3)\n\n"
        "Skin:\n"
        "  --upper FILE          healthy skin colour texture (PNG sRGB or EXR linear)\n"
        "  --lower FILE          dermis colour texture; both default to procedural skin\n\n"
        "Output:\n"
        "  --size N              texture side in pixels (default 2048, 16..16384)\n"
        "  --world-size-cm X     side of the texture on the body (default 10 cm)\n"
        "  --times LIST          days since injury, comma separated\n"
        "                        (default 0,0.003,0.02,0.75,5,12,20,30)\n"
        "  --timeline FILE.json  key positions: {\"keys\":[{\"phase\":\"scab\",\"day\":3},...],\n"
        "                        \"end_day\":30}; default mapping in docs/abrasion.md\n"
        "  --seed S              random seed (default 1); same seed, same pixels\n"
        "  --out DIR             output directory (default abrasion-out)\n"
        "  --threads N           worker threads (default: SKINSIM_THREADS or all cores)\n"
        "  --quiet               no progress on stderr\n"
        "  --json                print a summary as JSON on stdout\n"
        "  --exr                 also write every map as half-float OpenEXR (linear light)\n"
        "  --gltf                also write DIR/frames/t<days>.gltf: the frame on a square\n"
        "                        of the world size, for any glTF viewer or Blender\n"
        "                        (roughness = 1 - 0.8 x reflection in t<days>_metal_rough.png)\n\n"
        "Writes DIR/keys/<phase>_{color,reflection,height,normal}.png,\n"
        "DIR/frames/t<days>_{color,reflection,height,normal}.png, DIR/timeline.json and\n"
        "DIR/contact_sheet.png. Colour is sRGB 8-bit; reflection (specular strength)\n"
        "8-bit; height 16-bit (0.5 = skin surface, 0..1 spans -0.5..+0.5 mm); normal\n"
        "8-bit, tangent space, OpenGL convention (+Y up).\n\n"
        "Example:\n"
        "  skinsim abrasion --stroke data/examples/knee.csv --size 1024 --times 0,1,5,30 --out "
        "knee\n");
}

typedef struct opts {
    const char *stroke, *mask, *upper, *lower, *timeline, *out;
    int size, concave_k, threads, quiet, json, gltf, exr;
    ss_hull_kind hull;
    double world_cm;
    uint64_t seed;
    double *times;
    int ntimes;
} opts;

static int parse(int argc, char **argv, opts *o, ss_error *err) {
    static const struct option longopts[] = {{"stroke", required_argument, 0, 's'},
                                             {"mask", required_argument, 0, 'm'},
                                             {"hull", required_argument, 0, 'H'},
                                             {"concave-k", required_argument, 0, 'k'},
                                             {"upper", required_argument, 0, 'u'},
                                             {"lower", required_argument, 0, 'l'},
                                             {"size", required_argument, 0, 'n'},
                                             {"world-size-cm", required_argument, 0, 'w'},
                                             {"times", required_argument, 0, 't'},
                                             {"timeline", required_argument, 0, 'T'},
                                             {"seed", required_argument, 0, 'S'},
                                             {"out", required_argument, 0, 'o'},
                                             {"threads", required_argument, 0, 'j'},
                                             {"quiet", no_argument, 0, 'q'},
                                             {"json", no_argument, 0, 'J'},
                                             {"help", no_argument, 0, 'h'},
                                             {"gltf", no_argument, 0, 'G'},
                                             {"exr", no_argument, 0, 'E'},
                                             {0, 0, 0, 0}};
    memset(o, 0, sizeof *o);
    o->size = 2048;
    o->concave_k = 5;
    o->world_cm = 10.0;
    o->seed = 1;
    o->out = "abrasion-out";
    o->hull = SS_HULL_CONVEX;
    const char *times = "0,0.003,0.02,0.75,5,12,20,30";
    optind = 1;
    opterr = 0;
    int c;
    long v;
    ss_status st = SS_OK;
    while (!st && (c = getopt_long(argc, argv, "", longopts, NULL)) != -1) {
        switch (c) {
        case 's':
            o->stroke = optarg;
            break;
        case 'm':
            o->mask = optarg;
            break;
        case 'u':
            o->upper = optarg;
            break;
        case 'l':
            o->lower = optarg;
            break;
        case 'T':
            o->timeline = optarg;
            break;
        case 'o':
            o->out = optarg;
            break;
        case 't':
            times = optarg;
            break;
        case 'q':
            o->quiet = 1;
            break;
        case 'G':
            o->gltf = 1;
            break;
        case 'E':
            o->exr = 1;
            break;
        case 'J':
            o->json = 1;
            break;
        case 'h':
            help(stdout);
            return -1;
        case 'H':
            if (!strcmp(optarg, "convex"))
                o->hull = SS_HULL_CONVEX;
            else if (!strcmp(optarg, "concave"))
                o->hull = SS_HULL_CONCAVE;
            else
                st = ss_error_set(err, SS_ERR_INPUT, "--hull: '%s' is not convex or concave",
                                  optarg);
            break;
        case 'k':
            st = cli_parse_int("--concave-k", optarg, 3, 1000, &v, err);
            o->concave_k = (int)v;
            break;
        case 'n':
            st = cli_parse_int("--size", optarg, 16, 16384, &v, err);
            o->size = (int)v;
            break;
        case 'j':
            st = cli_parse_int("--threads", optarg, 1, SS_THREADS_MAX, &v, err);
            o->threads = (int)v;
            break;
        case 'w':
            st = cli_parse_double("--world-size-cm", optarg, 1e-3, 1e4, &o->world_cm, err);
            break;
        case 'S':
            st = cli_parse_u64("--seed", optarg, &o->seed, err);
            break;
        default:
            st =
                cli_unknown_option_set(err, "unknown or incomplete option", argv[optind - 1], help);
        }
    }
    if (!st && optind < argc)
        st = ss_error_set(err, SS_ERR_INPUT, "unexpected argument '%s'", argv[optind]);
    if (!st && o->stroke && o->mask)
        st = ss_error_set(err, SS_ERR_INPUT, "give --stroke or --mask, not both");
    if (!st) st = cli_parse_double_list("--times", times, 0.0, 1e5, &o->times, &o->ntimes, err);
    for (int i = 1; !st && i < o->ntimes; i++)
        if (o->times[i] < o->times[i - 1])
            st = ss_error_set(err, SS_ERR_INPUT,
                              "--times: list them in increasing order (%g after %g)", o->times[i],
                              o->times[i - 1]);
    /* each time names its files t<days>_*: two times with one name would
     * write the same files twice */
    for (int i = 0; !st && i < o->ntimes; i++)
        for (int j = 0; !st && j < i; j++) {
            char a[32], b[32];
            snprintf(a, sizeof a, "%g", o->times[i]);
            snprintf(b, sizeof b, "%g", o->times[j]);
            if (!strcmp(a, b))
                st = ss_error_set(err, SS_ERR_INPUT,
                                  "--times: %.15g and %.15g both name the frame t%s; give times "
                                  "that differ within 6 significant digits",
                                  o->times[j], o->times[i], a);
        }
    return st ? (int)st : 0;
}

/* A time as people say it: minutes under an hour, hours under two days. */
static void human_time(double day, char *buf, size_t n) {
    double min = day * 1440.0;
    if (min < 59.5)
        snprintf(buf, n, "%.0f min", min);
    else if (day < 2.0)
        snprintf(buf, n, "%.1f h", day * 24.0);
    else
        snprintf(buf, n, "day %.4g", day);
}

/* The four maps of a set, written in parallel (PNG encoding is serial per
 * file). Colour is sRGB 8-bit; height 16-bit (displacement needs the steps);
 * reflection and normal 8-bit linear, as engines expect them. */
static ss_status write_set(const char *dir, const char *stem, const ss_texture_set *t, int exr,
                           cJSON *files, ss_error *err) {
    static const char *names[4] = {"color", "reflection", "height", "normal"};
    static const int bits[4] = {8, 8, 16, 8};
    const ss_image *imgs[4] = {t->color, t->reflection, t->height, t->normal};
    ss_error errs[8];
    ss_status sts[8] = {0};
    /* k < 4: the PNGs; k >= 4 with --exr: the same maps as half-float EXR
     * (linear, colour included), for compositing and displacement. */
#pragma omp parallel for schedule(dynamic, 1)
    for (int k = 0; k < (exr ? 8 : 4); k++) {
        char path[4096];
        int m = k % 4;
        snprintf(path, sizeof path, "%s/%s_%s.%s", dir, stem, names[m], k < 4 ? "png" : "exr");
        sts[k] = k < 4 ? ss_png_write(path, imgs[m], bits[m], m == 0 ? SS_ENC_SRGB : SS_ENC_LINEAR,
                                      &errs[k])
                       : ss_exr_write(path, imgs[m], 1, &errs[k]);
    }
    for (int k = 0; k < (exr ? 8 : 4); k++) {
        if (sts[k]) {
            *err = errs[k];
            return sts[k];
        }
        char rel[512], key[32];
        snprintf(rel, sizeof rel, "%s_%s.%s", stem, names[k % 4], k < 4 ? "png" : "exr");
        snprintf(key, sizeof key, "%s%s", names[k % 4], k < 4 ? "" : "_exr");
        if (files) cJSON_AddStringToObject(files, key, rel);
    }
    return SS_OK;
}

/* The frame as a glTF square: a metal-rough texture from the reflection
 * map, and the .gltf referencing the colour, metal-rough and normal PNGs. */
static ss_status write_gltf(const char *dir, const char *stem, const ss_texture_set *t,
                            double world_cm, cJSON *files, ss_error *err) {
    ss_image *mr = ss_image_create_uninit(t->reflection->width, t->reflection->height, 3, err);
    if (!mr) return err->code;
    char path[4096], rel[512], gl[512];
    ss_status st = ss_reflection_to_metal_rough(t->reflection, mr, err);
    snprintf(rel, sizeof rel, "%s_metal_rough.png", stem);
    snprintf(path, sizeof path, "%s/%s", dir, rel);
    if (!st) st = ss_png_write(path, mr, 8, SS_ENC_LINEAR, err);
    ss_image_free(mr);
    if (st) return st;
    cJSON_AddStringToObject(files, "metal_rough", rel);
    /* URIs are relative to the .gltf, which sits in the same folder. */
    const char *base = strrchr(stem, '/') ? strrchr(stem, '/') + 1 : stem;
    char col[256], mrn[256], nrm[256];
    snprintf(col, sizeof col, "%s_color.png", base);
    snprintf(mrn, sizeof mrn, "%s_metal_rough.png", base);
    snprintf(nrm, sizeof nrm, "%s_normal.png", base);
    snprintf(gl, sizeof gl, "%s.gltf", stem);
    snprintf(path, sizeof path, "%s/%s", dir, gl);
    st = ss_gltf_write_textured_square(path, world_cm / 100.0, base, col, mrn, nrm, err);
    if (!st) cJSON_AddStringToObject(files, "gltf", gl);
    return st;
}

typedef struct inputs {
    ss_stroke_set strokes;
    ss_image *mask, *upper, *lower;
    ss_timeline timeline;
} inputs;

static void inputs_free(inputs *in) {
    ss_stroke_set_free(&in->strokes);
    ss_image_free(in->mask);
    ss_image_free(in->upper);
    ss_image_free(in->lower);
}

static ss_status read_inputs(const opts *o, inputs *in, ss_error *err) {
    memset(in, 0, sizeof *in);
    ss_status st = SS_OK;
    if (o->mask) {
        in->mask = ss_image_read(o->mask, SS_ENC_LINEAR, err);
        if (!in->mask) return err->code;
    } else if (o->stroke) {
        st = ss_stroke_csv_read(o->stroke, &in->strokes, err);
    } else {
        st = ss_abrasion_example_strokes(&in->strokes, err);
    }
    if (!st && o->upper && !(in->upper = ss_image_read(o->upper, SS_ENC_SRGB, err))) st = err->code;
    if (!st && o->lower && !(in->lower = ss_image_read(o->lower, SS_ENC_SRGB, err))) st = err->code;
    ss_timeline_default(&in->timeline);
    if (!st && o->timeline) st = ss_timeline_load_json(o->timeline, &in->timeline, err);
    return st;
}

/* Inputs read and checked, the shape built: everything that can be bad
 * input, before any output is touched. */
static ss_status prepare(const opts *o, inputs *in, ss_wound_shape **shape, ss_error *err) {
    ss_status st = read_inputs(o, in, err);
    *shape = NULL;
    /* Memory: five key sets and a frame (32 bytes a pixel each), the base
     * skin (48: linear and sRGB copies), the shape (12) and scratch; refuse what cannot fit. */
    double need = (double)o->size * (double)o->size * (6 * 32.0 + 48 + 12 + 16);
    double phys = ss_memory_physical_bytes();
    if (!st && phys > 0 && need > 0.8 * phys)
        st = ss_error_set(err, SS_ERR_INPUT,
                          "--size %d needs about %.1f GB, more than this machine's %.1f GB; "
                          "use a smaller --size",
                          o->size, need / 1e9, phys / 1e9);
    if (!st) {
        if (in->mask)
            st = ss_wound_shape_from_mask(in->mask, o->size, o->seed, shape, err);
        else
            st = ss_wound_shape_from_strokes(&in->strokes, o->hull, o->concave_k, o->size, o->seed,
                                             shape, err);
        if (st && (o->stroke || o->mask)) { /* name the file the shape came from */
            ss_error e2 = *err;
            ss_error_set(err, st, "%s: %s", o->stroke ? o->stroke : o->mask, e2.msg);
        }
    }
    return st;
}

/* Disk the outputs will take, generously: half the raw pixel bytes of every
 * map (keys for each of the five phases, every frame), of the contact sheet
 * (256-px tiles, 8 a row, as drawn below) and timeline.json. The procedural
 * maps compress to about 15% of raw (11 MB for 1024 px and three times),
 * photographs given as --upper to about 60%; a run that still outgrows the
 * estimate fails with the old output intact. */
static double estimate_bytes(const opts *o) {
    double px = (double)o->size * (double)o->size;
    double set = px * (3 + 1 + 2 + 3) + 4096;
    if (o->exr) set += px * (6 + 2 + 2 + 6) + 4096;
    double frame = set + (o->gltf ? px * 3 + 8192 : 0);
    int cols = o->ntimes < 8 ? o->ntimes : 8, rows = (o->ntimes + 7) / 8;
    double sheet = (cols * 276.0 + 20) * (rows * 320.0 + 20) * 3;
    return 0.5 * (5 * set + o->ntimes * frame + sheet) + 4096.0 * (o->ntimes + 4);
}

static ss_status render(const opts *o, inputs *in, const ss_wound_shape *shape, const char *dir,
                        cJSON *summary, ss_error *err) {
    ss_status st = SS_OK;
    ss_base_skin skin = {0};
    ss_abrasion *ab = NULL;
    ss_texture_set frame = {0};
    ss_image **thumbs = NULL;
    char **labels = NULL;
    ss_abrasion_settings set;
    ss_abrasion_settings_default(&set);
    set.size = o->size;
    set.world_size_cm = o->world_cm;
    set.seed = o->seed;
    ss_progress prog;
    double t0 = ss_now();
    /* Inputs are good: from here on, failures are runtime errors. */
    if (!st) st = ss_base_skin_create(in->upper, in->lower, o->size, o->seed, &skin, err);
    if (!st) {
        ss_progress_begin(&prog, "key positions", 1, o->quiet);
        st = ss_abrasion_create(&set, &in->timeline, shape, &skin, &ab, err);
        ss_progress_end(&prog);
    }
    double t_keys = ss_now() - t0;
    char sub[4096];
    if (!st) {
        snprintf(sub, sizeof sub, "%s/keys", dir);
        st = ss_mkdir_p(sub, err);
    }
    cJSON *keys = cJSON_AddArrayToObject(summary, "keys");
    for (int i = 0; i < in->timeline.nkeys && !st; i++) {
        ss_phase ph = in->timeline.key[i].phase;
        cJSON *k = cJSON_CreateObject();
        cJSON_AddItemToArray(keys, k);
        cJSON_AddStringToObject(k, "phase", ss_phase_name(ph));
        cJSON_AddNumberToObject(k, "day", in->timeline.key[i].day);
        cJSON *files = cJSON_AddObjectToObject(k, "files");
        char stem[128];
        snprintf(stem, sizeof stem, "keys/%s", ss_phase_name(ph));
        if (i > 0) {
            int seen = 0;
            for (int j = 0; j < i; j++) seen |= in->timeline.key[j].phase == ph;
            if (seen) { /* a double key outputs the same textures */
                static const char *names[4] = {"color", "reflection", "height", "normal"};
                for (int c = 0; c < 4; c++) {
                    char rel[256];
                    snprintf(rel, sizeof rel, "%s_%s.png", stem, names[c]);
                    cJSON_AddStringToObject(files, names[c], rel);
                }
                continue;
            }
        }
        st = write_set(dir, stem, &ab->phase[ph], o->exr, files, err);
    }
    cJSON_AddNumberToObject(summary, "end_day", in->timeline.end_day);
    if (!st) {
        snprintf(sub, sizeof sub, "%s/frames", dir);
        st = ss_mkdir_p(sub, err);
    }
    if (!st) st = ss_texture_set_create(o->size, &frame, err);
    thumbs = calloc((size_t)o->ntimes, sizeof *thumbs);
    labels = calloc((size_t)o->ntimes, sizeof *labels);
    if (!thumbs || !labels) st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    cJSON *frames = cJSON_AddArrayToObject(summary, "frames");
    if (!st) ss_progress_begin(&prog, "frames", o->ntimes, o->quiet);
    for (int i = 0; i < o->ntimes && !st; i++) {
        double day = o->times[i];
        st = ss_abrasion_frame(ab, day, &frame, err);
        if (st) break;
        char stem[128];
        snprintf(stem, sizeof stem, "frames/t%g", day);
        cJSON *f = cJSON_CreateObject();
        cJSON_AddItemToArray(frames, f);
        cJSON_AddNumberToObject(f, "day", day);
        ss_timeline_pos p = ss_timeline_locate(&in->timeline, day);
        if (p.in_maturation) {
            cJSON_AddStringToObject(f, "phase", "maturation");
            cJSON_AddNumberToObject(f, "maturation_position", p.maturation_pos);
        } else {
            cJSON_AddStringToObject(f, "from", ss_phase_name(in->timeline.key[p.key_a].phase));
            cJSON_AddStringToObject(f, "to", ss_phase_name(in->timeline.key[p.key_b].phase));
            cJSON_AddNumberToObject(f, "weight", p.weight);
        }
        cJSON *files = cJSON_AddObjectToObject(f, "files");
        st = write_set(dir, stem, &frame, o->exr, files, err);
        if (!st && o->gltf) st = write_gltf(dir, stem, &frame, o->world_cm, files, err);
        if (!st)
            thumbs[i] = ss_image_resize(frame.color, 512 < o->size ? 512 : o->size,
                                        512 < o->size ? 512 : o->size, err);
        if (!st && !thumbs[i]) st = err->code;
        if (!st) {
            char buf[64];
            human_time(day, buf, sizeof buf);
            labels[i] = strdup(buf);
        }
        ss_progress_update(&prog, i + 1);
    }
    if (!st) ss_progress_end(&prog);
    if (!st) {
        ss_image *sheet =
            ss_contact_sheet((const ss_image *const *)thumbs, (const char *const *)labels,
                             o->ntimes, 256, o->ntimes <= 8 ? o->ntimes : 8, err);
        if (!sheet)
            st = err->code;
        else {
            snprintf(sub, sizeof sub, "%s/contact_sheet.png", dir);
            st = ss_png_write(sub, sheet, 8, SS_ENC_SRGB, err);
            ss_image_free(sheet);
        }
    }
    if (!st) {
        cJSON_AddNumberToObject(summary, "size", o->size);
        cJSON_AddNumberToObject(summary, "world_size_cm", o->world_cm);
        cJSON_AddNumberToObject(summary, "seed", (double)o->seed);
        cJSON_AddNumberToObject(summary, "wounds", shape->nwounds);
        cJSON_AddNumberToObject(summary, "key_render_ms", t_keys * 1e3);
        cJSON_AddNumberToObject(summary, "total_ms", (ss_now() - t0) * 1e3);
        char *text = cJSON_Print(summary);
        snprintf(sub, sizeof sub, "%s/timeline.json", dir);
        st = text ? ss_write_file_atomic(sub, text, strlen(text), err)
                  : ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        free(text);
    }
    for (int i = 0; thumbs && i < o->ntimes; i++) ss_image_free(thumbs[i]);
    for (int i = 0; labels && i < o->ntimes; i++) free(labels[i]);
    free(thumbs);
    free(labels);
    ss_texture_set_free(&frame);
    ss_abrasion_free(ab);
    ss_base_skin_free(&skin);
    return st;
}

int cmd_abrasion(int argc, char **argv) {
    opts o;
    ss_error err;
    ss_error_clear(&err);
    int rc = parse(argc, argv, &o, &err);
    if (rc < 0) return 0; /* --help */
    if (rc) {
        free(o.times);
        return cli_usage_error(CMD, "%s", err.msg);
    }
    ss_threads_set(o.threads);
    cJSON *summary = cJSON_CreateObject();
    /* The output folder: checked now, staged by begin, swapped in whole by
     * finish (src/core/output.c). */
    inputs in;
    memset(&in, 0, sizeof in);
    ss_wound_shape *shape = NULL;
    ss_outputs *outs = ss_outputs_create(CMD, &err);
    ss_status st = outs ? SS_OK : SS_ERR_NOMEM;
    const char *ins[] = {o.stroke, o.mask, o.upper, o.lower, o.timeline};
    for (size_t k = 0; k < sizeof ins / sizeof *ins && !st; k++)
        st = ss_outputs_input(outs, ins[k], &err);
    if (!st) st = ss_outputs_add(outs, "--out", o.out, SS_OUTPUT_DIR, estimate_bytes(&o), &err);
    if (!st) st = prepare(&o, &in, &shape, &err);
    if (!st) st = ss_outputs_begin(outs, &err);
    if (!st) st = render(&o, &in, shape, ss_outputs_path(outs, 0), summary, &err);
    st = ss_outputs_finish(outs, st, &err);
    ss_outputs_free(outs);
    ss_wound_shape_free(shape);
    inputs_free(&in);
    if (!st && o.json) {
        cJSON_AddStringToObject(summary, "out", o.out);
        char *text = cJSON_PrintUnformatted(summary);
        if (text) printf("%s\n", text);
        free(text);
    } else if (!st && !o.quiet) {
        fprintf(stderr, "wrote %s (contact sheet: %s/contact_sheet.png)\n", o.out, o.out);
    }
    cJSON_Delete(summary);
    free(o.times);
    return st ? cli_fail(CMD, &err) : 0;
}
