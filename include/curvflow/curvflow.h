/*
 * curvflow — curvature-driven deformation of triangle meshes.
 *
 * This header holds what every module shares: the status codes, the
 * context object (allocator, log callback, last error message, solver
 * state) and the version. Every fallible public function takes a context as
 * its first parameter and returns a cf_status; on failure the context's
 * message names the problem and its place in one line, e.g.
 * "face 1832: edge (12, 977) is shared by 3 faces".
 *
 * The library never prints, never exits and never aborts on bad input.
 */
#ifndef CURVFLOW_CURVFLOW_H
#define CURVFLOW_CURVFLOW_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(CF_BUILDING_LIBRARY)
#define CF_API __attribute__((visibility("default")))
#else
#define CF_API
#endif

#define CF_VERSION_MAJOR 0
#define CF_VERSION_MINOR 1
#define CF_VERSION_PATCH 0

/* The range of geometry the library computes with (volumes are cubes of
 * coordinates; measured limits in docs/mesh.md). Coordinates beyond
 * CF_MAX_COORDINATE and faces (or curve edges) whose edges are all shorter
 * than CF_MIN_EDGE_LENGTH are refused with a message to rescale. */
#define CF_MAX_COORDINATE 1e50
#define CF_MIN_EDGE_LENGTH 1e-50

/* Status codes. CF_OK is zero, every error is negative. Mesh validation
 * failures each have their own code so a caller can react to the kind of
 * defect without parsing the message. */
typedef enum cf_status {
    CF_OK = 0,
    CF_ERR_INVALID_ARG = -1,     /* a parameter is out of range or NULL */
    CF_ERR_NOMEM = -2,           /* an allocation failed */
    CF_ERR_BAD_MESH = -3,        /* mesh unusable for the request (e.g. wrong genus for an option) */
    CF_ERR_IO = -4,              /* a file could not be opened, read, written or renamed */
    CF_ERR_NOT_POSDEF = -5,      /* a matrix expected to be positive definite is not */
    CF_ERR_NUMERICAL = -6,       /* NaN/Inf, singular system, a step that blew up */
    CF_ERR_NOT_CONVERGED = -7,   /* an iteration hit its limit */
    CF_ERR_CANCELLED = -8,       /* the progress callback asked to stop */
    CF_ERR_PARSE = -9,           /* malformed file content (bad token, bad header) */
    CF_ERR_TRUNCATED = -10,      /* file ended early (unexpected end of file) */
    CF_ERR_INDEX_RANGE = -11,    /* a face refers to a vertex that does not exist */
    CF_ERR_REPEATED_INDEX = -12, /* a face uses the same vertex twice */
    CF_ERR_NONFINITE = -13,      /* NaN or Inf coordinate or value */
    CF_ERR_DEGENERATE_FACE = -14,/* zero-area face */
    CF_ERR_NONMANIFOLD_EDGE = -15,   /* edge shared by more than two faces */
    CF_ERR_NONMANIFOLD_VERTEX = -16, /* vertex whose faces form several fans */
    CF_ERR_ORIENTATION = -17,    /* neighbouring faces traverse their edge in the same direction */
    CF_ERR_UNSUPPORTED = -18     /* valid request this build or method does not support */
} cf_status;

/* Static name of a status ("CF_ERR_NOMEM"); never NULL. */
CF_API const char *cf_status_name(cf_status status);

typedef enum cf_log_level {
    CF_LOG_DEBUG = 0,
    CF_LOG_INFO = 1,
    CF_LOG_WARNING = 2,
    CF_LOG_ERROR = 3
} cf_log_level;

/* Log callback: receives one line without a trailing newline. */
typedef void (*cf_log_fn)(void *user, cf_log_level level, const char *line);

/* Optional allocator. All three must be given together; `user` is passed
 * through. realloc may be NULL (the library then uses malloc + copy). */
typedef struct cf_allocator {
    void *(*malloc_fn)(void *user, size_t bytes);
    void *(*realloc_fn)(void *user, void *ptr, size_t old_bytes, size_t new_bytes);
    void (*free_fn)(void *user, void *ptr, size_t bytes);
    void *user;
} cf_allocator;

typedef struct cf_context cf_context;

/* Creates a context with the default allocator and no log callback.
 * Statuses: CF_OK, CF_ERR_INVALID_ARG (out NULL), CF_ERR_NOMEM. */
CF_API cf_status cf_context_create(cf_context **out);

/* As cf_context_create with a custom allocator (copied; may be NULL). */
CF_API cf_status cf_context_create_with_allocator(const cf_allocator *allocator, cf_context **out);

/* Frees the context and sets *ctx to NULL. Accepts NULL and *ctx == NULL.
 * Every object created with the context must be destroyed before it. */
CF_API void cf_context_destroy(cf_context **ctx);

/* Installs (or with fn == NULL removes) the log callback. Messages below
 * min_level are dropped. */
CF_API void cf_context_set_log(cf_context *ctx, cf_log_fn fn, void *user, cf_log_level min_level);

/* One-line message of the last error (or warning-as-error) recorded in the
 * context; "" if none. Valid until the next call on the context. */
CF_API const char *cf_context_message(const cf_context *ctx);

/* Status of the last error recorded in the context (CF_OK if none). */
CF_API cf_status cf_context_status(const cf_context *ctx);

/* Clears the recorded error. */
CF_API void cf_context_clear_error(cf_context *ctx);

/* Bytes currently allocated through the context (for leak tests). */
CF_API size_t cf_context_bytes_in_use(const cf_context *ctx);

/* Failure injection for tests: the n-th allocation from now (1-based)
 * fails, and every one after it too if `sticky`. n = 0 disables. */
CF_API void cf_context_fail_allocation(cf_context *ctx, int64_t n, int sticky);

/* Number of allocations made through the context so far. */
CF_API int64_t cf_context_allocation_count(const cf_context *ctx);

/* Threads of the library's solver work done with this context: CHOLMOD's
 * OpenMP parallel regions and OpenBLAS's threads inside the factorisations
 * and solves (CHOLMOD, UMFPACK):
 *   1 (default): serial. Debian's CHOLMOD 3.0.14 opens its regions with 4
 *     threads, which on small machines fight OpenBLAS's threads
 *     (factorisations about 2x slower on 2 cores, docs/linalg.md); and on a
 *     machine whose cores are busy with other work every threaded BLAS call
 *     waits for a worker thread to be scheduled (spot_3k's spin-willmore
 *     factorisation 16 ms -> 1.9 s beside two busy processes on 2 cores;
 *     on an idle machine one thread is as fast up to ~26k vertices and
 *     10-16 % slower at 41k-164k; docs/linalg.md, "OpenBLAS's threads");
 *   0: the library leaves the OpenMP runtime and OpenBLAS as the process
 *     set them (OMP_THREAD_LIMIT, OMP_MAX_ACTIVE_LEVELS,
 *     OPENBLAS_NUM_THREADS, the application's own calls): for applications
 *     that manage threads themselves;
 *   n > 1: parallel regions allowed (CHOLMOD picks its own count, capped
 *     by OMP_THREAD_LIMIT; n itself is not a count CHOLMOD can take), and
 *     OpenBLAS keeps the count the process gave it (OPENBLAS_NUM_THREADS,
 *     else one per core).
 * OpenMP's setting is applied through its max-active-levels ICV (0 for 1,
 * 1 for n > 1) of the calling thread just before each call into CHOLMOD
 * made with this context, never at load time, never with 0. OpenBLAS's
 * count is process-wide: with 1 it is lowered to one thread for the
 * duration of each factorisation or solve and handed back after it, so a
 * BLAS call that another thread of the application makes meanwhile runs on
 * one thread too. Results do not depend on the setting beyond rounding (the
 * order of OpenBLAS's reductions: last bits). The command-line tool and the
 * Python package take it from the environment variable CURVFLOW_THREADS.
 * Statuses: CF_ERR_INVALID_ARG (NULL ctx, threads < 0). */
CF_API cf_status cf_context_set_threads(cf_context *ctx, int32_t threads);
/* The context's setting (1 for a NULL ctx). */
CF_API int32_t cf_context_threads(const cf_context *ctx);

/* 1 if OpenBLAS's worker threads of this process are stuck: under an
 * address-space limit (RLIMIT_AS) that was too low when the process started
 * they could not map their work buffers (128 MB each) and retry forever.
 * Then every threaded BLAS call would wait for them (the library refuses
 * factorisations with CF_ERR_NOMEM instead), and exit() hangs, because
 * OpenBLAS joins its threads in its destructor: a program should flush its
 * streams and leave with _exit(). 0 otherwise, without a limit, or with
 * another BLAS. Process-wide; takes no context, never fails. */
CF_API int cf_blas_threads_stuck(void);

/* The name of the kernels OpenBLAS runs in this process ("SkylakeX",
 * "Haswell", "Prescott", ...), or NULL with another BLAS. Never fails. */
CF_API const char *cf_blas_core(void);
/* The value for OPENBLAS_CORETYPE that would make OpenBLAS run faster
 * kernels, or NULL when its own choice stands. OpenBLAS chooses once, when
 * it is loaded, from the CPU's model; one that its release does not know
 * gets the generic SSE3 "Prescott" kernels even with AVX-512 (OpenBLAS
 * 0.3.21 on family 6 model 207 Xeons: supernodal factorisations about
 * 1.8x slower). Non-NULL only then: OPENBLAS_CORETYPE unset, a
 * DYNAMIC_ARCH OpenBLAS running "Prescott" on a CPU with AVX2 and FMA
 * ("Haswell") or AVX-512 ("SkylakeX"). The library never changes the
 * environment: OpenBLAS reads the variable only at load time, so a program
 * sets it and re-executes itself (the command-line tool does), or sets it
 * before anything loads OpenBLAS (the Python package does; docs/linalg.md,
 * "OpenBLAS's kernels"). Never fails. */
CF_API const char *cf_blas_core_advice(void);

/* "0.1.0" */
CF_API const char *cf_version_string(void);

#ifdef __cplusplus
}
#endif
#endif /* CURVFLOW_CURVFLOW_H */
