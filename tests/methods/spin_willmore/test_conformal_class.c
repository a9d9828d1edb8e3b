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
#include "spin_test_util.h"

#include <stdio.h>

static void test_bob_plateau(void)
{
    const char *path = cft_optional_shared_mesh("bob_5k.obj");
    if (!path) return;
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, path, &mesh));
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    spin_run r = {0};
    double w[31];
    if (mesh && spin_run_steps(ctx, mesh, &o, 30, &r, w)) {
        CHECK(r.steps == 30);
        fprintf(stderr,
                "   bob_5k: W/4pi %.4f -> %.4f (10 steps) -> %.4f (30 steps), smallest time step %g; target W0/2 = "
                "%.4f\n",
                r.w0, w[10], r.w, r.smallest_step, 0.5 * r.w0);
        CHECK_LE(r.worst_rise, 0.0);           /* still descending */
        CHECK(w[10] > 0.5 * r.w0);             /* the target is not met ... */
        CHECK(r.w > 0.5 * r.w0);
        CHECK_LE(w[10] - r.w, 0.005 * w[10]);  /* ... on a plateau, not a stall: */
        CHECK_NEAR(r.smallest_step, 0.5, 0, 0); /* full steps throughout, from step 1 */
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
