/*
 * OFF reader (Geomview Object File Format, ASCII). Header keyword OFF with
 * the prefixes ST, C, N (texture coordinates, colour, normal per vertex,
 * written after x y z in the order normal, colour, texture); the keyword
 * itself may be omitted. Then "nv nf [ne]", nv vertex lines
 * "x y z [extra...]" and nf face lines "n i_0 ... i_{n-1} [colour...]" with
 * 0-based indices. Kept (session 30; they were dropped silently): a C
 * header's vertex colours (3 or 4 values: the properties red green blue
 * [alpha]), an ST header's texture coordinates (per-vertex uv), and face
 * colours of 3 or 4 values when every face has them (each triangle of a
 * polygon gets its colour). Colours written as integers are 0..255, as
 * floats 0..1 (the spec), stored as 0..255 (cfi_builder_add_colours).
 * Normals are ignored; a colour map index (one value) is ignored; extras
 * that do not fit the header, or colours on some faces only, are dropped
 * with one warning. '#' starts a
 * comment. The reader is line-based: one vertex or face per line, as every
 * OFF writer we know produces. Polygons are fan-triangulated.
 *
 * The header's counts are checked against the lines in both directions:
 * after the last face only blank and comment lines may follow, and a line
 * of the wrong kind where the counts put a vertex or a face is reported as
 * the mismatch ("header declares 3 vertices, file holds 4") rather than as
 * whatever that line fails to be.
 */
#include "io/io_internal.h"
#include "io/text.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* What the vertex and face lines carry beyond positions and indices. */
typedef struct off_extras {
    int vertex_colour_channels; /* 3 or 4 when the vertex colours are kept, else 0 */
    int vertex_colour_offset;   /* index of the first colour value after z */
    int texcoord_offset;        /* index of s after z when texture coordinates are kept, else -1 */
    bool vertex_colour_float;   /* a colour value was written as a float: 0..1 */
    cfi_buf vertex_colours;     /* double, channels per vertex */
    int face_colour_channels;   /* 0 before the first face, then 3 / 4; -1 when not kept */
    bool face_colour_float;
    int32_t faces_coloured;     /* faces that give 3 or 4 colour values */
    cfi_buf face_colours;       /* double, channels per triangle */
} off_extras;

typedef struct off_reader {
    cf_context *ctx;
    const char *name;
    cfi_text tx;                /* lines of the file */
    const char *ls;             /* start of the current line */
    const char *lp, *lend;      /* cursor and end of the current line (comment stripped) */
    int64_t line;
    bool last_unterminated;
    off_extras x;
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
    while (cfi_text_next(&r->tx)) {
        r->ls = r->lp = r->tx.s;
        r->lend = r->tx.e;
        r->last_unterminated = r->tx.unterminated;
        r->line = r->tx.line;
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
    return cfi_text_token(&r->lp, r->lend, NULL, s, e);
}

static int tok_len(const char *s, const char *e) { return cfi_tok_len(s, e); }

/* ---- shapes of lines, to name a count mismatch ------------------------------------ */

/* Tokens of [s, e). */
static int64_t count_tokens(const char *s, const char *e)
{
    int64_t n = 0;
    const char *ts, *te;
    while (cfi_text_token(&s, e, NULL, &ts, &te)) ++n;
    return n;
}

/* A face line: "n i_0 ... i_{n-1}" with n >= 3 non-negative integer
 * indices, then at most 4 colour values. */
static bool face_shaped(const char *s, const char *e)
{
    const char *ts, *te;
    int64_t n = 0, v = 0;
    if (!cfi_text_token(&s, e, NULL, &ts, &te) || !cfi_parse_int(ts, te, &n) || n < 3) return false;
    for (int64_t k = 0; k < n; ++k)
        if (!cfi_text_token(&s, e, NULL, &ts, &te) || !cfi_parse_int(ts, te, &v) || v < 0) return false;
    return count_tokens(s, e) <= 4;
}

/* A vertex line like the first one: the same number of tokens, all numbers. */
static bool vertex_shaped(const char *s, const char *e, int64_t vertex_tokens)
{
    const char *ts, *te;
    int64_t n = 0;
    double x;
    while (cfi_text_token(&s, e, NULL, &ts, &te)) {
        if (!cfi_parse_double(ts, te, &x)) return false;
        ++n;
    }
    return n == vertex_tokens;
}

/* Number of lines from the current one on (blank and comment lines
 * skipped) that are face lines (face) or vertex lines of vertex_tokens
 * values, up to the first that is not. *then_face (may be NULL) tells
 * whether that next line is a face line. The reader is not moved. */
static int64_t count_shaped(const off_reader *r, bool face, int64_t vertex_tokens, bool *then_face)
{
    off_reader c = *r;
    int64_t n = 0;
    bool more = true;
    do {
        if (face ? !face_shaped(c.ls, c.lend) : !vertex_shaped(c.ls, c.lend, vertex_tokens)) break;
        ++n;
    } while ((more = next_line(&c)));
    if (then_face) *then_face = more && face_shaped(c.ls, c.lend);
    return n;
}

/* Reads "nv nf [ne]" from the current line's remaining tokens. */
static cf_status read_counts(off_reader *r, int64_t *nv, int64_t *nf)
{
    const char *s[2], *e[2];
    int64_t c[2];
    for (int k = 0; k < 2; ++k) {
        if (!next_token(r, &s[k], &e[k])) return fail(r, CF_ERR_PARSE, "expected vertex and face counts");
        if (!cfi_parse_int(s[k], e[k], &c[k]) || c[k] < 0)
            return fail(r, CF_ERR_PARSE, "bad count '%.*s'", tok_len(s[k], e[k]), s[k]);
    }
    if (c[0] > CFI_MAX_ELEMENTS || c[1] > CFI_MAX_ELEMENTS) /* quoted as written: they may have saturated */
        return fail(r, CF_ERR_PARSE, "counts %.*s vertices, %.*s faces are too large", tok_len(s[0], e[0]), s[0],
                    tok_len(s[1], e[1]), s[1]);
    *nv = c[0];
    *nf = c[1];
    return CF_OK;
}

/* Called after the coordinates of vertex i were read: a line that has
 * another number of values than vertex 0's and reads as a face means the
 * header declares more vertices than the file holds (else the face would
 * be taken for a vertex, its extra values ignored as colours). */
static cf_status check_vertex_line(off_reader *r, int64_t i, int64_t nv, int64_t vertex_tokens)
{
    /* only the values after z are counted (none in plain OFF): the line is
     * parsed again only in the rare case that it differs */
    if (i == 0 || 3 + count_tokens(r->lp, r->lend) == vertex_tokens || !face_shaped(r->ls, r->lend)) return CF_OK;
    return fail(r, CF_ERR_PARSE, "header declares %lld vertices, file holds %lld (this line is a face)",
                (long long)nv, (long long)i);
}

/* After an error on the line of face f: if that line is no face but a
 * vertex line (face 0), and the lines after the vertex lines are faces,
 * the header declared too few vertices; the original error otherwise (a
 * cut face "3 0 1" also looks like a vertex). */
static cf_status diagnose_face_line(off_reader *r, cf_status st, int64_t f, int64_t nv, int64_t vertex_tokens)
{
    if (st == CF_ERR_NOMEM || f != 0 || nv == 0 || face_shaped(r->ls, r->lend) ||
        !vertex_shaped(r->ls, r->lend, vertex_tokens))
        return st;
    bool then_face = false;
    int64_t extra = count_shaped(r, false, vertex_tokens, &then_face);
    if (!then_face) return st;
    return fail(r, CF_ERR_PARSE, "header declares %lld vertices, file holds %lld", (long long)nv,
                (long long)(nv + extra));
}

/* A token written as an integer (no '.', exponent, inf or nan). */
static bool integer_token(const char *s, const char *e)
{
    for (const char *c = s; c < e; ++c)
        if (!(*c >= '0' && *c <= '9') && *c != '-' && *c != '+') return false;
    return true;
}

/* The colour after a face's indices: kept while every face so far has one
 * of the same number of values (3 or 4), for each of its `triangles`. */
static cf_status read_face_colour(off_reader *r, int64_t triangles)
{
    off_extras *x = &r->x;
    const char *s, *e;
    double c[4];
    int k = 0;
    bool numbers = true;
    while (next_token(r, &s, &e)) {
        double v = 0.0;
        numbers = numbers && cfi_parse_double(s, e, &v) && isfinite(v);
        if (k < 4) c[k] = v;
        x->face_colour_float = x->face_colour_float || !integer_token(s, e);
        ++k;
    }
    bool coloured = numbers && (k == 3 || k == 4);
    x->faces_coloured += coloured;
    if (x->face_colour_channels == 0) x->face_colour_channels = coloured ? k : -1; /* the first face decides */
    if (x->face_colour_channels < 0) return CF_OK;
    if (!coloured || k != x->face_colour_channels) {
        x->face_colour_channels = -1;
        return CF_OK;
    }
    if (cfi_buf_reserve(r->ctx, &x->face_colours, (size_t)(k * triangles)) != CF_OK) return CF_ERR_NOMEM;
    for (int64_t t = 0; t < triangles; ++t)
        for (int i = 0; i < k; ++i) ((double *)x->face_colours.data)[x->face_colours.count++] = c[i];
    return CF_OK;
}

static cf_status read_face(off_reader *r, cfi_mesh_builder *b, int64_t f, int64_t nv)
{
    cf_context *ctx = r->ctx;
    const char *s, *e;
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
        if (v < 0 || v >= nv) /* quoted as written: a huge index has saturated in v */
            return fail(r, CF_ERR_INDEX_RANGE, "face %lld: vertex index %.*s out of range [0, %lld)", (long long)f,
                        tok_len(s, e), s, (long long)nv);
        if (k == 0) v0 = (int32_t)v;
        else if (k >= 2) {
            if (b->triangles.count / 3 >= CFI_MAX_ELEMENTS) return fail(r, CF_ERR_PARSE, "too many triangles");
            if (cfi_push_int3(ctx, &b->triangles, v0, vp, (int32_t)v) != CF_OK) return CF_ERR_NOMEM;
        }
        vp = (int32_t)v;
    }
    if (n > 3) b->polygon_count++;
    return read_face_colour(r, n - 2);
}

/* The layout of the values after x y z from the header's prefixes and
 * vertex 0's line (`extra` values): normal (N, 3), colour (C, 3 or 4),
 * texture coordinates (ST, 2), in that order. What does not fit is dropped
 * with a warning. */
static void plan_vertex_extras(off_reader *r, bool has_st, bool has_c, bool has_n, int64_t extra)
{
    off_extras *x = &r->x;
    x->texcoord_offset = -1;
    if ((!has_st && !has_c) || extra < 0) return; /* extra < 0: vertex 0 lacks a coordinate, an error follows */
    int64_t fixed = 3 * has_n + 2 * has_st, colour = has_c ? extra - fixed : 0;
    if (extra < fixed || (has_c && colour != 3 && colour != 4) || (!has_c && extra != fixed)) {
        cfi_log(r->ctx, CF_LOG_WARNING,
                "%s: line %lld: vertex 0 has %lld values after x y z, which do not fit the header's %s%s%s "
                "(normal 3, colour 3 or 4, texture 2): its colours and texture coordinates are not kept",
                r->name, (long long)r->line, (long long)extra, has_st ? "ST" : "", has_c ? "C" : "",
                has_n ? "N" : "");
        return;
    }
    x->vertex_colour_channels = (int)colour;
    x->vertex_colour_offset = 3 * has_n;
    if (has_st) x->texcoord_offset = (int)(3 * has_n + colour);
}

/* Vertex i's colour and texture coordinates, after its x y z (the cursor
 * is there). A line with another number of values than vertex 0's ends
 * keeping them, with a warning. */
static cf_status read_vertex_extras(off_reader *r, cfi_mesh_builder *b, int64_t i, int64_t extra)
{
    off_extras *x = &r->x;
    if (x->vertex_colour_channels == 0 && x->texcoord_offset < 0) return CF_OK;
    double v[16];
    int64_t k = 0;
    const char *s, *e;
    bool numbers = true;
    while (next_token(r, &s, &e)) {
        double d = 0.0;
        numbers = numbers && cfi_parse_double(s, e, &d) && isfinite(d);
        if (k < 16) v[k] = d;
        if (x->vertex_colour_channels > 0 && k >= x->vertex_colour_offset &&
            k < x->vertex_colour_offset + x->vertex_colour_channels)
            x->vertex_colour_float = x->vertex_colour_float || !integer_token(s, e);
        ++k;
    }
    if (k != extra || !numbers) {
        cfi_log(r->ctx, CF_LOG_WARNING,
                "%s: line %lld: vertex %lld has %lld values after x y z, vertex 0 has %lld%s: the vertex colours and "
                "texture coordinates are not kept",
                r->name, (long long)r->line, (long long)i, (long long)k, (long long)extra,
                numbers ? "" : " (or one is not a finite number)");
        x->vertex_colour_channels = 0;
        x->texcoord_offset = -1;
        cfi_buf_free(r->ctx, &x->vertex_colours);
        cfi_buf_free(r->ctx, &b->uv);
        return CF_OK;
    }
    int c = x->vertex_colour_channels;
    if (c > 0) {
        if (cfi_buf_reserve(r->ctx, &x->vertex_colours, (size_t)c) != CF_OK) return CF_ERR_NOMEM;
        memcpy((double *)x->vertex_colours.data + x->vertex_colours.count, v + x->vertex_colour_offset,
               (size_t)c * sizeof(double));
        x->vertex_colours.count += (size_t)c;
    }
    if (x->texcoord_offset >= 0) {
        if (cfi_buf_reserve(r->ctx, &b->uv, 2) != CF_OK) return CF_ERR_NOMEM;
        memcpy((double *)b->uv.data + b->uv.count, v + x->texcoord_offset, 2 * sizeof(double));
        b->uv.count += 2;
    }
    return CF_OK;
}

/* Moves the kept colours into properties; warns about face colours that
 * only some faces give. */
static cf_status finish_extras(off_reader *r, cfi_mesh_builder *b, int64_t nv, int64_t nf)
{
    off_extras *x = &r->x;
    cf_status st = CF_OK;
    if (x->vertex_colour_channels > 0 && x->vertex_colours.count == (size_t)(nv * x->vertex_colour_channels)) {
        st = cfi_builder_add_colours(b, false, x->vertex_colour_channels, x->vertex_colours.data, (size_t)nv,
                                     x->vertex_colour_float ? CFI_COLOURS_UNIT : CFI_COLOURS_BYTES);
    }
    size_t nt = b->triangles.count / 3;
    if (st == CF_OK && x->face_colour_channels > 0 && x->face_colours.count == nt * (size_t)x->face_colour_channels)
        st = cfi_builder_add_colours(b, true, x->face_colour_channels, x->face_colours.data, nt,
                                     x->face_colour_float ? CFI_COLOURS_UNIT : CFI_COLOURS_BYTES);
    else if (st == CF_OK && x->faces_coloured > 0)
        cfi_log(r->ctx, CF_LOG_WARNING,
                "%s: %d of %lld faces give a colour (3 or 4 values, the same count on every face): face colours are "
                "kept only when every face has one, these are dropped",
                r->name, x->faces_coloured, (long long)nf);
    return st;
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
    bool has_st = false, has_c = false, has_n = false;
    if (len >= 3 && cfi_word_eq(e - 3, 3, "OFF")) {
        for (const char *c = s; c < e - 3; ++c)
            if (!strchr("STCNstcn", *c))
                return fail(r, CF_ERR_UNSUPPORTED, "unsupported OFF variant '%.*s'", tok_len(s, e), s);
        has_st = len >= 5 && cfi_word_eq(s, 2, "ST");
        for (const char *c = s + (has_st ? 2 : 0); c < e - 3; ++c) {
            has_c = has_c || *c == 'C' || *c == 'c';
            has_n = has_n || *c == 'N' || *c == 'n';
        }
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
    /* Each vertex line takes at least 6 bytes ("0 0 0\n"), each face line 8
     * ("3 0 1 2\n"): reject a header promising far more than the file can
     * hold before allocating anything for it (half the minimum, so that a
     * file cut a little short still gets the precise message below). */
    size_t remaining = (size_t)(r->tx.end - r->tx.p);
    if ((uint64_t)nv * 3 + (uint64_t)nf * 4 > (uint64_t)remaining + 1)
        return fail(r, CF_ERR_TRUNCATED, "header declares %lld vertices and %lld faces but only %zu bytes follow",
                    (long long)nv, (long long)nf, remaining);
    if (cfi_buf_reserve(ctx, &b->positions, (size_t)nv * 3) != CF_OK) return CF_ERR_NOMEM;
    if (cfi_buf_reserve(ctx, &b->triangles, (size_t)nf * 3) != CF_OK) return CF_ERR_NOMEM;
    double *pos = b->positions.data;
    int64_t vertex_tokens = 0; /* values on the line of vertex 0 */
    for (int64_t i = 0; i < nv; ++i) {
        if (!next_line(r))
            return cfi_error(ctx, CF_ERR_TRUNCATED, "%s: header declares %lld vertices, file holds %lld", r->name,
                             (long long)nv, (long long)i);
        if (i == 0) {
            vertex_tokens = count_tokens(r->ls, r->lend);
            plan_vertex_extras(r, has_st, has_c, has_n, vertex_tokens - 3);
        }
        for (int k = 0; k < 3; ++k) {
            if (!next_token(r, &s, &e))
                return fail(r, CF_ERR_PARSE, "vertex %lld has %d coordinates, expected 3", (long long)i, k);
            if (!cfi_parse_double(s, e, &pos[3 * i + k]))
                return fail(r, CF_ERR_PARSE, "vertex %lld: bad number '%.*s'", (long long)i, tok_len(s, e), s);
        }
        if ((st = check_vertex_line(r, i, nv, vertex_tokens)) != CF_OK) return st;
        if (!isfinite(pos[3 * i]) || !isfinite(pos[3 * i + 1]) || !isfinite(pos[3 * i + 2]))
            return fail(r, CF_ERR_NONFINITE, "vertex %lld has a non-finite coordinate", (long long)i);
        b->positions.count += 3;
        if ((st = read_vertex_extras(r, b, i, vertex_tokens - 3)) != CF_OK) return st;
    }
    for (int64_t f = 0; f < nf; ++f) {
        if (!next_line(r))
            return cfi_error(ctx, CF_ERR_TRUNCATED, "%s: header declares %lld faces, file holds %lld", r->name,
                             (long long)nf, (long long)f);
        if ((st = read_face(r, b, f, nv)) != CF_OK) return diagnose_face_line(r, st, f, nv, vertex_tokens);
    }
    /* After the last face only blank lines and comments may follow: more
     * faces than declared would otherwise be dropped without a word. */
    if (next_line(r)) {
        if (face_shaped(r->ls, r->lend))
            return fail(r, CF_ERR_PARSE, "header declares %lld faces, file holds %lld", (long long)nf,
                        (long long)(nf + count_shaped(r, true, 0, NULL)));
        const char *ts = r->lp, *te = r->lp;
        next_token(r, &ts, &te);
        return fail(r, CF_ERR_PARSE, "data after the last face ('%.*s'; the header declares %lld faces)",
                    tok_len(ts, te), ts, (long long)nf);
    }
    return finish_extras(r, b, nv, nf);
}

cf_status cfi_read_off(cf_context *ctx, const char *buf, size_t size, const char *name, cf_mesh_data **out)
{
    off_reader r;
    memset(&r, 0, sizeof r);
    r.ctx = ctx;
    r.name = name;
    cf_status st = cfi_text_check_nul(ctx, name, buf, 0, size);
    if (st != CF_OK) return st;
    cfi_text_init(&r.tx, buf, size);
    cfi_mesh_builder b;
    cfi_builder_init(&b, ctx);
    cfi_buf_init(&r.x.vertex_colours, sizeof(double));
    cfi_buf_init(&r.x.face_colours, sizeof(double));
    st = read_body(&r, &b);
    cfi_buf_free(ctx, &r.x.vertex_colours);
    cfi_buf_free(ctx, &r.x.face_colours);
    if (st != CF_OK) {
        cfi_builder_free(&b);
        return st;
    }
    if (b.polygon_count > 0)
        cfi_log(ctx, CF_LOG_WARNING, "%s: %d polygons with more than 3 vertices were fan-triangulated", name,
                b.polygon_count);
    return cfi_builder_finish(&b, out);
}
