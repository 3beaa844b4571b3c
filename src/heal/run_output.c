/* What a heal run writes (docs/heal-outputs.md): snapshots (VTK ImageData of
 * every field, the ParaView time collection, top-view surface maps of seed 001
 * §5.4's fields), the run metadata stored inside checkpoints so a resume
 * continues the area curve and the snapshot list, and the closing tables
 * (area.csv, the Fig. 4 plot area.png, summary.json).
 *
 * Design: every file is written atomically by the heal_io writers; the
 * directory itself is checked before any work (writable, no previous run
 * unless forced) and a forced re-run removes only the files this command
 * writes. Snapshot colour scales are a function of the state alone, so a
 * resumed run draws the same pictures as an uninterrupted one. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "run_internal.h"

/* ---- checkpoint metadata ------------------------------------------------------------ */

char *ss_heal_run__aux_json(const ss_heal_run *r, double wall) {
    cJSON *j = cJSON_CreateObject();
    cJSON_AddNumberToObject(j, "days", r->days);
    cJSON_AddNumberToObject(j, "snapshot_every_steps", (double)r->snap_every);
    cJSON_AddNumberToObject(j, "area_every_steps", (double)r->area_every);
    cJSON_AddNumberToObject(j, "checkpoint_every_steps", (double)r->ckpt_every);
    cJSON_AddNumberToObject(j, "seed", (double)r->c.seed);
    cJSON_AddNumberToObject(j, "wall_time_s", wall);
    if (r->wound) cJSON_AddItemToObject(j, "wound", cJSON_Duplicate(r->wound, 1));
    cJSON *a = cJSON_AddArrayToObject(j, "area");
    for (int i = 0; i < r->nrows; i++) {
        const ss_heal_area_row *row = &r->rows[i];
        double v[4 + SS_HEAL_NFIELDS] = {row->t_days, row->st.open_area_mm2,
                                         row->st.wound_region_area_mm2, row->st.initial_area_mm2};
        for (int k = 0; k < SS_HEAL_NFIELDS; k++) v[4 + k] = row->st.field_mean[k];
        cJSON_AddItemToArray(a, cJSON_CreateDoubleArray(v, 4 + SS_HEAL_NFIELDS));
    }
    cJSON *sn = cJSON_AddArrayToObject(j, "snapshots");
    for (int i = 0; i < r->nsnap; i++) {
        cJSON *e = cJSON_CreateArray();
        cJSON_AddItemToArray(e, cJSON_CreateNumber(r->snap_t[i]));
        cJSON_AddItemToArray(e, cJSON_CreateString(r->snap_file[i]));
        cJSON_AddItemToArray(sn, e);
    }
    ss_heal_run__mech_aux(r, j);
    char *s = cJSON_PrintUnformatted(j);
    cJSON_Delete(j);
    return s;
}

static ss_status restore_rows(ss_heal_run *r, const cJSON *area, const char *dir, ss_error *err) {
    const cJSON *e;
    cJSON_ArrayForEach(e, area) {
        if (cJSON_GetArraySize(e) != 4 + SS_HEAL_NFIELDS)
            return ss_error_set(err, SS_ERR_INPUT, "%s: checkpoint area rows malformed", dir);
        double v[4 + SS_HEAL_NFIELDS];
        for (int k = 0; k < 4 + SS_HEAL_NFIELDS; k++) {
            const cJSON *x = cJSON_GetArrayItem(e, k);
            if (!cJSON_IsNumber(x))
                return ss_error_set(err, SS_ERR_INPUT, "%s: checkpoint area rows malformed", dir);
            v[k] = x->valuedouble;
        }
        ss_status st = ss_heal_run__add_row(r, err);
        if (st) return st;
        ss_heal_area_row *row = &r->rows[r->nrows - 1];
        row->t_days = v[0];
        row->st.open_area_mm2 = v[1];
        row->st.wound_region_area_mm2 = v[2];
        row->st.initial_area_mm2 = v[3];
        for (int k = 0; k < SS_HEAL_NFIELDS; k++) row->st.field_mean[k] = v[4 + k];
    }
    return SS_OK;
}

static ss_status restore_snaps(ss_heal_run *r, const cJSON *snaps, const char *dir, ss_error *err) {
    const cJSON *e;
    cJSON_ArrayForEach(e, snaps) {
        const cJSON *t = cJSON_GetArrayItem(e, 0), *f = cJSON_GetArrayItem(e, 1);
        if (!cJSON_IsNumber(t) || !cJSON_IsString(f))
            return ss_error_set(err, SS_ERR_INPUT, "%s: checkpoint snapshot list malformed", dir);
        ss_status st = ss_heal_run__add_snap(r, t->valuedouble, f->valuestring, err);
        if (st) return st;
    }
    return SS_OK;
}

ss_status ss_heal_run__aux_restore(ss_heal_run *r, const char *aux, const char *dir,
                                   ss_error *err) {
    cJSON *j = cJSON_Parse(aux);
    if (!j) return ss_error_set(err, SS_ERR_INPUT, "%s: checkpoint metadata is malformed", dir);
    cJSON *days = cJSON_GetObjectItem(j, "days"),
          *se = cJSON_GetObjectItem(j, "snapshot_every_steps"),
          *ae = cJSON_GetObjectItem(j, "area_every_steps"),
          *ce = cJSON_GetObjectItem(j, "checkpoint_every_steps"),
          *seed = cJSON_GetObjectItem(j, "seed"), *wall = cJSON_GetObjectItem(j, "wall_time_s"),
          *area = cJSON_GetObjectItem(j, "area"), *snaps = cJSON_GetObjectItem(j, "snapshots");
    if (!cJSON_IsNumber(days) || !cJSON_IsNumber(se) || !cJSON_IsNumber(ae) ||
        !cJSON_IsNumber(ce) || !cJSON_IsArray(area) || !cJSON_IsArray(snaps)) {
        cJSON_Delete(j);
        return ss_error_set(err, SS_ERR_INPUT, "%s: checkpoint metadata is incomplete", dir);
    }
    r->days = days->valuedouble;
    r->snap_every = (long long)se->valuedouble;
    r->area_every = (long long)ae->valuedouble;
    r->ckpt_every = (long long)ce->valuedouble;
    ss_status st = SS_OK;
    if (r->snap_every < 0 || r->area_every < 1 || r->ckpt_every < 0)
        st = ss_error_set(err, SS_ERR_INPUT, "%s: checkpoint intervals are invalid", dir);
    if (cJSON_IsNumber(seed)) r->c.seed = (uint64_t)seed->valuedouble;
    if (cJSON_IsNumber(wall)) r->wall_prev = wall->valuedouble;
    cJSON *w = cJSON_GetObjectItem(j, "wound");
    if (w) r->wound = cJSON_Duplicate(w, 1);
    cJSON *mo = cJSON_GetObjectItem(j, "mechanics");
    if (mo && !(r->mech_aux = cJSON_Duplicate(mo, 1)))
        st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    if (!st) st = restore_rows(r, area, dir, err);
    if (!st) st = restore_snaps(r, snaps, dir, err);
    cJSON_Delete(j);
    return st;
}

/* ---- the output directory ------------------------------------------------------------ */

static int file_exists(const char *path) {
    struct stat st;
    return stat(path, &st) == 0;
}

ss_status ss_heal_run__check_out_dir(const ss_heal_run *r, ss_error *err) {
    const char *out = r->out_dir;
    ss_status st = ss_check_writable_dir(out, err);
    if (st) return st;
    char probe[4400], probe2[4400];
    snprintf(probe, sizeof probe, "%s/summary.json", out);
    snprintf(probe2, sizeof probe2, "%s/checkpoints", out);
    if (!r->c.force && (file_exists(probe) || file_exists(probe2)))
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s holds a previous run; use --resume %s to continue it, --force "
                            "to overwrite it, or another --out",
                            out, out);
    return SS_OK;
}

/* Removes the outputs of a previous run in dir (only files this command writes). */
static void clean_previous(const char *out) {
    static const char *const sub[3] = {"fields", "surface", "checkpoints"};
    char path[4400];
    for (int k = 0; k < 3; k++) {
        snprintf(path, sizeof path, "%s/%s", out, sub[k]);
        DIR *d = opendir(path);
        if (!d) continue;
        struct dirent *e;
        while ((e = readdir(d))) {
            const char *nm = e->d_name, *dot = strrchr(nm, '.');
            if (!dot) continue;
            if ((k == 0 &&
                 (!strcmp(dot, ".vti") || !strcmp(dot, ".pvd") || !strcmp(dot, ".vtu"))) ||
                (k == 1 && !strcmp(dot, ".png")) || (k == 2 && !strcmp(dot, ".sshc"))) {
                char f[4700];
                snprintf(f, sizeof f, "%s/%s", path, nm);
                unlink(f);
            }
        }
        closedir(d);
    }
}

ss_status ss_heal_run__prepare_out_dir(ss_heal_run *r, ss_error *err) {
    if (r->c.force && r->resumed_from < 0) clean_previous(r->out_dir);
    static const char *const subs[2] = {"fields", "surface"};
    char path[4400];
    ss_status st = SS_OK;
    for (int k = 0; k < 2 && !st; k++) {
        snprintf(path, sizeof path, "%s/%s", r->out_dir, subs[k]);
        st = ss_mkdir_p(path, err);
    }
    return st;
}

/* ---- snapshots ------------------------------------------------------------------------ */

/* Colour scale: 0 .. the next of 1, 2, 5, 10, 20, ... above the largest value,
 * so snapshots of a run share a scale unless a field grows past it. */
static double map_vmax(const ss_image *m) {
    float mx = 1;
    for (size_t i = 0; i < (size_t)m->width * (size_t)m->height; i++)
        if (m->data[i] > mx) mx = m->data[i];
    double vmax = 1;
    for (int step = 0; vmax < mx; step++) vmax *= step % 3 == 1 ? 2.5 : 2;
    return vmax;
}

static ss_status write_surface_maps(ss_heal_run *r, int idx, ss_error *err) {
    static const struct {
        int field;
        ss_heal_surface_mode mode;
        const char *how, *unit;
    } maps[4] = {{SS_HEAL_EPITHELIUM, SS_SURFACE_LAYER, "epithelial layer", "(1 = healthy)"},
                 {SS_HEAL_CAPILLARY, SS_SURFACE_TOP, "surface", "(1 = healthy)"},
                 {SS_HEAL_ESCHAR, SS_SURFACE_MAX, "column max", "(density)"},
                 {SS_HEAL_SCAR, SS_SURFACE_MAX, "column max", "(density)"}};
    char path[4400], title[256];
    for (int k = 0; k < 4; k++) {
        ss_image *m = ss_heal_surface_map(r->g, maps[k].field, maps[k].mode, err);
        if (!m) return err->code;
        const char *name = ss_heal_field_name(maps[k].field);
        snprintf(title, sizeof title, "%s (%s), day %.2f - %s", name, maps[k].how, r->g->t_days,
                 r->scenario);
        snprintf(path, sizeof path, "%s/surface/%s_%04d.png", r->out_dir, name, idx);
        ss_status st =
            ss_heal_surface_png(path, m, 0, map_vmax(m), title, maps[k].unit, r->g->dx_mm, err);
        ss_image_free(m);
        if (st) return st;
    }
    return SS_OK;
}

ss_status ss_heal_run_write_snapshot(ss_heal_run *r, ss_error *err) {
    if (!r->out_dir) return ss_error_set(err, SS_ERR_INPUT, "heal run: no output directory");
    char rel[64], path[4400];
    int idx = r->nsnap;
    /* a resumed run may redo snapshots the killed run wrote after its checkpoint */
    snprintf(rel, sizeof rel, "fields_%04d.vti", idx);
    snprintf(path, sizeof path, "%s/fields/%s", r->out_dir, rel);
    ss_status st;
    if (r->mech) { /* the displacement next to the velocity */
        float *const *u = ss_mech_grid_displacement(r->mech);
        if (!u) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        const char *name = "displacement";
        float *const vec[1][3] = {{u[0], u[1], u[2]}};
        st = ss_heal_vti_write_vectors(path, r->g, 1, &name, vec, err);
    } else {
        st = ss_heal_vti_write(path, r->g, err);
    }
    if (!st) st = ss_heal_run__mech_snapshot(r, idx, err);
    if (!st) st = ss_heal_run__add_snap(r, r->g->t_days, rel, err);
    if (st) return st;
    snprintf(path, sizeof path, "%s/fields/fields.pvd", r->out_dir);
    st = ss_heal_pvd_write(path, r->nsnap, r->snap_t, (const char *const *)r->snap_file, err);
    if (!st) st = write_surface_maps(r, idx, err);
    return st;
}

/* ---- closing tables ----------------------------------------------------------------- */

static void add_closure_time(cJSON *j, const char *key, double t) {
    if (t >= 0)
        cJSON_AddNumberToObject(j, key, t);
    else
        cJSON_AddNullToObject(j, key);
}

cJSON *ss_heal_run__summary(const ss_heal_run *r, double wall) {
    cJSON *j = cJSON_CreateObject();
    if (!j) return NULL;
    cJSON_AddStringToObject(j, "command", "heal");
    cJSON_AddStringToObject(j, "scenario", r->scenario);
    cJSON *g = cJSON_AddObjectToObject(j, "grid");
    cJSON_AddNumberToObject(g, "nx", r->g->nx);
    cJSON_AddNumberToObject(g, "ny", r->g->ny);
    cJSON_AddNumberToObject(g, "nz", r->g->nz);
    cJSON_AddNumberToObject(g, "dx_mm", r->g->dx_mm);
    double sz[3] = {r->g->nx * r->g->dx_mm, r->g->ny * r->g->dx_mm, r->g->nz * r->g->dx_mm};
    cJSON_AddItemToObject(g, "size_mm", cJSON_CreateDoubleArray(sz, 3));
    cJSON_AddNumberToObject(g, "skin_top_mm", r->g->skin_top_mm);
    if (r->wound) cJSON_AddItemToObject(j, "wound", cJSON_Duplicate(r->wound, 1));
    cJSON_AddStringToObject(j, "scheme", r->scheme == SS_HEAL_EXPLICIT ? "explicit" : "split");
    cJSON_AddNumberToObject(j, "dt_days", r->dt);
    cJSON_AddNumberToObject(j, "days", r->g->t_days);
    cJSON_AddNumberToObject(j, "steps", (double)r->g->step);
    add_closure_time(j, "time_to_50pct_closure_days",
                     ss_heal_time_to_closure(r->rows, r->nrows, 0.5));
    add_closure_time(j, "time_to_95pct_closure_days",
                     ss_heal_time_to_closure(r->rows, r->nrows, 0.05));
    if (r->nrows) {
        const ss_heal_stats *s0 = &r->rows[0].st, *s1 = &r->rows[r->nrows - 1].st;
        cJSON_AddNumberToObject(j, "initial_area_mm2", s0->initial_area_mm2);
        cJSON_AddNumberToObject(j, "final_open_area_mm2", s1->open_area_mm2);
        cJSON_AddNumberToObject(j, "final_normalised_area", ss_heal_area_normalised(s1));
    }
    cJSON_AddNumberToObject(j, "open_threshold", ss_heal_open_threshold());
    cJSON_AddNumberToObject(j, "wall_time_s", wall);
    cJSON_AddNumberToObject(j, "threads", ss_threads_get());
    cJSON_AddNumberToObject(j, "seed", (double)r->c.seed);
    cJSON_AddNumberToObject(j, "snapshots", r->nsnap);
    if (r->resumed_from >= 0)
        cJSON_AddNumberToObject(j, "resumed_from_step", (double)r->resumed_from);
    cJSON *pj = cJSON_Parse(r->params_json);
    cJSON_AddItemToObject(j, "params", pj ? pj : cJSON_CreateString(r->params_json));
    ss_heal_run__mech_summary(r, j);
    return j;
}

static ss_status write_json_file(const char *path, const cJSON *j, ss_error *err) {
    char *text = cJSON_Print(j);
    if (!text) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    size_t len = strlen(text);
    char *t2 = malloc(len + 2);
    ss_status st;
    if (t2) {
        memcpy(t2, text, len);
        t2[len] = '\n';
        t2[len + 1] = '\0';
        st = ss_write_file_atomic(path, t2, len + 1, err);
    } else {
        st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    free(text);
    free(t2);
    return st;
}

ss_status ss_heal_run__write_tables(ss_heal_run *r, double wall, cJSON **summary, ss_error *err) {
    char path[4400], title[256];
    *summary = NULL;
    snprintf(path, sizeof path, "%s/area.csv", r->out_dir);
    const char *const *cn = NULL;
    double *cv = NULL;
    int nc = ss_heal_run__mech_columns(r, &cn, &cv);
    if (nc < 0) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    ss_status st = ss_heal_area_csv_write_columns(path, r->rows, r->nrows, nc, cn, cv, err);
    free(cv);
    if (st) return st;
    snprintf(path, sizeof path, "%s/area.png", r->out_dir);
    snprintf(title, sizeof title, "Normalised open wound area - %s scenario", r->scenario);
    if ((st = ss_heal_area_plot(path, r->rows, r->nrows, title, err))) return st;
    cJSON *j = ss_heal_run__summary(r, wall);
    if (!j) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    snprintf(path, sizeof path, "%s/summary.json", r->out_dir);
    if ((st = write_json_file(path, j, err))) {
        cJSON_Delete(j);
        return st;
    }
    *summary = j;
    return SS_OK;
}
