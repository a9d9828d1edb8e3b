/*
 * cf_min_quad with quaternion_blocks: whole 4 x 4 blocks known (the fixed
 * boundary vertices of a Dirac matrix). On a small Hermitian quaternionic
 * SPD matrix the block elimination agrees with a dense reference (the free
 * block solved by Gaussian elimination on -b_u - A_uk y) and with the same
 * elimination in the real form, after a refactorisation too; the known
 * values come back exactly; solves allocate nothing. That the complex form
 * is really used shows in a block that is not a quaternion's matrix: the
 * real form accepts it, the quaternion form refuses it naming the block.
 * Refusals: a partly known block (named), block size not 4, equalities.
 */
#include "curvflow/linalg.h"
#include "curvflow/quaternion.h"
#include "linalg_test_util.h"
#include "test.h"

#include <stdlib.h>
#include <string.h>

#define NB 9       /* quaternion blocks (vertices) */
#define N (4 * NB) /* real unknowns */

/* Dense column-major real form of sum over edges (i, j) of
 * w |x_i - r_ij x_j|^2 + shift |x|^2 (a quaternionic connection Laplacian
 * plus a shift: SPD, every block a left-multiplication matrix). Edges: a
 * cycle through the NB vertices plus three chords. */
static void dense_connection_laplacian(double scale, double shift, double *a)
{
    static const int32_t chords[3][2] = {{0, 4}, {2, 7}, {3, 8}};
    memset(a, 0, sizeof(double) * N * N);
    for (int32_t e = 0; e < NB + 3; ++e) {
        int32_t i = e < NB ? e : chords[e - NB][0];
        int32_t j = e < NB ? (e + 1) % NB : chords[e - NB][1];
        double w = scale * (1.0 + 0.5 * rng_unit());
        cf_quat q = {rng_unit(), rng_unit(), rng_unit(), rng_unit()};
        double len = sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
        q.w *= 0.8 / len; q.x *= 0.8 / len; q.y *= 0.8 / len; q.z *= 0.8 / len;
        double lq[16];
        cf_quat_left_matrix(q, lq); /* row-major */
        for (int p = 0; p < 4; ++p) {
            a[(size_t)(4 * i + p) * N + 4 * i + p] += w;
            a[(size_t)(4 * j + p) * N + 4 * j + p] += 0.64 * w;
            for (int s = 0; s < 4; ++s) {
                /* (i, j) block -w L(q), (j, i) its transpose */
                a[(size_t)(4 * j + s) * N + 4 * i + p] -= w * lq[4 * p + s];
                a[(size_t)(4 * i + p) * N + 4 * j + s] -= w * lq[4 * p + s];
            }
        }
    }
    for (int32_t k = 0; k < N; ++k) a[(size_t)k * N + k] += shift;
}

/* Sparse copy of the dense matrix with whole 4 x 4 blocks stored wherever
 * the block is nonzero (explicit zeros inside a block kept: the complex
 * form needs whole blocks). */
static cf_sparse *blocks_to_sparse(cf_context *ctx, const double *a)
{
    int32_t *r = malloc(sizeof(int32_t) * N * N), *c = malloc(sizeof(int32_t) * N * N);
    double *v = malloc(sizeof(double) * N * N);
    int64_t k = 0;
    for (int32_t bj = 0; bj < NB; ++bj)
        for (int32_t bi = 0; bi < NB; ++bi) {
            int nonzero = 0;
            for (int p = 0; p < 16; ++p) nonzero |= a[(size_t)(4 * bj + p / 4) * N + 4 * bi + p % 4] != 0.0;
            if (!nonzero) continue;
            for (int p = 0; p < 16; ++p) {
                r[k] = 4 * bi + p % 4;
                c[k] = 4 * bj + p / 4;
                v[k] = a[(size_t)c[k] * N + r[k]];
                ++k;
            }
        }
    cf_sparse *s = NULL;
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, N, N, k, r, c, v, 1, &s, NULL));
    free(r);
    free(c);
    free(v);
    return s;
}

/* x = argmin 1/2 x^T A x + b^T x with x[known] = y, densely: the free block
 * A_uu x_u = -b_u - A_uk y by Gaussian elimination. */
static void dense_reference(const double *a, const double *b, int32_t nk, const int32_t *known, const double *y,
                            double *x)
{
    int32_t is_known[N], free_var[N], nu = 0;
    double yv[N] = {0};
    memset(is_known, 0, sizeof is_known);
    for (int32_t k = 0; k < nk; ++k) {
        is_known[known[k]] = 1;
        yv[known[k]] = y[k];
    }
    for (int32_t v = 0; v < N; ++v)
        if (!is_known[v]) free_var[nu++] = v;
    double *auu = malloc(sizeof(double) * (size_t)nu * nu), rhs[N], xu[N];
    for (int32_t q = 0; q < nu; ++q) {
        int32_t i = free_var[q];
        rhs[q] = -b[i];
        for (int32_t j = 0; j < N; ++j)
            if (is_known[j]) rhs[q] -= a[(size_t)j * N + i] * yv[j];
        for (int32_t p = 0; p < nu; ++p) auu[(size_t)p * nu + q] = a[(size_t)free_var[p] * N + i];
    }
    dense_solve(nu, auu, rhs, xu);
    for (int32_t v = 0; v < N; ++v) x[v] = yv[v];
    for (int32_t q = 0; q < nu; ++q) x[free_var[q]] = xu[q];
    free(auu);
}

static cf_min_quad_options quaternion_options(int quaternion)
{
    cf_min_quad_options o;
    cf_min_quad_options_default(&o);
    o.block_size = 4;
    o.quaternion_blocks = quaternion;
    return o;
}

static double max_rel_diff(const double *x, const double *ref)
{
    double big = 0.0, d = 0.0;
    for (int32_t i = 0; i < N; ++i) {
        big = fmax(big, fabs(ref[i]));
        d = fmax(d, fabs(x[i] - ref[i]));
    }
    return d / big;
}

static void test_matches_dense_reference(void)
{
    cf_context *ctx = cft_context();
    rng_seed(12);
    double *a = malloc(sizeof(double) * N * N);
    dense_connection_laplacian(1.0, 0.05, a);
    cf_sparse *s = blocks_to_sparse(ctx, a);
    /* vertices 1, 5 and 6 fixed (known in a shuffled order, as a caller may
     * list them), with quaternion values; a linear term on every variable */
    const int32_t known[12] = {20, 21, 22, 23, 4, 5, 6, 7, 24, 25, 26, 27};
    double y[12], b[N], ref[N], x[N], xr[N];
    for (int k = 0; k < 12; ++k) y[k] = rng_unit();
    for (int i = 0; i < N; ++i) b[i] = rng_unit();
    dense_reference(a, b, 12, known, y, ref);

    cf_min_quad_options oq = quaternion_options(1), orl = quaternion_options(0);
    cf_min_quad *q = NULL, *qr = NULL;
    CHECK_OK(ctx, cf_min_quad_create(ctx, s, 12, known, NULL, &oq, &q));
    CHECK_OK(ctx, cf_min_quad_create(ctx, s, 12, known, NULL, &orl, &qr));
    CHECK(cf_min_quad_free_count(q) == N - 12);
    int64_t before = cf_context_allocation_count(ctx);
    CHECK_OK(ctx, cf_min_quad_solve(q, 1, b, y, NULL, x));
    CHECK(cf_context_allocation_count(ctx) == before); /* the complex buffer was reserved at create */
    CHECK_OK(ctx, cf_min_quad_solve(qr, 1, b, y, NULL, xr));
    double e = max_rel_diff(x, ref), er = max_rel_diff(x, xr);
    fprintf(stderr, "  quaternion form vs dense %.3g, vs real form %.3g\n", e, er);
    /* condition number of the free block ~ 1e2: rounding leaves ~1e-15 */
    CHECK_LE(e, 1e-12);
    CHECK_LE(er, 1e-12);
    for (int k = 0; k < 12; ++k) CHECK(x[known[k]] == y[k]);
    /* the free variables satisfy the optimality condition (A x + b)_u = 0 */
    double worst = 0.0;
    for (int32_t i = 0; i < N; ++i) {
        int kn = 0;
        for (int k = 0; k < 12; ++k) kn |= known[k] == i;
        if (kn) continue;
        double g = b[i];
        for (int32_t j = 0; j < N; ++j) g += a[(size_t)j * N + i] * x[j];
        worst = fmax(worst, fabs(g));
    }
    CHECK_LE(worst, 1e-12);

    /* new values of the same pattern: refactorise, no new analysis */
    double *a2 = malloc(sizeof(double) * N * N);
    dense_connection_laplacian(2.5, 0.3, a2);
    cf_sparse *s2 = blocks_to_sparse(ctx, a2);
    CHECK(cf_sparse_nnz(s2) == cf_sparse_nnz(s));
    CHECK_OK(ctx, cf_min_quad_factorize(q, s2, NULL));
    CHECK_OK(ctx, cf_min_quad_solve(q, 1, b, y, NULL, x));
    dense_reference(a2, b, 12, known, y, ref);
    CHECK_LE(max_rel_diff(x, ref), 1e-12);

    /* a block that is not a quaternion's matrix: the real form solves it,
     * the quaternion form names the block (proof that it factorises the
     * complex form). Entry (1, 2) of the diagonal block of vertex 0 and its
     * mirror: still symmetric. */
    int64_t p12 = cf_sparse_find(s2, 1, 2), p21 = cf_sparse_find(s2, 2, 1);
    CHECK(p12 >= 0 && p21 >= 0);
    s2->values[p12] += 0.01;
    s2->values[p21] += 0.01;
    CHECK_OK(ctx, cf_min_quad_factorize(qr, s2, NULL));
    CHECK_STATUS(cf_min_quad_factorize(q, s2, NULL), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "quaternion") != NULL);
    CHECK_STATUS(cf_min_quad_solve(q, 1, b, y, NULL, x), CF_ERR_INVALID_ARG); /* refused after a failure */

    cf_min_quad_destroy(&q);
    cf_min_quad_destroy(&qr);
    cf_sparse_destroy(&s2);
    cf_sparse_destroy(&s);
    free(a2);
    free(a);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_refusals(void)
{
    cf_context *ctx = cft_context();
    rng_seed(3);
    double *a = malloc(sizeof(double) * N * N);
    dense_connection_laplacian(1.0, 0.05, a);
    cf_sparse *s = blocks_to_sparse(ctx, a);
    cf_min_quad *q = NULL;
    cf_min_quad_options o = quaternion_options(1);
    /* three components of vertex 2 known, the fourth free */
    const int32_t partial[3] = {8, 9, 10};
    CHECK_STATUS(cf_min_quad_create(ctx, s, 3, partial, NULL, &o, &q), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "block 2 (variables 8..11) is partly known (3 of 4 components)") != NULL);
    CHECK(q == NULL);
    o.block_size = 1;
    CHECK_STATUS(cf_min_quad_create(ctx, s, 0, NULL, NULL, &o, &q), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "quaternion blocks need block size 4, not 1") != NULL);
    o.block_size = 4;
    double ones[N];
    for (int i = 0; i < N; ++i) ones[i] = 1.0;
    cf_sparse *aeq = NULL;
    int32_t rows[N], cols[N];
    for (int i = 0; i < N; ++i) {
        rows[i] = 0;
        cols[i] = i;
    }
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, 1, N, N, rows, cols, ones, 0, &aeq, NULL));
    CHECK_STATUS(cf_min_quad_create(ctx, s, 0, NULL, aeq, &o, &q), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "no equality constraints (1 given)") != NULL);
    /* whole blocks, everything known: nothing to factorise, x = y */
    int32_t all[N];
    double y[N], x[N];
    for (int i = 0; i < N; ++i) {
        all[i] = i;
        y[i] = 0.5 * i;
    }
    CHECK_OK(ctx, cf_min_quad_create(ctx, s, N, all, NULL, &o, &q));
    CHECK_OK(ctx, cf_min_quad_solve(q, 1, NULL, y, NULL, x));
    CHECK(memcmp(x, y, sizeof x) == 0);
    cf_min_quad_destroy(&q);
    cf_sparse_destroy(&aeq);
    cf_sparse_destroy(&s);
    free(a);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

typedef struct sweep_data {
    const cf_sparse *a;
} sweep_data;

static cf_status sweep_call(cf_context *ctx, void *user)
{
    const sweep_data *d = user;
    cf_min_quad_options o = quaternion_options(1);
    const int32_t known[8] = {0, 1, 2, 3, 12, 13, 14, 15};
    cf_min_quad *q = NULL;
    cf_status st = cf_min_quad_create(ctx, d->a, 8, known, NULL, &o, &q);
    if (st == CF_OK) {
        double x[N];
        st = cf_min_quad_solve(q, 1, NULL, NULL, NULL, x);
    }
    cf_min_quad_destroy(&q);
    return st;
}

static void test_allocation_failures(void)
{
    cf_context *ctx = cft_context();
    rng_seed(5);
    double *a = malloc(sizeof(double) * N * N);
    dense_connection_laplacian(1.0, 0.05, a);
    cf_sparse *s = blocks_to_sparse(ctx, a);
    sweep_data d = {s};
    CHECK(cft_allocation_sweep(ctx, "min_quad create (quaternion blocks)", sweep_call, &d, 1) >= 10);
    cf_sparse_destroy(&s);
    free(a);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_matches_dense_reference);
    CFT_RUN(test_refusals);
    CFT_RUN(test_allocation_failures);
    return cft_finish();
}
