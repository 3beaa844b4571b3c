/* libFuzzer: the abrasion timeline JSON (`abrasion --timeline`), through
 * ss_timeline_load_json, then located at a few days. */
#include "fuzz_util.h"
#include "skinsim/abrasion.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const char *path = fuzz_file(data, size, ".json");
    ss_timeline t;
    ss_error err;
    if (!path || ss_timeline_load_json(path, &t, &err) != SS_OK) return 0;
    const double days[] = {0, 0.01, 1, 7, 30, 1e5};
    for (size_t i = 0; i < sizeof days / sizeof *days; i++) (void)ss_timeline_locate(&t, days[i]);
    return 0;
}
