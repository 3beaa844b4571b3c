/* skinsim geom: wound shapes in texture space. Convex hull by Andrew's monotone
 * chain (seed 000 Alg. 4.1, Eq. 4.4), concave hull by k-nearest neighbours
 * (Moreira & Santos 2007, named in seed 000 §5.1), polygon fill by scanlines
 * (seed 000 §5.1 Fig. 5.1; brute force Alg. 4.2 kept for tests), closing
 * distance (Alg. 4.3), distance from pixels to a polygon outline (Alg. 3.3),
 * exact Euclidean distance transform. Coordinates are pixels unless stated. */
#ifndef SKINSIM_GEOM_H
#define SKINSIM_GEOM_H

#include "skinsim/core.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct ss_vec2 {
    double x, y;
} ss_vec2;

/* A closed polygon (last vertex connects to the first). */
typedef struct ss_polygon {
    int count;
    ss_vec2 *pts;
} ss_polygon;

void ss_polygon_free(ss_polygon *poly); /* frees pts, zeroes the struct */

/* Convex hull of n points, clockwise in a y-down image frame as the seed's
 * Alg. 4.1 returns it. Duplicates and collinear points are dropped. Fewer than
 * 3 distinct non-collinear points is an input error. Precisely: the shoelace
 * area in raw pixel coordinates (x right, y down) is positive (clockwise as
 * seen on the image), every vertex turns with Eq. 4.4 det > 0, and a point
 * is inside when it is on no edge's Eq. 4.4 "right side" (det < 0), the test
 * of Alg. 4.2. The caller frees out with ss_polygon_free. */
ss_status ss_convex_hull(const ss_vec2 *pts, int n, ss_polygon *out, ss_error *err);
/* Concave hull with k nearest neighbours (k >= 3; k is raised automatically
 * until every point is inside, falling back to the convex hull). Starts at
 * the lowest-y point; k below 3 is taken as 3. Same orientation as
 * ss_convex_hull; the result is a simple polygon through input points with
 * every input point inside or on it. O(n^2) per attempt. */
ss_status ss_concave_hull(const ss_vec2 *pts, int n, int k, ss_polygon *out, ss_error *err);

/* Fill: sets mask pixels whose centre (x+0.5, y+0.5) is inside the polygon to
 * 1 (others untouched). Works for any simple polygon (even-odd rule). All
 * channels of a pixel are set. Parallel over rows. */
void ss_polygon_fill(const ss_polygon *poly, ss_image *mask);
/* The seed's Alg. 4.2 (bounding box + right-side test per edge), for convex
 * hulls only; used by tests as the brute-force reference. Like the seed it
 * writes 0 to the bounding-box pixels that are outside; either winding. */
void ss_polygon_fill_bruteforce(const ss_polygon *poly, ss_image *mask);

/* Alg. 4.3: the largest distance between two hull vertices. */
double ss_closing_distance(const ss_polygon *poly);

/* Alg. 3.3: distance from p to segment a-b. */
double ss_segment_distance(ss_vec2 a, ss_vec2 b, ss_vec2 p);
/* Distance from every pixel centre to the nearest outline edge of the
 * polygons (brute force over all edges, as seed Alg. 3.4 does). 1 channel
 * (channel 0 is written). +INFINITY where there is no edge at all. */
void ss_outline_distance_bruteforce(const ss_polygon *polys, int npolys, ss_image *dist);
/* Same result, cost independent of edge count: exact for pixel centres
 * within max_dist of the outline (beyond it the value is only guaranteed
 * to be > max_dist). Uses a distance transform to find candidate edges.
 * "Exact" means bit-identical to ss_outline_distance_bruteforce. Beyond
 * max_dist the value is a lower bound of the true distance that is still
 * > max_dist. max_dist = INFINITY asks for exact values everywhere. dist
 * must be 1 channel; max_dist < 0 or NaN and malformed polygons are input
 * errors. Memory: about (W + 2 max_dist)(H + 2 max_dist) * 9 bytes. */
ss_status ss_outline_distance(const ss_polygon *polys, int npolys, double max_dist, ss_image *dist,
                              ss_error *err);

/* Exact Euclidean distance transform (Felzenszwalb & Huttenlocher): for each
 * pixel, distance to the nearest pixel whose src value is > 0.5. Reads
 * channel 0 of src; dist must be 1 channel of the same size. +INFINITY when
 * no pixel is set. Bit-identical for any thread count. */
ss_status ss_distance_transform(const ss_image *src, ss_image *dist, ss_error *err);

/* ---- painted strokes (CSV) -----------------------------------------------
 * Format shared with `skinsim abrasion`: one point per line, `u,v` or
 * `u,v,stroke_id`; u, v are texture coordinates in [0,1] (u to the right, v
 * down, as image rows); stroke_id is a non-negative integer (default 0). An
 * optional first line that is not numeric is a header; blank lines and lines
 * starting with '#' are ignored; fields may be surrounded by spaces. Errors
 * (SS_ERR_INPUT, message names file and line): NaN/inf or non-numbers, u or v
 * outside [0,1], a negative or non-integer id, a wrong field count, no points,
 * any stroke with fewer than 3 points. Points keep file order. */
typedef struct ss_stroke_set {
    int npoints;
    double *u, *v;   /* npoints each */
    int *stroke;     /* npoints stroke ids */
    int nstrokes;    /* distinct ids */
    int *stroke_ids; /* the distinct ids, ascending */
} ss_stroke_set;
ss_status ss_stroke_csv_read(const char *path, ss_stroke_set *out, ss_error *err);
/* Same, from a NUL-terminated buffer; `name` is used in messages. */
ss_status ss_stroke_csv_parse(const char *text, const char *name, ss_stroke_set *out,
                              ss_error *err);
void ss_stroke_set_free(ss_stroke_set *s); /* frees arrays and zeroes the struct */
/* One hull per stroke (in stroke_ids order), points scaled to width x
 * height: convex (concave_k == 0) or k-nearest concave (>= 3). *out holds
 * nstrokes polygons; free each and the array. Errors name the stroke,
 * prefixed by name unless it is NULL. */
ss_status ss_stroke_hulls(const ss_stroke_set *s, double width, double height, int concave_k,
                          const char *name, ss_polygon **out, ss_error *err);
/* Footprint of a stroke set: each stroke's points (u*width, v*height pixels)
 * get a hull (concave_k == 0: convex hull, ss_convex_hull; >= 3: k-nearest
 * concave hull, ss_concave_hull) filled with ss_polygon_fill into a
 * width x height 1-channel 0/1 image. Hull errors (e.g. all points collinear)
 * are SS_ERR_INPUT naming the stroke. */
ss_image *ss_stroke_footprint(const ss_stroke_set *s, int width, int height, int concave_k,
                              const char *name, ss_error *err);

/* Corners rounded (src/geom/round.c): every vertex of `in` replaced by the
 * circular fillet of radius `radius` (pixels) tangent to both edges, its
 * tangent points clamped to half of each adjacent edge (the radius shrinks
 * with them), sampled within 0.05 px of the circle. Orientation and the first
 * vertex's place are kept; radius 0 copies the polygon. The caller frees out.
 * Fewer than 3 vertices or a negative or non-finite radius: SS_ERR_INPUT. */
ss_status ss_polygon_round(const ss_polygon *in, double radius, ss_polygon *out, ss_error *err);
/* The fraction of a hull's closing distance (Alg. 4.3) that `skinsim
 * abrasion` and a mesh's `--wound-uv` strokes round its corners by. */
#define SS_STROKE_ROUND 0.15
/* ss_stroke_hulls with every hull's corners rounded by round x its closing
 * distance (round in [0, 0.5]; 0 is ss_stroke_hulls). */
ss_status ss_stroke_outlines(const ss_stroke_set *s, double width, double height, int concave_k,
                             double round, const char *name, ss_polygon **out, ss_error *err);
/* ss_stroke_footprint of the rounded outlines (round 0: the same image). */
ss_image *ss_stroke_footprint_rounded(const ss_stroke_set *s, int width, int height, int concave_k,
                                      double round, const char *name, ss_error *err);

/* ---- glTF -------------------------------------------------------------- */

/* A glTF 2.0 file showing a texture set on a square of side_m metres (XY
 * plane, facing +Z, UV (0,0) at the top-left): glTF metallic-roughness
 * material with the given texture URIs (relative to the .gltf; any may be
 * NULL). Geometry embedded; written atomically. */
ss_status ss_gltf_write_textured_square(const char *path, double side_m, const char *name,
                                        const char *base_color_uri,
                                        const char *metallic_roughness_uri, const char *normal_uri,
                                        ss_error *err);
/* The same material on a mesh's own UVs (include/skinsim/mesh.h; positions
 * in the mesh's units, glTF: metres), with per-vertex tangents derived from
 * the UVs for the normal map. The mesh needs UVs. */
struct ss_mesh;
ss_status ss_gltf_write_textured_mesh(const char *path, const struct ss_mesh *mesh,
                                      const char *name, const char *base_color_uri,
                                      const char *metallic_roughness_uri, const char *normal_uri,
                                      ss_error *err);

/* A mesh with per-vertex data as one binary glTF 2.0 file (.glb), for any
 * glTF viewer or Blender: POSITION (mesh units x scale_m, glTF metres),
 * NORMAL, TEXCOORD_0 when the mesh has UVs, COLOR_0 (linear RGB, optional),
 * application-specific float attributes (names must start with '_', as the
 * glTF spec asks; 1-4 components), and optionally one morph target (a
 * POSITION delta in mesh units, shown at weight morph_weight; its name in
 * mesh.extras.targetNames, where Blender and three.js look). extras_json, a
 * JSON object's text or NULL, becomes the node's extras. Atomic. */
typedef struct ss_gltf_vertex_attr {
    const char *name;  /* "_EPITHELIUM" */
    const float *data; /* nvertices x ncomp */
    int ncomp;         /* 1 (SCALAR) .. 4 (VEC4) */
} ss_gltf_vertex_attr;
typedef struct ss_gltf_vertex_data {
    double scale_m;     /* one mesh unit in metres (> 0) */
    const char *name;   /* node, mesh and material name; NULL = "skin" */
    const float *color; /* nvertices x 3 linear RGB in 0..1, or NULL */
    const ss_gltf_vertex_attr *attrs;
    int nattrs;
    const float *morph_delta; /* nvertices x 3 in mesh units, or NULL */
    const char *morph_name;   /* NULL = "displacement" */
    double morph_weight;      /* default weight of the target, 0..1 */
    const char *extras_json;  /* the node's extras, or NULL */
} ss_gltf_vertex_data;
ss_status ss_gltf_write_mesh_glb(const char *path, const struct ss_mesh *mesh,
                                 const ss_gltf_vertex_data *d, ss_error *err);

#ifdef __cplusplus
}
#endif
#endif
