/*
 * Robust 3 x 3 signed SVD by one-sided (Hestenes) Jacobi rotations and the
 * closest rotation built from it. Rotations act on the columns of a scaled
 * copy of a until they are mutually orthogonal (B = a V); then the column
 * norms are the singular values and U the normalised columns. Because a^T a
 * is never formed, small singular values keep their relative accuracy
 * (Demmel & Veselic 1992). Column swaps used for sorting negate one column
 * in U and V alike so that V stays a rotation; the third column of U is
 * u0 x u1, which makes U a rotation and gives s[2] the sign of det(a).
 * (Moved here from src/metrics: it is dense linear algebra, used by metrics
 * and by the methods alike; declared in curvflow/svd3.h.)
 */
#include "curvflow/svd3.h"

#include <math.h>

#define SVD3_MAX_SWEEPS 32

static void set_identity(double m[9])
{
    for (int i = 0; i < 9; ++i) m[i] = (i % 4 == 0) ? 1.0 : 0.0;
}

static double col_dot(const double *m, int p, int q)
{
    return m[p] * m[q] + m[3 + p] * m[3 + q] + m[6 + p] * m[6 + q];
}

/* columns (p, q) <- (c p - s q, s p + c q) */
static void rotate_cols(double *m, int p, int q, double c, double s)
{
    for (int r = 0; r < 3; ++r) {
        double mp = m[3 * r + p], mq = m[3 * r + q];
        m[3 * r + p] = c * mp - s * mq;
        m[3 * r + q] = s * mp + c * mq;
    }
}

/* swap columns p, q and negate the new column q (determinant preserved) */
static void swap_cols(double *m, int p, int q)
{
    for (int r = 0; r < 3; ++r) {
        double t = m[3 * r + p];
        m[3 * r + p] = m[3 * r + q];
        m[3 * r + q] = -t;
    }
}

/* unit vector orthogonal to the unit vector u */
static void any_orthogonal(const double u[3], double out[3])
{
    /* cross with the coordinate axis least aligned with u */
    double ax = fabs(u[0]), ay = fabs(u[1]), az = fabs(u[2]);
    double e[3] = {0.0, 0.0, 0.0};
    if (ax <= ay && ax <= az) e[0] = 1.0;
    else if (ay <= az) e[1] = 1.0;
    else e[2] = 1.0;
    out[0] = u[1] * e[2] - u[2] * e[1];
    out[1] = u[2] * e[0] - u[0] * e[2];
    out[2] = u[0] * e[1] - u[1] * e[0];
    double n = sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2]);
    for (int i = 0; i < 3; ++i) out[i] /= n;
}

cf_status cf_svd3(const double a[9], double u[9], double s[3], double v[9])
{
    if (!a || !u || !s || !v) return CF_ERR_INVALID_ARG;
    set_identity(u);
    set_identity(v);
    s[0] = s[1] = s[2] = 0.0;
    double scale = 0.0;
    for (int i = 0; i < 9; ++i) {
        if (!isfinite(a[i])) return CF_ERR_NONFINITE;
        scale = fmax(scale, fabs(a[i]));
    }
    if (scale == 0.0) return CF_OK;
    /* scaling by the largest entry keeps the column dot products in range */
    double b[9];
    for (int i = 0; i < 9; ++i) b[i] = a[i] / scale;

    static const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    for (int sweep = 0; sweep < SVD3_MAX_SWEEPS; ++sweep) {
        int rotated = 0;
        for (int k = 0; k < 3; ++k) {
            int p = pairs[k][0], q = pairs[k][1];
            double alpha = col_dot(b, p, p), beta = col_dot(b, q, q), gamma = col_dot(b, p, q);
            /* columns orthogonal to working precision: skip */
            if (gamma == 0.0 || fabs(gamma) <= 1e-16 * sqrt(alpha * beta)) continue;
            /* rotation angle zeroing the (p, q) entry of B^T B (Hestenes 1958) */
            double zeta = (beta - alpha) / (2.0 * gamma);
            double t = (zeta >= 0.0 ? 1.0 : -1.0) / (fabs(zeta) + sqrt(1.0 + zeta * zeta));
            double c = 1.0 / sqrt(1.0 + t * t), sn = c * t;
            rotate_cols(b, p, q, c, sn);
            rotate_cols(v, p, q, c, sn);
            rotated = 1;
        }
        if (!rotated) break;
    }

    double norm[3];
    for (int k = 0; k < 3; ++k) norm[k] = sqrt(col_dot(b, k, k));
    /* sort columns by norm, descending (3-element bubble sort) */
    for (int pass = 0; pass < 2; ++pass)
        for (int k = 0; k < 2; ++k)
            if (norm[k] < norm[k + 1]) {
                double t = norm[k];
                norm[k] = norm[k + 1];
                norm[k + 1] = t;
                swap_cols(b, k, k + 1);
                swap_cols(v, k, k + 1);
            }

    double u0[3], u1[3], u2[3];
    for (int r = 0; r < 3; ++r) u0[r] = b[3 * r] / norm[0];
    if (norm[1] > 0.0) {
        for (int r = 0; r < 3; ++r) u1[r] = b[3 * r + 1] / norm[1];
        /* re-orthogonalise against u0 (matters only for tiny norm[1]) */
        double d = u0[0] * u1[0] + u0[1] * u1[1] + u0[2] * u1[2];
        for (int r = 0; r < 3; ++r) u1[r] -= d * u0[r];
        double n1 = sqrt(u1[0] * u1[0] + u1[1] * u1[1] + u1[2] * u1[2]);
        if (n1 > 0.0) {
            for (int r = 0; r < 3; ++r) u1[r] /= n1;
        } else {
            any_orthogonal(u0, u1);
        }
    } else {
        any_orthogonal(u0, u1);
    }
    u2[0] = u0[1] * u1[2] - u0[2] * u1[1];
    u2[1] = u0[2] * u1[0] - u0[0] * u1[2];
    u2[2] = u0[0] * u1[1] - u0[1] * u1[0];
    /* signed third singular value: the component of column 2 along u2 */
    double s2 = u2[0] * b[2] + u2[1] * b[5] + u2[2] * b[8];
    for (int r = 0; r < 3; ++r) {
        u[3 * r] = u0[r];
        u[3 * r + 1] = u1[r];
        u[3 * r + 2] = u2[r];
    }
    s[0] = norm[0] * scale;
    s[1] = norm[1] * scale;
    s[2] = s2 * scale;
    return CF_OK;
}

cf_status cf_rotation_from_covariance(const double a[9], double r[9])
{
    if (!r) return CF_ERR_INVALID_ARG;
    double u[9], s[3], v[9];
    cf_status st = cf_svd3(a, u, s, v);
    if (st != CF_OK) {
        set_identity(r);
        return st;
    }
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r[3 * i + j] = u[3 * i] * v[3 * j] + u[3 * i + 1] * v[3 * j + 1] + u[3 * i + 2] * v[3 * j + 2];
    return CF_OK;
}
