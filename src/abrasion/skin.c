/* Base skin textures (seed 000 §4.1): the "upper" healthy skin colour and the
 * "lower" dermis colour the wound phases draw from. Given as images, or made
 * procedurally: a base tone modulated by two value-noise layers, a broad
 * blotchiness (period ~1/8 of the reference texture) and fine pore-scale
 * grain, in linear light. Colours are sRGB values chosen to match the seed's
 * Fig. 4.1 (light skin; dermis a moist pink-red). */
#include "skinsim/abrasion.h"
#include "skinsim/texture.h"

#include <stdlib.h>

void ss_base_skin_free(ss_base_skin *b) {
    if (!b) return;
    ss_image_free(b->upper);
    ss_image_free(b->lower);
    ss_image_free(b->upper_srgb);
    ss_image_free(b->lower_srgb);
    free(b->palette);
    b->upper = b->lower = b->upper_srgb = b->lower_srgb = NULL;
    b->palette = NULL;
}

enum { STREAM_SKIN_BLOTCH = 0x51, STREAM_SKIN_GRAIN, STREAM_DERMIS_BLOTCH, STREAM_DERMIS_GRAIN };

static ss_status make_skin(int size, uint64_t seed, const float srgb[3], float blotch_amp,
                           float grain_amp, const float tint[3], uint64_t stream, ss_image **out,
                           ss_error *err) {
    ss_image *img = ss_image_create(size, size, 3, err);
    ss_image *blotch = img ? ss_image_create(size, size, 1, err) : NULL;
    ss_image *grain = blotch ? ss_image_create(size, size, 1, err) : NULL;
    if (!grain) {
        ss_image_free(img);
        ss_image_free(blotch);
        return err->code;
    }
    double k = size / 2048.0;
    ss_noise_params nb, ng;
    ss_noise_params_default(&nb);
    nb.octaves = 8;
    nb.persistence = 0.7f;
    nb.cell_px = (float)k;
    ss_noise_params_default(&ng);
    ng.octaves = 2;
    ng.persistence = 0.6f;
    ng.cell_px = (float)k;
    ss_status st = ss_value_noise(&nb, seed, stream, blotch, err);
    if (!st) st = ss_value_noise(&ng, seed, stream + 1, grain, err);
    if (!st) {
        float base[3];
        for (int c = 0; c < 3; c++) base[c] = ss_srgb_decode(srgb[c]);
        size_t n = (size_t)size * (size_t)size;
#pragma omp parallel for schedule(static)
        for (size_t i = 0; i < n; i++) {
            float b = (blotch->data[i] - 0.5f) * 2.0f, g = (grain->data[i] - 0.5f) * 2.0f;
            for (int c = 0; c < 3; c++) {
                float v = base[c] * (1.0f + blotch_amp * b * tint[c] + grain_amp * g);
                img->data[i * 3 + (size_t)c] = v < 0 ? 0 : v > 1 ? 1 : v;
            }
        }
    }
    ss_image_free(blotch);
    ss_image_free(grain);
    if (st) {
        ss_image_free(img);
        return st;
    }
    *out = img;
    return SS_OK;
}

ss_status ss_base_skin_create(const ss_image *upper_in, const ss_image *lower_in, int size,
                              uint64_t seed, ss_base_skin *out, ss_error *err) {
    out->upper = out->lower = out->upper_srgb = out->lower_srgb = NULL;
    out->palette = NULL;
    static const float skin_srgb[3] = {0.86f, 0.66f, 0.55f};   /* light skin */
    static const float skin_tint[3] = {0.6f, 1.0f, 1.1f};      /* blotches redden */
    static const float dermis_srgb[3] = {0.78f, 0.36f, 0.33f}; /* exposed dermis */
    static const float dermis_tint[3] = {0.5f, 1.0f, 1.0f};
    ss_status st = SS_OK;
    if (upper_in) {
        out->upper = ss_image_resize(upper_in, size, size, err);
        if (!out->upper) return err->code;
    } else {
        st = make_skin(size, seed, skin_srgb, 0.10f, 0.04f, skin_tint, STREAM_SKIN_BLOTCH,
                       &out->upper, err);
    }
    if (!st && lower_in) {
        out->lower = ss_image_resize(lower_in, size, size, err);
        if (!out->lower) st = err->code;
    } else if (!st) {
        st = make_skin(size, seed, dermis_srgb, 0.18f, 0.08f, dermis_tint, STREAM_DERMIS_BLOTCH,
                       &out->lower, err);
    }
    if (st) {
        ss_base_skin_free(out);
        return st;
    }
    /* Inputs of any channel count become RGB: grey is replicated, alpha
     * dropped (it is not a skin property here). */
    for (int k = 0; k < 2; k++) {
        ss_image **img = k ? &out->lower : &out->upper;
        int ch = (*img)->channels;
        if (ch != 3) {
            ss_image *rgb = ss_image_create(size, size, 3, err);
            if (!rgb) {
                ss_base_skin_free(out);
                return err->code;
            }
            size_t n = (size_t)size * (size_t)size;
            for (size_t i = 0; i < n; i++)
                for (int c = 0; c < 3; c++)
                    rgb->data[i * 3 + (size_t)c] =
                        (*img)->data[i * (size_t)ch + (size_t)(ch >= 3 ? c : 0)];
            ss_image_free(*img);
            *img = rgb;
        }
    }
    out->upper_srgb = ss_image_clone(out->upper, err);
    out->lower_srgb = out->upper_srgb ? ss_image_clone(out->lower, err) : NULL;
    if (!out->lower_srgb) {
        ss_base_skin_free(out);
        return err->code;
    }
    size_t n = (size_t)size * (size_t)size * 3;
    ss_srgb_encode_array(out->upper->data, out->upper_srgb->data, n);
    ss_srgb_encode_array(out->lower->data, out->lower_srgb->data, n);
    out->palette = malloc(sizeof *out->palette);
    ss_status st2 = out->palette ? ss_abrasion_palette_compute(out->upper, out->palette, err)
                                 : ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    if (st2) ss_base_skin_free(out);
    return st2;
}
