/* libFuzzer target for the per-vertex value files (`curvflow spin --rho
 * FILE`, cf_read_vertex_scalars_memory): any input gives a status, never a
 * crash, leak or sanitizer report; values that are accepted also go through
 * the SpinXForm on a 12-vertex icosphere (whatever its status). */
#include "curvflow/generate.h"
#include "curvflow/io.h"
#include "curvflow/spin_willmore.h"

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    cf_context *ctx = NULL;
    if (cf_context_create(&ctx) != CF_OK) return 0;
    cf_mesh *mesh = NULL;
    if (cf_generate_icosphere(ctx, 0, 1.0, &mesh) == CF_OK) {
        double rho[12], x[36];
        if (cf_read_vertex_scalars_memory(ctx, data, size, "fuzz.txt", cf_mesh_vertex_count(mesh), rho) == CF_OK)
            (void)cf_spin_transform(ctx, mesh, NULL, rho, x);
        cf_mesh_destroy(&mesh);
    }
    if (cf_context_bytes_in_use(ctx) != 0) abort();
    cf_context_destroy(&ctx);
    return 0;
}
