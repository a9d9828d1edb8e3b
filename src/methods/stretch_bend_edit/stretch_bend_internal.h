/*
 * Internal interface of the stretch/bend editing method: the energy model
 * (terms, rotations, bending data) shared by the flow and the energy
 * evaluation, so tests can reach the pieces.
 */
#ifndef CF_METHODS_STRETCH_BEND_EDIT_STRETCH_BEND_INTERNAL_H
#define CF_METHODS_STRETCH_BEND_EDIT_STRETCH_BEND_INTERNAL_H

#include "core/core.h"
#include "curvflow/linalg.h"
#include "curvflow/stretch_bend_edit.h"
#include "mesh/mesh_internal.h"

/* The rotation part of every energy is a sum of "terms"
 *     w |(x'_i - x'_j) - R_r (x_i - x_j)|^2
 * grouped by rotation r (one per face for E_s, one per vertex for ARAP).
 * The bending part is sum_v (|(K x')_v| - hm_v)^2 / M_v at the optimal u'. */
typedef struct cfi_stretch_bend_model {
    cf_context *ctx;         /* set by init (NULL: nothing to free) */
    cfi_workspace ws;        /* every array below the model owns (not rhs, hu) */
    const cf_mesh *mesh;
    int32_t nv;
    cf_stretch_bend_energy_kind energy;
    double alpha;            /* weight of the term energy in the total */
    double beta;             /* weight of the bending energy in the total */
    int32_t term_count;
    int32_t rot_count;
    int32_t *rot_offsets;    /* rot_count + 1 */
    int32_t *term_ij;        /* 2 term_count */
    double *term_w;          /* term_count */
    double *term_e;          /* 3 term_count, rest x_i - x_j */
    double *rest_sq;         /* rot_count: sum w |e|^2 */
    double *rotations;       /* 9 rot_count, row-major */
    double *quats;           /* 4 rot_count (w, x, y, z) warm start, per-vertex rotations (ARAP) */
    double *frames;          /* 9 nf rest frames b1, b2, n (stretch: rotation per face) */
    double *term_a;          /* 2 term_count: rest edge in its face's frame (stretch) */
    int32_t per_face;        /* rotations are per face (stretch) rather than per vertex */
    int64_t svd_fallbacks;   /* local steps that needed the full SVD (statistics) */
    double *rhs;             /* 3 nv interleaved, not owned: when set, the local step also
                                assembles the next global step's right-hand side into it */
    double *hu;              /* 3 nv interleaved scratch for |H| u', not owned (with rhs) */
    double *covariance;      /* 9 rot_count, scratch */
    cf_sparse *k;            /* K = 2 L (rest), only when beta > 0 */
    double *mass;            /* nv rest dual areas M_v (beta > 0) */
    double *hm;              /* nv |(K x)_v| at rest = M_v |H_v| (beta > 0) */
    double *u;               /* 3 nv interleaved unit vectors u' (beta > 0) */
    double *xcol;            /* 3 nv scratch */
    double *kx;              /* 3 nv interleaved scratch (K x') */
    int32_t negative_edges;       /* ARAP: edges whose rest weight cot a + cot b is negative */
    int32_t most_negative_edge;   /* ARAP: the most negative of them (-1: none) */
    double most_negative_weight;  /* ARAP: its cot a + cot b */
    int32_t clamped;              /* ARAP: those weights were set to 0 (arap_weights clamped) */
    double term_energy;      /* last local step: E_s or E_arap (unweighted) */
    double bend_energy;      /* last local step: E_db (unweighted) */
} cfi_stretch_bend_model;

/* Builds the model on `rest` (3 nv, interleaved). */
cf_status cfi_stretch_bend_model_init(cfi_stretch_bend_model *m, cf_context *ctx, const cf_mesh *mesh, const double *rest,
                             const cf_stretch_bend_options *options);
void cfi_stretch_bend_model_free(cfi_stretch_bend_model *m);

/* Local step at `x` (3 nv interleaved): optimal rotations and u', and the
 * energies E(x) with them (term_energy, bend_energy); returns the total.
 * exact != 0: every rotation from the robust SVD (cf_rotation_from_covariance);
 * otherwise per-face rotations use the closed-form rank-2 polar factor
 * (exact as well) and per-vertex rotations a polar iteration warm-started
 * at the previous rotation, never accepted if it lowers tr(R^T C) below the
 * previous rotation's, with the SVD as fallback when it does not converge. */
cf_status cfi_stretch_bend_local_step(cfi_stretch_bend_model *m, const double *x, int exact, double *total);

/* Right-hand side of Eq. 23 (interleaved, 3 nv) for the model's current
 * rotations and u' (needs m->hu when beta > 0). */
void cfi_stretch_bend_assemble_rhs(cfi_stretch_bend_model *m, double *rhs);

/* For tests, on a CF_FLOW_STRETCH_BEND_EDIT flow: the global phase alone
 * into x (3 nv) with the flow's current rotations and u'; the gradient
 * (3 nv interleaved) of the energy with rotations and u' held fixed, from
 * the assembled system (2 (A x - rhs)); the energy model. */
typedef struct cf_flow cf_flow;
cf_status cfi_stretch_bend_flow_global_solve(cf_flow *flow, double *x);
cf_status cfi_stretch_bend_flow_gradient(cf_flow *flow, const double *x, double *grad);
cfi_stretch_bend_model *cfi_stretch_bend_flow_model(cf_flow *flow);
/* Energy at x with the model's current rotations and u' held fixed
 * (Eqs. 5-7 and 15 before minimising over R, u'). */
double cfi_stretch_bend_fixed_energy(const cfi_stretch_bend_model *m, const double *x);

#endif /* CF_METHODS_STRETCH_BEND_EDIT_STRETCH_BEND_INTERNAL_H */
