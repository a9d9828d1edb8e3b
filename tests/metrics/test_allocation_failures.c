/* Failure injection for the metrics: every allocation fails in turn; each
 * call returns CF_ERR_NOMEM and leaks nothing. */
#include "curvflow/generate.h"
#include "curvflow/metrics.h"
#include "test.h"

#include <stdlib.h>

static const double *g_b; /* deformed positions */

static cf_status op_compare(cf_context *ctx, const cf_mesh *m, const double *x)
{
    cf_stats st;
    cf_status s = cf_quasi_conformal_error(ctx, m, x, g_b, NULL, &st);
    if (s == CF_OK) s = cf_log_area_distortion(ctx, m, x, g_b, NULL, &st);
    if (s == CF_OK) s = cf_angle_change(ctx, m, x, g_b, NULL, &st);
    cf_vertex_scale_fit fit;
    if (s == CF_OK) s = cf_vertex_scale_fit_compute(ctx, m, x, g_b, NULL, NULL, &fit);
    return s;
}

static cf_status op_summary(cf_context *ctx, const cf_mesh *m, const double *x)
{
    cf_shape_summary sm;
    return cf_shape_summary_compute(ctx, m, x, &sm);
}

static cf_status op_distance(cf_context *ctx, const cf_mesh *m, const double *x)
{
    double d;
    return cf_point_to_surface_distance(ctx, cf_mesh_vertex_count(m), g_b, m, x, NULL, &d, NULL, NULL);
}

static void quiet(void *user, cf_log_level level, const char *line)
{
    (void)user;
    (void)level;
    (void)line;
}

typedef cf_status (*metric_fn)(cf_context *, const cf_mesh *, const double *);

typedef struct metric_call {
    const cf_mesh *m;
    metric_fn fn;
} metric_call;

static cf_status call_metric(cf_context *ctx, void *user)
{
    const metric_call *c = user;
    return c->fn(ctx, c->m, cf_mesh_positions(c->m));
}

static void run(cf_context *ctx, const cf_mesh *m, metric_fn fn, const char *name)
{
    metric_call c = {m, fn};
    CHECK(cft_allocation_sweep(ctx, name, call_metric, &c, 0) > 0);
}

static void test_injection(void)
{
    cf_context *ctx = NULL;
    CHECK_STATUS(cf_context_create(&ctx), CF_OK);
    cf_context_set_log(ctx, quiet, NULL, CF_LOG_ERROR);
    cf_mesh *m = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 2, 0.2, 4u, &m));
    if (!m) return;
    size_t base = cf_context_bytes_in_use(ctx);
    int32_t nv = cf_mesh_vertex_count(m);
    double *b = malloc(sizeof(double) * 3 * nv);
    for (int32_t i = 0; i < 3 * nv; ++i) b[i] = cf_mesh_positions(m)[i] * (1.0 + 0.1 * (i % 3));
    g_b = b;
    run(ctx, m, op_compare, "compare");
    CHECK(cf_context_bytes_in_use(ctx) == base);
    run(ctx, m, op_summary, "summary");
    CHECK(cf_context_bytes_in_use(ctx) == base);
    run(ctx, m, op_distance, "distance");
    CHECK(cf_context_bytes_in_use(ctx) == base);
    free(b);
    cf_mesh_destroy(&m);
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_injection);
    return cft_finish();
}
