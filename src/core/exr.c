/* OpenEXR read/write through OpenEXR's C API (OpenEXRCore). */
#include "skinsim/core.h"

ss_status ss_exr_write(const char *path, const ss_image *img, int use_half, ss_error *err) {
    (void)img;
    (void)use_half;
    return ss_error_set(err, SS_ERR_RUNTIME, "%s: EXR output is not built yet", path);
}

ss_image *ss_exr_read(const char *path, ss_error *err) {
    ss_error_set(err, SS_ERR_RUNTIME, "%s: EXR input is not built yet", path);
    return NULL;
}
