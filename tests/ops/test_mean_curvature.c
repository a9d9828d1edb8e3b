/* Mean curvature, area, volume and Willmore energy on refined icospheres:
 * limits 1/R, 4 pi R^2, 4/3 pi R^3, 4 pi with the observed convergence
 * rate asserted; invariance under rigid motion and scaling. */
#include "curvflow/generate.h"
#include "curvflow/ops.h"
#include "test.h"

#include <math.h>
#include <stdlib.h>

#define PI 3.14159265358979323846

static double mean_edge_length(const cf_mesh *mesh, const double *x)
{
    int32_t ne = cf_mesh_edge_count(mesh);
    const int32_t *ev = cf_mesh_edge_vertices(mesh);
    double sum = 0;
    for (int32_t e = 0; e < ne; ++e) {
        const double *a = x + 3 * ev[2 * e], *b = x + 3 * ev[2 * e + 1];
        sum += sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
    }
    return sum / ne;
}

/* least-squares slope of log(err) against log(h) */
static double fit_rate(int n, const double *h, const double *err)
{
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (int i = 0; i < n; ++i) {
        double x = log(h[i]), y = log(err[i]);
        sx += x;
        sy += y;
        sxx += x * x;
        sxy += x * y;
    }
    return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

static void test_icosphere_convergence(void)
{
    cf_context *ctx = cft_context();
    const double r = 2.5;
    enum { LEVELS = 5 };
    double h[LEVELS], e_h[LEVELS], e_area[LEVELS], e_vol[LEVELS], e_will[LEVELS];
    for (int s = 1; s <= LEVELS; ++s) {
        cf_mesh *mesh = NULL;
        CHECK_OK(ctx, cf_generate_icosphere(ctx, s, r, &mesh));
        if (!mesh) break;
        const double *x = cf_mesh_positions(mesh);
        int32_t nv = cf_mesh_vertex_count(mesh);
        double *hv = malloc(sizeof(double) * nv);
        CHECK_OK(ctx, cf_mean_curvature(ctx, mesh, x, hv));
        double max_err = 0;
        for (int32_t v = 0; v < nv; ++v) max_err = fmax(max_err, fabs(hv[v] * r - 1.0));
        double area, vol, will;
        CHECK_OK(ctx, cf_total_area(ctx, mesh, x, &area));
        CHECK_OK(ctx, cf_enclosed_volume(ctx, mesh, x, &vol));
        CHECK_OK(ctx, cf_willmore_energy(ctx, mesh, x, &will));
        h[s - 1] = mean_edge_length(mesh, x) / r;
        e_h[s - 1] = max_err;
        e_area[s - 1] = fabs(area / (4 * PI * r * r) - 1.0);
        e_vol[s - 1] = fabs(vol / (4.0 / 3.0 * PI * r * r * r) - 1.0);
        e_will[s - 1] = fabs(will / (4 * PI) - 1.0);
        fprintf(stderr, "  subdiv %d  h/R %.4f  max|H R - 1| %.3e  area %.3e  volume %.3e  W/4pi-1 %.3e\n", s,
                h[s - 1], e_h[s - 1], e_area[s - 1], e_vol[s - 1], e_will[s - 1]);
        free(hv);
        cf_mesh_destroy(&mesh);
    }
    /* level 1 is exact to round-off (all vertices alike), so the H rate is
     * fitted on levels 2..5 */
    double rh = fit_rate(LEVELS - 1, h + 1, e_h + 1), ra = fit_rate(LEVELS, h, e_area), rv = fit_rate(LEVELS, h, e_vol),
           rw = fit_rate(LEVELS, h, e_will);
    fprintf(stderr, "  observed rates: H %.3f  area %.3f  volume %.3f  Willmore %.3f\n", rh, ra, rv, rw);
    /* inscribed polyhedron: area and volume deficits are O(h^2) */
    CHECK_NEAR(ra, 2.0, 0, 0.1);
    CHECK_NEAR(rv, 2.0, 0, 0.1);
    CHECK(e_area[LEVELS - 1] < 1e-3);
    CHECK(e_vol[LEVELS - 1] < 1e-3);
    /* mixed-Voronoi pointwise H: O(h^2) (measured 2.00) */
    CHECK_NEAR(rh, 2.0, 0, 0.1);
    CHECK(e_h[LEVELS - 1] < 1e-5);
    /* Willmore energy -> 4 pi, O(h^2) (measured 2.01) */
    CHECK_NEAR(rw, 2.0, 0, 0.1);
    CHECK(e_will[LEVELS - 1] < 1e-3);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void rigid_scale(int32_t nv, const double *x, double s, double *y)
{
    /* rotation about (1, 2, 2)/3 by 0.7 rad (Rodrigues), then scale and shift */
    double k[3] = {1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0}, c = cos(0.7), sn = sin(0.7);
    for (int32_t v = 0; v < nv; ++v) {
        const double *p = x + 3 * v;
        double kp = k[0] * p[0] + k[1] * p[1] + k[2] * p[2];
        double cr[3] = {k[1] * p[2] - k[2] * p[1], k[2] * p[0] - k[0] * p[2], k[0] * p[1] - k[1] * p[0]};
        for (int i = 0; i < 3; ++i)
            y[3 * v + i] = s * (p[i] * c + cr[i] * sn + k[i] * kp * (1 - c)) + (i + 1) * 0.37;
    }
}

/* Area, enclosed volume and Willmore energy of positions x: m[0..2]. */
static void measures(cf_context *ctx, const cf_mesh *mesh, const double *x, double m[3])
{
    CHECK_OK(ctx, cf_total_area(ctx, mesh, x, &m[0]));
    CHECK_OK(ctx, cf_enclosed_volume(ctx, mesh, x, &m[1]));
    CHECK_OK(ctx, cf_willmore_energy(ctx, mesh, x, &m[2]));
}

static void test_rigid_and_scale_invariance(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.3, 7u, &mesh));
    if (!mesh) return;
    const double *x = cf_mesh_positions(mesh);
    int32_t nv = cf_mesh_vertex_count(mesh);
    const double s = 2.75;
    double *y = malloc(sizeof(double) * 3 * nv), *h0 = malloc(sizeof(double) * nv), *h1 = malloc(sizeof(double) * nv);
    double *k0 = malloc(sizeof(double) * nv), *k1 = malloc(sizeof(double) * nv);
    rigid_scale(nv, x, s, y);
    CHECK_OK(ctx, cf_mean_curvature(ctx, mesh, x, h0));
    CHECK_OK(ctx, cf_mean_curvature(ctx, mesh, y, h1));
    CHECK_OK(ctx, cf_angle_defect(ctx, mesh, x, k0));
    CHECK_OK(ctx, cf_angle_defect(ctx, mesh, y, k1));
    int neg = 0;
    for (int32_t v = 0; v < nv; ++v) {
        CHECK_NEAR(h1[v], h0[v] / s, 1e-10, 1e-12); /* H scales as 1/s */
        CHECK_NEAR(k1[v], k0[v], 0, 1e-12);        /* angles are invariant */
        neg += h0[v] < 0;
    }
    double m0[3], m1[3];
    measures(ctx, mesh, x, m0);
    measures(ctx, mesh, y, m1);
    double a0 = m0[0], a1 = m1[0], v0 = m0[1], v1 = m1[1], w0 = m0[2], w1 = m1[2];
    CHECK_NEAR(a1, s * s * a0, 1e-12, 0);
    CHECK_NEAR(v1, s * s * s * v0, 1e-11, 0);
    CHECK_NEAR(w1, w0, 1e-10, 0);
    CHECK(w0 > 4 * PI); /* W >= 4 pi, equality only for round spheres */
    fprintf(stderr, "  bumpy sphere: W/4pi = %.4f, %d vertices with H < 0\n", w0 / (4 * PI), neg);
    /* integrated mean-curvature normal points outward on the convex sphere */
    cf_mesh *sphere = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &sphere));
    double *hn = malloc(sizeof(double) * 3 * cf_mesh_vertex_count(sphere));
    const double *xs = cf_mesh_positions(sphere);
    CHECK_OK(ctx, cf_mean_curvature_normal(ctx, sphere, xs, hn));
    for (int32_t v = 0; v < cf_mesh_vertex_count(sphere); ++v)
        CHECK(hn[3 * v] * xs[3 * v] + hn[3 * v + 1] * xs[3 * v + 1] + hn[3 * v + 2] * xs[3 * v + 2] > 0);
    /* bad input */
    y[5] = NAN;
    CHECK_STATUS(cf_mean_curvature(ctx, mesh, y, h1), CF_ERR_NONFINITE);
    CHECK_STATUS(cf_mean_curvature(ctx, mesh, NULL, h1), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_willmore_energy(ctx, NULL, x, &w0), CF_ERR_INVALID_ARG);
    free(hn);
    free(y);
    free(h0);
    free(h1);
    free(k0);
    free(k1);
    cf_mesh_destroy(&sphere);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* The same bumpy sphere moved far from the origin (a georeferenced scan:
 * by (1e6, -2e6, 5e5)): area, volume and W as at the origin, to what the
 * rounding of the moved coordinates (2.3e-10 near 2e6) allows. Before the
 * volume took its cones from the bounding box's centre it came out 108
 * times off here (spot_3k moved by 1e6: 0.7181662 against 0.7182588). */
static void test_far_from_origin(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.3, 7u, &mesh));
    if (!mesh) return;
    const double *x = cf_mesh_positions(mesh);
    int32_t nv = cf_mesh_vertex_count(mesh);
    const double offset[3] = {1e6, -2e6, 5e5};
    double *y = malloc(sizeof(double) * 3 * nv);
    for (int32_t i = 0; i < 3 * nv; ++i) y[i] = x[i] + offset[i % 3];
    double m0[3], m1[3];
    measures(ctx, mesh, x, m0);
    measures(ctx, mesh, y, m1);
    fprintf(stderr, "  moved by 2e6: relative change of area %.2e, volume %.2e, W %.2e\n", fabs(m1[0] / m0[0] - 1),
            fabs(m1[1] / m0[1] - 1), fabs(m1[2] / m0[2] - 1));
    CHECK_NEAR(m1[0], m0[0], 1e-8, 0);
    CHECK_NEAR(m1[1], m0[1], 1e-8, 0);
    CHECK_NEAR(m1[2], m0[2], 1e-6, 0);
    free(y);
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_icosphere_convergence);
    CFT_RUN(test_rigid_and_scale_invariance);
    CFT_RUN(test_far_from_origin);
    return cft_finish();
}
