/*
 * Corner angles and their cotangents, angles[3 f + k] at corner k of face f.
 * Angles use atan2(|u x v|, u . v), accurate also near 0 and pi.
 */
#include "curvflow/ops.h"
#include "ops/ops_internal.h"

cf_status cf_corner_angles(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *angles)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, angles, "corner_angles");
    if (s != CF_OK) return s;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * f;
        for (int k = 0; k < 3; ++k) {
            double u[3], v[3], c[3];
            cfi_v3_sub(positions + 3 * t[(k + 1) % 3], positions + 3 * t[k], u);
            cfi_v3_sub(positions + 3 * t[(k + 2) % 3], positions + 3 * t[k], v);
            cfi_v3_cross(u, v, c);
            angles[3 * f + k] = atan2(cfi_v3_norm(c), cfi_v3_dot(u, v));
        }
    }
    return CF_OK;
}

cf_status cf_corner_cotangents(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *cot)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, cot, "corner_cotangents");
    if (s != CF_OK) return s;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        s = cfi_face_cotangents(ctx, mesh, positions, f, cot + 3 * f, NULL);
        if (s != CF_OK) return s;
    }
    return CF_OK;
}
