/* cf_mesh_data_drop_unreferenced: the vertices no face uses (left by
 * scanners and editors) are dropped and the others renumbered in order,
 * with their per-vertex texture coordinates and properties; the result
 * builds a mesh; data without an unused vertex, or without faces, is left
 * as it is; a bad index is an error naming the face; running out of memory
 * at any allocation leaves the data unchanged. */
#define _POSIX_C_SOURCE 200809L
#include "io_test_util.h"
#include "curvflow/mesh.h"

/* A tetrahedron (vertices 0, 2, 3, 5 of the file) with unused vertices 1
 * and 4 between them and 6 at the end, u, v and a property "label" per
 * vertex (label = 10 x the file's index). */
static const char tetra_ply[] =
    "ply\nformat ascii 1.0\nelement vertex 7\nproperty double x\nproperty double y\nproperty double z\n"
    "property double u\nproperty double v\nproperty double label\nelement face 4\n"
    "property list uchar int vertex_indices\nend_header\n"
    "0 0 0 0.0 0.5 0\n"
    "9 9 9 0.1 0.5 10\n"
    "1 0 0 0.2 0.5 20\n"
    "0 1 0 0.3 0.5 30\n"
    "7 7 7 0.4 0.5 40\n"
    "0 0 1 0.5 0.5 50\n"
    "8 8 8 0.6 0.5 60\n"
    "3 0 3 2\n3 0 2 5\n3 0 5 3\n3 2 3 5\n";

static void test_drop(void)
{
    cf_context *ctx = cft_context();
    cf_mesh_data *d = NULL;
    CHECK_OK(ctx, cf_read_mesh_memory(ctx, tetra_ply, sizeof tetra_ply - 1, CF_FORMAT_PLY, "tetra.ply", &d));
    if (!d) {
        cf_context_destroy(&ctx);
        return;
    }
    /* as read, the mesh is refused */
    cf_mesh_desc desc;
    cf_mesh *m = NULL;
    cf_mesh_data_desc(d, &desc);
    CHECK_STATUS(cf_mesh_create(ctx, &desc, &m), CF_ERR_BAD_MESH);
    CHECK(strstr(cf_context_message(ctx), "vertex 1 is not used") != NULL);
    int32_t index[7], dropped = -1;
    CHECK_OK(ctx, cf_mesh_data_drop_unreferenced(ctx, d, index, &dropped));
    CHECK(dropped == 3 && d->vertex_count == 4 && d->uv_count == 4 && !d->uv_triangles);
    const int32_t expected_index[7] = {0, -1, 1, 2, -1, 3, -1};
    CHECK(memcmp(index, expected_index, sizeof index) == 0);
    const int32_t kept[4] = {0, 2, 3, 5};
    for (int k = 0; k < 4; ++k) {
        const double *x = d->positions + 3 * k;
        CHECK(x[0] + x[1] + x[2] == (kept[k] == 0 ? 0.0 : 1.0)); /* the tetrahedron's corners, in order */
        CHECK_NEAR(d->uv[2 * k], 0.1 * kept[k], 1e-15, 0.0);
        CHECK(d->vertex_properties[0].values[k] == 10.0 * kept[k]);
    }
    const int32_t triangles[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    CHECK(memcmp(d->triangles, triangles, sizeof triangles) == 0);
    cf_mesh_data_desc(d, &desc);
    CHECK_OK(ctx, cf_mesh_create(ctx, &desc, &m));
    CHECK(m && cf_mesh_genus(m) == 0 && cf_mesh_boundary_loop_count(m) == 0);
    cf_mesh_destroy(&m);
    /* a second call finds nothing */
    CHECK_OK(ctx, cf_mesh_data_drop_unreferenced(ctx, d, index, &dropped));
    CHECK(dropped == 0 && d->vertex_count == 4);
    for (int k = 0; k < 4; ++k) CHECK(index[k] == k);
    cf_mesh_data_destroy(&d);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_no_faces_and_bad_input(void)
{
    cf_context *ctx = cft_context();
    static const char points[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    cf_mesh_data *d = NULL;
    CHECK_OK(ctx, cf_read_mesh_memory(ctx, points, sizeof points - 1, CF_FORMAT_OBJ, "points.obj", &d));
    int32_t index[3], dropped = -1;
    if (d) {
        /* nothing to keep: left as it is, for the mesh check's own message */
        CHECK_OK(ctx, cf_mesh_data_drop_unreferenced(ctx, d, index, &dropped));
        CHECK(dropped == 0 && d->vertex_count == 3);
        CHECK(index[0] == -1 && index[2] == -1);
        cf_mesh_data_destroy(&d);
    }
    CHECK_STATUS(cf_mesh_data_drop_unreferenced(ctx, NULL, NULL, &dropped), CF_ERR_INVALID_ARG);
    CHECK_OK(ctx, cf_read_mesh_memory(ctx, tetra_ply, sizeof tetra_ply - 1, CF_FORMAT_PLY, "tetra.ply", &d));
    if (d) {
        CHECK_STATUS(cf_mesh_data_drop_unreferenced(ctx, d, NULL, NULL), CF_ERR_INVALID_ARG);
        d->triangles[5] = 7; /* past the vertices: named */
        CHECK_STATUS(cf_mesh_data_drop_unreferenced(ctx, d, NULL, &dropped), CF_ERR_INDEX_RANGE);
        CHECK(strstr(cf_context_message(ctx), "face 1") != NULL);
        CHECK(d->vertex_count == 7);
        cf_mesh_data_destroy(&d);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* every allocation failing in turn: an error, the data as it was */
static cf_status drop_call(cf_context *ctx, void *user)
{
    (void)user;
    cf_mesh_data *d = NULL;
    cf_status st = cf_read_mesh_memory(ctx, tetra_ply, sizeof tetra_ply - 1, CF_FORMAT_PLY, "tetra.ply", &d);
    if (st != CF_OK) return st;
    int32_t dropped = 0;
    st = cf_mesh_data_drop_unreferenced(ctx, d, NULL, &dropped);
    if (st != CF_OK) CHECK(d->vertex_count == 7 && dropped == 0 && d->vertex_properties[0].values[6] == 60.0);
    else CHECK(d->vertex_count == 4 && dropped == 3);
    cf_mesh_data_destroy(&d);
    return st;
}

static void test_allocation_failures(void)
{
    cf_context *ctx = cft_context();
    CHECK(cft_allocation_sweep(ctx, "drop_unreferenced", drop_call, NULL, 0) > 0);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_drop);
    CFT_RUN(test_no_faces_and_bad_input);
    CFT_RUN(test_allocation_failures);
    return cft_finish();
}
