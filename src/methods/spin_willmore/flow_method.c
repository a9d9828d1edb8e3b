/*
 * Conformal Willmore flow in curvature space: Crane, Pinkall, Schroeder
 * 2013, "Robust Fairing via Conformal Curvature Flow", Table 1 and
 * Sections 4, 6.1-6.3, App. B-E.
 *
 * One step on the current surface f:
 *   I.   H from the cotan Laplacian (Sec. 6.1);
 *   II.  rhodot = -2 H, optionally filtered v <- v - (id + sigma Delta^k)^-1 v (Sec. 4);
 *   III. constraints (Sec. 6.2): inversion N^x,y,z, then Moebius balancing
 *        (App. E.1), then total curvature 1 and exactness: by default the
 *        discrete linearisation of "no periods" (exactness_columns_linearized),
 *        or App. C.1's Z_i^x,y,z on closed surfaces (exactness_linearized = 0);
 *   IV.  rho = tau rhodot (so mu~ = (1 - 2 tau) mu, NOTES.md);
 *   V.   lambda = smallest eigenvector of X(rho) by one inverse power
 *        iteration from lambda = 1 (Sec. 6.4.2), with lambda restricted to
 *        r (a - b V~) on the boundary for prescribed binormals / CMC
 *        (Sec. 6.3.1), or the Dirichlet solve of Sec. 6.3.2 for a fixed
 *        boundary;
 *   VI.  transformed edges and the cotan Poisson problem (Eq. (6)), by
 *        default in the metric of the starting surface (input_metric); then
 *        the vertex-scale fairing's candidate (I + fairing tau L0)^-1 x,
 *        kept when its W is lower (option `fairing`; the paper is silent:
 *        docs/spin.md, "Vertex-scale fairing"); under `adaptive`, on closed
 *        surfaces by default, an attempt whose map makes more distortion
 *        than its vertex scales explain is rejected (max_conformal_excess;
 *        docs/spin.md, "The step's non-conformal excess").
 * With `adaptive`, the flow layer's step policy redoes IV-VI with tau
 * halved while W would rise (methods/flow.c, cf_flow_step); when its last
 * retry would stall, VI in the current metric is tried first (step_policy.c).
 * The symbolic factorisations of X (block size 4, complex form by default)
 * and L are computed once at creation; each step only refills values and
 * refactorises (X; X(0) for exactness; L only with the current metric).
 *
 * This file holds create / destroy, the geometry of the current surface and
 * the step itself in the flow layer's three parts: cfi_spin_begin_step
 * (I-II here, III in constraints.c), cfi_spin_attempt (IV-VI, redone by the
 * layer's step policy) and cfi_spin_end_step (the checks of step_policy.c
 * and the report); the other
 * concerns have a file each, listed in spin_flow.h.
 */
#include "methods/spin_willmore/spin_flow.h"
#include "curvflow/metrics.h"
#include "curvflow/ops.h"

#include <math.h>
#include <string.h>

/* ---- geometry of the current surface ---------------------------------- */

/* Refills L, areas, normals, L f, H and the energy W = sum |L f|_i^2 / (4 A_i)
 * (as cf_willmore_energy; interior vertices only when there is a boundary). */
cf_status cfi_spin_update_geometry(cf_flow *flow, cfi_spin_state *s, const double *x)
{
    cf_context *ctx = flow->ctx;
    const cf_mesh *mesh = flow->mesh;
    cf_status st = s->poisson ? cf_edge_poisson_set_metric(s->poisson, x)
                              : cf_cotan_laplacian_refill_floored(s->lap, mesh, x, s->opt.weight_floor, s->lap_slots);
    if (st == CF_OK) st = cf_vertex_areas(ctx, mesh, x, CF_DUAL_AREA_BARYCENTRIC, s->area);
    if (st == CF_OK) st = cf_vertex_normals(ctx, mesh, x, s->normal);
    if (st != CF_OK) return st;
    const cf_sparse *l = s->poisson ? cf_edge_poisson_laplacian(s->poisson) : s->lap;
    memset(s->lx, 0, 3 * (size_t)s->nv * sizeof(double));
    for (int32_t j = 0; j < s->nv; ++j)
        for (int32_t p = l->colptr[j]; p < l->colptr[j + 1]; ++p) {
            int32_t i = l->rowind[p];
            for (int c = 0; c < 3; ++c) s->lx[3 * i + c] += l->values[p] * x[3 * j + c];
        }
    double w = 0.0;
    for (int32_t i = 0; i < s->nv; ++i) {
        const double *v = s->lx + 3 * i, *n = s->normal + 3 * i;
        if (!(s->area[i] > 0.0)) return cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "vertex %d: zero dual area", i);
        if (mesh->vertex_on_boundary[i]) {
            s->h[i] = 0.0;
            continue;
        }
        s->h[i] = (v[0] * n[0] + v[1] * n[1] + v[2] * n[2]) / (2.0 * s->area[i]);
        w += (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) / (4.0 * s->area[i]);
    }
    s->energy = w;
    return CF_OK;
}

/* ---- creation ---------------------------------------------------------- */

void cfi_spin_destroy(cf_flow *flow)
{
    cfi_spin_state *s = flow->impl;
    if (!s) return;
    cf_context *ctx = flow->ctx;
    cfi_dirac_destroy(ctx, &s->dirac);
    cf_cholesky_destroy(&s->chol);
    cf_cholesky_destroy(&s->chol0);
    cf_edge_poisson_destroy(&s->poisson);
    cf_edge_poisson_destroy(&s->poisson_input);
    cf_sparse_destroy(&s->lap);
    cf_spectral_filter_destroy(&s->filter);
    cf_vertex_fairing_destroy(&s->fairing);
    cf_tangential_relaxation_destroy(&s->relaxation);
    cfi_spin_class_destroy(flow->ctx, &s->keep_class);
    cfi_workspace_free_all(&s->ws);
    CFI_FREE(ctx, s, 1);
    flow->impl = NULL;
}

/* The state's arrays, from the workspace (freed together by cfi_spin_destroy).
 * dim: harmonic dimension of the exactness constraint (0: off). */
static cf_status allocate_arrays(cfi_spin_state *s, int32_t dim)
{
    cfi_workspace *ws = &s->ws;
    int64_t nv = s->nv, ne = s->ne;
    int64_t zcols = s->linearized ? 3 * (int64_t)dim : dim;
    s->max_cols = 4 + 3 * dim; /* N x,y,z, 1, and 3 per harmonic form at most (constraints.c) */
    int ok = 1;
#define WS_ARRAY(field, count) ok = ok && ((field) = CFI_WS_ALLOC(ws, double, (count))) != NULL
    if (s->linearized) WS_ARRAY(s->hweights, ne);
    if (dim) {
        WS_ARRAY(s->harmonic, ne * dim);
        WS_ARRAY(s->zrhs, 4 * nv * zcols);
        WS_ARRAY(s->zsol, 4 * nv * zcols);
    }
    WS_ARRAY(s->area, nv);
    WS_ARRAY(s->normal, 3 * nv);
    WS_ARRAY(s->h, nv);
    if (s->opt.mobius) WS_ARRAY(s->rest_area, nv); /* Moebius balancing only, as vtmp */
    WS_ARRAY(s->rhodot, nv);
    WS_ARRAY(s->lambda, 4 * nv);
    if (s->fixed_boundary) WS_ARRAY(s->qrhs, 4 * nv);
    WS_ARRAY(s->qwork, 4 * nv);
    WS_ARRAY(s->basis, nv * s->max_cols);
    WS_ARRAY(s->edges, 3 * ne);
    WS_ARRAY(s->newpos, 3 * nv);
    /* Scratch of one phase each, in one array: rho from IV to the fill of
     * X in V, the recovered positions in VI, L f inside
     * cfi_spin_update_geometry (after VI). */
    s->lx = s->newpos;
    s->rho = s->newpos;
    if (s->opt.mobius) WS_ARRAY(s->vtmp, nv);
    if (s->opt.fairing > 0.0 && !s->restricted_boundary) WS_ARRAY(s->faired, 3 * nv);
    if (s->relax_iterations > 0) WS_ARRAY(s->relaxed, 3 * nv);
    WS_ARRAY(s->placed_area, nv);
    if (s->period_newton) {
        int64_t nz = 3 * (int64_t)dim;
        WS_ARRAY(s->period_rho, nv);
        WS_ARRAY(s->period_dx, 4 * nv * nz);
        WS_ARRAY(s->period_sol, 4 * nv * nz);
        WS_ARRAY(s->period_lambda, 4 * nv);
        WS_ARRAY(s->period_block, CFI_SPIN_PERIOD_BLOCK * 3 * nz);
        WS_ARRAY(s->period_acc, nz * nz);
        WS_ARRAY(s->period_matrix, nz * nz);
        WS_ARRAY(s->period_values, nz);
        WS_ARRAY(s->period_work, cf_dense_least_squares_work_size((int32_t)nz, (int32_t)nz));
    }
    if (s->restricted_boundary) {
        WS_ARRAY(s->frames, 16 * nv);
        WS_ARRAY(s->target, 3 * nv);
        WS_ARRAY(s->binormal, 3 * nv);
    }
#undef WS_ARRAY
    return ok ? CF_OK : CF_ERR_NOMEM;
}

/* The Poisson solver in the current metric (H every step; the positions
 * when they keep the current metric; the harmonic forms of the exactness
 * constraint). A fixed boundary makes its vertices known values (Sec.
 * 6.3.2). When no solve needs it (input_metric without a fixed boundary,
 * no exactness, no stall retry), only its Laplacian is kept, for H: its
 * solver's symbolic factor, slots and right-hand sides took ~100 MB at 655k
 * vertices (docs/memory.md). Same Laplacian, same values. */
static cf_status create_current_poisson(cf_flow *flow, cfi_spin_state *s)
{
    cf_context *ctx = flow->ctx;
    const cf_mesh *mesh = flow->mesh;
    if (s->opt.input_metric && !s->fixed_boundary && s->harmonic_dim == 0) {
        s->lap_slots = CFI_WS_ALLOC(&s->ws, int64_t, cf_cotan_laplacian_slot_count(mesh));
        if (!s->lap_slots) return CF_ERR_NOMEM;
        return cf_cotan_laplacian_with_slots_floored(ctx, mesh, flow->positions, s->opt.weight_floor, &s->lap,
                                                     s->lap_slots);
    }
    if (!s->fixed_boundary)
        return cf_edge_poisson_create_floored(ctx, mesh, flow->positions, 0, NULL, s->opt.weight_floor, &s->poisson);
    int32_t count = 0;
    for (int32_t i = 0; i < mesh->nv; ++i) count += mesh->vertex_on_boundary[i] != 0;
    int32_t *known = CFI_ALLOC(ctx, int32_t, count);
    if (!known) return CF_ERR_NOMEM;
    count = 0;
    for (int32_t i = 0; i < mesh->nv; ++i)
        if (mesh->vertex_on_boundary[i]) known[count++] = i;
    cf_status st = cf_edge_poisson_create_floored(ctx, mesh, flow->positions, count, known, s->opt.weight_floor,
                                                  &s->poisson);
    CFI_FREE(ctx, known, count);
    return st;
}

/* Symbolic factorisations of X (X(rho) and, for exactness, X(0)) on the
 * pattern of the filled Dirac matrix. */
static cf_status create_dirac(cf_flow *flow, cfi_spin_state *s)
{
    cf_context *ctx = flow->ctx;
    const cf_mesh *mesh = flow->mesh;
    /* X only in complex form (never the real one) when every use of it
     * takes that form: complex factorisation, and neither the prescribed/cmc
     * frames, which rewrite the real form's blocks, nor the fixed boundary,
     * whose cf_min_quad eliminates blocks of the real form (docs/memory.md) */
    int32_t complex_only = s->opt.complex_factorization && !s->restricted_boundary && !s->fixed_boundary;
    cf_status st = cfi_dirac_create_form(ctx, mesh, complex_only, &s->dirac);
    if (st == CF_OK) st = cfi_dirac_fill(s->dirac, mesh, flow->positions, NULL, s->eps);
    if (st != CF_OK) return st;
    cf_cholesky_options co;
    cf_cholesky_options_default(&co);
    co.block_size = 4;
    /* X is refactorised at every step (X(0) too on genus > 0), so METIS's
     * slower analysis, once per mesh, pays back where AUTO's rule does not
     * try it: bob_5k's complex factorisation 26-28 -> 21.5-22.6 ms (30 %
     * fewer flops; blade_slivers_8k 46 %, the built-in bumpy sphere 44 %;
     * docs/linalg.md, "Ordering") */
    co.ordering = CF_ORDERING_AUTO_REFACTORISED;
    /* X(rho) is a Hermitian quaternionic matrix; its complex form halves the
     * factorisation (docs/linalg.md). The boundary frames of prescribed/cmc
     * boundaries mix the quaternion components, so those keep the real form;
     * X(0) of the exactness constraint never has them. */
    co.quaternion_blocks = s->opt.complex_factorization && !s->restricted_boundary;
    /* A fixed boundary eliminates the boundary quaternions (whole blocks,
     * so the interior block keeps the complex form; dirac.c). */
    if (s->fixed_boundary) st = cfi_dirac_fixed_create(ctx, s->dirac, mesh, s->opt.complex_factorization);
    else st = cfi_dirac_analyse(ctx, s->dirac, &co, &s->chol);
    co.quaternion_blocks = s->opt.complex_factorization != 0;
    if (st == CF_OK && s->harmonic_dim) st = cfi_dirac_analyse(ctx, s->dirac, &co, &s->chol0);
    /* the solve workspaces now: steps allocate nothing (lambda: one column;
     * exactness: one per form, three per form when linearised) */
    if (st == CF_OK && s->chol) st = cf_cholesky_reserve_solve(s->chol, 1);
    if (st == CF_OK && s->chol0) st = cf_cholesky_reserve_solve(s->chol0, s->linearized ? 3 * s->harmonic_dim : s->harmonic_dim);
    return st;
}

/* The face thinnest against its size (its area over its longest edge
 * squared, the mesh check's measure, whose zero is CFI_ZERO_AREA_RATIO;
 * 0.43 for an equilateral triangle) below which spin-willmore speaks: a
 * vertex within about 1e-10 of an edge's length from its neighbour. From
 * 1e-11 on, measured on spot_3k, exact cotan weights of 1 / that ratio cost
 * every solve its accuracy and the flow stops far from round (W/4pi 2.8-5.6
 * after 10 steps instead of 1.002); the weight floor (option weight_floor,
 * on by default since session 30) bounds them, and the flow ends at 1.002
 * (docs/spin.md, "Near-duplicate vertices"). Every shared and generated
 * mesh is above 1e-6. */
#define CFI_SPIN_THIN_FACE_WARNING 1e-10

/* With the floor: a note (info) that it is in use; without: the warning. */
static void report_thin_faces(const cf_flow *flow, double weight_floor)
{
    const cf_mesh *mesh = flow->mesh;
    const double *x = flow->positions;
    double least = INFINITY;
    int32_t face = -1, count = 0;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * (int64_t)f;
        double longest2 = 0.0;
        double area = cfi_triangle_area(x + 3 * (int64_t)t[0], x + 3 * (int64_t)t[1], x + 3 * (int64_t)t[2], &longest2);
        double ratio = area / longest2;
        if (!(ratio < CFI_SPIN_THIN_FACE_WARNING)) continue;
        ++count;
        if (ratio < least) {
            least = ratio;
            face = f;
        }
    }
    if (face < 0) return;
    if (weight_floor > 0.0)
        cfi_log(flow->ctx, CF_LOG_INFO,
                "spin-willmore: face %d is nearly flat (its area is %.2g of its longest edge squared; %d face%s below "
                "%g): a near-duplicate vertex? Its cotan weights are bounded by weight_floor %g",
                face, least, count, count == 1 ? "" : "s", CFI_SPIN_THIN_FACE_WARNING, weight_floor);
    else
        cfi_log(flow->ctx, CF_LOG_WARNING,
                "spin-willmore: face %d is nearly flat (its area is %.2g of its longest edge squared; %d face%s below "
                "%g): a near-duplicate vertex? With weight_floor=0 its weights cost the solves their accuracy and the "
                "flow may stop far from its minimum; the default weight_floor or welding such vertices helps "
                "(docs/spin.md, \"Near-duplicate vertices\")",
                face, least, count, count == 1 ? "" : "s", CFI_SPIN_THIN_FACE_WARNING);
}

cf_status cfi_spin_create(cf_flow *flow, const void *options)
{
    cf_context *ctx = flow->ctx;
    const cf_mesh *mesh = flow->mesh;
    const cf_spin_willmore_options *o = options;
    cf_status st = cfi_spin_validate_options(ctx, mesh, o);
    if (st != CF_OK) return st;

    cfi_spin_state *s = CFI_ALLOC(ctx, cfi_spin_state, 1);
    if (!s) return CF_ERR_NOMEM;
    flow->impl = s;
    cfi_workspace_init(&s->ws, ctx);
    s->opt = *o;
    s->opt.boundary_targets = (cf_param_values){NULL, 0}; /* the caller's array is read below, not kept */
    /* the flow layer's step policy retries with a smaller tau under
     * `adaptive` only; its rise check (W never rises) does not apply where
     * prescribed and cmc boundaries may raise W by design */
    cfi_flow_set_time_step(flow, o->time_step);
    cfi_flow_policy_restrict(flow, 1, o->adaptive);
    s->nv = mesh->nv;
    s->ne = mesh->ne;
    s->nf = mesh->nf;
    s->has_boundary = mesh->boundary_loop_count > 0;
    s->fixed_boundary = o->boundary_mode == CF_SPIN_BOUNDARY_FIXED;
    s->restricted_boundary = o->boundary_mode == CF_SPIN_BOUNDARY_PRESCRIBED || o->boundary_mode == CF_SPIN_BOUNDARY_CMC;
    cfi_flow_policy_restrict(flow, cfi_flow_backtracks(flow) && !s->restricted_boundary, 1);
    /* the layer's divergence check neither (W may end above its start) */
    cfi_flow_policy_restrict_checks(flow, 1, !s->restricted_boundary);

    int32_t dim = 0;
    st = cfi_spin_exactness_dimension(flow, o, &dim);
    if (st != CF_OK) goto fail;
    s->harmonic_dim = dim;
    /* Closed surfaces too by default: App. C's Z_i remove the periods only
     * approximately (bob 32x, elephant_g3_3k only 2.9x, at first order in
     * tau), the linearised condition to first order (elephant 20x at tau
     * 0.01, 87x at 0.002); docs/spin.md. */
    s->linearized = dim > 0 && (s->has_boundary || o->exactness_linearized);
    /* Newton corrections of the periods on closed surfaces only: with a free
     * boundary they slowed W on the lion, blade and bunny_scan (docs/spin.md,
     * "Periods") */
    s->period_newton = s->linearized && !s->has_boundary && o->period_iterations > 0;
    /* The bound on a step's non-conformal excess, by default on closed
     * surfaces only: there a step whose map makes distortion its vertex
     * scales do not explain leaves it in the triangles, and the flow then
     * stalls (cow_3k and dino_4k Loop-subdivided twice: first steps with an
     * excess of 0.50 and 0.47, then W/4pi stuck at 31.8 and 59.5 with mean Q
     * 1.55 and 1.60; bounded, 15.1 / 1.12 and 30.5 / 1.05); on the zoo's
     * closed meshes the first step's excess is at most 0.10, and no run
     * changes. With a boundary it changed only bunny_scan, whose mean Q rose
     * from 1.427 to 1.492 (docs/spin.md, "The step's non-conformal excess"). */
    s->excess_bound = o->max_conformal_excess >= 0.0 ? o->max_conformal_excess
                      : s->has_boundary               ? 0.0
                                                      : CFI_SPIN_CLOSED_EXCESS_BOUND;
    if (s->restricted_boundary || !cfi_flow_backtracks(flow)) s->excess_bound = 0.0;
    /* a stall in the input metric is retried in the current one (docs/spin.md,
     * "Robustness"; cfi_spin_fallback) */
    s->stall_retry = o->input_metric && !s->fixed_boundary && !s->restricted_boundary && cfi_flow_backtracks(flow);
    /* the tangential relaxation, not with prescribed / cmc boundaries,
     * whose boundary vectors are the step's purpose; by default on closed
     * genus-0 surfaces only: on genus > 0 the resampled state lets the flow
     * go on to a lower W of the same class, which crowds a coarse mesh (the
     * double torus' mean Q 1.53 -> 1.97 with the class held or not; elk
     * 1.555 -> 1.482, both issue-13 targets met; session 41), with a (held)
     * boundary it slowed bunny_scan_35k (W/4pi 5.10 -> 8.83 after 10 steps;
     * docs/spin.md, "Tangential relaxation") */
    s->relax_iterations = s->restricted_boundary ? 0
                          : o->relaxation >= 0  ? o->relaxation
                          : !s->has_boundary && cf_mesh_genus(mesh) == 0 ? CFI_SPIN_RELAXATION_AUTO_SWEEPS
                                                                        : 0;
    st = allocate_arrays(s, dim);
    if (st == CF_OK && s->excess_bound > 0.0 &&
        !(s->excess_work = CFI_WS_ALLOC(&s->ws, double, cf_conformal_excess_work_size(mesh))))
        st = CF_ERR_NOMEM;
    if (st == CF_OK && dim) st = cfi_spin_exactness_init(flow, s);
    if (st == CF_OK) st = create_current_poisson(flow, s);
    /* Position recovery in the metric of the starting surface: the Dirichlet
     * energy is conformally invariant, so for a conformal flow the Poisson
     * problem of Eq. (6) is the same in the input's metric (as cMCF keeps the
     * input's Laplacian, Kazhdan et al. 2012), and its factorisation is done
     * once. Measured (docs/spin.md): armadillo mean Q 1.81 -> 1.24, max Q 12.0
     * -> 2.9; bunny max Q 7.1 -> 3.7; spot W/4pi 1.0488 -> 1.0472. A fixed
     * boundary rewrites the matrix every step and keeps the current metric. */
    if (st == CF_OK && o->input_metric && !s->fixed_boundary)
        st = cf_edge_poisson_create_floored(ctx, mesh, flow->positions, 0, NULL, o->weight_floor,
                                            &s->poisson_input); /* filled with these positions */
    /* its metric stays the input's until a relaxed state is kept, if ever:
     * the refill data would only hold memory (37 MB at 655k vertices), and
     * the first relaxed state's cf_edge_poisson_set_metric makes it again;
     * recovery_scale_weight refills it at every attempt */
    if (st == CF_OK && s->poisson_input && !(o->recovery_scale_weight > 0.0))
        cf_edge_poisson_freeze_metric(s->poisson_input);
    /* its metric's positions and a face array, for recovery_scale_weight's
     * per-attempt weights (scale_recovery) */
    if (st == CF_OK && s->poisson_input && o->recovery_scale_weight > 0.0) {
        s->recovery_metric = CFI_WS_ALLOC(&s->ws, double, 3 * (int64_t)mesh->nv);
        s->face_scale = CFI_WS_ALLOC(&s->ws, double, mesh->nf);
        if (!s->recovery_metric || !s->face_scale) st = CF_ERR_NOMEM;
        else memcpy(s->recovery_metric, flow->positions, 3 * (size_t)mesh->nv * sizeof(double));
    }
    if (st == CF_OK) st = cfi_spin_update_geometry(flow, s, flow->positions);
    /* desired vertex areas of Moebius balancing: the mesh's rest shape */
    if (st == CF_OK && s->rest_area) st = cf_vertex_areas(ctx, mesh, mesh->positions, CF_DUAL_AREA_BARYCENTRIC, s->rest_area);
    if (st != CF_OK) goto fail;
    s->eps = o->regularization * 4.0 * CFI_PI / flow->initial_area;
    st = cfi_spin_boundary_targets(flow, s, o);
    if (st == CF_OK) st = create_dirac(flow, s);
    /* the filter is built on the input: the weak cotan Laplacian is invariant
     * under conformal maps, and the flow is conformal */
    if (st == CF_OK && o->sigma > 0.0) {
        st = cf_spectral_filter_create(ctx, mesh, flow->positions, o->sigma, o->filter_k, &s->filter);
        if (st == CF_ERR_NUMERICAL) cfi_error_prefix(ctx, "spin-willmore: parameter 'sigma'");
    }
    /* the vertex-scale fairing, with the input's Laplacian (conformally
     * invariant, as the position recovery's) and the boundary held;
     * prescribed / cmc boundaries set their boundary vectors themselves */
    if (st == CF_OK && s->faired)
        st = cf_vertex_fairing_create_floored(ctx, mesh, flow->positions, 1, o->weight_floor, &s->fairing);
    /* against the input's triangles (the mesh's rest positions, also when
     * the run starts elsewhere): the distortion the flow is judged by. It
     * makes its arrays when a step's map first passes its threshold, as the
     * recovery's refill data come back with the first kept relaxed state
     * and the current-metric solver at a first stall: most flows never get
     * there (icosphere of 655k vertices: peak 4.50 GB against 4.36 with
     * both made here) */
    if (st == CF_OK && s->relax_iterations > 0)
        st = cf_tangential_relaxation_create(ctx, mesh, NULL, 1, &s->relaxation);
    if (st == CF_OK && o->keep_class) st = cfi_spin_class_create(flow, o->keep_class == 2, &s->keep_class);
    if (st != CF_OK) goto fail;

    flow->info.energy = s->energy;
    flow->info.energy_terms[0] = s->energy / (4.0 * CFI_PI);
    flow->info.term_names[0] = "W/4pi";
    report_thin_faces(flow, o->weight_floor);
    return CF_OK;
fail:
    cfi_spin_destroy(flow);
    return st;
}

/* ---- step -------------------------------------------------------------- */

/* V: lambda from X(s->rho) (fill, factorisation, inverse iteration or the
 * fixed-boundary solve), and its Rayleigh quotient. */
static cf_status solve_lambda(cf_flow *flow, cfi_spin_state *s, cfi_spin_timers *t)
{
    const cf_mesh *mesh = flow->mesh;
    cf_context *ctx = flow->ctx;
    int32_t nv = s->nv;
    double *x = flow->positions;
    cf_status st = CF_OK;
    double ta = cfi_now_seconds();
    /* The shift eps M is the regularisation alpha |lambda - 1|^2_M (option
     * `regularization`); it also makes the eigenproblem definite (X(0) 1 = 0).
     * With a fixed boundary the problem is the linear least-squares solve
     * (X_II + eps M) lambda_I = -X_IB 1 + eps M 1: without the eps M 1 on the
     * right the shift would bias lambda toward 0 (at tau -> 0 it shrank the
     * mushroom cap by 0.8 % and blade_slivers_8k by 47 % per step). */
    st = cfi_dirac_fill(s->dirac, mesh, x, s->rho, s->eps);
    if (st != CF_OK) return st;
    if (s->restricted_boundary) {
        st = cfi_spin_boundary_binormals(flow, s, x, s->binormal);
        if (st != CF_OK) return st;
        cfi_spin_boundary_frames(flow, s);
        cfi_dirac_restrict_boundary(s->dirac, mesh, s->frames);
    }
    double tb = cfi_now_seconds();
    t->assemble += tb - ta;
    st = s->fixed_boundary ? cfi_dirac_fixed_factorize(s->dirac) : cfi_dirac_factorize(s->dirac, s->chol);
    double tc = cfi_now_seconds();
    t->factorize += tc - tb;
    if (st != CF_OK) return st;
    if (s->fixed_boundary) {
        st = cfi_dirac_fixed_solve(s->dirac, mesh, s->area, s->eps, s->qrhs, s->lambda);
    } else {
        for (int32_t i = 0; i < nv; ++i) {
            s->lambda[4 * i] = 1.0;
            s->lambda[4 * i + 1] = s->lambda[4 * i + 2] = s->lambda[4 * i + 3] = 0.0;
            if (s->restricted_boundary && mesh->vertex_on_boundary[i]) {
                /* start from Q_i^T 1 restricted to the admissible components */
                const double *q = s->frames + 16 * (int64_t)i;
                s->lambda[4 * i] = q[0];
                s->lambda[4 * i + 1] = q[1];
                s->lambda[4 * i + 2] = s->lambda[4 * i + 3] = 0.0;
            }
        }
        st = cf_inverse_iteration_blocks(s->chol, s->area, 4, s->opt.power_iterations, cfi_spin_lambda_norm2(s),
                                         s->lambda, s->qwork);
    }
    t->solve += cfi_now_seconds() - tc;
    if (st != CF_OK) return cfi_error(ctx, st, "spin-willmore: eigenvector solve failed");
    double quotient = s->fixed_boundary ? cfi_dirac_fixed_quotient(s->dirac, mesh, s->area, s->lambda, s->qwork)
                                        : cfi_dirac_quotient(s->dirac, s->area, s->lambda, s->qwork);
    s->diag.eigenvalue = isnan(quotient) ? 0.0 : quotient - s->eps;
    if (s->restricted_boundary) {
        /* back to lambda = Q mu on the boundary */
        for (int32_t i = 0; i < nv; ++i) {
            if (!mesh->vertex_on_boundary[i]) continue;
            const double *q = s->frames + 16 * (int64_t)i;
            double mu[4];
            memcpy(mu, s->lambda + 4 * i, sizeof mu);
            for (int r = 0; r < 4; ++r)
                s->lambda[4 * i + r] = q[4 * r] * mu[0] + q[4 * r + 1] * mu[1] + q[4 * r + 2] * mu[2] + q[4 * r + 3] * mu[3];
        }
    }
    return CF_OK;
}

/* The Newton corrections of the periods (periods.c) after the first
 * lambda, whose periods err the caller has just measured (cfi_spin_periods,
 * which also left them in s->period_values): at most period_iterations,
 * while the harmonic part of e~ is above period_tolerance; a correction that
 * does not lower it is undone (rho, lambda and its eigenvalue back; X and
 * its factor are not used again in this attempt, the next one refills
 * them). With period_first_order a correction whose first-order lambda
 * meets the tolerance ends them without a factorisation of X at its rho
 * (docs/spin.md, "Periods"). */
static cf_status correct_periods(cf_flow *flow, cfi_spin_state *s, cfi_spin_timers *t, double err)
{
    int32_t nv = s->nv;
    s->diag.period_error_first = s->diag.period_error = err;
    s->diag.period_iterations = s->diag.period_first_order = 0;
    s->diag.period_first_order_error = 0.0;
    for (int32_t k = 0; k < s->opt.period_iterations && err > s->opt.period_tolerance; ++k) {
        memcpy(s->period_rho, s->rho, (size_t)nv * sizeof(double));
        /* lambda before the corrected rho, for an undo */
        memcpy(s->period_lambda, s->lambda, 4 * (size_t)nv * sizeof(double));
        double eigenvalue = s->diag.eigenvalue;
        cf_status st = cfi_spin_period_correction(flow, s, t);
        if (st != CF_OK) return st;
        /* the first-order lambda first: the factor of X at the corrected rho
         * only if it leaves the periods above the tolerance (it then also
         * serves the next correction's Jacobian) */
        double next = NAN;
        int32_t first_order = 0;
        if (s->opt.period_first_order) {
            double ta = cfi_now_seconds();
            if (cfi_spin_period_linear_lambda(s, s->lambda)) {
                next = cfi_spin_periods(flow->mesh, s, flow->positions, s->lambda, s->edges, s->period_values);
                first_order = next <= s->opt.period_tolerance;
            }
            t->solve += cfi_now_seconds() - ta;
            if (k == 0) s->diag.period_first_order_error = next;
        }
        if (!first_order) {
            st = solve_lambda(flow, s, t);
            if (st != CF_OK) return st;
            next = cfi_spin_periods(flow->mesh, s, flow->positions, s->lambda, s->edges, s->period_values);
        }
        if (!(next < err)) {
            memcpy(s->rho, s->period_rho, (size_t)nv * sizeof(double));
            memcpy(s->lambda, s->period_lambda, 4 * (size_t)nv * sizeof(double));
            s->diag.eigenvalue = eigenvalue;
            return CF_OK;
        }
        err = next;
        s->diag.period_error = err;
        s->diag.period_iterations = k + 1;
        s->diag.period_first_order += first_order;
    }
    return CF_OK;
}

/* W after the step if its rho were realised exactly: the spin
 * transformation changes the mean curvature half-density by rho (Eq. (1),
 * H~ |df~| = (H + rho) |df|), so H~^2 dA~ = (H + rho)^2 dA at every vertex
 * whatever the conformal factor; the tangential part of L f, which no
 * curvature change addresses, stays. With rho = tau rhodot, rhodot = -2 P H,
 * this is W - 4 tau (1 - tau) |P H|^2_M: the curvature-space model of the
 * step, against which realised_decrease measures the step (docs/spin.md,
 * "Realised decrease"). Interior vertices only, as W. */
static double predicted_energy(const cf_mesh *mesh, const cfi_spin_state *s)
{
    double w = s->energy_before;
    for (int32_t i = 0; i < s->nv; ++i) {
        if (mesh->vertex_on_boundary[i]) continue;
        double hn = s->h[i] + s->rho[i];
        w += (hn * hn - s->h[i] * s->h[i]) * s->area[i];
    }
    return w;
}

/* The fraction of the model's decrease W - predicted_energy that the step
 * realised; NaN when the model predicts no decrease (tau >= 1). With the
 * vertex-scale fairing it is the whole step's decrease (it may exceed 1):
 * the measured alternative, the spin part's alone, held tau on meshes whose
 * fairing does much of the work (triceratops_needles_3k: W/4pi 22.8 instead
 * of 8.8 after 10 steps; docs/spin.md, "Vertex-scale fairing"). */
static double realised_decrease(const cfi_spin_state *s)
{
    double predicted = s->energy_before - s->diag.predicted_energy;
    return predicted > 1e-12 * s->energy_before ? (s->energy_before - s->energy) / predicted : NAN;
}

/* I-III at the step's start: rhodot = -2 H (Sec. 6.1), the spectral
 * filter (Sec. 4), the constraints (Sec. 6.2). */
static cf_status step_direction(cf_flow *flow, cfi_spin_state *s, double *factor_seconds, double *solve_seconds)
{
    for (int32_t i = 0; i < s->nv; ++i) s->rhodot[i] = -2.0 * s->h[i];
    cf_solver_timings tm = {0.0, 0.0, 0.0};
    cf_status st = s->filter ? cf_spectral_filter_apply(s->filter, s->rhodot, &tm) : CF_OK;
    *solve_seconds += tm.solve_seconds;
    if (st == CF_OK) st = cfi_spin_apply_constraints(flow, s, flow->positions, factor_seconds, solve_seconds);
    return st;
}

/* The direction again with a new factor of X(0), after an attempt whose
 * exactness directions came from an older one and failed: its periods
 * above period_tolerance, or the attempt rejected (exactness.c, "Reusing
 * X(0)"). Positions and geometry are the step's start. */
static cf_status renew_direction(cf_flow *flow, cfi_spin_state *s, cfi_spin_timers *t)
{
    s->x0_factored = 0;
    s->x0_renew_pending = 0;
    ++s->diag.x0_renewed;
    return step_direction(flow, s, &t->factorize, &t->solve);
}

/* IV and the first lambda of V for tau from the current rhodot: rho = tau
 * rhodot, lambda from X(rho), and on closed genus > 0 with the period
 * corrections (*measured) the harmonic part err of its transformed edges
 * (cfi_spin_periods, which also leaves them in s->period_values). */
static cf_status first_lambda(cf_flow *flow, cfi_spin_state *s, double tau, cfi_spin_timers *t, int32_t *measured,
                              double *err)
{
    for (int32_t i = 0; i < s->nv; ++i) s->rho[i] = tau * s->rhodot[i];
    cf_status st = solve_lambda(flow, s, t);
    *measured = st == CF_OK && s->period_newton && s->zcount > 0;
    if (*measured) *err = cfi_spin_periods(flow->mesh, s, flow->positions, s->lambda, s->edges, s->period_values);
    return st;
}

/* Where the recovered positions go: the Poisson problem fixes them up to a
 * translation (and a scale when the recovery is not scale-bound), so the
 * flow keeps the area-weighted centroid of the step's start and, with
 * `normalize`, the initial total area (W is invariant under both). A fixed
 * boundary pins them already. */
typedef struct placement {
    double centroid[3]; /* of the step's start, area-weighted (s->area) */
} placement;

/* sum_i w_i x_i into sum (3) and sum_i w_i returned */
static double weighted_sum(int32_t nv, const double *w, const double *x, double sum[3])
{
    double total = 0.0;
    sum[0] = sum[1] = sum[2] = 0.0;
    for (int32_t i = 0; i < nv; ++i) {
        total += w[i];
        for (int c = 0; c < 3; ++c) sum[c] += w[i] * x[3 * i + c];
    }
    return total;
}

static void start_placement(const cf_flow *flow, const cfi_spin_state *s, const double *x, placement *pl)
{
    memset(pl, 0, sizeof *pl);
    if (s->fixed_boundary) return;
    double total = weighted_sum(flow->mesh->nv, s->area, x, pl->centroid);
    for (int c = 0; c < 3; ++c) pl->centroid[c] /= total;
}

/* dst = src moved to the start's centroid (each in its own vertex areas)
 * and scaled to the initial area with `normalize`; dst may equal src. */
static cf_status place(cf_flow *flow, const cfi_spin_state *s, const placement *pl, const double *src, double *dst)
{
    int32_t nv = flow->mesh->nv;
    if (s->fixed_boundary) {
        if (dst != src) memcpy(dst, src, 3 * (size_t)nv * sizeof(double));
        return CF_OK;
    }
    /* the centroid of src in its own vertex areas, so that dst's (the same
     * weights, scaled) is the start's exactly: in the start's weights it
     * moved at second order on shapes without symmetry (3e-6 of a star's size
     * over 10 steps once the relaxation had resampled it; test `components`) */
    cf_status st = cf_vertex_areas(flow->ctx, flow->mesh, src, CF_DUAL_AREA_BARYCENTRIC, s->placed_area);
    if (st != CF_OK) return st;
    double c_new[3], own_total = weighted_sum(nv, s->placed_area, src, c_new);
    if (!(own_total > 0.0)) return cfi_error(flow->ctx, CF_ERR_NUMERICAL, "spin-willmore: recovered surface has no area");
    for (int c = 0; c < 3; ++c) c_new[c] /= own_total;
    double scale = 1.0;
    if (s->opt.normalize) {
        /* the barycentric vertex areas sum to the total area */
        scale = sqrt(flow->initial_area / own_total);
    }
    for (int32_t i = 0; i < nv; ++i)
        for (int c = 0; c < 3; ++c) dst[3 * i + c] = pl->centroid[c] + scale * (src[3 * i + c] - c_new[c]);
    return CF_OK;
}

/* W of candidate positions p into *w (NAN when they are not finite or have
 * a degenerate face: such a candidate is not taken); *touched: s's geometry
 * was refilled (for p, or partly when that failed). */
static cf_status candidate_energy(cf_flow *flow, cfi_spin_state *s, const double *p, double *w, int *touched)
{
    *w = NAN;
    *touched = 0;
    for (int32_t i = 0; i < 3 * flow->mesh->nv; ++i)
        if (!isfinite(p[i])) return CF_OK;
    *touched = 1;
    cf_status st = cfi_spin_update_geometry(flow, s, p);
    if (st == CF_OK) *w = s->energy;
    else if (st == CF_ERR_DEGENERATE_FACE || st == CF_ERR_NUMERICAL) cf_context_clear_error(flow->ctx);
    else return st;
    return CF_OK;
}

/* The recovered positions x or the faired candidate (s->faired), whichever
 * has the lower W, into x, with s's geometry that of the positions kept.
 * The one that won the previous attempt is evaluated last, so that the
 * geometry need not be made a third time when it wins again. A failure of
 * x's own geometry fails the attempt, as without the fairing. */
static cf_status keep_lower(cf_flow *flow, cfi_spin_state *s, double *x)
{
    int32_t nv = flow->mesh->nv;
    double w_faired = NAN;
    int touched = 0, geometry_is_faired = 0;
    cf_status st = CF_OK;
    if (s->faired_won) {
        st = cfi_spin_update_geometry(flow, s, x);
        s->diag.plain_energy = s->energy;
        if (st == CF_OK) st = candidate_energy(flow, s, s->faired, &w_faired, &touched);
        geometry_is_faired = touched;
    } else {
        st = candidate_energy(flow, s, s->faired, &w_faired, &touched);
        if (st == CF_OK) st = cfi_spin_update_geometry(flow, s, x);
        s->diag.plain_energy = s->energy;
    }
    if (st != CF_OK) return st;
    s->diag.fairing_energy = w_faired;
    s->diag.fairing_kept = s->faired_won = w_faired < s->diag.plain_energy;
    if (s->diag.fairing_kept) {
        memcpy(x, s->faired, 3 * (size_t)nv * sizeof(double));
        return geometry_is_faired ? CF_OK : cfi_spin_update_geometry(flow, s, x);
    }
    return geometry_is_faired ? cfi_spin_update_geometry(flow, s, x) : CF_OK;
}

/* The bound on the step's non-conformal excess (max_conformal_excess) for
 * the positions x kept, whose geometry s holds: *too_large set when the
 * map from the step's start makes more distortion than its vertex scales
 * explain by more than the bound. */
static cf_status check_excess(cf_flow *flow, cfi_spin_state *s, const double *x, cfi_spin_too_large *too_large)
{
    /* An attempt that raises W is rejected by the layer's rise check anyway
     * (exact under `adaptive`, which the bound needs): no excess to measure,
     * so a stall's attempts do not pay for it. */
    s->diag.conformal_excess = 0.0;
    if (!(s->excess_bound > 0.0 && s->energy <= flow->info.energy)) return CF_OK;
    /* the map from the step's start (the layer's saved positions) to the
     * positions kept, faired or not: the distortion no vertex scale
     * explains (create says why the bound) */
    double mean_q = 0.0, mean_model_q = 0.0;
    cf_status st = cf_conformal_excess(flow->ctx, flow->mesh, flow->saved_positions, x, s->excess_work, &mean_q,
                                       &mean_model_q);
    if (st == CF_ERR_DEGENERATE_FACE || st == CF_ERR_NUMERICAL || st == CF_ERR_NOT_CONVERGED) {
        /* no model of the map: no excess to judge; the layer's face check decides */
        cf_context_clear_error(flow->ctx);
        return CF_OK;
    }
    if (st != CF_OK) return st;
    s->diag.conformal_excess = mean_q - mean_model_q;
    if (!(s->diag.conformal_excess <= s->excess_bound)) *too_large = CFI_SPIN_NOT_CONFORMAL;
    return CF_OK;
}

/* Option keep_class: the positions x kept by the attempt moved back onto
 * the input's conformal class (keep_class 2: its Gram matrix; keep_class.c),
 * placed again, and s's geometry (W) made for them: the step policy judges
 * the projected state. A face of x that degenerates, a factor that fails or
 * a projection that does not reach the class fails the attempt, which the
 * layer retries at a smaller step. Projecting the plain and the
 * faired candidate each before choosing (twice the cost) stalled the flow
 * sooner (elephant_g3_3k: 5 steps, class distance 0.05). */
static cf_status project_and_place(cf_flow *flow, cfi_spin_state *s, const placement *pl, double *x, double *residual)
{
    cf_status st = cfi_spin_class_project(flow, s->keep_class, x, residual);
    return st == CF_OK ? place(flow, s, pl, x, x) : st;
}

static cf_status project_to_class(cf_flow *flow, cfi_spin_state *s, const placement *pl, double *x)
{
    cf_status st = project_and_place(flow, s, pl, x, &s->diag.class_residual);
    return st == CF_OK ? cfi_spin_update_geometry(flow, s, x) : st;
}

/* The fallback's last variant (cfi_spin_fallback): the step's start
 * relaxed by the vertex-scale fairing alone, kappa = fairing tau, placed
 * like a step's positions. */
static cf_status realise_fairing_only(cf_flow *flow, cfi_spin_state *s, double tau, cfi_spin_too_large *too_large,
                                     cfi_spin_timers *t)
{
    double *x = flow->positions;
    double kappa = s->opt.fairing * tau;
    cf_solver_timings ft = {0.0, 0.0, 0.0};
    cf_status st = cf_vertex_fairing_apply(s->fairing, kappa, x, s->faired, &ft);
    t->solve += ft.solve_seconds;
    if (st == CF_ERR_NOT_CONVERGED) return CF_ERR_NUMERICAL; /* no candidate: the layer halves tau */
    if (st != CF_OK) return st;
    double ta = cfi_now_seconds();
    placement pl;
    start_placement(flow, s, x, &pl);
    st = place(flow, s, &pl, s->faired, x);
    if (st != CF_OK) return st;
    s->diag.scale_change = 0.0;
    s->diag.integrability_error = 0.0;
    s->diag.fairing_kappa = kappa;
    s->diag.fairing_kept = 1;
    s->diag.predicted_energy = NAN; /* no curvature-space model: no realised decrease, tau may grow */
    st = s->keep_class ? project_to_class(flow, s, &pl, x) : cfi_spin_update_geometry(flow, s, x);
    s->diag.fairing_energy = s->diag.plain_energy = s->energy;
    if (st == CF_OK) st = check_excess(flow, s, x, too_large);
    t->assemble += cfi_now_seconds() - ta;
    return st;
}

/* Option recovery_scale_weight p: the input-metric recovery's face weights
 * for this attempt's transformed edges, (A_f / A~_f)^p with A_f the face's
 * area in the recovery's metric and A~_f the area two of its transformed
 * edges span, each relative to its total (the fit does not depend on a
 * common factor; the relative shift of the solve does). Measured on a
 * trefoil tube of radius 0.25 (3 360 vertices): where an attempt's W rose
 * from 13.8 to 131 against a model of 13.3, the recovered edges missed
 * their transformed edges by 1-3 times their own length at the vertices
 * that made the rise (crowded 3e4-fold in area by the step), against a
 * median of 5 % (docs/spin.md, "Crowded regions in the position
 * recovery"). The factor is capped at 1e12: a transformed face of no area
 * would have no finite weight. */
#define CFI_SPIN_MAX_FACE_SCALE 1e12

static cf_status scale_recovery(cf_flow *flow, cfi_spin_state *s)
{
    const cf_mesh *mesh = flow->mesh;
    const double *m = s->recovery_metric;
    double total = 0.0, total_new = 0.0, longest2;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        const int32_t *tri = mesh->triangles + 3 * f;
        /* the triangle its transformed edges tri[0] -> tri[1] -> tri[2] span
         * (each edge stored once, from its lower vertex) */
        double corner[3][3] = {{0.0, 0.0, 0.0}};
        for (int k = 0; k < 2; ++k) {
            int64_t e = mesh->halfedge_edge[3 * f + k];
            double sign = mesh->edge_vertices[2 * e] == tri[k] ? 1.0 : -1.0;
            for (int c = 0; c < 3; ++c) corner[k + 1][c] = corner[k][c] + sign * s->edges[3 * e + c];
        }
        double area_new = cfi_triangle_area(corner[0], corner[1], corner[2], &longest2);
        double area = cfi_triangle_area(m + 3 * tri[0], m + 3 * tri[1], m + 3 * tri[2], &longest2);
        s->face_scale[f] = area_new > 0.0 ? area / area_new : INFINITY;
        total += area;
        total_new += area_new;
    }
    double p = s->opt.recovery_scale_weight;
    for (int32_t f = 0; f < mesh->nf; ++f)
        s->face_scale[f] = fmin(CFI_SPIN_MAX_FACE_SCALE, pow(s->face_scale[f] * (total_new / total), p));
    return cf_edge_poisson_set_metric_scaled(s->poisson_input, m, s->face_scale);
}

cf_status cfi_spin_realise_step(cf_flow *flow, cfi_spin_state *s, double tau, cfi_spin_too_large *too_large,
                                cfi_spin_timers *t)
{
    if (s->fairing_only_step) return realise_fairing_only(flow, s, tau, too_large, t);
    const cf_mesh *mesh = flow->mesh;
    cf_context *ctx = flow->ctx;
    int32_t nv = s->nv;
    double *x = flow->positions;
    cf_status st = CF_OK;
    if (s->x0_renew_pending) {
        st = renew_direction(flow, s, t);
        if (st != CF_OK) return st;
    }
    /* IV-V: rho = tau rhodot, lambda from X(rho), with the periods
     * corrected on closed genus > 0 */
    double err = 0.0;
    int32_t measured = 0;
    st = first_lambda(flow, s, tau, t, &measured, &err);
    if (st == CF_OK && measured && s->diag.x0_reused && !(err <= s->opt.period_tolerance)) {
        /* the older exactness directions missed by more than the
         * corrections are for: this attempt again with a new X(0) */
        st = renew_direction(flow, s, t);
        if (st == CF_OK) st = first_lambda(flow, s, tau, t, &measured, &err);
    }
    if (st == CF_OK && measured) st = correct_periods(flow, s, t, err);
    if (st != CF_OK) return st;
    /* periods the corrections could not cancel (their Newton step diverged:
     * the step is too large for their linearisation) would take the step
     * out of the conformal class by that much (docs/spin.md, "Periods the
     * corrections cannot cancel") */
    if (measured && cfi_flow_backtracks(flow) && s->opt.max_period_error > 0.0 &&
        !(s->diag.period_error <= s->opt.max_period_error)) {
        *too_large = CFI_SPIN_PERIODS_LEFT;
        return CF_OK;
    }
    s->diag.predicted_energy = predicted_energy(mesh, s);

    /* A lambda whose scale jumps along an edge gives transformed edges that
     * no similar triangle fits (docs/spin.md, "Robustness"): with adaptive
     * steps such a step is redone with a smaller tau before positions are
     * recovered. */
    s->diag.scale_change = cfi_spin_max_scale_change(mesh, s->lambda);
    /* (prescribed and cmc boundaries turn lambda by design: not bounded) */
    *too_large = cfi_flow_backtracks(flow) && !s->restricted_boundary && s->opt.max_scale_change > 0.0 &&
                         !(s->diag.scale_change <= s->opt.max_scale_change)
                     ? CFI_SPIN_SCALE_CHANGE
                     : CFI_SPIN_STEP_OK;
    if (*too_large) return CF_OK;

    /* VI. edges and positions */
    double ta = cfi_now_seconds();
    cfi_spin_transform_edges(mesh, x, s->lambda, s->edges);
    t->assemble += cfi_now_seconds() - ta;
    cf_solver_timings tm = {0.0, 0.0, 0.0};
    /* for the displacement from x: the recovery's rounding error then scales
     * with the step, not with the coordinates (docs/spin.md, "Stalls") */
    cf_edge_poisson *recovery = s->poisson_input && !s->current_metric_step ? s->poisson_input : s->poisson;
    if (recovery == s->poisson_input && s->face_scale) {
        st = scale_recovery(flow, s);
        if (st != CF_OK) return st;
    }
    st = cf_edge_poisson_solve_from(recovery, x, s->edges,
                                    s->fixed_boundary ? x : NULL, s->newpos, &tm);
    t->factorize += tm.factorize_seconds;
    t->solve += tm.solve_seconds;
    if (st != CF_OK) return st;
    s->diag.integrability_error = cf_edge_closure_error(mesh, s->newpos, s->edges);
    /* the optional bound on the non-integrability (docs/spin.md, "Periods") */
    if (cfi_flow_backtracks(flow) && !s->restricted_boundary && s->opt.max_integrability_error > 0.0 &&
        !(s->diag.integrability_error <= s->opt.max_integrability_error)) {
        *too_large = CFI_SPIN_NOT_INTEGRABLE;
        return CF_OK;
    }
    /* the vertex-scale fairing's candidate (docs/spin.md, "Vertex-scale
     * fairing"): kappa in proportion to tau, so that a step still tends to
     * the identity as tau -> 0 */
    double kappa = s->fairing ? s->opt.fairing * tau : 0.0;
    if (kappa > 0.0) {
        cf_solver_timings ft = {0.0, 0.0, 0.0};
        st = cf_vertex_fairing_apply(s->fairing, kappa, s->newpos, s->faired, &ft);
        t->solve += ft.solve_seconds;
        if (st == CF_ERR_NOT_CONVERGED) {
            /* no candidate this attempt (never seen on a test mesh) */
            cf_context_clear_error(ctx);
            kappa = 0.0;
            st = CF_OK;
        }
        if (st != CF_OK) return st;
    }
    /* fix translation (and the scale, if asked): Willmore energy is invariant under both */
    placement pl;
    start_placement(flow, s, x, &pl);
    if (kappa > 0.0 && place(flow, s, &pl, s->faired, s->faired) != CF_OK) {
        cf_context_clear_error(ctx); /* a candidate of no area is no candidate */
        kappa = 0.0;
    }
    s->diag.fairing_kappa = kappa;
    st = place(flow, s, &pl, s->newpos, x);
    if (st != CF_OK) return st;
    for (int32_t i = 0; i < 3 * nv; ++i)
        if (!isfinite(x[i])) return cfi_error(ctx, CF_ERR_NUMERICAL, "vertex %d: position is not finite", i / 3);

    ta = cfi_now_seconds();
    /* with keep_class the geometry is made once, for the projected positions
     * (project_to_class), unless the fairing's choice needs both candidates' */
    if (kappa > 0.0) st = keep_lower(flow, s, x);
    else if (!s->keep_class) st = cfi_spin_update_geometry(flow, s, x);
    if (st == CF_OK && s->keep_class) st = project_to_class(flow, s, &pl, x);
    if (st == CF_OK) st = check_excess(flow, s, x, too_large);
    t->assemble += cfi_now_seconds() - ta;
    return st;
}

/* I-III, shared by every attempt of the step (step_direction). */
cf_status cfi_spin_begin_step(cf_flow *flow, cf_flow_info *info)
{
    cfi_spin_state *s = flow->impl;
    s->energy_before = s->energy;
    s->current_metric_step = 0; /* the input metric again (cfi_spin_fallback) */
    /* After a step the fairing alone took, the spin step stalled again in
     * both metrics at every step where that was measured (man_slivers_17k,
     * steps 5-9, each after two rounds of attempts): such a step is the
     * fairing alone, and the run stops when it stalls (docs/spin.md, "A
     * stall's last variant"). Its tau is the layer's, carried from the last
     * fairing step (doubled when that needed no halving, as after any
     * step): the variant's first step (in the fallback) starts from the
     * full step, since the
     * stalled spin step's tau says nothing of the fairing's kappa, but the
     * next ones need not. Restarted from the full step, man_slivers_17k's
     * steps 6-9 halved 4, 7, 9 and 10 times down to the taus the carried
     * step reaches in 4, 3, 2 and 3 (0.90x the whole run). */
    s->fairing_only_step = s->last_fairing_only;
    s->step_start_tau = flow->policy.step; /* where the fallback restarts from */
    s->x0_renew_pending = 0;
    memset(&s->diag, 0, sizeof s->diag);
    return step_direction(flow, s, &info->factorize_seconds, &info->solve_seconds);
}

/* The regularization (in units of 4 pi / area) that an attempt outrunning
 * its model raises alpha to: the value docs/spin.md measured on long thin
 * shapes before this was automatic (`-p regularization=1`). */
#define CFI_SPIN_DAMPED_REGULARIZATION 1.0

/* Whether the attempt just realised lowered W by more than
 * max_realised_decrease times its curvature-space model's decrease
 * (predicted_energy), with alpha still below the damped value. Such a W is
 * not the work of the step's rho: on trefoil tubes the first step at tau
 * 0.5 realises 3.5-3.8 times its model (rings of the tube crowd to 1e-3 of
 * their area), while no attempt on the 20 shared meshes, the generated
 * plates, disks and Loop-subdivided meshes exceeds 1.72. The model's
 * decrease must be at least 1 % of W, and above rounding of a W near 0
 * (W is scale-free: 1e-9 of a round sphere's): a ratio of two small
 * differences says nothing (docs/spin.md, "Long tubes: damping when a step
 * outruns its model"). */
static int outran_model(const cfi_spin_state *s, double damped_eps)
{
    if (!(s->opt.max_realised_decrease > 0.0) || s->fairing_only_step || !(s->eps < damped_eps)) return 0;
    double predicted = s->energy_before - s->diag.predicted_energy;
    if (!(predicted >= 0.01 * s->energy_before) || !(predicted > 1e-9 * 4.0 * CFI_PI)) return 0;
    return realised_decrease(s) > s->opt.max_realised_decrease;
}

/* IV-VI for tau. While the flow layer backtracks (`adaptive`), an attempt
 * whose lambda changes the log scale across an edge by more than
 * max_scale_change is rejected with tau cut in proportion (the scale change
 * grows about linearly with tau; at least halved), one whose edges are less
 * integrable than max_integrability_error allows with tau halved, and one that fails
 * numerically is rejected too (redone with half the step: the failures of
 * a too large step, docs/spin.md). */
cf_status cfi_spin_attempt(cf_flow *flow, double tau, cf_flow_info *info, cfi_step_verdict *verdict)
{
    cfi_spin_state *s = flow->impl;
    cfi_spin_timers t = {0.0, 0.0, 0.0};
    cfi_spin_too_large too_large = CFI_SPIN_STEP_OK;
    info->time_step = tau;
    cf_status st = cfi_spin_realise_step(flow, s, tau, &too_large, &t);
    double damped_eps = CFI_SPIN_DAMPED_REGULARIZATION * 4.0 * CFI_PI / flow->initial_area;
    if (st == CF_OK && !too_large && cfi_flow_backtracks(flow) && outran_model(s, damped_eps)) {
        /* the near-kernel modes of X made this step: the same tau again
         * from the step's start with them damped (alpha raised for the rest
         * of the run: the tube stays a tube), and the direction renewed,
         * since X(0) + eps M behind the exactness directions changed */
        double outran = realised_decrease(s);
        s->eps = damped_eps;
        s->x0_renew_pending = 1;
        memcpy(flow->positions, flow->saved_positions, 3 * (size_t)s->nv * sizeof(double));
        st = cfi_spin_update_geometry(flow, s, flow->positions);
        if (st == CF_OK) st = cfi_spin_realise_step(flow, s, tau, &too_large, &t);
        s->diag.damped_realised = outran;
    }
    info->assemble_seconds += t.assemble;
    info->factorize_seconds += t.factorize;
    info->solve_seconds += t.solve;
    info->energy = s->energy;
    if (!cfi_flow_backtracks(flow)) return st;
    if (st == CF_OK && too_large) {
        verdict->rejected = 1;
        verdict->shrink = too_large == CFI_SPIN_SCALE_CHANGE ? 0.9 * s->opt.max_scale_change / s->diag.scale_change : 0.5;
    } else if (st == CF_OK) {
        /* a reduced tau grows back only after a step for which the
         * curvature-space model held (docs/spin.md, "Growing tau back") */
        double realised = realised_decrease(s);
        verdict->hold_step = s->opt.growth_ratio > 0.0 && realised < s->opt.growth_ratio;
    } else if (st == CF_ERR_NUMERICAL || st == CF_ERR_NOT_POSDEF || st == CF_ERR_DEGENERATE_FACE) {
        verdict->rejected = 1;
        verdict->shrink = 0.5;
        cf_context_clear_error(flow->ctx);
        st = CF_OK;
    }
    return st;
}

/* The layer's fallback at a stall (every attempt down to its limit raised W
 * or was rejected): where the input metric's least-squares recovery no
 * longer descends, the current metric's still does (docs/spin.md,
 * "Robustness"), so the rest of the step recovers positions in the metric
 * of the step's start, from four times the tau the step started at. The
 * current-metric solver is made here on first use: most flows never stall,
 * and at 655k vertices it would cost ~100 MB from creation on
 * (docs/memory.md). */
cf_status cfi_spin_fallback(cf_flow *flow, int32_t *switched, double *restart_step)
{
    cfi_spin_state *s = flow->impl;
    *switched = 0;
    /* the fairing alone stalled too: no variant is left, the run stops */
    if (s->fairing_only_step) return CF_OK;
    if (!s->stall_retry || s->current_metric_step) {
        /* the spin step stalled in every metric it has: the vertex-scale
         * fairing of the step's start alone, from the full step
         * (docs/spin.md, "A stall's last variant") */
        if (s->fairing && s->opt.stall_fairing) {
            s->fairing_only_step = 1;
            *switched = 1;
        }
        return CF_OK;
    }
    /* two doublings above the tau the step started at (the layer's,
     * carried from the last step), capped by the layer at the full step:
     * where the last step already needed this metric its tau is the better
     * guess than the full step (bull_6k, steps 6-9: 2-3 retries instead of
     * 8-9), and where it did not the full step's first attempts only blew
     * up (man_slivers_17k's step 4: W/4pi 7e7, 2e4, 714 at tau 0.09, 0.05,
     * 0.02 after two rejected for their scale change). Every other shared,
     * generated and knotted mesh keeps its result (docs/spin.md, "Stalls
     * of the input-metric recovery") */
    *restart_step = 4.0 * s->step_start_tau;
    if (!s->poisson) {
        /* the layer has reverted to the step's start: its metric, and from
         * now on H from the solver's Laplacian (the same values as s->lap) */
        cf_status st = cf_edge_poisson_create_floored(flow->ctx, flow->mesh, flow->positions, 0, NULL,
                                                      s->opt.weight_floor, &s->poisson);
        if (st != CF_OK) return st;
    }
    s->current_metric_step = 1;
    *switched = 1;
    return CF_OK;
}

/* After the layer restored the positions of the step's start: the geometry
 * (and W) of those positions again; rhodot and its constraints stay. */
cf_status cfi_spin_revert(cf_flow *flow)
{
    cfi_spin_state *s = flow->impl;
    /* a rejected attempt on older exactness directions: the next one renews them */
    if (s->diag.x0_reused) s->x0_renew_pending = 1;
    return cfi_spin_update_geometry(flow, s, flow->positions);
}

/* The tangential relaxation of an accepted step's positions (option
 * relaxation; docs/spin.md, "Tangential relaxation"), once the map's mean
 * distortion against the input is visible: kept if its W is not above the
 * step's (as the fairing's candidate); s's geometry is that of the
 * positions kept. */
static cf_status relax_positions(cf_flow *flow, cfi_spin_state *s)
{
    double *x = flow->positions;
    double w_step = s->energy;
    cf_tangential_relaxation_report rep = {0, 0, 0.0, 0.0};
    cf_status st = cf_tangential_relaxation_apply(s->relaxation, x, s->relax_iterations, CFI_SPIN_RELAXATION_MEAN_Q,
                                                  s->relaxed, &rep);
    if (st == CF_ERR_DEGENERATE_FACE) {
        /* a face without area: the layer's face check judges the step itself */
        cf_context_clear_error(flow->ctx);
        return CF_OK;
    }
    if (st != CF_OK) return st;
    s->diag.relaxation_iterations = rep.iterations;
    if (rep.iterations == 0) return CF_OK;
    /* the area (normalize) and the area-weighted centroid kept, the latter
     * in each state's own weights: the resampling moves both a little (a
     * star of eight limbs: its area by 5.8e-6, its centroid by 3e-4 of its
     * size in the first version; test `relaxation`) */
    placement pl;
    start_placement(flow, s, x, &pl);
    st = place(flow, s, &pl, s->relaxed, s->relaxed);
    if (st != CF_OK) return st;
    if (s->keep_class) {
        /* onto the class too, or the next step's attempts pay for the way back */
        double residual = 0.0;
        st = project_and_place(flow, s, &pl, s->relaxed, &residual);
        if (st == CF_ERR_NOMEM) return st;
        if (st != CF_OK) {
            cf_context_clear_error(flow->ctx);
            return CF_OK;
        }
    }
    double w = NAN;
    int touched = 0;
    st = candidate_energy(flow, s, s->relaxed, &w, &touched);
    if (st != CF_OK) return st;
    s->diag.relaxation_energy = w;
    if (w <= w_step) {
        memcpy(x, s->relaxed, 3 * (size_t)s->nv * sizeof(double));
        s->diag.relaxation_kept = 1;
        /* genus > 0: the reuse of X(0) is bounded by the steps' change of
         * scale, which says nothing of this move */
        s->x0_factored = 0;
        /* the relaxed map from the input is no longer conformal, so the
         * input's metric no longer recovers the next steps' positions
         * conformally: that of the relaxed state does (measured:
         * triceratops_needles_3k, whose tau fell to 0.003 after its first
         * relaxed step while the input's metric stayed; docs/spin.md) */
        if (s->recovery_metric) memcpy(s->recovery_metric, x, 3 * (size_t)s->nv * sizeof(double));
        return s->poisson_input ? cf_edge_poisson_set_metric(s->poisson_input, x) : CF_OK;
    }
    return touched ? cfi_spin_update_geometry(flow, s, x) : CF_OK;
}

/* The accepted attempt (or, at a stall, the state before the step): blow-up
 * and divergence checks, the report, convergence. */
cf_status cfi_spin_end_step(cf_flow *flow, cf_flow_info *info)
{
    cfi_spin_state *s = flow->impl;
    if (s->relax_iterations > 0 && info->time_step > 0.0 && s->energy < s->energy_before) {
        double t0 = cfi_now_seconds();
        cf_status st = relax_positions(flow, s);
        info->assemble_seconds += cfi_now_seconds() - t0;
        if (st != CF_OK) return st;
    }
    /* the blow-up and divergence checks follow in the flow layer (its step policy) */
    info->energy = s->energy;
    info->energy_terms[0] = s->energy / (4.0 * CFI_PI);
    info->term_names[0] = "W/4pi";
    info->residuals[0] = s->diag.constraint_residual;
    info->residual_names[0] = "constraint";
    info->residuals[1] = s->diag.integrability_error;
    info->residual_names[1] = "integrability";
    info->residuals[2] = s->diag.eigenvalue;
    info->residual_names[2] = "eigenvalue";
    /* slot 3 is left to the flow layer: time_step_halvings under `adaptive` */
    info->residuals[4] = s->diag.scale_change;
    info->residual_names[4] = "scale_change";
    if (s->period_newton) {
        /* harmonic part of e~ left after the period corrections, and their count */
        info->residuals[5] = s->diag.period_error;
        info->residual_names[5] = "periods";
        info->residuals[6] = s->diag.period_iterations;
        info->residual_names[6] = "period_iterations";
    }
    /* the fraction of the curvature-space model's decrease of W that the
     * step realised (1 for an exactly realised rho; docs/spin.md) */
    double realised = realised_decrease(s);
    s->diag.realised_decrease = isnan(realised) ? 0.0 : realised;
    info->residuals[7] = s->diag.realised_decrease;
    info->residual_names[7] = "realised_decrease";
    if (s->relax_iterations > 0) {
        /* the sweeps of the tangential relaxation this step kept (0: none
         * kept, or below its threshold) */
        info->residuals[8] = s->diag.relaxation_kept ? s->diag.relaxation_iterations : 0.0;
        info->residual_names[8] = "relaxation_sweeps";
    }
    if (s->keep_class) {
        /* what the projection left: |G^ - G^0| (keep_class 2: |G - G0|) */
        info->residuals[9] = s->diag.class_residual;
        info->residual_names[9] = "class";
    }
    flow->converged = cfi_spin_converged(s, s->energy_before);
    /* what the next step's reuse of X(0) is judged by (exactness.c); at a
     * stall the last rejected attempt's figures, an overestimate */
    s->x0_scale_since += s->diag.scale_change;
    s->x0_period_first = s->diag.period_error_first;
    s->diag.current_metric = s->current_metric_step;
    s->diag.fairing_only = s->fairing_only_step;
    s->last_fairing_only = s->fairing_only_step && info->time_step > 0.0;
    return CF_OK;
}

cf_status cfi_spin_reset(cf_flow *flow)
{
    cfi_spin_state *s = flow->impl;
    if (!s) return CF_OK;
    flow->converged = 0;
    s->x0_factored = 0; /* new positions: X(0) of the old ones is no guide */
    s->last_fairing_only = 0;
    cf_status st = cfi_spin_update_geometry(flow, s, flow->positions);
    /* the flow layer compares the next step's W with this one */
    flow->info.energy = s->energy;
    flow->info.energy_terms[0] = s->energy / (4.0 * CFI_PI);
    flow->info.term_names[0] = "W/4pi";
    return st;
}

cf_status cfi_spin_willmore_diagnostics(const cf_flow *flow, cfi_spin_diagnostics *out)
{
    if (!flow || !out || flow->method != &cfi_spin_willmore_method || !flow->impl) return CF_ERR_INVALID_ARG;
    *out = ((const cfi_spin_state *)flow->impl)->diag;
    return CF_OK;
}

const double *cfi_spin_willmore_harmonic_forms(const cf_flow *flow, int32_t *dimension)
{
    if (dimension) *dimension = 0;
    if (!flow || flow->method != &cfi_spin_willmore_method || !flow->impl) return NULL;
    const cfi_spin_state *s = flow->impl;
    if (dimension) *dimension = s->harmonic_dim;
    return s->harmonic;
}

const double *cfi_spin_willmore_last_edges(const cf_flow *flow)
{
    if (!flow || flow->method != &cfi_spin_willmore_method || !flow->impl) return NULL;
    return ((const cfi_spin_state *)flow->impl)->edges;
}

const double *cfi_spin_willmore_last_rhodot(const cf_flow *flow)
{
    if (!flow || flow->method != &cfi_spin_willmore_method || !flow->impl) return NULL;
    return ((const cfi_spin_state *)flow->impl)->rhodot;
}
