/* cf_edge_poisson / cf_edge_closure_error (ops/edge_poisson.c): positions
 * from edge vectors, free (shifted) and with fixed values, sign convention
 * b = L f, the metric switch, and failure paths. */
#include "curvflow/generate.h"
#include "curvflow/ops.h"
#include "test.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double *edges_of(const cf_mesh *mesh, const double *p)
{
    int32_t ne = cf_mesh_edge_count(mesh);
    const int32_t *ev = cf_mesh_edge_vertices(mesh);
    double *e = malloc(3 * (size_t)ne * sizeof(double));
    for (int32_t k = 0; k < ne; ++k)
        for (int c = 0; c < 3; ++c) e[3 * k + c] = p[3 * ev[2 * k + 1] + c] - p[3 * ev[2 * k] + c];
    return e;
}

/* Integrable edges give the surface back up to a translation (closed mesh,
 * shifted L), and the closure error of the result is ~0; a rotated copy of
 * the edges gives the rotated surface. */
static void test_integrable_edges_closed(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.2, 7, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    const double *p = cf_mesh_positions(mesh);
    double *e = edges_of(mesh, p), *x = malloc(3 * (size_t)nv * sizeof(double));
    cf_edge_poisson *ep = NULL;
    CHECK_OK(ctx, cf_edge_poisson_create(ctx, mesh, NULL, 0, NULL, &ep));
    cf_solver_timings tm = {0.0, 0.0, 0.0};
    CHECK_OK(ctx, cf_edge_poisson_solve(ep, e, NULL, x, &tm));
    double off[3] = {x[0] - p[0], x[1] - p[1], x[2] - p[2]}, err = 0.0;
    for (int32_t i = 0; i < nv; ++i)
        for (int c = 0; c < 3; ++c) err = fmax(err, fabs(x[3 * i + c] - off[c] - p[3 * i + c]));
    /* the 1e-10 relative shift perturbs the solution by ~1e-10 times L's condition number */
    CHECK_LE(err, 1e-7);
    CHECK_LE(cf_edge_closure_error(mesh, x, e), 1e-7);
    CHECK(tm.factorize_seconds >= 0.0 && tm.solve_seconds >= 0.0);
    /* a non-integrable field: closure error of the least-squares fit is positive */
    for (int32_t k = 0; k < cf_mesh_edge_count(mesh); ++k) e[3 * k] += (k % 3 == 0) ? 0.05 : 0.0;
    CHECK_OK(ctx, cf_edge_poisson_solve(ep, e, NULL, x, NULL));
    double ce = cf_edge_closure_error(mesh, x, e);
    CHECK(ce > 1e-3 && ce < 1.0);
    cf_edge_poisson_destroy(&ep);
    CHECK(ep == NULL);
    free(e);
    free(x);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Fixed values: on a flat grid, boundary vertices fixed to an affine map A p
 * and edges of A p: the interior is A p to rounding; fixed vertices keep
 * their values exactly. Then a least-squares property: with edges that are
 * not integrable, the residual L f - b vanishes at free vertices (sign
 * convention b_i = -sum_(i,j) w e~ + sum_(j,i) w e~). */
static void test_fixed_values_and_sign(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_grid(ctx, 12, 9, 1.0, 0.8, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh), ne = cf_mesh_edge_count(mesh);
    const double *p = cf_mesh_positions(mesh);
    const int32_t *ev = cf_mesh_edge_vertices(mesh);
    double *q = malloc(3 * (size_t)nv * sizeof(double)), *x = malloc(3 * (size_t)nv * sizeof(double));
    const double a[9] = {1.2, 0.3, 0.0, -0.4, 0.9, 0.1, 0.2, 0.5, 1.1};
    for (int32_t i = 0; i < nv; ++i)
        for (int r = 0; r < 3; ++r)
            q[3 * i + r] = a[3 * r] * p[3 * i] + a[3 * r + 1] * p[3 * i + 1] + a[3 * r + 2] * p[3 * i + 2] + 0.7 * r;
    int32_t *known = malloc((size_t)nv * sizeof(int32_t)), nk = 0;
    const uint8_t *onb = cf_mesh_vertex_on_boundary(mesh);
    for (int32_t i = 0; i < nv; ++i)
        if (onb[i]) known[nk++] = i;
    double *e = edges_of(mesh, q);
    cf_edge_poisson *ep = NULL;
    CHECK_OK(ctx, cf_edge_poisson_create(ctx, mesh, NULL, nk, known, &ep));
    CHECK_OK(ctx, cf_edge_poisson_solve(ep, e, q, x, NULL));
    double err = 0.0;
    for (int32_t i = 0; i < 3 * nv; ++i) err = fmax(err, fabs(x[i] - q[i]));
    CHECK_LE(err, 1e-12);
    for (int32_t k = 0; k < nk; ++k)
        for (int c = 0; c < 3; ++c) CHECK(x[3 * known[k] + c] == q[3 * known[k] + c]);
    /* non-integrable edges: gradient of 1/2 sum w |f_j - f_i - e~|^2 at free vertices is 0 */
    for (int32_t k = 0; k < ne; ++k) e[3 * k + 2] += 0.01 * (double)(k % 5);
    CHECK_OK(ctx, cf_edge_poisson_solve(ep, e, q, x, NULL));
    double *g = calloc(3 * (size_t)nv, sizeof(double)), gmax = 0.0;
    for (int32_t k = 0; k < ne; ++k) {
        int32_t i = ev[2 * k], j = ev[2 * k + 1];
        double w = cf_edge_poisson_weight(ep, k);
        for (int c = 0; c < 3; ++c) {
            double r = x[3 * j + c] - x[3 * i + c] - e[3 * k + c];
            g[3 * i + c] -= w * r;
            g[3 * j + c] += w * r;
        }
    }
    for (int32_t i = 0; i < nv; ++i)
        if (!onb[i])
            for (int c = 0; c < 3; ++c) gmax = fmax(gmax, fabs(g[3 * i + c]));
    CHECK_LE(gmax, 1e-12);
    /* the weight is minus L's off-diagonal entry: the Laplacian is PSD */
    const cf_sparse *l = cf_edge_poisson_laplacian(ep);
    CHECK_NEAR(cf_edge_poisson_weight(ep, 0), -l->values[cf_sparse_find(l, ev[0], ev[1])], 0.0, 0.0);
    /* scalar solves are for the free (shifted) solver only */
    CHECK_STATUS(cf_edge_poisson_solve_scalar(ep, 1, x, g, NULL), CF_ERR_INVALID_ARG);
    cf_edge_poisson_destroy(&ep);
    free(g);
    free(e);
    free(q);
    free(x);
    free(known);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* cf_edge_poisson_solve_from: the same least-squares fit solved for the
 * displacement from a base. A zero step gives the base back bit for bit
 * (also 1e6 away from the origin); a tiny integrable step (1e-9 of the size)
 * is recovered to 1e-4 of the step, while the absolute solve's error is
 * relative to the coordinates (the shift and rounding), above the step
 * itself; with fixed vertices both forms agree and the fixed values are
 * exact. */
static void test_solve_from(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.2, 7, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh), ne = cf_mesh_edge_count(mesh);
    const int32_t *ev = cf_mesh_edge_vertices(mesh);
    double *base = malloc(3 * (size_t)nv * sizeof(double)), *x = malloc(3 * (size_t)nv * sizeof(double));
    double *y = malloc(3 * (size_t)nv * sizeof(double)), *moved = malloc(3 * (size_t)nv * sizeof(double));
    const double *p = cf_mesh_positions(mesh);
    for (int32_t i = 0; i < 3 * nv; ++i) base[i] = p[i] + 1e6;
    cf_edge_poisson *ep = NULL;
    CHECK_OK(ctx, cf_edge_poisson_create(ctx, mesh, NULL, 0, NULL, &ep));
    /* zero step */
    double *e = edges_of(mesh, base);
    CHECK_OK(ctx, cf_edge_poisson_solve_from(ep, base, e, NULL, x, NULL));
    CHECK(memcmp(x, base, 3 * (size_t)nv * sizeof(double)) == 0);
    free(e);
    memcpy(base, p, 3 * (size_t)nv * sizeof(double));
    /* a tiny smooth step: g = 1e-9 (z^2, xy, sin x) */
    for (int32_t i = 0; i < nv; ++i) {
        const double *q = p + 3 * i;
        double g[3] = {q[2] * q[2], q[0] * q[1], sin(q[0])};
        for (int c = 0; c < 3; ++c) moved[3 * i + c] = base[3 * i + c] + 1e-9 * g[c];
    }
    /* target edges from the small differences (exact to rounding of 1e-9 g) */
    e = malloc(3 * (size_t)ne * sizeof(double));
    for (int32_t k = 0; k < ne; ++k)
        for (int c = 0; c < 3; ++c) {
            const double *a = p + 3 * ev[2 * k], *b = p + 3 * ev[2 * k + 1];
            double ga[3] = {a[2] * a[2], a[0] * a[1], sin(a[0])}, gb[3] = {b[2] * b[2], b[0] * b[1], sin(b[0])};
            e[3 * k + c] = (b[c] - a[c]) + 1e-9 * (gb[c] - ga[c]);
        }
    CHECK_OK(ctx, cf_edge_poisson_solve_from(ep, base, e, NULL, x, NULL));
    CHECK_OK(ctx, cf_edge_poisson_solve(ep, e, NULL, y, NULL));
    double err_from = 0.0, err_abs = 0.0, step = 0.0;
    for (int32_t k = 0; k < ne; ++k) {
        int32_t i = ev[2 * k], j = ev[2 * k + 1];
        for (int c = 0; c < 3; ++c) {
            double want = e[3 * k + c];
            step = fmax(step, fabs(e[3 * k + c] - (base[3 * j + c] - base[3 * i + c])));
            err_from = fmax(err_from, fabs(x[3 * j + c] - x[3 * i + c] - want));
            err_abs = fmax(err_abs, fabs(y[3 * j + c] - y[3 * i + c] - want));
        }
    }
    fprintf(stderr, "   step 1e-9: largest edge change %.2e, edge error from the base %.2e, "
                    "absolute solve %.2e\n", step, err_from, err_abs);
    CHECK(step > 1e-10);
    CHECK_LE(err_from, 1e-4 * step);
    CHECK(err_abs > err_from); /* what the displacement form is for */
    cf_edge_poisson_destroy(&ep);
    free(e);
    /* fixed vertices: both forms give the same fit, fixed values exactly */
    int32_t *known = malloc(2 * sizeof(int32_t));
    known[0] = 0;
    known[1] = nv / 2;
    CHECK_OK(ctx, cf_edge_poisson_create(ctx, mesh, NULL, 2, known, &ep));
    e = edges_of(mesh, p);
    for (int32_t k = 0; k < ne; ++k) e[3 * k + 1] += 0.01 * (double)(k % 3);
    CHECK_OK(ctx, cf_edge_poisson_solve_from(ep, p, e, moved, x, NULL));
    CHECK_OK(ctx, cf_edge_poisson_solve(ep, e, moved, y, NULL));
    double diff = 0.0;
    for (int32_t i = 0; i < 3 * nv; ++i) diff = fmax(diff, fabs(x[i] - y[i]));
    CHECK_LE(diff, 1e-12);
    for (int k = 0; k < 2; ++k)
        for (int c = 0; c < 3; ++c) CHECK(x[3 * known[k] + c] == moved[3 * known[k] + c]);
    CHECK_STATUS(cf_edge_poisson_solve_from(ep, p, e, NULL, x, NULL), CF_ERR_INVALID_ARG);
    cf_edge_poisson_destroy(&ep);
    free(known);
    free(e);
    free(base);
    free(x);
    free(y);
    free(moved);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* The metric switch: after set_metric to a scaled copy (cotan weights depend
 * only on angles, so the solve must not change) and to a sheared one (it
 * must, for non-integrable edges). */
static void test_metric(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh), ne = cf_mesh_edge_count(mesh);
    const double *p = cf_mesh_positions(mesh);
    double *s = malloc(3 * (size_t)nv * sizeof(double)), *x0 = malloc(3 * (size_t)nv * sizeof(double));
    double *x1 = malloc(3 * (size_t)nv * sizeof(double));
    double *e = edges_of(mesh, p);
    for (int32_t k = 0; k < ne; ++k) e[3 * k + 1] *= 1.0 + 0.1 * (double)(k % 2);
    cf_edge_poisson *ep = NULL;
    CHECK_OK(ctx, cf_edge_poisson_create(ctx, mesh, p, 0, NULL, &ep));
    CHECK_OK(ctx, cf_edge_poisson_solve(ep, e, NULL, x0, NULL));
    for (int32_t i = 0; i < 3 * nv; ++i) s[i] = 3.0 * p[i];
    CHECK_OK(ctx, cf_edge_poisson_set_metric(ep, s));
    CHECK_OK(ctx, cf_edge_poisson_solve(ep, e, NULL, x1, NULL));
    double d = 0.0;
    for (int32_t i = 0; i < 3 * nv; ++i) d = fmax(d, fabs((x1[i] - x1[i % 3]) - (x0[i] - x0[i % 3])));
    CHECK_LE(d, 1e-6);
    for (int32_t i = 0; i < nv; ++i) s[3 * i] = p[3 * i] + 0.8 * p[3 * i + 1];
    CHECK_OK(ctx, cf_edge_poisson_set_metric(ep, s));
    CHECK_OK(ctx, cf_edge_poisson_solve(ep, e, NULL, x1, NULL));
    d = 0.0;
    for (int32_t i = 0; i < 3 * nv; ++i) d = fmax(d, fabs((x1[i] - x1[i % 3]) - (x0[i] - x0[i % 3])));
    CHECK(d > 1e-4);
    cf_edge_poisson_destroy(&ep);
    free(s);
    free(x0);
    free(x1);
    free(e);
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
}

/* cf_edge_poisson_set_metric_scaled: scale 1 is set_metric bit for bit, a
 * common factor c gives c L (and the same fit); integrable edges come back
 * exactly whatever the positive scales; with edges that are not integrable
 * a face weighted 1e6 times more has its own edges fitted far closer (the
 * misfit goes elsewhere); a scale that is not positive and finite is
 * refused, naming the face. */
static void test_metric_scaled(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 2, 0.2, 3, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh), ne = cf_mesh_edge_count(mesh), nf = cf_mesh_face_count(mesh);
    const double *p = cf_mesh_positions(mesh);
    const int32_t *tri = cf_mesh_triangles(mesh);
    const int32_t *ev = cf_mesh_edge_vertices(mesh);
    double *scale = malloc((size_t)nf * sizeof(double));
    double *x = malloc(3 * (size_t)nv * sizeof(double)), *y = malloc(3 * (size_t)nv * sizeof(double));
    double *e = edges_of(mesh, p);
    cf_edge_poisson *a = NULL, *b = NULL;
    CHECK_OK(ctx, cf_edge_poisson_create(ctx, mesh, p, 0, NULL, &a));
    CHECK_OK(ctx, cf_edge_poisson_create(ctx, mesh, p, 0, NULL, &b));
    const cf_sparse *la = cf_edge_poisson_laplacian(a), *lb = cf_edge_poisson_laplacian(b);
    int64_t nnz = la->colptr[nv];
    CHECK_OK(ctx, cf_edge_poisson_set_metric(a, p)); /* a refill, as the scaled one (create sums in another order) */
    for (int32_t f = 0; f < nf; ++f) scale[f] = 1.0;
    CHECK_OK(ctx, cf_edge_poisson_set_metric_scaled(b, p, scale));
    CHECK(memcmp(la->values, lb->values, (size_t)nnz * sizeof(double)) == 0);
    CHECK_OK(ctx, cf_edge_poisson_set_metric_scaled(b, p, NULL));
    CHECK(memcmp(la->values, lb->values, (size_t)nnz * sizeof(double)) == 0);
    for (int32_t f = 0; f < nf; ++f) scale[f] = 2.5;
    CHECK_OK(ctx, cf_edge_poisson_set_metric_scaled(b, p, scale));
    double d = 0.0, big = 0.0;
    for (int64_t k = 0; k < nnz; ++k) {
        d = fmax(d, fabs(lb->values[k] - 2.5 * la->values[k]));
        big = fmax(big, fabs(la->values[k]));
    }
    CHECK_LE(d, 1e-14 * big);
    /* integrable edges: the surface again, whatever the positive scales */
    for (int32_t f = 0; f < nf; ++f) scale[f] = exp(6.0 * sin(1.7 * f)); /* e^-6 .. e^6 */
    CHECK_OK(ctx, cf_edge_poisson_set_metric_scaled(b, p, scale));
    CHECK_OK(ctx, cf_edge_poisson_solve_from(b, p, e, NULL, x, NULL));
    double err = 0.0;
    for (int32_t i = 0; i < 3 * nv; ++i) err = fmax(err, fabs(x[i] - p[i]));
    CHECK_LE(err, 1e-12);
    /* not integrable elsewhere: the edges of one face exact (they close),
     * the others perturbed; weighted 1e6, that face keeps its edges, where
     * the plain fit leaves part of the misfit on them */
    int32_t heavy = nf / 3;
    uint8_t *of_heavy = calloc((size_t)ne, 1);
    for (int32_t k = 0; k < ne; ++k) {
        int32_t in_face = 0;
        for (int c = 0; c < 3; ++c) in_face += tri[3 * heavy + c] == ev[2 * k] || tri[3 * heavy + c] == ev[2 * k + 1];
        of_heavy[k] = in_face == 2;
        if (!of_heavy[k]) e[3 * k] += (k % 3 == 0) ? 0.05 : -0.02;
    }
    for (int32_t f = 0; f < nf; ++f) scale[f] = 1.0;
    CHECK_OK(ctx, cf_edge_poisson_solve_from(a, p, e, NULL, x, NULL));
    scale[heavy] = 1e6;
    CHECK_OK(ctx, cf_edge_poisson_set_metric_scaled(b, p, scale));
    CHECK_OK(ctx, cf_edge_poisson_solve_from(b, p, e, NULL, y, NULL));
    double miss_plain = 0.0, miss_heavy = 0.0;
    for (int32_t k = 0; k < ne; ++k) {
        int32_t i = ev[2 * k], j = ev[2 * k + 1];
        if (!of_heavy[k]) continue;
        for (int c = 0; c < 3; ++c) {
            miss_plain = fmax(miss_plain, fabs(x[3 * j + c] - x[3 * i + c] - e[3 * k + c]));
            miss_heavy = fmax(miss_heavy, fabs(y[3 * j + c] - y[3 * i + c] - e[3 * k + c]));
        }
    }
    fprintf(stderr, "   misfit of the heavy face's edges: %.3g plain, %.3g weighted 1e6\n", miss_plain, miss_heavy);
    CHECK(miss_plain > 1e-3);
    CHECK_LE(miss_heavy, 1e-3 * miss_plain);
    /* refused: zero, negative, NaN, infinite */
    const double bad[4] = {0.0, -1.0, NAN, INFINITY};
    for (int k = 0; k < 4; ++k) {
        scale[7] = bad[k];
        CHECK_STATUS(cf_edge_poisson_set_metric_scaled(b, p, scale), CF_ERR_INVALID_ARG);
        CHECK(strstr(cf_context_message(ctx), "face 7") != NULL);
    }
    CHECK_STATUS(cf_edge_poisson_set_metric_scaled(NULL, p, scale), CF_ERR_INVALID_ARG);
    cf_edge_poisson_destroy(&a);
    cf_edge_poisson_destroy(&b);
    free(of_heavy);
    free(scale);
    free(x);
    free(y);
    free(e);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

typedef struct sweep_data {
    const cf_mesh *mesh;
    int32_t nk;
    const int32_t *known;
} sweep_data;

static cf_status create_and_free(cf_context *ctx, void *user)
{
    sweep_data *d = user;
    cf_edge_poisson *ep = NULL;
    cf_status st = cf_edge_poisson_create(ctx, d->mesh, NULL, d->nk, d->known, &ep);
    if (st == CF_OK && !ep) st = CF_ERR_NUMERICAL;
    cf_edge_poisson_destroy(&ep);
    return st;
}

static void test_invalid_and_allocation(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_grid(ctx, 4, 4, 1.0, 1.0, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    cf_edge_poisson *ep = NULL;
    CHECK_STATUS(cf_edge_poisson_create(ctx, NULL, NULL, 0, NULL, &ep), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_edge_poisson_create(ctx, mesh, NULL, 2, NULL, &ep), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_edge_poisson_create(ctx, mesh, NULL, nv, NULL, &ep), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "known vertices") != NULL);
    int32_t twice[2] = {3, 3};
    CHECK(cf_edge_poisson_create(ctx, mesh, NULL, 2, twice, &ep) != CF_OK);
    CHECK(ep == NULL);
    CHECK(isnan(cf_edge_closure_error(NULL, NULL, NULL)));
    cf_edge_poisson_destroy(NULL);
    int32_t known[2] = {0, 5};
    sweep_data d = {mesh, 0, NULL};
    cft_allocation_sweep(ctx, "edge_poisson free", create_and_free, &d, 1);
    d.nk = 2;
    d.known = known;
    cft_allocation_sweep(ctx, "edge_poisson fixed", create_and_free, &d, 1);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* A frozen metric (spin-willmore's input-metric solver) frees the refill
 * data: solves give the same result bit for bit and the bytes in use fall;
 * a later set_metric rebuilds the data (the bytes back) and gives the same
 * solves as a solver never frozen, bit for bit; out of memory there is
 * reported and leaves the solver frozen and usable. */
static void test_freeze_metric(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.2, 7, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *e = edges_of(mesh, cf_mesh_positions(mesh));
    for (int32_t k = 0; k < cf_mesh_edge_count(mesh); ++k) e[3 * k] += 0.01 * (double)(k % 5);
    double *x = malloc(3 * (size_t)nv * sizeof(double)), *y = malloc(3 * (size_t)nv * sizeof(double));
    cf_edge_poisson *a = NULL, *b = NULL;
    CHECK_OK(ctx, cf_edge_poisson_create(ctx, mesh, NULL, 0, NULL, &a));
    CHECK_OK(ctx, cf_edge_poisson_create(ctx, mesh, NULL, 0, NULL, &b));
    size_t before = cf_context_bytes_in_use(ctx);
    cf_edge_poisson_freeze_metric(b);
    cf_edge_poisson_freeze_metric(b); /* a second call does nothing */
    size_t after = cf_context_bytes_in_use(ctx);
    fprintf(stderr, "   freeze: %zu bytes freed (%d faces)\n", before - after, cf_mesh_face_count(mesh));
    CHECK(after < before);
    CHECK_OK(ctx, cf_edge_poisson_solve_from(a, cf_mesh_positions(mesh), e, NULL, x, NULL));
    CHECK_OK(ctx, cf_edge_poisson_solve_from(b, cf_mesh_positions(mesh), e, NULL, y, NULL));
    CHECK(memcmp(x, y, 3 * (size_t)nv * sizeof(double)) == 0);
    /* another metric: the bumpy sphere scaled along z (not a conformal map) */
    double *p2 = malloc(3 * (size_t)nv * sizeof(double));
    memcpy(p2, cf_mesh_positions(mesh), 3 * (size_t)nv * sizeof(double));
    for (int32_t i = 0; i < nv; ++i) p2[3 * i + 2] *= 1.7;
    cf_context_fail_allocation(ctx, 1, 0);
    CHECK_STATUS(cf_edge_poisson_set_metric(b, p2), CF_ERR_NOMEM);
    cf_context_fail_allocation(ctx, 0, 0);
    CHECK(cf_context_bytes_in_use(ctx) == after);
    CHECK_OK(ctx, cf_edge_poisson_solve_from(b, cf_mesh_positions(mesh), e, NULL, y, NULL));
    CHECK(memcmp(x, y, 3 * (size_t)nv * sizeof(double)) == 0);
    CHECK_OK(ctx, cf_edge_poisson_set_metric(b, p2));
    CHECK(cf_context_bytes_in_use(ctx) == before);
    CHECK_OK(ctx, cf_edge_poisson_set_metric(a, p2));
    CHECK_OK(ctx, cf_edge_poisson_solve_from(a, p2, e, NULL, x, NULL));
    CHECK_OK(ctx, cf_edge_poisson_solve_from(b, p2, e, NULL, y, NULL));
    CHECK(memcmp(x, y, 3 * (size_t)nv * sizeof(double)) == 0);
    free(p2);
    cf_edge_poisson_destroy(&a);
    cf_edge_poisson_destroy(&b);
    free(e);
    free(x);
    free(y);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_integrable_edges_closed);
    CFT_RUN(test_fixed_values_and_sign);
    CFT_RUN(test_metric);
    CFT_RUN(test_metric_scaled);
    CFT_RUN(test_solve_from);
    CFT_RUN(test_invalid_and_allocation);
    CFT_RUN(test_freeze_metric);
    return cft_finish();
}
