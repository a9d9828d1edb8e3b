/* Gradient and divergence: exact on linear functions, div grad = -L,
 * divergence is the negative adjoint of the gradient. */
#include "curvflow/generate.h"
#include "curvflow/ops.h"
#include "test.h"

#include <stdlib.h>

static void test_linear_exact(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    /* a curved surface: the gradient of a linear ambient function is its
     * coefficient vector projected to each face plane */
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 2, 0.3, 2u, &m));
    if (!m) return;
    const double *x = cf_mesh_positions(m);
    int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m);
    double *f = malloc(sizeof(double) * nv), *g = malloc(sizeof(double) * 3 * nf), *n = malloc(sizeof(double) * 3 * nf);
    const double c[3] = {0.7, -1.3, 2.1};
    for (int32_t v = 0; v < nv; ++v) f[v] = 5.0 + c[0] * x[3 * v] + c[1] * x[3 * v + 1] + c[2] * x[3 * v + 2];
    CHECK_OK(ctx, cf_gradient(ctx, m, x, f, g));
    CHECK_OK(ctx, cf_face_normals(ctx, m, x, n));
    for (int32_t i = 0; i < nf; ++i) {
        const double *ni = n + 3 * i;
        double cn = c[0] * ni[0] + c[1] * ni[1] + c[2] * ni[2];
        for (int k = 0; k < 3; ++k) CHECK_NEAR(g[3 * i + k], c[k] - cn * ni[k], 0, 1e-12);
    }
    free(f);
    free(g);
    free(n);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_div_grad(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 14, 6, 0.5, 1.5, &m));
    if (!m) return;
    const double *x = cf_mesh_positions(m);
    int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m);
    double *f = malloc(sizeof(double) * nv), *g = malloc(sizeof(double) * 3 * nf), *d = malloc(sizeof(double) * nv);
    double *lf = malloc(sizeof(double) * nv), *fa = malloc(sizeof(double) * nf), *u = malloc(sizeof(double) * 3 * nf);
    for (int32_t v = 0; v < nv; ++v) f[v] = cos(2 * x[3 * v]) * x[3 * v + 2] + x[3 * v + 1];
    CHECK_OK(ctx, cf_gradient(ctx, m, x, f, g));
    CHECK_OK(ctx, cf_divergence(ctx, m, x, g, d));
    cf_sparse *l = NULL;
    CHECK_OK(ctx, cf_cotan_laplacian(ctx, m, x, &l));
    if (l) {
        cf_sparse_multiply(l, f, lf);
        for (int32_t v = 0; v < nv; ++v) CHECK_NEAR(d[v], -lf[v], 1e-12, 1e-12);
    }
    /* adjoint: sum_f A_f <grad h, U_f> = -<h, div U> for any field U */
    CHECK_OK(ctx, cf_face_areas(ctx, m, x, fa));
    for (int32_t i = 0; i < 3 * nf; ++i) u[i] = sin(1.0 + i);
    CHECK_OK(ctx, cf_divergence(ctx, m, x, u, d));
    double lhs = 0, rhs = 0;
    for (int32_t i = 0; i < nf; ++i)
        lhs += fa[i] * (g[3 * i] * u[3 * i] + g[3 * i + 1] * u[3 * i + 1] + g[3 * i + 2] * u[3 * i + 2]);
    for (int32_t v = 0; v < nv; ++v) rhs -= f[v] * d[v];
    CHECK_NEAR(lhs, rhs, 1e-12, 1e-13);
    CHECK_STATUS(cf_gradient(ctx, m, x, NULL, g), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_divergence(ctx, m, x, NULL, d), CF_ERR_INVALID_ARG);
    cf_sparse_destroy(&l);
    free(f);
    free(g);
    free(d);
    free(lf);
    free(fa);
    free(u);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_linear_exact);
    CFT_RUN(test_div_grad);
    return cft_finish();
}
