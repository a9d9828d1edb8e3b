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
     * drifts and total_seconds. A method with policy.backtrack takes its
     * time step from cfi_flow_time_step(flow); when the policy rejects the
     * step, the layer restores the positions, calls reset and calls step
     * again with a smaller one. NULL when the method has begin_step and
     * attempt instead. */
    cf_status (*step)(cf_flow *flow, cf_flow_info *info);
    /* Optional, instead of step, for a method that redoes only a part of a
     * step when the policy rejects it (spin-willmore redoes IV-VI from the
     * same rhodot). begin_step: the part every attempt shares, from the
     * state at the start of the step (the layer has saved the positions).
     * attempt: the rest for `time_step` (the policy's current step, at most
     * the full step), updating flow->positions and filling info->energy;
     * it may reject its own result through *verdict (rejected, with the
     * factor the next step is cut by at least). end_step (optional): the
     * method's own checks and report of the accepted attempt, or at a stall
     * of the state before the step (info->time_step is then the last step
     * tried; the layer reports 0). The three share one info, which the
     * layer clears before begin_step only: timings add up over attempts.
     * None may allocate. */
    cf_status (*begin_step)(cf_flow *flow, cf_flow_info *info);
    cf_status (*attempt)(cf_flow *flow, double time_step, cf_flow_info *info, cfi_step_verdict *verdict);
    cf_status (*end_step)(cf_flow *flow, cf_flow_info *info);
    /* Called after cf_flow_set_positions or a failed step restored the
     * positions, so the method can resynchronise cached state and
     * recompute flow->info.energy for the current positions (may be NULL). */
    cf_status (*reset)(cf_flow *flow);
    /* Optional: after a rejected attempt the layer has put back the
     * positions of the step's start; resynchronise what the attempt changed
     * (NULL: reset). Unlike reset, the flow goes on with the same step. */
    cf_status (*revert)(cf_flow *flow);
    /* Optional, with attempt: at a stall (no attempt down to the policy's
     * limit accepted), the method may switch the rest of this step to
     * another variant of its attempt and set *switched; the layer then
     * restarts the step's halvings from *restart_step, and at that
     * variant's stall asks again (at most 4 variants per step; the method
     * says when it has none left by not switching)
     * (set to the full step before the call; the method may lower it, e.g.
     * to where the variant's last step was accepted). The method goes back
     * to its first variant in begin_step. The layer has put back the step's
     * start (revert) before the call. May allocate, on its first use only
     * (state it keeps for the flow's life). */
    cf_status (*fallback)(cf_flow *flow, int32_t *switched, double *restart_step);
    void (*destroy)(cf_flow *flow);
    /* Which checks of the shared step policy apply (methods/step_policy.h);
     * left out (all zero): none, the method accepts its own steps. */
    cfi_step_policy_desc policy;
    /* 1: on a mesh of several connected components the layer runs one flow
     * of this method per component, each with its own step policy, and
     * the flow of the whole mesh gathers them (flow_parts.c): for a method
     * whose step couples what the mesh does not (spin-willmore's
     * eigenvector and its whole-surface constraints). */
    int32_t per_component;
} cfi_flow_method;

/* One flow per connected component (flow_parts.c). */
typedef struct cfi_flow_parts cfi_flow_parts;

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
    int64_t attempts;           /* attempts made since create (tests, benchmarks) */
    cfi_flow_parts *parts;      /* per_component methods on several components: the flows doing the work */
};

/* The step policy's time step for the current attempt: the full step
 * given to cfi_flow_set_time_step, or a smaller one after rejected steps
 * (methods with policy.backtrack take their step from here). */
static inline double cfi_flow_time_step(const cf_flow *flow) { return flow->policy.step; }

/* 1 when this flow's rejected steps are redone with a smaller step. */
static inline int cfi_flow_backtracks(const cf_flow *flow) { return flow->policy.backtrack; }

/* Called by a backtracking method's create: its full time step (>= 0, in
 * its own units, e.g. the scale-free time_step times the area); the policy
 * starts from it and never grows the step above it. */
void cfi_flow_set_time_step(cf_flow *flow, double full_step);

/* Called by a method's create to turn the policy's rise check or its
 * backtracking off for this flow (1 keeps what the options and the
 * method's descriptor give, 0 turns it off; nothing is turned on), e.g.
 * spin-willmore without `adaptive`, or with boundaries that may raise W. */
void cfi_flow_policy_restrict(cf_flow *flow, int keep_rise_check, int keep_backtrack);

/* Called by a method's create to turn the blow-up or divergence check off
 * for this flow (1 keeps what the options and the descriptor give, 0 turns
 * it off), e.g. spin-willmore's divergence check with prescribed or cmc
 * boundaries, which may raise W by design. */
void cfi_flow_policy_restrict_checks(cf_flow *flow, int keep_blowup, int keep_divergence);

/* Area and volume of flow->positions into *info, with their drifts
 * against the flow's start. */
cf_status cfi_flow_measure(cf_flow *flow, cf_flow_info *info);

/* An accepted step's bookkeeping: iteration, time and the seconds since t0
 * into *step, which becomes flow->info (and *info when not NULL); then the
 * progress callback (CF_ERR_CANCELLED when it cancels). */
cf_status cfi_flow_accept_step(cf_flow *flow, cf_flow_info *step, cf_flow_info *info, double t0);

/* flow_parts.c: the flow of a per_component method on a mesh of several
 * components. create_parts builds one flow per component from
 * flow->positions and flow->options (vertex and face arrays sliced) and
 * fills flow->info; step_parts steps every component that has not
 * converged; set_positions_parts gives each its part of positions (all or
 * none); destroy_parts frees them. */
cf_status cfi_flow_create_parts(cf_flow *flow);
cf_status cfi_flow_step_parts(cf_flow *flow, cf_flow_info *info);
cf_status cfi_flow_set_positions_parts(cf_flow *flow, const double *positions);
void cfi_flow_destroy_parts(cf_flow *flow);

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
