/*
 * Saddle-point systems [[A, B^T], [B, -C]] [x; y] = [f; g] with diagonal
 * C >= 0. For C > 0 the system is reduced to the Schur complement onto the
 * primal block, S = A + B^T C^-1 B (symmetric positive definite when A is
 * positive semi-definite and S is nonsingular), whose pattern is computed
 * once at creation and refilled per factorisation through precomputed
 * slots (NOTES.md: 5x faster than cholmod_aat + cholmod_add); x solves
 * S x = f + B^T C^-1 g and y = C^-1 (B x - g). With C = 0, a zero entry of C,
 * a Schur complement that is not positive definite, or force_lu, the full
 * matrix is factorised by UMFPACK instead (symbolic once, numeric per
 * factorisation). Either way the solution is refined iteratively against
 * the full system (NOTES.md reports ~1e-6 relative residual for the plain
 * Schur solve).
 */
#include "linalg/linalg_internal.h"

#include <math.h>
#include <string.h>

/* Schur pattern is formed only if B^T B has at most this many pairs
 * (a dense constraint row would make S dense; LU handles that case). */
#define SCHUR_MAX_PAIRS ((int64_t)64 * 1000 * 1000)
/* target relative residual of the full system */
#define SADDLE_TARGET_RESIDUAL 1e-10

struct cf_saddle {
    cf_context *ctx;
    int32_t n, m;
    cf_saddle_options opt;
    cf_sparse *a, *b;          /* own copies, values refreshed at each factorisation */
    double *c;                 /* m */
    /* B by rows (row r of B = entries bt_ptr[r] .. bt_ptr[r + 1] - 1) */
    int32_t *bt_ptr, *bt_col;
    int64_t *bt_src;           /* index into b->values */
    /* Schur complement */
    int schur_possible;
    cf_sparse *s;              /* upper triangle */
    int64_t *s_slot_a;         /* per entry of A: slot in S, -1 below the diagonal */
    int64_t *pair_slot;        /* per pair (p <= q) of each row of B: slot in S */
    int64_t npairs;
    cf_cholesky *chol;
    /* LU on the full matrix, made on first need */
    cf_sparse *k;
    int64_t *k_slot;
    double *k_vals;
    int64_t k_ntrip;
    cf_lu *lu;
    int used_schur, factorized;
    double residual;           /* relative residual of the last solve */
    double *rf, *rg, *dx, *dy, *tn, *tm, *zn; /* work: n, m, n, m, n, m, n + m */
};

void cf_saddle_options_default(cf_saddle_options *options)
{
    if (!options) return;
    options->block_size = 1;
    options->refinement_steps = 2;
    options->force_lu = 0;
}

int32_t cf_saddle_used_schur(const cf_saddle *s) { return s ? s->used_schur : 0; }

double cf_saddle_residual(const cf_saddle *s) { return s ? s->residual : 0.0; }

void cf_saddle_destroy(cf_saddle **ps)
{
    if (!ps || !*ps) return;
    cf_saddle *s = *ps;
    cf_context *ctx = s->ctx;
    int64_t nnzb = s->b ? cf_sparse_nnz(s->b) : 0, nnza = s->a ? cf_sparse_nnz(s->a) : 0;
    size_t n = (size_t)s->n, m = (size_t)s->m;
    cf_cholesky_destroy(&s->chol);
    cf_lu_destroy(&s->lu);
    cf_sparse_destroy(&s->s);
    cf_sparse_destroy(&s->k);
    CFI_FREE(ctx, s->k_slot, s->k_ntrip);
    CFI_FREE(ctx, s->k_vals, s->k_ntrip);
    CFI_FREE(ctx, s->s_slot_a, nnza);
    CFI_FREE(ctx, s->pair_slot, s->npairs);
    CFI_FREE(ctx, s->bt_ptr, m + 1);
    CFI_FREE(ctx, s->bt_col, nnzb);
    CFI_FREE(ctx, s->bt_src, nnzb);
    CFI_FREE(ctx, s->c, m);
    CFI_FREE(ctx, s->rf, n);
    CFI_FREE(ctx, s->rg, m);
    CFI_FREE(ctx, s->dx, n);
    CFI_FREE(ctx, s->dy, m);
    CFI_FREE(ctx, s->tn, n);
    CFI_FREE(ctx, s->tm, m);
    CFI_FREE(ctx, s->zn, n + m);
    cf_sparse_destroy(&s->a);
    cf_sparse_destroy(&s->b);
    CFI_FREE(ctx, s, 1);
    *ps = NULL;
}

static cf_status check_shapes(cf_context *ctx, const cf_sparse *a, const cf_sparse *b, const char *what)
{
    if (!a || !b) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: A or B is NULL", what);
    if (a->nrows != a->ncols || a->nrows < 1)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: A is %d x %d, need square", what, a->nrows, a->ncols);
    if (b->ncols != a->ncols)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: B has %d columns, A has %d", what, b->ncols, a->ncols);
    return CF_OK;
}

/* Pattern of S = A + B^T B (upper triangle) with the slots of every A entry
 * and every pair of entries in a row of B. */
static cf_status build_schur_pattern(cf_saddle *s)
{
    cf_context *ctx = s->ctx;
    const cf_sparse *a = s->a;
    int64_t nnza = cf_sparse_nnz(a), ntrip = nnza + s->npairs;
    int32_t *ti = CFI_ALLOC(ctx, int32_t, (size_t)ntrip);
    int32_t *tj = CFI_ALLOC(ctx, int32_t, (size_t)ntrip);
    int64_t *slot = CFI_ALLOC(ctx, int64_t, (size_t)ntrip);
    s->s_slot_a = CFI_ALLOC(ctx, int64_t, (size_t)nnza);
    s->pair_slot = CFI_ALLOC(ctx, int64_t, (size_t)s->npairs);
    cf_status st = CF_ERR_NOMEM;
    if (ti && tj && slot && s->s_slot_a && s->pair_slot) {
        int64_t k = 0;
        /* A's upper triangle */
        for (int32_t j = 0; j < a->ncols; ++j)
            for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) {
                int32_t i = a->rowind[p];
                if (i > j) continue;
                ti[k] = i;
                tj[k++] = j;
            }
        int64_t kpairs = k;
        for (int32_t r = 0; r < s->m; ++r)
            for (int32_t p = s->bt_ptr[r]; p < s->bt_ptr[r + 1]; ++p)
                for (int32_t q = p; q < s->bt_ptr[r + 1]; ++q) {
                    ti[k] = s->bt_col[p]; /* rows of B^T sorted: bt_col[p] <= bt_col[q] */
                    tj[k++] = s->bt_col[q];
                }
        st = cf_sparse_from_triplets(ctx, s->n, s->n, k, ti, tj, NULL, 1, &s->s, slot);
        if (st == CF_OK) {
            s->s->upper_only = 1;
            int64_t t = 0;
            for (int32_t j = 0; j < a->ncols; ++j)
                for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p)
                    s->s_slot_a[p] = a->rowind[p] > j ? -1 : slot[t++];
            memcpy(s->pair_slot, slot + kpairs, (size_t)s->npairs * sizeof *slot);
        }
    }
    CFI_FREE(ctx, ti, ntrip);
    CFI_FREE(ctx, tj, ntrip);
    CFI_FREE(ctx, slot, ntrip);
    return st;
}

cf_status cf_saddle_create(cf_context *ctx, const cf_sparse *a, const cf_sparse *b, const cf_saddle_options *options,
                           cf_saddle **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "saddle create: out is NULL");
    *out = NULL;
    cf_status st = check_shapes(ctx, a, b, "saddle create");
    if (st != CF_OK) return st;
    cf_saddle_options opt;
    cf_saddle_options_default(&opt);
    if (options) opt = *options;
    if (opt.block_size < 1 || a->ncols % opt.block_size != 0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "saddle create: block size %d does not divide n = %d", opt.block_size,
                         a->ncols);
    if (opt.refinement_steps < 0 || opt.refinement_steps > 100)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "saddle create: refinement steps %d outside 0..100", opt.refinement_steps);
    if (b->upper_only) return cfi_error(ctx, CF_ERR_INVALID_ARG, "saddle create: B must store every entry");
    cf_saddle *s = CFI_ALLOC(ctx, cf_saddle, 1);
    if (!s) return CF_ERR_NOMEM;
    s->ctx = ctx;
    s->n = a->ncols;
    s->m = b->nrows;
    s->opt = opt;
    size_t n = (size_t)s->n, m = (size_t)s->m;
    int64_t nnzb = cf_sparse_nnz(b);
    if ((st = cfi_sparse_alloc(ctx, a->nrows, a->ncols, cf_sparse_nnz(a), &s->a)) != CF_OK) goto fail;
    memcpy(s->a->colptr, a->colptr, (n + 1) * sizeof *a->colptr);
    memcpy(s->a->rowind, a->rowind, (size_t)cf_sparse_nnz(a) * sizeof *a->rowind);
    s->a->symmetric = 1;
    s->a->upper_only = a->upper_only;
    if ((st = cfi_sparse_alloc(ctx, b->nrows, b->ncols, nnzb, &s->b)) != CF_OK) goto fail;
    memcpy(s->b->colptr, b->colptr, (n + 1) * sizeof *b->colptr);
    memcpy(s->b->rowind, b->rowind, (size_t)nnzb * sizeof *b->rowind);
    s->c = CFI_ALLOC(ctx, double, m);
    s->bt_ptr = CFI_ALLOC(ctx, int32_t, m + 1);
    s->bt_col = CFI_ALLOC(ctx, int32_t, (size_t)nnzb);
    s->bt_src = CFI_ALLOC(ctx, int64_t, (size_t)nnzb);
    s->rf = CFI_ALLOC(ctx, double, n);
    s->rg = CFI_ALLOC(ctx, double, m);
    s->dx = CFI_ALLOC(ctx, double, n);
    s->dy = CFI_ALLOC(ctx, double, m);
    s->tn = CFI_ALLOC(ctx, double, n);
    s->tm = CFI_ALLOC(ctx, double, m);
    s->zn = CFI_ALLOC(ctx, double, n + m);
    if (!s->c || !s->bt_ptr || !s->bt_col || !s->bt_src || !s->rf || !s->rg || !s->dx || !s->dy || !s->tn || !s->tm ||
        !s->zn) {
        st = CF_ERR_NOMEM;
        goto fail;
    }
    /* rows of B by a counting sort (columns visited in order: sorted within a row) */
    for (int64_t p = 0; p < nnzb; ++p) s->bt_ptr[b->rowind[p] + 1]++;
    for (size_t r = 0; r < m; ++r) s->bt_ptr[r + 1] += s->bt_ptr[r];
    for (int32_t j = 0; j < b->ncols; ++j)
        for (int32_t p = b->colptr[j]; p < b->colptr[j + 1]; ++p) {
            int32_t q = s->bt_ptr[b->rowind[p]]++;
            s->bt_col[q] = j;
            s->bt_src[q] = p;
        }
    for (size_t r = m; r > 0; --r) s->bt_ptr[r] = s->bt_ptr[r - 1];
    s->bt_ptr[0] = 0;
    /* pairs i <= j within each row of B: k (k + 1) / 2 per row of k entries */
    s->npairs = 0;
    for (size_t r = 0; r < m; ++r) {
        int64_t kr = s->bt_ptr[r + 1] - s->bt_ptr[r];
        s->npairs += kr * (kr + 1) / 2;
        if (s->npairs > SCHUR_MAX_PAIRS) break;
    }
    s->schur_possible = !opt.force_lu && s->npairs <= SCHUR_MAX_PAIRS;
    if (!s->schur_possible) s->npairs = 0;
    if (s->schur_possible) {
        if ((st = build_schur_pattern(s)) != CF_OK) goto fail;
        cf_cholesky_options co;
        cf_cholesky_options_default(&co);
        co.block_size = opt.block_size;
        if ((st = cf_cholesky_create(ctx, s->s, &co, &s->chol)) != CF_OK) goto fail;
    }
    *out = s;
    return CF_OK;
fail:
    cf_saddle_destroy(&s);
    return st;
}

/* Full matrix K = [[A, B^T], [B, -C]] assembled through a slot map so that
 * new values are refilled; made on first need. */
static cf_status build_full(cf_saddle *s)
{
    cf_context *ctx = s->ctx;
    const cf_sparse *a = s->a, *b = s->b;
    int64_t nnza = cf_sparse_nnz(a), nnzb = cf_sparse_nnz(b);
    int64_t ntrip = 2 * nnza + 2 * nnzb + s->m;
    int32_t *ti = CFI_ALLOC(ctx, int32_t, (size_t)ntrip);
    int32_t *tj = CFI_ALLOC(ctx, int32_t, (size_t)ntrip);
    cf_status st = CF_ERR_NOMEM;
    if (ti && tj) {
        int64_t k = 0;
        for (int32_t j = 0; j < a->ncols; ++j)
            for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) {
                int32_t i = a->rowind[p];
                if (a->upper_only && i > j) continue;
                ti[k] = i; tj[k++] = j;
                if (a->upper_only && i < j) { ti[k] = j; tj[k++] = i; }
            }
        for (int32_t j = 0; j < b->ncols; ++j)
            for (int32_t p = b->colptr[j]; p < b->colptr[j + 1]; ++p) {
                ti[k] = s->n + b->rowind[p]; tj[k++] = j;
                ti[k] = j; tj[k++] = s->n + b->rowind[p];
            }
        for (int32_t r = 0; r < s->m; ++r) { ti[k] = s->n + r; tj[k++] = s->n + r; }
        s->k_ntrip = k;
        s->k_slot = CFI_ALLOC(ctx, int64_t, (size_t)k);
        s->k_vals = CFI_ALLOC(ctx, double, (size_t)k);
        if (s->k_slot && s->k_vals)
            st = cf_sparse_from_triplets(ctx, s->n + s->m, s->n + s->m, k, ti, tj, NULL, 1, &s->k, s->k_slot);
    }
    CFI_FREE(ctx, ti, ntrip);
    CFI_FREE(ctx, tj, ntrip);
    return st;
}

static void refill_full(cf_saddle *s)
{
    const cf_sparse *a = s->a, *b = s->b;
    int64_t k = 0;
    for (int32_t j = 0; j < a->ncols; ++j)
        for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) {
            int32_t i = a->rowind[p];
            if (a->upper_only && i > j) continue;
            s->k_vals[k++] = a->values[p];
            if (a->upper_only && i < j) s->k_vals[k++] = a->values[p];
        }
    for (int64_t p = 0; p < cf_sparse_nnz(b); ++p) {
        s->k_vals[k++] = b->values[p];
        s->k_vals[k++] = b->values[p];
    }
    for (int32_t r = 0; r < s->m; ++r) s->k_vals[k++] = -s->c[r];
    cf_sparse_refill(s->k, s->k_ntrip, s->k_slot, s->k_vals);
}

static cf_status factorize_lu(cf_saddle *s)
{
    cf_status st;
    if (!s->k && (st = build_full(s)) != CF_OK) return st;
    refill_full(s);
    if (!s->lu) {
        st = cf_lu_create(s->ctx, s->k, &s->lu);
        /* refinement happens against the full system in cf_saddle_solve */
        cfi_lu_set_refinement_steps(s->lu, 0);
        return st;
    }
    return cf_lu_factorize(s->lu, s->k);
}

/* S = A + B^T C^-1 B into the fixed pattern. */
static void fill_schur(cf_saddle *s)
{
    cf_sparse *S = s->s;
    const cf_sparse *a = s->a;
    const double *bv = s->b->values;
    memset(S->values, 0, (size_t)cf_sparse_nnz(S) * sizeof *S->values);
    for (int64_t p = 0; p < cf_sparse_nnz(a); ++p)
        if (s->s_slot_a[p] >= 0) S->values[s->s_slot_a[p]] += a->values[p];
    int64_t t = 0;
    for (int32_t r = 0; r < s->m; ++r) {
        double inv = 1.0 / s->c[r];
        for (int32_t p = s->bt_ptr[r]; p < s->bt_ptr[r + 1]; ++p) {
            double bp = bv[s->bt_src[p]] * inv;
            for (int32_t q = p; q < s->bt_ptr[r + 1]; ++q) S->values[s->pair_slot[t++]] += bp * bv[s->bt_src[q]];
        }
    }
}

cf_status cf_saddle_factorize(cf_saddle *s, const cf_sparse *a, const cf_sparse *b, const double *c_diag)
{
    if (!s) return CF_ERR_INVALID_ARG;
    cf_context *ctx = s->ctx;
    s->factorized = 0;
    cf_status st = check_shapes(ctx, a, b, "saddle factorise");
    if (st != CF_OK) return st;
    if (a->ncols != s->n || b->nrows != s->m || cf_sparse_nnz(a) != cf_sparse_nnz(s->a) ||
        cf_sparse_nnz(b) != cf_sparse_nnz(s->b) ||
        memcmp(a->colptr, s->a->colptr, ((size_t)s->n + 1) * sizeof *a->colptr) != 0 ||
        memcmp(b->colptr, s->b->colptr, ((size_t)s->n + 1) * sizeof *b->colptr) != 0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "saddle factorise: pattern of A or B differs from creation");
    int64_t bad = cfi_first_nonfinite(a->values, cf_sparse_nnz(a));
    if (bad >= 0) return cfi_error(ctx, CF_ERR_NUMERICAL, "saddle factorise: A value %lld is not finite", (long long)bad);
    bad = cfi_first_nonfinite(b->values, cf_sparse_nnz(b));
    if (bad >= 0) return cfi_error(ctx, CF_ERR_NUMERICAL, "saddle factorise: B value %lld is not finite", (long long)bad);
    int c_positive = c_diag != NULL;
    for (int32_t r = 0; c_diag && r < s->m; ++r) {
        if (!isfinite(c_diag[r]) || c_diag[r] < 0.0)
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "saddle factorise: C[%d] = %g, need finite and >= 0", r, c_diag[r]);
        if (c_diag[r] == 0.0) c_positive = 0;
    }
    memcpy(s->a->values, a->values, (size_t)cf_sparse_nnz(a) * sizeof *a->values);
    memcpy(s->b->values, b->values, (size_t)cf_sparse_nnz(b) * sizeof *b->values);
    if (c_diag) memcpy(s->c, c_diag, (size_t)s->m * sizeof *s->c);
    else memset(s->c, 0, (size_t)s->m * sizeof *s->c);

    s->used_schur = 0;
    if (c_positive && s->schur_possible) {
        fill_schur(s);
        st = cf_cholesky_factorize(s->chol, s->s);
        if (st == CF_OK) {
            s->used_schur = 1;
            s->factorized = 1;
            return CF_OK;
        }
        if (st != CF_ERR_NOT_POSDEF) return st;
        cfi_log(ctx, CF_LOG_INFO, "saddle: Schur complement not positive definite (%s); using LU", cf_context_message(ctx));
        cf_context_clear_error(ctx);
    }
    if ((st = factorize_lu(s)) != CF_OK) return st;
    s->factorized = 1;
    return CF_OK;
}

/* One solve of the full system with the current factorisation. */
static cf_status solve_once(cf_saddle *s, const double *f, const double *g, double *x, double *y)
{
    cf_status st;
    if (s->used_schur) {
        /* S x = f + B^T C^-1 g, y = C^-1 (B x - g) */
        for (int32_t r = 0; r < s->m; ++r) s->tm[r] = g[r] / s->c[r];
        memcpy(s->tn, f, (size_t)s->n * sizeof *f);
        const cf_sparse *b = s->b;
        for (int32_t j = 0; j < b->ncols; ++j)
            for (int32_t p = b->colptr[j]; p < b->colptr[j + 1]; ++p) s->tn[j] += b->values[p] * s->tm[b->rowind[p]];
        if ((st = cf_cholesky_solve(s->chol, 1, s->tn, x)) != CF_OK) return st;
        cf_sparse_multiply(b, x, y);
        for (int32_t r = 0; r < s->m; ++r) y[r] = (y[r] - g[r]) / s->c[r];
        return CF_OK;
    }
    memcpy(s->zn, f, (size_t)s->n * sizeof *f);
    memcpy(s->zn + s->n, g, (size_t)s->m * sizeof *g);
    if ((st = cf_lu_solve(s->lu, s->zn, s->zn)) != CF_OK) return st;
    memcpy(x, s->zn, (size_t)s->n * sizeof *x);
    memcpy(y, s->zn + s->n, (size_t)s->m * sizeof *y);
    return CF_OK;
}

/* rf = f - A x - B^T y, rg = g - B x + C y; returns the 2-norm of (rf, rg). */
static double full_residual(cf_saddle *s, const double *f, const double *g, const double *x, const double *y)
{
    const cf_sparse *b = s->b;
    cf_sparse_multiply(s->a, x, s->rf);
    for (int32_t i = 0; i < s->n; ++i) s->rf[i] = f[i] - s->rf[i];
    for (int32_t j = 0; j < b->ncols; ++j)
        for (int32_t p = b->colptr[j]; p < b->colptr[j + 1]; ++p) s->rf[j] -= b->values[p] * y[b->rowind[p]];
    cf_sparse_multiply(b, x, s->rg);
    double sum = 0.0;
    for (int32_t r = 0; r < s->m; ++r) {
        s->rg[r] = g[r] - s->rg[r] + s->c[r] * y[r];
        sum += s->rg[r] * s->rg[r];
    }
    for (int32_t i = 0; i < s->n; ++i) sum += s->rf[i] * s->rf[i];
    return sqrt(sum);
}

cf_status cf_saddle_solve(cf_saddle *s, const double *f, const double *g, double *x, double *y)
{
    if (!s) return CF_ERR_INVALID_ARG;
    cf_context *ctx = s->ctx;
    if (!f || !x || (s->m > 0 && (!g || !y))) return cfi_error(ctx, CF_ERR_INVALID_ARG, "saddle solve: NULL vector");
    if (!s->factorized) return cfi_error(ctx, CF_ERR_INVALID_ARG, "saddle solve: no successful factorisation");
    int64_t bad = cfi_first_nonfinite(f, s->n);
    if (bad >= 0) return cfi_error(ctx, CF_ERR_NUMERICAL, "saddle solve: f[%lld] is not finite", (long long)bad);
    bad = cfi_first_nonfinite(g, s->m);
    if (bad >= 0) return cfi_error(ctx, CF_ERR_NUMERICAL, "saddle solve: g[%lld] is not finite", (long long)bad);
    double rhs = 0.0;
    for (int32_t i = 0; i < s->n; ++i) rhs += f[i] * f[i];
    for (int32_t r = 0; r < s->m; ++r) rhs += g[r] * g[r];
    rhs = sqrt(rhs);
    cf_status st = solve_once(s, f, g, x, y);
    if (st != CF_OK) return st;
    if (rhs == 0.0) { s->residual = 0.0; return CF_OK; }
    double res = full_residual(s, f, g, x, y) / rhs;
    /* iterative refinement on the full system; stops early once the
     * residual is at rounding level or stops decreasing */
    for (int32_t it = 0; it < s->opt.refinement_steps && res > 1e-14; ++it) {
        if ((st = solve_once(s, s->rf, s->rg, s->dx, s->dy)) != CF_OK) return st;
        for (int32_t i = 0; i < s->n; ++i) x[i] += s->dx[i];
        for (int32_t r = 0; r < s->m; ++r) y[r] += s->dy[r];
        double next = full_residual(s, f, g, x, y) / rhs;
        if (!(next < res) && next <= SADDLE_TARGET_RESIDUAL) { res = next; break; }
        res = next;
    }
    s->residual = res;
    bad = cfi_first_nonfinite(x, s->n);
    if (bad < 0) bad = cfi_first_nonfinite(y, s->m);
    if (bad >= 0 || !isfinite(res))
        return cfi_error(ctx, CF_ERR_NUMERICAL, "saddle solve: solution is not finite");
    if (res > SADDLE_TARGET_RESIDUAL)
        cfi_log(ctx, CF_LOG_WARNING, "saddle solve: relative residual %.3g after %d refinement steps (%s)", res,
                s->opt.refinement_steps, s->used_schur ? "Schur complement" : "LU");
    return CF_OK;
}
