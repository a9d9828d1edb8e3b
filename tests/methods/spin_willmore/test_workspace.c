/* The spin-willmore flow's workspace (workspace.c): every array of the flow
 * is recorded and freed by one call, so a create that fails at any
 * allocation leaves nothing behind, whatever subset of the state it built.
 * Sweeps cf_flow_create + two steps + destroy with the k-th allocation
 * failing, for every k, in each configuration that allocates differently:
 * closed genus 1 (exactness, linearised and App. C's Z_i), fixed, prescribed
 * and free boundaries, the spectral filter (k = 0 and 2), Moebius, fixed
 * tau. Create alone and create + two steps make the same number of
 * allocations: steps allocate nothing (the solve workspaces are reserved at
 * create, cf_cholesky_reserve_solve), but for two objects made on first
 * need, which these flows never reach: the current-metric solver at a first
 * stall, and the tangential relaxation's arrays when a map first passes
 * its threshold (swept in test `relaxation`). */
#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "spin_test_util.h"
#include "test.h"

#include <stdio.h>
#include <string.h>

typedef struct sweep_case {
    const char *name;
    const cf_mesh *mesh;
    const char *const *settings; /* name, value, ..., NULL */
} sweep_case;

static cf_status make_flow(cf_context *ctx, const sweep_case *sc, cf_flow **flow)
{
    cf_flow_options o;
    cf_status st = cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o);
    for (const char *const *s = sc->settings; st == CF_OK && s && s[0]; s += 2) st = cf_flow_options_set(ctx, &o, s[0], s[1]);
    if (st == CF_OK) st = cf_flow_create(ctx, sc->mesh, NULL, &o, flow);
    return st;
}

static cf_status create_destroy(cf_context *ctx, void *user)
{
    cf_flow *flow = NULL;
    cf_status st = make_flow(ctx, user, &flow);
    if (st == CF_OK && !flow) st = CF_ERR_NUMERICAL;
    cf_flow_destroy(&flow);
    return st;
}

static cf_status create_step_destroy(cf_context *ctx, void *user)
{
    const sweep_case *sc = user;
    return spin_two_steps(ctx, sc->mesh, sc->settings);
}

static void sweep(const char *name, const cf_mesh *mesh, const char *const *settings)
{
    cf_context *ctx = cft_context();
    sweep_case sc = {name, mesh, settings};
    /* start the context's CHOLMOD state first (its one-off allocation is
     * counted at the first use in a context), so both sweeps count alike */
    CHECK_OK(ctx, create_destroy(ctx, &sc));
    int64_t n_create = cft_allocation_sweep(ctx, name, create_destroy, &sc, 1);
    int64_t n_all = cft_allocation_sweep(ctx, name, create_step_destroy, &sc, 1);
    CHECK(n_create > 20);
    CHECK(n_all == n_create); /* the two steps allocated nothing (solve workspaces reserved at create) */
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_sweeps(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *torus = NULL, *cyl = NULL, *sphere = NULL;
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.4, 12, 6, &torus));
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 12, 4, 1.0, 2.0, &cyl));
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 1, 0.2, 3, &sphere));
    static const char *const closed_g1[] = {NULL};
    static const char *const closed_zi[] = {"exactness_linearized", "false", "harmonic_update", "true", NULL};
    static const char *const fixed[] = {"boundary", "fixed", NULL};
    static const char *const prescribed[] = {"boundary", "prescribed", "boundary_angle", "0.2", NULL};
    static const char *const free_holes[] = {"input_metric", "false", NULL};
    static const char *const filter2[] = {"sigma", "0.05", "filter_k", "2", "mobius", "true", NULL};
    static const char *const filter0[] = {"sigma", "0.05", "filter_k", "0", "adaptive", "false", NULL};
    sweep("torus (linearised exactness)", torus, closed_g1);
    sweep("torus (App. C Z_i)", torus, closed_zi);
    sweep("cylinder, boundary fixed", cyl, fixed);
    sweep("cylinder, boundary prescribed", cyl, prescribed);
    sweep("cylinder, free (exactness with holes), current metric", cyl, free_holes);
    sweep("sphere, filter k 2, mobius", sphere, filter2);
    sweep("sphere, filter k 0, fixed tau", sphere, filter0);
    cf_mesh_destroy(&torus);
    cf_mesh_destroy(&cyl);
    cf_mesh_destroy(&sphere);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_sweeps);
    return cft_finish();
}
