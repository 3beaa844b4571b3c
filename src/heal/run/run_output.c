/* What a heal run writes (docs/heal-outputs.md): snapshots (VTK ImageData of
 * every field, the ParaView time collection, top-view surface maps of seed 001
 * §5.4's fields), the run metadata stored inside checkpoints so a resume
 * continues the area curve and the snapshot list, and the closing tables
 * (area.csv, the Fig. 4 plot area.png, summary.json).
 *
 * Design: every file is written atomically by the heal_io writers, and the
 * folder goes through the core output discipline (src/core/output.c): checked
 * before any work, locked against a second run, its disk use estimated. A new
 * folder is written in place and marked unfinished until the end, so a killed
 * run resumes from its checkpoints and is never taken for a finished one;
 * --force over a previous run is staged next to it and swapped in whole at
 * the end, so the old run stays intact until then. A resume checks that
 * every checkpoint in the folder belongs to the run (run.json: a hash of
 * scenario, grid, parameters, wound, scheme and step) before anything is
 * touched. Snapshot colour scales are a function of the state alone, so a
 * resumed run draws the same pictures as an uninterrupted one. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <fcntl.h>
#include <stdint.h>
#include <time.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "run_internal.h"
#include "skinsim/shell.h"

/* ---- checkpoint metadata ------------------------------------------------------------ */

/* Values per stored area row: t, open, region and initial area, the field
 * means, then eschar over the wound, scar volume and scar maximum (rows of
 * checkpoints written before these three existed have only the first ones;
 * they read as 0). */
#define ROW_VALUES_OLD (4 + SS_HEAL_NFIELDS)
#define ROW_VALUES_7 (7 + SS_HEAL_NFIELDS) /* before the open column count */
#define ROW_VALUES_8 (8 + SS_HEAL_NFIELDS) /* before the elevation */
#define ROW_VALUES (10 + SS_HEAL_NFIELDS)

/* A number that reads back bit for bit: cJSON 1.7 prints %.15g when that
 * parses back within an epsilon, which loses the last bit of about one
 * double in five; a restored area row then interpolates the closure time
 * differently (t50 ...207 against ...208 after a resume). As in cJSON,
 * a value that is not finite is null. */
static cJSON *exact_number(double v) {
    char t[32];
    if (!isfinite(v)) return cJSON_CreateNull();
    snprintf(t, sizeof t, "%.17g", v);
    return cJSON_CreateRaw(t);
}

static void add_exact(cJSON *o, const char *name, double v) {
    cJSON_AddItemToObject(o, name, exact_number(v));
}

char *ss_heal_run__aux_json(const ss_heal_run *r, double wall) {
    cJSON *j = cJSON_CreateObject();
    if (r->run_id[0]) cJSON_AddStringToObject(j, "run_id", r->run_id); /* whose checkpoint */
    add_exact(j, "days", r->days);
    add_exact(j, "snapshot_every_steps", (double)r->snap_every);
    add_exact(j, "area_every_steps", (double)r->area_every);
    add_exact(j, "checkpoint_every_steps", (double)r->ckpt_every);
    add_exact(j, "seed", (double)r->c.seed);
    add_exact(j, "wall_time_s", wall);
    if (r->adapt_tol > 0) { /* the adaptive step's state: part of the run's state */
        add_exact(j, "adapt_tol", r->adapt_tol);
        add_exact(j, "adapt_mult", (double)r->mult);
        add_exact(j, "adapt_retried", (double)r->retried);
        add_exact(j, "adapt_taken", (double)r->taken);
    }
    if (r->wound) cJSON_AddItemToObject(j, "wound", cJSON_Duplicate(r->wound, 1));
    cJSON *a = cJSON_AddArrayToObject(j, "area");
    for (int i = 0; i < r->nrows; i++) {
        const ss_heal_area_row *row = &r->rows[i];
        double v[ROW_VALUES] = {row->t_days, row->st.open_area_mm2, row->st.wound_region_area_mm2,
                                row->st.initial_area_mm2};
        for (int k = 0; k < SS_HEAL_NFIELDS; k++) v[4 + k] = row->st.field_mean[k];
        v[4 + SS_HEAL_NFIELDS] = row->st.eschar_wound_mean;
        v[5 + SS_HEAL_NFIELDS] = row->st.scar_volume_mm3;
        v[6 + SS_HEAL_NFIELDS] = row->st.scar_max;
        v[7 + SS_HEAL_NFIELDS] = row->st.open_columns_mm2;
        v[8 + SS_HEAL_NFIELDS] = row->st.elevation_mean_mm;
        v[9 + SS_HEAL_NFIELDS] = row->st.elevation_max_mm;
        cJSON *row_j = cJSON_CreateArray();
        for (int k = 0; row_j && k < ROW_VALUES; k++)
            cJSON_AddItemToArray(row_j, exact_number(v[k]));
        cJSON_AddItemToArray(a, row_j);
    }
    cJSON *sn = cJSON_AddArrayToObject(j, "snapshots");
    for (int i = 0; i < r->nsnap; i++) {
        cJSON *e = cJSON_CreateArray();
        cJSON_AddItemToArray(e, exact_number(r->snap_t[i]));
        cJSON_AddItemToArray(e, cJSON_CreateString(r->snap_file[i]));
        cJSON_AddItemToArray(sn, e);
    }
    ss_heal_run__mech_aux(r, j);
    if (r->closed_day) { /* as text of %.17g numbers: cJSON's own printing rounds */
        size_t ncol = (size_t)r->g->nx * (size_t)r->g->ny, len = 0;
        char *txt = malloc(ncol * 26 + 1);
        for (size_t i = 0; txt && i < ncol; i++)
            len += (size_t)snprintf(txt + len, 26, i ? " %.17g" : "%.17g", r->closed_day[i]);
        if (txt) cJSON_AddStringToObject(j, "closed_day", txt);
        free(txt);
    }
    ss_heal_run__shell_aux(r, j);
    char *s = cJSON_PrintUnformatted(j);
    cJSON_Delete(j);
    return s;
}

static ss_status restore_rows(ss_heal_run *r, const cJSON *area, const char *dir, ss_error *err) {
    const cJSON *e;
    cJSON_ArrayForEach(e, area) {
        const int nv = cJSON_GetArraySize(e);
        if (nv != ROW_VALUES && nv != ROW_VALUES_8 && nv != ROW_VALUES_7 && nv != ROW_VALUES_OLD)
            return ss_error_set(err, SS_ERR_INPUT, "%s: checkpoint area rows malformed", dir);
        double v[ROW_VALUES] = {0};
        for (int k = 0; k < nv; k++) {
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
        row->st.eschar_wound_mean = v[4 + SS_HEAL_NFIELDS];
        row->st.scar_volume_mm3 = v[5 + SS_HEAL_NFIELDS];
        row->st.scar_max = v[6 + SS_HEAL_NFIELDS];
        row->st.open_columns_mm2 = v[7 + SS_HEAL_NFIELDS];
        row->st.elevation_mean_mm = v[8 + SS_HEAL_NFIELDS];
        row->st.elevation_max_mm = v[9 + SS_HEAL_NFIELDS];
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
    const cJSON *at = cJSON_GetObjectItem(j, "adapt_tol"),
                *am = cJSON_GetObjectItem(j, "adapt_mult"),
                *ar = cJSON_GetObjectItem(j, "adapt_retried"),
                *ak = cJSON_GetObjectItem(j, "adapt_taken");
    if (cJSON_IsNumber(at)) {
        r->adapt_tol = at->valuedouble;
        r->mult = cJSON_IsNumber(am) ? (long long)am->valuedouble : 1;
        r->retried = cJSON_IsNumber(ar) ? (long long)ar->valuedouble : 0;
        r->taken = cJSON_IsNumber(ak) ? (long long)ak->valuedouble : 0;
        if (!(r->adapt_tol > 0 && r->adapt_tol <= 1) || r->mult < 1)
            st = ss_error_set(err, SS_ERR_INPUT, "%s: checkpoint adaptive-step state is invalid",
                              dir);
    }
    cJSON *w = cJSON_GetObjectItem(j, "wound");
    if (w) r->wound = cJSON_Duplicate(w, 1);
    cJSON *mo = cJSON_GetObjectItem(j, "mechanics");
    if (mo && !(r->mech_aux = cJSON_Duplicate(mo, 1)))
        st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    const cJSON *cd = cJSON_GetObjectItem(j, "closed_day");
    size_t ncol = (size_t)r->g->nx * (size_t)r->g->ny;
    if (!st && cd) { /* checkpoints from before it lack it: the run starts tracking anew */
        const char *p = cJSON_IsString(cd) ? cd->valuestring : NULL;
        if (!p || !(r->closed_day = malloc(ncol * sizeof *r->closed_day)))
            st = ss_error_set(err, p ? SS_ERR_NOMEM : SS_ERR_INPUT,
                              p ? "out of memory" : "%s: checkpoint closure days malformed", dir);
        for (size_t k = 0; !st && k < ncol; k++) {
            char *end;
            r->closed_day[k] = strtod(p, &end);
            if (end == p || !isfinite(r->closed_day[k]))
                st = ss_error_set(err, SS_ERR_INPUT, "%s: checkpoint closure days malformed", dir);
            p = end;
        }
    }
    cJSON *so = cJSON_GetObjectItem(j, "shell");
    if (so && !(r->shell_aux = cJSON_Duplicate(so, 1)))
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

static int dir_has_entries(const char *path) {
    DIR *d = opendir(path);
    if (!d) return 0;
    struct dirent *e;
    int n = 0;
    while (!n && (e = readdir(d))) n = strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
    closedir(d);
    return n;
}

/* Disk a run writes from here to its end: every snapshot still due (VTK
 * fields, 8 bits of cell state and float32 fields and velocity per voxel,
 * and four surface maps), the checkpoints kept (two, plus the one being
 * written), the area table and plot. */
static double estimate_bytes(const ss_heal_run *r) {
    double cells = (double)r->g->nx * r->g->ny * r->g->nz;
    double vti = cells * (1 + 4.0 * (SS_HEAL_NFIELDS + 3)) + 8192;
    double map = 4 * 80e3; /* colour-mapped PNGs: about 12 KB each at 20 x 20 voxels */
    long long left = r->nsteps - (long long)r->g->step;
    double snaps = (r->snap_every ? (double)left / (double)r->snap_every : 0) + 2;
    double ckpt = r->ckpt_every ? 3 * (cells * (1 + 4.0 * (SS_HEAL_NFIELDS + 3)) + 65536) : 0;
    double rows = (double)left / (double)(r->area_every > 0 ? r->area_every : 1) + 2;
    if (r->mech) { /* displacement in the .vti, the mesh .vtu (ASCII), the velocity view */
        const ss_tetmesh *M = ss_mech_mesh(r->mech);
        vti += cells * 12.0;
        map += (double)M->nnodes * 120 + (double)M->ntets * 50 + 200e3;
        ckpt += r->ckpt_every ? 3 * (double)ss_mech_state_size(r->mech) * 4 / 3 : 0;
    }
    if (r->shell) /* the skin mesh: ASCII .vtu and binary .glb per snapshot */
        map += (double)r->surf.nvertices * (140 + 4 * (SS_SHELL_VERTEX_STRIDE + 11)) +
               (double)r->surf.ntriangles * 45 + 4096;
    return snaps * (vti + map) + ckpt + rows * 24.0 * (4 + SS_HEAL_NFIELDS) + 500e3;
}

/* The checks of ss_heal_run__outputs_open that need no grid (the folder's
 * lock, a previous run in it, the path itself), for a run that first does
 * long work (a mesh) before its grid exists: a bad --out fails at once. */
ss_status ss_heal_run__outputs_precheck(ss_heal_run *r, ss_error *err) {
    if (!r->out_dir) return SS_OK;
    ss_status s = ss_heal_run__outputs_open(r, err);
    ss_outputs_free(r->outs); /* nothing staged yet: only checked */
    r->outs = NULL;
    return s;
}

ss_status ss_heal_run__outputs_open(ss_heal_run *r, ss_error *err) {
    const ss_heal_run_config *c = &r->c;
    const char *dir = r->out_dir;
    const char *opt = c->resume_dir ? "--resume" : "--out";
    struct stat st;
    long holder = ss_output_lock_holder(dir);
    if (holder)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s %s: another skinsim run (process %ld) is writing it; wait for it "
                            "to finish or choose another folder",
                            opt, dir, holder);
    int exists = stat(dir, &st) == 0 && S_ISDIR(st.st_mode) && dir_has_entries(dir);
    if (!c->resume_dir && exists && !c->force) {
        char probe[4400];
        snprintf(probe, sizeof probe, "%s/checkpoints", dir);
        int complete = ss_output_dir_is_complete(dir, "heal");
        int unfinished =
            ss_output_dir_is_unfinished(dir, "heal") || (!complete && file_exists(probe));
        if (!complete && !unfinished) /* not a heal run: neither --resume nor --force takes it */
            return ss_error_set(err, SS_ERR_INPUT,
                                "--out %s: exists and is not a 'skinsim heal' run folder (no "
                                "finished or unfinished run of this command is in it), so it is "
                                "not replaced; choose another --out",
                                dir);
        return ss_error_set(
            err, SS_ERR_INPUT,
            "%s holds %s; use --resume %s to continue it, --force to replace "
            "it, or another --out",
            dir, unfinished ? "an unfinished run (stopped before its end)" : "a previous run", dir);
    }
    r->outs = ss_outputs_create("heal", err);
    if (!r->outs) return SS_ERR_NOMEM;
    const char *ins[] = {c->params_path,       c->wound_mask, c->wound_stroke, c->wound_mesh,
                         c->wound_depth_image, c->sutures,    c->tet_mesh};
    ss_status s = SS_OK;
    for (size_t k = 0; k < sizeof ins / sizeof *ins && !s; k++)
        s = ss_outputs_input(r->outs, ins[k], err);
    /* A new folder (and a resumed one) is written in place, so a killed run
     * can be resumed from its checkpoints; --force over a previous run is
     * staged and swapped in whole at the end, so the old run stays until
     * then. */
    ss_output_kind kind = !c->resume_dir && exists ? SS_OUTPUT_DIR : SS_OUTPUT_DIR_IN_PLACE;
    if (!s) s = ss_outputs_add(r->outs, opt, dir, kind, r->g ? estimate_bytes(r) : 0, err);
    return s;
}

ss_status ss_heal_run__prepare_out_dir(ss_heal_run *r, ss_error *err) {
    ss_status st = ss_outputs_begin(r->outs, err);
    if (st) return st;
    char *work = strdup(ss_outputs_path(r->outs, 0));
    if (!work) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    free(r->out_dir);
    r->out_dir = work; /* from here on every file goes here */
    static const char *const subs[2] = {"fields", "surface"};
    char path[4400];
    for (int k = 0; k < 2 && !st; k++) {
        snprintf(path, sizeof path, "%s/%s", r->out_dir, subs[k]);
        st = ss_mkdir_p(path, err);
    }
    if (!st && r->resumed_from < 0) st = ss_heal_run__write_identity(r, err);
    return st;
}

/* ---- run identity ------------------------------------------------------------------------ */

static uint64_t fnv1a(uint64_t h, const void *p, size_t n) {
    const unsigned char *b = p;
    for (size_t i = 0; i < n; i++) h = (h ^ b[i]) * 1099511628211ull;
    return h;
}

/* What makes two runs the same run: scenario, grid, parameters, wound,
 * scheme and step. Equal identities give equal states at equal steps, so a
 * checkpoint of one resumes the other exactly. */
typedef struct heal_identity {
    char run_id[17], params_hash[17], scenario[32];
    int n[3];
    double dx;
} heal_identity;

static void identity_of(const char *scenario, const ss_heal_grid *g, const char *params_json,
                        const cJSON *wound, int scheme, double dt, heal_identity *id) {
    memset(id, 0, sizeof *id);
    snprintf(id->scenario, sizeof id->scenario, "%s", scenario ? scenario : "");
    id->n[0] = g->nx, id->n[1] = g->ny, id->n[2] = g->nz;
    id->dx = g->dx_mm;
    const char *pj = params_json ? params_json : "";
    snprintf(id->params_hash, sizeof id->params_hash, "%016llx",
             (unsigned long long)fnv1a(14695981039346656037ull, pj, strlen(pj)));
    char *w = wound ? cJSON_PrintUnformatted(wound) : NULL;
    char head[256];
    snprintf(head, sizeof head, "%s|%d|%d|%d|%.17g|%.17g|%d|%.17g|", id->scenario, g->nx, g->ny,
             g->nz, g->dx_mm, g->skin_top_mm, scheme, dt);
    uint64_t h = fnv1a(14695981039346656037ull, head, strlen(head));
    h = fnv1a(h, pj, strlen(pj));
    if (w) h = fnv1a(h, w, strlen(w));
    snprintf(id->run_id, sizeof id->run_id, "%016llx", (unsigned long long)h);
    free(w);
}

static void describe(const heal_identity *id, char *buf, size_t n) {
    snprintf(buf, n, "run %s: scenario %s, grid %dx%dx%d of %g mm, parameters %s", id->run_id,
             id->scenario, id->n[0], id->n[1], id->n[2], id->dx, id->params_hash);
}

void ss_heal_run__new_run_id(ss_heal_run *r) {
    unsigned char b[16] = {0};
    ssize_t got = -1;
    int fd = open("/dev/urandom", O_RDONLY | O_CLOEXEC);
    if (fd >= 0) {
        got = read(fd, b, sizeof b);
        close(fd);
    }
    if (got != (ssize_t)sizeof b) { /* no urandom: time, process and address */
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        uint64_t v[2] = {(uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec,
                         (uint64_t)getpid() ^ (uint64_t)(uintptr_t)r};
        uint64_t h1 = fnv1a(14695981039346656037ull, v, sizeof v), h2 = fnv1a(h1, v, sizeof v);
        memcpy(b, &h1, 8);
        memcpy(b + 8, &h2, 8);
    }
    for (int i = 0; i < 16; i++) snprintf(r->run_id + 2 * i, 3, "%02x", b[i]);
}

ss_status ss_heal_run__write_identity(const ss_heal_run *r, ss_error *err) {
    heal_identity id;
    identity_of(r->scenario, r->g, r->params_json, r->wound, (int)r->scheme, r->dt, &id);
    cJSON *j = cJSON_CreateObject();
    if (!j) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    cJSON_AddStringToObject(j, "command", "heal");
    cJSON_AddNumberToObject(j, "format", SS_HEAL_RUN_FORMAT);
    cJSON_AddStringToObject(j, "skinsim_version", ss_version());
    cJSON_AddStringToObject(j, "run_id", r->run_id);
    cJSON_AddStringToObject(j, "identity", id.run_id);
    cJSON_AddStringToObject(j, "scenario", id.scenario);
    cJSON_AddItemToObject(j, "grid", cJSON_CreateIntArray(id.n, 3));
    cJSON_AddNumberToObject(j, "dx_mm", id.dx);
    cJSON_AddStringToObject(j, "params_hash", id.params_hash);
    char *text = cJSON_Print(j);
    cJSON_Delete(j);
    if (!text) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    char path[4400];
    snprintf(path, sizeof path, "%s/run.json", r->out_dir);
    ss_status st = ss_write_file_atomic(path, text, strlen(text), err);
    free(text);
    return st;
}

/* A checkpoint's identity (from its own grid, scenario, parameters, wound,
 * scheme and step) and the run id it was written under ("" = none). */
static void checkpoint_identity(const ss_heal_checkpoint *ck, heal_identity *id, char rid[33]) {
    cJSON *aux = ck->aux && *ck->aux ? cJSON_Parse(ck->aux) : NULL;
    identity_of(ck->scenario, ck->grid, ck->params_json, cJSON_GetObjectItem(aux, "wound"),
                ck->scheme, ck->dt_days, id);
    const cJSON *r = cJSON_GetObjectItem(aux, "run_id");
    snprintf(rid, 33, "%s",
             cJSON_IsString(r) && strlen(r->valuestring) == 32 ? r->valuestring : "");
    cJSON_Delete(aux);
}

/* What a refusal tells the user to do. */
#define RESUME_HINT                                                                                \
    "the checkpoints cannot be proven to be this run's, so nothing is resumed and the folder is "  \
    "left as it is; start the run again (heal --force --out DIR, or another --out)"

/* One checkpoint against the run: its run id and its identity. */
static ss_status check_one(const char *dir, const char *name, const ss_heal_checkpoint *ck,
                           const char *run_id, const char *identity, const heal_identity *want,
                           ss_error *err) {
    heal_identity have;
    char rid[33], a[512], b[512];
    checkpoint_identity(ck, &have, rid);
    if (!rid[0])
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: checkpoints/%s has no run id (written by a skinsim before run "
                            "ids, or not by this run); %s",
                            dir, name, RESUME_HINT);
    if (strcmp(rid, run_id) || strcmp(have.run_id, identity)) {
        describe(&have, a, sizeof a);
        describe(want, b, sizeof b);
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: checkpoints/%s belongs to another run (run id %s, %s; this run "
                            "per run.json: run id %s, %s); move it out of %s/checkpoints to "
                            "resume",
                            dir, name, rid, a, run_id, b, dir);
    }
    return SS_OK;
}

ss_status ss_heal_run__check_identity(ss_heal_run *r, const char *dir,
                                      const ss_heal_checkpoint *newest, ss_error *err) {
    char path[4400];
    /* the folder's own identity, written when the run began */
    snprintf(path, sizeof path, "%s/run.json", dir);
    if (!file_exists(path))
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: run.json is missing, so the run's identity is "
                            "unknown; " RESUME_HINT,
                            dir);
    ss_error e2;
    char *text = ss_read_file(path, NULL, &e2);
    cJSON *j = text ? cJSON_Parse(text) : NULL;
    free(text);
    const cJSON *rid = cJSON_GetObjectItem(j, "run_id"), *idy = cJSON_GetObjectItem(j, "identity"),
                *sc = cJSON_GetObjectItem(j, "scenario"), *gr = cJSON_GetObjectItem(j, "grid"),
                *dx = cJSON_GetObjectItem(j, "dx_mm"), *ph = cJSON_GetObjectItem(j, "params_hash");
    ss_status st = SS_OK;
    if (!j)
        st = ss_error_set(err, SS_ERR_INPUT, "%s: run.json is unreadable or damaged; " RESUME_HINT,
                          dir);
    else if (!cJSON_IsString(idy) || !cJSON_IsString(rid) || strlen(rid->valuestring) != 32)
        st = ss_error_set(err, SS_ERR_INPUT,
                          "%s: run.json has no run id (written by a skinsim before run ids); "
                          "resume it with the version that started it, or " RESUME_HINT,
                          dir);
    heal_identity want;
    memset(&want, 0, sizeof want);
    if (!st) {
        snprintf(want.run_id, sizeof want.run_id, "%s", idy->valuestring);
        snprintf(want.scenario, sizeof want.scenario, "%s",
                 cJSON_IsString(sc) ? sc->valuestring : "?");
        for (int k = 0; k < 3; k++) {
            const cJSON *v = cJSON_GetArrayItem(gr, k);
            want.n[k] = cJSON_IsNumber(v) ? v->valueint : 0;
        }
        want.dx = cJSON_IsNumber(dx) ? dx->valuedouble : 0;
        snprintf(want.params_hash, sizeof want.params_hash, "%s",
                 cJSON_IsString(ph) ? ph->valuestring : "?");
        st = check_one(dir, "(the newest usable checkpoint)", newest, rid->valuestring,
                       idy->valuestring, &want, err);
    }
    /* every other checkpoint there must be of the same run, or a later save
     * would prune or mix it */
    snprintf(path, sizeof path, "%s/checkpoints", dir);
    DIR *d = st ? NULL : opendir(path);
    struct dirent *e;
    while (!st && d && (e = readdir(d))) {
        size_t n = strlen(e->d_name);
        int head = n >= 6 && !strcmp(e->d_name + n - 5, ".sshh"); /* of a checkpoint in pieces */
        if (strncmp(e->d_name, "ckpt_", 5) || n < 6 ||
            (!head && strcmp(e->d_name + n - 5, ".sshc")))
            continue;
        char file[4700];
        snprintf(file, sizeof file, "%s/%s", path, e->d_name);
        ss_heal_checkpoint ck;
        if (head) { /* its header says whose it is */
            ss_heal_ckpt_header h;
            if (ss_heal_ckpt_header_read(file, &h, &e2)) continue; /* damaged: never read */
            ss_heal_grid gh = {0};
            gh.nx = h.whole[0], gh.ny = h.whole[1], gh.nz = h.whole[2];
            gh.dx_mm = h.dx_mm, gh.skin_top_mm = h.skin_top_mm;
            ck = (ss_heal_checkpoint){&gh, h.scenario, h.params_json, h.aux, h.scheme, h.dt_days};
            st = check_one(dir, e->d_name, &ck, rid->valuestring, idy->valuestring, &want, err);
            ss_heal_ckpt_header_free(&h);
        } else {
            if (ss_heal_checkpoint_read(file, &ck, &e2)) continue; /* damaged: skipped as before */
            st = check_one(dir, e->d_name, &ck, rid->valuestring, idy->valuestring, &want, err);
            ss_heal_checkpoint_free(&ck);
        }
    }
    if (d) closedir(d);
    if (!st) snprintf(r->run_id, sizeof r->run_id, "%s", rid->valuestring);
    cJSON_Delete(j);
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
        ss_image *m =
            r->hooks.surface_map
                ? r->hooks.surface_map(r->hooks.ctx, r->g, maps[k].field, maps[k].mode, err)
                : ss_heal_surface_map(r->g, maps[k].field, maps[k].mode, err);
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

ss_status ss_heal_run__series_pvd(const ss_heal_run *r, const char *dir, const char *stem,
                                  ss_error *err) {
    int n = r->nsnap + 1;
    double *t = malloc((size_t)n * sizeof *t);
    char **names = calloc((size_t)n, sizeof *names);
    ss_status st = SS_OK;
    if (!t || !names) st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    for (int i = 0; !st && i < n; i++) {
        char rel[128];
        t[i] = i < r->nsnap ? r->snap_t[i] : r->g->t_days;
        snprintf(rel, sizeof rel, "%s_%04d.vtu", stem, i);
        if (!(names[i] = strdup(rel))) st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    char path[4400];
    snprintf(path, sizeof path, "%s/%s/%s.pvd", r->out_dir, dir, stem);
    if (!st) st = ss_heal_pvd_write(path, n, t, (const char *const *)names, err);
    for (int i = 0; names && i < n; i++) free(names[i]);
    free(names);
    free(t);
    return st;
}

ss_status ss_heal_run__snapshot(ss_heal_run *r, ss_error *err) {
    if (!r->out_dir) return ss_error_set(err, SS_ERR_INPUT, "heal run: no output directory");
    ss_status st0 = ss_heal_run__sync(r, err);
    if (st0) return st0;
    char rel[64], path[4400];
    int idx = r->nsnap;
    /* distributed (no whole grid): the ranks write their pieces and the .pvti
     * that joins them (the snapshot hook below) */
    const int pieces = !r->g->cell;
    /* a resumed run may redo snapshots the killed run wrote after its checkpoint */
    snprintf(rel, sizeof rel, pieces ? "fields_%04d.pvti" : "fields_%04d.vti", idx);
    snprintf(path, sizeof path, "%s/fields/%s", r->out_dir, rel);
    ss_status st;
    if (pieces) {
        st = r->hooks.snapshot ? SS_OK
                               : ss_error_set(err, SS_ERR_INPUT, "heal run: no grid to write");
    } else if (r->mech) { /* the displacement next to the velocity */
        float *const *u = ss_mech_grid_displacement(r->mech);
        if (!u) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        const char *name = "displacement";
        float *const vec[1][3] = {{u[0], u[1], u[2]}};
        st = ss_heal_vti_write_all(path, r->g, 1, &name, vec, r->closed_day, err);
    } else {
        st = ss_heal_vti_write_all(path, r->g, 0, NULL, NULL, r->closed_day, err);
    }
    if (!st) st = ss_heal_run__mech_snapshot(r, idx, err);
    if (!st) st = ss_heal_run__shell_snapshot(r, idx, err);
    if (!st && r->hooks.snapshot) { /* e.g. the MPI driver's per-rank pieces */
        snprintf(path, sizeof path, "%s/fields", r->out_dir);
        st = r->hooks.snapshot(r->hooks.ctx, r->g, path, idx, err);
    }
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

/* The course figures of docs/heal-model.md §6 from the area rows: scab
 * formation and detachment, scar peak (largest density, volume) and the
 * state at the end. */
static void add_course(cJSON *j, const ss_heal_run *r) {
    if (!r->nrows) return;
    const double t95 = ss_heal_time_to_closure(r->rows, r->nrows, 0.05);
    double formed = -1, gone = -1, pmax = 0, pmax_day = 0, pvol = 0, pvol_day = 0;
    double emax = r->rows[0].st.elevation_max_mm, emax_day = r->rows[0].t_days;
    for (int i = 0; i < r->nrows; i++) {
        const ss_heal_area_row *w = &r->rows[i];
        if (formed < 0 && w->st.eschar_wound_mean > 0.5) formed = w->t_days;
        if (formed >= 0 && t95 >= 0 && gone < 0 && w->t_days >= t95 &&
            w->st.eschar_wound_mean < 0.05)
            gone = w->t_days;
        if (w->st.scar_max > pmax) pmax = w->st.scar_max, pmax_day = w->t_days;
        if (w->st.scar_volume_mm3 > pvol) pvol = w->st.scar_volume_mm3, pvol_day = w->t_days;
        if (w->st.elevation_max_mm > emax) emax = w->st.elevation_max_mm, emax_day = w->t_days;
    }
    const ss_heal_stats *e = &r->rows[r->nrows - 1].st;
    add_closure_time(j, "scab_formed_day", formed);
    add_closure_time(j, "scab_detached_day", gone);
    cJSON_AddNumberToObject(j, "final_eschar_wound_mean", e->eschar_wound_mean);
    cJSON_AddNumberToObject(j, "scar_peak_density", pmax);
    cJSON_AddNumberToObject(j, "scar_peak_density_day", pmax_day);
    cJSON_AddNumberToObject(j, "scar_peak_volume_mm3", pvol);
    cJSON_AddNumberToObject(j, "scar_peak_volume_day", pvol_day);
    cJSON_AddNumberToObject(j, "final_scar_volume_mm3", e->scar_volume_mm3);
    cJSON_AddNumberToObject(j, "final_wound_region_area_mm2", e->wound_region_area_mm2);
    /* the surface raised by collagen beyond the dermis it replaced (largest
     * over the run and the columns) and at the end [D12] */
    cJSON_AddNumberToObject(j, "surface_elevation_max_mm", emax);
    cJSON_AddNumberToObject(j, "surface_elevation_max_day", emax_day);
    cJSON_AddNumberToObject(j, "final_surface_elevation_max_mm", e->elevation_max_mm);
    cJSON_AddNumberToObject(j, "final_surface_elevation_mean_mm", e->elevation_mean_mm);
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
    if (r->adapt_tol > 0) {
        cJSON *a = cJSON_AddObjectToObject(j, "adaptive_steps");
        cJSON_AddNumberToObject(a, "tolerance", r->adapt_tol);
        cJSON_AddNumberToObject(a, "solver_steps", (double)r->taken);
        cJSON_AddNumberToObject(a, "retried", (double)r->retried);
        cJSON_AddNumberToObject(a, "max_dt_days", (double)r->mult_max * r->dt);
    }
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
        cJSON_AddNumberToObject(j, "final_open_columns_mm2", s1->open_columns_mm2);
    }
    /* how the open area is measured (the closure times follow it) */
    cJSON_AddStringToObject(j, "open_area", "uncovered: sum of 1 - e over the wound surface");
    cJSON_AddNumberToObject(j, "open_threshold", ss_heal_open_threshold());
    add_course(j, r);
    cJSON_AddNumberToObject(j, "wall_time_s", wall);
    cJSON_AddNumberToObject(j, "threads", ss_threads_get());
    cJSON_AddNumberToObject(j, "seed", (double)r->c.seed);
    cJSON_AddNumberToObject(j, "snapshots", r->nsnap);
    if (r->resumed_from >= 0)
        cJSON_AddNumberToObject(j, "resumed_from_step", (double)r->resumed_from);
    cJSON *pj = cJSON_Parse(r->params_json);
    cJSON_AddItemToObject(j, "params", pj ? pj : cJSON_CreateString(r->params_json));
    ss_heal_run__mech_summary(r, j);
    ss_heal_run__shell_summary(r, j);
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
    if (r->mech) { /* the contraction's course beside the open area */
        double *ol = malloc(((size_t)r->nrows + 1) * sizeof *ol);
        if (!ol) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        for (int i = 0; i < r->nrows; i++)
            ol[i] = r->outline[0] > 0 ? r->outline[i] / r->outline[0] : NAN;
        snprintf(title, sizeof title, "Open wound area and contraction - %s scenario", r->scenario);
        st = ss_heal_area_plot_contraction(path, r->rows, r->nrows, title, ol, r->myof, err);
        free(ol);
    } else
        st = ss_heal_area_plot(path, r->rows, r->nrows, title, err);
    if (st) return st;
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
