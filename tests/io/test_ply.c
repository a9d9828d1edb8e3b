/* PLY reader and writer: ascii / binary little / big endian round trips
 * (bit-exact positions, fields and uv), every scalar type, extra properties
 * kept by name, skipped elements and lists, polygons, error paths with
 * their statuses, absurd header counts, allocation failures. */
#define _POSIX_C_SOURCE 200809L
#include "io_test_util.h"

#include <stdint.h>

static void test_round_trip_all_encodings(void)
{
    cf_context *ctx = cft_context();
    static const cf_ply_encoding encs[3] = {CF_PLY_BINARY_LITTLE_ENDIAN, CF_PLY_BINARY_BIG_ENDIAN, CF_PLY_ASCII};
    for (int uv_mode = 0; uv_mode < 3; ++uv_mode) {
        cf_mesh *m = iot_octahedron_mesh(ctx, uv_mode);
        double moved[3 * IOT_NV], vf[IOT_NV], ff[IOT_NF], ff2[IOT_NF];
        for (int i = 0; i < 3 * IOT_NV; ++i) moved[i] = cf_mesh_positions(m)[i] * -2.3 + 1e-300;
        moved[4] = 4.9e-324; /* the smallest subnormal survives too */
        for (int i = 0; i < IOT_NV; ++i) vf[i] = 1.0 / (i + 3.0);
        for (int i = 0; i < IOT_NF; ++i) {
            ff[i] = 0.1 * i - 1e10;
            ff2[i] = i;
        }
        cf_field fields[3] = {{"quality", CF_FIELD_FACE, ff}, {"nx", CF_FIELD_VERTEX, vf}, {"label", CF_FIELD_FACE, ff2}};
        for (int e = 0; e < 3; ++e) {
            cf_write_options o;
            cf_write_options_default(&o);
            o.ply_encoding = encs[e];
            const char *path = cft_temp_path(".ply");
            CHECK_OK(ctx, cf_write_mesh_file_ex(ctx, path, m, moved, fields, 3, &o));
            cf_mesh_data *d = NULL;
            CHECK_OK(ctx, cf_read_mesh_file(ctx, path, &d));
            remove(path);
            if (!d) continue;
            CHECK(d->vertex_count == IOT_NV && d->face_count == IOT_NF);
            CHECK(memcmp(d->positions, moved, sizeof moved) == 0);
            CHECK(memcmp(d->triangles, cf_mesh_triangles(m), sizeof(int32_t) * 3 * IOT_NF) == 0);
            CHECK(d->vertex_property_count == 1 && d->face_property_count == 2);
            const cf_mesh_property *p = cf_mesh_data_vertex_property(d, "nx");
            CHECK(p && memcmp(p->values, vf, sizeof vf) == 0);
            p = cf_mesh_data_face_property(d, "quality");
            CHECK(p && memcmp(p->values, ff, sizeof ff) == 0);
            p = cf_mesh_data_face_property(d, "label");
            CHECK(p && memcmp(p->values, ff2, sizeof ff2) == 0);
            CHECK(cf_mesh_data_face_property(d, "nx") == NULL);
            if (uv_mode == 0) CHECK(d->uv_count == 0 && !d->uv);
            if (uv_mode == 1) {
                /* per-vertex uv is written as u,v properties and read back per vertex */
                CHECK(d->uv_count == IOT_NV && d->uv_triangles == NULL);
                if (d->uv) CHECK(memcmp(d->uv, cf_mesh_uv(m), sizeof(double) * 2 * IOT_NV) == 0);
            }
            if (uv_mode == 2) {
                /* per-corner uv as a texcoord list: same uv at every corner */
                CHECK(d->uv_count == 3 * IOT_NF && d->uv_triangles != NULL);
                if (d->uv && d->uv_triangles)
                    for (int c = 0; c < 3 * IOT_NF; ++c) {
                        const double *a = d->uv + 2 * d->uv_triangles[c];
                        const double *b = cf_mesh_uv(m) + 2 * cf_mesh_uv_triangles(m)[c];
                        CHECK(a[0] == b[0] && a[1] == b[1]);
                    }
            }
            /* and it builds the same mesh */
            cf_mesh_desc desc;
            CHECK_OK(ctx, cf_mesh_data_desc(d, &desc));
            cf_mesh *m2 = NULL;
            CHECK_OK(ctx, cf_mesh_create(ctx, &desc, &m2));
            if (m2) CHECK(cf_mesh_uv_count(m2) == cf_mesh_uv_count(m));
            cf_mesh_destroy(&m2);
            cf_mesh_data_destroy(&d);
        }
        cf_mesh_destroy(&m);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static const char *const ascii_ply =
    "ply\r\n"
    "format ascii 1.0\r\n"
    "comment made by hand\r\n"
    "obj_info anything\r\n"
    "element vertex 5\r\n"
    "property float x\r\n"
    "property float y\r\n"
    "property double z\r\n"
    "property uchar red\r\n"
    "property float s\r\n"
    "property float t\r\n"
    "property list uchar int ignored_list\r\n"
    "property float quality\r\n"
    "element edge 2\r\n"
    "property int vertex1\r\n"
    "property list uchar int more\r\n"
    "element face 2\r\n"
    "property uint flags\r\n"
    "property list uint8 uint32 vertex_index\r\n"
    "property double area\r\n"
    "end_header\r\n"
    "0 0 0 255 0 0 2 7 7 0.5\r\n"
    "1 0 0 1 1 0 0 -0.25\n"
    "1 1 0 2 1 1 1 9 1e-3\n"
    "0 1 0 3 0 1 0 1\n"
    "-1 0.5 0 4 0.5 0.5 0 2\n"
    "0 3 1 2 3\n"
    "1 0 \n"
    "7 4 0 1 2 3 0.75\n"
    "8 3 0 3 4 -1\n";

static void test_ascii_properties_and_skipping(void)
{
    cf_context *ctx = cft_context();
    cf_mesh_data *d = NULL;
    CHECK_OK(ctx, cf_read_mesh_memory(ctx, ascii_ply, strlen(ascii_ply), CF_FORMAT_PLY, "a.ply", &d));
    if (d) {
        CHECK(d->vertex_count == 5);
        CHECK(d->face_count == 3);
        CHECK(d->polygon_count == 1);
        static const int32_t tri[9] = {0, 1, 2, 0, 2, 3, 0, 3, 4};
        CHECK(memcmp(d->triangles, tri, sizeof tri) == 0);
        CHECK(d->positions[3 * 4] == -1.0 && d->positions[3 * 4 + 1] == 0.5);
        /* s,t become per-vertex uv; red and quality stay as properties */
        CHECK(d->uv_count == 5 && d->uv_triangles == NULL);
        if (d->uv) CHECK(d->uv[2 * 2] == 1.0 && d->uv[2 * 4 + 1] == 0.5);
        CHECK(d->vertex_property_count == 2);
        const cf_mesh_property *red = cf_mesh_data_vertex_property(d, "red");
        const cf_mesh_property *q = cf_mesh_data_vertex_property(d, "quality");
        CHECK(red && red->values[0] == 255.0 && red->values[4] == 4.0);
        CHECK(q && q->values[1] == -0.25 && q->values[2] == 1e-3);
        /* the quad's area and flags are repeated on both of its triangles */
        const cf_mesh_property *area = cf_mesh_data_face_property(d, "area");
        const cf_mesh_property *flags = cf_mesh_data_face_property(d, "flags");
        CHECK(area && area->values[0] == 0.75 && area->values[1] == 0.75 && area->values[2] == -1.0);
        CHECK(flags && flags->values[1] == 7.0 && flags->values[2] == 8.0);
    }
    cf_mesh_data_destroy(&d);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* ---- binary by hand ------------------------------------------------------------ */

typedef struct bytes {
    unsigned char b[4096];
    size_t n;
    int big;
} bytes;

static void put(bytes *w, uint64_t v, size_t size)
{
    for (size_t i = 0; i < size; ++i) w->b[w->n + (w->big ? size - 1 - i : i)] = (unsigned char)(v >> (8 * i));
    w->n += size;
}
static void put_f32(bytes *w, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put(w, u, 4);
}
static void put_f64(bytes *w, double f)
{
    uint64_t u;
    memcpy(&u, &f, 8);
    put(w, u, 8);
}
static void put_text(bytes *w, const char *s)
{
    memcpy(w->b + w->n, s, strlen(s));
    w->n += strlen(s);
}

/* A binary PLY using every scalar type; returns its size. */
static void make_binary(bytes *w, int big)
{
    memset(w, 0, sizeof *w);
    w->big = big;
    put_text(w, "ply\n");
    put_text(w, big ? "format binary_big_endian 1.0\n" : "format binary_little_endian 1.0\n");
    put_text(w, "element vertex 4\nproperty float32 x\nproperty float y\nproperty double z\n"
                "property char c\nproperty short s16\nproperty ushort u16\nproperty int i32\n"
                "property list uchar float normals\nproperty uint u32\nproperty int8 i8\n"
                "element material 2\nproperty list int uint16 junk\nproperty double shine\n"
                "element face 2\nproperty list ushort int16 vertex_indices\nproperty float64 q\n"
                "property list uint int other\n"
                "end_header\n");
    static const float xyz[4][2] = {{0.5f, -1.25f}, {3.0f, 0.125f}, {-2.0f, 8.0f}, {1.0f, 1.0f}};
    for (int v = 0; v < 4; ++v) {
        put_f32(w, xyz[v][0]);
        put_f32(w, xyz[v][1]);
        put_f64(w, 0.1 * v);
        put(w, (uint64_t)(int64_t)(-100 + v), 1);       /* char */
        put(w, (uint64_t)(int64_t)(-30000 + v), 2);     /* short */
        put(w, (uint64_t)(65535 - v), 2);               /* ushort */
        put(w, (uint64_t)(int64_t)(-2000000000 + v), 4); /* int */
        put(w, 2, 1);                                   /* list of 2 floats */
        put_f32(w, 1.0f);
        put_f32(w, 2.0f);
        put(w, 4000000000u + (uint64_t)v, 4); /* uint */
        put(w, (uint64_t)(int64_t)(-1 - v), 1); /* int8 */
    }
    for (int k = 0; k < 2; ++k) { /* material: list int count, uint16 items; double */
        put(w, 3, 4);
        put(w, 1, 2);
        put(w, 2, 2);
        put(w, 3, 2);
        put_f64(w, 0.5);
    }
    put(w, 3, 2); /* face 0 */
    put(w, 0, 2);
    put(w, 1, 2);
    put(w, 2, 2);
    put_f64(w, -7.5);
    put(w, 0, 4);
    put(w, 3, 2); /* face 1 */
    put(w, 0, 2);
    put(w, 2, 2);
    put(w, 3, 2);
    put_f64(w, 1e300);
    put(w, 1, 4);
    put(w, 42, 4);
}

static void test_binary_types(void)
{
    cf_context *ctx = cft_context();
    for (int big = 0; big < 2; ++big) {
        bytes w;
        make_binary(&w, big);
        cf_mesh_data *d = NULL;
        CHECK_OK(ctx, cf_read_mesh_memory(ctx, w.b, w.n, CF_FORMAT_PLY, "b.ply", &d));
        if (!d) continue;
        CHECK(d->vertex_count == 4 && d->face_count == 2);
        CHECK(d->positions[0] == 0.5 && d->positions[1] == -1.25 && d->positions[2] == 0.0);
        CHECK(d->positions[3 * 2] == -2.0 && d->positions[3 * 2 + 2] == 0.1 * 2);
        static const int32_t tri[6] = {0, 1, 2, 0, 2, 3};
        CHECK(memcmp(d->triangles, tri, sizeof tri) == 0);
        const cf_mesh_property *p;
        CHECK((p = cf_mesh_data_vertex_property(d, "c")) && p->values[3] == -97.0);
        CHECK((p = cf_mesh_data_vertex_property(d, "s16")) && p->values[1] == -29999.0);
        CHECK((p = cf_mesh_data_vertex_property(d, "u16")) && p->values[0] == 65535.0);
        CHECK((p = cf_mesh_data_vertex_property(d, "i32")) && p->values[2] == -1999999998.0);
        CHECK((p = cf_mesh_data_vertex_property(d, "u32")) && p->values[3] == 4000000003.0);
        CHECK((p = cf_mesh_data_vertex_property(d, "i8")) && p->values[0] == -1.0);
        CHECK(cf_mesh_data_vertex_property(d, "normals") == NULL); /* lists are not kept */
        CHECK((p = cf_mesh_data_face_property(d, "q")) && p->values[0] == -7.5 && p->values[1] == 1e300);
        CHECK(d->vertex_property_count == 6 && d->face_property_count == 1);
        cf_mesh_data_destroy(&d);

        /* cut anywhere in the binary data: always CF_ERR_TRUNCATED, never a crash */
        size_t header = (size_t)(strstr((const char *)w.b, "end_header\n") - (const char *)w.b) + 11;
        int truncated = 0;
        cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
        for (size_t cut = header; cut < w.n; ++cut) {
            cf_status st = cf_read_mesh_memory(ctx, w.b, cut, CF_FORMAT_PLY, "b.ply", &d);
            truncated += st == CF_ERR_TRUNCATED;
            cf_mesh_data_destroy(&d);
        }
        CHECK(truncated == (int)(w.n - header));
        CHECK(strstr(cf_context_message(ctx), "b.ply: binary data ends inside face 1") != NULL);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_errors(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
#define HDR "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n" \
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
    IOT_EXPECT(ctx, CF_FORMAT_PLY, HDR "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", CF_OK, NULL);
    IOT_EXPECT(ctx, CF_FORMAT_PLY, HDR "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", CF_ERR_INDEX_RANGE,
               "t: line 13: face 0: vertex index 3 out of range [0, 3)");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, HDR "0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n", CF_ERR_INDEX_RANGE, "vertex index -1");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, HDR "0 0 0\n1 0 0\n0 1 0\n2 0 1\n", CF_ERR_PARSE, "face 0 has 2 vertices");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, HDR "0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n", CF_ERR_PARSE, "bad vertex index 1.5");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, HDR "0 0 0\n1 0 0\n0 1 0\n", CF_ERR_TRUNCATED, NULL);
    IOT_EXPECT(ctx, CF_FORMAT_PLY, HDR "0 0 0\n1 0 0\n0 1 0\n3 0 1", CF_ERR_TRUNCATED, "file ends inside face 0");
    /* data beyond the header's properties is an error (issue 15, S1: it was accepted) */
    IOT_EXPECT(ctx, CF_FORMAT_PLY, HDR "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 3 4 5 6 7 8 9", CF_ERR_PARSE,
               "t: line 13: face 0 has 11 values, its properties take 4");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, HDR "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 4 5 6 7 8 9", CF_ERR_PARSE,
               "t: line 14: data after the last element ('3')");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, HDR "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n", CF_ERR_NONFINITE,
               "line 11: vertex 1 has a non-finite coordinate");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, HDR "0 0 0\n1 0 z\n0 1 0\n3 0 1 2\n", CF_ERR_PARSE, "line 11: vertex 1: bad number 'z'");
#undef HDR
    IOT_EXPECT(ctx, CF_FORMAT_PLY, "", CF_ERR_PARSE, "empty file");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, "plx\nformat ascii 1.0\nend_header\n", CF_ERR_PARSE, "not a PLY file");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, "ply\nformat ascii 1.0\nelement vertex 1\n", CF_ERR_TRUNCATED, "inside the PLY header");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, "ply\nformat ebcdic 1.0\nend_header\n", CF_ERR_PARSE, "line 2: unknown PLY format");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, "ply\nend_header\n", CF_ERR_PARSE, "no format line");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, "ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n",
               CF_ERR_PARSE, "line 4: unknown PLY type 'quad'");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, "ply\nformat ascii 1.0\nproperty float x\nend_header\n", CF_ERR_PARSE,
               "property before any element");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, "ply\nformat ascii 1.0\nelement vertex -1\nend_header\n", CF_ERR_PARSE, "bad element");
    /* found by fuzz_ply: a 20-digit count must saturate, not overflow */
    IOT_EXPECT(ctx, CF_FORMAT_PLY, "ply\nformat ascii 1.0\nelement vertex 44444444444444444444\nproperty float x\nend_header\n",
               CF_ERR_TRUNCATED, "header declares");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, "ply\nformat ascii 1.0\nbogus line\nend_header\n", CF_ERR_PARSE, "unknown header line");
    IOT_EXPECT(ctx, CF_FORMAT_PLY,
               "ply\nformat ascii 1.0\nelement face 1\nproperty list float int vertex_indices\nend_header\n3 0 1 2\n",
               CF_ERR_PARSE, "list count type");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n",
               CF_ERR_PARSE, "lacks scalar x, y and z");
    IOT_EXPECT(ctx, CF_FORMAT_PLY,
               "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int corners\nend_header\n3 0 1 2\n",
               CF_ERR_PARSE, "no vertex_indices");
    /* absurd counts are refused before any allocation for them */
    int64_t before = cf_context_allocation_count(ctx);
    IOT_EXPECT(ctx, CF_FORMAT_PLY,
               "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\nproperty double x\n"
               "property double y\nproperty double z\nend_header\n0123456789",
               CF_ERR_TRUNCATED, "header declares 2000000000 'vertex' elements but only 10 bytes");
    CHECK(cf_context_allocation_count(ctx) - before < 10);
    IOT_EXPECT(ctx, CF_FORMAT_PLY,
               "ply\nformat ascii 1.0\nelement junk 9223372036854775807\nproperty list uint uint x\nend_header\n1 2\n",
               CF_ERR_TRUNCATED, "header declares");
    IOT_EXPECT(ctx, CF_FORMAT_PLY,
               "ply\nformat binary_little_endian 1.0\nelement junk 99999999999\nend_header\n", CF_OK, NULL);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_huge_binary_list_count(void)
{
    /* a face claiming 4 billion indices in a 40-byte body */
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    bytes w;
    memset(&w, 0, sizeof w);
    put_text(&w, "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                 "property float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n");
    put_f32(&w, 0);
    put_f32(&w, 0);
    put_f32(&w, 0);
    put(&w, 0xFFFFFFFFu, 4);
    put(&w, 0, 4);
    cf_mesh_data *d = NULL;
    CHECK_STATUS(cf_read_mesh_memory(ctx, w.b, w.n, CF_FORMAT_PLY, "h.ply", &d), CF_ERR_TRUNCATED);
    CHECK(strstr(cf_context_message(ctx), "h.ply: binary data ends inside face 0") != NULL);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static void test_allocation_failures(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    CHECK(iot_nomem_sweep(ctx, ascii_ply, strlen(ascii_ply), CF_FORMAT_PLY) >= 8);
    bytes w;
    make_binary(&w, 1);
    CHECK(iot_nomem_sweep(ctx, w.b, w.n, CF_FORMAT_PLY) >= 8);
    cf_context_destroy(&ctx);
}

static void test_write_options(void)
{
    cf_context *ctx = cft_context();
    cf_mesh_format fmt = CF_FORMAT_AUTO;
    CHECK_OK(ctx, cf_mesh_format_from_path(ctx, "dir.v2/A.PLY", &fmt));
    CHECK(fmt == CF_FORMAT_PLY);
    CHECK_STATUS(cf_mesh_format_from_path(ctx, "a.ply.gz", &fmt), CF_ERR_UNSUPPORTED);
    CHECK_STATUS(cf_mesh_format_from_path(ctx, "dir.ply/noext", &fmt), CF_ERR_UNSUPPORTED);
    /* the format can be forced for any name; uv can be left out */
    cf_mesh *m = iot_octahedron_mesh(ctx, 1);
    cf_write_options o;
    cf_write_options_default(&o);
    CHECK(o.format == CF_FORMAT_AUTO && o.ply_encoding == CF_PLY_BINARY_LITTLE_ENDIAN && o.write_uv == 1);
    o.format = CF_FORMAT_PLY;
    o.write_uv = 0;
    char path[4096];
    snprintf(path, sizeof path, "%s", cft_temp_path(".bin"));
    CHECK_OK(ctx, cf_write_mesh_file_ex(ctx, path, m, NULL, NULL, 0, &o));
    size_t size = 0;
    char *content = iot_read(path, &size);
    CHECK(content && strncmp(content, "ply\nformat binary_little_endian 1.0\n", 36) == 0);
    cf_mesh_data *d = NULL;
    if (content) CHECK_OK(ctx, cf_read_mesh_memory(ctx, content, size, CF_FORMAT_PLY, path, &d));
    CHECK(d && d->vertex_count == IOT_NV && d->uv_count == 0 && d->uv == NULL);
    cf_mesh_data_destroy(&d);
    free(content);
    remove(path);
    o.ply_encoding = (cf_ply_encoding)7;
    CHECK_STATUS(cf_write_mesh_file_ex(ctx, path, m, NULL, NULL, 0, &o), CF_ERR_INVALID_ARG);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Colour channels (fields named red, green, blue or alpha whose values are
 * all whole numbers in [0, 255]) are written as uchar, as PLY viewers read
 * colours, and read back the same in every encoding; a "red" with a value
 * outside stays double (session 29: the flow now carries an input's
 * properties to its output, colours included). */
static void test_colour_channels(void)
{
    cf_context *ctx = cft_context();
    static const cf_ply_encoding encs[3] = {CF_PLY_BINARY_LITTLE_ENDIAN, CF_PLY_BINARY_BIG_ENDIAN, CF_PLY_ASCII};
    cf_mesh *m = iot_octahedron_mesh(ctx, 0);
    double red[IOT_NV], green[IOT_NV], alpha[IOT_NF], other[IOT_NV];
    for (int i = 0; i < IOT_NV; ++i) {
        red[i] = (i * 51) % 256;
        green[i] = i == 0 ? 255.0 : 0.0;
        other[i] = i == 1 ? 0.5 : 7.0; /* not whole: double */
    }
    for (int i = 0; i < IOT_NF; ++i) alpha[i] = 128 + i;
    for (int e = 0; m && e < 3; ++e) {
        cf_field fields[4] = {{"red", CF_FIELD_VERTEX, red},
                              {"green", CF_FIELD_VERTEX, green},
                              {"alpha", CF_FIELD_FACE, alpha},
                              {"blue", CF_FIELD_VERTEX, other}};
        cf_write_options o;
        cf_write_options_default(&o);
        o.ply_encoding = encs[e];
        const char *path = cft_temp_path(".ply");
        CHECK_OK(ctx, cf_write_mesh_file_ex(ctx, path, m, NULL, fields, 4, &o));
        size_t size = 0;
        char *text = iot_read(path, &size);
        CHECK(text && strstr(text, "property uchar red\nproperty uchar green\nproperty double blue\n"));
        CHECK(text && strstr(text, "property uchar alpha\n"));
        free(text);
        cf_mesh_data *d = NULL;
        CHECK_OK(ctx, cf_read_mesh_file(ctx, path, &d));
        remove(path);
        if (!d) continue;
        const cf_mesh_property *p = cf_mesh_data_vertex_property(d, "red");
        CHECK(p && memcmp(p->values, red, sizeof red) == 0);
        p = cf_mesh_data_vertex_property(d, "green");
        CHECK(p && memcmp(p->values, green, sizeof green) == 0);
        p = cf_mesh_data_vertex_property(d, "blue");
        CHECK(p && memcmp(p->values, other, sizeof other) == 0);
        p = cf_mesh_data_face_property(d, "alpha");
        CHECK(p && memcmp(p->values, alpha, sizeof alpha) == 0);
        cf_mesh_data_destroy(&d);
    }
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_round_trip_all_encodings);
    CFT_RUN(test_ascii_properties_and_skipping);
    CFT_RUN(test_binary_types);
    CFT_RUN(test_errors);
    CFT_RUN(test_huge_binary_list_count);
    CFT_RUN(test_allocation_failures);
    CFT_RUN(test_write_options);
    CFT_RUN(test_colour_channels);
    return cft_finish();
}
