/* libFuzzer: Wavefront OBJ, through both readers: the viewer's
 * ss_mesh_load (.obj: v/vt/vn/f, then a BVH and a ray) and heal's wound-mesh
 * ss_obj_parse (then the closed-mesh check). */
#include <math.h>

#include "fuzz_util.h"
#include "skinsim/heal_io.h"
#include "skinsim/mesh.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    ss_error err;
    const char *path = fuzz_file(data, size, ".obj");
    ss_mesh m;
    if (path && ss_mesh_load(path, &m, &err) == SS_OK) {
        ss_bvh *b = ss_bvh_build(&m, &err);
        const float o[3] = {0, 0, 10}, d[3] = {0.01f, 0.02f, -1};
        ss_ray_hit h;
        if (b) ss_bvh_raycast(b, o, d, 0, INFINITY, &h);
        ss_bvh_free(b);
        ss_mesh_free(&m);
    }
    char *text = fuzz_text(data, size);
    ss_tri_mesh t;
    if (text && ss_obj_parse(text, "fuzz.obj", &t, &err) == SS_OK) {
        (void)ss_tri_mesh_check_closed(&t, "fuzz.obj", &err);
        ss_tri_mesh_free(&t);
    }
    free(text);
    return 0;
}
