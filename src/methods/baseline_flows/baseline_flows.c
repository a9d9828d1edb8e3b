/*
 * Baseline curvature flows on the common flow interface (the flows the
 * papers compare against; formulas, energies and the scale-free time step
 * rule are in include/curvflow/baseline_flows.h):
 *  - explicit mean curvature flow (forward Euler);
 *  - implicit mean curvature flow, Desbrun, Meyer, Schroeder, Barr 1999,
 *    "Implicit fairing ...", Sec. 4: (M + tau L) x' = M x (backward Euler);
 *  - conformalized mean curvature flow, Kazhdan, Solomon, Ben-Chen 2012,
 *    "Can mean-curvature flow be modified to be non-singular?", Eq. (4):
 *    the stiffness L is frozen at the initial mesh, only M follows the flow;
 *  - explicit and implicit bi-Laplacian flows (Taubin-style fourth-order
 *    smoothing), the L2 gradient flow of (1/2) x^T L M^-1 L x.
 *
 * Everything a step needs (the Laplacian pattern and its slot map, the
 * Cholesky analysis, work vectors) is allocated in create; steps only refill
 * values, refactorise and solve.
 */
#include "curvflow/baseline_flows.h"

#include "curvflow/linalg.h"
#include "curvflow/ops.h"
#include "methods/flow_internal.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

/* Step acceptance is the shared step policy's (methods/step_policy.h, the
 * `policy` of the vtables below): every baseline flow descends its energy,
 * so a step that raises it is rejected. An explicit step that raises it is
 * taken as unstable: below the stability limit forward Euler on these
 * gradient flows lowers the energy, while an unstable mode grows
 * geometrically and raises it, so a rise is the earliest sign of it (a
 * factor test such as "rose by 50 %" misses modes that grow slowly); the
 * user chose the explicit step, so such a step fails. The implicit flows
 * are unconditionally stable for a frozen operator only: with L and M
 * following the surface a large step can raise the energy (issue 15 S3:
 * implicit-bilaplacian on spool_creases_650 at time_step 1e-7, 302.8 ->
 * 11 484 in 15 steps, crumpled); they take tau from the policy, so a
 * rising step, or one whose matrix does not factorise, is redone with half
 * the step. */

/* Area, relative to the start, below which a flow without rescaling is
 * reported as collapsed (see finish_step). */
#define BASELINE_COLLAPSE_AREA 1e-6

typedef struct baseline_state {
    cf_baseline_options opt;
    cfi_workspace ws;       /* the arrays below (slot_map ... y) */
    int32_t nv;
    double tau;             /* actual time step (scaled, see the header) */
    cf_sparse *l;           /* cotan Laplacian of the current positions (pattern fixed) */
    int64_t *slot_map;      /* nv + 2 ne slots of L's triplets (cf_cotan_laplacian_slot_count) */
    int64_t slot_count;
    int64_t *l_diag;        /* nv: slot of L(i, i) */
    double *l0_values;      /* conformal MCF: L values of the initial mesh (nnz) */
    cf_sparse *a;           /* system matrix (implicit flows); == l for implicit/conformal MCF */
    int64_t *a_diag;        /* nv: slot of A(i, i) */
    int64_t *pos;           /* nv workspace for the bi-Laplacian product, -1 when unused */
    cf_cholesky *chol;
    double *mass;           /* nv lumped vertex areas */
    double *x;              /* 3 nv column-major coordinates */
    double *b;              /* 3 nv right-hand sides */
    double *r;              /* 3 nv residual / interleaved work */
    double *y;              /* 3 nv interleaved work */
    double centroid0[3];
    const uint8_t *held;    /* boundary=fixed on a mesh with boundary: the held vertices; else NULL */
    double *held_positions; /* 3 nv: the held vertices' positions (written back after each solve) */
    int32_t rise_reported;  /* explicit bi-Laplacian: a stable step raised the energy (said once) */
    double first_auto_tau;  /* explicit flows, time_step 0: the first automatic step over the area (MCF) or
                             * its square (bi-Laplacian); 0: none yet */
    int32_t stall_reported; /* the automatic step so measured fell below CFI_AUTO_STEP_STALL of it (said once) */
} baseline_state;

/* The automatic explicit step (time_step 0) follows forward Euler's
 * stability limit, which a collapsing triangle drives toward 0: below this
 * fraction of the run's first automatic step the flow hardly moves, and
 * says so once (measured, 10 default steps: hand_1k's explicit MCF takes
 * 2.4e-8 of its first step by step 10, t 1.04e-5 -> 1.42e-5 over the
 * last nine; bull_6k, bunny_scan_35k, plane_841 and the bi-Laplacian on
 * bull, hand, man_slivers_17k fall below 5e-3; the other shared meshes stay
 * above 0.04). */
#define CFI_AUTO_STEP_STALL 1e-3

static const char *const mass_choices[] = {"barycentric", "voronoi", NULL};
static const char *const boundary_choices[] = {"free", "fixed", NULL};

/* The parameters every baseline flow shares after its time step. */
#define BASELINE_SHARED_PARAMS                                                                                         \
    {"mass", CF_PARAM_CHOICE, offsetof(cf_baseline_options, mass), 0, 1, mass_choices,                                 \
     "lumped mass matrix: barycentric or voronoi (mixed Voronoi, Meyer 2003)"},                                        \
    {"rescale", CF_PARAM_BOOL, offsetof(cf_baseline_options, rescale), 0, 1, NULL,                                     \
     "keep total area and centroid of the start shape after each step (Kazhdan 2012)"},                                \
    {"tolerance", CF_PARAM_DOUBLE, offsetof(cf_baseline_options, tolerance), 0, 1, NULL,                               \
     "converged when a step lowers the energy by less than this fraction (0: never)"},                                 \
    {"boundary", CF_PARAM_CHOICE, offsetof(cf_baseline_options, boundary), 0, 1, boundary_choices,                     \
     "free: boundary vertices move (natural boundary; MCF default); fixed: they are held and the bi-Laplacian "        \
     "energy counts interior vertices only (bi-Laplacian default: with a free boundary its step raises its "           \
     "energy on flat or nearly flat open meshes)"},                                                                    \
    {"weight_floor", CF_PARAM_DOUBLE, offsetof(cf_baseline_options, weight_floor), 0.0, 1e-3, NULL,                   \
     "floor on L's cotan weights: a face weighs as if twice its area were at least this times the sum of its "         \
     "squared edges (0: exact, the classical operator; 1e-8 bounds the weights of a near-duplicate vertex)"}

/* The time step's range is each family's: 0 asks the explicit flows for
 * their automatic step and is refused by the implicit ones, so their listing
 * starts above it (session 29: implicit-mcf listed [0, 1e6] and refused 0). */
static const cf_param_desc explicit_params[] = {
    {"time_step", CF_PARAM_DOUBLE, offsetof(cf_baseline_options, time_step), 0.0, 1e6, NULL,
     "scale-free time step in units of h^2 (MCF) or h^4 (bi-Laplacian), h the mean edge length; 0 = auto: 0.9 "
     "(MCF) or 0.5 (bi-Laplacian) of forward Euler's stability limit on the current mesh, every step"},
    BASELINE_SHARED_PARAMS,
};
static const cf_param_desc implicit_params[] = {
    {"time_step", CF_PARAM_DOUBLE, offsetof(cf_baseline_options, time_step), 1e-12, 1e6, NULL,
     "scale-free time step in units of area (MCF) or area^2 (bi-Laplacian). implicit-mcf and implicit-bilaplacian "
     "move vertices along the normal only and degenerate triangles within a few steps on most real meshes "
     "(docs/flowcli.md); conformal-mcf or spin-willmore keep them"},
    BASELINE_SHARED_PARAMS,
};

cf_status cf_baseline_options_default(cf_flow_kind kind, cf_baseline_options *o)
{
    if (!o) return CF_ERR_INVALID_ARG;
    memset(o, 0, sizeof *o);
    o->mass = CF_MASS_LUMPED_BARYCENTRIC;
    o->rescale = 0;
    o->tolerance = 0.0;
    switch (kind) {
    case CF_FLOW_EXPLICIT_MCF: o->time_step = 0.0; break;           /* auto: 0.9 of the stability limit */
    case CF_FLOW_IMPLICIT_MCF: o->time_step = 1e-3; break;          /* a sphere loses ~5 % of R^2 per step */
    case CF_FLOW_CONFORMAL_MCF: o->time_step = 1e-3; break;
    case CF_FLOW_EXPLICIT_BILAPLACIAN: o->time_step = 0.0; break;   /* auto */
    case CF_FLOW_IMPLICIT_BILAPLACIAN: o->time_step = 1e-5; break;
    default: return CF_ERR_INVALID_ARG;
    }
    /* the bi-Laplacian's free boundary is no descent of its energy (header) */
    o->boundary = kind == CF_FLOW_EXPLICIT_BILAPLACIAN || kind == CF_FLOW_IMPLICIT_BILAPLACIAN
                      ? CF_BASELINE_BOUNDARY_FIXED
                      : CF_BASELINE_BOUNDARY_FREE;
    return CF_OK;
}

static void default_explicit_mcf(void *o) { cf_baseline_options_default(CF_FLOW_EXPLICIT_MCF, o); }
static void default_implicit_mcf(void *o) { cf_baseline_options_default(CF_FLOW_IMPLICIT_MCF, o); }
static void default_conformal_mcf(void *o) { cf_baseline_options_default(CF_FLOW_CONFORMAL_MCF, o); }
static void default_explicit_bilaplacian(void *o) { cf_baseline_options_default(CF_FLOW_EXPLICIT_BILAPLACIAN, o); }
static void default_implicit_bilaplacian(void *o) { cf_baseline_options_default(CF_FLOW_IMPLICIT_BILAPLACIAN, o); }

/* ---- helpers ------------------------------------------------------------ */

static cf_flow_kind kind_of(const cf_flow *flow) { return flow->options.kind; }

static int is_bilaplacian(const cf_flow *flow)
{
    return kind_of(flow) == CF_FLOW_EXPLICIT_BILAPLACIAN || kind_of(flow) == CF_FLOW_IMPLICIT_BILAPLACIAN;
}

/* The lumped masses (option 'mass') of the current positions; every one
 * must be positive since the steps divide by them. */
static cf_status assemble_mass(cf_flow *flow, baseline_state *s)
{
    cf_dual_area_kind dk = s->opt.mass == CF_MASS_LUMPED_VORONOI ? CF_DUAL_AREA_MIXED_VORONOI : CF_DUAL_AREA_BARYCENTRIC;
    cf_status st = cf_vertex_areas(flow->ctx, flow->mesh, flow->positions, dk, s->mass);
    if (st != CF_OK) return st;
    for (int32_t i = 0; i < s->nv; ++i)
        if (!(s->mass[i] > 0.0)) return cfi_error(flow->ctx, CF_ERR_NUMERICAL, "vertex %d: dual area is %g", i, s->mass[i]);
    return CF_OK;
}

/* L and the lumped masses of the current positions. */
static cf_status assemble(cf_flow *flow, baseline_state *s)
{
    cf_status st = cf_cotan_laplacian_refill_floored(s->l, flow->mesh, flow->positions, s->opt.weight_floor, s->slot_map);
    if (st != CF_OK) return st;
    return assemble_mass(flow, s);
}

/* r = L x, one coordinate column at a time (x copied column-major into
 * s->x), through the differences of the coordinates
 * (cf_sparse_multiply_zero_row_sums): the same for a mesh moved far from
 * the origin. Before, a spot 1e6 away had an energy off in its 7th digit,
 * and the implicit bi-Laplacian flow stopped at step 10 on rises that were
 * rounding. */
static void laplacian_of_positions(baseline_state *s, const double *positions)
{
    int32_t nv = s->nv;
    for (int c = 0; c < 3; ++c) {
        for (int32_t i = 0; i < nv; ++i) s->x[(size_t)c * nv + i] = positions[3 * (size_t)i + c];
        cf_sparse_multiply_zero_row_sums(s->l, s->x + (size_t)c * nv, s->r + (size_t)c * nv);
    }
}

/* (1/2) sum_i |(L x)_i|^2 / m_i with L, M already assembled at x, over the
 * vertices that move (all, or the interior with boundary=fixed); leaves
 * L x (interleaved) in s->y, with the held rows set to 0: the explicit
 * step's L M^-1 (P L x) is then the gradient of this sum. */
static double bilaplacian_energy(const cf_flow *flow, baseline_state *s)
{
    int32_t nv = s->nv;
    laplacian_of_positions(s, flow->positions);
    double e = 0.0;
    for (int32_t i = 0; i < nv; ++i) {
        double q = 0.0;
        int held = s->held && s->held[i];
        for (int c = 0; c < 3; ++c) {
            double v = held ? 0.0 : s->r[(size_t)c * nv + i];
            s->y[3 * (size_t)i + c] = v;
            q += v * v;
        }
        e += q / s->mass[i];
    }
    return 0.5 * e;
}

/* Energy of the current positions; assembles L, M there for the
 * bi-Laplacian energy. */
static cf_status current_energy(cf_flow *flow, baseline_state *s, double *energy, double *assemble_seconds)
{
    if (is_bilaplacian(flow)) {
        double t0 = cfi_now_seconds();
        cf_status st = assemble(flow, s);
        if (assemble_seconds) *assemble_seconds += cfi_now_seconds() - t0;
        if (st != CF_OK) return st;
        *energy = bilaplacian_energy(flow, s);
        return CF_OK;
    }
    return cf_total_area(flow->ctx, flow->mesh, flow->positions, energy);
}

static void mass_centroid(const baseline_state *s, const double *x, double c[3])
{
    double w = 0.0;
    c[0] = c[1] = c[2] = 0.0;
    for (int32_t i = 0; i < s->nv; ++i) {
        for (int k = 0; k < 3; ++k) c[k] += s->mass[i] * x[3 * (size_t)i + k];
        w += s->mass[i];
    }
    for (int k = 0; k < 3; ++k) c[k] = w > 0.0 ? c[k] / w : 0.0;
}

/* Kazhdan et al. 2012, Sec. 5: restore the initial area and centroid. */
static cf_status rescale(cf_flow *flow, baseline_state *s)
{
    double area = 0.0;
    cf_status st = cf_total_area(flow->ctx, flow->mesh, flow->positions, &area);
    if (st != CF_OK) return st;
    if (!(area > 0.0)) return cfi_error(flow->ctx, CF_ERR_NUMERICAL, "rescale: total area is %g", area);
    st = cf_vertex_areas(flow->ctx, flow->mesh, flow->positions, CF_DUAL_AREA_BARYCENTRIC, s->mass);
    if (st != CF_OK) return st;
    double c[3];
    mass_centroid(s, flow->positions, c);
    double k = sqrt(flow->initial_area / area);
    for (int32_t i = 0; i < s->nv; ++i)
        for (int d = 0; d < 3; ++d) {
            double *p = &flow->positions[3 * (size_t)i + d];
            *p = s->centroid0[d] + k * (*p - c[d]);
        }
    return CF_OK;
}

/* A = tau * L P D^-1 L (pattern of L L) + D, D = diag(mass), P the
 * projection on the vertices that move (identity with a free boundary);
 * L and mass assembled. Row-by-column product with a dense position
 * workspace, no allocation. */
static void fill_bilaplacian_system(baseline_state *s, double tau)
{
    const cf_sparse *l = s->l;
    cf_sparse *a = s->a;
    int64_t nnz = cf_sparse_nnz(a);
    for (int64_t p = 0; p < nnz; ++p) a->values[p] = 0.0;
    for (int32_t j = 0; j < s->nv; ++j) {
        for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) s->pos[a->rowind[p]] = p;
        for (int32_t p = l->colptr[j]; p < l->colptr[j + 1]; ++p) {
            int32_t k = l->rowind[p];
            if (s->held && s->held[k]) continue;
            double lkj = l->values[p] / s->mass[k];
            for (int32_t q = l->colptr[k]; q < l->colptr[k + 1]; ++q) {
                int64_t slot = s->pos[l->rowind[q]];
                if (CF_NEVER(slot < 0)) continue;
                a->values[slot] += tau * l->values[q] * lkj;
            }
        }
        for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) s->pos[a->rowind[p]] = -1;
    }
    for (int32_t i = 0; i < s->nv; ++i) a->values[s->a_diag[i]] += s->mass[i];
}

/* boundary=fixed in the implicit system A d = r of the step's
 * displacement (A symmetric, both triangles stored): the held vertices do
 * not move (d_B = 0, so the held columns add nothing to the right-hand
 * side), and their rows and columns become m_i on the diagonal with
 * r_i = 0, so A stays symmetric positive definite. */
static void hold_boundary(baseline_state *s)
{
    cf_sparse *a = s->a;
    int32_t nv = s->nv;
    for (int32_t j = 0; j < nv; ++j) {
        int held_col = s->held[j];
        if (held_col)
            for (int c = 0; c < 3; ++c) s->b[(size_t)c * nv + j] = 0.0;
        for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) {
            int32_t i = a->rowind[p];
            if (i == j) {
                if (held_col) a->values[p] = s->mass[j];
                continue;
            }
            if (held_col || s->held[i]) a->values[p] = 0.0;
        }
    }
}

/* ---- create / destroy --------------------------------------------------- */

static void baseline_destroy(cf_flow *flow)
{
    baseline_state *s = flow->impl;
    if (!s) return;
    cf_context *ctx = flow->ctx;
    cf_cholesky_destroy(&s->chol);
    if (s->a != s->l) cf_sparse_destroy(&s->a);
    cf_sparse_destroy(&s->l);
    cfi_workspace_free_all(&s->ws);
    CFI_FREE(ctx, s, 1);
    flow->impl = NULL;
}

static cf_status find_diagonal(cf_context *ctx, const cf_sparse *m, int64_t *diag, const char *what)
{
    for (int32_t i = 0; i < m->ncols; ++i) {
        diag[i] = cf_sparse_find(m, i, i);
        if (diag[i] < 0) return cfi_error(ctx, CF_ERR_BAD_MESH, "vertex %d: no diagonal entry in %s", i, what);
    }
    return CF_OK;
}

static cf_status baseline_create(cf_flow *flow, const void *options)
{
    cf_context *ctx = flow->ctx;
    const cf_mesh *mesh = flow->mesh;
    const cf_baseline_options *opt = options;
    cf_flow_kind kind = kind_of(flow);
    int explicit_kind = kind == CF_FLOW_EXPLICIT_MCF || kind == CF_FLOW_EXPLICIT_BILAPLACIAN;
    if (!(opt->time_step > 0.0 || (explicit_kind && opt->time_step == 0.0)) || !isfinite(opt->time_step))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter 'time_step': must be positive%s, got %g",
                         explicit_kind ? " (or 0: auto)" : "", opt->time_step);
    if (opt->mass != CF_MASS_LUMPED_BARYCENTRIC && opt->mass != CF_MASS_LUMPED_VORONOI)
        return cfi_error(ctx, CF_ERR_UNSUPPORTED, "parameter 'mass': only lumped (barycentric, voronoi) is supported");
    if (!(opt->tolerance >= 0.0))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter 'tolerance': must be >= 0, got %g", opt->tolerance);
    if (opt->boundary != CF_BASELINE_BOUNDARY_FREE && opt->boundary != CF_BASELINE_BOUNDARY_FIXED)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "parameter 'boundary': must be free (0) or fixed (1), got %d",
                         (int)opt->boundary);
    int hold = mesh->boundary_loop_count > 0 && opt->boundary == CF_BASELINE_BOUNDARY_FIXED;
    if (hold && opt->rescale)
        return cfi_error(ctx, CF_ERR_INVALID_ARG,
                         "parameters 'rescale' and 'boundary': rescale=true would move the held boundary of this mesh; "
                         "use boundary=free with rescale=true");

    baseline_state *s = CFI_ALLOC(ctx, baseline_state, 1);
    if (!s) return CF_ERR_NOMEM;
    flow->impl = s;
    cfi_workspace_init(&s->ws, ctx);
    s->opt = *opt;
    s->nv = mesh->nv;
    size_t nv = (size_t)mesh->nv;
    s->slot_count = cf_cotan_laplacian_slot_count(mesh);
    s->slot_map = CFI_WS_ALLOC(&s->ws, int64_t, s->slot_count);
    s->l_diag = CFI_WS_ALLOC(&s->ws, int64_t, nv);
    s->a_diag = CFI_WS_ALLOC(&s->ws, int64_t, nv);
    s->mass = CFI_WS_ALLOC(&s->ws, double, nv);
    s->x = CFI_WS_ALLOC(&s->ws, double, 3 * nv);
    s->b = CFI_WS_ALLOC(&s->ws, double, 3 * nv);
    s->r = CFI_WS_ALLOC(&s->ws, double, 3 * nv);
    s->y = CFI_WS_ALLOC(&s->ws, double, 3 * nv);
    if (!s->slot_map || !s->l_diag || !s->a_diag || !s->mass || !s->x || !s->b || !s->r || !s->y) return CF_ERR_NOMEM;
    if (hold) {
        s->held = mesh->vertex_on_boundary;
        s->held_positions = CFI_WS_ALLOC(&s->ws, double, 3 * nv);
        if (!s->held_positions) return CF_ERR_NOMEM;
        memcpy(s->held_positions, flow->positions, 3 * nv * sizeof(double));
    }

    /* rescale's reference centroid, with the barycentric masses it uses */
    cf_status st = cf_vertex_areas(ctx, mesh, flow->positions, CF_DUAL_AREA_BARYCENTRIC, s->mass);
    if (st != CF_OK) return st;
    mass_centroid(s, flow->positions, s->centroid0);
    st = cf_cotan_laplacian_with_slots_floored(ctx, mesh, flow->positions, s->opt.weight_floor, &s->l, s->slot_map);
    if (st != CF_OK) return st;
    st = find_diagonal(ctx, s->l, s->l_diag, "the Laplacian");
    if (st != CF_OK) return st;
    st = assemble(flow, s);
    if (st != CF_OK) return st;

    /* Scale-free step (header): h^2, h^4 from the mean edge length, A0, A0^2. */
    double h = 0.0;
    for (int32_t e = 0; e < mesh->ne; ++e) {
        const double *p = flow->positions + 3 * (size_t)mesh->edge_vertices[2 * e];
        const double *q = flow->positions + 3 * (size_t)mesh->edge_vertices[2 * e + 1];
        h += sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
    }
    h = mesh->ne > 0 ? h / mesh->ne : 0.0;
    double a0 = flow->initial_area;
    if (!(h > 0.0) || !(a0 > 0.0)) return cfi_error(ctx, CF_ERR_BAD_MESH, "mesh has zero size (mean edge %g, area %g)", h, a0);
    switch (kind) {
    case CF_FLOW_EXPLICIT_MCF: s->tau = opt->time_step * h * h; break;
    case CF_FLOW_EXPLICIT_BILAPLACIAN: s->tau = opt->time_step * h * h * h * h; break;
    case CF_FLOW_IMPLICIT_MCF:
    case CF_FLOW_CONFORMAL_MCF: s->tau = opt->time_step * a0; break;
    case CF_FLOW_IMPLICIT_BILAPLACIAN: s->tau = opt->time_step * a0 * a0; break;
    default: return cfi_error(ctx, CF_ERR_INVALID_ARG, "not a baseline flow kind: %d", (int)kind);
    }
    /* the implicit flows take their step from the step policy (backtracking) */
    if (flow->method->policy.backtrack) cfi_flow_set_time_step(flow, s->tau);
    /* The explicit bi-Laplacian step is not a descent of its energy once L
     * and M follow the mesh: a thin tube shrinks under it and its energy,
     * 2 W on a closed surface, rises at first order in the step (a torus of
     * radius 1 and 0.4, `generate torus`: 53.5419 -> 53.5427 at step 1;
     * every knot tube of docs/spin.md "Long tubes"; a flat sheet's free
     * boundary). A rise of the layer's energy therefore does not show
     * instability. The energy of the operator the step was taken with does:
     * below forward Euler's limit it falls at every step (explicit_step),
     * so that is the test (explicit_step, under the same energy_check),
     * and the layer's own rise test is off. */
    if (kind == CF_FLOW_EXPLICIT_BILAPLACIAN) cfi_flow_policy_restrict(flow, 0, 1);

    cf_cholesky_options copt;
    cf_cholesky_options_default(&copt);
    copt.block_size = 1;
    if (kind == CF_FLOW_IMPLICIT_MCF || kind == CF_FLOW_CONFORMAL_MCF) {
        /* A = M + tau L has L's pattern: A is L's storage, refilled each step. */
        s->a = s->l;
        memcpy(s->a_diag, s->l_diag, nv * sizeof(int64_t));
        if (kind == CF_FLOW_CONFORMAL_MCF) {
            int64_t nnz = cf_sparse_nnz(s->l);
            s->l0_values = CFI_WS_ALLOC(&s->ws, double, nnz);
            if (!s->l0_values) return CF_ERR_NOMEM;
            memcpy(s->l0_values, s->l->values, (size_t)nnz * sizeof(double));
        }
        st = cf_cholesky_create(ctx, s->a, &copt, &s->chol);
        if (st != CF_OK) return st;
    } else if (kind == CF_FLOW_IMPLICIT_BILAPLACIAN) {
        st = cf_sparse_product(ctx, s->l, s->l, &s->a);
        if (st != CF_OK) return st;
        s->a->symmetric = 1;
        s->a->upper_only = 0;
        s->pos = CFI_WS_ALLOC(&s->ws, int64_t, nv);
        if (!s->pos) return CF_ERR_NOMEM;
        for (size_t i = 0; i < nv; ++i) s->pos[i] = -1;
        st = find_diagonal(ctx, s->a, s->a_diag, "the bi-Laplacian");
        if (st != CF_OK) return st;
        st = cf_cholesky_create(ctx, s->a, &copt, &s->chol);
        if (st != CF_OK) return st;
    }

    double energy = 0.0;
    st = current_energy(flow, s, &energy, NULL);
    if (st != CF_OK) return st;
    memset(&flow->info, 0, sizeof flow->info);
    flow->info.energy = energy;
    flow->info.energy_terms[0] = energy;
    flow->info.term_names[0] = is_bilaplacian(flow) ? "bilaplacian" : "area";
    return CF_OK;
}

static cf_status baseline_reset(cf_flow *flow)
{
    baseline_state *s = flow->impl;
    /* new positions (cf_flow_set_positions): the boundary is held there */
    if (s->held) memcpy(s->held_positions, flow->positions, 3 * (size_t)s->nv * sizeof(double));
    double energy = 0.0;
    cf_status st = current_energy(flow, s, &energy, NULL);
    if (st != CF_OK) return st;
    flow->info.energy = energy;
    flow->info.energy_terms[0] = energy;
    flow->converged = 0;
    /* the automatic step is measured against the new positions' */
    s->first_auto_tau = 0.0;
    s->stall_reported = 0;
    return CF_OK;
}

/* ---- steps -------------------------------------------------------------- */

/* Finishes a step: optional rescale, energy, collapse check. Rises of the
 * energy and convergence are the step policy's (cf_flow_step). */
static cf_status finish_step(cf_flow *flow, baseline_state *s, cf_flow_info *info, double tau)
{
    cf_status st = CF_OK;
    if (s->opt.rescale) {
        st = rescale(flow, s);
        if (st != CF_OK) return st;
    }
    double energy = 0.0;
    st = current_energy(flow, s, &energy, &info->assemble_seconds);
    if (st != CF_OK) return st;
    if (!s->opt.rescale) {
        /* These flows shrink a closed surface to a point in finite time
         * (spot_3k: area 5.7 -> 4e-3 -> 4e-6 -> 3e-11 in the last three
         * implicit steps). Past that the mass matrix vanishes against the
         * Laplacian and the next factorisation fails with an unhelpful "not
         * positive definite"; say what happened instead. */
        double area = energy;
        if (is_bilaplacian(flow)) {
            st = cf_total_area(flow->ctx, flow->mesh, flow->positions, &area);
            if (st != CF_OK) return st;
        }
        if (!(area >= BASELINE_COLLAPSE_AREA * flow->initial_area)) {
            /* an open surface with a free boundary shrinks too (blade_slivers_8k
             * under conformal-mcf: area 5e-8 of the start at step 7) */
            int open = flow->mesh->boundary_loop_count > 0;
            return cfi_error(flow->ctx, CF_ERR_NUMERICAL,
                             "%s: the surface collapsed (area %.3g, %.2g of the start): the flow shrinks a %s to a "
                             "point in finite time; %srescale=true keeps the area",
                             flow->method->name, area, area / flow->initial_area,
                             !open      ? "closed surface"
                             : s->held  ? "surface onto its held border"
                                        : "surface with a free boundary",
                             open && !s->held ? "boundary=fixed holds its border, " : "");
        }
    }
    info->time_step = tau;
    info->energy = energy;
    info->energy_terms[0] = energy;
    info->term_names[0] = is_bilaplacian(flow) ? "bilaplacian" : "area";
    return CF_OK;
}

/* The implicit systems are M + tau L (M^-1 L) with M > 0, positive definite
 * in exact arithmetic; a factorisation fails in practice only when triangles
 * have degenerated (the bi-Laplacian flow's tangential drift does this:
 * angles of 180 deg after ~270 rescaled steps on a bumpy sphere) and a tiny
 * vertex mass meets huge cotan weights. Say so, naming the worst face. */
static cf_status explain_not_posdef(cf_flow *flow)
{
    const cf_mesh *mesh = flow->mesh;
    double worst = INFINITY;
    int32_t worst_face = -1;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        for (int k = 0; k < 3; ++k) {
            double angle = cf_corner_angle(flow->positions, mesh->triangles + 3 * (size_t)f, k);
            if (angle < worst) {
                worst = angle;
                worst_face = f;
            }
        }
    }
    double degrees = worst * 180.0 / 3.14159265358979323846;
    if (degrees < 1.0)
        return cfi_error(flow->ctx, CF_ERR_NOT_POSDEF,
                         "%s: the system matrix is not numerically positive definite: the mesh has degenerated (face "
                         "%d has an angle of %.3g deg); a smaller time_step or a flow that keeps its triangles "
                         "(conformal-mcf, spin-willmore) may help",
                         flow->method->name, worst_face, degrees);
    return cfi_error(flow->ctx, CF_ERR_NOT_POSDEF,
                     "%s: the system matrix is not numerically positive definite (smallest angle %.3g deg, face %d)",
                     flow->method->name, degrees, worst_face);
}

/* Forward Euler on x' = -M^-1 L x is stable for tau <= 2 / mu_max, mu_max
 * the largest eigenvalue of M^-1 L (similar to M^-1/2 L M^-1/2, so real);
 * on x' = -(M^-1 L)^2 x for tau <= 2 / mu_max^2. Gershgorin's bound
 * mu_max <= max_i sum_j |L_ij| / M_i is cheap (one pass over L) and never
 * below mu_max: the auto step (time_step = 0) takes 0.9 of the step it gives
 * for MCF and 0.5 for the bi-Laplacian (whose energy is not exactly the one
 * the linear step descends once L and M move: bunny_scan_35k rose by 5e-5 at
 * step 5 with 0.9), recomputed every step since L and M change.
 * On a near-equilateral mesh it is about 1/4 of h^2 (MCF); slivers and
 * small triangles lower it, which is what makes explicit flows slow. */
static double explicit_auto_tau(const baseline_state *s, cf_flow_kind kind, int32_t *bounding_vertex)
{
    const cf_sparse *l = s->l;
    double bound = 0.0;
    *bounding_vertex = -1;
    for (int32_t j = 0; j < l->ncols; ++j) {
        double sum = 0.0;
        for (int32_t p = l->colptr[j]; p < l->colptr[j + 1]; ++p) sum += fabs(l->values[p]);
        double r = sum / s->mass[j]; /* L is symmetric: column sums are row sums */
        if (r > bound) {
            bound = r;
            *bounding_vertex = j;
        }
    }
    if (!(bound > 0.0)) return 0.0;
    return kind == CF_FLOW_EXPLICIT_MCF ? 0.9 * 2.0 / bound : 0.5 * 2.0 / (bound * bound);
}

static cf_status explicit_step(cf_flow *flow, cf_flow_info *info)
{
    baseline_state *s = flow->impl;
    int32_t nv = s->nv;
    int bilaplacian = kind_of(flow) == CF_FLOW_EXPLICIT_BILAPLACIAN;
    double frozen_before = 0.0; /* the bi-Laplacian energy at the step start */
    double t0 = cfi_now_seconds();
    cf_status st = assemble(flow, s);
    if (st != CF_OK) return st;
    if (s->opt.time_step == 0.0) {
        int32_t vertex = -1;
        s->tau = explicit_auto_tau(s, kind_of(flow), &vertex);
        if (!(s->tau > 0.0) || !isfinite(s->tau))
            return cfi_error(flow->ctx, CF_ERR_NUMERICAL, "%s: no stable time step on this mesh (Laplacian bound %g)",
                             flow->method->name, s->tau);
        /* scale-free: per unit of the current area (MCF) or its square
         * (bi-Laplacian), so that a surface shrinking as a whole does not
         * count; the lumped masses sum to the area */
        double area = 0.0;
        for (int32_t i = 0; i < nv; ++i) area += s->mass[i];
        double scaled = s->tau / (bilaplacian ? area * area : area);
        if (s->first_auto_tau == 0.0) {
            s->first_auto_tau = scaled;
        } else if (!s->stall_reported && scaled < CFI_AUTO_STEP_STALL * s->first_auto_tau) {
            s->stall_reported = 1;
            cfi_log(flow->ctx, CF_LOG_WARNING,
                    "iteration %lld: %s: the automatic time step fell to %.3g of the first step's, relative to the "
                    "surface's size (forward Euler's stability limit, set at vertex %d, where triangles degenerate): "
                    "the flow hardly moves any more; %s take larger steps (said once)",
                    (long long)info->iteration, flow->method->name, scaled / s->first_auto_tau, vertex,
                    bilaplacian ? "implicit-bilaplacian and spin-willmore" : "implicit-mcf and conformal-mcf");
        }
    }
    double t1 = t0;
    if (!bilaplacian) {
        info->assemble_seconds = cfi_now_seconds() - t0;
        t1 = cfi_now_seconds();
        laplacian_of_positions(s, flow->positions);
    } else {
        /* r = L M^-1 (P L x) */
        frozen_before = bilaplacian_energy(flow, s); /* leaves P L x in s->y */
        info->assemble_seconds = cfi_now_seconds() - t0;
        t1 = cfi_now_seconds();
        for (int c = 0; c < 3; ++c)
            for (int32_t i = 0; i < nv; ++i) s->b[(size_t)c * nv + i] = s->y[3 * (size_t)i + c] / s->mass[i];
        for (int c = 0; c < 3; ++c) cf_sparse_multiply(s->l, s->b + (size_t)c * nv, s->r + (size_t)c * nv);
    }
    /* x <- x - tau M^-1 r, r = L x (MCF) or L M^-1 L x; held vertices stay */
    for (int32_t i = 0; i < nv; ++i) {
        if (s->held && s->held[i]) continue;
        for (int c = 0; c < 3; ++c) flow->positions[3 * (size_t)i + c] -= s->tau * s->r[(size_t)c * nv + i] / s->mass[i];
    }
    info->solve_seconds = cfi_now_seconds() - t1;
    if (bilaplacian) {
        /* the step's energy with the L and M it was taken with (not yet
         * reassembled): forward Euler lowers it below its stability limit */
        double frozen_after = bilaplacian_energy(flow, s);
        if (flow->policy.opt.energy_check && cfi_step_policy_rose(&flow->policy, frozen_before, frozen_after))
            return cfi_error(
                flow->ctx, CF_ERR_NUMERICAL,
                "%s: unstable step: the energy of the mesh before the step, with its L and M held, rose from %.9g to "
                "%.9g (time step %g): %s; energy_check=false accepts such steps",
                flow->method->name, frozen_before, frozen_after, s->tau,
                s->opt.time_step == 0.0
                    ? "this was the automatic step (time_step 0), 0.5 of forward Euler's stability limit by "
                      "Gershgorin's bound, which should not happen"
                    : "the time step given (units of h^4) is above forward Euler's stability limit for this mesh; a "
                      "smaller one, or 0 (automatic), helps");
        /* With energy_check=false, the blow-up check on this energy: the
         * bi-Laplacian energy is scale-free, so an exploding mesh can keep
         * the reassembled one almost level (a torus at time_step 100 with
         * energy_check=false: area x3.2, energy 53.5 -> 85.0): the layer's
         * blow-up check would miss it, this energy does not (53.5 -> 2007) */
        if (cfi_step_policy_blew_up(&flow->policy, frozen_before, frozen_after, flow->policy.blowup_factor))
            return cfi_error(flow->ctx, CF_ERR_NUMERICAL,
                             "%s: the step blew up: the energy of the mesh before the step, with its L and M held, "
                             "grew from %.6g to %.6g (more than %gx; time step %g): the time step is above forward "
                             "Euler's stability limit; try a smaller time_step, or 0 (automatic)",
                             flow->method->name, frozen_before, frozen_after, flow->policy.blowup_factor, s->tau);
    }
    st = finish_step(flow, s, info, s->tau);
    if (st == CF_OK && bilaplacian && !s->rise_reported &&
        cfi_step_policy_rose(&flow->policy, frozen_before, info->energy)) {
        /* taken (stable), but a user watching the energy should know why it rose */
        s->rise_reported = 1;
        cfi_log(flow->ctx, CF_LOG_WARNING,
                "iteration %lld: %s: the energy rose (%.9g -> %.9g) in a stable step (the energy of the L and M the "
                "step was taken with fell): with L and M following the mesh this step is no descent of it (a thin "
                "tube shrinks, a free boundary moves in); later rises are not reported",
                (long long)info->iteration, flow->method->name, frozen_before, info->energy);
    }
    return st;
}

static cf_status implicit_step(cf_flow *flow, cf_flow_info *info)
{
    baseline_state *s = flow->impl;
    int32_t nv = s->nv;
    cf_flow_kind kind = kind_of(flow);
    /* s->tau, or less after the step policy rejected a step (it halves the
     * step and grows it back) */
    double tau = cfi_flow_time_step(flow);
    double t0 = cfi_now_seconds();
    cf_status st;
    if (kind == CF_FLOW_CONFORMAL_MCF) {
        /* Kazhdan 2012, Eq. (4): stiffness frozen at the initial mesh. */
        st = assemble_mass(flow, s);
        if (st != CF_OK) return st;
        int64_t nnz = cf_sparse_nnz(s->a);
        for (int64_t p = 0; p < nnz; ++p) s->a->values[p] = tau * s->l0_values[p];
        for (int32_t i = 0; i < nv; ++i) s->a->values[s->a_diag[i]] += s->mass[i];
    } else {
        st = assemble(flow, s);
        if (st != CF_OK) return st;
        if (kind == CF_FLOW_IMPLICIT_MCF) {
            /* Desbrun 1999, Eq. (9) with the mass matrix: (M + tau L) x' = M x */
            int64_t nnz = cf_sparse_nnz(s->a);
            for (int64_t p = 0; p < nnz; ++p) s->a->values[p] *= tau;
            for (int32_t i = 0; i < nv; ++i) s->a->values[s->a_diag[i]] += s->mass[i];
        } else {
            fill_bilaplacian_system(s, tau);
        }
    }
    /* A x' = M x solved for the displacement d = x' - x: A d = -(A - M) x
     * = -tau K x (K = L, L0 or L P M^-1 L, whose rows sum to zero), with
     * K x from the coordinates' differences (A's off-diagonal part is
     * tau K's; for the bi-Laplacian L x from them, then L P M^-1 of it).
     * The same step; but a mesh far from the origin keeps its precision:
     * solving for x' directly carried cond(A) eps |x| of error, 0.19 of
     * spot's size after 10 implicit bi-Laplacian steps 1e6 away. */
    if (kind == CF_FLOW_IMPLICIT_BILAPLACIAN) {
        /* tau L P M^-1 (L x): two passes over L rather than one over A,
         * whose pattern (L L's) has ~3.5 times L's entries */
        laplacian_of_positions(s, flow->positions);
        for (int c = 0; c < 3; ++c) {
            double *z = s->x + (size_t)c * nv, *b = s->b + (size_t)c * nv;
            const double *lx = s->r + (size_t)c * nv;
            for (int32_t i = 0; i < nv; ++i) z[i] = s->held && s->held[i] ? 0.0 : lx[i] / s->mass[i];
            cf_sparse_multiply(s->l, z, b);
            for (int32_t i = 0; i < nv; ++i) b[i] *= -tau;
        }
    } else {
        for (int c = 0; c < 3; ++c) {
            for (int32_t i = 0; i < nv; ++i) s->x[(size_t)c * nv + i] = flow->positions[3 * (size_t)i + c];
            double *b = s->b + (size_t)c * nv;
            cf_sparse_multiply_zero_row_sums(s->a, s->x + (size_t)c * nv, b);
            for (int32_t i = 0; i < nv; ++i) b[i] = -b[i];
        }
    }
    if (s->held) hold_boundary(s);
    info->assemble_seconds = cfi_now_seconds() - t0;

    double t1 = cfi_now_seconds();
    st = cf_cholesky_factorize(s->chol, s->a);
    if (st == CF_ERR_NOT_POSDEF) return explain_not_posdef(flow);
    if (st != CF_OK) return st;
    info->factorize_seconds = cfi_now_seconds() - t1;
    double t2 = cfi_now_seconds();
    st = cf_cholesky_solve(s->chol, 3, s->b, s->x);
    if (st != CF_OK) return st;
    info->solve_seconds = cfi_now_seconds() - t2;

    /* relative residual |A d - r| / |r| of the three solves */
    double rr = 0.0, bb = 0.0;
    for (int c = 0; c < 3; ++c) {
        double *r = s->r + (size_t)c * nv;
        memcpy(r, s->b + (size_t)c * nv, (size_t)nv * sizeof(double));
        cf_sparse_multiply_add(s->a, 1.0, s->x + (size_t)c * nv, -1.0, r);
        const double *b = s->b + (size_t)c * nv;
        for (int32_t i = 0; i < nv; ++i) {
            rr += r[i] * r[i];
            bb += b[i] * b[i];
        }
    }
    info->residuals[0] = bb > 0.0 ? sqrt(rr / bb) : sqrt(rr);
    info->residual_names[0] = "solve";
    for (int32_t i = 0; i < nv; ++i) {
        const double *from = s->held && s->held[i] ? s->held_positions : NULL;
        for (int c = 0; c < 3; ++c)
            flow->positions[3 * (size_t)i + c] =
                from ? from[3 * (size_t)i + c] : flow->positions[3 * (size_t)i + c] + s->x[(size_t)c * nv + i];
    }
    return finish_step(flow, s, info, tau);
}

/* The explicit flows' rise. The message prints the step used; the hint
 * must not claim it was above the stability limit: the automatic step
 * (time_step 0, the default) is below forward Euler's bound for the
 * operator of the mesh before the step, and a rise under it comes from the
 * operator changing as the mesh moves (an open flat sheet, `generate
 * sheet` or plane_841, rises with the bi-Laplacian and boundary=free at
 * every step size, at first order in the step), which a smaller step does
 * not cure. */
#define BASELINE_EXPLICIT_HINT(factor_, unit_)                                                                 \
    "with time_step 0 (the default) this was the automatic step, " factor_ " of forward Euler's stability "   \
    "limit for the current mesh, so the rise comes from the mesh moving (e.g. at a boundary), which a "       \
    "smaller time_step may not cure (energy_check=false accepts rising steps); with a time_step given "       \
    "(units of " unit_ "), a smaller one helps if it was above the stability limit"

#define BASELINE_METHOD(sym, kind_, name_, desc_, defaults_, params_, stepfn_, policy_)                                 \
    const cfi_flow_method sym = {                                                                              \
        .kind = (kind_),                                                                                       \
        .name = (name_),                                                                                       \
        .description = (desc_),                                                                                \
        .options_size = sizeof(cf_baseline_options),                                                          \
        .options_default = (defaults_),                                                                        \
        .params = (params_),                                                                                   \
        .param_count = (int32_t)(sizeof(params_) / sizeof((params_)[0])),                                     \
        .create = baseline_create,                                                                             \
        .step = (stepfn_),                                                                                     \
        .reset = baseline_reset,                                                                               \
        .destroy = baseline_destroy,                                                                           \
        .policy = policy_,                                                                                     \
    }
/* The blow-up and divergence checks only act on a step the rise check let
 * through, i.e. with energy_check=false. Explicit flows: blow-up check on
 * (factor 10): a forward Euler step above its stability limit (area x490
 * in one step on spot_3k at time_step 50) then fails cleanly (exit 3,
 * "iteration N: ... blew up") instead of running on from an exploded
 * state. Implicit flows: both available, off by default: energy_check=false
 * is how a user asks for backward Euler's raw steps (cli.cli_policy: the
 * bumpy plane's 130.8 -> 588 -> 13 552). Divergence off for all: with
 * energy_check=false a user asks for steps that may rise (plane_841's
 * bi-Laplacian energy with boundary=free rises at every step size), and
 * with it on an accepted step never ends above its start. */
#define BASELINE_EXPLICIT_POLICY(unit_, hint_)                                                                 \
    {.rise_check = 1, .backtrack = 0, .convergence = 1, .unit = (unit_), .rise_hint = (hint_),                 \
     .blowup_check = 1, .blowup_default = 10.0, .divergence_check = 1,                                         \
     .divergence_cause = " is above this mesh's stability limit"}
#define BASELINE_IMPLICIT_POLICY(unit_)                                                                        \
    {.rise_check = 1, .backtrack = 1, .convergence = 1, .unit = (unit_), .blowup_check = 1, .divergence_check = 1}

BASELINE_METHOD(cfi_explicit_mcf_method, CF_FLOW_EXPLICIT_MCF, "explicit-mcf",
                "explicit (forward Euler) mean curvature flow; energy: area", default_explicit_mcf, explicit_params,
                explicit_step,
                BASELINE_EXPLICIT_POLICY(CFI_ENERGY_UNIT_INITIAL_AREA, BASELINE_EXPLICIT_HINT("0.9", "h^2")));
BASELINE_METHOD(cfi_implicit_mcf_method, CF_FLOW_IMPLICIT_MCF, "implicit-mcf",
                "implicit mean curvature flow (Desbrun et al. 1999, backward Euler); energy: area",
                default_implicit_mcf, implicit_params, implicit_step,
                BASELINE_IMPLICIT_POLICY(CFI_ENERGY_UNIT_INITIAL_AREA));
BASELINE_METHOD(cfi_conformal_mcf_method, CF_FLOW_CONFORMAL_MCF, "conformal-mcf",
                "conformalized mean curvature flow (Kazhdan, Solomon, Ben-Chen 2012); energy: area",
                default_conformal_mcf, implicit_params, implicit_step,
                BASELINE_IMPLICIT_POLICY(CFI_ENERGY_UNIT_INITIAL_AREA));
BASELINE_METHOD(cfi_explicit_bilaplacian_method, CF_FLOW_EXPLICIT_BILAPLACIAN, "explicit-bilaplacian",
                "explicit bi-Laplacian flow (Taubin-style); energy: (1/2) x^T L M^-1 L x",
                default_explicit_bilaplacian, explicit_params, explicit_step,
                BASELINE_EXPLICIT_POLICY(CFI_ENERGY_UNIT_ONE, BASELINE_EXPLICIT_HINT("0.5", "h^4")));
BASELINE_METHOD(cfi_implicit_bilaplacian_method, CF_FLOW_IMPLICIT_BILAPLACIAN, "implicit-bilaplacian",
                "implicit bi-Laplacian flow (backward Euler); energy: (1/2) x^T L M^-1 L x",
                default_implicit_bilaplacian, implicit_params, implicit_step,
                BASELINE_IMPLICIT_POLICY(CFI_ENERGY_UNIT_ONE));
