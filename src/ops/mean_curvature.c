/*
 * Integrated mean-curvature normal L x = 2 H N A_i (Meyer et al. 2003,
 * Eq. (8), with the positive semi-definite L of docs/conventions.md) and the
 * pointwise signed mean curvature H_i = <L x, N_i> / (2 A_i) with
 * mixed-Voronoi A_i (Meyer 2003, Fig. 4) and area-weighted N_i; H = 1/R on a sphere of radius R
 * with outward normals. Applied matrix-free.
 */
#include "curvflow/ops.h"
#include "ops/cotan_laplacian.h"
#include "ops/ops_internal.h"

cf_status cf_mean_curvature_normal(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *hn)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, hn, "mean_curvature_normal");
    if (s != CF_OK) return s;
    return cfi_cotan_laplacian_apply(ctx, mesh, positions, 3, positions, hn);
}

cf_status cf_mean_curvature(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *h)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, h, "mean_curvature");
    if (s != CF_OK) return s;
    int64_t n3 = 3 * (int64_t)mesh->nv;
    double *hn = CFI_ALLOC(ctx, double, n3);
    double *nrm = CFI_ALLOC(ctx, double, n3);
    if (!hn || !nrm) {
        s = CF_ERR_NOMEM;
        goto done;
    }
    s = cfi_cotan_laplacian_apply(ctx, mesh, positions, 3, positions, hn);
    if (s != CF_OK) goto done;
    s = cf_vertex_areas(ctx, mesh, positions, CF_DUAL_AREA_MIXED_VORONOI, h);
    if (s != CF_OK) goto done;
    cfi_vertex_area_vectors(mesh, positions, nrm);
    for (int32_t v = 0; v < mesh->nv; ++v) {
        double len = cfi_v3_norm(nrm + 3 * v);
        if (!(len > 0.0)) {
            s = cfi_error(ctx, CF_ERR_NUMERICAL, "vertex %d: no normal (incident area vectors cancel)", v);
            goto done;
        }
        if (!(h[v] > 0.0)) {
            s = cfi_error(ctx, CF_ERR_NUMERICAL, "vertex %d: mixed Voronoi area is %g", v, h[v]);
            goto done;
        }
        h[v] = cfi_v3_dot(hn + 3 * v, nrm + 3 * v) / (len * 2.0 * h[v]);
    }
done:
    CFI_FREE(ctx, hn, n3);
    CFI_FREE(ctx, nrm, n3);
    return s;
}
