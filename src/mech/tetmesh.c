/* Tetrahedral meshes for the contraction mechanics (seed 001 §5.2).
 *
 * The seed tetrahedralises the skin with TetGen under a maximum-volume
 * constraint so the tets are evenly sized. Built in here is the robust
 * alternative for a voxel domain: a lattice of cubes (edge about the requested
 * size, fitted so the domain's bounding box is spanned exactly), each cube
 * kept when the voxel at its centre is tissue and cut into the six Kuhn tets
 * around a main diagonal, mirrored cube by cube (odd cube coordinates flip
 * the axis) so the lattice is as symmetric as the box. Neighbouring cubes
 * agree on their shared face's diagonal, so faces match (a conforming mesh)
 * without any search, every tet has the same volume edge^3 / 6 (the max-volume constraint
 * holds with equality) and no tet is ever sliver-shaped. What it gives up: the
 * boundary is a staircase at the lattice resolution, coarser than the grid's;
 * users who need a smooth boundary bring a TetGen or Gmsh mesh (read here) or
 * let skinsim call the `tetgen` program where installed (AGPL: called as a
 * program, never linked). */
#define _POSIX_C_SOURCE 200809L
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "skinsim/mech.h"

extern char **environ;

void ss_tetmesh_free(ss_tetmesh *m) {
    if (!m) return;
    free(m->x);
    free(m->tet);
    free(m);
}

static double tet_volume6(const double *x, const int32_t *t) {
    const double *a = x + 3 * t[0], *b = x + 3 * t[1], *c = x + 3 * t[2], *d = x + 3 * t[3];
    double u[3], v[3], w[3];
    for (int i = 0; i < 3; i++) {
        u[i] = b[i] - a[i];
        v[i] = c[i] - a[i];
        w[i] = d[i] - a[i];
    }
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
           u[2] * (v[0] * w[1] - v[1] * w[0]);
}

double ss_tetmesh_volume(const ss_tetmesh *m, double *max_tet_volume) {
    double s = 0, mx = 0;
    for (int t = 0; t < m->ntets; t++) {
        double v = fabs(tet_volume6(m->x, m->tet + 4 * t)) / 6.0;
        s += v;
        if (v > mx) mx = v;
    }
    if (max_tet_volume) *max_tet_volume = mx;
    return s;
}

/* Orients every tet positively; a degenerate tet (volume below 1e-12 of the
 * bounding box's) is an input error naming `what`. */
static ss_status orient_tets(ss_tetmesh *m, const char *what, ss_error *err) {
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < m->nnodes; i++)
        for (int d = 0; d < 3; d++) {
            double v = m->x[3 * i + d];
            if (v < lo[d]) lo[d] = v;
            if (v > hi[d]) hi[d] = v;
        }
    double box = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    for (int t = 0; t < m->ntets; t++) {
        int32_t *q = m->tet + 4 * t;
        double v = tet_volume6(m->x, q);
        if (!(fabs(v) > 1e-12 * box))
            return ss_error_set(err, SS_ERR_INPUT, "%s: tetrahedron %d is degenerate (zero volume)",
                                what, t + 1);
        if (v < 0) {
            int32_t tmp = q[2];
            q[2] = q[3];
            q[3] = tmp;
        }
    }
    return SS_OK;
}

ss_tetmesh *ss_tetmesh_lattice(const uint8_t *inside, int nx, int ny, int nz, double dx_mm,
                               double tet_size_mm, ss_error *err) {
    if (!inside || nx < 1 || ny < 1 || nz < 1 || !(dx_mm > 0) || !isfinite(dx_mm)) {
        ss_error_set(err, SS_ERR_INPUT, "tet lattice: no voxel domain");
        return NULL;
    }
    if (!(tet_size_mm > 0) || !isfinite(tet_size_mm)) {
        ss_error_set(err, SS_ERR_INPUT, "tet size %g mm must be > 0", tet_size_mm);
        return NULL;
    }
    int lo[3] = {nx, ny, nz}, hi[3] = {-1, -1, -1};
    const int dim[3] = {nx, ny, nz};
    for (int z = 0; z < nz; z++)
        for (int y = 0; y < ny; y++)
            for (int x = 0; x < nx; x++)
                if (inside[((size_t)z * ny + y) * nx + x]) {
                    int c[3] = {x, y, z};
                    for (int d = 0; d < 3; d++) {
                        if (c[d] < lo[d]) lo[d] = c[d];
                        if (c[d] > hi[d]) hi[d] = c[d];
                    }
                }
    if (hi[0] < 0) {
        ss_error_set(err, SS_ERR_INPUT, "tet lattice: the domain has no tissue voxel");
        return NULL;
    }
    int n[3];
    double org[3], h[3];
    double cubes = 1;
    for (int d = 0; d < 3; d++) {
        double L = (hi[d] - lo[d] + 1) * dx_mm;
        n[d] = (int)floor(L / tet_size_mm + 0.5);
        if (n[d] < 1) n[d] = 1;
        org[d] = lo[d] * dx_mm;
        h[d] = L / n[d];
        cubes *= n[d];
    }
    if (cubes > 2e7) {
        ss_error_set(err, SS_ERR_INPUT,
                     "tet size %g mm gives %.3g lattice cubes (more than 2e7); use a larger size",
                     tet_size_mm, cubes);
        return NULL;
    }
    const size_t nn = (size_t)(n[0] + 1) * (n[1] + 1) * (n[2] + 1);
    const size_t nc = (size_t)n[0] * n[1] * n[2];
    uint8_t *keep = calloc(nc, 1);
    int32_t *map = malloc(nn * sizeof *map);
    ss_tetmesh *m = calloc(1, sizeof *m);
    if (!keep || !map || !m) goto nomem;
    size_t nkeep = 0;
    for (int c = 0; c < n[2]; c++)
        for (int b = 0; b < n[1]; b++)
            for (int a = 0; a < n[0]; a++) {
                int ijk[3] = {a, b, c}, v[3];
                for (int d = 0; d < 3; d++) {
                    double centre = org[d] + (ijk[d] + 0.5) * h[d];
                    v[d] = (int)floor(centre / dx_mm);
                    if (v[d] < 0) v[d] = 0;
                    if (v[d] >= dim[d]) v[d] = dim[d] - 1;
                }
                if (inside[((size_t)v[2] * ny + v[1]) * nx + v[0]]) {
                    keep[((size_t)c * n[1] + b) * n[0] + a] = 1;
                    nkeep++;
                }
            }
    if (!nkeep) {
        ss_error_set(err, SS_ERR_INPUT, "tet size %g mm: no lattice cube has tissue at its centre",
                     tet_size_mm);
        goto fail;
    }
    for (size_t i = 0; i < nn; i++) map[i] = -1;
#define NODE(a, b, c) (((size_t)(c) * (n[1] + 1) + (size_t)(b)) * (n[0] + 1) + (size_t)(a))
    int32_t count = 0;
    for (int c = 0; c < n[2]; c++)
        for (int b = 0; b < n[1]; b++)
            for (int a = 0; a < n[0]; a++)
                if (keep[((size_t)c * n[1] + b) * n[0] + a])
                    for (int k = 0; k < 8; k++) {
                        size_t id = NODE(a + (k & 1), b + ((k >> 1) & 1), c + (k >> 2));
                        if (map[id] < 0) map[id] = 0; /* mark; numbered below in lattice order */
                    }
    for (size_t i = 0; i < nn; i++)
        if (map[i] >= 0) map[i] = count++;
    m->nnodes = count;
    m->ntets = (int)(6 * nkeep);
    m->x = malloc(3 * (size_t)count * sizeof(double));
    m->tet = malloc(4 * (size_t)m->ntets * sizeof(int32_t));
    if (!m->x || !m->tet) goto nomem;
    for (int c = 0; c <= n[2]; c++)
        for (int b = 0; b <= n[1]; b++)
            for (int a = 0; a <= n[0]; a++) {
                int32_t id = map[NODE(a, b, c)];
                if (id < 0) continue;
                m->x[3 * id] = org[0] + a * h[0];
                m->x[3 * id + 1] = org[1] + b * h[1];
                m->x[3 * id + 2] = org[2] + c * h[2];
            }
    /* Kuhn split: one tet per axis permutation, walking 000 -> 111 in the
     * cube's local frame; the frame is mirrored along every axis whose cube
     * coordinate is odd, so the diagonals alternate and the lattice has the
     * mirror symmetries of the box (a plain Kuhn lattice is chiral: contracted
     * along x it shears). Neighbours share a face's mirror state, so faces
     * still match. */
    static const int perm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                   {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    size_t t = 0;
    for (int c = 0; c < n[2]; c++)
        for (int b = 0; b < n[1]; b++)
            for (int a = 0; a < n[0]; a++) {
                if (!keep[((size_t)c * n[1] + b) * n[0] + a]) continue;
                const int base[3] = {a, b, c}, flip[3] = {a & 1, b & 1, c & 1};
                for (int p = 0; p < 6; p++) {
                    int loc[3] = {0, 0, 0};
                    int32_t *q = m->tet + 4 * t++;
                    for (int s = 0; s < 4; s++) {
                        if (s > 0) loc[perm[p][s - 1]] = 1;
                        int g[3];
                        for (int d = 0; d < 3; d++)
                            g[d] = base[d] + (flip[d] ? 1 - loc[d] : loc[d]);
                        q[s] = map[NODE(g[0], g[1], g[2])];
                    }
                }
            }
#undef NODE
    free(keep);
    free(map);
    if (orient_tets(m, "tet lattice", err) != SS_OK) {
        ss_tetmesh_free(m);
        return NULL;
    }
    return m;
nomem:
    ss_error_set(err, SS_ERR_NOMEM, "tet lattice: out of memory");
fail:
    free(keep);
    free(map);
    ss_tetmesh_free(m);
    return NULL;
}

/* ---- readers ---------------------------------------------------------------- */

/* Line reader over a whole file, skipping blank lines and # comments. */
typedef struct lines {
    const char *path, *p;
    int line;
    char buf[4096];
} lines;

static const char *next_line(lines *L) {
    while (L->p) {
        int too_long = 0;
        L->p = ss_text_next_line(L->p, L->buf, sizeof L->buf, &too_long);
        if (!L->p) break;
        L->line++;
        char *h = strchr(L->buf, '#');
        if (h) *h = 0;
        char *s = ss_text_trim(L->buf);
        if (*s) return s;
    }
    return NULL;
}

/* Reads up to max numbers from s; returns the count, -1 on a non-number. */
static int numbers(const char *s, double *out, int max) {
    int n = 0;
    while (*s) {
        while (isspace((unsigned char)*s) || *s == ',') s++;
        if (!*s) break;
        if (n == max) return n;
        char *end;
        errno = 0;
        double v = strtod(s, &end);
        if (end == s || errno == ERANGE || !isfinite(v)) return -1;
        out[n++] = v;
        s = end;
    }
    return n;
}

static int is_int(double v) { return v == floor(v) && fabs(v) < 2e9; }

ss_tetmesh *ss_tetmesh_read_tetgen(const char *node_path, const char *ele_path, ss_error *err) {
    char *nt = ss_read_file_max(node_path, NULL, SS_READ_MAX_MESH, err);
    if (!nt) return NULL;
    char *et = ss_read_file_max(ele_path, NULL, SS_READ_MAX_MESH, err);
    if (!et) {
        free(nt);
        return NULL;
    }
    ss_tetmesh *m = calloc(1, sizeof *m);
    int32_t *id2 = NULL;
    lines L = {node_path, nt, 0, {0}};
    double v[16];
    const char *s = next_line(&L);
    int k = s ? numbers(s, v, 4) : -1;
    if (!m) goto nomem;
    if (k < 1 || !is_int(v[0]) || v[0] < 4 || v[0] > 5e7 || (k >= 2 && v[1] != 3)) {
        ss_error_set(err, SS_ERR_INPUT,
                     "%s:%d: expected the header '<#points> 3 <#attributes> <#markers>'", node_path,
                     L.line);
        goto fail;
    }
    m->nnodes = (int)v[0];
    int nattr = k >= 3 ? (int)v[2] : 0, nmark = k >= 4 ? (int)v[3] : 0;
    if (nattr < 0 || nattr > 10 || nmark < 0 || nmark > 1) {
        ss_error_set(err, SS_ERR_INPUT, "%s:%d: bad attribute or marker count", node_path, L.line);
        goto fail;
    }
    m->x = malloc(3 * (size_t)m->nnodes * sizeof(double));
    if (!m->x) goto nomem;
    int base = -1;
    for (int i = 0; i < m->nnodes; i++) {
        s = next_line(&L);
        k = s ? numbers(s, v, 16) : -1;
        if (k < 4 || !is_int(v[0])) {
            ss_error_set(err, SS_ERR_INPUT, "%s:%d: expected '<id> <x> <y> <z>' for point %d",
                         node_path, L.line, i + 1);
            goto fail;
        }
        if (base < 0) base = (int)v[0];
        if ((int)v[0] != base + i) {
            ss_error_set(err, SS_ERR_INPUT, "%s:%d: point ids must be consecutive (got %g)",
                         node_path, L.line, v[0]);
            goto fail;
        }
        for (int d = 0; d < 3; d++) m->x[3 * i + d] = v[1 + d];
    }
    L = (lines){ele_path, et, 0, {0}};
    s = next_line(&L);
    k = s ? numbers(s, v, 3) : -1;
    if (k < 2 || !is_int(v[0]) || v[0] < 1 || v[0] > 3e8 || v[1] != 4) {
        ss_error_set(err, SS_ERR_INPUT,
                     "%s:%d: expected the header '<#tets> 4 <#attributes>' (4-node tets only)",
                     ele_path, L.line);
        goto fail;
    }
    m->ntets = (int)v[0];
    m->tet = malloc(4 * (size_t)m->ntets * sizeof(int32_t));
    if (!m->tet) goto nomem;
    for (int t = 0; t < m->ntets; t++) {
        s = next_line(&L);
        k = s ? numbers(s, v, 16) : -1;
        if (k < 5) {
            ss_error_set(err, SS_ERR_INPUT, "%s:%d: expected '<id> <n1> <n2> <n3> <n4>'", ele_path,
                         L.line);
            goto fail;
        }
        for (int c = 0; c < 4; c++) {
            double q = v[1 + c] - base;
            if (!is_int(q) || q < 0 || q >= m->nnodes) {
                ss_error_set(err, SS_ERR_INPUT, "%s:%d: node %g is not in %s", ele_path, L.line,
                             v[1 + c], node_path);
                goto fail;
            }
            m->tet[4 * t + c] = (int32_t)q;
        }
    }
    free(nt);
    free(et);
    if (orient_tets(m, ele_path, err) != SS_OK) {
        ss_tetmesh_free(m);
        return NULL;
    }
    return m;
nomem:
    ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", node_path);
fail:
    free(id2);
    free(nt);
    free(et);
    ss_tetmesh_free(m);
    return NULL;
}

ss_tetmesh *ss_tetmesh_read_msh(const char *path, ss_error *err) {
    char *text = ss_read_file_max(path, NULL, SS_READ_MAX_MESH, err);
    if (!text) return NULL;
    ss_tetmesh *m = calloc(1, sizeof *m);
    int32_t *idmap = NULL;
    long maxid = -1;
    lines L = {path, text, 0, {0}};
    const char *s;
    double v[64];
    int have_format = 0, have_nodes = 0, have_elems = 0;
    if (!m) goto nomem;
    while ((s = next_line(&L))) {
        if (!strcmp(s, "$MeshFormat")) {
            s = next_line(&L);
            int k = s ? numbers(s, v, 3) : -1;
            if (k < 1 || v[0] < 2.0 || v[0] >= 3.0 || (k >= 2 && v[1] != 0)) {
                ss_error_set(err, SS_ERR_INPUT,
                             "%s:%d: only Gmsh 2.x ASCII meshes are read (save as "
                             "'Version 2 ASCII')",
                             path, L.line);
                goto fail;
            }
            have_format = 1;
        } else if (!strcmp(s, "$Nodes")) {
            s = next_line(&L);
            int k = s ? numbers(s, v, 1) : -1;
            if (k != 1 || !is_int(v[0]) || v[0] < 4 || v[0] > 5e7) {
                ss_error_set(err, SS_ERR_INPUT, "%s:%d: bad node count", path, L.line);
                goto fail;
            }
            m->nnodes = (int)v[0];
            m->x = malloc(3 * (size_t)m->nnodes * sizeof(double));
            long *ids = malloc((size_t)m->nnodes * sizeof(long));
            if (!m->x || !ids) {
                free(ids);
                goto nomem;
            }
            for (int i = 0; i < m->nnodes; i++) {
                s = next_line(&L);
                k = s ? numbers(s, v, 4) : -1;
                if (k != 4 || !is_int(v[0]) || v[0] < 1 || v[0] > 1e9) {
                    free(ids);
                    ss_error_set(err, SS_ERR_INPUT, "%s:%d: expected '<id> <x> <y> <z>'", path,
                                 L.line);
                    goto fail;
                }
                ids[i] = (long)v[0];
                if (ids[i] > maxid) maxid = ids[i];
                for (int d = 0; d < 3; d++) m->x[3 * i + d] = v[1 + d];
            }
            if (maxid > 4L * m->nnodes + 1000000L) {
                free(ids);
                ss_error_set(err, SS_ERR_INPUT, "%s: node ids up to %ld for %d nodes (too sparse)",
                             path, maxid, m->nnodes);
                goto fail;
            }
            idmap = malloc((size_t)(maxid + 1) * sizeof *idmap);
            if (!idmap) {
                free(ids);
                goto nomem;
            }
            for (long i = 0; i <= maxid; i++) idmap[i] = -1;
            for (int i = 0; i < m->nnodes; i++) {
                if (idmap[ids[i]] >= 0) {
                    ss_error_set(err, SS_ERR_INPUT, "%s: node id %ld appears twice", path, ids[i]);
                    free(ids);
                    goto fail;
                }
                idmap[ids[i]] = i;
            }
            free(ids);
            have_nodes = 1;
        } else if (!strcmp(s, "$Elements")) {
            if (!have_nodes) {
                ss_error_set(err, SS_ERR_INPUT, "%s:%d: $Elements before $Nodes", path, L.line);
                goto fail;
            }
            s = next_line(&L);
            int k = s ? numbers(s, v, 1) : -1;
            if (k != 1 || !is_int(v[0]) || v[0] < 1 || v[0] > 3e8) {
                ss_error_set(err, SS_ERR_INPUT, "%s:%d: bad element count", path, L.line);
                goto fail;
            }
            int ne = (int)v[0], cap = 1024;
            m->tet = malloc(4 * (size_t)cap * sizeof(int32_t));
            if (!m->tet) goto nomem;
            for (int i = 0; i < ne; i++) {
                s = next_line(&L);
                k = s ? numbers(s, v, 64) : -1;
                if (k < 3 || !is_int(v[1]) || !is_int(v[2]) || v[2] < 0 || 3 + v[2] > k) {
                    ss_error_set(err, SS_ERR_INPUT,
                                 "%s:%d: expected '<id> <type> <#tags> <tags...> <nodes...>'", path,
                                 L.line);
                    goto fail;
                }
                if (v[1] != 4) continue; /* not a 4-node tet */
                int off = 3 + (int)v[2];
                if (k != off + 4) {
                    ss_error_set(err, SS_ERR_INPUT, "%s:%d: a tet needs 4 nodes", path, L.line);
                    goto fail;
                }
                if (m->ntets == cap) {
                    cap *= 2;
                    int32_t *nt = realloc(m->tet, 4 * (size_t)cap * sizeof(int32_t));
                    if (!nt) goto nomem;
                    m->tet = nt;
                }
                for (int c = 0; c < 4; c++) {
                    double q = v[off + c];
                    if (!is_int(q) || q < 0 || q > maxid || idmap[(long)q] < 0) {
                        ss_error_set(err, SS_ERR_INPUT, "%s:%d: node %g is not in $Nodes", path,
                                     L.line, q);
                        goto fail;
                    }
                    m->tet[4 * m->ntets + c] = idmap[(long)q];
                }
                m->ntets++;
            }
            have_elems = 1;
        }
    }
    if (!have_format || !have_nodes || !have_elems || m->ntets == 0) {
        ss_error_set(err, SS_ERR_INPUT, "%s: not a Gmsh 2.2 mesh with 4-node tetrahedra%s", path,
                     have_format ? "" : " (no $MeshFormat)");
        goto fail;
    }
    free(text);
    free(idmap);
    if (orient_tets(m, path, err) != SS_OK) {
        ss_tetmesh_free(m);
        return NULL;
    }
    return m;
nomem:
    ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
fail:
    free(text);
    free(idmap);
    ss_tetmesh_free(m);
    return NULL;
}

static int ends_with(const char *s, const char *suf) {
    size_t a = strlen(s), b = strlen(suf);
    return a >= b && !strcmp(s + a - b, suf);
}

ss_tetmesh *ss_tetmesh_read(const char *path, ss_error *err) {
    if (ends_with(path, ".msh")) return ss_tetmesh_read_msh(path, err);
    if (ends_with(path, ".node") || ends_with(path, ".ele")) {
        size_t n = strlen(path);
        size_t stem = n - (ends_with(path, ".node") ? 5 : 4);
        char *a = malloc(stem + 6), *b = malloc(stem + 6);
        if (!a || !b) {
            free(a);
            free(b);
            ss_error_set(err, SS_ERR_NOMEM, "%s: out of memory", path);
            return NULL;
        }
        memcpy(a, path, stem);
        memcpy(b, path, stem);
        strcpy(a + stem, ".node");
        strcpy(b + stem, ".ele");
        ss_tetmesh *m = ss_tetmesh_read_tetgen(a, b, err);
        free(a);
        free(b);
        return m;
    }
    ss_error_set(err, SS_ERR_INPUT, "%s: unknown tet mesh type (expected .msh, .node or .ele)",
                 path);
    return NULL;
}

/* ---- the tetgen program -------------------------------------------------------- */

static int in_path(const char *prog) {
    const char *path = getenv("PATH");
    if (!path) return 0;
    char buf[4096];
    while (*path) {
        const char *c = strchr(path, ':');
        size_t len = c ? (size_t)(c - path) : strlen(path);
        if (len && len + strlen(prog) + 2 < sizeof buf) {
            memcpy(buf, path, len);
            buf[len] = '/';
            strcpy(buf + len + 1, prog);
            if (access(buf, X_OK) == 0) return 1;
        }
        path += len + (c ? 1 : 0);
        if (!c) break;
    }
    return 0;
}

ss_tetmesh *ss_tetmesh_tetgen(const char *surface_path, double max_volume_mm3, ss_error *err) {
    if (!(max_volume_mm3 > 0) || !isfinite(max_volume_mm3)) {
        ss_error_set(err, SS_ERR_INPUT, "tetgen: maximum volume %g mm^3 must be > 0",
                     max_volume_mm3);
        return NULL;
    }
    if (!in_path("tetgen")) {
        ss_error_set(err, SS_ERR_INPUT,
                     "%s: the tetgen program is not installed (apt-get install tetgen), use "
                     "the built-in lattice or bring a .node/.ele or .msh mesh",
                     surface_path);
        return NULL;
    }
    const char *ext = strrchr(surface_path, '.');
    if (!ext || strlen(ext) > 8) {
        ss_error_set(err, SS_ERR_INPUT, "%s: no file extension tetgen knows", surface_path);
        return NULL;
    }
    char *text;
    size_t len;
    if (!(text = ss_read_file_max(surface_path, &len, SS_READ_MAX_MESH, err))) return NULL;
    char dir[] = "/tmp/skinsim-tetgen-XXXXXX";
    if (!mkdtemp(dir)) {
        free(text);
        ss_error_set(err, SS_ERR_RUNTIME, "tetgen: cannot create a temporary directory: %s",
                     strerror(errno));
        return NULL;
    }
    char in[128], node[128], ele[128], sw[64];
    snprintf(in, sizeof in, "%s/in%s", dir, ext);
    snprintf(node, sizeof node, "%s/in.1.node", dir);
    snprintf(ele, sizeof ele, "%s/in.1.ele", dir);
    snprintf(sw, sizeof sw, "-pqa%.9gQ", max_volume_mm3);
    ss_tetmesh *m = NULL;
    ss_status st = ss_write_file_atomic(in, text, len, err);
    free(text);
    if (st == SS_OK) {
        char *argv[] = {"tetgen", sw, in, NULL};
        pid_t pid;
        int status = 0;
        if (posix_spawnp(&pid, "tetgen", NULL, NULL, argv, environ) != 0 ||
            waitpid(pid, &status, 0) < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
            ss_error_set(err, SS_ERR_INPUT, "%s: tetgen %s failed (not a closed surface?)",
                         surface_path, sw);
        else
            m = ss_tetmesh_read_tetgen(node, ele, err);
    }
    ss_remove_tree(dir);
    return m;
}
