/*
 * Smallest eigenpairs of A v = lambda M v (A symmetric positive
 * semi-definite, M diagonal positive) by inverse subspace iteration on a
 * factorisation of A + shift M, with M-orthonormalisation (Gram-Schmidt)
 * and a Rayleigh-Ritz step (Jacobi eigen-decomposition of the small
 * projected matrix) each iteration. The shift makes a singular A (a
 * Laplacian's constants) factorisable without changing the eigenvectors.
 * Also a single inverse-iteration step for callers that keep their own
 * factorisation.
 */
#include "linalg/linalg_internal.h"

#include <math.h>
#include <string.h>

void cf_eigen_options_default(cf_eigen_options *options)
{
    if (!options) return;
    options->max_iterations = 50;
    options->tolerance = 1e-10;
    options->shift = 0.0;
}

/* Jacobi eigen-decomposition of the symmetric k x k matrix h (column-major,
 * destroyed): eigenvalues ascending in lambda, eigenvectors in q. */
static void jacobi_eigen(int32_t k, double *h, double *q, double *lambda)
{
    for (int32_t i = 0; i < k * k; ++i) q[i] = 0.0;
    for (int32_t i = 0; i < k; ++i) q[i * k + i] = 1.0;
    for (int sweep = 0; sweep < 100; ++sweep) {
        double off = 0.0, diag = 0.0;
        for (int32_t j = 0; j < k; ++j)
            for (int32_t i = 0; i < k; ++i) {
                if (i != j) off += h[j * k + i] * h[j * k + i];
                else diag += h[j * k + i] * h[j * k + i];
            }
        if (off <= 1e-32 * diag || off == 0.0) break;
        for (int32_t p = 0; p < k; ++p)
            for (int32_t r = p + 1; r < k; ++r) {
                double apr = h[r * k + p];
                if (apr == 0.0) continue;
                double theta = (h[r * k + r] - h[p * k + p]) / (2.0 * apr);
                double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (int32_t i = 0; i < k; ++i) { /* columns p, r */
                    double hp = h[p * k + i], hr = h[r * k + i];
                    h[p * k + i] = c * hp - s * hr;
                    h[r * k + i] = s * hp + c * hr;
                }
                for (int32_t i = 0; i < k; ++i) { /* rows p, r */
                    double hp = h[i * k + p], hr = h[i * k + r];
                    h[i * k + p] = c * hp - s * hr;
                    h[i * k + r] = s * hp + c * hr;
                }
                for (int32_t i = 0; i < k; ++i) {
                    double qp = q[p * k + i], qr = q[r * k + i];
                    q[p * k + i] = c * qp - s * qr;
                    q[r * k + i] = s * qp + c * qr;
                }
            }
    }
    for (int32_t i = 0; i < k; ++i) lambda[i] = h[i * k + i];
    /* sort ascending (selection sort; k is small) */
    for (int32_t i = 0; i < k; ++i) {
        int32_t best = i;
        for (int32_t j = i + 1; j < k; ++j)
            if (lambda[j] < lambda[best]) best = j;
        if (best == i) continue;
        double t = lambda[i]; lambda[i] = lambda[best]; lambda[best] = t;
        for (int32_t r = 0; r < k; ++r) { t = q[i * k + r]; q[i * k + r] = q[best * k + r]; q[best * k + r] = t; }
    }
}

cf_status cf_inverse_iteration_step(cf_cholesky *chol, const double *m_diag, int32_t k, double *vectors, double *work,
                                    int32_t *rank)
{
    if (!chol) return CF_ERR_INVALID_ARG;
    int32_t n = cf_cholesky_size(chol);
    if (k < 1 || !vectors || !work)
        return cfi_error(cfi_cholesky_context(chol), CF_ERR_INVALID_ARG, "inverse iteration: k = %d, vectors or work NULL", k);
    /* work = M V, then V = (A + s M)^-1 M V */
    for (int32_t j = 0; j < k; ++j)
        for (int32_t i = 0; i < n; ++i)
            work[(size_t)j * n + i] = (m_diag ? m_diag[i] : 1.0) * vectors[(size_t)j * n + i];
    cf_status st = cf_cholesky_solve(chol, k, work, vectors);
    if (st != CF_OK) return st;
    int32_t r = 0;
    cf_orthonormalize(n, k, vectors, m_diag, 1e-12, &r);
    if (rank) *rank = r;
    return CF_OK;
}

double cf_rayleigh_quotient(const cf_sparse *a, const double *m_diag, const double *v, double *work)
{
    if (!a || !v || !work) return NAN;
    cf_sparse_multiply(a, v, work);
    double num = cf_dot(a->nrows, v, work, NULL), den = cf_dot(a->nrows, v, v, m_diag);
    return den > 0.0 ? num / den : NAN;
}

cf_status cf_smallest_eigenvectors(cf_context *ctx, const cf_sparse *a, const double *m_diag, cf_cholesky *chol,
                                   int32_t k, const cf_eigen_options *options, double *vectors, double *eigenvalues,
                                   int32_t *iterations)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!a || !vectors || !eigenvalues) return cfi_error(ctx, CF_ERR_INVALID_ARG, "eigenvectors: NULL argument");
    if (a->nrows != a->ncols) return cfi_error(ctx, CF_ERR_INVALID_ARG, "eigenvectors: A is %d x %d", a->nrows, a->ncols);
    int32_t n = a->nrows;
    if (k < 1 || k > n) return cfi_error(ctx, CF_ERR_INVALID_ARG, "eigenvectors: k = %d outside 1..%d", k, n);
    cf_eigen_options opt;
    cf_eigen_options_default(&opt);
    if (options) opt = *options;
    if (opt.max_iterations < 1 || !(opt.tolerance > 0.0) || !isfinite(opt.shift))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "eigenvectors: bad options (iterations %d, tolerance %g, shift %g)",
                         opt.max_iterations, opt.tolerance, opt.shift);
    if (chol && cf_cholesky_size(chol) != n)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "eigenvectors: factorisation is %d x %d, A is %d", cf_cholesky_size(chol),
                         cf_cholesky_size(chol), n);
    for (int32_t i = 0; m_diag && i < n; ++i)
        if (!(m_diag[i] > 0.0) || !isfinite(m_diag[i]))
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "eigenvectors: mass %d is %g, need positive", i, m_diag[i]);
    if (iterations) *iterations = 0;

    /* iterate on a block with a few extra columns: the k-th vector then
     * converges like ((lambda_k + s) / (lambda_{kb+1} + s))^it instead of
     * the ratio to lambda_{k+1} */
    int32_t kb = k + (k < 2 ? 2 : k);
    if (kb > n) kb = n;
    size_t nkb = (size_t)n * (size_t)kb;
    cf_status st = CF_OK;
    cf_cholesky *own = NULL;
    cf_sparse *shifted = NULL, *diag = NULL;
    double *v = CFI_ALLOC(ctx, double, nkb), *w = CFI_ALLOC(ctx, double, nkb), *av = CFI_ALLOC(ctx, double, nkb);
    double *h = CFI_ALLOC(ctx, double, (size_t)kb * kb), *q = CFI_ALLOC(ctx, double, (size_t)kb * kb);
    double *lam = CFI_ALLOC(ctx, double, (size_t)kb);
    if (!v || !w || !av || !h || !q || !lam) { st = CF_ERR_NOMEM; goto done; }

    if (!chol) {
        /* factorise A + shift M (shift M added as a diagonal matrix: the
         * pattern of A need not contain the diagonal) */
        const cf_sparse *target = a;
        if (opt.shift != 0.0) {
            int32_t *idx = CFI_ALLOC(ctx, int32_t, (size_t)n);
            double *dv = CFI_ALLOC(ctx, double, (size_t)n);
            if (idx && dv) {
                for (int32_t i = 0; i < n; ++i) { idx[i] = i; dv[i] = opt.shift * (m_diag ? m_diag[i] : 1.0); }
                st = cf_sparse_from_triplets(ctx, n, n, n, idx, idx, dv, 1, &diag, NULL);
                if (st == CF_OK) diag->upper_only = a->upper_only;
                if (st == CF_OK) st = cf_sparse_add(ctx, 1.0, a, 1.0, diag, &shifted);
            } else {
                st = CF_ERR_NOMEM;
            }
            CFI_FREE(ctx, idx, n);
            CFI_FREE(ctx, dv, n);
            if (st != CF_OK) goto done;
            target = shifted;
        }
        if ((st = cf_cholesky_create(ctx, target, NULL, &own)) != CF_OK) goto done;
        if ((st = cf_cholesky_factorize(own, target)) != CF_OK) goto done;
        chol = own;
    }

    /* start: the caller's vectors, completed (or replaced when zero) by a
     * deterministic pseudo-random block */
    uint64_t seed = 0x243F6A8885A308D3ull;
    for (size_t t = 0; t < nkb; ++t) {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        v[t] = (double)(seed >> 11) / 9007199254740992.0 - 0.5;
    }
    int any = 0;
    for (size_t t = 0; t < (size_t)n * k; ++t) any |= vectors[t] != 0.0;
    if (any) memcpy(v, vectors, (size_t)n * k * sizeof *v);
    int32_t rank = 0;
    cf_orthonormalize(n, kb, v, m_diag, 1e-12, &rank);
    if (rank < kb) {
        st = cfi_error(ctx, CF_ERR_NUMERICAL, "eigenvectors: starting block has rank %d < %d", rank, kb);
        goto done;
    }
    /* scale of M^-1 A for the stopping test: Gershgorin bound of its spectrum */
    double scale = 0.0;
    {
        double *rowsum = w; /* borrow */
        memset(rowsum, 0, (size_t)n * sizeof *rowsum);
        for (int32_t j = 0; j < n; ++j)
            for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) {
                rowsum[a->rowind[p]] += fabs(a->values[p]);
                if (a->upper_only && a->rowind[p] != j) rowsum[j] += fabs(a->values[p]);
            }
        for (int32_t i = 0; i < n; ++i) scale = fmax(scale, rowsum[i] / (m_diag ? m_diag[i] : 1.0));
        if (scale == 0.0) scale = 1.0;
    }
    int32_t it = 0;
    int converged = 0;
    while (it < opt.max_iterations && !converged) {
        ++it;
        if ((st = cf_inverse_iteration_step(chol, m_diag, kb, v, w, &rank)) != CF_OK) goto done;
        if (rank < kb) {
            st = cfi_error(ctx, CF_ERR_NUMERICAL, "eigenvectors: iteration %d lost rank (%d < %d)", it, rank, kb);
            goto done;
        }
        /* Rayleigh-Ritz: H = V^T A V (V is M-orthonormal), V <- V Q */
        for (int32_t j = 0; j < kb; ++j) cf_sparse_multiply(a, v + (size_t)j * n, av + (size_t)j * n);
        for (int32_t j = 0; j < kb; ++j)
            for (int32_t i = 0; i <= j; ++i)
                h[j * kb + i] = h[i * kb + j] = 0.5 * (cf_dot(n, v + (size_t)i * n, av + (size_t)j * n, NULL) +
                                                       cf_dot(n, v + (size_t)j * n, av + (size_t)i * n, NULL));
        jacobi_eigen(kb, h, q, lam);
        memset(w, 0, nkb * sizeof *w);
        for (int32_t j = 0; j < kb; ++j)
            for (int32_t l = 0; l < kb; ++l) {
                double c = q[j * kb + l];
                const double *src = v + (size_t)l * n;
                double *dst = w + (size_t)j * n;
                for (int32_t i = 0; i < n; ++i) dst[i] += c * src[i];
            }
        memcpy(v, w, nkb * sizeof *v);
        /* residual |A v - lambda M v|_{M^-1} of the k wanted pairs */
        converged = 1;
        for (int32_t j = 0; j < k && converged; ++j) {
            const double *vj = v + (size_t)j * n;
            cf_sparse_multiply(a, vj, av);
            double r2 = 0.0;
            for (int32_t i = 0; i < n; ++i) {
                double mi = m_diag ? m_diag[i] : 1.0;
                double ri = av[i] - lam[j] * mi * vj[i];
                r2 += ri * ri / mi;
            }
            if (sqrt(r2) > opt.tolerance * scale) converged = 0;
        }
    }
    memcpy(vectors, v, (size_t)n * k * sizeof *v);
    memcpy(eigenvalues, lam, (size_t)k * sizeof *lam);
    if (iterations) *iterations = it;
    if (!converged)
        st = cfi_error(ctx, CF_ERR_NOT_CONVERGED, "eigenvectors: residual above %g after %d iterations", opt.tolerance, it);
done:
    cf_cholesky_destroy(&own);
    cf_sparse_destroy(&shifted);
    cf_sparse_destroy(&diag);
    CFI_FREE(ctx, v, nkb);
    CFI_FREE(ctx, w, nkb);
    CFI_FREE(ctx, av, nkb);
    CFI_FREE(ctx, h, (size_t)kb * kb);
    CFI_FREE(ctx, q, (size_t)kb * kb);
    CFI_FREE(ctx, lam, kb);
    return st;
}

/* Single-vector inverse power iteration with one mass per block of
 * block_size entries (moved here from spin_willmore, issue 12): the
 * block's squared norm is summed first and then weighted, the order the
 * spin flow has always used, so its results are unchanged bit for bit. */
cf_status cf_inverse_iteration_blocks(cf_cholesky *chol, const double *m_diag, int32_t block_size, int32_t iterations,
                                      double norm2, double *v, double *work)
{
    if (!chol) return CF_ERR_INVALID_ARG;
    cf_context *ctx = cfi_cholesky_context(chol);
    int32_t n = cf_cholesky_size(chol);
    if (!m_diag || !v || !work || block_size < 1 || n % block_size != 0 || iterations < 0 || !(norm2 > 0.0) ||
        !isfinite(norm2))
        return cfi_error(ctx, CF_ERR_INVALID_ARG,
                         "inverse iteration (blocks): block size %d for n = %d, %d iterations, norm2 %g, or a NULL array",
                         block_size, n, iterations, norm2);
    int32_t nb = n / block_size;
    for (int32_t it = 0; it < iterations; ++it) {
        for (int32_t i = 0; i < nb; ++i)
            for (int32_t c = 0; c < block_size; ++c)
                work[(int64_t)block_size * i + c] = m_diag[i] * v[(int64_t)block_size * i + c];
        cf_status st = cf_cholesky_solve(chol, 1, work, v);
        if (st != CF_OK) return st;
        double n2 = cf_normalize_blocks(nb, m_diag, block_size, norm2, v);
        if (!(n2 > 0.0) || !isfinite(n2))
            return cfi_error(ctx, CF_ERR_NUMERICAL, "inverse iteration (blocks): the iterate's M-norm is %g", n2);
    }
    return CF_OK;
}

double cf_normalize_blocks(int32_t nb, const double *m_diag, int32_t block_size, double norm2, double *v)
{
    double n2 = 0.0;
    for (int32_t i = 0; i < nb; ++i) {
        const double *vi = v + (int64_t)block_size * i;
        double q = 0.0;
        for (int32_t c = 0; c < block_size; ++c) q += vi[c] * vi[c];
        n2 += m_diag[i] * q;
    }
    if (!(n2 > 0.0) || !isfinite(n2)) return n2;
    double s = sqrt(norm2 / n2);
    for (int64_t i = 0; i < (int64_t)nb * block_size; ++i) v[i] *= s;
    return n2;
}

double cf_rayleigh_quotient_blocks(const cf_sparse *a, const double *m_diag, int32_t block_size, const double *v,
                                   double *work)
{
    if (!a || !m_diag || !v || !work || block_size < 1 || a->nrows != a->ncols || a->nrows % block_size != 0)
        return NAN;
    cf_sparse_multiply(a, v, work);
    int32_t nb = a->nrows / block_size;
    double num = 0.0, den = 0.0;
    for (int32_t i = 0; i < nb; ++i)
        for (int32_t c = 0; c < block_size; ++c) {
            int64_t k = (int64_t)block_size * i + c;
            num += v[k] * work[k];
            den += m_diag[i] * v[k] * v[k];
        }
    return den > 0.0 ? num / den : NAN;
}
