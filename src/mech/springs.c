/* Mass-spring system on the edges of a tet mesh (seed 001 §5.2) and its
 * relaxation by damped sub-steps.
 *
 * Every unique tet edge is a linear spring (force k (|e| - rest) along e);
 * its stiffness k = modulus V / l0^2, V a sixth of every adjacent tet's
 * volume, so the springs' energy density matches a material of that modulus
 * under uniform stretch. The seed relaxes with 60 sub-steps per frame; here
 * the sub-steps are dynamic relaxation (Underwood 1983; Barnes 1999):
 * semi-implicit Euler with fictitious nodal masses m_i = sum of the node's
 * spring and anchor stiffnesses (Gershgorin: the step is stable with room to
 * spare), viscous damping, and the velocities reset to zero whenever the power
 * f.v turns negative (the kinetic-damping idea, as in FIRE). Sub-steps stop
 * when the largest nodal move of a step falls under tol x the mean edge,
 * and the count is reported. Forces are gathered per node (each spring
 * evaluated from both ends) so the loop is parallel without atomics and the
 * result is bit-identical for any thread count. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "skinsim/mech.h"

/* nodes (or tets) per block of the fixed-order sums */
#define BLOCK 1024

typedef struct edge_share {
    uint64_t key;
    double vol;
} edge_share;

static int cmp_share(const void *a, const void *b) {
    uint64_t x = ((const edge_share *)a)->key, y = ((const edge_share *)b)->key;
    return x < y ? -1 : x > y;
}

void ss_springs_free(ss_springs *s) {
    if (!s) return;
    free(s->X);
    free(s->x);
    free(s->v);
    free(s->e);
    free(s->l0);
    free(s->rest);
    free(s->k);
    free(s->vol);
    free(s->anchor);
    free(s->fixed);
    free(s->adj_start);
    free(s->adj);
    free(s->mass);
    free(s->f);
    free(s->f2);
    free(s->x2);
    free(s->unode);
    free(s->tet);
    free(s->tet_edge);
    free(s->ntet_start);
    free(s->ntet);
    free(s->tvol0);
    free(s->tvol_rest);
    free(s->tcoef);
    free(s->tpart);
    free(s->tskip);
    free(s->xref);
    free(s->tdist);
    free(s->tnear);
    free(s->nsafe);
    free(s->tmark);
    free(s->nflag);
    free(s);
}

static ss_status build_adjacency(ss_springs *s, ss_error *err) {
    free(s->adj_start);
    free(s->adj);
    s->adj_start = calloc((size_t)s->nnodes + 1, sizeof(int32_t));
    s->adj = malloc(2 * (size_t)s->nsprings * sizeof(int32_t) + 1);
    if (!s->adj_start || !s->adj) return ss_error_set(err, SS_ERR_NOMEM, "springs: out of memory");
    for (int i = 0; i < s->nsprings; i++) {
        s->adj_start[s->e[2 * i] + 1]++;
        s->adj_start[s->e[2 * i + 1] + 1]++;
    }
    for (int i = 0; i < s->nnodes; i++) s->adj_start[i + 1] += s->adj_start[i];
    int32_t *fill = malloc((size_t)s->nnodes * sizeof(int32_t) + 1);
    if (!fill) return ss_error_set(err, SS_ERR_NOMEM, "springs: out of memory");
    memcpy(fill, s->adj_start, (size_t)s->nnodes * sizeof(int32_t));
    for (int i = 0; i < s->nsprings; i++) { /* spring order: ascending per node */
        s->adj[fill[s->e[2 * i]]++] = i;
        s->adj[fill[s->e[2 * i + 1]]++] = i;
    }
    free(fill);
    return SS_OK;
}

void ss_springs_update_mass(ss_springs *s) {
    for (int i = 0; i < s->nnodes; i++) {
        double m = s->anchor[i];
        for (int a = s->adj_start[i]; a < s->adj_start[i + 1]; a++) m += s->k[s->adj[a]];
        s->mass[i] = m > 0 ? m : 1.0;
    }
}

ss_springs *ss_springs_create(const ss_tetmesh *m, double modulus, ss_error *err) {
    if (!m || m->nnodes < 4 || m->ntets < 1) {
        ss_error_set(err, SS_ERR_INPUT, "springs: empty tet mesh");
        return NULL;
    }
    static const int E6[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    size_t ns = 6 * (size_t)m->ntets;
    edge_share *sh = malloc(ns * sizeof *sh);
    ss_springs *s = calloc(1, sizeof *s);
    if (!sh || !s) goto nomem;
    for (int t = 0; t < m->ntets; t++) {
        const int32_t *q = m->tet + 4 * t;
        const double *a = m->x + 3 * q[0], *b = m->x + 3 * q[1], *c = m->x + 3 * q[2],
                     *d = m->x + 3 * q[3];
        double u[3], v[3], w[3];
        for (int i = 0; i < 3; i++) {
            u[i] = b[i] - a[i];
            v[i] = c[i] - a[i];
            w[i] = d[i] - a[i];
        }
        double vol = fabs(u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
                          u[2] * (v[0] * w[1] - v[1] * w[0])) /
                     6.0;
        for (int k = 0; k < 6; k++) {
            uint32_t i = (uint32_t)q[E6[k][0]], j = (uint32_t)q[E6[k][1]];
            if (i > j) {
                uint32_t tmp = i;
                i = j;
                j = tmp;
            }
            sh[6 * (size_t)t + k] = (edge_share){((uint64_t)i << 32) | j, vol / 6.0};
        }
    }
    qsort(sh, ns, sizeof *sh, cmp_share);
    size_t ne = 0;
    for (size_t i = 0; i < ns; i++)
        if (i == 0 || sh[i].key != sh[i - 1].key) ne++;
    s->nnodes = m->nnodes;
    s->nsprings = (int)ne;
    size_t n3 = 3 * (size_t)m->nnodes;
    s->X = malloc(n3 * sizeof(double));
    s->x = malloc(n3 * sizeof(double));
    s->v = calloc(n3, sizeof(double));
    s->e = malloc(2 * ne * sizeof(int32_t));
    s->l0 = malloc(ne * sizeof(double));
    s->rest = malloc(ne * sizeof(double));
    s->k = malloc(ne * sizeof(double));
    s->vol = calloc(ne, sizeof(double));
    s->anchor = calloc((size_t)m->nnodes, sizeof(double));
    s->fixed = calloc((size_t)m->nnodes, 1);
    s->mass = malloc((size_t)m->nnodes * sizeof(double));
    s->f = malloc(n3 * sizeof(double));
    s->f2 = malloc(n3 * sizeof(double));
    s->x2 = malloc(n3 * sizeof(double));
    s->unode = malloc((size_t)m->nnodes * sizeof(double));
    if (!s->unode || !s->f || !s->f2 || !s->x2 || !s->X || !s->x || !s->v || !s->e || !s->l0 ||
        !s->rest || !s->k || !s->vol || !s->anchor || !s->fixed || !s->mass)
        goto nomem;
    memcpy(s->X, m->x, n3 * sizeof(double));
    memcpy(s->x, m->x, n3 * sizeof(double));
    long j = -1;
    for (size_t i = 0; i < ns; i++) {
        if (i == 0 || sh[i].key != sh[i - 1].key) {
            j++;
            s->e[2 * j] = (int32_t)(sh[i].key >> 32);
            s->e[2 * j + 1] = (int32_t)(sh[i].key & 0xffffffffu);
        }
        s->vol[j] += sh[i].vol;
    }
    free(sh);
    sh = NULL;
    for (int i = 0; i < s->nsprings; i++) {
        const double *a = s->X + 3 * s->e[2 * i], *b = s->X + 3 * s->e[2 * i + 1];
        double l = sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                        (b[2] - a[2]) * (b[2] - a[2]));
        s->l0[i] = s->rest[i] = l;
        s->k[i] = modulus * s->vol[i] / (l * l);
    }
    s->damping = 0.98;
    if (build_adjacency(s, err) != SS_OK) {
        ss_springs_free(s);
        return NULL;
    }
    ss_springs_update_mass(s);
    return s;
nomem:
    free(sh);
    ss_springs_free(s);
    ss_error_set(err, SS_ERR_NOMEM, "springs: out of memory for %d tets", m->ntets);
    return NULL;
}

ss_status ss_springs_add(ss_springs *s, int a, int b, double rest, double k, ss_error *err) {
    const int32_t ab[2] = {a, b};
    return ss_springs_add_many(s, 1, ab, &rest, &k, err);
}

/* One reallocation and one CSR rebuild for the whole batch: adding the
 * springs of many sutures one by one rebuilt the CSR each time (quadratic). */
ss_status ss_springs_add_many(ss_springs *s, int count, const int32_t *ab, const double *rest,
                              const double *k, ss_error *err) {
    if (count <= 0) return SS_OK;
    for (int i = 0; i < count; i++) {
        int a = ab[2 * i], b = ab[2 * i + 1];
        if (a < 0 || b < 0 || a >= s->nnodes || b >= s->nnodes || a == b)
            return ss_error_set(err, SS_ERR_INPUT, "springs: bad node pair %d-%d", a, b);
    }
    if (count > INT32_MAX - s->nsprings)
        return ss_error_set(err, SS_ERR_INPUT, "springs: more than %d springs", INT32_MAX);
    size_t n = (size_t)s->nsprings + (size_t)count;
    int32_t *e = realloc(s->e, 2 * n * sizeof(int32_t));
    if (e) s->e = e;
    double *l0 = realloc(s->l0, n * sizeof(double));
    if (l0) s->l0 = l0;
    double *rs = realloc(s->rest, n * sizeof(double));
    if (rs) s->rest = rs;
    double *kk = realloc(s->k, n * sizeof(double));
    if (kk) s->k = kk;
    double *vv = realloc(s->vol, n * sizeof(double));
    if (vv) s->vol = vv;
    if (!e || !l0 || !rs || !kk || !vv)
        return ss_error_set(err, SS_ERR_NOMEM, "springs: out of memory");
    for (int i = 0; i < count; i++) {
        int a = ab[2 * i], b = ab[2 * i + 1], j = s->nsprings + i;
        s->e[2 * j] = a;
        s->e[2 * j + 1] = b;
        const double *pa = s->X + 3 * a, *pb = s->X + 3 * b;
        s->l0[j] = sqrt((pb[0] - pa[0]) * (pb[0] - pa[0]) + (pb[1] - pa[1]) * (pb[1] - pa[1]) +
                        (pb[2] - pa[2]) * (pb[2] - pa[2]));
        s->rest[j] = rest[i];
        s->k[j] = k[i];
        s->vol[j] = 0;
    }
    s->nsprings = (int)n;
    ss_status st = build_adjacency(s, err);
    if (st == SS_OK) ss_springs_update_mass(s);
    return st;
}

static int cmp_key(const void *a, const void *b) {
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Signed volume of the tet q at positions x. */
static inline double tet_vol(const int32_t *q, const double *x) {
    const double *a = x + 3 * (size_t)q[0], *b = x + 3 * (size_t)q[1], *c = x + 3 * (size_t)q[2],
                 *d = x + 3 * (size_t)q[3];
    double u0 = b[0] - a[0], u1 = b[1] - a[1], u2 = b[2] - a[2];
    double v0 = c[0] - a[0], v1 = c[1] - a[1], v2 = c[2] - a[2];
    double w0 = d[0] - a[0], w1 = d[1] - a[1], w2 = d[2] - a[2];
    return (u0 * (v1 * w2 - v2 * w1) - u1 * (v0 * w2 - v2 * w0) + u2 * (v0 * w1 - v1 * w0)) / 6.0;
}

ss_status ss_springs_set_barrier(ss_springs *s, const ss_tetmesh *m, double kvol, double jmin,
                                 ss_error *err) {
    static const int E6[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    if (!(jmin >= 0 && jmin < 1) || !(kvol >= 0))
        return ss_error_set(err, SS_ERR_INPUT, "springs: bad volume barrier (%g, %g)", kvol, jmin);
    if (!m || m->nnodes != s->nnodes)
        return ss_error_set(err, SS_ERR_INPUT, "springs: barrier mesh does not match");
    s->jmin = jmin;
    s->kvol = kvol;
    if (jmin == 0 || kvol == 0 || s->ntets) return SS_OK;
    const int nt = m->ntets, ns = s->nsprings;
    const int nb = (nt + BLOCK - 1) / BLOCK;
    uint64_t *keys = malloc((size_t)ns * sizeof *keys + 1);
    s->tet = malloc(4 * (size_t)nt * sizeof(int32_t));
    s->tet_edge = malloc(6 * (size_t)nt * sizeof(int32_t));
    s->ntet_start = calloc((size_t)s->nnodes + 1, sizeof(int32_t));
    s->ntet = malloc(4 * (size_t)nt * sizeof(int32_t));
    s->tvol0 = malloc((size_t)nt * sizeof(double));
    s->tvol_rest = malloc((size_t)nt * sizeof(double));
    s->tcoef = calloc((size_t)nt, sizeof(double));
    s->tpart = calloc((size_t)nb + 1, sizeof(double));
    s->tskip = calloc((size_t)nt, 1);
    s->xref = malloc(3 * (size_t)s->nnodes * sizeof(double) + 1);
    s->tdist = malloc((size_t)nt * sizeof(double) + 1);
    s->tnear = malloc((size_t)nt * sizeof(int32_t) + 1);
    s->nsafe = malloc((size_t)s->nnodes * sizeof(double) + 1);
    s->tmark = calloc((size_t)nt + 1, 1);
    s->nflag = calloc((size_t)s->nnodes + 1, 1);
    int32_t *fill = malloc((size_t)s->nnodes * sizeof(int32_t) + 1);
    if (!keys || !s->tet || !s->tet_edge || !s->ntet_start || !s->ntet || !s->tvol0 ||
        !s->tvol_rest || !s->tcoef || !s->tpart || !s->tskip || !s->xref || !s->tdist ||
        !s->tnear || !s->nsafe || !s->tmark || !s->nflag || !fill) {
        free(keys);
        free(fill);
        return ss_error_set(err, SS_ERR_NOMEM, "springs: out of memory");
    }
    /* the springs of the mesh's edges are sorted by (low node, high node) */
    for (int i = 0; i < ns; i++)
        keys[i] = ((uint64_t)(uint32_t)s->e[2 * i] << 32) | (uint32_t)s->e[2 * i + 1];
    memcpy(s->tet, m->tet, 4 * (size_t)nt * sizeof(int32_t));
    for (int t = 0; t < nt; t++) {
        const int32_t *q = m->tet + 4 * t;
        for (int k = 0; k < 6; k++) {
            uint32_t i = (uint32_t)q[E6[k][0]], j = (uint32_t)q[E6[k][1]];
            uint64_t key = i < j ? ((uint64_t)i << 32) | j : ((uint64_t)j << 32) | i;
            const uint64_t *hit = bsearch(&key, keys, (size_t)ns, sizeof *keys, cmp_key);
            if (!hit) {
                free(keys);
                free(fill);
                return ss_error_set(err, SS_ERR_INPUT, "springs: tet %d edge without spring", t);
            }
            s->tet_edge[6 * (size_t)t + k] = (int32_t)(hit - keys);
        }
        s->tvol0[t] = s->tvol_rest[t] = tet_vol(q, s->X);
        for (int k = 0; k < 4; k++) s->ntet_start[q[k] + 1]++;
    }
    free(keys);
    for (int i = 0; i < s->nnodes; i++) s->ntet_start[i + 1] += s->ntet_start[i];
    memcpy(fill, s->ntet_start, (size_t)s->nnodes * sizeof(int32_t));
    for (int t = 0; t < nt; t++)
        for (int k = 0; k < 4; k++) s->ntet[fill[m->tet[4 * t + k]]++] = t;
    free(fill);
    s->ntets = nt;
    ss_springs_barrier_update(s);
    return SS_OK;
}

void ss_springs_barrier_update(ss_springs *s) {
    if (!s->ntets) return;
#pragma omp parallel for schedule(static)
    for (int t = 0; t < s->ntets; t++) {
        double r = 1;
        for (int k = 0; k < 6; k++) {
            int sp = s->tet_edge[6 * (size_t)t + k];
            r *= s->rest[sp] / s->l0[sp];
        }
        s->tvol_rest[t] = s->tvol0[t] * sqrt(r);
        s->tskip[t] = !(s->tvol0[t] > 0) || !(tet_vol(s->tet + 4 * (size_t)t, s->x) > 0);
    }
    s->bar_valid = 0; /* the rest volumes changed: the next force evaluation makes a full pass */
    s->fvalid = 0;
}

/* The barrier b(J) = -(J - jmin)^2 ln(J / jmin) for 0 < J < jmin, and
 * db/dJ; inf for J <= 0. */
static inline double barrier(double J, double jmin, double *db) {
    *db = 0;
    if (J >= jmin) return 0;
    if (!(J > 0)) return INFINITY;
    double d = J - jmin, l = log(J / jmin);
    *db = -2 * d * l - d * d / J;
    return -d * d * l;
}

/* One tet's barrier at x: its energy (dE/dV into tcoef) when J < jmin
 * (*dist = -1); otherwise 0, and *dist = how far every node may move
 * before the tet can reach jmin (when asked for; inf if not): V is
 * multilinear in the edge vectors from node 0, each at most L long and
 * moved by at most 2 d, so |dV| <= ((L + 2 d)^3 - L^3) / 6. */
static inline double tet_barrier(ss_springs *s, const double *x, int t, int want_dist,
                                 double *dist) {
    const int32_t *q = s->tet + 4 * (size_t)t;
    const double jm = s->jmin, vr = s->tvol_rest[t], V = tet_vol(q, x);
    if (V < jm * vr) {
        double db, u = s->kvol * vr * barrier(V / vr, jm, &db);
        s->tcoef[t] = s->kvol * db; /* dE/dV = kv vr b'(J) / vr */
        *dist = -1;
        return u;
    }
    if (s->tcoef[t] != 0) s->tcoef[t] = 0;
    *dist = INFINITY;
    if (want_dist) {
        double L2 = 0;
        for (int a = 0; a < 4; a++)
            for (int c = a + 1; c < 4; c++) {
                const double *pa = x + 3 * (size_t)q[a], *pc = x + 3 * (size_t)q[c];
                double e2 = (pa[0] - pc[0]) * (pa[0] - pc[0]) + (pa[1] - pc[1]) * (pa[1] - pc[1]) +
                            (pa[2] - pc[2]) * (pa[2] - pc[2]);
                if (e2 > L2) L2 = e2;
            }
        /* the d with f(d) = L^2 d + 2 L d^2 + 4/3 d^3 = V - jm vr, from
         * below without a cube root: f(d) / d grows with d, so d =
         * S / (f(d1) / d1) at d1 = S / L^2 >= d gives f(d) <= S */
        double S = V - jm * vr, d1 = S / L2, L = sqrt(L2);
        *dist = S / (L2 + 2 * L * d1 + (4.0 / 3.0) * d1 * d1);
    }
    return 0;
}

/* The radius of the near list: the largest power of two R such that at
 * most cap tets lie nearer jmin than R (those at 0, under it, always do),
 * from a histogram of the distances' binary exponents. */
static double near_radius(const double *dist, int nt, int cap) {
    enum { EMIN = -64, EMAX = 63 };
    int count[EMAX - EMIN + 1] = {0}, zero = 0;
    double dmin = INFINITY;
    for (int t = 0; t < nt; t++) {
        double d = dist[t];
        if (d <= 0) { /* below jmin, or at it */
            zero++;
            continue;
        }
        if (!(d < INFINITY)) continue;
        int e = ilogb(d);
        count[(e < EMIN ? EMIN : e > EMAX ? EMAX : e) - EMIN]++;
        if (d < dmin) dmin = d;
    }
    if (!(dmin < INFINITY)) return INFINITY; /* no tet can reach jmin: the list stays as is */
    double r = dmin;                         /* the zeros alone when one exponent holds too many */
    for (int e = EMIN, n = zero; e <= EMAX; e++) {
        n += count[e - EMIN];
        if (n > cap) break;
        if (count[e - EMIN]) r = ldexp(1.0, e + 1);
    }
    return r;
}

/* Full barrier pass over the tets at x: dE/dV per tet into tcoef, the
 * energy (summed in fixed blocks of tets) returned, inf once a tet folds;
 * *active: the number of tets where it acts (0: no barrier force to
 * gather). It also lists the tets near jmin and gives every node how far
 * it may move before one of its other tets can reach jmin (near_pass). */
static double barrier_pass(ss_springs *s, const double *x, int *active) {
    *active = 0;
    if (!s->ntets || !(s->jmin > 0)) return 0;
    const int nt = s->ntets, nb = (nt + BLOCK - 1) / BLOCK;
    int act = 0;
#pragma omp parallel for schedule(static) reduction(+ : act)
    for (int b = 0; b < nb; b++) {
        double u = 0;
        int hi = (b + 1) * BLOCK < nt ? (b + 1) * BLOCK : nt;
        for (int t = b * BLOCK; t < hi; t++) {
            if (s->tskip[t]) {
                s->tcoef[t] = 0;
                s->tdist[t] = INFINITY;
                continue;
            }
            double ut = tet_barrier(s, x, t, 1, s->tdist + t);
            if (s->tdist[t] < 0) {
                u += ut;
                act++;
            }
        }
        s->tpart[b] = u;
    }
    *active = act;
    double r = near_radius(s->tdist, nt, nt / 32 > 64 ? nt / 32 : 64);
    s->nnear = 0;
    for (int t = 0; t < nt; t++) {
        s->tmark[t] = s->tdist[t] < r;
        if (s->tmark[t]) s->tnear[s->nnear++] = t;
    }
#pragma omp parallel for schedule(static)
    for (int i = 0; i < s->nnodes; i++) {
        double m = INFINITY;
        for (int a = s->ntet_start[i]; a < s->ntet_start[i + 1]; a++) {
            int t = s->ntet[a];
            if (!s->tmark[t] && s->tdist[t] < m) m = s->tdist[t];
        }
        s->nsafe[i] = 0.99 * m; /* (a margin for the rounding of the distances) */
    }
    memcpy(s->xref, x, 3 * (size_t)s->nnodes * sizeof(double));
    s->bar_valid = 1;
    s->bar_passes[0]++;
    double u = 0;
    for (int b = 0; b < nb; b++) u += s->tpart[b];
    return u;
}

/* The barrier pass over the near list and the tets of the nflagged nodes
 * that have moved nsafe from the last full pass: any other tet has all four
 * nodes closer than its distance to jmin, so its term is zero (exact). A
 * flagged tet found below jmin joins the near list. The blocks sum in the
 * order of the full pass: the same bits. */
static double near_pass(ss_springs *s, const double *x, int nflagged, int *active) {
    const int nb = (s->ntets + BLOCK - 1) / BLOCK;
    int act = 0;
    s->bar_passes[1]++;
    memset(s->tpart, 0, (size_t)nb * sizeof(double));
    if (!nflagged) {
        for (int i = 0; i < s->nnear; i++) {
            int t = s->tnear[i];
            double dist, ut = tet_barrier(s, x, t, 0, &dist);
            if (dist < 0) {
                s->tpart[t / BLOCK] += ut;
                act++;
            }
        }
    } else {
        for (int i = 0; i < s->nnodes; i++)
            if (s->nflag[i])
                for (int a = s->ntet_start[i]; a < s->ntet_start[i + 1]; a++) {
                    int t = s->ntet[a];
                    if (!s->tmark[t] && !s->tskip[t]) s->tmark[t] = 2;
                }
        s->nnear = 0;
        for (int t = 0; t < s->ntets; t++) {
            if (!s->tmark[t]) continue;
            double dist, ut = tet_barrier(s, x, t, 0, &dist);
            if (dist < 0) {
                s->tpart[t / BLOCK] += ut;
                act++;
                s->tmark[t] = 1; /* stays evaluated: its tcoef is set */
            } else if (s->tmark[t] == 2) {
                s->tmark[t] = 0; /* (tet_barrier zeroed its tcoef) */
            }
            if (s->tmark[t]) s->tnear[s->nnear++] = t;
        }
    }
    *active = act;
    double u = 0;
    for (int b = 0; b < nb; b++) u += s->tpart[b];
    return u;
}

/* The barrier's energy at x, with dE/dV of every tet below jmin in tcoef:
 * the full pass when none is valid or many nodes have moved off their safe
 * distance, else the near pass. */
static double barrier_at(ss_springs *s, const double *x, int *active) {
    const int n = s->nnodes;
    if (!s->bar_valid || s->bar_full_always) return barrier_pass(s, x, active);
    int nflagged = 0;
#pragma omp parallel for schedule(static) reduction(+ : nflagged)
    for (int i = 0; i < n; i++) {
        const double *a = x + 3 * (size_t)i, *r = s->xref + 3 * (size_t)i;
        double d2 = (a[0] - r[0]) * (a[0] - r[0]) + (a[1] - r[1]) * (a[1] - r[1]) +
                    (a[2] - r[2]) * (a[2] - r[2]);
        s->nflag[i] = !(d2 < s->nsafe[i] * s->nsafe[i]);
        nflagged += s->nflag[i];
    }
    if (nflagged > n / 16) return barrier_pass(s, x, active);
    return near_pass(s, x, nflagged, active);
}

/* Adds the barrier force -dE/dV dV/dx_i of node i's active tets to f. */
static inline void barrier_force(const ss_springs *s, const double *x, int i, double f[3]) {
    for (int a = s->ntet_start[i]; a < s->ntet_start[i + 1]; a++) {
        int t = s->ntet[a];
        double c = s->tcoef[t];
        if (c == 0) continue;
        const int32_t *q = s->tet + 4 * (size_t)t;
        int k = q[0] == i ? 0 : q[1] == i ? 1 : q[2] == i ? 2 : 3;
        /* V = (x1 - x0) . ((x2 - x0) x (x3 - x0)) / 6 is linear in each node:
         * dV/dx_k = (x_b - x_a) x (x_c - x_a) / 6 over the opposite face
         * (a, b, c) taken so that the tet (k, a, b, c) is positive */
        static const int opp[4][3] = {{1, 3, 2}, {0, 2, 3}, {0, 3, 1}, {0, 1, 2}};
        const double *pa = x + 3 * (size_t)q[opp[k][0]], *pb = x + 3 * (size_t)q[opp[k][1]],
                     *pc = x + 3 * (size_t)q[opp[k][2]];
        double u0 = pb[0] - pa[0], u1 = pb[1] - pa[1], u2 = pb[2] - pa[2];
        double v0 = pc[0] - pa[0], v1 = pc[1] - pa[1], v2 = pc[2] - pa[2];
        f[0] -= c * (u1 * v2 - u2 * v1) / 6.0;
        f[1] -= c * (u2 * v0 - u0 * v2) / 6.0;
        f[2] -= c * (u0 * v1 - u1 * v0) / 6.0;
    }
}

/* Force on node i at positions x (gathered over its springs, in spring
 * order); returns the node's share of the energy (half of each spring's,
 * all of its anchor's). */
static inline double node_force(const ss_springs *s, const double *x, int i, double f[3]) {
    const double *xi = x + 3 * (size_t)i;
    double ax = s->X[3 * i] - xi[0], ay = s->X[3 * i + 1] - xi[1], az = s->X[3 * i + 2] - xi[2];
    double fx = s->anchor[i] * ax, fy = s->anchor[i] * ay, fz = s->anchor[i] * az;
    double u = 0.5 * s->anchor[i] * (ax * ax + ay * ay + az * az);
    for (int a = s->adj_start[i]; a < s->adj_start[i + 1]; a++) {
        int sp = s->adj[a];
        int j = s->e[2 * sp] == i ? s->e[2 * sp + 1] : s->e[2 * sp];
        const double *xj = x + 3 * (size_t)j;
        double d0 = xj[0] - xi[0], d1 = xj[1] - xi[1], d2 = xj[2] - xi[2];
        double l = sqrt(d0 * d0 + d1 * d1 + d2 * d2);
        double dl = l - s->rest[sp];
        u += 0.25 * s->k[sp] * dl * dl;
        if (l <= 0) continue;
        double c = s->k[sp] * dl / l;
        fx += c * d0;
        fy += c * d1;
        fz += c * d2;
    }
    f[0] = fx;
    f[1] = fy;
    f[2] = fz;
    return u;
}

/* Sums in fixed blocks of nodes, then the blocks in order: the same bits on
 * any thread count, with the work spread over the threads. */
static double block_sum(const double *partial, int nb) {
    double t = 0;
    for (int b = 0; b < nb; b++) t += partial[b];
    return t;
}

/* Forces at x into f (3n) and the potential energy. */
static double forces_at(ss_springs *s, const double *x, double *f, double *partial) {
    const int n = s->nnodes, nb = (n + BLOCK - 1) / BLOCK;
    int bar = 0;
    double ub = 0;
    if (s->ntets && s->jmin > 0) {
        ub = barrier_at(s, x, &bar);
        if (!(ub < INFINITY)) return INFINITY; /* a tet folds: never accepted */
    }
#pragma omp parallel for schedule(static)
    for (int b = 0; b < nb; b++) {
        double u = 0;
        int hi = (b + 1) * BLOCK < n ? (b + 1) * BLOCK : n;
        for (int i = b * BLOCK; i < hi; i++) {
            u += node_force(s, x, i, f + 3 * (size_t)i);
            if (bar) barrier_force(s, x, i, f + 3 * (size_t)i);
        }
        partial[b] = u;
    }
    return block_sum(partial, nb) + ub;
}

double ss_springs_forces(ss_springs *s, double *f) {
    int bar;
    barrier_pass(s, s->x, &bar);
#pragma omp parallel for schedule(static)
    for (int i = 0; i < s->nnodes; i++) {
        node_force(s, s->x, i, f + 3 * (size_t)i);
        if (bar) barrier_force(s, s->x, i, f + 3 * (size_t)i);
    }
    return ss_springs_energy(s);
}

double ss_springs_energy(const ss_springs *s) {
    double u = 0;
    for (int i = 0; i < s->nsprings; i++) {
        const double *a = s->x + 3 * s->e[2 * i], *b = s->x + 3 * s->e[2 * i + 1];
        double l = sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                        (b[2] - a[2]) * (b[2] - a[2]));
        u += 0.5 * s->k[i] * (l - s->rest[i]) * (l - s->rest[i]);
    }
    for (int i = 0; i < s->nnodes; i++) {
        if (s->anchor[i] <= 0) continue;
        double d2 = 0;
        for (int d = 0; d < 3; d++)
            d2 += (s->x[3 * i + d] - s->X[3 * i + d]) * (s->x[3 * i + d] - s->X[3 * i + d]);
        u += 0.5 * s->anchor[i] * d2;
    }
    for (int t = 0; t < (s->jmin > 0 ? s->ntets : 0); t++) {
        double vr = s->tvol_rest[t], db;
        if (!s->tskip[t])
            u += s->kvol * vr * barrier(tet_vol(s->tet + 4 * (size_t)t, s->x) / vr, s->jmin, &db);
    }
    return u;
}

double ss_springs_kinetic(const ss_springs *s) {
    double k = 0;
    for (int i = 0; i < s->nnodes; i++)
        k += 0.5 * s->mass[i] *
             (s->v[3 * i] * s->v[3 * i] + s->v[3 * i + 1] * s->v[3 * i + 1] +
              s->v[3 * i + 2] * s->v[3 * i + 2]);
    return k;
}

static double mean_rest(ss_springs *s) {
    if (s->mean_l0 <= 0) {
        double m = 0;
        for (int i = 0; i < s->nsprings; i++) m += s->l0[i];
        s->mean_l0 = s->nsprings ? m / s->nsprings : 1.0;
    }
    return s->mean_l0;
}

/* Largest move a pure gradient step would make: max_i |f_i| / m_i (a max:
 * the same on any thread count). */
static double residual(const ss_springs *s, const double *f) {
    double r = 0;
#pragma omp parallel for schedule(static) reduction(max : r)
    for (int i = 0; i < s->nnodes; i++) {
        if (s->fixed[i]) continue;
        double f2 = f[3 * i] * f[3 * i] + f[3 * i + 1] * f[3 * i + 1] + f[3 * i + 2] * f[3 * i + 2];
        double q = sqrt(f2) / s->mass[i];
        if (q > r) r = q;
    }
    return r;
}

static double kinetic(const ss_springs *s, const double *v, double *partial) {
    const int n = s->nnodes, nb = (n + BLOCK - 1) / BLOCK;
#pragma omp parallel for schedule(static)
    for (int b = 0; b < nb; b++) {
        double k = 0;
        int hi = (b + 1) * BLOCK < n ? (b + 1) * BLOCK : n;
        for (int i = b * BLOCK; i < hi; i++)
            k += 0.5 * s->mass[i] *
                 (v[3 * i] * v[3 * i] + v[3 * i + 1] * v[3 * i + 1] + v[3 * i + 2] * v[3 * i + 2]);
        partial[b] = k;
    }
    return block_sum(partial, nb);
}

double ss_springs_substep(ss_springs *s) {
    const int n = s->nnodes, nb = (n + BLOCK - 1) / BLOCK;
    double *part = s->unode; /* nb <= n partial sums */
    if (!s->fvalid) {
        s->U = forces_at(s, s->x, s->f, part);
        s->fvalid = 1;
    }
    const double E0 = s->U + kinetic(s, s->v, part);
    const double gam = s->damping;
    /* proposal: damped semi-implicit Euler, momentum dropped when going uphill */
#pragma omp parallel for schedule(static)
    for (int b = 0; b < nb; b++) {
        double pw = 0;
        int hi = (b + 1) * BLOCK < n ? (b + 1) * BLOCK : n;
        for (int i = b * BLOCK; i < hi; i++) {
            double *v = s->v + 3 * (size_t)i;
            if (s->fixed[i]) {
                v[0] = v[1] = v[2] = 0;
                continue;
            }
            double im = 1.0 / s->mass[i];
            for (int d = 0; d < 3; d++) {
                v[d] = gam * v[d] + s->f[3 * (size_t)i + d] * im;
                pw += s->f[3 * (size_t)i + d] * v[d];
            }
        }
        part[b] = pw;
    }
    const int uphill = block_sum(part, nb) < 0;
#pragma omp parallel for schedule(static)
    for (int i = 0; i < n; i++) {
        for (int d = 0; d < 3; d++) {
            size_t k = 3 * (size_t)i + d;
            if (uphill && !s->fixed[i]) s->v[k] = s->f[k] / s->mass[i];
            s->x2[k] = s->x[k] + s->v[k];
        }
    }
    double U1 = forces_at(s, s->x2, s->f2, part);
    if (U1 + kinetic(s, s->v, part) > E0) {
        /* reject: drop the momentum, gradient steps halved until downhill */
        memset(s->v, 0, 3 * (size_t)n * sizeof(double));
        double a = 1.0;
        for (int tries = 0; tries < 30; tries++, a *= 0.5) {
#pragma omp parallel for schedule(static)
            for (int i = 0; i < n; i++)
                for (int d = 0; d < 3; d++) {
                    size_t k = 3 * (size_t)i + d;
                    s->x2[k] = s->x[k] + (s->fixed[i] ? 0 : a * s->f[k] / s->mass[i]);
                }
            U1 = forces_at(s, s->x2, s->f2, part);
            if (U1 <= s->U) break;
        }
        if (U1 > s->U) /* no descent at all (rounding level): stay */
            return residual(s, s->f) / mean_rest(s);
    }
    double *t = s->x;
    s->x = s->x2;
    s->x2 = t;
    t = s->f;
    s->f = s->f2;
    s->f2 = t;
    s->U = U1;
    return residual(s, s->f) / mean_rest(s);
}

int ss_springs_relax(ss_springs *s, double tol, int max_steps, int *converged) {
    int it = 0, ok = 0;
    ss_springs_barrier_update(s);
    s->fvalid = 0;
    while (it < max_steps) {
        double d = ss_springs_substep(s);
        it++;
        if (it >= 2 && d < tol) {
            ok = 1;
            break;
        }
    }
    if (converged) *converged = ok;
    return it;
}
