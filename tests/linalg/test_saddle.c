/* Saddle-point systems [[A, B^T], [B, -C]] and the UMFPACK LU wrapper:
 * residual of the full system < 1e-10 (relative, 2-norm) through the Schur
 * complement (C > 0), through LU (C = 0, forced LU, Schur complement not
 * positive definite), solutions equal a dense reference; LU on unsymmetric
 * and singular matrices; A stored as its upper triangle; allocation-failure
 * injection. */
#include "test.h"
#include "linalg_test_util.h"

#include "curvflow/linalg.h"

#include <stdlib.h>
#include <string.h>

static int32_t rng_int(int32_t n) { return (int32_t)((rng_unit() + 1.0) * 0.5 * n) % n; }

/* Weighted path/grid Laplacian (positive semi-definite, constants in its
 * null space) plus diag_shift I; both triangles stored. */
static cf_sparse *grid_laplacian(cf_context *ctx, int32_t nx, int32_t ny, double diag_shift)
{
    int32_t n = nx * ny;
    int64_t cap = 8 * (int64_t)n + n;
    int32_t *r = malloc((size_t)cap * 4), *c = malloc((size_t)cap * 4);
    double *v = malloc((size_t)cap * 8);
    int64_t k = 0;
    for (int32_t y = 0; y < ny; ++y)
        for (int32_t x = 0; x < nx; ++x) {
            int32_t i = y * nx + x;
            int32_t nb[2] = {x + 1 < nx ? i + 1 : -1, y + 1 < ny ? i + nx : -1};
            for (int d = 0; d < 2; ++d) {
                if (nb[d] < 0) continue;
                double w = 1.0 + 0.5 * rng_unit();
                int32_t j = nb[d];
                r[k] = i; c[k] = i; v[k++] = w;
                r[k] = j; c[k] = j; v[k++] = w;
                r[k] = i; c[k] = j; v[k++] = -w;
                r[k] = j; c[k] = i; v[k++] = -w;
            }
            r[k] = i; c[k] = i; v[k++] = diag_shift;
        }
    cf_sparse *a = NULL;
    if (cf_sparse_from_triplets(ctx, n, n, k, r, c, v, 1, &a, NULL) != CF_OK) a = NULL;
    free(r); free(c); free(v);
    return a;
}

/* m x n constraint-like matrix: each row touches `per_row` random columns. */
static cf_sparse *random_rows(cf_context *ctx, int32_t m, int32_t n, int32_t per_row)
{
    int64_t k = 0, cap = (int64_t)m * per_row;
    int32_t *r = malloc((size_t)cap * 4), *c = malloc((size_t)cap * 4);
    double *v = malloc((size_t)cap * 8);
    for (int32_t i = 0; i < m; ++i)
        for (int32_t t = 0; t < per_row; ++t) { r[k] = i; c[k] = rng_int(n); v[k++] = rng_unit(); }
    cf_sparse *b = NULL;
    if (cf_sparse_from_triplets(ctx, m, n, k, r, c, v, 0, &b, NULL) != CF_OK) b = NULL;
    free(r); free(c); free(v);
    return b;
}

/* Upper triangle of a (both-triangle) symmetric matrix, flagged upper_only. */
static cf_status upper_triangle_copy(cf_context *ctx, const cf_sparse *a, cf_sparse **out)
{
    int64_t nnz = cf_sparse_nnz(a), k = 0;
    int32_t *r = malloc((size_t)nnz * 4), *c = malloc((size_t)nnz * 4);
    double *v = malloc((size_t)nnz * 8);
    for (int32_t j = 0; j < a->ncols; ++j)
        for (int32_t q = a->colptr[j]; q < a->colptr[j + 1]; ++q)
            if (a->rowind[q] <= j) { r[k] = a->rowind[q]; c[k] = j; v[k++] = a->values[q]; }
    cf_status st = cf_sparse_from_triplets(ctx, a->nrows, a->ncols, k, r, c, v, 1, out, NULL);
    if (st == CF_OK) (*out)->upper_only = 1;
    free(r); free(c); free(v);
    return st;
}

/* Dense K = [[A, B^T], [B, -C]] */
static double *dense_kkt(const cf_sparse *a, const cf_sparse *b, const double *c)
{
    int32_t n = a->ncols, m = b->nrows, N = n + m;
    double *k = calloc((size_t)N * N, sizeof *k);
    for (int32_t j = 0; j < n; ++j) {
        for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) {
            k[(size_t)j * N + a->rowind[p]] += a->values[p];
            if (a->upper_only && a->rowind[p] != j) k[(size_t)a->rowind[p] * N + j] += a->values[p];
        }
        for (int32_t p = b->colptr[j]; p < b->colptr[j + 1]; ++p) {
            k[(size_t)j * N + n + b->rowind[p]] += b->values[p];
            k[(size_t)(n + b->rowind[p]) * N + j] += b->values[p];
        }
    }
    for (int32_t r = 0; r < m; ++r) k[(size_t)(n + r) * N + n + r] -= c ? c[r] : 0.0;
    return k;
}

/* |K z - rhs|_2 / |rhs|_2 computed independently of the library */
static double kkt_residual(const double *k, int32_t N, const double *z, const double *rhs)
{
    double num = 0.0, den = 0.0;
    for (int32_t i = 0; i < N; ++i) {
        double s = -rhs[i];
        for (int32_t j = 0; j < N; ++j) s += k[(size_t)j * N + i] * z[j];
        num += s * s;
        den += rhs[i] * rhs[i];
    }
    return sqrt(num / den);
}

typedef struct problem {
    cf_sparse *a, *b;
    double *c, *f, *g;
    int32_t n, m;
} problem;

static problem make_problem(cf_context *ctx, int32_t nx, int32_t ny, int32_t m, double shift, double cscale)
{
    problem p;
    p.a = grid_laplacian(ctx, nx, ny, shift);
    p.n = nx * ny;
    p.m = m;
    p.b = random_rows(ctx, m, p.n, 4);
    p.c = malloc((size_t)m * sizeof *p.c);
    p.f = malloc((size_t)p.n * sizeof *p.f);
    p.g = malloc((size_t)m * sizeof *p.g);
    for (int32_t r = 0; r < m; ++r) { p.c[r] = cscale * (1.5 + rng_unit()); p.g[r] = rng_unit(); }
    for (int32_t i = 0; i < p.n; ++i) p.f[i] = rng_unit();
    return p;
}

static void free_problem(problem *p)
{
    cf_sparse_destroy(&p->a);
    cf_sparse_destroy(&p->b);
    free(p->c); free(p->f); free(p->g);
}

/* Solves with the given C (NULL: C = 0) and checks the full residual both
 * as reported and recomputed densely, and the solution against the dense
 * reference. Returns the reported residual. */
static double solve_and_check(cf_context *ctx, problem *p, const double *c, const cf_saddle_options *o, int expect_schur)
{
    cf_saddle *s = NULL;
    int32_t N = p->n + p->m;
    double *z = malloc((size_t)N * sizeof *z), *rhs = malloc((size_t)N * sizeof *rhs), *ref = malloc((size_t)N * sizeof *ref);
    memcpy(rhs, p->f, (size_t)p->n * sizeof *rhs);
    memcpy(rhs + p->n, p->g, (size_t)p->m * sizeof *rhs);
    double res = 1.0;
    CHECK_OK(ctx, cf_saddle_create(ctx, p->a, p->b, o, &s));
    if (s) {
        CHECK_OK(ctx, cf_saddle_factorize(s, p->a, p->b, c));
        CHECK(cf_saddle_used_schur(s) == expect_schur);
        CHECK_OK(ctx, cf_saddle_solve(s, p->f, p->g, z, z + p->n));
        res = cf_saddle_residual(s);
        /* the requirement: relative residual of the full system below 1e-10 */
        CHECK_LE(res, 1e-10);
        double *k = dense_kkt(p->a, p->b, c);
        CHECK_LE(kkt_residual(k, N, z, rhs), 1e-10);
        dense_solve(N, k, rhs, ref);
        double md = 0.0, mx = 0.0;
        for (int32_t i = 0; i < N; ++i) { md = fmax(md, fabs(z[i] - ref[i])); mx = fmax(mx, fabs(ref[i])); }
        /* cond(K) here is <= 1e6: 1e-8 relative agreement with the dense solve */
        CHECK_LE(md, 1e-8 * mx);
        free(k);
    }
    cf_saddle_destroy(&s);
    free(z); free(rhs); free(ref);
    return res;
}

static void test_schur_path(void)
{
    cf_context *ctx = cft_context();
    rng_seed(21);
    problem p = make_problem(ctx, 9, 8, 20, 0.0, 1.0); /* A singular PSD, C ~ 1: S is SPD */
    cf_saddle_options o;
    cf_saddle_options_default(&o);
    CHECK(o.refinement_steps == 2 && o.force_lu == 0 && o.block_size == 1);
    double r = solve_and_check(ctx, &p, p.c, &o, 1);
    fprintf(stderr, "   schur residual %.3g\n", r);
    /* a second factorisation with new values of the same pattern */
    for (int32_t k = 0; k < p.m; ++k) p.c[k] *= 0.5;
    r = solve_and_check(ctx, &p, p.c, &o, 1);
    /* block size 2 for the ordering of S (72 = 36 blocks) */
    o.block_size = 2;
    r = solve_and_check(ctx, &p, p.c, &o, 1);
    free_problem(&p);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Small C (~1e-8) makes S = A + B^T C^-1 B ill-conditioned: the plain
 * Schur solve leaves a relative residual ~1e-8 (NOTES.md reports ~1e-6 on
 * its systems) and iterative refinement must bring it below 1e-10. */
static void test_schur_refinement(void)
{
    cf_context *ctx = cft_context();
    rng_seed(22);
    problem p = make_problem(ctx, 10, 10, 30, 1e-3, 1e-8);
    cf_saddle_options o;
    cf_saddle_options_default(&o);
    o.refinement_steps = 0;
    cf_saddle *s = NULL;
    double *x = malloc((size_t)p.n * sizeof *x), *y = malloc((size_t)p.m * sizeof *y);
    CHECK_OK(ctx, cf_saddle_create(ctx, p.a, p.b, &o, &s));
    CHECK_OK(ctx, cf_saddle_factorize(s, p.a, p.b, p.c));
    CHECK_OK(ctx, cf_saddle_solve(s, p.f, p.g, x, y));
    double unrefined = cf_saddle_residual(s);
    cf_saddle_destroy(&s);
    o.refinement_steps = 4;
    double refined = solve_and_check(ctx, &p, p.c, &o, 1);
    fprintf(stderr, "   ill-conditioned Schur: residual %.3g unrefined, %.3g refined\n", unrefined, refined);
    CHECK(unrefined > 1e-10); /* the refinement is what makes the difference here */
    CHECK(refined <= 1e-10);
    free(x); free(y);
    free_problem(&p);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_lu_paths(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    rng_seed(23);
    problem p = make_problem(ctx, 8, 8, 12, 0.1, 1.0);
    cf_saddle_options o;
    cf_saddle_options_default(&o);
    /* C = 0: hard constraints, LU on the full matrix */
    double r = solve_and_check(ctx, &p, NULL, &o, 0);
    fprintf(stderr, "   LU (C = 0) residual %.3g\n", r);
    /* one zero entry in C also needs LU */
    p.c[3] = 0.0;
    solve_and_check(ctx, &p, p.c, &o, 0);
    p.c[3] = 1.0;
    /* forced LU with C > 0 */
    o.force_lu = 1;
    solve_and_check(ctx, &p, p.c, &o, 0);
    o.force_lu = 0;
    /* A indefinite: S not positive definite -> falls back to LU */
    int64_t d = cf_sparse_find(p.a, 5, 5);
    p.a->values[d] = -40.0;
    solve_and_check(ctx, &p, p.c, &o, 0);
    /* bad C */
    cf_saddle *s = NULL;
    CHECK_OK(ctx, cf_saddle_create(ctx, p.a, p.b, &o, &s));
    p.c[2] = -1.0;
    CHECK_STATUS(cf_saddle_factorize(s, p.a, p.b, p.c), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "C[2]") != NULL);
    p.c[2] = 1.0;
    double x[64], y[12];
    CHECK_STATUS(cf_saddle_solve(s, p.f, p.g, x, y), CF_ERR_INVALID_ARG); /* not factorised */
    CHECK_OK(ctx, cf_saddle_factorize(s, p.a, p.b, p.c));
    p.f[0] = NAN;
    CHECK_STATUS(cf_saddle_solve(s, p.f, p.g, x, y), CF_ERR_NUMERICAL);
    cf_saddle_destroy(&s);
    free_problem(&p);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_lu_wrapper(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    rng_seed(24);
    /* unsymmetric: random sparse + dominant diagonal */
    const int32_t n = 50;
    cf_sparse *r = random_rows(ctx, n, n, 5), *a = NULL, *eye = NULL;
    int32_t idx[50];
    double dv[50];
    for (int32_t i = 0; i < n; ++i) { idx[i] = i; dv[i] = 3.0 + rng_unit(); }
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, n, n, n, idx, idx, dv, 0, &eye, NULL));
    CHECK_OK(ctx, cf_sparse_add(ctx, 1.0, r, 1.0, eye, &a));
    double b[50], x[50], ref[50];
    for (int32_t i = 0; i < n; ++i) b[i] = rng_unit();
    cf_lu *lu = NULL;
    CHECK_OK(ctx, cf_lu_create(ctx, a, &lu));
    CHECK_OK(ctx, cf_lu_solve(lu, b, x));
    double *dense = calloc((size_t)n * n, sizeof *dense);
    for (int32_t j = 0; j < n; ++j)
        for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) dense[(size_t)j * n + a->rowind[p]] = a->values[p];
    dense_solve(n, dense, b, ref);
    double md = 0.0;
    for (int32_t i = 0; i < n; ++i) md = fmax(md, fabs(x[i] - ref[i]));
    CHECK_LE(md, 1e-12);
    /* in place */
    memcpy(x, b, sizeof x);
    CHECK_OK(ctx, cf_lu_solve(lu, x, x));
    CHECK_LE(fabs(x[7] - ref[7]), 1e-12);
    /* refactorise with doubled values: half the solution */
    for (int64_t p = 0; p < cf_sparse_nnz(a); ++p) a->values[p] *= 2.0;
    CHECK_OK(ctx, cf_lu_factorize(lu, a));
    CHECK_OK(ctx, cf_lu_solve(lu, b, x));
    CHECK_LE(fabs(2.0 * x[11] - ref[11]), 1e-12);
    /* singular: zero a whole column */
    for (int32_t p = a->colptr[9]; p < a->colptr[10]; ++p) a->values[p] = 0.0;
    CHECK_STATUS(cf_lu_factorize(lu, a), CF_ERR_NUMERICAL);
    CHECK(strstr(cf_context_message(ctx), "singular") != NULL);
    CHECK_STATUS(cf_lu_solve(lu, b, x), CF_ERR_INVALID_ARG);
    cf_lu_destroy(&lu);
    CHECK(lu == NULL);
    /* symmetric matrix given as its upper triangle: mirrored internally */
    cf_sparse *g = grid_laplacian(ctx, 5, 4, 0.5), *gu = NULL;
    CHECK_OK(ctx, upper_triangle_copy(ctx, g, &gu));
    double gb[20], gx[20], gref[20];
    for (int32_t i = 0; i < 20; ++i) gb[i] = rng_unit();
    CHECK_OK(ctx, cf_lu_create(ctx, g, &lu));
    CHECK_OK(ctx, cf_lu_solve(lu, gb, gref));
    cf_lu_destroy(&lu);
    CHECK_OK(ctx, cf_lu_create(ctx, gu, &lu));
    CHECK_OK(ctx, cf_lu_solve(lu, gb, gx));
    md = 0.0;
    for (int32_t i = 0; i < 20; ++i) md = fmax(md, fabs(gx[i] - gref[i]));
    CHECK_LE(md, 1e-13);
    cf_lu_destroy(&lu);
    cf_sparse_destroy(&g);
    cf_sparse_destroy(&gu);
    free(dense);
    cf_sparse_destroy(&r); cf_sparse_destroy(&a); cf_sparse_destroy(&eye);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_allocation_failures(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    rng_seed(25);
    problem p = make_problem(ctx, 5, 4, 6, 0.0, 1.0);
    size_t base = cf_context_bytes_in_use(ctx);
    double x[20], y[6];
    for (int lu = 0; lu < 2; ++lu) {
        int succeeded = 0, failures = 0, wrong = 0;
        for (int64_t k = 1; k < 300 && !succeeded; ++k) {
            cf_context_fail_allocation(ctx, k, 0);
            cf_saddle *s = NULL;
            cf_status st = cf_saddle_create(ctx, p.a, p.b, NULL, &s);
            if (st == CF_OK) st = cf_saddle_factorize(s, p.a, p.b, lu ? NULL : p.c);
            if (st == CF_OK) st = cf_saddle_solve(s, p.f, p.g, x, y);
            if (st == CF_OK) succeeded = 1;
            else if (st == CF_ERR_NOMEM) ++failures;
            else ++wrong;
            cf_saddle_destroy(&s);
            if (cf_context_bytes_in_use(ctx) != base) ++wrong;
        }
        cf_context_fail_allocation(ctx, 0, 0);
        CHECK(succeeded);
        CHECK(failures > 10);
        CHECK(wrong == 0);
    }
    free_problem(&p);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* A stored as its upper triangle only: same results on both paths. */
static void test_upper_only_a(void)
{
    cf_context *ctx = cft_context();
    rng_seed(26);
    problem p = make_problem(ctx, 7, 7, 10, 0.0, 1.0);
    cf_sparse *upper = NULL;
    CHECK_OK(ctx, upper_triangle_copy(ctx, p.a, &upper));
    cf_sparse_destroy(&p.a);
    p.a = upper;
    cf_saddle_options o;
    cf_saddle_options_default(&o);
    solve_and_check(ctx, &p, p.c, &o, 1);
    solve_and_check(ctx, &p, NULL, &o, 0);
    free_problem(&p);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_schur_path);
    CFT_RUN(test_schur_refinement);
    CFT_RUN(test_lu_paths);
    CFT_RUN(test_upper_only_a);
    CFT_RUN(test_lu_wrapper);
    CFT_RUN(test_allocation_failures);
    return cft_finish();
}
