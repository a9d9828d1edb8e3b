/*
 * Quaternion arithmetic (include/curvflow/quaternion.h). q = w + x i + y j + z k
 * with i^2 = j^2 = k^2 = ijk = -1 (Hamilton). The 4 x 4 real matrices follow
 * Le Folgoc et al., Eq. (7), with vectors stored (w, x, y, z).
 */
#include "curvflow/quaternion.h"

#include <math.h>

cf_quat cf_quat_make(double w, double x, double y, double z)
{
    cf_quat q = {w, x, y, z};
    return q;
}

cf_quat cf_quat_from_vector(const double v[3]) { return v ? cf_quat_make(0.0, v[0], v[1], v[2]) : cf_quat_make(0.0, 0.0, 0.0, 0.0); }

void cf_quat_to_vector(cf_quat q, double v[3])
{
    if (!v) return;
    v[0] = q.x;
    v[1] = q.y;
    v[2] = q.z;
}

cf_quat cf_quat_add(cf_quat a, cf_quat b) { return cf_quat_make(a.w + b.w, a.x + b.x, a.y + b.y, a.z + b.z); }
cf_quat cf_quat_sub(cf_quat a, cf_quat b) { return cf_quat_make(a.w - b.w, a.x - b.x, a.y - b.y, a.z - b.z); }
cf_quat cf_quat_scale(cf_quat a, double s) { return cf_quat_make(s * a.w, s * a.x, s * a.y, s * a.z); }

/* (a0 + a)(b0 + b) = a0 b0 - a.b + a0 b + b0 a + a x b. A compound
 * literal rather than cf_quat_make: an exported function is not inlined
 * into its neighbours (it could be interposed), and this one sits in the
 * ARAP local step's inner loop. */
cf_quat cf_quat_mul(cf_quat a, cf_quat b)
{
    return (cf_quat){a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
                     a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

cf_quat cf_quat_conj(cf_quat a) { return cf_quat_make(a.w, -a.x, -a.y, -a.z); }
double cf_quat_norm2(cf_quat a) { return a.w * a.w + a.x * a.x + a.y * a.y + a.z * a.z; }

/* hypot-style scaling so that tiny or huge quaternions do not under/overflow */
double cf_quat_norm(cf_quat a)
{
    double m = fmax(fmax(fabs(a.w), fabs(a.x)), fmax(fabs(a.y), fabs(a.z)));
    if (m == 0.0 || !isfinite(m)) return m;
    cf_quat s = cf_quat_scale(a, 1.0 / m);
    return m * sqrt(cf_quat_norm2(s));
}

cf_quat cf_quat_inverse(cf_quat a)
{
    double n2 = cf_quat_norm2(a);
    if (n2 == 0.0) return cf_quat_make(0.0, 0.0, 0.0, 0.0);
    return cf_quat_scale(cf_quat_conj(a), 1.0 / n2);
}

cf_quat cf_quat_normalize(cf_quat a)
{
    double n = cf_quat_norm(a);
    if (n == 0.0) return a;
    return cf_quat_scale(a, 1.0 / n);
}

/* q = cos(angle/2) + sin(angle/2) u rotates v by `angle` about u through
 * v -> q v conj(q) (right-hand rule). */
cf_quat cf_quat_from_axis_angle(const double axis[3], double angle)
{
    if (!axis) return cf_quat_make(1.0, 0.0, 0.0, 0.0);
    double n = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    if (n == 0.0) return cf_quat_make(1.0, 0.0, 0.0, 0.0);
    double s = sin(0.5 * angle) / n;
    return cf_quat_make(cos(0.5 * angle), s * axis[0], s * axis[1], s * axis[2]);
}

void cf_quat_conj_sandwich(cf_quat q, const double v[3], double out[3])
{
    if (!v || !out) return;
    cf_quat r = cf_quat_mul(cf_quat_mul(cf_quat_conj(q), cf_quat_from_vector(v)), q);
    cf_quat_to_vector(r, out);
}

/* Le Folgoc Eq. (7): column j of the matrix is q e_j. */
void cf_quat_left_matrix(cf_quat q, double m[16])
{
    if (!m) return;
    m[0] = q.w;  m[1] = -q.x; m[2] = -q.y;  m[3] = -q.z;
    m[4] = q.x;  m[5] = q.w;  m[6] = -q.z;  m[7] = q.y;
    m[8] = q.y;  m[9] = q.z;  m[10] = q.w;  m[11] = -q.x;
    m[12] = q.z; m[13] = -q.y; m[14] = q.x; m[15] = q.w;
}

/* p q: the imaginary block is transposed relative to the left matrix
 * (quaternion multiplication does not commute). */
void cf_quat_right_matrix(cf_quat q, double m[16])
{
    if (!m) return;
    m[0] = q.w;  m[1] = -q.x; m[2] = -q.y;  m[3] = -q.z;
    m[4] = q.x;  m[5] = q.w;  m[6] = q.z;   m[7] = -q.y;
    m[8] = q.y;  m[9] = -q.z; m[10] = q.w;  m[11] = q.x;
    m[12] = q.z; m[13] = q.y; m[14] = -q.x; m[15] = q.w;
}

/* Each component sits in four entries of the matrix, with the signs of the
 * layouts above; averaging them is the orthogonal projection onto the
 * 4-dimensional space of left (right) multiplication matrices. */
cf_quat cf_quat_from_left_matrix(const double m[16])
{
    if (!m) return cf_quat_make(0.0, 0.0, 0.0, 0.0);
    /* summed in pairs so that a quaternion's own matrix gives 4 q exactly */
    return cf_quat_make(0.25 * ((m[0] + m[5]) + (m[10] + m[15])), 0.25 * ((m[4] - m[1]) + (m[14] - m[11])),
                        0.25 * ((m[8] - m[2]) + (m[7] - m[13])), 0.25 * ((m[12] - m[3]) + (m[9] - m[6])));
}

cf_quat cf_quat_from_right_matrix(const double m[16])
{
    if (!m) return cf_quat_make(0.0, 0.0, 0.0, 0.0);
    return cf_quat_make(0.25 * ((m[0] + m[5]) + (m[10] + m[15])), 0.25 * ((m[4] - m[1]) + (m[11] - m[14])),
                        0.25 * ((m[8] - m[2]) + (m[13] - m[7])), 0.25 * ((m[12] - m[3]) + (m[6] - m[9])));
}

cf_quat cf_quat_load(const double p[4]) { return p ? (cf_quat){p[0], p[1], p[2], p[3]} : (cf_quat){0.0, 0.0, 0.0, 0.0}; }

void cf_quat_store(cf_quat q, double p[4])
{
    if (!p) return;
    p[0] = q.w;
    p[1] = q.x;
    p[2] = q.y;
    p[3] = q.z;
}

/* q v conj(q) expanded for |q| = 1 (w^2 = 1 - x^2 - y^2 - z^2 folded into
 * the diagonal). */
void cf_quat_to_rotation_matrix(cf_quat q, double r[9])
{
    if (!r) return;
    double w = q.w, x = q.x, y = q.y, z = q.z;
    r[0] = 1 - 2 * (y * y + z * z); r[1] = 2 * (x * y - w * z);     r[2] = 2 * (x * z + w * y);
    r[3] = 2 * (x * y + w * z);     r[4] = 1 - 2 * (x * x + z * z); r[5] = 2 * (y * z - w * x);
    r[6] = 2 * (x * z - w * y);     r[7] = 2 * (y * z + w * x);     r[8] = 1 - 2 * (x * x + y * y);
}

/* 4 w^2 = 1 + tr r, 4 x^2 = 1 + r00 - r11 - r22, ...: take the square root
 * of the largest, the other components from the off-diagonal sums and
 * differences divided by it. */
cf_quat cf_quat_from_rotation_matrix(const double r[9])
{
    if (!r) return cf_quat_make(1.0, 0.0, 0.0, 0.0);
    double q[4];
    double tr = r[0] + r[4] + r[8];
    if (tr > 0.0) {
        double s = 2.0 * sqrt(tr + 1.0);
        q[0] = 0.25 * s; q[1] = (r[7] - r[5]) / s; q[2] = (r[2] - r[6]) / s; q[3] = (r[3] - r[1]) / s;
    } else if (r[0] > r[4] && r[0] > r[8]) {
        double s = 2.0 * sqrt(1.0 + r[0] - r[4] - r[8]);
        q[0] = (r[7] - r[5]) / s; q[1] = 0.25 * s; q[2] = (r[1] + r[3]) / s; q[3] = (r[2] + r[6]) / s;
    } else if (r[4] > r[8]) {
        double s = 2.0 * sqrt(1.0 + r[4] - r[0] - r[8]);
        q[0] = (r[2] - r[6]) / s; q[1] = (r[1] + r[3]) / s; q[2] = 0.25 * s; q[3] = (r[5] + r[7]) / s;
    } else {
        double s = 2.0 * sqrt(1.0 + r[8] - r[0] - r[4]);
        q[0] = (r[3] - r[1]) / s; q[1] = (r[2] + r[6]) / s; q[2] = (r[5] + r[7]) / s; q[3] = 0.25 * s;
    }
    double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (int k = 0; k < 4; ++k) q[k] /= n;
    return cf_quat_make(q[0], q[1], q[2], q[3]);
}
