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
        for (int c = 0; c < 3; ++c) {
            double u[3], v[3], x[3];
            cfi_v3_sub(positions + 3 * t[(c + 1) % 3], positions + 3 * t[c], u);
            cfi_v3_sub(positions + 3 * t[(c + 2) % 3], positions + 3 * t[c], v);
            cfi_v3_cross(u, v, x);
            k[t[c]] -= atan2(cfi_v3_norm(x), cfi_v3_dot(u, v));
        }
    }
    return CF_OK;
}
