/* skinsim mesh: triangle meshes read from OBJ and glTF 2.0 (.gltf/.glb), their
 * UV islands, and a bounding volume hierarchy for ray casting. The painter
 * (seed 000 §4.2) turns a mouse ray into the hit triangle's barycentric
 * coordinates and from them a UV, the input of the hull (Alg. 4.1); other
 * modules use the same reader to put textures and mechanics on real bodies.
 *
 * UV convention: u to the right, v down, (0,0) at the top-left of the image,
 * as glTF and skinsim's images and stroke files have it. OBJ stores v up; the
 * reader flips it (v = 1 - v_obj) so every mesh speaks the same convention. */
#ifndef SKINSIM_MESH_H
#define SKINSIM_MESH_H

#include "skinsim/core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* An indexed triangle mesh. Vertices are unique (position, normal, UV)
 * combinations: a UV seam or a hard edge duplicates the position. */
typedef struct ss_mesh {
    int nvertices, ntriangles;
    float *positions;   /* 3 per vertex, in the file's units (glTF: metres) */
    float *normals;     /* 3 per vertex, unit length; computed when the file has none */
    float *uvs;         /* 2 per vertex; NULL when has_uvs == 0 */
    uint32_t *indices;  /* 3 per triangle, counter-clockwise front faces */
    int has_uvs;        /* every triangle corner had a texture coordinate */
    int normals_loaded; /* 1: normals from the file; 0: computed (area-weighted) */
    float bbox_min[3], bbox_max[3];
} ss_mesh;

/* Loads a mesh, choosing the reader by extension (.obj, .gltf, .glb; case
 * insensitive). OBJ: v/vt/vn/f (polygons fanned, negative indices, any of
 * the v, v/t, v//n, v/t/n forms; other statements ignored). glTF 2.0:
 * triangles, strips and fans, indexed or not; POSITION, NORMAL and
 * TEXCOORD_0 (float or normalised integers); buffers from the GLB BIN chunk,
 * base64 data URIs or files next to the .gltf; the default scene's node
 * transforms applied (a skinned mesh is kept in its bind pose, as the glTF
 * spec says to ignore the skinned node's own transform). Points and lines
 * are skipped. A mesh whose triangles lack UVs loads with has_uvs = 0: the
 * caller decides whether that is an error. Errors are SS_ERR_INPUT naming
 * the file and what is wrong (missing, truncated, out-of-range index, no
 * triangles, non-finite value, unsupported feature such as sparse
 * accessors or Draco compression); *out is then zeroed. */
ss_status ss_mesh_load(const char *path, ss_mesh *out, ss_error *err);
/* Builds a mesh from arrays (copied; uvs and normals may be NULL), checking
 * indices and finiteness; used by the readers and by tests. */
ss_status ss_mesh_from_arrays(const float *positions, const float *normals, const float *uvs,
                              int nvertices, const uint32_t *indices, int ntriangles,
                              const char *name, ss_mesh *out, ss_error *err);
void ss_mesh_free(ss_mesh *m); /* frees the arrays and zeroes the struct */

/* ---- wound meshes: the strict OBJ dialect (src/geom/mesh_obj.c) ---------------
 * Closed meshes in double precision (the healing grid's --wound-mesh):
 * `v x y z [w]`, `f` with `i`, `i/t`, `i//n`, `i/t/n` forms, negative
 * (relative) indices, polygons triangulated as fans; other statements (vt, vn,
 * o, g, s, usemtl, mtllib, l) are ignored, unknown ones refused. Errors name
 * file and line. */
typedef struct ss_tri_mesh {
    int nverts, ntris;
    double *v; /* 3*nverts, x y z */
    int *tri;  /* 3*ntris vertex indices (0-based) */
    int *line; /* ntris: OBJ line of the face each triangle came from */
} ss_tri_mesh;
ss_status ss_obj_read(const char *path, ss_tri_mesh *out, ss_error *err);
ss_status ss_obj_parse(const char *text, const char *name, ss_tri_mesh *out, ss_error *err);
void ss_tri_mesh_free(ss_tri_mesh *m);
/* Closed = every undirected edge is used by an even, non-zero number of
 * triangles and no triangle is degenerate (repeated vertex). Otherwise
 * SS_ERR_INPUT naming `name` and the OBJ line of an offending face. */
ss_status ss_tri_mesh_check_closed(const ss_tri_mesh *m, const char *name, ss_error *err);

/* UV islands: triangles joined through corners with identical UV coordinates
 * form one island. island[t] (ntriangles entries, caller-allocated) gets
 * 0..n-1, numbered in order of each island's first triangle. Returns n, or
 * -1 when the mesh has no UVs or memory runs out. */
int ss_mesh_uv_islands(const ss_mesh *m, int *island);

/* UV triangle rasteriser (src/geom/uvraster.c): for every triangle t in file
 * order, fn(x, y, t, b0, b1, b2, ctx) for every texel of the width x height
 * texture whose centre (x + 0.5, y + 0.5) lies in the triangle's UVs (within
 * 1e-9 in barycentrics, so texels on a shared edge are visited by both
 * triangles); b0..b2 weigh its corners indices[3t..3t+2]. Degenerate and
 * non-finite UV triangles are skipped. The mesh needs UVs. */
typedef void (*ss_uv_texel_fn)(int x, int y, int tri, double b0, double b1, double b2, void *ctx);
void ss_uv_triangle_raster(const ss_mesh *m, int width, int height, ss_uv_texel_fn fn, void *ctx);

/* UV coverage: mask[y * width + x] (caller-allocated) = 1 where the texel
 * centre lies in a UV triangle, else 0. No UVs -> SS_ERR_INPUT.
 * (src/geom/uvpad.c) */
ss_status ss_mesh_uv_coverage(const ss_mesh *m, int width, int height, unsigned char *mask,
                              ss_error *err);

/* UV padding: every texel with inside == 0 whose nearest texel with
 * inside != 0 (Euclidean, in texels; ties to the lower column, then row) is
 * at most n texels away takes that texel's value; texels with inside != 0
 * and those farther away are unchanged. Bit-identical for any thread count.
 * n <= 0 does nothing. */
ss_status ss_image_pad_islands(ss_image *img, const unsigned char *inside, int n, ss_error *err);

/* Vertices closer than SS_WELD_REL times the bounding box's diagonal are
 * one (seams duplicate positions, exporters round them differently). */
#define SS_WELD_REL 1e-6
/* weld[v] (n entries, caller-allocated): the lowest index of the points
 * joined to v by chains of distances <= SS_WELD_REL x the diagonal. */
ss_status ss_weld_positions(int n, const double *xyz, int *weld, ss_error *err);
/* The same for a mesh's vertices (seams duplicate positions). */
ss_status ss_mesh_weld(const ss_mesh *m, int *weld, ss_error *err);
/* Refines the triangles with a corner within radius of centre (mesh units):
 * split 1-to-4 at their edge midpoints while an edge is longer than
 * max_edge, at most max_levels times, with the neighbours split 1-to-2 (or
 * 1-to-4) so no T-junction opens the surface; edges are matched by welded
 * position, so seams stay closed. New vertices lie on the old triangles
 * (shape unchanged), normals and UVs interpolated. Old vertices keep their
 * indices. *out is a new mesh (free with ss_mesh_free). */
ss_status ss_mesh_refine_near(const ss_mesh *m, const float centre[3], float radius, float max_edge,
                              int max_levels, ss_mesh *out, ss_error *err);

/* ---- ray casting ------------------------------------------------------- */

/* A BVH over the mesh's triangles (binned surface-area heuristic, at most 4
 * triangles per leaf). It keeps a pointer to the mesh, which must outlive it
 * and not change. */
typedef struct ss_bvh ss_bvh;

typedef struct ss_ray_hit {
    int triangle; /* index into m->indices / 3; -1 for no hit */
    float t;      /* hit point = origin + t * dir */
    float b1, b2; /* barycentrics of corners 1 and 2 (corner 0: 1 - b1 - b2) */
    float uv[2];  /* interpolated UV (0 when the mesh has none) */
} ss_ray_hit;

ss_bvh *ss_bvh_build(const ss_mesh *m, ss_error *err);
void ss_bvh_free(ss_bvh *b);
/* Nearest hit with t in (tmin, tmax], both faces. Returns 1 on a hit and
 * fills *hit, else 0 (hit->triangle = -1). Equal t: the lower triangle index
 * wins, so the result equals ss_mesh_raycast_bruteforce exactly. */
int ss_bvh_raycast(const ss_bvh *b, const float origin[3], const float dir[3], float tmin,
                   float tmax, ss_ray_hit *hit);
/* The same by testing every triangle: the reference for tests. */
int ss_mesh_raycast_bruteforce(const ss_mesh *m, const float origin[3], const float dir[3],
                               float tmin, float tmax, ss_ray_hit *hit);
/* Depth of the tree and node count, for tests and benchmarks. */
void ss_bvh_stats(const ss_bvh *b, int *nodes, int *depth);

#ifdef __cplusplus
}
#endif
#endif
