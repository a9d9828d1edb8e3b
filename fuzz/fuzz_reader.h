/* Shared body of the libFuzzer targets (one per mesh reader): any input must
 * give a status, never a crash, leak or sanitizer report; on success the
 * data must also survive mesh validation (cf_mesh_create) without crashing,
 * and the weld of its seams (cf_mesh_data_weld), after its unused vertices
 * are dropped (cf_mesh_data_drop_unreferenced), must give a valid mesh
 * whenever it welds. */
#ifndef CF_FUZZ_FUZZ_READER_H
#define CF_FUZZ_FUZZ_READER_H

#include "curvflow/io.h"

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

static int fuzz_reader(const uint8_t *data, size_t size, cf_mesh_format format, const char *name)
{
    cf_context *ctx = NULL;
    if (cf_context_create(&ctx) != CF_OK) return 0;
    cf_mesh_data *d = NULL;
    if (cf_read_mesh_memory(ctx, data, size, format, name, &d) == CF_OK) {
        cf_mesh_desc desc;
        cf_mesh *mesh = NULL;
        if (cf_mesh_data_desc(d, &desc) == CF_OK && cf_mesh_create(ctx, &desc, &mesh) == CF_OK) cf_mesh_destroy(&mesh);
        /* the commands drop unused vertices and weld seams (docs/io.md): a
         * weld is made only when the welded data builds a valid mesh */
        cf_weld_report weld;
        int32_t dropped = 0;
        if (cf_mesh_data_drop_unreferenced(ctx, d, NULL, &dropped) == CF_OK &&
            cf_mesh_data_weld(ctx, d, NULL, &weld) == CF_OK && weld.welded) {
            if (cf_mesh_data_desc(d, &desc) != CF_OK || cf_mesh_create(ctx, &desc, &mesh) != CF_OK) abort();
            cf_mesh_destroy(&mesh);
        }
        cf_mesh_data_destroy(&d);
    }
    /* everything allocated through the context must be back */
    if (cf_context_bytes_in_use(ctx) != 0) abort();
    cf_context_destroy(&ctx);
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#endif
