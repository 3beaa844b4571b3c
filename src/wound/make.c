/* `skinsim wound` as a library call: run the heal simulation in memory (or
 * read a finished run folder, --heal DIR), and at each requested day sample
 * the tissue with the run's own closure days, render the textures and write
 * them in the texture-timeline layout of `skinsim abrasion`
 * (frames/t<days>_*.png, timeline.json, contact_sheet.png), plus a glTF scene
 * per day and compare_abrasion.png (the same wound through seed 000's artist
 * phases, row above row). The textures cover the heal block, or on a body
 * (--mesh) the mesh's UV layout. Without a wound input the wound is a
 * built-in irregular abrasion (default_footprint).
 *
 * Order of work, so that bad input writes nothing: parse and check the days,
 * read the table, the recipe and the base skin, create the heal run (which
 * validates the whole healing problem) or open the run folder and read its
 * day-0 snapshot, check the output directory; only then stage the output
 * directory (ss_output_dir_begin), fill it and swap it in. */
#define _POSIX_C_SOURCE 200809L
#include <cjson/cJSON.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/abrasion.h"
#include "skinsim/mech.h"
#include "skinsim/mesh.h"
#include "skinsim/shell.h"
#include "skinsim/texture.h"
#include "skinsim/wound.h"
#include "wound_internal.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

void ss_wound_make_config_default(ss_wound_make_config *c) {
    memset(c, 0, sizeof *c);
    ss_heal_run_config_default(&c->heal);
    c->size = 1024;
    c->compare = 1;
    c->seed = 1;
}

/* ---- inputs --------------------------------------------------------------------------- */

typedef struct job {
    const ss_wound_make_config *c;
    ss_mm_table *table;
    ss_wound_recipe recipe;
    ss_image *skin;
    ss_heal_run *run;         /* simulated here, or */
    ss_heal_saved_run *saved; /* read back from --heal DIR */
    ss_heal_grid *grid0;      /* --heal: the first snapshot (day 0) */
    float *disp0;             /* --heal: its displacement (NULL without mechanics) */
    double *closed0;          /* --heal: its closure days */
    ss_wound_tissue *tissue;
    ss_wound_renderer *renderer;
    double side_mm;
    double t_heal, t_render, t_write, t_setup, t_compare;
    const ss_mesh *mesh; /* on a real body (--mesh): the skin mesh, textures in its UVs */
    char warning[512];   /* set when the inputs were matched (e.g. the skin's world size) */
    ss_image *columns;   /* then: the tissue column under every texel */
} job;

static void job_free(job *j) {
    ss_mm_table_free(j->table);
    ss_image_free(j->skin);
    ss_wound_renderer_free(j->renderer);
    ss_wound_tissue_free(j->tissue);
    ss_heal_run_free(j->run);
    ss_heal_saved_run_free(j->saved);
    ss_heal_grid_free(j->grid0);
    ss_image_free(j->columns);
    free(j->disp0);
    free(j->closed0);
}

static const char *job_scenario(const job *j) {
    return j->run ? ss_heal_run_scenario(j->run) : ss_heal_saved_run_scenario(j->saved);
}
static double job_dt(const job *j) {
    return j->run ? ss_heal_run_dt(j->run) : ss_heal_saved_run_dt(j->saved);
}
static const ss_heal_params *job_params(const job *j) {
    return j->run ? ss_heal_run_params(j->run) : ss_heal_saved_run_params(j->saved);
}
static const ss_heal_grid *job_grid(const job *j) {
    return j->run ? ss_heal_run_grid(j->run) : j->grid0;
}

static ss_status check_days(const ss_wound_make_config *c, ss_error *err) {
    if (c->ndays < 1 || c->ndays > 64)
        return ss_error_set(err, SS_ERR_INPUT, "--days: give 1..64 days");
    for (int i = 0; i < c->ndays; i++) {
        if (!(c->days[i] >= 0 && c->days[i] <= 1e4))
            return ss_error_set(err, SS_ERR_INPUT, "--days: %g is outside 0..10000", c->days[i]);
        if (i && !(c->days[i] > c->days[i - 1]))
            return ss_error_set(err, SS_ERR_INPUT,
                                "--days: list them in increasing order (%g after %g)", c->days[i],
                                c->days[i - 1]);
    }
    if (c->size < 16 || c->size > 16384)
        return ss_error_set(err, SS_ERR_INPUT, "--size %d is outside 16..16384", c->size);
    return SS_OK;
}

/* The world size (cm) a `skinsim skin` folder's bio map covers, from the
 * skin.json next to it; 0 when there is none (a bare EXR). */
static double skin_world_cm(const char *path) {
    char file[4200];
    const char *slash = strrchr(path, '/');
    size_t n = strlen(path);
    if (n > 4 && !strcmp(path + n - 4, ".exr"))
        snprintf(file, sizeof file, "%.*s/skin.json", slash ? (int)(slash - path) : 1,
                 slash ? path : ".");
    else
        snprintf(file, sizeof file, "%s/skin.json", path);
    ss_error e;
    char *text = ss_read_file(file, NULL, &e);
    if (!text) return 0;
    cJSON *root = cJSON_Parse(text);
    free(text);
    const cJSON *w = root ? cJSON_GetObjectItemCaseSensitive(root, "world_size_cm") : NULL;
    double v = cJSON_IsNumber(w) && w->valuedouble > 0 ? w->valuedouble : 0;
    cJSON_Delete(root);
    return v;
}

/* A skin of another world size than the texture's (make demo's 5 cm skin
 * under a 3 cm block) would stretch its features: the part of it that the
 * texture covers is cut out (the middle, wrapping around: skin maps tile),
 * so freckles and follicles keep their size; j->warning says so. */
static ss_status match_skin(job *j, double skin_cm, ss_error *err) {
    double tex_cm = j->side_mm / 10.0;
    if (!(skin_cm > 0) || fabs(skin_cm - tex_cm) <= 0.01 * tex_cm) return SS_OK;
    const ss_image *b = j->skin;
    int w = (int)lround(b->width * tex_cm / skin_cm), h = (int)lround(b->height * tex_cm / skin_cm);
    if (w < 4) w = 4;
    if (h < 4) h = 4;
    ss_image *m = ss_image_create(w, h, b->channels, err);
    if (!m) return err->code;
    int x0 = (b->width - w) / 2, y0 = (b->height - h) / 2;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            int sx = ((x0 + x) % b->width + b->width) % b->width;
            int sy = ((y0 + y) % b->height + b->height) % b->height;
            memcpy(m->data + ((size_t)y * w + x) * b->channels,
                   b->data + ((size_t)sy * b->width + sx) * b->channels,
                   sizeof(float) * (size_t)b->channels);
        }
    snprintf(j->warning, sizeof j->warning,
             "--skin %s covers %g cm but the texture covers %g cm: using %s %g cm of it "
             "(features keep their size)",
             j->c->skin_path, skin_cm, tex_cm, tex_cm < skin_cm ? "the middle" : "a tiling to",
             tex_cm);
    ss_image_free(j->skin);
    j->skin = m;
    return SS_OK;
}

static ss_status read_skin(job *j, ss_error *err) {
    const ss_wound_make_config *c = j->c;
    j->skin = c->skin_path ? ss_wound_skin_read(c->skin_path, err)
                           : ss_wound_default_skin(c->size, j->side_mm, c->seed, err);
    if (!j->skin) return err->code ? err->code : SS_ERR_INPUT;
    return c->skin_path ? match_skin(j, skin_world_cm(c->skin_path), err) : SS_OK;
}

/* The built-in wound of `skinsim wound` when none is given: an irregular
 * abrasion instead of heal's schematic square. An ellipse of 0.74 x 0.5 of the
 * block (22 x 15 mm on the default 30 mm block), turned by 15 degrees, its
 * outline moved by value noise (seed 000 §3.2, about a third of the block per
 * period), then frayed along the scrape by seed 000's shape erosion (Alg. 3.1,
 * horizontal min filter of random widths up to 9 of 256 pixels): ragged
 * margins and streaks, as a scrape leaves them. A footprint over the whole
 * block (ss_heal_run_config.wound_footprint), deterministic per seed. */
#define FOOT_PX 256
static ss_image *default_footprint(uint64_t seed, ss_error *err) {
    ss_image *noise = ss_image_create(FOOT_PX, FOOT_PX, 1, err);
    ss_image *mask = noise ? ss_image_create(FOOT_PX, FOOT_PX, 1, err) : NULL;
    int *widths = mask ? malloc(sizeof *widths * FOOT_PX * FOOT_PX) : NULL;
    ss_status st = !noise || !mask ? err->code
                   : !widths       ? ss_error_set(err, SS_ERR_NOMEM, "out of memory")
                                   : SS_OK;
    if (!st) st = ss_wound__noise(FOOT_PX, FOOT_PX, FOOT_PX / 3.0, 3, seed, 301, noise, err);
    if (!st) {
        const double a = 0.37, b = 0.25, ang = 15 * M_PI / 180, ca = cos(ang), sa = sin(ang);
        for (int y = 0; y < FOOT_PX; y++)
            for (int x = 0; x < FOOT_PX; x++) {
                double u = (x + 0.5) / FOOT_PX - 0.5, v = (y + 0.5) / FOOT_PX - 0.5;
                double xr = ca * u + sa * v, yr = -sa * u + ca * v;
                double e = (xr / a) * (xr / a) + (yr / b) * (yr / b);
                size_t i = (size_t)y * FOOT_PX + (size_t)x;
                mask->data[i] = 1 - e + 0.6 * (noise->data[i] - 0.5) > 0 ? 1.f : 0.f;
            }
        ss_erosion_widths(FOOT_PX, FOOT_PX, 0, 9, seed, 302, widths);
        ss_erode(mask, widths, noise);
    }
    free(widths);
    ss_image_free(mask);
    if (st) {
        ss_image_free(noise);
        return NULL;
    }
    return noise;
}

static int heal_has_wound(const ss_heal_run_config *h) {
    return h->wound_mask || h->wound_stroke || h->wound_mesh || h->wound_footprint ||
           h->wound_depth_image || h->skin_mesh || h->wound_uv;
}

/* --heal DIR: a finished heal run instead of a simulation. The healing
 * problem then comes from DIR (the heal options must be left alone), every
 * requested day must be one of its snapshots, and its first snapshot (day 0)
 * is read now, so a damaged folder is an input error before anything is
 * written. */
static ss_status open_saved(job *j, ss_error *err) {
    const ss_wound_make_config *c = j->c;
    ss_heal_run_config def;
    ss_heal_run_config_default(&def);
    def.mechanics = c->heal.mechanics; /* --mechanics: see below */
    if (memcmp(&def, &c->heal, sizeof def))
        return ss_error_set(err, SS_ERR_INPUT,
                            "--heal %s: the healing problem comes from the run folder; leave out "
                            "the options of skinsim heal (--scenario, --stroke, --grid, ...)",
                            c->heal_dir);
    ss_status st = ss_heal_saved_run_open(c->heal_dir, &j->saved, err);
    if (st) return st;
    const ss_heal_saved_run *s = j->saved;
    double end = ss_heal_saved_run_end_day(s);
    for (int i = 0; i < c->ndays; i++) {
        if (c->days[i] > end + 1e-3 * ss_heal_saved_run_dt(s))
            return ss_error_set(err, SS_ERR_INPUT,
                                "--days: day %g is outside the run in --heal %s (simulated to "
                                "day %g)",
                                c->days[i], c->heal_dir, end);
        if (ss_heal_saved_run_find(s, c->days[i]) < 0)
            return ss_error_set(err, SS_ERR_INPUT,
                                "--days: --heal %s has no snapshot at day %g (snapshots every "
                                "%g days up to day %g; run skinsim heal with --snapshot-every)",
                                c->heal_dir, c->days[i],
                                ss_heal_saved_run_snapshot_count(s) > 1
                                    ? ss_heal_saved_run_snapshot_day(s, 1) -
                                          ss_heal_saved_run_snapshot_day(s, 0)
                                    : end,
                                end);
    }
    for (int i = 0; i < c->ndays; i++) { /* their files, before anything is written */
        ss_status st2 = ss_heal_saved_run_check(s, ss_heal_saved_run_find(s, c->days[i]), err);
        if (st2) return st2;
    }
    if (ss_heal_saved_run_snapshot_day(s, 0) > 1e-3 * ss_heal_saved_run_dt(s))
        return ss_error_set(err, SS_ERR_INPUT, "--heal %s: its first snapshot is not day 0",
                            c->heal_dir);
    if (!(j->grid0 = ss_heal_saved_run_load(s, 0, &j->disp0, &j->closed0, err))) return err->code;
    if ((c->mechanics || c->heal.mechanics) && !j->disp0)
        return ss_error_set(err, SS_ERR_INPUT,
                            "--mechanics: --heal %s was run without --mechanics (its snapshots "
                            "hold no displacement)",
                            c->heal_dir);
    return SS_OK;
}

static ss_status read_inputs(job *j, ss_error *err) {
    const ss_wound_make_config *c = j->c;
    ss_status st = check_days(c, err);
    if (st) return st;
    char def[4096];
    snprintf(def, sizeof def, "%s/modelmatch_default.sstab", ss_data_dir());
    j->table = ss_mm_table_read(c->table_path ? c->table_path : def, err);
    if (!j->table) return err->code;
    ss_wound_recipe_default(&j->recipe);
    if (c->recipe_path && (st = ss_wound_recipe_load(c->recipe_path, &j->recipe, err))) return st;
    if (c->heal_dir) {
        st = open_saved(j, err);
    } else { /* the heal run: in memory, to the last requested day (at least one step) */
        ss_heal_run_config hc = c->heal;
        hc.out_dir = NULL;
        hc.resume_dir = NULL;
        hc.mechanics = c->mechanics || c->heal.mechanics; /* the run's own coupled mechanics */
        double last = c->days[c->ndays - 1];
        hc.days = last > 0 ? last : 1;
        ss_image *foot = NULL;
        if (!heal_has_wound(&hc) && !(hc.wound_footprint = foot = default_footprint(c->seed, err)))
            return err->code;
        st = ss_heal_run_create(&hc, &j->run, err);
        ss_image_free(foot);
    }
    if (st) return st;
    const ss_heal_grid *g = job_grid(j);
    j->side_mm = g->nx * g->dx_mm;
    const ss_shell_patch *patch = j->run ? ss_heal_run_shell(j->run) : NULL;
    if (patch) { /* on a real body: the textures cover the mesh's UV layout */
        if (c->mechanics || c->heal.mechanics)
            return ss_error_set(err, SS_ERR_INPUT,
                                "--mechanics: not drawn on a --mesh's UV layout (yet); leave it "
                                "out, or heal a flat block");
        j->mesh = ss_heal_run_skin_mesh(j->run);
        if (!(j->columns = ss_wound_uv_columns(patch, j->mesh, c->size, &j->side_mm, err)))
            return err->code;
    } else if (fabs(g->ny * g->dx_mm - j->side_mm) > 1e-9 * j->side_mm)
        return ss_error_set(err, SS_ERR_INPUT,
                            "the heal block is %g x %g mm; the texture needs a square block "
                            "(--size-mm X,X,Z)",
                            j->side_mm, g->ny * g->dx_mm);
    for (int i = 0; i < c->ndays; i++) {
        long long k = llround(c->days[i] / job_dt(j));
        if (fabs(k * job_dt(j) - c->days[i]) > 1e-6 * (c->days[i] + 1))
            return ss_error_set(err, SS_ERR_INPUT,
                                "--days: %g is not a whole number of steps of %g days", c->days[i],
                                job_dt(j));
    }
    return read_skin(j, err);
}

/* The output folder and the inputs it must not overwrite (src/core/output.c). */
static ss_status declare_outputs(const ss_wound_make_config *c, ss_outputs *outs, ss_error *err) {
    const char *ins[] = {c->heal.wound_stroke,
                         c->heal.wound_mask,
                         c->heal.wound_mesh,
                         c->heal.params_path,
                         c->heal.wound_depth_image,
                         c->skin_path,
                         c->table_path,
                         c->recipe_path,
                         c->heal_dir,
                         c->heal.skin_mesh,
                         c->heal.wound_uv};
    ss_status st = SS_OK;
    for (size_t k = 0; k < sizeof ins / sizeof *ins && !st; k++)
        if (ins[k]) st = ss_outputs_input(outs, ins[k], err);
    /* per day: PNGs of about 9 bytes a texel before compression, EXRs 20 */
    double texels = (double)c->size * (double)c->size;
    double bytes = c->ndays * texels * (c->exr ? 29.0 : 9.0) + 4e6;
    if (!st) st = ss_outputs_add(outs, "--out", c->out_dir, SS_OUTPUT_DIR, bytes, err);
    return st;
}

/* ---- writing --------------------------------------------------------------------------- */

/* The height PNG has skinsim skin's encoding: 16-bit, 0..1 spans the frame's
 * height_min_mm..height_max_mm (written next to the file names in
 * timeline.json), here the frame's own range widened to at least
 * +-height_range, so it never clips and a flat frame is mid-grey. */
ss_status ss_wound_height_range(const ss_image *h, double range_mm, double *lo, double *hi) {
    double mn = -range_mm, mx = range_mm;
    size_t n = (size_t)h->width * (size_t)h->height;
    for (size_t i = 0; i < n; i++) {
        double v = h->data[i];
        if (!isfinite(v)) return SS_ERR_RUNTIME;
        mn = v < mn ? v : mn;
        mx = v > mx ? v : mx;
    }
    *lo = mn;
    *hi = mx;
    return SS_OK;
}

static ss_status write_frame(const char *dir, const char *stem, const ss_wound_textures *t,
                             double range_mm, int exr, cJSON *frame, cJSON *files, ss_error *err) {
    static const char *names[4] = {"base_color", "roughness", "height", "normal"};
    static const int bits[4] = {8, 8, 16, 8};
    ss_image *h01 = ss_image_create(t->height->width, t->height->height, 1, err);
    if (!h01) return err->code;
    size_t n = (size_t)t->height->width * (size_t)t->height->height;
    double lo, hi;
    if (ss_wound_height_range(t->height, range_mm, &lo, &hi)) {
        ss_image_free(h01);
        return ss_error_set(err, SS_ERR_RUNTIME, "%s: the height map is not finite", stem);
    }
    for (size_t i = 0; i < n; i++) h01->data[i] = (float)((t->height->data[i] - lo) / (hi - lo));
    cJSON_AddNumberToObject(frame, "height_min_mm", lo);
    cJSON_AddNumberToObject(frame, "height_max_mm", hi);
    const ss_image *imgs[4] = {t->base_color, t->roughness, h01, t->normal};
    const ss_image *raw[4] = {t->base_color, t->roughness, t->height, t->normal};
    ss_error errs[8];
    ss_status sts[8] = {0};
    int nfile = exr ? 8 : 4;
#pragma omp parallel for schedule(dynamic, 1)
    for (int k = 0; k < nfile; k++) {
        char path[4600];
        int m = k % 4;
        snprintf(path, sizeof path, "%s/%s_%s.%s", dir, stem, names[m], k < 4 ? "png" : "exr");
        sts[k] = k < 4 ? ss_png_write(path, imgs[m], bits[m], m == 0 ? SS_ENC_SRGB : SS_ENC_LINEAR,
                                      &errs[k])
                       : ss_exr_write(path, raw[m], 1, &errs[k]);
    }
    ss_image_free(h01);
    for (int k = 0; k < nfile; k++) {
        if (sts[k]) {
            *err = errs[k];
            return sts[k];
        }
        char rel[600], key[32];
        snprintf(rel, sizeof rel, "%s_%s.%s", stem, names[k % 4], k < 4 ? "png" : "exr");
        snprintf(key, sizeof key, "%s%s", names[k % 4], k < 4 ? "" : "_exr");
        cJSON_AddStringToObject(files, key, rel);
        if (k == 0) cJSON_AddStringToObject(files, "color", rel); /* abrasion's key */
    }
    return SS_OK;
}

/* glTF metallic-roughness: G = roughness, B = metallic 0, R unused (1). */
static ss_status write_gltf(const char *dir, const char *stem, const ss_wound_textures *t,
                            double side_mm, const ss_mesh *mesh, cJSON *files, ss_error *err) {
    int w = t->roughness->width, h = t->roughness->height;
    ss_image *mr = ss_image_create(w, h, 3, err);
    if (!mr) return err->code;
    for (size_t i = 0; i < (size_t)w * (size_t)h; i++) {
        mr->data[i * 3] = 1;
        mr->data[i * 3 + 1] = t->roughness->data[i];
    }
    char path[4600], rel[600];
    snprintf(rel, sizeof rel, "%s_metal_rough.png", stem);
    snprintf(path, sizeof path, "%s/%s", dir, rel);
    ss_status st = ss_png_write(path, mr, 8, SS_ENC_LINEAR, err);
    ss_image_free(mr);
    if (st) return st;
    cJSON_AddStringToObject(files, "metal_rough", rel);
    const char *base = strrchr(stem, '/') ? strrchr(stem, '/') + 1 : stem;
    char col[300], mrn[300], nrm[300];
    snprintf(col, sizeof col, "%s_base_color.png", base);
    snprintf(mrn, sizeof mrn, "%s_metal_rough.png", base);
    snprintf(nrm, sizeof nrm, "%s_normal.png", base);
    snprintf(rel, sizeof rel, "%s.gltf", stem);
    snprintf(path, sizeof path, "%s/%s", dir, rel);
    st = mesh ? ss_gltf_write_textured_mesh(path, mesh, base, col, mrn, nrm, err)
              : ss_gltf_write_textured_square(path, side_mm / 1000.0, base, col, mrn, nrm, err);
    if (!st) cJSON_AddStringToObject(files, "gltf", rel);
    return st;
}

static void day_label(double day, char *buf, size_t n) { snprintf(buf, n, "day %g", day); }

static ss_status write_sheet(const char *path, ss_image *const *tiles, const char *const *labels,
                             int n, int columns, ss_error *err) {
    ss_image *sheet =
        ss_contact_sheet((const ss_image *const *)tiles, labels, n, 256, columns, err);
    if (!sheet) return err->code;
    ss_status st = ss_png_write(path, sheet, 8, SS_ENC_SRGB, err);
    ss_image_free(sheet);
    return st;
}

/* The same wound through seed 000's abrasion phases (top row) and through the
 * simulation (bottom row), at the same days. */
static ss_status write_compare(job *j, const char *dir, const ss_image *mask0,
                               ss_image *const *wound_thumbs, ss_error *err) {
    const ss_wound_make_config *c = j->c;
    int size = c->size < 256 ? c->size : 256, n = c->ndays; /* the sheet's tile size */
    ss_wound_shape *shape = NULL;
    ss_status st;
    const char *strokes = c->heal.wound_stroke ? c->heal.wound_stroke : c->heal.wound_uv;
    if (strokes) { /* a flat block's strokes, or a mesh's UV strokes */
        ss_stroke_set ss;
        st = ss_stroke_csv_read(strokes, &ss, err);
        if (!st)
            st = ss_wound_shape_from_strokes(
                &ss, c->heal.concave_k ? SS_HULL_CONCAVE : SS_HULL_CONVEX,
                c->heal.concave_k ? c->heal.concave_k : 5, size, c->seed, &shape, err);
        ss_stroke_set_free(&ss);
    } else { /* the wound region of day 0 as a mask */
        st = ss_wound_shape_from_mask(mask0, size, c->seed, &shape, err);
    }
    ss_base_skin skin = {0};
    ss_abrasion *ab = NULL;
    ss_texture_set frame = {0};
    ss_abrasion_settings set;
    ss_abrasion_settings_default(&set);
    set.size = size;
    set.world_size_cm = j->side_mm / 10.0;
    set.seed = c->seed;
    ss_timeline tl;
    ss_timeline_default(&tl);
    if (!st) st = ss_base_skin_create(NULL, NULL, size, c->seed, &skin, err);
    if (!st) st = ss_abrasion_create(&set, &tl, shape, &skin, &ab, err);
    if (!st) st = ss_texture_set_create(size, &frame, err);
    ss_image **tiles = calloc((size_t)(2 * n), sizeof *tiles);
    char **labels = calloc((size_t)(2 * n), sizeof *labels);
    if (!st && (!tiles || !labels)) st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    for (int i = 0; !st && i < n; i++) {
        ss_texture_set col = {frame.color, NULL, NULL, NULL};
        st = ss_abrasion_frame(ab, c->days[i], &col, err);
        if (!st && !(tiles[i] = ss_image_clone(frame.color, err))) st = err->code;
        tiles[n + i] = wound_thumbs[i];
        char buf[64];
        snprintf(buf, sizeof buf, "abrasion, day %g", c->days[i]);
        labels[i] = strdup(buf);
        snprintf(buf, sizeof buf, "simulated, day %g", c->days[i]);
        labels[n + i] = strdup(buf);
        if (!labels[i] || !labels[n + i]) st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    char path[4600];
    snprintf(path, sizeof path, "%s/compare_abrasion.png", dir);
    if (!st) st = write_sheet(path, tiles, (const char *const *)labels, 2 * n, n, err);
    for (int i = 0; tiles && i < n; i++) ss_image_free(tiles[i]);
    for (int i = 0; labels && i < 2 * n; i++) free(labels[i]);
    free(tiles);
    free(labels);
    ss_texture_set_free(&frame);
    ss_abrasion_free(ab);
    ss_base_skin_free(&skin);
    ss_wound_shape_free(shape);
    return st;
}

/* ---- the run ----------------------------------------------------------------------------- */

/* Brings the tissue to `day`: steps the heal run there, or reads the saved
 * run's snapshot of that day, and observes it with the run's own closure
 * days (kept every step, so both are exact). *def receives the day's
 * per-texel deformation when the run has mechanics. */
static ss_status advance(job *j, double day, ss_progress *pr, ss_image **def, ss_error *err) {
    const ss_wound_make_config *c = j->c;
    ss_status st = SS_OK;
    *def = NULL;
    if (j->run) {
        /* in pieces of a fiftieth of the run (at least 2 days), for the
         * progress bar; each lands exactly (adaptive steps included) */
        double piece = fmax(2.0, c->days[c->ndays - 1] / 50.0);
        while (!st && ss_heal_run_day(j->run) < day - 1e-9 * (1 + day)) {
            double next = fmin(day, ss_heal_run_day(j->run) + piece);
            st = ss_heal_run_advance_to(j->run, next, err);
            ss_progress_update(pr, (double)ss_heal_run_step_index(j->run));
        }
        if (st) return st;
        ss_wound_tissue_observe_closure(j->tissue, ss_heal_run_grid(j->run),
                                        ss_heal_run_closure(j->run));
        ss_mech *mech = ss_heal_run_mech(j->run);
        if (mech && !(*def = ss_wound_deformation_from_grid(
                          ss_heal_run_grid(j->run), ss_mech_grid_displacement(mech), c->size, err)))
            st = err->code;
        return st;
    }
    int i = ss_heal_saved_run_find(j->saved, day);
    ss_heal_grid *g = j->grid0;
    float *disp = j->disp0;
    double *closed = j->closed0;
    if (i > 0 && !(g = ss_heal_saved_run_load(j->saved, i, &disp, &closed, err)))
        return err->code ? err->code : SS_ERR_RUNTIME;
    ss_wound_tissue_observe_closure(j->tissue, g, closed);
    ss_progress_update(pr, (double)i);
    if (disp) {
        size_t n = (size_t)g->nx * (size_t)g->ny * (size_t)g->nz;
        float *const comp[3] = {disp, disp + n, disp + 2 * n};
        if (!(*def = ss_wound_deformation_from_grid(g, comp, c->size, err))) st = err->code;
    }
    if (g != j->grid0) {
        ss_heal_grid_free(g);
        free(disp);
        free(closed);
    }
    return st;
}

static ss_status run_days(job *j, const char *dir, cJSON *frames, ss_image **thumbs,
                          ss_error *err) {
    const ss_wound_make_config *c = j->c;
    ss_wound_textures tex = {0};
    ss_status st = ss_wound_textures_create(c->size, &tex, err);
    ss_progress pr;
    double total = j->run ? (double)ss_heal_run_steps_total(j->run)
                          : (double)ss_heal_saved_run_find(j->saved, c->days[c->ndays - 1]);
    ss_progress_begin(&pr, "wound", total, c->quiet);
    double range = j->recipe.v[SS_WR_HEIGHT_RANGE_MM];
    for (int i = 0; !st && i < c->ndays; i++) {
        double t0 = ss_now();
        ss_image *def = NULL;
        st = advance(j, c->days[i], &pr, &def, err);
        double t1 = ss_now();
        if (!st) st = ss_wound_render(j->renderer, j->tissue, def, &tex, err);
        ss_image_free(def);
        double t2 = ss_now();
        char stem[128];
        snprintf(stem, sizeof stem, "frames/t%g", c->days[i]);
        cJSON *f = cJSON_CreateObject();
        cJSON_AddItemToArray(frames, f);
        cJSON_AddNumberToObject(f, "day", c->days[i]);
        cJSON_AddStringToObject(f, "phase", "simulated");
        cJSON *files = cJSON_AddObjectToObject(f, "files");
        if (!st) st = write_frame(dir, stem, &tex, range, c->exr, f, files, err);
        if (!st) st = write_gltf(dir, stem, &tex, j->side_mm, j->mesh, files, err);
        int ts = c->size < 512 ? c->size : 512;
        if (!st && !(thumbs[i] = ss_image_resize(tex.base_color, ts, ts, err))) st = err->code;
        j->t_heal += t1 - t0;
        j->t_render += t2 - t1;
        j->t_write += ss_now() - t2;
        cJSON_AddNumberToObject(f, "heal_s", t1 - t0);
        cJSON_AddNumberToObject(f, "texture_s", t2 - t1);
    }
    ss_progress_end(&pr);
    ss_wound_textures_free(&tex);
    return st;
}

static ss_status make(job *j, const char *dir, cJSON *sum, ss_error *err) {
    const ss_wound_make_config *c = j->c;
    ss_wound_render_options ro;
    ss_wound_render_options_default(&ro);
    ro.size = c->size;
    ro.side_mm = j->side_mm;
    ro.skin = j->skin;
    ro.table = j->table;
    ro.recipe = j->recipe;
    ro.seed = c->seed;
    double t0 = ss_now();
    ss_status st = ss_wound_renderer_create(&ro, &j->renderer, err);
    j->t_setup = ss_now() - t0;
    if (!st) {
        j->tissue = ss_wound_tissue_create(job_grid(j), job_params(j), &j->recipe, err);
        if (!j->tissue) st = err->code;
    }
    if (!st && j->columns) st = ss_wound_renderer_set_columns(j->renderer, j->columns, err);
    /* the wound region of day 0, for the abrasion comparison (over the block,
     * or over the UV layout through the column map) */
    ss_image *mask0 = NULL;
    const ss_wound_tissue *t = j->tissue;
    if (!st && j->columns) {
        if (!(mask0 = ss_image_create(c->size, c->size, 1, err))) st = err->code;
        for (size_t i = 0; !st && i < (size_t)c->size * (size_t)c->size; i++) {
            const float *cm = j->columns->data + 2 * i;
            long x = cm[0] == cm[0] ? lround(cm[0]) : -1, y = cm[0] == cm[0] ? lround(cm[1]) : -1;
            mask0->data[i] = x >= 0 && y >= 0 && x < t->nx && y < t->ny &&
                                     t->plasma[(size_t)y * (size_t)t->nx + (size_t)x] > 0.5f
                                 ? 1.f
                                 : 0.f;
        }
    } else if (!st && !(mask0 = ss_image_create(t->nx, t->ny, 1, err))) {
        st = err->code;
    }
    for (size_t i = 0; !st && !j->columns && i < (size_t)t->nx * (size_t)t->ny; i++)
        mask0->data[i] = t->plasma[i] > 0.5f ? 1.f : 0.f;
    char path[4600];
    snprintf(path, sizeof path, "%s/frames", dir);
    if (!st) st = ss_mkdir_p(path, err);
    ss_image **thumbs = calloc((size_t)c->ndays, sizeof *thumbs);
    char **labels = calloc((size_t)c->ndays, sizeof *labels);
    if (!thumbs || !labels) st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    cJSON *frames = cJSON_AddArrayToObject(sum, "frames");
    if (!st) st = run_days(j, dir, frames, thumbs, err);
    for (int i = 0; !st && i < c->ndays; i++) {
        char buf[64];
        day_label(c->days[i], buf, sizeof buf);
        if (!(labels[i] = strdup(buf))) st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    snprintf(path, sizeof path, "%s/contact_sheet.png", dir);
    if (!st)
        st = write_sheet(path, thumbs, (const char *const *)labels, c->ndays,
                         c->ndays <= 8 ? c->ndays : 8, err);
    t0 = ss_now();
    if (!st && c->compare) st = write_compare(j, dir, mask0, thumbs, err);
    j->t_compare = ss_now() - t0;
    ss_image_free(mask0);
    for (int i = 0; thumbs && i < c->ndays; i++) ss_image_free(thumbs[i]);
    for (int i = 0; labels && i < c->ndays; i++) free(labels[i]);
    free(thumbs);
    free(labels);
    return st;
}

static cJSON *summary_base(const job *j) {
    const ss_wound_make_config *c = j->c;
    cJSON *s = cJSON_CreateObject();
    cJSON_AddStringToObject(s, "command", "wound");
    cJSON_AddStringToObject(s, "scenario", job_scenario(j));
    if (c->heal_dir)
        cJSON_AddStringToObject(s, "heal_dir", c->heal_dir);
    else if (!heal_has_wound(&c->heal))
        cJSON_AddStringToObject(s, "wound",
                                "built-in irregular abrasion (0.74 x 0.5 of the block)");
    cJSON_AddArrayToObject(s,
                           "keys"); /* abrasion's key positions: none, every frame is simulated */
    cJSON_AddNumberToObject(s, "end_day", c->days[c->ndays - 1]);
    cJSON_AddNumberToObject(s, "size", c->size);
    cJSON_AddNumberToObject(s, "world_size_cm", j->side_mm / 10.0);
    cJSON_AddNumberToObject(s, "seed", (double)c->seed);
    cJSON_AddNumberToObject(s, "height_range_mm", j->recipe.v[SS_WR_HEIGHT_RANGE_MM]);
    cJSON_AddStringToObject(s, "height_encoding",
                            "16-bit PNG, value v in 0..1: height_mm = height_min_mm + v * "
                            "(height_max_mm - height_min_mm), per frame (as skinsim skin's "
                            "height.png); the range covers at least +-height_range_mm");
    cJSON_AddStringToObject(s, "base_skin", c->skin_path ? c->skin_path : "forearm (built-in)");
    cJSON *warn = cJSON_AddArrayToObject(s, "warnings");
    if (j->warning[0]) cJSON_AddItemToArray(warn, cJSON_CreateString(j->warning));
    if (j->mesh) {
        cJSON_AddStringToObject(s, "skin_mesh", c->heal.skin_mesh);
        cJSON_AddStringToObject(s, "texture_space", "the mesh's UV layout");
        cJSON_AddNumberToObject(s, "mm_per_uv", j->side_mm);
    }
    cJSON_AddBoolToObject(s, "mechanics",
                          j->run ? c->mechanics || c->heal.mechanics : j->disp0 != NULL);
    char *rj = ss_wound_recipe_to_json(&j->recipe);
    cJSON *r = rj ? cJSON_Parse(rj) : NULL;
    free(rj);
    if (r) cJSON_AddItemToObject(s, "recipe", cJSON_DetachItemFromObject(r, "recipe"));
    cJSON_Delete(r);
    return s;
}

ss_status ss_wound_make(const ss_wound_make_config *c, char **summary_json, ss_error *err) {
    if (summary_json) *summary_json = NULL;
    job j = {0};
    j.c = c;
    double t0 = ss_now();
    ss_outputs *outs = ss_outputs_create("wound", err);
    ss_status st = outs ? declare_outputs(c, outs, err) : err->code;
    if (!st) st = read_inputs(&j, err);
    if (!st) st = ss_outputs_begin(outs, err);
    if (st) {
        ss_outputs_free(outs);
        job_free(&j);
        return st;
    }
    /* everything is validated: from here on, failures are runtime errors */
    cJSON *sum = summary_base(&j);
    const char *staging = ss_outputs_path(outs, 0);
    st = make(&j, staging, sum, err);
    if (!st) {
        cJSON_AddNumberToObject(sum, "heal_s", j.t_heal);
        cJSON_AddNumberToObject(sum, "texture_s", j.t_render);
        cJSON_AddNumberToObject(sum, "write_s", j.t_write);
        cJSON_AddNumberToObject(sum, "setup_s", j.t_setup);
        cJSON_AddNumberToObject(sum, "compare_s", j.t_compare);
        cJSON_AddNumberToObject(sum, "total_s", ss_now() - t0);
        char *text = cJSON_Print(sum), path[4600];
        snprintf(path, sizeof path, "%s/timeline.json", staging);
        st = text ? ss_write_file_atomic(path, text, strlen(text), err)
                  : ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        free(text);
    }
    if (st && err->code == SS_ERR_INPUT) st = err->code = SS_ERR_RUNTIME;
    st = ss_outputs_finish(outs, st, err);
    ss_outputs_free(outs);
    if (!st && summary_json) *summary_json = cJSON_PrintUnformatted(sum);
    cJSON_Delete(sum);
    job_free(&j);
    return st;
}
