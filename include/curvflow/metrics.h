/*
 * Shape metrics: comparison of two position sets on one connectivity
 * (quasi-conformal error, area distortion, angle change), single-shape
 * summaries (area, volume, Willmore energy, Gauss-Bonnet check, best-fit
 * sphere), similarity alignment (Umeyama) and vertex-to-surface distance.
 * The 3 x 3 SVD and closest-rotation kernels live in the linear-algebra
 * layer (curvflow/svd3.h, included here for existing callers).
 *
 * Matrices are 3 x 3 row-major (m[3 r + c]). Per-face/per-vertex outputs are
 * caller-allocated and optional (NULL skips them).
 */
#ifndef CURVFLOW_METRICS_H
#define CURVFLOW_METRICS_H

#include "curvflow/curvflow.h"
#include "curvflow/mesh.h"
#include "curvflow/svd3.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- statistics ---------------------------------------------------------- */

typedef struct cf_stats {
    int64_t count;
    double min, max;
    double mean;           /* plain mean */
    double weighted_mean;  /* weighted by the given weights (areas) */
    double weighted_std;   /* weighted standard deviation about weighted_mean */
    double p50, p95;       /* unweighted percentiles (nearest rank) */
} cf_stats;

/* Statistics of n values (weights NULL: uniform). Allocates a sorted copy
 * through the context for the percentiles. Non-finite values give
 * CF_ERR_NONFINITE naming the index. */
CF_API cf_status cf_stats_compute(cf_context *ctx, int64_t n, const double *values, const double *weights,
                                  cf_stats *out);

/* ---- comparisons on one connectivity ------------------------------------ */

/* Quasi-conformal error per face (Sander et al. 2001): the ratio
 * sigma_max / sigma_min >= 1 of the singular values of the affine map from
 * the triangle in `a` to the triangle in `b`, each expressed in its own
 * orthonormal 2D frame. 1 for a similarity. q: nf (optional); stats
 * weighted by the face areas in `a` (optional). */
CF_API cf_status cf_quasi_conformal_error(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b,
                                          double *q, cf_stats *stats);

/* Log area distortion per face, log(A_b / A_a) after scaling `b` so that
 * both total areas are equal (so a uniform scaling gives 0 everywhere).
 * out: nf (optional); stats weighted by face areas in `a` (optional):
 * weighted_mean and weighted_std are the figures usually quoted. */
CF_API cf_status cf_log_area_distortion(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b,
                                        double *out, cf_stats *stats);

/* Per-vertex angle change: the largest |theta_b - theta_a| (radians) over
 * the vertex's corners. out: nv (optional); stats unweighted over vertices,
 * weighted by barycentric areas of `a` (optional). */
CF_API cf_status cf_angle_change(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b,
                                 double *out, cf_stats *stats);

/* The conformal part of a map between two position sets on one
 * connectivity. Log scale factors u at the vertices are fitted to the
 * change of edge lengths by least squares,
 *   min_u sum over edges ij of (u_i + u_j - 2 log(|e_ij|_b / |e_ij|_a))^2,
 * the edge rescaling |e_ij| -> e^((u_i + u_j) / 2) |e_ij| of discrete
 * conformal equivalence (Luo 2004; Springborn, Schroeder, Pinkall 2008).
 * Each face's model Q is the quasi-conformal error from its triangle in `a`
 * to the triangle with the rescaled lengths: the distortion that the
 * variation of the conformal scale across the face causes by itself, which
 * no map of that scale avoids on this triangulation (an exactly conformal
 * map sampled at the vertices of a tube of n sides, crowded as a limb is
 * under a conformal map, has mean Q 2.18 / 1.77 / 1.45 for n = 6 / 8 / 12:
 * docs/ops.md). A Moebius transformation is fitted exactly (no residual,
 * model Q = Q). When the model Q is close to cf_quasi_conformal_error's,
 * the map is as conformal as its scale allows; the residual is the part of
 * the length change that no vertex scale explains. */
typedef struct cf_vertex_scale_fit {
    cf_stats q;            /* model Q over the faces whose rescaled lengths form a triangle, weighted by areas in a */
    int32_t invalid_faces; /* faces whose rescaled lengths violate the triangle inequality (no model triangle) */
    double rms_residual;   /* RMS over edges of log(|e|_b / |e|_a) - (u_i + u_j) / 2 */
} cf_vertex_scale_fit;

/* u: nv (optional), the fitted log scales (unique: a uniform scaling of b
 * by s adds log s to every u_i); q: nf (optional),
 * the model Q per face, NaN for the invalid faces; result: optional.
 * Statuses: CF_OK, CF_ERR_INVALID_ARG (NULL mesh or positions),
 * CF_ERR_NONFINITE (a coordinate NaN or infinite, naming the vertex),
 * CF_ERR_DEGENERATE_FACE (an edge of zero length in a or b, naming it),
 * CF_ERR_NUMERICAL (no face has a model triangle), CF_ERR_NOT_CONVERGED
 * (the normal equations' conjugate gradients past 2000 iterations; 22-26
 * on every mesh tried, docs/ops.md), CF_ERR_NOMEM. */
CF_API cf_status cf_vertex_scale_fit_compute(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b,
                                             double *u, double *q, cf_vertex_scale_fit *result);

/* The two means of the split above for a check made at every step, with no
 * allocation: *mean_q, the area-weighted mean Q of the map a -> b
 * (cf_quasi_conformal_error's weighted_mean; infinite if a face of b has no
 * area), and *mean_model_q, its vertex-scale model's over the faces that
 * have one (cf_vertex_scale_fit_compute's q.weighted_mean; NaN if none).
 * *mean_q - *mean_model_q is the map's distortion that no vertex scale
 * explains. work: cf_conformal_excess_work_size(mesh) doubles. Statuses as
 * cf_vertex_scale_fit_compute's, and CF_ERR_INVALID_ARG for a NULL work or
 * output. */
CF_API int64_t cf_conformal_excess_work_size(const cf_mesh *mesh);
CF_API cf_status cf_conformal_excess(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b,
                                     double *work, double *mean_q, double *mean_model_q);

/* ---- conformal class (closed surfaces of genus >= 1) ----------------------- */

/* The conformal class of a closed connected surface of genus g >= 1, from
 * its discrete harmonic 1-forms (cotan metric) and the periods along 2g
 * homology cycles that the connectivity alone fixes (a tree-cotree split),
 * so that two position sets of one mesh are compared on the same marked
 * cycles (docs/ops.md, "Conformal class"). */
typedef struct cf_conformal_class {
    int32_t genus;
    double modulus[2];         /* genus 1: tau = modulus[0] + i modulus[1] with C / (Z + tau Z) conformally
                                * equivalent, in the standard fundamental domain (|Re| <= 1/2, |tau| >= 1; a torus
                                * of revolution with radii R > r: i sqrt(R^2 - r^2) / r or its inverse); NaN for
                                * genus > 1 */
    double intersection_error; /* largest distance of the dual forms' intersection numbers from integers: rounding
                                * (a check of the computation) */
    double hodge_defect;       /* |det(G)^(1/2g) - 1| for the Gram matrix G below, 0 for a smooth surface */
} cf_conformal_class;

/* gram (optional, (2g)^2 doubles, column-major): G, the *1 Gram matrix of
 * the harmonic forms dual to the marked cycles (period 1 along one, 0 along
 * the others), a complete invariant of the marked conformal class.
 * Statuses: CF_ERR_INVALID_ARG (NULL), CF_ERR_NONFINITE (naming the vertex),
 * CF_ERR_BAD_MESH (several components, a boundary, genus 0),
 * CF_ERR_DEGENERATE_FACE, CF_ERR_NUMERICAL, CF_ERR_NOMEM, solver errors. */
CF_API cf_status cf_conformal_class_compute(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                            double *gram, cf_conformal_class *out);

/* Distance between the marked conformal classes of two position sets of
 * one mesh: sqrt(sum log^2 mu / 2) over the eigenvalues mu of
 * G^_a^-1 G^_b, the classes alone (cf_conformal_class_normalize; before
 * session 38 of G_a^-1 G_b scaled to det 1, the same for genus 1). 0 for
 * conformally equivalent positions (up to the discretisation); for genus 1
 * the hyperbolic distance between the two moduli (before their reduction
 * to the fundamental domain). class_a and
 * class_b (each may be NULL) receive cf_conformal_class_compute's for a and
 * b from the same harmonic forms. Statuses as cf_conformal_class_compute's. */
CF_API cf_status cf_conformal_class_distance(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b,
                                             cf_conformal_class *class_a, cf_conformal_class *class_b,
                                             double *distance);

/* G of cf_conformal_class_compute (gram, (2g)^2 doubles, required) and,
 * if gradient is not NULL, its derivative in the positions: for each pair
 * k <= l in the order (0,0), (0,1), (1,1), (0,2), ... (m = g (2g + 1)
 * pairs), 3 nv doubles d G_kl / d x. The harmonic representatives are held
 * fixed in it: they minimise the Dirichlet energy within their cohomology
 * class, so their own change does not enter at first order. G here is
 * summed face by face as area <v_k, v_l> of the forms' constant fields,
 * equal to cf_conformal_class_compute's (P^T P)^-1 up to rounding.
 * Statuses as cf_conformal_class_compute's. */
CF_API cf_status cf_conformal_class_gram_gradient(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                                  double *gram, double *gradient);

/* cf_conformal_class_gram_gradient for many position sets of one mesh (a
 * Gauss-Newton projection): the marked cycles found and the harmonic
 * forms' factorisations analysed once (cf_harmonic_workspace); the first
 * call returns what cf_conformal_class_gram_gradient returns bit for bit,
 * later ones to rounding (the harmonic workspace's refill). The workspace
 * keeps `mesh`, which must outlive it. Statuses as
 * cf_conformal_class_gram_gradient's (create: CF_ERR_BAD_MESH for a surface
 * that is not closed, connected and of genus >= 1). */
typedef struct cf_conformal_class_workspace cf_conformal_class_workspace;
CF_API cf_status cf_conformal_class_workspace_create(cf_context *ctx, const cf_mesh *mesh,
                                                     cf_conformal_class_workspace **out);
CF_API cf_status cf_conformal_class_workspace_gram_gradient(cf_conformal_class_workspace *workspace,
                                                            const double *positions, double *gram, double *gradient);
CF_API void cf_conformal_class_workspace_destroy(cf_conformal_class_workspace **workspace);

/* The intersection form I_jk = int eta_j ^ eta_k of the harmonic forms dual
 * to the marked cycles (form: (2g)^2 doubles, column-major; integers,
 * antisymmetric, det 1, the same for every position set of the mesh).
 * Statuses as cf_conformal_class_compute's, and CF_ERR_NUMERICAL where the
 * computed numbers are not within 1/4 of integers. */
CF_API cf_status cf_conformal_class_intersection_form(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                                      double *form);

/* The class alone from G: the discrete Hodge star S = I^-1 G misses the
 * smooth surface's S^2 = -1 by O(h^2) (`hodge_defect` is one of those
 * g^2 numbers), so G has g (2g + 1) entries where a marked class has
 * g (g + 1) degrees of freedom. normalized (dim x dim) receives
 * G^ = I J with J = S (-S^2)^-1/2, the complex structure nearest S (the
 * Newton iteration S <- (S - S^-1) / 2): symmetric, positive, J^2 = -1,
 * unchanged by G -> c G, equal to G for a smooth surface, and two position
 * sets are conformally equivalent exactly when their G^ agree. Genus 1:
 * G^ = G / sqrt(det G). If derivative is not NULL, it receives the
 * pairs x pairs matrix (column-major, pairs = g (2g + 1), the pair order of
 * cf_conformal_class_gram_gradient) of d G^_p / d G_q, G_q moved in both of
 * its symmetric entries; its rank is g (g + 1). Statuses: CF_ERR_INVALID_ARG
 * (NULL, dim not even and positive, I singular), CF_ERR_NONFINITE,
 * CF_ERR_NUMERICAL (no complex structure: G not positive definite or I not
 * antisymmetric), CF_ERR_NOMEM. */
CF_API cf_status cf_conformal_class_normalize(cf_context *ctx, int32_t dim, const double *form, const double *gram,
                                              double *normalized, double *derivative);

/* ---- single-shape summary -------------------------------------------------- */

typedef struct cf_shape_summary {
    double area;
    double volume;                 /* signed enclosed volume */
    double willmore;               /* cf_willmore_energy */
    double willmore_over_4pi;
    double total_angle_defect;     /* sum K_i */
    double gauss_bonnet_target;    /* 2 pi chi */
    double sphere_center[3];       /* least-squares (geometric) sphere fit */
    double sphere_radius;
    double sphere_max_deviation;   /* max_i | |x_i - c| - R | / R */
    double sphere_rms_deviation;   /* RMS of the same, / R */
} cf_shape_summary;

CF_API cf_status cf_shape_summary_compute(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                          cf_shape_summary *out);

/* Least-squares sphere through n points (3 n doubles): algebraic fit
 * refined by Gauss-Newton on sum (|x_i - c| - R)^2. max_dev and rms_dev are
 * relative to R (either may be NULL). Needs n >= 4 non-coplanar points
 * (CF_ERR_NUMERICAL otherwise). */
CF_API cf_status cf_fit_sphere(cf_context *ctx, int32_t n, const double *points, double center[3], double *radius,
                               double *max_dev, double *rms_dev);

/* ---- alignment and distances ---------------------------------------------- */

/* Similarity y ~ scale * rotation * x + translation minimising
 * sum w_i |y_i - (s R x_i + t)|^2 over rotations (no reflection), s > 0 and t
 * (Umeyama 1991). source, target: 3 n; weights: n or NULL. rms (optional)
 * receives the weighted RMS residual. with_scale = 0 fixes s = 1 (rigid). */
CF_API cf_status cf_similarity_align(cf_context *ctx, int32_t n, const double *source, const double *target,
                                     const double *weights, int with_scale, double rotation[9], double *scale,
                                     double translation[3], double *rms);

/* out_i = s R x_i + t for n points (x, out: 3 n; out may equal x). Does
 * nothing when a pointer is NULL or n is out of range. */
CF_API void cf_similarity_apply(int32_t n, const double rotation[9], double scale, const double translation[3],
                                const double *x, double *out);

/* Distance from each of n points to the nearest point on the triangles of
 * `mesh` at `positions` (bounding-volume hierarchy, exact point-triangle
 * distance). dist: n (optional); max_dist/rms_dist optional; argmax
 * (optional) the index of the farthest point. */
CF_API cf_status cf_point_to_surface_distance(cf_context *ctx, int32_t n, const double *points,
                                              const cf_mesh *mesh, const double *positions, double *dist,
                                              double *max_dist, double *rms_dist, int32_t *argmax);

/* Convenience for shape reconstruction on one connectivity: aligns `a` to
 * `b` by cf_similarity_align (vertex correspondence, uniform weights;
 * with_scale = 0 for rigid only), then measures the distance from each
 * aligned vertex of `a` to the surface of `b`. max_dist / rms_dist
 * (optional) are in the units of `b`; scale (optional) receives the scale
 * applied to `a`. */
CF_API cf_status cf_aligned_surface_distance(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b,
                                             int with_scale, double *max_dist, double *rms_dist, double *scale);

/* ---- mesh quality summary ------------------------------------------------- */

/* The corner-angle and face-area figures of `curvflow info` (and of the
 * Python package's curvflow.info). Angles in radians; medians are the
 * element n / 2 of the sorted values (upper median); "below 10 degrees"
 * compares angle * 180 / pi < 10. */
typedef struct cf_mesh_quality {
    double min_angle, median_angle, max_angle;      /* over all 3 nf corners */
    double fraction_angles_below_10_degrees;        /* of all corners */
    double median_face_min_angle;                   /* over faces, of each face's smallest angle */
    double fraction_faces_min_below_10_degrees;     /* faces whose smallest angle is below 10 degrees */
    double total_area;                              /* face areas summed in face order */
    double min_face_area, median_face_area, max_face_area;
    double willmore_over_4pi;                       /* cf_willmore_energy / 4 pi; NaN with boundary loops */
    double volume;                                  /* cf_enclosed_volume; NaN with boundary loops */
} cf_mesh_quality;

/* Fills `out` for `mesh` at `positions` (3 nv; NULL = the rest positions).
 * Statuses: CF_OK, CF_ERR_INVALID_ARG (NULL mesh or out), CF_ERR_NONFINITE
 * (a coordinate NaN, infinite or beyond CF_MAX_COORDINATE, naming the
 * vertex), CF_ERR_NOMEM; out is untouched on failure. */
CF_API cf_status cf_mesh_quality_compute(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                         cf_mesh_quality *out);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_METRICS_H */
