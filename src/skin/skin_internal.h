/* Internal to src/skin: the baseline mottling (fBm in mm, mottle.c), the
 * microrelief network (relief.c) and the wrinkle field direction
 * (features.c), shared by the texel pass in texgen.c. */
#ifndef SKINSIM_SKIN_INTERNAL_H
#define SKINSIM_SKIN_INTERNAL_H

#include "skinsim/skin.h"

/* ---- mottle.c: periodic fBm in world units --------------------------------- */
#define MOTTLE_F 8    /* fields: the 6 optical parameters, height, sebum */
#define MOTTLE_OCT 12 /* at most this many octaves */
enum { MOT_HEIGHT = 6, MOT_SEBUM = 7 };
/* A cubic Bezier in power form, made once per curve for the distance
 * search (ss_bezier3_distance prepares it on every call). */
typedef struct skin_bezier3_prep {
    double ax, bx, cx, x0, ay, by, cy, y0, sp; /* sp: max control-polygon leg */
} skin_bezier3_prep;
void skin_bezier3_prepare(const ss_bezier3 *b, skin_bezier3_prep *q);
double skin_bezier3_distance_prep(const skin_bezier3_prep *q, double px, double py, int coarse,
                                  double tol, double reach, double *t_out);

typedef struct skin_mottle {
    int noct;
    int n[MOTTLE_OCT];             /* lattice points per side of octave k */
    float *lat[MOTTLE_OCT];        /* n^2 x MOTTLE_F values in [-1, 1] */
    float w[MOTTLE_OCT][MOTTLE_F]; /* amplitude of octave k in field f (0: skipped) */
} skin_mottle;
/* Octave wavelengths from s->dist.mottle_max_mm halving down to mottle_min_mm,
 * each a periodic lattice of round(world / wavelength) points; octaves
 * shorter than 2 texels are dropped and 2-4 texels faded (no aliasing), the
 * normalisation counts every octave, so the coarse ones keep their amplitude
 * at any --size. The sum has a standard deviation of about 1. */
ss_status skin_mottle_init(skin_mottle *m, const ss_skin_settings *s, ss_error *err);
void skin_mottle_free(skin_mottle *m);
/* The MOTTLE_F fields at texture position (u, v) in [0, 1). */
void skin_mottle_eval(const skin_mottle *m, double u, double v, float out[MOTTLE_F]);

/* ---- relief.c: the microrelief network ------------------------------------- */
typedef struct skin_relief {
    int m1, m2;     /* cells per side, primary and secondary */
    float *p1, *p2; /* jittered points: x, y (texture units), depth factor */
    double world_mm, texel_mm;
    double w1, w2; /* line half-widths, mm (>= 0.75 sub-sample spacing) */
    double d1, d2; /* line depths, mm (scaled by w / w_eff when widened) */
    double k1, k2; /* that scale (1 when not widened), also applied to the groove */
    double stretch;
    int ns; /* sub-samples per texel side (the footprint is averaged) */
    int nd; /* direction grid per side (doubled angle: cos 2a, sin 2a) */
    float *dir;
} skin_relief;
/* vf: the wrinkle vector field (NULL: the built-in one), sampled on a grid
 * of about 0.4 mm and interpolated as an axis (doubled angle), so the
 * network turns smoothly and tiles. */
ss_status skin_relief_init(skin_relief *r, const ss_skin_settings *s, const ss_image *vf,
                           ss_error *err);
void skin_relief_free(skin_relief *r);
/* Height (mm, <= 0) of the network at (u, v), lines stretched along the
 * field; *groove: 0..1, 1 on a primary line. */
float skin_relief_eval(const skin_relief *r, double u, double v, float *groove);

/* ---- features.c ------------------------------------------------------------- */
/* The wrinkle field's direction at (x, y) (texture units; the built-in field
 * when vf is NULL), unit length; 0 if the field has no direction there. */
int skin_field_direction(const ss_image *vf, double x, double y, double *vx, double *vy);

#endif
