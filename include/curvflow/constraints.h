/*
 * Constraints on mesh vertices, shared by the methods: which vertices
 * (point sets: index lists, boxes, files), where they must go (targets:
 * cf_handle_set, vertices with target positions) and how a group of
 * targets is made from a motion (rigid transforms), plus the JSON
 * constraint file that the editing tool calls a handle file (format in
 * docs/edit.md). The stretch-bend editing method takes its handles as a
 * cf_handle_set; constrained Willmore and the Regge flows are meant to take
 * fixed points and point pairs from here too.
 *
 * Conventions: vertex indices are int32 in [0, nv); positions are 3 nv
 * doubles, interleaved (x, y, z); every created set is sorted ascending
 * with each vertex once. Rotations follow the right-hand rule: a positive
 * angle turns counter-clockwise seen from the tip of the axis (the map
 * v -> q v conj(q) of cf_quat_from_axis_angle). Coordinates beyond
 * CF_MAX_COORDINATE are refused as targets. The JSON reader is the only
 * code of the library that uses jansson.
 */
#ifndef CURVFLOW_CONSTRAINTS_H
#define CURVFLOW_CONSTRAINTS_H

#include "curvflow/curvflow.h"
#include "curvflow/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Rigid transforms ------------------------------------------------------ */

/* x -> center + scale R (x - center) + translation: a rotation R about
 * `center`, a uniform scale about the same point (1 = rigid) and a
 * translation, applied in that order. */
typedef struct cf_rigid_transform {
    double rotation[9];    /* row-major rotation matrix (orthonormal, det +1) */
    double scale;          /* > 0 */
    double center[3];
    double translation[3];
} cf_rigid_transform;

/* The identity: R = I, scale 1, center and translation 0. NULL is ignored. */
CF_API void cf_rigid_transform_identity(cf_rigid_transform *t);

/* Sets t->rotation to the rotation by `angle` radians about `axis` (any
 * nonzero length; normalised here), Rodrigues' formula, right-hand rule.
 * Statuses: CF_ERR_INVALID_ARG (NULL, zero or non-finite axis, non-finite
 * angle). */
CF_API cf_status cf_rigid_transform_set_rotation(cf_context *ctx, cf_rigid_transform *t, const double axis[3],
                                                 double angle);

/* out[i] = t(in[i]) for n points (3 n doubles each, interleaved); out may
 * equal in. Statuses: CF_ERR_INVALID_ARG (NULL, n < 0, a non-finite entry
 * of t or scale <= 0), CF_ERR_NONFINITE (an image beyond CF_MAX_COORDINATE;
 * the message names the point; out then holds the images before it). */
CF_API cf_status cf_rigid_transform_apply(cf_context *ctx, const cf_rigid_transform *t, int64_t n, const double *in,
                                          double *out);

/* ---- Point sets ------------------------------------------------------------- */

/* A set of vertices, ascending, each once. Created by the library,
 * read-only for the caller. */
typedef struct cf_point_set {
    int32_t count;
    int32_t *vertices;     /* count, ascending */
    cf_context *ctx;
} cf_point_set;

/* From a list of `count` indices (any order) of a mesh with vertex_count
 * vertices. Statuses: CF_ERR_INVALID_ARG (index outside [0, vertex_count),
 * named with its position; an index listed twice; NULL list with
 * count > 0), CF_ERR_NOMEM. An empty list gives an empty set. */
CF_API cf_status cf_point_set_from_indices(cf_context *ctx, int32_t vertex_count, int32_t count,
                                           const int32_t *indices, cf_point_set **out);

/* The vertices of `positions` (3 vertex_count) inside the axis-aligned box
 * [min, max] (inclusive). relative != 0: min and max are fractions of the
 * bounding box of `positions` (0 = its lower corner, 1 = its upper one;
 * a slack of 1e-12 of the extent keeps the extreme vertices inside despite
 * rounding). The set may be empty. Statuses: CF_ERR_INVALID_ARG (NULL,
 * non-finite box), CF_ERR_NOMEM. */
CF_API cf_status cf_point_set_from_box(cf_context *ctx, int32_t vertex_count, const double *positions,
                                       const double min[3], const double max[3], int32_t relative,
                                       cf_point_set **out);

/* The union of the selections of a constraint file (the JSON format below;
 * each set needs "vertices", "box" or "relative_box"; "fixed", "targets"
 * and "transform" are optional here and checked when present). Sets must
 * not overlap. Statuses as cf_handle_set_read_json, without the "every
 * vertex constrained" error. */
CF_API cf_status cf_point_set_read_json(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                        const char *path, cf_point_set **out);
CF_API cf_status cf_point_set_parse_json(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                         const char *text, const char *source_name, cf_point_set **out);

CF_API void cf_point_set_destroy(cf_point_set **set);

/* ---- Targets (handles) ------------------------------------------------------ */

/* Constrained vertices with their target positions. A fixed vertex has its
 * current position as target. Created by the library, read-only for the
 * caller. Vertices are unique and sorted ascending. */
typedef struct cf_handle_set {
    int32_t count;        /* constrained vertices */
    int32_t *vertices;    /* count, ascending */
    double *targets;      /* 3 count */
    int32_t moved_count;  /* how many targets differ from the positions the set was built on (informational) */
    cf_context *ctx;
} cf_handle_set;

/* Copies `count` vertices and their targets (3 count) into a new set,
 * sorting them. Statuses: CF_ERR_INVALID_ARG (negative index, a vertex
 * given twice, NULL arrays with count > 0), CF_ERR_NONFINITE (a target),
 * CF_ERR_NOMEM. */
CF_API cf_status cf_handle_set_create(cf_context *ctx, int32_t count, const int32_t *vertices, const double *targets,
                                      cf_handle_set **out);

/* Targets for the vertices of `set`: t(positions[v]) for a transform t, or
 * the positions themselves (fixed) when transform is NULL. positions: 3 nv
 * of the mesh the set was made on. Statuses: CF_ERR_INVALID_ARG (NULL set
 * or positions, a bad transform), CF_ERR_NONFINITE (a position or target
 * beyond CF_MAX_COORDINATE, named), CF_ERR_NOMEM. */
CF_API cf_status cf_handle_set_from_points(cf_context *ctx, const cf_point_set *set, const double *positions,
                                           const cf_rigid_transform *transform, cf_handle_set **out);

CF_API void cf_handle_set_destroy(cf_handle_set **handles);

/* Reads a JSON constraint ("handle") file (format in docs/edit.md):
 *   { "sets": [
 *       { "name": "feet", "box": { "min": [x,y,z], "max": [x,y,z] }, "fixed": true },
 *       { "name": "head", "relative_box": { "min": [0,0.9,0], "max": [1,1,1] },
 *         "transform": { "translate": [0,0.1,0],
 *                        "rotate": { "axis": [0,0,1], "angle_degrees": 30, "center": [0,0,0] },
 *                        "scale": 1.0 } },
 *       { "name": "tip", "vertices": [12, 40], "targets": [[0,0,1], [0,1,1]] } ] }
 * Each set selects vertices by "vertices" (index list), "box" (axis-aligned,
 * absolute coordinates, inclusive) or "relative_box" (fractions of the
 * bounding box of `positions`), and gives exactly one of "fixed": true,
 * "targets" (one position per listed vertex) or "transform" (applied as
 * x -> c + scale R(axis, angle) (x - c) + translate, c = rotation centre,
 * default the set's centroid). Selection and transforms use `positions`
 * (3 nv; NULL = the mesh's rest positions), so a handle file can be applied
 * to a deformed state. A vertex in two sets is an error.
 * Warnings (through the context's log callback, at CF_LOG_WARNING; the
 * file is still read): a top-level key other than "sets" (ignored), a set
 * without a "name" (messages call it #index) or with a non-string name.
 * Statuses: CF_ERR_IO (cannot read), CF_ERR_PARSE (malformed JSON with
 * line:column, unknown key inside a set, wrong type, unknown vertex index
 * with its value and the set's name, empty set, overlapping sets, every
 * vertex constrained, a NUL byte), CF_ERR_NOMEM. The message starts with
 * the path. */
CF_API cf_status cf_handle_set_read_json(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                         const char *path, cf_handle_set **out);
/* As above from a string; `source_name` prefixes messages (may be NULL). */
CF_API cf_status cf_handle_set_parse_json(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                          const char *text, const char *source_name, cf_handle_set **out);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_CONSTRAINTS_H */
