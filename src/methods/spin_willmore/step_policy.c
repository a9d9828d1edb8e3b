/*
 * Step policy of the spin-willmore flow, the method's part of it: the
 * largest change of the log conformal scale across an edge (an attempt of
 * IV-VI above max_scale_change is rejected under `adaptive`) and
 * convergence: a relative decrease below `tolerance` (docs/spin.md). The
 * retries themselves (tau halved, or cut for the scale change, while W
 * would rise; up to max_halvings per step, then the state is kept and the
 * flow reports convergence; tau grown back by step_growth) and the
 * blow-up and divergence checks of an accepted step (the common options
 * blowup_factor and divergence_factor, spin's defaults 10 and 1 in its
 * descriptor, options.c) are the flow layer's step policy (cf_flow_step,
 * methods/step_policy.h), through the vtable's begin_step / attempt /
 * revert / end_step.
 *
 * A stall of the input-metric recovery (every retry of the layer raised W)
 * gets one more chance before the layer stops the run: the step again,
 * positions recovered in the current metric (the layer's fallback hook,
 * cfi_spin_fallback in flow_method.c). At a
 * stalled state the input metric's least-squares fit puts the step's
 * non-integrable part where the flow crowded the mesh, so no tau lowers W
 * (cow_3k after 9 steps: +0.007 W/4pi at tau 5e-4), while the current
 * metric's still does (-0.27 at tau 0.03); a low-pass filtered direction
 * (M + s L)^-1 M rhodot, s = 0.001 .. 1, raised W at every tau on cow,
 * bull and elk in either metric (docs/spin.md, "Robustness").
 *
 * Convergence stays here rather than in the layer's test: spin's is "W
 * decreased by at most tolerance W" (a rise, however small, never
 * converges; tolerance 0 still stops when W is unchanged), the layer's is
 * "|change| < tolerance E, or E = 0" (tolerance 0: never). They differ for
 * runs whose W may rise (adaptive=0, prescribed / cmc boundaries) and at
 * tolerance 0, so moving it would change results.
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

int32_t cfi_spin_converged(const cfi_spin_state *s, double energy_before)
{
    double decrease = energy_before - s->energy;
    return decrease >= 0.0 && decrease <= s->opt.tolerance * energy_before;
}
