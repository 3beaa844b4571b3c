/* Small text helpers shared by the file readers (stroke CSV, OBJ, ...):
 * line splitting that handles \n, \r\n and \r, trimming, and strict number
 * parsing that tells "not a number" from "not finite". */
#define _POSIX_C_SOURCE 200809L
#include "skinsim/core.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

const char *ss_text_next_line(const char *p, char *buf, size_t bufsize, int *too_long) {
    if (!*p) return NULL;
    size_t n = 0;
    *too_long = 0;
    while (*p && *p != '\n' && *p != '\r') {
        if (n + 1 < bufsize)
            buf[n++] = *p;
        else
            *too_long = 1;
        p++;
    }
    buf[n] = '\0';
    if (*p == '\r') p++;
    if (*p == '\n') p++;
    return p;
}

char *ss_text_trim(char *s) {
    while (isspace((unsigned char)*s)) s++;
    size_t n = strlen(s);
    while (n && isspace((unsigned char)s[n - 1])) s[--n] = '\0';
    return s;
}

int ss_text_parse_number(const char *s, double *out) {
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end != '\0') return 1;
    /* underflow (1e-320) is a finite number as good as 0; overflow is not */
    if (!isfinite(v) || (errno == ERANGE && fabs(v) > 1.0)) return 2;
    *out = v;
    return 0;
}
