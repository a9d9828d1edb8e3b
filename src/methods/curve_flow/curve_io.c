/*
 * Polyline files for the curve flow (curvflow/curve_flow.h):
 * CSV ("x,y" or "x y" per line) and a small SVG subset (first polygon /
 * polyline "points", or first path "d" with M, L, H, V, Z in absolute and
 * relative form). Files are read whole (lines of any length) and checked
 * by io's cf_text_check as every text input of the library (byte-order mark
 * skipped, NUL bytes refused with their offset); writing goes through the
 * atomic text writer of io.
 */
#include "curvflow/curve_flow.h"
#include "curvflow/io.h"
#include "core/core.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct pbuf {
    cf_context *ctx;
    double *xy;
    int64_t count, cap;   /* points */
} pbuf;

static cf_status push(pbuf *b, double x, double y)
{
    if (!isfinite(x) || !isfinite(y))
        return cfi_error(b->ctx, CF_ERR_NONFINITE, "point %lld: not finite", (long long)b->count);
    if (fabs(x) > CF_MAX_COORDINATE || fabs(y) > CF_MAX_COORDINATE)
        return cfi_error(b->ctx, CF_ERR_NONFINITE, "point %lld: (%.3g, %.3g) is out of range (|x| > %.0e); rescale the curve",
                         (long long)b->count, x, y, CF_MAX_COORDINATE);
    if (b->count == b->cap) {
        int64_t ncap = b->cap ? 2 * b->cap : 64;
        if (ncap > INT32_MAX / 2) return cfi_error(b->ctx, CF_ERR_INVALID_ARG, "curve: too many points");
        double *p = cfi_realloc(b->ctx, b->xy, 2 * (size_t)b->cap * sizeof(double), 2 * (size_t)ncap * sizeof(double));
        if (!p) return CF_ERR_NOMEM;
        b->xy = p;
        b->cap = ncap;
    }
    b->xy[2 * b->count] = x;
    b->xy[2 * b->count + 1] = y;
    ++b->count;
    return CF_OK;
}

static cf_status read_file(cf_context *ctx, const char *path, char **text, size_t *size, size_t *length)
{
    FILE *fp = fopen(path, "rb");
    if (!fp) return cfi_error(ctx, CF_ERR_IO, "%s: cannot open (%s)", path, strerror(errno));
    size_t cap = 4096, n = 0;
    char *buf = cfi_malloc(ctx, cap);
    if (!buf) {
        fclose(fp);
        return CF_ERR_NOMEM;
    }
    for (;;) {
        if (n + 1 >= cap) {
            char *nb = cfi_realloc(ctx, buf, cap, 2 * cap);
            if (!nb) {
                cfi_free(ctx, buf, cap);
                fclose(fp);
                return CF_ERR_NOMEM;
            }
            buf = nb;
            cap *= 2;
        }
        size_t r = fread(buf + n, 1, cap - 1 - n, fp);
        n += r;
        if (r == 0) break;
    }
    int err = ferror(fp);
    fclose(fp);
    if (err) {
        cfi_free(ctx, buf, cap);
        return cfi_error(ctx, CF_ERR_IO, "%s: read error", path);
    }
    buf[n] = '\0';
    *text = buf;
    *size = cap;
    *length = n;
    return CF_OK;
}

/* CSV separators: whitespace, ',' and ';'. */
static bool csv_sep(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f' || c == ',' || c == ';'; }

/* Next CSV token of [*p, e); false when none is left. */
static bool csv_token(const char **p, const char *e, const char **ts, const char **te)
{
    const char *q = *p;
    while (q < e && csv_sep(*q)) ++q;
    *ts = q;
    while (q < e && !csv_sep(*q)) ++q;
    *te = q;
    *p = q;
    return *ts < q;
}

static int tok_len(const char *s, const char *e) { return (int)(e - s > 64 ? 64 : e - s); }

/* One "x,y" (or "x y", "x;y") point per line; '#' comment lines and blank
 * lines are skipped, a first line that holds no numbers is a header. A third
 * column is ignored with one warning per file (a z or a label would
 * otherwise vanish without a word). Lines have any length: they are ranges
 * of the whole text (NUL-terminated, so strtod stops at its end). */
static cf_status parse_csv(pbuf *b, const char *path, const char *text, size_t length)
{
    bool warned = false;
    const char *end = text + length;
    int64_t line = 0;
    for (const char *s = text; s < end;) {
        const char *nl = memchr(s, '\n', (size_t)(end - s)), *e = nl ? nl : end, *p = s, *s1, *e1, *s2, *e2, *s3, *e3;
        s = nl ? nl + 1 : end;
        ++line;
        if (!csv_token(&p, e, &s1, &e1) || *s1 == '#') continue;
        double x = 0.0, y = 0.0;
        char *stop = NULL;
        bool ok = csv_token(&p, e, &s2, &e2);
        if (ok) {
            x = strtod(s1, &stop);
            ok = stop == e1;
        }
        if (ok) {
            y = strtod(s2, &stop);
            ok = stop == e2;
        }
        if (!ok) {
            if (b->count == 0 && line == 1) continue; /* header line */
            return cfi_error(b->ctx, CF_ERR_PARSE, "%s:%lld: expected two numbers \"x,y\"", path, (long long)line);
        }
        if (!warned && csv_token(&p, e, &s3, &e3) && *s3 != '#') {
            cfi_log(b->ctx, CF_LOG_WARNING,
                    "%s: line %lld: a third column ('%.*s') is ignored (x,y expected; further ones silently)", path,
                    (long long)line, tok_len(s3, e3), s3);
            warned = true;
        }
        cf_status st = push(b, x, y);
        if (st != CF_OK) return st;
    }
    return CF_OK;
}

/* Value of attribute `name` of the first element `tag` (pointer into text,
 * terminated by the closing quote, which is overwritten). */
static char *svg_attribute(char *text, const char *tag, const char *name)
{
    size_t tl = strlen(tag), nl = strlen(name);
    for (char *p = text; (p = strchr(p, '<')) != NULL; ++p) {
        if (strncmp(p + 1, tag, tl) != 0 || !(isspace((unsigned char)p[1 + tl]) || p[1 + tl] == '/')) continue;
        char *end = strchr(p, '>');
        for (char *a = p + 1 + tl; *a && (!end || a < end); ++a) {
            if (isspace((unsigned char)a[-1]) && strncmp(a, name, nl) == 0) {
                char *q = a + nl;
                while (isspace((unsigned char)*q)) ++q;
                if (*q != '=') continue;
                ++q;
                while (isspace((unsigned char)*q)) ++q;
                if (*q != '"' && *q != '\'') continue;
                char quote = *q++;
                char *close = strchr(q, quote);
                if (!close) return NULL;
                *close = '\0';
                return q;
            }
        }
    }
    return NULL;
}

static const char *skip_sep(const char *s)
{
    while (isspace((unsigned char)*s) || *s == ',') ++s;
    return s;
}

static cf_status parse_points(pbuf *b, const char *path, const char *s)
{
    for (;;) {
        s = skip_sep(s);
        if (!*s) return CF_OK;
        char *e1, *e2;
        double x = strtod(s, &e1);
        const char *r = skip_sep(e1);
        double y = strtod(r, &e2);
        if (e1 == s || e2 == r) return cfi_error(b->ctx, CF_ERR_PARSE, "%s: bad number in points attribute near \"%.20s\"", path, s);
        cf_status st = push(b, x, y);
        if (st != CF_OK) return st;
        s = e2;
    }
}

static cf_status parse_path(pbuf *b, const char *path, const char *s)
{
    char cmd = 0;
    double cx = 0.0, cy = 0.0;
    int started = 0;
    for (;;) {
        s = skip_sep(s);
        if (!*s) return CF_OK;
        if (isalpha((unsigned char)*s)) {
            cmd = *s++;
            if (cmd == 'Z' || cmd == 'z') return CF_OK;   /* first subpath only */
            if (!strchr("MmLlHhVv", cmd))
                return cfi_error(b->ctx, CF_ERR_PARSE, "%s: unsupported path command '%c' (only M L H V Z)", path, cmd);
            if ((cmd == 'M' || cmd == 'm') && started) return CF_OK;
            continue;
        }
        if (!cmd) return cfi_error(b->ctx, CF_ERR_PARSE, "%s: path data must start with a command", path);
        char *e1, *e2;
        double a = strtod(s, &e1);
        if (e1 == s) return cfi_error(b->ctx, CF_ERR_PARSE, "%s: bad number in path near \"%.20s\"", path, s);
        s = e1;
        int rel = islower((unsigned char)cmd);
        double nx = cx, ny = cy;
        switch (cmd) {
        case 'H': case 'h': nx = rel ? cx + a : a; break;
        case 'V': case 'v': ny = rel ? cy + a : a; break;
        default: {
            const char *r = skip_sep(s);
            double c = strtod(r, &e2);
            if (e2 == r) return cfi_error(b->ctx, CF_ERR_PARSE, "%s: path point needs two numbers near \"%.20s\"", path, r);
            s = e2;
            nx = rel ? cx + a : a;
            ny = rel ? cy + c : c;
        }
        }
        cf_status st = push(b, nx, ny);
        if (st != CF_OK) return st;
        started = 1;
        cx = nx;
        cy = ny;
        if (cmd == 'M') cmd = 'L';   /* implicit repeats of moveto are lineto */
        if (cmd == 'm') cmd = 'l';
    }
}

static int has_suffix(const char *path, const char *suffix)
{
    size_t n = strlen(path), m = strlen(suffix);
    if (n < m) return 0;
    for (size_t i = 0; i < m; ++i)
        if (tolower((unsigned char)path[n - m + i]) != suffix[i]) return 0;
    return 1;
}

/* Parses `length` bytes of text followed by a NUL (modified in place), named
 * `name` in messages; a NUL byte inside the text is refused. */
static cf_status parse_text(cf_context *ctx, char *text, size_t length, const char *name, int svg, cf_curve **out)
{
    size_t start = 0;
    cf_status st = cf_text_check(ctx, text, length, name, &start);
    if (st != CF_OK) return st;
    text += start;
    length -= start;
    pbuf b = {ctx, NULL, 0, 0};
    if (svg) {
        char *attr = svg_attribute(text, "polygon", "points");
        if (attr) {
            st = parse_points(&b, name, attr);
        } else if ((attr = svg_attribute(text, "polyline", "points")) != NULL) {
            st = parse_points(&b, name, attr);
        } else if ((attr = svg_attribute(text, "path", "d")) != NULL) {
            st = parse_path(&b, name, attr);
        } else {
            st = cfi_error(ctx, CF_ERR_PARSE, "%s: no <polygon>, <polyline> or <path> found", name);
        }
    } else {
        st = parse_csv(&b, name, text, length);
    }
    if (st == CF_OK && b.count >= 2 && b.xy[0] == b.xy[2 * b.count - 2] && b.xy[1] == b.xy[2 * b.count - 1]) --b.count;
    if (st == CF_OK && b.count < 3) st = cfi_error(ctx, CF_ERR_PARSE, "%s: need at least 3 points, found %lld", name, (long long)b.count);
    cf_curve *c = NULL;
    if (st == CF_OK) {
        c = CFI_ALLOC(ctx, cf_curve, 1);
        if (!c) st = CF_ERR_NOMEM;
    }
    if (st != CF_OK) {
        cfi_free(ctx, b.xy, 2 * (size_t)b.cap * sizeof(double));
        return st;
    }
    /* shrink to the exact size so destroy knows the byte count */
    double *xy = cfi_realloc(ctx, b.xy, 2 * (size_t)b.cap * sizeof(double), 2 * (size_t)b.count * sizeof(double));
    if (!xy) {
        cfi_free(ctx, b.xy, 2 * (size_t)b.cap * sizeof(double));
        CFI_FREE(ctx, c, 1);
        return CF_ERR_NOMEM;
    }
    c->count = (int32_t)b.count;
    c->points = xy;
    c->ctx = ctx;
    *out = c;
    return CF_OK;
}

cf_status cf_curve_read(cf_context *ctx, const char *path, cf_curve **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!path || !out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "curve_read: path and out are required");
    *out = NULL;
    char *text = NULL;
    size_t cap = 0, length = 0;
    cf_status st = read_file(ctx, path, &text, &cap, &length);
    if (st != CF_OK) return st;
    st = parse_text(ctx, text, length, path, has_suffix(path, ".svg"), out);
    cfi_free(ctx, text, cap);
    return st;
}

cf_status cf_curve_read_memory(cf_context *ctx, const void *bytes, size_t size, int svg, const char *name,
                               cf_curve **out)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if ((!bytes && size) || !out) return cfi_error(ctx, CF_ERR_INVALID_ARG, "curve_read_memory: bytes and out are required");
    *out = NULL;
    if (!name) name = svg ? "<memory>.svg" : "<memory>.csv";
    if (size >= SIZE_MAX) return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: too large", name);
    char *text = cfi_malloc(ctx, size + 1);
    if (!text) return CF_ERR_NOMEM;
    if (size) memcpy(text, bytes, size);
    text[size] = '\0';
    cf_status st = parse_text(ctx, text, size, name, svg, out);
    cfi_free(ctx, text, size + 1);
    return st;
}

void cf_curve_destroy(cf_curve **pc)
{
    if (!pc || !*pc) return;
    cf_curve *c = *pc;
    cf_context *ctx = c->ctx;
    CFI_FREE(ctx, c->points, 2 * (int64_t)c->count);
    CFI_FREE(ctx, c, 1);
    *pc = NULL;
}

cf_status cf_curve_write(cf_context *ctx, const char *path, int32_t n, const double *points)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!path || !points || n < 1) return cfi_error(ctx, CF_ERR_INVALID_ARG, "curve_write: path, points and n >= 1 required");
    int svg = has_suffix(path, ".svg");
    size_t cap = (size_t)n * 56 + 512;
    char *buf = cfi_malloc(ctx, cap);
    if (!buf) return CF_ERR_NOMEM;
    size_t len = 0;
    if (svg) {
        double lo[2] = {points[0], points[1]}, hi[2] = {points[0], points[1]};
        for (int32_t i = 0; i < n; ++i)
            for (int c = 0; c < 2; ++c) {
                lo[c] = fmin(lo[c], points[2 * i + c]);
                hi[c] = fmax(hi[c], points[2 * i + c]);
            }
        double pad = 0.05 * fmax(hi[0] - lo[0], hi[1] - lo[1]) + 1e-9;
        double sw = 0.005 * fmax(hi[0] - lo[0], hi[1] - lo[1]) + 1e-12;
        len += (size_t)snprintf(buf + len, cap - len,
                                "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"%.9g %.9g %.9g %.9g\">\n"
                                "<polygon fill=\"none\" stroke=\"black\" stroke-width=\"%.6g\" points=\"",
                                lo[0] - pad, lo[1] - pad, hi[0] - lo[0] + 2 * pad, hi[1] - lo[1] + 2 * pad, sw);
    }
    for (int32_t i = 0; i < n && len < cap; ++i)
        len += (size_t)snprintf(buf + len, cap - len, svg ? "%.17g,%.17g " : "%.17g,%.17g\n", points[2 * i],
                                points[2 * i + 1]);
    if (svg && len < cap) len += (size_t)snprintf(buf + len, cap - len, "\"/>\n</svg>\n");
    cf_status st = len < cap ? cf_write_text_file_atomic(ctx, path, buf, len)
                             : cfi_error(ctx, CF_ERR_NUMERICAL, "curve_write: buffer too small");
    cfi_free(ctx, buf, cap);
    return st;
}
