/* libFuzzer: the .pvti of a snapshot in pieces (`wound --heal` on a run made
 * on MPI ranks), through ss_heal_pvti_check and ss_heal_pvti_read: the XML
 * scan, entity decoding of Source, the extents and the tiling check come
 * before any piece is opened; the pieces named do not exist (or are the
 * input itself), so each reader must refuse by name, without a crash. */
#include "fuzz_util.h"
#include "skinsim/heal_io.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    ss_error err;
    const char *path = fuzz_file(data, size, ".pvti");
    if (!path) return 0;
    ss_heal_pvti_check(path, &err);
    float *disp = NULL;
    double *closed = NULL;
    ss_heal_grid *g = ss_heal_pvti_read(path, &disp, &closed, &err);
    ss_heal_grid_free(g);
    free(disp);
    free(closed);
    return 0;
}
