/*
 * The Dirac matrix X(rho) in its two forms (dirac.c): the complex form,
 * filled straight from the faces, holds exactly the values the real form's
 * conversion (cf_cholesky quaternion_blocks) factorises, so the solves are
 * bit for bit the same; its product equals the real form's bit for bit at
 * rho = 0 (the lower blocks then are exact conjugates) and to rounding
 * otherwise, and so does the Rayleigh quotient; and it takes far less
 * memory (docs/memory.md: the reason it exists).
 * The derivative of X along a change of rho applied to lambda, assembled
 * face by face (cfi_dirac_rho_derivative, the Jacobian of the period
 * corrections): against central differences of the filled matrix in both
 * forms (exact for a quadratic, any step) and one-sided differences; for
 * several directions at once, bit for bit each direction's own.
 * The derivative of the transformed edges along changes of lambda
 * (cfi_spin_transform_edges_derivative, the periods' Jacobian since session
 * 33, which took two edge transforms per direction before): against central
 * differences of cfi_spin_transform_edges (exact for a quadratic), on a
 * block of edges and for several directions.
 */
#include "test.h"

#include "curvflow/generate.h"
#include "curvflow/linalg.h"
#include "methods/spin_willmore/spin_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static double rel_diff(const double *a, const double *b, int64_t n)
{
    double d = 0.0, big = 0.0;
    for (int64_t i = 0; i < n; ++i) {
        d = fmax(d, fabs(a[i] - b[i]));
        big = fmax(big, fabs(a[i]));
    }
    return d / big;
}

/* A bumpy sphere x from the icosphere and a rho of both signs: no symmetry
 * to hide behind. */
static void bumpy_fixture(const cf_mesh *mesh, double *x, double *rho)
{
    for (int32_t i = 0; i < mesh->nv; ++i) {
        const double *p = mesh->positions + 3 * i;
        double s = 1.0 + 0.1 * sin(3.0 * p[0]) * cos(2.0 * p[1] + p[2]);
        for (int c = 0; c < 3; ++c) x[3 * i + c] = s * p[c];
        rho[i] = 2.0 * sin(5.0 * p[2]) + 0.3;
    }
}

/* A lambda near 1 that varies from vertex to vertex in all four components. */
static void lambda_fixture(const cf_mesh *mesh, double *lambda)
{
    for (int32_t i = 0; i < mesh->nv; ++i) {
        const double *p = mesh->positions + 3 * i;
        for (int c = 0; c < 4; ++c) lambda[4 * i + c] = (c == 0 ? 1.0 : 0.0) + 0.3 * sin((c + 1.0) * p[c % 3] + i);
    }
}

static void test_forms_agree(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 3, 1.0, &mesh));
    if (!mesh) return;
    int32_t nv = mesh->nv, n = 4 * nv;
    double *x = malloc(3 * (size_t)nv * sizeof *x), *rho = malloc((size_t)nv * sizeof *rho);
    double *area = malloc((size_t)nv * sizeof *area);
    bumpy_fixture(mesh, x, rho);
    CHECK_OK(ctx, cf_vertex_areas(ctx, mesh, x, CF_DUAL_AREA_BARYCENTRIC, area));
    size_t base = cf_context_bytes_in_use(ctx);
    cfi_dirac *real = NULL, *cplx = NULL;
    CHECK_OK(ctx, cfi_dirac_create_form(ctx, mesh, 0, &real));
    size_t real_bytes = cf_context_bytes_in_use(ctx) - base;
    CHECK_OK(ctx, cfi_dirac_create_form(ctx, mesh, 1, &cplx));
    size_t cplx_bytes = cf_context_bytes_in_use(ctx) - base - real_bytes;
    if (!real || !cplx) return;
    CHECK(real->x != NULL && real->z == NULL && cplx->z != NULL && cplx->x == NULL);
    /* real: 16 (nv + 2 ne) values and row indices (12 bytes each) plus 36
     * int64 slots per face; complex: 4 ne + 3 nv complex entries (20 bytes)
     * plus one int32 per edge and per vertex: with ne = 3 nv, nf = 2 nv,
     * 316 vs 1344 + 576 bytes per vertex, 0.165 (and the real form's
     * factorisation needed a complex copy on top) */
    fprintf(stderr, "   Dirac matrix of %d vertices: real form %zu bytes, complex form %zu bytes\n", nv, real_bytes,
            cplx_bytes);
    CHECK_LE((double)cplx_bytes, 0.2 * (double)real_bytes);

    double *b = malloc((size_t)n * sizeof *b), *xr = malloc((size_t)n * sizeof *xr),
           *xz = malloc((size_t)n * sizeof *xz), *w = malloc((size_t)n * sizeof *w);
    for (int32_t i = 0; i < n; ++i) b[i] = cos(0.37 * i) + (i % 4 == 0);
    for (int with_rho = 0; with_rho < 2; ++with_rho) {
        const double *r = with_rho ? rho : NULL;
        CHECK_OK(ctx, cfi_dirac_fill(real, mesh, x, r, 1e-3));
        CHECK_OK(ctx, cfi_dirac_fill(cplx, mesh, x, r, 1e-3));
        /* products */
        cf_sparse_multiply(real->x, b, xr);
        cf_quat_sparse_multiply(cplx->z, b, xz);
        if (!with_rho) CHECK(memcmp(xr, xz, (size_t)n * sizeof *xr) == 0);
        CHECK_LE(rel_diff(xr, xz, n), 1e-14);
        /* factorisations: the real form through quaternion_blocks, the complex one directly */
        cf_cholesky_options co;
        cf_cholesky_options_default(&co);
        co.block_size = 4;
        co.quaternion_blocks = 1;
        cf_cholesky *cr = NULL, *cz = NULL;
        CHECK_OK(ctx, cfi_dirac_analyse(ctx, real, &co, &cr));
        CHECK_OK(ctx, cfi_dirac_analyse(ctx, cplx, &co, &cz));
        CHECK_OK(ctx, cfi_dirac_factorize(real, cr));
        CHECK_OK(ctx, cfi_dirac_factorize(cplx, cz));
        CHECK_OK(ctx, cf_cholesky_solve(cr, 1, b, xr));
        CHECK_OK(ctx, cf_cholesky_solve(cz, 1, b, xz));
        CHECK(memcmp(xr, xz, (size_t)n * sizeof *xr) == 0);
        /* the eigenvalue residual: equal to rounding */
        double qr = cfi_dirac_quotient(real, area, xr, w), qz = cfi_dirac_quotient(cplx, area, xz, w);
        CHECK(isfinite(qr) && qr > 0.0);
        CHECK_NEAR(qz, qr, 1e-13, 0.0);
        if (!with_rho) CHECK(qz == qr);
        cf_cholesky_destroy(&cr);
        cf_cholesky_destroy(&cz);
    }
    cfi_dirac_destroy(ctx, &real);
    cfi_dirac_destroy(ctx, &cplx);
    CHECK(cf_context_bytes_in_use(ctx) == base);
    free(x); free(rho); free(area); free(b); free(xr); free(xz); free(w);
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
}

static void test_rho_derivative(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 3, 1.0, &mesh));
    if (!mesh) return;
    int32_t nv = mesh->nv, n = 4 * nv;
    double *x = malloc(3 * (size_t)nv * sizeof *x), *rho = malloc((size_t)nv * sizeof *rho);
    double *drho = malloc((size_t)nv * sizeof *drho), *trial = malloc((size_t)nv * sizeof *trial);
    double *lambda = malloc((size_t)n * sizeof *lambda), *direct = malloc((size_t)n * sizeof *direct);
    double *plus = malloc((size_t)n * sizeof *plus), *minus = malloc((size_t)n * sizeof *minus);
    bumpy_fixture(mesh, x, rho);
    lambda_fixture(mesh, lambda);
    for (int32_t i = 0; i < nv; ++i) {
        const double *p = mesh->positions + 3 * i;
        drho[i] = cos(4.0 * p[0] + p[1]) - 0.2 * p[2];
    }
    cfi_dirac_rho_derivative(mesh, x, rho, 1, drho, lambda, direct);
    for (int form = 0; form < 2; ++form) {
        cfi_dirac *d = NULL;
        CHECK_OK(ctx, cfi_dirac_create_form(ctx, mesh, form, &d));
        if (!d) continue;
        /* central differences, step 1 and 1e-3: exact for a quadratic */
        for (int hs = 0; hs < 2; ++hs) {
            double h = hs ? 1e-3 : 1.0;
            for (int32_t i = 0; i < nv; ++i) trial[i] = rho[i] + h * drho[i];
            CHECK_OK(ctx, cfi_dirac_fill(d, mesh, x, trial, 0.25));
            cfi_dirac_multiply(d, lambda, plus);
            for (int32_t i = 0; i < nv; ++i) trial[i] = rho[i] - h * drho[i];
            CHECK_OK(ctx, cfi_dirac_fill(d, mesh, x, trial, 0.25));
            cfi_dirac_multiply(d, lambda, minus);
            for (int32_t k = 0; k < n; ++k) plus[k] = (plus[k] - minus[k]) / (2.0 * h);
            double r = rel_diff(direct, plus, n);
            fprintf(stderr, "   %s form, central difference with step %g: relative difference %.2e\n",
                    form ? "complex" : "real", h, r);
            CHECK_LE(r, hs ? 1e-9 : 1e-13);
        }
        /* one-sided: first order in h, the error halving with h */
        double err[2];
        for (int hs = 0; hs < 2; ++hs) {
            double h = hs ? 5e-4 : 1e-3;
            CHECK_OK(ctx, cfi_dirac_fill(d, mesh, x, rho, 0.25));
            cfi_dirac_multiply(d, lambda, minus);
            for (int32_t i = 0; i < nv; ++i) trial[i] = rho[i] + h * drho[i];
            CHECK_OK(ctx, cfi_dirac_fill(d, mesh, x, trial, 0.25));
            cfi_dirac_multiply(d, lambda, plus);
            for (int32_t k = 0; k < n; ++k) plus[k] = (plus[k] - minus[k]) / h;
            err[hs] = rel_diff(direct, plus, n);
        }
        fprintf(stderr, "   %s form, one-sided differences: %.2e (h 1e-3), %.2e (h 5e-4)\n", form ? "complex" : "real",
                err[0], err[1]);
        CHECK(err[0] < 1e-3);
        CHECK_NEAR(err[1] / err[0], 0.5, 1e-3, 0);
        cfi_dirac_destroy(ctx, &d);
    }
    free(x); free(rho); free(drho); free(trial); free(lambda); free(direct); free(plus); free(minus);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Three directions at once: each is bit for bit its own single pass (the
 * face's shared part is the same arithmetic), so the batching changes no
 * result. */
static void test_rho_derivative_batched(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &mesh));
    if (!mesh) return;
    int32_t nv = mesh->nv, n = 4 * nv;
    double *x = malloc(3 * (size_t)nv * sizeof *x), *rho = malloc((size_t)nv * sizeof *rho);
    double *drho = malloc(3 * (size_t)nv * sizeof *drho), *lambda = malloc((size_t)n * sizeof *lambda);
    double *all = malloc(3 * (size_t)n * sizeof *all), *one = malloc((size_t)n * sizeof *one);
    bumpy_fixture(mesh, x, rho);
    lambda_fixture(mesh, lambda);
    for (int32_t i = 0; i < nv; ++i) {
        const double *p = mesh->positions + 3 * i;
        for (int l = 0; l < 3; ++l) drho[l * nv + i] = cos((l + 2.0) * p[l] + p[(l + 1) % 3]) - 0.1 * l;
    }
    cfi_dirac_rho_derivative(mesh, x, rho, 3, drho, lambda, all);
    for (int l = 0; l < 3; ++l) {
        cfi_dirac_rho_derivative(mesh, x, rho, 1, drho + l * nv, lambda, one);
        CHECK(memcmp(one, all + (int64_t)l * n, (size_t)n * sizeof *one) == 0);
        CHECK(rel_diff(one, all, n) > 1e-3 || l == 0); /* the directions differ */
    }
    free(x); free(rho); free(drho); free(lambda); free(all); free(one);
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
}

static void test_edges_derivative(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 3, 1.0, &mesh));
    if (!mesh) return;
    int32_t nv = mesh->nv, ne = mesh->ne, n = 4 * nv;
    double *x = malloc(3 * (size_t)nv * sizeof *x), *rho = malloc((size_t)nv * sizeof *rho);
    double *lambda = malloc((size_t)n * sizeof *lambda), *dl = malloc(3 * (size_t)n * sizeof *dl);
    double *trial = malloc((size_t)n * sizeof *trial), *plus = malloc(3 * (size_t)ne * sizeof *plus);
    double *minus = malloc(3 * (size_t)ne * sizeof *minus), *diff = malloc(3 * (size_t)ne * sizeof *diff);
    bumpy_fixture(mesh, x, rho);
    lambda_fixture(mesh, lambda);
    for (int32_t i = 0; i < nv; ++i) {
        const double *p = mesh->positions + 3 * i;
        for (int c = 0; c < 4; ++c)
            for (int l = 0; l < 3; ++l) dl[(int64_t)l * n + 4 * i + c] = 0.5 * cos((l + 1.0) * p[(c + l) % 3] - c + 0.7 * i);
    }
    /* edges [first, first + count) only: the block form the Jacobian uses */
    int32_t first = ne / 3, count = ne / 2;
    double *block = malloc((size_t)count * 9 * sizeof *block), *column = malloc((size_t)count * 3 * sizeof *column);
    cfi_spin_transform_edges_derivative(mesh, x, lambda, 3, dl, first, count, block);
    for (int l = 0; l < 3; ++l) {
        for (int hs = 0; hs < 2; ++hs) {
            double h = hs ? 1e-3 : 1.0; /* central differences: exact for a quadratic, any step */
            for (int32_t k = 0; k < n; ++k) trial[k] = lambda[k] + h * dl[(int64_t)l * n + k];
            cfi_spin_transform_edges(mesh, x, trial, plus);
            for (int32_t k = 0; k < n; ++k) trial[k] = lambda[k] - h * dl[(int64_t)l * n + k];
            cfi_spin_transform_edges(mesh, x, trial, minus);
            for (int32_t k = 0; k < 3 * count; ++k) {
                int64_t g = 3 * (int64_t)first + k;
                diff[k] = (plus[g] - minus[g]) / (2.0 * h);
            }
            for (int32_t e = 0; e < count; ++e)
                for (int c = 0; c < 3; ++c) column[3 * e + c] = block[9 * (int64_t)e + 3 * l + c];
            double r = rel_diff(column, diff, 3 * count);
            fprintf(stderr, "   direction %d, central difference with step %g: relative difference %.2e\n", l, h, r);
            CHECK_LE(r, hs ? 1e-9 : 1e-13);
        }
    }
    free(x); free(rho); free(lambda); free(dl); free(trial); free(plus); free(minus); free(diff); free(block);
    free(column);
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_forms_agree);
    CFT_RUN(test_rho_derivative);
    CFT_RUN(test_rho_derivative_batched);
    CFT_RUN(test_edges_derivative);
    return cft_finish();
}
