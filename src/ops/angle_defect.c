/*
 * Angle defect (integrated Gaussian curvature): K_i = 2 pi - sum of corner
 * angles at interior vertices and pi - sum (integrated geodesic curvature)
 * at boundary vertices, so that sum_i K_i = 2 pi chi exactly (discrete
 * Gauss-Bonnet).
 */
#include "curvflow/ops.h"
#include "ops/ops_internal.h"

cf_status cf_angle_defect(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *k)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, k, "angle_defect");
    if (s != CF_OK) return s;
    for (int32_t v = 0; v < mesh->nv; ++v) k[v] = mesh->vertex_on_boundary[v] ? CFI_PI : 2.0 * CFI_PI;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * f;
        for (int c = 0; c < 3; ++c) k[t[c]] -= cfi_corner_angle(positions, t, c);
    }
    return CF_OK;
}
