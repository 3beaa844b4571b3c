/* Parameters of the §4.1 healing model (seed 001) and the scenario presets of
 * §6 / Fig. 2: clean regeneration, scab formation, keloid overgrowth. Every
 * parameter has a unit and a source (table below); JSON files give
 * {"value", "unit", "source"} per key and are checked key by key (unknown key,
 * missing or wrong unit, bad value -> SS_ERR_INPUT naming the key). The
 * shipped data/heal/<scenario>.json files equal these built-in presets. */
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "skinsim/heal.h"

typedef struct pdef {
    const char *key;
    size_t off;
    const char *unit;
    const char *source;
    double clean, scab, keloid; /* preset values */
} pdef;

#define OFF(m) offsetof(ss_heal_params, m)
#define CAL "calibrated: 2x2 cm shallow wound against the clinical course (docs/heal-model.md)"
#define DIM "dimensional reasoning (docs/heal-model.md)"
static const pdef PDEFS[] = {
    {"D1", OFF(D1), "mm^2/day",
     "effective, " DIM ": oxygen penetration sqrt(D1/lam11) = 0.45 mm, the scale of a shallow "
     "wound; molecular O2 diffusivity (2e-5 cm^2/s = 173 mm^2/day) would make u1 quasi-static",
     2.0, 2.0, 2.0},
    {"lam11", OFF(lam11), "1/day", DIM ": oxygen relaxes within hours (1/lam11 = 2.4 h)", 10.0,
     10.0, 10.0},
    {"lam31", OFF(lam31), "1/day",
     "set equal to lam11 so healthy tissue (u3 = 1) has u1 = 1 (normalisation, seed §4.1.1)", 10.0,
     10.0, 10.0},
    {"D2", OFF(D2), "mm^2/day", DIM ": growth-factor spread of ~1 mm in a day", 0.5, 0.5, 0.5},
    {"lam12", OFF(lam12), "1/day", CAL, 5.0, 5.0, 5.0},
    {"lam22", OFF(lam22), "1/day",
     DIM ": MDGF half-life ~8 h, range sqrt(D2/lam22) = 0.5 mm; Jin et al. 2011 (BMC Syst Biol "
         "5:60, Table 4) use a TGF-beta decay of 15/day (half-life ~1 h), which would confine the "
         "signal to 0.18 mm, below the voxel (docs/heal-model.md §5)",
     2.0, 2.0, 2.0},
    {"u1_beta2", OFF(u1_beta2), "1",
     "seed §4.1.2 threshold u1^beta2; below healthy u1 = 1 so intact tissue makes no MDGF", 0.8,
     0.8, 0.8},
    {"D3", OFF(D3), "mm^2/day", CAL ": capillary front 0.3-0.8 mm/day", 0.05, 0.05, 0.05},
    {"lam33", OFF(lam33), "1/day", CAL, 0.15, 0.15, 0.15},
    {"lam32", OFF(lam32), "1/day", CAL, 0.5, 0.5, 0.5},
    {"u3_eq", OFF(u3_eq), "1", "normalisation: healthy capillary density = 1", 1.0, 1.0, 1.0},
    {"Dn", OFF(Dn), "mm^2/day", DIM ": fibroblast random motility ~0.01-0.1 mm^2/day", 0.05, 0.05,
     0.05},
    {"rn", OFF(rn), "1/day",
     DIM ": fibroblast doubling ~1 day when oxygenated; Jin et al. 2011 (BMC Syst Biol 5:60, "
         "Table 4) use a fibroblast growth rate of 0.924/day",
     0.8, 0.8, 0.8},
    {"K", OFF(K), "1", "normalisation: fibroblast capacity = 1", 1.0, 1.0, 1.0},
    {"lamnn", OFF(lamnn), "1/day",
     DIM ": fibroblast lifetime ~1 week; Jin et al. 2011 (BMC Syst Biol 5:60, Table 4) use a "
         "fibroblast apoptosis rate of 0.12/day",
     0.15, 0.15, 0.15},
    {"Ds", OFF(Ds), "mm^2/day",
     CAL ": the crust spreads along its layer only (x-y; it is confined to the top scab_mm, "
         "docs/heal-model.md [D6]), smoothing its edge over sqrt(Ds t) ~0.3 mm in 2 weeks",
     0.005, 0.005, 0.005},
    {"Rs", OFF(Rs), "1/day",
     CAL ": scab within the first day on a dry wound (seed §3); only used with scab = 1", 4.0, 4.0,
     4.0},
    {"lames", OFF(lames), "1/day",
     CAL ": keratinocytes dissolve the eschar from underneath (Kubo et al. 2001, seed [KWP01]); "
         "the scab detaches days after closure (clinically within 1-2 weeks)",
     0.3, 0.3, 0.3},
    {"De", OFF(De), "mm^2/day",
     CAL ": epithelial front 2 sqrt(De lamge) = 1.3 mm/day on a ready bed; front width "
         "sqrt(De/lamge) = 0.9 mm so 0.5 mm voxels resolve it (docs/heal-model.md)",
     0.6, 0.6, 0.6},
    {"lamge", OFF(lamge), "1/day", CAL ": with De, the front speed above", 0.75, 0.75, 0.75},
    {"lamee", OFF(lamee), "1/day",
     "seed §4.1.6 loss term kept, set to 0: a closed new epidermis renews itself like the intact "
     "one (held at 1); a positive value strips it within months once Q(u3) -> 0 on the "
     "revascularised bed",
     0, 0, 0},
    {"gamma1", OFF(gamma1), "1",
     CAL ": capillary density of maximal Q (seed §4.1.6); high so the epithelial window stays open "
         "while granulation matures",
     0.8, 0.8, 0.8},
    {"lamnrho", OFF(lamnrho), "1/day",
     CAL ": scar forms during the first 1-2 weeks, peak density ~1.5 x normal dermis", 0.6, 0.6,
     0.6},
    {"lamrhop", OFF(lamrhop), "1/day",
     "remodelling half-life ln 2 / lamrhop = 120 days (clean, scab) of the collagen above "
     "rho_mature (docs/heal-model.md [D10]): scar maturation takes 6-24 "
     "months (Gurtner et al. 2008, Nature 453:314; Bayat et al. 2003, BMJ 326:88); keloid 365 "
     "days: keloids do not regress",
     0.005776, 0.005776, 0.0019},
    {"rho_open", OFF(rho_open), "1",
     "departure from §4.1.7 (docs/heal-model.md): fibroblasts keep depositing collagen in "
     "vascularised granulation tissue as long as the wound above is open, so delayed closure "
     "scars more (seed §4.1.5; Deitch 1983). Calibrated: peak scar scab > clean",
     0.3, 0.3, 0.3},
    {"lamkrho", OFF(lamkrho), "1/day",
     "keloid only (departure from §4.1.7, docs/heal-model.md): autocrine collagen deposition of "
     "keloid fibroblasts in the wound region, independent of vascularisation and closure; in "
     "tissue not yet keloid (rho < rho_max) scaled by the invasion signal (keloid_tau). "
     "Calibrated with keloid_tau: scar denser than the clean peak >= 2 mm beyond the margin by "
     "day 60, then slower invasion (keloid_floor, docs/heal-model.md §6); keloid fibroblasts "
     "synthesise ~20x the "
     "collagen of normal ones (Craig et al. 1975, Eur J Clin Invest 5:69)",
     0, 0, 0.6},
    {"Dp", OFF(Dp), "mm^2/day",
     DIM ": clot plasma spreads ~mm in days; keloid: with lamkrho, rho_max and keloid_tau it "
         "sets the front speed (calibrated, docs/heal-model.md §6)",
     0.05, 0.05, 0.08},
    {"lampp", OFF(lampp), "1/day",
     "signed; negative = resorption of the clot (half-life 35 days; keloid 17 days); with it the "
     "far field relaxes to p = 0 within sqrt(Dp/|lampp|) (keloid 1.4 mm) of the region, so the "
     "block walls do not shape it (keloid: calibrated so that 30 and 50 mm blocks give the same "
     "extent at day 365, docs/heal-model.md §6); only used with static_region = 0",
     -0.02, -0.02, -0.04},
    {"rho_max", OFF(rho_max), "1",
     "seed §4.1.8 collagen threshold of C(rho); clean/scab: unused (static region); keloid: "
     "calibrated with lamkrho and Dp (docs/heal-model.md)",
     1, 1, 0.3},
    {"u1_wound", OFF(u1_wound), "1", "hypoxic clot: no oxygen at t = 0 (seed §3)", 0.0, 0.0, 0.0},
    {"bed_mm", OFF(bed_mm), "mm",
     "depth of the wound bed under the epithelial sheet whose mean capillary density enters "
     "Q(u3) (seed §4.1.6: the epithelium grows on granulation tissue)",
     1.0, 1.0, 1.0},
    {"scab_mm", OFF(scab_mm), "mm",
     "thickness of the exposed layer that dries into eschar (R(omega) of seed §4.1.5)", 0.5, 0.5,
     0.5},
    {"kscab", OFF(kscab), "1",
     "departure from §4.1.6 (docs/heal-model.md): under a scab the epithelium has to cleave its "
     "way beneath the eschar (Winter 1962; Hinman & Maibach 1963); a full eschar slows its "
     "migration and growth by this fraction. Calibrated with kang: dry/moist time to 95 % closure "
     "~2",
     0.55, 0.55, 0.55},
    {"kang", OFF(kang), "1",
     "departure from §4.1.3 (docs/heal-model.md): dry wounds revascularise more slowly in every "
     "zone of the wound bed (Dyson et al. 1992, J Invest Dermatol 99:729); a full crust over a "
     "column slows capillary growth in the wound region below it by this fraction (the seed's "
     "(1 - s) acts in the crust itself). Calibrated with kscab: dry/moist time to 95 % closure ~2 "
     "with a peak scar below the keloid's packing limit",
     0.9, 0.9, 0.9},
    {"rho_sat", OFF(rho_sat), "1",
     "packing limit of scar collagen, x normal dermis (docs/heal-model.md): collagen is 70-80 % "
     "of the dermis' dry weight in a tissue that is ~2/3 water, i.e. ~0.3 of its volume; a "
     "keloid's dense hyalinised bundles can at most fill ~0.9, so ~3 x; the keloid's autocrine "
     "deposition (lamkrho) saturates as (1 - rho/rho_sat)",
     3.0, 3.0, 3.0},
    {"keloid_tau", OFF(keloid_tau), "day",
     "keloid only (docs/heal-model.md §2 [D6]): e-folding time of the acute part of the invasion "
     "signal (the inflammation at the keloid's leading edge, Eura et al. 2022, PRS Glob Open "
     "10:e4374; Limandjaja et al. 2020, Front Cell Dev Biol 8:360) that converts normal dermis "
     "at the margin into keloid; established keloid (rho > rho_max) deposits without it. "
     "Calibrated with keloid_floor (no published growth rate found): the front advances ~1.3 mm "
     "in the first month, as before; 0 = no decay (the full signal persists)",
     20.0, 20.0, 20.0},
    {"keloid_floor", OFF(keloid_floor), "1",
     "keloid only (docs/heal-model.md §2 [D6]): share of the invasion signal that persists after "
     "the acute phase. Keloids are driven by a chronic inflammation in the reticular dermis with "
     "neovascularisation at the leading edge that does not resolve (Eura et al. 2022; Ogawa "
     "2017, Int J Mol Sci 18:606) and keep invading the surrounding dermis for months to years "
     "(Bayat et al. 2003, BMJ 326:88), so the front keeps advancing at a slow steady rate "
     "(calibrated, no measured lateral rate found: ~0.4-0.5 mm per month after the first three "
     "months, docs/heal-model.md §6); 0 = the signal wanes and the front stops ~3 mm beyond the "
     "margin",
     0.02, 0.02, 0.02},
    {"rho_mature", OFF(rho_mature), "1",
     "collagen of a mature scar, x normal dermis (docs/heal-model.md §2 [D10]): remodelling "
     "(lamrhop) resorbs only the excess above it, so the scar matures to a permanent plateau "
     "instead of fading: the scar's collagen content levels off while synthesis and lysis go on "
     "(Madden & Peacock 1971, Ann Surg 174:511), type III is replaced by type I over 6-24 months "
     "and the mature scar reaches only ~70-80 % of the strength of normal skin (Levenson et al. "
     "1965, Ann Surg 161:293; Gurtner et al. 2008, Nature 453:314); 1 = the collagen of the "
     "dermis the scar replaced",
     1.0, 1.0, 1.0},
    {"kadn", OFF(kadn), "1/day",
     "adnexal re-epithelialisation (docs/heal-model.md §2 [D11]): outgrowth rate of the "
     "epithelium from surviving hair-follicle and sweat-gland remnants below a partial-thickness "
     "wound (eccrine glands are major contributors, Rittié et al. 2013, Am J Pathol 182:163; "
     "~1.4 follicles and ~1.3 eccrine glands per mm^2, Xu et al. 2017, J Am Acad Dermatol "
     "77:1133: ~1 mm apart, below the voxel, so an areal source). Calibrated: a 2 x 2 cm wound "
     "0.25 mm deep closes to 95 % in ~7 days (superficial partial-thickness wounds heal in 7-14 "
     "days from their adnexa, Deitch et al. 1983, J Trauma 23:895); 0 = the edge only",
     0.02, 0.02, 0.02},
    {"adnexa_mm", OFF(adnexa_mm), "mm",
     "wound depth at which no adnexal remnant is left to re-epithelialise (docs/heal-model.md §2 "
     "[D11]): the share that survives falls linearly from 1 at the surface to 0 here. Vellus "
     "follicles, the most numerous outside the scalp (Otberg et al. 2004, J Invest Dermatol "
     "122:14), end ~1 mm deep; deep dermal wounds keep few remnants and heal mostly from the "
     "edge, in more than 3 weeks with hypertrophic scarring (Deitch et al. 1983). At 1 mm the "
     "default wound heals from its edge only",
     1.0, 1.0, 1.0},
    {"keloid_mm", OFF(keloid_mm), "mm",
     "keloid only (docs/heal-model.md §2 [D12]): depth below the skin surface to which the "
     "keloid's autocrine deposition reaches. Keloids are driven by chronic inflammation in the "
     "reticular dermis (Eura et al. 2022, PRS Glob Open 10:e4374; Limandjaja et al. 2020, Front "
     "Cell Dev Biol 8:360: a dermal lesion) and do not fill the tissue below it; 2 mm, the depth "
     "of the dermis on the trunk and limbs (estimate); the deeper tissue of the block stays "
     "intact",
     2.0, 2.0, 2.0},
    {"keloid_gain", OFF(keloid_gain), "1",
     "keloid only (docs/heal-model.md [D16]): share of the keloid deposition that the packing "
     "limit refuses (the part its (1 - rho/rho_sat) factor removes) that stays as added tissue "
     "volume in its column, so the keloid keeps rising after its dermis saturates (keloids "
     "grow slowly over months to years and stand proud of the skin, Bayat et al. 2003, BMJ "
     "326:88; untreated keloids keep enlarging over 1-6 years of follow-up). Calibrated (no "
     "measured height growth rate found): the default keloid's elevation rises ~1 mm per 100 "
     "days after its dermis saturates; 0 = none",
     0.0, 0.0, 0.03},
};
#define NPDEFS ((int)(sizeof PDEFS / sizeof PDEFS[0]))
/* keys whose value may be negative */
static int may_be_negative(const char *key) { return !strcmp(key, "lampp"); }

static double *pval(ss_heal_params *p, const pdef *d) { return (double *)((char *)p + d->off); }

static const char *const SCEN[3] = {"clean", "scab", "keloid"};

const char *ss_heal_param_unit(const char *key) {
    if (!key) return NULL;
    for (int i = 0; i < NPDEFS; i++)
        if (!strcmp(PDEFS[i].key, key)) return PDEFS[i].unit;
    return NULL;
}

ss_heal_params *ss_heal_params_preset(const char *scenario, ss_error *err) {
    int k = -1;
    for (int i = 0; i < 3; i++)
        if (scenario && !strcmp(scenario, SCEN[i])) k = i;
    if (k < 0) {
        ss_error_set(err, SS_ERR_INPUT,
                     "heal scenario '%s' unknown; valid names: clean, scab, keloid",
                     scenario ? scenario : "(null)");
        return NULL;
    }
    ss_heal_params *p = calloc(1, sizeof *p);
    if (!p) {
        ss_error_set(err, SS_ERR_NOMEM, "heal params: out of memory");
        return NULL;
    }
    snprintf(p->scenario, sizeof p->scenario, "%s", SCEN[k]);
    for (int i = 0; i < NPDEFS; i++)
        *pval(p, &PDEFS[i]) = k == 0 ? PDEFS[i].clean : k == 1 ? PDEFS[i].scab : PDEFS[i].keloid;
    p->scab = k == 1;
    p->static_region = k != 2;
    return p;
}

ss_heal_params *ss_heal_params_clone(const ss_heal_params *p, ss_error *err) {
    ss_heal_params *q = malloc(sizeof *q);
    if (!q) {
        ss_error_set(err, SS_ERR_NOMEM, "heal params: out of memory");
        return NULL;
    }
    *q = *p;
    return q;
}

void ss_heal_params_free(ss_heal_params *p) { free(p); }

ss_status ss_heal_params_set_switches(ss_heal_params *p, int scab, int static_region) {
    if (!p || scab < -1 || scab > 1 || static_region < -1 || static_region > 1) return SS_ERR_INPUT;
    if (scab >= 0) p->scab = scab;
    if (static_region >= 0) p->static_region = static_region;
    return SS_OK;
}

double ss_heal_crust_voxel_share(const ss_heal_params *p, double dx_mm) {
    if (!p || !p->scab || !(dx_mm > 0) || !(p->scab_mm > 0)) return 1.0;
    return p->scab_mm < dx_mm ? p->scab_mm / dx_mm : 1.0;
}

void ss_heal_params_healthy(const ss_heal_params *p, float h[SS_HEAL_NFIELDS]) {
    for (int f = 0; f < SS_HEAL_NFIELDS; f++) h[f] = 0.0f;
    double u3 = p->u3_eq;
    double u1 = p->lam11 > 0 ? p->lam31 * u3 / p->lam11 : 1.0;
    double n = (p->rn > 0 && u1 > 0) ? p->K * (1.0 - p->lamnn / (p->rn * u1)) : 0.0;
    h[SS_HEAL_OXYGEN] = (float)u1;
    h[SS_HEAL_CAPILLARY] = (float)u3;
    h[SS_HEAL_FIBROBLAST] = (float)(n > 0 ? n : 0.0);
}

static ss_status check_value(const char *what, const pdef *d, double v, ss_error *err) {
    if (!isfinite(v) || (v < 0 && !may_be_negative(d->key)))
        return ss_error_set(err, SS_ERR_INPUT, "%s: parameter '%s' = %g must be a finite %s", what,
                            d->key, v, may_be_negative(d->key) ? "number" : "value >= 0");
    if ((!strcmp(d->key, "u3_eq") || !strcmp(d->key, "K") || !strcmp(d->key, "lam11") ||
         !strcmp(d->key, "rho_max") || !strcmp(d->key, "u1_beta2") || !strcmp(d->key, "bed_mm") ||
         !strcmp(d->key, "rho_sat") || !strcmp(d->key, "adnexa_mm") ||
         !strcmp(d->key, "keloid_mm")) &&
        !(v > 0))
        return ss_error_set(err, SS_ERR_INPUT, "%s: parameter '%s' = %g must be > 0", what, d->key,
                            v);
    if (!strcmp(d->key, "rho_open") && !(v >= 0 && v <= 1))
        return ss_error_set(err, SS_ERR_INPUT, "%s: parameter 'rho_open' = %g must be in [0, 1]",
                            what, v);
    if (!strcmp(d->key, "keloid_floor") && !(v >= 0 && v <= 1))
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: parameter 'keloid_floor' = %g must be in [0, 1]", what, v);
    if (!strcmp(d->key, "kscab") && !(v >= 0 && v < 1))
        return ss_error_set(err, SS_ERR_INPUT, "%s: parameter 'kscab' = %g must be in [0, 1)", what,
                            v);
    if (!strcmp(d->key, "kang") && !(v >= 0 && v <= 1))
        return ss_error_set(err, SS_ERR_INPUT, "%s: parameter 'kang' = %g must be in [0, 1]", what,
                            v);
    if (!strcmp(d->key, "gamma1") && !(v > 0 && v < 1))
        return ss_error_set(err, SS_ERR_INPUT, "%s: parameter 'gamma1' = %g must be in (0, 1)",
                            what, v);
    return SS_OK;
}

const char *ss_heal_param_key(int i) { return i >= 0 && i < NPDEFS ? PDEFS[i].key : NULL; }

static const pdef *find_def(const char *key) {
    for (int i = 0; key && i < NPDEFS; i++)
        if (!strcmp(PDEFS[i].key, key)) return &PDEFS[i];
    return NULL;
}

ss_status ss_heal_param_get(const ss_heal_params *p, const char *key, double *v, ss_error *err) {
    const pdef *d = find_def(key);
    if (!p || !d) return ss_error_set(err, SS_ERR_INPUT, "unknown heal parameter '%s'", key);
    *v = *(const double *)((const char *)p + d->off);
    return SS_OK;
}

ss_status ss_heal_param_set(ss_heal_params *p, const char *key, double v, ss_error *err) {
    const pdef *d = find_def(key);
    if (!p || !d) return ss_error_set(err, SS_ERR_INPUT, "unknown heal parameter '%s'", key);
    ss_status st = check_value("heal parameter", d, v, err);
    if (st) return st;
    *pval(p, d) = v;
    return SS_OK;
}

ss_heal_params *ss_heal_params_parse(const char *text, const char *what, const char *scenario,
                                     ss_error *err) {
    if (!what) what = "heal parameters";
    cJSON *root = text ? cJSON_Parse(text) : NULL;
    if (!root || !cJSON_IsObject(root)) {
        const char *ep = cJSON_GetErrorPtr();
        char near[40] = "";
        if (ep) snprintf(near, sizeof near, "%.30s", ep);
        ss_error_set(err, SS_ERR_INPUT, "%s: malformed JSON%s%s%s", what, ep ? " near '" : "", near,
                     ep ? "'" : "");
        cJSON_Delete(root);
        return NULL;
    }
    ss_heal_params *p = NULL;
    const cJSON *sc = cJSON_GetObjectItemCaseSensitive(root, "scenario");
    if (sc && !cJSON_IsString(sc)) {
        ss_error_set(err, SS_ERR_INPUT, "%s: key 'scenario' must be a string", what);
        goto fail;
    }
    if (!scenario) scenario = sc ? sc->valuestring : "clean";
    p = ss_heal_params_preset(scenario, err);
    if (!p) {
        if (sc && !strcmp(scenario, sc->valuestring)) { /* the file's own word: name the file */
            ss_error e2 = *err;
            ss_error_set(err, e2.code, "%s: %s", what, e2.msg);
        }
        goto fail;
    }
    for (const cJSON *it = root->child; it; it = it->next) {
        if (strcmp(it->string, "scenario") && strcmp(it->string, "params") &&
            strcmp(it->string, "switches") && strcmp(it->string, "comment") &&
            strcmp(it->string, "mechanics")) { /* mechanics: read by src/mech */
            ss_error_set(err, SS_ERR_INPUT,
                         "%s: unknown top-level key '%s' (expected scenario, params, switches, "
                         "mechanics, comment)",
                         what, it->string);
            goto fail;
        }
    }
    const cJSON *sw = cJSON_GetObjectItemCaseSensitive(root, "switches");
    if (sw) {
        if (!cJSON_IsObject(sw)) {
            ss_error_set(err, SS_ERR_INPUT, "%s: 'switches' must be an object", what);
            goto fail;
        }
        for (const cJSON *it = sw->child; it; it = it->next) {
            int *dst = !strcmp(it->string, "scab")            ? &p->scab
                       : !strcmp(it->string, "static_region") ? &p->static_region
                                                              : NULL;
            if (!dst) {
                ss_error_set(err, SS_ERR_INPUT,
                             "%s: unknown switch '%s' (expected scab, static_region)", what,
                             it->string);
                goto fail;
            }
            if (cJSON_IsBool(it))
                *dst = cJSON_IsTrue(it);
            else if (cJSON_IsNumber(it) && (it->valuedouble == 0 || it->valuedouble == 1))
                *dst = (int)it->valuedouble;
            else {
                ss_error_set(err, SS_ERR_INPUT, "%s: switch '%s' must be 0/1 or true/false", what,
                             it->string);
                goto fail;
            }
        }
    }
    const cJSON *pa = cJSON_GetObjectItemCaseSensitive(root, "params");
    if (pa && !cJSON_IsObject(pa)) {
        ss_error_set(err, SS_ERR_INPUT, "%s: 'params' must be an object", what);
        goto fail;
    }
    for (const cJSON *it = pa ? pa->child : NULL; it; it = it->next) {
        const pdef *d = NULL;
        for (int i = 0; i < NPDEFS; i++)
            if (!strcmp(PDEFS[i].key, it->string)) d = &PDEFS[i];
        if (!d) {
            ss_error_set(err, SS_ERR_INPUT, "%s: unknown parameter '%s'", what, it->string);
            goto fail;
        }
        if (!cJSON_IsObject(it)) {
            ss_error_set(err, SS_ERR_INPUT,
                         "%s: parameter '%s' must be an object {\"value\": ..., \"unit\": \"%s\"}",
                         what, d->key, d->unit);
            goto fail;
        }
        const cJSON *v = cJSON_GetObjectItemCaseSensitive(it, "value");
        const cJSON *u = cJSON_GetObjectItemCaseSensitive(it, "unit");
        if (!v || !cJSON_IsNumber(v)) {
            ss_error_set(err, SS_ERR_INPUT, "%s: parameter '%s' has no numeric \"value\"", what,
                         d->key);
            goto fail;
        }
        if (!u || !cJSON_IsString(u)) {
            ss_error_set(err, SS_ERR_INPUT, "%s: parameter '%s' has no \"unit\" (expected \"%s\")",
                         what, d->key, d->unit);
            goto fail;
        }
        if (strcmp(u->valuestring, d->unit)) {
            ss_error_set(err, SS_ERR_INPUT, "%s: parameter '%s' has unit \"%s\", expected \"%s\"",
                         what, d->key, u->valuestring, d->unit);
            goto fail;
        }
        if (check_value(what, d, v->valuedouble, err) != SS_OK) goto fail;
        *pval(p, d) = v->valuedouble;
    }
    cJSON_Delete(root);
    return p;
fail:
    cJSON_Delete(root);
    ss_heal_params_free(p);
    return NULL;
}

ss_heal_params *ss_heal_params_load(const char *json_path, const char *scenario, ss_error *err) {
    if (!json_path) {
        ss_error_set(err, SS_ERR_INPUT, "heal parameters: no file given");
        return NULL;
    }
    size_t len = 0;
    char *text = ss_read_file_max(json_path, &len, SS_READ_MAX_CONFIG, err);
    if (!text) {
        if (err) err->code = SS_ERR_INPUT;
        return NULL;
    }
    ss_heal_params *p = ss_heal_params_parse(text, json_path, scenario, err);
    free(text);
    return p;
}

char *ss_heal_params_to_json(const ss_heal_params *p) {
    if (!p) return NULL;
    cJSON *root = cJSON_CreateObject();
    if (!root) return NULL;
    cJSON_AddStringToObject(root, "scenario", p->scenario);
    cJSON *sw = cJSON_AddObjectToObject(root, "switches");
    cJSON_AddNumberToObject(sw, "scab", p->scab);
    cJSON_AddNumberToObject(sw, "static_region", p->static_region);
    cJSON *pa = cJSON_AddObjectToObject(root, "params");
    for (int i = 0; i < NPDEFS; i++) {
        cJSON *o = cJSON_AddObjectToObject(pa, PDEFS[i].key);
        cJSON_AddNumberToObject(o, "value", *(const double *)((const char *)p + PDEFS[i].off));
        cJSON_AddStringToObject(o, "unit", PDEFS[i].unit);
        cJSON_AddStringToObject(o, "source", PDEFS[i].source);
    }
    char *s = cJSON_Print(root);
    cJSON_Delete(root);
    return s;
}
