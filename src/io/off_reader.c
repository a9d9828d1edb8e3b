/*
 * OFF reader (Geomview Object File Format, ASCII). Header keyword OFF with
 * the usual prefixes tolerated (ST, C, N: texture, colour, normal values per
 * vertex are ignored); the keyword itself may be omitted. Then
 * "nv nf [ne]", nv vertex lines "x y z [extra...]" and nf face lines
 * "n i_0 ... i_{n-1} [colour...]" with 0-based indices. '#' starts a
 * comment. The reader is line-based: one vertex or face per line, as every
 * OFF writer we know produces. Polygons are fan-triangulated.
 */
#include "io/io_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

typedef struct off_reader {
    cf_context *ctx;
    const char *name;
    const char *p, *buf_end;    /* next line starts at p */
    const char *lp, *lend;      /* cursor and end of the current line (comment stripped) */
    int64_t line;
    bool last_unterminated;
} off_reader;

static cf_status fail(off_reader *r, cf_status st, const char *fmt, ...) CF_PRINTF(3, 4);
static cf_status fail(off_reader *r, cf_status st, const char *fmt, ...)
{
    char msg[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (st == CF_ERR_PARSE && r->last_unterminated)
        return cfi_error(r->ctx, CF_ERR_TRUNCATED, "%s: line %lld: %s (file ends inside this line: truncated?)",
                         r->name, (long long)r->line, msg);
    return cfi_error(r->ctx, st, "%s: line %lld: %s", r->name, (long long)r->line, msg);
}

/* Advances to the next line holding a token (blank and comment lines are
 * skipped); false at the end of the file. */
static bool next_line(off_reader *r)
{
    while (r->p < r->buf_end) {
        const char *nl = memchr(r->p, '\n', (size_t)(r->buf_end - r->p));
        r->lp = r->p;
        r->lend = nl ? nl : r->buf_end;
        r->last_unterminated = nl == NULL;
        r->p = nl ? nl + 1 : r->buf_end;
        r->line++;
        const char *hash = memchr(r->lp, '#', (size_t)(r->lend - r->lp));
        if (hash) r->lend = hash;
        const char *q = r->lp;
        while (q < r->lend && cfi_is_space(*q)) ++q;
        if (q < r->lend) return true;
    }
    return false;
}

static bool next_token(off_reader *r, const char **s, const char **e)
{
    const char *p = r->lp;
    while (p < r->lend && cfi_is_space(*p)) ++p;
    if (p >= r->lend) {
        r->lp = p;
        return false;
    }
    *s = p;
    while (p < r->lend && !cfi_is_space(*p)) ++p;
    *e = p;
    r->lp = p;
    return true;
}

static int tok_len(const char *s, const char *e) { return (int)(e - s > 40 ? 40 : e - s); }

/* Reads "nv nf [ne]" from the current line's remaining tokens. */
static cf_status read_counts(off_reader *r, int64_t *nv, int64_t *nf)
{
    const char *s, *e;
    int64_t c[2];
    for (int k = 0; k < 2; ++k) {
        if (!next_token(r, &s, &e)) return fail(r, CF_ERR_PARSE, "expected vertex and face counts");
        if (!cfi_parse_int(s, e, &c[k]) || c[k] < 0)
            return fail(r, CF_ERR_PARSE, "bad count '%.*s'", tok_len(s, e), s);
    }
    *nv = c[0];
    *nf = c[1];
    return CF_OK;
}

static cf_status read_body(off_reader *r, cfi_mesh_builder *b)
{
    cf_context *ctx = r->ctx;
    const char *s, *e;
    if (!next_line(r)) return cfi_error(ctx, CF_ERR_TRUNCATED, "%s: empty file (no OFF header)", r->name);
    const char *save = r->lp;
    if (!next_token(r, &s, &e)) return fail(r, CF_ERR_PARSE, "missing header");
    int64_t nv = 0, nf = 0;
    size_t len = (size_t)(e - s);
    if (len >= 3 && cfi_word_eq(e - 3, 3, "OFF")) {
        for (const char *c = s; c < e - 3; ++c)
            if (!strchr("STCNstcn", *c))
                return fail(r, CF_ERR_UNSUPPORTED, "unsupported OFF variant '%.*s'", tok_len(s, e), s);
        if (next_token(r, &s, &e)) {
            if (cfi_word_eq(s, (size_t)(e - s), "BINARY"))
                return fail(r, CF_ERR_UNSUPPORTED, "binary OFF is not supported");
            r->lp = s; /* counts on the header line */
        } else if (!next_line(r)) {
            return cfi_error(ctx, CF_ERR_TRUNCATED, "%s: file ends after the OFF header", r->name);
        }
    } else {
        r->lp = save; /* header keyword omitted: this line holds the counts */
    }
    cf_status st = read_counts(r, &nv, &nf);
    if (st != CF_OK) return st;
    if (nv > CFI_MAX_ELEMENTS || nf > CFI_MAX_ELEMENTS)
        return fail(r, CF_ERR_PARSE, "counts %lld vertices, %lld faces are too large", (long long)nv, (long long)nf);
    /* Each vertex line takes at least 6 bytes ("0 0 0\n"), each face line 8
     * ("3 0 1 2\n"): reject a header promising far more than the file can
     * hold before allocating anything for it (half the minimum, so that a
     * file cut a little short still gets the precise message below). */
    size_t remaining = (size_t)(r->buf_end - r->p);
    if ((uint64_t)nv * 3 + (uint64_t)nf * 4 > (uint64_t)remaining + 1)
        return fail(r, CF_ERR_TRUNCATED, "header declares %lld vertices and %lld faces but only %zu bytes follow",
                    (long long)nv, (long long)nf, remaining);
    if (cfi_buf_reserve(ctx, &b->positions, (size_t)nv * 3) != CF_OK) return CF_ERR_NOMEM;
    if (cfi_buf_reserve(ctx, &b->triangles, (size_t)nf * 3) != CF_OK) return CF_ERR_NOMEM;
    double *pos = b->positions.data;
    for (int64_t i = 0; i < nv; ++i) {
        if (!next_line(r))
            return cfi_error(ctx, CF_ERR_TRUNCATED, "%s: file ends after %lld of %lld vertices", r->name,
                             (long long)i, (long long)nv);
        for (int k = 0; k < 3; ++k) {
            if (!next_token(r, &s, &e))
                return fail(r, CF_ERR_PARSE, "vertex %lld has %d coordinates, expected 3", (long long)i, k);
            if (!cfi_parse_double(s, e, &pos[3 * i + k]))
                return fail(r, CF_ERR_PARSE, "vertex %lld: bad number '%.*s'", (long long)i, tok_len(s, e), s);
        }
        if (!isfinite(pos[3 * i]) || !isfinite(pos[3 * i + 1]) || !isfinite(pos[3 * i + 2]))
            return fail(r, CF_ERR_NONFINITE, "vertex %lld has a non-finite coordinate", (long long)i);
        b->positions.count += 3;
    }
    for (int64_t f = 0; f < nf; ++f) {
        if (!next_line(r))
            return cfi_error(ctx, CF_ERR_TRUNCATED, "%s: file ends after %lld of %lld faces", r->name, (long long)f,
                             (long long)nf);
        int64_t n;
        if (!next_token(r, &s, &e) || !cfi_parse_int(s, e, &n))
            return fail(r, CF_ERR_PARSE, "face %lld: bad vertex count", (long long)f);
        if (n < 3) return fail(r, CF_ERR_PARSE, "face %lld has %lld vertices", (long long)f, (long long)n);
        int32_t v0 = -1, vp = -1;
        for (int64_t k = 0; k < n; ++k) {
            int64_t v;
            if (!next_token(r, &s, &e))
                return fail(r, CF_ERR_PARSE, "face %lld: %lld of %lld vertex indices", (long long)f, (long long)k,
                            (long long)n);
            if (!cfi_parse_int(s, e, &v))
                return fail(r, CF_ERR_PARSE, "face %lld: bad index '%.*s'", (long long)f, tok_len(s, e), s);
            if (v < 0 || v >= nv)
                return fail(r, CF_ERR_INDEX_RANGE, "face %lld: vertex index %lld out of range [0, %lld)",
                            (long long)f, (long long)v, (long long)nv);
            if (k == 0) v0 = (int32_t)v;
            else if (k >= 2) {
                if (b->triangles.count / 3 >= CFI_MAX_ELEMENTS) return fail(r, CF_ERR_PARSE, "too many triangles");
                if (cfi_push_int3(ctx, &b->triangles, v0, vp, (int32_t)v) != CF_OK) return CF_ERR_NOMEM;
            }
            vp = (int32_t)v;
        }
        if (n > 3) b->polygon_count++;
    }
    return CF_OK;
}

cf_status cfi_read_off(cf_context *ctx, const char *buf, size_t size, const char *name, cf_mesh_data **out)
{
    off_reader r;
    memset(&r, 0, sizeof r);
    r.ctx = ctx;
    r.name = name;
    r.p = buf;
    r.buf_end = buf + size;
    cfi_mesh_builder b;
    cfi_builder_init(&b, ctx);
    cf_status st = read_body(&r, &b);
    if (st != CF_OK) {
        cfi_builder_free(&b);
        return st;
    }
    if (b.polygon_count > 0)
        cfi_log(ctx, CF_LOG_WARNING, "%s: %d polygons with more than 3 vertices were fan-triangulated", name,
                b.polygon_count);
    return cfi_builder_finish(&b, out);
}
