/*
 * The Dirac matrix X(rho) in its two forms (dirac.c): the complex form,
 * filled straight from the faces, holds exactly the values the real form's
 * conversion (cf_cholesky quaternion_blocks) factorises, so the solves are
 * bit for bit the same; its product equals the real form's bit for bit at
 * rho = 0 (the lower blocks then are exact conjugates) and to rounding
 * otherwise, and so does the Rayleigh quotient; and it takes far less
 * memory (docs/memory.md: the reason it exists).
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

static void test_forms_agree(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 3, 1.0, &mesh));
    if (!mesh) return;
    int32_t nv = mesh->nv, n = 4 * nv;
    /* a bumpy sphere and a rho of both signs: no symmetry to hide behind */
    double *x = malloc(3 * (size_t)nv * sizeof *x), *rho = malloc((size_t)nv * sizeof *rho);
    double *area = malloc((size_t)nv * sizeof *area);
    for (int32_t i = 0; i < nv; ++i) {
        const double *p = mesh->positions + 3 * i;
        double s = 1.0 + 0.1 * sin(3.0 * p[0]) * cos(2.0 * p[1] + p[2]);
        for (int c = 0; c < 3; ++c) x[3 * i + c] = s * p[c];
        rho[i] = 2.0 * sin(5.0 * p[2]) + 0.3;
    }
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

int main(void)
{
    CFT_RUN(test_forms_agree);
    return cft_finish();
}
