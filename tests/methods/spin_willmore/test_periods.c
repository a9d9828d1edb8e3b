/*
 * Newton corrections of the periods (periods.c; docs/spin.md, "Periods"):
 * on closed surfaces of genus > 0 the linearised exactness constraint
 * leaves periods of second order in tau, which the corrections remove.
 *
 * - Generated double torus (genus 2, 198 vertices), one fixed step at tau
 *   0.5: the harmonic part of the transformed edges converges
 *   quadratically (5.7e-2 -> 2.4e-3 -> 1.4e-5 re-solved, then 3.3e-10 with
 *   the first-order lambda, which a tolerance of 1e-8 first accepts there:
 *   the Jacobian is exact), the default stops below period_tolerance, the step's
 *   non-integrability falls with it. period_iterations = 0 makes none.
 * - Bumped torus: periods already below the tolerance are left alone (the
 *   step of period_iterations = 0); a correction that would raise them is
 *   undone.
 * - Option max_integrability_error on the generated eight-armed star: every
 *   accepted step stays under the bound (its first step, 1.4 % at tau 0.5,
 *   is redone with tau 0.25 under a bound of 1 %), W still falls.
 * - Option period_first_order: the first-order lambda's periods against the
 *   re-solved one's (test_first_order_lambda).
 * - elk_g1_2k (shared): 10 default steps reach W0/2 (measured 22.8 -> 5.76;
 *   11.50 without the corrections, issue 13's target 11.41), W never
 *   rising, no defect.
 */
#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/metrics.h"
#include "curvflow/spin_willmore.h"
#include "methods/spin_willmore/spin_internal.h"
#include "spin_test_util.h"
#include "test.h"

#include <math.h>
#include <stdio.h>

#define FOUR_PI (4.0 * 3.14159265358979323846)

/* One step of the fixed scheme (adaptive = 0) at tau 0.5 with at most
 * `iterations` corrections: the diagnostics and W/4pi before and after. */
static void one_step_at(cf_context *ctx, const cf_mesh *mesh, const double *x, int32_t iterations, double tolerance,
                        int32_t first_order, const char *tau, cfi_spin_diagnostics *d, double *w0, double *w1)
{
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "adaptive", "0"));
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "time_step", tau));
    cf_spin_willmore_options *so = cf_flow_options_method(&o);
    so->period_iterations = iterations;
    so->period_tolerance = tolerance;
    so->period_first_order = first_order;
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, x, &o, &flow));
    if (!flow) return;
    *w0 = cf_flow_energy(flow) / FOUR_PI;
    CHECK_OK(ctx, cf_flow_step(flow, NULL));
    *w1 = cf_flow_energy(flow) / FOUR_PI;
    CHECK_OK(ctx, cfi_spin_willmore_diagnostics(flow, d));
    cf_flow_destroy(&flow);
}

static void one_step(cf_context *ctx, const cf_mesh *mesh, const double *x, int32_t iterations, double tolerance,
                     cfi_spin_diagnostics *d, double *w0, double *w1)
{
    one_step_at(ctx, mesh, x, iterations, tolerance, 1, "0.5", d, w0, w1);
}

static void test_double_torus(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_double_torus(ctx, 2, &mesh));
    if (mesh) {
        cfi_spin_diagnostics none = {0}, one = {0}, dflt = {0}, tight = {0};
        double w0 = 0, w_none = 0, w_one = 0, w_default = 0, w_tight = 0;
        one_step(ctx, mesh, NULL, 0, 3e-3, &none, &w0, &w_none);
        one_step(ctx, mesh, NULL, 1, 1e-8, &one, &w0, &w_one);
        one_step(ctx, mesh, NULL, 3, 3e-3, &dflt, &w0, &w_default);
        one_step(ctx, mesh, NULL, 3, 1e-8, &tight, &w0, &w_tight);
        fprintf(stderr,
                "   double torus (generated, genus 2), one step at tau 0.5: harmonic part of e~ %.3e -> %.3e (1 "
                "correction) -> %.3e (3); integrability %.4f without, %.4f with; W/4pi %.4f -> %.4f without, %.4f "
                "with\n",
                one.period_error_first, one.period_error, tight.period_error, none.integrability_error,
                dflt.integrability_error, w0, w_none, w_default);
        CHECK(none.period_iterations == 0 && none.period_error == 0.0); /* 0: no correction */
        CHECK(one.period_error_first > 10.0 * 3e-3);                     /* measured 5.7e-2 */
        CHECK_NEAR(tight.period_error_first, one.period_error_first, 1e-12, 0); /* the same first lambda */
        /* Newton with the exact Jacobian: measured 5.7e-2 -> 2.4e-3 -> 1.4e-5 -> 3.3e-10 */
        CHECK_LE(one.period_error, 0.1 * one.period_error_first);
        CHECK(tight.period_iterations == 3);
        CHECK_LE(tight.period_error, 1e-6);
        /* the default stops below period_tolerance, after one correction here */
        CHECK(dflt.period_iterations == 1);
        CHECK_LE(dflt.period_error, 3e-3);
        CHECK_LE(dflt.integrability_error, none.integrability_error); /* 0.0764 vs 0.0901 */
        CHECK_LE(w_default, w0);
    }
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Option period_first_order (the default): a correction first takes lambda
 * at first order in it. On the generated double torus, one fixed step at
 * tau 0.5 / 0.25 / 0.125, the first correction's first-order lambda leaves
 * periods of 5.4e-4 / 1.5e-4 / 2.5e-5 where the re-solved lambda leaves
 * 2.4e-3 / 3.0e-4 / 4.7e-5 (the Newton step models the first-order lambda;
 * the re-solved one adds its own second-order change). Below the default
 * tolerance the corrections end there, without the factorisation of X at
 * the corrected rho; period_first_order = 0 re-solves every correction. */
static void test_first_order_lambda(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_double_torus(ctx, 2, &mesh));
    const char *taus[] = {"0.5", "0.25", "0.125"};
    for (int k = 0; mesh && k < 3; ++k) {
        cfi_spin_diagnostics first = {0}, solved = {0};
        double w0 = 0, w_first = 0, w_solved = 0;
        one_step_at(ctx, mesh, NULL, 3, 3e-3, 1, taus[k], &first, &w0, &w_first);
        one_step_at(ctx, mesh, NULL, 3, 3e-3, 0, taus[k], &solved, &w0, &w_solved);
        /* the re-solved lambda's periods after one correction */
        cfi_spin_diagnostics one = {0};
        double w_one = 0;
        one_step_at(ctx, mesh, NULL, 1, 1e-12, 0, taus[k], &one, &w0, &w_one);
        fprintf(stderr,
                "   double torus, tau %s: periods %.3e -> %.3e (first-order lambda) / %.3e (re-solved); W/4pi %.5f -> "
                "%.5f / %.5f\n",
                taus[k], first.period_error_first, first.period_first_order_error, one.period_error, w0, w_first,
                w_solved);
        CHECK_NEAR(first.period_error_first, solved.period_error_first, 0, 0); /* the same first lambda */
        CHECK(first.period_error_first > 3e-3);                                /* a correction is made */
        CHECK(first.period_first_order_error > 0.0);
        CHECK_LE(first.period_first_order_error, one.period_error);
        CHECK_LE(first.period_first_order_error, 0.02 * first.period_error_first); /* 0.95 %, 0.86 %, 0.54 % */
        /* taken: the corrections end after it, without a factorisation */
        CHECK(first.period_iterations == 1 && first.period_first_order == 1);
        CHECK_NEAR(first.period_error, first.period_first_order_error, 0, 0);
        CHECK(solved.period_first_order == 0 && solved.period_first_order_error == 0.0);
        CHECK_LE(w_first, w0);
    }
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_bumped_torus(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    double *x = bumped_torus_fixture(ctx, &mesh);
    if (x) {
        /* its periods (2.8e-3 of e~) are below the default tolerance: no
         * correction, the step of period_iterations = 0 to the last bit */
        cfi_spin_diagnostics none = {0}, dflt = {0};
        double w0 = 0, w_none = 0, w_default = 0;
        one_step(ctx, mesh, x, 0, 3e-3, &none, &w0, &w_none);
        one_step(ctx, mesh, x, 3, 3e-3, &dflt, &w0, &w_default);
        CHECK(dflt.period_iterations == 0);
        CHECK(dflt.period_error_first > 0.0 && dflt.period_error_first <= 3e-3);
        CHECK_NEAR(w_default, w_none, 1e-12, 0); /* (the basis is orthonormalised in two passes) */
        /* with a tighter tolerance: measured 2.8e-3 -> 1.6e-3 after one
         * correction, and the second, which raised it, undone (the periods of
         * this torus respond weakly to rho) */
        cfi_spin_diagnostics tight = {0};
        double w_tight = 0;
        one_step(ctx, mesh, x, 3, 1e-5, &tight, &w0, &w_tight);
        fprintf(stderr, "   bumped torus: harmonic part of e~ %.3e, %.3e after %d correction(s) at period_tolerance 1e-5\n",
                tight.period_error_first, tight.period_error, tight.period_iterations);
        CHECK_LE(tight.period_error, tight.period_error_first);
        CHECK_LE(w_tight, w0);
    }
    free(x);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_integrability_bound(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_limb_sphere(ctx, 5, 8, 1.4, 0.22, &mesh));
    for (int bounded = 0; mesh && bounded < 2; ++bounded) {
        cf_flow_options o;
        CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
        if (bounded) CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "max_integrability_error", "0.01"));
        cf_flow *flow = NULL;
        CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
        if (!flow) break;
        double w = cf_flow_energy(flow), worst = 0.0, first_tau = 0.0;
        for (int step = 0; step < 3; ++step) {
            cf_flow_info info;
            CHECK_OK(ctx, cf_flow_step(flow, &info));
            cfi_spin_diagnostics d;
            CHECK_OK(ctx, cfi_spin_willmore_diagnostics(flow, &d));
            if (d.integrability_error > worst) worst = d.integrability_error;
            if (step == 0) first_tau = info.time_step;
            CHECK_LE(cf_flow_energy(flow), w);
            w = cf_flow_energy(flow);
        }
        fprintf(stderr, "   star, 3 default steps%s: largest non-integrability %.4f, first tau %g, W/4pi %.4f\n",
                bounded ? " with max_integrability_error 0.01" : "", worst, first_tau, w / FOUR_PI);
        if (bounded) {
            CHECK_LE(worst, 0.01);
            CHECK(first_tau < 0.5);
        } else {
            CHECK(worst > 0.01); /* measured 0.0138 in the first step */
            CHECK_NEAR(first_tau, 0.5, 0, 0);
        }
        cf_flow_destroy(&flow);
    }
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_elk(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "elk_g1_2k.obj", 0)) return;
    cf_context *ctx = shared.ctx;
    cf_mesh *mesh = shared.mesh;
    if (mesh) {
        /* 10 default steps with and without the corrections */
        spin_run with = {0}, without = {0};
        cf_flow_options o;
        CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
        spin_run_steps(ctx, mesh, &o, 10, &with, NULL);
        ((cf_spin_willmore_options *)cf_flow_options_method(&o))->period_iterations = 0;
        spin_run_steps(ctx, mesh, &o, 10, &without, NULL);
        fprintf(stderr,
                "   elk_g1_2k, 10 default steps: W/4pi %.4f -> %.4f (mean Q %.3f) with the corrections, %.4f (mean Q "
                "%.3f) without\n",
                with.w0, with.w, with.mean_q, without.w, without.mean_q);
        CHECK_LE(with.w, 0.5 * with.w0);     /* measured 5.76 of 22.8 */
        CHECK(without.w > 0.5 * with.w0);    /* 11.50: what the corrections change */
        CHECK_LE(with.worst_rise, 0.0);
        CHECK(with.defects == 0);
    }
    cft_shared_case_close(&shared);
}

int main(void)
{
    CFT_RUN(test_double_torus);
    CFT_RUN(test_first_order_lambda);
    CFT_RUN(test_bumped_torus);
    CFT_RUN(test_integrability_bound);
    CFT_RUN(test_elk);
    return cft_finish();
}
