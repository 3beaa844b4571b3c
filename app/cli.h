/* Shared helpers for the `skinsim` subcommands: number parsing that names the
 * option on error, error printing with the right exit code, common options. */
#ifndef SKINSIM_CLI_H
#define SKINSIM_CLI_H

#include <stdio.h>

#include "skinsim/core.h"

/* One subcommand: name, one-line summary, entry point returning the exit code. */
typedef struct cli_command {
    const char *name;
    const char *summary;
    int (*run)(int argc, char **argv);
} cli_command;

/* Subcommand entry points (one file each: app/cmd_<name>.c). */
int cmd_abrasion(int argc, char **argv);
int cmd_heal(int argc, char **argv);
int cmd_wound(int argc, char **argv);
int cmd_optics(int argc, char **argv);
int cmd_skin(int argc, char **argv);
int cmd_view(int argc, char **argv); /* execs skinsim-view (app/cmd_view.c) */
int cmd_mech(int argc, char **argv); /* `skinsim mech stretch` (app/cmd_mech.c) */
/* `skinsim optics fit` and `skinsim optics table` (app/cmd_optics_fit.c). */
int cmd_optics_fit(int argc, char **argv);
int cmd_optics_table(int argc, char **argv);
/* `skinsim optics match` (app/cmd_optics_match.c). */
int cmd_optics_match(int argc, char **argv);

/* Prints "skinsim <cmd>: <msg>" on stderr and returns the exit code for err. */
int cli_fail(const char *cmd, const ss_error *err);
/* For hand-rolled option loops: argv[*i] must be an option ("--name") and be
 * followed by its value, which is returned (and *i advanced past it); NULL
 * with err set otherwise. */
const char *cli_option_value(int argc, char **argv, int *i, ss_error *err);
/* Prints a usage error (exit code 2) with a hint to --help. */
int cli_usage_error(const char *cmd, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* "Did you mean": the text a help function prints (malloc'd, NULL on
 * failure), and the option of that text nearest to a misspelt one by edit
 * distance (at most 2 edits; 3 for names of 12 characters or more), written
 * into buf as " (did you mean '--photons'?)"; buf is "" when none is near or
 * bad is an option of the text (given without its value). Returns buf. */
char *cli_help_text(void (*help)(FILE *));
const char *cli_suggest(const char *bad, const char *help_text, char *buf, size_t n);

/* The usage error for an option the command does not know (exit 2), with the
 * suggestion from its help; the _set form puts "<what> '<opt>' (did you mean
 * ...)" into err instead, for parsers that report through an ss_error. */
int cli_unknown_option(const char *cmd, const char *opt, void (*help)(FILE *));
ss_status cli_unknown_option_set(ss_error *err, const char *what, const char *opt,
                                 void (*help)(FILE *));

/* Strict number parsing: the whole string must be a finite number within
 * [lo, hi]; on failure err names the option and the value. */
ss_status cli_parse_double(const char *opt, const char *s, double lo, double hi, double *out,
                           ss_error *err);
ss_status cli_parse_int(const char *opt, const char *s, long lo, long hi, long *out, ss_error *err);
ss_status cli_parse_u64(const char *opt, const char *s, uint64_t *out, ss_error *err);
/* Comma-separated list of doubles within [lo, hi]; *out is malloc'd. */
ss_status cli_parse_double_list(const char *opt, const char *s, double lo, double hi, double **out,
                                int *count, ss_error *err);

#endif
