/*
 * Geometry and discrete operators on a cf_mesh with given positions.
 * Each operator lives in its own source file under src/ops/ and states its
 * sign convention here. Outputs are caller-allocated unless they are sparse
 * matrices (created by the library, freed with cf_sparse_destroy).
 * `positions` is 3 nv doubles; pass cf_mesh_positions(mesh) for the rest
 * shape.
 *
 * Project-wide signs (docs/conventions.md):
 *  - L is the positive semi-definite weak cotan Laplacian:
 *    (L f)_i = sum_j w_ij (f_i - f_j), w_ij = (cot a_ij + cot b_ij) / 2
 *    (one cotangent for a boundary edge). libigl's cotmatrix is -L.
 *  - L x = 2 H N dA (integrated mean-curvature normal), H > 0 on a sphere
 *    with outward normals.
 *  - K_i = 2 pi - sum of corner angles (interior), pi - sum (boundary).
 *
 * Statuses shared by every function below (others are listed where they
 * apply): CF_OK; CF_ERR_INVALID_ARG for a NULL context, mesh, positions,
 * input or output array, or an unknown kind; CF_ERR_NONFINITE when a
 * position is NaN/Inf (the message names the vertex); CF_ERR_DEGENERATE_FACE
 * ("face f: zero area") from the operators that divide by a face area
 * (cotangents, cotan weights and Laplacian, mixed Voronoi areas and mean
 * curvature, face normals, *2, gradient, divergence, harmonic basis);
 * CF_ERR_NOMEM from those that allocate. On failure caller-allocated
 * outputs may hold partial values.
 */
#ifndef CURVFLOW_OPS_H
#define CURVFLOW_OPS_H

#include "curvflow/curvflow.h"
#include "curvflow/linalg.h"
#include "curvflow/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Corner angles: angles[3 f + k] is the angle of face f at corner k. */
CF_API cf_status cf_corner_angles(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *angles);
/* One of them: the angle (radians, in [0, pi]) at corner `corner` (0..2) of
 * the triangle with vertex indices triangle[0..2] into positions (3 nv), as
 * atan2(|u x v|, u . v), accurate near 0 and pi. No checks (a kernel for
 * loops that already validated their input). */
CF_API double cf_corner_angle(const double *positions, const int32_t triangle[3], int corner);

/* Cotangents of corner angles, same layout (cot[3f+k] is the cotangent at
 * corner k, i.e. of the angle opposite halfedge 3f + (k+1)%3). */
CF_API cf_status cf_corner_cotangents(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *cot);

/* Face areas (nf, positive). */
CF_API cf_status cf_face_areas(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *areas);

/* Unit face normals (3 nf), right-hand rule on the corner order. */
CF_API cf_status cf_face_normals(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *normals);

/* Area-weighted unit vertex normals (3 nv). CF_ERR_NUMERICAL when the
 * area vectors around a vertex cancel (no normal). */
CF_API cf_status cf_vertex_normals(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *normals);

typedef enum cf_dual_area_kind {
    CF_DUAL_AREA_BARYCENTRIC = 0, /* a third of each incident face */
    CF_DUAL_AREA_MIXED_VORONOI = 1 /* Meyer et al. 2003 mixed Voronoi cells */
} cf_dual_area_kind;

/* Dual (vertex) areas, nv entries; they sum to the total area. */
CF_API cf_status cf_vertex_areas(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                 cf_dual_area_kind kind, double *areas);

/* Positive semi-definite cotan Laplacian L (nv x nv, symmetric, both
 * triangles stored, sorted, one-pass assembly). */
CF_API cf_status cf_cotan_laplacian(cf_context *ctx, const cf_mesh *mesh, const double *positions, cf_sparse **out);

/* The same L for flows that change the geometry every step: the pattern is
 * built once and the values are refilled in place without allocating.
 * cf_cotan_laplacian_slot_count(mesh) = nv + 2 ne is the size of the
 * caller's slot_map (the diagonal entry of vertex v at v, entries (i, j) and
 * (j, i) of edge e at nv + 2 e and nv + 2 e + 1); _with_slots builds L for
 * `positions` as cf_cotan_laplacian does and fills slot_map; _refill
 * overwrites L's values for new positions (same sign, PSD). The refill does
 * not check positions for finiteness (the caller's step does; NaN gives
 * NaN values) and fails with CF_ERR_DEGENERATE_FACE naming the face on a
 * zero-area face (L then holds partial values). Statuses otherwise as
 * cf_cotan_laplacian; CF_ERR_INVALID_ARG for NULL arguments. */
CF_API int64_t cf_cotan_laplacian_slot_count(const cf_mesh *mesh);
CF_API cf_status cf_cotan_laplacian_with_slots(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                               cf_sparse **out, int64_t *slot_map);
CF_API cf_status cf_cotan_laplacian_refill(cf_sparse *l, const cf_mesh *mesh, const double *positions,
                                           const int64_t *slot_map);

/* Cotan weights per edge, w_e = (cot a + cot b) / 2 (ne entries). This is
 * also the DEC Hodge star *1. */
CF_API cf_status cf_cotan_weights(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *weights);

/* The same operators with a floor on the weights (session 30): each face's
 * cotangents are taken as if twice its area were at least weight_floor (in
 * [0, 1]; 0: exact, the functions above) times the sum of its squared edge
 * lengths. An equilateral face has 0.29, a face with a small angle of t
 * radians about t / 2: a floor of 1e-8 leaves every face with its angles
 * above about 2e-8 rad exact and bounds the weights of a nearly flat face (a
 * near-duplicate vertex) at about 1 / weight_floor, which would otherwise
 * cost every solve on L that many digits (docs/spin.md, "Near-duplicate
 * vertices"; spin-willmore's option weight_floor). Areas, angles and
 * curvature sums are not affected. CF_ERR_INVALID_ARG for a floor outside
 * [0, 1]. */
CF_API cf_status cf_cotan_laplacian_floored(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                            double weight_floor, cf_sparse **out);
CF_API cf_status cf_cotan_laplacian_with_slots_floored(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                                       double weight_floor, cf_sparse **out, int64_t *slot_map);
CF_API cf_status cf_cotan_laplacian_refill_floored(cf_sparse *l, const cf_mesh *mesh, const double *positions,
                                                   double weight_floor, const int64_t *slot_map);
CF_API cf_status cf_cotan_weights_floored(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                          double weight_floor, double *weights);

/* ---- Positions from edge vectors (src/ops/edge_poisson.c) ---------------
 * Least-squares fit of positions f (3 nv) to prescribed edge vectors e~
 * (3 ne, interleaved, e~_e for edge e running i -> j, i < j as in
 * cf_mesh_edge_vertices) in the cotan metric of some surface (Crane et al.
 * 2011; Crane, Pinkall, Schroeder 2013, Eq. (6)):
 *     minimise 1/2 sum_e w_e |f_j - f_i - e~_e|^2,  i.e.  L f = b,
 *     b_i = -sum_{e = (i, j)} w_e e~_e + sum_{e = (j, i)} w_e e~_e,
 * L the positive semi-definite cotan Laplacian and w_e its weights, so that
 * integrable edges (e~_e = g_j - g_i) give b = L g and f = g. The metric is
 * that of the positions given at create (the source surface), or of any
 * later cf_edge_poisson_set_metric (e.g. the target surface); the pattern
 * and the symbolic factorisation are made once. With known vertices their
 * values are fixed (cf_min_quad on the free block, linalg.h); without, L is
 * shifted by 1e-10 times its mean diagonal and the caller fixes the
 * translation (the constant mode is arbitrary up to that shift). No
 * allocation after create. */
typedef struct cf_edge_poisson cf_edge_poisson;

/* positions: 3 nv, the metric's surface (NULL: the mesh's rest positions);
 * known: known_count distinct vertices (0 <= known_count < nv; NULL if 0),
 * copied. Statuses: CF_ERR_INVALID_ARG, CF_ERR_DEGENERATE_FACE,
 * CF_ERR_NOT_POSDEF (a free component with no known vertex), CF_ERR_NOMEM,
 * solver errors. The object keeps `mesh` (it must outlive it). */
CF_API cf_status cf_edge_poisson_create(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                        int32_t known_count, const int32_t *known, cf_edge_poisson **out);
/* The same with L's weights floored as cf_cotan_laplacian_floored's, for
 * this metric and every later one (weight_floor in [0, 1]; 0: exact, as
 * cf_edge_poisson_create). Used by spin-willmore (option weight_floor). */
CF_API cf_status cf_edge_poisson_create_floored(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                                int32_t known_count, const int32_t *known, double weight_floor,
                                                cf_edge_poisson **out);
/* Refills L for the metric of `positions` (3 nv, values only); the next
 * solve refactorises. CF_ERR_DEGENERATE_FACE on a zero-area face. */
CF_API cf_status cf_edge_poisson_set_metric(cf_edge_poisson *p, const double *positions);
/* The same with face f's cotan weights multiplied by face_scale[f] (nf
 * entries, each positive and finite, else CF_ERR_INVALID_ARG naming the
 * face; NULL: 1, as cf_edge_poisson_set_metric): the fit then weighs the
 * misfit of f's edges by that factor, e.g. more where the target surface is
 * smaller than the metric's (spin-willmore's `recovery_scale_weight`).
 * L = sum_f face_scale[f] L_f stays positive semi-definite. */
CF_API cf_status cf_edge_poisson_set_metric_scaled(cf_edge_poisson *p, const double *positions,
                                                   const double *face_scale);
/* Frees what cf_edge_poisson_set_metric needs (the Laplacian's slot map:
 * 8 bytes per vertex and two per edge; 37 MB at 655k vertices) for a solver
 * whose metric seldom or never changes (spin-willmore's input-metric
 * position solve); a later set_metric rebuilds it from the slots the
 * solver keeps (an allocation: CF_ERR_NOMEM, the solver then still frozen
 * and usable), and refills as without the freeze. Solves are unaffected. */
CF_API void cf_edge_poisson_freeze_metric(cf_edge_poisson *p);
/* f from edges (3 ne); fixed: 3 nv interleaved, read at the known vertices
 * only (NULL without known vertices); out: 3 nv interleaved (the known
 * vertices get their fixed values exactly). timings (may be NULL)
 * accumulates factorise / solve seconds. Solver statuses. */
CF_API cf_status cf_edge_poisson_solve(cf_edge_poisson *p, const double *edges, const double *fixed, double *out,
                                       cf_solver_timings *timings);
/* The same fit solved for the displacement from `base` (3 nv, interleaved;
 * NULL: as cf_edge_poisson_solve): L (f - base) = b - L base, with the edge
 * differences e~_e - (base_j - base_i) built per edge. Use it when f is a
 * step away from known positions: the solve's rounding error is then
 * relative to the step, not to the coordinates, which matters where a flow
 * has crowded triangles far below the mesh's scale (docs/spin.md). out may
 * not alias base. */
CF_API cf_status cf_edge_poisson_solve_from(cf_edge_poisson *p, const double *base, const double *edges,
                                            const double *fixed, double *out, cf_solver_timings *timings);
/* (L + shift I) u = b for ncols scalar columns (nv each, column-major) with
 * the current metric, factorising only if the metric changed since the last
 * factorisation (a position solve of the same metric shares it). Only
 * without known vertices (else CF_ERR_INVALID_ARG). */
CF_API cf_status cf_edge_poisson_solve_scalar(cf_edge_poisson *p, int32_t ncols, const double *b, double *u,
                                              cf_solver_timings *timings);
/* The current L (positive semi-definite, both triangles) and the weight
 * w_e = -L_ij of edge e (no check of e). */
CF_API const cf_sparse *cf_edge_poisson_laplacian(const cf_edge_poisson *p);
CF_API double cf_edge_poisson_weight(const cf_edge_poisson *p, int32_t e);
CF_API void cf_edge_poisson_destroy(cf_edge_poisson **p);

/* Integrability (closure) measure of edge vectors against positions:
 * sqrt(sum_e |f_j - f_i - e~_e|^2 / sum_e |e~_e|^2) (0 when every e~ is
 * zero; NaN for NULL arguments). After cf_edge_poisson_solve it is the
 * relative part of e~ that no surface realises (Crane 2013, Sec. 6.4). */
CF_API double cf_edge_closure_error(const cf_mesh *mesh, const double *positions, const double *edges);

/* ---- Spectral filter (src/ops/spectral_filter.c) -------------------------
 * v <- v - (id + sigma' Delta^k)^-1 v for vertex functions v (nv), with
 * Delta = M^-1 L, L the positive semi-definite cotan Laplacian and M the
 * lumped barycentric mass of the surface given at create (Crane, Pinkall,
 * Schroeder 2013, Sec. 4, Fig. 8): an eigenfunction of Delta with
 * eigenvalue mu is multiplied by sigma' mu^k / (1 + sigma' mu^k), so
 * constants vanish and rough components pass. sigma' = sigma R^(2k),
 * R = sqrt(area / (4 pi)): sigma is scale-free. k = 0 is the constant factor
 * sigma / (1 + sigma). The matrix F = M + sigma' L (M^-1 L)^(k-1) is built
 * and factorised once; apply allocates nothing. */
typedef struct cf_spectral_filter cf_spectral_filter;
/* positions: 3 nv (NULL: rest positions); sigma > 0 finite; k in 0..3.
 * Statuses: CF_ERR_INVALID_ARG, CF_ERR_DEGENERATE_FACE, CF_ERR_NOMEM,
 * CF_ERR_NUMERICAL when F cannot be factorised in double precision (sigma'
 * so large that F's constant mode is lost to rounding; the message names
 * the mesh's sizes and the largest sigma / 10^n that works), other
 * factorisation errors. */
CF_API cf_status cf_spectral_filter_create(cf_context *ctx, const cf_mesh *mesh, const double *positions, double sigma,
                                           int32_t k, cf_spectral_filter **out);
/* Filters v (nv) in place; timings (may be NULL) accumulates the solve time. */
CF_API cf_status cf_spectral_filter_apply(cf_spectral_filter *f, double *v, cf_solver_timings *timings);
CF_API void cf_spectral_filter_destroy(cf_spectral_filter **f);

/* ---- Vertex-scale fairing (src/ops/vertex_fairing.c) ---------------------
 * One implicit Laplacian step on positions with unit vertex weights and the
 * cotan Laplacian L0 (positive semi-definite) of the surface given at create:
 *   out = argmin |x - in|^2 + kappa x^T L0 x,  i.e. (I + kappa L0) out = in,
 * with the boundary vertices held at their input positions if asked. L0's
 * weights are scale-free, so kappa is dimensionless and the step is
 * covariant with scaling, also locally: a part of the surface shrunk by s is
 * moved s times as far. An eigenvector of L0 with eigenvalue mu is damped by
 * 1 / (1 + kappa mu): for kappa of order one the modes that change sign from
 * one vertex to the next (mu of order one) are damped, smooth ones
 * (mu ~ 1 / nv) are not. Solved by conjugate gradients preconditioned with
 * the diagonal, to a relative residual of 1e-12 of the change per
 * coordinate (no factorisation is kept: any kappa costs the same). Used by
 * spin-willmore (docs/spin.md, "Vertex-scale fairing"). */
typedef struct cf_vertex_fairing cf_vertex_fairing;
/* positions: 3 nv, the reference surface of L0 (NULL: rest positions);
 * hold_boundary: nonzero keeps boundary vertices in place. Statuses:
 * CF_ERR_INVALID_ARG, CF_ERR_DEGENERATE_FACE, CF_ERR_NOMEM, solver errors. */
CF_API cf_status cf_vertex_fairing_create(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                          int32_t hold_boundary, cf_vertex_fairing **out);
/* The same with L0's weights floored as cf_edge_poisson_create_floored's
 * (weight_floor in [0, 1]; 0: exact). */
CF_API cf_status cf_vertex_fairing_create_floored(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                                  int32_t hold_boundary, double weight_floor,
                                                  cf_vertex_fairing **out);
/* out = the faired positions of in (3 nv each, interleaved; out may equal
 * in). kappa >= 0 (0: a copy). timings (may be NULL) accumulates the solve
 * seconds. Statuses: CF_ERR_INVALID_ARG (kappa negative or not finite),
 * CF_ERR_NUMERICAL (a position of in, or of the result, not finite, named),
 * CF_ERR_NOT_CONVERGED (2000 iterations; not seen on any test mesh). */
CF_API cf_status cf_vertex_fairing_apply(cf_vertex_fairing *f, double kappa, const double *in, double *out,
                                         cf_solver_timings *timings);
/* Conjugate-gradient iterations of the last apply (0 for kappa 0). */
CF_API int32_t cf_vertex_fairing_iterations(const cf_vertex_fairing *f);
CF_API void cf_vertex_fairing_destroy(cf_vertex_fairing **f);

/* ---- Tangential relaxation (src/ops/tangential_relaxation.c) -------------
 * Moves the vertices of a surface within it so that its map from reference
 * triangles is more conformal face by face: descends the MIPS energy
 *   E(x) = sum_f A0_f (Q_f + 1 / Q_f) / 2 = sum_f A0_f |J_f|^2 / (2 det J_f)
 * (A0_f the reference area, J_f the face's linear map from its reference
 * triangle, Q_f the ratio of J_f's singular values; E = sum A0 exactly at a
 * similarity) with every vertex kept on the surface given to apply: after
 * each step a vertex goes to the nearest point of its own star there, so no
 * vertex leaves its star in one call and the shape is the given one's,
 * resampled. No face is inverted (against the surface given). A conformal
 * map sampled at the vertices is not conformal per face where its scale
 * varies across a face (crowded limbs); this spreads the crowding. Used by
 * spin-willmore (option relaxation; docs/spin.md, "Tangential relaxation"). */
typedef struct cf_tangential_relaxation cf_tangential_relaxation;
typedef struct cf_tangential_relaxation_report {
    int32_t iterations;      /* sweeps over the vertices that moved one (fewer than asked at a minimum
                              * within the stars) */
    int32_t trials;          /* vertex moves tried (each a projection and the star's energy) */
    double energy_before;    /* E of the positions given */
    double energy_after;     /* E of the positions returned (<= energy_before) */
} cf_tangential_relaxation_report;
/* E(positions) against the reference triangles (NULL: rest positions) and,
 * if gradient is not NULL, dE/dx (3 nv). One pass over the faces, no
 * allocation. CF_ERR_DEGENERATE_FACE names a reference face without area,
 * or says that a face of positions has none. */
CF_API cf_status cf_mips_energy(cf_context *ctx, const cf_mesh *mesh, const double *reference,
                                const double *positions, double *energy, double *gradient);
/* reference: 3 nv (NULL: rest positions; another is copied); hold_boundary:
 * nonzero keeps the boundary vertices where apply finds them. The arrays of
 * the descent are made by the first apply above its threshold (none below).
 * CF_ERR_DEGENERATE_FACE names a reference face without area; CF_ERR_NOMEM. */
CF_API cf_status cf_tangential_relaxation_create(cf_context *ctx, const cf_mesh *mesh, const double *reference,
                                                 int32_t hold_boundary, cf_tangential_relaxation **out);
/* out = in relaxed by up to `iterations` sweeps (every vertex's move at once) on the surface of in
 * (out may equal in); none while the area-weighted mean of (Q + 1 / Q) / 2
 * against the reference is at most that of min_mean_q (>= 1; 1: always
 * relax). report may be NULL. CF_ERR_INVALID_ARG,
 * CF_ERR_NUMERICAL (a position of in not finite, named),
 * CF_ERR_DEGENERATE_FACE (a face of in has no area; out = in),
 * CF_ERR_NOMEM (the first call above the threshold makes the arrays; out = in). */
CF_API cf_status cf_tangential_relaxation_apply(cf_tangential_relaxation *r, const double *in, int32_t iterations,
                                                double min_mean_q, double *out,
                                                cf_tangential_relaxation_report *report);
CF_API void cf_tangential_relaxation_destroy(cf_tangential_relaxation **r);

typedef enum cf_mass_kind {
    CF_MASS_LUMPED_BARYCENTRIC = 0,
    CF_MASS_LUMPED_VORONOI = 1,
    CF_MASS_GALERKIN = 2          /* consistent P1 mass matrix (not diagonal) */
} cf_mass_kind;

/* Mass matrix M (nv x nv). Lumped kinds are diagonal. */
CF_API cf_status cf_mass_matrix(cf_context *ctx, const cf_mesh *mesh, const double *positions, cf_mass_kind kind,
                                cf_sparse **out);

/* DEC (Desbrun et al. 2008). Orientation: edge e points from
 * edge_vertices[2e] to edge_vertices[2e+1]; a face's boundary runs along its
 * corner order. d0: ne x nv, (d0 f)_e = f_j - f_i. d1: nf x ne, +-1 by
 * whether the face traverses the edge along its orientation. d1 d0 = 0. */
CF_API cf_status cf_dec_d0(cf_context *ctx, const cf_mesh *mesh, cf_sparse **out);
CF_API cf_status cf_dec_d1(cf_context *ctx, const cf_mesh *mesh, cf_sparse **out);
/* Diagonal Hodge stars as vectors: *0 = barycentric dual areas (nv),
 * *1 = cotan weights (ne), *2 = 1 / face area (nf). */
CF_API cf_status cf_dec_star0(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *star0);
CF_API cf_status cf_dec_star1(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *star1);
CF_API cf_status cf_dec_star2(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *star2);

/* Integrated mean-curvature normal hn = L x (3 nv): 2 H N A_i, pointing
 * outward on a convex closed surface. */
CF_API cf_status cf_mean_curvature_normal(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *hn);

/* Pointwise signed mean curvature H_i = <L x, N_i> / (2 A_i) with
 * mixed-Voronoi A_i (Meyer et al. 2003) and area-weighted normal N_i (nv);
 * CF_ERR_NUMERICAL when N_i or A_i vanishes.
 * 1/R on a sphere. (Barycentric A_i does not converge pointwise on
 * irregular meshes: ~15% max error on every refined icosphere, while the
 * Voronoi estimate converges as O(h^2); see docs/ops.md.) */
CF_API cf_status cf_mean_curvature(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *h);

/* Angle defect K_i = 2 pi - sum of angles (interior), pi - sum (boundary:
 * geodesic curvature) so that sum K = 2 pi chi (nv). */
CF_API cf_status cf_angle_defect(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *k);

/* Discrete Willmore energy W = sum_i H_i^2 A_i with H_i = |L x|_i / (2 A_i),
 * barycentric A_i (W = 4 pi on a round sphere in the limit). */
CF_API cf_status cf_willmore_energy(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *energy);

/* Signed enclosed volume (1/6) sum_f x_a . (x_b x x_c); positive for a
 * closed outward-oriented mesh (computed with the x relative to the centre
 * of the bounding box, which changes nothing in exact arithmetic and keeps
 * the digits of a mesh far from the origin). For meshes with boundary it is
 * the volume of the cone from the origin and depends on the origin. */
CF_API cf_status cf_enclosed_volume(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *volume);

/* Total surface area. */
CF_API cf_status cf_total_area(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *area);

/* Piecewise-linear gradient of a vertex function (nv) as one vector per
 * face (3 nf). */
CF_API cf_status cf_gradient(cf_context *ctx, const cf_mesh *mesh, const double *positions, const double *f,
                             double *grad);

/* Integrated divergence of a per-face vector field (3 nf) at vertices (nv),
 * the negative adjoint of the gradient: div = -G^T A_f X, so that
 * div(grad f) = -L f. */
CF_API cf_status cf_divergence(cf_context *ctx, const cf_mesh *mesh, const double *positions, const double *field,
                               double *div);

/* Basis of harmonic 1-forms (Crane 2013, App. C.1) spanning the first
 * cohomology: `dim` columns of ne values each, column-major, orthonormal
 * under the *1 inner product. dim = sum over connected components of 2g on
 * closed components and 2g + b - 1 on components with b > 0 boundary loops
 * (0 on a disk). Each column is closed (d1 h = 0 on every face) and
 * co-closed at every vertex, d0^T *1 h = 0, boundary vertices included: on a
 * surface with boundary these are the Neumann harmonic fields (no flux
 * through the boundary), and a closed 1-form is exact iff it is
 * *1-orthogonal to all of them. *dimension receives dim; `basis` must hold
 * ne * dim doubles (pass NULL to query the dimension only). Deterministic
 * (seeded). Statuses: CF_ERR_INVALID_ARG, CF_ERR_NONFINITE,
 * CF_ERR_DEGENERATE_FACE, CF_ERR_NOMEM, solver errors. */
CF_API cf_status cf_harmonic_basis(cf_context *ctx, const cf_mesh *mesh, const double *positions, int32_t *dimension,
                                   double *basis);

/* cf_harmonic_basis for many position sets of one mesh (a Gauss-Newton
 * projection, a flow's steps): _create factorises the combinatorial
 * d1 d1^T once; the first _compute builds the cotan Laplacian of its
 * positions and analyses it, returning cf_harmonic_basis's forms bit for
 * bit (which is create + compute + destroy); later ones refill and
 * refactorise it without allocating through the context, equal to
 * cf_harmonic_basis to rounding (the refill sums the diagonal in another
 * order: 3e-16 of forms of size 0.08 on a torus). basis: ne * dimension
 * doubles. The workspace keeps `mesh`, which must outlive it. _dimension
 * is dim (0 for NULL). Statuses as cf_harmonic_basis's. */
typedef struct cf_harmonic_workspace cf_harmonic_workspace;
CF_API cf_status cf_harmonic_workspace_create(cf_context *ctx, const cf_mesh *mesh, cf_harmonic_workspace **out);
CF_API int32_t cf_harmonic_workspace_dimension(const cf_harmonic_workspace *workspace);
CF_API cf_status cf_harmonic_workspace_compute(cf_harmonic_workspace *workspace, const double *positions,
                                               double *basis);
CF_API void cf_harmonic_workspace_destroy(cf_harmonic_workspace **workspace);

/* Per-face vector field (3 nf) of a 1-form (ne values, on oriented edges):
 * the Whitney interpolation evaluated at the face barycentre. */
CF_API cf_status cf_one_form_to_vector_field(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                             const double *one_form, double *field);

/* One or more levels of Loop subdivision (Loop 1987; boundary rules of
 * Hoppe et al. 1994). Creates a new mesh whose rest positions are the
 * subdivided ones. Texture coordinates are subdivided linearly.
 * levels: 1 .. 10 (each multiplies the face count by 4). *out receives a
 * new mesh on the same context (free with cf_mesh_destroy), NULL on
 * failure. CF_ERR_INVALID_ARG also when the result would not fit int32
 * counts. */
CF_API cf_status cf_loop_subdivide(cf_context *ctx, const cf_mesh *mesh, const double *positions, int32_t levels,
                                   cf_mesh **out);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_OPS_H */
