/* Mesh validation: every defect built by hand from tiny arrays gives its own
 * status and a one-line message naming the element; the check order decides
 * which defect is reported first; cf_mesh_validate counts all defects. */
#include "curvflow/generate.h"
#include "curvflow/mesh.h"
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Regular tetrahedron-ish fixture, outward oriented. */
static const double tet_pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
static const int32_t tet_tri[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};

static void expect(const double *pos, int32_t nv, const int32_t *tri, int32_t nf, cf_status status,
                   const char *message)
{
    cf_context *ctx = cft_context();
    cf_mesh_desc d = {nv, pos, nf, tri, 0, NULL, NULL};
    cf_mesh *m = NULL;
    CHECK_STATUS(cf_mesh_create(ctx, &d, &m), status);
    CHECK(m == NULL);
    if (strcmp(cf_context_message(ctx), message) != 0)
        cft_fail(__FILE__, __LINE__, "message \"%s\", expected \"%s\"", cf_context_message(ctx), message);
    /* the full report agrees on the first defect */
    cf_mesh_report r;
    CHECK_OK(ctx, cf_mesh_validate(ctx, &d, &r));
    CHECK_STATUS(r.first_status, status);
    CHECK(strcmp(r.first_message, message) == 0);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_valid_tetrahedron(void)
{
    cf_context *ctx = cft_context();
    cf_mesh_desc d = {4, tet_pos, 4, tet_tri, 0, NULL, NULL};
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_mesh_create(ctx, &d, &m));
    cf_mesh_report r;
    CHECK_OK(ctx, cf_mesh_validate(ctx, &d, &r));
    CHECK_STATUS(r.first_status, CF_OK);
    CHECK(r.first_message[0] == '\0');
    CHECK(r.index_out_of_range + r.repeated_index + r.nonfinite_coordinates + r.degenerate_faces +
              r.nonmanifold_edges + r.nonmanifold_vertices + r.inconsistent_orientation_edges +
              r.unreferenced_vertices ==
          0);
    cf_mesh_destroy(&m);
    CHECK(m == NULL);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_index_out_of_range(void)
{
    const int32_t tri[] = {0, 2, 1, 0, 1, 5, 0, 3, 2, 1, 2, 3};
    expect(tet_pos, 4, tri, 4, CF_ERR_INDEX_RANGE, "face 1: vertex index 5 out of range [0, 4)");
    const int32_t neg[] = {0, 2, 1, 0, 1, 3, 0, 3, -1, 1, 2, 3};
    expect(tet_pos, 4, neg, 4, CF_ERR_INDEX_RANGE, "face 2: vertex index -1 out of range [0, 4)");
}

static void test_repeated_index(void)
{
    const int32_t tri[] = {0, 2, 1, 0, 1, 3, 3, 2, 3, 1, 2, 3};
    expect(tet_pos, 4, tri, 4, CF_ERR_REPEATED_INDEX, "face 2: vertex 3 repeated");
}

/* The tetrahedron scaled by `scale` is accepted. */
static void expect_valid_scaled_tetrahedron(double scale)
{
    double pos[12];
    for (int i = 0; i < 12; ++i) pos[i] = scale * tet_pos[i];
    cf_context *ctx = cft_context();
    cf_mesh_desc d = {4, pos, 4, tet_tri, 0, NULL, NULL};
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_mesh_create(ctx, &d, &m));
    cf_mesh_destroy(&m);
    cf_context_destroy(&ctx);
}

static void test_nonfinite(void)
{
    double pos[12];
    memcpy(pos, tet_pos, sizeof pos);
    pos[3 * 2 + 1] = NAN;
    expect(pos, 4, tet_tri, 4, CF_ERR_NONFINITE, "vertex 2: coordinate y is NaN");
    pos[3 * 2 + 1] = 1.0;
    pos[3 * 3 + 2] = -INFINITY;
    expect(pos, 4, tet_tri, 4, CF_ERR_NONFINITE, "vertex 3: coordinate z is infinite");
}

/* Finite coordinates outside the range the library computes with: beyond
 * 1e50 areas squared and volumes overflow (a 1e90 copy of spot_3k made the
 * Willmore flow fail with "eigenvector solve failed" and implicit MCF with
 * "initial energy is not finite"); edges below 1e-50 underflow when squared.
 * Both are rejected with a message that says to rescale; 1e45 and 1e-45
 * copies are accepted (and flow like the unit one: tests/methods/test_flow.c). */
static void test_out_of_range_coordinates(void)
{
    double pos[12];
    for (int i = 0; i < 12; ++i) pos[i] = 1e60 * tet_pos[i];
    expect(pos, 4, tet_tri, 4, CF_ERR_NONFINITE,
           "vertex 1: coordinate x = 1e+60 is out of range (|x| > 1e+50, volumes would overflow); rescale the mesh");
    for (int i = 0; i < 12; ++i) pos[i] = 1e-60 * tet_pos[i];
    expect(pos, 4, tet_tri, 4, CF_ERR_DEGENERATE_FACE,
           "face 0: its edges are shorter than 1e-50 (longest component 1e-60), below the range of lengths this "
           "library computes with; rescale the mesh");
    expect_valid_scaled_tetrahedron(1e45);
    expect_valid_scaled_tetrahedron(1e-45);
    /* the report counts them with the non-finite coordinates and the degenerate faces */
    for (int i = 0; i < 12; ++i) pos[i] = 1e60 * tet_pos[i];
    cf_context *ctx = cft_context();
    cf_mesh_desc d = {4, pos, 4, tet_tri, 0, NULL, NULL};
    cf_mesh_report r;
    CHECK_OK(ctx, cf_mesh_validate(ctx, &d, &r));
    CHECK(r.nonfinite_coordinates == 3);
    CHECK(r.degenerate_faces == 0);
    cf_context_destroy(&ctx);
}

static void test_zero_area(void)
{
    /* vertex 3 moved onto the segment 1-2: face 3 (1, 2, 3) is collinear */
    const double pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.5, 0.5, 0};
    expect(pos, 4, tet_tri, 4, CF_ERR_DEGENERATE_FACE, "face 3: zero area");
    /* the threshold is relative: a tiny but well-shaped mesh is fine */
    expect_valid_scaled_tetrahedron(1e-30);
}

static void test_nonmanifold_edge(void)
{
    /* three triangles on edge (0, 1) */
    const double pos[] = {0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0, 0.5, 0, 1};
    const int32_t tri[] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    expect(pos, 5, tri, 3, CF_ERR_NONMANIFOLD_EDGE, "face 2: edge (0, 1) is shared by 3 faces");
}

static void test_nonmanifold_vertex(void)
{
    /* bow tie: two triangles meeting only at vertex 0 */
    const double pos[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, -1, 0, 0, -1, -1, 0};
    const int32_t tri[] = {0, 1, 2, 0, 3, 4};
    expect(pos, 5, tri, 2, CF_ERR_NONMANIFOLD_VERTEX, "vertex 0: its faces form 2 separate fans");
    /* two tetrahedra glued at one vertex (closed fans) */
    const double pos2[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, -1, 0, 0, 0, -1, 0, 0, 0, -1};
    const int32_t tri2[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3, 0, 5, 4, 0, 4, 6, 0, 6, 5, 4, 5, 6};
    expect(pos2, 7, tri2, 8, CF_ERR_NONMANIFOLD_VERTEX, "vertex 0: its faces form 2 separate fans");
}

static void test_orientation(void)
{
    double pos[12];
    memcpy(pos, tet_pos, sizeof pos);
    /* flip face 3 (1, 2, 3) -> (1, 3, 2): it now runs 3->2 like face 2 (0, 3, 2) */
    const int32_t tri[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 3, 2};
    expect(pos, 4, tri, 4, CF_ERR_ORIENTATION,
           "faces 0 and 3: edge (2, 1) is traversed in the same direction by both");
}

static void test_unreferenced_and_empty(void)
{
    const double pos[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 5, 5, 5};
    expect(pos, 5, tet_tri, 4, CF_ERR_BAD_MESH, "vertex 4 is not used by any face");
    expect(pos, 4, tet_tri, 0, CF_ERR_BAD_MESH, "empty mesh (4 vertices, 0 faces)");
}

static void test_check_order(void)
{
    /* repeated index in face 3 and a NaN at vertex 0: the index checks come
     * first, whatever the element order */
    double pos[12];
    memcpy(pos, tet_pos, sizeof pos);
    pos[0] = NAN;
    const int32_t tri[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 1, 3};
    expect(pos, 4, tri, 4, CF_ERR_REPEATED_INDEX, "face 3: vertex 1 repeated");
}

static void test_uv_checks(void)
{
    cf_context *ctx = cft_context();
    double uv[8] = {0, 0, 1, 0, 0, 1, 1, 1};
    int32_t uvt[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 4};
    cf_mesh_desc d = {4, tet_pos, 4, tet_tri, 4, uv, uvt};
    cf_mesh *m = NULL;
    CHECK_STATUS(cf_mesh_create(ctx, &d, &m), CF_ERR_INDEX_RANGE);
    CHECK(strcmp(cf_context_message(ctx), "face 3: uv index 4 out of range [0, 4)") == 0);
    uvt[11] = 3;
    uv[5] = NAN;
    CHECK_STATUS(cf_mesh_create(ctx, &d, &m), CF_ERR_NONFINITE);
    CHECK(strcmp(cf_context_message(ctx), "uv 2: coordinate v is NaN") == 0);
    uv[5] = 1;
    CHECK_OK(ctx, cf_mesh_create(ctx, &d, &m));
    CHECK(cf_mesh_uv_count(m) == 4);
    CHECK(memcmp(cf_mesh_uv_triangles(m), uvt, sizeof uvt) == 0);
    cf_mesh_destroy(&m);
    /* per-vertex uv: uv_triangles becomes the triangle list */
    d.uv_triangles = NULL;
    CHECK_OK(ctx, cf_mesh_create(ctx, &d, &m));
    CHECK(memcmp(cf_mesh_uv_triangles(m), tet_tri, sizeof tet_tri) == 0);
    CHECK(cf_mesh_uv(m)[6] == 1.0);
    cf_mesh_destroy(&m);
    /* per-vertex uv with the wrong count is an argument error */
    d.uv_count = 3;
    CHECK_STATUS(cf_mesh_create(ctx, &d, &m), CF_ERR_INVALID_ARG);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_arguments(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = NULL;
    CHECK_STATUS(cf_mesh_create(ctx, NULL, &m), CF_ERR_INVALID_ARG);
    cf_mesh_desc d = {4, NULL, 4, tet_tri, 0, NULL, NULL};
    CHECK_STATUS(cf_mesh_create(ctx, &d, &m), CF_ERR_INVALID_ARG);
    d.positions = tet_pos;
    CHECK_STATUS(cf_mesh_create(ctx, &d, NULL), CF_ERR_INVALID_ARG);
    d.vertex_count = -1;
    CHECK_STATUS(cf_mesh_create(ctx, &d, &m), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_mesh_validate(ctx, &d, NULL), CF_ERR_INVALID_ARG);
    cf_mesh_destroy(NULL);
    cf_mesh_destroy(&m);
    cf_context_destroy(&ctx);
}

static void test_report_counts_everything(void)
{
    /* a strip of 6 triangles with: face 0 out of range, face 1 repeated,
     * vertex 9 NaN, face 2 collinear, one unreferenced vertex (8) */
    const double pos[] = {0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0, 1, 1, 0, 2, 1, 0, 0, 2, 0, 1, 2, 0, 9, 9, 9, 0, 0, NAN};
    const int32_t tri[] = {0, 1, 40, 1, 1, 4, 0, 1, 2, 1, 5, 4, 3, 4, 7, 3, 7, 6};
    cf_context *ctx = cft_context();
    cf_mesh_desc d = {10, pos, 6, tri, 0, NULL, NULL};
    cf_mesh_report r;
    CHECK_OK(ctx, cf_mesh_validate(ctx, &d, &r));
    CHECK(r.index_out_of_range == 1);
    CHECK(r.repeated_index == 1);
    CHECK(r.nonfinite_coordinates == 1);
    CHECK(r.degenerate_faces == 1);
    /* vertex 8 and vertex 9 are unreferenced (faces 0 and 1 are skipped) */
    CHECK(r.unreferenced_vertices == 2);
    CHECK(r.nonmanifold_edges == 0);
    CHECK(r.inconsistent_orientation_edges == 0);
    CHECK_STATUS(r.first_status, CF_ERR_INDEX_RANGE);
    CHECK(strcmp(r.first_message, "face 0: vertex index 40 out of range [0, 10)") == 0);
    /* validate does not record an error in the context */
    CHECK_STATUS(cf_context_status(ctx), CF_OK);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_report_counts_topology(void)
{
    /* fan of three faces on edge (0,1) plus an orientation flip elsewhere:
     * faces 3, 4 share edge (5, 6) in the same direction */
    const double pos[] = {0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0, 0.5, 0, 1,
                          5, 0, 0, 6, 0, 0, 5.5, 1, 0, 5.5, -1, 0};
    const int32_t tri[] = {0, 1, 2, 1, 0, 3, 0, 1, 4, 5, 6, 7, 5, 6, 8};
    cf_context *ctx = cft_context();
    cf_mesh_desc d = {9, pos, 5, tri, 0, NULL, NULL};
    cf_mesh_report r;
    CHECK_OK(ctx, cf_mesh_validate(ctx, &d, &r));
    CHECK(r.nonmanifold_edges == 1);
    CHECK(r.inconsistent_orientation_edges == 1);
    CHECK_STATUS(r.first_status, CF_ERR_NONMANIFOLD_EDGE);
    cf_context_destroy(&ctx);
}


/* cf_mesh_check_positions (a flow result on a built mesh) gives the same
 * report as the full check of the same triangles and positions, and
 * allocates nothing: the command line runs it on a 655k-vertex result while
 * the flow still holds its factors (issue 15's memory line). */
static void expect_same_report(cf_context *ctx, const cf_mesh *mesh, const double *pos)
{
    cf_mesh_desc d = {cf_mesh_vertex_count(mesh), pos, cf_mesh_face_count(mesh), cf_mesh_triangles(mesh), 0, NULL,
                      NULL};
    cf_mesh_report full, quick;
    CHECK_OK(ctx, cf_mesh_validate(ctx, &d, &full));
    int64_t allocations = cf_context_allocation_count(ctx);
    CHECK_OK(ctx, cf_mesh_check_positions(ctx, mesh, pos, &quick));
    CHECK(cf_context_allocation_count(ctx) == allocations);
    CHECK(memcmp(&full, &quick, sizeof full) == 0);
}

static void test_check_positions(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &mesh));
    int32_t nv = cf_mesh_vertex_count(mesh);
    const int32_t *tri = cf_mesh_triangles(mesh);
    double *pos = calloc(3 * (size_t)nv, sizeof *pos);
    CHECK(pos != NULL);
    memcpy(pos, cf_mesh_positions(mesh), 3 * (size_t)nv * sizeof *pos);
    cf_mesh_report r;
    CHECK_OK(ctx, cf_mesh_check_positions(ctx, mesh, pos, &r));
    CHECK_STATUS(r.first_status, CF_OK);
    expect_same_report(ctx, mesh, pos);
    /* face 7 collapsed onto a segment, then two non-finite coordinates */
    int32_t a = tri[21], b = tri[22], c = tri[23];
    for (int k = 0; k < 3; ++k) pos[3 * c + k] = 0.5 * (pos[3 * a + k] + pos[3 * b + k]);
    expect_same_report(ctx, mesh, pos);
    CHECK_OK(ctx, cf_mesh_check_positions(ctx, mesh, pos, &r));
    CHECK_STATUS(r.first_status, CF_ERR_DEGENERATE_FACE);
    CHECK(r.degenerate_faces >= 1);
    pos[3 * 5 + 1] = NAN;
    pos[3 * 9 + 2] = 1e300;
    expect_same_report(ctx, mesh, pos);
    CHECK_OK(ctx, cf_mesh_check_positions(ctx, mesh, pos, &r));
    CHECK_STATUS(r.first_status, CF_ERR_NONFINITE);
    CHECK(r.nonfinite_coordinates == 2);
    CHECK(strcmp(r.first_message, "vertex 5: coordinate y is NaN") == 0);
    CHECK_STATUS(cf_mesh_check_positions(ctx, mesh, pos, NULL), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_mesh_check_positions(ctx, NULL, pos, &r), CF_ERR_INVALID_ARG);
    free(pos);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_valid_tetrahedron);
    CFT_RUN(test_index_out_of_range);
    CFT_RUN(test_repeated_index);
    CFT_RUN(test_nonfinite);
    CFT_RUN(test_out_of_range_coordinates);
    CFT_RUN(test_zero_area);
    CFT_RUN(test_nonmanifold_edge);
    CFT_RUN(test_nonmanifold_vertex);
    CFT_RUN(test_orientation);
    CFT_RUN(test_unreferenced_and_empty);
    CFT_RUN(test_check_order);
    CFT_RUN(test_uv_checks);
    CFT_RUN(test_arguments);
    CFT_RUN(test_report_counts_everything);
    CFT_RUN(test_report_counts_topology);
    CFT_RUN(test_check_positions);
    return cft_finish();
}
