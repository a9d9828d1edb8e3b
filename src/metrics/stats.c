/* Summary statistics (min/max/means/weighted std/percentiles) of a sample. */
#include "metrics/metrics_internal.h"

#include <math.h>
#include <stdlib.h>

static int compare_doubles(const void *pa, const void *pb)
{
    double a = *(const double *)pa, b = *(const double *)pb;
    return (a > b) - (a < b);
}

cf_status cf_stats_compute(cf_context *ctx, int64_t n, const double *values, const double *weights, cf_stats *out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out || (n > 0 && !values)) return cfi_error(ctx, CF_ERR_INVALID_ARG, "stats: NULL argument");
    if (n < 0) return cfi_error(ctx, CF_ERR_INVALID_ARG, "stats: negative count %lld", (long long)n);
    cf_stats st = {0};
    st.count = n;
    if (n == 0) {
        *out = st;
        return CF_OK;
    }
    double sum = 0.0, wsum = 0.0, wx = 0.0;
    st.min = INFINITY;
    st.max = -INFINITY;
    for (int64_t i = 0; i < n; ++i) {
        double w = weights ? weights[i] : 1.0;
        if (!isfinite(values[i]))
            return cfi_error(ctx, CF_ERR_NONFINITE, "stats: value %lld is not finite", (long long)i);
        if (!isfinite(w) || w < 0.0)
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "stats: weight %lld is negative or not finite", (long long)i);
        st.min = fmin(st.min, values[i]);
        st.max = fmax(st.max, values[i]);
        sum += values[i];
        wsum += w;
        wx += w * values[i];
    }
    st.mean = sum / (double)n;
    st.weighted_mean = wsum > 0.0 ? wx / wsum : st.mean;
    double wvar = 0.0;
    for (int64_t i = 0; i < n; ++i) {
        double w = weights ? weights[i] : 1.0, d = values[i] - st.weighted_mean;
        wvar += w * d * d;
    }
    st.weighted_std = wsum > 0.0 ? sqrt(wvar / wsum) : 0.0;
    double *sorted = CFI_ALLOC(ctx, double, n);
    if (!sorted) return CF_ERR_NOMEM;
    for (int64_t i = 0; i < n; ++i) sorted[i] = values[i];
    qsort(sorted, (size_t)n, sizeof(double), compare_doubles);
    /* nearest rank: the smallest value with at least p n values <= it */
    int64_t r50 = (int64_t)ceil(0.50 * (double)n) - 1, r95 = (int64_t)ceil(0.95 * (double)n) - 1;
    st.p50 = sorted[r50 < 0 ? 0 : r50];
    st.p95 = sorted[r95 < 0 ? 0 : r95];
    CFI_FREE(ctx, sorted, n);
    *out = st;
    return CF_OK;
}

cf_status cfi_metrics_check_pair(cf_context *ctx, const cf_mesh *mesh, const double *a, const double *b,
                                 const char *fn)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!mesh) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: mesh is NULL", fn);
    if (!a || !b) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: positions are NULL", fn);
    for (int64_t i = 0; i < 3 * (int64_t)mesh->nv; ++i)
        if (!isfinite(a[i]) || !isfinite(b[i]))
            return cfi_error(ctx, CF_ERR_NONFINITE, "%s: vertex %d: non-finite coordinate", fn, (int)(i / 3));
    return CF_OK;
}
