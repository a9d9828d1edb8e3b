/*
 * The step policy shared by every flow method (issue 12 item 4): whether a
 * step is accepted, retried with a smaller time step, or failed, and when a
 * run has converged. The common options (cf_step_policy, include/curvflow/
 * flow.h) are set by the user; each method says in its vtable
 * (cfi_flow_method.policy) which of the checks apply to it.
 *
 * Every energy comparison has a relative tolerance and an absolute floor:
 *   "b exceeds a" means b > a + rel |a| + floor unit,
 * so rounding at an equilibrium (a round sphere, a flat sheet whose W is 0
 * and becomes 6.7e-29) is no rise, and a start at energy 0 does not make
 * every later rounding error a divergence (issue 15 M1).
 */
#ifndef CF_METHODS_STEP_POLICY_H
#define CF_METHODS_STEP_POLICY_H

#include "curvflow/flow.h"

#include <stdint.h>

/* What the absolute floor (cf_step_policy.energy_floor) is measured in:
 * the method's energy is scale-free (bi-Laplacian energy; W, whose natural
 * unit 4 pi is the W of a round sphere), or it scales with the surface
 * (area: the floor is a fraction of the starting area). */
typedef enum cfi_energy_unit {
    CFI_ENERGY_UNIT_ONE = 0,
    CFI_ENERGY_UNIT_4PI = 1,
    CFI_ENERGY_UNIT_INITIAL_AREA = 2
} cfi_energy_unit;

/* A method's part of the policy (a field of cfi_flow_method). All zero (the
 * default of a designated initialiser) opts out of every shared check: a
 * method whose energy is not expected to decrease at every step. */
typedef struct cfi_step_policy_desc {
    /* 1: the energy should not rise in a step (a gradient flow): a step
     * that raises it beyond the tolerance and floor is rejected. */
    int32_t rise_check;
    /* 1: the method takes its time step from cfi_flow_time_step(flow)
     * (having given its full step to cfi_flow_set_time_step in create), so
     * a rejected step can be redone with a smaller step and the step grown
     * back afterwards. 0 (e.g. explicit flows, whose stability the user
     * chose with time_step): a rejected step fails. */
    int32_t backtrack;
    /* 1 (without backtrack): a rejected rise ends the run as converged,
     * keeping the state before it, instead of failing (a method without a
     * time step to reduce, whose iteration has stopped lowering its
     * energy: stretch-bend-edit). */
    int32_t rise_stops;
    /* 1: the flow layer decides convergence from the method's parameter
     * named tolerance_param (NULL: "tolerance"): |E - E_prev| <
     * tolerance E_prev, or E = 0; 0: the method sets flow->converged
     * itself. */
    int32_t convergence;
    const char *tolerance_param;
    cfi_energy_unit unit;
    /* What the message of a failed rise adds, e.g. "the time step is above
     * the stability limit; a smaller time_step helps" (NULL: a generic hint). */
    const char *rise_hint;
    /* 1: any rise of the energy, however small, is rejected (no
     * rise_tolerance or energy_floor): a method whose claim is that its
     * energy never rises under backtracking (spin-willmore's W). */
    int32_t rise_exact;
    /* 1: max_halvings counts the retries of one step, so the step may go
     * lower over several steps (spin-willmore); 0: the step never goes
     * below the full step / 2^max_halvings (a run near its minimum does not
     * creep on with ever smaller steps). */
    int32_t halvings_per_step;
    /* What a stall (no step down to the smallest allowed is accepted) looks
     * like. 1: an accepted step of time step 0 at the state before it (the
     * iteration advances, an INFO notice "<method>: <energy_name> does not
     * decrease for any time step down to ..."): spin-willmore. 0: the
     * iteration does not advance and a WARNING says why the run stops. */
    int32_t stall_as_step;
    /* 1: the option halving_search applies (halvings_per_step needed): a
     * round of halvings whose rises look persistent tries its smallest
     * step first and bisects (flow.c, halving_search). */
    int32_t halving_search;
    const char *energy_name; /* in the stall and divergence messages (NULL: "the energy") */
    /* 1: the blow-up check applies (the common option blowup_factor): an
     * accepted step whose energy exceeds blowup_factor times the energy
     * before it, plus the floor, is a numerical failure; blowup_default is
     * the option's default for this method (0: off unless set). 0 opts
     * out: the option has no effect (a method without a time step whose
     * rise already ends the run: stretch-bend-edit). */
    int32_t blowup_check;
    double blowup_default;
    /* 1: the divergence check applies (divergence_factor): an accepted
     * step that leaves the energy above divergence_factor times the
     * starting energy (of create or cf_flow_set_positions), with
     * divergence_tolerance and the floor, is a numerical failure;
     * divergence_default as above. */
    int32_t divergence_check;
    double divergence_default;
    /* What the divergence message "... the flow diverges (time_step T<cause>);
     * try a smaller time_step<, hint>" says (NULL: nothing), e.g. cause " is
     * above this mesh's stability limit" (an explicit step), hint
     * "adaptive=1 or a larger regularization (docs/spin.md)". */
    const char *divergence_cause;
    const char *divergence_hint;
} cfi_step_policy_desc;

/* How an attempt (cfi_flow_method.attempt) judges its own result, besides
 * the policy's tests: rejected 1 redoes the step from its start with a step
 * of at most min(0.5, shrink) times this one (shrink NaN or >= 0.5: half),
 * e.g. spin-willmore's cut for a scale change above max_scale_change.
 * hold_step 1 on an accepted attempt keeps a reduced step where it is
 * instead of growing it back by step_growth (a trust region that expands
 * only when the step did what the method's model of it predicted, e.g.
 * spin-willmore's growth_ratio). */
typedef struct cfi_step_verdict {
    int32_t rejected;
    double shrink;
    int32_t hold_step;
} cfi_step_verdict;

/* The policy's state inside a flow (cf_flow.policy). */
typedef struct cfi_step_policy_state {
    cf_step_policy opt;     /* copy of the common options */
    double full_step;       /* the method's time step (cfi_flow_set_time_step; 1 if not given) */
    double step;            /* (0, full_step]: the time step of the next attempt */
    double unit;            /* value of the floor's unit for this flow (> 0) */
    double tolerance;       /* convergence tolerance (desc.convergence), 0: never */
    int32_t rise_check;     /* this flow's: desc.rise_check and energy_check (cfi_flow_policy_restrict) */
    int32_t backtrack;      /* this flow's: desc.backtrack, backtrack and energy_check (ditto) */
    double blowup_factor;   /* this flow's: opt.blowup_factor if desc.blowup_check, else 0 (off) */
    double divergence_factor; /* this flow's: opt.divergence_factor if desc.divergence_check (and
                               * cfi_flow_policy_restrict_checks), else 0 (off) */
    double initial_energy;  /* energy at create / cf_flow_set_positions (divergence check) */
} cfi_step_policy_state;

/* Upper end of the byte range of cf_flow_options.storage a method's options
 * may use; the common options follow it. */
#define CFI_STEP_POLICY_OFFSET (CF_FLOW_OPTIONS_STORAGE - CF_STEP_POLICY_STORAGE)

/* Defaults of the common options; blowup_factor and divergence_factor 0
 * (off), which a method's descriptor overrides through
 * cfi_step_policy_default_for. */
void cfi_step_policy_default(cf_step_policy *policy);

/* Defaults of the common options for a method: cfi_step_policy_default
 * with the descriptor's blowup_default / divergence_default (only where
 * the check applies; else 0). */
void cfi_step_policy_default_for(cf_step_policy *policy, const cfi_step_policy_desc *desc);

/* The parameter table of the common options (offsets into
 * cf_flow_options.storage, like a method's table, so that the same set /
 * format code serves both), and the entry named `name` (NULL if none). */
const cf_param_desc *cfi_step_policy_params(int32_t *count);
const cf_param_desc *cfi_step_policy_find_param(const char *name);

/* Checks the common options (ranges are those of the table; also for
 * fields set directly). CF_OK or CF_ERR_INVALID_ARG with a message naming
 * the parameter. */
cf_status cfi_step_policy_validate(cf_context *ctx, const cf_step_policy *policy);

/* 1 when `after` exceeds `before` by more than rel |before| + floor (see
 * the top of this file); NaN exceeds everything. */
int cfi_step_policy_exceeds(double after, double before, double rel, double floor);

/* 1 when a step from energy `before` to `after` is a rise the policy
 * rejects (rise_tolerance, energy_floor in the flow's unit). */
int cfi_step_policy_rose(const cfi_step_policy_state *p, double before, double after);

/* 1 when `energy` is above factor times the starting energy by more than
 * divergence_tolerance and the floor: the divergence test (the flow's
 * divergence_factor; cf_flow_step). factor 0: never. */
int cfi_step_policy_diverged(const cfi_step_policy_state *p, double energy, double initial, double factor);

/* 1 when a step from energy `before` > 0 to `after` is a blow-up: after >
 * factor before + the floor (the flow's blowup_factor; no relative slack,
 * the factor is one). factor 0 or before <= 0: never; NaN after: always. */
int cfi_step_policy_blew_up(const cfi_step_policy_state *p, double before, double after, double factor);

/* 1 when a step from `before` to `after` changed the energy by less than
 * the tolerance (relative to before > 0), or reached energy 0: the run has
 * converged. tolerance 0: never. */
int cfi_step_policy_converged(double before, double after, double tolerance);

#endif /* CF_METHODS_STEP_POLICY_H */
