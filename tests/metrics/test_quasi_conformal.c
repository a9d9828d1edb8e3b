/* Quasi-conformal error (Sander 2001), log area distortion, angle change:
 * Q = 1 for similarities to 1e-12, analytic Q for a shear, first-order
 * convergence of Q for a sampled Moebius map, statistics. */
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/metrics.h"
#include "test.h"

#include <stdlib.h>

#define PI_TEST 3.14159265358979323846

/* y = s R x + t with R about axis (2, -1, 2)/3 by 1.1 rad */
static void similarity(int32_t nv, const double *x, double s, double *y)
{
    double k[3] = {2.0 / 3.0, -1.0 / 3.0, 2.0 / 3.0}, c = cos(1.1), sn = sin(1.1);
    for (int32_t v = 0; v < nv; ++v) {
        const double *p = x + 3 * v;
        double kp = k[0] * p[0] + k[1] * p[1] + k[2] * p[2];
        double cr[3] = {k[1] * p[2] - k[2] * p[1], k[2] * p[0] - k[0] * p[2], k[0] * p[1] - k[1] * p[0]};
        for (int i = 0; i < 3; ++i) y[3 * v + i] = s * (p[i] * c + cr[i] * sn + k[i] * kp * (1 - c)) + 0.3 * (i - 1);
    }
}

static void check_similarity(cf_context *ctx, const cf_mesh *m)
{
    int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m);
    const double *x = cf_mesh_positions(m);
    double *y = malloc(sizeof(double) * 3 * nv), *q = malloc(sizeof(double) * nf), *la = malloc(sizeof(double) * nf);
    double *da = malloc(sizeof(double) * nv);
    similarity(nv, x, 3.7, y);
    cf_stats st, sa, sg;
    CHECK_OK(ctx, cf_quasi_conformal_error(ctx, m, x, y, q, &st));
    CHECK_OK(ctx, cf_log_area_distortion(ctx, m, x, y, la, &sa));
    CHECK_OK(ctx, cf_angle_change(ctx, m, x, y, da, &sg));
    for (int32_t f = 0; f < nf; ++f) {
        CHECK_NEAR(q[f], 1.0, 0, 1e-12);
        CHECK_NEAR(la[f], 0.0, 0, 1e-12);
    }
    for (int32_t v = 0; v < nv; ++v) CHECK_NEAR(da[v], 0.0, 0, 1e-12);
    CHECK_NEAR(st.max, 1.0, 0, 1e-12);
    CHECK_NEAR(st.weighted_mean, 1.0, 0, 1e-12);
    CHECK(st.count == nf);
    fprintf(stderr, "  similarity: max Q - 1 = %.2e, max |log area| = %.2e, max angle change = %.2e\n", st.max - 1,
            fmax(fabs(sa.min), fabs(sa.max)), sg.max);
    free(y);
    free(q);
    free(la);
    free(da);
}

static void test_similarity(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.3, 12u, &m));
    if (m) check_similarity(ctx, m);
    cf_mesh_destroy(&m);
    const char *spot = cft_shared_mesh_path("spot_3k.obj");
    if (spot) {
        CHECK_OK(ctx, cf_load_mesh(ctx, spot, &m));
        if (m) check_similarity(ctx, m);
        cf_mesh_destroy(&m);
    } else {
        fprintf(stderr, "  (spot_3k.obj part skipped: ../shared absent)\n");
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Shear (x, y) -> (x + k y, y): singular values (sqrt(k^2 + 4) +- k) / 2,
 * Q = ((sqrt(k^2 + 4) + k) / 2)^2 on every face; area unchanged (det 1). */
static void test_shear(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_grid(ctx, 7, 5, 1.0, 1.0, &m));
    if (!m) return;
    int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m);
    const double *x = cf_mesh_positions(m);
    double *y = malloc(sizeof(double) * 3 * nv), *q = malloc(sizeof(double) * nf);
    const double k = 0.5;
    for (int32_t v = 0; v < nv; ++v) {
        y[3 * v] = x[3 * v] + k * x[3 * v + 1];
        y[3 * v + 1] = x[3 * v + 1];
        y[3 * v + 2] = x[3 * v + 2];
    }
    double s1 = (sqrt(k * k + 4) + k) / 2, expect = s1 * s1;
    cf_stats st, sa, sg;
    CHECK_OK(ctx, cf_quasi_conformal_error(ctx, m, x, y, q, &st));
    for (int32_t f = 0; f < nf; ++f) CHECK_NEAR(q[f], expect, 1e-13, 0);
    CHECK_NEAR(st.p50, expect, 1e-13, 0);
    CHECK_NEAR(st.p95, expect, 1e-13, 0);
    CHECK_OK(ctx, cf_log_area_distortion(ctx, m, x, y, NULL, &sa));
    CHECK_NEAR(sa.max, 0.0, 0, 1e-13);
    CHECK_NEAR(sa.weighted_std, 0.0, 0, 1e-13);
    CHECK_OK(ctx, cf_angle_change(ctx, m, x, y, NULL, &sg));
    CHECK(sg.max > 0.1);
    /* stretching the top half by 2 in y: log area change +-log(2)... after
     * normalising the total, top faces get log 2 - log(1.5) and bottom
     * faces -log(1.5) (grid y in [0, 1], 5 rows: use row-aligned cut at y = 0.4) */
    for (int32_t v = 0; v < nv; ++v) {
        y[3 * v] = x[3 * v];
        y[3 * v + 1] = x[3 * v + 1] <= 0.4 + 1e-12 ? x[3 * v + 1] : 0.4 + 2.0 * (x[3 * v + 1] - 0.4);
    }
    double *la = malloc(sizeof(double) * nf);
    CHECK_OK(ctx, cf_log_area_distortion(ctx, m, x, y, la, &sa));
    double total = 0.4 + 2.0 * 0.6;
    const int32_t *t = cf_mesh_triangles(m);
    for (int32_t f = 0; f < nf; ++f) {
        double cy = (x[3 * t[3 * f] + 1] + x[3 * t[3 * f + 1] + 1] + x[3 * t[3 * f + 2] + 1]) / 3;
        CHECK_NEAR(la[f], (cy > 0.4 ? log(2.0) : 0.0) - log(total), 0, 1e-12);
    }
    /* area-weighted mean of log distortion is <= 0 (Jensen) */
    CHECK(sa.weighted_mean < 0);
    free(la);
    free(y);
    free(q);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* An exactly conformal map sampled at the vertices is not conformal per
 * triangle: the affine interpolant misses the variation of the scale factor
 * across a triangle, so mean Q - 1 = O(h |grad u|). This is the floor every
 * discrete conformal method is measured against (docs/spin.md uses it to read
 * the flow's mean Q). Map: a rotated unit icosphere, stereographic
 * projection, plane scaled by 4, back (a Moebius transformation; log area
 * std 1.35). Measured mean Q - 1: 0.0873, 0.0425, 0.0210 at 642, 2562,
 * 10242 vertices: each halving of h halves it. */
static void test_moebius_sampling_first_order(void)
{
    cf_context *ctx = cft_context();
    double excess[3];
    for (int level = 3; level <= 5; ++level) {
        cf_mesh *m = NULL;
        CHECK_OK(ctx, cf_generate_icosphere(ctx, level, 1.0, &m));
        int32_t nv = cf_mesh_vertex_count(m);
        const double *x0 = cf_mesh_positions(m);
        double *x = malloc(sizeof(double) * 3 * nv), *y = malloc(sizeof(double) * 3 * nv);
        double c1 = cos(0.3), s1 = sin(0.3), c2 = cos(0.7), s2 = sin(0.7);
        for (int32_t v = 0; v < nv; ++v) {
            /* rotate so that no vertex sits at the projection pole */
            double px = c1 * x0[3 * v] - s1 * x0[3 * v + 2], pz = s1 * x0[3 * v] + c1 * x0[3 * v + 2];
            double py = c2 * x0[3 * v + 1] - s2 * pz;
            pz = s2 * x0[3 * v + 1] + c2 * pz;
            x[3 * v] = px;
            x[3 * v + 1] = py;
            x[3 * v + 2] = pz;
            double u = 4.0 * px / (1.0 - pz), w = 4.0 * py / (1.0 - pz), r2 = u * u + w * w;
            y[3 * v] = 2.0 * u / (1.0 + r2);
            y[3 * v + 1] = 2.0 * w / (1.0 + r2);
            y[3 * v + 2] = (r2 - 1.0) / (r2 + 1.0);
        }
        cf_stats q, a;
        CHECK_OK(ctx, cf_quasi_conformal_error(ctx, m, x, y, NULL, &q));
        CHECK_OK(ctx, cf_log_area_distortion(ctx, m, x, y, NULL, &a));
        excess[level - 3] = q.weighted_mean - 1.0;
        fprintf(stderr, "  Moebius map, %d vertices: mean Q %.4f, max Q %.3f, log area std %.3f\n", nv,
                q.weighted_mean, q.max, a.weighted_std);
        CHECK_NEAR(a.weighted_std, 1.35, 0.0, 0.03);
        free(x);
        free(y);
        cf_mesh_destroy(&m);
    }
    for (int k = 0; k < 2; ++k) {
        double ratio = excess[k] / excess[k + 1];
        CHECK(ratio > 1.8 && ratio < 2.2);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* The stereographic Moebius map of test_moebius_sampling_first_order at
 * `level`: x (the rotated icosphere), y (its image) and the analytic log
 * conformal factor at each vertex, log(4 / (1 - z) * 2 / (1 + r^2)): 1 / (1 - z)
 * for the projection, 4 for the scaling, 2 / (1 + r^2) back to the sphere. */
static cf_mesh *moebius_case(cf_context *ctx, int level, double **x, double **y, double **log_scale)
{
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, level, 1.0, &m));
    if (!m) return NULL;
    int32_t nv = cf_mesh_vertex_count(m);
    const double *x0 = cf_mesh_positions(m);
    *x = malloc(sizeof(double) * 3 * nv);
    *y = malloc(sizeof(double) * 3 * nv);
    *log_scale = malloc(sizeof(double) * nv);
    double c1 = cos(0.3), s1 = sin(0.3), c2 = cos(0.7), s2 = sin(0.7);
    for (int32_t v = 0; v < nv; ++v) {
        double px = c1 * x0[3 * v] - s1 * x0[3 * v + 2], pz = s1 * x0[3 * v] + c1 * x0[3 * v + 2];
        double py = c2 * x0[3 * v + 1] - s2 * pz;
        pz = s2 * x0[3 * v + 1] + c2 * pz;
        (*x)[3 * v] = px;
        (*x)[3 * v + 1] = py;
        (*x)[3 * v + 2] = pz;
        double u = 4.0 * px / (1.0 - pz), w = 4.0 * py / (1.0 - pz), r2 = u * u + w * w;
        (*y)[3 * v] = 2.0 * u / (1.0 + r2);
        (*y)[3 * v + 1] = 2.0 * w / (1.0 + r2);
        (*y)[3 * v + 2] = (r2 - 1.0) / (r2 + 1.0);
        (*log_scale)[v] = log(4.0 / (1.0 - pz) * 2.0 / (1.0 + r2));
    }
    return m;
}

/* cf_vertex_scale_fit_compute. A similarity: u = log s at every vertex,
 * residual 0, model Q 1. The Moebius map: a Moebius transformation scales
 * every chord exactly by the geometric mean of the conformal factors at its
 * ends, |M x - M y| = sqrt(l(x) l(y)) |x - y| (which is why Springborn,
 * Schroeder and Pinkall 2008 call discrete conformal equivalence
 * Moebius-invariant), so the fit recovers the analytic log factor at every
 * vertex with no residual, and each face's model triangle is the sampled
 * map's own: model Q = Q face by face. Measured: |u - log factor| <= 7.5e-13,
 * residual <= 6.9e-14 (the conjugate gradients' tolerance, 1e-13 of the
 * right-hand side), at 642 / 2562 / 10242 vertices. */
static void test_vertex_scale_fit(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.3, 12u, &m));
    if (m) {
        int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m);
        double *y = malloc(sizeof(double) * 3 * nv), *u = malloc(sizeof(double) * nv), *q = malloc(sizeof(double) * nf);
        similarity(nv, cf_mesh_positions(m), 3.7, y);
        cf_vertex_scale_fit fit;
        CHECK_OK(ctx, cf_vertex_scale_fit_compute(ctx, m, cf_mesh_positions(m), y, u, q, &fit));
        for (int32_t v = 0; v < nv; ++v) CHECK_NEAR(u[v], log(3.7), 0, 1e-12);
        for (int32_t f = 0; f < nf; ++f) CHECK_NEAR(q[f], 1.0, 0, 1e-12);
        CHECK(fit.invalid_faces == 0 && fit.q.count == nf);
        CHECK_LE(fit.rms_residual, 1e-13);
        fprintf(stderr, "  similarity: u - log 3.7 within 1e-12, model Q 1, residual %.2e\n", fit.rms_residual);
        free(y);
        free(u);
        free(q);
        cf_mesh_destroy(&m);
    }
    for (int level = 3; level <= 5; ++level) {
        double *x = NULL, *y = NULL, *exact = NULL;
        m = moebius_case(ctx, level, &x, &y, &exact);
        if (!m) continue;
        int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m);
        double *u = malloc(sizeof(double) * nv), *qm = malloc(sizeof(double) * nf), *qs = malloc(sizeof(double) * nf);
        cf_vertex_scale_fit fit;
        cf_stats q;
        CHECK_OK(ctx, cf_vertex_scale_fit_compute(ctx, m, x, y, u, qm, &fit));
        CHECK_OK(ctx, cf_quasi_conformal_error(ctx, m, x, y, qs, &q));
        double u_error = 0.0, q_error = 0.0;
        for (int32_t v = 0; v < nv; ++v) u_error = fmax(u_error, fabs(u[v] - exact[v]));
        for (int32_t f = 0; f < nf; ++f) q_error = fmax(q_error, fabs(qm[f] - qs[f]));
        fprintf(stderr,
                "  Moebius map, %d vertices: max |u - log factor| %.2e, residual %.2e, model Q %.4f (sampled map's "
                "%.4f, max difference per face %.2e)\n",
                nv, u_error, fit.rms_residual, fit.q.weighted_mean, q.weighted_mean, q_error);
        CHECK_LE(u_error, 1e-11);
        CHECK_LE(fit.rms_residual, 1e-12);
        CHECK_LE(q_error, 1e-11);
        CHECK(fit.invalid_faces == 0 && fit.q.count == nf);
        CHECK(q.weighted_mean - 1.0 > 0.02); /* the sampled map is not conformal per face */
        free(u);
        free(qm);
        free(qs);
        free(x);
        free(y);
        free(exact);
        cf_mesh_destroy(&m);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* What crowding costs: the exactly conformal map (theta, z) -> e^-z (cos
 * theta, sin theta, 0) of the unit tube onto the plane, sampled at the
 * vertices of cf_generate_cylinder (n sides, square cells), crowds the tube
 * along its axis as a limb is crowded under a conformal map of the whole
 * shape. Its mean Q depends on n only (every band is the same up to
 * scale) and Q - 1 is first order in 1 / n (each doubling of n halves it
 * in the limit); the vertex-scale model explains it, to 2.3 % at n = 6.
 * A limb of 8 sides crowded this way is above 1.5 by itself. Measured
 * (docs/ops.md): n = 6 / 8 / 12 / 24 / 48: mean Q 2.1759 / 1.7692 / 1.4545 /
 * 1.2040 / 1.0971. */
static void test_tube_crowding(void)
{
    cf_context *ctx = cft_context();
    const int sides[5] = {6, 8, 12, 24, 48};
    const double measured[5] = {2.1759, 1.7692, 1.4545, 1.2040, 1.0971};
    double excess[5];
    for (int k = 0; k < 5; ++k) {
        int n = sides[k], bands = 4;
        cf_mesh *m = NULL;
        CHECK_OK(ctx, cf_generate_cylinder(ctx, n, bands, 1.0, bands * 2.0 * PI_TEST / n, &m));
        if (!m) return;
        int32_t nv = cf_mesh_vertex_count(m);
        const double *x = cf_mesh_positions(m);
        double *y = malloc(sizeof(double) * 3 * nv);
        for (int32_t v = 0; v < nv; ++v) {
            double theta = atan2(x[3 * v + 1], x[3 * v]), r = exp(-x[3 * v + 2]);
            y[3 * v] = r * cos(theta);
            y[3 * v + 1] = r * sin(theta);
            y[3 * v + 2] = 0.0;
        }
        cf_stats q;
        cf_vertex_scale_fit fit;
        CHECK_OK(ctx, cf_quasi_conformal_error(ctx, m, x, y, NULL, &q));
        CHECK_OK(ctx, cf_vertex_scale_fit_compute(ctx, m, x, y, NULL, NULL, &fit));
        excess[k] = q.weighted_mean - 1.0;
        CHECK_NEAR(q.weighted_mean, measured[k], 1e-4, 0);
        CHECK_NEAR(fit.q.weighted_mean, q.weighted_mean, 0.025 * q.weighted_mean, 0);
        CHECK(fit.invalid_faces == 0);
        fprintf(stderr, "  tube of %d sides: mean Q %.4f (max %.3f), vertex-scale model %.4f, residual %.2e\n", n,
                q.weighted_mean, q.max, fit.q.weighted_mean, fit.rms_residual);
        free(y);
        cf_mesh_destroy(&m);
    }
    double ratio = excess[3] / excess[4];
    fprintf(stderr, "  (Q - 1) at 24 sides / at 48: %.3f\n", ratio);
    CHECK(ratio > 1.9 && ratio < 2.3);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* cf_conformal_excess: the two weighted means of cf_quasi_conformal_error
 * and cf_vertex_scale_fit_compute without their arrays. Against them on the
 * Moebius map (excess 0: the model is the map) and on a map with a shear
 * part (the bumpy sphere's positions pushed along x by a smooth function of
 * z, whose excess is positive); a workspace of the stated size is enough
 * (checked with a guard after it); nothing is allocated; bad arguments. */
static void test_conformal_excess(void)
{
    cf_context *ctx = cft_context();
    double *x = NULL, *y = NULL, *exact = NULL;
    cf_mesh *m = moebius_case(ctx, 4, &x, &y, &exact);
    if (m) {
        int64_t n = cf_conformal_excess_work_size(m);
        CHECK(n == 5 * (int64_t)cf_mesh_vertex_count(m) + cf_mesh_edge_count(m));
        double *work = malloc(sizeof(double) * (size_t)(n + 1));
        work[n] = 12345.0; /* guard */
        cf_stats q;
        cf_vertex_scale_fit fit;
        double mean_q = 0.0, mean_model = 0.0;
        CHECK_OK(ctx, cf_quasi_conformal_error(ctx, m, x, y, NULL, &q));
        CHECK_OK(ctx, cf_vertex_scale_fit_compute(ctx, m, x, y, NULL, NULL, &fit));
        size_t bytes = cf_context_bytes_in_use(ctx);
        CHECK_OK(ctx, cf_conformal_excess(ctx, m, x, y, work, &mean_q, &mean_model));
        CHECK(cf_context_bytes_in_use(ctx) == bytes);
        CHECK(work[n] == 12345.0);
        fprintf(stderr, "  Moebius map: mean Q %.6f (%.6f), model %.6f (%.6f)\n", mean_q, q.weighted_mean, mean_model,
                fit.q.weighted_mean);
        CHECK_NEAR(mean_q, q.weighted_mean, 1e-12, 0);
        CHECK_NEAR(mean_model, fit.q.weighted_mean, 1e-9, 0);
        CHECK_NEAR(mean_q - mean_model, 0.0, 0, 1e-9);
        CHECK(mean_q - 1.0 > 0.02);

        /* a shear: x += 0.3 sin(2 z) moves the faces' shapes in a way no vertex scale explains */
        int32_t nv = cf_mesh_vertex_count(m);
        for (int32_t v = 0; v < nv; ++v) {
            for (int c = 0; c < 3; ++c) y[3 * v + c] = x[3 * v + c];
            y[3 * v] += 0.3 * sin(2.0 * x[3 * v + 2]);
        }
        CHECK_OK(ctx, cf_quasi_conformal_error(ctx, m, x, y, NULL, &q));
        CHECK_OK(ctx, cf_vertex_scale_fit_compute(ctx, m, x, y, NULL, NULL, &fit));
        CHECK_OK(ctx, cf_conformal_excess(ctx, m, x, y, work, &mean_q, &mean_model));
        fprintf(stderr, "  shear: mean Q %.6f, model %.6f, excess %.4f\n", mean_q, mean_model, mean_q - mean_model);
        CHECK_NEAR(mean_q, q.weighted_mean, 1e-12, 0);
        CHECK_NEAR(mean_model, fit.q.weighted_mean, 1e-9, 0);
        CHECK(mean_q - mean_model > 0.05);

        CHECK(cf_conformal_excess(ctx, m, x, y, NULL, &mean_q, &mean_model) == CF_ERR_INVALID_ARG);
        CHECK(cf_conformal_excess(ctx, m, x, y, work, NULL, &mean_model) == CF_ERR_INVALID_ARG);
        CHECK(cf_conformal_excess(ctx, NULL, x, y, work, &mean_q, &mean_model) == CF_ERR_INVALID_ARG);
        y[7] = NAN;
        CHECK(cf_conformal_excess(ctx, m, x, y, work, &mean_q, &mean_model) == CF_ERR_NONFINITE);
        CHECK(cf_conformal_excess_work_size(NULL) == 0);
        free(work);
        free(x);
        free(y);
        free(exact);
        cf_mesh_destroy(&m);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_stats(void)
{
    cf_context *ctx = cft_context();
    const double v[5] = {5, 1, 4, 2, 3}, w[5] = {1, 1, 1, 1, 4};
    cf_stats st;
    CHECK_OK(ctx, cf_stats_compute(ctx, 5, v, w, &st));
    CHECK(st.count == 5 && st.min == 1 && st.max == 5);
    CHECK_NEAR(st.mean, 3.0, 1e-15, 0);
    CHECK_NEAR(st.weighted_mean, (5 + 1 + 4 + 2 + 12) / 8.0, 1e-15, 0);
    CHECK(st.p50 == 3 && st.p95 == 5);
    double bad[2] = {1, NAN};
    CHECK_STATUS(cf_stats_compute(ctx, 2, bad, NULL, &st), CF_ERR_NONFINITE);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_similarity);
    CFT_RUN(test_shear);
    CFT_RUN(test_moebius_sampling_first_order);
    CFT_RUN(test_vertex_scale_fit);
    CFT_RUN(test_tube_crowding);
    CFT_RUN(test_conformal_excess);
    CFT_RUN(test_stats);
    return cft_finish();
}
