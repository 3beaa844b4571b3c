/* Painted-stroke files (seed 000 §4.2.1 records UV points while the user
 * paints): CSV "u,v[,stroke_id]", parsed strictly so a bad line is reported
 * with its file and line number. */
#define _POSIX_C_SOURCE 200809L
#include "skinsim/abrasion.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

void ss_strokes_free(ss_strokes *s) {
    if (!s) return;
    free(s->uv);
    free(s->stroke_id);
    memset(s, 0, sizeof *s);
}

static int push(ss_strokes *s, int *cap, double u, double v, int id) {
    if (s->count == *cap) {
        int nc = *cap ? *cap * 2 : 256;
        ss_vec2 *uv = realloc(s->uv, (size_t)nc * sizeof *uv);
        if (!uv) return -1;
        s->uv = uv;
        int *ids = realloc(s->stroke_id, (size_t)nc * sizeof *ids);
        if (!ids) return -1;
        s->stroke_id = ids;
        *cap = nc;
    }
    s->uv[s->count].x = u;
    s->uv[s->count].y = v;
    s->stroke_id[s->count] = id;
    s->count++;
    return 0;
}

/* Parses one number field; returns pointer past it or NULL. */
static const char *field(const char *p, double *out) {
    while (*p == ' ' || *p == '\t') p++;
    char *end;
    errno = 0;
    *out = strtod(p, &end);
    if (end == p || errno == ERANGE) return NULL;
    p = end;
    while (*p == ' ' || *p == '\t') p++;
    return p;
}

ss_status ss_strokes_read_csv(const char *path, ss_strokes *out, ss_error *err) {
    memset(out, 0, sizeof *out);
    size_t len;
    char *text = ss_read_file(path, &len, err);
    if (!text) return SS_ERR_INPUT;
    if (memchr(text, '\0', len))
        return free(text), ss_error_set(err, SS_ERR_INPUT, "%s: binary data, not a CSV file", path);
    int cap = 0, lineno = 0, first_data = 1;
    ss_status st = SS_OK;
    char *save = NULL;
    for (char *line = strtok_r(text, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        lineno++;
        size_t n = strlen(line);
        while (n && (line[n - 1] == '\r' || isspace((unsigned char)line[n - 1]))) line[--n] = '\0';
        const char *p = line;
        while (*p == ' ' || *p == '\t') p++;
        if (*p == '\0' || *p == '#') continue;
        double v[3];
        int k = 0;
        const char *q = p;
        while (k < 3) {
            q = field(q, &v[k]);
            if (!q) break;
            k++;
            if (*q == ',') q++;
            else break;
        }
        if (!q || (k < 2) || *q != '\0') {
            if (first_data && !isdigit((unsigned char)*p) && *p != '-' && *p != '.' && *p != '+') {
                first_data = 0; /* a header line such as "u,v,stroke" */
                continue;
            }
            st = ss_error_set(err, SS_ERR_INPUT,
                              "%s:%d: expected 'u,v' or 'u,v,stroke_id' numbers, got '%s'", path,
                              lineno, p);
            break;
        }
        first_data = 0;
        if (!isfinite(v[0]) || !isfinite(v[1])) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s:%d: u,v must be finite numbers", path, lineno);
            break;
        }
        if (v[0] < 0 || v[0] > 1 || v[1] < 0 || v[1] > 1) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s:%d: point (%g, %g) is outside 0..1", path,
                              lineno, v[0], v[1]);
            break;
        }
        int id = 0;
        if (k == 3) {
            if (!isfinite(v[2]) || v[2] != floor(v[2]) || v[2] < 0 || v[2] > 1e6) {
                st = ss_error_set(err, SS_ERR_INPUT,
                                  "%s:%d: stroke id must be a whole number 0..1000000", path,
                                  lineno);
                break;
            }
            id = (int)v[2];
        }
        if (push(out, &cap, v[0], v[1], id)) {
            st = ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
            break;
        }
    }
    free(text);
    if (!st && out->count == 0) st = ss_error_set(err, SS_ERR_INPUT, "%s: no points in file", path);
    if (st) ss_strokes_free(out);
    return st;
}

ss_status ss_strokes_example(ss_strokes *out, ss_error *err) {
    /* A scrape painted as a wobbly band, wider at one end, like the seed's
     * Fig. 4.5 knuckle abrasion; points follow the brush path. */
    memset(out, 0, sizeof *out);
    int cap = 0;
    for (int i = 0; i <= 40; i++) {
        double t = i / 40.0;
        double cx = 0.30 + 0.40 * t, cy = 0.42 + 0.10 * t + 0.03 * sin(6.0 * t);
        double half = 0.07 + 0.06 * t;
        for (int side = -1; side <= 1; side += 2)
            if (push(out, &cap, cx - 0.02 * side, cy + side * half * (0.8 + 0.2 * cos(9 * t)), 0))
                return ss_strokes_free(out), ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    return SS_OK;
}
