/* The Generate job (seed 000 §3-4, §4.2): from painted strokes, the five
 * key positions and maturation at the extra positions of layers.c, packed
 * into the layers the slider blends.
 *
 * Design (profiled at 2048^2 on 2 busy cores): the work is mostly memory
 * traffic, not arithmetic, so the fast path avoids whole-texture passes
 * and overlaps the steps that do not depend on each other:
 *   - the wound shape and the healthy skin are made at once (a thread for
 *     the skin; each step keeps its own OpenMP team);
 *   - maturation's key is rendered first; its eight extra positions then
 *     run in their own thread while the other four keys render;
 *   - outside the changed region (ss_abrasion_changed_region: the wound's
 *     box grown by the widest gradient) every key is the same healthy skin,
 *     so each layer is a copy of maturation's packed layer with only that
 *     region packed from the key's maps (the sRGB encode per texel was a
 *     third of the packing).
 * The reference path (SKINSIM_VIEW_REFERENCE=1) does each step in turn and
 * packs every layer whole; the two give the same bytes (e2e_view compares
 * their layers_hash). What it gave up: an extra texture set (128 MB at
 * 2048^2) for the maturation thread, and the threads oversubscribe the
 * cores briefly (OpenMP waits passively in the viewer, see app.c). */
#define _POSIX_C_SOURCE 200809L
#include "view.h"

#include "skinsim/wound.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const double MAT_POS[] = {0.0625, 0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 1.0};
#define NMAT ((int)(sizeof MAT_POS / sizeof MAT_POS[0]))

ss_image *view_strokes_mask(const ss_stroke_set *strokes, int size, uint64_t seed, ss_error *err) {
    ss_wound_shape *shape = NULL;
    if (ss_wound_shape_from_strokes(strokes, SS_HULL_CONVEX, 5, size, seed, &shape, err))
        return NULL;
    ss_image *m = shape->mask;
    shape->mask = NULL;
    ss_wound_shape_free(shape);
    return m;
}

/* The rectangle a layer differs from the healthy skin in. */
typedef struct rect {
    int x, y, w, h;
} rect;

/* Copies the packed layer src into layer dst, then packs r from the maps. */
static void pack_from(view_layers *l, int dst, int src, const ss_image *color, const ss_image *refl,
                      const ss_image *height, const ss_image *normal, rect r) {
    size_t plane = (size_t)l->size * (size_t)l->size * 4;
    memcpy(l->cr + plane * dst, l->cr + plane * src, plane);
    memcpy(l->nh + plane * dst, l->nh + plane * src, plane);
    if (r.w > 0 && r.h > 0)
        view_layers_pack_rect(l, dst, color, refl, height, normal, r.x, r.y, r.w, r.h);
}

/* Resets r of work from key (so maturation re-renders from the key colour)
 * and renders maturation's colour at position pos into it. */
static ss_status maturation_at(const ss_wound_shape *shape, const ss_base_skin *skin,
                               const ss_abrasion_settings *set, const ss_image *key, rect r,
                               double pos, ss_image *work, ss_error *err) {
    size_t ch = (size_t)key->channels, n = (size_t)key->width;
    for (int y = r.y; y < r.y + r.h; y++)
        memcpy(work->data + ((size_t)y * n + (size_t)r.x) * ch,
               key->data + ((size_t)y * n + (size_t)r.x) * ch, sizeof(float) * (size_t)r.w * ch);
    return ss_abrasion_maturation_color(shape, skin, set, pos, work, err);
}

/* ---- threads ------------------------------------------------------------------- */

typedef struct skin_job {
    const ss_image *in;
    int size;
    uint64_t seed;
    ss_base_skin skin;
    ss_status st;
    ss_error err;
} skin_job;

static void *skin_thread(void *p) {
    skin_job *j = p;
    j->st = ss_base_skin_create(j->in, NULL, j->size, j->seed, &j->skin, &j->err);
    return NULL;
}

/* The extra maturation positions, from maturation's key set (read only). */
typedef struct mat_job {
    const ss_wound_shape *shape;
    const ss_base_skin *skin;
    const ss_abrasion_settings *set;
    const ss_texture_set *key;
    view_layers *out;
    rect r;
    int done; /* positions finished (atomic), for the progress bar */
    ss_status st;
    ss_error err;
} mat_job;

static void *mat_thread(void *p) {
    mat_job *j = p;
    ss_image *work = ss_image_clone(j->key->color, &j->err);
    if (!work) {
        j->st = j->err.code ? j->err.code : SS_ERR_NOMEM;
        return NULL;
    }
    for (int i = 0; i < NMAT && !j->st; i++) {
        j->st = maturation_at(j->shape, j->skin, j->set, j->key->color, j->r, MAT_POS[i], work,
                              &j->err);
        if (!j->st)
            pack_from(j->out, SS_PHASE_COUNT + i, SS_PHASE_MATURATION, work, j->key->reflection,
                      j->key->height, j->key->normal, j->r);
        __atomic_add_fetch(&j->done, 1, __ATOMIC_RELAXED);
    }
    ss_image_free(work);
    return NULL;
}

/* ---- the two paths ---------------------------------------------------------------- */

/* One step after another, every layer packed whole. t: shape, skin, keys,
 * maturation positions finished. */
static ss_status generate_reference(const ss_stroke_set *strokes, const ss_image *skin_in,
                                    const ss_abrasion_settings *set, volatile double *progress,
                                    double steps, ss_wound_shape **shape, ss_base_skin *skin,
                                    view_layers *out, double t[4], ss_error *err) {
    int size = set->size;
    double done = 0;
    ss_texture_set ts = {0};
    ss_image *work = NULL;
    ss_status st =
        ss_wound_shape_from_strokes(strokes, SS_HULL_CONVEX, 5, size, set->seed, shape, err);
    if (progress) *progress = ++done / steps;
    t[0] = ss_now();
    if (!st) st = ss_base_skin_create(skin_in, NULL, size, set->seed, skin, err);
    if (progress) *progress = ++done / steps;
    t[1] = ss_now();
    if (!st) st = view_layers_alloc(out, size, SS_PHASE_COUNT + NMAT, err);
    if (!st) st = ss_texture_set_create(size, &ts, err);
    rect whole = {0, 0, size, size};
    for (int p = 0; p < SS_PHASE_COUNT && !st; p++) {
        st = ss_abrasion_render_phase((ss_phase)p, 0.0, *shape, skin, set, &ts, err);
        if (!st)
            view_layers_pack_rect(out, p, ts.color, ts.reflection, ts.height, ts.normal, 0, 0, size,
                                  size);
        if (progress) *progress = ++done / steps;
    }
    t[2] = ss_now();
    /* ts holds maturation's key now */
    rect r = {0};
    if (!st) ss_abrasion_changed_region(*shape, set, &r.x, &r.y, &r.w, &r.h);
    if (!st && !(work = ss_image_clone(ts.color, err))) st = err->code ? err->code : SS_ERR_NOMEM;
    for (int i = 0; i < NMAT && !st; i++) {
        st = maturation_at(*shape, skin, set, ts.color, r, MAT_POS[i], work, err);
        if (!st)
            view_layers_pack_rect(out, SS_PHASE_COUNT + i, work, ts.reflection, ts.height,
                                  ts.normal, whole.x, whole.y, whole.w, whole.h);
        if (progress) *progress = ++done / steps;
    }
    t[3] = ss_now();
    ss_image_free(work);
    ss_texture_set_free(&ts);
    return st;
}

static ss_status generate_fast(const ss_stroke_set *strokes, const ss_image *skin_in,
                               const ss_abrasion_settings *set, volatile double *progress,
                               double steps, ss_wound_shape **shape, ss_base_skin *skin,
                               view_layers *out, double t[4], ss_error *err) {
    int size = set->size;
    skin_job sj = {.in = skin_in, .size = size, .seed = set->seed};
    pthread_t skin_tid;
    int have_skin_thread = pthread_create(&skin_tid, NULL, skin_thread, &sj) == 0;
    ss_status st =
        ss_wound_shape_from_strokes(strokes, SS_HULL_CONVEX, 5, size, set->seed, shape, err);
    t[0] = ss_now();
    if (have_skin_thread)
        pthread_join(skin_tid, NULL);
    else
        skin_thread(&sj); /* no thread to be had: one after the other */
    *skin = sj.skin;
    if (!st && sj.st) {
        *err = sj.err;
        st = sj.st;
    }
    t[1] = ss_now();
    double done = 2;
    if (progress) *progress = done / steps;
    ss_texture_set key = {0}, ts = {0};
    if (!st) st = view_layers_alloc(out, size, SS_PHASE_COUNT + NMAT, err);
    if (!st) st = ss_texture_set_create(size, &key, err);
    if (!st) st = ss_texture_set_create(size, &ts, err);
    if (!st) st = ss_abrasion_render_phase(SS_PHASE_MATURATION, 0.0, *shape, skin, set, &key, err);
    if (!st)
        view_layers_pack_rect(out, SS_PHASE_MATURATION, key.color, key.reflection, key.height,
                              key.normal, 0, 0, size, size);
    if (progress) *progress = ++done / steps;
    mat_job mj = {.shape = *shape, .skin = skin, .set = set, .key = &key, .out = out};
    if (!st) ss_abrasion_changed_region(*shape, set, &mj.r.x, &mj.r.y, &mj.r.w, &mj.r.h);
    pthread_t mat_tid;
    int have_mat_thread = !st && pthread_create(&mat_tid, NULL, mat_thread, &mj) == 0;
    for (int p = 0; p < SS_PHASE_MATURATION && !st; p++) {
        st = ss_abrasion_render_phase((ss_phase)p, 0.0, *shape, skin, set, &ts, err);
        if (!st)
            pack_from(out, p, SS_PHASE_MATURATION, ts.color, ts.reflection, ts.height, ts.normal,
                      mj.r);
        if (progress) *progress = (++done + __atomic_load_n(&mj.done, __ATOMIC_RELAXED)) / steps;
    }
    t[2] = ss_now();
    if (have_mat_thread)
        pthread_join(mat_tid, NULL);
    else if (!st)
        mat_thread(&mj);
    if (!st && mj.st) {
        *err = mj.err;
        st = mj.st;
    }
    t[3] = ss_now();
    ss_texture_set_free(&ts);
    ss_texture_set_free(&key);
    return st;
}

ss_status view_layers_generate(const ss_stroke_set *strokes, const ss_image *skin_in, int size,
                               uint64_t seed, volatile double *progress, view_layers *out,
                               ss_error *err) {
    memset(out, 0, sizeof *out);
    const double steps = 2 + SS_PHASE_COUNT + NMAT;
    if (progress) *progress = 0;
    ss_abrasion_settings set;
    ss_abrasion_settings_default(&set);
    set.size = size;
    set.seed = seed;
    ss_timeline tl;
    ss_timeline_default(&tl);
    ss_wound_shape *shape = NULL;
    ss_base_skin skin = {0};
    const char *ref = getenv("SKINSIM_VIEW_REFERENCE");
    int reference = ref && *ref && strcmp(ref, "0") != 0;
    double t0 = ss_now(), t[4];
    ss_status st = (reference ? generate_reference : generate_fast)(
        strokes, skin_in, &set, progress, steps, &shape, &skin, out, t, err);
    if (!st) {
        double mat_day = 0;
        for (int k = 0; k < tl.nkeys; k++) {
            view_layers_add_stop(out, tl.key[k].day, (int)tl.key[k].phase,
                                 ss_phase_name(tl.key[k].phase));
            if (tl.key[k].phase == SS_PHASE_MATURATION) mat_day = tl.key[k].day;
        }
        for (int i = 0; i < NMAT; i++)
            view_layers_add_stop(out, mat_day + MAT_POS[i] * (tl.end_day - mat_day),
                                 SS_PHASE_COUNT + i, "maturation");
        out->end_day = tl.end_day;
        out->height_mm = set.scab_height_mm;
        snprintf(out->source, sizeof out->source, "%d painted stroke(s), %d^2%s", strokes->nstrokes,
                 size, skin_in ? ", on the loaded skin" : "");
        view_layers_build_mips(out, NULL); /* on failure OpenGL makes the levels */
        double t5 = ss_now();
        if (reference)
            snprintf(out->timing, sizeof out->timing,
                     "%.2f s, reference path: shape %.2f, skin %.2f, phases %.2f, maturation "
                     "%.2f, mipmaps %.2f",
                     t5 - t0, t[0] - t0, t[1] - t[0], t[2] - t[1], t[3] - t[2], t5 - t[3]);
        else
            snprintf(out->timing, sizeof out->timing,
                     "%.2f s: shape %.2f with skin %.2f, phases %.2f, maturation %.2f more, "
                     "mipmaps %.2f",
                     t5 - t0, t[0] - t0, t[1] - t0, t[2] - t[1], t[3] - t[2], t5 - t[3]);
    } else {
        view_layers_free(out);
    }
    ss_base_skin_free(&skin);
    ss_wound_shape_free(shape);
    return st;
}
