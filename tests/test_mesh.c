/* mesh: the shipped hand (GLB, skinned, three UV islands), hand-written OBJ
 * (quads, negative indices, v/t/n forms, v flipped to v-down, no UVs
 * reported as a flag) and glTF (external .bin, data URI, GLB, node
 * transforms with mirroring, strips), broken files refused as input errors
 * naming the file; BVH ray casts equal to the brute-force loop on random
 * rays (same triangle, same t), UVs interpolated from barycentrics. */
#include "testutil.h"
#include "skinsim/mesh.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static char *hand_path(void) {
    static char p[4096];
    snprintf(p, sizeof p, "%s/data/meshes/generic-hand-left.glb", SKINSIM_SOURCE_DIR);
    return p;
}

static void write_text(const char *path, const char *text) {
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static void write_bytes(const char *path, const void *data, size_t n) {
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, n, f), n);
    fclose(f);
}

static void test_hand(void **state) {
    (void)state;
    ss_mesh m;
    ss_error err = {0};
    assert_int_equal(ss_mesh_load(hand_path(), &m, &err), SS_OK);
    /* Counts from the file's accessors: 1360 vertices, 6942 indices. */
    assert_int_equal(m.nvertices, 1360);
    assert_int_equal(m.ntriangles, 6942 / 3);
    assert_true(m.has_uvs);
    assert_true(m.normals_loaded);
    /* Skinned node: bind pose, so the bounds are the POSITION accessor's. */
    const float mn[3] = {-0.05657949f, -0.13369706f, -0.07951044f};
    const float mx[3] = {0.02044241f, 0.07834381f, 0.06639536f};
    for (int d = 0; d < 3; d++) {
        assert_true(fabsf(m.bbox_min[d] - mn[d]) < 1e-6f);
        assert_true(fabsf(m.bbox_max[d] - mx[d]) < 1e-6f);
    }
    for (int i = 0; i < 2 * m.nvertices; i++) assert_true(m.uvs[i] >= 0 && m.uvs[i] <= 1);
    for (int i = 0; i < m.nvertices; i++) {
        const float *n = m.normals + 3 * i;
        assert_true(fabsf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] - 1) < 1e-4f);
    }
    /* DESIGN.md: three UV islands (palm, back of the hand, wrist cap). */
    int *island = malloc(sizeof *island * (size_t)m.ntriangles);
    int n = ss_mesh_uv_islands(&m, island);
    assert_int_equal(n, 3);
    int count[3] = {0, 0, 0};
    for (int t = 0; t < m.ntriangles; t++) count[island[t]]++;
    for (int i = 0; i < 3; i++) assert_true(count[i] > 0);
    free(island);
    ss_mesh_free(&m);
    assert_null(m.positions);
}

static void test_obj(void **state) {
    (void)state;
    char *dir = tu_tmpdir("mesh");
    char path[4200];
    snprintf(path, sizeof path, "%s/quad.obj", dir);
    /* Two quads sharing an edge, one as v/t/n and one with negative indices;
     * the second quad's UVs are a separate island (a seam). */
    write_text(path, "# test\n"
                     "o thing\nmtllib x.mtl\n"
                     "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n"
                     "vt 0 0\nvt 0.5 0\nvt 0.5 1\nvt 0 1\n"
                     "vt 0.6 0\nvt 1 0\nvt 1 1\nvt 0.6 1\n"
                     "vn 0 0 1\n"
                     "usemtl skin\ns 1\n"
                     "f 1/1/1 2/2/1 3/3/1 4/4/1\n"
                     "f -5/-4/-1 -2/-3/-1 -1/-2/-1 -4/-1/-1\n");
    ss_mesh m;
    ss_error err = {0};
    assert_int_equal(ss_mesh_load(path, &m, &err), SS_OK);
    assert_int_equal(m.ntriangles, 4);
    assert_int_equal(m.nvertices, 8);
    assert_true(m.has_uvs);
    assert_true(m.normals_loaded);
    /* Vertex 0 is v1/vt1: OBJ v=0 (bottom) becomes 1 in skinsim's v-down. */
    assert_true(m.positions[0] == 0 && m.uvs[0] == 0.0f && m.uvs[1] == 1.0f);
    int island[4];
    assert_int_equal(ss_mesh_uv_islands(&m, island), 2);
    assert_int_equal(island[0], island[1]);
    assert_int_equal(island[2], island[3]);
    assert_int_not_equal(island[0], island[2]);
    ss_mesh_free(&m);

    /* No vt: loads, flagged; normals computed, facing +z for CCW. */
    write_text(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    assert_int_equal(ss_mesh_load(path, &m, &err), SS_OK);
    assert_false(m.has_uvs);
    assert_null(m.uvs);
    assert_false(m.normals_loaded);
    assert_true(fabsf(m.normals[2] - 1) < 1e-6f);
    assert_int_equal(ss_mesh_uv_islands(&m, island), -1);
    ss_mesh_free(&m);

    /* Broken OBJ files: input errors naming the file. */
    const char *bad[] = {
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",       /* index out of range */
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n",         /* two corners */
        "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",     /* NaN */
        "v 0 0\nf 1 1 1\n",                           /* short vertex */
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",       /* index 0 */
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/5 2/5 3/5\n", /* vt out of range */
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1x 2 3\n",      /* junk */
        "v 0 0 0\n",                                  /* no faces */
        "",                                           /* empty */
    };
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        write_text(path, bad[i]);
        ss_error_clear(&err);
        assert_int_equal(ss_mesh_load(path, &m, &err), SS_ERR_INPUT);
        assert_non_null(strstr(err.msg, "quad.obj"));
        assert_null(m.positions);
    }
    snprintf(path, sizeof path, "%s/missing.obj", dir);
    assert_int_equal(ss_mesh_load(path, &m, &err), SS_ERR_INPUT);
    snprintf(path, sizeof path, "%s/thing.stl", dir);
    assert_int_equal(ss_mesh_load(path, &m, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "unknown mesh format"));
    tu_rmtree(dir);
    free(dir);
}

/* The binary part of the small glTF: 4 positions, 4 UVs, 6 ushort indices
 * (a unit quad in XY facing +z, two CCW triangles). */
typedef struct quad_bin {
    float pos[12];
    float uv[8];
    uint16_t idx[6];
    uint16_t pad;
} quad_bin;

static const quad_bin QUAD = {
    {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}, {0, 1, 1, 1, 1, 0, 0, 0}, {0, 1, 2, 0, 2, 3}, 0};

static const char *QUAD_JSON_FMT =
    "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
    "\"nodes\":[{\"translation\":[1,2,3],\"children\":[1]},"
    "{\"scale\":[-2,2,2],\"mesh\":0}],"
    "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":1},"
    "\"indices\":2}]}],"
    "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
    "{\"bufferView\":0,\"byteOffset\":48,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"},"
    "{\"bufferView\":1,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
    "\"bufferViews\":[{\"buffer\":0,\"byteLength\":80},"
    "{\"buffer\":0,\"byteOffset\":80,\"byteLength\":12}],"
    "\"buffers\":[{\"byteLength\":%d%s}]}";

static char *b64(const unsigned char *in, size_t n) {
    static const char t[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char *out = malloc(4 * ((n + 2) / 3) + 1), *o = out;
    for (size_t i = 0; i < n; i += 3) {
        unsigned v = (unsigned)in[i] << 16;
        if (i + 1 < n) v |= (unsigned)in[i + 1] << 8;
        if (i + 2 < n) v |= in[i + 2];
        *o++ = t[(v >> 18) & 63];
        *o++ = t[(v >> 12) & 63];
        *o++ = i + 1 < n ? t[(v >> 6) & 63] : '=';
        *o++ = i + 2 < n ? t[v & 63] : '=';
    }
    *o = 0;
    return out;
}

static void check_quad(const ss_mesh *m) {
    assert_int_equal(m->nvertices, 4);
    assert_int_equal(m->ntriangles, 2);
    assert_true(m->has_uvs);
    /* Vertex 1 (1,0,0): scaled by (-2,2,2) then translated by (1,2,3). */
    assert_true(fabsf(m->positions[3] - (-1.0f)) < 1e-6f);
    assert_true(fabsf(m->positions[4] - 2.0f) < 1e-6f);
    assert_true(fabsf(m->positions[5] - 3.0f) < 1e-6f);
    /* Mirrored: the winding is reversed so the computed normal still faces +z. */
    assert_true(m->normals[2] > 0.99f);
    assert_int_equal(m->indices[0], 0);
    assert_int_equal(m->indices[1], 2);
    assert_int_equal(m->indices[2], 1);
    assert_true(m->uvs[2] == 1.0f && m->uvs[3] == 1.0f);
}

static void test_gltf(void **state) {
    (void)state;
    char *dir = tu_tmpdir("gltf");
    char path[4200], bin[4200], json[8192];
    ss_mesh m;
    ss_error err = {0};
    int blen = (int)sizeof QUAD - 2; /* 92 bytes */

    /* External .bin with a space in its name (percent-encoded URI). */
    snprintf(bin, sizeof bin, "%s/quad data.bin", dir);
    write_bytes(bin, &QUAD, (size_t)blen);
    snprintf(path, sizeof path, "%s/quad.gltf", dir);
    snprintf(json, sizeof json, QUAD_JSON_FMT, blen, ",\"uri\":\"quad%20data.bin\"");
    write_text(path, json);
    assert_int_equal(ss_mesh_load(path, &m, &err), SS_OK);
    check_quad(&m);
    ss_mesh_free(&m);

    /* The same as a base64 data URI. */
    char *enc = b64((const unsigned char *)&QUAD, (size_t)blen);
    char uri[1024];
    snprintf(uri, sizeof uri, ",\"uri\":\"data:application/octet-stream;base64,%s\"", enc);
    free(enc);
    snprintf(json, sizeof json, QUAD_JSON_FMT, blen, uri);
    write_text(path, json);
    assert_int_equal(ss_mesh_load(path, &m, &err), SS_OK);
    check_quad(&m);
    ss_mesh_free(&m);

    /* The same as GLB: header, JSON chunk (space-padded), BIN chunk. */
    snprintf(json, sizeof json, QUAD_JSON_FMT, blen, "");
    size_t jl = strlen(json), jpad = (jl + 3) & ~(size_t)3, bpad = ((size_t)blen + 3) & ~(size_t)3;
    size_t total = 12 + 8 + jpad + 8 + bpad;
    unsigned char *glb = calloc(1, total);
    uint32_t hdr[3] = {0x46546C67u, 2, (uint32_t)total};
    memcpy(glb, hdr, 12);
    uint32_t ch[2] = {(uint32_t)jpad, 0x4E4F534Au};
    memcpy(glb + 12, ch, 8);
    memset(glb + 20, ' ', jpad);
    memcpy(glb + 20, json, jl);
    uint32_t cb[2] = {(uint32_t)bpad, 0x004E4942u};
    memcpy(glb + 20 + jpad, cb, 8);
    memcpy(glb + 28 + jpad, &QUAD, (size_t)blen);
    snprintf(path, sizeof path, "%s/quad.glb", dir);
    write_bytes(path, glb, total);
    assert_int_equal(ss_mesh_load(path, &m, &err), SS_OK);
    check_quad(&m);
    ss_mesh_free(&m);
    /* Truncated GLB, wrong version: refused. */
    write_bytes(path, glb, total - 10);
    assert_int_equal(ss_mesh_load(path, &m, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "quad.glb"));
    glb[4] = 1;
    write_bytes(path, glb, total);
    assert_int_equal(ss_mesh_load(path, &m, &err), SS_ERR_INPUT);
    free(glb);

    /* A triangle strip without indices, no scene: 4 vertices -> 2 triangles. */
    snprintf(path, sizeof path, "%s/strip.gltf", dir);
    enc = b64((const unsigned char *)QUAD.pos, sizeof QUAD.pos);
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},\"meshes\":[{\"primitives\":[{\"mode\":5,"
             "\"attributes\":{\"POSITION\":0}}]}],\"accessors\":[{\"bufferView\":0,"
             "\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"}],\"bufferViews\":[{"
             "\"buffer\":0,\"byteLength\":48}],\"buffers\":[{\"byteLength\":48,\"uri\":"
             "\"data:application/gltf-buffer;base64,%s\"}]}",
             enc);
    free(enc);
    write_text(path, json);
    assert_int_equal(ss_mesh_load(path, &m, &err), SS_OK);
    assert_int_equal(m.ntriangles, 2);
    assert_false(m.has_uvs);
    ss_mesh_free(&m);

    /* Broken glTF: each an input error naming the file, nothing returned. */
    const char *broken[] = {
        "{not json", "{\"asset\":{\"version\":\"1.0\"}}",
        "{\"asset\":{\"version\":\"2.0\"}}", /* no triangles */
    };
    for (size_t i = 0; i < sizeof broken / sizeof *broken; i++) {
        write_text(path, broken[i]);
        assert_int_equal(ss_mesh_load(path, &m, &err), SS_ERR_INPUT);
        assert_non_null(strstr(err.msg, "strip.gltf"));
        assert_null(m.positions);
    }
    /* Accessor past the end of its view; index out of range; missing .bin. */
    snprintf(path, sizeof path, "%s/quad.gltf", dir);
    snprintf(json, sizeof json, QUAD_JSON_FMT, blen, ",\"uri\":\"quad%20data.bin\"");
    char *p = strstr(json, "\"count\":4,\"type\":\"VEC3\"");
    p[8] = '9';
    write_text(path, json);
    assert_int_equal(ss_mesh_load(path, &m, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "past the end"));
    quad_bin q2 = QUAD;
    q2.idx[4] = 7;
    write_bytes(bin, &q2, (size_t)blen);
    snprintf(json, sizeof json, QUAD_JSON_FMT, blen, ",\"uri\":\"quad%20data.bin\"");
    write_text(path, json);
    assert_int_equal(ss_mesh_load(path, &m, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "out of range"));
    remove(bin);
    assert_int_equal(ss_mesh_load(path, &m, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "quad data.bin"));
    /* A node cycle is caught by the depth limit. */
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],"
             "\"nodes\":[{\"children\":[1]},{\"children\":[0]}]}");
    write_text(path, json);
    assert_int_equal(ss_mesh_load(path, &m, &err), SS_ERR_INPUT);

    /* Truncated hand GLB: every prefix length is an input error. */
    size_t hlen;
    char *hand = ss_read_file(hand_path(), &hlen, &err);
    assert_non_null(hand);
    snprintf(path, sizeof path, "%s/cut.glb", dir);
    size_t cuts[] = {0, 3, 12, 19, 100, 4000, hlen / 2, hlen - 1};
    for (size_t i = 0; i < sizeof cuts / sizeof *cuts; i++) {
        write_bytes(path, hand, cuts[i]);
        assert_int_equal(ss_mesh_load(path, &m, &err), SS_ERR_INPUT);
    }
    free(hand);
    tu_rmtree(dir);
    free(dir);
}

/* Random rays aimed at the mesh's box from outside, plus rays in random
 * directions from inside it: the BVH returns what the loop returns. */
static void compare_random_rays(const ss_mesh *m, int nrays, uint64_t seed) {
    ss_error err = {0};
    ss_bvh *b = ss_bvh_build(m, &err);
    assert_non_null(b);
    int nodes, depth;
    ss_bvh_stats(b, &nodes, &depth);
    assert_true(nodes >= 1 && depth < 100);
    float c[3], r = 0;
    for (int d = 0; d < 3; d++) {
        c[d] = 0.5f * (m->bbox_min[d] + m->bbox_max[d]);
        float e = m->bbox_max[d] - m->bbox_min[d];
        r += e * e;
    }
    r = sqrtf(r);
    int hits = 0;
    for (int i = 0; i < nrays; i++) {
        float o[3], target[3], dir[3];
        for (int d = 0; d < 3; d++) {
            float lo = m->bbox_min[d], hi = m->bbox_max[d];
            target[d] = lo + (hi - lo) * (float)ss_rng_uniform(seed, 1, (uint64_t)(3 * i + d));
            o[d] = c[d] + r * (2 * (float)ss_rng_uniform(seed, 2, (uint64_t)(3 * i + d)) - 1);
        }
        if (i % 4 == 3) { /* from inside, random direction */
            for (int d = 0; d < 3; d++) {
                o[d] = target[d];
                dir[d] = 2 * (float)ss_rng_uniform(seed, 3, (uint64_t)(3 * i + d)) - 1;
            }
        } else {
            for (int d = 0; d < 3; d++) dir[d] = target[d] - o[d];
        }
        ss_ray_hit hb, hf;
        int kb = ss_bvh_raycast(b, o, dir, 0.0f, INFINITY, &hb);
        int kf = ss_mesh_raycast_bruteforce(m, o, dir, 0.0f, INFINITY, &hf);
        assert_int_equal(kb, kf);
        assert_int_equal(hb.triangle, hf.triangle);
        if (kb) {
            hits++;
            assert_true(hb.t == hf.t && hb.b1 == hf.b1 && hb.b2 == hf.b2);
            assert_true(hb.uv[0] == hf.uv[0] && hb.uv[1] == hf.uv[1]);
        }
    }
    assert_true(hits > nrays / 10); /* the test exercised hits, not only misses */
    ss_bvh_free(b);
}

static void test_bvh_hand(void **state) {
    (void)state;
    ss_mesh m;
    ss_error err = {0};
    assert_int_equal(ss_mesh_load(hand_path(), &m, &err), SS_OK);
    compare_random_rays(&m, tu_quick() ? 2000 : 20000, 7);
    ss_mesh_free(&m);
}

static void test_bvh_soup(void **state) {
    (void)state;
    /* Random triangle soup, including duplicates (ties go to the lower index). */
    enum { NT = 3000 };
    float *pos = malloc(sizeof(float) * 9 * NT);
    uint32_t *idx = malloc(sizeof(uint32_t) * 3 * NT);
    for (int t = 0; t < NT; t++) {
        float c[3];
        for (int d = 0; d < 3; d++) c[d] = (float)ss_rng_uniform(11, 1, (uint64_t)(3 * t + d));
        for (int k = 0; k < 9; k++)
            pos[9 * t + k] =
                c[k % 3] + 0.08f * ((float)ss_rng_uniform(11, 2, (uint64_t)(9 * t + k)) - 0.5f);
        if (t % 50 == 49) memcpy(pos + 9 * t, pos + 9 * (t - 1), sizeof(float) * 9);
        for (int k = 0; k < 3; k++) idx[3 * t + k] = (uint32_t)(3 * t + k);
    }
    ss_mesh m;
    ss_error err = {0};
    assert_int_equal(ss_mesh_from_arrays(pos, NULL, NULL, 3 * NT, idx, NT, "soup", &m, &err),
                     SS_OK);
    compare_random_rays(&m, tu_quick() ? 2000 : 10000, 13);
    ss_mesh_free(&m);
    free(pos);
    free(idx);
}

static void test_ray_uv(void **state) {
    (void)state;
    /* One quad with UVs: a ray straight down onto (x, y) hits UV (x, 1-y). */
    const float pos[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    const float uv[8] = {0, 1, 1, 1, 1, 0, 0, 0};
    const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    ss_mesh m;
    ss_error err = {0};
    assert_int_equal(ss_mesh_from_arrays(pos, NULL, uv, 4, idx, 2, "quad", &m, &err), SS_OK);
    ss_bvh *b = ss_bvh_build(&m, &err);
    const float o[3] = {0.3f, 0.8f, 5.0f}, dir[3] = {0, 0, -1};
    ss_ray_hit h;
    assert_int_equal(ss_bvh_raycast(b, o, dir, 0, INFINITY, &h), 1);
    assert_int_equal(h.triangle, 1);
    assert_true(fabsf(h.t - 5.0f) < 1e-6f);
    assert_true(fabsf(h.uv[0] - 0.3f) < 1e-6f && fabsf(h.uv[1] - 0.2f) < 1e-6f);
    /* tmax before the surface, a ray pointing away, a NaN ray: misses. */
    assert_int_equal(ss_bvh_raycast(b, o, dir, 0, 4.0f, &h), 0);
    const float up[3] = {0, 0, 1}, bad[3] = {NAN, 0, -1};
    assert_int_equal(ss_bvh_raycast(b, o, up, 0, INFINITY, &h), 0);
    assert_int_equal(h.triangle, -1);
    assert_int_equal(ss_bvh_raycast(b, o, bad, 0, INFINITY, &h), 0);
    ss_bvh_free(b);
    ss_mesh_free(&m);
    /* Index out of range and NaN positions are refused by from_arrays. */
    const uint32_t badidx[3] = {0, 1, 4};
    assert_int_equal(ss_mesh_from_arrays(pos, NULL, uv, 4, badidx, 1, "quad", &m, &err),
                     SS_ERR_INPUT);
    ss_mesh_free(&m);
    float nanpos[12];
    memcpy(nanpos, pos, sizeof nanpos);
    nanpos[4] = NAN;
    assert_int_equal(ss_mesh_from_arrays(nanpos, NULL, uv, 4, idx, 2, "quad", &m, &err),
                     SS_ERR_INPUT);
}

/* Coordinates near FLT_MAX: triangle centroids overflow to +-inf, the
 * centroid extent to inf, and the bin of a triangle came out NaN before the
 * conversion to int (found by fuzz_gltf; UBSan in make test-asan flags the
 * conversion). Three triangles at x = +3e38, three at -3e38. */
static void test_bvh_huge_coordinates(void **state) {
    (void)state;
    ss_error err;
    const float M = 3.0e38f;
    float pos[18 * 3];
    uint32_t idx[18];
    for (int t = 0; t < 6; t++)
        for (int k = 0; k < 3; k++) {
            float *p = &pos[3 * (3 * t + k)];
            p[0] = t < 3 ? M : -M;
            p[1] = (float)(t + k);
            p[2] = (float)(k == 2);
            idx[3 * t + k] = (uint32_t)(3 * t + k);
        }
    ss_mesh m;
    assert_int_equal(ss_mesh_from_arrays(pos, NULL, NULL, 18, idx, 6, "huge", &m, &err), SS_OK);
    ss_bvh *b = ss_bvh_build(&m, &err);
    assert_non_null(b);
    ss_bvh_free(b);
    ss_mesh_free(&m);
}

/* UV padding: two islands (a triangle and a quad) on a 48 x 40 texture with
 * a different value in every covered texel. Outside texels within N of an
 * island get the value of a covered texel at the least distance (brute
 * force over all covered texels), farther ones and covered ones keep
 * theirs; the same with 1 and 2 threads. */
static void test_uv_pad(void **state) {
    (void)state;
    ss_error err;
    const int W = 48, H = 40, N = 5;
    const float pos[7 * 3] = {0};
    const float uv[7 * 2] = {0.10f, 0.10f, 0.45f, 0.15f, 0.20f, 0.70f, /* triangle */
                             0.60f, 0.30f, 0.90f, 0.30f, 0.90f, 0.80f, 0.60f, 0.80f};
    const uint32_t idx[9] = {0, 1, 2, 3, 4, 5, 3, 5, 6};
    ss_mesh m;
    assert_int_equal(ss_mesh_from_arrays(pos, NULL, uv, 7, idx, 3, "islands", &m, &err), SS_OK);
    unsigned char *in = malloc((size_t)W * H);
    assert_int_equal(ss_mesh_uv_coverage(&m, W, H, in, &err), SS_OK);
    /* the quad island covers x 29..43 (centres 0.6*48=28.8 .. 43.2), y 12..31 */
    assert_true(in[20 * W + 35] && !in[20 * W + 28] && in[20 * W + 29] && !in[11 * W + 35]);
    ss_image *img = ss_image_create(W, H, 2, &err), *ref = ss_image_create(W, H, 2, &err);
    for (int i = 0; i < W * H; i++) {
        img->data[2 * i] = in[i] ? (float)i : -1.0f;
        img->data[2 * i + 1] = in[i] ? (float)(i % 7) : -2.0f;
    }
    memcpy(ref->data, img->data, (size_t)W * H * 2 * sizeof(float));
    ss_image *again = ss_image_clone(img, &err);
    ss_threads_set(2);
    assert_int_equal(ss_image_pad_islands(img, in, N, &err), SS_OK);
    ss_threads_set(1);
    assert_int_equal(ss_image_pad_islands(again, in, N, &err), SS_OK);
    assert_memory_equal(img->data, again->data, (size_t)W * H * 2 * sizeof(float));
    int padded = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const int i = y * W + x;
            if (in[i]) {
                assert_true(img->data[2 * i] == ref->data[2 * i] &&
                            img->data[2 * i + 1] == ref->data[2 * i + 1]);
                continue;
            }
            long best = -1;
            for (int j = 0; j < W * H; j++) {
                if (!in[j]) continue;
                long dx = j % W - x, dy = j / W - y, d2 = dx * dx + dy * dy;
                if (best < 0 || d2 < best) best = d2;
            }
            if (best > (long)N * N) {
                assert_true(img->data[2 * i] == -1.0f && img->data[2 * i + 1] == -2.0f);
                continue;
            }
            int src = (int)img->data[2 * i];
            assert_true(src >= 0 && src < W * H && in[src]);
            long dx = src % W - x, dy = src / W - y;
            assert_int_equal(dx * dx + dy * dy, best); /* a nearest covered texel */
            assert_true(img->data[2 * i + 1] == (float)(src % 7));
            padded++;
        }
    assert_true(padded > 100);
    /* n = 0 changes nothing; no UVs is an input error */
    memcpy(again->data, ref->data, (size_t)W * H * 2 * sizeof(float));
    assert_int_equal(ss_image_pad_islands(again, in, 0, &err), SS_OK);
    assert_memory_equal(again->data, ref->data, (size_t)W * H * 2 * sizeof(float));
    ss_mesh nouv;
    assert_int_equal(ss_mesh_from_arrays(pos, NULL, NULL, 7, idx, 3, "bare", &nouv, &err), SS_OK);
    assert_int_equal(ss_mesh_uv_coverage(&nouv, W, H, in, &err), SS_ERR_INPUT);
    ss_mesh_free(&nouv);
    ss_image_free(img);
    ss_image_free(ref);
    ss_image_free(again);
    free(in);
    ss_mesh_free(&m);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hand),
        cmocka_unit_test(test_obj),
        cmocka_unit_test(test_gltf),
        cmocka_unit_test(test_bvh_hand),
        cmocka_unit_test(test_bvh_soup),
        cmocka_unit_test(test_ray_uv),
        cmocka_unit_test(test_bvh_huge_coordinates),
        cmocka_unit_test(test_uv_pad),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
