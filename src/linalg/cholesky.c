/*
 * Sparse Cholesky through CHOLMOD: symbolic analysis once per pattern with
 * a fill-reducing ordering computed on the graph of blocks (the vertex
 * graph for matrices lifted to 3x3 / 4x4 blocks) and expanded to the full
 * matrix, supernodal or simplicial as CHOLMOD chooses, numeric
 * refactorisation on a zero-copy header over the cf_sparse arrays, optional
 * shift (A + sI via cholmod_factorize_p's beta), and solves with several
 * right-hand sides whose workspace is kept between calls.
 */
#include "linalg/linalg_internal.h"

#include <math.h>
#include <string.h>

/* Complex columns (2 per vertex) up to which the quaternion-block analysis
 * widens CHOLMOD's supernode amalgamation: at 164k / 655k vertices the
 * default gives a factor 15 % / 14 % smaller (49.0 -> 41.8 M, 218 -> 188 M
 * complex entries; 3.5 -> 3.0 GB) at the same speed, and no amalgamation
 * zeros (zrelax 0) another 7 % (175.7 M, 2.8 GB) at +5 % time (analyse). */
#define CFI_QUAT_WIDE_RELAX_MAX_COLUMNS 100000

struct cf_cholesky {
    cf_context *ctx;
    cholmod_common *common;
    cholmod_factor *factor;
    int32_t n;            /* real unknowns (4 nb for the quaternion forms) */
    int64_t nnz;          /* of the analysed pattern */
    int32_t ncols;        /* columns of the analysed pattern: n, or 2 nb for a cf_quat_sparse */
    int32_t *colptr;      /* analysed pattern's column pointers (ncols + 1), to detect a changed pattern */
    int factorized;       /* last numeric factorisation succeeded */
    cholmod_dense *x;     /* solve workspace, reused (cholmod_solve2) */
    cholmod_dense *y;
    cholmod_dense *e;
    cf_solver_timings timings;
    cfi_quat_map *quat;   /* quaternion_blocks: the factor is of the complex form */
    int32_t complex_form; /* the factor is of the complex form (quat, or created from a cf_quat_sparse) */
    int32_t quat_input;   /* created by cf_cholesky_create_quat */
    double *zwork;        /* complex right-hand sides, n doubles per column */
    int32_t zwork_cols;
    double factor_entries; /* entries of L from the analysis (complex ones with quat), for messages */
};

void cf_cholesky_options_default(cf_cholesky_options *options)
{
    if (!options) return;
    options->block_size = 1;
    options->ordering = CF_ORDERING_AUTO;
    options->quaternion_blocks = 0;
}

int32_t cf_cholesky_size(const cf_cholesky *chol) { return chol ? chol->n : 0; }

cf_context *cfi_cholesky_context(const cf_cholesky *chol) { return chol ? chol->ctx : NULL; }

void cf_cholesky_timings(const cf_cholesky *chol, cf_solver_timings *timings)
{
    if (!timings) return;
    if (!chol) { memset(timings, 0, sizeof *timings); return; }
    *timings = chol->timings;
}

void cf_cholesky_destroy(cf_cholesky **pchol)
{
    if (!pchol || !*pchol) return;
    cf_cholesky *chol = *pchol;
    cf_context *ctx = chol->ctx;
    if (chol->common) {
        cholmod_free_factor(&chol->factor, chol->common);
        cholmod_free_dense(&chol->x, chol->common);
        cholmod_free_dense(&chol->y, chol->common);
        cholmod_free_dense(&chol->e, chol->common);
    }
    CFI_FREE(ctx, chol->colptr, (size_t)chol->ncols + 1);
    cfi_quat_map_destroy(ctx, &chol->quat);
    CFI_FREE(ctx, chol->zwork, (size_t)chol->n * chol->zwork_cols);
    CFI_FREE(ctx, chol, 1);
    *pchol = NULL;
}

/* Pattern of the block graph: entry (I, J), I <= J, for every stored entry
 * (i, j), i <= j, of a, with I = i / b, J = j / b. Upper triangle only. */
static cf_status block_pattern(cf_context *ctx, const cf_sparse *a, int32_t b, cf_sparse **out)
{
    *out = NULL;
    int32_t nb = a->ncols / b;
    int64_t cap = a->colptr[a->ncols];
    int32_t *bi = CFI_ALLOC(ctx, int32_t, (size_t)cap);
    int32_t *bj = CFI_ALLOC(ctx, int32_t, (size_t)cap);
    int32_t *mark = CFI_ALLOC(ctx, int32_t, (size_t)nb);
    cf_status st = CF_ERR_NOMEM;
    if (bi && bj && mark) {
        int64_t k = 0;
        for (int32_t I = 0; I < nb; ++I) mark[I] = -1;
        for (int32_t J = 0; J < nb; ++J)
            for (int32_t j = J * b; j < (J + 1) * b; ++j)
                for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) {
                    int32_t i = a->rowind[p];
                    if (i > j) continue;
                    int32_t I = i / b;
                    if (mark[I] == J) continue;
                    mark[I] = J;
                    /* i <= j only bounds I <= J up to the block; keep the upper triangle */
                    bi[k] = I < J ? I : J;
                    bj[k++] = I < J ? J : I;
                }
        st = cf_sparse_from_triplets(ctx, nb, nb, k, bi, bj, NULL, 1, out, NULL);
        if (st == CF_OK) (*out)->upper_only = 1;
    }
    CFI_FREE(ctx, bi, cap);
    CFI_FREE(ctx, bj, cap);
    CFI_FREE(ctx, mark, nb);
    return st;
}

/* Symbolic analysis of the block pattern with one ordering method; the
 * factor carries the permutation, Common->fl / lnz its flop and fill counts. */
static cholmod_factor *analyze_blocks(cholmod_sparse *view, int method, double *fl, double *lnz, cholmod_common *c)
{
    cfi_cholmod_reset_parameters(c);
    c->supernodal = CHOLMOD_SIMPLICIAL; /* symbolic only: we just want its permutation and counts */
    c->nmethods = 1;
    c->method[0].ordering = method;
    cholmod_factor *lb = cholmod_analyze(view, c);
    *fl = c->fl;
    *lnz = c->lnz;
    cfi_cholmod_reset_parameters(c);
    return lb;
}

/* FNV-1a over the block pattern: with the block and entry counts, the
 * key of the context's ordering cache. (A collision could only cost fill:
 * any permutation gives a correct factor.) */
static uint64_t pattern_hash(const cf_sparse *p)
{
    uint64_t h = 1469598103934665603ull;
    int64_t nnz = p->colptr[p->ncols];
    for (int32_t j = 0; j <= p->ncols; ++j) h = (h ^ (uint32_t)p->colptr[j]) * 1099511628211ull;
    for (int64_t k = 0; k < nnz; ++k) h = (h ^ (uint32_t)p->rowind[k]) * 1099511628211ull;
    return h;
}

/* The block ordering of method m (0: AMD, 1: METIS) of the block graph
 * `view` (key nb, nnz, hash), with its flop and fill counts: from the
 * context's cache when it holds this graph and method, else by a symbolic
 * analysis, whose result the cache then keeps (a failed cache allocation
 * only skips the caching). *perm points into the cache or into *own
 * (nb entries, freed by the caller). */
static cf_status graph_ordering(cf_cholesky *chol, cholmod_sparse *view, int32_t nb, int64_t nnz, uint64_t hash,
                                int m, const int32_t **perm, int32_t **own, double *fl, double *lnz)
{
    cf_context *ctx = chol->ctx;
    cholmod_common *c = chol->common;
    cfi_ordering_cache *cache = cfi_cholmod_ordering_cache(ctx);
    if (cache->perm[m] && cache->nb == nb && cache->nnz == nnz && cache->hash == hash) {
        *perm = cache->perm[m];
        *fl = cache->fl[m];
        *lnz = cache->lnz[m];
        return CF_OK;
    }
    cholmod_factor *lb = analyze_blocks(view, m ? CHOLMOD_METIS : CHOLMOD_AMD, fl, lnz, c);
    cf_status st = cfi_cholmod_check(ctx, c, lb != NULL,
                                     m ? "cholesky analyse (block graph, METIS)" : "cholesky analyse (block graph)");
    if (st == CF_OK) {
        int32_t *p = cfi_ordering_cache_store(ctx, nb, nnz, hash, m, *fl, *lnz);
        if (!p) p = *own = CFI_ALLOC(ctx, int32_t, (size_t)nb);
        if (p) {
            memcpy(p, lb->Perm, (size_t)nb * sizeof *p);
            *perm = p;
        } else {
            st = CF_ERR_NOMEM;
        }
    }
    cholmod_free_factor(&lb, c);
    return st;
}

/* Fill-reducing permutation of the block graph, expanded to a: perm[b K + d]
 * = b perm_blocks[K] + d. rule_b: the block size of the real matrix whose
 * counts the rule below estimates (b, or 4 for the complex form of a
 * quaternion matrix, whose 2 x 2 blocks stand for 4 x 4 real ones, so that
 * both forms choose the same ordering). AUTO applies CHOLMOD's own rule (its default
 * nmethods = 0 strategy) with the counts of the expanded matrix: AMD first;
 * METIS is tried only if AMD's ordering is costly, i.e. fl / lnz >= 500 and
 * lnz / anz >= 5, and kept if it needs fewer flops. Expanding b x b blocks
 * multiplies lnz and anz by b^2 and the flops by b^3, so fl / lnz grows by
 * b: METIS, whose analysis is 5-7x slower here (176 vs 19 ms at 41k
 * vertices), is tried for the lifted 3x3 / 4x4 operators and large meshes,
 * where it pays back in every refactorisation (docs/linalg.md).
 * AUTO_REFACTORISED, for matrices that a flow refactorises at every step,
 * tries METIS from fl / lnz >= 200: there it needed 30-44 % fewer flops
 * (the complex form of spin-willmore's X on bob_5k, blade_slivers_8k,
 * mushroom_cap_2k, the built-in bumpy sphere: 230-414) or 2 % (armadillo,
 * 248), and below it more flops than AMD or at most 12 % fewer (every
 * other shared mesh: 51-189). The block orderings of the last block graph
 * are kept in the context, so that the matrices of one mesh (Laplacians,
 * the Dirac matrix) share them. */
static cf_status block_ordering(cf_cholesky *chol, const cf_sparse *a, int32_t b, int32_t rule_b, cf_ordering ordering,
                                int32_t *perm)
{
    cf_context *ctx = chol->ctx;
    cf_sparse *pattern = NULL;
    cf_status st = block_pattern(ctx, a, b, &pattern);
    if (st != CF_OK) return st;
    cholmod_sparse view;
    cfi_cholmod_view(pattern, 1, &view);
    view.xtype = CHOLMOD_PATTERN;
    view.x = NULL;
    int32_t nb = pattern->ncols;
    int64_t nnz = cf_sparse_nnz(pattern); /* upper triangle with diagonal */
    uint64_t hash = pattern_hash(pattern);
    const int32_t *pb = NULL, *pm = NULL;
    int32_t *own_b = NULL, *own_m = NULL;
    double fl = 0.0, lnz = 0.0, fl_metis = 0.0, lnz_metis = 0.0;
    int first = ordering == CF_ORDERING_METIS;
    st = graph_ordering(chol, &view, nb, nnz, hash, first, &pb, &own_b, &fl, &lnz);
    double costly = ordering == CF_ORDERING_AUTO ? 500.0 : ordering == CF_ORDERING_AUTO_REFACTORISED ? 200.0 : INFINITY;
    if (st == CF_OK && lnz > 0.0 && rule_b * fl / lnz >= costly && lnz / (double)nnz >= 5.0) {
        /* (the AMD ordering pb stays valid: storing METIS keeps the cache's AMD entry of the same graph) */
        st = graph_ordering(chol, &view, nb, nnz, hash, 1, &pm, &own_m, &fl_metis, &lnz_metis);
        if (st == CF_OK && fl_metis < fl) pb = pm;
    }
    if (st == CF_OK)
        for (int32_t K = 0; K < nb; ++K)
            for (int32_t d = 0; d < b; ++d) perm[b * K + d] = b * pb[K] + d;
    CFI_FREE(ctx, own_b, nb);
    CFI_FREE(ctx, own_m, nb);
    cf_sparse_destroy(&pattern);
    return st;
}

static cf_status check_matrix(cf_context *ctx, const cf_sparse *a, const char *what)
{
    if (!a) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: matrix is NULL", what);
    if (a->nrows != a->ncols) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: matrix is %d x %d, not square", what, a->nrows, a->ncols);
    return CF_OK;
}

/* A factorisation object for n real unknowns whose analysed pattern has
 * ncols columns with column pointers colptr (kept to detect a changed
 * pattern at factorisation). */
static cf_status new_cholesky(cf_context *ctx, int32_t n, int32_t ncols, const int32_t *colptr, cf_cholesky **out)
{
    *out = NULL;
    cholmod_common *c = NULL;
    cf_status st = cfi_cholmod_common(ctx, &c);
    if (st != CF_OK) return st;
    cf_cholesky *chol = CFI_ALLOC(ctx, cf_cholesky, 1);
    if (!chol) return CF_ERR_NOMEM;
    chol->ctx = ctx;
    chol->common = c;
    chol->n = n;
    chol->ncols = ncols;
    chol->nnz = colptr[ncols];
    chol->colptr = CFI_ALLOC(ctx, int32_t, (size_t)ncols + 1);
    if (!chol->colptr) {
        cf_cholesky_destroy(&chol);
        return CF_ERR_NOMEM;
    }
    memcpy(chol->colptr, colptr, ((size_t)ncols + 1) * sizeof *chol->colptr);
    *out = chol;
    return CF_OK;
}

/* Symbolic analysis of `view` (the matrix CHOLMOD factorises: the real one,
 * or the complex form of a quaternion matrix) with the ordering of the
 * graph of b x b blocks of `blocks` (whose pattern is view's), expanded
 * (block_ordering; rule_b there). t0: start time for the timings. */
static cf_status analyse(cf_cholesky *chol, cholmod_sparse *view, const cf_sparse *blocks, int32_t b, int32_t rule_b,
                         cf_ordering ordering, double t0)
{
    cf_context *ctx = chol->ctx;
    cholmod_common *c = chol->common;
    cf_status st = CF_OK;
    int32_t *perm = NULL;
    size_t nperm = (size_t)blocks->ncols;
    if (ordering == CF_ORDERING_NATURAL) {
        cfi_cholmod_reset_parameters(c);
        c->nmethods = 1;
        c->method[0].ordering = CHOLMOD_NATURAL;
        c->postorder = 0;
        chol->factor = cholmod_analyze(view, c);
    } else {
        perm = CFI_ALLOC(ctx, int32_t, nperm);
        if (!perm) return CF_ERR_NOMEM;
        if ((st = block_ordering(chol, blocks, b, rule_b, ordering, perm)) != CF_OK) goto done;
        if (chol->quat) {
            /* the block order, expanded to 2 complex unknowns per block
             * (in place: the first pass reads ahead of what it writes, the
             * second behind) */
            int32_t nb = chol->n / 4;
            for (int32_t K = 0; K < nb; ++K) perm[K] = perm[4 * K] / 4;
            for (int32_t k = 2 * nb - 1; k >= 0; --k) perm[k] = 2 * perm[k / 2] + k % 2;
        }
        cfi_cholmod_reset_parameters(c);
        c->nmethods = 1;
        c->method[0].ordering = CHOLMOD_GIVEN;
        if (chol->complex_form && chol->n / 2 <= CFI_QUAT_WIDE_RELAX_MAX_COLUMNS) {
            /* Twice CHOLMOD's relaxed amalgamation (nrelax 4/16/48 -> 8/32/96,
             * zrelax 0.1/0.05 -> 0.2/0.1): the complex factor of a vertex-graph
             * matrix has many small supernodes whose BLAS calls cost more than
             * the explicit zeros that merging them adds. Measured per step of
             * the spin flow: spot_3k 7.6 -> 6.4 ms, armadillo_26k 78 -> 72 ms,
             * 10k-vertex sphere 46 -> 41 ms, 41k/164k within noise; three times
             * was slower, and for scalar Laplacians it is slower beyond 10k
             * vertices (docs/linalg.md). Beyond 50k vertices the explicit zeros
             * cost memory for no measured gain (docs/memory.md): CHOLMOD's
             * default there. */
            c->nrelax[0] = 8;
            c->nrelax[1] = 32;
            c->nrelax[2] = 96;
            c->zrelax[1] = 0.2;
            c->zrelax[2] = 0.1;
        } else if (chol->complex_form) {
            /* Beyond, no explicit zeros at all (zrelax 0; supernodes of
             * fewer than nrelax columns still merge): at 655k vertices X's
             * factor 188.4 -> 175.7 M complex entries (-190 MB, the flow's
             * peak 4429 -> 4248 MB) for +5 % in its factorisation; at 164k
             * 41.8 -> 38.7 M (docs/memory.md). */
            c->zrelax[0] = 0.0;
            c->zrelax[1] = 0.0;
            c->zrelax[2] = 0.0;
        }
        chol->factor = cholmod_analyze_p(view, perm, NULL, 0, c);
    }
    cfi_cholmod_reset_parameters(c);
    if ((st = cfi_cholmod_check(ctx, c, chol->factor != NULL, "cholesky analyse")) != CF_OK) goto done;
    /* a supernodal factor's size is its value array's (with the explicit
     * zeros of amalgamation); a simplicial one's the analysis's count */
    chol->factor_entries = chol->factor->is_super ? (double)chol->factor->xsize : c->lnz;
    chol->timings.analyze_seconds = cfi_now_seconds() - t0;
done:
    CFI_FREE(ctx, perm, nperm);
    return st;
}

cf_status cf_cholesky_create(cf_context *ctx, const cf_sparse *a, const cf_cholesky_options *options, cf_cholesky **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "cholesky create: out is NULL");
    *out = NULL;
    cf_status st = check_matrix(ctx, a, "cholesky create");
    if (st != CF_OK) return st;
    cf_cholesky_options opt;
    cf_cholesky_options_default(&opt);
    if (options) opt = *options;
    if (opt.block_size < 1 || a->ncols % opt.block_size != 0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "cholesky create: block size %d does not divide n = %d",
                         opt.block_size, a->ncols);
    if (opt.ordering < CF_ORDERING_AUTO || opt.ordering > CF_ORDERING_AUTO_REFACTORISED)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "cholesky create: unknown ordering %d", (int)opt.ordering);
    if (opt.quaternion_blocks && opt.block_size != 4)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "cholesky create: quaternion blocks need block size 4, not %d",
                         opt.block_size);

    double t0 = cfi_now_seconds();
    cf_cholesky *chol = NULL;
    if ((st = new_cholesky(ctx, a->ncols, a->ncols, a->colptr, &chol)) != CF_OK) return st;
    cholmod_sparse view;
    cfi_cholmod_view(a, 1, &view);
    if (opt.quaternion_blocks) {
        /* analyse the complex form's pattern (2 unknowns per block) */
        if ((st = cfi_quat_map_create(ctx, a, &chol->quat)) != CF_OK) goto fail;
        chol->complex_form = 1;
        cfi_quat_map_view(chol->quat, 0, &view);
    }
    if ((st = analyse(chol, &view, a, opt.block_size, opt.block_size, opt.ordering, t0)) != CF_OK) goto fail;
    *out = chol;
    return CF_OK;
fail:
    cf_cholesky_destroy(&chol);
    return st;
}

/* CHOLMOD header over a cf_quat_sparse (stype 1: its upper triangle). */
static void quat_sparse_view(const cf_quat_sparse *a, int with_values, cholmod_sparse *view)
{
    cfi_complex_upper_view(a->nb, a->colptr[2 * (size_t)a->nb], a->colptr, a->rowind, with_values ? a->values : NULL,
                           view);
}

static cf_status check_quat(cf_context *ctx, const cf_quat_sparse *a, const char *what)
{
    if (!a || !a->colptr) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: quaternion matrix is NULL", what);
    if (a->nb < 0 || (int64_t)4 * a->nb > INT32_MAX)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: %d quaternion blocks exceed int32 indices", what, a->nb);
    return CF_OK;
}

cf_status cf_cholesky_create_quat(cf_context *ctx, const cf_quat_sparse *a, const cf_cholesky_options *options,
                                  cf_cholesky **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "cholesky create: out is NULL");
    *out = NULL;
    cf_status st = check_quat(ctx, a, "cholesky create");
    if (st != CF_OK) return st;
    cf_cholesky_options opt;
    cf_cholesky_options_default(&opt);
    if (options) opt = *options;
    if (opt.ordering < CF_ORDERING_AUTO || opt.ordering > CF_ORDERING_AUTO_REFACTORISED)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "cholesky create: unknown ordering %d", (int)opt.ordering);
    double t0 = cfi_now_seconds();
    cf_cholesky *chol = NULL;
    if ((st = new_cholesky(ctx, 4 * a->nb, 2 * a->nb, a->colptr, &chol)) != CF_OK) return st;
    chol->complex_form = 1;
    chol->quat_input = 1;
    cholmod_sparse view;
    quat_sparse_view(a, 0, &view);
    /* the block graph from the complex pattern's 2 x 2 blocks is the real
     * form's graph of 4 x 4 blocks: same cache key, same ordering */
    cf_sparse pattern = {2 * a->nb, 2 * a->nb, a->colptr, a->rowind, NULL, 1, 1, ctx};
    if ((st = analyse(chol, &view, &pattern, 2, 4, opt.ordering, t0)) != CF_OK) goto fail;
    *out = chol;
    return CF_OK;
fail:
    cf_cholesky_destroy(&chol);
    return st;
}

static cf_status factorize_view(cf_cholesky *chol, cholmod_sparse *view, double shift, double t0);

static cf_status factorize(cf_cholesky *chol, const cf_sparse *a, double shift)
{
    if (!chol) return CF_ERR_INVALID_ARG;
    cf_context *ctx = chol->ctx;
    chol->factorized = 0;
    cf_status st = check_matrix(ctx, a, "cholesky factorise");
    if (st != CF_OK) return st;
    if (chol->quat_input)
        return cfi_error(ctx, CF_ERR_INVALID_ARG,
                         "cholesky factorise: analysed from a quaternion matrix in complex form (cf_cholesky_factorize_quat)");
    if (a->ncols != chol->n || a->colptr[a->ncols] != chol->nnz ||
        memcmp(a->colptr, chol->colptr, ((size_t)chol->n + 1) * sizeof *chol->colptr) != 0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "cholesky factorise: pattern differs from the analysed one");
    if (!isfinite(shift)) return cfi_error(ctx, CF_ERR_NUMERICAL, "cholesky factorise: non-finite shift");
    int64_t bad = cfi_first_nonfinite(a->values, chol->nnz);
    if (bad >= 0) {
        int32_t j = 0;
        while (a->colptr[j + 1] <= bad) ++j;
        return cfi_error(ctx, CF_ERR_NUMERICAL, "cholesky factorise: entry (%d, %d) is not finite",
                         a->rowind[bad], j);
    }
    double t0 = cfi_now_seconds();
    cholmod_sparse view;
    if (chol->quat) {
        /* the Dirac matrices are exact left-multiplication blocks; allow
         * rounding from a caller's own assembly */
        if ((st = cfi_quat_map_fill(ctx, chol->quat, a, 1e-12)) != CF_OK) return st;
        cfi_quat_map_view(chol->quat, 1, &view);
    } else {
        cfi_cholmod_view(a, 1, &view);
    }
    return factorize_view(chol, &view, shift, t0);
}

/* The numeric factorisation of view (A, or its complex form), with the
 * failures named for the caller's real matrix. */
static cf_status factorize_view(cf_cholesky *chol, cholmod_sparse *view, double shift, double t0)
{
    cf_context *ctx = chol->ctx;
    cf_status st = CF_OK;
    cholmod_common *c = chol->common;
    cfi_cholmod_apply_threads(ctx); /* the context's OpenMP setting (cf_context_set_threads) */
    c->status = CHOLMOD_OK;
    cfi_cholmod_clear_message();
    /* the supernodal numeric factorisation is the first BLAS call
     * (LAPACK potrf, syrk/herk, gemm, trsm): OpenBLAS's buffer first */
    if (chol->factor->is_super && (st = cfi_blas_reserve(ctx, "cholesky factorise")) != CF_OK) return st;
    double beta[2] = {shift, 0.0};
    int blas_threads = cfi_blas_threads_enter(ctx); /* one OpenBLAS thread by default (cf_context_set_threads) */
    int ok = cholmod_factorize_p(view, beta, NULL, 0, chol->factor, c);
    cfi_blas_threads_leave(blas_threads);
    chol->timings.factorize_seconds = cfi_now_seconds() - t0;
    if (c->status == CHOLMOD_NOT_POSDEF || (ok && chol->factor->minor < chol->factor->n)) {
        /* L->minor is the column (in the permuted order) where the pivot
         * failed; report it and the original column it came from */
        size_t minor = chol->factor->minor;
        const int *p = chol->factor->Perm;
        int32_t col = (p && minor < chol->factor->n) ? p[minor] : (int32_t)minor;
        if (chol->complex_form) {
            /* complex unknown k of block K = k / 2: real columns 4 K + 2 (k % 2) .. + 1 */
            col = 4 * (col / 2) + 2 * (col % 2);
            minor *= 2;
        }
        c->status = CHOLMOD_OK;
        return cfi_error(ctx, CF_ERR_NOT_POSDEF,
                         "cholesky factorise: matrix not positive definite at column %d (pivot %zu of %d)", col, minor,
                         chol->n);
    }
    if ((st = cfi_cholmod_check(ctx, c, ok, "cholesky factorise")) != CF_OK) {
        if (st == CF_ERR_NOMEM) {
            /* name the need and the limit instead of CHOLMOD's bare "out of memory" */
            char note[128];
            cfi_address_space_note(note, sizeof note);
            double bytes = chol->factor_entries * (chol->complex_form ? 16.0 : 8.0);
            return cfi_error(ctx, CF_ERR_NOMEM,
                             "cholesky factorise: out of memory for the factor (%.3g %s entries, %.0f MB, %d columns; %s)",
                             chol->factor_entries, chol->complex_form ? "complex" : "real", bytes / (1024.0 * 1024.0),
                             (int)chol->factor->n, note);
        }
        return st;
    }
    chol->factorized = 1;
    return CF_OK;
}

cf_status cf_cholesky_factorize(cf_cholesky *chol, const cf_sparse *a) { return factorize(chol, a, 0.0); }

cf_status cf_cholesky_factorize_shifted(cf_cholesky *chol, const cf_sparse *a, double shift)
{
    return factorize(chol, a, shift);
}

cf_status cf_cholesky_factorize_quat(cf_cholesky *chol, const cf_quat_sparse *a)
{
    if (!chol) return CF_ERR_INVALID_ARG;
    cf_context *ctx = chol->ctx;
    chol->factorized = 0;
    cf_status st = check_quat(ctx, a, "cholesky factorise");
    if (st != CF_OK) return st;
    if (!chol->quat_input)
        return cfi_error(ctx, CF_ERR_INVALID_ARG,
                         "cholesky factorise: analysed from a real matrix (cf_cholesky_factorize), not a quaternion one");
    if (2 * a->nb != chol->ncols || a->colptr[2 * a->nb] != chol->nnz ||
        memcmp(a->colptr, chol->colptr, ((size_t)chol->ncols + 1) * sizeof *chol->colptr) != 0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "cholesky factorise: pattern differs from the analysed one");
    int64_t bad = cfi_first_nonfinite(a->values, 2 * chol->nnz);
    if (bad >= 0) {
        int64_t e = bad / 2;
        int32_t j = 0;
        while (a->colptr[j + 1] <= e) ++j;
        return cfi_error(ctx, CF_ERR_NUMERICAL, "cholesky factorise: quaternion block (%d, %d) is not finite",
                         a->rowind[e] / 2, j / 2);
    }
    double t0 = cfi_now_seconds();
    cholmod_sparse view;
    quat_sparse_view(a, 1, &view);
    return factorize_view(chol, &view, 0.0, t0);
}

/* The complex-form buffer of quaternion-block solves, grown to nrhs columns. */
static cf_status reserve_zwork(cf_cholesky *chol, int32_t nrhs)
{
    if (!chol->complex_form || chol->quat_input || nrhs <= chol->zwork_cols) return CF_OK;
    cf_context *ctx = chol->ctx;
    double *w = CFI_ALLOC(ctx, double, (size_t)chol->n * (size_t)nrhs);
    if (!w) return CF_ERR_NOMEM;
    CFI_FREE(ctx, chol->zwork, (size_t)chol->n * chol->zwork_cols);
    chol->zwork = w;
    chol->zwork_cols = nrhs;
    return CF_OK;
}

cf_status cf_cholesky_reserve_solve(cf_cholesky *chol, int32_t nrhs)
{
    if (!chol) return CF_ERR_INVALID_ARG;
    if (nrhs < 0) return cfi_error(chol->ctx, CF_ERR_INVALID_ARG, "cholesky reserve: %d right-hand sides", nrhs);
    return reserve_zwork(chol, nrhs);
}

cf_status cf_cholesky_solve(cf_cholesky *chol, int32_t nrhs, const double *b, double *x)
{
    if (!chol) return CF_ERR_INVALID_ARG;
    cf_context *ctx = chol->ctx;
    if (nrhs < 0 || (nrhs > 0 && (!b || !x)))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "cholesky solve: %d right-hand sides, b or x NULL", nrhs);
    if (!chol->factorized) return cfi_error(ctx, CF_ERR_INVALID_ARG, "cholesky solve: no successful factorisation");
    if (nrhs == 0 || chol->n == 0) return CF_OK;
    int64_t total = (int64_t)chol->n * nrhs;
    int64_t bad = cfi_first_nonfinite(b, total);
    if (bad >= 0)
        return cfi_error(ctx, CF_ERR_NUMERICAL, "cholesky solve: right-hand side %lld, row %lld is not finite",
                         (long long)(bad / chol->n), (long long)(bad % chol->n));
    /* supernodal solves call BLAS (trsm, gemm), maybe on another thread
     * than the factorisation */
    if (chol->factor->is_super) {
        cf_status sr = cfi_blas_reserve(ctx, "cholesky solve");
        if (sr != CF_OK) return sr;
    }
    double t0 = cfi_now_seconds();
    cholmod_common *c = chol->common;
    c->status = CHOLMOD_OK;
    cfi_cholmod_clear_message();
    cholmod_dense bd;
    memset(&bd, 0, sizeof bd);
    bd.nrow = (size_t)chol->n;
    bd.ncol = (size_t)nrhs;
    bd.nzmax = (size_t)total;
    bd.d = (size_t)chol->n;
    bd.x = (void *)b;
    bd.xtype = CHOLMOD_REAL;
    bd.dtype = CHOLMOD_DOUBLE;
    if (chol->complex_form) {
        /* From a cf_quat_sparse the complex right-hand sides go into the
         * caller's x (n doubles per column hold n / 2 complex entries; x may
         * be b, the conversion works in place): no buffer of our own (21 MB
         * at 655k vertices; docs/memory.md). CHOLMOD reads B before it
         * writes its own X. */
        double *zb = x;
        if (!chol->quat_input) {
            cf_status sz = reserve_zwork(chol, nrhs);
            if (sz != CF_OK) return sz;
            zb = chol->zwork;
        }
        cfi_quat_to_complex(chol->n, nrhs, b, zb);
        bd.nrow = bd.d = (size_t)chol->n / 2;
        bd.nzmax = (size_t)total / 2;
        bd.x = zb;
        bd.xtype = CHOLMOD_COMPLEX;
    }
    /* x, y, e keep their storage between calls (reallocated only when nrhs grows) */
    int blas_threads = cfi_blas_threads_enter(ctx);
    int ok = cholmod_solve2(CHOLMOD_A, chol->factor, &bd, NULL, &chol->x, NULL, &chol->y, &chol->e, c);
    cfi_blas_threads_leave(blas_threads);
    cf_status st = cfi_cholmod_check(ctx, c, ok, "cholesky solve");
    if (st != CF_OK) return st;
    if (chol->complex_form)
        cfi_quat_from_complex(chol->n, nrhs, chol->x->x, x);
    else
        memcpy(x, chol->x->x, (size_t)total * sizeof *x);
    chol->timings.solve_seconds = cfi_now_seconds() - t0;
    bad = cfi_first_nonfinite(x, total);
    if (bad >= 0)
        return cfi_error(ctx, CF_ERR_NUMERICAL, "cholesky solve: solution %lld, row %lld is not finite (overflow)",
                         (long long)(bad / chol->n), (long long)(bad % chol->n));
    return CF_OK;
}
