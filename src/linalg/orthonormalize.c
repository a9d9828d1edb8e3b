/*
 * Weighted inner products, modified Gram-Schmidt with one
 * reorthogonalisation pass ("twice is enough", Giraud et al. 2005) and
 * rank detection, and projection onto the orthogonal complement of a small
 * orthonormal basis.
 */
#include "linalg/linalg_internal.h"

#include <math.h>
#include <string.h>

double cf_dot(int32_t n, const double *a, const double *b, const double *w)
{
    if (!a || !b || n <= 0) return 0.0;
    double s = 0.0;
    if (w)
        for (int32_t i = 0; i < n; ++i) s += w[i] * a[i] * b[i];
    else
        for (int32_t i = 0; i < n; ++i) s += a[i] * b[i];
    return s;
}

void cf_orthonormalize(int32_t n, int32_t k, double *basis, const double *w, double tol, int32_t *rank)
{
    int32_t r = 0;
    if (!basis || n <= 0 || k <= 0) {
        if (rank) *rank = 0;
        return;
    }
    if (!(tol >= 0.0)) tol = 0.0;
    for (int32_t j = 0; j < k; ++j) {
        double *v = basis + (size_t)j * n;
        double norm0 = sqrt(fmax(cf_dot(n, v, v, w), 0.0));
        double norm = norm0;
        /* two passes of modified Gram-Schmidt against the kept columns */
        for (int pass = 0; pass < 2 && norm0 > 0.0; ++pass) {
            for (int32_t i = 0; i < r; ++i) {
                const double *b = basis + (size_t)i * n;
                double c = cf_dot(n, v, b, w);
                for (int32_t t = 0; t < n; ++t) v[t] -= c * b[t];
            }
            norm = sqrt(fmax(cf_dot(n, v, v, w), 0.0));
        }
        if (!(norm0 > 0.0) || !isfinite(norm) || norm <= tol * norm0 || norm == 0.0) continue; /* dependent: drop */
        double *dst = basis + (size_t)r * n;
        for (int32_t t = 0; t < n; ++t) dst[t] = v[t] / norm;
        ++r;
    }
    /* dropped columns leave zeros behind the packed basis */
    if (r < k) memset(basis + (size_t)r * n, 0, (size_t)(k - r) * (size_t)n * sizeof *basis);
    if (rank) *rank = r;
}

void cf_project_out(int32_t n, int32_t k, const double *basis, const double *w, double *v)
{
    if (!basis || !v || n <= 0) return;
    for (int32_t i = 0; i < k; ++i) {
        const double *b = basis + (size_t)i * n;
        double c = cf_dot(n, v, b, w);
        for (int32_t t = 0; t < n; ++t) v[t] -= c * b[t];
    }
}
