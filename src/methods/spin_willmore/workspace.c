/*
 * The arrays of one spin-willmore flow, allocated through the context (so
 * allocation-failure injection reaches every one of them) and recorded, so
 * that destroy frees them all in one call whatever subset a failed create
 * got to. The record is a fixed table inside the flow's state: recording
 * itself never allocates.
 */
#include "methods/spin_willmore/spin_flow.h"

void *cfi_spin_ws_alloc(cfi_spin_workspace *ws, size_t count, size_t size)
{
    if (CF_NEVER(ws->count >= CFI_SPIN_WORKSPACE_SLOTS)) {
        cfi_error(ws->ctx, CF_ERR_NOMEM, "spin-willmore: workspace table full (%d arrays)", ws->count);
        return NULL;
    }
    void *p = cfi_alloc_array(ws->ctx, count, size);
    if (!p) return NULL;
    ws->ptr[ws->count] = p;
    ws->bytes[ws->count] = count * size; /* cfi_alloc_array checked the product */
    ws->count++;
    return p;
}

void cfi_spin_ws_free_all(cfi_spin_workspace *ws)
{
    /* newest first, the reverse of the allocation order */
    while (ws->count > 0) {
        --ws->count;
        cfi_free(ws->ctx, ws->ptr[ws->count], ws->bytes[ws->count]);
        ws->ptr[ws->count] = NULL;
    }
}
