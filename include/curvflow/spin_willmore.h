/*
 * Conformal Willmore flow in curvature space and the spin transformation it
 * is built from (Crane, Pinkall, Schroeder 2013, "Robust Fairing via
 * Conformal Curvature Flow"; vertex-based spin transformations of Crane,
 * Pinkall, Schroeder 2011).
 *
 * Conventions (docs/spin.md):
 *  - rho is a change of mean curvature per vertex, in units of 1/length:
 *    the transformed surface has H~ ~= H + rho (Crane 2013, Sec. 6,
 *    mu~ = mu + (rho - gamma)|df|).
 *  - Time step: one step of the flow prescribes rho = tau * rhodot with
 *    rhodot = -2 H projected onto the constraints (Crane 2013, Sec. 4/6.1:
 *    mu~ = (1 - 2 tau) mu). The flow is stable for 0 < tau < 1 and
 *    tau = 1/2 removes the (projected) curvature deviation to first order in
 *    one step. The default is 0.5 (docs/spin.md says why).
 *
 * Use through the common flow interface (curvflow/flow.h) with kind
 * CF_FLOW_SPIN_WILLMORE; the options struct below is the method part of
 * cf_flow_options, and every field can also be set by name
 * ("time_step", "sigma", "filter_k", "mobius", ...).
 */
#ifndef CURVFLOW_SPIN_WILLMORE_H
#define CURVFLOW_SPIN_WILLMORE_H

#include "curvflow/curvflow.h"
#include "curvflow/flow.h"
#include "curvflow/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum cf_spin_boundary_mode {
    /* Natural boundary conditions of the facewise Dirac matrix (Sec. 6.2:
     * "for topological disks this flow can be integrated without further
     * modification"). */
    CF_SPIN_BOUNDARY_FREE = 0,
    /* Sec. 6.3.2: lambda = 1 on boundary vertices (boundary columns of X moved
     * to the right-hand side) and a Poisson problem with the boundary
     * positions fixed: boundary vertices do not move at all. */
    CF_SPIN_BOUNDARY_FIXED = 1,
    /* Sec. 6.3.1: prescribed boundary vectors. At each boundary vertex the
     * vector V = cos(phi) B + sin(phi) N of the N-B plane (B = T x N, T:
     * boundary tangent, N: vertex normal made orthogonal to T, phi =
     * boundary_vector_angle; tilted toward T by boundary_tangent_angle)
     * must map to a target direction V~: lambda is
     * restricted to r (a - b V~) with r the rotation V -> V~. Targets are fixed
     * at creation: the per-vertex directions of boundary_targets if given,
     * otherwise V~ = V on boundary loop 0 and V rotated by boundary_angle
     * about boundary_axis on every other loop (Fig. 14: a cylinder bends). */
    CF_SPIN_BOUNDARY_PRESCRIBED = 2,
    /* Sec. 6.3.1 with V~ = V (= B by default) at every step: the boundary
     * vectors keep their direction; with V = B minimising W gives
     * constant-mean-curvature surfaces. */
    CF_SPIN_BOUNDARY_CMC = 3
} cf_spin_boundary_mode;

typedef struct cf_spin_willmore_options {
    double time_step;          /* tau, rho = -2 tau H (projected); stable for tau < 1. Default 0.5 */
    int32_t total_curvature;   /* constraint <rhodot, 1> = 0 (App. B). Default 1 */
    int32_t inversion;         /* constraints <rhodot, N^x,y,z> = 0 (App. D). Default 1 */
    int32_t exactness;         /* constraints <rhodot, Z_i^x,y,z> = 0 for genus > 0 (App. C). Default 1 */
    int32_t mobius;            /* Moebius balancing (App. E.1). Default 0 */
    double mobius_weight;      /* scale of the balancing term. Default 1 */
    /* Spectral filter v <- v - (id + sigma' Delta^k)^-1 v (Sec. 4, Fig. 8, 19),
     * Delta = M^-1 L >= 0, sigma' = sigma R^(2k) with R = sqrt(area / 4 pi)
     * of the input (so sigma is scale-free). sigma = 0 disables. */
    double sigma;              /* default 0 */
    int32_t filter_k;          /* 0..3, default 2 */
    int32_t boundary_mode;     /* cf_spin_boundary_mode, default FREE */
    double boundary_angle;     /* PRESCRIBED: rotation of the target vectors, radians. Default 0 */
    double boundary_vector_angle; /* PRESCRIBED/CMC: V = cos(phi) B + sin(phi) N, |phi| <= 1.5
                                   * (V = +-N excluded, Sec. 6.3.1). Default 0 (V = B) */
    double boundary_tangent_angle; /* PRESCRIBED/CMC: V is tilted toward the boundary tangent T,
                                * V = cos(psi) (cos(phi) B + sin(phi) N) + sin(psi) T, |psi| <= pi/2
                                * (pi/2: prescribed tangents, Fig. 15 centre; Sec. 6.3.1 allows any
                                * combination of N, T, B, and the problem is elliptic and self-adjoint
                                * only for psi = 0). Default 0 */
    double boundary_axis[3];   /* PRESCRIBED: rotation axis. Default (1, 0, 0) */
    int32_t power_iterations;  /* inverse power iterations per step, default 1 (Sec. 6.4.2) */
    int32_t normalize;         /* keep total area and area-weighted centroid (Willmore energy is
                                * scale invariant). Default 1 */
    double tolerance;          /* converged when the relative energy decrease of a step is
                                * below this. Default 1e-6 */
    /* blowup_factor and divergence_factor are the common step policy's
     * (cf_step_policy in curvflow/flow.h; spin's defaults 10 and 1, the
     * divergence check not with prescribed / cmc boundaries) */
    int32_t complex_factorization; /* factorise the quaternionic matrices as their complex
                                * Hermitian form of half the size (same result to rounding); 0 uses
                                * the real 4 nv x 4 nv form. Prescribed/cmc boundaries always use
                                * the real form. Default 1 */
    int32_t input_metric;      /* recover positions (Eq. 6) with the cotan Laplacian of the starting
                                * surface, factorised once, instead of the current surface's each
                                * step (the paper is silent; docs/spin.md). Not with a fixed
                                * boundary. Default 1 */
    int32_t adaptive;          /* adaptive time steps (the paper is silent): a step that would raise W,
                                * change the conformal scale across an edge by more than
                                * max_scale_change, or fails numerically is redone with a smaller
                                * tau (at most 10 retries, then the state is kept and the flow
                                * reports convergence); tau grows back after. Default 1 (0: the
                                * paper's fixed step; docs/spin.md, "Robustness") */
    double max_scale_change;   /* with adaptive: the largest change of the log conformal scale
                                * |log(|lambda_i|^2 / |lambda_j|^2)| across an edge in one step
                                * (docs/spin.md, "Option notes"). Default 1.2; 0 = no bound */
    int32_t exactness_linearized; /* exactness constraint (genus > 0, or holes with a free
                                * boundary) as the discrete linearisation of "the transformed edges
                                * have no periods" (first order in tau); 0 uses App. C.1's Z_i on
                                * closed surfaces (docs/spin.md). Surfaces with boundary always use
                                * the linearisation. Default 1 */
    int32_t period_iterations; /* closed surfaces of genus > 0 with the linearised exactness: at most
                                * this many Newton corrections of rho per attempt (in the span of the
                                * exactness columns) that cancel the periods the first-order
                                * constraint leaves at second order in tau. Default 3; 0: the
                                * constraint alone (docs/spin.md, "Periods") */
    double period_tolerance;   /* stop the corrections when the harmonic part of the transformed edges
                                * is below this fraction of them (*1 norm of the input). Default 3e-3;
                                * 1e-3 lowers W further on knotted tubes (docs/spin.md, "The period
                                * tolerance on knotted tubes") */
    double max_integrability_error; /* with adaptive: redo a step (tau halved) whose transformed edges
                                * are non-integrable by more than this fraction (the `integrability`
                                * residual). Default 0 = no bound: it trades W for triangle quality
                                * (docs/spin.md, "Periods") */
    int32_t harmonic_update;   /* with App. C's Z_i (exactness_linearized = 0): re-project the
                                * input's harmonic 1-forms onto the current surface's every step;
                                * 0 keeps the input's forms, as the paper. Default 1 */
    double regularization;     /* weight alpha of |lambda - 1|^2 in the step's eigenproblem, in units
                                * of 4 pi / area (the paper is silent): damps the modes of X whose
                                * eigenvalue is below alpha. Default 1e-3 (enough to factorise the
                                * singular X(0)); docs/spin.md, "Option notes" */
    double growth_ratio;       /* with adaptive: after a step taken at a reduced tau without retries,
                                * tau grows back (by the step policy's step_growth) only if the step
                                * realised at least this fraction of the decrease of W its
                                * curvature-space model predicts (the `realised_decrease` residual):
                                * a trust region that expands only where the model holds. Default
                                * 0.75; 0: always grow (docs/spin.md, "Growing tau back") */
    double exactness_refresh;  /* closed surfaces of genus > 0 with the period corrections: the
                                * factorisation of X(0) behind the exactness directions is kept from an
                                * earlier step while the steps since it changed the log conformal scale
                                * by at most this much in sum (the `scale_change` residuals) and the
                                * previous step's periods before corrections stayed below half of
                                * period_tolerance; the corrections absorb what the older directions
                                * miss, and an attempt on them whose periods exceed period_tolerance,
                                * or that is rejected, is made again with a new factorisation.
                                * Default 0.1; 0: a new factorisation every step (docs/spin.md,
                                * "Reusing X(0)") */
    cf_param_values boundary_targets; /* table parameter "boundary_targets" (vertex vectors, boundary
                                * vertices only). PRESCRIBED: target directions V~ per vertex (count nv,
                                * values 3 nv doubles, x y z; only boundary vertices' entries are read,
                                * each must be finite and nonzero, and is normalised). Read once by
                                * cf_flow_create, not kept. {NULL, 0} (default): the boundary_angle /
                                * boundary_axis rule above */
    double fairing;            /* vertex-scale fairing per unit tau (the paper is silent): after the
                                * positions of a step are recovered, x = (I + fairing tau L0)^-1 x (L0
                                * the input's cotan Laplacian, unit vertex weights, boundary vertices
                                * held; curvflow/ops.h, cf_vertex_fairing), and the faired positions
                                * are kept if their W is lower. It removes the vertex-scale part of the
                                * cotan curvature, which the vertex-based spin transformation sees only
                                * through face sums. Default 1; 0: the paper's step. Not with
                                * prescribed / cmc boundaries (docs/spin.md, "Vertex-scale fairing") */
    double max_conformal_excess; /* with adaptive: redo a step (tau halved) whose map from the step's
                                * start has an area-weighted mean Q above its vertex-scale model's
                                * by more than this (cf_conformal_excess: the distortion that no
                                * vertex scale explains, which a conformal step should not make).
                                * 0 = no bound. Default -1 = automatic: 0.12 on closed surfaces, no
                                * bound with a boundary (docs/spin.md, "The step's non-conformal
                                * excess") */
    int32_t stall_fairing;     /* with adaptive and fairing: a step whose spin attempts raise W at
                                * every tau, in the input metric and in the current one, is taken as
                                * the vertex-scale fairing of its start alone (kappa = fairing tau,
                                * tau halved while W rises or the excess bound is exceeded) before
                                * the flow stops as converged. Default 1; 0: the stall stops the
                                * run (docs/spin.md, "A stall's last variant") */
    double max_realised_decrease; /* with adaptive: an attempt whose W falls by more than this multiple
                                * of the decrease its curvature-space model predicts (the
                                * `realised_decrease` residual; counted only where the prediction is at
                                * least 1 % of W) is not a realisation of its curvature change: the
                                * near-kernel modes of X took it over (long thin tubes). The attempt
                                * is redone at the same tau with `regularization` raised to 1, which
                                * stays for the rest of the run. Default 2; 0: never (docs/spin.md,
                                * "Long tubes: damping when a step outruns its model") */
    double weight_floor;       /* floor on the cotan weights of every Laplacian the flow builds (the
                                * energy's, the position recovery's, the fairing's, the exactness
                                * metric's; not the Dirac matrix): a face weighs as if twice its area
                                * were at least weight_floor times the sum of its squared edges
                                * (cf_cotan_laplacian_floored). A near-duplicate vertex gives weights
                                * of 1 / (its distance in edge lengths) that cost every solve that many
                                * digits (spot_3k with one at 1e-12: W/4pi 4.4 after 10 steps instead
                                * of 1.002). Default 1e-8 (only faces with an angle below about 2e-8
                                * rad are touched; none on any shared mesh); 0: exact weights
                                * (docs/spin.md, "Near-duplicate vertices") */
    double max_period_error;   /* with adaptive, closed surfaces of genus > 0 with the period
                                * corrections: redo a step (tau halved) whose periods the corrections
                                * leave above this (the `periods` residual, relative as
                                * period_tolerance): their Newton steps diverge when a step is too
                                * large for their linearisation, and the step then leaves the
                                * conformal class by that much (a real knot tube: 0.083 left after
                                * step 1, its distortion mean Q 1.56 after 10 steps). Default 0.03
                                * (10 period_tolerance); 0: no bound (docs/spin.md, "Periods the
                                * corrections cannot cancel") */
    int32_t relaxation;        /* tangential relaxation (the paper is silent): after a step that
                                * lowered W, once the map from the input has a mean Q above 1.3,
                                * this many sweeps of the MIPS energy against the input's
                                * triangles, every vertex moved within its star on the step's surface
                                * (curvflow/ops.h, cf_tangential_relaxation, boundary held); kept if
                                * its W is not above the step's, the position recovery then taking
                                * the relaxed state's metric. -1 (default): 10 on a closed surface
                                * of genus 0 (each component judged alone), 0 otherwise: on genus > 0
                                * the resampled state lets the flow go on to a lower W of the same
                                * class that crowds a coarse mesh (the double torus, 315 vertices:
                                * mean Q 1.53 -> 1.97; elk meets both issue-13 targets with it), and
                                * with a boundary (held) it slowed bunny_scan_35k's flow (W/4pi 5.10
                                * -> 8.83 after 10 steps). 0: off (docs/spin.md, "Tangential
                                * relaxation") */
    int32_t keep_class;        /* closed surfaces of genus >= 1: after each attempt, Gauss-Newton
                                * steps (halved until the residual falls) move its positions back
                                * onto the input's conformal class before its W is judged, the
                                * correction smoothed as (I + 10 L)^-1 J^T y with L the cotan
                                * Laplacian of the positions projected. 1: the class alone (G^ of
                                * cf_conformal_class_normalize, to 1e-10 relative); 2: the Gram
                                * matrix G of cf_conformal_class_gram_gradient itself, which also
                                * holds the discrete Hodge star's defect, a property of the
                                * triangles (elk_g1_2k: mean Q 1.35 against 1.71 with 1, but the
                                * knotted tubes stall). The discrete flow otherwise drifts from the
                                * class on coarse meshes (elephant_g3_3k 0.75, elk 0.175 after 10
                                * steps). Default 0 (W falls less on most meshes of genus > 0 and
                                * it costs 1.8-11x the time: bob 1.8-2.1x, elk 1.8-3.0x, elephant
                                * 11x; docs/spin.md, "The conformal class the flow keeps"); on
                                * another surface it is refused */
    double recovery_scale_weight; /* the input-metric position recovery (Eq. (6), input_metric) weighs
                                * the misfit of face f's edges by (A_f / A~_f)^p, p this value in
                                * [0, 1]: A_f its area in the recovery's metric (the input, or the
                                * relaxed state it took), A~_f the area its transformed edges span
                                * (both relative to their totals; the factor capped at 1e12). Where
                                * the flow has crowded a region, the plain fit (p = 0) leaves misfits
                                * comparable to the mesh's edges on edges far smaller, which the
                                * step then realises as crumpled triangles of huge W; p > 0 fits them
                                * relative to their size and leaves the misfit on the large
                                * triangles instead (distortion there). One real refactorisation of
                                * the recovery per attempt; no effect where positions are not
                                * recovered in the input metric (input_metric 0, a fixed boundary,
                                * the current-metric retry of a stall). Default 0 (0.5 takes more
                                * knotted tubes to W0/2 but raises mean Q on the shared genus-0
                                * meshes; docs/spin.md, "Crowded regions in the position
                                * recovery") */
    int32_t period_first_order; /* the period corrections (period_iterations): each correction first
                                * takes lambda at first order in it, the lambda before it plus the
                                * derivative the correction's Jacobian already solved for, and
                                * factorises X at the corrected rho only when that leaves periods
                                * above period_tolerance. The first-order lambda is what the Newton
                                * step models, so it cancels the periods better than the re-solved
                                * one (generated double torus, tau 0.5: 5.7e-2 -> 5.4e-4 against
                                * 2.4e-3), and the step saves one factorisation of X per correction
                                * (bob_5k: the first two steps 135 and 114 ms -> 109 and 86 ms).
                                * Default 1; 0: every correction re-solves (docs/spin.md, "Periods") */
} cf_spin_willmore_options;

CF_API void cf_spin_willmore_options_default(cf_spin_willmore_options *options);

/* SpinXForm (Crane et al. 2011; Crane 2013, Sec. 6 and App. G): finds the
 * smallest eigenvector lambda of the facewise quaternionic matrix X(rho)
 * (real 4 nv x 4 nv form) by inverse power iteration on a Cholesky
 * factorisation, transforms every edge by lambda and recovers the positions
 * from the cotan Poisson problem L f~ = div e~.
 *   positions: 3 nv (NULL: the mesh's rest positions);
 *   rho: nv values, curvature change in 1/length (H~ ~= H + rho);
 *   out_positions: 3 nv, caller-allocated (may not alias positions).
 * The result keeps the area-weighted centroid of the input; its scale is set
 * by normalising lambda to mean |lambda|^2 = 1 (area weighted). The
 * Poisson problem's weights have the flow's default floor (weight_floor
 * 1e-8: only faces with an angle below about 2e-8 rad are touched).
 * Statuses: CF_OK, CF_ERR_INVALID_ARG, CF_ERR_NONFINITE (rho), CF_ERR_NOMEM,
 * CF_ERR_DEGENERATE_FACE, CF_ERR_NOT_POSDEF, CF_ERR_NUMERICAL. */
CF_API cf_status cf_spin_transform(cf_context *ctx, const cf_mesh *mesh, const double *positions, const double *rho,
                                   double *out_positions);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_SPIN_WILLMORE_H */
