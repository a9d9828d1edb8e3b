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
 * before anything is allocated for it.
 */
#include "io/io_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

typedef enum ply_type { T_NONE = 0, T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_F32, T_F64 } ply_type;

static const size_t type_size[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};

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
    int64_t count;
    elem_kind kind;
    size_t first_prop, prop_count; /* into the property table */
} ply_elem;

typedef enum ply_encoding { ENC_ASCII, ENC_LE, ENC_BE } ply_encoding;

typedef struct ply_reader {
    cf_context *ctx;
    const char *name;
    const char *p, *end;
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
    const char *p = r->p;
    bool have_format = false;
    r->in_header = true;
    int64_t line = 0;
    for (;;) {
        if (p >= r->end)
            return cfi_error(ctx, line == 0 ? CF_ERR_PARSE : CF_ERR_TRUNCATED, "%s: %s", r->name,
                             line == 0 ? "empty file (expected a PLY header)" : "file ends inside the PLY header");
        const char *nl = memchr(p, '\n', (size_t)(r->end - p));
        if (!nl) return cfi_error(ctx, CF_ERR_TRUNCATED, "%s: file ends inside the PLY header", r->name);
        const char *s = p, *e = nl;
        p = nl + 1;
        ++line;
        r->line = line;
        if (memchr(s, '\0', (size_t)(e - s))) return fail(r, CF_ERR_PARSE, "NUL byte in the PLY header");
        const char *ts[8], *te[8];
        int n = split(s, e, ts, te);
        if (line == 1) {
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
    r->p = p;
    r->line = line + 1; /* first data line (ascii) */
    r->in_header = false;
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
                             "%s: header declares %lld '%.*s' elements but only %llu bytes of data follow", r->name,
                             (long long)el->count, clip(el->name_len), el->name, (unsigned long long)remaining);
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

/* Next value as a double. false (with the error recorded) at the end of
 * the data or on a bad token; `what` names the element for messages. */
static cf_status read_value(ply_reader *r, ply_type t, double *out, const char *what, int64_t index)
{
    if (r->enc == ENC_ASCII) {
        const char *p = r->p;
        while (p < r->end && (cfi_is_space(*p) || *p == '\n')) {
            if (*p == '\n') r->line++;
            ++p;
        }
        if (p >= r->end) {
            r->p = p;
            return fail(r, CF_ERR_TRUNCATED, "file ends inside %s %lld", what, (long long)index);
        }
        const char *s = p;
        while (p < r->end && !cfi_is_space(*p) && *p != '\n') ++p;
        r->p = p;
        if (!cfi_parse_double(s, p, out))
            return fail(r, CF_ERR_PARSE, "%s %lld: bad number '%.*s'", what, (long long)index, clip((size_t)(p - s)), s);
        return CF_OK;
    }
    size_t n = type_size[t];
    if ((size_t)(r->end - r->p) < n)
        return fail(r, CF_ERR_TRUNCATED, "binary data ends inside %s %lld", what, (long long)index);
    const unsigned char *b = (const unsigned char *)r->p;
    uint64_t u = 0;
    for (size_t i = 0; i < n; ++i) u |= (uint64_t)b[r->enc == ENC_BE ? n - 1 - i : i] << (8 * i);
    r->p += n;
    switch (t) {
    case T_I8: *out = (double)(int64_t)u - (u & 0x80u ? 256.0 : 0.0); break;
    case T_I16: *out = (double)(int64_t)u - (u & 0x8000u ? 65536.0 : 0.0); break;
    case T_I32: *out = (double)(int64_t)u - (u & 0x80000000u ? 4294967296.0 : 0.0); break;
    case T_U8:
    case T_U16:
    case T_U32: *out = (double)u; break;
    case T_F32: {
        uint32_t w = (uint32_t)u;
        float f;
        memcpy(&f, &w, 4);
        *out = (double)f;
        break;
    }
    case T_F64: memcpy(out, &u, 8); break;
    case T_NONE: *out = 0.0; break;
    }
    return CF_OK;
}

/* A value that must be an integer in [lo, hi]. */
static cf_status read_int(ply_reader *r, ply_type t, int64_t lo, int64_t hi, int64_t *out, cf_status range_status,
                          const char *what, int64_t index)
{
    double v = 0.0;
    cf_status st = read_value(r, t, &v, what, index);
    if (st != CF_OK) return st;
    if (!(v == floor(v)) || v < (double)lo || v > (double)hi) {
        if (range_status == CF_ERR_INDEX_RANGE && v == floor(v))
            return fail(r, CF_ERR_INDEX_RANGE, "%s %lld: vertex index %.17g out of range [0, %lld)", what,
                        (long long)index, v, (long long)hi + 1);
        return fail(r, CF_ERR_PARSE, "%s %lld: bad %s %.17g", what, (long long)index,
                    range_status == CF_ERR_INDEX_RANGE ? "vertex index" : "list count", v);
    }
    *out = (int64_t)v;
    return CF_OK;
}

/* Skips a property of an element we do not use. */
static cf_status skip_prop(ply_reader *r, const ply_prop *pr, const char *what, int64_t index)
{
    double v = 0.0;
    if (pr->count_type == T_NONE) return read_value(r, pr->type, &v, what, index);
    int64_t n = 0;
    cf_status st = read_int(r, pr->count_type, 0, INT64_MAX / 16, &n, CF_ERR_PARSE, what, index);
    if (st != CF_OK) return st;
    if (r->enc != ENC_ASCII) {
        uint64_t bytes = (uint64_t)n * type_size[pr->type];
        if (bytes > (uint64_t)(r->end - r->p))
            return fail(r, CF_ERR_TRUNCATED, "binary data ends inside %s %lld", what, (long long)index);
        r->p += bytes;
        return CF_OK;
    }
    for (int64_t k = 0; k < n; ++k)
        if ((st = read_value(r, pr->type, &v, what, index)) != CF_OK) return st;
    return CF_OK;
}

/* ---- elements ------------------------------------------------------------------------ */

static cf_status read_vertices(ply_reader *r, const ply_elem *el)
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
    for (int64_t i = 0; i < el->count; ++i) {
        for (size_t k = 0; k < el->prop_count; ++k) {
            const ply_prop *pr = &ep[k];
            if (pr->role == R_SKIP) {
                cf_status st = skip_prop(r, pr, "vertex", i);
                if (st != CF_OK) return st;
                continue;
            }
            double v = 0.0;
            cf_status st = read_value(r, pr->type, &v, "vertex", i);
            if (st != CF_OK) return st;
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

static cf_status read_faces(ply_reader *r, const ply_elem *el)
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
        r->poly.count = 0;
        r->texc.count = 0;
        bool got_texc = false;
        for (size_t k = 0; k < el->prop_count; ++k) {
            const ply_prop *pr = &ep[k];
            if (pr->role == R_INDICES) {
                int64_t n = 0;
                if ((st = read_int(r, pr->count_type, 0, INT64_MAX / 16, &n, CF_ERR_PARSE, "face", f)) != CF_OK)
                    return st;
                if (r->enc != ENC_ASCII && (uint64_t)n * type_size[pr->type] > (uint64_t)(r->end - r->p))
                    return fail(r, CF_ERR_TRUNCATED, "binary data ends inside face %lld", (long long)f);
                for (int64_t c = 0; c < n; ++c) {
                    int64_t v = 0;
                    if ((st = read_int(r, pr->type, 0, r->nv - 1, &v, CF_ERR_INDEX_RANGE, "face", f)) != CF_OK)
                        return st;
                    if (cfi_buf_reserve(ctx, &r->poly, 1) != CF_OK) return CF_ERR_NOMEM;
                    ((int32_t *)r->poly.data)[r->poly.count++] = (int32_t)v;
                }
            } else if (pr->role == R_TEXCOORD && corner_uv) {
                int64_t n = 0;
                if ((st = read_int(r, pr->count_type, 0, INT64_MAX / 16, &n, CF_ERR_PARSE, "face", f)) != CF_OK)
                    return st;
                if (r->enc != ENC_ASCII && (uint64_t)n * type_size[pr->type] > (uint64_t)(r->end - r->p))
                    return fail(r, CF_ERR_TRUNCATED, "binary data ends inside face %lld", (long long)f);
                for (int64_t c = 0; c < n; ++c) {
                    double v = 0.0;
                    if ((st = read_value(r, pr->type, &v, "face", f)) != CF_OK) return st;
                    if (!isfinite(v))
                        return fail(r, CF_ERR_NONFINITE, "face %lld has a non-finite texture coordinate", (long long)f);
                    if (cfi_push_double(ctx, &r->texc, v) != CF_OK) return CF_ERR_NOMEM;
                }
                got_texc = true;
            } else if (pr->role == R_EXTRA) {
                double v = 0.0;
                if ((st = read_value(r, pr->type, &v, "face", f)) != CF_OK) return st;
                r->face_extra[pr->slot] = v;
            } else if ((st = skip_prop(r, pr, "face", f)) != CF_OK) {
                return st;
            }
        }
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

static cf_status read_other(ply_reader *r, const ply_elem *el)
{
    const ply_prop *ep = elem_props(r, el);
    char what[48];
    snprintf(what, sizeof what, "'%.*s' element", clip(el->name_len), el->name);
    for (int64_t i = 0; i < el->count; ++i)
        for (size_t k = 0; k < el->prop_count; ++k) {
            cf_status st = skip_prop(r, &ep[k], what, i);
            if (st != CF_OK) return st;
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
    for (size_t i = 0; i < r->elems.count && st == CF_OK; ++i) {
        if (els[i].kind == E_VERTEX) {
            st = read_vertices(r, &els[i]);
        } else if (els[i].kind == E_FACE) {
            st = read_faces(r, &els[i]);
        } else {
            st = read_other(r, &els[i]);
        }
    }
    return st;
}

cf_status cfi_read_ply(cf_context *ctx, const char *buf, size_t size, const char *name, cf_mesh_data **out)
{
    ply_reader r;
    memset(&r, 0, sizeof r);
    r.ctx = ctx;
    r.name = name;
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
