/*
 * Quadratic minimisation with fixed values and linear equality constraints,
 * split into precompute (create / factorize) and solve, in the shape of
 * libigl's min_quad_with_fixed (Jacobson et al.):
 *
 *     minimise 1/2 x^T A x + b^T x   subject to  x[known] = y,  Aeq x = beq.
 *
 * With u the free variables and k the known ones, the known columns move to
 * the right-hand side:
 *     no equalities:  A_uu x_u = -b_u - A_uk y                    (Cholesky)
 *     equalities:     [ A_uu    Aeq_u^T ] [x_u]   [ -b_u - A_uk y    ]
 *                     [ Aeq_u   0       ] [lam] = [ beq - Aeq_k y    ]  (saddle layer)
 * (lam are the multipliers of L = 1/2 x^T A x + b^T x + lam^T (Aeq x - beq)).
 * A_uu and Aeq_u are extracted once with a map from each of their entries
 * to its slot in A (Aeq), so a refactorisation for new values of the same
 * patterns only copies values; A_uk and Aeq_k are kept column by column for
 * the right-hand sides. A_uk y is accumulated separately and subtracted
 * from -b_u at the end, column by column of the known variables in
 * ascending order: the order of operations of the stretch-bend edit's own
 * elimination, which this replaces (its results are bit-identical).
 *
 * Quaternion blocks (options.quaternion_blocks): when A is a Hermitian
 * quaternionic matrix (a Dirac matrix, docs/linalg.md) and the known
 * variables are whole 4-component blocks, A_uu is the same kind of matrix
 * and keeps the complex factorisation of half the size; eliminating single
 * components would break the blocks and force the real 4n x 4n form. The
 * spin flow's fixed boundary (Crane et al. 2013, Sec. 6.3.2) is the user.
 */
#include "linalg/linalg_internal.h"

#include <math.h>
#include <string.h>

/* Tolerance of the symmetry check, relative to the largest |A_ij|: a
 * product such as K M^-1 K is symmetric only up to a few rounding errors of
 * its largest entries, while a genuinely unsymmetric A (which the quadratic
 * form cannot represent) differs at order one. */
#define MIN_QUAD_SYMMETRY_TOL 1e-10

struct cf_min_quad {
    cf_context *ctx;
    cf_min_quad_options opt;
    int32_t n, nk, nu, m;
    int32_t *cursor;      /* n: work of the symmetry check */
    int32_t *free_index;  /* n: index among the free variables, or -1 for a known one */
    int32_t *free_var;    /* nu: variable of each free index */
    int32_t *known_var;   /* nk: known variables, ascending */
    int32_t *known_slot;  /* nk: row of y (position in the caller's list) of known_var[k] */
    /* pattern of A and Aeq as given at create (checked at factorize) */
    int32_t *a_colptr, *a_rowind;
    int64_t a_nnz;
    int32_t *e_colptr, *e_rowind;
    int64_t e_nnz;
    /* A_uu (both triangles, CSC order of A: entry t comes from A->values[src[t]])
     * and A_uk by known column (entries kptr[k] .. kptr[k + 1] - 1, free row
     * krow, value kval); Aeq_u (m x nu) and Aeq_k likewise. */
    struct col_split {
        cf_sparse *block;
        int32_t *src;
        int64_t nblock;
        int64_t *kptr;     /* nk + 1 */
        int32_t *krow, *ksrc;
        double *kval;
        int64_t nknown;
    } a_split, e_split;
    cf_cholesky *chol;
    cf_saddle *saddle;
    int32_t factorized;
    /* work: nu x max_rhs right-hand side, solution, A_uk y; m for the constraints */
    double *ru, *su, *tu, *re, *te, *le;
    /* tu holds A_uk y for y_cache (nk x tu_cols) when tu_valid: a solve with
     * the same known values (an iteration with fixed handles) skips it */
    double *y_cache;
    int32_t tu_cols, tu_valid;
};

void cf_min_quad_options_default(cf_min_quad_options *options)
{
    if (!options) return;
    memset(options, 0, sizeof *options);
    options->block_size = 1;
    options->ordering = CF_ORDERING_AUTO;
    options->max_rhs = 1;
}

static void split_free(cf_context *ctx, struct col_split *c, size_t nk)
{
    cf_sparse_destroy(&c->block);
    CFI_FREE(ctx, c->src, (size_t)c->nblock);
    CFI_FREE(ctx, c->kptr, nk + 1);
    CFI_FREE(ctx, c->krow, (size_t)c->nknown);
    CFI_FREE(ctx, c->ksrc, (size_t)c->nknown);
    CFI_FREE(ctx, c->kval, (size_t)c->nknown);
}

void cf_min_quad_destroy(cf_min_quad **q)
{
    if (!q || !*q) return;
    cf_min_quad *s = *q;
    cf_context *ctx = s->ctx;
    size_t n = (size_t)s->n, nk = (size_t)s->nk, nu = (size_t)s->nu, m = (size_t)s->m;
    size_t w = nu * (size_t)s->opt.max_rhs;
    cf_cholesky_destroy(&s->chol);
    cf_saddle_destroy(&s->saddle);
    CFI_FREE(ctx, s->cursor, n);
    CFI_FREE(ctx, s->free_index, n);
    CFI_FREE(ctx, s->free_var, nu);
    CFI_FREE(ctx, s->known_var, nk);
    CFI_FREE(ctx, s->known_slot, nk);
    CFI_FREE(ctx, s->a_colptr, n + 1);
    CFI_FREE(ctx, s->a_rowind, (size_t)s->a_nnz);
    if (s->e_colptr) CFI_FREE(ctx, s->e_colptr, n + 1);
    CFI_FREE(ctx, s->e_rowind, (size_t)s->e_nnz);
    split_free(ctx, &s->a_split, nk);
    split_free(ctx, &s->e_split, nk);
    CFI_FREE(ctx, s->ru, w);
    CFI_FREE(ctx, s->su, w);
    CFI_FREE(ctx, s->tu, w);
    CFI_FREE(ctx, s->y_cache, nk * (size_t)s->opt.max_rhs);
    CFI_FREE(ctx, s->re, m);
    CFI_FREE(ctx, s->te, m);
    CFI_FREE(ctx, s->le, m);
    cfi_free(ctx, s, sizeof *s);
    *q = NULL;
}

/* A: finite, and symmetric up to MIN_QUAD_SYMMETRY_TOL of its largest
 * entry. The pattern is checked too: every entry above the diagonal has its
 * mirror and every entry below is some entry's mirror. One pass over the
 * entries: rows are sorted, so the mirrors of the entries above the
 * diagonal met column after column come down each column in order, and
 * cursor[i] (n entries of work) walks column i below the diagonal (a
 * binary search per entry cost 25 % of a Dirac matrix's refactorisation).
 * A lower entry without mirror is named by a second, searching pass (error
 * path only), so that the first one in column order is reported. */
static cf_status check_a_values(cf_context *ctx, const cf_sparse *a, const char *what, int32_t *cursor)
{
    int64_t nnz = cf_sparse_nnz(a);
    /* one pass for the largest entry and finiteness (poison stays 0 unless
     * an entry is NaN or infinite); the entry is named on the error path */
    double big = 0.0, poison = 0.0;
    for (int64_t p = 0; p < nnz; ++p) {
        double v = fabs(a->values[p]);
        big = v > big ? v : big;
        poison += v * 0.0;
    }
    if (poison != 0.0 || poison != poison) {
        int64_t bad = cfi_first_nonfinite(a->values, nnz);
        int32_t j = 0;
        while (a->colptr[j + 1] <= bad) ++j;
        return cfi_error(ctx, CF_ERR_NONFINITE, "%s: A(%d, %d) is not finite", what, a->rowind[bad], j);
    }
    const int32_t *cp = a->colptr, *ri = a->rowind;
    for (int32_t i = 0; i < a->ncols; ++i) {
        int32_t t = cp[i];
        while (t < cp[i + 1] && ri[t] <= i) ++t;
        cursor[i] = t;
    }
    int lower_orphan = 0;
    for (int32_t j = 0; j < a->ncols; ++j)
        for (int32_t p = cp[j]; p < cp[j + 1] && ri[p] < j; ++p) {
            int32_t i = ri[p], t = cursor[i];
            while (t < cp[i + 1] && ri[t] < j) { /* (ri[t], i) was nobody's mirror */
                lower_orphan = 1;
                ++t;
            }
            if (t == cp[i + 1] || ri[t] != j)
                return cfi_error(ctx, CF_ERR_INVALID_ARG,
                                 "%s: A is not structurally symmetric: A(%d, %d) is stored, A(%d, %d) not", what, i, j,
                                 j, i);
            if (fabs(a->values[p] - a->values[t]) > MIN_QUAD_SYMMETRY_TOL * big)
                return cfi_error(ctx, CF_ERR_INVALID_ARG,
                                 "%s: A is not symmetric: A(%d, %d) = %.17g but A(%d, %d) = %.17g", what, i, j,
                                 a->values[p], j, i, a->values[t]);
            cursor[i] = t + 1;
        }
    for (int32_t i = 0; i < a->ncols; ++i) lower_orphan |= cursor[i] < cp[i + 1];
    if (lower_orphan) {
        for (int32_t j = 0; j < a->ncols; ++j)
            for (int32_t p = cp[j]; p < cp[j + 1]; ++p)
                if (ri[p] > j && cf_sparse_find(a, j, ri[p]) < 0)
                    return cfi_error(ctx, CF_ERR_INVALID_ARG,
                                     "%s: A is not structurally symmetric: A(%d, %d) is stored, A(%d, %d) not", what,
                                     ri[p], j, j, ri[p]);
    }
    return CF_OK;
}

static cf_status check_shapes(cf_context *ctx, const cf_sparse *a, const cf_sparse *aeq, const char *what)
{
    if (!a) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: A is NULL", what);
    if (a->nrows != a->ncols || a->ncols < 1)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: A is %d x %d, need square and non-empty", what, a->nrows,
                         a->ncols);
    if (a->upper_only)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: A must store both triangles (it is upper_only)", what);
    if (aeq && aeq->ncols != a->ncols)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: Aeq has %d columns, A has %d", what, aeq->ncols, a->ncols);
    if (aeq && aeq->upper_only) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: Aeq must store every entry", what);
    if (aeq) {
        int64_t bad = cfi_first_nonfinite(aeq->values, cf_sparse_nnz(aeq));
        if (bad >= 0) {
            int32_t j = 0;
            while (aeq->colptr[j + 1] <= bad) ++j;
            return cfi_error(ctx, CF_ERR_NONFINITE, "%s: Aeq(%d, %d) is not finite", what, aeq->rowind[bad], j);
        }
    }
    return CF_OK;
}

/* Splits the columns of M (A or Aeq) into the free block (with the source
 * slot of each entry) and the known columns (grouped by known index,
 * ascending variable order). `row_map` maps a row of M to its row in the
 * free block, -1 to drop it (A's known rows); NULL keeps every row (Aeq).
 * On failure the caller frees `c` (its sizes are set before allocating). */
static cf_status split_columns(cf_min_quad *s, const cf_sparse *mat, const int32_t *row_map, int32_t nrows_block,
                               int symmetric, struct col_split *c)
{
    cf_context *ctx = s->ctx;
    int64_t nblock = 0, nknown = 0;
    for (int32_t j = 0; j < s->n; ++j)
        for (int32_t p = mat->colptr[j]; p < mat->colptr[j + 1]; ++p) {
            if (row_map && row_map[mat->rowind[p]] < 0) continue;
            if (s->free_index[j] >= 0) ++nblock;
            else ++nknown;
        }
    c->nblock = nblock;
    c->nknown = nknown;
    c->src = CFI_ALLOC(ctx, int32_t, nblock);
    c->kptr = CFI_ALLOC(ctx, int64_t, (size_t)s->nk + 1);
    c->krow = CFI_ALLOC(ctx, int32_t, nknown);
    c->ksrc = CFI_ALLOC(ctx, int32_t, nknown);
    c->kval = CFI_ALLOC(ctx, double, nknown);
    int32_t *rows = CFI_ALLOC(ctx, int32_t, nblock);
    int32_t *cols = CFI_ALLOC(ctx, int32_t, nblock);
    cf_status st = CF_OK;
    if (!c->src || !rows || !cols || !c->kptr || !c->krow || !c->ksrc || !c->kval) {
        st = CF_ERR_NOMEM;
        goto done;
    }
    int64_t t = 0, u = 0;
    int32_t k = 0;
    for (int32_t j = 0; j < s->n; ++j) {
        int32_t fj = s->free_index[j];
        if (fj < 0) c->kptr[k] = u;
        for (int32_t p = mat->colptr[j]; p < mat->colptr[j + 1]; ++p) {
            int32_t r = row_map ? row_map[mat->rowind[p]] : mat->rowind[p];
            if (r < 0) continue;
            if (fj >= 0) {
                rows[t] = r;
                cols[t] = fj;
                c->src[t++] = p;
            } else {
                c->krow[u] = r;
                c->ksrc[u++] = p;
            }
        }
        if (fj < 0) ++k;
    }
    c->kptr[s->nk] = u;
    /* pattern only: refactor() pours the values */
    st = cf_sparse_from_triplets(ctx, nrows_block, s->nu, nblock, rows, cols, NULL, symmetric, &c->block, NULL);
    /* The triplets come in CSC order (columns and, within a column, rows of
     * M ascending; the row map is monotone), so entry t of the block is
     * triplet t and values are copied slot by slot. */
    if (st == CF_OK && CF_NEVER(cf_sparse_nnz(c->block) != nblock))
        st = cfi_error(ctx, CF_ERR_INVALID_ARG, "min_quad: repeated entries in a column");
done:
    CFI_FREE(ctx, rows, nblock);
    CFI_FREE(ctx, cols, nblock);
    return st;
}

/* Numeric part: values of A_uu, A_uk, Aeq_u, Aeq_k from a, aeq (patterns
 * already checked) and the factorisation. */
static cf_status refactor(cf_min_quad *s, const cf_sparse *a, const cf_sparse *aeq)
{
    s->factorized = 0;
    s->tu_valid = 0; /* A_uk changes */
    const struct col_split *ca = &s->a_split, *ce = &s->e_split;
    for (int64_t t = 0; t < ca->nblock; ++t) ca->block->values[t] = a->values[ca->src[t]];
    for (int64_t t = 0; t < ca->nknown; ++t) ca->kval[t] = a->values[ca->ksrc[t]];
    if (s->m > 0) {
        for (int64_t t = 0; t < ce->nblock; ++t) ce->block->values[t] = aeq->values[ce->src[t]];
        for (int64_t t = 0; t < ce->nknown; ++t) ce->kval[t] = aeq->values[ce->ksrc[t]];
    }
    if (s->nu == 0) {
        s->factorized = 1;
        return CF_OK;
    }
    cf_status st;
    if (s->m == 0) {
        st = cf_cholesky_factorize(s->chol, ca->block);
        if (st != CF_OK) return cfi_error_prefix(s->ctx, "min_quad (free block, %d variables)", s->nu);
    } else {
        st = cf_saddle_factorize(s->saddle, ca->block, ce->block, NULL);
        if (st != CF_OK) return cfi_error_prefix(s->ctx, "min_quad (%d free variables, %d constraints)", s->nu, s->m);
    }
    s->factorized = 1;
    return CF_OK;
}

/* The arguments of cf_min_quad_create that need no allocation: options,
 * counts, and what quaternion blocks require. */
static cf_status check_create_arguments(cf_context *ctx, const cf_sparse *a, int32_t known_count, const int32_t *known,
                                        const cf_sparse *aeq, const cf_min_quad_options *opt_in)
{
    const cf_min_quad_options opt = *opt_in;
    if (opt.max_rhs < 1 || opt.max_rhs > 4096)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "min_quad create: max_rhs %d not in [1, 4096]", opt.max_rhs);
    if (opt.block_size < 1)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "min_quad create: block size %d must be >= 1", opt.block_size);
    int32_t n = a->ncols;
    if (known_count < 0 || known_count > n || (known_count > 0 && !known))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "min_quad create: %d known variables (of %d), list %s", known_count,
                         n, known ? "given" : "NULL");
    int32_t m = aeq ? aeq->nrows : 0;
    if (m < 0) return cfi_error(ctx, CF_ERR_INVALID_ARG, "min_quad create: Aeq has %d rows", m);
    if (opt.quaternion_blocks) {
        /* the complex form exists for the Cholesky path only (the saddle
         * layer factorises real matrices) */
        if (opt.block_size != 4)
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "min_quad create: quaternion blocks need block size 4, not %d",
                             opt.block_size);
        if (m > 0)
            return cfi_error(ctx, CF_ERR_INVALID_ARG,
                             "min_quad create: quaternion blocks take no equality constraints (%d given)", m);
        if (n % 4 != 0)
            return cfi_error(ctx, CF_ERR_INVALID_ARG,
                             "min_quad create: quaternion blocks: %d variables are not whole 4 x 4 blocks", n);
    }
    if (m > 0 && known_count == n)
        return cfi_error(ctx, CF_ERR_INVALID_ARG,
                         "min_quad create: every variable is known, none is left for the %d equality constraints", m);
    return CF_OK;
}

/* Splits the variables into free and known (known[k] = the caller's slot
 * k), refusing indices out of range, repeats, partly known quaternion
 * blocks and a block size that does not divide the free count. */
static cf_status partition_variables(cf_min_quad *s, const int32_t *known)
{
    cf_context *ctx = s->ctx;
    const cf_min_quad_options opt = s->opt;
    int32_t n = s->n;
    /* known variables: range, repeats; free_index temporarily holds the
     * caller's slot + 1 of each known variable */
    for (int32_t v = 0; v < n; ++v) s->free_index[v] = 0;
    for (int32_t k = 0; k < s->nk; ++k) {
        int32_t v = known[k];
        if (v < 0 || v >= n) {
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "min_quad create: known[%d] = %d is outside [0, %d)", k, v, n);
        }
        if (s->free_index[v] != 0) {
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "min_quad create: variable %d is known twice (known[%d], known[%d])",
                           v, s->free_index[v] - 1, k);
        }
        s->free_index[v] = k + 1;
    }
    {
        int32_t nu = 0, nk = 0;
        for (int32_t v = 0; v < n; ++v) {
            if (s->free_index[v] == 0) {
                s->free_var[nu] = v;
                s->free_index[v] = nu++;
            } else {
                s->known_var[nk] = v;
                s->known_slot[nk++] = s->free_index[v] - 1;
                s->free_index[v] = -1;
            }
        }
    }
    /* Whole blocks known or free: then A_uu keeps A's quaternion blocks
     * (rows and columns of a block are removed together). */
    for (int32_t b = 0; opt.quaternion_blocks && b < n / 4; ++b) {
        int known_here = 0;
        for (int c = 0; c < 4; ++c) known_here += s->free_index[4 * b + c] < 0;
        if (known_here != 0 && known_here != 4) {
            return cfi_error(ctx, CF_ERR_INVALID_ARG,
                           "min_quad create: quaternion blocks: block %d (variables %d..%d) is partly known (%d of 4 "
                           "components); fix whole blocks",
                           b, 4 * b, 4 * b + 3, known_here);
        }
    }
    if (s->nu > 0 && s->nu % opt.block_size != 0) {
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "min_quad create: block size %d does not divide the %d free variables",
                       opt.block_size, s->nu);
    }
    return CF_OK;
}

cf_status cf_min_quad_create(cf_context *ctx, const cf_sparse *a, int32_t known_count, const int32_t *known,
                             const cf_sparse *aeq, const cf_min_quad_options *options, cf_min_quad **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "min_quad create: output is NULL");
    *out = NULL;
    cf_status st = check_shapes(ctx, a, aeq, "min_quad create");
    if (st != CF_OK) return st;
    cf_min_quad_options opt;
    cf_min_quad_options_default(&opt);
    if (options) opt = *options;
    st = check_create_arguments(ctx, a, known_count, known, aeq, &opt);
    if (st != CF_OK) return st;
    int32_t n = a->ncols;
    int32_t m = aeq ? aeq->nrows : 0;
    int32_t *cursor = CFI_ALLOC(ctx, int32_t, n);
    if (!cursor) return CF_ERR_NOMEM;
    st = check_a_values(ctx, a, "min_quad create", cursor);
    if (st != CF_OK) {
        CFI_FREE(ctx, cursor, n);
        return st;
    }

    cf_min_quad *s = cfi_malloc(ctx, sizeof *s);
    if (!s) {
        CFI_FREE(ctx, cursor, n);
        return CF_ERR_NOMEM;
    }
    memset(s, 0, sizeof *s);
    s->cursor = cursor;
    s->ctx = ctx;
    s->opt = opt;
    s->n = n;
    s->nk = known_count;
    s->nu = n - known_count;
    s->m = m;
    s->a_nnz = cf_sparse_nnz(a);
    s->e_nnz = aeq ? cf_sparse_nnz(aeq) : 0;
    size_t w = (size_t)s->nu * (size_t)opt.max_rhs;
    s->free_index = CFI_ALLOC(ctx, int32_t, n);
    s->free_var = CFI_ALLOC(ctx, int32_t, s->nu);
    s->known_var = CFI_ALLOC(ctx, int32_t, s->nk);
    s->known_slot = CFI_ALLOC(ctx, int32_t, s->nk);
    s->a_colptr = CFI_ALLOC(ctx, int32_t, (size_t)n + 1);
    s->a_rowind = CFI_ALLOC(ctx, int32_t, s->a_nnz);
    if (aeq) {
        s->e_colptr = CFI_ALLOC(ctx, int32_t, (size_t)n + 1);
        s->e_rowind = CFI_ALLOC(ctx, int32_t, s->e_nnz);
    }
    s->ru = CFI_ALLOC(ctx, double, w);
    s->su = CFI_ALLOC(ctx, double, w);
    s->tu = CFI_ALLOC(ctx, double, w);
    s->y_cache = CFI_ALLOC(ctx, double, (size_t)s->nk * (size_t)opt.max_rhs);
    s->re = CFI_ALLOC(ctx, double, m);
    s->te = CFI_ALLOC(ctx, double, m);
    s->le = CFI_ALLOC(ctx, double, m);
    /* (zero-length arrays are one-byte allocations: every pointer is set) */
    if (!s->free_index || !s->free_var || !s->known_var || !s->known_slot || !s->a_colptr || !s->a_rowind ||
        (aeq && (!s->e_colptr || !s->e_rowind)) || !s->ru || !s->su || !s->tu || !s->y_cache || !s->re || !s->te ||
        !s->le) {
        st = CF_ERR_NOMEM;
        goto fail;
    }
    memcpy(s->a_colptr, a->colptr, ((size_t)n + 1) * sizeof *s->a_colptr);
    memcpy(s->a_rowind, a->rowind, (size_t)s->a_nnz * sizeof *s->a_rowind);
    if (aeq) {
        memcpy(s->e_colptr, aeq->colptr, ((size_t)n + 1) * sizeof *s->e_colptr);
        memcpy(s->e_rowind, aeq->rowind, (size_t)s->e_nnz * sizeof *s->e_rowind);
    }
    st = partition_variables(s, known);
    if (st != CF_OK) goto fail;
    st = split_columns(s, a, s->free_index, s->nu, 1, &s->a_split);
    if (st != CF_OK) goto fail;
    if (m > 0) {
        st = split_columns(s, aeq, NULL, m, 0, &s->e_split);
        if (st != CF_OK) goto fail;
    }
    if (s->nu > 0) {
        if (m == 0) {
            cf_cholesky_options co;
            cf_cholesky_options_default(&co);
            co.block_size = opt.block_size;
            co.ordering = opt.ordering;
            co.quaternion_blocks = opt.quaternion_blocks;
            st = cf_cholesky_create(ctx, s->a_split.block, &co, &s->chol);
        } else {
            cf_saddle_options so;
            cf_saddle_options_default(&so);
            so.block_size = opt.block_size;
            st = cf_saddle_create(ctx, s->a_split.block, s->e_split.block, &so, &s->saddle);
        }
        if (st != CF_OK) goto fail;
    }
    st = refactor(s, a, aeq);
    if (st != CF_OK) goto fail;
    /* One solve with zero right-hand sides makes CHOLMOD allocate its solve
     * workspace for max_rhs columns now, so solves of that width allocate
     * nothing. */
    if (s->chol) {
        memset(s->ru, 0, w * sizeof *s->ru);
        st = cf_cholesky_solve(s->chol, opt.max_rhs, s->ru, s->su);
        if (st != CF_OK) goto fail;
    }
    *out = s;
    return CF_OK;
fail:
    cf_min_quad_destroy(&s);
    return st;
}

cf_status cf_min_quad_factorize(cf_min_quad *q, const cf_sparse *a, const cf_sparse *aeq)
{
    if (!q) return CF_ERR_INVALID_ARG;
    cf_context *ctx = q->ctx;
    q->factorized = 0;
    cf_status st = check_shapes(ctx, a, aeq, "min_quad factorize");
    if (st != CF_OK) return st;
    if (a->ncols != q->n || cf_sparse_nnz(a) != q->a_nnz ||
        memcmp(a->colptr, q->a_colptr, ((size_t)q->n + 1) * sizeof *a->colptr) != 0 ||
        memcmp(a->rowind, q->a_rowind, (size_t)q->a_nnz * sizeof *a->rowind) != 0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "min_quad factorize: the pattern of A differs from the one at create");
    if ((aeq != NULL) != (q->e_colptr != NULL) ||
        (aeq && (aeq->nrows != q->m || cf_sparse_nnz(aeq) != q->e_nnz ||
                 memcmp(aeq->colptr, q->e_colptr, ((size_t)q->n + 1) * sizeof *aeq->colptr) != 0 ||
                 memcmp(aeq->rowind, q->e_rowind, (size_t)q->e_nnz * sizeof *aeq->rowind) != 0)))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "min_quad factorize: Aeq differs in shape or pattern from create");
    st = check_a_values(ctx, a, "min_quad factorize", q->cursor);
    if (st != CF_OK) return st;
    return refactor(q, a, aeq);
}

int32_t cf_min_quad_free_count(const cf_min_quad *q) { return q ? q->nu : 0; }

/* Names the first non-finite entry of an n x nrhs column-major input. */
static cf_status check_input(cf_context *ctx, const double *v, int32_t n, int32_t nrhs, const char *name)
{
    if (!v || n == 0) return CF_OK;
    int64_t bad = cfi_first_nonfinite(v, (int64_t)n * nrhs);
    if (bad < 0) return CF_OK;
    return cfi_error(ctx, CF_ERR_NUMERICAL, "min_quad solve: %s[%lld] (column %lld) is not finite", name,
                     (long long)(bad % n), (long long)(bad / n));
}

cf_status cf_min_quad_solve(cf_min_quad *q, int32_t nrhs, const double *b, const double *y, const double *beq,
                            double *x)
{
    if (!q) return CF_ERR_INVALID_ARG;
    cf_context *ctx = q->ctx;
    if (nrhs < 0 || (nrhs > 0 && !x))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "min_quad solve: %d right-hand sides, x %s", nrhs, x ? "given" : "NULL");
    if (!q->factorized) return cfi_error(ctx, CF_ERR_INVALID_ARG, "min_quad solve: no successful factorisation");
    /* b is checked on the way (its entries at known variables are not used) */
    cf_status st = check_input(ctx, y, q->nk, nrhs, "y");
    if (st == CF_OK) st = check_input(ctx, beq, q->m, nrhs, "beq");
    if (st != CF_OK) return st;
    int32_t n = q->n, nu = q->nu, nk = q->nk, m = q->m;
    const struct col_split *ca = &q->a_split, *ce = &q->e_split;
    for (int32_t c0 = 0; c0 < nrhs; c0 += q->opt.max_rhs) {
        int32_t cols = nrhs - c0 < q->opt.max_rhs ? nrhs - c0 : q->opt.max_rhs;
        /* t = A_uk y, accumulated by known column in ascending order; kept
         * while y does not change (y NULL is zero: t = 0) */
        const double *ychunk = y ? y + (size_t)c0 * nk : NULL;
        size_t ybytes = (size_t)nk * (size_t)cols * sizeof *y;
        int same = q->tu_valid && q->tu_cols == cols &&
                   (ychunk ? q->tu_valid == 1 && memcmp(q->y_cache, ychunk, ybytes) == 0 : q->tu_valid == 2);
        if (!same) {
            memset(q->tu, 0, (size_t)nu * (size_t)cols * sizeof *q->tu);
            for (int32_t c = 0; c < cols && y; ++c) {
                const double *yc = ychunk + (size_t)c * nk;
                double *tc = q->tu + (size_t)c * nu;
                for (int32_t k = 0; k < nk; ++k) {
                    double yk = yc[q->known_slot[k]];
                    for (int64_t t = ca->kptr[k]; t < ca->kptr[k + 1]; ++t) tc[ca->krow[t]] += ca->kval[t] * yk;
                }
            }
            if (ychunk) memcpy(q->y_cache, ychunk, ybytes);
            q->tu_cols = cols;
            q->tu_valid = ychunk ? 1 : 2;
        }
        for (int32_t c = 0; c < cols; ++c) {
            const double *bc = b ? b + (size_t)(c0 + c) * n : NULL;
            double *rc = q->ru + (size_t)c * nu;
            const double *tc = q->tu + (size_t)c * nu;
            double poison = 0.0; /* stays 0 unless an entry is NaN or infinite (x * 0 is NaN then) */
            for (int32_t i = 0; i < nu; ++i) {
                rc[i] = (bc ? -bc[q->free_var[i]] : 0.0) - tc[i];
                poison += rc[i] * 0.0;
            }
            if (poison != 0.0 || poison != poison) {
                for (int32_t i = 0; bc && i < nu; ++i)
                    if (!isfinite(bc[q->free_var[i]]))
                        return cfi_error(ctx, CF_ERR_NUMERICAL, "min_quad solve: b[%d] (column %d) is not finite",
                                         q->free_var[i], c0 + c);
                return cfi_error(ctx, CF_ERR_NUMERICAL, "min_quad solve: the right-hand side of column %d overflows",
                                 c0 + c);
            }
        }
        if (nu > 0 && m == 0) {
            st = cf_cholesky_solve(q->chol, cols, q->ru, q->su);
            if (st != CF_OK) return st;
        } else if (nu > 0) {
            for (int32_t c = 0; c < cols; ++c) {
                /* g = beq - Aeq_k y */
                memset(q->te, 0, (size_t)m * sizeof *q->te);
                if (y) {
                    const double *yc = y + (size_t)(c0 + c) * nk;
                    for (int32_t k = 0; k < nk; ++k) {
                        double yk = yc[q->known_slot[k]];
                        for (int64_t t = ce->kptr[k]; t < ce->kptr[k + 1]; ++t) q->te[ce->krow[t]] += ce->kval[t] * yk;
                    }
                }
                const double *bq = beq ? beq + (size_t)(c0 + c) * m : NULL;
                for (int32_t r = 0; r < m; ++r) q->re[r] = (bq ? bq[r] : 0.0) - q->te[r];
                st = cf_saddle_solve(q->saddle, q->ru + (size_t)c * nu, q->re, q->su + (size_t)c * nu, q->le);
                if (st != CF_OK) return st;
            }
        }
        for (int32_t c = 0; c < cols; ++c) {
            double *xc = x + (size_t)(c0 + c) * n;
            const double *sc = q->su + (size_t)c * nu;
            for (int32_t i = 0; i < nu; ++i) xc[q->free_var[i]] = sc[i];
            const double *yc = y ? y + (size_t)(c0 + c) * nk : NULL;
            for (int32_t k = 0; k < nk; ++k) xc[q->known_var[k]] = yc ? yc[q->known_slot[k]] : 0.0;
        }
    }
    return CF_OK;
}
