/*
 * Anderson acceleration of a fixed-point iteration x <- G(x) (Anderson
 * 1965; "type II" in the form of Walker & Ni 2011, Sec. 3, and Fang & Saad
 * 2009): with f = G(x) - x and the last m differences of f and of G(x)
 * between consecutive calls, dF and dG,
 *     gamma = argmin |f - dF gamma|_2,    x_next = G(x) - dG gamma.
 * The least-squares problem is solved through its normal equations
 * (dF^T dF) gamma = dF^T f, Cholesky with a relative Tikhonov shift of 1e-10
 * times the largest diagonal entry, which keeps nearly dependent history
 * columns from blowing gamma up (the caller's safeguard, e.g. an energy
 * test, decides whether to take x_next).
 *
 * The history is a circular buffer of `depth` columns; dF^T dF is kept
 * between calls by slot, so a call computes only the new column's dot
 * products. One pass over the n entries pushes the new difference pair and
 * accumulates those dots and dF^T f; a second pass mixes the candidate.
 * (Recomputing the whole Gram matrix cost 1.8 ms per iteration of the
 * stretch-bend edit on armadillo_26k, 17 % of the iteration.) Everything is
 * allocated at create: a step allocates nothing.
 *
 * Moved here from the stretch-bend editing method, unchanged in arithmetic
 * (the edit's results are bit-identical).
 */
#include "linalg/linalg_internal.h"

#include <math.h>
#include <string.h>

struct cf_anderson {
    cf_context *ctx;
    int64_t n;
    int32_t depth;
    int32_t count;        /* valid history columns */
    int32_t next;         /* next column to overwrite */
    int32_t have_prev;    /* fprev, gprev hold the previous call's f, G(x) */
    double *df, *dg;      /* depth columns of n: differences of f and of G(x) */
    double *fprev, *gprev;
    double *gram;         /* depth x depth, dF^T dF by history slot */
    double *chol;         /* depth x depth scratch: Cholesky factor */
    double *gram_row;     /* depth: dots of the new column */
    double *rhs;          /* depth: dF^T f */
    double *gamma;        /* depth */
    const double **df_col, **dg_col; /* depth column pointers */
};

void cf_anderson_destroy(cf_anderson **aa)
{
    if (!aa || !*aa) return;
    cf_anderson *a = *aa;
    cf_context *ctx = a->ctx;
    size_t n = (size_t)a->n, m = (size_t)a->depth;
    CFI_FREE(ctx, a->df, m * n);
    CFI_FREE(ctx, a->dg, m * n);
    CFI_FREE(ctx, a->fprev, n);
    CFI_FREE(ctx, a->gprev, n);
    CFI_FREE(ctx, a->gram, m * m);
    CFI_FREE(ctx, a->chol, m * m);
    CFI_FREE(ctx, a->gram_row, m);
    CFI_FREE(ctx, a->rhs, m);
    CFI_FREE(ctx, a->gamma, m);
    CFI_FREE(ctx, a->df_col, m);
    CFI_FREE(ctx, a->dg_col, m);
    cfi_free(ctx, a, sizeof *a);
    *aa = NULL;
}

cf_status cf_anderson_create(cf_context *ctx, int64_t n, int32_t depth, cf_anderson **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "anderson: output is NULL");
    *out = NULL;
    if (n < 1) return cfi_error(ctx, CF_ERR_INVALID_ARG, "anderson: vector length %lld must be >= 1", (long long)n);
    if (depth < 1 || depth > CF_ANDERSON_MAX_DEPTH)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "anderson: depth %d not in [1, %d]", (int)depth,
                         CF_ANDERSON_MAX_DEPTH);
    cf_anderson *a = cfi_malloc(ctx, sizeof *a);
    if (!a) return CF_ERR_NOMEM;
    memset(a, 0, sizeof *a);
    a->ctx = ctx;
    a->n = n;
    a->depth = depth;
    size_t nn = (size_t)n, m = (size_t)depth;
    a->df = CFI_ALLOC(ctx, double, m * nn);
    a->dg = CFI_ALLOC(ctx, double, m * nn);
    a->fprev = CFI_ALLOC(ctx, double, nn);
    a->gprev = CFI_ALLOC(ctx, double, nn);
    a->gram = CFI_ALLOC(ctx, double, m * m);
    a->chol = CFI_ALLOC(ctx, double, m * m);
    a->gram_row = CFI_ALLOC(ctx, double, m);
    a->rhs = CFI_ALLOC(ctx, double, m);
    a->gamma = CFI_ALLOC(ctx, double, m);
    a->df_col = CFI_ALLOC(ctx, const double *, m);
    a->dg_col = CFI_ALLOC(ctx, const double *, m);
    if (!a->df || !a->dg || !a->fprev || !a->gprev || !a->gram || !a->chol || !a->gram_row || !a->rhs || !a->gamma ||
        !a->df_col || !a->dg_col) {
        cf_anderson_destroy(&a);
        return CF_ERR_NOMEM;
    }
    for (int32_t b = 0; b < depth; ++b) {
        a->df_col[b] = a->df + (size_t)b * nn;
        a->dg_col[b] = a->dg + (size_t)b * nn;
    }
    *out = a;
    return CF_OK;
}

/* Stale entries of the kept Gram matrix are never read: the k-th push after
 * a reset writes row and column k for every slot below it. */
void cf_anderson_reset(cf_anderson *aa)
{
    if (!aa) return;
    aa->count = 0;
    aa->next = 0;
    aa->have_prev = 0;
}

int32_t cf_anderson_history(const cf_anderson *aa) { return aa ? aa->count : 0; }

/* Names the first entry where G(x) - x is not finite (or says the squares
 * overflowed) and resets, so the next call starts a fresh history. */
static cf_status nonfinite(cf_anderson *a, const double *x, const double *g)
{
    cf_anderson_reset(a);
    for (int64_t i = 0; i < a->n; ++i)
        if (!isfinite(g[i] - x[i]))
            return cfi_error(a->ctx, CF_ERR_NUMERICAL, "anderson step: G(x) - x is not finite at entry %lld",
                             (long long)i);
    return cfi_error(a->ctx, CF_ERR_NUMERICAL, "anderson step: the differences of G(x) - x overflow");
}

cf_status cf_anderson_step(cf_anderson *aa, const double *x, const double *g, double *out, int32_t *mixed)
{
    if (!aa) return CF_ERR_INVALID_ARG;
    if (mixed) *mixed = 0;
    if (!x || !g || !out || !mixed) return cfi_error(aa->ctx, CF_ERR_INVALID_ARG, "anderson step: NULL argument");
    size_t n = (size_t)aa->n;
    if (!aa->have_prev) {
        double sq = 0.0;
        for (size_t i = 0; i < n; ++i) {
            double f = g[i] - x[i];
            aa->fprev[i] = f;
            aa->gprev[i] = g[i];
            sq += f * f;
        }
        if (!isfinite(sq)) return nonfinite(aa, x, g);
        aa->have_prev = 1;
        return CF_OK;
    }
    int32_t slot = aa->next;
    aa->next = (aa->next + 1) % aa->depth;
    if (aa->count < aa->depth) ++aa->count;
    int32_t m = aa->count; /* the valid slots are 0 .. m-1 */
    int32_t ld = aa->depth;
    double *df_new = aa->df + (size_t)slot * n, *dg_new = aa->dg + (size_t)slot * n;
    const double *const *df_col = aa->df_col;
    double *gram_row = aa->gram_row, *rhs = aa->rhs, *gamma = aa->gamma;
    for (int32_t b = 0; b < m; ++b) gram_row[b] = rhs[b] = 0.0;
    for (size_t i = 0; i < n; ++i) {
        double f = g[i] - x[i];
        double dfi = f - aa->fprev[i];
        df_new[i] = dfi;
        dg_new[i] = g[i] - aa->gprev[i];
        aa->fprev[i] = f;
        aa->gprev[i] = g[i];
        for (int32_t b = 0; b < m; ++b) {
            double db = b == slot ? dfi : df_col[b][i];
            gram_row[b] += dfi * db;
            rhs[b] += db * f;
        }
    }
    if (!isfinite(gram_row[slot])) return nonfinite(aa, x, g);
    double *kept = aa->gram;
    for (int32_t b = 0; b < m; ++b) kept[slot * ld + b] = kept[b * ld + slot] = gram_row[b];
    /* Cholesky of the Gram matrix with a relative Tikhonov shift. */
    double *l = aa->chol;
    double big = 0.0;
    for (int32_t a = 0; a < m; ++a) big = fmax(big, kept[a * ld + a]);
    if (!(big > 0.0)) return CF_OK; /* f did not change: nothing to mix */
    for (int32_t a = 0; a < m; ++a) {
        for (int32_t b = 0; b <= a; ++b) {
            double v = kept[a * ld + b] + (a == b ? 1e-10 * big : 0.0);
            for (int32_t k = 0; k < b; ++k) v -= l[a * ld + k] * l[b * ld + k];
            if (a == b) {
                if (!(v > 0.0)) return CF_OK; /* numerically singular history */
                l[a * ld + a] = sqrt(v);
            } else {
                l[a * ld + b] = v / l[b * ld + b];
            }
        }
    }
    for (int32_t a = 0; a < m; ++a) {
        double v = rhs[a];
        for (int32_t k = 0; k < a; ++k) v -= l[a * ld + k] * gamma[k];
        gamma[a] = v / l[a * ld + a];
    }
    for (int32_t a = m - 1; a >= 0; --a) {
        double v = gamma[a];
        for (int32_t k = a + 1; k < m; ++k) v -= l[k * ld + a] * gamma[k];
        gamma[a] = v / l[a * ld + a];
    }
    for (int32_t a = 0; a < m; ++a)
        if (!isfinite(gamma[a])) return CF_OK;
    const double *const *dg_col = aa->dg_col;
    for (size_t i = 0; i < n; ++i) {
        double v = g[i];
        for (int32_t a = 0; a < m; ++a) v -= gamma[a] * dg_col[a][i];
        out[i] = v;
    }
    *mixed = 1;
    return CF_OK;
}
