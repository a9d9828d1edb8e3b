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

void cfi_quat_map_view(const cfi_quat_map *m, int with_values, cholmod_sparse *view)
{
    memset(view, 0, sizeof *view);
    view->nrow = view->ncol = (size_t)2 * m->nb;
    view->nzmax = (size_t)m->znnz;
    view->p = m->zcolptr;
    view->i = m->zrowind;
    view->x = with_values ? m->zvalues : NULL;
    view->stype = 1;
    view->itype = CHOLMOD_INT;
    view->xtype = with_values ? CHOLMOD_COMPLEX : CHOLMOD_PATTERN;
    view->dtype = CHOLMOD_DOUBLE;
    view->sorted = 1;
    view->packed = 1;
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
