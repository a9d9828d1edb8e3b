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

static const double *g_torus_b; /* a torus stretched along x */

static cf_status op_conformal_class(cf_context *ctx, const cf_mesh *m, const double *x)
{
    cf_conformal_class cls;
    double gram[4], d;
    cf_status s = cf_conformal_class_compute(ctx, m, x, gram, &cls);
    if (s == CF_OK) s = cf_conformal_class_distance(ctx, m, x, g_torus_b, &cls, &cls, &d);
    double *gradient = malloc(sizeof(double) * 3 * 3 * (size_t)cf_mesh_vertex_count(m));
    if (s == CF_OK) s = gradient ? cf_conformal_class_gram_gradient(ctx, m, g_torus_b, gram, gradient) : CF_ERR_NOMEM;
    free(gradient);
    cf_conformal_class_workspace *w = NULL;
    if (s == CF_OK) s = cf_conformal_class_workspace_create(ctx, m, &w);
    double g2[4];
    if (s == CF_OK) s = cf_conformal_class_workspace_gram_gradient(w, g_torus_b, g2, NULL);
    cf_conformal_class_workspace_destroy(&w);
    double form[4], normalized[4], derivative[9];
    if (s == CF_OK) s = cf_conformal_class_intersection_form(ctx, m, x, form);
    if (s == CF_OK) s = cf_conformal_class_normalize(ctx, 2, form, gram, normalized, derivative);
    return s;
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

/* may_recover: the call goes through CHOLMOD's analysis (the harmonic
 * forms of the conformal class), which tries several orderings and keeps
 * the best that succeeded, so a failed allocation inside one of them can
 * legitimately end in CF_OK (as in the ops test). */
static void run(cf_context *ctx, const cf_mesh *m, metric_fn fn, const char *name, int may_recover)
{
    metric_call c = {m, fn};
    CHECK(cft_allocation_sweep(ctx, name, call_metric, &c, may_recover) > 0);
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
    run(ctx, m, op_compare, "compare", 0);
    CHECK(cf_context_bytes_in_use(ctx) == base);
    run(ctx, m, op_summary, "summary", 0);
    CHECK(cf_context_bytes_in_use(ctx) == base);
    run(ctx, m, op_distance, "distance", 0);
    CHECK(cf_context_bytes_in_use(ctx) == base);
    free(b);
    cf_mesh_destroy(&m);
    cf_mesh *torus = NULL;
    CHECK_OK(ctx, cf_generate_torus(ctx, 1.0, 0.4, 12, 6, &torus));
    if (torus) {
        int32_t tv = cf_mesh_vertex_count(torus);
        double *tb = malloc(sizeof(double) * 3 * tv);
        for (int32_t i = 0; i < 3 * tv; ++i) tb[i] = cf_mesh_positions(torus)[i] * (i % 3 == 0 ? 1.3 : 1.0);
        g_torus_b = tb;
        size_t torus_base = cf_context_bytes_in_use(ctx);
        run(ctx, torus, op_conformal_class, "conformal class", 1);
        CHECK(cf_context_bytes_in_use(ctx) == torus_base);
        free(tb);
        cf_mesh_destroy(&torus);
    }
    CHECK(cf_context_bytes_in_use(ctx) == 0);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_injection);
    return cft_finish();
}
