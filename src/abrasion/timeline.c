/* The timeline of key positions (seed 000 §3.2, Fig. 3.1 and 4.4): keys with
 * a phase and a day; a time between two keys is their linear blend; two keys
 * of the same phase hold it; maturation is re-rendered at its position from
 * its key to the end of the timeline (§4.3.5). Default days follow the
 * physiology of seed §2.1 (docs/abrasion.md). */
#include "skinsim/abrasion.h"
#include "abrasion_internal.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MINUTE (1.0 / 1440.0)

void ss_timeline_default(ss_timeline *t) {
    static const ss_timeline_key keys[] = {
        {SS_PHASE_VASOCONSTRICTION, 0.0},        /* injury: vessels narrow ... */
        {SS_PHASE_VASOCONSTRICTION, 5 * MINUTE}, /* ... for 5-10 minutes */
        {SS_PHASE_VASODILATION, 10 * MINUTE},    /* then dilate, redder, ... */
        {SS_PHASE_VASODILATION, 30 * MINUTE},    /* ... for about 20 minutes */
        {SS_PHASE_SCAB_FORMING, 0.5},            /* the bed dries over hours */
        {SS_PHASE_SCAB_FORMING, 1.0},
        {SS_PHASE_SCAB, 3.0},                      /* a scab within days */
        {SS_PHASE_SCAB, 10.0},                     /* holds while the wound contracts */
        {SS_PHASE_MATURATION, 10.0 + 10 * MINUTE}, /* scab falls off: the jump */
    };
    t->nkeys = (int)(sizeof keys / sizeof keys[0]);
    memcpy(t->key, keys, sizeof keys);
    t->end_day = 30.0; /* maturation runs out about three weeks later */
}

ss_status ss_timeline_validate(const ss_timeline *t, ss_error *err) {
    if (t->nkeys < 2 || t->nkeys > SS_TIMELINE_MAX_KEYS)
        return ss_error_set(err, SS_ERR_INPUT, "timeline: %d keys; need 2..%d", t->nkeys,
                            SS_TIMELINE_MAX_KEYS);
    for (int i = 0; i < t->nkeys; i++) {
        if ((unsigned)t->key[i].phase >= SS_PHASE_COUNT)
            return ss_error_set(err, SS_ERR_INPUT, "timeline: key %d has an unknown phase", i);
        if (!isfinite(t->key[i].day) || t->key[i].day < 0)
            return ss_error_set(err, SS_ERR_INPUT, "timeline: key %d day must be finite and >= 0",
                                i);
        if (i && !(t->key[i].day > t->key[i - 1].day))
            return ss_error_set(err, SS_ERR_INPUT,
                                "timeline: key %d (day %g) is not after key %d (day %g)", i,
                                t->key[i].day, i - 1, t->key[i - 1].day);
        if (t->key[i].phase == SS_PHASE_MATURATION && i != t->nkeys - 1)
            return ss_error_set(err, SS_ERR_INPUT,
                                "timeline: maturation must be the last key (it runs to end_day)");
    }
    if (!isfinite(t->end_day) || t->end_day <= t->key[t->nkeys - 1].day)
        return ss_error_set(err, SS_ERR_INPUT,
                            "timeline: end_day %g must be after the last key (day %g)", t->end_day,
                            t->key[t->nkeys - 1].day);
    return SS_OK;
}

ss_status ss_timeline_load_json(const char *path, ss_timeline *t, ss_error *err) {
    char *text = ss_read_file_max(path, NULL, SS_READ_MAX_CONFIG, err);
    if (!text) return SS_ERR_INPUT;
    cJSON *root = cJSON_Parse(text);
    free(text);
    if (!root || !cJSON_IsObject(root)) {
        cJSON_Delete(root);
        return ss_error_set(err, SS_ERR_INPUT, "%s: not a JSON object", path);
    }
    ss_timeline nt;
    ss_timeline_default(&nt);
    ss_status st = SS_OK;
    const cJSON *keys = cJSON_GetObjectItemCaseSensitive(root, "keys");
    if (keys) {
        if (!cJSON_IsArray(keys)) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s: \"keys\" must be an array", path);
        } else {
            nt.nkeys = 0;
            const cJSON *k;
            cJSON_ArrayForEach(k, keys) {
                if (nt.nkeys == SS_TIMELINE_MAX_KEYS) {
                    st = ss_error_set(err, SS_ERR_INPUT, "%s: more than %d keys", path,
                                      SS_TIMELINE_MAX_KEYS);
                    break;
                }
                const cJSON *ph = cJSON_GetObjectItemCaseSensitive(k, "phase");
                const cJSON *day = cJSON_GetObjectItemCaseSensitive(k, "day");
                int p = cJSON_IsString(ph) ? ss_phase_from_name(ph->valuestring) : -1;
                if (p < 0) {
                    st = ss_error_set(err, SS_ERR_INPUT,
                                      "%s: key %d: \"phase\" must be one of vasoconstriction, "
                                      "vasodilation, scab_forming, scab, maturation",
                                      path, nt.nkeys);
                    break;
                }
                if (!cJSON_IsNumber(day)) {
                    st = ss_error_set(err, SS_ERR_INPUT, "%s: key %d: \"day\" must be a number",
                                      path, nt.nkeys);
                    break;
                }
                nt.key[nt.nkeys].phase = (ss_phase)p;
                nt.key[nt.nkeys].day = day->valuedouble;
                nt.nkeys++;
            }
        }
    }
    const cJSON *end = cJSON_GetObjectItemCaseSensitive(root, "end_day");
    if (!st && end) {
        if (!cJSON_IsNumber(end))
            st = ss_error_set(err, SS_ERR_INPUT, "%s: \"end_day\" must be a number", path);
        else
            nt.end_day = end->valuedouble;
    }
    cJSON_Delete(root);
    if (!st) {
        ss_error e2;
        if (ss_timeline_validate(&nt, &e2))
            st = ss_error_set(err, SS_ERR_INPUT, "%s: %s", path, e2.msg);
    }
    if (!st) *t = nt;
    return st;
}

ss_timeline_pos ss_timeline_locate(const ss_timeline *t, double day) {
    ss_timeline_pos p = {0, 0, 0.0, 0, 0.0};
    int last = t->nkeys - 1;
    if (t->key[last].phase == SS_PHASE_MATURATION && day >= t->key[last].day) {
        p.key_a = p.key_b = last;
        p.in_maturation = 1;
        double span = t->end_day - t->key[last].day;
        double pos = span > 0 ? (day - t->key[last].day) / span : 1.0;
        p.maturation_pos = pos < 0 ? 0 : pos > 1 ? 1 : pos;
        return p;
    }
    if (day <= t->key[0].day) return p;
    if (day >= t->key[last].day) {
        p.key_a = p.key_b = last;
        return p;
    }
    int i = 0;
    while (i + 1 < last && day >= t->key[i + 1].day) i++;
    p.key_a = i;
    p.key_b = i + 1;
    p.weight = (day - t->key[i].day) / (t->key[i + 1].day - t->key[i].day);
    return p;
}

void ss_abrasion_free(ss_abrasion *a) {
    if (!a) return;
    for (int p = 0; p < SS_PHASE_COUNT; p++) ss_texture_set_free(&a->phase[p]);
    free(a);
}

ss_status ss_abrasion_create(const ss_abrasion_settings *s, const ss_timeline *t,
                             const ss_wound_shape *w, const ss_base_skin *skin, ss_abrasion **out,
                             ss_error *err) {
    *out = NULL;
    ss_status st = ss_timeline_validate(t, err);
    if (st) return st;
    ss_abrasion *a = calloc(1, sizeof *a);
    if (!a) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    a->settings = *s;
    a->timeline = *t;
    a->shape = w;
    a->skin = skin;
    for (int i = 0; i < t->nkeys && !st; i++) {
        ss_phase ph = t->key[i].phase;
        if (a->rendered[ph]) continue;
        st = ss_texture_set_create(s->size, &a->phase[ph], err);
        a->rendered[ph] = !st;
    }
    if (!st) st = ss_abrasion_update(a, w, err);
    if (st) {
        ss_abrasion_free(a);
        return st;
    }
    *out = a;
    return SS_OK;
}

ss_status ss_abrasion_update(ss_abrasion *a, const ss_wound_shape *w, ss_error *err) {
    if (w->size != a->settings.size)
        return ss_error_set(err, SS_ERR_INPUT, "wound shape size %d differs from the timeline's %d",
                            w->size, a->settings.size);
    a->shape = w;
    for (int ph = 0; ph < SS_PHASE_COUNT; ph++) {
        if (!a->rendered[ph]) continue;
        ss_status st = ss_abrasion_render_phase((ss_phase)ph, 0.0, w, a->skin, &a->settings,
                                                &a->phase[ph], err);
        if (st) return st;
    }
    return SS_OK;
}

/* Row-parallel copy of whole images (memcpy of one big block is serial). */
static void copy_image(const ss_image *src, ss_image *dst) {
    size_t row = (size_t)src->width * (size_t)src->channels;
#pragma omp parallel for schedule(static)
    for (int y = 0; y < src->height; y++)
        memcpy(dst->data + (size_t)y * row, src->data + (size_t)y * row, row * sizeof(float));
}

/* Maps left NULL in dst are skipped. */
static void copy_set(const ss_texture_set *src, ss_texture_set *dst, int color) {
    if (color) copy_image(src->color, dst->color);
    if (dst->reflection) copy_image(src->reflection, dst->reflection);
    if (dst->height) copy_image(src->height, dst->height);
    if (dst->normal) copy_image(src->normal, dst->normal);
}

/* Outside the changed region both keys are the same healthy skin, so that
 * part is copied and only the region is blended. normal: renormalise the
 * blend so the map stays unit length. */
typedef struct region {
    int x, y, w, h;
} region;

static void blend_map(const ss_image *a, const ss_image *b, float t, ss_image *out, region r,
                      int normal) {
    int n = a->width, ch = a->channels;
    size_t row = (size_t)n * (size_t)ch;
#pragma omp parallel for schedule(static)
    for (int y = 0; y < a->height; y++) {
        const float *pa = a->data + (size_t)y * row, *pb = b->data + (size_t)y * row;
        float *po = out->data + (size_t)y * row;
        if (y < r.y || y >= r.y + r.h || r.w == 0) {
            memcpy(po, pa, row * sizeof(float));
            continue;
        }
        size_t lo = (size_t)r.x * (size_t)ch, hi = (size_t)(r.x + r.w) * (size_t)ch;
        memcpy(po, pa, lo * sizeof(float));
        memcpy(po + hi, pa + hi, (row - hi) * sizeof(float));
        if (!normal) {
            for (size_t i = lo; i < hi; i++) po[i] = pa[i] + (pb[i] - pa[i]) * t;
            continue;
        }
        for (size_t i = lo; i < hi; i += 3) {
            float v[3];
            for (int k = 0; k < 3; k++)
                v[k] = 2.0f * (pa[i + k] + (pb[i + k] - pa[i + k]) * t) - 1.0f;
            float len = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            float inv = len > 1e-12f ? 1.0f / len : 0.0f;
            for (int k = 0; k < 3; k++) po[i + k] = 0.5f + 0.5f * v[k] * inv;
        }
    }
}

ss_status ss_abrasion_frame(const ss_abrasion *a, double day, ss_texture_set *out, ss_error *err) {
    return ss_abrasion_frame_poll(a, day, out, NULL, NULL, err);
}

/* the poll between maps: stop (SS_ERR_RUNTIME) when fn says so */
static int frame_stop(ss_progress_fn fn, void *user, double fraction, ss_error *err) {
    if (fn && fn(user, fraction)) {
        ss_error_set(err, SS_ERR_RUNTIME, "abrasion frame: cancelled");
        return 1;
    }
    return 0;
}

ss_status ss_abrasion_frame_poll(const ss_abrasion *a, double day, ss_texture_set *out,
                                 ss_progress_fn fn, void *user, ss_error *err) {
    if (!isfinite(day) || day < 0)
        return ss_error_set(err, SS_ERR_INPUT, "time %g days must be finite and >= 0", day);
    int n = a->settings.size;
    const ss_image *maps[4] = {out->color, out->reflection, out->height, out->normal};
    if (!out->color) return ss_error_set(err, SS_ERR_INPUT, "frame output has no colour image");
    for (int k = 0; k < 4; k++)
        if (maps[k] && (maps[k]->width != n || maps[k]->height != n))
            return ss_error_set(err, SS_ERR_INPUT, "frame output size differs from %d", n);
    ss_timeline_pos p = ss_timeline_locate(&a->timeline, day);
    const ss_texture_set *ka = &a->phase[a->timeline.key[p.key_a].phase];
    const ss_texture_set *kb = &a->phase[a->timeline.key[p.key_b].phase];
    if (p.in_maturation) {
        copy_set(ka, out, 1);
        if (frame_stop(fn, user, 0.0, err)) return err->code;
        const ss_timeline *tl = &a->timeline;
        double start = tl->key[tl->nkeys - 1].day, span = tl->end_day - start;
        ss_status st = abrasion_maturation_at_poll(
            a->shape, a->skin, &a->settings, p.maturation_pos, span > 0 ? span : 0,
            day > tl->end_day ? day - tl->end_day : 0, out->color, out->reflection, fn, user, err);
        return st;
    }
    if (ka == kb || p.weight <= 0.0) {
        copy_set(ka, out, 1);
        if (fn) fn(user, 1.0); /* done: a stop now changes nothing */
        return SS_OK;
    }
    region r;
    ss_abrasion_changed_region(a->shape, &a->settings, &r.x, &r.y, &r.w, &r.h);
    float w = (float)p.weight;
    blend_map(ka->color, kb->color, w, out->color, r, 0);
    if (frame_stop(fn, user, 0.25, err)) return err->code;
    if (out->reflection) blend_map(ka->reflection, kb->reflection, w, out->reflection, r, 0);
    if (frame_stop(fn, user, 0.5, err)) return err->code;
    if (out->height) blend_map(ka->height, kb->height, w, out->height, r, 0);
    if (frame_stop(fn, user, 0.75, err)) return err->code;
    if (out->normal) blend_map(ka->normal, kb->normal, w, out->normal, r, 1);
    if (fn) fn(user, 1.0);
    return SS_OK;
}
