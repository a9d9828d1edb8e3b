/* cf_cholesky_reserve_solve: after reserving nrhs columns, solves of up to
 * nrhs columns make no allocation through the context (quaternion-block
 * factorisations keep a complex-form buffer), wider ones grow it once; the
 * solution is the same; bad input is refused. */
#include "curvflow/linalg.h"
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* (path Laplacian + I) with each entry s a whole 4 x 4 block s I_4 (zeros
 * stored): the left-multiplication matrix of the real quaternion s */
static cf_sparse *quaternion_matrix(cf_context *ctx, int32_t n)
{
    int64_t cap = 3 * 16 * (int64_t)n, k = 0;
    int32_t *r = malloc((size_t)cap * sizeof(int32_t)), *c = malloc((size_t)cap * sizeof(int32_t));
    double *v = malloc((size_t)cap * sizeof(double));
    for (int32_t i = 0; i < n; ++i)
        for (int32_t j = i - 1; j <= i + 1; ++j) {
            if (j < 0 || j >= n) continue;
            double s = i == j ? 3.0 : -1.0;
            for (int p = 0; p < 4; ++p)
                for (int q = 0; q < 4; ++q) r[k] = 4 * i + p, c[k] = 4 * j + q, v[k++] = p == q ? s : 0.0;
        }
    cf_sparse *a = NULL;
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, 4 * n, 4 * n, k, r, c, v, 1, &a, NULL));
    free(r);
    free(c);
    free(v);
    return a;
}

static void test_reserve(void)
{
    cf_context *ctx = cft_context();
    const int32_t n = 50, n4 = 200; /* 4 n unknowns */
    cf_sparse *a = quaternion_matrix(ctx, n);
    cf_cholesky_options co;
    cf_cholesky_options_default(&co);
    co.block_size = 4;
    co.quaternion_blocks = 1;
    cf_cholesky *chol = NULL;
    CHECK_OK(ctx, cf_cholesky_create(ctx, a, &co, &chol));
    CHECK_OK(ctx, cf_cholesky_factorize(chol, a));
    CHECK_OK(ctx, cf_cholesky_reserve_solve(chol, 3));
    double *b = malloc(4 * (size_t)n4 * sizeof(double)), *x = malloc(4 * (size_t)n4 * sizeof(double));
    for (int32_t i = 0; i < 4 * n4; ++i) b[i] = sin(0.1 * i);
    int64_t before = cf_context_allocation_count(ctx);
    CHECK_OK(ctx, cf_cholesky_solve(chol, 1, b, x));
    CHECK_OK(ctx, cf_cholesky_solve(chol, 3, b, x));
    CHECK(cf_context_allocation_count(ctx) == before); /* reserved: nothing allocated */
    /* A x = b column 0 */
    double *ax = malloc((size_t)n4 * sizeof(double)), res = 0.0;
    cf_sparse_multiply(a, x, ax);
    for (int32_t i = 0; i < n4; ++i) res = fmax(res, fabs(ax[i] - b[i]));
    CHECK_LE(res, 1e-12);
    CHECK_OK(ctx, cf_cholesky_solve(chol, 4, b, x)); /* wider: grows once */
    CHECK(cf_context_allocation_count(ctx) == before + 1);
    CHECK_OK(ctx, cf_cholesky_reserve_solve(chol, 2)); /* smaller than held: nothing */
    CHECK(cf_context_allocation_count(ctx) == before + 1);
    CHECK_STATUS(cf_cholesky_reserve_solve(chol, -1), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_cholesky_reserve_solve(NULL, 1), CF_ERR_INVALID_ARG);
    cf_context_fail_allocation(ctx, 1, 0);
    CHECK_STATUS(cf_cholesky_reserve_solve(chol, 8), CF_ERR_NOMEM);
    cf_context_fail_allocation(ctx, 0, 0);
    CHECK_OK(ctx, cf_cholesky_solve(chol, 4, b, x)); /* the old buffer still works */
    cf_cholesky_destroy(&chol);
    cf_sparse_destroy(&a);
    free(b);
    free(x);
    free(ax);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_reserve);
    return cft_finish();
}
