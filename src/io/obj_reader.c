/*
 * Wavefront OBJ reader: v, vt and f (v, v/vt, v/vt/vn, v//vn, negative
 * relative indices); polygons are fan-triangulated with one warning.
 * mtllib and usemtl are kept (cf_mesh_data's materials: the libraries, the
 * names, each triangle's material), so that writers can carry them.
 * Vertex colours `v x y z r g b` (the extension of MeshLab, ZBrush and most
 * scanners) become the vertex properties red, green, blue (0..255, as PLY's;
 * cfi_builder_add_colours) when every vertex has one; when only some do they
 * are dropped with a warning (session 30; they were ignored silently).
 * vn, vp, comments, o, g, s are ignored; any other keyword
 * is ignored with a single warning, as are v lines with values beyond
 * x y z [w] / x y z r g b. Lines come from the shared text input
 * (io/text.h: any length, byte-order mark skipped, NUL bytes refused).
 *
 * Decisions where the format is loose:
 *  - an index must refer to a v/vt defined on an earlier line (the usual
 *    reading of the spec; relative indices need it anyway);
 *  - texture coordinates are kept per corner when every face gives vt; if
 *    only some faces do, they are dropped with a warning;
 *  - truncation: a malformed line that is the last line of a file not ending
 *    in a newline is reported as CF_ERR_TRUNCATED instead of CF_ERR_PARSE
 *    (e.g. "f 93 165" cut from "f 93 1651 1513"). A cut that still leaves a
 *    well-formed line cannot be detected.
 */
#include "io/io_internal.h"
#include "io/text.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

typedef struct obj_line {
    const char *p;     /* cursor */
    const char *end;   /* end of line (the '\n' or the end of the buffer) */
    int64_t number;    /* 1-based */
    bool last_unterminated; /* last line of the file and no newline after it */
    const char *keyword;
} obj_line;

typedef struct obj_reader {
    cf_context *ctx;
    const char *name;
    cfi_mesh_builder b;
    int32_t nv, nvt;
    int uv_mode;          /* -1 undecided, 0 no uv, 1 per-corner uv */
    bool uv_dropped;
    bool warned_unknown;
    bool warned_vertex_values;
    cfi_buf libraries;      /* char *: the text after each mtllib */
    cfi_buf materials;      /* char *: usemtl names, in order of first use */
    cfi_buf face_materials; /* int32_t per triangle, from the first usemtl on (earlier ones -1) */
    int32_t material;       /* current: index into materials, -1 before any usemtl */
    cfi_buf colours;        /* double, r g b per vertex while every vertex so far has one */
    int32_t coloured;       /* vertices with a colour */
    bool colours_mixed;     /* some vertex has none: no colours are kept */
} obj_reader;


/* Records an error for the current line; a malformed (CF_ERR_PARSE) last
 * line without newline becomes CF_ERR_TRUNCATED. */
static cf_status fail(obj_reader *r, const obj_line *ln, cf_status st, const char *fmt, ...) CF_PRINTF(4, 5);
static cf_status fail(obj_reader *r, const obj_line *ln, cf_status st, const char *fmt, ...)
{
    char msg[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (st == CF_ERR_PARSE && ln->last_unterminated)
        return cfi_error(r->ctx, CF_ERR_TRUNCATED, "%s: line %lld: %s (file ends inside a %s line: truncated?)",
                         r->name, (long long)ln->number, msg, ln->keyword);
    return cfi_error(r->ctx, st, "%s: line %lld: %s", r->name, (long long)ln->number, msg);
}

/* The rest of the line after the keyword, without surrounding blanks, as a
 * new string in *out (NULL for an empty rest). */
static cf_status line_rest(obj_reader *r, obj_line *ln, char **out)
{
    const char *s = ln->p, *e = ln->end;
    while (s < e && cfi_is_space(*s)) ++s;
    while (e > s && cfi_is_space(e[-1])) --e;
    *out = NULL;
    if (s == e) return CF_OK;
    char *t = cfi_malloc(r->ctx, (size_t)(e - s) + 1);
    if (!t) return CF_ERR_NOMEM;
    memcpy(t, s, (size_t)(e - s));
    t[e - s] = '\0';
    *out = t;
    return CF_OK;
}

static cf_status push_string(obj_reader *r, cfi_buf *b, char *t)
{
    if (b->count == b->cap && cfi_buf_reserve(r->ctx, b, 1) != CF_OK) {
        cfi_free(r->ctx, t, strlen(t) + 1);
        return CF_ERR_NOMEM;
    }
    ((char **)b->data)[b->count++] = t;
    return CF_OK;
}

static cf_status parse_mtllib(obj_reader *r, obj_line *ln)
{
    char *t = NULL;
    cf_status st = line_rest(r, ln, &t);
    if (st != CF_OK || !t) return st == CF_OK ? fail(r, ln, CF_ERR_PARSE, "mtllib without a file name") : st;
    return push_string(r, &r->libraries, t);
}

/* usemtl NAME: the material of the faces that follow. The triangles before
 * the first usemtl get -1. */
static cf_status parse_usemtl(obj_reader *r, obj_line *ln)
{
    char *t = NULL;
    cf_status st = line_rest(r, ln, &t);
    if (st != CF_OK || !t) return st == CF_OK ? fail(r, ln, CF_ERR_PARSE, "usemtl without a material name") : st;
    char **names = r->materials.data;
    for (size_t i = 0; i < r->materials.count; ++i)
        if (strcmp(names[i], t) == 0) {
            cfi_free(r->ctx, t, strlen(t) + 1);
            r->material = (int32_t)i;
            return CF_OK;
        }
    if (r->material < 0 && r->materials.count == 0) { /* the first: earlier triangles have none */
        size_t nf = r->b.triangles.count / 3;
        if (nf > 0 && cfi_buf_reserve(r->ctx, &r->face_materials, nf) != CF_OK) {
            cfi_free(r->ctx, t, strlen(t) + 1);
            return CF_ERR_NOMEM;
        }
        for (size_t f = 0; f < nf; ++f) ((int32_t *)r->face_materials.data)[r->face_materials.count++] = -1;
    }
    st = push_string(r, &r->materials, t);
    if (st == CF_OK) r->material = (int32_t)(r->materials.count - 1);
    return st;
}

static void free_string_buf(cf_context *ctx, cfi_buf *b)
{
    char **s = b->data;
    for (size_t i = 0; i < b->count; ++i) cfi_free(ctx, s[i], strlen(s[i]) + 1);
    cfi_buf_free(ctx, b);
}

static void free_materials(obj_reader *r)
{
    free_string_buf(r->ctx, &r->libraries);
    free_string_buf(r->ctx, &r->materials);
    cfi_buf_free(r->ctx, &r->face_materials);
}

/* Moves the materials into the finished data (freeing them on failure). */
static cf_status give_materials(obj_reader *r, cf_mesh_data *d)
{
    int32_t nl = (int32_t)r->libraries.count, nm = (int32_t)r->materials.count;
    void *libs = NULL, *names = NULL, *faces = NULL;
    if (cfi_buf_take(r->ctx, &r->libraries, &libs) != CF_OK ||
        cfi_buf_take(r->ctx, &r->materials, &names) != CF_OK ||
        (nm > 0 && cfi_buf_take(r->ctx, &r->face_materials, &faces) != CF_OK)) {
        cfi_free_strings(r->ctx, libs, nl);
        cfi_free_strings(r->ctx, names, nm);
        free_materials(r);
        return CF_ERR_NOMEM;
    }
    cfi_buf_free(r->ctx, &r->face_materials);
    d->material_library_count = libs ? nl : 0;
    d->material_libraries = libs;
    d->material_count = names ? nm : 0;
    d->material_names = names;
    d->face_materials = faces;
    return CF_OK;
}

/* Next whitespace-separated token of the line; false at the end. */
static bool next_token(obj_line *ln, const char **s, const char **e)
{
    const char *p = ln->p;
    while (p < ln->end && cfi_is_space(*p)) ++p;
    if (p >= ln->end) {
        ln->p = p;
        return false;
    }
    *s = p;
    while (p < ln->end && !cfi_is_space(*p)) ++p;
    *e = p;
    ln->p = p;
    return true;
}

static cf_status parse_vertex(obj_reader *r, obj_line *ln)
{
    double x[3];
    const char *s, *e;
    for (int k = 0; k < 3; ++k) {
        if (!next_token(ln, &s, &e))
            return fail(r, ln, CF_ERR_PARSE, "vertex %d has %d coordinates, expected 3", r->nv, k);
        if (!cfi_parse_double(s, e, &x[k]))
            return fail(r, ln, CF_ERR_PARSE, "vertex %d: bad number '%.*s'", r->nv, (int)(e - s > 40 ? 40 : e - s), s);
    }
    /* x y z w (the spec) is read, w ignored; x y z r g b (the colour
     * extension of many writers) keeps its colour; any other count, or a
     * token that is not a number, is input we would drop without a word: say
     * so once. */
    int extra = 0;
    const char *first_s = NULL, *first_e = NULL;
    bool all_numbers = true;
    double rgb[3] = {0.0, 0.0, 0.0};
    while (next_token(ln, &s, &e)) {
        double v = 0.0;
        if (extra == 0) {
            first_s = s;
            first_e = e;
        }
        all_numbers = all_numbers && cfi_parse_double(s, e, &v);
        if (extra < 3) rgb[extra] = v;
        ++extra;
    }
    bool coloured = extra == 3 && all_numbers && isfinite(rgb[0]) && isfinite(rgb[1]) && isfinite(rgb[2]);
    r->coloured += coloured;
    if (coloured && !r->colours_mixed && r->colours.count == 3 * (size_t)r->nv) {
        if (cfi_buf_reserve(r->ctx, &r->colours, 3) != CF_OK) return CF_ERR_NOMEM;
        memcpy((double *)r->colours.data + r->colours.count, rgb, sizeof rgb);
        r->colours.count += 3;
    } else if (coloured || r->colours.count > 0) {
        r->colours_mixed = true; /* a vertex without colour after coloured ones, or the reverse */
    }
    if ((extra == 2 || extra > 3 || !all_numbers) && !r->warned_vertex_values) {
        cfi_log(r->ctx, CF_LOG_WARNING,
                "%s: line %lld: vertex %d has %d values, expected x y z [w] or x y z r g b; the values after z "
                "('%.*s' ...) are ignored (further such lines silently)",
                r->name, (long long)ln->number, r->nv, 3 + extra, cfi_tok_len(first_s, first_e), first_s);
        r->warned_vertex_values = true;
    }
    if (!isfinite(x[0]) || !isfinite(x[1]) || !isfinite(x[2]))
        return fail(r, ln, CF_ERR_NONFINITE, "vertex %d has a non-finite coordinate", r->nv);
    if (r->nv >= CFI_MAX_ELEMENTS) return fail(r, ln, CF_ERR_PARSE, "too many vertices");
    cf_context *ctx = r->ctx;
    cfi_buf *pos = &r->b.positions;
    if (cfi_buf_reserve(ctx, pos, 3) != CF_OK) return CF_ERR_NOMEM;
    double *dst = (double *)pos->data + pos->count;
    dst[0] = x[0];
    dst[1] = x[1];
    dst[2] = x[2];
    pos->count += 3;
    r->nv++;
    return CF_OK;
}

static cf_status parse_texcoord(obj_reader *r, obj_line *ln)
{
    double t[2] = {0.0, 0.0};
    const char *s, *e;
    int k = 0;
    for (; k < 2 && next_token(ln, &s, &e); ++k)
        if (!cfi_parse_double(s, e, &t[k]))
            return fail(r, ln, CF_ERR_PARSE, "texture coordinate %d: bad number '%.*s'", r->nvt,
                        (int)(e - s > 40 ? 40 : e - s), s);
    if (k == 0) return fail(r, ln, CF_ERR_PARSE, "texture coordinate %d has no values", r->nvt);
    if (!isfinite(t[0]) || !isfinite(t[1]))
        return fail(r, ln, CF_ERR_NONFINITE, "texture coordinate %d is not finite", r->nvt);
    if (r->nvt >= INT32_MAX / 2) return fail(r, ln, CF_ERR_PARSE, "too many texture coordinates");
    if (cfi_buf_reserve(r->ctx, &r->b.uv, 2) != CF_OK) return CF_ERR_NOMEM;
    double *dst = (double *)r->b.uv.data + r->b.uv.count;
    dst[0] = t[0];
    dst[1] = t[1];
    r->b.uv.count += 2;
    r->nvt++;
    return CF_OK;
}

/* Resolves a 1-based (or negative, relative) OBJ index against `count`
 * elements defined so far; -1 if out of range. */
static int64_t resolve(int64_t idx, int32_t count)
{
    if (idx > 0) return idx <= count ? idx - 1 : -1;
    if (idx < 0) return -idx <= count ? count + idx : -1;
    return -1;
}

/* One corner token: v, v/vt, v/vt/vn or v//vn. */
static cf_status parse_corner(obj_reader *r, obj_line *ln, const char *s, const char *e, int32_t *v, int32_t *vt)
{
    const char *slash1 = memchr(s, '/', (size_t)(e - s));
    const char *vend = slash1 ? slash1 : e;
    int64_t iv = 0, it = 0, in = 0;
    int tl = (int)(e - s > 40 ? 40 : e - s);
    if (!cfi_parse_int(s, vend, &iv)) return fail(r, ln, CF_ERR_PARSE, "bad face index '%.*s'", tl, s);
    *vt = -1;
    bool has_vt = false;
    const char *tend = e;
    if (slash1) {
        const char *t = slash1 + 1;
        const char *slash2 = memchr(t, '/', (size_t)(e - t));
        tend = slash2 ? slash2 : e;
        if (tend > t) {
            if (!cfi_parse_int(t, tend, &it)) return fail(r, ln, CF_ERR_PARSE, "bad face index '%.*s'", tl, s);
            has_vt = true;
        } else if (!slash2) {
            return fail(r, ln, CF_ERR_PARSE, "bad face index '%.*s'", tl, s); /* "v/" */
        }
        /* The normal index is checked for syntax only: normals are ignored. */
        if (slash2 && !cfi_parse_int(slash2 + 1, e, &in))
            return fail(r, ln, CF_ERR_PARSE, "bad face index '%.*s'", tl, s);
    }
    /* Out-of-range indices are quoted as written: a 26-digit index has
     * saturated in iv and would print as some other number. */
    int64_t rv = resolve(iv, r->nv);
    if (rv < 0)
        return fail(r, ln, CF_ERR_INDEX_RANGE, "vertex index %.*s out of range (%d vertices defined so far)",
                    cfi_tok_len(s, vend), s, r->nv);
    *v = (int32_t)rv;
    if (has_vt) {
        int64_t rt = resolve(it, r->nvt);
        if (rt < 0)
            return fail(r, ln, CF_ERR_INDEX_RANGE,
                        "texture index %.*s out of range (%d texture coordinates defined so far)",
                        cfi_tok_len(slash1 + 1, tend), slash1 + 1, r->nvt);
        *vt = (int32_t)rt;
    }
    return CF_OK;
}

static cf_status parse_face(obj_reader *r, obj_line *ln)
{
    cf_context *ctx = r->ctx;
    const char *s, *e;
    int32_t v0 = -1, t0 = -1, vp = -1, tp = -1;
    int64_t corners = 0;
    int face_uv = -1;
    while (next_token(ln, &s, &e)) {
        int32_t v = -1, t = -1;
        cf_status st = parse_corner(r, ln, s, e, &v, &t);
        if (st != CF_OK) return st;
        int this_uv = t >= 0;
        if (face_uv < 0) face_uv = this_uv;
        else if (face_uv != this_uv)
            return fail(r, ln, CF_ERR_PARSE, "face mixes corners with and without a texture index");
        if (corners == 0) {
            v0 = v;
            t0 = t;
        } else if (corners >= 2) {
            if (r->b.triangles.count / 3 >= CFI_MAX_ELEMENTS) return fail(r, ln, CF_ERR_PARSE, "too many faces");
            if (cfi_push_int3(ctx, &r->b.triangles, v0, vp, v) != CF_OK) return CF_ERR_NOMEM;
            if (r->materials.count > 0) {
                if (r->face_materials.count == r->face_materials.cap &&
                    cfi_buf_reserve(ctx, &r->face_materials, 1) != CF_OK)
                    return CF_ERR_NOMEM;
                ((int32_t *)r->face_materials.data)[r->face_materials.count++] = r->material;
            }
            if (r->uv_mode == 1 && !r->uv_dropped && face_uv == 1 &&
                cfi_push_int3(ctx, &r->b.uv_triangles, t0, tp, t) != CF_OK)
                return CF_ERR_NOMEM;
        }
        vp = v;
        tp = t;
        ++corners;
        if (corners == 2 && r->uv_mode < 0) r->uv_mode = face_uv;
    }
    if (corners < 3) return fail(r, ln, CF_ERR_PARSE, "face has %lld vertices", (long long)corners);
    if (!r->uv_dropped && face_uv != r->uv_mode) {
        cfi_log(ctx, CF_LOG_WARNING, "%s: line %lld: only some faces have texture indices; texture coordinates dropped",
                r->name, (long long)ln->number);
        r->uv_dropped = true;
    }
    if (corners > 3) {
        if (r->b.polygon_count == INT32_MAX) return fail(r, ln, CF_ERR_PARSE, "too many polygons");
        r->b.polygon_count++;
    }
    return CF_OK;
}

static bool is_word(const char *s, const char *e, const char *w)
{
    size_t n = strlen(w);
    return (size_t)(e - s) == n && memcmp(s, w, n) == 0;
}

cf_status cfi_read_obj(cf_context *ctx, const char *buf, size_t size, const char *name, cf_mesh_data **out)
{
    obj_reader r;
    memset(&r, 0, sizeof r);
    r.ctx = ctx;
    r.name = name;
    r.uv_mode = -1;
    r.material = -1;
    cfi_buf_init(&r.libraries, sizeof(char *));
    cfi_buf_init(&r.materials, sizeof(char *));
    cfi_buf_init(&r.face_materials, sizeof(int32_t));
    cfi_buf_init(&r.colours, sizeof(double));
    cf_status st = cfi_text_check_nul(ctx, name, buf, 0, size);
    if (st != CF_OK) return st;
    cfi_builder_init(&r.b, ctx);
    cfi_text text;
    cfi_text_init(&text, buf, size);
    obj_line ln;
    memset(&ln, 0, sizeof ln);
    while (st == CF_OK && cfi_text_next(&text)) {
        ln.p = text.s;
        ln.end = text.e;
        ln.number = text.line;
        ln.last_unterminated = text.unterminated;
        const char *s, *e;
        if (!next_token(&ln, &s, &e) || *s == '#') continue;
        if (is_word(s, e, "v")) {
            ln.keyword = "vertex";
            st = parse_vertex(&r, &ln);
        } else if (is_word(s, e, "vt")) {
            ln.keyword = "texture coordinate";
            st = parse_texcoord(&r, &ln);
        } else if (is_word(s, e, "f")) {
            ln.keyword = "face";
            st = parse_face(&r, &ln);
        } else if (is_word(s, e, "mtllib")) {
            ln.keyword = "mtllib";
            st = parse_mtllib(&r, &ln);
        } else if (is_word(s, e, "usemtl")) {
            ln.keyword = "usemtl";
            st = parse_usemtl(&r, &ln);
        } else if (is_word(s, e, "vn") || is_word(s, e, "vp") || is_word(s, e, "o") || is_word(s, e, "g") ||
                   is_word(s, e, "s")) {
            continue;
        } else if (!r.warned_unknown) {
            cfi_log(ctx, CF_LOG_WARNING, "%s: line %lld: unknown keyword '%.*s' ignored (further ones silently)", name,
                    (long long)ln.number, (int)(e - s > 40 ? 40 : e - s), s);
            r.warned_unknown = true;
        }
    }
    if (st == CF_OK && r.coloured > 0) {
        if (r.coloured == r.nv && !r.colours_mixed)
            st = cfi_builder_add_colours(&r.b, false, 3, r.colours.data, (size_t)r.nv, CFI_COLOURS_GUESS);
        else
            cfi_log(ctx, CF_LOG_WARNING,
                    "%s: %d of %d vertices give a colour (v x y z r g b): colours are kept only when every vertex "
                    "has one, these are dropped",
                    name, r.coloured, r.nv);
    }
    cfi_buf_free(ctx, &r.colours);
    if (st != CF_OK) {
        cfi_builder_free(&r.b);
        free_materials(&r);
        return st;
    }
    if (r.uv_mode == 1 && !r.uv_dropped) {
        r.b.uv_per_corner = true;
    } else {
        /* vt lines no face refers to carry no usable information. */
        cfi_buf_free(ctx, &r.b.uv);
        cfi_buf_free(ctx, &r.b.uv_triangles);
    }
    if (r.b.polygon_count > 0)
        cfi_log(ctx, CF_LOG_WARNING, "%s: %d polygons with more than 3 vertices were fan-triangulated", name,
                r.b.polygon_count);
    st = cfi_builder_finish(&r.b, out);
    if (st != CF_OK) {
        free_materials(&r);
        return st;
    }
    st = give_materials(&r, *out);
    if (st != CF_OK) cf_mesh_data_destroy(out);
    return st;
}
