/* Contact sheets: images side by side, each with a text label under it,
 * drawn with cairo (text) on an sRGB canvas; returned as a linear image so it
 * is written like any other colour image. */
#include "skinsim/core.h"

#include <cairo.h>
#include <math.h>
#include <string.h>

/* Box-filtered (area-average) downsample of one tile into the canvas. */
static void blit(unsigned char *canvas, int stride, int ox, int oy, int tw, int th,
                 const ss_image *img) {
    for (int y = 0; y < th; y++) {
        int y0 = (int)((long)y * img->height / th), y1 = (int)((long)(y + 1) * img->height / th);
        if (y1 <= y0) y1 = y0 + 1;
        for (int x = 0; x < tw; x++) {
            int x0 = (int)((long)x * img->width / tw), x1 = (int)((long)(x + 1) * img->width / tw);
            if (x1 <= x0) x1 = x0 + 1;
            double acc[3] = {0, 0, 0};
            int cnt = 0;
            for (int yy = y0; yy < y1; yy++)
                for (int xx = x0; xx < x1; xx++) {
                    const float *p = ss_image_px(img, xx, yy);
                    for (int c = 0; c < 3; c++) acc[c] += p[img->channels >= 3 ? c : 0];
                    cnt++;
                }
            unsigned char *d = canvas + (size_t)(oy + y) * (size_t)stride + (size_t)(ox + x) * 4;
            unsigned char rgb[3];
            for (int c = 0; c < 3; c++)
                rgb[c] = (unsigned char)lrintf(ss_srgb_encode((float)(acc[c] / cnt)) * 255.0f);
            d[0] = rgb[2]; /* cairo ARGB32 is B,G,R,A in memory on little-endian */
            d[1] = rgb[1];
            d[2] = rgb[0];
            d[3] = 255;
        }
    }
}

ss_image *ss_contact_sheet(const ss_image *const *tiles, const char *const *labels, int n,
                           int tile_px, int columns, ss_error *err) {
    if (n < 1 || tile_px < 8 || columns < 1) {
        ss_error_set(err, SS_ERR_INPUT, "contact sheet: need >= 1 tile of >= 8 px");
        return NULL;
    }
    if (columns > n) columns = n;
    int rows = (n + columns - 1) / columns, pad = tile_px / 16 + 4, label_h = tile_px / 8 + 12;
    int W = columns * (tile_px + pad) + pad, H = rows * (tile_px + label_h + pad) + pad;
    cairo_surface_t *surf = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, W, H);
    if (cairo_surface_status(surf) != CAIRO_STATUS_SUCCESS) {
        cairo_surface_destroy(surf);
        ss_error_set(err, SS_ERR_NOMEM, "contact sheet: cannot create a %dx%d canvas", W, H);
        return NULL;
    }
    cairo_t *cr = cairo_create(surf);
    cairo_set_source_rgb(cr, 0.12, 0.12, 0.12);
    cairo_paint(cr);
    cairo_surface_flush(surf);
    unsigned char *px = cairo_image_surface_get_data(surf);
    int stride = cairo_image_surface_get_stride(surf);
    for (int i = 0; i < n; i++) {
        int ox = pad + (i % columns) * (tile_px + pad),
            oy = pad + (i / columns) * (tile_px + label_h + pad);
        int tw = tile_px, th = tile_px;
        if (tiles[i]->width >= tiles[i]->height)
            th = (int)((long)tile_px * tiles[i]->height / tiles[i]->width);
        else
            tw = (int)((long)tile_px * tiles[i]->width / tiles[i]->height);
        blit(px, stride, ox, oy, tw > 0 ? tw : 1, th > 0 ? th : 1, tiles[i]);
    }
    cairo_surface_mark_dirty(surf);
    cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
    cairo_set_font_size(cr, label_h * 0.55);
    cairo_set_source_rgb(cr, 0.95, 0.95, 0.95);
    for (int i = 0; i < n; i++) {
        if (!labels || !labels[i]) continue;
        int ox = pad + (i % columns) * (tile_px + pad),
            oy = pad + (i / columns) * (tile_px + label_h + pad);
        cairo_text_extents_t ext;
        cairo_text_extents(cr, labels[i], &ext);
        cairo_move_to(cr, ox + (tile_px - ext.width) / 2 - ext.x_bearing,
                      oy + tile_px + label_h * 0.72);
        cairo_show_text(cr, labels[i]);
    }
    cairo_surface_flush(surf);
    ss_image *out = ss_image_create(W, H, 3, err);
    if (out) {
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                const unsigned char *d = px + (size_t)y * (size_t)stride + (size_t)x * 4;
                float *o = ss_image_px(out, x, y);
                o[0] = ss_srgb_decode(d[2] / 255.0f);
                o[1] = ss_srgb_decode(d[1] / 255.0f);
                o[2] = ss_srgb_decode(d[0] / 255.0f);
            }
    }
    cairo_destroy(cr);
    cairo_surface_destroy(surf);
    return out;
}
