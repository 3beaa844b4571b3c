/* MCML input (.mci) and output (.mco) files, so existing MCML inputs run
 * unchanged (MCML 1.2, Wang, Jacques & Zheng 1995, Comput. Methods Programs
 * Biomed. 47:131). The reader follows MCML's rules: one item per data line,
 * '#' starts a comment, blank and comment-only lines are skipped; a run's
 * output line must give both the name and the type (a line "A" alone is
 * refused, not written as a file called A) and the grid's 2-D arrays hold
 * at most SS_MCI_MAX_GRID_VALUES values within the memory available. The writer
 * produces MCML's ASCII layout and normalisations: RAT, A_l [-], A_z [1/cm],
 * Rd_r and Tt_r [1/cm^2] (annulus 2 pi (ir+0.5) dr^2), Rd_a and Tt_a [1/sr]
 * (2 pi sin((ia+0.5) da) da), values beyond the grid collected in the last
 * bin, and the two-dimensional arrays A_rz [1/cm^3] (volume 2 pi (ir+0.5)
 * dr^2 dz), Rd_ra and Tt_ra [1/(cm^2 sr)] (4 pi^2 dr^2 sin(da/2) (ir+0.5)
 * sin(2 (ia+0.5) da)) in MCML's order (r slowest), five values per line. */
#define _POSIX_C_SOURCE 200809L
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "optics_internal.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

typedef struct line_reader {
    const char *p;
    int lineno;
    char buf[4096];
    const char *name;
} line_reader;

/* Next data line (comment stripped, trimmed); NULL at the end. */
static const char *next_line(line_reader *lr) {
    while (*lr->p) {
        const char *s = lr->p;
        const char *e = strchr(s, '\n');
        size_t len = e ? (size_t)(e - s) : strlen(s);
        lr->p = e ? e + 1 : s + len;
        lr->lineno++;
        if (len >= sizeof lr->buf) len = sizeof lr->buf - 1;
        memcpy(lr->buf, s, len);
        lr->buf[len] = 0;
        char *h = strchr(lr->buf, '#');
        if (h) *h = 0;
        char *b = lr->buf;
        while (*b && isspace((unsigned char)*b)) b++;
        char *t = b + strlen(b);
        while (t > b && isspace((unsigned char)t[-1])) *--t = 0;
        if (*b) return b;
    }
    return NULL;
}

static ss_status perr(line_reader *lr, ss_error *err, const char *fmt, ...) {
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return ss_error_set(err, SS_ERR_INPUT, "%s: line %d: %s", lr->name, lr->lineno, msg);
}

/* Parses exactly n doubles from a data line. */
static ss_status read_doubles(line_reader *lr, const char *what, int n, double *v, ss_error *err) {
    const char *s = next_line(lr);
    if (!s) return perr(lr, err, "unexpected end of file, expected %s", what);
    const char *p = s;
    for (int i = 0; i < n; i++) {
        char *end;
        errno = 0;
        v[i] = strtod(p, &end);
        if (end == p || errno == ERANGE || !isfinite(v[i]))
            return perr(lr, err, "expected %s, got '%s'", what, s);
        p = end;
    }
    while (*p && isspace((unsigned char)*p)) p++;
    if (*p) return perr(lr, err, "expected %s, got extra text '%s'", what, p);
    return SS_OK;
}

static int is_int(double v, double lo, double hi) { return v == floor(v) && v >= lo && v <= hi; }

void ss_mci_file_free(ss_mci_file *f) {
    if (!f) return;
    free(f->runs);
    f->runs = NULL;
    f->nruns = 0;
}

ss_status ss_mci_parse(const char *text, const char *name, ss_mci_file *out, ss_error *err) {
    if (!out) return ss_error_set(err, SS_ERR_INPUT, "mci output is NULL");
    memset(out, 0, sizeof *out);
    if (!text) return ss_error_set(err, SS_ERR_INPUT, "%s: no text", name ? name : "mci");
    line_reader lr = {text, 0, {0}, name ? name : "mci"};
    double v[5];
    ss_status st;
    if ((st = read_doubles(&lr, "the file version (1.0)", 1, v, err))) return st;
    if (v[0] != 1.0) return perr(&lr, err, "unsupported file version %g (MCML uses 1.0)", v[0]);
    if ((st = read_doubles(&lr, "the number of runs", 1, v, err))) return st;
    if (!is_int(v[0], 1, 10000))
        return perr(&lr, err, "number of runs %g is not in 1..10000", v[0]);
    int nruns = (int)v[0];
    out->runs = calloc((size_t)nruns, sizeof *out->runs);
    if (!out->runs) return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    out->nruns = nruns;
    for (int r = 0; r < nruns; r++) {
        ss_mci_run *run = &out->runs[r];
        const char *s = next_line(&lr);
        if (!s) {
            ss_mci_file_free(out);
            return perr(&lr, err, "unexpected end of file, expected run %d's output file name",
                        r + 1);
        }
        char fname[1024], type[16] = "A";
        int k = sscanf(s, "%1023s %15s", fname, type);
        if (k < 1 || strlen(type) != 1 || (type[0] != 'A' && type[0] != 'a')) {
            ss_mci_file_free(out);
            return perr(&lr, err, "run %d: expected 'name.mco A' (ASCII output), got '%s'", r + 1,
                        s);
        }
        /* both the name and the type letter: a line "A" alone is a name left
         * out, not an output called A in the current folder (where the
         * output may go is the caller's rule, ss_path_under) */
        if (k < 2) {
            ss_mci_file_free(out);
            return perr(&lr, err,
                        "run %d: expected 'name.mco A' (output name and type), got only '%s'",
                        r + 1, s);
        }
        snprintf(run->out_name, sizeof run->out_name, "%s", fname);
        run->out_type = 'A';
        for (int q = 0; q < r; q++)
            if (!strcmp(out->runs[q].out_name, fname)) {
                ss_mci_file_free(out);
                return perr(&lr, err, "run %d writes '%s' like run %d", r + 1, fname, q + 1);
            }
#define FAIL(...)                                                                                  \
    do {                                                                                           \
        ss_mci_file_free(out);                                                                     \
        return perr(&lr, err, __VA_ARGS__);                                                        \
    } while (0)
#define READ(what, n)                                                                              \
    do {                                                                                           \
        if ((st = read_doubles(&lr, what, n, v, err))) {                                           \
            ss_mci_file_free(out);                                                                 \
            return st;                                                                             \
        }                                                                                          \
    } while (0)
        READ("the number of photons", 1);
        if (!is_int(v[0], 1, 1e12)) FAIL("run %d: photon count %g is not in 1..1e12", r + 1, v[0]);
        run->photons = (uint64_t)v[0];
        READ("dz dr [cm]", 2);
        if (!(v[0] > 0 && v[1] > 0)) FAIL("run %d: dz %g and dr %g must be > 0", r + 1, v[0], v[1]);
        run->dz_cm = v[0];
        run->dr_cm = v[1];
        READ("nz nr na", 3);
        if (!is_int(v[0], 1, 100000) || !is_int(v[1], 1, 100000) || !is_int(v[2], 1, 100000))
            FAIL("run %d: grid sizes nz %g nr %g na %g must be integers in 1..100000", r + 1, v[0],
                 v[1], v[2]);
        run->nz = (int)v[0];
        run->nr = (int)v[1];
        run->na = (int)v[2];
        /* the 2-D tallies (A_rz, Rd_ra, Tt_ra), bounded before anything is
         * allocated: a stated cap, and the memory they take (at least two
         * block copies and the total, 8 bytes a value, plus 13 characters a
         * value of .mco text) within what is available */
        double cells = v[1] * (v[0] + 2.0 * v[2]); /* (FAIL frees run: v[] in messages) */
        if (cells > SS_MCI_MAX_GRID_VALUES)
            FAIL("run %d: grid nz %d nr %d na %d holds %.0f values in its 2-D arrays (nr * (nz + "
                 "2 na)), above the limit of %d",
                 r + 1, (int)v[0], (int)v[1], (int)v[2], cells, SS_MCI_MAX_GRID_VALUES);
        double need = cells * (3 * 8.0 + 13.0), avail = ss_memory_available_bytes();
        if (avail > 0 && need > avail)
            FAIL("run %d: grid nz %d nr %d na %d needs %.2f GB, more than the %.2f GB of memory "
                 "available",
                 r + 1, (int)v[0], (int)v[1], (int)v[2], need / 1e9, avail / 1e9);
        READ("the number of layers", 1);
        if (!is_int(v[0], 1, SS_OPTICS_MAX_LAYERS))
            FAIL("run %d: number of layers %g is not in 1..%d", r + 1, v[0], SS_OPTICS_MAX_LAYERS);
        ss_optics_slab *sl = &run->slab;
        sl->nlayers = (int)v[0];
        sl->bottom_albedo = -1.0;
        READ("n for the medium above", 1);
        sl->n_above = v[0];
        for (int l = 0; l < sl->nlayers; l++) {
            READ("a layer: n mua mus g d", 5);
            sl->layer[l] = (ss_optics_layer){v[0], v[1], v[2], v[3], v[4], 0, {0}};
        }
        READ("n for the medium below", 1);
        sl->n_below = v[0];
        ss_error e2;
        if (ss_optics_slab_validate(sl, &e2)) FAIL("run %d: %s", r + 1, e2.msg);
#undef READ
#undef FAIL
    }
    return SS_OK;
}

/* growable text buffer */
typedef struct sbuf {
    char *s;
    size_t n, cap;
    int fail;
} sbuf;

static void sb_printf(sbuf *b, const char *fmt, ...) {
    if (b->fail) return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int k = vsnprintf(b->s ? b->s + b->n : NULL, b->s ? b->cap - b->n : 0, fmt, ap);
        va_end(ap);
        if (k < 0) {
            b->fail = 1;
            return;
        }
        if (b->s && b->n + (size_t)k < b->cap) {
            b->n += (size_t)k;
            return;
        }
        size_t nc = (b->cap ? b->cap * 2 : 65536) + (size_t)k;
        char *t = realloc(b->s, nc);
        if (!t) {
            b->fail = 1;
            return;
        }
        b->s = t;
        b->cap = nc;
    }
}

/* A 2-D MCML array: MCML's header lines, values row-major (first index
 * slowest) times scale[i][j] = 1 / (s1[i] s2[j]), "%12.4E " with a newline
 * after every fifth value, then a newline (MCML 1.2's WriteA_rz / WriteRd_ra). */
static void sb_array2(sbuf *b, const char *header, const double *raw, int n1, int n2,
                      const double *s1, const double *s2) {
    sb_printf(b, "%s", header);
    for (int i = 0; i < n1; i++)
        for (int j = 0; j < n2; j++) {
            sb_printf(b, "%12.4E ", raw[(size_t)i * n2 + j] / (s1[i] * s2[j]));
            if (((size_t)i * n2 + j + 1) % 5 == 0) sb_printf(b, "\n");
        }
    sb_printf(b, "\n");
}

static void sb_array(sbuf *b, const char *head, const char *fmt, const double *v, int n) {
    sb_printf(b, "%s\n", head);
    for (int i = 0; i < n; i++) sb_printf(b, fmt, v[i]);
    sb_printf(b, "\n");
}

ss_status ss_mci_simulate(const ss_mci_run *run, uint64_t seed, char **mco_text, ss_error *err) {
    if (!run || !mco_text) return ss_error_set(err, SS_ERR_INPUT, "mci run or output is NULL");
    *mco_text = NULL;
    ss_mc_options o;
    ss_mc_options_default(&o);
    o.photons = run->photons;
    o.seed = seed;
    o.kernel = run->kernel;
    ss_mc_tally_spec sp;
    memset(&sp, 0, sizeof sp);
    sp.mcml = 1;
    sp.rad_n = run->nr;
    sp.rad_dr = run->dr_cm;
    sp.dz = run->dz_cm;
    sp.nz = run->nz;
    sp.na = run->na;
    ss_mc_tallies t;
    double t0 = ss_now();
    ss_status st = ss_mc_run_tallies(&run->slab, &o, &sp, &t, err);
    if (st) return st;
    double secs = ss_now() - t0;
    double N = (double)run->photons;
    const ss_optics_slab *sl = &run->slab;
    double *tmp = malloc(sizeof(double) * (size_t)(run->nz + run->nr + run->na + 16));
    if (!tmp) {
        ss_mc_tallies_free(&t);
        return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    sbuf b = {0};
    sb_printf(&b, "A1 \t# Version number of the file format.\n\n"
                  "####\n# Data categories include: \n# InParm, RAT, \n"
                  "# A_l, A_z, Rd_r, Rd_a, Tt_r, Tt_a, \n"
                  "# A_rz, Rd_ra, Tt_ra \n####\n\n");
    sb_printf(&b, "# User time: %10.2f sec = %8.2f hr.  Simulation time of this run.\n\n", secs,
              secs / 3600.0);
    sb_printf(&b, "InParm \t\t\t# Input parameters. cm is used.\n");
    sb_printf(&b, "%s \tA\t\t# output file name, ASCII.\n", run->out_name);
    sb_printf(&b, "%llu \t\t\t# No. of photons\n", (unsigned long long)run->photons);
    sb_printf(&b, "%G\t%G\t\t# dz, dr [cm]\n", run->dz_cm, run->dr_cm);
    sb_printf(&b, "%d\t%d\t%d\t# No. of dz, dr, da.\n\n", run->nz, run->nr, run->na);
    sb_printf(&b, "%d\t\t\t\t\t# Number of layers\n", sl->nlayers);
    sb_printf(&b, "#n\tmua\tmus\tg\td\t# One line for each layer\n");
    sb_printf(&b, "%G\t\t\t\t\t# n for medium above\n", sl->n_above);
    for (int l = 0; l < sl->nlayers; l++)
        sb_printf(&b, "%G\t%G\t%G\t%G\t%G\t# layer %d\n", sl->layer[l].n, sl->layer[l].mua_per_cm,
                  sl->layer[l].mus_per_cm, sl->layer[l].g, sl->layer[l].d_cm, l + 1);
    sb_printf(&b, "%G\t\t\t\t\t# n for medium below\n\n", sl->n_below);
    sb_printf(&b, "RAT #Reflectance, absorption, transmission. \n");
    sb_printf(&b, "%-14.6G \t#Specular reflectance [-]\n", t.specular / N);
    sb_printf(&b, "%-14.6G \t#Diffuse reflectance [-]\n", t.diffuse / N);
    sb_printf(&b, "%-14.6G \t#Absorbed fraction [-]\n", t.absorbed / N);
    sb_printf(&b, "%-14.6G \t#Transmittance [-]\n\n", t.transmit / N);
    for (int l = 0; l < sl->nlayers; l++) tmp[l] = t.abs_layer[l] / N;
    sb_array(&b, "A_l #Absorption as a function of layer. [-]", "%12.4G\n", tmp, sl->nlayers);
    for (int i = 0; i < run->nz; i++) tmp[i] = t.a_z[i] / (run->dz_cm * N);
    sb_array(&b, "A_z #A[0], [1],..A[nz-1]. [1/cm]", "%12.4E\n", tmp, run->nz);
    double dr = run->dr_cm, da = M_PI / (2.0 * run->na);
    for (int i = 0; i < run->nr; i++) tmp[i] = t.rd_r[i] / (2.0 * M_PI * (i + 0.5) * dr * dr * N);
    sb_array(&b, "Rd_r #Rd[0], [1],..Rd[nr-1]. [1/cm2]", "%12.4E\n", tmp, run->nr);
    for (int i = 0; i < run->na; i++)
        tmp[i] = t.rd_a[i] / (2.0 * M_PI * sin((i + 0.5) * da) * da * N);
    sb_array(&b, "Rd_a #Rd[0], [1],..Rd[na-1]. [sr-1]", "%12.4E\n", tmp, run->na);
    for (int i = 0; i < run->nr; i++) tmp[i] = t.tt_r[i] / (2.0 * M_PI * (i + 0.5) * dr * dr * N);
    sb_array(&b, "Tt_r #Tt[0], [1],..Tt[nr-1]. [1/cm2]", "%12.4E\n", tmp, run->nr);
    for (int i = 0; i < run->na; i++)
        tmp[i] = t.tt_a[i] / (2.0 * M_PI * sin((i + 0.5) * da) * da * N);
    sb_array(&b, "Tt_a #Tt[0], [1],..Tt[na-1]. [sr-1]", "%12.4E\n", tmp, run->na);
    /* 2-D arrays with MCML's scalings: A_rz / (2 pi (ir+0.5) dr^2 dz N),
     * Rd_ra, Tt_ra / (4 pi^2 dr^2 sin(da/2) N (ir+0.5) sin(2 (ia+0.5) da)) */
    double *sr = malloc(sizeof(double) * (size_t)run->nr * 2);
    double *sz = malloc(sizeof(double) * (size_t)(run->nz + run->na));
    if (sr && sz) {
        double *sr2 = sr + run->nr, *sa = sz + run->nz;
        for (int i = 0; i < run->nr; i++) {
            sr[i] = 2.0 * M_PI * (i + 0.5) * dr * dr * run->dz_cm * N;
            sr2[i] = 4.0 * M_PI * M_PI * dr * dr * sin(da / 2.0) * N * (i + 0.5);
        }
        for (int i = 0; i < run->nz; i++) sz[i] = 1.0;
        for (int i = 0; i < run->na; i++) sa[i] = sin(2.0 * (i + 0.5) * da);
        sb_array2(&b,
                  "# A[r][z]. [1/cm3]\n# A[0][0], [0][1],..[0][nz-1]\n"
                  "# A[1][0], [1][1],..[1][nz-1]\n# ...\n"
                  "# A[nr-1][0], [nr-1][1],..[nr-1][nz-1]\nA_rz\n",
                  t.a_rz, run->nr, run->nz, sr, sz);
        sb_array2(&b,
                  "# Rd[r][angle]. [1/(cm2sr)].\n# Rd[0][0], [0][1],..[0][na-1]\n"
                  "# Rd[1][0], [1][1],..[1][na-1]\n# ...\n"
                  "# Rd[nr-1][0], [nr-1][1],..[nr-1][na-1]\nRd_ra\n",
                  t.rd_ra, run->nr, run->na, sr2, sa);
        sb_array2(&b,
                  "# Tt[r][angle]. [1/(cm2sr)].\n# Tt[0][0], [0][1],..[0][na-1]\n"
                  "# Tt[1][0], [1][1],..[1][na-1]\n# ...\n"
                  "# Tt[nr-1][0], [nr-1][1],..[nr-1][na-1]\nTt_ra\n",
                  t.tt_ra, run->nr, run->na, sr2, sa);
    } else
        b.fail = 1;
    free(sr);
    free(sz);
    free(tmp);
    ss_mc_tallies_free(&t);
    if (b.fail) {
        free(b.s);
        return ss_error_set(err, SS_ERR_NOMEM, "out of memory writing the MCML output");
    }
    *mco_text = b.s;
    return SS_OK;
}
