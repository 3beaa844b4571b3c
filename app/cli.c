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

/* ---- "did you mean" ------------------------------------------------------------
 * The options a command knows are the "--name" words of its own --help text,
 * so the suggestion can never name an option the help does not show, and no
 * second list of options has to be kept in step with the parser. */

char *cli_help_text(void (*help)(FILE *)) {
    char *text = NULL;
    size_t len = 0;
    FILE *m = open_memstream(&text, &len);
    if (!m) return NULL;
    help(m);
    if (fclose(m) != 0) {
        free(text);
        return NULL;
    }
    return text;
}

/* Levenshtein distance of a[0..na) and b[0..nb), at most 63 characters each. */
static int edit_distance(const char *a, size_t na, const char *b, size_t nb) {
    int row[64];
    for (size_t j = 0; j <= nb; j++) row[j] = (int)j;
    for (size_t i = 1; i <= na; i++) {
        int diag = row[0];
        row[0] = (int)i;
        for (size_t j = 1; j <= nb; j++) {
            int up = row[j];
            int best = diag + (a[i - 1] != b[j - 1]);
            if (up + 1 < best) best = up + 1;
            if (row[j - 1] + 1 < best) best = row[j - 1] + 1;
            row[j] = best;
            diag = up;
        }
    }
    return row[nb];
}

const char *cli_suggest(const char *bad, const char *help_text, char *buf, size_t n) {
    if (n) buf[0] = '\0';
    if (!bad || !help_text || n < 32 || strncmp(bad, "--", 2)) return buf;
    size_t nb = strcspn(bad, "="); /* --name=value: the name */
    if (nb > 63) return buf;
    size_t best_len = 0;
    const char *best = NULL;
    int best_d = nb >= 12 ? 4 : 3; /* a suggestion is at most 2 edits away, 3 for long names */
    for (const char *p = help_text; (p = strstr(p, "--"));) {
        int starts = p == help_text || strchr(" \t\n(,[|", p[-1]);
        size_t k = 2;
        while ((p[k] >= 'a' && p[k] <= 'z') || (p[k] >= '0' && p[k] <= '9') || p[k] == '-') k++;
        if (starts && k > 2 && k <= 63 && p[k - 1] != '-') {
            int d = edit_distance(bad, nb, p, k);
            if (d == 0) return buf; /* a known option (given without its value) */
            if (d < best_d) best_d = d, best = p, best_len = k;
        }
        p += k;
    }
    if (best) snprintf(buf, n, " (did you mean '%.*s'?)", (int)best_len, best);
    return buf;
}

int cli_unknown_option(const char *cmd, const char *opt, void (*help)(FILE *)) {
    char *text = cli_help_text(help), sug[128];
    int rc =
        cli_usage_error(cmd, "unknown option '%s'%s", opt, cli_suggest(opt, text, sug, sizeof sug));
    free(text);
    return rc;
}

ss_status cli_unknown_option_set(ss_error *err, const char *what, const char *opt,
                                 void (*help)(FILE *)) {
    char *text = cli_help_text(help), sug[128];
    ss_status st = ss_error_set(err, SS_ERR_INPUT, "%s '%s'%s", what, opt,
                                cli_suggest(opt, text, sug, sizeof sug));
    free(text);
    return st;
}
