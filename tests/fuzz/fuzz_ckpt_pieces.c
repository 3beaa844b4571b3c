/* libFuzzer: the header of a checkpoint in pieces (`heal --resume`, the MPI
 * driver's resume), through ss_heal_ckpt_header_read: magic, version, CRC,
 * values, piece list size and the tiling check come before anything is
 * allocated or trusted. Each input is read as it is and sealed (its trailing
 * CRC made right), to reach the parser behind the check; a header that
 * passes is then checked against its pieces (none exist: each must be
 * refused by name, without a crash). */
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
        const char *path = fuzz_file(k ? sealed : data, size, ".sshh");
        ss_heal_ckpt_header h;
        if (path && ss_heal_ckpt_header_read(path, &h, &err) == SS_OK) {
            ss_heal_ckpt_pieces_check("/nonexistent-skinsim-fuzz", &h, 1, &err);
            ss_heal_ckpt_header_free(&h);
        }
    }
    free(sealed);
    return 0;
}
