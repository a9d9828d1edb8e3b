/* Placeholder registration of the spin-Willmore flow until it lands. */
#include "methods/flow_internal.h"

static void spin_willmore_options_default(void *options) { (void)options; }
static cf_status spin_willmore_create(cf_flow *flow, const void *options)
{
    (void)options;
    return cfi_error(flow->ctx, CF_ERR_UNSUPPORTED, "spin-willmore: not implemented yet");
}
static cf_status spin_willmore_step(cf_flow *flow, cf_flow_info *info)
{
    (void)info;
    return cfi_error(flow->ctx, CF_ERR_UNSUPPORTED, "spin-willmore: not implemented yet");
}
static void spin_willmore_destroy(cf_flow *flow) { (void)flow; }

const cfi_flow_method cfi_spin_willmore_method = {
    CF_FLOW_SPIN_WILLMORE, "spin-willmore",
    "conformal Willmore flow in curvature space (Crane, Pinkall, Schroeder 2013)",
    8, spin_willmore_options_default, NULL, 0,
    spin_willmore_create, spin_willmore_step, NULL, spin_willmore_destroy,
};
