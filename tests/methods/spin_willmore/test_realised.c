/*
 * The residual `realised_decrease` of spin-willmore: the fraction of the
 * curvature-space model's decrease of W that a step realises (docs/spin.md,
 * "Realised decrease").
 *
 * A spin transformation changes the mean curvature half-density by rho
 * (Crane 2013, Eq. (1): H~ |df~| = (H + rho) |df|), so the step's rho
 * predicts W~ = sum (H + rho)^2 A plus the tangential part of L f, which no
 * curvature change touches. Checked here:
 *  - the residual against that prediction recomputed from the public
 *    operators and the step's rhodot (test hook);
 *  - Eq. (1) itself on the built-in bumpy sphere: small smooth steps
 *    (tau 0.05) realise 0.99 of the model's decrease at every step;
 *  - on spot_3k (skips without ../shared) the first default step realises
 *    about all of it (measured 1.04) and the tenth a tenth (0.08): the
 *    curvature left after a few steps is what the vertex-based step cannot
 *    realise (its rho enters through face sums), the slow tail of the flow;
 *  - from spot's state after 9 steps, one spin transformation realises a
 *    smooth rho (0.97) and white noise (0.27) of the same size far better
 *    than the flow's own rho (0.04): what is left is what the step realises
 *    least, not rough curvature in general.
 */
#include "test.h"

#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/linalg.h"
#include "curvflow/mesh.h"
#include "curvflow/ops.h"
#include "curvflow/spin_willmore.h"
#include "methods/spin_willmore/spin_internal.h"

#include <math.h>
#include <stdlib.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* Normal mean curvature h = <L x, N> / (2 A) and barycentric areas A at x
 * from the public operators; returns W = sum |L x|^2 / (4 A). */
static double curvature(cf_context *ctx, const cf_mesh *mesh, const double *x, double *h, double *area)
{
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *lx = malloc(3 * (size_t)nv * sizeof(double)), *normal = malloc(3 * (size_t)nv * sizeof(double));
    CHECK_OK(ctx, cf_mean_curvature_normal(ctx, mesh, x, lx));
    CHECK_OK(ctx, cf_vertex_areas(ctx, mesh, x, CF_DUAL_AREA_BARYCENTRIC, area));
    CHECK_OK(ctx, cf_vertex_normals(ctx, mesh, x, normal));
    double w = 0.0;
    for (int32_t i = 0; i < nv; ++i) {
        const double *v = lx + 3 * i, *n = normal + 3 * i;
        h[i] = (v[0] * n[0] + v[1] * n[1] + v[2] * n[2]) / (2.0 * area[i]);
        w += (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) / (4.0 * area[i]);
    }
    free(lx);
    free(normal);
    return w;
}

/* W~ of the model for the step from x with rho = tau rhodot (closed mesh):
 * W + sum ((h + rho)^2 - h^2) A. Stores W in w_out. */
static double model_energy(cf_context *ctx, const cf_mesh *mesh, const double *x, const double *rhodot, double tau,
                           double *w_out)
{
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *h = malloc((size_t)nv * sizeof(double)), *area = malloc((size_t)nv * sizeof(double));
    double w = curvature(ctx, mesh, x, h, area), model = 0.0;
    for (int32_t i = 0; i < nv; ++i) {
        double hn = h[i] + tau * rhodot[i];
        model += (hn * hn - h[i] * h[i]) * area[i];
    }
    free(h);
    free(area);
    *w_out = w;
    return w + model;
}

/* Runs `steps` steps of spin-willmore with time step tau (adaptive as
 * given) from mesh, storing the residual of each step in frac; the first
 * step is also checked against the model recomputed here. */
static void run(cf_context *ctx, const cf_mesh *mesh, double tau, int adaptive, int steps, double *frac)
{
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    char text[32];
    snprintf(text, sizeof text, "%.17g", tau);
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "time_step", text));
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "adaptive", adaptive ? "true" : "false"));
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    if (!flow) return;
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *x0 = malloc(3 * (size_t)nv * sizeof(double));
    memcpy(x0, cf_flow_positions(flow), 3 * (size_t)nv * sizeof(double));
    for (int k = 0; k < steps; ++k) {
        cf_flow_info info;
        CHECK_OK(ctx, cf_flow_step(flow, &info));
        frac[k] = cft_flow_residual(&info, "realised_decrease");
        CHECK(!isnan(frac[k])); /* the step reports it */
        if (k == 0) {
            /* the first step from x0 at the full tau: the model from outside */
            const double *rhodot = cfi_spin_willmore_last_rhodot(flow);
            double w0 = 0.0, model = model_energy(ctx, mesh, x0, rhodot, info.time_step, &w0);
            double w1 = cf_flow_energy(flow);
            double expect = (w0 - w1) / (w0 - model);
            fprintf(stderr, "   step 1: W %.6g -> %.6g, model %.6g, realised %.6f (recomputed %.6f)\n", w0, w1, model,
                    frac[0], expect);
            CHECK_NEAR(frac[0], expect, 1e-9, 1e-12);
        }
    }
    free(x0);
    cf_flow_destroy(&flow);
}

static void test_bumpy_sphere(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 4, 0.25, 1u, &mesh));
    double frac[10];
    run(ctx, mesh, 0.05, 0, 10, frac);
    fprintf(stderr, "   bumpy sphere, tau 0.05, realised decrease per step:");
    for (int k = 0; k < 10; ++k) fprintf(stderr, " %.4f", frac[k]);
    fprintf(stderr, "\n");
    /* Eq. (1) holds for small smooth steps (measured 0.987-0.988) */
    for (int k = 0; k < 10; ++k) CHECK(frac[k] > 0.95 && frac[k] < 1.05);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_spot(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "spot_3k.obj", 0)) return;
    cf_context *ctx = shared.ctx;
    cf_mesh *mesh = shared.mesh;
    if (mesh) {
        double frac[10];
        run(ctx, mesh, 0.5, 1, 10, frac);
        fprintf(stderr, "   spot_3k, defaults, realised decrease per step:");
        for (int k = 0; k < 10; ++k) fprintf(stderr, " %.3f", frac[k]);
        fprintf(stderr, "\n");
        /* measured 1.043 and 0.078 */
        CHECK(frac[0] > 0.9 && frac[0] < 1.2);
        CHECK(frac[9] > 0.0 && frac[9] < 0.15);
        for (int k = 1; k < 10; ++k) CHECK(frac[k] < frac[k - 1] + 0.05); /* it decays */
    }
    cft_shared_case_close(&shared);
}

/* rho M-orthogonal to the constants and the normal components (what the
 * flow's constraints leave), then scaled to M-norm `norm`. */
static void constrain(cf_context *ctx, const cf_mesh *mesh, const double *x, const double *area, double norm,
                      double *rho)
{
    int32_t nv = cf_mesh_vertex_count(mesh), rank = 0;
    double *basis = malloc(4 * (size_t)nv * sizeof(double)), *normal = malloc(3 * (size_t)nv * sizeof(double));
    CHECK_OK(ctx, cf_vertex_normals(ctx, mesh, x, normal));
    for (int32_t i = 0; i < nv; ++i) {
        basis[i] = 1.0;
        for (int c = 0; c < 3; ++c) basis[(c + 1) * (int64_t)nv + i] = normal[3 * i + c];
    }
    cf_orthonormalize(nv, 4, basis, area, 1e-10, &rank);
    CHECK(rank == 4);
    cf_project_out(nv, rank, basis, area, rho);
    double scale = norm / sqrt(cf_dot(nv, rho, rho, area));
    for (int32_t i = 0; i < nv; ++i) rho[i] *= scale;
    free(basis);
    free(normal);
}

/* The part of the half-density change H~ |df~| - H |df| that one spin
 * transformation of x by rho realises along rho: <realised, rho>_M /
 * <rho, rho>_M (1 when Eq. (1) holds exactly). */
static double realised_along(cf_context *ctx, const cf_mesh *mesh, const double *x, const double *rho)
{
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *h0 = malloc((size_t)nv * sizeof(double)), *a0 = malloc((size_t)nv * sizeof(double)),
           *h1 = malloc((size_t)nv * sizeof(double)), *a1 = malloc((size_t)nv * sizeof(double)),
           *y = malloc(3 * (size_t)nv * sizeof(double));
    double num = 0.0, den = 0.0;
    CHECK_OK(ctx, cf_spin_transform(ctx, mesh, x, rho, y));
    curvature(ctx, mesh, x, h0, a0);
    curvature(ctx, mesh, y, h1, a1);
    for (int32_t i = 0; i < nv; ++i) {
        double change = (h1[i] * sqrt(a1[i]) - h0[i] * sqrt(a0[i])) / sqrt(a0[i]);
        num += change * rho[i] * a0[i];
        den += rho[i] * rho[i] * a0[i];
    }
    free(h0);
    free(a0);
    free(h1);
    free(a1);
    free(y);
    return num / den;
}

/* Why the tail is slow: after 9 default steps spot_3k still realises a
 * smooth rho (measured 0.97) and white noise in part (0.28) of the same
 * size as the flow's, but the flow's own rho only at 0.04. The curvature
 * left is not rough curvature in general: it is what the flow could not
 * remove, the directions this discretisation realises least. */
static void test_spot_what_is_left(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "spot_3k.obj", 0)) return;
    cf_context *ctx = shared.ctx;
    cf_mesh *mesh = shared.mesh;
    cf_flow *flow = NULL;
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    if (mesh) CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    if (flow) {
        int32_t nv = cf_mesh_vertex_count(mesh);
        double *x = malloc(3 * (size_t)nv * sizeof(double)), *area = malloc((size_t)nv * sizeof(double)),
               *h = malloc((size_t)nv * sizeof(double)), *rho = malloc((size_t)nv * sizeof(double));
        CHECK_OK(ctx, cf_flow_run(flow, 9, NULL));
        memcpy(x, cf_flow_positions(flow), 3 * (size_t)nv * sizeof(double));
        cf_flow_info info;
        CHECK_OK(ctx, cf_flow_step(flow, &info)); /* its rhodot is the one at x */
        const double *rhodot = cfi_spin_willmore_last_rhodot(flow);
        curvature(ctx, mesh, x, h, area);
        double norm = 0.0, zc = 0.0, atot = 0.0;
        for (int32_t i = 0; i < nv; ++i) {
            rho[i] = info.time_step * rhodot[i];
            norm += rho[i] * rho[i] * area[i];
            zc += x[3 * i + 2] * area[i];
            atot += area[i];
        }
        norm = sqrt(norm);
        zc /= atot;
        double flow_part = realised_along(ctx, mesh, x, rho);
        double radius = sqrt(atot / (4.0 * 3.14159265358979323846));
        for (int32_t i = 0; i < nv; ++i) rho[i] = cos(2.0 * (x[3 * i + 2] - zc) / radius);
        constrain(ctx, mesh, x, area, norm, rho);
        double smooth_part = realised_along(ctx, mesh, x, rho);
        uint32_t state = 12345u;
        for (int32_t i = 0; i < nv; ++i) {
            state = state * 1664525u + 1013904223u;
            rho[i] = (double)(state >> 8) / 16777216.0 - 0.5;
        }
        constrain(ctx, mesh, x, area, norm, rho);
        double noise_part = realised_along(ctx, mesh, x, rho);
        fprintf(stderr, "   spot_3k after 9 steps, |rho|_M %.3g: realised along rho: the flow's %.3f, smooth %.3f, "
                        "white noise %.3f\n", norm, flow_part, smooth_part, noise_part);
        CHECK(smooth_part > 0.85);              /* measured 0.97 */
        CHECK(noise_part > 0.15);               /* 0.28 */
        CHECK(flow_part < 0.1);                 /* 0.04 */
        CHECK(flow_part < noise_part / 3.0);
        free(x);
        free(area);
        free(h);
        free(rho);
    }
    cf_flow_destroy(&flow);
    cft_shared_case_close(&shared);
}

int main(void)
{
    CFT_RUN(test_bumpy_sphere);
    CFT_RUN(test_spot);
    CFT_RUN(test_spot_what_is_left);
    return cft_finish();
}
