/*
 * Step policy of the spin-willmore flow: which attempt of steps IV-VI is
 * accepted. With `adaptive` an attempt that raises W, fails numerically or
 * changes the log conformal scale across an edge by more than
 * max_scale_change is redone from the same rhodot with a smaller tau (up to
 * the common option max_halvings times, 10 by default; then the state is
 * kept and the flow reports convergence), and tau grows back after an
 * accepted step. Every accepted
 * step is then checked for blow-up (energy jump > blowup_factor) and
 * divergence (W above divergence_factor times its start), and convergence is
 * a relative decrease below `tolerance` (docs/spin.md).
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

cf_status cfi_spin_advance(cf_flow *flow, cfi_spin_state *s, double energy_before, cfi_spin_attempt *out,
                           cfi_spin_timers *t)
{
    cf_context *ctx = flow->ctx;
    int32_t nv = s->nv;
    double *x = flow->positions;
    cf_status st = CF_OK;
    /* IV-VI, and with adaptive time steps the step is redone from the same
     * rhodot with tau halved while W would rise (or the step fails
     * numerically); when no halving helps, the state is kept and the flow
     * reports convergence (W stopped decreasing). The number of halvings
     * per step and the growth factor are the shared step policy's
     * (max_halvings, step_growth; docs/flowcli.md), the rise test its
     * comparison with no slack: the flow's claim is that W never rises.
     * The retry stays here since it redoes only IV-VI from the same rhodot,
     * which a flow-layer retry of the whole step could not. */
    const cfi_step_policy_state *policy = &flow->policy;
    double tau = s->tau; /* opt.time_step unless adaptive steps changed it */
    int32_t halvings = 0;
    int stalled = 0;
    /* a failed attempt restores x from xsave, so one copy serves every retry */
    if (s->opt.adaptive) memcpy(s->xsave, x, 3 * (size_t)nv * sizeof(double));
    for (;;) {
        int too_large = 0;
        st = cfi_spin_realise_step(flow, s, tau, &too_large, t);
        if (!s->opt.adaptive) break;
        /* prescribed and cmc boundaries may raise W by design: only the scale bound applies */
        if (st == CF_OK && !too_large &&
            (!cfi_step_policy_exceeds(s->energy, energy_before, 0.0, 0.0) || s->restricted_boundary))
            break;
        if (st != CF_OK && st != CF_ERR_NUMERICAL && st != CF_ERR_NOT_POSDEF && st != CF_ERR_DEGENERATE_FACE)
            return st;
        memcpy(x, s->xsave, 3 * (size_t)nv * sizeof(double));
        cf_status sg = cfi_spin_update_geometry(flow, s, x);
        if (sg != CF_OK) return sg;
        if (halvings >= policy->opt.max_halvings) {
            stalled = 1;
            st = CF_OK;
            cfi_log(ctx, CF_LOG_INFO,
                    "spin-willmore: W does not decrease for any time step down to %g; stopping at W/4pi = %.6g", tau,
                    s->energy / (4.0 * CFI_PI));
            break;
        }
        ++halvings;
        /* the scale change grows about linearly with tau: cut it in proportion (at least halve) */
        tau *= too_large ? fmin(0.5, 0.9 * s->opt.max_scale_change / s->diag.scale_change) : 0.5;
    }
    if (st != CF_OK) return st;
    if (s->opt.adaptive && !stalled) s->tau = halvings ? tau : fmin(s->opt.time_step, policy->opt.step_growth * tau);
    out->tau = tau;
    out->halvings = halvings;
    out->stalled = stalled;
    return CF_OK;
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
    if (s->opt.divergence_factor > 0.0 && !s->restricted_boundary &&
        cfi_step_policy_exceeds(s->energy, s->opt.divergence_factor * s->initial_energy,
                                flow->policy.opt.divergence_tolerance, flow->policy.opt.energy_floor * 4.0 * CFI_PI))
        return cfi_error(ctx, CF_ERR_NUMERICAL,
                         "spin-willmore: W/4pi rose to %.6g, above %g times its starting value %.6g: the flow "
                         "diverges (time_step %g is above this mesh's stability limit); try a smaller time_step, "
                         "adaptive=1 or a larger regularization (docs/spin.md)",
                         s->energy / (4.0 * CFI_PI), s->opt.divergence_factor, s->initial_energy / (4.0 * CFI_PI), tau);
    return CF_OK;
}

int32_t cfi_spin_converged(const cfi_spin_state *s, double energy_before, int stalled)
{
    double decrease = energy_before - s->energy;
    return stalled || (decrease >= 0.0 && decrease <= s->opt.tolerance * energy_before);
}
