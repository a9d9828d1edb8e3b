/*
 * Sparse linear algebra: compressed-column matrices, one-pass assembly with
 * value refill into a fixed pattern, Cholesky with symbolic analysis reused
 * across numeric refactorisations, saddle-point systems, LU, inverse power
 * iteration and weighted Gram-Schmidt; the fixed-value / linear-equality
 * quadratic solver built on them (cf_min_quad); Anderson acceleration
 * (cf_anderson); matrix-free preconditioned conjugate gradients
 * (cf_pcg_solve); the dense 3 x 3 SVD (curvflow/svd3.h, included here).
 *
 * Only src/linalg/ includes SuiteSparse. Dense vectors are double arrays;
 * several right-hand sides are stored column after column (column-major,
 * leading dimension n).
 */
#ifndef CURVFLOW_LINALG_H
#define CURVFLOW_LINALG_H

#include "curvflow/curvflow.h"
#include "curvflow/svd3.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Compressed-column sparse matrix, owned by the library (create/destroy
 * through the functions below). Row indices in each column are sorted and
 * unique. `symmetric` != 0 marks a symmetric matrix; every entry is still
 * stored (both triangles) unless `upper_only` is set. */
typedef struct cf_sparse {
    int32_t nrows;
    int32_t ncols;
    int32_t *colptr;   /* ncols + 1 */
    int32_t *rowind;   /* colptr[ncols] */
    double *values;    /* colptr[ncols] */
    int32_t symmetric;
    int32_t upper_only;
    cf_context *ctx;   /* allocator owner */
} cf_sparse;

/* Builds A from n triplets (rows[k], cols[k], vals[k]) in one pass;
 * duplicates are summed. If slot_map is not NULL it receives the index into
 * A->values of every triplet (n entries, caller-allocated), so later value
 * sets can be poured into the same pattern by cf_sparse_refill. vals may be
 * NULL (pattern only, values zero). Two stable counting sorts (by row, then
 * by column): O(n + nrows + ncols), rows sorted, duplicates summed in
 * triplet order (a refill reproduces a rebuild bit for bit). `symmetric`
 * only sets the flag: give both triangles (or set upper_only afterwards and
 * give the upper one). Statuses: CF_OK, CF_ERR_INVALID_ARG (index out of
 * range, symmetric but not square, more than INT32_MAX distinct entries),
 * CF_ERR_NONFINITE (NaN/Inf value, message names the triplet), CF_ERR_NOMEM. */
CF_API cf_status cf_sparse_from_triplets(cf_context *ctx, int32_t nrows, int32_t ncols, int64_t n,
                                         const int32_t *rows, const int32_t *cols, const double *vals,
                                         int32_t symmetric, cf_sparse **out, int64_t *slot_map);

/* Zeroes A's values and adds vals[k] into A->values[slot_map[k]]. No
 * allocation; slots outside the matrix are ignored. */
CF_API void cf_sparse_refill(cf_sparse *a, int64_t n, const int64_t *slot_map, const double *vals);

CF_API void cf_sparse_destroy(cf_sparse **a);
CF_API int64_t cf_sparse_nnz(const cf_sparse *a);

/* y = A x (y has nrows entries; x ncols). For upper_only matrices the
 * mirrored lower triangle is included. */
CF_API void cf_sparse_multiply(const cf_sparse *a, const double *x, double *y);

/* y = alpha A x + beta y. */
CF_API void cf_sparse_multiply_add(const cf_sparse *a, double alpha, const double *x, double beta, double *y);

/* y = (A - diag(A 1)) x, i.e. y_i = sum over j != i of a_ij (x_j - x_i):
 * A x for a square matrix whose rows sum to zero (a Laplacian), with the
 * diagonal never read. Adding a constant to x leaves y unchanged, exactly:
 * where x holds coordinates far from the origin (a georeferenced scan,
 * 1e6 away with millimetre detail) x_j - x_i keeps the detail, while A x
 * through the diagonal loses it to cancellation (error eps |A| |x|). Also
 * the off-diagonal part of a matrix M + t K, K with zero row sums, applied
 * this way gives t K x. For upper_only matrices the mirrored lower
 * triangle is included. */
CF_API void cf_sparse_multiply_zero_row_sums(const cf_sparse *a, const double *x, double *y);

/* Copy of A with every scalar entry replaced by a b x b identity block
 * scaled by the entry (A kron I_b); used to lift vertex operators to 3-vectors
 * or quaternions. Entry (i, j) goes to rows b i .. b i + b - 1. */
CF_API cf_status cf_sparse_kron_identity(cf_context *ctx, const cf_sparse *a, int32_t b, cf_sparse **out);

/* A kron ones(b, b): every entry (i, j) of A becomes a dense b x b block
 * (rows b i .. b i + b - 1 of columns b j .. b j + b - 1) filled with a_ij.
 * Builds the pattern of a block operator (the 4 x 4 quaternion blocks of a
 * Dirac matrix) from its vertex graph with nnz(A) b^2 entries and no
 * triplets: value slot of (b i + r, b j + c) = colptr[b j + c] +
 * b (p - A.colptr[j]) + r, p the slot of (i, j) in A. A must store both
 * triangles. CF_ERR_INVALID_ARG beyond int32 indices or for an upper-only A. */
CF_API cf_status cf_sparse_kron_dense(cf_context *ctx, const cf_sparse *a, int32_t b, cf_sparse **out);

/* C = alpha A + beta B (same shape). */
CF_API cf_status cf_sparse_add(cf_context *ctx, double alpha, const cf_sparse *a, double beta,
                               const cf_sparse *b, cf_sparse **out);

CF_API cf_status cf_sparse_transpose(cf_context *ctx, const cf_sparse *a, cf_sparse **out);

/* C = A B. */
CF_API cf_status cf_sparse_product(cf_context *ctx, const cf_sparse *a, const cf_sparse *b, cf_sparse **out);

/* Sets every value in column j of row i ... convenience: returns the index of
 * entry (i, j) in values, or -1 if it is not in the pattern. */
CF_API int64_t cf_sparse_find(const cf_sparse *a, int32_t i, int32_t j);

/* ---- Cholesky (CHOLMOD, supernodal when it pays) ---------------------- */

typedef enum cf_ordering {
    CF_ORDERING_AUTO = 0,   /* AMD; METIS too when AMD's factor is costly (CHOLMOD's rule), fewer flops wins */
    CF_ORDERING_AMD = 1,
    CF_ORDERING_METIS = 2,
    CF_ORDERING_NATURAL = 3,
    /* AUTO's rule for a matrix refactorised at every step of a flow: METIS is
     * tried from fl / lnz >= 200 instead of 500, since its slower analysis
     * (5-6x AMD's), paid once per mesh, then comes back in the
     * factorisations; fewer flops wins (docs/linalg.md, "Ordering") */
    CF_ORDERING_AUTO_REFACTORISED = 4
} cf_ordering;

typedef struct cf_cholesky_options {
    /* The matrix is made of block_size x block_size blocks (1, 3 or 4, or any
     * b >= 1): the fill-reducing ordering is computed on the graph of blocks
     * (the vertex graph) and expanded, which gives the same fill far more
     * cheaply. */
    int32_t block_size;
    cf_ordering ordering;
    /* Nonzero: A's 4 x 4 blocks are matrices of left multiplication by
     * quaternions (Le Folgoc Eq. 7; block_size must be 4, both triangles
     * stored), i.e. A is a Hermitian quaternionic matrix. It is then
     * factorised as the equivalent complex Hermitian matrix of half the
     * size, which is about twice as fast; solves still take and return
     * real vectors. Each factorisation checks the block structure
     * (CF_ERR_INVALID_ARG naming the first bad block). Default 0. */
    int32_t quaternion_blocks;
} cf_cholesky_options;

CF_API void cf_cholesky_options_default(cf_cholesky_options *options);

typedef struct cf_cholesky cf_cholesky;

/* Symbolic analysis of the pattern of A (symmetric, square; the upper
 * triangle is read). options may be NULL. The block-graph orderings (AMD,
 * METIS) of the last block graph analysed in ctx are kept in the context
 * and reused when the next matrix has the same graph of blocks (e.g. the
 * scalar Laplacian and the 4 x 4-block Dirac matrix of one mesh): the same
 * permutation, so the same factor bit for bit, without recomputing METIS
 * (2-4 s at 655k vertices; docs/memory.md). */
CF_API cf_status cf_cholesky_create(cf_context *ctx, const cf_sparse *a, const cf_cholesky_options *options,
                                    cf_cholesky **out);

/* Numeric factorisation of A (same pattern as at create, else
 * CF_ERR_INVALID_ARG). Always LL'. A matrix that is not positive definite
 * gives CF_ERR_NOT_POSDEF with the failing (original) column in the message
 * ("... at column 23 (pivot 17 of 64)"); NaN/Inf values give
 * CF_ERR_NUMERICAL naming the entry. After a failure solves are refused
 * until a factorisation succeeds. */
CF_API cf_status cf_cholesky_factorize(cf_cholesky *chol, const cf_sparse *a);

/* Factorises A + shift I (same pattern; the diagonal must be in it). */
CF_API cf_status cf_cholesky_factorize_shifted(cf_cholesky *chol, const cf_sparse *a, double shift);

/* Solves A X = B for nrhs columns (column-major, leading dimension n). x
 * may equal b. Uses preallocated workspace after the first call. NaN/Inf
 * in b or in the solution: CF_ERR_NUMERICAL naming the column and row. */
CF_API cf_status cf_cholesky_solve(cf_cholesky *chol, int32_t nrhs, const double *b, double *x);

/* Allocates now the library's solve workspace for up to nrhs columns (the
 * complex-form buffer of quaternion_blocks factorisations), so that later
 * solves of at most nrhs columns allocate nothing through the context: for
 * objects that must not allocate in their steps. CHOLMOD's own solve
 * storage is allocated by CHOLMOD at the first solve, outside the context's
 * allocator. Statuses: CF_ERR_INVALID_ARG (NULL, nrhs < 0), CF_ERR_NOMEM. */
CF_API cf_status cf_cholesky_reserve_solve(cf_cholesky *chol, int32_t nrhs);

CF_API int32_t cf_cholesky_size(const cf_cholesky *chol);

/* Timings of the last analyse / factorise / solve, in seconds. */
typedef struct cf_solver_timings {
    double analyze_seconds;
    double factorize_seconds;
    double solve_seconds;
} cf_solver_timings;
CF_API void cf_cholesky_timings(const cf_cholesky *chol, cf_solver_timings *timings);

CF_API void cf_cholesky_destroy(cf_cholesky **chol);

/* ---- Hermitian quaternionic matrices in complex form ------------------ */

/* An nb x nb Hermitian quaternionic matrix (block (I, J) the quaternion
 * q_IJ, q_JI = conj(q_IJ), real diagonal blocks): the operator that
 * cf_cholesky_options.quaternion_blocks takes as a real symmetric 4 nb x
 * 4 nb matrix of left-multiplication blocks, stored instead as the upper
 * triangle of the complex Hermitian 2 nb x 2 nb matrix of the same operator
 * (docs/linalg.md, "Quaternion blocks"), a quarter of the real form's
 * values and no second copy at factorisation. q = a + b i + c j + d k is
 * the complex 2 x 2 block [[a + b i, -c - d i], [c - d i, a - b i]] on the
 * unknowns 2 I, 2 I + 1; a real vector (w, x, y, z) per block maps to
 * (w + x i, y - z i). Layout (CSC, int32 indices, sorted rows): complex
 * column 2 J holds rows 2 I, 2 I + 1 of every stored block I < J (I
 * ascending), then row 2 J; column 2 J + 1 the same rows, then 2 J, 2 J + 1.
 * So block k of block column J (counting from 0, I ascending, the diagonal
 * block last) has its entry (2 I, 2 J) at colptr[2 J] + 2 k, (2 I + 1, 2 J)
 * at colptr[2 J] + 2 k + 1 (I < J only), (2 I, 2 J + 1) at colptr[2 J + 1]
 * + 2 k and (2 I + 1, 2 J + 1) after it. values: (re, im) interleaved. */
typedef struct cf_quat_sparse {
    int32_t nb;        /* quaternion blocks per side */
    int32_t *colptr;   /* 2 nb + 1 */
    int32_t *rowind;   /* colptr[2 nb] */
    double *values;    /* 2 colptr[2 nb] */
    cf_context *ctx;   /* allocator owner */
} cf_quat_sparse;

/* Pattern (values zero) from the block graph: `graph` is nb x nb with
 * sorted rows; its entries (I, J) with I <= J are the stored blocks, in
 * order, so the k-th entry of graph column J with row <= J is block k of
 * block column J (above). Entries below the diagonal are ignored (a graph
 * with both triangles may be given). Statuses: CF_ERR_INVALID_ARG (not
 * square, a missing diagonal entry or unsorted rows, named by column; more
 * than INT32_MAX complex entries), CF_ERR_NOMEM. */
CF_API cf_status cf_quat_sparse_create(cf_context *ctx, const cf_sparse *graph, cf_quat_sparse **out);
CF_API void cf_quat_sparse_destroy(cf_quat_sparse **a);
/* Complex entries stored (colptr[2 nb]). */
CF_API int64_t cf_quat_sparse_nnz(const cf_quat_sparse *a);
/* y = A x on real vectors (4 nb entries, (w, x, y, z) per block), summed
 * in the order of cf_sparse_multiply on the real form with both triangles
 * (each row over block columns ascending); the lower blocks are the
 * conjugates of the stored upper ones. x and y must not overlap. */
CF_API void cf_quat_sparse_multiply(const cf_quat_sparse *a, const double *x, double *y);

/* cf_cholesky_create / cf_cholesky_factorize for a matrix in complex form:
 * the same ordering (the block graph's, shared through the context's
 * cache), analysis and factor as cf_cholesky_create with quaternion_blocks
 * on the real form of the same operator, without that real form or a copy
 * of the values: the factorisation reads a->values. Solves
 * (cf_cholesky_solve, cf_inverse_iteration_blocks) take and return real
 * vectors of 4 nb entries (converted to the complex form inside x, so no
 * buffer is kept and cf_cholesky_reserve_solve has nothing to reserve);
 * cf_cholesky_size is 4 nb. options: only
 * `ordering` is read (may be NULL). Factorising needs a's pattern of the
 * analysis (CF_ERR_INVALID_ARG otherwise); NaN/Inf: CF_ERR_NUMERICAL
 * naming the block; not positive definite: CF_ERR_NOT_POSDEF naming the
 * real column as cf_cholesky_factorize does. A factorisation created by
 * one of the two create functions refuses the other's factorize. */
CF_API cf_status cf_cholesky_create_quat(cf_context *ctx, const cf_quat_sparse *a,
                                         const cf_cholesky_options *options, cf_cholesky **out);
CF_API cf_status cf_cholesky_factorize_quat(cf_cholesky *chol, const cf_quat_sparse *a);

/* CHOLMOD's OpenMP threads: a context option, cf_context_set_threads
 * (curvflow.h; default serial). */

/* ---- Saddle-point systems --------------------------------------------- */

/* [ A  B^T ] [x]   [f]
 * [ B  -C  ] [y] = [g]
 * A: n x n symmetric positive semi-definite; B: m x n; C: m diagonal
 * entries >= 0 (c_diag NULL means C = 0).
 * With C > 0 the system is reduced to the Schur complement
 * S = A + B^T C^-1 B (symmetric positive definite, supernodal Cholesky, pattern
 * analysed once and refilled), y = C^-1 (B x - g), and the result is
 * refined iteratively against the full system. With C = 0 (hard equality
 * constraints), any zero entry of C, or when S is not positive definite it
 * falls back to LU (UMFPACK) on the full matrix (symbolic analysis on first
 * use, numeric per factorisation). If the rows of B are so dense that S
 * would have more than 64e6 pair contributions, LU is used throughout.
 * A may store both triangles or be upper_only; B stores every entry. The
 * object keeps copies of the values, so the caller's matrices may change
 * between factorize and solve. Statuses as for cf_cholesky_*, plus
 * CF_ERR_INVALID_ARG for C[r] < 0 or non-finite (message names r). */
typedef struct cf_saddle cf_saddle;

typedef struct cf_saddle_options {
    int32_t block_size;        /* as in cf_cholesky_options */
    int32_t refinement_steps;  /* iterative refinement steps (default 2) */
    int32_t force_lu;          /* nonzero: always UMFPACK on the full matrix */
} cf_saddle_options;

CF_API void cf_saddle_options_default(cf_saddle_options *options);
CF_API cf_status cf_saddle_create(cf_context *ctx, const cf_sparse *a, const cf_sparse *b,
                                  const cf_saddle_options *options, cf_saddle **out);
/* Numeric factorisation for new values of A, B (same patterns) and C. */
CF_API cf_status cf_saddle_factorize(cf_saddle *s, const cf_sparse *a, const cf_sparse *b, const double *c_diag);
/* x: n entries, y: m entries. */
CF_API cf_status cf_saddle_solve(cf_saddle *s, const double *f, const double *g, double *x, double *y);
/* 1 if the last factorisation used the Schur complement, 0 if LU. */
CF_API int32_t cf_saddle_used_schur(const cf_saddle *s);
/* Relative residual |K z - rhs|_2 / |rhs|_2 of the full system after the
 * last solve (after refinement). A warning is logged when it exceeds 1e-10. */
CF_API double cf_saddle_residual(const cf_saddle *s);
CF_API void cf_saddle_destroy(cf_saddle **s);

/* ---- LU (UMFPACK) for general square matrices ------------------------- */

typedef struct cf_lu cf_lu;
CF_API cf_status cf_lu_create(cf_context *ctx, const cf_sparse *a, cf_lu **out);   /* symbolic + numeric */
CF_API cf_status cf_lu_factorize(cf_lu *lu, const cf_sparse *a);                   /* numeric, same pattern */
/* x may equal b. A singular matrix makes create/factorize fail with
 * CF_ERR_NUMERICAL ("UMFPACK status 1 (singular matrix)"). The LU keeps its
 * own copy of the values (for UMFPACK's iterative refinement). */
CF_API cf_status cf_lu_solve(cf_lu *lu, const double *b, double *x);
CF_API void cf_lu_destroy(cf_lu **lu);

/* ---- Eigenvectors and projections ------------------------------------- */

/* Smallest eigenpairs of A v = lambda M v for symmetric positive semi-definite
 * A and diagonal positive M (m_diag; NULL means identity), by inverse power
 * iteration with M-orthogonalisation (subspace iteration on a block of
 * k + max(2, k) columns, with a Rayleigh-Ritz step each iteration) on a
 * factorisation of A + shift M. `chol` may be a factorisation of that
 * matrix the caller keeps (then a and shift are only used for the Rayleigh
 * quotients); if NULL one is made and freed. vectors: n x k, column-major;
 * on entry a starting guess (or all zeros for a deterministic default), on
 * exit M-orthonormal, eigenvalues ascending (Rayleigh quotients). Stops
 * when every eigen-residual |A v - lambda M v|_{M^-1} is below tolerance
 * times a Gershgorin bound of the spectrum of M^-1 A (a scale that stays
 * meaningful for eigenvalue 0), or after max_iterations
 * (CF_ERR_NOT_CONVERGED, outputs hold the last iterate). */
typedef struct cf_eigen_options {
    int32_t max_iterations;  /* default 50 */
    double tolerance;        /* default 1e-10 */
    double shift;            /* default 0; a small positive value for singular A */
} cf_eigen_options;
CF_API void cf_eigen_options_default(cf_eigen_options *options);
CF_API cf_status cf_smallest_eigenvectors(cf_context *ctx, const cf_sparse *a, const double *m_diag,
                                          cf_cholesky *chol, int32_t k, const cf_eigen_options *options,
                                          double *vectors, double *eigenvalues, int32_t *iterations);

/* One step of inverse (subspace) iteration with a factorisation the caller
 * keeps (of A + s M): vectors <- M-orthonormalised chol^-1 (M vectors).
 * vectors: n x k column-major, in/out; work: caller-allocated n x k doubles
 * (no allocation here, so it suits step loops); rank (may be NULL)
 * receives the number of independent columns kept. m_diag NULL: identity. */
CF_API cf_status cf_inverse_iteration_step(cf_cholesky *chol, const double *m_diag, int32_t k, double *vectors,
                                           double *work, int32_t *rank);

/* Rayleigh quotient v^T A v / v^T M v; work: n doubles. */
CF_API double cf_rayleigh_quotient(const cf_sparse *a, const double *m_diag, const double *v, double *work);

/* Block-aware variants for fields of block_size components per element
 * with one mass per element (a quaternion field: block_size 4, m_diag the
 * nv vertex masses, v 4 nv entries stored element by element), so the mass
 * array need not be repeated per component. |v_i|^2 is the squared norm of
 * block i, and the M-norm sum_i m_i |v_i|^2.
 * cf_inverse_iteration_blocks: `iterations` times v <- chol^-1 (M v)
 * (chol: a factorisation of A + s M the caller keeps), each followed by the
 * scaling to sum_i m_i |v_i|^2 = norm2 (e.g. the total mass, for mean
 * |v|^2 = 1); v: n = cf_cholesky_size(chol) entries, in/out (the start on
 * entry); work: n doubles; no allocation. Statuses: CF_ERR_INVALID_ARG
 * (NULL array, block_size < 1 or not dividing n, iterations < 0, norm2 not
 * positive and finite), CF_ERR_NUMERICAL (the iterate's M-norm is zero or
 * not finite), solve errors.
 * cf_rayleigh_quotient_blocks: v^T A v / sum_i m_i |v_i|^2 (A square, n a
 * multiple of block_size); work: n doubles; NaN for bad arguments or a
 * zero denominator. */
CF_API cf_status cf_inverse_iteration_blocks(cf_cholesky *chol, const double *m_diag, int32_t block_size,
                                             int32_t iterations, double norm2, double *v, double *work);
/* The scaling each inverse iteration above ends with: v (nb blocks of
 * block_size entries, one mass m_diag[i] each) scaled to
 * sum_i m_i |v_i|^2 = norm2. Returns that sum before the scaling; when it is
 * not positive and finite v is left as it was. */
CF_API double cf_normalize_blocks(int32_t nb, const double *m_diag, int32_t block_size, double norm2, double *v);
CF_API double cf_rayleigh_quotient_blocks(const cf_sparse *a, const double *m_diag, int32_t block_size,
                                          const double *v, double *work);

/* Orthonormalises the k columns of basis (n x k, column-major) in place
 * under <u, v> = sum_i w_i u_i v_i (w NULL: identity), by modified
 * Gram-Schmidt with one reorthogonalisation. Columns whose remaining norm is
 * below tol times their original norm are dropped; *rank receives how many
 * columns remain (packed first). */
CF_API void cf_orthonormalize(int32_t n, int32_t k, double *basis, const double *w, double tol, int32_t *rank);

/* v <- v - sum_j <v, b_j>_w b_j for an orthonormal basis (n x k). */
CF_API void cf_project_out(int32_t n, int32_t k, const double *basis, const double *w, double *v);

/* Weighted dot product sum_i w_i a_i b_i (w NULL: plain). */
CF_API double cf_dot(int32_t n, const double *a, const double *b, const double *w);

/* ---- Small dense least squares (LAPACK) ------------------------------- */

/* Doubles of workspace cf_dense_least_squares needs for an m x n system. */
CF_API int64_t cf_dense_least_squares_work_size(int32_t m, int32_t n);

/* Minimum-norm least-squares solution of the small dense system a x = b
 * (a: m x n, column-major, overwritten; b: max(m, n) entries, the m
 * right-hand side values in, the n solution values out), by LAPACK's
 * SVD-based dgelss: singular values below rcond times the largest count as
 * zero. work: cf_dense_least_squares_work_size(m, n) doubles. *rank (may be
 * NULL) receives the effective rank. Statuses: CF_ERR_INVALID_ARG (bad
 * sizes, NULL, too little work), CF_ERR_NONFINITE (a or b not finite),
 * CF_ERR_NUMERICAL (the SVD did not converge). */
CF_API cf_status cf_dense_least_squares(int32_t m, int32_t n, double *a, double *b, double rcond, double *work,
                                        int64_t work_size, int32_t *rank);

/* Doubles of workspace cf_dense_generalized_eigenvalues needs (n x n). */
CF_API int64_t cf_dense_generalized_eigenvalues_work_size(int32_t n);

/* Eigenvalues (ascending) of the small dense symmetric-definite pencil
 * a x = lambda b x (n x n, column-major, lower triangles read, both
 * overwritten; b positive definite), by LAPACK's dsygv. work:
 * cf_dense_generalized_eigenvalues_work_size(n) doubles. Statuses:
 * CF_ERR_INVALID_ARG (bad size, NULL, too little work), CF_ERR_NONFINITE,
 * CF_ERR_NOT_POSDEF (b not positive definite), CF_ERR_NUMERICAL (no
 * convergence). */
CF_API cf_status cf_dense_generalized_eigenvalues(int32_t n, double *a, double *b, double *eigenvalues, double *work,
                                                  int64_t work_size);

/* ---- Quadratics with fixed values and linear equalities --------------- */

/* Precompute / solve for
 *
 *     minimise   1/2 x^T A x + b^T x
 *     subject to x[known[k]] = y[k]  (k < known_count)  and  Aeq x = beq,
 *
 * the shape of libigl's min_quad_with_fixed. Sign convention: the linear
 * term enters with +b, so without constraints x = -A^-1 b (a system
 * A x = r is b = -r). A: n x n symmetric, both triangles stored (its values
 * are checked symmetric to 1e-10 of its largest entry; the form only sees
 * (A + A^T) / 2 and a one-sided A would be silently wrong); Aeq: m x n, any
 * pattern. With u the free variables the known columns move to the right:
 *   no equalities: A_uu x_u = -b_u - A_uk y, by supernodal Cholesky
 *     (A_uu must be positive definite: a known value in every connected
 *     component of a Laplacian, for instance);
 *   equalities:    [A_uu Aeq_u^T; Aeq_u 0] [x_u; lambda] =
 *                  [-b_u - A_uk y; beq - Aeq_k y] by the saddle layer (C = 0:
 *     LU on the full matrix), so A_uu may be only semi-definite as long as
 *     the constraints remove its kernel; lambda are the multipliers of
 *     1/2 x^T A x + b^T x + lambda^T (Aeq x - beq) (not returned).
 * create analyses and factorises; cf_min_quad_factorize refactorises for new
 * values of the same patterns and known set (no new analysis); solve takes
 * new b, y, beq for any number of columns without refactorising.
 * Conventions: several right-hand sides are columns (column-major): b is
 * n x nrhs, y known_count x nrhs in the order of `known`, beq m x nrhs,
 * x n x nrhs; on exit x[known[k]] = y[k] exactly. */
typedef struct cf_min_quad cf_min_quad;

typedef struct cf_min_quad_options {
    int32_t block_size;   /* as cf_cholesky_options (default 1); must divide the number of free variables */
    cf_ordering ordering; /* fill-reducing ordering of A_uu (default CF_ORDERING_AUTO) */
    int32_t max_rhs;      /* columns solved at once (default 1, at most 4096): solves of up to this many
                             columns allocate nothing (the Cholesky path); wider ones go in chunks */
    /* Nonzero: A is a Hermitian quaternionic matrix (4 x 4 left-multiplication
     * blocks, as cf_cholesky_options.quaternion_blocks; block_size must be 4,
     * no equalities). The known variables must then be whole blocks (all four
     * components of a quaternion, e.g. every boundary vertex of a Dirac
     * matrix), so that A_uu is again made of whole quaternion blocks and is
     * factorised in the complex form of half the size. Default 0. */
    int32_t quaternion_blocks;
} cf_min_quad_options;

CF_API void cf_min_quad_options_default(cf_min_quad_options *options);

/* Precompute. known: known_count distinct indices in [0, n) in any order
 * (NULL if known_count = 0); aeq may be NULL (no equalities); options may
 * be NULL. The caller's matrices are not kept (values are copied).
 * Statuses: CF_ERR_INVALID_ARG (shapes, upper_only input, A not
 * structurally symmetric or not symmetric in value, a known index out of
 * range or repeated, equalities with every variable known, block size not
 * dividing the free count; with quaternion_blocks: block size not 4,
 * equalities, a block partly known (named), a block that is not a
 * quaternion's matrix), CF_ERR_NONFINITE (a value of A or Aeq, named),
 * CF_ERR_NOT_POSDEF (A_uu, no equalities; the message names the column of
 * the free block), CF_ERR_NUMERICAL (singular saddle system, e.g. dependent
 * rows of Aeq), CF_ERR_NOMEM. */
CF_API cf_status cf_min_quad_create(cf_context *ctx, const cf_sparse *a, int32_t known_count, const int32_t *known,
                                    const cf_sparse *aeq, const cf_min_quad_options *options, cf_min_quad **out);

/* Numeric refactorisation for new values of A and Aeq with the patterns
 * given at create (else CF_ERR_INVALID_ARG); the analysis is reused.
 * Other statuses as create. After a failure, solves are refused until a
 * factorisation succeeds. */
CF_API cf_status cf_min_quad_factorize(cf_min_quad *q, const cf_sparse *a, const cf_sparse *aeq);

/* Solves for nrhs columns. b, y, beq may be NULL (zero); the entries of b
 * at known variables are not used. x may equal b (it must not overlap y or
 * beq). Statuses: CF_ERR_INVALID_ARG (no successful factorisation, NULL x),
 * CF_ERR_NUMERICAL (a non-finite entry of b at a free variable, of y or of
 * beq, named; an overflowing right-hand side; a non-finite solution). */
CF_API cf_status cf_min_quad_solve(cf_min_quad *q, int32_t nrhs, const double *b, const double *y, const double *beq,
                                   double *x);

/* Number of free variables (n - known_count). */
CF_API int32_t cf_min_quad_free_count(const cf_min_quad *q);

CF_API void cf_min_quad_destroy(cf_min_quad **q);

/* ---- Anderson acceleration --------------------------------------------- */

/* Accelerator of a fixed-point iteration x <- G(x) ("type II" Anderson
 * mixing, Walker & Ni 2011). Sign convention: the residual is
 * f = G(x) - x (zero at a fixed point). With dF, dG the differences of f
 * and of G(x) between the last `depth` + 1 calls,
 *     gamma = argmin_gamma |f - dF gamma|_2,   x_next = G(x) - dG gamma,
 * gamma from the normal equations with a Tikhonov shift of 1e-10 times the
 * largest diagonal entry. The object owns all its memory (2 depth n + 2 n
 * doubles, allocated at create): a step allocates nothing and costs
 * O(depth n). It is not a safeguard: a caller that needs monotone progress
 * (an energy, a residual norm) tests x_next and, if it is worse, takes G(x)
 * and calls cf_anderson_reset. */
typedef struct cf_anderson cf_anderson;

#define CF_ANDERSON_MAX_DEPTH 64

/* n: vector length (>= 1); depth: history columns in [1, CF_ANDERSON_MAX_DEPTH]
 * (5 is a good default; see docs/linalg.md). Statuses: CF_OK,
 * CF_ERR_INVALID_ARG, CF_ERR_NOMEM. */
CF_API cf_status cf_anderson_create(cf_context *ctx, int64_t n, int32_t depth, cf_anderson **out);

/* Pushes the pair (x, g = G(x)) (n entries each) into the history and, when
 * there is at least one difference pair, writes the mixed candidate into out
 * (n entries; may not alias x or g) and sets *mixed = 1. *mixed = 0 (out
 * untouched) on the first call after create/reset, when f did not change,
 * or when the history is numerically singular: take g then. Statuses:
 * CF_OK; CF_ERR_INVALID_ARG (NULL argument); CF_ERR_NUMERICAL when
 * G(x) - x is not finite (message names the entry; the history is reset). */
CF_API cf_status cf_anderson_step(cf_anderson *aa, const double *x, const double *g, double *out, int32_t *mixed);

/* Forgets the history (after a rejected candidate, a restart or a jump of
 * x the iteration did not make). No allocation. NULL is ignored. */
CF_API void cf_anderson_reset(cf_anderson *aa);

/* Number of difference columns in the history (0 .. depth). */
CF_API int32_t cf_anderson_history(const cf_anderson *aa);

CF_API void cf_anderson_destroy(cf_anderson **aa);

/* ---- matrix-free preconditioned conjugate gradients ---------------------- */

/* Up to this many right-hand sides per cf_pcg_solve call. */
#define CF_PCG_MAX_COLUMNS 8

/* q = A p for the symmetric positive (semi)definite A of cf_pcg_solve, on
 * its interleaved columns, and pq[c] = p . q of every column c. */
typedef void (*cf_pcg_multiply_fn)(void *user, const double *p, double *q, double *pq);

typedef struct cf_pcg_result {
    int32_t iterations;       /* products with A */
    double relative_residual; /* largest |r_c| / |r_c at the start| over the columns */
} cf_pcg_result;

/* Conjugate gradients on A x = b with the preconditioner
 * diag(inverse_diagonal), for `columns` right-hand sides at once (1 ..
 * CF_PCG_MAX_COLUMNS). Unlike the rest of this header, the columns are
 * interleaved: entry (i, c) of x, r, p and q is at index i * columns + c,
 * the layout of vertex positions. On entry x is the starting guess and r
 * the residual b - A x (the caller forms it: it knows its rows); on return x
 * is the solution and r its residual. p and q are workspace of n * columns
 * each; nothing is allocated. A row whose inverse_diagonal is 0 never moves
 * when its r is 0 and multiply keeps its q at 0 (held rows). Each column has
 * its own step lengths and stops once |r_c| <= tolerance |r_c at the start|
 * (a zero right-hand side at once). Statuses: CF_OK; CF_ERR_NOT_CONVERGED
 * after max_iterations (x and r hold the last iterate, *result says how far
 * it got; the message gives both); CF_ERR_INVALID_ARG. */
CF_API cf_status cf_pcg_solve(cf_context *ctx, int32_t n, int32_t columns, cf_pcg_multiply_fn multiply, void *user,
                              const double *inverse_diagonal, double *x, double *r, double *p, double *q,
                              double tolerance, int32_t max_iterations, cf_pcg_result *result);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_LINALG_H */
