/*
 * Targets of constrained vertices (cf_handle_set: Zhao & Gortler, Sec. 4.1,
 * positional vertex constraints; fixed points of the other methods) and the
 * rigid transforms that make them from a selection.
 */
#include "constraints/constraints_internal.h"

#include <math.h>
#include <string.h>

/* ---- rigid transforms ----------------------------------------------------- */

void cf_rigid_transform_identity(cf_rigid_transform *t)
{
    if (!t) return;
    memset(t, 0, sizeof *t);
    t->rotation[0] = t->rotation[4] = t->rotation[8] = 1.0;
    t->scale = 1.0;
}

void cfi_axis_angle_matrix(const double axis[3], double angle, double r[9])
{
    double c = cos(angle), s = sin(angle), t = 1.0 - c;
    double x = axis[0], y = axis[1], z = axis[2];
    r[0] = t * x * x + c;     r[1] = t * x * y - s * z; r[2] = t * x * z + s * y;
    r[3] = t * x * y + s * z; r[4] = t * y * y + c;     r[5] = t * y * z - s * x;
    r[6] = t * x * z - s * y; r[7] = t * y * z + s * x; r[8] = t * z * z + c;
}

cf_status cf_rigid_transform_set_rotation(cf_context *ctx, cf_rigid_transform *t, const double axis[3], double angle)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!t || !axis) return cfi_error(ctx, CF_ERR_INVALID_ARG, "rigid transform: NULL argument");
    if (!isfinite(angle)) return cfi_error(ctx, CF_ERR_INVALID_ARG, "rigid transform: the angle is not finite");
    double len = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    if (!(len > 0.0) || !isfinite(len))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "rigid transform: the rotation axis is zero or not finite");
    double unit[3] = {axis[0] / len, axis[1] / len, axis[2] / len};
    cfi_axis_angle_matrix(unit, angle, t->rotation);
    return CF_OK;
}

static cf_status check_transform(cf_context *ctx, const cf_rigid_transform *t)
{
    for (int k = 0; k < 9; ++k)
        if (!isfinite(t->rotation[k])) return cfi_error(ctx, CF_ERR_INVALID_ARG, "rigid transform: rotation[%d] is not finite", k);
    for (int d = 0; d < 3; ++d)
        if (!isfinite(t->center[d]) || !isfinite(t->translation[d]))
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "rigid transform: center or translation is not finite");
    if (!(t->scale > 0.0) || !isfinite(t->scale))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "rigid transform: scale %g must be positive and finite", t->scale);
    return CF_OK;
}

cf_status cf_rigid_transform_apply(cf_context *ctx, const cf_rigid_transform *t, int64_t n, const double *in,
                                   double *out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!t || n < 0 || (n > 0 && (!in || !out))) return cfi_error(ctx, CF_ERR_INVALID_ARG, "rigid transform: NULL argument");
    cf_status st = check_transform(ctx, t);
    if (st != CF_OK) return st;
    for (int64_t i = 0; i < n; ++i) {
        double o[3];
        cfi_rigid_apply_point(t, in + 3 * i, o);
        if (cfi_first_unusable_point(o, 1, 3) >= 0)
            return cfi_error(ctx, CF_ERR_NONFINITE,
                             "rigid transform: point %lld goes to (%.3g, %.3g, %.3g), beyond the range of coordinates "
                             "(|x| <= %.0e)",
                             (long long)i, o[0], o[1], o[2], CF_MAX_COORDINATE);
        memcpy(out + 3 * i, o, sizeof o);
    }
    return CF_OK;
}

/* ---- handle sets ------------------------------------------------------------ */

void cf_handle_set_destroy(cf_handle_set **handles)
{
    if (!handles || !*handles) return;
    cf_handle_set *h = *handles;
    cf_context *ctx = h->ctx;
    CFI_FREE(ctx, h->vertices, (size_t)h->count);
    CFI_FREE(ctx, h->targets, 3 * (size_t)h->count);
    cfi_free(ctx, h, sizeof *h);
    *handles = NULL;
}

cf_handle_set *cfi_handle_set_alloc(cf_context *ctx, int32_t count)
{
    cf_handle_set *h = cfi_malloc(ctx, sizeof *h);
    if (!h) return NULL;
    memset(h, 0, sizeof *h);
    h->ctx = ctx;
    h->count = count;
    h->vertices = CFI_ALLOC(ctx, int32_t, (size_t)(count > 0 ? count : 0));
    h->targets = CFI_ALLOC(ctx, double, 3 * (size_t)(count > 0 ? count : 0));
    if (count > 0 && (!h->vertices || !h->targets)) {
        cf_handle_set_destroy(&h);
        return NULL;
    }
    return h;
}

cf_status cf_handle_set_create(cf_context *ctx, int32_t count, const int32_t *vertices, const double *targets,
                               cf_handle_set **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "handle set output is NULL");
    *out = NULL;
    if (count < 0) return cfi_error(ctx, CF_ERR_INVALID_ARG, "handle count %d is negative", (int)count);
    if (count > 0 && (!vertices || !targets))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "handle vertices or targets are NULL");
    for (int32_t k = 0; k < count; ++k) {
        if (vertices[k] < 0)
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "handle %d: vertex index %d is negative", k, vertices[k]);
        for (int d = 0; d < 3; ++d) {
            double t = targets[3 * k + d];
            if (!isfinite(t))
                return cfi_error(ctx, CF_ERR_NONFINITE, "handle %d (vertex %d): target is not finite", k, vertices[k]);
            if (fabs(t) > CF_MAX_COORDINATE)
                return cfi_error(ctx, CF_ERR_NONFINITE,
                                 "handle %d (vertex %d): target coordinate %.3g is out of range (|x| > %.0e)", k,
                                 vertices[k], t, CF_MAX_COORDINATE);
        }
    }
    cf_handle_set *h = cfi_handle_set_alloc(ctx, count);
    if (!h) return CF_ERR_NOMEM;
    /* Sort the (vertex, slot) pairs through an index array (no vertex count
     * is known here for a counting pass). */
    int32_t *order = CFI_ALLOC(ctx, int32_t, (size_t)(count > 0 ? count : 1));
    if (!order) {
        cf_handle_set_destroy(&h);
        return CF_ERR_NOMEM;
    }
    for (int32_t k = 0; k < count; ++k) order[k] = k;
    /* Shell sort on the vertex index (no global state for a qsort comparator). */
    for (int32_t gap = count / 2; gap > 0; gap /= 2)
        for (int32_t i = gap; i < count; ++i) {
            int32_t t = order[i], j = i;
            while (j >= gap && vertices[order[j - gap]] > vertices[t]) {
                order[j] = order[j - gap];
                j -= gap;
            }
            order[j] = t;
        }
    cf_status st = CF_OK;
    for (int32_t k = 0; k < count; ++k) {
        h->vertices[k] = vertices[order[k]];
        memcpy(h->targets + 3 * k, targets + 3 * (size_t)order[k], 3 * sizeof(double));
        if (k > 0 && h->vertices[k] == h->vertices[k - 1]) {
            st = cfi_error(ctx, CF_ERR_INVALID_ARG, "vertex %d is constrained twice", h->vertices[k]);
            break;
        }
    }
    CFI_FREE(ctx, order, (size_t)(count > 0 ? count : 1));
    if (st != CF_OK) {
        cf_handle_set_destroy(&h);
        return st;
    }
    h->moved_count = count;
    *out = h;
    return CF_OK;
}

cf_status cf_handle_set_from_points(cf_context *ctx, const cf_point_set *set, const double *positions,
                                    const cf_rigid_transform *transform, cf_handle_set **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "handle set output is NULL");
    *out = NULL;
    if (!set || !positions || (set->count > 0 && !set->vertices))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "handle set from points: NULL set or positions");
    if (transform) {
        cf_status st = check_transform(ctx, transform);
        if (st != CF_OK) return st;
    }
    cf_handle_set *h = cfi_handle_set_alloc(ctx, set->count);
    if (!h) return CF_ERR_NOMEM;
    int32_t moved = 0;
    for (int32_t k = 0; k < set->count; ++k) {
        int32_t v = set->vertices[k];
        const double *p = positions + 3 * (size_t)v;
        double *o = h->targets + 3 * (size_t)k;
        h->vertices[k] = v;
        if (cfi_first_unusable_point(p, 1, 3) >= 0) {
            cf_handle_set_destroy(&h);
            return cfi_error(ctx, CF_ERR_NONFINITE, "handle set from points: vertex %d: position is not finite or beyond %.0e",
                             v, CF_MAX_COORDINATE);
        }
        if (transform) cfi_rigid_apply_point(transform, p, o);
        else memcpy(o, p, 3 * sizeof *o);
        if (cfi_first_unusable_point(o, 1, 3) >= 0) {
            double where[3] = {o[0], o[1], o[2]}; /* o points into h, which is freed before the message */
            cf_handle_set_destroy(&h);
            return cfi_error(ctx, CF_ERR_NONFINITE,
                             "handle set from points: the transform moves vertex %d to (%.3g, %.3g, %.3g), beyond the "
                             "range of coordinates (|x| <= %.0e)",
                             v, where[0], where[1], where[2], CF_MAX_COORDINATE);
        }
        moved += o[0] != p[0] || o[1] != p[1] || o[2] != p[2];
    }
    h->moved_count = moved;
    *out = h;
    return CF_OK;
}
