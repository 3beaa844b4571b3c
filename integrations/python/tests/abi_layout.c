/* Prints the sizes and field offsets of the structs the Python package
 * mirrors with ctypes (integrations/python/skinsim/_lib.py), one line each:
 *   struct <name> <sizeof>
 *   field <struct> <field> <offsetof>
 * test_layout.py compares them with ctypes, so a header change that the
 * bindings do not follow fails a test. Compiled by tests/e2e_python.sh. */
#include <stddef.h>
#include <stdio.h>

#include "skinsim/abrasion.h"
#include "skinsim/core.h"
#include "skinsim/geom.h"
#include "skinsim/heal.h"
#include "skinsim/heal_io.h"
#include "skinsim/heal_run.h"
#include "skinsim/optics.h"
#include "skinsim/optics_fit.h"
#include "skinsim/skin.h"
#include "skinsim/wound.h"

#define S(t) printf("struct %s %zu\n", #t, sizeof(t))
#define F(t, f) printf("field %s %s %zu\n", #t, #f, offsetof(t, f))

int main(void) {
    S(ss_wound_recipe);
    S(ss_wound_render_options), F(ss_wound_render_options, side_mm),
        F(ss_wound_render_options, skin), F(ss_wound_render_options, table),
        F(ss_wound_render_options, recipe), F(ss_wound_render_options, scab_photons),
        F(ss_wound_render_options, seed);
    S(ss_wound_textures), F(ss_wound_textures, height), F(ss_wound_textures, normal);
    S(ss_error), F(ss_error, code), F(ss_error, msg);
    S(ss_image), F(ss_image, width), F(ss_image, channels), F(ss_image, data);
    S(ss_bio_params), F(ss_bio_params, melanin), F(ss_bio_params, betacarotene_g_per_l);
    S(ss_mc_options), F(ss_mc_options, photons), F(ss_mc_options, seed),
        F(ss_mc_options, theta_i_rad), F(ss_mc_options, roughness_sigma),
        F(ss_mc_options, stochastic_absorb), F(ss_mc_options, radial_bins),
        F(ss_mc_options, radial_max_cm), F(ss_mc_options, radial_distance),
        F(ss_mc_options, cancel), F(ss_mc_options, cancel_user);
    S(ss_optics_layer), F(ss_optics_layer, d_cm), F(ss_optics_layer, phase_n),
        F(ss_optics_layer, phase_theta);
    S(ss_optics_slab), F(ss_optics_slab, layer), F(ss_optics_slab, n_above),
        F(ss_optics_slab, bottom_albedo);
    S(ss_mc_result), F(ss_mc_result, transmit_se), F(ss_mc_result, brdf_exit),
        F(ss_mc_result, absorbed_per_layer), F(ss_mc_result, roulette_net),
        F(ss_mc_result, radial_bins), F(ss_mc_result, radial_dr_cm);
    S(ss_spectrum_options), F(ss_spectrum_options, wl_step_nm), F(ss_spectrum_options, mc),
        F(ss_spectrum_options, progress), F(ss_spectrum_options, progress_user);
    S(ss_reflectance_spectrum), F(ss_reflectance_spectrum, wavelength_nm),
        F(ss_reflectance_spectrum, std_error), F(ss_reflectance_spectrum, specular);
    S(ss_brdf_sampled), F(ss_brdf_sampled, n_phi), F(ss_brdf_sampled, f_rgb);
    S(ss_render_params), F(ss_render_params, specular), F(ss_render_params, roughness);
    S(ss_fit_options), F(ss_fit_options, tol), F(ss_fit_options, weighting),
        F(ss_fit_options, max_theta_rad), F(ss_fit_options, base_mode),
        F(ss_fit_options, albedo_rgb), F(ss_fit_options, surface);
    S(ss_fit_result), F(ss_fit_result, params), F(ss_fit_result, distance),
        F(ss_fit_result, residual_rel), F(ss_fit_result, evaluations);
    S(ss_mm_entry), F(ss_mm_entry, residual_rel), F(ss_mm_entry, sss_radius_cm),
        F(ss_mm_entry, albedo_rgb);
    S(ss_mm_table), F(ss_mm_table, axis), F(ss_mm_table, nentries), F(ss_mm_table, entries),
        F(ss_mm_table, photons), F(ss_mm_table, n_theta_i), F(ss_mm_table, n_phi),
        F(ss_mm_table, wl_min_nm), F(ss_mm_table, wl_step_nm);
    S(ss_mm_build_options), F(ss_mm_build_options, spectrum), F(ss_mm_build_options, n_theta_i),
        F(ss_mm_build_options, fit), F(ss_mm_build_options, base), F(ss_mm_build_options, quiet);
    S(ss_stroke_set), F(ss_stroke_set, u), F(ss_stroke_set, stroke), F(ss_stroke_set, nstrokes),
        F(ss_stroke_set, stroke_ids);
    S(ss_wound_shape), F(ss_wound_shape, mask), F(ss_wound_shape, label),
        F(ss_wound_shape, nwounds), F(ss_wound_shape, closing_px), F(ss_wound_shape, box_x),
        F(ss_wound_shape, npolys), F(ss_wound_shape, polys);
    S(ss_base_skin), F(ss_base_skin, lower_srgb);
    S(ss_texture_set), F(ss_texture_set, normal);
    S(ss_abrasion_settings), F(ss_abrasion_settings, world_size_cm), F(ss_abrasion_settings, seed);
    S(ss_timeline_key), F(ss_timeline_key, day);
    S(ss_timeline), F(ss_timeline, key), F(ss_timeline, end_day);
    S(ss_abrasion), F(ss_abrasion, timeline), F(ss_abrasion, shape), F(ss_abrasion, skin),
        F(ss_abrasion, phase), F(ss_abrasion, rendered);
    S(ss_heal_stats), F(ss_heal_stats, initial_area_mm2), F(ss_heal_stats, field_mean),
        F(ss_heal_stats, scar_max), F(ss_heal_stats, open_columns_mm2),
        F(ss_heal_stats, elevation_mean_mm), F(ss_heal_stats, elevation_max_mm);
    S(ss_heal_area_row), F(ss_heal_area_row, st);
    S(ss_heal_grid), F(ss_heal_grid, dx_mm), F(ss_heal_grid, cell), F(ss_heal_grid, field),
        F(ss_heal_grid, velocity), F(ss_heal_grid, t_days), F(ss_heal_grid, step);
    S(ss_heal_run_config), F(ss_heal_run_config, params_path), F(ss_heal_run_config, no_scab),
        F(ss_heal_run_config, grid), F(ss_heal_run_config, size_mm),
        F(ss_heal_run_config, epidermis_mm), F(ss_heal_run_config, wound_mask),
        F(ss_heal_run_config, concave_k), F(ss_heal_run_config, wound_footprint),
        F(ss_heal_run_config, wound_depth_image), F(ss_heal_run_config, days),
        F(ss_heal_run_config, scheme), F(ss_heal_run_config, dt_days),
        F(ss_heal_run_config, checkpoint_every), F(ss_heal_run_config, out_dir),
        F(ss_heal_run_config, force), F(ss_heal_run_config, resume_dir),
        F(ss_heal_run_config, seed), F(ss_heal_run_config, mechanics), F(ss_heal_run_config, kappa),
        F(ss_heal_run_config, tet_mesh), F(ss_heal_run_config, adapt_tol),
        F(ss_heal_run_config, skin_mesh), F(ss_heal_run_config, wound_uv),
        F(ss_heal_run_config, mesh_units_mm);
    S(ss_skin_dist);
    S(ss_skin_settings), F(ss_skin_settings, world_size_cm), F(ss_skin_settings, seed),
        F(ss_skin_settings, wrap), F(ss_skin_settings, sampler), F(ss_skin_settings, count),
        F(ss_skin_settings, dist), F(ss_skin_settings, base_lo), F(ss_skin_settings, base_hi),
        F(ss_skin_settings, phi);
    S(ss_skin_fields), F(ss_skin_fields, lips), F(ss_skin_fields, wrinkle_vectors);
    S(ss_bezier3), F(ss_bezier3, y);
    S(ss_skin_feature), F(ss_skin_feature, x), F(ss_skin_feature, r2), F(ss_skin_feature, w),
        F(ss_skin_feature, curve);
    S(ss_skin_feature_list), F(ss_skin_feature_list, f);
    S(ss_skin_maps), F(ss_skin_maps, specular), F(ss_skin_maps, normal),
        F(ss_skin_maps, height_min_mm), F(ss_skin_maps, height_max_mm);
    return 0;
}
