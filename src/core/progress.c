/* Progress bar on stderr, only when stderr is a terminal; redrawn at most 10x/s.
 * For a program that runs a command as a child (the Blender add-on): with
 * SKINSIM_PROGRESS_FD=N in the environment, every redraw also writes the line
 * "skinsim-progress LABEL FRACTION" to file descriptor N, quiet or not. The
 * enabled field holds which of the two are on (1 the bar, 2 the lines). */
#define _POSIX_C_SOURCE 200809L
#include "skinsim/core.h"

#include <errno.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

#define BAR 1
#define LINES 2

/* The descriptor of SKINSIM_PROGRESS_FD, or -1 (unset, not a number, not open). */
static int line_fd(void) {
    const char *e = getenv("SKINSIM_PROGRESS_FD");
    if (!e || !*e) return -1;
    char *end;
    errno = 0;
    long v = strtol(e, &end, 10);
    if (*end || errno || v < 3 || v > 1 << 20) return -1; /* never stdin/out/err */
    return (int)v;
}

static void write_line(const ss_progress *p, double f) {
    int fd = line_fd();
    if (fd < 0) return;
    char buf[160];
    int n = snprintf(buf, sizeof buf, "skinsim-progress %s %.4f\n", p->label ? p->label : "-", f);
    if (n > 0 && n < (int)sizeof buf && write(fd, buf, (size_t)n) < 0) {
        /* the reader went away: nothing to report to */
    }
}

double ss_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void draw(ss_progress *p) {
    double f = p->total > 0 ? p->done / p->total : 0;
    if (f > 1) f = 1;
    if (p->enabled & LINES) write_line(p, f);
    if (!(p->enabled & BAR)) return;
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
    p->enabled = (!quiet && isatty(STDERR_FILENO) ? BAR : 0) | (line_fd() >= 0 ? LINES : 0);
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
    if (p->enabled & BAR) fputc('\n', stderr);
}
