/* libFuzzer target for the inputs a user hands over: stroke CSV, timeline
 * JSON, PNG masks and meshes (GLB/glTF JSON, OBJ). Each input goes through the same readers the
 * CLI uses (via a temporary file); any crash or sanitizer report is a bug.
 * Build: make fuzz (clang -fsanitize=fuzzer,address,undefined). */
#define _DEFAULT_SOURCE /* mkstemps */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "skinsim/abrasion.h"
#include "skinsim/mesh.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size < 1) return 0;
    /* Meshes are read by extension: the path carries one. */
    static const char *const ext[] = {".csv", ".json", ".png", ".glb", ".gltf", ".obj"};
    char path[64];
    snprintf(path, sizeof path, "/tmp/skinsim-fuzz-XXXXXX%s", ext[data[0] % 6]);
    int fd = mkstemps(path, (int)strlen(ext[data[0] % 6]));
    if (fd < 0) return 0;
    /* The first byte picks the reader, the rest is the file. */
    if (write(fd, data + 1, size - 1) < 0) {
        close(fd);
        unlink(path);
        return 0;
    }
    close(fd);
    ss_error err;
    switch (data[0] % 6) {
    case 0: {
        ss_stroke_set s;
        if (ss_stroke_csv_read(path, &s, &err) == SS_OK) {
            ss_wound_shape *w = NULL;
            if (ss_wound_shape_from_strokes(&s,
                                            (data[0] / 3) % 2 ? SS_HULL_CONCAVE : SS_HULL_CONVEX, 5,
                                            32, 1, &w, &err) == SS_OK)
                ss_wound_shape_free(w);
            ss_stroke_set_free(&s);
        }
        break;
    }
    case 1: {
        ss_timeline t;
        ss_timeline_load_json(path, &t, &err);
        break;
    }
    case 3:
    case 4:
    case 5: {
        ss_mesh m;
        if (ss_mesh_load(path, &m, &err) == SS_OK) {
            ss_bvh *b = ss_bvh_build(&m, &err);
            const float o[3] = {0, 0, 10}, d[3] = {0.01f, 0.02f, -1};
            ss_ray_hit h;
            if (b) ss_bvh_raycast(b, o, d, 0, INFINITY, &h);
            ss_bvh_free(b);
            ss_mesh_free(&m);
        }
        break;
    }
    default: {
        ss_image *img = ss_png_read(path, SS_ENC_LINEAR, &err);
        if (img && img->width <= 512 && img->height <= 512) {
            ss_wound_shape *w = NULL;
            if (ss_wound_shape_from_mask(img, 32, 1, &w, &err) == SS_OK) ss_wound_shape_free(w);
        }
        ss_image_free(img);
    }
    }
    unlink(path);
    return 0;
}
