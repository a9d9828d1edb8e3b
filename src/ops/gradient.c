/*
 * Piecewise-linear gradient of a vertex function, one vector per face:
 * grad f = sum_k f_k (N x e_k) / (2 A), e_k the edge opposite corner k
 * traversed counter-clockwise (Botsch et al., "Polygon Mesh Processing",
 * Sec. 3.3). Divergence is its negative adjoint under the face-area inner
 * product: div X = -G^T A_f X, so div(grad f) = -L f with the positive L.
 */
#include "curvflow/ops.h"
#include "ops/ops_internal.h"

cf_status cf_gradient(cf_context *ctx, const cf_mesh *mesh, const double *positions, const double *f,
                      double *grad)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, grad, "gradient");
    if (s != CF_OK) return s;
    if (!f) return cfi_error(ctx, CF_ERR_INVALID_ARG, "gradient: function is NULL");
    for (int32_t i = 0; i < mesh->nf; ++i) {
        double g[9], area;
        s = cfi_face_hat_gradients(ctx, mesh, positions, i, g, &area);
        if (s != CF_OK) return s;
        const int32_t *t = mesh->triangles + 3 * i;
        for (int c = 0; c < 3; ++c)
            grad[3 * i + c] = f[t[0]] * g[c] + f[t[1]] * g[3 + c] + f[t[2]] * g[6 + c];
    }
    return CF_OK;
}

cf_status cf_divergence(cf_context *ctx, const cf_mesh *mesh, const double *positions, const double *field,
                        double *div)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, div, "divergence");
    if (s != CF_OK) return s;
    if (!field) return cfi_error(ctx, CF_ERR_INVALID_ARG, "divergence: field is NULL");
    for (int32_t v = 0; v < mesh->nv; ++v) div[v] = 0.0;
    for (int32_t i = 0; i < mesh->nf; ++i) {
        double g[9], area;
        s = cfi_face_hat_gradients(ctx, mesh, positions, i, g, &area);
        if (s != CF_OK) return s;
        const int32_t *t = mesh->triangles + 3 * i;
        for (int k = 0; k < 3; ++k) div[t[k]] -= area * cfi_v3_dot(g + 3 * k, field + 3 * i);
    }
    return CF_OK;
}
