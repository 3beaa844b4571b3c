/* The orbit camera of glTF viewers: drag rotates around a target, shift-drag
 * (or the middle/right button) pans, the wheel zooms. Perspective, +Y up,
 * yaw around Y and pitch limited short of the poles so "up" stays up. The
 * first view looks at the back of the hand: the mean normal of the UV
 * island that holds UV (0.5, 0.5), where the built-in wound lies. */
#include "view.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void normalize3(float *v) {
    float l = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (l > 0)
        for (int k = 0; k < 3; k++) v[k] /= l;
}

static void cross3(const float *a, const float *b, float *o) {
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

void view_camera_eye(const view_camera *c, float eye[3]) {
    eye[0] = c->target[0] + c->dist * cosf(c->pitch) * sinf(c->yaw);
    eye[1] = c->target[1] + c->dist * sinf(c->pitch);
    eye[2] = c->target[2] + c->dist * cosf(c->pitch) * cosf(c->yaw);
}

/* Camera basis: forward f (eye -> target), right r, up u. */
static void basis(const view_camera *c, float f[3], float r[3], float u[3]) {
    float eye[3];
    view_camera_eye(c, eye);
    for (int k = 0; k < 3; k++) f[k] = c->target[k] - eye[k];
    normalize3(f);
    const float wup[3] = {0, 1, 0};
    cross3(f, wup, r);
    normalize3(r);
    cross3(r, f, u);
}

void view_camera_frame(view_camera *c, const ss_mesh *m) {
    float dir[3] = {0, 0, 1};
    c->radius = 0;
    for (int k = 0; k < 3; k++) {
        c->target[k] = 0.5f * (m->bbox_min[k] + m->bbox_max[k]);
        float e = 0.5f * (m->bbox_max[k] - m->bbox_min[k]);
        c->radius += e * e;
    }
    c->radius = sqrtf(c->radius);
    if (!(c->radius > 0)) c->radius = 1;
    const float centre[2] = {0.5f, 0.5f};
    int t0 = m->has_uvs ? ss_mesh_locate_uv(m, centre, NULL) : -1;
    int *isl = t0 >= 0 ? malloc(sizeof *isl * (size_t)m->ntriangles) : NULL;
    if (isl && ss_mesh_uv_islands(m, isl) >= 0) {
        double acc[3] = {0, 0, 0};
        for (int t = 0; t < m->ntriangles; t++) {
            if (isl[t] != isl[t0]) continue;
            const uint32_t *ix = m->indices + 3 * (size_t)t;
            const float *a = m->positions + 3 * (size_t)ix[0],
                        *b = m->positions + 3 * (size_t)ix[1],
                        *cc = m->positions + 3 * (size_t)ix[2];
            float e1[3], e2[3], n[3];
            for (int k = 0; k < 3; k++) e1[k] = b[k] - a[k], e2[k] = cc[k] - a[k];
            cross3(e1, e2, n);
            for (int k = 0; k < 3; k++) acc[k] += n[k];
        }
        double l = sqrt(acc[0] * acc[0] + acc[1] * acc[1] + acc[2] * acc[2]);
        if (l > 0)
            for (int k = 0; k < 3; k++) dir[k] = (float)(acc[k] / l);
    }
    free(isl);
    c->yaw = atan2f(dir[0], dir[2]);
    c->pitch = asinf(dir[1] < -0.95f ? -0.95f : dir[1] > 0.95f ? 0.95f : dir[1]);
    c->fov_y = 0.6f;
    c->dist = 0.95f * c->radius / sinf(0.5f * c->fov_y);
}

void view_camera_matrix(const view_camera *c, float mvp[16]) {
    float f[3], r[3], u[3], eye[3];
    basis(c, f, r, u);
    view_camera_eye(c, eye);
    float aspect = c->height > 0 ? (float)c->width / (float)c->height : 1.0f;
    float zn = fmaxf(c->dist - 2.5f * c->radius, c->radius * 0.01f),
          zf = c->dist + 2.5f * c->radius;
    float t = 1.0f / tanf(0.5f * c->fov_y);
    /* view (rows r, u, -f) then perspective, column-major */
    float v[16] = {r[0],
                   u[0],
                   -f[0],
                   0,
                   r[1],
                   u[1],
                   -f[1],
                   0,
                   r[2],
                   u[2],
                   -f[2],
                   0,
                   -(r[0] * eye[0] + r[1] * eye[1] + r[2] * eye[2]),
                   -(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2]),
                   (f[0] * eye[0] + f[1] * eye[1] + f[2] * eye[2]),
                   1};
    float p[16] = {0};
    p[0] = t / aspect;
    p[5] = t;
    p[10] = (zf + zn) / (zn - zf);
    p[11] = -1;
    p[14] = 2 * zf * zn / (zn - zf);
    for (int col = 0; col < 4; col++)
        for (int row = 0; row < 4; row++) {
            float s = 0;
            for (int k = 0; k < 4; k++) s += p[k * 4 + row] * v[col * 4 + k];
            mvp[col * 4 + row] = s;
        }
}

void view_camera_ray(const view_camera *c, double x, double y, float origin[3], float dir[3],
                     float right[3], float up[3]) {
    float f[3];
    basis(c, f, right, up);
    view_camera_eye(c, origin);
    float t = tanf(0.5f * c->fov_y);
    float aspect = c->height > 0 ? (float)c->width / (float)c->height : 1.0f;
    float nx = (float)(2.0 * (x + 0.5) / (c->width > 0 ? c->width : 1) - 1.0);
    float ny = (float)(1.0 - 2.0 * (y + 0.5) / (c->height > 0 ? c->height : 1));
    for (int k = 0; k < 3; k++) dir[k] = f[k] + nx * t * aspect * right[k] + ny * t * up[k];
    normalize3(dir);
}

void view_camera_orbit(view_camera *c, double dx, double dy) {
    c->yaw -= (float)(dx * 0.01);
    c->pitch += (float)(dy * 0.01);
    if (c->pitch > 1.5f) c->pitch = 1.5f;
    if (c->pitch < -1.5f) c->pitch = -1.5f;
}

void view_camera_pan(view_camera *c, double dx, double dy) {
    float f[3], r[3], u[3];
    basis(c, f, r, u);
    double s = view_camera_pixel_size(c, c->dist);
    for (int k = 0; k < 3; k++) c->target[k] += (float)(-dx * s * r[k] + dy * s * u[k]);
}

void view_camera_zoom(view_camera *c, double steps) {
    c->dist *= (float)pow(0.9, steps);
    if (c->dist < 0.05f * c->radius) c->dist = 0.05f * c->radius;
    if (c->dist > 20 * c->radius) c->dist = 20 * c->radius;
}

double view_camera_pixel_size(const view_camera *c, double d) {
    return 2.0 * d * tan(0.5 * c->fov_y) / (c->height > 0 ? c->height : 1);
}
