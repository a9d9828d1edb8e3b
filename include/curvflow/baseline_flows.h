/*
 * Baseline curvature flows the papers compare against, on the common flow
 * interface (curvflow/flow.h):
 *
 *   explicit-mcf           x <- x - tau M^-1 L x                  energy: area
 *   implicit-mcf           (M + tau L) x' = M x, L and M of x     energy: area
 *                          (Desbrun, Meyer, Schroeder, Barr 1999, backward Euler)
 *   conformal-mcf          (M + tau L0) x' = M x, L0 of the initial mesh, M of x
 *                          (Kazhdan, Solomon, Ben-Chen 2012)      energy: area
 *   explicit-bilaplacian   x <- x - tau M^-1 L M^-1 L x           energy: (1/2) x^T L M^-1 L x
 *   implicit-bilaplacian   (M + tau L M^-1 L) x' = M x            energy: (1/2) x^T L M^-1 L x
 *
 * With boundary=fixed (the bi-Laplacian flows' default; see
 * cf_baseline_boundary) the boundary vertices B are held and the others I
 * move: explicit steps update x_I only, with the bi-Laplacian's inner
 * M^-1 L x restricted to I (the gradient of its interior energy), and the
 * implicit ones solve for x_I with x_B on the right-hand side:
 *   MCF           (M_II + tau L_II) x_I' = M_II x_I - tau L_IB x_B
 *   bi-Laplacian  (M_II + tau L_II M_II^-1 L_II) x_I' = M_II x_I - tau L_II M_II^-1 L_IB x_B
 *
 * L is the positive semi-definite cotan Laplacian and M the lumped mass
 * matrix (curvflow/ops.h), both of the current positions unless stated.
 * The bi-Laplacian energy is the squared L2 norm of the discrete
 * mean-curvature normal, (1/2) sum_i |(L x)_i|^2 / m_i = 2 sum_i H_i^2 m_i,
 * i.e. twice the discrete Willmore energy (Willmore-like; it is not
 * invariant under Moebius transformations and differs from cf_willmore_energy
 * by the factor 2 only).
 *
 * Time steps are scale-free. The actual step tau is
 *   explicit-mcf           time_step * h^2      (h: mean edge length of the start shape)
 *   explicit-bilaplacian   time_step * h^4
 *   implicit-mcf, conformal-mcf   time_step * A0    (A0: total area of the start shape)
 *   implicit-bilaplacian   time_step * A0^2
 * so that a uniformly scaled mesh follows the same (scaled) path. The
 * explicit flows default to time_step 0, "auto": each step takes 0.9 (MCF) or
 * 0.5 (bi-Laplacian) of forward Euler's stability limit on the current mesh,
 * from a Gershgorin bound of M^-1 L (slivers and small triangles lower it).
 * Given explicitly, they are stable for time_step below about 1/3 (MCF) and
 * 1/20 (bi-Laplacian) on near-equilateral meshes; above the limit the step is
 * rejected with CF_ERR_NUMERICAL as soon as an explicit step raises the
 * energy at all (beyond a 1e-9 relative rounding slack: below the limit
 * forward Euler on these gradient flows lowers it, an unstable mode raises
 * it), and the previous state is kept.
 */
#ifndef CURVFLOW_BASELINE_FLOWS_H
#define CURVFLOW_BASELINE_FLOWS_H

#include "curvflow/flow.h"
#include "curvflow/ops.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cf_baseline_options {
    /* Scale-free time step (see above). Parameter "time_step". */
    double time_step;
    /* Lumped mass: CF_MASS_LUMPED_BARYCENTRIC (0) or CF_MASS_LUMPED_VORONOI
     * (1) (a cf_mass_kind value). Parameter "mass" = barycentric | voronoi. */
    int32_t mass;
    /* Nonzero: after each step scale about the centroid and translate so that
     * total area and (mass-weighted) centroid equal the start shape's, as
     * Kazhdan et al. 2012 do. Parameter "rescale". */
    int32_t rescale;
    /* The flow reports convergence when the relative energy decrease of a
     * step is below this (0: never). Parameter "tolerance". */
    double tolerance;
    /* What happens at the boundary of a mesh with boundary (a
     * cf_baseline_boundary value; parameter "boundary" = free | fixed). */
    int32_t boundary;
    /* Floor on the cotan weights of L (cf_cotan_laplacian_floored): a face
     * weighs as if twice its area were at least this times the sum of its
     * squared edges. Default 0: the exact weights, the classical operators.
     * 1e-8 bounds the weights of a near-duplicate vertex, which otherwise
     * make the explicit flows' automatic step vanish and cost the implicit
     * solves their accuracy (docs/flowcli.md). Parameter "weight_floor",
     * session 30. */
    double weight_floor;
} cf_baseline_options;

/* Boundary conditions of the baseline flows.
 *  - FREE: the natural boundary condition of the energy: boundary vertices
 *    move like the others (MCF shrinks the boundary curve along with the
 *    surface). The default of the three MCF flows.
 *  - FIXED: boundary vertices are held where they start (Dirichlet), and the
 *    bi-Laplacian energy sums over the interior vertices only,
 *    (1/2) sum_{i interior} |(L x)_i|^2 / m_i: the fairing problem of a
 *    patch with its border given. The default of the two bi-Laplacian
 *    flows: with a free boundary their step is not a descent of their
 *    energy at a boundary (a flat sheet's energy, all of it in the boundary
 *    rows of L x, rises at first order in the step: plane_841's goes
 *    139.98 -> 481.88 in 10 explicit steps; the implicit flow stops at step
 *    1). On closed meshes both are the same. */
typedef enum cf_baseline_boundary {
    CF_BASELINE_BOUNDARY_FREE = 0,
    CF_BASELINE_BOUNDARY_FIXED = 1
} cf_baseline_boundary;

/* Defaults of one baseline kind (explicit/implicit MCF, conformal MCF,
 * explicit/implicit bi-Laplacian): chosen stable and visibly smoothing in
 * about 10 steps. CF_ERR_INVALID_ARG for another kind. */
CF_API cf_status cf_baseline_options_default(cf_flow_kind kind, cf_baseline_options *options);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_BASELINE_FLOWS_H */
