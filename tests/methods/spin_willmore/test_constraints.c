/*
 * Constraints of the conformal Willmore flow (Crane, Pinkall, Schroeder
 * 2013, Sec. 6.2, App. B-E):
 *  - after projection <rhodot, 1> and <rhodot, N^x,y,z> vanish to 1e-10
 *    relative (App. B, D);
 *  - genus > 0 (Fig. 12): with the exactness constraint the flow on bob_5k
 *    lowers W without degenerate triangles, and the integrability error is
 *    at least 10x smaller than without it;
 *  - annulus with free boundary (Sec. 6.2: "torus or annulus"): the
 *    linearised exactness constraint removes the first-order period of the
 *    transformed edges, so the integrability error is >= 10x smaller at
 *    tau = 0.005 and falls like tau^2 instead of tau; fixed / prescribed
 *    boundaries get no exactness constraint (docs/spin.md);
 *  - Moebius balancing (Fig. 13) reduces the spread of log area distortion
 *    on spot_3k;
 *  - harmonic_update: after 40 steps on a bumped torus the forms behind the
 *    exactness constraint are harmonic on the current surface (they lie in
 *    the span of a freshly computed basis), where the input's forms have
 *    drifted out of it.
 */
#include "test.h"
#include "spin_test_util.h"

#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/metrics.h"
#include "curvflow/ops.h"
#include "curvflow/spin_willmore.h"
#include "methods/spin_willmore/spin_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static cf_flow *make_flow(cf_context *ctx, const cf_mesh *mesh, double tau, int tc, int inv, int ex, int mob)
{
    cf_flow_options o;
    cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o);
    cf_spin_willmore_options *so = cf_flow_options_method(&o);
    so->time_step = tau;
    so->total_curvature = tc;
    so->inversion = inv;
    so->exactness = ex;
    so->mobius = mob;
    so->tolerance = 0.0;
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    return flow;
}

static double period_part(cf_context *ctx, const cf_mesh *mesh, const double *x, const double *edges);

/* Takes `steps` steps, each of which must succeed without raising W;
 * returns the final energy (the start energy if flow is NULL). */
static double monotone_steps(cf_context *ctx, cf_flow *flow, int steps)
{
    if (!flow) return 0.0;
    double w = cf_flow_energy(flow);
    for (int s = 0; s < steps; ++s) {
        cf_flow_info info;
        CHECK_OK(ctx, cf_flow_step(flow, &info));
        CHECK_LE(info.energy, w);
        w = info.energy;
    }
    return w;
}

/* Total mean curvature sum_i A_i H_i. */
static double total_curvature(cf_context *ctx, const cf_mesh *mesh, const double *x)
{
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *h = malloc((size_t)nv * sizeof(double)), *a = malloc((size_t)nv * sizeof(double));
    CHECK_OK(ctx, cf_mean_curvature(ctx, mesh, x, h));
    CHECK_OK(ctx, cf_vertex_areas(ctx, mesh, x, CF_DUAL_AREA_BARYCENTRIC, a));
    double t = 0.0, area = 0.0;
    for (int32_t i = 0; i < nv; ++i) {
        t += a[i] * h[i];
        area += a[i];
    }
    free(h);
    free(a);
    return t / sqrt(area);   /* scale invariant, like mu */
}

static void test_residuals_and_total_curvature(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "spot_3k.obj", 1)) return;
    cf_context *ctx = shared.ctx;
    cf_mesh *mesh = shared.mesh;
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *x0 = malloc(3 * (size_t)nv * sizeof(double)), *a = malloc((size_t)nv * sizeof(double));
    double *n = malloc(3 * (size_t)nv * sizeof(double));
    double change[2];
    for (int tc = 1; tc >= 0; --tc) {
        cf_flow *flow = make_flow(ctx, mesh, 0.1, tc, 1, 1, 0);
        memcpy(x0, cf_flow_positions(flow), 3 * (size_t)nv * sizeof(double));
        double t0 = total_curvature(ctx, mesh, x0);
        CHECK_OK(ctx, cf_flow_step(flow, NULL));
        double t1 = total_curvature(ctx, mesh, cf_flow_positions(flow));
        change[tc] = fabs(t1 - t0) / fabs(t0);
        /* independent check of the residuals against the raw constraint functions
         * of the surface the step started from */
        const double *rd = cfi_spin_willmore_last_rhodot(flow);
        CHECK_OK(ctx, cf_vertex_areas(ctx, mesh, x0, CF_DUAL_AREA_BARYCENTRIC, a));
        CHECK_OK(ctx, cf_vertex_normals(ctx, mesh, x0, n));
        double rr = 0.0, r1 = 0.0, c11 = 0.0, rn[3] = {0, 0, 0}, cnn[3] = {0, 0, 0};
        for (int32_t i = 0; i < nv; ++i) {
            rr += a[i] * rd[i] * rd[i];
            r1 += a[i] * rd[i];
            c11 += a[i];
            for (int c = 0; c < 3; ++c) {
                rn[c] += a[i] * rd[i] * n[3 * i + c];
                cnn[c] += a[i] * n[3 * i + c] * n[3 * i + c];
            }
        }
        double worst_n = 0.0;
        for (int c = 0; c < 3; ++c) worst_n = fmax(worst_n, fabs(rn[c]) / sqrt(rr * cnn[c]));
        cfi_spin_diagnostics d;
        CHECK_OK(ctx, cfi_spin_willmore_diagnostics(flow, &d));
        fprintf(stderr, "   total_curvature=%d: |<rhodot,1>| %.2e, max |<rhodot,N>| %.2e, hook %.2e, rank %d/%d, total curvature change %.3e\n",
                tc, fabs(r1) / sqrt(rr * c11), worst_n, d.constraint_residual, d.constraint_rank, d.constraint_count,
                change[tc]);
        CHECK_LE(worst_n, 1e-10);
        CHECK_LE(d.constraint_residual, 1e-10);
        if (tc) {
            CHECK_LE(fabs(r1) / sqrt(rr * c11), 1e-10);
            CHECK(d.constraint_rank == 4 && d.constraint_count == 4);
        }
        cf_flow_destroy(&flow);
    }
    /* App. B promises conservation of total curvature for <rhodot, 1> = 0;
     * the realised change is dominated by the discretisation (docs/spin.md),
     * so only the prescribed part is asserted above and the realised change
     * is printed. */
    free(x0);
    free(a);
    free(n);
    cft_shared_case_close(&shared);
}

/* App. B: what a step conserves is the total of the curvature half-density,
 * sum_i H~_i sqrt(A~_i A_i) against the surface the step started from, not
 * the total mean curvature sum_i H~_i A~_i. Measured on spot_3k (one step):
 * relative change -1.26e-3 / -4.8e-4 at tau 0.02 / 0.01 for the half-density
 * total against ~-3.8e-2 at tau 0.02 for the plain total (scale-free form).
 * The half-density total is not exactly conserved (the discrete transform
 * realises about 0.98 of rho), but 30x better than the plain one and
 * shrinking with tau. */
static double half_density_total(cf_context *ctx, const cf_mesh *mesh, const double *x0, const double *x)
{
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *h = malloc((size_t)nv * sizeof(double)), *a = malloc((size_t)nv * sizeof(double)),
           *a0 = malloc((size_t)nv * sizeof(double)), t = 0.0;
    CHECK_OK(ctx, cf_mean_curvature(ctx, mesh, x, h));
    CHECK_OK(ctx, cf_vertex_areas(ctx, mesh, x, CF_DUAL_AREA_BARYCENTRIC, a));
    CHECK_OK(ctx, cf_vertex_areas(ctx, mesh, x0, CF_DUAL_AREA_BARYCENTRIC, a0));
    for (int32_t i = 0; i < nv; ++i) t += h[i] * sqrt(a[i] * a0[i]);
    free(h);
    free(a);
    free(a0);
    return t;
}

static void test_total_curvature_half_density(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "spot_3k.obj", 0)) return;
    cf_context *ctx = shared.ctx;
    cf_mesh *mesh = shared.mesh;
    const double *x0 = cf_mesh_positions(mesh);
    double half[2], plain[2];
    const double taus[2] = {0.02, 0.01};
    for (int k = 0; k < 2; ++k) {
        cf_flow *flow = make_flow(ctx, mesh, taus[k], 1, 1, 1, 0);
        if (!flow) break;
        double h0 = half_density_total(ctx, mesh, x0, x0), p0 = total_curvature(ctx, mesh, x0);
        CHECK_OK(ctx, cf_flow_step(flow, NULL));
        const double *x = cf_flow_positions(flow);
        half[k] = fabs(half_density_total(ctx, mesh, x0, x) - h0) / fabs(h0);
        plain[k] = fabs(total_curvature(ctx, mesh, x) - p0) / fabs(p0);
        cf_flow_destroy(&flow);
    }
    fprintf(stderr, "   spot one step: relative change of the half-density total %.3g / %.3g at tau 0.02 / 0.01, "
                    "of the total mean curvature %.3g / %.3g\n", half[0], half[1], plain[0], plain[1]);
    CHECK_LE(half[0], 0.1 * plain[0]);
    CHECK_LE(half[1], 0.6 * half[0]);
    CHECK_LE(half[0], 3e-3);
    cft_shared_case_close(&shared);
}

/* Fig. 12: genus 1 (bob_5k). */
static void test_exactness_genus_one(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "bob_5k.obj", 1)) return;
    cf_context *ctx = shared.ctx;
    cf_mesh *mesh = shared.mesh;
    CHECK(cf_mesh_genus(mesh) == 1);
    double integ[2], period[2];
    for (int ex = 1; ex >= 0; --ex) {
        cf_flow *flow = make_flow(ctx, mesh, 0.1, 1, 1, ex, 0);
        cf_flow_info info;
        CHECK_OK(ctx, cf_flow_step(flow, &info));
        cfi_spin_diagnostics d;
        CHECK_OK(ctx, cfi_spin_willmore_diagnostics(flow, &d));
        integ[ex] = d.integrability_error;
        period[ex] = period_part(ctx, mesh, cf_mesh_positions(mesh), cfi_spin_willmore_last_edges(flow));
        CHECK(d.harmonic_dimension == (ex ? 2 : 0));
        if (ex) CHECK(d.constraint_rank == 4 + 6);
        cf_flow_destroy(&flow);
    }
    fprintf(stderr, "   bob tau 0.1: integrability error with exactness %.3g, without %.3g (ratio %.1f)\n", integ[1],
            integ[0], integ[0] / integ[1]);
    fprintf(stderr, "   bob tau 0.1: period part of e~ with exactness %.3g, without %.3g\n", period[1], period[0]);
    CHECK(integ[0] >= 10.0 * integ[1]);
    CHECK(period[0] >= 10.0 * period[1]);
    /* the default flow lowers W monotonically with triangles kept healthy */
    cf_flow *flow = make_flow(ctx, mesh, 0.5, 1, 1, 1, 0);
    double w0 = cf_flow_energy(flow), w = monotone_steps(ctx, flow, 10);
    cf_stats q;
    CHECK_OK(ctx, cf_quasi_conformal_error(ctx, mesh, cf_mesh_positions(mesh), cf_flow_positions(flow), NULL, &q));
    int32_t nf = cf_mesh_face_count(mesh);
    double *fa = malloc((size_t)nf * sizeof(double)), *fa0 = malloc((size_t)nf * sizeof(double));
    CHECK_OK(ctx, cf_face_areas(ctx, mesh, cf_flow_positions(flow), fa));
    CHECK_OK(ctx, cf_face_areas(ctx, mesh, cf_mesh_positions(mesh), fa0));
    double min_ratio = INFINITY;
    for (int32_t f = 0; f < nf; ++f) min_ratio = fmin(min_ratio, fa[f] / fa0[f]);
    fprintf(stderr, "   bob 10 steps: W/4pi %.4f -> %.4f (Willmore torus: pi/2 = 1.5708), Q mean %.4f max %.4f, min area ratio %.3g\n",
            w0 / (4 * 3.14159265358979323846), w / (4 * 3.14159265358979323846), q.weighted_mean, q.max, min_ratio);
    CHECK_LE(w, 0.6 * w0);
    CHECK_LE(w / (4 * 3.14159265358979323846), 1.9);   /* measured 1.857 */
    CHECK_LE(q.max, 2.0);            /* measured 1.30: no degenerate triangles */
    CHECK(min_ratio > 1e-3);
    free(fa);
    free(fa0);
    cf_flow_destroy(&flow);
    cft_shared_case_close(&shared);
}

/* One step on a bumped cylinder (32 x 12, radius 1, height 1; the bump
 * breaks the rotational symmetry that would make every period vanish by
 * itself); returns the integrability error and the diagnostics. */
static double annulus_step(cf_context *ctx, const cf_mesh *mesh, const double *x, double tau, int ex, int mode,
                           cfi_spin_diagnostics *d)
{
    cf_flow_options o;
    cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o);
    cf_spin_willmore_options *so = cf_flow_options_method(&o);
    so->time_step = tau;
    so->exactness = ex;
    so->boundary_mode = mode;
    so->tolerance = 0.0;
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, x, &o, &flow));
    if (!flow) return NAN;
    CHECK_OK(ctx, cf_flow_step(flow, NULL));
    CHECK_OK(ctx, cfi_spin_willmore_diagnostics(flow, d));
    cf_flow_destroy(&flow);
    return d->integrability_error;
}

static void test_exactness_annulus(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 32, 12, 1.0, 1.0, &mesh));
    if (!mesh) return;
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *x = malloc(3 * (size_t)nv * sizeof(double));
    memcpy(x, cf_mesh_positions(mesh), 3 * (size_t)nv * sizeof(double));
    for (int32_t i = 0; i < nv; ++i) {
        double *p = x + 3 * i, s = 1.0 + 0.3 * (p[0] + 0.5 * p[1] * p[1] + 0.7 * p[2] * p[0]);
        p[0] *= s;
        p[1] *= s;
    }
    double err[2][2];   /* [exactness][tau 0.005, 0.02] */
    const double taus[2] = {0.005, 0.02};
    for (int ex = 1; ex >= 0; --ex)
        for (int k = 0; k < 2; ++k) {
            cfi_spin_diagnostics d;
            err[ex][k] = annulus_step(ctx, mesh, x, taus[k], ex, CF_SPIN_BOUNDARY_FREE, &d);
            CHECK(d.harmonic_dimension == (ex ? 1 : 0));
            /* N^x,y,z, 1 and three columns for the one harmonic form */
            CHECK(d.constraint_rank == (ex ? 7 : 4));
            CHECK_LE(d.constraint_residual, 1e-10);
        }
    fprintf(stderr, "   bumped cylinder, free boundary: integrability error with / without exactness: "
            "tau 0.005 %.3g / %.3g (ratio %.1f), tau 0.02 %.3g / %.3g (ratio %.1f)\n",
            err[1][0], err[0][0], err[0][0] / err[1][0], err[1][1], err[0][1], err[0][1] / err[1][1]);
    CHECK(err[0][0] >= 10.0 * err[1][0]);   /* measured 20.5 */
    /* orders in tau (x4): the period is first order without the constraint
     * (measured x4.3) and second order with it (measured x10.5; the
     * tau-independent local non-closedness keeps it below 16) */
    CHECK_LE(err[0][1] / err[0][0], 6.0);
    CHECK(err[1][1] / err[1][0] >= 8.0);
    /* fixed and prescribed boundaries: no exactness constraint */
    for (int mode = CF_SPIN_BOUNDARY_FIXED; mode <= CF_SPIN_BOUNDARY_CMC; ++mode) {
        cfi_spin_diagnostics d;
        annulus_step(ctx, mesh, x, 0.005, 1, mode, &d);
        CHECK(d.harmonic_dimension == 0);
    }
    free(x);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Fig. 13: Moebius balancing reduces area distortion on spot. */
static void test_mobius_balancing(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "spot_3k.obj", 1)) return;
    cf_context *ctx = shared.ctx;
    cf_mesh *mesh = shared.mesh;
    double spread[2];
    for (int mob = 0; mob <= 1; ++mob) {
        cf_flow *flow = make_flow(ctx, mesh, 0.5, 1, 1, 1, mob);
        CHECK_OK(ctx, cf_flow_run(flow, 10, NULL));
        cf_stats s;
        CHECK_OK(ctx, cf_log_area_distortion(ctx, mesh, cf_mesh_positions(mesh), cf_flow_positions(flow), NULL, &s));
        spread[mob] = s.weighted_std;
        cf_flow_destroy(&flow);
    }
    fprintf(stderr, "   spot 10 steps: std of log area distortion %.3f without, %.3f with Moebius balancing\n",
            spread[0], spread[1]);
    CHECK_LE(spread[1], 0.93 * spread[0]);   /* measured 1.97 vs 2.22 */
    cft_shared_case_close(&shared);
}

/* Harmonic (period) part of the transformed edges e~ (3 ne, interleaved)
 * relative to |e~|, in the *1 inner product of the surface x they were
 * built on: sqrt(sum_c |P_H e~_c|^2 / sum_c |e~_c|^2). */
static double period_part(cf_context *ctx, const cf_mesh *mesh, const double *x, const double *edges)
{
    int32_t ne = cf_mesh_edge_count(mesh), dim = 0;
    CHECK_OK(ctx, cf_harmonic_basis(ctx, mesh, x, &dim, NULL));
    double *h = malloc((size_t)ne * dim * sizeof(double)), *w = malloc((size_t)ne * sizeof(double));
    double *gram = calloc((size_t)dim * dim, sizeof(double)), *r = malloc((size_t)dim * sizeof(double));
    CHECK_OK(ctx, cf_harmonic_basis(ctx, mesh, x, &dim, h));
    CHECK_OK(ctx, cf_cotan_weights(ctx, mesh, x, w));
    for (int a = 0; a < dim; ++a)
        for (int b = 0; b < dim; ++b)
            for (int32_t e = 0; e < ne; ++e) gram[a * dim + b] += w[e] * h[(size_t)a * ne + e] * h[(size_t)b * ne + e];
    double proj = 0.0, total = 0.0;
    for (int c = 0; c < 3; ++c) {
        for (int a = 0; a < dim; ++a) {
            r[a] = 0.0;
            for (int32_t e = 0; e < ne; ++e) r[a] += w[e] * h[(size_t)a * ne + e] * edges[3 * e + c];
        }
        /* |P e|^2 = r^T G^-1 r, by Cholesky of the small Gram matrix */
        double *l = malloc((size_t)dim * dim * sizeof(double)), *y = malloc((size_t)dim * sizeof(double));
        for (int i = 0; i < dim; ++i)
            for (int j = 0; j <= i; ++j) {
                double v = gram[i * dim + j];
                for (int k = 0; k < j; ++k) v -= l[i * dim + k] * l[j * dim + k];
                l[i * dim + j] = i == j ? sqrt(v) : v / l[j * dim + j];
            }
        for (int i = 0; i < dim; ++i) {
            double v = r[i];
            for (int k = 0; k < i; ++k) v -= l[i * dim + k] * y[k];
            y[i] = v / l[i * dim + i];
            proj += y[i] * y[i];
        }
        for (int32_t e = 0; e < ne; ++e) total += w[e] * edges[3 * e + c] * edges[3 * e + c];
        free(l);
        free(y);
    }
    free(h);
    free(w);
    free(gram);
    free(r);
    return sqrt(proj / total);
}

/* Fig. 12, genus 3 (elephant_g3_3k): the exactness constraint removes the
 * periods of the transformed edges (their harmonic part); the total
 * integrability error is dominated by the local error at the thin cone tips
 * and falls only ~2x (docs/spin.md). */
static void test_exactness_genus_three(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "elephant_g3_3k.obj", 0)) return;
    cf_context *ctx = shared.ctx;
    cf_mesh *mesh = shared.mesh;
    CHECK(cf_mesh_genus(mesh) == 3);
    /* mode 0: no exactness, 1: linearised (default), 2: App. C's Z_i */
    double period[3] = {0, 0, 0}, integ[3] = {0, 0, 0};
    for (int mode = 0; mode < 3; ++mode) {
        cf_flow_options o;
        cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o);
        cf_spin_willmore_options *so = cf_flow_options_method(&o);
        so->time_step = 0.01;
        so->tolerance = 0.0;
        so->exactness = mode != 0;
        so->exactness_linearized = mode == 1;
        cf_flow *flow = NULL;
        CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
        if (!flow) break;
        cf_flow_info info;
        CHECK_OK(ctx, cf_flow_step(flow, &info));
        cfi_spin_diagnostics d;
        CHECK_OK(ctx, cfi_spin_willmore_diagnostics(flow, &d));
        CHECK(d.harmonic_dimension == (mode ? 6 : 0));
        CHECK(d.constraint_rank == 4 + (mode == 0 ? 0 : mode == 1 ? 18 : 18));
        integ[mode] = d.integrability_error;
        period[mode] = period_part(ctx, mesh, cf_mesh_positions(mesh), cfi_spin_willmore_last_edges(flow));
        cf_flow_destroy(&flow);
    }
    fprintf(stderr, "   elephant tau 0.01: period part of e~ without exactness %.3g, linearised %.3g (ratio %.1f), "
                    "App. C Z_i %.3g (ratio %.1f); integrability error %.3g / %.3g / %.3g\n",
            period[0], period[1], period[0] / period[1], period[2], period[0] / period[2], integ[0], integ[1], integ[2]);
    CHECK(period[0] >= 10.0 * period[1]);
    CHECK(period[2] >= 3.0 * period[1]); /* the paper's Z_i: only ~3x here (measured 2.8x) */
    CHECK_LE(integ[1], integ[0]);
    /* W falls monotonically for the first 8 steps at tau 0.05 (W/4pi 24.99 ->
     * 12.75; 15.2 with the paper's Z_i) with the smallest angle 18.8 degrees;
     * after about 16 steps (W/4pi 9.1) the cone tips collapse (test blowup) */
    cf_flow *flow = make_flow(ctx, mesh, 0.05, 1, 1, 1, 0);
    double w0 = cf_flow_energy(flow), w = monotone_steps(ctx, flow, 8);
    CHECK_LE(w, 0.55 * w0);
    double min_angle = smallest_angle(mesh, cf_flow_positions(flow));
    fprintf(stderr, "   elephant 8 steps at tau 0.05: W/4pi %.3f -> %.3f, smallest angle %.2f deg\n",
            w0 / (4 * 3.14159265358979323846), w / (4 * 3.14159265358979323846), min_angle);
    CHECK(min_angle > 10.0);
    cf_flow_destroy(&flow);
    /* with regularization 100 (damping the soft modes of the thin cone tips)
     * tau 0.1 lowers W monotonically for 20 steps, 24.99 -> 10.26, smallest
     * angle 11.6 degrees (input 30.0); the default diverges at this tau in
     * step 7 */
    {
        cf_flow_options o;
        cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o);
        cf_spin_willmore_options *so = cf_flow_options_method(&o);
        so->time_step = 0.1;
        so->tolerance = 0.0;
        so->regularization = 100.0;
        so->fairing = 0.0; /* the regularisation alone (with the fairing: W/4pi 9.69, smallest angle 9.7 deg) */
        CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
        w = monotone_steps(ctx, flow, 20);
        double angle = flow ? smallest_angle(mesh, cf_flow_positions(flow)) : 0.0;
        fprintf(stderr, "   elephant 20 steps at tau 0.1, regularization 100: W/4pi %.3f -> %.3f, smallest angle %.2f deg\n",
                w0 / (4 * 3.14159265358979323846), w / (4 * 3.14159265358979323846), angle);
        CHECK_LE(w, 0.45 * w0);
        CHECK(angle > 10.0);
        cf_flow_destroy(&flow);
    }
    cft_shared_case_close(&shared);
}

/* Part of the forms (ne x dim) outside the span of basis (ne x dim), in the
 * *1 inner product of weights: max over forms of |f - P f| / |f|. */
static double outside_span(int32_t ne, int32_t dim, const double *weights, const double *basis, const double *forms)
{
    double gram[4] = {0, 0, 0, 0}, worst = 0.0;
    for (int a = 0; a < dim; ++a)
        for (int b = 0; b < dim; ++b)
            for (int32_t e = 0; e < ne; ++e) gram[2 * a + b] += weights[e] * basis[(size_t)a * ne + e] * basis[(size_t)b * ne + e];
    double det = gram[0] * gram[3] - gram[1] * gram[2];
    for (int g = 0; g < dim; ++g) {
        const double *f = forms + (size_t)g * ne;
        double r[2] = {0, 0}, ff = 0.0;
        for (int a = 0; a < dim; ++a)
            for (int32_t e = 0; e < ne; ++e) r[a] += weights[e] * basis[(size_t)a * ne + e] * f[e];
        for (int32_t e = 0; e < ne; ++e) ff += weights[e] * f[e] * f[e];
        double c0 = (gram[3] * r[0] - gram[1] * r[1]) / det, c1 = (gram[0] * r[1] - gram[2] * r[0]) / det;
        double res = 0.0;
        for (int32_t e = 0; e < ne; ++e) {
            double d = f[e] - c0 * basis[e] - c1 * basis[(size_t)ne + e];
            res += weights[e] * d * d;
        }
        worst = fmax(worst, sqrt(res / ff));
    }
    return worst;
}

static void test_harmonic_update(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.4, 48, 24, &mesh));
    if (!mesh) return;
    int32_t ne = cf_mesh_edge_count(mesh);
    double *start = bumped_torus_positions(mesh);
    double *weights = malloc((size_t)ne * sizeof(double)), *basis = malloc(2 * (size_t)ne * sizeof(double));
    double outside[2] = {0, 0}, w_end[2] = {0, 0};
    for (int update = 0; update < 2; ++update) {
        cf_flow_options o;
        cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o);
        cf_spin_willmore_options *so = cf_flow_options_method(&o);
        so->time_step = 0.1;
        so->tolerance = 0.0;
        so->harmonic_update = update;
        so->exactness_linearized = 0; /* the update serves App. C's Z_i */
        cf_flow *flow = NULL;
        CHECK_OK(ctx, cf_flow_create(ctx, mesh, start, &o, &flow));
        if (!flow) break;
        for (int s = 0; s < 40; ++s) {
            cf_flow_info info;
            CHECK_OK(ctx, cf_flow_step(flow, &info));
        }
        w_end[update] = cf_flow_energy(flow) / (4.0 * 3.14159265358979323846);
        /* the forms were last updated at the start of step 40: compare with
         * the harmonic basis of that surface, one step back */
        int32_t dim = 0, dim2 = 0;
        const double *forms = cfi_spin_willmore_harmonic_forms(flow, &dim);
        CHECK(dim == 2);
        const double *x = cf_flow_positions(flow);
        CHECK_OK(ctx, cf_harmonic_basis(ctx, mesh, x, &dim2, basis));
        CHECK_OK(ctx, cf_cotan_weights(ctx, mesh, x, weights));
        if (forms && dim == 2 && dim2 == 2) outside[update] = outside_span(ne, dim, weights, basis, forms);
        cf_flow_destroy(&flow);
    }
    fprintf(stderr, "   bumped torus, 40 steps at tau 0.1: forms outside the current harmonic span %.3g (input's) vs %.3g "
                    "(updated); W/4pi %.4f / %.4f\n", outside[0], outside[1], w_end[0], w_end[1]);
    CHECK_LE(outside[1], 0.1 * outside[0]);
    /* both lower W from 2.328; the updated constraint is the stricter one
     * (1.979 against 1.973: the stale one lets the flow break exactness) */
    CHECK_LE(w_end[1], 2.0);
    free(start);
    free(weights);
    free(basis);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Genus 1, long run: with the linearised exactness a bumped torus lowers W
 * monotonically for 70 steps at tau 0.1; with App. C's Z_i the periods leak
 * and W turns back up after a minimum near t = 5 (printed, docs/spin.md). */
static void test_torus_long_run(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.4, 48, 24, &mesh));
    if (!mesh) return;
    double *start = bumped_torus_positions(mesh);
    const double four_pi = 4.0 * 3.14159265358979323846;
    double w_first = 0, w_min[2] = {1e300, 1e300}, w_last[2] = {0, 0};
    int rises[2] = {0, 0};
    for (int linearized = 1; linearized >= 0; --linearized) {
        cf_flow_options o;
        cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o);
        cf_spin_willmore_options *so = cf_flow_options_method(&o);
        so->time_step = 0.1;
        so->tolerance = 0.0;
        so->exactness_linearized = linearized;
        cf_flow *flow = NULL;
        CHECK_OK(ctx, cf_flow_create(ctx, mesh, start, &o, &flow));
        if (!flow) break;
        double w = cf_flow_energy(flow);
        w_first = w;
        for (int s = 0; s < 70; ++s) {
            cf_flow_info info;
            cf_status st = cf_flow_step(flow, &info);
            if (linearized) CHECK_OK(ctx, st);
            if (st != CF_OK) break;
            if (info.energy > w) ++rises[linearized];
            w = info.energy;
            w_min[linearized] = fmin(w_min[linearized], w);
        }
        w_last[linearized] = w;
        cf_flow_destroy(&flow);
    }
    fprintf(stderr, "   bumped torus, 70 steps at tau 0.1: W/4pi %.4f -> %.4f (linearised exactness, %d rises); "
                    "App. C Z_i: minimum %.4f, last %.4f (%d rises)\n",
            w_first / four_pi, w_last[1] / four_pi, rises[1], w_min[0] / four_pi, w_last[0] / four_pi, rises[0]);
    CHECK(rises[1] == 0);
    CHECK_LE(w_last[1] / four_pi, 1.96); /* measured 1.940 */
    free(start);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_residuals_and_total_curvature);
    CFT_RUN(test_total_curvature_half_density);
    CFT_RUN(test_exactness_genus_one);
    CFT_RUN(test_exactness_genus_three);
    CFT_RUN(test_exactness_annulus);
    CFT_RUN(test_mobius_balancing);
    CFT_RUN(test_harmonic_update);
    CFT_RUN(test_torus_long_run);
    return cft_finish();
}
