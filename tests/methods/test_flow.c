/*
 * Common flow layer (src/methods/flow.c): registry, parameter parsing by
 * name, the per-step safety net (restore on failure, iteration prefix),
 * progress cancellation, accessors, no allocation in steps, no leaks.
 * The numerical behaviour of each baseline flow is tested in
 * tests/methods/baseline_flows/.
 */
#include "curvflow/baseline_flows.h"
#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/ops.h"
#include "test.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void test_registry(void)
{
    for (int k = 0; k < CF_FLOW_KIND_COUNT; ++k) {
        const char *name = cf_flow_kind_name((cf_flow_kind)k);
        CHECK(name != NULL);
        CHECK(cf_flow_kind_description((cf_flow_kind)k) != NULL);
        cf_flow_kind back = CF_FLOW_KIND_COUNT;
        CHECK_STATUS(cf_flow_kind_from_name(name, &back), CF_OK);
        CHECK(back == (cf_flow_kind)k);
    }
    CHECK(strcmp(cf_flow_kind_name(CF_FLOW_IMPLICIT_MCF), "implicit-mcf") == 0);
    CHECK(cf_flow_kind_name(CF_FLOW_KIND_COUNT) == NULL);
    CHECK(cf_flow_kind_name((cf_flow_kind)-1) == NULL);
    cf_flow_kind k;
    CHECK_STATUS(cf_flow_kind_from_name("no-such-flow", &k), CF_ERR_INVALID_ARG);
    cf_flow_options o;
    CHECK_STATUS(cf_flow_options_default(CF_FLOW_KIND_COUNT, &o), CF_ERR_INVALID_ARG);
}

static void test_options_by_name(void)
{
    cf_context *ctx = cft_context();
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_IMPLICIT_MCF, &o));
    cf_baseline_options *b = cf_flow_options_method(&o);
    cf_baseline_options def;
    CHECK_STATUS(cf_baseline_options_default(CF_FLOW_IMPLICIT_MCF, &def), CF_OK);
    CHECK(b->time_step == def.time_step && b->mass == def.mass && b->rescale == def.rescale);

    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "time_step", "0.25"));
    CHECK(b->time_step == 0.25);
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "mass", "voronoi"));
    CHECK(b->mass == CF_MASS_LUMPED_VORONOI);
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "rescale", "yes"));
    CHECK(b->rescale == 1);
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "rescale", "False"));
    CHECK(b->rescale == 0);

    /* errors name the parameter and leave the value alone */
    CHECK_STATUS(cf_flow_options_set(ctx, &o, "time_stp", "1"), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "time_stp") != NULL);
    CHECK(strstr(cf_context_message(ctx), "time_step") != NULL); /* lists the known names */
    CHECK_STATUS(cf_flow_options_set(ctx, &o, "time_step", "abc"), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "'time_step'") != NULL);
    CHECK_STATUS(cf_flow_options_set(ctx, &o, "time_step", "0.1x"), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_flow_options_set(ctx, &o, "time_step", "nan"), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_flow_options_set(ctx, &o, "time_step", "-1"), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "outside") != NULL);
    CHECK_STATUS(cf_flow_options_set(ctx, &o, "tolerance", "2"), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_flow_options_set(ctx, &o, "mass", "galerkinn"), CF_ERR_INVALID_ARG);
    CHECK(strstr(cf_context_message(ctx), "barycentric") != NULL);
    CHECK_STATUS(cf_flow_options_set(ctx, &o, "rescale", "maybe"), CF_ERR_INVALID_ARG);
    CHECK(b->time_step == 0.25 && b->mass == CF_MASS_LUMPED_VORONOI && b->rescale == 0);
    CHECK_STATUS(cf_flow_options_set(ctx, NULL, "mass", "voronoi"), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_flow_options_set(ctx, &o, NULL, "1"), CF_ERR_INVALID_ARG);

    /* formatting round-trips through set */
    const cf_param_desc *params;
    int32_t count;
    CHECK_OK(ctx, cf_flow_params(CF_FLOW_IMPLICIT_MCF, &params, &count));
    CHECK(count >= 4);
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "time_step", "0.1"));
    for (int32_t i = 0; i < count; ++i) {
        char text[64];
        CHECK_OK(ctx, cf_flow_options_format(&o, &params[i], text, sizeof text));
        cf_flow_options copy;
        CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_IMPLICIT_MCF, &copy));
        CHECK_OK(ctx, cf_flow_options_set(ctx, &copy, params[i].name, text));
        CHECK(memcmp(copy.storage.bytes + params[i].offset, o.storage.bytes + params[i].offset,
                     params[i].type == CF_PARAM_DOUBLE ? sizeof(double) : sizeof(int32_t)) == 0);
    }
    char tiny[2];
    CHECK_STATUS(cf_flow_options_format(&o, &params[0], tiny, sizeof tiny), CF_ERR_INVALID_ARG);
    cf_context_destroy(&ctx);
}

/* An icosphere with reproducible radial noise (a few % of the radius). */
static cf_mesh *noisy_sphere(cf_context *ctx, int32_t subdivisions, double **noisy)
{
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, subdivisions, 1.0, &mesh));
    if (!mesh) return NULL;
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *x = malloc(3 * (size_t)nv * sizeof *x);
    uint32_t state = 12345u;
    for (int32_t i = 0; i < nv; ++i) {
        state = state * 1664525u + 1013904223u;
        double r = 1.0 + 0.04 * ((double)(state >> 8) / 16777216.0 - 0.5);
        for (int c = 0; c < 3; ++c) x[3 * i + c] = r * cf_mesh_positions(mesh)[3 * i + c];
    }
    *noisy = x;
    return mesh;
}

static void test_step_info_and_no_allocation(void)
{
    cf_context *ctx = cft_context();
    double *x0 = NULL;
    cf_mesh *mesh = noisy_sphere(ctx, 2, &x0);
    if (!mesh) { cf_context_destroy(&ctx); return; }
    int32_t nv = cf_mesh_vertex_count(mesh);
    for (int k = CF_FLOW_EXPLICIT_MCF; k <= CF_FLOW_IMPLICIT_BILAPLACIAN; ++k) {
        cf_flow_options o;
        CHECK_OK(ctx, cf_flow_options_default((cf_flow_kind)k, &o));
        cf_flow *flow = NULL;
        CHECK_OK(ctx, cf_flow_create(ctx, mesh, x0, &o, &flow));
        if (!flow) continue;
        CHECK(cf_flow_get_kind(flow) == (cf_flow_kind)k);
        CHECK(cf_flow_mesh(flow) == mesh);
        CHECK(memcmp(cf_flow_positions(flow), x0, 3 * (size_t)nv * sizeof(double)) == 0);
        const cf_flow_info *i0 = cf_flow_last_info(flow);
        CHECK(i0->iteration == 0);
        double area0 = 0.0, vol0 = 0.0;
        CHECK_OK(ctx, cf_total_area(ctx, mesh, x0, &area0));
        CHECK_OK(ctx, cf_enclosed_volume(ctx, mesh, x0, &vol0));
        CHECK_NEAR(i0->area, area0, 1e-15, 0.0);
        CHECK_NEAR(i0->volume, vol0, 1e-15, 0.0);
        CHECK(isfinite(cf_flow_energy(flow)) && cf_flow_energy(flow) > 0.0);

        /* No allocation inside steps (STYLE.md "preallocate in create"). */
        int64_t allocations = cf_context_allocation_count(ctx);
        double time = 0.0;
        for (int s = 1; s <= 3; ++s) {
            cf_flow_info info;
            CHECK_OK(ctx, cf_flow_step(flow, &info));
            CHECK(info.iteration == s);
            CHECK(info.time_step > 0.0);
            time += info.time_step;
            CHECK_NEAR(info.time, time, 1e-14, 0.0);
            double area = 0.0, vol = 0.0;
            CHECK_OK(ctx, cf_total_area(ctx, mesh, cf_flow_positions(flow), &area));
            CHECK_OK(ctx, cf_enclosed_volume(ctx, mesh, cf_flow_positions(flow), &vol));
            CHECK_NEAR(info.area, area, 1e-14, 0.0);
            CHECK_NEAR(info.area_drift, area / area0 - 1.0, 1e-12, 1e-15);
            CHECK_NEAR(info.volume_drift, vol / vol0 - 1.0, 1e-12, 1e-15);
            CHECK(info.total_seconds >= 0.0);
            CHECK(info.energy == cf_flow_energy(flow));
            CHECK(info.term_names[0] != NULL);
        }
        CHECK(cf_context_allocation_count(ctx) == allocations);
        cf_flow_destroy(&flow);
        CHECK(flow == NULL);
    }
    free(x0);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Every flow is scale-free (time steps in units of the mesh's own size):
 * across the range of coordinates the mesh check accepts (1e-50 .. 1e50) the
 * scaled result is the unscaled one, scaled, and the energy scales by a
 * fixed power (area s^2; bi-Laplacian and Willmore energies s^0). At 1e60
 * areas squared would overflow, so cf_mesh_create rejects such meshes
 * (tests/mesh/test_validate.c). */
static void test_scale_invariance(void)
{
    cf_context *ctx = cft_context();
    double *x0 = NULL;
    cf_mesh *mesh = noisy_sphere(ctx, 2, &x0);
    if (!mesh) { cf_context_destroy(&ctx); return; }
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *xs = malloc(3 * (size_t)nv * sizeof *xs);
    double *ref = malloc(3 * (size_t)nv * sizeof *ref);
    const double scales[] = {1e45, 1e-45};
    for (int k = CF_FLOW_EXPLICIT_MCF; k <= CF_FLOW_SPIN_WILLMORE; ++k) {
        cf_flow_options o;
        CHECK_OK(ctx, cf_flow_options_default((cf_flow_kind)k, &o));
        cf_flow *flow = NULL;
        CHECK_OK(ctx, cf_flow_create(ctx, mesh, x0, &o, &flow));
        if (!flow) continue;
        for (int s = 0; s < 2; ++s) CHECK_OK(ctx, cf_flow_step(flow, NULL));
        double e_ref = cf_flow_energy(flow);
        memcpy(ref, cf_flow_positions(flow), 3 * (size_t)nv * sizeof *ref);
        cf_flow_destroy(&flow);
        for (size_t t = 0; t < sizeof scales / sizeof scales[0]; ++t) {
            double scale = scales[t];
            for (int32_t i = 0; i < 3 * nv; ++i) xs[i] = scale * x0[i];
            CHECK_OK(ctx, cf_flow_create(ctx, mesh, xs, &o, &flow));
            if (!flow) continue;
            for (int s = 0; s < 2; ++s) CHECK_OK(ctx, cf_flow_step(flow, NULL));
            double worst = 0.0;
            for (int32_t i = 0; i < 3 * nv; ++i) worst = fmax(worst, fabs(cf_flow_positions(flow)[i] / scale - ref[i]));
            if (worst > 1e-9) printf("  %s at scale %g: positions differ by %g\n", cf_flow_kind_name((cf_flow_kind)k), scale, worst);
            CHECK_LE(worst, 1e-9);
            /* energy = scale^p e_ref with an integer p */
            double p = log(cf_flow_energy(flow) / e_ref) / log(scale);
            CHECK(isfinite(p));
            CHECK_NEAR(p, round(p), 0.0, 1e-9);
            CHECK(round(p) == (k <= CF_FLOW_CONFORMAL_MCF ? 2.0 : 0.0));
            cf_flow_destroy(&flow);
        }
    }
    /* starting positions beyond the range are refused up front, naming the vertex */
    for (int32_t i = 0; i < 3 * nv; ++i) xs[i] = 1e60 * x0[i];
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    cf_flow *flow = NULL;
    CHECK_STATUS(cf_flow_create(ctx, mesh, xs, &o, &flow), CF_ERR_NONFINITE);
    CHECK(flow == NULL);
    CHECK(strncmp(cf_context_message(ctx), "vertex 0: starting position (", 29) == 0);
    CHECK(strstr(cf_context_message(ctx), "is out of range (|x| > 1e+50)") != NULL);
    free(xs);
    free(ref);
    free(x0);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* A step that blows up is rejected: state and energy stay those before it,
 * and the message names the iteration. */
static void test_failed_step_keeps_state(void)
{
    cf_context *ctx = cft_context();
    double *x0 = NULL;
    cf_mesh *mesh = noisy_sphere(ctx, 2, &x0);
    if (!mesh) { cf_context_destroy(&ctx); return; }
    int32_t nv = cf_mesh_vertex_count(mesh);
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_EXPLICIT_MCF, &o));
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, x0, &o, &flow));
    CHECK_OK(ctx, cf_flow_step(flow, NULL));
    double *good = malloc(3 * (size_t)nv * sizeof *good);
    memcpy(good, cf_flow_positions(flow), 3 * (size_t)nv * sizeof *good);
    double energy = cf_flow_energy(flow);
    /* 100x the default step: far above the explicit stability limit (~1/3). */
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "time_step", "10"));
    cf_flow *bad = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, good, &o, &bad));
    cf_status st = CF_OK;
    int64_t it = 0;
    for (it = 1; it <= 50 && st == CF_OK; ++it) st = cf_flow_step(bad, NULL);
    CHECK_STATUS(st, CF_ERR_NUMERICAL);
    char expected[64];
    snprintf(expected, sizeof expected, "iteration %lld: ", (long long)(it - 1));
    CHECK(strncmp(cf_context_message(ctx), expected, strlen(expected)) == 0);
    CHECK(cf_flow_last_info(bad)->iteration == it - 2);
    const double *x = cf_flow_positions(bad);
    int finite = 1;
    for (int32_t i = 0; i < 3 * nv; ++i) finite &= isfinite(x[i]) != 0;
    CHECK(finite);
    /* the state kept is the one the last accepted step reported */
    double area = 0.0;
    CHECK_OK(ctx, cf_total_area(ctx, mesh, x, &area));
    CHECK_NEAR(area, cf_flow_last_info(bad)->area, 1e-14, 0.0);
    if (it == 2) CHECK(memcmp(x, good, 3 * (size_t)nv * sizeof *good) == 0);
    (void)energy;

    /* set_positions validates and resets */
    double *nanx = malloc(3 * (size_t)nv * sizeof *nanx);
    memcpy(nanx, good, 3 * (size_t)nv * sizeof *nanx);
    nanx[3 * 7 + 1] = NAN;
    CHECK_STATUS(cf_flow_set_positions(flow, nanx), CF_ERR_NONFINITE);
    CHECK(strstr(cf_context_message(ctx), "vertex 7") != NULL);
    CHECK_OK(ctx, cf_flow_set_positions(flow, x0));
    CHECK(memcmp(cf_flow_positions(flow), x0, 3 * (size_t)nv * sizeof(double)) == 0);
    double area0 = 0.0;
    CHECK_OK(ctx, cf_total_area(ctx, mesh, x0, &area0));
    CHECK_NEAR(cf_flow_energy(flow), area0, 1e-14, 0.0); /* explicit MCF energy is the area */
    cf_flow_destroy(&bad);
    CHECK_STATUS(cf_flow_create(ctx, mesh, nanx, &o, &bad), CF_ERR_NONFINITE);
    CHECK(bad == NULL);

    free(nanx);
    free(good);
    cf_flow_destroy(&flow);
    cf_flow_destroy(&bad);
    free(x0);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

typedef struct cancel_state {
    int64_t stop_at;
    int calls;
} cancel_state;

static int cancel_after(void *user, const cf_flow_info *info)
{
    cancel_state *c = user;
    c->calls++;
    return info->iteration >= c->stop_at;
}

static void test_cancel_and_run(void)
{
    cf_context *ctx = cft_context();
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 2, 1.0, &mesh));
    if (!mesh) { cf_context_destroy(&ctx); return; }
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_IMPLICIT_MCF, &o));
    cf_flow *flow = NULL;
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    cancel_state c = {3, 0};
    cf_flow_set_progress(flow, cancel_after, &c);
    cf_flow_info info;
    CHECK_STATUS(cf_flow_run(flow, 10, &info), CF_ERR_CANCELLED);
    CHECK(c.calls == 3);
    CHECK(info.iteration == 3);
    CHECK(strstr(cf_context_message(ctx), "iteration 3") != NULL);
    cf_flow_set_progress(flow, NULL, NULL);
    CHECK_OK(ctx, cf_flow_run(flow, 2, &info));
    CHECK(info.iteration == 5);
    CHECK_STATUS(cf_flow_run(flow, -1, &info), CF_ERR_INVALID_ARG);
    cf_flow_destroy(&flow);

    /* convergence stops a run early with CF_OK */
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "tolerance", "0.5"));
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    CHECK_OK(ctx, cf_flow_run(flow, 10, &info));
    CHECK(info.iteration == 1);
    CHECK(cf_flow_converged(flow) == 1);
    cf_flow_destroy(&flow);

    /* apply == create + run + copy */
    int32_t nv = cf_mesh_vertex_count(mesh);
    double *out = malloc(3 * (size_t)nv * sizeof *out);
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_IMPLICIT_MCF, &o));
    CHECK_OK(ctx, cf_flow_apply(ctx, mesh, &o, 2, out, &info));
    CHECK(info.iteration == 2);
    CHECK_OK(ctx, cf_flow_create(ctx, mesh, NULL, &o, &flow));
    CHECK_OK(ctx, cf_flow_run(flow, 2, NULL));
    CHECK(memcmp(out, cf_flow_positions(flow), 3 * (size_t)nv * sizeof *out) == 0);
    cf_flow_destroy(&flow);
    free(out);

    CHECK_STATUS(cf_flow_create(ctx, NULL, NULL, &o, &flow), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_flow_create(ctx, mesh, NULL, NULL, &flow), CF_ERR_INVALID_ARG);
    CHECK_STATUS(cf_flow_step(NULL, &info), CF_ERR_INVALID_ARG);
    cf_flow_destroy(NULL);
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

/* Every allocation of create can fail cleanly. */
static void test_allocation_failures(void)
{
    cf_context *ctx = NULL;
    CHECK_STATUS(cf_context_create(&ctx), CF_OK);
    cf_mesh *mesh = NULL;
    CHECK_OK(ctx, cf_generate_icosphere(ctx, 1, 1.0, &mesh));
    if (!mesh) { cf_context_destroy(&ctx); return; }
    size_t base = cf_context_bytes_in_use(ctx);
    for (int k = CF_FLOW_EXPLICIT_MCF; k <= CF_FLOW_IMPLICIT_BILAPLACIAN; ++k) {
        cf_flow_options o;
        CHECK_OK(ctx, cf_flow_options_default((cf_flow_kind)k, &o));
        int ok = 0;
        for (int64_t n = 1; n < 200 && !ok; ++n) {
            cf_flow *flow = NULL;
            cf_context_fail_allocation(ctx, n, 0);
            cf_status st = cf_flow_create(ctx, mesh, NULL, &o, &flow);
            cf_context_fail_allocation(ctx, 0, 0);
            if (st == CF_OK) {
                ok = 1;
                cf_flow_destroy(&flow);
            } else {
                CHECK_STATUS(st, CF_ERR_NOMEM);
                CHECK(flow == NULL);
            }
            CHECK(cf_context_bytes_in_use(ctx) == base);
        }
        CHECK(ok);
    }
    cf_mesh_destroy(&mesh);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_registry);
    CFT_RUN(test_options_by_name);
    CFT_RUN(test_step_info_and_no_allocation);
    CFT_RUN(test_scale_invariance);
    CFT_RUN(test_failed_step_keeps_state);
    CFT_RUN(test_cancel_and_run);
    CFT_RUN(test_allocation_failures);
    return cft_finish();
}
