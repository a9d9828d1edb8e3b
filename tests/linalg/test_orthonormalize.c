/* Weighted modified Gram-Schmidt: orthonormality to rounding level under a
 * weighted inner product, even for nearly parallel columns (where a single
 * pass loses orthogonality); rank detection with an exactly dependent
 * column (dropped, basis packed); projection onto the complement. */
#include "test.h"

#include "curvflow/linalg.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static double max_orthogonality_error(int32_t n, int32_t k, const double *q, const double *w)
{
    double e = 0.0;
    for (int32_t a = 0; a < k; ++a)
        for (int32_t b = 0; b <= a; ++b)
            e = fmax(e, fabs(cf_dot(n, q + (size_t)a * n, q + (size_t)b * n, w) - (a == b ? 1.0 : 0.0)));
    return e;
}

static void test_weighted_orthonormality(void)
{
    const int32_t n = 200, k = 6;
    double *q = malloc((size_t)n * k * sizeof *q), w[200];
    for (int32_t i = 0; i < n; ++i) w[i] = 0.1 + (double)((i * 37) % 17) / 4.0;
    /* columns nearly parallel: x^j sampled on [1, 1.001] (Vandermonde, cond ~1e15) */
    for (int32_t j = 0; j < k; ++j)
        for (int32_t i = 0; i < n; ++i) q[(size_t)j * n + i] = pow(1.0 + 1e-3 * i / n, j) + (j == 0 ? 0.0 : 1e-9 * sin(i * j));
    int32_t rank = -1;
    cf_orthonormalize(n, k, q, w, 1e-13, &rank);
    CHECK(rank == k);
    /* with reorthogonalisation the loss of orthogonality stays at rounding
     * level independently of the conditioning */
    CHECK_LE(max_orthogonality_error(n, rank, q, w), 1e-13);
    /* unweighted */
    for (int32_t j = 0; j < k; ++j)
        for (int32_t i = 0; i < n; ++i) q[(size_t)j * n + i] = cos(0.01 * i * (j + 1)) + 0.5 * j;
    cf_orthonormalize(n, k, q, NULL, 1e-12, &rank);
    CHECK(rank == k);
    CHECK_LE(max_orthogonality_error(n, rank, q, NULL), 1e-14);
    free(q);
}

static void test_dependent_column_dropped(void)
{
    const int32_t n = 5, k = 4;
    /* column 2 = 2 * column 0 - column 1: rank 3; column 3 independent */
    double q[20] = {1, 0, 2, 0, 1,   0, 1, 1, 0, 0,   2, -1, 3, 0, 2,   0, 0, 0, 1, 1};
    double c3[5];
    memcpy(c3, q + 15, sizeof c3);
    double w[5] = {1, 2, 1, 3, 1};
    int32_t rank = -1;
    cf_orthonormalize(n, k, q, w, 1e-10, &rank);
    CHECK(rank == 3);
    CHECK_LE(max_orthogonality_error(n, rank, q, w), 1e-15);
    /* the dropped slot (last) is zeroed; the packed basis spans column 3 */
    for (int32_t i = 0; i < n; ++i) CHECK(q[3 * n + i] == 0.0);
    cf_project_out(n, rank, q, w, c3);
    CHECK_LE(sqrt(cf_dot(n, c3, c3, w)), 1e-14);
    /* zero column: dropped, rank 0 */
    double z[5] = {0};
    cf_orthonormalize(5, 1, z, NULL, 1e-10, &rank);
    CHECK(rank == 0);
}

static void test_project_out(void)
{
    const int32_t n = 30;
    double b[60], v[30], w[30];
    for (int32_t i = 0; i < n; ++i) {
        w[i] = 1.0 + 0.1 * i;
        b[i] = 1.0;            /* constants */
        b[n + i] = (double)i;  /* linear */
        v[i] = sin(0.3 * i) + 2.0 + 0.5 * i;
    }
    int32_t rank = 0;
    cf_orthonormalize(n, 2, b, w, 1e-12, &rank);
    CHECK(rank == 2);
    cf_project_out(n, 2, b, w, v);
    /* v is now w-orthogonal to constants and to the linear function */
    double one[30], lin[30];
    for (int32_t i = 0; i < n; ++i) { one[i] = 1.0; lin[i] = i; }
    CHECK_NEAR(cf_dot(n, v, one, w), 0.0, 0.0, 1e-12);
    CHECK_NEAR(cf_dot(n, v, lin, w), 0.0, 0.0, 1e-11);
    /* projecting twice changes nothing (idempotent) */
    double v2[30];
    memcpy(v2, v, sizeof v2);
    cf_project_out(n, 2, b, w, v2);
    double md = 0.0;
    for (int32_t i = 0; i < n; ++i) md = fmax(md, fabs(v2[i] - v[i]));
    CHECK_LE(md, 1e-14);
    CHECK(cf_dot(3, one, lin, NULL) == 3.0); /* 0 + 1 + 2 */
    CHECK(cf_dot(0, one, lin, NULL) == 0.0);
}

/* Bases wider than one block (32 columns) go block by block through BLAS
 * products (session 29: 301 columns of 40k rows took 7 s of each
 * spin-willmore step on a sphere with 100 holes). The same contract:
 * orthonormal to rounding under the weights, the same span, dependent
 * columns dropped (inside a block, and dependent on columns of earlier
 * blocks), order kept; weights that are not all positive take the
 * column-by-column loop. */
static void test_blocked(void)
{
    const int32_t n = 3000, k = 100;
    double *q = malloc((size_t)n * k * sizeof *q), *orig = malloc((size_t)n * k * sizeof *q);
    double *w = malloc((size_t)n * sizeof *w), *v = malloc((size_t)n * sizeof *v);
    for (int32_t i = 0; i < n; ++i) w[i] = 0.5 + (double)((i * 37) % 17) / 8.0;
    uint32_t seed = 7u;
    for (int64_t t = 0; t < (int64_t)n * k; ++t) {
        seed = seed * 1664525u + 1013904223u;
        q[t] = (double)(seed >> 8) / 16777216.0 - 0.5;
    }
    /* dependent columns: 40 = 3 c5 (on a column of block 0), 70 = c64 + c65
     * (inside block 2), 99 = c1 - 2 c98 (across blocks) */
    for (int32_t i = 0; i < n; ++i) {
        q[40 * (size_t)n + i] = 3.0 * q[5 * (size_t)n + i];
        q[70 * (size_t)n + i] = q[64 * (size_t)n + i] + q[65 * (size_t)n + i];
        q[99 * (size_t)n + i] = q[1 * (size_t)n + i] - 2.0 * q[98 * (size_t)n + i];
    }
    memcpy(orig, q, (size_t)n * k * sizeof *q);
    for (int weighted = 0; weighted < 2; ++weighted) {
        const double *wt = weighted ? w : NULL;
        memcpy(q, orig, (size_t)n * k * sizeof *q);
        int32_t rank = -1;
        cf_orthonormalize(n, k, q, wt, 1e-10, &rank);
        double ortho = max_orthogonality_error(n, rank, q, wt);
        /* every input column lies in the span: what projecting it out leaves */
        double worst = 0.0;
        for (int32_t j = 0; j < k; ++j) {
            memcpy(v, orig + (size_t)j * n, (size_t)n * sizeof *v);
            double n0 = sqrt(cf_dot(n, v, v, wt));
            cf_project_out(n, rank, q, wt, v);
            worst = fmax(worst, sqrt(cf_dot(n, v, v, wt)) / n0);
        }
        /* order kept: column 0 of the basis is input column 0 normalised */
        double first = 0.0, n00 = sqrt(cf_dot(n, orig, orig, wt));
        for (int32_t i = 0; i < n; ++i) first = fmax(first, fabs(q[i] - orig[i] / n00));
        fprintf(stderr, "   %s: rank %d of %d, orthogonality %.1e, span residual %.1e, first column %.1e\n",
                weighted ? "weighted" : "unweighted", rank, k, ortho, worst, first);
        CHECK(rank == k - 3);
        CHECK_LE(ortho, 1e-13);
        CHECK_LE(worst, 1e-12);
        CHECK_LE(first, 1e-15);
        for (int64_t t = (int64_t)rank * n; t < (int64_t)k * n; ++t) CHECK(q[t] == 0.0);
    }
    /* a weight that is not positive: the column loop, same contract */
    memcpy(q, orig, (size_t)n * k * sizeof *q);
    w[17] = 0.0;
    int32_t rank = -1;
    cf_orthonormalize(n, k, q, w, 1e-10, &rank);
    CHECK(rank == k - 3);
    CHECK_LE(max_orthogonality_error(n, rank, q, w), 1e-13);
    free(q);
    free(orig);
    free(w);
    free(v);
}

int main(void)
{
    CFT_RUN(test_blocked);
    CFT_RUN(test_weighted_orthonormality);
    CFT_RUN(test_dependent_column_dropped);
    CFT_RUN(test_project_out);
    return cft_finish();
}
