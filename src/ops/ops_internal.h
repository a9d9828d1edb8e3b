/*
 * Shared helpers of the operator files: argument checks and small 3-vector
 * routines. Internal (cfi_ prefix); not part of the public API.
 */
#ifndef CF_OPS_OPS_INTERNAL_H
#define CF_OPS_OPS_INTERNAL_H

#include "core/core.h"
#include "mesh/mesh_internal.h"

#include <math.h>

/* M_PI is not in strict C17 */
#define CFI_PI 3.14159265358979323846

/* Checks ctx, mesh, positions (finite) and the output pointer (may be
 * omitted by passing a non-NULL dummy). `fn` names the caller in the
 * message. Returns CF_OK or CF_ERR_INVALID_ARG / CF_ERR_NONFINITE. */
cf_status cfi_ops_check(cf_context *ctx, const cf_mesh *mesh, const double *positions, const void *out,
                        const char *fn);

/* Cotangent of the angle at corner k of face f, and twice the face area in
 * *double_area. Returns CF_ERR_DEGENERATE_FACE (with message) on a face of
 * zero area. weight_floor >= 0: the cotangents are taken as if twice the
 * area were at least weight_floor times the sum of the squared edge
 * lengths (the weights of a nearly flat face bounded by about
 * 1 / weight_floor; 0: the exact cotangents); *double_area stays exact. */
cf_status cfi_face_cotangents(cf_context *ctx, const cf_mesh *mesh, const double *positions, int32_t f,
                              double weight_floor, double cot[3], double *double_area);

/* Gradients of the three hat functions of face f (row k: grad phi_k,
 * 9 doubles) and its area (optional). CF_ERR_DEGENERATE_FACE on zero area. */
cf_status cfi_face_hat_gradients(cf_context *ctx, const cf_mesh *mesh, const double *positions, int32_t f,
                                 double g[9], double *area);

static inline void cfi_v3_sub(const double *a, const double *b, double *out)
{
    out[0] = a[0] - b[0];
    out[1] = a[1] - b[1];
    out[2] = a[2] - b[2];
}

static inline double cfi_v3_dot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static inline void cfi_v3_cross(const double *a, const double *b, double *out)
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static inline double cfi_v3_norm(const double *a) { return sqrt(cfi_v3_dot(a, a)); }

/* Twice the area vector of face f: (x1 - x0) x (x2 - x0). */
static inline void cfi_face_area_vector(const cf_mesh *mesh, const double *positions, int32_t f, double out[3])
{
    const int32_t *t = mesh->triangles + 3 * f;
    double e1[3], e2[3];
    cfi_v3_sub(positions + 3 * t[1], positions + 3 * t[0], e1);
    cfi_v3_sub(positions + 3 * t[2], positions + 3 * t[0], e2);
    cfi_v3_cross(e1, e2, out);
}

/* Sum over the faces around each vertex of their area vectors
 * (x1 - x0) x (x2 - x0): 3 nv doubles, overwritten. Unnormalised
 * area-weighted vertex normals (twice the area). */
void cfi_vertex_area_vectors(const cf_mesh *mesh, const double *positions, double *out);

/* Area of face f: half the norm of its area vector. */
static inline double cfi_face_area(const cf_mesh *mesh, const double *positions, int32_t f)
{
    double n[3];
    cfi_face_area_vector(mesh, positions, f, n);
    return 0.5 * cfi_v3_norm(n);
}

/* Angle at corner k of the triangle t (three vertex indices), as
 * atan2(|u x v|, u . v) with u, v the edges leaving the corner: accurate
 * also near 0 and pi, where acos of the normalised dot product is not. */
static inline double cfi_corner_angle(const double *positions, const int32_t *t, int k)
{
    double u[3], v[3], c[3];
    cfi_v3_sub(positions + 3 * t[(k + 1) % 3], positions + 3 * t[k], u);
    cfi_v3_sub(positions + 3 * t[(k + 2) % 3], positions + 3 * t[k], v);
    cfi_v3_cross(u, v, c);
    return atan2(cfi_v3_norm(c), cfi_v3_dot(u, v));
}

#endif /* CF_OPS_OPS_INTERNAL_H */
