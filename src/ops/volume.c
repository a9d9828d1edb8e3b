/*
 * Signed enclosed volume (1/6) sum_f x_a . (x_b x x_c) (divergence theorem
 * on the cones from the origin). Positive for closed outward meshes;
 * origin-dependent on meshes with boundary.
 */
#include "curvflow/ops.h"
#include "ops/ops_internal.h"

cf_status cf_enclosed_volume(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *volume)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, volume, "enclosed_volume");
    if (s != CF_OK) return s;
    double sum = 0.0;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * f;
        double c[3];
        cfi_v3_cross(positions + 3 * t[1], positions + 3 * t[2], c);
        sum += cfi_v3_dot(positions + 3 * t[0], c);
    }
    *volume = sum / 6.0;
    return CF_OK;
}
