/* Cholesky wrapper: solutions of seeded random SPD systems against a dense
 * reference (relative residual < 1e-10), several right-hand sides in place,
 * block ordering = plain ordering, every ordering, refactorisation with new
 * values, shifted factorisation of a singular Laplacian, NOT_POSDEF with the
 * failing column, non-finite input, allocation-failure injection. */
#define _GNU_SOURCE 1 /* RTLD_DEFAULT */
#include "test.h"
#include "linalg_test_util.h"

#include "curvflow/linalg.h"

#include <dlfcn.h>
#include <stdlib.h>
#include <string.h>


/* Weighted graph Laplacian of an nx x ny grid with b x b SPD edge blocks
 * W_e = I + 0.3 R_e R_e^T-like random symmetric part (kept positive
 * definite), plus diag_shift * I: symmetric positive definite when
 * diag_shift > 0, singular (constants per component) when 0 and b = 1 with
 * scalar weights. Stored with both triangles. */
static cf_sparse *grid_matrix(cf_context *ctx, int32_t nx, int32_t ny, int32_t b, double diag_shift, int random_weights)
{
    int32_t nv = nx * ny, n = nv * b;
    int64_t cap = (int64_t)(4 * 2 * nv) * b * b + n;
    int32_t *r = malloc((size_t)cap * 4), *c = malloc((size_t)cap * 4);
    double *v = malloc((size_t)cap * 8);
    int64_t k = 0;
    for (int32_t y = 0; y < ny; ++y)
        for (int32_t x = 0; x < nx; ++x)
            for (int dir = 0; dir < 2; ++dir) {
                int32_t i = y * nx + x, j;
                if (dir == 0 && x + 1 < nx) j = i + 1;
                else if (dir == 1 && y + 1 < ny) j = i + nx;
                else continue;
                double w = random_weights ? 1.0 + 0.5 * rng_unit() : 1.0;
                /* block w (I + 0.2 S) with S symmetric, |S| small: SPD */
                double blk[16];
                for (int32_t p = 0; p < b; ++p)
                    for (int32_t q = 0; q <= p; ++q) {
                        double s = (p == q) ? 1.0 : (random_weights ? 0.2 * rng_unit() / b : 0.0);
                        blk[p * b + q] = blk[q * b + p] = w * s;
                    }
                for (int32_t p = 0; p < b; ++p)
                    for (int32_t q = 0; q < b; ++q) {
                        double s = blk[p * b + q];
                        r[k] = i * b + p; c[k] = i * b + q; v[k++] = s;
                        r[k] = j * b + p; c[k] = j * b + q; v[k++] = s;
                        r[k] = i * b + p; c[k] = j * b + q; v[k++] = -s;
                        r[k] = j * b + p; c[k] = i * b + q; v[k++] = -s;
                    }
            }
    for (int32_t i = 0; i < n; ++i) { r[k] = i; c[k] = i; v[k++] = diag_shift; }
    cf_sparse *a = NULL;
    cf_status st = cf_sparse_from_triplets(ctx, n, n, k, r, c, v, 1, &a, NULL);
    if (st != CF_OK) a = NULL;
    free(r); free(c); free(v);
    return a;
}

static double *dense_of(const cf_sparse *a)
{
    double *d = calloc((size_t)a->nrows * a->ncols, sizeof *d);
    for (int32_t j = 0; j < a->ncols; ++j)
        for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) d[(size_t)j * a->nrows + a->rowind[p]] += a->values[p];
    return d;
}

/* |A x - b| / (|A| |x| + |b|) in the infinity norm */
static double relative_residual(const cf_sparse *a, const double *x, const double *b)
{
    int32_t n = a->nrows;
    double *r = malloc((size_t)n * sizeof *r);
    cf_sparse_multiply(a, x, r);
    double rn = 0.0, xn = 0.0, bn = 0.0, an = 0.0;
    for (int32_t i = 0; i < n; ++i) {
        rn = fmax(rn, fabs(r[i] - b[i]));
        xn = fmax(xn, fabs(x[i]));
        bn = fmax(bn, fabs(b[i]));
    }
    for (int32_t j = 0; j < a->ncols; ++j) {
        double s = 0.0;
        for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) s += fabs(a->values[p]);
        an = fmax(an, s);
    }
    free(r);
    return rn / (an * xn + bn);
}

static void test_solve_matches_dense(void)
{
    cf_context *ctx = cft_context();
    rng_seed(11);
    cf_sparse *a = grid_matrix(ctx, 7, 6, 2, 0.05, 1); /* n = 84 */
    CHECK(a != NULL);
    if (!a) return;
    int32_t n = a->nrows;
    enum { NRHS = 3 };
    double *b = malloc((size_t)n * NRHS * sizeof *b), *x = malloc((size_t)n * NRHS * sizeof *x);
    double *ref = malloc((size_t)n * sizeof *ref);
    for (int32_t k = 0; k < n * NRHS; ++k) b[k] = rng_unit();
    double *dense = dense_of(a);
    cf_cholesky *chol = NULL;
    CHECK_OK(ctx, cf_cholesky_create(ctx, a, NULL, &chol));
    CHECK(cf_cholesky_size(chol) == n);
    CHECK_OK(ctx, cf_cholesky_factorize(chol, a));
    CHECK_OK(ctx, cf_cholesky_solve(chol, NRHS, b, x));
    for (int32_t r = 0; r < NRHS; ++r) {
        dense_solve(n, dense, b + (size_t)r * n, ref);
        double md = 0.0, mx = 0.0;
        for (int32_t i = 0; i < n; ++i) {
            md = fmax(md, fabs(x[(size_t)r * n + i] - ref[i]));
            mx = fmax(mx, fabs(ref[i]));
        }
        CHECK_LE(md, 1e-10 * mx);
        CHECK_LE(relative_residual(a, x + (size_t)r * n, b + (size_t)r * n), 1e-14);
    }
    /* in place (x == b) gives the same numbers */
    double *y = malloc((size_t)n * NRHS * sizeof *y);
    memcpy(y, b, (size_t)n * NRHS * sizeof *y);
    CHECK_OK(ctx, cf_cholesky_solve(chol, NRHS, y, y));
    CHECK(memcmp(x, y, (size_t)n * NRHS * sizeof *x) == 0);
    /* solving one column again reuses the workspace (no new allocations in the context) */
    int64_t before = cf_context_allocation_count(ctx);
    CHECK_OK(ctx, cf_cholesky_solve(chol, 1, b, y));
    CHECK(cf_context_allocation_count(ctx) == before);

    /* refactorisation with new values of the same pattern */
    for (int64_t p = 0; p < cf_sparse_nnz(a); ++p) a->values[p] *= 2.0;
    CHECK_OK(ctx, cf_cholesky_factorize(chol, a));
    CHECK_OK(ctx, cf_cholesky_solve(chol, 1, b, y));
    double md = 0.0;
    for (int32_t i = 0; i < n; ++i) md = fmax(md, fabs(2.0 * y[i] - x[i]));
    CHECK_LE(md, 1e-12);

    cf_solver_timings tm;
    cf_cholesky_timings(chol, &tm);
    CHECK(tm.analyze_seconds >= 0.0 && tm.factorize_seconds >= 0.0 && tm.solve_seconds >= 0.0);

    cf_cholesky_destroy(&chol);
    CHECK(chol == NULL);
    cf_sparse_destroy(&a);
    free(b); free(x); free(y); free(ref); free(dense);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Ordering the 3x3 block graph and expanding gives a valid factorisation
 * whose solution equals that of ordering the whole matrix; every ordering
 * agrees on the solution. */
static void test_orderings_agree(void)
{
    cf_context *ctx = cft_context();
    rng_seed(12);
    cf_sparse *a = grid_matrix(ctx, 15, 14, 3, 0.01, 1); /* n = 630 */
    CHECK(a != NULL);
    if (!a) return;
    int32_t n = a->nrows;
    double *b = malloc((size_t)n * sizeof *b), *x0 = malloc((size_t)n * sizeof *x0), *x = malloc((size_t)n * sizeof *x);
    for (int32_t i = 0; i < n; ++i) b[i] = rng_unit();
    cf_cholesky_options o;
    cf_cholesky_options_default(&o);
    CHECK(o.block_size == 1 && o.ordering == CF_ORDERING_AUTO);
    cf_cholesky *chol = NULL;
    CHECK_OK(ctx, cf_cholesky_create(ctx, a, &o, &chol));
    CHECK_OK(ctx, cf_cholesky_factorize(chol, a));
    CHECK_OK(ctx, cf_cholesky_solve(chol, 1, b, x0));
    CHECK_LE(relative_residual(a, x0, b), 1e-14);
    cf_cholesky_destroy(&chol);
    double scale = 0.0;
    for (int32_t i = 0; i < n; ++i) scale = fmax(scale, fabs(x0[i]));
    const cf_ordering orders[5] = {CF_ORDERING_AUTO, CF_ORDERING_AMD, CF_ORDERING_METIS, CF_ORDERING_NATURAL,
                                   CF_ORDERING_AUTO_REFACTORISED};
    for (int blocks = 1; blocks <= 3; blocks += 2)
        for (int k = 0; k < 5; ++k) {
            o.block_size = blocks;
            o.ordering = orders[k];
            CHECK_OK(ctx, cf_cholesky_create(ctx, a, &o, &chol));
            CHECK_OK(ctx, cf_cholesky_factorize(chol, a));
            CHECK_OK(ctx, cf_cholesky_solve(chol, 1, b, x));
            double md = 0.0;
            for (int32_t i = 0; i < n; ++i) md = fmax(md, fabs(x[i] - x0[i]));
            /* condition number of this grid is ~1e4: 1e-10 relative leaves 1e2 margin */
            CHECK_LE(md, 1e-10 * scale);
            cf_cholesky_destroy(&chol);
        }
    o.block_size = 4; /* 630 is not a multiple of 4 */
    CHECK_STATUS(cf_cholesky_create(ctx, a, &o, &chol), CF_ERR_INVALID_ARG);
    cf_sparse_destroy(&a);
    free(b); free(x0); free(x);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Path-graph Laplacian (singular: constants) + shift s: (L + s I) x = b
 * against the dense solve; the plain factorisation must fail. */
static void test_shifted_singular_laplacian(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    cf_sparse *l = grid_matrix(ctx, 40, 1, 1, 0.0, 0);
    CHECK(l != NULL);
    if (!l) return;
    int32_t n = l->nrows;
    cf_cholesky *chol = NULL;
    CHECK_OK(ctx, cf_cholesky_create(ctx, l, NULL, &chol));
    /* exactly singular: the last pivot is zero (or rounding-small); CHOLMOD
     * may or may not flag it, but a shifted matrix must factorise */
    const double shift = 1e-3;
    CHECK_OK(ctx, cf_cholesky_factorize_shifted(chol, l, shift));
    double b[40], x[40], ref[40];
    rng_seed(13);
    for (int32_t i = 0; i < n; ++i) b[i] = rng_unit();
    CHECK_OK(ctx, cf_cholesky_solve(chol, 1, b, x));
    double *d = dense_of(l);
    for (int32_t i = 0; i < n; ++i) d[(size_t)i * n + i] += shift;
    dense_solve(n, d, b, ref);
    double md = 0.0, mx = 0.0;
    for (int32_t i = 0; i < n; ++i) { md = fmax(md, fabs(x[i] - ref[i])); mx = fmax(mx, fabs(ref[i])); }
    CHECK_LE(md, 1e-10 * mx);
    free(d);
    /* a negative shift larger than the smallest eigenvalue: not positive definite */
    CHECK_STATUS(cf_cholesky_factorize_shifted(chol, l, -0.5), CF_ERR_NOT_POSDEF);
    CHECK_STATUS(cf_cholesky_solve(chol, 1, b, x), CF_ERR_INVALID_ARG); /* no valid factor */
    cf_cholesky_destroy(&chol);
    cf_sparse_destroy(&l);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Diagonal-dominant matrix with one negative diagonal entry at column 23:
 * whatever the ordering, the failing pivot is that column. */
static void test_not_posdef_names_column(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    rng_seed(14);
    cf_sparse *a = grid_matrix(ctx, 8, 8, 1, 10.0, 1);
    CHECK(a != NULL);
    if (!a) return;
    const cf_ordering orders[3] = {CF_ORDERING_AMD, CF_ORDERING_METIS, CF_ORDERING_NATURAL};
    int64_t p = cf_sparse_find(a, 23, 23);
    CHECK(p >= 0);
    a->values[p] = -1.0; /* row 23 is no longer positive */
    for (int k = 0; k < 3; ++k) {
        cf_cholesky_options o;
        cf_cholesky_options_default(&o);
        o.ordering = orders[k];
        cf_cholesky *chol = NULL;
        CHECK_OK(ctx, cf_cholesky_create(ctx, a, &o, &chol));
        CHECK_STATUS(cf_cholesky_factorize(chol, a), CF_ERR_NOT_POSDEF);
        CHECK(strstr(cf_context_message(ctx), "column 23 ") != NULL);
        cf_cholesky_destroy(&chol);
    }
    cf_sparse_destroy(&a);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_nonfinite_and_misuse(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    cf_sparse *a = grid_matrix(ctx, 5, 5, 1, 1.0, 0), *other = grid_matrix(ctx, 5, 4, 1, 1.0, 0);
    CHECK(a && other);
    if (!a || !other) return;
    cf_cholesky *chol = NULL;
    CHECK_OK(ctx, cf_cholesky_create(ctx, a, NULL, &chol));
    double b[25], x[25];
    for (int i = 0; i < 25; ++i) b[i] = 1.0;
    CHECK_STATUS(cf_cholesky_solve(chol, 1, b, x), CF_ERR_INVALID_ARG); /* not factorised yet */
    CHECK_OK(ctx, cf_cholesky_factorize(chol, a));
    b[7] = NAN;
    CHECK_STATUS(cf_cholesky_solve(chol, 1, b, x), CF_ERR_NUMERICAL);
    CHECK(strstr(cf_context_message(ctx), "row 7") != NULL);
    b[7] = INFINITY;
    CHECK_STATUS(cf_cholesky_solve(chol, 1, b, x), CF_ERR_NUMERICAL);
    b[7] = 1.0;
    a->values[3] = NAN;
    CHECK_STATUS(cf_cholesky_factorize(chol, a), CF_ERR_NUMERICAL);
    CHECK_STATUS(cf_cholesky_factorize(chol, other), CF_ERR_INVALID_ARG); /* other pattern */
    CHECK_STATUS(cf_cholesky_factorize_shifted(chol, a, NAN), CF_ERR_NUMERICAL);
    cf_cholesky_destroy(&chol);
    CHECK_STATUS(cf_cholesky_create(ctx, NULL, NULL, &chol), CF_ERR_INVALID_ARG);
    cf_cholesky_destroy(&chol); /* NULL is fine */
    cf_sparse_destroy(&a);
    cf_sparse_destroy(&other);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* A larger system (2D grid, 90 x 90 x 3 = 24300 unknowns): residual at
 * machine precision, so the supernodal path is exercised. */
static void test_larger_grid(void)
{
    cf_context *ctx = cft_context();
    rng_seed(15);
    cf_sparse *a = grid_matrix(ctx, 90, 90, 3, 1e-3, 1);
    CHECK(a != NULL);
    if (!a) return;
    int32_t n = a->nrows;
    double *b = malloc((size_t)n * 2 * sizeof *b), *x = malloc((size_t)n * 2 * sizeof *x);
    for (int32_t i = 0; i < 2 * n; ++i) b[i] = rng_unit();
    cf_cholesky_options o;
    cf_cholesky_options_default(&o);
    o.block_size = 3;
    cf_cholesky *chol = NULL;
    CHECK_OK(ctx, cf_cholesky_create(ctx, a, &o, &chol));
    CHECK_OK(ctx, cf_cholesky_factorize(chol, a));
    CHECK_OK(ctx, cf_cholesky_solve(chol, 2, b, x));
    /* cond ~ 1e4 for this grid with shift 1e-3: backward error stays ~1e-16 */
    CHECK_LE(relative_residual(a, x, b), 1e-13);
    CHECK_LE(relative_residual(a, x + n, b + n), 1e-13);
    cf_cholesky_destroy(&chol);
    cf_sparse_destroy(&a);
    free(b); free(x);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Fails the k-th context allocation for every k: CF_ERR_NOMEM and no leak
 * (CHOLMOD's own memory comes from malloc and is not injectable). */
static void test_allocation_failures(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    cf_sparse *a = grid_matrix(ctx, 6, 5, 3, 0.5, 1);
    CHECK(a != NULL);
    if (!a) return;
    double b[90], x[90];
    for (int i = 0; i < 90; ++i) b[i] = 1.0;
    cf_context *fresh = NULL; /* also fail the lazy CHOLMOD start */
    CHECK(cf_context_create(&fresh) == CF_OK);
    int succeeded = 0, failures = 0, wrong = 0;
    size_t base = cf_context_bytes_in_use(ctx);
    for (int64_t k = 1; k < 100 && !succeeded; ++k) {
        cf_context_fail_allocation(ctx, k, 0);
        cf_cholesky_options o;
        cf_cholesky_options_default(&o);
        o.block_size = 3;
        cf_cholesky *chol = NULL;
        cf_status st = cf_cholesky_create(ctx, a, &o, &chol);
        if (st == CF_OK) st = cf_cholesky_factorize(chol, a);
        if (st == CF_OK) st = cf_cholesky_solve(chol, 1, b, x);
        if (st == CF_OK) succeeded = 1;
        else if (st == CF_ERR_NOMEM) ++failures;
        else ++wrong;
        cf_cholesky_destroy(&chol);
        if (cf_context_bytes_in_use(ctx) != base) ++wrong; /* only the matrix remains */
    }
    cf_context_fail_allocation(ctx, 0, 0);
    CHECK(succeeded);
    CHECK(failures >= 5);
    CHECK(wrong == 0);
    cf_context_fail_allocation(fresh, 1, 0);
    cf_cholesky *chol = NULL;
    CHECK_STATUS(cf_cholesky_create(fresh, a, NULL, &chol), CF_ERR_NOMEM);
    CHECK_OK(fresh, cf_cholesky_create(fresh, a, NULL, &chol));
    cf_cholesky_destroy(&chol);
    CHECK(cf_context_bytes_in_use(fresh) == 0);
    cf_context_destroy(&fresh);
    cf_sparse_destroy(&a);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* The in-library thread fix (docs/linalg.md): after the first CHOLMOD use
 * the OpenMP max-active-levels ICV is 0, so CHOLMOD's parallel regions run
 * on one thread without OMP_THREAD_LIMIT. */
static void test_thread_fix_applied(void)
{
    cf_context *ctx = cft_context();
    cf_sparse *a = grid_matrix(ctx, 4, 4, 1, 1.0, 0);
    cf_cholesky *chol = NULL;
    CHECK_OK(ctx, cf_cholesky_create(ctx, a, NULL, &chol));
    void *sym = dlsym(RTLD_DEFAULT, "omp_get_max_active_levels");
    CHECK(sym != NULL); /* libgomp comes with CHOLMOD */
    if (sym) {
        int (*get_levels)(void);
        memcpy(&get_levels, &sym, sizeof get_levels);
        CHECK(get_levels() == 0);
    }
    cf_cholesky_destroy(&chol);
    cf_sparse_destroy(&a);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_solve_matches_dense);
    CFT_RUN(test_orderings_agree);
    CFT_RUN(test_shifted_singular_laplacian);
    CFT_RUN(test_not_posdef_names_column);
    CFT_RUN(test_nonfinite_and_misuse);
    CFT_RUN(test_larger_grid);
    CFT_RUN(test_allocation_failures);
    CFT_RUN(test_thread_fix_applied);
    return cft_finish();
}
