/* Constitutive laws of the contraction mechanics (seed 001 §4.2, §4.3, §5.2)
 * and their parameters.
 *
 * - p_cell(theta): the seed's piecewise-linear active pressure of the
 *   myofibroblasts [MGAD08]. The seed's second case reads "theta <= theta1
 *   <= theta*"; it is the interval theta1 <= theta <= theta* (the line
 *   through (theta1, K_pas theta1) and (theta*, p_max + K_pas theta*)).
 * - GOH energy [GOH06]: isochoric neo-Hooke ground + volumetric K/2 (J-1)^2,
 *   two fibre families Psi_fi = k1/(2 k2) (exp(k2 E_i^2) - 1) with
 *   E_i = H_i : C - 1, H_i = kappa I + (1 - 3 kappa) a_i (x) a_i. The fibre
 *   invariants use the full C (not C-bar, Nolan et al. 2014 show the isochoric
 *   fibre invariants are unphysical) and act in compression too: the seed's
 *   contraction compresses, and Fig. 7's anisotropy comes from the fibre terms.
 * - per-spring energy (§5.2): the active stress sigma drives an isotropic
 *   volumetric strain sigma / K_bulk in the ground matrix; its GOH energy is
 *   weighted onto a spring of direction e as Psi_g + w_1 Psi_f1 + w_2 Psi_f2,
 *   w_i = kappa + (1 - 3 kappa) |a_i . e|. At kappa = 0 this is the seed's
 *   |a_i . e / |e||; at kappa = 1/3 (isotropic dispersion) every direction
 *   weighs the same, as H_i = I/3 says. The seed prints Psi_f1 in both terms;
 *   the second is family 2's. Delta l = sqrt(2 Psi_e / k) with Psi_e = V psi,
 *   k = 9 K_bulk V / l^2 (a spring network of the ground alone then shortens
 *   by exactly the linear strain theta/3), so Delta l / l = sqrt(2 psi / 9 K).
 * Parameters: data/heal/mechanics.json, every value with unit and source. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "skinsim/mech.h"

typedef struct key {
    const char *name, *unit;
    size_t off;
    double lo, hi;
    int is_int;
} key;

#define K(n, u, lo, hi)                                                                            \
    { #n, u, offsetof(ss_mech_params, n), lo, hi, 0 }
static const key keys[] = {
    K(K_pas, "kPa", 0, 1e6),
    K(K_act, "kPa", 1e-9, 1e6),
    K(p_max, "kPa", 0, 1e6),
    K(theta1, "1", -0.99, -1e-9),
    K(theta2, "1", 1e-9, 10),
    K(K_m, "1", 0, 1e6),
    K(tau_myo, "day", 0, 1e3),
    K(tau_proto, "day", 1e-3, 1e3),
    K(gf_half, "1", 1e-6, 1e3),
    K(rho_myo, "1", 0, 1e3),
    K(tau_apo, "day", 1e-3, 1e4),
    K(tau_remodel, "day", 0, 1e3),
    K(mu, "kPa", 0, 1e7),
    K(K_bulk, "kPa", 1e-9, 1e7),
    K(k1, "kPa", 0, 1e7),
    K(k2, "1", 0, 1e3),
    K(kappa, "1", 0, 1.0 / 3.0),
    K(ecm_floor, "1", 1e-3, 1),
    K(tet_size_mm, "mm", 1e-3, 1e3),
    K(anchor, "kPa/mm", 0, 1e6),
    K(anchor_side, "kPa/mm", 0, 1e6),
    K(k_suture, "mN/mm", 0, 1e9),
    K(max_shorten, "1", 0, 0.9),
    K(j_min, "1", 0, 0.9),
    K(tol, "1", 1e-9, 0.1),
    {"max_substeps", "1", offsetof(ss_mech_params, max_substeps), 1, 1e6, 1},
    K(k1_goh, "kPa", 0, 1e7),
    K(prestretch, "1", 1, 1.5),
    K(k_suture_goh, "mN/mm", 0, 1e9),
    K(K_m_goh, "1", 0, 1e6),
    K(tau_contract_goh, "day", 0, 1e3),
};
#undef K
#define NKEYS (sizeof keys / sizeof keys[0])

void ss_mech_params_default(ss_mech_params *p) {
    memset(p, 0, sizeof *p);
    p->K_pas = 1.0;
    p->K_act = 100.0;
    p->p_max = 5.0;
    p->theta1 = -0.9;
    p->theta2 = 0.5;
    p->K_m = 25.0;
    p->tau_myo = 7.0;
    p->tau_proto = 3.0;
    p->gf_half = 0.2;
    p->rho_myo = 0.3;
    p->tau_apo = 14.0;
    p->tau_remodel = 4.0;
    p->mu = 13.5;
    p->K_bulk = 29.0;
    p->k1 = 90000.0;
    p->k2 = 1.0;
    p->kappa = 0.0;
    p->fibre[0][0] = 1.0;
    p->nfibres = 1;
    p->ecm_floor = 0.5;
    p->tet_size_mm = 1.0;
    p->anchor = 0.1;
    p->anchor_side = 1.6;
    p->k_suture = 1.0;
    p->max_shorten = 0.8;
    p->j_min = 0.2;
    p->tol = 1e-4;
    p->max_substeps = 400;
    p->model = SS_MECH_MODEL_SPRINGS;
    p->k1_goh = 100.0;
    p->prestretch = 1.15;
    p->k_suture_goh = 1000.0;
    p->K_m_goh = 150.0;
    p->tau_contract_goh = 4.0;
}

ss_status ss_mech_model_parse(const char *text, int *model, ss_error *err) {
    if (text && !strcmp(text, "springs"))
        *model = SS_MECH_MODEL_SPRINGS;
    else if (text && !strcmp(text, "goh"))
        *model = SS_MECH_MODEL_GOH;
    else
        return ss_error_set(err, SS_ERR_INPUT, "mechanics model '%s' is not 'springs' or 'goh'",
                            text ? text : "");
    return SS_OK;
}

const char *ss_mech_model_name(int model) { return model == SS_MECH_MODEL_GOH ? "goh" : "springs"; }

const char *ss_mech_param_unit(const char *k) {
    if (!k) return NULL;
    if (!strcmp(k, "fibres") || !strcmp(k, "model")) return "1";
    for (size_t i = 0; i < NKEYS; i++)
        if (!strcmp(keys[i].name, k)) return keys[i].unit;
    return NULL;
}

static double get(const ss_mech_params *p, const key *k) {
    const char *b = (const char *)p + k->off;
    if (k->is_int) return *(const int *)(const void *)b;
    return *(const double *)(const void *)b;
}

static void set(ss_mech_params *p, const key *k, double v) {
    char *b = (char *)p + k->off;
    if (k->is_int)
        *(int *)(void *)b = (int)v;
    else
        *(double *)(void *)b = v;
}

ss_status ss_mech_params_set(ss_mech_params *p, const char *k, const char *v, ss_error *err) {
    if (!k || !v) return ss_error_set(err, SS_ERR_INPUT, "mechanics parameter: no name or value");
    if (!strcmp(k, "fibres")) return ss_mech_params_set_fibres(p, v, err);
    if (!strcmp(k, "model")) return ss_mech_model_parse(v, &p->model, err);
    for (size_t i = 0; i < NKEYS; i++) {
        if (strcmp(keys[i].name, k)) continue;
        char *end;
        double x = strtod(v, &end);
        if (end == v || *end || !isfinite(x))
            return ss_error_set(err, SS_ERR_INPUT, "mechanics parameter %s: '%s' is not a number",
                                k, v);
        if (x < keys[i].lo || x > keys[i].hi || (keys[i].is_int && x != floor(x)))
            return ss_error_set(err, SS_ERR_INPUT, "mechanics parameter %s = %g outside %g..%g %s",
                                k, x, keys[i].lo, keys[i].hi, keys[i].unit);
        set(p, &keys[i], x);
        return SS_OK;
    }
    return ss_error_set(err, SS_ERR_INPUT, "unknown mechanics parameter '%s'", k);
}

ss_status ss_mech_params_set_fibres(ss_mech_params *p, const char *text, ss_error *err) {
    double a[2][3] = {{0}};
    int n = 0;
    const char *s = text;
    if (!s || !*s)
        return ss_error_set(err, SS_ERR_INPUT, "--fibres: empty (expected X,Y,Z[:X,Y,Z])");
    while (n < 2) {
        char *end;
        for (int d = 0; d < 3; d++) {
            a[n][d] = strtod(s, &end);
            if (end == s || !isfinite(a[n][d]))
                return ss_error_set(err, SS_ERR_INPUT,
                                    "--fibres '%s': expected X,Y,Z[:X,Y,Z] with finite numbers",
                                    text);
            s = end;
            if (d < 2) {
                if (*s != ',')
                    return ss_error_set(err, SS_ERR_INPUT, "--fibres '%s': expected X,Y,Z[:X,Y,Z]",
                                        text);
                s++;
            }
        }
        double len = sqrt(a[n][0] * a[n][0] + a[n][1] * a[n][1] + a[n][2] * a[n][2]);
        if (!(len > 1e-12))
            return ss_error_set(err, SS_ERR_INPUT, "--fibres '%s': fibre %d is the zero vector",
                                text, n + 1);
        for (int d = 0; d < 3; d++) a[n][d] /= len;
        n++;
        if (*s == ':') {
            s++;
            continue;
        }
        break;
    }
    if (*s) return ss_error_set(err, SS_ERR_INPUT, "--fibres '%s': unexpected '%s'", text, s);
    if (n == 2) {
        double c = fabs(a[0][0] * a[1][0] + a[0][1] * a[1][1] + a[0][2] * a[1][2]);
        if (c > 1.0 - 1e-9)
            return ss_error_set(err, SS_ERR_INPUT,
                                "--fibres '%s': the two fibre families are parallel", text);
    }
    memcpy(p->fibre, a, sizeof a);
    p->nfibres = n;
    return SS_OK;
}

ss_status ss_mech_params_check(const ss_mech_params *p, ss_error *err) {
    for (size_t i = 0; i < NKEYS; i++) {
        double v = get(p, &keys[i]);
        if (!isfinite(v) || v < keys[i].lo || v > keys[i].hi)
            return ss_error_set(err, SS_ERR_INPUT, "mechanics parameter %s = %g %s outside %g..%g",
                                keys[i].name, v, keys[i].unit, keys[i].lo, keys[i].hi);
    }
    double ts = p->p_max / p->K_act;
    if (!(p->theta1 < ts && ts < p->theta2))
        return ss_error_set(err, SS_ERR_INPUT,
                            "mechanics parameters: need theta1 (%g) < theta* = p_max/K_act (%g) < "
                            "theta2 (%g)",
                            p->theta1, ts, p->theta2);
    if (p->model != SS_MECH_MODEL_SPRINGS && p->model != SS_MECH_MODEL_GOH)
        return ss_error_set(err, SS_ERR_INPUT, "mechanics: model must be springs or goh");
    if (p->nfibres < 1 || p->nfibres > 2)
        return ss_error_set(err, SS_ERR_INPUT, "mechanics: 1 or 2 fibre families");
    return SS_OK;
}

ss_status ss_mech_params_parse(ss_mech_params *p, const char *json_text, const char *what,
                               ss_error *err) {
    cJSON *root = cJSON_Parse(json_text);
    if (!root || !cJSON_IsObject(root)) {
        cJSON_Delete(root);
        return ss_error_set(err, SS_ERR_INPUT, "%s: not a JSON object", what);
    }
    ss_status st = SS_OK;
    const cJSON *mo = cJSON_GetObjectItemCaseSensitive(root, "mechanics");
    if (mo && !cJSON_IsObject(mo)) {
        st = ss_error_set(err, SS_ERR_INPUT, "%s: 'mechanics' must be an object", what);
        goto done;
    }
    const cJSON *it;
    cJSON_ArrayForEach(it, mo) {
        if (!strcmp(it->string, "comment")) continue;
        const char *unit = ss_mech_param_unit(it->string);
        if (!unit) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s: unknown mechanics parameter '%s'", what,
                              it->string);
            goto done;
        }
        const cJSON *v = cJSON_GetObjectItemCaseSensitive(it, "value");
        const cJSON *u = cJSON_GetObjectItemCaseSensitive(it, "unit");
        if (!cJSON_IsObject(it) || !v) {
            st = ss_error_set(err, SS_ERR_INPUT,
                              "%s: mechanics parameter '%s' must be {\"value\", \"unit\", "
                              "\"source\"}",
                              what, it->string);
            goto done;
        }
        if (!cJSON_IsString(u) || strcmp(u->valuestring, unit)) {
            st = ss_error_set(err, SS_ERR_INPUT,
                              "%s: mechanics parameter '%s' needs \"unit\": \"%s\"", what,
                              it->string, unit);
            goto done;
        }
        if (!strcmp(it->string, "fibres")) {
            if (!cJSON_IsString(v)) {
                st = ss_error_set(err, SS_ERR_INPUT, "%s: 'fibres' value must be \"X,Y,Z[:X,Y,Z]\"",
                                  what);
                goto done;
            }
            if ((st = ss_mech_params_set_fibres(p, v->valuestring, err)) != SS_OK) goto done;
            continue;
        }
        if (!strcmp(it->string, "model")) {
            if (!cJSON_IsString(v)) {
                st = ss_error_set(err, SS_ERR_INPUT,
                                  "%s: 'model' value must be \"springs\" or \"goh\"", what);
                goto done;
            }
            if ((st = ss_mech_model_parse(v->valuestring, &p->model, err)) != SS_OK) goto done;
            continue;
        }
        if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble)) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s: mechanics parameter '%s' is not a number",
                              what, it->string);
            goto done;
        }
        for (size_t i = 0; i < NKEYS; i++)
            if (!strcmp(keys[i].name, it->string)) {
                double x = v->valuedouble;
                if (x < keys[i].lo || x > keys[i].hi || (keys[i].is_int && x != floor(x))) {
                    st = ss_error_set(err, SS_ERR_INPUT,
                                      "%s: mechanics parameter '%s' = %g outside %g..%g %s", what,
                                      it->string, x, keys[i].lo, keys[i].hi, unit);
                    goto done;
                }
                set(p, &keys[i], x);
            }
    }
    ss_error e2;
    if (ss_mech_params_check(p, &e2) != SS_OK)
        st = ss_error_set(err, SS_ERR_INPUT, "%.200s: %.800s", what, e2.msg);
done:
    cJSON_Delete(root);
    return st;
}

char *ss_mech_params_to_json(const ss_mech_params *p) {
    cJSON *root = cJSON_CreateObject();
    cJSON *mo = cJSON_AddObjectToObject(root, "mechanics");
    for (size_t i = 0; i < NKEYS; i++) {
        cJSON *o = cJSON_AddObjectToObject(mo, keys[i].name);
        cJSON_AddNumberToObject(o, "value", get(p, &keys[i]));
        cJSON_AddStringToObject(o, "unit", keys[i].unit);
    }
    char fb[160];
    int n = snprintf(fb, sizeof fb, "%.17g,%.17g,%.17g", p->fibre[0][0], p->fibre[0][1],
                     p->fibre[0][2]);
    if (p->nfibres == 2)
        snprintf(fb + n, sizeof fb - (size_t)n, ":%.17g,%.17g,%.17g", p->fibre[1][0],
                 p->fibre[1][1], p->fibre[1][2]);
    cJSON *o = cJSON_AddObjectToObject(mo, "fibres");
    cJSON_AddStringToObject(o, "value", fb);
    cJSON_AddStringToObject(o, "unit", "1");
    o = cJSON_AddObjectToObject(mo, "model");
    cJSON_AddStringToObject(o, "value", ss_mech_model_name(p->model));
    cJSON_AddStringToObject(o, "unit", "1");
    char *s = cJSON_Print(root);
    cJSON_Delete(root);
    return s;
}

/* ---- laws -------------------------------------------------------------------- */

double ss_mech_pcell(const ss_mech_params *p, double th) {
    const double ts = p->p_max / p->K_act;
    if (th < p->theta1 || th > p->theta2) return p->K_pas * th;
    if (th <= ts)
        return p->K_act * p->p_max / (p->K_act * p->theta1 - p->p_max) * (p->theta1 - th) +
               p->K_pas * th;
    return p->K_act * p->p_max / (p->K_act * p->theta2 - p->p_max) * (p->theta2 - th) +
           p->K_pas * th;
}

static double fibre_psi(const ss_mech_params *p, double E) {
    if (p->k2 < 1e-12) return 0.5 * p->k1 * E * E;
    return p->k1 / (2.0 * p->k2) * expm1(p->k2 * E * E);
}

void ss_mech_goh_energy(const ss_mech_params *p, const double C[9], double *psi_g,
                        double psi_f[2]) {
    double I1 = C[0] + C[4] + C[8];
    double det = C[0] * (C[4] * C[8] - C[5] * C[7]) - C[1] * (C[3] * C[8] - C[5] * C[6]) +
                 C[2] * (C[3] * C[7] - C[4] * C[6]);
    double J = sqrt(det > 0 ? det : 0);
    double I1bar = J > 0 ? I1 * pow(J, -2.0 / 3.0) : 3.0;
    *psi_g = 0.5 * p->mu * (I1bar - 3.0) + 0.5 * p->K_bulk * (J - 1.0) * (J - 1.0);
    for (int i = 0; i < 2; i++) {
        psi_f[i] = 0;
        if (i >= p->nfibres) continue;
        const double *a = p->fibre[i];
        double I4 = 0;
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++) I4 += a[r] * C[3 * r + c] * a[c];
        double E = p->kappa * I1 + (1.0 - 3.0 * p->kappa) * I4 - 1.0;
        psi_f[i] = fibre_psi(p, E);
    }
}

double ss_mech_spring_energy_density(const ss_mech_params *p, double sigma, const double e[3]) {
    double th = sigma / p->K_bulk; /* volumetric contraction the stress drives */
    if (th > 0.9) th = 0.9;
    if (th < -0.9) th = -0.9;
    double J = 1.0 - th, l2 = pow(J, 2.0 / 3.0);
    double C[9] = {l2, 0, 0, 0, l2, 0, 0, 0, l2};
    double pg, pf[2];
    ss_mech_goh_energy(p, C, &pg, pf);
    double len = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    double psi = pg;
    for (int i = 0; i < p->nfibres; i++) {
        double c =
            len > 0
                ? fabs(p->fibre[i][0] * e[0] + p->fibre[i][1] * e[1] + p->fibre[i][2] * e[2]) / len
                : 0;
        psi += (p->kappa + (1.0 - 3.0 * p->kappa) * c) * pf[i];
    }
    return psi;
}

double ss_mech_shortening(const ss_mech_params *p, double psi) {
    double s = sqrt(2.0 * (psi > 0 ? psi : 0) / (9.0 * p->K_bulk));
    return s > p->max_shorten ? p->max_shorten : s;
}
