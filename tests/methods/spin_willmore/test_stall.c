/*
 * A stall of the default flow (every retry of a step raises W) is retried
 * with the positions recovered in the current metric before the run stops
 * (step_policy.c, cfi_spin_stall_retry; docs/spin.md, "Robustness").
 *
 * With the input metric alone, triceratops_needles_3k stopped at W/4pi
 * 35.35 after 5 steps (issue 13's target W0/2 = 18.73) and cow_3k at 24.106
 * in step 10; with the retry they reach 8.44 and 23.83 (mean Q 1.445 and
 * 1.329), W still non-increasing at every step and the results passing the
 * mesh check. Those figures were measured with tau doubled after every
 * accepted step, the rule before growth_ratio (test `growth`), and the
 * retry is tested here under that rule (growth_ratio=0): with the default
 * the trajectories differ (triceratops 5.47 with mean Q 1.531, cow 24.49
 * without a stall; docs/spin.md, "Growing tau back"). bull_6k, with the
 * defaults but the tangential relaxation, checks where the retry restarts
 * when the step before it needed the current metric too. Every run here is
 * without the relaxation (a default on closed genus-0 surfaces since
 * session 36), whose resampled states take other trajectories: it is not
 * what these tests are about. Skips without ../shared.
 */
#include "test.h"

#include "curvflow/flow.h"
#include "curvflow/io.h"
#include "curvflow/spin_willmore.h"
#include "methods/flow_internal.h"
#include "methods/spin_willmore/spin_internal.h"
#include "spin_test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* `steps` steps of spin-willmore, defaults but growth_ratio=0 (and the
 * convergence tolerance 0 if asked), on a shared mesh (spin_run_steps). 0
 * when the flow could not be made. */
static int run_default(const char *name, int steps, int no_tolerance, spin_run *r)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, name, 1)) return 0; /* exit 77 with a SKIP line when absent */
    cf_context *ctx = shared.ctx;
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    cf_spin_willmore_options *spin = cf_flow_options_method_as(&o, CF_FLOW_SPIN_WILLMORE);
    if (spin) spin->growth_ratio = 0.0; /* the rule the stalls were measured with */
    if (spin) spin->fairing = 0.0;      /* and the step without the vertex-scale fairing */
    if (spin) spin->relaxation = 0;     /* nor the tangential relaxation */
    if (spin && no_tolerance) spin->tolerance = 0.0;
    int ran = shared.mesh && spin_run_steps(ctx, shared.mesh, &o, steps, r, NULL);
    if (ran)
        fprintf(stderr, "   %s: W/4pi %.4f -> %.4f, largest rise %.3g, mean Q %.4f, %d defects\n", name, r->w0, r->w,
                r->worst_rise, r->mean_q, r->defects);
    cft_shared_case_close(&shared);
    return ran;
}

static void test_triceratops_reaches_target(void)
{
    spin_run r = {0};
    if (!run_default("triceratops_needles_3k.obj", 10, 0, &r)) return;
    CHECK_LE(r.w, 0.5 * r.w0);  /* measured 8.44 of 37.46; 35.35 (stalled) without the retry */
    CHECK_LE(r.worst_rise, 0.0);
    CHECK_LE(r.mean_q, 1.5);      /* measured 1.445 */
    CHECK(r.defects == 0);
}

/* Which step of cow's run stalls in the input metric depends on the
 * rounding of the machine (step 10 where this was first measured; on
 * another machine the decrease fell below the convergence tolerance at step
 * 9 first, W/4pi 24.10629, and the stall came at step 13): with the
 * tolerance off and 20 steps the stall is reached either way, and the retry
 * takes the run past it (measured 23.833 in step 13, 23.831 by step 16,
 * where it stops). */
static void test_cow_goes_on(void)
{
    spin_run r = {0};
    if (!run_default("cow_3k.obj", 20, 1, &r)) return;
    CHECK_LE(r.w, 23.95);       /* measured 23.831; the input metric alone stalls at 24.106 */
    CHECK_LE(r.worst_rise, 0.0);
    CHECK(r.defects == 0);
}

/* bull_6k with the defaults creeps from step 5 on (its needles, docs/spin.md),
 * every step in the current metric: the retry of a step whose predecessor
 * already needed the current metric restarts at four times that step's tau
 * instead of the full step, so it takes 2-3 halvings, not 7-9 (10 steps:
 * 5.0 -> 3.4-4.2 s), and W goes on falling as before (61.2240 -> 61.2210). */
static void test_bull_retry_restarts_near_last_step(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "bull_6k.obj", 1)) return;
    cf_context *ctx = shared.ctx;
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    /* the trajectory measured: with the relaxation bull converges at step 7
     * (W/4pi 46.07) after one current-metric step */
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "relaxation", "0"));
    cf_flow *flow = NULL;
    if (shared.mesh) CHECK_OK(ctx, cf_flow_create(ctx, shared.mesh, NULL, &o, &flow));
    if (flow) {
        double w0 = cf_flow_energy(flow), before = w0;
        int previous_current = 0, pairs = 0;
        for (int k = 1; k <= 10 && !cf_flow_converged(flow); ++k) {
            cf_flow_info info;
            CHECK_OK(ctx, cf_flow_step(flow, &info));
            cfi_spin_diagnostics d;
            CHECK_OK(ctx, cfi_spin_willmore_diagnostics(flow, &d));
            double halvings = cft_flow_residual(&info, "time_step_halvings");
            fprintf(stderr, "   step %d: tau %.4g, halvings %.0f, current metric %d, W/4pi %.4f\n", k, info.time_step,
                    halvings, d.current_metric, cf_flow_energy(flow) / (4.0 * 3.14159265358979323846));
            CHECK_LE(cf_flow_energy(flow), before);
            if (previous_current && d.current_metric && info.time_step > 0.0) {
                ++pairs;
                CHECK_LE(halvings, 3.0); /* measured 2-3; 7-9 from the full step */
            }
            previous_current = d.current_metric && info.time_step > 0.0;
            before = cf_flow_energy(flow);
        }
        CHECK(pairs >= 3); /* measured 4 (steps 6-9) */
        CHECK_LE(cf_flow_energy(flow), 0.5 * w0); /* issue 13's target; measured 61.221 of 125.74 */
        cf_flow_destroy(&flow);
    }
    cft_shared_case_close(&shared);
}

/* One run for test_halving_search: 10 steps with halving_search on or off
 * and the options `settings` (name, value pairs, NULL-terminated): the
 * positions (3 nv), W after each step and the attempts made; -1 when the
 * flow could not be made. */
static int64_t halving_run(const cft_shared_case *shared, int search, const char *const *settings, double *positions,
                           double w[10])
{
    cf_context *ctx = shared->ctx;
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "halving_search", search ? "true" : "false"));
    for (int k = 0; settings[k]; k += 2) CHECK_OK(ctx, cf_flow_options_set(ctx, &o, settings[k], settings[k + 1]));
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, shared->mesh, NULL, &o, &flow));
    if (!flow) return -1;
    for (int k = 0; k < 10; ++k) {
        if (!cf_flow_converged(flow)) CHECK_OK(ctx, cf_flow_step(flow, NULL));
        w[k] = cf_flow_energy(flow);
    }
    memcpy(positions, cf_flow_positions(flow), 3 * (size_t)cf_mesh_vertex_count(shared->mesh) * sizeof(double));
    int64_t attempts = flow->attempts;
    cf_flow_destroy(&flow);
    return attempts;
}

/* The layer's search of a round of halvings (option halving_search, on by
 * default; src/methods/flow.c) takes the same steps as plain halving, bit
 * for bit, in fewer attempts. On bull_6k (steps 5-10) and
 * spool_creases_650 (steps 3-4) the input metric's rounds rise at every
 * step down to the limit before the current-metric retry or the stall: the
 * search tries the smallest step after three rises that halve like a
 * first-order rise, and ends the round there when it rises as predicted
 * (10 default steps, measured: bull 95 -> 60 attempts, spool 60 -> 32, its
 * stalls ending in the fairing alone, test_stall_fairing).
 * On triceratops_needles_3k with growth_ratio=0 and fairing=0
 * (test_triceratops_reaches_target) a round that looked like that had a
 * descent at a small step (step 4: rises at 0.0125 and 0.00625 that halved
 * by 2.5 and 1.8, accepted at 0.000195): the bisection finds the step plain
 * halving takes, so W/4pi stays 8.442 (a rule that ended the round there
 * instead reached 6.05 at mean Q 1.516). Without the tangential relaxation,
 * whose resampled states stall less often (bull 41 against 48 attempts with
 * it, spool 50 against 56). */
static void test_halving_search(void)
{
    static const char *const none[] = {"relaxation", "0", NULL};
    static const char *const triceratops[] = {"growth_ratio", "0", "fairing", "0", "relaxation", "0", NULL};
    const struct {
        const char *mesh;
        const char *const *settings;
        double most; /* attempts with the search / without, at most */
    } cases[] = {{"bull_6k.obj", none, 0.75}, {"spool_creases_650.obj", none, 0.75},
                 {"triceratops_needles_3k.obj", triceratops, 0.85}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        cft_shared_case shared;
        if (!cft_shared_case_open(&shared, cases[c].mesh, 1)) return;
        size_t n3 = shared.mesh ? 3 * (size_t)cf_mesh_vertex_count(shared.mesh) : 0;
        double *x_search = n3 ? calloc(n3, sizeof(double)) : NULL, *x_plain = n3 ? calloc(n3, sizeof(double)) : NULL;
        if (x_search && x_plain) {
            double w_search[10] = {0}, w_plain[10] = {0};
            int64_t a_search = halving_run(&shared, 1, cases[c].settings, x_search, w_search);
            int64_t a_plain = halving_run(&shared, 0, cases[c].settings, x_plain, w_plain);
            fprintf(stderr, "   %s: %lld attempts with the search, %lld without; W/4pi %.6f / %.6f\n", cases[c].mesh,
                    (long long)a_search, (long long)a_plain, w_search[9] / (4.0 * 3.14159265358979323846),
                    w_plain[9] / (4.0 * 3.14159265358979323846));
            CHECK(a_search > 0 && a_plain > 0);
            CHECK(memcmp(x_search, x_plain, n3 * sizeof(double)) == 0);
            CHECK(memcmp(w_search, w_plain, sizeof w_search) == 0);
            CHECK_LE((double)a_search, cases[c].most * (double)a_plain); /* measured 0.63, 0.53, 0.78 */
        }
        free(x_search);
        free(x_plain);
        cft_shared_case_close(&shared);
    }
}

/* A stall in both metrics ends in the vertex-scale fairing of the step's
 * start alone (option stall_fairing, default on; docs/spin.md, "A stall's
 * last variant"). man_slivers_17k stalls at step 4: W rises at every tau
 * in the input metric and in the current one, and the run stopped there
 * (W/4pi 109.59 of 235.0). The fairing alone lowers W where the spin step
 * cannot (the vertex-scale part of the cotan curvature the transformation
 * does not see), under the same excess bound as every closed-surface step:
 * measured 81.998 after 10 steps, mean Q 1.312 (1.207 stopped); with the
 * tangential relaxation (the default since session 36) 70.23 in 9 steps,
 * mean Q 1.231; since session 39 the fairing steps after the first carry
 * their tau (70.197 in 10 steps, mean Q 1.231). */
static void test_stall_fairing(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "man_slivers_17k.obj", 1)) return;
    cf_context *ctx = shared.ctx;
    spin_run off = {0}, on = {0};
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    CHECK(((cf_spin_willmore_options *)cf_flow_options_method(&o))->stall_fairing == 1);
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "stall_fairing", "false"));
    if (shared.mesh && spin_run_steps(ctx, shared.mesh, &o, 10, &off, NULL)) {
        fprintf(stderr, "   stall_fairing=false: %d steps, W/4pi %.4f -> %.4f, mean Q %.4f\n", off.steps, off.w0, off.w,
                off.mean_q);
        CHECK(off.steps == 4); /* the stall at step 4 stops the run */
    }
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    cf_flow *flow = NULL;
    if (shared.mesh) CHECK_OK(ctx, cf_flow_create(ctx, shared.mesh, NULL, &o, &flow));
    if (flow) {
        double before = cf_flow_energy(flow);
        int fairing_steps = 0, carried_steps = 0;
        double last_tau = 0.0, last_halvings = -1.0; /* of the last fairing-only step */
        for (int k = 1; k <= 10 && !cf_flow_converged(flow); ++k) {
            cf_flow_info info;
            CHECK_OK(ctx, cf_flow_step(flow, &info));
            cfi_spin_diagnostics d;
            CHECK_OK(ctx, cfi_spin_willmore_diagnostics(flow, &d));
            CHECK_LE(cf_flow_energy(flow), before);
            double halvings = cft_flow_residual(&info, "time_step_halvings");
            if (d.fairing_only && info.time_step > 0.0) {
                ++fairing_steps;
                CHECK_LE(d.conformal_excess, 0.12);
                CHECK(d.fairing_kappa == info.time_step); /* kappa = fairing tau, fairing 1 */
                if (last_halvings >= 0.0) {
                    /* a fairing step after another starts from the tau
                     * carried by the layer (doubled after a step without
                     * halvings, up to the full 0.5), not from the full
                     * step again: its first attempt is its tau times
                     * 2^halvings (measured on man: 4, 3, 2, 3 halvings;
                     * from the full step 4, 7, 9) */
                    double carried = last_halvings == 0.0 ? fmin(0.5, 2.0 * last_tau) : last_tau;
                    CHECK_NEAR(ldexp(info.time_step, (int)halvings), carried, 1e-12, 0.0);
                    ++carried_steps;
                }
                last_tau = info.time_step;
                last_halvings = halvings;
            } else {
                last_halvings = -1.0;
            }
            before = cf_flow_energy(flow);
        }
        fprintf(stderr, "   default: %d fairing-only steps, %d from the carried tau\n", fairing_steps, carried_steps);
        CHECK(fairing_steps >= 1);
        CHECK(carried_steps >= 2);
        cf_flow_destroy(&flow);
    }
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    if (shared.mesh && spin_run_steps(ctx, shared.mesh, &o, 10, &on, NULL)) {
        fprintf(stderr, "   default: %d steps, W/4pi %.4f -> %.4f, mean Q %.4f, %d defects\n", on.steps, on.w0, on.w,
                on.mean_q, on.defects);
        CHECK_LE(on.worst_rise, 0.0);
        CHECK_LE(on.w, 0.70 * off.w); /* measured 70.2 against 109.6 (82.0 without the relaxation) */
        CHECK_LE(on.mean_q, 1.3);     /* measured 1.231 (1.312 without) */
        CHECK(on.defects == 0);
    }
    cft_shared_case_close(&shared);
}

int main(void)
{
    CFT_RUN(test_triceratops_reaches_target);
    CFT_RUN(test_cow_goes_on);
    CFT_RUN(test_bull_retry_restarts_near_last_step);
    CFT_RUN(test_halving_search);
    CFT_RUN(test_stall_fairing);
    return cft_finish();
}
