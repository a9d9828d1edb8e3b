/*
 * A real symmetric matrix whose 4 x 4 blocks are matrices of left
 * multiplication by quaternions (Le Folgoc Eq. 7) is a Hermitian quaternionic
 * matrix, and that is the same operator as a complex Hermitian matrix of half
 * the size. Writing a quaternion as q = z1 + j z2 with z1 = a + b i and
 * z2 = c - d i (so q = a + b i + c j + d k), left multiplication x -> q x on
 * x = w1 + j w2 commutes with complex scalars acting on the right and reads
 *     q x = (z1 w1 - conj(z2) w2) + j (z2 w1 + conj(z1) w2),
 * i.e. the 2 x 2 complex block [[z1, -conj(z2)], [z2, conj(z1)]] acting on
 * (w1, w2). The real form's eigenvalues are the complex form's, each twice;
 * a complex supernodal Cholesky of the 2n x 2n form does about half the
 * work of the real 4n x 4n one (measured in docs/linalg.md).
 */
#include "linalg/linalg_internal.h"

#include <math.h>
#include <string.h>

struct cfi_quat_map {
    int32_t nb;           /* quaternion blocks per side */
    int32_t *zcolptr;     /* complex upper-triangle pattern, 2 nb columns */
    int32_t *zrowind;
    double *zvalues;      /* interleaved (re, im), 2 znnz */
    int64_t znnz;
    int64_t nblocks;      /* stored blocks (I, J) with I <= J */
    int64_t *src;         /* 4 per block: position of entry (4 I, 4 J + c) in the real values */
    int64_t *dst;         /* 4 per block: complex entries (2I,2J) (2I+1,2J) (2I,2J+1) (2I+1,2J+1), -1 absent */
    int32_t *block_row;   /* I of each block, for messages */
    int32_t *block_col;   /* J */
};

static void map_free(cf_context *ctx, cfi_quat_map *m)
{
    CFI_FREE(ctx, m->zcolptr, (size_t)2 * m->nb + 1);
    CFI_FREE(ctx, m->zrowind, (size_t)m->znnz);
    CFI_FREE(ctx, m->zvalues, (size_t)2 * m->znnz);
    CFI_FREE(ctx, m->src, (size_t)4 * m->nblocks);
    CFI_FREE(ctx, m->dst, (size_t)4 * m->nblocks);
    CFI_FREE(ctx, m->block_row, (size_t)m->nblocks);
    CFI_FREE(ctx, m->block_col, (size_t)m->nblocks);
    CFI_FREE(ctx, m, 1);
}

void cfi_quat_map_destroy(cf_context *ctx, cfi_quat_map **map)
{
    if (!map || !*map) return;
    map_free(ctx, *map);
    *map = NULL;
}

/* The blocks of block column J must be stored densely: in each of the
 * columns 4J..4J+3 the same runs of four consecutive rows 4I..4I+3. */
static cf_status check_block_column(cf_context *ctx, const cf_sparse *a, int32_t J, int64_t *upper_blocks,
                                    int32_t *has_diagonal)
{
    const int32_t *cp = a->colptr, *ri = a->rowind;
    int32_t len = cp[4 * J + 1] - cp[4 * J];
    for (int c = 1; c < 4; ++c)
        if (cp[4 * J + c + 1] - cp[4 * J + c] != len ||
            memcmp(ri + cp[4 * J + c], ri + cp[4 * J], (size_t)len * sizeof *ri) != 0)
            return cfi_error(ctx, CF_ERR_INVALID_ARG,
                             "cholesky create: quaternion blocks: columns %d and %d have different patterns "
                             "(4 x 4 blocks must be stored whole, both triangles)", 4 * J, 4 * J + c);
    if (len % 4 != 0)
        return cfi_error(ctx, CF_ERR_INVALID_ARG,
                         "cholesky create: quaternion blocks: column %d has %d entries, not whole 4 x 4 blocks", 4 * J,
                         len);
    *upper_blocks = 0;
    *has_diagonal = 0;
    for (int32_t p = cp[4 * J]; p < cp[4 * J + 1]; p += 4) {
        int32_t r = ri[p];
        if (r % 4 != 0 || ri[p + 1] != r + 1 || ri[p + 2] != r + 2 || ri[p + 3] != r + 3)
            return cfi_error(ctx, CF_ERR_INVALID_ARG,
                             "cholesky create: quaternion blocks: column %d, row %d does not start a whole 4 x 4 block",
                             4 * J, r);
        if (r / 4 < J) ++*upper_blocks;
        if (r / 4 == J) *has_diagonal = 1;
    }
    return CF_OK;
}

cf_status cfi_quat_map_create(cf_context *ctx, const cf_sparse *a, cfi_quat_map **out)
{
    *out = NULL;
    if (a->ncols % 4 != 0 || a->nrows != a->ncols)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "cholesky create: quaternion blocks need a square matrix of size 4 n, got %d",
                         a->ncols);
    if (a->upper_only)
        return cfi_error(ctx, CF_ERR_INVALID_ARG,
                         "cholesky create: quaternion blocks need both triangles stored (matrix is upper-only)");
    int32_t nb = a->ncols / 4;
    int64_t znnz = 0, nblocks = 0;
    for (int32_t J = 0; J < nb; ++J) {
        int64_t upper = 0;
        int32_t diag = 0;
        cf_status st = check_block_column(ctx, a, J, &upper, &diag);
        if (st != CF_OK) return st;
        nblocks += upper + diag;
        znnz += 4 * upper + 3 * diag;
    }
    if (znnz > INT32_MAX) return cfi_error(ctx, CF_ERR_INVALID_ARG, "cholesky create: quaternion blocks: matrix too large");
    cfi_quat_map *m = CFI_ALLOC(ctx, cfi_quat_map, 1);
    if (!m) return CF_ERR_NOMEM;
    memset(m, 0, sizeof *m);
    m->nb = nb;
    m->znnz = znnz;
    m->nblocks = nblocks;
    m->zcolptr = CFI_ALLOC(ctx, int32_t, (size_t)2 * nb + 1);
    m->zrowind = CFI_ALLOC(ctx, int32_t, (size_t)znnz);
    m->zvalues = CFI_ALLOC(ctx, double, (size_t)2 * znnz);
    m->src = CFI_ALLOC(ctx, int64_t, (size_t)4 * nblocks);
    m->dst = CFI_ALLOC(ctx, int64_t, (size_t)4 * nblocks);
    m->block_row = CFI_ALLOC(ctx, int32_t, (size_t)nblocks);
    m->block_col = CFI_ALLOC(ctx, int32_t, (size_t)nblocks);
    if (!m->zcolptr || (znnz && (!m->zrowind || !m->zvalues)) ||
        (nblocks && (!m->src || !m->dst || !m->block_row || !m->block_col))) {
        map_free(ctx, m);
        return CF_ERR_NOMEM;
    }
    /* Complex column 2J holds rows 2I, 2I+1 of every block I < J, then row
     * 2J; column 2J+1 the same rows, then 2J and 2J+1 (upper triangle). The
     * real rows are sorted, so the complex ones are too. */
    const int32_t *cp = a->colptr, *ri = a->rowind;
    int64_t z = 0, b = 0;
    m->zcolptr[0] = 0;
    for (int32_t J = 0; J < nb; ++J) {
        int64_t upper = 0;
        for (int32_t p = cp[4 * J]; p < cp[4 * J + 1]; p += 4) upper += ri[p] / 4 < J;
        int32_t diag = 0;
        for (int32_t p = cp[4 * J]; p < cp[4 * J + 1]; p += 4) diag |= ri[p] / 4 == J;
        int64_t col0 = z, col1 = z + 2 * upper + diag;
        int64_t k = 0;
        for (int32_t p = cp[4 * J]; p < cp[4 * J + 1]; p += 4) {
            int32_t I = ri[p] / 4;
            if (I > J) break;
            for (int c = 0; c < 4; ++c) m->src[4 * b + c] = (int64_t)(p - cp[4 * J]) + cp[4 * J + c];
            m->block_row[b] = I;
            m->block_col[b] = J;
            if (I < J) {
                m->zrowind[col0 + 2 * k] = 2 * I;
                m->zrowind[col0 + 2 * k + 1] = 2 * I + 1;
                m->zrowind[col1 + 2 * k] = 2 * I;
                m->zrowind[col1 + 2 * k + 1] = 2 * I + 1;
                m->dst[4 * b] = col0 + 2 * k;
                m->dst[4 * b + 1] = col0 + 2 * k + 1;
                m->dst[4 * b + 2] = col1 + 2 * k;
                m->dst[4 * b + 3] = col1 + 2 * k + 1;
                ++k;
            } else {
                m->zrowind[col0 + 2 * upper] = 2 * J;
                m->zrowind[col1 + 2 * upper] = 2 * J;
                m->zrowind[col1 + 2 * upper + 1] = 2 * J + 1;
                m->dst[4 * b] = col0 + 2 * upper;
                m->dst[4 * b + 1] = -1;
                m->dst[4 * b + 2] = col1 + 2 * upper;
                m->dst[4 * b + 3] = col1 + 2 * upper + 1;
            }
            ++b;
        }
        z = col1 + 2 * upper + 2 * diag;
        m->zcolptr[2 * J + 1] = (int32_t)col1;
        m->zcolptr[2 * J + 2] = (int32_t)z;
    }
    *out = m;
    return CF_OK;
}

void cfi_complex_upper_view(int32_t nb, int64_t nnz, int32_t *colptr, int32_t *rowind, double *values,
                            cholmod_sparse *view)
{
    memset(view, 0, sizeof *view);
    view->nrow = view->ncol = (size_t)2 * nb;
    view->nzmax = (size_t)nnz;
    view->p = colptr;
    view->i = rowind;
    view->x = values;
    view->stype = 1;
    view->itype = CHOLMOD_INT;
    view->xtype = values ? CHOLMOD_COMPLEX : CHOLMOD_PATTERN;
    view->dtype = CHOLMOD_DOUBLE;
    view->sorted = 1;
    view->packed = 1;
}

void cfi_quat_map_view(const cfi_quat_map *m, int with_values, cholmod_sparse *view)
{
    cfi_complex_upper_view(m->nb, m->znnz, m->zcolptr, m->zrowind, with_values ? m->zvalues : NULL, view);
}

cf_status cfi_quat_map_fill(cf_context *ctx, cfi_quat_map *m, const cf_sparse *a, double tolerance)
{
    const double *val = a->values;
    double *zv = m->zvalues;
    double largest = 0.0, worst = 0.0;
    int64_t worst_block = -1;
    for (int64_t b = 0; b < m->nblocks; ++b) {
        const double *c0 = val + m->src[4 * b], *c1 = val + m->src[4 * b + 1], *c2 = val + m->src[4 * b + 2],
                     *c3 = val + m->src[4 * b + 3];
        /* Nearest left-multiplication matrix (the blocks are exact in exact
         * arithmetic; the deviation is checked below). */
        double qa = 0.25 * (c0[0] + c1[1] + c2[2] + c3[3]);
        double qb = 0.25 * (c0[1] - c1[0] + c2[3] - c3[2]);
        double qc = 0.25 * (c0[2] - c2[0] + c3[1] - c1[3]);
        double qd = 0.25 * (c0[3] - c3[0] + c1[2] - c2[1]);
        const double expect[16] = {qa, qb, qc, qd, -qb, qa, qd, -qc, -qc, -qd, qa, qb, -qd, qc, -qb, qa};
        const double *cols[4] = {c0, c1, c2, c3};
        double dev = 0.0, big = 0.0; /* plain comparisons: fmax is a library call here */
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) {
                double v = cols[c][r], mag = fabs(v), e = fabs(v - expect[4 * c + r]);
                big = mag > big ? mag : big;
                dev = e > dev ? e : dev;
            }
        if (big > largest) largest = big;
        if (m->block_row[b] == m->block_col[b]) dev = fmax(dev, fmax(fabs(qb), fmax(fabs(qc), fabs(qd))));
        if (dev > worst || dev != dev) {
            worst = dev;
            worst_block = b;
        }
        int64_t d0 = m->dst[4 * b], d1 = m->dst[4 * b + 1], d2 = m->dst[4 * b + 2], d3 = m->dst[4 * b + 3];
        zv[2 * d0] = qa;
        zv[2 * d0 + 1] = qb;
        if (d1 >= 0) {
            zv[2 * d1] = qc;
            zv[2 * d1 + 1] = -qd;
        }
        zv[2 * d2] = -qc;
        zv[2 * d2 + 1] = -qd;
        zv[2 * d3] = qa;
        zv[2 * d3 + 1] = -qb;
    }
    if (worst_block >= 0 && !(worst <= tolerance * largest))
        return cfi_error(ctx, CF_ERR_INVALID_ARG,
                         "cholesky factorise: block (%d, %d) is not %s (deviation %.3g, largest entry %.3g)",
                         m->block_row[worst_block], m->block_col[worst_block],
                         m->block_row[worst_block] == m->block_col[worst_block]
                             ? "a real multiple of the identity (a diagonal block of a Hermitian quaternionic matrix)"
                             : "a quaternion's left-multiplication matrix",
                         worst, largest);
    return CF_OK;
}

void cfi_quat_to_complex(int32_t n, int32_t nrhs, const double *real, double *cplx)
{
    /* x = x0 + x1 i + x2 j + x3 k = w1 + j w2: w1 = x0 + x1 i, w2 = x2 - x3 i */
    int64_t total = (int64_t)n * nrhs;
    for (int64_t k = 0; k < total; k += 4) {
        cplx[k] = real[k];
        cplx[k + 1] = real[k + 1];
        cplx[k + 2] = real[k + 2];
        cplx[k + 3] = -real[k + 3];
    }
}

void cfi_quat_from_complex(int32_t n, int32_t nrhs, const double *cplx, double *real)
{
    cfi_quat_to_complex(n, nrhs, cplx, real); /* the map is its own inverse */
}

/* ---- cf_quat_sparse: the complex form held directly -------------------- */

/* A Dirac-type matrix can be assembled straight into the complex form
 * (the caller adds each quaternion contribution to the four complex
 * entries of its block), so that the real 4 n x 4 n form, its slot table
 * and the real -> complex copy above are never made (docs/memory.md). */

void cf_quat_sparse_destroy(cf_quat_sparse **pa)
{
    if (!pa || !*pa) return;
    cf_quat_sparse *a = *pa;
    cf_context *ctx = a->ctx;
    size_t nnz = a->colptr ? (size_t)a->colptr[2 * (size_t)a->nb] : 0;
    CFI_FREE(ctx, a->rowind, nnz);
    CFI_FREE(ctx, a->values, 2 * nnz);
    CFI_FREE(ctx, a->colptr, 2 * (size_t)a->nb + 1);
    CFI_FREE(ctx, a, 1);
    *pa = NULL;
}

int64_t cf_quat_sparse_nnz(const cf_quat_sparse *a) { return a && a->colptr ? a->colptr[2 * (int64_t)a->nb] : 0; }

cf_status cf_quat_sparse_create(cf_context *ctx, const cf_sparse *g, cf_quat_sparse **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!g || !out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "quaternion matrix create: graph or out is NULL");
    *out = NULL;
    if (g->nrows != g->ncols)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "quaternion matrix create: block graph is %d x %d, not square",
                         g->nrows, g->ncols);
    int32_t nb = g->ncols;
    if ((int64_t)2 * nb + 1 > INT32_MAX)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "quaternion matrix create: %d blocks exceed int32 indices", nb);
    const int32_t *gcp = g->colptr, *gri = g->rowind;
    int64_t znnz = 0;
    for (int32_t J = 0; J < nb; ++J) {
        int64_t upper = 0;
        int diag = 0;
        for (int32_t p = gcp[J]; p < gcp[J + 1]; ++p) {
            if (p > gcp[J] && gri[p] <= gri[p - 1])
                return cfi_error(ctx, CF_ERR_INVALID_ARG,
                                 "quaternion matrix create: block graph column %d: rows not sorted (row %d after %d)", J,
                                 gri[p], gri[p - 1]);
            upper += gri[p] < J;
            diag |= gri[p] == J;
        }
        if (!diag)
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "quaternion matrix create: block column %d has no diagonal block", J);
        znnz += 4 * upper + 3;
    }
    if (znnz > INT32_MAX)
        return cfi_error(ctx, CF_ERR_INVALID_ARG,
                         "quaternion matrix create: %lld complex entries exceed int32 indices", (long long)znnz);
    cf_quat_sparse *a = CFI_ALLOC(ctx, cf_quat_sparse, 1);
    if (!a) return CF_ERR_NOMEM;
    a->ctx = ctx;
    a->nb = nb;
    a->colptr = CFI_ALLOC(ctx, int32_t, 2 * (size_t)nb + 1);
    if (!a->colptr) {
        CFI_FREE(ctx, a, 1);
        return CF_ERR_NOMEM;
    }
    a->rowind = CFI_ALLOC(ctx, int32_t, (size_t)znnz);
    a->values = CFI_ALLOC(ctx, double, 2 * (size_t)znnz);
    if (znnz && (!a->rowind || !a->values)) {
        /* colptr is still zero: destroy frees nothing by a wrong count */
        CFI_FREE(ctx, a->rowind, (size_t)znnz);
        CFI_FREE(ctx, a->values, 2 * (size_t)znnz);
        cf_quat_sparse_destroy(&a);
        return CF_ERR_NOMEM;
    }
    int32_t z = 0;
    for (int32_t J = 0; J < nb; ++J) {
        int32_t col0 = z, k = 0;
        for (int32_t p = gcp[J]; p < gcp[J + 1] && gri[p] < J; ++p) k += 2;
        int32_t col1 = col0 + k + 1;
        for (int32_t p = gcp[J]; p < gcp[J + 1] && gri[p] <= J; ++p) {
            int32_t I = gri[p], off = 2 * (p - gcp[J]);
            a->rowind[col0 + off] = 2 * I;
            a->rowind[col1 + off] = 2 * I;
            if (I < J) {
                a->rowind[col0 + off + 1] = 2 * I + 1;
                a->rowind[col1 + off + 1] = 2 * I + 1;
            } else {
                a->rowind[col1 + off + 1] = 2 * J + 1;
            }
        }
        z = col1 + k + 2;
        a->colptr[2 * J + 1] = col1;
        a->colptr[2 * J + 2] = z;
    }
    *out = a;
    return CF_OK;
}

/* y (4 entries) += L(q) x, or L(q)^T x = L(conj q) x, with L(q) the
 * left-multiplication matrix of q (Le Folgoc Eq. 7), column by column as
 * cf_sparse_multiply runs through the real form's columns. */
static inline void add_block_product(const double q[4], int transpose, const double *x, double *y)
{
    /* column-major: column c is q e_c */
    const double m[16] = {q[0], q[1], q[2], q[3], -q[1], q[0], q[3], -q[2],
                          -q[2], -q[3], q[0], q[1], -q[3], q[2], -q[1], q[0]};
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) y[r] += (transpose ? m[4 * r + c] : m[4 * c + r]) * x[c];
}

void cf_quat_sparse_multiply(const cf_quat_sparse *a, const double *x, double *y)
{
    if (!a || !x || !y) return;
    int32_t nb = a->nb;
    const int32_t *cp = a->colptr, *ri = a->rowind;
    const double *v = a->values;
    memset(y, 0, 4 * (size_t)nb * sizeof *y);
    /* Row block J receives, in the real form's order, the products with
     * block columns I < J (the conjugates of the blocks stored in column
     * J), then its diagonal block, then those with J' > J, added when
     * column J' is reached; so column J first completes y_J's left part,
     * then adds its blocks' products to the rows I < J. */
    for (int32_t J = 0; J < nb; ++J) {
        int32_t c0 = cp[2 * J], c1 = cp[2 * J + 1];
        int32_t nblk = (c1 - c0 + 1) / 2; /* blocks I < J, then the diagonal */
        for (int32_t k = 0; k < nblk; ++k) {
            /* q = a + b i + c j + d k: (2I, 2J) = a + b i, (2I, 2J+1) = -c - d i */
            const double q[4] = {v[2 * ((int64_t)c0 + 2 * k)], v[2 * ((int64_t)c0 + 2 * k) + 1],
                                 -v[2 * ((int64_t)c1 + 2 * k)], -v[2 * ((int64_t)c1 + 2 * k) + 1]};
            int32_t I = ri[c0 + 2 * k] / 2;
            add_block_product(q, I < J, x + 4 * (int64_t)I, y + 4 * (int64_t)J);
        }
        for (int32_t k = 0; k + 1 < nblk; ++k) {
            const double q[4] = {v[2 * ((int64_t)c0 + 2 * k)], v[2 * ((int64_t)c0 + 2 * k) + 1],
                                 -v[2 * ((int64_t)c1 + 2 * k)], -v[2 * ((int64_t)c1 + 2 * k) + 1]};
            int32_t I = ri[c0 + 2 * k] / 2;
            add_block_product(q, 0, x + 4 * (int64_t)J, y + 4 * (int64_t)I);
        }
    }
}
