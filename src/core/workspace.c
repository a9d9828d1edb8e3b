/*
 * Per-object workspace: arrays allocated through the context and recorded
 * in a fixed table, freed in one call (core/core.h).
 */
#include "core/core.h"

#include <string.h>

void cfi_workspace_init(cfi_workspace *ws, cf_context *ctx)
{
    memset(ws, 0, sizeof *ws);
    ws->ctx = ctx;
}

void *cfi_workspace_alloc(cfi_workspace *ws, size_t count, size_t size)
{
    if (CF_NEVER(ws->count >= CFI_WORKSPACE_SLOTS)) {
        cfi_error(ws->ctx, CF_ERR_NOMEM, "workspace table full (%d arrays)", (int)ws->count);
        return NULL;
    }
    void *p = cfi_alloc_array(ws->ctx, count, size);
    if (!p) return NULL;
    ws->ptr[ws->count] = p;
    ws->bytes[ws->count] = count * size; /* cfi_alloc_array checked the product */
    ws->count++;
    return p;
}

void cfi_workspace_free_all(cfi_workspace *ws)
{
    if (!ws) return;
    while (ws->count > 0) {
        --ws->count;
        cfi_free(ws->ctx, ws->ptr[ws->count], ws->bytes[ws->count]);
        ws->ptr[ws->count] = NULL;
        ws->bytes[ws->count] = 0;
    }
}
