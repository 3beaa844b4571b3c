/* features.csv: one row per feature (seed 003 §4.8.8's RTree contents), so a
 * user can edit a mole and re-render with --features-in. Numbers are printed
 * with 17 significant digits (%.17g), which round-trips every double, so a
 * list written and read back renders bit-identical maps. Rows are read in
 * file order; rendering applies them in type (priority) order. */
#include "skinsim/skin.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char HEADER[] = "type,x,y,r,r2,h,m,p,w,x1,y1,x2,y2,x3,y3";
#define NCOLS 15

static void values_of(const ss_skin_feature *f, double v[NCOLS - 1]) {
    v[0] = f->x, v[1] = f->y, v[2] = f->r, v[3] = f->r2, v[4] = f->h, v[5] = f->m, v[6] = f->p,
    v[7] = f->w;
    for (int i = 1; i < 4; i++) {
        v[6 + 2 * i] = f->type == SS_FEAT_WRINKLE ? f->curve.x[i] : 0.0;
        v[7 + 2 * i] = f->type == SS_FEAT_WRINKLE ? f->curve.y[i] : 0.0;
    }
}

ss_status ss_skin_features_write_csv(const char *path, const ss_skin_feature_list *l,
                                     ss_error *err) {
    ss_atomic_file af;
    ss_status st = ss_atomic_open(&af, path, err);
    if (st) return st;
    fprintf(af.fp, "%s\n", HEADER);
    for (size_t i = 0; i < l->n; i++) {
        const ss_skin_feature *f = &l->f[i];
        double v[NCOLS - 1];
        values_of(f, v);
        fputs(ss_feature_type_name(f->type), af.fp);
        for (int c = 0; c < NCOLS - 1; c++) fprintf(af.fp, ",%.17g", v[c] == 0.0 ? 0.0 : v[c]);
        fputc('\n', af.fp);
    }
    if (ferror(af.fp)) {
        ss_atomic_abort(&af);
        return ss_error_set(err, SS_ERR_RUNTIME, "%s: write failed", path);
    }
    return ss_atomic_commit(&af, err);
}

ss_status ss_skin_features_parse_csv(const char *text, const char *name, ss_skin_feature_list *out,
                                     ss_error *err) {
    memset(out, 0, sizeof *out);
    size_t cap = 0, lineno = 0;
    char line[4096];
    int too_long = 0, header_seen = 0;
    const char *p = text;
    ss_status st = SS_OK;
    while (!st && (p = ss_text_next_line(p, line, sizeof line, &too_long)) != NULL) {
        lineno++;
        if (too_long) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s:%zu: line too long", name, lineno);
            break;
        }
        char *s = ss_text_trim(line);
        if (!*s || *s == '#') continue;
        if (!header_seen) {
            if (strcmp(s, HEADER) != 0) {
                st = ss_error_set(err, SS_ERR_INPUT, "%s:%zu: expected the header '%s'", name,
                                  lineno, HEADER);
                break;
            }
            header_seen = 1;
            continue;
        }
        char *fields[NCOLS + 1];
        int nf = 0;
        for (char *q = s;; q++) {
            if (nf <= NCOLS) fields[nf] = q;
            nf++;
            q = strchr(q, ',');
            if (!q) break;
            *q = '\0';
        }
        if (nf != NCOLS) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s:%zu: %d fields, expected %d", name, lineno, nf,
                              NCOLS);
            break;
        }
        ss_skin_feature f;
        memset(&f, 0, sizeof f);
        f.type = ss_feature_type_from_name(ss_text_trim(fields[0]));
        if (f.type < 0) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s:%zu: unknown feature type '%s'", name, lineno,
                              fields[0]);
            break;
        }
        double v[NCOLS - 1];
        for (int c = 0; c < NCOLS - 1 && !st; c++) {
            int r = ss_text_parse_number(ss_text_trim(fields[c + 1]), &v[c]);
            if (r)
                st = ss_error_set(err, SS_ERR_INPUT, "%s:%zu: column %d '%s' is %s", name, lineno,
                                  c + 2, fields[c + 1], r == 2 ? "not finite" : "not a number");
            else if (c < 2 && !(v[c] >= -1.0 && v[c] <= 2.0))
                st = ss_error_set(err, SS_ERR_INPUT,
                                  "%s:%zu: position %g outside the texture (0..1)", name, lineno,
                                  v[c]);
            else if (c >= 2 && c <= 7 && !(v[c] >= 0.0 && v[c] <= 1000.0))
                st = ss_error_set(err, SS_ERR_INPUT, "%s:%zu: column %d (%g) is outside 0..1000",
                                  name, lineno, c + 2, v[c]);
            else if (c >= 8 && !(fabs(v[c]) <= 10.0))
                st = ss_error_set(err, SS_ERR_INPUT, "%s:%zu: control point %g out of range", name,
                                  lineno, v[c]);
        }
        if (st) break;
        f.x = v[0], f.y = v[1], f.r = v[2], f.r2 = v[3], f.h = v[4], f.m = v[5], f.p = v[6],
        f.w = v[7];
        if (f.type == SS_FEAT_WRINKLE) {
            f.curve.x[0] = f.x, f.curve.y[0] = f.y;
            for (int i = 1; i < 4; i++) f.curve.x[i] = v[6 + 2 * i], f.curve.y[i] = v[7 + 2 * i];
        }
        if ((f.type == SS_FEAT_MOLE || f.type == SS_FEAT_FRECKLE) && (f.m > 1.0 || f.p > 1.0)) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s:%zu: pigment fraction above 1", name, lineno);
            break;
        }
        if (out->n == cap) {
            size_t nc = cap ? 2 * cap : 1024;
            ss_skin_feature *g = realloc(out->f, nc * sizeof *g);
            if (!g) {
                st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", name);
                break;
            }
            out->f = g;
            cap = nc;
        }
        out->f[out->n++] = f;
    }
    if (!st && !header_seen)
        st = ss_error_set(err, SS_ERR_INPUT, "%s: empty (no header '%s')", name, HEADER);
    if (st) ss_skin_feature_list_free(out);
    return st;
}

ss_status ss_skin_features_read_csv(const char *path, ss_skin_feature_list *out, ss_error *err) {
    memset(out, 0, sizeof *out);
    size_t len;
    char *text = ss_read_file_max(path, &len, SS_READ_MAX_FEATURES, err);
    if (!text) return err->code;
    if (strlen(text) != len) {
        free(text);
        return ss_error_set(err, SS_ERR_INPUT, "%s: not a text file (NUL byte)", path);
    }
    ss_status st = ss_skin_features_parse_csv(text, path, out, err);
    free(text);
    return st;
}
