/* Conformal class of closed surfaces of genus >= 1 (cf_conformal_class_*):
 * the modulus of tori of revolution against i sqrt(R^2 - r^2) / r, with
 * second-order convergence under refinement; invariance under
 * similarities (exact) and under an inversion in a sphere (a conformal map:
 * up to the discretisation); the intersection numbers integral; the
 * distance against the hyperbolic distance of the moduli; bad input. */
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/metrics.h"
#include "test.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* the torus of revolution (R, r) is conformally C / (Z + i b Z) with
 * b = sqrt(R^2 - r^2) / r in the fundamental domain (b >= 1 for R >= r sqrt 2) */
static double revolution_modulus(double big_r, double small_r)
{
    double b = sqrt(big_r * big_r - small_r * small_r) / small_r;
    return b >= 1.0 ? b : 1.0 / b;
}

static void test_torus_of_revolution(void)
{
    cf_context *ctx = cft_context();
    const double radii[3][2] = {{1.0, 0.4}, {1.0, 1.0 / sqrt(2.0)}, {1.0, 0.2}};
    for (int c = 0; c < 3; ++c) {
        double exact = revolution_modulus(radii[c][0], radii[c][1]), err[2] = {0, 0};
        for (int level = 0; level < 2; ++level) {
            int32_t n = 24 << level;
            cf_mesh *m = NULL;
            CHECK_OK(ctx, cf_generate_torus(ctx, radii[c][0], radii[c][1], 2 * n, n, &m));
            if (!m) continue;
            cf_conformal_class cls;
            double gram[4];
            CHECK_OK(ctx, cf_conformal_class_compute(ctx, m, cf_mesh_positions(m), gram, &cls));
            CHECK(cls.genus == 1);
            CHECK_NEAR(cls.modulus[0], 0.0, 0, 1e-9); /* rectangular: a reflection symmetry */
            err[level] = fabs(cls.modulus[1] - exact);
            CHECK_LE(cls.intersection_error, 1e-9);
            fprintf(stderr, "   torus R %.3f r %.3f, %d x %d: tau %.3g + %.6f i (exact %.6f i), hodge defect %.2g\n",
                    radii[c][0], radii[c][1], (int)(2 * n), (int)n, cls.modulus[0], cls.modulus[1], exact,
                    cls.hodge_defect);
            CHECK_LE(cls.hodge_defect, 0.02);
            CHECK_NEAR(gram[1], gram[2], 0, 1e-12 * fabs(gram[0]));
            cf_mesh_destroy(&m);
        }
        CHECK_LE(err[1], 0.01 * exact);
        CHECK_LE(err[1], 0.35 * err[0] + 1e-12); /* second order: halving the edges quarters the error */
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* a similarity changes nothing; an inversion in a sphere (conformal)
 * changes the class only by the discretisation */
static void test_invariance(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.45, 96, 48, &m));
    if (!m) return;
    int32_t nv = cf_mesh_vertex_count(m);
    const double *x = cf_mesh_positions(m);
    double *y = malloc(sizeof(double) * 3 * nv), *z = malloc(sizeof(double) * 3 * nv);
    for (int32_t v = 0; v < nv; ++v) {
        const double *p = x + 3 * v;
        /* scale 3, rotation about z by 0.7, translation */
        y[3 * v] = 3.0 * (cos(0.7) * p[0] - sin(0.7) * p[1]) + 0.4;
        y[3 * v + 1] = 3.0 * (sin(0.7) * p[0] + cos(0.7) * p[1]) - 1.0;
        y[3 * v + 2] = 3.0 * p[2] + 2.0;
        /* inversion in the unit sphere about (0.3, 0.2, 2.1), outside the torus */
        double d[3] = {p[0] - 0.3, p[1] - 0.2, p[2] - 2.1}, d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        for (int c = 0; c < 3; ++c) z[3 * v + c] = d[c] / d2;
    }
    cf_conformal_class a, b, c;
    double dist_similar = -1, dist_inverted = -1, dist_other = -1;
    CHECK_OK(ctx, cf_conformal_class_compute(ctx, m, x, NULL, &a));
    CHECK_OK(ctx, cf_conformal_class_compute(ctx, m, y, NULL, &b));
    CHECK_OK(ctx, cf_conformal_class_distance(ctx, m, x, y, NULL, NULL, &dist_similar));
    /* the inversion reverses the orientation of the surface */
    CHECK_OK(ctx, cf_conformal_class_distance(ctx, m, x, z, NULL, NULL, &dist_inverted));
    CHECK_OK(ctx, cf_conformal_class_compute(ctx, m, z, NULL, &c));
    /* a torus of another class on the same connectivity: radii 1, 0.3 */
    cf_mesh *other = NULL;
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.3, 96, 48, &other));
    if (other) CHECK_OK(ctx, cf_conformal_class_distance(ctx, m, x, cf_mesh_positions(other), NULL, NULL, &dist_other));
    fprintf(stderr, "   similarity: tau %.9f -> %.9f, distance %.2g; inversion: tau %.6f (defect %.2g -> %.2g), distance %.2g; "
                    "R 1 r 0.3: distance %.6f (hyperbolic %.6f)\n",
            a.modulus[1], b.modulus[1], dist_similar, c.modulus[1], a.hodge_defect, c.hodge_defect, dist_inverted,
            dist_other, log(revolution_modulus(1.0, 0.3) / revolution_modulus(1.0, 0.45)));
    CHECK_NEAR(b.modulus[1], a.modulus[1], 1e-10, 0);
    /* the distance hands back both classes, as cf_conformal_class_compute makes them */
    cf_conformal_class a2, b2;
    double dist2 = -1;
    CHECK_OK(ctx, cf_conformal_class_distance(ctx, m, x, y, &a2, &b2, &dist2));
    CHECK(a2.modulus[1] == a.modulus[1] && b2.modulus[1] == b.modulus[1] && dist2 == dist_similar);
    CHECK(a2.hodge_defect == a.hodge_defect && b2.intersection_error == b.intersection_error);
    CHECK_NEAR(dist_similar, 0.0, 0, 1e-10);
    CHECK_NEAR(c.modulus[1], a.modulus[1], 2e-3, 0);
    CHECK_LE(dist_inverted, 2e-3);
    /* genus 1: the hyperbolic distance between i b1 and i b2, |log(b2 / b1)| */
    CHECK_NEAR(dist_other, log(revolution_modulus(1.0, 0.3) / revolution_modulus(1.0, 0.45)), 5e-3, 0);
    free(y);
    free(z);
    cf_mesh_destroy(&m);
    cf_mesh_destroy(&other);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* the Gram matrix summed face by face equals (P^T P)^-1, and its gradient
 * (harmonic representatives held fixed) matches central differences of G
 * recomputed with new harmonic forms: the envelope argument, checked */
static void test_gram_gradient(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.45, 24, 12, &m));
    if (!m) return;
    int32_t nv = cf_mesh_vertex_count(m);
    double *x = malloc(sizeof(double) * 3 * nv), *d = malloc(sizeof(double) * 3 * nv);
    double *xp = malloc(sizeof(double) * 3 * nv), *xm = malloc(sizeof(double) * 3 * nv);
    double *grad = malloc(sizeof(double) * 3 * 3 * nv);
    unsigned seed = 12345u;
    for (int32_t i = 0; i < 3 * nv; ++i) {
        seed = seed * 1103515245u + 12345u;
        double r = (double)(seed >> 8) / (double)(1u << 24) - 0.5;
        seed = seed * 1103515245u + 12345u;
        double r2 = (double)(seed >> 8) / (double)(1u << 24) - 0.5;
        x[i] = cf_mesh_positions(m)[i] * (1.0 + 0.3 * (i % 3 == 0)) + 0.02 * r; /* generic: not a torus of revolution */
        d[i] = r2;
    }
    double gram[4], g_ref[4], gp[4], gm[4];
    cf_conformal_class cls;
    CHECK_OK(ctx, cf_conformal_class_gram_gradient(ctx, m, x, gram, grad));
    CHECK_OK(ctx, cf_conformal_class_compute(ctx, m, x, g_ref, &cls));
    for (int k = 0; k < 4; ++k) CHECK_NEAR(gram[k], g_ref[k], 1e-10, 0);
    const double h = 1e-6;
    for (int32_t i = 0; i < 3 * nv; ++i) {
        xp[i] = x[i] + h * d[i];
        xm[i] = x[i] - h * d[i];
    }
    CHECK_OK(ctx, cf_conformal_class_compute(ctx, m, xp, gp, &cls));
    CHECK_OK(ctx, cf_conformal_class_compute(ctx, m, xm, gm, &cls));
    const int kk[3] = {0, 0, 1}, ll[3] = {0, 1, 1};
    for (int p = 0; p < 3; ++p) {
        double fd = (gp[kk[p] + 2 * ll[p]] - gm[kk[p] + 2 * ll[p]]) / (2 * h), an = 0.0;
        for (int32_t i = 0; i < 3 * nv; ++i) an += grad[(int64_t)p * 3 * nv + i] * d[i];
        fprintf(stderr, "   G_%d%d: directional derivative %.10f, central difference %.10f\n", kk[p], ll[p], an, fd);
        CHECK_NEAR(an, fd, 1e-6, 1e-9);
    }
    /* with no gradient asked: the same G */
    double g2[4];
    CHECK_OK(ctx, cf_conformal_class_gram_gradient(ctx, m, x, g2, NULL));
    for (int k = 0; k < 4; ++k) CHECK(g2[k] == gram[k]);
    CHECK_STATUS(cf_conformal_class_gram_gradient(ctx, m, x, NULL, grad), CF_ERR_INVALID_ARG);
    free(x);
    free(d);
    free(xp);
    free(xm);
    free(grad);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_bad_input(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *sphere = NULL, *torus = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &sphere));
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.4, 12, 6, &torus));
    if (!sphere || !torus) return;
    cf_conformal_class cls;
    double d;
    CHECK_STATUS(cf_conformal_class_compute(ctx, sphere, cf_mesh_positions(sphere), NULL, &cls), CF_ERR_BAD_MESH);
    CHECK(strstr(cf_context_message(ctx), "genus") != NULL);
    CHECK_STATUS(cf_conformal_class_compute(ctx, torus, NULL, NULL, &cls), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_conformal_class_compute(ctx, torus, cf_mesh_positions(torus), NULL, NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_conformal_class_distance(ctx, torus, cf_mesh_positions(torus), cf_mesh_positions(torus), NULL, NULL, NULL),
                 CF_ERR_INVALID_ARG);
    int32_t nv = cf_mesh_vertex_count(torus);
    double *x = malloc(sizeof(double) * 3 * nv);
    memcpy(x, cf_mesh_positions(torus), sizeof(double) * 3 * nv);
    x[3 * 7 + 1] = NAN;
    CHECK_STATUS(cf_conformal_class_distance(ctx, torus, cf_mesh_positions(torus), x, NULL, NULL, &d), CF_ERR_NONFINITE);
    CHECK(strstr(cf_context_message(ctx), "vertex 7") != NULL);
    free(x);
    cf_mesh_destroy(&sphere);
    cf_mesh_destroy(&torus);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_torus_of_revolution);
    CFT_RUN(test_invariance);
    CFT_RUN(test_gram_gradient);
    CFT_RUN(test_bad_input);
    return cft_finish();
}
