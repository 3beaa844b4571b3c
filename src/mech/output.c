/* Outputs of the contraction mechanics: the deformed tet mesh as a VTK XML
 * UnstructuredGrid (.vtu, ASCII, point data displacement, velocity, stress;
 * a .pvd collection of them comes from ss_heal_pvd_write), and a top view of
 * the deformed skin coloured by speed like the seed's Fig. 7 (blue = no
 * movement, cyan, green, yellow, red = fastest), with the deformed outline of
 * the initial wound in white. The top view rasterises the top surface
 * triangles with barycentric interpolation of the nodal speed; no GPU, no
 * library beyond core's images. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cairo.h>

#include "mech_internal.h"

ss_status ss_mech_vtu_write(const ss_mech *m, const char *path, double t_days, ss_error *err) {
    const ss_tetmesh *M = m->mesh;
    const double *x = m->S->x;
    ss_atomic_file af;
    ss_status st = ss_atomic_open(&af, path, err);
    if (st) return st;
    FILE *f = af.fp;
    fprintf(f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
               "byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n");
    fprintf(f,
            "<FieldData><DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" "
            "format=\"ascii\">%.17g</DataArray></FieldData>\n",
            t_days);
    fprintf(f, "<Piece NumberOfPoints=\"%d\" NumberOfCells=\"%d\">\n", M->nnodes, M->ntets);
    fprintf(f, "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for (int i = 0; i < M->nnodes; i++)
        fprintf(f, "%.9g %.9g %.9g\n", x[3 * i], x[3 * i + 1], x[3 * i + 2]);
    fprintf(f, "</DataArray></Points>\n<Cells>\n<DataArray type=\"Int32\" Name=\"connectivity\" "
               "format=\"ascii\">\n");
    for (int t = 0; t < M->ntets; t++)
        fprintf(f, "%d %d %d %d\n", M->tet[4 * t], M->tet[4 * t + 1], M->tet[4 * t + 2],
                M->tet[4 * t + 3]);
    fprintf(f, "</DataArray>\n<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n");
    for (int t = 0; t < M->ntets; t++) fprintf(f, "%d\n", 4 * (t + 1));
    fprintf(f, "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for (int t = 0; t < M->ntets; t++) fprintf(f, "10\n");
    fprintf(f, "</DataArray>\n</Cells>\n<PointData Vectors=\"velocity\" Scalars=\"stress\">\n");
    fprintf(f, "<DataArray type=\"Float64\" Name=\"displacement\" NumberOfComponents=\"3\" "
               "format=\"ascii\">\n");
    for (int i = 0; i < M->nnodes; i++)
        fprintf(f, "%.9g %.9g %.9g\n", x[3 * i] - M->x[3 * i], x[3 * i + 1] - M->x[3 * i + 1],
                x[3 * i + 2] - M->x[3 * i + 2]);
    fprintf(f, "</DataArray>\n<DataArray type=\"Float64\" Name=\"velocity\" "
               "NumberOfComponents=\"3\" format=\"ascii\">\n");
    for (int i = 0; i < M->nnodes; i++)
        fprintf(f, "%.9g %.9g %.9g\n", m->vel[3 * i], m->vel[3 * i + 1], m->vel[3 * i + 2]);
    fprintf(f, "</DataArray>\n<DataArray type=\"Float64\" Name=\"stress\" format=\"ascii\">\n");
    for (int i = 0; i < M->nnodes; i++) fprintf(f, "%.9g\n", m->stress[i]);
    fprintf(f, "</DataArray>\n</PointData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    if (ferror(f)) {
        ss_atomic_abort(&af);
        return ss_error_set(err, SS_ERR_RUNTIME, "%s: write failed", path);
    }
    return ss_atomic_commit(&af, err);
}

/* blue, cyan, green, yellow, red over t in 0..1 */
static void ramp(double t, float rgb[3]) {
    static const float c[5][3] = {{0, 0, 1}, {0, 1, 1}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}};
    if (!(t > 0)) t = 0;
    if (t > 1) t = 1;
    double s = t * 4;
    int i = (int)s;
    if (i > 3) i = 3;
    double f = s - i;
    for (int k = 0; k < 3; k++) rgb[k] = (float)((1 - f) * c[i][k] + f * c[i + 1][k]);
}

static void put_line(ss_image *img, double x0, double y0, double x1, double y1) {
    int n = (int)ceil(fmax(fabs(x1 - x0), fabs(y1 - y0))) + 1;
    for (int i = 0; i <= n; i++) {
        double t = (double)i / n;
        int x = (int)floor(x0 + t * (x1 - x0)), y = (int)floor(y0 + t * (y1 - y0));
        for (int dy = 0; dy < 2; dy++)
            for (int dx = 0; dx < 2; dx++) {
                int xx = x + dx, yy = y + dy;
                if (xx < 0 || yy < 0 || xx >= img->width || yy >= img->height) continue;
                float *p = ss_image_px(img, xx, yy);
                p[0] = p[1] = p[2] = 1.0f;
            }
    }
}

ss_image *ss_mech_top_view(const ss_mech *m, int px, double vmax, ss_error *err) {
    if (px < 16 || px > 8192) {
        ss_error_set(err, SS_ERR_INPUT, "top view: size %d px outside 16..8192", px);
        return NULL;
    }
    const double W = m->nx * m->dx, H = m->ny * m->dx;
    int w = W >= H ? px : (int)ceil(px * W / H), h = H >= W ? px : (int)ceil(px * H / W);
    ss_image *img = ss_image_create(w, h, 3, err);
    if (!img) return NULL;
    const float bg[3] = {0.02f, 0.02f, 0.02f};
    ss_image_fill(img, bg);
    const double sc = w / W;
    const int nn = m->mesh->nnodes;
    double *speed = malloc((size_t)nn * sizeof(double));
    if (!speed) {
        ss_image_free(img);
        ss_error_set(err, SS_ERR_NOMEM, "top view: out of memory");
        return NULL;
    }
    double vm = 0;
    for (int i = 0; i < nn; i++) {
        const double *v = m->vel + 3 * i;
        speed[i] = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (speed[i] > vm) vm = speed[i];
    }
    if (vmax <= 0) vmax = vm > 0 ? vm : 1.0;
    const double *x = m->S->x;
    for (int t = 0; t < m->ntri; t++) {
        const int32_t *q = m->tri + 3 * t;
        double X[3], Y[3], S[3];
        for (int k = 0; k < 3; k++) {
            X[k] = x[3 * q[k]] * sc;
            Y[k] = (H - x[3 * q[k] + 1]) * sc; /* image row 0 at the top (+y) */
            S[k] = speed[q[k]] / vmax;
        }
        double den = (Y[1] - Y[2]) * (X[0] - X[2]) + (X[2] - X[1]) * (Y[0] - Y[2]);
        if (fabs(den) < 1e-12) continue;
        int x0 = (int)floor(fmin(X[0], fmin(X[1], X[2]))),
            x1 = (int)ceil(fmax(X[0], fmax(X[1], X[2])));
        int y0 = (int)floor(fmin(Y[0], fmin(Y[1], Y[2]))),
            y1 = (int)ceil(fmax(Y[0], fmax(Y[1], Y[2])));
        if (x0 < 0) x0 = 0;
        if (y0 < 0) y0 = 0;
        if (x1 > w - 1) x1 = w - 1;
        if (y1 > h - 1) y1 = h - 1;
        for (int yy = y0; yy <= y1; yy++)
            for (int xx = x0; xx <= x1; xx++) {
                double cx = xx + 0.5, cy = yy + 0.5;
                double l0 = ((Y[1] - Y[2]) * (cx - X[2]) + (X[2] - X[1]) * (cy - Y[2])) / den;
                double l1 = ((Y[2] - Y[0]) * (cx - X[2]) + (X[0] - X[2]) * (cy - Y[2])) / den;
                double l2 = 1 - l0 - l1;
                if (l0 < -1e-9 || l1 < -1e-9 || l2 < -1e-9) continue;
                float rgb[3];
                ramp(l0 * S[0] + l1 * S[1] + l2 * S[2], rgb);
                memcpy(ss_image_px(img, xx, yy), rgb, sizeof rgb);
            }
    }
    /* the deformed wound outline: edges of wound triangles not shared with
     * another wound triangle */
    for (int t = 0; t < m->ntri; t++) {
        if (!m->tri_wound[t]) continue;
        for (int k = 0; k < 3; k++) {
            int a = m->tri[3 * t + k], b = m->tri[3 * t + (k + 1) % 3];
            int shared = 0;
            for (int u = 0; u < m->ntri && !shared; u++) {
                if (u == t || !m->tri_wound[u]) continue;
                const int32_t *r = m->tri + 3 * u;
                int ha = r[0] == a || r[1] == a || r[2] == a;
                int hb = r[0] == b || r[1] == b || r[2] == b;
                shared = ha && hb;
            }
            if (shared) continue;
            /* on a stepped surface (a patch of a curved body) a step's riser
             * separates two wound triangles: an outline edge has intact skin
             * on its far side (the reference footprint half a lattice cube
             * across, where the neighbouring square's centre is, the point
             * ss_mech_create classified the triangles by) */
            const double *A = m->mesh->x + 3 * a, *B = m->mesh->x + 3 * b;
            double mx = 0.5 * (A[0] + B[0]), my = 0.5 * (A[1] + B[1]);
            double nx_ = B[1] - A[1], ny_ = -(B[0] - A[0]), len = hypot(nx_, ny_);
            const int32_t *q = m->tri + 3 * t;
            double cx = 0, cy = 0;
            for (int k2 = 0; k2 < 3; k2++) {
                cx += m->mesh->x[3 * q[k2]] / 3;
                cy += m->mesh->x[3 * q[k2] + 1] / 3;
            }
            if (len > 0 && (mx - cx) * nx_ + (my - cy) * ny_ < 0) nx_ = -nx_, ny_ = -ny_;
            if (len > 0) {
                const double hs = 0.5 * m->p.tet_size_mm;
                if (ss_mech_in_foot(m, mx + hs * nx_ / len, my + hs * ny_ / len)) continue;
            }
            put_line(img, x[3 * a] * sc, (H - x[3 * a + 1]) * sc, x[3 * b] * sc,
                     (H - x[3 * b + 1]) * sc);
        }
    }
    free(speed);
    return img;
}

/* The top view with a colour bar to its right: the ramp from 0 (bottom) to
 * vmax (top) with its end values in mm/day, drawn with cairo (text) on an
 * sRGB canvas and returned linear, as the view itself. */
ss_image *ss_mech_top_view_bar(const ss_mech *m, int px, double vmax, ss_error *err) {
    if (!(vmax > 0)) {
        vmax = 0;
        const int nn = m->mesh->nnodes;
        for (int i = 0; i < nn; i++) {
            const double *v = m->vel + 3 * i;
            double s = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            if (s > vmax) vmax = s;
        }
        if (!(vmax > 0)) vmax = 1.0;
    }
    ss_image *view = ss_mech_top_view(m, px, vmax, err);
    if (!view) return NULL;
    const int bw = 110, W = view->width + bw, H = view->height;
    cairo_surface_t *cs = cairo_image_surface_create(CAIRO_FORMAT_RGB24, W, H);
    if (cairo_surface_status(cs) != CAIRO_STATUS_SUCCESS) {
        cairo_surface_destroy(cs);
        ss_image_free(view);
        ss_error_set(err, SS_ERR_NOMEM, "top view: out of memory");
        return NULL;
    }
    cairo_surface_flush(cs);
    unsigned char *d = cairo_image_surface_get_data(cs);
    const int stride = cairo_image_surface_get_stride(cs);
    const int bx0 = view->width + 14, bx1 = bx0 + 18, by0 = 24, by1 = H - 24;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float rgb[3] = {0.02f, 0.02f, 0.02f};
            if (x < view->width)
                memcpy(rgb, ss_image_px(view, x, y), sizeof rgb);
            else if (x >= bx0 && x < bx1 && y >= by0 && y <= by1)
                ramp((double)(by1 - y) / (by1 - by0), rgb);
            unsigned char *p = d + (size_t)y * (size_t)stride + 4 * (size_t)x;
            for (int c = 0; c < 3; c++) {
                float e = ss_srgb_encode(rgb[c] < 0 ? 0 : rgb[c] > 1 ? 1 : rgb[c]);
                p[2 - c] = (unsigned char)lrintf(e * 255.0f);
            }
            p[3] = 255;
        }
    cairo_surface_mark_dirty(cs);
    cairo_t *cr = cairo_create(cs);
    cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, 13);
    cairo_set_source_rgb(cr, 1, 1, 1);
    char lab[64];
    snprintf(lab, sizeof lab, "%.3g", vmax);
    cairo_move_to(cr, bx1 + 6, by0 + 5);
    cairo_show_text(cr, lab);
    cairo_move_to(cr, bx1 + 6, (by0 + by1) / 2 + 5);
    snprintf(lab, sizeof lab, "%.3g", 0.5 * vmax);
    cairo_show_text(cr, lab);
    cairo_move_to(cr, bx1 + 6, by1 + 5);
    cairo_show_text(cr, "0");
    cairo_move_to(cr, bx0 - 4, 15);
    cairo_show_text(cr, "mm/day");
    cairo_destroy(cr);
    cairo_surface_flush(cs);
    ss_image *out = ss_image_create(W, H, 3, err);
    if (out)
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                const unsigned char *p = d + (size_t)y * (size_t)stride + 4 * (size_t)x;
                float *q = ss_image_px(out, x, y);
                for (int c = 0; c < 3; c++) q[c] = ss_srgb_decode(p[2 - c] / 255.0f);
            }
    cairo_surface_destroy(cs);
    ss_image_free(view);
    return out;
}
