/*
 * Quaternions q = w + x i + y j + z k, stored (w, x, y, z). Vectors of R^3
 * are imaginary quaternions (0, x, y, z). One shared type for every method.
 */
#ifndef CURVFLOW_QUATERNION_H
#define CURVFLOW_QUATERNION_H

#include "curvflow/curvflow.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cf_quat {
    double w, x, y, z;
} cf_quat;

CF_API cf_quat cf_quat_make(double w, double x, double y, double z);
CF_API cf_quat cf_quat_from_vector(const double v[3]);
CF_API void cf_quat_to_vector(cf_quat q, double v[3]);     /* imaginary part */
CF_API cf_quat cf_quat_add(cf_quat a, cf_quat b);
CF_API cf_quat cf_quat_sub(cf_quat a, cf_quat b);
CF_API cf_quat cf_quat_scale(cf_quat a, double s);
CF_API cf_quat cf_quat_mul(cf_quat a, cf_quat b);          /* Hamilton product a b */
CF_API cf_quat cf_quat_conj(cf_quat a);
CF_API double cf_quat_norm2(cf_quat a);
CF_API double cf_quat_norm(cf_quat a);
CF_API cf_quat cf_quat_inverse(cf_quat a);                 /* conj / |a|^2; zero gives zero */
CF_API cf_quat cf_quat_normalize(cf_quat a);
/* Unit quaternion rotating by `angle` radians about `axis` (normalised
 * here; a zero or NULL axis gives the identity). Pointer arguments of
 * the functions below may be NULL: nothing is read or written. */
CF_API cf_quat cf_quat_from_axis_angle(const double axis[3], double angle);
/* conj(q) v q for an imaginary v: the map of spin transformations (Crane
 * et al. 2011), i.e. the inverse of the rotation q v conj(q), scaled by
 * |q|^2. */
CF_API void cf_quat_conj_sandwich(cf_quat q, const double v[3], double out[3]);

/* Real 4 x 4 matrix of left multiplication p -> q p (row-major, 16
 * doubles), Le Folgoc Eq. (7):
 *   [ w -x -y -z ]
 *   [ x  w -z  y ]
 *   [ y  z  w -x ]
 *   [ z -y  x  w ]  */
CF_API void cf_quat_left_matrix(cf_quat q, double m[16]);
/* Real 4 x 4 matrix of right multiplication p -> p q (row-major). */
CF_API void cf_quat_right_matrix(cf_quat q, double m[16]);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_QUATERNION_H */
