/* libFuzzer target for the JSON handle files of `curvflow edit`: any input
 * gives a status, never a crash, leak or sanitizer report; a handle set that
 * parses also goes through the stretch-bend flow's checks (create only). The
 * mesh is a fixed 5 x 5 sheet. */
#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/stretch_bend_edit.h"

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    cf_context *ctx = NULL;
    if (cf_context_create(&ctx) != CF_OK) return 0;
    cf_mesh *mesh = NULL;
    char *text = malloc(size + 1);
    if (text && cf_generate_sheet(ctx, 4, 1.0, 0, &mesh) == CF_OK) {
        memcpy(text, data, size);
        text[size] = '\0';
        cf_handle_set *h = NULL;
        if (cf_handle_set_parse_json(ctx, mesh, NULL, text, "fuzz.json", &h) == CF_OK) {
            cf_flow_options o;
            cf_flow_options_default(CF_FLOW_STRETCH_BEND_EDIT, &o);
            ((cf_stretch_bend_options *)cf_flow_options_method(&o))->handles = h;
            cf_flow *flow = NULL;
            if (cf_flow_create(ctx, mesh, NULL, &o, &flow) == CF_OK) cf_flow_destroy(&flow);
            cf_handle_set_destroy(&h);
        }
        cf_mesh_destroy(&mesh);
    }
    free(text);
    if (cf_context_bytes_in_use(ctx) != 0) abort();
    cf_context_destroy(&ctx);
    return 0;
}
