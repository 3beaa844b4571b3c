/* Render BRDF models for ModelMatch (seed 003 §6.1): Ashikhmin-Shirley (2000,
 * isotropic, the model behind the seed's iRay material) and the glTF 2.0
 * metallic-roughness model with metallic = 0 (GGX with height-correlated
 * Smith visibility and Schlick Fresnel, plus Lambert coupled to the specular
 * lobe as in Kelemen & Szirmay-Kalos 2001: base/pi (1 - E(cos_i))
 * (1 - E(cos_r)) / (1 - E_avg), E the directional albedo of the specular
 * lobe and E_avg its cosine-weighted hemispherical mean, so that the
 * directional albedo is E + base (1 - E) <= 1 and the diffuse part is nearly
 * Lambertian where the lobe is weak; glTF's 1-F(h.k) weight exceeds 1 at
 * grazing). E is tabulated once per process (pthread_once) over cos and
 * roughness by stratified visible-normal quadrature and interpolated
 * bilinearly; it is linear in F0 (Schlick), E = F0 A + B. Both are written as
 * f_c = base_c * diffuse + specular so the fitter can solve the colour in closed form; the
 * direction-only parts are precomputed in ss_render_geom. Also: bin-averaged sampling in the
 * ss_brdf_sampled layout and directional albedo by quadrature. */
#include "skinsim/optics_fit.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

const char *ss_render_model_name(ss_render_model m) {
    return m == SS_RENDER_AS ? "ashikhmin-shirley" : "ggx";
}

void ss_render_geom_init(double theta_i, double theta_r, double dphi, ss_render_geom *g) {
    /* k_i and k_r both point away from the surface; dphi = pi is the mirror
     * direction (the half vector is then the normal when theta_r = theta_i). */
    double si = sin(theta_i), ci = cos(theta_i), sr = sin(theta_r), cr = cos(theta_r);
    double hx = si + sr * cos(dphi), hy = sr * sin(dphi), hz = ci + cr;
    double len = sqrt(hx * hx + hy * hy + hz * hz);
    g->cos_i = ci;
    g->cos_r = cr;
    g->valid = ci > 1e-12 && cr > 1e-12 && len > 1e-12;
    if (!g->valid) {
        g->cos_h = g->cos_hk = 1.0;
        g->log_cos_h = g->schlick5 = g->as_diffuse = g->schlick5_i = g->schlick5_r = 0.0;
        return;
    }
    g->cos_h = hz / len;
    g->log_cos_h = log(g->cos_h);
    double hk = (hx * si + hz * ci) / len;
    if (hk < 0) hk = 0;
    if (hk > 1) hk = 1;
    g->cos_hk = hk;
    double m = 1.0 - hk;
    g->schlick5 = m * m * m * m * m;
    double mi = 1.0 - ci, mr = 1.0 - cr;
    g->schlick5_i = mi * mi * mi * mi * mi;
    g->schlick5_r = mr * mr * mr * mr * mr;
    double a = 1.0 - 0.5 * ci, b = 1.0 - 0.5 * cr;
    g->as_diffuse = 28.0 / (23.0 * M_PI) * (1.0 - a * a * a * a * a) * (1.0 - b * b * b * b * b);
}

/* ---- specular-lobe albedo table (GGX, height-correlated Smith) ------------- */
#define ES_NMU 48
#define ES_NR 40
#define ES_NS 32
static double es_A[ES_NR][ES_NMU], es_B[ES_NR][ES_NMU], es_Aavg[ES_NR], es_Bavg[ES_NR];
static pthread_once_t es_once = PTHREAD_ONCE_INIT;

static double es_lambda(double a2, double c) {
    double t2 = (1.0 - c * c) / (c * c);
    return 0.5 * (-1.0 + sqrt(1.0 + a2 * t2));
}

static double es_rough(int k) {
    return SS_RENDER_ROUGHNESS_MIN + (1.0 - SS_RENDER_ROUGHNESS_MIN) * k / (ES_NR - 1);
}
static double es_mu(int j) { return 0.005 + 0.995 * j / (ES_NMU - 1); }

/* E(mu) = E_h~VNDF[F(i.h) G2/G1(i)] with the reflected direction above the
 * horizon; stratified midpoints of the spherical-cap sampler (Dupuy & Benyoub
 * 2023), split into the F0 and (1-h.k)^5 parts of Schlick's F. */
static void es_init(void) {
    for (int k = 0; k < ES_NR; k++) {
        double al = es_rough(k) * es_rough(k), a2 = al * al;
        for (int j = 0; j < ES_NMU; j++) {
            double mu = es_mu(j), si = sqrt(1.0 - mu * mu);
            double wi[3] = {si, 0.0, mu};
            double vx = al * wi[0], vz = wi[2], vn = sqrt(vx * vx + vz * vz);
            vx /= vn;
            vz /= vn;
            double li = es_lambda(a2, mu), g1 = 1.0 / (1.0 + li), A = 0, B = 0;
            for (int p = 0; p < ES_NS; p++)
                for (int q = 0; q < ES_NS; q++) {
                    double u1 = (p + 0.5) / ES_NS, u2 = (q + 0.5) / ES_NS;
                    double phi = 2.0 * M_PI * u1, z = (1.0 - u2) * (1.0 + vz) - vz;
                    double st = sqrt(fmax(0.0, 1.0 - z * z));
                    double hx = al * (st * cos(phi) + vx), hy = al * st * sin(phi), hz = z + vz;
                    double hn = sqrt(hx * hx + hy * hy + hz * hz);
                    hx /= hn;
                    hy /= hn;
                    hz /= hn;
                    double ih = wi[0] * hx + wi[2] * hz;
                    double oz = 2.0 * ih * hz - wi[2];
                    if (oz <= 1e-9) continue;
                    double g2 = 1.0 / (1.0 + li + es_lambda(a2, fmin(1.0, oz)));
                    double m = 1.0 - fmin(1.0, fmax(0.0, ih)), s5 = m * m * m * m * m;
                    double w = g2 / g1;
                    A += (1.0 - s5) * w;
                    B += s5 * w;
                }
            es_A[k][j] = A / (ES_NS * ES_NS);
            es_B[k][j] = B / (ES_NS * ES_NS);
        }
        /* cosine-weighted mean 2 int E mu dmu (trapezoid; E at mu < 0.005 taken as at 0.005) */
        double sa = 0, sb = 0;
        for (int j = 0; j + 1 < ES_NMU; j++) {
            double m0 = es_mu(j), m1 = es_mu(j + 1), h = m1 - m0;
            sa += 0.5 * h * (es_A[k][j] * m0 + es_A[k][j + 1] * m1);
            sb += 0.5 * h * (es_B[k][j] * m0 + es_B[k][j + 1] * m1);
        }
        double m0 = es_mu(0);
        sa += es_A[k][0] * 0.5 * m0 * m0;
        sb += es_B[k][0] * 0.5 * m0 * m0;
        es_Aavg[k] = 2.0 * sa;
        es_Bavg[k] = 2.0 * sb;
    }
}

static void es_coords(double rough, int *k, double *fk) {
    double x = (rough - SS_RENDER_ROUGHNESS_MIN) / (1.0 - SS_RENDER_ROUGHNESS_MIN) * (ES_NR - 1);
    if (x < 0) x = 0;
    if (x > ES_NR - 1) x = ES_NR - 1;
    *k = (int)x;
    if (*k > ES_NR - 2) *k = ES_NR - 2;
    *fk = x - *k;
}

static double es_eval(double f0, int k, double fk, double mu) {
    double x = (mu - 0.005) / 0.995 * (ES_NMU - 1);
    if (x < 0) x = 0;
    if (x > ES_NMU - 1) x = ES_NMU - 1;
    int j = (int)x;
    if (j > ES_NMU - 2) j = ES_NMU - 2;
    double fj = x - j;
    double a = (1 - fk) * ((1 - fj) * es_A[k][j] + fj * es_A[k][j + 1]) +
               fk * ((1 - fj) * es_A[k + 1][j] + fj * es_A[k + 1][j + 1]);
    double b = (1 - fk) * ((1 - fj) * es_B[k][j] + fj * es_B[k][j + 1]) +
               fk * ((1 - fj) * es_B[k + 1][j] + fj * es_B[k + 1][j + 1]);
    return f0 * a + b;
}

double ss_render_ggx_spec_albedo(double specular, double roughness, double cos_theta) {
    pthread_once(&es_once, es_init);
    int k;
    double fk;
    es_coords(roughness, &k, &fk);
    return es_eval(SS_RENDER_F0_PER_SPECULAR * specular, k, fk, cos_theta);
}

void ss_render_terms_geom(ss_render_model m, double specular, double roughness,
                          const ss_render_geom *g, double *diffuse, double *spec) {
    if (!g->valid) {
        *diffuse = *spec = 0.0;
        return;
    }
    double f0 = SS_RENDER_F0_PER_SPECULAR * specular;
    double fres = f0 + (1.0 - f0) * g->schlick5;
    double alpha = roughness * roughness;
    if (m == SS_RENDER_GGX) {
        double a2 = alpha * alpha;
        double t = g->cos_h * g->cos_h * (a2 - 1.0) + 1.0;
        double d = a2 / (M_PI * t * t);
        double ci = g->cos_i, cr = g->cos_r;
        double v =
            0.5 / (ci * sqrt(cr * cr * (1.0 - a2) + a2) + cr * sqrt(ci * ci * (1.0 - a2) + a2));
        pthread_once(&es_once, es_init);
        int k;
        double fk;
        es_coords(roughness, &k, &fk);
        double ei = es_eval(f0, k, fk, ci), er = es_eval(f0, k, fk, cr);
        double eavg = f0 * ((1 - fk) * es_Aavg[k] + fk * es_Aavg[k + 1]) +
                      ((1 - fk) * es_Bavg[k] + fk * es_Bavg[k + 1]);
        *diffuse = (1.0 - ei) * (1.0 - er) / (M_PI * (1.0 - eavg));
        *spec = fres * d * v;
    } else {
        /* Ashikhmin-Shirley with n_u = n_v = n; n from the Beckmann-equivalent
         * relation n = 2/alpha^2 - 2 (roughness 1 gives n = 0). */
        double n = 2.0 / (alpha * alpha) - 2.0;
        if (n < 0) n = 0;
        double hk = g->cos_hk > 1e-6 ? g->cos_hk : 1e-6;
        double mx = g->cos_i > g->cos_r ? g->cos_i : g->cos_r;
        *diffuse = g->as_diffuse * (1.0 - f0);
        *spec = (n + 1.0) / (8.0 * M_PI) * exp(n * g->log_cos_h) / (hk * mx) * fres;
    }
}

void ss_render_brdf_terms(ss_render_model m, double specular, double roughness, double theta_i,
                          double theta_r, double dphi, double *diffuse, double *spec) {
    ss_render_geom g;
    ss_render_geom_init(theta_i, theta_r, dphi, &g);
    ss_render_terms_geom(m, specular, roughness, &g, diffuse, spec);
}

void ss_render_brdf_eval(ss_render_model m, const ss_render_params *p, double theta_i,
                         double theta_r, double dphi, double f_rgb[3]) {
    double d, s;
    ss_render_brdf_terms(m, p->specular, p->roughness, theta_i, theta_r, dphi, &d, &s);
    for (int c = 0; c < 3; c++) f_rgb[c] = p->base_rgb[c] * d + s;
}

ss_status ss_render_brdf_sample(ss_render_model m, const ss_render_params *p, int n_theta_i,
                                int n_theta_r, int n_phi, int subsamples, ss_brdf_sampled *out,
                                ss_error *err) {
    out->f_rgb = NULL;
    if (n_theta_i < 1 || n_theta_r < 1 || n_phi < 1 || subsamples < 1 || n_theta_i > 1024 ||
        n_theta_r > 1024 || n_phi > 1024 || subsamples > 64)
        return ss_error_set(err, SS_ERR_INPUT,
                            "render BRDF sampling: bad bin counts %d x %d x %d (subsamples %d)",
                            n_theta_i, n_theta_r, n_phi, subsamples);
    size_t n = (size_t)n_theta_i * (size_t)n_theta_r * (size_t)n_phi * 3;
    out->f_rgb = malloc(n * sizeof(double));
    if (!out->f_rgb) return ss_error_set(err, SS_ERR_NOMEM, "render BRDF sampling: out of memory");
    out->n_theta_i = n_theta_i;
    out->n_theta_r = n_theta_r;
    out->n_phi = n_phi;
    double dti = M_PI / 2 / n_theta_i, dtr = M_PI / 2 / n_theta_r, dp = M_PI / n_phi;
    for (int ti = 0; ti < n_theta_i; ti++) {
        double thi = (ti + 0.5) * dti;
        for (int tr = 0; tr < n_theta_r; tr++)
            for (int ph = 0; ph < n_phi; ph++) {
                double acc[3] = {0, 0, 0}, wsum = 0, cc = cos((tr + 0.5) * dtr);
                for (int a = 0; a < subsamples; a++) {
                    double thr = (tr + (a + 0.5) / subsamples) * dtr;
                    double w = sin(thr) * cos(thr);
                    for (int b = 0; b < subsamples; b++) {
                        double phi = (ph + (b + 0.5) / subsamples) * dp, f[3];
                        ss_render_brdf_eval(m, p, thi, thr, phi, f);
                        for (int c = 0; c < 3; c++) acc[c] += w * f[c];
                        wsum += sin(thr) * cc;
                    }
                }
                double *o = out->f_rgb + (((size_t)ti * n_theta_r + tr) * n_phi + ph) * 3;
                for (int c = 0; c < 3; c++) o[c] = acc[c] / wsum;
            }
    }
    return SS_OK;
}

double ss_render_albedo(ss_render_model m, const ss_render_params *p, double theta_i, int channel,
                        int n) {
    /* Integral over theta_r in [0, pi/2] and dphi in [0, pi], doubled for the
     * other half of the azimuth (isotropic model). */
    double dt = M_PI / 2 / n, dp = M_PI / n, sum = 0;
    for (int a = 0; a < n; a++) {
        double thr = (a + 0.5) * dt, w = sin(thr) * cos(thr) * dt * dp;
        for (int b = 0; b < n; b++) {
            double f[3];
            ss_render_brdf_eval(m, p, theta_i, thr, (b + 0.5) * dp, f);
            sum += w * f[channel];
        }
    }
    return 2.0 * sum;
}
