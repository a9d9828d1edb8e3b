/* Cholesky with quaternion_blocks: a quaternionic connection Laplacian
 * (4 x 4 left-multiplication blocks) solved through its complex Hermitian
 * form agrees with the real factorisation and has a small residual, with
 * several right-hand sides, shifts, refactorisations and every ordering;
 * blocks that are not quaternions, partly stored blocks and the wrong block
 * size are refused with messages naming the problem; an indefinite matrix
 * gives NOT_POSDEF; allocation failures leave nothing behind. */
#include "test.h"
#include "linalg_test_util.h"

#include "curvflow/linalg.h"
#include "curvflow/quaternion.h"

#include <stdlib.h>
#include <string.h>

/* Quaternionic connection Laplacian of an nx x ny grid plus shift I:
 * sum over edges ij of w |x_i - r_ij x_j|^2 with random weights w and
 * random quaternions |r_ij| = 0.9, as a real 4 nv x 4 nv matrix of
 * left-multiplication blocks, both triangles stored. With perturb > 0 the
 * off-diagonal block of the first edge gets perturb added to one entry
 * (and to its mirror, keeping the matrix symmetric). */
static cf_sparse *quaternion_grid(cf_context *ctx, int32_t nx, int32_t ny, double shift, double perturb)
{
    int32_t nv = nx * ny, n = 4 * nv;
    int64_t cap = (int64_t)2 * nv * 4 * 16 + (int64_t)16 * nv;
    int32_t *r = malloc((size_t)cap * sizeof *r), *c = malloc((size_t)cap * sizeof *c);
    double *v = malloc((size_t)cap * sizeof *v);
    int64_t k = 0;
    int first = 1;
    for (int32_t y = 0; y < ny; ++y)
        for (int32_t x = 0; x < nx; ++x)
            for (int dir = 0; dir < 2; ++dir) {
                int32_t i = y * nx + x, j;
                if (dir == 0 && x + 1 < nx) j = i + 1;
                else if (dir == 1 && y + 1 < ny) j = i + nx;
                else continue;
                double w = 1.0 + 0.5 * rng_unit();
                cf_quat q = {rng_unit(), rng_unit(), rng_unit(), rng_unit()};
                double len = sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
                q.w *= 0.9 / len; q.x *= 0.9 / len; q.y *= 0.9 / len; q.z *= 0.9 / len;
                double lq[16], lr[16];
                cf_quat_left_matrix(q, lq); /* row-major */
                cf_quat_left_matrix((cf_quat){w, 0.0, 0.0, 0.0}, lr);
                for (int p = 0; p < 4; ++p)
                    for (int s = 0; s < 4; ++s) {
                        /* (i, i) and (j, j): w (1 and |r|^2) I; (i, j): -w L(r); (j, i) = its transpose */
                        r[k] = 4 * i + p; c[k] = 4 * i + s; v[k++] = lr[4 * p + s];
                        r[k] = 4 * j + p; c[k] = 4 * j + s; v[k++] = 0.81 * lr[4 * p + s];
                        double e = -w * lq[4 * p + s] + (first && p == 1 && s == 2 ? perturb : 0.0);
                        r[k] = 4 * i + p; c[k] = 4 * j + s; v[k++] = e;
                        r[k] = 4 * j + s; c[k] = 4 * i + p; v[k++] = e;
                    }
                first = 0;
            }
    for (int32_t i = 0; i < n; ++i) { r[k] = i; c[k] = i; v[k++] = shift; }
    cf_sparse *a = NULL;
    if (cf_sparse_from_triplets(ctx, n, n, k, r, c, v, 1, &a, NULL) != CF_OK) a = NULL;
    free(r); free(c); free(v);
    return a;
}

static double residual(const cf_sparse *a, const double *x, const double *b)
{
    int32_t n = a->nrows;
    double *ax = malloc((size_t)n * sizeof *ax), num = 0.0, den = 0.0;
    cf_sparse_multiply(a, x, ax);
    for (int32_t i = 0; i < n; ++i) {
        num += (ax[i] - b[i]) * (ax[i] - b[i]);
        den += b[i] * b[i];
    }
    free(ax);
    return sqrt(num / den);
}

/* Options for 4 x 4 blocks with or without the complex form. */
static cf_cholesky_options block_options(int quaternion, cf_ordering ordering)
{
    cf_cholesky_options o;
    cf_cholesky_options_default(&o);
    o.block_size = 4;
    o.ordering = ordering;
    o.quaternion_blocks = quaternion;
    return o;
}

static cf_status factor_and_solve(cf_context *ctx, const cf_sparse *a, int quaternion, cf_ordering ordering, double shift,
                                  int32_t nrhs, const double *b, double *x)
{
    cf_cholesky_options o = block_options(quaternion, ordering);
    cf_cholesky *chol = NULL;
    cf_status st = cf_cholesky_create(ctx, a, &o, &chol);
    if (st == CF_OK) st = cf_cholesky_factorize_shifted(chol, a, shift);
    if (st == CF_OK) st = cf_cholesky_solve(chol, nrhs, b, x);
    cf_cholesky_destroy(&chol);
    return st;
}

static void test_matches_real_factorisation(void)
{
    cf_context *ctx = cft_context();
    rng_seed(11);
    cf_sparse *a = quaternion_grid(ctx, 13, 11, 0.05, 0.0);
    CHECK(a != NULL);
    if (!a) return;
    int32_t n = a->nrows, nrhs = 3;
    double *b = malloc((size_t)n * nrhs * sizeof *b), *xr = malloc((size_t)n * nrhs * sizeof *xr),
           *xq = malloc((size_t)n * nrhs * sizeof *xq);
    for (int32_t i = 0; i < n * nrhs; ++i) b[i] = rng_unit();
    const cf_ordering orderings[] = {CF_ORDERING_AUTO, CF_ORDERING_AMD, CF_ORDERING_METIS, CF_ORDERING_NATURAL,
                                     CF_ORDERING_AUTO_REFACTORISED};
    for (int o = 0; o < 5; ++o) {
        for (int s = 0; s < 2; ++s) {
            double shift = s ? 0.7 : 0.0;
            CHECK_OK(ctx, factor_and_solve(ctx, a, 0, orderings[o], shift, nrhs, b, xr));
            CHECK_OK(ctx, factor_and_solve(ctx, a, 1, orderings[o], shift, nrhs, b, xq));
            double diff = 0.0, size = 0.0;
            for (int32_t i = 0; i < n * nrhs; ++i) {
                diff = fmax(diff, fabs(xr[i] - xq[i]));
                size = fmax(size, fabs(xr[i]));
            }
            CHECK_LE(diff, 1e-11 * size);
            if (shift == 0.0)
                for (int32_t k = 0; k < nrhs; ++k) CHECK_LE(residual(a, xq + (size_t)k * n, b + (size_t)k * n), 1e-12);
        }
    }
    free(b); free(xr); free(xq);
    cf_sparse_destroy(&a);
    cf_context_destroy(&ctx);
}

/* Refactorisation with new values in the same pattern, a growing number of
 * right-hand sides (the complex workspace is regrown), and x == b. */
static void test_refactorise_and_workspace(void)
{
    cf_context *ctx = cft_context();
    rng_seed(5);
    cf_sparse *a = quaternion_grid(ctx, 9, 8, 0.1, 0.0);
    rng_seed(6);
    cf_sparse *a2 = quaternion_grid(ctx, 9, 8, 0.3, 0.0);
    CHECK(a && a2);
    if (!a || !a2) return;
    int32_t n = a->nrows;
    cf_cholesky_options o = block_options(1, CF_ORDERING_AUTO);
    cf_cholesky *chol = NULL;
    CHECK_OK(ctx, cf_cholesky_create(ctx, a, &o, &chol));
    double *b = malloc((size_t)n * 4 * sizeof *b), *x = malloc((size_t)n * 4 * sizeof *x);
    for (int32_t i = 0; i < 4 * n; ++i) b[i] = rng_unit();
    for (int pass = 0; pass < 2; ++pass) {
        const cf_sparse *m = pass ? a2 : a;
        CHECK_OK(ctx, cf_cholesky_factorize(chol, m));
        CHECK_OK(ctx, cf_cholesky_solve(chol, 1, b, x));
        CHECK_LE(residual(m, x, b), 1e-12);
        CHECK_OK(ctx, cf_cholesky_solve(chol, 4, b, x));
        for (int32_t k = 0; k < 4; ++k) CHECK_LE(residual(m, x + (size_t)k * n, b + (size_t)k * n), 1e-12);
        memcpy(x, b, (size_t)n * 2 * sizeof *x);
        CHECK_OK(ctx, cf_cholesky_solve(chol, 2, x, x));
        for (int32_t k = 0; k < 2; ++k) CHECK_LE(residual(m, x + (size_t)k * n, b + (size_t)k * n), 1e-12);
    }
    cf_cholesky_destroy(&chol);
    free(b); free(x);
    cf_sparse_destroy(&a);
    cf_sparse_destroy(&a2);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_refuses_non_quaternion_input(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    rng_seed(3);
    cf_sparse *bad = quaternion_grid(ctx, 5, 4, 0.1, 1e-3);
    CHECK(bad != NULL);
    if (!bad) return;
    cf_cholesky_options o = block_options(1, CF_ORDERING_AUTO);
    cf_cholesky *chol = NULL;
    /* symmetric but one off-diagonal block is not a left multiplication
     * (the first edge joins vertices 0 and 1) */
    CHECK_OK(ctx, cf_cholesky_create(ctx, bad, &o, &chol));
    CHECK_STATUS(cf_cholesky_factorize(chol, bad), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "block (0, 1)") != NULL);
    CHECK(strstr(cf_context_message(ctx), "left-multiplication") != NULL);
    double b[80] = {1.0}, x[80];
    CHECK_STATUS(cf_cholesky_solve(chol, 1, b, x), CF_ERR_INVALID_ARG); /* no factorisation */
    cf_cholesky_destroy(&chol);
    /* the real path takes the same matrix */
    o.quaternion_blocks = 0;
    CHECK_OK(ctx, cf_cholesky_create(ctx, bad, &o, &chol));
    CHECK_OK(ctx, cf_cholesky_factorize(chol, bad));
    cf_cholesky_destroy(&chol);
    /* a diagonal block that is not a real multiple of the identity */
    rng_seed(3);
    cf_sparse *diag = quaternion_grid(ctx, 5, 4, 0.1, 0.0);
    diag->values[diag->colptr[0]] += 0.5; /* entry (0, 0) */
    o.quaternion_blocks = 1;
    CHECK_OK(ctx, cf_cholesky_create(ctx, diag, &o, &chol));
    CHECK_STATUS(cf_cholesky_factorize(chol, diag), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "block (0, 0)") != NULL);
    cf_cholesky_destroy(&chol);
    /* indefinite: NOT_POSDEF names a column */
    CHECK_OK(ctx, cf_cholesky_create(ctx, diag, &o, &chol));
    rng_seed(3);
    cf_sparse *good = quaternion_grid(ctx, 5, 4, 0.1, 0.0);
    CHECK_STATUS(cf_cholesky_factorize_shifted(chol, good, -100.0), CF_ERR_NOT_POSDEF);
    CHECK(strstr(cf_context_message(ctx), "not positive definite at column") != NULL);
    CHECK_OK(ctx, cf_cholesky_factorize(chol, good));
    cf_cholesky_destroy(&chol);
    /* wrong block size */
    o.block_size = 2;
    CHECK_STATUS(cf_cholesky_create(ctx, good, &o, &chol), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "block size 4") != NULL);
    /* blocks not stored whole: the identity has one entry per column */
    o.block_size = 4;
    int32_t idx[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    double ones[8] = {1, 1, 1, 1, 1, 1, 1, 1};
    cf_sparse *eye = NULL;
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, 8, 8, 8, idx, idx, ones, 1, &eye, NULL));
    CHECK_STATUS(cf_cholesky_create(ctx, eye, &o, &chol), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "stored whole") != NULL);
    CHECK(chol == NULL);
    cf_sparse_destroy(&eye);
    cf_sparse_destroy(&good);
    cf_sparse_destroy(&diag);
    cf_sparse_destroy(&bad);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

typedef struct {
    const cf_sparse *a;
    const double *b;
    double *x;
} sweep_data;

static cf_status sweep_call(cf_context *ctx, void *user)
{
    sweep_data *d = user;
    cf_cholesky_options o = block_options(1, CF_ORDERING_AUTO);
    cf_cholesky *chol = NULL;
    cf_status st = cf_cholesky_create(ctx, d->a, &o, &chol);
    if (st == CF_OK) st = cf_cholesky_factorize(chol, d->a);
    if (st == CF_OK) st = cf_cholesky_solve(chol, 2, d->b, d->x);
    cf_cholesky_destroy(&chol);
    return st;
}

static void test_allocation_failures(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    rng_seed(9);
    cf_sparse *a = quaternion_grid(ctx, 4, 3, 0.2, 0.0);
    CHECK(a != NULL);
    if (!a) return;
    double b[96], x[96];
    for (int i = 0; i < 96; ++i) b[i] = rng_unit();
    sweep_data d = {a, b, x};
    int64_t count = cft_allocation_sweep(ctx, "quaternion cholesky", sweep_call, &d, 1);
    CHECK(count >= 8);
    cf_sparse_destroy(&a);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_matches_real_factorisation);
    CFT_RUN(test_refactorise_and_workspace);
    CFT_RUN(test_refuses_non_quaternion_input);
    CFT_RUN(test_allocation_failures);
    return cft_finish();
}
