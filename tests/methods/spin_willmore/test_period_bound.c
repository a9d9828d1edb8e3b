/*
 * Option max_period_error of spin-willmore (docs/spin.md, "Periods the
 * corrections cannot cancel"): on a closed surface of genus > 0 an attempt
 * whose periods the Newton corrections leave above the bound (0.03, ten
 * times period_tolerance) is redone with half tau.
 *
 * The case is a coarse knotted tube (trefoil, 120 rings of 10 vertices,
 * radius 0.35 +- 0.1; bench/bench_unseen_kinds.py --tubes,
 * tube_trefoil_120x10). Measured: at tau 0.5 its first step's correction
 * diverges and is undone, leaving periods of 0.040; without the bound that
 * step is kept and 10 steps end at W/4pi 5.81 (issue 13's target, half of
 * 10.69, is 5.34). With it the first step is redone at tau 0.25 and 10
 * steps reach 4.98 (mean Q 1.51 against 1.47). On a real knot tube (1 440
 * vertices, outside the repository) the bound takes mean Q after 10 steps
 * from 1.56 to 1.42 with W/4pi 3.07 against a target of 3.17; no shared
 * mesh's run changes.
 * Checked: the bound is kept at every step, the first step is redone, the
 * target, W non-increasing, the mesh check; without the bound the periods
 * left and the missed target.
 */
#include "test.h"

#include "curvflow/flow.h"
#include "curvflow/mesh.h"
#include "spin_test_util.h"

#include <math.h>
#include <string.h>

/* What a run's steps left: the largest `periods` residual and the first
 * step's `time_step_halvings` (a spin_step_hook). */
typedef struct periods_seen {
    double largest;
    double first_halvings;
} periods_seen;

static double residual(const cf_flow_info *info, const char *name)
{
    for (int32_t k = 0; k < CF_FLOW_MAX_RESIDUALS; ++k)
        if (info->residual_names[k] && strcmp(info->residual_names[k], name) == 0) return info->residuals[k];
    return NAN;
}

static void record(cf_context *ctx, const cf_flow *flow, int step, void *user)
{
    (void)ctx;
    periods_seen *seen = user;
    const cf_flow_info *info = cf_flow_last_info(flow);
    double periods = residual(info, "periods");
    CHECK(isfinite(periods));
    if (periods > seen->largest) seen->largest = periods;
    if (step == 1) seen->first_halvings = residual(info, "time_step_halvings");
}

static void run(cf_context *ctx, const cf_mesh *mesh, const char *bound, spin_run *r, periods_seen *seen)
{
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    if (bound) CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "max_period_error", bound));
    memset(seen, 0, sizeof *seen);
    CHECK(spin_run_steps_hooked(ctx, mesh, &o, 10, r, NULL, record, seen));
}

static void test_coarse_knot(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *knot = spin_knotted_tube(ctx, 120, 10, 0.35, 0.1);
    CHECK(knot != NULL && cf_mesh_genus(knot) == 1);
    if (!knot) {
        cf_context_destroy(&ctx);
        return;
    }
    spin_run bounded, unbounded;
    periods_seen with, without;
    run(ctx, knot, NULL, &bounded, &with);
    run(ctx, knot, "0", &unbounded, &without);
    printf("  knot 120 x 10: W/4pi %.4f -> %.4f (mean Q %.3f), largest periods %.4f, first step halved %g times; "
           "without the bound %.4f (mean Q %.3f), largest periods %.4f\n",
           bounded.w0, bounded.w, bounded.mean_q, with.largest, with.first_halvings, unbounded.w, unbounded.mean_q,
           without.largest);
    /* the bound holds at every step, and it is what redid the first one */
    CHECK(with.largest <= 0.03 && with.first_halvings >= 1.0);
    CHECK(without.largest > 0.03 && without.first_halvings == 0.0);
    /* issue 13's targets that this tube meets with it: W halved, W never rising, a valid mesh */
    CHECK(bounded.steps == 10 && bounded.w <= 0.5 * bounded.w0);
    CHECK(bounded.worst_rise <= 1e-9 * bounded.w0 && bounded.defects == 0);
    /* and the damage without it: the target missed (measured 5.81 of 10.69) */
    CHECK(unbounded.w > 0.5 * unbounded.w0 && unbounded.w > bounded.w + 0.5);
    cf_mesh_destroy(&knot);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_coarse_knot);
    return cft_finish();
}
