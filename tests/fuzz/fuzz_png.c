/* libFuzzer: PNG images (masks, skin textures, depth images), through
 * ss_png_read in both encodings; small images go on into a wound shape.
 * Header bombs must be refused before allocation (input error). */
#include "fuzz_util.h"
#include "skinsim/abrasion.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const char *path = fuzz_file(data, size, ".png");
    ss_error err;
    if (!path) return 0;
    for (int enc = 0; enc < 2; enc++) {
        ss_image *img = ss_png_read(path, enc ? SS_ENC_SRGB : SS_ENC_LINEAR, &err);
        if (img && !enc && img->width <= 256 && img->height <= 256) {
            ss_wound_shape *w = NULL;
            if (ss_wound_shape_from_mask(img, 32, 1, &w, &err) == SS_OK) ss_wound_shape_free(w);
        }
        ss_image_free(img);
    }
    return 0;
}
