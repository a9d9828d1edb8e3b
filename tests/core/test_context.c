/* Context: messages, statuses, allocation accounting and failure injection. */
#include "core/core.h"
#include "test.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void test_status_names(void)
{
    CHECK(strcmp(cf_status_name(CF_OK), "CF_OK") == 0);
    CHECK(strcmp(cf_status_name(CF_ERR_NONMANIFOLD_EDGE), "CF_ERR_NONMANIFOLD_EDGE") == 0);
    CHECK(strcmp(cf_status_name((cf_status)-999), "CF_ERR_UNKNOWN") == 0);
}

static void test_error_message_is_one_line(void)
{
    cf_context *ctx = cft_context();
    CHECK_STATUS(cfi_error(ctx, CF_ERR_PARSE, "line %d:\nbad token", 7), CF_ERR_PARSE);
    CHECK(strcmp(cf_context_message(ctx), "line 7: bad token") == 0);
    CHECK_STATUS(cf_context_status(ctx), CF_ERR_PARSE);
    cfi_error_prefix(ctx, "%s", "mesh.obj");
    CHECK(strcmp(cf_context_message(ctx), "mesh.obj: line 7: bad token") == 0);
    cf_context_clear_error(ctx);
    CHECK(cf_context_message(ctx)[0] == '\0');
    cf_context_destroy(&ctx);
    CHECK(ctx == NULL);
}

static void test_allocation_accounting_and_injection(void)
{
    cf_context *ctx = cft_context();
    double *a = CFI_ALLOC(ctx, double, 100);
    CHECK(a != NULL);
    CHECK(cf_context_bytes_in_use(ctx) == 100 * sizeof(double));
    CFI_FREE(ctx, a, 100);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_fail_allocation(ctx, 2, 0);
    void *p1 = cfi_malloc(ctx, 8);
    void *p2 = cfi_malloc(ctx, 8);
    void *p3 = cfi_malloc(ctx, 8);
    CHECK(p1 != NULL);
    CHECK(p2 == NULL);
    CHECK(p3 != NULL);
    cfi_free(ctx, p1, 8);
    cfi_free(ctx, p3, 8);
    CHECK(CFI_ALLOC(ctx, double, SIZE_MAX / 4) == NULL);
    CHECK_STATUS(cf_context_status(ctx), CF_ERR_NOMEM);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* A counting allocator without realloc: the library must fall back to
 * malloc + copy + free and route every byte through it. */
typedef struct counting {
    int64_t mallocs, frees;
    size_t live;
} counting;

static void *counting_malloc(void *user, size_t bytes)
{
    counting *c = user;
    ++c->mallocs;
    c->live += bytes;
    return malloc(bytes);
}

static void counting_free(void *user, void *ptr, size_t bytes)
{
    counting *c = user;
    ++c->frees;
    c->live -= bytes;
    free(ptr);
}

static void test_custom_allocator(void)
{
    counting cnt = {0, 0, 0};
    cf_allocator a = {counting_malloc, NULL, counting_free, &cnt};
    cf_context *ctx = NULL;
    CHECK_STATUS(cf_context_create_with_allocator(&a, &ctx), CF_OK);
    CHECK(ctx != NULL);
    if (!ctx) return;
    CHECK(cnt.mallocs == 1); /* the context itself */
    int32_t *v = CFI_ALLOC(ctx, int32_t, 4);
    CHECK(v != NULL);
    if (v) {
        for (int i = 0; i < 4; ++i) v[i] = 10 + i;
        int32_t *w = cfi_realloc(ctx, v, 4 * sizeof *v, 8 * sizeof *v);
        CHECK(w != NULL);
        if (w) {
            CHECK(w[0] == 10 && w[3] == 13); /* contents kept by the malloc + copy fallback */
            v = w;
        }
        CHECK(cf_context_bytes_in_use(ctx) == 8 * sizeof *v);
        cfi_free(ctx, v, 8 * sizeof *v);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
    CHECK(cnt.mallocs == cnt.frees);
    CHECK(cnt.live == 0);
    /* an allocator missing malloc or free is refused */
    cf_allocator bad = {NULL, NULL, counting_free, &cnt};
    CHECK_STATUS(cf_context_create_with_allocator(&bad, &ctx), CF_ERR_INVALID_ARG);
    CHECK(ctx == NULL);
}

static void test_sticky_injection(void)
{
    cf_context *ctx = cft_context();
    int64_t before = cf_context_allocation_count(ctx);
    cf_context_fail_allocation(ctx, 2, 1);
    void *p1 = cfi_malloc(ctx, 8), *p2 = cfi_malloc(ctx, 8), *p3 = cfi_malloc(ctx, 8);
    CHECK(p1 != NULL);
    CHECK(p2 == NULL);
    CHECK(p3 == NULL); /* sticky: every allocation after the n-th fails too */
    CHECK(cf_context_allocation_count(ctx) == before + 3);
    cf_context_fail_allocation(ctx, 0, 0);
    void *p4 = cfi_malloc(ctx, 8);
    CHECK(p4 != NULL);
    cfi_free(ctx, p1, 8);
    cfi_free(ctx, p4, 8);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

typedef struct log_capture {
    int calls;
    cf_log_level level;
    char line[CF_MESSAGE_CAPACITY];
} log_capture;

static void capture_log(void *user, cf_log_level level, const char *line)
{
    log_capture *c = user;
    ++c->calls;
    c->level = level;
    snprintf(c->line, sizeof c->line, "%s", line);
}

static void test_log_callback(void)
{
    cf_context *ctx = cft_context();
    log_capture cap = {0, CF_LOG_DEBUG, ""};
    cf_context_set_log(ctx, capture_log, &cap, CF_LOG_WARNING);
    cfi_log(ctx, CF_LOG_INFO, "dropped %d", 1);
    CHECK(cap.calls == 0);
    cfi_log(ctx, CF_LOG_WARNING, "two\nlines %d", 2);
    CHECK(cap.calls == 1);
    CHECK(cap.level == CF_LOG_WARNING);
    CHECK(strcmp(cap.line, "two lines 2") == 0);
    /* errors are forwarded at CF_LOG_ERROR */
    cfi_error(ctx, CF_ERR_IO, "x.obj: cannot open");
    CHECK(cap.calls == 2);
    CHECK(cap.level == CF_LOG_ERROR);
    CHECK(strcmp(cap.line, "x.obj: cannot open") == 0);
    cf_context_set_log(ctx, NULL, NULL, CF_LOG_DEBUG);
    cfi_log(ctx, CF_LOG_ERROR, "nobody listens");
    CHECK(cap.calls == 2);
    cf_context_destroy(&ctx);
}

static void test_null_safety(void)
{
    CHECK_STATUS(cf_context_create(NULL), CF_ERR_INVALID_ARG);
    cf_context_destroy(NULL);
    cf_context *none = NULL;
    cf_context_destroy(&none);
    CHECK(strcmp(cf_context_message(NULL), "") == 0);
    CHECK_STATUS(cf_context_status(NULL), CF_ERR_INVALID_ARG);
    CHECK(cf_context_bytes_in_use(NULL) == 0);
    cf_context_clear_error(NULL);
    cf_context_set_log(NULL, NULL, NULL, CF_LOG_DEBUG);
    cf_context_fail_allocation(NULL, 1, 1);
    char version[32];
    snprintf(version, sizeof version, "%d.%d.%d", CF_VERSION_MAJOR, CF_VERSION_MINOR, CF_VERSION_PATCH);
    CHECK(strcmp(cf_version_string(), version) == 0);
}

int main(void)
{
    CFT_RUN(test_custom_allocator);
    CFT_RUN(test_sticky_injection);
    CFT_RUN(test_log_callback);
    CFT_RUN(test_null_safety);
    CFT_RUN(test_status_names);
    CFT_RUN(test_error_message_is_one_line);
    CFT_RUN(test_allocation_accounting_and_injection);
    return cft_finish();
}
