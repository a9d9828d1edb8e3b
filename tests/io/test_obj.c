/* OBJ reader and writer: every face syntax, relative indices, polygons,
 * ignored keywords, line endings, every error path, bit-exact round trips
 * with texture coordinates, side CSV fields, vertex colours, materials,
 * allocation failures. */
#define _POSIX_C_SOURCE 200809L
#include "io_test_util.h"

static const char *const square_v = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

static cf_mesh_data *read_text(cf_context *ctx, const char *text)
{
    cf_mesh_data *d = NULL;
    CHECK_OK(ctx, cf_read_mesh_memory(ctx, text, strlen(text), CF_FORMAT_OBJ, "t.obj", &d));
    return d;
}

static void test_face_syntaxes(void)
{
    cf_context *ctx = cft_context();
    static const char *const faces[] = {
        "f 1 2 3\nf 1 3 4\n",
        "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n",
        "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n",
        "f 1//1 2//1 3//1\nf 1//1 3//1 4//1\n",
        "f -4 -3 -2\nf -4 -2 -1\n",               /* relative to the 4 vertices so far */
        "f -4/-4 -3/-3 -2/-2\nf 1/-4 3/-2 4/-1\n", /* relative texture indices too */
    };
    static const int32_t expect[6] = {0, 1, 2, 0, 2, 3};
    for (size_t i = 0; i < sizeof faces / sizeof faces[0]; ++i) {
        char text[512];
        snprintf(text, sizeof text, "%svt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n%s", square_v, faces[i]);
        cf_mesh_data *d = read_text(ctx, text);
        if (!d) continue;
        CHECK(d->vertex_count == 4);
        CHECK(d->face_count == 2);
        CHECK(memcmp(d->triangles, expect, sizeof expect) == 0);
        bool with_vt = strchr(faces[i], '/') && !strstr(faces[i], "//");
        CHECK(d->uv_count == (with_vt ? 4 : 0));
        CHECK((d->uv_triangles != NULL) == with_vt);
        if (with_vt && d->uv_triangles) {
            CHECK(memcmp(d->uv_triangles, expect, sizeof expect) == 0);
            CHECK(d->uv[2 * 2] == 1.0 && d->uv[2 * 2 + 1] == 1.0);
        }
        cf_mesh_data_destroy(&d);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_polygons_and_ignored_lines(void)
{
    cf_context *ctx = cft_context();
    iot_log log = {0, ""};
    cf_context_set_log(ctx, iot_log_fn, &log, CF_LOG_WARNING);
    /* \r\n endings, comments, o/g/s/usemtl/mtllib, two unknown keywords
     * (one warning), a quad and a pentagon, no newline at the end. */
    const char *text = "# comment\r\nmtllib a.mtl\r\no thing\r\ng group\r\ns off\r\nusemtl red\r\n"
                       "v 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0 1 0\r\nv -1 0.5 0\r\n  \r\n"
                       "curv 1 2\r\nl 1 2\r\n"
                       "f 1 2 3 4\r\nf 1 4 5 2 3\r\nf 2 3 4";
    cf_mesh_data *d = read_text(ctx, text);
    if (d) {
        CHECK(d->vertex_count == 5);
        CHECK(d->face_count == 2 + 3 + 1);
        CHECK(d->polygon_count == 2);
        /* fan (v0, v_i, v_i+1) */
        static const int32_t expect[18] = {0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 1, 0, 1, 2, 1, 2, 3};
        CHECK(memcmp(d->triangles, expect, sizeof expect) == 0);
        /* the materials are kept (session 29): every triangle is 'red' */
        CHECK(d->material_library_count == 1 && strcmp(d->material_libraries[0], "a.mtl") == 0);
        CHECK(d->material_count == 1 && strcmp(d->material_names[0], "red") == 0);
        for (int32_t f = 0; d->face_materials && f < d->face_count; ++f) CHECK(d->face_materials[f] == 0);
        CHECK(d->face_materials != NULL);
    }
    /* one warning for the unknown keywords, one for the polygons */
    CHECK(log.warnings == 2);
    CHECK(strstr(log.last, "2 polygons") != NULL);
    cf_mesh_data_destroy(&d);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_partial_texture_is_dropped(void)
{
    cf_context *ctx = cft_context();
    iot_log log = {0, ""};
    cf_context_set_log(ctx, iot_log_fn, &log, CF_LOG_WARNING);
    cf_mesh_data *d = read_text(ctx, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\nf 1 3 4\n");
    if (d) {
        CHECK(d->face_count == 2);
        CHECK(d->uv_count == 0 && d->uv == NULL && d->uv_triangles == NULL);
    }
    CHECK(log.warnings == 1);
    cf_mesh_data_destroy(&d);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_errors(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    char text[512];
#define SQ(rest) (snprintf(text, sizeof text, "%s%s", square_v, rest), text)
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, SQ("f 1 2 0\n"), CF_ERR_INDEX_RANGE, "t: line 5: vertex index 0");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, SQ("f 1 2 5\n"), CF_ERR_INDEX_RANGE, "line 5: vertex index 5 out of range");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, SQ("f 1 2 -5\n"), CF_ERR_INDEX_RANGE, "line 5");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", CF_ERR_INDEX_RANGE, "line 1");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, SQ("vt 0 0\nf 1/1 2/2 3/1\n"), CF_ERR_INDEX_RANGE, "line 6: texture index 2");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, SQ("f 1 2\nf 1 2 3\n"), CF_ERR_PARSE, "line 5: face has 2 vertices");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, SQ("f 1 2 3\nf 1 2"), CF_ERR_TRUNCATED,
               "line 6: face has 2 vertices (file ends inside a face line: truncated?)");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, SQ("f 1 2\n"), CF_ERR_PARSE, "face has 2 vertices"); /* newline: not truncated */
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, "v 0 0 0\nv 1 0", CF_ERR_TRUNCATED, "line 2: vertex 1 has 2 coordinates");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, "v 0 0 0\nv 1 0\nv 1 1 1\n", CF_ERR_PARSE, "line 2: vertex 1 has 2 coordinates");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, "v 0 0 0\nv 1 0x 0\n", CF_ERR_PARSE, "line 2: vertex 1: bad number '0x'");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, "v 0 0 0\nv 1 1e999 0\n", CF_ERR_NONFINITE, "line 2: vertex 1 has a non-finite");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, "v 0 0 0\nv inf 1 0\n", CF_ERR_NONFINITE, "vertex 1 has a non-finite coordinate");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, "vt nan 0\n", CF_ERR_NONFINITE, "line 1: texture coordinate 0");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, "vt\n", CF_ERR_PARSE, "texture coordinate 0 has no values");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, SQ("f 1/ 2/ 3/\n"), CF_ERR_PARSE, "bad face index '1/'");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, SQ("f 1/1/ 2 3\n"), CF_ERR_PARSE, "bad face index");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, SQ("f a 2 3\n"), CF_ERR_PARSE, "bad face index 'a'");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, SQ("vt 0 0\nf 1/1 2 3\n"), CF_ERR_PARSE, "mixes corners");
    /* a huge index saturates and is reported as out of range, not wrapped */
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, SQ("f 1 2 99999999999999999999999\n"), CF_ERR_INDEX_RANGE, "line 5");
#undef SQ
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_empty_input(void)
{
    cf_context *ctx = cft_context();
    cf_mesh_data *d = NULL;
    CHECK_OK(ctx, cf_read_mesh_memory(ctx, "", 0, CF_FORMAT_OBJ, NULL, &d));
    if (d) CHECK(d->vertex_count == 0 && d->face_count == 0 && d->positions == NULL);
    cf_mesh_data_destroy(&d);
    CHECK_STATUS(cf_read_mesh_memory(ctx, "v 0 0 0\n", 8, CF_FORMAT_AUTO, NULL, &d), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_read_mesh_memory(ctx, NULL, 3, CF_FORMAT_OBJ, NULL, &d), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_read_mesh_file(ctx, "x.stl", &d), CF_ERR_UNSUPPORTED);
    CHECK_STATUS(cf_read_mesh_file(ctx, "/nonexistent_dir/mesh.obj", &d), CF_ERR_IO);
    CHECK(strcmp(cf_context_message(ctx), "/nonexistent_dir/mesh.obj: cannot open: No such file or directory") == 0);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_round_trip_with_uv_and_csv(void)
{
    cf_context *ctx = cft_context();
    for (int uv_mode = 0; uv_mode < 3; ++uv_mode) {
        cf_mesh *m = iot_octahedron_mesh(ctx, uv_mode);
        double moved[3 * IOT_NV], vf[IOT_NV], ff[IOT_NF];
        for (int i = 0; i < 3 * IOT_NV; ++i) moved[i] = cf_mesh_positions(m)[i] * 1.7 + 1e-17 * i;
        for (int i = 0; i < IOT_NV; ++i) vf[i] = 1.0 / (i + 3.0);
        for (int i = 0; i < IOT_NF; ++i) ff[i] = -0.1 * i;
        cf_field fields[3] = {{"curv", CF_FIELD_VERTEX, vf}, {"q", CF_FIELD_FACE, ff}, {"w", CF_FIELD_VERTEX, vf}};
        const char *path = cft_temp_path(".OBJ"); /* extension case does not matter */
        char stem[4096];
        snprintf(stem, sizeof stem, "%.*s", (int)(strlen(path) - 4), path);
        CHECK_OK(ctx, cf_write_mesh_file(ctx, path, m, moved, fields, 3));
        cf_mesh_data *d = NULL;
        CHECK_OK(ctx, cf_read_mesh_file(ctx, path, &d));
        if (d) {
            CHECK(d->vertex_count == IOT_NV && d->face_count == IOT_NF);
            CHECK(memcmp(d->positions, moved, sizeof moved) == 0); /* bit-exact */
            CHECK(memcmp(d->triangles, cf_mesh_triangles(m), sizeof(int32_t) * 3 * IOT_NF) == 0);
            CHECK(d->uv_count == cf_mesh_uv_count(m));
            if (uv_mode && d->uv && d->uv_triangles) {
                CHECK(memcmp(d->uv, cf_mesh_uv(m), sizeof(double) * 2 * (size_t)d->uv_count) == 0);
                CHECK(memcmp(d->uv_triangles, cf_mesh_uv_triangles(m), sizeof(int32_t) * 3 * IOT_NF) == 0);
            }
            cf_mesh_data_destroy(&d);
        }
        /* side CSV: "<stem>.vertex.csv" with both vertex fields, "<stem>.face.csv" */
        char csv_path[4200];
        snprintf(csv_path, sizeof csv_path, "%s.vertex.csv", stem);
        char *csv = iot_read(csv_path, NULL);
        CHECK(csv != NULL);
        if (csv) {
            CHECK(strncmp(csv, "index,curv,w\n0,0.33333333333333331,0.33333333333333331\n1,0.25,0.25\n", 66) == 0);
            double back = 0.0;
            CHECK(sscanf(strstr(csv, "\n2,") + 3, "%lf", &back) == 1 && back == vf[2]);
            free(csv);
        }
        remove(csv_path);
        snprintf(csv_path, sizeof csv_path, "%s.face.csv", stem);
        csv = iot_read(csv_path, NULL);
        CHECK(csv != NULL && strncmp(csv, "index,q\n0,-0\n1,-0.10000000000000001\n", 36) == 0);
        free(csv);
        remove(csv_path);
        remove(path);
        cf_mesh_destroy(&m);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_load_mesh(void)
{
    cf_context *ctx = cft_context();
    const char *path = cft_temp_path(".obj");
    iot_write_text(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n");
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_load_mesh(ctx, path, &m));
    if (m) CHECK(cf_mesh_vertex_count(m) == 4 && cf_mesh_face_count(m) == 4 && cf_mesh_genus(m) == 0);
    cf_mesh_destroy(&m);
    /* a validation failure keeps the mesh core's status, prefixed by the path */
    iot_write_text(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 1\n");
    CHECK_STATUS(cf_load_mesh(ctx, path, &m), CF_ERR_REPEATED_INDEX);
    CHECK(strncmp(cf_context_message(ctx), path, strlen(path)) == 0);
    CHECK(m == NULL);
    remove(path);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_allocation_failures(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    const char *text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n"
                       "f 1/1 2/2 3/3 4/1\nf 1/1 3/3 4/2\n";
    int failures = iot_nomem_sweep(ctx, text, strlen(text), CF_FORMAT_OBJ);
    CHECK(failures >= 5); /* copy, positions, uv, triangles, uv triangles, result... */
    /* the file path too: reading the file, parsing, building the mesh */
    const char *path = cft_temp_path(".obj");
    iot_write_text(path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n");
    int64_t n = 1;
    for (; n < 10000; ++n) {
        cf_mesh *m = NULL;
        cf_context_fail_allocation(ctx, n, 0);
        cf_status st = cf_load_mesh(ctx, path, &m);
        cf_context_fail_allocation(ctx, 0, 0);
        cf_mesh_destroy(&m);
        CHECK(cf_context_bytes_in_use(ctx) == 0);
        if (st == CF_OK) break;
        CHECK_STATUS(st, CF_ERR_NOMEM);
        if (st != CF_ERR_NOMEM) break;
    }
    CHECK(n > 5 && n < 10000);
    remove(path);
    cf_context_destroy(&ctx);
}

/* mtllib and usemtl are kept (session 29: they were dropped, so a textured
 * OBJ's output lost its material): libraries in file order, names in order
 * of first use, -1 for the faces before the first usemtl, each triangle of
 * a fan-triangulated polygon with its polygon's material; written back as
 * OBJ with a usemtl before each run; a bad list is refused. */
static void test_materials(void)
{
    cf_context *ctx = cft_context();
    const char *text = "mtllib  lib one.mtl \nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\n"
                       "f 1 2 5\nusemtl skin\nf 1 4 3 2\nusemtl eye\nf 2 3 5\nusemtl skin\nf 3 4 5\nmtllib two.mtl\n"
                       "f 4 1 5\n";
    cf_mesh_data *d = read_text(ctx, text);
    static const int32_t expect[6] = {-1, 0, 0, 1, 0, 0};
    if (d) {
        CHECK(d->face_count == 6);
        CHECK(d->material_library_count == 2 && strcmp(d->material_libraries[0], "lib one.mtl") == 0 &&
              strcmp(d->material_libraries[1], "two.mtl") == 0);
        CHECK(d->material_count == 2 && strcmp(d->material_names[0], "skin") == 0 &&
              strcmp(d->material_names[1], "eye") == 0);
        CHECK(d->face_materials && memcmp(d->face_materials, expect, sizeof expect) == 0);
        cf_mesh_desc desc;
        cf_mesh_data_desc(d, &desc);
        cf_mesh *m = NULL;
        CHECK_OK(ctx, cf_mesh_create(ctx, &desc, &m));
        cf_write_options o;
        cf_write_options_default(&o);
        o.material_library_count = d->material_library_count;
        o.material_libraries = (const char *const *)d->material_libraries;
        o.material_count = d->material_count;
        o.material_names = (const char *const *)d->material_names;
        o.face_materials = d->face_materials;
        const char *path = cft_temp_path(".obj");
        if (m) CHECK_OK(ctx, cf_write_mesh_file_ex(ctx, path, m, NULL, NULL, 0, &o));
        size_t size = 0;
        char *written = iot_read(path, &size);
        CHECK(written && strstr(written, "mtllib lib one.mtl\nmtllib two.mtl\n"));
        CHECK(written && strstr(written, "f 1 2 5\nusemtl skin\nf 1 4 3\nf 1 3 2\nusemtl eye\nf 2 3 5\nusemtl skin\n"
                                         "f 3 4 5\nf 4 1 5\n"));
        free(written);
        cf_mesh_data *back = NULL;
        CHECK_OK(ctx, cf_read_mesh_file(ctx, path, &back));
        CHECK(back && back->face_materials && memcmp(back->face_materials, expect, sizeof expect) == 0);
        cf_mesh_data_destroy(&back);
        /* a face material out of range, a name with a line break: refused */
        int32_t bad[6] = {0, 0, 2, 0, 0, 0};
        o.face_materials = bad;
        if (m) CHECK_STATUS(cf_write_mesh_file_ex(ctx, path, m, NULL, NULL, 0, &o), CF_ERR_INVALID_ARG);
        CHECK(strstr(cf_context_message(ctx), "face 2: material 2 out of range (2 materials)") != NULL);
        const char *broken[2] = {"skin", "e\nye"};
        o.face_materials = d->face_materials;
        o.material_names = broken;
        if (m) CHECK_STATUS(cf_write_mesh_file_ex(ctx, path, m, NULL, NULL, 0, &o), CF_ERR_INVALID_ARG);
        remove(path);
        cf_mesh_destroy(&m);
    }
    cf_mesh_data_destroy(&d);
    /* usemtl without a name */
    cf_mesh_data *e = NULL;
    const char *bad_text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl\nf 1 2 3\n";
    CHECK_STATUS(cf_read_mesh_memory(ctx, bad_text, strlen(bad_text), CF_FORMAT_OBJ, "m.obj", &e), CF_ERR_PARSE);
    CHECK(strstr(cf_context_message(ctx), "m.obj: line 4: usemtl without a material name") != NULL);
    /* allocation failures while reading materials: NOMEM, nothing leaked */
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    int failures = iot_nomem_sweep(ctx, text, strlen(text), CF_FORMAT_OBJ);
    CHECK(failures >= 8);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* `v x y z r g b` (session 30; the colours were ignored without a word):
 * kept as the vertex properties red green blue in PLY's 0..255 when every
 * vertex has one (0..1 values scaled and rounded, 0..255 values as
 * written); dropped with one warning when only some vertices have one. The
 * writer puts vertex fields red green blue in [0, 255] back on the v lines
 * (as 0..1) and the other fields in the CSV file. */
static void test_vertex_colours(void)
{
    cf_context *ctx = cft_context();
    iot_log log = {0, ""};
    cf_context_set_log(ctx, iot_log_fn, &log, CF_LOG_WARNING);
    const char *faces = "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";
    char text[512];
    snprintf(text, sizeof text, "v 0 0 0 1 0 0\nv 1 0 0 0.5 0.25 0\nv 0 1 0 0 1 0.003\nv 0 0 1 0 0 1\n%s", faces);
    cf_mesh_data *d = read_text(ctx, text);
    static const double red[4] = {255, 128, 0, 0}, green[4] = {0, 64, 255, 0}, blue[4] = {0, 0, 1, 255};
    const cf_mesh_property *r = d ? cf_mesh_data_vertex_property(d, "red") : NULL;
    const cf_mesh_property *g = d ? cf_mesh_data_vertex_property(d, "green") : NULL;
    const cf_mesh_property *b = d ? cf_mesh_data_vertex_property(d, "blue") : NULL;
    CHECK(d && d->vertex_property_count == 3 && r && g && b);
    CHECK(r && memcmp(r->values, red, sizeof red) == 0);
    CHECK(g && memcmp(g->values, green, sizeof green) == 0);
    CHECK(b && memcmp(b->values, blue, sizeof blue) == 0);
    CHECK(log.warnings == 0);
    cf_mesh_data_destroy(&d);
    /* a file that writes 0..255 keeps its values */
    snprintf(text, sizeof text, "v 0 0 0 255 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 17\nv 0 0 1 1 1 1\n%s", faces);
    d = read_text(ctx, text);
    r = d ? cf_mesh_data_vertex_property(d, "red") : NULL;
    b = d ? cf_mesh_data_vertex_property(d, "blue") : NULL;
    CHECK(r && r->values[0] == 255 && r->values[3] == 1 && b && b->values[2] == 17);
    cf_mesh_data_destroy(&d);
    /* only some vertices: no colours, one warning; w is not a colour */
    static const char *const partial[] = {
        "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0 1 0\nv 0 0 1 0 0 1\n",
        "v 0 0 0\nv 1 0 0 1 0 0\nv 0 1 0 0 1 0\nv 0 0 1 0 0 1\n",
        "v 0 0 0 1 0 0\nv 1 0 0 1 0 0\nv 0 1 0 0 1 0\nv 0 0 1 nan 0 1\n",
    };
    for (size_t i = 0; i < sizeof partial / sizeof partial[0]; ++i) {
        log.warnings = 0;
        snprintf(text, sizeof text, "%s%s", partial[i], faces);
        d = read_text(ctx, text);
        CHECK(d && d->vertex_property_count == 0);
        CHECK(log.warnings == 1 && strstr(log.last, "3 of 4 vertices give a colour (v x y z r g b)"));
        cf_mesh_data_destroy(&d);
    }
    log.warnings = 0;
    snprintf(text, sizeof text, "v 0 0 0 1\nv 1 0 0 1\nv 0 1 0 1\nv 0 0 1 1\n%s", faces);
    d = read_text(ctx, text);
    CHECK(d && d->vertex_property_count == 0 && log.warnings == 0);
    cf_mesh_data_destroy(&d);

    /* writer: colours on the v lines, alpha and others in the CSV; read back */
    cf_mesh *m = iot_octahedron_mesh(ctx, 0);
    double rr[IOT_NV], gg[IOT_NV], bb[IOT_NV], aa[IOT_NV];
    for (int i = 0; i < IOT_NV; ++i) rr[i] = 51.0 * i, gg[i] = 255 - 40 * i, bb[i] = i == 2 ? 255 : 3, aa[i] = 200;
    cf_field fields[4] = {{"blue", CF_FIELD_VERTEX, bb}, {"alpha", CF_FIELD_VERTEX, aa},
                          {"red", CF_FIELD_VERTEX, rr}, {"green", CF_FIELD_VERTEX, gg}};
    const char *path = cft_temp_path(".obj");
    char csv_path[4200];
    snprintf(csv_path, sizeof csv_path, "%.*s.vertex.csv", (int)(strlen(path) - 4), path);
    CHECK_OK(ctx, cf_write_mesh_file(ctx, path, m, NULL, fields, 4));
    char *obj = iot_read(path, NULL), *csv = iot_read(csv_path, NULL);
    CHECK(obj && strstr(obj, " 0 1 0.011764705882352941\nv ")); /* vertex 0: r g b = 0, 1, 3/255 */
    CHECK(csv && strncmp(csv, "index,alpha\n0,200\n", 18) == 0);
    free(obj);
    free(csv);
    CHECK_OK(ctx, cf_read_mesh_file(ctx, path, &d));
    r = d ? cf_mesh_data_vertex_property(d, "red") : NULL;
    g = d ? cf_mesh_data_vertex_property(d, "green") : NULL;
    b = d ? cf_mesh_data_vertex_property(d, "blue") : NULL;
    CHECK(r && memcmp(r->values, rr, sizeof rr) == 0 && g && memcmp(g->values, gg, sizeof gg) == 0);
    CHECK(b && memcmp(b->values, bb, sizeof bb) == 0);
    cf_mesh_data_destroy(&d);
    /* a "red" outside [0, 255] is no colour: every field to the CSV, plain v lines */
    rr[1] = 300;
    CHECK_OK(ctx, cf_write_mesh_file(ctx, path, m, NULL, fields, 4));
    obj = iot_read(path, NULL);
    csv = iot_read(csv_path, NULL);
    CHECK(obj && !strstr(obj, " 0 1 0.011764705882352941\n"));
    CHECK(csv && strncmp(csv, "index,blue,alpha,red,green\n", 27) == 0);
    free(obj);
    free(csv);
    remove(csv_path);
    remove(path);
    cf_mesh_destroy(&m);
    /* allocation failures on a coloured file */
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    snprintf(text, sizeof text, "v 0 0 0 1 0 0\nv 1 0 0 0.5 0.25 0\nv 0 1 0 0 1 0.003\nv 0 0 1 0 0 1\n%s", faces);
    CHECK(iot_nomem_sweep(ctx, text, strlen(text), CF_FORMAT_OBJ) >= 5);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_face_syntaxes);
    CFT_RUN(test_polygons_and_ignored_lines);
    CFT_RUN(test_partial_texture_is_dropped);
    CFT_RUN(test_errors);
    CFT_RUN(test_empty_input);
    CFT_RUN(test_round_trip_with_uv_and_csv);
    CFT_RUN(test_load_mesh);
    CFT_RUN(test_allocation_failures);
    CFT_RUN(test_materials);
    CFT_RUN(test_vertex_colours);
    return cft_finish();
}
