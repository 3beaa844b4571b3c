/* Internal interfaces of the optics module (not installed): the full Monte
 * Carlo tally set used by ss_mc_run, the MCML runner and the path tracer, and
 * the tabulated spectra. Seed 003 §4.4-4.7. */
#ifndef SKINSIM_OPTICS_INTERNAL_H
#define SKINSIM_OPTICS_INTERNAL_H

#include "skinsim/optics.h"

/* What to tally. All sizes 0 = not tallied. */
typedef struct ss_mc_tally_spec {
    int brdf_nt, brdf_np; /* exit direction bins (theta_r x dphi), specular included */
    int rad_n;            /* Rd(r) bins */
    double rad_dr;        /* cm */
    int mcml;             /* 1: MCML arrays below, overflow into last bins */
    double dz;            /* A(z) bin, cm */
    int nz, na;           /* A(z) bins, exit-angle bins (Rd_a, Tt_a) */
} ss_mc_tally_spec;

/* Raw (un-normalised) tallies: sums of packet weights over all photons. */
typedef struct ss_mc_tallies {
    uint64_t photons;
    double specular, diffuse, diffuse2, transmit, transmit2, absorbed, roulette;
    double abs_layer[SS_OPTICS_MAX_LAYERS];
    double *brdf;                     /* brdf_nt*brdf_np */
    double *rd_r;                     /* rad_n */
    double *a_z, *rd_a, *tt_r, *tt_a; /* mcml only */
    double *a_rz, *rd_ra, *tt_ra;     /* mcml only: [ir * nz + iz], [ir * na + ia] */
    double *mem;
} ss_mc_tallies;

/* Runs the transport and fills raw tallies (arrays allocated here, free with
 * ss_mc_tallies_free). */
ss_status ss_mc_run_tallies(const ss_optics_slab *slab, const ss_mc_options *opt,
                            const ss_mc_tally_spec *spec, ss_mc_tallies *t, ss_error *err);
void ss_mc_tallies_free(ss_mc_tallies *t);

/* One Smith microsurface random walk on the rough air/skin interface (GGX
 * alpha; see mc.c). Local frame: +z towards the incident side of index n_in,
 * w (unit, w.z < 0) the travel direction, replaced by the exit direction.
 * Returns 0 if reflected (w.z > 0), 1 if transmitted into n_out (w.z < 0);
 * *order = number of facet interactions. Random numbers: stream (seed, stream). */
int ss_ms_walk(double alpha, double n_in, double n_out, double w[3], uint64_t seed, uint64_t stream,
               int *order);
/* Test hook for the inner loop's samplers (mc.c): n standard exponential
 * variates (ziggurat) and n uniform azimuths (cos, sin) from the stream
 * (seed, 0); any output pointer may be NULL. */
void ss_mc_test_samplers(uint64_t seed, size_t n, double *expo, double *cosp, double *sinp);

#define SS_BRULS_COLUMNS 9

/* Tabulated spectra loaded from data/spectra (wavelength nm, value). */
typedef struct ss_spectrum_table {
    int n;
    double *nm, *v;
} ss_spectrum_table;
struct ss_optics_data {
    ss_spectrum_table eumelanin, pheomelanin;  /* cm^-1 per mg/mL */
    ss_spectrum_table hbo2, hb;                /* molar extinction, cm^-1/M (decadic) */
    ss_spectrum_table bilirubin, betacarotene; /* molar extinction, cm^-1/M (decadic) */
    ss_spectrum_table cie_x, cie_y, cie_z, d65;
    /* Bruls & van der Leun 1984 cumulative transmitted percentage over the
     * exitant angle (deg, in the "nm" field): stratum corneum at 254, 302, 365,
     * 436, 546 nm, then epidermis at 302, 365, 436, 546 nm. */
    ss_spectrum_table bruls[SS_BRULS_COLUMNS];
};
ss_status ss_optics_data_load(ss_optics_data *d, ss_error *err);
void ss_optics_data_free(ss_optics_data *d);
double ss_spectrum_table_eval(const ss_spectrum_table *t, double nm); /* linear, clamped */
/* Skin slab from already loaded data (ss_optics_skin_slab loads per call). */
ss_status ss_optics_skin_slab_data(const ss_optics_data *d, const ss_bio_params *bio,
                                   double wavelength_nm, ss_optics_slab *out, ss_error *err);
/* Colour with loaded tables. */
ss_status ss_spectrum_to_srgb_data(const ss_optics_data *d, const double *wl_nm, const double *refl,
                                   int n, double rgb[3], ss_error *err);

#endif
