/* Built-in generators: counts, topology (chi, genus, boundary loops),
 * outward orientation through the signed volume, analytic area/volume
 * limits with the observed convergence rate, texture coordinates where
 * promised, and bit-exact determinism. */
#include "curvflow/generate.h"
#include "curvflow/mesh.h"
#include "test.h"

#include <math.h>
#include <string.h>

#define PI 3.14159265358979323846

static double mesh_area(const cf_mesh *m)
{
    const double *p = cf_mesh_positions(m);
    const int32_t *t = cf_mesh_triangles(m);
    double area = 0.0;
    for (int32_t f = 0; f < cf_mesh_face_count(m); ++f) {
        const double *a = p + 3 * t[3 * f], *b = p + 3 * t[3 * f + 1], *c = p + 3 * t[3 * f + 2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        area += 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    return area;
}

/* Signed enclosed volume (divergence theorem); > 0 iff outward oriented. */
static double mesh_volume(const cf_mesh *m)
{
    const double *p = cf_mesh_positions(m);
    const int32_t *t = cf_mesh_triangles(m);
    double vol = 0.0;
    for (int32_t f = 0; f < cf_mesh_face_count(m); ++f) {
        const double *a = p + 3 * t[3 * f], *b = p + 3 * t[3 * f + 1], *c = p + 3 * t[3 * f + 2];
        vol += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0;
    }
    return vol;
}

static void check_topology(const cf_mesh *m, int32_t chi, int32_t genus, int32_t loops)
{
    CHECK(cf_mesh_euler_characteristic(m) == chi);
    CHECK(cf_mesh_genus(m) == genus);
    CHECK(cf_mesh_boundary_loop_count(m) == loops);
    CHECK(cf_mesh_component_count(m) == 1);
}

static void test_icosphere(void)
{
    cf_context *ctx = cft_context();
    const double R = 2.5;
    double err[7];
    for (int32_t s = 0; s <= 6; ++s) {
        cf_mesh *m = NULL;
        CHECK_OK(ctx, cf_generate_icosphere(ctx, s, R, &m));
        int32_t p4 = 1 << (2 * s);
        CHECK(cf_mesh_vertex_count(m) == 10 * p4 + 2);
        CHECK(cf_mesh_face_count(m) == 20 * p4);
        check_topology(m, 2, 0, 0);
        double worst = 0.0;
        for (int32_t v = 0; v < cf_mesh_vertex_count(m); ++v) {
            const double *p = cf_mesh_positions(m) + 3 * v;
            double d = fabs(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - R);
            if (d > worst) worst = d;
        }
        CHECK_LE(worst, 4e-15 * R); /* exact projection, up to rounding */
        CHECK(mesh_volume(m) > 0.0);
        err[s] = 4.0 * PI * R * R - mesh_area(m);
        CHECK(err[s] > 0.0); /* inscribed polyhedron */
        cf_mesh_destroy(&m);
    }
    /* The inscribed area error is O(h^2): each split halves h, so the error
     * ratio between levels tends to 4 (observed 3.98-4.00 from s = 3). */
    for (int s = 3; s < 6; ++s) {
        double rate = log2(err[s] / err[s + 1]);
        CHECK_NEAR(rate, 2.0, 0.0, 0.02);
    }
    CHECK_LE(err[6] / (4.0 * PI * R * R), 2e-4);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_torus(void)
{
    cf_context *ctx = cft_context();
    const double R = 3.0, r = 1.0;
    double prev_err = 0.0;
    for (int32_t n = 16; n <= 64; n *= 2) {
        cf_mesh *m = NULL;
        CHECK_OK(ctx, cf_generate_torus(ctx, R, r, 2 * n, n, &m));
        CHECK(cf_mesh_vertex_count(m) == 2 * n * n && cf_mesh_face_count(m) == 4 * n * n);
        check_topology(m, 0, 1, 0);
        /* vertex 0 at angles (0, 0): (R + r, 0, 0) */
        CHECK(cf_mesh_positions(m)[0] == R + r && cf_mesh_positions(m)[2] == 0.0);
        double vol = mesh_volume(m), err = fabs(vol - 2.0 * PI * PI * R * r * r);
        CHECK(vol > 0.0);
        CHECK_NEAR(mesh_area(m), 4.0 * PI * PI * R * r, 0.02, 0.0);
        /* second order: the volume error drops ~4x per doubling */
        if (prev_err > 0.0) CHECK_NEAR(log2(prev_err / err), 2.0, 0.0, 0.1);
        prev_err = err;
        cf_mesh_destroy(&m);
    }
    cf_mesh *m = NULL;
    CHECK_STATUS(cf_generate_torus(ctx, 1.0, 1.0, 8, 8, &m), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_generate_torus(ctx, 2.0, 1.0, 2, 8, &m), CF_ERR_INVALID_ARG);
    CHECK(m == NULL);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_bumpy_sphere(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *a = NULL, *b = NULL, *c = NULL;
    const double amp = 0.2;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 4, amp, 7u, &a));
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 4, amp, 7u, &b));
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 4, amp, 8u, &c));
    const int32_t nv = cf_mesh_vertex_count(a), nf = cf_mesh_face_count(a);
    check_topology(a, 2, 0, 0);
    CHECK(mesh_volume(a) > 0.0);
    /* deterministic per seed, different across seeds */
    CHECK(memcmp(cf_mesh_positions(a), cf_mesh_positions(b), 3 * (size_t)nv * sizeof(double)) == 0);
    CHECK(memcmp(cf_mesh_positions(a), cf_mesh_positions(c), 3 * (size_t)nv * sizeof(double)) != 0);
    CHECK(cf_mesh_uv_count(a) == cf_mesh_uv_count(b));
    CHECK(memcmp(cf_mesh_uv(a), cf_mesh_uv(b), 2 * (size_t)cf_mesh_uv_count(a) * sizeof(double)) == 0);
    /* radial bump field normalised so max |r - 1| = amplitude */
    double lo = 10.0, hi = 0.0;
    for (int32_t v = 0; v < nv; ++v) {
        const double *p = cf_mesh_positions(a) + 3 * v;
        double rr = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        lo = rr < lo ? rr : lo;
        hi = rr > hi ? rr : hi;
    }
    CHECK_NEAR(fmax(hi - 1.0, 1.0 - lo), amp, 1e-12, 0.0);
    /* per-corner uv with a seam: more uv entries than vertices, every face's
     * u span stays small (no face wraps through the whole texture), and v
     * is the latitude of the corner's vertex */
    const double *uv = cf_mesh_uv(a);
    const int32_t *ut = cf_mesh_uv_triangles(a), *t = cf_mesh_triangles(a);
    CHECK(ut != NULL && cf_mesh_uv_count(a) > nv);
    int bad = 0;
    double span_max = 0.0;
    for (int32_t f = 0; f < nf; ++f) {
        double umin = 10, umax = -10;
        for (int k = 0; k < 3; ++k) {
            double u = uv[2 * ut[3 * f + k]];
            umin = fmin(umin, u), umax = fmax(umax, u);
            const double *p = cf_mesh_positions(a) + 3 * t[3 * f + k];
            double lat = asin(p[2] / sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2])) / PI + 0.5;
            if (fabs(uv[2 * ut[3 * f + k] + 1] - lat) > 1e-12) ++bad;
        }
        span_max = fmax(span_max, umax - umin);
    }
    CHECK(bad == 0);
    /* a face straddling the seam without its own uv would span ~1; the
     * widest legitimate faces touch a pole of valence 5 (72 deg = 0.2) */
    CHECK_LE(span_max, 0.2 + 1e-12);
    cf_mesh_destroy(&a);
    cf_mesh_destroy(&b);
    CHECK_STATUS(cf_generate_bumpy_sphere(ctx, 2, 0.6, 1u, &b), CF_ERR_INVALID_ARG);
    CHECK(b == NULL);
    cf_mesh_destroy(&c);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_grid_and_sheet(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_grid(ctx, 8, 5, 2.0, 1.0, &m));
    CHECK(cf_mesh_vertex_count(m) == 54 && cf_mesh_face_count(m) == 80);
    check_topology(m, 1, 0, 1);
    CHECK(cf_mesh_boundary_loop_offsets(m)[1] == 2 * (8 + 5));
    CHECK_NEAR(mesh_area(m), 2.0, 1e-14, 0.0);
    /* flat, +z normals, uv = normalised (x, y) per vertex */
    const double *p = cf_mesh_positions(m), *uv = cf_mesh_uv(m);
    const int32_t *t = cf_mesh_triangles(m);
    int bad = 0;
    for (int32_t v = 0; v < cf_mesh_vertex_count(m); ++v)
        if (p[3 * v + 2] != 0.0 || fabs(uv[2 * v] - p[3 * v] / 2.0) > 1e-15 || fabs(uv[2 * v + 1] - p[3 * v + 1]) > 1e-15)
            ++bad;
    for (int32_t f = 0; f < cf_mesh_face_count(m); ++f) {
        const double *a = p + 3 * t[3 * f], *b = p + 3 * t[3 * f + 1], *c = p + 3 * t[3 * f + 2];
        if ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) <= 0.0) ++bad;
    }
    CHECK(bad == 0);
    CHECK(cf_mesh_uv_count(m) == cf_mesh_vertex_count(m));
    cf_mesh_destroy(&m);

    /* Zhao & Gortler App. B, Table 1: the n = 10 unit sheet has 200 triangles */
    cf_mesh *s0 = NULL, *s1 = NULL;
    CHECK_OK(ctx, cf_generate_sheet(ctx, 10, 1.0, 0, &s0));
    CHECK_OK(ctx, cf_generate_sheet(ctx, 10, 1.0, 1, &s1));
    CHECK(cf_mesh_face_count(s0) == 200 && cf_mesh_vertex_count(s0) == 121);
    check_topology(s0, 1, 0, 1);
    check_topology(s1, 1, 0, 1);
    CHECK_NEAR(mesh_area(s0), 1.0, 1e-14, 0.0);
    CHECK_NEAR(mesh_area(s1), 1.0, 1e-14, 0.0);
    /* same vertices, different triangulation */
    CHECK(memcmp(cf_mesh_positions(s0), cf_mesh_positions(s1), 3 * 121 * sizeof(double)) == 0);
    CHECK(memcmp(cf_mesh_triangles(s0), cf_mesh_triangles(s1), 3 * 200 * sizeof(int32_t)) != 0);
    /* pattern 0: every diagonal joins (x0, y0)-(x1, y1): edges with both dx, dy != 0 have dx = dy */
    bad = 0;
    for (int32_t e = 0; e < cf_mesh_edge_count(s0); ++e) {
        const double *a = cf_mesh_positions(s0) + 3 * cf_mesh_edge_vertices(s0)[2 * e];
        const double *b = cf_mesh_positions(s0) + 3 * cf_mesh_edge_vertices(s0)[2 * e + 1];
        double dx = b[0] - a[0], dy = b[1] - a[1];
        if (dx != 0.0 && dy != 0.0 && fabs(dx - dy) > 1e-15) ++bad;
    }
    CHECK(bad == 0);
    cf_mesh_destroy(&s0);
    cf_mesh_destroy(&s1);
    CHECK_STATUS(cf_generate_grid(ctx, 0, 5, 1.0, 1.0, &m), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_generate_sheet(ctx, 4, 1.0, 2, &m), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_generate_grid(ctx, 3, 5, NAN, 1.0, &m), CF_ERR_INVALID_ARG);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_bumpy_plane(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *a = NULL, *b = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_plane(ctx, 40, 2.0, 0.1, 5u, &a));
    CHECK_OK(ctx, cf_generate_bumpy_plane(ctx, 40, 2.0, 0.1, 5u, &b));
    check_topology(a, 1, 0, 1);
    const int32_t nv = cf_mesh_vertex_count(a);
    CHECK(memcmp(cf_mesh_positions(a), cf_mesh_positions(b), 3 * (size_t)nv * sizeof(double)) == 0);
    double zmax = 0.0;
    for (int32_t v = 0; v < nv; ++v) zmax = fmax(zmax, fabs(cf_mesh_positions(a)[3 * v + 2]));
    /* max |z| = amplitude * size on the 201^2 sample grid; the 41^2 vertex
     * grid is a subset of it (40 divides 200), so the bound is exact */
    CHECK_LE(zmax, 0.2 + 1e-15);
    CHECK(zmax > 0.1);
    CHECK(cf_mesh_uv(a) != NULL);
    cf_mesh_destroy(&a);
    cf_mesh_destroy(&b);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_cylinder(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 16, 5, 1.0, 2.0, &m));
    CHECK(cf_mesh_vertex_count(m) == 96 && cf_mesh_face_count(m) == 160);
    check_topology(m, 0, 0, 2);
    CHECK(cf_mesh_uv_count(m) == 17 * 6);
    /* outward: the face normal points away from the axis */
    const double *p = cf_mesh_positions(m), *uv = cf_mesh_uv(m);
    const int32_t *t = cf_mesh_triangles(m), *ut = cf_mesh_uv_triangles(m);
    int bad = 0;
    for (int32_t f = 0; f < cf_mesh_face_count(m); ++f) {
        const double *a = p + 3 * t[3 * f], *b = p + 3 * t[3 * f + 1], *c = p + 3 * t[3 * f + 2];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double nx = u[1] * v[2] - u[2] * v[1], ny = u[2] * v[0] - u[0] * v[2];
        if (nx * (a[0] + b[0] + c[0]) + ny * (a[1] + b[1] + c[1]) <= 0.0) ++bad;
        double umin = 10, umax = -10;
        for (int k = 0; k < 3; ++k) umin = fmin(umin, uv[2 * ut[3 * f + k]]), umax = fmax(umax, uv[2 * ut[3 * f + k]]);
        if (umax - umin > 1.0 / 16 + 1e-15) ++bad; /* no seam jump */
    }
    CHECK(bad == 0);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_bar(void)
{
    cf_context *ctx = cft_context();
    const int32_t nx = 12, ny = 3, nz = 2;
    cf_mesh *a = NULL, *b = NULL;
    CHECK_OK(ctx, cf_generate_bar(ctx, nx, ny, nz, 6.0, 1.0, 0.5, 0, &a));
    CHECK_OK(ctx, cf_generate_bar(ctx, nx, ny, nz, 6.0, 1.0, 0.5, 1, &b));
    int32_t cells = nx * ny + ny * nz + nz * nx;
    CHECK(cf_mesh_vertex_count(a) == 2 * cells + 2 && cf_mesh_face_count(a) == 4 * cells);
    check_topology(a, 2, 0, 0);
    check_topology(b, 2, 0, 0);
    CHECK_NEAR(mesh_volume(a), 3.0, 1e-14, 0.0);
    CHECK_NEAR(mesh_volume(b), 3.0, 1e-14, 0.0);
    CHECK_NEAR(mesh_area(a), 2.0 * (6.0 + 3.0 + 0.5), 1e-14, 0.0);
    /* same vertex set, different diagonals */
    CHECK(memcmp(cf_mesh_positions(a), cf_mesh_positions(b), 3 * (size_t)cf_mesh_vertex_count(a) * sizeof(double)) == 0);
    CHECK(memcmp(cf_mesh_triangles(a), cf_mesh_triangles(b), 3 * (size_t)cf_mesh_face_count(a) * sizeof(int32_t)) != 0);
    cf_mesh_destroy(&a);
    cf_mesh_destroy(&b);
    CHECK_STATUS(cf_generate_bar(ctx, 0, 1, 1, 1.0, 1.0, 1.0, 0, &a), CF_ERR_INVALID_ARG);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_double_torus(void)
{
    cf_context *ctx = cft_context();
    for (int32_t r = 1; r <= 3; ++r) {
        cf_mesh *m = NULL;
        CHECK_OK(ctx, cf_generate_double_torus(ctx, r, &m));
        check_topology(m, -2, 2, 0);
        /* 5 x 3 x 1 cells minus two holes, cell side 1/5 */
        CHECK_NEAR(mesh_volume(m), 13.0 / 125.0, 1e-13, 0.0);
        cf_mesh_destroy(&m);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_icosphere);
    CFT_RUN(test_torus);
    CFT_RUN(test_bumpy_sphere);
    CFT_RUN(test_grid_and_sheet);
    CFT_RUN(test_bumpy_plane);
    CFT_RUN(test_cylinder);
    CFT_RUN(test_bar);
    CFT_RUN(test_double_torus);
    return cft_finish();
}
