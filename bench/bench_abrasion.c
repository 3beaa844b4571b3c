/* Abrasion benchmark: ms per key position and for the whole timeline at
 * 2048x2048, ms for one arbitrary frame (a blend and a maturation frame),
 * value noise ns/sample (6 octaves), on 1 and 2 threads. Prints figures only.
 * usage: bench_abrasion [size] */
#include <stdio.h>
#include <stdlib.h>

#include "skinsim/abrasion.h"
#include "skinsim/texture.h"

static double best_of(int reps, double (*fn)(void *), void *arg) {
    double best = 1e30;
    for (int r = 0; r < reps; r++) {
        double t = fn(arg);
        if (t < best) best = t;
    }
    return best;
}

typedef struct job {
    ss_wound_shape *w;
    ss_base_skin *skin;
    ss_abrasion_settings *s;
    ss_texture_set *out;
    ss_phase phase;
    ss_abrasion *ab;
    double day;
    ss_image *noise_img;
} job;

static double run_phase(void *p) {
    job *j = p;
    ss_error err;
    double t0 = ss_now();
    if (ss_abrasion_render_phase(j->phase, 0.0, j->w, j->skin, j->s, j->out, &err)) {
        fprintf(stderr, "%s\n", err.msg);
        exit(1);
    }
    return ss_now() - t0;
}

static double run_timeline(void *p) {
    job *j = p;
    ss_error err;
    ss_timeline tl;
    ss_timeline_default(&tl);
    ss_abrasion *a;
    double t0 = ss_now();
    if (ss_abrasion_create(j->s, &tl, j->w, j->skin, &a, &err)) {
        fprintf(stderr, "%s\n", err.msg);
        exit(1);
    }
    double t = ss_now() - t0;
    ss_abrasion_free(a);
    return t;
}

/* A repaint: the keys re-rendered for the shape into existing textures. */
static double run_update(void *p) {
    job *j = p;
    ss_error err;
    double t0 = ss_now();
    if (ss_abrasion_update(j->ab, j->w, &err)) {
        fprintf(stderr, "%s\n", err.msg);
        exit(1);
    }
    return ss_now() - t0;
}

static double run_frame(void *p) {
    job *j = p;
    ss_error err;
    double t0 = ss_now();
    if (ss_abrasion_frame(j->ab, j->day, j->out, &err)) {
        fprintf(stderr, "%s\n", err.msg);
        exit(1);
    }
    return ss_now() - t0;
}

static double run_noise(void *p) {
    job *j = p;
    ss_error err;
    ss_noise_params np;
    ss_noise_params_default(&np);
    np.octaves = 5; /* Alg. 3.2 runs octaves..0: 6 octaves */
    double t0 = ss_now();
    ss_value_noise(&np, 1, 2, j->noise_img, &err);
    return ss_now() - t0;
}

int main(int argc, char **argv) {
    int n = argc > 1 ? atoi(argv[1]) : 2048;
    if (n < 16 || n > 16384) {
        fprintf(stderr, "usage: bench_abrasion [size 16..16384]\n");
        return 2;
    }
    ss_error err;
    ss_stroke_set st;
    ss_abrasion_example_strokes(&st, &err);
    ss_wound_shape *w;
    ss_base_skin skin;
    ss_abrasion_settings s;
    ss_abrasion_settings_default(&s);
    s.size = n;
    double t0 = ss_now();
    if (ss_wound_shape_from_strokes(&st, SS_HULL_CONVEX, 5, n, 1, &w, &err) ||
        ss_base_skin_create(NULL, NULL, n, 1, &skin, &err)) {
        fprintf(stderr, "%s\n", err.msg);
        return 1;
    }
    printf("abrasion benchmark, %dx%d (setup: shape + base skin %.1f ms)\n", n, n,
           (ss_now() - t0) * 1e3);
    ss_texture_set out;
    ss_texture_set_create(n, &out, &err);
    ss_image *noise_img = ss_image_create(n, n, 1, &err);
    ss_timeline tl;
    ss_timeline_default(&tl);
    for (int threads = 1; threads <= 2; threads++) {
        ss_threads_set(threads);
        printf("\n-- %d thread%s --\n", threads, threads > 1 ? "s" : "");
        job j = {w, &skin, &s, &out, 0, NULL, 0, noise_img};
        for (int ph = 0; ph < SS_PHASE_COUNT; ph++) {
            j.phase = (ss_phase)ph;
            printf("  key %-17s %8.1f ms\n", ss_phase_name((ss_phase)ph),
                   1e3 * best_of(3, run_phase, &j));
        }
        printf("  whole timeline (5 keys, allocating) %8.1f ms   target <= 300 ms on 2 cores; seed "
               "943 ms on "
               "a GTX 780\n",
               1e3 * best_of(3, run_timeline, &j));
        ss_abrasion_create(&s, &tl, w, &skin, &j.ab, &err);
        printf("  repaint (5 keys, textures reused) %8.1f ms   (the seed's measure: a wound drawn "
               "again)\n",
               1e3 * best_of(3, run_update, &j));
        j.day = 0.5 * (tl.key[3].day + tl.key[4].day);
        printf("  frame (blend of 2 keys)  %8.1f ms   target <= 15 ms\n",
               1e3 * best_of(5, run_frame, &j));
        j.day = 20.0;
        printf("  frame (maturation)       %8.1f ms   target <= 15 ms\n",
               1e3 * best_of(5, run_frame, &j));
        /* What a time slider needs: the colour map only. */
        ss_texture_set color_only = {out.color, NULL, NULL, NULL};
        j.out = &color_only;
        j.day = 0.5 * (tl.key[3].day + tl.key[4].day);
        printf("  colour frame (blend)     %8.1f ms\n", 1e3 * best_of(5, run_frame, &j));
        j.day = 20.0;
        printf("  colour frame (maturation)%8.1f ms\n", 1e3 * best_of(5, run_frame, &j));
        j.out = &out;
        ss_abrasion_free(j.ab);
        /* The cost grows with the wound: the same timeline for a wound that
         * covers most of the texture (a square from 0.05 to 0.95). */
        {
            ss_stroke_set big = {0};
            double u[4] = {0.05, 0.95, 0.95, 0.05}, v[4] = {0.05, 0.05, 0.95, 0.95};
            int ids[4] = {0, 0, 0, 0}, one[1] = {0};
            big.npoints = 4;
            big.u = u;
            big.v = v;
            big.stroke = ids;
            big.nstrokes = 1;
            big.stroke_ids = one;
            ss_wound_shape *wb;
            if (ss_wound_shape_from_strokes(&big, SS_HULL_CONVEX, 5, n, 1, &wb, &err) == SS_OK) {
                job jb = j;
                jb.w = wb;
                printf("  whole timeline, wound covering 81%% of the texture %8.1f ms\n",
                       1e3 * best_of(2, run_timeline, &jb));
                ss_wound_shape_free(wb);
            }
        }
        double tn = best_of(3, run_noise, &j);
        printf("  value noise, 6 octaves   %8.2f ns/sample (%.1f ms per %dx%d texture)\n",
               tn * 1e9 / ((double)n * n), tn * 1e3, n, n);
    }
    ss_image_free(noise_img);
    ss_texture_set_free(&out);
    ss_base_skin_free(&skin);
    ss_wound_shape_free(w);
    ss_stroke_set_free(&st);
    return 0;
}
