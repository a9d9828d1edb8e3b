/*
 * Single-shape figures: area, volume, Willmore energy (W / 4 pi), total
 * angle defect against 2 pi chi, and the least-squares sphere (algebraic
 * fit of |x|^2 = 2 c.x + d, then Gauss-Newton on the geometric residuals
 * |x_i - c| - R) with the max and RMS deviation relative to R.
 */
#include "metrics/metrics_internal.h"
#include "curvflow/ops.h"

#include <math.h>

#define PI_ 3.14159265358979323846

/* Solves the 4 x 4 system a x = b by Gaussian elimination with partial
 * pivoting; returns 0 if a pivot is below tol times the largest entry. */
static int solve4(double a[16], double b[4], double x[4])
{
    double scale = 0.0;
    for (int i = 0; i < 16; ++i) scale = fmax(scale, fabs(a[i]));
    if (!(scale > 0.0)) return 0;
    for (int col = 0; col < 4; ++col) {
        int piv = col;
        for (int r = col + 1; r < 4; ++r)
            if (fabs(a[4 * r + col]) > fabs(a[4 * piv + col])) piv = r;
        if (!(fabs(a[4 * piv + col]) > 1e-13 * scale)) return 0;
        if (piv != col) {
            for (int c = 0; c < 4; ++c) {
                double t = a[4 * col + c];
                a[4 * col + c] = a[4 * piv + c];
                a[4 * piv + c] = t;
            }
            double t = b[col];
            b[col] = b[piv];
            b[piv] = t;
        }
        for (int r = col + 1; r < 4; ++r) {
            double f = a[4 * r + col] / a[4 * col + col];
            for (int c = col; c < 4; ++c) a[4 * r + c] -= f * a[4 * col + c];
            b[r] -= f * b[col];
        }
    }
    for (int r = 3; r >= 0; --r) {
        double s = b[r];
        for (int c = r + 1; c < 4; ++c) s -= a[4 * r + c] * x[c];
        x[r] = s / a[4 * r + r];
    }
    return 1;
}

cf_status cf_fit_sphere(cf_context *ctx, int32_t n, const double *points, double center[3], double *radius,
                        double *max_dev, double *rms_dev)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!points || !center || !radius) return cfi_error(ctx, CF_ERR_INVALID_ARG, "fit_sphere: NULL argument");
    if (n < 4) return cfi_error(ctx, CF_ERR_NUMERICAL, "fit_sphere: need at least 4 points, got %d", n);
    if (n > INT32_MAX / 3) return cfi_error(ctx, CF_ERR_INVALID_ARG, "fit_sphere: too many points (%d)", n);
    /* work relative to the centroid, scaled to unit RMS radius, for
     * conditioning */
    double g[3] = {0.0, 0.0, 0.0};
    for (int32_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            if (!isfinite(points[3 * i + c]))
                return cfi_error(ctx, CF_ERR_NONFINITE, "fit_sphere: point %d is not finite", i);
            g[c] += points[3 * i + c] / n;
        }
    double rms = 0.0;
    for (int32_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) rms += (points[3 * i + c] - g[c]) * (points[3 * i + c] - g[c]);
    rms = sqrt(rms / n);
    if (!(rms > 0.0)) return cfi_error(ctx, CF_ERR_NUMERICAL, "fit_sphere: all points coincide");
    /* algebraic fit: rows (2x, 2y, 2z, 1) . (c, d) = |p|^2 */
    double ata[16] = {0}, atb[4] = {0}, sol[4];
    for (int32_t i = 0; i < n; ++i) {
        double p[3], row[4];
        for (int c = 0; c < 3; ++c) p[c] = (points[3 * i + c] - g[c]) / rms;
        row[0] = 2.0 * p[0];
        row[1] = 2.0 * p[1];
        row[2] = 2.0 * p[2];
        row[3] = 1.0;
        double rhs = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        for (int r = 0; r < 4; ++r) {
            atb[r] += row[r] * rhs;
            for (int c = 0; c < 4; ++c) ata[4 * r + c] += row[r] * row[c];
        }
    }
    if (!solve4(ata, atb, sol)) return cfi_error(ctx, CF_ERR_NUMERICAL, "fit_sphere: points are coplanar");
    double c0[3] = {sol[0], sol[1], sol[2]};
    double r2 = sol[3] + c0[0] * c0[0] + c0[1] * c0[1] + c0[2] * c0[2];
    if (!(r2 > 0.0)) return cfi_error(ctx, CF_ERR_NUMERICAL, "fit_sphere: no real sphere fits the points");
    double r = sqrt(r2);
    /* Gauss-Newton on the geometric residuals (unknowns c, R) */
    for (int it = 0; it < 20; ++it) {
        double jtj[16] = {0}, jtr[4] = {0}, step[4];
        for (int32_t i = 0; i < n; ++i) {
            double d[3], len;
            for (int c = 0; c < 3; ++c) d[c] = (points[3 * i + c] - g[c]) / rms - c0[c];
            len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (!(len > 0.0)) continue;
            double row[4] = {-d[0] / len, -d[1] / len, -d[2] / len, -1.0}, res = len - r;
            for (int a = 0; a < 4; ++a) {
                jtr[a] -= row[a] * res;
                for (int b = 0; b < 4; ++b) jtj[4 * a + b] += row[a] * row[b];
            }
        }
        if (!solve4(jtj, jtr, step)) break;
        for (int c = 0; c < 3; ++c) c0[c] += step[c];
        r += step[3];
        if (sqrt(step[0] * step[0] + step[1] * step[1] + step[2] * step[2] + step[3] * step[3]) < 1e-15 * r) break;
    }
    double dmax = 0.0, dsum = 0.0;
    for (int32_t i = 0; i < n; ++i) {
        double d[3];
        for (int c = 0; c < 3; ++c) d[c] = (points[3 * i + c] - g[c]) / rms - c0[c];
        double dev = fabs(sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) - r) / r;
        dmax = fmax(dmax, dev);
        dsum += dev * dev;
    }
    for (int c = 0; c < 3; ++c) center[c] = g[c] + rms * c0[c];
    *radius = rms * r;
    if (max_dev) *max_dev = dmax;
    if (rms_dev) *rms_dev = sqrt(dsum / n);
    return CF_OK;
}

cf_status cf_shape_summary_compute(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                   cf_shape_summary *out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!mesh || !positions || !out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "shape_summary: NULL argument");
    cf_shape_summary sm = {0};
    cf_status s;
    if ((s = cf_total_area(ctx, mesh, positions, &sm.area)) != CF_OK) return s;
    if ((s = cf_enclosed_volume(ctx, mesh, positions, &sm.volume)) != CF_OK) return s;
    if ((s = cf_willmore_energy(ctx, mesh, positions, &sm.willmore)) != CF_OK) return s;
    sm.willmore_over_4pi = sm.willmore / (4.0 * PI_);
    double *k = CFI_ALLOC(ctx, double, mesh->nv);
    if (!k) return CF_ERR_NOMEM;
    s = cf_angle_defect(ctx, mesh, positions, k);
    if (s == CF_OK) {
        for (int32_t v = 0; v < mesh->nv; ++v) sm.total_angle_defect += k[v];
        sm.gauss_bonnet_target = 2.0 * PI_ * mesh->euler_characteristic;
    }
    CFI_FREE(ctx, k, mesh->nv);
    if (s != CF_OK) return s;
    s = cf_fit_sphere(ctx, mesh->nv, positions, sm.sphere_center, &sm.sphere_radius, &sm.sphere_max_deviation,
                      &sm.sphere_rms_deviation);
    if (s != CF_OK) return s;
    *out = sm;
    return CF_OK;
}
