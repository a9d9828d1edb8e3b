/*
 * Timing of the baseline flows (src/methods/baseline_flows/) on icospheres
 * of growing size: milliseconds per step split into assemble / factorize /
 * solve, after one warm-up step. Prints TSV; asserts nothing.
 *   bench_baseline_flows [max_subdivisions (default 6)]
 */
#include "curvflow/baseline_flows.h"
#include "curvflow/flow.h"
#include "curvflow/generate.h"

#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv)
{
    int max_sub = argc > 1 ? atoi(argv[1]) : 6;
    cf_context *ctx = NULL;
    if (cf_context_create(&ctx) != CF_OK) return 1;
    printf("method\tV\tF\tsteps\tms_per_step\tassemble_ms\tfactorize_ms\tsolve_ms\tenergy_ratio\n");
    for (int sub = 3; sub <= max_sub; ++sub) {
        cf_mesh *mesh = NULL;
        if (cf_generate_bumpy_sphere(ctx, sub, 0.2, 1u, &mesh) != CF_OK) {
            fprintf(stderr, "%s\n", cf_context_message(ctx));
            return 1;
        }
        for (int k = CF_FLOW_EXPLICIT_MCF; k <= CF_FLOW_IMPLICIT_BILAPLACIAN; ++k) {
            cf_flow_options o;
            cf_flow_options_default((cf_flow_kind)k, &o);
            cf_flow *flow = NULL;
            if (cf_flow_create(ctx, mesh, NULL, &o, &flow) != CF_OK) {
                fprintf(stderr, "%s: %s\n", cf_flow_kind_name((cf_flow_kind)k), cf_context_message(ctx));
                continue;
            }
            double e0 = cf_flow_energy(flow);
            cf_flow_info info;
            cf_flow_step(flow, &info); /* warm-up */
            const int steps = 5;
            double total = 0, as = 0, fa = 0, so = 0;
            for (int s = 0; s < steps; ++s) {
                if (cf_flow_step(flow, &info) != CF_OK) {
                    fprintf(stderr, "%s\n", cf_context_message(ctx));
                    break;
                }
                total += info.total_seconds;
                as += info.assemble_seconds;
                fa += info.factorize_seconds;
                so += info.solve_seconds;
            }
            printf("%s\t%d\t%d\t%d\t%.3f\t%.3f\t%.3f\t%.3f\t%.6f\n", cf_flow_kind_name((cf_flow_kind)k),
                   (int)cf_mesh_vertex_count(mesh), (int)cf_mesh_face_count(mesh), steps, 1e3 * total / steps,
                   1e3 * as / steps, 1e3 * fa / steps, 1e3 * so / steps, cf_flow_energy(flow) / e0);
            cf_flow_destroy(&flow);
        }
        cf_mesh_destroy(&mesh);
    }
    cf_context_destroy(&ctx);
    return 0;
}
