/*
 * Positive semi-definite cotan Laplacian (Pinkall & Polthier 1993; Desbrun
 * et al. 1999): (L f)_i = sum_j w_ij (f_i - f_j), w_ij = (cot a_ij + cot b_ij)/2,
 * one cotangent on boundary edges. Assembled in one pass from 9 triplets per
 * face (duplicates summed by cf_sparse_from_triplets), plus the per-edge
 * weights (the DEC Hodge star *1) and a matrix-free application.
 */
#include "ops/cotan_laplacian.h"

#include "curvflow/ops.h"
#include "ops/ops_internal.h"

int64_t cfi_cotan_laplacian_triplet_count(const cf_mesh *mesh)
{
    return mesh ? (int64_t)CFI_COTAN_TRIPLETS_PER_FACE * mesh->nf : 0;
}

/* Values of the 9 triplets of face f, in the layout of the header. */
static cf_status face_values(cf_context *ctx, const cf_mesh *mesh, const double *positions, int32_t f, double *v)
{
    double cot[3];
    cf_status s = cfi_face_cotangents(ctx, mesh, positions, f, cot, NULL);
    if (s != CF_OK) return s;
    for (int k = 0; k < 3; ++k) {
        /* halfedge k runs t[k] -> t[k+1] and is opposite corner k+2 */
        double w = 0.5 * cot[(k + 2) % 3];
        /* the two halfedges of f touching corner k are k and k+2 */
        v[k] = 0.5 * (cot[(k + 2) % 3] + cot[(k + 1) % 3]);
        v[3 + 2 * k] = -w;
        v[4 + 2 * k] = -w;
    }
    return CF_OK;
}

cf_status cfi_cotan_laplacian_pattern(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                      cf_sparse **out, int64_t *slot_map)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, out, "cotan_laplacian");
    if (s != CF_OK) return s;
    *out = NULL;
    int64_t n = cfi_cotan_laplacian_triplet_count(mesh);
    int32_t *rows = CFI_ALLOC(ctx, int32_t, n);
    int32_t *cols = CFI_ALLOC(ctx, int32_t, n);
    double *vals = CFI_ALLOC(ctx, double, n);
    if (!rows || !cols || !vals) {
        s = CF_ERR_NOMEM;
        goto done;
    }
    for (int32_t f = 0; f < mesh->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * f;
        int64_t b = (int64_t)CFI_COTAN_TRIPLETS_PER_FACE * f;
        s = face_values(ctx, mesh, positions, f, vals + b);
        if (s != CF_OK) goto done;
        for (int k = 0; k < 3; ++k) {
            int32_t i = t[k], j = t[(k + 1) % 3];
            rows[b + k] = i;
            cols[b + k] = i;
            rows[b + 3 + 2 * k] = i;
            cols[b + 3 + 2 * k] = j;
            rows[b + 4 + 2 * k] = j;
            cols[b + 4 + 2 * k] = i;
        }
    }
    s = cf_sparse_from_triplets(ctx, mesh->nv, mesh->nv, n, rows, cols, vals, 1, out, slot_map);
done:
    CFI_FREE(ctx, rows, n);
    CFI_FREE(ctx, cols, n);
    CFI_FREE(ctx, vals, n);
    return s;
}

cf_status cfi_cotan_laplacian_refill(cf_sparse *l, const cf_mesh *mesh, const double *positions,
                                     const int64_t *slot_map)
{
    if (!l || !mesh || !positions || !slot_map) return CF_ERR_INVALID_ARG;
    cf_context *ctx = l->ctx;
    int64_t nnz = cf_sparse_nnz(l);
    for (int64_t k = 0; k < nnz; ++k) l->values[k] = 0.0;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        double v[CFI_COTAN_TRIPLETS_PER_FACE];
        cf_status s = face_values(ctx, mesh, positions, f, v);
        if (s != CF_OK) return s;
        const int64_t *slot = slot_map + (int64_t)CFI_COTAN_TRIPLETS_PER_FACE * f;
        for (int k = 0; k < CFI_COTAN_TRIPLETS_PER_FACE; ++k) l->values[slot[k]] += v[k];
    }
    return CF_OK;
}

cf_status cf_cotan_laplacian(cf_context *ctx, const cf_mesh *mesh, const double *positions, cf_sparse **out)
{
    return cfi_cotan_laplacian_pattern(ctx, mesh, positions, out, NULL);
}

cf_status cfi_cotan_laplacian_apply(cf_context *ctx, const cf_mesh *mesh, const double *positions, int32_t dim,
                                    const double *x, double *y)
{
    for (int64_t i = 0; i < (int64_t)dim * mesh->nv; ++i) y[i] = 0.0;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * f;
        double cot[3];
        cf_status s = cfi_face_cotangents(ctx, mesh, positions, f, cot, NULL);
        if (s != CF_OK) return s;
        for (int k = 0; k < 3; ++k) {
            int64_t i = t[k], j = t[(k + 1) % 3];
            double w = 0.5 * cot[(k + 2) % 3];
            for (int32_t c = 0; c < dim; ++c) {
                double d = w * (x[i * dim + c] - x[j * dim + c]);
                y[i * dim + c] += d;
                y[j * dim + c] -= d;
            }
        }
    }
    return CF_OK;
}

cf_status cf_cotan_weights(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *weights)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, weights, "cotan_weights");
    if (s != CF_OK) return s;
    for (int32_t e = 0; e < mesh->ne; ++e) weights[e] = 0.0;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        double cot[3];
        s = cfi_face_cotangents(ctx, mesh, positions, f, cot, NULL);
        if (s != CF_OK) return s;
        for (int k = 0; k < 3; ++k) weights[mesh->halfedge_edge[3 * f + k]] += 0.5 * cot[(k + 2) % 3];
    }
    return CF_OK;
}
