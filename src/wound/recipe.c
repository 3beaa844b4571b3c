/* The wound recipe: every number of the tissue -> biology mapping (seed 001
 * §5.4: "all parameters that go into the shader can be ramped and
 * multiplied") with its unit, range and default, in one table that drives the
 * defaults, the JSON reader and writer. The reasons and sources of the
 * defaults are in docs/wound.md.
 *
 * Design: one static table rather than a struct of named fields, so a new
 * mapping is one line here and the reader, the writer and the unknown-key
 * check follow; gave up: type safety of named fields (callers index by the
 * SS_WR_* enum). */
#define _POSIX_C_SOURCE 200809L
#include <cjson/cJSON.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/wound.h"

static const struct {
    const char *key, *unit;
    double def, lo, hi;
} K[SS_WR_NKEYS] = {
    [SS_WR_CAPILLARY_THRESHOLD] = {"capillary_threshold", "1", 0.5, 0.01, 1},
    [SS_WR_EPITHELIUM_LO] = {"epithelium_lo", "1", 0.2, 0, 1},
    [SS_WR_EPITHELIUM_HI] = {"epithelium_hi", "1", 0.8, 0, 1},
    [SS_WR_REGION_LO] = {"region_lo", "1", 0.25, 0, 1},
    [SS_WR_REGION_HI] = {"region_hi", "1", 0.75, 0, 1},
    [SS_WR_BED_BLOOD] = {"bed_blood", "1", 0.4, 0, 1},
    [SS_WR_TISSUE_MIN_OXYGENATION] = {"tissue_min_oxygenation", "1", 0.65, 0, 1},
    [SS_WR_YOUNG_BLOOD] = {"young_blood", "1", SS_YOUNG_DERMIS_BLOOD, 0, 1},
    [SS_WR_SCAR_DAYS] = {"scar_maturation", "day", 120, 0.01, 1e5},
    [SS_WR_EPIDERMIS_DAYS] = {"epidermis_maturation", "day", 14, 0.01, 1e5},
    [SS_WR_PIGMENT_DAYS] = {"repigmentation", "day", SS_REPIG_DAYS, 0.01, 1e5},
    [SS_WR_NEW_MELANIN] = {"new_melanin", "1", SS_REPIG_NEW_MELANIN, 0, 10},
    [SS_WR_SCAR_MELANIN] = {"scar_melanin", "1", SS_REPIG_SCAR_MELANIN, 0, 10},
    [SS_WR_NEW_EPIDERMIS] = {"new_epidermis", "1", SS_NEW_EPIDERMIS_FRACTION, 0, 10},
    [SS_WR_SCAR_DENSITY_HI] = {"scar_density_hi", "1", 0.3, 1e-6, 1e3},
    [SS_WR_SCAR_BLOOD] = {"scar_blood", "1", 0.6, 0, 10},
    [SS_WR_SCAR_WHITENING] = {"scar_whitening", "1", 0.2, 0, 1},
    [SS_WR_SCAB_SCALE] = {"scab_scale", "1", 1, 0, 100},
    [SS_WR_SCAB_HB_FACTOR] = {"scab_hb_factor", "1", 3, 0, 20},
    [SS_WR_SCAB_MIN_DENSITY] = {"scab_min_density", "1", 0.5, 0.2, 0.8},
    [SS_WR_CLOT_SCALE] = {"clot_scale", "1", 1, 0, 100},
    [SS_WR_BED_OXYGENATION] = {"bed_oxygenation", "1", 0.9, 0, 1},
    [SS_WR_WET_ROUGHNESS] = {"wet_roughness", "1", 0.3, 0, 1},
    [SS_WR_SCAB_ROUGHNESS] = {"scab_roughness", "1", 0.85, 0, 1},
    [SS_WR_SCAR_ROUGHNESS] = {"scar_roughness", "1", 0.35, 0, 1},
    [SS_WR_DEPTH_SCALE] = {"depth_scale", "1", 1, 0, 100},
    [SS_WR_KELOID_SCALE] = {"keloid_scale", "1", 1, 0, 100},
    [SS_WR_HEIGHT_RANGE_MM] = {"height_range", "mm", 2, 1e-3, 1e3},
    [SS_WR_SCAB_MOTTLE] = {"scab_mottle", "1", 0.6, 0, 1},
    [SS_WR_SCAB_SEROUS] = {"scab_serous", "1", 0.5, 0, 1},
    [SS_WR_SCAB_SEROUS_HB] = {"scab_serous_hb", "1", 0.4, 0, 20},
    [SS_WR_SCAB_DOME_MM] = {"scab_dome", "mm", 2, 1e-3, 100},
    [SS_WR_SCAB_EDGE] = {"scab_edge", "1", 0.25, 0, 1},
    [SS_WR_CRACK_WIDTH] = {"crack_width", "1", 0.05, 0, 0.5},
    [SS_WR_CRACK_REACH_MM] = {"crack_reach", "mm", 4, 1e-3, 100},
    [SS_WR_KELOID_LOOK_MM] = {"keloid_look", "mm", 0.3, 1e-3, 100},
    [SS_WR_KELOID_BLOOD] = {"keloid_blood", "1", 0.05, 0, 1},
    [SS_WR_KELOID_OXYGENATION] = {"keloid_oxygenation", "1", 0.8, 0, 1},
    [SS_WR_KELOID_MELANIN] = {"keloid_melanin", "1", 1.15, 0, 10},
    [SS_WR_KELOID_ROUGHNESS] = {"keloid_roughness", "1", 0.22, 0, 1},
    [SS_WR_SCAB_BILIRUBIN] = {"scab_bilirubin", "g/L", 1.5, 0, 100},
    [SS_WR_PIH_GAIN] = {"pih_gain", "1", SS_PIH_GAIN, 0, 100},
    [SS_WR_CRUST_DRY_DAYS] = {"crust_dry_days", "day", 2, 0.01, 1e5},
    [SS_WR_CRUST_LIFT_MM] = {"crust_lift", "mm", 0.15, 0, 10},
    [SS_WR_BED_TEXTURE] = {"bed_texture", "1", 1, 0, 10},
    [SS_WR_LOOP_DEPTH_MM] = {"loop_depth", "mm", 0.2, 0, 10},
    [SS_WR_CLOT_OXYGENATION] = {"clot_oxygenation", "1", 0.7, 0, 1},
    [SS_WR_KELOID_MARGIN_MM] = {"keloid_margin", "mm", 1.5, 0.01, 100},
    [SS_WR_KELOID_CENTRE_BLOOD] = {"keloid_centre_blood", "1", 0.3, 0, 1},
    [SS_WR_KELOID_MATURE_DAYS] = {"keloid_maturation", "day", 60, 0.01, 1e5},
    [SS_WR_KELOID_VESSELS] = {"keloid_vessels", "1", 1, 0, 1},
    [SS_WR_KELOID_VESSEL_MM] = {"keloid_vessel_width", "mm", 0.18, 0.005, 2},
    [SS_WR_KELOID_NODULES] = {"keloid_nodules", "1", 0.12, 0, 1},
};

void ss_wound_recipe_default(ss_wound_recipe *r) {
    for (int k = 0; k < SS_WR_NKEYS; k++) r->v[k] = K[k].def;
}

const char *ss_wound_recipe_key(int key) {
    return key >= 0 && key < SS_WR_NKEYS ? K[key].key : NULL;
}

const char *ss_wound_recipe_unit(int key) {
    return key >= 0 && key < SS_WR_NKEYS ? K[key].unit : NULL;
}

static ss_status parse_entry(const cJSON *e, const char *name, ss_wound_recipe *r, ss_error *err) {
    int k = 0;
    while (k < SS_WR_NKEYS && strcmp(K[k].key, e->string)) k++;
    if (k == SS_WR_NKEYS)
        return ss_error_set(err, SS_ERR_INPUT, "%s: unknown recipe key '%s'", name, e->string);
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(e, "value"),
                *u = cJSON_GetObjectItemCaseSensitive(e, "unit");
    if (!cJSON_IsObject(e) || !cJSON_IsNumber(v))
        return ss_error_set(err, SS_ERR_INPUT, "%s: %s needs {\"value\": number, \"unit\": \"%s\"}",
                            name, e->string, K[k].unit);
    if (!cJSON_IsString(u))
        return ss_error_set(err, SS_ERR_INPUT, "%s: %s has no unit (expected \"%s\")", name,
                            e->string, K[k].unit);
    if (strcmp(u->valuestring, K[k].unit))
        return ss_error_set(err, SS_ERR_INPUT, "%s: %s has unit \"%s\", expected \"%s\"", name,
                            e->string, u->valuestring, K[k].unit);
    double x = v->valuedouble;
    if (!isfinite(x) || x < K[k].lo || x > K[k].hi)
        return ss_error_set(err, SS_ERR_INPUT, "%s: %s = %g is outside %g..%g %s", name, e->string,
                            x, K[k].lo, K[k].hi, K[k].unit);
    r->v[k] = x;
    return SS_OK;
}

ss_status ss_wound_recipe_parse(const char *json, const char *name, ss_wound_recipe *r,
                                ss_error *err) {
    cJSON *j = cJSON_Parse(json);
    if (!j || !cJSON_IsObject(j)) {
        cJSON_Delete(j);
        return ss_error_set(err, SS_ERR_INPUT, "%s: not a JSON object", name);
    }
    ss_status st = SS_OK;
    const cJSON *e;
    cJSON_ArrayForEach(e, j) {
        if (strcmp(e->string, "recipe") && strcmp(e->string, "comment")) {
            st = ss_error_set(err, SS_ERR_INPUT,
                              "%s: unknown top-level key '%s' (expected \"recipe\")", name,
                              e->string);
            break;
        }
    }
    const cJSON *rec = cJSON_GetObjectItemCaseSensitive(j, "recipe");
    if (!st && !cJSON_IsObject(rec))
        st = ss_error_set(err, SS_ERR_INPUT, "%s: needs a \"recipe\" object", name);
    ss_wound_recipe tmp = *r;
    if (!st) cJSON_ArrayForEach(e, rec) {
            if ((st = parse_entry(e, name, &tmp, err))) break;
        }
    if (!st && tmp.v[SS_WR_EPITHELIUM_LO] >= tmp.v[SS_WR_EPITHELIUM_HI])
        st = ss_error_set(err, SS_ERR_INPUT, "%s: epithelium_lo must be below epithelium_hi", name);
    if (!st && tmp.v[SS_WR_REGION_LO] >= tmp.v[SS_WR_REGION_HI])
        st = ss_error_set(err, SS_ERR_INPUT, "%s: region_lo must be below region_hi", name);
    cJSON_Delete(j);
    if (!st) *r = tmp;
    return st;
}

ss_status ss_wound_recipe_load(const char *path, ss_wound_recipe *r, ss_error *err) {
    char *text = ss_read_file_max(path, NULL, SS_READ_MAX_CONFIG, err);
    if (!text) return err->code;
    ss_status st = ss_wound_recipe_parse(text, path, r, err);
    free(text);
    return st;
}

char *ss_wound_recipe_to_json(const ss_wound_recipe *r) {
    cJSON *j = cJSON_CreateObject(), *rec = cJSON_AddObjectToObject(j, "recipe");
    for (int k = 0; k < SS_WR_NKEYS; k++) {
        cJSON *e = cJSON_AddObjectToObject(rec, K[k].key);
        cJSON_AddNumberToObject(e, "value", r->v[k]);
        cJSON_AddStringToObject(e, "unit", K[k].unit);
    }
    char *s = cJSON_Print(j);
    cJSON_Delete(j);
    return s;
}
