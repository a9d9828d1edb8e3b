/*
 * Vertices that no face uses, dropped from what a file holds
 * (cf_mesh_data_drop_unreferenced, curvflow/io.h).
 *
 * Scanners, CAD exporters and editors leave them: points of a cloud the
 * triangulation skipped, the vertices of deleted faces that an OBJ keeps.
 * They carry nothing a flow could move (no face, no area, no curvature),
 * but a mesh with one is refused ("vertex 12 is not used by any face"),
 * so a user's file would not run at all (docs/io.md, "Unused vertices").
 */
#include "io/io_internal.h"

#include <string.h>

cf_status cf_mesh_data_drop_unreferenced(cf_context *ctx, cf_mesh_data *data, int32_t *new_index, int32_t *dropped)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!data || !dropped)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "cf_mesh_data_drop_unreferenced: data or dropped is NULL");
    *dropped = 0;
    int32_t nv = data->vertex_count;
    size_t nc = 3 * (size_t)data->face_count;
    for (size_t c = 0; c < nc; ++c)
        if (data->triangles[c] < 0 || data->triangles[c] >= nv)
            return cfi_error(ctx, CF_ERR_INDEX_RANGE, "face %d: vertex index %d out of range [0, %d)", (int)(c / 3),
                             (int)data->triangles[c], (int)nv);
    int32_t *index = CFI_ALLOC(ctx, int32_t, nv > 0 ? nv : 1);
    if (!index) return cfi_error(ctx, CF_ERR_NOMEM, "drop_unreferenced: out of memory for %d vertices", (int)nv);
    for (int32_t v = 0; v < nv; ++v) index[v] = -1;
    for (size_t c = 0; c < nc; ++c) index[data->triangles[c]] = 0;
    int32_t n = 0;
    for (int32_t v = 0; v < nv; ++v)
        if (index[v] == 0) index[v] = n++;
    cf_status st = CF_OK;
    if (n == nv || n == 0) {
        /* nothing unused, or no face at all: a file the mesh check refuses
         * as empty, with its own message */
        if (new_index)
            for (int32_t v = 0; v < nv; ++v) new_index[v] = n == nv ? v : -1;
        goto done;
    }
    /* every new array first, so that running out of memory changes nothing */
    bool per_vertex_uv = data->uv_count > 0 && !data->uv_triangles;
    int32_t np = data->vertex_property_count;
    size_t n_alloc = (size_t)n;
    double *positions = CFI_ALLOC(ctx, double, 3 * n_alloc);
    double *uv = per_vertex_uv ? CFI_ALLOC(ctx, double, 2 * n_alloc) : NULL;
    double **properties = np > 0 ? CFI_ALLOC(ctx, double *, np) : NULL;
    bool complete = positions && (!per_vertex_uv || uv) && (np == 0 || properties);
    for (int32_t p = 0; complete && p < np; ++p) properties[p] = NULL;
    for (int32_t p = 0; complete && p < np; ++p) complete = (properties[p] = CFI_ALLOC(ctx, double, n_alloc)) != NULL;
    if (!complete) {
        CFI_FREE(ctx, positions, 3 * n_alloc);
        CFI_FREE(ctx, uv, 2 * n_alloc);
        for (int32_t p = 0; properties && p < np; ++p) CFI_FREE(ctx, properties[p], n_alloc);
        CFI_FREE(ctx, properties, np);
        st = cfi_error(ctx, CF_ERR_NOMEM, "drop_unreferenced: out of memory for %d vertices", (int)n);
        goto done;
    }
    for (int32_t v = 0; v < nv; ++v) {
        int32_t k = index[v];
        if (k < 0) continue;
        memcpy(positions + 3 * (size_t)k, data->positions + 3 * (size_t)v, 3 * sizeof(double));
        if (uv) memcpy(uv + 2 * (size_t)k, data->uv + 2 * (size_t)v, 2 * sizeof(double));
        for (int32_t p = 0; p < np; ++p) properties[p][k] = data->vertex_properties[p].values[v];
    }
    for (size_t c = 0; c < nc; ++c) data->triangles[c] = index[data->triangles[c]];
    cfi_free(ctx, data->positions, 3 * (size_t)nv * sizeof(double));
    data->positions = positions;
    if (uv) {
        cfi_free(ctx, data->uv, 2 * (size_t)nv * sizeof(double));
        data->uv = uv;
        data->uv_count = n;
    }
    for (int32_t p = 0; p < np; ++p) {
        cfi_free(ctx, data->vertex_properties[p].values, (size_t)nv * sizeof(double));
        data->vertex_properties[p].values = properties[p];
    }
    CFI_FREE(ctx, properties, np);
    data->vertex_count = n;
    *dropped = nv - n;
    if (new_index) memcpy(new_index, index, (size_t)nv * sizeof(int32_t));
done:
    CFI_FREE(ctx, index, nv > 0 ? nv : 1);
    return st;
}
