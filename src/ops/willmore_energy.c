/*
 * Discrete Willmore energy W = sum_i H_i^2 A_i with H_i = |L x|_i / (2 A_i)
 * and barycentric A_i, i.e. W = sum_i |L x|_i^2 / (4 A_i). Tends to 4 pi on
 * refined round spheres (W/4pi = 1); scale invariant.
 */
#include "curvflow/ops.h"
#include "ops/cotan_laplacian.h"
#include "ops/ops_internal.h"

cf_status cf_willmore_energy(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *energy)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, energy, "willmore_energy");
    if (s != CF_OK) return s;
    int64_t n3 = 3 * (int64_t)mesh->nv;
    double *hn = CFI_ALLOC(ctx, double, n3);
    double *area = CFI_ALLOC(ctx, double, mesh->nv);
    if (!hn || !area) {
        s = CF_ERR_NOMEM;
        goto done;
    }
    s = cfi_cotan_laplacian_apply(ctx, mesh, positions, 3, positions, hn);
    if (s == CF_OK) s = cf_vertex_areas(ctx, mesh, positions, CF_DUAL_AREA_BARYCENTRIC, area);
    if (s != CF_OK) goto done;
    double w = 0.0;
    for (int32_t v = 0; v < mesh->nv; ++v) w += cfi_v3_dot(hn + 3 * v, hn + 3 * v) / (4.0 * area[v]);
    *energy = w;
done:
    CFI_FREE(ctx, hn, n3);
    CFI_FREE(ctx, area, mesh->nv);
    return s;
}
