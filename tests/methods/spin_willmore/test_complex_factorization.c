/*
 * The flow factorises X(rho) (and X(0) of the exactness constraint) as the
 * complex Hermitian form of half the size (complex_factorization = 1, the
 * default). It must follow the real 4 nv x 4 nv path to rounding on every
 * branch that uses it: a bumpy sphere (eigenproblem), a bumped torus (exactness
 * solves with X(0)), a cylinder with a fixed boundary (linear solve), and a
 * cylinder with prescribed binormals (always real: the option must not break
 * it). The two runs must also differ in what they allocate, so the option is
 * known to reach the solver.
 */
#include "test.h"
#include "spin_test_util.h"

#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/spin_willmore.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Runs `steps` steps with both settings; returns the largest coordinate
 * difference relative to the bounding-box diagonal. */
static double compare_paths(cf_context *ctx, const cf_mesh *mesh, const double *start, const char *boundary, double tau,
                            int steps, int *bytes_differ)
{
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *result[2] = {malloc(3 * (size_t)nv * sizeof(double)), malloc(3 * (size_t)nv * sizeof(double))};
    size_t bytes[2] = {0, 0};
    char tau_text[32];
    snprintf(tau_text, sizeof tau_text, "%.17g", tau);
    for (int complex_form = 0; complex_form < 2; ++complex_form) {
        cf_flow_options o;
        CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
        CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "boundary", boundary));
        CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "time_step", tau_text));
        CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "complex_factorization", complex_form ? "1" : "0"));
        size_t before = cf_context_bytes_in_use(ctx);
        cf_flow *flow = NULL;
        CHECK_OK(ctx, cf_flow_create(ctx, mesh, start, &o, &flow));
        if (!flow) break;
        bytes[complex_form] = cf_context_bytes_in_use(ctx) - before;
        for (int s = 0; s < steps; ++s) {
            cf_flow_info info;
            CHECK_OK(ctx, cf_flow_step(flow, &info));
        }
        memcpy(result[complex_form], cf_flow_positions(flow), 3 * (size_t)nv * sizeof(double));
        cf_flow_destroy(&flow);
    }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, diff = 0.0;
    for (int32_t i = 0; i < 3 * nv; ++i) {
        lo[i % 3] = fmin(lo[i % 3], result[0][i]);
        hi[i % 3] = fmax(hi[i % 3], result[0][i]);
        diff = fmax(diff, fabs(result[0][i] - result[1][i]));
    }
    double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                       (hi[2] - lo[2]) * (hi[2] - lo[2]));
    *bytes_differ = bytes[0] != bytes[1];
    free(result[0]);
    free(result[1]);
    return diff / diag;
}

static void test_paths_agree(void)
{
    cf_context *ctx = cft_context();
    struct {
        const char *name, *boundary;
        double tau;
        int expect_bytes_differ;
        cf_mesh *mesh;
    } cases[4] = {{"bumpy sphere", "free", 0.5, 1, NULL},
                  {"torus (exactness)", "free", 0.1, 1, NULL},
                  {"cylinder, fixed boundary", "fixed", 0.1, 1, NULL},
                  {"cylinder, prescribed binormals", "prescribed", 0.05, 0, NULL}};
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.2, 7u, &cases[0].mesh));
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.4, 24, 12, &cases[1].mesh));
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 24, 12, 0.5, 1.5, &cases[2].mesh));
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 24, 12, 0.5, 1.5, &cases[3].mesh));
    /* a wavy cylinder, so the fixed-boundary flow has something to do */
    int32_t ncyl = cases[2].mesh ? cf_mesh_vertex_count(cases[2].mesh) : 0;
    double *wavy = malloc(3 * (size_t)ncyl * sizeof *wavy);
    if (ncyl) memcpy(wavy, cf_mesh_positions(cases[2].mesh), 3 * (size_t)ncyl * sizeof *wavy);
    for (int32_t i = 0; i < ncyl; ++i) {
        double f = 1.0 + 0.15 * sin(6.0 * wavy[3 * i + 2]) * cos(3.0 * atan2(wavy[3 * i + 1], wavy[3 * i]));
        wavy[3 * i] *= f;
        wavy[3 * i + 1] *= f;
    }
    /* a bumped torus (a torus of revolution is a critical point: nothing moves) */
    double *bumped = cases[1].mesh ? bumped_torus_positions(cases[1].mesh) : NULL;
    for (int c = 0; c < 4; ++c) {
        if (!cases[c].mesh) continue;
        int bytes_differ = 0;
        double d = compare_paths(ctx, cases[c].mesh, c == 2 ? wavy : c == 1 ? bumped : NULL, cases[c].boundary, cases[c].tau, 3,
                                 &bytes_differ);
        fprintf(stderr, "   %s: complex vs real factorisation, max difference %.3g of the diagonal\n", cases[c].name, d);
        CHECK_LE(d, 1e-9);
        CHECK(bytes_differ == cases[c].expect_bytes_differ);
        cf_mesh_destroy(&cases[c].mesh);
    }
    free(wavy);
    free(bumped);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_paths_agree);
    return cft_finish();
}
