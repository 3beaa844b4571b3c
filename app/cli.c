#define _POSIX_C_SOURCE 200809L
/* Shared CLI helpers; see cli.h. */
#include "cli.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

int cli_fail(const char *cmd, const ss_error *err) {
    fprintf(stderr, "skinsim %s: error: %s\n", cmd, err->msg[0] ? err->msg : "unknown error");
    return ss_status_exit_code(err->code ? err->code : SS_ERR_RUNTIME);
}

int cli_usage_error(const char *cmd, const char *fmt, ...) {
    va_list ap;
    fprintf(stderr, "skinsim %s: error: ", cmd);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\n(see 'skinsim %s --help')\n", cmd);
    return 2;
}

ss_status cli_parse_double(const char *opt, const char *s, double lo, double hi, double *out,
                           ss_error *err) {
    char *end;
    errno = 0;
    double v = s ? strtod(s, &end) : NAN;
    if (!s || end == s || *end != '\0')
        return ss_error_set(err, SS_ERR_INPUT, "%s: '%s' is not a number", opt,
                            s ? s : "(missing)");
    /* ERANGE with a tiny result is underflow: the value is as good as 0 and
     * the range check below says whether that is allowed */
    if (!isfinite(v) || (errno == ERANGE && fabs(v) > 1.0))
        return ss_error_set(err, SS_ERR_INPUT, "%s: '%s' is %s", opt, s,
                            isnan(v) ? "not a number" : "too large (not finite as a double)");
    if (v < lo || v > hi)
        return ss_error_set(err, SS_ERR_INPUT, "%s: %s is out of range [%g, %g]", opt, s, lo, hi);
    *out = v;
    return SS_OK;
}

ss_status cli_parse_int(const char *opt, const char *s, long lo, long hi, long *out,
                        ss_error *err) {
    char *end;
    errno = 0;
    long v = s ? strtol(s, &end, 10) : 0;
    if (!s || end == s || *end != '\0')
        return ss_error_set(err, SS_ERR_INPUT, "%s: '%s' is not an integer", opt,
                            s ? s : "(missing)");
    if (errno == ERANGE)
        return ss_error_set(err, SS_ERR_INPUT, "%s: %s is out of range [%ld, %ld]", opt, s, lo, hi);
    if (v < lo || v > hi)
        return ss_error_set(err, SS_ERR_INPUT, "%s: %ld is out of range [%ld, %ld]", opt, v, lo,
                            hi);
    *out = v;
    return SS_OK;
}

ss_status cli_parse_u64(const char *opt, const char *s, uint64_t *out, ss_error *err) {
    char *end;
    errno = 0;
    if (!s || *s == '-' || *s == '\0')
        return ss_error_set(err, SS_ERR_INPUT, "%s: '%s' is not a non-negative integer", opt,
                            s ? s : "(missing)");
    unsigned long long v = strtoull(s, &end, 10);
    if (end == s || *end != '\0')
        return ss_error_set(err, SS_ERR_INPUT, "%s: '%s' is not a non-negative integer", opt, s);
    if (errno == ERANGE)
        return ss_error_set(err, SS_ERR_INPUT, "%s: %s is too large (at most %llu)", opt, s,
                            (unsigned long long)UINT64_MAX);
    *out = (uint64_t)v;
    return SS_OK;
}

ss_status cli_parse_double_list(const char *opt, const char *s, double lo, double hi, double **out,
                                int *count, ss_error *err) {
    *out = NULL;
    *count = 0;
    if (!s || !*s) return ss_error_set(err, SS_ERR_INPUT, "%s: empty list", opt);
    size_t n = 1;
    for (const char *p = s; *p; p++) n += *p == ',';
    double *v = malloc(n * sizeof *v);
    char *copy = strdup(s);
    if (!v || !copy) {
        free(v);
        free(copy);
        return ss_error_set(err, SS_ERR_NOMEM, "out of memory");
    }
    int k = 0;
    char *save = NULL;
    for (char *tok = strtok_r(copy, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        ss_status st = cli_parse_double(opt, tok, lo, hi, &v[k], err);
        if (st) {
            free(v);
            free(copy);
            return st;
        }
        k++;
    }
    free(copy);
    if (k == 0) {
        free(v);
        return ss_error_set(err, SS_ERR_INPUT, "%s: empty list", opt);
    }
    *out = v;
    *count = k;
    return SS_OK;
}

const char *cli_option_value(int argc, char **argv, int *i, ss_error *err) {
    const char *a = argv[*i];
    if (strncmp(a, "--", 2) != 0) {
        ss_error_set(err, SS_ERR_INPUT, "unexpected argument '%s'", a);
        return NULL;
    }
    if (*i + 1 >= argc) {
        ss_error_set(err, SS_ERR_INPUT, "%s needs a value", a);
        return NULL;
    }
    return argv[++*i];
}
