/* MPI start-up for skinsim (docs/scaling.md): MPI is initialised only when
 * the process was launched by an MPI launcher, so `skinsim` run directly
 * starts as fast as a build without MPI and never touches the network stack;
 * under mpirun every rank runs the same command line and rank 0 decides. */
#include <mpi.h>
#include <stdlib.h>

#include "skinsim/dist.h"

static int g_inited, g_rank, g_size = 1;

static int launched_by_mpirun(void) {
    const char *vars[] = {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE", "PMI_RANK"};
    for (size_t i = 0; i < sizeof vars / sizeof vars[0]; i++)
        if (getenv(vars[i])) return 1;
    const char *f = getenv("SKINSIM_MPI");
    return f && f[0] == '1';
}

int ss_dist_init(int *argc, char ***argv) {
    if (g_inited || !launched_by_mpirun()) return 0;
    int provided = 0;
    if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) return -1;
    g_inited = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &g_rank);
    MPI_Comm_size(MPI_COMM_WORLD, &g_size);
    return 0;
}

void ss_dist_finalize(void) {
    if (!g_inited) return;
    MPI_Finalize();
    g_inited = 0;
}

int ss_dist_rank(void) { return g_rank; }
int ss_dist_active(void) { return g_inited; }
int ss_dist_size(void) { return g_size; }
