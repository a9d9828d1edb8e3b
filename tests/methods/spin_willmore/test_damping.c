/*
 * Option max_realised_decrease of spin-willmore (docs/spin.md, "Long tubes:
 * damping when a step outruns its model"): an attempt that lowers W by more
 * than twice the decrease its curvature-space model predicts is redone at
 * the same tau with `regularization` raised to 1 for the rest of the run.
 *
 * The case is a knotted tube, generated here as bench/bench_unseen_kinds.py
 * makes it (trefoil centre line, 240 rings of 14 vertices, radius 0.35 +-
 * 0.1), the kind of issue 13's held-out knot. Measured with the default
 * regularization alone: its first step at tau 0.5 lowers W 3.5 times as much
 * as its model says, one ring of the tube shrinks to 1e-3 of its area, and
 * 10 steps end at W/4pi 8.51 of 10.80 (issue 13's target is half). With the
 * damping the first step is redone and 10 steps reach 5.26 (mean Q 1.32).
 * Checked: the trigger and its figure, the target, W non-increasing, mean Q,
 * the mesh check, the run without the option (the damage), and that an
 * ordinary shape (the built-in bumpy sphere; spot_3k when ../shared is
 * there) never triggers it.
 */
#include "test.h"

#include "curvflow/flow.h"
#include "curvflow/generate.h"
#include "curvflow/mesh.h"
#include "curvflow/metrics.h"
#include "curvflow/spin_willmore.h"
#include "methods/spin_willmore/spin_internal.h"
#include "spin_test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846


/* The first step at which the damping was triggered (0: never) and the
 * realised decrease that triggered it (a spin_step_hook). */
typedef struct damping_trigger {
    int32_t step;
    double realised;
} damping_trigger;

static void record_trigger(cf_context *ctx, const cf_flow *flow, int step, void *user)
{
    damping_trigger *t = user;
    cfi_spin_diagnostics d;
    CHECK_OK(ctx, cfi_spin_willmore_diagnostics(flow, &d));
    if (d.damped_realised > 0.0 && t->step == 0) {
        t->step = step;
        t->realised = d.damped_realised;
    }
}

/* `steps` default steps of spin-willmore on mesh, with
 * max_realised_decrease=bound if bound is not NULL (spin_run_steps). */
static void run_flow(cf_context *ctx, const cf_mesh *mesh, const char *bound, int steps, spin_run *r,
                     damping_trigger *trigger)
{
    memset(r, 0, sizeof *r);
    memset(trigger, 0, sizeof *trigger);
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    if (bound) CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "max_realised_decrease", bound));
    spin_run_steps_hooked(ctx, mesh, &o, steps, r, NULL, record_trigger, trigger);
}

static void test_knot_reaches_target(void)
{
    cf_context *ctx = NULL;
    CHECK_OK(NULL, cf_context_create(&ctx));
    cf_mesh *knot = spin_knotted_tube(ctx, 240, 14, 0.35, 0.1);
    if (!knot) {
        cf_context_destroy(&ctx);
        return;
    }
    spin_run damped, plain;
    damping_trigger damped_trigger, plain_trigger;
    run_flow(ctx, knot, NULL, 10, &damped, &damped_trigger);
    run_flow(ctx, knot, "0", 10, &plain, &plain_trigger);
    fprintf(stderr, "   knot: W/4pi %.4f -> %.4f (damped from step %d, realised %.3f; largest rise %.3g, mean Q %.4f, "
                    "%d defects); max_realised_decrease=0: %.4f (mean Q %.4f)\n",
            damped.w0, damped.w, damped_trigger.step, damped_trigger.realised, damped.worst_rise, damped.mean_q,
            damped.defects, plain.w, plain.mean_q);
    CHECK(damped.steps == 10);
    CHECK(damped_trigger.step == 1);            /* the first step outruns its model */
    CHECK(damped_trigger.realised > 3.0);       /* measured 3.51 */
    CHECK_LE(damped.worst_rise, 0.0);
    CHECK_LE(damped.w, 0.5 * damped.w0);        /* issue 13's target: measured 5.26 of 10.80 */
    CHECK_LE(damped.mean_q, 1.5);               /* measured 1.32 */
    CHECK(damped.defects == 0);
    CHECK(plain_trigger.step == 0);
    CHECK(plain.w > 0.7 * plain.w0);            /* the damage: measured 8.51 */
    cf_mesh_destroy(&knot);
    cf_context_destroy(&ctx);
}

/* What a long tube becomes (docs/spin.md, "Long tubes end as chains of
 * bubbles"): the vertices whose share of the total area is at least a
 * tenth of their share in the input, grouped along edges into components
 * of more than 20 vertices (the bubbles), and the rest (the necks between
 * them). W per vertex is the flow's, |L x|^2 / (4 A) with barycentric A. */
typedef struct bubble_census {
    int32_t count;          /* bubbles */
    double least_w, most_w; /* W/4pi of the bubble with the least / most */
    double bubbles_w;       /* W/4pi of all bubbles */
    double neck_w;          /* W/4pi of the necks */
    double neck_area;       /* the necks' share of the area */
} bubble_census;

static int32_t census_root(int32_t *parent, int32_t v)
{
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
}

static void count_bubbles(cf_context *ctx, const cf_mesh *mesh, const double *x, bubble_census *c)
{
    int32_t nv = cf_mesh_vertex_count(mesh), nf = cf_mesh_face_count(mesh);
    const int32_t *tri = cf_mesh_triangles(mesh);
    double *area0 = malloc(nv * sizeof(double)), *area = malloc(nv * sizeof(double));
    double *hn = malloc(3 * nv * sizeof(double)), *w = malloc(nv * sizeof(double));
    double *component_w = calloc(nv, sizeof(double));
    int32_t *parent = malloc(nv * sizeof(int32_t)), *size = calloc(nv, sizeof(int32_t));
    uint8_t *grown = malloc(nv);
    memset(c, 0, sizeof *c);
    if (!area0 || !area || !hn || !w || !component_w || !parent || !size || !grown) {
        CHECK(!"out of memory");
        goto done;
    }
    CHECK_OK(ctx, cf_vertex_areas(ctx, mesh, cf_mesh_positions(mesh), CF_DUAL_AREA_BARYCENTRIC, area0));
    CHECK_OK(ctx, cf_vertex_areas(ctx, mesh, x, CF_DUAL_AREA_BARYCENTRIC, area));
    CHECK_OK(ctx, cf_mean_curvature_normal(ctx, mesh, x, hn));
    double total0 = 0.0, total = 0.0;
    for (int32_t v = 0; v < nv; ++v) {
        total0 += area0[v];
        total += area[v];
    }
    for (int32_t v = 0; v < nv; ++v) {
        const double *h = hn + 3 * v;
        w[v] = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]) / (4.0 * area[v]) / (4.0 * PI);
        grown[v] = area[v] / total >= 0.1 * area0[v] / total0;
        parent[v] = v;
    }
    for (int32_t f = 0; f < nf; ++f)
        for (int k = 0; k < 3; ++k) {
            int32_t a = tri[3 * f + k], b = tri[3 * f + (k + 1) % 3];
            if (grown[a] && grown[b]) parent[census_root(parent, a)] = census_root(parent, b);
        }
    for (int32_t v = 0; v < nv; ++v)
        if (grown[v]) {
            int32_t r = census_root(parent, v);
            ++size[r];
            component_w[r] += w[v];
        }
    c->least_w = INFINITY;
    for (int32_t v = 0; v < nv; ++v) {
        int32_t r = census_root(parent, v);
        if (grown[v] && size[r] > 20) {
            if (r == v) {
                ++c->count;
                c->least_w = fmin(c->least_w, component_w[r]);
                c->most_w = fmax(c->most_w, component_w[r]);
                c->bubbles_w += component_w[r];
            }
        } else {
            c->neck_w += w[v];
            c->neck_area += area[v] / total;
        }
    }
done:
    free(area0);
    free(area);
    free(hn);
    free(w);
    free(component_w);
    free(parent);
    free(size);
    free(grown);
}

/* The positions after the last step (a spin_step_hook's user). */
typedef struct last_positions {
    size_t bytes;
    double *x;
} last_positions;

static void keep_positions(cf_context *ctx, const cf_flow *flow, int step, void *user)
{
    (void)ctx;
    (void)step;
    last_positions *last = user;
    memcpy(last->x, cf_flow_positions(flow), last->bytes);
}

/* 10 steps on the tube with `regularization` (NULL: the default) into *c. */
static void tube_census(cf_context *ctx, const cf_mesh *tube, const char *regularization, spin_run *r, bubble_census *c)
{
    memset(r, 0, sizeof *r);
    memset(c, 0, sizeof *c);
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    if (regularization) CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "regularization", regularization));
    last_positions last = {3 * (size_t)cf_mesh_vertex_count(tube) * sizeof(double), NULL};
    double *x = last.x = malloc(last.bytes);
    if (!x) {
        CHECK(!"out of memory");
        return;
    }
    memcpy(x, cf_mesh_positions(tube), last.bytes);
    spin_run_steps_hooked(ctx, tube, &o, 10, r, NULL, keep_positions, &last);
    count_bubbles(ctx, tube, x, c);
    fprintf(stderr,
            "   tube 0.40 +- 0.1, regularization %s: W/4pi %.4f -> %.4f (target %.4f); %d bubbles of W/4pi %.3f .. %.3f "
            "(sum %.3f), necks W/4pi %.3f on %.4f of the area\n",
            regularization ? regularization : "default", r->w0, r->w, 0.5 * r->w0, c->count, c->least_w, c->most_w,
            c->bubbles_w, c->neck_w, c->neck_area);
    free(x);
}

/* The trefoil tube of radius 0.40 +- 0.1 misses issue 13's W <= W0/2 (4.70)
 * with every regularization measured (docs/spin.md). With its soft modes
 * damped (regularization 1) the flow pinches the tube at its five thin
 * sections into five near-round bubbles joined by necks: five bubbles alone
 * hold more than the target. With the default the first steps crowd the
 * necks, whose badly resolved W is most of what is left. */
static void test_tube_bubbles(void)
{
    cf_context *ctx = NULL;
    CHECK_OK(NULL, cf_context_create(&ctx));
    cf_mesh *tube = spin_knotted_tube(ctx, 240, 14, 0.40, 0.1);
    if (!tube) {
        cf_context_destroy(&ctx);
        return;
    }
    spin_run damped, plain;
    bubble_census damped_census, plain_census;
    tube_census(ctx, tube, "1", &damped, &damped_census);
    tube_census(ctx, tube, NULL, &plain, &plain_census);
    CHECK(damped.steps == 10);
    CHECK(damped_census.count == 5);
    CHECK(damped_census.least_w > 0.85); /* each near a round sphere's 1 */
    CHECK(damped_census.most_w < 1.05);
    CHECK(damped_census.bubbles_w > 0.5 * damped.w0); /* the bubbles alone miss the target */
    CHECK(damped_census.neck_area < 0.02);
    CHECK(damped.w > 0.5 * damped.w0);
    CHECK(plain_census.count <= 3);
    CHECK(plain_census.neck_w > 0.4 * plain.w); /* the crowded necks hold much of W */
    CHECK(plain.w > damped.w);
    cf_mesh_destroy(&tube);
    cf_context_destroy(&ctx);
}

/* 10 default steps on mesh: the damping never triggers. */
static void check_untouched(cf_context *ctx, const cf_mesh *mesh, const char *name, spin_run *r)
{
    damping_trigger trigger;
    run_flow(ctx, mesh, NULL, 10, r, &trigger);
    fprintf(stderr, "   %s: W/4pi %.4f -> %.4f, damped from step %d\n", name, r->w0, r->w, trigger.step);
    CHECK(trigger.step == 0);
}

/* No ordinary shape triggers it: the built-in bumpy sphere, and spot_3k if
 * ../shared is there (no attempt on the 20 shared meshes exceeds 1.72). */
static void test_ordinary_shapes_untouched(void)
{
    cf_context *ctx = NULL;
    CHECK_OK(NULL, cf_context_create(&ctx));
    cf_mesh *bumpy = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 3, 0.2, 2u, &bumpy));
    spin_run r;
    if (bumpy) check_untouched(ctx, bumpy, "bumpy sphere", &r);
    cf_mesh_destroy(&bumpy);
    cf_context_destroy(&ctx);
    cft_shared_case spot;
    if (!cft_shared_case_open(&spot, "spot_3k.obj", 0)) return;
    check_untouched(spot.ctx, spot.mesh, "spot_3k", &r);
    CHECK_LE(r.w, 1.01); /* issue 13's convergence target, untouched */
    cft_shared_case_close(&spot);
}

static void test_bound_validated(void)
{
    cf_context *ctx = NULL;
    CHECK_OK(NULL, cf_context_create(&ctx));
    cf_mesh *bumpy = NULL;
    CHECK_OK(ctx, cf_generate_bumpy_sphere(ctx, 2, 0.2, 2u, &bumpy));
    cf_flow_options o;
    CHECK_OK(ctx, cf_flow_options_default(CF_FLOW_SPIN_WILLMORE, &o));
    CHECK_OK(ctx, cf_flow_options_set(ctx, &o, "max_realised_decrease", "0.5"));
    cf_flow *flow = NULL;
    CHECK(cf_flow_create(ctx, bumpy, NULL, &o, &flow) == CF_ERR_INVALID_ARG);
    CHECK(flow == NULL);
    CHECK(strstr(cf_context_message(ctx), "max_realised_decrease") != NULL);
    cf_mesh_destroy(&bumpy);
    cf_context_destroy(&ctx);
}

int main(void)
{
    CFT_RUN(test_knot_reaches_target);
    CFT_RUN(test_tube_bubbles);
    CFT_RUN(test_ordinary_shapes_untouched);
    CFT_RUN(test_bound_validated);
    return cft_finish();
}
