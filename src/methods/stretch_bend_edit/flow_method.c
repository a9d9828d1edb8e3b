/* Placeholder registration of the stretch-bend editing method until it lands. */
#include "methods/flow_internal.h"

static void stretch_bend_edit_options_default(void *options) { (void)options; }
static cf_status stretch_bend_edit_create(cf_flow *flow, const void *options)
{
    (void)options;
    return cfi_error(flow->ctx, CF_ERR_UNSUPPORTED, "stretch-bend-edit: not implemented yet");
}
static cf_status stretch_bend_edit_step(cf_flow *flow, cf_flow_info *info)
{
    (void)info;
    return cfi_error(flow->ctx, CF_ERR_UNSUPPORTED, "stretch-bend-edit: not implemented yet");
}
static void stretch_bend_edit_destroy(cf_flow *flow) { (void)flow; }

const cfi_flow_method cfi_stretch_bend_edit_method = {
    CF_FLOW_STRETCH_BEND_EDIT, "stretch-bend-edit",
    "stretching + bending mesh editing by local/global iteration (Zhao & Gortler), and ARAP",
    8, stretch_bend_edit_options_default, NULL, 0,
    stretch_bend_edit_create, stretch_bend_edit_step, NULL, stretch_bend_edit_destroy,
};
