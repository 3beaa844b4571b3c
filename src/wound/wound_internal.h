/* Internal to src/wound: value noise with its period in mm (skin.c), for
 * the renderer's uneven crust. Not installed. */
#ifndef SKINSIM_WOUND_INTERNAL_H
#define SKINSIM_WOUND_INTERNAL_H

#include "skinsim/wound.h"

/* Fills out (size x size, 1 channel) with value noise whose coarsest period
 * is about period_mm over a texture of side_mm; deterministic per (seed, stream). */
ss_status ss_wound__noise(int size, double side_mm, double period_mm, int octaves, uint64_t seed,
                          uint64_t stream, ss_image *out, ss_error *err);

/* One Monte Carlo run of a slab (the blood layers' and the bed's spectra,
 * layer.c): its diffuse reflectance and (transmit non-NULL) transmittance. */
ss_status ss_wound__mc_one(const ss_optics_slab *slab, uint64_t photons, uint64_t seed,
                           double *diffuse, double *transmit, ss_error *err);

#endif
