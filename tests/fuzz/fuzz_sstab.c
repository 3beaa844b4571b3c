/* libFuzzer: ModelMatch tables (`optics table --lookup`), through
 * ss_mm_table_read (magic, version, sizes, CRC) and a lookup in any table
 * that loads; each input also sealed (trailing CRC made right) so mutations
 * reach the parser behind the check. */
#include <zlib.h>

#include "fuzz_util.h"
#include "skinsim/optics_fit.h"

static uint32_t crc(const uint8_t *p, size_t n) {
    return (uint32_t)crc32_z(crc32_z(0L, Z_NULL, 0), p, n);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    ss_error err;
    uint8_t *sealed = fuzz_sealed(data, size, crc);
    for (int k = 0; k < 2 && sealed; k++) {
        const char *path = fuzz_file(k ? sealed : data, size, ".sstab");
        ss_mm_table *t = path ? ss_mm_table_read(path, &err) : NULL;
        if (t) {
            ss_bio_params bio;
            ss_bio_params_default(&bio);
            ss_mm_entry e;
            (void)ss_mm_table_lookup_bio(t, &bio, &e, &err);
            ss_mm_table_free(t);
        }
    }
    free(sealed);
    return 0;
}
