/* cf_svd3 / cf_rotation_from_covariance: reconstruction, orthogonality,
 * ordering and signs on random, near-singular, rank-1, reflected input. */
#include "curvflow/svd3.h"
#include "test.h"

#include <stdint.h>

static uint64_t rng_state = 0x243f6a8885a308d3ull;
static double urand(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) / 9007199254740992.0 * 2.0 - 1.0;
}

static double det3(const double m[9])
{
    return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
}

static double fro(const double m[9])
{
    double s = 0;
    for (int i = 0; i < 9; ++i) s += m[i] * m[i];
    return sqrt(s);
}

/* checks u, v rotations, ordering, sign rule and reconstruction to tol * |a| */
static void check_svd(const double a[9], double tol)
{
    double u[9], s[3], v[9];
    CHECK_STATUS(cf_svd3(a, u, s, v), CF_OK);
    double na = fro(a);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double uu = 0, vv = 0, r = 0;
            for (int k = 0; k < 3; ++k) {
                uu += u[3 * k + i] * u[3 * k + j];
                vv += v[3 * k + i] * v[3 * k + j];
                r += u[3 * i + k] * s[k] * v[3 * j + k];
            }
            CHECK_NEAR(uu, i == j ? 1.0 : 0.0, 0, 1e-14);
            CHECK_NEAR(vv, i == j ? 1.0 : 0.0, 0, 1e-14);
            CHECK_NEAR(r, a[3 * i + j], 0, tol * na);
        }
    CHECK_NEAR(det3(u), 1.0, 0, 1e-14);
    CHECK_NEAR(det3(v), 1.0, 0, 1e-14);
    CHECK(s[0] >= s[1]);
    CHECK(s[1] >= fabs(s[2]));
    double d = det3(a);
    if (fabs(d) > 1e-12 * na * na * na) CHECK((s[2] < 0) == (d < 0));
}

static void test_random(void)
{
    for (int t = 0; t < 2000; ++t) {
        double a[9];
        for (int i = 0; i < 9; ++i) a[i] = urand() * (t % 3 == 0 ? 1e6 : 1.0);
        check_svd(a, 1e-12);
    }
}

static void test_special(void)
{
    double zero[9] = {0};
    check_svd(zero, 0);
    double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    check_svd(id, 1e-15);
    /* reflection: singular values (1, 1, -1) */
    double refl[9] = {1, 0, 0, 0, 1, 0, 0, 0, -1}, u[9], s[3], v[9];
    check_svd(refl, 1e-15);
    cf_svd3(refl, u, s, v);
    CHECK_NEAR(s[0], 1.0, 0, 1e-15);
    CHECK_NEAR(s[1], 1.0, 0, 1e-15);
    CHECK_NEAR(s[2], -1.0, 0, 1e-15);
    /* rank 1: outer product x y^T, singular values |x||y|, 0, 0 */
    double x[3] = {1, 2, 3}, y[3] = {-2, 0.5, 1}, r1[9];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) r1[3 * i + j] = x[i] * y[j];
    check_svd(r1, 1e-14);
    cf_svd3(r1, u, s, v);
    CHECK_NEAR(s[0], sqrt(14.0) * sqrt(5.25), 1e-14, 0);
    CHECK_NEAR(s[1], 0.0, 0, 1e-14);
    CHECK_NEAR(s[2], 0.0, 0, 1e-14);
    /* rank 2 and near-singular: diag(3, 2, 1e-13) rotated; the small value
     * keeps its relative accuracy (one-sided Jacobi never squares it) */
    for (int t = 0; t < 200; ++t) {
        double q[9], b[9], a[9];
        /* random rotation from the closest rotation of a random matrix */
        for (int i = 0; i < 9; ++i) b[i] = urand();
        CHECK_STATUS(cf_rotation_from_covariance(b, q), CF_OK);
        double sv[3] = {3.0, 2.0, (t % 2) ? 1e-13 : 0.0};
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) a[3 * i + j] = q[3 * i + j] * sv[j];
        check_svd(a, 1e-14);
        cf_svd3(a, u, s, v);
        CHECK_NEAR(s[0], 3.0, 1e-14, 0);
        CHECK_NEAR(s[1], 2.0, 1e-14, 0);
        CHECK_NEAR(fabs(s[2]), sv[2], 1e-6, 1e-28);
    }
    double nan9[9] = {1, 0, 0, 0, NAN, 0, 0, 0, 1};
    CHECK_STATUS(cf_svd3(nan9, u, s, v), CF_ERR_NONFINITE);
    CHECK_STATUS(cf_svd3(NULL, u, s, v), CF_ERR_INVALID_ARG);
}

static void test_closest_rotation(void)
{
    for (int t = 0; t < 500; ++t) {
        double a[9], r[9];
        for (int i = 0; i < 9; ++i) a[i] = urand();
        CHECK_STATUS(cf_rotation_from_covariance(a, r), CF_OK);
        CHECK_NEAR(det3(r), 1.0, 0, 1e-13);
        /* optimality: trace(r^T a) is not beaten by small perturbations of
         * r along any rotation generator */
        double base = 0;
        for (int i = 0; i < 9; ++i) base += r[i] * a[i];
        for (int g = 0; g < 3; ++g)
            for (int sgn = -1; sgn <= 1; sgn += 2) {
                double h = 1e-4 * sgn, c = cos(h), s = sin(h), rot[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, rr[9];
                int p = (g + 1) % 3, q = (g + 2) % 3;
                rot[3 * p + p] = c;
                rot[3 * q + q] = c;
                rot[3 * p + q] = -s;
                rot[3 * q + p] = s;
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j) {
                        rr[3 * i + j] = 0;
                        for (int k = 0; k < 3; ++k) rr[3 * i + j] += rot[3 * i + k] * r[3 * k + j];
                    }
                double tr = 0;
                for (int i = 0; i < 9; ++i) tr += rr[i] * a[i];
                CHECK_LE(tr, base + 1e-12);
            }
    }
    /* a rotation is its own closest rotation; a reflection maps to the
     * rotation with the smallest singular direction flipped */
    double refl[9] = {1, 0, 0, 0, 1, 0, 0, 0, -1}, scaled[9] = {3, 0, 0, 0, 2, 0, 0, 0, -1}, r[9];
    CHECK_STATUS(cf_rotation_from_covariance(scaled, r), CF_OK);
    for (int i = 0; i < 9; ++i) CHECK_NEAR(r[i], (i % 4 == 0) ? 1.0 : 0.0, 0, 1e-15);
    (void)refl;
}

int main(void)
{
    CFT_RUN(test_random);
    CFT_RUN(test_special);
    CFT_RUN(test_closest_rotation);
    return cft_finish();
}
