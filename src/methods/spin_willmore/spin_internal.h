/*
 * Internal pieces of the spin-transformation machinery (Crane, Pinkall,
 * Schroeder 2011/2013) shared by cf_spin_transform and the conformal
 * Willmore flow, plus a test hook exposing per-step diagnostics.
 *
 * Quaternion fields are stored as 4 doubles per vertex (w, x, y, z), which is
 * also the row layout of the real 4 nv x 4 nv matrix X: entry 4 i + c.
 */
#ifndef CF_METHODS_SPIN_WILLMORE_SPIN_INTERNAL_H
#define CF_METHODS_SPIN_WILLMORE_SPIN_INTERNAL_H

#include "core/core.h"
#include "curvflow/flow.h"
#include "curvflow/linalg.h"
#include "curvflow/ops.h"
#include "curvflow/spin_willmore.h"
#include "mesh/mesh_internal.h"

/* The facewise matrix X(rho) of Crane 2013, App. G, with a fixed pattern;
 * values are refilled in place. In one of two forms, chosen at creation:
 * - real: a real symmetric 4 nv x 4 nv matrix (x), both triangles, for the
 *   paths that read or rewrite the real form (boundary=prescribed/cmc,
 *   boundary=fixed through cf_min_quad, complex_factorization=0, and
 *   cf_spin_transform);
 * - complex: only the upper triangle of the complex Hermitian 2 nv x 2 nv
 *   form (z, curvflow/linalg.h cf_quat_sparse), filled straight from the
 *   per-face quaternions and factorised without a copy: at 655k vertices
 *   the real form, its 36 int64 slots per face and the real -> complex
 *   copy took 1.7 GB at the factorisation's peak (docs/memory.md). The
 *   faces are summed in the same order, so the complex values equal those
 *   the real form's conversion gives, bit for bit. */
typedef struct cfi_dirac {
    cf_sparse *x;          /* real form, or NULL */
    cf_quat_sparse *z;     /* complex form, or NULL */
    int64_t *block_slot;   /* real: 36 nf: slot of entry (4 i, 4 j + c) for face k, pair (m, n), column c */
    int64_t *diag_slot;    /* real: 4 nv: slot of entry (4 i + c, 4 i + c) */
    int32_t *zslot;        /* complex: ne: complex entry (2 i, 2 j) of edge (i, j)'s block, i < j */
    int32_t *zdiag;        /* complex: nv: complex entry (2 i, 2 i) */
    int32_t nv, nf, ne;
    /* Fixed boundary (cfi_dirac_fixed_*): X with the boundary quaternions
     * known, eliminated by linalg's cf_min_quad in whole 4 x 4 blocks. */
    cf_min_quad *fixed;
    int32_t nknown;        /* 4 per boundary vertex */
    int32_t *known;        /* nknown: the components 4 i .. 4 i + 3 of each boundary vertex i */
    double *known_values;  /* nknown: lambda_B = 1 = (1, 0, 0, 0) per boundary vertex */
} cfi_dirac;

/* The real form (cfi_dirac_create) or, with complex_form, the complex one.
 * Statuses: CF_ERR_INVALID_ARG (mesh beyond int32 indices), CF_ERR_NOMEM. */
cf_status cfi_dirac_create(cf_context *ctx, const cf_mesh *mesh, cfi_dirac **out);
cf_status cfi_dirac_create_form(cf_context *ctx, const cf_mesh *mesh, int32_t complex_form, cfi_dirac **out);
void cfi_dirac_destroy(cf_context *ctx, cfi_dirac **d);
/* Analysis of X's pattern for a factorisation of either form (co: block
 * size 4, ordering, and for the real form whether to factorise it as its
 * complex form), and the numeric factorisation of the current values. */
cf_status cfi_dirac_analyse(cf_context *ctx, const cfi_dirac *d, const cf_cholesky_options *co, cf_cholesky **out);
cf_status cfi_dirac_factorize(const cfi_dirac *d, cf_cholesky *chol);
/* Rayleigh quotient lambda^T X lambda / sum_i area_i |lambda_i|^2
 * (cf_rayleigh_quotient_blocks on the real form; on the complex form the
 * same sums over cf_quat_sparse_multiply, whose lower blocks are the
 * conjugates of the upper ones where the real form's lower blocks are
 * summed separately: equal up to rounding). work: 4 nv doubles. */
double cfi_dirac_quotient(const cfi_dirac *d, const double *area, const double *lambda, double *work);
/* out = X lambda (4 nv each, quaternion per vertex) for the filled X, either form. */
void cfi_dirac_multiply(const cfi_dirac *d, const double *lambda, double *out);
/* out = (dX(rho)/drho [drho]) lambda (4 nv) for `count` directions drho
 * (nv each, one after the other; out: 4 nv each): the derivative of App. G's
 * X along drho applied to lambda, face by face without the matrix (X is
 * quadratic in rho: (rho_m e_n - rho_n e_m) / 6 + A rho_m rho_n / 9), the
 * face's geometry once for all directions. rho NULL: rho = 0. Faces of
 * zero area contribute only their linear term. */
void cfi_dirac_rho_derivative(const cf_mesh *mesh, const double *positions, const double *rho, int32_t count,
                              const double *drho, const double *lambda, double *out);

/* Fills X(rho) + shift * M (M: barycentric vertex areas) for `positions`.
 * rho may be NULL (rho = 0). Sign: X = (D - P rho)^* A (D - P rho) with
 * (D lambda)_k = -sum_j e_j lambda_j / (2 A_k), e_j the ccw edge opposite j. */
cf_status cfi_dirac_fill(cfi_dirac *d, const cf_mesh *mesh, const double *positions, const double *rho,
                         double shift);

/* Fixed boundary (Crane 2013, Sec. 6.3.2): lambda_B = 1 on the boundary
 * vertices and, on the interior, the least-squares solve
 * (X_II + eps M_I) lambda_I = -X_IB 1 + eps M_I 1 (X already holding the
 * shift eps M from cfi_dirac_fill). The boundary quaternions are known
 * variables of linalg's cf_min_quad (whole 4 x 4 blocks, so the interior
 * block keeps the complex factorisation when complex_form is set).
 * _create: analyses and factorises the current values of X (call after a
 * fill); _factorize: after each refill; _solve: lambda (4 nv) from the
 * areas (nv) and eps; b: 4 nv doubles of work. No allocation after create.
 * Statuses: those of cf_min_quad_* (CF_ERR_NOT_POSDEF naming the column of
 * the interior block), CF_ERR_NOMEM at create. */
cf_status cfi_dirac_fixed_create(cf_context *ctx, cfi_dirac *d, const cf_mesh *mesh, int32_t complex_form);
cf_status cfi_dirac_fixed_factorize(cfi_dirac *d);
cf_status cfi_dirac_fixed_solve(cfi_dirac *d, const cf_mesh *mesh, const double *area, double eps, double *b,
                                double *lambda);
/* Rayleigh quotient lambda^T X_D lambda / sum_i area_i |lambda_i|^2 of the
 * Dirichlet matrix X_D: X with the boundary rows and columns replaced by
 * the identity (the matrix the fixed-boundary solve used to factorise; the
 * flow's "eigenvalue" residual). work: 4 nv doubles. */
double cfi_dirac_fixed_quotient(const cfi_dirac *d, const cf_mesh *mesh, const double *area, const double *lambda,
                                double *work);

/* Prescribed boundary vectors (Crane 2013, Sec. 6.3.1): at boundary vertex
 * i, lambda_i = Q_i mu_i with Q_i (frames + 16 i, row-major 4 x 4,
 * orthonormal) whose first two columns r and r V~ span the admissible
 * lambdas and mu_i's last two components zero. Rewrites X (after a fill) as
 * Q^T X Q with those components pinned (identity rows and columns). */
void cfi_dirac_restrict_boundary(cfi_dirac *d, const cf_mesh *mesh, const double *frames);

/* Transformed edge vectors (Crane et al. 2011; NOTES.md):
 * e~_ij = 1/3 l_i' e l_i + 1/6 l_i' e l_j + 1/6 l_j' e l_i + 1/3 l_j' e l_j
 * (l' = conj(l)), e = f_j - f_i for every edge i < j. out: 3 ne. */
void cfi_spin_transform_edges(const cf_mesh *mesh, const double *positions, const double *lambda, double *out);
/* Its derivative at lambda along `count` directions dlambda (4 nv each, one
 * after the other), for the edges [first, first + n): out[(e - first) *
 * 3 count + 3 l + c] is component c of d e~_e along direction l. e~ is
 * quadratic in lambda, so this is exactly (e~(lambda + dl) - e~(lambda -
 * dl)) / 2 (test `dirac_forms`). */
void cfi_spin_transform_edges_derivative(const cf_mesh *mesh, const double *positions, const double *lambda,
                                         int32_t count, const double *dlambda, int32_t first, int32_t n, double *out);
/* Relative shift of the Dirac eigenproblem: X + eps M with
 * eps = CFI_SPIN_SHIFT * 4 pi / area (a fraction of 1/R^2 of the sphere of
 * equal area), so that the singular X(0) can be factorised. 1e-3 rather than
 * a tiny value: with a free boundary X has a large near-kernel, and one
 * inverse iteration from lambda = 1 must not amplify it (mushroom cap: 1e-6
 * blows up after 6 steps, 1e-3 lowers W for 8 steps, then stalls); on closed meshes
 * the results agree with 1e-6 to 1e-5 relative in W (spot, bunny, bob).
 * The flow's default; its option `regularization` changes it. */
#define CFI_SPIN_SHIFT 1e-3

/* Default floor on the flow's cotan weights (option weight_floor): twice a
 * face's area counts as at least this times the sum of its squared edges.
 * Session 28 measured it (docs/spin.md, "Near-duplicate vertices"): every
 * near-duplicate from 1e-10 to 1e-13 of an edge on spot_3k then ends at
 * W/4pi 1.002 after 10 steps; the smallest ratio on the shared meshes is
 * 1.2e-6 (triceratops_needles_3k), so none of them is touched. */
#define CFI_SPIN_WEIGHT_FLOOR 1e-8

/* Inverse power iteration (Crane 2013, Sec. 6.4.2) on a factorisation of
 * X + eps M and its Rayleigh quotient: cf_inverse_iteration_blocks /
 * cf_rayleigh_quotient_blocks (curvflow/linalg.h) with block size 4 and the
 * vertex areas as masses, lambda normalised to sum_i M_i |lambda_i|^2 =
 * sum_i M_i; the eigenvalue of X is the quotient minus eps. */

/* Positions from the transformed edges: cf_edge_poisson (curvflow/ops.h);
 * the integrability error: cf_edge_closure_error. */

/* Diagnostics of the last step of a spin-willmore flow (test hook). */
typedef struct cfi_spin_diagnostics {
    int32_t constraint_count;       /* columns of the constraint basis before orthonormalisation */
    int32_t constraint_rank;
    double constraint_residual;     /* max_i |<rhodot, c_i>_M| / (|rhodot|_M |c_i|_M) over enforced constraints */
    double total_curvature_change;  /* |<rhodot, 1>_M| / (|rhodot|_M |1|_M) */
    double integrability_error;     /* cf_edge_closure_error of the step */
    double conformal_excess;        /* mean Q of the step's map minus its vertex-scale model's (cf_conformal_excess;
                                     * measured while max_conformal_excess bounds it and the attempt did not
                                     * raise W, else 0) */
    double eigenvalue;              /* Rayleigh quotient of lambda (shift removed; of the last factorised X's
                                     * lambda when a period correction took the first-order one) */
    int32_t harmonic_dimension;     /* dim H^1 used by the exactness constraint: 2g, or 2g + b - 1 with a free boundary (0 if off) */
    double mobius_norm;             /* |balancing term|_M added to rhodot */
    double scale_change;            /* max over edges of |log(|lambda_i|^2 / |lambda_j|^2)| of the step */
    int32_t x0_solve_columns;       /* right-hand sides of the exactness X(0) solve (0: none) */
    int32_t x0_reused;              /* 1: this step's exactness directions came from X(0) of an earlier step */
    int32_t x0_renewed;             /* times this step renewed them after a failed attempt (0 or 1) */
    double period_error_first;      /* harmonic part of e~ / |e~| (*1 of the input) before the period corrections */
    double period_error;            /* ... after them (closed genus > 0 with period_iterations > 0; else 0) */
    int32_t period_iterations;      /* corrections made in the accepted attempt */
    int32_t period_first_order;     /* ... of which taken with the first-order lambda (no factorisation of X) */
    double period_first_order_error; /* periods of the first correction's first-order lambda, whether taken
                                      * or not (0: none tried) */
    double predicted_energy;        /* W the step's rho would give if realised exactly (Eq. (1)), see realised_decrease */
    double realised_decrease;       /* (W before - W after) / (W before - predicted_energy); 0 when no decrease is predicted */
    double fairing_kappa;           /* kappa = fairing tau of the vertex-scale fairing in the accepted attempt (0: none) */
    int32_t fairing_kept;           /* 1: the faired positions had the lower W and were kept */
    double fairing_energy;          /* W of the faired candidate (NaN when it could not be evaluated; 0 without) */
    int32_t relaxation_kept;        /* 1: the tangentially relaxed positions were kept */
    double class_residual;          /* keep_class: |G - G0| before the projection's last Gauss-Newton step */
    int32_t relaxation_iterations;  /* descent steps the relaxation took (0 without) */
    double relaxation_energy;       /* W of the relaxed candidate (0 without) */
    double plain_energy;            /* W of the recovered positions without the fairing */
    int32_t current_metric;         /* 1: the accepted attempt recovered positions in the current metric (the
                                       layer's fallback at a stall of the input metric's); at a stall, the
                                       last attempt's */
    int32_t fairing_only;           /* 1: the accepted step was the vertex-scale fairing alone (the spin
                                       step stalled in both metrics) */
    double damped_realised;         /* an attempt of this step outran its model by more than
                                       max_realised_decrease: the realised_decrease it had, after which
                                       regularization was raised (flow_method.c); 0: none */
} cfi_spin_diagnostics;

/* Nonzero full: the linearised exactness constraint solves X(0) for each of
 * its 3 x dim columns, as before they shared one solve per harmonic form
 * (test hook; exactness.c). CF_ERR_INVALID_ARG unless a spin-willmore flow. */
cf_status cfi_spin_willmore_set_x0_full_solves(cf_flow *flow, int32_t full);

/* CF_ERR_INVALID_ARG unless the flow is a spin-willmore flow. */
cf_status cfi_spin_willmore_diagnostics(const cf_flow *flow, cfi_spin_diagnostics *out);

/* The flow direction rhodot (nv) and the prescribed rho (nv) of the last
 * step, for tests; NULL if the flow is not spin-willmore. */
const double *cfi_spin_willmore_last_rhodot(const cf_flow *flow);
/* The harmonic 1-forms the exactness constraint uses (ne x *dimension,
 * column-major), as of the last step (test hook). */
const double *cfi_spin_willmore_harmonic_forms(const cf_flow *flow, int32_t *dimension);
/* Transformed edge vectors e~ of the last step (3 ne, interleaved; test hook). */
const double *cfi_spin_willmore_last_edges(const cf_flow *flow);

#endif /* CF_METHODS_SPIN_WILLMORE_SPIN_INTERNAL_H */
