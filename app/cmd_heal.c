/* skinsim heal: the physically based wound-healing simulation of seed 001
 * (§4.1 biochemistry on the §5.1 grid) from the command line. Builds the wound
 * (footprint mask, painted strokes, depth image or a closed OBJ mesh voxelised
 * by ray parity), validates every input before anything is written, runs the
 * solver and writes the area curve of Fig. 4 (CSV + plot), VTK snapshots with
 * a ParaView time collection, top-view surface maps, checkpoints for exact
 * resume, and summary.json. */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE /* sysconf(_SC_PHYS_PAGES) */
#include <cjson/cJSON.h>
#include <dirent.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "skinsim/heal.h"
#include "skinsim/heal_io.h"

#define CMD "heal"

static void help(void) {
    printf("usage: skinsim heal [options]\n"
           "\n"
           "Simulates the healing of a wound in a block of skin with the biochemical\n"
           "model of Feess et al. (seed 001 §4.1): oxygen, MDGF, capillaries,\n"
           "fibroblasts, eschar, epithelium, scar and plasma on a regular 3D grid.\n"
           "Units: lengths in mm, times in days. x, y run along the skin, z up.\n"
           "\n"
           "Scenario and model\n"
           "  --scenario NAME        clean | scab | keloid (default clean, or the\n"
           "                         \"scenario\" key of --params)\n"
           "  --params FILE.json     parameter overrides (every value with its unit, see\n"
           "                         data/heal/params.json); applied on top of the scenario\n"
           "  --no-scab              switch off eschar (scab) formation\n"
           "  --static-region        keep the wound region fixed (no keloid growth)\n"
           "\n"
           "Grid (default: a 30 x 30 x 4 mm block, 0.5 mm voxels = 60x60x8, skin\n"
           "surface at 3 mm, 0.1 mm epidermis (at least 2 voxels))\n"
           "  --grid NXxNYxNZ        voxels; alone it keeps 0.5 mm voxels\n"
           "  --size-mm X,Y,Z        block size in mm; alone it keeps 0.5 mm voxels;\n"
           "                         with --grid the voxels must come out cubic\n"
           "  --skin-top-mm H        height of the skin surface (default: NZ-2 voxels,\n"
           "                         3 mm in the default block, one air layer)\n"
           "  --epidermis-mm E       epidermis thickness (default 0.1; at least 2 voxels\n"
           "                         are used)\n"
           "\n"
           "Wound (default: a centred square 20 x 20 mm, or 2/3 of the smaller block\n"
           "side if that is less, 1 mm deep)\n"
           "  --wound-mask PNG       footprint: pixels > 0.5 are wound; the image covers\n"
           "                         the whole block (row 0 at the far y edge)\n"
           "  --stroke CSV           painted outline(s): lines 'u,v[,stroke_id]', u,v in\n"
           "                         0..1 over the block; each stroke's hull is filled\n"
           "  --concave-k K          with --stroke: k-nearest concave hull (K >= 3);\n"
           "                         default 0 = convex hull\n"
           "  --wound-mesh OBJ       closed triangle mesh in mm in the grid frame (origin\n"
           "                         at the block corner, z up); voxels whose centre is\n"
           "                         inside (ray parity along z) are wound\n"
           "  --wound-depth-mm D     depth below the skin surface (default 1); with a\n"
           "                         PNG depth image, the depth of a white pixel\n"
           "  --wound-depth-image F  per-pixel depth: PNG grey 0..1 x --wound-depth-mm,\n"
           "                         or EXR in mm; alone it is also the footprint\n"
           "                         (depth > 0)\n"
           "\n");
    printf("Time\n"
           "  --days T               simulated time (default 10)\n"
           "  --scheme S             explicit | split (default split: implicit diffusion)\n"
           "  --dt DAYS              time step (default: automatic, see the solver's\n"
           "                         stability limit; too large is an error)\n"
           "  --snapshot-every DAYS  VTK + surface maps interval (default 1; 0 = first\n"
           "                         and last only)\n"
           "  --area-every DAYS      area.csv row interval (default 0.01, at least 1 step)\n"
           "  --checkpoint-every DAYS  write a checkpoint at this interval (default off)\n"
           "  --resume DIR           continue the run in DIR from its newest valid\n"
           "                         checkpoint (bit-identical to an uninterrupted run);\n"
           "                         may be combined with --days, --checkpoint-every,\n"
           "                         --threads, --quiet, --json\n"
           "\n"
           "Output\n"
           "  --out DIR              output directory (default heal-out)\n"
           "  --force                overwrite a previous run's outputs in DIR\n"
           "  --threads N            OpenMP threads (default $SKINSIM_THREADS or all)\n"
           "  --seed N               recorded in summary.json (the solver is deterministic\n"
           "                         and draws no random numbers)\n"
           "  --quiet                no progress bar or text summary\n"
           "  --json                 print summary.json on stdout\n"
           "\n");
    printf("Files written in DIR:\n"
           "  area.csv               t_days, open_area_mm2 (surface epithelium < 0.5),\n"
           "                         normalised_area (open / initial), wound_region_area_mm2,\n"
           "                         mean_<field> over tissue cells\n"
           "  area.png               normalised open area vs days (seed 001 Fig. 4)\n"
           "  fields/fields_NNNN.vti VTK ImageData: cell_state (UInt8) + 8 Float32 fields\n"
           "                         as cell data, spacing = voxel size in mm\n"
           "  fields/fields.pvd      ParaView collection, time = days (time slider)\n"
           "  surface/<f>_NNNN.png   top views of epithelium, capillary (surface value),\n"
           "                         eschar, scar (column maximum)\n"
           "  checkpoints/ckpt_*.sshc  with --checkpoint-every (newest 2 kept)\n"
           "  summary.json           scenario, grid, dt, scheme, days, time to 50%% and\n"
           "                         95%% closure, wall time, parameters\n"
           "See docs/heal-outputs.md. Exit codes: 0 ok, 1 runtime failure, 2 bad input\n"
           "(nothing is written then).\n");
}

typedef struct opts {
    const char *scenario, *params, *mask, *stroke, *mesh, *depth_image, *out, *resume;
    int grid[3], have_grid;
    double size[3];
    int have_size;
    double skin_top, epidermis, depth;
    int have_skin_top, have_depth, have_scenario;
    double days, dt, snap_every, area_every, ckpt_every;
    int have_days, have_ckpt;
    int scheme, concave_k, threads, no_scab, static_region, quiet, json, force;
    uint64_t seed;
    int nonresume_opts; /* options that a --resume run cannot take */
} opts;

/* ---- run state ----------------------------------------------------------------- */

typedef struct run {
    opts o;
    char scenario[32];
    ss_heal_params *p;
    ss_heal_grid *g;
    ss_heal_solver *s;
    char *params_json;
    double dt;
    long long nsteps, snap_every, area_every, ckpt_every;
    ss_heal_area_row *rows;
    int nrows, caprows;
    double *snap_t;
    char **snap_file;
    int nsnap, capsnap;
    double wall_prev;
    long long resumed_from;
    cJSON *wound; /* description for summary.json */
} run;

static void run_free(run *r) {
    ss_heal_solver_free(r->s);
    ss_heal_grid_free(r->g);
    ss_heal_params_free(r->p);
    free(r->params_json);
    free(r->rows);
    free(r->snap_t);
    for (int i = 0; i < r->nsnap; i++) free(r->snap_file[i]);
    free(r->snap_file);
    cJSON_Delete(r->wound);
}

static ss_status add_row(run *r, ss_error *err) {
    if (r->nrows == r->caprows) {
        int cap = r->caprows ? 2 * r->caprows : 256;
        ss_heal_area_row *q = realloc(r->rows, (size_t)cap * sizeof *q);
        if (!q) return ss_error_set(err, SS_ERR_NOMEM, "out of memory (area rows)");
        r->rows = q;
        r->caprows = cap;
    }
    ss_heal_area_row *row = &r->rows[r->nrows++];
    row->t_days = r->g->t_days;
    ss_heal_stats_compute(r->g, &row->st);
    return SS_OK;
}

static ss_status add_snap(run *r, double t, const char *file, ss_error *err) {
    if (r->nsnap == r->capsnap) {
        int cap = r->capsnap ? 2 * r->capsnap : 32;
        double *qt = realloc(r->snap_t, (size_t)cap * sizeof *qt);
        if (qt) r->snap_t = qt;
        char **qf = realloc(r->snap_file, (size_t)cap * sizeof *qf);
        if (qf) r->snap_file = qf;
        if (!qt || !qf) return ss_error_set(err, SS_ERR_NOMEM, "out of memory (snapshots)");
        r->capsnap = cap;
    }
    r->snap_file[r->nsnap] = strdup(file);
    if (!r->snap_file[r->nsnap]) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    r->snap_t[r->nsnap++] = t;
    return SS_OK;
}

/* ---- aux metadata stored in checkpoints ------------------------------------------ */

static char *aux_json(const run *r, double wall) {
    cJSON *j = cJSON_CreateObject();
    cJSON_AddNumberToObject(j, "days", r->o.days);
    cJSON_AddNumberToObject(j, "snapshot_every_steps", (double)r->snap_every);
    cJSON_AddNumberToObject(j, "area_every_steps", (double)r->area_every);
    cJSON_AddNumberToObject(j, "checkpoint_every_steps", (double)r->ckpt_every);
    cJSON_AddNumberToObject(j, "seed", (double)r->o.seed);
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
    char *s = cJSON_PrintUnformatted(j);
    cJSON_Delete(j);
    return s;
}

static ss_status aux_restore(run *r, const char *aux, const char *dir, ss_error *err) {
    cJSON *j = cJSON_Parse(aux);
    if (!j) return ss_error_set(err, SS_ERR_INPUT, "%s: checkpoint metadata is malformed", dir);
    ss_status st = SS_OK;
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
    if (!r->o.have_days) r->o.days = days->valuedouble;
    r->snap_every = (long long)se->valuedouble;
    r->area_every = (long long)ae->valuedouble;
    if (!r->o.have_ckpt) r->ckpt_every = (long long)ce->valuedouble;
    if (cJSON_IsNumber(seed)) r->o.seed = (uint64_t)seed->valuedouble;
    if (cJSON_IsNumber(wall)) r->wall_prev = wall->valuedouble;
    cJSON *w = cJSON_GetObjectItem(j, "wound");
    if (w) r->wound = cJSON_Duplicate(w, 1);
    cJSON *e;
    cJSON_ArrayForEach(e, area) {
        if (cJSON_GetArraySize(e) != 4 + SS_HEAL_NFIELDS) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s: checkpoint area rows malformed", dir);
            break;
        }
        double v[4 + SS_HEAL_NFIELDS];
        for (int k = 0; k < 4 + SS_HEAL_NFIELDS; k++) v[k] = cJSON_GetArrayItem(e, k)->valuedouble;
        if ((st = add_row(r, err))) break;
        ss_heal_area_row *row = &r->rows[r->nrows - 1];
        row->t_days = v[0];
        row->st.open_area_mm2 = v[1];
        row->st.wound_region_area_mm2 = v[2];
        row->st.initial_area_mm2 = v[3];
        for (int k = 0; k < SS_HEAL_NFIELDS; k++) row->st.field_mean[k] = v[4 + k];
    }
    cJSON_ArrayForEach(e, snaps) {
        if (st) break;
        cJSON *t = cJSON_GetArrayItem(e, 0), *f = cJSON_GetArrayItem(e, 1);
        if (!cJSON_IsNumber(t) || !cJSON_IsString(f)) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s: checkpoint snapshot list malformed", dir);
            break;
        }
        st = add_snap(r, t->valuedouble, f->valuestring, err);
    }
    cJSON_Delete(j);
    return st;
}

/* ---- argument parsing -------------------------------------------------------------- */

static ss_status parse_grid(const char *s, int g[3], ss_error *err) {
    long v[3];
    char *end;
    const char *p = s;
    for (int k = 0; k < 3; k++) {
        v[k] = strtol(p, &end, 10);
        if (end == p || v[k] < 3 || v[k] > 100000) goto bad;
        if (k < 2) {
            if (*end != 'x' && *end != 'X') goto bad;
            p = end + 1;
        }
    }
    if (*end) goto bad;
    for (int k = 0; k < 3; k++) g[k] = (int)v[k];
    return SS_OK;
bad:
    return ss_error_set(err, SS_ERR_INPUT,
                        "--grid: '%s' is not NXxNYxNZ with each count between 3 and 100000", s);
}

static int parse_args(int argc, char **argv, opts *o, ss_error *err) {
    memset(o, 0, sizeof *o);
    o->scenario = "clean";
    o->out = "heal-out";
    o->days = 10;
    o->snap_every = 1;
    o->area_every = 0.01;
    o->depth = SS_HEAL_DEFAULT_DEPTH_MM;
    o->epidermis = SS_HEAL_DEFAULT_EPIDERMIS_MM;
    o->scheme = SS_HEAL_SPLIT;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) return 1;
        int flag = 1;
        if (!strcmp(a, "--no-scab")) {
            o->no_scab = 1, o->nonresume_opts++;
        } else if (!strcmp(a, "--static-region")) {
            o->static_region = 1, o->nonresume_opts++;
        } else if (!strcmp(a, "--quiet")) {
            o->quiet = 1;
        } else if (!strcmp(a, "--json")) {
            o->json = 1;
        } else if (!strcmp(a, "--force")) {
            o->force = 1;
        } else {
            flag = 0;
        }
        if (flag) continue;
        if (strncmp(a, "--", 2) != 0) {
            ss_error_set(err, SS_ERR_INPUT, "unexpected argument '%s'", a);
            return -1;
        }
        if (i + 1 >= argc) {
            ss_error_set(err, SS_ERR_INPUT, "%s needs a value", a);
            return -1;
        }
        const char *v = argv[++i];
        ss_status st = SS_OK;
        long l;
        int resume_ok = 0;
        if (!strcmp(a, "--scenario")) {
            o->scenario = v;
            o->have_scenario = 1;
        } else if (!strcmp(a, "--params")) {
            o->params = v;
        } else if (!strcmp(a, "--grid")) {
            st = parse_grid(v, o->grid, err);
            o->have_grid = 1;
        } else if (!strcmp(a, "--size-mm")) {
            double *d;
            int n;
            st = cli_parse_double_list(a, v, 1e-6, 1e6, &d, &n, err);
            if (!st && n != 3) st = ss_error_set(err, SS_ERR_INPUT, "--size-mm: need X,Y,Z");
            if (!st)
                for (int k = 0; k < 3; k++) o->size[k] = d[k];
            if (!st) free(d);
            o->have_size = 1;
        } else if (!strcmp(a, "--skin-top-mm")) {
            st = cli_parse_double(a, v, 1e-6, 1e6, &o->skin_top, err);
            o->have_skin_top = 1;
        } else if (!strcmp(a, "--epidermis-mm")) {
            st = cli_parse_double(a, v, 0, 1e6, &o->epidermis, err);
        } else if (!strcmp(a, "--wound-mask")) {
            o->mask = v;
        } else if (!strcmp(a, "--stroke")) {
            o->stroke = v;
        } else if (!strcmp(a, "--concave-k")) {
            st = cli_parse_int(a, v, 0, 10000, &l, err);
            o->concave_k = (int)l;
            if (!st && l > 0 && l < 3)
                st = ss_error_set(err, SS_ERR_INPUT, "--concave-k: use 0 (convex) or >= 3");
        } else if (!strcmp(a, "--wound-mesh")) {
            o->mesh = v;
        } else if (!strcmp(a, "--wound-depth-mm")) {
            st = cli_parse_double(a, v, 1e-6, 1e6, &o->depth, err);
            o->have_depth = 1;
        } else if (!strcmp(a, "--wound-depth-image")) {
            o->depth_image = v;
        } else if (!strcmp(a, "--days")) {
            st = cli_parse_double(a, v, 1e-9, 1e6, &o->days, err);
            o->have_days = 1;
            resume_ok = 1;
        } else if (!strcmp(a, "--dt")) {
            st = cli_parse_double(a, v, 1e-12, 1e3, &o->dt, err);
        } else if (!strcmp(a, "--scheme")) {
            if (!strcmp(v, "explicit"))
                o->scheme = SS_HEAL_EXPLICIT;
            else if (!strcmp(v, "split"))
                o->scheme = SS_HEAL_SPLIT;
            else
                st = ss_error_set(err, SS_ERR_INPUT, "--scheme: '%s' is not 'explicit' or 'split'",
                                  v);
        } else if (!strcmp(a, "--snapshot-every")) {
            st = cli_parse_double(a, v, 0, 1e6, &o->snap_every, err);
        } else if (!strcmp(a, "--area-every")) {
            st = cli_parse_double(a, v, 0, 1e6, &o->area_every, err);
        } else if (!strcmp(a, "--checkpoint-every")) {
            st = cli_parse_double(a, v, 0, 1e6, &o->ckpt_every, err);
            o->have_ckpt = 1;
            resume_ok = 1;
        } else if (!strcmp(a, "--resume")) {
            o->resume = v;
            resume_ok = 1;
        } else if (!strcmp(a, "--out")) {
            o->out = v;
        } else if (!strcmp(a, "--threads")) {
            st = cli_parse_int(a, v, 0, 4096, &l, err);
            o->threads = (int)l;
            resume_ok = 1;
        } else if (!strcmp(a, "--seed")) {
            st = cli_parse_u64(a, v, &o->seed, err);
        } else {
            ss_error_set(err, SS_ERR_INPUT, "unknown option '%s'", a);
            return -1;
        }
        if (st) return -1;
        if (!resume_ok) o->nonresume_opts++;
    }
    return 0;
}

/* ---- setting up a fresh run (no file is written here) --------------------------- */

static int file_exists(const char *path) {
    struct stat st;
    return stat(path, &st) == 0;
}

static ss_status check_memory(int nx, int ny, int nz, ss_error *err) {
    size_t cells = (size_t)nx * (size_t)ny * (size_t)nz;
    if (cells > SS_HEAL_MAX_CELLS)
        return ss_error_set(err, SS_ERR_INPUT, "--grid %dx%dx%d: %zu cells exceed the limit %zu",
                            nx, ny, nz, cells, (size_t)SS_HEAL_MAX_CELLS);
    /* grid + wound mask + solver scratch (about two more grids for the split scheme) */
    double need = 3.0 * (double)ss_heal_grid_bytes(nx, ny, nz) + (double)cells;
    double avail = ss_memory_physical_bytes();
    if (avail > 0 && need > 0.8 * avail)
        return ss_error_set(err, SS_ERR_INPUT,
                            "--grid %dx%dx%d needs about %.1f GB, more than this machine's "
                            "memory (%.1f GB)",
                            nx, ny, nz, need / 1e9, avail / 1e9);
    return SS_OK;
}

static ss_status setup_fresh(run *r, ss_error *err) {
    opts *o = &r->o;
    ss_status st;
    /* scenario + parameters */
    /* with --params and no --scenario, the file's "scenario" key decides */
    r->p = o->params ? ss_heal_params_load(o->params, o->have_scenario ? o->scenario : NULL, err)
                     : ss_heal_params_preset(o->scenario, err);
    if (!r->p) return err->code ? err->code : SS_ERR_INPUT;
    if ((st = ss_heal_params_set_switches(r->p, o->no_scab ? 0 : -1, o->static_region ? 1 : -1)))
        return ss_error_set(err, st, "cannot apply --no-scab/--static-region");
    snprintf(r->scenario, sizeof r->scenario, "%s", r->p->scenario);

    /* grid geometry */
    int n[3];
    double dx = SS_HEAL_DEFAULT_DX_MM;
    if (o->have_grid && o->have_size) {
        dx = o->size[0] / o->grid[0];
        for (int k = 1; k < 3; k++)
            if (fabs(o->size[k] / o->grid[k] - dx) > 1e-6 * dx)
                return ss_error_set(err, SS_ERR_INPUT,
                                    "--size-mm %g,%g,%g with --grid %dx%dx%d gives non-cubic "
                                    "voxels (%g, %g, %g mm); voxels must be cubic",
                                    o->size[0], o->size[1], o->size[2], o->grid[0], o->grid[1],
                                    o->grid[2], o->size[0] / o->grid[0], o->size[1] / o->grid[1],
                                    o->size[2] / o->grid[2]);
        memcpy(n, o->grid, sizeof n);
    } else if (o->have_grid) {
        memcpy(n, o->grid, sizeof n);
    } else {
        double sz[3] = {SS_HEAL_DEFAULT_BLOCK_X_MM, SS_HEAL_DEFAULT_BLOCK_Y_MM,
                        SS_HEAL_DEFAULT_BLOCK_Z_MM};
        if (o->have_size) memcpy(sz, o->size, sizeof sz);
        for (int k = 0; k < 3; k++) {
            double c = ceil(sz[k] / dx - 1e-9);
            if (c < 3 || c > 100000)
                return ss_error_set(err, SS_ERR_INPUT,
                                    "--size-mm: %g mm gives %g voxels of %g mm (need 3..100000)",
                                    sz[k], c, dx);
            n[k] = (int)c;
        }
    }
    if ((st = check_memory(n[0], n[1], n[2], err))) return st;
    double X = n[0] * dx, Y = n[1] * dx, Z = n[2] * dx;
    /* Default skin surface: one air layer under the top boundary voxel, which
     * is the highest surface ss_heal_grid_init accepts ((nz-2) voxels). */
    double top = o->have_skin_top ? o->skin_top : (n[2] - 2) * dx;
    if (!(top > 0) || top >= Z)
        return ss_error_set(err, SS_ERR_INPUT,
                            "skin surface at %g mm is outside the block (0..%g mm); use "
                            "--skin-top-mm or --size-mm",
                            top, Z);

    /* wound inputs: read and check everything before creating the grid */
    int nsrc = !!o->mask + !!o->stroke + !!o->mesh;
    if (nsrc > 1)
        return ss_error_set(err, SS_ERR_INPUT,
                            "give only one of --wound-mask, --stroke, --wound-mesh");
    if (o->mesh && (o->depth_image || o->have_depth))
        return ss_error_set(err, SS_ERR_INPUT,
                            "--wound-mesh defines the wound volume; it cannot be combined with "
                            "--wound-depth-mm or --wound-depth-image");
    if (o->concave_k && !o->stroke)
        return ss_error_set(err, SS_ERR_INPUT, "--concave-k only applies to --stroke");
    if (!o->depth_image && o->depth >= top - dx)
        return ss_error_set(err, SS_ERR_INPUT,
                            "--wound-depth-mm %g reaches the bottom of the tissue (skin surface "
                            "at %g mm, %g mm voxels)",
                            o->depth, top, dx);
    ss_image *fp = NULL, *dimg = NULL;
    ss_tri_mesh mesh = {0};
    r->wound = cJSON_CreateObject();
    if (o->mask) {
        fp = ss_heal_footprint_read(o->mask, err);
        if (!fp) return err->code;
        cJSON_AddStringToObject(r->wound, "mask", o->mask);
    } else if (o->stroke) {
        ss_stroke_set ss;
        if ((st = ss_stroke_csv_read(o->stroke, &ss, err))) return st;
        fp = ss_stroke_footprint(&ss, 4 * n[0], 4 * n[1], o->concave_k, o->stroke, err);
        cJSON_AddStringToObject(r->wound, "stroke", o->stroke);
        cJSON_AddNumberToObject(r->wound, "strokes", ss.nstrokes);
        cJSON_AddStringToObject(r->wound, "hull", o->concave_k ? "concave" : "convex");
        ss_stroke_set_free(&ss);
        if (!fp) return err->code;
    } else if (o->mesh) {
        if ((st = ss_obj_read(o->mesh, &mesh, err))) return st;
        if ((st = ss_tri_mesh_check_closed(&mesh, o->mesh, err))) {
            ss_tri_mesh_free(&mesh);
            return st;
        }
        cJSON_AddStringToObject(r->wound, "mesh", o->mesh);
        cJSON_AddNumberToObject(r->wound, "triangles", mesh.ntris);
    }
    if (o->depth_image) {
        dimg = ss_heal_depth_image_read(o->depth_image, o->depth, err);
        if (!dimg) {
            ss_image_free(fp);
            return err->code;
        }
        float dmax = 0;
        size_t np = (size_t)dimg->width * (size_t)dimg->height;
        for (size_t i = 0; i < np; i++)
            if (dimg->data[i] > dmax) dmax = dimg->data[i];
        if (dmax >= top - dx) {
            ss_image_free(fp);
            ss_image_free(dimg);
            return ss_error_set(err, SS_ERR_INPUT,
                                "%s: depth %g mm reaches the bottom of the tissue (skin surface "
                                "at %g mm)",
                                o->depth_image, dmax, top);
        }
        if (!fp) { /* the depth image alone: its non-zero pixels are the footprint */
            fp = ss_image_create(dimg->width, dimg->height, 1, err);
            if (!fp) {
                ss_image_free(dimg);
                return err->code;
            }
            size_t on = 0;
            for (size_t i = 0; i < np; i++) on += (fp->data[i] = dimg->data[i] > 0 ? 1.f : 0.f);
            if (!on) {
                ss_image_free(fp);
                ss_image_free(dimg);
                return ss_error_set(err, SS_ERR_INPUT, "%s: depth image is zero everywhere",
                                    o->depth_image);
            }
        }
        cJSON_AddStringToObject(r->wound, "depth_image", o->depth_image);
    }
    if (!o->mesh) cJSON_AddNumberToObject(r->wound, "depth_mm", o->depth);

    /* grid + wound + init */
    r->g = ss_heal_grid_create(n[0], n[1], n[2], dx, err);
    uint8_t *w3 = NULL;
    if (r->g) {
        if (o->mesh) {
            size_t cnt = 0;
            w3 = ss_heal_voxelise_mesh(&mesh, n[0], n[1], n[2], dx, &cnt, err);
            if (w3 && cnt == 0) {
                ss_error_set(err, SS_ERR_INPUT,
                             "%s: no voxel centre of the %gx%gx%g mm block lies inside the mesh "
                             "(coordinates are mm from the block corner, z up)",
                             o->mesh, X, Y, Z);
                free(w3);
                w3 = NULL;
            }
            if (w3) cJSON_AddNumberToObject(r->wound, "voxels", (double)cnt);
        } else if (fp) {
            w3 = ss_heal_wound_from_footprint(r->g, top, fp, o->depth, dimg, err);
        } else {
            double side = SS_HEAL_DEFAULT_WOUND_MM, lim = (X < Y ? X : Y) * 2.0 / 3.0;
            if (side > lim) side = lim;
            w3 = ss_heal_wound_box(r->g, top, side, side, o->depth, err);
            cJSON_AddStringToObject(r->wound, "builtin", "centred square");
            cJSON_AddNumberToObject(r->wound, "side_mm", side);
        }
    }
    /* the wound must reach at least one voxel under the skin surface */
    size_t below = 0, plane = (size_t)n[0] * (size_t)n[1];
    for (size_t i = 0; w3 && i < plane * (size_t)n[2]; i++)
        below += w3[i] && ((double)(i / plane) + 0.5) * dx < top;
    if (w3 && !below) {
        ss_error_set(err, SS_ERR_INPUT,
                     "%s: the wound covers no voxel under the skin surface (%g mm) of the "
                     "%gx%gx%g mm block with %g mm voxels%s",
                     o->mesh     ? o->mesh
                     : o->mask   ? o->mask
                     : o->stroke ? o->stroke
                                 : "--wound-depth-mm",
                     top, X, Y, Z, dx,
                     o->mesh ? "; mesh coordinates are mm from the block corner, z up"
                             : "; make it larger or deeper");
        free(w3);
        w3 = NULL;
    }
    ss_tri_mesh_free(&mesh);
    ss_image_free(fp);
    ss_image_free(dimg);
    if (!w3) return err->code ? err->code : SS_ERR_RUNTIME;
    st = ss_heal_grid_init(r->g, top, o->epidermis, w3, r->p, err);
    free(w3);
    if (st) return st;

    /* time stepping */
    r->s = ss_heal_solver_create(r->g, r->p, (ss_heal_scheme)o->scheme, o->dt, err);
    if (!r->s) return err->code ? err->code : SS_ERR_INPUT;
    r->dt = ss_heal_solver_dt(r->s);
    r->snap_every = o->snap_every > 0 ? llround(o->snap_every / r->dt) : 0;
    if (o->snap_every > 0 && r->snap_every < 1) r->snap_every = 1;
    r->area_every = llround(o->area_every / r->dt);
    if (r->area_every < 1) r->area_every = 1;
    r->ckpt_every = o->ckpt_every > 0 ? llround(o->ckpt_every / r->dt) : 0;
    if (o->ckpt_every > 0 && r->ckpt_every < 1) r->ckpt_every = 1;
    r->params_json = ss_heal_params_to_json(r->p);
    if (!r->params_json) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    return SS_OK;
}

static ss_status setup_resume(run *r, ss_error *err) {
    opts *o = &r->o;
    if (o->nonresume_opts)
        return ss_error_set(err, SS_ERR_INPUT,
                            "--resume continues a run with its own settings; only --days, "
                            "--checkpoint-every, --threads, --quiet and --json may be given");
    o->out = o->resume;
    ss_heal_checkpoint ck;
    char note[2048];
    ss_status st = ss_heal_checkpoint_load_latest(o->resume, &ck, note, sizeof note, err);
    if (st) return st;
    if (note[0] && !o->quiet) fprintf(stderr, "skinsim heal: %s\n", note);
    r->g = ck.grid;
    ck.grid = NULL;
    snprintf(r->scenario, sizeof r->scenario, "%s", ck.scenario);
    r->params_json = ck.params_json;
    ck.params_json = NULL;
    r->dt = ck.dt_days;
    o->scheme = ck.scheme;
    st = aux_restore(r, ck.aux, o->resume, err);
    ss_heal_checkpoint_free(&ck);
    if (st) return st;
    r->p = ss_heal_params_parse(r->params_json, "checkpoint parameters", r->scenario, err);
    if (!r->p) return err->code ? err->code : SS_ERR_INPUT;
    r->s = ss_heal_solver_create(r->g, r->p, (ss_heal_scheme)o->scheme, r->dt, err);
    if (!r->s) return err->code ? err->code : SS_ERR_INPUT;
    if (ss_heal_solver_dt(r->s) != r->dt)
        return ss_error_set(err, SS_ERR_INPUT, "%s: solver refused the checkpoint's dt %.17g",
                            o->resume, r->dt);
    if (o->have_ckpt) r->ckpt_every = o->ckpt_every > 0 ? llround(o->ckpt_every / r->dt) : 0;
    if (o->have_ckpt && o->ckpt_every > 0 && r->ckpt_every < 1) r->ckpt_every = 1;
    r->resumed_from = (long long)r->g->step;
    return SS_OK;
}

/* ---- outputs ---------------------------------------------------------------------- */

static ss_status write_snapshot(run *r, ss_error *err) {
    char rel[64], path[4400];
    int idx = r->nsnap;
    /* a resumed run may redo snapshots the killed run wrote after its checkpoint */
    snprintf(rel, sizeof rel, "fields_%04d.vti", idx);
    snprintf(path, sizeof path, "%s/fields/%s", r->o.out, rel);
    ss_status st = ss_heal_vti_write(path, r->g, err);
    if (st) return st;
    if ((st = add_snap(r, r->g->t_days, rel, err))) return st;
    snprintf(path, sizeof path, "%s/fields/fields.pvd", r->o.out);
    if ((st = ss_heal_pvd_write(path, r->nsnap, r->snap_t, (const char *const *)r->snap_file, err)))
        return st;
    static const struct {
        int field;
        ss_heal_surface_mode mode;
        const char *how, *unit;
    } maps[4] = {{SS_HEAL_EPITHELIUM, SS_SURFACE_LAYER, "epithelial layer", "(1 = healthy)"},
                 {SS_HEAL_CAPILLARY, SS_SURFACE_TOP, "surface", "(1 = healthy)"},
                 {SS_HEAL_ESCHAR, SS_SURFACE_MAX, "column max", "(density)"},
                 {SS_HEAL_SCAR, SS_SURFACE_MAX, "column max", "(density)"}};
    for (int k = 0; k < 4; k++) {
        ss_image *m = ss_heal_surface_map(r->g, maps[k].field, maps[k].mode, err);
        if (!m) return err->code;
        /* Colour scale: 0 .. the next of 1, 2, 5, 10, 20, ... above the
         * largest value, so snapshots of a run share a scale unless a field
         * grows past it (a function of the state only, so resumed runs draw
         * the same maps). */
        float mx = 1;
        for (size_t i = 0; i < (size_t)m->width * (size_t)m->height; i++)
            if (m->data[i] > mx) mx = m->data[i];
        double vmax = 1;
        for (int step = 0; vmax < mx; step++) vmax *= step % 3 == 1 ? 2.5 : 2;
        const char *name = ss_heal_field_name(maps[k].field);
        char title[256];
        snprintf(title, sizeof title, "%s (%s), day %.2f - %s", name, maps[k].how, r->g->t_days,
                 r->scenario);
        snprintf(path, sizeof path, "%s/surface/%s_%04d.png", r->o.out, name, idx);
        st = ss_heal_surface_png(path, m, 0, vmax, title, maps[k].unit, r->g->dx_mm, err);
        ss_image_free(m);
        if (st) return st;
    }
    return SS_OK;
}

static ss_status write_tables(run *r, double wall, cJSON **summary_out, ss_error *err) {
    char path[4400], title[256];
    snprintf(path, sizeof path, "%s/area.csv", r->o.out);
    ss_status st = ss_heal_area_csv_write(path, r->rows, r->nrows, err);
    if (st) return st;
    snprintf(path, sizeof path, "%s/area.png", r->o.out);
    snprintf(title, sizeof title, "Normalised open wound area - %s scenario", r->scenario);
    if ((st = ss_heal_area_plot(path, r->rows, r->nrows, title, err))) return st;

    cJSON *j = cJSON_CreateObject();
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
    cJSON_AddStringToObject(j, "scheme", r->o.scheme == SS_HEAL_EXPLICIT ? "explicit" : "split");
    cJSON_AddNumberToObject(j, "dt_days", r->dt);
    cJSON_AddNumberToObject(j, "days", r->g->t_days);
    cJSON_AddNumberToObject(j, "steps", (double)r->g->step);
    double t50 = ss_heal_time_to_closure(r->rows, r->nrows, 0.5);
    double t95 = ss_heal_time_to_closure(r->rows, r->nrows, 0.05);
    if (t50 >= 0)
        cJSON_AddNumberToObject(j, "time_to_50pct_closure_days", t50);
    else
        cJSON_AddNullToObject(j, "time_to_50pct_closure_days");
    if (t95 >= 0)
        cJSON_AddNumberToObject(j, "time_to_95pct_closure_days", t95);
    else
        cJSON_AddNullToObject(j, "time_to_95pct_closure_days");
    if (r->nrows) {
        const ss_heal_stats *s0 = &r->rows[0].st, *s1 = &r->rows[r->nrows - 1].st;
        cJSON_AddNumberToObject(j, "initial_area_mm2", s0->initial_area_mm2);
        cJSON_AddNumberToObject(j, "final_open_area_mm2", s1->open_area_mm2);
        cJSON_AddNumberToObject(j, "final_normalised_area", ss_heal_area_normalised(s1));
    }
    cJSON_AddNumberToObject(j, "open_threshold", ss_heal_open_threshold());
    cJSON_AddNumberToObject(j, "wall_time_s", wall);
    cJSON_AddNumberToObject(j, "threads", ss_threads_get());
    cJSON_AddNumberToObject(j, "seed", (double)r->o.seed);
    cJSON_AddNumberToObject(j, "snapshots", r->nsnap);
    if (r->resumed_from >= 0)
        cJSON_AddNumberToObject(j, "resumed_from_step", (double)r->resumed_from);
    cJSON *pj = cJSON_Parse(r->params_json);
    cJSON_AddItemToObject(j, "params", pj ? pj : cJSON_CreateString(r->params_json));
    char *text = cJSON_Print(j);
    size_t len = strlen(text);
    char *t2 = malloc(len + 2);
    if (t2) {
        memcpy(t2, text, len);
        t2[len] = '\n';
        t2[len + 1] = '\0';
    }
    snprintf(path, sizeof path, "%s/summary.json", r->o.out);
    st = t2 ? ss_write_file_atomic(path, t2, len + 1, err)
            : ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    free(text);
    free(t2);
    if (st) {
        cJSON_Delete(j);
        return st;
    }
    *summary_out = j;
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
            if ((k == 0 && (!strcmp(dot, ".vti") || !strcmp(dot, ".pvd"))) ||
                (k == 1 && !strcmp(dot, ".png")) || (k == 2 && !strcmp(dot, ".sshc"))) {
                char f[4700];
                snprintf(f, sizeof f, "%s/%s", path, nm);
                unlink(f);
            }
        }
        closedir(d);
    }
}

/* ---- main --------------------------------------------------------------------------- */

int cmd_heal(int argc, char **argv) {
    ss_error err;
    ss_error_clear(&err);
    run r;
    memset(&r, 0, sizeof r);
    r.resumed_from = -1;
    int pa = parse_args(argc, argv, &r.o, &err);
    if (pa == 1) {
        help();
        return 0;
    }
    if (pa < 0) return cli_usage_error(CMD, "%s", err.msg);
    opts *o = &r.o;
    ss_threads_set(o->threads);

    ss_status st = o->resume ? setup_resume(&r, &err) : setup_fresh(&r, &err);
    if (!st) {
        r.nsteps = llround(o->days / r.dt);
        if (r.nsteps < 1)
            st = ss_error_set(&err, SS_ERR_INPUT, "--days %g is shorter than one step (dt %g)",
                              o->days, r.dt);
        else if (r.nsteps > 2000000000LL)
            st = ss_error_set(&err, SS_ERR_INPUT, "--days %g needs %lld steps of %g days", o->days,
                              r.nsteps, r.dt);
        else if (fabs((double)r.nsteps * r.dt - o->days) > 1e-9 * (o->days > 1 ? o->days : 1) &&
                 !o->quiet && !o->json)
            fprintf(stderr, "skinsim heal: note: --days %g rounded to %lld steps of %g days\n",
                    o->days, r.nsteps, r.dt);
        if (!st && (long long)r.g->step > r.nsteps)
            st = ss_error_set(&err, SS_ERR_INPUT,
                              "--days %g is before the checkpoint's time %g days", o->days,
                              r.g->t_days);
    }
    if (!st && !o->resume) {
        char probe[4400];
        st = ss_check_writable_dir(o->out, &err);
        snprintf(probe, sizeof probe, "%s/summary.json", o->out);
        char probe2[4400];
        snprintf(probe2, sizeof probe2, "%s/checkpoints", o->out);
        if (!st && !o->force && (file_exists(probe) || file_exists(probe2)))
            st = ss_error_set(&err, SS_ERR_INPUT,
                              "%s holds a previous run; use --resume %s to continue it, --force "
                              "to overwrite it, or another --out",
                              o->out, o->out);
    }
    if (st) {
        int rc = cli_fail(CMD, &err);
        run_free(&r);
        return rc;
    }

    /* Everything is validated: from here on, files are written. */
    char path[4400];
    double t0 = ss_now();
    if (o->force && !o->resume) clean_previous(o->out);
    const char *subs[2] = {"fields", "surface"};
    for (int k = 0; k < 2 && !st; k++) {
        snprintf(path, sizeof path, "%s/%s", o->out, subs[k]);
        st = ss_mkdir_p(path, &err);
    }
    if (!st && !o->resume) {
        st = add_row(&r, &err);
        if (!st) st = write_snapshot(&r, &err);
    }
    if (!st && !o->quiet && !o->json && !o->resume)
        fprintf(stderr,
                "skinsim heal: %s, %dx%dx%d voxels of %g mm, %s scheme, dt %g days, %lld "
                "steps\n",
                r.scenario, r.g->nx, r.g->ny, r.g->nz, r.g->dx_mm,
                o->scheme == SS_HEAL_EXPLICIT ? "explicit" : "split", r.dt, r.nsteps);
    ss_progress pr;
    ss_progress_begin(&pr, "heal", (double)r.nsteps, o->quiet);
    for (long long k = (long long)r.g->step + 1; !st && k <= r.nsteps; k++) {
        if ((st = ss_heal_step(r.s, r.g, &err))) break;
        int last = k == r.nsteps;
        if (k % r.area_every == 0 || last) st = add_row(&r, &err);
        if (!st && ((r.snap_every && k % r.snap_every == 0) || last)) st = write_snapshot(&r, &err);
        if (!st && r.ckpt_every && (k % r.ckpt_every == 0 || last)) {
            char *aux = aux_json(&r, r.wall_prev + ss_now() - t0);
            st = aux ? ss_heal_checkpoint_save(o->out, r.g, r.scenario, r.params_json, o->scheme,
                                               r.dt, aux, 2, &err)
                     : ss_error_set(&err, SS_ERR_NOMEM, "out of memory");
            free(aux);
        }
        ss_progress_update(&pr, (double)k);
    }
    ss_progress_end(&pr);
    cJSON *summary = NULL;
    if (!st) st = write_tables(&r, r.wall_prev + ss_now() - t0, &summary, &err);
    if (st) {
        if (err.code == SS_ERR_INPUT) err.code = SS_ERR_RUNTIME; /* mid-run: runtime failure */
        int rc = cli_fail(CMD, &err);
        run_free(&r);
        return rc;
    }
    if (o->json) {
        char *s = cJSON_Print(summary);
        printf("%s\n", s);
        free(s);
    } else if (!o->quiet) {
        cJSON *a = cJSON_GetObjectItem(summary, "time_to_50pct_closure_days");
        cJSON *b = cJSON_GetObjectItem(summary, "time_to_95pct_closure_days");
        cJSON *fa = cJSON_GetObjectItem(summary, "final_normalised_area");
        printf("%s: %.3g days simulated, final normalised open area %.4f\n", r.scenario,
               r.g->t_days, cJSON_IsNumber(fa) ? fa->valuedouble : NAN);
        char s50[32] = "not reached", s95[32] = "not reached";
        if (cJSON_IsNumber(a)) snprintf(s50, sizeof s50, "%.3f days", a->valuedouble);
        if (cJSON_IsNumber(b)) snprintf(s95, sizeof s95, "%.3f days", b->valuedouble);
        printf("time to 50%% closure: %s, to 95%%: %s\n", s50, s95);
        printf("outputs in %s/ (area.csv, area.png, fields/, surface/, summary.json)\n", o->out);
    }
    cJSON_Delete(summary);
    run_free(&r);
    return 0;
}
