/*
 * One interface for every method: create a flow from a mesh and options,
 * step it, read its state, destroy it. The CLI, benchmarks and reports
 * treat all methods alike through it.
 *
 *   cf_flow_options opts;                      // common part + method part
 *   cf_flow_options_default(CF_FLOW_IMPLICIT_MCF, &opts);
 *   cf_flow_options_set(ctx, &opts, "time_step", "0.01");   // by name, or
 *   cf_baseline_options *b = cf_flow_options_method_as(&opts, CF_FLOW_IMPLICIT_MCF);
 *   b->time_step = 0.01;                       // by field (checked by create)
 *   cf_flow *flow;
 *   cf_flow_create(ctx, mesh, NULL, &opts, &flow);
 *   cf_flow_info info;
 *   for (int i = 0; i < 10; ++i) if (cf_flow_step(flow, &info)) break;
 *   const double *x = cf_flow_positions(flow);
 *   cf_flow_destroy(&flow);
 *
 * Robustness: every step is checked (finite positions and energy, method
 * status). When a step fails, the flow keeps the last good state, the
 * status is returned and the context message names the iteration, e.g.
 * "iteration 17: energy is NaN".
 */
#ifndef CURVFLOW_FLOW_H
#define CURVFLOW_FLOW_H

#include "curvflow/curvflow.h"
#include "curvflow/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum cf_flow_kind {
    CF_FLOW_EXPLICIT_MCF = 0,          /* explicit mean curvature flow */
    CF_FLOW_IMPLICIT_MCF = 1,          /* Desbrun et al. 1999, backward Euler */
    CF_FLOW_CONFORMAL_MCF = 2,         /* Kazhdan, Solomon, Ben-Chen 2012 */
    CF_FLOW_EXPLICIT_BILAPLACIAN = 3,  /* Taubin-style explicit bi-Laplacian */
    CF_FLOW_IMPLICIT_BILAPLACIAN = 4,  /* backward Euler bi-Laplacian */
    CF_FLOW_SPIN_WILLMORE = 5,         /* Crane, Pinkall, Schroeder 2013 */
    CF_FLOW_STRETCH_BEND_EDIT = 6,     /* Zhao & Gortler, and ARAP variants */
    CF_FLOW_KIND_COUNT = 7
} cf_flow_kind;

/* "implicit-mcf" etc.; NULL for an unknown kind. */
CF_API const char *cf_flow_kind_name(cf_flow_kind kind);
CF_API const char *cf_flow_kind_description(cf_flow_kind kind);
/* Looks a kind up by name. CF_ERR_INVALID_ARG for an unknown name. */
CF_API cf_status cf_flow_kind_from_name(const char *name, cf_flow_kind *kind);

/* Method parameters are described by a table so that front ends can set
 * them by name ("--param sigma=0.5") and list them with their help.
 *
 * Scalar types (DOUBLE, INT, BOOL, CHOICE) are set from text by
 * cf_flow_options_set or directly in the method's options struct; either
 * way cf_flow_create checks every one against the table (same range and
 * same message), so a field set by hand out of range is refused there.
 *
 * Array types carry data, not text: the field is a cf_param_values
 * (VERTEX_*, FACE_*) or a `const cf_handle_set *` (POINT_SETS), set in the
 * options struct by the caller (the CLI loads them from a file or a PLY
 * property, cli/common.c). The data is caller-owned and must stay valid
 * until cf_flow_create returns (methods copy what they keep; see each
 * method's header for exceptions). For array types min_value is 1 when the
 * method requires the parameter and 0 when it is optional; max_value is
 * unused. cf_flow_create checks the element count against the mesh (the
 * message names the parameter and the expected count). */
typedef enum cf_param_type {
    CF_PARAM_DOUBLE = 0,
    CF_PARAM_INT = 1,     /* int32_t */
    CF_PARAM_BOOL = 2,    /* int32_t, 0 or 1; accepts true/false/yes/no/1/0 */
    CF_PARAM_CHOICE = 3,  /* int32_t index into `choices` (NULL-terminated names) */
    CF_PARAM_VERTEX_SCALARS = 4,  /* cf_param_values: one double per vertex (count = nv) */
    CF_PARAM_VERTEX_VECTORS = 5,  /* cf_param_values: x y z per vertex (3 nv doubles, count = nv);
                                   * max_value 1: only boundary vertices carry one (others ignored) */
    CF_PARAM_FACE_SCALARS = 6,    /* cf_param_values: one double per face (count = nf) */
    CF_PARAM_POINT_SETS = 7       /* const cf_handle_set * (curvflow/constraints.h): vertices with targets */
} cf_param_type;

/* The field of a VERTEX_SCALARS / VERTEX_VECTORS / FACE_SCALARS parameter:
 * `count` elements (vertices or faces) of 1 or 3 doubles each, interleaved.
 * values NULL (count 0) = not given. Caller-owned, see above. */
typedef struct cf_param_values {
    const double *values;
    int32_t count;
} cf_param_values;

typedef struct cf_param_desc {
    const char *name;
    cf_param_type type;
    size_t offset;              /* offset of the field in the method's options struct */
    double min_value, max_value;  /* inclusive range for numbers; arrays: min_value 1 = required */
    const char *const *choices; /* for CF_PARAM_CHOICE */
    const char *help;
} cf_param_desc;

/* 1 for the array types (VERTEX_SCALARS .. POINT_SETS), else 0. */
CF_API int32_t cf_param_type_is_array(cf_param_type type);
/* "double", "int", "bool", "choice", "vertex-scalars", "vertex-vectors",
 * "face-scalars", "point-set"; NULL for an unknown type. */
CF_API const char *cf_param_type_name(cf_param_type type);

/* Options of one flow: the kind and the method's own options struct
 * (cf_<method>_options, see the method's header), stored inline so the
 * struct can be copied by value. cf_flow_options_method gives a pointer to
 * it. */
#define CF_FLOW_OPTIONS_STORAGE 1024
typedef struct cf_flow_options {
    cf_flow_kind kind;
    union {
        double align_;
        unsigned char bytes[CF_FLOW_OPTIONS_STORAGE];
    } storage;
} cf_flow_options;

/* The step policy common to every method (docs/flowcli.md, "Step policy"):
 * when a step is accepted, retried with a smaller time step, or failed. It
 * lives in the last CF_STEP_POLICY_STORAGE bytes of cf_flow_options.storage
 * (method options use the bytes before them) and is set like a method
 * parameter: cf_flow_options_set(ctx, &o, "backtrack", "false"), or through
 * cf_flow_options_policy(&o)->backtrack = 0. Which checks apply depends on
 * the method (a method whose energy need not decrease opts out). */
#define CF_STEP_POLICY_STORAGE 128
typedef struct cf_step_policy {
    int32_t energy_check;       /* 1: reject a step that raises the energy (methods that descend it) [1] */
    int32_t backtrack;          /* 1: retry a rejected step with half the time step, grow it back after [1] */
    int32_t max_halvings;       /* retries of one step, 0..60 [10] */
    int32_t halving_search;     /* 1: a round of halvings whose rises shrink like a first-order rise
                                 * tries the smallest step it may reach first and bisects; the same
                                 * step as plain halving wherever acceptance is monotone in the step,
                                 * in fewer attempts (spin-willmore; docs/flowcli.md) [1] */
    double step_growth;         /* factor on the step after an accepted step, up to time_step, [1, 16] [2] */
    double rise_tolerance;      /* relative rise of the energy in a step taken as rounding, [0, 1] [1e-9] */
    double divergence_tolerance; /* relative slack of divergence tests against the start, [0, 1] [1e-4] */
    double energy_floor;        /* absolute slack of every energy test, in the method's unit, [0, 1] [1e-12] */
    double blowup_factor;       /* an accepted step whose energy exceeds this factor times the energy
                                 * before it (and the floor) fails (CF_ERR_NUMERICAL, the last good
                                 * state kept); 0 (off) or > 1. Default per method (docs/flowcli.md):
                                 * 10 for spin-willmore and the explicit flows, 0 for the implicit
                                 * ones; no effect on a method that opts out (stretch-bend-edit) */
    double divergence_factor;   /* an accepted step that leaves the energy above this factor times the
                                 * starting energy (with divergence_tolerance and the floor) fails;
                                 * 0 (off) or >= 1. Default per method: 1 for spin-willmore (not with
                                 * prescribed / cmc boundaries), 0 for the baselines */
} cf_step_policy;

/* The common step policy inside `options` (NULL for NULL). */
CF_API cf_step_policy *cf_flow_options_policy(cf_flow_options *options);
CF_API const cf_step_policy *cf_flow_options_policy_const(const cf_flow_options *options);

/* The parameter table of the common step policy (the same for every kind;
 * set and formatted with cf_flow_options_set / _format like a method's). */
CF_API cf_status cf_flow_common_params(const cf_param_desc **params, int32_t *count);

/* Fills the defaults of the method. CF_ERR_INVALID_ARG for a bad kind. */
CF_API cf_status cf_flow_options_default(cf_flow_kind kind, cf_flow_options *options);
/* The method's options struct inside `options` when options->kind is
 * `expected`, else NULL (also for NULL options): the checked way to reach
 * cf_<method>_options, e.g.
 *   cf_baseline_options *b = cf_flow_options_method_as(&opts, CF_FLOW_IMPLICIT_MCF); */
CF_API void *cf_flow_options_method_as(cf_flow_options *options, cf_flow_kind expected);
CF_API const void *cf_flow_options_method_as_const(const cf_flow_options *options, cf_flow_kind expected);
/* Unchecked form, kept for compatibility: the method's options struct
 * whatever the kind (the caller casts it). Prefer cf_flow_options_method_as. */
CF_API void *cf_flow_options_method(cf_flow_options *options);
CF_API const void *cf_flow_options_method_const(const cf_flow_options *options);

/* Sets a parameter from its text form; CF_ERR_INVALID_ARG with a message
 * naming the parameter for an unknown name, bad text or value out of range,
 * and for an array-typed parameter (those are set in the options struct). */
CF_API cf_status cf_flow_options_set(cf_context *ctx, cf_flow_options *options, const char *name, const char *value);

/* Text form of the current value of one parameter (as accepted by
 * cf_flow_options_set; choices by name, bools as true/false; array types
 * "none" or "N values" / "N points", which cf_flow_options_set does not
 * take). CF_ERR_INVALID_ARG if buf is too small. */
CF_API cf_status cf_flow_options_format(const cf_flow_options *options, const cf_param_desc *param, char *buf,
                                        size_t size);

/* Text of the values a parameter accepts, as the range messages of
 * cf_flow_options_set name them: "[1e-09, 10]" for numbers (each limit the
 * shortest text that reads back as it, e.g. 1.5707963267948966), "true|false",
 * the choices "a|b|c", or for array types "required" / "optional".
 * CF_ERR_INVALID_ARG for NULL or a too small buffer. */
CF_API cf_status cf_flow_param_range_format(const cf_param_desc *param, char *buf, size_t size);

/* The parameter table of a kind. */
CF_API cf_status cf_flow_params(cf_flow_kind kind, const cf_param_desc **params, int32_t *count);

/* What one step reports. Energy terms and residuals are named by the method
 * (term_names, residual_names); unused slots have NULL names. */
#define CF_FLOW_MAX_TERMS 4
#define CF_FLOW_MAX_RESIDUALS 10
typedef struct cf_flow_info {
    int64_t iteration;       /* steps taken so far, this one included */
    double time;             /* accumulated flow time (sum of time steps) */
    double time_step;        /* step used for this step */
    double energy;           /* the method's energy after the step */
    double energy_terms[CF_FLOW_MAX_TERMS];
    const char *term_names[CF_FLOW_MAX_TERMS];
    double residuals[CF_FLOW_MAX_RESIDUALS];
    const char *residual_names[CF_FLOW_MAX_RESIDUALS];
    double area;             /* total area after the step */
    double volume;           /* enclosed volume after the step */
    double area_drift;       /* area / initial area - 1 */
    double volume_drift;     /* volume / initial volume - 1 (0 if initial volume is 0) */
    double assemble_seconds; /* time split of this step */
    double factorize_seconds;
    double solve_seconds;
    double total_seconds;
} cf_flow_info;

/* Progress callback, called after each step of cf_flow_run (and of
 * cf_flow_step). Return nonzero to cancel: the run stops with
 * CF_ERR_CANCELLED and keeps the state reached. */
typedef int (*cf_progress_fn)(void *user, const cf_flow_info *info);

typedef struct cf_flow cf_flow;

/* Creates a flow. `positions` (3 nv) is the starting state; NULL starts from
 * the mesh's rest positions. options is required (it names the kind) and
 * is copied. The mesh must outlive the flow. Statuses: CF_OK,
 * CF_ERR_INVALID_ARG (NULL argument, unknown kind, a parameter out of
 * range), CF_ERR_NONFINITE (a starting position, naming the vertex),
 * CF_ERR_NOMEM, CF_ERR_NUMERICAL (non-finite initial energy), and the
 * method's own (e.g. CF_ERR_UNSUPPORTED, CF_ERR_BAD_MESH, solver errors);
 * *out is NULL on failure. */
CF_API cf_status cf_flow_create(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                const cf_flow_options *options, cf_flow **out);

/* Creates a flow whose reference is the mesh and whose state starts at
 * `start` (3 nv: same vertices as the mesh, e.g. a previous run's output or
 * a perturbed copy): cf_flow_create(ctx, mesh, NULL, options, out) and then
 * cf_flow_set_positions(*out, start). Everything a method derives from its
 * input at create therefore comes from the mesh's positions, as in a run
 * from the mesh itself: the metric of spin-willmore's input_metric, its
 * spectral filter, harmonic basis, prescribed boundary targets and Moebius
 * rest areas, cMCF's stiffness, the baselines' scale-free step and rescale
 * reference, the edit's rest pose; area and volume drifts are relative to
 * the mesh. (cf_flow_create with `positions` derives those from the
 * positions instead.) So a run resumed from its own output continues with
 * the same reference. start NULL: same as cf_flow_create(..., NULL, ...).
 * Statuses: those of cf_flow_create, and of cf_flow_set_positions for the
 * start (CF_ERR_NONFINITE naming the vertex; a method's error for a start
 * it cannot measure, e.g. a zero-area face), the message prefixed "start: ";
 * *out is NULL on failure. */
CF_API cf_status cf_flow_create_at(cf_context *ctx, const cf_mesh *mesh, const double *start,
                                   const cf_flow_options *options, cf_flow **out);

/* One step. On failure the state is the one before the step and the
 * context message is prefixed "iteration N: ". The context's recorded error
 * is cleared when the step starts. info may be NULL. The step policy
 * (cf_step_policy) applies: a step that raises the energy of a method that
 * descends it is redone with half the time step (backtracking methods) or
 * fails; when no step down to time_step / 2^max_halvings lowers the energy
 * (or, for a method without a time step, the step raised it) the state is
 * kept, the flow is marked converged, a warning is logged and CF_OK is
 * returned without advancing the iteration (info then describes the kept
 * state). Statuses: the method's errors, CF_ERR_NUMERICAL for a non-finite
 * position, energy, area or volume after the step, a face that
 * degenerated, or a rejected rise without backtracking, CF_ERR_CANCELLED
 * when the progress callback asks to stop (the step is kept). */
CF_API cf_status cf_flow_step(cf_flow *flow, cf_flow_info *info);

/* Up to `steps` steps, calling the progress callback after each. Stops
 * early with CF_OK when the flow has converged (the method's or the step
 * policy's convergence tolerance, or the policy's stop). steps >= 0
 * (CF_ERR_INVALID_ARG otherwise); the first failing step's status is
 * returned with the state before it. info (optional) receives the last
 * accepted step's info. */
CF_API cf_status cf_flow_run(cf_flow *flow, int64_t steps, cf_flow_info *info);

CF_API void cf_flow_set_progress(cf_flow *flow, cf_progress_fn fn, void *user);

/* Current positions (3 nv), valid until the next step or destroy. */
CF_API const double *cf_flow_positions(const cf_flow *flow);
/* Replaces the state (3 nv); methods that keep extra state reset it.
 * CF_ERR_INVALID_ARG (NULL), CF_ERR_NONFINITE (naming the vertex); on any
 * failure the previous state is kept. */
CF_API cf_status cf_flow_set_positions(cf_flow *flow, const double *positions);
CF_API const cf_mesh *cf_flow_mesh(const cf_flow *flow);
CF_API cf_flow_kind cf_flow_get_kind(const cf_flow *flow);
/* Energy of the current state (as in the last info; computed at create). */
CF_API double cf_flow_energy(const cf_flow *flow);
/* Info of the last step (or of the initial state, iteration 0). */
CF_API const cf_flow_info *cf_flow_last_info(const cf_flow *flow);
/* 1 when the method considers itself converged (e.g. relative energy
 * decrease below its tolerance). */
CF_API int32_t cf_flow_converged(const cf_flow *flow);

CF_API void cf_flow_destroy(cf_flow **flow);

/* One-off convenience: creates, runs `steps` steps, copies the final
 * positions into out_positions (3 nv, caller-allocated), destroys. The
 * positions reached are copied also when a step fails (the last good
 * state); when creation fails out_positions is left untouched. */
CF_API cf_status cf_flow_apply(cf_context *ctx, const cf_mesh *mesh, const cf_flow_options *options, int64_t steps,
                               double *out_positions, cf_flow_info *info);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_FLOW_H */
