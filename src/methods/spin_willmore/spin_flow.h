/*
 * Private to src/methods/spin_willmore/: the state of a spin-willmore flow
 * and the functions its files share. flow_method.c runs the step
 * (Crane, Pinkall, Schroeder 2013, Table 1); the concerns it calls into
 * live in one file each:
 *   options.c          defaults, parameter table, validation of the options
 *   boundary_frames.c  boundary vectors and frames, prescribed targets (Sec. 6.3.1)
 *   exactness.c        harmonic 1-forms and the exactness columns (App. C; genus > 0, holes)
 *   periods.c          Newton corrections of the periods left by the linearised exactness (closed genus > 0)
 *   keep_class.c       option keep_class: each attempt projected back onto the input's conformal class
 *   mobius.c           Moebius balancing (App. E.1)
 *   constraints.c      assembling and projecting the constraints (Sec. 6.2)
 *   step_policy.c      the scale-change measure of the adaptive step, blow-up and
 *                      divergence checks, convergence (the retries themselves are the
 *                      flow layer's step policy: cf_flow_step)
 * and the shared machinery one layer down: the flow's arrays in a core
 * workspace (core/core.h, cfi_workspace: recorded, freed in one call), the spectral
 * filter and the position recovery from edges (curvflow/ops.h: cf_spectral_filter,
 * cf_edge_poisson, cf_edge_closure_error), the block-aware inverse iteration
 * (curvflow/linalg.h: cf_inverse_iteration_blocks) and quaternions
 * (curvflow/quaternion.h).
 */
#ifndef CF_METHODS_SPIN_WILLMORE_SPIN_FLOW_H
#define CF_METHODS_SPIN_WILLMORE_SPIN_FLOW_H

#include "methods/flow_internal.h"
#include "methods/spin_willmore/spin_internal.h"

#define CFI_PI 3.14159265358979323846
/* max_conformal_excess's automatic value on closed surfaces (docs/spin.md,
 * "The step's non-conformal excess") */
#define CFI_SPIN_CLOSED_EXCESS_BOUND 0.12
/* the mean Q of the map from the input below which no step is relaxed
 * (option relaxation; docs/spin.md, "Tangential relaxation") */
#define CFI_SPIN_RELAXATION_MEAN_Q 1.3
/* the sweeps of the default (relaxation -1) on a closed surface of genus 0
 * (docs/spin.md, "Tangential relaxation": 5 / 10 / 20 gave cactus 1.509 /
 * 1.4959 / 1.5005) */
#define CFI_SPIN_RELAXATION_AUTO_SWEEPS 10

/* the projection onto the input's conformal class (option keep_class;
 * keep_class.c) */
typedef struct cfi_spin_class cfi_spin_class;

typedef struct cfi_spin_state {
    cf_spin_willmore_options opt;
    cfi_workspace ws;        /* every array below */
    int32_t nv, ne, nf;
    cfi_dirac *dirac;
    cf_cholesky *chol;       /* X(rho) + eps M */
    cf_cholesky *chol0;      /* X(0) + eps M, exactness only */
    cf_edge_poisson *poisson;       /* solver in the current metric: positions without input_metric or with a
                                     * fixed boundary, harmonic forms (exactness); its Laplacian gives H */
    cf_sparse *lap;          /* without that solver: the current surface's cotan Laplacian alone (H) */
    int64_t *lap_slots;      /* its slot map (cf_cotan_laplacian_slot_count entries) */
    cf_edge_poisson *poisson_input; /* input_metric: that of the starting surface, factorised once */
    int32_t stall_retry;     /* input_metric under `adaptive`: a stalled step is retried in the current
                              * metric (cfi_spin_fallback, which makes s->poisson if there is none) */
    int32_t current_metric_step; /* this attempt recovers positions with s->poisson, not poisson_input */
    int32_t fairing_only_step;   /* this attempt is the vertex-scale fairing of the step's start alone
                                  * (cfi_spin_fallback's last variant, at a stall in both metrics) */
    double step_start_tau;       /* the tau this step's first attempt took (the layer's, carried) */
    int32_t last_fairing_only;   /* the last step was taken by that variant: this one begins with it */
    cf_spectral_filter *filter; /* sigma > 0: the spectral filter of the input (Sec. 4; curvflow/ops.h) */
    cf_vertex_fairing *fairing; /* fairing > 0 (not prescribed / cmc): the vertex-scale fairing (curvflow/ops.h) */
    double *faired;          /* 3 nv: the faired candidate of an attempt (fairing only) */
    int32_t faired_won;      /* the faired candidate had the lower W in the last attempt */
    cf_tangential_relaxation *relaxation; /* relaxation resolved > 0: its descent (curvflow/ops.h) */
    int32_t relax_iterations;  /* option relaxation (0 with prescribed / cmc boundaries) */
    double *relaxed;         /* 3 nv: the relaxed candidate of a step (relaxation only) */
    double *recovery_metric; /* 3 nv: the positions of poisson_input's metric (recovery_scale_weight > 0 only) */
    double *face_scale;      /* nf: that recovery's face weights of the attempt (recovery_scale_weight > 0 only) */
    cfi_spin_class *keep_class; /* option keep_class: the projection onto the input's class (keep_class.c) */
    int32_t harmonic_dim;    /* dim H^1 (2g + b - 1 with boundary) if the exactness constraint is active */
    int32_t linearized;      /* exactness by the discrete linearisation instead of App. C's Z_i */
    int32_t period_newton;   /* closed, genus > 0, linearised, period_iterations > 0: the Newton
                              * corrections of the periods (periods.c) */
    int32_t zfirst, zcount;  /* the exactness directions within the orthonormal basis (constraints.c) */
    double *period_rho;      /* nv: rho before a correction (periods.c) */
    double *period_dx;       /* 4 nv x 3 dim: dX lambda per direction */
    double *period_sol;      /* 4 nv x 3 dim: X^-1 dX lambda */
    double *period_lambda;   /* 4 nv: the lambda before a correction (undo) */
    double *period_block;    /* CFI_SPIN_PERIOD_BLOCK x 3 (3 dim): the edges' derivative, a block (periods.c) */
    double *period_acc;      /* 3 dim x 3 dim: the Jacobian by form, summed over the blocks */
    double *period_matrix;   /* 3 dim x 3 dim: the periods' Jacobian */
    double *period_values;   /* 3 dim (the right-hand side, then the solution) */
    double *period_work;     /* cf_dense_least_squares_work_size(3 dim, 3 dim) */
    double *hweights;        /* ne: cotan weights of the input (the *1 of the harmonic basis), linearized only */
    int32_t fixed_boundary;
    int32_t restricted_boundary;   /* PRESCRIBED or CMC */
    double excess_bound;     /* max_conformal_excess resolved (its -1: 0.12 closed, else 0) */
    double *excess_work;     /* cf_conformal_excess_work_size doubles while excess_bound > 0 */
    int32_t has_boundary;
    double *frames;          /* 16 nv: Q_i of cfi_dirac_restrict_boundary (boundary vertices) */
    double *target;          /* 3 nv: prescribed V~ (PRESCRIBED) */
    double *binormal;        /* 3 nv: current boundary binormals */
    double eps;
    double *harmonic;        /* ne x 2g */
    double *area;            /* nv barycentric areas of the current surface */
    double *normal;          /* 3 nv */
    double *lx;              /* 3 nv: L f, scratch of cfi_spin_update_geometry (shares newpos's array) */
    double *h;               /* nv */
    double *rest_area;       /* nv: areas of the input, for Moebius balancing (NULL without) */
    double *rhodot;          /* nv */
    double *rho;             /* nv, scratch until X is filled (shares newpos's array) */
    double *lambda, *qwork;  /* 4 nv */
    double *qrhs;            /* 4 nv, fixed boundary only */
    double *zrhs, *zsol;     /* 4 nv x dim (x 3 dim if linearized) */
    int32_t x0_full_solves;  /* test hook: the linearized columns' 3 dim X(0) solves, not dim (exactness.c) */
    int32_t x0_factored;     /* chol0 holds X(0) + eps M of an earlier surface of this flow */
    double x0_scale_since;   /* sum of the accepted steps' scale_change since chol0 was factorised */
    double x0_period_first;  /* the last accepted step's harmonic part of e~ before corrections */
    int32_t x0_renew_pending; /* an attempt on reused directions was rejected: the next renews them */
    double *basis;           /* nv x max_cols */
    int32_t max_cols;
    double *edges;           /* 3 ne */
    double *placed_area;     /* nv: vertex areas of the positions being placed (their centroid's weights) */
    double *newpos;          /* 3 nv */
    double *vtmp;            /* nv, Moebius balancing only */
    double energy;
    double energy_before;    /* W at the start of the current step */
    cfi_spin_diagnostics diag;
} cfi_spin_state;

/* ---- options.c ---- */
extern const char *const cfi_spin_boundary_choices[];
/* Checks the options against the mesh (ranges, boundary mode vs boundary,
 * per-vertex targets); CF_ERR_INVALID_ARG / CF_ERR_BAD_MESH with a message. */
cf_status cfi_spin_validate_options(cf_context *ctx, const cf_mesh *mesh, const cf_spin_willmore_options *o);

/* ---- flow_method.c: the vtable's functions (cfi_spin_willmore_method, options.c) ---- */
cf_status cfi_spin_create(cf_flow *flow, const void *options);
/* The step in the flow layer's parts (flow_internal.h): I-III, IV-VI for
 * one tau (rejecting a too large scale change or a numerical failure while
 * the layer backtracks), the geometry of the restored start after a
 * rejected attempt, and the checks and report of the accepted one. */
cf_status cfi_spin_begin_step(cf_flow *flow, cf_flow_info *info);
cf_status cfi_spin_attempt(cf_flow *flow, double tau, cf_flow_info *info, cfi_step_verdict *verdict);
cf_status cfi_spin_revert(cf_flow *flow);
cf_status cfi_spin_fallback(cf_flow *flow, int32_t *switched, double *restart_step);
cf_status cfi_spin_end_step(cf_flow *flow, cf_flow_info *info);
cf_status cfi_spin_reset(cf_flow *flow);
void cfi_spin_destroy(cf_flow *flow);
/* ---- geometry (flow_method.c) ---- */
/* Refills L, areas, normals, L f, H and the energy W of x (s->energy). */
cf_status cfi_spin_update_geometry(cf_flow *flow, cfi_spin_state *s, const double *x);

/* ---- boundary_frames.c ---- */
cf_status cfi_spin_boundary_binormals(const cf_flow *flow, const cfi_spin_state *s, const double *x, double *out);
void cfi_spin_boundary_frames(const cf_flow *flow, cfi_spin_state *s);
/* s->target of boundary=prescribed: the caller's per-vertex targets
 * (normalised) or the input's binormals rotated on loops 1, 2, ... */
cf_status cfi_spin_boundary_targets(cf_flow *flow, cfi_spin_state *s, const cf_spin_willmore_options *o);


/* ---- exactness.c ---- */
/* Harmonic dimension the exactness constraint needs for these options (0: off). */
cf_status cfi_spin_exactness_dimension(cf_flow *flow, const cf_spin_willmore_options *o, int32_t *dim);
/* Fills s->harmonic (and s->hweights when linearised) from the input. */
cf_status cfi_spin_exactness_init(cf_flow *flow, cfi_spin_state *s);
/* Appends the exactness columns to s->basis from *col (App. C's Z_i or the linearised ones). */
cf_status cfi_spin_exactness_columns(cf_flow *flow, cfi_spin_state *s, const double *x, int32_t *col,
                                     double *factor_seconds, double *solve_seconds);

/* ---- mobius.c ---- */
double cfi_spin_mobius_term(const cf_flow *flow, cfi_spin_state *s, const double *x);

/* ---- constraints.c ---- */
/* Step III: projects the constraints out of s->rhodot and records the diagnostics. */
cf_status cfi_spin_apply_constraints(cf_flow *flow, cfi_spin_state *s, const double *x, double *factor_seconds,
                                     double *solve_seconds);

/* ---- the step (flow_method.c) ---- */
typedef struct cfi_spin_timers {
    double assemble, factorize, solve;   /* seconds, accumulated */
} cfi_spin_timers;

/* ---- periods.c ---- */
/* Edges per block of the periods' Jacobian: the block of their derivative
 * along every direction (3 x 3 dim each: 72 at genus 4) stays in cache. */
#define CFI_SPIN_PERIOD_BLOCK 128
/* Periods of the transformed edges of lambda on x: periods[3 g + c] =
 * <e~_c, h_g>_*1 (3 dim; edges: 3 ne scratch, left holding e~). Returns the
 * relative harmonic part |P| / |e~|_*1 (*1 of the input). */
double cfi_spin_periods(const cf_mesh *mesh, const cfi_spin_state *s, const double *x, const double *lambda,
                        double *edges, double *periods);
/* One Newton correction of rho = s->period_rho (lambda, s->chol solved for
 * it) along the exactness directions, cancelling at first order the periods
 * in s->period_values (as cfi_spin_periods left them; overwritten): writes
 * s->rho. */
cf_status cfi_spin_period_correction(cf_flow *flow, cfi_spin_state *s, cfi_spin_timers *t);
/* lambda of the corrected rho at first order, without a new factor: the one
 * before the correction (s->period_lambda) plus the correction's dlambda,
 * normalised as the inverse iteration's. Reads what the correction just
 * left (its solves in s->period_sol, its steps in s->period_values), so it
 * is called before the next cfi_spin_periods. Returns 0 when that lambda
 * has no finite, nonzero norm to normalise (then it is not to be used). */
int cfi_spin_period_linear_lambda(const cfi_spin_state *s, double *lambda);
/* The M-norm^2 every lambda of the flow is normalised to: sum M |lambda|^2
 * = sum M (the mean |lambda|^2 is 1), for the inverse iteration and the
 * first-order lambda alike. */
static inline double cfi_spin_lambda_norm2(const cfi_spin_state *s)
{
    double total = 0.0;
    for (int32_t i = 0; i < s->nv; ++i) total += s->area[i];
    return total;
}

/* Option keep_class (keep_class.c; docs/spin.md, "The conformal class the
 * flow keeps"): the class of the input positions (whole_gram: its Gram
 * matrix G, keep_class 2), the smoother and the work arrays; the projection
 * of positions x (3 nv, in place) back onto it by at most
 * CFI_SPIN_CLASS_ITERATIONS Gauss-Newton steps, each halved at most
 * CFI_SPIN_CLASS_HALVINGS times until the residual falls, stopping below
 * CFI_SPIN_CLASS_TOLERANCE and failing (CF_ERR_NUMERICAL) above
 * CFI_SPIN_CLASS_ACCEPT (both relative to |G^0|); *residual (may be NULL)
 * the residual |G^(x) - G^0| (|G(x) - G0|) it ends at. */
#define CFI_SPIN_CLASS_ITERATIONS 8
#define CFI_SPIN_CLASS_HALVINGS 4
#define CFI_SPIN_CLASS_TOLERANCE 1e-10
#define CFI_SPIN_CLASS_ACCEPT 1e-6
#define CFI_SPIN_CLASS_SMOOTHING 10.0
cf_status cfi_spin_class_create(cf_flow *flow, int32_t whole_gram, cfi_spin_class **out);
cf_status cfi_spin_class_project(cf_flow *flow, cfi_spin_class *c, double *x, double *residual);
void cfi_spin_class_destroy(cf_context *ctx, cfi_spin_class **c);
/* Steps IV-VI for the time step tau from the current state (rhodot and its
 * constraints computed): rho, lambda, edges, positions (flow->positions in
 * place) and the geometry of the new surface (s->energy). *too_large (only
 * while the flow layer backtracks) says why an attempt was stopped: */
typedef enum cfi_spin_too_large {
    CFI_SPIN_STEP_OK = 0,
    CFI_SPIN_SCALE_CHANGE = 1,   /* before the positions: lambda's scale jumps more than max_scale_change */
    CFI_SPIN_NOT_INTEGRABLE = 2, /* the recovered positions not applied: the edges are less integrable
                                  * than max_integrability_error allows */
    CFI_SPIN_NOT_CONFORMAL = 3,  /* the new positions' map from the step's start makes more distortion
                                  * than its vertex scales explain by more than max_conformal_excess */
    CFI_SPIN_PERIODS_LEFT = 4    /* before the positions: the corrections left periods above
                                  * max_period_error */
} cfi_spin_too_large;
cf_status cfi_spin_realise_step(cf_flow *flow, cfi_spin_state *s, double tau, cfi_spin_too_large *too_large,
                                cfi_spin_timers *t);

/* ---- step_policy.c ---- */
/* Largest change of the log conformal scale across an edge, |log(|l_i|^2 / |l_j|^2)|. */
double cfi_spin_max_scale_change(const cf_mesh *mesh, const double *lambda);
/* Relative energy decrease below tolerance (a stall also converges: the flow layer). */
int32_t cfi_spin_converged(const cfi_spin_state *s, double energy_before);

#endif /* CF_METHODS_SPIN_WILLMORE_SPIN_FLOW_H */
