/* Sparse matrices: one-pass triplet assembly (sorted rows, duplicates summed,
 * slot map refill), products with vectors, Kronecker lifting, sum,
 * transpose, sparse product and lookup, all against dense references built
 * from the same seeded random triplets; allocation-failure injection. */
#include "test.h"

#include "curvflow/linalg.h"

#include <stdlib.h>
#include <string.h>

static uint64_t rng_state;
static void rng_seed(uint64_t s) { rng_state = s * 0x9E3779B97F4A7C15ull + 1; }
static uint32_t rng_u32(void)
{
    /* xorshift64*: deterministic and platform independent */
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (uint32_t)((rng_state * 0x2545F4914F6CDD1Dull) >> 32);
}
static double rng_unit(void) { return (rng_u32() + 0.5) / 4294967296.0 * 2.0 - 1.0; }

/* Dense column-major copy of a (mirrors upper_only). */
static double *to_dense(const cf_sparse *a)
{
    double *d = calloc((size_t)a->nrows * (size_t)a->ncols + 1, sizeof *d);
    for (int32_t j = 0; j < a->ncols; ++j)
        for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p) {
            int32_t i = a->rowind[p];
            d[(size_t)j * a->nrows + i] += a->values[p];
            if (a->upper_only && i != j) d[(size_t)i * a->nrows + j] += a->values[p];
        }
    return d;
}

static int rows_sorted_unique(const cf_sparse *a)
{
    for (int32_t j = 0; j < a->ncols; ++j)
        for (int32_t p = a->colptr[j] + 1; p < a->colptr[j + 1]; ++p)
            if (a->rowind[p] <= a->rowind[p - 1]) return 0;
    return 1;
}

typedef struct triplets {
    int64_t n;
    int32_t *r, *c;
    double *v;
} triplets;

/* n random triplets in an nr x nc matrix, with many duplicates (indices
 * drawn from a small range) */
static triplets random_triplets(int32_t nr, int32_t nc, int64_t n)
{
    triplets t = {n, malloc((size_t)n * 4 + 4), malloc((size_t)n * 4 + 4), malloc((size_t)n * 8 + 8)};
    for (int64_t k = 0; k < n; ++k) {
        t.r[k] = (int32_t)(rng_u32() % (uint32_t)nr);
        t.c[k] = (int32_t)(rng_u32() % (uint32_t)nc);
        t.v[k] = rng_unit();
    }
    return t;
}
static void free_triplets(triplets *t) { free(t->r); free(t->c); free(t->v); }

static void test_from_triplets_matches_dense(void)
{
    cf_context *ctx = cft_context();
    rng_seed(1);
    const int32_t nr = 17, nc = 13;
    triplets t = random_triplets(nr, nc, 400); /* 400 triplets in 221 cells: many duplicates */
    int64_t *slots = malloc(400 * sizeof *slots);
    cf_sparse *a = NULL;
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, nr, nc, t.n, t.r, t.c, t.v, 0, &a, slots));
    CHECK(rows_sorted_unique(a));
    double *ref = calloc((size_t)nr * nc, sizeof *ref);
    for (int64_t k = 0; k < t.n; ++k) ref[(size_t)t.c[k] * nr + t.r[k]] += t.v[k];
    double *d = to_dense(a);
    double maxdiff = 0.0;
    for (int32_t k = 0; k < nr * nc; ++k) maxdiff = fmax(maxdiff, fabs(d[k] - ref[k]));
    CHECK_LE(maxdiff, 1e-14);
    /* every distinct cell appears once: nnz equals the number of touched cells */
    int64_t cells = 0;
    char *touched = calloc((size_t)nr * nc, 1);
    for (int64_t k = 0; k < t.n; ++k) touched[(size_t)t.c[k] * nr + t.r[k]] = 1;
    for (int32_t k = 0; k < nr * nc; ++k) cells += touched[k];
    CHECK(cf_sparse_nnz(a) == cells);
    /* slot map points at the triplet's cell */
    int bad = 0;
    for (int64_t k = 0; k < t.n; ++k)
        bad += a->rowind[slots[k]] != t.r[k] || slots[k] < a->colptr[t.c[k]] || slots[k] >= a->colptr[t.c[k] + 1];
    CHECK(bad == 0);
    CHECK(cf_sparse_find(a, t.r[5], t.c[5]) == slots[5]);

    /* refill with new values equals a rebuild */
    for (int64_t k = 0; k < t.n; ++k) t.v[k] = rng_unit();
    cf_sparse *b = NULL;
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, nr, nc, t.n, t.r, t.c, t.v, 0, &b, NULL));
    cf_sparse_refill(a, t.n, slots, t.v);
    CHECK(cf_sparse_nnz(a) == cf_sparse_nnz(b));
    CHECK(memcmp(a->rowind, b->rowind, (size_t)cf_sparse_nnz(a) * sizeof(int32_t)) == 0);
    maxdiff = 0.0;
    for (int64_t p = 0; p < cf_sparse_nnz(a); ++p) maxdiff = fmax(maxdiff, fabs(a->values[p] - b->values[p]));
    CHECK(maxdiff == 0.0); /* same summation order: bit-identical */

    /* pattern-only assembly */
    cf_sparse *pat = NULL;
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, nr, nc, t.n, t.r, t.c, NULL, 0, &pat, NULL));
    CHECK(cf_sparse_nnz(pat) == cells);
    CHECK(pat->values[0] == 0.0);
    cf_sparse_destroy(&pat);
    CHECK(pat == NULL);

    free(touched); free(d); free(ref); free(slots);
    cf_sparse_destroy(&a);
    cf_sparse_destroy(&b);
    free_triplets(&t);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_invalid_input(void)
{
    cf_context *ctx = cft_context();
    int32_t r[2] = {0, 3}, c[2] = {1, 1};
    double v[2] = {1.0, 2.0};
    cf_sparse *a = NULL;
    CHECK_STATUS(cf_sparse_from_triplets(ctx, 3, 3, 2, r, c, v, 0, &a, NULL), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "triplet 1") != NULL);
    r[1] = 2;
    v[1] = NAN;
    CHECK_STATUS(cf_sparse_from_triplets(ctx, 3, 3, 2, r, c, v, 0, &a, NULL), CF_ERR_NONFINITE);
    CHECK_STATUS(cf_sparse_from_triplets(ctx, 3, 3, 2, NULL, c, v, 0, &a, NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_sparse_from_triplets(ctx, 3, 4, 0, r, c, v, 1, &a, NULL), CF_ERR_INVALID_ARG);
    CHECK(a == NULL);
    /* empty matrix is fine */
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, 4, 4, 0, NULL, NULL, NULL, 1, &a, NULL));
    CHECK(cf_sparse_nnz(a) == 0);
    cf_sparse_destroy(&a);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static double max_abs_diff(const double *a, const double *b, size_t n)
{
    double m = 0.0;
    for (size_t k = 0; k < n; ++k) m = fmax(m, fabs(a[k] - b[k]));
    return m;
}

static void test_operations_match_dense(void)
{
    cf_context *ctx = cft_context();
    rng_seed(2);
    const int32_t m = 9, n = 7, q = 5;
    triplets ta = random_triplets(m, n, 30), tb = random_triplets(n, q, 20), tc = random_triplets(m, n, 25);
    cf_sparse *a = NULL, *b = NULL, *c = NULL;
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, m, n, ta.n, ta.r, ta.c, ta.v, 0, &a, NULL));
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, n, q, tb.n, tb.r, tb.c, tb.v, 0, &b, NULL));
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, m, n, tc.n, tc.r, tc.c, tc.v, 0, &c, NULL));
    double *da = to_dense(a), *db = to_dense(b), *dc = to_dense(c);

    /* y = A x and y = 2 A x - 0.5 y */
    double x[7], y[9], yref[9];
    for (int32_t j = 0; j < n; ++j) x[j] = rng_unit();
    for (int32_t i = 0; i < m; ++i) {
        yref[i] = 0.0;
        for (int32_t j = 0; j < n; ++j) yref[i] += da[j * m + i] * x[j];
    }
    cf_sparse_multiply(a, x, y);
    CHECK_LE(max_abs_diff(y, yref, (size_t)m), 1e-14);
    cf_sparse_multiply_add(a, 2.0, x, -0.5, y);
    for (int32_t i = 0; i < m; ++i) yref[i] = 1.5 * yref[i];
    CHECK_LE(max_abs_diff(y, yref, (size_t)m), 1e-14);

    /* sum */
    cf_sparse *s = NULL;
    CHECK_OK(ctx, cf_sparse_add(ctx, 2.0, a, -3.0, c, &s));
    CHECK(rows_sorted_unique(s));
    double *ds = to_dense(s);
    double md = 0.0;
    for (int32_t k = 0; k < m * n; ++k) md = fmax(md, fabs(ds[k] - (2.0 * da[k] - 3.0 * dc[k])));
    CHECK_LE(md, 1e-14);

    /* transpose */
    cf_sparse *t = NULL;
    CHECK_OK(ctx, cf_sparse_transpose(ctx, a, &t));
    CHECK(t->nrows == n && t->ncols == m && rows_sorted_unique(t));
    double *dt = to_dense(t);
    md = 0.0;
    for (int32_t i = 0; i < m; ++i)
        for (int32_t j = 0; j < n; ++j) md = fmax(md, fabs(dt[i * n + j] - da[j * m + i]));
    CHECK(md == 0.0);

    /* product */
    cf_sparse *p = NULL;
    CHECK_OK(ctx, cf_sparse_product(ctx, a, b, &p));
    CHECK(p->nrows == m && p->ncols == q && rows_sorted_unique(p));
    double *dp = to_dense(p);
    md = 0.0;
    for (int32_t i = 0; i < m; ++i)
        for (int32_t j = 0; j < q; ++j) {
            double ref = 0.0;
            for (int32_t k = 0; k < n; ++k) ref += da[k * m + i] * db[j * n + k];
            md = fmax(md, fabs(dp[j * m + i] - ref));
        }
    CHECK_LE(md, 1e-14);
    cf_sparse *bad = NULL;
    CHECK_STATUS(cf_sparse_product(ctx, a, a, &bad), CF_ERR_INVALID_ARG);
    CHECK(bad == NULL);

    /* Kronecker product with I_3: entry (i, j) -> block (3i + d, 3j + d) */
    cf_sparse *k3 = NULL;
    CHECK_OK(ctx, cf_sparse_kron_identity(ctx, a, 3, &k3));
    CHECK(k3->nrows == 3 * m && k3->ncols == 3 * n && cf_sparse_nnz(k3) == 3 * cf_sparse_nnz(a));
    CHECK(rows_sorted_unique(k3));
    double *dk = to_dense(k3);
    md = 0.0;
    for (int32_t i = 0; i < 3 * m; ++i)
        for (int32_t j = 0; j < 3 * n; ++j) {
            double ref = (i % 3 == j % 3) ? da[(j / 3) * m + i / 3] : 0.0;
            md = fmax(md, fabs(dk[(size_t)j * 3 * m + i] - ref));
        }
    CHECK(md == 0.0);

    free(da); free(db); free(dc); free(ds); free(dt); free(dp); free(dk);
    cf_sparse_destroy(&a); cf_sparse_destroy(&b); cf_sparse_destroy(&c);
    cf_sparse_destroy(&s); cf_sparse_destroy(&t); cf_sparse_destroy(&p); cf_sparse_destroy(&k3);
    free_triplets(&ta); free_triplets(&tb); free_triplets(&tc);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_upper_only(void)
{
    cf_context *ctx = cft_context();
    rng_seed(3);
    const int32_t n = 8;
    /* symmetric matrix: random triplets mirrored; keep the upper part separately */
    triplets t = random_triplets(n, n, 20);
    for (int64_t k = 0; k < t.n; ++k)
        if (t.r[k] > t.c[k]) { int32_t s = t.r[k]; t.r[k] = t.c[k]; t.c[k] = s; }
    cf_sparse *u = NULL, *full = NULL, *prod = NULL, *uu = NULL;
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, n, n, t.n, t.r, t.c, t.v, 1, &u, NULL));
    u->upper_only = 1;
    double *du = to_dense(u); /* mirrored */
    double x[8], y[8], yref[8];
    for (int32_t j = 0; j < n; ++j) x[j] = rng_unit();
    for (int32_t i = 0; i < n; ++i) {
        yref[i] = 0.0;
        for (int32_t j = 0; j < n; ++j) yref[i] += du[j * n + i] * x[j];
    }
    cf_sparse_multiply(u, x, y);
    CHECK_LE(max_abs_diff(y, yref, (size_t)n), 1e-14);
    /* product expands the triangle: U_full * U_full */
    CHECK_OK(ctx, cf_sparse_product(ctx, u, u, &prod));
    double *dp = to_dense(prod);
    double md = 0.0;
    for (int32_t i = 0; i < n; ++i)
        for (int32_t j = 0; j < n; ++j) {
            double ref = 0.0;
            for (int32_t k = 0; k < n; ++k) ref += du[k * n + i] * du[j * n + k];
            md = fmax(md, fabs(dp[j * n + i] - ref));
        }
    CHECK_LE(md, 1e-14);
    CHECK_OK(ctx, cf_sparse_add(ctx, 1.0, u, 1.0, u, &uu));
    CHECK(uu->upper_only == 1);
    CHECK_OK(ctx, cf_sparse_transpose(ctx, u, &full));
    CHECK(full->upper_only == 1 && cf_sparse_nnz(full) == cf_sparse_nnz(u));
    free(du); free(dp);
    cf_sparse_destroy(&u); cf_sparse_destroy(&full); cf_sparse_destroy(&prod); cf_sparse_destroy(&uu);
    free_triplets(&t);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Every sparse operation in sequence on the triplets `user`, for
 * cft_allocation_sweep. */
static cf_status sparse_ops_call(cf_context *ctx, void *user)
{
    const triplets *t = user;
    cf_sparse *a = NULL, *b = NULL, *p = NULL, *s = NULL, *tr = NULL, *kr = NULL;
    cf_status st = cf_sparse_from_triplets(ctx, 12, 12, t->n, t->r, t->c, t->v, 0, &a, NULL);
    if (st == CF_OK) st = cf_sparse_transpose(ctx, a, &tr);
    if (st == CF_OK) st = cf_sparse_product(ctx, a, tr, &p);
    if (st == CF_OK) st = cf_sparse_add(ctx, 1.0, a, 1.0, tr, &s);
    if (st == CF_OK) st = cf_sparse_kron_identity(ctx, s, 4, &kr);
    if (st == CF_OK) { p->upper_only = 1; st = cf_sparse_product(ctx, p, a, &b); }
    cf_sparse_destroy(&a); cf_sparse_destroy(&b); cf_sparse_destroy(&p);
    cf_sparse_destroy(&s); cf_sparse_destroy(&tr); cf_sparse_destroy(&kr);
    return st;
}

/* Fails the k-th allocation for every k of the unhindered run: each failure
 * must give CF_ERR_NOMEM and leave nothing allocated. */
/* cf_sparse_multiply_zero_row_sums: a random symmetric matrix with zero
 * row sums (a graph Laplacian with random weights, diagonal stored) gives
 * A x as cf_sparse_multiply does (to rounding), both storages; the
 * diagonal is never read (a wrong one changes nothing); and a shift of x
 * by a constant changes nothing, bit for bit, where the shift is exact
 * (x on a 2^-20 grid, shift 2^20); a shift by 1e6 costs only the rounding
 * of the shifted data. */
static void test_zero_row_sums(void)
{
    cf_context *ctx = cft_context();
    rng_seed(11);
    const int32_t n = 40;
    int32_t r[4 * 120], c[4 * 120];
    double v[4 * 120];
    int64_t k = 0;
    for (int e = 0; e < 120; ++e) {
        int32_t i = (int32_t)(rng_u32() % n), j = (int32_t)(rng_u32() % n);
        if (i == j) continue;
        double w = 0.5 + rng_unit();
        r[k] = i; c[k] = i; v[k++] = w;
        r[k] = j; c[k] = j; v[k++] = w;
        r[k] = i; c[k] = j; v[k++] = -w;
        r[k] = j; c[k] = i; v[k++] = -w;
    }
    cf_sparse *a = NULL, *u = NULL;
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, n, n, k, r, c, v, 1, &a, NULL));
    /* the upper triangle alone */
    int64_t ku = 0;
    for (int64_t q = 0; q < k; ++q)
        if (r[q] <= c[q]) { r[ku] = r[q]; c[ku] = c[q]; v[ku++] = v[q]; }
    CHECK_OK(ctx, cf_sparse_from_triplets(ctx, n, n, ku, r, c, v, 1, &u, NULL));
    if (!a || !u) return;
    u->upper_only = 1;
    double x[40], xs[40], xf[40], y[40], yd[40], yu[40], ys[40], yf[40];
    for (int32_t i = 0; i < n; ++i) {
        x[i] = (double)(int32_t)(rng_unit() * 1048576.0) / 1048576.0; /* on the 2^-20 grid */
        xs[i] = x[i] + 1048576.0;                                       /* exact */
        xf[i] = x[i] + 1e6;
    }
    cf_sparse_multiply(a, x, yd);
    cf_sparse_multiply_zero_row_sums(a, x, y);
    cf_sparse_multiply_zero_row_sums(u, x, yu);
    CHECK_LE(max_abs_diff(y, yd, (size_t)n), 1e-13);
    CHECK_LE(max_abs_diff(yu, yd, (size_t)n), 1e-13);
    cf_sparse_multiply_zero_row_sums(a, xs, ys);
    CHECK(memcmp(ys, y, sizeof y) == 0);
    cf_sparse_multiply_zero_row_sums(u, xs, ys);
    CHECK(memcmp(ys, yu, sizeof yu) == 0);
    /* the diagonal is not read */
    for (int32_t j = 0; j < n; ++j)
        for (int32_t p = a->colptr[j]; p < a->colptr[j + 1]; ++p)
            if (a->rowind[p] == j) a->values[p] = 1e300;
    cf_sparse_multiply_zero_row_sums(a, x, ys);
    CHECK(memcmp(ys, y, sizeof y) == 0);
    /* 1e6 away: as good as the shifted data allows (x + 1e6 is rounded to
     * 1.2e-10, times weights below 1.5 and a few neighbours) */
    cf_sparse_multiply_zero_row_sums(a, xf, yf);
    CHECK_LE(max_abs_diff(yf, y, (size_t)n), 1e-8);
    cf_sparse_destroy(&a);
    cf_sparse_destroy(&u);
    cf_context_destroy(&ctx);
}

static void test_allocation_failures(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    rng_seed(4);
    triplets t = random_triplets(12, 12, 60);
    CHECK(cft_allocation_sweep(ctx, "sparse ops", sparse_ops_call, &t, 0) > 10); /* every allocation point was exercised */
    free_triplets(&t);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_from_triplets_matches_dense);
    CFT_RUN(test_invalid_input);
    CFT_RUN(test_operations_match_dense);
    CFT_RUN(test_upper_only);
    CFT_RUN(test_zero_row_sums);
    CFT_RUN(test_allocation_failures);
    return cft_finish();
}
