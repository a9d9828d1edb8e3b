/*
 * Stability threshold and time-step convergence of the conformal Willmore
 * flow (Crane, Pinkall, Schroeder 2013, Sec. 4 / Fig. 18 and Sec. 6.4.1 /
 * Fig. 16).
 *
 * Convention (NOTES.md): rho = -2 tau H, so mu~ = (1 - 2 tau) mu and the flow
 * is stable for tau < 1. Fig. 18 uses tau = 1 -/+ 0.3 on an irregular mesh.
 * Here: spot_3k at tau = 0.9 decreases W monotonically for 20 steps; at
 * tau = 1.1 and 1.3 the energy rises at some step (forward-Euler oscillation).
 * blade_slivers_8k is NOT used: the cotan mean curvature on its slivers is
 * not realisable by the spin transformation and the flow fails there at
 * every tau (docs/spin.md).
 *
 * Fig. 16: for a flow of fixed duration, conformal distortion converges
 * linearly in tau. Measured here: Q(tau) = Q0 + c tau with a spatial floor
 * Q0 (about 1.11 on spot for duration 0.8), so the order is estimated from
 * successive differences Q(tau) - Q(tau/2).
 */
#include "test.h"

#include "curvflow/flow.h"
#include "curvflow/io.h"
#include "curvflow/metrics.h"
#include "curvflow/spin_willmore.h"

#include <stdlib.h>

static cf_flow *make_flow(cf_context *ctx, const cf_mesh *mesh, double tau)
{
    cf_flow_options o;
    cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o);
    cf_spin_willmore_options *so = cf_flow_options_method(&o);
    so->time_step = tau;
    so->tolerance = 0.0;
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    return flow;
}

/* Number of steps (out of `steps`) whose energy rose; a failed step counts. */
static int energy_increases(cf_context *ctx, const cf_mesh *mesh, double tau, int steps)
{
    cf_flow *flow = make_flow(ctx, mesh, tau);
    if (!flow) return -1;
    double w = cf_flow_energy(flow);
    int rises = 0;
    fprintf(stderr, "   tau %.2f: W/4pi", tau);
    for (int s = 0; s < steps; ++s) {
        cf_flow_info info;
        if (cf_flow_step(flow, &info) != CF_OK) {
            ++rises;
            fprintf(stderr, " (step failed)");
            break;
        }
        fprintf(stderr, " %.4f", info.energy / (4 * 3.14159265358979323846));
        if (info.energy > w) ++rises;
        w = info.energy;
    }
    fprintf(stderr, "\n");
    cf_flow_destroy(&flow);
    return rises;
}

static void test_threshold(void)
{
    const char *path = cft_require_shared_mesh("spot_3k.obj");
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, path, &mesh));
    CHECK(energy_increases(ctx, mesh, 0.9, 20) == 0);
    CHECK(energy_increases(ctx, mesh, 1.1, 8) > 0);
    CHECK(energy_increases(ctx, mesh, 1.3, 8) > 0);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_time_step_convergence(void)
{
    const char *path = cft_require_shared_mesh("spot_3k.obj");
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, path, &mesh));
    double duration = 0.8, q[4];
    double tau = 0.4;
    for (int k = 0; k < 4; ++k, tau *= 0.5) {
        cf_flow *flow = make_flow(ctx, mesh, tau);
        int steps = (int)lround(duration / tau);
        CHECK_OK(ctx, cf_flow_run(flow, steps, NULL));
        cf_stats st;
        CHECK_OK(ctx, cf_quasi_conformal_error(ctx, mesh, cf_mesh_positions(mesh), cf_flow_positions(flow), NULL, &st));
        q[k] = st.weighted_mean;
        fprintf(stderr, "   tau %.3f x %d steps: mean Q %.5f\n", tau, steps, q[k]);
        cf_flow_destroy(&flow);
    }
    for (int k = 0; k < 2; ++k) {
        double order = log2((q[k] - q[k + 1]) / (q[k + 1] - q[k + 2]));
        fprintf(stderr, "   order from taus %d..%d: %.3f\n", k, k + 2, order);
        CHECK(order > 0.7 && order < 1.3);
    }
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_threshold);
    CFT_RUN(test_time_step_convergence);
    return cft_finish();
}
