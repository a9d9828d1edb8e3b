/*
 * The per-object workspace (cfi_workspace: src/core/core.h, workspace.c): arrays allocated through
 * the context are recorded, counted in cf_context_bytes_in_use and freed in
 * one call, newest first; an injected allocation failure returns NULL with
 * CF_ERR_NOMEM and keeps the arrays recorded before it, which the one call
 * still frees.
 */
#include "core/core.h"
#include "test.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* An allocator that logs the order of frees (by the first byte of each
 * array, its tag) and counts the bytes it holds. */
typedef struct free_log {
    unsigned char order[16];
    int count;
    size_t held;
} free_log;

static void *log_malloc(void *user, size_t bytes)
{
    free_log *l = user;
    l->held += bytes;
    return malloc(bytes);
}

static void log_free(void *user, void *ptr, size_t bytes)
{
    free_log *l = user;
    if (l->count < (int)sizeof l->order) l->order[l->count++] = *(unsigned char *)ptr;
    l->held -= bytes;
    free(ptr);
}

static void test_records_and_frees_newest_first(void)
{
    free_log log;
    memset(&log, 0, sizeof log);
    cf_allocator a = {log_malloc, NULL, log_free, &log};
    cf_context *ctx = NULL;
    CHECK_OK(ctx, cf_context_create_with_allocator(&a, &ctx));
    if (!ctx) return;
    size_t held0 = log.held; /* the context itself */
    cfi_workspace ws;
    cfi_workspace_init(&ws, ctx);
    double *d = CFI_WS_ALLOC(&ws, double, 100);
    int32_t *i = CFI_WS_ALLOC(&ws, int32_t, 7);
    unsigned char *e = CFI_WS_ALLOC(&ws, unsigned char, 0); /* 0 elements: still an allocation, of 1 byte */
    uint8_t *b = CFI_WS_ALLOC(&ws, uint8_t, 3);
    CHECK(d && i && e && b);
    if (!d || !i || !e || !b) {
        cfi_workspace_free_all(&ws);
        cf_context_destroy(&ctx);
        return;
    }
    CHECK(ws.count == 4);
    CHECK(cf_context_bytes_in_use(ctx) == 100 * sizeof(double) + 7 * sizeof(int32_t) + 1 + 3);
    CHECK(log.held - held0 == cf_context_bytes_in_use(ctx));
    /* zero-filled, and tagged for the order of the frees */
    CHECK(d[99] == 0.0 && i[6] == 0 && b[2] == 0);
    memset(d, 1, 1);
    memset(i, 2, 1);
    e[0] = 3;
    b[0] = 4;
    cfi_workspace_free_all(&ws);
    CHECK(ws.count == 0);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    CHECK(log.held == held0);
    CHECK(log.count == 4);
    CHECK(log.order[0] == 4 && log.order[1] == 3 && log.order[2] == 2 && log.order[3] == 1);
    /* empty again, usable again; freeing an empty one (or NULL) is nothing */
    cfi_workspace_free_all(&ws);
    cfi_workspace_free_all(NULL);
    CHECK(log.count == 4);
    CHECK(CFI_WS_ALLOC(&ws, double, 2) != NULL);
    CHECK(ws.count == 1);
    cfi_workspace_free_all(&ws);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* The n-th allocation fails for every n: NULL, CF_ERR_NOMEM and a message,
 * the earlier arrays kept (and still in bytes_in_use), nothing recorded for
 * the failed one; free_all then brings the bytes back to 0. */
static void test_failure_injection(void)
{
    cf_context *ctx = cft_context();
    const size_t counts[5] = {10, 1000, 3, 64, 5};
    for (int64_t n = 1; n <= 5; ++n) {
        cfi_workspace ws;
        cfi_workspace_init(&ws, ctx);
        cf_context_clear_error(ctx);
        cf_context_fail_allocation(ctx, n, 0);
        size_t expected = 0;
        int failed_at = -1;
        for (int k = 0; k < 5; ++k) {
            double *p = CFI_WS_ALLOC(&ws, double, counts[k]);
            if (!p) {
                failed_at = k;
                break;
            }
            expected += counts[k] * sizeof(double);
        }
        CHECK(failed_at == (int)n - 1);
        CHECK_STATUS(cf_context_status(ctx), CF_ERR_NOMEM);
        CHECK(strstr(cf_context_message(ctx), "out of memory") != NULL);
        CHECK(ws.count == (int32_t)n - 1);
        CHECK(cf_context_bytes_in_use(ctx) == expected);
        cf_context_fail_allocation(ctx, 0, 0);
        /* the ones after the failure allocate again (not sticky) */
        CHECK(CFI_WS_ALLOC(&ws, double, 1) != NULL);
        CHECK(ws.count == (int32_t)n);
        cfi_workspace_free_all(&ws);
        CHECK(cf_context_bytes_in_use(ctx) == 0);
    }
    /* a count whose byte size overflows: NULL and NOMEM, nothing recorded */
    cfi_workspace ws;
    cfi_workspace_init(&ws, ctx);
    CHECK(CFI_WS_ALLOC(&ws, double, SIZE_MAX / 4) == NULL);
    CHECK_STATUS(cf_context_status(ctx), CF_ERR_NOMEM);
    CHECK(ws.count == 0);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_records_and_frees_newest_first);
    CFT_RUN(test_failure_injection);
    return cft_finish();
}
