/* Cotan Laplacian: L 1 = 0, symmetry, PSD, linear precision on a flat grid,
 * agreement with the per-edge weights and the refill path, the floored
 * weights. */
#include "curvflow/generate.h"
#include "curvflow/ops.h"
#include "ops/cotan_laplacian.h"
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>

static uint64_t rng_state = 0x853c49e6748fea9bull;
static double urand(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) / 9007199254740992.0 * 2.0 - 1.0;
}

/* entry (i, j) of a CSC matrix, 0 if absent */
static double entry(const cf_sparse *a, int32_t i, int32_t j)
{
    for (int32_t k = a->colptr[j]; k < a->colptr[j + 1]; ++k)
        if (a->rowind[k] == i) return a->values[k];
    return 0.0;
}

static void check_basic_properties(cf_context *ctx, const cf_mesh *mesh, const double *x)
{
    cf_sparse *l = NULL;
    CHECK_OK(ctx, cf_cotan_laplacian(ctx, mesh, x, &l));
    if (!l) return;
    int32_t nv = cf_mesh_vertex_count(mesh);
    CHECK(l->nrows == nv && l->ncols == nv);
    double *ones = malloc(sizeof(double) * nv), *y = malloc(sizeof(double) * nv), *r = malloc(sizeof(double) * nv);
    double scale = 0;
    for (int32_t i = 0; i < nv; ++i) ones[i] = 1.0;
    for (int64_t k = 0; k < cf_sparse_nnz(l); ++k) scale = fmax(scale, fabs(l->values[k]));
    cf_sparse_multiply(l, ones, y);
    for (int32_t i = 0; i < nv; ++i) CHECK_NEAR(y[i], 0.0, 0, 1e-13 * scale); /* L 1 = 0 */
    /* symmetry, entry by entry */
    for (int32_t j = 0; j < nv; ++j)
        for (int32_t k = l->colptr[j]; k < l->colptr[j + 1]; ++k)
            CHECK_NEAR(l->values[k], entry(l, j, l->rowind[k]), 0, 1e-15 * scale);
    /* PSD on random vectors: x^T L x = sum_e w_e (x_i - x_j)^2 >= 0 need not
     * hold edge by edge (negative weights), but the sum is a Dirichlet
     * energy and must be >= 0 (-roundoff) */
    for (int t = 0; t < 20; ++t) {
        for (int32_t i = 0; i < nv; ++i) r[i] = urand();
        cf_sparse_multiply(l, r, y);
        double q = 0;
        for (int32_t i = 0; i < nv; ++i) q += r[i] * y[i];
        CHECK(q >= -1e-12 * scale * nv);
    }
    /* matrix-free application and per-edge weights agree with the matrix */
    double *y2 = malloc(sizeof(double) * nv);
    for (int32_t i = 0; i < nv; ++i) r[i] = urand();
    cf_sparse_multiply(l, r, y);
    CHECK_OK(ctx, cfi_cotan_laplacian_apply(ctx, mesh, x, 1, r, y2));
    for (int32_t i = 0; i < nv; ++i) CHECK_NEAR(y2[i], y[i], 0, 1e-12 * scale);
    int32_t ne = cf_mesh_edge_count(mesh);
    const int32_t *ev = cf_mesh_edge_vertices(mesh);
    double *w = malloc(sizeof(double) * ne);
    CHECK_OK(ctx, cf_cotan_weights(ctx, mesh, x, w));
    for (int32_t e = 0; e < ne; ++e) CHECK_NEAR(entry(l, ev[2 * e], ev[2 * e + 1]), -w[e], 0, 1e-14 * scale);
    free(w);
    free(y2);
    free(ones);
    free(y);
    free(r);
    cf_sparse_destroy(&l);
}

static void test_closed_and_open_meshes(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 3, 1.5, &m));
    if (m) check_basic_properties(ctx, m, cf_mesh_positions(m));
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_torus(ctx, 2.0, 0.6, 30, 12, &m));
    if (m) check_basic_properties(ctx, m, cf_mesh_positions(m));
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_bumpy_plane(ctx, 16, 1.0, 0.2, 3u, &m));
    if (m) check_basic_properties(ctx, m, cf_mesh_positions(m));
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Linear precision: on a flat mesh the cotan Laplacian of a linear function
 * vanishes at interior vertices (Pinkall & Polthier 1993), also on an
 * irregular (jittered) grid. At boundary vertices it does not. */
static void test_flat_grid_linear_precision(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_grid(ctx, 12, 9, 2.0, 1.5, &m));
    if (!m) return;
    int32_t nv = cf_mesh_vertex_count(m);
    const uint8_t *on_b = cf_mesh_vertex_on_boundary(m);
    double *x = malloc(sizeof(double) * 3 * nv), *f = malloc(sizeof(double) * nv), *y = malloc(sizeof(double) * nv);
    for (int32_t i = 0; i < 3 * nv; ++i) x[i] = cf_mesh_positions(m)[i];
    for (int32_t v = 0; v < nv; ++v)
        if (!on_b[v]) {
            x[3 * v] += 0.04 * urand();
            x[3 * v + 1] += 0.04 * urand();
        }
    cf_sparse *l = NULL;
    CHECK_OK(ctx, cf_cotan_laplacian(ctx, m, x, &l));
    for (int32_t v = 0; v < nv; ++v) f[v] = 0.3 + 1.7 * x[3 * v] - 2.9 * x[3 * v + 1];
    cf_sparse_multiply(l, f, y);
    int boundary_nonzero = 0;
    for (int32_t v = 0; v < nv; ++v) {
        if (!on_b[v]) CHECK_NEAR(y[v], 0.0, 0, 1e-12);
        else boundary_nonzero += fabs(y[v]) > 1e-6;
    }
    CHECK(boundary_nonzero > 0);
    cf_sparse_destroy(&l);
    free(x);
    free(f);
    free(y);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Analytic weights: on a right isosceles grid cell the diagonal edge has
 * weight cot(pi/2)... = 0 from both sides, axis edges 1/2 from each side. */
static void test_grid_weights(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_grid(ctx, 4, 4, 1.0, 1.0, &m));
    if (!m) return;
    int32_t ne = cf_mesh_edge_count(m);
    const int32_t *ev = cf_mesh_edge_vertices(m);
    const double *x = cf_mesh_positions(m);
    const uint8_t *on_b = cf_mesh_vertex_on_boundary(m);
    double *w = malloc(sizeof(double) * ne);
    CHECK_OK(ctx, cf_cotan_weights(ctx, m, x, w));
    for (int32_t e = 0; e < ne; ++e) {
        const double *a = x + 3 * ev[2 * e], *b = x + 3 * ev[2 * e + 1];
        int diagonal = a[0] != b[0] && a[1] != b[1];
        int boundary_edge = on_b[ev[2 * e]] && on_b[ev[2 * e + 1]] && (a[0] == b[0] ? (a[0] == 0 || a[0] == 1)
                                                                                       : (a[1] == 0 || a[1] == 1));
        double expect = diagonal ? 0.0 : (boundary_edge ? 0.5 : 1.0);
        CHECK_NEAR(w[e], expect, 0, 1e-14);
    }
    free(w);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* The refill path reproduces a fresh assembly after the geometry changes,
 * without allocating. */
static void test_refill(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 2, 0.2, 11u, &m));
    if (!m) return;
    int32_t nv = cf_mesh_vertex_count(m);
    int64_t n = cfi_cotan_laplacian_triplet_count(m);
    CHECK(n == nv + 2 * (int64_t)cf_mesh_edge_count(m));
    int64_t *slots = malloc(sizeof(int64_t) * n);
    cf_sparse *l = NULL, *fresh = NULL;
    CHECK_OK(ctx, cfi_cotan_laplacian_pattern(ctx, m, cf_mesh_positions(m), 0.0, &l, slots));
    double *y = malloc(sizeof(double) * 3 * nv);
    for (int32_t i = 0; i < 3 * nv; ++i) y[i] = cf_mesh_positions(m)[i] * (1.0 + 0.05 * urand());
    int64_t allocs = cf_context_allocation_count(ctx);
    CHECK_OK(ctx, cfi_cotan_laplacian_refill(l, m, y, 0.0, slots));
    CHECK(cf_context_allocation_count(ctx) == allocs);
    CHECK_OK(ctx, cf_cotan_laplacian(ctx, m, y, &fresh));
    CHECK(cf_sparse_nnz(l) == cf_sparse_nnz(fresh));
    for (int64_t k = 0; k < cf_sparse_nnz(l); ++k) {
        CHECK(l->rowind[k] == fresh->rowind[k]);
        CHECK_NEAR(l->values[k], fresh->values[k], 0, 1e-13);
    }
    cf_sparse_destroy(&l);
    cf_sparse_destroy(&fresh);
    free(slots);
    free(y);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* The public refill path (what the flows use; ops/cotan_laplacian.h is
 * private to ops) gives the values of the private one, bit for bit, and the
 * single-corner angle equals cf_corner_angles. */
static void test_public_refill(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 2, 0.2, 5u, &m));
    if (!m) return;
    int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m);
    int64_t n = cf_cotan_laplacian_slot_count(m);
    CHECK(n == cfi_cotan_laplacian_triplet_count(m));
    int64_t *slots = malloc(sizeof(int64_t) * n), *slots2 = malloc(sizeof(int64_t) * n);
    cf_sparse *l = NULL, *l2 = NULL;
    CHECK_STATUS(cf_cotan_laplacian_with_slots(ctx, m, cf_mesh_positions(m), &l, NULL), CF_ERR_INVALID_ARG);
    CHECK_OK(ctx, cf_cotan_laplacian_with_slots(ctx, m, cf_mesh_positions(m), &l, slots));
    CHECK_OK(ctx, cfi_cotan_laplacian_pattern(ctx, m, cf_mesh_positions(m), 0.0, &l2, slots2));
    double *y = malloc(sizeof(double) * 3 * nv);
    for (int32_t i = 0; i < 3 * nv; ++i) y[i] = cf_mesh_positions(m)[i] * (1.0 + 0.05 * urand());
    CHECK_OK(ctx, cf_cotan_laplacian_refill(l, m, y, slots));
    CHECK_OK(ctx, cfi_cotan_laplacian_refill(l2, m, y, 0.0, slots2));
    for (int64_t k = 0; k < cf_sparse_nnz(l); ++k) CHECK(l->values[k] == l2->values[k]);
    CHECK_STATUS(cf_cotan_laplacian_refill(l, m, y, NULL), CF_ERR_INVALID_ARG);
    double *angles = malloc(sizeof(double) * 3 * nf);
    CHECK_OK(ctx, cf_corner_angles(ctx, m, y, angles));
    for (int32_t f = 0; f < nf; ++f)
        for (int k = 0; k < 3; ++k) CHECK(cf_corner_angle(y, cf_mesh_triangles(m) + 3 * f, k) == angles[3 * f + k]);
    cf_sparse_destroy(&l);
    cf_sparse_destroy(&l2);
    free(slots);
    free(slots2);
    free(y);
    free(angles);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* The weight floor (session 30): a face's cotangents as if twice its area
 * were at least floor * (sum of squared edges). On a mesh whose faces are
 * all above the floor every floored operator equals the exact one bit for
 * bit; a near-duplicate vertex (at 1e-12 of an edge from its neighbour)
 * has exact weights of order 1e12 and floored ones of order 1 / floor, the
 * others unchanged; L 1 = 0 and symmetry hold; the floor's range is checked.
 * The floored solvers (edge Poisson, fairing) agree with the exact ones on
 * a mesh above the floor. */
static void test_weight_floor(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 2, 0.2, 5u, &m));
    if (!m) return;
    int32_t nv = cf_mesh_vertex_count(m), ne = cf_mesh_edge_count(m), nf = cf_mesh_face_count(m);
    const double *x = cf_mesh_positions(m);
    int64_t n = cf_cotan_laplacian_slot_count(m);
    int64_t *slots = malloc(sizeof(int64_t) * n), *slots2 = malloc(sizeof(int64_t) * n);
    double *w = malloc(sizeof(double) * ne), *wf = malloc(sizeof(double) * ne), *y = malloc(sizeof(double) * 3 * nv);
    cf_sparse *l = NULL, *lf = NULL, *ls = NULL;
    /* above the floor: bit for bit */
    CHECK_OK(ctx, cf_cotan_weights(ctx, m, x, w));
    CHECK_OK(ctx, cf_cotan_weights_floored(ctx, m, x, 1e-8, wf));
    CHECK(memcmp(w, wf, sizeof(double) * ne) == 0);
    CHECK_OK(ctx, cf_cotan_laplacian(ctx, m, x, &l));
    CHECK_OK(ctx, cf_cotan_laplacian_floored(ctx, m, x, 1e-8, &lf));
    CHECK_OK(ctx, cf_cotan_laplacian_with_slots_floored(ctx, m, x, 1e-8, &ls, slots));
    for (int64_t k = 0; l && lf && ls && k < cf_sparse_nnz(l); ++k)
        CHECK(l->values[k] == lf->values[k] && l->values[k] == ls->values[k]);
    cf_sparse_destroy(&lf);
    /* a near-duplicate vertex: face 100's first corner at 1e-12 of the way from its second */
    memcpy(y, x, sizeof(double) * 3 * nv);
    const int32_t *t = cf_mesh_triangles(m) + 3 * 100;
    for (int c = 0; c < 3; ++c) y[3 * t[0] + c] = x[3 * t[1] + c] + 1e-12 * (x[3 * t[0] + c] - x[3 * t[1] + c]);
    CHECK_OK(ctx, cf_cotan_weights(ctx, m, y, w));
    CHECK_OK(ctx, cf_cotan_weights_floored(ctx, m, y, 1e-8, wf));
    double exact_max = 0.0, floored_max = 0.0;
    int32_t changed = 0;
    for (int32_t e = 0; e < ne; ++e) {
        exact_max = fmax(exact_max, fabs(w[e]));
        floored_max = fmax(floored_max, fabs(wf[e]));
        changed += w[e] != wf[e];
    }
    fprintf(stderr, "   near-duplicate at 1e-12: largest weight %.3g exact, %.3g floored (1e-8); %d edges changed\n",
            exact_max, floored_max, (int)changed);
    CHECK(exact_max > 1e10);
    CHECK(floored_max < 1e8 && floored_max > 1e6);
    CHECK(changed > 0 && changed <= 6); /* the edges of the two thin faces */
    /* the floored L: refill equals a fresh build, L 1 = 0, symmetric */
    CHECK_OK(ctx, cf_cotan_laplacian_refill_floored(ls, m, y, 1e-8, slots));
    CHECK_OK(ctx, cf_cotan_laplacian_floored(ctx, m, y, 1e-8, &lf));
    double scale = 0.0;
    for (int64_t k = 0; lf && k < cf_sparse_nnz(lf); ++k) scale = fmax(scale, fabs(lf->values[k]));
    CHECK(scale < 1e8);
    /* the same sums in another order: equal to rounding */
    for (int64_t k = 0; ls && lf && k < cf_sparse_nnz(ls); ++k) CHECK_NEAR(ls->values[k], lf->values[k], 0, 1e-15 * scale);
    double *ones = malloc(sizeof(double) * nv), *r = malloc(sizeof(double) * nv);
    for (int32_t i = 0; i < nv; ++i) ones[i] = 1.0;
    if (lf) cf_sparse_multiply(lf, ones, r);
    for (int32_t i = 0; lf && i < nv; ++i) CHECK_NEAR(r[i], 0.0, 0, 1e-13 * scale);
    for (int32_t j = 0; lf && j < nv; ++j)
        for (int32_t k = lf->colptr[j]; k < lf->colptr[j + 1]; ++k)
            CHECK(lf->values[k] == entry(lf, j, lf->rowind[k]));
    /* the floor's range */
    CHECK_STATUS(cf_cotan_weights_floored(ctx, m, y, -1e-9, wf), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "weight_floor -1e-09 outside [0, 1]") != NULL);
    CHECK_STATUS(cf_cotan_laplacian_floored(ctx, m, y, NAN, &l), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_cotan_laplacian_refill_floored(ls, m, y, 2.0, slots), CF_ERR_INVALID_ARG);
    cf_edge_poisson *p = NULL;
    CHECK_STATUS(cf_edge_poisson_create_floored(ctx, m, y, 0, NULL, 1.5, &p), CF_ERR_INVALID_ARG);
    cf_vertex_fairing *fa = NULL;
    CHECK_STATUS(cf_vertex_fairing_create_floored(ctx, m, y, 1, -1.0, &fa), CF_ERR_INVALID_ARG);
    /* the solvers above the floor: the same results as the exact ones */
    cf_edge_poisson *p0 = NULL;
    CHECK_OK(ctx, cf_edge_poisson_create(ctx, m, x, 0, NULL, &p0));
    CHECK_OK(ctx, cf_edge_poisson_create_floored(ctx, m, x, 0, NULL, 1e-8, &p));
    double *edges = malloc(sizeof(double) * 3 * ne), *f0 = malloc(sizeof(double) * 3 * nv),
           *f1 = malloc(sizeof(double) * 3 * nv);
    const int32_t *ev = cf_mesh_edge_vertices(m);
    for (int32_t e = 0; e < ne; ++e)
        for (int c = 0; c < 3; ++c) edges[3 * e + c] = 1.1 * (x[3 * ev[2 * e + 1] + c] - x[3 * ev[2 * e] + c]);
    if (p0 && p) {
        CHECK_OK(ctx, cf_edge_poisson_solve(p0, edges, NULL, f0, NULL));
        CHECK_OK(ctx, cf_edge_poisson_solve(p, edges, NULL, f1, NULL));
        CHECK(memcmp(f0, f1, sizeof(double) * 3 * nv) == 0);
    }
    cf_vertex_fairing *fa0 = NULL;
    CHECK_OK(ctx, cf_vertex_fairing_create(ctx, m, x, 1, &fa0));
    CHECK_OK(ctx, cf_vertex_fairing_create_floored(ctx, m, x, 1, 1e-8, &fa));
    if (fa0 && fa) {
        CHECK_OK(ctx, cf_vertex_fairing_apply(fa0, 0.5, x, f0, NULL));
        CHECK_OK(ctx, cf_vertex_fairing_apply(fa, 0.5, x, f1, NULL));
        CHECK(memcmp(f0, f1, sizeof(double) * 3 * nv) == 0);
    }
    (void)nf;
    cf_edge_poisson_destroy(&p0);
    cf_edge_poisson_destroy(&p);
    cf_vertex_fairing_destroy(&fa0);
    cf_vertex_fairing_destroy(&fa);
    cf_sparse_destroy(&l);
    cf_sparse_destroy(&lf);
    cf_sparse_destroy(&ls);
    free(edges);
    free(f0);
    free(f1);
    free(ones);
    free(r);
    free(slots);
    free(slots2);
    free(w);
    free(wf);
    free(y);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Relabelling the vertices permutes L: L'[p(i), p(j)] = L[i, j]. */
static void test_relabelling(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL, *m2 = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 2, 0.3, 8u, &m));
    if (!m) return;
    int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m);
    int32_t *p = malloc(sizeof(int32_t) * nv), *tri = malloc(sizeof(int32_t) * 3 * nf);
    double *x = malloc(sizeof(double) * 3 * nv);
    for (int32_t i = 0; i < nv; ++i) p[i] = i;
    for (int32_t i = nv - 1; i > 0; --i) { /* Fisher-Yates with the test LCG */
        int32_t j = (int32_t)((urand() * 0.5 + 0.5) * (i + 1));
        if (j > i) j = i;
        int32_t t = p[i];
        p[i] = p[j];
        p[j] = t;
    }
    for (int32_t i = 0; i < nv; ++i)
        for (int c = 0; c < 3; ++c) x[3 * p[i] + c] = cf_mesh_positions(m)[3 * i + c];
    for (int32_t i = 0; i < 3 * nf; ++i) tri[i] = p[cf_mesh_triangles(m)[i]];
    cf_mesh_desc d = {nv, x, nf, tri, 0, NULL, NULL};
    CHECK_OK(ctx, cf_mesh_create(ctx, &d, &m2));
    cf_sparse *l = NULL, *l2 = NULL;
    CHECK_OK(ctx, cf_cotan_laplacian(ctx, m, cf_mesh_positions(m), &l));
    if (m2) CHECK_OK(ctx, cf_cotan_laplacian(ctx, m2, x, &l2));
    if (l && l2) {
        CHECK(cf_sparse_nnz(l) == cf_sparse_nnz(l2));
        for (int32_t j = 0; j < nv; ++j)
            for (int32_t k = l->colptr[j]; k < l->colptr[j + 1]; ++k)
                CHECK_NEAR(entry(l2, p[l->rowind[k]], p[j]), l->values[k], 0, 1e-14);
    }
    cf_sparse_destroy(&l);
    cf_sparse_destroy(&l2);
    cf_mesh_destroy(&m2);
    cf_mesh_destroy(&m);
    free(p);
    free(tri);
    free(x);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* cf_cotan_laplacian on the rest positions, for cft_allocation_sweep; a
 * failure that leaves an output matrix is an error of its own. */
static cf_status laplacian_call(cf_context *ctx, void *user)
{
    const cf_mesh *m = user;
    cf_sparse *l = NULL;
    cf_status s = cf_cotan_laplacian(ctx, m, cf_mesh_positions(m), &l);
    if (s != CF_OK && l) s = CF_ERR_INVALID_ARG;
    cf_sparse_destroy(&l);
    return s;
}

static void test_failures(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 1, 1.0, &m));
    if (!m) return;
    int32_t nv = cf_mesh_vertex_count(m);
    cf_sparse *l = NULL;
    CHECK_STATUS(cf_cotan_laplacian(ctx, m, NULL, &l), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_cotan_laplacian(ctx, NULL, cf_mesh_positions(m), &l), CF_ERR_INVALID_ARG);
    /* collapse face 0 onto a point: zero area is reported with the face */
    double *x = malloc(sizeof(double) * 3 * nv);
    for (int32_t i = 0; i < 3 * nv; ++i) x[i] = cf_mesh_positions(m)[i];
    const int32_t *t = cf_mesh_triangles(m);
    for (int c = 0; c < 3; ++c) x[3 * t[1] + c] = x[3 * t[2] + c] = x[3 * t[0] + c];
    CHECK_STATUS(cf_cotan_laplacian(ctx, m, x, &l), CF_ERR_DEGENERATE_FACE);
    CHECK(l == NULL);
    /* allocation failure at every allocation: clean NOMEM, no output, no leak */
    CHECK(cft_allocation_sweep(ctx, "laplacian", laplacian_call, m, 0) > 0);
    free(x);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_closed_and_open_meshes);
    CFT_RUN(test_flat_grid_linear_precision);
    CFT_RUN(test_grid_weights);
    CFT_RUN(test_refill);
    CFT_RUN(test_public_refill);
    CFT_RUN(test_relabelling);
    CFT_RUN(test_weight_floor);
    CFT_RUN(test_failures);
    return cft_finish();
}
