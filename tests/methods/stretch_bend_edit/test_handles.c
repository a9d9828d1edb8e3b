/*
 * Handle sets and the JSON handle file (docs/edit.md): selection by index
 * list, box and relative box; fixed sets, explicit targets and rigid
 * transforms; and each bad file yields CF_ERR_PARSE with a message naming
 * the problem (unknown vertex with its value and the set, empty set,
 * malformed JSON with line:column, all vertices fixed, overlapping sets).
 */
#include "test.h"

#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/stretch_bend_edit.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int contains(const char *s, const char *part) { return strstr(s, part) != NULL; }

static void expect_error(cf_context *ctx, const cf_mesh *mesh, const char *json, const char *part1, const char *part2)
{
    cf_handle_set *h = NULL;
    CHECK_STATUS(cf_handle_set_parse_json(ctx, mesh, NULL, json, "h.json", &h), CF_ERR_PARSE);
    CHECK(h == NULL);
    const char *msg = cf_context_message(ctx);
    if (!contains(msg, part1) || (part2 && !contains(msg, part2)))
        fprintf(stderr, "unexpected message: %s\n", msg);
    CHECK(contains(msg, part1));
    if (part2) CHECK(contains(msg, part2));
    CHECK(contains(msg, "h.json"));
}

/* Creates the edit flow with handles (vertices, targets) and checks the
 * status and, on failure, that the message contains `part`. */
static void expect_edit_create(cf_context *ctx, const cf_mesh *mesh, int32_t n, const int32_t *vertices,
                               const double *targets, cf_status status, const char *part)
{
    cf_handle_set *h = NULL;
    CHECK_OK(ctx, cf_handle_set_create(ctx, n, vertices, targets, &h));
    cf_flow_options fo;
    cf_flow_options_default(CF_FLOW_STRETCH_BEND_EDIT, &fo);
    ((cf_stretch_bend_options *)cf_flow_options_method(&fo))->handles = h;
    cf_flow *flow = NULL;
    CHECK_STATUS(cf_flow_create(ctx, mesh, NULL, &fo, &flow), status);
    if (part) CHECK(contains(cf_context_message(ctx), part));
    cf_flow_destroy(&flow);
    cf_handle_set_destroy(&h);
}

static void test_bad_files(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_sheet(ctx, 4, 1.0, 0, &mesh)); /* 25 vertices */
    if (!mesh) return;
    expect_error(ctx, mesh, "{\"sets\": [{\"name\": \"tip\", \"vertices\": [3, 99], \"fixed\": true}]}",
                 "unknown vertex 99", "'tip'");
    expect_error(ctx, mesh, "{\"sets\": [{\"name\": \"neg\", \"vertices\": [-1], \"fixed\": true}]}",
                 "unknown vertex -1", "'neg'");
    expect_error(ctx, mesh, "{\"sets\": [{\"name\": \"none\", \"vertices\": [], \"fixed\": true}]}", "empty",
                 "'none'");
    expect_error(ctx, mesh,
                 "{\"sets\": [{\"name\": \"far\", \"box\": {\"min\": [5,5,5], \"max\": [6,6,6]}, \"fixed\": true}]}",
                 "empty", "'far'");
    expect_error(ctx, mesh, "{\"sets\": [\n  {\"name\": \"a\", \"vertices\": [1,2] \"fixed\": true}]}",
                 "h.json:2:", "malformed JSON");
    expect_error(ctx, mesh,
                 "{\"sets\": [{\"name\": \"all\", \"relative_box\": {\"min\": [0,0,0], \"max\": [1,1,1]}, "
                 "\"fixed\": true}]}",
                 "all 25 vertices are constrained", NULL);
    expect_error(ctx, mesh,
                 "{\"sets\": [{\"name\": \"a\", \"vertices\": [1, 2], \"fixed\": true},"
                 " {\"name\": \"b\", \"vertices\": [2, 3], \"transform\": {\"translate\": [0,0,1]}}]}",
                 "vertex 2 is already in set", "'b'");
    expect_error(ctx, mesh, "{\"sets\": [{\"name\": \"a\", \"vertices\": [1], \"fixd\": true}]}", "unknown key: fixd",
                 NULL);
    expect_error(ctx, mesh, "{\"sets\": [{\"name\": \"a\", \"vertices\": [1, 2], \"targets\": [[0,0,0]]}]}",
                 "must hold 2 positions", NULL);
    expect_error(ctx, mesh, "{\"sets\": [{\"name\": \"a\", \"vertices\": [1]}]}", "exactly one of", NULL);
    expect_error(ctx, mesh, "{\"handles\": []}", "\"sets\"", NULL);
    expect_error(ctx, mesh,
                 "{\"sets\": [{\"name\": \"r\", \"vertices\": [1], \"transform\": {\"rotate\": {\"axis\": [0,0,0], "
                 "\"angle_degrees\": 10}}}]}",
                 "zero vector", NULL);
    /* targets beyond the mesh's coordinate range (1e50) are refused by the
     * reader, naming the set (a 1e308 translation used to fail later as
     * "energy is not finite") */
    expect_error(ctx, mesh, "{\"sets\": [{\"name\": \"far\", \"vertices\": [1], \"targets\": [[1e60, 0, 0]]}]}",
                 "set 'far': targets[0] is beyond the range of coordinates", NULL);
    expect_error(ctx, mesh,
                 "{\"sets\": [{\"name\": \"far\", \"vertices\": [1], \"transform\": {\"translate\": [1e308, 0, 0]}}]}",
                 "set 'far': the transform moves vertex 1 to (1e+308", "beyond the range of coordinates");
    {
        /* ... and so is an array-built set */
        cf_handle_set *far = NULL;
        const int32_t v1 = 1;
        const double t1[3] = {0.0, 2e50, 0.0};
        CHECK_STATUS(cf_handle_set_create(ctx, 1, &v1, t1, &far), CF_ERR_NONFINITE);
        CHECK(far == NULL);
        CHECK(contains(cf_context_message(ctx), "handle 0 (vertex 1): target coordinate 2e+50 is out of range"));
    }
    cf_handle_set *h = NULL;
    CHECK_STATUS(cf_handle_set_read_json(ctx, mesh, NULL, "/nonexistent/h.json", &h), CF_ERR_IO);
    CHECK(contains(cf_context_message(ctx), "/nonexistent/h.json"));

    /* All vertices fixed through the array API: the flow refuses it. */
    int32_t nv = cf_mesh_vertex_count(mesh);
    int32_t vs[25];
    for (int32_t v = 0; v < nv; ++v) vs[v] = v;
    CHECK_OK(ctx, cf_handle_set_create(ctx, nv, vs, cf_mesh_positions(mesh), &h));
    cf_flow_options fo;
    cf_flow_options_default(CF_FLOW_STRETCH_BEND_EDIT, &fo);
    ((cf_stretch_bend_options *)cf_flow_options_method(&fo))->handles = h;
    cf_flow *flow = NULL;
    CHECK_STATUS(cf_flow_create(ctx, mesh, NULL, &fo, &flow), CF_ERR_INVALID_ARG);
    CHECK(contains(cf_context_message(ctx), "all 25 vertices are handles"));
    cf_handle_set_destroy(&h);
    /* No handles at all. */
    ((cf_stretch_bend_options *)cf_flow_options_method(&fo))->handles = NULL;
    CHECK_STATUS(cf_flow_create(ctx, mesh, NULL, &fo, &flow), CF_ERR_INVALID_ARG);
    CHECK(contains(cf_context_message(ctx), "handle"));
    /* Duplicates through the array API. */
    int32_t dup[2] = {3, 3};
    double t[6] = {0};
    CHECK_STATUS(cf_handle_set_create(ctx, 2, dup, t, &h), CF_ERR_INVALID_ARG);
    CHECK(contains(cf_context_message(ctx), "vertex 3 is constrained twice"));
    /* Targets that force a zero-area face: the ends of an edge at one point
     * (before: every energy ran "successfully" to a mesh the reader rejects
     * with "face 0: zero area"), or a face's three corners on one line. */
    const int32_t *tri = cf_mesh_triangles(mesh);
    int32_t corners[3] = {tri[0], tri[1], tri[2]};
    for (int a = 0; a < 3; ++a) /* sorted, as the handle set stores them */
        for (int b = a + 1; b < 3; ++b)
            if (corners[b] < corners[a]) { int32_t tmp = corners[a]; corners[a] = corners[b]; corners[b] = tmp; }
    const double same[6] = {0.5, 0.5, 1.0, 0.5, 0.5, 1.0};
    expect_edit_create(ctx, mesh, 2, corners, same, CF_ERR_INVALID_ARG, "share an edge but their handle targets coincide");
    const double line[9] = {0, 0, 0, 1, 0, 0, 3, 0, 0};
    expect_edit_create(ctx, mesh, 3, corners, line, CF_ERR_INVALID_ARG,
                       "face 0: its three vertices are handles with collinear targets");
    /* the same corners at non-degenerate targets are fine */
    const double moved[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    expect_edit_create(ctx, mesh, 3, corners, moved, CF_OK, NULL);

    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_good_file(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_sheet(ctx, 4, 1.0, 0, &mesh));
    if (!mesh) return;
    const double *x = cf_mesh_positions(mesh);
    /* Left column fixed by a box, right column rotated 90 degrees about
     * the x axis through (1, 0.5, 0) and shifted, vertex 12 (the centre)
     * given an explicit target. */
    const char *json = "{\"sets\": ["
                       "{\"name\": \"left\", \"box\": {\"min\": [-0.1,-0.1,-0.1], \"max\": [0.1,1.1,0.1]}, "
                       "\"fixed\": true},"
                       "{\"name\": \"right\", \"relative_box\": {\"min\": [1,0,0], \"max\": [1,1,1]}, "
                       "\"transform\": {\"translate\": [0.5,0,0], \"rotate\": {\"axis\": [2,0,0], "
                       "\"angle_degrees\": 90, \"center\": [1,0.5,0]}}},"
                       "{\"name\": \"centre\", \"vertices\": [12], \"targets\": [[0.5,0.5,0.25]]}]}";
    const char *path = cft_temp_path(".json");
    FILE *f = fopen(path, "w");
    CHECK(f != NULL);
    if (!f) return;
    fputs(json, f);
    fclose(f);
    cf_handle_set *h = NULL;
    CHECK_OK(ctx, cf_handle_set_read_json(ctx, mesh, NULL, path, &h));
    if (!h) return;
    CHECK(h->count == 5 + 5 + 1);
    CHECK(h->moved_count == 5 + 1);
    for (int32_t k = 0; k < h->count; ++k) {
        int32_t v = h->vertices[k];
        const double *p = x + 3 * v, *q = h->targets + 3 * k;
        if (k > 0) CHECK(v > h->vertices[k - 1]);
        if (p[0] < 0.1) {
            CHECK(q[0] == p[0] && q[1] == p[1] && q[2] == p[2]);
        } else if (p[0] > 0.9) {
            /* (1, y, 0) -> (1, 0.5, y - 0.5) + (0.5, 0, 0) */
            CHECK_NEAR(q[0], 1.5, 0.0, 1e-12);
            CHECK_NEAR(q[1], 0.5, 0.0, 1e-12);
            CHECK_NEAR(q[2], p[1] - 0.5, 0.0, 1e-12);
        } else {
            CHECK(v == 12);
            CHECK_NEAR(q[2], 0.25, 0.0, 0.0);
        }
    }
    /* The set drives an edit; the handle vertices end on their targets. */
    cf_stretch_bend_options o;
    cf_stretch_bend_options_default(&o);
    o.handles = h;
    o.max_iterations = 20;
    double y[75];
    CHECK_OK(ctx, cf_stretch_bend_edit(ctx, mesh, NULL, &o, y, NULL));
    for (int32_t k = 0; k < h->count; ++k)
        for (int d = 0; d < 3; ++d) CHECK(y[3 * h->vertices[k] + d] == h->targets[3 * k + d]);
    cf_handle_set_destroy(&h);
    remove(path);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Continue from the deformed state, restart from the rest pose, and a
 * handle change mid-run (refactorisation). */
static void test_continue_and_restart(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_sheet(ctx, 6, 1.0, 0, &mesh));
    if (!mesh) return;
    const char *j1 = "{\"sets\": [{\"name\": \"l\", \"relative_box\": {\"min\": [0,0,0], \"max\": [0,1,1]}, \"fixed\": true},"
                     "{\"name\": \"r\", \"relative_box\": {\"min\": [1,0,0], \"max\": [1,1,1]}, "
                     "\"transform\": {\"translate\": [-0.2,0,0.3]}}]}";
    cf_handle_set *h1 = NULL, *h2 = NULL;
    CHECK_OK(ctx, cf_handle_set_parse_json(ctx, mesh, NULL, j1, "j1", &h1));
    cf_flow_options fo;
    cf_flow_options_default(CF_FLOW_STRETCH_BEND_EDIT, &fo);
    ((cf_stretch_bend_options *)cf_flow_options_method(&fo))->handles = h1;
    CHECK_OK(ctx, cf_flow_options_set(ctx, &fo, "energy", "arap"));
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &fo, &flow));
    if (!flow) return;
    CHECK_OK(ctx, cf_flow_run(flow, 50, NULL));
    double e1 = cf_flow_energy(flow);
    /* Second edit applied to the deformed state: pull the right side
     * away (stretching, so the energy must rise); the handle file is
     * evaluated on the current positions. */
    const char *j2 = "{\"sets\": [{\"name\": \"l\", \"relative_box\": {\"min\": [0,0,0], \"max\": [0.01,1,1]}, \"fixed\": true},"
                     "{\"name\": \"r\", \"vertices\": [6, 13, 20, 27, 34, 41, 48], "
                     "\"transform\": {\"translate\": [0.4,0,0]}}]}";
    CHECK_OK(ctx, cf_handle_set_parse_json(ctx, mesh, cf_flow_positions(flow), j2, "j2", &h2));
    CHECK_OK(ctx, cf_stretch_bend_set_handles(flow, h2));
    CHECK_NEAR(cf_flow_positions(flow)[3 * 48], 1.0 - 0.2 + 0.4, 0.0, 1e-12);
    CHECK_OK(ctx, cf_flow_run(flow, 50, NULL));
    CHECK(cf_flow_energy(flow) > e1);
    /* Restart from the rest pose with the second handle set. */
    CHECK_OK(ctx, cf_flow_set_positions(flow, cf_mesh_positions(mesh)));
    CHECK(h2->vertices[h2->count - 1] == 48);
    CHECK_NEAR(cf_flow_positions(flow)[3 * 48], h2->targets[3 * (h2->count - 1)], 0.0, 0.0);
    CHECK_NEAR(cf_flow_positions(flow)[3 * 47], cf_mesh_positions(mesh)[3 * 47], 0.0, 0.0);
    cf_flow_destroy(&flow);
    cf_handle_set_destroy(&h1);
    cf_handle_set_destroy(&h2);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Failure injection (as CHOLMOD's t_memory): the n-th allocation of
 * parsing a handle file, creating an edit flow and stepping it fails, for
 * every n until the whole sequence succeeds; every failure must be reported
 * (no crash) and leave nothing allocated. */
static void test_allocation_failures(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_sheet(ctx, 5, 1.0, 0, &mesh));
    if (!mesh) return;
    size_t base = cf_context_bytes_in_use(ctx);
    const char *json = "{\"sets\": [{\"name\": \"l\", \"relative_box\": {\"min\": [0,0,0], \"max\": [0,1,1]}, "
                       "\"fixed\": true}, {\"name\": \"r\", \"vertices\": [5, 35], \"transform\": "
                       "{\"translate\": [0,0,0.3]}}]}";
    for (int e = 0; e < CF_STRETCH_BEND_ENERGY_COUNT; ++e) {
        int succeeded = 0, failures = 0;
        for (int64_t n = 1; n < 2000 && !succeeded; ++n) {
            cf_context_fail_allocation(ctx, n, 1);
            cf_handle_set *h = NULL;
            cf_flow *flow = NULL;
            cf_status st = cf_handle_set_parse_json(ctx, mesh, NULL, json, "inject", &h);
            if (st == CF_OK) {
                cf_flow_options fo;
                cf_flow_options_default(CF_FLOW_STRETCH_BEND_EDIT, &fo);
                cf_stretch_bend_options *o = cf_flow_options_method(&fo);
                o->handles = h;
                o->energy = e;
                st = cf_flow_create(ctx, mesh, NULL, &fo, &flow);
                if (st == CF_OK) st = cf_flow_run(flow, 3, NULL);
            }
            cf_context_fail_allocation(ctx, 0, 0);
            cf_flow_destroy(&flow);
            cf_handle_set_destroy(&h);
            if (st == CF_OK) succeeded = 1; else ++failures;
            if (cf_context_bytes_in_use(ctx) != base) {
                fprintf(stderr, "leak after failing allocation %lld (%s)\n", (long long)n, cf_status_name(st));
                CHECK(cf_context_bytes_in_use(ctx) == base);
                break;
            }
        }
        CHECK(succeeded);
        CHECK(failures > 10);
    }
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* The rest pose is explicit (options.rest_positions): a mesh whose own
 * positions are a sheared copy, edited with the rest pose given and the
 * handles on the rest pose, returns to the rest pose (zero energy there),
 * which it would not with the mesh's positions as rest. */
static void test_explicit_rest_pose(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *bar = NULL;
    CHECK_OK(ctx, cf_generate_bar(ctx, 2, 2, 6, 1.0, 1.0, 3.0, 0, &bar));
    if (!bar) return;
    int32_t nv = cf_mesh_vertex_count(bar), nf = cf_mesh_face_count(bar);
    const double *rest = cf_mesh_positions(bar);
    double *sheared = malloc(sizeof(double) * 3 * (size_t)nv);
    for (int32_t v = 0; v < nv; ++v) {
        sheared[3 * v] = rest[3 * v] + 0.3 * rest[3 * v + 2];
        sheared[3 * v + 1] = rest[3 * v + 1];
        sheared[3 * v + 2] = rest[3 * v + 2];
    }
    cf_mesh_desc desc = {0};
    desc.vertex_count = nv;
    desc.positions = sheared;
    desc.face_count = nf;
    desc.triangles = cf_mesh_triangles(bar);
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_mesh_create(ctx, &desc, &mesh));
    cf_handle_set *h = NULL;
    const char *json = "{\"sets\": [{\"name\": \"ends\", \"relative_box\": {\"min\": [0,0,0], \"max\": [1,1,0]}, "
                       "\"fixed\": true}, {\"name\": \"top\", \"relative_box\": {\"min\": [0,0,1], \"max\": [1,1,1]}, "
                       "\"fixed\": true}]}";
    CHECK_OK(ctx, cf_handle_set_parse_json(ctx, mesh, rest, json, "rest", &h));
    if (!mesh || !h) return;
    cf_stretch_bend_options o;
    cf_stretch_bend_options_default(&o);
    o.energy = CF_STRETCH_BEND_ARAP;
    o.handles = h;
    o.rest_positions = rest;
    o.max_iterations = 500;
    o.relative_tolerance = 1e-12;
    double *y = malloc(sizeof(double) * 3 * (size_t)nv);
    cf_flow_info info;
    CHECK_OK(ctx, cf_stretch_bend_edit(ctx, mesh, NULL, &o, y, &info)); /* starts from the sheared positions */
    double err = 0.0;
    for (int32_t i = 0; i < 3 * nv; ++i) err = fmax(err, fabs(y[i] - rest[i]));
    CHECK_LE(err, 1e-6);
    CHECK_LE(fabs(info.energy), 1e-10);
    /* With the mesh's (sheared) positions as rest pose the same handles
     * give a deformed result with positive energy. */
    o.rest_positions = NULL;
    CHECK_OK(ctx, cf_stretch_bend_edit(ctx, mesh, NULL, &o, y, &info));
    CHECK(info.energy > 1e-3);
    free(y);
    free(sheared);
    cf_handle_set_destroy(&h);
    cf_mesh_destroy(&mesh);
    cf_mesh_destroy(&bar);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_explicit_rest_pose);
    CFT_RUN(test_allocation_failures);
    CFT_RUN(test_bad_files);
    CFT_RUN(test_good_file);
    CFT_RUN(test_continue_and_restart);
    return cft_finish();
}
