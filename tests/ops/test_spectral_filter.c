/* cf_spectral_filter (ops/spectral_filter.c): v <- v - (id + sigma' Delta^k)^-1 v.
 * Constants vanish, k = 0 is the factor sigma / (1 + sigma), k = 1 equals a
 * direct solve of (M + sigma' L) u = M v, the response to a near-eigenfunction
 * (z on a sphere) follows sigma' mu^k / (1 + sigma' mu^k), and bad input fails. */
#include "curvflow/generate.h"
#include "curvflow/ops.h"
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

static void test_constants_and_k0(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 2.0, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *v = malloc((size_t)nv * sizeof(double));
    for (int k = 1; k <= 3; ++k) {
        cf_spectral_filter *f = NULL;
        CHECK_OK(ctx, cf_spectral_filter_create(ctx, mesh, NULL, 0.5, k, &f));
        for (int32_t i = 0; i < nv; ++i) v[i] = 3.0;
        CHECK_OK(ctx, cf_spectral_filter_apply(f, v, NULL));
        double worst = 0.0;
        for (int32_t i = 0; i < nv; ++i) worst = fmax(worst, fabs(v[i]));
        CHECK_LE(worst, 1e-10); /* (M^-1 L)^k's conditioning: ~1e-11 for k = 3 */
        cf_spectral_filter_destroy(&f);
        CHECK(f == NULL);
    }
    cf_spectral_filter *f = NULL;
    CHECK_OK(ctx, cf_spectral_filter_create(ctx, mesh, NULL, 0.25, 0, &f));
    for (int32_t i = 0; i < nv; ++i) v[i] = (double)i;
    CHECK_OK(ctx, cf_spectral_filter_apply(f, v, NULL));
    CHECK_NEAR(v[7], 7.0 * 0.25 / 1.25, 1e-15, 0.0);
    cf_spectral_filter_destroy(&f);
    free(v);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* k = 1 against a direct solve, and the response to z on the unit sphere:
 * mu = z^T L z / z^T M z, factor sigma mu^k / (1 + sigma mu^k) (R = 1). */
static void test_response(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 4, 1.0, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    const double *p = cf_mesh_positions(mesh);
    double *z = malloc((size_t)nv * sizeof(double)), *v = malloc((size_t)nv * sizeof(double));
    double *m = malloc((size_t)nv * sizeof(double)), *lz = malloc((size_t)nv * sizeof(double));
    double *u = malloc((size_t)nv * sizeof(double)), area = 0.0;
    for (int32_t i = 0; i < nv; ++i) z[i] = p[3 * i + 2];
    CHECK_OK(ctx, cf_vertex_areas(ctx, mesh, p, CF_DUAL_AREA_BARYCENTRIC, m));
    CHECK_OK(ctx, cf_total_area(ctx, mesh, p, &area));
    cf_sparse *l = NULL, *mm = NULL, *a = NULL;
    CHECK_OK(ctx, cf_cotan_laplacian(ctx, mesh, p, &l));
    cf_sparse_multiply(l, z, lz);
    double mu = cf_dot(nv, z, lz, NULL) / cf_dot(nv, z, z, m);
    double r2 = area / (4.0 * PI), sigma = 0.3;
    for (int k = 1; k <= 2; ++k) {
        cf_spectral_filter *f = NULL;
        CHECK_OK(ctx, cf_spectral_filter_create(ctx, mesh, NULL, sigma, k, &f));
        memcpy(v, z, (size_t)nv * sizeof(double));
        cf_solver_timings tm = {0.0, 0.0, 0.0};
        CHECK_OK(ctx, cf_spectral_filter_apply(f, v, &tm));
        CHECK(tm.solve_seconds >= 0.0);
        double s = sigma * pow(r2, k) * pow(mu, k), factor = cf_dot(nv, v, z, m) / cf_dot(nv, z, z, m);
        /* z is an eigenfunction of the discrete Delta only to discretisation error */
        CHECK_NEAR(factor, s / (1.0 + s), 2e-3, 0.0);
        if (k == 1) {
            /* u = (M + sigma' L)^-1 M z, v = z - u */
            CHECK_OK(ctx, cf_mass_matrix(ctx, mesh, p, CF_MASS_LUMPED_BARYCENTRIC, &mm));
            CHECK_OK(ctx, cf_sparse_add(ctx, 1.0, mm, sigma * r2, l, &a));
            cf_cholesky *chol = NULL;
            CHECK_OK(ctx, cf_cholesky_create(ctx, a, NULL, &chol));
            CHECK_OK(ctx, cf_cholesky_factorize(chol, a));
            for (int32_t i = 0; i < nv; ++i) lz[i] = m[i] * z[i];
            CHECK_OK(ctx, cf_cholesky_solve(chol, 1, lz, u));
            double worst = 0.0;
            for (int32_t i = 0; i < nv; ++i) worst = fmax(worst, fabs(v[i] - (z[i] - u[i])));
            CHECK_LE(worst, 1e-12);
            cf_cholesky_destroy(&chol);
        }
        cf_spectral_filter_destroy(&f);
    }
    cf_sparse_destroy(&l);
    cf_sparse_destroy(&mm);
    cf_sparse_destroy(&a);
    free(z);
    free(v);
    free(m);
    free(lz);
    free(u);
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
}

static const cf_mesh *sweep_mesh;

static cf_status create_and_free(cf_context *ctx, void *user)
{
    cf_spectral_filter *f = NULL;
    cf_status st = cf_spectral_filter_create(ctx, sweep_mesh, NULL, 0.1, *(int *)user, &f);
    if (st == CF_OK && !f) st = CF_ERR_NUMERICAL;
    cf_spectral_filter_destroy(&f);
    return st;
}

static void test_invalid_and_allocation(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 1, 1.0, &mesh));
    cf_spectral_filter *f = NULL;
    CHECK_STATUS(cf_spectral_filter_create(ctx, mesh, NULL, 0.0, 1, &f), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "need sigma > 0") != NULL);
    CHECK_STATUS(cf_spectral_filter_create(ctx, mesh, NULL, 1.0, 4, &f), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_spectral_filter_create(ctx, mesh, NULL, NAN, 1, &f), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_spectral_filter_create(ctx, NULL, NULL, 1.0, 1, &f), CF_ERR_INVALID_ARG);
    CHECK(f == NULL);
    CHECK_STATUS(cf_spectral_filter_apply(NULL, NULL, NULL), CF_ERR_INVALID_ARG);
    cf_spectral_filter_destroy(NULL);
    sweep_mesh = mesh;
    for (int k = 0; k <= 3; ++k) cft_allocation_sweep(ctx, "spectral_filter", create_and_free, &k, 1);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_constants_and_k0);
    CFT_RUN(test_response);
    CFT_RUN(test_invalid_and_allocation);
    return cft_finish();
}
