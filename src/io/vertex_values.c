/*
 * Per-vertex values from text files: one number per vertex (the rho of
 * `curvflow spin --rho FILE`) and direction vectors "VERTEX X Y Z" for
 * chosen vertices (the boundary targets of `curvflow flow
 * --boundary-targets FILE`). They were read by the command line through a
 * 4096-byte line buffer, so the tail of a longer line (even of a comment)
 * was read as data; here they go through the library's text input
 * (io/text.h), which has no line length, and the fuzzers can reach them.
 */
#include "io/io_internal.h"
#include "io/text.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* [s, e) without a '#' comment. */
static const char *strip_comment(const char *s, const char *e)
{
    const char *hash = memchr(s, '#', (size_t)(e - s));
    return hash ? hash : e;
}

/* strtod over the whole token [s, e); the buffer ends in a NUL, so strtod
 * never runs past it. */
static bool token_double(const char *s, const char *e, double *v)
{
    char *end = NULL;
    *v = strtod(s, &end);
    return end == e;
}

/* A NUL-terminated copy of `size` bytes (*cap bytes to free), so that
 * strtod stops at the end of a memory buffer too. */
static cf_status terminated_copy(cf_context *ctx, const void *bytes, size_t size, const char *name, char **buf,
                                 size_t *cap)
{
    *buf = NULL;
    if (!bytes && size > 0) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: bytes is NULL", name);
    if (size == SIZE_MAX) return cfi_error(ctx, CF_ERR_NOMEM, "%s: input too large", name);
    *buf = cfi_malloc(ctx, size + 1);
    if (!*buf) return cfi_error(ctx, CF_ERR_NOMEM, "%s: out of memory copying %zu bytes", name, size);
    if (size) memcpy(*buf, bytes, size);
    (*buf)[size] = '\0';
    *cap = size + 1;
    return CF_OK;
}

/* ---- one number per vertex ---------------------------------------------------------- */

/* buf[size] == '\0' */
static cf_status parse_scalars(cf_context *ctx, const char *buf, size_t size, const char *name, int32_t nv,
                               double *out)
{
    cf_status st = cfi_text_check_nul(ctx, name, buf, 0, size);
    if (st != CF_OK) return st;
    cfi_text t;
    cfi_text_init(&t, buf, size);
    int64_t count = 0;
    while (cfi_text_next(&t)) {
        const char *p = t.s, *e = strip_comment(t.s, t.e), *ts, *te;
        while (cfi_text_token(&p, e, ",", &ts, &te)) {
            double v;
            if (!token_double(ts, te, &v))
                return cfi_error(ctx, CF_ERR_PARSE, "%s: line %lld: bad number '%.*s'", name, (long long)t.line,
                                 cfi_tok_len(ts, te), ts);
            if (!isfinite(v))
                return cfi_error(ctx, CF_ERR_NONFINITE, "%s: line %lld: value %lld ('%.*s') is not finite", name,
                                 (long long)t.line, (long long)count, cfi_tok_len(ts, te), ts);
            if (count >= nv)
                return cfi_error(ctx, CF_ERR_PARSE, "%s: line %lld: more than %d values (one per vertex expected)",
                                 name, (long long)t.line, nv);
            out[count++] = v;
        }
    }
    if (count != nv)
        return cfi_error(ctx, CF_ERR_PARSE, "%s: holds %lld values, expected one per vertex (%d)", name,
                         (long long)count, nv);
    return CF_OK;
}

cf_status cf_read_vertex_scalars_memory(cf_context *ctx, const void *bytes, size_t size, const char *name,
                                        int32_t vertex_count, double *out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!name) name = "<memory>";
    if (vertex_count < 0 || (!out && vertex_count > 0))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: vertex values: vertex_count %d or out is NULL", name,
                         vertex_count);
    char *buf = NULL;
    size_t cap = 0;
    cf_status st = terminated_copy(ctx, bytes, size, name, &buf, &cap);
    if (st == CF_OK) st = parse_scalars(ctx, buf, size, name, vertex_count, out);
    cfi_free(ctx, buf, cap);
    return st;
}

cf_status cf_read_vertex_scalars_file(cf_context *ctx, const char *path, int32_t vertex_count, double *out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!path) return cfi_error(ctx, CF_ERR_INVALID_ARG, "vertex values: path is NULL");
    char *buf = NULL;
    size_t size = 0, cap = 0;
    if (vertex_count < 0 || (!out && vertex_count > 0))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: vertex values: vertex_count %d or out is NULL", path,
                         vertex_count);
    cf_status st = cfi_read_whole_file(ctx, path, &buf, &size, &cap);
    if (st != CF_OK) return st;
    st = parse_scalars(ctx, buf, size, path, vertex_count, out);
    cfi_free(ctx, buf, cap);
    return st;
}

/* ---- "VERTEX X Y Z" directions -------------------------------------------------------- */

/* Checks one direction and stores it; `line` names the place. */
static cf_status store_direction(cf_context *ctx, const char *name, int64_t line, int64_t v, const double d[3],
                                 double *out)
{
    double largest = 0.0;
    for (int c = 0; c < 3; ++c) {
        if (!isfinite(d[c]))
            return cfi_error(ctx, CF_ERR_NONFINITE, "%s: line %lld: vertex %lld: direction (%g, %g, %g) is not finite",
                             name, (long long)line, (long long)v, d[0], d[1], d[2]);
        largest = fmax(largest, fabs(d[c]));
    }
    if (largest > CF_MAX_COORDINATE)
        return cfi_error(ctx, CF_ERR_NONFINITE,
                         "%s: line %lld: vertex %lld: direction (%g, %g, %g) is beyond the coordinate range "
                         "(|x| <= %.0e)",
                         name, (long long)line, (long long)v, d[0], d[1], d[2], CF_MAX_COORDINATE);
    /* the flow normalises it: a zero (or underflowing) length has no direction */
    if (largest < CF_MIN_EDGE_LENGTH)
        return cfi_error(ctx, CF_ERR_PARSE,
                         "%s: line %lld: vertex %lld: direction (%g, %g, %g) is zero (a direction needs a "
                         "component of at least %.0e)",
                         name, (long long)line, (long long)v, d[0], d[1], d[2], CF_MIN_EDGE_LENGTH);
    for (int c = 0; c < 3; ++c) out[3 * v + c] = d[c];
    return CF_OK;
}

/* buf[size] == '\0'; seen: nv bytes, zero */
static cf_status parse_directions(cf_context *ctx, const char *buf, size_t size, const char *name, int32_t nv,
                                  const uint8_t *required, const char *required_name, uint8_t *seen, double *out)
{
    cfi_text t;
    cfi_text_init(&t, buf, size);
    while (cfi_text_next(&t)) {
        const char *p = t.s, *e = strip_comment(t.s, t.e), *ts[5], *te[5];
        int n = 0;
        while (n < 5 && cfi_text_token(&p, e, NULL, &ts[n], &te[n])) ++n;
        if (n == 0) continue;
        int64_t v = 0;
        double d[3];
        bool ok = n == 4 && cfi_parse_int(ts[0], te[0], &v);
        for (int c = 0; ok && c < 3; ++c) ok = token_double(ts[c + 1], te[c + 1], &d[c]);
        if (!ok)
            return cfi_error(ctx, CF_ERR_PARSE, "%s: line %lld: expected 'VERTEX X Y Z', found '%.*s'", name,
                             (long long)t.line, cfi_tok_len(ts[0], te[n - 1]), ts[0]);
        if (v < 0 || v >= nv) /* quoted as written: a huge index has saturated in v */
            return cfi_error(ctx, CF_ERR_INDEX_RANGE, "%s: line %lld: vertex %.*s out of range [0, %d)", name,
                             (long long)t.line, cfi_tok_len(ts[0], te[0]), ts[0], nv);
        if (required && !required[v])
            return cfi_error(ctx, CF_ERR_PARSE, "%s: line %lld: vertex %lld is not a %s of the mesh", name,
                             (long long)t.line, (long long)v, required_name);
        if (seen[v])
            return cfi_error(ctx, CF_ERR_PARSE, "%s: line %lld: vertex %lld is listed twice", name, (long long)t.line,
                             (long long)v);
        seen[v] = 1;
        cf_status st = store_direction(ctx, name, t.line, v, d, out);
        if (st != CF_OK) return st;
    }
    for (int32_t i = 0; i < nv; ++i)
        if ((!required || required[i]) && !seen[i])
            return cfi_error(ctx, CF_ERR_PARSE, "%s: %s %d has no line (every %s needs one)", name, required_name, i,
                             required_name);
    return CF_OK;
}

/* Both entry points: buf[size] == '\0'. */
static cf_status read_directions(cf_context *ctx, const char *buf, size_t size, const char *name, int32_t nv,
                                 const uint8_t *required, const char *required_name, double *out)
{
    cf_status st = cfi_text_check_nul(ctx, name, buf, 0, size);
    if (st != CF_OK) return st;
    uint8_t *seen = nv > 0 ? CFI_ALLOC(ctx, uint8_t, nv) : NULL;
    if (nv > 0 && !seen) return CF_ERR_NOMEM;
    if (nv > 0) memset(out, 0, 3 * (size_t)nv * sizeof *out);
    st = parse_directions(ctx, buf, size, name, nv, required, required_name, seen, out);
    if (seen) CFI_FREE(ctx, seen, nv);
    return st;
}

static cf_status check_direction_args(cf_context *ctx, const char *name, int32_t nv, const double *out)
{
    if (nv < 0 || (!out && nv > 0))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: vertex directions: vertex_count %d or out is NULL", name, nv);
    return CF_OK;
}

cf_status cf_read_vertex_directions_memory(cf_context *ctx, const void *bytes, size_t size, const char *name,
                                           int32_t vertex_count, const uint8_t *required, const char *required_name,
                                           double *out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!name) name = "<memory>";
    if (!required_name) required_name = "vertex";
    cf_status st = check_direction_args(ctx, name, vertex_count, out);
    if (st != CF_OK) return st;
    char *buf = NULL;
    size_t cap = 0;
    st = terminated_copy(ctx, bytes, size, name, &buf, &cap);
    if (st == CF_OK) st = read_directions(ctx, buf, size, name, vertex_count, required, required_name, out);
    cfi_free(ctx, buf, cap);
    return st;
}

cf_status cf_read_vertex_directions_file(cf_context *ctx, const char *path, int32_t vertex_count,
                                         const uint8_t *required, const char *required_name, double *out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!path) return cfi_error(ctx, CF_ERR_INVALID_ARG, "vertex directions: path is NULL");
    if (!required_name) required_name = "vertex";
    cf_status st = check_direction_args(ctx, path, vertex_count, out);
    if (st != CF_OK) return st;
    char *buf = NULL;
    size_t size = 0, cap = 0;
    st = cfi_read_whole_file(ctx, path, &buf, &size, &cap);
    if (st != CF_OK) return st;
    st = read_directions(ctx, buf, size, path, vertex_count, required, required_name, out);
    cfi_free(ctx, buf, cap);
    return st;
}
