/*
 * Small dense least squares (dgelss) and symmetric-definite eigenvalues
 * (dsygv) through LAPACK (from the OpenBLAS / LAPACK that CHOLMOD links
 * anyway): the few-by-few systems of the methods, e.g. spin-willmore's
 * Newton correction of the periods (3 x 2g unknowns), and the conformal
 * class's 2g x 2g period matrices.
 */
#include "linalg/linalg_internal.h"

#include <math.h>

extern void dgelss_(const int *m, const int *n, const int *nrhs, double *a, const int *lda, double *b,
                    const int *ldb, double *s, const double *rcond, int *rank, double *work, const int *lwork,
                    int *info);

/* dgelss's minimal workspace, 3 min + max(2 min, max(m, n), nrhs), plus the
 * min(m, n) singular values. */
int64_t cf_dense_least_squares_work_size(int32_t m, int32_t n)
{
    if (m <= 0 || n <= 0) return 0;
    int64_t mn = m < n ? m : n, mx = m > n ? m : n;
    int64_t tail = 2 * mn > mx ? 2 * mn : mx;
    return mn + 3 * mn + tail + 1;
}

cf_status cf_dense_least_squares(int32_t m, int32_t n, double *a, double *b, double rcond, double *work,
                                 int64_t work_size, int32_t *rank)
{
    if (rank) *rank = 0;
    if (m <= 0 || n <= 0 || !a || !b || !work) return CF_ERR_INVALID_ARG;
    int64_t need = cf_dense_least_squares_work_size(m, n);
    if (work_size < need || need > INT32_MAX) return CF_ERR_INVALID_ARG;
    for (int64_t k = 0; k < (int64_t)m * n; ++k)
        if (!isfinite(a[k])) return CF_ERR_NONFINITE;
    for (int32_t k = 0; k < m; ++k)
        if (!isfinite(b[k])) return CF_ERR_NONFINITE;
    int mn = m < n ? m : n;
    int im = m, in = n, nrhs = 1, lda = m, ldb = m > n ? m : n, r = 0, info = 0;
    int lwork = (int)(need - mn);
    dgelss_(&im, &in, &nrhs, a, &lda, b, &ldb, work, &rcond, &r, work + mn, &lwork, &info);
    if (info < 0) return CF_ERR_INVALID_ARG;
    if (info > 0) return CF_ERR_NUMERICAL;
    if (rank) *rank = r;
    return CF_OK;
}

extern void dsygv_(const int *itype, const char *jobz, const char *uplo, const int *n, double *a, const int *lda,
                   double *b, const int *ldb, double *w, double *work, const int *lwork, int *info);

/* dsygv's minimal workspace without vectors, 3 n - 1 (at least 1). */
int64_t cf_dense_generalized_eigenvalues_work_size(int32_t n) { return n > 0 ? 3 * (int64_t)n : 0; }

cf_status cf_dense_generalized_eigenvalues(int32_t n, double *a, double *b, double *eigenvalues, double *work,
                                           int64_t work_size)
{
    if (n <= 0 || !a || !b || !eigenvalues || !work) return CF_ERR_INVALID_ARG;
    int64_t need = cf_dense_generalized_eigenvalues_work_size(n);
    if (work_size < need || need > INT32_MAX) return CF_ERR_INVALID_ARG;
    for (int64_t k = 0; k < (int64_t)n * n; ++k)
        if (!isfinite(a[k]) || !isfinite(b[k])) return CF_ERR_NONFINITE;
    int itype = 1, in = n, lda = n, lwork = (int)need, info = 0;
    dsygv_(&itype, "N", "L", &in, a, &lda, b, &lda, eigenvalues, work, &lwork, &info);
    if (info < 0) return CF_ERR_INVALID_ARG;
    if (info > n) return CF_ERR_NOT_POSDEF;
    if (info > 0) return CF_ERR_NUMERICAL;
    return CF_OK;
}
