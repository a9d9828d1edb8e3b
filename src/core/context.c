/* Context: allocator, error message, log callback, failure injection. */
#include "core/core.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

const char *cf_status_name(cf_status status)
{
    switch (status) {
    case CF_OK: return "CF_OK";
    case CF_ERR_INVALID_ARG: return "CF_ERR_INVALID_ARG";
    case CF_ERR_NOMEM: return "CF_ERR_NOMEM";
    case CF_ERR_BAD_MESH: return "CF_ERR_BAD_MESH";
    case CF_ERR_IO: return "CF_ERR_IO";
    case CF_ERR_NOT_POSDEF: return "CF_ERR_NOT_POSDEF";
    case CF_ERR_NUMERICAL: return "CF_ERR_NUMERICAL";
    case CF_ERR_NOT_CONVERGED: return "CF_ERR_NOT_CONVERGED";
    case CF_ERR_CANCELLED: return "CF_ERR_CANCELLED";
    case CF_ERR_PARSE: return "CF_ERR_PARSE";
    case CF_ERR_TRUNCATED: return "CF_ERR_TRUNCATED";
    case CF_ERR_INDEX_RANGE: return "CF_ERR_INDEX_RANGE";
    case CF_ERR_REPEATED_INDEX: return "CF_ERR_REPEATED_INDEX";
    case CF_ERR_NONFINITE: return "CF_ERR_NONFINITE";
    case CF_ERR_DEGENERATE_FACE: return "CF_ERR_DEGENERATE_FACE";
    case CF_ERR_NONMANIFOLD_EDGE: return "CF_ERR_NONMANIFOLD_EDGE";
    case CF_ERR_NONMANIFOLD_VERTEX: return "CF_ERR_NONMANIFOLD_VERTEX";
    case CF_ERR_ORIENTATION: return "CF_ERR_ORIENTATION";
    case CF_ERR_UNSUPPORTED: return "CF_ERR_UNSUPPORTED";
    }
    return "CF_ERR_UNKNOWN";
}

/* Built from the header's numbers so the two cannot drift apart. */
#define CFI_STRINGIFY2(x) #x
#define CFI_STRINGIFY(x) CFI_STRINGIFY2(x)
const char *cf_version_string(void)
{
    return CFI_STRINGIFY(CF_VERSION_MAJOR) "." CFI_STRINGIFY(CF_VERSION_MINOR) "." CFI_STRINGIFY(CF_VERSION_PATCH);
}

static void *default_malloc(void *user, size_t bytes) { (void)user; return malloc(bytes); }
static void *default_realloc(void *user, void *ptr, size_t old_bytes, size_t new_bytes)
{
    (void)user; (void)old_bytes;
    return realloc(ptr, new_bytes);
}
static void default_free(void *user, void *ptr, size_t bytes) { (void)user; (void)bytes; free(ptr); }

cf_status cf_context_create_with_allocator(const cf_allocator *allocator, cf_context **out)
{
    if (!out) return CF_ERR_INVALID_ARG;
    *out = NULL;
    if (allocator && (!allocator->malloc_fn || !allocator->free_fn)) return CF_ERR_INVALID_ARG;
    cf_context *ctx = allocator ? allocator->malloc_fn(allocator->user, sizeof *ctx) : malloc(sizeof *ctx);
    if (!ctx) return CF_ERR_NOMEM;
    memset(ctx, 0, sizeof *ctx);
    if (allocator) {
        ctx->allocator = *allocator;
        ctx->has_allocator = true;
    } else {
        ctx->allocator.malloc_fn = default_malloc;
        ctx->allocator.realloc_fn = default_realloc;
        ctx->allocator.free_fn = default_free;
    }
    ctx->log_min_level = CF_LOG_INFO;
    ctx->threads = 1;
    *out = ctx;
    return CF_OK;
}

cf_status cf_context_create(cf_context **out) { return cf_context_create_with_allocator(NULL, out); }

void cf_context_destroy(cf_context **pctx)
{
    if (!pctx || !*pctx) return;
    cf_context *ctx = *pctx;
    if (ctx->linalg_state && ctx->linalg_state_destroy) ctx->linalg_state_destroy(ctx, ctx->linalg_state);
    cf_allocator a = ctx->allocator;
    bool custom = ctx->has_allocator;
    if (custom) a.free_fn(a.user, ctx, sizeof *ctx);
    else free(ctx);
    *pctx = NULL;
}

cf_status cf_context_set_threads(cf_context *ctx, int32_t threads)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    if (threads < 0) return cfi_error(ctx, CF_ERR_INVALID_ARG, "context: threads must be >= 0, got %d", threads);
    ctx->threads = threads;
    return CF_OK;
}

int32_t cf_context_threads(const cf_context *ctx) { return ctx ? ctx->threads : 1; }

void cf_context_set_log(cf_context *ctx, cf_log_fn fn, void *user, cf_log_level min_level)
{
    if (!ctx) return;
    ctx->log_fn = fn;
    ctx->log_user = user;
    ctx->log_min_level = min_level;
}

const char *cf_context_message(const cf_context *ctx) { return ctx ? ctx->message : ""; }
cf_status cf_context_status(const cf_context *ctx) { return ctx ? ctx->last_status : CF_ERR_INVALID_ARG; }
void cf_context_clear_error(cf_context *ctx)
{
    if (!ctx) return;
    ctx->last_status = CF_OK;
    ctx->message[0] = '\0';
}
size_t cf_context_bytes_in_use(const cf_context *ctx) { return ctx ? ctx->bytes_in_use : 0; }
int64_t cf_context_allocation_count(const cf_context *ctx) { return ctx ? ctx->allocation_count : 0; }

void cf_context_fail_allocation(cf_context *ctx, int64_t n, int sticky)
{
    if (!ctx) return;
    ctx->fail_at = n > 0 ? ctx->allocation_count + n : 0;
    ctx->fail_sticky = sticky != 0;
}

static bool injected_failure(cf_context *ctx)
{
    ctx->allocation_count++;
    if (ctx->fail_at <= 0) return false;
    if (ctx->allocation_count == ctx->fail_at) return true;
    return ctx->fail_sticky && ctx->allocation_count > ctx->fail_at;
}

void *cfi_malloc(cf_context *ctx, size_t bytes)
{
    if (bytes == 0) bytes = 1;
    if (injected_failure(ctx)) return NULL;
    void *p = ctx->allocator.malloc_fn(ctx->allocator.user, bytes);
    if (p) ctx->bytes_in_use += bytes;
    return p;
}

void *cfi_calloc(cf_context *ctx, size_t count, size_t size)
{
    if (size != 0 && count > SIZE_MAX / size) return NULL;
    size_t bytes = count * size;
    void *p = cfi_malloc(ctx, bytes);
    if (p) memset(p, 0, bytes ? bytes : 1);
    return p;
}

void *cfi_realloc(cf_context *ctx, void *ptr, size_t old_bytes, size_t new_bytes)
{
    if (!ptr) return cfi_malloc(ctx, new_bytes);
    if (new_bytes == 0) new_bytes = 1;
    if (old_bytes == 0) old_bytes = 1;
    if (injected_failure(ctx)) return NULL;
    void *p;
    if (ctx->allocator.realloc_fn) {
        p = ctx->allocator.realloc_fn(ctx->allocator.user, ptr, old_bytes, new_bytes);
    } else {
        p = ctx->allocator.malloc_fn(ctx->allocator.user, new_bytes);
        if (p) {
            memcpy(p, ptr, old_bytes < new_bytes ? old_bytes : new_bytes);
            ctx->allocator.free_fn(ctx->allocator.user, ptr, old_bytes);
        }
    }
    if (p) ctx->bytes_in_use = ctx->bytes_in_use - old_bytes + new_bytes;
    return p;
}

void cfi_free(cf_context *ctx, void *ptr, size_t bytes)
{
    if (!ptr) return;
    if (bytes == 0) bytes = 1;
    ctx->allocator.free_fn(ctx->allocator.user, ptr, bytes);
    ctx->bytes_in_use -= bytes;
}

void *cfi_alloc_array(cf_context *ctx, size_t count, size_t size)
{
    void *p = cfi_calloc(ctx, count, size);
    if (!p) cfi_error(ctx, CF_ERR_NOMEM, "out of memory allocating %zu x %zu bytes", count, size);
    return p;
}

/* Messages and log lines are one line each (curvflow.h): line breaks in
 * formatted arguments (file names, parser excerpts) become spaces. */
static void one_line(char *text)
{
    for (char *c = text; *c; ++c)
        if (*c == '\n' || *c == '\r') *c = ' ';
}

static void vrecord(cf_context *ctx, const char *fmt, va_list ap)
{
    vsnprintf(ctx->message, sizeof ctx->message, fmt, ap);
    one_line(ctx->message);
}

cf_status cfi_error(cf_context *ctx, cf_status status, const char *fmt, ...)
{
    if (!ctx) return status;
    va_list ap;
    va_start(ap, fmt);
    vrecord(ctx, fmt, ap);
    va_end(ap);
    ctx->last_status = status;
    if (ctx->log_fn && CF_LOG_ERROR >= ctx->log_min_level) ctx->log_fn(ctx->log_user, CF_LOG_ERROR, ctx->message);
    return status;
}

cf_status cfi_error_prefix(cf_context *ctx, const char *fmt, ...)
{
    if (!ctx) return CF_ERR_INVALID_ARG;
    char old[CF_MESSAGE_CAPACITY];
    va_list ap;
    memcpy(old, ctx->message, sizeof old);
    va_start(ap, fmt);
    int n = vsnprintf(ctx->message, sizeof ctx->message, fmt, ap);
    va_end(ap);
    one_line(ctx->message);
    size_t used = n < 0 ? 0 : (size_t)n;
    if (used + 2 < sizeof ctx->message) {
        memcpy(ctx->message + used, ": ", 2);
        used += 2;
        size_t room = sizeof ctx->message - used - 1;
        size_t len = strlen(old);
        if (len > room) len = room;
        memcpy(ctx->message + used, old, len);
        ctx->message[used + len] = '\0';
    }
    return ctx->last_status;
}

void cfi_log(cf_context *ctx, cf_log_level level, const char *fmt, ...)
{
    if (!ctx || !ctx->log_fn || level < ctx->log_min_level) return;
    char line[CF_MESSAGE_CAPACITY];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    one_line(line);
    ctx->log_fn(ctx->log_user, level, line);
}

double cfi_now_seconds(void)
{
    struct timespec ts;
    timespec_get(&ts, TIME_UTC);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void cfi_bounding_box(const double *x, int64_t n, double lo[3], double hi[3])
{
    for (int c = 0; c < 3; ++c) {
        lo[c] = INFINITY;
        hi[c] = -INFINITY;
    }
    for (int64_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            lo[c] = fmin(lo[c], x[3 * i + c]);
            hi[c] = fmax(hi[c], x[3 * i + c]);
        }
}

void cfi_bounding_box_centre(const double *x, int64_t n, double centre[3])
{
    double lo[3], hi[3];
    cfi_bounding_box(x, n, lo, hi);
    for (int c = 0; c < 3; ++c) centre[c] = n > 0 ? 0.5 * (lo[c] + hi[c]) : 0.0;
}

int64_t cfi_first_unusable_point(const double *x, int64_t n, int dim)
{
    for (int64_t i = 0; i < n; ++i)
        for (int c = 0; c < dim; ++c)
            if (!(fabs(x[dim * i + c]) <= CF_MAX_COORDINATE)) return i; /* also NaN */
    return -1;
}
