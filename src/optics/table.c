/* The ModelMatch table (seed 003 §4.8.6): a hypercube over the six optical
 * biological parameters of §5.2, each entry the fitted render parameters;
 * multilinear lookup over the 2^6 surrounding nodes; a versioned
 * little-endian binary file with a CRC-32 (layout in docs/modelmatch.md).
 * The build reuses transport across entries: photon paths are traced once per
 * geometry (stratum corneum x epidermis thickness, wavelength, incidence bin)
 * with absorption off, and every absorption set (melanin, pheomelanin, blood,
 * oxygenation change only mu_a) is applied by exact reweighting. */
#include "skinsim/optics_fit.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static const char *axis_names[SS_MM_NAXES] = {"melanin",     "pheomelanin", "blood",
                                              "oxygenation", "sc",          "epidermis"};

const char *ss_mm_axis_name(int axis) {
    return axis >= 0 && axis < SS_MM_NAXES ? axis_names[axis] : "?";
}

void ss_mm_axis_default_range(int axis, double *lo, double *hi) {
    /* Plausible ranges (BioSpec / Jacques): melanosome fraction 1-43 %, blood
     * 0.2-5 % of the dermis, SC 10-40 um, epidermis 40-150 um. */
    static const double r[SS_MM_NAXES][2] = {{0.01, 0.43}, {0.0, 1.0},     {0.002, 0.05},
                                             {0.5, 1.0},   {0.001, 0.004}, {0.004, 0.015}};
    *lo = r[axis][0];
    *hi = r[axis][1];
}

void ss_mm_entry_pack(const ss_mm_entry *e, double v[SS_MM_NFIELDS]) {
    for (int m = 0; m < SS_RENDER_NMODELS; m++) {
        for (int c = 0; c < 3; c++) v[m * 5 + c] = e->fit[m].base_rgb[c];
        v[m * 5 + 3] = e->fit[m].specular;
        v[m * 5 + 4] = e->fit[m].roughness;
        v[10 + m] = e->residual_rel[m];
    }
    for (int c = 0; c < 3; c++) {
        v[12 + c] = e->sss_radius_cm[c];
        v[15 + c] = e->albedo_rgb[c];
    }
}

void ss_mm_entry_unpack(const double v[SS_MM_NFIELDS], ss_mm_entry *e) {
    for (int m = 0; m < SS_RENDER_NMODELS; m++) {
        for (int c = 0; c < 3; c++) e->fit[m].base_rgb[c] = v[m * 5 + c];
        e->fit[m].specular = v[m * 5 + 3];
        e->fit[m].roughness = v[m * 5 + 4];
        e->residual_rel[m] = v[10 + m];
    }
    for (int c = 0; c < 3; c++) {
        e->sss_radius_cm[c] = v[12 + c];
        e->albedo_rgb[c] = v[15 + c];
    }
}

/* ---- creation ------------------------------------------------------------ */

#define MM_MAX_SAMPLES 64
#define MM_MAX_ENTRIES 50000000u

static ss_mm_table *table_alloc(const int nsamples[SS_MM_NAXES], ss_error *err) {
    size_t n = 1;
    for (int a = 0; a < SS_MM_NAXES; a++) {
        if (nsamples[a] < 1 || nsamples[a] > MM_MAX_SAMPLES) {
            ss_error_set(err, SS_ERR_INPUT, "ModelMatch table: axis %s has %d samples (1..%d)",
                         axis_names[a], nsamples[a], MM_MAX_SAMPLES);
            return NULL;
        }
        n *= (size_t)nsamples[a];
        if (n > MM_MAX_ENTRIES) {
            ss_error_set(err, SS_ERR_INPUT, "ModelMatch table: more than %u entries",
                         MM_MAX_ENTRIES);
            return NULL;
        }
    }
    ss_mm_table *t = calloc(1, sizeof *t);
    if (!t) goto nomem;
    t->nentries = n;
    for (int a = 0; a < SS_MM_NAXES; a++) {
        t->nsamples[a] = nsamples[a];
        t->axis[a] = calloc((size_t)nsamples[a], sizeof(double));
        if (!t->axis[a]) goto nomem;
    }
    t->entries = calloc(n * SS_MM_NFIELDS, sizeof(double));
    if (!t->entries) goto nomem;
    return t;
nomem:
    ss_mm_table_free(t);
    ss_error_set(err, SS_ERR_NOMEM, "ModelMatch table: out of memory");
    return NULL;
}

ss_mm_table *ss_mm_table_create(const int nsamples[SS_MM_NAXES], const double lo[SS_MM_NAXES],
                                const double hi[SS_MM_NAXES], ss_error *err) {
    for (int a = 0; a < SS_MM_NAXES; a++)
        if (!isfinite(lo[a]) || !isfinite(hi[a]) || (nsamples[a] > 1 && !(hi[a] > lo[a]))) {
            ss_error_set(err, SS_ERR_INPUT, "ModelMatch table: axis %s range [%g, %g] is empty",
                         axis_names[a], lo[a], hi[a]);
            return NULL;
        }
    ss_mm_table *t = table_alloc(nsamples, err);
    if (!t) return NULL;
    for (int a = 0; a < SS_MM_NAXES; a++)
        for (int k = 0; k < nsamples[a]; k++)
            t->axis[a][k] = nsamples[a] == 1 ? lo[a]
                            : k == nsamples[a] - 1
                                ? hi[a]
                                : lo[a] + (hi[a] - lo[a]) * k / (nsamples[a] - 1);
    return t;
}

void ss_mm_table_free(ss_mm_table *t) {
    if (!t) return;
    for (int a = 0; a < SS_MM_NAXES; a++) free(t->axis[a]);
    free(t->entries);
    free(t);
}

size_t ss_mm_table_index(const ss_mm_table *t, const int idx[SS_MM_NAXES]) {
    size_t k = 0;
    for (int a = 0; a < SS_MM_NAXES; a++) k = k * (size_t)t->nsamples[a] + (size_t)idx[a];
    return k;
}

/* ---- lookup -------------------------------------------------------------- */

void ss_mm_table_lookup(const ss_mm_table *t, const double x[SS_MM_NAXES],
                        double out[SS_MM_NFIELDS]) {
    int i0[SS_MM_NAXES];
    double fr[SS_MM_NAXES];
    for (int a = 0; a < SS_MM_NAXES; a++) {
        int n = t->nsamples[a];
        const double *v = t->axis[a];
        i0[a] = 0;
        fr[a] = 0.0;
        if (n == 1) continue;
        double xa = x[a];
        if (!(xa > v[0])) xa = v[0]; /* also catches NaN */
        if (xa > v[n - 1]) xa = v[n - 1];
        int i = 0;
        while (i < n - 2 && xa >= v[i + 1]) i++;
        i0[a] = i;
        fr[a] = (xa - v[i]) / (v[i + 1] - v[i]);
    }
    for (int f = 0; f < SS_MM_NFIELDS; f++) out[f] = 0.0;
    for (int corner = 0; corner < (1 << SS_MM_NAXES); corner++) {
        double w = 1.0;
        int idx[SS_MM_NAXES];
        for (int a = 0; a < SS_MM_NAXES; a++) {
            int up = (corner >> a) & 1;
            if (t->nsamples[a] == 1 && up) {
                w = 0.0;
                break;
            }
            w *= up ? fr[a] : 1.0 - fr[a];
            idx[a] = i0[a] + up;
        }
        if (w == 0.0) continue;
        const double *e = t->entries + ss_mm_table_index(t, idx) * SS_MM_NFIELDS;
        for (int f = 0; f < SS_MM_NFIELDS; f++) out[f] += w * e[f];
    }
}

/* ---- file ---------------------------------------------------------------- */

static const unsigned char mm_magic[8] = {'S', 'S', 'M', 'M', 'T', 'A', 'B', '\n'};

typedef struct wbuf {
    unsigned char *p;
    size_t len, cap;
    int fail;
} wbuf;

static void put_bytes(wbuf *b, const void *src, size_t n) {
    if (b->fail) return;
    if (b->len + n > b->cap) {
        size_t cap = b->cap ? b->cap * 2 : 4096;
        while (cap < b->len + n) cap *= 2;
        unsigned char *q = realloc(b->p, cap);
        if (!q) {
            b->fail = 1;
            return;
        }
        b->p = q;
        b->cap = cap;
    }
    memcpy(b->p + b->len, src, n);
    b->len += n;
}
static void put_u32(wbuf *b, uint32_t v) {
    unsigned char c[4];
    for (int i = 0; i < 4; i++) c[i] = (unsigned char)(v >> (8 * i));
    put_bytes(b, c, 4);
}
static void put_u64(wbuf *b, uint64_t v) {
    unsigned char c[8];
    for (int i = 0; i < 8; i++) c[i] = (unsigned char)(v >> (8 * i));
    put_bytes(b, c, 8);
}
static void put_f64(wbuf *b, double d) {
    uint64_t v;
    memcpy(&v, &d, 8);
    put_u64(b, v);
}

ss_status ss_mm_table_write(const char *path, const ss_mm_table *t, ss_error *err) {
    wbuf b = {0};
    put_bytes(&b, mm_magic, 8);
    put_u32(&b, SS_MM_FILE_VERSION);
    put_u32(&b, SS_MM_NAXES);
    put_u32(&b, SS_MM_NFIELDS);
    put_u32(&b, (uint32_t)t->n_theta_i);
    put_u32(&b, (uint32_t)t->n_theta_r);
    put_u32(&b, (uint32_t)t->n_phi);
    put_u64(&b, t->photons);
    put_u64(&b, t->seed);
    put_f64(&b, t->wl_min_nm);
    put_f64(&b, t->wl_max_nm);
    put_f64(&b, t->wl_step_nm);
    for (int a = 0; a < SS_MM_NAXES; a++) {
        put_u32(&b, (uint32_t)a);
        put_u32(&b, (uint32_t)t->nsamples[a]);
        for (int k = 0; k < t->nsamples[a]; k++) put_f64(&b, t->axis[a][k]);
    }
    for (size_t i = 0; i < t->nentries * SS_MM_NFIELDS; i++) put_f64(&b, t->entries[i]);
    uLong crc = crc32(0L, Z_NULL, 0);
    if (!b.fail) crc = crc32(crc, b.p, (uInt)b.len);
    put_u32(&b, (uint32_t)crc);
    if (b.fail) {
        free(b.p);
        return ss_error_set(err, SS_ERR_NOMEM, "ModelMatch table: out of memory");
    }
    ss_status st = ss_write_file_atomic(path, b.p, b.len, err);
    free(b.p);
    return st;
}

typedef struct rbuf {
    const unsigned char *p;
    size_t len, pos;
} rbuf;

static int get_u32(rbuf *r, uint32_t *v) {
    if (r->len - r->pos < 4) return 0;
    *v = 0;
    for (int i = 0; i < 4; i++) *v |= (uint32_t)r->p[r->pos + i] << (8 * i);
    r->pos += 4;
    return 1;
}
static int get_u64(rbuf *r, uint64_t *v) {
    if (r->len - r->pos < 8) return 0;
    *v = 0;
    for (int i = 0; i < 8; i++) *v |= (uint64_t)r->p[r->pos + i] << (8 * i);
    r->pos += 8;
    return 1;
}
static int get_f64(rbuf *r, double *d) {
    uint64_t v;
    if (!get_u64(r, &v)) return 0;
    memcpy(d, &v, 8);
    return 1;
}

ss_mm_table *ss_mm_table_from_memory(const unsigned char *buf, size_t len, const char *name,
                                     ss_error *err) {
    rbuf r = {buf, len, 0};
    uint32_t version, naxes, nfields, nti, ntr, nph;
    if (len < 8 || memcmp(buf, mm_magic, 8) != 0) {
        ss_error_set(err, SS_ERR_INPUT, "%s: not a skinsim ModelMatch table (bad magic)", name);
        return NULL;
    }
    r.pos = 8;
    if (!get_u32(&r, &version)) goto truncated;
    if (version != SS_MM_FILE_VERSION) {
        ss_error_set(err, SS_ERR_INPUT,
                     "%s: ModelMatch table version %u is not supported (this build reads "
                     "version %d)",
                     name, version, SS_MM_FILE_VERSION);
        return NULL;
    }
    /* The CRC covers everything before the last 4 bytes: check it first so a
     * corrupt file is reported as such, not as whatever field broke. */
    if (len < 12 + 4) goto truncated;
    {
        rbuf tail = {buf, len, len - 4};
        uint32_t stored;
        get_u32(&tail, &stored);
        uLong crc = crc32(crc32(0L, Z_NULL, 0), buf, (uInt)(len - 4));
        if ((uint32_t)crc != stored) {
            ss_error_set(err, SS_ERR_INPUT,
                         "%s: ModelMatch table checksum mismatch (file truncated or corrupt)",
                         name);
            return NULL;
        }
    }
    r.len = len - 4;
    if (!get_u32(&r, &naxes) || !get_u32(&r, &nfields)) goto truncated;
    if (naxes != SS_MM_NAXES || nfields != SS_MM_NFIELDS) {
        ss_error_set(err, SS_ERR_INPUT,
                     "%s: ModelMatch table has %u axes and %u fields (expected %d and %d)", name,
                     naxes, nfields, SS_MM_NAXES, SS_MM_NFIELDS);
        return NULL;
    }
    uint64_t photons, seed;
    double wl[3];
    if (!get_u32(&r, &nti) || !get_u32(&r, &ntr) || !get_u32(&r, &nph) || !get_u64(&r, &photons) ||
        !get_u64(&r, &seed) || !get_f64(&r, &wl[0]) || !get_f64(&r, &wl[1]) || !get_f64(&r, &wl[2]))
        goto truncated;
    int ns[SS_MM_NAXES];
    double *vals[SS_MM_NAXES] = {0};
    ss_mm_table *t = NULL;
    for (int a = 0; a < SS_MM_NAXES; a++) {
        uint32_t id, n;
        if (!get_u32(&r, &id) || !get_u32(&r, &n)) goto trunc_free;
        if (id != (uint32_t)a || n < 1 || n > MM_MAX_SAMPLES) {
            ss_error_set(err, SS_ERR_INPUT,
                         "%s: ModelMatch table axis %d is malformed (id %u, %u samples)", name, a,
                         id, n);
            goto fail;
        }
        ns[a] = (int)n;
        vals[a] = malloc(n * sizeof(double));
        if (!vals[a]) {
            ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", name);
            goto fail;
        }
        for (uint32_t k = 0; k < n; k++) {
            if (!get_f64(&r, &vals[a][k])) goto trunc_free;
            if (!isfinite(vals[a][k]) || (k > 0 && !(vals[a][k] > vals[a][k - 1]))) {
                ss_error_set(err, SS_ERR_INPUT,
                             "%s: ModelMatch table axis %s values are not finite and increasing",
                             name, axis_names[a]);
                goto fail;
            }
        }
    }
    t = table_alloc(ns, err);
    if (!t) goto fail;
    for (int a = 0; a < SS_MM_NAXES; a++)
        memcpy(t->axis[a], vals[a], (size_t)ns[a] * sizeof(double));
    if ((r.len - r.pos) / 8 < t->nentries * SS_MM_NFIELDS) goto trunc_free;
    for (size_t i = 0; i < t->nentries * SS_MM_NFIELDS; i++) {
        get_f64(&r, &t->entries[i]);
        if (!isfinite(t->entries[i])) {
            ss_error_set(err, SS_ERR_INPUT, "%s: ModelMatch table entry value %zu is not finite",
                         name, i);
            goto fail;
        }
    }
    if (r.pos != r.len) {
        ss_error_set(err, SS_ERR_INPUT, "%s: ModelMatch table has %zu unexpected trailing bytes",
                     name, r.len - r.pos);
        goto fail;
    }
    t->n_theta_i = (int)nti;
    t->n_theta_r = (int)ntr;
    t->n_phi = (int)nph;
    t->photons = photons;
    t->seed = seed;
    t->wl_min_nm = wl[0];
    t->wl_max_nm = wl[1];
    t->wl_step_nm = wl[2];
    for (int a = 0; a < SS_MM_NAXES; a++) free(vals[a]);
    return t;
trunc_free:
    ss_error_set(err, SS_ERR_INPUT, "%s: ModelMatch table is truncated", name);
fail:
    for (int a = 0; a < SS_MM_NAXES; a++) free(vals[a]);
    ss_mm_table_free(t);
    return NULL;
truncated:
    ss_error_set(err, SS_ERR_INPUT, "%s: ModelMatch table is truncated", name);
    return NULL;
}

ss_mm_table *ss_mm_table_read(const char *path, ss_error *err) {
    size_t len = 0;
    char *buf = ss_read_file(path, &len, err);
    if (!buf) return NULL;
    ss_mm_table *t = ss_mm_table_from_memory((const unsigned char *)buf, len, path, err);
    free(buf);
    return t;
}
