/* The contraction mechanics coupled to the healing grid (seed 001 §5.1-5.3).
 *
 * One frame (ss_mech_step), after the biochemistry has advanced the grid:
 *  1. sample at every spring node, with the B-spline weights, the
 *     myofibroblast density: the mean fibroblast density of a column's
 *     wound-region cells (initial wound or omega: the granulation tissue the
 *     fibroblasts invade), weighted by 1 - epithelium at the column's top,
 *     through the column's whole thickness (the wound bed's activated dermis
 *     pulls with it). It starts at zero (the clot has no fibroblasts) and
 *     rises as they invade, so contraction sets in after a few days as
 *     observed clinically. Fibroblasts in open
 *     granulation tissue differentiate into myofibroblasts and these go by
 *     apoptosis once the wound is covered (Desmouliere et al. 1995, Am J
 *     Pathol 146:56); intact skin exerts no net pull. Then the volumetric
 *     strain theta (from the last frame) and
 *     rho_ecm / rho_ecm_hat (1 in intact tissue; in the initial wound the
 *     clot's ecm_floor plus the deposited collagen, the scar field rho,
 *     capped at 1);
 *  2. per spring: sigma = p_cell(theta) n K_m, its GOH energy weighted by
 *     the spring's direction against the fibres, the new rest length
 *     l0 (1 - Delta l / l0) (material.c); stiffness k_hat rho_ecm / rho_ecm_hat,
 *     the seed's linear dependence of the energy on the tissue density;
 *  3. relax with damped sub-steps to the convergence criterion (springs.c);
 *  4. particle velocities (moved distance / frame time, mm/day) and
 *     displacements go to the grid with the B-spline transfer (bspline.c);
 *     the velocity is the grid's convection velocity for the next heal step,
 *     the displacement's divergence is theta for the next frame.
 * Boundary: the top surface is free; the bottom and side faces sit on an
 * elastic foundation (anchor, kPa/mm per face area): the subcutis below and
 * the skin beyond the block, which give way but pull back. Rest lengths
 * never lengthen: new collagen is laid down in the contracted state and
 * locks it (the permanent strain of morphoelastic wound models, e.g. Hall
 * 2008 / Menon et al. 2017), so a scar stays contracted after the
 * myofibroblasts are gone; theta's feedback through p_cell (zero pressure
 * at theta1) ends the contraction. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mech_internal.h"

static void displacement_to_grid(ss_mech *m);

static int tissue(uint8_t c) {
    return c == SS_CELL_EPIDERMIS || c == SS_CELL_DERMIS || c == SS_CELL_WOUND;
}

void ss_mech_free(ss_mech *m) {
    if (!m) return;
    ss_tetmesh_free(m->mesh);
    ss_springs_free(m->S);
    ss_hyper_free(m->H);
    ss_mech_transfer_free(m->T);
    free(m->mask);
    free(m->wound0);
    free(m->side);
    free(m->foot);
    free(m->ecm);
    free(m->myo);
    free(m->gf);
    free(m->cov);
    free(m->rhoc);
    free(m->nrho);
    for (int d = 0; d < 3; d++) free(m->usub[d]);
    free(m->thsub);
    free(m->usub_valid);
    for (int d = 0; d < 3; d++) free(m->u[d]);
    free(m->kbase);
    free(m->rest_old);
    free(m->k_old);
    free(m->nmyo);
    free(m->nmf);
    free(m->nproto);
    free(m->nact);
    free(m->ngf);
    free(m->ncov);
    free(m->nth);
    free(m->necm);
    free(m->stress);
    free(m->vel);
    free(m->xprev);
    free(m->grad);
    free(m->disp);
    free(m->tri);
    free(m->tri_wound);
    free(m->suture_spring);
    free(m->suture_day);
    free(m);
}

typedef struct face {
    uint64_t key;
    int32_t tet, local;
} face;

static int cmp_face(const void *a, const void *b) {
    uint64_t x = ((const face *)a)->key, y = ((const face *)b)->key;
    return x < y ? -1 : x > y;
}

/* Boundary faces, by the grid cell just outside them: air above (outward
 * normal z > 0.5) makes the top surface triangles, other faces on air (the
 * risers of a stepped surface on a curved patch) are free too; faces on the
 * lateral sides of the mesh's box carry the far field (anchor_side), the
 * rest (bottom, inner bound of a shell) the subcutis (anchor). */
static ss_status boundary(ss_mech *m, const ss_heal_grid *g, ss_error *err) {
    const ss_tetmesh *M = m->mesh;
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int i = 0; i < M->nnodes; i++)
        for (int d = 0; d < 2; d++) {
            lo[d] = fmin(lo[d], M->x[3 * i + d]);
            hi[d] = fmax(hi[d], M->x[3 * i + d]);
        }
    const double eps = 1e-6 * (1 + fmax(hi[0] - lo[0], hi[1] - lo[1]));
    if (M->nnodes >= (1 << 21))
        return ss_error_set(err, SS_ERR_INPUT, "mechanics: %d nodes is more than 2^21", M->nnodes);
    static const int F[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}; /* outward */
    size_t nf = 4 * (size_t)M->ntets;
    face *fs = malloc(nf * sizeof *fs);
    if (!fs) return ss_error_set(err, SS_ERR_NOMEM, "mechanics: out of memory");
    for (int t = 0; t < M->ntets; t++)
        for (int k = 0; k < 4; k++) {
            int32_t a = M->tet[4 * t + F[k][0]], b = M->tet[4 * t + F[k][1]],
                    c = M->tet[4 * t + F[k][2]], tmp;
            if (a > b) tmp = a, a = b, b = tmp;
            if (b > c) tmp = b, b = c, c = tmp;
            if (a > b) tmp = a, a = b, b = tmp;
            fs[4 * (size_t)t + k] =
                (face){((uint64_t)a << 42) | ((uint64_t)b << 21) | (uint64_t)c, t, k};
        }
    qsort(fs, nf, sizeof *fs, cmp_face);
    int cap = 1024;
    m->tri = malloc(3 * (size_t)cap * sizeof(int32_t));
    if (!m->tri) {
        free(fs);
        return ss_error_set(err, SS_ERR_NOMEM, "mechanics: out of memory");
    }
    for (size_t i = 0; i < nf; i++) {
        int dup =
            (i > 0 && fs[i].key == fs[i - 1].key) || (i + 1 < nf && fs[i].key == fs[i + 1].key);
        if (dup) continue;
        const int32_t *q = M->tet + 4 * fs[i].tet;
        int32_t v[3] = {q[F[fs[i].local][0]], q[F[fs[i].local][1]], q[F[fs[i].local][2]]};
        const double *a = M->x + 3 * v[0], *b = M->x + 3 * v[1], *c = M->x + 3 * v[2];
        double u[3], w[3], n[3];
        for (int d = 0; d < 3; d++) {
            u[d] = b[d] - a[d];
            w[d] = c[d] - a[d];
        }
        n[0] = u[1] * w[2] - u[2] * w[1];
        n[1] = u[2] * w[0] - u[0] * w[2];
        n[2] = u[0] * w[1] - u[1] * w[0];
        double area2 = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(area2 > 0)) continue;
        /* the cell just outside the face */
        double qo[3];
        for (int d = 0; d < 3; d++)
            qo[d] = (a[d] + b[d] + c[d]) / 3 + 0.75 * g->dx_mm * n[d] / area2;
        int ci = (int)floor(qo[0] / g->dx_mm), cj = (int)floor(qo[1] / g->dx_mm),
            ck = (int)floor(qo[2] / g->dx_mm);
        int out = ci < 0 || cj < 0 || ck < 0 || ci >= g->nx || cj >= g->ny || ck >= g->nz;
        uint8_t cell = out ? SS_CELL_BOUND : g->cell[ss_heal_idx(g, ci, cj, ck)];
        int on_air = cell == SS_CELL_AIR;
        int lateral = 0;
        for (int d = 0; d < 2; d++) {
            int all_lo = 1, all_hi = 1;
            for (int k = 0; k < 3; k++) {
                double x = M->x[3 * v[k] + d];
                all_lo &= fabs(x - lo[d]) < eps;
                all_hi &= fabs(x - hi[d]) < eps;
            }
            lateral |= all_lo || all_hi;
        }
        if (!on_air && !lateral && n[2] / area2 > 0.5 && tissue(cell))
            on_air = 1;                              /* coarse lattice */
        if (on_air && n[2] / area2 <= 0.5) continue; /* a free riser */
        if (on_air) {
            if (m->ntri == cap) {
                cap *= 2;
                int32_t *nt = realloc(m->tri, 3 * (size_t)cap * sizeof(int32_t));
                if (!nt) {
                    free(fs);
                    return ss_error_set(err, SS_ERR_NOMEM, "mechanics: out of memory");
                }
                m->tri = nt;
            }
            memcpy(m->tri + 3 * (size_t)m->ntri++, v, sizeof v);
        } else {
            int side = lateral;
            double an = side ? m->p.anchor_side : m->p.anchor;
            for (int k = 0; k < 3; k++) {
                m->S->anchor[v[k]] += an * 0.5 * area2 / 3.0;
                if (side) m->side[v[k]] = 1;
            }
        }
    }
    free(fs);
    return SS_OK;
}

/* Mesh nodes bucketed in a uniform grid of cells of side h (>= the search
 * radius), so finding the nodes near a suture point looks at 27 cells, not
 * every node: n sutures cost O(n + nodes), not O(n * nodes). The cell
 * count is kept within 8 nodes' worth (h grows on a sparse mesh). */
typedef struct node_grid {
    double lo[3], h;
    int n[3];
    int *start, *node; /* node[start[c] .. start[c+1]) lie in cell c */
} node_grid;

static void node_grid_free(node_grid *q) {
    free(q->start);
    free(q->node);
}

static int node_cell(const node_grid *q, const double *x, int d) {
    long c = (long)floor((x[d] - q->lo[d]) / q->h);
    return (int)(c < 0 ? 0 : c >= q->n[d] ? q->n[d] - 1 : c);
}

static ss_status node_grid_build(node_grid *q, const ss_tetmesh *mesh, double h) {
    memset(q, 0, sizeof *q);
    double hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int d = 0; d < 3; d++) q->lo[d] = INFINITY;
    for (int i = 0; i < mesh->nnodes; i++)
        for (int d = 0; d < 3; d++) {
            double v = mesh->x[3 * (size_t)i + d];
            q->lo[d] = v < q->lo[d] ? v : q->lo[d];
            hi[d] = v > hi[d] ? v : hi[d];
        }
    if (!(h > 0)) h = 1;
    for (;;) {
        double cells = 1;
        for (int d = 0; d < 3; d++) {
            double nd = mesh->nnodes ? floor((hi[d] - q->lo[d]) / h) + 1 : 1;
            q->n[d] = (int)nd;
            cells *= nd;
        }
        if (cells <= 8.0 * mesh->nnodes + 64) break;
        h *= 2;
    }
    q->h = h;
    size_t nc = (size_t)q->n[0] * q->n[1] * q->n[2];
    q->start = calloc(nc + 1, sizeof(int));
    q->node = malloc(((size_t)mesh->nnodes + 1) * sizeof(int));
    if (!q->start || !q->node) return SS_ERR_NOMEM;
    int *cell = malloc(((size_t)mesh->nnodes + 1) * sizeof(int));
    if (!cell) return SS_ERR_NOMEM;
    for (int i = 0; i < mesh->nnodes; i++) {
        const double *x = mesh->x + 3 * (size_t)i;
        cell[i] =
            (node_cell(q, x, 2) * q->n[1] + node_cell(q, x, 1)) * q->n[0] + node_cell(q, x, 0);
        q->start[cell[i] + 1]++;
    }
    for (size_t c = 0; c < nc; c++) q->start[c + 1] += q->start[c];
    int *fill = malloc((nc + 1) * sizeof(int));
    if (!fill) {
        free(cell);
        return SS_ERR_NOMEM;
    }
    memcpy(fill, q->start, (nc + 1) * sizeof(int));
    for (int i = 0; i < mesh->nnodes; i++) q->node[fill[cell[i]]++] = i; /* ascending per cell */
    free(fill);
    free(cell);
    return SS_OK;
}

static int cmp_int(const void *a, const void *b) {
    int x = *(const int *)a, y = *(const int *)b;
    return (x > y) - (x < y);
}

/* The nodes within r (<= q->h) of p, ascending, in *out (malloc'd); with
 * *nearest the closest of them (lowest index on a tie, as a scan would
 * give) or -1 when none is within r. */
static ss_status near_nodes(const ss_mech *m, const node_grid *q, const double p[3], double r,
                            int **out, int *n, int *nearest, double *dist) {
    int c[3], cap = 16, k = 0, best = -1;
    double bd = INFINITY;
    int *v = malloc((size_t)cap * sizeof(int));
    if (!v) return SS_ERR_NOMEM;
    for (int d = 0; d < 3; d++) c[d] = node_cell(q, p, d);
    for (int z = c[2] - 1; z <= c[2] + 1; z++)
        for (int y = c[1] - 1; y <= c[1] + 1; y++)
            for (int x = c[0] - 1; x <= c[0] + 1; x++) {
                if (x < 0 || y < 0 || z < 0 || x >= q->n[0] || y >= q->n[1] || z >= q->n[2])
                    continue;
                size_t cc = ((size_t)z * q->n[1] + y) * q->n[0] + x;
                for (int j = q->start[cc]; j < q->start[cc + 1]; j++) {
                    int i = q->node[j];
                    const double *xi = m->mesh->x + 3 * (size_t)i;
                    double d = (xi[0] - p[0]) * (xi[0] - p[0]) + (xi[1] - p[1]) * (xi[1] - p[1]) +
                               (xi[2] - p[2]) * (xi[2] - p[2]);
                    if (d > r * r) continue;
                    if (d < bd || (d == bd && i < best)) bd = d, best = i;
                    if (k == cap) {
                        cap *= 2;
                        int *w = realloc(v, (size_t)cap * sizeof(int));
                        if (!w) {
                            free(v);
                            return SS_ERR_NOMEM;
                        }
                        v = w;
                    }
                    v[k++] = i;
                }
            }
    qsort(v, (size_t)k, sizeof(int), cmp_int);
    *out = v;
    *n = k;
    *nearest = best;
    *dist = sqrt(bd);
    return SS_OK;
}

/* The bite: the nearest node first, then the others within r ascending. */
static void bite_order(int *v, int n, int near) {
    int at = 0;
    while (at < n && v[at] != near) at++;
    for (; at > 0; at--) v[at] = v[at - 1];
    if (n) v[0] = near;
}

ss_mech *ss_mech_create(ss_heal_grid *g, const ss_heal_params *heal, const ss_mech_params *p,
                        const ss_tetmesh *mesh, const ss_mech_suture *sut, int nsut,
                        ss_error *err) {
    if (!g || !heal || !p) {
        ss_error_set(err, SS_ERR_INPUT, "mechanics: no grid or parameters");
        return NULL;
    }
    if (ss_mech_params_check(p, err) != SS_OK) return NULL;
    const size_t n = (size_t)g->nx * g->ny * g->nz;
    ss_mech *m = calloc(1, sizeof *m);
    if (!m) goto nomem;
    m->p = *p;
    m->nx = g->nx;
    m->ny = g->ny;
    m->nz = g->nz;
    m->dx = g->dx_mm;
    float hv[SS_HEAL_NFIELDS];
    ss_heal_params_healthy(heal, hv);
    m->n_healthy = hv[SS_HEAL_FIBROBLAST];
    m->mask = malloc(n);
    m->wound0 = malloc(n);
    m->ecm = calloc(n, sizeof(float));
    m->myo = calloc(n, sizeof(float));
    m->gf = calloc(n, sizeof(float));
    m->cov = calloc(n, sizeof(float));
    m->rhoc = calloc(n, sizeof(float));
    if (!m->mask || !m->wound0 || !m->ecm || !m->myo || !m->gf || !m->cov || !m->rhoc) goto nomem;
    size_t ncells = 0;
    for (size_t i = 0; i < n; i++) {
        m->mask[i] = tissue(g->cell[i]);
        m->wound0[i] = g->cell[i] == SS_CELL_WOUND;
        ncells += m->mask[i];
    }
    for (int d = 0; d < 3; d++) {
        if (!g->velocity[d] && !(g->velocity[d] = calloc(n, sizeof(float)))) goto nomem;
    }
    if (mesh) {
        m->mesh = calloc(1, sizeof *m->mesh);
        if (!m->mesh) goto nomem;
        m->mesh->nnodes = mesh->nnodes;
        m->mesh->ntets = mesh->ntets;
        m->mesh->x = malloc(3 * (size_t)mesh->nnodes * sizeof(double));
        m->mesh->tet = malloc(4 * (size_t)mesh->ntets * sizeof(int32_t));
        if (!m->mesh->x || !m->mesh->tet) goto nomem;
        memcpy(m->mesh->x, mesh->x, 3 * (size_t)mesh->nnodes * sizeof(double));
        memcpy(m->mesh->tet, mesh->tet, 4 * (size_t)mesh->ntets * sizeof(int32_t));
        for (int i = 0; i < mesh->nnodes; i++) {
            const double *x = mesh->x + 3 * i;
            if (!(x[0] >= 0 && x[1] >= 0 && x[2] >= 0 && x[0] <= g->nx * g->dx_mm &&
                  x[1] <= g->ny * g->dx_mm && x[2] <= g->nz * g->dx_mm)) {
                ss_error_set(err, SS_ERR_INPUT,
                             "mechanics: mesh node %d (%g, %g, %g) mm lies outside the grid", i + 1,
                             x[0], x[1], x[2]);
                goto fail;
            }
        }
    } else if (!(m->mesh = ss_tetmesh_lattice(m->mask, g->nx, g->ny, g->nz, g->dx_mm,
                                              p->tet_size_mm, err)))
        goto fail;
    if (!(m->S = ss_springs_create(m->mesh, 9.0 * p->K_bulk, err))) goto fail;
    if (ss_springs_set_barrier(m->S, m->mesh, p->K_bulk, p->j_min, err) != SS_OK) goto fail;
    const int nn = m->mesh->nnodes, ns = m->S->nsprings;
    if (!(m->side = calloc((size_t)nn, 1))) goto nomem;
    if (boundary(m, g, err) != SS_OK) goto fail;
    /* sutures: each end holds the tissue of its bite (the nodes within 1.5
     * tet edges of the point, at least the nearest), and every node pair
     * across the stitch gets a share of its stiffness with the rest length
     * that pulls the two points together; a point load on a single node
     * folds the tets around it */
    m->ntissue = m->S->nsprings;
    if (nsut > 0) {
        m->suture_spring = malloc(((size_t)nsut + 1) * sizeof(int));
        m->suture_day = malloc((size_t)nsut * sizeof(double));
        if (!m->suture_spring || !m->suture_day) goto nomem;
        double reach = 1.5 * p->tet_size_mm, bite = 1.5 * p->tet_size_mm;
        node_grid q;
        if (node_grid_build(&q, m->mesh, reach > bite ? reach : bite) != SS_OK) {
            node_grid_free(&q);
            goto nomem;
        }
        /* every suture's springs gathered, then added in one batch */
        size_t nadd = 0, capadd = 0;
        int32_t *ab = NULL;
        double *rest_add = NULL, *k_add = NULL;
        ss_status st = SS_OK;
        for (int i = 0; i < nsut && !st; i++) {
            double da, db;
            int a, b, *A = NULL, *B = NULL, na = 0, nb = 0;
            if (near_nodes(m, &q, sut[i].a, bite, &A, &na, &a, &da) != SS_OK ||
                near_nodes(m, &q, sut[i].b, bite, &B, &nb, &b, &db) != SS_OK) {
                free(A);
                free(B);
                st = ss_error_set(err, SS_ERR_NOMEM, "sutures: out of memory");
                break;
            }
            if (a < 0 || b < 0 || da > reach || db > reach || a == b) {
                free(A);
                free(B);
                st = ss_error_set(
                    err, SS_ERR_INPUT, "sutures: stitch %d (%g,%g,%g)-(%g,%g,%g) mm %s", i + 1,
                    sut[i].a[0], sut[i].a[1], sut[i].a[2], sut[i].b[0], sut[i].b[1], sut[i].b[2],
                    a >= 0 && a == b ? "joins a node to itself"
                                     : "has a point outside the skin domain");
                break;
            }
            bite_order(A, na, a);
            bite_order(B, nb, b);
            double gap = 0;
            for (int d = 0; d < 3; d++)
                gap += (sut[i].b[d] - sut[i].a[d]) * (sut[i].b[d] - sut[i].a[d]);
            gap = sqrt(gap);
            m->suture_spring[i] = m->S->nsprings + (int)nadd;
            for (int u = 0; u < na && !st; u++)
                for (int v = 0; v < nb && !st; v++) {
                    if (A[u] == B[v]) continue;
                    if (nadd == capadd) {
                        capadd = capadd ? 2 * capadd : 1024;
                        int32_t *nab = realloc(ab, 2 * capadd * sizeof *ab);
                        if (nab) ab = nab;
                        double *nr = realloc(rest_add, capadd * sizeof *nr);
                        if (nr) rest_add = nr;
                        double *nk = realloc(k_add, capadd * sizeof *nk);
                        if (nk) k_add = nk;
                        if (!nab || !nr || !nk) {
                            st = ss_error_set(err, SS_ERR_NOMEM, "sutures: out of memory");
                            break;
                        }
                    }
                    const double *xa = m->mesh->x + 3 * A[u], *xb = m->mesh->x + 3 * B[v];
                    double l =
                        sqrt((xb[0] - xa[0]) * (xb[0] - xa[0]) + (xb[1] - xa[1]) * (xb[1] - xa[1]) +
                             (xb[2] - xa[2]) * (xb[2] - xa[2]));
                    ab[2 * nadd] = A[u];
                    ab[2 * nadd + 1] = B[v];
                    rest_add[nadd] = l - gap > 0 ? l - gap : 0.0;
                    k_add[nadd] = p->k_suture / (na * nb);
                    nadd++;
                }
            free(A);
            free(B);
            m->suture_day[i] = sut[i].remove_day;
        }
        node_grid_free(&q);
        if (!st && nadd > (size_t)INT32_MAX)
            st = ss_error_set(err, SS_ERR_INPUT, "sutures: too many springs");
        if (!st) st = ss_springs_add_many(m->S, (int)nadd, ab, rest_add, k_add, err);
        free(ab);
        free(rest_add);
        free(k_add);
        if (st) goto fail;
        m->suture_spring[nsut] = m->S->nsprings;
        m->nsutures = nsut;
    }
    const int nsp = m->S->nsprings;
    (void)ns;
    m->kbase = malloc((size_t)nsp * sizeof(double));
    m->rest_old = malloc((size_t)nsp * sizeof(double));
    m->k_old = malloc((size_t)nsp * sizeof(double));
    if (!m->rest_old || !m->k_old) goto nomem;
    m->nmyo = calloc((size_t)nn, sizeof(double));
    m->nmf = calloc((size_t)nn, sizeof(double));
    m->nproto = calloc((size_t)nn, sizeof(double));
    m->ngf = calloc((size_t)nn, sizeof(double));
    m->ncov = calloc((size_t)nn, sizeof(double));
    m->nrho = calloc((size_t)nn, sizeof(double));
    if (!m->nmf || !m->nproto || !m->ngf || !m->ncov || !m->nrho) goto nomem;
    m->nth = calloc((size_t)nn, sizeof(double));
    m->necm = calloc((size_t)nn, sizeof(double));
    m->stress = calloc((size_t)nn, sizeof(double));
    m->vel = calloc(3 * (size_t)nn, sizeof(double));
    m->xprev = malloc(3 * (size_t)nn * sizeof(double));
    m->grad = calloc(9 * (size_t)nn, sizeof(double));
    m->disp = calloc(3 * (size_t)nn, sizeof(double));
    m->tri_wound = calloc((size_t)m->ntri + 1, 1);
    if (!m->kbase || !m->nmyo || !m->nth || !m->necm || !m->stress || !m->vel || !m->xprev ||
        !m->grad || !m->disp || !m->tri_wound)
        goto nomem;
    memcpy(m->kbase, m->S->k, (size_t)nsp * sizeof(double));
    ss_springs_update_mass(m->S);
    /* the wound's top triangles: reference centroid over a column with a wound voxel */
    uint8_t *foot = m->foot = calloc((size_t)g->nx * g->ny, 1);
    if (!foot) goto nomem;
    for (size_t i = 0; i < n; i++)
        if (m->wound0[i]) foot[i % ((size_t)g->nx * g->ny)] = 1;
    for (int t = 0; t < m->ntri; t++) {
        /* the midpoint of the longest edge: on a lattice, the centre of the
         * square face the triangle halves, so both halves agree */
        double c[2] = {0, 0}, best = -1;
        for (int k = 0; k < 3; k++) {
            const double *a = m->mesh->x + 3 * m->tri[3 * t + k],
                         *b = m->mesh->x + 3 * m->tri[3 * t + (k + 1) % 3];
            double l = (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]);
            if (l > best) {
                best = l;
                c[0] = 0.5 * (a[0] + b[0]);
                c[1] = 0.5 * (a[1] + b[1]);
            }
        }
        m->tri_wound[t] = (uint8_t)ss_mech_in_foot(m, c[0], c[1]);
    }
    double w = ss_mech_kernel_width(ncells, (size_t)nn);
    int stride = (int)floor(w + 0.5);
    if (stride < 1) stride = 1;
    if (!(m->T = ss_mech_transfer_create(g->nx, g->ny, g->nz, g->dx_mm, stride, err))) goto fail;
    m->kernel_width = w;
    {
        size_t ms = ss_mech_sub_count(m->T);
        for (int d = 0; d < 3; d++)
            if (!(m->usub[d] = calloc(ms, sizeof(double)))) goto nomem;
        m->thsub = calloc(ms, sizeof(double));
        m->usub_valid = calloc(ms, 1);
        if (!m->thsub || !m->usub_valid) goto nomem;
    }
    ss_mech_stats st;
    ss_mech_stats_compute(m, &st);
    m->outline0 = st.outline_area_mm2;
    if (p->model == SS_MECH_MODEL_GOH) {
        if (ss_mech_goh_setup(m, err) != SS_OK) goto fail;
        displacement_to_grid(m);
    }
    return m;
nomem:
    ss_error_set(err, SS_ERR_NOMEM, "mechanics: out of memory");
fail:
    ss_mech_free(m);
    return NULL;
}

const ss_tetmesh *ss_mech_mesh(const ss_mech *m) { return m->mesh; }
const double *ss_mech_positions(const ss_mech *m) { return m->S->x; }
const double *ss_mech_velocities(const ss_mech *m) { return m->vel; }
const double *ss_mech_node_stress(const ss_mech *m) { return m->stress; }
float *const *ss_mech_grid_displacement(ss_mech *m) {
    const size_t n = (size_t)m->nx * m->ny * m->nz;
    for (int d = 0; d < 3; d++)
        if (!m->u[d] && !(m->u[d] = calloc(n, sizeof(float)))) return NULL;
    ss_mech_sub_upsample(m->T, m->usub, m->usub_valid, 3, m->mask, m->u);
    return m->u;
}

/* Volume-weighted average over each node's tets of the P1 gradient of a
 * 3-component nodal field f (3n) in the current configuration: grad (9n),
 * grad[9i + 3c + d] = d f_c / d x_d. */
static void node_gradients(ss_mech *m, const double *f, double *grad) {
    const ss_tetmesh *M = m->mesh;
    const double *x = m->S->x;
    const int nn = M->nnodes;
    double *wsum = calloc((size_t)nn, sizeof(double));
    if (!wsum) return;
    memset(grad, 0, 9 * (size_t)nn * sizeof(double));
    for (int t = 0; t < M->ntets; t++) { /* serial: a fixed summation order */
        const int32_t *q = M->tet + 4 * t;
        double D[3][3], F[3][3];
        for (int k = 0; k < 3; k++)
            for (int d = 0; d < 3; d++) {
                D[d][k] = x[3 * q[k + 1] + d] - x[3 * q[0] + d];
                F[d][k] = f[3 * q[k + 1] + d] - f[3 * q[0] + d];
            }
        double det = D[0][0] * (D[1][1] * D[2][2] - D[1][2] * D[2][1]) -
                     D[0][1] * (D[1][0] * D[2][2] - D[1][2] * D[2][0]) +
                     D[0][2] * (D[1][0] * D[2][1] - D[1][1] * D[2][0]);
        if (fabs(det) < 1e-300) continue;
        double I[3][3];
        I[0][0] = (D[1][1] * D[2][2] - D[1][2] * D[2][1]) / det;
        I[0][1] = (D[0][2] * D[2][1] - D[0][1] * D[2][2]) / det;
        I[0][2] = (D[0][1] * D[1][2] - D[0][2] * D[1][1]) / det;
        I[1][0] = (D[1][2] * D[2][0] - D[1][0] * D[2][2]) / det;
        I[1][1] = (D[0][0] * D[2][2] - D[0][2] * D[2][0]) / det;
        I[1][2] = (D[0][2] * D[1][0] - D[0][0] * D[1][2]) / det;
        I[2][0] = (D[1][0] * D[2][1] - D[1][1] * D[2][0]) / det;
        I[2][1] = (D[0][1] * D[2][0] - D[0][0] * D[2][1]) / det;
        I[2][2] = (D[0][0] * D[1][1] - D[0][1] * D[1][0]) / det;
        double G[3][3], vol = fabs(det) / 6.0;
        for (int c = 0; c < 3; c++)
            for (int d = 0; d < 3; d++)
                G[c][d] = F[c][0] * I[0][d] + F[c][1] * I[1][d] + F[c][2] * I[2][d];
        for (int k = 0; k < 4; k++) {
            wsum[q[k]] += vol;
            for (int c = 0; c < 3; c++)
                for (int d = 0; d < 3; d++) grad[9 * (size_t)q[k] + 3 * c + d] += vol * G[c][d];
        }
    }
    for (int i = 0; i < nn; i++)
        if (wsum[i] > 0)
            for (int c = 0; c < 9; c++) grad[9 * (size_t)i + c] /= wsum[i];
    free(wsum);
}

/* Particle fields to the grid: velocity into g->velocity; displacement and
 * theta = div u on the transfer's sub-lattice (theta is only ever sampled
 * there; the grid displacement is upsampled when asked for). */
static void displacement_to_grid(ss_mech *m) {
    const int nn = m->mesh->nnodes;
    for (int i = 0; i < 3 * nn; i++) m->disp[i] = m->S->x[i] - m->S->X[i];
    node_gradients(m, m->disp, m->grad);
    ss_mech_p2g_sub(m->T, m->S->x, nn, m->disp, m->grad, 3);
    ss_mech_sub_get(m->T, 3, m->usub, m->usub_valid);
    ss_mech_sub_divergence(m->T, m->usub, m->usub_valid, m->thsub);
}

static void to_grid(ss_mech *m, ss_heal_grid *g) {
    const int nn = m->mesh->nnodes;
    node_gradients(m, m->vel, m->grad);
    ss_mech_p2g(m->T, m->S->x, nn, m->vel, m->grad, 3, m->mask, g->velocity);
    displacement_to_grid(m);
}

ss_status ss_mech_step(ss_mech *m, ss_heal_grid *g, double dt_days, ss_error *err) {
    if (!m || !g || g->nx != m->nx || g->ny != m->ny || g->nz != m->nz)
        return ss_error_set(err, SS_ERR_INPUT, "mechanics step: grid does not match");
    if (!(dt_days >= 0) || !isfinite(dt_days))
        return ss_error_set(err, SS_ERR_INPUT, "mechanics step: bad frame time %g days", dt_days);
    const ss_mech_params *p = &m->p;
    ss_springs *S = m->S;
    const int nn = m->mesh->nnodes;
    /* 1. fields at the nodes */
    const float *rho = g->field[SS_HEAL_SCAR], *fib = g->field[SS_HEAL_FIBROBLAST];
    const float *epi = g->field[SS_HEAL_EPITHELIUM], *pla = g->field[SS_HEAL_PLASMA];
    const float *mdgf = g->field[SS_HEAL_MDGF];
    const int nx = m->nx, ny = m->ny, nz = m->nz;
    const int gate = p->tau_myo > 0 && p->rho_myo > 0; /* the maturation needs the collagen */
    /* per block of MECH_COLS columns, z-slab by z-slab (the same per-column
     * sums as a column walk). The per-cell fields are read only by the
     * grid-to-node gathers, at the transfer's sub-lattice cells (every s-th
     * cell on each axis): only the columns at sub-lattice x, y are walked and
     * only their cells at sub-lattice z written (s^2 fewer columns; the
     * other cells are never read) */
    enum { MECH_COLS = 256 };
    const int s = ss_mech_transfer_stride(m->T);
    const int sx = (nx - 1) / s + 1, sy = (ny - 1) / s + 1;
    const int ncol = sx * sy;
    const size_t slab = (size_t)nx * ny;
#pragma omp parallel for schedule(static)
    for (int c0 = 0; c0 < ncol; c0 += MECH_COLS) {
        const int nb = ncol - c0 < MECH_COLS ? ncol - c0 : MECH_COLS;
        int top[MECH_COLS], nw[MECH_COLS];
        size_t col[MECH_COLS]; /* the grid column of sub-lattice column c0 + k */
        for (int k = 0; k < nb; k++)
            col[k] = (size_t)((c0 + k) / sx) * s * nx + (size_t)((c0 + k) % sx) * s;
        float sum[MECH_COLS], gsum[MECH_COLS], rsum[MECH_COLS], nmean[MECH_COLS], gmean[MECH_COLS],
            rmean[MECH_COLS], cover[MECH_COLS];
        for (int k = 0; k < nb; k++) {
            top[k] = -1;
            nw[k] = 0;
            sum[k] = gsum[k] = rsum[k] = 0.0f;
        }
        /* the column's surface: its top tissue cell; the wound region's
         * cells (initial wound or omega) give the mean fibroblast density
         * and growth factor, the top cell's epithelium the cover */
        for (int z = nz - 1; z >= 0; z--)
            for (int k = 0; k < nb; k++) {
                size_t i = (size_t)z * slab + col[k];
                if (!m->mask[i]) continue;
                if (top[k] < 0) top[k] = z;
                if (m->wound0[i] || pla[i] > SS_HEAL_P_MIN) {
                    sum[k] += fib[i];
                    gsum[k] += mdgf[i];
                    rsum[k] += rho[i];
                    nw[k]++;
                }
            }
        for (int k = 0; k < nb; k++) {
            nmean[k] = nw[k] ? sum[k] / (float)nw[k] : 0.0f;
            gmean[k] = nw[k] ? gsum[k] / (float)nw[k] : 0.0f;
            rmean[k] = nw[k] ? rsum[k] / (float)nw[k] : 0.0f;
            cover[k] = 1.0f;
            if (top[k] >= 0 && nw[k]) {
                float e = epi[(size_t)top[k] * slab + col[k]];
                cover[k] = e > 1.0f ? 1.0f : e < 0.0f ? 0.0f : e;
            }
        }
        for (int z = 0; z < nz; z += s)
            for (int k = 0; k < nb; k++) {
                size_t i = (size_t)z * slab + col[k];
                float e = 1.0f;
                if (m->wound0[i]) {
                    e = (float)p->ecm_floor + rho[i];
                    if (e > 1.0f) e = 1.0f;
                }
                m->ecm[i] = e;
                m->myo[i] = m->mask[i] ? nmean[k] : 0.0f;
                m->gf[i] = m->mask[i] ? gmean[k] : 0.0f;
                if (gate) m->rhoc[i] = m->mask[i] ? rmean[k] : 0.0f;
                m->cov[i] = m->mask[i] ? cover[k] : 1.0f;
            }
    }
    ss_mech_g2p(m->T, m->myo, m->mask, S->x, nn, m->nmyo);
    ss_mech_g2p_sub(m->T, m->thsub, m->usub_valid, S->x, nn, m->nth);
    ss_mech_g2p(m->T, m->ecm, m->mask, S->x, nn, m->necm);
    ss_mech_g2p(m->T, m->gf, m->mask, S->x, nn, m->ngf);
    ss_mech_g2p(m->T, m->cov, m->mask, S->x, nn, m->ncov);
    if (gate) ss_mech_g2p(m->T, m->rhoc, m->mask, S->x, nn, m->nrho);
        /* myofibroblast differentiation (docs/mech.md): the growth factor turns
         * the wound's fibroblasts into proto-myofibroblasts, these mature into
         * alpha-SMA myofibroblasts, and both go by apoptosis once the wound is
         * covered; implicit Euler per node over the frame (stable for any frame
         * time, keeps 0 <= q, m and q + m <= 1) */
#pragma omp parallel for schedule(static)
    for (int i = 0; i < nn; i++) {
        double n_w = m->nmyo[i] > 0 ? m->nmyo[i] : 0.0;
        double c = m->ncov[i] < 0 ? 0 : m->ncov[i] > 1 ? 1 : m->ncov[i];
        if (p->tau_myo > 0) {
            double gfv = m->ngf[i] > 0 ? m->ngf[i] : 0.0;
            /* maturation needs a matrix that resists the pull: the wound
             * matrix's collagen r against rho_myo (Hill, exponent 2) */
            double r = m->nrho[i] > 0 ? m->nrho[i] : 0.0,
                   mat = p->rho_myo > 0 ? r * r / (r * r + p->rho_myo * p->rho_myo) : 1.0;
            double a = gfv / (gfv + p->gf_half) / p->tau_proto, b = mat / p->tau_myo,
                   d = c / p->tau_apo, h = dt_days;
            double q = m->nproto[i], f = m->nmf[i];
            double A11 = 1 + h * (a + b + d), A12 = h * a, A21 = -h * b, A22 = 1 + h * d;
            double r1 = q + h * a, r2 = f, det = A11 * A22 - A12 * A21;
            double q1 = (r1 * A22 - A12 * r2) / det, f1 = (A11 * r2 - A21 * r1) / det;
            m->nproto[i] = q1 > 0 ? q1 : 0.0;
            m->nmf[i] = f1 < 0 ? 0.0 : f1 > 1 ? 1.0 : f1;
        } else {
            m->nproto[i] = 0;
            m->nmf[i] = 1.0 - c;
        }
        m->stress[i] = ss_mech_pcell(p, m->nth[i]) * n_w * m->nmf[i] * p->K_m;
    }
    if (m->H) { /* steps 2-3 on the hyperelastic tissue (mech_goh.c) */
        memcpy(m->xprev, S->x, 3 * (size_t)nn * sizeof(double));
        ss_status gst = ss_mech_goh_frame(m, g, dt_days, err);
        if (gst) return gst;
        goto velocities;
    }
    /* 2. rest lengths and stiffness of the tissue springs */
    const int ntis = m->ntissue;
    const double follow = p->tau_remodel > 0 ? 1.0 - exp(-dt_days / p->tau_remodel) : 1.0;
    memcpy(m->rest_old, S->rest, (size_t)S->nsprings * sizeof(double));
    memcpy(m->k_old, S->k, (size_t)S->nsprings * sizeof(double));
#pragma omp parallel for schedule(static)
    for (int s = 0; s < ntis; s++) {
        int a = S->e[2 * s], b = S->e[2 * s + 1];
        double sig = 0.5 * (m->stress[a] + m->stress[b]);
        double ecm = 0.5 * (m->necm[a] + m->necm[b]);
        double e[3];
        for (int d = 0; d < 3; d++) e[d] = S->X[3 * b + d] - S->X[3 * a + d];
        double psi = ss_mech_spring_energy_density(p, fabs(sig), e);
        double dl = ss_mech_shortening(p, psi);
        double r = S->l0[s] * (1.0 - (sig >= 0 ? dl : -dl));
        /* the matrix follows the pull with the remodelling lag, and the
         * contracted state is kept (rest lengths never lengthen) */
        if (r < S->rest[s]) S->rest[s] += follow * (r - S->rest[s]);
        S->k[s] = m->kbase[s] * (ecm > 0 ? ecm : p->ecm_floor);
    }
    for (int i = 0; i < m->nsutures; i++)
        for (int sp = m->suture_spring[i]; sp < m->suture_spring[i + 1]; sp++)
            S->k[sp] = g->t_days >= m->suture_day[i] ? 0.0 : m->kbase[sp];
    ss_springs_update_mass(S);
    /* 3. relax from the last configuration, at rest */
    memcpy(m->xprev, S->x, 3 * (size_t)nn * sizeof(double));
    memset(S->v, 0, 3 * (size_t)nn * sizeof(double));
    int inv0 = ss_mech_inverted_tets(m);
    m->last_substeps = ss_springs_relax(S, p->tol, p->max_substeps, &m->last_converged);
    m->last_increments = 1;
    /* inversion guard: a frame that folds tets is redone from the last
     * configuration with its load (rest lengths, stiffness) applied in 2, 4,
     * ... 32 increments, each relaxed to the criterion (a continuation: the
     * relaxation then follows the unfolded branch) */
    m->last_inverted = ss_mech_inverted_tets(m);
    if (m->last_inverted > inv0) {
        const int nsp = S->nsprings;
        double *rest_new = malloc((size_t)nsp * sizeof(double)),
               *k_new = malloc((size_t)nsp * sizeof(double));
        if (!rest_new || !k_new) {
            free(rest_new);
            free(k_new);
            return ss_error_set(err, SS_ERR_NOMEM, "mechanics step: out of memory");
        }
        memcpy(rest_new, S->rest, (size_t)nsp * sizeof(double));
        memcpy(k_new, S->k, (size_t)nsp * sizeof(double));
        for (int inc = 2; inc <= 32 && m->last_inverted > inv0; inc *= 2) {
            memcpy(S->x, m->xprev, 3 * (size_t)nn * sizeof(double));
            int total = 0, conv = 1;
            for (int q = 1; q <= inc; q++) {
                double w = (double)q / inc;
                for (int sp = 0; sp < nsp; sp++) {
                    S->rest[sp] = m->rest_old[sp] + w * (rest_new[sp] - m->rest_old[sp]);
                    S->k[sp] = m->k_old[sp] + w * (k_new[sp] - m->k_old[sp]);
                }
                ss_springs_update_mass(S);
                memset(S->v, 0, 3 * (size_t)nn * sizeof(double));
                int c = 0;
                total += ss_springs_relax(S, p->tol, p->max_substeps, &c);
                conv &= c;
            }
            m->last_substeps = total;
            m->last_converged = conv;
            m->last_increments = inc;
            m->last_inverted = ss_mech_inverted_tets(m);
        }
        free(rest_new);
        free(k_new);
    }
    /* 4. velocities and the grid */
velocities:;
    double vmax = 0;
    for (int i = 0; i < 3 * nn; i++) {
        m->vel[i] = dt_days > 0 ? (S->x[i] - m->xprev[i]) / dt_days : 0.0;
    }
    for (int i = 0; i < nn; i++) {
        double s2 = m->vel[3 * i] * m->vel[3 * i] + m->vel[3 * i + 1] * m->vel[3 * i + 1] +
                    m->vel[3 * i + 2] * m->vel[3 * i + 2];
        if (s2 > vmax) vmax = s2;
    }
    m->last_vmax = sqrt(vmax);
    to_grid(m, g);
    m->frames++;
    return SS_OK;
}

/* Signed volume of tet t at positions x (mm^3). */
static double tet_volume(const int32_t *q, const double *x) {
    double u[3], v[3], w[3];
    for (int d = 0; d < 3; d++) {
        u[d] = x[3 * q[1] + d] - x[3 * q[0] + d];
        v[d] = x[3 * q[2] + d] - x[3 * q[0] + d];
        w[d] = x[3 * q[3] + d] - x[3 * q[0] + d];
    }
    return (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
            u[2] * (v[0] * w[1] - v[1] * w[0])) /
           6.0;
}

int ss_mech_inverted_tets(const ss_mech *m) {
    int c = 0;
    for (int t = 0; t < m->mesh->ntets; t++) c += !(tet_volume(m->mesh->tet + 4 * t, m->S->x) > 0);
    return c;
}

void ss_mech_stats_compute(const ss_mech *m, ss_mech_stats *st) {
    memset(st, 0, sizeof *st);
    st->substeps = m->last_substeps;
    st->converged = m->last_converged;
    st->increments = m->last_increments;
    st->max_speed_mm_day = m->last_vmax;
    st->initial_outline_area_mm2 = m->outline0;
    const double *x = m->S->x;
    st->inverted_tets = ss_mech_inverted_tets(m);
    for (int i = 0; i < m->mesh->nnodes; i++) {
        if (!m->side[i]) continue;
        double d2 = 0;
        for (int d = 0; d < 3; d++)
            d2 += (x[3 * i + d] - m->S->X[3 * i + d]) * (x[3 * i + d] - m->S->X[3 * i + d]);
        if (d2 > st->side_max_disp_mm * st->side_max_disp_mm) st->side_max_disp_mm = sqrt(d2);
    }
    double msum = 0;
    int mcount = 0;
    for (int i = 0; i < m->mesh->nnodes; i++) {
        if (!ss_mech_in_foot(m, m->S->X[3 * i], m->S->X[3 * i + 1])) continue;
        msum += m->nmf[i];
        mcount++;
    }
    st->myofibroblast_fraction = mcount ? msum / mcount : 0.0;
    double A = 0, cx = 0, cy = 0, sxx = 0, syy = 0, sxy = 0;
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int t = 0; t < m->ntri; t++) {
        if (!m->tri_wound[t]) continue;
        const double *a = x + 3 * m->tri[3 * t], *b = x + 3 * m->tri[3 * t + 1],
                     *c = x + 3 * m->tri[3 * t + 2];
        double ar = 0.5 * fabs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
        double gx = (a[0] + b[0] + c[0]) / 3, gy = (a[1] + b[1] + c[1]) / 3;
        A += ar;
        cx += ar * gx;
        cy += ar * gy;
        sxx += ar * gx * gx;
        syy += ar * gy * gy;
        sxy += ar * gx * gy;
        const double *v[3] = {a, b, c};
        for (int k = 0; k < 3; k++)
            for (int d = 0; d < 2; d++) {
                if (v[k][d] < lo[d]) lo[d] = v[k][d];
                if (v[k][d] > hi[d]) hi[d] = v[k][d];
            }
    }
    st->outline_area_mm2 = A;
    if (A <= 0) return;
    cx /= A;
    cy /= A;
    sxx = sxx / A - cx * cx;
    syy = syy / A - cy * cy;
    sxy = sxy / A - cx * cy;
    st->extent_x_mm = hi[0] - lo[0];
    st->extent_y_mm = hi[1] - lo[1];
    double tr = sxx + syy, det = sxx * syy - sxy * sxy;
    double disc = sqrt(fmax(0, tr * tr / 4 - det));
    double l1 = tr / 2 + disc, l2 = tr / 2 - disc;
    double ang = 0.5 * atan2(2 * sxy, sxx - syy);
    st->principal[0] = cos(ang);
    st->principal[1] = sin(ang);
    st->aspect_major_minor = l2 > 0 ? sqrt(l1 / l2) : 0;
}

size_t ss_mech_state_size(const ss_mech *m) {
    return ((size_t)m->mesh->nnodes * 9 + (size_t)m->S->nsprings +
            (m->H ? 9 * (size_t)m->mesh->ntets + (size_t)m->mesh->nnodes : 0)) *
               sizeof(double) +
           sizeof(uint64_t);
}

void ss_mech_state_get(const ss_mech *m, void *buf) {
    const size_t nn = (size_t)m->mesh->nnodes;
    char *b = buf;
    uint64_t fr = (uint64_t)m->frames;
    memcpy(b, &fr, sizeof fr);
    b += sizeof fr;
    memcpy(b, m->S->x, 3 * nn * sizeof(double));
    memcpy(b + 3 * nn * sizeof(double), m->vel, 3 * nn * sizeof(double));
    memcpy(b + 6 * nn * sizeof(double), m->stress, nn * sizeof(double));
    memcpy(b + 7 * nn * sizeof(double), m->nmf, nn * sizeof(double));
    memcpy(b + 8 * nn * sizeof(double), m->nproto, nn * sizeof(double));
    memcpy(b + 9 * nn * sizeof(double), m->S->rest, (size_t)m->S->nsprings * sizeof(double));
    if (m->H) {
        const size_t o = 9 * nn + (size_t)m->S->nsprings, nt = (size_t)m->mesh->ntets;
        memcpy(b + o * sizeof(double), ss_hyper_growth(m->H), 9 * nt * sizeof(double));
        memcpy(b + (o + 9 * nt) * sizeof(double), m->nact, nn * sizeof(double));
    }
}

ss_status ss_mech_state_set(ss_mech *m, const void *buf, size_t size, ss_error *err) {
    /* goh states before the contraction lag had no lagged tension: resuming
     * one with the lag at zero would drop the wound's pull for days */
    if (m->H && size + (size_t)m->mesh->nnodes * sizeof(double) == ss_mech_state_size(m))
        return ss_error_set(err, SS_ERR_INPUT,
                            "mechanics state: a goh checkpoint from before the lagged active "
                            "tension (tau_contract_goh); it cannot be resumed exactly, run "
                            "again from day 0");
    if (size != ss_mech_state_size(m))
        return ss_error_set(err, SS_ERR_INPUT,
                            "mechanics state: %zu bytes, expected %zu (another mesh?)", size,
                            ss_mech_state_size(m));
    const size_t nn = (size_t)m->mesh->nnodes;
    const char *b = buf;
    uint64_t fr;
    memcpy(&fr, b, sizeof fr);
    b += sizeof fr;
    m->frames = (long)fr;
    memcpy(m->S->x, b, 3 * nn * sizeof(double));
    memcpy(m->vel, b + 3 * nn * sizeof(double), 3 * nn * sizeof(double));
    memcpy(m->stress, b + 6 * nn * sizeof(double), nn * sizeof(double));
    memcpy(m->nmf, b + 7 * nn * sizeof(double), nn * sizeof(double));
    memcpy(m->nproto, b + 8 * nn * sizeof(double), nn * sizeof(double));
    memcpy(m->S->rest, b + 9 * nn * sizeof(double), (size_t)m->S->nsprings * sizeof(double));
    if (m->H) {
        const size_t o = 9 * nn + (size_t)m->S->nsprings, nt = (size_t)m->mesh->ntets;
        memcpy(ss_hyper_growth(m->H), b + o * sizeof(double), 9 * nt * sizeof(double));
        memcpy(m->nact, b + (o + 9 * nt) * sizeof(double), nn * sizeof(double));
        for (size_t i = 0; i < nn; i++)
            if (!isfinite(m->nact[i]))
                return ss_error_set(err, SS_ERR_INPUT, "mechanics state: non-finite value");
    }
    for (size_t i = 0; i < 3 * nn; i++)
        if (!isfinite(m->S->x[i]) || !isfinite(m->vel[i]))
            return ss_error_set(err, SS_ERR_INPUT, "mechanics state: non-finite value");
    return SS_OK;
}

/* The strain from the restored particles (the same function a step ends
 * with, so a resumed run continues bit for bit); the grid velocity is the
 * checkpoint's own (a caller may have capped it) unless the grid has none. */
ss_status ss_mech_state_apply(ss_mech *m, ss_heal_grid *g, ss_error *err) {
    if (!m || !g || g->nx != m->nx || g->ny != m->ny || g->nz != m->nz)
        return ss_error_set(err, SS_ERR_INPUT, "mechanics state: grid does not match");
    const size_t n = (size_t)g->nx * g->ny * g->nz;
    int have = 1;
    for (int d = 0; d < 3; d++)
        if (!g->velocity[d]) {
            have = 0;
            if (!(g->velocity[d] = calloc(n, sizeof(float))))
                return ss_error_set(err, SS_ERR_NOMEM, "mechanics state: out of memory");
        }
    if (have)
        displacement_to_grid(m);
    else
        to_grid(m, g);
    return SS_OK;
}

ss_mech_suture *ss_mech_sutures_read(const char *path, int *count, ss_error *err) {
    char *text = ss_read_file_max(path, NULL, SS_READ_MAX_STROKES, err);
    if (!text) return NULL;
    int cap = 16, n = 0, line = 0, header = 0;
    ss_mech_suture *s = malloc((size_t)cap * sizeof *s);
    const char *p = text;
    char buf[1024];
    if (!s) goto nomem;
    while (p) {
        int too_long = 0;
        p = ss_text_next_line(p, buf, sizeof buf, &too_long);
        if (!p) break;
        line++;
        char *h = strchr(buf, '#');
        if (h) *h = 0;
        char *t = ss_text_trim(buf);
        if (!*t) continue;
        double v[7];
        int k = 0;
        char *tok = t, *save = NULL;
        int bad = 0;
        for (char *q = strtok_r(tok, ",", &save); q; q = strtok_r(NULL, ",", &save)) {
            if (k == 7) {
                bad = 1;
                break;
            }
            int r = ss_text_parse_number(ss_text_trim(q), &v[k]);
            if (r) {
                bad = r == 1 ? 2 : 1;
                break;
            }
            k++;
        }
        if (bad == 2 && n == 0 && !header) { /* a header line (first non-comment line) */
            header = 1;
            continue;
        }
        header = 1;
        if (bad || too_long || (k != 6 && k != 7)) {
            ss_error_set(err, SS_ERR_INPUT,
                         "%s:%d: expected 'x1,y1,z1,x2,y2,z2[,remove_day]' in mm and days", path,
                         line);
            goto fail;
        }
        if (k == 7 && !(v[6] >= 0)) {
            ss_error_set(err, SS_ERR_INPUT, "%s:%d: removal day %g must be >= 0", path, line, v[6]);
            goto fail;
        }
        if (n == SS_MECH_MAX_SUTURES) {
            ss_error_set(err, SS_ERR_INPUT, "%s:%d: more than %d sutures (the limit)", path, line,
                         SS_MECH_MAX_SUTURES);
            goto fail;
        }
        if (n == cap) {
            cap *= 2;
            ss_mech_suture *ns = realloc(s, (size_t)cap * sizeof *s);
            if (!ns) goto nomem;
            s = ns;
        }
        for (int d = 0; d < 3; d++) {
            s[n].a[d] = v[d];
            s[n].b[d] = v[3 + d];
        }
        s[n].remove_day = k == 7 ? v[6] : INFINITY;
        n++;
    }
    if (n == 0) {
        ss_error_set(err, SS_ERR_INPUT, "%s: no stitches", path);
        goto fail;
    }
    free(text);
    *count = n;
    return s;
nomem:
    ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
fail:
    free(text);
    free(s);
    return NULL;
}

double ss_mech_kernel(const ss_mech *m, int *stride) {
    if (stride) *stride = ss_mech_transfer_stride(m->T);
    return m->kernel_width;
}
