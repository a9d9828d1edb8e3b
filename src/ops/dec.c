/*
 * Discrete exterior calculus operators (Desbrun, Kanso & Tong 2008):
 * d0 (ne x nv), d1 (nf x ne) and the diagonal Hodge stars *0 (barycentric
 * dual areas), *1 (cotan weights), *2 (1 / face area). Edge e is oriented
 * from edge_vertices[2e] to edge_vertices[2e+1]; a face's boundary runs along
 * its corner order, so d1 d0 = 0 exactly.
 */
#include "curvflow/ops.h"
#include "ops/ops_internal.h"

static cf_status check_mesh(cf_context *ctx, const cf_mesh *mesh, const void *out, const char *fn)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!mesh) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: mesh is NULL", fn);
    if (!out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: output is NULL", fn);
    return CF_OK;
}

cf_status cf_dec_d0(cf_context *ctx, const cf_mesh *mesh, cf_sparse **out)
{
    cf_status s = check_mesh(ctx, mesh, out, "dec_d0");
    if (s != CF_OK) return s;
    *out = NULL;
    int64_t n = 2 * (int64_t)mesh->ne;
    int32_t *rows = CFI_ALLOC(ctx, int32_t, n);
    double *vals = CFI_ALLOC(ctx, double, n);
    if (!rows || !vals) {
        s = CF_ERR_NOMEM;
        goto done;
    }
    for (int32_t e = 0; e < mesh->ne; ++e) {
        rows[2 * e] = rows[2 * e + 1] = e;
        vals[2 * e] = -1.0; /* (d0 f)_e = f_j - f_i */
        vals[2 * e + 1] = 1.0;
    }
    s = cf_sparse_from_triplets(ctx, mesh->ne, mesh->nv, n, rows, mesh->edge_vertices, vals, 0, out, NULL);
done:
    CFI_FREE(ctx, rows, n);
    CFI_FREE(ctx, vals, n);
    return s;
}

cf_status cf_dec_d1(cf_context *ctx, const cf_mesh *mesh, cf_sparse **out)
{
    cf_status s = check_mesh(ctx, mesh, out, "dec_d1");
    if (s != CF_OK) return s;
    *out = NULL;
    int64_t n = 3 * (int64_t)mesh->nf;
    int32_t *rows = CFI_ALLOC(ctx, int32_t, n);
    double *vals = CFI_ALLOC(ctx, double, n);
    if (!rows || !vals) {
        s = CF_ERR_NOMEM;
        goto done;
    }
    for (int64_t h = 0; h < n; ++h) {
        int32_t e = mesh->halfedge_edge[h];
        rows[h] = (int32_t)(h / 3);
        /* +1 when halfedge h = (a -> b) runs along the edge's i -> j */
        vals[h] = mesh->triangles[h] == mesh->edge_vertices[2 * e] ? 1.0 : -1.0;
    }
    s = cf_sparse_from_triplets(ctx, mesh->nf, mesh->ne, n, rows, mesh->halfedge_edge, vals, 0, out, NULL);
done:
    CFI_FREE(ctx, rows, n);
    CFI_FREE(ctx, vals, n);
    return s;
}

cf_status cf_dec_star0(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *star0)
{
    return cf_vertex_areas(ctx, mesh, positions, CF_DUAL_AREA_BARYCENTRIC, star0);
}

cf_status cf_dec_star1(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *star1)
{
    return cf_cotan_weights(ctx, mesh, positions, star1);
}

cf_status cf_dec_star2(cf_context *ctx, const cf_mesh *mesh, const double *positions, double *star2)
{
    cf_status s = cfi_ops_check(ctx, mesh, positions, star2, "dec_star2");
    if (s != CF_OK) return s;
    for (int32_t f = 0; f < mesh->nf; ++f) {
        double n[3];
        cfi_face_area_vector(mesh, positions, f, n);
        double a = 0.5 * cfi_v3_norm(n);
        if (!(a > 0.0)) return cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "face %d: zero area", f);
        star2[f] = 1.0 / a;
    }
    return CF_OK;
}
