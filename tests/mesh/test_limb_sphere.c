/*
 * cf_generate_limb_sphere (src/mesh/generate.c), the demo's shape: counts
 * and texture coordinates, the radius formula at the limb tips and between
 * limbs, the curvature it carries (W/4pi), determinism, bad arguments, and
 * that the refactored bumpy sphere it shares its uv code with still carries
 * a seam-free per-corner uv.
 */
#include "curvflow/generate.h"
#include "curvflow/ops.h"
#include "test.h"

#include <math.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

/* Largest |x| over vertices lying within `cos_tol` of direction d (unit). */
static double radius_towards(const cf_mesh *m, const double d[3])
{
    const double *x = cf_mesh_positions(m);
    double best = -1.0, r = 0.0;
    for (int32_t v = 0; v < cf_mesh_vertex_count(m); ++v) {
        double n = sqrt(x[3 * v] * x[3 * v] + x[3 * v + 1] * x[3 * v + 1] + x[3 * v + 2] * x[3 * v + 2]);
        double c = (x[3 * v] * d[0] + x[3 * v + 1] * d[1] + x[3 * v + 2] * d[2]) / n;
        if (c > best) best = c, r = n;
    }
    return r;
}

static void test_demo_shape(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_limb_sphere(ctx, 5, 8, 1.4, 0.22, &m));
    if (!m) {
        cf_context_destroy(&ctx);
        return;
    }
    CHECK(cf_mesh_vertex_count(m) == 10242 && cf_mesh_face_count(m) == 20480);
    CHECK(cf_mesh_genus(m) == 0 && cf_mesh_boundary_loop_count(m) == 0);
    CHECK(cf_mesh_uv_count(m) > cf_mesh_vertex_count(m)); /* seam and pole copies */
    CHECK(cf_mesh_uv_triangles(m) != NULL);
    /* real curvature to remove (docs and the demo quote 5.78) */
    double w = 0.0;
    CHECK_OK(ctx, cf_willmore_energy(ctx, m, cf_mesh_positions(m), &w));
    CHECK_NEAR(w / (4.0 * PI), 5.783, 0.0, 0.001);
    /* a limb tip (cube corner) reaches 1 + length, plus the other limbs'
     * tails: exp(-(1 - 1/3) / 0.22^2) ~ 1e-6 for the three nearest corners;
     * the vertex nearest the corner is within half an edge of it */
    const double s = 1.0 / sqrt(3.0);
    const double tip[3] = {s, s, s}, face_centre[3] = {0.0, 0.0, 1.0};
    CHECK_NEAR(radius_towards(m, tip), 2.4, 0.0, 0.02);
    /* between limbs (a cube face centre, 54.7 degrees from four corners)
     * the radius is 1 + 4 * 1.4 * exp(-(1 - 1/sqrt(3)) / 0.22^2) = 1.0001 */
    CHECK_NEAR(radius_towards(m, face_centre), 1.0 + 5.6 * exp(-(1.0 - s) / (0.22 * 0.22)), 0.0, 1e-9);
    cf_mesh_destroy(&m);
    cf_context_destroy(&ctx);
}

static void test_limb_count_and_determinism(void)
{
    cf_context *ctx = cft_context();
    const double s = 1.0 / sqrt(3.0);
    const double first[3] = {s, s, s}, fifth[3] = {-s, -s, -s};
    double w_prev = 0.0;
    for (int32_t limbs = 1; limbs <= CF_LIMB_SPHERE_MAX_LIMBS; ++limbs) {
        cf_mesh *m = NULL;
        CHECK_OK(ctx, cf_generate_limb_sphere(ctx, 3, limbs, 1.0, 0.3, &m));
        if (!m) continue;
        CHECK(radius_towards(m, first) > 1.9);
        /* the fifth limb (opposite the first) appears only from 5 limbs on */
        CHECK(limbs >= 5 ? radius_towards(m, fifth) > 1.9 : radius_towards(m, fifth) < 1.01);
        double w = 0.0;
        CHECK_OK(ctx, cf_willmore_energy(ctx, m, cf_mesh_positions(m), &w));
        CHECK(w > w_prev); /* every limb adds bending */
        w_prev = w;
        cf_mesh_destroy(&m);
    }
    /* length 0 is the icosphere itself */
    cf_mesh *a = NULL, *b = NULL;
    CHECK_OK(ctx, cf_generate_limb_sphere(ctx, 2, 4, 0.0, 0.3, &a));
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &b));
    if (a && b)
        CHECK(memcmp(cf_mesh_positions(a), cf_mesh_positions(b), 3 * sizeof(double) * (size_t)cf_mesh_vertex_count(a)) ==
              0);
    cf_mesh_destroy(&a);
    cf_mesh_destroy(&b);
    /* same arguments, same bits */
    CHECK_OK(ctx, cf_generate_limb_sphere(ctx, 3, 6, 1.2, 0.25, &a));
    CHECK_OK(ctx, cf_generate_limb_sphere(ctx, 3, 6, 1.2, 0.25, &b));
    if (a && b)
        CHECK(memcmp(cf_mesh_positions(a), cf_mesh_positions(b), 3 * sizeof(double) * (size_t)cf_mesh_vertex_count(a)) ==
              0);
    cf_mesh_destroy(&a);
    cf_mesh_destroy(&b);
    cf_context_destroy(&ctx);
}

/* uv per corner without a jump: on every face the u values of the corners
 * differ by less than half a turn (the seam faces use the shifted copy). */
static void check_uv_continuous(const cf_mesh *m)
{
    const double *uv = cf_mesh_uv(m);
    const int32_t *ut = cf_mesh_uv_triangles(m);
    CHECK(uv != NULL && ut != NULL);
    if (!uv || !ut) return;
    double worst = 0.0;
    for (int32_t f = 0; f < cf_mesh_face_count(m); ++f)
        for (int k = 0; k < 3; ++k) {
            double du = fabs(uv[2 * ut[3 * f + k]] - uv[2 * ut[3 * f + (k + 1) % 3]]);
            if (du > worst) worst = du;
        }
    CHECK_LE(worst, 0.25);
}

static void test_uv(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_limb_sphere(ctx, 3, 8, 1.4, 0.22, &m));
    if (m) check_uv_continuous(m);
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.25, 1u, &m));
    if (m) check_uv_continuous(m);
    cf_mesh_destroy(&m);
    cf_context_destroy(&ctx);
}

static void test_bad_arguments(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_STATUS(cf_generate_limb_sphere(ctx, 3, 0, 1.0, 0.3, &m), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "0 limbs outside [1, 8]") != NULL);
    CHECK_STATUS(cf_generate_limb_sphere(ctx, 3, 9, 1.0, 0.3, &m), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_generate_limb_sphere(ctx, 3, 4, -0.1, 0.3, &m), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "limb length -0.1 outside [0, 10]") != NULL);
    CHECK_STATUS(cf_generate_limb_sphere(ctx, 3, 4, NAN, 0.3, &m), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_generate_limb_sphere(ctx, 3, 4, 1.0, 0.01, &m), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "limb width 0.01 outside [0.05, 2]") != NULL);
    CHECK_STATUS(cf_generate_limb_sphere(ctx, 3, 4, 1.0, INFINITY, &m), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_generate_limb_sphere(ctx, 10, 4, 1.0, 0.3, &m), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_generate_limb_sphere(ctx, 3, 4, 1.0, 0.3, NULL), CF_ERR_INVALID_ARG);
    CHECK(m == NULL);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static cf_status generate_call(cf_context *ctx, void *user)
{
    (void)user;
    cf_mesh *m = NULL;
    cf_status st = cf_generate_limb_sphere(ctx, 2, 8, 1.4, 0.22, &m);
    if (st == CF_OK && !m) st = CF_ERR_NUMERICAL;
    cf_mesh_destroy(&m);
    return st;
}

static void test_allocation_failures(void)
{
    cf_context *ctx = cft_context();
    CHECK(cft_allocation_sweep(ctx, "cf_generate_limb_sphere", generate_call, NULL, 0) > 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_demo_shape);
    CFT_RUN(test_limb_count_and_determinism);
    CFT_RUN(test_uv);
    CFT_RUN(test_bad_arguments);
    CFT_RUN(test_allocation_failures);
    return cft_finish();
}
