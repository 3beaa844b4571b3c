/* libFuzzer: heal checkpoints (`heal --resume`), through
 * ss_heal_checkpoint_read: magic, version, sizes and CRC are checked before
 * anything is allocated from them. Random mutations fail the CRC early, so
 * every input is read twice: as it is, and sealed (its trailing CRC made
 * right) to reach the parser behind the check. */
#include <zlib.h>

#include "fuzz_util.h"
#include "skinsim/heal_io.h"

static uint32_t crc(const uint8_t *p, size_t n) {
    return (uint32_t)crc32_z(crc32_z(0L, Z_NULL, 0), p, n);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    ss_error err;
    uint8_t *sealed = fuzz_sealed(data, size, crc);
    for (int k = 0; k < 2 && sealed; k++) {
        const char *path = fuzz_file(k ? sealed : data, size, ".sshc");
        ss_heal_checkpoint c;
        if (path && ss_heal_checkpoint_read(path, &c, &err) == SS_OK) ss_heal_checkpoint_free(&c);
    }
    free(sealed);
    return 0;
}
