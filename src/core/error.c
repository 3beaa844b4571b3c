/* Error records: a status code and a message that names the input. */
#include "skinsim/core.h"

#include <stdarg.h>
#include <string.h>

ss_status ss_error_set(ss_error *err, ss_status code, const char *fmt, ...) {
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
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
