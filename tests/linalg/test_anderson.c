/*
 * cf_anderson: Anderson acceleration of fixed-point iterations with known
 * answers. A scalar linear map is solved exactly by depth 1 (the secant
 * step); a 40-dimensional linear contraction with spectral radius 0.95 and
 * the cosine map (fixed point: the Dottie number) converge several times
 * faster than plain iteration (the measured factors are printed and
 * asserted with margin); a step allocates nothing; reset, history cap,
 * non-finite input and argument errors; allocation-failure sweep of create.
 */
#include "curvflow/linalg.h"
#include "linalg_test_util.h"
#include "test.h"

#include <stdio.h>
#include <string.h>

/* Iterates x <- G(x) from x0 until max |x - x*| <= tol, with (depth > 0)
 * or without Anderson mixing; returns the number of G evaluations, or -1
 * after max_it. */
typedef void (*fixed_point_map)(int32_t n, const double *x, double *g, const void *data);

static int run_iteration(cf_context *ctx, int32_t n, fixed_point_map map, const void *data, const double *x0,
                         const double *xstar, double tol, int32_t depth, int max_it)
{
    double *x = malloc((size_t)n * sizeof *x), *g = malloc((size_t)n * sizeof *g), *y = malloc((size_t)n * sizeof *y);
    memcpy(x, x0, (size_t)n * sizeof *x);
    cf_anderson *aa = NULL;
    if (depth > 0) CHECK_OK(ctx, cf_anderson_create(ctx, n, depth, &aa));
    int result = -1;
    for (int it = 1; it <= max_it; ++it) {
        map(n, x, g, data);
        int32_t mixed = 0;
        if (aa) CHECK_OK(ctx, cf_anderson_step(aa, x, g, y, &mixed));
        memcpy(x, mixed ? y : g, (size_t)n * sizeof *x);
        double err = 0.0;
        for (int32_t i = 0; i < n; ++i) err = fmax(err, fabs(x[i] - xstar[i]));
        if (err <= tol) {
            result = it;
            break;
        }
    }
    cf_anderson_destroy(&aa);
    free(x);
    free(g);
    free(y);
    return result;
}

/* G(x) = 0.5 x + 1, fixed point 2. */
static void half_map(int32_t n, const double *x, double *g, const void *data)
{
    (void)data;
    for (int32_t i = 0; i < n; ++i) g[i] = 0.5 * x[i] + 1.0;
}

/* Depth 1 on a scalar linear map is the secant method, exact after one
 * mixed step: x0 = 0, x1 = G(0) = 1, then f = (1, 0.5), df = -0.5,
 * dg = 0.5, gamma = -1 (up to the 1e-10 Tikhonov shift) and
 * x2 = G(1) - dg gamma = 1.5 + 0.5 = 2. */
static void test_secant_by_hand(void)
{
    cf_context *ctx = cft_context();
    cf_anderson *aa = NULL;
    CHECK_OK(ctx, cf_anderson_create(ctx, 1, 1, &aa));
    double x = 0.0, g = 0.0, y = -7.0;
    int32_t mixed = 1;
    half_map(1, &x, &g, NULL);
    CHECK_OK(ctx, cf_anderson_step(aa, &x, &g, &y, &mixed));
    CHECK(mixed == 0);
    CHECK(y == -7.0); /* untouched when not mixed */
    CHECK(cf_anderson_history(aa) == 0);
    x = g; /* 1 */
    half_map(1, &x, &g, NULL);
    CHECK_OK(ctx, cf_anderson_step(aa, &x, &g, &y, &mixed));
    CHECK(mixed == 1);
    CHECK(cf_anderson_history(aa) == 1);
    CHECK_NEAR(y, 2.0, 0.0, 1e-9);
    /* one more push at the fixed point: f no longer changes direction,
     * history stays capped at depth 1 */
    x = y;
    half_map(1, &x, &g, NULL);
    CHECK_OK(ctx, cf_anderson_step(aa, &x, &g, &y, &mixed));
    CHECK(cf_anderson_history(aa) == 1);
    if (mixed) CHECK_NEAR(y, 2.0, 0.0, 1e-9);
    /* after a reset the next call only records */
    cf_anderson_reset(aa);
    CHECK(cf_anderson_history(aa) == 0);
    CHECK_OK(ctx, cf_anderson_step(aa, &x, &g, &y, &mixed));
    CHECK(mixed == 0);
    cf_anderson_destroy(&aa);
    CHECK(aa == NULL);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

typedef struct linear_map {
    int32_t n;
    double *m; /* n x n column-major */
    double *c;
} linear_map;

static void apply_linear(int32_t n, const double *x, double *g, const void *data)
{
    const linear_map *lm = data;
    for (int32_t i = 0; i < n; ++i) g[i] = lm->c[i];
    for (int32_t j = 0; j < n; ++j)
        for (int32_t i = 0; i < n; ++i) g[i] += lm->m[(size_t)j * n + i] * x[j];
}

/* G(x) = M x + c with M = H diag(lambda) H (H a Householder reflection,
 * lambda spread over [-0.5, 0.95]) and c = x* - M x*: the fixed point x* is
 * known. Plain iteration converges like 0.95^k (about 450 steps to 1e-10
 * from 0); Anderson mixing behaves like GMRES restarted every few steps
 * and needs far fewer. Measured: 446 plain, 118 at depth 5 (factor 3.8),
 * 80 at depth 10 (5.6); asserted with margin: at least 3 and 4 times fewer. */
static void test_linear_contraction(void)
{
    cf_context *ctx = cft_context();
    enum { N = 40 };
    rng_seed(12);
    double v[N], lambda[N], xstar[N], x0[N] = {0};
    double vv = 0.0;
    for (int32_t i = 0; i < N; ++i) {
        v[i] = rng_unit();
        vv += v[i] * v[i];
        lambda[i] = -0.5 + 1.45 * (double)i / (N - 1);
        xstar[i] = rng_unit();
    }
    linear_map lm = {N, malloc(sizeof(double) * N * N), malloc(sizeof(double) * N)};
    /* H = I - 2 v v^T / v^T v; M = H diag(lambda) H */
    for (int32_t j = 0; j < N; ++j)
        for (int32_t i = 0; i < N; ++i) {
            double s = 0.0;
            for (int32_t k = 0; k < N; ++k) {
                double hik = (i == k) - 2.0 * v[i] * v[k] / vv, hkj = (k == j) - 2.0 * v[k] * v[j] / vv;
                s += hik * lambda[k] * hkj;
            }
            lm.m[(size_t)j * N + i] = s;
        }
    for (int32_t i = 0; i < N; ++i) {
        double mx = 0.0;
        for (int32_t j = 0; j < N; ++j) mx += lm.m[(size_t)j * N + i] * xstar[j];
        lm.c[i] = xstar[i] - mx;
    }
    int plain = run_iteration(ctx, N, apply_linear, &lm, x0, xstar, 1e-10, 0, 5000);
    int aa5 = run_iteration(ctx, N, apply_linear, &lm, x0, xstar, 1e-10, 5, 5000);
    int aa10 = run_iteration(ctx, N, apply_linear, &lm, x0, xstar, 1e-10, 10, 5000);
    fprintf(stderr, "linear contraction (rho 0.95, n %d): plain %d, depth 5 %d (factor %.1f), depth 10 %d\n", N, plain,
            aa5, aa5 > 0 ? (double)plain / aa5 : 0.0, aa10);
    /* plain: ceil(log(1e-10 / |x*|_inf) / log 0.95) or so */
    CHECK(plain > 400 && plain < 500);
    CHECK(aa5 > 0 && 3 * aa5 <= plain);
    CHECK(aa10 > 0 && 4 * aa10 <= plain);
    free(lm.m);
    free(lm.c);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void cos_map(int32_t n, const double *x, double *g, const void *data)
{
    (void)data;
    for (int32_t i = 0; i < n; ++i) g[i] = cos(x[i]);
}

/* The Dottie number, the fixed point of cos: 0.739085133215160641655...
 * Plain iteration contracts by |sin x*| = 0.674 per step (about 70 steps to
 * 1e-12); Anderson needs a handful. Measured: plain 68, depth 3: 9
 * (factor 7.6); asserted: at least 4 times fewer. */
static void test_cosine(void)
{
    cf_context *ctx = cft_context();
    const double dottie = 0.73908513321516064166;
    double x0[3] = {0.0, 1.0, -0.3}, xstar[3] = {dottie, dottie, dottie};
    int plain = run_iteration(ctx, 3, cos_map, NULL, x0, xstar, 1e-12, 0, 1000);
    int aa = run_iteration(ctx, 3, cos_map, NULL, x0, xstar, 1e-12, 3, 1000);
    fprintf(stderr, "cos fixed point: plain %d, depth 3 %d (factor %.1f)\n", plain, aa,
            aa > 0 ? (double)plain / aa : 0.0);
    CHECK(plain > 50);
    CHECK(aa > 0 && 4 * aa <= plain);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Steps allocate nothing (the history is preallocated at create). */
static void test_no_allocation_in_steps(void)
{
    cf_context *ctx = cft_context();
    enum { N = 100 };
    cf_anderson *aa = NULL;
    CHECK_OK(ctx, cf_anderson_create(ctx, N, 4, &aa));
    double x[N], g[N], y[N];
    for (int32_t i = 0; i < N; ++i) x[i] = 0.01 * i;
    int64_t before = cf_context_allocation_count(ctx);
    for (int it = 0; it < 20; ++it) {
        cos_map(N, x, g, NULL);
        int32_t mixed = 0;
        CHECK_OK(ctx, cf_anderson_step(aa, x, g, y, &mixed));
        memcpy(x, mixed ? y : g, sizeof x);
        if (it == 10) cf_anderson_reset(aa);
    }
    CHECK(cf_context_allocation_count(ctx) == before);
    CHECK(cf_anderson_history(aa) <= 4);
    cf_anderson_destroy(&aa);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static cf_status create_call(cf_context *ctx, void *user)
{
    (void)user;
    cf_anderson *aa = NULL;
    cf_status st = cf_anderson_create(ctx, 50, 6, &aa);
    cf_anderson_destroy(&aa);
    return st;
}

static void test_bad_input(void)
{
    cf_context *ctx = cft_context();
    cf_anderson *aa = NULL;
    CHECK_STATUS(cf_anderson_create(ctx, 10, 0, &aa), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "depth 0") != NULL);
    CHECK_STATUS(cf_anderson_create(ctx, 10, CF_ANDERSON_MAX_DEPTH + 1, &aa), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_anderson_create(ctx, 0, 3, &aa), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_anderson_create(ctx, 10, 3, NULL), CF_ERR_INVALID_ARG);
    CHECK(aa == NULL);
    CHECK_OK(ctx, cf_anderson_create(ctx, 3, 2, &aa));
    double x[3] = {0, 0, 0}, g[3] = {1, 2, 3}, y[3];
    int32_t mixed = 7;
    CHECK_STATUS(cf_anderson_step(aa, NULL, g, y, &mixed), CF_ERR_INVALID_ARG);
    CHECK(mixed == 0);
    CHECK_STATUS(cf_anderson_step(NULL, x, g, y, &mixed), CF_ERR_INVALID_ARG);
    /* a non-finite G(x) is named and resets the history */
    CHECK_OK(ctx, cf_anderson_step(aa, x, g, y, &mixed));
    g[1] = NAN;
    CHECK_STATUS(cf_anderson_step(aa, x, g, y, &mixed), CF_ERR_NUMERICAL);
    CHECK(strstr(cf_context_message(ctx), "not finite at entry 1") != NULL);
    CHECK(mixed == 0);
    CHECK(cf_anderson_history(aa) == 0);
    g[1] = INFINITY;
    CHECK_STATUS(cf_anderson_step(aa, x, g, y, &mixed), CF_ERR_NUMERICAL); /* also on the first call */
    cf_anderson_destroy(&aa);
    cf_anderson_destroy(NULL);
    cf_anderson_reset(NULL);
    CHECK(cf_anderson_history(NULL) == 0);
    int64_t count = cft_allocation_sweep(ctx, "anderson create", create_call, NULL, 0);
    CHECK(count >= 5);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_secant_by_hand);
    CFT_RUN(test_linear_contraction);
    CFT_RUN(test_cosine);
    CFT_RUN(test_no_allocation_in_steps);
    CFT_RUN(test_bad_input);
    return cft_finish();
}
