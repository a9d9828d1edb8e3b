/*
 * How a method plugs into the common flow interface (include/curvflow/flow.h).
 * Each method folder defines one `const cfi_flow_method cfi_<method>_method`
 * and src/methods/flow.c lists it in its registry.
 *
 * The common layer (flow.c) owns the position buffer and does everything
 * that is the same for all methods: copying options, checking every step
 * for non-finite values and restoring the last good state on failure,
 * area/volume drift, timing, progress callback, iteration count.
 */
#ifndef CF_METHODS_FLOW_INTERNAL_H
#define CF_METHODS_FLOW_INTERNAL_H

#include "core/core.h"
#include "curvflow/flow.h"
#include "mesh/mesh_internal.h"
#include "methods/step_policy.h"

typedef struct cfi_flow_method {
    cf_flow_kind kind;
    const char *name;          /* "implicit-mcf" */
    const char *description;   /* one line */
    size_t options_size;       /* must be <= CF_FLOW_OPTIONS_STORAGE */
    void (*options_default)(void *options);
    const cf_param_desc *params;
    int32_t param_count;
    /* Allocates the method state (preallocating everything the steps need)
     * into flow->impl, from flow->mesh, flow->positions and options. Fills
     * flow->info with the initial energy (iteration 0). On failure it
     * records the message; the common layer then calls destroy, which must
     * accept a partially built (or NULL) flow->impl. */
    cf_status (*create)(cf_flow *flow, const void *options);
    /* One step: updates flow->positions in place and fills the method's
     * parts of *info (time_step, energy, terms, residuals, assemble/
     * factorize/solve seconds). The common layer has saved the previous
     * positions and restores them if this returns an error. Must not
     * allocate. The common layer fills iteration, time, area, volume,
     * drifts and total_seconds. */
    cf_status (*step)(cf_flow *flow, cf_flow_info *info);
    /* Called after cf_flow_set_positions or a failed step restored the
     * positions, so the method can resynchronise cached state and
     * recompute flow->info.energy for the current positions (may be NULL). */
    cf_status (*reset)(cf_flow *flow);
    void (*destroy)(cf_flow *flow);
    /* Which checks of the shared step policy apply (methods/step_policy.h);
     * left out (all zero): none, the method accepts its own steps. */
    cfi_step_policy_desc policy;
} cfi_flow_method;

struct cf_flow {
    cf_context *ctx;
    const cf_mesh *mesh;
    const cfi_flow_method *method;
    cf_flow_options options;    /* copy */
    void *impl;                 /* method state */
    double *positions;          /* 3 nv, current state */
    double *saved_positions;    /* 3 nv, state before the current step */
    cf_flow_info info;          /* last step's info */
    double initial_area;
    double initial_volume;
    int32_t converged;          /* set by the method */
    cf_progress_fn progress;
    void *progress_user;
    cfi_step_policy_state policy; /* the shared step policy (cf_flow_step) */
};

/* Factor (0, 1] on the method's time step chosen by the step policy
 * (backtracking); methods with policy.backtrack multiply their step by it. */
static inline double cfi_flow_step_scale(const cf_flow *flow) { return flow->policy.step_scale; }



/* The registry entry of a kind, NULL if out of range. */
const cfi_flow_method *cfi_flow_method_of(cf_flow_kind kind);

/* The registry (src/methods/flow.c) lists one method per kind. */
extern const cfi_flow_method cfi_explicit_mcf_method;
extern const cfi_flow_method cfi_implicit_mcf_method;
extern const cfi_flow_method cfi_conformal_mcf_method;
extern const cfi_flow_method cfi_explicit_bilaplacian_method;
extern const cfi_flow_method cfi_implicit_bilaplacian_method;
extern const cfi_flow_method cfi_spin_willmore_method;
extern const cfi_flow_method cfi_stretch_bend_edit_method;
#endif /* CF_METHODS_FLOW_INTERNAL_H */
