/* skinsim view: internal interfaces of the interactive viewer (seed 000
 * §4.2, §4.4). Three parts, only the last knows GTK:
 *   layers.c  the texture stack the time slider scrubs: layers of packed
 *             RGBA8 maps and the stops (day -> layer) between which a frame
 *             blends; filled from `skinsim abrasion` / `skinsim skin`
 *             output folders or generated from painted strokes;
 *   render.c  OpenGL 3.3 core (libepoxy): the mesh (subdivided once for
 *             displacement), the texture arrays, the blend shader, stroke
 *             points, an offscreen framebuffer for screenshots and benches;
 *   camera.c  orbit/pan/zoom and the ray through a pixel;
 *   app.c     GTK 4 window (GtkGLArea), options, scripts, headless EGL.
 * Nothing here is part of libskinsim: GTK stays out of the library. */
#ifndef SKINSIM_VIEW_H
#define SKINSIM_VIEW_H

#include "skinsim/abrasion.h"
#include "skinsim/mesh.h"
#include "skinsim/paint.h"

/* ---- layers -------------------------------------------------------------- */

#define VIEW_MAX_STOPS 64

/* Two packed RGBA8 maps per layer: cr = sRGB colour + linear reflection
 * (specular strength 0..1) in alpha; nh = tangent-space normal (0..1
 * encoded, OpenGL +Y) + height in alpha (0.5 = skin surface). */
typedef struct view_layers {
    int size, nlayers;
    unsigned char *cr, *nh; /* nlayers * size * size * 4 each */
    /* Mipmap levels 1..nlevels-1 (level l: size >> l, all layers), made on
     * the CPU by view_layers_build_mips so the GL thread only copies. */
    int nlevels;
    unsigned char *cr_mip[16], *nh_mip[16];
    int nstops;
    double stop_day[VIEW_MAX_STOPS];
    int stop_layer[VIEW_MAX_STOPS];
    char stop_name[VIEW_MAX_STOPS][24];
    double end_day;
    double height_mm;  /* height 1 - height 0 in millimetres */
    char source[4200]; /* what the layers were made from, for the title */
    /* A single texture set (`skinsim skin`): its colour, linear RGB, kept
     * so Generate draws the wound on this skin (owned; the app takes it). */
    ss_image *skin;
    /* > 0: the textures cover a block of skin this many mm on a side (a
     * `skinsim wound` or heal run folder), not the mesh's UV layout;
     * view_layers_place_block maps it onto the mesh at that size. */
    double block_mm;
    /* Where view_layers_place_block put it: centre UV, side in UV units,
     * the mesh's mm per UV unit there. */
    double block_uv[2], block_side_uv, mm_per_uv;
    char timing[160]; /* Generate: where its time went */
} view_layers;

void view_layers_free(view_layers *l);
/* For layers.c and generate.c: n layers of size^2 (contents undefined). */
ss_status view_layers_alloc(view_layers *l, int size, int n, ss_error *err);
/* Packs the rectangle x0..x0+w-1, y0..y0+h-1 of one layer from full-size
 * maps. Any map but colour may be NULL (defaults: reflection 0.3, flat
 * normal, height 0.5). colour is linear RGB (or grey). Parallel. */
void view_layers_pack_rect(view_layers *l, int layer, const ss_image *color, const ss_image *refl,
                           const ss_image *height, const ss_image *normal, int x0, int y0, int w,
                           int h);
void view_layers_add_stop(view_layers *l, double day, int layer, const char *name);
/* FNV-1a (64-bit words) over every layer's packed bytes, mipmaps and stops:
 * what --json prints as layers_hash, so two ways of making them can be
 * shown byte-identical. */
uint64_t view_layers_hash(const view_layers *l);
/* Box-filtered mipmap chain down to 1x1 (colour averaged in linear light,
 * the other channels as stored). Parallel; returns SS_ERR_NOMEM on failure
 * (the renderer then lets OpenGL make the levels). */
ss_status view_layers_build_mips(view_layers *l, ss_error *err);
/* Where a day falls: layers a and b and the weight of b. */
void view_layers_locate(const view_layers *l, double day, int *a, int *b, float *w, int *stop);
/* One layer from the procedural healthy skin (what the hand shows before
 * any wound): size x size. */
ss_status view_layers_plain_skin(int size, uint64_t seed, view_layers *out, ss_error *err);
/* From a folder: `skinsim abrasion --out DIR` (timeline.json, keys and the
 * maturation frames) or a single texture set (`skinsim skin`: base_color,
 * roughness or specular, normal, height; or *_color.png and siblings). */
/* A finished `skinsim heal --out DIR` run is rendered first through the
 * `skinsim wound --heal` path (ss_wound_make, into a temporary folder that
 * is removed after loading): every snapshot day up to VIEW_HEAL_MAX_DAYS
 * (evenly thinned beyond), at texture side heal_size. */
#define VIEW_HEAL_MAX_DAYS 16
ss_status view_layers_load_dir(const char *dir, int heal_size, int quiet, view_layers *out,
                               ss_error *err);
/* A block (block_mm > 0) mapped onto the mesh at its world size: every
 * layer becomes a size x size texture of the mesh's UV layout with the
 * procedural healthy skin (seed) and the block pasted, centred on
 * centre_uv (NULL: UV (0.5, 0.5); the viewer passes the surface point in
 * the middle of the start view, the back of the shipped hand) and scaled
 * by the mesh's mm per UV unit in that point's UV island (mesh units are
 * metres), inside that island only, its outer 8 % blended into the skin.
 * island: per triangle (ss_paint's). Does nothing when block_mm == 0. */
ss_status view_layers_place_block(view_layers *l, const ss_mesh *m, const int *island,
                                  const float centre_uv[2], int size, uint64_t seed, ss_error *err);

/* The Generate job: the abrasion timeline from strokes, at size, with
 * maturation re-rendered at extra positions so the slider can blend it.
 * With SKINSIM_VIEW_REFERENCE=1 in the environment it takes the plain
 * path instead (one step after another, every layer packed whole), which
 * gives the same bytes: the e2e test compares the two layers_hash.
 * progress (0..1) is written as it goes (read by the UI thread). skin:
 * the healthy skin colour (linear RGB, any size: a loaded texture set) or
 * NULL for the procedural one, as `skinsim abrasion --upper`. Pure
 * computation: safe in a worker thread. */
ss_status view_layers_generate(const ss_stroke_set *strokes, const ss_image *skin, int size,
                               uint64_t seed, volatile double *progress, view_layers *out,
                               ss_error *err);
/* The mask of the painted wound in UV space (1 inside a hull, 0 outside),
 * size x size, as Generate fills it: what `skinsim abrasion --mask` reads. */
ss_image *view_strokes_mask(const ss_stroke_set *strokes, int size, uint64_t seed, ss_error *err);

/* ---- camera -------------------------------------------------------------- */

typedef struct view_camera {
    float target[3];
    float dist, yaw, pitch; /* radians; orbit around target */
    float fov_y;            /* radians */
    float radius;           /* of the mesh, for clip planes and pan speed */
    int width, height;      /* viewport in pixels */
} view_camera;

/* Looks at the mesh from the side of the back of the hand (the island
 * holding UV (0.5, 0.5)), the whole mesh in view. */
void view_camera_frame(view_camera *c, const ss_mesh *m);
void view_camera_eye(const view_camera *c, float eye[3]);
/* Column-major view-projection matrix. */
void view_camera_matrix(const view_camera *c, float mvp[16]);
/* Ray through window pixel (x, y) (origin top-left), and the camera's right
 * and up vectors (for the brush ring). */
void view_camera_ray(const view_camera *c, double x, double y, float origin[3], float dir[3],
                     float right[3], float up[3]);
void view_camera_orbit(view_camera *c, double dx_px, double dy_px);
void view_camera_pan(view_camera *c, double dx_px, double dy_px);
void view_camera_zoom(view_camera *c, double steps); /* > 0 closer */
/* Surface size of one pixel at distance d (for the brush radius). */
double view_camera_pixel_size(const view_camera *c, double d);

/* ---- renderer ------------------------------------------------------------ */

typedef struct view_renderer view_renderer;

/* Needs a current OpenGL >= 3.3 core context. */
view_renderer *view_renderer_create(const ss_mesh *m, ss_error *err);
void view_renderer_free(view_renderer *r);
/* Replaces the texture arrays (uploaded once; the slider never uploads). */
ss_status view_renderer_set_layers(view_renderer *r, const view_layers *l, ss_error *err);
/* Stroke samples to show (positions with NaN are skipped). */
void view_renderer_set_strokes(view_renderer *r, const ss_paint_sample *s, int n);
/* The brush ring: n points (xyz) of a closed outline on the surface (n = 0:
 * none), white, or red for the eraser. */
void view_renderer_set_ring(view_renderer *r, const float *pts, int n, int eraser);
/* Draws the frame at `day` into the currently bound framebuffer of w x h. */
void view_renderer_draw(view_renderer *r, const view_camera *c, const view_layers *l, double day,
                        float displace_scale, int show_strokes);
/* Offscreen: renders at w x h and reads back RGB8 rows top-first (sRGB
 * encoded) into rgb (w*h*3). */
ss_status view_renderer_offscreen(view_renderer *r, const view_camera *c, const view_layers *l,
                                  double day, float displace_scale, int show_strokes,
                                  unsigned char *rgb, ss_error *err);
/* Times n frames scrubbed across 0..end_day offscreen at w x h (glFinish
 * after each); ms[i] per frame. */
ss_status view_renderer_bench(view_renderer *r, const view_camera *c, const view_layers *l, int n,
                              float displace_scale, double *ms, ss_error *err);
const char *view_renderer_gl_info(view_renderer *r);

#endif
