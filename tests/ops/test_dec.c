/* DEC: d1 d0 = 0, d0^T *1 d0 = L, orientation of d0/d1 and the stars. */
#include "curvflow/generate.h"
#include "curvflow/ops.h"
#include "test.h"

#include <stdlib.h>

static void check_dec(cf_context *ctx, const cf_mesh *m)
{
    const double *x = cf_mesh_positions(m);
    int32_t nv = cf_mesh_vertex_count(m), ne = cf_mesh_edge_count(m), nf = cf_mesh_face_count(m);
    cf_sparse *d0 = NULL, *d1 = NULL, *d10 = NULL, *l = NULL;
    CHECK_OK(ctx, cf_dec_d0(ctx, m, &d0));
    CHECK_OK(ctx, cf_dec_d1(ctx, m, &d1));
    if (!d0 || !d1) return;
    CHECK(d0->nrows == ne && d0->ncols == nv && cf_sparse_nnz(d0) == 2 * ne);
    CHECK(d1->nrows == nf && d1->ncols == ne && cf_sparse_nnz(d1) == 3 * nf);
    /* d1 d0 = 0 exactly: every face boundary of an exact form sums to 0 */
    CHECK_OK(ctx, cf_sparse_product(ctx, d1, d0, &d10));
    if (d10)
        for (int64_t k = 0; k < cf_sparse_nnz(d10); ++k) CHECK(d10->values[k] == 0.0);
    /* (d0 f)_e = f_j - f_i on e = (i, j), i < j */
    const int32_t *ev = cf_mesh_edge_vertices(m);
    double *f = malloc(sizeof(double) * nv), *df = malloc(sizeof(double) * ne), *y = malloc(sizeof(double) * nv);
    double *w = malloc(sizeof(double) * ne), *lf = malloc(sizeof(double) * nv);
    for (int32_t v = 0; v < nv; ++v) f[v] = sin(3.0 * x[3 * v]) + x[3 * v + 1] * x[3 * v + 2];
    cf_sparse_multiply(d0, f, df);
    for (int32_t e = 0; e < ne; ++e) CHECK(df[e] == f[ev[2 * e + 1]] - f[ev[2 * e]]);
    /* d0^T *1 d0 f = L f */
    CHECK_OK(ctx, cf_dec_star1(ctx, m, x, w));
    for (int32_t e = 0; e < ne; ++e) df[e] *= w[e];
    for (int32_t v = 0; v < nv; ++v) y[v] = 0;
    for (int32_t e = 0; e < ne; ++e) {
        y[ev[2 * e + 1]] += df[e];
        y[ev[2 * e]] -= df[e];
    }
    CHECK_OK(ctx, cf_cotan_laplacian(ctx, m, x, &l));
    if (l) {
        cf_sparse_multiply(l, f, lf);
        for (int32_t v = 0; v < nv; ++v) CHECK_NEAR(y[v], lf[v], 1e-12, 1e-12);
    }
    /* d1 of a 1-form that is the edge vector component: circulation around a
     * face of an exact form is 0; of the rotated form it is signed by
     * orientation. Check the sign pattern directly on face 0. */
    const int32_t *t = cf_mesh_triangles(m);
    const int32_t *he = cf_mesh_halfedge_edge(m);
    for (int32_t i = 0; i < nf && i < 50; ++i)
        for (int k = 0; k < 3; ++k) {
            int32_t e = he[3 * i + k];
            double expect = t[3 * i + k] == ev[2 * e] ? 1.0 : -1.0;
            double got = 0;
            for (int32_t q = d1->colptr[e]; q < d1->colptr[e + 1]; ++q)
                if (d1->rowind[q] == i) got = d1->values[q];
            CHECK(got == expect);
        }
    /* stars: *0 sums to area, *2 is 1 / face area */
    double *s0 = malloc(sizeof(double) * nv), *s2 = malloc(sizeof(double) * nf), *fa = malloc(sizeof(double) * nf);
    double area, sum = 0;
    CHECK_OK(ctx, cf_dec_star0(ctx, m, x, s0));
    CHECK_OK(ctx, cf_dec_star2(ctx, m, x, s2));
    CHECK_OK(ctx, cf_face_areas(ctx, m, x, fa));
    CHECK_OK(ctx, cf_total_area(ctx, m, x, &area));
    for (int32_t v = 0; v < nv; ++v) sum += s0[v];
    CHECK_NEAR(sum, area, 1e-13, 0);
    for (int32_t i = 0; i < nf; ++i) CHECK_NEAR(s2[i] * fa[i], 1.0, 1e-15, 0);
    free(s0);
    free(s2);
    free(fa);
    free(f);
    free(df);
    free(y);
    free(w);
    free(lf);
    cf_sparse_destroy(&d0);
    cf_sparse_destroy(&d1);
    cf_sparse_destroy(&d10);
    cf_sparse_destroy(&l);
}

static void test_dec(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 2, 0.25, 1u, &m));
    if (m) check_dec(ctx, m);
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_double_torus(ctx, 1, &m));
    if (m) check_dec(ctx, m);
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_bumpy_plane(ctx, 8, 1.0, 0.2, 4u, &m));
    if (m) check_dec(ctx, m);
    cf_mesh_destroy(&m);
    cf_sparse *d = NULL;
    CHECK_STATUS(cf_dec_d0(ctx, NULL, &d), CF_ERR_INVALID_ARG);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_dec);
    return cft_finish();
}
