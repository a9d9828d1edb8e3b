/* Mesh connectivity: every table checked against its definition on
 * closed, boundary, multi-component and higher-genus fixtures; counts
 * invariant under relabelling; allocation-failure injection. */
#include "curvflow/generate.h"
#include "curvflow/mesh.h"
#include "mesh/mesh_internal.h"
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Checks every connectivity array of m against its definition. */
static void check_connectivity(const cf_mesh *m)
{
    const int32_t nv = cf_mesh_vertex_count(m), nf = cf_mesh_face_count(m), ne = cf_mesh_edge_count(m);
    const int32_t *tri = cf_mesh_triangles(m), *ev = cf_mesh_edge_vertices(m);
    const int32_t *he = cf_mesh_halfedge_edge(m), *tw = cf_mesh_halfedge_twin(m), *ef = cf_mesh_edge_faces(m);
    int bad = 0;
    int32_t boundary_he = 0;
    uint8_t *touch = calloc((size_t)nv, 1);
    for (int32_t h = 0; h < 3 * nf; ++h) {
        int32_t a = tri[h], b = tri[cfi_he_next(h)], e = he[h];
        int32_t lo = a < b ? a : b, hi = a < b ? b : a;
        if (e < 0 || e >= ne || ev[2 * e] != lo || ev[2 * e + 1] != hi) ++bad;
        if (ef[2 * e + (a == lo ? 0 : 1)] != h / 3) ++bad;
        int32_t t = tw[h];
        if (t >= 0) {
            if (tw[t] != h || tri[t] != b || tri[cfi_he_next(t)] != a || he[t] != e) ++bad;
        } else {
            ++boundary_he;
            touch[a] = touch[b] = 1;
            if (ef[2 * e + (a == lo ? 1 : 0)] != -1) ++bad;
        }
    }
    CHECK(bad == 0);
    /* edges sorted lexicographically, i < j, each with a halfedge */
    bad = 0;
    for (int32_t e = 0; e < ne; ++e) {
        if (ev[2 * e] >= ev[2 * e + 1]) ++bad;
        if (e > 0 && (ev[2 * e - 2] > ev[2 * e] || (ev[2 * e - 2] == ev[2 * e] && ev[2 * e - 1] >= ev[2 * e + 1])))
            ++bad;
        if (he[m->edge_halfedge[e]] != e) ++bad;
    }
    CHECK(bad == 0);
    CHECK(2 * ne == 3 * nf + boundary_he);
    /* boundary flags */
    bad = 0;
    for (int32_t v = 0; v < nv; ++v)
        if (cf_mesh_vertex_on_boundary(m)[v] != touch[v]) ++bad;
    CHECK(bad == 0);
    /* rings: sorted neighbours joined by the listed edge */
    const int32_t *ro = cf_mesh_vertex_ring_offsets(m), *rn = cf_mesh_vertex_neighbors(m), *re = cf_mesh_vertex_edges(m);
    bad = 0;
    CHECK(ro[0] == 0 && ro[nv] == 2 * ne);
    for (int32_t v = 0; v < nv; ++v)
        for (int32_t k = ro[v]; k < ro[v + 1]; ++k) {
            int32_t w = rn[k], e = re[k];
            int32_t lo = v < w ? v : w, hi = v < w ? w : v;
            if (ev[2 * e] != lo || ev[2 * e + 1] != hi) ++bad;
            if (k > ro[v] && rn[k - 1] >= w) ++bad;
        }
    CHECK(bad == 0);
    /* vertex faces: increasing, each containing v; 3 nf in total */
    const int32_t *fo = cf_mesh_vertex_face_offsets(m), *vf = cf_mesh_vertex_faces(m);
    bad = 0;
    CHECK(fo[0] == 0 && fo[nv] == 3 * nf);
    for (int32_t v = 0; v < nv; ++v)
        for (int32_t k = fo[v]; k < fo[v + 1]; ++k) {
            int32_t f = vf[k];
            if (tri[3 * f] != v && tri[3 * f + 1] != v && tri[3 * f + 2] != v) ++bad;
            if (k > fo[v] && vf[k - 1] >= f) ++bad;
        }
    CHECK(bad == 0);
    /* boundary loops follow boundary halfedges (interior on the left) */
    const int32_t nb = cf_mesh_boundary_loop_count(m);
    const int32_t *bo = cf_mesh_boundary_loop_offsets(m), *bv = cf_mesh_boundary_loop_vertices(m);
    CHECK(bo[0] == 0 && bo[nb] == boundary_he);
    bad = 0;
    for (int32_t b = 0; b < nb; ++b)
        for (int32_t k = bo[b]; k < bo[b + 1]; ++k) {
            int32_t a = bv[k], c = bv[k + 1 < bo[b + 1] ? k + 1 : bo[b]];
            int found = 0;
            for (int32_t j = fo[a]; j < fo[a + 1]; ++j)
                for (int q = 0; q < 3; ++q) {
                    int32_t h = 3 * vf[j] + q;
                    if (tw[h] < 0 && tri[h] == a && tri[cfi_he_next(h)] == c) found = 1;
                }
            if (!found) ++bad;
        }
    CHECK(bad == 0);
    /* components: edges and faces stay inside one component; ids 0..c-1 */
    const int32_t *vc = cf_mesh_vertex_component(m);
    bad = 0;
    for (int32_t e = 0; e < ne; ++e)
        if (vc[ev[2 * e]] != vc[ev[2 * e + 1]]) ++bad;
    for (int32_t f = 0; f < nf; ++f)
        if (m->face_component[f] != vc[tri[3 * f]]) ++bad;
    for (int32_t v = 0; v < nv; ++v)
        if (vc[v] < 0 || vc[v] >= cf_mesh_component_count(m)) ++bad;
    CHECK(bad == 0);
    CHECK(cf_mesh_euler_characteristic(m) == nv - ne + nf);
    free(touch);
}

static void test_tetrahedron(void)
{
    const double pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    const int32_t tri[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    cf_context *ctx = cft_context();
    cf_mesh_desc d = {4, pos, 4, tri, 0, NULL, NULL};
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_mesh_create(ctx, &d, &m));
    CHECK(cf_mesh_edge_count(m) == 6);
    CHECK(cf_mesh_euler_characteristic(m) == 2);
    CHECK(cf_mesh_genus(m) == 0);
    CHECK(cf_mesh_boundary_loop_count(m) == 0);
    CHECK(cf_mesh_component_count(m) == 1);
    CHECK(cf_mesh_context(m) == ctx);
    CHECK(cf_mesh_uv(m) == NULL && cf_mesh_uv_triangles(m) == NULL && cf_mesh_uv_count(m) == 0);
    /* edge 0 is (0, 1): runs 1->0 in face 0 and 0->1 in face 1 */
    CHECK(cf_mesh_edge_vertices(m)[0] == 0 && cf_mesh_edge_vertices(m)[1] == 1);
    CHECK(cf_mesh_edge_faces(m)[0] == 1 && cf_mesh_edge_faces(m)[1] == 0);
    /* positions are copied */
    CHECK(cf_mesh_positions(m) != pos && cf_mesh_positions(m)[11] == 1.0);
    check_connectivity(m);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_single_triangle_and_two_components(void)
{
    /* triangle + a separate tetrahedron */
    const double pos[] = {5, 5, 5, 6, 5, 5, 5, 6, 5, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    const int32_t tri[] = {0, 1, 2, 3, 5, 4, 3, 4, 6, 3, 6, 5, 4, 5, 6};
    cf_context *ctx = cft_context();
    cf_mesh_desc d = {7, pos, 5, tri, 0, NULL, NULL};
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_mesh_create(ctx, &d, &m));
    CHECK(cf_mesh_component_count(m) == 2);
    CHECK(cf_mesh_boundary_loop_count(m) == 1);
    CHECK(cf_mesh_euler_characteristic(m) == 3); /* disk 1 + sphere 2 */
    CHECK(cf_mesh_genus(m) == 0);
    const int32_t *bv = cf_mesh_boundary_loop_vertices(m);
    CHECK(bv[0] == 0 && bv[1] == 1 && bv[2] == 2); /* along the face's own order */
    CHECK(cf_mesh_vertex_component(m)[0] == 0 && cf_mesh_vertex_component(m)[3] == 1);
    check_connectivity(m);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_generated_fixtures(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_torus(ctx, 3.0, 1.0, 24, 10, &m));
    check_connectivity(m);
    CHECK(cf_mesh_genus(m) == 1);
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 12, 4, 1.0, 2.0, &m));
    check_connectivity(m);
    CHECK(cf_mesh_boundary_loop_count(m) == 2);
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_double_torus(ctx, 2, &m));
    check_connectivity(m);
    CHECK(cf_mesh_genus(m) == 2);
    cf_mesh_destroy(&m);
    CHECK_OK(ctx, cf_generate_grid(ctx, 7, 3, 1.0, 1.0, &m));
    check_connectivity(m);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Bipyramid over a 300-gon: both apexes have valence 300, which takes the
 * O(k log k) sorting path for large buckets (and faces are listed in a
 * scrambled order). */
static void test_high_valence(void)
{
    enum { N = 300 };
    static double pos[3 * (N + 2)];
    static int32_t tri[3 * 2 * N];
    pos[2] = 1.0, pos[5] = -1.0;
    for (int i = 0; i < N; ++i) {
        pos[3 * (i + 2)] = cos(2.0 * 3.14159265358979323846 * i / N);
        pos[3 * (i + 2) + 1] = sin(2.0 * 3.14159265358979323846 * i / N);
    }
    for (int i = 0; i < N; ++i) {
        int f = (7 * i) % N, a = 2 + i, b = 2 + (i + 1) % N; /* 7 is coprime to 300 */
        int32_t *t = tri + 6 * f;
        t[0] = 0, t[1] = a, t[2] = b; /* top, outward */
        t[3] = 1, t[4] = b, t[5] = a; /* bottom */
    }
    cf_context *ctx = cft_context();
    cf_mesh_desc d = {N + 2, pos, 2 * N, tri, 0, NULL, NULL};
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_mesh_create(ctx, &d, &m));
    CHECK(cf_mesh_edge_count(m) == 3 * N);
    CHECK(cf_mesh_genus(m) == 0 && cf_mesh_euler_characteristic(m) == 2);
    CHECK(cf_mesh_vertex_ring_offsets(m)[1] == N);
    check_connectivity(m);
    cf_mesh_destroy(&m);
    /* the same with one face flipped is caught */
    int32_t t0 = tri[1];
    tri[1] = tri[2], tri[2] = t0;
    CHECK_STATUS(cf_mesh_create(ctx, &d, &m), CF_ERR_ORIENTATION);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* A relabelled copy of a mesh (vertices and faces permuted, corners
 * rotated) has the same counts and valid tables. */
static void test_relabelling(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *a = NULL, *b = NULL;
    CHECK_OK(ctx, cf_generate_double_torus(ctx, 1, &a));
    const int32_t nv = cf_mesh_vertex_count(a), nf = cf_mesh_face_count(a);
    int32_t *vp = malloc(sizeof(int32_t) * (size_t)nv), *fp = malloc(sizeof(int32_t) * (size_t)nf);
    double *pos = malloc(sizeof(double) * 3 * (size_t)nv);
    int32_t *tri = malloc(sizeof(int32_t) * 3 * (size_t)nf);
    uint32_t s = 12345u;
    for (int32_t i = 0; i < nv; ++i) vp[i] = i;
    for (int32_t i = 0; i < nf; ++i) fp[i] = i;
    for (int32_t i = nv - 1; i > 0; --i) { /* Fisher-Yates with an LCG */
        s = s * 1664525u + 1013904223u;
        int32_t j = (int32_t)(s % (uint32_t)(i + 1)), t = vp[i];
        vp[i] = vp[j], vp[j] = t;
    }
    for (int32_t i = nf - 1; i > 0; --i) {
        s = s * 1664525u + 1013904223u;
        int32_t j = (int32_t)(s % (uint32_t)(i + 1)), t = fp[i];
        fp[i] = fp[j], fp[j] = t;
    }
    for (int32_t v = 0; v < nv; ++v) memcpy(pos + 3 * vp[v], cf_mesh_positions(a) + 3 * v, 3 * sizeof(double));
    for (int32_t f = 0; f < nf; ++f)
        for (int k = 0; k < 3; ++k) tri[3 * fp[f] + k] = vp[cf_mesh_triangles(a)[3 * f + (k + f) % 3]];
    cf_mesh_desc d = {nv, pos, nf, tri, 0, NULL, NULL};
    CHECK_OK(ctx, cf_mesh_create(ctx, &d, &b));
    CHECK(cf_mesh_edge_count(a) == cf_mesh_edge_count(b));
    CHECK(cf_mesh_genus(a) == cf_mesh_genus(b) && cf_mesh_genus(b) == 2);
    CHECK(cf_mesh_euler_characteristic(a) == cf_mesh_euler_characteristic(b));
    CHECK(cf_mesh_component_count(b) == 1 && cf_mesh_boundary_loop_count(b) == 0);
    /* vertex degrees are carried along by the permutation */
    int bad = 0;
    for (int32_t v = 0; v < nv; ++v) {
        const int32_t *ra = cf_mesh_vertex_ring_offsets(a), *rb = cf_mesh_vertex_ring_offsets(b);
        if (ra[v + 1] - ra[v] != rb[vp[v] + 1] - rb[vp[v]]) ++bad;
    }
    CHECK(bad == 0);
    check_connectivity(b);
    cf_mesh_destroy(&a);
    cf_mesh_destroy(&b);
    free(vp), free(fp), free(pos), free(tri);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Random damage to a valid mesh (flipped faces, deleted faces, merged
 * vertices, duplicated faces, moved vertices): cf_mesh_create must fail
 * exactly when cf_mesh_validate reports a defect, with the same status and
 * message, and every mesh it accepts must have consistent tables. */
static void test_random_damage(void)
{
    cf_context *ctx = NULL; /* no log callback: hundreds of expected errors */
    CHECK_OK(ctx, cf_context_create(&ctx));
    cf_mesh *base = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 1, 1.0, &base));
    const int32_t nv = cf_mesh_vertex_count(base), nf0 = cf_mesh_face_count(base);
    double *pos = malloc(sizeof(double) * 3 * (size_t)nv);
    int32_t *tri = malloc(sizeof(int32_t) * 3 * (size_t)(nf0 + 8));
    uint32_t s = 99u;
    int accepted = 0, rejected = 0, mismatched = 0;
    int kinds[8] = {0};
    for (int trial = 0; trial < 400; ++trial) {
        memcpy(pos, cf_mesh_positions(base), sizeof(double) * 3 * (size_t)nv);
        memcpy(tri, cf_mesh_triangles(base), sizeof(int32_t) * 3 * (size_t)nf0);
        int32_t nf = nf0;
        int ops = 1 + trial % 3;
        for (int o = 0; o < ops; ++o) {
            s = s * 1664525u + 1013904223u;
            uint32_t r = s >> 8;
            int32_t f = (int32_t)(r % (uint32_t)nf), g = (int32_t)((r / 7u) % (uint32_t)nf);
            switch ((r >> 16) % 5u) {
            case 0: { int32_t t = tri[3 * f]; tri[3 * f] = tri[3 * f + 1]; tri[3 * f + 1] = t; break; } /* flip */
            case 1: /* delete face f */
                memmove(tri + 3 * f, tri + 3 * f + 3, sizeof(int32_t) * 3 * (size_t)(nf - f - 1));
                --nf;
                break;
            case 2: tri[3 * f + (r % 3u)] = tri[3 * g + ((r >> 4) % 3u)]; break;            /* merge corners */
            case 3: memcpy(tri + 3 * nf, tri + 3 * g, 3 * sizeof(int32_t)); ++nf; break;   /* duplicate */
            default: memcpy(pos + 3 * tri[3 * f], pos + 3 * tri[3 * f + 1], 3 * sizeof(double)); break; /* collapse */
            }
            if (nf < 2) nf = 2;
        }
        cf_mesh_desc d = {nv, pos, nf, tri, 0, NULL, NULL};
        cf_mesh_report rep;
        CHECK_OK(ctx, cf_mesh_validate(ctx, &d, &rep));
        cf_mesh *m = NULL;
        cf_status st = cf_mesh_create(ctx, &d, &m);
        if (st != rep.first_status) ++mismatched;
        if (st == CF_OK) {
            ++accepted;
            check_connectivity(m);
            cf_mesh_destroy(&m);
        } else {
            ++rejected;
            if (strcmp(cf_context_message(ctx), rep.first_message) != 0) ++mismatched;
            if (-st < 8 + 11 && -st >= 11) ++kinds[-st - 11];
        }
    }
    fprintf(stderr, "   accepted %d, rejected %d (range %d, repeated %d, nonfinite %d, degenerate %d, "
                    "edge %d, vertex %d, orientation %d)\n",
            accepted, rejected, kinds[0], kinds[1], kinds[2], kinds[3], kinds[4], kinds[5], kinds[6]);
    CHECK(mismatched == 0);
    /* the damage must exercise both outcomes and most defect kinds */
    CHECK(accepted > 10 && rejected > 100);
    CHECK(kinds[1] > 0 && kinds[3] > 0 && kinds[4] > 0 && kinds[5] > 0 && kinds[6] > 0);
    free(pos);
    free(tri);
    cf_mesh_destroy(&base);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Fail the n-th allocation for every n until creation succeeds: each
 * failure must be CF_ERR_NOMEM and leak nothing. */
static void test_allocation_failures(void)
{
    cf_context *ctx = NULL;
    CHECK_OK(ctx, cf_context_create(&ctx));
    cf_mesh *src = NULL;
    CHECK_OK(ctx, cf_generate_cylinder(ctx, 6, 2, 1.0, 1.0, &src));
    cf_mesh_desc d = {cf_mesh_vertex_count(src), cf_mesh_positions(src), cf_mesh_face_count(src),
                      cf_mesh_triangles(src), cf_mesh_uv_count(src), cf_mesh_uv(src), cf_mesh_uv_triangles(src)};
    size_t base = cf_context_bytes_in_use(ctx);
    int failures = 0, bad = 0;
    int64_t n;
    for (n = 1; n < 1000; ++n) {
        cf_mesh *m = NULL;
        cf_context_fail_allocation(ctx, n, 0);
        cf_status st = cf_mesh_create(ctx, &d, &m);
        cf_context_fail_allocation(ctx, 0, 0);
        if (st == CF_OK) {
            check_connectivity(m);
            cf_mesh_destroy(&m);
            break;
        }
        ++failures;
        if (st != CF_ERR_NOMEM || m != NULL || cf_context_bytes_in_use(ctx) != base) ++bad;
    }
    CHECK(bad == 0);
    CHECK(failures >= 10); /* every table is its own allocation */
    CHECK(n < 1000);
    /* the same for a generator that allocates intermediate meshes */
    cf_mesh_destroy(&src);
    for (n = 1; n < 1000; ++n) {
        cf_mesh *m = NULL;
        cf_context_fail_allocation(ctx, n, 0);
        cf_status st = cf_generate_bumpy_sphere(ctx, 1, 0.2, 3u, &m);
        cf_context_fail_allocation(ctx, 0, 0);
        if (st == CF_OK) {
            cf_mesh_destroy(&m);
            break;
        }
        if (st != CF_ERR_NOMEM || cf_context_bytes_in_use(ctx) != 0) ++bad;
    }
    CHECK(bad == 0);
    CHECK(n < 1000);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_tetrahedron);
    CFT_RUN(test_single_triangle_and_two_components);
    CFT_RUN(test_generated_fixtures);
    CFT_RUN(test_high_valence);
    CFT_RUN(test_relabelling);
    CFT_RUN(test_random_damage);
    CFT_RUN(test_allocation_failures);
    return cft_finish();
}
