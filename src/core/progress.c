/* Progress bar on stderr, only when stderr is a terminal; redrawn at most 10x/s. */
#define _POSIX_C_SOURCE 200809L
#include "skinsim/core.h"

#include <time.h>
#include <unistd.h>

double ss_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void draw(ss_progress *p) {
    double f = p->total > 0 ? p->done / p->total : 0;
    if (f > 1) f = 1;
    int w = 30, n = (int)(f * w);
    fprintf(stderr, "\r%-16s [", p->label ? p->label : "");
    for (int i = 0; i < w; i++) fputc(i < n ? '#' : '.', stderr);
    fprintf(stderr, "] %3d%% %6.1fs", (int)(f * 100), ss_now() - p->start);
    fflush(stderr);
}

void ss_progress_begin(ss_progress *p, const char *label, double total, int quiet) {
    p->label = label;
    p->total = total;
    p->done = 0;
    p->enabled = !quiet && isatty(STDERR_FILENO);
    p->start = ss_now();
    p->last_draw = 0;
    if (p->enabled) draw(p);
}

void ss_progress_update(ss_progress *p, double done) {
    p->done = done;
    if (!p->enabled) return;
    double t = ss_now();
    if (t - p->last_draw < 0.1) return;
    p->last_draw = t;
    draw(p);
}

void ss_progress_end(ss_progress *p) {
    if (!p->enabled) return;
    p->done = p->total;
    draw(p);
    fputc('\n', stderr);
}
