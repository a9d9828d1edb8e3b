/* Smallest eigenpairs by inverse subspace iteration: path and grid graph
 * Laplacians against their closed-form spectra (path graph with n
 * vertices: 2 - 2 cos(k pi / n), eigenvector cos(k pi (i + 1/2) / n);
 * grid: sums of two path spectra), a generalised problem with a diagonal
 * mass matrix against a dense Jacobi reference, a kept factorisation,
 * determinism, non-convergence, and the single-step helper. */
#include "test.h"

#include "curvflow/generate.h"
#include "curvflow/linalg.h"
#include "curvflow/ops.h"

#include <stdlib.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

/* Unit-weight (or seeded random-weight) grid graph Laplacian, both triangles. */
static cf_sparse *grid_laplacian(cf_context *ctx, int32_t nx, int32_t ny, int random_weights)
{
    int32_t n = nx * ny;
    int64_t cap = 8 * (int64_t)n + 1;
    int32_t *r = malloc((size_t)cap * 4), *c = malloc((size_t)cap * 4);
    double *v = malloc((size_t)cap * 8);
    int64_t k = 0;
    uint64_t seed = 99;
    for (int32_t y = 0; y < ny; ++y)
        for (int32_t x = 0; x < nx; ++x) {
            int32_t i = y * nx + x;
            int32_t nb[2] = {x + 1 < nx ? i + 1 : -1, y + 1 < ny ? i + nx : -1};
            for (int d = 0; d < 2; ++d) {
                if (nb[d] < 0) continue;
                seed = seed * 6364136223846793005ull + 1442695040888963407ull;
                double w = random_weights ? 0.5 + (double)(seed >> 11) / 9007199254740992.0 : 1.0;
                int32_t j = nb[d];
                r[k] = i; c[k] = i; v[k++] = w;
                r[k] = j; c[k] = j; v[k++] = w;
                r[k] = i; c[k] = j; v[k++] = -w;
                r[k] = j; c[k] = i; v[k++] = -w;
            }
        }
    cf_sparse *a = NULL;
    if (cf_sparse_from_triplets(ctx, n, n, k, r, c, v, 1, &a, NULL) != CF_OK) a = NULL;
    free(r); free(c); free(v);
    return a;
}

static void test_path_graph(void)
{
    cf_context *ctx = cft_context();
    const int32_t n = 50, k = 4;
    cf_sparse *l = grid_laplacian(ctx, n, 1, 0);
    CHECK(l != NULL);
    if (!l) return;
    double *v = calloc((size_t)n * k, sizeof *v), lam[4];
    cf_eigen_options o;
    cf_eigen_options_default(&o);
    CHECK(o.max_iterations == 50 && o.tolerance == 1e-10 && o.shift == 0.0);
    o.shift = 1e-3; /* L is singular (constants) */
    o.max_iterations = 200;
    int32_t iters = 0;
    CHECK_OK(ctx, cf_smallest_eigenvectors(ctx, l, NULL, NULL, k, &o, v, lam, &iters));
    fprintf(stderr, "   path graph n = %d: %d iterations\n", n, iters);
    CHECK(iters > 1 && iters < 200);
    for (int32_t j = 0; j < k; ++j) {
        double exact = 2.0 - 2.0 * cos(j * PI / n);
        CHECK_NEAR(lam[j], exact, 0.0, 1e-8);
        /* eigenvector: cos(j pi (i + 1/2) / n), unit-normalised; compare |<v, u>| = 1 */
        double dot = 0.0, nu = 0.0;
        for (int32_t i = 0; i < n; ++i) {
            double u = cos(j * PI * (i + 0.5) / n);
            dot += u * v[(size_t)j * n + i];
            nu += u * u;
        }
        CHECK_NEAR(fabs(dot) / sqrt(nu), 1.0, 0.0, 1e-8);
    }
    /* orthonormal output */
    for (int32_t a = 0; a < k; ++a)
        for (int32_t b = 0; b <= a; ++b)
            CHECK_NEAR(cf_dot(n, v + (size_t)a * n, v + (size_t)b * n, NULL), a == b ? 1.0 : 0.0, 0.0, 1e-12);
    /* deterministic default start: a second run gives the same bits */
    double *v2 = calloc((size_t)n * k, sizeof *v2), lam2[4];
    CHECK_OK(ctx, cf_smallest_eigenvectors(ctx, l, NULL, NULL, k, &o, v2, lam2, NULL));
    CHECK(memcmp(v, v2, (size_t)n * k * sizeof *v) == 0);
    /* too few iterations: NOT_CONVERGED, last iterate returned */
    memset(v2, 0, (size_t)n * k * sizeof *v2);
    o.max_iterations = 2;
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    CHECK_STATUS(cf_smallest_eigenvectors(ctx, l, NULL, NULL, k, &o, v2, lam2, &iters), CF_ERR_NOT_CONVERGED);
    CHECK(iters == 2);
    CHECK_STATUS(cf_smallest_eigenvectors(ctx, l, NULL, NULL, 0, &o, v2, lam2, &iters), CF_ERR_INVALID_ARG);
    free(v); free(v2);
    cf_sparse_destroy(&l);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* 12 x 7 grid: spectrum {(2 - 2 cos(a pi / 12)) + (2 - 2 cos(b pi / 7))};
 * the four smallest are (0,0), (1,0), (0,1), (1,1) (0.2662 < (2,0) = 0.2679). Uses a factorisation
 * the caller keeps. */
static void test_grid_with_kept_factorisation(void)
{
    cf_context *ctx = cft_context();
    const int32_t nx = 12, ny = 7, n = nx * ny, k = 4;
    cf_sparse *l = grid_laplacian(ctx, nx, ny, 0);
    CHECK(l != NULL);
    if (!l) return;
    const double shift = 1e-2;
    cf_cholesky *chol = NULL;
    CHECK_OK(ctx, cf_cholesky_create(ctx, l, NULL, &chol));
    CHECK_OK(ctx, cf_cholesky_factorize_shifted(chol, l, shift));
    double *v = calloc((size_t)n * k, sizeof *v), lam[4];
    cf_eigen_options o;
    cf_eigen_options_default(&o);
    o.shift = shift;
    o.max_iterations = 300;
    CHECK_OK(ctx, cf_smallest_eigenvectors(ctx, l, NULL, chol, k, &o, v, lam, NULL));
    double px1 = 2.0 - 2.0 * cos(PI / nx), py1 = 2.0 - 2.0 * cos(PI / ny), px2 = 2.0 - 2.0 * cos(2.0 * PI / nx);
    CHECK(px1 + py1 < px2);
    double exact[4] = {0.0, px1, py1, px1 + py1};
    for (int32_t j = 0; j < k; ++j) CHECK_NEAR(lam[j], exact[j], 0.0, 1e-8);
    cf_cholesky_destroy(&chol);
    free(v);
    cf_sparse_destroy(&l);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Dense Jacobi for the reference spectrum of M^-1/2 L M^-1/2. */
static void dense_symmetric_eigenvalues(int32_t n, double *h, double *lam)
{
    for (int sweep = 0; sweep < 100; ++sweep) {
        double off = 0.0;
        for (int32_t j = 0; j < n; ++j)
            for (int32_t i = 0; i < n; ++i)
                if (i != j) off += h[j * n + i] * h[j * n + i];
        if (off < 1e-30) break;
        for (int32_t p = 0; p < n; ++p)
            for (int32_t q = p + 1; q < n; ++q) {
                double apq = h[q * n + p];
                if (apq == 0.0) continue;
                double theta = (h[q * n + q] - h[p * n + p]) / (2.0 * apq);
                double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (int32_t i = 0; i < n; ++i) {
                    double hp = h[p * n + i], hq = h[q * n + i];
                    h[p * n + i] = c * hp - s * hq;
                    h[q * n + i] = s * hp + c * hq;
                }
                for (int32_t i = 0; i < n; ++i) {
                    double hp = h[i * n + p], hq = h[i * n + q];
                    h[i * n + p] = c * hp - s * hq;
                    h[i * n + q] = s * hp + c * hq;
                }
            }
    }
    for (int32_t i = 0; i < n; ++i) lam[i] = h[i * n + i];
    for (int32_t i = 0; i < n; ++i) /* sort */
        for (int32_t j = i + 1; j < n; ++j)
            if (lam[j] < lam[i]) { double t = lam[i]; lam[i] = lam[j]; lam[j] = t; }
}

static void test_generalised_with_mass(void)
{
    cf_context *ctx = cft_context();
    const int32_t nx = 6, ny = 5, n = nx * ny, k = 3;
    cf_sparse *l = grid_laplacian(ctx, nx, ny, 1);
    CHECK(l != NULL);
    if (!l) return;
    double m[30];
    for (int32_t i = 0; i < n; ++i) m[i] = 0.5 + 0.05 * ((i * 7) % 11);
    double *h = calloc((size_t)n * n, sizeof *h), ref[30];
    for (int32_t j = 0; j < n; ++j)
        for (int32_t p = l->colptr[j]; p < l->colptr[j + 1]; ++p)
            h[(size_t)j * n + l->rowind[p]] += l->values[p] / sqrt(m[j] * m[l->rowind[p]]);
    dense_symmetric_eigenvalues(n, h, ref);
    double *v = calloc((size_t)n * k, sizeof *v), lam[3];
    cf_eigen_options o;
    cf_eigen_options_default(&o);
    o.shift = 1e-2;
    o.max_iterations = 300;
    CHECK_OK(ctx, cf_smallest_eigenvectors(ctx, l, m, NULL, k, &o, v, lam, NULL));
    for (int32_t j = 0; j < k; ++j) CHECK_NEAR(lam[j], ref[j], 0.0, 1e-8);
    /* M-orthonormal */
    for (int32_t a = 0; a < k; ++a)
        for (int32_t b = 0; b <= a; ++b)
            CHECK_NEAR(cf_dot(n, v + (size_t)a * n, v + (size_t)b * n, m), a == b ? 1.0 : 0.0, 0.0, 1e-12);
    /* the Rayleigh quotient of each returned vector is its eigenvalue */
    double work[30];
    for (int32_t j = 0; j < k; ++j) CHECK_NEAR(cf_rayleigh_quotient(l, m, v + (size_t)j * n, work), lam[j], 0.0, 1e-12);
    free(h); free(v);
    cf_sparse_destroy(&l);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* The single-step helper with a kept factorisation of L + I on a path:
 * iterating converges to the constant vector (eigenvalue 0) at the rate
 * (0 + 1) / (lambda_1 + 1) per step. */
static void test_single_step_helper(void)
{
    cf_context *ctx = cft_context();
    const int32_t n = 10;
    cf_sparse *l = grid_laplacian(ctx, n, 1, 0);
    CHECK(l != NULL);
    if (!l) return;
    cf_cholesky *chol = NULL;
    CHECK_OK(ctx, cf_cholesky_create(ctx, l, NULL, &chol));
    CHECK_OK(ctx, cf_cholesky_factorize_shifted(chol, l, 1.0));
    double v[10], work[10];
    for (int32_t i = 0; i < n; ++i) v[i] = 1.0 + 0.3 * i; /* not orthogonal to the constants */
    int32_t rank = 0;
    int64_t before = cf_context_allocation_count(ctx);
    /* rate (1 / (1 + 0.0979))^it: 400 steps reach ~1e-16 */
    for (int it = 0; it < 400; ++it) CHECK_OK(ctx, cf_inverse_iteration_step(chol, NULL, 1, v, work, &rank));
    CHECK(cf_context_allocation_count(ctx) == before); /* no allocation in the loop */
    CHECK(rank == 1);
    CHECK_NEAR(cf_rayleigh_quotient(l, NULL, v, work), 0.0, 0.0, 1e-12);
    CHECK_NEAR(fabs(v[0]), 1.0 / sqrt((double)n), 0.0, 1e-8);
    cf_cholesky_destroy(&chol);
    cf_sparse_destroy(&l);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_allocation_failures(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    cf_sparse *l = grid_laplacian(ctx, 8, 1, 0);
    size_t base = cf_context_bytes_in_use(ctx);
    cf_eigen_options o;
    cf_eigen_options_default(&o);
    o.shift = 0.1;
    o.max_iterations = 200;
    int succeeded = 0, failures = 0, wrong = 0;
    for (int64_t k = 1; k < 200 && !succeeded; ++k) {
        double v[16] = {0}, lam[2];
        cf_context_fail_allocation(ctx, k, 0);
        cf_status st = cf_smallest_eigenvectors(ctx, l, NULL, NULL, 2, &o, v, lam, NULL);
        if (st == CF_OK) succeeded = 1;
        else if (st == CF_ERR_NOMEM) ++failures;
        else ++wrong;
        if (cf_context_bytes_in_use(ctx) != base) ++wrong;
    }
    cf_context_fail_allocation(ctx, 0, 0);
    CHECK(succeeded);
    CHECK(failures > 5);
    CHECK(wrong == 0);
    cf_sparse_destroy(&l);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Unit sphere: the smallest eigenvalues of -Delta are 0 and 2 (l = 1,
 * three-fold). On icospheres with the cotan L and barycentric M:
 * lambda_0 = 0 to rounding; lambda_1..3 exactly degenerate (the l = 1
 * harmonics span an irreducible representation of the icosahedral group,
 * so the discrete operator keeps the triple eigenvalue up to rounding); and
 * |lambda_1 - 2| falls at least second order under refinement (observed
 * 9.2e-5, 8.1e-6, 6.4e-7: ratio 11-13 per level for halving h). */
static void test_sphere_spectrum(void)
{
    cf_context *ctx = cft_context();
    double err[3] = {0};
    for (int32_t s = 2; s <= 4; ++s) {
        cf_mesh *mesh = NULL;
        CHECK_OK(ctx, cf_generate_icosphere(ctx, s, 1.0, &mesh));
        if (!mesh) break;
        int32_t n = cf_mesh_vertex_count(mesh);
        cf_sparse *l = NULL;
        double *area = malloc((size_t)n * sizeof *area), *v = calloc((size_t)n * 4, sizeof *v), lam[4] = {0};
        CHECK_OK(ctx, cf_cotan_laplacian(ctx, mesh, cf_mesh_positions(mesh), &l));
        CHECK_OK(ctx, cf_vertex_areas(ctx, mesh, cf_mesh_positions(mesh), CF_DUAL_AREA_BARYCENTRIC, area));
        cf_eigen_options o;
        cf_eigen_options_default(&o);
        o.shift = 1e-2;
        o.max_iterations = 300;
        if (l) CHECK_OK(ctx, cf_smallest_eigenvectors(ctx, l, area, NULL, 4, &o, v, lam, NULL));
        CHECK_NEAR(lam[0], 0.0, 0.0, 1e-12);
        CHECK_NEAR(lam[2], lam[1], 1e-12, 0.0);
        CHECK_NEAR(lam[3], lam[1], 1e-12, 0.0);
        err[s - 2] = fabs(lam[1] - 2.0);
        free(area); free(v);
        cf_sparse_destroy(&l);
        cf_mesh_destroy(&mesh);
    }
    CHECK_LE(err[0], 1e-3);
    CHECK(err[1] > 0.0 && err[2] > 0.0);
    CHECK_LE(4.0 * err[1], err[0]); /* at least second order */
    CHECK_LE(4.0 * err[2], err[1]);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_path_graph);
    CFT_RUN(test_grid_with_kept_factorisation);
    CFT_RUN(test_generalised_with_mass);
    CFT_RUN(test_single_step_helper);
    CFT_RUN(test_sphere_spectrum);
    CFT_RUN(test_allocation_failures);
    return cft_finish();
}
