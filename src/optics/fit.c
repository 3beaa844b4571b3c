/* Least-squares ModelMatch fit of a render BRDF to a sampled BRDF (seed 003
 * §4.6-4.7). Distance: the seed's discretised squared difference over
 * (theta_i, theta_r, dphi) bins, each weighted by the solid angle of its exit
 * bin (§3.1.6: sin(theta) dtheta dphi, exact for the bin) times the incidence
 * bin width, summed over R, G, B. The model is evaluated per bin the way the
 * photon tally estimates it (integral of f cos dw over the bin divided by
 * solid angle times cos at the bin centre), by subsampling.
 * Variable projection: the base colour is linear in the model and solved in
 * closed form (clamped to [0,1]) for each (specular, roughness); those two are
 * found by a coarse grid followed by a bounded Nelder-Mead simplex.
 * Albedo-constrained mode (SS_FIT_BASE_ALBEDO, a departure from the seed used
 * by default for skin, docs/optics.md): the base colour is the one whose
 * diffuse term reflects the given albedo at normal incidence, and the lobe is
 * fitted alone - to the surface-reflected part of the BRDF when given (the
 * renderer's specular lobe models the surface reflection), else to the whole
 * BRDF. The residual is always that of the whole BRDF. */
#include "skinsim/optics_fit.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

void ss_fit_options_default(ss_fit_options *o) {
    o->subsamples = 3;
    o->max_iter = 300;
    o->tol = 1e-10;
    o->weighting = SS_FIT_SOLID_ANGLE;
    o->max_theta_rad = M_PI / 2;
    o->base_mode = SS_FIT_BASE_FREE;
    o->albedo_rgb[0] = o->albedo_rgb[1] = o->albedo_rgb[2] = 0.0;
    o->surface = NULL;
}

const char *ss_fit_weighting_name(int w) {
    return w == SS_FIT_UNIFORM ? "uniform" : w == SS_FIT_PROJECTED ? "projected" : "solid-angle";
}

typedef struct fit_ctx {
    ss_render_model model;
    int nbins, nsub;
    const double *data;   /* nbins * 3 */
    const double *weight; /* nbins */
    ss_render_geom *geom; /* nbins * nsub */
    double *subw;         /* nsub weights per bin (sum 1), same for all bins of a theta_r row */
    double *A, *S;        /* scratch nbins */
    int evals;
    int base_mode;         /* SS_FIT_BASE_FREE or SS_FIT_BASE_ALBEDO */
    double albedo[3];      /* base_mode ALBEDO */
    const double *surface; /* base_mode ALBEDO: surface-reflected part (nbins * 3) or NULL */
} fit_ctx;

/* Diffuse directional albedo at normal incidence of the model's diffuse term
 * per unit base colour, for the lobe (specular, roughness). */
static double diffuse_albedo_per_base(ss_render_model m, double spec, double rough) {
    ss_render_params p1, p0;
    memset(&p1, 0, sizeof p1);
    p1.specular = spec;
    p1.roughness = rough;
    p0 = p1;
    for (int ch = 0; ch < 3; ch++) p1.base_rgb[ch] = 1.0;
    return ss_render_albedo(m, &p1, 0.0, 0, 48) - ss_render_albedo(m, &p0, 0.0, 0, 48);
}

static double clampd(double v, double lo, double hi) { return v < lo ? lo : v > hi ? hi : v; }

/* Distance for (specular, roughness) with the best base colour; writes it. */
static double objective(fit_ctx *c, double spec, double rough, double base[3]) {
    spec = clampd(spec, 0.0, 1.0);
    rough = clampd(rough, SS_RENDER_ROUGHNESS_MIN, 1.0);
    c->evals++;
    double num[3] = {0, 0, 0}, den = 0;
    for (int b = 0; b < c->nbins; b++) {
        double a = 0, s = 0;
        const ss_render_geom *g = c->geom + (size_t)b * c->nsub;
        const double *w = c->subw + (size_t)b * c->nsub;
        for (int k = 0; k < c->nsub; k++) {
            double d, sp;
            ss_render_terms_geom(c->model, spec, rough, g + k, &d, &sp);
            a += w[k] * d;
            s += w[k] * sp;
        }
        c->A[b] = a;
        c->S[b] = s;
        double wb = c->weight[b];
        den += wb * a * a;
        for (int ch = 0; ch < 3; ch++) num[ch] += wb * a * (c->data[b * 3 + ch] - s);
    }
    if (c->base_mode == SS_FIT_BASE_ALBEDO) {
        double dn = diffuse_albedo_per_base(c->model, spec, rough);
        for (int ch = 0; ch < 3; ch++)
            base[ch] = dn > 0 ? clampd(c->albedo[ch] / dn, 0.0, 1.0) : 0.0;
        if (c->surface) { /* the lobe against the surface-reflected part */
            double dist = 0;
            for (int b = 0; b < c->nbins; b++)
                for (int ch = 0; ch < 3; ch++) {
                    double r = c->S[b] - c->surface[b * 3 + ch];
                    dist += c->weight[b] * r * r;
                }
            return dist;
        }
    } else
        for (int ch = 0; ch < 3; ch++) base[ch] = den > 0 ? clampd(num[ch] / den, 0.0, 1.0) : 0.0;
    double dist = 0;
    for (int b = 0; b < c->nbins; b++) {
        double e = 0;
        for (int ch = 0; ch < 3; ch++) {
            double r = base[ch] * c->A[b] + c->S[b] - c->data[b * 3 + ch];
            e += r * r;
        }
        dist += c->weight[b] * e;
    }
    return dist;
}

static double obj2(fit_ctx *c, const double x[2]) {
    double base[3];
    return objective(c, x[0], x[1], base);
}

/* Nelder-Mead on 2 variables; bounds are enforced by clamping x in place. */
static void nelder_mead(fit_ctx *c, double x0[2], double step, int max_iter, double tol) {
    double lo[2] = {0.0, SS_RENDER_ROUGHNESS_MIN}, hi[2] = {1.0, 1.0};
    double p[3][2], f[3];
    for (int i = 0; i < 3; i++) {
        p[i][0] = x0[0];
        p[i][1] = x0[1];
        if (i > 0) {
            int d = i - 1;
            p[i][d] += (p[i][d] + step > hi[d]) ? -step : step;
        }
        for (int d = 0; d < 2; d++) p[i][d] = clampd(p[i][d], lo[d], hi[d]);
        f[i] = obj2(c, p[i]);
    }
    for (int it = 0; it < max_iter; it++) {
        /* order: 0 best, 2 worst */
        for (int i = 0; i < 3; i++)
            for (int j = i + 1; j < 3; j++)
                if (f[j] < f[i]) {
                    double t = f[i];
                    f[i] = f[j];
                    f[j] = t;
                    for (int d = 0; d < 2; d++) {
                        t = p[i][d];
                        p[i][d] = p[j][d];
                        p[j][d] = t;
                    }
                }
        double size = fabs(p[1][0] - p[0][0]) + fabs(p[1][1] - p[0][1]) + fabs(p[2][0] - p[0][0]) +
                      fabs(p[2][1] - p[0][1]);
        if (fabs(f[2] - f[0]) <= tol * (fabs(f[0]) + 1e-300) && size < 1e-9) break;
        if (size < 1e-12) break;
        double cen[2], xr[2], xe[2], xc[2];
        for (int d = 0; d < 2; d++) cen[d] = 0.5 * (p[0][d] + p[1][d]);
        for (int d = 0; d < 2; d++) xr[d] = clampd(cen[d] + (cen[d] - p[2][d]), lo[d], hi[d]);
        double fr = obj2(c, xr);
        if (fr < f[0]) {
            for (int d = 0; d < 2; d++)
                xe[d] = clampd(cen[d] + 2.0 * (cen[d] - p[2][d]), lo[d], hi[d]);
            double fe = obj2(c, xe);
            if (fe < fr) {
                memcpy(p[2], xe, sizeof xe);
                f[2] = fe;
            } else {
                memcpy(p[2], xr, sizeof xr);
                f[2] = fr;
            }
        } else if (fr < f[1]) {
            memcpy(p[2], xr, sizeof xr);
            f[2] = fr;
        } else {
            int outside = fr < f[2];
            for (int d = 0; d < 2; d++)
                xc[d] =
                    outside ? cen[d] + 0.5 * (xr[d] - cen[d]) : cen[d] + 0.5 * (p[2][d] - cen[d]);
            double fc = obj2(c, xc);
            if (fc < (outside ? fr : f[2])) {
                memcpy(p[2], xc, sizeof xc);
                f[2] = fc;
            } else {
                for (int i = 1; i < 3; i++) {
                    for (int d = 0; d < 2; d++) p[i][d] = p[0][d] + 0.5 * (p[i][d] - p[0][d]);
                    f[i] = obj2(c, p[i]);
                }
            }
        }
    }
    int best = 0;
    for (int i = 1; i < 3; i++)
        if (f[i] < f[best]) best = i;
    x0[0] = p[best][0];
    x0[1] = p[best][1];
}

ss_status ss_render_fit(ss_render_model m, const ss_brdf_sampled *data, const ss_fit_options *o,
                        ss_fit_result *out, ss_error *err) {
    ss_fit_options def;
    if (!o) {
        ss_fit_options_default(&def);
        o = &def;
    }
    memset(out, 0, sizeof *out);
    if (m != SS_RENDER_GGX && m != SS_RENDER_AS)
        return ss_error_set(err, SS_ERR_INPUT, "fit: unknown render model %d", (int)m);
    if (!data || !data->f_rgb || data->n_theta_i < 1 || data->n_theta_r < 1 || data->n_phi < 1 ||
        data->n_theta_i > 1024 || data->n_theta_r > 1024 || data->n_phi > 1024)
        return ss_error_set(err, SS_ERR_INPUT, "fit: sampled BRDF is empty or has bad bin counts");
    if (o->subsamples < 1 || o->subsamples > 16 || o->max_iter < 1 || o->weighting < 0 ||
        o->weighting > SS_FIT_PROJECTED || o->base_mode < SS_FIT_BASE_FREE ||
        o->base_mode > SS_FIT_BASE_ALBEDO ||
        !(o->max_theta_rad > 0.0 && o->max_theta_rad <= M_PI / 2))
        return ss_error_set(err, SS_ERR_INPUT,
                            "fit: bad options (subsamples %d, max_iter %d, weighting %d, "
                            "max theta %g rad)",
                            o->subsamples, o->max_iter, o->weighting, o->max_theta_rad);
    int nti = data->n_theta_i, ntr = data->n_theta_r, nph = data->n_phi;
    size_t nbins = (size_t)nti * ntr * nph;
    for (size_t i = 0; i < nbins * 3; i++)
        if (!isfinite(data->f_rgb[i]))
            return ss_error_set(err, SS_ERR_INPUT, "fit: sampled BRDF value %zu is not finite", i);
    fit_ctx c;
    memset(&c, 0, sizeof c);
    c.model = m;
    c.base_mode = o->base_mode;
    if (o->base_mode == SS_FIT_BASE_ALBEDO) {
        for (int ch = 0; ch < 3; ch++) {
            if (!(o->albedo_rgb[ch] >= 0.0 && o->albedo_rgb[ch] <= 1.0))
                return ss_error_set(err, SS_ERR_INPUT,
                                    "fit: albedo channel %d = %g is outside 0..1", ch,
                                    o->albedo_rgb[ch]);
            c.albedo[ch] = o->albedo_rgb[ch];
        }
        if (o->surface) {
            if (!o->surface->f_rgb || o->surface->n_theta_i != data->n_theta_i ||
                o->surface->n_theta_r != data->n_theta_r || o->surface->n_phi != data->n_phi)
                return ss_error_set(err, SS_ERR_INPUT,
                                    "fit: the surface BRDF's bins differ from the data's");
            c.surface = o->surface->f_rgb;
        }
    }
    c.nbins = (int)nbins;
    c.nsub = o->subsamples * o->subsamples;
    c.data = data->f_rgb;
    double *weight = malloc(nbins * sizeof(double));
    c.geom = malloc(nbins * (size_t)c.nsub * sizeof(ss_render_geom));
    c.subw = malloc(nbins * (size_t)c.nsub * sizeof(double));
    c.A = malloc(nbins * sizeof(double));
    c.S = malloc(nbins * sizeof(double));
    if (!weight || !c.geom || !c.subw || !c.A || !c.S) {
        free(weight);
        free(c.geom);
        free(c.subw);
        free(c.A);
        free(c.S);
        return ss_error_set(err, SS_ERR_NOMEM, "fit: out of memory");
    }
    c.weight = weight;
    double dti = M_PI / 2 / nti, dtr = M_PI / 2 / ntr, dp = M_PI / nph;
    int ns = o->subsamples;
    double wsum = 0, fsum2 = 0;
    for (int ti = 0; ti < nti; ti++) {
        double thi = (ti + 0.5) * dti;
        for (int tr = 0; tr < ntr; tr++) {
            double t0 = tr * dtr, t1 = (tr + 1) * dtr;
            double omega = (cos(t0) - cos(t1)) * dp; /* exit bin solid angle, sr */
            for (int ph = 0; ph < nph; ph++) {
                size_t b = ((size_t)ti * ntr + tr) * nph + ph;
                if (o->weighting == SS_FIT_UNIFORM)
                    weight[b] = dti * dtr * dp;
                else if (o->weighting == SS_FIT_PROJECTED)
                    weight[b] = omega * dti * cos(thi) * cos((tr + 0.5) * dtr);
                else
                    weight[b] = omega * dti;
                if (thi > o->max_theta_rad || (tr + 0.5) * dtr > o->max_theta_rad) weight[b] = 0.0;
                wsum += weight[b];
                for (int ch = 0; ch < 3; ch++)
                    fsum2 += weight[b] * data->f_rgb[b * 3 + ch] * data->f_rgb[b * 3 + ch];
                /* bin estimate as the photon tally: int f cos dw / (omega cos(centre)) */
                double sw = 0, cc = cos((tr + 0.5) * dtr);
                for (int a = 0; a < ns; a++) {
                    double thr = (tr + (a + 0.5) / ns) * dtr;
                    double w = sin(thr) * cos(thr);
                    for (int q = 0; q < ns; q++) {
                        size_t k = b * (size_t)c.nsub + (size_t)a * ns + q;
                        ss_render_geom_init(thi, thr, (ph + (q + 0.5) / ns) * dp, &c.geom[k]);
                        c.subw[k] = w;
                        sw += sin(thr) * cc;
                    }
                }
                for (int k = 0; k < c.nsub; k++) c.subw[b * (size_t)c.nsub + k] /= sw;
            }
        }
    }
    if (!(wsum > 0.0)) {
        free(weight);
        free(c.geom);
        free(c.subw);
        free(c.A);
        free(c.S);
        return ss_error_set(err, SS_ERR_INPUT,
                            "fit: no bin lies below the maximum angle %g degrees",
                            o->max_theta_rad * 180.0 / M_PI);
    }
    /* Coarse grid over (specular, roughness), then Nelder-Mead from the best
     * node, restarted once from its own result. */
    double best[2] = {0.5, 0.5}, fbest = INFINITY;
    for (int i = 0; i <= 10; i++)
        for (int j = 0; j <= 12; j++) {
            double x[2] = {i / 10.0,
                           SS_RENDER_ROUGHNESS_MIN + (1.0 - SS_RENDER_ROUGHNESS_MIN) * j / 12.0};
            double f = obj2(&c, x);
            if (f < fbest) {
                fbest = f;
                best[0] = x[0];
                best[1] = x[1];
            }
        }
    nelder_mead(&c, best, 0.05, o->max_iter, o->tol);
    nelder_mead(&c, best, 0.01, o->max_iter, o->tol);
    double base[3];
    double dist = objective(&c, best[0], best[1], base);
    if (c.surface) { /* report the whole BRDF's distance */
        c.surface = NULL;
        dist = objective(&c, best[0], best[1], base);
    }
    out->model = m;
    for (int ch = 0; ch < 3; ch++) out->params.base_rgb[ch] = base[ch];
    out->params.specular = clampd(best[0], 0.0, 1.0);
    out->params.roughness = clampd(best[1], SS_RENDER_ROUGHNESS_MIN, 1.0);
    out->distance = dist;
    out->residual_rms = sqrt(dist / (3.0 * wsum));
    out->residual_rel = fsum2 > 0 ? sqrt(dist / fsum2) : 0.0;
    out->evaluations = c.evals;
    free(weight);
    free(c.geom);
    free(c.subw);
    free(c.A);
    free(c.S);
    return SS_OK;
}
