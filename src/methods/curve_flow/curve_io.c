/*
 * Polyline files for the curve flow (curvflow/curve_flow.h):
 * CSV ("x,y" or "x y" per line) and a small SVG subset: the first drawn
 * <polygon> / <polyline> "points", <path> "d" (M L H V C S Q T A Z,
 * absolute and relative; curves flattened), <rect>, <circle> or <ellipse>
 * in document order, mapped by the "transform" attributes of
 * the element and its ancestors; comments, CDATA, processing instructions
 * and the DOCTYPE are skipped, as are shapes inside elements that are not
 * drawn (defs, clipPath, mask, symbol, marker, pattern). Further shapes and
 * further subpaths of the path are ignored with a warning: the flow takes
 * one closed curve. Files are read whole (lines of any length) and checked
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

/* ---- SVG ----------------------------------------------------------------- */

#define SVG_PI 3.14159265358979323846

/* An affine map of the plane as SVG writes it, matrix(a b c d e f):
 * x' = a x + c y + e, y' = b x + d y + f. */
typedef struct affine {
    double a, b, c, d, e, f;
} affine;

static const affine identity_map = {1.0, 0.0, 0.0, 1.0, 0.0, 0.0};

/* m after n: (m o n)(p) = m(n(p)) */
static affine compose(affine m, affine n)
{
    affine r = {m.a * n.a + m.c * n.b, m.b * n.a + m.d * n.b, m.a * n.c + m.c * n.d,
                m.b * n.c + m.d * n.d, m.a * n.e + m.c * n.f + m.e, m.b * n.e + m.d * n.f + m.f};
    return r;
}

static cf_status push_mapped(pbuf *b, const affine *m, double x, double y)
{
    return push(b, m->a * x + m->c * y + m->e, m->b * x + m->d * y + m->f);
}

/* 1-based line of position p in text (for messages only). */
static long line_of(const char *text, const char *p)
{
    long line = 1;
    for (const char *q = text; q < p; ++q) line += *q == '\n';
    return line;
}

static const char *skip_sep(const char *s)
{
    while (isspace((unsigned char)*s) || *s == ',') ++s;
    return s;
}

/* A transform list ("translate(10,20) scale(2)"): functions applied right
 * to left, as SVG defines it; the value ends at `end` (its closing quote).
 * Messages name the line of `tag` in `text`, counted only for a message
 * (counting for every element made large files quadratic). */
static cf_status parse_transform(pbuf *b, const char *name, const char *text, const char *tag, const char *s,
                                 const char *end, affine *out)
{
    static const struct {
        const char *name;
        int min, max; /* argument counts */
    } kinds[] = {{"matrix", 6, 6}, {"translate", 1, 2}, {"scale", 1, 2}, {"rotate", 1, 3}, {"skewX", 1, 1}, {"skewY", 1, 1}};
    affine m = identity_map;
    for (;;) {
        while (s < end && (isspace((unsigned char)*s) || *s == ',')) ++s;
        if (s >= end) break;
        int k = -1;
        for (int i = 0; i < 6 && k < 0; ++i) {
            size_t n = strlen(kinds[i].name);
            if ((size_t)(end - s) > n && strncmp(s, kinds[i].name, n) == 0) {
                const char *q = s + n;
                while (q < end && isspace((unsigned char)*q)) ++q;
                if (q < end && *q == '(') {
                    k = i;
                    s = q + 1;
                }
            }
        }
        if (k < 0)
            return cfi_error(b->ctx, CF_ERR_PARSE, "%s: line %ld: unsupported transform near \"%.20s\"", name,
                             line_of(text, tag), s);
        double v[6];
        int n = 0;
        for (;;) {
            while (s < end && (isspace((unsigned char)*s) || *s == ',')) ++s;
            if (s < end && *s == ')') {
                ++s;
                break;
            }
            char *stop;
            double x = s < end ? strtod(s, &stop) : 0.0;
            if (s >= end || stop == s || stop > end || n == 6)
                return cfi_error(b->ctx, CF_ERR_PARSE, "%s: line %ld: bad %s() in transform near \"%.20s\"", name,
                                 line_of(text, tag), kinds[k].name, s);
            v[n++] = x;
            s = stop;
        }
        if (n < kinds[k].min || n > kinds[k].max || (k == 3 && n == 2))
            return cfi_error(b->ctx, CF_ERR_PARSE, "%s: line %ld: %s() takes %s arguments, got %d", name,
                             line_of(text, tag), kinds[k].name, k == 0 ? "6" : k == 3 ? "1 or 3" : k >= 4 ? "1" : "1 or 2",
                             n);
        affine t = identity_map;
        const double deg = SVG_PI / 180.0;
        switch (k) {
        case 0: t = (affine){v[0], v[1], v[2], v[3], v[4], v[5]}; break;
        case 1: t.e = v[0]; t.f = n > 1 ? v[1] : 0.0; break;
        case 2: t.a = v[0]; t.d = n > 1 ? v[1] : v[0]; break;
        case 3: {
            double c = cos(v[0] * deg), sn = sin(v[0] * deg);
            t = (affine){c, sn, -sn, c, 0.0, 0.0};
            if (n == 3) { /* about (cx, cy): translate(cx, cy) rotate(a) translate(-cx, -cy) */
                affine to = {1.0, 0.0, 0.0, 1.0, v[1], v[2]}, back = {1.0, 0.0, 0.0, 1.0, -v[1], -v[2]};
                t = compose(to, compose(t, back));
            }
            break;
        }
        case 4: t.c = tan(v[0] * deg); break;
        default: t.b = tan(v[0] * deg); break;
        }
        m = compose(m, t);
    }
    *out = m;
    return CF_OK;
}

static cf_status parse_points(pbuf *b, const char *path, const affine *m, const char *s)
{
    for (;;) {
        s = skip_sep(s);
        if (!*s) return CF_OK;
        char *e1, *e2;
        double x = strtod(s, &e1);
        const char *r = skip_sep(e1);
        double y = strtod(r, &e2);
        if (e1 == s || e2 == r) return cfi_error(b->ctx, CF_ERR_PARSE, "%s: bad number in points attribute near \"%.20s\"", path, s);
        cf_status st = push_mapped(b, m, x, y);
        if (st != CF_OK) return st;
        s = e2;
    }
}

/* ---- curves: flattened into the polyline ---------------------------------
 * Bezier segments and elliptical arcs become line segments whose distance
 * from the curve is at most SVG_FLATTEN_TOLERANCE times the segment's own
 * size (its control polygon's length, an arc's larger radius), so the
 * flattening does not depend on the drawing's units. The last point of a
 * segment is its end point as written. */
#define SVG_FLATTEN_TOLERANCE 1e-3
#define SVG_MAX_PIECES 1024

/* ceil(n) within [1, SVG_MAX_PIECES]; 1 for NaN (a segment of infinite
 * size is refused when its points are pushed) */
static int piece_count(double n)
{
    n = ceil(n);
    return !(n >= 1.0) ? 1 : n > SVG_MAX_PIECES ? SVG_MAX_PIECES : (int)n;
}

/* Pieces for a segment whose second derivative is at most `curvature` in
 * norm (over t in [0, 1]) and whose size is `size`: a uniform split into n
 * pieces deviates from it by at most curvature / (8 n^2). */
static int bezier_pieces(double curvature, double size)
{
    if (!(size > 0.0) || !(curvature > 0.0)) return 1;
    return piece_count(sqrt(curvature / (8.0 * SVG_FLATTEN_TOLERANCE * size)));
}

/* The cubic (x0 y0) (x1 y1) (x2 y2) (x3 y3), from its second point on. */
static cf_status push_cubic(pbuf *b, const affine *m, const double q[8])
{
    double size = 0.0, curvature = 0.0;
    for (int i = 0; i < 3; ++i) size += hypot(q[2 * i + 2] - q[2 * i], q[2 * i + 3] - q[2 * i + 1]);
    for (int i = 0; i < 2; ++i) /* B'' is linear in t between 6 (q_i - 2 q_i+1 + q_i+2) */
        curvature = fmax(curvature, 6.0 * hypot(q[2 * i] - 2.0 * q[2 * i + 2] + q[2 * i + 4],
                                                q[2 * i + 1] - 2.0 * q[2 * i + 3] + q[2 * i + 5]));
    if (size == 0.0) return CF_OK; /* a point: nothing drawn */
    int n = bezier_pieces(curvature, size);
    for (int k = 1; k < n; ++k) {
        double t = (double)k / n, s = 1.0 - t;
        double w0 = s * s * s, w1 = 3.0 * s * s * t, w2 = 3.0 * s * t * t, w3 = t * t * t;
        cf_status st = push_mapped(b, m, w0 * q[0] + w1 * q[2] + w2 * q[4] + w3 * q[6],
                                   w0 * q[1] + w1 * q[3] + w2 * q[5] + w3 * q[7]);
        if (st != CF_OK) return st;
    }
    return push_mapped(b, m, q[6], q[7]);
}

/* The quadratic (x0 y0) (x1 y1) (x2 y2), from its second point on. */
static cf_status push_quadratic(pbuf *b, const affine *m, const double q[6])
{
    double size = hypot(q[2] - q[0], q[3] - q[1]) + hypot(q[4] - q[2], q[5] - q[3]);
    if (size == 0.0) return CF_OK;
    int n = bezier_pieces(2.0 * hypot(q[0] - 2.0 * q[2] + q[4], q[1] - 2.0 * q[3] + q[5]), size);
    for (int k = 1; k < n; ++k) {
        double t = (double)k / n, s = 1.0 - t;
        double w0 = s * s, w1 = 2.0 * s * t, w2 = t * t;
        cf_status st = push_mapped(b, m, w0 * q[0] + w1 * q[2] + w2 * q[4], w0 * q[1] + w1 * q[3] + w2 * q[5]);
        if (st != CF_OK) return st;
    }
    return push_mapped(b, m, q[4], q[5]);
}

/* Pieces for an arc of `sweep` radians: a chord of angle a deviates from
 * its circle by r (1 - cos(a / 2)). */
static int arc_pieces(double sweep)
{
    return piece_count(fabs(sweep) / (2.0 * acos(1.0 - SVG_FLATTEN_TOLERANCE)));
}

/* The point at angle t of the ellipse with centre (cx, cy), radii rx, ry,
 * x axis turned by phi (cosine cp, sine sp). */
static cf_status push_ellipse_point(pbuf *b, const affine *m, double cx, double cy, double rx, double ry, double cp,
                                    double sp, double t)
{
    double c = cos(t), s = sin(t);
    return push_mapped(b, m, cx + rx * cp * c - ry * sp * s, cy + rx * sp * c + ry * cp * s);
}

/* The elliptical arc from (x1, y1) to (x2, y2) of SVG's path command A,
 * from its second point on, by the endpoint-to-centre conversion of SVG
 * 1.1 (implementation notes F.6.5, radii scaled up as in F.6.6). */
static cf_status push_arc(pbuf *b, const affine *m, double x1, double y1, double rx, double ry, double phi_deg,
                          int large, int sweep, double x2, double y2)
{
    if (x1 == x2 && y1 == y2) return CF_OK; /* omitted, as SVG says */
    rx = fabs(rx);
    ry = fabs(ry);
    if (rx == 0.0 || ry == 0.0) return push_mapped(b, m, x2, y2); /* a line, as SVG says */
    double phi = fmod(phi_deg, 360.0) * SVG_PI / 180.0, cp = cos(phi), sp = sin(phi);
    double hx = 0.5 * (x1 - x2), hy = 0.5 * (y1 - y2);
    double x1p = cp * hx + sp * hy, y1p = -sp * hx + cp * hy;
    /* radii too small for the end points are scaled up until they fit */
    double lambda = (x1p / rx) * (x1p / rx) + (y1p / ry) * (y1p / ry);
    if (lambda > 1.0) {
        rx *= sqrt(lambda);
        ry *= sqrt(lambda);
    }
    double num = (rx * ry) * (rx * ry) - (rx * y1p) * (rx * y1p) - (ry * x1p) * (ry * x1p);
    double den = (rx * y1p) * (rx * y1p) + (ry * x1p) * (ry * x1p);
    double coef = den > 0.0 && num > 0.0 ? sqrt(num / den) : 0.0;
    if (large == sweep) coef = -coef;
    double cxp = coef * rx * y1p / ry, cyp = -coef * ry * x1p / rx;
    double cx = cp * cxp - sp * cyp + 0.5 * (x1 + x2), cy = sp * cxp + cp * cyp + 0.5 * (y1 + y2);
    double t1 = atan2((y1p - cyp) / ry, (x1p - cxp) / rx);
    double dt = atan2((-y1p - cyp) / ry, (-x1p - cxp) / rx) - t1;
    if (sweep && dt < 0.0) dt += 2.0 * SVG_PI;
    if (!sweep && dt > 0.0) dt -= 2.0 * SVG_PI;
    int n = arc_pieces(dt);
    for (int k = 1; k < n; ++k) {
        cf_status st = push_ellipse_point(b, m, cx, cy, rx, ry, cp, sp, t1 + dt * k / n);
        if (st != CF_OK) return st;
    }
    return push_mapped(b, m, x2, y2);
}

/* A number of path data at *s (after separators) into *v; 0 when there is
 * none. */
static int path_number(const char **s, double *v)
{
    const char *r = skip_sep(*s);
    char *e;
    *v = strtod(r, &e);
    if (e == r) return 0;
    *s = e;
    return 1;
}

/* An arc flag: the single character 0 or 1 (SVG writes "a1 1 0 01 2 2"). */
static int path_flag(const char **s, int *flag)
{
    const char *r = skip_sep(*s);
    if (*r != '0' && *r != '1') return 0;
    *flag = *r == '1';
    *s = r + 1;
    return 1;
}

/* The first subpath of path data; *more is set when drawing commands
 * follow it (further subpaths, ignored by the caller with a warning).
 * Curves (C S Q T A) are flattened (push_cubic, push_quadratic, push_arc). */
static cf_status parse_path(pbuf *b, const char *path, const affine *m, const char *s, int *more)
{
    static const struct {
        char cmd;
        int numbers; /* per repeat */
    } arity[] = {{'M', 2}, {'L', 2}, {'H', 1}, {'V', 1}, {'C', 6}, {'S', 4}, {'Q', 4}, {'T', 2}, {'A', 7}};
    char cmd = 0, previous = 0;
    int numbers = 0;
    double cx = 0.0, cy = 0.0;
    double cubic_x = 0.0, cubic_y = 0.0, quad_x = 0.0, quad_y = 0.0; /* last control points, for S and T */
    int started = 0;
    *more = 0;
    for (;;) {
        s = skip_sep(s);
        if (!*s) return CF_OK;
        if (isalpha((unsigned char)*s)) {
            cmd = *s++;
            if (cmd == 'Z' || cmd == 'z') {   /* first subpath only */
                *more = *skip_sep(s) != '\0';
                return CF_OK;
            }
            numbers = 0;
            for (size_t i = 0; i < sizeof arity / sizeof arity[0]; ++i)
                if (toupper((unsigned char)cmd) == arity[i].cmd) numbers = arity[i].numbers;
            if (!numbers)
                return cfi_error(b->ctx, CF_ERR_PARSE, "%s: unsupported path command '%c' (M L H V C S Q T A Z)", path,
                                 cmd);
            if ((cmd == 'M' || cmd == 'm') && started) {
                *more = 1;
                return CF_OK;
            }
            continue;
        }
        if (!cmd) return cfi_error(b->ctx, CF_ERR_PARSE, "%s: path data must start with a command", path);
        double v[7];
        int flags[2] = {0, 0};
        const char *at = s;
        for (int i = 0; i < numbers; ++i) {
            int ok = (toupper((unsigned char)cmd) == 'A' && (i == 3 || i == 4)) ? path_flag(&s, &flags[i - 3])
                                                                                  : path_number(&s, &v[i]);
            if (ok) continue;
            if (toupper((unsigned char)cmd) == 'A' && (i == 3 || i == 4))
                return cfi_error(b->ctx, CF_ERR_PARSE, "%s: arc flag must be 0 or 1 near \"%.20s\"", path, skip_sep(s));
            if (i == 0) return cfi_error(b->ctx, CF_ERR_PARSE, "%s: bad number in path near \"%.20s\"", path, at);
            return cfi_error(b->ctx, CF_ERR_PARSE, "%s: path command '%c' takes %d numbers; too few near \"%.20s\"",
                             path, cmd, numbers, skip_sep(s));
        }
        int rel = islower((unsigned char)cmd);
        double ox = rel ? cx : 0.0, oy = rel ? cy : 0.0; /* origin of this command's coordinates */
        char up = (char)toupper((unsigned char)cmd);
        double nx = cx, ny = cy;
        cf_status st = CF_OK;
        switch (up) {
        case 'H': nx = ox + v[0]; st = push_mapped(b, m, nx, ny); break;
        case 'V': ny = oy + v[0]; st = push_mapped(b, m, nx, ny); break;
        case 'M': case 'L': nx = ox + v[0]; ny = oy + v[1]; st = push_mapped(b, m, nx, ny); break;
        case 'C': case 'S': {
            /* S: the first control point is the previous C/S's second, reflected */
            double c1x = cx, c1y = cy;
            if (up == 'C') {
                c1x = ox + v[0];
                c1y = oy + v[1];
            } else if (previous == 'C' || previous == 'S') {
                c1x = 2.0 * cx - cubic_x;
                c1y = 2.0 * cy - cubic_y;
            }
            const double *rest = up == 'C' ? v + 2 : v;
            double q[8] = {cx, cy, c1x, c1y, ox + rest[0], oy + rest[1], ox + rest[2], oy + rest[3]};
            st = push_cubic(b, m, q);
            cubic_x = q[4];
            cubic_y = q[5];
            nx = q[6];
            ny = q[7];
            break;
        }
        case 'Q': case 'T': {
            /* T: the control point is the previous Q/T's, reflected */
            double c1x = cx, c1y = cy;
            if (up == 'Q') {
                c1x = ox + v[0];
                c1y = oy + v[1];
            } else if (previous == 'Q' || previous == 'T') {
                c1x = 2.0 * cx - quad_x;
                c1y = 2.0 * cy - quad_y;
            }
            const double *rest = up == 'Q' ? v + 2 : v;
            double q[6] = {cx, cy, c1x, c1y, ox + rest[0], oy + rest[1]};
            st = push_quadratic(b, m, q);
            quad_x = c1x;
            quad_y = c1y;
            nx = q[4];
            ny = q[5];
            break;
        }
        default: /* A rx ry x-axis-rotation large-arc-flag sweep-flag x y */
            nx = ox + v[5];
            ny = oy + v[6];
            st = push_arc(b, m, cx, cy, v[0], v[1], v[2], flags[0], flags[1], nx, ny);
            break;
        }
        if (st != CF_OK) return st;
        started = 1;
        cx = nx;
        cy = ny;
        previous = up;
        if (cmd == 'M') cmd = 'L';   /* implicit repeats of moveto are lineto */
        if (cmd == 'm') cmd = 'l';
    }
}

/* Open elements deeper than this are refused (no real drawing nests so). */
#define SVG_MAX_DEPTH 256

typedef struct svg_scope {
    affine m;   /* this element's user coordinates -> the document's */
    int hidden; /* inside an element that is not drawn */
} svg_scope;

/* The basic shapes read as closed curves, and the attributes they take. */
static const char *const basic_shapes[3] = {"rect", "circle", "ellipse"};
enum { SHAPE_X, SHAPE_Y, SHAPE_WIDTH, SHAPE_HEIGHT, SHAPE_RX, SHAPE_RY, SHAPE_CX, SHAPE_CY, SHAPE_R, SHAPE_ATTRS };
static const char *const shape_attr_names[SHAPE_ATTRS] = {"x", "y", "width", "height", "rx", "ry", "cx", "cy", "r"};

/* An attribute's value as [*vs, *ve), *ve at its closing quote. */
typedef struct svg_attr {
    const char *vs, *ve;
} svg_attr;

/* A length attribute of a basic shape: a number in user units, "px"
 * allowed; *given is 0 (and *out 0, SVG's initial value) when absent. */
static cf_status shape_length(pbuf *b, const char *name, long line, int basic, int attr, const svg_attr *sizes,
                              int *given, double *out)
{
    *given = sizes[attr].vs != NULL;
    *out = 0.0;
    if (!*given) return CF_OK;
    const char *s = sizes[attr].vs, *e = sizes[attr].ve;
    while (s < e && isspace((unsigned char)*s)) ++s;
    char buf[64];
    size_t n = (size_t)(e - s) < sizeof buf - 1 ? (size_t)(e - s) : sizeof buf - 1;
    memcpy(buf, s, n);
    buf[n] = '\0';
    char *stop;
    *out = strtod(buf, &stop);
    if (stop != buf && strncmp(stop, "px", 2) == 0) stop += 2;
    while (isspace((unsigned char)*stop)) ++stop;
    if (stop == buf || *stop || (size_t)(e - s) >= sizeof buf - 1 || !isfinite(*out))
        return cfi_error(b->ctx, CF_ERR_PARSE, "%s: line %ld: <%s> %s=\"%.20s\" is not a number in user units", name, line,
                         basic_shapes[basic], shape_attr_names[attr], buf);
    return CF_OK;
}

/* A <rect>, <circle> or <ellipse> (basic_shapes[basic]) as its closed
 * outline, starting where SVG 2 starts it: a rect's at (x + rx, y) and
 * clockwise on the screen (y down), with its rounded corners (rx, ry:
 * one given stands for both, each at most half the side); a circle's or an
 * ellipse's at (cx + rx, cy). */
static cf_status push_basic_shape(pbuf *b, const char *name, long line, int basic, const svg_attr *sizes,
                                  const affine *m)
{
    double v[SHAPE_ATTRS];
    int given[SHAPE_ATTRS];
    for (int i = 0; i < SHAPE_ATTRS; ++i) {
        cf_status st = shape_length(b, name, line, basic, i, sizes, &given[i], &v[i]);
        if (st != CF_OK) return st;
    }
    static const int size_attrs[3][2] = {{SHAPE_WIDTH, SHAPE_HEIGHT}, {SHAPE_R, SHAPE_R}, {SHAPE_RX, SHAPE_RY}};
    for (int k = 0; k < 2; ++k) {
        int a = size_attrs[basic][k];
        if (!(v[a] > 0.0))
            return cfi_error(b->ctx, CF_ERR_PARSE, "%s: line %ld: <%s> needs %s > 0 (got %g): it draws nothing", name,
                             line, basic_shapes[basic], shape_attr_names[a], v[a]);
    }
    cf_status st = CF_OK;
    if (basic > 0) { /* circle, ellipse */
        double rx = basic == 1 ? v[SHAPE_R] : v[SHAPE_RX], ry = basic == 1 ? v[SHAPE_R] : v[SHAPE_RY];
        int n = arc_pieces(2.0 * SVG_PI);
        for (int k = 0; k < n && st == CF_OK; ++k)
            st = push_ellipse_point(b, m, v[SHAPE_CX], v[SHAPE_CY], rx, ry, 1.0, 0.0, 2.0 * SVG_PI * k / n);
        return st;
    }
    double x = v[SHAPE_X], y = v[SHAPE_Y], w = v[SHAPE_WIDTH], h = v[SHAPE_HEIGHT];
    if (given[SHAPE_RX] && v[SHAPE_RX] < 0.0) return cfi_error(b->ctx, CF_ERR_PARSE, "%s: line %ld: <rect> rx is negative", name, line);
    if (given[SHAPE_RY] && v[SHAPE_RY] < 0.0) return cfi_error(b->ctx, CF_ERR_PARSE, "%s: line %ld: <rect> ry is negative", name, line);
    double rx = given[SHAPE_RX] ? v[SHAPE_RX] : v[SHAPE_RY], ry = given[SHAPE_RY] ? v[SHAPE_RY] : v[SHAPE_RX];
    rx = fmin(rx, 0.5 * w);
    ry = fmin(ry, 0.5 * h);
    if (rx == 0.0 || ry == 0.0) {
        const double corners[8] = {x, y, x + w, y, x + w, y + h, x, y + h};
        for (int k = 0; k < 4 && st == CF_OK; ++k) st = push_mapped(b, m, corners[2 * k], corners[2 * k + 1]);
        return st;
    }
    /* four sides (left out where the corners meet) and four quarter arcs;
     * the last arc ends on the first point, which the reader then drops as
     * the closing repeat */
    const double sides[4][4] = {{x + rx, y, x + w - rx, y}, {x + w, y + ry, x + w, y + h - ry},
                                {x + w - rx, y + h, x + rx, y + h}, {x, y + h - ry, x, y + ry}};
    st = push_mapped(b, m, sides[0][0], sides[0][1]);
    for (int k = 0; k < 4 && st == CF_OK; ++k) {
        const double *side = sides[k], *next = sides[(k + 1) % 4];
        if (side[0] != side[2] || side[1] != side[3]) st = push_mapped(b, m, side[2], side[3]);
        if (st == CF_OK) st = push_arc(b, m, side[2], side[3], rx, ry, 0.0, 0, 1, next[0], next[1]);
    }
    return st;
}

/* 1 when the element name's local part (after a "svg:" style prefix)
 * equals `want`. */
static int name_is(const char *name, size_t len, const char *want)
{
    const char *colon = memchr(name, ':', len);
    if (colon) {
        len -= (size_t)(colon + 1 - name);
        name = colon + 1;
    }
    return strlen(want) == len && strncmp(name, want, len) == 0;
}

/* Reads the first drawn shape of an SVG text into b. The text is NUL
 * terminated; a value being parsed is NUL terminated in place for the
 * moment of its parse. */
static cf_status parse_svg(pbuf *b, const char *name, char *text)
{
    svg_scope *stack = CFI_ALLOC(b->ctx, svg_scope, SVG_MAX_DEPTH);
    if (!stack) return CF_ERR_NOMEM;
    int depth = 0, shapes = 0, hidden_shapes = 0;
    long first_line = 0, subpath_line = 0;
    const char *first_kind = NULL;
    cf_status st = CF_OK;
    char *p = text;
    while (st == CF_OK && (p = strchr(p, '<')) != NULL) {
        static const struct {
            const char *open, *close, *what;
        } skipped[] = {{"<!--", "-->", "comment"}, {"<![CDATA[", "]]>", "CDATA section"}, {"<?", "?>", "processing instruction"}};
        int skip = -1;
        for (int i = 0; i < 3 && skip < 0; ++i)
            if (strncmp(p, skipped[i].open, strlen(skipped[i].open)) == 0) skip = i;
        if (skip >= 0) {
            char *close = strstr(p + strlen(skipped[skip].open), skipped[skip].close);
            if (!close) {
                st = cfi_error(b->ctx, CF_ERR_PARSE, "%s: line %ld: %s not closed (no '%s')", name, line_of(text, p),
                               skipped[skip].what, skipped[skip].close);
                break;
            }
            p = close + strlen(skipped[skip].close);
            continue;
        }
        if (p[1] == '!') { /* <!DOCTYPE ...>, with its internal subset in [ ] */
            int brackets = 0;
            char *q = p + 2;
            for (; *q && (*q != '>' || brackets > 0); ++q) brackets += (*q == '[') - (*q == ']');
            if (!*q) {
                st = cfi_error(b->ctx, CF_ERR_PARSE, "%s: line %ld: declaration '<!' not closed", name, line_of(text, p));
                break;
            }
            p = q + 1;
            continue;
        }
        if (p[1] == '/') { /* end tag: leave the innermost element */
            char *q = strchr(p, '>');
            if (!q) {
                st = cfi_error(b->ctx, CF_ERR_PARSE, "%s: line %ld: end tag not closed (file ends inside it)", name,
                               line_of(text, p));
                break;
            }
            if (depth > 0) --depth;
            p = q + 1;
            continue;
        }
        /* start tag: name, attributes, then '>' or "/>" */
        char *tag = p + 1, *q = tag;
        while (*q && (isalnum((unsigned char)*q) || *q == '_' || *q == ':' || *q == '-' || *q == '.')) ++q;
        size_t tag_len = (size_t)(q - tag);
        if (tag_len == 0) { /* a stray '<' in text */
            ++p;
            continue;
        }
        svg_attr points = {NULL, NULL}, d = {NULL, NULL}, transform = {NULL, NULL};
        svg_attr sizes[SHAPE_ATTRS] = {{NULL, NULL}};
        int self_closing = 0;
        for (;;) {
            while (isspace((unsigned char)*q)) ++q;
            if (*q == '>') break;
            if (q[0] == '/' && q[1] == '>') {
                self_closing = 1;
                ++q;
                break;
            }
            const char *an = q;
            while (*q && !isspace((unsigned char)*q) && *q != '=' && *q != '>' && *q != '/') ++q;
            size_t an_len = (size_t)(q - an);
            while (isspace((unsigned char)*q)) ++q;
            if (an_len == 0 || *q != '=') break; /* malformed: reported below */
            ++q;
            while (isspace((unsigned char)*q)) ++q;
            if (*q != '"' && *q != '\'') break;
            char quote = *q++;
            char *close = strchr(q, quote);
            if (!close) break;
            svg_attr value = {q, close};
            if (an_len == 6 && strncmp(an, "points", 6) == 0) points = value;
            else if (an_len == 1 && an[0] == 'd') d = value;
            else if (an_len == 9 && strncmp(an, "transform", 9) == 0) transform = value;
            for (int i = 0; i < SHAPE_ATTRS; ++i)
                if (an_len == strlen(shape_attr_names[i]) && strncmp(an, shape_attr_names[i], an_len) == 0) sizes[i] = value;
            q = close + 1;
        }
        if (*q != '>') {
            st = cfi_error(b->ctx, CF_ERR_PARSE, "%s: line %ld: malformed or unclosed tag <%.*s", name, line_of(text, p),
                           (int)(tag_len > 32 ? 32 : tag_len), tag);
            break;
        }
        const svg_scope *parent = depth > 0 ? &stack[depth - 1] : NULL;
        svg_scope scope = {parent ? parent->m : identity_map, parent ? parent->hidden : 0};
        static const char *const not_drawn[] = {"defs", "clipPath", "mask", "symbol", "marker", "pattern"};
        for (int i = 0; i < 6; ++i) scope.hidden |= name_is(tag, tag_len, not_drawn[i]);
        int is_polygon = name_is(tag, tag_len, "polygon"), is_polyline = name_is(tag, tag_len, "polyline"),
            is_path = name_is(tag, tag_len, "path");
        int basic = -1; /* index into basic_shapes */
        for (int i = 0; i < 3; ++i)
            if (name_is(tag, tag_len, basic_shapes[i])) basic = i;
        int shape = (is_polygon || is_polyline) ? points.vs != NULL : is_path ? d.vs != NULL : basic >= 0;
        if (shape && scope.hidden) ++hidden_shapes;
        else if (shape && ++shapes == 1) {
            long line = line_of(text, p);
            first_line = line;
            first_kind = is_polygon ? "polygon" : is_polyline ? "polyline" : is_path ? "path" : basic_shapes[basic];
            if (transform.vs) {
                affine own;
                st = parse_transform(b, name, text, p, transform.vs, transform.ve, &own);
                if (st != CF_OK) break;
                scope.m = compose(scope.m, own);
            }
            int more = 0;
            if (basic >= 0) {
                st = push_basic_shape(b, name, line, basic, sizes, &scope.m);
            } else {
                svg_attr v = is_path ? d : points;
                char *end = (char *)v.ve, saved = *end;
                *end = '\0';
                st = is_path ? parse_path(b, name, &scope.m, v.vs, &more) : parse_points(b, name, &scope.m, v.vs);
                *end = saved;
            }
            if (st != CF_OK) break;
            if (more) subpath_line = line;
        } else if (!self_closing && transform.vs) {
            affine own;
            st = parse_transform(b, name, text, p, transform.vs, transform.ve, &own);
            if (st != CF_OK) break;
            scope.m = compose(scope.m, own);
        }
        if (!self_closing) {
            if (depth == SVG_MAX_DEPTH) {
                st = cfi_error(b->ctx, CF_ERR_PARSE, "%s: line %ld: elements nested deeper than %d", name,
                               line_of(text, p), SVG_MAX_DEPTH);
                break;
            }
            stack[depth++] = scope;
        }
        p = q + 1;
    }
    CFI_FREE(b->ctx, stack, SVG_MAX_DEPTH);
    if (st != CF_OK) return st;
    if (shapes == 0)
        return hidden_shapes ? cfi_error(b->ctx, CF_ERR_PARSE,
                                         "%s: no drawn <polygon>, <polyline>, <path>, <rect>, <circle> or <ellipse> (%d inside defs, clipPath, mask, "
                                         "symbol, marker or pattern, which are not drawn)",
                                         name, hidden_shapes)
                             : cfi_error(b->ctx, CF_ERR_PARSE, "%s: no <polygon>, <polyline>, <path>, <rect>, <circle> or <ellipse> found",
                                         name);
    if (subpath_line)
        cfi_log(b->ctx, CF_LOG_WARNING,
                "%s: line %ld: the <path> holds more than one subpath; the first is read and the others are ignored "
                "(the curve flow takes one closed curve)",
                name, subpath_line);
    if (shapes > 1)
        cfi_log(b->ctx, CF_LOG_WARNING,
                "%s: %d shapes are drawn; the first, the <%s> of line %ld, is read and the other%s ignored (the "
                "curve flow takes one closed curve)",
                name, shapes, first_kind, first_line, shapes == 2 ? " one is" : "s are");
    return CF_OK;
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
        st = parse_svg(&b, name, text);
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
