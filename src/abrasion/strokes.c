/* Painted-stroke files (seed 000 §4.2.1 records UV points while the user
 * paints): CSV "u,v[,stroke_id]", parsed strictly so a bad line is reported
 * with its file and line number. */
#define _POSIX_C_SOURCE 200809L
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
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
            if (*q == ',')
                q++;
            else
                break;
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
    /* A brush path scrubbed back and forth over a roundish patch, like the
     * knuckle abrasion of the seed's Fig. 4.5 (whose hull is "one big
     * circle"): a zig-zag inside an ellipse of radii 0.15 x 0.12, tilted. */
    memset(out, 0, sizeof *out);
    int cap = 0;
    const double cx = 0.5, cy = 0.5, rx = 0.15, ry = 0.12, tilt = 0.35;
    for (int i = 0; i <= 48; i++) {
        double t = i / 48.0 * 2.0 * M_PI;
        for (int pass = 0; pass < 2; pass++) {
            double r = pass ? 0.55 + 0.3 * sin(5 * t) : 1.0 - 0.06 * cos(3 * t);
            double ex = rx * r * cos(t), ey = ry * r * sin(t);
            double u = cx + ex * cos(tilt) - ey * sin(tilt),
                   v = cy + ex * sin(tilt) + ey * cos(tilt);
            if (push(out, &cap, u, v, 0))
                return ss_strokes_free(out), ss_error_set(err, SS_ERR_NOMEM, "out of memory");
        }
    }
    return SS_OK;
}
