/* Umeyama similarity alignment and point-to-surface distance (BVH against
 * brute force), sphere fit and the shape summary. */
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/metrics.h"
#include "curvflow/ops.h"
#include "test.h"

#include <stdlib.h>

#define PI 3.14159265358979323846

static uint64_t rng_state = 0x6a09e667f3bcc909ull;
static double urand(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) / 9007199254740992.0 * 2.0 - 1.0;
}

static void random_rotation(double r[9])
{
    double a[9];
    for (int i = 0; i < 9; ++i) a[i] = urand();
    cf_rotation_from_covariance(a, r);
}

static void test_recovers_similarity(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.3, 21u, &m));
    if (!m) return;
    int32_t nv = cf_mesh_vertex_count(m);
    const double *x = cf_mesh_positions(m);
    double *y = malloc(sizeof(double) * 3 * nv), *z = malloc(sizeof(double) * 3 * nv);
    for (int trial = 0; trial < 10; ++trial) {
        double r[9], t[3] = {urand() * 5, urand() * 5, urand() * 5}, s = 0.2 + 3 * fabs(urand());
        random_rotation(r);
        cf_similarity_apply(nv, r, s, t, x, y);
        double r2[9], s2, t2[3], rms;
        CHECK_OK(ctx, cf_similarity_align(ctx, nv, x, y, NULL, 1, r2, &s2, t2, &rms));
        for (int i = 0; i < 9; ++i) CHECK_NEAR(r2[i], r[i], 0, 1e-12);
        for (int i = 0; i < 3; ++i) CHECK_NEAR(t2[i], t[i], 0, 1e-11);
        CHECK_NEAR(s2, s, 1e-12, 0);
        CHECK_LE(rms, 1e-12 * s);
        /* the aligned copy lies on the target surface: distance 0 */
        cf_similarity_apply(nv, r2, s2, t2, x, z);
        double dmax;
        CHECK_OK(ctx, cf_point_to_surface_distance(ctx, nv, z, m, y, NULL, &dmax, NULL, NULL));
        CHECK_LE(dmax, 1e-11 * s);
        /* the same through the convenience call */
        double dmax2, drms2, sc2;
        CHECK_OK(ctx, cf_aligned_surface_distance(ctx, m, x, y, 1, &dmax2, &drms2, &sc2));
        CHECK_LE(dmax2, 1e-11 * s);
        CHECK_NEAR(sc2, s, 1e-12, 0);
        /* rigid variant on a rigid motion: scale stays 1 */
        cf_similarity_apply(nv, r, 1.0, t, x, y);
        CHECK_OK(ctx, cf_similarity_align(ctx, nv, x, y, NULL, 0, r2, &s2, t2, &rms));
        CHECK(s2 == 1.0);
        CHECK_LE(rms, 1e-12);
    }
    /* a mirror image is not a similarity: the best rotation leaves a residual */
    for (int32_t v = 0; v < nv; ++v) {
        y[3 * v] = -x[3 * v];
        y[3 * v + 1] = x[3 * v + 1];
        y[3 * v + 2] = x[3 * v + 2];
    }
    double r2[9], s2, t2[3], rms;
    CHECK_OK(ctx, cf_similarity_align(ctx, nv, x, y, NULL, 1, r2, &s2, t2, &rms));
    double det = r2[0] * (r2[4] * r2[8] - r2[5] * r2[7]) - r2[1] * (r2[3] * r2[8] - r2[5] * r2[6]) +
                 r2[2] * (r2[3] * r2[7] - r2[4] * r2[6]);
    CHECK_NEAR(det, 1.0, 0, 1e-12);
    CHECK(rms > 0.1);
    free(y);
    free(z);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static double brute_distance(const cf_mesh *m, const double *x, const double p[3])
{
    /* dense sampling is not exact; instead use the fact that the distance
     * to a triangle is min over a fine barycentric grid plus edges: here a
     * 60 x 60 grid per face bounds the true distance from above by h */
    double best = INFINITY;
    const int32_t *t = cf_mesh_triangles(m);
    for (int32_t f = 0; f < cf_mesh_face_count(m); ++f) {
        const double *a = x + 3 * t[3 * f], *b = x + 3 * t[3 * f + 1], *c = x + 3 * t[3 * f + 2];
        for (int i = 0; i <= 60; ++i)
            for (int j = 0; i + j <= 60; ++j) {
                double u = i / 60.0, v = j / 60.0, q[3], d2 = 0;
                for (int k = 0; k < 3; ++k) {
                    q[k] = a[k] + u * (b[k] - a[k]) + v * (c[k] - a[k]);
                    d2 += (q[k] - p[k]) * (q[k] - p[k]);
                }
                best = fmin(best, d2);
            }
    }
    return sqrt(best);
}

static void test_distance(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 1, 1.0, &m));
    if (!m) return;
    const double *x = cf_mesh_positions(m);
    /* points on rays from the centre: outside the inscribed polyhedron the
     * distance is at least |p| - 1 and at most |p| - (inradius) */
    enum { N = 40 };
    double p[3 * N], d[N];
    for (int i = 0; i < 3 * N; ++i) p[i] = 1.6 * urand();
    double dmax, drms;
    int32_t arg;
    CHECK_OK(ctx, cf_point_to_surface_distance(ctx, N, p, m, x, d, &dmax, &drms, &arg));
    double worst = 0;
    for (int i = 0; i < N; ++i) {
        double bd = brute_distance(m, x, p + 3 * i);
        /* the sampled distance is >= exact and within the grid spacing */
        CHECK_LE(d[i], bd + 1e-12);
        CHECK_LE(bd - d[i], 0.02);
        worst = fmax(worst, d[i]);
    }
    CHECK(dmax == worst && d[arg] == dmax);
    /* exact values: a vertex is at distance 0, a face centroid pushed out
     * along the face normal by 0.25 is at distance 0.25 */
    double q[6], dq[2], nn[3 * 80];
    const int32_t *t = cf_mesh_triangles(m);
    CHECK(cf_mesh_face_count(m) == 80);
    CHECK_OK(ctx, cf_face_normals(ctx, m, x, nn));
    for (int k = 0; k < 3; ++k) {
        q[k] = x[3 * 7 + k];
        q[3 + k] = (x[3 * t[0] + k] + x[3 * t[1] + k] + x[3 * t[2] + k]) / 3 + 0.25 * nn[k];
    }
    CHECK_OK(ctx, cf_point_to_surface_distance(ctx, 2, q, m, x, dq, NULL, NULL, NULL));
    CHECK_NEAR(dq[0], 0.0, 0, 1e-15);
    CHECK_NEAR(dq[1], 0.25, 1e-13, 0);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_sphere_fit_and_summary(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 4, 2.0, &m));
    if (!m) return;
    int32_t nv = cf_mesh_vertex_count(m);
    double *y = malloc(sizeof(double) * 3 * nv);
    const double c[3] = {10.0, -3.0, 0.5};
    for (int32_t v = 0; v < 3 * nv; ++v) y[v] = cf_mesh_positions(m)[v] + c[v % 3];
    cf_shape_summary s;
    CHECK_OK(ctx, cf_shape_summary_compute(ctx, m, y, &s));
    for (int k = 0; k < 3; ++k) CHECK_NEAR(s.sphere_center[k], c[k], 0, 1e-12);
    CHECK_NEAR(s.sphere_radius, 2.0, 1e-13, 0);
    CHECK_LE(s.sphere_max_deviation, 1e-13);
    CHECK_NEAR(s.total_angle_defect, s.gauss_bonnet_target, 0, 1e-10);
    CHECK_NEAR(s.gauss_bonnet_target, 4 * PI, 1e-15, 0);
    CHECK_NEAR(s.willmore_over_4pi, 1.0, 0, 2e-3);
    CHECK_NEAR(s.area, 16 * PI, 2e-3, 0);
    CHECK_NEAR(s.volume, 32.0 / 3.0 * PI, 3e-3, 0);
    /* an ellipsoid (1, 1, 1.2) deviates by 20% at the poles: max dev is
     * between 0.05 and 0.2 relative to the fitted radius */
    for (int32_t v = 0; v < nv; ++v) y[3 * v + 2] = 1.2 * cf_mesh_positions(m)[3 * v + 2];
    CHECK_OK(ctx, cf_shape_summary_compute(ctx, m, y, &s));
    CHECK(s.sphere_max_deviation > 0.05 && s.sphere_max_deviation < 0.2);
    CHECK(s.sphere_rms_deviation < s.sphere_max_deviation);
    CHECK(s.willmore_over_4pi > 1.0);
    /* coplanar points cannot define a sphere */
    const double flat[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
    double cc[3], rr;
    CHECK_STATUS(cf_fit_sphere(ctx, 4, flat, cc, &rr, NULL, NULL), CF_ERR_NUMERICAL);
    free(y);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_recovers_similarity);
    CFT_RUN(test_distance);
    CFT_RUN(test_sphere_fit_and_summary);
    return cft_finish();
}
