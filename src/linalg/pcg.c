/*
 * Matrix-free conjugate gradients with a diagonal (Jacobi) preconditioner,
 * several independent right-hand sides at once (curvflow/linalg.h,
 * cf_pcg_solve). Written for the two well-conditioned systems that keep no
 * factor: the vertex-scale fairing's I + kappa L0 (ops/vertex_fairing.c,
 * three coordinate columns, held rows) and the scale fit's signless
 * Laplacian (metrics/quasi_conformal.c, one column). Each column has its own
 * step lengths and stops on its own residual, so a column that is solved
 * (or zero) no longer moves while the others go on.
 */
#include "core/core.h"
#include "curvflow/linalg.h"

#include <math.h>

/* x += alpha p, r -= alpha q per column, and the new |r|^2 and r . M^-1 r. */
static inline void update_iterate(int32_t n, int32_t m, const double *inverse_diagonal, const double *alpha,
                                  const double *p, const double *q, double *x, double *r, double *rr, double *rz_new)
{
    for (int32_t i = 0; i < n; ++i)
        for (int32_t c = 0; c < m; ++c) {
            int64_t k = (int64_t)m * i + c;
            x[k] += alpha[c] * p[k];
            r[k] -= alpha[c] * q[k];
            rr[c] += r[k] * r[k];
            rz_new[c] += r[k] * r[k] * inverse_diagonal[i];
        }
}

/* p = M^-1 r + beta p per column. */
static inline void update_direction(int32_t n, int32_t m, const double *inverse_diagonal, const double *beta,
                                    const double *r, double *p)
{
    for (int32_t i = 0; i < n; ++i)
        for (int32_t c = 0; c < m; ++c) {
            int64_t k = (int64_t)m * i + c;
            p[k] = inverse_diagonal[i] * r[k] + beta[c] * p[k];
        }
}

cf_status cf_pcg_solve(cf_context *ctx, int32_t n, int32_t columns, cf_pcg_multiply_fn multiply, void *user,
                       const double *inverse_diagonal, double *x, double *r, double *p, double *q, double tolerance,
                       int32_t max_iterations, cf_pcg_result *result)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!multiply || !inverse_diagonal || !x || !r || !p || !q || !result)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "pcg_solve: a required argument is NULL");
    if (n < 0 || max_iterations < 0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "pcg_solve: n (%d) and max_iterations (%d) must be >= 0", n,
                         max_iterations);
    if (columns < 1 || columns > CF_PCG_MAX_COLUMNS)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "pcg_solve: %d columns, expected 1 to %d", columns,
                         CF_PCG_MAX_COLUMNS);
    if (!(tolerance >= 0.0) || !isfinite(tolerance))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "pcg_solve: tolerance must be finite and >= 0, got %g", tolerance);
    const int32_t m = columns;
    double bnorm[CF_PCG_MAX_COLUMNS], rz[CF_PCG_MAX_COLUMNS], rr[CF_PCG_MAX_COLUMNS];
    double pq[CF_PCG_MAX_COLUMNS], alpha[CF_PCG_MAX_COLUMNS], beta[CF_PCG_MAX_COLUMNS];
    double rz_new[CF_PCG_MAX_COLUMNS];
    int done[CF_PCG_MAX_COLUMNS];
    for (int32_t c = 0; c < m; ++c) bnorm[c] = rz[c] = 0.0;
    for (int32_t i = 0; i < n; ++i)
        for (int32_t c = 0; c < m; ++c) {
            int64_t k = (int64_t)m * i + c;
            p[k] = inverse_diagonal[i] * r[k];
            rz[c] += r[k] * p[k];
            bnorm[c] += r[k] * r[k];
        }
    int all_done = 1;
    for (int32_t c = 0; c < m; ++c) {
        done[c] = !(bnorm[c] > 0.0);
        rr[c] = bnorm[c];
        all_done = all_done && done[c];
    }
    int32_t it = 0;
    while (!all_done) {
        if (it >= max_iterations) break;
        ++it;
        multiply(user, p, q, pq);
        for (int32_t c = 0; c < m; ++c) {
            alpha[c] = done[c] || !(pq[c] > 0.0) ? 0.0 : rz[c] / pq[c];
            rr[c] = rz_new[c] = 0.0;
        }
        /* the column counts of the callers, as constants the loops unroll on */
        switch (m) {
        case 1: update_iterate(n, 1, inverse_diagonal, alpha, p, q, x, r, rr, rz_new); break;
        case 3: update_iterate(n, 3, inverse_diagonal, alpha, p, q, x, r, rr, rz_new); break;
        default: update_iterate(n, m, inverse_diagonal, alpha, p, q, x, r, rr, rz_new); break;
        }
        all_done = 1;
        for (int32_t c = 0; c < m; ++c) {
            if (!(rr[c] > tolerance * tolerance * bnorm[c])) done[c] = 1;
            all_done = all_done && done[c];
            beta[c] = rz[c] > 0.0 ? rz_new[c] / rz[c] : 0.0;
            rz[c] = rz_new[c];
        }
        switch (m) {
        case 1: update_direction(n, 1, inverse_diagonal, beta, r, p); break;
        case 3: update_direction(n, 3, inverse_diagonal, beta, r, p); break;
        default: update_direction(n, m, inverse_diagonal, beta, r, p); break;
        }
    }
    result->iterations = it;
    result->relative_residual = 0.0;
    for (int32_t c = 0; c < m; ++c)
        if (bnorm[c] > 0.0) result->relative_residual = fmax(result->relative_residual, sqrt(rr[c] / bnorm[c]));
    if (all_done) return CF_OK;
    return cfi_error(ctx, CF_ERR_NOT_CONVERGED,
                     "conjugate gradients did not converge in %d iterations (residual %.3g of the right-hand side)", it,
                     result->relative_residual);
}
