/*
 * Signed enclosed volume (1/6) sum_f x_a . (x_b x x_c) (divergence theorem
 * on the cones from an apex). Positive for closed outward meshes, where the
 * apex does not matter: there it is the centre of the bounding box, so
 * that a mesh far from the origin keeps its volume's digits (spot_3k moved
 * by 1e6 had 0.7181662 against 0.7182588: the triple products of 1e6-sized
 * vectors cancel to 1e-4). Meshes with boundary keep the origin as the
 * apex (their value depends on it; ops.h).
 */
#include "curvflow/ops.h"
#include "ops/ops_internal.h"

cf_status cf_enclosed_volume(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *volume)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, volume, "enclosed_volume");
    if (s != CF_OK) return s;
    double apex[3] = {0.0, 0.0, 0.0};
    if (mesh->boundary_loop_count == 0) cfi_bounding_box_centre(positions, mesh->nv, apex);
    double sum = 0.0;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * f;
        double a[3], b[3], c[3], n[3];
        cfi_v3_sub(positions + 3 * t[0], apex, a);
        cfi_v3_sub(positions + 3 * t[1], apex, b);
        cfi_v3_sub(positions + 3 * t[2], apex, c);
        cfi_v3_cross(b, c, n);
        sum += cfi_v3_dot(a, n);
    }
    *volume = sum / 6.0;
    return CF_OK;
}
