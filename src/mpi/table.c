/* The ModelMatch table of seed 003 §4.8.6 on MPI (docs/scaling.md): rank 0
 * hands out geometries (pairs of layer thicknesses, whose photon paths are
 * traced once for all their absorption sets) one at a time to the other
 * ranks as they ask for work (dynamic self-scheduling: a slow geometry or a
 * slow rank never holds the others back) and places the returned entries.
 * Every geometry draws from the same counter-based streams wherever it runs,
 * so the table has the bytes of the single-process build for the same seed.
 * Rank 0 only dispatches (it waits in MPI_Recv, which OpenMPI turns into
 * yielding when the machine is oversubscribed); run workers + 1 ranks. */
#include <mpi.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/dist.h"

enum { TAG_WORK = 1, TAG_HEAD, TAG_ENTRIES, TAG_MSG };

static int nabs_of(const ss_mm_table *t) {
    return t->nsamples[0] * t->nsamples[1] * t->nsamples[2] * t->nsamples[3];
}

/* index in t->entries (in entries) of absorption set a of geometry gi */
static size_t entry_at(const ss_mm_table *t, int gi, int a) {
    int idx[SS_MM_NAXES];
    for (int ax = 3; ax >= 0; ax--) {
        idx[ax] = a % t->nsamples[ax];
        a /= t->nsamples[ax];
    }
    idx[4] = gi / t->nsamples[5];
    idx[5] = gi % t->nsamples[5];
    return ss_mm_table_index(t, idx);
}

static void worker(ss_mm_table *t, const ss_mm_build_options *o, double *buf) {
    ss_mm_build_options q = *o;
    q.quiet = 1;
    const int nabs = nabs_of(t);
    for (;;) {
        int gi;
        MPI_Recv(&gi, 1, MPI_INT, 0, TAG_WORK, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        if (gi < 0) return;
        ss_error e;
        ss_error_clear(&e);
        int head[2] = {gi, (int)ss_mm_table_build_geometry(t, &q, gi, &e)};
        MPI_Send(head, 2, MPI_INT, 0, TAG_HEAD, MPI_COMM_WORLD);
        if (head[1]) {
            MPI_Send(e.msg, (int)sizeof e.msg, MPI_CHAR, 0, TAG_MSG, MPI_COMM_WORLD);
            continue;
        }
        for (int a = 0; a < nabs; a++)
            memcpy(buf + (size_t)a * SS_MM_NFIELDS, t->entries + entry_at(t, gi, a) * SS_MM_NFIELDS,
                   SS_MM_NFIELDS * sizeof(double));
        MPI_Send(buf, nabs * SS_MM_NFIELDS, MPI_DOUBLE, 0, TAG_ENTRIES, MPI_COMM_WORLD);
    }
}

static ss_status master(ss_mm_table *t, const ss_mm_build_options *o, int size, double *buf,
                        ss_error *err) {
    const int ngeo = ss_mm_table_ngeometries(t), nabs = nabs_of(t);
    int next = 0, busy = 0;
    ss_status st = SS_OK;
    ss_progress pr;
    ss_progress_begin(&pr, "ModelMatch table (MPI)", (double)ngeo, o->quiet);
    for (int w = 1; w < size; w++) {
        int gi = next < ngeo ? next++ : -1;
        MPI_Send(&gi, 1, MPI_INT, w, TAG_WORK, MPI_COMM_WORLD);
        busy += gi >= 0;
    }
    int done = 0;
    while (busy > 0) {
        int head[2];
        MPI_Status ms;
        MPI_Recv(head, 2, MPI_INT, MPI_ANY_SOURCE, TAG_HEAD, MPI_COMM_WORLD, &ms);
        const int w = ms.MPI_SOURCE;
        if (head[1]) {
            ss_error e;
            MPI_Recv(e.msg, (int)sizeof e.msg, MPI_CHAR, w, TAG_MSG, MPI_COMM_WORLD,
                     MPI_STATUS_IGNORE);
            e.msg[sizeof e.msg - 1] = 0;
            if (!st) st = ss_error_set(err, (ss_status)head[1], "%s", e.msg);
        } else {
            MPI_Recv(buf, nabs * SS_MM_NFIELDS, MPI_DOUBLE, w, TAG_ENTRIES, MPI_COMM_WORLD,
                     MPI_STATUS_IGNORE);
            for (int a = 0; a < nabs; a++)
                memcpy(t->entries + entry_at(t, head[0], a) * SS_MM_NFIELDS,
                       buf + (size_t)a * SS_MM_NFIELDS, SS_MM_NFIELDS * sizeof(double));
            ss_progress_update(&pr, (double)++done);
        }
        int gi = !st && next < ngeo ? next++ : -1;
        MPI_Send(&gi, 1, MPI_INT, w, TAG_WORK, MPI_COMM_WORLD);
        if (gi < 0) busy--;
    }
    ss_progress_end(&pr);
    if (!st) ss_mm_table_record_options(t, o);
    return st;
}

ss_status ss_dist_mm_table_build(ss_mm_table *t, const ss_mm_build_options *o, ss_status root_st,
                                 ss_error *err) {
    int rank, size;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    /* rank 0's verdict on its input and outputs, then every rank's table */
    int v = (int)root_st;
    MPI_Bcast(&v, 1, MPI_INT, 0, MPI_COMM_WORLD);
    if (!v) v = t ? (int)ss_mm_table_build_check(t, o, err) : (int)SS_ERR_NOMEM;
    int vmax = v;
    MPI_Allreduce(&v, &vmax, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    if (vmax) {
        if (!v) ss_error_set(err, (ss_status)vmax, "another rank refused the table");
        return (ss_status)vmax;
    }
    if (size == 1) return ss_mm_table_build(t, o, err);
    double *buf = malloc((size_t)nabs_of(t) * SS_MM_NFIELDS * sizeof(double));
    if (!buf) MPI_Abort(MPI_COMM_WORLD, 3); /* the others wait for this rank */
    ss_status st = SS_OK;
    if (rank == 0)
        st = master(t, o, size, buf, err);
    else
        worker(t, o, buf);
    free(buf);
    v = (int)st;
    MPI_Bcast(&v, 1, MPI_INT, 0, MPI_COMM_WORLD);
    if (v && rank != 0) ss_error_set(err, (ss_status)v, "rank 0 reported an error");
    return (ss_status)v;
}
