/*
 * Isometric curve flow of closed planar polylines (Crane, Pinkall, Schroeder
 * 2013, Sec. 5 and App. A): gradient descent of E = sum_i kappa_i^2 l_i* in
 * curvature space with the constraints <kappadot, 1> = <kappadot, f^x> =
 * <kappadot, f^y> = 0, tangents from cumulative angles and positions from the
 * 1D Poisson problem of Sec. 5.2. Edge lengths of the input are preserved up
 * to the (second order in tau) closure error.
 *
 * Discretisation: vertex i has dual length l_i* = (l_{i-1,i} + l_{i,i+1}) / 2
 * and curvature kappa_i = phi_i / l_i*, phi_i the signed turning angle
 * between edges (i-1, i) and (i, i+1). Lengths l are those of the input.
 * Time step: kappa <- kappa + tau kappadot with kappadot = -2 kappa
 * (projected); stable for tau < 1, tau = 1/2 removes the projected
 * curvature in one step.
 */
#ifndef CURVFLOW_CURVE_FLOW_H
#define CURVFLOW_CURVE_FLOW_H

#include "curvflow/curvflow.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cf_curve_flow_options {
    double time_step;   /* tau, default 0.5 */
} cf_curve_flow_options;

CF_API void cf_curve_flow_options_default(cf_curve_flow_options *options);

typedef struct cf_curve_flow_info {
    int64_t iteration;
    double energy;             /* sum kappa_i^2 l_i* after the step */
    double closure_gap;        /* |sum_i T~_i| / total length before the Poisson projection */
    double max_length_error;   /* max_i | |f_i+1 - f_i| - l_i | / l_i after the step */
    double constraint_residual;/* max |<kappadot, c^>| / |kappadot before projection|, c^ orthonormal */
    int32_t turning_number;    /* round(sum phi_i / 2 pi) after the step */
} cf_curve_flow_info;

typedef struct cf_curve_flow cf_curve_flow;

/* points: 2 n doubles (x, y), a closed polyline (the last point connects to
 * the first; do not repeat it), n >= 3, consecutive points distinct.
 * options may be NULL (defaults). Statuses: CF_OK, CF_ERR_INVALID_ARG,
 * CF_ERR_NONFINITE, CF_ERR_DEGENERATE_FACE (zero-length edge, named),
 * CF_ERR_NOMEM. */
CF_API cf_status cf_curve_flow_create(cf_context *ctx, int32_t n, const double *points,
                                      const cf_curve_flow_options *options, cf_curve_flow **out);
/* One step; info may be NULL. Allocates nothing. */
CF_API cf_status cf_curve_flow_step(cf_curve_flow *flow, cf_curve_flow_info *info);
/* Current points (2 n), valid until the next step. */
CF_API const double *cf_curve_flow_points(const cf_curve_flow *flow);
CF_API int32_t cf_curve_flow_size(const cf_curve_flow *flow);
/* Energy and turning number of the current state. */
CF_API double cf_curve_flow_energy(const cf_curve_flow *flow);
CF_API void cf_curve_flow_destroy(cf_curve_flow **flow);

/* ---- polyline files ----------------------------------------------------
 * CSV (.csv, .txt): one point per line, "x,y" or "x y"; blank lines and lines
 * starting with '#' are ignored, as is a first line that is not numeric
 * (header). SVG (.svg): the first drawn <polygon> or <polyline> "points",
 * <path> "d" (M L H V C S Q T A Z, absolute and relative, implicit repeats;
 * the first subpath is read), <rect>, <circle> or <ellipse>, mapped by its
 * transforms. Curves (Bezier segments, arcs, circles, ellipses, rounded
 * corners) are flattened: points on the curve whose chords are within 1e-3
 * of each segment's size (control polygon length, larger radius) of it. A
 * last point equal to the first is dropped (the curve is closed anyway). */
typedef struct cf_curve {
    int32_t count;
    double *points;     /* 2 count */
    cf_context *ctx;
} cf_curve;

/* Statuses: CF_OK, CF_ERR_INVALID_ARG, CF_ERR_IO, CF_ERR_PARSE (message
 * names line or offset), CF_ERR_NONFINITE, CF_ERR_NOMEM. */
CF_API cf_status cf_curve_read(cf_context *ctx, const char *path, cf_curve **out);
/* The same from memory: `size` bytes of CSV text (svg = 0) or SVG (svg = 1);
 * `name` (may be NULL) stands for the file in messages. */
CF_API cf_status cf_curve_read_memory(cf_context *ctx, const void *bytes, size_t size, int svg, const char *name,
                                      cf_curve **out);
/* Writes CSV or SVG (a <polygon>) by extension, atomically. */
CF_API cf_status cf_curve_write(cf_context *ctx, const char *path, int32_t n, const double *points);
CF_API void cf_curve_destroy(cf_curve **curve);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_CURVE_FLOW_H */
