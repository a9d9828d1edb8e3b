/*
 * Weighted inner products, modified Gram-Schmidt with one
 * reorthogonalisation pass ("twice is enough", Giraud et al. 2005) and
 * rank detection (blocked, with BLAS products, beyond 32 columns), and
 * projection onto the orthogonal complement of a small orthonormal basis.
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

/* Block width of the blocked form below: bases of at most this many
 * columns take the column-by-column loop alone. */
#define CFI_ORTHO_BLOCK 32

extern void dgemm_(const char *transa, const char *transb, const int *m, const int *n, const int *k,
                   const double *alpha, const double *a, const int *lda, const double *b, const int *ldb,
                   const double *beta, double *c, const int *ldc);

/* Columns [from, to) of basis (n rows) after the r columns kept so far:
 * each is orthogonalised twice (modified Gram-Schmidt) against the kept
 * columns from `first` on, dropped when what is left is below tol times
 * norm0[j - from] (its norm before any projection), else normalised and
 * packed at position r. Returns the new r. */
static int32_t orthonormalize_columns(int32_t n, double *basis, const double *w, double tol, int32_t first,
                                      int32_t r, int32_t from, int32_t to, const double *norm0)
{
    for (int32_t j = from; j < to; ++j) {
        double *v = basis + (size_t)j * n;
        double n0 = norm0 ? norm0[j - from] : sqrt(fmax(cf_dot(n, v, v, w), 0.0));
        double norm = n0;
        /* two passes of modified Gram-Schmidt against the kept columns */
        for (int pass = 0; pass < 2 && n0 > 0.0; ++pass) {
            for (int32_t i = first; i < r; ++i) {
                const double *b = basis + (size_t)i * n;
                double c = cf_dot(n, v, b, w);
                for (int32_t t = 0; t < n; ++t) v[t] -= c * b[t];
            }
            norm = sqrt(fmax(cf_dot(n, v, v, w), 0.0));
        }
        if (!(n0 > 0.0) || !isfinite(norm) || norm <= tol * n0 || norm == 0.0) continue; /* dependent: drop */
        double *dst = basis + (size_t)r * n;
        for (int32_t t = 0; t < n; ++t) dst[t] = v[t] / norm;
        ++r;
    }
    return r;
}

void cf_orthonormalize(int32_t n, int32_t k, double *basis, const double *w, double tol, int32_t *rank)
{
    int32_t r = 0;
    if (!basis || n <= 0 || k <= 0) {
        if (rank) *rank = 0;
        return;
    }
    if (!(tol >= 0.0)) tol = 0.0;
    int blocked = k > CFI_ORTHO_BLOCK;
    for (int32_t i = 0; w && blocked && i < n; ++i) blocked = w[i] > 0.0 && isfinite(w[i]);
    if (!blocked) {
        r = orthonormalize_columns(n, basis, w, tol, 0, 0, 0, k, NULL);
    } else {
        /* Larger bases block by block (block classical Gram-Schmidt twice,
         * each block then column by column): the projections on the kept
         * columns are matrix products (BLAS dgemm) that read the kept
         * columns once per block instead of twice per column. Column by
         * column, 300 columns of 40k rows (spin-willmore on a surface with
         * 100 holes) took 7 s of every step, memory bound. The weights go
         * into the columns as sqrt(w) for the products (w > 0 here; other
         * weights take the loop above) and out again at the end. */
        if (w)
            for (int32_t j = 0; j < k; ++j) {
                double *v = basis + (size_t)j * n;
                for (int32_t t = 0; t < n; ++t) v[t] *= sqrt(w[t]);
            }
        double norm0[CFI_ORTHO_BLOCK], c[CFI_ORTHO_BLOCK * CFI_ORTHO_BLOCK];
        const double one = 1.0, zero = 0.0, minus_one = -1.0;
        const int ld = n;
        for (int32_t j0 = 0; j0 < k; j0 += CFI_ORTHO_BLOCK) {
            int32_t bs = k - j0 < CFI_ORTHO_BLOCK ? k - j0 : CFI_ORTHO_BLOCK;
            double *block = basis + (size_t)j0 * n;
            for (int32_t t = 0; t < bs; ++t) {
                const double *v = block + (size_t)t * n;
                norm0[t] = sqrt(fmax(cf_dot(n, v, v, NULL), 0.0));
            }
            /* twice: block <- block - Q (Q^T block), Q the kept columns in
             * chunks of the block width (c stays small) */
            for (int pass = 0; pass < 2 && r > 0; ++pass)
                for (int32_t i0 = 0; i0 < r; i0 += CFI_ORTHO_BLOCK) {
                    int m = r - i0 < CFI_ORTHO_BLOCK ? r - i0 : CFI_ORTHO_BLOCK, nb = bs;
                    const double *q = basis + (size_t)i0 * n;
                    dgemm_("T", "N", &m, &nb, &ld, &one, q, &ld, block, &ld, &zero, c, &m);
                    dgemm_("N", "N", &ld, &nb, &m, &minus_one, q, &ld, c, &m, &one, block, &ld);
                }
            r = orthonormalize_columns(n, basis, NULL, tol, r, r, j0, j0 + bs, norm0);
        }
        if (w)
            for (int32_t j = 0; j < r; ++j) {
                double *v = basis + (size_t)j * n;
                for (int32_t t = 0; t < n; ++t) v[t] /= sqrt(w[t]);
            }
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
