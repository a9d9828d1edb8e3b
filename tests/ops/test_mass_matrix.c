/* Mass matrices and dual areas: every kind sums to the total area; the
 * Galerkin matrix integrates products of hat functions exactly. */
#include "curvflow/generate.h"
#include "curvflow/ops.h"
#include "test.h"

#include <stdlib.h>

static double sum_all(const cf_sparse *m)
{
    double s = 0;
    for (int64_t k = 0; k < cf_sparse_nnz(m); ++k) s += m->values[k];
    return s;
}

static void check_mesh(cf_context *ctx, const cf_mesh *mesh)
{
    const double *x = cf_mesh_positions(mesh);
    int32_t nv = cf_mesh_vertex_count(mesh);
    double area;
    CHECK_OK(ctx, cf_total_area(ctx, mesh, x, &area));
    double *a = malloc(sizeof(double) * nv);
    for (int kind = 0; kind <= 1; ++kind) {
        CHECK_OK(ctx, cf_vertex_areas(ctx, mesh, x, (cf_dual_area_kind)kind, a));
        double s = 0;
        for (int32_t v = 0; v < nv; ++v) {
            s += a[v];
            CHECK(a[v] > 0);
        }
        CHECK_NEAR(s, area, 1e-13, 0);
    }
    for (int kind = 0; kind <= 2; ++kind) {
        cf_sparse *m = NULL;
        CHECK_OK(ctx, cf_mass_matrix(ctx, mesh, x, (cf_mass_kind)kind, &m));
        if (!m) continue;
        CHECK_NEAR(sum_all(m), area, 1e-13, 0); /* 1^T M 1 = A */
        if (kind != CF_MASS_GALERKIN) CHECK(cf_sparse_nnz(m) == nv);
        else {
            /* integral of x^2 over the mesh is exact for the P1 interpolant
             * of x: x^T M x = sum_f A_f/6 (a^2 + b^2 + c^2 + ab + bc + ca) */
            const int32_t *t = cf_mesh_triangles(mesh);
            double *f = malloc(sizeof(double) * nv), *mf = malloc(sizeof(double) * nv);
            for (int32_t v = 0; v < nv; ++v) f[v] = x[3 * v] + 0.5 * x[3 * v + 2];
            cf_sparse_multiply(m, f, mf);
            double q = 0, exact = 0;
            for (int32_t v = 0; v < nv; ++v) q += f[v] * mf[v];
            double *fa = malloc(sizeof(double) * cf_mesh_face_count(mesh));
            CHECK_OK(ctx, cf_face_areas(ctx, mesh, x, fa));
            for (int32_t i = 0; i < cf_mesh_face_count(mesh); ++i) {
                double p = f[t[3 * i]], r = f[t[3 * i + 1]], u = f[t[3 * i + 2]];
                exact += fa[i] / 6.0 * (p * p + r * r + u * u + p * r + r * u + u * p);
            }
            CHECK_NEAR(q, exact, 1e-12, 0);
            free(f);
            free(mf);
            free(fa);
        }
        cf_sparse_destroy(&m);
    }
    free(a);
}

static void test_sums(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.3, 5u, &m));
    if (m) check_mesh(ctx, m);
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 17, 9, 0.4, 2.0, &m));
    if (m) check_mesh(ctx, m);
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.3, 24, 8, &m));
    if (m) check_mesh(ctx, m);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Obtuse triangle: Meyer's rule gives A/2 to the obtuse corner and A/4 to
 * the others; an acute one gets its exact Voronoi regions. */
static void test_mixed_voronoi_single_triangles(void)
{
    cf_context *ctx = cft_context();
    const double obtuse[9] = {0, 0, 0, 4, 0, 0, 2, 0.5, 0};
    const double equilateral[9] = {0, 0, 0, 1, 0, 0, 0.5, 0.8660254037844386, 0};
    const int32_t tri[3] = {0, 1, 2};
    cf_mesh_desc d = {3, obtuse, 1, tri, 0, NULL, NULL};
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_mesh_create(ctx, &d, &m));
    if (!m) return;
    double a[3];
    CHECK_OK(ctx, cf_vertex_areas(ctx, m, obtuse, CF_DUAL_AREA_MIXED_VORONOI, a));
    CHECK_NEAR(a[0], 0.25, 1e-15, 0);
    CHECK_NEAR(a[1], 0.25, 1e-15, 0);
    CHECK_NEAR(a[2], 0.5, 1e-15, 0);
    CHECK_OK(ctx, cf_vertex_areas(ctx, m, equilateral, CF_DUAL_AREA_MIXED_VORONOI, a));
    for (int k = 0; k < 3; ++k) CHECK_NEAR(a[k], sqrt(3.0) / 12.0, 1e-15, 0);
    CHECK_STATUS(cf_vertex_areas(ctx, m, obtuse, (cf_dual_area_kind)7, a), CF_ERR_INVALID_ARG);
    cf_sparse *mm = NULL;
    CHECK_STATUS(cf_mass_matrix(ctx, m, obtuse, (cf_mass_kind)9, &mm), CF_ERR_INVALID_ARG);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_sums);
    CFT_RUN(test_mixed_voronoi_single_triangles);
    return cft_finish();
}
