/* libFuzzer: glTF 2.0 meshes, as .glb (binary chunks) or .gltf (JSON with
 * data URIs), picked by the first byte, through ss_mesh_load, then a BVH and
 * a ray. */
#include <math.h>

#include "fuzz_util.h"
#include "skinsim/mesh.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size < 1) return 0;
    ss_error err;
    const char *path = fuzz_file(data + 1, size - 1, data[0] & 1 ? ".gltf" : ".glb");
    ss_mesh m;
    if (path && ss_mesh_load(path, &m, &err) == SS_OK) {
        ss_bvh *b = ss_bvh_build(&m, &err);
        const float o[3] = {0, 0, 10}, d[3] = {0.01f, 0.02f, -1};
        ss_ray_hit h;
        if (b) ss_bvh_raycast(b, o, d, 0, INFINITY, &h);
        ss_bvh_free(b);
        ss_mesh_free(&m);
    }
    return 0;
}
