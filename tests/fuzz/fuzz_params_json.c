/* libFuzzer: heal parameter files (`heal --params`), through
 * ss_heal_params_parse for every scenario, and back to JSON. */
#include "fuzz_util.h"
#include "skinsim/heal.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    char *text = fuzz_text(data, size);
    if (!text) return 0;
    const char *sc[] = {NULL, "clean", "keloid"};
    ss_error err;
    for (int i = 0; i < 3; i++) {
        ss_heal_params *p = ss_heal_params_parse(text, "fuzz.json", sc[i], &err);
        if (p) {
            free(ss_heal_params_to_json(p));
            ss_heal_params_free(p);
        }
    }
    free(text);
    return 0;
}
