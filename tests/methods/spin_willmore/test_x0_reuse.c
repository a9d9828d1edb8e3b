/*
 * Reusing the factorisation of X(0) for the exactness directions (option
 * exactness_refresh; exactness.c, docs/spin.md "Reusing X(0)"): on closed
 * surfaces of genus > 0 a step takes its exactness directions from the
 * factor of an earlier step while the steps since it changed the log
 * conformal scale by at most exactness_refresh in sum (default 0.1) and
 * the last periods before corrections were below period_tolerance / 2. An
 * attempt on such directions whose periods exceed period_tolerance, or that
 * is rejected, is made again with a new factor ("renewed").
 *
 * - A reused step also keeps the factorising step's X(0)^-1 B_g: it solves
 *   with X(0) not at all (x0_solve_columns 0), a factorising step once per
 *   harmonic form.
 * - bob_5k (shared; skips without it), 10 default steps against
 *   exactness_refresh = 0 (a new factorisation every step): X(0) is reused
 *   in steps 4-10, none renewed, every step's periods below
 *   period_tolerance without corrections, W never rises and ends within
 *   0.01 % of the run without reuse (1.84928 vs 1.84938).
 * - elephant_g3_3k (shared; it moves 0.03-0.9 per step), fairing off as
 *   everywhere here: with the default bound W ends as low as without reuse
 *   (measured 7.3671 vs 7.3718). With no effective bound (1) the
 *   invariants hold, but W ends at 8.4184 (X(0) reused in 5 steps; the
 *   runs part at step 4, the first reused one). Before the
 *   first-order lambda of the period corrections both ended near 8.2
 *   (8.2029 loose, 8.2243 without reuse) and this test checked the loose
 *   bound; the default bound is what it checks now.
 * - Bumped torus (generated), moving 0.04-0.06 per step: reuse is tried every
 *   other step; before the renewal those steps left periods of up to 1.1e-2
 *   (7e-4 with a new factor). Now attempts above period_tolerance are
 *   renewed (measured: 3 attempts of the default run), so every step's
 *   periods stay below it, and W stays within 1 % of the run without reuse.
 * - cf_flow_set_positions drops the old factor: the next step makes a new one.
 */
#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/spin_willmore.h"
#include "methods/spin_willmore/spin_internal.h"
#include "spin_test_util.h"
#include "test.h"

#include <math.h>
#include <stdio.h>

#define FOUR_PI (4.0 * 3.14159265358979323846)
#define STEPS 10
#define PERIOD_TOLERANCE 3e-3 /* the default */

typedef struct {
    int reused[STEPS], renewed[STEPS], solve_columns[STEPS];
    double scale_change[STEPS], period_first[STEPS], period_after[STEPS], w[STEPS + 1];
    int steps;
} reuse_run;

/* STEPS default steps (exactness_refresh = refresh) from x; the per-step
 * diagnostics. */
static void run(cf_context *ctx, const cf_mesh *mesh, const double *x, double refresh, reuse_run *r)
{
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    ((cf_spin_willmore_options *)cf_flow_options_method(&o))->exactness_refresh = refresh;
    /* without the vertex-scale fairing: whether its candidate is kept
     * branches on W, so the reused and the fresh factor, which differ by
     * the reuse's small error, can take different branches (bob: 2e-4 in
     * W/4pi after 10 steps with it); the reuse is what is compared here */
    ((cf_spin_willmore_options *)cf_flow_options_method(&o))->fairing = 0.0;
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, x, &o, &flow));
    if (!flow) return;
    r->w[0] = cf_flow_energy(flow) / FOUR_PI;
    for (r->steps = 0; r->steps < STEPS; ++r->steps) {
        if (cf_flow_converged(flow)) break;
        cf_status st = cf_flow_step(flow, NULL);
        CHECK_OK(ctx, st);
        if (st != CF_OK) break;
        cfi_spin_diagnostics d;
        CHECK_OK(ctx, cfi_spin_willmore_diagnostics(flow, &d));
        r->reused[r->steps] = d.x0_reused;
        r->renewed[r->steps] = d.x0_renewed;
        r->solve_columns[r->steps] = d.x0_solve_columns;
        r->scale_change[r->steps] = d.scale_change;
        r->period_first[r->steps] = d.period_error_first;
        r->period_after[r->steps] = d.period_error;
        r->w[r->steps + 1] = cf_flow_energy(flow) / FOUR_PI;
    }
    cf_flow_destroy(&flow);
}

static int count(const int *v, int n)
{
    int c = 0;
    for (int k = 0; k < n; ++k) c += v[k] != 0;
    return c;
}

/* The invariants of a run with bound `refresh` against one without reuse:
 * the rule (a reused step follows steps that moved at most `refresh` since
 * the factorisation, and a step whose periods before corrections were below
 * half the tolerance), periods below the tolerance after every step, W
 * never rising. Returns the number of reused steps. */
static int check_against_refresh(const char *name, double refresh, const reuse_run *a, const reuse_run *fresh)
{
    double scale_since = 0.0;
    for (int k = 0; k < a->steps; ++k) {
        if (a->reused[k]) {
            CHECK(k > 0 && !a->renewed[k]);
            CHECK_LE(scale_since, refresh);
            CHECK_LE(a->period_first[k - 1], 0.5 * PERIOD_TOLERANCE);
            CHECK(a->solve_columns[k] == 0); /* X(0)^-1 B_g of the factorising step */
        } else {
            CHECK(a->solve_columns[k] > 0);
            scale_since = 0.0;
        }
        scale_since += a->scale_change[k];
        CHECK_LE(a->period_after[k], PERIOD_TOLERANCE);
        CHECK_LE(a->w[k + 1], a->w[k] * (1.0 + 1e-12));
    }
    CHECK(count(fresh->reused, fresh->steps) == 0 && count(fresh->renewed, fresh->steps) == 0);
    CHECK(a->steps == fresh->steps);
    int reused = count(a->reused, a->steps);
    fprintf(stderr,
            "   %s, exactness_refresh %g: X(0) reused in %d of %d steps, renewed in %d; W/4pi %.5f -> %.5f (%.5f "
            "refactorising every step)\n",
            name, refresh, reused, a->steps, count(a->renewed, a->steps), a->w[0], a->w[a->steps],
            fresh->w[fresh->steps]);
    return reused;
}

static void test_bumped_torus(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    double *x = bumped_torus_fixture(ctx, &mesh);
    if (x) {
        reuse_run dflt = {0}, loose = {0}, fresh = {0};
        run(ctx, mesh, x, 0.1, &dflt);
        run(ctx, mesh, x, 1.0, &loose);
        run(ctx, mesh, x, 0.0, &fresh);
        CHECK(check_against_refresh("bumped torus", 0.1, &dflt, &fresh) >= 2);
        CHECK(check_against_refresh("bumped torus", 1.0, &loose, &fresh) >= 2);
        CHECK(count(dflt.renewed, dflt.steps) >= 1); /* the renewal acts here (3 attempts) */
        CHECK_NEAR(dflt.w[dflt.steps], fresh.w[fresh.steps], 0.01, 0);
    }
    free(x);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* The runs with bound `refresh` and without reuse on a shared mesh; 0 when
 * it is missing (the test skips) or fails to load. */
static int shared_runs(const char *file, double refresh, reuse_run *a, reuse_run *fresh)
{
    const char *path = cft_optional_shared_mesh(file);
    if (!path) return 0;
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, path, &mesh));
    if (mesh) {
        run(ctx, mesh, NULL, refresh, a);
        run(ctx, mesh, NULL, 0.0, fresh);
    }
    int ok = mesh != NULL;
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
    return ok;
}

static void test_bob(void)
{
    reuse_run a = {0}, fresh = {0};
    if (!shared_runs("bob_5k.obj", 0.1, &a, &fresh)) return;
    CHECK(check_against_refresh("bob_5k", 0.1, &a, &fresh) >= 6); /* measured 7: steps 4-10 */
    CHECK(count(a.renewed, a.steps) == 0);
    CHECK_NEAR(a.w[a.steps], fresh.w[fresh.steps], 1e-4, 0);
}

static void test_elephant(void)
{
    reuse_run a = {0}, loose = {0}, fresh = {0};
    if (!shared_runs("elephant_g3_3k.obj", 0.1, &a, &fresh)) return;
    CHECK(check_against_refresh("elephant_g3_3k", 0.1, &a, &fresh) >= 1);
    CHECK(a.steps == STEPS);
    CHECK_LE(a.w[a.steps], fresh.w[fresh.steps] * (1.0 + 1e-3)); /* 7.3671 vs 7.3718 */
    /* no effective bound: the invariants hold, W ends higher (measured 8.4184) */
    if (!shared_runs("elephant_g3_3k.obj", 1.0, &loose, &fresh)) return;
    check_against_refresh("elephant_g3_3k", 1.0, &loose, &fresh);
    CHECK(loose.steps == STEPS);
}

static void test_set_positions_drops_factor(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    double *x = bumped_torus_fixture(ctx, &mesh);
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    cf_flow *flow = NULL;
    if (x) CHECK_OK(ctx, cf_flow_create(ctx, mesh, x, &o, &flow));
    if (flow) {
        cfi_spin_diagnostics d;
        int reused = 0;
        for (int k = 0; k < STEPS && !reused; ++k) {
            CHECK_OK(ctx, cf_flow_step(flow, NULL));
            CHECK_OK(ctx, cfi_spin_willmore_diagnostics(flow, &d));
            reused = d.x0_reused;
        }
        CHECK(reused); /* the state before set_positions would allow it */
        CHECK_OK(ctx, cf_flow_set_positions(flow, x));
        CHECK_OK(ctx, cf_flow_step(flow, NULL));
        CHECK_OK(ctx, cfi_spin_willmore_diagnostics(flow, &d));
        CHECK(d.x0_reused == 0);
        cf_flow_destroy(&flow);
    }
    free(x);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_bumped_torus);
    CFT_RUN(test_bob);
    CFT_RUN(test_elephant);
    CFT_RUN(test_set_positions_drops_factor);
    return cft_finish();
}
