/* skinsim abrasion: the abrasion-healing timeline (seed 000). */
#include "cli.h"

int cmd_abrasion(int argc, char **argv) {
    (void)argc;
    (void)argv;
    return cli_usage_error("abrasion", "not built yet");
}
