/* libFuzzer: skin's features.csv (`skinsim skin --features-in`), through
 * ss_skin_features_read_csv and on into the bio maps of a small texture, as
 * the command renders a list a user edited. */
#include "fuzz_util.h"
#include "skinsim/skin.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    const char *path = fuzz_file(data, size, ".csv");
    ss_skin_feature_list l;
    ss_error err;
    if (!path || ss_skin_features_read_csv(path, &l, &err) != SS_OK) return 0;
    ss_skin_settings s;
    if (l.n <= 2000 && ss_skin_settings_preset(&s, "forearm", 16, &err) == SS_OK) {
        s.world_size_cm = 0.5; /* keep each feature's box small */
        ss_image *bio = ss_skin_bio_maps(&s, NULL, &l, &err);
        ss_image_free(bio);
    }
    ss_skin_feature_list_free(&l);
    return 0;
}
