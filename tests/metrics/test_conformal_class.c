/* Conformal class of closed surfaces of genus >= 1 (cf_conformal_class_*):
 * the modulus of tori of revolution against i sqrt(R^2 - r^2) / r, with
 * second-order convergence under refinement; invariance under
 * similarities (exact) and under an inversion in a sphere (a conformal map:
 * up to the discretisation); the intersection numbers integral; the
 * distance against the hyperbolic distance of the moduli; the intersection
 * form and the normalised Gram matrix G^ (the class alone) with its
 * derivative; bad input. */
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/linalg.h"
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

/* inverse of a small square matrix through the least-squares routine */
static void small_inverse(int32_t n, const double *a, double *inv)
{
    int64_t lw = cf_dense_least_squares_work_size(n, n);
    double *copy = malloc(sizeof(double) * n * n), *work = malloc(sizeof(double) * lw);
    for (int32_t j = 0; j < n; ++j) {
        memcpy(copy, a, sizeof(double) * n * n);
        for (int32_t i = 0; i < n; ++i) inv[i + j * n] = i == j;
        int32_t rank = 0;
        CHECK(cf_dense_least_squares(n, n, copy, inv + j * n, 1e-14, work, lw, &rank) == CF_OK && rank == n);
    }
    free(copy);
    free(work);
}

/* One surface's intersection form and normalised Gram matrix: I integral,
 * antisymmetric and unimodular; G^ symmetric, with G^ I^-1 G^ = -I (J^2 =
 * -1), a fixed point of the normalisation, unchanged by G -> c G, within
 * the Hodge defect of G; its derivative against central differences and of
 * rank g (g + 1). Returns the largest |G^ - G| relative to |G|. */
static double check_normalized(cf_context *ctx, const cf_mesh *m, const double *x)
{
    int32_t dim = 2 * cf_mesh_genus(m), n2 = dim * dim, pairs = dim * (dim + 1) / 2;
    double *form = malloc(sizeof(double) * n2), *gram = malloc(sizeof(double) * n2), *ghat = malloc(sizeof(double) * n2);
    double *again = malloc(sizeof(double) * n2), *scaled = malloc(sizeof(double) * n2), *finv = malloc(sizeof(double) * n2);
    double *gp = malloc(sizeof(double) * n2), *gm = malloc(sizeof(double) * n2);
    double *deriv = malloc(sizeof(double) * pairs * pairs), *copy = malloc(sizeof(double) * pairs * pairs);
    double worst_rel = 0.0;
    CHECK_OK(ctx, cf_conformal_class_intersection_form(ctx, m, x, form));
    CHECK_OK(ctx, cf_conformal_class_gram_gradient(ctx, m, x, gram, NULL));
    CHECK_OK(ctx, cf_conformal_class_normalize(ctx, dim, form, gram, ghat, deriv));
    small_inverse(dim, form, finv);
    double gnorm = 0.0;
    for (int32_t q = 0; q < n2; ++q) gnorm = fmax(gnorm, fabs(gram[q]));
    for (int32_t i = 0; i < dim; ++i)
        for (int32_t j = 0; j < dim; ++j) {
            double f = form[i + j * dim];
            CHECK(f == nearbyint(f));
            CHECK(f == -form[j + i * dim]);
            CHECK(ghat[i + j * dim] == ghat[j + i * dim]);
            worst_rel = fmax(worst_rel, fabs(ghat[i + j * dim] - gram[i + j * dim]) / gnorm);
            /* G^ I^-1 G^ + I = 0 */
            double sum = form[i + j * dim];
            for (int32_t k = 0; k < dim; ++k)
                for (int32_t l = 0; l < dim; ++l) sum += ghat[i + k * dim] * finv[k + l * dim] * ghat[l + j * dim];
            CHECK_NEAR(sum, 0.0, 0, 1e-11 * gnorm);
        }
    /* I^-1 integral too: unimodular */
    for (int32_t q = 0; q < n2; ++q) CHECK_NEAR(finv[q], nearbyint(finv[q]), 0, 1e-12);
    CHECK_OK(ctx, cf_conformal_class_normalize(ctx, dim, form, ghat, again, NULL));
    for (int32_t q = 0; q < n2; ++q) CHECK_NEAR(again[q], ghat[q], 0, 1e-12 * gnorm);
    for (int32_t q = 0; q < n2; ++q) scaled[q] = 3.7 * gram[q];
    CHECK_OK(ctx, cf_conformal_class_normalize(ctx, dim, form, scaled, again, NULL));
    for (int32_t q = 0; q < n2; ++q) CHECK_NEAR(again[q], ghat[q], 0, 1e-12 * gnorm);
    /* the derivative against central differences in G */
    double worst = 0.0, largest = 0.0, h = 1e-6 * gnorm;
    int32_t q = 0;
    for (int32_t l = 0; l < dim; ++l)
        for (int32_t k = 0; k <= l; ++k, ++q) {
            memcpy(gp, gram, sizeof(double) * n2);
            memcpy(gm, gram, sizeof(double) * n2);
            gp[k + l * dim] += h;
            gm[k + l * dim] -= h;
            if (k != l) {
                gp[l + k * dim] += h;
                gm[l + k * dim] -= h;
            }
            CHECK_OK(ctx, cf_conformal_class_normalize(ctx, dim, form, gp, again, NULL));
            CHECK_OK(ctx, cf_conformal_class_normalize(ctx, dim, form, gm, scaled, NULL));
            int32_t p = 0;
            for (int32_t ll = 0; ll < dim; ++ll)
                for (int32_t kk = 0; kk <= ll; ++kk, ++p) {
                    double fd = (again[kk + ll * dim] - scaled[kk + ll * dim]) / (2 * h);
                    worst = fmax(worst, fabs(fd - deriv[p + q * pairs]));
                    largest = fmax(largest, fabs(fd));
                }
        }
    memcpy(copy, deriv, sizeof(double) * pairs * pairs);
    int64_t lw = cf_dense_least_squares_work_size(pairs, pairs);
    double *work = malloc(sizeof(double) * lw), *rhs = calloc((size_t)pairs, sizeof(double));
    int32_t rank = -1;
    CHECK_OK(ctx, cf_dense_least_squares(pairs, pairs, copy, rhs, 1e-9, work, lw, &rank));
    fprintf(stderr, "   genus %d: |G^ - G| / |G| %.3g, derivative against central differences %.2g (largest %.3g), rank %d of %d\n",
            (int)(dim / 2), worst_rel, worst, largest, (int)rank, (int)pairs);
    CHECK_LE(worst, 1e-7 * largest);
    CHECK(rank == dim / 2 * (dim / 2 + 1));
    free(work);
    free(rhs);
    free(form);
    free(gram);
    free(ghat);
    free(again);
    free(scaled);
    free(finv);
    free(gp);
    free(gm);
    free(deriv);
    free(copy);
    return worst_rel;
}

/* cf_conformal_class_intersection_form and cf_conformal_class_normalize on
 * a generic torus (genus 1: G^ = G / sqrt(det G)) and the generated double
 * torus, as given and moved generically; bad input */
static void test_normalized_gram(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *torus = NULL, *dt = NULL;
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.45, 24, 12, &torus));
    CHECK_OK(ctx, cf_generate_double_torus(ctx, 2, &dt));
    if (!torus || !dt) return;
    cf_mesh *meshes[2] = {torus, dt};
    for (int k = 0; k < 2; ++k) {
        cf_mesh *m = meshes[k];
        int32_t nv = cf_mesh_vertex_count(m);
        double *x = malloc(sizeof(double) * 3 * nv);
        unsigned seed = 777u;
        for (int32_t i = 0; i < 3 * nv; ++i) {
            seed = seed * 1103515245u + 12345u;
            double r = (double)(seed >> 8) / (double)(1u << 24) - 0.5;
            x[i] = cf_mesh_positions(m)[i] * (1.0 + 0.3 * (i % 3 == 0)) + 0.01 * r;
        }
        double rel[2] = {check_normalized(ctx, m, cf_mesh_positions(m)), check_normalized(ctx, m, x)};
        /* G^ differs from G by about the Hodge defect, a discretisation error */
        CHECK_LE(rel[0], 0.2);
        CHECK_LE(rel[1], 0.2);
        if (k == 0) {
            double form[4], gram[4], ghat[4];
            CHECK_OK(ctx, cf_conformal_class_intersection_form(ctx, m, x, form));
            CHECK(form[0] == 0 && form[3] == 0 && fabs(form[1]) == 1 && form[2] == -form[1]);
            CHECK_OK(ctx, cf_conformal_class_gram_gradient(ctx, m, x, gram, NULL));
            CHECK_OK(ctx, cf_conformal_class_normalize(ctx, 2, form, gram, ghat, NULL));
            double s = sqrt(gram[0] * gram[3] - gram[1] * gram[2]);
            for (int q = 0; q < 4; ++q) CHECK_NEAR(ghat[q], gram[q] / s, 0, 1e-13 * fabs(gram[0]));
            /* bad input */
            double bad[4] = {0, 0, 0, 0}, out[4], neg[4] = {-gram[0], -gram[1], -gram[2], -gram[3]};
            CHECK_STATUS(cf_conformal_class_normalize(ctx, 2, NULL, gram, out, NULL), CF_ERR_INVALID_ARG);
            CHECK_STATUS(cf_conformal_class_normalize(ctx, 3, form, gram, out, NULL), CF_ERR_INVALID_ARG);
            CHECK_STATUS(cf_conformal_class_normalize(ctx, 2, bad, gram, out, NULL), CF_ERR_INVALID_ARG);
            CHECK(strstr(cf_context_message(ctx), "singular") != NULL);
            double nan_gram[4] = {gram[0], NAN, gram[2], gram[3]};
            CHECK_STATUS(cf_conformal_class_normalize(ctx, 2, form, nan_gram, out, NULL), CF_ERR_NONFINITE);
            /* -G: the star's eigenvalues are still imaginary for genus 1, J flips sign and G^ = -G / sqrt(det) */
            CHECK_OK(ctx, cf_conformal_class_normalize(ctx, 2, form, neg, out, NULL));
            double sym[4] = {form[0], form[1], form[1], form[3]}; /* symmetric: real eigenvalues of S */
            CHECK_STATUS(cf_conformal_class_normalize(ctx, 2, sym, gram, out, NULL), CF_ERR_NUMERICAL);
            CHECK(strstr(cf_context_message(ctx), "complex structure") != NULL);
            CHECK_STATUS(cf_conformal_class_intersection_form(ctx, m, x, NULL), CF_ERR_INVALID_ARG);
        }
        free(x);
    }
    cf_mesh *sphere = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 1, 1.0, &sphere));
    double f4[4];
    if (sphere) CHECK_STATUS(cf_conformal_class_intersection_form(ctx, sphere, cf_mesh_positions(sphere), f4), CF_ERR_BAD_MESH);
    cf_mesh_destroy(&sphere);
    cf_mesh_destroy(&torus);
    cf_mesh_destroy(&dt);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* cf_conformal_class_workspace: the same G and dG/dx as
 * cf_conformal_class_gram_gradient for two position sets of one torus, bit
 * for bit for the first (the harmonic workspace builds its Laplacian as
 * cf_harmonic_basis does), to rounding for the second (it refills it);
 * refused on a sphere; bad input */
static void test_class_workspace(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL, *sphere = NULL;
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.45, 24, 12, &m));
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 1, 1.0, &sphere));
    if (m && sphere) {
        int32_t nv = cf_mesh_vertex_count(m);
        double *x = malloc(sizeof(double) * 3 * nv), *ga = malloc(sizeof(double) * 9 * nv);
        double *gb = malloc(sizeof(double) * 9 * nv), gram_a[4], gram_b[4];
        cf_conformal_class_workspace *w = NULL;
        CHECK_OK(ctx, cf_conformal_class_workspace_create(ctx, m, &w));
        for (int variant = 0; w && variant < 2; ++variant) {
            for (int32_t i = 0; i < 3 * nv; ++i) x[i] = cf_mesh_positions(m)[i] * (variant && i % 3 == 1 ? 1.7 : 1.0);
            CHECK_OK(ctx, cf_conformal_class_gram_gradient(ctx, m, x, gram_a, ga));
            CHECK_OK(ctx, cf_conformal_class_workspace_gram_gradient(w, x, gram_b, gb));
            if (variant == 0) {
                CHECK(memcmp(gram_a, gram_b, sizeof gram_a) == 0);
                CHECK(memcmp(ga, gb, sizeof(double) * 9 * nv) == 0);
                continue;
            }
            double worst = 0.0, largest = 0.0;
            for (int k = 0; k < 4; ++k) CHECK_NEAR(gram_b[k], gram_a[k], 1e-12, 1e-14);
            for (int32_t i = 0; i < 9 * nv; ++i) {
                worst = fmax(worst, fabs(ga[i] - gb[i]));
                largest = fmax(largest, fabs(ga[i]));
            }
            CHECK_LE(worst, 1e-10 * largest);
        }
        CHECK_STATUS(cf_conformal_class_workspace_gram_gradient(w, x, NULL, gb), CF_ERR_INVALID_ARG);
        x[4] = INFINITY;
        CHECK_STATUS(cf_conformal_class_workspace_gram_gradient(w, x, gram_b, gb), CF_ERR_NONFINITE);
        CHECK_STATUS(cf_conformal_class_workspace_gram_gradient(NULL, x, gram_b, gb), CF_ERR_INVALID_ARG);
        cf_conformal_class_workspace_destroy(&w);
        CHECK(w == NULL);
        CHECK_STATUS(cf_conformal_class_workspace_create(ctx, sphere, &w), CF_ERR_BAD_MESH);
        CHECK(w == NULL && strstr(cf_context_message(ctx), "genus") != NULL);
        CHECK_STATUS(cf_conformal_class_workspace_create(ctx, m, NULL), CF_ERR_INVALID_ARG);
        free(x);
        free(ga);
        free(gb);
    }
    cf_mesh_destroy(&m);
    cf_mesh_destroy(&sphere);
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
    CFT_RUN(test_normalized_gram);
    CFT_RUN(test_class_workspace);
    CFT_RUN(test_bad_input);
    return cft_finish();
}
