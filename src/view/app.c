/* `skinsim view` (the skinsim-view program): the interactive painter and
 * viewer of seed 000 §4.2 on GTK 4 + GtkGLArea, and its batch face.
 *
 * One controller (struct app) holds the mesh, camera, painted strokes,
 * texture stack and time; GTK event handlers, script lines and batch options
 * all call the same app_* functions, so a script replays exactly what a
 * mouse does. Generate runs the abrasion timeline in a worker thread
 * (pthread) that only computes; the UI thread polls its progress, and
 * uploads the finished layers in the GL context, so the window stays live.
 *
 * Batch (--screenshot, --bench-frames, --save-strokes): inputs are all read
 * and checked first (exit 2 naming the input); then a GL context is made:
 * the GtkGLArea of a window on the display (Xvfb in tests), or, with --egl
 * or when no display can be opened, an EGL surfaceless context (Mesa
 * llvmpipe needs neither X nor a GPU). Frames for files and benchmarks go to
 * an offscreen framebuffer of exactly --size, whatever the window got. */
#define _POSIX_C_SOURCE 200809L
#include "view.h"

#include <cjson/cJSON.h>
#include <epoxy/egl.h>
#include <epoxy/gl.h>
#include <getopt.h>
#include <gtk/gtk.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"

static const char *CMD = "view";
#define VIEW_HISTORY 64 /* undo steps kept */
#define RING_POINTS 48

/* ---- options ------------------------------------------------------------------ */

typedef struct opts {
    const char *mesh, *load, *strokes, *screenshot, *script, *save_strokes, *window_shot,
        *save_mask;
    int width, height, texture_size, bench_frames, generate, egl, json, quiet, hide_strokes, mirror;
    double day, brush_mm, displace;
    double t_start; /* when main started (ss_now) */
    uint64_t seed;
} opts;

static void help(void) {
    printf("usage: skinsim view [options]\n\n"
           "Paint a wound on a body and scrub its healing (seed 000 §4.2): GTK 4 window\n"
           "with the mesh, paint mode, Generate and a time slider.\n\n"
           "  --mesh FILE          .glb/.gltf/.obj with UVs (default: the shipped hand)\n"
           "  --load DIR           textures: a `skinsim abrasion` or `skinsim wound` folder\n"
           "                       (timeline.json) or a single set (`skinsim skin`:\n"
           "                       base_color.png, roughness/specular, normal, height)\n"
           "  --strokes FILE.csv   painted strokes to start from (the abrasion CSV)\n"
           "  --generate           run Generate at start (painted strokes, else the\n"
           "                       built-in example wound)\n"
           "  --texture-size N     texture side for Generate (default 2048)\n"
           "  --time DAYS          time on the slider (default 0)\n"
           "  --brush-mm R         brush radius on the surface in mm (default 4)\n"
           "  --displace X         height displacement scale (default 1 = true size)\n"
           "  --seed S             random seed (default 1)\n"
           "  --hide-strokes       do not draw the painted strokes (H toggles)\n"
           "  --mirror             mirror symmetry: every stroke is also painted mirrored\n"
           "                       in the plane x = the mesh's centre (M toggles)\n\n"
           "Batch (no window needed; exits when done):\n"
           "  --screenshot FILE.png  render one frame to FILE\n"
           "  --size WxH           frame size (default 1280x720)\n"
           "  --script FILE        replay events: move X Y | press X Y [1|2|3] [shift] |\n"
           "                       release X Y | drag X1 Y1 X2 Y2 STEPS | scroll DY |\n"
           "                       key NAME | slider DAYS | wait (window pixels)\n"
           "  --save-strokes FILE  write the painted strokes (CSV) at the end\n"
           "  --save-mask FILE.png write the painted wound as a UV mask (white = wound,\n"
           "                       --texture-size; what skinsim abrasion --mask reads)\n"
           "  --bench-frames N     render N frames across the timeline; print ms/frame\n"
           "                       (median, 95th percentile) and the resolution\n"
           "  --egl                headless OpenGL through EGL (no display needed)\n"
           "  --window-shot FILE.png  open the window, replay --script, save a picture\n"
           "                       of the whole window (controls included) and close\n"
           "  --json               print a JSON summary on stdout\n"
           "  --quiet              no messages on stderr but errors\n\n"
           "Controls: drag rotates, shift-drag or right/middle drag pans, wheel zooms;\n"
           "P paint mode (drag paints; a ring shows the brush), E eraser, M mirror,\n"
           "Z or Ctrl+Z undo, Y, Ctrl+Y or Ctrl+Shift+Z redo, C clear, G generate,\n"
           "Space play/pause, Left/Right previous/next key, S save strokes, X save the\n"
           "mask, H hide/show strokes, R reset view, F1 help, Escape or Ctrl+Q quit.\n\n"
           "Example (scrub a `skinsim abrasion --out abrasion-out` result):\n"
           "  skinsim view --load abrasion-out\n");
}

static int parse_size(const char *s, int *w, int *h, ss_error *err) {
    char tail;
    if (sscanf(s, "%dx%d%c", w, h, &tail) != 2 || *w < 16 || *h < 16 || *w > 8192 || *h > 8192)
        return ss_error_set(err, SS_ERR_INPUT, "--size: '%s' is not WxH (16..8192)", s);
    return SS_OK;
}

static int parse(int argc, char **argv, opts *o, ss_error *err) {
    static const struct option lo[] = {{"mesh", 1, 0, 'm'},
                                       {"load", 1, 0, 'l'},
                                       {"strokes", 1, 0, 's'},
                                       {"screenshot", 1, 0, 'o'},
                                       {"script", 1, 0, 'x'},
                                       {"save-strokes", 1, 0, 'w'},
                                       {"size", 1, 0, 'z'},
                                       {"texture-size", 1, 0, 'n'},
                                       {"bench-frames", 1, 0, 'b'},
                                       {"generate", 0, 0, 'g'},
                                       {"egl", 0, 0, 'e'},
                                       {"json", 0, 0, 'J'},
                                       {"quiet", 0, 0, 'q'},
                                       {"time", 1, 0, 't'},
                                       {"brush-mm", 1, 0, 'r'},
                                       {"displace", 1, 0, 'd'},
                                       {"seed", 1, 0, 'S'},
                                       {"help", 0, 0, 'h'},
                                       {"window-shot", 1, 0, 'W'},
                                       {"hide-strokes", 0, 0, 'H'},
                                       {"save-mask", 1, 0, 'M'},
                                       {"mirror", 0, 0, 'X'},
                                       {0, 0, 0, 0}};
    memset(o, 0, sizeof *o);
    o->width = 1280, o->height = 720, o->texture_size = 2048;
    o->brush_mm = 4, o->displace = 1, o->seed = 1;
    optind = 1;
    opterr = 0;
    int c;
    long v;
    ss_status st = SS_OK;
    while (!st && (c = getopt_long(argc, argv, "", lo, NULL)) != -1) {
        switch (c) {
        case 'm':
            o->mesh = optarg;
            break;
        case 'l':
            o->load = optarg;
            break;
        case 's':
            o->strokes = optarg;
            break;
        case 'o':
            o->screenshot = optarg;
            break;
        case 'x':
            o->script = optarg;
            break;
        case 'w':
            o->save_strokes = optarg;
            break;
        case 'W':
            o->window_shot = optarg;
            break;
        case 'H':
            o->hide_strokes = 1;
            break;
        case 'M':
            o->save_mask = optarg;
            break;
        case 'X':
            o->mirror = 1;
            break;
        case 'z':
            st = parse_size(optarg, &o->width, &o->height, err);
            break;
        case 'n':
            st = cli_parse_int("--texture-size", optarg, 16, 4096, &v, err);
            o->texture_size = (int)v;
            break;
        case 'b':
            st = cli_parse_int("--bench-frames", optarg, 1, 100000, &v, err);
            o->bench_frames = (int)v;
            break;
        case 'g':
            o->generate = 1;
            break;
        case 'e':
            o->egl = 1;
            break;
        case 'J':
            o->json = 1;
            break;
        case 'q':
            o->quiet = 1;
            break;
        case 't':
            st = cli_parse_double("--time", optarg, 0, 1e5, &o->day, err);
            break;
        case 'r':
            st = cli_parse_double("--brush-mm", optarg, 0.01, 1000, &o->brush_mm, err);
            break;
        case 'd':
            st = cli_parse_double("--displace", optarg, 0, 1000, &o->displace, err);
            break;
        case 'S':
            st = cli_parse_u64("--seed", optarg, &o->seed, err);
            break;
        case 'h':
            help();
            return -1;
        default:
            st = ss_error_set(err, SS_ERR_INPUT, "unknown or incomplete option '%s'",
                              argv[optind - 1]);
        }
    }
    if (!st && optind < argc)
        st = ss_error_set(err, SS_ERR_INPUT, "unexpected argument '%s'", argv[optind]);
    return (int)st;
}

/* ---- scripts ------------------------------------------------------------------- */

typedef enum ev_kind {
    EV_MOVE,
    EV_PRESS,
    EV_RELEASE,
    EV_DRAG,
    EV_SCROLL,
    EV_KEY,
    EV_SLIDER,
    EV_WAIT
} ev_kind;
typedef struct script_ev {
    ev_kind kind;
    double x, y, x2, y2, value;
    int button, shift, steps;
    char key[64];
    int line;
} script_ev;

static int count_words(const char *s) {
    int n = 0, in = 0;
    for (; *s; s++) {
        int sp = *s == ' ' || *s == '\t';
        if (!sp && !in) n++;
        in = !sp;
    }
    return n;
}

static ss_status parse_script(const char *path, script_ev **out, int *n, ss_error *err) {
    *out = NULL;
    *n = 0;
    char *text = ss_read_file(path, NULL, err);
    if (!text) return err->code;
    int cap = 64, k = 0, lineno = 0;
    script_ev *ev = malloc(sizeof *ev * (size_t)cap);
    char line[512];
    ss_status st = ev ? SS_OK : ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    const char *p = text;
    while (!st) {
        int too_long = 0;
        p = ss_text_next_line(p, line, sizeof line, &too_long);
        if (!p) break;
        lineno++;
        char *l = ss_text_trim(line);
        if (too_long) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s:%d: line too long", path, lineno);
            break;
        }
        if (!*l || *l == '#') continue;
        if (k == cap) {
            script_ev *e2 = realloc(ev, sizeof *ev * (size_t)(cap *= 2));
            if (!e2) {
                st = ss_error_set(err, SS_ERR_NOMEM, "out of memory");
                break;
            }
            ev = e2;
        }
        script_ev *e = &ev[k];
        memset(e, 0, sizeof *e);
        e->line = lineno;
        e->button = 1;
        char w[5][64] = {"", "", "", "", ""};
        char extra[8];
        int nw = count_words(l);
        if (nw > 6 ||
            sscanf(l, "%63s %63s %63s %63s %63s %7s", w[0], w[1], w[2], w[3], w[4], extra) < 1) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s:%d: too many words", path, lineno);
            break;
        }
        double num[5];
        int nnum = 0, bad = 0;
        for (int i = 1; i < nw && i < 5; i++) {
            if (!strcmp(w[i], "shift")) {
                e->shift = 1;
                continue;
            }
            if (ss_text_parse_number(w[i], &num[nnum]) != 0) {
                if (strcmp(w[0], "key")) bad = 1;
            } else if (fabs(num[nnum]) > 1e6) {
                bad = 1;
            } else {
                nnum++;
            }
        }
        const char *cmd = w[0];
        if (bad) {
            st = ss_error_set(err, SS_ERR_INPUT, "%s:%d: '%s' takes numbers", path, lineno, cmd);
        } else if (!strcmp(cmd, "move") || !strcmp(cmd, "release")) {
            if (nnum != 2) st = ss_error_set(err, SS_ERR_INPUT, "%s:%d: %s X Y", path, lineno, cmd);
            e->kind = cmd[0] == 'm' ? EV_MOVE : EV_RELEASE;
            e->x = num[0], e->y = num[1];
        } else if (!strcmp(cmd, "press")) {
            if (nnum < 2 || nnum > 3)
                st = ss_error_set(err, SS_ERR_INPUT, "%s:%d: press X Y [button] [shift]", path,
                                  lineno);
            e->kind = EV_PRESS;
            e->x = num[0], e->y = num[1];
            if (nnum == 3) e->button = (int)num[2];
            if (e->button < 1 || e->button > 3)
                st = ss_error_set(err, SS_ERR_INPUT, "%s:%d: button must be 1, 2 or 3", path,
                                  lineno);
        } else if (!strcmp(cmd, "drag")) {
            double n5;
            if (nnum != 4 || nw != 6 || ss_text_parse_number(extra, &n5) || n5 < 1 || n5 > 10000)
                st = ss_error_set(err, SS_ERR_INPUT, "%s:%d: drag X1 Y1 X2 Y2 STEPS", path, lineno);
            e->kind = EV_DRAG;
            e->x = num[0], e->y = num[1], e->x2 = num[2], e->y2 = num[3];
            e->steps = st ? 1 : (int)n5;
        } else if (!strcmp(cmd, "scroll") || !strcmp(cmd, "slider")) {
            if (nnum != 1 || (cmd[1] == 'l' && num[0] < 0))
                st = ss_error_set(err, SS_ERR_INPUT, "%s:%d: %s VALUE%s", path, lineno, cmd,
                                  cmd[1] == 'l' ? " (days >= 0)" : "");
            e->kind = cmd[1] == 'c' ? EV_SCROLL : EV_SLIDER;
            e->value = num[0];
        } else if (!strcmp(cmd, "key")) {
            if (nw != 2) st = ss_error_set(err, SS_ERR_INPUT, "%s:%d: key NAME", path, lineno);
            e->kind = EV_KEY;
            snprintf(e->key, sizeof e->key, "%s", w[1]);
        } else if (!strcmp(cmd, "wait")) {
            e->kind = EV_WAIT;
        } else {
            st = ss_error_set(err, SS_ERR_INPUT, "%s:%d: unknown event '%s'", path, lineno, cmd);
        }
        if (!st) k++;
    }
    free(text);
    if (st) {
        free(ev);
        return st;
    }
    *out = ev;
    *n = k;
    return SS_OK;
}

/* ---- the controller -------------------------------------------------------------- */

typedef struct app {
    opts o;
    ss_mesh mesh;
    ss_paint paint;
    int can_paint;
    view_camera cam;
    view_layers layers;
    ss_image *skin; /* a loaded `skinsim skin` colour: Generate draws on it */
    view_renderer *rend;
    double day;
    int playing, paint_mode, strokes_dirty, layers_dirty, hide_strokes;
    int drag_button, drag_shift, dragging, painting;
    double lx, ly;
    /* paint tools: eraser, mirror (about the plane x = the mesh's centre),
     * the cursor (for the brush ring), undo/redo history of the samples */
    int erase_mode, mirror, hover, changed;
    double hx, hy;
    float *gesture; /* the current gesture's rays (origin, dir, right, up): mirrored at release */
    int ngesture, capgesture;
    struct paint_snap {
        ss_paint_sample *s;
        int n;
    } undo[VIEW_HISTORY], redo[VIEW_HISTORY];
    int nundo, nredo;
    /* Generate worker */
    pthread_t worker;
    int generating;
    volatile double progress;
    int worker_done; /* atomic */
    ss_status worker_status, gen_failed;
    ss_error worker_err;
    ss_stroke_set worker_strokes;
    view_layers worker_layers;
    /* script replay */
    script_ev *ev;
    int nev, next_ev;
    cJSON *picks;
    char status[1024];
    /* GTK (NULL when headless) */
    GtkWidget *window, *area, *scale, *day_label, *progress_bar, *status_label, *paint_btn,
        *play_btn, *gen_btn, *help_box, *erase_btn, *mirror_btn;
    int updating_scale;
    int quit;    /* Escape or Ctrl+Q: close the window at the next tick */
    int help;    /* the F1 help overlay is shown */
    int focused; /* the 3D view took the keyboard focus once the window was up */
    /* batch outputs: where to write (staging paths of ss_outputs) */
    const char *shot_path, *csv_path, *mask_path;
} app;

static void app_message(app *a, int is_error, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static void app_message(app *a, int is_error, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(a->status, sizeof a->status, fmt, ap);
    va_end(ap);
    if (is_error || !a->o.quiet) fprintf(stderr, "skinsim view: %s\n", a->status);
    if (a->status_label) {
        /* errors in the window as well as on stderr, in red */
        char *esc = g_markup_escape_text(a->status, -1);
        char *m =
            is_error
                ? g_strdup_printf("<span foreground=\"#d02020\" weight=\"bold\">%s</span>", esc)
                : g_strdup(esc);
        gtk_label_set_markup(GTK_LABEL(a->status_label), m);
        g_free(m);
        g_free(esc);
    }
}

static void app_redraw(app *a) {
    if (a->area) gtk_gl_area_queue_render(GTK_GL_AREA(a->area));
}

static void app_sync_time_widgets(app *a) {
    if (!a->scale) return;
    a->updating_scale = 1;
    double end = a->layers.end_day > 0 ? a->layers.end_day : 1;
    gtk_range_set_range(GTK_RANGE(a->scale), 0, end);
    gtk_range_set_value(GTK_RANGE(a->scale), a->day);
    a->updating_scale = 0;
    int la, lb, stop;
    float w;
    view_layers_locate(&a->layers, a->day, &la, &lb, &w, &stop);
    char buf[128];
    const char *name = a->layers.nstops ? a->layers.stop_name[stop] : "";
    if (a->day < 2.0 / 24)
        snprintf(buf, sizeof buf, "%.0f min  %s", a->day * 1440, name);
    else if (a->day < 2)
        snprintf(buf, sizeof buf, "%.1f h  %s", a->day * 24, name);
    else
        snprintf(buf, sizeof buf, "day %.1f  %s", a->day, name);
    gtk_label_set_text(GTK_LABEL(a->day_label), buf);
}

static void app_set_time(app *a, double day) {
    /* Not clamped to the current stack: --time 5 before Generate means day 5
     * of what Generate makes; rendering clamps to the last stop. */
    if (!(day >= 0)) day = 0;
    a->day = day;
    app_sync_time_widgets(a);
    app_redraw(a);
}

/* ---- paint history: snapshots of the samples (undo/redo any action) ---- */

static void snap_free(struct paint_snap *q) {
    free(q->s);
    q->s = NULL;
    q->n = 0;
}

static int snap_take(const ss_paint *p, struct paint_snap *q) {
    q->n = p->n;
    q->s = malloc(sizeof *q->s * (size_t)(p->n > 0 ? p->n : 1));
    if (!q->s) return 0;
    if (p->n) memcpy(q->s, p->s, sizeof *q->s * (size_t)p->n);
    return 1;
}

/* Replaces the samples by the snapshot's (the snapshot is consumed). */
static void snap_restore(ss_paint *p, struct paint_snap *q) {
    free(p->s);
    p->s = q->s;
    p->n = p->cap = q->n;
    if (p->cap == 0) {
        free(p->s);
        p->s = NULL;
    }
    q->s = NULL;
    q->n = 0;
}

/* Before an action that changes the samples: the current ones can come back. */
static void app_history_push(app *a) {
    if (!a->can_paint) return;
    if (a->nundo == VIEW_HISTORY) { /* the oldest step is forgotten */
        snap_free(&a->undo[0]);
        memmove(a->undo, a->undo + 1, sizeof a->undo[0] * (VIEW_HISTORY - 1));
        a->nundo--;
    }
    if (!snap_take(&a->paint, &a->undo[a->nundo])) return;
    a->nundo++;
    for (int i = 0; i < a->nredo; i++) snap_free(&a->redo[i]);
    a->nredo = 0;
}

/* An action that changed nothing leaves no undo step. */
static void app_history_drop_last(app *a) {
    if (a->nundo > 0) snap_free(&a->undo[--a->nundo]);
}

static int app_undo_redo(app *a, int redo) {
    struct paint_snap *from = redo ? a->redo : a->undo, *to = redo ? a->undo : a->redo;
    int *nfrom = redo ? &a->nredo : &a->nundo, *nto = redo ? &a->nundo : &a->nredo;
    if (*nfrom == 0 || a->painting) return 0;
    if (*nto == VIEW_HISTORY) {
        snap_free(&to[0]);
        memmove(to, to + 1, sizeof to[0] * (VIEW_HISTORY - 1));
        (*nto)--;
    }
    if (!snap_take(&a->paint, &to[*nto])) return 0;
    (*nto)++;
    snap_restore(&a->paint, &from[--*nfrom]);
    a->strokes_dirty = 1;
    return 1;
}

/* Removes the samples within the brush radius of the surface point the ray
 * hits; returns 1 on a hit. */
static int app_erase_ray(app *a, const float o[3], const float d[3]) {
    ss_ray_hit h;
    if (!ss_bvh_raycast(a->paint.bvh, o, d, 0, INFINITY, &h)) return 0;
    float q[3];
    for (int k = 0; k < 3; k++) q[k] = o[k] + h.t * d[k];
    double r2 = a->paint.brush_radius * a->paint.brush_radius;
    int k = 0;
    for (int i = 0; i < a->paint.n; i++) {
        const float *p = a->paint.s[i].pos;
        double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
        if (!isnan(p[0]) && dx * dx + dy * dy + dz * dz <= r2) continue;
        a->paint.s[k++] = a->paint.s[i];
    }
    if (k != a->paint.n) a->strokes_dirty = a->changed = 1;
    a->paint.n = k;
    return 1;
}

/* The mirror image of a ray in the plane x = centre of the mesh's box. */
static void mirror_vec(const app *a, const float in[3], float out[3], int is_point) {
    float cx = 0.5f * (a->mesh.bbox_min[0] + a->mesh.bbox_max[0]);
    out[0] = is_point ? 2 * cx - in[0] : -in[0];
    out[1] = in[1];
    out[2] = in[2];
}

/* A ray through pixel (x, y) paints (or erases); returns 1 on a hit. */
static int app_paint_at(app *a, double x, double y) {
    float o[3], d[3], r[3], u[3];
    view_camera_ray(&a->cam, x, y, o, d, r, u);
    if (a->erase_mode) {
        int hit = app_erase_ray(a, o, d);
        if (a->mirror) {
            float mo[3], md[3];
            mirror_vec(a, o, mo, 1), mirror_vec(a, d, md, 0);
            app_erase_ray(a, mo, md);
        }
        return hit;
    }
    if (a->mirror) { /* kept, to paint its mirror image at release */
        if (a->ngesture == a->capgesture) {
            int cap = a->capgesture ? 2 * a->capgesture : 256;
            float *g = realloc(a->gesture, sizeof *g * 12 * (size_t)cap);
            if (g) a->gesture = g, a->capgesture = cap;
        }
        if (a->ngesture < a->capgesture) {
            float *g = a->gesture + 12 * a->ngesture++;
            memcpy(g, o, sizeof o), memcpy(g + 3, d, sizeof d);
            memcpy(g + 6, r, sizeof r), memcpy(g + 9, u, sizeof u);
        }
    }
    ss_ray_hit h;
    int n0 = a->paint.n;
    int hit = ss_paint_add(&a->paint, o, d, r, u, &h);
    if (a->paint.n != n0) a->changed = 1;
    if (hit && a->picks) {
        cJSON *p = cJSON_CreateObject();
        cJSON_AddNumberToObject(p, "x", x);
        cJSON_AddNumberToObject(p, "y", y);
        cJSON_AddNumberToObject(p, "triangle", h.triangle);
        cJSON_AddNumberToObject(p, "u", h.uv[0]);
        cJSON_AddNumberToObject(p, "v", h.uv[1]);
        cJSON_AddNumberToObject(p, "island", a->paint.island[h.triangle]);
        cJSON_AddNumberToObject(p, "stroke", a->paint.n > n0 ? a->paint.s[n0].stroke : -1);
        cJSON_AddItemToArray(a->picks, p);
    }
    if (a->paint.n != n0) a->strokes_dirty = 1;
    return hit;
}

static void app_press(app *a, double x, double y, int button, int shift) {
    a->dragging = 1;
    a->drag_button = button;
    a->drag_shift = shift;
    a->lx = x, a->ly = y;
    a->painting = button == 1 && !shift && a->paint_mode && a->can_paint;
    if (a->painting) {
        app_history_push(a);
        a->changed = 0;
        a->ngesture = 0;
        if (!a->erase_mode) ss_paint_begin(&a->paint);
        app_paint_at(a, x, y);
        app_redraw(a);
    }
}

static void app_motion(app *a, double x, double y) {
    a->hover = 1, a->hx = x, a->hy = y; /* the brush ring follows the cursor */
    if (!a->dragging) {
        if (a->paint_mode) app_redraw(a);
        return;
    }
    if (a->painting) {
        /* Samples no farther apart than half the brush, so the band has no gaps. */
        double d = hypot(x - a->lx, y - a->ly);
        double brush_px = a->paint.brush_radius / view_camera_pixel_size(&a->cam, a->cam.dist);
        int steps = (int)ceil(d / fmax(1.0, 0.5 * brush_px));
        if (steps > 1000) steps = 1000;
        for (int i = 1; i <= steps; i++)
            app_paint_at(a, a->lx + (x - a->lx) * i / steps, a->ly + (y - a->ly) * i / steps);
    } else if (a->drag_button == 1 && !a->drag_shift) {
        view_camera_orbit(&a->cam, x - a->lx, y - a->ly);
    } else {
        view_camera_pan(&a->cam, x - a->lx, y - a->ly);
    }
    a->lx = x, a->ly = y;
    app_redraw(a);
}

static void app_release(app *a, double x, double y) {
    if (!a->dragging) return;
    app_motion(a, x, y);
    if (a->painting && !a->erase_mode) {
        ss_paint_end(&a->paint);
        if (a->mirror && a->ngesture > 0) { /* the same gesture in the mirror */
            ss_paint_begin(&a->paint);
            int n0 = a->paint.n;
            for (int i = 0; i < a->ngesture; i++) {
                const float *g = a->gesture + 12 * i;
                float mo[3], md[3], mr[3], mu[3];
                ss_ray_hit h;
                mirror_vec(a, g, mo, 1), mirror_vec(a, g + 3, md, 0);
                mirror_vec(a, g + 6, mr, 0), mirror_vec(a, g + 9, mu, 0);
                ss_paint_add(&a->paint, mo, md, mr, mu, &h);
            }
            ss_paint_end(&a->paint);
            if (a->paint.n != n0) a->changed = a->strokes_dirty = 1;
        }
    }
    if (a->painting && !a->changed) app_history_drop_last(a);
    a->dragging = a->painting = 0;
    app_redraw(a);
}

static void app_scroll(app *a, double dy) {
    view_camera_zoom(&a->cam, -dy);
    app_redraw(a);
}

static void *generate_worker(void *arg) {
    app *a = arg;
    a->worker_status =
        view_layers_generate(&a->worker_strokes, a->skin, a->o.texture_size, a->o.seed,
                             &a->progress, &a->worker_layers, &a->worker_err);
    __atomic_store_n(&a->worker_done, 1, __ATOMIC_RELEASE);
    return NULL;
}

static void app_update_gen_widgets(app *a) {
    if (a->gen_btn) gtk_widget_set_sensitive(a->gen_btn, !a->generating);
    if (a->progress_bar)
        gtk_progress_bar_set_fraction(GTK_PROGRESS_BAR(a->progress_bar),
                                      a->generating ? a->progress : 0);
}

/* Starts Generate from the painted strokes (or the built-in example when
 * nothing is painted). */
static void app_generate(app *a) {
    if (a->generating) return;
    if (!a->mesh.has_uvs) { /* the textures would land nowhere: refuse at once */
        a->gen_failed = SS_ERR_INPUT;
        app_message(a, 1,
                    "Generate: the mesh has no texture coordinates (UVs), so textures cannot "
                    "be put on it; open a mesh with a UV map");
        return;
    }
    ss_error err = {0};
    int dropped = 0;
    ss_status st;
    if (a->paint.n > 0) {
        st = ss_paint_to_strokes(&a->paint, &a->worker_strokes, &dropped, &err);
    } else {
        st = ss_abrasion_example_strokes(&a->worker_strokes, &err);
        if (!st) app_message(a, 0, "nothing painted: generating the built-in example wound");
    }
    if (st) {
        a->gen_failed = st;
        app_message(a, 1, "Generate: %s", err.msg);
        return;
    }
    if (dropped)
        app_message(a, 0, "Generate: %d stroke piece(s) too small for a hull left out", dropped);
    a->progress = 0;
    a->worker_done = 0;
    a->generating = 1;
    if (pthread_create(&a->worker, NULL, generate_worker, a) != 0) {
        a->generating = 0;
        ss_stroke_set_free(&a->worker_strokes);
        app_message(a, 1, "Generate: cannot start a thread");
    }
    app_update_gen_widgets(a);
}

/* Called on the UI thread: when the worker is done (or, with wait, after
 * waiting for it) takes its layers; they are uploaded at the next
 * app_sync_gl. Returns 1 when a job finished. */
static int app_generate_finish(app *a, int wait) {
    if (!a->generating) return 0;
    if (!wait && !__atomic_load_n(&a->worker_done, __ATOMIC_ACQUIRE)) return 0;
    pthread_join(a->worker, NULL);
    a->generating = 0;
    ss_stroke_set_free(&a->worker_strokes);
    if (a->worker_status) {
        a->gen_failed = a->worker_status;
        app_message(a, 1, "Generate: %s", a->worker_err.msg);
    } else {
        view_layers_free(&a->layers);
        a->layers = a->worker_layers;
        memset(&a->worker_layers, 0, sizeof a->worker_layers);
        a->layers_dirty = 1;
        app_message(a, 0, "generated: %s; slide from injury (day 0) to day %g (%s)",
                    a->layers.source, a->layers.end_day, a->layers.timing);
    }
    app_update_gen_widgets(a);
    app_set_time(a, a->day);
    return 1;
}

/* Loads a texture folder into l: a heal run is rendered first, a wound
 * block is put on the mesh at its world size, a skin set's colour becomes
 * the skin Generate draws on (*skin, replaced only on success). */
static ss_status app_load_textures(app *a, const char *dir, view_layers *l, ss_error *err) {
    int ts = a->o.texture_size;
    ss_status st = view_layers_load_dir(dir, ts < 512 ? ts : 512, a->o.quiet, l, err);
    if (!st && l->block_mm > 0 && a->can_paint) {
        /* the mesh's texture at Generate's size, smaller when the stack would
         * pass 512 MB (two RGBA8 maps a layer) */
        int size = ts;
        while (size > 256 && (double)l->nlayers * size * size * 8 > 512e6) size /= 2;
        /* centred where the start view looks: the back of the shipped hand */
        view_camera c;
        view_camera_frame(&c, &a->mesh);
        c.width = a->o.width, c.height = a->o.height;
        float o[3], d[3], r[3], u[3];
        ss_ray_hit h;
        view_camera_ray(&c, 0.5 * c.width, 0.5 * c.height, o, d, r, u);
        int hit = ss_bvh_raycast(a->paint.bvh, o, d, 0, INFINITY, &h);
        st = view_layers_place_block(l, &a->mesh, a->paint.island, hit ? h.uv : NULL, size,
                                     a->o.seed, err);
        if (st) view_layers_free(l);
    }
    if (!st && l->skin) {
        ss_image_free(a->skin);
        a->skin = l->skin;
        l->skin = NULL;
    }
    return st;
}

/* The painted wound as a UV mask PNG (white = wound) at the texture size:
 * what Generate fills, and what `skinsim abrasion --mask` reads. */
static ss_status save_mask(app *a, const char *path, ss_error *err) {
    ss_stroke_set ss = {0};
    int dropped = 0;
    ss_status st = ss_paint_to_strokes(&a->paint, &ss, &dropped, err);
    ss_image *m = st ? NULL : view_strokes_mask(&ss, a->o.texture_size, a->o.seed, err);
    ss_stroke_set_free(&ss);
    if (!m) return err->code;
    st = ss_png_write(path, m, 8, SS_ENC_LINEAR, err);
    ss_image_free(m);
    return st;
}

static void app_save_mask(app *a, const char *path) {
    ss_error err = {0};
    if (!a->can_paint)
        app_message(a, 1, "%s: the mesh has no UVs, so there is no mask to save", path);
    else if (save_mask(a, path, &err))
        app_message(a, 1, "%s: %s", path, err.msg);
    else
        app_message(a, 0, "mask (%d^2, white = wound) saved to %s", a->o.texture_size, path);
}

static void app_save_strokes(app *a, const char *path) {
    ss_error err = {0};
    int dropped = 0;
    if (ss_paint_save_csv(&a->paint, path, &dropped, &err))
        app_message(a, 1, "%s: %s", path, err.msg);
    else
        app_message(a, 0, "strokes saved to %s%s", path, dropped ? " (tiny pieces left out)" : "");
}

static void app_load_strokes(app *a, const char *path) {
    ss_error err = {0};
    int outside = 0;
    if (!a->can_paint) {
        app_message(a, 1, "%s: the mesh has no UVs; strokes cannot be shown", path);
        return;
    }
    app_history_push(a);
    if (ss_paint_load_csv(&a->paint, path, &outside, &err)) {
        app_history_drop_last(a);
        app_message(a, 1, "%s", err.msg);
        return;
    }
    a->strokes_dirty = 1;
    if (outside)
        app_message(a, 1,
                    "%s: %d of %d points lie outside this mesh's UV islands (a stroke file for "
                    "another mesh?)",
                    path, outside, a->paint.n);
    else
        app_message(a, 0, "%s: %d points loaded", path, a->paint.n);
    app_redraw(a);
}

static void app_step_key(app *a, int dir) {
    const view_layers *l = &a->layers;
    double t = a->day;
    if (dir > 0) {
        for (int i = 0; i < l->nstops; i++)
            if (l->stop_day[i] > t + 1e-9) {
                app_set_time(a, l->stop_day[i]);
                return;
            }
        app_set_time(a, l->end_day);
    } else {
        for (int i = l->nstops - 1; i >= 0; i--)
            if (l->stop_day[i] < t - 1e-9) {
                app_set_time(a, l->stop_day[i]);
                return;
            }
        app_set_time(a, 0);
    }
}

static void app_set_paint_mode(app *a, int on) {
    if (on && !a->can_paint) {
        app_message(a, 1, "the mesh has no UVs: painting is off");
        on = 0;
    }
    a->paint_mode = on;
    if (a->paint_btn) gtk_toggle_button_set_active(GTK_TOGGLE_BUTTON(a->paint_btn), on);
    app_message(a, 0, on ? "paint mode: drag on the mesh to paint (P to leave)" : "view mode");
}

static void app_set_playing(app *a, int on) {
    a->playing = on;
    if (a->play_btn) gtk_button_set_label(GTK_BUTTON(a->play_btn), on ? "Pause" : "Play");
}

static void app_key(app *a, const char *k) {
    if (!strcasecmp(k, "p"))
        app_set_paint_mode(a, !a->paint_mode);
    else if (!strcasecmp(k, "z") || !strcasecmp(k, "ctrl+z")) {
        if (!app_undo_redo(a, 0)) app_message(a, 0, "nothing to undo");
    } else if (!strcasecmp(k, "y") || !strcasecmp(k, "ctrl+y") || !strcasecmp(k, "ctrl+shift+z")) {
        if (!app_undo_redo(a, 1)) app_message(a, 0, "nothing to redo");
    } else if (!strcasecmp(k, "c")) {
        if (a->paint.n > 0) {
            app_history_push(a);
            ss_paint_clear(&a->paint);
            a->strokes_dirty = 1;
        }
    } else if (!strcasecmp(k, "e")) {
        a->erase_mode = !a->erase_mode;
        if (a->erase_btn)
            gtk_toggle_button_set_active(GTK_TOGGLE_BUTTON(a->erase_btn), a->erase_mode);
        app_message(a, 0,
                    a->erase_mode ? "eraser: dragging in paint mode removes paint (E: brush)"
                                  : "brush: dragging in paint mode paints");
    } else if (!strcasecmp(k, "m")) {
        a->mirror = !a->mirror;
        if (a->mirror_btn)
            gtk_toggle_button_set_active(GTK_TOGGLE_BUTTON(a->mirror_btn), a->mirror);
        app_message(a, 0,
                    a->mirror ? "mirror: strokes are also painted mirrored in x (M: off)"
                              : "mirror off");
    } else if (!strcasecmp(k, "x"))
        app_save_mask(a, a->o.save_mask ? a->o.save_mask : "mask.png");
    else if (!strcasecmp(k, "g"))
        app_generate(a);
    else if (!strcasecmp(k, "space"))
        app_set_playing(a, !a->playing);
    else if (!strcasecmp(k, "right"))
        app_step_key(a, 1);
    else if (!strcasecmp(k, "left"))
        app_step_key(a, -1);
    else if (!strcasecmp(k, "s"))
        app_save_strokes(a, a->o.save_strokes ? a->o.save_strokes : "strokes.csv");
    else if (!strcasecmp(k, "r"))
        view_camera_frame(&a->cam, &a->mesh);
    else if (!strcasecmp(k, "h"))
        a->hide_strokes = !a->hide_strokes;
    else if (!strcasecmp(k, "F1") || !strcmp(k, "question") || !strcmp(k, "?"))
        a->help = !a->help;
    else if (!strcasecmp(k, "Escape")) {
        if (a->help)
            a->help = 0; /* Escape first closes the help, then the window */
        else
            a->quit = 1;
    } else if (!strcasecmp(k, "ctrl+q"))
        a->quit = 1;
    else
        app_message(a, 0, "key '%s' does nothing (F1: help)", k);
    if (a->help_box) gtk_widget_set_visible(a->help_box, a->help);
    app_redraw(a);
}

/* One script event; returns 0 when it must wait (Generate running). */
static int app_script_step(app *a, const script_ev *e) {
    if (e->kind == EV_WAIT && a->generating) return 0;
    switch (e->kind) {
    case EV_MOVE:
        app_motion(a, e->x, e->y);
        break;
    case EV_PRESS:
        app_press(a, e->x, e->y, e->button, e->shift);
        break;
    case EV_RELEASE:
        app_release(a, e->x, e->y);
        break;
    case EV_DRAG:
        app_press(a, e->x, e->y, e->button, e->shift);
        for (int i = 1; i <= e->steps; i++)
            app_motion(a, e->x + (e->x2 - e->x) * i / e->steps,
                       e->y + (e->y2 - e->y) * i / e->steps);
        app_release(a, e->x2, e->y2);
        break;
    case EV_SCROLL:
        app_scroll(a, e->value);
        break;
    case EV_KEY:
        app_key(a, e->key);
        break;
    case EV_SLIDER:
        app_set_time(a, e->value);
        break;
    case EV_WAIT:
        break;
    }
    return 1;
}

/* The brush ring under the cursor in paint mode: a circle of the brush
 * radius in the plane of the triangle the cursor's ray hits. */
static void app_update_ring(app *a) {
    float pts[3 * RING_POINTS];
    int n = 0;
    ss_ray_hit h;
    float o[3], d[3], r[3], u[3];
    if (a->paint_mode && a->can_paint && a->hover) {
        view_camera_ray(&a->cam, a->hx, a->hy, o, d, r, u);
        if (ss_bvh_raycast(a->paint.bvh, o, d, 0, INFINITY, &h)) {
            const uint32_t *ix = a->mesh.indices + 3 * h.triangle;
            const float *p0 = a->mesh.positions + 3 * ix[0], *p1 = a->mesh.positions + 3 * ix[1],
                        *p2 = a->mesh.positions + 3 * ix[2];
            double e1[3], e2[3], nn[3], t1[3], t2[3];
            for (int k = 0; k < 3; k++) e1[k] = p1[k] - p0[k], e2[k] = p2[k] - p0[k];
            nn[0] = e1[1] * e2[2] - e1[2] * e2[1];
            nn[1] = e1[2] * e2[0] - e1[0] * e2[2];
            nn[2] = e1[0] * e2[1] - e1[1] * e2[0];
            double ln = sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
            double le = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
            if (ln > 0 && le > 0) {
                for (int k = 0; k < 3; k++) nn[k] /= ln, t1[k] = e1[k] / le;
                t2[0] = nn[1] * t1[2] - nn[2] * t1[1];
                t2[1] = nn[2] * t1[0] - nn[0] * t1[2];
                t2[2] = nn[0] * t1[1] - nn[1] * t1[0];
                double R = a->paint.brush_radius;
                for (int i = 0; i < RING_POINTS; i++) {
                    double ang = 6.283185307179586 * i / RING_POINTS, ca = cos(ang), sa = sin(ang);
                    for (int k = 0; k < 3; k++)
                        pts[3 * n + k] = (float)(o[k] + h.t * d[k] + R * (ca * t1[k] + sa * t2[k]));
                    n++;
                }
            }
        }
    }
    view_renderer_set_ring(a->rend, pts, n, a->erase_mode);
}

/* Uploads what changed; needs the GL context current. */
static void app_sync_gl(app *a) {
    if (!a->rend) return;
    app_update_ring(a);
    if (a->layers_dirty) {
        ss_error err = {0};
        double t0 = ss_now();
        if (view_renderer_set_layers(a->rend, &a->layers, &err))
            app_message(a, 1, "%s", err.msg);
        else if (!a->o.quiet)
            fprintf(stderr, "skinsim view: %d layers of %d^2 uploaded in %.0f ms\n",
                    a->layers.nlayers, a->layers.size, (ss_now() - t0) * 1e3);
        a->layers_dirty = 0;
    }
    if (a->strokes_dirty) {
        view_renderer_set_strokes(a->rend, a->paint.s, a->paint.n);
        a->strokes_dirty = 0;
    }
}

/* ---- inputs ---------------------------------------------------------------------- */

static ss_status app_init(app *a, const opts *o, ss_error *err) {
    memset(a, 0, sizeof *a);
    a->o = *o;
    char def[4096];
    snprintf(def, sizeof def, "%s/meshes/generic-hand-left.glb", ss_data_dir());
    const char *mesh = o->mesh ? o->mesh : def;
    ss_status st = ss_mesh_load(mesh, &a->mesh, err);
    if (st) return st;
    a->can_paint = a->mesh.has_uvs;
    a->hide_strokes = o->hide_strokes;
    a->mirror = o->mirror;
    if (a->can_paint) st = ss_paint_create(&a->mesh, o->brush_mm * 1e-3, &a->paint, err);
    if (st) return st;
    if (!a->mesh.has_uvs)
        app_message(a, 1, "%s has no texture coordinates (UVs): textures and painting are off",
                    mesh);
    view_camera_frame(&a->cam, &a->mesh);
    a->cam.width = o->width;
    a->cam.height = o->height;
    if (o->strokes) {
        int outside = 0;
        if (!a->can_paint)
            return ss_error_set(err, SS_ERR_INPUT, "%s: the mesh has no UVs to put strokes on",
                                o->strokes);
        st = ss_paint_load_csv(&a->paint, o->strokes, &outside, err);
        if (st) return st;
        if (outside)
            return ss_error_set(err, SS_ERR_INPUT,
                                "%s: %d of %d points lie outside the UV islands of %s (a stroke "
                                "file for another mesh?)",
                                o->strokes, outside, a->paint.n, mesh);
        a->strokes_dirty = 1;
    }
    if (o->script) {
        st = parse_script(o->script, &a->ev, &a->nev, err);
        if (st) return st;
    }
    if (o->load) {
        st = app_load_textures(a, o->load, &a->layers, err);
    } else {
        st = view_layers_plain_skin(o->texture_size > 1024 ? 1024 : o->texture_size, o->seed,
                                    &a->layers, err);
    }
    if (st) return st;
    a->layers_dirty = 1;
    a->day = o->day;
    a->picks = cJSON_CreateArray();
    return SS_OK;
}

static void app_free(app *a) {
    if (a->generating) {
        pthread_join(a->worker, NULL);
        ss_stroke_set_free(&a->worker_strokes);
        view_layers_free(&a->worker_layers);
    }
    view_layers_free(&a->layers);
    ss_image_free(a->skin);
    for (int i = 0; i < a->nundo; i++) snap_free(&a->undo[i]);
    for (int i = 0; i < a->nredo; i++) snap_free(&a->redo[i]);
    free(a->gesture);
    ss_paint_free(&a->paint);
    ss_mesh_free(&a->mesh);
    free(a->ev);
    cJSON_Delete(a->picks);
}

/* ---- batch work (any current GL context) ----------------------------------------- */

static int cmp_double(const void *x, const void *y) {
    double a = *(const double *)x, b = *(const double *)y;
    return a < b ? -1 : a > b;
}

static ss_status write_screenshot(const char *path, const unsigned char *rgb, int w, int h,
                                  ss_error *err) {
    ss_image *img = ss_image_create_uninit(w, h, 3, err);
    if (!img) return err->code;
    /* The bytes are sRGB: decode to linear so the PNG is written (and tagged)
     * as sRGB; encode(decode(b)) gives b back. */
    float lut[256];
    for (int i = 0; i < 256; i++) lut[i] = ss_srgb_decode(i / 255.0f);
    for (size_t i = 0; i < (size_t)w * (size_t)h * 3; i++) img->data[i] = lut[rgb[i]];
    ss_status st = ss_png_write(path, img, 8, SS_ENC_SRGB, err);
    ss_image_free(img);
    return st;
}

/* Runs the script, Generate, the bench and the screenshot; the GL context is
 * current. Returns the exit code. */
static int app_batch(app *a) {
    ss_error err = {0};
    cJSON *sum = cJSON_CreateObject();
    int rc = 0;
    a->rend = view_renderer_create(&a->mesh, &err);
    if (!a->rend) {
        cJSON_Delete(sum);
        return cli_fail(CMD, &err);
    }
    cJSON_AddStringToObject(sum, "renderer", view_renderer_gl_info(a->rend));
    if (!a->o.quiet) fprintf(stderr, "skinsim view: OpenGL %s\n", view_renderer_gl_info(a->rend));
    if (a->o.generate) app_generate(a);
    /* Batch: Generate is waited for where a script says wait, and at the end. */
    for (int i = 0; i < a->nev; i++) {
        if (a->ev[i].kind == EV_WAIT) app_generate_finish(a, 1);
        app_script_step(a, &a->ev[i]);
        app_generate_finish(a, 0);
    }
    app_generate_finish(a, 1);
    if (a->gen_failed) rc = ss_status_exit_code(a->gen_failed);
    app_sync_gl(a);
    cJSON_AddStringToObject(sum, "textures", a->layers.source);
    cJSON_AddNumberToObject(sum, "layers", a->layers.nlayers);
    cJSON_AddNumberToObject(sum, "texture_size", a->layers.size);
    if (a->o.json) { /* a hex string: JSON numbers lose 64-bit integers */
        char hash[24];
        snprintf(hash, sizeof hash, "%016llx", (unsigned long long)view_layers_hash(&a->layers));
        cJSON_AddStringToObject(sum, "layers_hash", hash);
    }
    cJSON_AddNumberToObject(sum, "end_day", a->layers.end_day);
    cJSON_AddNumberToObject(sum, "day", a->day);
    cJSON_AddBoolToObject(sum, "generate_skin_loaded", a->skin != NULL);
    if (a->layers.block_mm > 0 && a->layers.block_side_uv > 0) {
        cJSON *b = cJSON_AddObjectToObject(sum, "block");
        cJSON_AddNumberToObject(b, "side_mm", a->layers.block_mm);
        cJSON_AddNumberToObject(b, "mm_per_uv", a->layers.mm_per_uv);
        cJSON_AddNumberToObject(b, "side_uv", a->layers.block_side_uv);
        cJSON_AddNumberToObject(b, "u", a->layers.block_uv[0]);
        cJSON_AddNumberToObject(b, "v", a->layers.block_uv[1]);
        /* where its centre is in the frame (pixels, origin top-left) */
        float uv[2] = {(float)a->layers.block_uv[0], (float)a->layers.block_uv[1]}, pos[3], mvp[16];
        if (ss_mesh_locate_uv(&a->mesh, uv, pos) >= 0) {
            view_camera_matrix(&a->cam, mvp);
            float cl[4];
            for (int r = 0; r < 4; r++)
                cl[r] = mvp[r] * pos[0] + mvp[4 + r] * pos[1] + mvp[8 + r] * pos[2] + mvp[12 + r];
            if (cl[3] > 0) {
                cJSON_AddNumberToObject(b, "x", (cl[0] / cl[3] * 0.5 + 0.5) * a->cam.width);
                cJSON_AddNumberToObject(b, "y", (0.5 - cl[1] / cl[3] * 0.5) * a->cam.height);
            }
        }
    }
    if (!rc && a->o.bench_frames > 0) {
        int n = a->o.bench_frames;
        double *ms = malloc(sizeof *ms * (size_t)n);
        double t0 = ss_now();
        struct timespec c0, c1;
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
        ss_status st = ms ? view_renderer_bench(a->rend, &a->cam, &a->layers, n,
                                                (float)a->o.displace, ms, &err)
                          : ss_error_set(&err, SS_ERR_NOMEM, "out of memory");
        if (st) {
            rc = cli_fail(CMD, &err);
        } else {
            double total = (ss_now() - t0) * 1e3;
            clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
            double cpu =
                ((double)(c1.tv_sec - c0.tv_sec) * 1e3 + (c1.tv_nsec - c0.tv_nsec) * 1e-6) / n;
            qsort(ms, (size_t)n, sizeof *ms, cmp_double);
            double med = n % 2 ? ms[n / 2] : 0.5 * (ms[n / 2 - 1] + ms[n / 2]);
            int i95 = (int)ceil(0.95 * n) - 1;
            double p95 = ms[i95 < 0 ? 0 : i95];
            printf("bench: %d frames at %dx%d, textures %d^2 x %d layers, %d..%g days: median %.2f "
                   "ms/frame, 95th percentile %.2f ms, min %.2f, max %.2f; CPU time %.2f ms/frame "
                   "over all threads (%s)\n",
                   n, a->cam.width, a->cam.height, a->layers.size, a->layers.nlayers, 0,
                   a->layers.end_day, med, p95, ms[0], ms[n - 1], cpu,
                   view_renderer_gl_info(a->rend));
            cJSON *b = cJSON_AddObjectToObject(sum, "bench");
            cJSON_AddNumberToObject(b, "frames", n);
            cJSON_AddNumberToObject(b, "width", a->cam.width);
            cJSON_AddNumberToObject(b, "height", a->cam.height);
            cJSON_AddNumberToObject(b, "median_ms", med);
            cJSON_AddNumberToObject(b, "p95_ms", p95);
            cJSON_AddNumberToObject(b, "total_ms", total);
            cJSON_AddNumberToObject(b, "cpu_ms_per_frame", cpu);
        }
        free(ms);
    }
    if (!rc && a->o.screenshot) {
        unsigned char *rgb = malloc((size_t)a->cam.width * (size_t)a->cam.height * 3);
        ss_status st =
            rgb ? view_renderer_offscreen(a->rend, &a->cam, &a->layers, a->day,
                                          (float)a->o.displace, !a->hide_strokes, rgb, &err)
                : ss_error_set(&err, SS_ERR_NOMEM, "out of memory");
        if (!st) st = write_screenshot(a->shot_path, rgb, a->cam.width, a->cam.height, &err);
        free(rgb);
        if (st)
            rc = cli_fail(CMD, &err);
        else
            cJSON_AddStringToObject(sum, "screenshot", a->o.screenshot);
    }
    if (!rc && a->o.save_strokes) {
        int dropped = 0;
        if (ss_paint_save_csv(&a->paint, a->csv_path, &dropped, &err))
            rc = cli_fail(CMD, &err);
        else
            cJSON_AddStringToObject(sum, "strokes", a->o.save_strokes);
    }
    if (!rc && a->o.save_mask) {
        if (save_mask(a, a->mask_path, &err))
            rc = cli_fail(CMD, &err);
        else
            cJSON_AddStringToObject(sum, "mask", a->o.save_mask);
    }
    cJSON_AddNumberToObject(sum, "stroke_points", a->paint.n);
    cJSON_AddItemReferenceToObject(sum, "picks", a->picks);
    if (a->o.json && !rc) {
        char *s = cJSON_Print(sum);
        if (s) printf("%s\n", s);
        free(s);
    }
    cJSON_Delete(sum);
    view_renderer_free(a->rend);
    a->rend = NULL;
    return rc;
}

/* ---- EGL surfaceless ------------------------------------------------------------- */

static int run_egl(app *a) {
    ss_error err = {0};
    EGLDisplay dpy = EGL_NO_DISPLAY;
    if (epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_MESA_platform_surfaceless") &&
        epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_EXT_platform_base"))
        dpy = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
    EGLint maj, min;
    if (dpy == EGL_NO_DISPLAY || !eglInitialize(dpy, &maj, &min)) {
        ss_error_set(&err, SS_ERR_RUNTIME,
                     "no display and no EGL surfaceless platform (install Mesa's libegl-mesa0, or "
                     "run under Xvfb)");
        return cli_fail(CMD, &err);
    }
    int rc = 1;
    EGLContext ctx = EGL_NO_CONTEXT;
    if (eglBindAPI(EGL_OPENGL_API)) {
        const EGLint attr[] = {EGL_CONTEXT_MAJOR_VERSION,
                               3,
                               EGL_CONTEXT_MINOR_VERSION,
                               3,
                               EGL_CONTEXT_OPENGL_PROFILE_MASK,
                               EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                               EGL_NONE};
        ctx = eglCreateContext(dpy, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attr);
    }
    if (ctx == EGL_NO_CONTEXT || !eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
        ss_error_set(&err, SS_ERR_RUNTIME, "EGL: cannot make an OpenGL 3.3 core context (0x%x)",
                     (unsigned)eglGetError());
        rc = cli_fail(CMD, &err);
    } else {
        rc = app_batch(a);
        eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
    if (ctx != EGL_NO_CONTEXT) eglDestroyContext(dpy, ctx);
    eglTerminate(dpy);
    return rc;
}

/* ---- GTK --------------------------------------------------------------------------- */

typedef struct gtk_run {
    app *a;
    int batch, rc, done, idle_ticks, drawn;
} gtk_run;

/* --window-shot: the window as drawn (widgets and the GL frame) to a PNG. */
static void save_window(gtk_run *g) {
    app *a = g->a;
    int w = gtk_widget_get_width(a->window), h = gtk_widget_get_height(a->window);
    GdkPaintable *p = gtk_widget_paintable_new(a->window);
    GtkSnapshot *s = gtk_snapshot_new();
    gdk_paintable_snapshot(p, GDK_SNAPSHOT(s), w, h);
    GskRenderNode *node = gtk_snapshot_free_to_node(s);
    GskRenderer *r = gtk_native_get_renderer(GTK_NATIVE(a->window));
    graphene_rect_t rect = GRAPHENE_RECT_INIT(0, 0, (float)w, (float)h);
    GdkTexture *tex = node && r ? gsk_renderer_render_texture(r, node, &rect) : NULL;
    if (!tex || !gdk_texture_save_to_png(tex, a->o.window_shot)) {
        app_message(a, 1, "%s: cannot save the window", a->o.window_shot);
        g->rc = 1;
    } else if (!a->o.quiet) {
        fprintf(stderr, "skinsim view: window saved to %s\n", a->o.window_shot);
    }
    if (tex) g_object_unref(tex);
    if (node) gsk_render_node_unref(node);
    g_object_unref(p);
}

static gboolean on_render(GtkGLArea *area, GdkGLContext *ctx, gpointer data) {
    (void)ctx;
    gtk_run *g = data;
    app *a = g->a;
    if (!a->rend) return TRUE;
    app_sync_gl(a);
    int scale = gtk_widget_get_scale_factor(GTK_WIDGET(area));
    view_camera c = a->cam;
    c.width = gtk_widget_get_width(GTK_WIDGET(area)) * scale;
    c.height = gtk_widget_get_height(GTK_WIDGET(area)) * scale;
    if (c.width < 1 || c.height < 1) return TRUE;
    view_renderer_draw(a->rend, &c, &a->layers, a->day, (float)a->o.displace, !a->hide_strokes);
    if (!g->drawn) {
        g->drawn = 1;
        if (!a->o.quiet)
            fprintf(stderr, "skinsim view: first frame %.2f s after start\n",
                    ss_now() - a->o.t_start);
    }
    return TRUE;
}

static void on_resize(GtkGLArea *area, int w, int h, gpointer data) {
    gtk_run *g = data;
    int scale = gtk_widget_get_scale_factor(GTK_WIDGET(area));
    if (!g->batch) {
        g->a->cam.width = w / (scale > 0 ? scale : 1);
        g->a->cam.height = h / (scale > 0 ? scale : 1);
    }
}

static void on_realize(GtkGLArea *area, gpointer data) {
    gtk_run *g = data;
    app *a = g->a;
    gtk_gl_area_make_current(area);
    GError *ge = gtk_gl_area_get_error(area);
    if (ge) {
        app_message(a, 1, "OpenGL: %s", ge->message);
        g->rc = 1;
        g->done = 1;
        return;
    }
    if (g->batch) {
        g->rc = app_batch(a);
        g->done = 1;
        return;
    }
    ss_error err = {0};
    a->rend = view_renderer_create(&a->mesh, &err);
    if (!a->rend) {
        app_message(a, 1, "%s", err.msg);
        return;
    }
    a->layers_dirty = a->strokes_dirty = 1;
    if (!a->mesh.has_uvs)
        app_message(a, 1,
                    "this mesh has no texture coordinates (UVs): painting and Generate are off; "
                    "open a mesh with a UV map (F1: help)");
    else
        app_message(a, 0,
                    "%s | %s. P: paint, G: generate, drag: rotate, shift-drag: pan, wheel: zoom, "
                    "F1: help",
                    a->layers.source, view_renderer_gl_info(a->rend));
}

static void on_unrealize(GtkGLArea *area, gpointer data) {
    gtk_run *g = data;
    gtk_gl_area_make_current(area);
    view_renderer_free(g->a->rend);
    g->a->rend = NULL;
}

static GdkModifierType event_mods(GtkGesture *gest) {
    return gtk_event_controller_get_current_event_state(GTK_EVENT_CONTROLLER(gest));
}

static void on_drag_begin(GtkGestureDrag *gest, double x, double y, gpointer data) {
    gtk_run *g = data;
    int button = (int)gtk_gesture_single_get_current_button(GTK_GESTURE_SINGLE(gest));
    int shift = (event_mods(GTK_GESTURE(gest)) & GDK_SHIFT_MASK) != 0;
    app_press(g->a, x, y, button == 1 ? 1 : button == 2 ? 2 : 3, shift);
    gtk_widget_grab_focus(g->a->area);
}

static void on_drag_update(GtkGestureDrag *gest, double dx, double dy, gpointer data) {
    gtk_run *g = data;
    double x0, y0;
    gtk_gesture_drag_get_start_point(gest, &x0, &y0);
    app_motion(g->a, x0 + dx, y0 + dy);
    if (g->a->strokes_dirty) app_redraw(g->a);
}

static void on_drag_end(GtkGestureDrag *gest, double dx, double dy, gpointer data) {
    gtk_run *g = data;
    double x0, y0;
    gtk_gesture_drag_get_start_point(gest, &x0, &y0);
    app_release(g->a, x0 + dx, y0 + dy);
}

static gboolean on_scroll(GtkEventControllerScroll *c, double dx, double dy, gpointer data) {
    (void)c, (void)dx;
    app_scroll(((gtk_run *)data)->a, dy);
    return TRUE;
}

static gboolean on_key(GtkEventControllerKey *c, guint keyval, guint code, GdkModifierType mods,
                       gpointer data) {
    (void)c, (void)code;
    app *a = ((gtk_run *)data)->a;
    const char *name = gdk_keyval_name(gdk_keyval_to_lower(keyval));
    if (!name) return FALSE;
    if ((mods & GDK_CONTROL_MASK) && !strcmp(name, "q")) {
        app_key(a, "ctrl+q");
        return TRUE;
    }
    if (!strcmp(name, "Escape") || !strcmp(name, "F1") || !strcmp(name, "question")) {
        app_key(a, name);
        return TRUE;
    }
    if ((mods & GDK_CONTROL_MASK) && !strcmp(name, "z")) {
        app_key(a, (mods & GDK_SHIFT_MASK) ? "ctrl+shift+z" : "ctrl+z");
        return TRUE;
    }
    if ((mods & GDK_CONTROL_MASK) && !strcmp(name, "y")) {
        app_key(a, "ctrl+y");
        return TRUE;
    }
    if (mods & GDK_CONTROL_MASK) return FALSE;
    if (!strcmp(name, "Left") || !strcmp(name, "Right") || !strcmp(name, "space") ||
        strlen(name) == 1) {
        app_key(a, name);
        return TRUE;
    }
    return FALSE;
}

static const char HELP_TEXT[] =
    "skinsim view\n\n"
    "drag            rotate          shift-drag / middle   pan\n"
    "wheel           zoom            R                     reset the view\n"
    "P               paint mode (drag on the mesh to paint a wound)\n"
    "E               eraser          M                     mirror symmetry (x)\n"
    "Z  Ctrl+Z       undo            Y  Ctrl+Y  Ctrl+Shift+Z  redo\n"
    "C               clear strokes   X                     save the mask (PNG)\n"
    "H               hide strokes    S                     save strokes\n"
    "G               Generate (the abrasion timeline from the strokes)\n"
    "Space           play / pause    Left / Right          previous / next key\n"
    "F1  ?           this help       Escape  Ctrl+Q        close the help, quit";

static void on_scale(GtkRange *r, gpointer data) {
    app *a = ((gtk_run *)data)->a;
    if (a->updating_scale) return;
    app_set_time(a, gtk_range_get_value(r));
}

static void on_paint_toggled(GtkToggleButton *b, gpointer data) {
    app *a = ((gtk_run *)data)->a;
    int on = gtk_toggle_button_get_active(b);
    if (on != a->paint_mode) app_set_paint_mode(a, on);
}

static void on_tool_toggled(GtkToggleButton *b, gpointer data) {
    app *a = ((gtk_run *)data)->a;
    const char *k = g_object_get_data(G_OBJECT(b), "key");
    int on = gtk_toggle_button_get_active(b);
    if (on != (k[0] == 'e' ? a->erase_mode : a->mirror)) app_key(a, k);
}

static void on_hover(GtkEventControllerMotion *c, double x, double y, gpointer data) {
    (void)c;
    app *a = ((gtk_run *)data)->a;
    if (!a->dragging) app_motion(a, x, y);
}

static void on_leave(GtkEventControllerMotion *c, gpointer data) {
    (void)c;
    app *a = ((gtk_run *)data)->a;
    a->hover = 0;
    app_redraw(a);
}

static void on_brush(GtkSpinButton *s, gpointer data) {
    app *a = ((gtk_run *)data)->a;
    a->paint.brush_radius = gtk_spin_button_get_value(s) * 1e-3;
    app_redraw(a); /* the ring shows the new size */
}

static void on_button(GtkButton *b, gpointer data) {
    app *a = ((gtk_run *)data)->a;
    const char *k = g_object_get_data(G_OBJECT(b), "key");
    app_key(a, k);
}

static void on_file_response(GtkNativeDialog *d, int response, gpointer data) {
    app *a = ((gtk_run *)data)->a;
    int save = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(d), "save"));
    int mask = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(d), "mask"));
    int folder = GPOINTER_TO_INT(g_object_get_data(G_OBJECT(d), "folder"));
    if (response == GTK_RESPONSE_ACCEPT) {
        GFile *f = gtk_file_chooser_get_file(GTK_FILE_CHOOSER(d));
        char *path = f ? g_file_get_path(f) : NULL;
        if (path && mask)
            app_save_mask(a, path);
        else if (path && save)
            app_save_strokes(a, path);
        else if (path && folder) {
            view_layers l;
            ss_error err = {0};
            if (app_load_textures(a, path, &l, &err))
                app_message(a, 1, "%s", err.msg);
            else {
                view_layers_free(&a->layers);
                a->layers = l;
                a->layers_dirty = 1;
                app_message(a, 0, "loaded %s", l.source);
                app_set_time(a, 0);
            }
        } else if (path)
            app_load_strokes(a, path);
        g_free(path);
        if (f) g_object_unref(f);
    }
    g_object_unref(d);
    app_redraw(a);
}

static void on_file_button(GtkButton *b, gpointer data) {
    gtk_run *g = data;
    const char *what = g_object_get_data(G_OBJECT(b), "file");
    int mask = !strcmp(what, "mask");
    int save = !strcmp(what, "save") || mask, folder = !strcmp(what, "folder");
    GtkFileChooserNative *d =
        gtk_file_chooser_native_new(mask     ? "Save the wound mask"
                                    : save   ? "Save strokes"
                                    : folder ? "Open a texture folder"
                                             : "Load strokes",
                                    GTK_WINDOW(g->a->window),
                                    save     ? GTK_FILE_CHOOSER_ACTION_SAVE
                                    : folder ? GTK_FILE_CHOOSER_ACTION_SELECT_FOLDER
                                             : GTK_FILE_CHOOSER_ACTION_OPEN,
                                    save ? "Save" : "Open", "Cancel");
    if (save)
        gtk_file_chooser_set_current_name(GTK_FILE_CHOOSER(d), mask ? "mask.png" : "strokes.csv");
    g_object_set_data(G_OBJECT(d), "save", GINT_TO_POINTER(save));
    g_object_set_data(G_OBJECT(d), "mask", GINT_TO_POINTER(mask));
    g_object_set_data(G_OBJECT(d), "folder", GINT_TO_POINTER(folder));
    g_signal_connect(d, "response", G_CALLBACK(on_file_response), g);
    gtk_native_dialog_show(GTK_NATIVE_DIALOG(d));
}

static gboolean on_close(GtkWindow *w, gpointer data) {
    (void)w;
    ((gtk_run *)data)->done = 1;
    return FALSE;
}

/* 30 Hz: Generate progress, playback, script replay. */
static gboolean on_tick(gpointer data) {
    gtk_run *g = data;
    app *a = g->a;
    if (a->quit) { /* Escape / Ctrl+Q (also from a script) */
        g->done = 1;
        return G_SOURCE_CONTINUE;
    }
    /* GTK gives a new window's focus to its first focusable widget (the
     * brush field) when it maps; once the 3D view is realised, take it */
    if (!a->focused && a->rend && a->area) {
        gtk_widget_grab_focus(a->area);
        a->focused = 1;
    }
    if (a->generating) {
        app_update_gen_widgets(a);
        if (app_generate_finish(a, 0)) app_redraw(a);
    }
    if (a->playing) {
        double end = a->layers.end_day;
        /* log-time playback: the early phases last minutes, maturation weeks */
        double t = a->day <= 0 ? 1e-3 : a->day * 1.04;
        if (t >= end) {
            t = end;
            app_set_playing(a, 0);
        }
        app_set_time(a, t);
    }
    if (a->next_ev < a->nev && a->rend && app_script_step(a, &a->ev[a->next_ev])) a->next_ev++;
    /* --window-shot: once the script and Generate are done and a few frames
     * have been drawn, save the window and close. */
    if (a->o.window_shot && a->rend && a->next_ev >= a->nev && !a->generating &&
        ++g->idle_ticks == 10) {
        save_window(g);
        g->done = 1;
    }
    return G_SOURCE_CONTINUE; /* removed by run_gtk */
}

static GtkWidget *button(const char *label, const char *key, const char *tip, gtk_run *g) {
    GtkWidget *b = gtk_button_new_with_label(label);
    g_object_set_data(G_OBJECT(b), "key", (gpointer)key);
    gtk_widget_set_tooltip_text(b, tip);
    g_signal_connect(b, "clicked", G_CALLBACK(on_button), g);
    gtk_widget_set_focusable(b, FALSE);
    return b;
}

static GtkWidget *file_button(const char *label, const char *what, gtk_run *g) {
    GtkWidget *b = gtk_button_new_with_label(label);
    g_object_set_data(G_OBJECT(b), "file", (gpointer)what);
    g_signal_connect(b, "clicked", G_CALLBACK(on_file_button), g);
    gtk_widget_set_focusable(b, FALSE);
    return b;
}

static int run_gtk(app *a, int batch) {
    gtk_run g = {a, batch, 0, 0, 0, 0};
    GtkWidget *win = gtk_window_new();
    a->window = win;
    gtk_window_set_title(GTK_WINDOW(win), "skinsim view");
    gtk_window_set_default_size(GTK_WINDOW(win), batch ? 320 : a->o.width,
                                batch ? 240 : a->o.height + 90);
    GtkWidget *vbox = gtk_box_new(GTK_ORIENTATION_VERTICAL, 4);
    gtk_window_set_child(GTK_WINDOW(win), vbox);
    GtkWidget *tools = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    gtk_box_append(GTK_BOX(vbox), tools);
    a->paint_btn = gtk_toggle_button_new_with_label("Paint");
    gtk_widget_set_focusable(a->paint_btn, FALSE);
    gtk_widget_set_tooltip_text(a->paint_btn, "paint mode (P): drag on the mesh to paint a wound");
    g_signal_connect(a->paint_btn, "toggled", G_CALLBACK(on_paint_toggled), &g);
    gtk_box_append(GTK_BOX(tools), a->paint_btn);
    gtk_box_append(GTK_BOX(tools), gtk_label_new("brush mm"));
    GtkWidget *spin = gtk_spin_button_new_with_range(0.5, 50, 0.5);
    gtk_spin_button_set_value(GTK_SPIN_BUTTON(spin), a->o.brush_mm);
    g_signal_connect(spin, "value-changed", G_CALLBACK(on_brush), &g);
    gtk_box_append(GTK_BOX(tools), spin);
    a->erase_btn = gtk_toggle_button_new_with_label("Eraser");
    a->mirror_btn = gtk_toggle_button_new_with_label("Mirror");
    GtkWidget *toggles[2] = {a->erase_btn, a->mirror_btn};
    const char *tkeys[2] = {"e", "m"};
    const char *ttips[2] = {"eraser (E): dragging in paint mode removes paint",
                            "mirror symmetry (M): strokes are also painted mirrored in x"};
    for (int i = 0; i < 2; i++) {
        gtk_widget_set_focusable(toggles[i], FALSE);
        gtk_widget_set_tooltip_text(toggles[i], ttips[i]);
        g_object_set_data(G_OBJECT(toggles[i]), "key", (gpointer)tkeys[i]);
        g_signal_connect(toggles[i], "toggled", G_CALLBACK(on_tool_toggled), &g);
        gtk_box_append(GTK_BOX(tools), toggles[i]);
    }
    gtk_toggle_button_set_active(GTK_TOGGLE_BUTTON(a->mirror_btn), a->mirror);
    gtk_box_append(GTK_BOX(tools), button("Undo", "z", "undo (Z, Ctrl+Z)", &g));
    gtk_box_append(GTK_BOX(tools), button("Redo", "y", "redo (Y, Ctrl+Y, Ctrl+Shift+Z)", &g));
    gtk_box_append(GTK_BOX(tools), button("Clear", "c", "remove all strokes (C)", &g));
    gtk_box_append(GTK_BOX(tools), file_button("Load strokes", "load", &g));
    gtk_box_append(GTK_BOX(tools), file_button("Save strokes", "save", &g));
    gtk_box_append(GTK_BOX(tools), file_button("Save mask", "mask", &g));
    gtk_box_append(GTK_BOX(tools), file_button("Open textures", "folder", &g));
    a->gen_btn = button("Generate", "g", "render the abrasion timeline from the strokes (G)", &g);
    gtk_box_append(GTK_BOX(tools), a->gen_btn);
    a->progress_bar = gtk_progress_bar_new();
    gtk_widget_set_hexpand(a->progress_bar, TRUE);
    gtk_widget_set_valign(a->progress_bar, GTK_ALIGN_CENTER);
    gtk_box_append(GTK_BOX(tools), a->progress_bar);

    a->area = gtk_gl_area_new();
    gtk_gl_area_set_required_version(GTK_GL_AREA(a->area), 3, 3);
    gtk_gl_area_set_has_depth_buffer(GTK_GL_AREA(a->area), TRUE);
    gtk_widget_set_hexpand(a->area, TRUE);
    gtk_widget_set_vexpand(a->area, TRUE);
    gtk_widget_set_size_request(a->area, batch ? 64 : 320, batch ? 64 : 240);
    gtk_widget_set_focusable(a->area, TRUE);
    g_signal_connect(a->area, "realize", G_CALLBACK(on_realize), &g);
    g_signal_connect(a->area, "unrealize", G_CALLBACK(on_unrealize), &g);
    g_signal_connect(a->area, "render", G_CALLBACK(on_render), &g);
    g_signal_connect(a->area, "resize", G_CALLBACK(on_resize), &g);
    /* the F1 help: a dark box over the 3D view, hidden until asked for */
    GtkWidget *overlay = gtk_overlay_new();
    gtk_overlay_set_child(GTK_OVERLAY(overlay), a->area);
    GtkWidget *help = gtk_label_new(HELP_TEXT);
    gtk_widget_add_css_class(help, "skinsim-help");
    gtk_widget_set_halign(help, GTK_ALIGN_CENTER);
    gtk_widget_set_valign(help, GTK_ALIGN_CENTER);
    gtk_widget_set_can_target(help, FALSE);
    gtk_widget_set_visible(help, a->help);
    gtk_overlay_add_overlay(GTK_OVERLAY(overlay), help);
    a->help_box = help;
    GtkCssProvider *css = gtk_css_provider_new();
    gtk_css_provider_load_from_data(css,
                                    ".skinsim-help { background-color: rgba(0,0,0,0.8); "
                                    "color: #ffffff; padding: 16px; font-family: monospace; }",
                                    -1);
    gtk_style_context_add_provider_for_display(gdk_display_get_default(), GTK_STYLE_PROVIDER(css),
                                               GTK_STYLE_PROVIDER_PRIORITY_APPLICATION);
    g_object_unref(css);
    GtkGesture *drag = gtk_gesture_drag_new();
    gtk_gesture_single_set_button(GTK_GESTURE_SINGLE(drag), 0);
    g_signal_connect(drag, "drag-begin", G_CALLBACK(on_drag_begin), &g);
    g_signal_connect(drag, "drag-update", G_CALLBACK(on_drag_update), &g);
    g_signal_connect(drag, "drag-end", G_CALLBACK(on_drag_end), &g);
    gtk_widget_add_controller(a->area, GTK_EVENT_CONTROLLER(drag));
    GtkEventController *scroll =
        gtk_event_controller_scroll_new(GTK_EVENT_CONTROLLER_SCROLL_VERTICAL);
    g_signal_connect(scroll, "scroll", G_CALLBACK(on_scroll), &g);
    gtk_widget_add_controller(a->area, scroll);
    GtkEventController *motion = gtk_event_controller_motion_new();
    g_signal_connect(motion, "motion", G_CALLBACK(on_hover), &g);
    g_signal_connect(motion, "leave", G_CALLBACK(on_leave), &g);
    gtk_widget_add_controller(a->area, motion);
    GtkEventController *keys = gtk_event_controller_key_new();
    g_signal_connect(keys, "key-pressed", G_CALLBACK(on_key), &g);
    gtk_widget_add_controller(win, keys);
    gtk_box_append(GTK_BOX(vbox), overlay);

    GtkWidget *timebar = gtk_box_new(GTK_ORIENTATION_HORIZONTAL, 4);
    gtk_box_append(GTK_BOX(vbox), timebar);
    gtk_box_append(GTK_BOX(timebar), button("|<", "left", "previous key (Left)", &g));
    a->play_btn = button("Play", "space", "play/pause (Space)", &g);
    gtk_box_append(GTK_BOX(timebar), a->play_btn);
    gtk_box_append(GTK_BOX(timebar), button(">|", "right", "next key (Right)", &g));
    a->scale = gtk_scale_new_with_range(GTK_ORIENTATION_HORIZONTAL, 0, 1, 0.001);
    gtk_scale_set_draw_value(GTK_SCALE(a->scale), FALSE);
    gtk_widget_set_hexpand(a->scale, TRUE);
    gtk_widget_set_focusable(a->scale, FALSE);
    g_signal_connect(a->scale, "value-changed", G_CALLBACK(on_scale), &g);
    gtk_box_append(GTK_BOX(timebar), a->scale);
    a->day_label = gtk_label_new("");
    gtk_label_set_width_chars(GTK_LABEL(a->day_label), 26);
    gtk_box_append(GTK_BOX(timebar), a->day_label);
    a->status_label = gtk_label_new(a->status);
    gtk_label_set_xalign(GTK_LABEL(a->status_label), 0);
    gtk_label_set_ellipsize(GTK_LABEL(a->status_label), PANGO_ELLIPSIZE_END);
    gtk_box_append(GTK_BOX(vbox), a->status_label);

    app_sync_time_widgets(a);
    g_signal_connect(win, "close-request", G_CALLBACK(on_close), &g);
    guint tick = g_timeout_add(33, on_tick, &g);
    gtk_window_present(GTK_WINDOW(win));
    /* keys go to the 3D view from the start, not into the brush field */
    gtk_widget_grab_focus(a->area);
    if (!batch && a->o.generate) app_generate(a);
    while (!g.done) g_main_context_iteration(NULL, TRUE);
    g_source_remove(tick);
    gtk_window_destroy(GTK_WINDOW(win));
    while (g_main_context_pending(NULL)) g_main_context_iteration(NULL, FALSE);
    a->window = a->area = NULL;
    a->scale = a->day_label = a->progress_bar = a->status_label = a->paint_btn = NULL;
    a->help_box = a->erase_btn = a->mirror_btn = NULL;
    a->play_btn = a->gen_btn = NULL;
    return g.rc;
}

/* Sets what the process must have from its start (see main); returns 1
 * when something was set. */
static int view_env_defaults(void) {
    int set = 0;
    if (!getenv("OMP_WAIT_POLICY") && setenv("OMP_WAIT_POLICY", "passive", 1) == 0) set = 1;
    /* glibc's malloc asks for transparent huge pages (madvise) on the large
     * blocks it maps: Generate's layers, the library's images and Mesa's
     * texture storage. Where THP is "madvise" (Debian's default), every 4 KiB
     * first touch was a page fault: at 2048^2 Generate + upload took 6.0 +
     * 2.8 s, 4.3 CPU-s of it in the kernel; with this 3.3 + 0.35 s
     * (bench/view_startup.sh). GLIBC_TUNABLES=glibc.malloc.hugetlb=0 keeps
     * the old behaviour. */
    const char *t = getenv("GLIBC_TUNABLES");
    if (!t || !strstr(t, "glibc.malloc.hugetlb")) {
        char buf[1024];
        if (!t || !*t)
            snprintf(buf, sizeof buf, "glibc.malloc.hugetlb=1");
        else
            snprintf(buf, sizeof buf, "%s:glibc.malloc.hugetlb=1", t);
        if (strlen(buf) < sizeof buf - 1 && setenv("GLIBC_TUNABLES", buf, 1) == 0) set = 1;
    }
    return set;
}

int main(int argc, char **argv) {
    /* OpenMP threads that spin at barriers (libgomp's default) take the CPU
     * the GTK thread and the other team members need: on 2 busy cores the
     * start-up took 6-24 s instead of 1.4-2.2 s (bench/view.md). libgomp
     * reads OMP_WAIT_POLICY once, when it is loaded (glibc its tunables
     * likewise), so the policy is set here and the program runs itself again
     * (`skinsim view` sets both before it runs this program, so that costs
     * nothing there). */
    if (view_env_defaults()) execv("/proc/self/exe", argv); /* on failure: carry on as we are */
    double t_start = ss_now();                              /* for the first-frame time */
    /* Called as "skinsim view ..." through the skinsim command, or directly. */
    if (argc > 1 && !strcmp(argv[1], "view")) argc--, argv++;
    opts o;
    ss_error err = {0};
    int r = parse(argc, argv, &o, &err);
    o.t_start = t_start;
    if (r < 0) return 0;
    if (r) return cli_fail(CMD, &err);
    int batch = o.screenshot || o.bench_frames > 0 || o.save_strokes || o.save_mask;
    /* Batch outputs go through the project's output discipline: checked
     * now, staged after the inputs are read, swapped in only on success. */
    ss_outputs *outs = NULL;
    int i_shot = -1, i_csv = -1, i_mask = -1;
    ss_status st = SS_OK;
    if (o.screenshot || o.save_strokes || o.save_mask) {
        outs = ss_outputs_create("view", &err);
        if (!outs) return cli_fail(CMD, &err);
        const char *ins[] = {o.mesh, o.strokes, o.script};
        for (int i = 0; i < 3 && !st; i++)
            if (ins[i]) st = ss_outputs_input(outs, ins[i], &err);
        if (!st && o.screenshot) {
            i_shot = ss_outputs_count(outs);
            st = ss_outputs_add(outs, "--screenshot", o.screenshot, SS_OUTPUT_FILE,
                                (double)o.width * o.height * 3, &err);
        }
        if (!st && o.save_strokes) {
            i_csv = ss_outputs_count(outs);
            st = ss_outputs_add(outs, "--save-strokes", o.save_strokes, SS_OUTPUT_FILE, 0, &err);
        }
        if (!st && o.save_mask) {
            i_mask = ss_outputs_count(outs);
            st = ss_outputs_add(outs, "--save-mask", o.save_mask, SS_OUTPUT_FILE,
                                (double)o.texture_size * o.texture_size, &err);
        }
        if (st) {
            ss_outputs_free(outs);
            return cli_fail(CMD, &err);
        }
    }
    app *a = calloc(1, sizeof *a);
    if (!a) {
        ss_outputs_free(outs);
        return 1;
    }
    st = app_init(a, &o, &err);
    if (!st && outs) {
        st = ss_outputs_begin(outs, &err);
        if (i_shot >= 0) a->shot_path = ss_outputs_path(outs, i_shot);
        if (i_csv >= 0) a->csv_path = ss_outputs_path(outs, i_csv);
        if (i_mask >= 0) a->mask_path = ss_outputs_path(outs, i_mask);
    }
    int rc;
    if (st) {
        rc = cli_fail(CMD, &err);
    } else if (o.egl) {
        rc = run_egl(a);
    } else if (gtk_init_check()) {
        rc = run_gtk(a, batch);
    } else if (batch) {
        if (!o.quiet) fprintf(stderr, "skinsim view: no display; rendering through EGL\n");
        rc = run_egl(a);
    } else {
        fprintf(stderr, "skinsim view: cannot open a display (set DISPLAY, or use --screenshot "
                        "with --egl for headless rendering)\n");
        rc = 1;
    }
    if (outs && !st) {
        ss_error e2 = {0};
        if (ss_outputs_finish(outs, rc ? SS_ERR_RUNTIME : SS_OK, &e2) && !rc)
            rc = cli_fail(CMD, &e2);
    }
    ss_outputs_free(outs);
    app_free(a);
    free(a);
    return rc;
}
