/*
 * Software renderer (include/curvflow/render.h): projects the triangles,
 * rasterises them with edge functions and a depth buffer, shades with a
 * headlight (Lambert + ambient), optionally colours faces by a scalar field
 * or modulates by a uv checkerboard, and writes PNG through stb_image_write
 * (Debian libstb-dev) into an atomic file.
 *
 * Deviation from the allocation rule: stb_image_write's PNG compressor
 * allocates with malloc internally (it has no allocator context); the
 * depth buffer and everything else go through the context.
 */
#include "curvflow/render.h"

#include "core/core.h"
#include "io/atomic_file.h"
#include "mesh/mesh_internal.h"

#include <math.h>
#include <string.h>

#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wpedantic"
#pragma GCC diagnostic ignored "-Wmissing-prototypes"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#endif
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#define STBI_WRITE_NO_STDIO
#include <stb_image_write.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
/* stb declares its HDR writer static without defining it under
 * STBI_WRITE_NO_STDIO; GCC reports that at the end of the file. */
#pragma GCC diagnostic ignored "-Wunused-function"
#endif

void cf_render_options_default(cf_render_options *o)
{
    if (!o) return;
    memset(o, 0, sizeof *o);
    o->width = 800;
    o->height = 800;
    o->view[0] = 0.4;
    o->view[1] = 0.5;
    o->view[2] = 1.0;
    o->up[1] = 1.0;
    o->perspective = 0;
    o->fill = 0.9;
    o->background[0] = o->background[1] = o->background[2] = 1.0;
    o->color[0] = 0.72;
    o->color[1] = 0.76;
    o->color[2] = 0.84;
    o->ambient = 0.25;
    o->face_field = NULL;
    o->field_min = 0.0;
    o->field_max = 0.0;
    o->uv_checker = 0;
    o->checker_count = 16.0;
    o->vertex_colors = NULL;
    o->face_colors = NULL;
}

static double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void cross3(const double *a, const double *b, double *out)
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static int normalize3(double *v)
{
    double n = sqrt(dot3(v, v));
    if (!(n > 1e-300) || !isfinite(n)) return 0;
    v[0] /= n;
    v[1] /= n;
    v[2] /= n;
    return 1;
}

/* Diverging blue - white - red map for t in [0, 1]. */
static void color_map(double t, double *rgb)
{
    static const double lo[3] = {0.23, 0.30, 0.75}, mid[3] = {0.92, 0.92, 0.92}, hi[3] = {0.71, 0.02, 0.15};
    if (!(t >= 0.0)) t = 0.0;
    if (t > 1.0) t = 1.0;
    for (int k = 0; k < 3; ++k)
        rgb[k] = t < 0.5 ? lo[k] + (mid[k] - lo[k]) * 2.0 * t : mid[k] + (hi[k] - mid[k]) * (2.0 * t - 1.0);
}

static uint8_t to_byte(double v)
{
    if (!(v > 0.0)) return 0;
    if (v >= 1.0) return 255;
    return (uint8_t)(v * 255.0 + 0.5);
}

static cf_status check_options(cf_context *ctx, const cf_mesh *mesh, const cf_render_options *o)
{
    if (o->width < 1 || o->height < 1 || o->width > 16384 || o->height > 16384)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "render: image size %d x %d outside 1..16384", (int)o->width,
                         (int)o->height);
    for (int k = 0; k < 3; ++k)
        if (!isfinite(o->view[k]) || !isfinite(o->up[k]) || !isfinite(o->background[k]) || !isfinite(o->color[k]))
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "render: view, up and colours must be finite");
    if (!(o->fill > 0.0 && o->fill <= 10.0)) return cfi_error(ctx, CF_ERR_INVALID_ARG, "render: fill %g outside (0, 10]", o->fill);
    if (!(o->ambient >= 0.0 && o->ambient <= 1.0))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "render: ambient %g outside [0, 1]", o->ambient);
    if (o->uv_checker) {
        if (!mesh->uv) return cfi_error(ctx, CF_ERR_INVALID_ARG, "render: uv checker requested but the mesh has no uv");
        if (!(o->checker_count > 0.0) || !isfinite(o->checker_count))
            return cfi_error(ctx, CF_ERR_INVALID_ARG, "render: checker_count %g must be positive", o->checker_count);
    }
    return CF_OK;
}

cf_status cf_render_rgb(cf_context *ctx, const cf_mesh *mesh, const double *positions, const cf_render_options *o,
                        uint8_t *rgb)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!mesh || !o || !rgb) return cfi_error(ctx, CF_ERR_INVALID_ARG, "render: NULL argument");
    cf_status st = check_options(ctx, mesh, o);
    if (st != CF_OK) return st;
    const double *x = positions ? positions : mesh->positions;
    int32_t nv = mesh->nv, nf = mesh->nf;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int32_t v = 0; v < nv; ++v)
        for (int k = 0; k < 3; ++k) {
            double c = x[3 * (size_t)v + k];
            if (!isfinite(c)) return cfi_error(ctx, CF_ERR_NONFINITE, "vertex %d: position is not finite", v);
            lo[k] = fmin(lo[k], c);
            hi[k] = fmax(hi[k], c);
        }
    double fmin_v = o->field_min, fmax_v = o->field_max;
    const double *vcol = o->face_field || o->face_colors ? NULL : o->vertex_colors;
    const double *fcol = o->face_field ? NULL : o->face_colors;
    for (size_t i = 0; vcol && i < 3 * (size_t)nv; ++i)
        if (!isfinite(vcol[i])) return cfi_error(ctx, CF_ERR_NONFINITE, "vertex %zu: colour is not finite", i / 3);
    for (size_t i = 0; fcol && i < 3 * (size_t)nf; ++i)
        if (!isfinite(fcol[i])) return cfi_error(ctx, CF_ERR_NONFINITE, "face %zu: colour is not finite", i / 3);
    if (o->face_field) {
        double a = INFINITY, b = -INFINITY;
        for (int32_t f = 0; f < nf; ++f) {
            double q = o->face_field[f];
            if (!isfinite(q)) return cfi_error(ctx, CF_ERR_NONFINITE, "face %d: field value is not finite", f);
            a = fmin(a, q);
            b = fmax(b, q);
        }
        if (!(fmin_v < fmax_v)) {
            fmin_v = a;
            fmax_v = b > a ? b : a + 1.0;
        }
    }
    /* bounding sphere: centre of the box, radius to the farthest vertex */
    double center[3], radius = 0.0;
    for (int k = 0; k < 3; ++k) center[k] = 0.5 * (lo[k] + hi[k]);
    for (int32_t v = 0; v < nv; ++v) {
        const double *p = x + 3 * (size_t)v;
        double q[3] = {p[0] - center[0], p[1] - center[1], p[2] - center[2]};
        radius = fmax(radius, dot3(q, q));
    }
    radius = sqrt(radius);
    if (!(radius > 0.0)) return cfi_error(ctx, CF_ERR_INVALID_ARG, "render: the mesh has zero extent");

    /* Camera frame: d towards the camera, u up, r = u x d right (r, u, d right-handed). */
    double d[3] = {o->view[0], o->view[1], o->view[2]}, u[3], r[3];
    if (!normalize3(d)) return cfi_error(ctx, CF_ERR_INVALID_ARG, "render: view direction is zero");
    double ud = dot3(o->up, d), up_len = sqrt(dot3(o->up, o->up));
    for (int k = 0; k < 3; ++k) u[k] = o->up[k] - ud * d[k];
    /* relative test: for an up exactly along view the projection leaves
     * only rounding (~1e-17 |up|), which normalize3 alone would accept */
    if (!(sqrt(dot3(u, u)) > 1e-9 * up_len) || !normalize3(u))
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "render: up is parallel to the view direction (or zero)");
    cross3(u, d, r);
    double cam_dist = 3.0 * radius;
    double cam[3] = {center[0] + cam_dist * d[0], center[1] + cam_dist * d[1], center[2] + cam_dist * d[2]};
    int32_t w = o->width, h = o->height;
    double scale = o->fill * (double)(w < h ? w : h) / (2.0 * radius);

    size_t npix = (size_t)w * (size_t)h;
    double *zbuf = CFI_ALLOC(ctx, double, npix);
    if (!zbuf) return CF_ERR_NOMEM;
    for (size_t p = 0; p < npix; ++p) {
        zbuf[p] = -INFINITY;
        for (int k = 0; k < 3; ++k) rgb[3 * p + k] = to_byte(o->background[k]);
    }

    for (int32_t f = 0; f < nf; ++f) {
        const int32_t *t = mesh->triangles + 3 * (size_t)f;
        double sx[3], sy[3], sz[3];
        for (int k = 0; k < 3; ++k) {
            const double *p = x + 3 * (size_t)t[k];
            double q[3] = {p[0] - center[0], p[1] - center[1], p[2] - center[2]};
            double a = dot3(q, r), b = dot3(q, u), c = dot3(q, d);
            if (o->perspective) {
                double s = cam_dist / (cam_dist - c); /* |q| <= radius < cam_dist */
                a *= s;
                b *= s;
            }
            sx[k] = 0.5 * w + a * scale;
            sy[k] = 0.5 * h - b * scale;
            sz[k] = c;
        }
        double area2 = (sx[1] - sx[0]) * (sy[2] - sy[0]) - (sx[2] - sx[0]) * (sy[1] - sy[0]);
        if (fabs(area2) < 1e-12) continue; /* seen edge-on */
        /* Lambert with a headlight; back faces (open meshes) darker. */
        const double *p0 = x + 3 * (size_t)t[0], *p1 = x + 3 * (size_t)t[1], *p2 = x + 3 * (size_t)t[2];
        double e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
        double e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
        double n[3];
        cross3(e1, e2, n);
        if (!normalize3(n)) continue;
        double to_eye[3] = {d[0], d[1], d[2]};
        if (o->perspective) {
            for (int k = 0; k < 3; ++k) to_eye[k] = cam[k] - (p0[k] + p1[k] + p2[k]) / 3.0;
            normalize3(to_eye);
        }
        double facing = dot3(n, to_eye);
        double shade = o->ambient + (1.0 - o->ambient) * fabs(facing);
        if (facing < 0.0) shade *= 0.6;
        double base[3] = {o->color[0], o->color[1], o->color[2]};
        if (o->face_field) color_map((o->face_field[f] - fmin_v) / (fmax_v - fmin_v), base);
        if (fcol)
            for (int c = 0; c < 3; ++c) base[c] = fcol[3 * (size_t)f + (size_t)c];
        const double *c0 = vcol ? vcol + 3 * (size_t)t[0] : NULL, *c1 = vcol ? vcol + 3 * (size_t)t[1] : NULL,
                     *c2 = vcol ? vcol + 3 * (size_t)t[2] : NULL;
        const double *uv0 = NULL, *uv1 = NULL, *uv2 = NULL;
        if (o->uv_checker) {
            const int32_t *ut = mesh->uv_triangles + 3 * (size_t)f;
            uv0 = mesh->uv + 2 * (size_t)ut[0];
            uv1 = mesh->uv + 2 * (size_t)ut[1];
            uv2 = mesh->uv + 2 * (size_t)ut[2];
        }
        int32_t x0 = (int32_t)floor(fmin(sx[0], fmin(sx[1], sx[2]))), x1 = (int32_t)ceil(fmax(sx[0], fmax(sx[1], sx[2])));
        int32_t y0 = (int32_t)floor(fmin(sy[0], fmin(sy[1], sy[2]))), y1 = (int32_t)ceil(fmax(sy[0], fmax(sy[1], sy[2])));
        if (x0 < 0) x0 = 0;
        if (y0 < 0) y0 = 0;
        if (x1 > w - 1) x1 = w - 1;
        if (y1 > h - 1) y1 = h - 1;
        for (int32_t py = y0; py <= y1; ++py) {
            for (int32_t px = x0; px <= x1; ++px) {
                double cx = px + 0.5, cy = py + 0.5;
                /* barycentric coordinates from edge functions */
                double b0 = ((sx[1] - cx) * (sy[2] - cy) - (sx[2] - cx) * (sy[1] - cy)) / area2;
                double b1 = ((sx[2] - cx) * (sy[0] - cy) - (sx[0] - cx) * (sy[2] - cy)) / area2;
                double b2 = 1.0 - b0 - b1;
                if (b0 < 0.0 || b1 < 0.0 || b2 < 0.0) continue;
                double z = b0 * sz[0] + b1 * sz[1] + b2 * sz[2];
                size_t pix = (size_t)py * (size_t)w + (size_t)px;
                if (!(z > zbuf[pix])) continue;
                zbuf[pix] = z;
                double k = shade;
                if (o->uv_checker) {
                    double uu = b0 * uv0[0] + b1 * uv1[0] + b2 * uv2[0];
                    double vv = b0 * uv0[1] + b1 * uv1[1] + b2 * uv2[1];
                    /* parity of the cell index, in doubles: casting floor(u n)
                     * to an integer overflows (UB) for large uv or n */
                    double cell = floor(uu * o->checker_count) + floor(vv * o->checker_count);
                    if (fabs(fmod(cell, 2.0)) == 1.0) k *= 0.55;
                }
                if (vcol)
                    for (int c = 0; c < 3; ++c) base[c] = b0 * c0[c] + b1 * c1[c] + b2 * c2[c];
                for (int c = 0; c < 3; ++c) rgb[3 * pix + (size_t)c] = to_byte(k * base[c]);
            }
        }
    }
    CFI_FREE(ctx, zbuf, npix);
    return CF_OK;
}

typedef struct png_sink {
    FILE *fp;
    int failed;
} png_sink;

static void png_write_cb(void *context, void *data, int size)
{
    png_sink *s = context;
    if (size > 0 && fwrite(data, 1, (size_t)size, s->fp) != (size_t)size) s->failed = 1;
}

cf_status cf_write_png(cf_context *ctx, const char *path, int32_t width, int32_t height, const uint8_t *rgb)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!path || !rgb) return cfi_error(ctx, CF_ERR_INVALID_ARG, "write_png: NULL argument");
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "%s: image size %d x %d outside 1..16384", path, (int)width, (int)height);
    cfi_atomic_file f;
    cf_status st = cfi_atomic_open(ctx, path, &f);
    if (st != CF_OK) return st;
    png_sink sink = {f.fp, 0};
    int ok = stbi_write_png_to_func(png_write_cb, &sink, width, height, 3, rgb, 3 * width);
    if (!ok || sink.failed) {
        cfi_atomic_abort(ctx, &f);
        return cfi_error(ctx, CF_ERR_IO, "%s: PNG encoding or writing failed", path);
    }
    return cfi_atomic_commit(ctx, &f);
}

cf_status cf_render_png(cf_context *ctx, const char *path, const cf_mesh *mesh, const double *positions,
                        const cf_render_options *options)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (!options || !path) return cfi_error(ctx, CF_ERR_INVALID_ARG, "render: NULL argument");
    size_t bytes = 3 * (size_t)(options->width > 0 ? options->width : 0) * (size_t)(options->height > 0 ? options->height : 0);
    if (bytes == 0 || options->width > 16384 || options->height > 16384)
        return cfi_error(ctx, CF_ERR_INVALID_ARG, "render: image size %d x %d outside 1..16384", (int)options->width,
                         (int)options->height);
    uint8_t *rgb = CFI_ALLOC(ctx, uint8_t, bytes);
    if (!rgb) return CF_ERR_NOMEM;
    cf_status st = cf_render_rgb(ctx, mesh, positions, options, rgb);
    if (st == CF_OK) st = cf_write_png(ctx, path, options->width, options->height, rgb);
    CFI_FREE(ctx, rgb, bytes);
    return st;
}
