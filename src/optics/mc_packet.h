/* The vector half of the packet path of src/optics/mc.c (seed 003 §4.4; issue
 * 28): PK_W = 4 photons advanced together in structure-of-arrays lanes, one
 * hop-drop-spin event per lane per step, without branches (masks and blends).
 * Boundary crossings, roulette, launches and tallies that scatter into arrays
 * run per lane in mc.c's scalar helpers. Included twice by mc.c: once under
 * `#pragma GCC target("avx2")` and once for the x86-64 baseline (SSE2; GCC
 * splits each 4-wide operation in two), with PK_SUFFIX naming the copy. Both
 * copies perform the same IEEE operations in the same order (no FMA
 * contraction: the avx2 target has no fma, and mc.c is built with
 * -ffp-contract=off), so they give bit-identical results.
 *
 * Needs from mc.c: pk_vd / pk_vl / pk_vu (4-lane double, int64, uint64
 * vectors), pk_state, the per-lane helpers pk_boundary, pk_roulette,
 * pk_fill, pk_phase_fix and PK_SEL. */

#define PK_CAT2(a, b) a##b
#define PK_CAT(a, b) PK_CAT2(a, b)
#define PK(name) PK_CAT(name, PK_SUFFIX)

static inline pk_vd PK(pk_sqrt)(pk_vd a) {
#if defined(__AVX__)
    return (pk_vd)_mm256_sqrt_pd((__m256d)a);
#elif defined(__SSE2__)
    __m128d h[2];
    memcpy(h, &a, sizeof h);
    h[0] = _mm_sqrt_pd(h[0]);
    h[1] = _mm_sqrt_pd(h[1]);
    memcpy(&a, h, sizeof h);
    return a;
#else
    for (int k = 0; k < PK_W; k++) a[k] = sqrt(a[k]);
    return a;
#endif
}

/* Lane-wise a < b and a == b as masks (all ones / zero). Written with the
 * target's compare instructions: GCC lowers a 4-wide double compare to
 * per-lane branches when the target has no 256-bit compare (the baseline). */
static inline pk_vl PK(pk_lt)(pk_vd a, pk_vd b) {
#if defined(__AVX__)
    return (pk_vl)_mm256_cmp_pd((__m256d)a, (__m256d)b, _CMP_LT_OQ);
#elif defined(__SSE2__)
    __m128d x[2], y[2];
    memcpy(x, &a, sizeof x);
    memcpy(y, &b, sizeof y);
    x[0] = _mm_cmplt_pd(x[0], y[0]);
    x[1] = _mm_cmplt_pd(x[1], y[1]);
    pk_vl r;
    memcpy(&r, x, sizeof r);
    return r;
#else
    return a < b;
#endif
}
static inline pk_vl PK(pk_eq)(pk_vd a, pk_vd b) {
#if defined(__AVX__)
    return (pk_vl)_mm256_cmp_pd((__m256d)a, (__m256d)b, _CMP_EQ_OQ);
#elif defined(__SSE2__)
    __m128d x[2], y[2];
    memcpy(x, &a, sizeof x);
    memcpy(y, &b, sizeof y);
    x[0] = _mm_cmpeq_pd(x[0], y[0]);
    x[1] = _mm_cmpeq_pd(x[1], y[1]);
    pk_vl r;
    memcpy(&r, x, sizeof r);
    return r;
#else
    return a == b;
#endif
}
#define PK_LT(a, b) PK(pk_lt)((a), (b))
#define PK_B(x) ((pk_vd){0} + (x)) /* broadcast */

static inline pk_vu PK(pk_rotl)(pk_vu x, int k) { return (x << k) | (x >> (64 - k)); }

/* xoroshiro128++ on every lane (the scalar prng_next, lane-wise). */
static inline pk_vu PK(pk_next)(pk_state *P) {
    const pk_vu s0 = P->s0;
    pk_vu s1 = P->s1;
    const pk_vu out = PK(pk_rotl)(s0 + s1, 17) + s0;
    s1 ^= s0;
    P->s0 = PK(pk_rotl)(s0, 49) ^ s1 ^ (s1 << 21);
    P->s1 = PK(pk_rotl)(s1, 28);
    return out;
}

/* Integer k < 2^52 (as uint64 lanes) to double, exactly: the bits of 2^52 + k
 * minus 2^52 (there is no int64 -> double vector conversion before AVX-512). */
static inline pk_vd PK(pk_u2d)(pk_vu k, double off) {
    return (pk_vd)(k | 0x4330000000000000ull) - (4503599627370496.0 + off);
}

/* Natural logarithm of positive normal doubles: the reduction and the
 * polynomial of fdlibm's e_log.c (Sun Microsystems 1993; log(1+f) = f - hfsq
 * + s (hfsq + R(s^2)), s = f / (2 + f), R a degree-14 even minimax
 * polynomial, error below 1 ulp) written lane-wise without branches; mc.c's
 * pk_log1 is the same sequence of operations on one double. */
static inline pk_vd PK(pk_log)(pk_vd x) {
    const double ln2_hi = 6.93147180369123816490e-01, ln2_lo = 1.90821492927058770002e-10;
    const double Lg1 = 6.666666666666735130e-01, Lg2 = 3.999999999940941908e-01,
                 Lg3 = 2.857142874366239149e-01, Lg4 = 2.222219843214978396e-01,
                 Lg5 = 1.818357216161805012e-01, Lg6 = 1.531383769920937332e-01,
                 Lg7 = 1.479819860511658591e-01;
    pk_vu b = (pk_vu)x;
    pk_vu e = b >> 52;
    pk_vd m = (pk_vd)((b & 0x000fffffffffffffull) | 0x3ff0000000000000ull); /* [1, 2) */
    pk_vl big = PK_LT(PK_B(1.41421356237309504880), m);
    m = PK_SEL(big, m * 0.5, m);
    e += (pk_vu)big & 1u;
    pk_vd k = PK(pk_u2d)(e, 1023.0);
    pk_vd f = m - 1.0;
    pk_vd s = f / (2.0 + f), z = s * s, w = z * z;
    pk_vd t1 = w * (Lg2 + w * (Lg4 + w * Lg6));
    pk_vd t2 = z * (Lg1 + w * (Lg3 + w * (Lg5 + w * Lg7)));
    pk_vd R = t2 + t1, hfsq = 0.5 * f * f;
    return k * ln2_hi - ((hfsq - (s * (hfsq + R) + k * ln2_lo)) - f);
}

/* Uniform azimuth (cos, sin) of 2 pi u from the low 32 bits of each lane:
 * fast_azimuth of mc.c lane-wise (same quadrant split, same series). */
static inline void PK(pk_azimuth)(pk_vu bits, pk_vd *cp, pk_vd *sp) {
    pk_vu q = (bits >> 30) & 3u;
    pk_vd f = PK(pk_u2d)(bits & 0x3fffffffu, -0.5) * (1.0 / 1073741824.0);
    pk_vd a = (f - 0.5) * (M_PI / 2), a2 = a * a;
    pk_vd ca = AZ_COS_SERIES(a2), sa = AZ_SIN_SERIES(a, a2);
    const double h = 0.70710678118654752440;
    pk_vd c = h * (ca - sa), s = h * (ca + sa);
    /* quadrants 1 and 3: (c, s) -> (-s, c) then 2 and 3 negate both */
    pk_vl odd = (pk_vl)(0u - (q & 1u));
    pk_vd c1 = PK_SEL(odd, -s, c), s1 = PK_SEL(odd, c, s);
    pk_vu neg = (q & 2u) << 62;
    *cp = (pk_vd)((pk_vu)c1 ^ neg);
    *sp = (pk_vd)((pk_vu)s1 ^ neg);
}

/* Lane k's mask (all ones or zero) as bit k. */
static inline int PK(pk_bits)(pk_vl m) {
#if defined(__AVX__)
    return _mm256_movemask_pd((__m256d)m);
#elif defined(__SSE2__)
    __m128d h[2];
    memcpy(h, &m, sizeof h);
    return _mm_movemask_pd(h[0]) | _mm_movemask_pd(h[1]) << 2;
#else
    int r = 0;
    for (int k = 0; k < PK_W; k++) r |= (m[k] != 0) << k;
    return r;
#endif
}

/* Runs photons [lo, hi) of one block into a (and pb). */
static void PK(pk_run_block)(const mc_ctx *c, uint64_t lo, uint64_t hi, mc_acc *a, path_buf *pb) {
    pk_state P;
    pk_state_init(&P);
    uint64_t next = lo;
    for (int k = 0; k < PK_W; k++) pk_fill(c, a, pb, &P, k, &next, hi);
    const int track = c->paths, hdist = c->path_dist, mcml = c->spec.mcml;
    const pk_vd zero = {0, 0, 0, 0};
    while (PK(pk_bits)(P.live)) {
        /* ---- hop: a fresh optical depth where the last one was spent ---- */
        pk_vu r1 = PK(pk_next)(&P), r2 = PK(pk_next)(&P);
        pk_vd u1 = (pk_vd)((r1 >> 12) | 0x3ff0000000000000ull) - (1.0 - 0x1p-53); /* (0,1) */
        /* each lane keeps its next optical depth ready (drawn a step ahead, or
         * at launch), so the logarithm's latency is off the critical path */
        pk_vd tn = -PK(pk_log)(u1);
        P.tau = PK_SEL(P.need, P.tnext, P.tau);
        P.tnext = PK_SEL(P.need, tn, P.tnext);
        /* interaction before the boundary: s |uz| < |z_b - z| with s = tau / mut
         * (the scalar test tau < mut (z_b - z) / uz without its division);
         * a clear layer (mut = 0) has no interaction */
        pk_vd uz = P.uz;
        pk_vl up = PK_LT(zero, uz);
        pk_vd s = P.tau * P.linv;
        pk_vd gap = PK_SEL(up, P.lz1 - P.z, P.z - P.lz0), auz = PK_SEL(up, uz, -uz);
        pk_vl inside = (PK_LT(s * auz, gap) | PK(pk_eq)(auz, zero)) & PK_LT(zero, P.lmut);
        pk_vl hit = ~inside & P.live;
        pk_vl act = inside & P.live;
        s = PK_SEL(act, s, zero);
        P.x += s * P.ux;
        P.y += s * P.uy;
        P.z += s * uz;
        if (track) P.seg += s;
        if (hdist) P.hp += s * PK(pk_sqrt)(P.ux * P.ux + P.uy * P.uy);
        P.need = act;

        /* ---- drop ---- */
        pk_vd dw = PK_SEL(act, P.w * P.labs, zero);
        P.w -= dw;
        P.absacc += dw;
        pk_vi iz = {0}, ir = {0};
        if (mcml) { /* A(r, z): the bins of mcml_absorb, lane-wise; the adds per lane */
            const double nzd = c->spec.nz, nrd = c->spec.rad_n;
            pk_vd rq = PK(pk_sqrt)(P.x * P.x + P.y * P.y) * c->inv_dr, zq = P.z * c->inv_dz;
            zq = PK_SEL(PK_LT(zq, PK_B(nzd)), zq, zero + (nzd - 1.0));
            zq = PK_SEL(PK_LT(zq, zero), zero, zq);
            rq = PK_SEL(PK_LT(rq, PK_B(nrd)), rq, zero + (nrd - 1.0));
            iz = __builtin_convertvector(zq, pk_vi);
            ir = __builtin_convertvector(rq, pk_vi);
        }

        /* ---- spin: Henyey-Greenstein (tabulated phase functions per lane) ---- */
        pk_vd u = PK(pk_u2d)(r2 >> 32, -0.5) * (1.0 / 4294967296.0);
        pk_vd t = P.hgb / (P.hg1mg + P.hg2g * u);
        pk_vd cost = P.hgc * (P.hga - t * t);
        cost = PK_SEL(PK_LT(cost, PK_B(-1.0)), zero - 1.0, cost);
        cost = PK_SEL(PK_LT(PK_B(1.0), cost), zero + 1.0, cost);
        cost = PK_SEL(P.iso, 2.0 * u - 1.0, cost);
        int tm = PK(pk_bits)(P.tab & act);
        if (tm)
            for (int k = 0; k < PK_W; k++)
                if (tm >> k & 1) cost[k] = pk_phase_fix(c, P.layer[k], u[k]);
        pk_vd sint = PK(pk_sqrt)(1.0 - cost * cost), cp, sp;
        PK(pk_azimuth)(r2, &cp, &sp);
        pk_vd ux = P.ux, uy = P.uy;
        pk_vd tmp = PK(pk_sqrt)(1.0 - uz * uz), inv = 1.0 / tmp;
        pk_vd nx = sint * (ux * uz * cp - uy * sp) * inv + ux * cost;
        pk_vd ny = sint * (uy * uz * cp + ux * sp) * inv + uy * cost;
        pk_vd nz = -sint * cp * tmp + uz * cost;
        pk_vl pole = PK_LT(PK_B(1.0 - 1e-12), uz) | PK_LT(uz, PK_B(-(1.0 - 1e-12)));
        nx = PK_SEL(pole, sint * cp, nx);
        ny = PK_SEL(pole, sint * sp, ny);
        nz = PK_SEL(pole, PK_SEL(up, cost, -cost), nz);
        P.ux = PK_SEL(act, nx, ux);
        P.uy = PK_SEL(act, ny, uy);
        P.uz = PK_SEL(act, nz, uz);

        if (mcml) {
            int am = PK(pk_bits)(act);
            for (int k = 0; k < PK_W; k++)
                if (am >> k & 1) a->a_rz[(size_t)ir[k] * c->spec.nz + (size_t)iz[k]] += dw[k];
        }

        /* ---- roulette, then the lanes that reached a boundary ---- */
        int rm = PK(pk_bits)(act & PK_LT(P.w, PK_B(1e-4)));
        int hm = PK(pk_bits)(hit);
        if (rm | hm) {
            for (int k = 0; k < PK_W; k++) {
                int alive = 1;
                if (rm >> k & 1)
                    alive = pk_roulette(a, &P, k);
                else if (hm >> k & 1)
                    alive = pk_boundary(c, a, pb, &P, k);
                if (!alive) {
                    pk_finish(a, &P, k);
                    pk_fill(c, a, pb, &P, k, &next, hi);
                }
            }
        }
    }
}

#undef PK_LT
#undef PK_B
#undef PK
#undef PK_CAT
#undef PK_CAT2
