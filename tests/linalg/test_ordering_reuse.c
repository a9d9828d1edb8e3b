/* Memory and analysis cost of large block operators (issue 15, docs/memory.md):
 * cf_sparse_kron_dense lifts a vertex graph to dense 4 x 4 blocks with the
 * documented slot formula; the context's ordering cache gives factors that
 * are bit-identical to a fresh analysis, whether the cached graph is the
 * same (Laplacian after its quaternion lift, in either order) or another
 * one (the cache is replaced, results unchanged); CF_ORDERING_AUTO_REFACTORISED
 * tries METIS where AUTO would not. */
#include "test.h"

#include "curvflow/generate.h"
#include "curvflow/linalg.h"
#include "curvflow/ops.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void test_kron_dense(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &mesh));
    cf_sparse *l = NULL, *x = NULL;
    CHECK_OK(ctx, cf_cotan_laplacian(ctx, mesh, cf_mesh_positions(mesh), &l));
    CHECK_OK(ctx, cf_sparse_kron_dense(ctx, l, 4, &x));
    if (l && x) {
        CHECK(x->nrows == 4 * l->nrows && x->ncols == 4 * l->ncols);
        CHECK(cf_sparse_nnz(x) == 16 * cf_sparse_nnz(l));
        CHECK(x->symmetric == l->symmetric && !x->upper_only);
        int bad = 0;
        for (int32_t j = 0; j < l->ncols; ++j)
            for (int32_t p = l->colptr[j]; p < l->colptr[j + 1]; ++p)
                for (int c = 0; c < 4; ++c)
                    for (int r = 0; r < 4; ++r) {
                        int64_t e = x->colptr[4 * j + c] + 4 * (int64_t)(p - l->colptr[j]) + r;
                        bad += x->rowind[e] != 4 * l->rowind[p] + r || x->values[e] != l->values[p];
                        bad += cf_sparse_find(x, 4 * l->rowind[p] + r, 4 * j + c) != e;
                    }
        CHECK(bad == 0);
        /* rows sorted and unique in every column */
        for (int32_t j = 0; j < x->ncols; ++j)
            for (int32_t p = x->colptr[j] + 1; p < x->colptr[j + 1]; ++p) bad += x->rowind[p] <= x->rowind[p - 1];
        CHECK(bad == 0);
    }
    cf_sparse_destroy(&x);
    /* an upper-only matrix has no lower blocks to lift */
    if (l) {
        l->upper_only = 1;
        CHECK_STATUS(cf_sparse_kron_dense(ctx, l, 4, &x), CF_ERR_INVALID_ARG);
        CHECK(strstr(cf_context_message(ctx), "upper triangle") != NULL);
        l->upper_only = 0;
    }
    CHECK_STATUS(cf_sparse_kron_dense(ctx, l, 0, &x), CF_ERR_INVALID_ARG);
    CHECK(x == NULL);
    cf_sparse_destroy(&l);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* L (shifted) and Q = L kron I4 stored as whole quaternion blocks, of
 * mesh (destroyed here). */
static void mesh_matrices(cf_context *ctx, cf_mesh *mesh, cf_sparse **l, cf_sparse **q)
{
    if (mesh) CHECK_OK(ctx, cf_cotan_laplacian(ctx, mesh, cf_mesh_positions(mesh), l));
    for (int32_t j = 0; *l && j < (*l)->ncols; ++j)
        (*l)->values[cf_sparse_find(*l, j, j)] += 1e-2;
    if (*l) CHECK_OK(ctx, cf_sparse_kron_dense(ctx, *l, 4, q));
    for (int32_t j = 0; *q && j < (*q)->ncols; ++j)
        for (int32_t p = (*q)->colptr[j]; p < (*q)->colptr[j + 1]; ++p)
            if ((*q)->rowind[p] % 4 != j % 4) (*q)->values[p] = 0.0; /* a_ij I4: real quaternions */
    cf_mesh_destroy(&mesh);
}

/* The same of the icosphere with `level` subdivisions. */
static void sphere_matrices(cf_context *ctx, int32_t level, cf_sparse **l, cf_sparse **q)
{
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, level, 1.0, &mesh));
    mesh_matrices(ctx, mesh, l, q);
}

/* Factorises a with the options and solves for a fixed right-hand side. */
static double *solve_ordered(cf_context *ctx, const cf_sparse *a, int32_t block, int32_t quat, cf_ordering ordering)
{
    cf_cholesky_options o;
    cf_cholesky_options_default(&o);
    o.block_size = block;
    o.quaternion_blocks = quat;
    o.ordering = ordering;
    cf_cholesky *chol = NULL;
    double *x = calloc((size_t)a->ncols, sizeof *x);
    for (int32_t i = 0; i < a->ncols; ++i) x[i] = sin(0.37 * i) + 0.1 * (i % 7);
    CHECK_OK(ctx, cf_cholesky_create(ctx, a, &o, &chol));
    CHECK_OK(ctx, cf_cholesky_factorize(chol, a));
    CHECK_OK(ctx, cf_cholesky_solve(chol, 1, x, x));
    cf_cholesky_destroy(&chol);
    return x;
}

static double *solve(cf_context *ctx, const cf_sparse *a, int32_t block, int32_t quat)
{
    return solve_ordered(ctx, a, block, quat, CF_ORDERING_AUTO);
}

static void test_cache_bit_identical(void)
{
    /* level 5 (10242 vertices): the AUTO rule picks METIS for the 4 x 4
     * blocks and AMD for the scalar matrix, so both orderings get cached */
    cf_context *fresh = cft_context(), *shared = cft_context();
    cf_sparse *l = NULL, *q = NULL, *l2 = NULL, *q2 = NULL;
    sphere_matrices(fresh, 5, &l, &q);
    sphere_matrices(shared, 3, &l2, &q2); /* another graph, analysed in between */
    if (!l || !q || !l2 || !q2) return;
    size_t nl = (size_t)l->ncols * sizeof(double), nq = (size_t)q->ncols * sizeof(double);
    /* reference: each matrix in a context of its own */
    double *l_ref = solve(fresh, l, 1, 0);
    cf_context *fresh2 = cft_context();
    double *q_ref = solve(fresh2, q, 4, 1);
    double *q_ref_real = solve(fresh2, q, 4, 0);
    /* one context: Q first (computes AMD and METIS), then L (reuses them),
     * another graph (replaces the cache), then both again in the other order */
    double *q1 = solve(shared, q, 4, 1), *l1 = solve(shared, l, 1, 0);
    double *q1_real = solve(shared, q, 4, 0);
    double *o1 = solve(shared, q2, 4, 1);
    double *l3 = solve(shared, l, 1, 0), *q3 = solve(shared, q, 4, 1);
    CHECK(memcmp(l1, l_ref, nl) == 0);
    CHECK(memcmp(l3, l_ref, nl) == 0);
    CHECK(memcmp(q1, q_ref, nq) == 0);
    CHECK(memcmp(q3, q_ref, nq) == 0);
    CHECK(memcmp(q1_real, q_ref_real, nq) == 0);
    double *o_ref = solve(fresh, q2, 4, 1);
    CHECK(memcmp(o1, o_ref, (size_t)q2->ncols * sizeof(double)) == 0);
    /* and the solution is right: Q x = b componentwise is L x_c = b_c */
    double *r = calloc((size_t)q->ncols, sizeof *r), err = 0.0;
    cf_sparse_multiply(q, q1, r);
    for (int32_t i = 0; i < q->ncols; ++i) err = fmax(err, fabs(r[i] - (sin(0.37 * i) + 0.1 * (i % 7))));
    CHECK_LE(err, 1e-9);
    free(r);
    free(l_ref); free(q_ref); free(q_ref_real); free(q1); free(l1); free(q1_real); free(o1); free(l3); free(q3);
    free(o_ref);
    cf_sparse_destroy(&l);
    cf_sparse_destroy(&q);
    cf_sparse_destroy(&l2);
    cf_sparse_destroy(&q2);
    CHECK(cf_context_bytes_in_use(fresh) == 0 && cf_context_bytes_in_use(shared) == 0);
    cf_context_destroy(&fresh);
    cf_context_destroy(&fresh2);
    cf_context_destroy(&shared);
}

/* CF_ORDERING_AUTO_REFACTORISED, on the quaternion lift Q of a shifted
 * Laplacian (4 x 4 blocks, as a flow's Dirac matrix): AUTO's rule with
 * METIS tried from 4 fl / lnz >= 200 (4: the block size; fl, lnz:
 * CHOLMOD's counts of the vertex graph under AMD) instead of 500, fewer
 * flops winning; the solution is bit for bit that of the ordering taken. The built-in bumpy
 * sphere (2 562 vertices): 4 fl / lnz = 313, 7.0e6 flops with AMD, 3.95e6
 * with METIS, so METIS (AUTO keeps AMD); the generated double torus (198
 * vertices): 48, AMD (METIS would need 2.60e4 flops against 2.16e4). An
 * ordering outside the enum is refused. */
static void test_auto_refactorised(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *bumpy = NULL, *torus = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 4, 0.25, 1, &bumpy));
    CHECK_OK(ctx, cf_generate_double_torus(ctx, 2, &torus));
    cf_sparse *l[2] = {NULL, NULL}, *a[2] = {NULL, NULL};
    mesh_matrices(ctx, bumpy, &l[0], &a[0]);
    mesh_matrices(ctx, torus, &l[1], &a[1]);
    const cf_ordering taken[2] = {CF_ORDERING_METIS, CF_ORDERING_AMD}, other[2] = {CF_ORDERING_AMD, CF_ORDERING_METIS};
    for (int k = 0; k < 2; ++k) {
        if (!a[k]) continue;
        size_t n = (size_t)a[k]->ncols * sizeof(double);
        double *x = solve_ordered(ctx, a[k], 4, 1, CF_ORDERING_AUTO_REFACTORISED);
        double *same = solve_ordered(ctx, a[k], 4, 1, taken[k]), *not_taken = solve_ordered(ctx, a[k], 4, 1, other[k]);
        double *automatic = solve_ordered(ctx, a[k], 4, 1, CF_ORDERING_AUTO);
        CHECK(memcmp(x, same, n) == 0);
        CHECK(memcmp(x, not_taken, n) != 0);
        /* AUTO's rule keeps AMD on both */
        CHECK(memcmp(automatic, k == 0 ? not_taken : same, n) == 0);
        free(x);
        free(same);
        free(not_taken);
        free(automatic);
    }
    cf_cholesky_options o;
    cf_cholesky_options_default(&o);
    o.ordering = (cf_ordering)(CF_ORDERING_AUTO_REFACTORISED + 1);
    cf_cholesky *chol = NULL;
    if (a[0]) {
        CHECK_STATUS(cf_cholesky_create(ctx, a[0], &o, &chol), CF_ERR_INVALID_ARG);
        CHECK(strstr(cf_context_message(ctx), "unknown ordering") != NULL);
    }
    CHECK(chol == NULL);
    for (int k = 0; k < 2; ++k) {
        cf_sparse_destroy(&l[k]);
        cf_sparse_destroy(&a[k]);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_kron_dense);
    CFT_RUN(test_cache_bit_identical);
    CFT_RUN(test_auto_refactorised);
    return cft_finish();
}
