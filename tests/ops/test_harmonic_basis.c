/* Harmonic 1-form basis (Crane 2013, App. C.1): dimension 2g, closed
 * (d1 h = 0) and co-closed (d0^T *1 h = 0) to 1e-10 relative, orthonormal
 * under *1; the Whitney vector field reproduces a closed form's edge values
 * and the gradient of a linear function. */
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/ops.h"
#include "test.h"

#include <stdlib.h>

static void check_basis(cf_context *ctx, const cf_mesh *m, int32_t expect, const char *name)
{
    const double *x = cf_mesh_positions(m);
    int32_t nv = cf_mesh_vertex_count(m), ne = cf_mesh_edge_count(m), nf = cf_mesh_face_count(m);
    int32_t dim = -1;
    CHECK_OK(ctx, cf_harmonic_basis(ctx, m, x, &dim, NULL));
    CHECK(dim == expect);
    if (dim != expect) return;
    double *h = malloc(sizeof(double) * ((size_t)ne * (dim ? dim : 1)));
    CHECK_OK(ctx, cf_harmonic_basis(ctx, m, x, &dim, h));
    double *w = malloc(sizeof(double) * ne), *r = malloc(sizeof(double) * (nv > nf ? nv : nf));
    CHECK_OK(ctx, cf_cotan_weights(ctx, m, x, w));
    const int32_t *ev = cf_mesh_edge_vertices(m), *t = cf_mesh_triangles(m), *he = cf_mesh_halfedge_edge(m);
    double worst_closed = 0, worst_coclosed = 0;
    for (int32_t c = 0; c < dim; ++c) {
        const double *hc = h + (int64_t)ne * c;
        double hmax = 0;
        for (int32_t e = 0; e < ne; ++e) hmax = fmax(hmax, fabs(hc[e]));
        /* closed: circulation around each face, relative to the edge values */
        for (int32_t i = 0; i < nf; ++i) {
            double s = 0;
            for (int j = 0; j < 3; ++j) {
                int32_t e = he[3 * i + j];
                s += (t[3 * i + j] == ev[2 * e] ? 1.0 : -1.0) * hc[e];
            }
            worst_closed = fmax(worst_closed, fabs(s) / hmax);
        }
        /* co-closed: d0^T *1 h at each vertex, relative to sum |w h| there */
        for (int32_t v = 0; v < nv; ++v) r[v] = 0;
        double *scale = calloc((size_t)nv, sizeof(double));
        for (int32_t e = 0; e < ne; ++e) {
            double y = w[e] * hc[e];
            r[ev[2 * e + 1]] += y;
            r[ev[2 * e]] -= y;
            scale[ev[2 * e]] += fabs(y);
            scale[ev[2 * e + 1]] += fabs(y);
        }
        double smax = 0;
        for (int32_t v = 0; v < nv; ++v) smax = fmax(smax, scale[v]);
        for (int32_t v = 0; v < nv; ++v) worst_coclosed = fmax(worst_coclosed, fabs(r[v]) / smax);
        free(scale);
        /* orthonormal under *1 */
        for (int32_t d = 0; d < dim; ++d) {
            const double *hd = h + (int64_t)ne * d;
            double ip = 0;
            for (int32_t e = 0; e < ne; ++e) ip += w[e] * hc[e] * hd[e];
            CHECK_NEAR(ip, c == d ? 1.0 : 0.0, 0, 1e-10);
        }
    }
    fprintf(stderr, "  %-24s dim %d  max |d1 h| %.1e  max |d0^T *1 h| %.1e (relative)\n", name, dim, worst_closed,
            worst_coclosed);
    CHECK_LE(worst_closed, 1e-10);
    CHECK_LE(worst_coclosed, 1e-10);
    /* Whitney field of a closed form: <v_f, e> = omega(e) on each edge of f */
    if (dim > 0) {
        double *v = malloc(sizeof(double) * 3 * nf);
        CHECK_OK(ctx, cf_one_form_to_vector_field(ctx, m, x, h, v));
        double worst = 0, hmax = 0;
        for (int32_t e = 0; e < ne; ++e) hmax = fmax(hmax, fabs(h[e]));
        for (int32_t i = 0; i < nf; ++i)
            for (int j = 0; j < 3; ++j) {
                int32_t a = t[3 * i + j], b = t[3 * i + (j + 1) % 3], e = he[3 * i + j];
                double om = (a == ev[2 * e] ? 1.0 : -1.0) * h[e];
                double d = 0;
                for (int k = 0; k < 3; ++k) d += v[3 * i + k] * (x[3 * b + k] - x[3 * a + k]);
                worst = fmax(worst, fabs(d - om) / hmax);
            }
        CHECK_LE(worst, 1e-10);
        free(v);
    }
    free(h);
    free(w);
    free(r);
}

static void test_generated(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &m));
    if (m) check_basis(ctx, m, 0, "icosphere(2)");
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.35, 40, 16, &m));
    if (m) check_basis(ctx, m, 2, "torus");
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_double_torus(ctx, 2, &m));
    if (m) check_basis(ctx, m, 4, "double torus (generated)");
    cf_mesh_destroy(&m);
    /* meshes with boundary are not supported (closed meshes only) */
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 10, 3, 1.0, 1.0, &m));
    int32_t dim;
    if (m) CHECK_STATUS(cf_harmonic_basis(ctx, m, cf_mesh_positions(m), &dim, NULL), CF_ERR_UNSUPPORTED);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_shared(void)
{
    static const char *names[] = {"bob_5k.obj", "double_torus_315.obj", "elephant_g3_3k.obj", "spot_3k.obj"};
    static const int32_t dims[] = {2, 4, 6, 0};
    if (!cft_shared_mesh_path(names[0])) cft_skip("../shared/meshes is absent");
    cf_context *ctx = cft_context();
    for (int i = 0; i < 4; ++i) {
        cf_mesh *m = NULL;
        CHECK_OK(ctx, cf_load_mesh(ctx, cft_shared_mesh_path(names[i]), &m));
        if (m) check_basis(ctx, m, dims[i], names[i]);
        cf_mesh_destroy(&m);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Whitney field of an exact form d0 f with linear f is the gradient. */
static void test_whitney_exact(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 2, 0.2, 3u, &m));
    if (!m) return;
    const double *x = cf_mesh_positions(m);
    int32_t nv = cf_mesh_vertex_count(m), ne = cf_mesh_edge_count(m), nf = cf_mesh_face_count(m);
    const int32_t *ev = cf_mesh_edge_vertices(m);
    double *f = malloc(sizeof(double) * nv), *om = malloc(sizeof(double) * ne);
    double *v = malloc(sizeof(double) * 3 * nf), *g = malloc(sizeof(double) * 3 * nf);
    for (int32_t i = 0; i < nv; ++i) f[i] = 2 * x[3 * i] - x[3 * i + 1] + 0.5 * x[3 * i + 2] + sin(x[3 * i]);
    for (int32_t e = 0; e < ne; ++e) om[e] = f[ev[2 * e + 1]] - f[ev[2 * e]];
    CHECK_OK(ctx, cf_one_form_to_vector_field(ctx, m, x, om, v));
    CHECK_OK(ctx, cf_gradient(ctx, m, x, f, g));
    for (int32_t i = 0; i < 3 * nf; ++i) CHECK_NEAR(v[i], g[i], 0, 1e-12);
    free(f);
    free(om);
    free(v);
    free(g);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_whitney_exact);
    CFT_RUN(test_generated);
    CFT_RUN(test_shared);
    return cft_finish();
}
