/*
 * Positions from edge vectors (Crane et al. 2011; Crane, Pinkall, Schroeder
 * 2013, Eq. (6) and Sec. 6.3.2): the least-squares fit of vertex positions
 * to prescribed edge vectors in a cotan metric, i.e. the Poisson problem
 * L f = b with (b)_i = -sum_j w_ij e~_ij, either with a tiny relative
 * diagonal shift (nothing fixed; the factorisation is kept until the metric
 * changes, so a fixed metric factorises once) or with some vertices' values
 * fixed (cf_min_quad on the free block, refactorised after a metric change).
 * Moved here from src/methods/spin_willmore/poisson.c for the face-based
 * spin and Regge flows (issue 12). Conventions: curvflow/ops.h.
 */
#include "curvflow/ops.h"
#include "mesh/mesh_internal.h"
#include "ops/cotan_laplacian.h"

#include <math.h>
#include <string.h>

/* Relative diagonal shift that makes the singular L positive definite; the
 * constant mode it perturbs is removed by the caller's centring. */
#define CFI_EDGE_POISSON_SHIFT 1e-10

struct cf_edge_poisson {
    cf_context *ctx;
    const cf_mesh *mesh;
    cf_sparse *l;
    int64_t *slot_map;     /* cf_cotan_laplacian_slot_count entries */
    int64_t slot_count;
    int64_t *edge_slot;    /* ne: slot of entry (i, j), L_ij = -w_ij */
    int64_t *diag_slot;    /* nv */
    cf_cholesky *chol;     /* nothing fixed: L + shift I */
    cf_min_quad *quad;     /* fixed values: the free block */
    int32_t *known;        /* known_count vertices */
    double *y;             /* 3 known_count, column-major */
    double *rhs;           /* 3 nv, column-major */
    double *sol;           /* 3 nv */
    int32_t nv, ne, known_count;
    int32_t factored;      /* the factorisation matches L's current values */
    double weight_floor;   /* of L's cotan weights (cf_edge_poisson_create_floored) */
};

static cf_status edge_slots(cf_edge_poisson *p)
{
    const cf_mesh *mesh = p->mesh;
    for (int32_t e = 0; e < mesh->ne; ++e) {
        p->edge_slot[e] = cf_sparse_find(p->l, mesh->edge_vertices[2 * e], mesh->edge_vertices[2 * e + 1]);
        if (CF_NEVER(p->edge_slot[e] < 0))
            return cfi_error(p->ctx, CF_ERR_NUMERICAL, "edge %d: not in the Laplacian pattern", e);
    }
    for (int32_t v = 0; v < mesh->nv; ++v) {
        p->diag_slot[v] = cf_sparse_find(p->l, v, v);
        if (CF_NEVER(p->diag_slot[v] < 0))
            return cfi_error(p->ctx, CF_ERR_NUMERICAL, "vertex %d: no diagonal entry in the Laplacian", v);
    }
    return CF_OK;
}

static cf_status create_solver(cf_edge_poisson *p)
{
    if (p->known_count == 0) {
        cf_cholesky_options co;
        cf_cholesky_options_default(&co);
        co.block_size = 1;
        return cf_cholesky_create(p->ctx, p->l, &co, &p->chol);
    }
    cf_min_quad_options mo;
    cf_min_quad_options_default(&mo);
    mo.max_rhs = 3; /* x, y, z at once without allocating */
    cf_status st = cf_min_quad_create(p->ctx, p->l, p->known_count, p->known, NULL, &mo, &p->quad);
    p->factored = st == CF_OK;
    return st;
}

cf_status cf_edge_poisson_create(cf_context *ctx, const cf_mesh *mesh, const double *positions, int32_t known_count,
                                 const int32_t *known, cf_edge_poisson **out)
{
    return cf_edge_poisson_create_floored(ctx, mesh, positions, known_count, known, 0.0, out);
}

cf_status cf_edge_poisson_create_floored(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                         int32_t known_count, const int32_t *known, double weight_floor,
                                         cf_edge_poisson **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "edge_poisson: out is NULL");
    *out = NULL;
    cf_status floor_ok = cfi_check_weight_floor(ctx, weight_floor, "edge_poisson");
    if (floor_ok != CF_OK) return floor_ok;
    if (!mesh) return cfi_error(ctx, CF_ERR_INVALID_ARG, "edge_poisson: mesh is NULL");
    if (known_count < 0 || known_count >= mesh->nv || (known_count > 0 && !known))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "edge_poisson: %d known vertices of %d (need 0 .. nv - 1, and the list)",
                         known_count, mesh->nv);
    if (!positions) positions = mesh->positions;
    cf_edge_poisson *p = CFI_ALLOC(ctx, cf_edge_poisson, 1);
    if (!p) return CF_ERR_NOMEM;
    p->ctx = ctx;
    p->mesh = mesh;
    p->nv = mesh->nv;
    p->ne = mesh->ne;
    p->known_count = known_count;
    p->weight_floor = weight_floor;
    p->slot_count = cf_cotan_laplacian_slot_count(mesh);
    p->slot_map = CFI_ALLOC(ctx, int64_t, p->slot_count);
    p->edge_slot = CFI_ALLOC(ctx, int64_t, mesh->ne);
    p->diag_slot = CFI_ALLOC(ctx, int64_t, mesh->nv);
    p->rhs = CFI_ALLOC(ctx, double, 3 * (int64_t)mesh->nv);
    p->sol = CFI_ALLOC(ctx, double, 3 * (int64_t)mesh->nv);
    if (known_count > 0) {
        p->known = CFI_ALLOC(ctx, int32_t, known_count);
        p->y = CFI_ALLOC(ctx, double, 3 * (int64_t)known_count);
    }
    cf_status st = CF_OK;
    if (!p->slot_map || !p->edge_slot || !p->diag_slot || !p->rhs || !p->sol ||
        (known_count > 0 && (!p->known || !p->y))) {
        st = CF_ERR_NOMEM;
        goto fail;
    }
    if (known_count > 0) memcpy(p->known, known, (size_t)known_count * sizeof *known);
    st = cfi_cotan_laplacian_pattern(ctx, mesh, positions, weight_floor, &p->l, p->slot_map);
    if (st == CF_OK) st = edge_slots(p);
    if (st == CF_OK) st = create_solver(p);
    if (st != CF_OK) goto fail;
    *out = p;
    return CF_OK;
fail:
    cf_edge_poisson_destroy(&p);
    return st;
}

void cf_edge_poisson_destroy(cf_edge_poisson **pp)
{
    if (!pp || !*pp) return;
    cf_edge_poisson *p = *pp;
    cf_context *ctx = p->ctx;
    cf_cholesky_destroy(&p->chol);
    cf_min_quad_destroy(&p->quad);
    cf_sparse_destroy(&p->l);
    if (p->slot_map) CFI_FREE(ctx, p->slot_map, p->slot_count);
    CFI_FREE(ctx, p->edge_slot, p->ne);
    CFI_FREE(ctx, p->diag_slot, p->nv);
    CFI_FREE(ctx, p->rhs, 3 * (int64_t)p->nv);
    CFI_FREE(ctx, p->sol, 3 * (int64_t)p->nv);
    if (p->known) CFI_FREE(ctx, p->known, p->known_count);
    if (p->y) CFI_FREE(ctx, p->y, 3 * (int64_t)p->known_count);
    CFI_FREE(ctx, p, 1);
    *pp = NULL;
}

void cf_edge_poisson_freeze_metric(cf_edge_poisson *p)
{
    if (!p || !p->slot_map) return;
    CFI_FREE(p->ctx, p->slot_map, p->slot_count);
    p->slot_map = NULL;
}

/* The slot map of a frozen solver again, from the slots it kept: each
 * triplet of the pattern (cfi_cotan_laplacian_triplet_count's layout) has
 * one entry of L, the slot cf_sparse_from_triplets gave it. */
static cf_status rebuild_slot_map(cf_edge_poisson *p)
{
    const cf_mesh *mesh = p->mesh;
    p->slot_map = CFI_ALLOC(p->ctx, int64_t, p->slot_count);
    if (!p->slot_map)
        return cfi_error(p->ctx, CF_ERR_NOMEM, "edge poisson: out of memory for the refill map of %d vertices", p->nv);
    for (int32_t v = 0; v < p->nv; ++v) p->slot_map[v] = p->diag_slot[v];
    for (int32_t e = 0; e < p->ne; ++e) {
        int64_t b = p->nv + 2 * (int64_t)e;
        p->slot_map[b] = p->edge_slot[e];
        p->slot_map[b + 1] = cf_sparse_find(p->l, mesh->edge_vertices[2 * e + 1], mesh->edge_vertices[2 * e]);
    }
    return CF_OK;
}

cf_status cf_edge_poisson_set_metric(cf_edge_poisson *p, const double *positions)
{
    return cf_edge_poisson_set_metric_scaled(p, positions, NULL);
}

cf_status cf_edge_poisson_set_metric_scaled(cf_edge_poisson *p, const double *positions, const double *face_scale)
{
    if (!p || !positions) return CF_ERR_INVALID_ARG;
    if (face_scale)
        for (int32_t f = 0; f < p->mesh->nf; ++f)
            if (!(face_scale[f] > 0.0) || !isfinite(face_scale[f]))
                return cfi_error(p->ctx, CF_ERR_INVALID_ARG, "edge_poisson: face %d: scale %g is not positive and finite",
                                 f, face_scale[f]);
    if (!p->slot_map) {
        cf_status st = rebuild_slot_map(p);
        if (st != CF_OK) return st;
    }
    p->factored = 0;
    return cfi_cotan_laplacian_refill_scaled(p->l, p->mesh, positions, p->weight_floor, face_scale, p->slot_map);
}

const cf_sparse *cf_edge_poisson_laplacian(const cf_edge_poisson *p) { return p ? p->l : NULL; }

double cf_edge_poisson_weight(const cf_edge_poisson *p, int32_t e) { return -p->l->values[p->edge_slot[e]]; }

/* Factorises L + shift I (shift relative to the mean diagonal) and leaves
 * L's values as they were. */
static cf_status factorize(cf_edge_poisson *p, cf_solver_timings *timings)
{
    double t0 = cfi_now_seconds();
    cf_status st;
    if (p->quad) {
        st = cf_min_quad_factorize(p->quad, p->l, NULL);
    } else {
        cf_sparse *l = p->l;
        double mean_diag = 0.0;
        for (int32_t v = 0; v < p->nv; ++v) mean_diag += l->values[p->diag_slot[v]];
        double shift = CFI_EDGE_POISSON_SHIFT * mean_diag / p->nv;
        for (int32_t v = 0; v < p->nv; ++v) l->values[p->diag_slot[v]] += shift;
        t0 = cfi_now_seconds();
        st = cf_cholesky_factorize(p->chol, l);
        if (timings) timings->factorize_seconds += cfi_now_seconds() - t0;
        for (int32_t v = 0; v < p->nv; ++v) l->values[p->diag_slot[v]] -= shift;
        p->factored = st == CF_OK;
        return st;
    }
    if (timings) timings->factorize_seconds += cfi_now_seconds() - t0;
    p->factored = st == CF_OK;
    return st;
}

cf_status cf_edge_poisson_solve_scalar(cf_edge_poisson *p, int32_t ncols, const double *b, double *u,
                                       cf_solver_timings *timings)
{
    if (!p || ncols < 1 || !b || !u) return CF_ERR_INVALID_ARG;
    if (p->quad)
        return cfi_error(p->ctx, CF_ERR_INVALID_ARG, "edge_poisson: solve_scalar needs a solver without fixed values");
    cf_status st = p->factored ? CF_OK : factorize(p, timings);
    if (st != CF_OK) return st;
    double t0 = cfi_now_seconds();
    st = cf_cholesky_solve(p->chol, ncols, b, u);
    if (timings) timings->solve_seconds += cfi_now_seconds() - t0;
    return st;
}

cf_status cf_edge_poisson_solve(cf_edge_poisson *p, const double *edges, const double *fixed, double *out,
                                cf_solver_timings *timings)
{
    return cf_edge_poisson_solve_from(p, NULL, edges, fixed, out, timings);
}

/* With a base, the unknown is the displacement d = f - base and the right-hand
 * side is built from e~ - e(base): since div e(base) = L base exactly for
 * these weights, L d = b - L base is the same least-squares problem, but the
 * rounding error of the solve is relative to |d| (the step) instead of |f|
 * (the coordinates). Where a flow has crowded a region to 1e-8 of the mean
 * edge length, the absolute solve's error is larger than its triangles. */
cf_status cf_edge_poisson_solve_from(cf_edge_poisson *p, const double *base, const double *edges, const double *fixed,
                                     double *out, cf_solver_timings *timings)
{
    if (!p || !edges || !out || (p->known_count > 0 && !fixed)) return CF_ERR_INVALID_ARG;
    const cf_mesh *mesh = p->mesh;
    int32_t nv = p->nv;
    const cf_sparse *l = p->l;
    double *rhs = p->rhs;
    memset(rhs, 0, 3 * (size_t)nv * sizeof(double));
    for (int32_t e = 0; e < mesh->ne; ++e) {
        int32_t i = mesh->edge_vertices[2 * e], j = mesh->edge_vertices[2 * e + 1];
        double w = -l->values[p->edge_slot[e]];
        for (int c = 0; c < 3; ++c) {
            double d = base ? edges[3 * e + c] - (base[3 * j + c] - base[3 * i + c]) : edges[3 * e + c];
            rhs[c * nv + i] -= w * d;
            rhs[c * nv + j] += w * d;
        }
    }
    cf_status st = p->factored ? CF_OK : factorize(p, timings);
    if (st != CF_OK) return st;
    double t1 = cfi_now_seconds();
    if (p->quad) {
        /* min 1/2 f^T L f - rhs^T f with the known values: b = -rhs */
        for (int64_t k = 0; k < 3 * (int64_t)nv; ++k) rhs[k] = -rhs[k];
        for (int32_t k = 0; k < p->known_count; ++k)
            for (int c = 0; c < 3; ++c) {
                int64_t v = 3 * (int64_t)p->known[k] + c;
                p->y[c * p->known_count + k] = base ? fixed[v] - base[v] : fixed[v];
            }
        st = cf_min_quad_solve(p->quad, 3, rhs, p->y, NULL, p->sol);
    } else {
        st = cf_cholesky_solve(p->chol, 3, rhs, p->sol);
    }
    if (timings) timings->solve_seconds += cfi_now_seconds() - t1;
    if (st != CF_OK) return st;
    for (int32_t v = 0; v < nv; ++v)
        for (int c = 0; c < 3; ++c) out[3 * v + c] = base ? base[3 * v + c] + p->sol[c * nv + v] : p->sol[c * nv + v];
    /* the known vertices get their fixed values exactly, also with a base */
    if (base)
        for (int32_t k = 0; k < p->known_count; ++k)
            for (int c = 0; c < 3; ++c) out[3 * p->known[k] + c] = fixed[3 * p->known[k] + c];
    return CF_OK;
}

double cf_edge_closure_error(const cf_mesh *mesh, const double *positions, const double *edges)
{
    if (!mesh || !positions || !edges) return NAN;
    double num = 0.0, den = 0.0;
    for (int32_t e = 0; e < mesh->ne; ++e) {
        int32_t i = mesh->edge_vertices[2 * e], j = mesh->edge_vertices[2 * e + 1];
        for (int c = 0; c < 3; ++c) {
            double g = positions[3 * j + c] - positions[3 * i + c];
            double t = edges[3 * e + c];
            num += (g - t) * (g - t);
            den += t * t;
        }
    }
    return den > 0.0 ? sqrt(num / den) : 0.0;
}
