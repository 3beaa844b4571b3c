/* libFuzzer: a heal snapshot (.vti, VTK ImageData with raw appended data)
 * through ss_heal_vti_read, the reader `wound --heal` uses for every frame:
 * the header scan (WholeExtent, Piece Extent, Spacing, TimeValue), each
 * DataArray's name, type, components and offset, and the appended blocks'
 * UInt64 sizes against the bytes present. A file without appended data, a
 * huge extent or a block running past the end must be refused by name. */
#include "fuzz_util.h"
#include "skinsim/heal_io.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    ss_error err;
    const char *path = fuzz_file(data, size, ".vti");
    if (!path) return 0;
    float *disp = NULL;
    double *closed = NULL;
    ss_heal_grid *g = ss_heal_vti_read(path, &disp, &closed, &err);
    ss_heal_grid_free(g);
    free(disp);
    free(closed);
    return 0;
}
