/* skinsim paint: painting wound strokes on a mesh (seed 000 §4.2.1). A ray
 * from the camera through the mouse hits a triangle; its barycentric
 * coordinates give the UV (Eq. 4.1-4.3) that is recorded. A brush of a
 * radius on the surface adds a ring of samples around each hit, so a single
 * click still makes a hull. A stroke never spans two UV islands: when the
 * brush crosses a seam the stroke is split and continues under a new id in
 * the other island, so no hull is ever drawn across the seam. No toolkit,
 * no OpenGL: the viewer feeds rays, tests and scripts can too. */
#ifndef SKINSIM_PAINT_H
#define SKINSIM_PAINT_H

#include "skinsim/geom.h"
#include "skinsim/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct ss_paint_sample {
    float uv[2];
    float pos[3]; /* surface point (for display); NaN when unknown */
    int stroke;   /* stroke id: one UV island, one hull */
    int group;    /* one press-drag-release; undo removes a group */
    int island;
} ss_paint_sample;

typedef struct ss_paint {
    const ss_mesh *mesh; /* not owned; must outlive the session */
    ss_bvh *bvh;
    int *island; /* per triangle */
    int nislands;
    ss_paint_sample *s;
    int n, cap;
    int next_stroke, next_group;
    int cur_group, cur_stroke, cur_island; /* cur_group < 0: not painting */
    double brush_radius;                   /* on the surface, mesh units */
    int ring;                              /* ring samples per hit (default 8) */
    /* the last centre hit of the current stroke: where its UV continuity
     * is judged from (triangle, surface point, UV) */
    int cur_tri;
    float cur_pos[3], cur_uv[2];
} ss_paint;

/* A session on mesh m (which needs UVs: a mesh without them is an input
 * error saying so). brush_radius in mesh units (> 0, finite). */
ss_status ss_paint_create(const ss_mesh *m, double brush_radius, ss_paint *p, ss_error *err);
void ss_paint_free(ss_paint *p);

/* Starts a group (mouse press), adds samples (press and every motion),
 * ends it (release). add returns 1 when the ray hit the mesh. right[3] and
 * up[3] span the plane the brush ring lies in as seen (the camera's right
 * and up vectors); the ring points are cast as rays parallel to dir
 * through hit + radius * (cos a right + sin a up), and only those that land
 * in the island of the centre hit are kept. */
void ss_paint_begin(ss_paint *p);
int ss_paint_add(ss_paint *p, const float origin[3], const float dir[3], const float right[3],
                 const float up[3], ss_ray_hit *hit);
void ss_paint_end(ss_paint *p);
/* Removes the last group; returns 0 when there was none. */
int ss_paint_undo(ss_paint *p);
void ss_paint_clear(ss_paint *p);

/* The strokes as geom's stroke set (ids renumbered 0..k-1 in order). A
 * stroke with fewer than 3 distinct points cannot make a hull and is left
 * out (*dropped counts them). No stroke left is an input error. */
ss_status ss_paint_to_strokes(const ss_paint *p, ss_stroke_set *out, int *dropped, ss_error *err);
/* Writes the CSV that `skinsim abrasion --stroke` reads (header
 * "u,v,stroke"), atomically. */
ss_status ss_paint_save_csv(const ss_paint *p, const char *path, int *dropped, ss_error *err);
/* Replaces the strokes with those of a CSV file (read with
 * ss_stroke_csv_read, so UVs outside 0..1 are refused naming the line).
 * Each point is placed on the surface by finding the triangle that holds
 * its UV; *outside counts points in no triangle (a file made for another
 * mesh), which are kept but have no position. */
ss_status ss_paint_load_csv(ss_paint *p, const char *path, int *outside, ss_error *err);

/* The triangle whose UV triangle contains uv (-1 if none) and the surface
 * point there. Linear in the triangle count. */
int ss_mesh_locate_uv(const ss_mesh *m, const float uv[2], float pos[3]);

#ifdef __cplusplus
}
#endif
#endif
