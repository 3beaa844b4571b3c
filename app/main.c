/* The `skinsim` command: dispatches to one subcommand per file (cmd_*.c). */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#ifdef SKINSIM_HAVE_MPI
#include "skinsim/dist.h"
#endif

static const cli_command commands[] = {
    {"abrasion", "abrasion-healing texture timeline (seed 000)", cmd_abrasion},
    {"heal", "3D wound-healing simulation: fields, area curve, VTK (seed 001)", cmd_heal},
    {"wound", "a healing wound as skin textures day by day (seeds 001 + 003 + 000)", cmd_wound},
    {"optics", "skin light transport: spectra, colour, BRDF, MCML files (seed 003)", cmd_optics},
    {"skin", "procedural skin textures from biological features (seed 003)", cmd_skin},
    {"mech", "tissue mechanics: the uniaxial stretch test of the GOH and springs models", cmd_mech},
    {"view", "paint a wound on a 3D body and scrub its healing (GTK 4 window)", cmd_view},
};
static const int ncommands = (int)(sizeof commands / sizeof commands[0]);

static void usage(FILE *f) {
    fprintf(f,
            "skinsim %s - simulate skin and wound healing, and turn it into textures\n\n"
            "usage: skinsim <command> [options]     skinsim <command> --help\n\n"
            "commands:\n",
            SKINSIM_VERSION);
    for (int i = 0; i < ncommands; i++)
        fprintf(f, "  %-10s %s\n", commands[i].name, commands[i].summary);
    fprintf(f, "\noptions:\n"
               "  --help       this text\n"
               "  --version    print the version\n\n"
               "Exit codes: 0 success, 1 runtime failure, 2 bad usage or bad input.\n"
               "Environment: SKINSIM_THREADS (default thread count), SKINSIM_DATA (data dir).\n");
}

static int dispatch(int argc, char **argv);

/* `skinsim heal` steps thousands of short parallel loops; with the OpenMP
 * default (threads spin at each barrier for a while before they sleep) the
 * spinning cost 30 % of the command's CPU time on a machine shared with other
 * jobs (1 simulated day on the 160x124x159 grid, 2 threads, load ~7: 11.4 vs
 * 8.1 CPU-s; docs/heal-model.md §8). libgomp reads its environment when it is
 * loaded, before main, so the policy is set by running the command once more
 * with OMP_WAIT_POLICY=PASSIVE (same process, same pid: mpirun is unaffected).
 * A user's OMP_WAIT_POLICY or GOMP_SPINCOUNT is kept; results do not depend on
 * it (no reductions depend on the schedule). If exec fails the run goes on.
 * Under a tool that hosts the process (valgrind), set OMP_WAIT_POLICY. */
static void passive_threads(int argc, char **argv) {
    if (argc < 2 || strcmp(argv[1], "heal") || getenv("OMP_WAIT_POLICY") ||
        getenv("GOMP_SPINCOUNT"))
        return;
    if (setenv("OMP_WAIT_POLICY", "PASSIVE", 0)) return;
    execv("/proc/self/exe", argv);
}

/* Under mpirun (a build with MPI) every rank runs the same command line; only
 * rank 0 prints (the others' stdout and stderr go to /dev/null unless
 * SKINSIM_DIST_VERBOSE=1) and only heal and optics run on several ranks. */
int main(int argc, char **argv) {
    passive_threads(argc, argv);
#ifdef SKINSIM_HAVE_MPI
    if (ss_dist_init(&argc, &argv)) {
        fprintf(stderr, "skinsim: error: MPI_Init failed\n");
        return 1;
    }
    const char *verbose = getenv("SKINSIM_DIST_VERBOSE");
    if (ss_dist_rank() > 0 && !(verbose && verbose[0] == '1')) {
        if (!freopen("/dev/null", "w", stdout) || !freopen("/dev/null", "w", stderr)) return 1;
    }
    int rc = 2;
    if (ss_dist_size() > 1 && argc >= 2 && strcmp(argv[1], "heal") &&
        !(argc >= 3 && !strcmp(argv[1], "optics") && !strcmp(argv[2], "table")))
        fprintf(stderr,
                "skinsim: error: '%s' does not run on %d MPI ranks; only heal and "
                "optics table do (run it without mpirun)\n",
                argv[1], ss_dist_size());
    else
        rc = dispatch(argc, argv);
    ss_dist_finalize();
    return rc;
#else
    return dispatch(argc, argv);
#endif
}

static int dispatch(int argc, char **argv) {
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    const char *cmd = argv[1];
    if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || !strcmp(cmd, "help")) {
        usage(stdout);
        return 0;
    }
    if (!strcmp(cmd, "--version") || !strcmp(cmd, "-V")) {
#ifdef SKINSIM_HAVE_MPI
        printf("skinsim %s (with MPI)\n", SKINSIM_VERSION);
#else
        printf("skinsim %s\n", SKINSIM_VERSION);
#endif
        return 0;
    }
    /* SKINSIM_THREADS is checked like --threads, once for every command */
    ss_error err;
    ss_error_clear(&err);
    if (ss_threads_check_env(&err)) {
        fprintf(stderr, "skinsim: error: %s\n", err.msg);
        return 2;
    }
    for (int i = 0; i < ncommands; i++)
        if (!strcmp(cmd, commands[i].name)) return commands[i].run(argc - 1, argv + 1);
    fprintf(stderr, "skinsim: unknown command '%s'\n\n", cmd);
    usage(stderr);
    return 2;
}
