/* Mesh quality summary (cf_mesh_quality_compute): angle and area figures
 * against shapes whose angles are known in closed form (a grid of right
 * isosceles triangles, a long box with 5.7 degree corners), W/4pi and
 * volume of a refined sphere, NaN for meshes with boundary, the upper-median
 * convention, bad input, and allocation failures. */
#include "curvflow/generate.h"
#include "curvflow/metrics.h"
#include "curvflow/ops.h"
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

/* Unit square in 4 x 4 cells, each split into two right isosceles
 * triangles: every face has angles 45, 45, 90 degrees and area 1/32. */
static void test_grid(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_grid(ctx, 4, 4, 1.0, 1.0, &m));
    cf_mesh_quality q;
    CHECK_OK(ctx, cf_mesh_quality_compute(ctx, m, NULL, &q));
    CHECK_NEAR(q.min_angle, PI / 4, 1e-14, 0);
    CHECK_NEAR(q.max_angle, PI / 2, 1e-14, 0);
    /* 2/3 of the sorted corners are 45 degrees: the element n/2 is one */
    CHECK_NEAR(q.median_angle, PI / 4, 1e-14, 0);
    CHECK_NEAR(q.median_face_min_angle, PI / 4, 1e-14, 0);
    CHECK(q.fraction_angles_below_10_degrees == 0.0);
    CHECK(q.fraction_faces_min_below_10_degrees == 0.0);
    CHECK_NEAR(q.total_area, 1.0, 1e-14, 0);
    CHECK_NEAR(q.min_face_area, 1.0 / 32, 1e-14, 0);
    CHECK_NEAR(q.max_face_area, 1.0 / 32, 1e-14, 0);
    CHECK(isnan(q.willmore_over_4pi) && isnan(q.volume)); /* one boundary loop */
    cf_mesh_destroy(&m);
    cf_context_destroy(&ctx);
}

/* Box [0,10] x [0,1] x [0,1] with one cell per side: the four long sides
 * are 10 x 1 rectangles (corners atan(1/10) = 5.71, 84.29 and 90 degrees),
 * the two ends unit squares (45, 45, 90). 36 corners, 8 below 10 degrees;
 * 8 of the 12 faces have their smallest angle below 10 degrees. */
static void test_long_box(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_bar(ctx, 1, 1, 1, 10.0, 1.0, 1.0, 0, &m));
    CHECK(cf_mesh_face_count(m) == 12);
    cf_mesh_quality q;
    CHECK_OK(ctx, cf_mesh_quality_compute(ctx, m, NULL, &q));
    CHECK_NEAR(q.min_angle, atan(0.1), 1e-14, 0);
    CHECK_NEAR(q.max_angle, PI / 2, 1e-14, 0);
    CHECK_NEAR(q.fraction_angles_below_10_degrees, 8.0 / 36.0, 0, 0);
    CHECK_NEAR(q.fraction_faces_min_below_10_degrees, 8.0 / 12.0, 0, 0);
    /* sorted face minima: 8 x 5.71, 4 x 45 degrees; element 6 is 5.71 */
    CHECK_NEAR(q.median_face_min_angle, atan(0.1), 1e-14, 0);
    CHECK_NEAR(q.total_area, 4 * 10.0 + 2 * 1.0, 1e-14, 0);
    CHECK_NEAR(q.min_face_area, 0.5, 1e-14, 0);
    CHECK_NEAR(q.max_face_area, 5.0, 1e-14, 0);
    CHECK_NEAR(q.median_face_area, 5.0, 1e-14, 0); /* 4 x 0.5, 8 x 5: element 6 is 5 */
    /* sorted corners: 8 x 5.71, 8 x 45, 8 x 84.29, 12 x 90 degrees; element 18 */
    CHECK_NEAR(q.median_angle, atan(10.0), 1e-14, 0);
    CHECK_NEAR(q.volume, 10.0, 1e-13, 0);
    CHECK(isfinite(q.willmore_over_4pi) && q.willmore_over_4pi > 1.0);
    /* the same figures for explicit positions: scaled by 2 */
    int32_t nv = cf_mesh_vertex_count(m);
    double *x = malloc(sizeof(double) * 3 * nv);
    for (int32_t i = 0; i < 3 * nv; ++i) x[i] = 2.0 * cf_mesh_positions(m)[i];
    cf_mesh_quality q2;
    CHECK_OK(ctx, cf_mesh_quality_compute(ctx, m, x, &q2));
    CHECK_NEAR(q2.total_area, 4.0 * q.total_area, 1e-14, 0);
    CHECK_NEAR(q2.volume, 8.0 * q.volume, 1e-13, 0);
    CHECK_NEAR(q2.min_angle, q.min_angle, 1e-14, 0);
    CHECK_NEAR(q2.willmore_over_4pi, q.willmore_over_4pi, 1e-12, 0); /* scale invariant */
    free(x);
    cf_mesh_destroy(&m);
    cf_context_destroy(&ctx);
}

/* A refined sphere of radius 2: W/4pi -> 1, volume -> 32 pi / 3, and the
 * figures agree with the operators they come from. */
static void test_sphere(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 4, 2.0, &m));
    cf_mesh_quality q;
    CHECK_OK(ctx, cf_mesh_quality_compute(ctx, m, NULL, &q));
    CHECK_NEAR(q.willmore_over_4pi, 1.0, 0, 5e-3);
    CHECK_NEAR(q.volume, 32.0 * PI / 3.0, 5e-3, 0); /* inscribed polyhedron: slightly less */
    CHECK(q.volume < 32.0 * PI / 3.0);
    double area = 0.0, w = 0.0;
    CHECK_OK(ctx, cf_total_area(ctx, m, cf_mesh_positions(m), &area));
    CHECK_OK(ctx, cf_willmore_energy(ctx, m, cf_mesh_positions(m), &w));
    CHECK_NEAR(q.total_area, area, 1e-13, 0);
    CHECK_NEAR(q.willmore_over_4pi, w / (4 * PI), 1e-15, 0);
    CHECK(q.min_angle <= q.median_angle && q.median_angle <= q.max_angle);
    CHECK(q.min_angle > 40 * PI / 180 && q.max_angle < 80 * PI / 180); /* a well-shaped icosphere */
    CHECK(q.min_face_area <= q.median_face_area && q.median_face_area <= q.max_face_area);
    cf_mesh_destroy(&m);
    cf_context_destroy(&ctx);
}

/* Two triangles of areas 0.5 and 2.5: the median of an even count is the
 * upper one (element n / 2), as `curvflow info` and CHECKS.tsv take it. */
static void test_upper_median(void)
{
    cf_context *ctx = cft_context();
    const double x[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 3, 3, 0};
    const int32_t t[] = {0, 1, 2, 1, 3, 2};
    cf_mesh_desc d = {4, x, 2, t, 0, NULL, NULL};
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_mesh_create(ctx, &d, &m));
    cf_mesh_quality q;
    CHECK_OK(ctx, cf_mesh_quality_compute(ctx, m, NULL, &q));
    CHECK_NEAR(q.median_face_area, 2.5, 1e-15, 0);
    CHECK_NEAR(q.min_face_area, 0.5, 1e-15, 0);
    CHECK_NEAR(q.total_area, 3.0, 1e-15, 0);
    CHECK_NEAR(q.median_face_min_angle, PI / 4, 1e-15, 0); /* minima: atan(1/5) (face 1), 45 degrees */
    cf_mesh_destroy(&m);
    cf_context_destroy(&ctx);
}

static void test_bad_input(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 1, 1.0, &m));
    cf_mesh_quality q;
    q.total_area = -7.0;
    CHECK(cf_mesh_quality_compute(ctx, NULL, NULL, &q) == CF_ERR_INVALID_ARG);
    CHECK(cf_mesh_quality_compute(ctx, m, NULL, NULL) == CF_ERR_INVALID_ARG);
    CHECK(cf_mesh_quality_compute(NULL, m, NULL, &q) == CF_ERR_INVALID_ARG);
    int32_t nv = cf_mesh_vertex_count(m);
    double *x = malloc(sizeof(double) * 3 * nv);
    for (int32_t i = 0; i < 3 * nv; ++i) x[i] = cf_mesh_positions(m)[i];
    x[3 * 5 + 1] = NAN;
    CHECK(cf_mesh_quality_compute(ctx, m, x, &q) == CF_ERR_NONFINITE);
    CHECK(strstr(cf_context_message(ctx), "vertex 5") != NULL);
    x[3 * 5 + 1] = 1e60;
    CHECK(cf_mesh_quality_compute(ctx, m, x, &q) == CF_ERR_NONFINITE);
    CHECK(q.total_area == -7.0); /* untouched on failure */
    free(x);
    cf_mesh_destroy(&m);
    cf_context_destroy(&ctx);
}

static const cf_mesh *g_mesh;

static cf_status call_quality(cf_context *ctx, void *user)
{
    (void)user;
    cf_mesh_quality q;
    return cf_mesh_quality_compute(ctx, g_mesh, NULL, &q);
}

static void quiet(void *user, cf_log_level level, const char *line)
{
    (void)user;
    (void)level;
    (void)line;
}

static void test_allocation_failures(void)
{
    cf_context *mesh_ctx = cft_context(), *ctx = NULL;
    cf_mesh *m = NULL;
    CHECK_OK(mesh_ctx, cf_generate_icosphere(mesh_ctx, 2, 1.0, &m));
    CHECK(cf_context_create(&ctx) == CF_OK);
    cf_context_set_log(ctx, quiet, NULL, CF_LOG_DEBUG);
    g_mesh = m;
    CHECK(cft_allocation_sweep(ctx, "mesh_quality", call_quality, NULL, 0) > 0);
    cf_context_destroy(&ctx);
    cf_mesh_destroy(&m);
    cf_context_destroy(&mesh_ctx);
}

int main(void)
{
    CFT_RUN(test_grid);
    CFT_RUN(test_long_box);
    CFT_RUN(test_sphere);
    CFT_RUN(test_upper_median);
    CFT_RUN(test_bad_input);
    CFT_RUN(test_allocation_failures);
    return cft_finish();
}
