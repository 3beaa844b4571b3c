/* The normalised wound-area curve of seed 001 Fig. 4 (time in days vs open
 * area / initial area) as CSV and as a cairo plot, and colour-mapped top-view
 * surface maps (seed 001 Fig. 2 seen from above) with a labelled colour bar.
 * PNGs are rendered with cairo into memory and written atomically. */
#define _POSIX_C_SOURCE 200809L
#include "skinsim/heal_io.h"

#include <cairo.h>
#include <math.h>
#include <stdlib.h>
#include <errno.h>
#include <string.h>

#define FONT "DejaVu Sans"
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ---- area table ---------------------------------------------------------------- */

double ss_heal_area_normalised(const ss_heal_stats *st) {
    return st->initial_area_mm2 > 0 ? st->open_area_mm2 / st->initial_area_mm2 : 0.0;
}

ss_status ss_heal_area_csv_write(const char *path, const ss_heal_area_row *rows, int n,
                                 ss_error *err) {
    return ss_heal_area_csv_write_columns(path, rows, n, 0, NULL, NULL, err);
}

ss_status ss_heal_area_csv_write_columns(const char *path, const ss_heal_area_row *rows, int n,
                                         int ncols, const char *const *names, const double *vals,
                                         ss_error *err) {
    ss_atomic_file af;
    ss_status st = ss_atomic_open(&af, path, err);
    if (st) return st;
    FILE *f = af.fp;
    fprintf(f, "t_days,open_area_mm2,normalised_area,wound_region_area_mm2");
    for (int k = 0; k < SS_HEAL_NFIELDS; k++) {
        const char *name = ss_heal_field_name(k);
        fprintf(f, ",mean_%s", name ? name : "field");
    }
    fprintf(f, ",open_columns_mm2,elevation_mean_mm,elevation_max_mm");
    for (int c = 0; c < ncols; c++) fprintf(f, ",%s", names[c]);
    fputc('\n', f);
    for (int i = 0; i < n; i++) {
        const ss_heal_stats *s = &rows[i].st;
        fprintf(f, "%.9g,%.9g,%.9g,%.9g", rows[i].t_days, s->open_area_mm2,
                ss_heal_area_normalised(s), s->wound_region_area_mm2);
        for (int k = 0; k < SS_HEAL_NFIELDS; k++) fprintf(f, ",%.9g", s->field_mean[k]);
        fprintf(f, ",%.9g,%.9g,%.9g", s->open_columns_mm2, s->elevation_mean_mm,
                s->elevation_max_mm);
        for (int c = 0; c < ncols; c++) fprintf(f, ",%.9g", vals[(size_t)i * ncols + c]);
        fputc('\n', f);
    }
    if (ferror(f)) {
        int e = errno;
        ss_atomic_abort(&af);
        return ss_error_set(err, SS_ERR_RUNTIME, "%s: write failed: %s", path, strerror(e));
    }
    return ss_atomic_commit(&af, err);
}

double ss_heal_time_to_closure(const ss_heal_area_row *rows, int n, double level) {
    for (int i = 0; i < n; i++) {
        double a = ss_heal_area_normalised(&rows[i].st);
        if (a <= level) {
            if (i == 0) return rows[0].t_days;
            double a0 = ss_heal_area_normalised(&rows[i - 1].st);
            double f = a0 != a ? (a0 - level) / (a0 - a) : 1.0;
            return rows[i - 1].t_days + f * (rows[i].t_days - rows[i - 1].t_days);
        }
    }
    return -1.0;
}

/* ---- cairo helpers ------------------------------------------------------------ */

typedef struct membuf {
    unsigned char *p;
    size_t len, cap;
    int bad;
} membuf;

static cairo_status_t mem_write(void *closure, const unsigned char *data, unsigned int length) {
    membuf *m = closure;
    if (m->len + length > m->cap) {
        size_t cap = m->cap ? m->cap : 65536;
        while (cap < m->len + length) cap *= 2;
        unsigned char *q = realloc(m->p, cap);
        if (!q) {
            m->bad = 1;
            return CAIRO_STATUS_WRITE_ERROR;
        }
        m->p = q;
        m->cap = cap;
    }
    memcpy(m->p + m->len, data, length);
    m->len += length;
    return CAIRO_STATUS_SUCCESS;
}

static ss_status surface_to_png(cairo_surface_t *s, const char *path, ss_error *err) {
    membuf m = {0};
    cairo_surface_flush(s);
    cairo_status_t cs = cairo_surface_write_to_png_stream(s, mem_write, &m);
    ss_status st;
    if (cs != CAIRO_STATUS_SUCCESS || m.bad)
        st = ss_error_set(err, SS_ERR_RUNTIME, "%s: PNG encoding failed: %s", path,
                          cairo_status_to_string(cs));
    else
        st = ss_write_file_atomic(path, m.p, m.len, err);
    free(m.p);
    return st;
}

/* A "nice" tick step (1, 2, 5 x 10^k) giving about `target` intervals. */
static double nice_step(double range, int target) {
    if (!(range > 0)) return 1;
    double raw = range / target, p = pow(10, floor(log10(raw))), r = raw / p;
    return (r < 1.5 ? 1 : r < 3.5 ? 2 : r < 7.5 ? 5 : 10) * p;
}

static void text_at(cairo_t *cr, double x, double y, const char *s, double ax, double ay) {
    cairo_text_extents_t te;
    cairo_text_extents(cr, s, &te);
    cairo_move_to(cr, x - te.x_bearing - ax * te.width, y - te.y_bearing - ay * te.height);
    cairo_show_text(cr, s);
}

static void fmt_tick(char *buf, size_t n, double v, double step) {
    int dec = step >= 1 ? 0 : (int)ceil(-log10(step) - 1e-9);
    if (dec > 6) dec = 6;
    if (fabs(v) < step * 1e-6) v = 0;
    snprintf(buf, n, "%.*f", dec, v);
}

/* ---- area plot ------------------------------------------------------------------ */

ss_status ss_heal_area_plot(const char *path, const ss_heal_area_row *rows, int n,
                            const char *title, ss_error *err) {
    return ss_heal_area_plot_contraction(path, rows, n, title, NULL, NULL, err);
}

/* One extra curve (values per row; NaN rows skipped), clipped to the plot. */
static void extra_curve(cairo_t *cr, const ss_heal_area_row *rows, int n, const double *v, double L,
                        double T, double pw, double ph, double tmin, double tmax, double ytop) {
    int started = 0;
    for (int i = 0; i < n; i++) {
        if (!isfinite(v[i])) continue;
        double x = L + (rows[i].t_days - tmin) / (tmax - tmin) * pw, y = T + ph - v[i] / ytop * ph;
        if (!started)
            cairo_move_to(cr, x, y);
        else
            cairo_line_to(cr, x, y);
        started = 1;
    }
    cairo_stroke(cr);
}

ss_status ss_heal_area_plot_contraction(const char *path, const ss_heal_area_row *rows, int n,
                                        const char *title, const double *outline,
                                        const double *myofibroblasts, ss_error *err) {
    const int W = 900, H = 560;
    const double L = 90, R = 30, T = 60, B = 70;
    cairo_surface_t *s = cairo_image_surface_create(CAIRO_FORMAT_RGB24, W, H);
    cairo_t *cr = cairo_create(s);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    cairo_select_font_face(cr, FONT, CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);

    double tmax = n > 0 ? rows[n - 1].t_days : 1, tmin = n > 0 ? rows[0].t_days : 0;
    if (tmin > 0) tmin = 0;
    if (!(tmax > tmin)) tmax = tmin + 1;
    double ymax = 1.0;
    for (int i = 0; i < n; i++) {
        double a = ss_heal_area_normalised(&rows[i].st);
        if (isfinite(a) && a > ymax) ymax = a;
    }
    double tstep = nice_step(tmax - tmin, 8), ystep = nice_step(ymax, 5);
    tmax = ceil(tmax / tstep - 1e-9) * tstep;
    ymax = ceil(ymax / ystep - 1e-9) * ystep;
    double pw = W - L - R, ph = H - T - B;
    double ytop = ymax * 1.04; /* headroom so a curve at the top stays visible */
#define PX(t) (L + ((t)-tmin) / (tmax - tmin) * pw)
#define PY(a) (T + ph - (a) / ytop * ph)

    /* grid and ticks */
    char buf[64];
    cairo_set_font_size(cr, 14);
    cairo_set_line_width(cr, 1);
    for (double t = tmin; t <= tmax + 1e-9 * tstep; t += tstep) {
        double x = round(PX(t)) + 0.5;
        cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
        cairo_move_to(cr, x, T);
        cairo_line_to(cr, x, T + ph);
        cairo_stroke(cr);
        cairo_set_source_rgb(cr, 0, 0, 0);
        cairo_move_to(cr, x, T + ph);
        cairo_line_to(cr, x, T + ph + 6);
        cairo_stroke(cr);
        fmt_tick(buf, sizeof buf, t, tstep);
        text_at(cr, x, T + ph + 10, buf, 0.5, 0);
    }
    for (double a = 0; a <= ymax + 1e-9 * ystep; a += ystep) {
        double y = round(PY(a)) + 0.5;
        cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
        cairo_move_to(cr, L, y);
        cairo_line_to(cr, L + pw, y);
        cairo_stroke(cr);
        cairo_set_source_rgb(cr, 0, 0, 0);
        cairo_move_to(cr, L - 6, y);
        cairo_line_to(cr, L, y);
        cairo_stroke(cr);
        fmt_tick(buf, sizeof buf, a, ystep);
        text_at(cr, L - 10, y, buf, 1, 0.5);
    }
    /* closure guides */
    static const double guide[2] = {0.5, 0.05};
    static const char *glabel[2] = {"50% closed", "95% closed"};
    double dash[2] = {6, 4};
    cairo_set_font_size(cr, 12);
    for (int k = 0; k < 2; k++) {
        if (guide[k] > ymax) continue;
        cairo_set_source_rgb(cr, 0.55, 0.55, 0.55);
        cairo_set_dash(cr, dash, 2, 0);
        cairo_move_to(cr, L, PY(guide[k]));
        cairo_line_to(cr, L + pw, PY(guide[k]));
        cairo_stroke(cr);
        cairo_set_dash(cr, NULL, 0, 0);
        text_at(cr, L + pw - 4, PY(guide[k]) - 3, glabel[k], 1, 1);
    }
    /* axes box */
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 1.5);
    cairo_rectangle(cr, L, T, pw, ph);
    cairo_stroke(cr);
    /* curve */
    if (n > 0) {
        cairo_save(cr);
        cairo_rectangle(cr, L, T, pw, ph);
        cairo_clip(cr);
        cairo_set_source_rgb(cr, 0.12, 0.35, 0.75);
        cairo_set_line_width(cr, 2.5);
        cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
        int started = 0;
        for (int i = 0; i < n; i++) {
            double a = ss_heal_area_normalised(&rows[i].st);
            if (!isfinite(a)) continue;
            if (!started)
                cairo_move_to(cr, PX(rows[i].t_days), PY(a));
            else
                cairo_line_to(cr, PX(rows[i].t_days), PY(a));
            started = 1;
        }
        if (n == 1) cairo_rel_line_to(cr, 1, 0);
        cairo_stroke(cr);
        if (outline) {
            cairo_set_source_rgb(cr, 0.85, 0.37, 0.05);
            extra_curve(cr, rows, n, outline, L, T, pw, ph, tmin, tmax, ytop);
        }
        if (myofibroblasts) {
            double d2[2] = {8, 5};
            cairo_set_dash(cr, d2, 2, 0);
            cairo_set_source_rgb(cr, 0.15, 0.6, 0.25);
            extra_curve(cr, rows, n, myofibroblasts, L, T, pw, ph, tmin, tmax, ytop);
            cairo_set_dash(cr, NULL, 0, 0);
        }
        cairo_restore(cr);
    }
    if (outline || myofibroblasts) { /* legend, top right */
        static const char *lab[3] = {"open wound area", "wound outline (contraction)",
                                     "myofibroblast fraction"};
        static const double col[3][3] = {{0.12, 0.35, 0.75}, {0.85, 0.37, 0.05}, {0.15, 0.6, 0.25}};
        const int have[3] = {1, outline != NULL, myofibroblasts != NULL};
        double y = T + 18, x = L + pw - 250;
        cairo_set_font_size(cr, 13);
        for (int k = 0; k < 3; k++) {
            if (!have[k]) continue;
            cairo_set_source_rgb(cr, col[k][0], col[k][1], col[k][2]);
            cairo_set_line_width(cr, 2.5);
            if (k == 2) {
                double d2[2] = {8, 5};
                cairo_set_dash(cr, d2, 2, 0);
            }
            cairo_move_to(cr, x, y);
            cairo_line_to(cr, x + 30, y);
            cairo_stroke(cr);
            cairo_set_dash(cr, NULL, 0, 0);
            cairo_set_source_rgb(cr, 0, 0, 0);
            text_at(cr, x + 38, y, lab[k], 0, 0.5);
            y += 20;
        }
    }
    /* labels */
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_font_size(cr, 16);
    text_at(cr, L + pw / 2, H - 28, "time (days)", 0.5, 0);
    cairo_save(cr);
    cairo_translate(cr, 24, T + ph / 2);
    cairo_rotate(cr, -M_PI / 2);
    text_at(cr, 0, 0,
            outline || myofibroblasts ? "fraction of the initial wound area; myofibroblast fraction"
                                      : "normalised open wound area (open / initial)",
            0.5, 0);
    cairo_restore(cr);
    cairo_select_font_face(cr, FONT, CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
    cairo_set_font_size(cr, 18);
    text_at(cr, W / 2.0, 20, title ? title : "normalised wound area", 0.5, 0);
#undef PX
#undef PY
    cairo_destroy(cr);
    ss_status st = surface_to_png(s, path, err);
    cairo_surface_destroy(s);
    return st;
}

/* ---- colour-mapped surface maps ------------------------------------------------ */

/* viridis, 9 stops (sRGB 8-bit values from matplotlib's table). */
static void viridis(double t, double rgb[3]) {
    static const double c[9][3] = {{68, 1, 84},    {71, 44, 122},  {59, 81, 139},
                                   {44, 113, 142}, {33, 144, 141}, {39, 173, 129},
                                   {92, 200, 99},  {170, 220, 50}, {253, 231, 37}};
    if (!(t >= 0)) t = 0;
    if (t > 1) t = 1;
    double u = t * 8;
    int i = (int)u;
    if (i > 7) i = 7;
    double f = u - i;
    for (int k = 0; k < 3; k++) rgb[k] = ((1 - f) * c[i][k] + f * c[i + 1][k]) / 255.0;
}

ss_status ss_heal_surface_png(const char *path, const ss_image *map, double vmin, double vmax,
                              const char *title, const char *unit, double dx_mm, ss_error *err) {
    if (!map || map->channels < 1 || map->width < 1 || map->height < 1)
        return ss_error_set(err, SS_ERR_INPUT, "%s: empty map", path);
    if (!(vmax > vmin)) vmax = vmin + 1;
    int scale = (360 + map->width - 1) / map->width;
    if (map->height * scale > 720) scale = 720 / map->height > 0 ? 720 / map->height : 1;
    if (scale < 1) scale = 1;
    int mw = map->width * scale, mh = map->height * scale;
    const int L = 70, T = 58, B = 60, CB = 120;
    int bh = mh < 240 ? 240 : mh; /* colour bar height: readable for flat maps too */
    int W = L + mw + CB, H = T + (bh > mh ? bh : mh) + B;
    cairo_surface_t *img = cairo_image_surface_create(CAIRO_FORMAT_RGB24, map->width, map->height);
    unsigned char *px = cairo_image_surface_get_data(img);
    int stride = cairo_image_surface_get_stride(img);
    cairo_surface_flush(img);
    for (int y = 0; y < map->height; y++)
        for (int x = 0; x < map->width; x++) {
            double v = ss_image_px(map, x, y)[0], rgb[3];
            viridis((v - vmin) / (vmax - vmin), rgb);
            uint32_t word = (uint32_t)lround(rgb[0] * 255) << 16 |
                            (uint32_t)lround(rgb[1] * 255) << 8 | (uint32_t)lround(rgb[2] * 255);
            memcpy(px + (size_t)y * (size_t)stride + 4 * (size_t)x, &word, 4);
        }
    cairo_surface_mark_dirty(img);

    cairo_surface_t *s = cairo_image_surface_create(CAIRO_FORMAT_RGB24, W, H);
    cairo_t *cr = cairo_create(s);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    cairo_save(cr);
    cairo_translate(cr, L, T);
    cairo_scale(cr, scale, scale);
    cairo_set_source_surface(cr, img, 0, 0);
    cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
    cairo_rectangle(cr, 0, 0, map->width, map->height);
    cairo_fill(cr);
    cairo_restore(cr);
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_set_line_width(cr, 1);
    cairo_rectangle(cr, L - 0.5, T - 0.5, mw + 1, mh + 1);
    cairo_stroke(cr);

    cairo_select_font_face(cr, FONT, CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    char buf[128];
    /* mm ticks along x and y */
    cairo_set_font_size(cr, 12);
    if (dx_mm > 0) {
        double wmm = map->width * dx_mm, hmm = map->height * dx_mm;
        double st = nice_step(wmm > hmm ? wmm : hmm, 5), sty = st;
        if (hmm < 0.4 * wmm) sty = nice_step(hmm, 3); /* flat maps: finer y ticks */
        for (double v = 0; v <= wmm + 1e-9; v += st) {
            double x = L + v / dx_mm * scale;
            cairo_move_to(cr, x, T + mh);
            cairo_line_to(cr, x, T + mh + 5);
            cairo_stroke(cr);
            fmt_tick(buf, sizeof buf, v, st);
            text_at(cr, x, T + mh + 8, buf, 0.5, 0);
        }
        for (double v = 0; v <= hmm + 1e-9; v += sty) {
            double y = T + (hmm - v) / dx_mm * scale; /* image row 0 = far y edge */
            cairo_move_to(cr, L - 5, y);
            cairo_line_to(cr, L, y);
            cairo_stroke(cr);
            fmt_tick(buf, sizeof buf, v, sty);
            text_at(cr, L - 8, y, buf, 1, 0.5);
        }
        cairo_set_font_size(cr, 13);
        text_at(cr, L + mw / 2.0, T + mh + 30, "x (mm)", 0.5, 0);
        cairo_save(cr);
        cairo_translate(cr, 14, T + mh / 2.0);
        cairo_rotate(cr, -M_PI / 2);
        text_at(cr, 0, 0, "y (mm)", 0.5, 0);
        cairo_restore(cr);
    }
    /* colour bar */
    int bx = L + mw + 25, bw = 22;
    for (int y = 0; y < bh; y++) {
        double rgb[3];
        viridis(1.0 - (y + 0.5) / bh, rgb);
        cairo_set_source_rgb(cr, rgb[0], rgb[1], rgb[2]);
        cairo_rectangle(cr, bx, T + y, bw, 1);
        cairo_fill(cr);
    }
    cairo_set_source_rgb(cr, 0, 0, 0);
    cairo_rectangle(cr, bx - 0.5, T - 0.5, bw + 1, bh + 1);
    cairo_stroke(cr);
    cairo_set_font_size(cr, 12);
    double cst = nice_step(vmax - vmin, 4);
    for (double v = ceil(vmin / cst - 1e-9) * cst; v <= vmax + 1e-9 * cst; v += cst) {
        double y = T + bh - (v - vmin) / (vmax - vmin) * bh;
        cairo_move_to(cr, bx + bw, y);
        cairo_line_to(cr, bx + bw + 5, y);
        cairo_stroke(cr);
        fmt_tick(buf, sizeof buf, v, cst);
        text_at(cr, bx + bw + 8, y, buf, 0, 0.5);
    }
    if (unit && *unit) text_at(cr, bx + bw / 2.0, T - 6, unit, 0.5, 1);
    cairo_select_font_face(cr, FONT, CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
    cairo_set_font_size(cr, 15);
    text_at(cr, W / 2.0, 12, title ? title : "", 0.5, 0);
    cairo_destroy(cr);
    ss_status st = surface_to_png(s, path, err);
    cairo_surface_destroy(s);
    cairo_surface_destroy(img);
    return st;
}
