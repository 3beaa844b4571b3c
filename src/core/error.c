/* Error records: a status code and a message that names the input. A
 * message longer than the record keeps its start and its end (the reason)
 * and loses the middle, so a 5000-character path cannot hide why. */
#define _GNU_SOURCE /* vasprintf */
#include "skinsim/core.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

ss_status ss_error_set(ss_error *err, ss_status code, const char *fmt, ...) {
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        char *full = NULL;
        int n = vasprintf(&full, fmt, ap);
        va_end(ap);
        if (n >= 0 && (size_t)n < sizeof err->msg) {
            memcpy(err->msg, full, (size_t)n + 1);
        } else if (n >= 0) {
            /* Too long (a path of thousands of characters): keep the start
             * and the end, where the reason is, and cut the middle. */
            size_t head = 300, tail = sizeof err->msg - head - 40;
            snprintf(err->msg, sizeof err->msg, "%.*s [...%zu characters...] %s", (int)head, full,
                     (size_t)n - head - tail, full + n - tail);
        } else {
            va_start(ap, fmt);
            vsnprintf(err->msg, sizeof err->msg, fmt, ap);
            va_end(ap);
        }
        free(full);
        err->code = code;
    }
    return code;
}

void ss_error_clear(ss_error *err) {
    if (err) {
        err->code = SS_OK;
        err->msg[0] = '\0';
    }
}

int ss_status_exit_code(ss_status code) {
    if (code == SS_OK) return 0;
    return code == SS_ERR_INPUT ? 2 : 1;
}
