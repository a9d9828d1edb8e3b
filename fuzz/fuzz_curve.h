/* Shared body of the polyline fuzz targets: any input gives a status, never
 * a crash, leak or sanitizer report; a curve that parses also goes through
 * cf_curve_flow_create and, if accepted, one step (whatever its status). */
#ifndef CF_FUZZ_FUZZ_CURVE_H
#define CF_FUZZ_FUZZ_CURVE_H

#include "curvflow/curve_flow.h"

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

static int fuzz_curve(const uint8_t *data, size_t size, int svg)
{
    cf_context *ctx = NULL;
    if (cf_context_create(&ctx) != CF_OK) return 0;
    cf_curve *curve = NULL;
    if (cf_curve_read_memory(ctx, data, size, svg, NULL, &curve) == CF_OK) {
        cf_curve_flow *flow = NULL;
        if (cf_curve_flow_create(ctx, curve->count, curve->points, NULL, &flow) == CF_OK) {
            (void)cf_curve_flow_step(flow, NULL);
            cf_curve_flow_destroy(&flow);
        }
        cf_curve_destroy(&curve);
    }
    if (cf_context_bytes_in_use(ctx) != 0) abort();
    cf_context_destroy(&ctx);
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#endif
