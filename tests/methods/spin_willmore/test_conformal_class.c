/*
 * Issue 13's W target (W after 10 steps <= W0/2) on bob_5k (genus 1), as a
 * measurement of why it is not met: the flow keeps the conformal class
 * (exactness constraints, period corrections), so it tends to the least W of
 * the input's class, not to the least W of all tori. After 10 default
 * steps it is on a plateau: full steps (no halving), periods below the
 * tolerance, W/4pi 1.8494 after 10 steps and 1.8457 after 30 (0.2 % in 20
 * steps, the rate still falling), against a target of 1.7123. Skips without
 * ../shared.
 */
#include "curvflow/flow.h"
#include "curvflow/io.h"
#include "test.h"

#include <stdio.h>

#define FOUR_PI (4.0 * 3.14159265358979323846)

static void test_bob_plateau(void)
{
    const char *path = cft_optional_shared_mesh("bob_5k.obj");
    if (!path) return;
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, path, &mesh));
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    cf_flow *flow = NULL;
    if (mesh) CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    if (flow) {
        double w0 = cf_flow_energy(flow) / FOUR_PI, w10 = 0.0, w = w0, smallest_step = 1.0;
        for (int step = 1; step <= 30; ++step) {
            cf_flow_info info;
            CHECK_OK(ctx, cf_flow_step(flow, &info));
            double next = cf_flow_energy(flow) / FOUR_PI;
            CHECK_LE(next, w); /* still descending */
            w = next;
            if (step == 10) w10 = w;
            if (step > 10 && info.time_step < smallest_step) smallest_step = info.time_step;
        }
        fprintf(stderr,
                "   bob_5k: W/4pi %.4f -> %.4f (10 steps) -> %.4f (30 steps), smallest time step in steps 11-30 %g; "
                "target W0/2 = %.4f\n",
                w0, w10, w, smallest_step, 0.5 * w0);
        CHECK(w10 > 0.5 * w0);             /* the target is not met ... */
        CHECK(w > 0.5 * w0);
        CHECK_LE(w10 - w, 0.005 * w10);    /* ... on a plateau, not a stall: */
        CHECK_NEAR(smallest_step, 0.5, 0, 0); /* full steps throughout */
        cf_flow_destroy(&flow);
    }
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_bob_plateau);
    return cft_finish();
}
