/* cf_context_set_threads: CHOLMOD's OpenMP regions follow the context's
 * setting (max-active-levels 0 for 1 thread, 1 for more) at each
 * factorisation, the runtime is left alone with 0, and the factor does not
 * depend on the setting. OpenBLAS runs the factorisations and solves on one
 * thread with the default 1 and hands the process's count back after them;
 * with 0 and n > 1 it keeps the process's count. */
#define _GNU_SOURCE 1 /* RTLD_DEFAULT */
#include "curvflow/linalg.h"
#include "test.h"

#include <dlfcn.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* linalg_internal.h (blas_buffers.c); that header needs CHOLMOD's, which
 * the tests do not see */
int cfi_blas_threads_last_entered(void);

static int (*get_levels)(void);
static void (*set_levels)(int);
static int (*blas_get_threads)(void);
static void (*blas_set_threads)(int);
/* OpenBLAS's count during the last factorisation / solve of factor_with */
static int blas_in_factorize, blas_in_solve;

static cf_sparse *grid(cf_context *ctx, int32_t m)
{
    int32_t n = m * m, k = 0;
    int32_t *r = malloc(5 * (size_t)n * sizeof(int32_t)), *c = malloc(5 * (size_t)n * sizeof(int32_t));
    double *v = malloc(5 * (size_t)n * sizeof(double));
    for (int32_t i = 0; i < m; ++i)
        for (int32_t j = 0; j < m; ++j) {
            int32_t p = i * m + j;
            r[k] = c[k] = p, v[k++] = 4.5;
            if (i > 0) r[k] = p, c[k] = p - m, v[k++] = -1.0;
            if (i < m - 1) r[k] = p, c[k] = p + m, v[k++] = -1.0;
            if (j > 0) r[k] = p, c[k] = p - 1, v[k++] = -1.0;
            if (j < m - 1) r[k] = p, c[k] = p + 1, v[k++] = -1.0;
        }
    cf_sparse *a = NULL;
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, n, n, k, r, c, v, 1, &a, NULL));
    free(r);
    free(c);
    free(v);
    return a;
}

/* factorises and solves A x = 1 with the context's setting; returns the ICV after */
static int factor_with(int32_t threads, double *x)
{
    cf_context *ctx = cft_context();
    CHECK(cf_context_threads(ctx) == 1); /* the default */
    CHECK_OK(ctx, cf_context_set_threads(ctx, threads));
    CHECK(cf_context_threads(ctx) == threads);
    cf_sparse *a = grid(ctx, 30);
    int32_t n = a->nrows;
    double *b = malloc((size_t)n * sizeof(double));
    for (int32_t i = 0; i < n; ++i) b[i] = 1.0;
    cf_cholesky *chol = NULL;
    CHECK_OK(ctx, cf_cholesky_create(ctx, a, NULL, &chol));
    CHECK_OK(ctx, cf_cholesky_factorize(chol, a));
    blas_in_factorize = cfi_blas_threads_last_entered();
    CHECK_OK(ctx, cf_cholesky_solve(chol, 1, b, x));
    blas_in_solve = cfi_blas_threads_last_entered();
    int levels = get_levels();
    cf_cholesky_destroy(&chol);
    cf_sparse_destroy(&a);
    free(b);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
    return levels;
}

static void test_setting_applied(void)
{
    void *g = dlsym(RTLD_DEFAULT, "omp_get_max_active_levels"), *s = dlsym(RTLD_DEFAULT, "omp_set_max_active_levels");
    CHECK(g != NULL && s != NULL); /* libgomp comes with CHOLMOD */
    if (!g || !s) return;
    memcpy(&get_levels, &g, sizeof get_levels);
    memcpy(&set_levels, &s, sizeof set_levels);
    double x1[900], x2[900], x0[900];
    set_levels(3);
    CHECK(factor_with(1, x1) == 0); /* serial */
    CHECK(factor_with(2, x2) == 1); /* parallel regions allowed */
    set_levels(3);
    CHECK(factor_with(0, x0) == 3); /* untouched */
    /* the solution does not depend on the setting (CHOLMOD's regions split
     * independent work; a regression would show here) */
    double d = 0.0;
    for (int i = 0; i < 900; ++i) d = fmax(d, fmax(fabs(x1[i] - x2[i]), fabs(x1[i] - x0[i])));
    CHECK_LE(d, 1e-12);
    set_levels(0);
}

/* OpenBLAS: one thread inside the library's calls with the default, the
 * process's count (2 here) after them and with 0 or 2; UMFPACK's LU too */
static void test_openblas_threads(void)
{
    void *g = dlsym(RTLD_DEFAULT, "openblas_get_num_threads"), *s = dlsym(RTLD_DEFAULT, "openblas_set_num_threads");
    if (!g || !s) {
        printf("SKIP openblas_threads: the BLAS of this process is not OpenBLAS\n");
        return;
    }
    memcpy(&blas_get_threads, &g, sizeof blas_get_threads);
    memcpy(&blas_set_threads, &s, sizeof blas_set_threads);
    int process = blas_get_threads();
    blas_set_threads(2);
    CHECK(blas_get_threads() == 2);
    double x1[900], x2[900], x0[900];
    factor_with(1, x1);
    CHECK(blas_in_factorize == 1 && blas_in_solve == 1);
    CHECK(blas_get_threads() == 2); /* handed back */
    factor_with(2, x2);
    CHECK(blas_in_factorize == 2 && blas_in_solve == 2);
    factor_with(0, x0);
    CHECK(blas_in_factorize == 2 && blas_in_solve == 2);
    CHECK(blas_get_threads() == 2);
    double d = 0.0;
    for (int i = 0; i < 900; ++i) d = fmax(d, fmax(fabs(x1[i] - x2[i]), fabs(x1[i] - x0[i])));
    CHECK_LE(d, 1e-12);

    /* the LU (UMFPACK) of the same matrix: factorisation and solve */
    for (int32_t threads = 1; threads >= 0; --threads) {
        cf_context *ctx = cft_context();
        CHECK_OK(ctx, cf_context_set_threads(ctx, threads));
        cf_sparse *a = grid(ctx, 30);
        cf_lu *lu = NULL;
        CHECK_OK(ctx, cf_lu_create(ctx, a, &lu));
        CHECK(cfi_blas_threads_last_entered() == (threads == 1 ? 1 : 2));
        double b[900], x[900];
        for (int i = 0; i < 900; ++i) b[i] = 1.0;
        CHECK_OK(ctx, cf_lu_solve(lu, b, x));
        CHECK(cfi_blas_threads_last_entered() == (threads == 1 ? 1 : 2));
        CHECK(blas_get_threads() == 2);
        double e = 0.0;
        for (int i = 0; i < 900; ++i) e = fmax(e, fabs(x[i] - x1[i]));
        CHECK_LE(e, 1e-12);
        cf_lu_destroy(&lu);
        cf_sparse_destroy(&a);
        cf_context_destroy(&ctx);
    }
    blas_set_threads(process);
}

static void test_bad_input(void)
{
    cf_context *ctx = cft_context();
    CHECK_STATUS(cf_context_set_threads(ctx, -1), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "threads must be >= 0, got -1") != NULL);
    CHECK(cf_context_threads(ctx) == 1);
    CHECK_STATUS(cf_context_set_threads(NULL, 1), CF_ERR_INVALID_ARG);
    CHECK(cf_context_threads(NULL) == 1);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_setting_applied);
    CFT_RUN(test_openblas_threads);
    CFT_RUN(test_bad_input);
    return cft_finish();
}
