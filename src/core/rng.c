/* Counter-based random numbers: Philox4x32-10 (Salmon et al., SC'11). The key
 * is the 64-bit seed, the 128-bit counter is (index, stream), so any draw can be
 * computed independently, which makes every output independent of thread count. */
#include "skinsim/core.h"

static inline void philox_round(uint32_t ctr[4], const uint32_t key[2]) {
    const uint64_t p0 = (uint64_t)0xD2511F53u * ctr[0];
    const uint64_t p1 = (uint64_t)0xCD9E8D57u * ctr[2];
    uint32_t hi0 = (uint32_t)(p0 >> 32), lo0 = (uint32_t)p0;
    uint32_t hi1 = (uint32_t)(p1 >> 32), lo1 = (uint32_t)p1;
    uint32_t n0 = hi1 ^ ctr[1] ^ key[0];
    uint32_t n2 = hi0 ^ ctr[3] ^ key[1];
    ctr[0] = n0;
    ctr[1] = lo1;
    ctr[2] = n2;
    ctr[3] = lo0;
}

void ss_rng4(uint64_t seed, uint64_t stream, uint64_t index, uint32_t out[4]) {
    uint32_t key[2] = {(uint32_t)seed, (uint32_t)(seed >> 32)};
    uint32_t ctr[4] = {(uint32_t)index, (uint32_t)(index >> 32), (uint32_t)stream,
                       (uint32_t)(stream >> 32)};
    for (int r = 0; r < 10; r++) {
        philox_round(ctr, key);
        key[0] += 0x9E3779B9u;
        key[1] += 0xBB67AE85u;
    }
    for (int i = 0; i < 4; i++) out[i] = ctr[i];
}

uint32_t ss_rng_u32(uint64_t seed, uint64_t stream, uint64_t index) {
    uint32_t o[4];
    ss_rng4(seed, stream, index, o);
    return o[0];
}

static double u53(uint32_t a, uint32_t b) {
    return (double)(((uint64_t)a << 21) ^ (uint64_t)(b >> 11)) * (1.0 / 9007199254740992.0);
}

double ss_rng_uniform(uint64_t seed, uint64_t stream, uint64_t index) {
    uint32_t o[4];
    ss_rng4(seed, stream, index, o);
    return u53(o[0], o[1]);
}

void ss_rng_seq_init(ss_rng_seq *r, uint64_t seed, uint64_t stream) {
    r->seed = seed;
    r->stream = stream;
    r->counter = 0;
    r->left = 0;
}

uint32_t ss_rng_seq_u32(ss_rng_seq *r) {
    if (r->left == 0) {
        ss_rng4(r->seed, r->stream, r->counter++, r->buf);
        r->left = 4;
    }
    return r->buf[4 - r->left--];
}

double ss_rng_seq_uniform(ss_rng_seq *r) {
    uint32_t a = ss_rng_seq_u32(r), b = ss_rng_seq_u32(r);
    return u53(a, b);
}

double ss_rng_seq_uniform_open(ss_rng_seq *r) {
    double u;
    do u = ss_rng_seq_uniform(r);
    while (u == 0.0);
    return u;
}

/* Draws first .. first+n-1 into u (raw) or f (24-bit floats in [0,1)):
 * Philox block k/4, lane k%4, so any sub-range gives the same values. */
static void fill(uint64_t seed, uint64_t stream, uint64_t first, size_t n, uint32_t *u, float *f) {
    if (n == 0) return;
    const uint64_t b0 = first / 4, b1 = (first + n - 1) / 4;
#pragma omp parallel for schedule(static)
    for (uint64_t b = b0; b <= b1; b++) {
        uint32_t o[4];
        ss_rng4(seed, stream, b, o);
        for (int lane = 0; lane < 4; lane++) {
            uint64_t k = b * 4 + (uint64_t)lane;
            if (k < first || k >= first + n) continue;
            if (u)
                u[k - first] = o[lane];
            else
                f[k - first] = (float)(o[lane] >> 8) * 0x1p-24f;
        }
    }
}

void ss_rng_fill_u32(uint64_t seed, uint64_t stream, uint64_t first, uint32_t *out, size_t n) {
    fill(seed, stream, first, n, out, NULL);
}

void ss_rng_fill_f32(uint64_t seed, uint64_t stream, uint64_t first, float *out, size_t n) {
    fill(seed, stream, first, n, NULL, out);
}
