/* A finished heal run folder, read back: `skinsim wound --heal DIR` renders
 * textures from a run `skinsim heal` made earlier instead of simulating again.
 * The folder is checked as a whole before anything is read from its
 * snapshots: complete (the output discipline's marker, no unfinished mark),
 * of this format (run.json "format", written since format 1), with a
 * summary.json that gives the scenario, grid, parameters and step, and a
 * fields.pvd that lists the snapshots in time order. A snapshot is read on
 * demand (ss_heal_vti_read, or ss_heal_pvti_read when a run on MPI ranks left
 * fields_NNNN.pvti and its pieces instead of the gathered fields_NNNN.vti) and
 * checked against the summary's grid and the day fields.pvd gives it.
 *
 * Design: what the snapshots hold is the full state of the species fields
 * and cell states at their days, which is all a consumer of the surface
 * needs; what happened between snapshots (for example the exact day a column
 * closed) is not there, so a reader learns it at snapshot resolution. Gave
 * up: reading folders of older formats (they lack the format stamp, and the
 * meaning of their fields may have changed with the model). */
#define _POSIX_C_SOURCE 200809L
#include <cjson/cJSON.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "skinsim/heal_io.h"
#include "skinsim/heal_run.h"

struct ss_heal_saved_run {
    char *dir;
    char scenario[32];
    ss_heal_params *p;
    int nx, ny, nz;
    double dx, skin_top, dt;
    int n;
    double *day;
    char **file;
};

void ss_heal_saved_run_free(ss_heal_saved_run *s) {
    if (!s) return;
    for (int i = 0; i < s->n; i++) free(s->file[i]);
    free(s->file);
    free(s->day);
    ss_heal_params_free(s->p);
    free(s->dir);
    free(s);
}

static cJSON *read_json(const char *dir, const char *name, ss_error *err) {
    char path[4400];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    ss_error e2;
    ss_error_clear(&e2);
    char *text = ss_read_file(path, NULL, &e2);
    cJSON *j = text ? cJSON_Parse(text) : NULL;
    free(text);
    if (!j)
        ss_error_set(err, SS_ERR_INPUT, "--heal %s: %s is %s", dir, name,
                     e2.code ? "missing or unreadable" : "not valid JSON");
    return j;
}

/* run.json: a heal run of this format. */
static ss_status check_identity(const char *dir, ss_error *err) {
    cJSON *j = read_json(dir, "run.json", err);
    if (!j) return SS_ERR_INPUT;
    const cJSON *cmd = cJSON_GetObjectItem(j, "command"), *fmt = cJSON_GetObjectItem(j, "format"),
                *ver = cJSON_GetObjectItem(j, "skinsim_version");
    ss_status st = SS_OK;
    if (!cJSON_IsString(cmd) || strcmp(cmd->valuestring, "heal"))
        st =
            ss_error_set(err, SS_ERR_INPUT, "--heal %s: run.json is not a skinsim heal run's", dir);
    else if (!cJSON_IsNumber(fmt) || fmt->valuedouble != SS_HEAL_RUN_FORMAT) {
        char have[64];
        if (cJSON_IsNumber(fmt))
            snprintf(have, sizeof have, "run format %g", fmt->valuedouble);
        else
            snprintf(have, sizeof have, "no run format");
        st = ss_error_set(err, SS_ERR_INPUT,
                          "--heal %s: written by another version of skinsim (%s%s%s; this "
                          "version reads run format %d); run skinsim heal again",
                          dir, cJSON_IsString(ver) ? ver->valuestring : "",
                          cJSON_IsString(ver) ? ", " : "", have, SS_HEAL_RUN_FORMAT);
    }
    cJSON_Delete(j);
    return st;
}

/* summary.json: scenario, grid, parameters, step. */
static ss_status read_summary(ss_heal_saved_run *s, ss_error *err) {
    cJSON *j = read_json(s->dir, "summary.json", err);
    if (!j) return SS_ERR_INPUT;
    const cJSON *sc = cJSON_GetObjectItem(j, "scenario"), *g = cJSON_GetObjectItem(j, "grid"),
                *dt = cJSON_GetObjectItem(j, "dt_days"), *pj = cJSON_GetObjectItem(j, "params");
    const cJSON *nx = cJSON_GetObjectItem(g, "nx"), *ny = cJSON_GetObjectItem(g, "ny"),
                *nz = cJSON_GetObjectItem(g, "nz"), *dx = cJSON_GetObjectItem(g, "dx_mm"),
                *top = cJSON_GetObjectItem(g, "skin_top_mm");
    ss_status st = SS_OK;
    if (!cJSON_IsString(sc) || !cJSON_IsNumber(nx) || !cJSON_IsNumber(ny) || !cJSON_IsNumber(nz) ||
        !cJSON_IsNumber(dx) || !cJSON_IsNumber(top) || !cJSON_IsNumber(dt) || !cJSON_IsObject(pj) ||
        !(dx->valuedouble > 0) || !(dt->valuedouble > 0) || nx->valuedouble < 1 ||
        ny->valuedouble < 1 || nz->valuedouble < 1) {
        cJSON_Delete(j);
        return ss_error_set(err, SS_ERR_INPUT,
                            "--heal %s: summary.json lacks the scenario, grid, dt_days or params",
                            s->dir);
    }
    snprintf(s->scenario, sizeof s->scenario, "%s", sc->valuestring);
    s->nx = nx->valueint, s->ny = ny->valueint, s->nz = nz->valueint;
    s->dx = dx->valuedouble, s->skin_top = top->valuedouble, s->dt = dt->valuedouble;
    char *text = cJSON_PrintUnformatted(pj), what[4400];
    snprintf(what, sizeof what, "--heal %s: summary.json params", s->dir);
    if (!text) st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    if (!st && !(s->p = ss_heal_params_parse(text, what, s->scenario, err))) st = err->code;
    free(text);
    cJSON_Delete(j);
    return st;
}

/* fields/fields.pvd: (timestep, file) per snapshot, in time order. */
static ss_status read_pvd(ss_heal_saved_run *s, ss_error *err) {
    char path[4400];
    snprintf(path, sizeof path, "%s/fields/fields.pvd", s->dir);
    ss_error e2;
    ss_error_clear(&e2);
    char *text = ss_read_file(path, NULL, &e2);
    if (!text)
        return ss_error_set(err, SS_ERR_INPUT, "--heal %s: fields/fields.pvd is missing", s->dir);
    ss_status st = SS_OK;
    for (const char *p = text; !st && (p = strstr(p, "<DataSet ")); p++) {
        const char *ts = strstr(p, "timestep=\""), *fl = strstr(p, "file=\""),
                   *end = strchr(p, '>');
        const char *q = fl ? strchr(fl + 6, '"') : NULL;
        double t;
        if (!ts || !fl || !end || ts > end || fl > end || !q || sscanf(ts + 10, "%lg", &t) != 1 ||
            !(t >= 0) || (s->n && !(t > s->day[s->n - 1])) || q - fl - 6 < 1 || q - fl - 6 > 255) {
            st = ss_error_set(err, SS_ERR_INPUT, "--heal %s: fields/fields.pvd is malformed",
                              s->dir);
            break;
        }
        double *d = realloc(s->day, (size_t)(s->n + 1) * sizeof *d);
        if (d) s->day = d;
        char **f = d ? realloc(s->file, (size_t)(s->n + 1) * sizeof *f) : NULL;
        if (f) s->file = f;
        char *name = f ? strndup(fl + 6, (size_t)(q - fl - 6)) : NULL;
        if (!name) {
            st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
            break;
        }
        if (strchr(name, '/')) { /* snapshots live next to the .pvd */
            free(name);
            st = ss_error_set(err, SS_ERR_INPUT, "--heal %s: fields/fields.pvd is malformed",
                              s->dir);
            break;
        }
        s->day[s->n] = t;
        s->file[s->n++] = name;
    }
    free(text);
    if (!st && !s->n)
        st = ss_error_set(err, SS_ERR_INPUT, "--heal %s: fields/fields.pvd lists no snapshot",
                          s->dir);
    return st;
}

ss_status ss_heal_saved_run_open(const char *dir, ss_heal_saved_run **out, ss_error *err) {
    *out = NULL;
    struct stat sb;
    if (!dir || stat(dir, &sb) || !S_ISDIR(sb.st_mode))
        return ss_error_set(err, SS_ERR_INPUT, "--heal %s: no such directory", dir ? dir : "");
    if (ss_output_dir_is_unfinished(dir, NULL))
        return ss_error_set(err, SS_ERR_INPUT,
                            "--heal %s: the run is incomplete (%s: being written, or stopped "
                            "before its end; finish it with skinsim heal --resume %s)",
                            dir, SS_OUTPUT_UNFINISHED, dir);
    if (!ss_output_dir_is_complete(dir, "heal"))
        return ss_error_set(err, SS_ERR_INPUT,
                            "--heal %s: not a finished skinsim heal run (no %s marker)", dir,
                            SS_OUTPUT_MARKER);
    ss_status st = check_identity(dir, err);
    if (st) return st;
    ss_heal_saved_run *s = calloc(1, sizeof *s);
    if (!s || !(s->dir = strdup(dir))) {
        free(s);
        return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    st = read_summary(s, err);
    if (!st) st = read_pvd(s, err);
    if (st) {
        ss_heal_saved_run_free(s);
        return st;
    }
    *out = s;
    return SS_OK;
}

const char *ss_heal_saved_run_scenario(const ss_heal_saved_run *s) { return s->scenario; }
const ss_heal_params *ss_heal_saved_run_params(const ss_heal_saved_run *s) { return s->p; }
double ss_heal_saved_run_dt(const ss_heal_saved_run *s) { return s->dt; }
double ss_heal_saved_run_end_day(const ss_heal_saved_run *s) { return s->day[s->n - 1]; }
int ss_heal_saved_run_snapshot_count(const ss_heal_saved_run *s) { return s->n; }
double ss_heal_saved_run_snapshot_day(const ss_heal_saved_run *s, int i) {
    return i >= 0 && i < s->n ? s->day[i] : NAN;
}

int ss_heal_saved_run_find(const ss_heal_saved_run *s, double day) {
    for (int i = 0; i < s->n; i++)
        if (fabs(s->day[i] - day) <= 1e-3 * s->dt) return i;
    return -1;
}

/* The file of a snapshot: the .vti fields.pvd names or, when it is not
 * there (a run on MPI ranks that wrote pieces only), the .pvti of the same
 * name joining its pieces; a .pvti named in fields.pvd is one. path is
 * changed to the file to read; 1 = a .pvti, 0 = a .vti, -1 = neither is
 * there (err names both). */
static int snapshot_file(char *path, size_t len, ss_error *err) {
    size_t l = strlen(path);
    struct stat sb;
    if (l > 5 && !strcmp(path + l - 5, ".pvti")) return 1;
    if (l > 4 && l + 2 < len && !strcmp(path + l - 4, ".vti") && stat(path, &sb) != 0) {
        char vti[4800];
        snprintf(vti, sizeof vti, "%s", path);
        memcpy(path + l - 4, ".pvti", 6);
        if (stat(path, &sb) == 0) return 1;
        ss_error_set(err, SS_ERR_INPUT, "%s: the snapshot is missing (and so is %s)", vti, path);
        return -1;
    }
    return 0;
}

ss_status ss_heal_saved_run_check(const ss_heal_saved_run *s, int i, ss_error *err) {
    if (i < 0 || i >= s->n)
        return ss_error_set(err, SS_ERR_INPUT, "--heal %s: no snapshot %d", s->dir, i);
    char path[4800];
    snprintf(path, sizeof path, "%s/fields/%s", s->dir, s->file[i]);
    struct stat sb;
    ss_status st;
    switch (snapshot_file(path, sizeof path, err)) {
    case 1:
        st = ss_heal_pvti_check(path, err);
        break;
    case 0:
        st = stat(path, &sb) || !S_ISREG(sb.st_mode)
                 ? ss_error_set(err, SS_ERR_INPUT, "%s: the snapshot is missing", path)
                 : SS_OK;
        break;
    default:
        return SS_ERR_INPUT;
    }
    if (st) return st;
    /* read whole and dropped: its header, extent, grid, day and size are
     * checked as the load checks them, so a damaged snapshot is an input
     * error before the caller has done any work */
    float *disp = NULL;
    double *closed = NULL;
    ss_heal_grid *g = ss_heal_saved_run_load(s, i, &disp, &closed, err);
    if (!g) return err && err->code ? err->code : SS_ERR_INPUT;
    ss_heal_grid_free(g);
    free(disp);
    free(closed);
    return SS_OK;
}

ss_heal_grid *ss_heal_saved_run_load(const ss_heal_saved_run *s, int i, float **displacement,
                                     double **closed_day, ss_error *err) {
    if (displacement) *displacement = NULL;
    if (closed_day) *closed_day = NULL;
    double *closed = NULL;
    if (i < 0 || i >= s->n) {
        ss_error_set(err, SS_ERR_INPUT, "--heal %s: no snapshot %d", s->dir, i);
        return NULL;
    }
    char path[4800];
    snprintf(path, sizeof path, "%s/fields/%s", s->dir, s->file[i]);
    int kind = snapshot_file(path, sizeof path, err);
    if (kind < 0) return NULL;
    ss_heal_grid *g = kind ? ss_heal_pvti_read(path, displacement, &closed, err)
                           : ss_heal_vti_read(path, displacement, &closed, err);
    if (!g) return NULL;
    if (!closed)
        ss_error_set(err, SS_ERR_INPUT,
                     "%s: no closed_day array (every snapshot of run format %d has one)", path,
                     SS_HEAL_RUN_FORMAT);
    if (!closed || g->nx != s->nx || g->ny != s->ny || g->nz != s->nz ||
        fabs(g->dx_mm - s->dx) > 1e-9 * s->dx ||
        fabs(g->t_days - s->day[i]) > 1e-6 * (1 + s->day[i])) {
        if (closed)
            ss_error_set(
                err, SS_ERR_INPUT,
                "%s: grid %dx%dx%d of %g mm at day %g, but summary.json and fields.pvd say "
                "%dx%dx%d of %g mm at day %g",
                path, g->nx, g->ny, g->nz, g->dx_mm, g->t_days, s->nx, s->ny, s->nz, s->dx,
                s->day[i]);
        ss_heal_grid_free(g);
        free(closed);
        if (displacement) {
            free(*displacement);
            *displacement = NULL;
        }
        return NULL;
    }
    if (closed_day)
        *closed_day = closed;
    else
        free(closed);
    g->skin_top_mm = s->skin_top;
    g->step = (uint64_t)llround(g->t_days / s->dt);
    return g;
}
