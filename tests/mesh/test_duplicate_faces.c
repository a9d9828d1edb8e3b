/* Issue 15, M10: a face given twice (same three vertices, in any rotation,
 * with the same or the opposite orientation) is reported as a duplicate
 * naming both faces, not as an orientation conflict or a non-manifold
 * edge; cf_mesh_validate agrees with cf_mesh_create. */
#include "curvflow/mesh.h"
#include "test.h"

#include <string.h>

static const double tet_x[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
static const int32_t tet_f[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};

/* The tetrahedron plus `extra` (3 indices) as face 4. */
static void expect_duplicate(cf_context *ctx, const int32_t extra[3], const char *message)
{
    int32_t tri[15];
    memcpy(tri, tet_f, sizeof tet_f);
    memcpy(tri + 12, extra, 3 * sizeof(int32_t));
    cf_mesh_desc d = {4, tet_x, 5, tri, 0, NULL, NULL};
    cf_mesh *m = NULL;
    CHECK_STATUS(cf_mesh_create(ctx, &d, &m), CF_ERR_BAD_MESH);
    CHECK(m == NULL);
    if (!strstr(cf_context_message(ctx), message))
        cft_fail(__FILE__, __LINE__, "message '%s' lacks '%s'", cf_context_message(ctx), message);
    cf_mesh_report r;
    CHECK_OK(ctx, cf_mesh_validate(ctx, &d, &r));
    CHECK(r.first_status == CF_ERR_BAD_MESH);
    CHECK(strcmp(r.first_message, cf_context_message(ctx)) == 0);
}

static void test_duplicates(void)
{
    cf_context *ctx = NULL;
    CHECK_OK(ctx, cf_context_create(&ctx));
    /* face 1 is (0, 1, 3): again as written, rotated, and reversed */
    static const int32_t same[3] = {0, 1, 3}, rotated[3] = {3, 0, 1}, reversed[3] = {1, 0, 3}, rev_rot[3] = {3, 1, 0};
    expect_duplicate(ctx, same, "faces 1 and 4 are the same triangle (vertices 0, 1, 3; same orientation)");
    expect_duplicate(ctx, rotated, "faces 1 and 4 are the same triangle (vertices 0, 1, 3; same orientation)");
    expect_duplicate(ctx, reversed, "faces 1 and 4 are the same triangle (vertices 0, 1, 3; opposite orientation)");
    expect_duplicate(ctx, rev_rot, "faces 1 and 4 are the same triangle (vertices 0, 1, 3; opposite orientation)");
    /* two coincident opposite triangles on their own: each edge has two
     * faces, consistently oriented, but it is no surface */
    static const int32_t pillow[6] = {0, 1, 2, 0, 2, 1};
    cf_mesh_desc d = {3, tet_x, 2, pillow, 0, NULL, NULL};
    cf_mesh *m = NULL;
    CHECK_STATUS(cf_mesh_create(ctx, &d, &m), CF_ERR_BAD_MESH);
    CHECK(strstr(cf_context_message(ctx), "faces 0 and 1 are the same triangle (vertices 0, 1, 2; opposite orientation)"));
    /* the first pair by face index is named */
    int32_t tri[18];
    memcpy(tri, tet_f, sizeof tet_f);
    static const int32_t two[6] = {3, 2, 1, 2, 0, 3};
    memcpy(tri + 12, two, sizeof two);
    cf_mesh_desc d2 = {4, tet_x, 6, tri, 0, NULL, NULL};
    CHECK_STATUS(cf_mesh_create(ctx, &d2, &m), CF_ERR_BAD_MESH);
    CHECK(strstr(cf_context_message(ctx), "faces 2 and 5 are the same triangle (vertices 0, 2, 3"));
    /* and a valid tetrahedron is still valid */
    cf_mesh_desc ok = {4, tet_x, 4, tet_f, 0, NULL, NULL};
    CHECK_OK(ctx, cf_mesh_create(ctx, &ok, &m));
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_duplicates);
    return cft_finish();
}
