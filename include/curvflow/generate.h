/*
 * Built-in meshes: deterministic generators for tests, the demo and the
 * benchmarks. Every generator returns a new, validated cf_mesh whose rest
 * positions are the generated ones, with counter-clockwise (outward)
 * triangles; the caller frees it with cf_mesh_destroy. Random generators
 * take a seed and give bit-identical output for the same seed.
 *
 * Statuses: CF_OK, CF_ERR_INVALID_ARG (NULL out, counts too small or too
 * large, non-positive or non-finite sizes), CF_ERR_NOMEM.
 */
#ifndef CURVFLOW_GENERATE_H
#define CURVFLOW_GENERATE_H

#include "curvflow/curvflow.h"
#include "curvflow/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Icosahedron refined `subdivisions` times (0..9) by 1-to-4 splits, every
 * new vertex projected exactly onto the sphere of `radius` centred at the
 * origin. V = 10 4^s + 2, F = 20 4^s, genus 0. */
CF_API cf_status cf_generate_icosphere(cf_context *ctx, int32_t subdivisions, double radius, cf_mesh **out);

/* Torus of revolution around the z axis: tube centre at distance
 * major_radius, tube radius minor_radius (0 < minor < major), n_major >= 3
 * vertices around z, n_minor >= 3 around the tube. V = n_major n_minor,
 * F = 2 V, genus 1. Vertex i * n_minor + j sits at angles
 * u = 2 pi i / n_major, v = 2 pi j / n_minor:
 * ((R + r cos v) cos u, (R + r cos v) sin u, r sin v). */
CF_API cf_status cf_generate_torus(cf_context *ctx, double major_radius, double minor_radius, int32_t n_major,
                                   int32_t n_minor, cf_mesh **out);

/* Icosphere of radius 1 with a smooth radial bump field: radius
 * 1 + amplitude * sum_k c_k exp(-(1 - <n, d_k>) / w_k^2) over a few random
 * low-frequency bumps (directions d_k, widths w_k in [0.35, 0.7], signs and
 * weights c_k in [-1, 1] normalised so max |sum| = 1), drawn from `seed`.
 * |amplitude| < 0.5. Carries per-corner texture coordinates (u, v) =
 * (longitude / 2 pi, latitude / pi + 1/2) with a proper seam: corners of
 * faces that straddle the longitude-pi seam get their own uv (u > 1 side is
 * continued), and the poles get one uv per corner at the face's mean u. */
CF_API cf_status cf_generate_bumpy_sphere(cf_context *ctx, int32_t subdivisions, double amplitude, uint32_t seed,
                                          cf_mesh **out);

/* Most limbs of cf_generate_limb_sphere. */
#define CF_LIMB_SPHERE_MAX_LIMBS 8

/* Unit icosphere (`subdivisions` 0..9) with `limbs` (1..8) smooth limbs
 * grown radially: radius 1 + length * sum_k exp(-(1 - <n, d_k>) / width^2)
 * at the unit direction n, with d_k the first `limbs` of the cube's corner
 * directions (1,1,1), (1,-1,-1), (-1,1,-1), (-1,-1,1) (a regular
 * tetrahedron), then their opposites (-1,-1,-1), (-1,1,1), (1,-1,1),
 * (1,1,-1), normalised. `length` in [0, 10] is the limb's extra radius in
 * units of the sphere's radius, `width` in [0.05, 2] its angular width
 * (radians, ~ the Gaussian's standard deviation). Texture coordinates as
 * cf_generate_bumpy_sphere (per corner, seam and poles handled). The demo
 * uses (5, 8, 1.4, 0.22): 10242 vertices, W/4pi 5.78, an eight-armed star
 * that the conformal Willmore flow takes to a round sphere.
 * Statuses: CF_OK, CF_ERR_INVALID_ARG (counts or sizes out of range),
 * CF_ERR_NOMEM. */
CF_API cf_status cf_generate_limb_sphere(cf_context *ctx, int32_t subdivisions, int32_t limbs, double length,
                                         double width, cf_mesh **out);

/* Flat rectangle [0, width] x [0, height] at z = 0 made of nx x ny cells
 * (nx, ny >= 1), each split into two triangles along the diagonal from
 * (x0, y0) to (x1, y1). V = (nx+1)(ny+1), F = 2 nx ny, one boundary loop,
 * normals +z. Per-vertex uv = (x / width, y / height). Vertex index
 * j * (nx + 1) + i is at (i width / nx, j height / ny). */
CF_API cf_status cf_generate_grid(cf_context *ctx, int32_t nx, int32_t ny, double width, double height,
                                  cf_mesh **out);

/* Open tube around the z axis, z in [0, height], n_around >= 3 vertices per
 * ring, n_along >= 1 bands (n_along + 1 rings), normals pointing away from
 * the axis. V = n_around (n_along + 1), two boundary loops, genus 0.
 * Vertex j * n_around + i is at angle 2 pi i / n_around, z = height j / n_along.
 * Texture coordinates (u, v) = (i / n_around, j / n_along) are per corner
 * with a seam column: the faces closing the tube use u = 1 instead of 0
 * ((n_around + 1)(n_along + 1) uv entries), so the texture has no jump. */
CF_API cf_status cf_generate_cylinder(cf_context *ctx, int32_t n_around, int32_t n_along, double radius,
                                      double height, cf_mesh **out);

/* Closed box [0, lx] x [0, ly] x [0, lz] triangulated on a regular grid of
 * nx x ny x nz cells (each >= 1) on every side, outward normals.
 * pattern 0: every quad split along the same diagonal (seen from outside);
 * pattern 1: the diagonal alternates in a checkerboard (criss-cross style),
 * so the same bar can be re-triangulated. V = 2(nx ny + ny nz + nz nx) + 2,
 * F = 4(nx ny + ny nz + nz nx), genus 0. (Zhao & Gortler, §5 bar tests.) */
CF_API cf_status cf_generate_bar(cf_context *ctx, int32_t nx, int32_t ny, int32_t nz, double lx, double ly,
                                 double lz, int32_t pattern, cf_mesh **out);

/* Flat square [0, size]^2 at z = 0 with n x n cells split into 2 triangles
 * each (pattern as for cf_generate_bar; pattern 0 splits every cell along
 * the diagonal (x0, y0)-(x1, y1), the "triangulated unit square" of Zhao &
 * Gortler App. B at size 1). Per-vertex uv = (x, y) / size. */
CF_API cf_status cf_generate_sheet(cf_context *ctx, int32_t n, double size, int32_t pattern, cf_mesh **out);

/* Height field z = amplitude * size * h(x, y) over the sheet [0, size]^2
 * (n x n cells, pattern 0), h a sum of a few random smooth Gaussian bumps
 * drawn from `seed` with max |h| = 1. Per-vertex uv = (x, y) / size. */
CF_API cf_status cf_generate_bumpy_plane(cf_context *ctx, int32_t n, double size, double amplitude, uint32_t seed,
                                         cf_mesh **out);

/* Closed genus-2 surface (test fixture): the boundary of a thickened
 * figure-eight, i.e. a box with two square holes, triangulated on a grid
 * refined `resolution` (>= 1) times per unit cell. Bounding box
 * [0, 5] x [0, 3] x [0, 1] scaled by 1/5. Validates, chi = -2, genus 2. */
CF_API cf_status cf_generate_double_torus(cf_context *ctx, int32_t resolution, cf_mesh **out);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_GENERATE_H */
