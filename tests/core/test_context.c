/* Context: messages, statuses, allocation accounting and failure injection. */
#include "core/core.h"
#include "test.h"

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

int main(void)
{
    CFT_RUN(test_status_names);
    CFT_RUN(test_error_message_is_one_line);
    CFT_RUN(test_allocation_accounting_and_injection);
    return cft_finish();
}
