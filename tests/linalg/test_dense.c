/* Small dense least squares (cf_dense_least_squares, LAPACK dgelss):
 * consistent and inconsistent overdetermined systems against the normal
 * equations, the minimum-norm solution of a rank-deficient one, and the
 * statuses of bad input; the eigenvalues of a symmetric-definite pencil
 * (cf_dense_generalized_eigenvalues, LAPACK dsygv). */
#include "test.h"

#include "curvflow/linalg.h"

#include <math.h>
#include <string.h>

static void test_overdetermined(void)
{
    /* a (4 x 2) = [1 0; 1 1; 1 2; 1 3] column-major */
    const double a0[8] = {1, 1, 1, 1, 0, 1, 2, 3};
    double a[8], b[4], work[64];
    int32_t rank = -1;
    CHECK(cf_dense_least_squares_work_size(4, 2) <= 64);
    /* consistent: b = 2 + 3 t */
    memcpy(a, a0, sizeof a);
    for (int k = 0; k < 4; ++k) b[k] = 2.0 + 3.0 * k;
    CHECK(cf_dense_least_squares(4, 2, a, b, 1e-12, work, 64, &rank) == CF_OK);
    CHECK(rank == 2);
    CHECK_NEAR(b[0], 2.0, 1e-13, 0);
    CHECK_NEAR(b[1], 3.0, 1e-13, 0);
    /* inconsistent: b = (0, 1, 0, 1); normal equations [4 6; 6 14] x = (2, 4)
     * give x = (0.2, 0.2) */
    memcpy(a, a0, sizeof a);
    const double rhs[4] = {0, 1, 0, 1};
    memcpy(b, rhs, sizeof b);
    CHECK(cf_dense_least_squares(4, 2, a, b, 1e-12, work, 64, &rank) == CF_OK);
    CHECK_NEAR(b[0], 0.2, 1e-13, 0);
    CHECK_NEAR(b[1], 0.2, 1e-13, 0);
}

static void test_rank_deficient(void)
{
    /* two equal columns: x1 + x2 = 2 in every row; minimum norm x = (1, 1) */
    double a[6] = {1, 1, 1, 1, 1, 1}, b[3] = {2, 2, 2}, work[64];
    int32_t rank = -1;
    CHECK(cf_dense_least_squares(3, 2, a, b, 1e-12, work, 64, &rank) == CF_OK);
    CHECK(rank == 1);
    CHECK_NEAR(b[0], 1.0, 1e-13, 0);
    CHECK_NEAR(b[1], 1.0, 1e-13, 0);
    /* underdetermined 1 x 3: x1 + 2 x2 + 2 x3 = 9, minimum norm (1, 2, 2) */
    double c[3] = {1, 2, 2}, d[3] = {9, 0, 0};
    CHECK(cf_dense_least_squares(1, 3, c, d, 1e-12, work, 64, &rank) == CF_OK);
    CHECK(rank == 1);
    CHECK_NEAR(d[0], 1.0, 1e-13, 0);
    CHECK_NEAR(d[1], 2.0, 1e-13, 0);
    CHECK_NEAR(d[2], 2.0, 1e-13, 0);
}

static void test_bad_input(void)
{
    double a[4] = {1, 0, 0, 1}, b[2] = {1, 1}, work[64];
    CHECK(cf_dense_least_squares(0, 2, a, b, 1e-12, work, 64, NULL) == CF_ERR_INVALID_ARG);
    CHECK(cf_dense_least_squares(2, 2, NULL, b, 1e-12, work, 64, NULL) == CF_ERR_INVALID_ARG);
    CHECK(cf_dense_least_squares(2, 2, a, b, 1e-12, work, 2, NULL) == CF_ERR_INVALID_ARG);
    a[3] = NAN;
    CHECK(cf_dense_least_squares(2, 2, a, b, 1e-12, work, 64, NULL) == CF_ERR_NONFINITE);
    a[3] = 1.0;
    b[1] = INFINITY;
    CHECK(cf_dense_least_squares(2, 2, a, b, 1e-12, work, 64, NULL) == CF_ERR_NONFINITE);
    CHECK(cf_dense_least_squares_work_size(0, 3) == 0);
}

/* a x = mu b x for b = L L^T and a = L diag(1, 2, 5) L^T: mu = 1, 2, 5 */
static void test_generalized_eigenvalues(void)
{
    const double l[9] = {2.0, 0.5, -1.0, 0.0, 1.5, 0.3, 0.0, 0.0, 0.7}; /* lower triangular, column-major */
    const double d[3] = {1.0, 2.0, 5.0};
    double a[9], b[9], mu[3], work[16];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double sa = 0.0, sb = 0.0;
            for (int k = 0; k < 3; ++k) {
                sa += l[i + 3 * k] * d[k] * l[j + 3 * k];
                sb += l[i + 3 * k] * l[j + 3 * k];
            }
            a[i + 3 * j] = sa;
            b[i + 3 * j] = sb;
        }
    CHECK(cf_dense_generalized_eigenvalues_work_size(3) <= 16);
    CHECK_STATUS(cf_dense_generalized_eigenvalues(3, a, b, mu, work, 16), CF_OK);
    for (int k = 0; k < 3; ++k) CHECK_NEAR(mu[k], d[k], 1e-13, 0.0); /* ascending */
    /* b not positive definite */
    double a2[4] = {1.0, 0.0, 0.0, 1.0}, b2[4] = {1.0, 0.0, 0.0, -1.0};
    CHECK_STATUS(cf_dense_generalized_eigenvalues(2, a2, b2, mu, work, 16), CF_ERR_NOT_POSDEF);
    double a3[4] = {1.0, NAN, NAN, 1.0}, b3[4] = {1.0, 0.0, 0.0, 1.0};
    CHECK_STATUS(cf_dense_generalized_eigenvalues(2, a3, b3, mu, work, 16), CF_ERR_NONFINITE);
    CHECK_STATUS(cf_dense_generalized_eigenvalues(2, b3, b3, mu, work, 1), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_dense_generalized_eigenvalues(0, b3, b3, mu, work, 16), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_dense_generalized_eigenvalues(2, NULL, b3, mu, work, 16), CF_ERR_INVALID_ARG);
}

int main(void)
{
    CFT_RUN(test_overdetermined);
    CFT_RUN(test_rank_deficient);
    CFT_RUN(test_bad_input);
    CFT_RUN(test_generalized_eigenvalues);
    return cft_finish();
}
