/*
 * Area-weighted unit vertex normals: the normalised sum of the area vectors
 * (x1 - x0) x (x2 - x0) of the incident faces.
 */
#include "curvflow/ops.h"
#include "ops/ops_internal.h"

cf_status cf_vertex_normals(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *normals)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, normals, "vertex_normals");
    if (s != CF_OK) return s;
    cfi_vertex_area_vectors(mesh, positions, normals);
    for (int32_t v = 0; v < mesh->nv; ++v) {
        double len = cfi_v3_norm(normals + 3 * v);
        if (!(len > 0.0))
            return cfi_error(ctx, CF_ERR_NUMERICAL, "vertex %d: incident area vectors cancel, no normal", v);
        for (int c = 0; c < 3; ++c) normals[3 * v + c] /= len;
    }
    return CF_OK;
}
