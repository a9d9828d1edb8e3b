/* libFuzzer target for the boundary target files (`curvflow flow
 * --boundary-targets FILE`, cf_read_vertex_directions_memory with the
 * boundary of an 8 x 2 cylinder): any input gives a status, never a crash,
 * leak or sanitizer report. Targets the reader accepts must also be
 * accepted by spin-willmore's creation (issue 15, E4: bad values used to
 * pass the reader and fail there as a usage error): abort otherwise. */
#include "curvflow/flow.h"
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
    if (cf_generate_cylinder(ctx, 8, 2, 1.0, 1.0, &mesh) == CF_OK) {
        int32_t nv = cf_mesh_vertex_count(mesh);
        double *targets = malloc(3 * (size_t)nv * sizeof(double));
        if (targets && cf_read_vertex_directions_memory(ctx, data, size, "fuzz.txt", nv, cf_mesh_vertex_on_boundary(mesh),
                                                        "boundary vertex", targets) == CF_OK) {
            cf_flow_options o;
            cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o);
            cf_spin_willmore_options *so = cf_flow_options_method(&o);
            so->boundary_mode = CF_SPIN_BOUNDARY_PRESCRIBED;
            so->boundary_targets = (cf_param_values){.values = targets, .count = nv};
            cf_flow *flow = NULL;
            cf_status st = cf_flow_create(ctx, mesh, NULL, &o, &flow);
            cf_flow_destroy(&flow);
            if (st == CF_ERR_INVALID_ARG) abort();
        }
        free(targets);
        cf_mesh_destroy(&mesh);
    }
    if (cf_context_bytes_in_use(ctx) != 0) abort();
    cf_context_destroy(&ctx);
    return 0;
}
