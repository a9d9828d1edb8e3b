/*
 * A stall of the default flow (every retry of a step raises W) is retried
 * with the positions recovered in the current metric before the run stops
 * (step_policy.c, cfi_spin_stall_retry; docs/spin.md, "Robustness").
 *
 * With the input metric alone, triceratops_needles_3k stopped at W/4pi
 * 35.35 after 5 steps (issue 13's target W0/2 = 18.73) and cow_3k at 24.106
 * in step 10; with the retry they reach 8.44 and 23.83 (mean Q 1.445 and
 * 1.329), W still non-increasing at every step and the results passing the
 * mesh check. Skips without ../shared.
 */
#include "test.h"

#include "curvflow/flow.h"
#include "curvflow/io.h"
#include "curvflow/mesh.h"
#include "curvflow/metrics.h"

#include <math.h>
#include <stdlib.h>

#define PI 3.14159265358979323846

/* 10 default steps of spin-willmore on a shared mesh: W/4pi before and
 * after, the largest rise of W/4pi over one step (<= 0 when monotone), the
 * area-weighted mean quasi-conformal error against the input and the mesh check's
 * count of bad faces and coordinates. 0 when the flow could not be made. */
typedef struct run_result {
    double w0, w10, worst_rise, mean_q;
    int32_t defects;
} run_result;

static int run_default(const char *name, run_result *r)
{
    const char *path = cft_require_shared_mesh(name); /* exit 77 with a SKIP line when absent */
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, path, &mesh));
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    cf_flow *flow = NULL;
    if (mesh) CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    int ran = flow != NULL;
    if (flow) {
        r->w0 = cf_flow_energy(flow) / (4.0 * PI);
        double before = r->w0;
        r->worst_rise = -INFINITY;
        for (int step = 0; step < 10 && !cf_flow_converged(flow); ++step) {
            CHECK_OK(ctx, cf_flow_step(flow, NULL));
            double w = cf_flow_energy(flow) / (4.0 * PI);
            if (w - before > r->worst_rise) r->worst_rise = w - before;
            before = w;
        }
        r->w10 = before;
        cf_stats q = {0};
        CHECK_OK(ctx, cf_quasi_conformal_error(ctx, mesh, cf_mesh_positions(mesh), cf_flow_positions(flow), NULL, &q));
        r->mean_q = q.weighted_mean; /* by the input's face areas, as issue 13 states it */
        cf_mesh_report report;
        CHECK_OK(ctx, cf_mesh_check_positions(ctx, mesh, cf_flow_positions(flow), &report));
        r->defects = report.nonfinite_coordinates + report.degenerate_faces;
        fprintf(stderr, "   %s: W/4pi %.4f -> %.4f, largest rise %.3g, mean Q %.4f, %d defects\n", name, r->w0, r->w10,
                r->worst_rise, r->mean_q, r->defects);
    }
    cf_flow_destroy(&flow);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
    return ran;
}

static void test_triceratops_reaches_target(void)
{
    run_result r = {0};
    if (!run_default("triceratops_needles_3k.obj", &r)) return;
    CHECK_LE(r.w10, 0.5 * r.w0);  /* measured 8.44 of 37.46; 35.35 (stalled) without the retry */
    CHECK_LE(r.worst_rise, 0.0);
    CHECK_LE(r.mean_q, 1.5);      /* measured 1.445 */
    CHECK(r.defects == 0);
}

static void test_cow_goes_on(void)
{
    run_result r = {0};
    if (!run_default("cow_3k.obj", &r)) return;
    CHECK_LE(r.w10, 23.95);       /* measured 23.832; 24.106 (stalled in step 10) without the retry */
    CHECK_LE(r.worst_rise, 0.0);
    CHECK(r.defects == 0);
}

int main(void)
{
    CFT_RUN(test_triceratops_reaches_target);
    CFT_RUN(test_cow_goes_on);
    return cft_finish();
}
