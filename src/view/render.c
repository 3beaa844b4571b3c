/* OpenGL 3.3 core renderer of the viewer (libepoxy for the entry points).
 *
 * - The mesh is subdivided once (each triangle into 4, shared edge
 *   midpoints so there are no cracks inside a UV island) and displaced in
 *   the vertex shader by the blended height map along the normal: the
 *   "height as displacement on a subdivided mesh" of the issue, without
 *   tessellation shaders (OpenGL 4.0, which this profile does not assume).
 * - Textures are two GL_TEXTURE_2D_ARRAYs uploaded once per texture stack:
 *   sRGB colour + reflection, normal + height. A frame is one draw: the
 *   fragment shader samples the two layers around the time and blends them
 *   (normal renormalised), so scrubbing changes three uniforms and nothing
 *   else (seed 000 §4.4 measured 1 ms/frame on a GPU doing the same).
 * - Shading: Lambert diffuse plus GGX specular (Smith-Schlick visibility,
 *   Schlick Fresnel with skin's F0 = 0.028, Weyrich 2006) scaled by the
 *   reflection map, roughness = 1 - 0.8 x reflection (as the glTF export),
 *   a key and a fill light and a little ambient; tangent-space
 *   normal map (OpenGL, +Y up = -v since skinsim's v points down). The
 *   result is sRGB-encoded in the shader, so any RGBA8 framebuffer (the
 *   GtkGLArea's or the offscreen one) holds display values.
 * - Stroke samples are drawn as round points in a colour per UV island,
 *   nudged towards the eye so the surface does not hide them; the brush
 *   ring (the brush's outline on the surface under the cursor) as a line
 *   loop over everything, white for the brush and red for the eraser. */
#include "view.h"

#include <epoxy/gl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SUBDIV_LEVELS 1
#define VERTEX_FLOATS 12 /* pos 3, normal 3, uv 2, tangent 4 */

struct view_renderer {
    GLuint prog, vao, vbo, ibo;
    GLsizei nindex;
    GLuint pprog, pvao, pvbo;
    GLsizei npoints;
    GLuint rvao, rvbo; /* the brush ring: a line loop */
    GLsizei nring;
    GLuint tex_cr, tex_nh;
    int tex_layers;
    GLuint fbo, fbo_color, fbo_depth;
    int fbo_w, fbo_h;
    float radius;
    char info[256];
};

/* ---- shaders ---------------------------------------------------------------- */

static const char *VS = "#version 330 core\n"
                        "layout(location=0) in vec3 a_pos;\n"
                        "layout(location=1) in vec3 a_nrm;\n"
                        "layout(location=2) in vec2 a_uv;\n"
                        "layout(location=3) in vec4 a_tan;\n"
                        "uniform mat4 u_mvp;\n"
                        "uniform sampler2DArray u_nh;\n"
                        "uniform float u_la, u_lb, u_w, u_disp;\n"
                        "out vec3 v_pos; out vec3 v_nrm; out vec2 v_uv; out vec4 v_tan;\n"
                        "void main() {\n"
                        "  float ha = textureLod(u_nh, vec3(a_uv, u_la), 0.0).a;\n"
                        "  float hb = textureLod(u_nh, vec3(a_uv, u_lb), 0.0).a;\n"
                        "  vec3 p = a_pos + a_nrm * (mix(ha, hb, u_w) - 0.5) * u_disp;\n"
                        "  v_pos = p; v_nrm = a_nrm; v_uv = a_uv; v_tan = a_tan;\n"
                        "  gl_Position = u_mvp * vec4(p, 1.0);\n"
                        "}\n";

static const char *FS =
    "#version 330 core\n"
    "in vec3 v_pos; in vec3 v_nrm; in vec2 v_uv; in vec4 v_tan;\n"
    "uniform sampler2DArray u_cr;\n"
    "uniform sampler2DArray u_nh;\n"
    "uniform float u_la, u_lb, u_w;\n"
    "uniform bool u_blend;\n"
    "uniform vec3 u_eye, u_key, u_fill;\n"
    "out vec4 o_color;\n"
    "float ggx(vec3 n, vec3 v, vec3 l, float rough) {\n"
    "  vec3 h = normalize(v + l);\n"
    "  float a = rough * rough, a2 = a * a;\n"
    "  float nh = max(dot(n, h), 0.0), nv = max(dot(n, v), 1e-3), nl = max(dot(n, l), 0.0);\n"
    "  float d = nh * nh * (a2 - 1.0) + 1.0;\n"
    "  float D = a2 / (3.14159265 * d * d);\n"
    "  float k = a * 0.5;\n"
    "  float V = 1.0 / ((nv * (1.0 - k) + k) * (nl * (1.0 - k) + k));\n"
    "  float F = 0.028 + (1.0 - 0.028) * pow(1.0 - max(dot(h, v), 0.0), 5.0);\n"
    "  return D * V * F * 0.25 * nl;\n"
    "}\n"
    "vec3 srgb(vec3 c) {\n"
    "  c = clamp(c, 0.0, 1.0);\n"
    "  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));\n"
    "}\n"
    "void main() {\n"
    "  vec4 cr = texture(u_cr, vec3(v_uv, u_la));\n"
    "  vec3 nt = texture(u_nh, vec3(v_uv, u_la)).rgb;\n"
    "  if (u_blend) {\n" /* uniform branch: a held key samples once */
    "    cr = mix(cr, texture(u_cr, vec3(v_uv, u_lb)), u_w);\n"
    "    nt = mix(nt, texture(u_nh, vec3(v_uv, u_lb)).rgb, u_w);\n"
    "  }\n"
    "  nt = nt * 2.0 - 1.0;\n"
    "  if (dot(nt, nt) < 1e-6) nt = vec3(0.0, 0.0, 1.0);\n"
    "  nt = normalize(nt);\n"
    "  vec3 N = normalize(v_nrm);\n"
    "  vec3 T = v_tan.xyz - N * dot(N, v_tan.xyz);\n"
    "  vec3 n = N;\n"
    "  if (dot(T, T) > 1e-12) {\n"
    "    T = normalize(T);\n"
    "    vec3 B = cross(N, T) * v_tan.w;\n"
    "    n = normalize(T * nt.x + B * nt.y + N * nt.z);\n"
    "  }\n"
    "  vec3 v = normalize(u_eye - v_pos);\n"
    "  if (!gl_FrontFacing) { n = -n; }\n"
    "  float refl = cr.a, rough = clamp(1.0 - 0.8 * refl, 0.08, 1.0);\n"
    "  vec3 albedo = cr.rgb;\n"
    "  vec3 lights[2] = vec3[2](u_key, u_fill);\n"
    "  float power[2] = float[2](2.2, 0.8);\n"
    "  vec3 c = albedo * 0.25;\n"
    "  for (int i = 0; i < 2; i++) {\n"
    "    vec3 l = normalize(lights[i]);\n"
    "    float nl = max(dot(n, l), 0.0);\n"
    "    c += power[i] * (albedo * nl * 0.35 + (0.3 + refl) * ggx(n, v, l, rough));\n"
    "  }\n"
    "  o_color = vec4(srgb(c), 1.0);\n"
    "}\n";

static const char *PVS = "#version 330 core\n"
                         "layout(location=0) in vec3 a_pos;\n"
                         "layout(location=1) in float a_island;\n"
                         "uniform mat4 u_mvp;\n"
                         "uniform vec3 u_eye;\n"
                         "uniform float u_size, u_nudge;\n"
                         "flat out float v_island;\n"
                         "void main() {\n"
                         "  vec3 p = a_pos + normalize(u_eye - a_pos) * u_nudge;\n"
                         "  gl_Position = u_mvp * vec4(p, 1.0);\n"
                         "  gl_PointSize = u_size;\n"
                         "  v_island = a_island;\n"
                         "}\n";

static const char *PFS =
    "#version 330 core\n"
    "flat in float v_island;\n"
    "out vec4 o_color;\n"
    "uniform int u_line;\n"
    "void main() {\n"
    "  vec2 d = gl_PointCoord * 2.0 - 1.0;\n"
    "  if (u_line == 0 && dot(d, d) > 1.0) discard;\n"
    "  int i = int(v_island + 0.5);\n"
    "  vec3 c = i == 0 ? vec3(0.1, 0.9, 1.0) : i == 1 ? vec3(1.0, 0.85, 0.1) : i == 2 ? "
    "vec3(0.9, 0.2, 1.0) : i == 3 ? vec3(0.3, 1.0, 0.3) : i == 4 ? vec3(1.0) : "
    "vec3(1.0, 0.25, 0.2);\n"
    "  o_color = vec4(c, 1.0);\n"
    "}\n";

static GLuint compile(GLenum type, const char *src, char *log, size_t logn) {
    GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &src, NULL);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        glGetShaderInfoLog(s, (GLsizei)logn, NULL, log);
        glDeleteShader(s);
        return 0;
    }
    return s;
}

static GLuint link_program(const char *vs, const char *fs, ss_error *err) {
    char log[2048] = "";
    GLuint v = compile(GL_VERTEX_SHADER, vs, log, sizeof log);
    GLuint f = v ? compile(GL_FRAGMENT_SHADER, fs, log, sizeof log) : 0;
    if (!v || !f) {
        if (v) glDeleteShader(v);
        ss_error_set(err, SS_ERR_RUNTIME, "viewer: shader does not compile: %s", log);
        return 0;
    }
    GLuint p = glCreateProgram();
    glAttachShader(p, v);
    glAttachShader(p, f);
    glLinkProgram(p);
    glDeleteShader(v);
    glDeleteShader(f);
    GLint ok = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        glGetProgramInfoLog(p, sizeof log, NULL, log);
        glDeleteProgram(p);
        ss_error_set(err, SS_ERR_RUNTIME, "viewer: shader does not link: %s", log);
        return 0;
    }
    return p;
}

/* ---- mesh preparation ---------------------------------------------------------- */

/* Per-vertex tangents from UV gradients (accumulated per triangle,
 * Gram-Schmidt against the normal); w = handedness. Image "up" is -v. */
static void compute_tangents(const ss_mesh *m, float *vtx) {
    size_t nv = (size_t)m->nvertices;
    double *t = calloc(nv * 6, sizeof *t); /* tangent 3, bitangent 3 */
    if (!t) return;
    for (int tri = 0; tri < m->ntriangles; tri++) {
        const uint32_t *ix = m->indices + 3 * (size_t)tri;
        const float *p0 = m->positions + 3 * (size_t)ix[0], *p1 = m->positions + 3 * (size_t)ix[1],
                    *p2 = m->positions + 3 * (size_t)ix[2];
        const float *u0 = m->uvs + 2 * (size_t)ix[0], *u1 = m->uvs + 2 * (size_t)ix[1],
                    *u2 = m->uvs + 2 * (size_t)ix[2];
        double e1[3], e2[3];
        for (int k = 0; k < 3; k++) e1[k] = p1[k] - p0[k], e2[k] = p2[k] - p0[k];
        double du1 = u1[0] - u0[0], dv1 = -(u1[1] - u0[1]), du2 = u2[0] - u0[0],
               dv2 = -(u2[1] - u0[1]);
        double det = du1 * dv2 - du2 * dv1;
        if (fabs(det) < 1e-20) continue;
        double r = 1.0 / det;
        for (int c = 0; c < 3; c++) {
            size_t v = ix[c];
            for (int k = 0; k < 3; k++) {
                t[6 * v + k] += (e1[k] * dv2 - e2[k] * dv1) * r;
                t[6 * v + 3 + k] += (e2[k] * du1 - e1[k] * du2) * r;
            }
        }
    }
    for (size_t v = 0; v < nv; v++) {
        const float *n = m->normals + 3 * v;
        double *tt = t + 6 * v, *bb = t + 6 * v + 3;
        double d = tt[0] * n[0] + tt[1] * n[1] + tt[2] * n[2];
        double o[3] = {tt[0] - n[0] * d, tt[1] - n[1] * d, tt[2] - n[2] * d};
        double l = sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
        float *out = vtx + VERTEX_FLOATS * v + 8;
        if (l > 0) {
            for (int k = 0; k < 3; k++) out[k] = (float)(o[k] / l);
            double c[3] = {n[1] * o[2] - n[2] * o[1], n[2] * o[0] - n[0] * o[2],
                           n[0] * o[1] - n[1] * o[0]};
            out[3] = (c[0] * bb[0] + c[1] * bb[1] + c[2] * bb[2]) < 0 ? -1.0f : 1.0f;
        } else {
            out[0] = out[1] = out[2] = 0;
            out[3] = 1;
        }
    }
    free(t);
}

typedef struct vbuf {
    float *v;
    size_t n, cap; /* vertices */
    uint32_t *idx;
    size_t ni;
} vbuf;

/* Edge-midpoint table: open addressing on the (min, max) vertex pair. */
typedef struct edge_map {
    uint64_t *key;
    uint32_t *val;
    size_t cap;
} edge_map;

static uint32_t midpoint(vbuf *b, edge_map *em, uint32_t a, uint32_t c) {
    uint64_t key = a < c ? ((uint64_t)a << 32 | c) : ((uint64_t)c << 32 | a);
    size_t h = (size_t)((key * 0x9E3779B97F4A7C15ull) >> 20) & (em->cap - 1);
    while (em->key[h] != UINT64_MAX) {
        if (em->key[h] == key) return em->val[h];
        h = (h + 1) & (em->cap - 1);
    }
    float *va = b->v + VERTEX_FLOATS * (size_t)a, *vc = b->v + VERTEX_FLOATS * (size_t)c;
    float *o = b->v + VERTEX_FLOATS * b->n;
    for (int k = 0; k < VERTEX_FLOATS; k++) o[k] = 0.5f * (va[k] + vc[k]);
    o[11] = va[11];
    for (int s = 3; s <= 8; s += 5) { /* renormalise normal (3..5) and tangent (8..10) */
        float l = sqrtf(o[s] * o[s] + o[s + 1] * o[s + 1] + o[s + 2] * o[s + 2]);
        if (l > 0)
            for (int k = 0; k < 3; k++) o[s + k] /= l;
    }
    em->key[h] = key;
    em->val[h] = (uint32_t)b->n;
    return (uint32_t)b->n++;
}

static int subdivide(vbuf *b) {
    size_t nt = b->ni / 3;
    size_t nv_new = b->n + 3 * nt; /* upper bound on new vertices */
    float *v = realloc(b->v, sizeof(float) * VERTEX_FLOATS * nv_new);
    uint32_t *idx = malloc(sizeof(uint32_t) * 12 * nt);
    edge_map em;
    em.cap = 1;
    while (em.cap < 6 * nt) em.cap <<= 1;
    em.key = malloc(sizeof *em.key * em.cap);
    em.val = malloc(sizeof *em.val * em.cap);
    if (!v || !idx || !em.key || !em.val) {
        if (v) b->v = v;
        free(idx), free(em.key), free(em.val);
        return -1;
    }
    b->v = v;
    memset(em.key, 0xff, sizeof *em.key * em.cap);
    size_t k = 0;
    for (size_t t = 0; t < nt; t++) {
        uint32_t a = b->idx[3 * t], c = b->idx[3 * t + 1], d = b->idx[3 * t + 2];
        uint32_t ac = midpoint(b, &em, a, c), cd = midpoint(b, &em, c, d),
                 da = midpoint(b, &em, d, a);
        uint32_t q[12] = {a, ac, da, ac, c, cd, da, cd, d, ac, cd, da};
        memcpy(idx + k, q, sizeof q);
        k += 12;
    }
    free(b->idx);
    b->idx = idx;
    b->ni = k;
    free(em.key), free(em.val);
    return 0;
}

/* ---- creation ---------------------------------------------------------------- */

view_renderer *view_renderer_create(const ss_mesh *m, ss_error *err) {
    if (epoxy_gl_version() < 33) {
        ss_error_set(err, SS_ERR_RUNTIME, "viewer: OpenGL 3.3 needed, the context has %d.%d",
                     epoxy_gl_version() / 10, epoxy_gl_version() % 10);
        return NULL;
    }
    view_renderer *r = calloc(1, sizeof *r);
    if (!r) {
        ss_error_set(err, SS_ERR_NOMEM, "viewer: out of memory");
        return NULL;
    }
    snprintf(r->info, sizeof r->info, "%s | %s", (const char *)glGetString(GL_RENDERER),
             (const char *)glGetString(GL_VERSION));
    r->prog = link_program(VS, FS, err);
    r->pprog = r->prog ? link_program(PVS, PFS, err) : 0;
    if (!r->pprog) {
        view_renderer_free(r);
        return NULL;
    }
    vbuf b = {0};
    b.n = (size_t)m->nvertices;
    b.v = calloc(b.n * VERTEX_FLOATS, sizeof(float));
    b.ni = 3 * (size_t)m->ntriangles;
    b.idx = malloc(sizeof(uint32_t) * b.ni);
    if (!b.v || !b.idx) {
        free(b.v), free(b.idx), view_renderer_free(r);
        ss_error_set(err, SS_ERR_NOMEM, "viewer: out of memory");
        return NULL;
    }
    memcpy(b.idx, m->indices, sizeof(uint32_t) * b.ni);
    for (size_t i = 0; i < b.n; i++) {
        float *o = b.v + VERTEX_FLOATS * i;
        memcpy(o, m->positions + 3 * i, sizeof(float) * 3);
        memcpy(o + 3, m->normals + 3 * i, sizeof(float) * 3);
        if (m->has_uvs) memcpy(o + 6, m->uvs + 2 * i, sizeof(float) * 2);
        o[11] = 1;
    }
    if (m->has_uvs) compute_tangents(m, b.v);
    for (int lv = 0; lv < SUBDIV_LEVELS; lv++)
        if (subdivide(&b)) break;
    glGenVertexArrays(1, &r->vao);
    glBindVertexArray(r->vao);
    glGenBuffers(1, &r->vbo);
    glBindBuffer(GL_ARRAY_BUFFER, r->vbo);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(sizeof(float) * VERTEX_FLOATS * b.n), b.v,
                 GL_STATIC_DRAW);
    glGenBuffers(1, &r->ibo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, r->ibo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(sizeof(uint32_t) * b.ni), b.idx,
                 GL_STATIC_DRAW);
    const int comps[4] = {3, 3, 2, 4}, offs[4] = {0, 3, 6, 8};
    for (int a = 0; a < 4; a++) {
        glEnableVertexAttribArray((GLuint)a);
        glVertexAttribPointer((GLuint)a, comps[a], GL_FLOAT, GL_FALSE,
                              (GLsizei)(sizeof(float) * VERTEX_FLOATS),
                              (const void *)(sizeof(float) * (size_t)offs[a]));
    }
    r->nindex = (GLsizei)b.ni;
    free(b.v), free(b.idx);
    glGenVertexArrays(1, &r->pvao);
    glBindVertexArray(r->pvao);
    glGenBuffers(1, &r->pvbo);
    glBindBuffer(GL_ARRAY_BUFFER, r->pvbo);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(float) * 4, (const void *)0);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 1, GL_FLOAT, GL_FALSE, sizeof(float) * 4,
                          (const void *)(sizeof(float) * 3));
    glGenVertexArrays(1, &r->rvao);
    glBindVertexArray(r->rvao);
    glGenBuffers(1, &r->rvbo);
    glBindBuffer(GL_ARRAY_BUFFER, r->rvbo);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(float) * 4, (const void *)0);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 1, GL_FLOAT, GL_FALSE, sizeof(float) * 4,
                          (const void *)(sizeof(float) * 3));
    glBindVertexArray(0);
    r->radius = 0;
    for (int k = 0; k < 3; k++) {
        float e = 0.5f * (m->bbox_max[k] - m->bbox_min[k]);
        r->radius += e * e;
    }
    r->radius = sqrtf(r->radius);
    return r;
}

void view_renderer_free(view_renderer *r) {
    if (!r) return;
    if (r->prog) glDeleteProgram(r->prog);
    if (r->pprog) glDeleteProgram(r->pprog);
    if (r->vbo) glDeleteBuffers(1, &r->vbo);
    if (r->ibo) glDeleteBuffers(1, &r->ibo);
    if (r->pvbo) glDeleteBuffers(1, &r->pvbo);
    if (r->vao) glDeleteVertexArrays(1, &r->vao);
    if (r->pvao) glDeleteVertexArrays(1, &r->pvao);
    if (r->rvbo) glDeleteBuffers(1, &r->rvbo);
    if (r->rvao) glDeleteVertexArrays(1, &r->rvao);
    if (r->tex_cr) glDeleteTextures(1, &r->tex_cr);
    if (r->tex_nh) glDeleteTextures(1, &r->tex_nh);
    if (r->fbo) glDeleteFramebuffers(1, &r->fbo);
    if (r->fbo_color) glDeleteRenderbuffers(1, &r->fbo_color);
    if (r->fbo_depth) glDeleteRenderbuffers(1, &r->fbo_depth);
    free(r);
}

const char *view_renderer_gl_info(view_renderer *r) { return r->info; }

/* A texture array with its mipmaps: the CPU-made chain when there is one
 * (the GL thread then only copies), else glGenerateMipmap. */
static GLuint make_array(GLenum internal, int size, int layers, const unsigned char *data,
                         unsigned char *const *mips, int nlevels) {
    GLuint t;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D_ARRAY, t);
    int levels = 1;
    while ((size >> levels) > 0) levels++;
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAX_LEVEL, levels - 1);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, (GLint)internal, size, size, layers, 0, GL_RGBA,
                 GL_UNSIGNED_BYTE, data);
    if (nlevels == levels) {
        for (int lv = 1; lv < levels; lv++)
            glTexImage3D(GL_TEXTURE_2D_ARRAY, lv, (GLint)internal, size >> lv, size >> lv, layers,
                         0, GL_RGBA, GL_UNSIGNED_BYTE, mips[lv]);
    } else {
        glGenerateMipmap(GL_TEXTURE_2D_ARRAY);
    }
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_NEAREST);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return t;
}

ss_status view_renderer_set_layers(view_renderer *r, const view_layers *l, ss_error *err) {
    GLint max_size = 0, max_layers = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
    if (l->size > max_size || l->nlayers > max_layers)
        return ss_error_set(err, SS_ERR_INPUT,
                            "viewer: %d layers of %d^2 exceed this OpenGL (max %d^2, %d layers)",
                            l->nlayers, l->size, max_size, max_layers);
    if (r->tex_cr) glDeleteTextures(1, &r->tex_cr);
    if (r->tex_nh) glDeleteTextures(1, &r->tex_nh);
    while (glGetError() != GL_NO_ERROR) {
    }
    r->tex_cr = make_array(GL_SRGB8_ALPHA8, l->size, l->nlayers, l->cr, l->cr_mip, l->nlevels);
    r->tex_nh = make_array(GL_RGBA8, l->size, l->nlayers, l->nh, l->nh_mip, l->nlevels);
    r->tex_layers = l->nlayers;
    GLenum e = glGetError();
    if (e == GL_OUT_OF_MEMORY)
        return ss_error_set(err, SS_ERR_NOMEM,
                            "viewer: out of texture memory for %d layers of %d^2", l->nlayers,
                            l->size);
    return SS_OK;
}

void view_renderer_set_strokes(view_renderer *r, const ss_paint_sample *s, int n) {
    float *buf = malloc(sizeof(float) * 4 * (size_t)(n > 0 ? n : 1));
    if (!buf) return;
    int k = 0;
    for (int i = 0; i < n; i++) {
        if (isnan(s[i].pos[0])) continue;
        memcpy(buf + 4 * k, s[i].pos, sizeof(float) * 3);
        buf[4 * k + 3] = (float)(s[i].island < 0 ? 3 : s[i].island);
        k++;
    }
    glBindBuffer(GL_ARRAY_BUFFER, r->pvbo);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(sizeof(float) * 4 * (size_t)(k > 0 ? k : 1)), buf,
                 GL_DYNAMIC_DRAW);
    r->npoints = k;
    free(buf);
}

void view_renderer_set_ring(view_renderer *r, const float *pts, int n, int eraser) {
    float buf[4 * 256];
    if (n > 256) n = 256;
    for (int i = 0; i < n; i++) {
        memcpy(buf + 4 * i, pts + 3 * i, sizeof(float) * 3);
        buf[4 * i + 3] = eraser ? 5.0f : 4.0f;
    }
    r->nring = n;
    if (n == 0) return;
    glBindBuffer(GL_ARRAY_BUFFER, r->rvbo);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(sizeof(float) * 4 * (size_t)n), buf,
                 GL_DYNAMIC_DRAW);
}

void view_renderer_draw(view_renderer *r, const view_camera *c, const view_layers *l, double day,
                        float displace_scale, int show_strokes) {
    float mvp[16], eye[3];
    view_camera_matrix(c, mvp);
    view_camera_eye(c, eye);
    glViewport(0, 0, c->width, c->height);
    glClearColor(0.16f, 0.17f, 0.19f, 1.0f);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    if (!r->tex_cr) return;
    int la, lb;
    float w;
    view_layers_locate(l, day, &la, &lb, &w, NULL);
    glUseProgram(r->prog);
    glUniformMatrix4fv(glGetUniformLocation(r->prog, "u_mvp"), 1, GL_FALSE, mvp);
    glUniform3fv(glGetUniformLocation(r->prog, "u_eye"), 1, eye);
    /* Lights in camera terms: key from the upper left front, fill from the right. */
    float f[3], rt[3], up[3], o[3];
    view_camera_ray(c, c->width * 0.5, c->height * 0.5, o, f, rt, up);
    float key[3], fill[3];
    for (int k = 0; k < 3; k++) {
        key[k] = -f[k] - 0.6f * rt[k] + 0.7f * up[k];
        fill[k] = -f[k] + 0.9f * rt[k] - 0.2f * up[k];
    }
    glUniform3fv(glGetUniformLocation(r->prog, "u_key"), 1, key);
    glUniform3fv(glGetUniformLocation(r->prog, "u_fill"), 1, fill);
    glUniform1f(glGetUniformLocation(r->prog, "u_la"), (float)la);
    glUniform1f(glGetUniformLocation(r->prog, "u_lb"), (float)lb);
    glUniform1f(glGetUniformLocation(r->prog, "u_w"), w);
    glUniform1i(glGetUniformLocation(r->prog, "u_blend"), la != lb && w > 0);
    /* height 0..1 spans height_mm; mesh units are metres (glTF). */
    glUniform1f(glGetUniformLocation(r->prog, "u_disp"),
                (float)(l->height_mm * 1e-3) * displace_scale);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D_ARRAY, r->tex_cr);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D_ARRAY, r->tex_nh);
    glUniform1i(glGetUniformLocation(r->prog, "u_cr"), 0);
    glUniform1i(glGetUniformLocation(r->prog, "u_nh"), 1);
    glBindVertexArray(r->vao);
    glDrawElements(GL_TRIANGLES, r->nindex, GL_UNSIGNED_INT, 0);
    if (show_strokes && r->npoints > 0) {
        glUseProgram(r->pprog);
        glEnable(GL_PROGRAM_POINT_SIZE);
        glUniformMatrix4fv(glGetUniformLocation(r->pprog, "u_mvp"), 1, GL_FALSE, mvp);
        glUniform3fv(glGetUniformLocation(r->pprog, "u_eye"), 1, eye);
        glUniform1f(glGetUniformLocation(r->pprog, "u_size"),
                    fmaxf(3.0f, (float)c->height / 240.0f));
        glUniform1f(glGetUniformLocation(r->pprog, "u_nudge"), 0.01f * r->radius);
        glUniform1i(glGetUniformLocation(r->pprog, "u_line"), 0);
        glBindVertexArray(r->pvao);
        glDrawArrays(GL_POINTS, 0, r->npoints);
    }
    if (r->nring > 1) { /* the brush outline, over the surface, never hidden by it */
        glUseProgram(r->pprog);
        glUniformMatrix4fv(glGetUniformLocation(r->pprog, "u_mvp"), 1, GL_FALSE, mvp);
        glUniform3fv(glGetUniformLocation(r->pprog, "u_eye"), 1, eye);
        glUniform1f(glGetUniformLocation(r->pprog, "u_size"), 1.0f);
        glUniform1f(glGetUniformLocation(r->pprog, "u_nudge"), 0.01f * r->radius);
        glUniform1i(glGetUniformLocation(r->pprog, "u_line"), 1);
        glDisable(GL_DEPTH_TEST);
        glBindVertexArray(r->rvao);
        glDrawArrays(GL_LINE_LOOP, 0, r->nring);
        glEnable(GL_DEPTH_TEST);
    }
    glBindVertexArray(0);
    glUseProgram(0);
}

static ss_status ensure_fbo(view_renderer *r, int w, int h, ss_error *err) {
    if (r->fbo && r->fbo_w == w && r->fbo_h == h) return SS_OK;
    if (!r->fbo) {
        glGenFramebuffers(1, &r->fbo);
        glGenRenderbuffers(1, &r->fbo_color);
        glGenRenderbuffers(1, &r->fbo_depth);
    }
    glBindRenderbuffer(GL_RENDERBUFFER, r->fbo_color);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
    glBindRenderbuffer(GL_RENDERBUFFER, r->fbo_depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, r->fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, r->fbo_color);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, r->fbo_depth);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        return ss_error_set(err, SS_ERR_RUNTIME, "viewer: offscreen framebuffer %dx%d incomplete",
                            w, h);
    r->fbo_w = w;
    r->fbo_h = h;
    return SS_OK;
}

ss_status view_renderer_offscreen(view_renderer *r, const view_camera *c, const view_layers *l,
                                  double day, float displace_scale, int show_strokes,
                                  unsigned char *rgb, ss_error *err) {
    GLint prev = 0;
    glGetIntegerv(GL_FRAMEBUFFER_BINDING, &prev);
    ss_status st = ensure_fbo(r, c->width, c->height, err);
    if (!st) {
        glBindFramebuffer(GL_FRAMEBUFFER, r->fbo);
        view_renderer_draw(r, c, l, day, displace_scale, show_strokes);
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        unsigned char *tmp = malloc((size_t)c->width * (size_t)c->height * 4);
        if (!tmp)
            st = ss_error_set(err, SS_ERR_NOMEM, "viewer: out of memory");
        else {
            glReadPixels(0, 0, c->width, c->height, GL_RGBA, GL_UNSIGNED_BYTE, tmp);
            for (int y = 0; y < c->height; y++) /* GL rows are bottom-first */
                for (int x = 0; x < c->width; x++)
                    memcpy(rgb + 3 * ((size_t)y * (size_t)c->width + (size_t)x),
                           tmp + 4 * ((size_t)(c->height - 1 - y) * (size_t)c->width + (size_t)x),
                           3);
            free(tmp);
        }
    }
    glBindFramebuffer(GL_FRAMEBUFFER, (GLuint)prev);
    return st;
}

ss_status view_renderer_bench(view_renderer *r, const view_camera *c, const view_layers *l, int n,
                              float displace_scale, double *ms, ss_error *err) {
    GLint prev = 0;
    glGetIntegerv(GL_FRAMEBUFFER_BINDING, &prev);
    ss_status st = ensure_fbo(r, c->width, c->height, err);
    if (!st) {
        glBindFramebuffer(GL_FRAMEBUFFER, r->fbo);
        unsigned char px[4];
        for (int i = 0; i < n; i++) {
            double day = n > 1 ? l->end_day * i / (n - 1) : 0;
            double t0 = ss_now();
            view_renderer_draw(r, c, l, day, displace_scale, 0);
            /* Reading one pixel waits for the frame like a swap would. */
            glReadPixels(c->width / 2, c->height / 2, 1, 1, GL_RGBA, GL_UNSIGNED_BYTE, px);
            ms[i] = (ss_now() - t0) * 1e3;
        }
    }
    glBindFramebuffer(GL_FRAMEBUFFER, (GLuint)prev);
    return st;
}
