/* cf_inverse_iteration_blocks / cf_rayleigh_quotient_blocks /
 * cf_normalize_blocks: block masses
 * agree with the same masses repeated per component (cf_inverse_iteration_step,
 * cf_rayleigh_quotient), the normalisation target is met, the iteration finds
 * the smallest eigenpair of a known spectrum, and bad input is refused. */
#include "curvflow/linalg.h"
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

/* Path-graph Laplacian of nb nodes (Neumann ends) lifted to blocks of b:
 * L kron I_b, plus a diagonal mass; eigenvalues of M^-1 L with uniform M = m
 * are (2 - 2 cos(pi k / nb)) / m, each b times. */
static cf_sparse *path_laplacian(cf_context *ctx, int32_t nb, int32_t b, double shift_mass, const double *mass)
{
    int64_t cap = 3 * (int64_t)nb * b;
    int32_t *r = malloc((size_t)cap * sizeof(int32_t)), *c = malloc((size_t)cap * sizeof(int32_t));
    double *v = malloc((size_t)cap * sizeof(double));
    int64_t n = 0;
    for (int32_t i = 0; i < nb; ++i) {
        int32_t deg = (i > 0) + (i < nb - 1);
        for (int32_t k = 0; k < b; ++k) {
            r[n] = c[n] = b * i + k;
            v[n++] = deg + shift_mass * mass[i];
            if (i > 0) r[n] = b * i + k, c[n] = b * (i - 1) + k, v[n++] = -1.0;
            if (i < nb - 1) r[n] = b * i + k, c[n] = b * (i + 1) + k, v[n++] = -1.0;
        }
    }
    cf_sparse *a = NULL;
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, nb * b, nb * b, n, r, c, v, 1, &a, NULL));
    free(r);
    free(c);
    free(v);
    return a;
}

static void test_blocks_match_repeated_masses(void)
{
    cf_context *ctx = cft_context();
    const int32_t nb = 40, b = 4, n = nb * b;
    double mass[40], mrep[160], v1[160], v2[160], w[160];
    for (int32_t i = 0; i < nb; ++i) mass[i] = 0.5 + 0.02 * (double)((i * 7) % 11);
    for (int32_t i = 0; i < n; ++i) mrep[i] = mass[i / b];
    double eps = 1e-3;
    cf_sparse *a = path_laplacian(ctx, nb, b, eps, mass), *l = path_laplacian(ctx, nb, b, 0.0, mass);
    cf_cholesky_options co;
    cf_cholesky_options_default(&co);
    co.block_size = b;
    cf_cholesky *chol = NULL;
    CHECK_OK(ctx, cf_cholesky_create(ctx, a, &co, &chol));
    CHECK_OK(ctx, cf_cholesky_factorize(chol, a));
    for (int32_t i = 0; i < n; ++i) v1[i] = v2[i] = 1.0 + 0.3 * sin(0.37 * i) + (i % b == 0 ? 1.0 : 0.0);
    double total = 0.0;
    for (int32_t i = 0; i < nb; ++i) total += mass[i];
    CHECK_OK(ctx, cf_inverse_iteration_blocks(chol, mass, b, 3, total, v1, w));
    int32_t rank = 0;
    for (int it = 0; it < 3; ++it) CHECK_OK(ctx, cf_inverse_iteration_step(chol, mrep, 1, v2, w, &rank));
    CHECK(rank == 1);
    /* same direction; the blocks variant scaled to sum m |v|^2 = total, the other to 1 */
    double n2 = 0.0, diff = 0.0, s = sqrt(total);
    for (int32_t i = 0; i < n; ++i) n2 += mrep[i] * v1[i] * v1[i];
    CHECK_NEAR(n2, total, 1e-14, 0.0);
    for (int32_t i = 0; i < n; ++i) diff = fmax(diff, fabs(v1[i] - s * v2[i]));
    CHECK_LE(diff, 1e-12);
    CHECK_NEAR(cf_rayleigh_quotient_blocks(l, mass, b, v1, w), cf_rayleigh_quotient(l, mrep, v1, w), 1e-13, 0.0);
    /* zero iterations leave v alone */
    memcpy(v2, v1, sizeof v1);
    CHECK_OK(ctx, cf_inverse_iteration_blocks(chol, mass, b, 0, total, v1, w));
    CHECK(memcmp(v1, v2, sizeof v1) == 0);
    cf_cholesky_destroy(&chol);
    cf_sparse_destroy(&a);
    cf_sparse_destroy(&l);
    cf_context_destroy(&ctx);
}

/* With a uniform mass m and shift s, iterating from a generic start converges to
 * the constant block vectors (eigenvalue 0 of L); from a start antisymmetric
 * about the middle (no constant part) to the first nonzero eigenvalue
 * (2 - 2 cos(pi / nb)) / m. */
static void test_converges_to_known_eigenvalue(void)
{
    cf_context *ctx = cft_context();
    const int32_t nb = 30, b = 2, n = nb * b;
    double mass[30], v[60], w[60];
    for (int32_t i = 0; i < nb; ++i) mass[i] = 0.25;
    cf_sparse *a = path_laplacian(ctx, nb, b, 0.05, mass), *l = path_laplacian(ctx, nb, b, 0.0, mass);
    cf_cholesky *chol = NULL;
    CHECK_OK(ctx, cf_cholesky_create(ctx, a, NULL, &chol));
    CHECK_OK(ctx, cf_cholesky_factorize(chol, a));
    /* antisymmetric about the middle: orthogonal to the constants, keeps the second mode */
    for (int32_t i = 0; i < nb; ++i)
        for (int32_t c = 0; c < b; ++c) v[b * i + c] = (i < nb / 2 ? 1.0 : -1.0) * (c + 1);
    /* 15 iterations: the next odd mode (k = 3) decays by 0.21 per iteration,
     * while rounding's constant component grows by (lambda_1 + s) / s = 1.9 */
    CHECK_OK(ctx, cf_inverse_iteration_blocks(chol, mass, b, 15, 1.0, v, w));
    double expect = (2.0 - 2.0 * cos(PI / nb)) / 0.25;
    CHECK_NEAR(cf_rayleigh_quotient_blocks(l, mass, b, v, w), expect, 1e-9, 0.0);
    for (int32_t i = 0; i < n; ++i) v[i] = 1.0 + 0.1 * (double)(i % 3);
    CHECK_OK(ctx, cf_inverse_iteration_blocks(chol, mass, b, 200, 1.0, v, w));
    CHECK_NEAR(cf_rayleigh_quotient_blocks(l, mass, b, v, w), 0.0, 0.0, 1e-10);
    cf_cholesky_destroy(&chol);
    cf_sparse_destroy(&a);
    cf_sparse_destroy(&l);
    cf_context_destroy(&ctx);
}

/* cf_normalize_blocks, the scaling the iteration ends with: the target met,
 * the sum before it returned, a zero or non-finite vector left alone. */
static void test_normalize_blocks(void)
{
    double mass[3] = {0.5, 2.0, 1.5}, v[6] = {1.0, 2.0, 0.0, 3.0, -1.0, 1.0}, w[6];
    double before = 0.5 * 5.0 + 2.0 * 9.0 + 1.5 * 2.0, after = 0.0;
    CHECK_NEAR(cf_normalize_blocks(3, mass, 2, 4.0, v), before, 1e-15, 0.0);
    for (int32_t i = 0; i < 3; ++i) after += mass[i] * (v[2 * i] * v[2 * i] + v[2 * i + 1] * v[2 * i + 1]);
    CHECK_NEAR(after, 4.0, 1e-14, 0.0);
    CHECK_NEAR(v[1] / v[0], 2.0, 1e-15, 0.0); /* a scaling: directions kept */
    memset(w, 0, sizeof w);
    CHECK(cf_normalize_blocks(3, mass, 2, 4.0, w) == 0.0);
    for (int32_t i = 0; i < 6; ++i) CHECK(w[i] == 0.0);
    w[3] = NAN;
    CHECK(isnan(cf_normalize_blocks(3, mass, 2, 4.0, w)));
    CHECK(w[0] == 0.0 && isnan(w[3]));
}

static void test_bad_input(void)
{
    cf_context *ctx = cft_context();
    double mass[6] = {1, 1, 1, 1, 1, 1}, v[12] = {0}, w[12];
    cf_sparse *a = path_laplacian(ctx, 6, 2, 1.0, mass);
    cf_cholesky *chol = NULL;
    CHECK_OK(ctx, cf_cholesky_create(ctx, a, NULL, &chol));
    CHECK_OK(ctx, cf_cholesky_factorize(chol, a));
    CHECK_STATUS(cf_inverse_iteration_blocks(NULL, mass, 2, 1, 1.0, v, w), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_inverse_iteration_blocks(chol, mass, 5, 1, 1.0, v, w), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "block size 5 for n = 12") != NULL);
    CHECK_STATUS(cf_inverse_iteration_blocks(chol, mass, 0, 1, 1.0, v, w), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_inverse_iteration_blocks(chol, mass, 2, 1, 0.0, v, w), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_inverse_iteration_blocks(chol, NULL, 2, 1, 1.0, v, w), CF_ERR_INVALID_ARG);
    /* a zero start stays zero: refused, not normalised into NaN */
    CHECK_STATUS(cf_inverse_iteration_blocks(chol, mass, 2, 1, 1.0, v, w), CF_ERR_NUMERICAL);
    CHECK(strstr(cf_context_message(ctx), "M-norm is 0") != NULL);
    CHECK(isnan(cf_rayleigh_quotient_blocks(a, mass, 2, v, w)));
    CHECK(isnan(cf_rayleigh_quotient_blocks(a, mass, 5, v, w)));
    CHECK(isnan(cf_rayleigh_quotient_blocks(NULL, mass, 2, v, w)));
    cf_cholesky_destroy(&chol);
    cf_sparse_destroy(&a);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_blocks_match_repeated_masses);
    CFT_RUN(test_converges_to_known_eigenvalue);
    CFT_RUN(test_normalize_blocks);
    CFT_RUN(test_bad_input);
    return cft_finish();
}
