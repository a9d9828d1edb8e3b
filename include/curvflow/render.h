/*
 * A small software renderer for pictures of results: z-buffered
 * rasterisation of the triangles (orthographic or perspective), Lambert
 * shading from a light at the camera plus ambient, an optional per-face
 * scalar colour map (e.g. the quasi-conformal error Q) and an optional
 * checkerboard from the texture coordinates (to show that a flow preserves
 * the texture). Output as an RGB buffer or a PNG file (written atomically).
 *
 * Camera: it looks at the centre of the bounding box from direction `view`
 * (from the object towards the camera), with `up` projected to the screen's
 * vertical; the object fills `fill` of the smaller image side.
 */
#ifndef CURVFLOW_RENDER_H
#define CURVFLOW_RENDER_H

#include "curvflow/curvflow.h"
#include "curvflow/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cf_render_options {
    int32_t width, height;      /* pixels, 1..16384 (default 800 x 800) */
    double view[3];             /* towards the camera (default (0.4, 0.5, 1)) */
    double up[3];               /* default (0, 1, 0); must not be parallel to view */
    int32_t perspective;        /* 0: orthographic (default), 1: perspective (camera at 3 radii) */
    double fill;                /* fraction of the smaller side the bounding sphere fills (default 0.9) */
    double background[3];       /* RGB in [0, 1] (default white) */
    double color[3];            /* surface colour without a field (default light grey-blue) */
    double ambient;             /* in [0, 1] (default 0.25) */
    /* Per-face scalar field (nf values) shown with a blue-white-red map
     * from field_min to field_max (if field_min >= field_max the data range
     * is used). NULL: plain colour. */
    const double *face_field;
    double field_min, field_max;
    /* Nonzero: multiply the colour by a checkerboard of the texture
     * coordinates with `checker_count` squares per unit of uv (default 16).
     * Needs a mesh with uv (CF_ERR_INVALID_ARG otherwise). */
    int32_t uv_checker;
    double checker_count;
    /* The mesh's own colours, RGB in [0, 1] (values outside are clamped):
     * vertex_colors (3 nv, interpolated across each face) or face_colors
     * (3 nf), e.g. a scan's colours read from its file. face_field, when
     * given, takes precedence; NULL (default): none. Session 30. */
    const double *vertex_colors;
    const double *face_colors;
} cf_render_options;

CF_API void cf_render_options_default(cf_render_options *options);

/* Renders into rgb (3 * width * height bytes, row by row from the top,
 * caller-allocated). positions: 3 nv (NULL: rest positions). Statuses:
 * CF_OK, CF_ERR_INVALID_ARG (NULL, sizes, parallel view/up, uv_checker
 * without uv), CF_ERR_NONFINITE (position, field value or colour),
 * CF_ERR_NOMEM. */
CF_API cf_status cf_render_rgb(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                               const cf_render_options *options, uint8_t *rgb);

/* Renders and writes a PNG atomically. Same statuses plus CF_ERR_IO. */
CF_API cf_status cf_render_png(cf_context *ctx, const char *path, const cf_mesh *mesh, const double *positions,
                               const cf_render_options *options);

/* Encodes an RGB buffer (3 * width * height bytes, rows from the top) as
 * PNG and writes it atomically. Statuses: CF_OK, CF_ERR_INVALID_ARG (NULL
 * path or buffer, size outside 1..16384), CF_ERR_IO naming the path. */
CF_API cf_status cf_write_png(cf_context *ctx, const char *path, int32_t width, int32_t height, const uint8_t *rgb);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_RENDER_H */
