/* Per-vertex values from text files (cf_read_vertex_scalars_*: the rho of
 * `curvflow spin`; cf_read_vertex_directions_*: the boundary targets of
 * `curvflow flow --boundary-targets`): lines of any length, comments, BOM,
 * NUL bytes, counts, bad values with their file and line (issue 15: S2, E4,
 * M6, M7), allocation failures. */
#define _POSIX_C_SOURCE 200809L
#include "io_test_util.h"

#include <math.h>

#define BOM "\xEF\xBB\xBF"

static void expect_scalars(cf_context *ctx, const char *text, int32_t nv, cf_status status, const char *part,
                           double *out)
{
    CHECK_STATUS(cf_read_vertex_scalars_memory(ctx, text, strlen(text), "rho.txt", nv, out), status);
    if (part && !strstr(cf_context_message(ctx), part))
        cft_fail(__FILE__, __LINE__, "message '%s' lacks '%s'", cf_context_message(ctx), part);
}

static void test_scalars(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    double v[4] = {0};
    /* one per line, commas, comments, CRLF, BOM, no final newline */
    expect_scalars(ctx, BOM "# rho\r\n1\r\n-2.5, 3e-3 # two on a line\r\n\r\n4", 4, CF_OK, NULL, v);
    CHECK(v[0] == 1.0 && v[1] == -2.5 && v[2] == 3e-3 && v[3] == 4.0);
    expect_scalars(ctx, "1,2,3,4\n", 4, CF_OK, NULL, v);
    CHECK(v[3] == 4.0);
    /* S2: a comment longer than any line buffer, ending in numbers, is a comment */
    size_t n = 100000;
    char *text = malloc(n + 64);
    memset(text, 'c', n);
    text[0] = '#';
    memcpy(text + n - 6, " 5 5 5", 6);
    strcpy(text + n, "\n0\n0\n0\n0\n");
    expect_scalars(ctx, text, 4, CF_OK, NULL, v);
    CHECK(v[0] == 0.0 && v[1] == 0.0 && v[2] == 0.0 && v[3] == 0.0);
    free(text);
    /* S2: one comma-separated line of 35 KB and more */
    int32_t nv = 5000;
    double *many = malloc(sizeof(double) * (size_t)nv);
    char *line = malloc((size_t)nv * 16 + 2);
    size_t len = 0;
    for (int32_t i = 0; i < nv; ++i) len += (size_t)sprintf(line + len, "%s%.6f", i ? "," : "", i * 1e-3);
    strcpy(line + len, "\n");
    CHECK(len > 35000);
    expect_scalars(ctx, line, nv, CF_OK, NULL, many);
    CHECK(many[0] == 0.0 && many[4999] == 4.999 && many[1234] == 1.234);
    free(line);
    free(many);
    /* errors name the file and the line */
    expect_scalars(ctx, "1\n2\nx\n4\n", 4, CF_ERR_PARSE, "rho.txt: line 3: bad number 'x'", v);
    expect_scalars(ctx, "1\n2 nan\n", 4, CF_ERR_NONFINITE, "rho.txt: line 2: value 2 ('nan') is not finite", v);
    expect_scalars(ctx, "1 1e999 1 1\n", 4, CF_ERR_NONFINITE, "('1e999') is not finite", v);
    expect_scalars(ctx, "1 2 3\n", 4, CF_ERR_PARSE, "rho.txt: holds 3 values, expected one per vertex (4)", v);
    expect_scalars(ctx, "1 2 3 4\n5\n", 4, CF_ERR_PARSE, "rho.txt: line 2: more than 4 values", v);
    expect_scalars(ctx, "1 2 3 4" BOM "\n", 4, CF_ERR_PARSE, "bad number", v); /* a BOM only at the start */
    static const char nul[] = "1\n2\n3\0\n4\n";
    CHECK_STATUS(cf_read_vertex_scalars_memory(ctx, nul, sizeof nul - 1, "rho.txt", 4, v), CF_ERR_PARSE);
    CHECK(iot_has(cf_context_message(ctx), "rho.txt: line 3: NUL byte at offset 5"));
    CHECK_STATUS(cf_read_vertex_scalars_memory(ctx, "1", 1, "r", 1, NULL), CF_ERR_INVALID_ARG);
    /* from a file */
    const char *path = cft_temp_path(".txt");
    iot_write_text(path, "7 8\n9 10\n");
    CHECK_OK(ctx, cf_read_vertex_scalars_file(ctx, path, 4, v));
    CHECK(v[0] == 7.0 && v[3] == 10.0);
    remove(path);
    CHECK_STATUS(cf_read_vertex_scalars_file(ctx, path, 4, v), CF_ERR_IO);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* A 6-vertex "mesh" whose vertices 1, 2 and 4 are required (a boundary). */
static const uint8_t boundary[6] = {0, 1, 1, 0, 1, 0};

static void expect_dirs(cf_context *ctx, const char *text, cf_status status, const char *part, double *out)
{
    CHECK_STATUS(cf_read_vertex_directions_memory(ctx, text, strlen(text), "t.txt", 6, boundary, "boundary vertex", out),
                 status);
    if (part && !strstr(cf_context_message(ctx), part))
        cft_fail(__FILE__, __LINE__, "message '%s' lacks '%s'", cf_context_message(ctx), part);
}

static void test_directions(void)
{
    cf_context *ctx = cft_context();
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_ERROR);
    double d[18];
    for (int i = 0; i < 18; ++i) d[i] = 99.0;
    expect_dirs(ctx, BOM "# VERTEX X Y Z\n4 0 0 1\n1 1 0 0 # first\n\n 2\t0 1 0\r\n", CF_OK, NULL, d);
    CHECK(d[3] == 1.0 && d[7] == 1.0 && d[14] == 1.0);
    CHECK(d[0] == 0.0 && d[9] == 0.0 && d[17] == 0.0); /* vertices not listed: zero */
    /* S2: a long comment ending in what looks like a target */
    size_t n = 50000;
    char *text = malloc(n + 64);
    memset(text, 'c', n);
    text[0] = '#';
    memcpy(text + n - 8, " 3 1 1 1", 8);
    strcpy(text + n, "\n1 1 0 0\n2 0 1 0\n4 0 0 1\n");
    expect_dirs(ctx, text, CF_OK, NULL, d);
    free(text);
    /* E4: bad values are input errors naming file and line */
    expect_dirs(ctx, "1 1 0 0\n2 nan 1 0\n4 0 0 1\n", CF_ERR_NONFINITE,
                "t.txt: line 2: vertex 2: direction (nan, 1, 0) is not finite", d);
    expect_dirs(ctx, "1 1 0 0\n2 0 0 0\n4 0 0 1\n", CF_ERR_PARSE, "t.txt: line 2: vertex 2: direction (0, 0, 0) is zero", d);
    expect_dirs(ctx, "1 1 0 0\n2 1e-60 0 0\n4 0 0 1\n", CF_ERR_PARSE, "line 2: vertex 2: direction (1e-60, 0, 0) is zero", d);
    expect_dirs(ctx, "1 1 0 0\n2 0 0 1\n4 1e308 0 0\n", CF_ERR_NONFINITE,
                "t.txt: line 3: vertex 4: direction (1e+308, 0, 0) is beyond the coordinate range", d);
    expect_dirs(ctx, "1 1 0 0\n2 0 0 1\n4 0 0 inf\n", CF_ERR_NONFINITE, "line 3: vertex 4: direction (0, 0, inf)", d);
    /* the file's structure */
    expect_dirs(ctx, "1 1 0 0\n2 0 1\n4 0 0 1\n", CF_ERR_PARSE, "t.txt: line 2: expected 'VERTEX X Y Z', found '2 0 1'", d);
    expect_dirs(ctx, "1 1 0 0 7\n", CF_ERR_PARSE, "line 1: expected 'VERTEX X Y Z', found '1 1 0 0 7'", d);
    expect_dirs(ctx, "1.5 1 0 0\n", CF_ERR_PARSE, "line 1: expected 'VERTEX X Y Z'", d);
    expect_dirs(ctx, "1 1 0 0\n3 1 0 0\n", CF_ERR_PARSE, "t.txt: line 2: vertex 3 is not a boundary vertex of the mesh", d);
    expect_dirs(ctx, "1 1 0 0\n1 1 0 0\n", CF_ERR_PARSE, "t.txt: line 2: vertex 1 is listed twice", d);
    expect_dirs(ctx, "1 1 0 0\n4 1 0 0\n", CF_ERR_PARSE, "t.txt: boundary vertex 2 has no line (every boundary vertex needs one)", d);
    /* M7: an index is quoted as written */
    expect_dirs(ctx, "99999999999999999999999999 1 0 0\n", CF_ERR_INDEX_RANGE,
                "t.txt: line 1: vertex 99999999999999999999999999 out of range [0, 6)", d);
    expect_dirs(ctx, "-1 1 0 0\n", CF_ERR_INDEX_RANGE, "vertex -1 out of range [0, 6)", d);
    static const char nul[] = "1 1 0 0\n2 0\0 1 0\n";
    CHECK_STATUS(cf_read_vertex_directions_memory(ctx, nul, sizeof nul - 1, "t.txt", 6, boundary, "boundary vertex", d),
                 CF_ERR_PARSE);
    CHECK(iot_has(cf_context_message(ctx), "t.txt: line 2: NUL byte at offset 11"));
    /* required = NULL: every vertex, once */
    CHECK_OK(ctx, cf_read_vertex_directions_memory(ctx, "1 0 1 0\n0 1 0 0\n", 16, NULL, 2, NULL, NULL, d));
    CHECK(d[0] == 1.0 && d[4] == 1.0);
    CHECK_STATUS(cf_read_vertex_directions_memory(ctx, "1 0 1 0\n", 8, NULL, 2, NULL, NULL, d), CF_ERR_PARSE);
    CHECK(iot_has(cf_context_message(ctx), "<memory>: vertex 0 has no line"));
    /* from a file */
    const char *path = cft_temp_path(".txt");
    iot_write_text(path, "4 0 0 2\n2 0 3 0\n1 5 0 0\n");
    CHECK_OK(ctx, cf_read_vertex_directions_file(ctx, path, 6, boundary, "boundary vertex", d));
    CHECK(d[3] == 5.0 && d[7] == 3.0 && d[14] == 2.0);
    remove(path);
    CHECK_STATUS(cf_read_vertex_directions_file(ctx, path, 6, boundary, "boundary vertex", d), CF_ERR_IO);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

static cf_status read_both(cf_context *ctx, void *user)
{
    (void)user;
    double v[3], d[18];
    cf_status st = cf_read_vertex_scalars_memory(ctx, "1 2 3", 5, "a", 3, v);
    if (st == CF_OK) st = cf_read_vertex_directions_memory(ctx, "1 1 0 0\n2 0 1 0\n4 0 0 1\n", 24, "b", 6, boundary,
                                                           "boundary vertex", d);
    return st;
}

static void test_allocation_failures(void)
{
    cf_context *ctx = NULL;
    CHECK_OK(ctx, cf_context_create(&ctx));
    CHECK(cft_allocation_sweep(ctx, "vertex values", read_both, NULL, 0) >= 3);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_scalars);
    CFT_RUN(test_directions);
    CFT_RUN(test_allocation_failures);
    return cft_finish();
}
