/*
 * cf_min_quad: minimise 1/2 x^T A x + b^T x subject to x[known] = y and
 * Aeq x = beq, precompute / solve. Hand-solved small problems (a 1D
 * Dirichlet problem, the minimum-norm point of a plane with and without a
 * fixed coordinate), a grid Laplacian whose harmonic extension of linear
 * boundary data is the linear function, random problems against a dense
 * reference (the KKT system solved by Gaussian elimination) with the
 * constraint residuals, refactorisation for new values, chunked
 * multi-column solves, no allocation in solves, bad input and an
 * allocation-failure sweep.
 */
#include "curvflow/linalg.h"
#include "linalg_test_util.h"
#include "test.h"

#include <stdio.h>
#include <string.h>

/* Sparse matrix from a dense column-major one (entries with |v| > 0). */
static cf_sparse *from_dense(cf_context *ctx, int32_t nr, int32_t nc, const double *d, int32_t symmetric)
{
    int64_t n = 0;
    int32_t *r = malloc(sizeof(int32_t) * (size_t)nr * nc + 1), *c = malloc(sizeof(int32_t) * (size_t)nr * nc + 1);
    double *v = malloc(sizeof(double) * (size_t)nr * nc + 1);
    for (int32_t j = 0; j < nc; ++j)
        for (int32_t i = 0; i < nr; ++i)
            if (d[(size_t)j * nr + i] != 0.0) {
                r[n] = i;
                c[n] = j;
                v[n++] = d[(size_t)j * nr + i];
            }
    cf_sparse *s = NULL;
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, nr, nc, n, r, c, v, symmetric, &s, NULL));
    free(r);
    free(c);
    free(v);
    return s;
}

/* 1D Dirichlet problem: A = tridiag(-1, 2, -1) on 3 variables, x0 = 1 and
 * x2 = 3 known: 2 x1 = -b1 + x0 + x2, so x1 = 2 for b = 0 and 3 for
 * b1 = -2 (two columns at once). */
static void test_dirichlet_by_hand(void)
{
    cf_context *ctx = cft_context();
    const double ad[9] = {2, -1, 0, -1, 2, -1, 0, -1, 2};
    cf_sparse *a = from_dense(ctx, 3, 3, ad, 1);
    const int32_t known[2] = {2, 0}; /* any order: y follows it */
    cf_min_quad_options o;
    cf_min_quad_options_default(&o);
    o.max_rhs = 2;
    cf_min_quad *q = NULL;
    CHECK_OK(ctx, cf_min_quad_create(ctx, a, 2, known, NULL, &o, &q));
    CHECK(cf_min_quad_free_count(q) == 1);
    const double b[6] = {0, 0, 0, 0, -2, 0}, y[4] = {3, 1, 3, 1};
    double x[6];
    CHECK_OK(ctx, cf_min_quad_solve(q, 2, b, y, NULL, x));
    CHECK_NEAR(x[1], 2.0, 0, 1e-15);
    CHECK_NEAR(x[4], 3.0, 0, 1e-15);
    CHECK(x[0] == 1.0 && x[2] == 3.0 && x[3] == 1.0 && x[5] == 3.0);
    /* b NULL is zero; y NULL is zero: x1 = 0 */
    CHECK_OK(ctx, cf_min_quad_solve(q, 1, NULL, y, NULL, x));
    CHECK_NEAR(x[1], 2.0, 0, 1e-15);
    CHECK_OK(ctx, cf_min_quad_solve(q, 1, NULL, NULL, NULL, x));
    CHECK(x[0] == 0.0 && x[1] == 0.0 && x[2] == 0.0);
    /* new known values in the same array are seen (A_uk y is reused only
     * while y is unchanged): x0 = 5, x2 = 3 gives x1 = 4 */
    double y2[2] = {3, 1};
    CHECK_OK(ctx, cf_min_quad_solve(q, 1, NULL, y2, NULL, x));
    CHECK_NEAR(x[1], 2.0, 0, 1e-15);
    y2[1] = 5;
    CHECK_OK(ctx, cf_min_quad_solve(q, 1, NULL, y2, NULL, x));
    CHECK_NEAR(x[1], 4.0, 0, 1e-15);
    CHECK(x[0] == 5.0);
    cf_min_quad_destroy(&q);
    CHECK(q == NULL);
    cf_sparse_destroy(&a);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Minimum-norm point of x0 + x1 + x2 = beq: (1, 1, 1) beq / 3; with x2 = 0
 * known, (1, 1, 0) beq / 2. Columns beq = 3 and 6. */
static void test_plane_by_hand(void)
{
    cf_context *ctx = cft_context();
    const double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, ones[3] = {1, 1, 1};
    cf_sparse *a = from_dense(ctx, 3, 3, id, 1), *aeq = from_dense(ctx, 1, 3, ones, 0);
    cf_min_quad *q = NULL;
    CHECK_OK(ctx, cf_min_quad_create(ctx, a, 0, NULL, aeq, NULL, &q));
    const double beq[2] = {3, 6};
    double x[6];
    CHECK_OK(ctx, cf_min_quad_solve(q, 2, NULL, NULL, beq, x));
    for (int k = 0; k < 3; ++k) {
        CHECK_NEAR(x[k], 1.0, 0, 1e-14);
        CHECK_NEAR(x[3 + k], 2.0, 0, 1e-14);
    }
    cf_min_quad_destroy(&q);
    const int32_t k2 = 2;
    const double y[2] = {0, 0};
    CHECK_OK(ctx, cf_min_quad_create(ctx, a, 1, &k2, aeq, NULL, &q));
    CHECK_OK(ctx, cf_min_quad_solve(q, 2, NULL, y, beq, x));
    CHECK_NEAR(x[0], 1.5, 0, 1e-14);
    CHECK_NEAR(x[1], 1.5, 0, 1e-14);
    CHECK(x[2] == 0.0);
    CHECK_NEAR(x[3], 3.0, 0, 1e-14);
    CHECK_NEAR(x[4], 3.0, 0, 1e-14);
    CHECK(x[5] == 0.0);
    /* the linear term shifts the optimum along the plane: b = (-1, 1, 0)
     * with x2 = 0 and x0 + x1 = 3: x0 - 1 = x1 + 1 (equal multipliers),
     * x = (2.5, 0.5, 0) */
    const double b[3] = {-1, 1, 0};
    CHECK_OK(ctx, cf_min_quad_solve(q, 1, b, y, beq, x));
    CHECK_NEAR(x[0], 2.5, 0, 1e-14);
    CHECK_NEAR(x[1], 0.5, 0, 1e-14);
    cf_min_quad_destroy(&q);
    cf_sparse_destroy(&a);
    cf_sparse_destroy(&aeq);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Graph Laplacian (4-neighbour, unit weights) of a g x g grid; vertex
 * i + g j. Linear functions are harmonic at interior vertices, so fixing the
 * boundary to a + b i + c j gives that function everywhere. */
static cf_sparse *grid_laplacian(cf_context *ctx, int32_t g)
{
    int32_t n = g * g;
    int64_t cap = 5 * (int64_t)n, t = 0;
    int32_t *r = malloc(sizeof(int32_t) * cap), *c = malloc(sizeof(int32_t) * cap);
    double *v = malloc(sizeof(double) * cap);
    for (int32_t j = 0; j < g; ++j)
        for (int32_t i = 0; i < g; ++i) {
            int32_t p = i + g * j, deg = 0;
            const int32_t di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
            for (int k = 0; k < 4; ++k) {
                int32_t ii = i + di[k], jj = j + dj[k];
                if (ii < 0 || jj < 0 || ii >= g || jj >= g) continue;
                r[t] = p;
                c[t] = ii + g * jj;
                v[t++] = -1.0;
                ++deg;
            }
            r[t] = p;
            c[t] = p;
            v[t++] = deg;
        }
    cf_sparse *l = NULL;
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, n, n, t, r, c, v, 1, &l, NULL));
    free(r);
    free(c);
    free(v);
    return l;
}

static void test_grid_harmonic(void)
{
    cf_context *ctx = cft_context();
    const int32_t g = 20, n = g * g;
    cf_sparse *l = grid_laplacian(ctx, g);
    int32_t *known = malloc(sizeof(int32_t) * n);
    double *y = malloc(sizeof(double) * 2 * n), *x = malloc(sizeof(double) * 2 * n);
    int32_t nk = 0;
    for (int32_t j = 0; j < g; ++j)
        for (int32_t i = 0; i < g; ++i)
            if (i == 0 || j == 0 || i == g - 1 || j == g - 1) known[nk++] = i + g * j;
    for (int32_t k = 0; k < nk; ++k) {
        int32_t i = known[k] % g, j = known[k] / g;
        y[k] = 0.5 + 2.0 * i - 1.5 * j;
        y[nk + k] = -3.0 + 0.25 * j;
    }
    cf_min_quad_options o;
    cf_min_quad_options_default(&o);
    o.max_rhs = 2;
    cf_min_quad *q = NULL;
    CHECK_OK(ctx, cf_min_quad_create(ctx, l, nk, known, NULL, &o, &q));
    CHECK(cf_min_quad_free_count(q) == (g - 2) * (g - 2));
    CHECK_OK(ctx, cf_min_quad_solve(q, 2, NULL, y, NULL, x));
    double err = 0.0;
    for (int32_t p = 0; p < n; ++p) {
        int32_t i = p % g, j = p / g;
        err = fmax(err, fabs(x[p] - (0.5 + 2.0 * i - 1.5 * j)));
        err = fmax(err, fabs(x[n + p] - (-3.0 + 0.25 * j)));
    }
    CHECK_LE(err, 1e-12);
    /* solves with at most max_rhs columns allocate nothing */
    int64_t before = cf_context_allocation_count(ctx);
    for (int it = 0; it < 5; ++it) CHECK_OK(ctx, cf_min_quad_solve(q, 2, NULL, y, NULL, x));
    CHECK(cf_context_allocation_count(ctx) == before);
    /* new values, same pattern: 3 L gives the same harmonic functions */
    for (int64_t p = 0; p < cf_sparse_nnz(l); ++p) l->values[p] *= 3.0;
    CHECK_OK(ctx, cf_min_quad_factorize(q, l, NULL));
    CHECK_OK(ctx, cf_min_quad_solve(q, 2, NULL, y, NULL, x));
    for (int32_t p = 0; p < n; ++p) CHECK_NEAR(x[p], 0.5 + 2.0 * (p % g) - 1.5 * (p / g), 0, 1e-12);
    /* without any known value the Laplacian is singular */
    cf_min_quad *q2 = NULL;
    CHECK_STATUS(cf_min_quad_create(ctx, l, 0, NULL, NULL, NULL, &q2), CF_ERR_NOT_POSDEF);
    CHECK(q2 == NULL);
    CHECK(strstr(cf_context_message(ctx), "min_quad") != NULL);
    /* ... but an equality on the mean removes the kernel (saddle path):
     * minimise 1/2 x^T L x + b^T x with sum x = 0 and b = e_0 - e_{n-1} */
    double *ones = malloc(sizeof(double) * n), *b = calloc((size_t)n, sizeof(double));
    for (int32_t p = 0; p < n; ++p) ones[p] = 1.0;
    b[0] = 1.0;
    b[n - 1] = -1.0;
    cf_sparse *aeq = from_dense(ctx, 1, n, ones, 0);
    CHECK_OK(ctx, cf_min_quad_create(ctx, l, 0, NULL, aeq, NULL, &q2));
    double zero = 0.0;
    CHECK_OK(ctx, cf_min_quad_solve(q2, 1, b, NULL, &zero, x));
    /* optimality: 3 L x + b = -lambda 1 with lambda = -mean(b) = 0 here; sum x = 0 */
    double *r = malloc(sizeof(double) * n), sum = 0.0, res = 0.0;
    cf_sparse_multiply(l, x, r);
    for (int32_t p = 0; p < n; ++p) {
        sum += x[p];
        res = fmax(res, fabs(r[p] + b[p]));
    }
    CHECK_LE(fabs(sum), 1e-12);
    CHECK_LE(res, 1e-10);
    cf_min_quad_destroy(&q2);
    cf_sparse_destroy(&aeq);
    free(ones);
    free(b);
    free(r);
    cf_min_quad_destroy(&q);
    cf_sparse_destroy(&l);
    free(known);
    free(y);
    free(x);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Random SPD A (n x n, dense-ish), known set, Aeq (m x n), nrhs columns:
 * the dense KKT system over all n variables
 *   [ A_uu  A_uk  Aeq_u^T ]   rows of the free variables
 *   [ 0     I     0       ]   x_k = y
 *   [ Aeq_u Aeq_k 0       ]   Aeq x = beq
 * solved by Gaussian elimination is the reference. */
static void random_problem(int32_t n, int32_t nk, int32_t m, int32_t nrhs, int32_t max_rhs, uint64_t seed)
{
    cf_context *ctx = cft_context();
    rng_seed(seed);
    double *r = malloc(sizeof(double) * n * n), *ad = calloc((size_t)n * n, sizeof(double));
    for (int32_t i = 0; i < n * n; ++i) r[i] = rng_unit() > 0.4 ? rng_unit() : 0.0;
    for (int32_t j = 0; j < n; ++j)
        for (int32_t i = 0; i < n; ++i) {
            double s = i == j ? 0.5 : 0.0;
            for (int32_t k = 0; k < n; ++k) s += r[(size_t)i * n + k] * r[(size_t)j * n + k];
            ad[(size_t)j * n + i] = s;
        }
    double *ed = malloc(sizeof(double) * (m > 0 ? m : 1) * n);
    for (int32_t i = 0; i < m * n; ++i) ed[i] = rng_unit();
    /* known: steps of 7 (coprime to n) from a random start, listed backwards */
    int32_t *known = malloc(sizeof(int32_t) * (nk > 0 ? nk : 1));
    int32_t start = (int32_t)(fabs(rng_unit()) * 3.0);
    for (int32_t k = 0; k < nk; ++k) known[nk - 1 - k] = (start + 7 * k) % n;
    double *b = malloc(sizeof(double) * n * nrhs), *y = malloc(sizeof(double) * (nk > 0 ? nk : 1) * nrhs);
    double *beq = malloc(sizeof(double) * (m > 0 ? m : 1) * nrhs), *x = malloc(sizeof(double) * n * nrhs);
    for (int32_t i = 0; i < n * nrhs; ++i) b[i] = rng_unit();
    for (int32_t i = 0; i < nk * nrhs; ++i) y[i] = rng_unit();
    for (int32_t i = 0; i < m * nrhs; ++i) beq[i] = rng_unit();

    cf_sparse *a = from_dense(ctx, n, n, ad, 1), *aeq = m > 0 ? from_dense(ctx, m, n, ed, 0) : NULL;
    cf_min_quad_options o;
    cf_min_quad_options_default(&o);
    o.max_rhs = max_rhs;
    cf_min_quad *q = NULL;
    CHECK_OK(ctx, cf_min_quad_create(ctx, a, nk, known, aeq, &o, &q));
    if (!q) return;
    CHECK_OK(ctx, cf_min_quad_solve(q, nrhs, b, y, m > 0 ? beq : NULL, x));

    int32_t big = n + m;
    double *kkt = malloc(sizeof(double) * big * big), *rhs = malloc(sizeof(double) * big), *sol = malloc(sizeof(double) * big);
    char *is_known = calloc((size_t)n, 1);
    int32_t *slot = malloc(sizeof(int32_t) * n);
    for (int32_t k = 0; k < nk; ++k) {
        is_known[known[k]] = 1;
        slot[known[k]] = k;
    }
    double worst = 0.0, worst_eq = 0.0;
    for (int32_t c = 0; c < nrhs; ++c) {
        memset(kkt, 0, sizeof(double) * big * big);
        for (int32_t i = 0; i < n; ++i) {
            if (is_known[i]) {
                kkt[(size_t)i * big + i] = 1.0;
                rhs[i] = y[(size_t)c * nk + slot[i]];
                continue;
            }
            for (int32_t j = 0; j < n; ++j) kkt[(size_t)j * big + i] = ad[(size_t)j * n + i];
            for (int32_t e = 0; e < m; ++e) kkt[(size_t)(n + e) * big + i] = ed[(size_t)i * m + e];
            rhs[i] = -b[(size_t)c * n + i];
        }
        for (int32_t e = 0; e < m; ++e) {
            for (int32_t j = 0; j < n; ++j) kkt[(size_t)j * big + n + e] = ed[(size_t)j * m + e];
            rhs[n + e] = beq[(size_t)c * m + e];
        }
        dense_solve(big, kkt, rhs, sol);
        double scale = 0.0;
        for (int32_t i = 0; i < n; ++i) scale = fmax(scale, fabs(sol[i]));
        for (int32_t i = 0; i < n; ++i) worst = fmax(worst, fabs(x[(size_t)c * n + i] - sol[i]) / scale);
        for (int32_t k = 0; k < nk; ++k) CHECK(x[(size_t)c * n + known[k]] == y[(size_t)c * nk + k]);
        /* constraint residual |Aeq x - beq| relative to |Aeq| |x| */
        for (int32_t e = 0; e < m; ++e) {
            double s = -beq[(size_t)c * m + e], mag = fabs(beq[(size_t)c * m + e]);
            for (int32_t j = 0; j < n; ++j) {
                s += ed[(size_t)j * m + e] * x[(size_t)c * n + j];
                mag += fabs(ed[(size_t)j * m + e] * x[(size_t)c * n + j]);
            }
            worst_eq = fmax(worst_eq, fabs(s) / mag);
        }
    }
    fprintf(stderr, "n %d, known %d, equalities %d, %d columns (max_rhs %d): max rel. error %.2e, constraint residual %.2e\n",
            n, nk, m, nrhs, max_rhs, worst, worst_eq);
    CHECK_LE(worst, 1e-10);
    CHECK_LE(worst_eq, 1e-13);
    free(kkt);
    free(rhs);
    free(sol);
    free(is_known);
    free(slot);
    cf_min_quad_destroy(&q);
    cf_sparse_destroy(&a);
    cf_sparse_destroy(&aeq);
    free(r);
    free(ad);
    free(ed);
    free(known);
    free(b);
    free(y);
    free(beq);
    free(x);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_dense_reference(void)
{
    random_problem(15, 4, 0, 3, 3, 1);  /* Cholesky path */
    random_problem(15, 4, 2, 3, 1, 2);  /* saddle path, one column at a time */
    random_problem(30, 0, 3, 5, 2, 3);  /* no known values, chunks of 2 columns */
    random_problem(30, 10, 1, 1, 1, 4);
    random_problem(12, 12, 0, 2, 2, 5); /* everything known: x = y */
}

static void test_bad_input(void)
{
    cf_context *ctx = cft_context();
    const double ad[9] = {2, -1, 0, -1, 2, -1, 0, -1, 2};
    cf_sparse *a = from_dense(ctx, 3, 3, ad, 1);
    cf_min_quad *q = NULL;
    const int32_t rep[2] = {1, 1}, out[1] = {3};
    CHECK_STATUS(cf_min_quad_create(ctx, a, 2, rep, NULL, NULL, &q), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "variable 1 is known twice") != NULL);
    CHECK_STATUS(cf_min_quad_create(ctx, a, 1, out, NULL, NULL, &q), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "known[0] = 3") != NULL);
    CHECK_STATUS(cf_min_quad_create(ctx, a, 1, NULL, NULL, NULL, &q), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_min_quad_create(ctx, NULL, 0, NULL, NULL, NULL, &q), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_min_quad_create(ctx, a, 0, NULL, NULL, NULL, NULL), CF_ERR_INVALID_ARG);
    /* unsymmetric values and pattern */
    const double un[9] = {2, -1, 0, -1.5, 2, -1, 0, -1, 2};
    cf_sparse *u = from_dense(ctx, 3, 3, un, 1);
    CHECK_STATUS(cf_min_quad_create(ctx, u, 0, NULL, NULL, NULL, &q), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "A is not symmetric: A(0, 1)") != NULL);
    cf_sparse_destroy(&u);
    const double up[9] = {2, 0, 0, -1, 2, 0, 0, -1, 2};
    u = from_dense(ctx, 3, 3, up, 0);
    CHECK_STATUS(cf_min_quad_create(ctx, u, 0, NULL, NULL, NULL, &q), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "structurally symmetric") != NULL);
    cf_sparse_destroy(&u);
    const double low[9] = {2, -1, 0, 0, 2, -1, 0, 0, 2};
    u = from_dense(ctx, 3, 3, low, 0);
    CHECK_STATUS(cf_min_quad_create(ctx, u, 0, NULL, NULL, NULL, &q), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "A(1, 0) is stored, A(0, 1) not") != NULL);
    cf_sparse_destroy(&u);
    /* a non-finite value is named */
    a->values[1] = NAN;
    CHECK_STATUS(cf_min_quad_create(ctx, a, 0, NULL, NULL, NULL, &q), CF_ERR_NONFINITE);
    CHECK(strstr(cf_context_message(ctx), "A(1, 0) is not finite") != NULL);
    a->values[1] = -1.0;
    /* equalities with every variable known */
    const double ones[3] = {1, 1, 1};
    const int32_t all[3] = {0, 1, 2};
    cf_sparse *aeq = from_dense(ctx, 1, 3, ones, 0);
    CHECK_STATUS(cf_min_quad_create(ctx, a, 3, all, aeq, NULL, &q), CF_ERR_INVALID_ARG);
    /* dependent constraint rows make the saddle system singular */
    const double twice[6] = {1, 2, 1, 2, 1, 2};
    cf_sparse *dep = from_dense(ctx, 2, 3, twice, 0);
    cf_status st = cf_min_quad_create(ctx, a, 0, NULL, dep, NULL, &q);
    CHECK(st == CF_ERR_NUMERICAL || st == CF_ERR_NOT_POSDEF);
    CHECK(q == NULL);
    cf_sparse_destroy(&dep);
    /* solve: non-finite input named; factorize: pattern must match */
    const int32_t k0 = 0;
    CHECK_OK(ctx, cf_min_quad_create(ctx, a, 1, &k0, NULL, NULL, &q));
    double b[3] = {0, INFINITY, 0}, y = 1.0, x[3];
    CHECK_STATUS(cf_min_quad_solve(q, 1, b, &y, NULL, x), CF_ERR_NUMERICAL);
    CHECK(strstr(cf_context_message(ctx), "b[1] (column 0) is not finite") != NULL);
    CHECK_STATUS(cf_min_quad_solve(q, 1, NULL, &y, NULL, NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_min_quad_factorize(q, aeq, NULL), CF_ERR_INVALID_ARG);
    const double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    cf_sparse *other = from_dense(ctx, 3, 3, id, 1);
    CHECK_STATUS(cf_min_quad_factorize(q, other, NULL), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "pattern of A differs") != NULL);
    /* a failed factorisation refuses solves until one succeeds */
    CHECK_STATUS(cf_min_quad_solve(q, 1, NULL, &y, NULL, x), CF_ERR_INVALID_ARG);
    CHECK_OK(ctx, cf_min_quad_factorize(q, a, NULL));
    CHECK_OK(ctx, cf_min_quad_solve(q, 1, NULL, &y, NULL, x));
    CHECK_NEAR(x[2], 1.0 / 3.0, 0, 1e-15); /* [2 -1; -1 2] [x1 x2] = [1 0] */
    cf_min_quad_destroy(&q);
    cf_sparse_destroy(&other);
    cf_sparse_destroy(&aeq);
    cf_sparse_destroy(&a);
    cf_min_quad_destroy(NULL);
    CHECK(cf_min_quad_free_count(NULL) == 0);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

typedef struct sweep_data {
    const cf_sparse *a, *aeq;
    int32_t nk;
    const int32_t *known;
} sweep_data;

static cf_status sweep_call(cf_context *ctx, void *user)
{
    const sweep_data *d = user;
    cf_min_quad_options o;
    cf_min_quad_options_default(&o);
    o.max_rhs = 2;
    cf_min_quad *q = NULL;
    cf_status st = cf_min_quad_create(ctx, d->a, d->nk, d->known, d->aeq, &o, &q);
    if (st == CF_OK) {
        double x[2 * 64];
        st = cf_min_quad_solve(q, 2, NULL, NULL, NULL, x);
    }
    cf_min_quad_destroy(&q);
    return st;
}

static void test_allocation_failures(void)
{
    cf_context *ctx = cft_context();
    cf_sparse *l = grid_laplacian(ctx, 8);
    const int32_t known[3] = {0, 7, 63};
    double ones[64];
    for (int k = 0; k < 64; ++k) ones[k] = 1.0;
    cf_sparse *aeq = from_dense(ctx, 1, 64, ones, 0);
    sweep_data chol = {l, NULL, 3, known}, sad = {l, aeq, 0, NULL};
    CHECK(cft_allocation_sweep(ctx, "min_quad create (Cholesky)", sweep_call, &chol, 1) >= 10);
    CHECK(cft_allocation_sweep(ctx, "min_quad create (saddle)", sweep_call, &sad, 1) >= 10);
    cf_sparse_destroy(&aeq);
    cf_sparse_destroy(&l);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_dirichlet_by_hand);
    CFT_RUN(test_plane_by_hand);
    CFT_RUN(test_grid_harmonic);
    CFT_RUN(test_dense_reference);
    CFT_RUN(test_bad_input);
    CFT_RUN(test_allocation_failures);
    return cft_finish();
}
