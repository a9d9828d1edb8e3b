/*
 * Internal part of the sparse linear-algebra layer: the per-context CHOLMOD
 * state, status checking after every CHOLMOD call, and zero-copy CHOLMOD
 * headers over cf_sparse arrays. Only files in src/linalg/ include this
 * header (it includes cholmod.h).
 */
#ifndef CF_LINALG_LINALG_INTERNAL_H
#define CF_LINALG_LINALG_INTERNAL_H

#include "core/core.h"
#include "curvflow/linalg.h"

#include <cholmod.h>

/* CHOLMOD's Common for ctx, started on first use (print = 0, error handler
 * installed, OpenMP threads limited; see cholmod_state.c) and finished by
 * cf_context_destroy. Statuses: CF_OK, CF_ERR_NOMEM. */
cf_status cfi_cholmod_common(cf_context *ctx, cholmod_common **out);
/* Applies the context's thread setting (cf_context_set_threads) to OpenMP
 * before a parallel CHOLMOD call (no-op before CHOLMOD started in ctx). */
void cfi_cholmod_apply_threads(cf_context *ctx);

/* The context's ordering cache: the fill-reducing orderings (0: AMD,
 * 1: METIS; NULL if not computed) of the last block graph analysed,
 * identified by its block count, entry count and a hash of its pattern,
 * with CHOLMOD's flop and fill counts. It lives in the CHOLMOD state (valid
 * after cfi_cholmod_common) and is freed with the context; its arrays come
 * from the context's allocator outside the byte count, like the state. */
typedef struct cfi_ordering_cache {
    int32_t nb;
    int64_t nnz;
    uint64_t hash;
    int32_t *perm[2];
    double fl[2], lnz[2];
} cfi_ordering_cache;
cfi_ordering_cache *cfi_cholmod_ordering_cache(cf_context *ctx);
/* Room (nb entries) for the ordering of method m of the graph (nb, nnz,
 * hash), recorded with its counts; a different graph replaces the cached
 * one. The caller fills the permutation. NULL if the allocation fails (no
 * caching then, not an error). */
int32_t *cfi_ordering_cache_store(cf_context *ctx, int32_t nb, int64_t nnz, uint64_t hash, int m, double fl,
                                  double lnz);

/* Restores the analysis parameters of Common that the layer changes
 * (ordering methods, postorder, supernodal switch) to our defaults. */
void cfi_cholmod_reset_parameters(cholmod_common *c);

/* Converts Common->status after a CHOLMOD call `what` into a cf_status with
 * a message (CHOLMOD's own message included when its error handler ran).
 * `ok` is the call's own success indicator (nonzero pointer / TRUE).
 * Warnings other than NOT_POSDEF are ignored (CHOLMOD_DSMALL only reports a
 * tiny pivot). */
cf_status cfi_cholmod_check(cf_context *ctx, cholmod_common *c, int ok, const char *what);

/* Clears the record of CHOLMOD's last error message (before a call). */
void cfi_cholmod_clear_message(void);

/* A cholmod_sparse header sharing a's arrays (no copy). stype: 0 unsymmetric,
 * 1 use the upper triangle. */
void cfi_cholmod_view(const cf_sparse *a, int stype, cholmod_sparse *view);

/* Iterative refinement steps UMFPACK takes inside each cf_lu_solve
 * (UMFPACK's default 2); the saddle solver refines on its own and sets 0. */
void cfi_lu_set_refinement_steps(cf_lu *lu, int32_t steps);

/* Makes sure the calling thread has OpenBLAS's work buffer before the
 * first BLAS call (blas_buffers.c): checks that the address space for it is
 * there and makes OpenBLAS map it with a tiny LAPACK call; once per thread,
 * a no-op with another BLAS. Call it before anything that reaches BLAS
 * (supernodal factorisations and solves, UMFPACK). `what` prefixes the
 * message. Statuses: CF_OK, CF_ERR_NOMEM (the buffer does not fit under the
 * address-space limit, or OpenBLAS's worker threads are stuck without
 * theirs: the message names the need and the limit). */
cf_status cfi_blas_reserve(cf_context *ctx, const char *what);
/* OpenBLAS's thread count for the library's own BLAS work (supernodal
 * factorisations and solves, UMFPACK), from the context's thread setting
 * (cf_context_set_threads): with 1 (the default) the call runs on one
 * OpenBLAS thread, and the process's count is handed back after it; with 0
 * or n > 1 OpenBLAS keeps the count the process gave it. Why: on a machine
 * whose cores are busy, each threaded BLAS call of a factorisation waits for
 * a worker that has to be scheduled first (spot_3k's factorisation 16 ms ->
 * 1.9 s with two busy processes on 2 cores; docs/linalg.md, "OpenBLAS's
 * threads"). OpenBLAS's count is process-wide: another application thread's
 * BLAS call made meanwhile runs on one thread too (results do not depend on
 * it beyond rounding). Returns what cfi_blas_threads_leave needs; never
 * fails, a no-op with another BLAS. */
int cfi_blas_threads_enter(const cf_context *ctx);
void cfi_blas_threads_leave(int saved);
/* The OpenBLAS thread count in effect at the calling thread's last
 * cfi_blas_threads_enter (0: none yet, or not OpenBLAS); for the tests. */
int cfi_blas_threads_last_entered(void);
/* "address-space limit (RLIMIT_AS) 288 MB, 270 MB in use" (or "no
 * address-space limit, ... mapped") into buf, for out-of-memory messages. */
void cfi_address_space_note(char *buf, size_t size);

/* The context a factorisation was created with. */
cf_context *cfi_cholesky_context(const cf_cholesky *chol);

/* Index of the first non-finite entry of x[0..n), or -1. */
int64_t cfi_first_nonfinite(const double *x, int64_t n);

/* Allocates an empty nrows x ncols matrix with room for nnz entries
 * (colptr zeroed). Statuses: CF_OK, CF_ERR_INVALID_ARG (nnz > INT32_MAX),
 * CF_ERR_NOMEM. */
cf_status cfi_sparse_alloc(cf_context *ctx, int32_t nrows, int32_t ncols, int64_t nnz, cf_sparse **out);

/* Copies of a, or of a with the mirrored lower triangle when a is
 * upper_only (a full symmetric matrix). */
cf_status cfi_sparse_copy(cf_context *ctx, const cf_sparse *a, cf_sparse **out);

/* Quaternion blocks (quaternion_blocks.c): a real symmetric 4 nb x 4 nb
 * matrix of left-multiplication blocks seen as the complex Hermitian
 * 2 nb x 2 nb matrix of the same operator. create checks that the blocks
 * are stored whole (both triangles) and builds the complex upper-triangle
 * pattern; fill converts the values, failing with CF_ERR_INVALID_ARG naming
 * the block when one deviates from a quaternion's matrix by more than
 * tolerance times the largest entry (or a diagonal block is not real). */
typedef struct cfi_quat_map cfi_quat_map;
cf_status cfi_quat_map_create(cf_context *ctx, const cf_sparse *a, cfi_quat_map **out);
void cfi_quat_map_destroy(cf_context *ctx, cfi_quat_map **map);
void cfi_quat_map_view(const cfi_quat_map *map, int with_values, cholmod_sparse *view);
/* CHOLMOD header (no copy) over the upper triangle of a complex Hermitian
 * 2 nb x 2 nb matrix in compressed columns: the quaternion map's and
 * cf_quat_sparse's (stype 1; pattern only when values is NULL). */
void cfi_complex_upper_view(int32_t nb, int64_t nnz, int32_t *colptr, int32_t *rowind, double *values,
                            cholmod_sparse *view);
cf_status cfi_quat_map_fill(cf_context *ctx, cfi_quat_map *map, const cf_sparse *a, double tolerance);
/* Real n x nrhs (4 entries per quaternion) <-> complex n/2 x nrhs
 * interleaved; real and cplx may be the same array. */
void cfi_quat_to_complex(int32_t n, int32_t nrhs, const double *real, double *cplx);
void cfi_quat_from_complex(int32_t n, int32_t nrhs, const double *cplx, double *real);

#endif /* CF_LINALG_LINALG_INTERNAL_H */
