/*
 * Issue 13's W target (W after 10 steps <= W0/2) on bob_5k (genus 1), as a
 * measurement of why it is not met: the flow keeps the conformal class
 * (exactness constraints, period corrections), so it tends to the least W of
 * the input's class, not to the least W of all tori. After 10 default
 * steps it is on a plateau: full steps (no halving), periods below the
 * tolerance, W/4pi 1.8510 after 10 steps and 1.8449 after 30 (0.3 % in 20
 * steps, the rate still falling), against a target of 1.7123. The plateau
 * is measured against the class itself (cf_conformal_class_compute): bob
 * is conformally the rectangular torus of modulus 1.7957 i, the flow keeps
 * it to a distance of 0.006, and W stays within 0.5 % of the homogeneous
 * torus of that class, W/4pi = (pi / 4) (b + 1 / b) = 1.848 (the circular
 * torus of revolution of the class), 8 % above the target.
 *
 * Issue 13's Fig. 18 target on blade_slivers_8k (W monotone for 20 fixed
 * steps at tau 0.9), as a measurement of why it is not met: blade is an
 * annulus (free boundary) that is conformally a cylinder of length 39.45 /
 * 2 pi = 6.3 circumferences (the Dirichlet energy D of the harmonic
 * function 0 on one loop, 1 on the other: ln(R/r) = 2 pi / D for the
 * conformally equivalent flat annulus r < |z| < R; checked on a round
 * cylinder, where it is height / radius). Every surface of W = 0 in that
 * class crowds area by a factor beyond double precision: the flat annulus
 * by (R/r)^2 = e^78.9, the catenoid piece by cosh^2(ln(R/r)/2) = e^38.1,
 * against 1/eps = e^36.0. A step of tau 0.9 heads for such a surface: two
 * of them spread the log area ratio over 28 (-20.4 .. +7.6, W/4pi 424.1 ->
 * 14.2 -> 10.84) and the third blows up. Skips without ../shared.
 *
 * Also measured here: the option keep_class (the class held exactly), and
 * why the tangential relaxation stays off on genus > 0 although it meets
 * elk's two targets (the double torus' mean Q).
 */
#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/metrics.h"
#include "curvflow/spin_willmore.h"
#include "spin_test_util.h"

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ln(R/r) of the flat annulus r < |z| < R conformally equivalent to the
 * annulus `mesh` (two boundary loops): 2 pi / D, D = sum_e w_e (u_j - u_i)^2
 * the Dirichlet energy of the discrete harmonic u (0 on loop 0, 1 on loop
 * 1) in the cotan metric (cf_edge_poisson's weights). NaN on failure. */
static double annulus_log_radius_ratio(cf_context *ctx, const cf_mesh *mesh)
{
    int32_t nv = cf_mesh_vertex_count(mesh), ne = cf_mesh_edge_count(mesh);
    CHECK(cf_mesh_boundary_loop_count(mesh) == 2);
    if (cf_mesh_boundary_loop_count(mesh) != 2) return NAN;
    const int32_t *offsets = cf_mesh_boundary_loop_offsets(mesh), *loops = cf_mesh_boundary_loop_vertices(mesh);
    const int32_t *ev = cf_mesh_edge_vertices(mesh);
    double *fixed = calloc(3 * (size_t)nv, sizeof(double)), *edges = calloc(3 * (size_t)ne, sizeof(double));
    double *u = calloc(3 * (size_t)nv, sizeof(double));
    cf_edge_poisson *poisson = NULL;
    double ratio = NAN;
    if (fixed && edges && u) {
        for (int32_t k = offsets[1]; k < offsets[2]; ++k) fixed[3 * loops[k]] = 1.0;
        CHECK_OK(ctx, cf_edge_poisson_create(ctx, mesh, NULL, offsets[2], loops, &poisson));
    }
    if (poisson) {
        /* edges 0: the least-squares fit is the harmonic extension of the fixed values */
        CHECK_OK(ctx, cf_edge_poisson_solve(poisson, edges, fixed, u, NULL));
        double dirichlet = 0.0;
        for (int32_t e = 0; e < ne; ++e) {
            double d = u[3 * ev[2 * e + 1]] - u[3 * ev[2 * e]];
            dirichlet += cf_edge_poisson_weight(poisson, e) * d * d;
        }
        ratio = 2.0 * 3.14159265358979323846 / dirichlet;
    }
    cf_edge_poisson_destroy(&poisson);
    free(fixed);
    free(edges);
    free(u);
    return ratio;
}

/* max - min over faces of log(area / input area) */
static double log_area_spread(cf_context *ctx, const cf_mesh *mesh, const double *x)
{
    int32_t nf = cf_mesh_face_count(mesh);
    double *a0 = malloc((size_t)nf * sizeof(double)), *a = malloc((size_t)nf * sizeof(double));
    double lo = INFINITY, hi = -INFINITY;
    if (a0 && a) {
        CHECK_OK(ctx, cf_face_areas(ctx, mesh, cf_mesh_positions(mesh), a0));
        CHECK_OK(ctx, cf_face_areas(ctx, mesh, x, a));
        for (int32_t f = 0; f < nf; ++f) {
            double l = log(a[f] / a0[f]);
            lo = fmin(lo, l);
            hi = fmax(hi, l);
        }
    }
    free(a0);
    free(a);
    return hi - lo;
}

static void test_cylinder_modulus(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *cylinder = NULL;
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 64, 32, 1.0, 2.0, &cylinder));
    if (cylinder) {
        double ratio = annulus_log_radius_ratio(ctx, cylinder);
        fprintf(stderr, "   cylinder r 1, h 2: ln(R/r) %.4f (exact 2)\n", ratio);
        CHECK_NEAR(ratio, 2.0, 0.0, 2e-3); /* a round cylinder is the flat annulus of ln(R/r) = h / r */
    }
    cf_mesh_destroy(&cylinder);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_blade_class_beyond_double_precision(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "blade_slivers_8k.obj", 0)) return;
    cf_context *ctx = shared.ctx;
    const cf_mesh *mesh = shared.mesh;
    double ratio = annulus_log_radius_ratio(ctx, mesh);
    double flat = 2.0 * ratio, catenoid = 2.0 * log(cosh(0.5 * ratio)), beyond = -log(DBL_EPSILON);
    fprintf(stderr, "   blade: ln(R/r) %.3f; log area ratio of W = 0: flat %.1f, catenoid %.1f; -ln eps %.1f\n", ratio,
            flat, catenoid, beyond);
    CHECK_NEAR(ratio, 39.45, 0.0, 0.01); /* measured 39.4536 */
    CHECK(catenoid > beyond);
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    cf_spin_willmore_options *spin = cf_flow_options_method_as(&o, CF_FLOW_SPIN_WILLMORE);
    if (spin) {
        spin->adaptive = 0; /* Fig. 18's fixed step, nothing else changed */
        spin->time_step = 0.9;
    }
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    if (flow) {
        double w[3] = {cf_flow_energy(flow), 0.0, 0.0};
        for (int k = 1; k <= 2; ++k) {
            CHECK_OK(ctx, cf_flow_step(flow, NULL));
            w[k] = cf_flow_energy(flow);
        }
        double spread = log_area_spread(ctx, mesh, cf_flow_positions(flow));
        const double four_pi = 4.0 * 3.14159265358979323846;
        fprintf(stderr, "   blade, tau 0.9: W/4pi %.2f -> %.2f -> %.2f, log area spread %.1f\n", w[0] / four_pi,
                w[1] / four_pi, w[2] / four_pi, spread);
        CHECK(w[1] < w[0] && w[2] < w[1]); /* measured 424.1 -> 14.2 -> 10.84 */
        CHECK(spread > 25.0);                 /* measured 28.0 after two steps */
        cf_status st = cf_flow_step(flow, NULL); /* the third: energy grew more than 10x */
        CHECK(st == CF_ERR_NUMERICAL);
        cf_context_clear_error(ctx);
        cf_flow_destroy(&flow);
    }
    cft_shared_case_close(&shared);
}

/* the modulus (imaginary part; the real part is checked near 0: bob's
 * class is rectangular) of the flow's positions after steps 10 and 30 */
typedef struct bob_classes {
    double modulus[2], distance[2], real_part;
} bob_classes;

static void record_class(cf_context *ctx, const cf_flow *flow, int step, void *user)
{
    bob_classes *c = user;
    int k = step == 10 ? 0 : step == 30 ? 1 : -1;
    if (k < 0) return;
    const cf_mesh *mesh = cf_flow_mesh(flow);
    cf_conformal_class cls;
    CHECK_OK(ctx, cf_conformal_class_compute(ctx, mesh, cf_flow_positions(flow), NULL, &cls));
    CHECK_OK(ctx, cf_conformal_class_distance(ctx, mesh, cf_mesh_positions(mesh), cf_flow_positions(flow), NULL, NULL,
                                              &c->distance[k]));
    c->modulus[k] = cls.modulus[1];
    c->real_part = fmax(c->real_part, fabs(cls.modulus[0]));
}

/* W/4pi of the homogeneous torus of the rectangular class i b: the
 * stereographic image of S^1(r) x S^1(s) in S^3 with s / r = b (a torus of
 * revolution with circular profile), W = pi^2 (b + 1 / b) */
static double homogeneous_torus_w(double b) { return 0.25 * 3.14159265358979323846 * (b + 1.0 / b); }

static void test_bob_plateau(void)
{
    cft_shared_case shared;
    if (!cft_shared_case_open(&shared, "bob_5k.obj", 0)) return;
    cf_flow_options o;
    CHECK_OK(shared.ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    spin_run r = {0};
    double w[31];
    cf_conformal_class input;
    CHECK_OK(shared.ctx, cf_conformal_class_compute(shared.ctx, shared.mesh, cf_mesh_positions(shared.mesh), NULL, &input));
    bob_classes c = {{0, 0}, {-1, -1}, fabs(input.modulus[0])};
    if (spin_run_steps_hooked(shared.ctx, shared.mesh, &o, 30, &r, w, record_class, &c)) {
        CHECK(r.steps == 30);
        fprintf(stderr,
                "   bob_5k: W/4pi %.4f -> %.4f (10 steps) -> %.4f (30 steps), smallest time step %g; target W0/2 = "
                "%.4f\n",
                r.w0, w[10], r.w, r.smallest_step, 0.5 * r.w0);
        fprintf(stderr,
                "   bob_5k: modulus %.4f i -> %.4f i (10 steps, class distance %.2g) -> %.4f i (30 steps, %.2g); the "
                "homogeneous torus of each class: W/4pi %.4f, %.4f, %.4f\n",
                input.modulus[1], c.modulus[0], c.distance[0], c.modulus[1], c.distance[1],
                homogeneous_torus_w(input.modulus[1]), homogeneous_torus_w(c.modulus[0]),
                homogeneous_torus_w(c.modulus[1]));
        CHECK_LE(r.worst_rise, 0.0);           /* still descending */
        CHECK(w[10] > 0.5 * r.w0);             /* the target is not met ... */
        CHECK(r.w > 0.5 * r.w0);
        CHECK_LE(w[10] - r.w, 0.005 * w[10]);  /* ... on a plateau, not a stall: */
        CHECK_NEAR(r.smallest_step, 0.5, 0, 0); /* full steps throughout, from step 1 */
        /* The plateau is the homogeneous torus of bob's own conformal class:
         * the class is kept (measured distance 0.0062 after 10 steps,
         * 0.0047 after 30), rectangular, and W is within 0.5 % of that
         * torus' (measured -0.15 % and -0.40 %; for b > sqrt 3 it is not
         * the least W of its class, and the flow goes slightly below it).
         * The target W0/2 lies 7 % below it: it would take the class of
         * b = 1.51, a different surface. */
        CHECK_LE(c.real_part, 1e-3);
        CHECK_LE(c.distance[0], 0.01);
        CHECK_LE(c.distance[1], 0.01);
        CHECK_NEAR(w[10], homogeneous_torus_w(c.modulus[0]), 0.005, 0);
        CHECK_NEAR(r.w, homogeneous_torus_w(c.modulus[1]), 0.005, 0);
        CHECK_LE(0.5 * r.w0, 0.95 * homogeneous_torus_w(input.modulus[1])); /* measured 0.927 */
    }
    cft_shared_case_close(&shared);
}

/* Option keep_class: the run with it and without, 10 steps; the class
 * distance of the result from the input's, W/4pi, mean Q. */
typedef struct class_run {
    spin_run run;
    double distance;    /* of the classes (cf_conformal_class_distance) */
    double gram_change; /* max |G - G0| / max |G0| of the Gram matrices themselves */
} class_run;

static int run_keep_class_relaxed(cf_context *ctx, const cf_mesh *mesh, int keep, const char *relaxation,
                                  class_run *out)
{
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    const char *mode[3] = {"0", "1", "2"};
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "keep_class", mode[keep]));
    if (relaxation) CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "relaxation", relaxation));
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    if (!flow) return 0;
    const double four_pi = 4.0 * 3.14159265358979323846;
    spin_run *r = &out->run;
    memset(r, 0, sizeof *r);
    r->w0 = r->w = cf_flow_energy(flow) / four_pi;
    r->worst_rise = -INFINITY;
    while (r->steps < 10 && !cf_flow_converged(flow)) {
        cf_flow_info info;
        CHECK_OK(ctx, cf_flow_step(flow, &info));
        double w = cf_flow_energy(flow) / four_pi;
        r->worst_rise = fmax(r->worst_rise, w - r->w);
        r->w = w;
        ++r->steps;
        if (keep) CHECK(info.residual_names[9] && strcmp(info.residual_names[9], "class") == 0);
    }
    cf_stats q;
    CHECK_OK(ctx, cf_quasi_conformal_error(ctx, mesh, cf_mesh_positions(mesh), cf_flow_positions(flow), NULL, &q));
    r->mean_q = q.weighted_mean;
    CHECK_OK(ctx, cf_conformal_class_distance(ctx, mesh, cf_mesh_positions(mesh), cf_flow_positions(flow), NULL, NULL,
                                              &out->distance));
    int32_t dim = 2 * cf_mesh_genus(mesh);
    double *g0 = malloc(sizeof(double) * dim * dim), *g = malloc(sizeof(double) * dim * dim);
    CHECK_OK(ctx, cf_conformal_class_gram_gradient(ctx, mesh, cf_mesh_positions(mesh), g0, NULL));
    CHECK_OK(ctx, cf_conformal_class_gram_gradient(ctx, mesh, cf_flow_positions(flow), g, NULL));
    double big = 0.0, change = 0.0;
    for (int32_t k = 0; k < dim * dim; ++k) {
        big = fmax(big, fabs(g0[k]));
        change = fmax(change, fabs(g[k] - g0[k]));
    }
    out->gram_change = change / big;
    free(g0);
    free(g);
    cf_flow_destroy(&flow);
    return 1;
}

static int run_keep_class(cf_context *ctx, const cf_mesh *mesh, int keep, class_run *out)
{
    return run_keep_class_relaxed(ctx, mesh, keep, NULL, out);
}

/* The generated double torus (198 vertices) drifts from its class by 0.35
 * in 10 default steps (mean Q 1.80, W/4pi 4.97 -> 2.36). keep_class 1 holds
 * the class (measured 5e-11; the Gram matrix itself moves by 5 %: its
 * triangulation's part), W still falls at every step and further
 * (2.28), and the triangles keep better (mean Q 1.51); keep_class 2 holds
 * the Gram matrix too (1e-11), the triangles keep better still (1.29) and
 * W falls less (2.74). */
static void test_keep_class_double_torus(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_double_torus(ctx, 2, &mesh));
    class_run plain, kept, whole;
    if (mesh && run_keep_class(ctx, mesh, 0, &plain) && run_keep_class(ctx, mesh, 1, &kept) &&
        run_keep_class(ctx, mesh, 2, &whole)) {
        fprintf(stderr,
                "   double torus: W/4pi %.4f -> %.4f / %.4f / %.4f (default / keep_class 1 / 2), mean Q %.4f / %.4f / "
                "%.4f, class distance %.3g / %.3g / %.3g, Gram matrix change %.3g / %.3g / %.3g\n",
                plain.run.w0, plain.run.w, kept.run.w, whole.run.w, plain.run.mean_q, kept.run.mean_q,
                whole.run.mean_q, plain.distance, kept.distance, whole.distance, plain.gram_change, kept.gram_change,
                whole.gram_change);
        CHECK(plain.distance > 0.1);
        CHECK_LE(kept.distance, 1e-8);
        CHECK(kept.gram_change > 1e-3); /* the class alone: not the triangulation's part */
        CHECK_LE(whole.gram_change, 1e-8);
        CHECK_LE(whole.distance, 1e-8);
        CHECK_LE(kept.run.worst_rise, 0.0);
        CHECK_LE(whole.run.worst_rise, 0.0);
        CHECK(kept.run.w < 0.5 * kept.run.w0);
        CHECK(kept.run.w < plain.run.w);
        CHECK(whole.run.w < 0.6 * whole.run.w0);
        CHECK(kept.run.mean_q < plain.run.mean_q);
        CHECK(whole.run.mean_q < kept.run.mean_q);
    }
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* bob with keep_class 1 ends on the homogeneous torus of its exact class
 * (W/4pi 1.8452 against (pi / 4)(b + 1 / b) = 1.8477, 0.14 % below: the
 * discretisation; the default's 1.8510, 0.15 % above that of the class it
 * drifted to), its triangles as the default's (mean Q 1.037). On elk,
 * keep_class 1 meets the W target (6.51 <= 11.41) but raises mean Q above
 * the default's (1.708 against 1.625); keep_class 2, which also holds the
 * triangulation's part of the Gram matrix, meets both issue-13 targets
 * (W/4pi 10.11, mean Q 1.351). */
static void test_keep_class_shared(void)
{
    cft_shared_case bob, elk;
    if (cft_shared_case_open(&bob, "bob_5k.obj", 0)) {
        class_run r;
        cf_conformal_class input;
        CHECK_OK(bob.ctx, cf_conformal_class_compute(bob.ctx, bob.mesh, cf_mesh_positions(bob.mesh), NULL, &input));
        if (run_keep_class(bob.ctx, bob.mesh, 1, &r)) {
            double homogeneous = homogeneous_torus_w(input.modulus[1]);
            fprintf(stderr, "   bob keep_class 1: W/4pi %.4f (homogeneous torus %.4f), mean Q %.4f, class distance %.3g\n",
                    r.run.w, homogeneous, r.run.mean_q, r.distance);
            CHECK_LE(r.distance, 1e-9);
            CHECK_LE(r.run.worst_rise, 0.0);
            CHECK_NEAR(r.run.w, homogeneous, 0.005, 0); /* 0.5 %, as the default against its own class */
            CHECK_LE(r.run.mean_q, 1.05);
        }
        cft_shared_case_close(&bob);
    }
    if (cft_shared_case_open(&elk, "elk_g1_2k.obj", 0)) {
        class_run r[2];
        for (int mode = 1; mode <= 2; ++mode)
            if (run_keep_class(elk.ctx, elk.mesh, mode, &r[mode - 1]))
                fprintf(stderr,
                        "   elk keep_class %d: W/4pi %.4f -> %.4f (target %.4f), mean Q %.4f, class distance %.3g, "
                        "Gram matrix change %.3g, %d steps\n",
                        mode, r[mode - 1].run.w0, r[mode - 1].run.w, 0.5 * r[mode - 1].run.w0, r[mode - 1].run.mean_q,
                        r[mode - 1].distance, r[mode - 1].gram_change, r[mode - 1].run.steps);
        for (int mode = 0; mode < 2; ++mode) {
            CHECK_LE(r[mode].distance, 1e-9);
            CHECK_LE(r[mode].run.worst_rise, 0.0);
            CHECK_LE(r[mode].run.w, 0.5 * r[mode].run.w0);
        }
        CHECK(r[0].run.mean_q > 1.625); /* the class alone does not keep elk's triangles */
        CHECK_LE(r[1].gram_change, 1e-9);
        CHECK_LE(r[1].run.mean_q, 1.5);
        /* With the tangential relaxation too (not a default on genus > 0):
         * its candidate is moved back onto the class before its W is
         * compared. Before, the kept relaxed state left the class, every
         * attempt of the next step paid for the way back (W/4pi 8.59 at tau
         * -> 0 from 8.45) and the run stalled at step 5 (W/4pi 8.45, mean
         * Q 1.372). With that, 10 steps, W/4pi 8.354, mean Q 1.346 (still
         * near a stall: tau 0.004-0.001 from step 5). With the first-order
         * lambda of the period corrections (period_first_order, default
         * since) the run no longer stalls: W/4pi 6.280, and mean Q 1.703,
         * that of keep_class 1 without the relaxation (1.697): elk's class
         * costs its triangles this much at that W, and the relaxation keeps
         * no worse. (The bound here was mean Q <= 1.4 before.) */
        class_run relaxed;
        if (run_keep_class_relaxed(elk.ctx, elk.mesh, 1, "10", &relaxed)) {
            fprintf(stderr, "   elk keep_class 1, relaxation 10: W/4pi %.4f, mean Q %.4f, class distance %.3g, %d steps\n",
                    relaxed.run.w, relaxed.run.mean_q, relaxed.distance, relaxed.run.steps);
            CHECK(relaxed.run.steps == 10);
            CHECK_LE(relaxed.distance, 1e-9);
            CHECK_LE(relaxed.run.worst_rise, 0.0);
            CHECK_LE(relaxed.run.w, 0.5 * relaxed.run.w0);
            CHECK(relaxed.run.w < 8.0); /* past the old stall (8.45) */
            CHECK_LE(relaxed.run.mean_q, 1.01 * r[0].run.mean_q);
        }
        cft_shared_case_close(&elk);
    }
}

/* The tangential relaxation on closed surfaces of genus > 0 (`relaxation`,
 * not a default there; session 41, docs/spin.md "Tangential relaxation").
 * elk with 10 sweeps meets both issue-13 targets (measured W/4pi 5.707,
 * mean Q 1.482; the default 5.755, 1.555) and its class drifts less (0.127
 * against 0.175). The double torus is why it stays off by default: W falls
 * further (2.362 against 2.988) but its mean Q rises to 1.969 (1.531), and
 * with keep_class 1 as well the class is held and mean Q is still 1.967, so
 * the rise is not the class moving: the resampled state lets the flow go
 * on to a lower W of the same class, which crowds this 315-vertex mesh. */
static void test_relaxation_on_genus_above_zero(void)
{
    cft_shared_case elk, torus;
    if (cft_shared_case_open(&elk, "elk_g1_2k.obj", 0)) {
        class_run plain, relaxed;
        if (run_keep_class_relaxed(elk.ctx, elk.mesh, 0, NULL, &plain) &&
            run_keep_class_relaxed(elk.ctx, elk.mesh, 0, "10", &relaxed)) {
            fprintf(stderr,
                    "   elk: W/4pi %.4f -> %.4f (default) / %.4f (relaxation 10), target %.4f; mean Q %.4f / %.4f; "
                    "class distance %.3g / %.3g\n",
                    plain.run.w0, plain.run.w, relaxed.run.w, 0.5 * plain.run.w0, plain.run.mean_q, relaxed.run.mean_q,
                    plain.distance, relaxed.distance);
            CHECK(plain.run.mean_q > 1.5); /* the default's miss */
            CHECK(relaxed.run.steps == 10);
            CHECK_LE(relaxed.run.worst_rise, 0.0);
            CHECK_LE(relaxed.run.w, 0.5 * relaxed.run.w0);
            CHECK_LE(relaxed.run.mean_q, 1.5);
            CHECK_LE(relaxed.distance, plain.distance);
        }
        cft_shared_case_close(&elk);
    }
    if (cft_shared_case_open(&torus, "double_torus_315.obj", 0)) {
        class_run plain, relaxed, held;
        if (run_keep_class_relaxed(torus.ctx, torus.mesh, 0, NULL, &plain) &&
            run_keep_class_relaxed(torus.ctx, torus.mesh, 0, "10", &relaxed) &&
            run_keep_class_relaxed(torus.ctx, torus.mesh, 1, "10", &held)) {
            fprintf(stderr,
                    "   double torus: W/4pi %.4f -> %.4f (default) / %.4f (relaxation 10) / %.4f (and keep_class 1); "
                    "mean Q %.4f / %.4f / %.4f; class distance %.3g / %.3g / %.3g\n",
                    plain.run.w0, plain.run.w, relaxed.run.w, held.run.w, plain.run.mean_q, relaxed.run.mean_q,
                    held.run.mean_q, plain.distance, relaxed.distance, held.distance);
            CHECK_LE(relaxed.run.worst_rise, 0.0);
            CHECK(relaxed.run.w < plain.run.w - 0.3);
            CHECK(relaxed.run.mean_q > plain.run.mean_q + 0.3);
            CHECK_LE(held.distance, 1e-9);
            CHECK(held.run.mean_q > plain.run.mean_q + 0.3);
        }
        cft_shared_case_close(&torus);
    }
}

/* on a sphere (one class) and with a boundary the option is refused, naming itself */
static void test_keep_class_refused(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *sphere = NULL, *cylinder = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &sphere));
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 16, 8, 1.0, 2.0, &cylinder));
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "keep_class", "1"));
    cf_flow *flow = NULL;
    if (sphere) {
        CHECK_STATUS(cf_flow_create(ctx, sphere, NULL, &o, &flow), CF_ERR_BAD_MESH);
        CHECK(strstr(cf_context_message(ctx), "keep_class") && strstr(cf_context_message(ctx), "genus 0"));
    }
    if (cylinder) {
        CHECK_STATUS(cf_flow_create(ctx, cylinder, NULL, &o, &flow), CF_ERR_BAD_MESH);
        CHECK(strstr(cf_context_message(ctx), "keep_class") && strstr(cf_context_message(ctx), "boundary"));
    }
    CHECK(flow == NULL);
    cf_mesh_destroy(&sphere);
    cf_mesh_destroy(&cylinder);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* keep_class's steps allocate (the harmonic forms of each projection):
 * every allocation of create + two steps + destroy fails in turn, each
 * gives CF_ERR_NOMEM (or CHOLMOD recovers) and leaks nothing */
static cf_status keep_class_two_steps(cf_context *ctx, void *user)
{
    static const char *const keep[] = {"keep_class", "1", NULL};
    return spin_two_steps(ctx, user, keep);
}

static cf_status keep_gram_two_steps(cf_context *ctx, void *user)
{
    static const char *const keep[] = {"keep_class", "2", NULL};
    return spin_two_steps(ctx, user, keep);
}

static void test_keep_class_allocations(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *torus = NULL;
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.4, 12, 6, &torus));
    if (torus) {
        CHECK_OK(ctx, keep_class_two_steps(ctx, torus)); /* the context's CHOLMOD state first */
        CHECK(cft_allocation_sweep(ctx, "keep_class", keep_class_two_steps, torus, 1) > 20);
        CHECK_OK(ctx, keep_gram_two_steps(ctx, torus));
        CHECK(cft_allocation_sweep(ctx, "keep_class 2", keep_gram_two_steps, torus, 1) > 20);
    }
    cf_mesh_destroy(&torus);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_bob_plateau);
    CFT_RUN(test_keep_class_double_torus);
    CFT_RUN(test_keep_class_shared);
    CFT_RUN(test_relaxation_on_genus_above_zero);
    CFT_RUN(test_keep_class_refused);
    CFT_RUN(test_keep_class_allocations);
    CFT_RUN(test_cylinder_modulus);
    CFT_RUN(test_blade_class_beyond_double_precision);
    return cft_finish();
}
