/* OFF reader and writer: header variants, comments, polygons, extra
 * per-vertex values, error paths, bit-exact round trip, allocation failures. */
#define _POSIX_C_SOURCE 200809L
#include "io_test_util.h"

static void test_variants(void)
{
    cf_context *ctx = cft_context();
    static const char *const texts[] = {
        "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n",
        /* comments, blank lines, counts on the header line, CRLF, no final newline */
        "# a square\r\nOFF 4 2 5\r\n\r\n0 0 0 # origin\r\n1 0 0\r\n1 1 0\r\n0 1 0\r\n3 0 1 2\r\n3 0 2 3",
        /* colours per vertex and per face (kept: test_colours_and_texture) */
        ("COFF\n4 2 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n1 1 0 0 0 255 255\n0 1 0 1 1 1 1\n"
         "3 0 1 2 1 0 0\n3 0 2 3 0.5 0.5 0.5 1\n"),
        /* normals; keyword omitted entirely */
        "NOFF\n4 2 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n3 0 2 3\n",
        "4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n",
        /* a quad is fan-triangulated into the same two triangles */
        "STCNOFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n",
    };
    static const int32_t tri[6] = {0, 1, 2, 0, 2, 3};
    for (size_t i = 0; i < sizeof texts / sizeof texts[0]; ++i) {
        cf_mesh_data *d = NULL;
        CHECK_OK(ctx, cf_read_mesh_memory(ctx, texts[i], strlen(texts[i]), CF_FORMAT_OFF, "s.off", &d));
        if (!d) continue;
        CHECK(d->vertex_count == 4 && d->face_count == 2);
        CHECK(memcmp(d->triangles, tri, sizeof tri) == 0);
        CHECK(d->positions[3 * 2] == 1.0 && d->positions[3 * 2 + 1] == 1.0 && d->positions[3 * 3 + 2] == 0.0);
        CHECK(d->polygon_count == (i == 5 ? 1 : 0));
        cf_mesh_data_destroy(&d);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_errors(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "", CF_ERR_TRUNCATED, "t: empty file");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n", CF_ERR_TRUNCATED, "file ends after the OFF header");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n3 x 0\n", CF_ERR_PARSE, "t: line 2: bad count 'x'");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n-3 1 0\n", CF_ERR_PARSE, "bad count '-3'");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "4OFF\n3 1 0\n", CF_ERR_UNSUPPORTED, "unsupported OFF variant '4OFF'");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF BINARY\n3 1 0\n", CF_ERR_UNSUPPORTED, "binary OFF");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n3000000000 1 0\n", CF_ERR_PARSE, "too large");
    /* an absurd count in a small file is refused before allocating for it */
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n100000000 1 0\n0 0 0\n", CF_ERR_TRUNCATED,
               "header declares 100000000 vertices and 1 faces but only 6 bytes follow");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 \n\n\n\n", CF_OK, NULL);
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n\n\n\n\n\n", CF_ERR_TRUNCATED,
               "t: header declares 2 faces, file holds 1");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n\n\n\n\n\n\n\n\n\n\n\n", CF_ERR_TRUNCATED,
               "t: header declares 4 vertices, file holds 3");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n", CF_ERR_PARSE,
               "t: line 4: vertex 1 has 2 coordinates, expected 3");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1", CF_ERR_TRUNCATED,
               "line 6: face 0: 2 of 3 vertex indices (file ends inside this line: truncated?)");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n", CF_ERR_PARSE, "face 0: 2 of 3");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1 2\n", CF_ERR_PARSE, "face 0 has 2 vertices");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", CF_ERR_INDEX_RANGE,
               "line 6: face 0: vertex index 3 out of range [0, 3)");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n", CF_ERR_INDEX_RANGE, "index -1");
    /* found by fuzz_off: a 20-digit index must saturate, not overflow */
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 44444444444444444444\n", CF_ERR_INDEX_RANGE,
               "out of range");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n3 1 0\n0 0 0\n1 -inf 0\n0 1 0\n3 0 1 2\n", CF_ERR_NONFINITE,
               "line 4: vertex 1 has a non-finite coordinate");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n3 1 0\n0 0 0\n1 0,5 0\n0 1 0\n3 0 1 2\n", CF_ERR_PARSE, "bad number '0,5'");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2.0\n", CF_ERR_PARSE, "bad index '2.0'");
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_round_trip(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *m = iot_octahedron_mesh(ctx, 2);
    const char *path = cft_temp_path(".Off");
    CHECK_OK(ctx, cf_write_mesh_file(ctx, path, m, NULL, NULL, 0));
    cf_mesh_data *d = NULL;
    CHECK_OK(ctx, cf_read_mesh_file(ctx, path, &d));
    if (d) {
        CHECK(d->vertex_count == IOT_NV && d->face_count == IOT_NF);
        CHECK(memcmp(d->positions, cf_mesh_positions(m), sizeof(double) * 3 * IOT_NV) == 0);
        CHECK(memcmp(d->triangles, cf_mesh_triangles(m), sizeof(int32_t) * 3 * IOT_NF) == 0);
        CHECK(d->uv == NULL); /* OFF holds positions only */
    }
    cf_mesh_data_destroy(&d);
    /* fields other than colours cannot be stored in OFF */
    double f[IOT_NV] = {0};
    cf_field field = {"f", CF_FIELD_VERTEX, f};
    CHECK_STATUS(cf_write_mesh_file(ctx, path, m, NULL, &field, 1), CF_ERR_UNSUPPORTED);
    CHECK(strstr(cf_context_message(ctx), "OFF holds only colours") && strstr(cf_context_message(ctx), "field 'f'"));
    /* colours (session 30): vertex RGB (alpha 255 written), face RGBA; whole numbers; read back the same */
    double r[IOT_NV], g[IOT_NV], b[IOT_NV], fr[IOT_NF], fg[IOT_NF], fb[IOT_NF], fa[IOT_NF];
    for (int i = 0; i < IOT_NV; ++i) r[i] = 40.0 * i, g[i] = 255.0 - i, b[i] = i == 3 ? 127.6 : 1.0;
    for (int i = 0; i < IOT_NF; ++i) fr[i] = i, fg[i] = 2 * i, fb[i] = 0, fa[i] = 250 - i;
    cf_field colours[8] = {{"red", CF_FIELD_VERTEX, r},  {"green", CF_FIELD_VERTEX, g}, {"blue", CF_FIELD_VERTEX, b},
                           {"alpha", CF_FIELD_FACE, fa}, {"red", CF_FIELD_FACE, fr},    {"green", CF_FIELD_FACE, fg},
                           {"blue", CF_FIELD_FACE, fb},  {"f", CF_FIELD_VERTEX, f}};
    uint8_t writable[8];
    CHECK(cf_off_fields_writable(colours, 8, IOT_NV, IOT_NF, writable) == 7 && writable[7] == 0 && writable[3] == 1);
    CHECK_STATUS(cf_write_mesh_file(ctx, path, m, NULL, colours, 8), CF_ERR_UNSUPPORTED);
    CHECK_OK(ctx, cf_write_mesh_file(ctx, path, m, NULL, colours, 7));
    char *text = iot_read(path, NULL);
    CHECK(text && strncmp(text, "COFF\n6 8 0\n", 11) == 0 && strstr(text, " 120 252 128 255\n")); /* vertex 3 */
    CHECK(text && strstr(text, " 7 14 0 243\n")); /* face 7 */
    free(text);
    CHECK_OK(ctx, cf_read_mesh_file(ctx, path, &d));
    const cf_mesh_property *p = d ? cf_mesh_data_vertex_property(d, "red") : NULL;
    CHECK(p && memcmp(p->values, r, sizeof r) == 0);
    p = d ? cf_mesh_data_vertex_property(d, "alpha") : NULL;
    CHECK(p && p->values[0] == 255 && p->values[5] == 255);
    p = d ? cf_mesh_data_face_property(d, "alpha") : NULL;
    CHECK(p && memcmp(p->values, fa, sizeof fa) == 0);
    CHECK(d && memcmp(d->positions, cf_mesh_positions(m), sizeof(double) * 3 * IOT_NV) == 0);
    cf_mesh_data_destroy(&d);
    /* red and green without blue, or a value past 255: no colour, refused */
    CHECK(cf_off_fields_writable(colours, 2, IOT_NV, IOT_NF, writable) == 0 && writable[0] == 0);
    r[2] = 256;
    CHECK(cf_off_fields_writable(colours, 7, IOT_NV, IOT_NF, NULL) == 4);
    CHECK_STATUS(cf_write_mesh_file(ctx, path, m, NULL, colours, 3), CF_ERR_UNSUPPORTED);
    remove(path);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static const cf_mesh_property *vprop(const cf_mesh_data *d, const char *name)
{
    return d ? cf_mesh_data_vertex_property(d, name) : NULL;
}

static const cf_mesh_property *fprop(const cf_mesh_data *d, const char *name)
{
    return d ? cf_mesh_data_face_property(d, name) : NULL;
}

static cf_mesh_data *read_off(cf_context *ctx, const char *text)
{
    cf_mesh_data *d = NULL;
    CHECK_OK(ctx, cf_read_mesh_memory(ctx, text, strlen(text), CF_FORMAT_OFF, "c.off", &d));
    return d;
}

/* Session 30 (they were dropped without a word): a C header's vertex
 * colours and an ST header's texture coordinates, in the order the spec
 * gives after x y z (normal, colour, texture); face colours when every face
 * has one of the same size. Integers are 0..255, floats 0..1 (stored as
 * 0..255, rounded). What does not fit is dropped with one warning. */
static void test_colours_and_texture(void)
{
    cf_context *ctx = cft_context();
    iot_log log = {0, ""};
    cf_context_set_log(ctx, iot_log_fn, &log, CF_LOG_WARNING);
    const char *square = "3 0 1 2\n3 0 2 3\n";
    char text[600];
    /* normals, float RGBA, texture coordinates */
    snprintf(text, sizeof text,
             "STCNOFF\n4 2 0\n0 0 0  0 0 1  1 0 0 1  0 0\n1 0 0  0 0 1  0.5 0.25 0 1  1 0\n"
             "1 1 0  0 0 1  0 1 0 0.5  1 1\n0 1 0  0 0 1  0 0 1 1  0 0.75\n%s",
             square);
    cf_mesh_data *d = read_off(ctx, text);
    static const double red[4] = {255, 128, 0, 0}, green[4] = {0, 64, 255, 0}, alpha[4] = {255, 255, 128, 255};
    static const double uv[8] = {0, 0, 1, 0, 1, 1, 0, 0.75};
    CHECK(d && d->vertex_property_count == 4 && d->face_property_count == 0);
    CHECK(vprop(d, "red") && memcmp(vprop(d, "red")->values, red, sizeof red) == 0);
    CHECK(vprop(d, "green") && memcmp(vprop(d, "green")->values, green, sizeof green) == 0);
    CHECK(vprop(d, "alpha") && memcmp(vprop(d, "alpha")->values, alpha, sizeof alpha) == 0);
    CHECK(d && d->uv_count == 4 && d->uv && !d->uv_triangles && memcmp(d->uv, uv, sizeof uv) == 0);
    cf_mesh_data_destroy(&d);
    /* integers are 0..255, also when they are only 0 and 1 (the spec); RGB */
    snprintf(text, sizeof text, "COFF\n4 2 0\n0 0 0 1 0 0\n1 0 0 0 1 0\n1 1 0 0 0 1\n0 1 0 255 255 255\n%s",
             square);
    d = read_off(ctx, text);
    CHECK(d && d->vertex_property_count == 3 && !vprop(d, "alpha"));
    CHECK(vprop(d, "red") && vprop(d, "red")->values[0] == 1 && vprop(d, "red")->values[3] == 255);
    cf_mesh_data_destroy(&d);
    /* texture coordinates alone */
    snprintf(text, sizeof text, "STOFF\n4 2 0\n0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 0.75\n%s", square);
    d = read_off(ctx, text);
    CHECK(d && d->vertex_property_count == 0 && d->uv_count == 4 && d->uv && memcmp(d->uv, uv, sizeof uv) == 0);
    cf_mesh_data_destroy(&d);
    /* face colours: a quad's two triangles share its colour; floats scaled */
    d = read_off(ctx, "OFF\n5 3 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\n"
                      "4 0 1 2 3 255 0 0 10\n3 0 4 1 0 255 0 20\n3 1 4 2 0 0 255 30\n");
    static const double fred[4] = {255, 255, 0, 0}, falpha[4] = {10, 10, 20, 30};
    CHECK(d && d->face_count == 4 && d->face_property_count == 4 && d->vertex_property_count == 0);
    CHECK(fprop(d, "red") && memcmp(fprop(d, "red")->values, fred, sizeof fred) == 0);
    CHECK(fprop(d, "alpha") && memcmp(fprop(d, "alpha")->values, falpha, sizeof falpha) == 0);
    cf_mesh_data_destroy(&d);
    d = read_off(ctx, "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2 1.0 0 0\n3 0 2 3 0 0.5 0\n");
    CHECK(fprop(d, "red") && fprop(d, "red")->values[0] == 255 && fprop(d, "green")->values[1] == 128);
    cf_mesh_data_destroy(&d);
    if (log.warnings != 1) /* the quad's fan triangulation */
        cft_fail(__FILE__, __LINE__, "%d warnings, last '%s'", log.warnings, log.last);
    /* what does not fit: one warning each, nothing kept */
    static const struct {
        const char *text, *warning;
    } unfit[] = {
        {"OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2 255 0 0\n3 0 2 3\n", "1 of 2 faces give a colour"},
        {"OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2 255 0 0\n3 0 2 3 1 1 1 1\n", "2 of 2 faces give a colour"},
        {"OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3 255 0 0\n", "1 of 2 faces give a colour"},
        {"COFF\n4 2 0\n0 0 0 255 0 0\n1 0 0 255 0\n1 1 0 0 0 255\n0 1 0 0 0 255\n3 0 1 2\n3 0 2 3\n",
         "line 4: vertex 1 has 2 values after x y z, vertex 0 has 3"},
        {"STOFF\n4 2 0\n0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 nan\n0 1 0 0 1\n3 0 1 2\n3 0 2 3\n",
         "vertex 2 has 2 values after x y z, vertex 0 has 2 (or one is not a finite number)"},
        {"COFF\n4 2 0\n0 0 0 1 2\n1 0 0 1 2\n1 1 0 0 2\n0 1 0 0 2\n3 0 1 2\n3 0 2 3\n",
         "vertex 0 has 2 values after x y z, which do not fit the header's C"},
        {"STCNOFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n", "which do not fit the header's STCN"},
    };
    for (size_t i = 0; i < sizeof unfit / sizeof unfit[0]; ++i) {
        log.warnings = 0;
        d = read_off(ctx, unfit[i].text);
        CHECK(d && d->vertex_count == 4 && d->vertex_property_count == 0 && d->face_property_count == 0);
        CHECK(d && d->uv_count == 0 && !d->uv);
        if (log.warnings != 1 || !strstr(log.last, unfit[i].warning))
            cft_fail(__FILE__, __LINE__, "case %zu: %d warnings, last '%s'", i, log.warnings, log.last);
        cf_mesh_data_destroy(&d);
    }
    /* a colour map index (one value) is no colour and no warning */
    log.warnings = 0;
    d = read_off(ctx, "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2 7\n3 0 2 3 7\n");
    CHECK(d && d->face_property_count == 0 && log.warnings == 0);
    cf_mesh_data_destroy(&d);
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    CHECK(iot_nomem_sweep(ctx, text, strlen(text), CF_FORMAT_OFF) >= 3);
    const char *both = "CNOFF\n4 2 0\n0 0 0 0 0 1 255 0 0\n1 0 0 0 0 1 0 255 0\n1 1 0 0 0 1 0 0 255\n"
                       "0 1 0 0 0 1 9 9 9\n3 0 1 2 1 2 3\n3 0 2 3 4 5 6\n";
    CHECK(iot_nomem_sweep(ctx, both, strlen(both), CF_FORMAT_OFF) >= 5);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_allocation_failures(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    const char *text = "OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n-1 0.5 0\n4 0 1 2 3\n5 0 1 2 3 4\n";
    CHECK(iot_nomem_sweep(ctx, text, strlen(text), CF_FORMAT_OFF) >= 3);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_variants);
    CFT_RUN(test_errors);
    CFT_RUN(test_round_trip);
    CFT_RUN(test_colours_and_texture);
    CFT_RUN(test_allocation_failures);
    return cft_finish();
}
