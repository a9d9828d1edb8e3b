/* Quaternion algebra identities, the Le Folgoc Eq. (7) matrix forms and
 * their inverses, and rotation matrices. */
#include "curvflow/quaternion.h"
#include "test.h"

#include <stdint.h>

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static double urand(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) / 9007199254740992.0 * 2.0 - 1.0;
}
static cf_quat rquat(void) { return cf_quat_make(urand(), urand(), urand(), urand()); }

static double qdist(cf_quat a, cf_quat b) { return cf_quat_norm(cf_quat_sub(a, b)); }

static void test_basis_products(void)
{
    cf_quat one = cf_quat_make(1, 0, 0, 0), i = cf_quat_make(0, 1, 0, 0), j = cf_quat_make(0, 0, 1, 0),
            k = cf_quat_make(0, 0, 0, 1);
    /* Hamilton: i^2 = j^2 = k^2 = ijk = -1, ij = k, jk = i, ki = j */
    CHECK(qdist(cf_quat_mul(i, i), cf_quat_scale(one, -1)) == 0.0);
    CHECK(qdist(cf_quat_mul(j, j), cf_quat_scale(one, -1)) == 0.0);
    CHECK(qdist(cf_quat_mul(k, k), cf_quat_scale(one, -1)) == 0.0);
    CHECK(qdist(cf_quat_mul(cf_quat_mul(i, j), k), cf_quat_scale(one, -1)) == 0.0);
    CHECK(qdist(cf_quat_mul(i, j), k) == 0.0);
    CHECK(qdist(cf_quat_mul(j, k), i) == 0.0);
    CHECK(qdist(cf_quat_mul(k, i), j) == 0.0);
    CHECK(qdist(cf_quat_mul(j, i), cf_quat_scale(k, -1)) == 0.0);
}

static void test_matrices_match_products(void)
{
    for (int t = 0; t < 200; ++t) {
        cf_quat q = rquat(), p = rquat();
        double l[16], r[16];
        cf_quat_left_matrix(q, l);
        cf_quat_right_matrix(q, r);
        double pv[4] = {p.w, p.x, p.y, p.z}, lp[4] = {0}, rp[4] = {0};
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) {
                lp[a] += l[4 * a + b] * pv[b];
                rp[a] += r[4 * a + b] * pv[b];
            }
        cf_quat qp = cf_quat_mul(q, p), pq = cf_quat_mul(p, q);
        CHECK_NEAR(lp[0], qp.w, 0, 1e-15);
        CHECK_NEAR(lp[1], qp.x, 0, 1e-15);
        CHECK_NEAR(lp[2], qp.y, 0, 1e-15);
        CHECK_NEAR(lp[3], qp.z, 0, 1e-15);
        CHECK_NEAR(rp[0], pq.w, 0, 1e-15);
        CHECK_NEAR(rp[1], pq.x, 0, 1e-15);
        CHECK_NEAR(rp[2], pq.y, 0, 1e-15);
        CHECK_NEAR(rp[3], pq.z, 0, 1e-15);
        /* Le Folgoc Remark 51: M[conj q] = M[q]^T */
        double lc[16];
        cf_quat_left_matrix(cf_quat_conj(q), lc);
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) CHECK(lc[4 * a + b] == l[4 * b + a]);
    }
    /* Le Folgoc Eq. (7) layout, entry by entry for q = 1 + 2i + 3j + 4k */
    double m[16];
    cf_quat_left_matrix(cf_quat_make(1, 2, 3, 4), m);
    const double expect[16] = {1, -2, -3, -4, 2, 1, -4, 3, 3, 4, 1, -2, 4, -3, 2, 1};
    for (int a = 0; a < 16; ++a) CHECK(m[a] == expect[a]);
}

static void test_identities(void)
{
    for (int t = 0; t < 200; ++t) {
        cf_quat a = rquat(), b = rquat(), c = rquat();
        CHECK_LE(qdist(cf_quat_mul(cf_quat_mul(a, b), c), cf_quat_mul(a, cf_quat_mul(b, c))), 1e-15);
        CHECK_NEAR(cf_quat_norm(cf_quat_mul(a, b)), cf_quat_norm(a) * cf_quat_norm(b), 1e-15, 0);
        CHECK_LE(qdist(cf_quat_conj(cf_quat_mul(a, b)), cf_quat_mul(cf_quat_conj(b), cf_quat_conj(a))), 1e-15);
        CHECK_LE(qdist(cf_quat_mul(a, cf_quat_inverse(a)), cf_quat_make(1, 0, 0, 0)), 1e-14);
        CHECK_LE(qdist(cf_quat_mul(cf_quat_inverse(a), a), cf_quat_make(1, 0, 0, 0)), 1e-14);
        CHECK_NEAR(cf_quat_norm(cf_quat_normalize(a)), 1.0, 1e-15, 0);
        /* distributivity */
        CHECK_LE(qdist(cf_quat_mul(a, cf_quat_add(b, c)), cf_quat_add(cf_quat_mul(a, b), cf_quat_mul(a, c))),
                 1e-15);
    }
    CHECK(cf_quat_norm2(cf_quat_inverse(cf_quat_make(0, 0, 0, 0))) == 0.0);
    /* norm without overflow */
    CHECK_NEAR(cf_quat_norm(cf_quat_make(3e200, 4e200, 0, 0)), 5e200, 1e-15, 0);
}

static void test_rotation(void)
{
    /* 90 degrees about z maps x to y: q v conj(q); the sandwich conj(q) v q
     * is the inverse rotation. */
    double z[3] = {0, 0, 1}, x[3] = {1, 0, 0}, out[3];
    cf_quat q = cf_quat_from_axis_angle(z, 0.5 * 3.14159265358979323846);
    cf_quat r = cf_quat_mul(cf_quat_mul(q, cf_quat_from_vector(x)), cf_quat_conj(q));
    CHECK_NEAR(r.w, 0.0, 0, 1e-15);
    CHECK_NEAR(r.x, 0.0, 0, 1e-15);
    CHECK_NEAR(r.y, 1.0, 0, 1e-15);
    CHECK_NEAR(r.z, 0.0, 0, 1e-15);
    cf_quat_conj_sandwich(q, x, out);
    CHECK_NEAR(out[0], 0.0, 0, 1e-15);
    CHECK_NEAR(out[1], -1.0, 0, 1e-15);
    CHECK_NEAR(out[2], 0.0, 0, 1e-15);
    /* general axis: rotation keeps the axis, length and the angle to it;
     * non-unit q scales by |q|^2 (spin transformations) */
    for (int t = 0; t < 100; ++t) {
        double axis[3] = {urand(), urand(), urand()}, v[3] = {urand(), urand(), urand()}, w[3];
        double angle = 3.0 * urand();
        cf_quat p = cf_quat_scale(cf_quat_from_axis_angle(axis, angle), 2.0);
        cf_quat_conj_sandwich(p, axis, w);
        for (int c = 0; c < 3; ++c) CHECK_NEAR(w[c], 4.0 * axis[c], 0, 1e-14);
        cf_quat_conj_sandwich(p, v, w);
        double nv = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]), nw = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        CHECK_NEAR(nw, 4.0 * nv, 1e-14, 0);
        /* angle of rotation: component of v orthogonal to the axis turns by -angle */
        double na = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
        double a[3] = {axis[0] / na, axis[1] / na, axis[2] / na};
        double dv = v[0] * a[0] + v[1] * a[1] + v[2] * a[2];
        double pv[3] = {v[0] - dv * a[0], v[1] - dv * a[1], v[2] - dv * a[2]};
        double dw = (w[0] * a[0] + w[1] * a[1] + w[2] * a[2]) / 4.0;
        double pw[3] = {w[0] / 4.0 - dw * a[0], w[1] / 4.0 - dw * a[1], w[2] / 4.0 - dw * a[2]};
        double cosang = (pv[0] * pw[0] + pv[1] * pw[1] + pv[2] * pw[2]) / (pv[0] * pv[0] + pv[1] * pv[1] + pv[2] * pv[2]);
        CHECK_NEAR(cosang, cos(angle), 0, 1e-12);
    }
}

static void matmul4(const double *a, const double *b, double *c)
{
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            double v = 0.0;
            for (int k = 0; k < 4; ++k) v += a[4 * i + k] * b[4 * k + j];
            c[4 * i + j] = v;
        }
}

/* The 4 x 4 forms are algebra homomorphisms: L(a) L(b) = L(a b),
 * R(a) R(b) = R(b a), and left and right multiplications commute; the
 * inverse conversions give q back bit for bit and project any other
 * matrix orthogonally onto the quaternion matrices. */
static void test_matrix_conversions(void)
{
    for (int t = 0; t < 200; ++t) {
        cf_quat a = rquat(), b = rquat();
        double la[16], lb[16], ra[16], rb[16], lab[16], rba[16], prod[16], prod2[16];
        cf_quat_left_matrix(a, la);
        cf_quat_left_matrix(b, lb);
        cf_quat_right_matrix(a, ra);
        cf_quat_right_matrix(b, rb);
        cf_quat_left_matrix(cf_quat_mul(a, b), lab);
        cf_quat_right_matrix(cf_quat_mul(b, a), rba);
        matmul4(la, lb, prod);
        for (int k = 0; k < 16; ++k) CHECK_NEAR(prod[k], lab[k], 0, 1e-15);
        matmul4(ra, rb, prod);
        for (int k = 0; k < 16; ++k) CHECK_NEAR(prod[k], rba[k], 0, 1e-15);
        matmul4(la, rb, prod);
        matmul4(rb, la, prod2);
        for (int k = 0; k < 16; ++k) CHECK_NEAR(prod[k], prod2[k], 0, 1e-15);
        /* round trips are exact */
        cf_quat back = cf_quat_from_left_matrix(la), back_r = cf_quat_from_right_matrix(ra);
        CHECK(back.w == a.w && back.x == a.x && back.y == a.y && back.z == a.z);
        CHECK(back_r.w == a.w && back_r.x == a.x && back_r.y == a.y && back_r.z == a.z);
        /* projection: m - L(p) is orthogonal to every L(e) for a random m */
        double m[16], lp[16], basis[16];
        for (int k = 0; k < 16; ++k) m[k] = urand();
        cf_quat p = cf_quat_from_left_matrix(m);
        cf_quat_left_matrix(p, lp);
        const cf_quat units[4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
        for (int e = 0; e < 4; ++e) {
            cf_quat_left_matrix(units[e], basis);
            double dot = 0.0;
            for (int k = 0; k < 16; ++k) dot += (m[k] - lp[k]) * basis[k];
            CHECK_NEAR(dot, 0.0, 0, 1e-14);
        }
        /* array load/store */
        double arr[4];
        cf_quat_store(a, arr);
        CHECK(arr[0] == a.w && arr[1] == a.x && arr[2] == a.y && arr[3] == a.z);
        cf_quat l = cf_quat_load(arr);
        CHECK(l.w == a.w && l.x == a.x && l.y == a.y && l.z == a.z);
    }
    CHECK(cf_quat_norm2(cf_quat_from_left_matrix(NULL)) == 0.0);
    CHECK(cf_quat_norm2(cf_quat_load(NULL)) == 0.0);
}

static double det3(const double *m)
{
    return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
}

/* Rotation matrices: r v = q v conj(q), orthogonal with det +1; 90 degrees
 * about z is counter-clockwise; rotation -> quaternion -> rotation is the
 * identity map, through every branch of the conversion (angles near pi
 * about each axis exercise the three non-trace branches). */
static void test_rotation_matrix(void)
{
    double z[3] = {0, 0, 1}, r[9];
    cf_quat_to_rotation_matrix(cf_quat_from_axis_angle(z, 0.5 * 3.14159265358979323846), r);
    const double expect[9] = {0, -1, 0, 1, 0, 0, 0, 0, 1};
    for (int k = 0; k < 9; ++k) CHECK_NEAR(r[k], expect[k], 0, 1e-15);
    const double axes[4][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
    for (int t = 0; t < 400; ++t) {
        double axis[3] = {urand(), urand(), urand()}, v[3] = {urand(), urand(), urand()};
        double angle = 3.14159265358979323846 * urand();
        if (t < 40) { /* near a half turn about a coordinate axis (or the diagonal) */
            for (int c = 0; c < 3; ++c) axis[c] = axes[t % 4][c] + 1e-3 * urand();
            angle = 3.14159265358979323846 * (1.0 - 1e-3 * fabs(urand()));
        }
        cf_quat q = cf_quat_from_axis_angle(axis, angle);
        cf_quat_to_rotation_matrix(q, r);
        double rv[3];
        for (int i = 0; i < 3; ++i) rv[i] = r[3 * i] * v[0] + r[3 * i + 1] * v[1] + r[3 * i + 2] * v[2];
        cf_quat s = cf_quat_mul(cf_quat_mul(q, cf_quat_from_vector(v)), cf_quat_conj(q));
        CHECK_NEAR(rv[0], s.x, 0, 1e-15);
        CHECK_NEAR(rv[1], s.y, 0, 1e-15);
        CHECK_NEAR(rv[2], s.z, 0, 1e-15);
        CHECK_NEAR(det3(r), 1.0, 0, 1e-14);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                double d = r[i] * r[j] + r[3 + i] * r[3 + j] + r[6 + i] * r[6 + j];
                CHECK_NEAR(d, i == j ? 1.0 : 0.0, 0, 1e-14); /* a few ulps per entry from q and the formula */
            }
        cf_quat p = cf_quat_from_rotation_matrix(r);
        CHECK_NEAR(cf_quat_norm(p), 1.0, 0, 1e-15);
        /* q and -q are the same rotation */
        double sign = (p.w * q.w + p.x * q.x + p.y * q.y + p.z * q.z) < 0.0 ? -1.0 : 1.0;
        CHECK_LE(qdist(cf_quat_scale(p, sign), q), 1e-14);
        double r2[9];
        cf_quat_to_rotation_matrix(p, r2);
        for (int k = 0; k < 9; ++k) CHECK_NEAR(r2[k], r[k], 0, 1e-14);
    }
    cf_quat id = cf_quat_from_rotation_matrix(NULL);
    CHECK(id.w == 1.0 && id.x == 0.0 && id.y == 0.0 && id.z == 0.0);
}

int main(void)
{
    CFT_RUN(test_basis_products);
    CFT_RUN(test_matrices_match_products);
    CFT_RUN(test_identities);
    CFT_RUN(test_rotation);
    CFT_RUN(test_matrix_conversions);
    CFT_RUN(test_rotation_matrix);
    return cft_finish();
}
