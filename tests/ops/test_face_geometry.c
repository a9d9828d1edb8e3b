/* Corner angles/cotangents, face areas/normals, vertex normals. */
#include "curvflow/generate.h"
#include "curvflow/ops.h"
#include "test.h"

#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

static void test_sphere_geometry(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 3, 2.0, &m));
    if (!m) return;
    const double *x = cf_mesh_positions(m);
    int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m);
    const int32_t *t = cf_mesh_triangles(m);
    double *ang = malloc(sizeof(double) * 3 * nf), *cot = malloc(sizeof(double) * 3 * nf);
    double *fn = malloc(sizeof(double) * 3 * nf), *vn = malloc(sizeof(double) * 3 * nv), *fa = malloc(sizeof(double) * nf);
    CHECK_OK(ctx, cf_corner_angles(ctx, m, x, ang));
    CHECK_OK(ctx, cf_corner_cotangents(ctx, m, x, cot));
    CHECK_OK(ctx, cf_face_normals(ctx, m, x, fn));
    CHECK_OK(ctx, cf_vertex_normals(ctx, m, x, vn));
    CHECK_OK(ctx, cf_face_areas(ctx, m, x, fa));
    double area = 0, total;
    for (int32_t i = 0; i < nf; ++i) {
        CHECK_NEAR(ang[3 * i] + ang[3 * i + 1] + ang[3 * i + 2], PI, 0, 1e-14);
        for (int k = 0; k < 3; ++k) CHECK_NEAR(cot[3 * i + k], 1.0 / tan(ang[3 * i + k]), 1e-12, 1e-14);
        /* outward: the normal points away from the centre */
        double c[3] = {0, 0, 0};
        for (int k = 0; k < 3; ++k)
            for (int q = 0; q < 3; ++q) c[q] += x[3 * t[3 * i + k] + q] / 3;
        CHECK(fn[3 * i] * c[0] + fn[3 * i + 1] * c[1] + fn[3 * i + 2] * c[2] > 0);
        CHECK_NEAR(fn[3 * i] * fn[3 * i] + fn[3 * i + 1] * fn[3 * i + 1] + fn[3 * i + 2] * fn[3 * i + 2], 1.0, 1e-15, 0);
        area += fa[i];
    }
    CHECK_OK(ctx, cf_total_area(ctx, m, x, &total));
    CHECK_NEAR(area, total, 1e-14, 0);
    /* vertex normals close to radial (within the angular resolution) */
    for (int32_t v = 0; v < nv; ++v) {
        double d = (vn[3 * v] * x[3 * v] + vn[3 * v + 1] * x[3 * v + 1] + vn[3 * v + 2] * x[3 * v + 2]) / 2.0;
        CHECK(d > 0.9999);
    }
    free(ang);
    free(cot);
    free(fn);
    free(vn);
    free(fa);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_single_triangle(void)
{
    cf_context *ctx = cft_context();
    /* 3-4-5 right triangle in the xy plane, counter-clockwise: normal +z */
    const double x[9] = {0, 0, 0, 4, 0, 0, 0, 3, 0};
    const int32_t tri[3] = {0, 1, 2};
    cf_mesh_desc d = {3, x, 1, tri, 0, NULL, NULL};
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_mesh_create(ctx, &d, &m));
    if (!m) return;
    double a[3], c[3], n[3], area, vn[9];
    CHECK_OK(ctx, cf_corner_angles(ctx, m, x, a));
    CHECK_OK(ctx, cf_corner_cotangents(ctx, m, x, c));
    CHECK_OK(ctx, cf_face_normals(ctx, m, x, n));
    CHECK_OK(ctx, cf_face_areas(ctx, m, x, &area));
    CHECK_OK(ctx, cf_vertex_normals(ctx, m, x, vn));
    CHECK_NEAR(a[0], PI / 2, 0, 1e-15);
    CHECK_NEAR(c[0], 0.0, 0, 1e-15);
    CHECK_NEAR(c[1], 4.0 / 3.0, 1e-15, 0);
    CHECK_NEAR(c[2], 3.0 / 4.0, 1e-15, 0);
    CHECK_NEAR(area, 6.0, 1e-15, 0);
    CHECK(n[0] == 0 && n[1] == 0 && n[2] == 1.0);
    CHECK(vn[2] == 1.0 && vn[5] == 1.0 && vn[8] == 1.0);
    /* non-finite positions are rejected with the vertex named */
    const double bad[9] = {0, 0, 0, 4, 0, 0, 0, INFINITY, 0};
    CHECK_STATUS(cf_face_areas(ctx, m, bad, &area), CF_ERR_NONFINITE);
    CHECK(strstr(cf_context_message(ctx), "vertex 2") != NULL);
    const double flat[9] = {0, 0, 0, 1, 0, 0, 2, 0, 0};
    CHECK_STATUS(cf_face_normals(ctx, m, flat, n), CF_ERR_DEGENERATE_FACE);
    CHECK_STATUS(cf_corner_cotangents(ctx, m, flat, c), CF_ERR_DEGENERATE_FACE);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_sphere_geometry);
    CFT_RUN(test_single_triangle);
    return cft_finish();
}
