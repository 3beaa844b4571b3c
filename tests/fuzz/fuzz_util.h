/* Shared by the libFuzzer targets (one per input format, tests/fuzz/fuzz_*.c):
 * the readers take paths, so each input is written to one temporary file per
 * process (with the extension the reader dispatches on) and read back through
 * the same function the command uses. Build and run: make fuzz. */
#ifndef SKINSIM_FUZZ_UTIL_H
#define SKINSIM_FUZZ_UTIL_H

#define _DEFAULT_SOURCE /* mkstemps */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "skinsim/core.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Writes data to this process's fuzz file ending in ext; returns its path
 * (static), or NULL if the file could not be written. */
static const char *fuzz_file(const uint8_t *data, size_t size, const char *ext) {
    static char path[128];
    static char made_ext[16];
    if (!path[0] || strcmp(made_ext, ext)) {
        if (path[0]) unlink(path);
        snprintf(path, sizeof path, "/tmp/skinsim-fuzz-%ld-XXXXXX%s", (long)getpid(), ext);
        int fd = mkstemps(path, (int)strlen(ext));
        if (fd < 0) {
            path[0] = '\0';
            return NULL;
        }
        close(fd);
        snprintf(made_ext, sizeof made_ext, "%s", ext);
    }
    FILE *f = fopen(path, "wb");
    if (!f) return NULL;
    int ok = fwrite(data, 1, size, f) == size;
    ok &= fclose(f) == 0;
    return ok ? path : NULL;
}

/* The input as a NUL-terminated string (for the text parsers); caller frees. */
static char *fuzz_text(const uint8_t *data, size_t size) {
    char *t = malloc(size + 1);
    if (!t) return NULL;
    memcpy(t, data, size);
    t[size] = '\0';
    return t;
}

/* Formats ending in a little-endian CRC-32 of everything before it
 * (checkpoints, ModelMatch tables): a copy of the input with that CRC made
 * right, so mutations reach the parser behind the check. Caller frees. */
static uint8_t *fuzz_sealed(const uint8_t *data, size_t size,
                            uint32_t (*crc)(const uint8_t *, size_t)) {
    uint8_t *buf = malloc(size ? size : 1);
    if (!buf) return NULL;
    memcpy(buf, data, size);
    if (size >= 4) {
        uint32_t c = crc(buf, size - 4);
        for (int k = 0; k < 4; k++) buf[size - 4 + k] = (uint8_t)(c >> (8 * k));
    }
    return buf;
}

#endif
