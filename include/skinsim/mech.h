/* skinsim mech: wound contraction mechanics of seed 001 (Feess et al.) §4.2,
 * §4.3, §5.2 and §5.3: a tetrahedral mesh of the skin (a lattice
 * tetrahedralisation of the voxel domain, or a TetGen / Gmsh mesh), a
 * mass-spring system on its edges whose rest lengths follow the myofibroblast
 * stress (piecewise-linear p_cell) through the GOH strain energy with two
 * fibre families, relaxed by damped sub-steps to a convergence criterion, and
 * the cubic B-spline coupling to the healing grid (particle velocities to the
 * grid's convection term, grid volumetric strain to the particles).
 * Units: mm, days, kPa (= mN/mm^2), energies in uJ (kPa mm^3). See docs/mech.md. */
#ifndef SKINSIM_MECH_H
#define SKINSIM_MECH_H

#include <stddef.h>
#include <stdint.h>

#include "skinsim/core.h"
#include "skinsim/heal.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- tetrahedral meshes (§5.2) ------------------------------------------- */

typedef struct ss_tetmesh {
    int nnodes, ntets;
    double *x;    /* 3 * nnodes, mm */
    int32_t *tet; /* 4 * ntets node indices, positively oriented */
} ss_tetmesh;

/* Lattice tetrahedralisation of a voxel domain: inside[nx*ny*nz] (index
 * (z*ny + y)*nx + x, voxel centres at (i + 0.5) * dx_mm) is covered by cubes
 * of edge about tet_size_mm (fitted to the domain's bounding box so it is
 * spanned exactly), a cube kept when the voxel at its centre is inside, each
 * cube cut into the 6 tets of the Kuhn (Freudenthal) split around a main
 * diagonal, mirrored in cubes with odd coordinates (symmetric, conforming). Every tet has volume <=
 * edge^3 / 6: this is the maximum-volume constraint of §5.2. */
ss_tetmesh *ss_tetmesh_lattice(const uint8_t *inside, int nx, int ny, int nz, double dx_mm,
                               double tet_size_mm, ss_error *err);
/* TetGen .node + .ele (1- or 0-based, attributes and boundary markers
 * ignored) and Gmsh 2.2 ASCII .msh (element type 4 = 4-node tet; other
 * elements skipped). ss_tetmesh_read picks by extension: .msh, .node or .ele
 * (the sibling with the other extension is read too). Malformed files, bad
 * indices, non-finite coordinates or degenerate tets -> SS_ERR_INPUT naming
 * the file and line. Negatively oriented tets are flipped. */
ss_tetmesh *ss_tetmesh_read_tetgen(const char *node_path, const char *ele_path, ss_error *err);
ss_tetmesh *ss_tetmesh_read_msh(const char *path, ss_error *err);
ss_tetmesh *ss_tetmesh_read(const char *path, ss_error *err);
/* Runs the `tetgen` program (AGPL: only ever called as a program, never
 * linked) on a closed surface (.off, .ply, .stl, .poly, .smesh as tetgen
 * reads them) with quality and the maximum volume constraint max_volume_mm3,
 * in a temporary directory, and reads its .node/.ele. SS_ERR_INPUT when
 * tetgen is not installed (the message says so) or fails. */
ss_tetmesh *ss_tetmesh_tetgen(const char *surface_path, double max_volume_mm3, ss_error *err);
/* Sum of tet volumes (mm^3) and the largest tet volume. */
double ss_tetmesh_volume(const ss_tetmesh *m, double *max_tet_volume);
void ss_tetmesh_free(ss_tetmesh *m);

/* ---- parameters (§4.2, §4.3; values, units, sources in data/heal/mechanics.json) */

typedef struct ss_mech_params {
    /* myofibroblast stress sigma_cell = p_cell(theta) n K_m (§4.2) */
    double K_pas;  /* kPa, passive volumetric stiffness of the contractile element */
    double K_act;  /* kPa, active volumetric stiffness */
    double p_max;  /* kPa, maximal active pressure */
    double theta1; /* 1, shortening strain limit (< 0) */
    double theta2; /* 1, lengthening strain limit (> p_max / K_act) */
    double K_m;    /* 1, enhancement factor */
    /* myofibroblast kinetics (docs/mech.md): the fraction of the wound's
     * fibroblasts that are proto-myofibroblasts (q) and myofibroblasts (m),
     * dq/dt = S (1 - q - m) / tau_proto - q / tau_myo - c q / tau_apo,
     * dm/dt = q / tau_myo - c m / tau_apo, S = g / (g + gf_half) the
     * growth-factor (MDGF, g) stimulus, c the epithelial cover; the stress
     * uses n m. tau_myo = 0 switches the kinetics off: m = 1 - c at once. */
    double tau_myo;     /* days, proto-myofibroblast -> alpha-SMA myofibroblast */
    double tau_proto;   /* days, fibroblast -> proto-myofibroblast at saturating growth factor */
    double gf_half;     /* 1, MDGF level of the half-maximal differentiation stimulus */
    double rho_myo;     /* 1, wound collagen at which maturation runs at half rate (0 = ungated) */
    double tau_apo;     /* days, myofibroblast apoptosis time once the wound is covered */
    double tau_remodel; /* days, lag of the rest lengths behind the pull (0 = none) */
    /* GOH skin (§4.3): Psi = mu/2 (I1bar - 3) + K/2 (J - 1)^2 + sum_i Psi_fi */
    double mu;          /* kPa, ground matrix shear modulus */
    double K_bulk;      /* kPa, ground matrix bulk modulus */
    double k1;          /* kPa, fibre stiffness */
    double k2;          /* 1, fibre nonlinearity */
    double kappa;       /* 1, dispersion in 0..1/3 (0 aligned, 1/3 isotropic) */
    double fibre[2][3]; /* unit vectors a_01, a_02 (a zero second vector = one family) */
    int nfibres;        /* 1 or 2 */
    double ecm_floor;   /* 1, rho_ecm / rho_ecm_hat of fresh clot */
    /* mesh, boundary, solver */
    double tet_size_mm; /* lattice cube edge, mm */
    double anchor;      /* kPa/mm, elastic foundation of the bottom faces (subcutis) */
    double anchor_side; /* kPa/mm, far-field stiffness of the side faces (skin beyond) */
    double k_suture;    /* mN/mm, suture spring stiffness */
    double max_shorten; /* 1, largest relative rest-length change per spring */
    double j_min;       /* 1, volume ratio below which the tet barrier acts (0 = none) */
    double tol;         /* 1, convergence: max residual displacement / edge length */
    int max_substeps;   /* sub-steps per frame at most */
    /* the hyperelastic path (ss_hyper, --mech-model goh; docs/mech.md) */
    int model;               /* SS_MECH_MODEL_SPRINGS (the seed's, default) or SS_MECH_MODEL_GOH */
    double k1_goh;           /* kPa, GOH fibre stiffness of the hyperelastic solver */
    double prestretch;       /* 1, in vivo resting stretch of intact skin along the fibres */
    double k_suture_goh;     /* mN/mm, stitch stiffness on the hyperelastic path */
    double K_m_goh;          /* 1, K_m of the hyperelastic path's in-plane active tension */
    double tau_contract_goh; /* days, lag of that tension behind n m K_m_goh (0 = none) */
} ss_mech_params;
enum { SS_MECH_MODEL_SPRINGS = 0, SS_MECH_MODEL_GOH = 1 };
/* "springs" / "goh" -> *model; anything else SS_ERR_INPUT naming the text. */
ss_status ss_mech_model_parse(const char *text, int *model, ss_error *err);
const char *ss_mech_model_name(int model);

/* The built-in defaults (equal to data/heal/mechanics.json). */
void ss_mech_params_default(ss_mech_params *p);
/* Defaults, then the "mechanics" object of a parameter JSON file of the form
 * {"mechanics": {"K_act": {"value": 1, "unit": "kPa", "source": "..."}, ...}}
 * (other top-level keys are left to the heal parameter reader). Unknown key,
 * missing or wrong unit, non-finite or out-of-range value -> SS_ERR_INPUT naming
 * the key. No "mechanics" object: the defaults. */
ss_status ss_mech_params_parse(ss_mech_params *p, const char *json_text, const char *what,
                               ss_error *err);
/* Sets one parameter from text: a numeric key ("mu", "1e3"), "fibres"
 * ("X,Y,Z[:X,Y,Z]") or "model" ("springs" / "goh"); unknown key, bad number
 * or out-of-range value -> SS_ERR_INPUT naming the key. */
ss_status ss_mech_params_set(ss_mech_params *p, const char *key, const char *value, ss_error *err);
/* Unit of a key ("K_act" -> "kPa"), NULL if unknown. */
const char *ss_mech_param_unit(const char *key);
/* Parses "X,Y,Z[:X,Y,Z]" into p->fibre / p->nfibres (normalised); zero,
 * non-finite or parallel vectors -> SS_ERR_INPUT naming the text. */
ss_status ss_mech_params_set_fibres(ss_mech_params *p, const char *text, ss_error *err);
/* Checks ranges (theta1 < 0 < p_max/K_act < theta2, kappa in 0..1/3, ...). */
ss_status ss_mech_params_check(const ss_mech_params *p, ss_error *err);
/* malloc'd JSON text {"mechanics": {...}} with value + unit for every key. */
char *ss_mech_params_to_json(const ss_mech_params *p);

/* ---- constitutive laws ------------------------------------------------------ */

/* §4.2 piecewise-linear active pressure (kPa) for volumetric strain theta. */
double ss_mech_pcell(const ss_mech_params *p, double theta);
/* §4.3 GOH energy density (kPa) of the right Cauchy-Green tensor C (row-major
 * 3x3): ground (isochoric neo-Hooke + volumetric) in *psi_g, fibre family i
 * with structure tensor H_i = kappa I + (1 - 3 kappa) a_i a_i in psi_f[i].
 * The fibre terms act in tension and compression (see docs/mech.md). */
void ss_mech_goh_energy(const ss_mech_params *p, const double C[9], double *psi_g, double psi_f[2]);
/* §5.2 per-spring energy density (kPa) for the active stress sigma (kPa,
 * > 0 contractile) along the unit spring direction e: the GOH energy of the
 * isotropic contraction sigma drives in the ground matrix (volumetric strain
 * sigma / K_bulk), weighted Psi_g + w_1 Psi_f1 + w_2 Psi_f2 with
 * w_i = kappa + (1 - 3 kappa) |a_i . e| (the seed's |a_i . e| at kappa = 0;
 * the seed prints Psi_f1 twice, the second term is family 2). */
double ss_mech_spring_energy_density(const ss_mech_params *p, double sigma, const double e[3]);
/* Relative rest-length change of a spring whose energy density is psi
 * (Delta l = sqrt(2 Psi_e / k) with Psi_e = V psi, k = 9 K_bulk V / l^2). */
double ss_mech_shortening(const ss_mech_params *p, double psi);

/* ---- mass-spring system (§5.2) ---------------------------------------------- */

typedef struct ss_springs {
    int nnodes, nsprings;
    double *X;      /* 3n reference positions, mm */
    double *x;      /* 3n current positions */
    double *v;      /* 3n sub-step velocities (mm per sub-step) */
    int32_t *e;     /* 2 * nsprings */
    double *l0;     /* reference length */
    double *rest;   /* current rest length */
    double *k;      /* stiffness, mN/mm */
    double *vol;    /* volume share of each spring (mm^3) */
    double *anchor; /* n: foundation stiffness to X (mN/mm), 0 = none */
    uint8_t *fixed; /* n: 1 = held at X */
    /* node -> springs (CSR) for the gather force loop */
    int32_t *adj_start, *adj;
    double *mass; /* n: fictitious mass (dynamic relaxation) */
    double damping;
    /* forces and energy at x, cached between sub-steps; set fvalid = 0 after
     * changing x, rest, k or anchor from outside (ss_springs_relax does) */
    double *f, *f2, *x2, *unode, U;
    double mean_l0; /* cached mean reference edge length */
    int fvalid;
    /* volume barrier (ss_springs_set_barrier; ntets = 0: none): per tet its
     * nodes, its six edge springs, reference and rest volume, the barrier's
     * dE/dV at the last force evaluation, and a flag for tets already folded
     * when a relaxation starts (left out); node -> tets (CSR) */
    int ntets;
    int32_t *tet, *tet_edge, *ntet_start, *ntet;
    double *tvol0, *tvol_rest, *tcoef, *tpart;
    uint8_t *tskip;
    /* the last full tet pass (bar_valid 0: make one at the next force
     * evaluation): its positions; per node how far it may move from them
     * before a tet off the near list can reach jmin; the tets near jmin (in
     * tet order, marked 1 in tmark), always evaluated; per-tet distances
     * and per-node flags (scratch) */
    double *xref, *nsafe, *tdist;
    int32_t *tnear;
    uint8_t *tmark, *nflag;
    int nnear, bar_valid;
    int bar_full_always; /* every evaluation makes the full pass (tests: the reference) */
    long bar_passes[2];  /* full and near passes made (statistics) */
    double kvol, jmin;   /* kPa, barrier modulus; J below which it acts */
} ss_springs;

/* Springs on the unique tet edges; stiffness k = modulus * vol / l0^2 (vol =
 * a sixth of every adjacent tet's volume), rest = l0. */
ss_springs *ss_springs_create(const ss_tetmesh *m, double modulus_kpa, ss_error *err);
void ss_springs_free(ss_springs *s);
/* Adds a spring (sutures); rest length and stiffness given. Rebuilds the CSR. */
ss_status ss_springs_add(ss_springs *s, int a, int b, double rest, double k, ss_error *err);
/* The same for count springs at once (node pairs ab[2i], ab[2i+1]): one CSR
 * rebuild, so many sutures cost linear time. */
ss_status ss_springs_add_many(ss_springs *s, int count, const int32_t *ab, const double *rest,
                              const double *k, ss_error *err);
/* Inversion-resistant volume term: every tet of m (the mesh the springs were
 * made from) gets the energy kvol V_r b(J), J = V / V_r its volume over its
 * rest volume V_r = V_0 sqrt(prod of its six edges' rest / l0) (exact for a
 * uniform shrink), b(J) = -(J - jmin)^2 ln(J / jmin) for 0 < J < jmin and
 * 0 above (the smooth log barrier of incremental potential contact, Li et
 * al. 2020, ACM Trans Graph 39:49): zero where the tet keeps more than jmin
 * of its rest volume, infinite as it flattens, so no accepted sub-step
 * folds a tet (a tet folded when ss_springs_relax starts is left out).
 * Edge springs alone do not resist a tet turning inside out. Call before
 * ss_springs_add. jmin = 0 removes it. */
ss_status ss_springs_set_barrier(ss_springs *s, const ss_tetmesh *m, double kvol, double jmin,
                                 ss_error *err);
/* Rest volumes and folded-tet flags from the current rest lengths and
 * positions (ss_springs_relax calls it; after changing rest from outside,
 * before ss_springs_forces or ss_springs_energy). */
void ss_springs_barrier_update(ss_springs *s);
/* Recomputes fictitious masses after stiffness changes. */
void ss_springs_update_mass(ss_springs *s);
/* Total force on every node (3n, mN) and the potential energy (uJ). */
double ss_springs_forces(ss_springs *s, double *f);
double ss_springs_energy(const ss_springs *s);
double ss_springs_kinetic(const ss_springs *s);
/* One damped sub-step (semi-implicit Euler with fictitious masses, velocity
 * reset when the power turns negative), accepted only if the total energy
 * (potential + kinetic) does not grow; otherwise the momentum is dropped and
 * a gradient step taken, halved until the potential does not grow. Returns
 * the residual: the largest move a gradient step (f_i / m_i) would make at
 * the new positions, divided by the mean edge length. */
double ss_springs_substep(ss_springs *s);
/* Sub-steps until the residual < tol (after at least 2) or max_steps;
 * returns the count (*converged = 1 if tol was met). */
int ss_springs_relax(ss_springs *s, double tol, int max_steps, int *converged);

/* ---- hyperelastic GOH tet solver (docs/mech.md, "The GOH solver") ------------ */

/* The tissue as a continuum on linear tets: per tet the Gasser-Ogden-
 * Holzapfel energy (Gasser, Ogden, Holzapfel 2006) of the elastic part F_e =
 * F G^-1 of the deformation gradient, G the tet's growth / contraction /
 * pre-stretch tensor (multiplicative F = F_e G), plus an active isotropic
 * stress s (kPa, > 0 pulls: Cauchy stress s I, energy s J per reference
 * volume), an elastic foundation per node, dead loads per node and zero- or
 * finite-rest-length springs (sutures). Quasi-static: ss_hyper_solve
 * minimises the energy by Newton's method with the analytic tangent (sparse
 * 3x3-block matrix, conjugate gradients with block-Jacobi plus a coarse
 * correction on aggregates' rigid modes, stopped at negative curvature; the
 * tangent reused while it still converges fast) and a backtracking line search that never accepts a
 * folded tet. Units: mm, kPa, mN, uJ. Bit-identical for any thread count. */
typedef struct ss_hyper ss_hyper;
/* The energy density of one tet's material: W(F_e) = mu/2 (J^-2/3 I1 - 3) +
 * K_bulk/2 (J - 1)^2 + sum_i k1/(2 k2) (exp(k2 E_i^2) - 1) for E_i > 0 (the
 * fibres bear no compression, as in GOH06), E_i = kappa I1 + (1 - 3 kappa) I4_i
 * - 1, I4_i = a_i . C a_i; p gives mu, K_bulk, k1_goh (the fibre stiffness of
 * this solver; k1 is the springs path's), k2, kappa and the fibres. Also P =
 * dW/dF (row-major 3x3, *P may be NULL). Returns W (kPa); J <= 0: INFINITY. */
double ss_hyper_goh_energy(const ss_mech_params *p, const double F[9], double P[9]);
/* The closed-form Cauchy stress of the same law (kPa, row-major):
 * sigma = mu J^-5/3 dev(b) + K (J - 1) I + (2/J) sum_i psi_i' (kappa b + (1 - 3 kappa)
 * (F a_i)(F a_i)), b = F F^T; written from the invariants, independently of
 * the solver's derivative code. */
void ss_hyper_goh_cauchy(const ss_mech_params *p, const double F[9], double sigma[9]);

/* A solver on mesh m (copied) with the material of p. All tets start with
 * G = I, s = 0, full stiffness and fibres on; nodes free at their reference
 * positions. */
ss_hyper *ss_hyper_create(const ss_tetmesh *m, const ss_mech_params *p, ss_error *err);
void ss_hyper_free(ss_hyper *h);
/* on (the default): the two-level preconditioner (block-Jacobi plus a coarse
 * correction on the aggregates' rigid modes) and the tangent reused while
 * Newton converges fast; off: block-Jacobi and a fresh tangent every Newton
 * iteration (the reference the tests compare with). */
void ss_hyper_set_fast(ss_hyper *h, int on);
/* on (the default): changes that keep the result within the Newton
 * tolerance but not its bytes: the per-tet tangents and the matrix of the
 * CG's products in single precision (the gradient, the line search, the
 * sums and the preconditioner stay in double); a predictor, the last
 * solve's change of positions added to the start when the positions are
 * where the last solve left them (if that folds no tet); and a Newton step
 * already under the tolerance taken without the line search's evaluation
 * if it folds no tet (the report's residual is then the one before that
 * step). Off: the solver as it was before them (docs/mech.md, stop 38). */
void ss_hyper_set_tolerant(ss_hyper *h, int on);
int ss_hyper_nodes(const ss_hyper *h);
int ss_hyper_tets(const ss_hyper *h);
/* Current positions (3n, mm): read, or set before a solve (a warm start). */
double *ss_hyper_x(ss_hyper *h);
const double *ss_hyper_X(const ss_hyper *h); /* reference positions */
/* Per tet: growth tensor G (9, row-major, det > 0), active stress s (kPa),
 * stiffness scale c (> 0, multiplies W), fibres on (1) or off (0, e.g. a
 * clot without oriented collagen). */
double *ss_hyper_growth(ss_hyper *h);
double *ss_hyper_active(ss_hyper *h);
/* on != 0: act[t] is the amplitude of an in-plane active tension (the
 * skin's plane, z up) act[t] p_cell(theta) (the seed's cell law,
 * ss_mech_pcell, with the parameters given at create) at the tet's current
 * areal strain theta = J_a - 1 of its total deformation against the
 * reference mesh, evaluated inside the solve (energy, forces, tangent);
 * off (the default): act[t] is a constant isotropic Cauchy stress. */
void ss_hyper_set_active_law(ss_hyper *h, int on);
double *ss_hyper_scale(ss_hyper *h);
uint8_t *ss_hyper_fibres_on(ss_hyper *h);
/* Per node: foundation stiffness to the reference position (mN/mm), dead
 * load (3n, mN), fixed degrees of freedom (3n, 1 = held at its current
 * value). */
double *ss_hyper_anchor(ss_hyper *h);
double *ss_hyper_load(ss_hyper *h);
uint8_t *ss_hyper_fixed(ss_hyper *h);
/* Adds a spring k/2 (|x_b - x_a| - rest)^2 (k mN/mm); returns its index. */
int ss_hyper_add_spring(ss_hyper *h, int a, int b, double rest, double k, ss_error *err);
void ss_hyper_set_spring(ss_hyper *h, int i, double rest, double k);
/* The internal force of the tets (3n, mN: -dE_tets/dx) at the current
 * positions, springs, foundation and loads left out. */
void ss_hyper_tet_forces(ss_hyper *h, double *f);
/* Total potential energy (uJ) at the current positions. */
double ss_hyper_energy(ss_hyper *h);
typedef struct ss_hyper_report {
    int newton, cg;     /* Newton iterations, conjugate-gradient iterations in all */
    int converged;      /* 1: the last Newton step moved no node more than tol * h */
    double max_step_mm; /* largest node move of the last Newton step */
    double residual;    /* largest free-dof force (mN) at the end */
    int predicted;      /* 1: the last solve's change was taken as a first step */
} ss_hyper_report;
/* Newton to the energy minimum from the current positions: stops when a
 * step moves no node more than tol times the mean edge, or after max_newton
 * iterations. SS_ERR_NOMEM only. */
ss_status ss_hyper_solve(ss_hyper *h, double tol, int max_newton, ss_hyper_report *rep,
                         ss_error *err);
/* Volume-weighted mean Cauchy stress (kPa, 9) over all tets, and the current
 * volume (mm^3). */
void ss_hyper_mean_cauchy(ss_hyper *h, double sigma[9], double *volume);

/* ---- the uniaxial material test (`skinsim mech stretch`) ------------------- */

typedef struct ss_mech_stretch_config {
    double stretch;     /* lambda along the axis (> 0) */
    int axis;           /* 0 x, 1 y, 2 z */
    double fibre[3];    /* fibre direction (unit; one family) */
    double size_mm;     /* cube edge of the block (default 4) */
    double tet_size_mm; /* lattice edge (default: p's tet_size_mm) */
    int model;          /* SS_MECH_MODEL_GOH or SS_MECH_MODEL_SPRINGS */
    int increments;     /* load steps (default 10) */
} ss_mech_stretch_config;
typedef struct ss_mech_stretch_result {
    double stress_kpa;          /* axial force on the high end face / current cross-section */
    double analytic_stress_kpa; /* homogeneous uniaxial GOH (lateral tractions zero) */
    double lateral_stretch[2];  /* the block's lateral stretches (the next two axes, cyclic):
                                   distance of opposite lateral faces / reference, mean F */
    double analytic_lateral[2];
    double shear[2]; /* the mean F's F_a1, F_a2: the axial displacement's gradient across */
    double analytic_shear[2];
    double mean_sigma_kpa; /* the volume-weighted Cauchy stress along the axis */
    int nodes, tets, newton, cg, converged;
} ss_mech_stretch_result;
void ss_mech_stretch_config_default(ss_mech_stretch_config *c);
/* Stretches a lattice block of the solver's own mesh, lateral faces free.
 * Tension: a dead load on the end faces (uniform traction along the axis,
 * found by a secant iteration so the faces end lambda apart) and six pins
 * against rigid motion, so the block may shear. Compression: the low face
 * slides on its plane, the high face is moved to lambda. The analytic value
 * solves the same GOH law for the homogeneous state with only the axial
 * Cauchy stress non-zero and F e_axis = lambda e_axis (the state a dead
 * load admits). */
ss_status ss_mech_stretch(const ss_mech_params *p, const ss_mech_stretch_config *c,
                          ss_mech_stretch_result *r, ss_error *err);
/* The analytic part alone: homogeneous uniaxial stretch lambda along the unit
 * vector n, F upper triangular in the frame (n, t1, t2): t1 the coordinate
 * axis after n's largest component (cyclic), made orthogonal to n, t2 = n x
 * t1 (for n = e_x: e_y, e_z). *lateral (2, may be NULL): the stretches
 * across n (distance of the faces normal to t1, t2 over the reference);
 * *shear (2, may be NULL): F_n1, F_n2. */
ss_status ss_mech_uniaxial_analytic(const ss_mech_params *p, const double n[3], double lambda,
                                    double *sigma_kpa, double lateral[2], double shear[2],
                                    ss_error *err);

/* ---- cubic B-spline kernel and grid <-> particle transfer (§5.3) ------------ */

/* The seed's cubic B-spline (1D), support |x| < 2, integral 1. */
double ss_mech_bspline(double x);
/* Kernel width in grid cells w = (N_c / N_m)^(1/3) (at least 1). */
double ss_mech_kernel_width(size_t active_cells, size_t particles);

/* A transfer between a heal grid and particles: the kernel runs on the
 * sub-lattice of every s-th grid cell (s = round(w), so the kernel spans
 * two particle spacings and the weights are a partition of unity that
 * reproduces linear fields); P2G values reach the other cells by trilinear
 * interpolation (exact for linear fields too). */
typedef struct ss_mech_transfer ss_mech_transfer;
ss_mech_transfer *ss_mech_transfer_create(int nx, int ny, int nz, double dx_mm, int stride,
                                          ss_error *err);
void ss_mech_transfer_free(ss_mech_transfer *t);
int ss_mech_transfer_stride(const ss_mech_transfer *t);
/* Interpolates a grid field (nx*ny*nz, NULL-safe mask: cells with mask 0 are
 * skipped and the weights renormalised) at np points (3np, mm). */
void ss_mech_g2p(const ss_mech_transfer *t, const float *field, const uint8_t *mask,
                 const double *pts, int np, double *out);
/* Splats ncomp-component particle values (val[p*ncomp + c]) with their
 * gradients (grad[(p*ncomp + c)*3 + d], d/dx_d per mm; NULL = 0) to the grid:
 * v_I = sum_p phi_Ip (v_p + G_p (x_I - x_p)) / sum_p phi_Ip on the sub-lattice,
 * trilinear in between; cells with mask 0 (or no particle within reach) get 0.
 * out[c] are nx*ny*nz floats each. */
void ss_mech_p2g(ss_mech_transfer *t, const double *pts, int np, const double *val,
                 const double *grad, int ncomp, const uint8_t *mask, float **out);
/* Divergence (1/mm) of a grid vector field by central differences on the
 * sub-lattice, trilinear in between (the volumetric strain of a displacement). */
void ss_mech_divergence(ss_mech_transfer *t, float *const u[3], const uint8_t *mask, float *out);

/* ---- the coupled mechanics (§5.1-5.3) --------------------------------------- */

typedef struct ss_mech ss_mech;

typedef struct ss_mech_suture {
    double a[3], b[3]; /* mm, stitched points */
    double remove_day; /* the stitch is taken out at this day (inf = never) */
} ss_mech_suture;
/* CSV lines "x1,y1,z1,x2,y2,z2[,remove_day]" in mm (a header line and # comments
 * allowed). *n gets the count; malformed -> SS_ERR_INPUT naming the line. */
#define SS_MECH_MAX_SUTURES 10000 /* more stitches in a file is SS_ERR_INPUT */
ss_mech_suture *ss_mech_sutures_read(const char *path, int *n, ss_error *err);

/* Mechanics on a healing grid: the tissue cells (epidermis, dermis, wound) are
 * meshed by the lattice (mesh NULL) or the given mesh is used (its nodes must
 * lie in the grid's tissue). heal gives the healthy fibroblast level. The
 * grid's velocity arrays are allocated (zero) if absent. Sutures whose points
 * are farther than 1.5 tet edges (the grip, docs/mech.md) from the mesh ->
 * SS_ERR_INPUT. */
ss_mech *ss_mech_create(ss_heal_grid *g, const ss_heal_params *heal, const ss_mech_params *p,
                        const ss_tetmesh *mesh, const ss_mech_suture *sutures, int nsutures,
                        ss_error *err);
void ss_mech_free(ss_mech *m);
/* One frame over dt_days ending at g->t_days: samples the myofibroblast
 * density (n above its healthy level), the grid volumetric strain and
 * rho_ecm at the spring ends, sets rest lengths, relaxes, and writes the
 * particle velocities (mm/day) to g->velocity and the displacement to the
 * mechanics' own grid arrays. */
ss_status ss_mech_step(ss_mech *m, ss_heal_grid *g, double dt_days, ss_error *err);

typedef struct ss_mech_stats {
    int substeps, converged; /* of the last frame (all its load increments) */
    int increments;          /* load increments of the last frame (1; more after a fold) */
    double max_speed_mm_day; /* largest particle speed of the last frame */
    double outline_area_mm2; /* initial wound outline, deformed, projected on x,y */
    double initial_outline_area_mm2;
    double extent_x_mm, extent_y_mm; /* of the deformed outline */
    double principal[2];             /* unit major axis of the deformed outline (x,y) */
    double aspect_major_minor;       /* sqrt of the covariance eigenvalue ratio */
    int inverted_tets;               /* tets with non-positive volume now (folds) */
    double side_max_disp_mm;         /* largest displacement of a side-face node */
    double myofibroblast_fraction;   /* mean m over the nodes under the initial wound */
} ss_mech_stats;
void ss_mech_stats_compute(const ss_mech *m, ss_mech_stats *st);
/* Tets whose current signed volume is not positive (folded). */
int ss_mech_inverted_tets(const ss_mech *m);

/* Access for output and checkpoints. */
const ss_tetmesh *ss_mech_mesh(const ss_mech *m);    /* reference mesh */
const double *ss_mech_positions(const ss_mech *m);   /* 3n current, mm */
const double *ss_mech_velocities(const ss_mech *m);  /* 3n, mm/day, last frame */
const double *ss_mech_node_stress(const ss_mech *m); /* n, active stress kPa */
/* The displacement on the grid (3 arrays, mm), upsampled on call; NULL
 * when out of memory. */
float *const *ss_mech_grid_displacement(ss_mech *m);
/* Flat state for checkpoints: positions, velocities, rest lengths, stress,
 * grid displacement; model goh adds per tet the rest state G and the lagged
 * active tension. size in bytes; set returns SS_ERR_INPUT on a size mismatch
 * (a goh state without the lagged tension, written before it existed, is
 * refused with a message that says so). */
size_t ss_mech_state_size(const ss_mech *m);
void ss_mech_state_get(const ss_mech *m, void *buf);
ss_status ss_mech_state_set(ss_mech *m, const void *buf, size_t size, ss_error *err);
/* After state_set: rebuilds the displacement and strain from the restored
 * particles, exactly as the step that saved them left them; the grid's
 * velocity is kept when it has one (restored with it), else rebuilt. */
ss_status ss_mech_state_apply(ss_mech *m, ss_heal_grid *g, ss_error *err);
/* Kernel width w = (N_c/N_m)^(1/3) in cells and the sub-lattice stride used. */
double ss_mech_kernel(const ss_mech *m, int *stride);

/* ---- outputs ------------------------------------------------------------------ */

/* VTK XML UnstructuredGrid of the deformed tet mesh with point data
 * displacement, velocity (mm/day) and stress (kPa). Atomic. */
ss_status ss_mech_vtu_write(const ss_mech *m, const char *path, double t_days, ss_error *err);
/* Top view like Fig. 7: the deformed top surface seen from +z, coloured by
 * speed on blue-cyan-green-yellow-red (0 .. vmax mm/day; vmax <= 0 = the
 * frame's maximum), the deformed wound outline in white. Linear RGB image,
 * px pixels on the longer side. */
ss_image *ss_mech_top_view(const ss_mech *m, int px, double vmax, ss_error *err);
/* The same view with a colour bar on its right, labelled 0, vmax / 2 and vmax
 * mm/day (vmax <= 0: the frame's largest speed). */
ss_image *ss_mech_top_view_bar(const ss_mech *m, int px, double vmax, ss_error *err);

#ifdef __cplusplus
}
#endif
#endif
