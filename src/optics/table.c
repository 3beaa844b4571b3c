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
    /* Plausible ranges (BioSpec / Jacques): melanosome fraction 0.3-43 %
     * (0.3 %: the very light end, ITA above 55 degrees), blood
     * 0.2-5 % of the dermis, SC 10-40 um, epidermis 40-150 um. */
    static const double r[SS_MM_NAXES][2] = {{0.003, 0.43}, {0.0, 1.0},     {0.002, 0.05},
                                             {0.5, 1.0},    {0.001, 0.004}, {0.004, 0.015}};
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

/* Fields interpolated in log space (colours: base colours, radius, albedo).
 * The weights along the blood axis are taken in sqrt(blood): blood absorbs
 * in the dermis, below the scattering epidermis, where diffuse reflectance
 * falls about as exp(-c sqrt(mu_a)) (diffusion theory), so log colour is
 * about linear in sqrt(blood); at 16 random off-grid points against the
 * transport this halved the worst error (dE00 2.0 -> 0.9, at blood 0.0046
 * between the nodes 0.002 and 0.01; docs/modelmatch.md). The other axes
 * weigh linearly (melanin and pheomelanin: Beer-Lambert through the
 * epidermis, log linear). Nodes are still returned exactly. */
static int field_is_colour(int f) { return (f >= 0 && f < 3) || (f >= 5 && f < 8) || f >= 12; }

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
        /* blood: the weight in sqrt(blood) (see the header) */
        if (a == SS_MM_AXIS_BLOOD && v[i] >= 0.0)
            fr[a] = (sqrt(xa) - sqrt(v[i])) / (sqrt(v[i + 1]) - sqrt(v[i]));
        else
            fr[a] = (xa - v[i]) / (v[i + 1] - v[i]);
    }
    double w[1 << SS_MM_NAXES];
    const double *e[1 << SS_MM_NAXES];
    int nc = 0;
    for (int corner = 0; corner < (1 << SS_MM_NAXES); corner++) {
        double wc = 1.0;
        int idx[SS_MM_NAXES];
        for (int a = 0; a < SS_MM_NAXES; a++) {
            int up = (corner >> a) & 1;
            if (t->nsamples[a] == 1 && up) {
                wc = 0.0;
                break;
            }
            wc *= up ? fr[a] : 1.0 - fr[a];
            idx[a] = i0[a] + up;
        }
        if (wc == 0.0) continue;
        w[nc] = wc;
        e[nc++] = t->entries + ss_mm_table_index(t, idx) * SS_MM_NFIELDS;
    }
    if (nc == 1) { /* on a node: its entry exactly */
        memcpy(out, e[0], SS_MM_NFIELDS * sizeof(double));
        return;
    }
    for (int f = 0; f < SS_MM_NFIELDS; f++) {
        int use_log = field_is_colour(f);
        for (int k = 0; k < nc && use_log; k++) use_log = e[k][f] > 0.0;
        double s = 0.0;
        if (use_log) {
            for (int k = 0; k < nc; k++) s += w[k] * log(e[k][f]);
            out[f] = exp(s);
        } else {
            for (int k = 0; k < nc; k++) s += w[k] * e[k][f];
            out[f] = s;
        }
    }
}

void ss_mm_surface_lobe(const ss_mm_table *t, double sigma, double *specular, double *roughness,
                        double *diffuse_scale) {
    const double e_spec = t->entries ? t->entries[3] : 0.5,
                 e_rough = t->entries ? t->entries[4] : 0.5;
    double sp = e_spec, ro = e_rough, sc = 1.0;
    if (t->nsurface >= 2) {
        const int n = t->nsurface;
        const double *v = t->surf_sigma;
        double s = sigma;
        if (!(s > v[0])) s = v[0];
        if (s > v[n - 1]) s = v[n - 1];
        int i = 0;
        while (i < n - 2 && s >= v[i + 1]) i++;
        double f = (s - v[i]) / (v[i + 1] - v[i]);
        sp = t->surf_specular[i] + f * (t->surf_specular[i + 1] - t->surf_specular[i]);
        ro = t->surf_roughness[i] + f * (t->surf_roughness[i + 1] - t->surf_roughness[i]);
        /* the scale at the two nodes, interpolated like the lobe */
        const double one_e0 = 1.0 - ss_render_ggx_spec_albedo(e_spec, e_rough, 1.0);
        const double s0 = one_e0 / (1.0 - ss_render_ggx_spec_albedo(t->surf_specular[i],
                                                                    t->surf_roughness[i], 1.0));
        const double s1 = one_e0 / (1.0 - ss_render_ggx_spec_albedo(t->surf_specular[i + 1],
                                                                    t->surf_roughness[i + 1], 1.0));
        sc = s0 + f * (s1 - s0);
    }
    if (specular) *specular = sp;
    if (roughness) *roughness = ro;
    if (diffuse_scale) *diffuse_scale = sc;
}

void ss_mm_table_lookup_many(const ss_mm_table *t, const double *x, size_t n, double *out) {
    long long m = (long long)n;
#pragma omp parallel for schedule(static)
    for (long long i = 0; i < m; i++)
        ss_mm_table_lookup(t, x + (size_t)i * SS_MM_NAXES, out + (size_t)i * SS_MM_NFIELDS);
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
    put_f64(&b, t->surface_sigma);
    put_u32(&b, (uint32_t)t->nsurface);
    for (int k = 0; k < t->nsurface; k++) {
        put_f64(&b, t->surf_sigma[k]);
        put_f64(&b, t->surf_specular[k]);
        put_f64(&b, t->surf_roughness[k]);
    }
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
    if (version != 1 && version != SS_MM_FILE_VERSION) {
        ss_error_set(err, SS_ERR_INPUT,
                     "%s: ModelMatch table version %u is not supported (this build reads "
                     "versions 1 and %d)",
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
    {
        /* the entry block must be present before anything is allocated for it */
        size_t need = 1;
        for (int a = 0; a < SS_MM_NAXES; a++) need *= (size_t)ns[a];
        if ((r.len - r.pos) / 8 / SS_MM_NFIELDS < need) goto trunc_free;
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
    if (version >= 2) {
        uint32_t ns2;
        if (!get_f64(&r, &t->surface_sigma) || !get_u32(&r, &ns2)) goto trunc_free;
        if (!(t->surface_sigma >= 0.0 && t->surface_sigma <= 10.0) || ns2 == 1 ||
            ns2 > SS_MM_MAX_SURFACE) {
            ss_error_set(err, SS_ERR_INPUT,
                         "%s: ModelMatch table surface curve is malformed (sigma %g, %u points)",
                         name, t->surface_sigma, ns2);
            goto fail;
        }
        t->nsurface = (int)ns2;
        for (int k = 0; k < t->nsurface; k++) {
            if (!get_f64(&r, &t->surf_sigma[k]) || !get_f64(&r, &t->surf_specular[k]) ||
                !get_f64(&r, &t->surf_roughness[k]))
                goto trunc_free;
            if (!isfinite(t->surf_sigma[k]) || !isfinite(t->surf_specular[k]) ||
                !isfinite(t->surf_roughness[k]) ||
                (k > 0 && !(t->surf_sigma[k] > t->surf_sigma[k - 1]))) {
                ss_error_set(err, SS_ERR_INPUT,
                             "%s: ModelMatch table surface curve is not finite and increasing",
                             name);
                goto fail;
            }
        }
    } else {
        t->surface_sigma = 0.75; /* version 1 tables were all built at BioSpec's default */
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
    char *buf = ss_read_file_max(path, &len, SS_READ_MAX_TABLE, err);
    if (!buf) return NULL;
    ss_mm_table *t = ss_mm_table_from_memory((const unsigned char *)buf, len, path, err);
    free(buf);
    return t;
}
ss_status ss_mm_table_lookup_bio(const ss_mm_table *t, const ss_bio_params *bio, ss_mm_entry *out,
                                 ss_error *err) {
    ss_status st = ss_bio_params_validate(bio, err);
    if (st) return st;
    double x[SS_MM_NAXES] = {bio->melanin,     bio->pheomelanin_ratio, bio->blood,
                             bio->oxygenation, bio->sc_thickness_cm,   bio->epidermis_thickness_cm};
    double v[SS_MM_NFIELDS];
    ss_mm_table_lookup(t, x, v);
    ss_mm_entry_unpack(v, out);
    return SS_OK;
}

/* ---- building: trace once per geometry, reweight per absorption set ------- */

#define MM_RADIAL_BINS 200
#define MM_RADIAL_MAX_CM 1.0

void ss_mm_build_options_default(ss_mm_build_options *o) {
    memset(o, 0, sizeof *o);
    ss_spectrum_options_default(&o->spectrum);
    o->spectrum.wl_min_nm = 400.0;
    o->spectrum.wl_max_nm = 700.0;
    o->spectrum.wl_step_nm = 20.0;
    o->spectrum.mc.photons = 10000;
    o->n_theta_i = 8;
    o->n_theta_r = 8;
    o->n_phi = 8;
    ss_fit_options_default(&o->fit);
    o->fit.base_mode = SS_FIT_BASE_ALBEDO; /* departure from the seed: docs/optics.md */
    ss_bio_params_default(&o->base);
    o->quiet = 1;
}

static ss_status check_build_options(const ss_mm_build_options *o, int *nwl, ss_error *err) {
    const ss_spectrum_options *s = &o->spectrum;
    if (!(s->wl_min_nm >= 300.0 && s->wl_max_nm <= 800.0 && s->wl_min_nm <= s->wl_max_nm &&
          s->wl_step_nm > 0.0 && (s->wl_max_nm - s->wl_min_nm) / s->wl_step_nm <= 1000.0))
        return ss_error_set(err, SS_ERR_INPUT,
                            "ModelMatch: wavelengths %g..%g nm step %g: need 300 <= min <= max <= "
                            "800 and at most 1001 samples",
                            s->wl_min_nm, s->wl_max_nm, s->wl_step_nm);
    if (o->n_theta_i < 1 || o->n_theta_i > 64 || o->n_theta_r < 1 || o->n_theta_r > 64 ||
        o->n_phi < 1 || o->n_phi > 64)
        return ss_error_set(err, SS_ERR_INPUT, "ModelMatch: BRDF bins %d x %d x %d (each 1..64)",
                            o->n_theta_i, o->n_theta_r, o->n_phi);
    if (s->mc.photons < 100 || s->mc.stochastic_absorb)
        return ss_error_set(err, SS_ERR_INPUT,
                            "ModelMatch: photons %llu (need >= 100, weighted transport)",
                            (unsigned long long)s->mc.photons);
    *nwl = (int)floor((s->wl_max_nm - s->wl_min_nm) / s->wl_step_nm + 1e-9) + 1;
    return SS_OK;
}

static int same_geometry(const ss_optics_slab *a, const ss_optics_slab *b) {
    if (a->nlayers != b->nlayers || a->n_above != b->n_above || a->n_below != b->n_below ||
        a->bottom_albedo != b->bottom_albedo)
        return 0;
    for (int l = 0; l < a->nlayers; l++)
        if (a->layer[l].n != b->layer[l].n || a->layer[l].mus_per_cm != b->layer[l].mus_per_cm ||
            a->layer[l].g != b->layer[l].g || a->layer[l].d_cm != b->layer[l].d_cm ||
            a->layer[l].phase_n != b->layer[l].phase_n ||
            memcmp(a->layer[l].phase_theta, b->layer[l].phase_theta,
                   sizeof a->layer[l].phase_theta))
            return 0;
    return 1;
}

/* Per absorption set results of one geometry. */
typedef struct mm_geo_out {
    double *f_rgb;  /* nsets * nti*ntr*nph*3 */
    double *radial; /* nsets * MM_RADIAL_BINS * 3 */
    double *albedo; /* nsets * 3 */
} mm_geo_out;

/* bios[0..nsets): parameter sets that share sc and epidermis thickness. */
static ss_status build_geometry(const ss_optics_data *data, const ss_bio_params *bios, int nsets,
                                const ss_mm_build_options *o, int nwl, const double *wl,
                                const double *W, mm_geo_out *out, ss_progress *prog,
                                double *prog_done, ss_error *err) {
    int nti = o->n_theta_i, ntr = o->n_theta_r, nph = o->n_phi;
    size_t nb = (size_t)ntr * nph, per = (size_t)nti * nb * 3;
    double *mua = malloc((size_t)nsets * SS_OPTICS_MAX_LAYERS * sizeof(double));
    if (!mua) return ss_error_set(err, SS_ERR_NOMEM, "ModelMatch: out of memory");
    ss_status st = SS_OK;
    for (int k = 0; k < nwl && !st; k++) {
        ss_optics_slab geo;
        if ((st = ss_optics_skin_slab_with(data, &bios[0], wl[k], &geo, err))) break;
        /* absorption of every set; the exactness of reweighting rests on the
         * sets differing only in mua, which is checked here */
        int bad = -1;
        ss_status pst = SS_OK;
        ss_error perr;
#pragma omp parallel for schedule(dynamic, 4)
        for (int a = 0; a < nsets; a++) {
            ss_optics_slab sa;
            ss_error e2;
            ss_status s2 = ss_optics_skin_slab_with(data, &bios[a], wl[k], &sa, &e2);
            if (s2 || !same_geometry(&sa, &geo)) {
#pragma omp critical(mm_geo_err)
                {
                    if (pst == SS_OK) {
                        pst = s2 ? s2 : SS_ERR_RUNTIME;
                        perr = e2;
                        bad = a;
                    }
                }
                continue;
            }
            for (int l = 0; l < geo.nlayers; l++)
                mua[(size_t)a * SS_OPTICS_MAX_LAYERS + l] = sa.layer[l].mua_per_cm;
        }
        if (pst) {
            if (pst == SS_ERR_RUNTIME)
                st = ss_error_set(err, SS_ERR_RUNTIME,
                                  "ModelMatch: parameter set %d changes more than absorption at "
                                  "%g nm; the reweighting fast path does not apply",
                                  bad, wl[k]);
            else {
                *err = perr;
                st = pst;
            }
            break;
        }
        /* nti incidence bins for the BRDF, plus normal incidence for the
         * albedo and the radial profile */
        for (int ti = 0; ti <= nti && !st; ti++) {
            ss_mc_options mc = o->spectrum.mc;
            mc.radial_bins = 0;
            mc.radial_max_cm = 0;
            mc.brdf_n_theta = mc.brdf_n_phi = 0;
            if (ti < nti) {
                mc.theta_i_rad = (ti + 0.5) * M_PI / (2.0 * nti);
                mc.brdf_n_theta = ntr;
                mc.brdf_n_phi = nph;
            } else {
                mc.theta_i_rad = 0.0;
                mc.radial_bins = MM_RADIAL_BINS;
                mc.radial_max_cm = MM_RADIAL_MAX_CM;
            }
            ss_mc_paths *paths = NULL;
            if ((st = ss_mc_trace_paths(&geo, &mc, &paths, err))) break;
            ss_status ast = SS_OK;
            ss_error aerr;
#pragma omp parallel for schedule(dynamic, 1)
            for (int a = 0; a < nsets; a++) {
                ss_mc_result r;
                ss_error e2;
                ss_status s2 =
                    ss_mc_paths_apply(paths, mua + (size_t)a * SS_OPTICS_MAX_LAYERS, &r, &e2);
                if (s2) {
#pragma omp critical(mm_apply_err)
                    {
                        if (ast == SS_OK) {
                            ast = s2;
                            aerr = e2;
                        }
                    }
                    continue;
                }
                const double *w = W + 3 * k;
                if (ti < nti) {
                    double *f = out->f_rgb + (size_t)a * per + (size_t)ti * nb * 3;
                    for (size_t b = 0; b < nb; b++)
                        for (int c = 0; c < 3; c++) f[b * 3 + c] += w[c] * r.brdf_exit[b];
                } else {
                    /* the radius is a mean distance: weighted by the spectral
                     * energy each channel sees (the positive part of its
                     * colour-matching weight), never by signed sRGB weights,
                     * whose negative lobes made it negative for dark skin */
                    double *rad = out->radial + (size_t)a * MM_RADIAL_BINS * 3;
                    for (int b = 0; b < MM_RADIAL_BINS; b++)
                        for (int c = 0; c < 3; c++)
                            rad[b * 3 + c] += (w[c] > 0.0 ? w[c] : 0.0) * r.radial[b];
                    for (int c = 0; c < 3; c++) out->albedo[(size_t)a * 3 + c] += w[c] * r.diffuse;
                }
                ss_mc_result_free(&r);
            }
            ss_mc_paths_free(paths);
            if (ast) {
                *err = aerr;
                st = ast;
            }
            if (prog) {
                *prog_done += 1.0;
                ss_progress_update(prog, *prog_done);
            }
        }
    }
    free(mua);
    return st;
}

void ss_mm_sss_radius(const double *rad, int bins, double max_cm, double out[3]) {
    double dr = max_cm / bins;
    for (int c = 0; c < 3; c++) {
        double num = 0, den = 0;
        for (int b = 0; b < bins; b++) {
            double r0 = b * dr, r1 = r0 + dr;
            double area = M_PI * (r1 * r1 - r0 * r0);
            double rc = 2.0 / 3.0 * (r1 * r1 * r1 - r0 * r0 * r0) / (r1 * r1 - r0 * r0);
            num += rad[b * 3 + c] * area * rc;
            den += rad[b * 3 + c] * area;
        }
        out[c] = den > 0 ? num / den : 0.0;
    }
}

void ss_mm_radial_albedo(const double *rad, int bins, double max_cm, double out[3]) {
    double dr = max_cm / bins;
    for (int c = 0; c < 3; c++) {
        double s = 0;
        for (int b = 0; b < bins; b++) {
            double r0 = b * dr, r1 = r0 + dr;
            s += rad[b * 3 + c] * M_PI * (r1 * r1 - r0 * r0);
        }
        out[c] = s;
    }
}

static void sss_radius(const double *rad, double out[3]) {
    ss_mm_sss_radius(rad, MM_RADIAL_BINS, MM_RADIAL_MAX_CM, out);
}

static ss_status colour_weights(const double *wl, int nwl, double *W, ss_error *err) {
    double *imp = calloc((size_t)nwl, sizeof(double));
    if (!imp) return ss_error_set(err, SS_ERR_NOMEM, "ModelMatch: out of memory");
    ss_status st = SS_OK;
    for (int k = 0; k < nwl && !st; k++) {
        imp[k] = 1.0;
        st = ss_spectrum_to_srgb_linear(wl, imp, nwl, W + 3 * k, err);
        imp[k] = 0.0;
    }
    free(imp);
    return st;
}

static ss_status alloc_geo_out(mm_geo_out *g, int nsets, const ss_mm_build_options *o,
                               ss_error *err) {
    size_t per = (size_t)o->n_theta_i * o->n_theta_r * o->n_phi * 3;
    g->f_rgb = calloc((size_t)nsets * per, sizeof(double));
    g->radial = calloc((size_t)nsets * MM_RADIAL_BINS * 3, sizeof(double));
    g->albedo = calloc((size_t)nsets * 3, sizeof(double));
    if (!g->f_rgb || !g->radial || !g->albedo) {
        free(g->f_rgb);
        free(g->radial);
        free(g->albedo);
        return ss_error_set(err, SS_ERR_NOMEM, "ModelMatch: out of memory");
    }
    return SS_OK;
}

static void free_geo_out(mm_geo_out *g) {
    free(g->f_rgb);
    free(g->radial);
    free(g->albedo);
}

static ss_status make_wavelengths(const ss_mm_build_options *o, int nwl, double **wl, double **W,
                                  ss_error *err) {
    *wl = malloc((size_t)nwl * sizeof(double));
    *W = malloc((size_t)nwl * 3 * sizeof(double));
    if (!*wl || !*W) {
        free(*wl);
        free(*W);
        return ss_error_set(err, SS_ERR_NOMEM, "ModelMatch: out of memory");
    }
    for (int k = 0; k < nwl; k++) (*wl)[k] = o->spectrum.wl_min_nm + k * o->spectrum.wl_step_nm;
    ss_status st = colour_weights(*wl, nwl, *W, err);
    if (st) {
        free(*wl);
        free(*W);
    }
    return st;
}

ss_status ss_mm_sample_fast(const ss_bio_params *bio, const ss_mm_build_options *o,
                            ss_brdf_sampled *out, double sss_radius_cm[3], double albedo_rgb[3],
                            ss_error *err) {
    memset(out, 0, sizeof *out);
    int nwl;
    ss_status st = check_build_options(o, &nwl, err);
    if (st) return st;
    if ((st = ss_bio_params_validate(bio, err))) return st;
    double *wl, *W;
    if ((st = make_wavelengths(o, nwl, &wl, &W, err))) return st;
    mm_geo_out g;
    if ((st = alloc_geo_out(&g, 1, o, err))) {
        free(wl);
        free(W);
        return st;
    }
    double done = 0;
    ss_optics_data *data = NULL;
    st = ss_optics_data_open(&data, err);
    if (!st) st = build_geometry(data, bio, 1, o, nwl, wl, W, &g, NULL, &done, err);
    ss_optics_data_close(data);
    if (!st) {
        out->n_theta_i = o->n_theta_i;
        out->n_theta_r = o->n_theta_r;
        out->n_phi = o->n_phi;
        out->f_rgb = g.f_rgb;
        g.f_rgb = NULL;
        if (sss_radius_cm) sss_radius(g.radial, sss_radius_cm);
        if (albedo_rgb)
            for (int c = 0; c < 3; c++) albedo_rgb[c] = g.albedo[c];
    }
    free_geo_out(&g);
    free(wl);
    free(W);
    return st;
}

void ss_mm_table_record_options(ss_mm_table *t, const ss_mm_build_options *o) {
    t->surface_sigma = o->spectrum.mc.roughness_sigma;
    t->photons = o->spectrum.mc.photons;
    t->seed = o->spectrum.mc.seed;
    t->n_theta_i = o->n_theta_i;
    t->n_theta_r = o->n_theta_r;
    t->n_phi = o->n_phi;
    t->wl_min_nm = o->spectrum.wl_min_nm;
    t->wl_max_nm = o->spectrum.wl_max_nm;
    t->wl_step_nm = o->spectrum.wl_step_nm;
}

int ss_mm_table_ngeometries(const ss_mm_table *t) {
    return t->nsamples[SS_MM_AXIS_SC] * t->nsamples[SS_MM_AXIS_EPIDERMIS];
}

static ss_status build_range(ss_mm_table *t, const ss_mm_build_options *o, int g0, int g1,
                             ss_error *err);

ss_status ss_mm_table_build(ss_mm_table *t, const ss_mm_build_options *o, ss_error *err) {
    ss_status st = build_range(t, o, 0, ss_mm_table_ngeometries(t), err);
    if (!st)
        st = ss_mm_table_build_surface(t, o, SS_MM_SURFACE_N, SS_MM_SURFACE_LO, SS_MM_SURFACE_HI,
                                       err);
    return st;
}

ss_status ss_mm_table_build_surface(ss_mm_table *t, const ss_mm_build_options *o, int nsurface,
                                    double sigma_lo, double sigma_hi, ss_error *err) {
    int nwl;
    ss_status st = check_build_options(o, &nwl, err);
    if (st) return st;
    if (nsurface < 2 || nsurface > SS_MM_MAX_SURFACE || !(sigma_lo > 0.0) ||
        !(sigma_hi > sigma_lo) || sigma_hi > 2.0)
        return ss_error_set(err, SS_ERR_INPUT,
                            "ModelMatch surface curve: %d sigmas over %g..%g (need 2..%d, 0 < lo "
                            "< hi <= 2)",
                            nsurface, sigma_lo, sigma_hi, SS_MM_MAX_SURFACE);
    ss_status fst = SS_OK;
    ss_error ferr;
    double sp[SS_MM_MAX_SURFACE], ro[SS_MM_MAX_SURFACE];
    /* each sigma: the surface-reflected BRDF alone (air over the stratum
     * corneum, nothing from below), the GGX lobe fitted to it as the
     * entries' lobe is (base colour 0) */
#pragma omp parallel for schedule(dynamic, 1)
    for (int k = 0; k < nsurface; k++) {
        ss_spectrum_options so = o->spectrum;
        so.mc.roughness_sigma = sigma_lo + (sigma_hi - sigma_lo) * k / (nsurface - 1);
        /* ten times the entries' packets: one grey trace per incidence bin
         * is cheap, and the lobe's strength is a small signal */
        so.mc.photons = o->spectrum.mc.photons * 10;
        ss_brdf_sampled surf = {0, 0, 0, NULL};
        ss_error e2;
        ss_status s2 =
            ss_optics_surface_brdf_sample(&so, o->n_theta_i, o->n_theta_r, o->n_phi, &surf, &e2);
        ss_fit_result fr;
        if (!s2) {
            ss_fit_options fo = o->fit;
            fo.base_mode = SS_FIT_BASE_ALBEDO;
            fo.albedo_rgb[0] = fo.albedo_rgb[1] = fo.albedo_rgb[2] = 0.0;
            fo.surface = &surf;
            s2 = ss_render_fit(SS_RENDER_GGX, &surf, &fo, &fr, &e2);
        }
        ss_brdf_sampled_free(&surf);
        if (s2) {
#pragma omp critical(mm_surf_err)
            {
                if (fst == SS_OK) {
                    fst = s2;
                    ferr = e2;
                }
            }
            continue;
        }
        sp[k] = fr.params.specular;
        ro[k] = fr.params.roughness;
    }
    if (fst) {
        *err = ferr;
        return fst;
    }
    t->surface_sigma = o->spectrum.mc.roughness_sigma;
    t->nsurface = nsurface;
    for (int k = 0; k < nsurface; k++) {
        t->surf_sigma[k] = sigma_lo + (sigma_hi - sigma_lo) * k / (nsurface - 1);
        t->surf_specular[k] = sp[k];
        t->surf_roughness[k] = ro[k];
    }
    return SS_OK;
}

ss_status ss_mm_table_build_geometry(ss_mm_table *t, const ss_mm_build_options *o, int gi,
                                     ss_error *err) {
    if (gi < 0 || gi >= ss_mm_table_ngeometries(t))
        return ss_error_set(err, SS_ERR_INPUT, "ModelMatch: geometry %d is not in 0..%d", gi,
                            ss_mm_table_ngeometries(t) - 1);
    return build_range(t, o, gi, gi + 1, err);
}

ss_status ss_mm_table_build_check(const ss_mm_table *t, const ss_mm_build_options *o,
                                  ss_error *err) {
    int nwl;
    ss_status st = check_build_options(o, &nwl, err);
    if (st) return st;
    for (int a = 0; a < SS_MM_NAXES; a++)
        for (int k = 0; k < t->nsamples[a]; k++) {
            double v = t->axis[a][k];
            int thick = a >= SS_MM_AXIS_SC;
            if (!(v >= 0.0 && v <= 1.0) || (thick && !(v > 0.0)))
                return ss_error_set(err, SS_ERR_INPUT, "ModelMatch: axis %s value %g is outside %s",
                                    axis_names[a], v, thick ? "(0, 1] cm" : "[0, 1]");
        }
    return SS_OK;
}

static ss_status build_range(ss_mm_table *t, const ss_mm_build_options *o, int g0, int g1,
                             ss_error *err) {
    int nwl;
    ss_status st = ss_mm_table_build_check(t, o, err); /* options, and every node valid */
    if (st || (st = check_build_options(o, &nwl, err))) return st;
    double *wl, *W;
    if ((st = make_wavelengths(o, nwl, &wl, &W, err))) return st;
    int nabs = t->nsamples[0] * t->nsamples[1] * t->nsamples[2] * t->nsamples[3];
    ss_bio_params *bios = malloc((size_t)nabs * sizeof *bios);
    mm_geo_out g = {0};
    if (!bios || (st = alloc_geo_out(&g, nabs, o, err))) {
        free(bios);
        free(wl);
        free(W);
        return st ? st : ss_error_set(err, SS_ERR_NOMEM, "ModelMatch: out of memory");
    }
    ss_optics_data *data = NULL;
    ss_brdf_sampled surf = {0, 0, 0, NULL}; /* surface part, the same for every entry */
    if ((st = ss_optics_data_open(&data, err)) ||
        (o->fit.base_mode == SS_FIT_BASE_ALBEDO && !o->fit.surface &&
         (st = ss_optics_surface_brdf_sample(&o->spectrum, o->n_theta_i, o->n_theta_r, o->n_phi,
                                             &surf, err)))) {
        ss_optics_data_close(data);
        free_geo_out(&g);
        free(bios);
        free(wl);
        free(W);
        return st;
    }
    ss_progress prog;
    ss_progress_begin(&prog, "ModelMatch table", (double)(g1 - g0) * nwl * (o->n_theta_i + 1),
                      o->quiet);
    double done = 0;
    size_t per = (size_t)o->n_theta_i * o->n_theta_r * o->n_phi * 3;
    for (int gi = g0; gi < g1 && !st; gi++) {
        int isc = gi / t->nsamples[5], iep = gi % t->nsamples[5];
        for (int a = 0; a < nabs; a++) {
            int r = a;
            int idx[4];
            for (int ax = 3; ax >= 0; ax--) {
                idx[ax] = r % t->nsamples[ax];
                r /= t->nsamples[ax];
            }
            ss_bio_params b = o->base;
            b.melanin = t->axis[0][idx[0]];
            b.pheomelanin_ratio = t->axis[1][idx[1]];
            b.blood = t->axis[2][idx[2]];
            b.oxygenation = t->axis[3][idx[3]];
            b.sc_thickness_cm = t->axis[4][isc];
            b.epidermis_thickness_cm = t->axis[5][iep];
            bios[a] = b;
        }
        memset(g.f_rgb, 0, (size_t)nabs * per * sizeof(double));
        memset(g.radial, 0, (size_t)nabs * MM_RADIAL_BINS * 3 * sizeof(double));
        memset(g.albedo, 0, (size_t)nabs * 3 * sizeof(double));
        st = build_geometry(data, bios, nabs, o, nwl, wl, W, &g, &prog, &done, err);
        if (st) break;
        /* fit both render models to every absorption set of this geometry */
        ss_status fst = SS_OK;
        ss_error ferr;
#pragma omp parallel for schedule(dynamic, 1)
        for (int a = 0; a < nabs; a++) {
            ss_brdf_sampled s = {o->n_theta_i, o->n_theta_r, o->n_phi, g.f_rgb + (size_t)a * per};
            ss_mm_entry e;
            memset(&e, 0, sizeof e);
            ss_error e2;
            ss_fit_options fo = o->fit;
            for (int c = 0; c < 3; c++) fo.albedo_rgb[c] = g.albedo[(size_t)a * 3 + c];
            for (int m = 0; m < SS_RENDER_NMODELS; m++) {
                ss_fit_result fr;
                /* the GGX lobe models the surface reflection; the Ashikhmin-
                 * Shirley lobe cannot (its best fit to it is no lobe) and is
                 * fitted to the whole BRDF (docs/optics.md) */
                if (surf.f_rgb) fo.surface = m == SS_RENDER_GGX ? &surf : NULL;
                ss_status s2 = ss_render_fit((ss_render_model)m, &s, &fo, &fr, &e2);
                if (s2) {
#pragma omp critical(mm_fit_err)
                    {
                        if (fst == SS_OK) {
                            fst = s2;
                            ferr = e2;
                        }
                    }
                    break;
                }
                e.fit[m] = fr.params;
                e.residual_rel[m] = fr.residual_rel;
            }
            sss_radius(g.radial + (size_t)a * MM_RADIAL_BINS * 3, e.sss_radius_cm);
            for (int c = 0; c < 3; c++) e.albedo_rgb[c] = g.albedo[(size_t)a * 3 + c];
            int r = a, idx[SS_MM_NAXES];
            for (int ax = 3; ax >= 0; ax--) {
                idx[ax] = r % t->nsamples[ax];
                r /= t->nsamples[ax];
            }
            idx[4] = isc;
            idx[5] = iep;
            ss_mm_entry_pack(&e, t->entries + ss_mm_table_index(t, idx) * SS_MM_NFIELDS);
        }
        if (fst) {
            *err = ferr;
            st = fst;
        }
    }
    ss_progress_end(&prog);
    ss_optics_data_close(data);
    ss_brdf_sampled_free(&surf);
    if (!st) ss_mm_table_record_options(t, o);
    free_geo_out(&g);
    free(bios);
    free(wl);
    free(W);
    return st;
}
