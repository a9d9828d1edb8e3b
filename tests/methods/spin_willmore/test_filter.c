/*
 * Spectral filtering of the flow direction (Crane, Pinkall, Schroeder 2013,
 * Sec. 4, Fig. 8 and 19): v <- v - (id + sigma Delta^k)^-1 v damps the
 * low-frequency part of v. k = 0 is a plain scaling by sigma / (1 + sigma);
 * for k = 1..3 with the cut-off sigma Delta^k = 1 at Delta = 20 / R^2 the
 * filtered direction has a higher Dirichlet/L2 ratio (it is "rougher") than
 * the unfiltered one, and the flow still lowers W.
 */
#include "test.h"

#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/ops.h"
#include "curvflow/spin_willmore.h"
#include "methods/spin_willmore/spin_internal.h"

#include <stdlib.h>
#include <string.h>

/* One step with (sigma, k); copies rhodot (nv) and returns the energy ratio W1/W0. */
static double one_step(cf_context *ctx, const cf_mesh *mesh, double sigma, int k, double *rhodot)
{
    cf_flow_options o;
    cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o);
    cf_spin_willmore_options *so = cf_flow_options_method(&o);
    so->sigma = sigma;
    so->filter_k = k;
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    if (!flow) return NAN;
    double w0 = cf_flow_energy(flow);
    cf_flow_info info;
    CHECK_OK(ctx, cf_flow_step(flow, &info));
    memcpy(rhodot, cfi_spin_willmore_last_rhodot(flow), (size_t)cf_mesh_vertex_count(mesh) * sizeof(double));
    cf_flow_destroy(&flow);
    return info.energy / w0;
}

static double roughness(const cf_sparse *l, const double *m, int32_t n, const double *v, double *tmp)
{
    cf_sparse_multiply(l, v, tmp);
    double num = 0.0, den = 0.0;
    for (int32_t i = 0; i < n; ++i) {
        num += v[i] * tmp[i];
        den += m[i] * v[i] * v[i];
    }
    return num / den;
}

static void test_filter(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.3, 5u, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *v0 = malloc((size_t)nv * sizeof(double)), *v = malloc((size_t)nv * sizeof(double));
    double *m = malloc((size_t)nv * sizeof(double)), *tmp = malloc((size_t)nv * sizeof(double));
    cf_sparse *l = NULL;
    CHECK_OK(ctx, cf_cotan_laplacian(ctx, mesh, cf_mesh_positions(mesh), &l));
    CHECK_OK(ctx, cf_vertex_areas(ctx, mesh, cf_mesh_positions(mesh), CF_DUAL_AREA_BARYCENTRIC, m));
    double r0 = one_step(ctx, mesh, 0.0, 2, v0);
    double rough0 = roughness(l, m, nv, v0, tmp);
    /* k = 0: exact scaling (the projection is linear) */
    one_step(ctx, mesh, 1.0, 0, v);
    double worst = 0.0, vmax = 0.0;
    for (int32_t i = 0; i < nv; ++i) {
        worst = fmax(worst, fabs(v[i] - 0.5 * v0[i]));
        vmax = fmax(vmax, fabs(v0[i]));
    }
    CHECK_LE(worst, 1e-12 * vmax);
    fprintf(stderr, "   unfiltered: W1/W0 %.4f, roughness %.3f\n", r0, rough0);
    for (int k = 1; k <= 3; ++k) {
        /* cut-off at Delta = 20 / R^2 (about spherical harmonic degree 4) */
        double sigma = pow(20.0, -k);
        double r = one_step(ctx, mesh, sigma, k, v);
        double rough = roughness(l, m, nv, v, tmp);
        fprintf(stderr, "   k = %d, sigma %.3g: W1/W0 %.4f, roughness %.3f\n", k, sigma, r, rough);
        CHECK(rough > 1.2 * rough0);
        CHECK(r < 1.0);
    }
    cf_sparse_destroy(&l);
    free(v0);
    free(v);
    free(m);
    free(tmp);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_filter);
    return cft_finish();
}
