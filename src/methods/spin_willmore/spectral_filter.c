/*
 * Spectral filter of the curvature flow direction (Crane, Pinkall,
 * Schroeder 2013, Sec. 4, Fig. 8): rhodot <- rhodot - (id + sigma Delta^k)^-1
 * rhodot with Delta = M^-1 L (L the positive semi-definite cotan
 * Laplacian), i.e. the solve of F u = M rhodot with
 * F = M + sigma' L (M^-1 L)^(k-1), sigma' = sigma R^2k, R = sqrt(area / 4 pi)
 * (scale-free sigma). k = 0 is the constant factor sigma / (1 + sigma).
 */
#include "methods/spin_willmore/spin_flow.h"
#include "curvflow/ops.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* Copy of a with column j scaled by colscale[j]. */
static cf_status scaled_copy(cf_context *ctx, const cf_sparse *a, const double *colscale, cf_sparse **out)
{
    int64_t nnz = cf_sparse_nnz(a);
    int32_t *r = CFI_ALLOC(ctx, int32_t, nnz), *c = CFI_ALLOC(ctx, int32_t, nnz);
    double *v = CFI_ALLOC(ctx, double, nnz);
    cf_status st = CF_ERR_NOMEM;
    if (r && c && v) {
        for (int32_t j = 0; j < a->ncols; ++j)
            for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) {
                r[p] = a->rowind[p];
                c[p] = j;
                v[p] = a->values[p] * colscale[j];
            }
        st = cf_sparse_from_triplets(ctx, a->nrows, a->ncols, nnz, r, c, v, 0, out, NULL);
    }
    CFI_FREE(ctx, r, nnz);
    CFI_FREE(ctx, c, nnz);
    CFI_FREE(ctx, v, nnz);
    return st;
}

/* F fails to factorise when sigma' (M^-1 L)^k dwarfs M by about the
 * reciprocal of the rounding unit: its constant mode (L 1 = 0, so F 1 = M 1)
 * is then lost to rounding, and Cholesky breaks down at the last pivot
 * (issue 15 E3: spot_3k at sigma 1e12, "not positive definite at column
 * 190"). The largest sigma that still factorises depends on the mesh
 * (spot_3k 1e11, a 642-vertex icosphere above 1e12), so it is found by
 * trying sigma / 10, / 100, ... with the same analysis (failure path only),
 * and the message names the option, the mesh's sizes and that value; the
 * user's sigma is not changed behind their back. stiff is L (k = 1) or
 * L (M^-1 L)^(k-1), radius_k R^2k. */
static cf_status explain_filter_failure(cf_flow *flow, cfi_spin_state *s, const cf_sparse *m, const cf_sparse *stiff,
                                        double radius_k)
{
    cf_context *ctx = flow->ctx;
    double works = 0.0;
    for (double trial = s->opt.sigma / 10.0; s->filter_chol && trial >= 1e-6 && works == 0.0; trial /= 10.0) {
        cf_sparse *f = NULL;
        if (cf_sparse_add(ctx, 1.0, m, trial * radius_k, stiff, &f) != CF_OK) break;
        f->symmetric = 1;
        if (cf_cholesky_factorize(s->filter_chol, f) == CF_OK) works = trial;
        cf_sparse_destroy(&f);
    }
    char hint[96];
    if (works > 0.0)
        snprintf(hint, sizeof hint, "sigma = %g factorises on this mesh", works);
    else
        snprintf(hint, sizeof hint, "no sigma down to 1e-6 factorises either");
    return cfi_error(ctx, CF_ERR_NUMERICAL,
                     "spin-willmore: parameter 'sigma': the spectral filter M + sigma R^%d L (M^-1 L)^%d cannot be "
                     "factorised in double precision with sigma = %g on this mesh (%d vertices, %d faces, R = "
                     "sqrt(area / 4pi) = %.4g): its constant mode is lost to rounding; use a smaller sigma (%s; the "
                     "filter's effect saturates long before) or a smaller filter_k",
                     2 * s->opt.filter_k, s->opt.filter_k - 1, s->opt.sigma, s->nv, flow->mesh->nf,
                     sqrt(flow->initial_area / (4.0 * CFI_PI)), hint);
}

/* Filter matrix F = M + sigma' L (M^-1 L)^(k-1) of the input surface. The
 * weak cotan Laplacian is invariant under conformal maps, and the flow is
 * conformal, so F is built and factorised once. */
cf_status cfi_spin_filter_build(cf_flow *flow, cfi_spin_state *s)
{
    cf_context *ctx = flow->ctx;
    const cf_mesh *mesh = flow->mesh;
    int32_t k = s->opt.filter_k;
    double sigma = s->opt.sigma;
    if (k == 0) {
        s->filter_scale = sigma / (1.0 + sigma);
        return CF_OK;
    }
    s->filter_mass = CFI_SPIN_WS_ALLOC(&s->ws, double, s->nv);
    if (!s->filter_mass) return CF_ERR_NOMEM;
    memcpy(s->filter_mass, s->area, (size_t)s->nv * sizeof(double));
    double radius2 = flow->initial_area / (4.0 * CFI_PI);
    double sig = sigma * pow(radius2, (double)k);
    cf_sparse *l = NULL, *m = NULL, *lminv = NULL, *p = NULL, *p2 = NULL;
    cf_status st = cf_cotan_laplacian(ctx, mesh, flow->positions, &l);
    if (st == CF_OK) st = cf_mass_matrix(ctx, mesh, flow->positions, CF_MASS_LUMPED_BARYCENTRIC, &m);
    if (st != CF_OK) goto done;
    if (k == 1) {
        st = cf_sparse_add(ctx, 1.0, m, sig, l, &s->filter);
    } else {
        for (int32_t i = 0; i < s->nv; ++i) s->vtmp[i] = 1.0 / s->area[i];
        st = scaled_copy(ctx, l, s->vtmp, &lminv);
        if (st == CF_OK) st = cf_sparse_product(ctx, lminv, l, &p);
        if (st == CF_OK && k == 3) {
            st = cf_sparse_product(ctx, lminv, p, &p2);
            cf_sparse_destroy(&p);
            p = p2;
            p2 = NULL;
        }
        if (st == CF_OK) st = cf_sparse_add(ctx, 1.0, m, sig, p, &s->filter);
    }
    if (st != CF_OK) goto done;
    s->filter->symmetric = 1;
    cf_cholesky_options co;
    cf_cholesky_options_default(&co);
    co.block_size = 1;
    st = cf_cholesky_create(ctx, s->filter, &co, &s->filter_chol);
    if (st == CF_OK) st = cf_cholesky_factorize(s->filter_chol, s->filter);
    if (st == CF_ERR_NOT_POSDEF) st = explain_filter_failure(flow, s, m, k == 1 ? l : p, pow(radius2, (double)k));
done:
    cf_sparse_destroy(&l);
    cf_sparse_destroy(&m);
    cf_sparse_destroy(&lminv);
    cf_sparse_destroy(&p);
    cf_sparse_destroy(&p2);
    return st;
}

cf_status cfi_spin_filter_apply(cfi_spin_state *s, double *solve_seconds)
{
    int32_t nv = s->nv;
    cf_status st = CF_OK;
    if (s->opt.sigma > 0.0) {
        if (s->opt.filter_k == 0) {
            for (int32_t i = 0; i < nv; ++i) s->rhodot[i] *= s->filter_scale;
        } else {
            for (int32_t i = 0; i < nv; ++i) s->vtmp[i] = s->filter_mass[i] * s->rhodot[i];
            double ts = cfi_now_seconds();
            st = cf_cholesky_solve(s->filter_chol, 1, s->vtmp, s->vtmp2);
            *solve_seconds += cfi_now_seconds() - ts;
            if (st != CF_OK) return st;
            for (int32_t i = 0; i < nv; ++i) s->rhodot[i] -= s->vtmp2[i];
        }
    }
    return st;
}
