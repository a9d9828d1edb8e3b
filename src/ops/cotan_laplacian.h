/*
 * Internal assembly path of the cotan Laplacian for flows that update the
 * geometry every step: the pattern (and the map from each per-face triplet
 * to its slot in L->values) is built once, then values are refilled in place
 * without allocating. Same sign as cf_cotan_laplacian (positive
 * semi-definite).
 */
#ifndef CF_OPS_COTAN_LAPLACIAN_H
#define CF_OPS_COTAN_LAPLACIAN_H

#include "curvflow/linalg.h"
#include "mesh/mesh_internal.h"

/* Number of slot_map entries: nv + 2 ne (layout: the diagonal entry of
 * vertex v at v, then (i, j) and (j, i) of edge e at nv + 2e, nv + 2e + 1). */
int64_t cfi_cotan_laplacian_triplet_count(const cf_mesh *mesh);

/* CF_OK for a weight floor in [0, 1]; else CF_ERR_INVALID_ARG naming `fn`. */
cf_status cfi_check_weight_floor(cf_context *ctx, double weight_floor, const char *fn);

/* Builds L for `positions` (nv x nv, symmetric) and fills the caller's
 * slot_map (cfi_cotan_laplacian_triplet_count entries; NULL: none).
 * weight_floor: as cfi_face_cotangents (0: the exact weights). */
cf_status cfi_cotan_laplacian_pattern(cf_context *ctx, const cf_mesh *mesh, const double *positions,
                                      double weight_floor, cf_sparse **out, int64_t *slot_map);

/* Overwrites L's values with the cotan Laplacian of `positions`, using the
 * slot_map from cfi_cotan_laplacian_pattern. No allocation; positions are
 * not checked for finiteness (the caller's step does). Fails with
 * CF_ERR_DEGENERATE_FACE (message names the face) on a zero-area face, L
 * then holds partial values. */
cf_status cfi_cotan_laplacian_refill(cf_sparse *l, const cf_mesh *mesh, const double *positions,
                                     double weight_floor, const int64_t *slot_map);

/* The same with face f's weights multiplied by face_scale[f] (nf entries,
 * positive and finite, unchecked; NULL: 1): sum_f face_scale[f] L_f, still
 * positive semi-definite, since each face's term is. */
cf_status cfi_cotan_laplacian_refill_scaled(cf_sparse *l, const cf_mesh *mesh, const double *positions,
                                            double weight_floor, const double *face_scale, const int64_t *slot_map);

/* Applies L to a vertex function without forming the matrix: y = L x for
 * `dim` interleaved components (x, y: dim nv, entry v * dim + c). */
cf_status cfi_cotan_laplacian_apply(cf_context *ctx, const cf_mesh *mesh, const double *positions, int32_t dim,
                                    const double *x, double *y);

#endif /* CF_OPS_COTAN_LAPLACIAN_H */
