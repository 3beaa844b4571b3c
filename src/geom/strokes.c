/* Painted strokes (seed 000 §4.2.1 records UV points while the user paints):
 * the CSV format shared by `skinsim abrasion` and `skinsim heal`, and the
 * hull of each stroke (convex, Alg. 4.1, or concave k-NN). Parsing is strict
 * and every error names the file and line. */
#define _POSIX_C_SOURCE 200809L
#include "skinsim/geom.h"

#include <errno.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

void ss_stroke_set_free(ss_stroke_set *s) {
    if (!s) return;
    free(s->u);
    free(s->v);
    free(s->stroke);
    free(s->stroke_ids);
    memset(s, 0, sizeof *s);
}

static int cmp_int(const void *a, const void *b) {
    int x = *(const int *)a, y = *(const int *)b;
    return (x > y) - (x < y);
}

ss_status ss_stroke_csv_parse(const char *text, const char *name, ss_stroke_set *out,
                              ss_error *err) {
    memset(out, 0, sizeof *out);
    int cap = 256, n = 0, lineno = 0, seen_data = 0;
    double *u = malloc((size_t)cap * sizeof *u), *v = malloc((size_t)cap * sizeof *v);
    int *id = malloc((size_t)cap * sizeof *id);
    char line[1024];
    int too_long;
    ss_status st = SS_OK;
    if (!u || !v || !id) {
        st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", name);
        goto fail;
    }
    if (!strncmp(text, "\xEF\xBB\xBF", 3)) text += 3; /* UTF-8 byte order mark */
    for (const char *p = text; (p = ss_text_next_line(p, line, sizeof line, &too_long));) {
        lineno++;
        if (too_long) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s:%d: line too long", name, lineno);
            goto fail;
        }
        char *s = ss_text_trim(line);
        if (!*s || *s == '#') continue;
        char *fld[4];
        int nf = 0;
        for (char *q = s;;) {
            char *c = strchr(q, ',');
            if (nf < 4) fld[nf] = q;
            nf++;
            if (!c) break;
            *c = '\0';
            q = c + 1;
        }
        for (int k = 0; k < nf && k < 4; k++) fld[k] = ss_text_trim(fld[k]);
        double a, b;
        int ra = nf >= 1 ? ss_text_parse_number(fld[0], &a) : 1;
        if (!seen_data && ra == 1) { /* header line */
            seen_data = 1;
            continue;
        }
        seen_data = 1;
        if (nf < 2 || nf > 3) {
            st = ss_error_set(err, SS_ERR_INPUT,
                              "%s:%d: expected 'u,v' or 'u,v,stroke_id', got %d field%s", name,
                              lineno, nf, nf == 1 ? "" : "s");
            goto fail;
        }
        int rb = ss_text_parse_number(fld[1], &b);
        if (ra || rb) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s:%d: %s '%s' is %s", name, lineno,
                              ra ? "u" : "v", ra ? fld[0] : fld[1],
                              (ra ? ra : rb) == 2 ? "not finite" : "not a number");
            goto fail;
        }
        if (a < 0 || a > 1 || b < 0 || b > 1) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s:%d: u,v = %g,%g is outside [0,1]", name,
                              lineno, a, b);
            goto fail;
        }
        long sid = 0;
        if (nf == 3) {
            char *end;
            errno = 0;
            sid = strtol(fld[2], &end, 10);
            if (end == fld[2] || *end) {
                st = ss_error_set(err, SS_ERR_INPUT, "%s:%d: stroke id '%s' is not a whole number",
                                  name, lineno, fld[2]);
                goto fail;
            }
            if (errno == ERANGE || sid < 0 || sid > 1000000000L) {
                st = ss_error_set(err, SS_ERR_INPUT,
                                  "%s:%d: stroke id %s is out of range [0, 1000000000]", name,
                                  lineno, fld[2]);
                goto fail;
            }
        }
        if (n == cap) {
            cap *= 2;
            double *nu = realloc(u, (size_t)cap * sizeof *u);
            if (nu) u = nu;
            double *nv = realloc(v, (size_t)cap * sizeof *v);
            if (nv) v = nv;
            int *ni = realloc(id, (size_t)cap * sizeof *id);
            if (ni) id = ni;
            if (!nu || !nv || !ni) {
                st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", name);
                goto fail;
            }
        }
        u[n] = a;
        v[n] = b;
        id[n] = (int)sid;
        n++;
    }
    if (n == 0) {
        st = ss_error_set(err, SS_ERR_INPUT, "%s: no stroke points", name);
        goto fail;
    }
    int *ids = malloc((size_t)n * sizeof *ids);
    if (!ids) {
        st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", name);
        goto fail;
    }
    memcpy(ids, id, (size_t)n * sizeof *ids);
    qsort(ids, (size_t)n, sizeof *ids, cmp_int);
    int k = 0;
    for (int i = 0; i < n;) {
        int j = i;
        while (j < n && ids[j] == ids[i]) j++;
        if (j - i < 3) {
            st = ss_error_set(err, SS_ERR_INPUT,
                              "%s: stroke %d has %d point%s; a wound outline needs at least 3",
                              name, ids[i], j - i, j - i == 1 ? "" : "s");
            free(ids);
            goto fail;
        }
        ids[k++] = ids[i];
        i = j;
    }
    out->npoints = n;
    out->u = u;
    out->v = v;
    out->stroke = id;
    out->nstrokes = k;
    out->stroke_ids = ids;
    return SS_OK;
fail:
    free(u);
    free(v);
    free(id);
    return st;
}

ss_status ss_stroke_csv_read(const char *path, ss_stroke_set *out, ss_error *err) {
    memset(out, 0, sizeof *out);
    char *text = ss_read_file_max(path, NULL, SS_READ_MAX_STROKES, err);
    if (!text) return err ? err->code : SS_ERR_INPUT;
    ss_status st = ss_stroke_csv_parse(text, path, out, err);
    free(text);
    return st;
}

ss_status ss_stroke_hulls(const ss_stroke_set *s, double width, double height, int concave_k,
                          const char *name, ss_polygon **out, ss_error *err) {
    *out = NULL;
    /* name prefixes the messages; NULL leaves it to the caller */
    char pre[512] = "";
    if (name) snprintf(pre, sizeof pre, "%s: ", name);
    if (concave_k != 0 && concave_k < 3)
        return ss_error_set(err, SS_ERR_INPUT, "%sconcave hull k must be >= 3 (got %d)", pre,
                            concave_k);
    ss_polygon *polys = calloc((size_t)(s->nstrokes > 0 ? s->nstrokes : 1), sizeof *polys);
    ss_vec2 *pts = malloc((size_t)(s->npoints > 0 ? s->npoints : 1) * sizeof *pts);
    ss_status st = polys && pts ? SS_OK : ss_error_set(err, SS_ERR_NOMEM, "%sout of memory", pre);
    for (int k = 0; k < s->nstrokes && !st; k++) {
        int n = 0;
        for (int i = 0; i < s->npoints; i++)
            if (s->stroke[i] == s->stroke_ids[k])
                pts[n++] = (ss_vec2){s->u[i] * width, s->v[i] * height};
        ss_error e;
        ss_error_clear(&e);
        st = concave_k ? ss_concave_hull(pts, n, concave_k, &polys[k], &e)
                       : ss_convex_hull(pts, n, &polys[k], &e);
        if (st) ss_error_set(err, st, "%sstroke %d: %s", pre, s->stroke_ids[k], e.msg);
    }
    free(pts);
    if (st) {
        for (int k = 0; polys && k < s->nstrokes; k++) ss_polygon_free(&polys[k]);
        free(polys);
        return st;
    }
    *out = polys;
    return SS_OK;
}

ss_image *ss_stroke_footprint(const ss_stroke_set *s, int width, int height, int concave_k,
                              const char *name, ss_error *err) {
    /* the sharp hulls: round.c's footprint with no corner rounding */
    return ss_stroke_footprint_rounded(s, width, height, concave_k, 0.0, name, err);
}
