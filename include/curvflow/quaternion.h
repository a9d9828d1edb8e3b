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
/* Real 4 x 4 matrix of right multiplication p -> p q (row-major):
 *   [ w -x -y -z ]
 *   [ x  w  z -y ]
 *   [ y -z  w  x ]
 *   [ z  y -x  w ]
 * Left and right matrices commute (L(a) R(b) p = a p b). */
CF_API void cf_quat_right_matrix(cf_quat q, double m[16]);

/* Inverse of cf_quat_left_matrix / cf_quat_right_matrix: the quaternion
 * whose matrix is nearest to m (row-major 4 x 4) in the Frobenius norm,
 * i.e. the average of the four entries that hold each component. Exact
 * (q back bit for bit) on a matrix made by the functions above; on a block
 * that is not a quaternion's matrix it is the orthogonal projection onto
 * those matrices. A NULL m gives zero. */
CF_API cf_quat cf_quat_from_left_matrix(const double m[16]);
CF_API cf_quat cf_quat_from_right_matrix(const double m[16]);

/* (w, x, y, z) arrays <-> cf_quat, for quaternion fields stored as 4
 * doubles per element (as the methods' 4 nv vectors are). NULL reads as
 * zero / writes nothing. */
CF_API cf_quat cf_quat_load(const double p[4]);
CF_API void cf_quat_store(cf_quat q, double p[4]);

/* Rotation matrix (3 x 3, row-major) of a UNIT quaternion: r v = q v conj(q)
 * for v in R^3 (imaginary quaternions), i.e. a rotation by angle theta about
 * the unit axis u for q = cos(theta/2) + sin(theta/2) u, counter-clockwise
 * seen from the tip of u (right-hand rule). The unit-norm formula
 * (1 - 2 (y^2 + z^2), ...) is used as is: normalise q first. Note the
 * opposite order of cf_quat_conj_sandwich (conj(q) v q = r^T v |q|^2). */
CF_API void cf_quat_to_rotation_matrix(cf_quat q, double r[9]);
/* Unit quaternion of a rotation matrix (row-major), from the largest of
 * the four diagonal combinations (Shepperd's branch choice, no
 * cancellation), normalised; either sign of q may come back (q and -q are
 * the same rotation). r must be a rotation (orthogonal, det +1); the input
 * is not checked. A NULL r gives the identity. */
CF_API cf_quat cf_quat_from_rotation_matrix(const double r[9]);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_QUATERNION_H */
