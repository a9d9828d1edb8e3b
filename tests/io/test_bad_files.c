/* The four files of ../shared/meshes/bad: each is rejected with its own
 * status and a message naming the file and the place (see bad/MANIFEST.tsv
 * for what each defect is). */
#define _POSIX_C_SOURCE 200809L
#include "io_test_util.h"

static void expect_load(const char *name, cf_status status, const char *part)
{
    cf_context *ctx = cft_context();
    char rel[256];
    snprintf(rel, sizeof rel, "bad/%s", name);
    char path[4096];
    snprintf(path, sizeof path, "%s", cft_require_shared_mesh(rel));
    cf_mesh *m = NULL;
    CHECK_STATUS(cf_load_mesh(ctx, path, &m), status);
    CHECK(m == NULL);
    const char *msg = cf_context_message(ctx);
    /* the message starts with the path as given, then names the place */
    if (strncmp(msg, path, strlen(path)) != 0 || !strstr(msg, part))
        cft_fail(__FILE__, __LINE__, "message '%s' lacks '%s: ...%s'", msg, path, part);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_truncated(void)
{
    /* cut inside "f 93 1651 1513": the last line "f 93 165" has no newline */
    expect_load("truncated_spot.obj", CF_ERR_TRUNCATED,
                ": line 7063: face has 2 vertices (file ends inside a face line: truncated?)");
}

static void test_nan(void)
{
    /* "v nan 0.31134 2.364574" on line 11 = vertex 10 (0-based); rejected by the reader */
    expect_load("nan_coordinate_bunny.obj", CF_ERR_NONFINITE, ": line 11: vertex 10 has a non-finite coordinate");
    cf_context *ctx = cft_context();
    cf_mesh_data *d = NULL;
    CHECK_STATUS(cf_read_mesh_file(ctx, cft_require_shared_mesh("bad/nan_coordinate_bunny.obj"), &d),
                 CF_ERR_NONFINITE);
    CHECK(d == NULL && cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_nonmanifold_edges(void)
{
    /* the reader accepts it (1148 v, 2053 triangles); the mesh core rejects it */
    cf_context *ctx = cft_context();
    cf_mesh_data *d = NULL;
    CHECK_OK(ctx, cf_read_mesh_file(ctx, cft_require_shared_mesh("bad/nonmanifold_edges_beetle.obj"), &d));
    CHECK(d && d->vertex_count == 1148 && d->face_count == 2053);
    cf_mesh_data_destroy(&d);
    cf_context_destroy(&ctx);
    expect_load("nonmanifold_edges_beetle.obj", CF_ERR_NONMANIFOLD_EDGE, "is shared by 3 faces");
}

static void test_flipped_face(void)
{
    /* face #101 (1-based, line 3031) reversed: f 213 823 829 */
    cf_context *ctx = cft_context();
    cf_mesh_data *d = NULL;
    CHECK_OK(ctx, cf_read_mesh_file(ctx, cft_require_shared_mesh("bad/flipped_face_spot.obj"), &d));
    CHECK(d && d->vertex_count == 2930 && d->face_count == 5856);
    if (d) CHECK(d->triangles[3 * 100] == 212 && d->triangles[3 * 100 + 1] == 822 && d->triangles[3 * 100 + 2] == 828);
    cf_mesh_data_destroy(&d);
    cf_context_destroy(&ctx);
    expect_load("flipped_face_spot.obj", CF_ERR_ORIENTATION, "face");
}

int main(void)
{
    CFT_RUN(test_truncated);
    CFT_RUN(test_nan);
    CFT_RUN(test_nonmanifold_edges);
    CFT_RUN(test_flipped_face);
    return cft_finish();
}
