/*
 * Bad input to every public operator and metric: NULL context, mesh,
 * positions or output, a NaN position, an unknown kind. Each call must
 * return its documented status (include/curvflow/ops.h, metrics.h) with a
 * message naming the function or the vertex, never crash, and leave no
 * allocation behind.
 */
#include "curvflow/generate.h"
#include "curvflow/metrics.h"
#include "curvflow/ops.h"
#include "curvflow/quaternion.h"
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* One operator with the common signature (ctx, mesh, positions, out). */
typedef cf_status (*vec_op)(cf_context *, const cf_mesh *, const double *, double *);

typedef struct named_op {
    const char *name; /* the function name used in its messages */
    vec_op fn;
} named_op;

static cf_status op_vertex_areas_bary(cf_context *c, const cf_mesh *m, const double *x, double *o)
{
    return cf_vertex_areas(c, m, x, CF_DUAL_AREA_BARYCENTRIC, o);
}
/* A finite input function / face field, large enough for either use. */
static double field[3 * 4096];
static cf_status op_gradient(cf_context *c, const cf_mesh *m, const double *x, double *o)
{
    return cf_gradient(c, m, x, field, o);
}
static cf_status op_divergence(cf_context *c, const cf_mesh *m, const double *x, double *o)
{
    return cf_divergence(c, m, x, field, o);
}
static cf_status op_total_area(cf_context *c, const cf_mesh *m, const double *x, double *o)
{
    return cf_total_area(c, m, x, o);
}
static cf_status op_volume(cf_context *c, const cf_mesh *m, const double *x, double *o)
{
    return cf_enclosed_volume(c, m, x, o);
}
static cf_status op_willmore(cf_context *c, const cf_mesh *m, const double *x, double *o)
{
    return cf_willmore_energy(c, m, x, o);
}

static const named_op ops[] = {
    {"corner_angles", cf_corner_angles},
    {"corner_cotangents", cf_corner_cotangents},
    {"face_areas", cf_face_areas},
    {"face_normals", cf_face_normals},
    {"vertex_normals", cf_vertex_normals},
    {"vertex_areas", op_vertex_areas_bary},
    {"cotan_weights", cf_cotan_weights},
    {"dec_star2", cf_dec_star2},
    {"mean_curvature_normal", cf_mean_curvature_normal},
    {"mean_curvature", cf_mean_curvature},
    {"angle_defect", cf_angle_defect},
    {"willmore_energy", op_willmore},
    {"enclosed_volume", op_volume},
    {"total_area", op_total_area},
    {"gradient", op_gradient},
    {"divergence", op_divergence},
};
#define OP_COUNT (sizeof ops / sizeof ops[0])

static void test_vector_operators(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 1, 1.0, &m));
    if (!m) {
        cf_context_destroy(&ctx);
        return;
    }
    int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m);
    CHECK(3 * (size_t)nf <= sizeof field / sizeof field[0]);
    for (size_t i = 0; i < sizeof field / sizeof field[0]; ++i) field[i] = 0.25 * (double)(i % 7);
    size_t n3 = 3 * (size_t)(nv > nf ? nv : nf);
    double *x = malloc(3 * (size_t)nv * sizeof *x), *out = malloc(n3 * sizeof *out);
    CHECK(x && out);
    if (!x || !out) goto done;
    memcpy(x, cf_mesh_positions(m), 3 * (size_t)nv * sizeof *x);
    x[3 * 7 + 1] = NAN;
    for (size_t i = 0; i < OP_COUNT; ++i) {
        const named_op *op = &ops[i];
        CHECK_STATUS(op->fn(NULL, m, cf_mesh_positions(m), out), CF_ERR_INVALID_ARG);
        CHECK_STATUS(op->fn(ctx, NULL, cf_mesh_positions(m), out), CF_ERR_INVALID_ARG);
        CHECK(strstr(cf_context_message(ctx), op->name) != NULL);
        CHECK_STATUS(op->fn(ctx, m, NULL, out), CF_ERR_INVALID_ARG);
        CHECK_STATUS(op->fn(ctx, m, cf_mesh_positions(m), NULL), CF_ERR_INVALID_ARG);
        CHECK_STATUS(op->fn(ctx, m, x, out), CF_ERR_NONFINITE);
        CHECK(strstr(cf_context_message(ctx), "vertex 7") != NULL);
        /* and the valid call still works after all that */
        CHECK_OK(ctx, op->fn(ctx, m, cf_mesh_positions(m), out));
        CHECK(cf_context_bytes_in_use(ctx) > 0); /* only the mesh */
    }
    /* function arguments of gradient / divergence */
    CHECK_STATUS(cf_gradient(ctx, m, cf_mesh_positions(m), NULL, out), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_divergence(ctx, m, cf_mesh_positions(m), NULL, out), CF_ERR_INVALID_ARG);
    /* unknown kinds */
    CHECK_STATUS(cf_vertex_areas(ctx, m, cf_mesh_positions(m), (cf_dual_area_kind)7, out), CF_ERR_INVALID_ARG);
    cf_sparse *s = NULL;
    CHECK_STATUS(cf_mass_matrix(ctx, m, cf_mesh_positions(m), (cf_mass_kind)9, &s), CF_ERR_INVALID_ARG);
    CHECK(s == NULL);
    /* sparse-valued operators */
    CHECK_STATUS(cf_cotan_laplacian(ctx, m, x, &s), CF_ERR_NONFINITE);
    CHECK(s == NULL);
    CHECK_STATUS(cf_cotan_laplacian(ctx, m, cf_mesh_positions(m), NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_mass_matrix(ctx, NULL, cf_mesh_positions(m), CF_MASS_GALERKIN, &s), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_dec_d0(ctx, NULL, &s), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_dec_d1(ctx, m, NULL), CF_ERR_INVALID_ARG);
    /* harmonic basis, one-forms, subdivision */
    int32_t dim = -1;
    CHECK_STATUS(cf_harmonic_basis(ctx, m, x, &dim, NULL), CF_ERR_NONFINITE);
    CHECK_STATUS(cf_harmonic_basis(ctx, m, cf_mesh_positions(m), NULL, NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_one_form_to_vector_field(ctx, m, cf_mesh_positions(m), NULL, out), CF_ERR_INVALID_ARG);
    cf_mesh *fine = NULL;
    CHECK_STATUS(cf_loop_subdivide(ctx, m, x, 1, &fine), CF_ERR_NONFINITE);
    CHECK_STATUS(cf_loop_subdivide(ctx, m, cf_mesh_positions(m), 0, &fine), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_loop_subdivide(ctx, m, cf_mesh_positions(m), 11, &fine), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_loop_subdivide(ctx, NULL, cf_mesh_positions(m), 1, &fine), CF_ERR_INVALID_ARG);
    CHECK(fine == NULL);
done:
    free(x);
    free(out);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_metrics(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 1, 1.0, &m));
    if (!m) {
        cf_context_destroy(&ctx);
        return;
    }
    int32_t nv = cf_mesh_vertex_count(m);
    const double *a = cf_mesh_positions(m);
    double *b = malloc(3 * (size_t)nv * sizeof *b);
    CHECK(b != NULL);
    if (!b) goto done;
    memcpy(b, a, 3 * (size_t)nv * sizeof *b);
    b[3 * 5 + 2] = INFINITY;
    cf_stats st;
    CHECK_STATUS(cf_quasi_conformal_error(NULL, m, a, a, NULL, &st), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_quasi_conformal_error(ctx, NULL, a, a, NULL, &st), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_quasi_conformal_error(ctx, m, a, NULL, NULL, &st), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_quasi_conformal_error(ctx, m, a, b, NULL, &st), CF_ERR_NONFINITE);
    CHECK(strstr(cf_context_message(ctx), "vertex 5") != NULL);
    CHECK_STATUS(cf_log_area_distortion(ctx, m, b, a, NULL, &st), CF_ERR_NONFINITE);
    CHECK_STATUS(cf_angle_change(ctx, m, a, b, NULL, &st), CF_ERR_NONFINITE);
    cf_vertex_scale_fit fit;
    CHECK_STATUS(cf_vertex_scale_fit_compute(ctx, m, a, b, NULL, NULL, &fit), CF_ERR_NONFINITE);
    CHECK(strstr(cf_context_message(ctx), "vertex 5") != NULL);
    CHECK_STATUS(cf_vertex_scale_fit_compute(ctx, NULL, a, a, NULL, NULL, &fit), CF_ERR_INVALID_ARG);
    {
        /* an edge of zero length in b: vertex 1 onto its neighbour (the edge is named) */
        double *c = malloc(3 * (size_t)nv * sizeof *c);
        const int32_t *ev = cf_mesh_edge_vertices(m);
        memcpy(c, a, 3 * (size_t)nv * sizeof *c);
        memcpy(c + 3 * ev[1], c + 3 * ev[0], 3 * sizeof *c);
        CHECK_STATUS(cf_vertex_scale_fit_compute(ctx, m, a, c, NULL, NULL, &fit), CF_ERR_DEGENERATE_FACE);
        CHECK(strstr(cf_context_message(ctx), "edge 0") != NULL);
        CHECK(strstr(cf_context_message(ctx), "deformed") != NULL);
        free(c);
    }
    CHECK_STATUS(cf_stats_compute(ctx, -1, a, NULL, &st), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_stats_compute(ctx, 3, NULL, NULL, &st), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_stats_compute(ctx, (int64_t)nv * 3, b, NULL, &st), CF_ERR_NONFINITE);
    cf_shape_summary sum;
    CHECK_STATUS(cf_shape_summary_compute(ctx, m, NULL, &sum), CF_ERR_INVALID_ARG);
    double c[3], r = 0.0, rot[9], sc = 0.0, t[3];
    CHECK_STATUS(cf_fit_sphere(ctx, 3, a, c, &r, NULL, NULL), CF_ERR_NUMERICAL);
    CHECK_STATUS(cf_fit_sphere(ctx, nv, NULL, c, &r, NULL, NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_similarity_align(ctx, 0, a, a, NULL, 1, rot, &sc, t, NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_similarity_align(ctx, INT32_MAX, a, a, NULL, 1, rot, &sc, t, NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_similarity_align(ctx, nv, a, b, NULL, 1, rot, &sc, t, NULL), CF_ERR_NONFINITE);
    cf_similarity_apply(nv, NULL, 1.0, t, a, b); /* NULL rotation: no-op, no crash */
    CHECK(isinf(b[3 * 5 + 2]));
    CHECK_STATUS(cf_point_to_surface_distance(ctx, -1, a, m, a, NULL, NULL, NULL, NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_point_to_surface_distance(ctx, nv, b, m, a, NULL, NULL, NULL, NULL), CF_ERR_NONFINITE);
    CHECK_STATUS(cf_aligned_surface_distance(ctx, m, a, b, 1, NULL, NULL, NULL), CF_ERR_NONFINITE);
    double u[9], s3[3], v[9], bad[9] = {1, 0, 0, 0, NAN, 0, 0, 0, 1};
    CHECK_STATUS(cf_svd3(NULL, u, s3, v), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_svd3(bad, u, s3, v), CF_ERR_NONFINITE);
    CHECK_STATUS(cf_rotation_from_covariance(bad, rot), CF_ERR_NONFINITE);
done:
    free(b);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Quaternion helpers taking pointers accept NULL (header: nothing is read
 * or written). */
static void test_quaternion_null(void)
{
    cf_quat z = cf_quat_from_vector(NULL);
    CHECK(z.w == 0.0 && z.x == 0.0 && z.y == 0.0 && z.z == 0.0);
    cf_quat one = cf_quat_from_axis_angle(NULL, 1.0);
    CHECK(one.w == 1.0 && one.x == 0.0);
    cf_quat_to_vector(one, NULL);
    double v[3] = {1, 2, 3};
    cf_quat_conj_sandwich(one, v, NULL);
    cf_quat_conj_sandwich(one, NULL, v);
    CHECK(v[0] == 1.0 && v[1] == 2.0 && v[2] == 3.0);
    cf_quat_left_matrix(one, NULL);
    cf_quat_right_matrix(one, NULL);
}

int main(void)
{
    CFT_RUN(test_vector_operators);
    CFT_RUN(test_metrics);
    CFT_RUN(test_quaternion_null);
    return cft_finish();
}
