/* Reading a parallel snapshot back whole: a .pvti (VTK's PImageData, written
 * by ss_heal_pvti_write) and its .vti pieces (ss_heal_vti_write_piece, one
 * per MPI rank) become one ss_heal_grid, equal to what ss_heal_vti_read gives
 * for the gathered snapshot of the same state, so `skinsim wound --heal` can
 * read a run that wrote pieces only (seed 001 §5.4's fields, handed on).
 *
 * Design: not a general VTK reader. The .pvti is scanned for this writer's
 * tags (PImageData's WholeExtent and Spacing, one Extent and Source per
 * Piece); each piece is read by the .vti reader's piece form and checked
 * against the .pvti (its WholeExtent, Extent and Spacing) and the other
 * pieces (one TimeValue); the pieces must tile the extent exactly; only then
 * is the grid returned. Pieces are read one at a time into the whole grid
 * (memory: the whole grid plus the largest piece). The closure days
 * (a FieldData array per piece, for its own columns) are joined the same way:
 * pieces sharing a column (a z stack) must agree, and every column must be
 * covered once any piece has them. A Source must name a file inside the
 * .pvti's folder (no "..", no absolute path, no symbolic link out of it).
 * Gave up: ghost levels, other VTK encodings
 * and point data (this writer makes none). */
#define _POSIX_C_SOURCE 200809L
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "../solver/heal_internal.h"
#include "skinsim/heal_io.h"

/* The value of attribute name="..." inside the tag tag..end, unescaped, in
 * buf; NULL when absent or too long. */
static const char *attr(const char *tag, const char *end, const char *name, char *buf, size_t n) {
    size_t l = strlen(name);
    for (const char *p = tag; (p = strstr(p, name)) && p < end; p++) {
        if (p[-1] != ' ' || p[l] != '=' || p[l + 1] != '"') continue;
        const char *v = p + l + 2, *q = strchr(v, '"');
        if (!q || q > end) return NULL;
        size_t k = 0;
        for (const char *s = v; s < q; s++) {
            static const char *const ent[][2] = {
                {"&amp;", "&"}, {"&lt;", "<"}, {"&gt;", ">"}, {"&quot;", "\""}};
            char c = *s;
            for (size_t e = 0; c == '&' && e < 4; e++)
                if (!strncmp(s, ent[e][0], strlen(ent[e][0]))) {
                    c = ent[e][1][0];
                    s += strlen(ent[e][0]) - 1;
                }
            if (k + 1 >= n) return NULL;
            buf[k++] = c;
        }
        buf[k] = '\0';
        return buf;
    }
    return NULL;
}

typedef struct pv_piece {
    ss_heal_box box;
    char *file; /* the piece's path, inside the .pvti's folder */
} pv_piece;

typedef struct pv_image {
    int whole[3];
    double dx;
    int n;
    pv_piece *p;
    char why[sizeof(((ss_error *)0)->msg)]; /* a refused Source, whole */
} pv_image;

static void pv_free(pv_image *v) {
    for (int i = 0; i < v->n; i++) free(v->p[i].file);
    free(v->p);
    v->p = NULL;
    v->n = 0;
}

/* The .pvti's own XML: NULL or why it is malformed. */
static const char *pv_parse(const char *path, const char *text, pv_image *v) {
    char buf[4096];
    const char *vf = strstr(text, "<VTKFile"), *im = strstr(text, "<PImageData");
    const char *vfe = vf ? strchr(vf, '>') : NULL, *ime = im ? strchr(im, '>') : NULL;
    if (!vfe || !ime || !attr(vf, vfe, "type", buf, sizeof buf) || strcmp(buf, "PImageData"))
        return "not a VTK parallel image (no <VTKFile type=\"PImageData\"> and <PImageData>)";
    if (!strstr(ime, "</PImageData>") || !strstr(ime, "</VTKFile>"))
        return "malformed XML (PImageData or VTKFile not closed)";
    int e0[3];
    double sp[3];
    if (!attr(im, ime, "WholeExtent", buf, sizeof buf) ||
        sscanf(buf, "%d %d %d %d %d %d", &e0[0], &v->whole[0], &e0[1], &v->whole[1], &e0[2],
               &v->whole[2]) != 6 ||
        e0[0] || e0[1] || e0[2] || v->whole[0] < 1 || v->whole[1] < 1 || v->whole[2] < 1)
        return "bad WholeExtent";
    if ((double)v->whole[0] * v->whole[1] * v->whole[2] > (double)SS_HEAL_MAX_CELLS)
        return "WholeExtent larger than any heal grid";
    if (!attr(im, ime, "Spacing", buf, sizeof buf) ||
        sscanf(buf, "%lg %lg %lg", &sp[0], &sp[1], &sp[2]) != 3 || !(sp[0] > 0) || sp[1] != sp[0] ||
        sp[2] != sp[0])
        return "bad Spacing (the heal grid has cubic voxels)";
    v->dx = sp[0];
    for (const char *pc = ime; (pc = strstr(pc, "<Piece")); pc++) {
        const char *pe = strchr(pc, '>');
        int e[6];
        if (!pe) return "malformed XML (a Piece tag is not closed)";
        if (!attr(pc, pe, "Extent", buf, sizeof buf) ||
            sscanf(buf, "%d %d %d %d %d %d", &e[0], &e[1], &e[2], &e[3], &e[4], &e[5]) != 6)
            return "a Piece has no Extent";
        if (v->n == SS_HEAL_CKPT_MAX_PIECES) return "too many pieces";
        pv_piece *np = realloc(v->p, (size_t)(v->n + 1) * sizeof *np);
        if (!np) return "out of memory";
        v->p = np;
        pv_piece *p = &v->p[v->n];
        memset(p, 0, sizeof *p);
        for (int a = 0; a < 3; a++) p->box.lo[a] = e[2 * a], p->box.n[a] = e[2 * a + 1] - e[2 * a];
        v->n++;
        if (!attr(pc, pe, "Source", buf, sizeof buf) || !buf[0]) return "a Piece has no Source";
        /* inside the .pvti's folder: no "..", no absolute path, no link out */
        ss_error e2;
        if (ss_input_path_inside(path, buf, &p->file, &e2)) {
            snprintf(v->why, sizeof v->why, "%s", e2.msg);
            return v->why;
        }
    }
    if (!v->n) return "no Piece";
    return NULL;
}

/* The .pvti read and checked (XML, tiling); SS_OK or an error naming it. */
static ss_status pv_open(const char *path, pv_image *v, ss_error *err) {
    memset(v, 0, sizeof *v);
    char *text = ss_read_file_max(path, NULL, SS_READ_MAX_CONFIG, err);
    if (!text) return err && err->code ? err->code : SS_ERR_INPUT;
    const char *why = pv_parse(path, text, v);
    free(text);
    int bad = -1;
    if (!why && (why = ss_heal__boxes_tile(v->whole, v->n, v->p, sizeof *v->p, &bad)) && bad >= 0) {
        const ss_heal_box *b = &v->p[bad].box;
        ss_error_set(err, SS_ERR_INPUT,
                     "%s: the pieces do not tile the extent 0 %d 0 %d 0 %d: %s (Extent %d %d %d "
                     "%d %d %d) %s",
                     path, v->whole[0], v->whole[1], v->whole[2], v->p[bad].file, b->lo[0],
                     b->lo[0] + b->n[0], b->lo[1], b->lo[1] + b->n[1], b->lo[2], b->lo[2] + b->n[2],
                     why);
    } else if (why == v->why) {
        ss_error_set(err, SS_ERR_INPUT, "%s", why);
    } else if (why) {
        ss_error_set(err, SS_ERR_INPUT, "%s: %s", path, why);
    }
    if (why) pv_free(v);
    return why ? SS_ERR_INPUT : SS_OK;
}

ss_status ss_heal_pvti_check(const char *path, ss_error *err) {
    pv_image v;
    ss_status st = pv_open(path, &v, err);
    if (st) return st;
    struct stat sb;
    for (int i = 0; !st && i < v.n; i++)
        if (stat(v.p[i].file, &sb) || !S_ISREG(sb.st_mode) || sb.st_size == 0)
            st = ss_error_set(err, SS_ERR_INPUT, "%s: piece of %s is missing or empty", v.p[i].file,
                              path);
    pv_free(&v);
    return st;
}

ss_heal_grid *ss_heal_pvti_read(const char *path, float **displacement, double **closed_day,
                                ss_error *err) {
    if (displacement) *displacement = NULL;
    if (closed_day) *closed_day = NULL;
    pv_image v;
    if (pv_open(path, &v, err)) return NULL;
    ss_heal_grid *g = ss_heal_grid_create(v.whole[0], v.whole[1], v.whole[2], v.dx, err);
    const size_t ncell = (size_t)v.whole[0] * v.whole[1] * v.whole[2];
    const size_t ncol = (size_t)v.whole[0] * v.whole[1];
    float *disp = g && displacement ? malloc(3 * ncell * sizeof *disp) : NULL;
    double *closed = g && closed_day ? malloc(ncol * sizeof *closed) : NULL;
    unsigned char *cover = g ? calloc(ncol, 1) : NULL; /* 1: a piece gave the column's day */
    int ndisp = 0, nclosed = 0, nadded = 0,
        ok = g && cover && (!displacement || disp) && (!closed_day || closed);
    if (g && !ok) ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
    for (int i = 0; ok && i < v.n; i++) {
        const char *file = v.p[i].file;
        const ss_heal_box *b = &v.p[i].box;
        int pw[3], off[3];
        float *pd = NULL;
        double *pc = NULL;
        ss_heal_grid *p =
            ss_heal__vti_read_piece(file, pw, off, displacement ? &pd : NULL, &pc, err);
        if (!p) {
            char msg[sizeof err->msg];
            snprintf(msg, sizeof msg, "%s", err ? err->msg : "");
            if (err) ss_error_set(err, err->code, "%s (a piece of %s)", msg, path);
            ok = 0;
            break;
        }
        const char *mis = NULL;
        if (memcmp(pw, v.whole, sizeof pw))
            mis = "its WholeExtent differs from the .pvti's";
        else if (memcmp(off, b->lo, sizeof off) || p->nx != b->n[0] || p->ny != b->n[1] ||
                 p->nz != b->n[2])
            mis = "its Extent differs from the one the .pvti gives it";
        else if (p->dx_mm != v.dx)
            mis = "its Spacing differs from the .pvti's";
        else if (i > 0 && p->t_days != g->t_days)
            mis = "its TimeValue differs from the other pieces'";
        if (mis) ss_error_set(err, SS_ERR_INPUT, "%s: piece of %s: %s", file, path, mis);
        ok = !mis;
        /* a keloid run's added volume [D16]: in every piece or in none */
        if (ok && p->added && !g->added && !(g->added = calloc(ncell, sizeof *g->added))) {
            ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
            ok = 0;
        }
        const size_t pn = (size_t)b->n[0] * b->n[1] * b->n[2];
        for (int z = 0; ok && z < b->n[2]; z++)
            for (int y = 0; y < b->n[1]; y++) {
                const size_t s = ss_heal_idx(p, 0, y, z);
                const size_t d = ss_heal_idx(g, b->lo[0], b->lo[1] + y, b->lo[2] + z);
                memcpy(g->cell + d, p->cell + s, (size_t)b->n[0]);
                for (int f = 0; f < SS_HEAL_NFIELDS; f++)
                    memcpy(g->field[f] + d, p->field[f] + s, (size_t)b->n[0] * sizeof(float));
                if (p->added) memcpy(g->added + d, p->added + s, (size_t)b->n[0] * sizeof(float));
                for (int c = 0; pd && c < 3; c++)
                    memcpy(disp + (size_t)c * ncell + d, pd + (size_t)c * pn + s,
                           (size_t)b->n[0] * sizeof(float));
            }
        for (int y = 0; ok && pc && y < b->n[1]; y++)
            for (int x = 0; x < b->n[0]; x++) {
                const size_t d = (size_t)(b->lo[1] + y) * v.whole[0] + (size_t)(b->lo[0] + x);
                const double day = pc[(size_t)y * b->n[0] + (size_t)x];
                if (cover[d] && closed && memcmp(&closed[d], &day, sizeof day)) {
                    ss_error_set(err, SS_ERR_INPUT,
                                 "%s: piece of %s: its closed_day of column %d,%d differs from "
                                 "another piece's",
                                 file, path, b->lo[0] + x, b->lo[1] + y);
                    ok = 0;
                    break;
                }
                if (closed) closed[d] = day;
                cover[d] = 1;
            }
        ndisp += pd != NULL;
        nadded += ok && p->added != NULL;
        nclosed += pc != NULL;
        if (ok) g->t_days = p->t_days;
        free(pd);
        free(pc);
        ss_heal_grid_free(p);
    }
    for (size_t c = 0; ok && nclosed && c < ncol; c++)
        if (!cover[c]) {
            ss_error_set(err, SS_ERR_INPUT,
                         "%s: the pieces' closed_day arrays leave column %zu,%zu uncovered", path,
                         c % (size_t)v.whole[0], c / (size_t)v.whole[0]);
            ok = 0;
        }
    if (ok && nadded && nadded != v.n) {
        ss_error_set(err, SS_ERR_INPUT, "%s: some pieces hold keloid_added and others do not",
                     path);
        ok = 0;
    }
    free(cover);
    const int npieces = v.n;
    pv_free(&v);
    if (!ok) {
        ss_heal_grid_free(g);
        free(disp);
        free(closed);
        return NULL;
    }
    if (displacement && ndisp == npieces)
        *displacement = disp;
    else
        free(disp);
    if (closed_day && nclosed)
        *closed_day = closed;
    else
        free(closed);
    return g;
}
