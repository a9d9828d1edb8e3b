/*
 * Internal pieces of the constraints module shared by its files: set
 * allocation, box selection and the point map of a rigid transform.
 */
#ifndef CF_CONSTRAINTS_CONSTRAINTS_INTERNAL_H
#define CF_CONSTRAINTS_CONSTRAINTS_INTERNAL_H

#include "core/core.h"
#include "curvflow/constraints.h"

/* Empty sets of `count` entries (arrays zeroed), or NULL (out of memory). */
cf_point_set *cfi_point_set_alloc(cf_context *ctx, int32_t count);
cf_handle_set *cfi_handle_set_alloc(cf_context *ctx, int32_t count);

/* Writes the vertices of x (3 nv) inside [lo, hi] (absolute, or fractions
 * of the bounding box when relative) into members (capacity nv), ascending;
 * returns how many. */
int32_t cfi_select_box(int32_t nv, const double *x, const double lo[3], const double hi[3], int relative,
                       int32_t *members);

/* Rotation matrix (row-major) for a UNIT axis and an angle in radians
 * (Rodrigues), right-hand rule. */
void cfi_axis_angle_matrix(const double axis[3], double angle, double r[9]);

/* o = c + s R (p - c) + t for one point (o may equal p). */
static inline void cfi_rigid_apply_point(const cf_rigid_transform *t, const double p[3], double o[3])
{
    const double *c = t->center, *r = t->rotation;
    double q[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    for (int d = 0; d < 3; ++d)
        o[d] = c[d] + t->scale * (r[3 * d] * q[0] + r[3 * d + 1] * q[1] + r[3 * d + 2] * q[2]) + t->translation[d];
}

#endif /* CF_CONSTRAINTS_CONSTRAINTS_INTERNAL_H */
