/*
 * Face areas, unit face normals (right-hand rule on the corner order, i.e.
 * outward for counter-clockwise faces) and the total area.
 */
#include "curvflow/ops.h"
#include "ops/ops_internal.h"

cf_status cf_face_areas(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *areas)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, areas, "face_areas");
    if (s != CF_OK) return s;
    for (int32_t f = 0; f < mesh->nf; ++f) areas[f] = cfi_face_area(mesh, positions, f);
    return CF_OK;
}

cf_status cf_face_normals(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *normals)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, normals, "face_normals");
    if (s != CF_OK) return s;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        double n[3];
        cfi_face_area_vector(mesh, positions, f, n);
        double len = cfi_v3_norm(n);
        if (!(len > 0.0)) return cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "face %d: zero area, no normal", f);
        for (int c = 0; c < 3; ++c) normals[3 * f + c] = n[c] / len;
    }
    return CF_OK;
}

cf_status cf_total_area(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *area)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, area, "total_area");
    if (s != CF_OK) return s;
    double sum = 0.0;
    for (int32_t f = 0; f < mesh->nf; ++f) sum += cfi_face_area(mesh, positions, f);
    *area = sum;
    return CF_OK;
}
