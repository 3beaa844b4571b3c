/* Internal to the abrasion module: what timeline.c needs from phases.c and
 * the public header does not show (the maturation re-render with a progress
 * and cancel callback, for ss_abrasion_frame_poll). */
#ifndef SKINSIM_ABRASION_INTERNAL_H
#define SKINSIM_ABRASION_INTERNAL_H

#include "skinsim/abrasion.h"

/* ss_abrasion_maturation_at with fn (core.h ss_progress_fn) polled between
 * bands of the region's rows with the fraction of the region done. */
ss_status abrasion_maturation_at_poll(const ss_wound_shape *w, const ss_base_skin *skin,
                                      const ss_abrasion_settings *s, double position,
                                      double span_days, double after_days, ss_image *color,
                                      ss_image *reflection, ss_progress_fn fn, void *user,
                                      ss_error *err);

#endif
