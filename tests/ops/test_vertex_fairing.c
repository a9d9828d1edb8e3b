/* cf_vertex_fairing (ops/vertex_fairing.c): out = (I + kappa L0)^-1 in on
 * the free vertices. The result solves its defining equation, held boundary
 * vertices do not move, linear positions on a flat grid are a fixed point,
 * it commutes with scaling and translation, a new kappa refactorises,
 * vertex-scale noise is damped while a smooth shape is not, and bad input
 * fails cleanly. */
#include "curvflow/generate.h"
#include "curvflow/ops.h"
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

/* uniform in [-1, 1], reproducible */
static double noise(uint32_t *state)
{
    *state = *state * 1664525u + 1013904223u;
    return (double)(*state >> 8) / (double)(1u << 23) - 1.0;
}

/* max over free vertices i of |out_i + kappa (L0 out)_i - in_i| relative to max |in| */
static double equation_residual(const cf_sparse *l, const cf_mesh *mesh, int hold, double kappa, const double *in,
                                const double *out)
{
    int32_t nv = cf_mesh_vertex_count(mesh);
    const uint8_t *on_boundary = cf_mesh_vertex_on_boundary(mesh);
    double *col = malloc((size_t)nv * sizeof(double)), *lcol = malloc((size_t)nv * sizeof(double));
    double worst = 0.0, size = 0.0;
    for (int32_t i = 0; i < 3 * nv; ++i) size = fmax(size, fabs(in[i]));
    for (int c = 0; c < 3; ++c) {
        for (int32_t i = 0; i < nv; ++i) col[i] = out[3 * i + c];
        cf_sparse_multiply(l, col, lcol);
        for (int32_t i = 0; i < nv; ++i) {
            if (hold && on_boundary[i]) continue;
            worst = fmax(worst, fabs(col[i] + kappa * lcol[i] - in[3 * i + c]));
        }
    }
    free(col);
    free(lcol);
    return worst / size;
}

static void test_definition_and_refactorisation(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 3, 1.0, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    const double *p = cf_mesh_positions(mesh);
    double *in = malloc(3 * (size_t)nv * sizeof(double)), *out = malloc(3 * (size_t)nv * sizeof(double));
    uint32_t seed = 7u;
    for (int32_t i = 0; i < 3 * nv; ++i) in[i] = p[i] + 0.01 * noise(&seed);
    cf_sparse *l = NULL;
    CHECK_OK(ctx, cf_cotan_laplacian(ctx, mesh, p, &l));
    cf_vertex_fairing *f = NULL;
    CHECK_OK(ctx, cf_vertex_fairing_create(ctx, mesh, NULL, 1, &f));
    const double kappas[] = {0.3, 2.0, 0.3};
    for (int k = 0; k < 3; ++k) {
        cf_solver_timings tm = {0.0, 0.0, 0.0};
        CHECK_OK(ctx, cf_vertex_fairing_apply(f, kappas[k], in, out, &tm));
        CHECK(tm.solve_seconds > 0.0 && tm.factorize_seconds == 0.0); /* no factorisation */
        int32_t it = cf_vertex_fairing_iterations(f);
        fprintf(stderr, "   kappa %.1f: %d iterations\n", kappas[k], it);
        CHECK(it > 0 && it < 200);
        CHECK_LE(equation_residual(l, mesh, 0, kappas[k], in, out), 1e-12);
    }
    /* in place, and kappa 0 is a copy */
    memcpy(out, in, 3 * (size_t)nv * sizeof(double));
    CHECK_OK(ctx, cf_vertex_fairing_apply(f, 2.0, out, out, NULL));
    CHECK_LE(equation_residual(l, mesh, 0, 2.0, in, out), 1e-12);
    CHECK_OK(ctx, cf_vertex_fairing_apply(f, 0.0, in, out, NULL));
    CHECK(memcmp(in, out, 3 * (size_t)nv * sizeof(double)) == 0);
    CHECK(cf_vertex_fairing_iterations(f) == 0);
    cf_vertex_fairing_destroy(&f);
    CHECK(f == NULL);
    cf_vertex_fairing_destroy(&f); /* NULL is fine */
    cf_sparse_destroy(&l);
    free(in);
    free(out);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* A flat grid: boundary vertices are held exactly, the free equation holds,
 * and linear positions (L0 x = 0 at interior vertices of a flat grid) stay. */
static void test_held_boundary_and_linear_fixed_point(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_grid(ctx, 9, 7, 2.0, 1.5, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    const double *p = cf_mesh_positions(mesh);
    const uint8_t *on_boundary = cf_mesh_vertex_on_boundary(mesh);
    double *in = malloc(3 * (size_t)nv * sizeof(double)), *out = malloc(3 * (size_t)nv * sizeof(double));
    cf_vertex_fairing *f = NULL;
    CHECK_OK(ctx, cf_vertex_fairing_create(ctx, mesh, NULL, 1, &f));
    /* linear in x, y: a fixed point */
    for (int32_t i = 0; i < nv; ++i) {
        in[3 * i] = p[3 * i] + 0.5 * p[3 * i + 1];
        in[3 * i + 1] = 2.0 * p[3 * i + 1] - p[3 * i];
        in[3 * i + 2] = 0.25 * p[3 * i] + 1.0;
    }
    CHECK_OK(ctx, cf_vertex_fairing_apply(f, 1.5, in, out, NULL));
    double moved = 0.0;
    for (int32_t i = 0; i < 3 * nv; ++i) moved = fmax(moved, fabs(out[i] - in[i]));
    CHECK_LE(moved, 1e-13);
    /* noise in z: boundary exactly held, interior solves the free equation */
    uint32_t seed = 3u;
    for (int32_t i = 0; i < nv; ++i) {
        in[3 * i] = p[3 * i];
        in[3 * i + 1] = p[3 * i + 1];
        in[3 * i + 2] = 0.05 * noise(&seed);
    }
    CHECK_OK(ctx, cf_vertex_fairing_apply(f, 0.7, in, out, NULL));
    int held = 1;
    double interior_before = 0.0, interior_after = 0.0;
    for (int32_t i = 0; i < nv; ++i) {
        if (on_boundary[i]) {
            held = held && memcmp(in + 3 * i, out + 3 * i, 3 * sizeof(double)) == 0;
            continue;
        }
        interior_before += in[3 * i + 2] * in[3 * i + 2];
        interior_after += out[3 * i + 2] * out[3 * i + 2];
    }
    CHECK(held);
    cf_sparse *l = NULL;
    CHECK_OK(ctx, cf_cotan_laplacian(ctx, mesh, p, &l));
    CHECK_LE(equation_residual(l, mesh, 1, 0.7, in, out), 1e-12);
    CHECK_LE(interior_after, 0.5 * interior_before); /* white noise is mostly vertex-scale */
    /* without holding the boundary the boundary moves too */
    cf_vertex_fairing *free_boundary = NULL;
    CHECK_OK(ctx, cf_vertex_fairing_create(ctx, mesh, NULL, 0, &free_boundary));
    CHECK_OK(ctx, cf_vertex_fairing_apply(free_boundary, 0.7, in, out, NULL));
    CHECK_LE(equation_residual(l, mesh, 0, 0.7, in, out), 1e-12);
    cf_vertex_fairing_destroy(&free_boundary);
    cf_sparse_destroy(&l);
    cf_vertex_fairing_destroy(&f);
    free(in);
    free(out);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* out(s in + t) = s out(in) + t: the step acts on a part of the surface at
 * that part's size, whatever its size (scaled positions, L0 1 = 0). */
static void test_scale_and_translation(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    const double *p = cf_mesh_positions(mesh);
    double *in = malloc(3 * (size_t)nv * sizeof(double)), *out = malloc(3 * (size_t)nv * sizeof(double));
    double *moved = malloc(3 * (size_t)nv * sizeof(double)), *out2 = malloc(3 * (size_t)nv * sizeof(double));
    uint32_t seed = 11u;
    for (int32_t i = 0; i < 3 * nv; ++i) in[i] = p[i] + 0.02 * noise(&seed);
    cf_vertex_fairing *f = NULL;
    CHECK_OK(ctx, cf_vertex_fairing_create(ctx, mesh, NULL, 1, &f));
    CHECK_OK(ctx, cf_vertex_fairing_apply(f, 0.8, in, out, NULL));
    const double s = 1e-7, t[3] = {3.0, -2.0, 0.5};
    for (int32_t i = 0; i < nv; ++i)
        for (int c = 0; c < 3; ++c) moved[3 * i + c] = s * in[3 * i + c] + t[c];
    CHECK_OK(ctx, cf_vertex_fairing_apply(f, 0.8, moved, out2, NULL));
    double worst = 0.0;
    for (int32_t i = 0; i < nv; ++i)
        for (int c = 0; c < 3; ++c) worst = fmax(worst, fabs((out2[3 * i + c] - t[c]) - s * out[3 * i + c]));
    /* the iteration works on the change from the input, so its tolerance
     * (1e-12 of the change) scales with s and the translation drops out */
    double change = 0.0;
    for (int32_t i = 0; i < 3 * nv; ++i) change = fmax(change, fabs(out[i] - in[i]));
    CHECK_LE(worst, 1e-10 * s * change + 1e-15 * 10.0);
    cf_vertex_fairing_destroy(&f);
    free(in);
    free(out);
    free(moved);
    free(out2);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* On a unit sphere with vertex-scale radial noise the step removes most of
 * the noise's Willmore energy; on a smooth ellipsoid it barely changes W. */
static void test_vertex_scale_damping(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 4, 1.0, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    const double *p = cf_mesh_positions(mesh);
    double *x = malloc(3 * (size_t)nv * sizeof(double)), *out = malloc(3 * (size_t)nv * sizeof(double));
    cf_vertex_fairing *f = NULL;
    CHECK_OK(ctx, cf_vertex_fairing_create(ctx, mesh, NULL, 1, &f));
    uint32_t seed = 5u;
    for (int32_t i = 0; i < nv; ++i) {
        double r = 1.0 + 0.004 * noise(&seed);
        for (int c = 0; c < 3; ++c) x[3 * i + c] = r * p[3 * i + c];
    }
    double w_noisy = 0.0, w_faired = 0.0, w_sphere = 0.0;
    CHECK_OK(ctx, cf_willmore_energy(ctx, mesh, p, &w_sphere));
    CHECK_OK(ctx, cf_willmore_energy(ctx, mesh, x, &w_noisy));
    CHECK_OK(ctx, cf_vertex_fairing_apply(f, 0.5, x, out, NULL));
    CHECK_OK(ctx, cf_willmore_energy(ctx, mesh, out, &w_faired));
    fprintf(stderr, "   W/4pi: sphere %.5f, noisy %.5f, faired %.5f\n", w_sphere / (4 * PI), w_noisy / (4 * PI),
            w_faired / (4 * PI));
    CHECK(w_noisy > 1.2 * w_sphere);
    CHECK_LE(w_faired - w_sphere, 0.2 * (w_noisy - w_sphere));
    /* a smooth ellipsoid (1.3, 1, 0.8): W changes by under 1 % */
    for (int32_t i = 0; i < nv; ++i) {
        x[3 * i] = 1.3 * p[3 * i];
        x[3 * i + 1] = p[3 * i + 1];
        x[3 * i + 2] = 0.8 * p[3 * i + 2];
    }
    double w_ellipsoid = 0.0, w_after = 0.0;
    CHECK_OK(ctx, cf_willmore_energy(ctx, mesh, x, &w_ellipsoid));
    CHECK_OK(ctx, cf_vertex_fairing_apply(f, 0.5, x, out, NULL));
    CHECK_OK(ctx, cf_willmore_energy(ctx, mesh, out, &w_after));
    fprintf(stderr, "   ellipsoid W/4pi %.5f -> %.5f\n", w_ellipsoid / (4 * PI), w_after / (4 * PI));
    CHECK_NEAR(w_after, w_ellipsoid, 1e-2, 0.0);
    cf_vertex_fairing_destroy(&f);
    free(x);
    free(out);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_bad_input(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 1, 1.0, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    cf_vertex_fairing *f = NULL;
    CHECK_STATUS(cf_vertex_fairing_create(ctx, NULL, NULL, 1, &f), CF_ERR_INVALID_ARG);
    CHECK(f == NULL);
    CHECK_STATUS(cf_vertex_fairing_create(ctx, mesh, NULL, 1, NULL), CF_ERR_INVALID_ARG);
    CHECK_OK(ctx, cf_vertex_fairing_create(ctx, mesh, NULL, 1, &f));
    double *x = malloc(3 * (size_t)nv * sizeof(double));
    memcpy(x, cf_mesh_positions(mesh), 3 * (size_t)nv * sizeof(double));
    CHECK_STATUS(cf_vertex_fairing_apply(f, -1.0, x, x, NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_vertex_fairing_apply(f, NAN, x, x, NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_vertex_fairing_apply(f, INFINITY, x, x, NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_vertex_fairing_apply(NULL, 1.0, x, x, NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_vertex_fairing_apply(f, 1.0, NULL, x, NULL), CF_ERR_INVALID_ARG);
    x[4] = NAN;
    CHECK_STATUS(cf_vertex_fairing_apply(f, 1.0, x, x, NULL), CF_ERR_NUMERICAL);
    CHECK(strstr(cf_context_message(ctx), "vertex 1") != NULL);
    cf_vertex_fairing_destroy(&f);
    free(x);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_definition_and_refactorisation);
    CFT_RUN(test_held_boundary_and_linear_fixed_point);
    CFT_RUN(test_scale_and_translation);
    CFT_RUN(test_vertex_scale_damping);
    CFT_RUN(test_bad_input);
    return cft_finish();
}
