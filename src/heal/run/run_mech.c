/* The contraction mechanics inside a heal run (seed 001 §5.1-5.3; the model
 * is src/mech, docs/mech.md): set-up from the run's config and parameter file
 * (fresh) or from the checkpoint's metadata (resume), the per-row outline
 * area and the state at 95 % closure, the per-snapshot deformed tet mesh
 * (fields/mesh_NNNN.vtu + fields/mesh.pvd) and velocity top view
 * (surface/velocity_NNNN.png, Fig. 7), the area.csv columns and the
 * summary.json block.
 *
 * Design: the run steps the mechanics right after each heal step (run.c),
 * so the velocity of frame k drives the convection of step k+1. A checkpoint
 * stores the mechanics' particle state (positions, velocities, stresses,
 * rest lengths) base64-encoded in the run metadata next to the parameters and
 * sutures it was made with; a resume rebuilds the same mesh from the
 * checkpointed grid, restores the state and rebuilds the grid arrays with the
 * same function a step ends with, so it continues bit for bit. Gave up: the
 * metadata grows with the mesh (about 80 bytes per node). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "run_internal.h"

/* ---- base64 ------------------------------------------------------------------------- */

static const char b64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

static char *b64_encode(const unsigned char *d, size_t n) {
    char *o = malloc(4 * ((n + 2) / 3) + 1), *p = o;
    if (!o) return NULL;
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)d[i] << 16;
        if (i + 1 < n) v |= (uint32_t)d[i + 1] << 8;
        if (i + 2 < n) v |= d[i + 2];
        *p++ = b64[v >> 18];
        *p++ = b64[(v >> 12) & 63];
        *p++ = i + 1 < n ? b64[(v >> 6) & 63] : '=';
        *p++ = i + 2 < n ? b64[v & 63] : '=';
    }
    *p = 0;
    return o;
}

static unsigned char *b64_decode(const char *s, size_t *n) {
    size_t len = strlen(s);
    if (len % 4) return NULL;
    unsigned char *o = malloc(len / 4 * 3 + 1);
    if (!o) return NULL;
    size_t k = 0;
    for (size_t i = 0; i < len; i += 4) {
        uint32_t v = 0;
        int pad = 0;
        for (int j = 0; j < 4; j++) {
            const char c = s[i + j];
            const char *q = c == '=' ? NULL : strchr(b64, c);
            if (c == '=' && i + 4 == len && j >= 2) {
                pad++;
                v <<= 6;
                continue;
            }
            if (!q || !c || pad) {
                free(o);
                return NULL;
            }
            v = (v << 6) | (uint32_t)(q - b64);
        }
        o[k++] = (unsigned char)(v >> 16);
        if (pad < 2) o[k++] = (unsigned char)(v >> 8);
        if (pad < 1) o[k++] = (unsigned char)v;
    }
    *n = k;
    return o;
}

/* Exact double arrays in the checkpoint metadata (cJSON's printing rounds
 * to 15 digits when that reads back within an epsilon). */
static void add_doubles(cJSON *o, const char *key, const double *v, int n) {
    char *s = b64_encode((const unsigned char *)v, (size_t)n * sizeof(double));
    if (s) cJSON_AddStringToObject(o, key, s);
    free(s);
}

static int get_doubles(const cJSON *o, const char *key, double *v, int n) {
    const cJSON *j = cJSON_GetObjectItem(o, key);
    if (!cJSON_IsString(j)) return -1;
    size_t len = 0;
    unsigned char *b = b64_decode(j->valuestring, &len);
    int ok = b && len == (size_t)n * sizeof(double);
    if (ok) memcpy(v, b, len);
    free(b);
    return ok ? 0 : -1;
}

/* ---- set-up ---------------------------------------------------------------------------- */

static ss_status create_mech(ss_heal_run *r, ss_heal_grid *g, ss_error *err) {
    ss_tetmesh *mesh = NULL;
    if (r->c.tet_mesh && !(mesh = ss_tetmesh_read(r->c.tet_mesh, err)))
        return err->code ? err->code : SS_ERR_INPUT;
    r->mech = ss_mech_create(g, r->p, &r->mp, mesh, r->sutures, r->nsutures, err);
    ss_tetmesh_free(mesh);
    if (!r->mech && err && !strncmp(err->msg, "sutures: ", 9)) { /* name the file */
        ss_error e2 = *err;
        ss_error_set(err, e2.code, "%s: %s", r->c.sutures ? r->c.sutures : "the run's sutures",
                     e2.msg + 9);
    }
    if (!r->mech) return err->code ? err->code : SS_ERR_INPUT;
    return SS_OK;
}

ss_status ss_heal_run__mech_check_options(ss_heal_run *r, ss_error *err) {
    const ss_heal_run_config *c = &r->c;
    if (!c->mechanics) return ss_heal_run__mech_setup_fresh(r, err); /* only checks */
    if (c->kappa >= 0 && !(c->kappa <= 1.0 / 3.0 + 1e-12))
        return ss_error_set(err, SS_ERR_INPUT, "--kappa %g: the dispersion is 0..1/3", c->kappa);
    if (c->tet_size_mm != 0 && !(c->tet_size_mm > 0 && c->tet_size_mm <= 1e3))
        return ss_error_set(err, SS_ERR_INPUT, "--tet-size-mm %g: need a value in (0, 1000] mm",
                            c->tet_size_mm);
    ss_mech_params mp;
    ss_mech_params_default(&mp);
    ss_status st = SS_OK;
    if (c->params_path) {
        char *text = ss_read_file_max(c->params_path, NULL, SS_READ_MAX_CONFIG, err);
        if (!text) return err->code ? err->code : SS_ERR_INPUT;
        st = ss_mech_params_parse(&mp, text, c->params_path, err);
        free(text);
        if (st) return st;
    }
    if (c->fibres && (st = ss_mech_params_set_fibres(&mp, c->fibres, err))) return st;
    if ((st = ss_mech_params_check(&mp, err))) return st;
    if (c->sutures && !r->sutures &&
        !(r->sutures = ss_mech_sutures_read(c->sutures, &r->nsutures, err)))
        return err->code ? err->code : SS_ERR_INPUT;
    return SS_OK;
}

ss_status ss_heal_run__mech_setup_fresh(ss_heal_run *r, ss_error *err) {
    const ss_heal_run_config *c = &r->c;
    if (!c->mechanics) {
        if (c->fibres || c->kappa >= 0 || c->tet_size_mm != 0 || c->sutures || c->tet_mesh ||
            c->mech_model)
            return ss_error_set(err, SS_ERR_INPUT,
                                "--fibres, --kappa, --tet-size-mm, --sutures, --tet-mesh and "
                                "--mech-model need --mechanics");
        return SS_OK;
    }
    ss_mech_params_default(&r->mp);
    ss_status st = SS_OK;
    if (c->params_path) {
        char *text = ss_read_file_max(c->params_path, NULL, SS_READ_MAX_CONFIG, err);
        if (!text) return err->code ? err->code : SS_ERR_INPUT;
        st = ss_mech_params_parse(&r->mp, text, c->params_path, err);
        free(text);
        if (st) return st;
    }
    if (c->fibres && (st = ss_mech_params_set_fibres(&r->mp, c->fibres, err))) return st;
    if (c->mech_model && (st = ss_mech_model_parse(c->mech_model, &r->mp.model, err))) return st;
    if (c->kappa >= 0) {
        if (!(c->kappa <= 1.0 / 3.0 + 1e-12))
            return ss_error_set(err, SS_ERR_INPUT, "--kappa %g: the dispersion is 0..1/3",
                                c->kappa);
        r->mp.kappa = c->kappa > 1.0 / 3.0 ? 1.0 / 3.0 : c->kappa;
    }
    if (c->tet_size_mm != 0) {
        if (!(c->tet_size_mm >= r->g->dx_mm && c->tet_size_mm <= 1e3))
            return ss_error_set(err, SS_ERR_INPUT,
                                "--tet-size-mm %g: at least the voxel size %g mm", c->tet_size_mm,
                                r->g->dx_mm);
        r->mp.tet_size_mm = c->tet_size_mm;
    }
    if ((st = ss_mech_params_check(&r->mp, err))) return st;
    if (c->sutures && !r->sutures &&
        !(r->sutures = ss_mech_sutures_read(c->sutures, &r->nsutures, err)))
        return err->code ? err->code : SS_ERR_INPUT;
    if (c->tet_mesh && !r->g->cell) { /* read it now: its errors are input errors */
        ss_tetmesh *mesh = ss_tetmesh_read(c->tet_mesh, err);
        if (!mesh) return err->code ? err->code : SS_ERR_INPUT;
        ss_tetmesh_free(mesh);
    }
    if (!r->g->cell || c->distributed) { /* created on the grid the MPI driver attaches */
        r->mech_pending = 1;
        return SS_OK;
    }
    return create_mech(r, r->g, err);
}

static ss_status mech_resume_on(ss_heal_run *r, ss_heal_grid *g, const char *dir, ss_error *err);

ss_status ss_heal_run__mech_setup_resume(ss_heal_run *r, const char *dir, ss_error *err) {
    if (!r->mech_aux) return SS_OK;
    if (r->c.distributed) { /* created on the grid the driver attaches */
        r->mech_pending = 1;
        return SS_OK;
    }
    return mech_resume_on(r, r->g, dir, err);
}

int ss_heal_run_mech_pending(const ss_heal_run *r) { return r && r->mech_pending; }

ss_status ss_heal_run_mech_attach(ss_heal_run *r, ss_heal_grid *mg, ss_error *err) {
    if (!r->mech_pending || !mg || mg->nx != r->g->nx || mg->ny != r->g->ny || mg->nz != r->g->nz ||
        !mg->cell) {
        ss_heal_grid_free(mg);
        return ss_error_set(err, SS_ERR_INPUT, "heal run: no pending mechanics for this grid");
    }
    r->mg = mg;
    r->mech_pending = 0;
    mg->t_days = r->g->t_days;
    mg->step = r->g->step;
    if (r->mech_aux) return mech_resume_on(r, mg, r->out_dir, err);
    return create_mech(r, mg, err);
}

static ss_status mech_resume_on(ss_heal_run *r, ss_heal_grid *g, const char *dir, ss_error *err) {
    cJSON *m = r->mech_aux;
    const cJSON *pj = cJSON_GetObjectItem(m, "params"), *st_b64 = cJSON_GetObjectItem(m, "state"),
                *ol = cJSON_GetObjectItem(m, "outline"), *su = cJSON_GetObjectItem(m, "sutures"),
                *tm = cJSON_GetObjectItem(m, "tet_mesh");
    if (!cJSON_IsObject(pj) || !cJSON_IsString(st_b64) || !cJSON_IsString(ol))
        return ss_error_set(err, SS_ERR_INPUT, "%s: checkpoint mechanics metadata is incomplete",
                            dir);
    ss_mech_params_default(&r->mp);
    cJSON *wrap = cJSON_CreateObject();
    cJSON_AddItemToObject(wrap, "mechanics", cJSON_Duplicate(pj, 1));
    char *text = cJSON_PrintUnformatted(wrap);
    cJSON_Delete(wrap);
    if (!text) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    ss_status st = ss_mech_params_parse(&r->mp, text, "checkpoint mechanics parameters", err);
    free(text);
    if (st) return st;
    if (cJSON_IsArray(su)) {
        r->nsutures = cJSON_GetArraySize(su);
        r->sutures = calloc((size_t)r->nsutures + 1, sizeof *r->sutures);
        if (!r->sutures) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        for (int i = 0; i < r->nsutures; i++) {
            const cJSON *e = cJSON_GetArrayItem(su, i);
            double v[7];
            for (int k = 0; k < 7; k++) {
                const cJSON *x = cJSON_GetArrayItem(e, k);
                v[k] = cJSON_IsNumber(x) ? x->valuedouble : (k == 6 ? INFINITY : NAN);
            }
            for (int d = 0; d < 3; d++) {
                r->sutures[i].a[d] = v[d];
                r->sutures[i].b[d] = v[3 + d];
            }
            r->sutures[i].remove_day = v[6] < 0 ? INFINITY : v[6];
        }
    }
    if (cJSON_IsString(tm)) r->c.tet_mesh = tm->valuestring; /* used during create only */
    st = create_mech(r, g, err);
    r->c.tet_mesh = NULL;
    if (st) return st;
    size_t n = 0;
    unsigned char *buf = b64_decode(st_b64->valuestring, &n);
    if (!buf) return ss_error_set(err, SS_ERR_INPUT, "%s: checkpoint mechanics state damaged", dir);
    st = ss_mech_state_set(r->mech, buf, n, err);
    free(buf);
    if (!st) st = ss_mech_state_apply(r->mech, g, err);
    if (st) return st;
    r->capoutline = r->nrows + 256;
    r->outline = malloc((size_t)r->capoutline * sizeof(double));
    r->myof = malloc((size_t)r->capoutline * sizeof(double));
    if (!r->outline || !r->myof) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    if (get_doubles(m, "outline", r->outline, r->nrows) ||
        get_doubles(m, "myofibroblasts", r->myof, r->nrows))
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: checkpoint mechanics rows do not match its area rows", dir);
    double v[9];
    if (cJSON_GetObjectItem(m, "closure")) {
        if (get_doubles(m, "closure", v, 9))
            return ss_error_set(err, SS_ERR_INPUT, "%s: checkpoint closure state damaged", dir);
        r->closed = 1;
        r->close_day = v[0];
        r->close_st.outline_area_mm2 = v[1];
        r->close_st.initial_outline_area_mm2 = v[2];
        r->close_st.extent_x_mm = v[3];
        r->close_st.extent_y_mm = v[4];
        r->close_st.principal[0] = v[5];
        r->close_st.principal[1] = v[6];
        r->close_st.aspect_major_minor = v[7];
        r->close_st.max_speed_mm_day = v[8];
    }
    cJSON_Delete(r->mech_aux);
    r->mech_aux = NULL;
    return SS_OK;
}

void ss_heal_run__mech_free(ss_heal_run *r) {
    ss_mech_free(r->mech);
    ss_heal_grid_free(r->mg);
    free(r->sutures);
    free(r->outline);
    free(r->myof);
    cJSON_Delete(r->mech_aux);
}

/* ---- per row, per snapshot -------------------------------------------------------------- */

ss_status ss_heal_run__mech_row(ss_heal_run *r, ss_error *err) {
    if (!r->mech) return SS_OK;
    if (r->nrows > r->capoutline) {
        int cap = r->nrows + 256;
        double *q = realloc(r->outline, (size_t)cap * sizeof *q);
        if (q) r->outline = q;
        double *q2 = q ? realloc(r->myof, (size_t)cap * sizeof *q2) : NULL;
        if (!q2) return ss_error_set(err, SS_ERR_NOMEM, "out of memory (area rows)");
        r->myof = q2;
        r->capoutline = cap;
    }
    ss_mech_stats st;
    ss_mech_stats_compute(r->mech, &st);
    r->outline[r->nrows - 1] = st.outline_area_mm2;
    r->myof[r->nrows - 1] = st.myofibroblast_fraction;
    const ss_heal_area_row *row = &r->rows[r->nrows - 1];
    if (!r->closed && r->nrows > 1 && ss_heal_area_normalised(&row->st) <= 0.05) {
        r->closed = 1;
        r->close_day = row->t_days;
        r->close_st = st;
    }
    return SS_OK;
}

ss_status ss_heal_run__mech_snapshot(ss_heal_run *r, int idx, ss_error *err) {
    if (!r->mech) return SS_OK;
    char path[4400];
    snprintf(path, sizeof path, "%s/fields/mesh_%04d.vtu", r->out_dir, idx);
    ss_status st = ss_mech_vtu_write(r->mech, path, r->g->t_days, err);
    if (st) return st;
    st = ss_heal_run__series_pvd(r, "fields", "mesh", err);
    if (st) return st;
    /* Fig. 7: speed from 0 to the frame's largest, with a colour bar that
     * says what it is (a fixed 0.5 mm/day left most of a fast frame flat
     * red and a slow one flat blue) */
    ss_image *img = ss_mech_top_view_bar(r->mech, 512, 0, err);
    if (!img) return err->code ? err->code : SS_ERR_NOMEM;
    snprintf(path, sizeof path, "%s/surface/velocity_%04d.png", r->out_dir, idx);
    st = ss_png_write(path, img, 8, SS_ENC_SRGB, err);
    ss_image_free(img);
    return st;
}

/* ---- metadata, tables ---------------------------------------------------------------------- */

static cJSON *params_object(const ss_heal_run *r) {
    char *t = ss_mech_params_to_json(&r->mp);
    cJSON *j = t ? cJSON_Parse(t) : NULL;
    free(t);
    cJSON *m = j ? cJSON_DetachItemFromObject(j, "mechanics") : NULL;
    cJSON_Delete(j);
    return m;
}

void ss_heal_run__mech_aux(const ss_heal_run *r, cJSON *aux) {
    if (!r->mech) return;
    cJSON *m = cJSON_AddObjectToObject(aux, "mechanics");
    cJSON *p = params_object(r);
    if (p) cJSON_AddItemToObject(m, "params", p);
    if (r->c.tet_mesh) cJSON_AddStringToObject(m, "tet_mesh", r->c.tet_mesh);
    if (r->nsutures) {
        cJSON *su = cJSON_AddArrayToObject(m, "sutures");
        for (int i = 0; i < r->nsutures; i++) {
            const ss_mech_suture *s = &r->sutures[i];
            double v[7] = {s->a[0],
                           s->a[1],
                           s->a[2],
                           s->b[0],
                           s->b[1],
                           s->b[2],
                           isfinite(s->remove_day) ? s->remove_day : -1};
            cJSON_AddItemToArray(su, cJSON_CreateDoubleArray(v, 7));
        }
    }
    size_t n = ss_mech_state_size(r->mech);
    unsigned char *buf = malloc(n);
    if (buf) {
        ss_mech_state_get(r->mech, buf);
        char *s = b64_encode(buf, n);
        if (s) cJSON_AddStringToObject(m, "state", s);
        free(s);
        free(buf);
    }
    add_doubles(m, "outline", r->outline, r->nrows);
    add_doubles(m, "myofibroblasts", r->myof, r->nrows);
    if (r->closed) {
        const ss_mech_stats *c = &r->close_st;
        double v[9] = {r->close_day,    c->outline_area_mm2,   c->initial_outline_area_mm2,
                       c->extent_x_mm,  c->extent_y_mm,        c->principal[0],
                       c->principal[1], c->aspect_major_minor, c->max_speed_mm_day};
        add_doubles(m, "closure", v, 9);
    }
}

/* Contraction and closure shares of row i: c = 1 - outline/outline0 (the
 * deformed initial outline), f = 1 - open/initial; the share of the closure
 * due to contraction is c / f (clamped to 0..1), the rest is epithelialisation. */
static void shares(const ss_heal_run *r, int i, double *contraction, double *by_c) {
    double o0 = r->outline[0];
    double c = o0 > 0 ? 1.0 - r->outline[i] / o0 : 0.0;
    double f = 1.0 - ss_heal_area_normalised(&r->rows[i].st);
    double s = f > 1e-9 ? c / f : 0.0;
    *contraction = c;
    *by_c = s < 0 ? 0 : s > 1 ? 1 : s;
}

int ss_heal_run__mech_columns(const ss_heal_run *r, const char *const **names, double **vals) {
    static const char *const cols[5] = {
        "outline_area_mm2", "contraction", "closure_share_contraction",
        "closure_share_epithelialisation", "myofibroblast_fraction"};
    if (!r->mech) return 0;
    double *v = malloc((size_t)r->nrows * 5 * sizeof(double) + 1);
    if (!v) return -1;
    for (int i = 0; i < r->nrows; i++) {
        double c, s;
        shares(r, i, &c, &s);
        v[5 * i] = r->outline[i];
        v[5 * i + 1] = c;
        v[5 * i + 2] = s;
        v[5 * i + 3] = 1.0 - ss_heal_area_normalised(&r->rows[i].st) > 1e-9 ? 1.0 - s : 0.0;
        v[5 * i + 4] = r->myof[i];
    }
    *names = cols;
    *vals = v;
    return 5;
}

void ss_heal_run__mech_summary(const ss_heal_run *r, cJSON *j) {
    if (!r->mech) return;
    cJSON *m = cJSON_AddObjectToObject(j, "mechanics");
    const ss_tetmesh *M = ss_mech_mesh(r->mech);
    cJSON_AddNumberToObject(m, "tets", M->ntets);
    cJSON_AddNumberToObject(m, "nodes", M->nnodes);
    int stride;
    double w = ss_mech_kernel(r->mech, &stride);
    cJSON_AddNumberToObject(m, "kernel_width_cells", w);
    cJSON_AddNumberToObject(m, "kernel_stride_cells", stride);
    cJSON_AddNumberToObject(m, "sutures", r->nsutures);
    ss_mech_stats now;
    ss_mech_stats_compute(r->mech, &now);
    cJSON_AddNumberToObject(m, "last_frame_substeps", now.substeps);
    /* at 95 % closure, or at the end when the wound did not close */
    const ss_mech_stats *s = r->closed ? &r->close_st : &now;
    cJSON_AddBoolToObject(m, "closed", r->closed);
    if (r->closed)
        cJSON_AddNumberToObject(m, "closure_day", r->close_day);
    else
        cJSON_AddNullToObject(m, "closure_day");
    double red = s->initial_outline_area_mm2 > 0
                     ? 100.0 * (1.0 - s->outline_area_mm2 / s->initial_outline_area_mm2)
                     : 0.0;
    cJSON_AddNumberToObject(m, "contraction_percent", red);
    cJSON_AddNumberToObject(m, "initial_outline_area_mm2", s->initial_outline_area_mm2);
    cJSON_AddNumberToObject(m, "outline_area_mm2", s->outline_area_mm2);
    cJSON_AddNumberToObject(m, "extent_x_mm", s->extent_x_mm);
    cJSON_AddNumberToObject(m, "extent_y_mm", s->extent_y_mm);
    cJSON_AddNumberToObject(m, "aspect_ratio_y_over_x",
                            s->extent_x_mm > 0 ? s->extent_y_mm / s->extent_x_mm : 0.0);
    cJSON_AddNumberToObject(m, "aspect_ratio_major_minor", s->aspect_major_minor);
    cJSON_AddItemToObject(m, "principal_direction", cJSON_CreateDoubleArray(s->principal, 2));
    int i = -1;
    for (int k = 0; k < r->nrows; k++)
        if (!r->closed || r->rows[k].t_days <= r->close_day) i = k;
    if (i >= 0) {
        double c, sh;
        shares(r, i, &c, &sh);
        cJSON_AddNumberToObject(m, "closure_share_contraction", sh);
        cJSON_AddNumberToObject(m, "closure_share_epithelialisation", 1.0 - sh);
    }
    /* the time course: contraction of the outline by day 2, 5, 10, 15, 20, 30
     * (the last area row at or before the day, when the run got there), and
     * the state at the end of the run (the scar keeps contracting after the
     * epithelium has closed, docs/mech.md) */
    cJSON *by = cJSON_AddObjectToObject(m, "contraction_percent_by_day");
    static const int days[] = {2, 5, 10, 15, 20, 30};
    for (size_t d = 0; d < sizeof days / sizeof days[0]; d++) {
        int k = -1;
        for (int q = 0; q < r->nrows; q++)
            if (r->rows[q].t_days <= days[d] + 1e-9) k = q;
        if (k < 0 || r->rows[r->nrows - 1].t_days < days[d] - 1e-9) continue;
        char key[16];
        snprintf(key, sizeof key, "%d", days[d]);
        cJSON_AddNumberToObject(
            by, key, r->outline[0] > 0 ? 100.0 * (1.0 - r->outline[k] / r->outline[0]) : 0.0);
    }
    cJSON *end = cJSON_AddObjectToObject(m, "end");
    cJSON_AddNumberToObject(end, "day", r->nrows ? r->rows[r->nrows - 1].t_days : 0.0);
    cJSON_AddNumberToObject(end, "contraction_percent",
                            now.initial_outline_area_mm2 > 0
                                ? 100.0 *
                                      (1.0 - now.outline_area_mm2 / now.initial_outline_area_mm2)
                                : 0.0);
    cJSON_AddNumberToObject(end, "aspect_ratio_y_over_x",
                            now.extent_x_mm > 0 ? now.extent_y_mm / now.extent_x_mm : 0.0);
    cJSON_AddNumberToObject(end, "myofibroblast_fraction", now.myofibroblast_fraction);
    cJSON *p = params_object(r);
    if (p) cJSON_AddItemToObject(m, "params", p);
}
