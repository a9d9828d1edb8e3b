/*
 * Vertex-scale fairing of positions: one implicit Laplacian step with the
 * cotan Laplacian L0 of a reference surface and unit vertex weights,
 *   x = argmin |x - f|^2 + kappa x^T L0 x   (held vertices keep f),
 * i.e. (I + kappa L0) x = f on the free vertices. L0's weights are
 * scale-free, so the step acts on every part of a surface at that part's
 * own size (a region shrunk by s moves by s times as much as before); an
 * eigenvector of L0 with eigenvalue mu is damped by 1 / (1 + kappa mu), so
 * for kappa of order one only modes that vary from one vertex to the next
 * (mu of order one) are damped and smooth ones (mu ~ 1 / nv) pass. Written
 * for spin-willmore's vertex-scale fairing (docs/spin.md, "Vertex-scale
 * fairing"); conventions: curvflow/ops.h.
 */
#include "curvflow/ops.h"
#include "mesh/mesh_internal.h"

#include <math.h>
#include <string.h>

struct cf_vertex_fairing {
    cf_context *ctx;
    int32_t nv, known_count;
    cf_sparse *a;          /* I + kappa L0 (L0's pattern, both triangles) */
    double *l0;            /* L0's values, in a's slots */
    int64_t *diag_slot;    /* nv */
    cf_cholesky *chol;     /* nothing held */
    cf_min_quad *quad;     /* held vertices: the free block */
    int32_t *known;        /* known_count vertices */
    double *y;             /* 3 known_count, column-major */
    double *rhs, *sol;     /* 3 nv each, column-major */
    double kappa;          /* of the current factorisation (0: none yet) */
};

/* a = I + kappa L0 */
static void fill(cf_vertex_fairing *f, double kappa)
{
    int64_t nnz = cf_sparse_nnz(f->a);
    for (int64_t p = 0; p < nnz; ++p) f->a->values[p] = kappa * f->l0[p];
    for (int32_t i = 0; i < f->nv; ++i) f->a->values[f->diag_slot[i]] += 1.0;
}

cf_status cf_vertex_fairing_create(cf_context *ctx, const cf_mesh *mesh, const double *positions, int32_t hold_boundary,
                                   cf_vertex_fairing **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out || !mesh) return cfi_error(ctx, CF_ERR_INVALID_ARG, "vertex_fairing: mesh or out is NULL");
    *out = NULL;
    if (!positions) positions = mesh->positions;
    cf_vertex_fairing *f = CFI_ALLOC(ctx, cf_vertex_fairing, 1);
    if (!f) return CF_ERR_NOMEM;
    f->ctx = ctx;
    f->nv = mesh->nv;
    int32_t known = 0;
    if (hold_boundary)
        for (int32_t i = 0; i < mesh->nv; ++i) known += mesh->vertex_on_boundary[i] != 0;
    f->known_count = known;
    cf_status st = cf_cotan_laplacian(ctx, mesh, positions, &f->a);
    if (st != CF_OK) goto fail;
    int64_t nnz = cf_sparse_nnz(f->a);
    f->l0 = CFI_ALLOC(ctx, double, nnz);
    f->diag_slot = CFI_ALLOC(ctx, int64_t, f->nv);
    f->rhs = CFI_ALLOC(ctx, double, 3 * (int64_t)f->nv);
    f->sol = CFI_ALLOC(ctx, double, 3 * (int64_t)f->nv);
    if (known > 0) {
        f->known = CFI_ALLOC(ctx, int32_t, known);
        f->y = CFI_ALLOC(ctx, double, 3 * (int64_t)known);
    }
    if (!f->l0 || !f->diag_slot || !f->rhs || !f->sol || (known > 0 && (!f->known || !f->y))) {
        st = CF_ERR_NOMEM;
        goto fail;
    }
    memcpy(f->l0, f->a->values, (size_t)nnz * sizeof(double));
    for (int32_t i = 0; i < f->nv; ++i) {
        f->diag_slot[i] = cf_sparse_find(f->a, i, i);
        if (CF_NEVER(f->diag_slot[i] < 0)) {
            st = cfi_error(ctx, CF_ERR_NUMERICAL, "vertex_fairing: vertex %d has no diagonal entry", i);
            goto fail;
        }
    }
    known = 0;
    if (f->known)
        for (int32_t i = 0; i < mesh->nv; ++i)
            if (mesh->vertex_on_boundary[i]) f->known[known++] = i;
    if (f->known_count == f->nv) {
        /* nothing is free: apply copies */
    } else if (f->known_count == 0) {
        cf_cholesky_options co;
        cf_cholesky_options_default(&co);
        st = cf_cholesky_create(ctx, f->a, &co, &f->chol);
    } else {
        /* cf_min_quad analyses and factorises at once: with kappa = 1 */
        fill(f, 1.0);
        cf_min_quad_options mo;
        cf_min_quad_options_default(&mo);
        mo.max_rhs = 3;
        st = cf_min_quad_create(ctx, f->a, f->known_count, f->known, NULL, &mo, &f->quad);
        if (st == CF_OK) f->kappa = 1.0;
    }
    if (st != CF_OK) goto fail;
    *out = f;
    return CF_OK;
fail:
    cf_vertex_fairing_destroy(&f);
    return st;
}

cf_status cf_vertex_fairing_apply(cf_vertex_fairing *f, double kappa, const double *in, double *out,
                                  cf_solver_timings *timings)
{
    if (!f || !in || !out) return CF_ERR_INVALID_ARG;
    if (!(kappa >= 0.0) || !isfinite(kappa))
        return cfi_error(f->ctx, CF_ERR_INVALID_ARG, "vertex_fairing: kappa must be finite and >= 0, got %g", kappa);
    int32_t nv = f->nv;
    if (kappa == 0.0 || f->known_count == nv) {
        if (out != in) memmove(out, in, 3 * (size_t)nv * sizeof(double));
        return CF_OK;
    }
    cf_status st = CF_OK;
    if (kappa != f->kappa) {
        double t0 = cfi_now_seconds();
        f->kappa = 0.0; /* until the factorisation succeeds */
        fill(f, kappa);
        st = f->quad ? cf_min_quad_factorize(f->quad, f->a, NULL) : cf_cholesky_factorize(f->chol, f->a);
        if (timings) timings->factorize_seconds += cfi_now_seconds() - t0;
        if (st != CF_OK) return st;
        f->kappa = kappa;
    }
    for (int c = 0; c < 3; ++c)
        for (int32_t i = 0; i < nv; ++i) f->rhs[(int64_t)c * nv + i] = in[3 * (int64_t)i + c];
    double t0 = cfi_now_seconds();
    if (f->quad) {
        /* min 1/2 x^T (I + kappa L0) x - f^T x with the held values */
        for (int32_t k = 0; k < f->known_count; ++k)
            for (int c = 0; c < 3; ++c) f->y[(int64_t)c * f->known_count + k] = f->rhs[(int64_t)c * nv + f->known[k]];
        for (int64_t i = 0; i < 3 * (int64_t)nv; ++i) f->rhs[i] = -f->rhs[i];
        st = cf_min_quad_solve(f->quad, 3, f->rhs, f->y, NULL, f->sol);
    } else {
        st = cf_cholesky_solve(f->chol, 3, f->rhs, f->sol);
    }
    if (timings) timings->solve_seconds += cfi_now_seconds() - t0;
    if (st != CF_OK) return st;
    for (int c = 0; c < 3; ++c)
        for (int32_t i = 0; i < nv; ++i) out[3 * (int64_t)i + c] = f->sol[(int64_t)c * nv + i];
    return CF_OK;
}

void cf_vertex_fairing_destroy(cf_vertex_fairing **fp)
{
    if (!fp || !*fp) return;
    cf_vertex_fairing *f = *fp;
    cf_context *ctx = f->ctx;
    int64_t nnz = f->a ? cf_sparse_nnz(f->a) : 0;
    cf_sparse_destroy(&f->a);
    cf_cholesky_destroy(&f->chol);
    cf_min_quad_destroy(&f->quad);
    if (f->l0) CFI_FREE(ctx, f->l0, nnz);
    if (f->diag_slot) CFI_FREE(ctx, f->diag_slot, f->nv);
    if (f->rhs) CFI_FREE(ctx, f->rhs, 3 * (int64_t)f->nv);
    if (f->sol) CFI_FREE(ctx, f->sol, 3 * (int64_t)f->nv);
    if (f->known) CFI_FREE(ctx, f->known, f->known_count);
    if (f->y) CFI_FREE(ctx, f->y, 3 * (int64_t)f->known_count);
    CFI_FREE(ctx, f, 1);
    *fp = NULL;
}
