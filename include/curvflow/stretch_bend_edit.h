/*
 * Interactive mesh editing with a stretching + bending energy (Zhao &
 * Gortler, "A Report on Shape Deformation with a Stretching and Bending
 * Energy"), together with the ARAP energies it is compared against.
 *
 * Energies (x = rest positions, x' = deformed positions, cot a_vw = cotangent
 * of the corner opposite halfedge v->w in the REST mesh, W_vw = cot a_vw +
 * cot a_wv, M_v = rest dual area, (K f)_v = sum_w W_vw (f_v - f_w), which is
 * twice the project's L):
 *   stretch   E_s  = sum_halfedges cot a_vw |(x'_v - x'_w) - R_t (x_v - x_w)|^2     (Eq. 5)
 *   bend      E_db = sum_v M_v |(K x')_v / M_v - |H_v| u'_v|^2, |H_v| = |(K x)_v| / M_v   (Eq. 15)
 *   hybrid    E_t  = (lambda / A) E_s + (1 - lambda) E_db                          (Eq. 17)
 *   arap      sum_v sum_{w in N(v)} W_vw |(x'_v - x'_w) - R_v (x_v - x_w)|^2     (Eq. 6)
 *   arap-rims sum_v sum_{(m,n) in E(v)} W_mn |(x'_m - x'_n) - R_v (x_m - x_n)|^2 (Eq. 7)
 * with one rotation R_t per triangle (stretch) or R_v per vertex (ARAP), and
 * one unit vector u'_v per vertex (bend). E(v) is the set of spoke and rim
 * edges of the triangles around v, each edge once with its full weight W.
 * A is the total rest area when `scale_free` is set (default), else 1: it
 * makes lambda independent of the model's size (the paper notes E_s scales
 * with the square of the size while E_db does not). "stretch" and "bend" are
 * the hybrid at lambda = 1 and 0.
 *
 * The energies are minimised by local/global iteration (Sec. 4): one flow
 * step (cf_flow_step on a CF_FLOW_STRETCH_BEND_EDIT flow) is one global
 * solve (Eq. 23, handle vertices moved to the right-hand side, matrix
 * factorised once per handle set, three right-hand sides) followed by one
 * local step (Procrustes rotations with determinant correction, Eq. 24, and
 * u' = normalised K x'). The energy reported after a step is E(x') with the
 * optimal rotations, so it never increases from step to step (also with
 * Anderson acceleration, on by default for hybrid/stretch/bend, which keeps
 * a mixed step only if it lowers the energy). The first step after create,
 * reset or new handles tries the rotations of the state before the handles
 * moved and those of the snapped state, and keeps the better result.
 *
 * Note: E(v) in Eq. 7 uses the full weight W of every edge, as printed; it
 * reproduces App. B's table but, unlike CGAL's per-face variant, is not
 * positive semi-definite when W < 0 (non-Delaunay edges); ARAP spokes has the
 * same property (the paper's Fig. 8). Details and measurements: docs/edit.md.
 *
 * Names: folder src/methods/stretch_bend_edit, flow kind "stretch-bend-edit"
 * (CF_FLOW_STRETCH_BEND_EDIT), public prefix cf_stretch_bend_ / CF_STRETCH_BEND_,
 * internal cfi_stretch_bend_. The command `curvflow edit` is a front end on
 * `curvflow flow --method stretch-bend-edit` (docs/edit.md).
 */
#ifndef CURVFLOW_STRETCH_BEND_EDIT_H
#define CURVFLOW_STRETCH_BEND_EDIT_H

#include "curvflow/constraints.h"
#include "curvflow/curvflow.h"
#include "curvflow/flow.h"
#include "curvflow/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum cf_stretch_bend_energy_kind {
    CF_STRETCH_BEND_HYBRID = 0,    /* lambda E_s + (1 - lambda) E_db (Eq. 17) */
    CF_STRETCH_BEND_STRETCH = 1,   /* E_s only (Eq. 5), lambda = 1 */
    CF_STRETCH_BEND_BEND = 2,      /* E_db only (Eq. 15), lambda = 0 */
    CF_STRETCH_BEND_ARAP = 3,      /* ARAP spokes, per-vertex rotations (Eq. 6) */
    CF_STRETCH_BEND_ARAP_RIMS = 4, /* ARAP spokes and rims (Eq. 7) */
    CF_STRETCH_BEND_ENERGY_COUNT = 5
} cf_stretch_bend_energy_kind;

/* "hybrid", "stretch", "bend", "arap", "arap-rims"; NULL if out of range. */
CF_API const char *cf_stretch_bend_energy_name(cf_stretch_bend_energy_kind energy);
/* CF_ERR_INVALID_ARG with a message listing the names for an unknown name. */
CF_API cf_status cf_stretch_bend_energy_from_name(cf_context *ctx, const char *name, cf_stretch_bend_energy_kind *energy);

/* Dual area M_v of the bending energy (the paper suggests Voronoi). */
typedef enum cf_stretch_bend_mass {
    CF_STRETCH_BEND_MASS_VORONOI = 0,      /* Meyer et al. mixed Voronoi cells */
    CF_STRETCH_BEND_MASS_BARYCENTRIC = 1
} cf_stretch_bend_mass;

/* Edge weights of the ARAP energies (Eq. 6, 7): W = cot a + cot b is
 * negative on an edge whose opposite angles sum to more than pi (a
 * non-Delaunay edge), and there the energy is not bounded below: a needle
 * triangle beside a vertex lets the iteration pull that vertex far off
 * while the energy goes negative (docs/edit.md, "ARAP edge weights"). */
typedef enum cf_stretch_bend_arap_weights {
    CF_STRETCH_BEND_ARAP_COTAN = 0,   /* W as the paper writes it (default) */
    CF_STRETCH_BEND_ARAP_CLAMPED = 1  /* max(W, 0): a sum of squares, bounded below by 0 */
} cf_stretch_bend_arap_weights;

/* ---- Handles ------------------------------------------------------------ */

/* The handles are a cf_handle_set (vertices with target positions) of the
 * constraints module (curvflow/constraints.h, included here): made from
 * arrays (cf_handle_set_create), from a point set and a rigid transform
 * (cf_handle_set_from_points) or read from a JSON handle file
 * (cf_handle_set_read_json). */

/* ---- Options and flow ---------------------------------------------------- */

typedef struct cf_stretch_bend_options {
    int32_t energy;              /* cf_stretch_bend_energy_kind, default CF_STRETCH_BEND_HYBRID */
    double lambda;               /* hybrid weight in [0, 1], default 0.5 */
    int32_t max_iterations;      /* for cf_stretch_bend_edit and the CLI, default 100 */
    double relative_tolerance;   /* converged when (E_prev - E) / E_prev < tol, default 1e-6 */
    int32_t mass;                /* cf_stretch_bend_mass, default CF_STRETCH_BEND_MASS_VORONOI */
    int32_t scale_free;          /* 1: stretch term divided by total rest area (default) */
    int32_t anderson;            /* Anderson acceleration of the local/global fixed-point map with this
                                    many past iterates (0 = off, at most 10; default -1 = 5 for hybrid,
                                    stretch and bend, 0 for the ARAP energies). A step is kept only if it
                                    lowers the energy, else the plain step is taken, so the energy still
                                    never increases. */
    int32_t arap_weights;        /* cf_stretch_bend_arap_weights of the ARAP energies, default
                                    CF_STRETCH_BEND_ARAP_COTAN; the other energies ignore it */
    const cf_handle_set *handles;   /* table parameter "handles" (point set, required): copied by create
                                       (a caller may free it once create returned) */
    const double *rest_positions;   /* 3 nv rest pose, NULL = the mesh's positions; copied by create */
} cf_stretch_bend_options;

CF_API void cf_stretch_bend_options_default(cf_stretch_bend_options *options);

/* Replaces the handle set of a running CF_FLOW_STRETCH_BEND_EDIT flow:
 * refactorises the system and moves the handle vertices of the current
 * state to their targets; the next step continues from the current state.
 * (To restart from the rest pose, call cf_flow_set_positions with it.)
 * Statuses: CF_ERR_INVALID_ARG (not such a flow, bad handles),
 * CF_ERR_NOT_POSDEF (indefinite ARAP system), CF_ERR_NOMEM. */
CF_API cf_status cf_stretch_bend_set_handles(cf_flow *flow, const cf_handle_set *handles);

/* Convenience: runs up to options->max_iterations local/global iterations
 * (stopping at the relative tolerance) from `start` (3 nv, NULL = rest pose)
 * and writes the result into out_positions (3 nv, caller-allocated).
 * info (may be NULL) receives the last step's info. */
CF_API cf_status cf_stretch_bend_edit(cf_context *ctx, const cf_mesh *mesh, const double *start,
                                      const cf_stretch_bend_options *options, double *out_positions,
                                      cf_flow_info *info);

/* Energy terms of a deformed state without handles: E(x') minimised over
 * the rotations (and u'), as in App. B's tables. energy selects which
 * rotation sets are used; the outputs that do not apply are set to 0:
 *   stretch  = E_s (Eq. 5), bend = E_db (Eq. 15)  for hybrid/stretch/bend,
 *   arap     = E_arap (Eq. 6) or E_arap-SR (Eq. 7) for arap/arap-rims,
 *   total    = the energy the method minimises (hybrid weighting included).
 * rest (3 nv, NULL = mesh positions), deformed (3 nv). Any output may be NULL. */
CF_API cf_status cf_stretch_bend_energy(cf_context *ctx, const cf_mesh *mesh, const double *rest,
                                        const double *deformed, const cf_stretch_bend_options *options,
                                        double *stretch, double *bend, double *arap, double *total);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_STRETCH_BEND_EDIT_H */
