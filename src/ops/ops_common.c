/* Argument checks, per-face cotangents and hat gradients, and per-vertex
 * area vectors shared by the operator files. */
#include "ops/ops_internal.h"

cf_status cfi_ops_check(cf_context *ctx, const cf_mesh *mesh, const double *positions, const void *out,
                        const char *fn)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!mesh) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: mesh is NULL", fn);
    if (!positions) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: positions is NULL", fn);
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: output is NULL", fn);
    int64_t n = 3 * (int64_t)mesh->nv;
    for (int64_t i = 0; i < n; ++i)
        if (!isfinite(positions[i]))
            return cfi_error(ctx, CF_ERR_NONFINITE, "%s: vertex %d: non-finite coordinate", fn, (int)(i / 3));
    return CF_OK;
}

/* cot of the angle at a between u = b - a and v = c - a is (u . v) / |u x v| */
cf_status cfi_face_cotangents(cf_context *ctx, const cf_mesh *mesh, const double *positions, int32_t f,
                              double weight_floor, double cot[3], double *double_area)
{
    const int32_t *t = mesh->triangles + 3 * f;
    const double *p[3] = {positions + 3 * t[0], positions + 3 * t[1], positions + 3 * t[2]};
    double n[3], e1[3], e2[3];
    cfi_v3_sub(p[1], p[0], e1);
    cfi_v3_sub(p[2], p[0], e2);
    cfi_v3_cross(e1, e2, n);
    double a2 = cfi_v3_norm(n);
    if (!(a2 > 0.0)) return cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "face %d: zero area", f);
    double weight_area = a2;
    if (weight_floor > 0.0) {
        double e0[3];
        cfi_v3_sub(p[2], p[1], e0);
        double floor_area = weight_floor * (cfi_v3_dot(e0, e0) + cfi_v3_dot(e1, e1) + cfi_v3_dot(e2, e2));
        if (weight_area < floor_area) weight_area = floor_area;
    }
    for (int k = 0; k < 3; ++k) {
        double u[3], v[3];
        cfi_v3_sub(p[(k + 1) % 3], p[k], u);
        cfi_v3_sub(p[(k + 2) % 3], p[k], v);
        cot[k] = cfi_v3_dot(u, v) / weight_area;
    }
    if (double_area) *double_area = a2;
    return CF_OK;
}

/* grad phi_k = N x e_k / (2 A), e_k the edge opposite corner k traversed
 * counter-clockwise (from corner k+1 to corner k+2). */
cf_status cfi_face_hat_gradients(cf_context *ctx, const cf_mesh *mesh, const double *positions, int32_t f,
                                 double g[9], double *area)
{
    const int32_t *t = mesh->triangles + 3 * f;
    double n[3];
    cfi_face_area_vector(mesh, positions, f, n);
    double a2 = cfi_v3_norm(n);
    if (!(a2 > 0.0)) return cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "face %d: zero area", f);
    for (int c = 0; c < 3; ++c) n[c] /= a2;
    for (int k = 0; k < 3; ++k) {
        double e[3];
        cfi_v3_sub(positions + 3 * t[(k + 2) % 3], positions + 3 * t[(k + 1) % 3], e);
        cfi_v3_cross(n, e, g + 3 * k);
        for (int c = 0; c < 3; ++c) g[3 * k + c] /= a2;
    }
    if (area) *area = 0.5 * a2;
    return CF_OK;
}

void cfi_vertex_area_vectors(const cf_mesh *mesh, const double *positions, double *out)
{
    for (int64_t i = 0; i < 3 * (int64_t)mesh->nv; ++i) out[i] = 0.0;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        double n[3];
        cfi_face_area_vector(mesh, positions, f, n);
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c) out[3 * mesh->triangles[3 * f + k] + c] += n[c];
    }
}
