/* VTK XML ImageData export of the healing grid (seed 001 §5.4: the simulated
 * fields, here handed to ParaView instead of a shader): one .vti per snapshot
 * with the cell state (UInt8) and every species field (Float32) as cell data,
 * appended raw binary with UInt64 block headers, and a .pvd collection that
 * gives ParaView a time slider in days. Written atomically. A keloid grid's
 * added volume (g->added, docs/heal-model.md [D16]) is one more Float32 cell
 * array, keloid_added, so a snapshot read back has the full state and its
 * surface elevation equals the run's (skinsim wound --heal). */
#define _POSIX_C_SOURCE 200809L
#include "skinsim/heal_io.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

static int little_endian(void) {
    static const uint32_t one = 1;
    return *(const unsigned char *)&one == 1;
}

static void put_u64le(FILE *f, uint64_t v) {
    unsigned char b[8];
    for (int i = 0; i < 8; i++) b[i] = (unsigned char)(v >> (8 * i));
    fwrite(b, 1, 8, f);
}

static void put_f32le(FILE *f, const float *a, size_t n) {
    if (little_endian()) {
        fwrite(a, sizeof(float), n, f);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        uint32_t v;
        unsigned char b[4];
        memcpy(&v, &a[i], 4);
        for (int k = 0; k < 4; k++) b[k] = (unsigned char)(v >> (8 * k));
        fwrite(b, 1, 4, f);
    }
}

/* Swaps a written file in, or drops it after a write error. */
static ss_status commit(ss_atomic_file *af, const char *path, ss_error *err) {
    if (ferror(af->fp)) {
        int e = errno;
        ss_atomic_abort(af);
        return ss_error_set(err, SS_ERR_RUNTIME, "%s: write failed: %s", path, strerror(e));
    }
    return ss_atomic_commit(af, err);
}

static void xml_attr(FILE *f, const char *s) {
    for (; *s; s++) {
        switch (*s) {
        case '&':
            fputs("&amp;", f);
            break;
        case '<':
            fputs("&lt;", f);
            break;
        case '>':
            fputs("&gt;", f);
            break;
        case '"':
            fputs("&quot;", f);
            break;
        default:
            fputc(*s, f);
        }
    }
}

ss_status ss_heal_vti_write(const char *path, const ss_heal_grid *g, ss_error *err) {
    return ss_heal_vti_write_vectors(path, g, 0, NULL, NULL, err);
}

static void put_vec3(FILE *f, float *const v[3], size_t n) {
    put_u64le(f, (uint64_t)(12 * n));
    float buf[3 * 256];
    for (size_t i = 0; i < n; i += 256) {
        size_t m = n - i < 256 ? n - i : 256;
        for (size_t j = 0; j < m; j++)
            for (int c = 0; c < 3; c++) buf[3 * j + (size_t)c] = v[c][i + j];
        put_f32le(f, buf, 3 * m);
    }
}

static ss_status write_vti(const char *path, const ss_heal_grid *g, const int box[6], int nvec,
                           const char *const *names, float *const (*vecs)[3],
                           const double *closed_day, const float *elevation, const int off[3],
                           const int whole[3], ss_error *err);

/* The vector v (3 arrays over g) on g's box bx (x0 y0 z0 nx ny nz), row by row. */
static void put_vec3_box(FILE *f, const ss_heal_grid *g, float *const v[3], const int bx[6]) {
    put_u64le(f, (uint64_t)(12 * (size_t)bx[3] * bx[4] * bx[5]));
    float buf[3 * 256];
    for (int z = 0; z < bx[5]; z++)
        for (int y = 0; y < bx[4]; y++) {
            const size_t r = ss_heal_idx(g, bx[0], bx[1] + y, bx[2] + z);
            for (int i = 0; i < bx[3]; i += 256) {
                int m = bx[3] - i < 256 ? bx[3] - i : 256;
                for (int j = 0; j < m; j++)
                    for (int c = 0; c < 3; c++) buf[3 * j + c] = v[c][r + (size_t)(i + j)];
                put_f32le(f, buf, 3 * (size_t)m);
            }
        }
}

ss_status ss_heal_vti_write_vectors(const char *path, const ss_heal_grid *g, int nvec,
                                    const char *const *names, float *const (*vecs)[3],
                                    ss_error *err) {
    return ss_heal_vti_write_all(path, g, nvec, names, vecs, NULL, err);
}

static void put_f64le(FILE *f, const double *a, size_t n) {
    for (size_t i = 0; i < n; i++) {
        uint64_t v;
        unsigned char b[8];
        memcpy(&v, &a[i], 8);
        for (int k = 0; k < 8; k++) b[k] = (unsigned char)(v >> (8 * k));
        fwrite(b, 1, 8, f);
    }
}

ss_status ss_heal_vti_write_all(const char *path, const ss_heal_grid *g, int nvec,
                                const char *const *names, float *const (*vecs)[3],
                                const double *closed_day, ss_error *err) {
    if (!g || !g->cell) return ss_error_set(err, SS_ERR_INPUT, "%s: no grid", path);
    const int off[3] = {0, 0, 0}, whole[3] = {g->nx, g->ny, g->nz};
    return write_vti(path, g, NULL, nvec, names, vecs, closed_day, NULL, off, whole, err);
}

ss_status ss_heal_vti_write_piece(const char *path, const ss_heal_grid *piece, const int off[3],
                                  const int whole[3], ss_error *err) {
    if (!piece || !piece->cell) return ss_error_set(err, SS_ERR_INPUT, "%s: no grid", path);
    return write_vti(path, piece, NULL, 0, NULL, NULL, NULL, NULL, off, whole, err);
}

ss_status ss_heal_vti_write_piece_all(const char *path, const ss_heal_grid *piece, const int off[3],
                                      const int whole[3], int nvec, const char *const *names,
                                      float *const (*vecs)[3], const double *closed_day,
                                      ss_error *err) {
    if (!piece || !piece->cell) return ss_error_set(err, SS_ERR_INPUT, "%s: no grid", path);
    return write_vti(path, piece, NULL, nvec, names, vecs, closed_day, NULL, off, whole, err);
}

ss_status ss_heal_vti_write_box(const char *path, const ss_heal_grid *g, const int box[6],
                                const int off[3], const int whole[3], const double *closed_day,
                                ss_error *err) {
    if (!g || !g->cell || !box || box[0] < 0 || box[1] < 0 || box[2] < 0 || box[3] < 1 ||
        box[4] < 1 || box[5] < 1 || box[0] + box[3] > g->nx || box[1] + box[4] > g->ny ||
        box[2] + box[5] > g->nz)
        return ss_error_set(err, SS_ERR_INPUT, "%s: no grid, or the box is not inside it", path);
    return write_vti(path, g, box, 0, NULL, NULL, closed_day, NULL, off, whole, err);
}

ss_status ss_heal_vti_write_box_vectors(const char *path, const ss_heal_grid *g, const int box[6],
                                        const int off[3], const int whole[3], int nvec,
                                        const char *const *names, float *const (*vecs)[3],
                                        const double *closed_day, const float *elevation,
                                        ss_error *err) {
    if (!g || !g->cell || !box || box[0] < 0 || box[1] < 0 || box[2] < 0 || box[3] < 1 ||
        box[4] < 1 || box[5] < 1 || box[0] + box[3] > g->nx || box[1] + box[4] > g->ny ||
        box[2] + box[5] > g->nz || nvec < 0 || (nvec && (!names || !vecs)))
        return ss_error_set(err, SS_ERR_INPUT, "%s: no grid, or the box is not inside it", path);
    return write_vti(path, g, box, nvec, names, vecs, closed_day, elevation, off, whole, err);
}

ss_status ss_heal_pvti_write(const char *path, const int whole[3], double dx_mm, int npieces,
                             const int (*ext)[6], const char *const *files, ss_error *err) {
    return ss_heal_pvti_write_vectors(path, whole, dx_mm, npieces, ext, files, 0, NULL, err);
}

ss_status ss_heal_pvti_write_vectors(const char *path, const int whole[3], double dx_mm,
                                     int npieces, const int (*ext)[6], const char *const *files,
                                     int nvec, const char *const *names, ss_error *err) {
    return ss_heal_pvti_write_arrays(path, whole, dx_mm, npieces, ext, files, nvec, names, 0, err);
}

ss_status ss_heal_pvti_write_arrays(const char *path, const int whole[3], double dx_mm, int npieces,
                                    const int (*ext)[6], const char *const *files, int nvec,
                                    const char *const *names, int added, ss_error *err) {
    ss_atomic_file af;
    ss_status st = ss_atomic_open(&af, path, err);
    if (st) return st;
    FILE *f = af.fp;
    fprintf(f, "<?xml version=\"1.0\"?>\n"
               "<VTKFile type=\"PImageData\" version=\"1.0\" byte_order=\"LittleEndian\" "
               "header_type=\"UInt64\">\n");
    fprintf(f,
            "  <PImageData WholeExtent=\"0 %d 0 %d 0 %d\" GhostLevel=\"0\" Origin=\"0 0 0\" "
            "Spacing=\"%.17g %.17g %.17g\">\n",
            whole[0], whole[1], whole[2], dx_mm, dx_mm, dx_mm);
    fprintf(f, "    <PCellData Scalars=\"cell_state\">\n"
               "      <PDataArray type=\"UInt8\" Name=\"cell_state\"/>\n");
    for (int k = 0; k < SS_HEAL_NFIELDS; k++)
        fprintf(f, "      <PDataArray type=\"Float32\" Name=\"%s\"/>\n", ss_heal_field_name(k));
    for (int v = 0; v < nvec; v++)
        fprintf(f, "      <PDataArray type=\"Float32\" Name=\"%s\" NumberOfComponents=\"3\"/>\n",
                names[v]);
    fprintf(f, "      <PDataArray type=\"Float32\" Name=\"surface_elevation_mm\"/>\n");
    if (added) fprintf(f, "      <PDataArray type=\"Float32\" Name=\"keloid_added\"/>\n");
    fprintf(f, "    </PCellData>\n");
    for (int i = 0; i < npieces; i++) {
        fprintf(f, "    <Piece Extent=\"%d %d %d %d %d %d\" Source=\"", ext[i][0], ext[i][1],
                ext[i][2], ext[i][3], ext[i][4], ext[i][5]);
        xml_attr(f, files[i]);
        fprintf(f, "\"/>\n");
    }
    fprintf(f, "  </PImageData>\n</VTKFile>\n");
    return commit(&af, path, err);
}

/* The grid g as the piece of a larger image whose cell (0,0,0) is at off and
 * whose dimensions are whole (the plain file: off 0, whole = g's). */
static ss_status write_vti(const char *path, const ss_heal_grid *g, const int box[6], int nvec,
                           const char *const *names, float *const (*vecs)[3],
                           const double *closed_day, const float *elevation, const int org[3],
                           const int whole[3], ss_error *err) {
    int vel = g->velocity[0] && g->velocity[1] && g->velocity[2];
    /* the cells written: g's box x0 y0 z0 nx ny nz (box), or all of g */
    const int bx[6] = {box ? box[0] : 0,     box ? box[1] : 0,     box ? box[2] : 0,
                       box ? box[3] : g->nx, box ? box[4] : g->ny, box ? box[5] : g->nz};
    size_t n = (size_t)bx[3] * (size_t)bx[4] * (size_t)bx[5];
    /* the surface elevation of every column (given, or over the box's levels,
     * which for a box spanning the grid's depth is the whole column) */
    float *elev = NULL;
    if (!elevation) {
        elev = calloc((size_t)g->nx * (size_t)g->ny, sizeof *elev);
        if (!elev) return ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
        ss_heal_elevation_scan(g, bx[2], bx[2] + bx[5], elev);
        elevation = elev;
    }
    ss_atomic_file af;
    ss_status st = ss_atomic_open(&af, path, err);
    if (st) {
        free(elev);
        return st;
    }
    FILE *f = af.fp;
    fprintf(f, "<?xml version=\"1.0\"?>\n"
               "<VTKFile type=\"ImageData\" version=\"1.0\" byte_order=\"LittleEndian\" "
               "header_type=\"UInt64\">\n");
    fprintf(f,
            "  <ImageData WholeExtent=\"0 %d 0 %d 0 %d\" Origin=\"0 0 0\" "
            "Spacing=\"%.17g %.17g %.17g\">\n",
            whole[0], whole[1], whole[2], g->dx_mm, g->dx_mm, g->dx_mm);
    fprintf(f,
            "    <FieldData>\n"
            "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" "
            "format=\"ascii\">%.17g</DataArray>\n",
            g->t_days);
    /* the closure days go after every cell array in the appended data */
    const int add = g->added != NULL;
    size_t ncol = (size_t)bx[3] * (size_t)bx[4];
    uint64_t coff = 8 + n + (SS_HEAL_NFIELDS + add) * (8 + 4 * (uint64_t)n) +
                    (uint64_t)(vel + nvec) * (8 + 12 * (uint64_t)n) + 8 + 4 * (uint64_t)n;
    if (closed_day)
        fprintf(f,
                "      <DataArray type=\"Float64\" Name=\"closed_day\" NumberOfTuples=\"%zu\" "
                "format=\"appended\" offset=\"%llu\"/>\n",
                ncol, (unsigned long long)coff);
    fprintf(f, "    </FieldData>\n");
    fprintf(f, "    <Piece Extent=\"%d %d %d %d %d %d\">\n", org[0], org[0] + bx[3], org[1],
            org[1] + bx[4], org[2], org[2] + bx[5]);
    fprintf(f, "      <CellData Scalars=\"cell_state\">\n");
    uint64_t off = 0;
    fprintf(f,
            "        <DataArray type=\"UInt8\" Name=\"cell_state\" format=\"appended\" "
            "offset=\"%llu\"/>\n",
            (unsigned long long)off);
    off += 8 + n;
    for (int k = 0; k < SS_HEAL_NFIELDS; k++) {
        const char *name = ss_heal_field_name(k);
        fprintf(f,
                "        <DataArray type=\"Float32\" Name=\"%s\" format=\"appended\" "
                "offset=\"%llu\"/>\n",
                name ? name : "field", (unsigned long long)off);
        off += 8 + 4 * n;
    }
    if (vel)
        fprintf(f,
                "        <DataArray type=\"Float32\" Name=\"velocity\" NumberOfComponents=\"3\" "
                "format=\"appended\" offset=\"%llu\"/>\n",
                (unsigned long long)off);
    if (vel) off += 8 + 12 * n;
    for (int v = 0; v < nvec; v++) {
        fprintf(f,
                "        <DataArray type=\"Float32\" Name=\"%s\" NumberOfComponents=\"3\" "
                "format=\"appended\" offset=\"%llu\"/>\n",
                names[v], (unsigned long long)off);
        off += 8 + 12 * n;
    }
    fprintf(f,
            "        <DataArray type=\"Float32\" Name=\"surface_elevation_mm\" "
            "format=\"appended\" offset=\"%llu\"/>\n",
            (unsigned long long)off);
    off += 8 + 4 * n;
    if (add) /* the keloid's added volume, rho units per cell [D16] */
        fprintf(f,
                "        <DataArray type=\"Float32\" Name=\"keloid_added\" "
                "format=\"appended\" offset=\"%llu\"/>\n",
                (unsigned long long)off);
    fprintf(f, "      </CellData>\n    </Piece>\n  </ImageData>\n"
               "  <AppendedData encoding=\"raw\">\n   _");
    put_u64le(f, (uint64_t)n);
    if (!box) fwrite(g->cell, 1, n, f);
    for (int z = 0; box && z < bx[5]; z++) /* a box: row by row */
        for (int y = 0; y < bx[4]; y++)
            fwrite(g->cell + ss_heal_idx(g, bx[0], bx[1] + y, bx[2] + z), 1, (size_t)bx[3], f);
    for (int k = 0; k < SS_HEAL_NFIELDS; k++) {
        put_u64le(f, (uint64_t)(4 * n));
        if (!box) put_f32le(f, g->field[k], n);
        for (int z = 0; box && z < bx[5]; z++)
            for (int y = 0; y < bx[4]; y++)
                put_f32le(f, g->field[k] + ss_heal_idx(g, bx[0], bx[1] + y, bx[2] + z),
                          (size_t)bx[3]);
    }
    if (vel && !box) put_vec3(f, g->velocity, n);
    if (vel && box) put_vec3_box(f, g, g->velocity, bx);
    for (int v = 0; v < nvec; v++) {
        if (!box) put_vec3(f, vecs[v], n);
        if (box) put_vec3_box(f, g, vecs[v], bx);
    }
    put_u64le(f, (uint64_t)(4 * n)); /* per column, repeated along z */
    for (int z = 0; z < bx[5]; z++)
        for (int y = 0; y < bx[4]; y++)
            put_f32le(f, elevation + (size_t)(bx[1] + y) * (size_t)g->nx + (size_t)bx[0],
                      (size_t)bx[3]);
    free(elev);
    if (add) {
        put_u64le(f, (uint64_t)(4 * n));
        if (!box) put_f32le(f, g->added, n);
        for (int z = 0; box && z < bx[5]; z++)
            for (int y = 0; y < bx[4]; y++)
                put_f32le(f, g->added + ss_heal_idx(g, bx[0], bx[1] + y, bx[2] + z), (size_t)bx[3]);
    }
    if (closed_day) {
        put_u64le(f, (uint64_t)(8 * ncol));
        put_f64le(f, closed_day, ncol);
    }
    fprintf(f, "\n  </AppendedData>\n</VTKFile>\n");
    return commit(&af, path, err);
}

ss_status ss_heal_pvd_write(const char *path, int n, const double *t_days, const char *const *files,
                            ss_error *err) {
    ss_atomic_file af;
    ss_status st = ss_atomic_open(&af, path, err);
    if (st) return st;
    FILE *f = af.fp;
    fprintf(f, "<?xml version=\"1.0\"?>\n"
               "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
               "  <Collection>\n");
    for (int i = 0; i < n; i++) {
        fprintf(f, "    <DataSet timestep=\"%.12g\" group=\"\" part=\"0\" file=\"", t_days[i]);
        xml_attr(f, files[i]);
        fprintf(f, "\"/>\n");
    }
    fprintf(f, "  </Collection>\n</VTKFile>\n");
    return commit(&af, path, err);
}

/* ---- reading back what ss_heal_vti_write_vectors wrote ----------------------------------
 * Not a general VTK reader: the header is scanned for the attributes this
 * writer puts there (WholeExtent, Spacing, TimeValue, each DataArray's Name,
 * type, components and offset), the appended block sizes are checked against
 * the extent, and anything else is an input error naming the file. */

static const char *attr_in(const char *tag, const char *end, const char *name) {
    size_t n = strlen(name);
    for (const char *p = tag; p && p + n + 2 < end; p++) {
        p = strstr(p, name);
        if (!p || p + n + 2 >= end) return NULL;
        if ((p == tag || p[-1] == ' ') && p[n] == '=' && p[n + 1] == '"') return p + n + 2;
    }
    return NULL;
}

static uint64_t get_u64le(const unsigned char *b) {
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--) v = (v << 8) | b[i];
    return v;
}

static void get_f32le(float *dst, const unsigned char *src, size_t n) {
    if (little_endian()) {
        memcpy(dst, src, 4 * n);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        uint32_t v = (uint32_t)src[4 * i] | (uint32_t)src[4 * i + 1] << 8 |
                     (uint32_t)src[4 * i + 2] << 16 | (uint32_t)src[4 * i + 3] << 24;
        memcpy(&dst[i], &v, 4);
    }
}

/* One appended array: its block at data + offset, of `bytes` bytes. */
static const unsigned char *vti_block(const unsigned char *data, size_t avail, uint64_t off,
                                      uint64_t bytes) {
    if (off > avail || avail - off < 8) return NULL;
    if (get_u64le(data + off) != bytes || avail - off - 8 < bytes) return NULL;
    return data + off + 8;
}

/* A snapshot or, piece, a piece of a parallel image: the grid of its Piece
 * Extent (off..off+n in whole-grid cells, whole from WholeExtent); a whole
 * file must have its piece span the WholeExtent. */
static ss_heal_grid *read_vti(const char *path, int piece, int whole[3], int off[3],
                              float **displacement, double **closed_day, ss_error *err) {
    if (displacement) *displacement = NULL;
    if (closed_day) *closed_day = NULL;
    double *closed = NULL;
    size_t len = 0;
    char *text = ss_read_file(path, &len, err);
    if (!text) return NULL;
    ss_heal_grid *g = NULL;
    float *disp = NULL;
    const char *why = NULL;
    char *app = strstr(text, "<AppendedData encoding=\"raw\">");
    char *us = app ? strchr(app, '_') : NULL;
    int n[3] = {0, 0, 0}, e0[3], *W = whole, pe[6];
    double sp[3] = {0, 0, 0};
    const char *we = strstr(text, "WholeExtent=\""), *pex = strstr(text, "<Piece Extent=\"");
    const char *spc = strstr(text, "Spacing=\"");
    const char *tv = strstr(text, "Name=\"TimeValue\"");
    if (!app || !us || !we || !spc || !tv || we > app || spc > app || tv > app)
        why = "not a skinsim heal snapshot (no extent, spacing, time or appended data)";
    else if (sscanf(we + 13, "%d %d %d %d %d %d", &e0[0], &W[0], &e0[1], &W[1], &e0[2], &W[2]) !=
                 6 ||
             e0[0] || e0[1] || e0[2] || W[0] < 1 || W[1] < 1 || W[2] < 1)
        why = "bad WholeExtent";
    else if (!pex || pex > app ||
             sscanf(pex + 15, "%d %d %d %d %d %d", &pe[0], &pe[1], &pe[2], &pe[3], &pe[4],
                    &pe[5]) != 6)
        why = "no Piece Extent";
    for (int a = 0; !why && a < 3; a++) {
        off[a] = pe[2 * a], n[a] = pe[2 * a + 1] - pe[2 * a];
        if (off[a] < 0 || n[a] < 1 || off[a] > W[a] - n[a] || (!piece && n[a] != W[a]))
            why = piece ? "Piece Extent not inside the WholeExtent"
                        : "Piece Extent is not the WholeExtent (a piece of a .pvti?)";
    }
    if (!why && (sscanf(spc + 9, "%lg %lg %lg", &sp[0], &sp[1], &sp[2]) != 3 || !(sp[0] > 0) ||
                 sp[1] != sp[0] || sp[2] != sp[0]))
        why = "bad Spacing (the heal grid has cubic voxels)";
    double t = 0;
    const char *tvv = tv ? strchr(tv, '>') : NULL;
    if (!why && (!tvv || sscanf(tvv + 1, "%lg", &t) != 1 || !(t >= 0))) why = "bad TimeValue";
    /* a piece may be thinner than a grid can be: allocated at least 3 wide */
    if (!why &&
        !(g = ss_heal_grid_create(piece && n[0] < 3 ? 3 : n[0], piece && n[1] < 3 ? 3 : n[1],
                                  piece && n[2] < 3 ? 3 : n[2], sp[0], err))) {
        free(text);
        return NULL;
    }
    if (g) g->nx = n[0], g->ny = n[1], g->nz = n[2];
    /* no arithmetic on us when there is no appended data (NULL + 1 is UB) */
    const unsigned char *data = us ? (const unsigned char *)us + 1 : NULL;
    size_t avail = us ? len - (size_t)(us + 1 - text) : 0;
    size_t ncell = (size_t)n[0] * (size_t)n[1] * (size_t)n[2];
    int have_cell = 0, have[SS_HEAL_NFIELDS] = {0};
    /* each DataArray of the header */
    for (char *da = text; !why && (da = strstr(da, "<DataArray")) && da < app; da++) {
        const char *end = strchr(da, '>');
        if (!end) break;
        const char *nm = attr_in(da, end, "Name"), *of = attr_in(da, end, "offset"),
                   *ty = attr_in(da, end, "type"), *nc = attr_in(da, end, "NumberOfComponents");
        if (!nm || !of) continue; /* TimeValue (ascii) */
        const char *q = strchr(nm, '"');
        size_t nl = q ? (size_t)(q - nm) : 0;
        unsigned long long off = strtoull(of, NULL, 10);
        int comps = nc ? atoi(nc) : 1;
        if (nl == 10 && !strncmp(nm, "closed_day", 10)) {
            size_t ncol = (size_t)n[0] * (size_t)n[1];
            const unsigned char *b = strncmp(ty ? ty : "", "Float64\"", 8)
                                         ? NULL
                                         : vti_block(data, avail, off, 8 * (uint64_t)ncol);
            if (!b)
                why = "the closed_day array is malformed";
            else if (closed_day && !(closed = malloc(ncol * sizeof *closed)))
                why = "out of memory";
            for (size_t i = 0; closed && !why && i < ncol; i++) {
                uint64_t v = get_u64le(b + 8 * i);
                memcpy(&closed[i], &v, 8);
            }
            continue;
        }
        if (nl == 10 && !strncmp(nm, "cell_state", 10)) {
            const unsigned char *b =
                strncmp(ty ? ty : "", "UInt8\"", 6) ? NULL : vti_block(data, avail, off, ncell);
            if (!b)
                why = "cell_state array malformed";
            else
                memcpy(g->cell, b, ncell), have_cell = 1;
            continue;
        }
        const unsigned char *b = strncmp(ty ? ty : "", "Float32\"", 8)
                                     ? NULL
                                     : vti_block(data, avail, off, 4 * (uint64_t)comps * ncell);
        int k = 0;
        while (k < SS_HEAL_NFIELDS &&
               !(strlen(ss_heal_field_name(k)) == nl && !strncmp(nm, ss_heal_field_name(k), nl)))
            k++;
        if (k < SS_HEAL_NFIELDS) {
            if (!b || comps != 1)
                why = "a field array is malformed";
            else
                get_f32le(g->field[k], b, ncell), have[k] = 1;
        } else if (nl == 12 && !strncmp(nm, "keloid_added", 12)) {
            if (!b || comps != 1)
                why = "the keloid_added array is malformed";
            else if (!g->added && !(g->added = malloc(ncell * sizeof *g->added)))
                why = "out of memory";
            else
                get_f32le(g->added, b, ncell);
        } else if (nl == 12 && !strncmp(nm, "displacement", 12) && displacement) {
            if (!b || comps != 3)
                why = "the displacement array is malformed";
            else if (!(disp = malloc(3 * ncell * sizeof *disp)))
                why = "out of memory";
            else { /* interleaved per cell in the file; x, y, z blocks in memory */
                float v[3];
                for (size_t i = 0; i < ncell; i++) {
                    get_f32le(v, b + 12 * i, 3);
                    for (int c = 0; c < 3; c++) disp[(size_t)c * ncell + i] = v[c];
                }
            }
        }
    }
    for (int k = 0; !why && k < SS_HEAL_NFIELDS; k++)
        if (!have[k]) why = "a field array is missing";
    if (!why && !have_cell) why = "the cell_state array is missing";
    free(text);
    if (why) {
        ss_error_set(err, SS_ERR_INPUT, "%s: %s", path, why);
        ss_heal_grid_free(g);
        free(disp);
        free(closed);
        return NULL;
    }
    g->t_days = t;
    if (displacement) *displacement = disp;
    if (closed_day) *closed_day = closed;
    return g;
}

ss_heal_grid *ss_heal_vti_read(const char *path, float **displacement, double **closed_day,
                               ss_error *err) {
    int whole[3], off[3];
    return read_vti(path, 0, whole, off, displacement, closed_day, err);
}

ss_heal_grid *ss_heal__vti_read_piece(const char *path, int whole[3], int off[3],
                                      float **displacement, double **closed_day, ss_error *err) {
    return read_vti(path, 1, whole, off, displacement, closed_day, err);
}
