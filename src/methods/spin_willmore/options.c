/*
 * Options of the spin-willmore flow: defaults, the parameter table of the
 * common flow interface (names, ranges, help), and the validation that
 * create runs before anything is allocated, and the method's entry in the
 * flow registry (its vtable; the functions are in flow_method.c). Conventions of each parameter:
 * docs/spin.md.
 */
#include "methods/spin_willmore/spin_flow.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

void cf_spin_willmore_options_default(cf_spin_willmore_options *o)
{
    if (!o) return;
    memset(o, 0, sizeof *o);
    o->time_step = 0.5;
    o->total_curvature = 1;
    o->inversion = 1;
    o->exactness = 1;
    o->mobius = 0;
    o->mobius_weight = 1.0;
    o->sigma = 0.0;
    o->filter_k = 2;
    o->boundary_mode = CF_SPIN_BOUNDARY_FREE;
    o->boundary_angle = 0.0;
    o->boundary_axis[0] = 1.0;
    o->power_iterations = 1;
    o->normalize = 1;
    o->tolerance = 1e-6;
    o->complex_factorization = 1;
    o->harmonic_update = 1;
    o->exactness_linearized = 1;
    o->period_iterations = 3;
    o->period_tolerance = 3e-3;
    o->max_period_error = 3e-2;
    o->relaxation = -1;
    o->keep_class = 0;
    o->recovery_scale_weight = 0.0;
    o->period_first_order = 1;
    o->max_integrability_error = 0.0;
    o->max_conformal_excess = -1.0; /* automatic: the bound on closed surfaces only */
    o->stall_fairing = 1;
    o->max_realised_decrease = 2.0;
    o->adaptive = 1;
    o->max_scale_change = 1.2;
    o->input_metric = 1;
    o->regularization = CFI_SPIN_SHIFT;
    o->growth_ratio = 0.75;
    o->exactness_refresh = 0.1;
    o->fairing = 1.0;
    o->weight_floor = CFI_SPIN_WEIGHT_FLOOR;
}

static void options_default(void *options) { cf_spin_willmore_options_default(options); }

const char *const cfi_spin_boundary_choices[] = {"free", "fixed", "prescribed", "cmc", NULL};

#define OPT(f) offsetof(cf_spin_willmore_options, f)
static const cf_param_desc spin_params[] = {
    {"time_step", CF_PARAM_DOUBLE, OPT(time_step), 1e-9, 10.0, NULL,
     "tau: rho = -2 tau H per step (stable for tau < 1; 0.5 removes curvature to first order)"},
    {"total_curvature", CF_PARAM_BOOL, OPT(total_curvature), 0, 1, NULL, "constraint <rhodot, 1> = 0 (App. B)"},
    {"inversion", CF_PARAM_BOOL, OPT(inversion), 0, 1, NULL, "constraints <rhodot, N> = 0 (App. D)"},
    {"exactness", CF_PARAM_BOOL, OPT(exactness), 0, 1, NULL,
     "constraints <rhodot, Z_i> = 0: genus > 0, or holes with boundary=free (App. C)"},
    {"mobius", CF_PARAM_BOOL, OPT(mobius), 0, 1, NULL, "Moebius balancing toward the input area distribution (App. E)"},
    {"mobius_weight", CF_PARAM_DOUBLE, OPT(mobius_weight), 0.0, 100.0, NULL, "scale of the balancing term"},
    {"sigma", CF_PARAM_DOUBLE, OPT(sigma), 0.0, 1e12, NULL,
     "spectral filter strength in units of R^2k, R = sqrt(area/4pi); 0 = off (Sec. 4)"},
    {"filter_k", CF_PARAM_INT, OPT(filter_k), 0, 3, NULL, "spectral filter power k (Fig. 8)"},
    {"boundary", CF_PARAM_CHOICE, OPT(boundary_mode), 0, 3, cfi_spin_boundary_choices,
     "free (natural), fixed positions (Sec. 6.3.2), prescribed binormals or cmc (Sec. 6.3.1)"},
    {"boundary_angle", CF_PARAM_DOUBLE, OPT(boundary_angle), -6.3, 6.3, NULL,
     "prescribed: rotation (radians) of the target binormals of boundary loops 1, 2, ..."},
    {"boundary_vector_angle", CF_PARAM_DOUBLE, OPT(boundary_vector_angle), -1.5, 1.5, NULL,
     "prescribed/cmc: V = cos(phi) B + sin(phi) N in the N-B plane (0: binormal; not +-N)"},
    {"boundary_tangent_angle", CF_PARAM_DOUBLE, OPT(boundary_tangent_angle), -1.5707963267948966, 1.5707963267948966, NULL,
     "prescribed/cmc: tilt psi of V toward the boundary tangent T (pi/2: V = T, Fig. 15 centre)"},
    {"boundary_axis_x", CF_PARAM_DOUBLE, OPT(boundary_axis[0]), -1e9, 1e9, NULL, "prescribed: rotation axis x"},
    {"boundary_axis_y", CF_PARAM_DOUBLE, OPT(boundary_axis[1]), -1e9, 1e9, NULL, "prescribed: rotation axis y"},
    {"boundary_axis_z", CF_PARAM_DOUBLE, OPT(boundary_axis[2]), -1e9, 1e9, NULL, "prescribed: rotation axis z"},
    {"power_iterations", CF_PARAM_INT, OPT(power_iterations), 1, 100, NULL, "inverse power iterations per step"},
    {"normalize", CF_PARAM_BOOL, OPT(normalize), 0, 1, NULL, "keep total area and centroid"},
    {"tolerance", CF_PARAM_DOUBLE, OPT(tolerance), 0.0, 1.0, NULL, "converged below this relative energy decrease"},
    {"complex_factorization", CF_PARAM_BOOL, OPT(complex_factorization), 0, 1, NULL,
     "factorise X as its complex Hermitian form of half the size (0: real 4n x 4n form)"},
    {"input_metric", CF_PARAM_BOOL, OPT(input_metric), 0, 1, NULL,
     "recover positions in the cotan metric of the starting surface (0: the current surface's, per step)"},
    {"adaptive", CF_PARAM_BOOL, OPT(adaptive), 0, 1, NULL,
     "retry a step with a smaller tau while it would raise W or exceed max_scale_change (up to max_halvings times; then "
     "stop as converged), grow tau back after; 0: the paper's fixed step"},
    {"max_scale_change", CF_PARAM_DOUBLE, OPT(max_scale_change), 0.0, 100.0, NULL,
     "adaptive: largest change of the log conformal scale across an edge in one step (0: no bound)"},
    {"exactness_linearized", CF_PARAM_BOOL, OPT(exactness_linearized), 0, 1, NULL,
     "exactness as the discrete linearisation of 'no periods' (0: App. C's Z_i on closed surfaces)"},
    {"period_iterations", CF_PARAM_INT, OPT(period_iterations), 0, 20, NULL,
     "closed genus > 0: Newton corrections of rho per step that cancel the periods of the transformed edges (0: "
     "first-order exactness only)"},
    {"period_tolerance", CF_PARAM_DOUBLE, OPT(period_tolerance), 0.0, 1.0, NULL,
     "stop the period corrections below this harmonic part of the transformed edges (relative; 1e-3 lowers W "
     "further on knotted and long-handled tubes at 1.0-1.4x the time per step, docs/spin.md)"},
    {"max_period_error", CF_PARAM_DOUBLE, OPT(max_period_error), 0.0, 1.0, NULL,
     "adaptive, closed genus > 0: redo a step with half tau whose periods the corrections leave above this "
     "(relative, as period_tolerance: their Newton steps diverged; 0: no bound)"},
    {"period_first_order", CF_PARAM_BOOL, OPT(period_first_order), 0, 1, NULL,
     "period corrections: take lambda at first order in each correction and factorise X at the corrected rho only "
     "if its periods stay above period_tolerance (0: always factorise; the first-order lambda cancels them better "
     "and saves a factorisation per correction)"},
    {"relaxation", CF_PARAM_INT, OPT(relaxation), -1, 1000, NULL,
     "tangential relaxation: after a step that lowered W, once the map from the input has mean Q above 1.3, this "
     "many sweeps moving every vertex within its star on the surface to lower the MIPS energy against the input's "
     "triangles, kept if W does not rise (-1, default: 10 on a closed surface of genus 0, 0 otherwise, since on "
     "genus > 0 it lets a coarse mesh crowd further (the double torus: mean Q 1.53 -> 1.97; elk 1.56 -> 1.48) and "
     "with a boundary it can slow the flow; 0: off)"},
    {"keep_class", CF_PARAM_INT, OPT(keep_class), 0, 2, NULL,
     "closed genus > 0: after each attempt Gauss-Newton steps move its positions back onto the input's conformal "
     "class (1: the class alone; 2: also the triangulation's part of its Gram matrix, which keeps triangles better "
     "and stalls knotted tubes; smoothed; off by default: W falls less on most meshes of genus > 0, 1.8-11x the "
     "time)"},
    {"recovery_scale_weight", CF_PARAM_DOUBLE, OPT(recovery_scale_weight), 0.0, 1.0, NULL,
     "input-metric position recovery: weigh each face's edge misfit by (its area in the metric / the area its "
     "transformed edges span)^p, so that crowded regions are fitted relative to their size (0, default: the plain "
     "input metric; 0.5 takes knotted tubes further, at some cost in mean Q; one refactorisation per attempt)"},
    {"max_integrability_error", CF_PARAM_DOUBLE, OPT(max_integrability_error), 0.0, 1.0, NULL,
     "adaptive: redo a step with half tau while its transformed edges are non-integrable by more than this "
     "(relative; 0: no bound; e.g. 0.04 keeps triangles better at some cost in W)"},
    {"max_conformal_excess", CF_PARAM_DOUBLE, OPT(max_conformal_excess), -1.0, 100.0, NULL,
     "adaptive: redo a step with half tau while its map's mean Q exceeds its vertex-scale model's by more than "
     "this (the distortion no conformal scale explains; -1: 0.12 on closed surfaces, no bound with a boundary; "
     "0: no bound)"},
    {"stall_fairing", CF_PARAM_BOOL, OPT(stall_fairing), 0, 1, NULL,
     "adaptive, fairing > 0: a step that raises W at every tau in both metrics is taken as the vertex-scale "
     "fairing of its start alone (tau halved while W rises or the excess bound is exceeded) before the run "
     "stops as converged (0: it stops)"},
    {"max_realised_decrease", CF_PARAM_DOUBLE, OPT(max_realised_decrease), 0.0, 1000.0, NULL,
     "adaptive: an attempt that lowers W by more than this multiple of its predicted decrease (which is at least "
     "1% of W) is redone at the same tau with regularization raised to 1 for the rest of the run (long thin "
     "tubes; 0: never)"},
    {"regularization", CF_PARAM_DOUBLE, OPT(regularization), 1e-9, 1e6, NULL,
     "weight of |lambda - 1|^2 in units of 4pi/area: damps near-kernel modes of thin shapes"},
    {"growth_ratio", CF_PARAM_DOUBLE, OPT(growth_ratio), 0.0, 1.0, NULL,
     "adaptive: grow a reduced tau back only after a step that realised at least this fraction of its predicted "
     "decrease of W (realised_decrease; 0: always)"},
    {"exactness_refresh", CF_PARAM_DOUBLE, OPT(exactness_refresh), 0.0, 100.0, NULL,
     "closed genus > 0: keep X(0)'s factorisation (exactness directions) while the steps since it changed the "
     "log conformal scale by at most this in sum and the periods stay below period_tolerance / 2; an attempt that "
     "fails on it is redone with a new one (0: refactorise every step)"},
    {"fairing", CF_PARAM_DOUBLE, OPT(fairing), 0.0, 1000.0, NULL,
     "vertex-scale fairing per unit tau: each step's positions relaxed by (I + fairing tau L0)^-1 (input cotan "
     "Laplacian, unit vertex weights, boundary held), kept if W is lower (0: off, the paper's step; not with "
     "prescribed/cmc boundaries)"},
    {"weight_floor", CF_PARAM_DOUBLE, OPT(weight_floor), 0.0, 1e-3, NULL,
     "floor on the cotan weights of the flow's Laplacians: a face weighs as if twice its area were at least this "
     "times the sum of its squared edges (bounds the weights of a near-duplicate vertex; 0: exact weights)"},
    {"harmonic_update", CF_PARAM_BOOL, OPT(harmonic_update), 0, 1, NULL,
     "with App. C's Z_i: re-project the harmonic 1-forms onto the current metric each step"},
    {"boundary_targets", CF_PARAM_VERTEX_VECTORS, OPT(boundary_targets), 0, 1, NULL,
     "boundary=prescribed: target direction of V at each boundary vertex (file: one line 'VERTEX X Y Z' per "
     "boundary vertex; --boundary-targets FILE is -p boundary=prescribed -p boundary_targets=FILE)"},
};
#undef OPT

cf_status cfi_spin_validate_options(cf_context *ctx, const cf_mesh *mesh, const cf_spin_willmore_options *o)
{
    /* Every range of the table above (time_step, filter_k, sigma, angles,
     * regularization, power_iterations, boundary, mobius_weight, the count of
     * boundary_targets) was checked by cf_flow_create; what follows are the
     * rules a range cannot express. */
    if (!(o->regularization > 0.0) || !isfinite(o->regularization))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: regularization must be > 0, got %g", o->regularization);
    if (o->max_realised_decrease != 0.0 && !(o->max_realised_decrease > 1.0))
        return cfi_error(ctx, CF_ERR_INVALID_ARG,
                         "spin-willmore: max_realised_decrease must be 0 (never) or above 1 (a step realises its model's "
                         "decrease at 1), got %g",
                         o->max_realised_decrease);
    if (o->max_conformal_excess < 0.0 && o->max_conformal_excess != -1.0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG,
                         "spin-willmore: max_conformal_excess must be -1 (automatic), 0 (no bound) or positive, got %g",
                         o->max_conformal_excess);
    double axis_len = sqrt(o->boundary_axis[0] * o->boundary_axis[0] + o->boundary_axis[1] * o->boundary_axis[1] +
                           o->boundary_axis[2] * o->boundary_axis[2]);
    if (o->boundary_mode == CF_SPIN_BOUNDARY_PRESCRIBED && (!(axis_len > 0.0) || !isfinite(axis_len) || !isfinite(o->boundary_angle)))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: boundary_axis must be a nonzero finite vector");
    if (o->boundary_targets.values && o->boundary_mode != CF_SPIN_BOUNDARY_PRESCRIBED)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: boundary targets are given but boundary=%s "
                         "(they need boundary=prescribed)", cfi_spin_boundary_choices[o->boundary_mode]);
    if (o->boundary_targets.values)
        for (int32_t i = 0; i < mesh->nv; ++i) {
            if (!mesh->vertex_on_boundary[i]) continue;
            const double *t = o->boundary_targets.values + 3 * (int64_t)i;
            double len = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
            if (!isfinite(len) || !(len > 0.0))
                return cfi_error(ctx, CF_ERR_INVALID_ARG, "spin-willmore: vertex %d: boundary target (%g, %g, %g) is %s",
                                 i, t[0], t[1], t[2], isfinite(len) ? "zero" : "not finite");
        }
    int32_t has_boundary = mesh->boundary_loop_count > 0;
    if (o->keep_class && (has_boundary || cf_mesh_genus(mesh) < 1))
        return cfi_error(ctx, CF_ERR_BAD_MESH,
                         "spin-willmore: keep_class needs a closed surface of genus >= 1 (this one has %s)",
                         has_boundary ? "a boundary" : "genus 0: a sphere has one conformal class");
    if (o->boundary_mode != CF_SPIN_BOUNDARY_FREE && !has_boundary)
        return cfi_error(ctx, CF_ERR_BAD_MESH, "spin-willmore: boundary=%s needs a mesh with boundary",
                         cfi_spin_boundary_choices[o->boundary_mode]);
    /* A mesh whose every vertex lies on its boundary (a band of one row of
     * triangles, a fan) has no vertex that a fixed boundary lets move, and
     * its W, a sum over interior vertices, is 0: the Poisson and Dirac
     * systems would have no unknown left. Refused as the edit refuses handles
     * that hold every vertex; the other boundary modes run (and converge at
     * once). */
    if (o->boundary_mode == CF_SPIN_BOUNDARY_FIXED) {
        int32_t interior = 0;
        for (int32_t i = 0; i < mesh->nv && !interior; ++i) interior = !mesh->vertex_on_boundary[i];
        if (!interior)
            return cfi_error(ctx, CF_ERR_BAD_MESH,
                             "spin-willmore: boundary=fixed holds all %d vertices of this mesh (every vertex is on its "
                             "boundary): nothing is left to move",
                             mesh->nv);
    }
    return CF_OK;
}

const cfi_flow_method cfi_spin_willmore_method = {
    .kind = CF_FLOW_SPIN_WILLMORE,
    .name = "spin-willmore",
    .description = "conformal Willmore flow in curvature space (Crane, Pinkall, Schroeder 2013)",
    .options_size = sizeof(cf_spin_willmore_options),
    .options_default = options_default,
    .params = spin_params,
    .param_count = (int32_t)(sizeof spin_params / sizeof spin_params[0]),
    .create = cfi_spin_create,
    .begin_step = cfi_spin_begin_step,
    .attempt = cfi_spin_attempt,
    .end_step = cfi_spin_end_step,
    .reset = cfi_spin_reset,
    .revert = cfi_spin_revert,
    .fallback = cfi_spin_fallback,
    .destroy = cfi_spin_destroy,
    /* Under `adaptive` the flow layer redoes IV-VI (attempt) from the same
     * rhodot (begin_step) with a smaller tau while W would rise at all or
     * the attempt rejects its scale change, max_halvings times per step,
     * and a stall is a step of time step 0 that ends the run. Prescribed
     * and cmc boundaries may raise W by design: no rise check and no
     * divergence check (create). An explicit step on rho can overshoot
     * where the realised curvature change is far from the prescribed one
     * (thin cone tips, slivers; docs/spin.md): the blow-up check (default
     * 10) fails a step whose W jumps, so that the last good state is kept.
     * A descent that creeps above its start has diverged even without a
     * jump (elephant_g3_3k at tau 0.5: W/4pi 24.99 -> 12.46 -> 26.9 ->
     * 102): the divergence check (default 1). Convergence is the method's
     * (end_step; step_policy.c says why). */
    .policy = {.rise_check = 1, .backtrack = 1, .unit = CFI_ENERGY_UNIT_4PI, .rise_exact = 1,
               .halvings_per_step = 1, .stall_as_step = 1, .halving_search = 1, .energy_name = "W", .blowup_check = 1,
               .blowup_default = 10.0, .divergence_check = 1, .divergence_default = 1.0,
               .divergence_cause = " is above this mesh's stability limit",
               .divergence_hint = "adaptive=1 or a larger regularization (docs/spin.md)"},
    /* X(rho)'s eigenvector and the constraints are the whole surface's: on
     * several components each is flowed on its own (methods/flow_parts.c) */
    .per_component = 1,
};
