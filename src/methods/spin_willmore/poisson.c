/*
 * Position recovery of spin transformations (Crane et al. 2011; Crane 2013,
 * Eq. (6) and Sec. 6.3.2): least-squares fit of vertex positions to the
 * transformed edge vectors, i.e. the cotan Poisson problem L f~ = div e~ with
 * (div e~)_i = -sum_j w_ij e~_ij (so that e~ = e gives back L f), either with
 * a tiny diagonal shift (closed surfaces, free boundary; the factorisation is
 * kept until the next refill, so a flow that never refills factorises once)
 * or with the boundary vertices fixed (Dirichlet rows).
 */
#include "methods/spin_willmore/spin_internal.h"
#include "ops/cotan_laplacian.h"

#include <string.h>

/* Relative diagonal shift that makes the singular L positive definite; the
 * constant mode it perturbs is removed by the caller's centring. */
#define CFI_POISSON_SHIFT 1e-10

cf_status cfi_poisson_create(cf_context *ctx, const cf_mesh *mesh, const double *positions, cfi_poisson **out)
{
    *out = NULL;
    cfi_poisson *p = CFI_ALLOC(ctx, cfi_poisson, 1);
    if (!p) return CF_ERR_NOMEM;
    p->nv = mesh->nv;
    p->ne = mesh->ne;
    p->factored = 0;
    p->slot_count = cfi_cotan_laplacian_triplet_count(mesh);
    p->slot_map = CFI_ALLOC(ctx, int64_t, p->slot_count);
    p->edge_slot = CFI_ALLOC(ctx, int64_t, mesh->ne);
    p->diag_slot = CFI_ALLOC(ctx, int64_t, mesh->nv);
    p->rhs = CFI_ALLOC(ctx, double, 3 * (int64_t)mesh->nv);
    p->sol = CFI_ALLOC(ctx, double, 3 * (int64_t)mesh->nv);
    cf_status st = CF_OK;
    if (!p->slot_map || !p->edge_slot || !p->diag_slot || !p->rhs || !p->sol) {
        st = CF_ERR_NOMEM;
        goto fail;
    }
    st = cfi_cotan_laplacian_pattern(ctx, mesh, positions, &p->l, p->slot_map);
    if (st != CF_OK) goto fail;
    for (int32_t e = 0; e < mesh->ne; ++e) {
        p->edge_slot[e] = cf_sparse_find(p->l, mesh->edge_vertices[2 * e], mesh->edge_vertices[2 * e + 1]);
        if (CF_NEVER(p->edge_slot[e] < 0)) {
            st = cfi_error(ctx, CF_ERR_NUMERICAL, "edge %d: not in the Laplacian pattern", e);
            goto fail;
        }
    }
    for (int32_t v = 0; v < mesh->nv; ++v) {
        p->diag_slot[v] = cf_sparse_find(p->l, v, v);
        if (CF_NEVER(p->diag_slot[v] < 0)) {
            st = cfi_error(ctx, CF_ERR_NUMERICAL, "vertex %d: no diagonal entry in the Laplacian", v);
            goto fail;
        }
    }
    cf_cholesky_options co;
    cf_cholesky_options_default(&co);
    co.block_size = 1;
    st = cf_cholesky_create(ctx, p->l, &co, &p->chol);
    if (st != CF_OK) goto fail;
    *out = p;
    return CF_OK;
fail:
    cfi_poisson_destroy(ctx, &p);
    return st;
}

void cfi_poisson_destroy(cf_context *ctx, cfi_poisson **pp)
{
    if (!pp || !*pp) return;
    cfi_poisson *p = *pp;
    cf_cholesky_destroy(&p->chol);
    cf_sparse_destroy(&p->l);
    CFI_FREE(ctx, p->slot_map, p->slot_count);
    CFI_FREE(ctx, p->edge_slot, p->ne);
    CFI_FREE(ctx, p->diag_slot, p->nv);
    CFI_FREE(ctx, p->rhs, 3 * (int64_t)p->nv);
    CFI_FREE(ctx, p->sol, 3 * (int64_t)p->nv);
    CFI_FREE(ctx, p, 1);
    *pp = NULL;
}

cf_status cfi_poisson_refill(cfi_poisson *p, const cf_mesh *mesh, const double *positions)
{
    p->factored = 0;
    return cfi_cotan_laplacian_refill(p->l, mesh, positions, p->slot_map);
}

/* Factorises L + shift I (shift relative to the mean diagonal) and leaves
 * L's values as they were. */
static cf_status factorize_shifted(cfi_poisson *p, double *factor_seconds)
{
    cf_sparse *l = p->l;
    double mean_diag = 0.0;
    for (int32_t v = 0; v < p->nv; ++v) mean_diag += l->values[p->diag_slot[v]];
    double shift = CFI_POISSON_SHIFT * mean_diag / p->nv;
    for (int32_t v = 0; v < p->nv; ++v) l->values[p->diag_slot[v]] += shift;
    double t0 = cfi_now_seconds();
    cf_status st = cf_cholesky_factorize(p->chol, l);
    if (factor_seconds) *factor_seconds += cfi_now_seconds() - t0;
    for (int32_t v = 0; v < p->nv; ++v) l->values[p->diag_slot[v]] -= shift;
    p->factored = st == CF_OK;
    return st;
}

cf_status cfi_poisson_solve_scalar(cfi_poisson *p, int32_t ncols, const double *b, double *u, double *factor_seconds,
                                   double *solve_seconds)
{
    cf_status st = p->factored ? CF_OK : factorize_shifted(p, factor_seconds);
    if (st != CF_OK) return st;
    double t0 = cfi_now_seconds();
    st = cf_cholesky_solve(p->chol, ncols, b, u);
    if (solve_seconds) *solve_seconds += cfi_now_seconds() - t0;
    return st;
}

cf_status cfi_poisson_solve(cfi_poisson *p, const cf_mesh *mesh, const double *edges, int fixed_boundary,
                            const double *fixed, double *out, double *factor_seconds, double *solve_seconds)
{
    int32_t nv = mesh->nv;
    cf_sparse *l = p->l;
    double *rhs = p->rhs;
    memset(rhs, 0, 3 * (size_t)nv * sizeof(double));
    for (int32_t e = 0; e < mesh->ne; ++e) {
        int32_t i = mesh->edge_vertices[2 * e], j = mesh->edge_vertices[2 * e + 1];
        double w = -l->values[p->edge_slot[e]];
        for (int c = 0; c < 3; ++c) {
            rhs[c * nv + i] -= w * edges[3 * e + c];
            rhs[c * nv + j] += w * edges[3 * e + c];
        }
    }
    cf_status st = CF_OK;
    if (fixed_boundary) {
        const uint8_t *onb = mesh->vertex_on_boundary;
        /* move boundary columns to the right-hand side, then identity rows/columns */
        for (int32_t j = 0; j < nv; ++j) {
            if (!onb[j]) continue;
            for (int32_t q = l->colptr[j]; q < l->colptr[j + 1]; ++q) {
                int32_t i = l->rowind[q];
                if (onb[i]) continue;
                for (int c = 0; c < 3; ++c) rhs[c * nv + i] -= l->values[q] * fixed[3 * j + c];
            }
        }
        for (int32_t j = 0; j < nv; ++j) {
            for (int32_t q = l->colptr[j]; q < l->colptr[j + 1]; ++q) {
                int32_t i = l->rowind[q];
                if (onb[i] || onb[j]) l->values[q] = i == j ? 1.0 : 0.0;
            }
        }
        for (int32_t j = 0; j < nv; ++j)
            if (onb[j])
                for (int c = 0; c < 3; ++c) rhs[c * nv + j] = fixed[3 * j + c];
        /* L's values now hold the Dirichlet rows: refactorise, and let the
         * next user refill first */
        p->factored = 0;
        double t0 = cfi_now_seconds();
        st = cf_cholesky_factorize(p->chol, l);
        if (factor_seconds) *factor_seconds += cfi_now_seconds() - t0;
    } else if (!p->factored) {
        st = factorize_shifted(p, factor_seconds);
    }
    double t1 = cfi_now_seconds();
    if (st == CF_OK) st = cf_cholesky_solve(p->chol, 3, rhs, p->sol);
    if (solve_seconds) *solve_seconds += cfi_now_seconds() - t1;
    if (st != CF_OK) return st;
    for (int32_t v = 0; v < nv; ++v)
        for (int c = 0; c < 3; ++c) out[3 * v + c] = p->sol[c * nv + v];
    return CF_OK;
}
