/*
 * Welding a file's seams: boundary vertices at exactly the position of
 * another boundary vertex are joined (cf_mesh_data_weld, curvflow/io.h).
 *
 * Exporters split vertices wherever a per-vertex attribute changes: texture
 * seams (glTF, PLY with u,v), hard normals, STL-style unshared triangles.
 * The file then describes a surface cut open along those seams, and every
 * flow treats the cuts as free boundaries and tears them apart (docs/io.md,
 * "Seams"). Only boundary vertices are candidates: a vertex inside the
 * surface that shares its position with another (a surface touching itself)
 * is no seam, and joining it would make the vertex non-manifold.
 */
#include "io/io_internal.h"
#include "curvflow/mesh.h"

#include <stdlib.h>
#include <string.h>

/* A candidate with its position beside it: qsort has no context argument,
 * and a global would not be thread-safe. */
typedef struct candidate {
    double x[3];
    int32_t vertex;
} candidate;

static int by_position_then_index(const void *pa, const void *pb)
{
    const candidate *a = pa, *b = pb;
    for (int k = 0; k < 3; ++k)
        if (a->x[k] != b->x[k]) return a->x[k] < b->x[k] ? -1 : 1;
    return (a->vertex > b->vertex) - (a->vertex < b->vertex);
}

static int by_key(const void *pa, const void *pb)
{
    int64_t a = *(const int64_t *)pa, b = *(const int64_t *)pb;
    return (a > b) - (a < b);
}

/* Flags the vertices of edges used by exactly one face: the boundary of
 * the surface the triangles describe, before any check of their
 * connectivity (the caller checked the index range). */
static cf_status mark_boundary(cf_context *ctx, int32_t vertex_count, int32_t face_count, const int32_t *triangles,
                               uint8_t *on_boundary)
{
    size_t nh = 3 * (size_t)face_count;
    if (nh == 0) return CF_OK;
    int64_t *keys = CFI_ALLOC(ctx, int64_t, nh);
    if (!keys) return cfi_error(ctx, CF_ERR_NOMEM, "weld: out of memory for %zu edges", nh);
    int64_t nv = vertex_count;
    for (size_t h = 0; h < nh; ++h) {
        int64_t a = triangles[h], b = triangles[h - h % 3 + (h % 3 + 1) % 3];
        keys[h] = a < b ? a * nv + b : b * nv + a;
    }
    qsort(keys, nh, sizeof *keys, by_key);
    for (size_t i = 0, j; i < nh; i = j) {
        for (j = i + 1; j < nh && keys[j] == keys[i];) ++j;
        if (j - i == 1) on_boundary[keys[i] / nv] = on_boundary[keys[i] % nv] = 1;
    }
    CFI_FREE(ctx, keys, nh);
    return CF_OK;
}

/* Groups the boundary vertices by exact position: keep[v] is the lowest
 * index at v's position (v itself when v is alone there or not on the
 * boundary). */
static cf_status group_candidates(cf_context *ctx, int32_t nv, const double *positions, int32_t nf,
                                  const int32_t *triangles, int32_t *keep, cf_weld_report *report)
{
    uint8_t *on_boundary = CFI_ALLOC(ctx, uint8_t, nv);
    candidate *candidates = CFI_ALLOC(ctx, candidate, nv);
    cf_status st = on_boundary && candidates ? mark_boundary(ctx, nv, nf, triangles, on_boundary)
                                             : cfi_error(ctx, CF_ERR_NOMEM, "weld: out of memory for %d vertices", nv);
    if (st == CF_OK) {
        int32_t nc = 0;
        for (int32_t v = 0; v < nv; ++v) {
            keep[v] = v;
            if (!on_boundary[v]) continue;
            memcpy(candidates[nc].x, positions + 3 * (size_t)v, sizeof candidates[nc].x);
            candidates[nc++].vertex = v;
        }
        qsort(candidates, (size_t)nc, sizeof *candidates, by_position_then_index);
        /* each group of equal positions joins its lowest index (sorted first) */
        for (int32_t i = 0, j; i < nc; i = j) {
            const double *x = candidates[i].x;
            for (j = i + 1; j < nc; ++j) {
                const double *y = candidates[j].x;
                if (x[0] != y[0] || x[1] != y[1] || x[2] != y[2]) break;
                keep[candidates[j].vertex] = candidates[i].vertex;
            }
            if (j - i > 1) report->groups++, report->candidates += j - i;
        }
    }
    CFI_FREE(ctx, on_boundary, nv);
    CFI_FREE(ctx, candidates, nv);
    return st;
}

/* The welded positions and triangles for the map: a vertex is kept when its
 * new index is the next one (representatives come first and are numbered
 * in order; a joined vertex maps to an earlier one). */
static void apply_map(int32_t nv, const double *positions, int32_t nf, const int32_t *triangles,
                      const int32_t *index, double *welded_positions, int32_t *welded_triangles)
{
    for (int32_t v = 0, n = 0; v < nv; ++v)
        if (index[v] == n) memcpy(welded_positions + 3 * (size_t)n++, positions + 3 * (size_t)v, 3 * sizeof(double));
    for (size_t c = 0; c < 3 * (size_t)nf; ++c) welded_triangles[c] = index[triangles[c]];
}

/* cf_weld_map; when it welds and welded_out is not NULL, the welded
 * positions (3 vertices) and triangles it validated are handed over
 * (welded_out[0], [1]; the caller frees them) instead of being freed. */
static cf_status weld_map(cf_context *ctx, int32_t vertex_count, const double *positions, int32_t face_count,
                          const int32_t *triangles, int32_t *new_index, cf_weld_report *report,
                          double **welded_positions_out, int32_t **welded_triangles_out)
{
    memset(report, 0, sizeof *report);
    int32_t nv = vertex_count, nf = face_count;
    report->vertices = nv;
    for (int32_t v = 0; v < nv; ++v) new_index[v] = v;
    for (size_t c = 0; c < 3 * (size_t)nf; ++c)
        if (triangles[c] < 0 || triangles[c] >= nv)
            return cfi_error(ctx, CF_ERR_INDEX_RANGE, "face %d: vertex index %d out of range [0, %d)",
                             (int)(c / 3), (int)triangles[c], (int)nv);
    if (nv == 0) return CF_OK;
    int32_t *keep = CFI_ALLOC(ctx, int32_t, nv), *index = CFI_ALLOC(ctx, int32_t, nv), n = 0;
    double *welded_positions = NULL;
    int32_t *welded_triangles = NULL;
    cf_status st = keep && index ? group_candidates(ctx, nv, positions, nf, triangles, keep, report)
                                 : cfi_error(ctx, CF_ERR_NOMEM, "weld: out of memory for %d vertices", nv);
    if (st != CF_OK || report->groups == 0) goto done;
    for (int32_t v = 0; v < nv; ++v) index[v] = keep[v] == v ? n++ : index[keep[v]]; /* keep[v] <= v */
    /* the welded surface must be one a mesh can be built from; if not, the
     * candidates stay apart and the report says why */
    welded_positions = CFI_ALLOC(ctx, double, 3 * (size_t)n);
    welded_triangles = CFI_ALLOC(ctx, int32_t, nf > 0 ? 3 * (size_t)nf : 1);
    if (!welded_positions || !welded_triangles) {
        st = cfi_error(ctx, CF_ERR_NOMEM, "weld: out of memory for %d vertices", n);
        goto done;
    }
    apply_map(nv, positions, nf, triangles, index, welded_positions, welded_triangles);
    cf_mesh_desc desc = {.vertex_count = n, .positions = welded_positions, .face_count = nf,
                         .triangles = welded_triangles};
    cf_mesh_report check;
    if ((st = cf_mesh_validate(ctx, &desc, &check)) != CF_OK) goto done;
    if (check.first_status != CF_OK) {
        /* the validation message fits the report's with the prefix cut short */
        snprintf(report->refused, sizeof report->refused, "after welding, %.*s",
                 (int)(sizeof report->refused - sizeof "after welding, "), check.first_message);
        goto done;
    }
    memcpy(new_index, index, (size_t)nv * sizeof(int32_t));
    report->welded = 1;
    report->removed = nv - n;
    report->vertices = n;
    if (welded_positions_out && welded_triangles_out) {
        *welded_positions_out = welded_positions, *welded_triangles_out = welded_triangles;
        welded_positions = NULL, welded_triangles = NULL;
    }
done:
    CFI_FREE(ctx, keep, nv);
    CFI_FREE(ctx, index, nv);
    CFI_FREE(ctx, welded_positions, 3 * (size_t)n);
    CFI_FREE(ctx, welded_triangles, nf > 0 ? 3 * (size_t)nf : 1);
    return st;
}

cf_status cf_weld_map(cf_context *ctx, int32_t vertex_count, const double *positions, int32_t face_count,
                      const int32_t *triangles, int32_t *new_index, cf_weld_report *report)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!report || !new_index || vertex_count < 0 || face_count < 0 || (vertex_count > 0 && !positions) ||
        (face_count > 0 && !triangles))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "cf_weld_map: missing array or negative count");
    return weld_map(ctx, vertex_count, positions, face_count, triangles, new_index, report, NULL, NULL);
}

/* The arrays a weld replaces, made in full before any is swapped in, so
 * that running out of memory leaves the data as it was; positions and
 * triangles are the ones weld_map validated. */
typedef struct welded_arrays {
    double *positions;
    int32_t *triangles;
    int32_t *uv_triangles;   /* per-vertex uv become per-corner (NULL otherwise) */
    double **properties;     /* one array per vertex property */
    int32_t *first;          /* the kept vertex of each new index */
} welded_arrays;

static void free_welded(cf_context *ctx, welded_arrays *w, int32_t n, const cf_mesh_data *d)
{
    size_t nf = (size_t)d->face_count;
    CFI_FREE(ctx, w->positions, 3 * (size_t)n);
    CFI_FREE(ctx, w->triangles, nf > 0 ? 3 * nf : 1); /* as weld_map made it */
    CFI_FREE(ctx, w->uv_triangles, 3 * nf);
    CFI_FREE(ctx, w->first, n);
    if (w->properties) {
        for (int32_t p = 0; p < d->vertex_property_count; ++p) CFI_FREE(ctx, w->properties[p], n);
        CFI_FREE(ctx, w->properties, d->vertex_property_count);
    }
}

/* The texture's corners and the vertex properties of the welded data (w's
 * positions and triangles already made). */
static cf_status make_welded(cf_context *ctx, const cf_mesh_data *d, const int32_t *index, int32_t n,
                             welded_arrays *w, int32_t *differing)
{
    int32_t nv = d->vertex_count;
    size_t nf = (size_t)d->face_count;
    w->first = CFI_ALLOC(ctx, int32_t, n);
    bool per_vertex_uv = d->uv_count > 0 && !d->uv_triangles;
    if (per_vertex_uv) w->uv_triangles = CFI_ALLOC(ctx, int32_t, 3 * nf);
    if (d->vertex_property_count > 0) {
        w->properties = CFI_ALLOC(ctx, double *, d->vertex_property_count);
        for (int32_t p = 0; w->properties && p < d->vertex_property_count; ++p)
            if (!(w->properties[p] = CFI_ALLOC(ctx, double, n))) break;
    }
    bool complete = w->first && (!per_vertex_uv || w->uv_triangles) &&
                    (d->vertex_property_count == 0 ||
                     (w->properties && w->properties[d->vertex_property_count - 1]));
    if (!complete) return cfi_error(ctx, CF_ERR_NOMEM, "weld: out of memory for %d vertices", n);
    /* the texture keeps each corner's own coordinates: on a seam they differ */
    if (per_vertex_uv) memcpy(w->uv_triangles, d->triangles, 3 * nf * sizeof(int32_t));
    *differing = 0;
    for (int32_t v = 0, kept = 0; v < nv; ++v) {
        bool first = index[v] == kept, differs = false;
        if (first) w->first[kept++] = v;
        for (int32_t p = 0; p < d->vertex_property_count; ++p) {
            const double *old = d->vertex_properties[p].values;
            if (first) w->properties[p][index[v]] = old[v];
            else differs = differs || old[v] != old[w->first[index[v]]];
        }
        *differing += differs;
    }
    return CF_OK;
}

cf_status cf_mesh_data_weld(cf_context *ctx, cf_mesh_data *data, int32_t *new_index, cf_weld_report *report)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!data || !report) return cfi_error(ctx, CF_ERR_INVALID_ARG, "cf_mesh_data_weld: data or report is NULL");
    int32_t nv = data->vertex_count;
    int32_t *index = CFI_ALLOC(ctx, int32_t, nv > 0 ? nv : 1);
    if (!index) {
        memset(report, 0, sizeof *report);
        return cfi_error(ctx, CF_ERR_NOMEM, "weld: out of memory for %d vertices", nv);
    }
    welded_arrays w = {0};
    cf_status st = weld_map(ctx, nv, data->positions, data->face_count, data->triangles, index, report, &w.positions,
                            &w.triangles);
    int32_t n = report->vertices;
    if (st == CF_OK && report->welded) st = make_welded(ctx, data, index, n, &w, &report->differing_properties);
    if (st != CF_OK || !report->welded) {
        if (st != CF_OK) report->welded = report->removed = 0, report->vertices = nv;
        if (new_index)
            for (int32_t v = 0; v < nv; ++v) new_index[v] = v;
        goto done;
    }
    size_t nf = (size_t)data->face_count;
    cfi_free(ctx, data->positions, 3 * (size_t)nv * sizeof(double));
    cfi_free(ctx, data->triangles, 3 * nf * sizeof(int32_t));
    data->positions = w.positions, data->triangles = w.triangles;
    if (w.uv_triangles) data->uv_triangles = w.uv_triangles;
    for (int32_t p = 0; p < data->vertex_property_count; ++p) {
        cfi_free(ctx, data->vertex_properties[p].values, (size_t)nv * sizeof(double));
        data->vertex_properties[p].values = w.properties[p];
    }
    CFI_FREE(ctx, w.properties, data->vertex_property_count);
    CFI_FREE(ctx, w.first, n);
    memset(&w, 0, sizeof w);
    data->vertex_count = n;
    if (new_index) memcpy(new_index, index, (size_t)nv * sizeof(int32_t));
done:
    free_welded(ctx, &w, n, data);
    CFI_FREE(ctx, index, nv > 0 ? nv : 1);
    return st;
}
