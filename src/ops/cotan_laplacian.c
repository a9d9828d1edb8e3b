/*
 * Positive semi-definite cotan Laplacian (Pinkall & Polthier 1993; Desbrun
 * et al. 1999): (L f)_i = sum_j w_ij (f_i - f_j), w_ij = (cot a_ij + cot b_ij)/2,
 * one cotangent on boundary edges. Assembled in one pass from nv + 2 ne
 * triplets (per-vertex diagonal, per-edge off-diagonals), with a refill path
 * into the fixed pattern, the per-edge weights (the DEC Hodge star *1) and a
 * matrix-free application.
 */
#include "ops/cotan_laplacian.h"

#include "curvflow/ops.h"
#include "ops/ops_internal.h"

int64_t cfi_cotan_laplacian_triplet_count(const cf_mesh *mesh)
{
    return mesh ? (int64_t)mesh->nv + 2 * (int64_t)mesh->ne : 0;
}

/* Per-edge assembly (nv + 2 ne triplets, 2.6x fewer than 9 per face): the
 * weights are accumulated per edge, the diagonal per vertex. */
cf_status cfi_cotan_laplacian_pattern(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                      double weight_floor, cf_sparse **out, int64_t *slot_map)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, out, "cotan_laplacian");
    if (s != CF_OK) return s;
    *out = NULL;
    int32_t nv = mesh->nv, ne = mesh->ne;
    int64_t n = cfi_cotan_laplacian_triplet_count(mesh);
    int32_t *rows = CFI_ALLOC(ctx, int32_t, n);
    int32_t *cols = CFI_ALLOC(ctx, int32_t, n);
    double *vals = CFI_ALLOC(ctx, double, n);
    if (!rows || !cols || !vals) {
        s = CF_ERR_NOMEM;
        goto done;
    }
    /* weights into vals[nv + 2e] first (cf_cotan_weights checks again) */
    for (int32_t v = 0; v < nv; ++v) {
        rows[v] = cols[v] = v;
        vals[v] = 0.0;
    }
    for (int32_t e = 0; e < ne; ++e) vals[nv + 2 * (int64_t)e] = 0.0;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        double cot[3];
        s = cfi_face_cotangents(ctx, mesh, positions, f, weight_floor, cot, NULL);
        if (s != CF_OK) goto done;
        for (int k = 0; k < 3; ++k) vals[nv + 2 * (int64_t)mesh->halfedge_edge[3 * f + k]] += 0.5 * cot[(k + 2) % 3];
    }
    for (int32_t e = 0; e < ne; ++e) {
        int64_t b = nv + 2 * (int64_t)e;
        int32_t i = mesh->edge_vertices[2 * e], j = mesh->edge_vertices[2 * e + 1];
        double w = vals[b];
        vals[i] += w;
        vals[j] += w;
        rows[b] = i;
        cols[b] = j;
        rows[b + 1] = j;
        cols[b + 1] = i;
        vals[b] = vals[b + 1] = -w;
    }
    s = cf_sparse_from_triplets(ctx, nv, nv, n, rows, cols, vals, 1, out, slot_map);
done:
    CFI_FREE(ctx, rows, n);
    CFI_FREE(ctx, cols, n);
    CFI_FREE(ctx, vals, n);
    return s;
}

cf_status cfi_cotan_laplacian_refill(cf_sparse *l, const cf_mesh *mesh, const double *positions,
                                     double weight_floor, const int64_t *slot_map)
{
    return cfi_cotan_laplacian_refill_scaled(l, mesh, positions, weight_floor, NULL, slot_map);
}

cf_status cfi_cotan_laplacian_refill_scaled(cf_sparse *l, const cf_mesh *mesh, const double *positions,
                                            double weight_floor, const double *face_scale, const int64_t *slot_map)
{
    if (!l || !mesh || !positions || !slot_map) return CF_ERR_INVALID_ARG;
    cf_context *ctx = l->ctx;
    int64_t nnz = cf_sparse_nnz(l);
    for (int64_t k = 0; k < nnz; ++k) l->values[k] = 0.0;
    const int64_t *edge_slot = slot_map + mesh->nv;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        double cot[3];
        cf_status s = cfi_face_cotangents(ctx, mesh, positions, f, weight_floor, cot, NULL);
        if (s != CF_OK) return s;
        const int32_t *t = mesh->triangles + 3 * f;
        for (int k = 0; k < 3; ++k) {
            /* halfedge k runs t[k] -> t[k+1] and is opposite corner k+2 */
            double w = 0.5 * cot[(k + 2) % 3];
            if (face_scale) w *= face_scale[f];
            int64_t e = mesh->halfedge_edge[3 * f + k];
            l->values[edge_slot[2 * e]] -= w;
            l->values[edge_slot[2 * e + 1]] -= w;
            l->values[slot_map[t[k]]] += w;
            l->values[slot_map[t[(k + 1) % 3]]] += w;
        }
    }
    return CF_OK;
}

cf_status cf_cotan_laplacian(cf_context *ctx, const cf_mesh *mesh, const double *positions, cf_sparse **out)
{
    return cfi_cotan_laplacian_pattern(ctx, mesh, positions, 0.0, out, NULL);
}

cf_status cfi_check_weight_floor(cf_context *ctx, double weight_floor, const char *fn)
{
    if (weight_floor >= 0.0 && weight_floor <= 1.0) return CF_OK;
    return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: weight_floor %g outside [0, 1]", fn, weight_floor);
}

static cf_status check_floor(cf_context *ctx, double weight_floor)
{
    return cfi_check_weight_floor(ctx, weight_floor, "cotan weights");
}

cf_status cf_cotan_laplacian_floored(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                     double weight_floor, cf_sparse **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    cf_status s = check_floor(ctx, weight_floor);
    return s != CF_OK ? s : cfi_cotan_laplacian_pattern(ctx, mesh, positions, weight_floor, out, NULL);
}

/* Public face of the refill path (ops/cotan_laplacian.h stays private to
 * ops; the layer check, tests/architecture, enforces it). */
int64_t cf_cotan_laplacian_slot_count(const cf_mesh *mesh) { return cfi_cotan_laplacian_triplet_count(mesh); }

cf_status cf_cotan_laplacian_with_slots(cf_context *ctx, const cf_mesh *mesh, const double *positions, cf_sparse **out,
                                        int64_t *slot_map)
{
    return cf_cotan_laplacian_with_slots_floored(ctx, mesh, positions, 0.0, out, slot_map);
}

cf_status cf_cotan_laplacian_with_slots_floored(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                                double weight_floor, cf_sparse **out, int64_t *slot_map)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!slot_map) return cfi_error(ctx, CF_ERR_INVALID_ARG, "cotan_laplacian_with_slots: slot_map is NULL");
    cf_status s = check_floor(ctx, weight_floor);
    return s != CF_OK ? s : cfi_cotan_laplacian_pattern(ctx, mesh, positions, weight_floor, out, slot_map);
}

cf_status cf_cotan_laplacian_refill(cf_sparse *l, const cf_mesh *mesh, const double *positions, const int64_t *slot_map)
{
    return cfi_cotan_laplacian_refill(l, mesh, positions, 0.0, slot_map);
}

cf_status cf_cotan_laplacian_refill_floored(cf_sparse *l, const cf_mesh *mesh, const double *positions,
                                            double weight_floor, const int64_t *slot_map)
{
    if (l && check_floor(l->ctx, weight_floor) != CF_OK) return CF_ERR_INVALID_ARG;
    return cfi_cotan_laplacian_refill(l, mesh, positions, weight_floor, slot_map);
}

cf_status cfi_cotan_laplacian_apply(cf_context *ctx, const cf_mesh *mesh, const double *positions, int32_t dim,
                                    const double *x, double *y)
{
    for (int64_t i = 0; i < (int64_t)dim * mesh->nv; ++i) y[i] = 0.0;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * f;
        double cot[3];
        cf_status s = cfi_face_cotangents(ctx, mesh, positions, f, 0.0, cot, NULL);
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
    return cf_cotan_weights_floored(ctx, mesh, positions, 0.0, weights);
}

cf_status cf_cotan_weights_floored(cf_context *ctx, const cf_mesh *mesh, const double *positions, double weight_floor,
                                   double *weights)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, weights, "cotan_weights");
    if (s == CF_OK) s = check_floor(ctx, weight_floor);
    if (s != CF_OK) return s;
    for (int32_t e = 0; e < mesh->ne; ++e) weights[e] = 0.0;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        double cot[3];
        s = cfi_face_cotangents(ctx, mesh, positions, f, weight_floor, cot, NULL);
        if (s != CF_OK) return s;
        for (int k = 0; k < 3; ++k) weights[mesh->halfedge_edge[3 * f + k]] += 0.5 * cot[(k + 2) % 3];
    }
    return CF_OK;
}
