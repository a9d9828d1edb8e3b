/*
 * The constraints module: point sets from index lists, boxes and files,
 * rigid transforms (right-hand rule, centre, scale, range check), targets
 * from a set and a transform (agreeing with the JSON file's "transform"),
 * the file reader's warnings (issue 15: unknown top-level keys and sets
 * without a name are reported through the log callback), and failure paths.
 * The handle-file errors are tested with the edit method
 * (tests/methods/stretch_bend_edit/test_handles.c).
 */
#include "test.h"

#include "curvflow/constraints.h"
#include "curvflow/generate.h"
#include "curvflow/quaternion.h"

#include <stdio.h>
#include <string.h>

static int contains(const char *s, const char *part) { return strstr(s, part) != NULL; }

/* Collects warning lines for the warning tests. */
static void test_point_sets(void)
{
    cf_context *ctx = cft_context();
    cf_point_set *s = NULL;
    const int32_t idx[5] = {7, 2, 11, 0, 5};
    CHECK_OK(ctx, cf_point_set_from_indices(ctx, 12, 5, idx, &s));
    if (!s) return;
    CHECK(s->count == 5);
    const int32_t sorted[5] = {0, 2, 5, 7, 11};
    for (int k = 0; k < 5; ++k) CHECK(s->vertices[k] == sorted[k]);
    cf_point_set_destroy(&s);
    CHECK(s == NULL);
    const int32_t dup[3] = {4, 1, 4}, out[2] = {1, 12};
    CHECK_STATUS(cf_point_set_from_indices(ctx, 12, 3, dup, &s), CF_ERR_INVALID_ARG);
    CHECK(contains(cf_context_message(ctx), "vertex 4 is listed twice (indices[0] and [2])"));
    CHECK_STATUS(cf_point_set_from_indices(ctx, 12, 2, out, &s), CF_ERR_INVALID_ARG);
    CHECK(contains(cf_context_message(ctx), "indices[1] = 12 is not a vertex (mesh has 12)"));
    CHECK_STATUS(cf_point_set_from_indices(ctx, 12, 2, NULL, &s), CF_ERR_INVALID_ARG);
    CHECK(s == NULL);
    CHECK_OK(ctx, cf_point_set_from_indices(ctx, 12, 0, NULL, &s));
    CHECK(s && s->count == 0);
    cf_point_set_destroy(&s);

    /* boxes on the 4 x 4 sheet [0, 1]^2 (vertex i + 5 j at (i, j) / 4) */
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_sheet(ctx, 4, 1.0, 0, &mesh));
    if (!mesh) return;
    int32_t nv = cf_mesh_vertex_count(mesh);
    const double *x = cf_mesh_positions(mesh);
    const double lo[3] = {0.7, -1, -1}, hi[3] = {2, 0.3, 1};
    CHECK_OK(ctx, cf_point_set_from_box(ctx, nv, x, lo, hi, 0, &s));
    /* x >= 0.7: columns i = 3, 4; y <= 0.3: rows j = 0, 1 */
    CHECK(s && s->count == 4);
    const int32_t in_box[4] = {3, 4, 8, 9};
    for (int k = 0; s && k < s->count && k < 4; ++k) CHECK(s->vertices[k] == in_box[k]);
    cf_point_set_destroy(&s);
    /* relative: the right column (fraction 1 of x) despite rounding */
    const double rlo[3] = {1, 0, 0}, rhi[3] = {1, 1, 1};
    CHECK_OK(ctx, cf_point_set_from_box(ctx, nv, x, rlo, rhi, 1, &s));
    CHECK(s && s->count == 5);
    for (int k = 0; s && k < s->count; ++k) CHECK(s->vertices[k] == 4 + 5 * k);
    cf_point_set_destroy(&s);
    const double far[3] = {5, 5, 5};
    CHECK_OK(ctx, cf_point_set_from_box(ctx, nv, x, far, far, 0, &s));
    CHECK(s && s->count == 0);
    cf_point_set_destroy(&s);
    const double bad[3] = {0, NAN, 0};
    CHECK_STATUS(cf_point_set_from_box(ctx, nv, x, bad, hi, 0, &s), CF_ERR_INVALID_ARG);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_rigid_transforms(void)
{
    cf_context *ctx = cft_context();
    cf_rigid_transform t;
    cf_rigid_transform_identity(&t);
    const double p[6] = {1, 2, 3, -4, 5, 0.5};
    double q[6];
    CHECK_OK(ctx, cf_rigid_transform_apply(ctx, &t, 2, p, q));
    for (int k = 0; k < 6; ++k) CHECK(q[k] == p[k]);
    /* 90 degrees about +z turns +x into +y (right-hand rule) */
    const double z[3] = {0, 0, 2}, ex[3] = {1, 0, 0};
    CHECK_OK(ctx, cf_rigid_transform_set_rotation(ctx, &t, z, 0.5 * 3.14159265358979323846));
    CHECK_OK(ctx, cf_rigid_transform_apply(ctx, &t, 1, ex, q));
    CHECK_NEAR(q[0], 0.0, 0, 1e-15);
    CHECK_NEAR(q[1], 1.0, 0, 1e-15);
    CHECK_NEAR(q[2], 0.0, 0, 1e-15);
    /* the same rotation as the quaternion module's, for any axis */
    const double axis[3] = {0.3, -1.2, 0.7};
    CHECK_OK(ctx, cf_rigid_transform_set_rotation(ctx, &t, axis, 2.1));
    double r[9];
    cf_quat_to_rotation_matrix(cf_quat_from_axis_angle(axis, 2.1), r);
    for (int k = 0; k < 9; ++k) CHECK_NEAR(t.rotation[k], r[k], 0, 1e-15);
    /* centre, scale, translation: c + s R (x - c) + t with R = 180 deg about z */
    CHECK_OK(ctx, cf_rigid_transform_set_rotation(ctx, &t, z, 3.14159265358979323846));
    t.scale = 2.0;
    t.center[0] = 1.0;
    t.translation[2] = 0.5;
    const double a[3] = {2, 1, 0};
    CHECK_OK(ctx, cf_rigid_transform_apply(ctx, &t, 1, a, q)); /* (1,0,0) + 2 (-1,-1,0) + (0,0,0.5) */
    CHECK_NEAR(q[0], -1.0, 0, 1e-14);
    CHECK_NEAR(q[1], -2.0, 0, 1e-14);
    CHECK_NEAR(q[2], 0.5, 0, 1e-15);
    /* in place */
    double b[3] = {2, 1, 0};
    CHECK_OK(ctx, cf_rigid_transform_apply(ctx, &t, 1, b, b));
    CHECK_NEAR(b[0], -1.0, 0, 1e-14);
    /* failures: zero axis, bad scale, image out of range (named) */
    const double zero[3] = {0, 0, 0};
    CHECK_STATUS(cf_rigid_transform_set_rotation(ctx, &t, zero, 1.0), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_rigid_transform_set_rotation(ctx, &t, z, NAN), CF_ERR_INVALID_ARG);
    t.scale = 0.0;
    CHECK_STATUS(cf_rigid_transform_apply(ctx, &t, 1, a, q), CF_ERR_INVALID_ARG);
    cf_rigid_transform_identity(&t);
    t.translation[1] = 1e60;
    CHECK_STATUS(cf_rigid_transform_apply(ctx, &t, 2, p, q), CF_ERR_NONFINITE);
    CHECK(contains(cf_context_message(ctx), "point 0 goes to"));
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Targets from a set and a transform equal the JSON file's "transform" for
 * the same selection and motion (the file reader uses the same map). */
static void test_targets_from_points(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_sheet(ctx, 4, 1.0, 0, &mesh));
    if (!mesh) return;
    const double *x = cf_mesh_positions(mesh);
    const int32_t idx[3] = {24, 4, 14};
    cf_point_set *s = NULL;
    CHECK_OK(ctx, cf_point_set_from_indices(ctx, cf_mesh_vertex_count(mesh), 3, idx, &s));
    cf_handle_set *fixed = NULL, *moved = NULL, *file = NULL;
    CHECK_OK(ctx, cf_handle_set_from_points(ctx, s, x, NULL, &fixed));
    CHECK(fixed && fixed->count == 3 && fixed->moved_count == 0);
    for (int k = 0; fixed && k < 3; ++k)
        for (int d = 0; d < 3; ++d) CHECK(fixed->targets[3 * k + d] == x[3 * fixed->vertices[k] + d]);
    cf_rigid_transform t;
    cf_rigid_transform_identity(&t);
    const double axis[3] = {1, 0, 0};
    CHECK_OK(ctx, cf_rigid_transform_set_rotation(ctx, &t, axis, 30.0 * 3.14159265358979323846 / 180.0));
    t.center[0] = 1.0;
    t.center[1] = 0.5;
    t.scale = 1.5;
    t.translation[2] = 0.25;
    CHECK_OK(ctx, cf_handle_set_from_points(ctx, s, x, &t, &moved));
    CHECK(moved && moved->moved_count == 3);
    const char *json = "{\"sets\": [{\"name\": \"right\", \"vertices\": [24, 4, 14], \"transform\": {\"rotate\": "
                       "{\"axis\": [1,0,0], \"angle_degrees\": 30, \"center\": [1,0.5,0]}, \"scale\": 1.5, "
                       "\"translate\": [0,0,0.25]}}]}";
    CHECK_OK(ctx, cf_handle_set_parse_json(ctx, mesh, NULL, json, "t.json", &file));
    CHECK(file && moved && file->count == 3);
    for (int k = 0; file && moved && k < 9; ++k) CHECK(file->targets[k] == moved->targets[k]);
    /* a transform that leaves the coordinate range is refused, naming the vertex */
    cf_handle_set *h = NULL;
    t.translation[0] = 1e300;
    CHECK_STATUS(cf_handle_set_from_points(ctx, s, x, &t, &h), CF_ERR_NONFINITE);
    CHECK(contains(cf_context_message(ctx), "moves vertex 4 to"));
    CHECK(h == NULL);
    cf_handle_set_destroy(&fixed);
    cf_handle_set_destroy(&moved);
    cf_handle_set_destroy(&file);
    cf_point_set_destroy(&s);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Point sets from a file: a set needs only a selection; a handle file is a
 * point-set file too; sets must not overlap. */
static void test_point_set_file(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_sheet(ctx, 4, 1.0, 0, &mesh));
    if (!mesh) return;
    cf_point_set *s = NULL;
    const char *sel = "{\"sets\": [{\"name\": \"a\", \"vertices\": [3, 1]},"
                      " {\"name\": \"left\", \"relative_box\": {\"min\": [0,0,0], \"max\": [0,1,1]}}]}";
    CHECK_OK(ctx, cf_point_set_parse_json(ctx, mesh, NULL, sel, "p.json", &s));
    CHECK(s && s->count == 7); /* vertices 1, 3 and the left column 0, 5, 10, 15, 20 */
    const int32_t expect[7] = {0, 1, 3, 5, 10, 15, 20};
    for (int k = 0; s && k < 7; ++k) CHECK(s->vertices[k] == expect[k]);
    cf_point_set_destroy(&s);
    /* the whole mesh may be selected (no "nothing left to deform" here) */
    const char *all = "{\"sets\": [{\"name\": \"all\", \"relative_box\": {\"min\": [0,0,0], \"max\": [1,1,1]}}]}";
    CHECK_OK(ctx, cf_point_set_parse_json(ctx, mesh, NULL, all, "p.json", &s));
    CHECK(s && s->count == 25);
    cf_point_set_destroy(&s);
    const char *handles = "{\"sets\": [{\"name\": \"a\", \"vertices\": [3], \"transform\": {\"translate\": [0,0,1]}}]}";
    CHECK_OK(ctx, cf_point_set_parse_json(ctx, mesh, NULL, handles, "h.json", &s));
    CHECK(s && s->count == 1 && s->vertices[0] == 3);
    cf_point_set_destroy(&s);
    const char *overlap = "{\"sets\": [{\"name\": \"a\", \"vertices\": [3]}, {\"name\": \"b\", \"vertices\": [3]}]}";
    CHECK_STATUS(cf_point_set_parse_json(ctx, mesh, NULL, overlap, "o.json", &s), CF_ERR_PARSE);
    CHECK(contains(cf_context_message(ctx), "o.json: set 'b': vertex 3 is already in set"));
    /* ... but a handle file still needs a target rule */
    cf_handle_set *h = NULL;
    CHECK_STATUS(cf_handle_set_parse_json(ctx, mesh, NULL, sel, "p.json", &h), CF_ERR_PARSE);
    CHECK(contains(cf_context_message(ctx), "exactly one of"));
    /* from a file, and the file errors */
    const char *path = cft_temp_path(".json");
    FILE *f = fopen(path, "w");
    CHECK(f != NULL);
    if (f) {
        fputs(sel, f);
        fclose(f);
        CHECK_OK(ctx, cf_point_set_read_json(ctx, mesh, NULL, path, &s));
        CHECK(s && s->count == 7);
        cf_point_set_destroy(&s);
        f = fopen(path, "wb");
        fwrite("{\"sets\"\0: []}", 1, 13, f);
        fclose(f);
        CHECK_STATUS(cf_point_set_read_json(ctx, mesh, NULL, path, &s), CF_ERR_PARSE);
        CHECK(contains(cf_context_message(ctx), "NUL byte"));
        remove(path);
    }
    CHECK_STATUS(cf_point_set_read_json(ctx, mesh, NULL, "/nonexistent/p.json", &s), CF_ERR_IO);
    CHECK(contains(cf_context_message(ctx), "/nonexistent/p.json: cannot open point set file"));
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Issue 15 (false alarms, last bullet): input the reader ignores is
 * reported as a warning through the context's log callback, and the file is
 * still read. */
static void test_warnings(void)
{
    cf_context *ctx = NULL;
    CHECK(cf_context_create(&ctx) == CF_OK);
    cft_warnings cap;
    cft_capture_warnings(ctx, &cap);
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_sheet(ctx, 4, 1.0, 0, &mesh));
    if (!mesh) return;
    const char *json = "{\"version\": 2, \"sets\": [{\"vertices\": [1], \"fixed\": true},"
                       " {\"name\": 7, \"vertices\": [2], \"fixed\": true},"
                       " {\"name\": \"ok\", \"vertices\": [3], \"fixed\": true}], \"handles\": []}";
    cf_handle_set *h = NULL;
    CHECK_OK(ctx, cf_handle_set_parse_json(ctx, mesh, NULL, json, "w.json", &h));
    CHECK(h && h->count == 3);
    CHECK(cap.count == 4);
    CHECK(contains(cap.text, "w.json: unknown top-level key 'version' ignored"));
    CHECK(contains(cap.text, "w.json: unknown top-level key 'handles' ignored"));
    CHECK(contains(cap.text, "w.json: set #0 has no \"name\""));
    CHECK(contains(cap.text, "w.json: set #1: \"name\" is not a string"));
    if (cap.count != 4) fprintf(stderr, "warnings:\n%s", cap.text);
    cf_handle_set_destroy(&h);
    /* a clean file warns about nothing; the point-set reader warns too */
    cft_capture_warnings(ctx, &cap);
    const char *clean = "{\"sets\": [{\"name\": \"a\", \"vertices\": [1], \"fixed\": true}]}";
    CHECK_OK(ctx, cf_handle_set_parse_json(ctx, mesh, NULL, clean, "c.json", &h));
    CHECK(cap.count == 0);
    cf_handle_set_destroy(&h);
    cf_point_set *s = NULL;
    CHECK_OK(ctx, cf_point_set_parse_json(ctx, mesh, NULL, "{\"set\": 1, \"sets\": [{\"vertices\": [1]}]}", "p.json", &s));
    CHECK(cap.count == 2);
    CHECK(contains(cap.text, "p.json: unknown top-level key 'set' ignored"));
    cf_point_set_destroy(&s);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

typedef struct sweep_data {
    const cf_mesh *mesh;
    const char *json;
} sweep_data;

static cf_status sweep_call(cf_context *ctx, void *user)
{
    const sweep_data *d = user;
    cf_point_set *s = NULL;
    cf_handle_set *h = NULL;
    cf_status st = cf_point_set_parse_json(ctx, d->mesh, NULL, d->json, "sweep", &s);
    if (st == CF_OK) {
        cf_rigid_transform t;
        cf_rigid_transform_identity(&t);
        t.translation[2] = 1.0;
        st = cf_handle_set_from_points(ctx, s, cf_mesh_positions(d->mesh), &t, &h);
    }
    cf_handle_set_destroy(&h);
    cf_point_set_destroy(&s);
    return st;
}

static void test_allocation_failures(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_sheet(ctx, 4, 1.0, 0, &mesh));
    if (!mesh) return;
    /* jansson allocates with malloc, not through the context: only the
     * library's own allocations are swept */
    sweep_data d = {mesh, "{\"sets\": [{\"name\": \"l\", \"box\": {\"min\": [0,0,0], \"max\": [0.3,1,1]}}]}"};
    CHECK(cft_allocation_sweep(ctx, "point set file + targets", sweep_call, &d, 0) >= 5);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_point_sets);
    CFT_RUN(test_rigid_transforms);
    CFT_RUN(test_targets_from_points);
    CFT_RUN(test_point_set_file);
    CFT_RUN(test_warnings);
    CFT_RUN(test_allocation_failures);
    return cft_finish();
}
