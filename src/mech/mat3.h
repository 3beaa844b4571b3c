/* mat3.h -- 3x3 helpers shared by the hyperelastic solver and the stretch
 * test (row-major double[9]); header-only so the solver's per-tet loops
 * keep them inlined. */
#ifndef SKINSIM_MECH_MAT3_H
#define SKINSIM_MECH_MAT3_H

/* The cofactor matrix of A (J A^-T = c); returns det A (expanded along the
 * first row, the same floats as the explicit formula). */
static inline double mat3_cofactors(const double A[9], double c[9]) {
    c[0] = A[4] * A[8] - A[5] * A[7];
    c[1] = A[5] * A[6] - A[3] * A[8];
    c[2] = A[3] * A[7] - A[4] * A[6];
    c[3] = A[2] * A[7] - A[1] * A[8];
    c[4] = A[0] * A[8] - A[2] * A[6];
    c[5] = A[1] * A[6] - A[0] * A[7];
    c[6] = A[1] * A[5] - A[2] * A[4];
    c[7] = A[2] * A[3] - A[0] * A[5];
    c[8] = A[0] * A[4] - A[1] * A[3];
    return A[0] * c[0] + A[1] * c[1] + A[2] * c[2];
}

#endif
