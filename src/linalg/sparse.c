/*
 * Compressed-column sparse matrices: one-pass assembly from triplets (two
 * stable counting sorts, by row then by column, so rows come out sorted in
 * every column without a comparison sort; duplicates summed; slot map for
 * refilling), refill, products with vectors, Kronecker lifting to blocks,
 * sum, transpose, sparse product, lookup.
 */
#include "linalg/linalg_internal.h"

#include <math.h>
#include <string.h>

cf_status cfi_sparse_alloc(cf_context *ctx, int32_t nrows, int32_t ncols, int64_t nnz, cf_sparse **out)
{
    *out = NULL;
    if (nnz < 0 || nnz > INT32_MAX)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "sparse matrix %d x %d: %lld nonzeros exceed the int32 index range",
                         nrows, ncols, (long long)nnz);
    cf_sparse *a = CFI_ALLOC(ctx, cf_sparse, 1);
    if (!a) return CF_ERR_NOMEM;
    a->ctx = ctx;
    a->nrows = nrows;
    a->ncols = ncols;
    a->colptr = CFI_ALLOC(ctx, int32_t, (size_t)ncols + 1);
    a->rowind = CFI_ALLOC(ctx, int32_t, (size_t)nnz);
    a->values = CFI_ALLOC(ctx, double, (size_t)nnz);
    if (!a->colptr || !a->rowind || !a->values) {
        CFI_FREE(ctx, a->colptr, (size_t)ncols + 1);
        CFI_FREE(ctx, a->rowind, (size_t)nnz);
        CFI_FREE(ctx, a->values, (size_t)nnz);
        CFI_FREE(ctx, a, 1);
        return CF_ERR_NOMEM;
    }
    /* colptr[ncols] always holds the capacity, so destroy frees the right
     * byte count even if the caller fails before filling the columns */
    a->colptr[ncols] = (int32_t)nnz;
    *out = a;
    return CF_OK;
}

void cf_sparse_destroy(cf_sparse **pa)
{
    if (!pa || !*pa) return;
    cf_sparse *a = *pa;
    cf_context *ctx = a->ctx;
    size_t nnz = a->colptr ? (size_t)a->colptr[a->ncols] : 0;
    /* rowind/values were allocated with the capacity given at creation,
     * which equals colptr[ncols] for every matrix this file returns */
    CFI_FREE(ctx, a->rowind, nnz);
    CFI_FREE(ctx, a->values, nnz);
    CFI_FREE(ctx, a->colptr, (size_t)a->ncols + 1);
    CFI_FREE(ctx, a, 1);
    *pa = NULL;
}

int64_t cf_sparse_nnz(const cf_sparse *a) { return a ? (int64_t)a->colptr[a->ncols] : 0; }

cf_status cf_sparse_from_triplets(cf_context *ctx, int32_t nrows, int32_t ncols, int64_t n, const int32_t *rows,
                                  const int32_t *cols, const double *vals, int32_t symmetric, cf_sparse **out,
                                  int64_t *slot_map)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "sparse from triplets: out is NULL");
    *out = NULL;
    if (nrows < 0 || ncols < 0 || n < 0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "sparse from triplets: negative size (%d x %d, %lld triplets)",
                         nrows, ncols, (long long)n);
    if (n > 0 && (!rows || !cols)) return cfi_error(ctx, CF_ERR_INVALID_ARG, "sparse from triplets: rows or cols NULL");
    if (symmetric && nrows != ncols)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "sparse from triplets: symmetric matrix must be square (%d x %d)",
                         nrows, ncols);
    if ((uint64_t)n > SIZE_MAX / (2 * sizeof(int64_t)))
        return cfi_error(ctx, CF_ERR_NOMEM, "sparse from triplets: %lld triplets overflow memory size", (long long)n);
    for (int64_t k = 0; k < n; ++k) {
        if (rows[k] < 0 || rows[k] >= nrows || cols[k] < 0 || cols[k] >= ncols)
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "triplet %lld: index (%d, %d) outside %d x %d", (long long)k,
                             rows[k], cols[k], nrows, ncols);
        if (vals && !isfinite(vals[k]))
            return cfi_error(ctx, CF_ERR_NONFINITE, "triplet %lld: non-finite value at (%d, %d)", (long long)k,
                             rows[k], cols[k]);
    }

    cf_status st = CF_OK;
    int64_t *start = CFI_ALLOC(ctx, int64_t, (size_t)(nrows > ncols ? nrows : ncols) + 1);
    int64_t *byrow = CFI_ALLOC(ctx, int64_t, (size_t)n);
    int64_t *bycol = CFI_ALLOC(ctx, int64_t, (size_t)n);
    int64_t *slots = slot_map ? slot_map : CFI_ALLOC(ctx, int64_t, (size_t)n);
    cf_sparse *a = NULL;
    if (!start || !byrow || !bycol || !slots) {
        st = CF_ERR_NOMEM;
        goto done;
    }

    /* stable counting sort of the triplets by row */
    for (int64_t k = 0; k < n; ++k) start[rows[k] + 1]++;
    for (int32_t i = 0; i < nrows; ++i) start[i + 1] += start[i];
    for (int64_t k = 0; k < n; ++k) byrow[start[rows[k]]++] = k;

    /* then by column: visiting in row order leaves rows sorted in each column */
    memset(start, 0, ((size_t)ncols + 1) * sizeof *start);
    for (int64_t k = 0; k < n; ++k) start[cols[k] + 1]++;
    for (int32_t j = 0; j < ncols; ++j) start[j + 1] += start[j];
    for (int64_t t = 0; t < n; ++t) {
        int64_t k = byrow[t];
        bycol[start[cols[k]]++] = k;
    }
    /* start[j] is now the end of column j's bucket */

    /* number the distinct (row, column) pairs: duplicates are adjacent */
    int64_t nnz = 0;
    {
        int64_t t = 0;
        for (int32_t j = 0; j < ncols; ++j) {
            int32_t prev = -1;
            for (; t < start[j]; ++t) {
                int64_t k = bycol[t];
                if (rows[k] != prev) {
                    prev = rows[k];
                    ++nnz;
                }
                slots[k] = nnz - 1;
            }
        }
    }
    st = cfi_sparse_alloc(ctx, nrows, ncols, nnz, &a);
    if (st != CF_OK) goto done;
    {
        int64_t t = 0, e = -1;
        for (int32_t j = 0; j < ncols; ++j) {
            for (; t < start[j]; ++t) {
                int64_t k = bycol[t];
                if (slots[k] != e) {
                    e = slots[k];
                    a->rowind[e] = rows[k];
                }
                if (vals) a->values[e] += vals[k];
            }
            a->colptr[j + 1] = (int32_t)(e + 1);
        }
    }
    a->symmetric = symmetric != 0;
    a->upper_only = 0;
    *out = a;

done:
    if (!slot_map) CFI_FREE(ctx, slots, n);
    CFI_FREE(ctx, bycol, n);
    CFI_FREE(ctx, byrow, n);
    CFI_FREE(ctx, start, (size_t)(nrows > ncols ? nrows : ncols) + 1);
    return st;
}

void cf_sparse_refill(cf_sparse *a, int64_t n, const int64_t *slot_map, const double *vals)
{
    if (!a || !slot_map || !vals || n < 0) return;
    int64_t nnz = a->colptr[a->ncols];
    memset(a->values, 0, (size_t)nnz * sizeof *a->values);
    for (int64_t k = 0; k < n; ++k) {
        int64_t s = slot_map[k];
        if (s >= 0 && s < nnz) a->values[s] += vals[k];
    }
}

void cf_sparse_multiply_add(const cf_sparse *a, double alpha, const double *x, double beta, double *y)
{
    if (!a || !x || !y) return;
    if (beta == 0.0) memset(y, 0, (size_t)a->nrows * sizeof *y);
    else if (beta != 1.0)
        for (int32_t i = 0; i < a->nrows; ++i) y[i] *= beta;
    for (int32_t j = 0; j < a->ncols; ++j) {
        double xj = alpha * x[j];
        double acc = 0.0;
        for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) {
            int32_t i = a->rowind[p];
            y[i] += a->values[p] * xj;
            /* mirrored strictly-lower entry (j, i) of an upper-only matrix */
            if (a->upper_only && i < j) acc += a->values[p] * x[i];
        }
        if (a->upper_only) y[j] += alpha * acc;
    }
}

void cf_sparse_multiply(const cf_sparse *a, const double *x, double *y) { cf_sparse_multiply_add(a, 1.0, x, 0.0, y); }

void cf_sparse_multiply_zero_row_sums(const cf_sparse *a, const double *x, double *y)
{
    if (!a || !x || !y) return;
    memset(y, 0, (size_t)a->nrows * sizeof *y);
    for (int32_t j = 0; j < a->ncols; ++j)
        for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) {
            int32_t i = a->rowind[p];
            if (i == j) continue;
            y[i] += a->values[p] * (x[j] - x[i]);
            /* mirrored strictly-lower entry (j, i) of an upper-only matrix */
            if (a->upper_only && i < j) y[j] += a->values[p] * (x[i] - x[j]);
        }
}

cf_status cf_sparse_kron_identity(cf_context *ctx, const cf_sparse *a, int32_t b, cf_sparse **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!a || !out || b < 1) return cfi_error(ctx, CF_ERR_INVALID_ARG, "kron identity: NULL matrix or block size %d", b);
    *out = NULL;
    int64_t nnz = a->colptr[a->ncols];
    if ((int64_t)a->nrows * b > INT32_MAX || (int64_t)a->ncols * b > INT32_MAX || nnz * b > INT32_MAX)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "kron identity: %d x %d matrix times block %d exceeds int32 indices",
                         a->nrows, a->ncols, b);
    cf_sparse *c = NULL;
    cf_status st = cfi_sparse_alloc(ctx, a->nrows * b, a->ncols * b, nnz * b, &c);
    if (st != CF_OK) return st;
    int32_t e = 0;
    for (int32_t j = 0; j < a->ncols; ++j) {
        for (int32_t d = 0; d < b; ++d) {
            for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) {
                c->rowind[e] = b * a->rowind[p] + d;
                c->values[e++] = a->values[p];
            }
            c->colptr[b * j + d + 1] = e;
        }
    }
    c->symmetric = a->symmetric;
    c->upper_only = a->upper_only;
    *out = c;
    return CF_OK;
}

cf_status cf_sparse_kron_dense(cf_context *ctx, const cf_sparse *a, int32_t b, cf_sparse **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!a || !out || b < 1) return cfi_error(ctx, CF_ERR_INVALID_ARG, "kron dense: NULL matrix or block size %d", b);
    *out = NULL;
    if (a->upper_only)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "kron dense: the matrix stores its upper triangle only");
    int64_t nnz = a->colptr[a->ncols];
    if ((int64_t)a->nrows * b > INT32_MAX || (int64_t)a->ncols * b > INT32_MAX || nnz * b * b > INT32_MAX)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "kron dense: %d x %d matrix with %lld entries times %d x %d blocks "
                         "exceeds int32 indices", a->nrows, a->ncols, (long long)nnz, b, b);
    cf_sparse *c = NULL;
    cf_status st = cfi_sparse_alloc(ctx, a->nrows * b, a->ncols * b, nnz * b * b, &c);
    if (st != CF_OK) return st;
    /* column b j + d holds, for every entry (i, j) of a in row order, the
     * rows b i .. b i + b - 1: rows stay sorted and unique */
    int32_t e = 0;
    for (int32_t j = 0; j < a->ncols; ++j) {
        for (int32_t d = 0; d < b; ++d) {
            for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p)
                for (int32_t r = 0; r < b; ++r) {
                    c->rowind[e] = b * a->rowind[p] + r;
                    c->values[e++] = a->values[p];
                }
            c->colptr[b * j + d + 1] = e;
        }
    }
    c->symmetric = a->symmetric;
    c->upper_only = 0;
    *out = c;
    return CF_OK;
}

cf_status cf_sparse_add(cf_context *ctx, double alpha, const cf_sparse *a, double beta, const cf_sparse *b,
                        cf_sparse **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!a || !b || !out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "sparse add: NULL argument");
    *out = NULL;
    if (a->nrows != b->nrows || a->ncols != b->ncols)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "sparse add: shapes %d x %d and %d x %d differ", a->nrows, a->ncols,
                         b->nrows, b->ncols);
    if (a->upper_only != b->upper_only)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "sparse add: one operand stores the upper triangle only");
    if (!isfinite(alpha) || !isfinite(beta)) return cfi_error(ctx, CF_ERR_NONFINITE, "sparse add: non-finite scale");
    /* merged pattern size: count first so the result is allocated exactly */
    int64_t nnz = 0;
    for (int32_t j = 0; j < a->ncols; ++j) {
        int32_t p = a->colptr[j], q = b->colptr[j];
        while (p < a->colptr[j + 1] || q < b->colptr[j + 1]) {
            if (q >= b->colptr[j + 1] || (p < a->colptr[j + 1] && a->rowind[p] < b->rowind[q])) ++p;
            else if (p >= a->colptr[j + 1] || b->rowind[q] < a->rowind[p]) ++q;
            else { ++p; ++q; }
            ++nnz;
        }
    }
    cf_sparse *c = NULL;
    cf_status st = cfi_sparse_alloc(ctx, a->nrows, a->ncols, nnz, &c);
    if (st != CF_OK) return st;
    int32_t e = 0;
    for (int32_t j = 0; j < a->ncols; ++j) {
        int32_t p = a->colptr[j], q = b->colptr[j];
        while (p < a->colptr[j + 1] || q < b->colptr[j + 1]) {
            if (q >= b->colptr[j + 1] || (p < a->colptr[j + 1] && a->rowind[p] < b->rowind[q])) {
                c->rowind[e] = a->rowind[p];
                c->values[e] = alpha * a->values[p++];
            } else if (p >= a->colptr[j + 1] || b->rowind[q] < a->rowind[p]) {
                c->rowind[e] = b->rowind[q];
                c->values[e] = beta * b->values[q++];
            } else {
                c->rowind[e] = a->rowind[p];
                c->values[e] = alpha * a->values[p++] + beta * b->values[q++];
            }
            ++e;
        }
        c->colptr[j + 1] = e;
    }
    c->symmetric = a->symmetric && b->symmetric;
    c->upper_only = a->upper_only;
    *out = c;
    return CF_OK;
}

/* Transpose of any column-compressed array triple (rows may be unsorted on
 * input; the counting sort returns them sorted). */
static void transpose_into(const cf_sparse *a, cf_sparse *t)
{
    int32_t *next = t->colptr; /* use colptr as cursor, then shift back */
    memset(next, 0, ((size_t)a->nrows + 1) * sizeof *next);
    int32_t nnz = a->colptr[a->ncols];
    for (int32_t p = 0; p < nnz; ++p) next[a->rowind[p] + 1]++;
    for (int32_t i = 0; i < a->nrows; ++i) next[i + 1] += next[i];
    for (int32_t j = 0; j < a->ncols; ++j)
        for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) {
            int32_t q = next[a->rowind[p]]++;
            t->rowind[q] = j;
            t->values[q] = a->values[p];
        }
    for (int32_t i = a->nrows; i > 0; --i) next[i] = next[i - 1];
    next[0] = 0;
}

cf_status cfi_sparse_copy(cf_context *ctx, const cf_sparse *a, cf_sparse **out)
{
    *out = NULL;
    cf_sparse *c = NULL;
    int64_t nnz = a->colptr[a->ncols];
    if (!a->upper_only) {
        cf_status st = cfi_sparse_alloc(ctx, a->nrows, a->ncols, nnz, &c);
        if (st != CF_OK) return st;
        memcpy(c->colptr, a->colptr, ((size_t)a->ncols + 1) * sizeof *c->colptr);
        memcpy(c->rowind, a->rowind, (size_t)nnz * sizeof *c->rowind);
        memcpy(c->values, a->values, (size_t)nnz * sizeof *c->values);
        c->symmetric = a->symmetric;
        *out = c;
        return CF_OK;
    }
    /* full symmetric matrix from the upper triangle: U + strict_upper(U)^T */
    int64_t diag = 0;
    for (int32_t j = 0; j < a->ncols; ++j)
        for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) diag += a->rowind[p] == j;
    int64_t full = 2 * nnz - diag;
    int64_t ntrip = full;
    int32_t *ti = CFI_ALLOC(ctx, int32_t, (size_t)ntrip);
    int32_t *tj = CFI_ALLOC(ctx, int32_t, (size_t)ntrip);
    double *tv = CFI_ALLOC(ctx, double, (size_t)ntrip);
    cf_status st = CF_ERR_NOMEM;
    if (ti && tj && tv) {
        int64_t k = 0;
        for (int32_t j = 0; j < a->ncols; ++j)
            for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) {
                int32_t i = a->rowind[p];
                if (i > j) continue; /* ignore anything below the diagonal */
                ti[k] = i; tj[k] = j; tv[k++] = a->values[p];
                if (i != j) { ti[k] = j; tj[k] = i; tv[k++] = a->values[p]; }
            }
        st = cf_sparse_from_triplets(ctx, a->nrows, a->ncols, k, ti, tj, tv, 1, &c, NULL);
    }
    CFI_FREE(ctx, ti, ntrip);
    CFI_FREE(ctx, tj, ntrip);
    CFI_FREE(ctx, tv, ntrip);
    if (st == CF_OK) *out = c;
    return st;
}

cf_status cf_sparse_transpose(cf_context *ctx, const cf_sparse *a, cf_sparse **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!a || !out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "sparse transpose: NULL argument");
    *out = NULL;
    /* an upper-only matrix stands for a symmetric one: its transpose is itself */
    if (a->upper_only) {
        cf_sparse *c = NULL;
        int64_t nnz = a->colptr[a->ncols];
        cf_status st = cfi_sparse_alloc(ctx, a->nrows, a->ncols, nnz, &c);
        if (st != CF_OK) return st;
        memcpy(c->colptr, a->colptr, ((size_t)a->ncols + 1) * sizeof *c->colptr);
        memcpy(c->rowind, a->rowind, (size_t)nnz * sizeof *c->rowind);
        memcpy(c->values, a->values, (size_t)nnz * sizeof *c->values);
        c->symmetric = a->symmetric;
        c->upper_only = 1;
        *out = c;
        return CF_OK;
    }
    cf_sparse *t = NULL;
    cf_status st = cfi_sparse_alloc(ctx, a->ncols, a->nrows, a->colptr[a->ncols], &t);
    if (st != CF_OK) return st;
    transpose_into(a, t);
    t->symmetric = a->symmetric;
    *out = t;
    return CF_OK;
}

cf_status cf_sparse_product(cf_context *ctx, const cf_sparse *a, const cf_sparse *b, cf_sparse **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!a || !b || !out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "sparse product: NULL argument");
    *out = NULL;
    if (a->ncols != b->nrows)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "sparse product: inner sizes differ (%d x %d times %d x %d)",
                         a->nrows, a->ncols, b->nrows, b->ncols);
    cf_status st = CF_OK;
    cf_sparse *afull = NULL, *bfull = NULL, *c = NULL, *ct = NULL;
    int32_t *mark = NULL;
    double *acc = NULL;
    if (a->upper_only && (st = cfi_sparse_copy(ctx, a, &afull)) != CF_OK) goto done;
    if (b->upper_only && (st = cfi_sparse_copy(ctx, b, &bfull)) != CF_OK) goto done;
    const cf_sparse *A = afull ? afull : a, *B = bfull ? bfull : b;
    mark = CFI_ALLOC(ctx, int32_t, (size_t)A->nrows);
    acc = CFI_ALLOC(ctx, double, (size_t)A->nrows);
    if (!mark || !acc) { st = CF_ERR_NOMEM; goto done; }
    /* symbolic pass (Gustavson): count entries of each column of C */
    int64_t nnz = 0;
    for (int32_t i = 0; i < A->nrows; ++i) mark[i] = -1;
    for (int32_t j = 0; j < B->ncols; ++j)
        for (int32_t q = B->colptr[j]; q < B->colptr[j + 1]; ++q) {
            int32_t k = B->rowind[q];
            for (int32_t p = A->colptr[k]; p < A->colptr[k + 1]; ++p)
                if (mark[A->rowind[p]] != j) { mark[A->rowind[p]] = j; ++nnz; }
        }
    if ((st = cfi_sparse_alloc(ctx, A->nrows, B->ncols, nnz, &c)) != CF_OK) goto done;
    /* numeric pass: rows land unsorted; two transposes sort them */
    for (int32_t i = 0; i < A->nrows; ++i) mark[i] = -1;
    int32_t e = 0;
    for (int32_t j = 0; j < B->ncols; ++j) {
        int32_t begin = e;
        for (int32_t q = B->colptr[j]; q < B->colptr[j + 1]; ++q) {
            int32_t k = B->rowind[q];
            double bkj = B->values[q];
            for (int32_t p = A->colptr[k]; p < A->colptr[k + 1]; ++p) {
                int32_t i = A->rowind[p];
                if (mark[i] != j) { mark[i] = j; acc[i] = 0.0; c->rowind[e++] = i; }
                acc[i] += A->values[p] * bkj;
            }
        }
        for (int32_t p = begin; p < e; ++p) c->values[p] = acc[c->rowind[p]];
        c->colptr[j + 1] = e;
    }
    if ((st = cfi_sparse_alloc(ctx, c->ncols, c->nrows, nnz, &ct)) != CF_OK) goto done;
    transpose_into(c, ct);
    transpose_into(ct, c);
    *out = c;
    c = NULL;
done:
    CFI_FREE(ctx, mark, afull ? afull->nrows : a->nrows);
    CFI_FREE(ctx, acc, afull ? afull->nrows : a->nrows);
    cf_sparse_destroy(&ct);
    cf_sparse_destroy(&c);
    cf_sparse_destroy(&afull);
    cf_sparse_destroy(&bfull);
    return st;
}

int64_t cf_sparse_find(const cf_sparse *a, int32_t i, int32_t j)
{
    if (!a || i < 0 || i >= a->nrows || j < 0 || j >= a->ncols) return -1;
    int32_t lo = a->colptr[j], hi = a->colptr[j + 1];
    while (lo < hi) {
        int32_t mid = lo + (hi - lo) / 2;
        if (a->rowind[mid] < i) lo = mid + 1;
        else hi = mid;
    }
    return (lo < a->colptr[j + 1] && a->rowind[lo] == i) ? lo : -1;
}
