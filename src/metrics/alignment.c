/*
 * Similarity (rotation + uniform scale + translation) alignment of
 * corresponding point sets, Umeyama 1991 (Eqs. 34-42), with the 3 x 3 SVD of
 * svd3.c. The signed SVD already carries Umeyama's reflection correction
 * S = diag(1, 1, det U det V): R = U V^T and scale = (s0 + s1 + s2) / var_x.
 */
#include "metrics/metrics_internal.h"

#include <math.h>

cf_status cf_similarity_align(cf_context *ctx, int32_t n, const double *source, const double *target,
                              const double *weights, int with_scale, double rotation[9], double *scale,
                              double translation[3], double *rms)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!source || !target || !rotation || !scale || !translation)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "similarity_align: NULL argument");
    if (n < 1 || n > INT32_MAX / 3)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "similarity_align: point count %d outside [1, %d]", n, INT32_MAX / 3);
    double wsum = 0.0, mx[3] = {0, 0, 0}, my[3] = {0, 0, 0};
    for (int32_t i = 0; i < n; ++i) {
        double w = weights ? weights[i] : 1.0;
        if (!isfinite(w) || w < 0.0)
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "similarity_align: weight %d is negative or not finite", i);
        for (int c = 0; c < 3; ++c) {
            if (!isfinite(source[3 * i + c]) || !isfinite(target[3 * i + c]))
                return cfi_error(ctx, CF_ERR_NONFINITE, "similarity_align: point %d is not finite", i);
            mx[c] += w * source[3 * i + c];
            my[c] += w * target[3 * i + c];
        }
        wsum += w;
    }
    if (!(wsum > 0.0)) return cfi_error(ctx, CF_ERR_INVALID_ARG, "similarity_align: weights sum to zero");
    for (int c = 0; c < 3; ++c) {
        mx[c] /= wsum;
        my[c] /= wsum;
    }
    /* Umeyama Eqs. (36), (38): cross-covariance and source variance */
    double cov[9] = {0}, varx = 0.0;
    for (int32_t i = 0; i < n; ++i) {
        double w = (weights ? weights[i] : 1.0) / wsum, dx[3], dy[3];
        for (int c = 0; c < 3; ++c) {
            dx[c] = source[3 * i + c] - mx[c];
            dy[c] = target[3 * i + c] - my[c];
        }
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) cov[3 * r + c] += w * dy[r] * dx[c];
        varx += w * (dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2]);
    }
    double u[9], sv[3], v[9];
    cf_status s = cf_svd3(cov, u, sv, v);
    if (s != CF_OK) return cfi_error(ctx, s, "similarity_align: SVD failed");
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            rotation[3 * r + c] = u[3 * r] * v[3 * c] + u[3 * r + 1] * v[3 * c + 1] + u[3 * r + 2] * v[3 * c + 2];
    double sc = 1.0;
    if (with_scale) {
        if (!(varx > 0.0)) return cfi_error(ctx, CF_ERR_NUMERICAL, "similarity_align: source points coincide");
        sc = (sv[0] + sv[1] + sv[2]) / varx; /* Umeyama Eq. (42) */
        if (!(sc > 0.0))
            return cfi_error(ctx, CF_ERR_NUMERICAL, "similarity_align: no positive scale (degenerate target)");
    }
    for (int r = 0; r < 3; ++r)
        translation[r] = my[r] - sc * (rotation[3 * r] * mx[0] + rotation[3 * r + 1] * mx[1] + rotation[3 * r + 2] * mx[2]);
    *scale = sc;
    if (rms) {
        double e = 0.0;
        for (int32_t i = 0; i < n; ++i) {
            double w = (weights ? weights[i] : 1.0) / wsum, y[3];
            cf_similarity_apply(1, rotation, sc, translation, source + 3 * i, y);
            for (int c = 0; c < 3; ++c) e += w * (y[c] - target[3 * i + c]) * (y[c] - target[3 * i + c]);
        }
        *rms = sqrt(e);
    }
    return CF_OK;
}

void cf_similarity_apply(int32_t n, const double rotation[9], double scale, const double translation[3],
                         const double *x, double *out)
{
    if (!rotation || !translation || !x || !out || n > INT32_MAX / 3) return;
    for (int32_t i = 0; i < n; ++i) {
        double p[3] = {x[3 * i], x[3 * i + 1], x[3 * i + 2]};
        for (int r = 0; r < 3; ++r)
            out[3 * i + r] =
                scale * (rotation[3 * r] * p[0] + rotation[3 * r + 1] * p[1] + rotation[3 * r + 2] * p[2]) +
                translation[r];
    }
}
