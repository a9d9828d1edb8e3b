/*
 * Step policy of the spin-willmore flow, the method's part of it: the
 * largest change of the log conformal scale across an edge (an attempt of
 * IV-VI above max_scale_change is rejected under `adaptive`), the blow-up
 * (energy jump > blowup_factor) and divergence (W above divergence_factor
 * times its start) checks of an accepted step, and convergence: a relative
 * decrease below `tolerance` (docs/spin.md). The retries themselves (tau
 * halved, or cut for the scale change, while W would rise; up to
 * max_halvings per step, then the state is kept and the flow reports
 * convergence; tau grown back by step_growth) are the flow layer's step
 * policy (cf_flow_step, methods/step_policy.h), through the vtable's
 * begin_step / attempt / revert / end_step.
 */
#include "methods/spin_willmore/spin_flow.h"

#include <math.h>
#include <string.h>

/* Largest change of the log conformal scale across an edge, |log(|l_i|^2 / |l_j|^2)|. */
double cfi_spin_max_scale_change(const cf_mesh *mesh, const double *lambda)
{
    double worst = 0.0;
    for (int32_t e = 0; e < mesh->ne; ++e) {
        const double *li = lambda + 4 * (int64_t)mesh->edge_vertices[2 * e];
        const double *lj = lambda + 4 * (int64_t)mesh->edge_vertices[2 * e + 1];
        double ni = li[0] * li[0] + li[1] * li[1] + li[2] * li[2] + li[3] * li[3];
        double nj = lj[0] * lj[0] + lj[1] * lj[1] + lj[2] * lj[2] + lj[3] * lj[3];
        double r = ni > 0.0 && nj > 0.0 ? fabs(log(ni / nj)) : INFINITY;
        if (!(r <= worst)) worst = r;
    }
    return worst;
}

cf_status cfi_spin_check_energy(cf_flow *flow, const cfi_spin_state *s, double energy_before, double tau)
{
    cf_context *ctx = flow->ctx;
    /* An explicit step on rho can overshoot where the realised curvature
     * change is far from the prescribed one (thin cone tips, slivers;
     * docs/spin.md): a jump of the energy by more than blowup_factor is
     * reported as a failure so that the flow layer keeps the last good state. */
    if (s->opt.blowup_factor > 0.0 && energy_before > 0.0 && s->energy > s->opt.blowup_factor * energy_before)
        return cfi_error(ctx, CF_ERR_NUMERICAL,
                         "spin-willmore: energy grew from %.6g to %.6g in one step (more than %gx): the step blew "
                         "up; try a smaller time_step",
                         energy_before, s->energy, s->opt.blowup_factor);
    /* A Willmore descent that ends above its start has diverged, even when
     * it creeps up by less than blowup_factor per step (elephant_g3_3k at
     * the default tau: 24.99 -> 12.46 -> 26.9 -> 102 -> ...). Prescribed and
     * cmc boundaries may raise W by design. The test is the shared step
     * policy's (methods/step_policy.h), with its relative tolerance
     * (divergence_tolerance) and floor (energy_floor, in units of 4pi): W
     * creeping up by 7e-8 of itself per step at tau 1e-9 on spot_3k, or a
     * flat sheet's W going from 0 to 6.7e-29, is no divergence (issue 15
     * M1; the former slack 1e-9 called both one). */
    if (!s->restricted_boundary &&
        cfi_step_policy_diverged(&flow->policy, s->energy, s->initial_energy, s->opt.divergence_factor))
        return cfi_error(ctx, CF_ERR_NUMERICAL,
                         "spin-willmore: W/4pi rose to %.6g, above %g times its starting value %.6g: the flow "
                         "diverges (time_step %g is above this mesh's stability limit); try a smaller time_step, "
                         "adaptive=1 or a larger regularization (docs/spin.md)",
                         s->energy / (4.0 * CFI_PI), s->opt.divergence_factor, s->initial_energy / (4.0 * CFI_PI), tau);
    return CF_OK;
}

int32_t cfi_spin_converged(const cfi_spin_state *s, double energy_before)
{
    double decrease = energy_before - s->energy;
    return decrease >= 0.0 && decrease <= s->opt.tolerance * energy_before;
}
