/*
 * Small dense least squares through LAPACK (dgelss, from the OpenBLAS /
 * LAPACK that CHOLMOD links anyway): the few-by-few systems of the methods,
 * e.g. spin-willmore's Newton correction of the periods (3 x 2g unknowns).
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
