/*
 * Internal core: allocation through the context, error recording, logging.
 * Every library function that can fail records its message with cfi_error
 * and returns the same status, so the usual idiom is
 *     if (nv < 3) return cfi_error(ctx, CF_ERR_INVALID_ARG, "need at least 3 vertices, got %d", nv);
 */
#ifndef CF_CORE_CORE_H
#define CF_CORE_CORE_H

#include "curvflow/curvflow.h"

#include <assert.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define CF_MESSAGE_CAPACITY 512

/* Guards a branch that should be unreachable: asserts in debug builds,
 * evaluates to the condition in release builds so the caller can still fail
 * gracefully. */
#ifdef NDEBUG
#define CF_NEVER(x) (x)
#else
#define CF_NEVER(x) ((x) ? (assert(!#x), 1) : 0)
#endif

#if defined(__GNUC__)
#define CF_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define CF_PRINTF(a, b)
#endif

/* A subsystem (the linear-algebra layer) can park its per-context state
 * here; core frees it through the given destructor in cf_context_destroy. */
typedef void (*cfi_state_destroy_fn)(cf_context *ctx, void *state);

struct cf_context {
    cf_allocator allocator;
    bool has_allocator;
    cf_log_fn log_fn;
    void *log_user;
    cf_log_level log_min_level;
    cf_status last_status;
    char message[CF_MESSAGE_CAPACITY];
    size_t bytes_in_use;
    int64_t allocation_count;
    int64_t fail_at;      /* allocation number that fails (0 = never) */
    bool fail_sticky;
    void *linalg_state;
    cfi_state_destroy_fn linalg_state_destroy;
    int32_t threads;      /* cf_context_set_threads: OpenMP regions and OpenBLAS (1 serial, 0 untouched) */
};

/* Allocation. Sizes are in bytes; counts times element size are
 * overflow-checked by the *_array variants, which record CF_ERR_NOMEM with a
 * message on failure. cfi_free accepts NULL. The byte count given to
 * cfi_free/cfi_realloc must be the one allocated. */
void *cfi_malloc(cf_context *ctx, size_t bytes);
void *cfi_calloc(cf_context *ctx, size_t count, size_t size);
void *cfi_realloc(cf_context *ctx, void *ptr, size_t old_bytes, size_t new_bytes);
void cfi_free(cf_context *ctx, void *ptr, size_t bytes);
/* Array helpers: count elements of `size` bytes, zero-filled, overflow-checked. */
void *cfi_alloc_array(cf_context *ctx, size_t count, size_t size);
#define CFI_ALLOC(ctx, type, count) ((type *)cfi_alloc_array((ctx), (size_t)(count), sizeof(type)))
#define CFI_FREE(ctx, ptr, count) \
    do { cfi_free((ctx), (ptr), (size_t)(count) * sizeof(*(ptr))); (ptr) = NULL; } while (0)

/* Records status and a printf-formatted one-line message; returns status.
 * Also forwards the line to the log callback at CF_LOG_ERROR. */
cf_status cfi_error(cf_context *ctx, cf_status status, const char *fmt, ...) CF_PRINTF(3, 4);

/* Prefixes the current message with "prefix: " (e.g. a file name and line),
 * keeping the status; returns the status. */
cf_status cfi_error_prefix(cf_context *ctx, const char *fmt, ...) CF_PRINTF(2, 3);

/* Sends one line to the log callback if installed and level high enough. */
void cfi_log(cf_context *ctx, cf_log_level level, const char *fmt, ...) CF_PRINTF(3, 4);

/* Monotonic wall-clock time in seconds (for per-step timings). */
double cfi_now_seconds(void);

/* Index of the first of the n points x[dim i .. dim i + dim) with a
 * coordinate that is NaN, infinite or beyond CF_MAX_COORDINATE; -1 if none. */
int64_t cfi_first_unusable_point(const double *x, int64_t n, int dim);

/* Smallest and largest coordinates of the n points x[3 i .. 3 i + 3)
 * (lo = +inf, hi = -inf for n = 0; NaN coordinates are skipped). */
void cfi_bounding_box(const double *x, int64_t n, double lo[3], double hi[3]);
/* The centre of that box: coordinates relative to it keep the digits of
 * points far from the origin (0 for n = 0). */
void cfi_bounding_box_centre(const double *x, int64_t n, double centre[3]);

/* ---- workspace (src/core/workspace.c) ----
 *
 * A per-object workspace (issue 12 item 6): a record of the arrays one
 * flow (or any object with a create / destroy pair) allocates, each through
 * the context, so that allocation-failure injection reaches every one of
 * them and cf_context_bytes_in_use counts them, and so that destroy frees
 * them all in one call whatever subset a failed create got to. The record
 * is a fixed table inside the owner's state: recording never allocates,
 * and steps that only use the arrays allocate nothing.
 *
 *     cfi_workspace_init(&s->ws, ctx);
 *     s->mass = CFI_WS_ALLOC(&s->ws, double, nv);          (NULL: CF_ERR_NOMEM recorded)
 *     ...
 *     cfi_workspace_free_all(&s->ws);                      (in destroy)
 *
 * Arrays that are replaced during the owner's life (reallocated) do not
 * belong here: the workspace frees only at the end.
 */

/* Arrays one workspace can record (the largest user, spin-willmore, has up to 22). */
#define CFI_WORKSPACE_SLOTS 48

typedef struct cfi_workspace {
    cf_context *ctx;
    int32_t count;                      /* arrays recorded, oldest first */
    void *ptr[CFI_WORKSPACE_SLOTS];
    size_t bytes[CFI_WORKSPACE_SLOTS];  /* as allocated, for cfi_free */
} cfi_workspace;

/* An empty workspace allocating through ctx (a zero-filled struct with ctx
 * set is the same). */
void cfi_workspace_init(cfi_workspace *ws, cf_context *ctx);

/* count elements of `size` bytes, zero-filled, overflow-checked, recorded.
 * NULL with CF_ERR_NOMEM and a message in the context when the allocation
 * fails (or the table is full); the arrays recorded before are kept. A
 * count of 0 gives a recorded allocation of 0 bytes like cfi_alloc_array. */
void *cfi_workspace_alloc(cfi_workspace *ws, size_t count, size_t size);
#define CFI_WS_ALLOC(ws, type, count) ((type *)cfi_workspace_alloc((ws), (size_t)(count), sizeof(type)))

/* Frees every recorded array, newest first (the reverse of the allocation
 * order); the workspace is empty afterwards and may be used again. Accepts
 * an empty workspace and NULL. */
void cfi_workspace_free_all(cfi_workspace *ws);

#endif /* CF_CORE_CORE_H */
