/*
 * cf_flow_create_at: a flow created on the mesh (its reference) and started
 * from other positions with the same connectivity (`curvflow flow --start`,
 * `curvflow edit --start`). Only the public flow interface: creating on the
 * mesh and then replacing the state is what makes the reference the mesh's
 * for every method, without a per-method notion of "reference positions".
 */
#include "core/core.h"
#include "curvflow/flow.h"

cf_status cf_flow_create_at(cf_context *ctx, const cf_mesh *mesh, const double *start,
                            const cf_flow_options *options, cf_flow **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "cf_flow_create_at: output is NULL");
    *out = NULL;
    cf_flow *flow = NULL;
    cf_status st = cf_flow_create(ctx, mesh, NULL, options, &flow);
    if (st != CF_OK || !start) {
        *out = flow;
        return st;
    }
    st = cf_flow_set_positions(flow, start);
    if (st != CF_OK) {
        cfi_error_prefix(ctx, "start");
        cf_flow_destroy(&flow);
        return st;
    }
    *out = flow;
    return CF_OK;
}
