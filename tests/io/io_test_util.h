/*
 * Shared fixtures of the I/O tests: small files written into the build
 * tree, an octahedron with "ugly" coordinates (so bit-exactness is tested
 * on doubles that do not print short), a warning counter, temp-file scans.
 */
#ifndef CF_TESTS_IO_TEST_UTIL_H
#define CF_TESTS_IO_TEST_UTIL_H

#include "curvflow/io.h"
#include "test.h"

#include <dirent.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static inline void iot_write(const char *path, const void *bytes, size_t n)
{
    FILE *fp = fopen(path, "wb");
    if (!fp || fwrite(bytes, 1, n, fp) != n) {
        fprintf(stderr, "cannot write %s\n", path);
        exit(1);
    }
    fclose(fp);
}

static inline void iot_write_text(const char *path, const char *text) { iot_write(path, text, strlen(text)); }

/* Whole file as a malloc'ed NUL-terminated string (NULL if absent). */
static inline char *iot_read(const char *path, size_t *size)
{
    FILE *fp = fopen(path, "rb");
    if (!fp) return NULL;
    fseek(fp, 0, SEEK_END);
    long n = ftell(fp);
    fseek(fp, 0, SEEK_SET);
    char *buf = malloc((size_t)n + 1);
    if (!buf || fread(buf, 1, (size_t)n, fp) != (size_t)n) {
        fclose(fp);
        free(buf);
        return NULL;
    }
    buf[n] = '\0';
    fclose(fp);
    if (size) *size = (size_t)n;
    return buf;
}

/* Octahedron, outward counter-clockwise faces. Coordinates are scaled by
 * factors such as 1/3 and pi whose %.6g prints would not round-trip. */
#define IOT_NV 6
#define IOT_NF 8
static inline void iot_octahedron(double *x, int32_t *tri)
{
    static const double base[IOT_NV][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    static const int32_t faces[IOT_NF][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                             {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    for (int v = 0; v < IOT_NV; ++v)
        for (int k = 0; k < 3; ++k)
            x[3 * v + k] = base[v][k] * (1.0 / 3.0 + 0.1 * v) + 3.141592653589793 * 1e-3 * (k + 1) / (v + 7.0);
    memcpy(tri, faces, sizeof faces);
}

/* Octahedron as a cf_mesh, optionally with per-corner uv (each corner its
 * own uv entry) or per-vertex uv. */
static inline cf_mesh *iot_octahedron_mesh(cf_context *ctx, int uv_mode /* 0 none, 1 vertex, 2 corner */)
{
    double x[3 * IOT_NV], uv[2 * 3 * IOT_NF];
    int32_t tri[3 * IOT_NF], uvt[3 * IOT_NF];
    iot_octahedron(x, tri);
    for (int i = 0; i < 3 * IOT_NF; ++i) {
        uv[2 * i] = 0.1 * i + 1.0 / 7.0;
        uv[2 * i + 1] = 1.0 - 0.03 * i / 3.0;
        uvt[i] = i;
    }
    cf_mesh_desc d;
    memset(&d, 0, sizeof d);
    d.vertex_count = IOT_NV;
    d.positions = x;
    d.face_count = IOT_NF;
    d.triangles = tri;
    if (uv_mode == 1) {
        d.uv_count = IOT_NV;
        d.uv = uv;
    } else if (uv_mode == 2) {
        d.uv_count = 3 * IOT_NF;
        d.uv = uv;
        d.uv_triangles = uvt;
    }
    cf_mesh *m = NULL;
    if (cf_mesh_create(ctx, &d, &m) != CF_OK) {
        fprintf(stderr, "octahedron: %s\n", cf_context_message(ctx));
        exit(1);
    }
    return m;
}

/* Counts log lines at warning level. */
typedef struct iot_log {
    int warnings;
    char last[512];
} iot_log;

static inline void iot_log_fn(void *user, cf_log_level level, const char *line)
{
    iot_log *l = user;
    if (level == CF_LOG_WARNING) {
        l->warnings++;
        snprintf(l->last, sizeof l->last, "%s", line);
    }
}

/* Number of leftover temporary files of `path` (".<base>.tmp-*" next to it). */
static inline int iot_temp_files(const char *path)
{
    char dir[4200], prefix[4200];
    const char *slash = strrchr(path, '/');
    snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - path) : 1, slash ? path : ".");
    snprintf(prefix, sizeof prefix, ".%s.tmp", slash ? slash + 1 : path);
    DIR *d = opendir(dir);
    if (!d) return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strncmp(e->d_name, prefix, strlen(prefix)) == 0) ++n;
    closedir(d);
    return n;
}

static inline bool iot_has(const char *msg, const char *part) { return !part || strstr(msg, part) != NULL; }

/* Reads `text` as `fmt` from memory and checks status and a message part. */
#define IOT_EXPECT(ctx, fmt, text, status, part) IOT_EXPECT_N(ctx, fmt, text, strlen(text), status, part)

/* The same for `size` bytes (which may hold NUL bytes). */
#define IOT_EXPECT_N(ctx, fmt, text, size, status, part) \
    do { \
        cf_mesh_data *iot_d_ = NULL; \
        CHECK_STATUS(cf_read_mesh_memory((ctx), (text), (size), (fmt), "t", &iot_d_), (status)); \
        if (!iot_has(cf_context_message(ctx), (part))) \
            cft_fail(__FILE__, __LINE__, "message '%s' lacks '%s'", cf_context_message(ctx), (part)); \
        if ((status) != CF_OK) CHECK(iot_d_ == NULL); \
        cf_mesh_data_destroy(&iot_d_); \
    } while (0)

/* Fail-allocation injection: for n = 1, 2, ... the n-th allocation fails
 * until the read succeeds; every failure must be CF_ERR_NOMEM with nothing
 * leaked. Returns the number of failing runs. */
static inline int iot_nomem_sweep(cf_context *ctx, const void *bytes, size_t size, cf_mesh_format fmt)
{
    for (int64_t n = 1; n < 100000; ++n) {
        cf_mesh_data *d = NULL;
        cf_context_fail_allocation(ctx, n, 0);
        cf_status st = cf_read_mesh_memory(ctx, bytes, size, fmt, "nomem", &d);
        cf_context_fail_allocation(ctx, 0, 0);
        if (st == CF_OK) {
            cf_mesh_data_destroy(&d);
            CHECK(cf_context_bytes_in_use(ctx) == 0);
            return (int)(n - 1);
        }
        CHECK_STATUS(st, CF_ERR_NOMEM);
        CHECK(d == NULL);
        CHECK(cf_context_bytes_in_use(ctx) == 0);
        if (st != CF_ERR_NOMEM) return -1;
    }
    return -1;
}

#endif /* CF_TESTS_IO_TEST_UTIL_H */
