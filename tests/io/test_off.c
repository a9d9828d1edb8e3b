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
        /* colours per vertex and per face are ignored */
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
    /* fields cannot be stored in OFF */
    double f[IOT_NV] = {0};
    cf_field field = {"f", CF_FIELD_VERTEX, f};
    CHECK_STATUS(cf_write_mesh_file(ctx, path, m, NULL, &field, 1), CF_ERR_UNSUPPORTED);
    remove(path);
    cf_mesh_destroy(&m);
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
    CFT_RUN(test_allocation_failures);
    return cft_finish();
}
