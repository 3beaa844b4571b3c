/* libFuzzer: OpenEXR images (masks, linear skin textures, depth in mm),
 * through ss_exr_read (OpenEXRCore, scanline files). */
#include "fuzz_util.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const char *path = fuzz_file(data, size, ".exr");
    ss_error err;
    if (!path) return 0;
    ss_image_free(ss_exr_read(path, &err));
    return 0;
}
