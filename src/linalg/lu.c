/*
 * LU factorisation of general square sparse matrices with UMFPACK:
 * symbolic analysis once per pattern, numeric factorisation per update,
 * solves with UMFPACK's iterative refinement on preallocated workspace
 * (umfpack_di_wsolve: no allocation per solve). Upper-only symmetric input
 * is expanded to both triangles through a precomputed position map.
 */
#include "linalg/linalg_internal.h"

#include <math.h>
#include <string.h>
#include <umfpack.h>

struct cf_lu {
    cf_context *ctx;
    int32_t n;
    int64_t nnz;               /* of the input pattern */
    int32_t *colptr;           /* input pattern column pointers, to detect a changed pattern */
    cf_sparse *full;           /* own copy of the matrix (expanded when the input is upper_only), kept for refinement */
    double *bcopy;             /* n: right-hand side copy, so x may alias b */
    int64_t *mirror;           /* upper_only: position in full of the mirrored entry (or -1), per input entry */
    int64_t *direct;           /* upper_only: position in full of each input entry */
    void *symbolic;
    void *numeric;
    double control[UMFPACK_CONTROL];
    double info[UMFPACK_INFO];
    int32_t *wi;               /* wsolve workspace: n ints, 5n doubles */
    double *w;
};

static const char *umfpack_status_text(int st)
{
    switch (st) {
    case UMFPACK_WARNING_singular_matrix: return "singular matrix";
    case UMFPACK_ERROR_out_of_memory: return "out of memory";
    case UMFPACK_ERROR_invalid_matrix: return "invalid matrix";
    case UMFPACK_ERROR_different_pattern: return "pattern changed";
    default: return "error";
    }
}

static cf_status check_umfpack(cf_context *ctx, int st, const char *what)
{
    if (st == UMFPACK_OK || st == UMFPACK_WARNING_determinant_underflow || st == UMFPACK_WARNING_determinant_overflow)
        return CF_OK;
    if (st == UMFPACK_ERROR_out_of_memory) return cfi_error(ctx, CF_ERR_NOMEM, "%s: UMFPACK out of memory (status %d)", what, st);
    if (st == UMFPACK_WARNING_singular_matrix)
        return cfi_error(ctx, CF_ERR_NUMERICAL, "%s: UMFPACK status %d (%s)", what, st, umfpack_status_text(st));
    return cfi_error(ctx, CF_ERR_NUMERICAL, "%s: UMFPACK status %d (%s)", what, st, umfpack_status_text(st));
}

void cfi_lu_set_refinement_steps(cf_lu *lu, int32_t steps)
{
    if (lu) lu->control[UMFPACK_IRSTEP] = steps < 0 ? 0 : steps;
}

void cf_lu_destroy(cf_lu **plu)
{
    if (!plu || !*plu) return;
    cf_lu *lu = *plu;
    cf_context *ctx = lu->ctx;
    if (lu->numeric) umfpack_di_free_numeric(&lu->numeric);
    if (lu->symbolic) umfpack_di_free_symbolic(&lu->symbolic);
    cf_sparse_destroy(&lu->full);
    CFI_FREE(ctx, lu->mirror, lu->nnz);
    CFI_FREE(ctx, lu->direct, lu->nnz);
    CFI_FREE(ctx, lu->colptr, (size_t)lu->n + 1);
    CFI_FREE(ctx, lu->wi, lu->n);
    CFI_FREE(ctx, lu->w, 5 * (size_t)lu->n);
    CFI_FREE(ctx, lu->bcopy, lu->n);
    CFI_FREE(ctx, lu, 1);
    *plu = NULL;
}

/* The matrix UMFPACK sees: a itself, or its expansion refreshed from a. */
static const cf_sparse *umf_matrix(cf_lu *lu, const cf_sparse *a)
{
    if (!lu->direct) {
        memcpy(lu->full->values, a->values, (size_t)lu->nnz * sizeof(double));
        return lu->full;
    }
    memset(lu->full->values, 0, (size_t)cf_sparse_nnz(lu->full) * sizeof(double));
    for (int64_t p = 0; p < lu->nnz; ++p) {
        if (lu->direct[p] < 0) continue;
        lu->full->values[lu->direct[p]] = a->values[p];
        if (lu->mirror[p] >= 0) lu->full->values[lu->mirror[p]] = a->values[p];
    }
    return lu->full;
}

static cf_status check_input(cf_context *ctx, const cf_sparse *a, const char *what)
{
    if (!a) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: matrix is NULL", what);
    if (a->nrows != a->ncols || a->nrows < 1)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: matrix is %d x %d, need square and non-empty", what, a->nrows, a->ncols);
    int64_t bad = cfi_first_nonfinite(a->values, cf_sparse_nnz(a));
    if (bad >= 0) return cfi_error(ctx, CF_ERR_NUMERICAL, "%s: value %lld (row %d) is not finite", what, (long long)bad, a->rowind[bad]);
    return CF_OK;
}

cf_status cf_lu_factorize(cf_lu *lu, const cf_sparse *a)
{
    if (!lu) return CF_ERR_INVALID_ARG;
    cf_context *ctx = lu->ctx;
    cf_status st = check_input(ctx, a, "LU factorise");
    if (st != CF_OK) return st;
    if (a->ncols != lu->n || cf_sparse_nnz(a) != lu->nnz ||
        memcmp(a->colptr, lu->colptr, ((size_t)lu->n + 1) * sizeof *lu->colptr) != 0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "LU factorise: pattern differs from the analysed one");
    if (lu->numeric) umfpack_di_free_numeric(&lu->numeric);
    /* UMFPACK's numeric factorisation and solves call BLAS: OpenBLAS's buffer first */
    if ((st = cfi_blas_reserve(ctx, "LU factorise")) != CF_OK) return st;
    const cf_sparse *m = umf_matrix(lu, a);
    int blas_threads = cfi_blas_threads_enter(ctx); /* one OpenBLAS thread by default (cf_context_set_threads) */
    int ust = umfpack_di_numeric(m->colptr, m->rowind, m->values, lu->symbolic, &lu->numeric, lu->control, lu->info);
    cfi_blas_threads_leave(blas_threads);
    if (ust != UMFPACK_OK && lu->numeric && ust != UMFPACK_WARNING_determinant_underflow &&
        ust != UMFPACK_WARNING_determinant_overflow) {
        umfpack_di_free_numeric(&lu->numeric);
    }
    return check_umfpack(ctx, ust, "LU factorise");
}

cf_status cf_lu_create(cf_context *ctx, const cf_sparse *a, cf_lu **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "LU create: out is NULL");
    *out = NULL;
    cf_status st = check_input(ctx, a, "LU create");
    if (st != CF_OK) return st;
    cf_lu *lu = CFI_ALLOC(ctx, cf_lu, 1);
    if (!lu) return CF_ERR_NOMEM;
    lu->ctx = ctx;
    lu->n = a->ncols;
    lu->nnz = cf_sparse_nnz(a);
    lu->colptr = CFI_ALLOC(ctx, int32_t, (size_t)lu->n + 1);
    lu->wi = CFI_ALLOC(ctx, int32_t, (size_t)lu->n);
    lu->w = CFI_ALLOC(ctx, double, 5 * (size_t)lu->n);
    lu->bcopy = CFI_ALLOC(ctx, double, (size_t)lu->n);
    if (!lu->colptr || !lu->wi || !lu->w || !lu->bcopy) { st = CF_ERR_NOMEM; goto fail; }
    memcpy(lu->colptr, a->colptr, ((size_t)lu->n + 1) * sizeof *lu->colptr);
    if ((st = cfi_sparse_copy(ctx, a, &lu->full)) != CF_OK) goto fail;
    if (a->upper_only) {
        lu->direct = CFI_ALLOC(ctx, int64_t, (size_t)lu->nnz);
        lu->mirror = CFI_ALLOC(ctx, int64_t, (size_t)lu->nnz);
        if (!lu->direct || !lu->mirror) { st = CF_ERR_NOMEM; goto fail; }
        for (int32_t j = 0; j < a->ncols; ++j)
            for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) {
                int32_t i = a->rowind[p];
                lu->direct[p] = i <= j ? cf_sparse_find(lu->full, i, j) : -1; /* entries below the diagonal are ignored */
                lu->mirror[p] = i < j ? cf_sparse_find(lu->full, j, i) : -1;
            }
    }
    umfpack_di_defaults(lu->control);
    lu->control[UMFPACK_PRL] = 0; /* never print */
    const cf_sparse *m = umf_matrix(lu, a);
    int ust = umfpack_di_symbolic(lu->n, lu->n, m->colptr, m->rowind, m->values, &lu->symbolic, lu->control, lu->info);
    if ((st = check_umfpack(ctx, ust, "LU analyse")) != CF_OK) goto fail;
    if ((st = cf_lu_factorize(lu, a)) != CF_OK) goto fail;
    *out = lu;
    return CF_OK;
fail:
    cf_lu_destroy(&lu);
    return st;
}

cf_status cf_lu_solve(cf_lu *lu, const double *b, double *x)
{
    if (!lu) return CF_ERR_INVALID_ARG;
    cf_context *ctx = lu->ctx;
    if (!b || !x) return cfi_error(ctx, CF_ERR_INVALID_ARG, "LU solve: b or x is NULL");
    if (!lu->numeric) return cfi_error(ctx, CF_ERR_INVALID_ARG, "LU solve: no successful factorisation");
    int64_t bad = cfi_first_nonfinite(b, lu->n);
    if (bad >= 0) return cfi_error(ctx, CF_ERR_NUMERICAL, "LU solve: right-hand side row %lld is not finite", (long long)bad);
    cf_status sr = cfi_blas_reserve(ctx, "LU solve"); /* the solve may run on another thread */
    if (sr != CF_OK) return sr;
    const cf_sparse *m = lu->full;
    memcpy(lu->bcopy, b, (size_t)lu->n * sizeof *b); /* x may alias b */
    int blas_threads = cfi_blas_threads_enter(ctx);
    int ust = umfpack_di_wsolve(UMFPACK_A, m->colptr, m->rowind, m->values, x, lu->bcopy, lu->numeric, lu->control,
                                lu->info, lu->wi, lu->w);
    cfi_blas_threads_leave(blas_threads);
    cf_status st = check_umfpack(ctx, ust, "LU solve");
    if (st != CF_OK) return st;
    bad = cfi_first_nonfinite(x, lu->n);
    if (bad >= 0) return cfi_error(ctx, CF_ERR_NUMERICAL, "LU solve: solution row %lld is not finite", (long long)bad);
    return CF_OK;
}
