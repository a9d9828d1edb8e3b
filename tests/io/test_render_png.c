/*
 * Software renderer (src/io/render_png.c): silhouette size of a sphere
 * under orthographic projection, headlight shading, depth test, uv
 * checkerboard placement, the mesh's own colours (per vertex, interpolated;
 * per face), PNG round trip (decoded with stb_image) and error paths.
 */
#include "curvflow/generate.h"
#include "curvflow/ops.h"
#include "curvflow/render.h"
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "png_read.h"

enum { W = 101, H = 101 };

static int is_background(const uint8_t *p) { return p[0] == 255 && p[1] == 255 && p[2] == 255; }

/* Default options for a W x H image viewed along +z. */
static void front_view_options(cf_render_options *o)
{
    cf_render_options_default(o);
    o->width = W;
    o->height = H;
    o->view[0] = 0.0;
    o->view[1] = 0.0;
    o->view[2] = 1.0;
}

static void test_sphere_silhouette_and_shading(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 4, 1.0, &mesh));
    if (!mesh) { cf_context_destroy(&ctx); return; }
    cf_render_options o;
    front_view_options(&o);
    uint8_t *rgb = malloc(3 * W * H);
    CHECK_OK(ctx, cf_render_rgb(ctx, mesh, NULL, &o, rgb));
    int covered = 0;
    for (int p = 0; p < W * H; ++p) covered += !is_background(rgb + 3 * p);
    /* The unit sphere fills `fill` (0.9) of the image width: a disc of radius
     * 0.45 W, area fraction pi 0.45^2 = 0.636. Pixel-centre sampling of the
     * boundary gives O(1/W) relative error (~2 % at W = 101). */
    CHECK_NEAR((double)covered / (W * H), acos(-1.0) * 0.45 * 0.45, 0.03, 0.0);
    /* Headlight: the centre faces the camera, so it shows the full colour. */
    const uint8_t *c = rgb + 3 * (H / 2 * W + W / 2);
    CHECK(abs((int)c[0] - (int)(0.72 * 255 + 0.5)) <= 2);
    CHECK(abs((int)c[2] - (int)(0.84 * 255 + 0.5)) <= 2);
    /* Near the rim the normal is almost perpendicular to the view: darker. */
    const uint8_t *rim = rgb + 3 * (H / 2 * W + W / 2 + 44);
    CHECK(!is_background(rim));
    CHECK(rim[0] < c[0] / 2 + 10);

    /* Depth test: colour faces by the sign of their normal's z; the visible
     * side is the front (z > 0), shown red (top of the range). */
    int32_t nf = cf_mesh_face_count(mesh);
    double *normals = malloc(3 * (size_t)nf * sizeof *normals);
    double *field = malloc((size_t)nf * sizeof *field);
    CHECK_OK(ctx, cf_face_normals(ctx, mesh, cf_mesh_positions(mesh), normals));
    for (int32_t f = 0; f < nf; ++f) field[f] = normals[3 * f + 2] > 0 ? 1.0 : -1.0;
    o.face_field = field;
    o.field_min = -1.0;
    o.field_max = 1.0;
    CHECK_OK(ctx, cf_render_rgb(ctx, mesh, NULL, &o, rgb));
    CHECK(c[0] > 150 && c[2] < 60); /* red, not blue */
    o.perspective = 1;
    CHECK_OK(ctx, cf_render_rgb(ctx, mesh, NULL, &o, rgb));
    CHECK(c[0] > 150 && c[2] < 60);
    free(normals);
    free(field);
    free(rgb);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* The checkerboard follows uv: on the unit grid seen from +z, uv = (x, y). */
static void test_uv_checker(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_grid(ctx, 8, 8, 1.0, 1.0, &mesh));
    if (!mesh) { cf_context_destroy(&ctx); return; }
    cf_render_options o;
    front_view_options(&o);
    o.ambient = 1.0; /* flat: only the checker changes the colour */
    o.uv_checker = 1;
    o.checker_count = 4.0;
    uint8_t *rgb = malloc(3 * W * H);
    CHECK_OK(ctx, cf_render_rgb(ctx, mesh, NULL, &o, rgb));
    double scale = 0.9 * W / (2.0 * sqrt(0.5)); /* bounding radius of the unit square */
    int light = 0, dark = 0, wrong = 0;
    for (double u = 0.05; u < 1.0; u += 0.1) {
        for (double v = 0.05; v < 1.0; v += 0.1) {
            int px = (int)(W / 2.0 + (u - 0.5) * scale), py = (int)(H / 2.0 - (v - 0.5) * scale);
            /* skip samples within a pixel of a checker line */
            double fu = u * 4 - floor(u * 4), fv = v * 4 - floor(v * 4);
            if (fu < 0.1 || fu > 0.9 || fv < 0.1 || fv > 0.9) continue;
            const uint8_t *p = rgb + 3 * (py * W + px);
            int expect_dark = ((int)floor(u * 4) + (int)floor(v * 4)) & 1;
            int is_dark = p[0] < 0.72 * 255 * 0.8;
            wrong += expect_dark != is_dark;
            light += !is_dark;
            dark += is_dark;
        }
    }
    CHECK(wrong == 0);
    CHECK(light > 10 && dark > 10);
    free(rgb);

    /* errors */
    cf_mesh *ico = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 1, 1.0, &ico));
    uint8_t tiny[3 * 4 * 4];
    o.width = o.height = 4;
    CHECK_STATUS(cf_render_rgb(ctx, ico, NULL, &o, tiny), CF_ERR_INVALID_ARG); /* no uv */
    CHECK(strstr(cf_context_message(ctx), "uv") != NULL);
    o.uv_checker = 0;
    o.up[0] = 0.0;
    o.up[1] = 0.0;
    o.up[2] = 2.0;
    CHECK_STATUS(cf_render_rgb(ctx, ico, NULL, &o, tiny), CF_ERR_INVALID_ARG);
    /* up along an oblique view: the projection leaves only rounding, which
     * must still count as parallel */
    double saved_view[3] = {o.view[0], o.view[1], o.view[2]};
    static const double oblique[3] = {0.4, 0.5, 1.0}; /* accepted before the relative test */
    for (int k = 0; k < 3; ++k) o.view[k] = o.up[k] = oblique[k];
    CHECK_STATUS(cf_render_rgb(ctx, ico, NULL, &o, tiny), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "parallel") != NULL);
    for (int k = 0; k < 3; ++k) o.view[k] = saved_view[k];
    o.up[0] = 0.0;
    o.up[2] = 0.0;
    o.up[1] = 1.0;
    o.width = 0;
    CHECK_STATUS(cf_render_rgb(ctx, ico, NULL, &o, tiny), CF_ERR_INVALID_ARG);
    o.width = 4;
    CHECK_OK(ctx, cf_render_rgb(ctx, ico, NULL, &o, tiny));
    CHECK_STATUS(cf_render_png(ctx, "/nonexistent-dir/x.png", ico, NULL, &o), CF_ERR_IO);
    cf_mesh_destroy(&ico);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* The mesh's own colours (session 30): vertex colours interpolated
 * barycentrically across a face (a unit grid with red growing along x and
 * green along y shows each pixel's own mix), face colours constant per
 * face; a face field wins over both; a non-finite colour is refused. */
static void test_own_colours(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_grid(ctx, 4, 4, 1.0, 1.0, &mesh));
    if (!mesh) { cf_context_destroy(&ctx); return; }
    int32_t nv = cf_mesh_vertex_count(mesh), nf = cf_mesh_face_count(mesh);
    const double *x = cf_mesh_positions(mesh);
    double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
    for (int32_t v = 0; v < nv; ++v)
        for (int k = 0; k < 2; ++k) lo[k] = fmin(lo[k], x[3 * v + k]), hi[k] = fmax(hi[k], x[3 * v + k]);
    double *vc = malloc(3 * (size_t)nv * sizeof *vc), *fc = malloc(3 * (size_t)nf * sizeof *fc);
    for (int32_t v = 0; v < nv; ++v) {
        vc[3 * v] = (x[3 * v] - lo[0]) / (hi[0] - lo[0]);
        vc[3 * v + 1] = (x[3 * v + 1] - lo[1]) / (hi[1] - lo[1]);
        vc[3 * v + 2] = 0.5;
    }
    for (int32_t f = 0; f < nf; ++f) fc[3 * f] = 0.1, fc[3 * f + 1] = f % 2 ? 0.9 : 0.3, fc[3 * f + 2] = 1.7;
    cf_render_options o;
    front_view_options(&o);
    o.ambient = 1.0; /* flat: the colour alone */
    o.vertex_colors = vc;
    uint8_t *rgb = malloc(3 * W * H);
    CHECK_OK(ctx, cf_render_rgb(ctx, mesh, NULL, &o, rgb));
    double scale = 0.9 * W / (2.0 * sqrt(0.5));
    int checked = 0;
    double worst = 0.0;
    for (double u = 0.1; u < 0.95; u += 0.2)
        for (double v = 0.1; v < 0.95; v += 0.2) {
            int px = (int)(W / 2.0 + (u - 0.5) * scale), py = (int)(H / 2.0 - (v - 0.5) * scale);
            /* the pixel centre's own (u, v): linear colours are interpolated exactly */
            double cu = (px + 0.5 - W / 2.0) / scale + 0.5, cv = (H / 2.0 - py - 0.5) / scale + 0.5;
            const uint8_t *p = rgb + 3 * (py * W + px);
            worst = fmax(worst, fmax(fabs(p[0] - 255.0 * cu), fabs(p[1] - 255.0 * cv)));
            worst = fmax(worst, fabs(p[2] - 127.5));
            ++checked;
        }
    CHECK(checked == 25);
    if (!(worst <= 1.0)) cft_fail(__FILE__, __LINE__, "vertex colours off by %g of 255", worst);
    /* face colours (clamped to [0, 1]) take precedence over vertex colours */
    o.face_colors = fc;
    CHECK_OK(ctx, cf_render_rgb(ctx, mesh, NULL, &o, rgb));
    int greens[2] = {0, 0}, others = 0;
    for (int p = 0; p < W * H; ++p) {
        const uint8_t *q = rgb + 3 * p;
        if (is_background(q)) continue;
        if (q[0] == 26 && q[2] == 255 && (q[1] == 230 || q[1] == 77)) greens[q[1] == 230]++;
        else ++others;
    }
    CHECK(greens[0] > 100 && greens[1] > 100 && others == 0);
    /* a face field wins */
    double *field = calloc((size_t)nf, sizeof *field);
    o.face_field = field;
    CHECK_OK(ctx, cf_render_rgb(ctx, mesh, NULL, &o, rgb));
    const uint8_t *c = rgb + 3 * (H / 2 * W + W / 2);
    CHECK(c[0] == 59 && c[1] == 77 && c[2] == 191); /* the map's low end (0.23, 0.30, 0.75) for a constant field */
    o.face_field = NULL;
    fc[3 * 5 + 1] = NAN;
    CHECK_STATUS(cf_render_rgb(ctx, mesh, NULL, &o, rgb), CF_ERR_NONFINITE);
    CHECK(strstr(cf_context_message(ctx), "face 5: colour is not finite") != NULL);
    o.face_colors = NULL;
    vc[3 * 7 + 2] = INFINITY;
    CHECK_STATUS(cf_render_rgb(ctx, mesh, NULL, &o, rgb), CF_ERR_NONFINITE);
    CHECK(strstr(cf_context_message(ctx), "vertex 7: colour is not finite") != NULL);
    free(field);
    free(rgb);
    free(vc);
    free(fc);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* PNG is lossless: decoding the file gives back the rendered bytes. */
static void test_png_round_trip(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 2, 0.2, 3u, &mesh));
    if (!mesh) { cf_context_destroy(&ctx); return; }
    cf_render_options o;
    cf_render_options_default(&o);
    o.width = 64;
    o.height = 48;
    o.uv_checker = 1;
    uint8_t *rgb = malloc(3 * 64 * 48);
    CHECK_OK(ctx, cf_render_rgb(ctx, mesh, NULL, &o, rgb));
    char path[4096];
    snprintf(path, sizeof path, "%s", cft_temp_path(".png"));
    CHECK_OK(ctx, cf_render_png(ctx, path, mesh, NULL, &o));
    int w = 0, h = 0;
    unsigned char *img = cft_png_load_rgb(path, &w, &h);
    CHECK(img != NULL);
    if (img) {
        CHECK(w == 64 && h == 48);
        CHECK(memcmp(img, rgb, 3 * 64 * 48) == 0);
        cft_png_free(img);
    }
    unlink(path);
    free(rgb);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_sphere_silhouette_and_shading);
    CFT_RUN(test_uv_checker);
    CFT_RUN(test_own_colours);
    CFT_RUN(test_png_round_trip);
    return cft_finish();
}
