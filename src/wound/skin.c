/* The base skin a wound is drawn on, as bio-parameter maps (seed 003 §5.2,
 * skinsim/skin.h): reading `skinsim skin`'s bio.exr by channel name, a
 * validator for maps from files, and value noise with its period in mm (seed
 * 000 §3.3) for the renderer's uneven crust.
 *
 * Design: noise periods are set in mm through the texel size, so the look is
 * the same at any texture size; deterministic per (seed, stream). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>

#include "skinsim/texture.h"
#include "wound_internal.h"

/* The finest noise period, in texels (Nyquist: 2). */
#define NOISE_MIN_PX 2.0

ss_status ss_wound__noise(int size, double side_mm, double period_mm, int octaves, uint64_t seed,
                          uint64_t stream, ss_image *out, ss_error *err) {
    ss_noise_params p;
    ss_noise_params_default(&p);
    p.octaves = octaves;
    /* base cell of 2^octaves cells, the coarsest period about period_mm */
    double px_per_mm = size / side_mm;
    double cell = period_mm * px_per_mm / (double)(1 << octaves);
    /* band limit: the finest octave's period at least NOISE_MIN_PX texels.
     * Finer octaves would alias into texel-sized speckle (on a mesh's UV
     * layout a texel is 0.3-0.7 mm: the jitter of the tissue sampling then
     * left isolated texels along a wound's rim); they are dropped, the
     * coarser ones keep their period in mm. */
    while (cell < NOISE_MIN_PX && p.octaves > 0) p.octaves--, cell *= 2;
    p.cell_px = (float)(cell < NOISE_MIN_PX ? NOISE_MIN_PX : cell);
    return ss_value_noise(&p, seed, stream, out, err);
}

ss_status ss_wound_skin_validate(const ss_image *bio, const char *name, ss_error *err) {
    if (!bio || bio->channels != SS_BIO_NCHANNELS)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: a base skin needs the %d channels of a skin bio map, not %d", name,
                            SS_BIO_NCHANNELS, bio ? bio->channels : 0);
    size_t n = (size_t)bio->width * (size_t)bio->height;
    for (size_t i = 0; i < n; i++) {
        const float *b = bio->data + i * SS_BIO_NCHANNELS;
        for (int c = 0; c < SS_BIO_NCHANNELS; c++) {
            int frac = c <= SS_BIO_OXYGENATION || c >= SS_BIO_EXTRA_R,
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

ss_image *ss_wound_skin_read(const char *path, ss_error *err) {
    char file[4200];
    struct stat sb;
    if (stat(path, &sb) == 0 && S_ISDIR(sb.st_mode))
        snprintf(file, sizeof file, "%s/bio.exr", path);
    else
        snprintf(file, sizeof file, "%s", path);
    const char *names[SS_BIO_NCHANNELS];
    for (int c = 0; c < SS_BIO_NCHANNELS; c++) names[c] = ss_bio_channel_name(c);
    ss_image *bio = ss_exr_read_channels(file, names, SS_BIO_NCHANNELS, err);
    if (bio && ss_wound_skin_validate(bio, file, err)) {
        ss_image_free(bio);
        return NULL;
    }
    return bio;
}

ss_image *ss_wound_default_skin(int size, double side_mm, uint64_t seed, ss_error *err) {
    if (!(side_mm > 0)) {
        ss_error_set(err, SS_ERR_INPUT, "default skin: side %g mm must be > 0", side_mm);
        return NULL;
    }
    return ss_skin_bio_default(size, side_mm / 10.0, seed, err);
}
