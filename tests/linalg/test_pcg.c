/*
 * cf_pcg_solve: matrix-free Jacobi-preconditioned conjugate gradients on
 * interleaved columns. Against the dense reference solver on a random SPD
 * matrix; one iteration where the preconditioner is the inverse; columns
 * solved together are bit for bit the columns solved alone (each has its own
 * steps and stops on its own, a zero column never moves); a held row stays
 * where it starts; the iteration limit gives CF_ERR_NOT_CONVERGED with the
 * count and residual; bad arguments are refused with a message.
 */
#include "curvflow/linalg.h"
#include "linalg_test_util.h"
#include "test.h"

#include <stdio.h>
#include <string.h>

/* A dense symmetric matrix (column-major) as the operator of cf_pcg_solve
 * on `columns` interleaved columns; rows in `held` give q = 0. */
typedef struct dense_operator {
    int32_t n, columns;
    const double *a;
    const uint8_t *held; /* NULL: none */
} dense_operator;

static void dense_multiply(void *user, const double *p, double *q, double *pq)
{
    const dense_operator *op = user;
    int32_t n = op->n, m = op->columns;
    for (int32_t c = 0; c < m; ++c) pq[c] = 0.0;
    for (int32_t i = 0; i < n; ++i)
        for (int32_t c = 0; c < m; ++c) {
            double s = 0.0;
            if (!op->held || !op->held[i])
                for (int32_t j = 0; j < n; ++j) s += op->a[(size_t)j * n + i] * p[(size_t)m * j + c];
            q[(size_t)m * i + c] = s;
            pq[c] += p[(size_t)m * i + c] * s;
        }
}

/* A = B^T B / n + D with B random and D = diag(1 .. 100): SPD, condition
 * number of order 100, a diagonal far from constant (so the preconditioner
 * matters). */
static double *random_spd(int32_t n, uint64_t seed)
{
    rng_seed(seed);
    double *b = malloc(sizeof(double) * (size_t)n * n), *a = malloc(sizeof(double) * (size_t)n * n);
    for (size_t k = 0; k < (size_t)n * n; ++k) b[k] = rng_unit();
    for (int32_t j = 0; j < n; ++j)
        for (int32_t i = 0; i < n; ++i) {
            double s = 0.0;
            for (int32_t k = 0; k < n; ++k) s += b[(size_t)i * n + k] * b[(size_t)j * n + k];
            a[(size_t)j * n + i] = s / n + (i == j ? 1.0 + 99.0 * i / (n - 1) : 0.0);
        }
    free(b);
    return a;
}

/* x from 0: r = b; returns the status, the solution in x (interleaved). */
static cf_status solve(cf_context *ctx, const dense_operator *op, const double *rhs, double *x, double tolerance,
                       int32_t max_iterations, cf_pcg_result *result)
{
    int32_t n = op->n, m = op->columns;
    size_t size = (size_t)n * m;
    double *r = malloc(size * sizeof *r), *p = malloc(size * sizeof *p), *q = malloc(size * sizeof *q);
    double *minv = malloc((size_t)n * sizeof *minv);
    for (int32_t i = 0; i < n; ++i) minv[i] = op->held && op->held[i] ? 0.0 : 1.0 / op->a[(size_t)i * n + i];
    memcpy(r, rhs, size * sizeof *r);
    for (size_t k = 0; k < size; ++k) x[k] = 0.0;
    cf_status st = cf_pcg_solve(ctx, n, m, dense_multiply, (void *)(uintptr_t)op, minv, x, r, p, q, tolerance,
                                max_iterations, result);
    free(r);
    free(p);
    free(q);
    free(minv);
    return st;
}

static void test_against_dense_solver(void)
{
    cf_context *ctx = cft_context();
    enum { N = 60, M = 3 };
    double *a = random_spd(N, 7);
    double rhs[N * M], x[N * M], col[N], ref[N];
    for (int32_t k = 0; k < N * M; ++k) rhs[k] = rng_unit();
    dense_operator op = {N, M, a, NULL};
    cf_pcg_result result = {0, 0.0};
    CHECK_OK(ctx, solve(ctx, &op, rhs, x, 1e-12, 1000, &result));
    fprintf(stderr, "   n %d: %d iterations, residual %.2g\n", N, result.iterations, result.relative_residual);
    CHECK(result.iterations > 1 && result.iterations <= N);
    CHECK_LE(result.relative_residual, 1e-12);
    for (int c = 0; c < M; ++c) {
        for (int32_t i = 0; i < N; ++i) col[i] = rhs[M * i + c];
        dense_solve(N, a, col, ref);
        double err = 0.0, size = 0.0;
        for (int32_t i = 0; i < N; ++i) {
            err = fmax(err, fabs(x[M * i + c] - ref[i]));
            size = fmax(size, fabs(ref[i]));
        }
        CHECK_LE(err, 1e-10 * size);
    }
    free(a);
    cf_context_destroy(&ctx);
}

/* A diagonal matrix: the Jacobi preconditioner is its inverse, and the
 * first step is the solution. */
static void test_exact_preconditioner_one_iteration(void)
{
    cf_context *ctx = cft_context();
    enum { N = 10 };
    double a[N * N] = {0}, rhs[N], x[N];
    for (int32_t i = 0; i < N; ++i) {
        a[i * N + i] = 1.0 + i * i;
        rhs[i] = 1.0 - 0.3 * i;
    }
    dense_operator op = {N, 1, a, NULL};
    cf_pcg_result result = {0, 0.0};
    CHECK_OK(ctx, solve(ctx, &op, rhs, x, 1e-14, 100, &result));
    CHECK(result.iterations == 1);
    for (int32_t i = 0; i < N; ++i) CHECK_NEAR(x[i], rhs[i] / (1.0 + i * i), 0.0, 1e-15);
    cf_context_destroy(&ctx);
}

/* Three columns at once, one of them zero, against each alone: the same
 * bits, because every column has its own step lengths and its sums run in
 * the same order; the zero column stays exactly 0. */
static void test_columns_are_independent(void)
{
    cf_context *ctx = cft_context();
    enum { N = 40, M = 3 };
    double *a = random_spd(N, 11);
    double rhs[N * M], x[N * M], one_rhs[N], one_x[N];
    for (int32_t i = 0; i < N; ++i) {
        rhs[M * i + 0] = rng_unit();
        rhs[M * i + 1] = 0.0;
        rhs[M * i + 2] = 1e6 * rng_unit(); /* another scale: its own relative stop */
    }
    dense_operator op = {N, M, a, NULL}, op1 = {N, 1, a, NULL};
    cf_pcg_result together = {0, 0.0}, alone = {0, 0.0};
    CHECK_OK(ctx, solve(ctx, &op, rhs, x, 1e-11, 1000, &together));
    int32_t most = 0;
    for (int c = 0; c < M; ++c) {
        for (int32_t i = 0; i < N; ++i) one_rhs[i] = rhs[M * i + c];
        CHECK_OK(ctx, solve(ctx, &op1, one_rhs, one_x, 1e-11, 1000, &alone));
        if (alone.iterations > most) most = alone.iterations;
        int same = 1;
        for (int32_t i = 0; i < N; ++i) same = same && x[M * i + c] == one_x[i];
        CHECK(same);
        if (c == 1) CHECK(alone.iterations == 0);
    }
    CHECK(together.iterations == most);
    for (int32_t i = 0; i < N; ++i) CHECK(x[M * i + 1] == 0.0);
    free(a);
    cf_context_destroy(&ctx);
}

/* A held row (inverse diagonal 0, q kept 0, r 0 there) keeps its starting
 * value; the free rows solve their own block with the held value moved to
 * the right-hand side. */
static void test_held_row_stays(void)
{
    cf_context *ctx = cft_context();
    enum { N = 12 };
    double *a = random_spd(N, 3);
    uint8_t held[N] = {0};
    held[4] = 1;
    double x[N], r[N], p[N], q[N], minv[N], rhs[N];
    for (int32_t i = 0; i < N; ++i) {
        rhs[i] = rng_unit();
        x[i] = i == 4 ? 2.5 : 0.0;
        minv[i] = held[i] ? 0.0 : 1.0 / a[(size_t)i * N + i];
    }
    for (int32_t i = 0; i < N; ++i) r[i] = held[i] ? 0.0 : rhs[i] - a[(size_t)4 * N + i] * 2.5;
    dense_operator op = {N, 1, a, held};
    cf_pcg_result result = {0, 0.0};
    CHECK_OK(ctx, cf_pcg_solve(ctx, N, 1, dense_multiply, &op, minv, x, r, p, q, 1e-13, 100, &result));
    CHECK(x[4] == 2.5);
    double worst = 0.0;
    for (int32_t i = 0; i < N; ++i) {
        if (held[i]) continue;
        double s = 0.0;
        for (int32_t j = 0; j < N; ++j) s += a[(size_t)j * N + i] * x[j];
        worst = fmax(worst, fabs(s - rhs[i]));
    }
    CHECK_LE(worst, 1e-11);
    free(a);
    cf_context_destroy(&ctx);
}

static void test_iteration_limit(void)
{
    cf_context *ctx = cft_context();
    enum { N = 60 };
    double *a = random_spd(N, 5);
    double rhs[N], x[N];
    for (int32_t i = 0; i < N; ++i) rhs[i] = rng_unit();
    dense_operator op = {N, 1, a, NULL};
    cf_pcg_result result = {0, 0.0};
    CHECK(solve(ctx, &op, rhs, x, 1e-12, 3, &result) == CF_ERR_NOT_CONVERGED);
    CHECK(result.iterations == 3);
    CHECK(result.relative_residual > 1e-12);
    CHECK(strstr(cf_context_message(ctx), "did not converge in 3 iterations") != NULL);
    /* the last iterate is returned */
    for (int32_t i = 0; i < N; ++i) CHECK(isfinite(x[i]));
    free(a);
    cf_context_destroy(&ctx);
}

static void test_bad_arguments(void)
{
    cf_context *ctx = cft_context();
    double a[4] = {2.0, 0.0, 0.0, 2.0}, x[2] = {0}, r[2] = {1, 1}, p[2], q[2], minv[2] = {0.5, 0.5};
    dense_operator op = {2, 1, a, NULL};
    cf_pcg_result result;
    CHECK(cf_pcg_solve(NULL, 2, 1, dense_multiply, &op, minv, x, r, p, q, 1e-12, 10, &result) == CF_ERR_INVALID_ARG);
    CHECK(cf_pcg_solve(ctx, 2, 1, NULL, &op, minv, x, r, p, q, 1e-12, 10, &result) == CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "pcg_solve") != NULL);
    CHECK(cf_pcg_solve(ctx, 2, 0, dense_multiply, &op, minv, x, r, p, q, 1e-12, 10, &result) == CF_ERR_INVALID_ARG);
    CHECK(cf_pcg_solve(ctx, 2, CF_PCG_MAX_COLUMNS + 1, dense_multiply, &op, minv, x, r, p, q, 1e-12, 10, &result) ==
          CF_ERR_INVALID_ARG);
    CHECK(cf_pcg_solve(ctx, 2, 1, dense_multiply, &op, minv, x, r, p, q, -1.0, 10, &result) == CF_ERR_INVALID_ARG);
    CHECK(cf_pcg_solve(ctx, 2, 1, dense_multiply, &op, minv, x, r, p, q, NAN, 10, &result) == CF_ERR_INVALID_ARG);
    CHECK(cf_pcg_solve(ctx, 2, 1, dense_multiply, &op, minv, x, r, p, q, 1e-12, 10, NULL) == CF_ERR_INVALID_ARG);
    /* nothing was touched by a refused call */
    CHECK(x[0] == 0.0 && r[0] == 1.0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_against_dense_solver);
    CFT_RUN(test_exact_preconditioner_one_iteration);
    CFT_RUN(test_columns_are_independent);
    CFT_RUN(test_held_row_stays);
    CFT_RUN(test_iteration_limit);
    CFT_RUN(test_bad_arguments);
    return cft_finish();
}
