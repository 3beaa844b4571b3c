/* Internal to src/core: helpers shared by its files and nobody else (not
 * installed; other modules use skinsim/core.h). */
#ifndef SKINSIM_CORE_INTERNAL_H
#define SKINSIM_CORE_INTERNAL_H

#include <sys/types.h>

/* What a file of mode m is, for messages: "a named pipe", "a folder", ... */
const char *ss__file_kind(mode_t m);

#endif
