/* cf_mips_energy and cf_tangential_relaxation (ops/tangential_relaxation.c):
 * the energy is the area-weighted sum of (Q + 1 / Q) / 2 of the metrics'
 * own Q face by face, sum A0 at a similarity, its gradient matches central
 * differences; the relaxation lowers it and the mean Q of a non-conformal
 * map of the sphere onto itself (back to the identity, call after call), keeps every vertex on the surface it was given and every face's
 * orientation, holds boundary vertices, leaves a map below its threshold
 * and the identity alone, and bad input fails cleanly. */
#include "curvflow/generate.h"
#include "curvflow/metrics.h"
#include "curvflow/ops.h"
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* uniform in [-1, 1], reproducible */
static double noise(uint32_t *state)
{
    *state = *state * 1664525u + 1013904223u;
    return (double)(*state >> 8) / (double)(1u << 23) - 1.0;
}

/* (b - a) x (c - a) of face f at x: twice its area along its normal */
static void face_normal(const cf_mesh *mesh, const double *x, int32_t f, double n[3])
{
    const int32_t *t = cf_mesh_triangles(mesh) + 3 * f;
    const double *a = x + 3 * t[0], *b = x + 3 * t[1], *c = x + 3 * t[2];
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * v[2] - u[2] * v[1], n[1] = u[2] * v[0] - u[0] * v[2], n[2] = u[0] * v[1] - u[1] * v[0];
}

static double face_area(const cf_mesh *mesh, const double *x, int32_t f)
{
    double n[3];
    face_normal(mesh, x, f, n);
    return 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

static double area_total(const cf_mesh *mesh, const double *x)
{
    double total = 0.0;
    for (int32_t f = 0; f < cf_mesh_face_count(mesh); ++f) total += face_area(mesh, x, f);
    return total;
}

/* The unit sphere with its latitudes moved: polar angle t -> t + a sin 2t
 * (poles and equator stay): a smooth map of the sphere onto itself that is
 * not conformal (meridians and parallels stretch differently). */
static void remap_latitudes(int32_t nv, const double *p, double a, double *out)
{
    for (int32_t i = 0; i < nv; ++i) {
        const double *x = p + 3 * i;
        double t = acos(fmax(-1.0, fmin(1.0, x[2]))), phi = atan2(x[1], x[0]), u = t + a * sin(2.0 * t);
        out[3 * i] = sin(u) * cos(phi);
        out[3 * i + 1] = sin(u) * sin(phi);
        out[3 * i + 2] = cos(u);
    }
}

/* area-weighted mean Q of the map from the rest positions to x */
static double mean_q(cf_context *ctx, const cf_mesh *mesh, const double *x)
{
    int32_t nf = cf_mesh_face_count(mesh);
    double *q = malloc((size_t)nf * sizeof(double));
    cf_stats stats;
    CHECK_OK(ctx, cf_quasi_conformal_error(ctx, mesh, cf_mesh_positions(mesh), x, q, &stats));
    free(q);
    return stats.weighted_mean;
}

static void test_energy_against_q_and_similarity(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh), nf = cf_mesh_face_count(mesh);
    const double *p = cf_mesh_positions(mesh);
    double a0 = area_total(mesh, p), e = 0.0;
    /* a similarity: rotated about z, scaled by 3, moved */
    double *x = malloc(3 * (size_t)nv * sizeof(double));
    double c = cos(0.7), s = sin(0.7);
    for (int32_t i = 0; i < nv; ++i) {
        const double *v = p + 3 * i;
        x[3 * i] = 3.0 * (c * v[0] - s * v[1]) + 1.0;
        x[3 * i + 1] = 3.0 * (s * v[0] + c * v[1]) - 2.0;
        x[3 * i + 2] = 3.0 * v[2] + 0.5;
    }
    CHECK_OK(ctx, cf_mips_energy(ctx, mesh, NULL, x, &e, NULL));
    CHECK_NEAR(e, a0, 1e-13, 0.0);
    /* a distorted map: E = sum A0 (Q + 1 / Q) / 2 with the metrics' Q */
    uint32_t seed = 11u;
    for (int32_t i = 0; i < 3 * nv; ++i) x[i] = p[i] + 0.05 * noise(&seed);
    double *q = malloc((size_t)nf * sizeof(double));
    cf_stats stats;
    CHECK_OK(ctx, cf_quasi_conformal_error(ctx, mesh, p, x, q, &stats));
    double expected = 0.0;
    for (int32_t f = 0; f < nf; ++f) expected += face_area(mesh, p, f) * 0.5 * (q[f] + 1.0 / q[f]);
    CHECK_OK(ctx, cf_mips_energy(ctx, mesh, NULL, x, &e, NULL));
    CHECK_NEAR(e, expected, 1e-12, 0.0);
    CHECK(e > 1.001 * a0);
    free(q);
    free(x);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_gradient_central_differences(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 1, 1.0, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    const double *p = cf_mesh_positions(mesh);
    double *x = malloc(3 * (size_t)nv * sizeof(double)), *g = malloc(3 * (size_t)nv * sizeof(double));
    uint32_t seed = 5u;
    for (int32_t i = 0; i < 3 * nv; ++i) x[i] = 1.3 * p[i] + 0.08 * noise(&seed);
    double e = 0.0, gmax = 0.0, worst = 0.0;
    CHECK_OK(ctx, cf_mips_energy(ctx, mesh, NULL, x, &e, g));
    for (int32_t i = 0; i < 3 * nv; ++i) gmax = fmax(gmax, fabs(g[i]));
    const double h = 1e-6;
    for (int32_t i = 0; i < 3 * nv; ++i) {
        double keep = x[i], ep = 0.0, em = 0.0;
        x[i] = keep + h;
        CHECK_OK(ctx, cf_mips_energy(ctx, mesh, NULL, x, &ep, NULL));
        x[i] = keep - h;
        CHECK_OK(ctx, cf_mips_energy(ctx, mesh, NULL, x, &em, NULL));
        x[i] = keep;
        worst = fmax(worst, fabs((ep - em) / (2.0 * h) - g[i]));
    }
    CHECK(gmax > 0.1);
    CHECK_LE(worst, 1e-7 * gmax);
    free(x);
    free(g);
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
}

/* squared distance from p to the nearest point of any face of the surface x */
static double distance2_to_surface(const cf_mesh *mesh, const double *x, const double *p)
{
    int32_t nf = cf_mesh_face_count(mesh);
    const int32_t *t = cf_mesh_triangles(mesh);
    double best = INFINITY;
    for (int32_t f = 0; f < nf; ++f) {
        /* the closest point by a fine barycentric search is enough for a
         * bound: the plane's projection when inside, else the edges */
        const double *a = x + 3 * t[3 * f], *b = x + 3 * t[3 * f + 1], *c = x + 3 * t[3 * f + 2];
        double ab[3], ac[3], ap[3];
        for (int k = 0; k < 3; ++k) ab[k] = b[k] - a[k], ac[k] = c[k] - a[k], ap[k] = p[k] - a[k];
        double d00 = 0, d01 = 0, d11 = 0, d20 = 0, d21 = 0;
        for (int k = 0; k < 3; ++k)
            d00 += ab[k] * ab[k], d01 += ab[k] * ac[k], d11 += ac[k] * ac[k], d20 += ap[k] * ab[k], d21 += ap[k] * ac[k];
        double det = d00 * d11 - d01 * d01;
        double v = (d11 * d20 - d01 * d21) / det, w = (d00 * d21 - d01 * d20) / det;
        v = fmin(fmax(v, 0.0), 1.0), w = fmin(fmax(w, 0.0), 1.0 - v);
        double d2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            double q = a[k] + v * ab[k] + w * ac[k] - p[k];
            d2 += q * q;
        }
        best = fmin(best, d2);
    }
    return best;
}

static void test_sphere_back_to_identity(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 3, 1.0, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh), nf = cf_mesh_face_count(mesh);
    const int32_t *t = cf_mesh_triangles(mesh);
    const double *p = cf_mesh_positions(mesh);
    double *moved = malloc(3 * (size_t)nv * sizeof(double)), *out = malloc(3 * (size_t)nv * sizeof(double));
    remap_latitudes(nv, p, 0.3, moved);
    cf_tangential_relaxation *r = NULL;
    CHECK_OK(ctx, cf_tangential_relaxation_create(ctx, mesh, NULL, 1, &r));
    cf_tangential_relaxation_report rep;
    double q_before = mean_q(ctx, mesh, moved);
    CHECK_OK(ctx, cf_tangential_relaxation_apply(r, moved, 10, 1.0, out, &rep));
    double q_after = mean_q(ctx, mesh, out);
    CHECK(rep.iterations == 10 && rep.trials >= nv);
    double e = 0.0;
    CHECK_OK(ctx, cf_mips_energy(ctx, mesh, NULL, out, &e, NULL));
    CHECK_NEAR(e, rep.energy_after, 1e-12, 0.0);
    /* measured: mean Q 1.677 -> 1.428, E 14.57 -> 13.46 (sum A0 12.5) */
    CHECK(q_before > 1.6);
    CHECK_LE(q_after, 1.5);
    CHECK(rep.energy_after < 0.95 * rep.energy_before);
    /* every vertex on the surface given, every face turned as there */
    double worst = 0.0;
    for (int32_t i = 0; i < nv; ++i) worst = fmax(worst, distance2_to_surface(mesh, moved, out + 3 * i));
    CHECK_LE(sqrt(worst), 1e-13);
    for (int32_t f = 0; f < nf; ++f) {
        const double *a = out + 3 * t[3 * f], *b = out + 3 * t[3 * f + 1], *c = out + 3 * t[3 * f + 2];
        double n[3];
        face_normal(mesh, out, f, n);
        double centroid_dot = (a[0] + b[0] + c[0]) * n[0] + (a[1] + b[1] + c[1]) * n[1] + (a[2] + b[2] + c[2]) * n[2];
        CHECK(centroid_dot > 0.0); /* outward, as on the sphere */
    }
    /* call after call (out may equal in) the map goes back to the identity,
     * E's global minimum: measured mean Q 1.068 after six calls */
    for (int k = 0; k < 5; ++k) {
        double before = rep.energy_after;
        CHECK_OK(ctx, cf_tangential_relaxation_apply(r, out, 10, 1.0, out, &rep));
        CHECK_LE(rep.energy_after, before);
    }
    CHECK_LE(mean_q(ctx, mesh, out), 1.1);
    /* below the threshold nothing moves: the remapped sphere's mean
     * (Q + 1 / Q) / 2 is below that of Q = 3 */
    CHECK_OK(ctx, cf_tangential_relaxation_apply(r, moved, 10, 3.0, out, &rep));
    CHECK(rep.iterations == 0 && rep.trials == 0);
    CHECK(memcmp(out, moved, 3 * (size_t)nv * sizeof(double)) == 0);
    /* the identity is E's global minimum (every face at Q = 1): nothing moves */
    CHECK_OK(ctx, cf_tangential_relaxation_apply(r, p, 10, 1.0, out, &rep));
    CHECK(rep.iterations == 0);
    CHECK(memcmp(out, p, 3 * (size_t)nv * sizeof(double)) == 0);
    cf_tangential_relaxation_destroy(&r);
    CHECK(r == NULL);
    free(moved);
    free(out);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_held_boundary_on_a_plane(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_grid(ctx, 9, 7, 2.0, 1.5, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    const double *p = cf_mesh_positions(mesh);
    const uint8_t *on_boundary = cf_mesh_vertex_on_boundary(mesh);
    double *in = malloc(3 * (size_t)nv * sizeof(double)), *out = malloc(3 * (size_t)nv * sizeof(double));
    /* a smooth in-plane distortion of the interior (x -> x + 0.15 sin) */
    for (int32_t i = 0; i < nv; ++i) {
        in[3 * i] = p[3 * i] + (on_boundary[i] ? 0.0 : 0.15 * sin(3.0 * p[3 * i + 1]) * cos(2.0 * p[3 * i]));
        in[3 * i + 1] = p[3 * i + 1];
        in[3 * i + 2] = 0.0;
    }
    cf_tangential_relaxation *r = NULL;
    CHECK_OK(ctx, cf_tangential_relaxation_create(ctx, mesh, NULL, 1, &r));
    cf_tangential_relaxation_report rep;
    CHECK_OK(ctx, cf_tangential_relaxation_apply(r, in, 30, 1.0, out, &rep));
    CHECK(rep.iterations > 0 && rep.energy_after < rep.energy_before);
    int32_t held = 0;
    for (int32_t i = 0; i < nv; ++i) {
        CHECK(out[3 * i + 2] == 0.0); /* the plane is the surface */
        if (!on_boundary[i]) continue;
        ++held;
        CHECK(memcmp(out + 3 * i, in + 3 * i, 3 * sizeof(double)) == 0);
    }
    CHECK(held > 0);
    cf_tangential_relaxation_destroy(&r);
    free(in);
    free(out);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

typedef struct create_call {
    const cf_mesh *mesh;
} create_call;

static cf_status create_and_destroy(cf_context *ctx, void *user)
{
    const create_call *c = user;
    cf_tangential_relaxation *r = NULL;
    cf_status st = cf_tangential_relaxation_create(ctx, c->mesh, NULL, 1, &r);
    cf_tangential_relaxation_destroy(&r);
    return st;
}

/* create, then one apply above the threshold on the mesh stretched 2x
 * along z (out = in when it fails) */
static cf_status create_and_apply(cf_context *ctx, void *user)
{
    const create_call *c = user;
    int32_t nv = cf_mesh_vertex_count(c->mesh);
    double *in = malloc(3 * (size_t)nv * sizeof(double)), *out = malloc(3 * (size_t)nv * sizeof(double));
    if (!in || !out) {
        free(in);
        free(out);
        return CF_ERR_INVALID_ARG;
    }
    memcpy(in, cf_mesh_positions(c->mesh), 3 * (size_t)nv * sizeof(double));
    for (int32_t i = 0; i < nv; ++i) in[3 * i + 2] *= 2.0;
    cf_tangential_relaxation *r = NULL;
    cf_tangential_relaxation_report rep = {0, 0, 0.0, 0.0};
    cf_status st = cf_tangential_relaxation_create(ctx, c->mesh, NULL, 1, &r);
    if (st == CF_OK) st = cf_tangential_relaxation_apply(r, in, 2, 1.0, out, &rep);
    if (st == CF_OK && rep.iterations == 0) st = CF_ERR_INVALID_ARG; /* it must have relaxed */
    if (st == CF_ERR_NOMEM && r && memcmp(in, out, 3 * (size_t)nv * sizeof(double)) != 0) st = CF_ERR_INVALID_ARG;
    cf_tangential_relaxation_destroy(&r);
    free(in);
    free(out);
    return st;
}

static void test_bad_input(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 1, 1.0, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    const double *p = cf_mesh_positions(mesh);
    double *x = malloc(3 * (size_t)nv * sizeof(double));
    memcpy(x, p, 3 * (size_t)nv * sizeof(double));
    cf_tangential_relaxation *r = NULL;
    CHECK_STATUS(cf_tangential_relaxation_create(ctx, NULL, NULL, 1, &r), CF_ERR_INVALID_ARG);
    CHECK_OK(ctx, cf_tangential_relaxation_create(ctx, mesh, NULL, 1, &r));
    CHECK_STATUS(cf_tangential_relaxation_apply(r, x, -1, 1.0, x, NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_tangential_relaxation_apply(r, x, 5, 0.5, x, NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_tangential_relaxation_apply(r, x, 5, NAN, x, NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_tangential_relaxation_apply(r, NULL, 5, 1.0, x, NULL), CF_ERR_INVALID_ARG);
    x[3 * 4 + 1] = NAN;
    CHECK_STATUS(cf_tangential_relaxation_apply(r, x, 5, 1.0, x, NULL), CF_ERR_NUMERICAL);
    CHECK(strstr(cf_context_message(ctx), "vertex 4") != NULL);
    /* a face of the surface without area: named, and out is in */
    memcpy(x, p, 3 * (size_t)nv * sizeof(double));
    const int32_t *t = cf_mesh_triangles(mesh);
    memcpy(x + 3 * t[1], x + 3 * t[0], 3 * sizeof(double));
    double *out = malloc(3 * (size_t)nv * sizeof(double));
    CHECK_STATUS(cf_tangential_relaxation_apply(r, x, 5, 1.0, out, NULL), CF_ERR_DEGENERATE_FACE);
    CHECK(memcmp(out, x, 3 * (size_t)nv * sizeof(double)) == 0);
    double e = 0.0;
    CHECK_STATUS(cf_mips_energy(ctx, mesh, NULL, x, &e, NULL), CF_ERR_DEGENERATE_FACE);
    /* a degenerate reference face is named at create */
    cf_tangential_relaxation_destroy(&r);
    CHECK_STATUS(cf_tangential_relaxation_create(ctx, mesh, x, 1, &r), CF_ERR_DEGENERATE_FACE);
    CHECK(strstr(cf_context_message(ctx), "face 0") != NULL);
    CHECK(r == NULL);
    cf_tangential_relaxation_destroy(NULL);
    /* every allocation failing in turn: an error, nothing leaked */
    create_call call = {mesh};
    CHECK(cft_allocation_sweep(ctx, "tangential_relaxation_create", create_and_destroy, &call, 0) > 0);
    /* below the threshold apply makes nothing; the first call above it makes
     * the descent's arrays (each failure an error, nothing leaked, out = in) */
    CHECK_OK(ctx, cf_tangential_relaxation_create(ctx, mesh, NULL, 1, &r));
    size_t created = cf_context_bytes_in_use(ctx);
    CHECK_OK(ctx, cf_tangential_relaxation_apply(r, p, 5, 1.0, out, NULL)); /* the identity: E = sum A0 */
    CHECK(cf_context_bytes_in_use(ctx) == created);
    cf_tangential_relaxation_destroy(&r);
    CHECK(cft_allocation_sweep(ctx, "tangential_relaxation_apply", create_and_apply, &call, 0) > 0);
    free(x);
    free(out);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_energy_against_q_and_similarity);
    CFT_RUN(test_gradient_central_differences);
    CFT_RUN(test_sphere_back_to_identity);
    CFT_RUN(test_held_boundary_on_a_plane);
    CFT_RUN(test_bad_input);
    return cft_finish();
}
