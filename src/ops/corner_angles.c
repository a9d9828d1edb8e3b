/*
 * Corner angles and their cotangents, angles[3 f + k] at corner k of face f.
 * Angles use atan2(|u x v|, u . v) (cfi_corner_angle), accurate also near 0 and pi.
 */
#include "curvflow/ops.h"
#include "ops/ops_internal.h"

cf_status cf_corner_angles(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *angles)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, angles, "corner_angles");
    if (s != CF_OK) return s;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * f;
        for (int k = 0; k < 3; ++k) angles[3 * f + k] = cfi_corner_angle(positions, t, k);
    }
    return CF_OK;
}

cf_status cf_corner_cotangents(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *cot)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, cot, "corner_cotangents");
    if (s != CF_OK) return s;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        s = cfi_face_cotangents(ctx, mesh, positions, f, 0.0, cot + 3 * f, NULL);
        if (s != CF_OK) return s;
    }
    return CF_OK;
}

double cf_corner_angle(const double *positions, const int32_t triangle[3], int corner)
{
    return cfi_corner_angle(positions, triangle, corner);
}
