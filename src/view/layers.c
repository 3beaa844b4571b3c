/* The texture stack the time slider scrubs (seed 000 §3.2, §4.2): a list of
 * layers (packed RGBA8 maps, uploaded once as OpenGL texture arrays) and
 * stops (day -> layer). A frame at day t blends the two stops around t, as
 * the seed's timeline blends its two key positions; the GPU does it per
 * pixel, so scrubbing never touches the CPU images again.
 *
 * Maturation is not a blend on the CPU path (its colour is re-rendered at
 * every position, §4.3.5). To keep the slider a pure blend, maturation is
 * sampled at extra positions (0 and MAT_POS below, denser early where the
 * colour changes fastest) and the GPU blends between those samples: a
 * piecewise-linear approximation of the CPU frame. Measured midway between
 * samples on a 512^2 stack, the screenshots differ from those of
 * `skinsim abrasion`'s own frames by at most 9 8-bit steps (mean 1-3 over
 * the wound pixels that differ at all); with 4 evenly spaced samples it was
 * 16. A loaded `skinsim abrasion` folder contributes its maturation frames
 * the same way.
 *
 * Packing: cr = sRGB colour (hardware-decoded to linear when sampled) and
 * linear reflection in alpha; nh = normal and height, 8 bits each. 8-bit
 * height is 1/255 of the scab thickness (about 4 um): invisible as
 * displacement on a hand-sized mesh. */
#define _POSIX_C_SOURCE 200809L
#include "view.h"

#include "skinsim/heal_run.h"
#include "skinsim/wound.h"

#include <cjson/cJSON.h>
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define MAX_SIZE 4096

void view_layers_free(view_layers *l) {
    if (!l) return;
    free(l->cr);
    free(l->nh);
    ss_image_free(l->skin);
    for (int i = 0; i < 16; i++) free(l->cr_mip[i]), free(l->nh_mip[i]);
    memset(l, 0, sizeof *l);
}

/* One 2x2 box step from src (side n) to dst (side n/2) for nlayers layers;
 * lin: channels 0-2 are sRGB bytes averaged in linear light. */
#define ENC_LUT 16384 /* linear 0..1 -> sRGB byte; 0.2 of a step at most off */

static void half(const unsigned char *src, unsigned char *dst, int n, int nlayers, int lin,
                 const float *dec, const unsigned char *enc) {
    int m = n / 2;
#pragma omp parallel for schedule(static)
    for (int row = 0; row < nlayers * m; row++) {
        int layer = row / m, y = row % m;
        const unsigned char *s0 = src + ((size_t)layer * n * n + (size_t)(2 * y) * n) * 4;
        const unsigned char *s1 = s0 + (size_t)n * 4;
        unsigned char *d = dst + ((size_t)layer * m * m + (size_t)y * m) * 4;
        for (int x = 0; x < m; x++)
            for (int k = 0; k < 4; k++) {
                int i = 8 * x + k;
                if (lin && k < 3) {
                    float v = 0.25f * (dec[s0[i]] + dec[s0[i + 4]] + dec[s1[i]] + dec[s1[i + 4]]);
                    d[4 * x + k] = enc[(int)(v * (ENC_LUT - 1) + 0.5f)];
                } else {
                    d[4 * x + k] = (unsigned char)((s0[i] + s0[i + 4] + s1[i] + s1[i + 4] + 2) / 4);
                }
            }
    }
}

ss_status view_layers_build_mips(view_layers *l, ss_error *err) {
    float dec[256];
    for (int i = 0; i < 256; i++) dec[i] = ss_srgb_decode(i / 255.0f);
    /* a table instead of a power per texel (it was 2.2 s of Generate's 12 at 2048^2) */
    unsigned char *enc = malloc(ENC_LUT);
    if (!enc) return ss_error_set(err, SS_ERR_NOMEM, "viewer: out of memory for mipmaps");
    for (int i = 0; i < ENC_LUT; i++)
        enc[i] = (unsigned char)(ss_srgb_encode((float)i / (ENC_LUT - 1)) * 255.0f + 0.5f);
    int n = l->size, lv = 1;
    const unsigned char *cr = l->cr, *nh = l->nh;
    /* odd sides cannot be halved exactly: leave those to OpenGL */
    while (n > 1 && n % 2 == 0 && lv < 16) {
        size_t bytes = (size_t)(n / 2) * (size_t)(n / 2) * 4 * (size_t)l->nlayers;
        l->cr_mip[lv] = malloc(bytes);
        l->nh_mip[lv] = malloc(bytes);
        if (!l->cr_mip[lv] || !l->nh_mip[lv]) {
            for (int i = 1; i <= lv; i++) {
                free(l->cr_mip[i]), free(l->nh_mip[i]);
                l->cr_mip[i] = l->nh_mip[i] = NULL;
            }
            l->nlevels = 0;
            free(enc);
            return ss_error_set(err, SS_ERR_NOMEM, "viewer: out of memory for mipmaps");
        }
        half(cr, l->cr_mip[lv], n, l->nlayers, 1, dec, enc);
        half(nh, l->nh_mip[lv], n, l->nlayers, 0, dec, enc);
        cr = l->cr_mip[lv], nh = l->nh_mip[lv];
        n /= 2;
        lv++;
    }
    free(enc);
    l->nlevels = n == 1 ? lv : 0; /* a full chain, else let OpenGL make it */
    return SS_OK;
}

void view_layers_locate(const view_layers *l, double day, int *a, int *b, float *w, int *stop) {
    *a = *b = l->nstops > 0 ? l->stop_layer[0] : 0;
    *w = 0;
    if (stop) *stop = 0;
    if (l->nstops <= 1 || !(day > l->stop_day[0])) return;
    int last = l->nstops - 1;
    if (day >= l->stop_day[last]) {
        *a = *b = l->stop_layer[last];
        if (stop) *stop = last;
        return;
    }
    int i = 0;
    while (i + 1 < last && day >= l->stop_day[i + 1]) i++;
    double span = l->stop_day[i + 1] - l->stop_day[i];
    *a = l->stop_layer[i];
    *b = l->stop_layer[i + 1];
    *w = span > 0 ? (float)((day - l->stop_day[i]) / span) : 1.0f;
    if (stop) *stop = i;
}

ss_status view_layers_alloc(view_layers *l, int size, int n, ss_error *err) {
    memset(l, 0, sizeof *l);
    size_t bytes = (size_t)size * (size_t)size * 4 * (size_t)n;
    l->cr = malloc(bytes);
    l->nh = malloc(bytes);
    if (!l->cr || !l->nh) {
        view_layers_free(l);
        return ss_error_set(err, SS_ERR_NOMEM, "viewer: out of memory for %d layers of %d^2", n,
                            size);
    }
    l->size = size;
    l->nlayers = n;
    ss_abrasion_settings s;
    ss_abrasion_settings_default(&s);
    l->height_mm = s.scab_height_mm;
    return SS_OK;
}

static unsigned char to_byte(float v) {
    if (!(v > 0)) return 0;
    if (v >= 1) return 255;
    return (unsigned char)(v * 255.0f + 0.5f);
}

void view_layers_pack_rect(view_layers *l, int layer, const ss_image *color, const ss_image *refl,
                           const ss_image *height, const ss_image *normal, int x0, int y0, int w,
                           int h) {
    size_t n = (size_t)l->size * (size_t)l->size;
    unsigned char *cr = l->cr + (size_t)layer * n * 4, *nh = l->nh + (size_t)layer * n * 4;
#pragma omp parallel for schedule(static)
    for (long long j = 0; j < (long long)w * h; j++) {
        long long i = (long long)(y0 + j / w) * l->size + x0 + j % w;
        const float *c = color->data + (size_t)i * (size_t)color->channels;
        for (int k = 0; k < 3; k++)
            cr[4 * i + k] = to_byte(ss_srgb_encode(c[color->channels >= 3 ? k : 0]));
        cr[4 * i + 3] = to_byte(refl ? refl->data[(size_t)i * (size_t)refl->channels] : 0.3f);
        if (normal) {
            const float *q = normal->data + (size_t)i * (size_t)normal->channels;
            for (int k = 0; k < 3; k++)
                nh[4 * i + k] = to_byte(normal->channels >= 3 ? q[k] : 0.5f);
        } else {
            nh[4 * i] = nh[4 * i + 1] = 128;
            nh[4 * i + 2] = 255;
        }
        nh[4 * i + 3] = to_byte(height ? height->data[(size_t)i * (size_t)height->channels] : 0.5f);
    }
}

static void pack_layer(view_layers *l, int layer, const ss_image *color, const ss_image *refl,
                       const ss_image *height, const ss_image *normal) {
    view_layers_pack_rect(l, layer, color, refl, height, normal, 0, 0, l->size, l->size);
}

void view_layers_add_stop(view_layers *l, double day, int layer, const char *name) {
    if (l->nstops >= VIEW_MAX_STOPS) return;
    l->stop_day[l->nstops] = day;
    l->stop_layer[l->nstops] = layer;
    snprintf(l->stop_name[l->nstops], sizeof l->stop_name[0], "%s", name);
    l->nstops++;
}

ss_status view_layers_plain_skin(int size, uint64_t seed, view_layers *out, ss_error *err) {
    ss_base_skin skin = {0};
    ss_status st = ss_base_skin_create(NULL, NULL, size, seed, &skin, err);
    if (!st) st = view_layers_alloc(out, size, 1, err);
    if (!st) {
        pack_layer(out, 0, skin.upper, NULL, NULL, NULL);
        view_layers_add_stop(out, 0, 0, "healthy skin");
        view_layers_build_mips(out, NULL);
        snprintf(out->source, sizeof out->source, "healthy skin (no wound)");
    }
    ss_base_skin_free(&skin);
    return st;
}

/* ---- loading folders --------------------------------------------------------- */

static int file_exists(const char *p) {
    struct stat st;
    return stat(p, &st) == 0 && S_ISREG(st.st_mode);
}

/* Reads a map (NULL path: NULL, no error) at `size` (resampled when the
 * file is another size; size 0 takes the file's, capped at MAX_SIZE). */
static ss_image *read_map(const char *path, ss_encoding enc, int *size, ss_error *err) {
    ss_image *img = ss_image_read(path, enc, err);
    if (!img) return NULL;
    if (img->width != img->height && *size == 0) {
        ss_error_set(err, SS_ERR_INPUT, "%s: texture is %dx%d; the viewer needs square textures",
                     path, img->width, img->height);
        ss_image_free(img);
        return NULL;
    }
    if (*size == 0) *size = img->width > MAX_SIZE ? MAX_SIZE : img->width;
    if (img->width != *size || img->height != *size) {
        ss_image *r = ss_image_resize(img, *size, *size, err);
        ss_image_free(img);
        img = r;
    }
    return img;
}

typedef struct set_paths {
    char color[4096], refl[4096], rough[4096], height[4096], normal[4096];
} set_paths;

/* Reads a set and packs it into layer (allocating the layers at the first). */
static ss_status load_set(const set_paths *p, view_layers *l, int layer, int nlayers,
                          ss_image **keep_color, ss_error *err) {
    int size = l->size;
    ss_image *c = read_map(p->color, SS_ENC_SRGB, &size, err);
    if (!c) return err->code;
    ss_status st = SS_OK;
    if (!l->cr) st = view_layers_alloc(l, size, nlayers, err);
    ss_image *r = NULL, *h = NULL, *n = NULL;
    if (!st && p->refl[0] && !(r = read_map(p->refl, SS_ENC_LINEAR, &size, err))) st = err->code;
    if (!st && !r && p->rough[0]) {
        if (!(r = read_map(p->rough, SS_ENC_LINEAR, &size, err)))
            st = err->code;
        else /* roughness = 1 - 0.8 reflection (abrasion's glTF export), inverted */
            for (size_t i = 0; i < (size_t)size * (size_t)size * (size_t)r->channels; i++) {
                float v = (1.0f - r->data[i]) / 0.8f;
                r->data[i] = v < 0 ? 0 : v > 1 ? 1 : v;
            }
    }
    if (!st && p->height[0] && !(h = read_map(p->height, SS_ENC_LINEAR, &size, err)))
        st = err->code;
    if (!st && p->normal[0] && !(n = read_map(p->normal, SS_ENC_LINEAR, &size, err)))
        st = err->code;
    if (!st) pack_layer(l, layer, c, r, h, n);
    if (!st && keep_color) *keep_color = c, c = NULL;
    ss_image_free(c), ss_image_free(r), ss_image_free(h), ss_image_free(n);
    return st;
}

static const char *json_str(const cJSON *o, const char *k) {
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, k);
    return cJSON_IsString(v) ? v->valuestring : NULL;
}

static void join(char *out, const char *dir, const char *rel) {
    snprintf(out, 4096, "%s/%s", dir, rel);
}

static ss_status files_to_paths(const char *dir, const cJSON *files, const char *where,
                                set_paths *p, ss_error *err) {
    memset(p, 0, sizeof *p);
    const char *c = json_str(files, "color");
    if (!c)
        return ss_error_set(err, SS_ERR_INPUT, "%s/timeline.json: %s has no colour file", dir,
                            where);
    join(p->color, dir, c);
    const char *r = json_str(files, "reflection"), *h = json_str(files, "height"),
               *n = json_str(files, "normal");
    if (r) join(p->refl, dir, r);
    if (h) join(p->height, dir, h);
    if (n) join(p->normal, dir, n);
    return SS_OK;
}

static ss_status load_timeline_dir(const char *dir, const char *json_path, view_layers *out,
                                   ss_error *err) {
    char *text = ss_read_file(json_path, NULL, err);
    if (!text) return err->code;
    cJSON *root = cJSON_Parse(text);
    free(text);
    if (!root) return ss_error_set(err, SS_ERR_INPUT, "%s: not valid JSON", json_path);
    const cJSON *keys = cJSON_GetObjectItemCaseSensitive(root, "keys");
    const cJSON *frames = cJSON_GetObjectItemCaseSensitive(root, "frames");
    const cJSON *end = cJSON_GetObjectItemCaseSensitive(root, "end_day");
    ss_status st = SS_OK;
    /* `skinsim abrasion`: keys (+ maturation frames); `skinsim wound`: no
     * keys, every frame is a stop (a healing texture sequence). */
    int seq = cJSON_IsArray(keys) && cJSON_GetArraySize(keys) == 0 && cJSON_IsArray(frames) &&
              cJSON_GetArraySize(frames) > 0;
    if (!seq && (!cJSON_IsArray(keys) || cJSON_GetArraySize(keys) < 1))
        st = ss_error_set(err, SS_ERR_INPUT,
                          "%s: no \"keys\" or \"frames\" (not a skinsim abrasion or wound folder?)",
                          json_path);
    /* Candidate stops: keys, then maturation frames after the last key. */
    typedef struct cand {
        double day;
        char name[24];
        set_paths paths;
    } cand;
    int nk = cJSON_IsArray(keys) ? cJSON_GetArraySize(keys) : 0;
    int nf = cJSON_IsArray(frames) ? cJSON_GetArraySize(frames) : 0;
    cand *cs = calloc((size_t)(nk + nf + 1), sizeof *cs);
    int nc = 0;
    if (!cs && !st) st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    double last_key_day = -1;
    for (int i = 0; i < nk && !st; i++) {
        const cJSON *k = cJSON_GetArrayItem(keys, i);
        const cJSON *day = cJSON_GetObjectItemCaseSensitive(k, "day");
        const char *phase = json_str(k, "phase");
        char where[64];
        snprintf(where, sizeof where, "key %d", i);
        if (!cJSON_IsNumber(day) || !isfinite(day->valuedouble) || day->valuedouble < 0 ||
            day->valuedouble < last_key_day || !phase)
            st = ss_error_set(err, SS_ERR_INPUT, "%s: key %d needs a phase and an increasing day",
                              json_path, i);
        else
            st = files_to_paths(dir, cJSON_GetObjectItemCaseSensitive(k, "files"), where,
                                &cs[nc].paths, err);
        if (!st) {
            cs[nc].day = last_key_day = day->valuedouble;
            snprintf(cs[nc].name, sizeof cs[nc].name, "%s", phase);
            nc++;
        }
    }
    /* Maturation frames (re-rendered positions) extend the blend past the last key. */
    for (int i = 0; i < nf && !st; i++) {
        const cJSON *f = cJSON_GetArrayItem(frames, i);
        const cJSON *day = cJSON_GetObjectItemCaseSensitive(f, "day");
        const char *phase = json_str(f, "phase");
        if (!cJSON_IsNumber(day) || !isfinite(day->valuedouble) || day->valuedouble < 0 ||
            (!seq && (!phase || strcmp(phase, "maturation") || !(day->valuedouble > last_key_day))))
            continue;
        char where[64];
        snprintf(where, sizeof where, "frame %d", i);
        if (files_to_paths(dir, cJSON_GetObjectItemCaseSensitive(f, "files"), where, &cs[nc].paths,
                           err) == SS_OK) {
            cs[nc].day = day->valuedouble;
            snprintf(cs[nc].name, sizeof cs[nc].name, "%s", seq ? "healing" : "maturation");
            nc++;
        }
    }
    /* Sort the frames part by day (keys are already in order). */
    for (int i = 1; i < nc; i++)
        for (int j = i; j > 0 && cs[j].day < cs[j - 1].day; j--) {
            cand t = cs[j];
            cs[j] = cs[j - 1];
            cs[j - 1] = t;
        }
    if (nc > VIEW_MAX_STOPS) nc = VIEW_MAX_STOPS;
    if (!st && nc == 0)
        st = ss_error_set(err, SS_ERR_INPUT, "%s: no frame with texture files", json_path);
    /* Unique layers by colour file. */
    int *layer_of = calloc((size_t)(nc + 1), sizeof *layer_of);
    int nl = 0;
    if (!layer_of && !st) st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    for (int i = 0; i < nc && !st; i++) {
        layer_of[i] = -1;
        for (int j = 0; j < i && layer_of[i] < 0; j++)
            if (!strcmp(cs[j].paths.color, cs[i].paths.color)) layer_of[i] = layer_of[j];
        if (layer_of[i] < 0) layer_of[i] = nl++;
    }
    memset(out, 0, sizeof *out);
    for (int i = 0, next = 0; i < nc && !st; i++) {
        if (layer_of[i] == next) {
            st = load_set(&cs[i].paths, out, next, nl, NULL, err);
            next++;
        }
    }
    if (!st) {
        for (int i = 0; i < nc; i++) {
            if (i > 0 && cs[i].day == cs[i - 1].day && layer_of[i] == layer_of[i - 1]) continue;
            view_layers_add_stop(out, cs[i].day, layer_of[i], cs[i].name);
        }
        out->end_day = cJSON_IsNumber(end) && end->valuedouble > 0 ? end->valuedouble
                                                                   : out->stop_day[out->nstops - 1];
        if (out->end_day < out->stop_day[out->nstops - 1])
            out->end_day = out->stop_day[out->nstops - 1];
        /* wound: height 0..1 spans -range..+range mm */
        const cJSON *hr = cJSON_GetObjectItemCaseSensitive(root, "height_range_mm");
        if (cJSON_IsNumber(hr) && hr->valuedouble > 0 && isfinite(hr->valuedouble))
            out->height_mm = 2 * hr->valuedouble;
        /* `skinsim wound` without --mesh: the textures cover a block of skin
         * world_size_cm on a side, not the mesh's UV layout */
        const char *cmd = json_str(root, "command");
        const cJSON *ws = cJSON_GetObjectItemCaseSensitive(root, "world_size_cm");
        if (cmd && !strcmp(cmd, "wound") && !json_str(root, "texture_space") &&
            cJSON_IsNumber(ws) && ws->valuedouble > 0 && isfinite(ws->valuedouble))
            out->block_mm = 10 * ws->valuedouble;
        if (seq)
            snprintf(out->source, sizeof out->source, "%s (healing sequence, %d days)", dir, nc);
        else
            snprintf(out->source, sizeof out->source, "%s (%d keys, %d layers)", dir, nk, nl);
    } else {
        view_layers_free(out);
    }
    free(layer_of);
    free(cs);
    cJSON_Delete(root);
    return st;
}

/* A single texture set: base_color.png / color.png / <stem>_color.png and
 * the siblings named alike. */
static ss_status load_single_set(const char *dir, view_layers *out, ss_error *err) {
    set_paths p;
    memset(&p, 0, sizeof p);
    const char *stems[] = {"base_color", "color", "albedo"};
    for (int i = 0; i < 3 && !p.color[0]; i++) {
        char t[4096];
        snprintf(t, sizeof t, "%s/%s.png", dir, stems[i]);
        if (file_exists(t)) snprintf(p.color, sizeof p.color, "%s", t);
    }
    char prefix[256] = "";
    if (!p.color[0]) { /* <stem>_color.png, first in name order */
        DIR *d = opendir(dir);
        char best[256] = "";
        struct dirent *e;
        while (d && (e = readdir(d))) {
            size_t n = strlen(e->d_name);
            if (n > 10 && n < 200 && !strcmp(e->d_name + n - 10, "_color.png") &&
                (!best[0] || strcmp(e->d_name, best) < 0))
                snprintf(best, sizeof best, "%s", e->d_name);
        }
        if (d) closedir(d);
        if (best[0]) {
            snprintf(p.color, sizeof p.color, "%s/%s", dir, best);
            snprintf(prefix, sizeof prefix, "%.*s_", (int)(strlen(best) - 10), best);
        }
    }
    if (!p.color[0])
        return ss_error_set(
            err, SS_ERR_INPUT,
            "%s: no textures found (expected timeline.json from skinsim abrasion or "
            "skinsim wound, run.json of a skinsim heal run, or base_color.png / "
            "*_color.png of skinsim skin)",
            dir);
    struct {
        const char *name;
        char *dst;
    } opt[] = {{"reflection", p.refl},
               {"roughness", p.rough},
               {"specular", p.refl}, /* only without roughness (skinsim skin writes both) */
               {"height", p.height},
               {"normal", p.normal}};
    for (size_t i = 0; i < sizeof opt / sizeof *opt; i++) {
        char t[4096];
        snprintf(t, sizeof t, "%s/%s%s.png", dir, prefix, opt[i].name);
        if (opt[i].dst == p.refl && p.rough[0]) continue;
        if (!opt[i].dst[0] && file_exists(t)) snprintf(opt[i].dst, 4096, "%s", t);
    }
    memset(out, 0, sizeof *out);
    ss_status st = load_set(&p, out, 0, 1, &out->skin, err);
    if (!st) {
        view_layers_add_stop(out, 0, 0, "texture set");
        snprintf(out->source, sizeof out->source, "%s", p.color);
    }
    return st;
}

/* A `skinsim heal --out DIR` run: rendered by `skinsim wound --heal`'s code
 * (ss_wound_make) into a temporary folder, which is then loaded as any
 * `skinsim wound` folder and removed. */
static ss_status load_heal_run(const char *dir, int size, int quiet, view_layers *out,
                               ss_error *err) {
    ss_heal_saved_run *run = NULL;
    ss_status st = ss_heal_saved_run_open(dir, &run, err);
    if (st)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: looks like a skinsim heal run (run.json) but cannot be read: %s",
                            dir, err->msg);
    int n = ss_heal_saved_run_snapshot_count(run), k = 0;
    double days[VIEW_HEAL_MAX_DAYS];
    /* every snapshot, or VIEW_HEAL_MAX_DAYS of them evenly (first and last kept) */
    for (int i = 0; i < n && k < VIEW_HEAL_MAX_DAYS; i++) {
        int j = n <= VIEW_HEAL_MAX_DAYS
                    ? i
                    : (int)lround((double)i * (n - 1) / (VIEW_HEAL_MAX_DAYS - 1));
        if (j >= n) break;
        double d = ss_heal_saved_run_snapshot_day(run, j);
        if (k == 0 || d > days[k - 1]) days[k++] = d;
    }
    ss_heal_saved_run_free(run);
    if (k == 0) return ss_error_set(err, SS_ERR_INPUT, "%s: the heal run has no snapshots", dir);
    char tmp[4096];
    const char *td = getenv("TMPDIR");
    snprintf(tmp, sizeof tmp, "%s/skinsim-view-heal-XXXXXX", td && *td ? td : "/tmp");
    if (!mkdtemp(tmp))
        return ss_error_set(err, SS_ERR_RUNTIME, "%s: cannot make a temporary folder", tmp);
    char wdir[4200];
    snprintf(wdir, sizeof wdir, "%s/wound", tmp);
    ss_wound_make_config c;
    ss_wound_make_config_default(&c);
    c.heal_dir = dir;
    c.days = days;
    c.ndays = k;
    c.size = size;
    c.out_dir = wdir;
    c.compare = 0;
    c.quiet = 1;
    if (!quiet)
        fprintf(stderr,
                "skinsim view: %s is a skinsim heal run: rendering %d day(s) at %d^2 as "
                "`skinsim wound --heal` does\n",
                dir, k, size);
    st = ss_wound_make(&c, NULL, err);
    if (!st) {
        char json[4300];
        snprintf(json, sizeof json, "%s/timeline.json", wdir);
        st = load_timeline_dir(wdir, json, out, err);
    }
    if (!st)
        snprintf(out->source, sizeof out->source,
                 "%s (heal run, %d days rendered as skinsim wound)", dir, k);
    ss_remove_tree(tmp);
    return st;
}

ss_status view_layers_load_dir(const char *dir, int heal_size, int quiet, view_layers *out,
                               ss_error *err) {
    memset(out, 0, sizeof *out);
    struct stat sb;
    if (stat(dir, &sb) != 0 || !S_ISDIR(sb.st_mode))
        return ss_error_set(err, SS_ERR_INPUT, "%s: not a folder", dir);
    char json[4096], run[4096];
    snprintf(json, sizeof json, "%s/timeline.json", dir);
    snprintf(run, sizeof run, "%s/run.json", dir);
    ss_status st = file_exists(json)  ? load_timeline_dir(dir, json, out, err)
                   : file_exists(run) ? load_heal_run(dir, heal_size, quiet, out, err)
                                      : load_single_set(dir, out, err);
    if (!st) view_layers_build_mips(out, NULL); /* on failure OpenGL makes the levels */
    return st;
}

/* ---- a block of skin at its world size --------------------------------------- */

/* Bilinear sample of layer `layer` of a packed map (side n, RGBA8) at
 * (x, y) in texels (0.5 = first texel centre), clamped at the edges. */
static void sample_rgba(const unsigned char *map, int n, int layer, double x, double y,
                        float out[4]) {
    x -= 0.5, y -= 0.5;
    double fx = floor(x), fy = floor(y);
    int x0 = (int)fx, y0 = (int)fy;
    float tx = (float)(x - fx), ty = (float)(y - fy);
    const unsigned char *base = map + (size_t)layer * n * n * 4;
    for (int k = 0; k < 4; k++) out[k] = 0;
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 2; i++) {
            int xi = x0 + i < 0 ? 0 : x0 + i >= n ? n - 1 : x0 + i;
            int yi = y0 + j < 0 ? 0 : y0 + j >= n ? n - 1 : y0 + j;
            float w = (i ? tx : 1 - tx) * (j ? ty : 1 - ty);
            const unsigned char *p = base + ((size_t)yi * n + xi) * 4;
            for (int k = 0; k < 4; k++) out[k] += w * p[k];
        }
}

/* 1 where a texel centre of a size x size texture lies in a triangle of
 * island `isl` (UV v down, as the texture rows). */
static unsigned char *island_mask(const ss_mesh *m, const int *island, int isl, int size) {
    unsigned char *mask = calloc((size_t)size * size, 1);
    if (!mask) return NULL;
    for (int t = 0; t < m->ntriangles; t++) {
        if (island[t] != isl) continue;
        const float *a = m->uvs + 2 * m->indices[3 * t], *b = m->uvs + 2 * m->indices[3 * t + 1],
                    *c = m->uvs + 2 * m->indices[3 * t + 2];
        double ax = a[0] * size, ay = a[1] * size, bx = b[0] * size, by = b[1] * size,
               cx = c[0] * size, cy = c[1] * size;
        double area = (bx - ax) * (cy - ay) - (cx - ax) * (by - ay);
        if (area == 0) continue;
        int x0 = (int)floor(fmin(ax, fmin(bx, cx))), x1 = (int)ceil(fmax(ax, fmax(bx, cx)));
        int y0 = (int)floor(fmin(ay, fmin(by, cy))), y1 = (int)ceil(fmax(ay, fmax(by, cy)));
        if (x0 < 0) x0 = 0;
        if (y0 < 0) y0 = 0;
        if (x1 > size) x1 = size;
        if (y1 > size) y1 = size;
        for (int y = y0; y < y1; y++)
            for (int x = x0; x < x1; x++) {
                double px = x + 0.5, py = y + 0.5;
                double w0 = ((bx - px) * (cy - py) - (cx - px) * (by - py)) / area;
                double w1 = ((cx - px) * (ay - py) - (ax - px) * (cy - py)) / area;
                double w2 = 1 - w0 - w1;
                if (w0 >= -1e-9 && w1 >= -1e-9 && w2 >= -1e-9) mask[(size_t)y * size + x] = 1;
            }
    }
    return mask;
}

ss_status view_layers_place_block(view_layers *l, const ss_mesh *m, const int *island,
                                  const float centre_uv[2], int size, uint64_t seed,
                                  ss_error *err) {
    if (!(l->block_mm > 0)) return SS_OK;
    if (!m->has_uvs || !island) return SS_OK; /* no UV layout: shown as loaded */
    /* the centre, else the centroid of the first triangle */
    float c_uv[2] = {centre_uv ? centre_uv[0] : 0.5f, centre_uv ? centre_uv[1] : 0.5f}, pos[3];
    int tri = ss_mesh_locate_uv(m, c_uv, pos);
    if (tri < 0) {
        tri = 0;
        for (int k = 0; k < 2; k++)
            c_uv[k] = (m->uvs[2 * m->indices[0] + k] + m->uvs[2 * m->indices[1] + k] +
                       m->uvs[2 * m->indices[2] + k]) /
                      3.0f;
    }
    int isl = island[tri];
    /* mm per UV unit over that island: sqrt(surface area / UV area) */
    double a3 = 0, a2 = 0;
    for (int t = 0; t < m->ntriangles; t++) {
        if (island[t] != isl) continue;
        const uint32_t *ix = m->indices + 3 * t;
        const float *p0 = m->positions + 3 * ix[0], *p1 = m->positions + 3 * ix[1],
                    *p2 = m->positions + 3 * ix[2];
        double e1[3], e2[3];
        for (int k = 0; k < 3; k++) e1[k] = p1[k] - p0[k], e2[k] = p2[k] - p0[k];
        double cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                        e1[0] * e2[1] - e1[1] * e2[0]};
        a3 += 0.5 * sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
        const float *u0 = m->uvs + 2 * ix[0], *u1 = m->uvs + 2 * ix[1], *u2 = m->uvs + 2 * ix[2];
        a2 += 0.5 * fabs((double)(u1[0] - u0[0]) * (u2[1] - u0[1]) -
                         (double)(u2[0] - u0[0]) * (u1[1] - u0[1]));
    }
    if (!(a3 > 0 && a2 > 0)) return SS_OK;
    double mm_per_uv = sqrt(a3 / a2) * 1e3; /* metres -> mm */
    double side = l->block_mm / mm_per_uv;  /* the block's side in UV units */
    view_layers out = {0};
    ss_base_skin skin = {0};
    unsigned char *mask = island_mask(m, island, isl, size);
    ss_status st = mask ? SS_OK : ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    if (!st) st = ss_base_skin_create(NULL, NULL, size, seed, &skin, err);
    if (!st) st = view_layers_alloc(&out, size, l->nlayers, err);
    if (st) {
        free(mask);
        ss_base_skin_free(&skin);
        return st;
    }
    /* the plain skin everywhere, the block's texels where it lies */
    pack_layer(&out, 0, skin.upper, NULL, NULL, NULL);
    size_t n = (size_t)size * size;
    for (int k = 1; k < l->nlayers; k++) {
        memcpy(out.cr + k * n * 4, out.cr, n * 4);
        memcpy(out.nh + k * n * 4, out.nh, n * 4);
    }
    /* the source level whose texels are about the target's (no aliasing) */
    double step = (double)l->size * (1.0 / size) / side; /* source texels per target texel */
    int lv = 0;
    while (lv + 1 < l->nlevels && step >= 2.0) lv++, step /= 2;
    int ns = l->size >> lv;
    const unsigned char *scr = lv ? l->cr_mip[lv] : l->cr, *snh = lv ? l->nh_mip[lv] : l->nh;
    double u0 = c_uv[0] - 0.5 * side, v0 = c_uv[1] - 0.5 * side;
    int x0 = (int)floor(u0 * size), x1 = (int)ceil((u0 + side) * size);
    int y0 = (int)floor(v0 * size), y1 = (int)ceil((v0 + side) * size);
    if (x0 < 0) x0 = 0;
    if (y0 < 0) y0 = 0;
    if (x1 > size) x1 = size;
    if (y1 > size) y1 = size;
    float dec[256];
    for (int i = 0; i < 256; i++) dec[i] = ss_srgb_decode(i / 255.0f);
    for (int k = 0; k < l->nlayers; k++) {
        unsigned char *dcr = out.cr + k * n * 4, *dnh = out.nh + k * n * 4;
#pragma omp parallel for schedule(static)
        for (int y = y0; y < y1; y++)
            for (int x = x0; x < x1; x++) {
                size_t i = (size_t)y * size + x;
                if (!mask[i]) continue;
                double bu = ((x + 0.5) / size - u0) / side, bv = ((y + 0.5) / size - v0) / side;
                if (bu < 0 || bu > 1 || bv < 0 || bv > 1) continue;
                /* feather: 0 at the block's edge, 1 from 8 % inside */
                double e = fmin(fmin(bu, 1 - bu), fmin(bv, 1 - bv)) / 0.08;
                float w = e >= 1 ? 1.0f : (float)(e * e * (3 - 2 * e));
                float c[4], h[4];
                sample_rgba(scr, ns, k, bu * ns, bv * ns, c);
                sample_rgba(snh, ns, k, bu * ns, bv * ns, h);
                for (int q = 0; q < 3; q++) { /* colour blended in linear light */
                    float lin = (1 - w) * dec[dcr[4 * i + q]] + w * ss_srgb_decode(c[q] / 255.0f);
                    dcr[4 * i + q] = to_byte(ss_srgb_encode(lin));
                }
                dcr[4 * i + 3] = to_byte(((1 - w) * dcr[4 * i + 3] + w * c[3]) / 255.0f);
                for (int q = 0; q < 4; q++)
                    dnh[4 * i + q] = to_byte(((1 - w) * dnh[4 * i + q] + w * h[q]) / 255.0f);
            }
    }
    free(mask);
    ss_base_skin_free(&skin);
    /* keep the stops, the timeline and the source; replace the maps */
    out.nstops = l->nstops;
    memcpy(out.stop_day, l->stop_day, sizeof out.stop_day);
    memcpy(out.stop_layer, l->stop_layer, sizeof out.stop_layer);
    memcpy(out.stop_name, l->stop_name, sizeof out.stop_name);
    out.end_day = l->end_day;
    out.height_mm = l->height_mm;
    out.block_mm = l->block_mm;
    out.block_uv[0] = c_uv[0], out.block_uv[1] = c_uv[1];
    out.block_side_uv = side;
    out.mm_per_uv = mm_per_uv;
    snprintf(out.source, sizeof out.source, "%.3900s (%.0f mm block at its size on the mesh)",
             l->source, l->block_mm);
    view_layers_free(l);
    *l = out;
    view_layers_build_mips(l, NULL);
    return SS_OK;
}

/* ---- hash ----------------------------------------------------------------------- */

static uint64_t fnv_bytes(uint64_t h, const void *p, size_t n) {
    const unsigned char *b = p;
    size_t i = 0;
    /* eight bytes at a time: the full byte-wise FNV takes 1 s on 13 layers of 2048^2 */
    for (; i + 8 <= n; i += 8) {
        uint64_t w;
        memcpy(&w, b + i, 8);
        h = (h ^ w) * 0x100000001b3ULL;
    }
    for (; i < n; i++) h = (h ^ b[i]) * 0x100000001b3ULL;
    return h;
}

uint64_t view_layers_hash(const view_layers *l) {
    uint64_t h = 0xcbf29ce484222325ULL;
    int hdr[3] = {l->size, l->nlayers, l->nstops};
    h = fnv_bytes(h, hdr, sizeof hdr);
    size_t n = (size_t)l->size * (size_t)l->size * 4 * (size_t)l->nlayers;
    if (l->cr) h = fnv_bytes(h, l->cr, n);
    if (l->nh) h = fnv_bytes(h, l->nh, n);
    for (int lv = 1; lv < l->nlevels && lv < 16; lv++) {
        size_t m = (size_t)(l->size >> lv) * (size_t)(l->size >> lv) * 4 * (size_t)l->nlayers;
        if (l->cr_mip[lv]) h = fnv_bytes(h, l->cr_mip[lv], m);
        if (l->nh_mip[lv]) h = fnv_bytes(h, l->nh_mip[lv], m);
    }
    for (int i = 0; i < l->nstops; i++) {
        h = fnv_bytes(h, &l->stop_day[i], sizeof l->stop_day[i]);
        h = fnv_bytes(h, &l->stop_layer[i], sizeof l->stop_layer[i]);
    }
    return h;
}
