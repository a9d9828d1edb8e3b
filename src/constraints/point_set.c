/*
 * Point sets: vertex selections from index lists and axis-aligned boxes
 * (absolute or relative to the bounding box). Files: constraint_file.c.
 */
#include "constraints/constraints_internal.h"

#include <math.h>
#include <string.h>

cf_point_set *cfi_point_set_alloc(cf_context *ctx, int32_t count)
{
    cf_point_set *s = cfi_malloc(ctx, sizeof *s);
    if (!s) return NULL;
    memset(s, 0, sizeof *s);
    s->ctx = ctx;
    s->count = count;
    s->vertices = CFI_ALLOC(ctx, int32_t, (size_t)(count > 0 ? count : 0));
    if (!s->vertices) {
        cf_point_set_destroy(&s);
        return NULL;
    }
    return s;
}

void cf_point_set_destroy(cf_point_set **set)
{
    if (!set || !*set) return;
    cf_point_set *s = *set;
    cf_context *ctx = s->ctx;
    CFI_FREE(ctx, s->vertices, (size_t)(s->count > 0 ? s->count : 0));
    cfi_free(ctx, s, sizeof *s);
    *set = NULL;
}

/* A mark per vertex (its position in the list + 1) sorts the list and finds
 * repeats in O(nv + count) without a comparator. */
cf_status cf_point_set_from_indices(cf_context *ctx, int32_t vertex_count, int32_t count, const int32_t *indices,
                                    cf_point_set **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "point set: output is NULL");
    *out = NULL;
    if (vertex_count < 0 || count < 0 || (count > 0 && !indices))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "point set: %d indices of %d vertices, list %s", (int)count,
                         (int)vertex_count, indices ? "given" : "NULL");
    for (int32_t k = 0; k < count; ++k)
        if (indices[k] < 0 || indices[k] >= vertex_count)
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "point set: indices[%d] = %d is not a vertex (mesh has %d)", k,
                             indices[k], vertex_count);
    int32_t *mark = CFI_ALLOC(ctx, int32_t, (size_t)(vertex_count > 0 ? vertex_count : 0));
    if (!mark) return CF_ERR_NOMEM;
    cf_status st = CF_OK;
    for (int32_t k = 0; k < count && st == CF_OK; ++k) {
        int32_t v = indices[k];
        if (mark[v])
            st = cfi_error(ctx, CF_ERR_INVALID_ARG, "point set: vertex %d is listed twice (indices[%d] and [%d])", v,
                           mark[v] - 1, k);
        mark[v] = k + 1;
    }
    cf_point_set *s = st == CF_OK ? cfi_point_set_alloc(ctx, count) : NULL;
    if (st == CF_OK && !s) st = CF_ERR_NOMEM;
    if (st == CF_OK) {
        int32_t n = 0;
        for (int32_t v = 0; v < vertex_count; ++v)
            if (mark[v]) s->vertices[n++] = v;
        *out = s;
    }
    CFI_FREE(ctx, mark, (size_t)(vertex_count > 0 ? vertex_count : 0));
    return st;
}

int32_t cfi_select_box(int32_t nv, const double *x, const double lo_in[3], const double hi_in[3], int relative,
                       int32_t *members)
{
    double lo[3] = {lo_in[0], lo_in[1], lo_in[2]}, hi[3] = {hi_in[0], hi_in[1], hi_in[2]};
    if (relative) {
        double bmin[3] = {INFINITY, INFINITY, INFINITY}, bmax[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int32_t v = 0; v < nv; ++v)
            for (int d = 0; d < 3; ++d) {
                bmin[d] = fmin(bmin[d], x[3 * v + d]);
                bmax[d] = fmax(bmax[d], x[3 * v + d]);
            }
        for (int d = 0; d < 3; ++d) {
            double ext = bmax[d] - bmin[d];
            /* A small slack so that fractions 0 and 1 include the extreme
             * vertices despite rounding. */
            lo[d] = bmin[d] + lo[d] * ext - 1e-12 * (ext + 1.0);
            hi[d] = bmin[d] + hi[d] * ext + 1e-12 * (ext + 1.0);
        }
    }
    int32_t count = 0;
    for (int32_t v = 0; v < nv; ++v) {
        const double *p = x + 3 * v;
        if (p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] && p[1] <= hi[1] && p[2] >= lo[2] && p[2] <= hi[2])
            members[count++] = v;
    }
    return count;
}

cf_status cf_point_set_from_box(cf_context *ctx, int32_t vertex_count, const double *positions, const double min[3],
                                const double max[3], int32_t relative, cf_point_set **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "point set: output is NULL");
    *out = NULL;
    if (vertex_count < 0 || (vertex_count > 0 && !positions) || !min || !max)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "point set from box: NULL argument or %d vertices", (int)vertex_count);
    for (int d = 0; d < 3; ++d)
        if (!isfinite(min[d]) || !isfinite(max[d]))
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "point set from box: the box is not finite");
    int32_t *members = CFI_ALLOC(ctx, int32_t, (size_t)(vertex_count > 0 ? vertex_count : 0));
    if (!members) return CF_ERR_NOMEM;
    int32_t n = cfi_select_box(vertex_count, positions, min, max, relative, members);
    cf_point_set *s = cfi_point_set_alloc(ctx, n);
    if (s) memcpy(s->vertices, members, (size_t)n * sizeof *members);
    CFI_FREE(ctx, members, (size_t)(vertex_count > 0 ? vertex_count : 0));
    if (!s) return CF_ERR_NOMEM;
    *out = s;
    return CF_OK;
}
