/* Harmonic 1-form basis (Crane 2013, App. C.1): dimension 2g on closed
 * meshes and 2g + b - 1 per component with b > 0 boundary loops (0 on a
 * disk), closed (d1 h = 0) and co-closed (d0^T *1 h = 0 at every vertex,
 * the Neumann condition on the boundary) to 1e-10 relative, orthonormal
 * under *1; nonzero periods around the holes of annuli (sqrt(2 pi) on a
 * cylinder, the period of d theta / |d theta|); the Whitney vector field
 * reproduces a closed form's edge values and the gradient of a linear
 * function. */
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/ops.h"
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Periods of column c of h around each boundary loop, along the boundary
 * halfedges (loop of a halfedge = loop of its start vertex). */
static void boundary_periods(const cf_mesh *m, const double *hc, double *period)
{
    int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m), nb = cf_mesh_boundary_loop_count(m);
    const int32_t *ev = cf_mesh_edge_vertices(m), *t = cf_mesh_triangles(m), *he = cf_mesh_halfedge_edge(m);
    const int32_t *tw = cf_mesh_halfedge_twin(m), *off = cf_mesh_boundary_loop_offsets(m);
    const int32_t *lv = cf_mesh_boundary_loop_vertices(m);
    int32_t *loop = malloc(sizeof(int32_t) * (size_t)nv);
    for (int32_t b = 0; b < nb; ++b) {
        period[b] = 0;
        for (int32_t k = off[b]; k < off[b + 1]; ++k) loop[lv[k]] = b;
    }
    for (int32_t h = 0; h < 3 * nf; ++h) {
        if (tw[h] >= 0) continue;
        int32_t e = he[h];
        period[loop[t[h]]] += (t[h] == ev[2 * e] ? 1.0 : -1.0) * hc[e];
    }
    free(loop);
}

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
    fprintf(stderr, "  %-26s dim %d  max |d1 h| %.1e  max |d0^T *1 h| %.1e (relative)\n", name, dim, worst_closed,
            worst_coclosed);
    /* with holes: the boundary periods sum to zero (Stokes: the sum of d1 h
     * over all faces). For one component of genus 0 the b - 1 independent
     * loops carry every class, so each column has a nonzero period (its
     * class is not zero); otherwise (handles, closed components) some
     * columns may have none, but at least one column must. */
    int32_t nb = cf_mesh_boundary_loop_count(m);
    int every = cf_mesh_genus(m) == 0 && cf_mesh_component_count(m) == 1;
    if (nb > 1 && dim > 0) {
        double *p = malloc(sizeof(double) * (size_t)nb), best = 0;
        for (int32_t c = 0; c < dim; ++c) {
            boundary_periods(m, h + (int64_t)ne * c, p);
            double sum = 0, pmax = 0;
            for (int32_t b = 0; b < nb; ++b) {
                sum += p[b];
                pmax = fmax(pmax, fabs(p[b]));
            }
            fprintf(stderr, "    column %d: largest boundary period %.4f, sum %.1e\n", c, pmax, sum);
            if (every) CHECK(pmax > 0.1);   /* smallest measured: 0.17 (chinese_lion) */
            best = fmax(best, pmax);
            CHECK_NEAR(sum, 0, 0, 1e-10);
        }
        CHECK(best > 0.1);
        free(p);
    }
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
    /* meshes with boundary: disk 0, annulus 1 */
    CHECK_OK(ctx, cf_generate_grid(ctx, 12, 9, 1.0, 0.7, &m));
    if (m) check_basis(ctx, m, 0, "grid (disk)");
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 48, 12, 1.0, 1.0, &m));
    if (m) check_basis(ctx, m, 1, "cylinder (annulus)");
    if (m) {
        /* the continuous Neumann harmonic field of a cylinder of radius 1 and
         * height 1 is d theta / |d theta| with |d theta|^2 = 2 pi, so its
         * period is 2 pi / sqrt(2 pi) = sqrt(2 pi); 48 chords per turn give
         * O(1/48^2) discretisation error (about 1e-3), 1e-2 is the margin */
        int32_t ne = cf_mesh_edge_count(m), dim = 0;
        double *h = malloc(sizeof(double) * (size_t)ne), p[2];
        CHECK_OK(ctx, cf_harmonic_basis(ctx, m, cf_mesh_positions(m), &dim, h));
        boundary_periods(m, h, p);
        fprintf(stderr, "  cylinder periods %.6f %.6f (sqrt(2 pi) = %.6f)\n", p[0], p[1], sqrt(6.283185307179586));
        CHECK_NEAR(fabs(p[0]), sqrt(6.283185307179586), 1e-2, 0);
        CHECK_NEAR(p[0], -p[1], 0, 1e-10);
        /* deterministic: a second call gives the same bits */
        double *h2 = malloc(sizeof(double) * (size_t)ne);
        CHECK_OK(ctx, cf_harmonic_basis(ctx, m, cf_mesh_positions(m), &dim, h2));
        CHECK(memcmp(h, h2, sizeof(double) * (size_t)ne) == 0);
        free(h);
        free(h2);
    }
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* cf_harmonic_workspace: on a torus moved three ways (as given, stretched,
 * moved at random), one workspace returns cf_harmonic_basis's bits for the
 * first (it builds L as cf_harmonic_basis does) and the same forms to
 * rounding for the others (it refills L: another summation order), which
 * allocate nothing through the context; a sphere's has dimension 0; bad
 * input named. */
static void test_workspace(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL, *sphere = NULL;
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.35, 40, 16, &m));
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &sphere));
    if (m && sphere) {
        int32_t nv = cf_mesh_vertex_count(m), ne = cf_mesh_edge_count(m), dim = 0;
        double *x = malloc(sizeof(double) * 3 * (size_t)nv), *a = malloc(sizeof(double) * 2 * (size_t)ne);
        double *b = malloc(sizeof(double) * 2 * (size_t)ne);
        cf_harmonic_workspace *w = NULL;
        CHECK_OK(ctx, cf_harmonic_workspace_create(ctx, m, &w));
        CHECK(cf_harmonic_workspace_dimension(w) == 2);
        unsigned seed = 99u;
        for (int variant = 0; w && variant < 3; ++variant) {
            for (int32_t i = 0; i < 3 * nv; ++i) {
                seed = seed * 1103515245u + 12345u;
                double r = (double)(seed >> 8) / (double)(1u << 24) - 0.5;
                double p = cf_mesh_positions(m)[i];
                x[i] = variant == 0 ? p : variant == 1 ? p * (i % 3 == 0 ? 2.0 : 1.0) : p + 0.01 * r;
            }
            CHECK_OK(ctx, cf_harmonic_basis(ctx, m, x, &dim, a));
            int64_t before = cf_context_allocation_count(ctx);
            CHECK_OK(ctx, cf_harmonic_workspace_compute(w, x, b));
            if (variant == 0) {
                CHECK(memcmp(a, b, sizeof(double) * 2 * (size_t)ne) == 0);
                continue;
            }
            CHECK(cf_context_allocation_count(ctx) == before);
            double worst = 0.0, largest = 0.0;
            for (int64_t i = 0; i < 2 * (int64_t)ne; ++i) {
                worst = fmax(worst, fabs(a[i] - b[i]));
                largest = fmax(largest, fabs(a[i]));
            }
            fprintf(stderr, "   workspace, positions %d: largest difference from cf_harmonic_basis %.2g (forms up to %.3g)\n",
                    variant, worst, largest);
            CHECK_LE(worst, 1e-12 * largest);
        }
        x[5] = NAN;
        CHECK_STATUS(cf_harmonic_workspace_compute(w, x, b), CF_ERR_NONFINITE);
        CHECK_STATUS(cf_harmonic_workspace_compute(w, NULL, b), CF_ERR_INVALID_ARG);
        CHECK_STATUS(cf_harmonic_workspace_compute(NULL, x, b), CF_ERR_INVALID_ARG);
        cf_harmonic_workspace_destroy(&w);
        CHECK(w == NULL);
        cf_harmonic_workspace_destroy(&w); /* NULL: nothing */
        CHECK_OK(ctx, cf_harmonic_workspace_create(ctx, sphere, &w));
        CHECK(cf_harmonic_workspace_dimension(w) == 0);
        CHECK_OK(ctx, cf_harmonic_workspace_compute(w, cf_mesh_positions(sphere), b)); /* nothing to write */
        cf_harmonic_workspace_destroy(&w);
        CHECK_STATUS(cf_harmonic_workspace_create(ctx, NULL, &w), CF_ERR_INVALID_ARG);
        CHECK_STATUS(cf_harmonic_workspace_create(ctx, m, NULL), CF_ERR_INVALID_ARG);
        free(x);
        free(a);
        free(b);
    }
    cf_mesh_destroy(&m);
    cf_mesh_destroy(&sphere);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* 2g + b - 1 with genus and holes, and components of both kinds: a torus
 * with two faces removed (g 1, b 2: dim 3) next to a closed torus (dim 2). */
static void test_holed_torus(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *t = NULL, *m = NULL;
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.35, 40, 16, &t));
    if (!t) return;
    int32_t nv = cf_mesh_vertex_count(t), nf = cf_mesh_face_count(t);
    const int32_t *tri = cf_mesh_triangles(t);
    const double *x = cf_mesh_positions(t);
    double *p = malloc(sizeof(double) * 6 * (size_t)nv);
    int32_t *f = malloc(sizeof(int32_t) * 6 * (size_t)nf), k = 0;
    for (int32_t i = 0; i < 3 * nv; ++i) {
        p[i] = x[i];
        p[3 * nv + i] = x[i] + (i % 3 == 0 ? 3.0 : 0.0);
    }
    for (int32_t i = 0; i < nf; ++i) {
        if (i == 0 || i == nf / 2) continue;   /* two holes, far apart */
        for (int j = 0; j < 3; ++j) f[3 * k + j] = tri[3 * i + j];
        ++k;
    }
    for (int32_t i = 0; i < nf; ++i, ++k)
        for (int j = 0; j < 3; ++j) f[3 * k + j] = tri[3 * i + j] + nv;
    cf_mesh_desc d = {0};
    d.vertex_count = 2 * nv;
    d.positions = p;
    d.face_count = k;
    d.triangles = f;
    CHECK_OK(ctx, cf_mesh_create(ctx, &d, &m));
    if (m) {
        CHECK(cf_mesh_boundary_loop_count(m) == 2 && cf_mesh_component_count(m) == 2 && cf_mesh_genus(m) == 2);
        check_basis(ctx, m, 3 + 2, "holed torus + torus");
    }
    free(p);
    free(f);
    cf_mesh_destroy(&m);
    cf_mesh_destroy(&t);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* check_basis on each of the n shared meshes names[i], expecting dims[i]
 * harmonic fields; skips the program when ../shared/meshes is absent. */
static void check_shared(const char *const *names, const int32_t *dims, int n)
{
    if (!cft_shared_mesh_path(names[0])) cft_skip("../shared/meshes is absent");
    cf_context *ctx = cft_context();
    for (int i = 0; i < n; ++i) {
        cf_mesh *m = NULL;
        CHECK_OK(ctx, cf_load_mesh(ctx, cft_shared_mesh_path(names[i]), &m));
        if (m) check_basis(ctx, m, dims[i], names[i]);
        cf_mesh_destroy(&m);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_shared(void)
{
    static const char *names[] = {"bob_5k.obj", "double_torus_315.obj", "elephant_g3_3k.obj", "spot_3k.obj"};
    static const int32_t dims[] = {2, 4, 6, 0};
    check_shared(names, dims, 4);
}

/* Shared meshes with boundary (MANIFEST.tsv: genus 0, one component):
 * disks give 0, the two annuli 1, the bunny scan (5 holes) 4 = 2g + b - 1. */
static void test_shared_boundary(void)
{
    static const char *names[] = {"mushroom_cap_2k.obj", "plane_841.obj", "blade_slivers_8k.obj",
                                  "chinese_lion_statue_10k.obj", "bunny_scan_35k.obj"};
    static const int32_t dims[] = {0, 0, 1, 1, 4};
    check_shared(names, dims, 5);
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
    CFT_RUN(test_holed_torus);
    CFT_RUN(test_workspace);
    CFT_RUN(test_shared);
    CFT_RUN(test_shared_boundary);
    return cft_finish();
}
