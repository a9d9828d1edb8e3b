/*
 * Growing tau back (option growth_ratio, docs/spin.md "Growing tau back"):
 * after a step taken at a reduced tau without retries, tau grows back only
 * if the step realised at least growth_ratio (default 0.75) of the decrease
 * of W that its curvature-space model predicts.
 *
 * - bull_6k (shared): with tau doubled after every accepted step
 *   (growth_ratio=0, the rule before), step 4 at tau 0.13 lowered W/4pi
 *   98.70 -> 67.19 but crowded the horns and legs to 1e-18 of the mean
 *   vertex area, and from there no tau lowered W by more than 0.02 per step:
 *   67.15 after 10 steps, above issue 13's target W0/2 = 62.87. With the
 *   default the flow holds tau while the model is not met and reaches 59.74
 *   (mean Q 1.417). Asserted: the default meets the target, the old rule
 *   does not, and every step of the default run follows the rule (from its
 *   log: time step, retries, realised_decrease).
 * - cow_3k (shared): the default holds tau at 0.039 (the step realises 0.31
 *   to 0.43 of the model) and W/4pi falls by more than 1 in every one of the
 *   10 steps (41.36 -> 24.49); with the old rule the flow crawled from step 8
 *   on (24.1063 -> 24.1063 in step 9).
 * Skip without ../shared; bull is left out of sanitizer builds (6k vertices,
 * as in the zoo).
 */
#include "test.h"

#include "curvflow/flow.h"
#include "curvflow/io.h"
#include "curvflow/spin_willmore.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define GROWTH_STEPS 10
#define GROWTH_FOUR_PI (4.0 * 3.14159265358979323846)

typedef struct growth_log {
    double w[GROWTH_STEPS + 1];          /* W/4pi at the start and after each step */
    double time_step[GROWTH_STEPS + 1];  /* the accepted step's tau (index 1..) */
    double halvings[GROWTH_STEPS + 1];
    double realised[GROWTH_STEPS + 1];
    int steps;
} growth_log;

/* 10 steps of spin-willmore with its defaults and growth_ratio g (NAN: the
 * default) on a shared mesh. 0 when the mesh or the flow could not be made. */
static int run_growth(cf_context *ctx, const cf_mesh *mesh, double g, growth_log *out)
{
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    cf_spin_willmore_options *spin = cf_flow_options_method_as(&o, CF_FLOW_SPIN_WILLMORE);
    if (!isnan(g)) spin->growth_ratio = g;
    /* the trajectories the growth rule was measured on: the step without
     * the vertex-scale fairing, which reaches bull's and cow's targets on
     * its own (test `zoo`), nor the tangential relaxation (a default on
     * closed genus-0 surfaces since session 36; with it the rule before also
     * meets bull's target) */
    spin->fairing = 0.0;
    spin->relaxation = 0;
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    if (!flow) return 0;
    memset(out, 0, sizeof *out);
    out->w[0] = cf_flow_energy(flow) / GROWTH_FOUR_PI;
    while (out->steps < GROWTH_STEPS && !cf_flow_converged(flow)) {
        cf_flow_info info;
        CHECK_OK(ctx, cf_flow_step(flow, &info));
        int k = ++out->steps;
        out->w[k] = cf_flow_energy(flow) / GROWTH_FOUR_PI;
        out->time_step[k] = info.time_step;
        out->halvings[k] = cft_flow_residual(&info, "time_step_halvings");
        out->realised[k] = cft_flow_residual(&info, "realised_decrease");
    }
    cf_flow_destroy(&flow);
    return 1;
}

static void test_bull_reaches_target(void)
{
    if (CFT_UNDER_ASAN) {
        fprintf(stderr, "   SKIP bull_6k: 6k vertices, left out of sanitizer builds\n");
        return;
    }
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "bull_6k.obj", 1)) return; /* exit 77 with a SKIP line when absent */
    cf_context *ctx = shared.ctx;
    cf_mesh *mesh = shared.mesh;
    growth_log held, doubled;
    if (mesh && run_growth(ctx, mesh, NAN, &held) && run_growth(ctx, mesh, 0.0, &doubled)) {
        fprintf(stderr, "   bull_6k W/4pi %.4f -> %.4f (default), %.4f (growth_ratio=0); target %.4f\n", held.w[0],
                held.w[held.steps], doubled.w[doubled.steps], 0.5 * held.w[0]);
        CHECK(held.steps == GROWTH_STEPS);
        CHECK_LE(held.w[held.steps], 0.5 * held.w[0]);      /* measured 59.74 of 125.74 */
        CHECK(doubled.w[doubled.steps] > 0.5 * doubled.w[0]); /* measured 67.15: the old rule misses it */
        for (int k = 1; k <= held.steps; ++k) CHECK_LE(held.w[k], held.w[k - 1]);
        /* the rule, step by step: after a step at a reduced tau without
         * retries, the next step starts at the same tau when the step
         * realised less than 0.75 of its model (so is accepted at it or
         * below), at twice it otherwise (accepted at twice it when it needed
         * no retry) */
        int held_count = 0, grown_count = 0;
        for (int k = 2; k <= held.steps; ++k) {
            if (held.halvings[k - 1] != 0.0 || !(held.time_step[k - 1] < 0.5)) continue;
            if (held.realised[k - 1] < 0.75) {
                CHECK_LE(held.time_step[k], held.time_step[k - 1] * (1.0 + 1e-12));
                ++held_count;
            } else if (held.halvings[k] == 0.0) {
                CHECK_NEAR(held.time_step[k], fmin(0.5, 2.0 * held.time_step[k - 1]), 1e-12, 0.0);
                ++grown_count;
            }
        }
        CHECK(held_count >= 3); /* measured: steps 2-6 held, 7 grown */
        CHECK(grown_count >= 1);
    }
    cft_shared_case_close(&shared);
}

static void test_cow_keeps_descending(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "cow_3k.obj", 1)) return;
    cf_context *ctx = shared.ctx;
    cf_mesh *mesh = shared.mesh;
    growth_log r;
    if (mesh && run_growth(ctx, mesh, NAN, &r)) {
        fprintf(stderr, "   cow_3k W/4pi %.4f -> %.4f, tau %.4f .. %.4f\n", r.w[0], r.w[r.steps], r.time_step[1],
                r.time_step[r.steps]);
        CHECK(r.steps == GROWTH_STEPS);
        for (int k = 1; k <= r.steps; ++k) {
            CHECK(r.w[k - 1] - r.w[k] >= 1.0); /* measured 1.06 .. 2.00 per step */
            CHECK_NEAR(r.time_step[k], r.time_step[1], 1e-12, 0.0); /* held: realised 0.31 .. 0.43 */
        }
        CHECK_LE(r.w[r.steps], 24.6); /* measured 24.49 */
    }
    cft_shared_case_close(&shared);
}

int main(void)
{
    CFT_RUN(test_bull_reaches_target);
    CFT_RUN(test_cow_keeps_descending);
    return cft_finish();
}
