/* cf_quat_sparse, a Hermitian quaternionic matrix held only in its complex
 * form: built from a block graph, its product equals the real form's
 * (cf_sparse_multiply) bit for bit, and cf_cholesky_create_quat /
 * cf_cholesky_factorize_quat give the same solutions, bit for bit, as
 * cf_cholesky_create with quaternion_blocks on the real form (same
 * ordering, same factor) for every ordering, across refactorisations; a
 * changed pattern, NaN, mixing the two kinds of factorisation, graphs
 * without a diagonal entry or with unsorted rows are refused by name; an
 * indefinite matrix names the same column as the real form; allocation
 * failures leave nothing behind. */
#include "test.h"
#include "linalg_test_util.h"

#include "curvflow/linalg.h"
#include "curvflow/quaternion.h"

#include <stdlib.h>
#include <string.h>

/* A random Hermitian quaternionic matrix on the vertex graph of an nx x ny
 * grid with one diagonal per cell: off-diagonal blocks random quaternions,
 * diagonal blocks real, diag_extra plus the sum of the |q| of the row (so
 * positive definite for diag_extra > 0). Both forms: *real (4 nv x 4 nv,
 * both triangles) and *z (values written through the documented layout). */
typedef struct fixture {
    cf_sparse *real;
    cf_quat_sparse *z;
    int32_t nv;
} fixture;

static void fixture_free(fixture *f)
{
    cf_sparse_destroy(&f->real);
    cf_quat_sparse_destroy(&f->z);
}

/* complex entry of block (I, J), I <= J, found through the graph's column */
static int64_t block_entry(const cf_sparse *g, const cf_quat_sparse *z, int32_t I, int32_t J)
{
    for (int32_t p = g->colptr[J]; p < g->colptr[J + 1]; ++p)
        if (g->rowind[p] == I) return z->colptr[2 * J] + 2 * (int64_t)(p - g->colptr[J]);
    return -1;
}

static int make_fixture(cf_context *ctx, int32_t nx, int32_t ny, double diag_extra, fixture *f)
{
    memset(f, 0, sizeof *f);
    int32_t nv = nx * ny;
    f->nv = nv;
    int32_t ne_max = 3 * nv;
    int32_t *ei = malloc((size_t)ne_max * sizeof *ei), *ej = malloc((size_t)ne_max * sizeof *ej);
    int32_t ne = 0;
    for (int32_t y = 0; y < ny; ++y)
        for (int32_t x = 0; x < nx; ++x) {
            int32_t i = y * nx + x;
            if (x + 1 < nx) { ei[ne] = i; ej[ne++] = i + 1; }
            if (y + 1 < ny) { ei[ne] = i; ej[ne++] = i + nx; }
            if (x + 1 < nx && y + 1 < ny) { ei[ne] = i + 1; ej[ne++] = i + nx; }
        }
    /* graph: both triangles and the diagonal */
    int64_t ng = 2 * (int64_t)ne + nv;
    int32_t *gr = malloc((size_t)ng * sizeof *gr), *gc = malloc((size_t)ng * sizeof *gc);
    int64_t k = 0;
    for (int32_t e = 0; e < ne; ++e) {
        gr[k] = ei[e]; gc[k++] = ej[e];
        gr[k] = ej[e]; gc[k++] = ei[e];
    }
    for (int32_t i = 0; i < nv; ++i) { gr[k] = i; gc[k++] = i; }
    cf_sparse *g = NULL;
    int ok = cf_sparse_from_triplets(ctx, nv, nv, ng, gr, gc, NULL, 1, &g, NULL) == CF_OK &&
             cf_quat_sparse_create(ctx, g, &f->z) == CF_OK;
    /* real form by triplets; complex values by the layout */
    int64_t nt = (int64_t)ne * 32 + (int64_t)nv * 4;
    int32_t *tr = malloc((size_t)nt * sizeof *tr), *tc = malloc((size_t)nt * sizeof *tc);
    double *tv = malloc((size_t)nt * sizeof *tv), *dsum = calloc((size_t)nv, sizeof *dsum);
    k = 0;
    for (int32_t e = 0; ok && e < ne; ++e) {
        int32_t I = ei[e] < ej[e] ? ei[e] : ej[e], J = ei[e] < ej[e] ? ej[e] : ei[e];
        cf_quat q = {rng_unit(), rng_unit(), rng_unit(), rng_unit()};
        double lq[16];
        cf_quat_left_matrix(q, lq); /* row-major */
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) {
                tr[k] = 4 * I + r; tc[k] = 4 * J + c; tv[k++] = lq[4 * r + c];
                tr[k] = 4 * J + c; tc[k] = 4 * I + r; tv[k++] = lq[4 * r + c];
            }
        double mag = sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
        dsum[I] += mag;
        dsum[J] += mag;
        int64_t d0 = block_entry(g, f->z, I, J);
        int64_t d2 = d0 + (f->z->colptr[2 * J + 1] - f->z->colptr[2 * J]);
        double *v = f->z->values;
        /* [[a + b i, -c - d i], [c - d i, a - b i]] */
        v[2 * d0] = q.w; v[2 * d0 + 1] = q.x;
        v[2 * d0 + 2] = q.y; v[2 * d0 + 3] = -q.z;
        v[2 * d2] = -q.y; v[2 * d2 + 1] = -q.z;
        v[2 * d2 + 2] = q.w; v[2 * d2 + 3] = -q.x;
    }
    for (int32_t i = 0; ok && i < nv; ++i) {
        double a = dsum[i] + diag_extra;
        for (int c = 0; c < 4; ++c) { tr[k] = 4 * i + c; tc[k] = 4 * i + c; tv[k++] = a; }
        int64_t d0 = block_entry(g, f->z, i, i);
        int64_t d2 = d0 + (f->z->colptr[2 * i + 1] - f->z->colptr[2 * i]);
        f->z->values[2 * d0] = a;
        f->z->values[2 * d2 + 2] = a;
    }
    /* the real form stores the dense 4 x 4 blocks whole (zeros of the diagonal blocks too) */
    int64_t nt2 = k + (int64_t)nv * 16;
    int32_t *tr2 = malloc((size_t)nt2 * sizeof *tr2), *tc2 = malloc((size_t)nt2 * sizeof *tc2);
    double *tv2 = malloc((size_t)nt2 * sizeof *tv2);
    memcpy(tr2, tr, (size_t)k * sizeof *tr2);
    memcpy(tc2, tc, (size_t)k * sizeof *tc2);
    memcpy(tv2, tv, (size_t)k * sizeof *tv2);
    int64_t k2 = k;
    for (int32_t i = 0; i < nv; ++i)
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 4; ++c) { tr2[k2] = 4 * i + r; tc2[k2] = 4 * i + c; tv2[k2++] = 0.0; }
    ok = ok && cf_sparse_from_triplets(ctx, 4 * nv, 4 * nv, k2, tr2, tc2, tv2, 1, &f->real, NULL) == CF_OK;
    cf_sparse_destroy(&g);
    free(ei); free(ej); free(gr); free(gc); free(tr); free(tc); free(tv); free(dsum);
    free(tr2); free(tc2); free(tv2);
    if (!ok) fixture_free(f);
    return ok;
}

static cf_cholesky_options options(int quaternion, cf_ordering ordering)
{
    cf_cholesky_options o;
    cf_cholesky_options_default(&o);
    o.block_size = 4;
    o.quaternion_blocks = quaternion;
    o.ordering = ordering;
    return o;
}

static void test_layout_and_product(void)
{
    cf_context *ctx = cft_context();
    rng_seed(3);
    fixture f;
    CHECK(make_fixture(ctx, 5, 4, 0.5, &f));
    if (!f.z) return;
    int32_t n = 4 * f.nv;
    /* 5 x 4 grid: 16 horizontal + 15 vertical + 12 diagonal edges = 43 upper blocks, 20 diagonal ones */
    CHECK(cf_quat_sparse_nnz(f.z) == 4 * 43 + 3 * 20);
    CHECK(f.z->colptr[0] == 0 && f.z->colptr[1] == 1 && f.z->colptr[2] == 3); /* block column 0: its diagonal only */
    double *x = malloc((size_t)n * sizeof *x), *yr = malloc((size_t)n * sizeof *yr), *yz = malloc((size_t)n * sizeof *yz);
    for (int32_t i = 0; i < n; ++i) x[i] = rng_unit();
    cf_sparse_multiply(f.real, x, yr);
    cf_quat_sparse_multiply(f.z, x, yz);
    CHECK(memcmp(yr, yz, (size_t)n * sizeof *yr) == 0);
    double worst = 0.0;
    for (int32_t i = 0; i < n; ++i) worst = fmax(worst, fabs(yr[i] - yz[i]));
    CHECK_NEAR(worst, 0.0, 0.0, 0.0);
    free(x); free(yr); free(yz);
    fixture_free(&f);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_same_factor_as_real_form(void)
{
    cf_context *ctx = cft_context();
    rng_seed(5);
    fixture f;
    CHECK(make_fixture(ctx, 9, 7, 0.1, &f));
    if (!f.z) return;
    int32_t n = 4 * f.nv, nrhs = 3;
    double *b = malloc((size_t)n * nrhs * sizeof *b), *xr = malloc((size_t)n * nrhs * sizeof *xr),
           *xz = malloc((size_t)n * nrhs * sizeof *xz), *xp = malloc((size_t)n * nrhs * sizeof *xp);
    const cf_ordering orders[5] = {CF_ORDERING_AUTO, CF_ORDERING_AMD, CF_ORDERING_METIS, CF_ORDERING_NATURAL,
                                   CF_ORDERING_AUTO_REFACTORISED};
    for (int o = 0; o < 5; ++o) {
        for (int32_t i = 0; i < n * nrhs; ++i) b[i] = rng_unit();
        cf_cholesky_options oq = options(1, orders[o]), op = options(0, orders[o]);
        cf_cholesky *cr = NULL, *cz = NULL, *cp = NULL;
        CHECK_OK(ctx, cf_cholesky_create(ctx, f.real, &oq, &cr));
        CHECK_OK(ctx, cf_cholesky_create_quat(ctx, f.z, &oq, &cz));
        CHECK_OK(ctx, cf_cholesky_create(ctx, f.real, &op, &cp));
        if (!cr || !cz || !cp) break;
        CHECK(cf_cholesky_size(cz) == n);
        /* twice: a refactorisation of new values reuses the analysis */
        for (int round = 0; round < 2; ++round) {
            if (round == 1) {
                for (int64_t e = 0; e < 2 * cf_quat_sparse_nnz(f.z); ++e) f.z->values[e] *= 1.5;
                for (int64_t e = 0; e < cf_sparse_nnz(f.real); ++e) f.real->values[e] *= 1.5;
            }
            CHECK_OK(ctx, cf_cholesky_factorize(cr, f.real));
            CHECK_OK(ctx, cf_cholesky_factorize_quat(cz, f.z));
            CHECK_OK(ctx, cf_cholesky_factorize(cp, f.real));
            CHECK_OK(ctx, cf_cholesky_solve(cr, nrhs, b, xr));
            CHECK_OK(ctx, cf_cholesky_solve(cz, nrhs, b, xz));
            CHECK_OK(ctx, cf_cholesky_solve(cp, nrhs, b, xp));
            CHECK(memcmp(xr, xz, (size_t)n * nrhs * sizeof *xr) == 0);
            double diff = 0.0, big = 0.0;
            for (int32_t i = 0; i < n * nrhs; ++i) {
                diff = fmax(diff, fabs(xz[i] - xp[i]));
                big = fmax(big, fabs(xp[i]));
            }
            /* the real factorisation of the same operator, up to rounding */
            CHECK_LE(diff, 1e-10 * big);
        }
        for (int64_t e = 0; e < 2 * cf_quat_sparse_nnz(f.z); ++e) f.z->values[e] /= 1.5;
        for (int64_t e = 0; e < cf_sparse_nnz(f.real); ++e) f.real->values[e] /= 1.5;
        cf_cholesky_destroy(&cr);
        cf_cholesky_destroy(&cz);
        cf_cholesky_destroy(&cp);
    }
    free(b); free(xr); free(xz); free(xp);
    fixture_free(&f);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_refusals(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    rng_seed(7);
    fixture f, other;
    CHECK(make_fixture(ctx, 4, 4, 0.3, &f));
    CHECK(make_fixture(ctx, 4, 5, 0.3, &other));
    if (!f.z || !other.z) return;
    cf_cholesky_options o = options(1, CF_ORDERING_AUTO);
    cf_cholesky *cz = NULL, *cr = NULL;
    CHECK_OK(ctx, cf_cholesky_create_quat(ctx, f.z, &o, &cz));
    CHECK_OK(ctx, cf_cholesky_create(ctx, f.real, &o, &cr));
    /* another pattern */
    CHECK_STATUS(cf_cholesky_factorize_quat(cz, other.z), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "pattern differs") != NULL);
    /* the two kinds do not mix */
    CHECK_STATUS(cf_cholesky_factorize(cz, f.real), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "cf_cholesky_factorize_quat") != NULL);
    CHECK_STATUS(cf_cholesky_factorize_quat(cr, f.z), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "real matrix") != NULL);
    /* NaN in block (I, J) = (1, 5): named by block */
    cf_sparse *g = NULL;
    int64_t e = -1; /* entry (2 I, 2 J) = (2, 10) */
    for (int32_t p = f.z->colptr[10]; p < f.z->colptr[11]; ++p)
        if (f.z->rowind[p] == 2) e = p;
    CHECK(e >= 0);
    if (e >= 0) {
        double keep = f.z->values[2 * e + 1];
        f.z->values[2 * e + 1] = NAN;
        CHECK_STATUS(cf_cholesky_factorize_quat(cz, f.z), CF_ERR_NUMERICAL);
        CHECK(strstr(cf_context_message(ctx), "quaternion block (1, 5) is not finite") != NULL);
        f.z->values[2 * e + 1] = keep;
    }
    /* indefinite: the same column named as by the real form's quaternion factorisation */
    for (int64_t k = 0; k < 2 * cf_quat_sparse_nnz(f.z); ++k) f.z->values[k] = -f.z->values[k];
    for (int64_t k = 0; k < cf_sparse_nnz(f.real); ++k) f.real->values[k] = -f.real->values[k];
    CHECK_STATUS(cf_cholesky_factorize(cr, f.real), CF_ERR_NOT_POSDEF);
    char real_message[256];
    snprintf(real_message, sizeof real_message, "%s", cf_context_message(ctx));
    CHECK_STATUS(cf_cholesky_factorize_quat(cz, f.z), CF_ERR_NOT_POSDEF);
    CHECK(strcmp(real_message, cf_context_message(ctx)) == 0);
    CHECK(strstr(cf_context_message(ctx), "not positive definite at column") != NULL);
    double b[64] = {0}, x[64];
    CHECK_STATUS(cf_cholesky_solve(cz, 1, b, x), CF_ERR_INVALID_ARG);
    cf_cholesky_destroy(&cz);
    cf_cholesky_destroy(&cr);
    /* graphs: no diagonal entry in column 2; unsorted rows; not square */
    {
        int32_t r[5] = {0, 1, 0, 1, 3}, c[5] = {0, 1, 2, 3, 3};
        CHECK_OK(ctx, cf_sparse_from_triplets(ctx, 4, 4, 5, r, c, NULL, 0, &g, NULL));
        cf_quat_sparse *z = NULL;
        CHECK_STATUS(cf_quat_sparse_create(ctx, g, &z), CF_ERR_INVALID_ARG);
        CHECK(strstr(cf_context_message(ctx), "block column 2 has no diagonal block") != NULL);
        CHECK(z == NULL);
        cf_sparse_destroy(&g);
    }
    {
        int32_t colptr[3] = {0, 1, 3}, rowind[3] = {0, 1, 0};
        cf_sparse bad = {2, 2, colptr, rowind, NULL, 0, 0, ctx};
        cf_quat_sparse *z = NULL;
        CHECK_STATUS(cf_quat_sparse_create(ctx, &bad, &z), CF_ERR_INVALID_ARG);
        CHECK(strstr(cf_context_message(ctx), "column 1: rows not sorted (row 0 after 1)") != NULL);
        bad.nrows = 3;
        CHECK_STATUS(cf_quat_sparse_create(ctx, &bad, &z), CF_ERR_INVALID_ARG);
        CHECK(strstr(cf_context_message(ctx), "not square") != NULL);
    }
    fixture_free(&f);
    fixture_free(&other);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

typedef struct {
    const cf_sparse *graph;
    const double *b;
    double *x;
} sweep_data;

static cf_status sweep_call(cf_context *ctx, void *user)
{
    sweep_data *d = user;
    cf_cholesky_options o = options(1, CF_ORDERING_AUTO);
    cf_quat_sparse *z = NULL;
    cf_cholesky *chol = NULL;
    cf_status st = cf_quat_sparse_create(ctx, d->graph, &z);
    if (st == CF_OK) {
        /* diagonally dominant: 8 on every diagonal block, small off-diagonal ones */
        for (int32_t J = 0; J < z->nb; ++J) {
            int32_t c0 = z->colptr[2 * J], c1 = z->colptr[2 * J + 1];
            for (int32_t p = c0; p < c1; ++p) z->values[2 * p] = z->rowind[p] == 2 * J ? 8.0 : 0.5;
            z->values[2 * ((int64_t)z->colptr[2 * J + 2] - 1)] = 8.0;
        }
        st = cf_cholesky_create_quat(ctx, z, &o, &chol);
    }
    if (st == CF_OK) st = cf_cholesky_factorize_quat(chol, z);
    if (st == CF_OK) st = cf_cholesky_solve(chol, 1, d->b, d->x);
    cf_cholesky_destroy(&chol);
    cf_quat_sparse_destroy(&z);
    return st;
}

static void test_allocation_failures(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    /* path graph 0 - 1 - ... - 7 with the diagonal */
    int32_t r[22], c[22], k = 0;
    for (int32_t i = 0; i < 8; ++i) { r[k] = i; c[k++] = i; }
    for (int32_t i = 0; i + 1 < 8; ++i) { r[k] = i; c[k++] = i + 1; r[k] = i + 1; c[k++] = i; }
    cf_sparse *g = NULL;
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, 8, 8, k, r, c, NULL, 1, &g, NULL));
    double b[32], x[32];
    for (int i = 0; i < 32; ++i) b[i] = 1.0 + 0.1 * i;
    sweep_data d = {g, b, x};
    int64_t count = cft_allocation_sweep(ctx, "quaternion matrix cholesky", sweep_call, &d, 1);
    CHECK(count >= 6);
    cf_sparse_destroy(&g);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_layout_and_product);
    CFT_RUN(test_same_factor_as_real_form);
    CFT_RUN(test_refusals);
    CFT_RUN(test_allocation_failures);
    return cft_finish();
}
