/*
 * The step policy shared by every flow method (src/methods/step_policy.h):
 * the common options, their table, and the energy tests with a relative
 * tolerance and an absolute floor. cf_flow_step (flow.c) applies them.
 */
#include "methods/step_policy.h"

#include "core/core.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

_Static_assert(sizeof(cf_step_policy) <= CF_STEP_POLICY_STORAGE, "cf_step_policy must fit its storage");
_Static_assert(CFI_STEP_POLICY_OFFSET % sizeof(double) == 0, "the policy must be aligned like a double");

void cfi_step_policy_default(cf_step_policy *p)
{
    memset(p, 0, sizeof *p);
    p->energy_check = 1;
    p->backtrack = 1;
    p->max_halvings = 10;
    p->halving_search = 1;
    p->step_growth = 2.0;
    /* the explicit baselines' former slack: above rounding, below any
     * unstable mode's growth per step */
    p->rise_tolerance = 1e-9;
    /* spin-willmore's W at tau 1e-9 on spot_3k creeps up by 7e-8 of itself
     * per step (the realised step is not exact): far below any divergence
     * (elephant_g3_3k: +8 % at step 2), but 1e-9 called it one (issue 15 M1) */
    p->divergence_tolerance = 1e-4;
    p->energy_floor = 1e-12;
    /* blowup_factor, divergence_factor: 0 (off) unless the method's
     * descriptor gives a default (cfi_step_policy_default_for) */
}

void cfi_step_policy_default_for(cf_step_policy *p, const cfi_step_policy_desc *desc)
{
    cfi_step_policy_default(p);
    if (desc->blowup_check) p->blowup_factor = desc->blowup_default;
    if (desc->divergence_check) p->divergence_factor = desc->divergence_default;
}

#define POL(f) (CFI_STEP_POLICY_OFFSET + offsetof(cf_step_policy, f))
static const cf_param_desc policy_params[] = {
    {"energy_check", CF_PARAM_BOOL, POL(energy_check), 0, 1, NULL,
     "step policy: reject a step that raises the energy by more than rise_tolerance (methods that descend their "
     "energy: the baseline flows)"},
    {"backtrack", CF_PARAM_BOOL, POL(backtrack), 0, 1, NULL,
     "step policy: redo a rejected step with half the time step and grow the step back by step_growth after each "
     "accepted one (implicit-mcf, conformal-mcf, implicit-bilaplacian); false: a rejected step fails (exit 3)"},
    {"max_halvings", CF_PARAM_INT, POL(max_halvings), 0, 60, NULL,
     "step policy: the step never goes below time_step / 2^max_halvings; when no step down to that lowers the "
     "energy, the run stops there as converged (the last state that lowered it kept)"},
    {"halving_search", CF_PARAM_BOOL, POL(halving_search), 0, 1, NULL,
     "step policy: once two halvings in a row shrank the rise as a first-order rise shrinks, try the smallest "
     "step the limit allows and bisect: the step plain halving finds wherever acceptance is monotone in the "
     "step, in fewer attempts (spin-willmore); false: plain halving"},
    {"step_growth", CF_PARAM_DOUBLE, POL(step_growth), 1.0, 16.0, NULL,
     "step policy: factor on a reduced time step after an accepted step (up to time_step)"},
    {"rise_tolerance", CF_PARAM_DOUBLE, POL(rise_tolerance), 0.0, 1.0, NULL,
     "step policy: rise of the energy in one step, relative to it, taken as rounding"},
    {"divergence_tolerance", CF_PARAM_DOUBLE, POL(divergence_tolerance), 0.0, 1.0, NULL,
     "step policy: relative slack of the divergence test (divergence_factor) against the starting energy"},
    {"energy_floor", CF_PARAM_DOUBLE, POL(energy_floor), 0.0, 1e6, NULL,
     "step policy: absolute slack of every energy test, in the method's unit (area of the start for area flows, "
     "4pi for W, 1 for the bi-Laplacian energy)"},
    {"blowup_factor", CF_PARAM_DOUBLE, POL(blowup_factor), 0.0, 1e12, NULL,
     "step policy: fail a step whose energy grows more than this factor (0: never; else > 1; spin-willmore and "
     "explicit flows 10, implicit flows 0; stretch-bend-edit: no check)"},
    {"divergence_factor", CF_PARAM_DOUBLE, POL(divergence_factor), 0.0, 1e12, NULL,
     "step policy: fail a step that leaves the energy above this factor times the starting energy (0: never; "
     "else >= 1; spin-willmore 1, not for boundary=prescribed/cmc; baselines 0; stretch-bend-edit: no check)"},
};
#undef POL
#define POLICY_PARAM_COUNT ((int32_t)(sizeof policy_params / sizeof policy_params[0]))

const cf_param_desc *cfi_step_policy_params(int32_t *count)
{
    if (count) *count = POLICY_PARAM_COUNT;
    return policy_params;
}

const cf_param_desc *cfi_step_policy_find_param(const char *name)
{
    for (int32_t i = 0; name && i < POLICY_PARAM_COUNT; ++i)
        if (strcmp(policy_params[i].name, name) == 0) return &policy_params[i];
    return NULL;
}

cf_status cf_flow_common_params(const cf_param_desc **params, int32_t *count)
{
    if (!params || !count) return CF_ERR_INVALID_ARG;
    *params = cfi_step_policy_params(count);
    return CF_OK;
}

cf_step_policy *cf_flow_options_policy(cf_flow_options *options)
{
    return options ? (cf_step_policy *)(void *)(options->storage.bytes + CFI_STEP_POLICY_OFFSET) : NULL;
}

const cf_step_policy *cf_flow_options_policy_const(const cf_flow_options *options)
{
    return options ? (const cf_step_policy *)(const void *)(options->storage.bytes + CFI_STEP_POLICY_OFFSET) : NULL;
}

cf_status cfi_step_policy_validate(cf_context *ctx, const cf_step_policy *p)
{
    /* every field against its table entry, so a struct set by hand obeys
     * the same limits as one set by name */
    for (int32_t i = 0; i < POLICY_PARAM_COUNT; ++i) {
        const cf_param_desc *d = &policy_params[i];
        const unsigned char *field = (const unsigned char *)p + (d->offset - CFI_STEP_POLICY_OFFSET);
        double v;
        if (d->type == CF_PARAM_DOUBLE) {
            memcpy(&v, field, sizeof v);
        } else {
            int32_t iv;
            memcpy(&iv, field, sizeof iv);
            v = iv;
        }
        if (!(v >= d->min_value && v <= d->max_value))
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter '%s': %g is outside [%g, %g]", d->name, v,
                             d->min_value, d->max_value);
    }
    /* what a range cannot say: a factor of 1 or less would fail every
     * step that does not lower the energy (blow-up), below 1 every run
     * that starts near its minimum (divergence) */
    if (!(p->blowup_factor == 0.0 || p->blowup_factor > 1.0))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter 'blowup_factor': must be 0 (off) or > 1, got %g",
                         p->blowup_factor);
    if (!(p->divergence_factor == 0.0 || p->divergence_factor >= 1.0))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter 'divergence_factor': must be 0 (off) or >= 1, got %g",
                         p->divergence_factor);
    return CF_OK;
}

int cfi_step_policy_exceeds(double after, double before, double rel, double floor)
{
    if (isnan(after) || isnan(before)) return 1;
    return after > before + rel * fabs(before) + floor;
}

int cfi_step_policy_rose(const cfi_step_policy_state *p, double before, double after)
{
    return cfi_step_policy_exceeds(after, before, p->opt.rise_tolerance, p->opt.energy_floor * p->unit);
}

int cfi_step_policy_diverged(const cfi_step_policy_state *p, double energy, double initial, double factor)
{
    if (!(factor > 0.0)) return 0;
    return cfi_step_policy_exceeds(energy, factor * initial, p->opt.divergence_tolerance, p->opt.energy_floor * p->unit);
}

int cfi_step_policy_converged(double before, double after, double tolerance)
{
    return tolerance > 0.0 && ((before > 0.0 && fabs(before - after) < tolerance * before) || after == 0.0);
}

int cfi_step_policy_blew_up(const cfi_step_policy_state *p, double before, double after, double factor)
{
    if (!(factor > 0.0) || !(before > 0.0)) return 0;
    return cfi_step_policy_exceeds(after, factor * before, 0.0, p->opt.energy_floor * p->unit);
}
