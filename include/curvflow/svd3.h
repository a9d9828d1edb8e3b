/*
 * Dense 3 x 3 kernels of the linear-algebra layer (src/linalg/svd3.c): the
 * signed singular value decomposition and the closest rotation built from
 * it, used by Procrustes alignment (metrics), the ARAP / stretching local
 * steps (stretch_bend_edit) and any method with per-element rotations.
 *
 * Matrices are 3 x 3 row-major (m[3 r + c]). These are pure kernels: no
 * context, no allocation. Also reachable through curvflow/linalg.h and,
 * for existing callers, curvflow/metrics.h.
 */
#ifndef CURVFLOW_SVD3_H
#define CURVFLOW_SVD3_H

#include "curvflow/curvflow.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Signed singular value decomposition a = u diag(s) v^T by one-sided
 * (Hestenes) Jacobi rotations, accurate to the relative precision of the
 * small singular values (no a^T a is formed).
 * u and v are rotations (det +1). Sign correction: s[0] >= s[1] >= |s[2]|
 * and s[2] carries the sign of det(a), i.e. s[2] < 0 exactly when a
 * contains a reflection; |s| are the usual singular values. Rank-deficient
 * inputs get an arbitrary orthonormal completion of u.
 * Statuses: CF_OK, CF_ERR_INVALID_ARG (NULL), CF_ERR_NONFINITE (NaN/Inf
 * entry; outputs then hold identity/zero). No context: this is a pure kernel. */
CF_API cf_status cf_svd3(const double a[9], double u[9], double s[3], double v[9]);

/* Closest rotation r to a in the Frobenius norm (maximises trace(r^T a)):
 * r = u v^T with the signed SVD above, which is the polar factor with the
 * determinant correction "negate the column of the smallest singular value".
 * For an ARAP/Procrustes covariance S = sum_k w_k p_k q_k^T (p rest, q
 * deformed edge) the rotation taking p to q is cf_rotation_from_covariance
 * of S^T. Statuses as cf_svd3 (r is the identity on failure). */
CF_API cf_status cf_rotation_from_covariance(const double a[9], double r[9]);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_SVD3_H */
