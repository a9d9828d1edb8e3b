/*
 * Mass matrices (nv x nv): lumped barycentric (A_f / 3 per corner), lumped
 * mixed Voronoi (Meyer et al. 2003) and the consistent P1 Galerkin matrix
 * (A_f / 6 on the diagonal, A_f / 12 off it, per face). All sum to the total
 * area: 1^T M 1 = A.
 */
#include "curvflow/ops.h"
#include "ops/ops_internal.h"

static cf_status diagonal_matrix(cf_context *ctx, int32_t n, const double *d, cf_sparse **out)
{
    int32_t *idx = CFI_ALLOC(ctx, int32_t, n);
    if (!idx) return CF_ERR_NOMEM;
    for (int32_t i = 0; i < n; ++i) idx[i] = i;
    cf_status s = cf_sparse_from_triplets(ctx, n, n, n, idx, idx, d, 1, out, NULL);
    CFI_FREE(ctx, idx, n);
    return s;
}

static cf_status galerkin(cf_context *ctx, const cf_mesh *mesh, const double *positions, cf_sparse **out)
{
    int64_t n = 9 * (int64_t)mesh->nf;
    int32_t *rows = CFI_ALLOC(ctx, int32_t, n);
    int32_t *cols = CFI_ALLOC(ctx, int32_t, n);
    double *vals = CFI_ALLOC(ctx, double, n);
    cf_status s = CF_OK;
    if (!rows || !cols || !vals) {
        s = CF_ERR_NOMEM;
        goto done;
    }
    for (int32_t f = 0; f < mesh->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * f;
        double area = cfi_face_area(mesh, positions, f);
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) {
                int64_t k = 9 * (int64_t)f + 3 * a + b;
                rows[k] = t[a];
                cols[k] = t[b];
                vals[k] = a == b ? area / 6.0 : area / 12.0;
            }
    }
    s = cf_sparse_from_triplets(ctx, mesh->nv, mesh->nv, n, rows, cols, vals, 1, out, NULL);
done:
    CFI_FREE(ctx, rows, n);
    CFI_FREE(ctx, cols, n);
    CFI_FREE(ctx, vals, n);
    return s;
}

cf_status cf_mass_matrix(cf_context *ctx, const cf_mesh *mesh, const double *positions, cf_mass_kind kind,
                         cf_sparse **out)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, out, "mass_matrix");
    if (s != CF_OK) return s;
    *out = NULL;
    if (kind == CF_MASS_GALERKIN) return galerkin(ctx, mesh, positions, out);
    if (kind != CF_MASS_LUMPED_BARYCENTRIC && kind != CF_MASS_LUMPED_VORONOI)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "mass_matrix: unknown kind %d", (int)kind);
    double *d = CFI_ALLOC(ctx, double, mesh->nv);
    if (!d) return CF_ERR_NOMEM;
    s = cf_vertex_areas(ctx, mesh, positions,
                        kind == CF_MASS_LUMPED_VORONOI ? CF_DUAL_AREA_MIXED_VORONOI : CF_DUAL_AREA_BARYCENTRIC, d);
    if (s == CF_OK) s = diagonal_matrix(ctx, mesh->nv, d, out);
    CFI_FREE(ctx, d, mesh->nv);
    return s;
}
