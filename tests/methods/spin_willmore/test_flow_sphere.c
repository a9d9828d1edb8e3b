/*
 * Conformal Willmore flow to the round sphere (Crane, Pinkall, Schroeder
 * 2013, Sec. 6.1, Fig. 1: "flows to a round sphere in only three large,
 * explicit time steps ... the quality of the triangulation is almost
 * perfectly preserved"). Default tau = 0.5 (rho = -2 tau H, NOTES.md).
 *
 * On the built-in bumpy sphere the issue's bounds hold (W/4pi <= 1.01 in 10
 * steps, area-weighted mean Q <= 1.10). On spot_3k W/4pi <= 1.01 holds
 * since the vertex-scale fairing (test_spot_issue13: the paper's step keeps
 * a vertex-scale residue of the cotan curvature that the vertex-based spin
 * transformation realises only slowly); mean Q <= 1.10 holds on neither
 * spot_3k nor bunny_2k, whose conformal maps to the sphere have large area
 * distortion. Those cases assert the measured behaviour with a margin
 * (regression bounds) and print it.
 * test_conformality_reference shows that mean Q <= 1.10 is below what the
 * converged conformalized MCF reaches on the same meshes (1.125 / 1.123),
 * and that the spin flow at small tau matches that reference.
 */
#include "test.h"
#include "spin_test_util.h"

#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/metrics.h"
#include "curvflow/ops.h"
#include "curvflow/spin_willmore.h"

#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

typedef struct result {
    double w0, w;          /* W / 4 pi before and after */
    double q_mean, q_max;  /* quasi-conformal error against the input */
    double sphere_rms;     /* relative RMS distance to the fitted sphere */
    int steps;
} result;

static void run_metric(cf_context *ctx, const cf_mesh *mesh, int steps, int input_metric, result *r)
{
    memset(r, 0, sizeof *r);
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    ((cf_spin_willmore_options *)cf_flow_options_method(&o))->input_metric = input_metric;
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    if (!flow) return;
    r->w0 = cf_flow_energy(flow) / (4.0 * PI);
    cf_flow_info info = {0};
    for (int s = 0; s < steps; ++s) {
        CHECK_OK(ctx, cf_flow_step(flow, &info));
        ++r->steps;
        CHECK(info.energy <= 4.0 * PI * r->w0);
    }
    r->w = info.energy / (4.0 * PI);
    int32_t nv = cf_mesh_vertex_count(mesh);
    cf_stats q;
    CHECK_OK(ctx, cf_quasi_conformal_error(ctx, mesh, cf_mesh_positions(mesh), cf_flow_positions(flow), NULL, &q));
    r->q_mean = q.weighted_mean;
    r->q_max = q.max;
    double c[3], rad;
    CHECK_OK(ctx, cf_fit_sphere(ctx, nv, cf_flow_positions(flow), c, &rad, NULL, &r->sphere_rms));
    /* the common layer reports the area drift: normalize keeps the area */
    CHECK_NEAR(info.area_drift, 0.0, 0.0, 1e-9);
    cf_flow_destroy(&flow);
}

static void run(cf_context *ctx, const cf_mesh *mesh, int steps, result *r) { run_metric(ctx, mesh, steps, 1, r); }

/* Issue bounds on the built-in bumpy sphere (the demo's mesh). */
static void test_bumpy_sphere(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 4, 0.25, 1u, &mesh));
    result r;
    run(ctx, mesh, 10, &r);
    fprintf(stderr, "   bumpy sphere: W/4pi %.4f -> %.5f, Q mean %.4f max %.4f, sphere rms %.2e\n", r.w0, r.w, r.q_mean,
            r.q_max, r.sphere_rms);
    CHECK_LE(r.w, 1.01);
    CHECK_LE(r.q_mean, 1.10);
    CHECK_LE(r.sphere_rms, 1e-3);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void shared_case(const char *name, double w_bound, double q_bound, double qmax_bound, double rms_bound)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, name, 0)) return;
    cf_context *ctx = shared.ctx;
    cf_mesh *mesh = shared.mesh;
    result r, rc;
    run(ctx, mesh, 10, &r);
    run_metric(ctx, mesh, 10, 0, &rc);
    fprintf(stderr, "   %s: W/4pi %.4f -> %.5f, Q mean %.4f max %.4f, sphere rms %.2e (current metric: W/4pi %.5f, "
                    "Q mean %.4f max %.4f)\n",
            name, r.w0, r.w, r.q_mean, r.q_max, r.sphere_rms, rc.w, rc.q_mean, rc.q_max);
    CHECK_LE(r.w, w_bound);
    CHECK_LE(r.q_mean, q_bound);
    CHECK_LE(r.q_max, qmax_bound);
    CHECK_LE(r.sphere_rms, rms_bound);
    /* recovering positions in the input's metric is no worse than in the
     * current one */
    CHECK_LE(r.q_mean, rc.q_mean);
    CHECK_LE(r.q_max, rc.q_max);
    cft_shared_case_close(&shared);
}

/* Measured at tau = 0.5 with the default vertex-scale fairing (input
 * metric): spot W/4pi 10.65 -> 1.0017, Q mean 1.149, max 1.58; bunny
 * 1.025, Q mean 1.172, max 2.75 (the paper's step: spot 1.047 / 1.163 /
 * 1.58, bunny 1.195 / 1.200 / 3.65). Bounds = measured + ~2 %. */
static void test_spot(void) { shared_case("spot_3k.obj", 1.02, 1.17, 1.62, 3e-3); }
static void test_bunny(void) { shared_case("bunny_2k.obj", 1.05, 1.20, 2.85, 4e-3); }

/* Mean Q of the fully converged conformalized mean curvature flow (Kazhdan,
 * Solomon, Ben-Chen 2012, area rescaled every step), the usual conformal map
 * to the sphere in libigl-style tools: an independent reference for how
 * conformal a vertex-sampled map of this triangulation onto the round sphere
 * can be. Returns its W/4pi in *w. */
static double reference_q(cf_context *ctx, const cf_mesh *mesh, double *w, double *positions)
{
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_CONFORMAL_MCF, &o));
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "rescale", "true"));
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    if (!flow) return 0.0;
    CHECK_OK(ctx, cf_flow_run(flow, 400, NULL));
    cf_stats q;
    CHECK_OK(ctx, cf_quasi_conformal_error(ctx, mesh, cf_mesh_positions(mesh), cf_flow_positions(flow), NULL, &q));
    double wn = 0.0;
    CHECK_OK(ctx, cf_willmore_energy(ctx, mesh, cf_flow_positions(flow), &wn));
    *w = wn / (4.0 * PI);
    if (positions) memcpy(positions, cf_flow_positions(flow), 3 * (size_t)cf_mesh_vertex_count(mesh) * sizeof *positions);
    cf_flow_destroy(&flow);
    return q.weighted_mean;
}

/* Mean Q against the input of sphere-like positions y (centred on their
 * fitted sphere, unit radius) after the inversion about p = z / |z|^2,
 * y -> p + (y - p) / |y - p|^2: |p| > 1 for |z| < 1, so the sphere goes to a sphere and the map
 * stays conformal; z = 0 is the identity. Any other normalisation of a
 * conformal map of a genus-0 surface onto the sphere differs from this one
 * by a Moebius transformation, up to a similarity, which Q does not see. */
static double inverted_q(cf_context *ctx, const cf_mesh *mesh, const double *y, const double z[3], double *out)
{
    int32_t nv = cf_mesh_vertex_count(mesh);
    double r2 = z[0] * z[0] + z[1] * z[1] + z[2] * z[2];
    if (!(r2 < 0.98 * 0.98)) return INFINITY;
    for (int32_t i = 0; i < nv; ++i) {
        double d[3], dd = 0.0;
        for (int c = 0; c < 3; ++c) {
            double p = r2 > 0.0 ? z[c] / r2 : 0.0;
            d[c] = y[3 * (size_t)i + c] - p;
            dd += d[c] * d[c];
        }
        for (int c = 0; c < 3; ++c) out[3 * (size_t)i + c] = r2 > 0.0 ? z[c] / r2 + d[c] / dd : y[3 * (size_t)i + c];
    }
    cf_stats q;
    CHECK_OK(ctx, cf_quasi_conformal_error(ctx, mesh, cf_mesh_positions(mesh), out, NULL, &q));
    return q.weighted_mean;
}

/* Compass search for a lower inverted_q from z (updated) whose value is
 * *value (updated): steps of 0.05 halved down to 1e-4. */
static void compass_refine(cf_context *ctx, const cf_mesh *mesh, const double *y, double z[3], double *value,
                           double *out)
{
    for (double step = 0.05; step > 1e-4;) {
        int improved = 0;
        for (int c = 0; c < 6; ++c) {
            double t[3] = {z[0], z[1], z[2]};
            t[c / 2] += c % 2 ? -step : step;
            double v = inverted_q(ctx, mesh, y, t, out);
            if (v < *value) {
                *value = v;
                memcpy(z, t, sizeof t);
                improved = 1;
            }
        }
        if (!improved) step *= 0.5;
    }
}

/* The least mean Q over the Moebius normalisations of the sphere map
 * `positions` (normalised to its fitted sphere): a grid of inversions (12
 * radii of z x 64 directions), then a compass search from each of the
 * MOEBIUS_STARTS best grid points (the landscape has several local minima).
 * Returns the least, with its z. */
#define MOEBIUS_STARTS 8
static double moebius_least_q(cf_context *ctx, const cf_mesh *mesh, const double *positions, double z_best[3])
{
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *y = malloc(3 * (size_t)nv * sizeof *y), *out = malloc(3 * (size_t)nv * sizeof *out);
    double centre[3] = {0.0, 0.0, 0.0}, radius = 1.0;
    CHECK_OK(ctx, cf_fit_sphere(ctx, nv, positions, centre, &radius, NULL, NULL));
    for (int32_t i = 0; i < nv; ++i)
        for (int c = 0; c < 3; ++c) y[3 * (size_t)i + c] = (positions[3 * (size_t)i + c] - centre[c]) / radius;
    /* the best grid points, sorted by value (z = 0, the identity, included) */
    double start_z[MOEBIUS_STARTS][3] = {{0.0, 0.0, 0.0}}, start_v[MOEBIUS_STARTS];
    for (int k = 0; k < MOEBIUS_STARTS; ++k) start_v[k] = INFINITY;
    start_v[0] = inverted_q(ctx, mesh, y, start_z[0], out);
    const int directions = 64; /* a Fibonacci sphere */
    for (int k = 1; k <= 12; ++k)
        for (int d = 0; d < directions; ++d) {
            double h = 1.0 - (2.0 * d + 1.0) / directions, ring = sqrt(1.0 - h * h), phi = d * PI * (3.0 - sqrt(5.0));
            double z[3] = {0.075 * k * ring * cos(phi), 0.075 * k * ring * sin(phi), 0.075 * k * h};
            double v = inverted_q(ctx, mesh, y, z, out);
            int at = MOEBIUS_STARTS;
            while (at > 0 && v < start_v[at - 1]) --at;
            if (at == MOEBIUS_STARTS) continue;
            memmove(start_v + at + 1, start_v + at, (MOEBIUS_STARTS - 1 - at) * sizeof start_v[0]);
            memmove(start_z + at + 1, start_z + at, (MOEBIUS_STARTS - 1 - at) * sizeof start_z[0]);
            start_v[at] = v;
            memcpy(start_z[at], z, sizeof z);
        }
    double best = INFINITY;
    z_best[0] = z_best[1] = z_best[2] = 0.0;
    for (int k = 0; k < MOEBIUS_STARTS && isfinite(start_v[k]); ++k) {
        compass_refine(ctx, mesh, y, start_z[k], &start_v[k], out);
        if (start_v[k] < best) {
            best = start_v[k];
            memcpy(z_best, start_z[k], sizeof start_z[k]);
        }
    }
    free(y);
    free(out);
    return best;
}

/* Spin flow with time step tau for `steps` steps: mean Q against the input. */
static double spin_q(cf_context *ctx, const cf_mesh *mesh, double tau, int steps, double *w)
{
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    ((cf_spin_willmore_options *)cf_flow_options_method(&o))->time_step = tau;
    ((cf_spin_willmore_options *)cf_flow_options_method(&o))->tolerance = 0.0;
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    if (!flow) return 0.0;
    CHECK_OK(ctx, cf_flow_run(flow, steps, NULL));
    *w = cf_flow_energy(flow) / (4.0 * PI);
    cf_stats q;
    CHECK_OK(ctx, cf_quasi_conformal_error(ctx, mesh, cf_mesh_positions(mesh), cf_flow_positions(flow), NULL, &q));
    cf_flow_destroy(&flow);
    return q.weighted_mean;
}

/* Fig. 1's "quality of the triangulation almost perfectly preserved",
 * measured against the best a conformal map of the same triangulation onto
 * the sphere reaches. The converged conformalized MCF has mean Q 1.125 on
 * spot_3k and 1.123 on bunny_2k, above the issue's bound of 1.10: that bound
 * is below what a cotan-conformal map of these meshes achieves, so no
 * conformal flow can meet it at this resolution (the built-in bumpy sphere,
 * whose conformal factor varies less, meets it). The spin flow's own
 * distortion is first order in tau (Fig. 16, test `constraints`) and at
 * small tau it matches the reference: tau = 0.05 for 100 steps gives 1.125
 * on spot and 1.144 on bunny. At the default tau = 0.5, 10 steps give 1.163
 * and 1.200 (the price of reaching the sphere in 10 steps). */
static void reference_case(const char *name, double small_tau_ratio_bound)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, name, 0)) return;
    cf_context *ctx = shared.ctx;
    cf_mesh *mesh = shared.mesh;
    double w_ref = 0.0, w_small = 0.0, w_default = 0.0;
    double q_ref = reference_q(ctx, mesh, &w_ref, NULL);
    double q_small = spin_q(ctx, mesh, 0.05, 100, &w_small);
    double q_default = spin_q(ctx, mesh, 0.5, 10, &w_default);
    fprintf(stderr,
            "   %s: converged conformalized MCF Q mean %.4f (W/4pi %.4f); spin tau 0.05 x 100: %.4f (W/4pi %.4f), "
            "tau 0.5 x 10: %.4f (W/4pi %.4f); (Q - 1) ratios %.2f, %.2f\n",
            name, q_ref, w_ref, q_small, w_small, q_default, w_default, (q_small - 1.0) / (q_ref - 1.0),
            (q_default - 1.0) / (q_ref - 1.0));
    CHECK_LE(w_ref, 1.0);      /* the reference did reach the sphere */
    CHECK(q_ref > 1.11);       /* ... and its floor is above the issue's 1.10 */
    CHECK_LE(q_small - 1.0, small_tau_ratio_bound * (q_ref - 1.0));
    CHECK_LE(q_small, q_default); /* distortion grows with tau */
    cft_shared_case_close(&shared);
}

/* Fig. 1: "flows to a round sphere in only three large, explicit time
 * steps ... the quality of the triangulation is almost perfectly
 * preserved". After three default steps (tau 0.5) spot_3k is a sphere to
 * 2.6 % RMS of its radius (the input: 29 %), W/4pi 10.65 -> 1.15, mean Q
 * 1.15, and the smallest angle of the triangulation is kept (9.8 deg, input
 * 10.2). */
static void test_three_steps(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "spot_3k.obj", 0)) return;
    cf_context *ctx = shared.ctx;
    cf_mesh *mesh = shared.mesh;
    int32_t nv = cf_mesh_vertex_count(mesh);
    double c[3], rad, rms0 = 0.0, rms = 0.0;
    CHECK_OK(ctx, cf_fit_sphere(ctx, nv, cf_mesh_positions(mesh), c, &rad, NULL, &rms0));
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    if (!flow) {
        cft_shared_case_close(&shared);
        return;
    }
    double w0 = cf_flow_energy(flow) / (4.0 * PI);
    CHECK_OK(ctx, cf_flow_run(flow, 3, NULL));
    double w = cf_flow_energy(flow) / (4.0 * PI);
    const double *x = cf_flow_positions(flow);
    CHECK_OK(ctx, cf_fit_sphere(ctx, nv, x, c, &rad, NULL, &rms));
    cf_stats q;
    CHECK_OK(ctx, cf_quasi_conformal_error(ctx, mesh, cf_mesh_positions(mesh), x, NULL, &q));
    double a0 = smallest_angle(mesh, cf_mesh_positions(mesh)), a = smallest_angle(mesh, x);
    fprintf(stderr,
            "   spot_3k, 3 steps: sphere RMS %.2e (input %.2e), W/4pi %.4f -> %.4f, Q mean %.4f max %.4f, smallest "
            "angle %.2f deg (input %.2f)\n",
            rms, rms0, w0, w, q.weighted_mean, q.max, a, a0);
    CHECK(rms0 > 0.25);
    CHECK_LE(rms, 0.03);
    CHECK_LE(w, 1.2);
    CHECK_LE(q.weighted_mean, 1.2);
    CHECK(a >= 0.9 * a0); /* degrees: 9.8 after, 10.2 before */
    cf_flow_destroy(&flow);
    cft_shared_case_close(&shared);
}

/* Issue 13 on spot_3k: W/4pi <= 1.01 within 20 default steps, with mean Q
 * within 5 % of the converged conformalized MCF map of the same
 * triangulation. The paper's step alone (fairing 0) does not get there: its
 * tail is the vertex-scale part of the cotan curvature, which the
 * vertex-based spin transformation sees only through face sums (1.027 after
 * 20 steps); the default vertex-scale fairing removes it (measured: 1.0171
 * after 3 steps, below 1.01 from step 4, 1.0000 after 20, mean Q 1.149 =
 * 1.021 x the reference's 1.125; docs/spin.md, "Vertex-scale fairing"). */
static void test_spot_issue13(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "spot_3k.obj", 0)) return;
    cf_context *ctx = shared.ctx;
    cf_mesh *mesh = shared.mesh;
    double w_ref = 0.0, q_ref = reference_q(ctx, mesh, &w_ref, NULL);
    for (int faired = 1; faired >= 0; --faired) {
        cf_flow_options o;
        CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
        if (!faired) ((cf_spin_willmore_options *)cf_flow_options_method(&o))->fairing = 0.0;
        cf_flow *flow = NULL;
        CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
        if (!flow) break;
        int reached = 0, steps = 0;
        double w = cf_flow_energy(flow) / (4.0 * PI);
        while (steps < 20 && !cf_flow_converged(flow)) {
            CHECK_OK(ctx, cf_flow_step(flow, NULL));
            ++steps;
            w = cf_flow_energy(flow) / (4.0 * PI);
            if (!reached && w <= 1.01) reached = steps;
        }
        cf_stats q;
        CHECK_OK(ctx, cf_quasi_conformal_error(ctx, mesh, cf_mesh_positions(mesh), cf_flow_positions(flow), NULL, &q));
        fprintf(stderr, "   spot_3k, %s: W/4pi %.4f after %d steps (<= 1.01 from step %d), mean Q %.4f (%.3f x the "
                        "conformalized MCF reference %.4f)\n",
                faired ? "default" : "fairing 0 (the paper's step)", w, steps, reached, q.weighted_mean,
                q.weighted_mean / q_ref, q_ref);
        if (faired) {
            CHECK(reached > 0 && reached <= 20);
            CHECK_LE(q.weighted_mean, 1.05 * q_ref);
        } else {
            CHECK(reached == 0); /* 1.027 after 20 steps */
        }
        cf_flow_destroy(&flow);
    }
    cft_shared_case_close(&shared);
}

static void test_conformality_reference(void)
{
    reference_case("spot_3k.obj", 1.05);
    reference_case("bunny_2k.obj", 1.25);
}

/* Issue 13's mean Q <= 1.5 (10 default steps) on cactus_620 is below the
 * conformal floor of that triangulation: the converged conformalized MCF
 * (400 steps, W/4pi 0.966) has mean Q 1.525 (800 steps: 1.528, 1600:
 * 1.539), and the spin flow's 1.580 after 10 default steps (W/4pi 6.48 ->
 * 1.02) is within 5 % of it, the criterion the issue sets for spot_3k.
 * No other normalisation of that map gets under 1.5 either: the least mean
 * Q found over the Moebius transformations is 1.5220 (measured). The
 * landscape has at least two local minima, 1.5227 and a narrow 1.5220 at a
 * strong inversion (|z| 0.69); a denser grid refined from its 24 best
 * points, and a Nelder-Mead search outside the suite, found only the
 * first. */
static void test_cactus_reference(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "cactus_620.obj", 0)) return;
    cf_context *ctx = shared.ctx;
    cf_mesh *mesh = shared.mesh;
    double w_ref = 0.0, w_default = 0.0, w0 = 0.0;
    CHECK_OK(ctx, cf_willmore_energy(ctx, mesh, cf_mesh_positions(mesh), &w0));
    w0 /= 4.0 * PI;
    double *sphere = malloc(3 * (size_t)cf_mesh_vertex_count(mesh) * sizeof *sphere), z[3];
    double q_ref = reference_q(ctx, mesh, &w_ref, sphere);
    double q_moebius = moebius_least_q(ctx, mesh, sphere, z);
    free(sphere);
    double q_default = spin_q(ctx, mesh, 0.5, 10, &w_default);
    fprintf(stderr,
            "   cactus_620: converged conformalized MCF Q mean %.4f (W/4pi %.4f), least over its Moebius "
            "normalisations %.4f (inversion z = %.3f %.3f %.3f); spin, 10 default steps: Q mean %.4f (%.3f x the "
            "reference), W/4pi %.4f -> %.4f\n",
            q_ref, w_ref, q_moebius, z[0], z[1], z[2], q_default, q_default / q_ref, w0, w_default);
    CHECK_LE(w_ref, 1.0);             /* the reference did reach the sphere */
    CHECK(q_ref > 1.5);               /* its floor is above the issue's absolute bound */
    CHECK(q_moebius > 1.5);           /* in every normalisation */
    CHECK_LE(q_moebius, q_ref - 1e-3); /* the search found a better one than cMCF's own */
    CHECK_LE(q_default, 1.05 * q_ref); /* within 5 % of it */
    CHECK_LE(w_default, 0.5 * w0);
    cft_shared_case_close(&shared);
}

/* Parameters by name through the common interface (curvflow flow --param). */
static void test_params_by_name(void)
{
    cf_context *ctx = cft_context();
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    const cf_spin_willmore_options *so = cf_flow_options_method_const(&o);
    CHECK_NEAR(so->time_step, 0.5, 0, 0);
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "sigma", "0.1"));
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "filter_k", "3"));
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "mobius", "yes"));
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "boundary", "fixed"));
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "time_step", "0.25"));
    CHECK_NEAR(so->sigma, 0.1, 0, 0);
    CHECK(so->filter_k == 3 && so->mobius == 1 && so->boundary_mode == CF_SPIN_BOUNDARY_FIXED);
    CHECK_NEAR(so->time_step, 0.25, 0, 0);
    CHECK_STATUS(cf_flow_options_set(ctx, &o, "filter_k", "4"), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_flow_options_set(ctx, &o, "no_such", "1"), CF_ERR_INVALID_ARG);
    /* boundary=fixed on a closed mesh is refused with a message */
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &mesh));
    cf_flow *flow = NULL;
    CHECK_STATUS(cf_flow_create(ctx, mesh, NULL, &o, &flow), CF_ERR_BAD_MESH);
    CHECK(strstr(cf_context_message(ctx), "boundary") != NULL);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Allocation failures in create fail cleanly; the step allocates nothing of
 * its own (counted through the context allocator). */
static void test_allocation(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 2, 0.2, 3u, &mesh));
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "sigma", "0.05"));
    size_t base = cf_context_bytes_in_use(ctx);
    cf_flow *flow = NULL;
    int ok = 0;
    for (int64_t n = 1; n < 400 && !ok; ++n) {
        cf_context_fail_allocation(ctx, n, 0);
        cf_status st = cf_flow_create(ctx, mesh, NULL, &o, &flow);
        cf_context_fail_allocation(ctx, 0, 0);
        CHECK(st == CF_OK || st == CF_ERR_NOMEM);
        if (st == CF_OK) {
            ok = 1;
            break;
        }
        CHECK(flow == NULL);
        CHECK(cf_context_bytes_in_use(ctx) == base);
    }
    CHECK(ok);
    if (flow) {
        CHECK_OK(ctx, cf_flow_step(flow, NULL));   /* first step: solver workspaces */
        int64_t before = cf_context_allocation_count(ctx);
        CHECK_OK(ctx, cf_flow_step(flow, NULL));
        int64_t after = cf_context_allocation_count(ctx);
        fprintf(stderr, "   allocations during the second step: %lld\n", (long long)(after - before));
        CHECK(after == before);
        cf_flow_destroy(&flow);
    }
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_allocation);
    CFT_RUN(test_bumpy_sphere);
    CFT_RUN(test_spot);
    CFT_RUN(test_bunny);
    CFT_RUN(test_three_steps);
    CFT_RUN(test_conformality_reference);
    CFT_RUN(test_spot_issue13);
    CFT_RUN(test_cactus_reference);
    CFT_RUN(test_params_by_name);
    return cft_finish();
}
