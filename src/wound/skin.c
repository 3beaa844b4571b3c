/* The base skin a wound is drawn on, as bio-parameter maps (seed 003 §5.2):
 * the channel order of `skinsim skin`'s bio.exr, a validator for maps read
 * from files, and the built-in baseline used until procedural skin features
 * (seed 003 §4.8) are plugged in with --skin: a light skin (melanin 0.03,
 * blood 0.01, the default oxygenation and layer thicknesses of the optics
 * model) mottled by value noise (seed 000 §3.3): melanin +-20 % at ~2 mm,
 * blood +-25 % at ~5 mm, and a 0.02 mm relief at ~0.3 mm.
 *
 * Design: noise periods are set in mm through the texel size, so the skin looks
 * the same at any texture size; deterministic per (seed, stream). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdlib.h>

#include "skinsim/texture.h"
#include "skinsim/wound.h"

static ss_status noise(int size, double side_mm, double period_mm, int octaves, uint64_t seed,
                       uint64_t stream, ss_image *out, ss_error *err) {
    ss_noise_params p;
    ss_noise_params_default(&p);
    p.octaves = octaves;
    /* base cell of 2^octaves cells, the coarsest period about period_mm */
    double px_per_mm = size / side_mm;
    double cell = period_mm * px_per_mm / (double)(1 << octaves);
    p.cell_px = (float)(cell < 1 ? 1 : cell);
    return ss_value_noise(&p, seed, stream, out, err);
}

ss_image *ss_wound_default_skin(int size, double side_mm, uint64_t seed, ss_error *err) {
    if (size < 1 || !(side_mm > 0)) {
        ss_error_set(err, SS_ERR_INPUT, "default skin: size %d, side %g mm", size, side_mm);
        return NULL;
    }
    ss_image *bio = ss_image_create(size, size, SS_BIO_NCHANNELS, err);
    ss_image *n1 = bio ? ss_image_create(size, size, 1, err) : NULL;
    ss_image *n2 = n1 ? ss_image_create(size, size, 1, err) : NULL;
    ss_image *n3 = n2 ? ss_image_create(size, size, 1, err) : NULL;
    ss_status st = n3 ? SS_OK : (err->code ? err->code : SS_ERR_NOMEM);
    if (!st) st = noise(size, side_mm, 8.0, 3, seed, 101, n1, err);
    if (!st) st = noise(size, side_mm, 20.0, 2, seed, 102, n2, err);
    if (!st) st = noise(size, side_mm, 1.2, 2, seed, 103, n3, err);
    if (!st) {
        ss_bio_params d;
        ss_bio_params_default(&d);
        size_t n = (size_t)size * (size_t)size;
        for (size_t i = 0; i < n; i++) {
            float *b = bio->data + i * SS_BIO_NCHANNELS;
            b[SS_BIO_MELANIN] = 0.03f * (1.0f + 0.4f * (n1->data[i] - 0.5f));
            b[SS_BIO_PHEOMELANIN] = (float)d.pheomelanin_ratio;
            b[SS_BIO_BLOOD] = 0.01f * (1.0f + 0.5f * (n2->data[i] - 0.5f));
            b[SS_BIO_OXYGENATION] = (float)d.oxygenation;
            b[SS_BIO_SC_CM] = (float)d.sc_thickness_cm;
            b[SS_BIO_EPIDERMIS_CM] = (float)d.epidermis_thickness_cm;
            b[SS_BIO_HEIGHT_MM] = 0.04f * (n3->data[i] - 0.5f);
        }
    }
    ss_image_free(n1);
    ss_image_free(n2);
    ss_image_free(n3);
    if (st) {
        ss_image_free(bio);
        return NULL;
    }
    return bio;
}

ss_status ss_wound_skin_validate(const ss_image *bio, const char *name, ss_error *err) {
    if (!bio || bio->channels != SS_BIO_NCHANNELS)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: a base skin needs %d channels (melanin, pheomelanin, blood, "
                            "oxygenation, sc_cm, epidermis_cm, height_mm), not %d",
                            name, SS_BIO_NCHANNELS, bio ? bio->channels : 0);
    size_t n = (size_t)bio->width * (size_t)bio->height;
    for (size_t i = 0; i < n; i++) {
        const float *b = bio->data + i * SS_BIO_NCHANNELS;
        for (int c = 0; c < SS_BIO_NCHANNELS; c++) {
            int frac = c <= SS_BIO_OXYGENATION,
                thick = c == SS_BIO_SC_CM || c == SS_BIO_EPIDERMIS_CM;
            if (!isfinite(b[c]) || (frac && (b[c] < 0 || b[c] > 1)) || (thick && !(b[c] > 0)))
                return ss_error_set(err, SS_ERR_INPUT,
                                    "%s: texel (%zu, %zu) channel %d has %g (fractions 0..1, "
                                    "thicknesses > 0, all finite)",
                                    name, i % (size_t)bio->width, i / (size_t)bio->width, c,
                                    (double)b[c]);
        }
    }
    return SS_OK;
}
