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

/* Value of triplet k of d0: (d0 f)_e = f_j - f_i, columns (i, j) of edge e. */
static double d0_value(const cf_mesh *mesh, int64_t k)
{
    (void)mesh;
    return k % 2 ? 1.0 : -1.0;
}

/* Value of triplet h (halfedge h = a -> b of face h / 3) of d1: +1 when it
 * runs along its edge's i -> j. */
static double d1_value(const cf_mesh *mesh, int64_t h)
{
    int32_t e = mesh->halfedge_edge[h];
    return mesh->triangles[h] == mesh->edge_vertices[2 * e] ? 1.0 : -1.0;
}

/* A signed incidence matrix with `per_row` entries per row: triplet k sits
 * in row k / per_row, column cols[k], with value value(mesh, k). */
static cf_status incidence_matrix(cf_context *ctx, const cf_mesh *mesh, int32_t nrows, int32_t ncols, int per_row,
                                  const int32_t *cols, double (*value)(const cf_mesh *, int64_t), cf_sparse **out)
{
    int64_t n = (int64_t)per_row * nrows;
    int32_t *rows = CFI_ALLOC(ctx, int32_t, n);
    double *vals = CFI_ALLOC(ctx, double, n);
    cf_status s = CF_ERR_NOMEM;
    if (rows && vals) {
        for (int64_t k = 0; k < n; ++k) {
            rows[k] = (int32_t)(k / per_row);
            vals[k] = value(mesh, k);
        }
        s = cf_sparse_from_triplets(ctx, nrows, ncols, n, rows, cols, vals, 0, out, NULL);
    }
    CFI_FREE(ctx, rows, n);
    CFI_FREE(ctx, vals, n);
    return s;
}

cf_status cf_dec_d0(cf_context *ctx, const cf_mesh *mesh, cf_sparse **out)
{
    cf_status s = check_mesh(ctx, mesh, out, "dec_d0");
    if (s != CF_OK) return s;
    *out = NULL;
    return incidence_matrix(ctx, mesh, mesh->ne, mesh->nv, 2, mesh->edge_vertices, d0_value, out);
}

cf_status cf_dec_d1(cf_context *ctx, const cf_mesh *mesh, cf_sparse **out)
{
    cf_status s = check_mesh(ctx, mesh, out, "dec_d1");
    if (s != CF_OK) return s;
    *out = NULL;
    return incidence_matrix(ctx, mesh, mesh->nf, mesh->ne, 3, mesh->halfedge_edge, d1_value, out);
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
        double a = cfi_face_area(mesh, positions, f);
        if (!(a > 0.0)) return cfi_error(ctx, CF_ERR_DEGENERATE_FACE, "face %d: zero area", f);
        star2[f] = 1.0 / a;
    }
    return CF_OK;
}
