/* The mesh and polyline readers under the hostile inputs of issue 15:
 * header counts against the data in both directions (S1, M8), a UTF-8
 * byte-order mark and NUL bytes (M6), huge integers named as written (M7),
 * silently ignored input that now gets a warning (OBJ v values, a third
 * CSV column, PLY values outside their type), and lines of any length. */
#define _POSIX_C_SOURCE 200809L
#include "curvflow/curve_flow.h"
#include "io_test_util.h"

#include <stdint.h>

#define BOM "\xEF\xBB\xBF"

/* a tetrahedron's four outward faces */
#define TET_V "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
#define TET_F "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"
#define PLY_HDR(nv, nf) \
    "ply\nformat ascii 1.0\nelement vertex " #nv "\nproperty float x\nproperty float y\nproperty float z\n" \
    "element face " #nf "\nproperty list uchar int vertex_indices\nend_header\n"

static void test_header_counts_text(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    /* the file is right */
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n4 4 0\n" TET_V TET_F, CF_OK, NULL);
    IOT_EXPECT(ctx, CF_FORMAT_PLY, PLY_HDR(4, 4) TET_V TET_F, CF_OK, NULL);
    /* S1: more faces than declared was read as an open 2-face mesh */
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n4 2 0\n" TET_V TET_F, CF_ERR_PARSE,
               "t: line 9: header declares 2 faces, file holds 4");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, PLY_HDR(4, 2) TET_V TET_F, CF_ERR_PARSE,
               "t: line 16: header declares 2 faces, file holds 4");
    /* M8: more vertices than declared gave "face 0 has 0 vertices" */
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n3 4 0\n" TET_V TET_F, CF_ERR_PARSE,
               "t: line 6: header declares 3 vertices, file holds 4");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, PLY_HDR(3, 4) TET_V TET_F, CF_ERR_PARSE,
               "t: line 13: header declares 3 vertices, file holds 4");
    /* fewer vertices than declared: a face line where a vertex was expected */
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n5 4 0\n" TET_V TET_F, CF_ERR_PARSE,
               "t: line 7: header declares 5 vertices, file holds 4");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, PLY_HDR(5, 4) TET_V TET_F, CF_ERR_PARSE,
               "t: line 14: header declares 5 vertices, file holds 4");
    /* fewer faces than declared: the file ends */
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n4 6 0\n" TET_V TET_F, CF_ERR_TRUNCATED, "t: header declares 6 faces, file holds 4");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, PLY_HDR(4, 6) TET_V TET_F "\n\n", CF_ERR_TRUNCATED,
               "t: header declares 6 faces, file holds 4");
    /* what may follow the last element: blank lines (and in OFF comments) */
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n4 4 0\n" TET_V TET_F "\n  \t\n# end\n\r\n", CF_OK, NULL);
    IOT_EXPECT(ctx, CF_FORMAT_PLY, PLY_HDR(4, 4) TET_V TET_F "\n \r\n\t", CF_OK, NULL);
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n4 4 0\n" TET_V TET_F "end\n", CF_ERR_PARSE,
               "t: line 11: data after the last face");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, PLY_HDR(4, 4) TET_V TET_F "# end\n", CF_ERR_PARSE,
               "t: line 18: data after the last element");
    /* one element per line in ascii PLY (the format says so): a face split
     * over two lines or a vertex with a value too many is an error */
    IOT_EXPECT(ctx, CF_FORMAT_PLY, PLY_HDR(4, 4) TET_V "3 0 2\n1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n", CF_ERR_PARSE,
               "t: line 14: face 0 has too few values");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, PLY_HDR(4, 4) "0 0 0\n1 0 0 7\n0 1 0\n0 0 1\n" TET_F, CF_ERR_PARSE,
               "t: line 11: vertex 1 has 4 values, its properties take 3");
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* ---- binary PLY ---------------------------------------------------------------- */

typedef struct bin {
    unsigned char b[1024];
    size_t n;
} bin;

static void add(bin *w, const void *p, size_t n)
{
    memcpy(w->b + w->n, p, n);
    w->n += n;
}

/* A little-endian binary tetrahedron whose header declares nf_declared
 * faces, with nf_written faces in the data. */
static void binary_tet(bin *w, int nf_declared, int nf_written)
{
    w->n = 0;
    char hdr[256];
    snprintf(hdr, sizeof hdr,
             "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
             "property float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n",
             nf_declared);
    add(w, hdr, strlen(hdr));
    static const float x[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    add(w, x, sizeof x);
    static const int32_t f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    for (int i = 0; i < nf_written; ++i) {
        unsigned char three = 3;
        add(w, &three, 1);
        add(w, f[i % 4], sizeof f[0]);
    }
}

static void expect_bin(cf_context *ctx, const bin *w, cf_status status, const char *part)
{
    cf_mesh_data *d = NULL;
    CHECK_STATUS(cf_read_mesh_memory(ctx, w->b, w->n, CF_FORMAT_PLY, "b.ply", &d), status);
    if (part && !strstr(cf_context_message(ctx), part))
        cft_fail(__FILE__, __LINE__, "message '%s' lacks '%s'", cf_context_message(ctx), part);
    if (d) CHECK(d->face_count == 4);
    cf_mesh_data_destroy(&d);
}

static void test_header_counts_binary(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    bin w;
    binary_tet(&w, 4, 4);
    expect_bin(ctx, &w, CF_OK, NULL);
    /* S1: trailing bytes were accepted */
    binary_tet(&w, 2, 4);
    expect_bin(ctx, &w, CF_ERR_PARSE, "b.ply: header declares 2 faces, file holds 4");
    binary_tet(&w, 4, 4);
    add(&w, "\n\0\0", 3);
    expect_bin(ctx, &w, CF_ERR_PARSE, "b.ply: 3 bytes after the last element");
    /* fewer: the message names the counts */
    binary_tet(&w, 4, 2);
    expect_bin(ctx, &w, CF_ERR_TRUNCATED, "b.ply: header declares 4 faces, file holds 2");
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* ---- byte-order mark, NUL bytes -------------------------------------------------- */

static void test_bom_and_nul(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    iot_log log = {0};
    cf_context_set_log(ctx, iot_log_fn, &log, CF_LOG_WARNING);
    static const char *const obj = BOM "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    cf_mesh_data *d = NULL;
    CHECK_OK(ctx, cf_read_mesh_memory(ctx, obj, strlen(obj), CF_FORMAT_OBJ, "b.obj", &d));
    CHECK(d && d->vertex_count == 4 && d->face_count == 4);
    CHECK(log.warnings == 0); /* was: unknown keyword '\ufeffv' ignored */
    cf_mesh_data_destroy(&d);
    IOT_EXPECT(ctx, CF_FORMAT_OFF, BOM "OFF\n4 4 0\n" TET_V TET_F, CF_OK, NULL);
    IOT_EXPECT(ctx, CF_FORMAT_OFF, BOM "4 4 0\n" TET_V TET_F, CF_OK, NULL);
    IOT_EXPECT(ctx, CF_FORMAT_PLY, BOM PLY_HDR(4, 4) TET_V TET_F, CF_OK, NULL);
    bin w;
    binary_tet(&w, 4, 4);
    bin wb = {{0xEF, 0xBB, 0xBF}, 3};
    add(&wb, w.b, w.n);
    expect_bin(ctx, &wb, CF_OK, NULL);
    /* only at the start: elsewhere it is an ordinary bad token */
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n" BOM "4 4 0\n" TET_V TET_F, CF_ERR_PARSE, "line 2");
    CHECK(log.warnings == 0);

    /* NUL bytes: named with their offset, not "bad number '0'" */
    static const char nul_obj[] = "v 0 0 0\nv 1 0\0 0\n";
    IOT_EXPECT_N(ctx, CF_FORMAT_OBJ, nul_obj, sizeof nul_obj - 1, CF_ERR_PARSE, "t: line 2: NUL byte at offset 13");
    static const char nul_off[] = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0\0 1 3\n";
    IOT_EXPECT_N(ctx, CF_FORMAT_OFF, nul_off, sizeof nul_off - 1, CF_ERR_PARSE, "t: line 8: NUL byte at offset 45");
    static const char nul_off_bom[] = BOM "OFF\n\0";
    IOT_EXPECT_N(ctx, CF_FORMAT_OFF, nul_off_bom, sizeof nul_off_bom - 1, CF_ERR_PARSE, "t: line 2: NUL byte at offset 7");
    static const char nul_ply[] = PLY_HDR(4, 4) "0 0 0\n1\0 0 0\n";
    IOT_EXPECT_N(ctx, CF_FORMAT_PLY, nul_ply, sizeof nul_ply - 1, CF_ERR_PARSE, "t: line 11: NUL byte at offset 161");
    static const char nul_hdr[] = "ply\nformat ascii 1.0\ncomment \0\nend_header\n";
    IOT_EXPECT_N(ctx, CF_FORMAT_PLY, nul_hdr, sizeof nul_hdr - 1, CF_ERR_PARSE, "t: line 3: NUL byte at offset 29");
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* M7: an integer too large for any index is printed as written */
static void test_huge_integers(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999999999\n", CF_ERR_INDEX_RANGE,
               "t: line 4: vertex index 99999999999999999999999999 out of range (3 vertices defined so far)");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -99999999999999999999999999/1\n",
               CF_ERR_INDEX_RANGE, "vertex index -99999999999999999999999999 out of range");
    IOT_EXPECT(ctx, CF_FORMAT_OBJ, "v 0 0 0\nvt 0 0\nf 1/1 1/99999999999999999999999 1/1\n", CF_ERR_INDEX_RANGE,
               "texture index 99999999999999999999999 out of range");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 99999999999999999999999999\n",
               CF_ERR_INDEX_RANGE, "t: line 6: face 0: vertex index 99999999999999999999999999 out of range [0, 3)");
    IOT_EXPECT(ctx, CF_FORMAT_OFF, "OFF\n99999999999999999999999999 1 0\n", CF_ERR_PARSE,
               "counts 99999999999999999999999999 vertices, 1 faces are too large");
    IOT_EXPECT(ctx, CF_FORMAT_PLY, PLY_HDR(3, 1) "0 0 0\n1 0 0\n0 1 0\n3 0 1 99999999999999999999999999\n",
               CF_ERR_INDEX_RANGE, "t: line 13: face 0: vertex index 99999999999999999999999999 out of range [0, 3)");
    IOT_EXPECT(ctx, CF_FORMAT_PLY,
               "ply\nformat ascii 1.0\nelement vertex 99999999999999999999999999\nproperty float x\nend_header\n",
               CF_ERR_TRUNCATED, "header declares 99999999999999999999999999 'vertex' elements");
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static int warnings_of(cf_context *ctx, cf_mesh_format fmt, const char *text, iot_log *log, cf_status *st)
{
    memset(log, 0, sizeof *log);
    cf_context_set_log(ctx, iot_log_fn, log, CF_LOG_WARNING);
    cf_mesh_data *d = NULL;
    *st = cf_read_mesh_memory(ctx, text, strlen(text), fmt, "w", &d);
    cf_mesh_data_destroy(&d);
    return log->warnings;
}

/* Input that was silently ignored gets one warning per file. */
static void test_ignored_input_warns(void)
{
    cf_context *ctx = cft_context();
    iot_log log;
    cf_status st;
    /* OBJ v: x y z, x y z w and x y z r g b are standard; anything else is not */
    CHECK(warnings_of(ctx, CF_FORMAT_OBJ, "v 0 0 0\nv 1 0 0 1\nv 0 1 0 0.5 0.5 0.5\nf 1 2 3\n", &log, &st) == 1);
    CHECK(st == CF_OK); /* but a colour on some vertices only is dropped: said since session 30 */
    CHECK(iot_has(log.last, "w: 1 of 3 vertices give a colour (v x y z r g b)"));
    CHECK(warnings_of(ctx, CF_FORMAT_OBJ, "v 0 0 0 1\nv 1 0 0 1\nv 0 1 0\nf 1 2 3\n", &log, &st) == 0);
    CHECK(warnings_of(ctx, CF_FORMAT_OBJ, "v 0 0 0\nv 1 0 0 1 2\nv 0 1 0 7 7 7 7 7\nf 1 2 3\n", &log, &st) == 1);
    CHECK(st == CF_OK);
    CHECK(iot_has(log.last, "w: line 2: vertex 1 has 5 values, expected x y z [w] or x y z r g b; the values "
                            "after z ('1' ...) are ignored (further such lines silently)"));
    CHECK(warnings_of(ctx, CF_FORMAT_OBJ, "v 0 0 0 oops\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", &log, &st) == 1);
    CHECK(iot_has(log.last, "w: line 1: vertex 0 has 4 values") && iot_has(log.last, "'oops'"));
    /* PLY values outside the range of their declared type */
    static const char *const ply_range =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "property uchar red\nproperty short s\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0 255 -32768\n1 0 0 300 0\n0 1 0 0 40000\n3 0 1 2\n";
    CHECK(warnings_of(ctx, CF_FORMAT_PLY, ply_range, &log, &st) == 1);
    CHECK(st == CF_OK);
    CHECK(iot_has(log.last, "w: line 13: vertex 1: value 300 of 'red' is not a valid uchar (kept as read; further such values "
                            "silently)"));
    CHECK(warnings_of(ctx, CF_FORMAT_PLY,
                      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 1e39\n1 0 0\n0 1 0\n"
                      "3 0 1 2\n",
                      &log, &st) == 1);
    CHECK(iot_has(log.last, "value 1e39 of 'z' is not a valid float"));
    CHECK(warnings_of(ctx, CF_FORMAT_PLY,
                      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                      "property int i\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                      "0 0 0 1.5\n1 0 0 0\n0 1 0 0\n3 0 1 2\n",
                      &log, &st) == 1);
    CHECK(iot_has(log.last, "value 1.5 of 'i' is not a valid int"));
    CHECK(warnings_of(ctx, CF_FORMAT_PLY, PLY_HDR(4, 4) TET_V TET_F, &log, &st) == 0);
    /* a third CSV column */
    memset(&log, 0, sizeof log);
    cf_context_set_log(ctx, iot_log_fn, &log, CF_LOG_WARNING);
    static const char csv[] = "x,y,z\n0,0,5\n1,0,5\n1,1,5\n0,1\n";
    cf_curve *c = NULL;
    CHECK_OK(ctx, cf_curve_read_memory(ctx, csv, sizeof csv - 1, 0, "c.csv", &c));
    CHECK(c && c->count == 4);
    CHECK(log.warnings == 1);
    CHECK(iot_has(log.last, "c.csv: line 2: a third column ('5') is ignored (x,y expected; further ones silently)"));
    cf_curve_destroy(&c);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* The polyline readers: BOM, NUL bytes, long lines. */
static void test_curve_text(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    cf_curve *c = NULL;
    /* the BOM made the first point look like a header line, which was dropped */
    static const char csv[] = BOM "0,0\n2,0\n2,1\n0,1\n";
    CHECK_OK(ctx, cf_curve_read_memory(ctx, csv, sizeof csv - 1, 0, NULL, &c));
    CHECK(c && c->count == 4);
    cf_curve_destroy(&c);
    static const char svg[] = BOM "<svg><polygon points=\"0,0 1,0 0,1\"/></svg>";
    CHECK_OK(ctx, cf_curve_read_memory(ctx, svg, sizeof svg - 1, 1, NULL, &c));
    CHECK(c && c->count == 3);
    cf_curve_destroy(&c);
    /* the public check the curve reader uses */
    size_t start = 99;
    CHECK_OK(ctx, cf_text_check(ctx, csv, sizeof csv - 1, NULL, &start));
    CHECK(start == 3);
    CHECK_OK(ctx, cf_text_check(ctx, "", 0, NULL, &start));
    CHECK(start == 0);
    CHECK_STATUS(cf_text_check(ctx, "a\n\0", 3, NULL, &start), CF_ERR_PARSE);
    CHECK(iot_has(cf_context_message(ctx), "<memory>: line 2: NUL byte at offset 2"));
    static const char nul[] = "0,0\n1,0\n1\0,1\n";
    CHECK_STATUS(cf_curve_read_memory(ctx, nul, sizeof nul - 1, 0, "n.csv", &c), CF_ERR_PARSE);
    CHECK(iot_has(cf_context_message(ctx), "n.csv: line 3: NUL byte at offset 9"));
    /* a comment line of 100 000 characters ending in numbers is a comment */
    size_t n = 100000;
    char *big = malloc(n + 64);
    memset(big, 'x', n);
    big[0] = '#';
    memcpy(big + n - 6, " 5 5 5", 6);
    strcpy(big + n, "\n0,0\n1,0\n0,1\n");
    CHECK_OK(ctx, cf_curve_read_memory(ctx, big, strlen(big), 0, "long.csv", &c));
    CHECK(c && c->count == 3);
    cf_curve_destroy(&c);
    /* and the same comment in every mesh format */
    strcpy(big + n, "\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    cf_mesh_data *d = NULL;
    CHECK_OK(ctx, cf_read_mesh_memory(ctx, big, strlen(big), CF_FORMAT_OBJ, "long.obj", &d));
    CHECK(d && d->vertex_count == 3 && d->face_count == 1);
    cf_mesh_data_destroy(&d);
    strcpy(big + n, "\nOFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    CHECK_OK(ctx, cf_read_mesh_memory(ctx, big, strlen(big), CF_FORMAT_OFF, "long.off", &d));
    CHECK(d && d->vertex_count == 3 && d->face_count == 1);
    cf_mesh_data_destroy(&d);
    free(big);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_header_counts_text);
    CFT_RUN(test_header_counts_binary);
    CFT_RUN(test_bom_and_nul);
    CFT_RUN(test_huge_integers);
    CFT_RUN(test_ignored_input_warns);
    CFT_RUN(test_curve_text);
    return cft_finish();
}
