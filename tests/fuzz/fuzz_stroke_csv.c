/* libFuzzer: painted-stroke CSV (u,v[,stroke_id] per line), through
 * ss_stroke_csv_read and on into convex and concave hulls and the wound
 * shape, as `abrasion --stroke` and `heal --stroke` use them. */
#include "fuzz_util.h"
#include "skinsim/abrasion.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const char *path = fuzz_file(data, size, ".csv");
    ss_stroke_set s;
    ss_error err;
    if (!path || ss_stroke_csv_read(path, &s, &err) != SS_OK) return 0;
    for (int concave = 0; concave < 2; concave++) {
        ss_wound_shape *w = NULL;
        if (ss_wound_shape_from_strokes(&s, concave ? SS_HULL_CONCAVE : SS_HULL_CONVEX, 5, 32, 1,
                                        &w, &err) == SS_OK)
            ss_wound_shape_free(w);
    }
    ss_stroke_set_free(&s);
    return 0;
}
