/* The built-in example stroke of `skinsim abrasion` (its own file: the CSV
 * reader is geom's). */
#include "skinsim/abrasion.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

ss_status ss_abrasion_example_strokes(ss_stroke_set *out, ss_error *err) {
    /* A brush path scrubbed back and forth over a roundish patch, like the
     * knuckle abrasion of the seed's Fig. 4.5 (whose hull is "one big
     * circle"): points on an ellipse of radii 0.15 x 0.12 and a wobbly inner
     * loop, tilted. */
    enum { N = 49 * 2 };
    memset(out, 0, sizeof *out);
    out->u = malloc(N * sizeof(double));
    out->v = malloc(N * sizeof(double));
    out->stroke = calloc(N, sizeof(int));
    out->stroke_ids = calloc(1, sizeof(int));
    if (!out->u || !out->v || !out->stroke || !out->stroke_ids) {
        ss_stroke_set_free(out);
        return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    const double cx = 0.5, cy = 0.5, rx = 0.15, ry = 0.12, tilt = 0.35;
    int n = 0;
    for (int i = 0; i <= 48; i++) {
        double t = i / 48.0 * 2.0 * M_PI;
        for (int pass = 0; pass < 2; pass++) {
            double r = pass ? 0.55 + 0.3 * sin(5 * t) : 1.0 - 0.06 * cos(3 * t);
            double ex = rx * r * cos(t), ey = ry * r * sin(t);
            out->u[n] = cx + ex * cos(tilt) - ey * sin(tilt);
            out->v[n] = cy + ex * sin(tilt) + ey * cos(tilt);
            n++;
        }
    }
    out->npoints = n;
    out->nstrokes = 1;
    return SS_OK;
}
