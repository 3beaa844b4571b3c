/* skinsim skin: procedural skin textures from biological features (seed 003
 * §4.8, §5). Parses options, reads the fields, the table and an optional
 * feature list, calls the skin library (generate, bio maps, render maps) and
 * writes the texture set into a folder that appears whole or not at all.
 * Every input is read and checked before any output is touched. */
#define _POSIX_C_SOURCE 200809L
#include <cjson/cJSON.h>
#include <getopt.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "skinsim/geom.h"
#include "skinsim/mesh.h"
#include "skinsim/skin.h"

static const char *CMD = "skin";

static void help(FILE *f) {
    fprintf(f, "usage: skinsim skin [options]\n\n"
               "Procedural skin textures (seed 003 §4.8, §5): cysts, moles, freckles, wrinkles\n"
               "and hair follicles scattered by probability fields over a baseline skin, lips\n"
               "from a field, turned into biological parameters per texel and through the\n"
               "ModelMatch table into render maps. Lengths in mm; see docs/skin.md.\n\n"
               "Skin:\n"
               "  --preset NAME         forearm (default: counts per cm^2 of a forearm, 5 cm)\n"
               "                        or seed (the seed's 5000 cysts, 700 moles, 3000\n"
               "                        freckles, 170000 follicles, 1000 wrinkles on 20 cm)\n"
               "  --count TYPE=N        features of a type: cysts, moles, freckles, wrinkles,\n"
               "                        follicles (repeatable; N >= 0)\n"
               "  --field TYPE=FILE     greyscale probability field (PNG or EXR, any size,\n"
               "                        stretched over the texture; colour images are read as\n"
               "                        luminance) for a feature type, or lips=FILE (lip\n"
               "                        weight), or vectors=FILE (RGB wrinkle vector field:\n"
               "                        R,G direction with 0.5 = 0, B length; wrinkles and the\n"
               "                        microrelief follow it, and wrinkles.cross_deg rotates\n"
               "                        every other wrinkle only when --param sets it), or the\n"
               "                        surface state: hydration=FILE, sebum=FILE (0..1,\n"
               "                        default: surface.hydration, surface.sebum), scar=FILE\n"
               "                        (mask: smooth, shiny, paler, no microrelief)\n"
               "  --param NAME=V        a distribution constant, e.g. moles.r_sigma=1.5\n"
               "                        (--list-params prints them with their values)\n"
               "  --base NAME=LO        low end of a baseline parameter: melanin, pheomelanin,\n"
               "                        blood, oxygenation, sc (cm), epidermis (cm)\n"
               "  --features-in FILE    render this features.csv instead of generating\n"
               "  --sampler NAME        alias (default, exact and fast) or rejection (the\n"
               "                        seed's ChoosePoint loop; same distribution)\n"
               "  --no-wrap             features do not wrap around the edges (for meshes\n"
               "                        with UV islands); default: the texture is a torus\n"
               "                        and the maps tile seamlessly\n\n");
    fprintf(f,
            "Output:\n"
            "  --size N              texture side in texels (default 2048, 8..16384)\n"
            "  --world-size-cm X     side of the texture on the body (default: preset's)\n"
            "  --table FILE          ModelMatch table (default data/modelmatch_default.sstab)\n"
            "  --normal-convention C opengl (default, +Y up) or directx (green flipped)\n"
            "  --seed S              random seed (default 1); bit-identical for any threads\n"
            "  --gltf                also write skin.gltf: the material on a square of the\n"
            "                        world size\n"
            "  --mesh FILE           with --gltf: the material on this mesh's UVs instead\n"
            "                        (OBJ, glTF or GLB, e.g. data/meshes/generic-hand-left.glb;\n"
            "                        --no-wrap suits UV islands)\n"
            "  --pad N               with --mesh: texels outside the UV islands, within N\n"
            "                        texels of one, take the nearest island texel's value\n"
            "                        in every map (edge dilation for filtering and mipmaps;\n"
            "                        default 0, 0..256)\n"
            "  --no-bio              do not write bio.exr (the slowest file)\n"
            "  --bio-float           bio.exr in float32 (default half: 3 significant\n"
            "                        digits, a quarter of the size and of the time)\n"
            "  --out DIR             output folder (default skin-out)\n"
            "  --threads N, --quiet, --json, --list-params, --help\n\n"
            "Writes DIR/base_color.png (sRGB), roughness.png, specular.png (GGX, linear\n"
            "8-bit), height.png (16-bit; 0..1 spans skin.json's height_min_mm..max_mm),\n"
            "normal.png, translucency.png (subsurface radius R,G,B, linear, 1 = 2 mm),\n"
            "cavity.png (1 open, 0 deep in a furrow), bio.exr (half channels: melanin,\n"
            "pheomelanin_ratio, blood, oxygenation, sc_thickness_cm,\n"
            "epidermis_thickness_cm, height_mm, extra.R/G/B/A, surface_roughness;\n"
            "ZIP-compressed), features.csv, contact_sheet.png and skin.json. With\n"
            "--gltf the material always points at an OpenGL (+Y) normal map\n"
            "(normal_gl.png when --normal-convention directx).\n\n"
            "Example:\n"
            "  skinsim skin --preset seed --field follicles=data/skin_face/follicles.png \\\n"
            "      --field lips=data/skin_face/lips.png --out face\n");
}

#define MAX_FIELDS 16
typedef struct opts {
    const char *out, *table, *features_in, *preset, *mesh;
    const char *field_name[MAX_FIELDS], *field_path[MAX_FIELDS];
    int nfields;
    char *counts[64], *params[64], *bases[16];
    int ncounts, nparams, nbases;
    int size, threads, quiet, json, gltf, no_wrap, directx, sampler, list_params, no_bio, bio_float,
        pad;
    double world_cm;
    int world_set;
    uint64_t seed;
} opts;

static ss_status split_kv(const char *opt, const char *s, char *key, size_t keylen,
                          const char **val, ss_error *err) {
    const char *eq = strchr(s, '=');
    if (!eq || eq == s || !eq[1] || (size_t)(eq - s) >= keylen)
        return ss_error_set(err, SS_ERR_INPUT, "%s '%s': expected NAME=VALUE", opt, s);
    memcpy(key, s, (size_t)(eq - s));
    key[eq - s] = '\0';
    *val = eq + 1;
    return SS_OK;
}

static int parse(int argc, char **argv, opts *o, ss_error *err) {
    static const struct option longopts[] = {{"out", required_argument, 0, 'o'},
                                             {"size", required_argument, 0, 'n'},
                                             {"preset", required_argument, 0, 'P'},
                                             {"count", required_argument, 0, 'c'},
                                             {"field", required_argument, 0, 'f'},
                                             {"param", required_argument, 0, 'p'},
                                             {"base", required_argument, 0, 'b'},
                                             {"features-in", required_argument, 0, 'F'},
                                             {"sampler", required_argument, 0, 'A'},
                                             {"no-wrap", no_argument, 0, 'W'},
                                             {"world-size-cm", required_argument, 0, 'w'},
                                             {"table", required_argument, 0, 'T'},
                                             {"normal-convention", required_argument, 0, 'N'},
                                             {"seed", required_argument, 0, 'S'},
                                             {"gltf", no_argument, 0, 'G'},
                                             {"mesh", required_argument, 0, 'M'},
                                             {"no-bio", no_argument, 0, 'B'},
                                             {"bio-float", no_argument, 0, 'X'},
                                             {"pad", required_argument, 0, 'D'},
                                             {"threads", required_argument, 0, 'j'},
                                             {"quiet", no_argument, 0, 'q'},
                                             {"json", no_argument, 0, 'J'},
                                             {"list-params", no_argument, 0, 'L'},
                                             {"help", no_argument, 0, 'h'},
                                             {0, 0, 0, 0}};
    memset(o, 0, sizeof *o);
    o->out = "skin-out";
    o->size = 2048;
    o->seed = 1;
    o->preset = "forearm";
    optind = 1;
    opterr = 0;
    int c;
    long v;
    ss_status st = SS_OK;
    while (!st && (c = getopt_long(argc, argv, "", longopts, NULL)) != -1) {
        switch (c) {
        case 'o':
            o->out = optarg;
            break;
        case 'n':
            st = cli_parse_int("--size", optarg, 8, 16384, &v, err);
            o->size = (int)v;
            break;
        case 'P':
            o->preset = optarg;
            break;
        case 'c':
            if (o->ncounts >= 64)
                st = ss_error_set(err, SS_ERR_INPUT, "--count: too many");
            else
                o->counts[o->ncounts++] = optarg;
            break;
        case 'p':
            if (o->nparams >= 64)
                st = ss_error_set(err, SS_ERR_INPUT, "--param: too many");
            else
                o->params[o->nparams++] = optarg;
            break;
        case 'b':
            if (o->nbases >= 16)
                st = ss_error_set(err, SS_ERR_INPUT, "--base: too many");
            else
                o->bases[o->nbases++] = optarg;
            break;
        case 'f': {
            const char *eq = strchr(optarg, '=');
            if (!eq || eq == optarg || !eq[1])
                st = ss_error_set(err, SS_ERR_INPUT, "--field '%s': expected TYPE=FILE", optarg);
            else if (o->nfields >= MAX_FIELDS)
                st = ss_error_set(err, SS_ERR_INPUT, "--field: too many");
            else {
                char *name = strndup(optarg, (size_t)(eq - optarg));
                o->field_name[o->nfields] = name;
                o->field_path[o->nfields++] = eq + 1;
            }
            break;
        }
        case 'F':
            o->features_in = optarg;
            break;
        case 'A':
            if (!strcmp(optarg, "alias"))
                o->sampler = SS_SAMPLER_ALIAS;
            else if (!strcmp(optarg, "rejection"))
                o->sampler = SS_SAMPLER_REJECTION;
            else
                st = ss_error_set(err, SS_ERR_INPUT, "--sampler: '%s' is not alias or rejection",
                                  optarg);
            break;
        case 'W':
            o->no_wrap = 1;
            break;
        case 'w':
            st = cli_parse_double("--world-size-cm", optarg, 1e-3, 1e4, &o->world_cm, err);
            o->world_set = 1;
            break;
        case 'T':
            o->table = optarg;
            break;
        case 'N':
            if (!strcmp(optarg, "opengl"))
                o->directx = 0;
            else if (!strcmp(optarg, "directx"))
                o->directx = 1;
            else
                st = ss_error_set(err, SS_ERR_INPUT,
                                  "--normal-convention: '%s' is not opengl or directx", optarg);
            break;
        case 'S':
            st = cli_parse_u64("--seed", optarg, &o->seed, err);
            break;
        case 'G':
            o->gltf = 1;
            break;
        case 'M':
            o->mesh = optarg;
            break;
        case 'B':
            o->no_bio = 1;
            break;
        case 'X':
            o->bio_float = 1;
            break;
        case 'D':
            st = cli_parse_int("--pad", optarg, 0, 256, &v, err);
            o->pad = (int)v;
            break;
        case 'j':
            st = cli_parse_int("--threads", optarg, 1, SS_THREADS_MAX, &v, err);
            o->threads = (int)v;
            break;
        case 'q':
            o->quiet = 1;
            break;
        case 'J':
            o->json = 1;
            break;
        case 'L':
            o->list_params = 1;
            break;
        case 'h':
            help(stdout);
            return -1;
        default:
            st =
                cli_unknown_option_set(err, "unknown or incomplete option", argv[optind - 1], help);
        }
    }
    if (!st && optind < argc)
        st = ss_error_set(err, SS_ERR_INPUT, "unexpected argument '%s'", argv[optind]);
    if (!st && o->mesh && !o->gltf)
        st = ss_error_set(err, SS_ERR_INPUT, "--mesh needs --gltf (the mesh is only used there)");
    if (!st && o->pad > 0 && !o->mesh)
        st = ss_error_set(err, SS_ERR_INPUT, "--pad needs --mesh (the UV islands to pad)");
    return st ? (int)st : 0;
}

static void opts_free(opts *o) {
    for (int i = 0; i < o->nfields; i++) free((char *)o->field_name[i]);
}

/* Settings from the preset and the options. */
static ss_status make_settings(const opts *o, ss_skin_settings *s, ss_error *err) {
    ss_status st = ss_skin_settings_preset(s, o->preset, o->size, err);
    if (st) return st;
    s->seed = o->seed;
    s->wrap = !o->no_wrap;
    s->sampler = o->sampler;
    if (o->world_set) {
        s->world_size_cm = o->world_cm;
        if (!strcmp(o->preset, "forearm")) ss_skin_forearm_counts(o->world_cm, s->count);
    }
    char key[128];
    const char *val;
    for (int i = 0; i < o->ncounts && !st; i++) {
        st = split_kv("--count", o->counts[i], key, sizeof key, &val, err);
        if (st) break;
        int t = ss_feature_type_from_name(key);
        if (t < 0) {
            st = ss_error_set(err, SS_ERR_INPUT,
                              "--count: unknown feature '%s' (cysts, moles, freckles, wrinkles, "
                              "follicles)",
                              key);
            break;
        }
        long n;
        st = cli_parse_int("--count", val, 0, 100000000L, &n, err);
        s->count[t] = n;
    }
    for (int i = 0; i < o->nparams && !st; i++) {
        st = split_kv("--param", o->params[i], key, sizeof key, &val, err);
        double x;
        if (!st) st = cli_parse_double("--param", val, -1e9, 1e9, &x, err);
        if (!st) st = ss_skin_dist_set(&s->dist, key, x, err);
        /* asked for on the command line: the crossing also applies with a
         * user's vector field (docs/skin.md) */
        if (!st && !strcmp(key, "wrinkles.cross_deg")) s->dist.wrinkle_cross_with_field = 1.0;
    }
    static const char *const base_names[6] = {"melanin",     "pheomelanin", "blood",
                                              "oxygenation", "sc",          "epidermis"};
    for (int i = 0; i < o->nbases && !st; i++) {
        st = split_kv("--base", o->bases[i], key, sizeof key, &val, err);
        if (st) break;
        int a = -1;
        for (int k = 0; k < 6; k++)
            if (!strcmp(key, base_names[k])) a = k;
        if (a < 0) {
            st = ss_error_set(err, SS_ERR_INPUT,
                              "--base: unknown parameter '%s' (melanin, pheomelanin, blood, "
                              "oxygenation, sc, epidermis)",
                              key);
            break;
        }
        double x;
        st = cli_parse_double("--base", val, 0.0, a >= 4 ? 0.1 : 1.0, &x, err);
        if (!st && x > s->base_hi[a])
            st = ss_error_set(err, SS_ERR_INPUT, "--base %s=%g: above the range's top %g", key, x,
                              s->base_hi[a]);
        if (!st) s->base_lo[a] = x;
    }
    if (!st) st = ss_skin_settings_validate(s, err);
    return st;
}

typedef struct inputs {
    ss_image *img[MAX_FIELDS];
    ss_skin_fields fields;
    ss_mm_table *table;
    ss_skin_feature_list features;
    int have_features;
    ss_mesh mesh;
    char table_path[4096];
} inputs;

static void inputs_free(inputs *in) {
    for (int i = 0; i < MAX_FIELDS; i++) ss_image_free(in->img[i]);
    ss_mm_table_free(in->table);
    ss_skin_feature_list_free(&in->features);
    ss_mesh_free(&in->mesh);
}

/* A probability field: PNG/EXR, colour converted to luminance (said in notes). */
static ss_image *read_grey(const char *name, const char *path, cJSON *notes, ss_error *err) {
    ss_error e2;
    ss_image *img = ss_image_read(path, SS_ENC_LINEAR, &e2);
    if (!img) {
        ss_error_set(err, e2.code, "--field %s: %s", name, e2.msg);
        return NULL;
    }
    if (img->channels == 1) return img;
    ss_image *g = ss_image_create_uninit(img->width, img->height, 1, err);
    if (!g) {
        ss_image_free(img);
        return NULL;
    }
    size_t n = (size_t)img->width * img->height;
    for (size_t i = 0; i < n; i++) {
        const float *p = img->data + i * (size_t)img->channels;
        g->data[i] = img->channels >= 3 ? 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2] : p[0];
    }
    if (img->channels >= 3) {
        char msg[600];
        snprintf(msg, sizeof msg,
                 "%s: colour image read as luminance (0.2126 R + 0.7152 G + "
                 "0.0722 B)",
                 path);
        cJSON_AddItemToArray(notes, cJSON_CreateString(msg));
    }
    ss_image_free(img);
    return g;
}

static ss_status read_inputs(const opts *o, inputs *in, cJSON *notes, ss_error *err) {
    memset(in, 0, sizeof *in);
    ss_status st = SS_OK;
    for (int i = 0; i < o->nfields && !st; i++) {
        const char *name = o->field_name[i], *path = o->field_path[i];
        if (!strcmp(name, "vectors")) {
            ss_error e2;
            in->img[i] = ss_image_read(path, SS_ENC_LINEAR, &e2);
            if (!in->img[i])
                st = ss_error_set(err, e2.code, "--field vectors: %s", e2.msg);
            else if (in->img[i]->channels < 3)
                st = ss_error_set(err, SS_ERR_INPUT,
                                  "--field vectors: %s is greyscale; the wrinkle vector field "
                                  "needs RGB (R, G direction, B length)",
                                  path);
            else
                in->fields.wrinkle_vectors = in->img[i];
            continue;
        }
        int t = ss_feature_type_from_name(name);
        int surf = !strcmp(name, "hydration") ? 1
                   : !strcmp(name, "sebum")   ? 2
                   : !strcmp(name, "scar")    ? 3
                                              : 0;
        if (t < 0 && !surf && strcmp(name, "lips")) {
            st = ss_error_set(err, SS_ERR_INPUT,
                              "--field: unknown name '%s' (cysts, moles, freckles, wrinkles, "
                              "follicles, lips, vectors, hydration, sebum, scar)",
                              name);
            break;
        }
        in->img[i] = read_grey(name, path, notes, err);
        if (!in->img[i]) {
            st = err->code;
            break;
        }
        size_t n = (size_t)in->img[i]->width * in->img[i]->height;
        for (size_t k = 0; k < n; k++)
            if (!isfinite(in->img[i]->data[k])) {
                st = ss_error_set(err, SS_ERR_INPUT, "--field %s: %s has a non-finite value", name,
                                  path);
                break;
            }
        if (st) break;
        if (in->img[i]->width != o->size || in->img[i]->height != o->size) {
            char msg[600];
            snprintf(msg, sizeof msg, "%s: %dx%d field stretched over the %dx%d texture", path,
                     in->img[i]->width, in->img[i]->height, o->size, o->size);
            cJSON_AddItemToArray(notes, cJSON_CreateString(msg));
        }
        if (surf == 1)
            in->fields.hydration = in->img[i];
        else if (surf == 2)
            in->fields.sebum = in->img[i];
        else if (surf == 3)
            in->fields.scar = in->img[i];
        else if (t < 0)
            in->fields.lips = in->img[i];
        else
            in->fields.density[t] = in->img[i];
    }
    if (!st) {
        if (o->table)
            snprintf(in->table_path, sizeof in->table_path, "%s", o->table);
        else
            snprintf(in->table_path, sizeof in->table_path, "%s/modelmatch_default.sstab",
                     ss_data_dir());
        ss_error e2;
        in->table = ss_mm_table_read(in->table_path, &e2);
        if (!in->table) st = ss_error_set(err, SS_ERR_INPUT, "--table: %s", e2.msg);
    }
    if (!st && o->mesh) {
        ss_error e2;
        st = ss_mesh_load(o->mesh, &in->mesh, &e2);
        if (st)
            ss_error_set(err, st, "--mesh: %s", e2.msg);
        else if (!in->mesh.has_uvs)
            st = ss_error_set(err, SS_ERR_INPUT, "--mesh: %s has no texture coordinates", o->mesh);
    }
    if (!st && o->features_in) {
        st = ss_skin_features_read_csv(o->features_in, &in->features, err);
        in->have_features = !st;
    }
    return st;
}

/* Writes the maps. Translucency and height are turned into what their
 * files hold in place (the contact sheet, written before, has read them):
 * translucency to the subsurface radius over 2 mm, clamped; height to
 * 0..1 over height_min_mm..height_max_mm for the 16-bit PNG. No full-size
 * copies (fresh memory costs page faults: 67 MB at 2048^2). */
static ss_status write_maps(const char *dir, ss_skin_maps *m, const ss_image *bio, int bio_half,
                            const ss_image *mr, const ss_image *normal_gl, ss_error *err) {
    enum { N = 10 };
    static const char *names[N] = {
        "base_color.png", "roughness.png",   "specular.png",     "height.png", "normal.png",
        "bio.exr",        "metal_rough.png", "translucency.png", "cavity.png", "normal_gl.png"};
    const size_t n = (size_t)m->height_mm->width * m->height_mm->height;
    double lo = m->height_min_mm, span = m->height_max_mm - m->height_min_mm;
    float *h = m->height_mm->data, *t = m->translucency->data;
#pragma omp parallel for schedule(static)
    for (size_t i = 0; i < n; i++) {
        h[i] = span > 0 ? (float)((h[i] - lo) / span) : 0.5f;
        /* subsurface radius: 1.0 = 2 mm (5 x the table's cm), clamped */
        for (int c = 0; c < 3; c++) {
            float v = t[i * 3 + c] * 5.0f;
            t[i * 3 + c] = v < 0.0f ? 0.0f : v > 1.0f ? 1.0f : v;
        }
    }
    const char *bio_names[SS_BIO_NCHANNELS];
    for (int c = 0; c < SS_BIO_NCHANNELS; c++) bio_names[c] = ss_bio_channel_name(c);
    ss_error errs[N];
    ss_status sts[N] = {0};
#pragma omp parallel for schedule(dynamic, 1)
    for (int k = 0; k < N; k++) {
        char path[4200];
        snprintf(path, sizeof path, "%s/%s", dir, names[k]);
        switch (k) {
        case 0:
            sts[k] = ss_png_write(path, m->base_color, 8, SS_ENC_SRGB, &errs[k]);
            break;
        case 1:
            sts[k] = ss_png_write(path, m->roughness, 8, SS_ENC_LINEAR, &errs[k]);
            break;
        case 2:
            sts[k] = ss_png_write(path, m->specular, 8, SS_ENC_LINEAR, &errs[k]);
            break;
        case 3:
            sts[k] = ss_png_write(path, m->height_mm, 16, SS_ENC_LINEAR, &errs[k]);
            break;
        case 4:
            sts[k] = ss_png_write(path, m->normal, 8, SS_ENC_LINEAR, &errs[k]);
            break;
        case 5:
            if (bio) sts[k] = ss_exr_write_channels(path, bio, bio_names, bio_half, &errs[k]);
            break;
        case 6:
            if (mr) sts[k] = ss_png_write(path, mr, 8, SS_ENC_LINEAR, &errs[k]);
            break;
        case 7:
            sts[k] = ss_png_write(path, m->translucency, 8, SS_ENC_LINEAR, &errs[k]);
            break;
        case 8:
            sts[k] = ss_png_write(path, m->cavity, 8, SS_ENC_LINEAR, &errs[k]);
            break;
        case 9:
            if (normal_gl) sts[k] = ss_png_write(path, normal_gl, 8, SS_ENC_LINEAR, &errs[k]);
            break;
        }
    }
    for (int k = 0; k < N; k++)
        if (sts[k]) {
            *err = errs[k];
            return sts[k];
        }
    return SS_OK;
}

/* How a map is shown on the contact sheet, texel by texel (mapped while
 * shrinking, ss_image_resize_mapped: no full-size display image). */
typedef struct {
    int ch;        /* the channel shown (grey maps) */
    double lo, hi; /* grey maps: the displayed range */
} sheet_map;

/* Grey: a 1-channel quantity onto 0..1 grey from mean - 4 sd to mean + 4 sd
 * (clamped to the data's range): a few tall cysts do not turn everything
 * else into one grey. Decoded, since the sheet encodes sRGB. */
static void map_grey(const float *texel, float *out, void *ctx) {
    const sheet_map *g = ctx;
    double v = g->hi > g->lo ? (texel[g->ch] - g->lo) / (g->hi - g->lo) : 0.5;
    out[0] = ss_srgb_decode((float)(v < 0 ? 0 : v > 1 ? 1 : v));
}
static sheet_map grey_range(const ss_image *src, int ch) {
    const int C = src->channels;
    size_t n = (size_t)src->width * src->height;
    double s1 = 0, s2 = 0, mn = INFINITY, mx = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        double v = src->data[i * C + ch];
        s1 += v, s2 += v * v;
        mn = fmin(mn, v), mx = fmax(mx, v);
    }
    double mean = s1 / n, sd = sqrt(fmax(0.0, s2 / n - mean * mean));
    return (sheet_map){ch, fmax(mn, mean - 4 * sd), fmin(mx, mean + 4 * sd)};
}
/* translucency: radius 0..2 mm, shown as stored in translucency.png */
static void map_radius(const float *texel, float *out, void *ctx) {
    (void)ctx;
    for (int c = 0; c < 3; c++) {
        float v = texel[c] * 5.0f;
        out[c] = ss_srgb_decode(v < 0.0f ? 0.0f : v > 1.0f ? 1.0f : v);
    }
}

/* A w x w crop of img at its centre (1:1 texels for the contact sheet). */
static ss_image *crop_centre(const ss_image *img, int w, ss_error *err) {
    if (w > img->width) w = img->width;
    if (w > img->height) w = img->height;
    ss_image *c = ss_image_create_uninit(w, w, img->channels, err);
    if (!c) return NULL;
    int x0 = (img->width - w) / 2, y0 = (img->height - w) / 2;
    for (int y = 0; y < w; y++)
        memcpy(ss_image_px(c, 0, y), ss_image_px(img, x0, y0 + y),
               (size_t)w * (size_t)img->channels * sizeof(float));
    return c;
}

/* All maps side by side: base colour (whole and a 1:1 crop), roughness,
 * specular, height, normal (1:1 crop: at a glance the whole map is flat
 * blue), melanin, blood, translucency, cavity (1:1 crop). Written before
 * write_maps turns height and translucency into their file values. */
static ss_status write_sheet(const char *dir, const ss_skin_maps *m, const ss_image *bio,
                             ss_error *err) {
    enum { N = 10 };
    const int S = m->base_color->width, T = S < 512 ? S : 512, CROP = S < 256 ? S : 256;
    ss_image *tiles[N] = {0};
    static const char *labels[N] = {"base colour",  "base colour 1:1", "roughness", "specular",
                                    "height",       "normal 1:1",      "melanin",   "blood",
                                    "translucency", "cavity 1:1"};
    ss_status st = SS_OK;
    for (int k = 0; k < N && !st; k++) {
        const ss_image *src = NULL, *grey = NULL;
        ss_image *own = NULL;
        int ch = 0;
        switch (k) {
        case 0:
            src = m->base_color;
            break;
        case 1:
            src = own = crop_centre(m->base_color, CROP, err);
            break;
        case 2:
            grey = m->roughness;
            break;
        case 3:
            grey = m->specular;
            break;
        case 4:
            grey = m->height_mm;
            break;
        case 5: /* the normal map's stored values, shown as they are */
            if ((src = own = crop_centre(m->normal, CROP, err))) {
                size_t nv = (size_t)own->width * own->height * 3;
                for (size_t i = 0; i < nv; i++) own->data[i] = ss_srgb_decode(own->data[i]);
            }
            break;
        case 6:
            grey = bio, ch = SS_BIO_MELANIN;
            break;
        case 7:
            grey = bio, ch = SS_BIO_BLOOD;
            break;
        case 8:
            tiles[k] = ss_image_resize_mapped(m->translucency, T, T, 3, map_radius, NULL, err);
            break;
        case 9:
            if ((src = own = crop_centre(m->cavity, CROP, err))) {
                size_t nc = (size_t)own->width * own->height;
                for (size_t i = 0; i < nc; i++) own->data[i] = ss_srgb_decode(own->data[i]);
            }
            break;
        }
        if (grey) {
            sheet_map g = grey_range(grey, ch);
            tiles[k] = ss_image_resize_mapped(grey, T, T, 1, map_grey, &g, err);
        } else if (src && src->width > T)
            tiles[k] = ss_image_resize(src, T, T, err);
        else if (own)
            tiles[k] = own, own = NULL;
        else if (src)
            tiles[k] = ss_image_clone(src, err);
        ss_image_free(own);
        if (!tiles[k]) st = err->code;
    }
    if (!st) {
        ss_image *sheet = ss_contact_sheet((const ss_image *const *)tiles, labels, N, 256, 5, err);
        if (!sheet)
            st = err->code;
        else {
            char path[4200];
            snprintf(path, sizeof path, "%s/contact_sheet.png", dir);
            st = ss_png_write(path, sheet, 8, SS_ENC_SRGB, err);
            ss_image_free(sheet);
        }
    }
    for (int k = 0; k < N; k++) ss_image_free(tiles[k]);
    return st;
}

/* --pad: texels outside the mesh's UV islands, within pad texels of one,
 * take the nearest island texel's value in every map and the bio map. */
static ss_status pad_maps(const ss_mesh *mesh, int pad, ss_skin_maps *m, ss_image *bio,
                          ss_error *err) {
    const int w = m->base_color->width, h = m->base_color->height;
    unsigned char *in = malloc((size_t)w * (size_t)h);
    if (!in) return ss_error_set(err, SS_ERR_NOMEM, "--pad: out of memory");
    ss_status st = ss_mesh_uv_coverage(mesh, w, h, in, err);
    ss_image *const all[] = {m->base_color, m->roughness, m->specular, m->translucency,
                             m->cavity,     m->height_mm, m->normal,   bio};
    for (size_t k = 0; !st && k < sizeof all / sizeof all[0]; k++)
        if (all[k]) st = ss_image_pad_islands(all[k], in, pad, err);
    free(in);
    return st;
}

static ss_status run(const opts *o, const ss_skin_settings *s, inputs *in, const char *dir,
                     cJSON *summary, cJSON *notes, ss_error *err) {
    ss_status st = SS_OK;
    ss_skin_timing tm = {0};
    ss_skin_lut *lut = NULL;
    ss_image *bio = NULL, *mr = NULL, *normal_gl = NULL;
    ss_skin_maps maps = {0};
    double t0 = ss_now();
    char note_buf[512] = "";
    if (!in->have_features)
        st = ss_skin_generate(s, &in->fields, &in->features, note_buf, sizeof note_buf, err);
    if (note_buf[0]) cJSON_AddItemToArray(notes, cJSON_CreateString(note_buf));
    tm.generate_s = ss_now() - t0;
    if (!st && !(bio = ss_skin_bio_maps_timed(s, &in->fields, &in->features, &tm, err)))
        st = err->code;
    if (!st && !(lut = ss_skin_lut_create(in->table, err))) st = err->code;
    double t1 = ss_now();
    /* rendered in the OpenGL convention; a DirectX normal.png is a flipped
     * copy, and the OpenGL map is kept for glTF (normal_gl.png) */
    if (!st) st = ss_skin_render_maps(bio, lut, s->world_size_cm, 0, &maps, err);
    if (!st && o->pad > 0) st = pad_maps(&in->mesh, o->pad, &maps, bio, err);
    tm.lookup_s = ss_now() - t1;
    double t2 = ss_now();
    if (!st && o->gltf) {
        if (!(mr = ss_image_create_uninit(s->size, s->size, 3, err))) st = err->code;
        for (size_t i = 0; !st && i < (size_t)s->size * s->size; i++) {
            mr->data[i * 3] = 1.0f;
            mr->data[i * 3 + 1] = maps.roughness->data[i];
            mr->data[i * 3 + 2] = 0.0f;
        }
    }
    /* glTF requires a +Y (OpenGL) normal map: with --normal-convention
     * directx the material gets its own OpenGL copy */
    if (!st && o->directx) {
        ss_image *dx = ss_image_clone(maps.normal, err);
        if (!dx) st = err->code;
        for (size_t i = 0; !st && i < (size_t)s->size * s->size; i++)
            dx->data[i * 3 + 1] = 1.0f - dx->data[i * 3 + 1];
        if (!st) {
            if (o->gltf)
                normal_gl = maps.normal; /* the OpenGL map, for glTF */
            else
                ss_image_free(maps.normal);
            maps.normal = dx;
        }
    }
    /* the sheet first: write_maps turns height and translucency into
     * their file values in place */
    if (!st) st = write_sheet(dir, &maps, bio, err);
    char path[4200];
    if (!st) {
        snprintf(path, sizeof path, "%s/features.csv", dir);
        st = ss_skin_features_write_csv(path, &in->features, err);
    }
    if (!st) st = write_maps(dir, &maps, o->no_bio ? NULL : bio, !o->bio_float, mr, normal_gl, err);
    const char *gl_normal = o->directx ? "normal_gl.png" : "normal.png";
    if (!st && o->gltf) {
        snprintf(path, sizeof path, "%s/skin.gltf", dir);
        if (o->mesh)
            st = ss_gltf_write_textured_mesh(path, &in->mesh, "skin", "base_color.png",
                                             "metal_rough.png", gl_normal, err);
        else
            st = ss_gltf_write_textured_square(path, s->world_size_cm / 100.0, "skin",
                                               "base_color.png", "metal_rough.png", gl_normal, err);
    }
    double t3 = ss_now();
    if (!st) {
        long cnt[SS_FEAT_NTYPES] = {0};
        for (size_t i = 0; i < in->features.n; i++) cnt[in->features.f[i].type]++;
        cJSON *c = cJSON_AddObjectToObject(summary, "counts");
        for (int t = 0; t < SS_FEAT_NTYPES; t++)
            cJSON_AddNumberToObject(c, ss_feature_type_name(t), (double)cnt[t]);
        cJSON_AddStringToObject(summary, "preset", o->preset);
        cJSON_AddNumberToObject(summary, "seed", (double)s->seed);
        cJSON_AddNumberToObject(summary, "size", s->size);
        cJSON_AddNumberToObject(summary, "world_size_cm", s->world_size_cm);
        cJSON_AddNumberToObject(summary, "texel_mm", s->world_size_cm * 10.0 / s->size);
        cJSON_AddStringToObject(summary, "length_unit", "mm");
        cJSON_AddBoolToObject(summary, "wrap", s->wrap);
        cJSON_AddStringToObject(summary, "sampler",
                                s->sampler == SS_SAMPLER_REJECTION ? "rejection" : "alias");
        cJSON_AddStringToObject(summary, "normal_convention", o->directx ? "directx" : "opengl");
        cJSON_AddBoolToObject(summary, "bio_exr", !o->no_bio);
        if (!o->no_bio)
            cJSON_AddStringToObject(summary, "bio_exr_type", o->bio_float ? "float" : "half");
        cJSON_AddStringToObject(summary, "table", in->table_path);
        cJSON_AddStringToObject(summary, "render_model", "ggx");
        cJSON_AddNumberToObject(summary, "height_min_mm", maps.height_min_mm);
        cJSON_AddNumberToObject(summary, "height_max_mm", maps.height_max_mm);
        if (o->features_in) cJSON_AddStringToObject(summary, "features_in", o->features_in);
        cJSON *ch = cJSON_AddArrayToObject(summary, "bio_channels");
        for (int k = 0; k < SS_BIO_NCHANNELS; k++)
            cJSON_AddItemToArray(ch, cJSON_CreateString(ss_bio_channel_name(k)));
        cJSON *ti = cJSON_AddObjectToObject(summary, "timings_ms");
        cJSON_AddNumberToObject(ti, "generate", tm.generate_s * 1e3);
        cJSON_AddNumberToObject(ti, "index", tm.index_s * 1e3);
        cJSON_AddNumberToObject(ti, "texels", tm.texels_s * 1e3);
        cJSON_AddNumberToObject(ti, "lookup_and_normals", tm.lookup_s * 1e3);
        cJSON_AddNumberToObject(ti, "write", (t3 - t2) * 1e3);
        cJSON *p = cJSON_AddObjectToObject(summary, "params");
        for (const char *const *nm = ss_skin_dist_names(); *nm; nm++)
            cJSON_AddNumberToObject(p, *nm, ss_skin_dist_get(&s->dist, *nm));
        cJSON_AddItemReferenceToObject(summary, "notes", notes);
        char *text = cJSON_Print(summary);
        cJSON_DeleteItemFromObject(summary, "notes");
        snprintf(path, sizeof path, "%s/skin.json", dir);
        st = text ? ss_write_file_atomic(path, text, strlen(text), err)
                  : ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        free(text);
    }
    ss_image_free(mr);
    ss_image_free(normal_gl);
    ss_skin_maps_free(&maps);
    ss_image_free(bio);
    ss_skin_lut_free(lut);
    return st;
}

int cmd_skin(int argc, char **argv) {
    opts o;
    ss_error err;
    ss_error_clear(&err);
    int rc = parse(argc, argv, &o, &err);
    if (rc < 0) {
        opts_free(&o);
        return 0;
    }
    if (rc) {
        opts_free(&o);
        return cli_usage_error(CMD, "%s", err.msg);
    }
    ss_skin_settings s;
    ss_status st = make_settings(&o, &s, &err);
    if (!st && o.list_params) {
        for (const char *const *nm = ss_skin_dist_names(); *nm; nm++)
            printf("%-26s %g\n", *nm, ss_skin_dist_get(&s.dist, *nm));
        opts_free(&o);
        return 0;
    }
    ss_threads_set(o.threads);
    /* memory: bio map 44 B, render maps 52 B a texel, and a margin */
    double need = (double)s.size * s.size * 110.0;
    double phys = ss_memory_physical_bytes();
    if (!st && phys > 0 && need > 0.8 * phys)
        st = ss_error_set(&err, SS_ERR_INPUT,
                          "--size %d needs about %.1f GB, more than this machine's %.1f GB", s.size,
                          need / 1e9, phys / 1e9);
    cJSON *summary = cJSON_CreateObject(), *notes = cJSON_CreateArray();
    inputs in;
    memset(&in, 0, sizeof in);
    /* The output folder: checked now, staged by begin, swapped in whole by
     * finish (src/core/output.c). Estimate: bio.exr 44 B, maps ~8 B a texel. */
    ss_outputs *outs = st ? NULL : ss_outputs_create(CMD, &err);
    if (!st && !outs) st = SS_ERR_NOMEM;
    for (int i = 0; i < o.nfields && !st; i++) st = ss_outputs_input(outs, o.field_path[i], &err);
    if (!st) st = ss_outputs_input(outs, o.features_in, &err);
    if (!st) st = ss_outputs_input(outs, o.table, &err);
    if (!st) st = ss_outputs_input(outs, o.mesh, &err);
    if (!st)
        st = ss_outputs_add(outs, "--out", o.out, SS_OUTPUT_DIR, (double)s.size * s.size * 52.0,
                            &err);
    if (!st) st = read_inputs(&o, &in, notes, &err);
    if (!st) st = ss_outputs_begin(outs, &err);
    if (!st) st = run(&o, &s, &in, ss_outputs_path(outs, 0), summary, notes, &err);
    if (outs) st = ss_outputs_finish(outs, st, &err);
    ss_outputs_free(outs);
    if (!st && !o.quiet) {
        for (int i = 0; i < cJSON_GetArraySize(notes); i++)
            fprintf(stderr, "skinsim skin: note: %s\n", cJSON_GetArrayItem(notes, i)->valuestring);
    }
    if (!st && o.json) {
        cJSON_AddStringToObject(summary, "out", o.out);
        cJSON_AddItemReferenceToObject(summary, "notes", notes);
        char *text = cJSON_PrintUnformatted(summary);
        if (text) printf("%s\n", text);
        free(text);
        cJSON_DeleteItemFromObject(summary, "notes");
    } else if (!st && !o.quiet) {
        fprintf(stderr, "wrote %s (contact sheet: %s/contact_sheet.png)\n", o.out, o.out);
    }
    cJSON_Delete(summary);
    cJSON_Delete(notes);
    inputs_free(&in);
    opts_free(&o);
    return st ? cli_fail(CMD, &err) : 0;
}
