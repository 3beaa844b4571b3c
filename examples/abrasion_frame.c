/* Example: one frame of the abrasion-healing timeline, with the installed
 * library.
 *
 *   cc abrasion_frame.c $(pkg-config --cflags --libs skinsim) -o abrasion_frame
 *   ./abrasion_frame 3 out          # day 3 after the injury, into folder out/
 *
 * Renders the five key positions for the built-in example stroke at 256 px,
 * blends the frame at the given day, and writes its colour (sRGB) and normal
 * map as PNG. Prints the mean colour inside and outside the wound. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <skinsim/abrasion.h>
#include <skinsim/core.h>

int main(int argc, char **argv) {
    double day = 3.0;
    if (argc > 3) {
        fprintf(stderr, "usage: abrasion_frame [DAY [FOLDER]]\n");
        return 2;
    }
    if (argc > 1) {
        char *end = NULL;
        errno = 0;
        day = strtod(argv[1], &end);
        if (end == argv[1] || *end != '\0' || errno == ERANGE || !isfinite(day)) {
            fprintf(stderr, "abrasion_frame: day '%s' is not a number\n", argv[1]);
            return 2;
        }
    }
    const char *dir = argc > 2 ? argv[2] : ".";
    ss_abrasion_settings set;
    ss_abrasion_settings_default(&set);
    set.size = 256;
    ss_timeline timeline;
    ss_timeline_default(&timeline);

    ss_error err = {0};
    ss_stroke_set strokes = {0};
    ss_wound_shape *shape = NULL;
    ss_base_skin skin = {0};
    ss_abrasion *ab = NULL;
    ss_texture_set frame = {0};
    char path[4096];
    ss_status st = ss_abrasion_example_strokes(&strokes, &err);
    if (!st)
        st = ss_wound_shape_from_strokes(&strokes, SS_HULL_CONVEX, 0, set.size, set.seed, &shape,
                                         &err);
    if (!st) st = ss_base_skin_create(NULL, NULL, set.size, set.seed, &skin, &err);
    if (!st) st = ss_abrasion_create(&set, &timeline, shape, &skin, &ab, &err);
    if (!st) st = ss_texture_set_create(set.size, &frame, &err);
    if (!st) st = ss_abrasion_frame(ab, day, &frame, &err);
    if (!st) st = ss_mkdir_p(dir, &err);
    if (!st) {
        snprintf(path, sizeof path, "%s/frame_color.png", dir);
        st = ss_png_write(path, frame.color, 8, SS_ENC_SRGB, &err);
    }
    if (!st) {
        snprintf(path, sizeof path, "%s/frame_normal.png", dir);
        st = ss_png_write(path, frame.normal, 8, SS_ENC_LINEAR, &err);
    }
    if (!st) {
        double sum[2][3] = {{0}}, n[2] = {0};
        for (int y = 0; y < set.size; y++)
            for (int x = 0; x < set.size; x++) {
                int in = ss_image_px(shape->mask, x, y)[0] > 0.5f;
                const float *c = ss_image_px(frame.color, x, y);
                for (int k = 0; k < 3; k++) sum[in][k] += c[k];
                n[in] += 1;
            }
        printf("day %g: %d wound(s)\n", day, shape->nwounds);
        for (int in = 1; in >= 0; in--)
            printf("  mean linear colour %s the wound: %.3f %.3f %.3f\n",
                   in ? "inside " : "outside", sum[in][0] / n[in], sum[in][1] / n[in],
                   sum[in][2] / n[in]);
        printf("wrote %s/frame_color.png and %s/frame_normal.png\n", dir, dir);
    } else {
        fprintf(stderr, "abrasion_frame: %s\n", err.msg);
    }
    ss_texture_set_free(&frame);
    ss_abrasion_free(ab);
    ss_base_skin_free(&skin);
    ss_wound_shape_free(shape);
    ss_stroke_set_free(&strokes);
    return ss_status_exit_code(st);
}
