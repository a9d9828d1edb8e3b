/*
 * Benchmark of Zhao & Gortler editing and the ARAP energies (one TSV row
 * per energy): the set-up, a mesh (default armadillo_26k) with the
 * lowest 10% of the vertices (by y, the up axis) fixed and the highest 10%
 * moved sideways by 10% of the height. Reports the set-up time (model,
 * matrix, symbolic analysis + factorisation) and the per-iteration time
 * split into assembly (local step + right-hand side) and solve, and the
 * fastest single iteration (robust to other load on a shared machine).
 *
 *   bench_stretch_bend_edit [MESH] [ITERATIONS]
 * bench/cgal_deform.cpp measures CGAL's Surface_mesh_deformation on the same
 * handles (same selection rule) for comparison.
 */
#define _POSIX_C_SOURCE 200809L
#include "curvflow/curvflow.h"
#include "curvflow/flow.h"
#include "curvflow/io.h"
#include "curvflow/stretch_bend_edit.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static const double *sort_key;
static int by_height(const void *a, const void *b)
{
    int32_t i = *(const int32_t *)a, j = *(const int32_t *)b;
    double yi = sort_key[3 * i + 1], yj = sort_key[3 * j + 1];
    if (yi != yj) return yi < yj ? -1 : 1;
    return (i > j) - (i < j);
}

int main(int argc, char **argv)
{
    /* Default: ../shared/meshes next to the source tree (found from this
     * file's path), as the tests do. */
    char default_path[4096];
    snprintf(default_path, sizeof default_path, "%s", __FILE__);
    char *slash = strstr(default_path, "bench/bench_stretch_bend_edit.c");
    if (slash) snprintf(slash, sizeof default_path - (size_t)(slash - default_path), "../shared/meshes/armadillo_26k.obj");
    const char *path = argc > 1 ? argv[1] : default_path;
    int iterations = argc > 2 ? atoi(argv[2]) : 20;
    cf_context *ctx = NULL;
    if (cf_context_create(&ctx) != CF_OK) return 1;
    cf_mesh *mesh = NULL;
    if (cf_load_mesh(ctx, path, &mesh) != CF_OK) {
        fprintf(stderr, "bench_stretch_bend_edit: %s\n", cf_context_message(ctx));
        cf_context_destroy(&ctx);
        return 1;
    }
    int32_t nv = cf_mesh_vertex_count(mesh), nf = cf_mesh_face_count(mesh);
    const double *x = cf_mesh_positions(mesh);
    int32_t *order = malloc(sizeof(int32_t) * (size_t)nv);
    int32_t *vs = malloc(sizeof(int32_t) * (size_t)nv);
    double *ts = malloc(sizeof(double) * 3 * (size_t)nv);
    if (!order || !vs || !ts) return 1;
    for (int32_t v = 0; v < nv; ++v) order[v] = v;
    sort_key = x;
    qsort(order, (size_t)nv, sizeof(int32_t), by_height);
    double height = x[3 * order[nv - 1] + 1] - x[3 * order[0] + 1];
    int32_t tenth = nv / 10, n = 0;
    for (int32_t k = 0; k < nv; ++k) {
        if (k >= tenth && k < nv - tenth) continue;
        int32_t v = order[k];
        vs[n] = v;
        memcpy(ts + 3 * n, x + 3 * v, 3 * sizeof(double));
        if (k >= nv - tenth) ts[3 * n] += 0.1 * height;
        ++n;
    }
    cf_handle_set *h = NULL;
    if (cf_handle_set_create(ctx, n, vs, ts, &h) != CF_OK) return 1;

    printf("method\tenergy\tV\tF\thandles\titerations\tsetup_ms\tms_per_iteration\tassemble_local_ms\tsolve_ms\t"
           "min_ms_per_iteration\tenergy_first\tenergy_last\tanderson_accepted\tanderson_rejected\n");
    /* One row per energy, plus the hybrid with Anderson acceleration (depth 5). */
    for (int row = 0; row <= CF_STRETCH_BEND_ENERGY_COUNT; ++row) {
        int e = row < CF_STRETCH_BEND_ENERGY_COUNT ? row : CF_STRETCH_BEND_HYBRID;
        const char *label = row < CF_STRETCH_BEND_ENERGY_COUNT ? cf_stretch_bend_energy_name((cf_stretch_bend_energy_kind)e) : "hybrid+anderson5";
        cf_flow_options fo;
        cf_flow_options_default(CF_FLOW_STRETCH_BEND_EDIT, &fo);
        cf_stretch_bend_options *o = cf_flow_options_method(&fo);
        o->energy = e;
        o->anderson = row < CF_STRETCH_BEND_ENERGY_COUNT ? 0 : 5;
        o->handles = h;
        o->relative_tolerance = 0.0;
        cf_flow *flow = NULL;
        double t0 = now();
        if (cf_flow_create(ctx, mesh, NULL, &fo, &flow) != CF_OK) {
            printf("stretch-bend-edit\t%s\t%d\t%d\t%d\tfailed: %s\n", label, nv, nf, n, cf_context_message(ctx));
            continue;
        }
        double setup = now() - t0;
        double e0 = cf_flow_energy(flow), assemble = 0.0, solve = 0.0, total = 0.0, best = 1e30;
        cf_flow_info info;
        int done = 0;
        for (int k = 0; k < iterations; ++k) {
            double s0 = now();
            if (cf_flow_step(flow, &info) != CF_OK) break;
            double dt = now() - s0;
            total += dt;
            if (dt < best) best = dt;
            assemble += info.assemble_seconds;
            solve += info.solve_seconds;
            ++done;
        }
        /* Anderson's counters are residuals 1 and 2 when it is on. */
        double accepted = 0.0, rejected = 0.0;
        if (o->anderson > 0 && done > 0) {
            accepted = info.residuals[1];
            rejected = info.residuals[2];
        }
        if (done == 0) done = 1;
        printf("stretch-bend-edit\t%s\t%d\t%d\t%d\t%d\t%.1f\t%.2f\t%.2f\t%.2f\t%.2f\t%.6g\t%.6g\t%.0f\t%.0f\n",
               label, nv, nf, n, done, 1e3 * setup, 1e3 * total / done,
               1e3 * assemble / done, 1e3 * solve / done, 1e3 * best, e0, cf_flow_energy(flow), accepted, rejected);
        fflush(stdout);
        cf_flow_destroy(&flow);
    }
    cf_handle_set_destroy(&h);
    free(order);
    free(vs);
    free(ts);
    cf_mesh_destroy(&mesh);
    cf_context_destroy(&ctx);
    return 0;
}
