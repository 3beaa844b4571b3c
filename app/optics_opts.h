/* Options every `skinsim optics` subcommand shares, parsed in one place so
 * they stay the same everywhere: the biological parameters (seed 003 §5.2),
 * the wavelength range, the surface roughness, --photons and --seed. */
#ifndef SKINSIM_APP_OPTICS_OPTS_H
#define SKINSIM_APP_OPTICS_OPTS_H

#include "skinsim/optics.h"

/* Looks at argv[*i]: returns 1 when it is a shared option (then consumed,
 * with its value; *i advanced), 0 when it is not, -1 on a bad value (the
 * error is printed and *rc holds the exit code). --photons must lie in
 * [min_photons, max_photons]. */
int optics_parse_shared(const char *cmd, int argc, char **argv, int *i, ss_bio_params *bio,
                        ss_spectrum_options *spec, uint64_t min_photons, uint64_t max_photons,
                        int *rc);

#endif
