/*
 * Shared fixtures of the linear-algebra tests: a seeded xorshift64* random
 * generator (deterministic and platform independent, so the random test
 * matrices are the same everywhere) and the dense reference solver.
 */
#ifndef CF_TESTS_LINALG_TEST_UTIL_H
#define CF_TESTS_LINALG_TEST_UTIL_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static uint64_t lat_rng_state;

static inline void rng_seed(uint64_t s) { lat_rng_state = s * 0x9E3779B97F4A7C15ull + 1; }

/* Uniform in (-1, 1) with 53 random bits. */
static inline double rng_unit(void)
{
    lat_rng_state ^= lat_rng_state >> 12;
    lat_rng_state ^= lat_rng_state << 25;
    lat_rng_state ^= lat_rng_state >> 27;
    return ((double)((lat_rng_state * 0x2545F4914F6CDD1Dull) >> 11) + 0.5) / 9007199254740992.0 * 2.0 - 1.0;
}

/* Dense Gaussian elimination with partial pivoting: the reference solver.
 * a_in is n x n column-major and is not modified. */
static inline void dense_solve(int32_t n, const double *a_in, const double *b, double *x)
{
    double *a = malloc((size_t)n * n * sizeof *a);
    memcpy(a, a_in, (size_t)n * n * sizeof *a);
    memcpy(x, b, (size_t)n * sizeof *x);
    for (int32_t k = 0; k < n; ++k) {
        int32_t piv = k;
        for (int32_t i = k + 1; i < n; ++i)
            if (fabs(a[(size_t)k * n + i]) > fabs(a[(size_t)k * n + piv])) piv = i;
        for (int32_t j = 0; j < n; ++j) {
            double t = a[(size_t)j * n + k]; a[(size_t)j * n + k] = a[(size_t)j * n + piv]; a[(size_t)j * n + piv] = t;
        }
        double t = x[k]; x[k] = x[piv]; x[piv] = t;
        for (int32_t i = k + 1; i < n; ++i) {
            double f = a[(size_t)k * n + i] / a[(size_t)k * n + k];
            for (int32_t j = k; j < n; ++j) a[(size_t)j * n + i] -= f * a[(size_t)j * n + k];
            x[i] -= f * x[k];
        }
    }
    for (int32_t i = n - 1; i >= 0; --i) {
        double s = x[i];
        for (int32_t j = i + 1; j < n; ++j) s -= a[(size_t)j * n + i] * x[j];
        x[i] = s / a[(size_t)i * n + i];
    }
    free(a);
}

#endif /* CF_TESTS_LINALG_TEST_UTIL_H */
