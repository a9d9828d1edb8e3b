/*
 * PLY reader (Turk's polygon file format): ascii, binary_little_endian and
 * binary_big_endian. The vertex element gives x, y, z (any scalar type);
 * every other scalar vertex property is kept by name as doubles, except
 * texture coordinates (u,v or s,t or texture_u,texture_v), which become
 * per-vertex uv. The face element gives a list vertex_indices (or
 * vertex_index) of any count/index types, an optional list texcoord
 * (u0 v0 u1 v1 ..., MeshLab's per-corner uv) and scalar properties kept by
 * name. Other elements, and list properties we do not use, are skipped.
 *
 * Every count in the header is checked against the bytes that follow it
 * (an element needs at least one byte per scalar in binary, two in ascii)
 * before anything is allocated for it, and against the data itself in both
 * directions: data after the last element (other than blank lines in
 * ascii) is an error, as is an ascii line that holds another element than
 * the one the header's counts put there; both name the counts ("header
 * declares 2 faces, file holds 4"). In ascii each element is one line, as
 * the format defines it. Values outside the range of their declared type
 * are kept as read, with one warning per file.
 */
#include "io/io_internal.h"
#include "io/text.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

typedef enum ply_type { T_NONE = 0, T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_F32, T_F64 } ply_type;

static const size_t type_size[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};
static const char *const type_name[] = {"?", "char", "uchar", "short", "ushort", "int", "uint", "float", "double"};

typedef enum prop_role {
    R_SKIP = 0,   /* read and ignore */
    R_X, R_Y, R_Z, R_U, R_V,
    R_EXTRA,      /* kept by name (slot = builder property index) */
    R_INDICES,    /* face vertex list */
    R_TEXCOORD    /* face per-corner uv list */
} prop_role;

typedef struct ply_prop {
    const char *name;
    size_t name_len;
    ply_type type;        /* scalar type, or item type of a list */
    ply_type count_type;  /* T_NONE for a scalar */
    prop_role role;
    int32_t slot;
} ply_prop;

typedef enum elem_kind { E_OTHER = 0, E_VERTEX = 1, E_FACE = 2 } elem_kind;

typedef struct ply_elem {
    const char *name;
    size_t name_len;
    const char *count_text;   /* the count as written in the header */
    size_t count_len;
    int64_t count;
    elem_kind kind;
    size_t first_prop, prop_count; /* into the property table */
} ply_elem;

typedef enum ply_encoding { ENC_ASCII, ENC_LE, ENC_BE } ply_encoding;

typedef struct ply_reader {
    cf_context *ctx;
    const char *name;
    const char *base;      /* the buffer as given (offsets in messages) */
    const char *p, *end;   /* binary: next byte */
    cfi_text tx;           /* ascii data: lines */
    const char *lp, *lend; /* ascii data: cursor and end of the current element's line */
    int32_t line_values;   /* ascii data: values read from the current line */
    const char *tok, *tok_end; /* ascii data: the last value read, as written */
    bool in_instance;      /* an element's data has begun (for the diagnosis of errors) */
    bool warned_range;
    int64_t line;          /* header, ascii data: line of the current token */
    bool in_header;
    bool vertex_uv;        /* the vertex element has a u,v pair */
    ply_encoding enc;
    cfi_buf elems;         /* ply_elem */
    cfi_buf props;         /* ply_prop */
    cfi_mesh_builder b;
    int64_t nv;            /* vertex count from the header */
    cfi_buf poly;          /* int32_t: indices of the current face */
    cfi_buf texc;          /* double: texcoord list of the current face */
    double *face_extra;    /* one value per face extra property */
    size_t face_extra_count;
} ply_reader;

static cf_status fail(ply_reader *r, cf_status st, const char *fmt, ...) CF_PRINTF(3, 4);
static cf_status fail(ply_reader *r, cf_status st, const char *fmt, ...)
{
    char msg[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if ((r->in_header || r->enc == ENC_ASCII) && r->line > 0)
        return cfi_error(r->ctx, st, "%s: line %lld: %s", r->name, (long long)r->line, msg);
    return cfi_error(r->ctx, st, "%s: %s", r->name, msg);
}

static int clip(size_t n) { return (int)(n > 40 ? 40 : n); }

/* ---- header ----------------------------------------------------------------------- */

static ply_type parse_type(const char *s, size_t n)
{
    static const struct {
        const char *name;
        ply_type type;
    } names[] = {{"char", T_I8},     {"int8", T_I8},    {"uchar", T_U8},   {"uint8", T_U8},     {"short", T_I16},
                 {"int16", T_I16},   {"ushort", T_U16}, {"uint16", T_U16}, {"int", T_I32},      {"int32", T_I32},
                 {"uint", T_U32},    {"uint32", T_U32}, {"float", T_F32},  {"float32", T_F32},  {"double", T_F64},
                 {"float64", T_F64}};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i)
        if (strlen(names[i].name) == n && memcmp(names[i].name, s, n) == 0) return names[i].type;
    return T_NONE;
}

/* Splits the header line [s, e) into at most 8 tokens. */
static int split(const char *s, const char *e, const char **ts, const char **te)
{
    int n = 0;
    while (n < 8) {
        while (s < e && cfi_is_space(*s)) ++s;
        if (s >= e) break;
        ts[n] = s;
        while (s < e && !cfi_is_space(*s)) ++s;
        te[n++] = s;
    }
    return n;
}

static bool tok_is(const char *s, const char *e, const char *w)
{
    size_t n = strlen(w);
    return (size_t)(e - s) == n && memcmp(s, w, n) == 0;
}

static cf_status parse_header(ply_reader *r)
{
    cf_context *ctx = r->ctx;
    bool have_format = false;
    r->in_header = true;
    cfi_text tx;
    cfi_text_init(&tx, r->base, (size_t)(r->end - r->base)); /* after a byte-order mark */
    for (;;) {
        if (!cfi_text_next(&tx) || tx.unterminated)
            return cfi_error(ctx, tx.line == 0 ? CF_ERR_PARSE : CF_ERR_TRUNCATED, "%s: %s", r->name,
                             tx.line == 0 ? "empty file (expected a PLY header)" : "file ends inside the PLY header");
        const char *s = tx.s, *e = tx.e;
        r->line = tx.line;
        cf_status st = cfi_text_check_nul(ctx, r->name, r->base, (size_t)(s - r->base), (size_t)(e - r->base));
        if (st != CF_OK) return st;
        const char *ts[8], *te[8];
        int n = split(s, e, ts, te);
        if (tx.line == 1) {
            if (n != 1 || !tok_is(ts[0], te[0], "ply")) return fail(r, CF_ERR_PARSE, "not a PLY file (no 'ply' magic)");
            continue;
        }
        if (n == 0 || tok_is(ts[0], te[0], "comment") || tok_is(ts[0], te[0], "obj_info")) continue;
        if (tok_is(ts[0], te[0], "format")) {
            if (n < 2) return fail(r, CF_ERR_PARSE, "format line without an encoding");
            if (tok_is(ts[1], te[1], "ascii")) r->enc = ENC_ASCII;
            else if (tok_is(ts[1], te[1], "binary_little_endian")) r->enc = ENC_LE;
            else if (tok_is(ts[1], te[1], "binary_big_endian")) r->enc = ENC_BE;
            else return fail(r, CF_ERR_PARSE, "unknown PLY format '%.*s'", clip((size_t)(te[1] - ts[1])), ts[1]);
            have_format = true;
        } else if (tok_is(ts[0], te[0], "element")) {
            int64_t count;
            if (n != 3 || !cfi_parse_int(ts[2], te[2], &count) || count < 0)
                return fail(r, CF_ERR_PARSE, "bad element line (expected 'element <name> <count>')");
            if (cfi_buf_reserve(ctx, &r->elems, 1) != CF_OK) return CF_ERR_NOMEM;
            ply_elem *el = (ply_elem *)r->elems.data + r->elems.count++;
            memset(el, 0, sizeof *el);
            el->name = ts[1];
            el->name_len = (size_t)(te[1] - ts[1]);
            el->count_text = ts[2];
            el->count_len = (size_t)(te[2] - ts[2]);
            el->count = count;
            el->first_prop = r->props.count;
        } else if (tok_is(ts[0], te[0], "property")) {
            if (r->elems.count == 0) return fail(r, CF_ERR_PARSE, "property before any element");
            ply_prop pr;
            memset(&pr, 0, sizeof pr);
            if (n >= 2 && tok_is(ts[1], te[1], "list")) {
                if (n != 5) return fail(r, CF_ERR_PARSE, "bad list property (expected 'property list <count type> <type> <name>')");
                pr.count_type = parse_type(ts[2], (size_t)(te[2] - ts[2]));
                pr.type = parse_type(ts[3], (size_t)(te[3] - ts[3]));
                if (pr.count_type == T_NONE || pr.type == T_NONE)
                    return fail(r, CF_ERR_PARSE, "unknown PLY type in list property");
                if (pr.count_type == T_F32 || pr.count_type == T_F64)
                    return fail(r, CF_ERR_PARSE, "list count type must be an integer type");
                pr.name = ts[4];
                pr.name_len = (size_t)(te[4] - ts[4]);
            } else {
                if (n != 3) return fail(r, CF_ERR_PARSE, "bad property line (expected 'property <type> <name>')");
                pr.type = parse_type(ts[1], (size_t)(te[1] - ts[1]));
                if (pr.type == T_NONE)
                    return fail(r, CF_ERR_PARSE, "unknown PLY type '%.*s'", clip((size_t)(te[1] - ts[1])), ts[1]);
                pr.name = ts[2];
                pr.name_len = (size_t)(te[2] - ts[2]);
            }
            if (cfi_buf_reserve(ctx, &r->props, 1) != CF_OK) return CF_ERR_NOMEM;
            ((ply_prop *)r->props.data)[r->props.count++] = pr;
            ((ply_elem *)r->elems.data)[r->elems.count - 1].prop_count++;
        } else if (tok_is(ts[0], te[0], "end_header")) {
            break;
        } else {
            return fail(r, CF_ERR_PARSE, "unknown header line '%.*s'", clip((size_t)(te[0] - ts[0])), ts[0]);
        }
    }
    if (!have_format) return fail(r, CF_ERR_PARSE, "PLY header has no format line");
    r->p = tx.p;
    r->line = tx.line + 1; /* first data line (ascii) */
    r->in_header = false;
    if (r->enc == ENC_ASCII) {
        cf_status st = cfi_text_check_nul(ctx, r->name, r->base, (size_t)(r->p - r->base), (size_t)(r->end - r->base));
        if (st != CF_OK) return st;
        cfi_text_init_at(&r->tx, r->base, (size_t)(r->end - r->base), r->p, tx.line + 1);
    }
    return CF_OK;
}

/* The properties of an element (NULL when it has none: never offset a
 * NULL table). */
static ply_prop *elem_props(ply_reader *r, const ply_elem *el)
{
    return el->prop_count ? (ply_prop *)r->props.data + el->first_prop : NULL;
}

/* Assigns roles, checks counts against the data size, creates properties. */
static cf_status plan(ply_reader *r)
{
    ply_elem *els = r->elems.data;
    ply_prop *props = r->props.data;
    bool have_vertex = false, have_face = false;
    uint64_t remaining = (uint64_t)(r->end - r->p), needed = 0;
    for (size_t i = 0; i < r->elems.count; ++i) {
        ply_elem *el = &els[i];
        if (!have_vertex && tok_is(el->name, el->name + el->name_len, "vertex")) {
            el->kind = E_VERTEX;
            have_vertex = true;
        } else if (!have_face && tok_is(el->name, el->name + el->name_len, "face")) {
            el->kind = E_FACE;
            have_face = true;
        }
        /* Minimum bytes of one element: binary, every scalar and list count;
         * ascii, one character and one separator per value. */
        uint64_t min = 0;
        for (size_t k = 0; k < el->prop_count; ++k) {
            const ply_prop *pr = &props[el->first_prop + k];
            min += r->enc == ENC_ASCII ? 2 : type_size[pr->count_type != T_NONE ? pr->count_type : pr->type];
        }
        if (min > 0 && (uint64_t)el->count > (remaining + 1) / min)
            return cfi_error(r->ctx, CF_ERR_TRUNCATED,
                             "%s: header declares %.*s '%.*s' elements but only %llu bytes of data follow", r->name,
                             cfi_tok_len(el->count_text, el->count_text + el->count_len), el->count_text,
                             clip(el->name_len), el->name, (unsigned long long)remaining);
        needed += (uint64_t)el->count * min;
        if (needed > remaining + 1)
            return cfi_error(r->ctx, CF_ERR_TRUNCATED, "%s: header declares more elements than %llu bytes of data hold",
                             r->name, (unsigned long long)remaining);
        if (el->kind == E_OTHER) el->count = min == 0 ? 0 : el->count; /* nothing to read */
        if (el->kind != E_OTHER && el->count > CFI_MAX_ELEMENTS)
            return cfi_error(r->ctx, CF_ERR_PARSE, "%s: %lld %s elements are too many", r->name, (long long)el->count,
                             el->kind == E_VERTEX ? "vertex" : "face");
    }
    for (size_t i = 0; i < r->elems.count; ++i) {
        ply_elem *el = &els[i];
        if (el->kind == E_OTHER) continue;
        ply_prop *ep = elem_props(r, el);
        if (el->kind == E_VERTEX) {
            r->nv = el->count;
            static const char *const uv_names[3][2] = {{"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}};
            int xyz_found = 0;
            for (size_t k = 0; k < el->prop_count; ++k) {
                const char *s = ep[k].name, *e = s + ep[k].name_len;
                if (ep[k].count_type != T_NONE) continue;
                prop_role role = tok_is(s, e, "x") ? R_X : tok_is(s, e, "y") ? R_Y : tok_is(s, e, "z") ? R_Z : R_SKIP;
                if (role != R_SKIP && !(xyz_found & (1 << role))) {
                    ep[k].role = role;
                    xyz_found |= 1 << role;
                }
            }
            if (xyz_found != ((1 << R_X) | (1 << R_Y) | (1 << R_Z)))
                return cfi_error(r->ctx, CF_ERR_PARSE, "%s: vertex element lacks scalar x, y and z properties", r->name);
            for (int pair = 0; pair < 3; ++pair) {
                ply_prop *pu = NULL, *pv = NULL;
                for (size_t k = 0; k < el->prop_count; ++k) {
                    if (ep[k].count_type != T_NONE || ep[k].role != R_SKIP) continue;
                    const char *s = ep[k].name, *e = s + ep[k].name_len;
                    if (!pu && tok_is(s, e, uv_names[pair][0])) pu = &ep[k];
                    if (!pv && tok_is(s, e, uv_names[pair][1])) pv = &ep[k];
                }
                if (pu && pv) {
                    r->vertex_uv = true;
                    pu->role = R_U;
                    pv->role = R_V;
                    break;
                }
            }
            for (size_t k = 0; k < el->prop_count; ++k) {
                if (ep[k].count_type != T_NONE || ep[k].role != R_SKIP) continue;
                ep[k].role = R_EXTRA;
                cf_status st = cfi_builder_add_prop(&r->b, false, ep[k].name, ep[k].name_len, &ep[k].slot);
                if (st != CF_OK) return st == CF_ERR_PARSE ? fail(r, st, "bad vertex property name") : st;
            }
        } else {
            bool have_indices = false;
            for (size_t k = 0; k < el->prop_count; ++k) {
                const char *s = ep[k].name, *e = s + ep[k].name_len;
                if (ep[k].count_type != T_NONE) {
                    if (!have_indices && (tok_is(s, e, "vertex_indices") || tok_is(s, e, "vertex_index"))) {
                        ep[k].role = R_INDICES;
                        have_indices = true;
                    } else if (tok_is(s, e, "texcoord")) {
                        ep[k].role = R_TEXCOORD;
                    }
                    continue;
                }
                ep[k].role = R_EXTRA;
                cf_status st = cfi_builder_add_prop(&r->b, true, s, ep[k].name_len, &ep[k].slot);
                if (st != CF_OK) return st == CF_ERR_PARSE ? fail(r, st, "bad face property name") : st;
                r->face_extra_count++;
            }
            if (!have_indices)
                return cfi_error(r->ctx, CF_ERR_PARSE, "%s: face element has no vertex_indices list", r->name);
        }
    }
    return CF_OK;
}

/* ---- values ----------------------------------------------------------------------- */

/* "3 vertices", "1 face", "2 'edge' elements": a count of an element's instances. */
static void count_phrase(const ply_elem *el, int64_t n, char *buf, size_t size)
{
    if (el->kind == E_VERTEX) snprintf(buf, size, "%lld %s", (long long)n, n == 1 ? "vertex" : "vertices");
    else if (el->kind == E_FACE) snprintf(buf, size, "%lld %s", (long long)n, n == 1 ? "face" : "faces");
    else snprintf(buf, size, "%lld '%.*s' element%s", (long long)n, clip(el->name_len), el->name, n == 1 ? "" : "s");
}

/* The value of a binary scalar of type t at q (n = type_size[t] bytes available). */
static double decode(ply_encoding enc, ply_type t, const unsigned char *b)
{
    size_t n = type_size[t];
    uint64_t u = 0;
    for (size_t i = 0; i < n; ++i) u |= (uint64_t)b[enc == ENC_BE ? n - 1 - i : i] << (8 * i);
    double out = 0.0;
    switch (t) {
    case T_I8: out = (double)(int64_t)u - (u & 0x80u ? 256.0 : 0.0); break;
    case T_I16: out = (double)(int64_t)u - (u & 0x8000u ? 65536.0 : 0.0); break;
    case T_I32: out = (double)(int64_t)u - (u & 0x80000000u ? 4294967296.0 : 0.0); break;
    case T_U8:
    case T_U16:
    case T_U32: out = (double)u; break;
    case T_F32: {
        uint32_t w = (uint32_t)u;
        float f;
        memcpy(&f, &w, 4);
        out = (double)f;
        break;
    }
    case T_F64: memcpy(&out, &u, 8); break;
    case T_NONE: break;
    }
    return out;
}

/* Whether an ascii value can be stored in its declared type. */
static bool fits_type(ply_type t, double v)
{
    static const double lo[] = {0, -128, 0, -32768, 0, -2147483648.0, 0};
    static const double hi[] = {0, 127, 255, 32767, 65535, 2147483647.0, 4294967295.0};
    if (t == T_F64) return true;
    if (t == T_F32) return !isfinite(v) || fabs(v) <= FLT_MAX;
    return v == floor(v) && v >= lo[t] && v <= hi[t];
}

/* Next value of the current element as a double; `what` and `index` name
 * the element, `pr` the property (for the range warning). */
static cf_status read_value(ply_reader *r, const ply_prop *pr, ply_type t, double *out, const char *what, int64_t index)
{
    if (r->enc == ENC_ASCII) {
        const char *s, *e;
        if (!cfi_text_token(&r->lp, r->lend, NULL, &s, &e)) {
            if (r->tx.unterminated) return fail(r, CF_ERR_TRUNCATED, "file ends inside %s %lld", what, (long long)index);
            return fail(r, CF_ERR_PARSE, "%s %lld has too few values (the line ends after %d)", what,
                        (long long)index, r->line_values);
        }
        r->line_values++;
        r->tok = s;
        r->tok_end = e;
        if (!cfi_parse_double(s, e, out))
            return fail(r, CF_ERR_PARSE, "%s %lld: bad number '%.*s'", what, (long long)index, cfi_tok_len(s, e), s);
        if (!fits_type(t, *out) && !r->warned_range) {
            /* kept as read: the value is still the file's best statement */
            cfi_log(r->ctx, CF_LOG_WARNING,
                    "%s: line %lld: %s %lld: value %.*s of '%.*s' is not a valid %s (kept as read; further such "
                    "values silently)",
                    r->name, (long long)r->line, what, (long long)index, cfi_tok_len(s, e), s, clip(pr->name_len),
                    pr->name, type_name[t]);
            r->warned_range = true;
        }
        return CF_OK;
    }
    if ((size_t)(r->end - r->p) < type_size[t])
        return fail(r, CF_ERR_TRUNCATED, "binary data ends inside %s %lld", what, (long long)index);
    *out = decode(r->enc, t, (const unsigned char *)r->p);
    r->p += type_size[t];
    return CF_OK;
}

/* The last value read as it appears in the file (ascii: the token as
 * written, so a 26-digit index is not shown as some rounded number). */
static const char *value_text(const ply_reader *r, double v, char *buf, size_t size)
{
    if (r->enc == ENC_ASCII && r->tok) snprintf(buf, size, "%.*s", cfi_tok_len(r->tok, r->tok_end), r->tok);
    else snprintf(buf, size, "%.17g", v);
    return buf;
}

/* A value that must be an integer in [lo, hi]. */
static cf_status read_int(ply_reader *r, const ply_prop *pr, ply_type t, int64_t lo, int64_t hi, int64_t *out,
                          cf_status range_status, const char *what, int64_t index)
{
    double v = 0.0;
    cf_status st = read_value(r, pr, t, &v, what, index);
    if (st != CF_OK) return st;
    if (!(v == floor(v)) || v < (double)lo || v > (double)hi) {
        char text[80];
        if (range_status == CF_ERR_INDEX_RANGE && v == floor(v))
            return fail(r, CF_ERR_INDEX_RANGE, "%s %lld: vertex index %s out of range [0, %lld)", what,
                        (long long)index, value_text(r, v, text, sizeof text), (long long)hi + 1);
        return fail(r, CF_ERR_PARSE, "%s %lld: bad %s %s", what, (long long)index,
                    range_status == CF_ERR_INDEX_RANGE ? "vertex index" : "list count", value_text(r, v, text, sizeof text));
    }
    *out = (int64_t)v;
    return CF_OK;
}

/* Skips a property of an element we do not use. */
static cf_status skip_prop(ply_reader *r, const ply_prop *pr, const char *what, int64_t index)
{
    double v = 0.0;
    if (pr->count_type == T_NONE) return read_value(r, pr, pr->type, &v, what, index);
    int64_t n = 0;
    cf_status st = read_int(r, pr, pr->count_type, 0, INT64_MAX / 16, &n, CF_ERR_PARSE, what, index);
    if (st != CF_OK) return st;
    if (r->enc != ENC_ASCII) {
        uint64_t bytes = (uint64_t)n * type_size[pr->type];
        if (bytes > (uint64_t)(r->end - r->p))
            return fail(r, CF_ERR_TRUNCATED, "binary data ends inside %s %lld", what, (long long)index);
        r->p += bytes;
        return CF_OK;
    }
    for (int64_t k = 0; k < n; ++k)
        if ((st = read_value(r, pr, pr->type, &v, what, index)) != CF_OK) return st;
    return CF_OK;
}

/* ---- one element per line (ascii), counts against the data ------------------------ */

/* Moves to the next line that is not blank (ascii); false at the end. */
static bool ascii_next_line(ply_reader *r)
{
    while (cfi_text_next(&r->tx)) {
        const char *s, *e, *p = r->tx.s;
        if (cfi_text_token(&p, r->tx.e, NULL, &s, &e)) {
            r->lp = r->tx.s;
            r->lend = r->tx.e;
            r->line = r->tx.line;
            r->line_values = 0;
            return true;
        }
    }
    return false;
}

/* Start of instance `index` of el: the next line (ascii) or byte (binary).
 * The end of the data here means the header declared more instances than
 * the file holds. */
static cf_status begin_instance(ply_reader *r, const ply_elem *el, int64_t index)
{
    r->in_instance = false;
    bool more = r->enc == ENC_ASCII ? ascii_next_line(r) : r->p < r->end;
    if (!more) {
        char declared[96];
        count_phrase(el, el->count, declared, sizeof declared);
        return cfi_error(r->ctx, CF_ERR_TRUNCATED, "%s: header declares %s, file holds %lld", r->name, declared,
                         (long long)index);
    }
    r->in_instance = true;
    return CF_OK;
}

/* End of an instance: in ascii its line must hold nothing more. */
static cf_status end_instance(ply_reader *r, const char *what, int64_t index)
{
    if (r->enc != ENC_ASCII) return CF_OK;
    int32_t used = r->line_values;
    const char *s, *e;
    int64_t extra = 0;
    while (cfi_text_token(&r->lp, r->lend, NULL, &s, &e)) ++extra;
    if (extra > 0)
        return fail(r, CF_ERR_PARSE, "%s %lld has %lld values, its properties take %d", what, (long long)index,
                    (long long)(used + extra), used);
    return CF_OK;
}

/* Whether the ascii line [s, e) holds exactly one instance of el. */
static bool line_fits(const ply_reader *r, const ply_elem *el, const char *s, const char *e)
{
    const ply_prop *props = (const ply_prop *)r->props.data + el->first_prop;
    const char *ts, *te;
    double v;
    for (size_t k = 0; k < el->prop_count; ++k) {
        if (!cfi_text_token(&s, e, NULL, &ts, &te) || !cfi_parse_double(ts, te, &v)) return false;
        if (props[k].count_type == T_NONE) continue;
        if (!(v == floor(v)) || v < 0 || v > 1e9) return false;
        int64_t n = (int64_t)v;
        for (int64_t i = 0; i < n; ++i)
            if (!cfi_text_token(&s, e, NULL, &ts, &te) || !cfi_parse_double(ts, te, &v)) return false;
    }
    return !cfi_text_token(&s, e, NULL, &ts, &te);
}

/* Lines from the current one on (blank ones skipped) that each hold one
 * instance of el, up to the first that does not. The reader is not moved.
 * *then_fits (may be NULL) tells whether the line after them holds an
 * instance of `then`. */
static int64_t count_fitting(const ply_reader *r, const ply_elem *el, const ply_elem *then, bool *then_fits)
{
    ply_reader c = *r;
    int64_t n = 0;
    bool more = true;
    while (line_fits(&c, el, c.tx.s, c.tx.e)) {
        ++n;
        if (!(more = ascii_next_line(&c))) break;
    }
    if (then_fits) *then_fits = more && then && line_fits(&c, then, c.tx.s, c.tx.e);
    return n;
}

/* The element before / after els[i] that can have data (properties). */
static const ply_elem *neighbour(const ply_reader *r, size_t i, int dir)
{
    const ply_elem *els = r->elems.data;
    for (size_t k = i; dir < 0 ? k-- > 0 : ++k < r->elems.count;)
        if (els[k].prop_count > 0) return &els[k];
    return NULL;
}

/* After an error in the ascii line of instance `index` of els[ei]: when
 * that line does not hold this element but the previous one (the header
 * declared too few of those) or the next one (it declared too many of this
 * one), the count mismatch is the error to report. */
static cf_status diagnose(ply_reader *r, size_t ei, int64_t index, cf_status st)
{
    const ply_elem *el = (const ply_elem *)r->elems.data + ei;
    if (st == CF_ERR_NOMEM || !r->in_instance || line_fits(r, el, r->tx.s, r->tx.e)) return st;
    char declared[96];
    const ply_elem *prev = neighbour(r, ei, -1), *next = neighbour(r, ei, 1);
    if (index == 0 && prev && line_fits(r, prev, r->tx.s, r->tx.e)) {
        /* more lines of the previous element, then this one's: a line that
         * fits both ("3 0 2" is a vertex and a cut face) is not enough */
        bool then_fits = false;
        int64_t extra = count_fitting(r, prev, el, &then_fits);
        if (then_fits) {
            count_phrase(prev, prev->count, declared, sizeof declared);
            return fail(r, CF_ERR_PARSE, "header declares %s, file holds %lld", declared,
                        (long long)(prev->count + extra));
        }
    }
    if (next && line_fits(r, next, r->tx.s, r->tx.e)) {
        count_phrase(el, el->count, declared, sizeof declared);
        return fail(r, CF_ERR_PARSE, "header declares %s, file holds %lld", declared, (long long)index);
    }
    return st;
}

/* Size in bytes of the binary instance of el at q, 0 if it does not fit in [q, end). */
static uint64_t binary_instance_size(const ply_reader *r, const ply_elem *el, const char *q)
{
    const ply_prop *props = (const ply_prop *)r->props.data + el->first_prop;
    uint64_t size = 0, left = (uint64_t)(r->end - q);
    for (size_t k = 0; k < el->prop_count; ++k) {
        const ply_prop *pr = &props[k];
        ply_type t = pr->count_type != T_NONE ? pr->count_type : pr->type;
        if (left - size < type_size[t]) return 0;
        if (pr->count_type == T_NONE) {
            size += type_size[t];
            continue;
        }
        double n = decode(r->enc, t, (const unsigned char *)q + size);
        size += type_size[t];
        if (n < 0 || n * (double)type_size[pr->type] > (double)(left - size)) return 0;
        size += (uint64_t)n * type_size[pr->type];
    }
    return size;
}

/* After the last element: nothing but blank lines (ascii) or nothing at
 * all (binary). Extra data is named as extra instances of the last element
 * when it is exactly that. */
static cf_status check_end(ply_reader *r)
{
    const ply_elem *last = neighbour(r, r->elems.count, -1);
    char declared[96];
    if (last) count_phrase(last, last->count, declared, sizeof declared);
    if (r->enc == ENC_ASCII) {
        if (!ascii_next_line(r)) return CF_OK;
        if (last && line_fits(r, last, r->tx.s, r->tx.e))
            return fail(r, CF_ERR_PARSE, "header declares %s, file holds %lld", declared,
                        (long long)(last->count + count_fitting(r, last, NULL, NULL)));
        const char *s = r->lp, *e = r->lp;
        cfi_text_token(&r->lp, r->lend, NULL, &s, &e);
        return fail(r, CF_ERR_PARSE, "data after the last element ('%.*s')", cfi_tok_len(s, e), s);
    }
    if (r->p == r->end) return CF_OK;
    if (last) {
        int64_t extra = 0;
        uint64_t size;
        const char *q = r->p;
        while (q < r->end && (size = binary_instance_size(r, last, q)) > 0) {
            q += size;
            ++extra;
        }
        if (q == r->end)
            return cfi_error(r->ctx, CF_ERR_PARSE, "%s: header declares %s, file holds %lld", r->name, declared,
                             (long long)(last->count + extra));
    }
    return cfi_error(r->ctx, CF_ERR_PARSE, "%s: %zu bytes after the last element (the data must end there)", r->name,
                     (size_t)(r->end - r->p));
}

/* ---- elements ------------------------------------------------------------------------ */

static cf_status read_vertices(ply_reader *r, const ply_elem *el, int64_t *at)
{
    cf_context *ctx = r->ctx;
    const ply_prop *ep = elem_props(r, el);
    cfi_mesh_builder *b = &r->b;
    bool has_uv = false;
    for (size_t k = 0; k < el->prop_count; ++k) has_uv |= ep[k].role == R_U;
    if (cfi_buf_reserve(ctx, &b->positions, 3 * (size_t)el->count) != CF_OK) return CF_ERR_NOMEM;
    if (has_uv && cfi_buf_reserve(ctx, &b->uv, 2 * (size_t)el->count) != CF_OK) return CF_ERR_NOMEM;
    cfi_prop *vprops = b->vprops.data;
    for (size_t k = 0; k < b->vprops.count; ++k)
        if (cfi_buf_reserve(ctx, &vprops[k].values, (size_t)el->count) != CF_OK) return CF_ERR_NOMEM;
    double *pos = b->positions.data, *uv = b->uv.data;
    cf_status st;
    for (int64_t i = 0; i < el->count; ++i) {
        *at = i;
        if ((st = begin_instance(r, el, i)) != CF_OK) return st;
        for (size_t k = 0; k < el->prop_count; ++k) {
            const ply_prop *pr = &ep[k];
            if (pr->role == R_SKIP) {
                if ((st = skip_prop(r, pr, "vertex", i)) != CF_OK) return st;
                continue;
            }
            double v = 0.0;
            if ((st = read_value(r, pr, pr->type, &v, "vertex", i)) != CF_OK) return st;
            switch (pr->role) {
            case R_X: pos[3 * i] = v; break;
            case R_Y: pos[3 * i + 1] = v; break;
            case R_Z: pos[3 * i + 2] = v; break;
            case R_U: uv[2 * i] = v; break;
            case R_V: uv[2 * i + 1] = v; break;
            case R_EXTRA: ((double *)vprops[pr->slot].values.data)[i] = v; break;
            default: break;
            }
        }
        if ((st = end_instance(r, "vertex", i)) != CF_OK) return st;
        if (!isfinite(pos[3 * i]) || !isfinite(pos[3 * i + 1]) || !isfinite(pos[3 * i + 2]))
            return fail(r, CF_ERR_NONFINITE, "vertex %lld has a non-finite coordinate", (long long)i);
        if (has_uv && (!isfinite(uv[2 * i]) || !isfinite(uv[2 * i + 1])))
            return fail(r, CF_ERR_NONFINITE, "vertex %lld has a non-finite texture coordinate", (long long)i);
    }
    b->positions.count = 3 * (size_t)el->count;
    if (has_uv) b->uv.count = 2 * (size_t)el->count;
    for (size_t k = 0; k < b->vprops.count; ++k) vprops[k].values.count = (size_t)el->count;
    return CF_OK;
}

static cf_status read_faces(ply_reader *r, const ply_elem *el, int64_t *at)
{
    cf_context *ctx = r->ctx;
    const ply_prop *ep = elem_props(r, el);
    cfi_mesh_builder *b = &r->b;
    bool corner_uv = false;
    for (size_t k = 0; k < el->prop_count; ++k) corner_uv |= ep[k].role == R_TEXCOORD;
    if (r->vertex_uv) corner_uv = false; /* per-vertex uv wins; texcoord lists are skipped */
    b->uv_per_corner = corner_uv;
    if (cfi_buf_reserve(ctx, &b->triangles, 3 * (size_t)el->count) != CF_OK) return CF_ERR_NOMEM;
    cfi_prop *fprops = b->fprops.data;
    cf_status st = CF_OK;
    for (int64_t f = 0; f < el->count; ++f) {
        *at = f;
        if ((st = begin_instance(r, el, f)) != CF_OK) return st;
        r->poly.count = 0;
        r->texc.count = 0;
        bool got_texc = false;
        for (size_t k = 0; k < el->prop_count; ++k) {
            const ply_prop *pr = &ep[k];
            if (pr->role == R_INDICES) {
                int64_t n = 0;
                if ((st = read_int(r, pr, pr->count_type, 0, INT64_MAX / 16, &n, CF_ERR_PARSE, "face", f)) != CF_OK)
                    return st;
                if (r->enc != ENC_ASCII && (uint64_t)n * type_size[pr->type] > (uint64_t)(r->end - r->p))
                    return fail(r, CF_ERR_TRUNCATED, "binary data ends inside face %lld", (long long)f);
                for (int64_t c = 0; c < n; ++c) {
                    int64_t v = 0;
                    if ((st = read_int(r, pr, pr->type, 0, r->nv - 1, &v, CF_ERR_INDEX_RANGE, "face", f)) != CF_OK)
                        return st;
                    if (cfi_buf_reserve(ctx, &r->poly, 1) != CF_OK) return CF_ERR_NOMEM;
                    ((int32_t *)r->poly.data)[r->poly.count++] = (int32_t)v;
                }
            } else if (pr->role == R_TEXCOORD && corner_uv) {
                int64_t n = 0;
                if ((st = read_int(r, pr, pr->count_type, 0, INT64_MAX / 16, &n, CF_ERR_PARSE, "face", f)) != CF_OK)
                    return st;
                if (r->enc != ENC_ASCII && (uint64_t)n * type_size[pr->type] > (uint64_t)(r->end - r->p))
                    return fail(r, CF_ERR_TRUNCATED, "binary data ends inside face %lld", (long long)f);
                for (int64_t c = 0; c < n; ++c) {
                    double v = 0.0;
                    if ((st = read_value(r, pr, pr->type, &v, "face", f)) != CF_OK) return st;
                    if (!isfinite(v))
                        return fail(r, CF_ERR_NONFINITE, "face %lld has a non-finite texture coordinate", (long long)f);
                    if (cfi_push_double(ctx, &r->texc, v) != CF_OK) return CF_ERR_NOMEM;
                }
                got_texc = true;
            } else if (pr->role == R_EXTRA) {
                double v = 0.0;
                if ((st = read_value(r, pr, pr->type, &v, "face", f)) != CF_OK) return st;
                r->face_extra[pr->slot] = v;
            } else if ((st = skip_prop(r, pr, "face", f)) != CF_OK) {
                return st;
            }
        }
        if ((st = end_instance(r, "face", f)) != CF_OK) return st;
        size_t n = r->poly.count;
        if (n < 3) return fail(r, CF_ERR_PARSE, "face %lld has %zu vertices", (long long)f, n);
        if (corner_uv && (!got_texc || r->texc.count != 2 * n))
            return fail(r, CF_ERR_PARSE, "face %lld: texcoord list has %zu values, expected %zu", (long long)f,
                        r->texc.count, 2 * n);
        if (b->triangles.count / 3 + (n - 2) > CFI_MAX_ELEMENTS) return fail(r, CF_ERR_PARSE, "too many triangles");
        const int32_t *poly = r->poly.data;
        int64_t uv_base = (int64_t)(b->uv.count / 2);
        if (corner_uv) {
            if (uv_base + (int64_t)n > INT32_MAX / 2) return fail(r, CF_ERR_PARSE, "too many texture coordinates");
            for (size_t c = 0; c < 2 * n; ++c)
                if (cfi_push_double(ctx, &b->uv, ((const double *)r->texc.data)[c]) != CF_OK) return CF_ERR_NOMEM;
        }
        for (size_t k = 2; k < n; ++k) {
            if (cfi_push_int3(ctx, &b->triangles, poly[0], poly[k - 1], poly[k]) != CF_OK) return CF_ERR_NOMEM;
            if (corner_uv && cfi_push_int3(ctx, &b->uv_triangles, (int32_t)uv_base, (int32_t)(uv_base + (int64_t)k - 1),
                                           (int32_t)(uv_base + (int64_t)k)) != CF_OK)
                return CF_ERR_NOMEM;
            for (size_t q = 0; q < b->fprops.count; ++q)
                if (cfi_push_double(ctx, &fprops[q].values, r->face_extra[q]) != CF_OK) return CF_ERR_NOMEM;
        }
        if (n > 3) b->polygon_count++;
    }
    return CF_OK;
}

static cf_status read_other(ply_reader *r, const ply_elem *el, int64_t *at)
{
    const ply_prop *ep = elem_props(r, el);
    char what[48];
    snprintf(what, sizeof what, "'%.*s' element", clip(el->name_len), el->name);
    cf_status st;
    for (int64_t i = 0; i < el->count; ++i) {
        *at = i;
        if ((st = begin_instance(r, el, i)) != CF_OK) return st;
        for (size_t k = 0; k < el->prop_count; ++k)
            if ((st = skip_prop(r, &ep[k], what, i)) != CF_OK) return st;
        if ((st = end_instance(r, what, i)) != CF_OK) return st;
    }
    return CF_OK;
}

static cf_status read_all(ply_reader *r)
{
    cf_status st = parse_header(r);
    if (st == CF_OK) st = plan(r);
    if (st != CF_OK) return st;
    if (r->face_extra_count > 0 && !(r->face_extra = CFI_ALLOC(r->ctx, double, r->face_extra_count)))
        return CF_ERR_NOMEM;
    const ply_elem *els = r->elems.data;
    for (size_t i = 0; i < r->elems.count; ++i) {
        int64_t at = 0;
        if (els[i].kind == E_VERTEX) {
            st = read_vertices(r, &els[i], &at);
        } else if (els[i].kind == E_FACE) {
            st = read_faces(r, &els[i], &at);
        } else {
            st = read_other(r, &els[i], &at);
        }
        if (st != CF_OK) return r->enc == ENC_ASCII ? diagnose(r, i, at, st) : st;
    }
    return check_end(r);
}

cf_status cfi_read_ply(cf_context *ctx, const char *buf, size_t size, const char *name, cf_mesh_data **out)
{
    ply_reader r;
    memset(&r, 0, sizeof r);
    r.ctx = ctx;
    r.name = name;
    r.base = buf;
    r.p = buf;
    r.end = buf + size;
    cfi_buf_init(&r.elems, sizeof(ply_elem));
    cfi_buf_init(&r.props, sizeof(ply_prop));
    cfi_buf_init(&r.poly, sizeof(int32_t));
    cfi_buf_init(&r.texc, sizeof(double));
    cfi_builder_init(&r.b, ctx);
    cf_status st = read_all(&r);
    cfi_buf_free(ctx, &r.elems);
    cfi_buf_free(ctx, &r.props);
    cfi_buf_free(ctx, &r.poly);
    cfi_buf_free(ctx, &r.texc);
    if (r.face_extra) CFI_FREE(ctx, r.face_extra, r.face_extra_count);
    if (st != CF_OK) {
        cfi_builder_free(&r.b);
        return st;
    }
    if (r.b.polygon_count > 0)
        cfi_log(ctx, CF_LOG_WARNING, "%s: %d polygons with more than 3 vertices were fan-triangulated", name,
                r.b.polygon_count);
    return cfi_builder_finish(&r.b, out);
}
